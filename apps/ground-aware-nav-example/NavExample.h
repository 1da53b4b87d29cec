// Ground-aware mapping for MRPT -- navigation example (library part).
//
// Maps a simulated scene (libs/ground_sim) with CGroundAwareOccupancyGrid and
// with the height-band baseline CHeightBandOccupancyGrid, plans on each grid
// with mrpt::nav::PlannerSimple2D, and exports the occupied cells of a grid as
// the robot-frame obstacle points MRPT's reactive navigator consumes
// (CRobot2NavInterface::senseObstacles() fills a CSimplePointsMap of obstacles
// in the robot frame; CReactiveNavigationSystem keeps the points whose z is in
// [min_obstacles_height, max_obstacles_height]).
//
// Used by apps/ground-aware-nav-example and tests/nav.
#pragma once

#include <mrpt/maps/CGroundAwareOccupancyGrid.h>
#include <mrpt/maps/CHeightBandOccupancyGrid.h>
#include <mrpt/maps/CSimplePointsMap.h>
#include <mrpt/math/TPoint2D.h>
#include <mrpt/math/TPose2D.h>
#include <mrpt/obs/CObservation3DRangeScan.h>
#include <mrpt/poses/CPose2D.h>
#include <mrpt/poses/CPose3D.h>

#include <deque>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include "gam/sim/SceneFile.h"

namespace gam::nav
{
/** The depth frame a simulated Kinect takes at a robot pose, as the
 * CObservation3DRangeScan gam-simulate writes (range image in mm, depth along
 * +X, the scene's sensor pose and intrinsics). `sensorNoise` false = exact. */
mrpt::obs::CObservation3DRangeScan::Ptr simulateKinect(
	const gam::sim::SceneFile& sf, const gam::sim::Pose2& robot, std::mt19937& rng);
/** The same in `scene` (e.g. sf.scene.atFrame(f): the people where they are
 * then), with sf's camera. */
mrpt::obs::CObservation3DRangeScan::Ptr simulateKinect(
	const gam::sim::SceneFile& sf, const gam::sim::Scene& scene, const gam::sim::Pose2& robot, std::mt19937& rng);

/** The two grids of one mapping run over the scene's path. */
struct NavMaps
{
	mrpt::maps::CGroundAwareOccupancyGrid groundAware;
	mrpt::maps::CHeightBandOccupancyGrid heightBand;
	std::vector<mrpt::poses::CPose2D> robotPoses;  ///< one per frame (true poses)
	size_t framesWithGround = 0;                   ///< frames where RRT-GPD found the floor
};

struct MapOptions
{
	bool noise = true;  ///< simulate sensor noise (the scene's Kinect model)
	unsigned seed = 1;
};

/** Renders every frame of the scene's path with the Kinect model and inserts
 * it into both grids (extent = the scene's `grid` line, or the path +- 5 m).
 * Both grids keep their default options (paper Table I, band 0.2-1.5 m). */
void buildMaps(const gam::sim::SceneFile& sf, const MapOptions& opts, NavMaps& out);

/** The smallest PlannerSimple2D::robotRadius whose obstacle growth keeps a
 * square footprint of half side `halfSide` off every obstacle cell in any
 * heading. PlannerSimple2D grows each obstacle cell by n = ceil(radius /
 * resolution) cells in a square (8-neighbour dilation), so a path cell's
 * centre is at least n + 1/2 cells from the near edge of any obstacle cell
 * along an axis; the footprint turned by 45 deg reaches halfSide * sqrt(2)
 * (its circumcircle). n = ceil(halfSide * sqrt(2) / resolution - 1/2); the
 * radius returned is (n - 1/2) * resolution, well inside ceil()'s step. E.g.
 * 0.25 m, 5 cm cells: n = 7 (0.325 m); 0.30 m: n = 8 (0.375 m). */
double plannerRadiusForFootprint(double halfSide, double resolution);

struct PlanOptions
{
	/** PlannerSimple2D::robotRadius [m]; 0 or less: plannerRadiusForFootprint(
	 * footprintHalfSize + footprintMarginCells cells, the grid's resolution). */
	float robotRadius = 0.30f;
	double footprintHalfSize = 0.25;  ///< used when robotRadius <= 0 [m]
	double footprintMarginCells = 1;  ///< used when robotRadius <= 0 [cells]
	/** PlannerSimple2D::occupancyThreshold: cells whose FREE probability is
	 * below it are obstacles (unknown cells, 0.5, are traversable). */
	float occupancyThreshold = 0.45f;
	float minStepInReturnedPath = 0.05f;  ///< dense path, one point per cell
	float maxSearchPathLength = -1;
};

struct PlanResult
{
	bool found = false;
	std::deque<mrpt::math::TPoint2D> path;  ///< map frame, start to goal
	double length = 0;                      ///< [m]
	/** Largest |y - straight line| of the path from start to goal [m]. */
	double maxDeviation = 0;
};

PlanResult planPath(
	const mrpt::maps::COccupancyGridMap2D& grid, const mrpt::math::TPoint2D& start, const mrpt::math::TPoint2D& goal,
	const PlanOptions& opts = {});

/** The cells PlannerSimple2D does not enter with `opts` (1 = blocked, x + y *
 * sizeX): cells whose free probability is at most occupancyThreshold, grown
 * by ceil(radius / resolution) cells in a square, as the planner grows them. */
std::vector<uint8_t> plannerBlockedCells(const mrpt::maps::COccupancyGridMap2D& grid, const PlanOptions& opts);

/** When planPath() finds no path: a path from the cell outside the planner's
 * grown obstacles nearest to `start` (start itself if it is outside) to the
 * cell reachable from there that is nearest to `goal`. found = false if that
 * cell is not closer to the goal than the start by more than a cell. */
PlanResult planTowards(
	const mrpt::maps::COccupancyGridMap2D& grid, const mrpt::math::TPoint2D& start, const mrpt::math::TPoint2D& goal,
	const PlanOptions& opts = {});

struct ObstacleOptions
{
	/** A cell is an obstacle if its FREE probability is below this. */
	float maxFreeProbability = 0.4f;
	double maxRange = 6.0;  ///< only cells within this distance of the robot [m]
	/** z of every point. The grid is 2D; any z inside the reactive navigator's
	 * [min_obstacles_height, max_obstacles_height] works (defaults 0..10). */
	float z = 0.1f;
};

/** The occupied cells of `grid` (cell centres) within maxRange of the robot,
 * in the ROBOT frame (p_robot = robotPose (-) p_map), as the CSimplePointsMap
 * CRobot2NavInterface::senseObstacles() returns to CReactiveNavigationSystem. */
mrpt::maps::CSimplePointsMap obstaclePointsRobotFrame(
	const mrpt::maps::COccupancyGridMap2D& grid, const mrpt::poses::CPose2D& robotPose,
	const ObstacleOptions& opts = {});

struct ReactiveOptions
{
	/** MRPT's example reactive-navigator configuration (package mrpt-common);
	 * the keys below override it. */
	std::string baseConfig = "/usr/share/mrpt/config_files/navigation-ptgs/reactive2d_config.ini";
	std::string cacheDir = "/tmp";  ///< PTG look-up table cache files go here
	double robotHalfSize = 0.25;    ///< square robot footprint, half side [m]
	/** The navigator's shape is the footprint grown by this many cells of the
	 * grid. Its obstacles are the centres of occupied cells, and a cell only
	 * partly over a pit may be held free by the map while the ground truth
	 * (and the wheel) has a drop there: the cell next to an occupied one.
	 * Grown by one cell, the footprint keeps that neighbour's centre out.
	 * 0 here (the navigator alone, runReactiveNavigation: with one cell it
	 * stalls in front of the hatch from (0, 0.4), NAV_ERROR); the closed loop,
	 * which backs out of such stalls, uses 1 (ClosedLoopOptions). */
	double footprintMarginCells = 0;
	double refDistance = 4.0;  ///< PTG range [m]
	double maxSpeed = 0.5;     ///< [m/s]
	double maxTime = 40;       ///< simulated seconds
	double dt = 0.05;          ///< simulation step [s]
	float targetAllowedDistance = 0.3f;
	/** Keep only the forward path families (PTGs) of the base config: MRPT's
	 * example has a reversing one (CPTG_DiffDrive_C with K = -1), and the
	 * walker's camera and Leddar look forward: reversing, it drives where it
	 * has never looked (unknown cells are no obstacles), e.g. back into an
	 * unseen hole, and a walker is pushed forward by its user anyway. */
	bool forwardOnly = true;
	ObstacleOptions obstacles;
};

struct ReactiveResult
{
	bool reached = false;                         ///< the navigator ended (IDLE) within targetAllowedDistance
	std::string endState;                         ///< IDLE / NAVIGATING / SUSPENDED / NAV_ERROR
	std::vector<mrpt::math::TPose2D> trajectory;  ///< simulated robot poses
	double seconds = 0;                           ///< simulated time used
};

/** Closed loop with MRPT's reactive navigator: a CReactiveNavigationSystem
 * (config: opts.baseConfig + overrides) drives a simulated differential robot
 * (CVehicleSimul_DiffDriven) from `start` to `goal`; at every step its
 * senseObstacles() returns obstaclePointsRobotFrame(grid, current pose). The
 * grid is static (already mapped). Throws if the base config is missing. */
ReactiveResult runReactiveNavigation(
	const mrpt::maps::COccupancyGridMap2D& grid, const mrpt::math::TPose2D& start, const mrpt::math::TPoint2D& goal,
	const ReactiveOptions& opts = {});

struct ClosedLoopOptions
{
	/** The navigator, the simulated robot, dt and the time limit; the
	 * footprint grown by one cell (ReactiveOptions::footprintMarginCells). */
	ReactiveOptions reactive = [] {
		ReactiveOptions r;
		r.footprintMarginCells = 1;
		return r;
	}();
	/** The global planner (PlannerSimple2D) on the current grid; its radius
	 * from the navigator's footprint (reactive.robotHalfSize and
	 * footprintMarginCells) unless set > 0. */
	PlanOptions plan{0.0f};
	double frameInterval = 0.1;    ///< simulated time between depth frames [s] (10 Hz)
	double replanInterval = 2.0;   ///< the global plan is redone at least this often [s]
	double waypointSpacing = 1.0;  ///< waypoints along the planned path [m]
	unsigned seed = 1;             ///< sensor noise
	/** Odometry drift: the odometry integrates the true motion with its
	 * distance scaled by (1 + odometryScaleError) and its heading turned by
	 * odometryYawDriftDegPerM degrees per metre travelled. With drift the
	 * robot knows its odometry only: frames are inserted, plans start and
	 * obstacles are sensed at the odometry pose; the trajectory (falls,
	 * arrival) is the true one. 0, 0 = exact odometry. */
	double odometryScaleError = 0;
	double odometryYawDriftDegPerM = 0;
	/** Look before driving (issue #29, a forward-only walker whose camera sees
	 * ~70 deg ahead): when the plan's point lookAhead metres ahead is more
	 * than turnStartDeg off the heading, the robot turns in place towards it
	 * (turnRate) until it is within turnStopDeg, instead of letting the
	 * navigator drive an arc into cells it has not looked at; and when the
	 * planner finds no path on the current grid, it turns in place to look
	 * around (and replans every 0.5 s) instead of following the stale plan.
	 * Only where the turn is safe on the current grid: no obstacle cell's
	 * centre (ObstacleOptions::maxFreeProbability) within the circle the
	 * navigator's footprint sweeps ((robotHalfSize + footprintMarginCells
	 * cells) * sqrt(2): the navigator's own rule for its shape); otherwise
	 * the navigator, which checks its motions against the obstacles, drives. */
	bool turnInPlace = true;
	double lookAhead = 0.6;    ///< [m]
	double turnStartDeg = 60;  ///< [deg]
	double turnStopDeg = 15;   ///< [deg]
	double turnRate = 0.6;     ///< [rad/s]
	/** Back out of a dead end. The navigator drives forward only; in front of
	 * an obstacle, closer than the turn in place needs, it can stand still
	 * with a plan around the obstacle (gam-navbench seeds 12 and 29: 0.4 m
	 * before a box and an outlet, 14 s without a command). When the robot has
	 * stood still for stallSeconds while the navigator drives, it backs up
	 * straight at backupSpeed, only over cells the map holds free (p_free >
	 * 0.5: seen; the camera looks forward, so behind the robot these are the
	 * cells it saw on its way in), until the turn in place is clear or it has
	 * backed up backupMax, and then turns towards the plan. */
	bool backUpWhenStill = true;
	double stallSeconds = 1.0;  ///< [s]
	double backupSpeed = 0.2;   ///< [m/s]
	double backupMax = 0.5;     ///< [m], the footprint's side
	/** Before backing up, the robot follows the plan itself (pure pursuit of
	 * the lookAhead point at followSpeed) for waypointSpacing metres if the
	 * footprint is clear of obstacle cells (the navigator's rule) along the
	 * next followCheck seconds of the arc, every step: in front of an outlet
	 * with the plan around it, the navigator, whose target is the next
	 * waypoint behind the outlet, stands still where the plan's arc is free. */
	bool followPlanWhenStill = true;
	double followSpeed = 0.25;  ///< [m/s]
	double followCheck = 0.4;   ///< [s]
	/** No path to the goal on the current grid (seed 41: cells around the goal
	 * at 4 m that far-range noise holds occupied; seed 1009 of the doc: the
	 * robot's own cell inside an obstacle grown by the planner's radius):
	 * plan from the nearest cell outside the grown obstacles to the cell
	 * reachable from there that is nearest to the goal, drive there (the
	 * camera sees the goal's cells better from closer) and plan again.
	 * Without such a cell, turn in place and look (turnInPlace). */
	bool planTowardsGoalWhenNoPath = true;
	/** Called after every simulation step with the simulated time and the
	 * robot's TRUE pose; returning false ends the run there (a benchmark's
	 * fall, collision or no progress). */
	std::function<bool(double t, const mrpt::math::TPose2D& truePose)> onStep;
};

struct ClosedLoopResult : ReactiveResult
{
	size_t frames = 0;               ///< depth frames rendered and inserted
	size_t leddarScans = 0;          ///< Leddar scans (one with each depth frame if the scene has a Leddar)
	int plans = 0;                   ///< global plans computed (the first and the replans)
	int failedPlans = 0;             ///< planner calls that found no path
	double turningSeconds = 0;       ///< time spent turning in place (turnInPlace)
	int partialPlans = 0;            ///< plans to the reachable cell nearest the goal (planTowardsGoalWhenNoPath)
	int backups = 0;                 ///< times the robot backed out of a dead end
	int planFollows = 0;             ///< times the robot followed the plan itself (followSpeed)
	double followSeconds = 0;        ///< time spent following the plan itself
	double backupSeconds = 0;        ///< time spent backing up
	double finalOdometryError = 0;   ///< |odometry - true| at the end [m]
	bool stoppedByCallback = false;  ///< opts.onStep returned false
};

/** Issue #29, closed loop: the walker maps while it drives. Every
 * frameInterval the scene's Kinect renders a depth frame at the robot's true
 * pose (frame k at time k * frameInterval, in the scene as it is in its frame
 * k: Scene::atFrame, so that people cross as the scene file makes them),
 * with the scene's Leddar scan if it has one, and `grid` (a fresh or
 * stock-started grid; it is updated) inserts them
 * at the odometry pose (exact unless opts sets a drift). PlannerSimple2D plans on the current
 * grid from the robot to `goal`; CReactiveNavigationSystem follows that plan
 * as a waypoint sequence (navigateWaypoints), with obstacles from the current
 * grid (senseObstacles), and the plan is redone every replanInterval and as
 * soon as a cell along it turns into an obstacle. Ends when the last
 * waypoint is reached, the navigator stops, or at opts.reactive.maxTime. */
ClosedLoopResult runClosedLoopNavigation(
	const gam::sim::SceneFile& sf, mrpt::maps::COccupancyGridMap2D& grid, const mrpt::math::TPose2D& start,
	const mrpt::math::TPoint2D& goal, const ClosedLoopOptions& opts = {});

/** Smallest distance [m] from a point to the union of the scene's holes
 * (0 inside one), sampled on a grid of `step` metres inside each hole. */
double distanceToHoles(const gam::sim::Scene& scene, double x, double y, double step = 0.01);

/** Writes a PNG picture of the grid with the path drawn over it (red) and the
 * start (green) and goal (blue), one pixel per cell scaled by `scale`. */
void savePathPicture(
	const mrpt::maps::COccupancyGridMap2D& grid, const PlanResult& plan, const mrpt::math::TPoint2D& start,
	const mrpt::math::TPoint2D& goal, const std::string& file, int scale = 4);

}  // namespace gam::nav
