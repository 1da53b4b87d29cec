// Issue #29, closed loop: the walker maps while it drives. From the nav
// example's default start (0, 0), straight at the floor hatch (x 2.2-2.8,
// |y| <= 0.3) on the way to (4.5, 0), the grid is empty at the start: every
// 0.1 s the simulated Kinect's frame is inserted, PlannerSimple2D plans on the
// grid as it is, and MRPT's reactive navigator follows the plan's waypoints.
// The ground-aware grid sees the hatch and the robot drives around it; the
// height band never sees it and the robot drives over it.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <iostream>

#include "NavExample.h"

namespace
{
struct ClosedLoop : public ::testing::Test
{
	static void SetUpTestSuite()
	{
		sf = std::make_unique<gam::sim::SceneFile>(
			gam::sim::parseSceneFile(std::string(GAM_SOURCE_DIR) + "/config/scenes/nav_hole.scene"));
		cacheDir = std::string(GAM_TEST_TMP_DIR) + "/cl_ptg" + std::to_string(getpid());
		std::filesystem::create_directories(cacheDir);
	}
	static void TearDownTestSuite()
	{
		std::filesystem::remove_all(cacheDir);
		sf.reset();
	}
	template <class Grid>
	static gam::nav::ClosedLoopResult drive(Grid& g)
	{
		g.setSize(-1.0f, 6.0f, -2.0f, 2.0f, 0.05f, 0.5f);  // the scene's grid line
		gam::nav::ClosedLoopOptions o;
		o.reactive.cacheDir = cacheDir;
		o.reactive.maxTime = 60;
		return gam::nav::runClosedLoopNavigation(*sf, g, {0, 0, 0}, {4.5, 0}, o);
	}
	static double closestToHole(const gam::nav::ClosedLoopResult& r)
	{
		double d = 1e9;
		for (const auto& p : r.trajectory) d = std::min(d, gam::nav::distanceToHoles(sf->scene, p.x, p.y));
		return d;
	}
	static std::unique_ptr<gam::sim::SceneFile> sf;
	static std::string cacheDir;
};
std::unique_ptr<gam::sim::SceneFile> ClosedLoop::sf;
std::string ClosedLoop::cacheDir;

bool haveConfig() { return std::filesystem::exists(gam::nav::ReactiveOptions{}.baseConfig); }
}  // namespace

TEST_F(ClosedLoop, GroundAwareMapBuiltOnTheWayReachesTheGoalAroundTheHatch)
{
	if (!haveConfig()) GTEST_SKIP() << "mrpt-common's reactive2d_config.ini is not installed";
	mrpt::maps::CGroundAwareOccupancyGrid g;
	const auto r = drive(g);
	ASSERT_GE(r.trajectory.size(), 2u);
	std::cout << "[closed loop] ground_aware: " << (r.reached ? "goal reached" : "goal NOT reached") << " in "
			  << r.seconds << " s, " << r.frames << " frames, " << r.plans << " plans, closest to the hatch "
			  << closestToHole(r) << " m\n";
	EXPECT_TRUE(r.reached) << r.endState << " after " << r.seconds << " s at (" << r.trajectory.back().x << ", "
						   << r.trajectory.back().y << "), " << r.plans << " plans";
	EXPECT_GT(r.frames, 10u);
	EXPECT_GE(r.plans, 2) << "the first plan (empty grid: straight) and at least one after the hatch was seen";
	// The robot's centre never comes within its half size (0.25 m) of the hatch:
	// no wheel of the footprint over it.
	EXPECT_GT(closestToHole(r), 0.25) << "the robot's footprint went over the hatch";
}

TEST_F(ClosedLoop, HeightBandMapBuiltOnTheWayDrivesOverTheHatch)
{
	if (!haveConfig()) GTEST_SKIP() << "mrpt-common's reactive2d_config.ini is not installed";
	mrpt::maps::CHeightBandOccupancyGrid g;
	const auto r = drive(g);
	std::cout << "[closed loop] height_band: " << (r.reached ? "goal reached" : "goal NOT reached") << " in "
			  << r.seconds << " s, closest to the hatch " << closestToHole(r) << " m\n";
	EXPECT_LT(closestToHole(r), 0.25) << "the height band should not see the hatch";
}

TEST_F(ClosedLoop, WithOdometryDriftTheMapIsBuiltWhereTheRobotBelievesItIs)
{
	// A 2 % distance error and 1 deg of heading per metre: at the goal, 4.5 m
	// and a detour further, the odometry is off by 2 % of ~5 m (10 cm) plus
	// the heading's sweep (about 5 m x 0.5 x 5 deg in rad = 0.2 m), some
	// 0.1-0.3 m. The robot maps and plans at its believed poses and still goes
	// around the hatch (0.6 m wide; the margin without drift is 3 cm, so a
	// fall-free run is not guaranteed for larger drift: issue #29's benchmark).
	if (!haveConfig()) GTEST_SKIP() << "mrpt-common's reactive2d_config.ini is not installed";
	mrpt::maps::CGroundAwareOccupancyGrid g;
	g.setSize(-1.0f, 6.0f, -2.0f, 2.0f, 0.05f, 0.5f);
	gam::nav::ClosedLoopOptions o;
	o.reactive.cacheDir = cacheDir;
	o.reactive.maxTime = 60;
	o.odometryScaleError = 0.02;
	o.odometryYawDriftDegPerM = 1.0;
	const auto r = gam::nav::runClosedLoopNavigation(*sf, g, {0, 0, 0}, {4.5, 0}, o);
	std::cout << "[closed loop, drift] ground_aware: " << (r.reached ? "goal reached" : "goal NOT reached") << " in "
			  << r.seconds << " s, odometry off by " << r.finalOdometryError << " m, closest to the hatch "
			  << closestToHole(r) << " m\n";
	EXPECT_GT(r.finalOdometryError, 0.05) << "the drift is on";
	EXPECT_LT(r.finalOdometryError, 0.5);
	EXPECT_GT(closestToHole(r), 0.0) << "drove into the hatch";
}
