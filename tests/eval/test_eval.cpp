// Tests of libs/ground_eval (gam::eval) and rawlog_tools/gam-evaluate on hand-made
// ground truth and hand-made maps written into a temporary folder.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "gam/eval/Evaluation.h"

namespace fs = std::filesystem;
using namespace gam::eval;

namespace
{
// A hand-made scene, row 0 = highest y, 0.1 m cells, lower-left corner (0, 0):
//   '.' floor   '?' unobserved floor   'r' ramp (object 5, free)
//   'A' obstacle of object 1 (small)   'B' drop of object 2 (negative)
//   'C' obstacle of object 3 (large)   'D' obstacle of object 4 (overhang)
//   'E' unobserved obstacle of object 6 (large, never seen: must not count)
//   'q' unobserved cell of the ramp (object 5)
const std::vector<std::string> kScene = {
	"??????????????",  //
	"?...........E?",  //
	"?.AA......CC.?",  //
	"?.AA......CC.?",  //
	"?............?",  //
	"?....BB....rr?",  //
	"?....BB....rr?",  //
	"?.DD.........?",  //
	"?............?",  //
	"??????????????",
};
constexpr double kRes = 0.1;

struct TempDir
{
	fs::path path;
	TempDir()
	{
		char tmpl[] = "/tmp/gam_test_eval_XXXXXX";
		path = mkdtemp(tmpl);
	}
	~TempDir() { fs::remove_all(path); }
	std::string operator/(const std::string& f) const { return (path / f).string(); }
};

void writeFile(const std::string& p, const std::string& s)
{
	std::ofstream f(p, std::ios::binary);
	f << s;
}

std::string writeGt(const TempDir& d, const std::vector<std::string>& rows = kScene, double ox = 0, double oy = 0)
{
	const std::string prefix = d / "scene";
	writeFile(
		prefix + "_gt.yaml", "image: scene_gt.pgm\nresolution: 0.1\norigin: [" + std::to_string(ox) + ", " +
								 std::to_string(oy) + ", 0.0]\nnegate: 0\n");
	writeFile(
		prefix + "_gt_objects.csv",
		"id,name,type,category,min_x,min_y,min_z,max_x,max_y,max_z\n"
		"1,box,box,small,0,0,0,1,1,1\n2,outlet,hole,negative,0,0,0,1,1,1\n3,cabinet,box,large,0,0,0,1,1,1\n"
		"4,table,table,overhang,0,0,0,1,1,1\n5,ramp,ramp,ramp,0,0,0,1,1,1\n6,hidden,box,large,0,0,0,1,1,1\n");
	std::ostringstream l;
	l << "ix,iy,x,y,label,object_id,category\n";
	const int ny = int(rows.size()), nx = int(rows[0].size());
	const std::map<char, std::pair<int, std::string>> obj = {
		{'A', {1, "small"}}, {'B', {2, "negative"}}, {'C', {3, "large"}}, {'D', {4, "overhang"}},
		{'r', {5, "ramp"}},  {'E', {6, "large"}},    {'q', {5, "ramp"}}};
	for (int iy = 0; iy < ny; iy++)
		for (int ix = 0; ix < nx; ix++)
		{
			const char c = rows[size_t(ny - 1 - iy)][size_t(ix)];
			std::string label = "free";
			int id = 0;
			std::string cat = "none";
			if (c == '?' || c == 'E' || c == 'q')
				label = "unobserved";
			else if (c == 'B')
				label = "drop";
			else if (c != '.' && c != 'r')
				label = "obstacle";
			if (obj.count(c)) id = obj.at(c).first, cat = obj.at(c).second;
			char b[128];
			std::snprintf(
				b, sizeof(b), "%d,%d,%.4f,%.4f,%s,%d,%s\n", ix, iy, ox + (ix + 0.5) * kRes, oy + (iy + 0.5) * kRes,
				label.c_str(), id, cat.c_str());
			l << b;
		}
	writeFile(prefix + "_gt_labels.csv", l.str());
	return prefix;
}

/** A map_server map; pixels row 0 = highest y. */
std::string writeMap(
	const TempDir& d, const std::string& name, const std::vector<std::vector<uint8_t>>& px, double res, double ox,
	double oy, const std::string& extraYaml = "mode: scale\nnegate: 0\n")
{
	const int h = int(px.size()), w = int(px[0].size());
	std::string pgm = "P5\n# test\n" + std::to_string(w) + " " + std::to_string(h) + "\n255\n";
	for (const auto& r : px) pgm.append(r.begin(), r.end());
	writeFile(d / (name + ".pgm"), pgm);
	std::ostringstream y;
	y << "image: " << name << ".pgm\nresolution: " << res << "\norigin: [" << ox << ", " << oy << ", 0.0]\n"
	  << extraYaml << "occupied_thresh: 0.65\nfree_thresh: 0.196\n";
	writeFile(d / (name + ".yaml"), y.str());
	return d / (name + ".yaml");
}

/** The perfect map of kScene at resolution kRes / sub (each GT cell -> sub x sub
 * pixels), origin (0, 0): obstacle/drop 0, observed free 255, unobserved 128. */
std::vector<std::vector<uint8_t>> perfectPixels(const std::vector<std::string>& rows = kScene, int sub = 1)
{
	std::vector<std::vector<uint8_t>> px;
	for (const auto& r : rows)
	{
		std::vector<uint8_t> line;
		for (char c : r)
			for (int s = 0; s < sub; s++)
				line.push_back(c == '?' || c == 'E' || c == 'q' ? 128 : (c == '.' || c == 'r') ? 255 : 0);
		for (int s = 0; s < sub; s++) px.push_back(line);
	}
	return px;
}

/** Pixel of GT cell (ix, iy) in a perfectPixels(sub=1) image. */
uint8_t& at(std::vector<std::vector<uint8_t>>& px, int ix, int iy)
{
	return px[px.size() - 1 - size_t(iy)][size_t(ix)];
}

const CategoryScore& cat(const Reading& r, const std::string& c) { return r.categories.at(c); }

}  // namespace

TEST(Eval, ReadsGroundTruth)
{
	TempDir d;
	const GroundTruth gt = loadGroundTruth(writeGt(d));
	EXPECT_EQ(gt.nx, 14);
	EXPECT_EQ(gt.ny, 10);
	EXPECT_DOUBLE_EQ(gt.resolution, 0.1);
	EXPECT_EQ(gt.objects.size(), 6u);
	EXPECT_EQ(gt.label[gt.idx(2, 7)], Label::Obstacle);  // 'A' at row 2 -> iy 7
	EXPECT_EQ(gt.objectId[gt.idx(2, 7)], 1);
	EXPECT_EQ(gt.label[gt.idx(5, 4)], Label::Drop);
	EXPECT_EQ(gt.label[gt.idx(0, 0)], Label::Unobserved);
}

TEST(Eval, PerfectMapScoresFullDetectionAndNoFalseObstacles)
{
	TempDir d;
	const GroundTruth gt = loadGroundTruth(writeGt(d));
	const MapScore s = evaluate(gt, loadRosMap(writeMap(d, "perfect", perfectPixels(), kRes, 0, 0)));
	EXPECT_EQ(s.name, "perfect");
	for (const Reading* r : {&s.main, &s.strict})
	{
		for (const auto& c : reportCategories())
		{
			// One observed object per category: "large" also has object 6 in
			// the ground truth, which no frame observed, so it does not count.
			EXPECT_EQ(cat(*r, c).objects, 1) << c;
			EXPECT_EQ(cat(*r, c).detected, cat(*r, c).objects) << c;
			EXPECT_DOUBLE_EQ(cat(*r, c).meanCoverage(), 1.0) << c;
		}
		EXPECT_EQ(r->categories.count("ramp"), 0u);  // a ramp has no obstacle cells
		EXPECT_GT(r->floor.n, 30);
		EXPECT_EQ(r->floor.occupied, 0);
		EXPECT_EQ(r->floor.free, r->floor.n);
		EXPECT_DOUBLE_EQ(r->floor.pct(r->floor.free), 100.0);
		EXPECT_EQ(r->ramp.n, 4);  // the cabinet C is 2 rows above the ramp: outside the band
		EXPECT_EQ(r->obstacle.n, 4 + 4 + 4 + 2);
		EXPECT_EQ(r->obstacle.occupied, r->obstacle.n);
	}
	// the tolerance band: observed free cells within 1 cell of A, B, C or D
	EXPECT_GT(s.excluded_floor, 20);
	EXPECT_EQ(s.main.floor.n + s.excluded_floor, 12 * 8 - 15);  // every observed free cell (96 - 14 obstacle/drop - E)
}

TEST(Eval, MissingObjectFalseObstacleAndUnknownCells)
{
	TempDir d;
	const GroundTruth gt = loadGroundTruth(writeGt(d));
	auto px = perfectPixels();
	const MapScore ref = evaluate(gt, loadRosMap(writeMap(d, "ref", px, kRes, 0, 0)));
	// object 1 ('A', the small box, cells ix 2-3, iy 6-7) missing: floor there
	for (int ix = 2; ix <= 3; ix++)
		for (int iy = 6; iy <= 7; iy++) at(px, ix, iy) = 255;
	// one floor cell far from every object wrongly occupied (p_occ = 0.6: the main
	// reading calls it occupied, map_server's 0.65 does not)
	at(px, 7, 1) = 102;
	// two floor cells unknown: 128 (what the mapper writes) and 127 (1 grey level off)
	at(px, 8, 1) = 128;
	at(px, 9, 1) = 127;
	// one weakly free cell: free for the main reading, unknown for map_server (0.196)
	at(px, 6, 1) = 150;
	// an occupied cell right next to the drop: in the tolerance band, not scored
	at(px, 4, 4) = 0;
	const MapScore s = evaluate(gt, loadRosMap(writeMap(d, "m", px, kRes, 0, 0)));
	EXPECT_EQ(cat(s.main, "small").objects, 1);
	EXPECT_EQ(cat(s.main, "small").detected, 0);
	EXPECT_EQ(cat(s.main, "negative").detected, 1);
	EXPECT_EQ(cat(s.main, "large").detected, 1);
	EXPECT_EQ(cat(s.main, "overhang").detected, 1);
	EXPECT_EQ(s.main.objects.front().id, 1);
	EXPECT_EQ(s.main.objects.front().free, 4);
	EXPECT_FALSE(s.main.objects.front().detected);
	EXPECT_EQ(s.main.floor.n, ref.main.floor.n);  // the box's cells are obstacle in the GT, not floor
	EXPECT_EQ(s.main.floor.occupied, 1);
	EXPECT_EQ(s.main.floor.unknown, 2);
	EXPECT_EQ(s.main.floor.free, s.main.floor.n - 3);
	EXPECT_EQ(s.strict.floor.occupied, 0);
	EXPECT_EQ(s.strict.floor.unknown, 4);  // 102 and 150 are unknown for map_server too
	EXPECT_EQ(s.strict.floor.free, s.main.floor.n - 4);
	// without the tolerance band the cell next to the drop counts
	Options o0;
	o0.tolerance_cells = 0;
	const MapScore s0 = evaluate(gt, loadRosMap(writeMap(d, "m0", px, kRes, 0, 0)), o0);
	EXPECT_EQ(s0.main.floor.occupied, 2);
	EXPECT_EQ(s0.excluded_floor, 0);
	EXPECT_EQ(s0.main.floor.n, 12 * 8 - 15);
}

TEST(Eval, FloorNextToAnUnobservedObstacleCellIsNotScored)
{
	// A wall whose face lies in the outer sixth of the floor cell in front of
	// it: the GT's probes miss it there (that cell is floor), and every ray
	// ends in that cell, so the wall's own cells stay unobserved ('E'). A map
	// that marks the cell holding the face is right; the tolerance band holds
	// it as it holds the cells next to a wall that was observed. A ramp's
	// unobserved cell ('q') may be floor or a side face: no band around it.
	const std::vector<std::string> rows = {
		"???????",  //
		"?....E?",  //
		"?.....?",  //
		"?....q?",  //
		"???????",
	};
	TempDir d;
	const GroundTruth gt = loadGroundTruth(writeGt(d, rows));
	auto px = perfectPixels(rows);
	at(px, 4, 3) = 0;  // in front of E (row 1 -> iy 3)
	at(px, 4, 1) = 0;  // in front of q (row 3 -> iy 1)
	const MapScore s = evaluate(gt, loadRosMap(writeMap(d, "m", px, kRes, 0, 0)));
	// 13 observed free cells (rows 1-3, columns 1-5, but E and q); within one
	// cell of E: (4, 3), (4, 2), (5, 2).
	EXPECT_EQ(s.excluded_floor, 3);
	EXPECT_EQ(s.main.floor.n, 13 - 3);
	EXPECT_EQ(s.main.floor.occupied, 1);  // the cell next to q
	// E is no object of the score: none of its cells was observed.
	EXPECT_TRUE(s.main.objects.empty());
	Options o0;
	o0.tolerance_cells = 0;
	const MapScore s0 = evaluate(gt, loadRosMap(writeMap(d, "m0", px, kRes, 0, 0)), o0);
	EXPECT_EQ(s0.excluded_floor, 0);
	EXPECT_EQ(s0.main.floor.n, 13);
	EXPECT_EQ(s0.main.floor.occupied, 2);
}

TEST(Eval, MinHitsAndCoverage)
{
	TempDir d;
	const GroundTruth gt = loadGroundTruth(writeGt(d));
	auto px = perfectPixels();
	at(px, 2, 6) = at(px, 3, 6) = at(px, 3, 7) = 255;  // box: 1 of 4 cells left
	const auto m = loadRosMap(writeMap(d, "m", px, kRes, 0, 0));
	const MapScore s1 = evaluate(gt, m);
	EXPECT_EQ(cat(s1.main, "small").detected, 1);
	EXPECT_DOUBLE_EQ(cat(s1.main, "small").meanCoverage(), 0.25);
	Options o;
	o.min_hits = 2;
	EXPECT_EQ(cat(evaluate(gt, m, o).main, "small").detected, 0);
}

TEST(Eval, FinerMapWithAnotherOriginWorstSubcellWins)
{
	TempDir d;
	const GroundTruth gt = loadGroundTruth(writeGt(d));
	// 0.05 m map, 2 x 2 pixels per GT cell, with 3 extra columns on the left and 2 extra
	// rows at the bottom (origin -0.15, -0.10): same world, other origin and resolution
	auto px = perfectPixels(kScene, 2);
	for (auto& r : px) r.insert(r.begin(), 3, 128);
	for (int i = 0; i < 2; i++) px.push_back(std::vector<uint8_t>(px[0].size(), 128));
	const auto good = loadRosMap(writeMap(d, "fine", px, 0.05, -0.15, -0.10));
	const MapScore s = evaluate(gt, good);
	for (const auto& c : reportCategories()) EXPECT_EQ(cat(s.main, c).detected, 1) << c;
	EXPECT_EQ(s.main.floor.occupied, 0);
	EXPECT_EQ(s.main.floor.free, s.main.floor.n);
	EXPECT_DOUBLE_EQ(cat(s.main, "small").meanCoverage(), 1.0);
	// one 5 cm pixel occupied inside GT floor cell (7, 1): that cell is occupied
	// (x in [0.70, 0.80) -> pixel column 3 + 14 or 15; y in [0.10, 0.20) -> bottom rows 2+2..3)
	auto px2 = px;
	px2[px2.size() - 1 - 4][3 + 15] = 0;
	const MapScore s2 = evaluate(gt, loadRosMap(writeMap(d, "fine2", px2, 0.05, -0.15, -0.10)));
	EXPECT_EQ(s2.main.floor.occupied, 1);
	// only 1 of the 4 sub-cells of a box cell occupied: still occupied
	auto px3 = px;
	// box cells ix 2-3, iy 6-7 -> x 0.2-0.4 -> columns 3+4..3+7; y 0.6-0.8 -> bottom rows 2+12..2+15
	for (int c = 7; c <= 10; c++)
		for (int rb = 14; rb <= 17; rb++) px3[px3.size() - 1 - size_t(rb)][size_t(c)] = 255;
	px3[px3.size() - 1 - 14][7] = 0;
	const MapScore s3 = evaluate(gt, loadRosMap(writeMap(d, "fine3", px3, 0.05, -0.15, -0.10)));
	EXPECT_EQ(s3.main.objects.front().occupied, 1);
	EXPECT_TRUE(s3.main.objects.front().detected);
}

TEST(Eval, CoarserMapIsSampledAtCellCentres)
{
	TempDir d;
	const GroundTruth gt = loadGroundTruth(writeGt(d));
	// 0.2 m map covering x in [-0.2, 3.0), y in [0, 2.0): all free except the coarse
	// cell x in [0.6, 0.8), y in [0.0, 0.2) -> GT cells ix 6-7, iy 0-1
	std::vector<std::vector<uint8_t>> px(10, std::vector<uint8_t>(16, 255));
	px[9][4] = 0;
	const MapScore s = evaluate(gt, loadRosMap(writeMap(d, "coarse", px, 0.2, -0.2, 0.0)));
	EXPECT_EQ(s.main.floor.occupied, 2);  // (6,1), (7,1): iy 0 is unobserved
	EXPECT_EQ(cat(s.main, "small").detected, 0);
}

TEST(Eval, OutsideTheMapIsUnknown)
{
	TempDir d;
	const GroundTruth gt = loadGroundTruth(writeGt(d));
	// the perfect map's left half only (x < 0.7)
	auto px = perfectPixels();
	for (auto& r : px) r.resize(7);
	const MapScore s = evaluate(gt, loadRosMap(writeMap(d, "half", px, kRes, 0, 0)));
	EXPECT_EQ(s.main.floor.occupied, 0);
	EXPECT_GT(s.main.floor.unknown, 0);
	EXPECT_EQ(s.main.floor.free + s.main.floor.unknown, s.main.floor.n);
	EXPECT_EQ(cat(s.main, "large").detected, 0);  // the cabinet is at x 1.0-1.2
	EXPECT_EQ(cat(s.main, "small").detected, 1);
	EXPECT_EQ(s.main.ramp.unknown, s.main.ramp.n);
	// a map entirely elsewhere: everything unknown
	const MapScore far = evaluate(gt, loadRosMap(writeMap(d, "far", perfectPixels(), kRes, 100, 100)));
	EXPECT_EQ(far.main.floor.unknown, far.main.floor.n);
	for (const auto& c : reportCategories()) EXPECT_EQ(cat(far.main, c).detected, 0);
}

TEST(Eval, RampsAreScoredPerObject)
{
	// The ramp 'r' (object 5) is the 2 x 2 cells of rows 5-6 of kScene
	// (iy 4 and 3), columns 11-12: one occupied (0), one unknown (128), two free. Of the 4 cells: 25 %
	// occupied, 50 % free, 25 % unknown; free of the 3 the map knows: 2/3.
	TempDir d;
	const GroundTruth gt = loadGroundTruth(writeGt(d));
	auto px = perfectPixels();
	at(px, 11, 4) = 0;
	at(px, 12, 3) = 128;
	const MapScore s = evaluate(gt, loadRosMap(writeMap(d, "m", px, kRes, 0, 0)));
	ASSERT_EQ(s.main.ramps.size(), 1u);
	const RampScore& r = s.main.ramps.front();
	EXPECT_EQ(r.id, 5);
	EXPECT_EQ(r.name, "ramp");
	EXPECT_EQ(r.cells.n, 4);
	EXPECT_EQ(r.cells.occupied, 1);
	EXPECT_EQ(r.cells.free, 2);
	EXPECT_EQ(r.cells.unknown, 1);
	EXPECT_NEAR(r.freeOfKnownPct(), 100.0 * 2.0 / 3.0, 1e-9);
	EXPECT_EQ(s.main.ramp.occupied, 1) << "the pooled ramp counts agree";
	const std::vector<MapScore> v{s};
	EXPECT_NE(toCsv(v).find("m,main,ramp_object,5,ramp,4,1,2,1,0\n"), std::string::npos);
	EXPECT_NE(
		toJson(gt, v, {}).find("\"name\": \"ramp\", \"counts\": {\"cells\": 4, \"occupied\": 1"), std::string::npos);
	EXPECT_NE(toJson(gt, v, {}).find("\"free_of_known_pct\": 66.667"), std::string::npos);
	EXPECT_NE(
		formatTable(gt, v, {}).find(
			"ramp ramp: 4 cells, occupied 25.0 %, free 50.0 %, unknown 25.0 %; free of known 66.7 %"),
		std::string::npos);
}

TEST(Eval, TrinaryAndNegate)
{
	TempDir d;
	const GroundTruth gt = loadGroundTruth(writeGt(d));
	auto px = perfectPixels();
	at(px, 7, 1) = 102;  // p_occ 0.6: unknown in trinary (between 0.196 and 0.65)
	const MapScore t = evaluate(gt, loadRosMap(writeMap(d, "tri", px, kRes, 0, 0, "mode: trinary\nnegate: 0\n")));
	EXPECT_EQ(t.main.floor.occupied, 0);
	EXPECT_EQ(t.main.floor.unknown, 1);
	for (const auto& c : reportCategories()) EXPECT_EQ(cat(t.main, c).detected, 1);
	// negate 1: 255 = occupied
	for (auto& r : px)
		for (auto& v : r) v = uint8_t(255 - v);
	const MapScore n = evaluate(gt, loadRosMap(writeMap(d, "neg", px, kRes, 0, 0, "mode: scale\nnegate: 1\n")));
	EXPECT_EQ(n.main.floor.occupied, 1);
	for (const auto& c : reportCategories()) EXPECT_EQ(cat(n.main, c).detected, 1);
}

TEST(Eval, OutputsNameEveryMapAndCategory)
{
	TempDir d;
	const GroundTruth gt = loadGroundTruth(writeGt(d));
	std::vector<MapScore> v{
		evaluate(gt, loadRosMap(writeMap(d, "ground_aware", perfectPixels(), kRes, 0, 0))),
		evaluate(gt, loadRosMap(writeMap(d, "octomap", perfectPixels(), kRes, 0, 0)))};
	const std::string table = formatTable(gt, v, {});
	EXPECT_NE(table.find("ground_aware"), std::string::npos);
	EXPECT_NE(table.find("octomap"), std::string::npos);
	EXPECT_NE(table.find("1/1 (100%)"), std::string::npos);
	const std::string js = toJson(gt, v, {});
	for (const char* k :
		 {"\"negative\"", "\"small\"", "\"overhang\"", "\"large\"", "\"floor_false_obstacle_pct\": 0.000",
		  "\"floor_free_pct\": 100.000", "\"map_server\"", "\"detected\": true"})
		EXPECT_NE(js.find(k), std::string::npos) << k;
	const std::string csv = toCsv(v);
	EXPECT_EQ(csv.rfind("map,reading,record,id,category,n,occupied,free,unknown,detected\n", 0), 0u);
	EXPECT_NE(csv.find("octomap,main,object,1,small,4,4,0,0,1\n"), std::string::npos);
}

TEST(Eval, BadInputsThrow)
{
	TempDir d;
	const std::string prefix = writeGt(d);
	const std::string good = writeMap(d, "good", perfectPixels(), kRes, 0, 0);
	EXPECT_THROW(loadRosMap(d / "missing.yaml"), Error);
	EXPECT_THROW(loadGroundTruth(d / "missing"), Error);
	// yaml problems
	writeFile(d / "nores.yaml", "image: good.pgm\norigin: [0, 0, 0]\n");
	EXPECT_THROW(loadRosMap(d / "nores.yaml"), Error);
	writeFile(d / "badres.yaml", "image: good.pgm\nresolution: abc\norigin: [0, 0, 0]\n");
	EXPECT_THROW(loadRosMap(d / "badres.yaml"), Error);
	writeFile(d / "yaw.yaml", "image: good.pgm\nresolution: 0.1\norigin: [0, 0, 0.5]\n");
	EXPECT_THROW(loadRosMap(d / "yaw.yaml"), Error);
	writeFile(d / "raw.yaml", "image: good.pgm\nresolution: 0.1\norigin: [0, 0, 0]\nmode: raw\n");
	EXPECT_THROW(loadRosMap(d / "raw.yaml"), Error);
	writeFile(d / "noimg.yaml", "image: nothere.pgm\nresolution: 0.1\norigin: [0, 0, 0]\n");
	EXPECT_THROW(loadRosMap(d / "noimg.yaml"), Error);
	// pgm problems
	auto withPgm = [&](const std::string& name, const std::string& pgm) {
		writeFile(d / (name + ".pgm"), pgm);
		writeFile(d / (name + ".yaml"), "image: " + name + ".pgm\nresolution: 0.1\norigin: [0, 0, 0]\n");
		return d / (name + ".yaml");
	};
	EXPECT_THROW(loadRosMap(withPgm("ascii", "P2\n2 2\n255\n0 0 0 0\n")), Error);
	EXPECT_THROW(loadRosMap(withPgm("trunc", "P5\n4 4\n255\n" + std::string(5, '\0'))), Error);
	EXPECT_THROW(loadRosMap(withPgm("deep", "P5\n2 2\n65535\n" + std::string(8, '\0'))), Error);
	EXPECT_THROW(loadRosMap(withPgm("hdr", "P5\nx y\n255\n")), Error);
	EXPECT_NO_THROW(loadRosMap(withPgm("ok", "P5\n2 2\n255\n" + std::string(4, '\xff'))));
	// ground-truth problems
	const std::string labels = prefix + "_gt_labels.csv";
	std::ifstream in(labels);
	std::stringstream all;
	all << in.rdbuf();
	const std::string orig = all.str();
	auto breakLabels = [&](const std::string& from, const std::string& to) {
		std::string s = orig;
		s.replace(s.find(from), from.size(), to);
		writeFile(labels, s);
		EXPECT_THROW(loadGroundTruth(prefix), Error) << from << " -> " << to;
	};
	breakLabels(",free,", ",floor,");                   // unknown label
	breakLabels(",obstacle,1,", ",obstacle,99,");       // object not in objects.csv
	breakLabels("ix,iy,", "a,b,");                      // header
	breakLabels("0,0,0.0500,0.0500", "0,0,zz,0.0500");  // not a number
	{
		std::string s = orig;
		s.erase(s.rfind('\n', s.size() - 2) + 1);  // drop the last row
		writeFile(labels, s);
		EXPECT_THROW(loadGroundTruth(prefix), Error);
	}
	writeFile(labels, orig);
	EXPECT_NO_THROW(loadGroundTruth(prefix));
	fs::remove(prefix + "_gt_objects.csv");
	EXPECT_THROW(loadGroundTruth(prefix), Error);
}

#ifdef GAM_EVALUATE_EXE
namespace
{
int run(const std::string& args, const std::string& errFile)
{
	const int rc = std::system((std::string(GAM_EVALUATE_EXE) + " " + args + " >/dev/null 2>" + errFile).c_str());
	return WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
}
std::string slurp(const std::string& p)
{
	std::ifstream f(p);
	std::stringstream s;
	s << f.rdbuf();
	return s.str();
}
}  // namespace

TEST(EvalCli, WritesJsonCsvPngAndFailsCleanly)
{
	TempDir d;
	const std::string prefix = writeGt(d);
	const std::string m1 = writeMap(d, "ground_aware", perfectPixels(), kRes, 0, 0);
	const std::string m2 = writeMap(d, "octomap", perfectPixels(), kRes, 0, 0);
	const std::string err = d / "err.txt";
	EXPECT_EQ(
		run("--gt " + prefix + " --map " + m1 + " --map " + m2 + " --json " + (d / "o.json") + " --csv " +
				(d / "o.csv") + " --png " + (d / "o.png"),
			err),
		0);
	EXPECT_NE(slurp(d / "o.json").find("\"name\": \"octomap\""), std::string::npos);
	EXPECT_NE(slurp(d / "o.csv").find("ground_aware,main,floor"), std::string::npos);
	// the same map file name from two folders: told apart by the folder
	fs::create_directories(d / "runB");
	fs::copy_file(d / "ground_aware.yaml", d / "runB/ground_aware.yaml");
	fs::copy_file(d / "ground_aware.pgm", d / "runB/ground_aware.pgm");
	const std::string m3 = d / "runB/ground_aware.yaml";
	EXPECT_EQ(run("--gt " + prefix + " --map " + m1 + " --map " + m3 + " --json " + (d / "dup.json"), err), 0);
	EXPECT_NE(slurp(d / "dup.json").find("\"name\": \"runB/ground_aware\""), std::string::npos);
	EXPECT_GT(fs::file_size(d / "o.png"), 100u);
	// missing ground truth: exit 1, one line
	EXPECT_EQ(run("--gt " + (d / "nope") + " --map " + m1, err), 1);
	const std::string e = slurp(err);
	EXPECT_EQ(e.rfind("gam-evaluate: error: cannot open", 0), 0u) << e;
	EXPECT_EQ(std::count(e.begin(), e.end(), '\n'), 1);
	// missing map
	EXPECT_EQ(run("--gt " + prefix + " --map " + (d / "none.yaml"), err), 1);
	// unwritable JSON
	EXPECT_EQ(run("--gt " + prefix + " --map " + m1 + " --json /nonexistent/dir/o.json", err), 1);
	// command line: no --map
	EXPECT_EQ(run("--gt " + prefix, err), 2);
	EXPECT_EQ(slurp(err).rfind("gam-evaluate: error: ", 0), 0u);
	EXPECT_EQ(run("--gt " + prefix + " --map " + m1 + " --bogus", err), 2);
	EXPECT_EQ(run("--gt " + prefix + " --map " + m1 + " --tolerance-cells -1", err), 2);
}
#endif
