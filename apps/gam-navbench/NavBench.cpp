// Ground-aware mapping for MRPT -- gam-navbench (issue #29), library part.
#include "NavBench.h"

#include <gam/mapper/Mapper.h>
#include <mrpt/config/CConfigFileMemory.h>
#include <mrpt/img/CImage.h>
#include <mrpt/maps/registerBaselineMaps.h>
#include <mrpt/maps/registerGroundAwareMaps.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <limits>
#include <mutex>
#include <sstream>
#include <stdexcept>
#include <thread>

#include "navbench_default_config.h"

namespace gam::navbench
{
const std::vector<std::string>& mapNames()
{
	static const std::vector<std::string> names = {"ground_aware", "paper", "height_band", "octomap"};
	return names;
}

const std::vector<std::pair<std::string, std::string>>& paperOverrides()
{
	// rawlog_tools/gam-ablation-ini, row "paper" (tests/nav checks they agree)
	static const std::vector<std::pair<std::string, std::string>> kv = {
		{"ism_model", "paper"},
		{"rrt_variant", "paper"},
		{"scan_keeps_3d_obstacles", "false"},
		{"sparse_scan_near_edge", "false"}};
	return kv;
}

const char* defaultMapperIni() { return kNavBenchDefaultIni; }

std::unique_ptr<BenchMap> makeMap(const std::string& map, const gam::sim::GridSpec& extent, const std::string& iniText)
{
	const auto& names = mapNames();
	if (std::find(names.begin(), names.end(), map) == names.end())
		throw std::invalid_argument("unknown map '" + map + "'");
	const std::string kind = map == "height_band" ? "heightBandGrid"
							 : map == "octomap"   ? "octoMapGrid"
												  : "groundAwareGrid";
	// keeps both plugins linked (--as-needed) and registered
	mrpt::maps::registerGroundAwareMaps();
	mrpt::maps::registerBaselineMaps();
	mrpt::config::CConfigFileMemory ini(iniText);
	for (const char* k : {"groundAwareGrid", "heightBandGrid", "octoMapGrid", "CElevation25DMap"})
		ini.write("map", std::string(k) + "_count", k == kind ? 1 : 0);
	const std::string prefix = "map_" + kind + "_00_";
	// The scene's extent (the default's +-10 m would only cost time; the grids grow anyway).
	ini.write(prefix + "creationOpts", "min_x", extent.min_x);
	ini.write(prefix + "creationOpts", "max_x", extent.max_x);
	ini.write(prefix + "creationOpts", "min_y", extent.min_y);
	ini.write(prefix + "creationOpts", "max_y", extent.max_y);
	ini.write(prefix + "creationOpts", "label", map);
	if (map == "paper")
		for (const auto& [k, v] : paperOverrides()) ini.write(prefix + "groundOpts", k, v);
	auto out = std::make_unique<BenchMap>();
	gam::mapper::createMaps(ini, "map", out->multi);
	if (out->multi.maps.size() != 1) throw std::runtime_error("makeMap: the .ini made no single map for " + map);
	out->grid = dynamic_cast<mrpt::maps::COccupancyGridMap2D*>(out->multi.maps[0].get());
	if (!out->grid) throw std::runtime_error("makeMap: " + map + " is not a COccupancyGridMap2D");
	return out;
}

FootprintHit footprintOver(const gam::sim::GroundTruthGrid& gt, double x, double y, double yaw, double h)
{
	FootprintHit hit;
	const double res = gt.spec.resolution, R = h * std::sqrt(2.0);
	const double c = std::cos(yaw), s = std::sin(yaw);
	const int ix0 = std::max(0, int(std::floor((x - R - gt.spec.min_x) / res)));
	const int iy0 = std::max(0, int(std::floor((y - R - gt.spec.min_y) / res)));
	const int ix1 = std::min(gt.spec.nx() - 1, int(std::floor((x + R - gt.spec.min_x) / res)));
	const int iy1 = std::min(gt.spec.ny() - 1, int(std::floor((y + R - gt.spec.min_y) / res)));
	const double eps = 1e-9;
	for (int iy = iy0; iy <= iy1; iy++)
		for (int ix = ix0; ix <= ix1; ix++)
		{
			const double dx = gt.spec.cellX(ix) - x, dy = gt.spec.cellY(iy) - y;
			// the cell centre in the walker's frame
			const double lx = c * dx + s * dy, ly = -s * dx + c * dy;
			if (std::abs(lx) > h + eps || std::abs(ly) > h + eps) continue;
			const size_t i = gt.idx(ix, iy);
			if (gt.geomLabel[i] == gam::sim::Label::Drop)
			{
				if (!hit.dropCells++) hit.dropObject = gt.objectId[i];
			}
			else if (gt.geomLabel[i] == gam::sim::Label::Obstacle)
			{
				if (!hit.obstacleCells++) hit.obstacleObject = gt.objectId[i];
			}
		}
	return hit;
}

RunResult runOne(const gam::sim::GeneratedScene& g, const std::string& map, const BenchOptions& o)
{
	const auto wall0 = std::chrono::steady_clock::now();
	RunResult res;
	res.seed = g.seed;
	res.map = map;
	res.gtPathLength = g.gtPathLength;
	res.lineHazard = gam::sim::hazardKindName(g.lineHazard);
	const gam::sim::SceneFile& sf = g.file;

	auto bm = makeMap(map, sf.grid);
	gam::nav::ClosedLoopOptions co;
	co.reactive.baseConfig = o.reactiveConfig;
	co.reactive.cacheDir = o.cacheDir;
	co.reactive.maxTime = o.timeBase + o.timePerMetre * g.gtPathLength;
	co.plan.robotRadius = float(o.planRadius);
	co.seed = g.seed;  // sensor noise: the same frames for every map while they drive the same way
	const double half = co.reactive.robotHalfSize;

	// The judge: the ground truth of each frame, the footprint at the true pose.
	gam::sim::FrameGroundTruth truth(sf.scene, sf.grid);
	const std::vector<float> toGoal = gam::sim::distanceField(gam::sim::staticGroundTruth(sf), g.goal, 0.0);
	double best = std::numeric_limits<double>::infinity(), bestAt = 0;
	co.onStep = [&](double t, const mrpt::math::TPose2D& p) {
		truth.setFrame(int(std::floor(t / co.frameInterval + 1e-9)));
		const FootprintHit hit = footprintOver(truth.grid(), p.x, p.y, p.phi, half);
		if (hit.dropCells)
		{
			res.fell = true;
			res.hitObject = hit.dropObject;
			return false;
		}
		if (hit.obstacleCells)
		{
			res.collided = true;
			res.hitObject = hit.obstacleObject;
			return false;
		}
		int ix, iy;
		if (truth.grid().cellOf(p.x, p.y, ix, iy))
		{
			const double d = toGoal[truth.grid().idx(ix, iy)];
			if (std::isfinite(d) && d < best - o.stuckProgress)
			{
				best = d;
				bestAt = t;
			}
			else if (!std::isfinite(best))
				bestAt = t;
		}
		if (t - bestAt > o.stuckSeconds)
		{
			res.stuck = true;
			return false;
		}
		return true;
	};
	const mrpt::math::TPose2D start(g.start.x(), g.start.y(), g.startYaw);
	const auto r =
		gam::nav::runClosedLoopNavigation(sf, *bm->grid, start, mrpt::math::TPoint2D(g.goal.x(), g.goal.y()), co);

	if (!o.mapPictureDir.empty())
	{
		std::ofstream tf(o.mapPictureDir + "/seed_" + std::to_string(g.seed) + "_" + map + "_trajectory.csv");
		tf << "t,x,y,phi\n";
		for (size_t i = 0; i < r.trajectory.size(); i++)
			tf << i * co.reactive.dt << "," << r.trajectory[i].x << "," << r.trajectory[i].y << ","
			   << r.trajectory[i].phi << "\n";
		gam::nav::PlanResult traj;
		for (const auto& p : r.trajectory) traj.path.emplace_back(p.x, p.y);
		gam::nav::savePathPicture(
			*bm->grid, traj, {g.start.x(), g.start.y()}, {g.goal.x(), g.goal.y()},
			o.mapPictureDir + "/seed_" + std::to_string(g.seed) + "_" + map + ".png");
	}
	res.trajectory = r.trajectory;
	res.seconds = r.seconds;
	res.frames = r.frames;
	res.plans = r.plans;
	res.failedPlans = r.failedPlans;
	res.turningSeconds = r.turningSeconds;
	res.partialPlans = r.partialPlans;
	res.backups = r.backups;
	res.planFollows = r.planFollows;
	res.endState = r.endState;
	for (size_t i = 1; i < r.trajectory.size(); i++)
		res.pathLength +=
			std::hypot(r.trajectory[i].x - r.trajectory[i - 1].x, r.trajectory[i].y - r.trajectory[i - 1].y);
	const auto& e = r.trajectory.back();
	res.finalDistance = std::hypot(e.x - g.goal.x(), e.y - g.goal.y());
	if (res.fell)
		res.outcome = "fall";
	else if (res.collided)
		res.outcome = "collision";
	else if (res.finalDistance <= o.goalTolerance)
		res.arrived = true, res.outcome = "arrived";
	else if (res.stuck || r.endState == "NAV_ERROR")
		res.stuck = true, res.outcome = "stuck";
	else
		res.timedOut = true, res.outcome = "timeout";
	if (res.hitObject)
		if (const auto* ob = sf.scene.object(res.hitObject)) res.hitName = ob->name;
	res.wallSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
	return res;
}

namespace
{
double median(std::vector<double> v)
{
	if (v.empty()) return std::numeric_limits<double>::quiet_NaN();
	std::sort(v.begin(), v.end());
	const size_t n = v.size();
	return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}
std::string fmt1(double v)
{
	if (!std::isfinite(v)) return "-";
	std::ostringstream s;
	s << std::fixed << std::setprecision(1) << v;
	return s.str();
}
}  // namespace

std::string markdownTable(const std::vector<RunResult>& runs, const std::vector<std::string>& maps)
{
	std::ostringstream s;
	s << "| map | arrivals | falls | collisions | stuck | median time to goal [s] | median path [m] |\n";
	s << "|---|---|---|---|---|---|---|\n";
	for (const auto& m : maps)
	{
		int n = 0, arr = 0, falls = 0, coll = 0, stuck = 0;
		std::vector<double> times, paths;
		for (const auto& r : runs)
		{
			if (r.map != m) continue;
			n++;
			arr += r.arrived, falls += r.fell, coll += r.collided, stuck += r.stuck;
			if (r.arrived) times.push_back(r.seconds), paths.push_back(r.pathLength);
		}
		s << "| " << m << " | " << arr << "/" << n << " | " << falls << " | " << coll << " | " << stuck << " | "
		  << fmt1(median(times)) << " | " << fmt1(median(paths)) << " |\n";
	}
	return s.str();
}

std::string csvHeader()
{
	return "seed,map,outcome,arrived,fall,collision,stuck,timeout,time_s,path_m,final_distance_m,gt_path_m,"
		   "line_hazard,hit_object,hit_name,frames,plans,failed_plans,turning_s,partial_plans,backups,plan_follows,end_"
		   "state,wall_s\n";
}

std::string csvRow(const RunResult& r)
{
	std::ostringstream s;
	s << r.seed << "," << r.map << "," << r.outcome << "," << r.arrived << "," << r.fell << "," << r.collided << ","
	  << r.stuck << "," << r.timedOut << "," << std::fixed << std::setprecision(2) << r.seconds << "," << r.pathLength
	  << "," << r.finalDistance << "," << r.gtPathLength << "," << r.lineHazard << "," << r.hitObject << ","
	  << r.hitName << "," << r.frames << "," << r.plans << "," << r.failedPlans << "," << r.turningSeconds << ","
	  << r.partialPlans << "," << r.backups << "," << r.planFollows << "," << r.endState << "," << r.wallSeconds
	  << "\n";
	return s.str();
}

namespace
{
mrpt::img::TColor mapColour(size_t i)
{
	static const mrpt::img::TColor c[] = {{0, 160, 0}, {0, 90, 230}, {220, 0, 0}, {170, 0, 200}, {120, 120, 0}};
	return c[std::min<size_t>(i, 4)];
}
}  // namespace

void drawTrajectories(
	const std::vector<const gam::sim::GeneratedScene*>& scenes, const std::vector<RunResult>& runs,
	const std::vector<std::string>& maps, const std::string& file, int scale)
{
	if (scenes.empty()) return;
	// MRPT's "9x15" bitmap font: 9 px a character; lines 16 px apart.
	const int charW = 9, lineH = 16;
	const int gap = 8, head = 2 * lineH + 8, label = 2 * lineH;
	const std::string key =
		"ground truth: black obstacle, orange drop; grey: a person's crossing; x: where a run ended short";
	auto textWidth = [&](const std::string& t) { return charW * int(t.size()); };
	std::vector<gam::sim::GroundTruthGrid> gts;
	int W = 0, H = head;
	for (const auto* g : scenes)
	{
		gts.push_back(gam::sim::staticGroundTruth(g->file));
		W = std::max(W, gts.back().spec.nx() * scale);
		H += label + gts.back().spec.ny() * scale + gap;
	}
	// The picture is as wide as its widest line of text: the key, the legend
	// and each scene's lines (its outcomes name every map).
	int legendW = 0;
	for (const auto& m : maps) legendW += 20 + textWidth(m) + 2 * charW;
	auto title = [&](const gam::sim::GeneratedScene& g) {
		std::ostringstream t;
		t << "seed " << g.seed << ": " << gam::sim::hazardKindName(g.lineHazard)
		  << " on the straight line (o start, square goal)";
		return t.str();
	};
	auto outcomes = [&](const gam::sim::GeneratedScene& g) {
		std::string u = "outcomes:";
		for (const auto& m : maps)
			for (const auto& r : runs)
				if (r.seed == g.seed && r.map == m) u += " " + r.map + " " + r.outcome;
		return u;
	};
	int textW = std::max(textWidth(key), legendW);
	for (const auto* g : scenes) textW = std::max({textW, textWidth(title(*g)), textWidth(outcomes(*g))});
	W = std::max(W, textW) + 2 * gap;
	mrpt::img::CImage im(W, H, mrpt::img::CH_RGB);
	im.selectTextFont("9x15");
	im.filledRectangle(0, 0, W - 1, H - 1, mrpt::img::TColor(255, 255, 255));
	// legend
	int lx = gap;
	for (size_t k = 0; k < maps.size(); k++)
	{
		im.filledRectangle(lx, 9, lx + 14, 12, mapColour(k));
		im.textOut(lx + 20, 4, maps[k], mapColour(k));
		lx += 20 + textWidth(maps[k]) + 2 * charW;
	}
	im.textOut(gap, 4 + lineH, key, mrpt::img::TColor(0, 0, 0));
	int oy = head;
	for (size_t si = 0; si < scenes.size(); si++)
	{
		const auto& g = *scenes[si];
		const auto& gt = gts[si];
		const int nx = gt.spec.nx(), ny = gt.spec.ny();
		im.textOut(gap, oy, title(g), mrpt::img::TColor(0, 0, 0));
		im.textOut(gap, oy + lineH, outcomes(g), mrpt::img::TColor(0, 0, 0));
		oy += label;
		auto px = [&](double x) { return gap + int(std::lround((x - gt.spec.min_x) / gt.spec.resolution * scale)); };
		auto py = [&](double y) {
			return oy + ny * scale - 1 - int(std::lround((y - gt.spec.min_y) / gt.spec.resolution * scale));
		};
		for (int iy = 0; iy < ny; iy++)
			for (int ix = 0; ix < nx; ix++)
			{
				const auto l = gt.geomLabel[gt.idx(ix, iy)];
				const mrpt::img::TColor c = l == gam::sim::Label::Obstacle ? mrpt::img::TColor(0, 0, 0)
											: l == gam::sim::Label::Drop   ? mrpt::img::TColor(255, 150, 30)
																		   : mrpt::img::TColor(250, 250, 250);
				const int x0 = gap + ix * scale, y0 = oy + (ny - 1 - iy) * scale;
				im.filledRectangle(x0, y0, x0 + scale - 1, y0 + scale - 1, c);
			}
		// the people's crossings
		for (const auto& ob : g.file.scene.objects)
		{
			if (!ob.dynamic()) continue;
			const auto a = g.file.scene.footprintAt(ob.id, ob.first_frame),
					   b = g.file.scene.footprintAt(ob.id, ob.last_frame);
			if (a.isEmpty() || b.isEmpty()) continue;
			im.line(
				px(a.center().x()), py(a.center().y()), px(b.center().x()), py(b.center().y()),
				mrpt::img::TColor(150, 150, 150), 3);
		}
		for (size_t k = 0; k < maps.size(); k++)
			for (const auto& r : runs)
			{
				if (r.seed != g.seed || r.map != maps[k]) continue;
				for (size_t i = 1; i < r.trajectory.size(); i++)
					im.line(
						px(r.trajectory[i - 1].x), py(r.trajectory[i - 1].y), px(r.trajectory[i].x),
						py(r.trajectory[i].y), mapColour(k), 2);
				if (!r.arrived && !r.trajectory.empty())
					im.drawMark(px(r.trajectory.back().x), py(r.trajectory.back().y), mapColour(k), 'x', 7, 2);
			}
		im.drawCircle(px(g.start.x()), py(g.start.y()), 6, mrpt::img::TColor(0, 160, 0), 2);
		im.drawMark(px(g.goal.x()), py(g.goal.y()), mrpt::img::TColor(0, 0, 255), 's', 8, 2);
		oy += ny * scale + gap;
	}
	if (!im.saveToFile(file)) throw std::runtime_error("cannot write " + file);
}

void parseSeedRange(const std::string& s, unsigned& first, unsigned& last)
{
	auto num = [&](const std::string& t) {
		if (t.empty() || t.size() > 9 || t.find_first_not_of("0123456789") != std::string::npos)
			throw std::invalid_argument("bad --seeds '" + s + "' (expected A-B or A, non-negative integers)");
		return unsigned(std::stoul(t));
	};
	const auto dash = s.find('-');
	first = num(s.substr(0, dash));
	last = dash == std::string::npos ? first : num(s.substr(dash + 1));
	if (last < first) throw std::invalid_argument("bad --seeds '" + s + "' (A-B needs A <= B)");
}

std::vector<std::string> parseMapList(const std::string& s)
{
	std::vector<std::string> out;
	std::stringstream ss(s);
	std::string m;
	while (std::getline(ss, m, ','))
	{
		const auto& names = mapNames();
		if (std::find(names.begin(), names.end(), m) == names.end())
			throw std::invalid_argument(
				"unknown map '" + m + "' in --maps (known: ground_aware, paper, height_band, octomap)");
		if (std::find(out.begin(), out.end(), m) != out.end())
			throw std::invalid_argument("map '" + m + "' twice in --maps");
		out.push_back(m);
	}
	if (out.empty()) throw std::invalid_argument("--maps is empty");
	return out;
}

std::string runNavBench(const NavBenchOptions& o, std::ostream& progress)
{
	if (o.outDir.empty()) throw std::invalid_argument("no output folder");
	if (o.jobs < 1 || o.jobs > 64) throw std::invalid_argument("--jobs must be in 1..64");
	if (o.maps.empty()) throw std::invalid_argument("no maps");
	namespace fs = std::filesystem;
	fs::create_directories(o.outDir);

	// the scenes first (a seed without a layout stops before any run)
	std::vector<gam::sim::GeneratedScene> scenes;
	for (unsigned s = o.firstSeed; s <= o.lastSeed; s++)
	{
		scenes.push_back(gam::sim::generateScene(s));
		if (o.writeScenes)
		{
			fs::create_directories(o.outDir + "/scenes");
			gam::sim::writeGeneratedScene(
				scenes.back(), o.outDir + "/scenes/seed_" + std::to_string(s) + ".scene", o.writeScenesPath);
		}
		if (s == o.lastSeed) break;  // lastSeed may be UINT_MAX
	}

	struct Job
	{
		size_t scene;
		std::string map;
	};
	std::vector<Job> jobs;
	for (size_t i = 0; i < scenes.size(); i++)
		for (const auto& m : o.maps) jobs.push_back({i, m});
	std::vector<RunResult> results(jobs.size());
	NavBenchOptions opts = o;
	if (o.saveMaps)
	{
		opts.bench.mapPictureDir = o.outDir + "/maps";
		fs::create_directories(opts.bench.mapPictureDir);
	}
	// runs.csv grows run by run (in the order they end), so an interrupted
	// benchmark keeps what it did; at the end it is written again in seed order.
	std::ofstream partial(o.outDir + "/runs.csv");
	partial << csvHeader() << std::flush;
	std::atomic<size_t> next{0}, done{0};
	std::mutex mu;
	std::exception_ptr failure;
	auto worker = [&](int w) {
		BenchOptions bo = opts.bench;
		// each worker its own PTG cache folder (the tables are written on first use)
		bo.cacheDir = o.bench.cacheDir + "/navbench_ptg_w" + std::to_string(w);
		fs::create_directories(bo.cacheDir);
		for (size_t j; (j = next++) < jobs.size();)
		{
			try
			{
				results[j] = runOne(scenes[jobs[j].scene], jobs[j].map, bo);
			}
			catch (...)
			{
				std::lock_guard<std::mutex> lk(mu);
				if (!failure) failure = std::current_exception();
				next = jobs.size();
				return;
			}
			const auto& r = results[j];
			std::lock_guard<std::mutex> lk(mu);
			partial << csvRow(r) << std::flush;
			progress << "[gam-navbench " << ++done << "/" << jobs.size() << "] seed " << r.seed << " " << r.map << ": "
					 << r.outcome;
			if (r.hitObject) progress << " (" << r.hitName << ", id " << r.hitObject << ")";
			progress << std::fixed << std::setprecision(1) << " after " << r.seconds << " s, path " << r.pathLength
					 << " m, " << r.finalDistance << " m from the goal; " << r.wallSeconds << " s wall\n"
					 << std::flush;
		}
	};
	std::vector<std::thread> threads;
	for (int w = 1; w < o.jobs; w++) threads.emplace_back(worker, w);
	worker(0);
	for (auto& t : threads) t.join();
	if (failure) std::rethrow_exception(failure);
	partial.close();

	std::ofstream csv(o.outDir + "/runs.csv");
	csv << csvHeader();
	for (const auto& r : results) csv << csvRow(r);
	if (!csv) throw std::runtime_error("cannot write " + o.outDir + "/runs.csv");
	const std::string table = markdownTable(results, o.maps);
	std::ofstream md(o.outDir + "/table.md");
	md << table;
	if (!md) throw std::runtime_error("cannot write " + o.outDir + "/table.md");
	std::vector<const gam::sim::GeneratedScene*> fig;
	for (size_t i = 0; i < scenes.size() && int(i) < o.figureScenes; i++) fig.push_back(&scenes[i]);
	drawTrajectories(fig, results, o.maps, o.outDir + "/trajectories.png");
	return table;
}

}  // namespace gam::navbench
