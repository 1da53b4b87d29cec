// CGroundAwareOccupancyGrid on exact synthetic depth frames of known scenes.
#include <gam/maps/GridIO.h>
#include <gtest/gtest.h>
#include <mrpt/maps/CGroundAwareOccupancyGrid.h>
#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/obs/CObservation3DRangeScan.h>

#include <mrpt/system/filesystem.h>

#include <fstream>
#include <map>

#include "synthetic_scene.h"

using namespace mrpt::maps;
using mrpt::DEG2RAD;
using mrpt::poses::CPose3D;
using testscene::Box;

namespace
{
// A walker's Kinect: 1 m up, pitched 25 deg down.
const CPose3D kKinect(0, 0, 1.0, 0, DEG2RAD(25.0), 0);

// Floor with a 0.4 x 0.6 m hole (0.5 m deep) at x 2.0-2.4, a 10 cm box.
std::vector<Box> holeAndBoxScene()
{
	auto s = testscene::floorWithHole(-1, 6, -3, 3, 2.0, 2.4, -0.3, 0.3, 0.5);
	s.push_back({1.5, 0.6, 0.0, 1.7, 0.8, 0.10});
	return s;
}

double pOcc(const COccupancyGridMap2D& g, double x, double y) { return 1.0 - g.getPos(float(x), float(y)); }
// The most occupied of the cell at (x, y) and its 8 neighbours: a beam's end
// point is one cell, which a point on the same arc may miss by a cell.
double pOccNear(const COccupancyGridMap2D& g, double x, double y)
{
	const double r = g.getResolution();
	double p = 0;
	for (int dy = -1; dy <= 1; dy++)
		for (int dx = -1; dx <= 1; dx++) p = std::max(p, pOcc(g, x + dx * r, y + dy * r));
	return p;
}

// A level planar scan of `beams` valid beams over `apertureDeg`, 50 m max range.
mrpt::obs::CObservation2DRangeScan planarScan(double apertureDeg, size_t beams, const CPose3D& sensorPose)
{
	mrpt::obs::CObservation2DRangeScan s;
	s.aperture = float(DEG2RAD(apertureDeg));
	s.rightToLeft = true;
	s.maxRange = 50;
	s.sensorPose = sensorPose;
	s.resizeScan(beams);
	for (size_t i = 0; i < beams; i++) s.setScanRangeValidity(i, true);
	return s;
}

// A Leddar IS16 (16 segments over 45 deg) 0.3 m up, seeing a wall 3 m ahead.
mrpt::obs::CObservation2DRangeScan leddarWallScan()
{
	auto s = planarScan(45.0, 16, CPose3D(0.2, 0, 0.3, 0, 0, 0));
	for (size_t i = 0; i < 16; i++)
	{
		const double a = -s.aperture / 2 + (i + 0.5) * s.aperture / 16;
		s.setScanRange(i, float(2.8 / std::cos(a)));  // wall at x = 3.0 in the robot frame
	}
	return s;
}
}  // namespace

TEST(GroundAwareGrid, FloorFreeBoxAndHoleOccupied)
{
	CGroundAwareOccupancyGrid g;
	g.insertObservation(*testscene::renderDepth(holeAndBoxScene(), kKinect));
	const auto& d = g.lastFrame();
	ASSERT_TRUE(d.detection.ok()) << d.detection.describe();
	EXPECT_NEAR(d.detection.plane().tiltAngle(), 0.0, DEG2RAD(0.5));
	EXPECT_NEAR(d.detection.plane().heightAt(1, 0), 0.0, 0.01);
	EXPECT_GT(d.ism.drop, 0u);
	EXPECT_GT(d.ism.drop_ray_cells, 0u);

	EXPECT_LT(pOcc(g, 1.0, -0.5), 0.3) << "floor";
	EXPECT_LT(pOcc(g, 2.8, 0.0), 0.3) << "floor beyond the hole";
	EXPECT_GT(pOcc(g, 1.6, 0.7), 0.7) << "box";
	EXPECT_GT(pOcc(g, 2.2, 0.0), 0.7) << "hole centre";
	EXPECT_GT(pOcc(g, 2.05, 0.0), 0.7) << "hole near edge (only drop rays see it)";
	// Outside the field of view: unknown.
	EXPECT_NEAR(pOcc(g, -0.5, 0.0), 0.5, 1e-3);
}

TEST(GroundAwareGrid, HeightBandBaselineMissesTheSameHoleAndBox)
{
	// What pointcloud_to_laserscan (z 0.2-1.5 m) + a grid gives on the same frame.
	auto obs = testscene::renderDepth(holeAndBoxScene(), kKinect);
	mrpt::obs::T3DPointsTo2DScanParams sp;
	sp.use_origin_sensor_pose = true;
	sp.z_min = 0.2;
	sp.z_max = 1.5;
	mrpt::obs::CObservation2DRangeScan scan;
	obs->convertTo2DScan(scan, sp);
	COccupancyGridMap2D band(-10, 10, -10, 10, 0.05);
	band.insertionOptions.considerInvalidRangesAsFreeSpace = false;
	band.insertObservation(scan);
	EXPECT_LE(pOcc(band, 1.6, 0.7), 0.5);
	EXPECT_LE(pOcc(band, 2.2, 0.0), 0.5);
}

TEST(GroundAwareGrid, RampStaysFreeWithLocalPlanesOnly)
{
	// Floor, then a 2 m wide 6 deg ramp from x=2.5 to x=4 (1 cm steps every
	// 9.5 cm), then a landing.
	std::vector<Box> s = {{-1, -3, -0.1, 2.5, 3, 0.0}, {2.5, -3, -0.1, 6, -1, 0.0}, {2.5, 1, -0.1, 6, 3, 0.0}};
	const double slope = std::tan(DEG2RAD(6.0));
	for (double x = 2.5; x < 4.0 - 1e-9; x += 0.01 / slope)
		s.push_back({x, -1.0, -0.1, x + 0.01 / slope, 1.0, (x - 2.5) * slope + 0.01});
	s.push_back({4.0, -1.0, -0.1, 6.0, 1.0, 1.5 * slope});

	CGroundAwareOccupancyGrid local, global;
	auto globalOnly = global.groundOptions();
	globalOnly.pipeline.ism.local_planes = false;
	global.setGroundOptions(globalOnly);
	// The Kinect One's full 512 x 424 image: at half of it the far ramp cells
	// hold one or two samples, fewer than min_obstacle_points.
	auto obs = testscene::renderDepth(s, kKinect, {}, 512, 424);
	local.insertObservation(*obs);
	global.insertObservation(*obs);
	ASSERT_TRUE(local.lastFrame().detection.ok());
	EXPECT_NEAR(local.lastFrame().detection.plane().heightAt(1.5, 0), 0.0, 0.01) << "the floor is the main plane";
	EXPECT_GE(local.lastFrame().detection.planes.size(), 2u) << local.lastFrame().detection.describe();
	int freeLocal = 0, occGlobal = 0, n = 0;
	for (double x = 3.2; x <= 3.9; x += 0.1)
		for (double y = -0.4; y <= 0.4; y += 0.1)
		{
			n++;
			freeLocal += pOcc(local, x, y) < 0.4;
			occGlobal += pOcc(global, x, y) > 0.6;
		}
	EXPECT_GE(freeLocal, n * 8 / 10) << "ramp cells free with local planes";
	EXPECT_GE(occGlobal, n * 8 / 10) << "one global plane turns the ramp into an obstacle";
}

TEST(GroundAwareGrid, OverheadBeamDoesNotBlockButATableDoes)
{
	// A camera 0.9 m up sees a beam at 1.1-1.2 m (above robot_height = 1.0)
	// and a table top at 0.7 m (below it), both from x = 2.5.
	std::vector<Box> s = {
		{-1, -3, -0.1, 8, 3, 0.0},
		{2.5, -1.5, 1.1, 3.5, -0.5, 1.2},   // beam
		{2.5, 0.5, 0.68, 3.5, 1.5, 0.72}};  // table top
	CGroundAwareOccupancyGrid g;
	auto o = g.groundOptions();
	o.pipeline.ism.robot_height = 1.0;
	g.setGroundOptions(o);
	g.insertObservation(*testscene::renderDepth(s, CPose3D(0, 0, 0.9, 0, DEG2RAD(15.0), 0), {}, 512, 424));
	ASSERT_TRUE(g.lastFrame().detection.ok());
	int beamFree = 0, tableOcc = 0, n = 0;
	for (double x = 2.525; x < 2.9; x += 0.05)
		for (double y = -1.3; y <= -0.7; y += 0.1)
		{
			n++;
			beamFree += pOcc(g, x, y) < 0.4;
			tableOcc += pOcc(g, x, -y) > 0.6;
		}
	EXPECT_GE(beamFree, n * 9 / 10) << "floor under the beam";
	EXPECT_GE(tableOcc, n / 10) << "the table top";
	EXPECT_GT(pOcc(g, 2.525, 1.0), 0.7) << "the table's front edge";
}

TEST(GroundAwareGrid, NoFloorInViewChangesNothing)
{
	// Camera looking up at a wall 1.5 m away: no floor, so no plane.
	std::vector<Box> s = {{1.5, -3, 0.5, 1.7, 3, 3.0}, {1.0, -0.5, 1.2, 1.5, 0.5, 1.25}};
	CGroundAwareOccupancyGrid g;
	const auto before = g.getRawMap();
	EXPECT_TRUE(g.insertObservation(*testscene::renderDepth(s, CPose3D(0, 0, 1.5, 0, DEG2RAD(-20.0), 0))));
	EXPECT_FALSE(g.lastFrame().detection.ok());
	EXPECT_TRUE(g.lastFrameIsm().evidenceCells().empty());
	EXPECT_EQ(g.getRawMap(), before) << "a frame without ground must not invent obstacles";
}

TEST(GroundAwareGrid, TiltedRolledMountAndRobotPose)
{
	// Sensor rolled 8 deg and pitched 30 deg; robot at (1, 2) facing +y.
	const CPose3D robot(1.0, 2.0, 0, DEG2RAD(90.0), 0, 0);
	const CPose3D mount(0.1, 0.05, 1.1, DEG2RAD(3.0), DEG2RAD(30.0), DEG2RAD(8.0));
	// In the world: a box 1.5 m in front of the robot (world y = 3.5).
	std::vector<Box> s = {{-3, -2, -0.1, 5, 8, 0.0}, {0.9, 3.4, 0.0, 1.1, 3.6, 0.08}};
	CGroundAwareOccupancyGrid g;
	g.insertObservation(*testscene::renderDepth(s, mount, robot), robot);
	ASSERT_TRUE(g.lastFrame().detection.ok()) << g.lastFrame().detection.describe();
	EXPECT_NEAR(g.lastFrame().detection.plane().tiltAngle(), 0.0, DEG2RAD(0.5));
	EXPECT_GT(pOcc(g, 1.0, 3.5), 0.7) << "box at its world position";
	EXPECT_LT(pOcc(g, 1.0, 4.5), 0.3) << "floor behind it";
	EXPECT_LT(pOcc(g, 0.5, 3.0), 0.3) << "floor beside it";
}

TEST(GroundAwareGrid, EvidenceAccumulatesOverFrames)
{
	CGroundAwareOccupancyGrid g;
	auto obs = testscene::renderDepth(holeAndBoxScene(), kKinect);
	g.insertObservation(*obs);
	const double p1 = pOcc(g, 1.6, 0.7), f1 = pOcc(g, 1.0, -0.5);
	g.insertObservation(*obs);
	EXPECT_GT(pOcc(g, 1.6, 0.7), p1);
	EXPECT_LT(pOcc(g, 1.0, -0.5), f1);
}

namespace
{
using ScanRule = CGroundAwareOccupancyGrid::TGroundAwareOptions::ScanRule;

void setScanRule(CGroundAwareOccupancyGrid& g, ScanRule r)
{
	auto o = g.groundOptions();
	o.scan_keeps_3d_obstacles = r;
	g.setGroundOptions(o);
}
}  // namespace

TEST(GroundAwareGrid, LeddarScanFusesThroughTheBeamModel)
{
	const auto s = leddarWallScan();
	CGroundAwareOccupancyGrid walker, plain;
	setScanRule(walker, ScanRule::KeepCameraFloor);
	setScanRule(plain, ScanRule::BeamModel);
	ASSERT_TRUE(walker.insertObservation(s));
	ASSERT_TRUE(plain.insertObservation(s));
	for (const auto* m : {&walker, &plain})
	{
		EXPECT_GT(pOccNear(*m, 3.0, 0.0), 0.6);
		EXPECT_GT(pOccNear(*m, 3.0, 0.9), 0.6) << "edge segment covered (upsampled beams)";
	}
	// The plain beam model frees the space before the wall; with the walker's
	// rule a planar scan does not turn unknown floor into free floor.
	EXPECT_LT(pOcc(plain, 1.5, 0.0), 0.4);
	EXPECT_NEAR(pOcc(walker, 1.5, 0.0), 0.5, 1e-3);
}

TEST(GroundAwareGrid, AutoScanRuleIsTheBeamModelUntilTheFirstDepthFrame)
{
	// Issue #31: the default (auto) serves a lidar-only user and the walker.
	const auto s = leddarWallScan();
	CGroundAwareOccupancyGrid automatic, plain;
	ASSERT_EQ(automatic.groundOptions().scan_keeps_3d_obstacles, ScanRule::Auto);
	setScanRule(plain, ScanRule::BeamModel);
	EXPECT_FALSE(automatic.scanRuleActive());
	automatic.insertObservation(s);
	plain.insertObservation(s);
	EXPECT_EQ(automatic.getRawMap(), plain.getRawMap()) << "no depth frame yet: the stock beam model, cell for cell";
	EXPECT_LT(pOcc(automatic, 1.5, 0.0), 0.4);

	// After one depth frame the walker's rule holds: a scan frees nothing.
	automatic.insertObservation(*testscene::renderDepth(holeAndBoxScene(), kKinect));
	EXPECT_EQ(automatic.depthFramesReceived(), 1u);
	EXPECT_TRUE(automatic.scanRuleActive());
	const auto before = automatic.getRawMap();
	automatic.insertObservation(s);
	const auto& after = automatic.getRawMap();
	ASSERT_EQ(before.size(), after.size());
	size_t freer = 0;
	for (size_t i = 0; i < before.size(); i++) freer += after[i] > before[i];
	EXPECT_EQ(freer, 0u) << "cells made freer by a 2D scan after a depth frame";
	// clear() starts over: the grid is a stock grid again until its next depth frame.
	automatic.clear();
	EXPECT_EQ(automatic.depthFramesReceived(), 0u);
	EXPECT_FALSE(automatic.scanRuleActive());
}

namespace
{
// A 16-segment Leddar's scan over 45 deg, MRPT's convention: segment i at
// -22.5 + 3 i deg (s = 45 / 15 = 3 deg), every range still to be set.
mrpt::obs::CObservation2DRangeScan leddar16()
{
	mrpt::obs::CObservation2DRangeScan s;
	s.aperture = float(DEG2RAD(45.0));
	s.rightToLeft = true;
	s.maxRange = 50;
	s.resizeScan(16);
	return s;
}
}  // namespace

TEST(GroundAwareGrid, LeddarSegmentEchoStaysInItsOwnCone)
{
	// 16 segments over a 45 deg aperture: segment i points at -22.5 + 3 i deg
	// (s = 45 / 15 = 3 deg) and covers 3 deg around it. Upsampled with k = 8,
	// its rays are 3 / 8 = 0.375 deg apart: segment 0's at -22.5 - 1.5 +
	// 0.1875 = -23.8125 ... -21.1875 deg, and the new aperture is
	// (16 * 8 - 1) * 3 / 8 = 47.625 deg.
	auto s = leddar16();
	for (size_t i = 0; i < 16; i++) s.setScanRangeValidity(i, false);
	s.setScanRange(0, 6.0f);  // only segment 0 has an echo, 6 m away
	s.setScanRangeValidity(0, true);
	const auto up = CGroundAwareOccupancyGrid::upsampleSparseScan(s, 8);
	ASSERT_EQ(up.getScanSize(), 128u);
	EXPECT_NEAR(up.aperture, DEG2RAD(47.625), 1e-5);
	for (size_t o = 0; o < 8; o++) EXPECT_TRUE(up.getScanRangeValidity(o));
	EXPECT_FALSE(up.getScanRangeValidity(8));

	CGroundAwareOccupancyGrid g(-8, 8, -8, 8, 0.05f);
	ASSERT_TRUE(g.insertObservation(s));
	auto x = [](double deg) { return 6.0 * std::cos(DEG2RAD(deg)); };
	auto y = [](double deg) { return 6.0 * std::sin(DEG2RAD(deg)); };
	// The whole cone is marked (within a cell: rays 6 m x 0.375 deg = 3.9 cm
	// apart on 5 cm cells), its outer edge too: the old rays stopped at
	// -22.5 deg, the first beam's centre.
	EXPECT_GT(pOccNear(g, x(-23.7), y(-23.7)), 0.6) << "outer edge of segment 0";
	EXPECT_GT(pOccNear(g, x(-22.5), y(-22.5)), 0.6) << "centre of segment 0";
	EXPECT_GT(pOccNear(g, x(-21.3), y(-21.3)), 0.6) << "inner edge of segment 0";
	// Nothing inside segment 1's cone (-21 ... -18 deg) from 0.6 deg past its
	// border on (6 m x 0.6 deg = 6 cm, more than a 5 cm cell; the old rays
	// reached -20.0 deg).
	for (double deg = -20.4; deg <= -18.0; deg += 0.2) EXPECT_NEAR(pOcc(g, x(deg), y(deg)), 0.5, 1e-3) << deg << " deg";
}

namespace
{
// A 16-segment Leddar over 45 deg (segment i at -22.5 + 3 i deg, covering 3
// deg around it), each segment's range the nearest point of the wall x = D
// in its cone (the echo a wide beam reports): D / cos of the cone's edge
// nearest 0 deg (0 for the two central segments, whose cones end at 0).
mrpt::obs::CObservation2DRangeScan leddarFacingWall(double D)
{
	auto s = leddar16();
	for (size_t i = 0; i < 16; i++)
	{
		const double c = -22.5 + 3.0 * double(i), nearest = std::min(std::abs(c - 1.5), std::abs(c + 1.5));
		s.setScanRange(i, float(D / std::cos(DEG2RAD(c > -1.5 && c < 1.5 ? 0.0 : nearest))));
		s.setScanRangeValidity(i, true);
	}
	return s;
}
// Angle of ray o of a 16-segment, 45 deg scan upsampled with k = 8: segment
// o / 8's cone from its centre - 1.5 deg, rays 3 / 8 deg apart at the parts' centres.
double upsampledRayDeg(size_t o) { return -22.5 + 3.0 * double(o / 8) - 1.5 + (double(o % 8) + 0.5) * 0.375; }
}  // namespace

TEST(GroundAwareGrid, LeddarRaysEndOnTheWallTheSegmentsSawObliquely)
{
	// A wall 5.8 m ahead. Segment 15 (cone 21..24 deg) reports the wall's
	// nearest point in its cone, 5.8 / cos 21 = 6.2126 m. As an arc, its
	// outer ray (23.8125 deg) ended at x = 6.2126 cos 23.8125 = 5.6838 m:
	// 11.6 cm (two cells) in front of the wall. With the near-edge echoes,
	// every ray of every segment ends on the wall: x = r cos a = 5.8.
	const double D = 5.8;
	const auto s = leddarFacingWall(D);
	ASSERT_NEAR(s.getScanRange(15), 6.2126, 1e-4);
	const auto arc = CGroundAwareOccupancyGrid::upsampleSparseScan(s, 8, false);
	EXPECT_NEAR(arc.getScanRange(127) * std::cos(DEG2RAD(upsampledRayDeg(127))), 5.6838, 1e-4);
	const auto up = CGroundAwareOccupancyGrid::upsampleSparseScan(s, 8);
	ASSERT_EQ(up.getScanSize(), 128u);
	for (size_t o = 0; o < 128; o++)
	{
		ASSERT_TRUE(up.getScanRangeValidity(o));
		EXPECT_NEAR(up.getScanRange(o) * std::cos(DEG2RAD(upsampledRayDeg(o))), D, 1e-4) << "ray " << o;
		// Never nearer than the segment's echo (nothing in its cone is).
		EXPECT_GE(up.getScanRange(o), s.getScanRange(o / 8) - 1e-6f) << "ray " << o;
	}
	// In the grid (MRPT's beam model: no depth frame yet): occupied cells
	// more than a cell in front of the wall (centres x <= 5.725). The arcs
	// put some there: segment 15's rays end at x = 6.2126 cos a < 5.75 for
	// a > 22.26 deg (its 5 outer rays), segment 14's (6.0985 m) for a >
	// 19.45 deg, and so on inward. On the wall: none.
	CGroundAwareOccupancyGrid g(-8, 8, -8, 8, 0.05f), arcGrid(-8, 8, -8, 8, 0.05f);
	auto o = arcGrid.groundOptions();
	o.sparse_scan_near_edge = false;
	arcGrid.setGroundOptions(o);
	ASSERT_TRUE(g.insertObservation(s));
	ASSERT_TRUE(arcGrid.insertObservation(s));
	const auto inFront = [&](const CGroundAwareOccupancyGrid& grid) {
		int n = 0;
		for (double x = 4.025; x < 5.75; x += 0.05)
			for (double y = -3.0; y <= 3.0; y += 0.05) n += pOcc(grid, x, y) > 0.5;
		return n;
	};
	EXPECT_GE(inFront(arcGrid), 10);
	EXPECT_EQ(inFront(g), 0);
	for (double deg : {-23.5, 0.0, 23.5})
		EXPECT_GT(pOccNear(g, D, D * std::tan(DEG2RAD(deg))), 0.6) << deg << " deg: the wall";
}

TEST(GroundAwareGrid, LeddarRaysInACorridorEndOnBothWalls)
{
	// A corridor 2.87 m wide (wall faces y = +-1.435) closed 7.8 m ahead, the
	// Leddar on its axis. Each segment's echo: the nearest wall point in its
	// cone (found on 3001 directions). A ray that ends on a wall is within
	// 2 cm of it, on either side: the two halves are mirror images.
	auto s = leddar16();
	const auto wallRange = [](double a) {
		const double toSide = std::abs(std::sin(a)) > 1e-9 ? 1.435 / std::abs(std::sin(a)) : 1e9;
		return std::min(toSide, 7.8 / std::cos(a));
	};
	for (size_t i = 0; i < 16; i++)
	{
		double best = 1e9;
		for (int q = 0; q <= 3000; q++) best = std::min(best, wallRange(DEG2RAD(-24.0 + 3.0 * i + 3.0 * q / 3000.0)));
		s.setScanRange(i, float(best));
		s.setScanRangeValidity(i, true);
	}
	const auto up = CGroundAwareOccupancyGrid::upsampleSparseScan(s, 8);
	for (size_t o = 0; o < 128; o++)
	{
		const double a = DEG2RAD(upsampledRayDeg(o)), r = up.getScanRange(o);
		EXPECT_LE(r, wallRange(a) + 0.02) << "ray " << o << " ends behind the wall";
		EXPECT_NEAR(r, up.getScanRange(127 - o), 1e-3) << "ray " << o << " and its mirror image";
		// Segments 0-3 and 12-15 see a side wall over the whole cone and so
		// do their neighbours, segments 6-9 the end wall (the side walls end
		// at atan(1.435 / 7.8) = 10.4 deg, in segments 4 and 11): on the wall.
		const size_t seg = o / 8;
		if (seg <= 3 || seg >= 12 || (seg >= 6 && seg <= 9))
		{
			EXPECT_NEAR(r, wallRange(a), 0.02) << "ray " << o << " of segment " << seg;
		}
	}
	// The concave corners (the side walls end at atan(1.435 / 7.8) = 10.424
	// deg, in segments 4 and 11). Segment 4 (cone -12..-9 deg, echo 6.9020 m
	// on the side wall at -12) recedes toward segment 5 (7.8430 m: the end
	// wall at -6 deg), a local maximum of the ranges (segment 6: 7.8107 m).
	// The side wall's line, through segment 3's echo (5.5444 m at -15 deg)
	// and segment 4's, meets segment 5's direction (-9 deg) at 1.435 / sin 9
	// = 9.173 m, behind 7.8430: a corner. Segment 4's rays end on the side
	// wall (its line, exact on the wall) but no farther than 7.8430 m: its
	// rays at -11.8125 .. -10.6875 deg on the wall, 7.0099 .. 7.7378 m; those
	// past the corner (-10.3125 .. -9.1875 deg, the end wall 7.8/cos: 7.9281
	// .. 7.9014 m) at 7.8430 m, 8.5 .. 5.8 cm in front of it. The chord from
	// (6.9020 m, -12 deg) to (7.8430 m, -9 deg) cut the corner: the ray at
	// -10.3125 deg ended on it at 7.399 m, 53 cm in front of the end wall.
	for (size_t j = 0; j < 8; j++)
	{
		const double a = DEG2RAD(upsampledRayDeg(32 + j)), r = up.getScanRange(32 + j);
		if (j < 4)
			EXPECT_NEAR(r, wallRange(a), 0.002) << "segment 4, ray " << j << ": on the side wall";
		else
		{
			EXPECT_NEAR(r, 7.8430, 0.0005) << "segment 4, ray " << j << ": at segment 5's echo";
			EXPECT_LT(wallRange(a) - r, 0.086);
		}
	}
	EXPECT_NEAR(wallRange(DEG2RAD(upsampledRayDeg(36))), 7.9281, 1e-4);
	// Only on one straight surface: with segment 2's echo (at -18 deg) moved
	// from 4.6438 to 4.2 m, it lies 0.4438 x sin 18 deg = 0.137 m off the
	// side wall, on which segments 3's and 4's echoes lie: more than 3 x
	// 0.025 m (the scan's default range sigma) off their line. Segment 4
	// keeps its chord: 7.399 m at -10.3125 deg.
	auto bent = s;
	bent.setScanRange(2, 4.2f);
	const auto upBent = CGroundAwareOccupancyGrid::upsampleSparseScan(bent, 8);
	EXPECT_NEAR(upBent.getScanRange(36), 7.399, 0.001);
	// As an arc, segment 0 (echo 1.435 / sin 24 = 3.528 m) ended its inner
	// ray (21.1875 deg, the wall 1.435 / sin 21.1875 = 3.970 m away) 44 cm
	// in front of the wall.
	const auto arc = CGroundAwareOccupancyGrid::upsampleSparseScan(s, 8, false);
	EXPECT_NEAR(wallRange(DEG2RAD(upsampledRayDeg(7))) - arc.getScanRange(7), 0.442, 0.001);
}

TEST(GroundAwareGrid, LeddarPoleAndJumpKeepTheirArcs)
{
	// Where the nearest point may lie anywhere in the cone, the arc stays:
	// - a pole 2 m away in segment 5 (both neighbours see the wall farther):
	//   a local minimum;
	// - segments 9..11 on a box 2 m away, segment 12 (cone 12..15 deg) on the
	//   wall beyond, 5.8 / cos 12 = 5.9296 m: segment 11's chord runs from
	//   its echo at its near edge, 2 m at 9 deg = (1.9754, 0.3129), to
	//   segment 12's at the shared edge, 5.9296 m at 12 deg = (5.8, 1.2328):
	//   d = (3.8246, 0.9199), |d| = 3.9337; for the middle ray (10.5 deg)
	//   cross(u, d) = 0.98325 x 0.9199 - 0.18224 x 3.8246 = 0.2075, so the
	//   chord is asin(0.2075 / 3.9337) = 3.0 deg from the rays: a jump, not
	//   a surface at >= 10 deg from them.
	auto s = leddarFacingWall(5.8);
	for (size_t i : {5u, 9u, 10u, 11u}) s.setScanRange(i, 2.0f);
	const auto up = CGroundAwareOccupancyGrid::upsampleSparseScan(s, 8);
	for (size_t i : {5u, 11u})
		for (size_t j = 0; j < 8; j++) EXPECT_FLOAT_EQ(up.getScanRange(i * 8 + j), 2.0f) << "segment " << i;
}

TEST(GroundAwareGrid, LeddarBeamsOverAHoleDoNotClearIt)
{
	// The Leddar at 0.3 m sees the wall at 3 m over the hole and the box: its
	// free-space rays must not erase what the depth camera found below them.
	auto scene = holeAndBoxScene();
	const auto s = leddarWallScan();
	for (bool keep : {true, false})
	{
		CGroundAwareOccupancyGrid g;
		setScanRule(g, keep ? ScanRule::KeepCameraFloor : ScanRule::BeamModel);
		g.insertObservation(*testscene::renderDepth(scene, kKinect));
		const double hole = pOcc(g, 2.2, 0.0), box = pOcc(g, 1.6, 0.7), floor = pOcc(g, 1.0, 0.0);
		ASSERT_GT(hole, 0.7);
		for (int k = 0; k < 5; k++) g.insertObservation(s);
		if (keep)
		{
			EXPECT_DOUBLE_EQ(pOcc(g, 2.2, 0.0), hole);
			EXPECT_DOUBLE_EQ(pOcc(g, 1.6, 0.7), box);
			EXPECT_DOUBLE_EQ(pOcc(g, 1.0, 0.0), floor) << "a planar beam makes no cell freer, not even free floor";
		}
		else
			EXPECT_LT(pOcc(g, 2.2, 0.0), 0.5) << "the plain beam model erases the hole";
		EXPECT_GT(pOcc(g, 3.0, 0.0), 0.6) << "the wall";
	}
}

TEST(GroundAwareGrid, LeddarScansDoNotOutvoteAHoleSeenLater)
{
	// Issue #17, first cause. From afar a pit looks like floor (the part of it
	// the camera sees is shallower than the ground band), so its cells start
	// free. The Leddar then passes over them 10 times a second. If its beams
	// could reinforce free cells, 20 scans (2 s) would drive them to the
	// log-odds clamp and the hole seen later from close by could not mark them.
	// With no beam freeing, one floor frame (P = 0.5 - K_g = 0.2, log-odds
	// ln(0.8/0.2) = 1.39 towards free) is outvoted by two hole frames (P up to
	// 0.5 + 0.5 K_m = 0.9 each, 2 x ln(0.9/0.1) = 4.39 towards occupied).
	CGroundAwareOccupancyGrid g;
	g.insertObservation(*testscene::renderDepth(testscene::floorWithHole(-1, 6, -3, 3), kKinect));
	const double seenAsFloor = pOcc(g, 2.2, 0.0);
	ASSERT_LT(seenAsFloor, 0.4);
	const auto s = leddarWallScan();
	for (int k = 0; k < 20; k++) g.insertObservation(s);
	EXPECT_DOUBLE_EQ(pOcc(g, 2.2, 0.0), seenAsFloor) << "the Leddar passed over the cell: no evidence about the floor";
	const auto hole = testscene::renderDepth(holeAndBoxScene(), kKinect);
	for (int k = 0; k < 2; k++) g.insertObservation(*hole);
	EXPECT_GT(pOcc(g, 2.2, 0.0), 0.5) << "the hole seen from close by wins";
	EXPECT_GT(pOcc(g, 3.0, 0.0), 0.6) << "the Leddar's own hits still count";
}

TEST(GroundAwareGrid, LeddarScansTakeBackOnlyTheirOwnHits)
{
	// A wide beam's echo is drawn across its cone at the nearest range, so an
	// arc can lie in front of the real surface. A later scan whose rays pass
	// through such cells may take them back, but only up to unknown (a planar
	// beam never makes floor free), and only cells no one but a scan marked.
	auto fan = [](float range) {
		auto s = planarScan(90.0, 181, CPose3D(0, 0, 0.3, 0, 0, 0));  // 181 beams: no upsampling
		for (size_t i = 0; i < 181; i++) s.setScanRange(i, range);
		return s;
	};
	CGroundAwareOccupancyGrid g(-5, 5, -5, 5, 0.05f);
	setScanRule(g, ScanRule::KeepCameraFloor);         // no depth frame here: auto would be the beam model
	const int ux = g.x2idx(1.0f), uy = g.y2idx(1.0f);  // (1, 1): 1.41 m, inside both arcs
	g.setCell(unsigned(ux), unsigned(uy), 0.1f);       // occupied, not by a scan
	const float marked = g.getCell(unsigned(ux), unsigned(uy));
	ASSERT_TRUE(g.insertObservation(fan(2.0f)));
	ASSERT_GT(pOccNear(g, 2.0, 0.0), 0.6) << "the first scan's arc at 2 m";
	for (int k = 0; k < 5; k++) ASSERT_TRUE(g.insertObservation(fan(4.0f)));
	for (int dy = -1; dy <= 1; dy++)
		for (int dx = -1; dx <= 1; dx++)
			EXPECT_NEAR(pOcc(g, 2.0 + 0.05 * dx, 0.05 * dy), 0.5, 1e-3) << "taken back to unknown, not to free";
	EXPECT_NEAR(pOcc(g, 1.0, 0.0), 0.5, 1e-3) << "never seen occupied: a planar beam frees nothing";
	EXPECT_GT(pOccNear(g, 4.0, 0.0), 0.6) << "the second scan's arc";
	EXPECT_FLOAT_EQ(g.getCell(unsigned(ux), unsigned(uy)), marked) << "not a scan's hit: kept";
}

TEST(GroundAwareGrid, AnEchoInACellScansHaveSeenThroughIsTakenForNoise)
{
	// A scan's evidence in a cell is kept net: the cell holds what else was
	// said there plus min(0, the scans' echoes net of the rays passing since),
	// and an echo in a cell that scans have seen through since its last echo
	// adds nothing (the range noise of the surface behind it). MRPT's own beam
	// model on a stock grid gives each scan's log-odds step in the cell
	// [2.00, 2.05) x [0, 0.05) (the oracle): a fan of 65 beams from (0, 0.025)
	// ending at 2.025 m or passing it at 4 m. How many of MRPT's rays end in
	// or cross that cell (it steps aperture / N from one edge) does not
	// matter: both grids get the same scans.
	auto fan = [](float range) {
		auto s = planarScan(mrpt::RAD2DEG(64 * 0.025), 65, CPose3D(0, 0.025, 0.3, 0, 0, 0));
		for (size_t i = 0; i < 65; i++) s.setScanRange(i, range);
		return s;
	};
	const float x = 2.025f, y = 0.025f;
	const auto cellOf = [&](const COccupancyGridMap2D& m) {
		return int(m.getRawMap()[size_t(m.x2idx(x)) + size_t(m.y2idx(y)) * m.getSizeX()]);
	};
	// The oracle: one echo, one pass.
	COccupancyGridMap2D stock(-5, 5, -5, 5, 0.05f);
	stock.insertObservation(fan(2.025f));
	const int echo = cellOf(stock);
	stock.insertObservation(fan(4.0f));
	const int pass = cellOf(stock) - echo;
	ASSERT_LT(echo, -2 * pass);
	ASSERT_GT(pass, 0);
	{
		CGroundAwareOccupancyGrid g(-5, 5, -5, 5, 0.05f);
		setScanRule(g, ScanRule::KeepCameraFloor);
		ASSERT_TRUE(g.insertObservation(fan(4.0f)));
		EXPECT_EQ(cellOf(g), 0) << "seen through: never freer than unknown";
		g.insertObservation(fan(2.025f));
		EXPECT_EQ(cellOf(g), 0) << "an echo in a cell seen through since: no evidence";
		g.insertObservation(fan(2.025f));
		EXPECT_EQ(cellOf(g), echo) << "the second echo counts in full";
		EXPECT_GT(pOcc(g, x, y), 0.5);
		g.insertObservation(fan(4.0f));
		EXPECT_EQ(cellOf(g), echo + pass) << "a pass takes back part of it";
		for (int k = 0; k < 20; k++) g.insertObservation(fan(4.0f));
		EXPECT_EQ(cellOf(g), 0) << "all of it, up to unknown";
		g.insertObservation(fan(2.025f));
		EXPECT_EQ(cellOf(g), 0) << "and the next short echo is noise again";
	}
	{
		// Floor the camera saw free (here set by hand: base 45, p_free 0.95):
		// a scan's echo there counts, later passes take it back exactly to the
		// base, and none makes the cell freer.
		CGroundAwareOccupancyGrid g(-5, 5, -5, 5, 0.05f);
		setScanRule(g, ScanRule::KeepCameraFloor);
		g.setCell(unsigned(g.x2idx(x)), unsigned(g.y2idx(y)), 0.95f);
		const int base = cellOf(g);
		ASSERT_GT(base + echo, int(COccupancyGridMap2D::OCCGRID_CELLTYPE_MIN));
		g.insertObservation(fan(2.025f));
		EXPECT_EQ(cellOf(g), base + echo);
		g.insertObservation(fan(4.0f));
		EXPECT_EQ(cellOf(g), base + echo + pass);
		for (int k = 0; k < 20; k++) g.insertObservation(fan(4.0f));
		EXPECT_EQ(cellOf(g), base) << "back to what the camera said, not freer";
	}
}

TEST(GroundAwareGrid, AScanIsJudgedOnEveryCellItReaches)
{
	// insert2D() compares only the cells a scan can reach (a box around the
	// sensor). On a fresh grid a scan's own evidence is all there is, so every
	// cell must hold min(0, what MRPT's beam model did there on a stock grid):
	// a cell the box missed would keep the beam model's free evidence (> 0).
	// Scans that grow the grid, cross the +-180 deg line, and widen their
	// beams or take invalid ranges as free space, which reach farther.
	struct Case
	{
		double apertureDeg, robotX, robotY, robotYaw;
		bool widen, invalidAsFree;
	};
	for (const Case& c :
		 {Case{360, 4.0, 0.5, 0.0, false, false}, Case{360, 4.0, 0.5, 0.0, true, true},
		  Case{90, -3.5, 0.5, 3.0, false, true}, Case{90, 1.0, -4.0, -2.0, true, false}})
	{
		auto s = planarScan(c.apertureDeg, 181, CPose3D(0.2, 0, 0.3, 0, 0, 0));
		for (size_t i = 0; i < 181; i++) s.setScanRange(i, 2.0f + 0.01f * float(i % 50));
		for (size_t i = 0; i < 181; i += 7) s.setScanRangeValidity(i, false);
		const CPose3D robot(c.robotX, c.robotY, 0, c.robotYaw, 0, 0);
		CGroundAwareOccupancyGrid g(-5, 5, -5, 5, 0.05f);
		setScanRule(g, ScanRule::KeepCameraFloor);
		COccupancyGridMap2D stock(-5, 5, -5, 5, 0.05f);
		for (COccupancyGridMap2D* m : {static_cast<COccupancyGridMap2D*>(&g), &stock})
		{
			m->insertionOptions.wideningBeamsWithDistance = c.widen;
			m->insertionOptions.considerInvalidRangesAsFreeSpace = c.invalidAsFree;
			m->insertionOptions.maxDistanceInsertion = 50;
			m->insertObservation(s, robot);
		}
		ASSERT_EQ(g.getSizeX(), stock.getSizeX());
		ASSERT_EQ(g.getSizeY(), stock.getSizeY());
		ASSERT_GT(g.getSizeX() + g.getSizeY(), 400u) << "the scan grew the grid";
		int reached = 0, wrong = 0;
		for (size_t i = 0; i < stock.getRawMap().size(); i++)
		{
			const int want = std::min(0, int(stock.getRawMap()[i]));
			reached += stock.getRawMap()[i] != 0;
			wrong += int(g.getRawMap()[i]) != want;
		}
		EXPECT_GT(reached, 1000);
		EXPECT_EQ(wrong, 0) << "aperture " << c.apertureDeg << ", yaw " << c.robotYaw << ", widened " << c.widen
							<< ", invalid as free " << c.invalidAsFree;
	}
}

TEST(GroundAwareGrid, MalformedObservationsThrowClearErrors)
{
	auto obs = testscene::renderDepth(holeAndBoxScene(), kKinect);
	CGroundAwareOccupancyGrid g;
	auto bad = *obs;
	bad.cameraParams.ncols = 100;  // image is 256 wide
	EXPECT_THROW(g.insertObservation(bad), std::invalid_argument);
	bad = *obs;
	bad.rangeUnits = 0;
	EXPECT_THROW(g.insertObservation(bad), std::invalid_argument);
	bad = *obs;
	bad.cameraParams.setIntrinsicParamsFromValues(0, 0, 10, 10);
	EXPECT_THROW(g.insertObservation(bad), std::invalid_argument);
	// All-zero range image: nothing seen, nothing changed.
	bad = *obs;
	bad.rangeImage.fill(0);
	const auto before = g.getRawMap();
	EXPECT_NO_THROW(g.insertObservation(bad));
	EXPECT_EQ(g.getRawMap(), before);
}

TEST(GroundAwareGrid, OneFrameOfFloorReadsFreeThroughMapServersRule)
{
	// Issue #30: the ROS map_server pair as a ROS user reads it. map_server
	// (negate 0) takes p = (255 - pixel) / 255 as P(occupied); a pixel is
	// occupied (100) if p > occupied_thresh, free (0) if p < free_thresh, and
	// unknown (-1, trinary) or a scaled cost (scale) in between.
	// One frame of floor gives the cell P(occ) = 0.5 - K_g = 0.2 (Table I:
	// K_g = 0.3, the floor on the plane); the grid's int8 log-odds store it as
	// pixel 204 or 203, p = 0.2 or 0.204. With ROS's customary free_thresh
	// 0.196 that reads as not free; the written 0.25 reads it free. A hole
	// cell of one frame, P = 0.5 + 0.5 K_m = 0.9 (pixel 25 or 26), is
	// occupied (> 0.65); a cell never observed (pixel 128, p = 0.498), unknown.
	CGroundAwareOccupancyGrid g;
	g.insertObservation(*testscene::renderDepth(holeAndBoxScene(), kKinect));
	const std::string dir = mrpt::system::getTempFileName() + "_rosmap";
	mrpt::system::createDirectory(dir);
	gam::maps::writeRosMap(g, dir + "/m.yaml", dir + "/m.pgm", "m.pgm");

	std::map<std::string, std::string> yaml;
	{
		std::ifstream f(dir + "/m.yaml");
		std::string line;
		while (std::getline(f, line))
			if (const auto c = line.find(": "); c != std::string::npos) yaml[line.substr(0, c)] = line.substr(c + 2);
	}
	const double occTh = std::stod(yaml.at("occupied_thresh")), freeTh = std::stod(yaml.at("free_thresh"));
	EXPECT_EQ(yaml.at("negate"), "0");
	// The PGM: P5, a comment line, "W H", 255, then rows from the top (highest y).
	std::ifstream f(dir + "/m.pgm", std::ios::binary);
	std::string magic, comment;
	int W = 0, H = 0, maxv = 0;
	f >> magic;
	f.ignore();
	std::getline(f, comment);
	f >> W >> H >> maxv;
	f.ignore();
	std::vector<unsigned char> px(size_t(W) * size_t(H));
	f.read(reinterpret_cast<char*>(px.data()), std::streamsize(px.size()));
	ASSERT_EQ(magic, "P5");
	ASSERT_EQ(W, int(g.getSizeX()));
	auto mapServer = [&](double x, double y, double freeThresh) {
		const int cx = g.x2idx(float(x)), cy = g.y2idx(float(y));
		const double p = (255.0 - px[size_t(H - 1 - cy) * size_t(W) + size_t(cx)]) / 255.0;
		return p > occTh ? 100 : p < freeThresh ? 0 : -1;
	};
	EXPECT_EQ(mapServer(1.0, -0.5, freeTh), 0) << "floor seen in one frame";
	EXPECT_EQ(mapServer(1.0, -0.5, 0.196), -1) << "the customary 0.196 would call it unknown";
	EXPECT_EQ(mapServer(2.2, 0.0, freeTh), 100) << "the hole";
	EXPECT_EQ(mapServer(-5.0, 5.0, freeTh), -1) << "never observed";
}

TEST(GroundAwareGrid, AScanThatGrowsTheGridFreesNoNewCellUnderTheWalkersRule)
{
	// Issue #31: the walker's rule reverted only the cells of the grid's old
	// extent; a scan that grew the grid left the new cells it passed through
	// free (17,589 cells of the ramp scenes, outside the scored area).
	auto fan = planarScan(180.0, 181, CPose3D(0, 0, 0.3, 0, 0, 0));  // 181 beams: no upsampling
	for (size_t i = 0; i < 181; i++) fan.setScanRange(i, 4.0f);
	CGroundAwareOccupancyGrid g(-1, 1, -1, 1, 0.05f);
	setScanRule(g, ScanRule::KeepCameraFloor);
	ASSERT_TRUE(g.insertObservation(fan));
	ASSERT_GT(g.getXMax(), 3.9f) << "the scan grew the grid";
	size_t freed = 0;
	for (auto c : g.getRawMap()) freed += c > 0;
	EXPECT_EQ(freed, 0u) << "cells made free by a planar scan";
	size_t occ = 0;
	for (auto c : g.getRawMap()) occ += c < 0;
	EXPECT_GE(occ, 150u) << "its hits still count (181 beams, one end cell each)";
}
