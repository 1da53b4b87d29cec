// Unit tests of the comparison maps of libs/baseline_maps:
// CHeightBandOccupancyGrid (heightBandGrid) and COctoMapGrid2D (octoMapGrid).
#include <gtest/gtest.h>
#include <mrpt/config/CConfigFileMemory.h>
#include <mrpt/io/CMemoryStream.h>
#include <mrpt/maps/CHeightBandOccupancyGrid.h>
#include <mrpt/maps/CMultiMetricMap.h>
#include <mrpt/maps/COctoMapGrid2D.h>
#include <mrpt/maps/TMetricMapInitializer.h>
#include <mrpt/maps/registerBaselineMaps.h>
#include <mrpt/obs/CObservation3DRangeScan.h>
#include <mrpt/rtti/CObject.h>
#include <mrpt/serialization/CArchive.h>

#include <cmath>

using namespace mrpt::maps;

namespace
{
/** A camera 0.5 m up, pitched 20 deg down, sees a floor (z = 0) and a wall at x = 3 m. */
mrpt::obs::CObservation3DRangeScan wallFrame()
{
	const int W = 160, H = 120;
	const double fx = 120, fy = 120, cx = 79.5, cy = 59.5;
	mrpt::obs::CObservation3DRangeScan o;
	o.hasRangeImage = true;
	o.range_is_depth = true;
	o.rangeUnits = 0.001f;
	o.maxRange = 6.0f;
	o.sensorPose = mrpt::poses::CPose3D(0.2, 0, 0.5, 0, mrpt::DEG2RAD(20.0), 0);
	o.cameraParams.ncols = W;
	o.cameraParams.nrows = H;
	o.cameraParams.setIntrinsicParamsFromValues(fx, fy, cx, cy);
	o.cameraParamsIntensity = o.cameraParams;
	o.rangeImage_setSize(H, W);
	const auto R = o.sensorPose.getRotationMatrix();
	for (int r = 0; r < H; r++)
		for (int c = 0; c < W; c++)
		{
			const double ds[3] = {1.0, (cx - c) / fx, (cy - r) / fy};
			double d[3];
			for (int k = 0; k < 3; k++) d[k] = R(k, 0) * ds[0] + R(k, 1) * ds[1] + R(k, 2) * ds[2];
			double t = 1e9;
			if (d[0] > 1e-9) t = std::min(t, (3.0 - 0.2) / d[0]);  // wall
			if (d[2] < -1e-9) t = std::min(t, -0.5 / d[2]);        // floor
			o.rangeImage(r, c) = t < 5.9 ? uint16_t(std::lround(t / 0.001)) : 0;
		}
	return o;
}

/** Lowest p_free of the cells whose centre is in [x0, x1] at y. */
float minAlongX(const COccupancyGridMap2D& g, float x0, float x1, float y)
{
	float m = 1;
	for (int cx = 0; cx < int(g.getSizeX()); cx++)
		if (g.idx2x(cx) >= x0 && g.idx2x(cx) <= x1) m = std::min(m, g.getCell(cx, g.y2idx(y)));
	return m;
}

template <class T>
T roundTrip(const T& m)
{
	mrpt::io::CMemoryStream buf;
	auto ar = mrpt::serialization::archiveFrom(buf);
	ar << m;
	buf.Seek(0);
	T back;
	ar >> back;
	return back;
}
}  // namespace

TEST(ComparisonMaps, RegisteredForIniAndRtti)
{
	mrpt::maps::registerBaselineMaps();
	for (const char* n :
		 {"heightBandGrid", "CHeightBandOccupancyGrid", "mrpt::maps::CHeightBandOccupancyGrid", "octoMapGrid",
		  "COctoMapGrid2D", "mrpt::maps::COctoMapGrid2D"})
	{
		std::unique_ptr<TMetricMapInitializer> d(TMetricMapInitializer::factory(n));
		EXPECT_TRUE(d) << n;
	}
	EXPECT_TRUE(mrpt::rtti::findRegisteredClass("mrpt::maps::CHeightBandOccupancyGrid"));
	EXPECT_TRUE(mrpt::rtti::findRegisteredClass("mrpt::maps::COctoMapGrid2D"));
}

TEST(ComparisonMaps, HeightBandSeesTheWallNotTheFloor)
{
	CHeightBandOccupancyGrid g(-1, 5, -3, 3, 0.05f);
	auto o = wallFrame();
	ASSERT_TRUE(g.insertObservation(o, mrpt::poses::CPose3D()));
	ASSERT_TRUE(g.lastVirtualScan());
	EXPECT_TRUE(g.lastVirtualScan()->sensorPose == mrpt::poses::CPose3D());
	// The wall (x = 3) is occupied straight ahead, the floor before it free, nothing behind.
	EXPECT_LT(minAlongX(g, 2.93f, 3.07f, 0.02f), 0.3f);
	EXPECT_GT(g.getPos(2.02f, 0.02f), 0.6f);
	EXPECT_FLOAT_EQ(g.getPos(4.02f, 0.02f), 0.5f);
	// A band above the wall's top sees nothing.
	CHeightBandOccupancyGrid high(-1, 5, -3, 3, 0.05f);
	high.bandOptions.z_min = 5;
	high.bandOptions.z_max = 6;
	high.insertObservation(o, mrpt::poses::CPose3D());
	EXPECT_FLOAT_EQ(minAlongX(high, 2.5f, 3.5f, 0.02f), 0.5f);
}

TEST(ComparisonMaps, OctoMapGridUsesTheSensorPose)
{
	COctoMapGrid2D g(-1, 5, -3, 3, 0.05f);
	auto o = wallFrame();
	ASSERT_TRUE(g.insertObservation(o, mrpt::poses::CPose3D(1.0, 0.5, 0, 0, 0, 0)));
	EXPECT_FALSE(g.projectionOutdated());  // project_every = 1
	// Wall at x = 1 + 3 = 4 in the map (COctoMap's own 3D-scan path would put it short).
	EXPECT_LT(minAlongX(g, 3.93f, 4.07f, 0.52f), 0.1f);
	EXPECT_GT(minAlongX(g, 3.0f, 3.85f, 0.52f), 0.9f);  // free in the band up to the wall
	EXPECT_GT(g.getPos(2.02f, 0.52f), 0.9f);
	// The floor (z = 0) is below the band: not an obstacle.
	size_t occ = 0;
	for (int cx = 0; cx < int(g.getSizeX()); cx++)
		if (g.idx2x(cx) > 1.5f && g.idx2x(cx) < 3.85f && g.getCell(cx, g.y2idx(0.52f)) < 0.5f) occ++;
	EXPECT_EQ(occ, 0u);
	// Serialization keeps the octomap and the projection.
	const auto back = roundTrip(g);
	EXPECT_EQ(back.getRawMap(), g.getRawMap());
	EXPECT_EQ(back.octomap().getNumLeafNodes(), g.octomap().getNumLeafNodes());
	EXPECT_DOUBLE_EQ(back.octoOptions.z_max, g.octoOptions.z_max);
}

TEST(ComparisonMaps, HeightBandSerializationAndIni)
{
	mrpt::config::CConfigFileMemory ini(
		"[map]\nheightBandGrid_count=1\noctoMapGrid_count=1\n"
		"[map_heightBandGrid_00_bandOpts]\nz_min=0.1\nz_max=1.0\n"
		"[map_octoMapGrid_00_octoOpts]\nvoxel_size=0.1\nproject_every=0\n");
	TSetOfMetricMapInitializers inits;
	inits.loadFromConfigFile(ini, "map");
	CMultiMetricMap mm(inits);
	ASSERT_EQ(mm.maps.size(), 2u);
	auto hb = mm.mapByClass<CHeightBandOccupancyGrid>();
	auto oc = mm.mapByClass<COctoMapGrid2D>();
	ASSERT_TRUE(hb);
	ASSERT_TRUE(oc);
	EXPECT_DOUBLE_EQ(hb->bandOptions.z_min, 0.1);
	EXPECT_FALSE(hb->insertionOptions.considerInvalidRangesAsFreeSpace);
	EXPECT_DOUBLE_EQ(oc->octomap().getResolution(), 0.1);
	auto o = wallFrame();
	mm.insertObservation(o, mrpt::poses::CPose3D());
	EXPECT_TRUE(oc->projectionOutdated());  // project_every = 0
	const auto back = roundTrip(*hb);
	EXPECT_EQ(back.getRawMap(), hb->getRawMap());
	EXPECT_DOUBLE_EQ(back.bandOptions.z_max, 1.0);
	// Out of range in the .ini: the error names the key (MRPT's exception wrapper
	// reformats the rest of the text).
	mrpt::config::CConfigFileMemory bad(
		"[map]\nheightBandGrid_count=1\n[map_heightBandGrid_00_bandOpts]\noversampling_ratio=50\n");
	TSetOfMetricMapInitializers inits2;
	try
	{
		inits2.loadFromConfigFile(bad, "map");
		FAIL() << "no exception";
	}
	catch (const std::exception& e)
	{
		EXPECT_NE(std::string(e.what()).find("oversampling_ratio=50"), std::string::npos) << e.what();
		EXPECT_NE(std::string(e.what()).find("out of range"), std::string::npos) << e.what();
	}
}
