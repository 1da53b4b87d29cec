// Ground-aware mapping for MRPT -- map evaluation over time (see Sequence.h).
#include "gam/eval/Sequence.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <sstream>

#include "Csv.h"

namespace gam::eval
{
namespace
{
using detail::Columns;
using detail::readCsv;
using detail::toInt;
using detail::trim;

bool geomLabelFromName(const std::string& s, Label& l)
{
	for (Label c : {Label::Free, Label::Obstacle, Label::Drop})
		if (s == labelName(c))
		{
			l = c;
			return true;
		}
	return false;
}

/** Marks (bit) the cells of `runs` grown by m cells (Chebyshev), remembering the cells
 * it touched first. */
void markRuns(
	const GroundTruth& gt, const std::vector<CellRun>& runs, int m, uint8_t bit, std::vector<uint8_t>& mask,
	std::vector<size_t>& touched)
{
	for (const CellRun& r : runs)
		for (int y = std::max(0, r.iy - m); y <= std::min(gt.ny - 1, r.iy + m); y++)
			for (int x = std::max(0, r.ix0 - m); x <= std::min(gt.nx - 1, r.ix1 + m); x++)
			{
				uint8_t& v = mask[gt.idx(x, y)];
				if (!v) touched.push_back(gt.idx(x, y));
				v |= bit;
			}
}

/** Cells within `t` cells (Chebyshev) of a GT obstacle or drop of `label`. */
std::vector<uint8_t> nearHazard(const GroundTruth& gt, const std::vector<Label>& label, int t)
{
	std::vector<uint8_t> near(label.size(), 0);
	for (int iy = 0; iy < gt.ny; iy++)
		for (int ix = 0; ix < gt.nx; ix++)
		{
			const Label l = label[gt.idx(ix, iy)];
			if (l != Label::Obstacle && l != Label::Drop) continue;
			for (int y = std::max(0, iy - t); y <= std::min(gt.ny - 1, iy + t); y++)
				for (int x = std::max(0, ix - t); x <= std::min(gt.nx - 1, ix + t); x++) near[gt.idx(x, y)] = 1;
		}
	return near;
}

/** Is each GT cell's centre inside the map's extent? */
std::vector<uint8_t> insideMap(const GroundTruth& gt, const RosMap& m)
{
	std::vector<uint8_t> in(gt.label.size(), 0);
	const double x1 = m.origin_x + m.width * m.resolution, y1 = m.origin_y + m.height * m.resolution;
	for (size_t i = 0; i < in.size(); i++)
		in[i] = gt.x[i] >= m.origin_x && gt.x[i] < x1 && gt.y[i] >= m.origin_y && gt.y[i] < y1;
	return in;
}

std::string num(double v, int decimals)
{
	char b[64];
	std::snprintf(b, sizeof b, "%.*f", decimals, v);
	return b;
}
}  // namespace

SequenceTruth loadSequenceTruth(const std::string& prefix, const GroundTruth& gt)
{
	SequenceTruth seq;
	const std::string path = prefix + "_gt_frames.csv";
	auto header = [](const std::string& line) { return trim(line) == "frame,kind,iy,ix0,ix1,label,object_id"; };
	auto row = [&](const Columns& c, const std::string& at) {
		if (c.size() < 7) throw Error(at + ": too few columns");
		const int f = toInt(c[0], at + ": frame");
		if (f < 0 || f > 10000000) throw Error(at + ": bad frame " + c[0]);
		if (size_t(f) >= seq.frames.size()) seq.frames.resize(size_t(f) + 1);
		FrameTruth& ft = seq.frames[size_t(f)];
		const std::string kind = trim(c[1]);
		if (kind == "entries")
		{
			if (ft.lastEntry >= 0) throw Error(at + ": frame " + c[0] + " has two entries rows");
			ft.firstEntry = toInt(c[3], at + ": first entry");
			ft.lastEntry = toInt(c[4], at + ": last entry");
			if (ft.firstEntry < 0 || ft.lastEntry < ft.firstEntry) throw Error(at + ": bad rawlog entries");
			return;
		}
		CellRun r;
		r.iy = toInt(c[2], at + ": iy");
		r.ix0 = toInt(c[3], at + ": ix0");
		r.ix1 = toInt(c[4], at + ": ix1");
		if (r.iy < 0 || r.iy >= gt.ny || r.ix0 < 0 || r.ix1 < r.ix0 || r.ix1 >= gt.nx)
			throw Error(
				at + ": cells outside the ground truth's " + std::to_string(gt.nx) + "x" + std::to_string(gt.ny) +
				" grid");
		if (kind == "geom")
		{
			if (!geomLabelFromName(trim(c[5]), r.label))
				throw Error(at + ": label must be free, obstacle or drop (got '" + trim(c[5]) + "')");
			r.objectId = toInt(c[6], at + ": object_id");
			ft.geom.push_back(r);
		}
		else if (kind == "view")
			ft.view.push_back(r);
		else if (kind == "points")
			ft.points.push_back(r);
		else if (kind == "leddar")
			ft.leddar.push_back(r);
		else
			throw Error(at + ": unknown kind '" + kind + "' (entries, geom, view, points, leddar)");
	};
	readCsv(path, header, "frame,kind,iy,ix0,ix1,label,object_id", row);
	if (seq.frames.empty()) throw Error(path + ": no frames");
	for (size_t f = 0; f < seq.frames.size(); f++)
		if (seq.frames[f].lastEntry < 0) throw Error(path + ": frame " + std::to_string(f) + " has no entries row");
	return seq;
}

std::vector<SnapshotRow> loadSnapshotIndex(const std::string& mapDir)
{
	std::vector<SnapshotRow> rows;
	const std::string path = mapDir + "/snapshots/index.csv";
	auto header = [](const std::string& line) {
		return trim(line).rfind("snapshot,frames,frame_index,rawlog_entry", 0) == 0;
	};
	auto row = [&](const Columns& c, const std::string& at) {
		if (c.size() < 4) throw Error(at + ": too few columns");
		SnapshotRow r;
		r.name = trim(c[0]);
		if (r.name.empty() || r.name.find('/') != std::string::npos) throw Error(at + ": bad snapshot name");
		r.frames = toInt(c[1], at + ": frames");
		r.frameIndex = toInt(c[2], at + ": frame_index");
		r.rawlogEntry = toInt(c[3], at + ": rawlog_entry");
		rows.push_back(r);
	};
	readCsv(path, header, "snapshot,frames,frame_index,rawlog_entry,...", row);
	return rows;
}

std::vector<std::string> snapshotsPerFrame(const SequenceTruth& seq, const std::vector<SnapshotRow>& index)
{
	std::map<long, std::string> byEntry;
	for (const auto& r : index) byEntry[r.rawlogEntry] = r.name;
	std::vector<std::string> out;
	for (size_t f = 0; f < seq.frames.size(); f++)
	{
		const auto it = byEntry.find(seq.frames[f].lastEntry);
		if (it == byEntry.end())
			throw Error(
				"no snapshot after frame " + std::to_string(f) + " (rawlog entry " +
				std::to_string(seq.frames[f].lastEntry) + "): run ground-aware-mapper with --snapshot-every " +
				std::to_string(std::max(1L, seq.frames[f].lastEntry - seq.frames[f].firstEntry)));
		out.push_back(it->second);
	}
	return out;
}

double SequenceScore::medianClearFrames() const
{
	if (clear_frames.empty()) return -1;
	std::vector<int> v = clear_frames;
	std::sort(v.begin(), v.end());
	const size_t n = v.size();
	return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

int SequenceScore::maxClearFrames() const
{
	return clear_frames.empty() ? -1 : *std::max_element(clear_frames.begin(), clear_frames.end());
}

SequenceScore evaluateSequence(
	const GroundTruth& gt, const SequenceTruth& seq, const std::function<RosMap(int)>& snapshot,
	const SequenceOptions& opt)
{
	SequenceScore sc;
	const int F = int(seq.frames.size());
	sc.frames = F;
	const size_t n = gt.label.size();
	const int G = opt.ghost_frames;
	std::vector<Label> geom(n, Label::Free);
	std::vector<uint8_t> near(n, 0), seen(n, 0), mask(n, 0);
	std::vector<size_t> touched;
	// former obstacle cells
	enum : uint8_t
	{
		SeenObstacle = 1,
		Judged = 2,
		Ghost = 4
	};
	std::vector<uint8_t> flags(n, 0);
	std::vector<int> pending(n, -1);
	// hazards, changes
	std::vector<uint8_t> hazMarked(n, 0), hazOut(n, 0), hazLost(n, 0), changed(n, 0);
	std::vector<CellState> prevState(n, CellState::Unknown);
	std::vector<float> prevMax(n, 0.5f), prevMin(n, 0.5f);
	std::vector<uint8_t> prevInside(n, 1);
	const double occ = 0.5 + opt.unknown_tolerance, fre = 0.5 - opt.unknown_tolerance;
	constexpr uint8_t View = 1, ViewNear = 2, AnyNear = 4;

	for (int f = 0; f < F; f++)
	{
		const FrameTruth& ft = seq.frames[size_t(f)];
		for (const CellRun& r : ft.geom)
			for (int x = r.ix0; x <= r.ix1; x++) geom[gt.idx(x, r.iy)] = r.label;
		if (!ft.geom.empty()) near = nearHazard(gt, geom, opt.tolerance_cells);
		markRuns(gt, ft.view, 0, View, mask, touched);
		markRuns(gt, ft.view, opt.view_margin_cells, ViewNear | AnyNear, mask, touched);
		markRuns(gt, ft.points, opt.view_margin_cells, AnyNear, mask, touched);
		markRuns(gt, ft.leddar, opt.view_margin_cells, AnyNear, mask, touched);

		const RosMap map = snapshot(f);
		const Resampled rs = resample(gt, map);
		const std::vector<CellState> st = classify(rs, occ, fre);
		const std::vector<uint8_t> inside = insideMap(gt, map);

		FrameScore fs;
		fs.frame = f;
		for (size_t i = 0; i < n; i++)
		{
			const bool inView = mask[i] & View;
			const bool occupied = st[i] == CellState::Occupied;
			if (inView) seen[i] = 1;
			// (1) former obstacle cells: clearing and ghosts
			auto drop = [&] {
				sc.former_obstacle_cells--;
				if (flags[i] & Judged) sc.ghost_judged--;
				if (flags[i] & Ghost) sc.ghost_cells--;
				flags[i] &= uint8_t(~(Judged | Ghost));
				pending[i] = -1;
			};
			if (inView && geom[i] == Label::Obstacle)
			{
				if (pending[i] >= 0) drop();
				flags[i] |= SeenObstacle;
			}
			else if (inView && geom[i] == Label::Free && (flags[i] & SeenObstacle) && pending[i] < 0 && !near[i])
			{
				flags[i] &= uint8_t(~SeenObstacle);
				if (prevState[i] == CellState::Occupied)
				{
					pending[i] = f;
					sc.former_obstacle_cells++;
				}
			}
			if (pending[i] >= 0)
			{
				const int since = f - pending[i];
				if (!occupied)
				{
					sc.clear_frames.push_back(since);
					if (pending[i] + G <= F - 1 && !(flags[i] & Judged)) sc.ghost_judged++;
					flags[i] &= uint8_t(~(Judged | Ghost));
					pending[i] = -1;
				}
				else if (since == G && near[i])
					drop();  // an obstacle is back next to it: not judged
				else
				{
					if (since == G)
					{
						sc.ghost_judged++;
						sc.ghost_cells++;
						flags[i] |= Judged | Ghost;
					}
					fs.to_clear++;
					if (since >= G) fs.ghost_cells++;
				}
			}
			// (2) hazards out of view
			if (geom[i] != Label::Drop)
				hazMarked[i] = 0;
			else
			{
				// what the map had when it last saw the cell (or a cell next to it: the
				// margin) is what it must keep out of view
				const bool nearView = mask[i] & ViewNear;
				if (nearView) hazMarked[i] = occupied;
				if (hazMarked[i] && !nearView && inside[i])
				{
					fs.hazard_out_of_view++;
					hazOut[i] = 1;
					if (!occupied)
					{
						fs.hazard_lost++;
						hazLost[i] = 1;
					}
				}
			}
			// (3) changes outside every sensor's view
			if (!(mask[i] & AnyNear) && inside[i] && prevInside[i])
			{
				if (st[i] != prevState[i])
				{
					fs.changed_outside_view++;
					changed[i] = 1;
				}
				if (std::abs(rs.pMax[i] - prevMax[i]) > 0.5f / 255 || std::abs(rs.pMin[i] - prevMin[i]) > 0.5f / 255)
					fs.value_changed_outside_view++;
			}
			// (4) per-frame scores
			if (seen[i])
			{
				if (geom[i] == Label::Obstacle || geom[i] == Label::Drop)
				{
					fs.obstacle_cells++;
					fs.obstacle_occupied += occupied;
				}
				else if (!near[i])
				{
					fs.floor_cells++;
					fs.floor_occupied += occupied;
					fs.floor_free += st[i] == CellState::Free;
				}
			}
			prevState[i] = st[i];
			prevMax[i] = rs.pMax[i];
			prevMin[i] = rs.pMin[i];
			prevInside[i] = inside[i];
		}
		for (size_t i : touched) mask[i] = 0;
		touched.clear();
		sc.changed_outside_view += fs.changed_outside_view;
		sc.value_changed_outside_view += fs.value_changed_outside_view;
		sc.perFrame.push_back(fs);
	}
	for (size_t i = 0; i < n; i++)
	{
		sc.not_cleared += pending[i] >= 0;
		sc.hazard_cells += hazOut[i];
		sc.hazard_lost += hazLost[i];
		sc.changed_outside_cells += changed[i];
	}
	return sc;
}

std::string formatSequenceTable(const std::vector<SequenceScore>& s, const SequenceOptions& opt)
{
	std::ostringstream o;
	o << "over time (" << (s.empty() ? 0 : s[0].frames) << " frames): former obstacle cells = seen as obstacle, then "
	  << "seen free and occupied in the map; ghost = still occupied " << opt.ghost_frames
	  << " frames later; hazard = GT drop cell marked in view, checked while out of view (margin "
	  << opt.view_margin_cells << " cell); changed = map state changed outside every sensor's view\n";
	char b[400];
	std::snprintf(
		b, sizeof b, "%-14s %8s %14s %12s %8s %8s %8s %18s %10s\n", "map", "former", "ghost", "clear_med/max",
		"uncleared", "hazard", "lost", "changed_out(ev/cells)", "value_out");
	o << b;
	for (const auto& m : s)
	{
		const std::string ghost = std::to_string(m.ghost_cells) + "/" + std::to_string(m.ghost_judged) + " " +
								  (m.ghost_judged ? num(m.ghostPct(), 1) + "%" : std::string("-"));
		const std::string clr = m.clear_frames.empty()
									? std::string("-")
									: num(m.medianClearFrames(), 1) + "/" + std::to_string(m.maxClearFrames());
		const std::string ch = std::to_string(m.changed_outside_view) + "/" + std::to_string(m.changed_outside_cells);
		std::snprintf(
			b, sizeof b, "%-14s %8ld %14s %12s %8ld %8ld %8ld %18s %10ld\n", m.name.c_str(), m.former_obstacle_cells,
			ghost.c_str(), clr.c_str(), m.not_cleared, m.hazard_cells, m.hazard_lost, ch.c_str(),
			m.value_changed_outside_view);
		o << b;
	}
	return o.str();
}

std::string sequenceToJson(const std::vector<SequenceScore>& s, const SequenceOptions& opt)
{
	std::ostringstream o;
	o << "{\n  \"options\": {\"ghost_frames\": " << opt.ghost_frames << ", \"tolerance_cells\": " << opt.tolerance_cells
	  << ", \"view_margin_cells\": " << opt.view_margin_cells << "},\n  \"maps\": [";
	for (size_t k = 0; k < s.size(); k++)
	{
		const auto& m = s[k];
		o << (k ? ",\n" : "\n") << "    {\"name\": \"" << m.name << "\", \"frames\": " << m.frames
		  << ", \"former_obstacle_cells\": " << m.former_obstacle_cells << ", \"ghost_judged\": " << m.ghost_judged
		  << ", \"ghost_cells\": " << m.ghost_cells << ", \"ghost_pct\": " << num(m.ghostPct(), 3)
		  << ", \"cleared_cells\": " << m.clear_frames.size()
		  << ", \"clear_frames_median\": " << num(m.medianClearFrames(), 1)
		  << ", \"clear_frames_max\": " << m.maxClearFrames() << ", \"not_cleared\": " << m.not_cleared
		  << ", \"hazard_cells\": " << m.hazard_cells << ", \"hazard_lost\": " << m.hazard_lost
		  << ", \"changed_outside_view\": " << m.changed_outside_view
		  << ", \"changed_outside_cells\": " << m.changed_outside_cells
		  << ", \"value_changed_outside_view\": " << m.value_changed_outside_view << ",\n     \"clear_frames\": [";
		for (size_t c = 0; c < m.clear_frames.size(); c++) o << (c ? ", " : "") << m.clear_frames[c];
		o << "],\n     \"per_frame\": [";
		for (size_t f = 0; f < m.perFrame.size(); f++)
		{
			const auto& p = m.perFrame[f];
			o << (f ? ", " : "") << "{\"frame\": " << p.frame << ", \"obstacle_cells\": " << p.obstacle_cells
			  << ", \"obstacle_occupied\": " << p.obstacle_occupied << ", \"floor_cells\": " << p.floor_cells
			  << ", \"floor_occupied\": " << p.floor_occupied << ", \"floor_free\": " << p.floor_free
			  << ", \"to_clear\": " << p.to_clear << ", \"ghost_cells\": " << p.ghost_cells
			  << ", \"hazard_out_of_view\": " << p.hazard_out_of_view << ", \"hazard_lost\": " << p.hazard_lost
			  << ", \"changed_outside_view\": " << p.changed_outside_view
			  << ", \"value_changed_outside_view\": " << p.value_changed_outside_view << "}";
		}
		o << "]}";
	}
	o << "\n  ]\n}\n";
	return o.str();
}

std::string sequenceToCsv(const std::vector<SequenceScore>& s)
{
	std::ostringstream o;
	o << "map,frame,obstacle_cells,obstacle_occupied,floor_cells,floor_occupied,floor_free,to_clear,ghost_cells,"
		 "hazard_out_of_view,hazard_lost,changed_outside_view,value_changed_outside_view\n";
	for (const auto& m : s)
		for (const auto& p : m.perFrame)
			o << m.name << "," << p.frame << "," << p.obstacle_cells << "," << p.obstacle_occupied << ","
			  << p.floor_cells << "," << p.floor_occupied << "," << p.floor_free << "," << p.to_clear << ","
			  << p.ghost_cells << "," << p.hazard_out_of_view << "," << p.hazard_lost << "," << p.changed_outside_view
			  << "," << p.value_changed_outside_view << "\n";
	return o.str();
}

}  // namespace gam::eval
