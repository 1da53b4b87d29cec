// Ground-aware mapping for MRPT -- gam-figure: the paper's Fig. 4 and Fig. 5,
// reproduced on simulated rawlogs, as labelled PNGs with the figures behind
// them (issue #12; rawlog_tools/gam-paper-figures runs it for doc/figures/).
//
// usage:
//   gam-figure --figure 4 --rawlog R.rawlog --gt R [--rawlog ... --gt ...] --out F.png [--csv F.csv]
//       one row per rawlog, its first depth frame only: point cloud | 2.5D map
//       without outlier removal | 2D map with outliers | 2D map with 3-sigma |
//       height band 0.2-1.5 m | 3-sigma + IDW | our default
//   gam-figure --figure 5 --rawlog R.rawlog [--gt R] --out F.png [--cells 600] [--csv F.csv]
//       every frame: 600 x 600 local maps around the last pose: paper mode |
//       our default | Leddar alone | height band
// The 2D columns of Fig. 4 are the paper's method (ism_model = rrt_variant =
// paper); "3-sigma + IDW" feeds the IDW cells to the ISM (idw_in_ism = 1).
// exit: 0 ok, 1 bad input or unwritable output, 2 command line.
#include <gam/common/CommandLine.h>
#include <gam/common/Version.h>
#include <mrpt/3rdparty/tclap/CmdLine.h>
#include <mrpt/config/CConfigFileMemory.h>
#include <mrpt/img/CImage.h>
#include <mrpt/img/color_maps.h>
#include <mrpt/maps/CGroundAwareOccupancyGrid.h>
#include <mrpt/maps/CHeightBandOccupancyGrid.h>
#include <mrpt/maps/CMultiMetricMap.h>
#include <mrpt/maps/CSimplePointsMap.h>
#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/obs/CObservation3DRangeScan.h>
#include <mrpt/obs/T3DPointsProjectionParams.h>
#include <mrpt/system/filesystem.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <functional>
#include <iostream>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "gam/eval/Evaluation.h"
#include "gam/mapper/Mapper.h"
#include "gam/mapper/RawlogFrames.h"

using mrpt::img::CImage;
using mrpt::img::TColor;
using mrpt::maps::CGroundAwareOccupancyGrid;
using mrpt::maps::CHeightBandOccupancyGrid;
using mrpt::maps::COccupancyGridMap2D;
using mrpt::poses::CPose3D;

namespace
{
struct Failure : std::runtime_error
{
	using std::runtime_error::runtime_error;
};

struct Frame
{
	mrpt::obs::CObservation3DRangeScan::Ptr depth;  // null for a 2D scan
	mrpt::obs::CObservation2DRangeScan::Ptr scan;
	CPose3D pose;
};

/** Every depth frame and 2D scan of a rawlog at its odometry pose, read as
 * ground-aware-mapper reads it (gam::mapper::RawlogFrameReader). */
std::vector<Frame> loadFrames(const std::string& file)
{
	if (!mrpt::system::fileExists(file)) throw Failure("cannot read rawlog " + file + ": no such file");
	std::vector<Frame> out;
	try
	{
		gam::mapper::RawlogFrameReader reader(file);
		gam::mapper::Frame fr;
		while (reader.next(fr))
		{
			if (auto d = std::dynamic_pointer_cast<mrpt::obs::CObservation3DRangeScan>(fr.obs))
				out.push_back({d, nullptr, fr.robotPose});
			else if (auto s = std::dynamic_pointer_cast<mrpt::obs::CObservation2DRangeScan>(fr.obs))
				out.push_back({nullptr, s, fr.robotPose});
		}
	}
	catch (const std::exception& e)
	{
		throw Failure("cannot read rawlog " + file + ": " + e.what());
	}
	if (std::none_of(out.begin(), out.end(), [](const Frame& f) { return bool(f.depth); }))
		throw Failure(file + " has no CObservation3DRangeScan");
	return out;
}

/** The grid's p_occ as a map_server map (scale mode), for gam::eval. */
gam::eval::RosMap toRosMap(const COccupancyGridMap2D& g, const std::string& name)
{
	gam::eval::RosMap m;
	m.yamlPath = name;
	m.mode = "scale";
	m.resolution = g.getResolution();
	m.origin_x = g.getXMin();
	m.origin_y = g.getYMin();
	m.width = int(g.getSizeX());
	m.height = int(g.getSizeY());
	m.pixels.resize(size_t(m.width) * size_t(m.height));
	for (int row = 0; row < m.height; row++)
		for (int cx = 0; cx < m.width; cx++)
		{
			const int cy = m.height - 1 - row;  // rows from the top
			const float pFree = g.getCell(cx, cy);
			m.pixels[size_t(row) * size_t(m.width) + size_t(cx)] = uint8_t(std::lround(255.0 * pFree));
		}
	return m;
}

/** A square world window [x0, x0 + side] x [y0, y0 + side], drawn at `px`
 * pixels per metre with +x to the right and +y up. */
struct View
{
	double x0, y0, side;
	int pixels;
	int col(double x) const { return int(std::floor((x - x0) / side * pixels)); }
	int row(double y) const { return pixels - 1 - int(std::floor((y - y0) / side * pixels)); }
	double x(int c) const { return x0 + (c + 0.5) * side / pixels; }
	double y(int r) const { return y0 + (pixels - 1 - r + 0.5) * side / pixels; }
};

const TColor kUnknown(190, 205, 235), kText(0, 0, 0);

/** Free white, occupied black, unknown light blue, as gam-evaluate draws them. */
void drawGrid(CImage& im, int ox, int oy, const View& v, const COccupancyGridMap2D& g)
{
	for (int r = 0; r < v.pixels; r++)
		for (int c = 0; c < v.pixels; c++)
		{
			const int cx = g.x2idx(v.x(c)), cy = g.y2idx(v.y(r));
			TColor col = kUnknown;
			if (cx >= 0 && cy >= 0 && cx < int(g.getSizeX()) && cy < int(g.getSizeY()))
			{
				const double p = 1.0 - g.getCell(cx, cy);  // p_occ
				if (std::abs(p - 0.5) > 1.0 / 255.0)
				{
					const auto lvl = uint8_t(std::clamp(std::lround(255.0 * (1.0 - p)), 0L, 255L));
					col = TColor(lvl, lvl, lvl);
				}
			}
			im.setPixel(ox + c, oy + r, col);
		}
}

TColor heightColour(double z, double zlo, double zhi)
{
	return mrpt::img::colormap(mrpt::img::cmJET, float(std::clamp((z - zlo) / (zhi - zlo), 0.0, 1.0)));
}

/** The 2.5D map of one frame: z_max per cell (jet, zlo..zhi), unobserved light blue. */
void drawElevation(CImage& im, int ox, int oy, const View& v, const gam::ElevationGrid& e, double zlo, double zhi)
{
	const gam::GridGeometry& g = e.geometry();
	for (int r = 0; r < v.pixels; r++)
		for (int c = 0; c < v.pixels; c++)
		{
			const int cx = g.ix(v.x(c)), cy = g.iy(v.y(r));
			TColor col = kUnknown;
			if (g.inside(cx, cy) && e.cell(cx, cy).count) col = heightColour(e.cell(cx, cy).z_max, zlo, zhi);
			im.setPixel(ox + c, oy + r, col);
		}
}

/** The frame's points seen from 1.2 m behind and 1.8 m above the robot,
 * looking forward and 35 deg down; coloured by height; nearest point wins. */
void drawPointCloud(
	CImage& im, int ox, int oy, int w, int h, const mrpt::obs::CObservation3DRangeScan& obs, double zlo, double zhi)
{
	mrpt::maps::CSimplePointsMap pts;
	mrpt::obs::T3DPointsProjectionParams pp;
	pp.takeIntoAccountSensorPoseOnRobot = true;  // robot frame: x forward, z up
	auto copy = obs;                             // unprojectInto() writes into its source
	copy.unprojectInto(pts, pp);
	const double pitch = 35.0 * M_PI / 180.0, cxp = w / 2.0, cyp = h / 2.0, f = w / 1.1;
	const double camX = -1.2, camZ = 1.8;
	std::vector<float> depth(size_t(w) * size_t(h), std::numeric_limits<float>::infinity());
	im.filledRectangle(ox, oy, ox + w - 1, oy + h - 1, TColor(255, 255, 255));
	const auto& xs = pts.getPointsBufferRef_x();
	const auto& ys = pts.getPointsBufferRef_y();
	const auto& zs = pts.getPointsBufferRef_z();
	for (size_t i = 0; i < xs.size(); i++)
	{
		const double dx = xs[i] - camX, dy = ys[i], dz = zs[i] - camZ;
		const double fwd = dx * std::cos(pitch) - dz * std::sin(pitch);
		const double up = dx * std::sin(pitch) + dz * std::cos(pitch);
		const double right = -dy;
		if (fwd < 0.2) continue;
		const int u = int(cxp + f * right / fwd), vv = int(cyp - f * up / fwd);
		if (u < 0 || vv < 0 || u >= w || vv >= h) continue;
		float& d = depth[size_t(vv) * size_t(w) + size_t(u)];
		if (fwd >= d) continue;
		d = float(fwd);
		im.setPixel(ox + u, oy + vv, heightColour(zs[i], zlo, zhi));
	}
}

/** The ground-aware grid and the height band of the mapper's .ini (first of
 * each class), as every run of ground-aware-mapper and gam-benchmark builds
 * them; the figure's variants are copies with a few options changed. */
struct ConfiguredMaps
{
	CGroundAwareOccupancyGrid groundAware;
	CHeightBandOccupancyGrid heightBand;
};

ConfiguredMaps loadConfig(const std::string& path)
{
	std::ifstream f(path);
	if (!f) throw Failure("cannot read " + path);
	const std::string text((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
	mrpt::config::CConfigFileMemory ini(text);
	mrpt::maps::CMultiMetricMap mm;
	gam::mapper::createMaps(ini, "map", mm);
	const auto ga = mm.mapByClass<CGroundAwareOccupancyGrid>();
	const auto hb = mm.mapByClass<CHeightBandOccupancyGrid>();
	if (!ga || !hb) throw Failure(path + " must define a groundAwareGrid and a heightBandGrid");
	return {*ga, *hb};
}

void applyOptions(
	CGroundAwareOccupancyGrid& g, const std::function<void(CGroundAwareOccupancyGrid::TGroundAwareOptions&)>& edit)
{
	auto o = g.groundOptions();
	edit(o);
	g.setGroundOptions(o);
}

void paperMode(CGroundAwareOccupancyGrid::TGroundAwareOptions& o)
{
	o.pipeline.ism.model = gam::MethodVariant::Paper;
	o.pipeline.rrt.variant = gam::MethodVariant::Paper;
	o.scan_keeps_3d_obstacles = CGroundAwareOccupancyGrid::TGroundAwareOptions::ScanRule::BeamModel;
}

/** One line per map: occupied / free cells in the view; with a ground truth
 * also the detections and floor figures of gam-evaluate. */
struct Row
{
	std::string scene, column, figures;
};

std::string describe(
	const COccupancyGridMap2D& g, const View& v, const gam::eval::GroundTruth* gt, const std::string& name)
{
	long occ = 0, fr = 0;
	for (int cy = 0; cy < int(g.getSizeY()); cy++)
		for (int cx = 0; cx < int(g.getSizeX()); cx++)
		{
			const double x = g.idx2x(cx), y = g.idx2y(cy);
			if (x < v.x0 || y < v.y0 || x > v.x0 + v.side || y > v.y0 + v.side) continue;
			const double p = 1.0 - g.getCell(cx, cy);
			occ += p > 0.5 + 1.0 / 255.0;
			fr += p < 0.5 - 1.0 / 255.0;
		}
	char b[512];
	std::snprintf(b, sizeof b, "occupied %ld, free %ld cells", occ, fr);
	std::string s = b;
	if (gt)
	{
		const gam::eval::MapScore sc = gam::eval::evaluate(*gt, toRosMap(g, name));
		const auto& m = sc.main;
		for (const auto& [cat, cs] : m.categories)
		{
			std::snprintf(b, sizeof b, "; %s %d/%d", cat.c_str(), cs.detected, cs.objects);
			s += b;
		}
		std::snprintf(
			b, sizeof b, "; floor false-obstacle %.1f %%, floor free %.1f %%", m.floor.pct(m.floor.occupied),
			m.floor.pct(m.floor.free));
		s += b;
	}
	return s;
}

int panelLabelHeight = 16, gap = 8;

int figure4(
	const ConfiguredMaps& cfg, const std::vector<std::string>& rawlogs, const std::vector<std::string>& gts,
	const std::string& out, std::vector<Row>& rows)
{
	const std::vector<std::string> titles = {"point cloud",   "2.5D, no outlier removal", "2D, with outliers",
											 "2D, 3-sigma",   "height band 0.2-1.5 m",    "2D, 3-sigma + IDW",
											 "ours (default)"};
	const int panel = 300, cols = int(titles.size());
	const int rowH = panelLabelHeight + panel + gap + 14;
	CImage im(gap + cols * (panel + gap), 24 + int(rawlogs.size()) * rowH, mrpt::img::CH_RGB);
	im.filledRectangle(0, 0, int(im.getWidth()) - 1, int(im.getHeight()) - 1, TColor(255, 255, 255));
	im.textOut(
		gap, 4,
		"Fig. 4 reproduced (first depth frame of each scene; 2D columns: the paper's method; 6 m x 6 m ahead; "
		"white free, black occupied, blue unknown)",
		kText);
	for (size_t s = 0; s < rawlogs.size(); s++)
	{
		const std::vector<Frame> frames = loadFrames(rawlogs[s]);
		const Frame& f = *std::find_if(frames.begin(), frames.end(), [](const Frame& x) { return bool(x.depth); });
		std::unique_ptr<gam::eval::GroundTruth> gt;
		if (s < gts.size() && !gts[s].empty())
			gt = std::make_unique<gam::eval::GroundTruth>(gam::eval::loadGroundTruth(gts[s]));
		const View v{f.pose.x() - 0.5, f.pose.y() - 3.0, 6.0, panel};

		CGroundAwareOccupancyGrid withOutliers = cfg.groundAware, sigma = cfg.groundAware, idw = cfg.groundAware,
								  ours = cfg.groundAware;
		applyOptions(withOutliers, [](auto& o) {
			paperMode(o);
			o.pipeline.outliers.enabled = false;
			o.pipeline.idw.radius_cells = 0;
		});
		applyOptions(sigma, [](auto& o) {
			paperMode(o);
			o.pipeline.idw.radius_cells = 0;
		});
		applyOptions(idw, [](auto& o) {
			paperMode(o);
			o.pipeline.idw.radius_cells = 1;
			o.pipeline.idw_in_ism = true;
		});
		CHeightBandOccupancyGrid band = cfg.heightBand;
		for (COccupancyGridMap2D* m :
			 std::initializer_list<COccupancyGridMap2D*>{&withOutliers, &sigma, &idw, &ours, &band})
			m->insertObservation(*f.depth, f.pose);

		const std::string scene = mrpt::system::extractFileName(rawlogs[s]);
		const int y0 = 24 + int(s) * rowH;
		im.textOut(gap, y0, scene, TColor(120, 0, 0));
		const int py = y0 + 14 + panelLabelHeight;
		for (int c = 0; c < cols; c++) im.textOut(gap + c * (panel + gap), y0 + 14, titles[size_t(c)], kText);
		auto px = [&](int c) { return gap + c * (panel + gap); };
		const double zlo = f.pose.z() - 0.3, zhi = f.pose.z() + 1.2;
		drawPointCloud(im, px(0), py, panel, panel, *f.depth, zlo, zhi);
		drawElevation(im, px(1), py, v, withOutliers.lastFrameElevation(), zlo, zhi);
		const COccupancyGridMap2D* grids[] = {&withOutliers, &sigma, &band, &idw, &ours};
		for (int c = 2; c < cols; c++) drawGrid(im, px(c), py, v, *grids[c - 2]);

		const auto& e = withOutliers.lastFrameElevation();
		rows.push_back({scene, titles[1], std::to_string(e.observedCount()) + " observed cells"});
		for (int c = 2; c < cols; c++)
			rows.push_back({scene, titles[size_t(c)], describe(*grids[c - 2], v, gt.get(), titles[size_t(c)])});
		const auto& fr = idw.lastFrame();
		rows.push_back(
			{scene, "IDW",
			 std::to_string(idw.lastFrameElevation().observedCount() - sigma.lastFrameElevation().observedCount()) +
				 " cells added by IDW (ISM voxels " + std::to_string(fr.ism.ground + fr.ism.obstacle + fr.ism.drop) +
				 ")"});
	}
	if (!im.saveToFile(out)) throw Failure("cannot write " + out);
	return 0;
}

int figure5(
	const ConfiguredMaps& cfg, const std::string& rawlog, const std::string& gtPrefix, const std::string& out,
	int cells, std::vector<Row>& rows)
{
	const std::vector<Frame> frames = loadFrames(rawlog);
	std::unique_ptr<gam::eval::GroundTruth> gt;
	if (!gtPrefix.empty()) gt = std::make_unique<gam::eval::GroundTruth>(gam::eval::loadGroundTruth(gtPrefix));
	CGroundAwareOccupancyGrid paper = cfg.groundAware, ours = cfg.groundAware, leddar = cfg.groundAware;
	applyOptions(paper, paperMode);
	applyOptions(leddar, [](auto& o) {
		o.scan_keeps_3d_obstacles = CGroundAwareOccupancyGrid::TGroundAwareOptions::ScanRule::BeamModel;
	});  // MRPT's beam model
	CHeightBandOccupancyGrid band = cfg.heightBand;
	std::vector<std::pair<double, double>> path;
	size_t depthFrames = 0, scans = 0;
	for (size_t i = 0; i < frames.size(); i++)
	{
		const Frame& f = frames[i];
		if (f.depth)
		{
			paper.insertObservation(*f.depth, f.pose);
			ours.insertObservation(*f.depth, f.pose);
			band.insertObservation(*f.depth, f.pose);
			depthFrames++;
			path.emplace_back(f.pose.x(), f.pose.y());
		}
		else
		{
			// Every map gets every observation, as in the mapper.
			paper.insertObservation(*f.scan, f.pose);
			ours.insertObservation(*f.scan, f.pose);
			band.insertObservation(*f.scan, f.pose);
			leddar.insertObservation(*f.scan, f.pose);
			scans++;
		}
		if ((i + 1) % 50 == 0) std::cerr << "gam-figure: " << i + 1 << "/" << frames.size() << " observations\n";
	}
	const CPose3D last = frames.back().pose;
	const double side = cells * ours.getResolution();
	const int panel = 600;
	const View v{last.x() - side / 2, last.y() - side / 2, side, panel};
	const std::vector<std::string> titles = {
		"paper mode", "ours (default)", "Leddar alone (beam model)", "height band 0.2-1.5 m"};
	const COccupancyGridMap2D* grids[] = {&paper, &ours, &leddar, &band};
	const int cols = 2, rowsN = 2;
	CImage im(gap + cols * (panel + gap), 24 + rowsN * (panelLabelHeight + panel + gap), mrpt::img::CH_RGB);
	im.filledRectangle(0, 0, int(im.getWidth()) - 1, int(im.getHeight()) - 1, TColor(255, 255, 255));
	char head[256];
	std::snprintf(
		head, sizeof head,
		"Fig. 5 reproduced: %s, %zu depth frames + %zu Leddar scans; %d x %d local maps (%.0f m) at the last pose; "
		"red: path",
		mrpt::system::extractFileName(rawlog).c_str(), depthFrames, scans, cells, cells, side);
	im.textOut(gap, 4, head, kText);
	for (int k = 0; k < 4; k++)
	{
		const int ox = gap + (k % cols) * (panel + gap), oy = 24 + (k / cols) * (panelLabelHeight + panel + gap);
		im.textOut(ox, oy, titles[size_t(k)], kText);
		drawGrid(im, ox, oy + panelLabelHeight, v, *grids[k]);
		for (size_t i = 1; i < path.size(); i++)
			im.line(
				ox + v.col(path[i - 1].first), oy + panelLabelHeight + v.row(path[i - 1].second),
				ox + v.col(path[i].first), oy + panelLabelHeight + v.row(path[i].second), TColor(220, 0, 0), 2);
		rows.push_back(
			{mrpt::system::extractFileName(rawlog), titles[size_t(k)],
			 describe(*grids[k], v, gt.get(), titles[size_t(k)])});
	}
	if (!im.saveToFile(out)) throw Failure("cannot write " + out);
	return 0;
}
}  // namespace

int main(int argc, char** argv)
{
	try
	{
		TCLAP::CmdLine cmd("gam-figure: the paper's Fig. 4 and Fig. 5, reproduced (issue #12)", ' ', GAM_VERSION);
		TCLAP::ValueArg<int> argFig("", "figure", "4 or 5", true, 4, "N", cmd);
		TCLAP::MultiArg<std::string> argRawlog(
			"", "rawlog", "simulated rawlog (Fig. 4: one per row)", true, "FILE", cmd);
		TCLAP::MultiArg<std::string> argGt(
			"", "gt", "ground-truth prefix of gam-simulate, one per rawlog", false, "PREFIX", cmd);
		TCLAP::ValueArg<std::string> argOut("", "out", "PNG to write", true, "", "FILE", cmd);
		TCLAP::ValueArg<std::string> argCsv("", "csv", "also write the figures per panel", false, "", "FILE", cmd);
		TCLAP::ValueArg<std::string> argConfig(
			"", "config", "the mapper's .ini (its groundAwareGrid and heightBandGrid)", false,
			"config/ground-aware-mapper.ini", "FILE", cmd);
		TCLAP::ValueArg<int> argCells("", "cells", "Fig. 5: side of the local map in cells", false, 600, "N", cmd);
		if (const int rc = gam::parseCommandLine(cmd, argc, argv, "gam-figure"); rc >= 0) return rc;
		std::vector<Row> rows;
		const ConfiguredMaps cfg = loadConfig(argConfig.getValue());
		if (argFig.getValue() == 4)
			figure4(cfg, argRawlog.getValue(), argGt.getValue(), argOut.getValue(), rows);
		else if (argFig.getValue() == 5)
		{
			if (argRawlog.getValue().size() != 1) throw Failure("--figure 5 takes one --rawlog");
			if (argCells.getValue() < 10 || argCells.getValue() > 10000)
				throw Failure("--cells must be in [10, 10000]");
			figure5(
				cfg, argRawlog.getValue()[0], argGt.getValue().empty() ? "" : argGt.getValue()[0], argOut.getValue(),
				argCells.getValue(), rows);
		}
		else
			throw Failure("--figure must be 4 or 5");
		std::ofstream csv;
		if (!argCsv.getValue().empty())
		{
			csv.open(argCsv.getValue());
			if (!csv) throw Failure("cannot write " + argCsv.getValue());
			csv << "scene,panel,figures\n";
		}
		for (const Row& r : rows)
		{
			std::cout << r.scene << " | " << r.column << " | " << r.figures << "\n";
			if (csv.is_open()) csv << r.scene << ",\"" << r.column << "\",\"" << r.figures << "\"\n";
		}
		std::cout << "wrote " << argOut.getValue() << "\n";
		return 0;
	}
	catch (const std::exception& e)
	{
		std::cerr << "gam-figure: error: " << e.what() << "\n";
		return 1;
	}
}
