// Navigation example (apps/ground-aware-nav-example): a floor hatch on the
// straight line from start to goal. PlannerSimple2D must go around it on the
// ground-aware grid and straight through it on the height-band grid, and the
// ground-aware obstacle points (robot frame, for CReactiveNavigationSystem)
// must contain the hatch.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <set>

#include "NavExample.h"

namespace
{
const mrpt::math::TPoint2D kStart{0, 0}, kGoal{4.5, 0};

class NavExample : public ::testing::Test
{
   protected:
	static void SetUpTestSuite()
	{
		sf = std::make_unique<gam::sim::SceneFile>(
			gam::sim::parseSceneFile(std::string(GAM_SOURCE_DIR) + "/config/scenes/nav_hole.scene"));
		maps = std::make_unique<gam::nav::NavMaps>();
		gam::nav::buildMaps(*sf, gam::nav::MapOptions{}, *maps);
	}
	static void TearDownTestSuite()
	{
		maps.reset();
		sf.reset();
	}
	/** Centres of the grid cells whose centre lies inside a hole. */
	static std::vector<mrpt::math::TPoint2D> holeCells(const mrpt::maps::COccupancyGridMap2D& g)
	{
		std::vector<mrpt::math::TPoint2D> out;
		for (unsigned cy = 0; cy < g.getSizeY(); cy++)
			for (unsigned cx = 0; cx < g.getSizeX(); cx++)
			{
				const double x = g.idx2x(cx), y = g.idx2y(cy);
				for (const auto& h : sf->scene.holes)
					if (h.containsXY(x, y)) out.emplace_back(x, y);
			}
		return out;
	}
	static std::unique_ptr<gam::sim::SceneFile> sf;
	static std::unique_ptr<gam::nav::NavMaps> maps;
};
std::unique_ptr<gam::sim::SceneFile> NavExample::sf;
std::unique_ptr<gam::nav::NavMaps> NavExample::maps;
}  // namespace

TEST_F(NavExample, SceneHasAHoleOnTheStraightLine)
{
	ASSERT_EQ(sf->scene.holes.size(), 1u);
	EXPECT_EQ(gam::nav::distanceToHoles(sf->scene, 2.5, 0.0), 0.0);
	EXPECT_EQ(maps->framesWithGround, maps->robotPoses.size());
	EXPECT_GE(maps->robotPoses.size(), 5u);
}

TEST_F(NavExample, GroundAwarePathGoesAroundTheHole)
{
	gam::nav::PlanOptions po;  // robotRadius 0.30
	const auto plan = gam::nav::planPath(maps->groundAware, kStart, kGoal, po);
	ASSERT_TRUE(plan.found);
	const auto holes = holeCells(maps->groundAware);
	ASSERT_GT(holes.size(), 100u);  // 0.6 x 0.6 m at 5 cm
	double closest = 1e9;
	for (const auto& p : plan.path)
		for (const auto& h : holes) closest = std::min(closest, (p - h).norm());
	EXPECT_GE(closest, po.robotRadius) << "a path cell is within robotRadius of the hole";
	EXPECT_GT(plan.maxDeviation, 0.3 + po.robotRadius - 0.05);  // it had to swerve
	EXPECT_NEAR(plan.path.back().x, kGoal.x, 1e-6);
	EXPECT_LT(plan.length, 7.0);
}

TEST_F(NavExample, HeightBandPathCrossesTheHole)
{
	const auto plan = gam::nav::planPath(maps->heightBand, kStart, kGoal);
	ASSERT_TRUE(plan.found);
	size_t inside = 0;
	for (const auto& p : plan.path) inside += gam::nav::distanceToHoles(sf->scene, p.x, p.y) == 0;
	EXPECT_GT(inside, 5u) << "the height-band path should run straight over the hole";
	EXPECT_LT(plan.maxDeviation, 0.2);
	// and the hole cells really are traversable there (not obstacles)
	for (const auto& h : holeCells(maps->heightBand))
		EXPECT_GT(maps->heightBand.getCell(maps->heightBand.x2idx(h.x), maps->heightBand.y2idx(h.y)), 0.45f);
}

TEST_F(NavExample, ObstaclePointsContainTheHoleInTheRobotFrame)
{
	// An arbitrary robot pose: the points must be robot-frame coordinates.
	const mrpt::poses::CPose2D robot(1.0, 0.4, 30.0 * M_PI / 180.0);
	const auto pts = gam::nav::obstaclePointsRobotFrame(maps->groundAware, robot);
	ASSERT_GT(pts.size(), 0u);
	const auto& g = maps->groundAware;
	std::set<std::pair<int, int>> cells;
	for (size_t i = 0; i < pts.size(); i++)
	{
		float x, y, z;
		pts.getPoint(i, x, y, z);
		EXPECT_FLOAT_EQ(z, 0.1f);
		double gx, gy;
		robot.composePoint(x, y, gx, gy);
		EXPECT_LE(std::hypot(gx - robot.x(), gy - robot.y()), 6.0 + 1e-3);
		// every point is the centre of an occupied cell
		const int cx = g.x2idx(gx), cy = g.y2idx(gy);
		EXPECT_NEAR(g.idx2x(cx), gx, 1e-3);
		EXPECT_NEAR(g.idx2y(cy), gy, 1e-3);
		EXPECT_LT(g.getCell(cx, cy), 0.4f);
		cells.insert({cx, cy});
	}
	// The hole cells are in the point cloud: all but a few border cells.
	const auto holes = holeCells(g);
	size_t found = 0, interior = 0, interiorFound = 0;
	for (const auto& h : holes)
	{
		const bool in = cells.count({g.x2idx(h.x), g.y2idx(h.y)}) > 0;
		found += in;
		const bool isInterior = std::abs(h.x - 2.5) < 0.25 && std::abs(h.y) < 0.25;
		interior += isInterior;
		interiorFound += isInterior && in;
	}
	EXPECT_EQ(interiorFound, interior);
	EXPECT_GE(double(found), 0.9 * double(holes.size()));

	// The height-band grid's obstacles have no point in the hole.
	const auto band = gam::nav::obstaclePointsRobotFrame(maps->heightBand, robot);
	for (size_t i = 0; i < band.size(); i++)
	{
		float x, y, z;
		band.getPoint(i, x, y, z);
		double gx, gy;
		robot.composePoint(x, y, gx, gy);
		EXPECT_GT(gam::nav::distanceToHoles(sf->scene, gx, gy), 0.0);
	}
}

TEST_F(NavExample, ObstaclePointsRespectTheRange)
{
	gam::nav::ObstacleOptions oo;
	oo.maxRange = 1.0;
	const mrpt::poses::CPose2D robot(2.5, 0.0, 0.0);  // on the hatch
	const auto pts = gam::nav::obstaclePointsRobotFrame(maps->groundAware, robot, oo);
	ASSERT_GT(pts.size(), 50u);
	for (size_t i = 0; i < pts.size(); i++)
	{
		float x, y, z;
		pts.getPoint(i, x, y, z);
		EXPECT_LE(std::hypot(x, y), 1.0 + 1e-4);
	}
}

// PlannerSimple2D grows each obstacle cell by n = ceil(radius / resolution)
// cells in a square; the radius for a square footprint of half side h must
// make n + 1/2 cells reach h * sqrt(2), the footprint's circumcircle.
TEST(NavPlannerRadius, FromTheFootprintsCircumcircleAndTheCellSize)
{
	// 0.25 * sqrt(2) = 0.3536 m = 7.07 cells of 5 cm: n = ceil(6.57) = 7, radius 6.5 cells
	EXPECT_NEAR(gam::nav::plannerRadiusForFootprint(0.25, 0.05), 0.325, 1e-12);
	// 0.30 * sqrt(2) = 0.4243 m = 8.49 cells: n = ceil(7.99) = 8, radius 7.5 cells
	EXPECT_NEAR(gam::nav::plannerRadiusForFootprint(0.30, 0.05), 0.375, 1e-12);
	// 10 cm cells: 3.54 cells, n = ceil(3.04) = 4, radius 3.5 cells
	EXPECT_NEAR(gam::nav::plannerRadiusForFootprint(0.25, 0.10), 0.35, 1e-12);
	// and PlannerSimple2D's ceil() gives back n
	EXPECT_EQ(int(std::ceil(gam::nav::plannerRadiusForFootprint(0.30, 0.05) / 0.05)), 8);
}

namespace
{
/** 4 x 2 m of free cells (10 cm), one column of occupied cells at x = 3.0-3.1
 * from y = 0 to 2 (a wall across the whole grid). */
mrpt::maps::COccupancyGridMap2D gridWithAWallAcross()
{
	mrpt::maps::COccupancyGridMap2D g(0.0f, 4.0f, 0.0f, 2.0f, 0.1f);
	g.fill(0.9f);
	for (unsigned cy = 0; cy < g.getSizeY(); cy++) g.setCell(30, int(cy), 0.05f);
	return g;
}
}  // namespace

TEST(NavPlannerBlockedCells, TheObstacleGrownByCeilOfTheRadiusInASquare)
{
	mrpt::maps::COccupancyGridMap2D g(0.0f, 4.0f, 0.0f, 2.0f, 0.1f);
	g.fill(0.9f);
	g.setCell(20, 10, 0.05f);  // one occupied cell
	gam::nav::PlanOptions po;
	po.robotRadius = 0.25f;  // ceil(2.5) = 3 cells
	const auto b = gam::nav::plannerBlockedCells(g, po);
	const unsigned W = g.getSizeX();
	EXPECT_EQ(std::count(b.begin(), b.end(), 1), 7 * 7);  // the 7 x 7 square around it
	EXPECT_EQ(b[23 + 13 * W], 1);                         // corner of the square
	EXPECT_EQ(b[24 + 10 * W], 0);                         // one cell further
	EXPECT_EQ(b[20 + 6 * W], 0);
}

TEST(NavPlanTowards, NoPathToAGoalBehindAWallGivesThePathToTheNearestReachableCell)
{
	const auto g = gridWithAWallAcross();
	gam::nav::PlanOptions po;
	po.robotRadius = 0.15f;  // ceil(1.5) = 2 cells: the wall's column 30 blocks columns 28-32
	const mrpt::math::TPoint2D start{0.55, 1.05}, goal{3.55, 1.05};
	EXPECT_FALSE(gam::nav::planPath(g, start, goal, po).found);
	const auto p = gam::nav::planTowards(g, start, goal, po);
	ASSERT_TRUE(p.found);
	// column 27 (x 2.7-2.8, centre 2.75) is the last one before the grown wall,
	// and in it the row of the goal (centre 1.05) is the nearest cell
	EXPECT_NEAR(p.path.back().x, 2.75, 1e-6);
	EXPECT_NEAR(p.path.back().y, 1.05, 1e-6);
}

TEST(NavPlanTowards, FromInsideTheGrownObstaclesItStartsAtTheNearestCellOutside)
{
	const auto g = gridWithAWallAcross();
	gam::nav::PlanOptions po;
	po.robotRadius = 0.15f;
	// start in column 29 (x 2.95), inside the wall grown by 2 cells, its neighbours
	// 28 and 30 too: PlannerSimple2D finds no path even to a free cell behind it
	const mrpt::math::TPoint2D start{2.95, 1.05}, back{0.55, 1.05};
	EXPECT_FALSE(gam::nav::planPath(g, start, back, po).found);
	// nothing nearer the goal (3.55) is reachable: column 27 is 0.8 m from it, the start 0.6 m
	EXPECT_FALSE(gam::nav::planTowards(g, start, {3.55, 1.05}, po).found);
	// towards a goal on the start's side the path begins at the nearest free cell:
	// column 27, row 10 (0.2 m away; column 33 is 0.4 m away)
	const auto p = gam::nav::planTowards(g, start, {0.25, 1.05}, po);
	ASSERT_TRUE(p.found);
	EXPECT_NEAR(p.path.front().x, 2.75, 1e-6);
	EXPECT_NEAR(p.path.front().y, 1.05, 1e-6);
	EXPECT_NEAR(p.path.back().x, 0.25, 1e-6);
}
