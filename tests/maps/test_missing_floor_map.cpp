// Missing floor in CGroundAwareOccupancyGrid (issue #13) on exact synthetic
// depth frames: a hole deeper than the range (its rays return nothing), a
// black mat (the floor is there, its pixels return nothing), and a hole
// outside the field of view.
#include <gtest/gtest.h>
#include <mrpt/maps/CGroundAwareOccupancyGrid.h>
#include <mrpt/obs/CObservation3DRangeScan.h>

#include "synthetic_scene.h"

using namespace mrpt::maps;
using mrpt::DEG2RAD;
using mrpt::poses::CPose3D;
using testscene::Box;

namespace
{
// A walker's Kinect One: 0.8 m up, pitched 25 deg down.
const CPose3D kKinect(0.1, 0, 0.8, 0, DEG2RAD(25.0), 0);

double pOcc(const COccupancyGridMap2D& g, double x, double y) { return 1.0 - g.getPos(float(x), float(y)); }

using testscene::blackOut;

size_t missingCells(const CGroundAwareOccupancyGrid& g)
{
	const COccupancyGridMap2D& L = g.missingFloorLayer();
	size_t n = 0;
	for (unsigned y = 0; y < L.getSizeY(); y++)
		for (unsigned x = 0; x < L.getSizeX(); x++) n += L.getCell(x, y) < 0.5f;
	return n;
}
}  // namespace

/** A 0.4 x 0.6 m pit at x 2.5-2.9, 0.3 m deep, painted black: the rays
 * entering it return nothing. */
mrpt::obs::CObservation3DRangeScan::Ptr darkHoleFrame()
{
	auto o = testscene::renderDepth(testscene::floorWithHole(-1, 8, -4, 4, 2.5, 2.9, -0.3, 0.3, 0.3), kKinect);
	blackOut(*o, 2.5, 2.9, -0.3, 0.3);
	return o;
}

TEST(MissingFloorMap, DarkHoleIsMissingFloorAndBlocks)
{
	CGroundAwareOccupancyGrid g;
	g.insertObservation(*darkHoleFrame());
	ASSERT_TRUE(g.lastFrame().detection.ok());
	const auto& st = g.lastFrame().missing;
	EXPECT_TRUE(st.applied);
	EXPECT_GE(st.regions, 1u) << "rays " << st.rays << " empty " << st.empty_rays << " candidates " << st.candidates
							  << " unbordered " << st.unbordered;
	// The opening, 1 cell inside its edges: x 2.55..2.85, y -0.25..0.25.
	int inside = 0, marked = 0, blocked = 0;
	for (double x = 2.575; x < 2.85; x += 0.05)
		for (double y = -0.225; y < 0.25; y += 0.05)
		{
			inside++;
			marked += g.isMissingFloor(float(x), float(y));
			blocked += pOcc(g, x, y) > 0.5;
		}
	EXPECT_GE(marked, inside * 9 / 10) << marked << " of " << inside;
	EXPECT_GE(blocked, inside * 9 / 10) << blocked << " of " << inside;
	// The floor before and beyond it is seen, free and not missing.
	for (auto [x, y] : {std::pair{2.0, 0.0}, {3.4, 0.0}, {2.7, 0.8}})
	{
		EXPECT_FALSE(g.isMissingFloor(float(x), float(y))) << x << "," << y;
		EXPECT_LT(pOcc(g, x, y), 0.3) << x << "," << y;
	}
	// The layer is a grid of the same geometry.
	EXPECT_EQ(g.missingFloorLayer().getSizeX(), g.getSizeX());
	EXPECT_EQ(g.missingFloorLayer().getXMin(), g.getXMin());
}

TEST(MissingFloorMap, BlackMatIsMissingUntilFloorIsSeenThere)
{
	// At one instant a black mat looks like a dark hole: marked, and it blocks.
	CGroundAwareOccupancyGrid g;
	const auto plainFloor = testscene::floorWithHole(-1, 8, -4, 4);
	auto withMat = testscene::renderDepth(plainFloor, kKinect);
	blackOut(*withMat, 2.5, 3.1, -0.45, 0.45);
	g.insertObservation(*withMat);
	EXPECT_TRUE(g.isMissingFloor(2.8f, 0.0f));
	EXPECT_GT(pOcc(g, 2.8, 0.0), 0.5);
	// Floor seen there (the mat taken away, or seen from another angle): the
	// layer clears at once. The grid needs the ISM's floor evidence to outweigh
	// one frame of missing floor: +ln(0.9 / 0.1) = +2.20 against
	// ln(0.2 / 0.8) = -1.39 per floor frame (P = 0.5 - K_g = 0.2 on the plane),
	// so 2.20 - 1.39 = 0.81 > 0 (still occupied) after one, 0.81 - 1.39 < 0
	// (free) after two.
	const auto plain = testscene::renderDepth(plainFloor, kKinect);
	g.insertObservation(*plain);
	EXPECT_FALSE(g.isMissingFloor(2.8f, 0.0f));
	EXPECT_GT(g.missingFloorLayer().getPos(2.8f, 0.0f), 0.5f) << "the layer says: floor seen";
	EXPECT_GT(pOcc(g, 2.8, 0.0), 0.5);
	g.insertObservation(*plain);
	EXPECT_LT(pOcc(g, 2.8, 0.0), 0.5);
}

TEST(MissingFloorMap, OutsideTheFieldOfViewIsNeverMarked)
{
	// Pits beyond the range everywhere the camera does not look: beside it
	// (y 2.0-2.6 at x 2: the 70.6 deg view reaches |y| = 1.9 tan(35.3 deg) =
	// 1.35 m there), behind the robot, and under its nose (x 0.1-0.4: the lowest
	// ray, 25 + 30 = 55 deg down from 0.8 m, meets the floor 0.8 / tan(55 deg)
	// = 0.56 m ahead of the camera, at x = 0.66).
	std::vector<Box> scene;
	for (auto& b : testscene::floorWithHole(-1, 8, -4, 4, 2.0, 2.6, 2.0, 2.6, 10.0)) scene.push_back(b);
	CGroundAwareOccupancyGrid g;
	auto o = testscene::renderDepth(scene, kKinect);
	// Under the nose and behind: no pixel meets the floor there, whatever
	// the image holds; blank the lowest rows too (the robot's own bumper
	// returning nothing): with no floor seen nearer, it is not a gap.
	for (int r = int(o->rangeImage.rows()) - 10; r < int(o->rangeImage.rows()); r++)
		for (int c = 0; c < int(o->rangeImage.cols()); c++) o->rangeImage(r, c) = 0;
	g.insertObservation(*o);
	ASSERT_TRUE(g.lastFrame().detection.ok());
	EXPECT_EQ(missingCells(g), 0u);
	EXPECT_EQ(g.lastFrame().missing.cells, 0u);
	EXPECT_FALSE(g.isMissingFloor(2.3f, 2.3f));
	EXPECT_NEAR(pOcc(g, 2.3, 2.3), 0.5, 1e-3) << "unknown";
	EXPECT_NEAR(pOcc(g, 0.3, 0.0), 0.5, 1e-3) << "under the nose: unknown";
}

TEST(MissingFloorMap, BlockRangeDecidesWhatBlocks)
{
	// missing_floor_block_range = 0: the pit is in the layer, not in the grid
	// (unknown there); 2.6 m: only what lies within 2.6 m of the camera blocks.
	for (double range : {0.0, 2.6})
	{
		CGroundAwareOccupancyGrid g;
		auto o = g.groundOptions();
		o.pipeline.missing.block_range = range;
		g.setGroundOptions(o);
		g.insertObservation(*darkHoleFrame());
		EXPECT_TRUE(g.isMissingFloor(2.7f, 0.0f)) << range;
		EXPECT_EQ(g.lastFrame().missing.blocking == 0, range == 0.0) << range;
		// The camera is at x = 0.1: the cell at x 2.575 is 2.475 m away
		// (blocks at 2.6 m), the one at x 2.825 2.725 m (does not).
		if (range == 0.0)
		{
			EXPECT_NEAR(pOcc(g, 2.7, 0.0), 0.5, 0.05) << "not folded into the grid";
		}
		if (range > 0)
		{
			EXPECT_GT(pOcc(g, 2.575, 0.0), 0.5);
			EXPECT_TRUE(g.isMissingFloor(2.825f, 0.0f));
			EXPECT_NEAR(pOcc(g, 2.825, 0.0), 0.5, 0.05);
		}
	}
}

TEST(MissingFloorMap, OptionsAreInTheIniTable)
{
	CGroundAwareOccupancyGrid::TGroundAwareOptions o;
	EXPECT_TRUE(o.pipeline.missing.enabled);
	EXPECT_EQ(o.pipeline.missing.block_range, 1000.0) << "default: missing floor blocks";
	o.pipeline.missing.alpha = 0;  // out of range
	CGroundAwareOccupancyGrid g;
	EXPECT_THROW(g.setGroundOptions(o), std::invalid_argument);
}
