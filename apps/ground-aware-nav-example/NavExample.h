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

struct PlanOptions
{
	float robotRadius = 0.30f;  ///< PlannerSimple2D::robotRadius [m]
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
	/** The navigator's shape is the footprint grown by this [m] (its obstacles
	 * are cell centres, so the footprint may reach half a cell into an
	 * occupied cell). 0: one 5 cm cell, tried on gam-navbench, left 7 of the
	 * first 25 ground-aware runs stuck in front of obstacles (2 in seeds 1-30
	 * without it): the navigator finds fewer admissible motions. */
	double footprintMargin = 0;
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
	ReactiveOptions reactive;      ///< the navigator, the simulated robot, dt and the time limit
	PlanOptions plan;              ///< the global planner (PlannerSimple2D) on the current grid
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
	 * Only where the turn is safe on the current grid: no obstacle cell
	 * (ObstacleOptions::maxFreeProbability) within the circle the square
	 * footprint sweeps (robotHalfSize * sqrt(2)) plus one cell; otherwise the
	 * navigator, which checks its motions against the obstacles, drives. */
	bool turnInPlace = true;
	double lookAhead = 0.6;    ///< [m]
	double turnStartDeg = 60;  ///< [deg]
	double turnStopDeg = 15;   ///< [deg]
	double turnRate = 0.6;     ///< [rad/s]
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
