// Bad observations into every map class of the plugin: each gets a clear
// exception or a documented, sensible result (README "Robustness").
// Already covered elsewhere (not repeated here): tests/maps/test_ground_aware_grid.cpp
// MalformedObservationsThrowClearErrors (ground-aware grid only: ncols mismatch,
// rangeUnits 0, zero focal lengths, all-zero image) and NoFloorInViewChangesNothing.
#include <gtest/gtest.h>
#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/obs/CObservationImage.h>

#include <cmath>
#include <limits>

#include "robustness_helpers.h"

using namespace mrpt::maps;
using mrpt::poses::CPose3D;
using robust::allMaps;

namespace
{
mrpt::obs::CObservation3DRangeScan goodFrame(const CPose3D& mount = robust::kMount)
{
	return *testscene::renderDepth(robust::floorAndBox(), mount);
}

/** Inserting `o` into a fresh map of every class must throw a std::exception
 * whose message contains `what` (empty: any message). */
void expectThrowEverywhere(const mrpt::obs::CObservation& o, const std::string& what, const CPose3D& robot = {})
{
	for (auto& m : allMaps())
	{
		try
		{
			m.map->insertObservation(o, robot);
			ADD_FAILURE() << m.name << " accepted it";
		}
		catch (const std::exception& e)
		{
			if (!what.empty())
			{
				EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << m.name << ": " << e.what();
			}
		}
	}
}

/** State of a map for "did the insertion change anything" checks. */
std::vector<int> stateOf(const CMetricMap& m)
{
	if (const auto* g = dynamic_cast<const COccupancyGridMap2D*>(&m))
	{
		auto v = robust::gridCells(*g);
		if (const auto* oc = dynamic_cast<const COctoMapGrid2D*>(&m)) v.push_back(int(oc->octomap().getNumLeafNodes()));
		return v;
	}
	if (const auto* e = dynamic_cast<const CElevation25DMap*>(&m)) return {int(e->grid().observedCount())};
	return {};
}

/** Inserting `o` into a fresh map of every class neither throws nor changes the map. */
void expectNoEffectEverywhere(const mrpt::obs::CObservation& o, const CPose3D& robot = {})
{
	for (auto& m : allMaps())
	{
		const auto before = stateOf(*m.map);
		EXPECT_NO_THROW(m.map->insertObservation(o, robot)) << m.name;
		EXPECT_EQ(stateOf(*m.map), before) << m.name << " changed";
	}
}
}  // namespace

TEST(RobustObservations, AllZeroRangeImageAddsNothingToAnyMap)
{
	auto o = goodFrame();
	o.rangeImage.fill(0);
	expectNoEffectEverywhere(o);
}

TEST(RobustObservations, EmptyObservationAddsNothingToAnyMap)
{
	mrpt::obs::CObservation3DRangeScan o;  // no range image, no points
	expectNoEffectEverywhere(o);
	auto withImage = goodFrame();
	withImage.hasRangeImage = false;  // the flag says there is none
	expectNoEffectEverywhere(withImage);
}

TEST(RobustObservations, NanAndInfPoints3DAreSkipped)
{
	// A points3D-only frame: a floor patch 1..3 m ahead (robot frame, sensor at the
	// origin), with every other point NaN, +inf or -inf.
	mrpt::obs::CObservation3DRangeScan o;
	o.hasRangeImage = false;
	o.hasPoints3D = true;
	o.maxRange = 10;
	const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
	size_t good = 0;
	for (int i = 0; i < 40; i++)
		for (int j = 0; j < 40; j++)
		{
			const int k = (i * 40 + j) % 4;
			const float x = 1.0f + 0.05f * float(i), y = -1.0f + 0.05f * float(j), z = 0.0f;
			o.points3D_x.push_back(k == 1 ? nan : x);
			o.points3D_y.push_back(k == 2 ? inf : y);
			o.points3D_z.push_back(k == 3 ? -inf : z);
			good += k == 0;
		}
	for (auto& m : allMaps())
	{
		EXPECT_NO_THROW(m.map->insertObservation(o)) << m.name;
		if (auto* e = dynamic_cast<CElevation25DMap*>(m.map.get()))
		{
			// Only the finite points landed, all on the floor.
			EXPECT_LE(e->grid().observedCount(), good) << "only cells of the finite points";
			EXPECT_GT(e->grid().observedCount(), 0u);
		}
		if (auto* g = dynamic_cast<COccupancyGridMap2D*>(m.map.get()))
		{
			EXPECT_LE(g->getSizeX(), 1000u) << m.name << ": non-finite points must not grow the grid";
			EXPECT_LE(g->getSizeY(), 1000u) << m.name;
		}
	}
}

TEST(RobustObservations, AllNanPoints3DAddNothing)
{
	mrpt::obs::CObservation3DRangeScan o;
	o.hasRangeImage = false;
	o.hasPoints3D = true;
	const float nan = std::numeric_limits<float>::quiet_NaN();
	o.points3D_x.assign(100, nan);
	o.points3D_y.assign(100, nan);
	o.points3D_z.assign(100, nan);
	expectNoEffectEverywhere(o);
}

TEST(RobustObservations, RangeImageSizeNotMatchingCameraParamsIsAnError)
{
	// Fewer rows than cameraParams.nrows, then more columns than ncols.
	auto o = goodFrame();
	o.cameraParams.nrows = o.cameraParams.nrows + 40;
	expectThrowEverywhere(o, "camera");
	o = goodFrame();
	o.cameraParams.ncols = o.cameraParams.ncols / 2;
	expectThrowEverywhere(o, "camera");
}

TEST(RobustObservations, ZeroOrNegativeIntrinsicsAreAnError)
{
	for (double f : {0.0, -150.0, std::numeric_limits<double>::quiet_NaN()})
	{
		auto o = goodFrame();
		o.cameraParams.setIntrinsicParamsFromValues(f, f, 127.5, 105.5);
		expectThrowEverywhere(o, "focal");
	}
	auto o = goodFrame();
	o.cameraParams.setIntrinsicParamsFromValues(150, 150, std::numeric_limits<double>::infinity(), 105.5);
	expectThrowEverywhere(o, "principal point");
}

TEST(RobustObservations, BadRangeUnitsAreAnError)
{
	for (float u : {0.0f, -0.001f, std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity()})
	{
		auto o = goodFrame();
		o.rangeUnits = u;
		expectThrowEverywhere(o, "rangeUnits");
	}
}

TEST(RobustObservations, TinyRangeUnitsPutEveryPointAtTheSensor)
{
	// Found by tests/fuzz/fuzz_rawlog (UBSan): rangeUnits 1e-13 made the flying-pixel
	// tolerance, one cell in raw units (0.05 / 1e-13 = 5e11), overflow an int. Every
	// depth is then 1e-13 x its raw value <= 6.6e-9 m: every point is at the sensor
	// (min_range is 0). No map throws; the 2.5D map holds at most the sensor's cell,
	// and the ground-aware grid, with no floor in view, adds nothing.
	auto o = goodFrame();
	o.rangeUnits = 1e-13f;
	for (auto& m : allMaps())
	{
		const auto before = stateOf(*m.map);
		EXPECT_NO_THROW(m.map->insertObservation(o, CPose3D())) << m.name;
		if (const auto* e = dynamic_cast<const CElevation25DMap*>(m.map.get()))
			EXPECT_LE(e->grid().observedCount(), 1u);
		if (dynamic_cast<const CGroundAwareOccupancyGrid*>(m.map.get()))
			EXPECT_EQ(stateOf(*m.map), before) << m.name << " changed";
	}
}

TEST(RobustObservations, RangesBeyondAnySaneMaximumAreDropped)
{
	// Every pixel 65535 m away (rangeUnits 1), and the sensor claims a 1e6 m range.
	auto o = goodFrame();
	o.rangeUnits = 1.0f;
	o.maxRange = 1e6f;
	o.rangeImage.fill(65535);
	for (auto& m : allMaps())
	{
		EXPECT_NO_THROW(m.map->insertObservation(o)) << m.name;
		if (auto* e = dynamic_cast<CElevation25DMap*>(m.map.get()))
		{
			EXPECT_EQ(e->grid().observedCount(), 0u) << "beyond max_range";
		}
		if (auto* ga = dynamic_cast<CGroundAwareOccupancyGrid*>(m.map.get()))
		{
			EXPECT_FALSE(ga->lastFrame().detection.ok());
			EXPECT_TRUE(ga->lastFrameIsm().evidenceCells().empty());
		}
		if (auto* g = dynamic_cast<COccupancyGridMap2D*>(m.map.get()))
		{
			// Rays are cut at the map's range limit: the grid stays small.
			EXPECT_LE(g->getSizeX(), 2000u) << m.name;
			EXPECT_LE(g->getSizeY(), 2000u) << m.name;
		}
	}
}

TEST(RobustObservations, UpsideDownSensorGivesTheSameGroundAwareMap)
{
	// The same camera rolled 180 deg: the image is upside down, sensorPose says so.
	const CPose3D upright(0, 0, 1.0, 0, mrpt::DEG2RAD(25.0), 0);
	const CPose3D flipped(0, 0, 1.0, 0, mrpt::DEG2RAD(25.0), mrpt::DEG2RAD(180.0));
	CGroundAwareOccupancyGrid a, b;
	a.insertObservation(goodFrame(upright));
	b.insertObservation(goodFrame(flipped));
	ASSERT_TRUE(a.lastFrame().detection.ok());
	ASSERT_TRUE(b.lastFrame().detection.ok()) << b.lastFrame().detection.describe();
	EXPECT_NEAR(b.lastFrame().detection.plane().tiltAngle(), 0.0, mrpt::DEG2RAD(1.0));
	EXPECT_LT(b.getPos(1.65f, 0.65f), 0.3f) << "box occupied";
	EXPECT_GT(b.getPos(1.0f, -1.0f), 0.6f) << "floor free";
	// Cell by cell, nearly the same map (the pixel grid is mirrored, so not exactly).
	int same = 0, n = 0;
	for (float x = 0.5f; x < 3.0f; x += 0.05f)
		for (float y = -1.0f; y < 1.0f; y += 0.05f)
		{
			n++;
			same +=
				(a.getPos(x, y) > 0.5f) == (b.getPos(x, y) > 0.5f) || std::abs(a.getPos(x, y) - b.getPos(x, y)) < 0.1f;
		}
	EXPECT_GE(same, n * 95 / 100);
}

TEST(RobustObservations, SensorPointingAtTheSkyFindsNoFloorAndAddsNothing)
{
	// Upside-down pitch: the camera looks straight up; nothing in view.
	auto o = goodFrame(CPose3D(0, 0, 1.0, 0, mrpt::DEG2RAD(-90.0), 0));
	for (auto& m : allMaps()) EXPECT_NO_THROW(m.map->insertObservation(o)) << m.name;
	CGroundAwareOccupancyGrid g;
	const auto before = robust::gridCells(g);
	g.insertObservation(o);
	EXPECT_FALSE(g.lastFrame().detection.ok());
	EXPECT_EQ(robust::gridCells(g), before);
}

TEST(RobustObservations, AbsurdSensorPoseFarAwayAddsNothingOrIsAClearError)
{
	// A sensor 1e7 m above the robot (a unit mistake): its points are far out of
	// any band and of every map. The right outcome, per map: the 2D grids take
	// the frame and change no cell (no floor is found, nothing is invented),
	// the elevation map rejects it (nothing in its extent), and the octomap,
	// whose octree cannot hold a sensor that far, says so.
	auto o = goodFrame();
	o.sensorPose = CPose3D(0, 0, 1e7, 0, mrpt::DEG2RAD(25.0), 0);
	for (auto& m : allMaps())
	{
		const auto before = stateOf(*m.map);
		if (m.name == "COctoMapGrid2D")
		{
			try
			{
				m.map->insertObservation(o);
				ADD_FAILURE() << m.name << " accepted a sensor 1e7 m up";
			}
			catch (const std::exception& e)
			{
				EXPECT_NE(std::string(e.what()).find("too large for the octomap"), std::string::npos) << e.what();
			}
		}
		else
		{
			bool inserted = false;
			EXPECT_NO_THROW(inserted = m.map->insertObservation(o)) << m.name;
			// The grids report the frame as processed (lastFrame() says why
			// nothing changed); the elevation map, that nothing was inserted.
			EXPECT_EQ(inserted, m.name != "CElevation25DMap") << m.name;
		}
		EXPECT_EQ(stateOf(*m.map), before) << m.name << " changed";
	}
}

TEST(RobustObservations, NonFiniteSensorOrRobotPoseIsAnError)
{
	auto o = goodFrame();
	o.sensorPose = CPose3D(std::numeric_limits<double>::quiet_NaN(), 0, 1, 0, 0, 0);
	expectThrowEverywhere(o, "finite");
	expectThrowEverywhere(goodFrame(), "finite", CPose3D(0, std::numeric_limits<double>::infinity(), 0, 0, 0, 0));
}

TEST(RobustObservations, RobotPoseFarFromTheGridGivesAClearErrorNotAHugeGrid)
{
	// Odometry that jumped 1e7 m (a corrupt or unit-confused pose): growing a 5 cm
	// grid that far would need ~1e17 cells. A clear error, before allocating.
	const CPose3D far(1e7, -1e7, 0, 0, 0, 0);
	for (auto& m : allMaps())
	{
		if (!dynamic_cast<COccupancyGridMap2D*>(m.map.get())) continue;
		try
		{
			m.map->insertObservation(goodFrame(), far);
			ADD_FAILURE() << m.name << " accepted a robot pose 1e7 m away";
		}
		catch (const std::exception& e)
		{
			EXPECT_NE(std::string(e.what()).find("too large"), std::string::npos) << m.name << ": " << e.what();
		}
		auto* g = dynamic_cast<COccupancyGridMap2D*>(m.map.get());
		EXPECT_LE(size_t(g->getSizeX()) * g->getSizeY(), size_t(1) << 28) << m.name;
	}
	// The elevation map has a fixed extent: far points are simply outside it.
	CElevation25DMap e;
	EXPECT_NO_THROW(e.insertObservation(goodFrame(), far));
	EXPECT_EQ(e.grid().observedCount(), 0u);
}

TEST(RobustObservations, FloorOnlyAtTheImageEdge)
{
	// A wall 1.2 m ahead fills the view; the floor shows only in the bottom rows.
	std::vector<testscene::Box> s = {{-1, -3, -0.1, 6, 3, 0.0}, {1.2, -3, 0.0, 1.4, 3, 3.0}};
	auto o = testscene::renderDepth(s, CPose3D(0, 0, 1.0, 0, mrpt::DEG2RAD(5.0), 0));
	// Only the last rows see the floor.
	int floorRows = 0;
	for (int r = 0; r < int(o->rangeImage.rows()); r++)
	{
		const float d = o->rangeImage(r, o->rangeImage.cols() / 2) * o->rangeUnits;
		floorRows += d > 0 && d < 1.15f;
	}
	ASSERT_GT(floorRows, 0);
	ASSERT_LT(floorRows, int(o->rangeImage.rows()) / 4);
	for (auto& m : allMaps()) EXPECT_NO_THROW(m.map->insertObservation(*o)) << m.name;
	// Ground-aware grid: either the floor strip is found (then it is the real floor
	// and the wall is an obstacle) or there is no plane and nothing changes; never
	// a wrong (tilted or raised) plane.
	CGroundAwareOccupancyGrid g;
	const auto before = robust::gridCells(g);
	g.insertObservation(*o);
	const auto& d = g.lastFrame().detection;
	if (d.ok())
	{
		EXPECT_NEAR(d.plane().tiltAngle(), 0.0, mrpt::DEG2RAD(2.0));
		EXPECT_NEAR(d.plane().signedDistance(0.8, 0, 0), 0.0, 0.03);
		EXPECT_LT(g.getPos(1.25f, 0.0f), 0.3f) << "the wall";
	}
	else
		EXPECT_EQ(robust::gridCells(g), before) << "no plane: the frame adds nothing";
}

TEST(RobustObservations, ObservationsOfOtherClassesAreIgnored)
{
	mrpt::obs::CObservationImage img;
	img.image.resize(64, 48, mrpt::img::CH_GRAY);
	for (auto& m : allMaps())
	{
		const auto before = stateOf(*m.map);
		bool inserted = true;
		EXPECT_NO_THROW(inserted = m.map->insertObservation(img)) << m.name;
		EXPECT_FALSE(inserted) << m.name;
		EXPECT_EQ(stateOf(*m.map), before) << m.name;
	}
}

TEST(RobustObservations, EmptyAndDegenerate2DScans)
{
	// An empty scan changes no map.
	mrpt::obs::CObservation2DRangeScan empty;
	expectNoEffectEverywhere(empty);
	// NaN / inf / negative ranges and ranges beyond maxRange marked valid: each
	// is read as "no return" (the map's adapter clears its validity). So the
	// right outcome is that of the same scan with every range invalid: no map
	// throws; the ground-aware grid (auto: MRPT's beam model before any depth
	// frame) gives exactly the stock grid's cells for that scan (with
	// considerInvalidRangesAsFreeSpace = true, MRPT's default, the no-return
	// rays free space), and with the walker's rule no cell; the comparison maps
	// take no 2D scan into their cells and the elevation map none at all.
	mrpt::obs::CObservation2DRangeScan s;
	s.aperture = float(M_PI);
	s.maxRange = 10;
	s.resizeScan(16);
	const float vals[4] = {
		std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity(), -3.f, 1e30f};
	for (size_t i = 0; i < 16; i++)
	{
		s.setScanRange(i, vals[i % 4]);
		s.setScanRangeValidity(i, true);
	}
	auto noReturn = s;
	for (size_t i = 0; i < 16; i++)
	{
		noReturn.setScanRange(i, 0.f);
		noReturn.setScanRangeValidity(i, false);
	}
	// (16 beams < 64: the grid splits each into sparse_scan_upsampling = 8 rays.)
	COccupancyGridMap2D stock(-10, 10, -10, 10, 0.05f);
	stock.insertObservation(CGroundAwareOccupancyGrid::upsampleSparseScan(noReturn, 8));
	for (auto& m : allMaps())
	{
		const auto before = stateOf(*m.map);
		EXPECT_NO_THROW(m.map->insertObservation(s)) << m.name;
		if (auto* ga = dynamic_cast<CGroundAwareOccupancyGrid*>(m.map.get()))
		{
			EXPECT_EQ(robust::gridCells(*ga), robust::gridCells(stock)) << "as the stock grid with no returns";
			CGroundAwareOccupancyGrid walker;
			auto opts = walker.groundOptions();
			opts.scan_keeps_3d_obstacles = CGroundAwareOccupancyGrid::TGroundAwareOptions::ScanRule::KeepCameraFloor;
			walker.setGroundOptions(opts);
			const auto w0 = robust::gridCells(walker);
			EXPECT_NO_THROW(walker.insertObservation(s));
			EXPECT_EQ(robust::gridCells(walker), w0) << "the walker's rule: no return frees nothing";
		}
		else
			EXPECT_EQ(stateOf(*m.map), before) << m.name << " changed";
	}
}

TEST(RobustObservations, HugeValid2DRangesGiveAClearErrorNotAHeapOverflow)
{
	// Found by tests/fuzz/fuzz_rawlog: a scan whose maxRange and one valid range are
	// 1e30 m made MRPT's beam model grow the grid with overflowing 32-bit sizes (heap
	// overflow in COccupancyGridMap2D::resizeGrid).
	for (float maxRange : {1e30f, 0.f})
	{
		mrpt::obs::CObservation2DRangeScan s;
		s.aperture = float(M_PI);
		s.maxRange = maxRange;
		s.resizeScan(16);
		for (size_t i = 0; i < 16; i++)
		{
			s.setScanRange(i, i == 3 ? 1e30f : 2.0f);
			s.setScanRangeValidity(i, true);
		}
		for (auto& m : allMaps())
		{
			auto* g = dynamic_cast<COccupancyGridMap2D*>(m.map.get());
			if (!g || dynamic_cast<COctoMapGrid2D*>(g)) continue;  // the octomap clips rays itself
			try
			{
				m.map->insertObservation(s);
				ADD_FAILURE() << m.name << " accepted a 1e30 m range";
			}
			catch (const std::exception& e)
			{
				EXPECT_NE(std::string(e.what()).find("too large"), std::string::npos) << m.name << ": " << e.what();
			}
			EXPECT_LE(size_t(g->getSizeX()) * g->getSizeY(), size_t(1) << 28) << m.name;
		}
	}
}
