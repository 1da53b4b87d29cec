// Ground-aware mapping for MRPT -- navigation example (library part).
#include "NavExample.h"

#include <mrpt/config/CConfigFileMemory.h>
#include <mrpt/core/Clock.h>
#include <mrpt/img/CImage.h>
#include <mrpt/kinematics/CVehicleSimul_DiffDriven.h>
#include <mrpt/math/wrap2pi.h>
#include <mrpt/nav/planners/PlannerSimple2D.h>
#include <mrpt/nav/reactive/CReactiveNavigationSystem.h>
#include <mrpt/nav/reactive/CRobot2NavInterfaceForSimulator.h>
#include <mrpt/system/datetime.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <memory>
#include <mutex>
#include <sstream>
#include <stdexcept>

#include "gam/sim/KinectObservation.h"
#include "gam/sim/Sensors.h"

namespace gam::nav
{
namespace
{
mrpt::poses::CPose3D toCPose3D(const gam::sim::Pose3& p)
{
	const Eigen::Vector3d a = p.ypr();
	return mrpt::poses::CPose3D(p.t.x(), p.t.y(), p.t.z(), a[0], a[1], a[2]);
}
}  // namespace

mrpt::obs::CObservation3DRangeScan::Ptr simulateKinect(
	const gam::sim::SceneFile& sf, const gam::sim::Pose2& robot, std::mt19937& rng)
{
	return simulateKinect(sf, sf.scene, robot, rng);
}

mrpt::obs::CObservation3DRangeScan::Ptr simulateKinect(
	const gam::sim::SceneFile& sf, const gam::sim::Scene& scene, const gam::sim::Pose2& robot, std::mt19937& rng)
{
	const gam::sim::KinectModel kinect(sf.kinect);
	const gam::sim::Pose3 robot3 = gam::sim::Pose3::fromXYZYPR(robot.x, robot.y, 0, robot.yaw, 0, 0);
	const gam::sim::DepthFrame fr = kinect.render(scene, robot3 * sf.kinect_pose, rng);

	return gam::sim::toKinectObservation(sf.kinect, fr, toCPose3D(sf.kinect_pose));
}

void buildMaps(const gam::sim::SceneFile& sfIn, const MapOptions& opts, NavMaps& out)
{
	gam::sim::SceneFile sf = sfIn;
	sf.kinect.noise = opts.noise;
	const std::vector<gam::sim::Pose2> poses = gam::sim::samplePath(sf.path);
	if (poses.empty()) throw std::runtime_error("the scene's path has no frames");

	double x0, x1, y0, y1, res = 0.05;
	if (sf.has_grid)
	{
		x0 = sf.grid.min_x, x1 = sf.grid.max_x, y0 = sf.grid.min_y, y1 = sf.grid.max_y;
		res = sf.grid.resolution;
	}
	else
	{
		x0 = x1 = poses[0].x, y0 = y1 = poses[0].y;
		for (const auto& p : poses)
		{
			x0 = std::min(x0, p.x), x1 = std::max(x1, p.x);
			y0 = std::min(y0, p.y), y1 = std::max(y1, p.y);
		}
		x0 -= 5, x1 += 5, y0 -= 5, y1 += 5;
	}
	out.groundAware.setSize(float(x0), float(x1), float(y0), float(y1), float(res), 0.5f);
	out.heightBand.setSize(float(x0), float(x1), float(y0), float(y1), float(res), 0.5f);
	out.robotPoses.clear();
	out.framesWithGround = 0;

	std::mt19937 rng(opts.seed);
	for (const auto& p : poses)
	{
		const auto obs = simulateKinect(sf, p, rng);
		const mrpt::poses::CPose3D robotPose(p.x, p.y, 0, p.yaw, 0, 0);
		out.groundAware.insertObservation(*obs, robotPose);
		out.heightBand.insertObservation(*obs, robotPose);
		if (out.groundAware.lastFrame().detection.ok()) out.framesWithGround++;
		out.robotPoses.emplace_back(p.x, p.y, p.yaw);
	}
}

double plannerRadiusForFootprint(double halfSide, double resolution)
{
	const int n = int(std::ceil(halfSide * std::sqrt(2.0) / resolution - 0.5));
	return (n - 0.5) * resolution;
}

namespace
{
float effectiveRadius(const mrpt::maps::COccupancyGridMap2D& grid, const PlanOptions& opts)
{
	if (opts.robotRadius > 0) return opts.robotRadius;
	const double res = grid.getResolution();
	return float(plannerRadiusForFootprint(opts.footprintHalfSize + opts.footprintMarginCells * res, res));
}
}  // namespace

PlanResult planPath(
	const mrpt::maps::COccupancyGridMap2D& grid, const mrpt::math::TPoint2D& start, const mrpt::math::TPoint2D& goal,
	const PlanOptions& opts)
{
	mrpt::nav::PlannerSimple2D planner;
	planner.robotRadius = effectiveRadius(grid, opts);
	planner.occupancyThreshold = opts.occupancyThreshold;
	planner.minStepInReturnedPath = opts.minStepInReturnedPath;

	PlanResult r;
	bool notFound = true;
	planner.computePath(
		grid, mrpt::poses::CPose2D(start.x, start.y, 0), mrpt::poses::CPose2D(goal.x, goal.y, 0), r.path, notFound,
		opts.maxSearchPathLength);
	r.found = !notFound && !r.path.empty();
	if (!r.found) return r;

	const mrpt::math::TPoint2D d = goal - start;
	const double len = std::hypot(d.x, d.y);
	for (size_t i = 0; i < r.path.size(); i++)
	{
		if (i > 0) r.length += (r.path[i] - r.path[i - 1]).norm();
		if (len > 0)
		{
			const mrpt::math::TPoint2D v = r.path[i] - start;
			r.maxDeviation = std::max(r.maxDeviation, std::abs(d.x * v.y - d.y * v.x) / len);
		}
	}
	return r;
}

std::vector<uint8_t> plannerBlockedCells(const mrpt::maps::COccupancyGridMap2D& grid, const PlanOptions& opts)
{
	const int W = int(grid.getSizeX()), H = int(grid.getSizeY());
	const int n = int(std::ceil(effectiveRadius(grid, opts) / grid.getResolution()));
	std::vector<uint8_t> obstacle(size_t(W) * H), rows(size_t(W) * H), out(size_t(W) * H);
	for (int y = 0; y < H; y++)
		for (int x = 0; x < W; x++) obstacle[x + size_t(y) * W] = grid.getCell(x, y) <= opts.occupancyThreshold;
	// A square dilation is a dilation of the rows and then of the columns.
	for (int y = 0; y < H; y++)
		for (int x = 0; x < W; x++)
		{
			uint8_t b = 0;
			for (int k = std::max(0, x - n); k <= std::min(W - 1, x + n) && !b; k++) b = obstacle[k + size_t(y) * W];
			rows[x + size_t(y) * W] = b;
		}
	for (int y = 0; y < H; y++)
		for (int x = 0; x < W; x++)
		{
			uint8_t b = 0;
			for (int k = std::max(0, y - n); k <= std::min(H - 1, y + n) && !b; k++) b = rows[x + size_t(k) * W];
			out[x + size_t(y) * W] = b;
		}
	return out;
}

PlanResult planTowards(
	const mrpt::maps::COccupancyGridMap2D& grid, const mrpt::math::TPoint2D& start, const mrpt::math::TPoint2D& goal,
	const PlanOptions& opts)
{
	const int W = int(grid.getSizeX()), H = int(grid.getSizeY());
	const auto blocked = plannerBlockedCells(grid, opts);
	const int sx = grid.x2idx(start.x), sy = grid.y2idx(start.y);
	if (sx < 0 || sy < 0 || sx >= W || sy >= H) return {};
	// Breadth-first, 8-connected, over the cells outside the grown obstacles.
	auto bfs = [&](int fx, int fy, const std::function<void(int, int)>& visit) {
		std::vector<uint8_t> seen(size_t(W) * H);
		std::deque<std::pair<int, int>> q{{fx, fy}};
		seen[fx + size_t(fy) * W] = 1;
		while (!q.empty())
		{
			const auto [x, y] = q.front();
			q.pop_front();
			visit(x, y);
			for (int dy = -1; dy <= 1; dy++)
				for (int dx = -1; dx <= 1; dx++)
				{
					const int nx = x + dx, ny = y + dy;
					if (nx < 0 || ny < 0 || nx >= W || ny >= H) continue;
					const size_t i = nx + size_t(ny) * W;
					if (seen[i] || blocked[i]) continue;
					seen[i] = 1;
					q.emplace_back(nx, ny);
				}
		}
	};
	// The nearest cell outside the grown obstacles: within the growth plus two
	// cells (the robot is never deeper in them than the navigator lets it).
	int ox = -1, oy = -1;
	const int reach = int(std::ceil(effectiveRadius(grid, opts) / grid.getResolution())) + 2;
	double nearest = std::numeric_limits<double>::infinity();
	for (int y = std::max(0, sy - reach); y <= std::min(H - 1, sy + reach); y++)
		for (int x = std::max(0, sx - reach); x <= std::min(W - 1, sx + reach); x++)
		{
			const double d = std::hypot(x - sx, y - sy);
			if (!blocked[x + size_t(y) * W] && d < nearest) nearest = d, ox = x, oy = y;
		}
	if (ox < 0) return {};
	// The reachable cell nearest to the goal.
	int bx = ox, by = oy;
	double best = std::hypot(grid.idx2x(ox) - goal.x, grid.idx2y(oy) - goal.y);
	bfs(ox, oy, [&](int x, int y) {
		const double d = std::hypot(grid.idx2x(x) - goal.x, grid.idx2y(y) - goal.y);
		if (d < best) best = d, bx = x, by = y;
	});
	if (best > std::hypot(start.x - goal.x, start.y - goal.y) - grid.getResolution()) return {};
	const mrpt::math::TPoint2D from(grid.idx2x(ox), grid.idx2y(oy)), to(grid.idx2x(bx), grid.idx2y(by));
	PlanResult r = planPath(grid, from, to, opts);
	if (r.found && (ox != sx || oy != sy)) r.path.push_front(from);
	return r;
}

mrpt::maps::CSimplePointsMap obstaclePointsRobotFrame(
	const mrpt::maps::COccupancyGridMap2D& grid, const mrpt::poses::CPose2D& robotPose, const ObstacleOptions& opts)
{
	mrpt::maps::CSimplePointsMap pts;
	const double r2 = opts.maxRange * opts.maxRange;
	for (unsigned cy = 0; cy < grid.getSizeY(); cy++)
		for (unsigned cx = 0; cx < grid.getSizeX(); cx++)
		{
			if (grid.getCell(int(cx), int(cy)) >= opts.maxFreeProbability) continue;
			const double x = grid.idx2x(cx), y = grid.idx2y(cy);
			const double dx = x - robotPose.x(), dy = y - robotPose.y();
			if (dx * dx + dy * dy > r2) continue;
			double lx, ly;
			robotPose.inverseComposePoint(x, y, lx, ly);
			pts.insertPoint(float(lx), float(ly), opts.z);
		}
	return pts;
}

namespace
{
/** MRPT's reactive navigator reads mrpt::Clock::now() (its path-continuation
 * check compares the time since the last command with the PTG's limit, and it
 * interpolates the poses it was given at their timestamps). On the wall clock
 * a run depends on how long each step takes: a slow map (the octomap, up to
 * 0.3 s per frame against 0.05 s of simulated time) makes the navigator see
 * its commands as older and decide differently from one run to the next.
 * While the navigator runs, this sets MRPT's clock to the simulated time
 * instead. The clock is process-wide: one navigator step at a time holds it
 * (gam-navbench --jobs N runs N loops in threads), and the previous clock is
 * back when the step ends. */
class SimulatedClockStep
{
   public:
	explicit SimulatedClockStep(double simulatedSeconds) : m_lock(mutex()), m_previous(mrpt::Clock::getActiveClock())
	{
		// An epoch well away from 0: a zero time_point is MRPT's INVALID_TIMESTAMP.
		mrpt::Clock::setSimulatedTime(mrpt::Clock::fromDouble(kEpoch + simulatedSeconds));
		mrpt::Clock::setActiveClock(mrpt::Clock::Simulated);
	}
	~SimulatedClockStep() { mrpt::Clock::setActiveClock(m_previous); }
	SimulatedClockStep(const SimulatedClockStep&) = delete;
	SimulatedClockStep& operator=(const SimulatedClockStep&) = delete;

   private:
	static constexpr double kEpoch = 1.0e9;
	static std::mutex& mutex()
	{
		static std::mutex m;
		return m;
	}
	std::lock_guard<std::mutex> m_lock;
	mrpt::Clock::Source m_previous;
};

/** The simulated robot: pose and velocity from the kinematic simulator,
 * obstacles from the grid (robot frame). */
class GridSensingRobot : public mrpt::nav::CRobot2NavInterfaceForSimulator_DiffDriven
{
   public:
	/** `believed`: where the robot believes it is (its drifting odometry, kept
	 * by the caller); nullptr = the true pose. */
	GridSensingRobot(
		mrpt::kinematics::CVehicleSimul_DiffDriven& sim, const mrpt::maps::COccupancyGridMap2D& grid,
		const ObstacleOptions& oo, const mrpt::math::TPose2D* believed = nullptr)
		: CRobot2NavInterfaceForSimulator_DiffDriven(sim), m_sim(sim), m_grid(grid), m_oo(oo), m_believed(believed)
	{
	}
	mrpt::math::TPose2D believedPose() const { return m_believed ? *m_believed : m_sim.getCurrentGTPose(); }
	bool getCurrentPoseAndSpeeds(
		mrpt::math::TPose2D& pose, mrpt::math::TTwist2D& vel, mrpt::system::TTimeStamp& t, mrpt::math::TPose2D& odo,
		std::string& frame) override
	{
		const bool ok = CRobot2NavInterfaceForSimulator_DiffDriven::getCurrentPoseAndSpeeds(pose, vel, t, odo, frame);
		pose = believedPose();
		return ok;
	}
	bool senseObstacles(mrpt::maps::CSimplePointsMap& obstacles, mrpt::system::TTimeStamp& t) override
	{
		obstacles = obstaclePointsRobotFrame(m_grid, mrpt::poses::CPose2D(believedPose()), m_oo);
		t = mrpt::system::now();
		return true;
	}
	// quiet: the defaults print every event
	void sendNavigationStartEvent() override {}
	void sendNavigationEndEvent() override {}
	void sendWaySeemsBlockedEvent() override {}
	void sendApparentCollisionEvent() override {}
	void sendCannotGetCloserToBlockedTargetEvent() override {}

   private:
	mrpt::kinematics::CVehicleSimul_DiffDriven& m_sim;
	const mrpt::maps::COccupancyGridMap2D& m_grid;
	ObstacleOptions m_oo;
	const mrpt::math::TPose2D* m_believed;
};

const char* stateName(mrpt::nav::CAbstractNavigator::TState s)
{
	switch (s)
	{
		case mrpt::nav::CAbstractNavigator::IDLE: return "IDLE";
		case mrpt::nav::CAbstractNavigator::NAVIGATING: return "NAVIGATING";
		case mrpt::nav::CAbstractNavigator::SUSPENDED: return "SUSPENDED";
		case mrpt::nav::CAbstractNavigator::NAV_ERROR: return "NAV_ERROR";
	}
	return "?";
}
}  // namespace

namespace
{
/** MRPT's example navigator configuration with the walker's footprint, speed
 * and PTG range. Throws if the base config is missing. */
mrpt::config::CConfigFileMemory navigatorConfig(const ReactiveOptions& opts, double resolution)
{
	std::ifstream f(opts.baseConfig);
	if (!f) throw std::runtime_error("cannot read the reactive navigator config " + opts.baseConfig);
	std::stringstream text;
	text << f.rdbuf();
	mrpt::config::CConfigFileMemory cfg(text.str());
	const double h = opts.robotHalfSize + opts.footprintMarginCells * resolution;
	const std::string xs = mrpt::format("%f %f %f %f", -h, h, h, -h);
	const std::string ys = mrpt::format("%f %f %f %f", h, h, -h, -h);
	cfg.write("CAbstractPTGBasedReactive", "ptg_cache_files_directory", opts.cacheDir);
	cfg.write("CAbstractPTGBasedReactive", "enable_obstacle_filtering", "false");
	cfg.write("CAbstractPTGBasedReactive", "robotMax_V_mps", opts.maxSpeed);
	cfg.write("CAbstractPTGBasedReactive", "ref_distance", opts.refDistance);
	cfg.write("CReactiveNavigationSystem", "RobotModel_shape2D_xs", xs);
	cfg.write("CReactiveNavigationSystem", "RobotModel_shape2D_ys", ys);
	cfg.write("CReactiveNavigationSystem", "RobotModel_circular_shape_radius", h);
	const std::string sec = "CReactiveNavigationSystem";
	if (opts.forwardOnly)
	{
		// Renumber the PTGs whose K is not negative (K = -1: the reversing family)
		// as PTG0, PTG1, ...; the loader reads PTG_COUNT of them.
		std::vector<std::string> keys;
		cfg.getAllKeys(sec, keys);
		const int n = cfg.read_int(sec, "PTG_COUNT", 0);
		int kept = 0;
		std::vector<std::pair<std::string, std::string>> renamed;
		for (int i = 0; i < n; i++)
		{
			if (cfg.read_double(sec, mrpt::format("PTG%d_K", i), 1.0) < 0) continue;
			const std::string from = mrpt::format("PTG%d_", i), to = mrpt::format("PTG%d_", kept);
			for (const auto& k : keys)
				if (k.rfind(from, 0) == 0)
					renamed.emplace_back(to + k.substr(from.size()), cfg.read_string(sec, k, ""));
			kept++;
		}
		if (kept == 0)
			throw std::runtime_error("the reactive navigator config " + opts.baseConfig + " has no forward PTG");
		for (const auto& [k, v] : renamed) cfg.write(sec, k, v);
		cfg.write(sec, "PTG_COUNT", kept);
	}
	for (int i = 0; i < cfg.read_int(sec, "PTG_COUNT", 0); i++)
	{
		cfg.write(sec, mrpt::format("PTG%d_refDistance", i), opts.refDistance);
		cfg.write(sec, mrpt::format("PTG%d_v_max_mps", i), opts.maxSpeed);
	}
	return cfg;
}

/** A navigator for `robot`, configured and initialised. */
std::unique_ptr<mrpt::nav::CReactiveNavigationSystem> makeNavigator(
	mrpt::nav::CRobot2NavInterface& robot, const ReactiveOptions& opts, double resolution)
{
	const auto cfg = navigatorConfig(opts, resolution);
	auto nav = std::make_unique<mrpt::nav::CReactiveNavigationSystem>(robot, false, false);
	nav->setMinLoggingLevel(mrpt::system::LVL_ERROR);
	nav->loadConfigFile(cfg);
	// not read from the .ini by MRPT 2.5.8: set it here (else ReacNavGrid_*.dat.gz land in the cwd)
	nav->params_abstract_ptg_navigator.ptg_cache_files_directory = opts.cacheDir;
	nav->initialize();
	return nav;
}

/** The delay logger dumps its table when destroyed: keep the console quiet. */
void quietDelays(mrpt::nav::CReactiveNavigationSystem& nav)
{
	auto& delays = const_cast<mrpt::system::CTimeLogger&>(nav.getDelaysTimeLogger());
	delays.clear(true);
	delays.enable(false);
}
}  // namespace

ReactiveResult runReactiveNavigation(
	const mrpt::maps::COccupancyGridMap2D& grid, const mrpt::math::TPose2D& start, const mrpt::math::TPoint2D& goal,
	const ReactiveOptions& opts)
{
	mrpt::kinematics::CVehicleSimul_DiffDriven sim;
	sim.setCurrentGTPose(start);
	GridSensingRobot robot(sim, grid, opts.obstacles);
	robot.setMinLoggingLevel(mrpt::system::LVL_ERROR);
	const auto nav = makeNavigator(robot, opts, grid.getResolution());

	mrpt::nav::CAbstractNavigator::TNavigationParams np;
	np.target.target_coords = mrpt::math::TPose2D(goal.x, goal.y, 0);
	np.target.targetAllowedDistance = opts.targetAllowedDistance;
	np.target.targetIsRelative = false;
	{
		const SimulatedClockStep clock(0);
		nav->navigate(&np);
	}

	ReactiveResult r;
	r.trajectory.push_back(sim.getCurrentGTPose());
	for (double t = 0; t < opts.maxTime; t += opts.dt)
	{
		{
			const SimulatedClockStep clock(t);
			nav->navigationStep();
		}
		sim.simulateOneTimeStep(opts.dt);
		r.trajectory.push_back(sim.getCurrentGTPose());
		r.seconds = t + opts.dt;
		if (nav->getCurrentState() != mrpt::nav::CAbstractNavigator::NAVIGATING) break;
	}
	r.endState = stateName(nav->getCurrentState());
	quietDelays(*nav);
	const auto& p = r.trajectory.back();
	r.reached = nav->getCurrentState() == mrpt::nav::CAbstractNavigator::IDLE &&
				std::hypot(p.x - goal.x, p.y - goal.y) <= opts.targetAllowedDistance + 0.1;
	return r;
}

ClosedLoopResult runClosedLoopNavigation(
	const gam::sim::SceneFile& sf, mrpt::maps::COccupancyGridMap2D& grid, const mrpt::math::TPose2D& start,
	const mrpt::math::TPoint2D& goal, const ClosedLoopOptions& opts)
{
	const ReactiveOptions& ro = opts.reactive;
	mrpt::kinematics::CVehicleSimul_DiffDriven sim;
	sim.setCurrentGTPose(start);
	const bool drift = opts.odometryScaleError != 0 || opts.odometryYawDriftDegPerM != 0;
	mrpt::math::TPose2D odometry = start;
	GridSensingRobot robot(sim, grid, ro.obstacles, drift ? &odometry : nullptr);
	robot.setMinLoggingLevel(mrpt::system::LVL_ERROR);
	const auto nav = makeNavigator(robot, ro, grid.getResolution());
	std::mt19937 rng(opts.seed);
	const gam::sim::LeddarModel leddar(sf.leddar);

	ClosedLoopResult r;
	PlanResult plan;
	double nextFrame = 0, nextPlan = 0;
	// A cell along the rest of the plan that the grid now calls an obstacle.
	auto planBlocked = [&]() {
		for (const auto& p : plan.path)
			if (grid.getPos(float(p.x), float(p.y)) < opts.plan.occupancyThreshold) return true;
		return false;
	};
	r.trajectory.push_back(sim.getCurrentGTPose());
	bool navigating = false, noPath = false, turning = false, partialPlan = false, backingUp = false, following = false;
	double stillFor = 0, backedUp = 0, followed = 0;
	PlanOptions planOpts = opts.plan;
	planOpts.footprintHalfSize = ro.robotHalfSize;
	planOpts.footprintMarginCells = ro.footprintMarginCells;
	const double res = grid.getResolution();
	// The navigator's footprint: half side, grown by its margin.
	const double half = ro.robotHalfSize + ro.footprintMarginCells * res;
	// A turn in place sweeps the footprint's circumcircle: clear if no obstacle
	// cell's centre is inside it (the navigator's own rule for its shape).
	auto turnIsClear = [&](const mrpt::math::TPose2D& at) {
		const double R = half * std::sqrt(2.0);
		for (int cy = grid.y2idx(at.y - R); cy <= grid.y2idx(at.y + R); cy++)
			for (int cx = grid.x2idx(at.x - R); cx <= grid.x2idx(at.x + R); cx++)
			{
				if (cx < 0 || cy < 0 || cx >= int(grid.getSizeX()) || cy >= int(grid.getSizeY())) continue;
				if (std::hypot(grid.idx2x(cx) - at.x, grid.idx2y(cy) - at.y) <= R &&
					grid.getCell(cx, cy) < ro.obstacles.maxFreeProbability)
					return false;
			}
		return true;
	};
	// No obstacle cell's centre under the footprint at `p` (the navigator's rule).
	auto footprintClear = [&](const mrpt::poses::CPose2D& p) {
		const double R = half * std::sqrt(2.0);
		for (int cy = grid.y2idx(p.y() - R); cy <= grid.y2idx(p.y() + R); cy++)
			for (int cx = grid.x2idx(p.x() - R); cx <= grid.x2idx(p.x() + R); cx++)
			{
				if (cx < 0 || cy < 0 || cx >= int(grid.getSizeX()) || cy >= int(grid.getSizeY())) continue;
				double lx, ly;
				p.inverseComposePoint(grid.idx2x(cx), grid.idx2y(cy), lx, ly);
				if (std::abs(lx) <= half && std::abs(ly) <= half &&
					grid.getCell(cx, cy) < ro.obstacles.maxFreeProbability)
					return false;
			}
		return true;
	};
	// The plan's point lookAhead metres past its point nearest to `at`.
	auto lookAheadPoint = [&](const mrpt::math::TPose2D& at) {
		size_t i = 0;
		double bestD = 1e18;
		for (size_t k = 0; k < plan.path.size(); k++)
		{
			const double d = std::hypot(plan.path[k].x - at.x, plan.path[k].y - at.y);
			if (d < bestD) bestD = d, i = k;
		}
		while (i + 1 < plan.path.size() && std::hypot(plan.path[i].x - at.x, plan.path[i].y - at.y) < opts.lookAhead)
			i++;
		return plan.path[i];
	};
	auto bearingTo = [](const mrpt::math::TPose2D& at, const mrpt::math::TPoint2D& p) {
		return mrpt::math::wrapToPi(std::atan2(p.y - at.y, p.x - at.x) - at.phi);
	};
	// Pure pursuit of the plan at followSpeed (an arc through the look-ahead
	// point, slower the more it is off the heading); false if there is no plan
	// or the footprint is not clear along the next followCheck seconds of it.
	auto followCommand = [&](const mrpt::math::TPose2D& at, double& v, double& w) {
		if (plan.path.empty()) return false;
		const mrpt::math::TPoint2D la = lookAheadPoint(at);
		const double L = std::hypot(la.x - at.x, la.y - at.y);
		if (L < res) return false;
		const double bearing = mrpt::math::wrapToPi(std::atan2(la.y - at.y, la.x - at.x) - at.phi);
		v = opts.followSpeed * std::max(0.0, std::cos(bearing));
		w = std::clamp(2 * opts.followSpeed * std::sin(bearing) / L, -opts.turnRate, opts.turnRate);
		if (v < 0.2 * opts.followSpeed) return false;  // too far off the heading: the turn logic's case
		for (double s = ro.dt; s <= opts.followCheck + 1e-9; s += ro.dt)
		{
			const mrpt::poses::CPose2D p =
				std::abs(w) < 1e-9
					? mrpt::poses::CPose2D(at) + mrpt::poses::CPose2D(v * s, 0, 0)
					: mrpt::poses::CPose2D(at) +
						  mrpt::poses::CPose2D(v / w * std::sin(w * s), v / w * (1 - std::cos(w * s)), w * s);
			if (!footprintClear(p)) return false;
		}
		return true;
	};
	// Backing up one more step: every cell under the footprint moved back by
	// a cell and a step is one the map holds free (seen).
	auto backupIsClear = [&](const mrpt::math::TPose2D& at) {
		const double back = res + opts.backupSpeed * ro.dt, R = half * std::sqrt(2.0);
		const mrpt::poses::CPose2D behind = mrpt::poses::CPose2D(at) + mrpt::poses::CPose2D(-back, 0, 0);
		for (int cy = grid.y2idx(behind.y() - R); cy <= grid.y2idx(behind.y() + R); cy++)
			for (int cx = grid.x2idx(behind.x() - R); cx <= grid.x2idx(behind.x() + R); cx++)
			{
				double lx, ly;
				behind.inverseComposePoint(grid.idx2x(cx), grid.idx2y(cy), lx, ly);
				if (std::abs(lx) > half || std::abs(ly) > half) continue;
				if (cx < 0 || cy < 0 || cx >= int(grid.getSizeX()) || cy >= int(grid.getSizeY())) return false;
				if (grid.getCell(cx, cy) <= 0.5f) return false;
			}
		return true;
	};
	const bool moving = sf.scene.dynamic();
	gam::sim::Scene frameScene;
	for (double t = 0; t < ro.maxTime; t += ro.dt)
	{
		const mrpt::math::TPose2D gt = sim.getCurrentGTPose(), known = robot.believedPose();
		if (t >= nextFrame)
		{
			// Frame k of the scene (people move per frame), rendered where the robot
			// is, inserted where it believes it is.
			if (moving) frameScene = sf.scene.atFrame(int(r.frames));
			const gam::sim::Scene& scene = moving ? frameScene : sf.scene;
			const auto obs = simulateKinect(sf, scene, gam::sim::Pose2{gt.x, gt.y, gt.phi}, rng);
			const mrpt::poses::CPose3D believed(known.x, known.y, 0, known.phi, 0, 0);
			grid.insertObservation(*obs, believed);
			if (sf.leddar_enabled)
			{
				// The walker's Leddar, in the same step (the grid's own rule for 2D scans).
				const gam::sim::Pose3 robot3 = gam::sim::Pose3::fromXYZYPR(gt.x, gt.y, 0, gt.phi, 0, 0);
				const gam::sim::LeddarScan ls = leddar.scan(scene, robot3 * sf.leddar_pose, rng);
				grid.insertObservation(
					*gam::sim::toLeddarObservation(sf.leddar, ls, toCPose3D(sf.leddar_pose)), believed);
				r.leddarScans++;
			}
			r.frames++;
			nextFrame += opts.frameInterval;
		}
		if (t >= nextPlan || (navigating && !noPath && planBlocked()))
		{
			PlanResult p = planPath(grid, {known.x, known.y}, goal, planOpts);
			bool towards = false;
			if (!p.found && opts.planTowardsGoalWhenNoPath)
			{
				p = planTowards(grid, {known.x, known.y}, goal, planOpts);
				towards = p.found;
			}
			nextPlan = t + opts.replanInterval;
			noPath = !p.found;
			if (!p.found)
			{
				r.failedPlans++;
				if (opts.turnInPlace) nextPlan = t + 0.5;  // look again after a few degrees of turning
			}
			if (p.found)
			{
				plan = p;
				partialPlan = towards;
				r.plans++;
				r.partialPlans += towards;
				// Waypoints every waypointSpacing along the path, and its end: the goal,
				// or the cell nearest to it (planTowards).
				mrpt::nav::TWaypointSequence wps;
				double since = 0;
				for (size_t i = 1; i < plan.path.size(); i++)
				{
					since += (plan.path[i] - plan.path[i - 1]).norm();
					if (since >= opts.waypointSpacing && i + 1 < plan.path.size())
					{
						wps.waypoints.emplace_back(plan.path[i].x, plan.path[i].y, 0.5, true);
						since = 0;
					}
				}
				const mrpt::math::TPoint2D end = partialPlan ? plan.path.back() : goal;
				wps.waypoints.emplace_back(end.x, end.y, ro.targetAllowedDistance, false);
				const SimulatedClockStep clock(t);
				nav->navigateWaypoints(wps);
				navigating = true;
			}
		}
		// Backing out of a dead end: until the turn is clear, backupMax, or the
		// cells behind are not known free; then turn towards the plan.
		double probeV, probeW;
		if (backingUp && (backedUp >= opts.backupMax || !backupIsClear(known) || followCommand(known, probeV, probeW)))
		{
			backingUp = false;
			stillFor = 0;
			turning = true;  // down to turnStopDeg
			nextPlan = t;
		}
		// Following the plan where the navigator stood still: up to the next
		// waypoint's spacing, while each step is clear; then the navigator again.
		double followV = 0, followW = 0;
		if (following && (followed >= opts.waypointSpacing || !followCommand(known, followV, followW)))
		{
			following = false;
			stillFor = 0;
			nextPlan = t;
		}
		// Look before driving: turn in place towards the plan, or to look around
		// when there is no plan; otherwise the navigator drives.
		double turn = 0;
		if (backingUp || following)
			;
		else if (opts.turnInPlace && noPath)
			turn = 1;
		else if (opts.turnInPlace && navigating && !plan.path.empty())
		{
			const mrpt::math::TPoint2D la = lookAheadPoint(known);
			const double bearing = mrpt::math::wrapToPi(std::atan2(la.y - known.y, la.x - known.x) - known.phi);
			const double lim = mrpt::DEG2RAD(turning ? opts.turnStopDeg : opts.turnStartDeg);
			const bool far = std::hypot(la.x - known.x, la.y - known.y) > ro.targetAllowedDistance;
			if (far && std::abs(bearing) > lim) turn = bearing > 0 ? 1 : -1;
		}
		if (turn != 0 && !turnIsClear(known)) turn = 0;
		turning = turn != 0;
		if (following)
		{
			sim.movementCommand(followV, followW);
			followed += std::abs(followV) * ro.dt;
			r.followSeconds += ro.dt;
		}
		else if (backingUp)
		{
			sim.movementCommand(-opts.backupSpeed, 0);
			backedUp += opts.backupSpeed * ro.dt;
			r.backupSeconds += ro.dt;
		}
		else if (turning)
		{
			sim.movementCommand(0, turn * opts.turnRate);
			r.turningSeconds += ro.dt;
		}
		else
		{
			{
				const SimulatedClockStep clock(t);
				nav->navigationStep();
			}
			// Standing still while the navigator drives (its local minimum: the
			// target behind an obstacle). Follow the plan if its next steps are
			// clear, else back out if the cells behind are known free.
			const mrpt::math::TTwist2D v = sim.getCurrentGTVelLocal();
			const bool still = std::abs(v.vx) < 1e-3 && std::abs(v.omega) < 1e-3;
			stillFor = navigating && still ? stillFor + ro.dt : 0;
			double fv, fw;
			if (stillFor < opts.stallSeconds || plan.path.empty())
				;
			else if (opts.followPlanWhenStill && followCommand(known, fv, fw))
			{
				following = true;
				followed = 0;
				r.planFollows++;
			}
			else if (
				opts.turnInPlace && turnIsClear(known) &&
				std::abs(bearingTo(known, lookAheadPoint(known))) > mrpt::DEG2RAD(opts.turnStopDeg))
			{
				turning = true;  // the next steps turn down to turnStopDeg
				stillFor = 0;
			}
			else if (opts.backUpWhenStill && backupIsClear(known))
			{
				backingUp = true;
				backedUp = 0;
				r.backups++;
			}
		}
		sim.simulateOneTimeStep(ro.dt);
		if (drift)
		{
			// The true step in the robot frame, as the odometry measures it.
			const mrpt::poses::CPose2D step = mrpt::poses::CPose2D(sim.getCurrentGTPose()) - mrpt::poses::CPose2D(gt);
			const double dist = std::hypot(step.x(), step.y());
			const mrpt::poses::CPose2D measured(
				step.x() * (1 + opts.odometryScaleError), step.y() * (1 + opts.odometryScaleError),
				step.phi() + mrpt::DEG2RAD(opts.odometryYawDriftDegPerM) * dist);
			odometry = (mrpt::poses::CPose2D(odometry) + measured).asTPose();
		}
		r.trajectory.push_back(sim.getCurrentGTPose());
		r.seconds = t + ro.dt;
		if (opts.onStep && !opts.onStep(r.seconds, r.trajectory.back()))
		{
			r.stoppedByCallback = true;
			break;
		}
		if (navigating && nav->getWaypointNavStatus().final_goal_reached)
		{
			if (!partialPlan) break;
			// at the end of a plan towards the goal: plan again from here
			if (nextPlan > r.seconds) nextPlan = r.seconds;
		}
		if (navigating && nav->getCurrentState() == mrpt::nav::CAbstractNavigator::NAV_ERROR) break;
	}
	r.endState = stateName(nav->getCurrentState());
	quietDelays(*nav);
	const auto& p = r.trajectory.back();
	r.reached = std::hypot(p.x - goal.x, p.y - goal.y) <= ro.targetAllowedDistance + 0.1;
	const mrpt::math::TPose2D odo = robot.believedPose();
	r.finalOdometryError = std::hypot(odo.x - p.x, odo.y - p.y);
	return r;
}

double distanceToHoles(const gam::sim::Scene& scene, double x, double y, double step)
{
	double best = std::numeric_limits<double>::infinity();
	for (const auto& h : scene.holes)
	{
		if (h.containsXY(x, y)) return 0;
		const double R = h.shape == gam::sim::Hole::Circle ? h.r : std::hypot(h.hx, h.hy);
		for (double sx = h.cx - R; sx <= h.cx + R; sx += step)
			for (double sy = h.cy - R; sy <= h.cy + R; sy += step)
				if (h.containsXY(sx, sy)) best = std::min(best, std::hypot(sx - x, sy - y));
	}
	return best;
}

void savePathPicture(
	const mrpt::maps::COccupancyGridMap2D& grid, const PlanResult& plan, const mrpt::math::TPoint2D& start,
	const mrpt::math::TPoint2D& goal, const std::string& file, int scale)
{
	const int W = int(grid.getSizeX()), H = int(grid.getSizeY());
	mrpt::img::CImage img(W * scale, H * scale, mrpt::img::CH_RGB);
	auto cellRect = [&](int cx, int cy, const mrpt::img::TColor& c) {
		const int px = cx * scale, py = (H - 1 - cy) * scale;  // +y up
		img.filledRectangle(px, py, px + scale - 1, py + scale - 1, c);
	};
	for (int cy = 0; cy < H; cy++)
		for (int cx = 0; cx < W; cx++)
		{
			const uint8_t g = uint8_t(std::lround(255.0 * grid.getCell(cx, cy)));
			cellRect(cx, cy, mrpt::img::TColor(g, g, g));
		}
	for (const auto& p : plan.path) cellRect(grid.x2idx(p.x), grid.y2idx(p.y), {255, 0, 0});
	cellRect(grid.x2idx(start.x), grid.y2idx(start.y), {0, 200, 0});
	cellRect(grid.x2idx(goal.x), grid.y2idx(goal.y), {0, 0, 255});
	if (!img.saveToFile(file)) throw std::runtime_error("cannot write " + file);
}

}  // namespace gam::nav
