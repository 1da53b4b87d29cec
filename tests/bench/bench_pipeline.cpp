// Per-stage and whole-pipeline timings of the ground-aware grid, and the two
// comparison maps on the same frames, with Google Benchmark (Release build).
//
//   gam-bench [--frames=N] [--decimation=N] [--runs=R] [--full-octomap=M] [--no-summary] FILE.rawlog
//             [FILE.rawlog ...] [benchmark flags]
//
// Each rawlog's 3D frames (up to N, default 20) are loaded once; every case
// cycles through them. After the cases, a summary prints median and p95 ms
// per frame of the whole pipeline and of height_band / octomap on the same
// frames, and the ratios; then the ground-aware grid's stages (median / p95);
// where height_band's time goes (MRPT's convertTo2DScan, the scan's insertion)
// next to the same band as a plain loop; with --full-octomap=M, also the
// octomap fed every pixel (first M frames). --runs=R: the summary's maps are
// run R times over the same frames (one after the other, each time in the same
// order) and every figure printed is the median of the R runs' figures (a
// ratio too: each run's ratio is within one run); the machine's noise only
// adds time, and a shared machine's minutes differ. --no-summary: the cases
// only (a profile of the default alone, e.g. under callgrind; before/after
// stage timings).
#include <benchmark/benchmark.h>
#include <gam/core/CameraNoise.h>
#include <gam/maps/ObservationAdapters.h>
#include <mrpt/maps/CGroundAwareOccupancyGrid.h>

#include <mrpt/maps/CHeightBandOccupancyGrid.h>
#include <mrpt/maps/COctoMapGrid2D.h>
#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/obs/CObservation3DRangeScan.h>
#include <mrpt/obs/CObservationOdometry.h>
#include <mrpt/obs/CRawlog.h>
#include <mrpt/system/filesystem.h>
#include "gam/core/CameraNoise.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <functional>
#include <iostream>
#include <limits>
#include <memory>
#include <string>
#include <vector>

using namespace mrpt::maps;
using namespace mrpt::obs;
using mrpt::poses::CPose3D;

namespace
{
struct Frame
{
	CObservation3DRangeScan::Ptr depth;
	CObservation2DRangeScan::Ptr scan;  // may be null
	CPose3D pose;
};
struct Dataset
{
	std::string name;
	std::vector<Frame> frames;
};

Dataset load(const std::string& file, size_t maxFrames)
{
	Dataset d;
	d.name = mrpt::system::extractFileName(file);
	CRawlog rl;
	if (!rl.loadFromRawLogFile(file)) throw std::runtime_error("cannot read " + file);
	CPose3D pose;
	CObservation2DRangeScan::Ptr lastScan;
	for (size_t i = 0; i < rl.size() && d.frames.size() < maxFrames; i++)
	{
		if (rl.getType(i) != CRawlog::etObservation) continue;
		auto o = rl.getAsObservation(i);
		if (auto od = std::dynamic_pointer_cast<CObservationOdometry>(o)) pose = CPose3D(od->odometry);
		if (auto s2 = std::dynamic_pointer_cast<CObservation2DRangeScan>(o)) lastScan = s2;
		if (auto s3 = std::dynamic_pointer_cast<CObservation3DRangeScan>(o))
		{
			s3->load();
			s3->hasPoints3D = false;  // time the range-image path
			d.frames.push_back({s3, lastScan, pose});
		}
	}
	// Attach the Leddar scan that follows a depth frame, if it came after it.
	for (size_t i = 0; i + 1 < d.frames.size(); i++)
		if (!d.frames[i].scan) d.frames[i].scan = d.frames[i + 1].scan;
	if (d.frames.empty()) throw std::runtime_error(file + " has no CObservation3DRangeScan");
	return d;
}

std::vector<Dataset> g_data;

// --- stage cases -------------------------------------------------------------
// Each stage as it runs inside the real pipeline (gam::GroundAwarePipeline, the
// object CGroundAwareOccupancyGrid runs): every iteration processes the next
// frame and reports that stage's own timer (manual time).
void BM_Stage(benchmark::State& st, const Dataset* d, double gam::StageTimes::*stage, bool paperMode)
{
	const CGroundAwareOccupancyGrid grid;  // its default options and cell lattice
	gam::PipelineParams params = grid.groundOptions().pipeline;
	if (paperMode)  // ism_model = rrt_variant = paper
	{
		params.ism.model = gam::MethodVariant::Paper;
		params.rrt.variant = gam::MethodVariant::Paper;
	}
	gam::GroundAwarePipeline pipeline(params);
	const gam::GridLattice lattice{grid.getXMin(), grid.getYMin(), grid.getResolution()};
	size_t i = 0, samples = 0, ok = 0, n = 0;
	for (auto _ : st)
	{
		const Frame& f = d->frames[i++ % d->frames.size()];
		gam::SensorFrame frame;
		gam::maps::toSensorFrame(*f.depth, f.pose, frame);
		const gam::FrameResult& r =
			pipeline.process(frame, Eigen::Vector3d(f.pose.x(), f.pose.y(), f.pose.z()), lattice);
		st.SetIterationTime(r.ms.*stage / 1000.0);
		samples += r.samples;
		ok += r.detection.ok();
		n++;
	}
	if (stage == &gam::StageTimes::projection) st.counters["samples/frame"] = n ? double(samples) / double(n) : 0;
	if (stage == &gam::StageTimes::ground) st.counters["ground_found_%"] = n ? 100.0 * double(ok) / double(n) : 0;
}

void BM_LeddarInsertion(benchmark::State& st, const Dataset* d)
{
	std::vector<const Frame*> withScan;
	for (const Frame& f : d->frames)
		if (f.scan) withScan.push_back(&f);
	if (withScan.empty())
	{
		st.SkipWithError("no 2D scans in this rawlog");
		return;
	}
	CGroundAwareOccupancyGrid grid;
	size_t i = 0;
	for (auto _ : st)
	{
		const Frame* f = withScan[i++ % withScan.size()];
		grid.insertObservation(*f->scan, f->pose);
	}
}

template <class MAP>
void BM_WholeMap(benchmark::State& st, const Dataset* d)
{
	MAP grid;
	size_t i = 0;
	for (auto _ : st)
	{
		const Frame& f = d->frames[i++ % d->frames.size()];
		grid.insertObservation(*f.depth, f.pose);
	}
}

// --- the summary: same frames, each map, median / p95 -----------------------
// Wall-clock ms of each insertObservation(); `after` (not timed) sees the map
// after each frame.
template <class MAP>
std::vector<double> timesOf(
	const Dataset& d, int rounds, size_t maxFrames = 0, const std::function<void(MAP&)>& setup = {},
	const std::function<void(const MAP&)>& after = {})
{
	MAP grid;
	if (setup) setup(grid);
	std::vector<double> ms;
	for (int r = 0; r < rounds; r++)
		for (size_t i = 0; i < d.frames.size() && (!maxFrames || i < maxFrames); i++)
		{
			const Frame& f = d.frames[i];
			const auto t0 = std::chrono::steady_clock::now();
			grid.insertObservation(*f.depth, f.pose);
			ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
			if (after) after(grid);
		}
	return ms;
}
double quantile(std::vector<double> v, double q)
{
	if (v.empty()) return 0;
	std::sort(v.begin(), v.end());
	return v[std::min(v.size() - 1, size_t(q * double(v.size())))];
}

// One printed figure over the summary's runs: each run's median and p95 (of
// its frames), and the median of those over the runs (quantile(), so for an
// even number of runs the upper of the two middle ones).
struct Figure
{
	std::vector<double> q50, q95;
	void add(const std::vector<double>& v)
	{
		q50.push_back(quantile(v, 0.5));
		q95.push_back(quantile(v, 0.95));
	}
	double median() const { return quantile(q50, 0.5); }
	double p95() const { return quantile(q95, 0.5); }
};
// The median over the runs of a per-run ratio a / b of medians.
double medianRatio(const Figure& a, const Figure& b)
{
	std::vector<double> r;
	for (size_t i = 0; i < a.q50.size() && i < b.q50.size(); i++) r.push_back(a.q50[i] / b.q50[i]);
	return quantile(r, 0.5);
}

// The ground-aware grid's own per-stage timings (lastFrame()), frame by frame.
struct StageSeries
{
	std::vector<double> projection, outliers, ground, ism, missing, update, total;
	gam::CameraModel camera = gam::CameraModel::Custom;
	void add(const CGroundAwareOccupancyGrid& grid)
	{
		const gam::StageTimes& l = grid.lastFrame().ms;
		camera = grid.lastFrame().camera;
		projection.push_back(l.projection);
		outliers.push_back(l.outliers);
		ground.push_back(l.ground);
		ism.push_back(l.ism);
		missing.push_back(l.missing);
		update.push_back(grid.lastFrameTimes().update);
		total.push_back(grid.lastFrameTimes().total);
	}
};

// A StageSeries' figures over the summary's runs.
struct StageFigures
{
	Figure projection, outliers, ground, ism, missing, update, total;
	gam::CameraModel camera = gam::CameraModel::Custom;
	void add(const StageSeries& s)
	{
		camera = s.camera;
		projection.add(s.projection);
		outliers.add(s.outliers);
		ground.add(s.ground);
		ism.add(s.ism);
		missing.add(s.missing);
		update.add(s.update);
		total.add(s.total);
	}
};

// The CPU the figures were taken on (they mean little without it).
std::string cpuName()
{
	std::ifstream in("/proc/cpuinfo");
	std::string line, name;
	int cpus = 0;
	while (std::getline(in, line))
		if (line.rfind("model name", 0) == 0)
		{
			cpus++;
			if (name.empty()) name = line.substr(line.find(':') + 2);
		}
	return name.empty() ? std::string("unknown CPU") : name + ", " + std::to_string(cpus) + " CPUs";
}

// Where height_band's time goes, frame by frame: MRPT's
// CObservation3DRangeScan::convertTo2DScan() (what the map calls), the
// virtual scan's insertion into the map, and, for scale, the
// same band as a plain loop: each pixel unprojected (MRPT's convention) into
// the robot frame, kept if its z is in the band, binned by its bearing
// (atan2 per kept point, as ROS pointcloud_to_laserscan does), the nearest
// horizontal range per bin. No map: the scan it makes is not inserted.
struct HeightBandSplit
{
	std::vector<double> convert, insert, plainLoop;
};
HeightBandSplit heightBandSplit(const Dataset& d, int rounds)
{
	// Its default band, oversampling and insertion options; a 2D scan goes
	// into it as the virtual scan does after the conversion.
	CHeightBandOccupancyGrid band;
	const auto& bo = band.bandOptions;
	HeightBandSplit out;
	std::vector<float> nearest;
	const auto ms = [](auto a, auto b) { return std::chrono::duration<double, std::milli>(b - a).count(); };
	for (int r = 0; r < rounds; r++)
		for (const Frame& f : d.frames)
		{
			CObservation3DRangeScan& o = *f.depth;
			const T3DPointsTo2DScanParams sp = band.scanParams(o.sensorLabel);
			CObservation2DRangeScan scan;
			const auto t0 = std::chrono::steady_clock::now();
			o.convertTo2DScan(scan, sp);
			const auto t1 = std::chrono::steady_clock::now();
			band.insertObservation(scan, f.pose);
			const auto t2 = std::chrono::steady_clock::now();

			const int W = int(o.rangeImage.cols()), H = int(o.rangeImage.rows());
			const double fx = o.cameraParams.fx(), fy = o.cameraParams.fy();
			const double cx = o.cameraParams.cx(), cy = o.cameraParams.cy();
			const auto R = o.sensorPose.getRotationMatrix();
			const double tz = o.sensorPose.z();
			const int bins = std::max(1, int(W * bo.oversampling_ratio));
			const double a0 = -std::atan(W / (2 * fx)), da = -2 * a0 / bins;
			nearest.assign(size_t(bins), std::numeric_limits<float>::infinity());
			for (int row = 0; row < H; row++)
				for (int col = 0; col < W; col++)
				{
					const uint16_t v = o.rangeImage(row, col);
					if (!v) continue;
					const double X = v * double(o.rangeUnits), Y = (cx - col) * X / fx, Z = (cy - row) * X / fy;
					const double z = R(2, 0) * X + R(2, 1) * Y + R(2, 2) * Z + tz;
					if (z < bo.z_min || z > bo.z_max) continue;
					const double x = R(0, 0) * X + R(0, 1) * Y + R(0, 2) * Z,
								 y = R(1, 0) * X + R(1, 1) * Y + R(1, 2) * Z;
					const int b = int((std::atan2(y, x) - a0) / da);
					if (b >= 0 && b < bins) nearest[size_t(b)] = std::min(nearest[size_t(b)], float(std::hypot(x, y)));
				}
			benchmark::DoNotOptimize(nearest.data());
			const auto t3 = std::chrono::steady_clock::now();
			out.convert.push_back(ms(t0, t1));
			out.insert.push_back(ms(t1, t2));
			out.plainLoop.push_back(ms(t2, t3));
		}
	return out;
}

// Single-frame rawlogs are inserted repeatedly: about 40 insertions per map.
int roundsFor(const Dataset& d) { return std::max(1, int(40 / d.frames.size())); }
}  // namespace

int main(int argc, char** argv)
{
	size_t maxFrames = 20;
	int decimation = 1;  // > 1: also the default with every n-th pixel row and column
	int fullOctomapFrames = 0;
	int runs = 1;  // the summary's runs: every figure the median of theirs
	bool summary = true;
	std::vector<std::string> files;
	std::vector<char*> bargs{argv[0]};
	for (int i = 1; i < argc; i++)
	{
		if (std::strncmp(argv[i], "--frames=", 9) == 0)
			maxFrames = size_t(std::max(1, std::atoi(argv[i] + 9)));
		else if (std::strncmp(argv[i], "--decimation=", 13) == 0)
			decimation = std::max(1, std::atoi(argv[i] + 13));
		else if (std::strncmp(argv[i], "--runs=", 7) == 0)
			runs = std::max(1, std::atoi(argv[i] + 7));
		else if (std::strncmp(argv[i], "--full-octomap=", 15) == 0)
			fullOctomapFrames = std::max(0, std::atoi(argv[i] + 15));
		else if (std::strcmp(argv[i], "--no-summary") == 0)
			summary = false;
		else if (std::strncmp(argv[i], "--", 2) == 0)
			bargs.push_back(argv[i]);
		else
			files.push_back(argv[i]);
	}
	if (files.empty())
	{
		std::cerr << "usage: gam-bench [--frames=N] [--decimation=N] [--runs=R] [--full-octomap=M] [--no-summary] "
					 "FILE.rawlog "
					 "[...] [benchmark flags]\n";
		return 2;
	}
	try
	{
		for (const auto& f : files) g_data.push_back(load(f, maxFrames));
	}
	catch (const std::exception& e)
	{
		std::cerr << "gam-bench: error: " << e.what() << "\n";
		return 1;
	}
	for (const Dataset& d : g_data)
	{
		const std::string n = d.name + "/";
		const std::pair<const char*, double gam::StageTimes::*> stageCases[] = {
			{"1_projection", &gam::StageTimes::projection},
			{"2_outlier_filter", &gam::StageTimes::outliers},
			{"3_rrt_gpd", &gam::StageTimes::ground},
			{"4_ism", &gam::StageTimes::ism},
			{"4_missing_floor", &gam::StageTimes::missing}};
		for (const bool paperMode : {false, true})
			for (const auto& [name, stage] : stageCases)
			{
				if (paperMode && stage == &gam::StageTimes::missing) continue;  // paper mode has none
				benchmark::RegisterBenchmark(
					(n + (paperMode ? "paper_" : "") + name).c_str(), BM_Stage, &d, stage, paperMode)
					->UseManualTime()
					->Unit(benchmark::kMillisecond);
			}
		benchmark::RegisterBenchmark((n + "5_leddar").c_str(), BM_LeddarInsertion, &d)->Unit(benchmark::kMillisecond);
		benchmark::RegisterBenchmark((n + "6_whole_pipeline").c_str(), BM_WholeMap<CGroundAwareOccupancyGrid>, &d)
			->Unit(benchmark::kMillisecond);
	}
	int bargc = int(bargs.size());
	benchmark::Initialize(&bargc, bargs.data());
	benchmark::RunSpecifiedBenchmarks();
	benchmark::Shutdown();
	if (!summary) return 0;

	// Each map over the same frames, `runs` times; the ground-aware run also
	// records its stages, and so does the same grid in paper mode (ism_model =
	// rrt_variant = paper) and, with --decimation, decimated.
	const size_t D = g_data.size();
	std::vector<Figure> ga(D), hb(D), om(D), hbConvert(D), hbInsert(D), hbPlain(D);
	std::vector<StageFigures> stages(D), paperStages(D), decimatedStages(D);
	for (int run = 0; run < runs; run++)
	{
		if (runs > 1) std::fprintf(stderr, "gam-bench: summary run %d of %d\n", run + 1, runs);
		for (size_t k = 0; k < D; k++)
		{
			const Dataset& d = g_data[k];
			const int rounds = roundsFor(d);
			StageSeries def, paper, decimated;
			ga[k].add(timesOf<CGroundAwareOccupancyGrid>(
				d, rounds, 0, {}, [&](const CGroundAwareOccupancyGrid& g) { def.add(g); }));
			stages[k].add(def);
			timesOf<CGroundAwareOccupancyGrid>(
				d, rounds, 0,
				[](CGroundAwareOccupancyGrid& g) {
					auto o = g.groundOptions();
					o.pipeline.ism.model = gam::MethodVariant::Paper;
					o.pipeline.rrt.variant = gam::MethodVariant::Paper;
					g.setGroundOptions(o);
				},
				[&](const CGroundAwareOccupancyGrid& g) { paper.add(g); });
			paperStages[k].add(paper);
			if (decimation > 1)
			{
				timesOf<CGroundAwareOccupancyGrid>(
					d, rounds, 0,
					[&](CGroundAwareOccupancyGrid& g) {
						auto o = g.groundOptions();
						o.pipeline.projection.decimation = decimation;
						g.setGroundOptions(o);
					},
					[&](const CGroundAwareOccupancyGrid& g) { decimated.add(g); });
				decimatedStages[k].add(decimated);
			}
			hb[k].add(timesOf<CHeightBandOccupancyGrid>(d, rounds));
			om[k].add(timesOf<COctoMapGrid2D>(d, 1));
		}
		for (size_t k = 0; k < D; k++)
		{
			const HeightBandSplit hs = heightBandSplit(g_data[k], roundsFor(g_data[k]));
			hbConvert[k].add(hs.convert);
			hbInsert[k].add(hs.insert);
			hbPlain[k].add(hs.plainLoop);
		}
	}

	std::printf("\nCPU: %s (one core per map; compare within a row)\n", cpuName().c_str());
	if (runs > 1) std::printf("Every figure: the median of %d runs' figures.\n", runs);
	std::printf(
		"\n| data | frames | px/frame | ground_aware median / p95 ms | height_band median / p95 ms | octomap median / "
		"p95 ms | height_band / ground_aware | octomap / ground_aware |\n|---|---|---|---|---|---|---|---|\n");
	for (size_t k = 0; k < D; k++)
	{
		const Dataset& d = g_data[k];
		std::printf(
			"| %s | %zu | %zux%zu | %.2f / %.2f | %.2f / %.2f | %.2f / %.2f | %.1fx | %.1fx |\n", d.name.c_str(),
			d.frames.size(), size_t(d.frames[0].depth->rangeImage.cols()), size_t(d.frames[0].depth->rangeImage.rows()),
			ga[k].median(), ga[k].p95(), hb[k].median(), hb[k].p95(), om[k].median(), om[k].p95(),
			medianRatio(hb[k], ga[k]), medianRatio(om[k], ga[k]));
	}

	std::printf(
		"\nground_aware per stage (the map's own timers), default and paper mode, median / p95 ms (camera: the "
		"model the map took the frames for):\n\n| data | camera | 2.5D projection | 3-sigma filter + IDW | RRT-GPD | "
		"ISM | missing floor | grid update | whole frame |\n|---|---|---|---|---|---|---|---|---|\n");
	auto mp = [](const Figure& f) {
		char b[64];
		std::snprintf(b, sizeof b, "%.3f / %.3f", f.median(), f.p95());
		return std::string(b);
	};
	const std::string decimatedLabel = " (decimation " + std::to_string(decimation) + ")";
	for (const auto* series : {&stages, &paperStages, &decimatedStages})
		for (size_t k = 0; k < D; k++)
		{
			if (series == &decimatedStages && decimation == 1) break;
			const StageFigures& t = (*series)[k];
			const char* camera = series == &paperStages ? "-" : gam::kCameraModelNames[int(t.camera)];
			std::printf(
				"| %s%s | %s | %s | %s | %s | %s | %s | %s | %s |\n", g_data[k].name.c_str(),
				series == &paperStages       ? " (paper mode)"
				: series == &decimatedStages ? decimatedLabel.c_str()
											 : "",
				camera, mp(t.projection).c_str(), mp(t.outliers).c_str(), mp(t.ground).c_str(), mp(t.ism).c_str(),
				mp(t.missing).c_str(), mp(t.update).c_str(), mp(t.total).c_str());
		}

	std::printf(
		"\nheight_band's time, median / p95 ms: MRPT's convertTo2DScan() and the virtual scan's insertion (what the "
		"map does), and the same band as a plain loop over the pixels (no map; see heightBandSplit):\n\n| data | "
		"convertTo2DScan | scan insertion | plain loop | ground_aware median | plain loop / ground_aware "
		"|\n|---|---|---|---|---|---|\n");
	for (size_t k = 0; k < D; k++)
		std::printf(
			"| %s | %s | %s | %s | %.2f | %.2fx |\n", g_data[k].name.c_str(), mp(hbConvert[k]).c_str(),
			mp(hbInsert[k]).c_str(), mp(hbPlain[k]).c_str(), ga[k].median(), medianRatio(hbPlain[k], ga[k]));

	if (fullOctomapFrames > 0)
	{
		// The run's octomap inserts every 4th pixel of every 4th row (decimation 4,
		// ground-aware-mapper.ini): 1/16 of what the ground-aware grid reads. This
		// times it on every pixel too, the same input as the ground-aware grid.
		std::printf(
			"\noctomap on every pixel (decimation 1), first %d frames:\n\n| data | octomap (every pixel) median / p95 "
			"ms | ground_aware median ms | ratio |\n|---|---|---|---|\n",
			fullOctomapFrames);
		for (size_t k = 0; k < g_data.size(); k++)
		{
			const auto full = timesOf<COctoMapGrid2D>(
				g_data[k], 1, size_t(fullOctomapFrames), [](COctoMapGrid2D& m) { m.octoOptions.decimation = 1; });
			std::printf(
				"| %s | %.1f / %.1f | %.2f | %.0fx |\n", g_data[k].name.c_str(), quantile(full, 0.5),
				quantile(full, 0.95), ga[k].median(), quantile(full, 0.5) / ga[k].median());
		}
	}
	return 0;
}
