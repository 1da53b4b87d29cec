// The fusion rules of CGroundAwareOccupancyGrid over time (issue #14), each on
// a small hand-built sequence of exact depth frames.
//
// Cells hold MRPT's int8 log-odds of being FREE, 16 units per unit of
// log-odds, clamped to [-127, 127] (mrpt/maps/CLogOddsGridMapLUT.h). The map
// turns a piece of evidence P(occupied) into pFree = 1 - P and adds
// p2l(pFree) = round(16 logit(floor(127 pFree) / 127)):
//  * a dense obstacle voxel, P = 0.5 + 0.5 K_m = 0.9: pFree 0.1 -> 12 / 127 =
//    0.094488 -> logit -2.2617 -> -36;
//  * floor on the plane, P = 0.5 - K_g = 0.2: pFree 0.8 -> 101 / 127 = 0.795276
//    -> logit 1.3564 -> +22.
// So an obstacle saturates at -127 after 4 frames (-144), and once it is gone
// the floor frees it after 6 frames: -127 + 5 * 22 = -17 (still occupied),
// -127 + 6 * 22 = +5 (free). The clamp bounds how long clearing takes.
#include <gtest/gtest.h>
#include <mrpt/maps/CGroundAwareOccupancyGrid.h>
#include <mrpt/obs/CObservation3DRangeScan.h>

#include <cmath>

#include "synthetic_scene.h"

using namespace mrpt::maps;
using mrpt::DEG2RAD;
using mrpt::poses::CPose3D;
using testscene::Box;

namespace
{
const CPose3D kKinect(0.1, 0, 0.8, 0, DEG2RAD(25.0), 0);

// A 30 x 30 cm box, 20 cm high, at x 1.6-1.9 (centre cell (1.75, 0)).
const Box kBox{1.6, -0.15, 0.0, 1.9, 0.15, 0.2};

std::vector<Box> floorAnd(const std::vector<Box>& extra, bool hole = false)
{
	// A 0.4 x 0.4 m pit 0.3 m deep at x 2.4-2.8, y 0.4-0.8 when `hole`.
	auto s =
		hole ? testscene::floorWithHole(-6, 8, -6, 6, 2.4, 2.8, 0.4, 0.8, 0.3) : testscene::floorWithHole(-6, 8, -6, 6);
	for (const Box& b : extra) s.push_back(b);
	return s;
}

mrpt::obs::CObservation3DRangeScan::Ptr frame(const std::vector<Box>& scene, const CPose3D& robot, double t)
{
	auto o = testscene::renderDepth(scene, kKinect, robot);
	o->timestamp = mrpt::Clock::fromDouble(1000.0 + t);
	return o;
}

int rawCell(const COccupancyGridMap2D& g, double x, double y)
{
	return int(g.getRawMap()[size_t(g.x2idx(float(x))) + size_t(g.y2idx(float(y))) * g.getSizeX()]);
}
}  // namespace

TEST(FusionRules, ClampingBoundsHowLongAnObstacleTakesToClear)
{
	CGroundAwareOccupancyGrid g;
	for (int i = 0; i < 6; i++) g.insertObservation(*frame(floorAnd({kBox}), CPose3D(), 0.1 * i));
	EXPECT_EQ(rawCell(g, 1.75, 0.0), -127) << "saturated: 4 x -36 = -144 -> clamp";
	// The box is removed: floor seen there from the same place.
	for (int k = 1; k <= 6; k++)
	{
		g.insertObservation(*frame(floorAnd({}), CPose3D(), 0.6 + 0.1 * k));
		EXPECT_EQ(rawCell(g, 1.75, 0.0), -127 + 22 * k) << "after " << k << " floor frames";
	}
	EXPECT_LT(1.0 - g.getPos(1.75f, 0.0f), 0.5) << "free after 6 frames";
}

TEST(FusionRules, AHoleOutOfViewStaysAndNoCellOutsideTheViewChanges)
{
	// Frame 0 sees a pit; then the robot turns round (yaw 180 deg) and looks
	// at plain floor behind it for 20 frames: the pit cannot move, nothing
	// sees it, so its cells keep their exact values; neither does any cell
	// outside what each frame sees change.
	CGroundAwareOccupancyGrid g;
	g.insertObservation(*frame(floorAnd({}, true), CPose3D(), 0));
	const double hx = 2.6, hy = 0.6;
	ASSERT_GT(1.0 - g.getPos(float(hx), float(hy)), 0.7) << "the pit is marked";
	const int pit = rawCell(g, hx, hy);
	const CPose3D turned(0, 0, 0, DEG2RAD(180.0), 0, 0);
	for (int i = 1; i <= 20; i++)
	{
		const std::vector<int8_t> before = g.getRawMap();
		const unsigned sx0 = g.getSizeX();
		const float x0 = g.getXMin(), y0 = g.getYMin();
		g.insertObservation(*frame(floorAnd({}, true), turned, 0.1 * i), turned);
		EXPECT_EQ(rawCell(g, hx, hy), pit) << "frame " << i;
		// Facing -x from x = -0.1 (the camera), a frame sees only x < -0.1:
		// every cell with x > 0 must be as it was (the grid may have grown,
		// so compare by position).
		size_t changed = 0;
		for (size_t c = 0; c < before.size(); c++)
		{
			const float x = x0 + (float(c % sx0) + 0.5f) * g.getResolution();
			const float y = y0 + (float(c / sx0) + 0.5f) * g.getResolution();
			if (x <= 0.0f) continue;
			changed += rawCell(g, x, y) != int(before[c]);
		}
		EXPECT_EQ(changed, 0u) << "frame " << i;
	}
}

TEST(FusionRules, DecayForgetsPeopleNotHoles)
{
	// obstacle_decay_s = 1: a box seen at t = 0 .. 0.4 s and a pit seen at the
	// same time; then the robot turns round until t = 2.0 s. The box was last
	// seen at 0.4 s: still occupied at t = 1.4 s, unknown once t - 0.4 > 1
	// (the frame at 1.5 s). The pit never decays. With decay off (the
	// default) the box stays.
	for (double decay : {1.0, 0.0})
	{
		CGroundAwareOccupancyGrid g;
		auto o = g.groundOptions();
		o.obstacle_decay_s = decay;
		g.setGroundOptions(o);
		for (int i = 0; i <= 4; i++) g.insertObservation(*frame(floorAnd({kBox}, true), CPose3D(), 0.1 * i));
		ASSERT_GT(1.0 - g.getPos(1.75f, 0.0f), 0.7);
		ASSERT_GT(1.0 - g.getPos(2.6f, 0.6f), 0.7);
		const int pit = rawCell(g, 2.6, 0.6);
		const CPose3D turned(0, 0, 0, DEG2RAD(180.0), 0, 0);
		for (int i = 5; i <= 20; i++)
		{
			const double t = 0.1 * i;
			g.insertObservation(*frame(floorAnd({kBox}, true), turned, t), turned);
			const bool gone = decay > 0 && t - 0.4 > decay + 1e-9;
			if (gone)
				EXPECT_EQ(rawCell(g, 1.75, 0.0), 0) << "t=" << t << ": unknown";
			else
				EXPECT_LT(rawCell(g, 1.75, 0.0), -100) << "t=" << t << " decay " << decay;
			EXPECT_EQ(rawCell(g, 2.6, 0.6), pit) << "t=" << t << ": a hole never decays";
		}
	}
}

TEST(FusionRules, DecayIsAnOption)
{
	CGroundAwareOccupancyGrid::TGroundAwareOptions o;
	EXPECT_EQ(o.obstacle_decay_s, 0.0) << "off by default";
	o.obstacle_decay_s = -1;
	CGroundAwareOccupancyGrid g;
	EXPECT_THROW(g.setGroundOptions(o), std::invalid_argument);
}
