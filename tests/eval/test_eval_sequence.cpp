// Tests of the evaluation over time (issue #14: gam::eval::evaluateSequence,
// gam-evaluate --sequence) on a hand-made 8 x 1 cell sequence of 6 frames whose
// every number is derived by hand below.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "gam/eval/Evaluation.h"

namespace fs = std::filesystem;
using namespace gam::eval;

namespace
{
// Eight cells in a row (1 m cells, x = 0.5 ... 7.5), frames 0..5:
//   cell 0: floor, always seen, map free.
//   cell 1: obstacle (object 1) in frames 0-1, floor from frame 2, seen in every frame;
//           map occupied in frames 0-3, free from 4 -> seen free in frame 2 (the map has
//           to clear it), cleared in frame 4: 2 frames.
//   cell 2: like cell 1 but the map keeps it occupied to the end -> with ghost_frames 2
//           a ghost in frame 4 (2 frames after seen free), never cleared.
//   cell 3: obstacle in frames 0-1, floor later, but out of view from frame 2: never
//           seen free, not a former obstacle cell (map occupied throughout).
//   cell 4: floor, seen in every frame; map unknown in frame 0, free later.
//   cell 5: drop (object 2) in every frame, seen in frames 0-1 only; map occupied but
//           free in frame 4 -> a hazard cell lost while out of view; its changes in
//           frames 4 and 5 happen outside the view.
//   cell 6: drop, seen in every frame, map occupied: never out of view.
//   cell 7: floor never seen; the map turns it free in frame 3: a change outside the view.
const char* kMaps[6] = {
	// 0 1 2 3 4 5 6 7   (O occupied, F free, U unknown)
	"FOOOUOOU",  // frame 0
	"FOOOFOOU",  // frame 1
	"FOOOFOOU",  // frame 2
	"FOOOFOOF",  // frame 3
	"FFOOFFOF",  // frame 4
	"FFOOFOOF",  // frame 5
};

const char* kFrames =
	"frame,kind,iy,ix0,ix1,label,object_id\n"
	"0,geom,0,1,3,obstacle,1\n"
	"0,geom,0,5,6,drop,2\n"
	"0,view,0,0,6,,0\n"
	"0,entries,0,1,3,,0\n"
	"1,view,0,0,6,,0\n"
	"1,entries,0,4,6,,0\n"
	"2,geom,0,1,3,free,0\n"
	"2,view,0,0,2,,0\n"
	"2,view,0,4,4,,0\n"
	"2,view,0,6,6,,0\n"
	"2,entries,0,7,9,,0\n"
	"3,view,0,0,2,,0\n"
	"3,view,0,4,4,,0\n"
	"3,view,0,6,6,,0\n"
	"3,entries,0,10,12,,0\n"
	"4,view,0,0,2,,0\n"
	"4,view,0,4,4,,0\n"
	"4,view,0,6,6,,0\n"
	"4,entries,0,13,15,,0\n"
	"5,view,0,0,2,,0\n"
	"5,view,0,4,4,,0\n"
	"5,view,0,6,6,,0\n"
	"5,entries,0,16,18,,0\n";

struct TempDir
{
	fs::path path;
	TempDir()
	{
		char tmpl[] = "/tmp/gam_test_evalseq_XXXXXX";
		path = mkdtemp(tmpl);
	}
	~TempDir() { fs::remove_all(path); }
	std::string operator/(const std::string& f) const { return (path / f).string(); }
};

void writeFile(const std::string& p, const std::string& s)
{
	fs::create_directories(fs::path(p).parent_path());
	std::ofstream f(p, std::ios::binary);
	f << s;
}

/** The final ground truth (labels of frame 5; cell 7 never seen) as gam-simulate writes it. */
std::string writeGt(const TempDir& d)
{
	const std::string prefix = d / "seq";
	writeFile(prefix + "_gt.yaml", "image: seq_gt.pgm\nresolution: 1\norigin: [0.0, 0.0, 0.0]\nnegate: 0\n");
	writeFile(
		prefix + "_gt_objects.csv",
		"id,name,type,category,min_x,min_y,min_z,max_x,max_y,max_z\n1,person,box,large,1,0,0,4,1,1.7\n"
		"2,outlet,hole,negative,5,0,-0.1,7,1,0\n");
	const char* labels[8] = {"free", "free", "free", "free", "free", "drop", "drop", "unobserved"};
	std::ostringstream l;
	l << "ix,iy,x,y,label,object_id,category\n";
	for (int ix = 0; ix < 8; ix++)
		l << ix << ",0," << ix + 0.5 << ",0.5," << labels[ix] << "," << (ix == 5 || ix == 6 ? 2 : 0) << ","
		  << (ix == 5 || ix == 6 ? "negative" : "none") << "\n";
	writeFile(prefix + "_gt_labels.csv", l.str());
	writeFile(prefix + "_gt_frames.csv", kFrames);
	return prefix;
}

uint8_t pixel(char c) { return c == 'O' ? 0 : (c == 'F' ? 254 : 128); }

RosMap mapOf(const char* cells)
{
	RosMap m;
	m.mode = "scale";
	m.resolution = 1;
	m.width = 8;
	m.height = 1;
	for (int i = 0; i < 8; i++) m.pixels.push_back(pixel(cells[i]));
	return m;
}

/** DIR/m.yaml (the last map) and DIR/snapshots/NNNNNN/m.yaml after every observation
 * (--snapshot-every 1), with index.csv: each frame is 3 rawlog entries (odometry and two
 * observations), the frame's map is the one after its last entry. */
std::string writeRun(const TempDir& d)
{
	const std::string dir = d / "run";
	auto writeMap = [&](const std::string& folder, const char* cells) {
		std::string pgm = "P5\n8 1\n255\n";
		for (int i = 0; i < 8; i++) pgm += char(pixel(cells[i]));
		writeFile(folder + "/m.pgm", pgm);
		writeFile(
			folder + "/m.yaml",
			"image: m.pgm\nresolution: 1\norigin: [0, 0, 0]\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: "
			"0.196\nmode: scale\n");
	};
	std::ostringstream idx;
	idx << "snapshot,frames,frame_index,rawlog_entry,robot_x,robot_y,robot_yaw_deg\n";
	for (int f = 0; f < 6; f++)
	{
		char name[16];
		std::snprintf(name, sizeof name, "%06d", 2 * (f + 1));
		writeMap(dir + "/snapshots/" + name, kMaps[f]);
		// the snapshot after the first observation of a frame is not the frame's
		char mid[16];
		std::snprintf(mid, sizeof mid, "%06d", 2 * f + 1);
		writeMap(dir + "/snapshots/" + mid, "OOOOOOOO");
		idx << mid << "," << 2 * f + 1 << "," << 2 * f << "," << 3 * f + 2 << ",0,0,0\n";
		idx << name << "," << 2 * (f + 1) << "," << 2 * f + 1 << "," << 3 * f + 3 << ",0,0,0\n";
	}
	writeFile(dir + "/snapshots/index.csv", idx.str());
	writeMap(dir, kMaps[5]);
	return dir;
}

SequenceScore score(const GroundTruth& gt, const SequenceTruth& seq, int ghostFrames = 2)
{
	SequenceOptions o;
	o.ghost_frames = ghostFrames;
	o.view_margin_cells = 0;
	return evaluateSequence(
		gt, seq, [](int f) { return mapOf(kMaps[f]); }, o);
}
}  // namespace

TEST(EvalSequence, ReadsThePerFrameGroundTruthAndMatchesSnapshots)
{
	TempDir d;
	const std::string prefix = writeGt(d);
	const GroundTruth gt = loadGroundTruth(prefix);
	const SequenceTruth seq = loadSequenceTruth(prefix, gt);
	ASSERT_EQ(seq.frames.size(), 6u);
	ASSERT_EQ(seq.frames[0].geom.size(), 2u);
	EXPECT_EQ(seq.frames[0].geom[0].ix0, 1);
	EXPECT_EQ(seq.frames[0].geom[0].ix1, 3);
	EXPECT_EQ(seq.frames[0].geom[0].label, Label::Obstacle);
	EXPECT_EQ(seq.frames[0].geom[1].label, Label::Drop);
	EXPECT_EQ(seq.frames[0].geom[1].objectId, 2);
	EXPECT_EQ(seq.frames[2].view.size(), 3u);
	EXPECT_EQ(seq.frames[5].firstEntry, 16);
	EXPECT_EQ(seq.frames[5].lastEntry, 18);
	// the snapshot taken after each frame's last rawlog entry, not the one in between
	const std::string run = writeRun(d);
	const auto names = snapshotsPerFrame(seq, loadSnapshotIndex(run));
	ASSERT_EQ(names.size(), 6u);
	EXPECT_EQ(names[0], "000002");
	EXPECT_EQ(names[5], "000012");
	// a run without the snapshot of a frame: the error says which --snapshot-every fits
	std::vector<SnapshotRow> partial = loadSnapshotIndex(run);
	partial.pop_back();
	try
	{
		snapshotsPerFrame(seq, partial);
		FAIL() << "expected an error";
	}
	catch (const Error& e)
	{
		EXPECT_NE(std::string(e.what()).find("frame 5"), std::string::npos) << e.what();
		EXPECT_NE(std::string(e.what()).find("--snapshot-every 2"), std::string::npos) << e.what();
	}
}

TEST(EvalSequence, GhostsClearingHazardsAndChangesOutsideTheView)
{
	TempDir d;
	const std::string prefix = writeGt(d);
	const GroundTruth gt = loadGroundTruth(prefix);
	const SequenceScore s = score(gt, loadSequenceTruth(prefix, gt));
	EXPECT_EQ(s.frames, 6);
	// cells 1 and 2 had to be cleared (seen free in frame 2, occupied after frame 1)
	EXPECT_EQ(s.former_obstacle_cells, 2);
	// both judged (2 + 2 <= 5); cell 2 still occupied in frame 4: one ghost
	EXPECT_EQ(s.ghost_judged, 2);
	EXPECT_EQ(s.ghost_cells, 1);
	EXPECT_DOUBLE_EQ(s.ghostPct(), 50.0);
	ASSERT_EQ(s.clear_frames, std::vector<int>({2}));  // cell 1: frame 2 -> 4
	EXPECT_DOUBLE_EQ(s.medianClearFrames(), 2.0);
	EXPECT_EQ(s.maxClearFrames(), 2);
	EXPECT_EQ(s.not_cleared, 1);  // cell 2
	// cell 5: marked while seen, out of view in frames 2-5, free in frame 4
	EXPECT_EQ(s.hazard_cells, 1);
	EXPECT_EQ(s.hazard_lost, 1);
	// outside the view: cell 7 U->F (frame 3), cell 5 O->F (4) and F->O (5)
	EXPECT_EQ(s.changed_outside_view, 3);
	EXPECT_EQ(s.changed_outside_cells, 2);
	EXPECT_EQ(s.value_changed_outside_view, 3);

	ASSERT_EQ(s.perFrame.size(), 6u);
	const long toClear[6] = {0, 0, 2, 2, 1, 1}, ghosts[6] = {0, 0, 0, 0, 1, 1};
	const long hazOut[6] = {0, 0, 1, 1, 1, 1}, hazLost[6] = {0, 0, 0, 0, 1, 0};
	const long changed[6] = {0, 0, 0, 1, 1, 1};
	for (int f = 0; f < 6; f++)
	{
		SCOPED_TRACE(f);
		EXPECT_EQ(s.perFrame[size_t(f)].to_clear, toClear[f]);
		EXPECT_EQ(s.perFrame[size_t(f)].ghost_cells, ghosts[f]);
		EXPECT_EQ(s.perFrame[size_t(f)].hazard_out_of_view, hazOut[f]);
		EXPECT_EQ(s.perFrame[size_t(f)].hazard_lost, hazLost[f]);
		EXPECT_EQ(s.perFrame[size_t(f)].changed_outside_view, changed[f]);
	}
	// frame 0: seen cells 0-6; obstacles/drops 1,2,3,5,6 all occupied; every free cell
	// is within 1 cell of one: no floor scored
	EXPECT_EQ(s.perFrame[0].obstacle_cells, 5);
	EXPECT_EQ(s.perFrame[0].obstacle_occupied, 5);
	EXPECT_EQ(s.perFrame[0].floor_cells, 0);
	// frame 5: drops 5, 6 (occupied); floor 0-3 (4 is next to the drop): 2 and 3 occupied
	EXPECT_EQ(s.perFrame[5].obstacle_cells, 2);
	EXPECT_EQ(s.perFrame[5].obstacle_occupied, 2);
	EXPECT_EQ(s.perFrame[5].floor_cells, 4);
	EXPECT_EQ(s.perFrame[5].floor_occupied, 2);
	EXPECT_EQ(s.perFrame[5].floor_free, 2);
}

TEST(EvalSequence, GhostWindowAndViewMargin)
{
	TempDir d;
	const std::string prefix = writeGt(d);
	const GroundTruth gt = loadGroundTruth(prefix);
	const SequenceTruth seq = loadSequenceTruth(prefix, gt);
	// ghost_frames 4: seen free in frame 2, judged in frame 6 > last frame 5: nobody judged
	const SequenceScore late = score(gt, seq, 4);
	EXPECT_EQ(late.former_obstacle_cells, 2);
	EXPECT_EQ(late.ghost_judged, 0);
	EXPECT_EQ(late.ghost_cells, 0);
	EXPECT_EQ(late.not_cleared, 1);
	// ghost_frames 1: cell 1 still occupied in frame 3, cell 2 too: 2 of 2
	const SequenceScore early = score(gt, seq, 1);
	EXPECT_EQ(early.ghost_judged, 2);
	EXPECT_EQ(early.ghost_cells, 2);
	// a view margin of 1 cell: cell 5 lies next to the seen cells 4 and 6, so it is
	// never out of view and its changes are not outside the view; cell 7 next to 6 too
	SequenceOptions o;
	o.ghost_frames = 2;
	o.view_margin_cells = 1;
	const SequenceScore m = evaluateSequence(
		gt, seq, [](int f) { return mapOf(kMaps[f]); }, o);
	EXPECT_EQ(m.hazard_cells, 0);
	EXPECT_EQ(m.hazard_lost, 0);
	EXPECT_EQ(m.changed_outside_view, 0);
	EXPECT_EQ(m.ghost_cells, 1);  // the margin does not change what was seen
}

TEST(EvalSequence, BadPerFrameGroundTruth)
{
	TempDir d;
	const std::string prefix = writeGt(d);
	const GroundTruth gt = loadGroundTruth(prefix);
	auto expectError = [&](const std::string& text, const std::string& what) {
		writeFile(prefix + "_gt_frames.csv", text);
		try
		{
			loadSequenceTruth(prefix, gt);
			ADD_FAILURE() << "no error for: " << text;
		}
		catch (const Error& e)
		{
			EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
		}
	};
	const std::string h = "frame,kind,iy,ix0,ix1,label,object_id\n";
	expectError("frame,kind\n", "bad header");
	expectError(h + "0,view,0,0,8,,0\n0,entries,0,1,2,,0\n", "outside the ground truth's 8x1 grid");
	expectError(h + "0,geom,0,0,1,unobserved,0\n0,entries,0,1,2,,0\n", "label must be free, obstacle or drop");
	expectError(h + "0,fov,0,0,1,,0\n0,entries,0,1,2,,0\n", "unknown kind 'fov'");
	expectError(h + "0,entries,0,1,3,,0\n2,entries,0,7,9,,0\n", "frame 1 has no entries row");
	expectError(h, "no frames");
	fs::remove(prefix + "_gt_frames.csv");
	EXPECT_THROW(loadSequenceTruth(prefix, gt), Error);  // cannot open
}

TEST(EvalSequence, GamEvaluateSequenceWritesTableJsonAndCsv)
{
#ifndef GAM_EVALUATE_EXE
	GTEST_SKIP() << "gam-evaluate not built";
#else
	TempDir d;
	const std::string prefix = writeGt(d);
	const std::string run = writeRun(d);
	const std::string cmd = std::string(GAM_EVALUATE_EXE) + " --gt " + prefix + " --map " + run +
							"/m.yaml --sequence --ghost-frames 2 --view-margin-cells 0 --sequence-json " +
							(d / "seq.json") + " --sequence-csv " + (d / "seq.csv") + " > " + (d / "out.txt") + " 2>&1";
	ASSERT_EQ(WEXITSTATUS(std::system(cmd.c_str())), 0);
	std::ifstream j(d / "seq.json");
	std::stringstream js;
	js << j.rdbuf();
	for (const char* key :
		 {"\"former_obstacle_cells\": 2", "\"ghost_judged\": 2", "\"ghost_cells\": 1", "\"ghost_pct\": 50.000",
		  "\"clear_frames_median\": 2.0", "\"not_cleared\": 1", "\"hazard_cells\": 1", "\"hazard_lost\": 1",
		  "\"changed_outside_view\": 3", "\"changed_outside_cells\": 2"})
		EXPECT_NE(js.str().find(key), std::string::npos) << key << "\n" << js.str();
	std::ifstream c(d / "seq.csv");
	std::string line;
	int rows = 0;
	while (std::getline(c, line)) rows++;
	EXPECT_EQ(rows, 7);  // header + 6 frames
	std::ifstream o(d / "out.txt");
	std::stringstream os;
	os << o.rdbuf();
	EXPECT_NE(os.str().find("over time (6 frames)"), std::string::npos) << os.str();
	// --sequence-json without --sequence, and a run without snapshots
	EXPECT_EQ(
		WEXITSTATUS(std::system((std::string(GAM_EVALUATE_EXE) + " --gt " + prefix + " --map " + run +
								 "/m.yaml --sequence-json x.json" + " > /dev/null 2>&1")
									.c_str())),
		2);
	fs::remove_all(run + "/snapshots");
	EXPECT_EQ(
		WEXITSTATUS(std::system((std::string(GAM_EVALUATE_EXE) + " -q --gt " + prefix + " --map " + run +
								 "/m.yaml --sequence > " + (d / "err.txt") + " 2>&1")
									.c_str())),
		1);
	std::ifstream e(d / "err.txt");
	std::stringstream es;
	es << e.rdbuf();
	EXPECT_NE(es.str().find("gam-evaluate: error: cannot open"), std::string::npos) << es.str();
#endif
}
