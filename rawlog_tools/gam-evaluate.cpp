// Ground-aware mapping for MRPT -- gam-evaluate: scores 2D occupancy maps (ROS
// map_server yaml + pgm, as ground-aware-mapper writes them) against the ground
// truth of gam-simulate. See README "Map evaluator" and libs/ground_eval.
//
// usage: gam-evaluate --map DIR/ground_aware.yaml [--map DIR/octomap.yaml ...]
//                     --gt PREFIX [--json FILE] [--csv FILE] [--png FILE]
//                     [--tolerance-cells 1] [--min-hits 1] [--title TEXT]
// exit: 0 ok, 1 missing or bad input / unwritable output, 2 command line.
#include <gam/common/CommandLine.h>
#include <gam/common/Version.h>
#include <mrpt/3rdparty/tclap/CmdLine.h>
#include <mrpt/img/CImage.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iostream>

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

/** GT panel + one panel per map, all on the GT grid (+y up), cells scaled up. */
void writePng(
	const std::string& path, const std::string& title, const GroundTruth& gt, const std::vector<RosMap>& maps,
	const std::vector<MapScore>& scores)
{
	using mrpt::img::TColor;
	const int k = int(std::clamp(std::lround(480.0 / std::max(1, std::max(gt.nx, gt.ny))), 1L, 8L));
	const int pw = gt.nx * k, ph = gt.ny * k, gap = 8, top = 20, label = 16;
	const int n = 1 + int(maps.size());
	const int cols = (n * (pw + gap) > 1600 && n > 2) ? (n + 1) / 2 : n, rows = (n + cols - 1) / cols;
	mrpt::img::CImage im(cols * pw + (cols + 1) * gap, top + rows * (ph + label + gap), mrpt::img::CH_RGB);
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
	for (size_t m = 0; m < maps.size(); m++)
	{
		const Resampled r = resample(gt, maps[m]);
		const auto st = classify(r, scores[m].main.occ, scores[m].main.free);
		panel(int(m) + 1, scores[m].name, [&](size_t i) {
			if (st[i] == CellState::Unknown) return unknown;
			const double p = st[i] == CellState::Occupied ? r.pMax[i] : r.pMin[i];
			const auto g = uint8_t(std::clamp(std::lround(255.0 * (1.0 - p)), 0L, 255L));
			return TColor(g, g, g);
		});
	}
	if (!title.empty()) im.textOut(gap, 3, title, TColor(60, 60, 60));
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
	}
	catch (const std::exception& e)
	{
		std::cerr << "gam-evaluate: error: " << e.what() << "\n";
		return 1;
	}
	return 0;
}
