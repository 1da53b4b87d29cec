// Ground-aware mapping for MRPT
// RRT-GPD ground detection on synthetic 2.5D grids.
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <random>
#include <stdexcept>
#include <tuple>
#include <vector>

#include "gam/core/RrtGroundDetector.h"
#include "test_helpers.h"

using namespace gam;
using gamtest::deg2rad;
using gamtest::FloorWallBox;
using gamtest::rad2deg;
using Status = GroundDetection::Status;

namespace
{
ElevationGrid floorWallBoxGrid()
{
	ElevationGrid grid;  // -5..5 m, 5 cm
	std::mt19937 rng(11);
	gamtest::buildFloorWallBox(grid, rng);
	return grid;
}

void expectSameDetection(const GroundDetection& a, const GroundDetection& b)
{
	ASSERT_EQ(a.status, b.status);
	ASSERT_EQ(a.nodes.size(), b.nodes.size());
	for (size_t i = 0; i < a.nodes.size(); i++)
	{
		EXPECT_EQ(a.nodes[i].x, b.nodes[i].x) << i;
		EXPECT_EQ(a.nodes[i].y, b.nodes[i].y) << i;
		EXPECT_EQ(a.nodes[i].z, b.nodes[i].z) << i;
		EXPECT_EQ(a.nodes[i].parent, b.nodes[i].parent) << i;
		EXPECT_EQ(a.nodes[i].plane_id, b.nodes[i].plane_id) << i;
	}
	ASSERT_EQ(a.planes.size(), b.planes.size());
	for (size_t k = 0; k < a.planes.size(); k++)
	{
		EXPECT_EQ(a.planes[k].a, b.planes[k].a);
		EXPECT_EQ(a.planes[k].b, b.planes[k].b);
		EXPECT_EQ(a.planes[k].c, b.planes[k].c);
		EXPECT_EQ(a.planes[k].d, b.planes[k].d);
	}
	EXPECT_EQ(a.plane_support, b.plane_support);
}
}  // namespace

TEST(RrtGpdParams, ValidateRejectsOutOfRangeValues)
{
	EXPECT_NO_THROW(RrtGpdParams{}.validate());
	const std::vector<std::pair<const char*, std::function<void(RrtGpdParams&)>>> bad{
		{"K=0", [](RrtGpdParams& p) { p.iterations = 0; }},
		{"K<0", [](RrtGpdParams& p) { p.iterations = -5; }},
		{"N_th>1", [](RrtGpdParams& p) { p.normal_threshold = 1.5; }},
		{"N_th=0", [](RrtGpdParams& p) { p.normal_threshold = 0; }},
		{"E_th=0", [](RrtGpdParams& p) { p.elevation_threshold = 0; }},
		{"E_th NaN", [](RrtGpdParams& p) { p.elevation_threshold = NAN; }},
		{"s_x even", [](RrtGpdParams& p) { p.neighbourhood_x = 2; }},
		{"s_y even", [](RrtGpdParams& p) { p.neighbourhood_y = 4; }},
		{"s_x=0", [](RrtGpdParams& p) { p.neighbourhood_x = 0; }},
		{"s_x=33", [](RrtGpdParams& p) { p.neighbourhood_x = 33; }},
		{"s_x*s_y=1",
		 [](RrtGpdParams& p) {
			 p.neighbourhood_x = p.neighbourhood_y = 1;
			 p.min_valid_cells = 3;
		 }},
		{"s_x=1 (collinear)",
		 [](RrtGpdParams& p) {
			 p.neighbourhood_x = 1;
			 p.neighbourhood_y = 5;
			 p.min_valid_cells = 3;
		 }},
		{"d_n=0", [](RrtGpdParams& p) { p.expansion_distance = 0; }},
		{"max_cell_std=0", [](RrtGpdParams& p) { p.max_cell_std = 0; }},
		{"min_valid_cells=2", [](RrtGpdParams& p) { p.min_valid_cells = 2; }},
		{"min_valid_cells>s_x*s_y", [](RrtGpdParams& p) { p.min_valid_cells = 10; }},
		{"seed radius 0", [](RrtGpdParams& p) { p.seed_search_radius = 0; }},
		{"seed tol 0", [](RrtGpdParams& p) { p.seed_height_tolerance = 0; }},
		{"seed attempts 0", [](RrtGpdParams& p) { p.seed_attempts = 0; }},
		{"window margin 0", [](RrtGpdParams& p) { p.window_margin = 0; }},
		{"min_nodes 2", [](RrtGpdParams& p) { p.min_nodes = 2; }},
		{"ransac it 0", [](RrtGpdParams& p) { p.ransac_iterations = 0; }},
		{"ransac dist 0", [](RrtGpdParams& p) { p.ransac_inlier_distance = 0; }},
		{"max_planes 0", [](RrtGpdParams& p) { p.max_planes = 0; }},
		{"max_planes 9", [](RrtGpdParams& p) { p.max_planes = 9; }},
	};
	for (const auto& [name, mutate] : bad)
	{
		RrtGpdParams p;
		mutate(p);
		EXPECT_THROW(p.validate(), std::invalid_argument) << name;
	}
	// Boundary values that are valid.
	RrtGpdParams ok;
	ok.normal_threshold = 1.0;
	ok.neighbourhood_x = 31;
	ok.min_nodes = 3;
	ok.max_planes = 8;
	EXPECT_NO_THROW(ok.validate());

	// Parameters are checked when they are set, not on every frame: the
	// detector refuses them and keeps its previous, valid ones.
	RrtGpdParams p;
	p.neighbourhood_x = 2;
	EXPECT_THROW(RrtGroundDetector{p}, std::invalid_argument);
	RrtGroundDetector det;
	EXPECT_THROW(det.setParams(p), std::invalid_argument);
	EXPECT_EQ(det.params().neighbourhood_x, 3);
}

TEST(RrtGroundDetector, FindsFloorNotWallOrBox)
{
	const ElevationGrid grid = floorWallBoxGrid();
	RrtGroundDetector det;
	GroundDetection out;
	det.detect(grid, GroundSeedHint{0, 0, 0}, out);
	ASSERT_EQ(out.status, Status::Ok) << out.describe();
	ASSERT_FALSE(out.planes.empty());
	const Plane& pl = out.plane();
	std::cout << "RRT-GPD floor+wall+box: " << out.describe() << std::endl;
	EXPECT_LT(rad2deg(pl.tiltAngle()), 0.5);
	EXPECT_GT(pl.c, 0.99);
	EXPECT_NEAR(pl.heightAt(0, 0), 0.0, 0.005);
	EXPECT_NEAR(pl.heightAt(2, 2), 0.0, 0.01);
	// Not the wall (vertical) nor the box top (0.4 m).
	EXPECT_LT(std::abs(pl.heightAt(1.25, 0.75)), 0.05);

	ASSERT_GT(out.nodes.size(), 100u);
	EXPECT_EQ(out.nodes.front().parent, -1);
	EXPECT_GE(out.plane_support.front(), out.nodes.size() * 9 / 10);
	const GridGeometry& g = grid.geometry();
	for (size_t i = 0; i < out.nodes.size(); i++)
	{
		const GroundNode& n = out.nodes[i];
		EXPECT_NEAR(n.z, 0.0, 0.01) << i;
		EXPECT_TRUE(FloorWallBox::isFloor(n.x, n.y)) << "node " << i << " at " << n.x << "," << n.y;
		EXPECT_FALSE(FloorWallBox::isBox(n.x, n.y));
		EXPECT_FALSE(FloorWallBox::isWall(n.x, n.y));
		// Node at a cell centre of an observed cell.
		const int cx = g.ix(n.x), cy = g.iy(n.y);
		EXPECT_NEAR(n.x, g.cx(cx), 1e-5);
		EXPECT_NEAR(n.y, g.cy(cy), 1e-5);
		EXPECT_TRUE(grid.cell(cx, cy).observed());
		EXPECT_LT(rad2deg(n.local.tiltAngle()), 3.0);
		if (i > 0)
		{
			ASSERT_GE(n.parent, 0);
			ASSERT_LT(n.parent, int(i));
			const GroundNode& p = out.nodes[size_t(n.parent)];
			// One expansion step d_n = 0.4, snapped to a cell centre.
			EXPECT_LE(std::hypot(n.x - p.x, n.y - p.y), 0.4 + 0.05) << i;
		}
	}
	// The tree explored the floor, well beyond the robot's surroundings.
	float xmin = 1e9f, xmax = -1e9f;
	for (const auto& n : out.nodes) xmin = std::min(xmin, n.x), xmax = std::max(xmax, n.x);
	EXPECT_LT(xmin, -2.0f);
	EXPECT_GT(xmax, 2.0f);
}

TEST(RrtGroundDetector, RecoversTiltedFloor)
{
	ElevationGrid grid;
	std::mt19937 rng(3);
	gam::BinnedPoints b;
	const double slope = std::tan(deg2rad(3.0));
	gamtest::sampleSurfaceIf(
		grid, [](double x, double y) { return gamtest::inRect(x, y, -3, 3, -3, 3); },
		[slope](double x, double) { return slope * x; }, 3, 0.003, rng, b);
	gamtest::insertAll(grid, b);

	RrtGroundDetector det;
	GroundDetection out;
	det.detect(grid, GroundSeedHint{0, 0, 0}, out);
	ASSERT_EQ(out.status, Status::Ok) << out.describe();
	const Plane& pl = out.plane();
	const double tiltErr = std::abs(rad2deg(pl.tiltAngle()) - 3.0);
	const double offErr = std::abs(pl.heightAt(0, 0));
	std::cout << "RRT-GPD tilted floor 3 deg: tilt error " << tiltErr << " deg, height error at robot " << offErr * 1000
			  << " mm, " << out.nodes.size() << " nodes" << std::endl;
	EXPECT_LT(tiltErr, 0.3);
	EXPECT_LT(offErr, 0.01);
	// Rising along +x: the upward normal leans to -x.
	EXPECT_LT(pl.a, -0.04);
	EXPECT_NEAR(pl.b, 0.0, 0.01);
	EXPECT_NEAR(pl.heightAt(2, 0), 2 * slope, 0.015);
	for (const auto& n : out.nodes) EXPECT_NEAR(n.z, slope * n.x, 0.01);
}

TEST(RrtGroundDetector, FitLocalPlane)
{
	// Noise-free 3 deg floor on a 10 x 10 patch; wall columns at x in [0.3, 0.35).
	ElevationGrid grid(gamtest::makeGeometry(0, 0, 0.05, 20, 20));
	std::mt19937 rng(1);
	gam::BinnedPoints b;
	const double slope = std::tan(deg2rad(3.0));
	gamtest::sampleSurfaceIf(
		grid, [](double x, double y) { return x < 0.5 && y < 0.5 && !(x >= 0.3 && x < 0.35); },
		[slope](double x, double) { return slope * x; }, 2, 0.0, rng, b);
	gamtest::sampleColumns(grid, 0.3, 0.35, 0, 0.5, 0.0, 1.0, 0.1, b);
	gamtest::insertAll(grid, b);

	RrtGroundDetector det;
	Plane pl;
	double rms = -1;
	ASSERT_TRUE(det.fitLocalPlane(grid, 2, 2, pl, rms));
	EXPECT_NEAR(rad2deg(pl.tiltAngle()), 3.0, 1e-3);
	EXPECT_NEAR(rms, 0.0, 1e-5);
	// Expressed in grid coordinates: the height at the cell centre (0.125, 0.125).
	EXPECT_NEAR(pl.heightAt(0.125, 0.125), slope * 0.125, 1e-5);
	EXPECT_NEAR(pl.heightAt(1.0, 0.0), slope * 1.0, 1e-4);

	// Corner of the patch: 4 cells < min_valid_cells (5).
	EXPECT_FALSE(det.fitLocalPlane(grid, 0, 0, pl, rms));
	// Next to the wall column (cx = 6): the wall cells (std 0.3 m) are left out,
	// so the fit on the remaining 6 floor cells is still exact.
	ASSERT_TRUE(det.fitLocalPlane(grid, 5, 4, pl, rms));
	EXPECT_NEAR(rms, 0.0, 1e-5);
	EXPECT_NEAR(rad2deg(pl.tiltAngle()), 3.0, 1e-3);
	// Centred on the wall: only the 2 x 3 floor cells at x = 5 and 7 are left:
	// still 6 cells.
	ASSERT_TRUE(det.fitLocalPlane(grid, 6, 4, pl, rms));
	EXPECT_NEAR(rad2deg(pl.tiltAngle()), 3.0, 1e-3);
	// Far outside the data.
	EXPECT_FALSE(det.fitLocalPlane(grid, 15, 15, pl, rms));
}

TEST(RrtGroundDetector, NoFloorNearExpectedHeight)
{
	// A large table top at 1.0 m and nothing else: the robot expects the floor
	// at 0 (+-0.3 m) -> no valid seed.
	ElevationGrid grid;
	std::mt19937 rng(5);
	gam::BinnedPoints b;
	gamtest::sampleSurface(
		grid, -2, 2, -2, 2, [](double, double) { return 1.0; }, 3, 0.003, rng, b);
	gamtest::insertAll(grid, b);
	RrtGroundDetector det;
	GroundDetection out;
	det.detect(grid, GroundSeedHint{0, 0, 0}, out);
	EXPECT_EQ(out.status, Status::NoValidSeed);
	EXPECT_FALSE(out.ok());
	EXPECT_TRUE(out.planes.empty());
	EXPECT_TRUE(out.nodes.empty());
	// Expected at 1.0, the same grid is a floor.
	det.detect(grid, GroundSeedHint{0, 0, 1.0}, out);
	EXPECT_EQ(out.status, Status::Ok) << out.describe();
	EXPECT_NEAR(out.plane().heightAt(0, 0), 1.0, 0.01);

	// Only walls (vertical columns): nothing planar at all.
	ElevationGrid walls;
	b.clear();
	gamtest::sampleColumns(walls, -2, 2, 1.0, 1.1, 0, 2, 0.05, b);
	gamtest::sampleColumns(walls, 1.0, 1.1, -2, 2, 0, 2, 0.05, b);
	gamtest::insertAll(walls, b);
	det.detect(walls, GroundSeedHint{0, 0, 0}, out);
	EXPECT_EQ(out.status, Status::NoValidSeed);

	// A floor beyond seed_search_radius (5 m) from the robot.
	ElevationGrid farFloor;
	b.clear();
	gamtest::sampleSurface(
		farFloor, 3, 5, 3, 5, [](double, double) { return 0.0; }, 2, 0.0, rng, b);
	gamtest::insertAll(farFloor, b);
	det.detect(farFloor, GroundSeedHint{-3, -3, 0}, out);
	EXPECT_EQ(out.status, Status::NoValidSeed);
	det.detect(farFloor, GroundSeedHint{1, 1, 0}, out);  // 2.8 m away: found
	EXPECT_EQ(out.status, Status::Ok) << out.describe();
}

TEST(RrtGroundDetector, EmptyGridAndTinyFloorPatch)
{
	ElevationGrid grid;
	RrtGroundDetector det;
	GroundDetection out;
	det.detect(grid, {}, out);
	EXPECT_EQ(out.status, Status::EmptyGrid);

	// A 3 x 3 cell patch (15 cm): at most 5 cells have >= 5 valid neighbours,
	// fewer than min_nodes = 8.
	std::mt19937 rng(2);
	gam::BinnedPoints b;
	gamtest::sampleSurface(
		grid, -0.08, 0.06, -0.08, 0.06, [](double, double) { return 0.0; }, 3, 0.002, rng, b);
	gamtest::insertAll(grid, b);
	ASSERT_EQ(grid.observedCount(), 9u);
	det.detect(grid, {}, out);
	EXPECT_EQ(out.status, Status::TooFewNodes);
	EXPECT_LT(out.nodes.size(), 8u);
	EXPECT_GE(out.nodes.size(), 1u);
	EXPECT_TRUE(out.planes.empty());
	EXPECT_STREQ(GroundDetection::statusName(out.status), "too_few_nodes");

	// The same patch with min_nodes 3 is enough.
	RrtGpdParams p;
	p.min_nodes = 3;
	p.iterations = 20000;  // samples rarely fall on such a small patch
	det.setParams(p);
	det.detect(grid, {}, out);
	EXPECT_EQ(out.status, Status::Ok) << out.describe();
}

TEST(RrtGroundDetector, RetriesFromFloorWhenSeededOnABoxTop)
{
	// Floor everywhere, a 3 x 3 cell box top at 0.2 m right under the hint.
	ElevationGrid grid;
	std::mt19937 rng(8);
	gam::BinnedPoints b;
	auto isBox = [](double x, double y) { return gamtest::inRect(x, y, -0.08, 0.06, -0.08, 0.06); };
	gamtest::sampleSurfaceIf(
		grid, [&](double x, double y) { return gamtest::inRect(x, y, -3, 3, -3, 3) && !isBox(x, y); },
		[](double, double) { return 0.0; }, 3, 0.003, rng, b);
	gamtest::sampleSurfaceIf(
		grid, isBox, [](double, double) { return 0.2; }, 3, 0.003, rng, b);
	gamtest::insertAll(grid, b);

	const GroundSeedHint hint{-0.025, -0.025, 0.1};  // box centre; 0 and 0.2 within +-0.3
	RrtGpdParams p;
	p.seed_attempts = 1;
	RrtGroundDetector one(p);
	GroundDetection out;
	one.detect(grid, hint, out);
	EXPECT_EQ(out.status, Status::TooFewNodes) << out.describe();
	ASSERT_FALSE(out.nodes.empty());
	EXPECT_NEAR(out.nodes.front().z, 0.2, 0.01);  // the box top was the seed

	RrtGroundDetector retry;  // default: 3 attempts
	retry.detect(grid, hint, out);
	ASSERT_EQ(out.status, Status::Ok) << out.describe();
	EXPECT_NEAR(out.plane().heightAt(0, 0), 0.0, 0.01);
	for (const auto& n : out.nodes) EXPECT_NEAR(n.z, 0.0, 0.01);
}

namespace
{
// Floor seen from 0.6 to 4 m ahead of a robot at the origin (nothing nearer:
// the camera's blind zone), 4 m wide, with a flat top 3.4 cm high (a cable
// protector, a platform) from 0.6 m to xEnd ahead and |y| <= halfWidth; 3
// samples per cell, 3 mm noise.
void floorWithATopAhead(ElevationGrid& grid, double xEnd, double halfWidth)
{
	std::mt19937 rng(21);
	gam::BinnedPoints b;
	auto isTop = [&](double x, double y) { return gamtest::inRect(x, y, 0.6, xEnd, -halfWidth, halfWidth); };
	gamtest::sampleSurfaceIf(
		grid, [&](double x, double y) { return gamtest::inRect(x, y, 0.6, 4, -2, 2) && !isTop(x, y); },
		[](double, double) { return 0.0; }, 3, 0.003, rng, b);
	gamtest::sampleSurfaceIf(
		grid, isTop, [](double, double) { return 0.034; }, 3, 0.003, rng, b);
	gamtest::insertAll(grid, b);
}
}  // namespace

TEST(RrtGroundDetector, ReseedsWhenTheSeedsPlaneHoldsTooFewOfTheTreesNodes)
{
	// Nothing seen within 0.6 m of the robot (the camera's blind zone); the
	// nearest cells are the top of a 3.4 cm cable protector, 0.55 m deep and
	// 0.6 m wide, lying across the view; the floor around and beyond it. The
	// tree seeded on the protector steps down to the floor (3.4 cm < E_th =
	// 5 cm) and covers it (about 260 nodes); the seed's own plane, the ground
	// plane, holds the protector's top: a 0.55 x 0.6 m patch where nodes lie
	// about d_n = 0.4 m apart, a handful of them (5 with this draw), fewer
	// than min_nodes = 8.
	ElevationGrid grid;
	floorWithATopAhead(grid, 1.15, 0.3);
	const GroundSeedHint hint{0, 0, 0};

	RrtGpdParams p;
	p.seed_attempts = 1;     // the first tree is kept, as before this rule
	p.fill_patches = false;  // the tree's own nodes, which the rule counts
	RrtGroundDetector one(p);
	GroundDetection out;
	one.detect(grid, hint, out);
	ASSERT_EQ(out.status, Status::Ok) << out.describe();
	EXPECT_NEAR(out.nodes.front().z, 0.034, 0.01);  // seeded on the protector
	EXPECT_GT(out.nodes.size(), 100u);              // the tree is on the floor
	EXPECT_LT(out.plane_support.front(), p.min_nodes);
	EXPECT_NEAR(out.plane().heightAt(3, 0), 0.034, 0.01);  // the ground plane: the top

	RrtGroundDetector reseed;  // default: 3 attempts, fill_patches
	reseed.detect(grid, hint, out);
	ASSERT_EQ(out.status, Status::Ok) << out.describe();
	EXPECT_NEAR(out.nodes.front().z, 0.0, 0.01);  // seeded on the floor
	EXPECT_GE(out.plane_support.front(), reseed.params().min_nodes);
	EXPECT_NEAR(out.plane().heightAt(0, 0), 0.0, 0.005);
	EXPECT_NEAR(out.plane().heightAt(3, 0), 0.0, 0.005);

	// Were the robot's floor at the protector's height (hint 3.4 cm up), the
	// floor tree's plane would pass 3.4 cm from it at the robot, the first
	// tree's about 0: the first tree is grown again and kept.
	const GroundSeedHint high{0, 0, 0.034};
	reseed.detect(grid, high, out);
	ASSERT_EQ(out.status, Status::Ok) << out.describe();
	EXPECT_NEAR(out.nodes.front().z, 0.034, 0.01);
	EXPECT_NEAR(out.plane().heightAt(0.9, 0), 0.034, 0.01);
	EXPECT_LT(out.plane_support.front(), 30u);  // the top (and the fill's nodes on it), not the floor
}

TEST(RrtGroundDetector, ReseedsWhenTheSeedsPlaneHoldsLessThanHalfOfTheTreesNodes)
{
	// As above, but a deeper, wider top (1.0 x 1.6 m, a platform 3.4 cm
	// high): it holds more than min_nodes = 8 of the first tree's nodes (34
	// of 261 with this draw), yet the tree, stepped down to the floor, has
	// many times more there, and its ground plane is the top. The
	// seed's plane must also hold half of the tree's nodes to be the ground
	// (held-out Astra seed_3007, one draw of the tree in four: a protector's
	// top was the ground, and 5.6 % of the scene's floor occupied).
	ElevationGrid grid;
	floorWithATopAhead(grid, 1.6, 0.8);
	const GroundSeedHint hint{0, 0, 0};

	RrtGpdParams p;
	p.seed_attempts = 1;  // the first tree, kept
	p.fill_patches = false;
	RrtGroundDetector one(p);
	GroundDetection out;
	one.detect(grid, hint, out);
	ASSERT_EQ(out.status, Status::Ok) << out.describe();
	EXPECT_NEAR(out.nodes.front().z, 0.034, 0.01);           // seeded on the top
	EXPECT_NEAR(out.plane().heightAt(1.1, 0), 0.034, 0.01);  // the ground plane: the top
	EXPECT_NEAR(out.plane().heightAt(3, 0), 0.034, 0.01);
	// The premise: the top holds min_nodes or more, less than half of the tree.
	EXPECT_GE(out.plane_support.front(), p.min_nodes);
	EXPECT_LT(2 * out.plane_support.front(), out.nodes.size());

	RrtGroundDetector reseed;  // default: 3 attempts
	reseed.detect(grid, hint, out);
	ASSERT_EQ(out.status, Status::Ok) << out.describe();
	EXPECT_NEAR(out.nodes.front().z, 0.0, 0.01);  // seeded on the floor
	EXPECT_NEAR(out.plane().heightAt(0, 0), 0.0, 0.005);
	EXPECT_NEAR(out.plane().heightAt(3, 0), 0.0, 0.005);
}

TEST(RrtGroundDetector, PatchMeetsTheFloorBelowItOnlyWithinTheNoiseBandOrThroughTheNode)
{
	// Floor Q: z = 0. Patch node p at x = 1.0, floor node q at x = 0.7 (a
	// tree step, d_n = 0.4 m). Noise band tol = 1 cm, the ground plane's
	// inlier distance 2.5 cm: a patch parallel to the floor at height h
	// meets it at q if |h| <= 1 cm, or 0 < h <= 1 + 2.5 = 3.5 cm.
	const Plane floor;  // a = b = 0, c = 1, d = 0
	GroundNode p, q;
	p.x = 1.0f;
	q.x = 0.7f;
	const double tol = 0.01, inlier = 0.025;
	auto level = [](double h) { return Plane::fromNormalAndPoint({0, 0, 1}, {0, 0, h}); };
	auto meets = [&](const Plane& patch, bool qOnGround = true) {
		return patchMeetsPlaneBetween(patch, floor, p, q, qOnGround, tol, inlier);
	};
	EXPECT_TRUE(meets(level(-0.009)));   // within the band
	EXPECT_TRUE(meets(level(0.034)));    // a lip up: 3.4 <= 3.5 cm
	EXPECT_FALSE(meets(level(0.036)));   // 3.6 > 3.5 cm
	EXPECT_FALSE(meets(level(-0.034)));  // below: the lower level of a step (the old band took it)
	// q itself on the patch (a ramp down whose top holds floor nodes 2.5 cm
	// below the floor): |-0.030 - (-0.025)| = 0.5 cm <= tol.
	q.z = -0.025f;
	EXPECT_TRUE(meets(level(-0.030)));
	q.z = 0;
	// A patch crossing the floor between p and q: z = 0.1 (x - 0.85) is
	// +1.5 cm at p and -1.5 cm at q.
	EXPECT_TRUE(meets(Plane::fromNormalAndPoint({-0.1, 0, 1}, {0.85, 0, 0})));
	// Q another patch: 2 tol at q, on either side; -1.9 cm meets, -2.1 does not.
	EXPECT_TRUE(meets(level(-0.019), false));
	EXPECT_FALSE(meets(level(-0.021), false));
	EXPECT_FALSE(meets(level(0.021), false));
}

TEST(RrtGroundDetector, DeterministicForTheSameSeed)
{
	const ElevationGrid grid = floorWallBoxGrid();
	RrtGpdParams p;
	p.random_seed = 1234;
	RrtGroundDetector d1(p), d2(p);
	GroundDetection a, b, c;
	d1.detect(grid, {0, 0, 0}, a);
	d2.detect(grid, {0, 0, 0}, b);
	d1.detect(grid, {0, 0, 0}, c);  // reuse of the same detector (scratch state)
	ASSERT_EQ(a.status, Status::Ok);
	expectSameDetection(a, b);
	expectSameDetection(a, c);

	// Another seed grows another tree (same floor).
	p.random_seed = 99;
	RrtGroundDetector d3(p);
	GroundDetection e;
	d3.detect(grid, {0, 0, 0}, e);
	ASSERT_EQ(e.status, Status::Ok);
	bool differ = e.nodes.size() != a.nodes.size();
	for (size_t i = 0; !differ && i < a.nodes.size(); i++)
		differ = a.nodes[i].x != e.nodes[i].x || a.nodes[i].y != e.nodes[i].y;
	EXPECT_TRUE(differ);
	EXPECT_NEAR(e.plane().heightAt(0, 0), 0.0, 0.005);
}

TEST(RrtGroundDetector, RampBecomesAnExtraPlane)
{
	ElevationGrid grid;
	std::mt19937 rng(21);
	gamtest::buildRamp(grid, rng);
	RrtGroundDetector det;
	GroundDetection out;
	det.detect(grid, {0, 0, 0}, out);
	ASSERT_EQ(out.status, Status::Ok) << out.describe();
	std::cout << "RRT-GPD floor+6 deg ramp: " << out.describe() << std::endl;
	ASSERT_GE(out.planes.size(), 2u);
	ASSERT_EQ(out.plane_support.size(), out.planes.size());
	// planes[0]: the floor.
	EXPECT_LT(rad2deg(out.plane().tiltAngle()), 0.5);
	EXPECT_NEAR(out.plane().heightAt(-1, 0), 0.0, 0.01);
	// One of the extra planes is the ramp: 6 deg, z(2) = tan 6 deg = 0.105.
	int ramp = -1;
	for (size_t k = 1; k < out.planes.size(); k++)
		if (std::abs(rad2deg(out.planes[k].tiltAngle()) - 6.0) < 0.5) ramp = int(k);
	ASSERT_GE(ramp, 1);
	const Plane& rp = out.planes[size_t(ramp)];
	EXPECT_NEAR(rp.heightAt(2.0, 0.0), gamtest::rampHeight(2.0), 0.01);
	EXPECT_NEAR(rp.heightAt(2.5, 1.0), gamtest::rampHeight(2.5), 0.01);
	EXPECT_GE(out.plane_support[size_t(ramp)], RrtGpdParams{}.min_nodes_per_extra_plane);
	// The tree climbed the ramp; its nodes up there belong to the ramp plane
	// (except along the end of the data at x = 3: a fit window cut by it is
	// a few mm off, outside the patches' measured inlier distance).
	size_t high = 0;
	for (const auto& n : out.nodes)
	{
		EXPECT_NEAR(n.z, gamtest::rampHeight(n.x), 0.01);
		if (n.x > 1.8 && n.x < 2.9)
		{
			high++;
			EXPECT_EQ(n.plane_id, ramp) << n.x << "," << n.y;
		}
	}
	EXPECT_GT(high, 10u);

	// Extra planes disabled: the ramp is not a plane.
	RrtGpdParams p;
	p.min_nodes_per_extra_plane = 0;
	det.setParams(p);
	det.detect(grid, {0, 0, 0}, out);
	ASSERT_EQ(out.status, Status::Ok);
	EXPECT_EQ(out.planes.size(), 1u);
	p = RrtGpdParams{};
	p.max_planes = 1;
	det.setParams(p);
	det.detect(grid, {0, 0, 0}, out);
	EXPECT_EQ(out.planes.size(), 1u);
}

TEST(RrtGroundDetector, NarrowCorridorKeepsItsRoll)
{
	// A 30 cm wide, 6 m long corridor rolled 3 deg about X: the nodes lie
	// almost on a line, so RANSAC alone cannot fix the roll; the plane must
	// still come out 3 deg, leaning towards -Y.
	ElevationGrid grid;
	std::mt19937 rng(1);
	gam::BinnedPoints b;
	const double s = std::tan(deg2rad(3.0));
	gamtest::sampleSurfaceIf(
		grid, [](double x, double y) { return gamtest::inRect(x, y, -3, 3, -0.15, 0.15); },
		[s](double, double y) { return s * y; }, 3, 0.002, rng, b);
	gamtest::insertAll(grid, b);
	RrtGroundDetector det;
	GroundDetection out;
	det.detect(grid, {0, 0, 0}, out);
	ASSERT_EQ(out.status, Status::Ok) << out.describe();
	EXPECT_NEAR(rad2deg(out.plane().tiltAngle()), 3.0, 0.3);
	EXPECT_LT(out.plane().b, -0.045);
	EXPECT_NEAR(out.plane().a, 0.0, 0.005);
	EXPECT_NEAR(out.plane().heightAt(2.0, 0.1), s * 0.1, 0.005);
}

TEST(RrtGroundDetector, UpperStoreyFloorAtTenMetres)
{
	// The same floor + wall scene 10 m up (map frame of a multi-storey building).
	ElevationGrid grid;
	std::mt19937 rng(1);
	gam::BinnedPoints b;
	gamtest::sampleSurfaceIf(
		grid, FloorWallBox::isFloor, [](double, double) { return 10.0; }, 3, 0.003, rng, b);
	gamtest::sampleColumns(grid, 2.5, 2.6, -3, 3, 10.0, 12.0, 0.05, b);
	gamtest::insertAll(grid, b);
	RrtGroundDetector det;
	GroundDetection out;
	det.detect(grid, {0, 0, 10}, out);
	ASSERT_EQ(out.status, Status::Ok) << out.describe();
	EXPECT_LT(rad2deg(out.plane().tiltAngle()), 0.5);
	EXPECT_NEAR(out.plane().heightAt(0, 0), 10.0, 0.005);
	for (const auto& n : out.nodes) EXPECT_TRUE(FloorWallBox::isFloor(n.x, n.y));
	// Expecting the ground floor there finds nothing.
	det.detect(grid, {0, 0, 0}, out);
	EXPECT_EQ(out.status, Status::NoValidSeed);
}

TEST(RrtGroundDetector, SparseFloorNeedsIdw)
{
	// Only every other cell in x and y observed: each 3x3 neighbourhood has at
	// most 4 observed cells (< min_valid_cells = 5) -> no seed. IDW fills the
	// gaps and the floor is found; the estimates never become observations.
	ElevationGrid grid;
	std::mt19937 rng(1);
	gam::BinnedPoints b;
	const GridGeometry& g = grid.geometry();
	gamtest::sampleSurfaceIf(
		grid,
		[&](double x, double y) { return gamtest::inRect(x, y, -3, 3, -3, 3) && g.ix(x) % 2 == 0 && g.iy(y) % 2 == 0; },
		[](double, double) { return 0.0; }, 2, 0.003, rng, b);
	gamtest::insertAll(grid, b);
	const size_t observed = grid.observedCount();
	ASSERT_EQ(observed, 60u * 60u);
	RrtGroundDetector det;
	GroundDetection out;
	det.detect(grid, {0, 0, 0}, out);
	EXPECT_EQ(out.status, Status::NoValidSeed);

	IdwParams ip;
	ip.radius_cells = 1;
	EXPECT_GT(grid.interpolateIdw(ip), 3000u);
	EXPECT_EQ(grid.observedCount(), observed);
	det.detect(grid, {0, 0, 0}, out);
	ASSERT_EQ(out.status, Status::Ok) << out.describe();
	EXPECT_NEAR(out.plane().heightAt(0, 0), 0.0, 0.005);
	EXPECT_LT(rad2deg(out.plane().tiltAngle()), 0.5);
}

TEST(RrtGroundDetector, PatchSlopeWeighsNodeCentresAndLocalPlanesByTheirPrecision)
{
	// Four nodes of a patch spread 1 m along x (variance 1.0 m^2) and 0.1 m
	// across (variance 0.01 m^2); the centres' plane rises 0.12 along x and
	// -0.03 along y with a residual variance of 0.0004 m^2 (2 cm rms).
	// Their local planes' slopes: along x 0.09, 0.11, 0.09, 0.11 (mean 0.10,
	// population variance 0.0001), along y 0.02, 0, 0.02, 0 (mean 0.01,
	// population variance 0.0001).
	const Eigen::Vector2d nodes(0.12, -0.03);
	Eigen::Matrix2d spread;
	spread << 1.0, 0.0, 0.0, 0.01;
	const std::vector<Eigen::Vector2d> local{{0.09, 0.02}, {0.11, 0.0}, {0.09, 0.02}, {0.11, 0.0}};
	const Eigen::Vector2d g = combinedPatchGradient(nodes, 0.0004, spread, local);
	// Variance of the mean local slope: 0.0001 / (4 - 1) = 3.333e-5 on both
	// axes. Of the centres' slope: 0.0004 / (4 x 1.0) = 1e-4 along x,
	// 0.0004 / (4 x 0.01) = 0.01 across.
	// x: (0.10 / 3.333e-5 + 0.12 / 1e-4) / (1 / 3.333e-5 + 1 / 1e-4)
	//    = (3000 + 1200) / (30000 + 10000) = 0.105
	// y: (0.01 / 3.333e-5 - 0.03 / 0.01) / (30000 + 100) = 297 / 30100 = 0.0098671
	EXPECT_NEAR(g.x(), 0.105, 1e-9);
	EXPECT_NEAR(g.y(), 297.0 / 30100.0, 1e-9);

	// A line of nodes (no spread across it): the roll is the local planes'
	// alone (0.01), the slope along the line still weighted (0.105).
	spread << 1.0, 0.0, 0.0, 0.0;
	const Eigen::Vector2d line = combinedPatchGradient(nodes, 0.0004, spread, local);
	EXPECT_NEAR(line.x(), 0.105, 1e-9);
	EXPECT_NEAR(line.y(), 0.01, 1e-9);

	// Centres exactly on their plane: it wins outright.
	spread << 1.0, 0.0, 0.0, 0.01;
	const Eigen::Vector2d exact = combinedPatchGradient(nodes, 0.0, spread, local);
	EXPECT_NEAR(exact.x(), 0.12, 1e-12);
	EXPECT_NEAR(exact.y(), -0.03, 1e-12);
}

// The nearest-node query of RRT-GPD (nearestPoint): the nearest of n points,
// ties to the lowest index, wherever the candidates lie: it tests four
// points a step in four lanes (lane j: indices j, j + 4, ..., up to
// 4 floor(n / 4) - 1), the rest one by one (the tail).
namespace
{
// n points at (5, 5), but for the given (index, x, y).
struct PointSet
{
	std::vector<float> x, y;
	PointSet(size_t n, std::initializer_list<std::tuple<size_t, float, float>> at) : x(n, 5.f), y(n, 5.f)
	{
		for (const auto& [i, px, py] : at)
		{
			x[i] = px;
			y[i] = py;
		}
	}
	uint32_t nearest(float& d2) const { return nearestPoint(x.data(), y.data(), x.size(), 0.f, 0.f, d2); }
};
}  // namespace

TEST(RrtNearestPoint, FindsTheNearestAndBreaksTiesTowardTheLowestIndex)
{
	float d2 = -1.f;
	// Query (0, 0) throughout; every other point at (5, 5), d2 = 50.
	// Squared distances by hand: (3, 4) -> 25, (0, 2) -> 4, (1, 1) -> 2,
	// (-1, 1) -> 2, (0, -1.5) -> 2.25, (1, -1) -> 2, (1, 0) -> 1,
	// (0.5, 0) -> 0.25.
	// Fewer than four points (all in the tail): 1 and 2 tie at d2 = 2, 0 is
	// at 25: 1 wins.
	const PointSet few(3, {{0, 3.f, 4.f}, {1, 1.f, 1.f}, {2, -1.f, 1.f}});
	EXPECT_EQ(few.nearest(d2), 1u);
	EXPECT_EQ(d2, 2.f);
	// One point.
	EXPECT_EQ(PointSet(1, {{0, 3.f, 4.f}}).nearest(d2), 0u);
	EXPECT_EQ(d2, 25.f);
	// n = 7: lanes hold 0-3, the tail 4-6. Indices 2 (lane 2), 3 (lane 3)
	// and 6 (tail) tie at 2; 2 wins.
	const PointSet seven(
		7, {{0, 3.f, 4.f}, {1, 0.f, 2.f}, {2, 1.f, 1.f}, {3, -1.f, 1.f}, {5, 0.f, -1.5f}, {6, 1.f, -1.f}});
	EXPECT_EQ(seven.nearest(d2), 2u);
	EXPECT_EQ(d2, 2.f);
	// A tie across lanes where the later lane holds the lower index: 8
	// (lane 0) and 1 (lane 1) at d2 = 1: 1 wins.
	EXPECT_EQ(PointSet(16, {{8, 1.f, 0.f}, {1, -1.f, 0.f}}).nearest(d2), 1u);
	EXPECT_EQ(d2, 1.f);
	// ... and where the earlier lane holds the lower index: 1 (lane 1) and
	// 6 (lane 2), and 13 (lane 1) too, at d2 = 1: 1 wins.
	EXPECT_EQ(PointSet(16, {{1, 1.f, 0.f}, {6, -1.f, 0.f}, {13, 0.f, 1.f}}).nearest(d2), 1u);
	EXPECT_EQ(d2, 1.f);
	// A tie within one lane: 3 and 11 (both lane 3) at d2 = 1; 3 wins.
	EXPECT_EQ(PointSet(16, {{3, 0.f, 1.f}, {11, 0.f, -1.f}}).nearest(d2), 3u);
	EXPECT_EQ(d2, 1.f);
	// The nearest in the tail (n = 10: lanes hold 0-7, the tail 8 and 9).
	EXPECT_EQ(PointSet(10, {{8, 1.f, 0.f}, {9, 0.5f, 0.f}}).nearest(d2), 9u);
	EXPECT_EQ(d2, 0.25f);
	// A tie between a lane (index 1) and the tail (index 8): the lane's.
	EXPECT_EQ(PointSet(10, {{1, 0.f, 0.5f}, {8, -0.5f, 0.f}}).nearest(d2), 1u);
	EXPECT_EQ(d2, 0.25f);
	// Nearer points later in the same lane replace earlier ones: lane 0 holds
	// 0 (d2 25), 4 (4), 8 (2); lane 1 holds 5 (2.25): 8 wins.
	EXPECT_EQ(PointSet(12, {{0, 3.f, 4.f}, {4, 0.f, 2.f}, {8, 1.f, 1.f}, {5, 0.f, -1.5f}}).nearest(d2), 8u);
	EXPECT_EQ(d2, 2.f);
}

TEST(RrtFloorTest, TheFloorHoldsMoreNodesOnlyBeyondThreeSigmaOfMcNemarsDifference)
{
	// Nodes along y = 0 every 0.1 m. The plane z = 0.05 x (2.9 deg) against
	// the floor z = 0, each holding the nodes within 2.5 cm of it.
	// The plane's unit normal is (-0.05, 0, 1) / sqrt(1.0025), so a node on
	// the floor at x lies 0.05 x / 1.00125 from it: within 2.5 cm for
	// x <= 0.50063, i.e. x = 0.0 ... 0.5, six nodes. A node on the plane at
	// x lies 0.05 x from the floor: within 2.5 cm for x <= 0.5 (the same six).
	const Plane plane = [] {
		const double n = std::sqrt(1.0 + 0.05 * 0.05);
		return Plane{-0.05 / n, 0, 1 / n, 0};
	}();
	const Plane floor{0, 0, 1, 0};
	auto onFloor = [](int count) {
		std::vector<Eigen::Vector3d> v;
		for (int i = 0; i < count; i++) v.emplace_back(0.1 * i, 0, 0);
		return v;
	};
	// 15 floor nodes (x to 1.4): 9 only the floor's (x = 0.6 ... 1.4), none
	// only the plane's; 9 - 0 = 9 is not more than 3 sqrt(9) = 9.
	EXPECT_FALSE(floorHoldsMoreNodes(onFloor(15), plane, floor, 0.025, 3.0));
	// 16 (x to 1.5): 10 > 3 sqrt(10) = 9.49.
	EXPECT_TRUE(floorHoldsMoreNodes(onFloor(16), plane, floor, 0.025, 3.0));
	// With 2 sigma, 15 nodes are enough: 9 > 2 sqrt(9) = 6.
	EXPECT_TRUE(floorHoldsMoreNodes(onFloor(15), plane, floor, 0.025, 2.0));
	// The 16 floor nodes and 4 nodes on the plane only (x = 2.0 ... 2.3,
	// z = 0.05 x, 10 to 11.5 cm above the floor): 10 - 4 = 6 is not more
	// than 3 sqrt(14) = 11.2.
	std::vector<Eigen::Vector3d> mixed = onFloor(16);
	for (int i = 0; i < 4; i++) mixed.emplace_back(2.0 + 0.1 * i, 0, 0.05 * (2.0 + 0.1 * i));
	EXPECT_FALSE(floorHoldsMoreNodes(mixed, plane, floor, 0.025, 3.0));
	// Nodes on the plane (x = 0 ... 1.9): 14 only the plane's, none only the
	// floor's: the plane holds more, never the floor.
	std::vector<Eigen::Vector3d> sloped;
	for (int i = 0; i < 20; i++) sloped.emplace_back(0.1 * i, 0, 0.005 * i);
	EXPECT_FALSE(floorHoldsMoreNodes(sloped, plane, floor, 0.025, 3.0));
	EXPECT_TRUE(floorHoldsMoreNodes(sloped, floor, plane, 0.025, 3.0));
	// No node only one of them holds: no difference, no test passes.
	EXPECT_FALSE(floorHoldsMoreNodes(onFloor(6), plane, floor, 0.025, 0.0));
	EXPECT_FALSE(floorHoldsMoreNodes({}, plane, floor, 0.025, 3.0));
}
