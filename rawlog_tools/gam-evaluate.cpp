// Ground-aware mapping for MRPT -- gam-evaluate: scores 2D occupancy maps (ROS
// map_server yaml + pgm, as ground-aware-mapper writes them) against the ground
// truth of gam-simulate. See README "Map evaluator" and libs/ground_eval.
//
// usage: gam-evaluate --map DIR/ground_aware.yaml [--map DIR/octomap.yaml ...]
//                     --gt PREFIX [--json FILE] [--csv FILE] [--png FILE]
//                     [--tolerance-cells 1] [--min-hits 1] [--title TEXT]
//                     [--sequence [--ghost-frames 10] [--view-margin-cells 1]
//                      [--sequence-json FILE] [--sequence-csv FILE]]
// exit: 0 ok, 1 missing or bad input / unwritable output, 2 command line.
#include <gam/common/CommandLine.h>
#include <gam/common/Version.h>
#include <mrpt/3rdparty/tclap/CmdLine.h>
#include <mrpt/img/CImage.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <optional>

#include "gam/eval/Evaluation.h"

using namespace gam::eval;

namespace
{
void writeText(const std::string& path, const std::string& text)
{
	std::ofstream f(path);
	f << text;
	f.flush();
	if (!f) throw Error("cannot write " + path);
}

/** The robot's path of gam-simulate (PREFIX_gt_path.csv: frame,timestamp,x,y,...);
 * empty if there is none. */
std::vector<std::pair<double, double>> loadPath(const std::string& prefix)
{
	std::vector<std::pair<double, double>> path;
	std::ifstream f(prefix + "_gt_path.csv");
	std::string line;
	if (!std::getline(f, line)) return path;
	while (std::getline(f, line))
	{
		double fr, ts, x, y;
		if (std::sscanf(line.c_str(), "%lf,%lf,%lf,%lf", &fr, &ts, &x, &y) == 4) path.emplace_back(x, y);
	}
	return path;
}

/** The missing-floor layer written next to a ground-aware map
 * (DIR/<label>_missing_floor.yaml beside DIR/<label>.yaml), if there is one. */
std::optional<RosMap> missingFloorOf(const RosMap& map)
{
	namespace fs = std::filesystem;
	const fs::path y(map.yamlPath);
	const fs::path layer = y.parent_path() / (y.stem().string() + "_missing_floor.yaml");
	std::error_code ec;
	if (!fs::exists(layer, ec)) return std::nullopt;
	return loadRosMap(layer.string());
}

/** GT panel + one panel per map, all on the GT grid (+y up), cells scaled up;
 * the robot's path on every panel, a 1 m scale bar and a legend. A map with a
 * missing-floor layer beside it shows its missing-floor cells in orange. */
void writePng(
	const std::string& path, const std::string& title, const GroundTruth& gt, const std::vector<RosMap>& maps,
	const std::vector<MapScore>& scores)
{
	using mrpt::img::TColor;
	const int k = int(std::clamp(std::lround(480.0 / std::max(1, std::max(gt.nx, gt.ny))), 1L, 8L));
	const int pw = gt.nx * k, ph = gt.ny * k, gap = 8, top = 20, label = 16;
	const int n = 1 + int(maps.size());
	const int cols = (n * (pw + gap) > 1600 && n > 2) ? (n + 1) / 2 : n, rows = (n + cols - 1) / cols;
	const int legendH = 22;
	mrpt::img::CImage im(cols * pw + (cols + 1) * gap, top + rows * (ph + label + gap) + legendH, mrpt::img::CH_RGB);
	const auto robotPath = loadPath(gt.prefix);
	const double gxmin = gt.x[0] - 0.5 * gt.resolution, gymin = gt.y[0] - 0.5 * gt.resolution;
	im.filledRectangle(0, 0, int(im.getWidth()) - 1, int(im.getHeight()) - 1, TColor(255, 255, 255));
	const TColor unknown(190, 205, 235);
	auto panel = [&](int p, const std::string& name, auto colourOf) {
		const int x0 = gap + (p % cols) * (pw + gap), yb = top + (p / cols) * (label + ph + gap);
		im.textOut(x0, yb, name, TColor(0, 0, 0));
		const int y0 = yb + label;
		for (int iy = 0; iy < gt.ny; iy++)
			for (int ix = 0; ix < gt.nx; ix++)
			{
				const TColor c = colourOf(gt.idx(ix, iy));
				const int px = x0 + ix * k, py = y0 + (gt.ny - 1 - iy) * k;
				im.filledRectangle(px, py, px + k - 1, py + k - 1, c);
			}
		// The robot's path (red) and a 1 m scale bar in the lower left corner.
		auto toPx = [&](double x, double y) {
			return std::pair<int, int>(
				x0 + int(std::lround((x - gxmin) / gt.resolution * k)),
				y0 + int(std::lround((gt.ny - (y - gymin) / gt.resolution) * k)));
		};
		for (size_t i = 1; i < robotPath.size(); i++)
		{
			const auto a = toPx(robotPath[i - 1].first, robotPath[i - 1].second);
			const auto b = toPx(robotPath[i].first, robotPath[i].second);
			im.line(a.first, a.second, b.first, b.second, TColor(220, 0, 0), 2);
		}
		const int bar = int(std::lround(1.0 / gt.resolution * k)), bx = x0 + 6, by = y0 + ph - 8;
		im.filledRectangle(bx, by, bx + bar, by + 3, TColor(0, 90, 200));
		im.textOut(bx, by - 12, "1 m", TColor(0, 90, 200));
	};
	panel(0, "ground truth", [&](size_t i) {
		switch (gt.label[i])
		{
			case Label::Free: return TColor(255, 255, 255);
			case Label::Obstacle: return TColor(0, 0, 0);
			case Label::Drop: return TColor(200, 30, 30);
			default: return unknown;
		}
	});
	const TColor missingColour(255, 140, 0);
	for (size_t m = 0; m < maps.size(); m++)
	{
		const Resampled r = resample(gt, maps[m]);
		const auto st = classify(r, scores[m].main.occ, scores[m].main.free);
		std::vector<bool> missing(st.size(), false);
		if (const auto layer = missingFloorOf(maps[m]))
		{
			const Resampled rl = resample(gt, *layer);
			for (size_t i = 0; i < missing.size(); i++) missing[i] = rl.pMax[i] > 0.5;
		}
		panel(int(m) + 1, scores[m].name, [&](size_t i) {
			if (missing[i]) return missingColour;
			if (st[i] == CellState::Unknown) return unknown;
			const double p = st[i] == CellState::Occupied ? r.pMax[i] : r.pMin[i];
			const auto g = uint8_t(std::clamp(std::lround(255.0 * (1.0 - p)), 0L, 255L));
			return TColor(g, g, g);
		});
	}
	if (!title.empty()) im.textOut(gap, 3, title, TColor(60, 60, 60));
	// Legend.
	{
		int x = gap;
		const int y = int(im.getHeight()) - legendH + 4;
		auto swatch = [&](const TColor& c, const std::string& text) {
			im.filledRectangle(x, y, x + 12, y + 12, c);
			im.rectangle(x, y, x + 12, y + 12, TColor(120, 120, 120));
			im.textOut(x + 16, y + 2, text, TColor(0, 0, 0));
			x += 16 + 9 * int(text.size()) + 18;
		};
		swatch(TColor(255, 255, 255), "free");
		swatch(TColor(0, 0, 0), "occupied");
		swatch(unknown, "unknown");
		swatch(missingColour, "missing floor");
		swatch(TColor(200, 30, 30), "GT drop / hole");
		im.line(x, y + 6, x + 14, y + 6, TColor(220, 0, 0), 2);
		im.textOut(x + 18, y + 2, "robot path", TColor(0, 0, 0));
	}
	if (!im.saveToFile(path)) throw Error("cannot write " + path);
}
}  // namespace

int main(int argc, char** argv)
{
	TCLAP::CmdLine cmd(
		"gam-evaluate: scores ROS map_server maps against gam-simulate ground truth "
		"(per-object detection by category, floor false obstacles, floor free)",
		' ', GAM_VERSION);
	TCLAP::MultiArg<std::string> argMap(
		"m", "map", "map yaml (ROS map_server); repeat for several maps", true, "YAML", cmd);
	TCLAP::ValueArg<std::string> argGt(
		"g", "gt", "ground-truth prefix (PREFIX_gt.yaml, PREFIX_gt_labels.csv, PREFIX_gt_objects.csv)", true, "",
		"PREFIX", cmd);
	TCLAP::ValueArg<std::string> argJson("j", "json", "write every number as JSON", false, "", "FILE", cmd);
	TCLAP::ValueArg<std::string> argCsv(
		"", "csv", "write a flat CSV (per object and cell class) for aggregation", false, "", "FILE", cmd);
	TCLAP::ValueArg<std::string> argPng(
		"", "png", "write a PNG: ground truth and the maps side by side on the GT grid", false, "", "FILE", cmd);
	TCLAP::ValueArg<std::string> argTitle("", "title", "caption of the PNG", false, "", "TEXT", cmd);
	TCLAP::ValueArg<int> argTol(
		"", "tolerance-cells",
		"floor cells this close (cells, Chebyshev) to a GT obstacle/drop are not scored (default 1)", false, 1, "N",
		cmd);
	TCLAP::ValueArg<int> argHits(
		"", "min-hits", "occupied cells an object needs to be detected (default 1)", false, 1, "N", cmd);
	TCLAP::SwitchArg argSequence(
		"", "sequence",
		"also score each map after every frame: DIR/snapshots/ of each --map DIR/LABEL.yaml (ground-aware-mapper "
		"--snapshot-every) against PREFIX_gt_frames.csv (ghost cells, time to clear, hazards out of view, changes "
		"outside the view, per-frame scores)",
		cmd);
	TCLAP::ValueArg<int> argGhost(
		"", "ghost-frames",
		"--sequence: a cell still occupied this many frames after seen free is a ghost (default 10)", false, 10, "N",
		cmd);
	TCLAP::ValueArg<int> argMargin(
		"", "view-margin-cells", "--sequence: cells this close to a frame's footprint count as in view (default 1)",
		false, 1, "N", cmd);
	TCLAP::ValueArg<std::string> argSeqJson(
		"", "sequence-json", "--sequence: write its numbers (per frame too) as JSON", false, "", "FILE", cmd);
	TCLAP::ValueArg<std::string> argSeqCsv(
		"", "sequence-csv", "--sequence: write the per-frame scores as CSV", false, "", "FILE", cmd);
	TCLAP::SwitchArg argQuiet("q", "quiet", "no table on stdout", cmd);
	if (const int rc = gam::parseCommandLine(cmd, argc, argv, "gam-evaluate"); rc >= 0) return rc;
	Options opt;
	opt.tolerance_cells = argTol.getValue();
	opt.min_hits = argHits.getValue();
	if (opt.tolerance_cells < 0 || opt.tolerance_cells > 20 || opt.min_hits < 1)
	{
		std::cerr << "gam-evaluate: error: --tolerance-cells must be in [0, 20] and --min-hits >= 1\n";
		return 2;
	}
	SequenceOptions seqOpt;
	seqOpt.ghost_frames = argGhost.getValue();
	seqOpt.view_margin_cells = argMargin.getValue();
	seqOpt.tolerance_cells = opt.tolerance_cells;
	if (seqOpt.ghost_frames < 0 || seqOpt.view_margin_cells < 0 || seqOpt.view_margin_cells > 20)
	{
		std::cerr << "gam-evaluate: error: --ghost-frames must be >= 0 and --view-margin-cells in [0, 20]\n";
		return 2;
	}
	if (!argSequence.getValue() && (!argSeqJson.getValue().empty() || !argSeqCsv.getValue().empty()))
	{
		std::cerr << "gam-evaluate: error: --sequence-json and --sequence-csv need --sequence\n";
		return 2;
	}
	try
	{
		const GroundTruth gt = loadGroundTruth(argGt.getValue());
		std::vector<RosMap> maps;
		std::vector<MapScore> scores;
		for (const auto& y : argMap.getValue())
		{
			maps.push_back(loadRosMap(y));
			scores.push_back(evaluate(gt, maps.back(), opt));
		}
		// two maps with the same file name (e.g. two runs' ground_aware.yaml): name them
		// by their folder too
		std::vector<bool> dup(scores.size(), false);
		for (size_t i = 0; i < scores.size(); i++)
			for (size_t j = 0; j < scores.size(); j++) dup[i] = dup[i] || (i != j && scores[i].name == scores[j].name);
		for (size_t i = 0; i < scores.size(); i++)
		{
			const std::string parent = std::filesystem::path(scores[i].yamlPath).parent_path().filename().string();
			if (dup[i] && !parent.empty()) scores[i].name = parent + "/" + scores[i].name;
		}
		if (!argQuiet.getValue()) std::cout << formatTable(gt, scores, opt);
		if (!argJson.getValue().empty()) writeText(argJson.getValue(), toJson(gt, scores, opt));
		if (!argCsv.getValue().empty()) writeText(argCsv.getValue(), toCsv(scores));
		if (!argPng.getValue().empty()) writePng(argPng.getValue(), argTitle.getValue(), gt, maps, scores);
		if (argSequence.getValue())
		{
			// Issue #14: every map after every frame, from its run's snapshots.
			namespace fs = std::filesystem;
			const SequenceTruth seq = loadSequenceTruth(argGt.getValue(), gt);
			std::vector<SequenceScore> seqScores;
			for (size_t m = 0; m < maps.size(); m++)
			{
				const fs::path y(maps[m].yamlPath);
				const fs::path dir = y.parent_path().empty() ? fs::path(".") : y.parent_path();
				const std::vector<std::string> snaps = snapshotsPerFrame(seq, loadSnapshotIndex(dir.string()));
				SequenceScore ss = evaluateSequence(
					gt, seq,
					[&](int f) { return loadRosMap((dir / "snapshots" / snaps[size_t(f)] / y.filename()).string()); },
					seqOpt);
				ss.name = scores[m].name;
				seqScores.push_back(std::move(ss));
			}
			if (!argQuiet.getValue()) std::cout << formatSequenceTable(seqScores, seqOpt);
			if (!argSeqJson.getValue().empty()) writeText(argSeqJson.getValue(), sequenceToJson(seqScores, seqOpt));
			if (!argSeqCsv.getValue().empty()) writeText(argSeqCsv.getValue(), sequenceToCsv(seqScores));
		}
	}
	catch (const std::exception& e)
	{
		std::cerr << "gam-evaluate: error: " << e.what() << "\n";
		return 1;
	}
	return 0;
}
