// Real depth frames from ../shared/data/real (see its README for each scene).
#include <gtest/gtest.h>
#include <mrpt/maps/CElevation25DMap.h>
#include <mrpt/maps/CGroundAwareOccupancyGrid.h>
#include <mrpt/maps/CSimplePointsMap.h>
#include <mrpt/obs/CObservation3DRangeScan.h>
#include <mrpt/obs/CRawlog.h>
#include <mrpt/system/filesystem.h>

#include "real_data.h"

using namespace mrpt::maps;
using namespace mrpt::obs;
using mrpt::DEG2RAD;

namespace
{
using testdata::firstScan;
using testdata::realData;

#define LOAD_OR_SKIP(var, rel) \
	auto var = firstScan(rel); \
	if (!var) GTEST_SKIP() << "real data not found: " << realData(rel);

double pOcc(const COccupancyGridMap2D& g, double x, double y) { return 1.0 - g.getPos(float(x), float(y)); }

struct Census
{
	size_t ground = 0, groundMarkedOcc = 0, occupied = 0;
};
// Cells the frame classified as ground, and how many of them ended occupied.
Census census(const CGroundAwareOccupancyGrid& g)
{
	Census c;
	const auto& fr = g.lastFrameElevation();
	const auto& geo = fr.geometry();
	const auto& cls = g.lastFrameIsm().classes();
	for (uint32_t i : fr.observedCells())
	{
		const double x = geo.cx(int(i % uint32_t(geo.nx))), y = geo.cy(int(i / uint32_t(geo.nx)));
		const bool occ = pOcc(g, x, y) > 0.5;
		c.occupied += occ;
		if (cls[i] == gam::VoxelClass::Ground)
		{
			c.ground++;
			c.groundMarkedOcc += occ;
		}
	}
	return c;
}
// The frame's own samples against the map, cell by cell, where the map has
// evidence: a cell whose samples (at least 5) all lie within 3 cm of the floor
// (z = 0 by the dataset's floor fit, residual std about 1 cm) is floor; one
// whose samples all lie 0.15-1.2 m up is an object (as the real RealSense
// test does with its own points).
struct PointCensus
{
	size_t floorKnown = 0, floorOcc = 0, objectKnown = 0, objectOcc = 0;
};
PointCensus pointCensus(const CGroundAwareOccupancyGrid& g)
{
	PointCensus c;
	const auto& fr = g.lastFrameElevation();
	const auto& geo = fr.geometry();
	for (uint32_t i : fr.observedCells())
	{
		const auto& cell = fr.cell(i);
		const double x = geo.cx(int(i % uint32_t(geo.nx))), y = geo.cy(int(i / uint32_t(geo.nx)));
		const double p = pOcc(g, x, y);
		if (cell.count < 5 || std::abs(p - 0.5) < 1e-3) continue;  // too few samples, or no evidence
		if (cell.z_min >= -0.03f && cell.z_max <= 0.03f)
		{
			c.floorKnown++;
			c.floorOcc += p > 0.5;
		}
		else if (cell.z_min >= 0.15f && cell.z_max <= 1.2f)
		{
			c.objectKnown++;
			c.objectOcc += p > 0.5;
		}
	}
	return c;
}
}  // namespace

TEST(RealData, KinectV1FramesFloorFreeObjectsMarked)
{
	// PCL's three Kinect v1 frames, read as structured light (`auto`: 640x480
	// at 62.7 deg). Issue #27 asks a real frame's floor to be <= 1 % occupied.
	// (Read as a camera of unknown noise, before 2026-11-29, the corridor's
	// floor was 36 of 821 cells occupied, the office's 8 of 505.)
	for (const char* rel :
		 {"pcl_milk_bottles_on_carpet/pcl_milk_bottles_on_carpet.rawlog", "pcl_office1/pcl_office1.rawlog",
		  "pcl_five_people_corridor/pcl_five_people_corridor.rawlog"})
	{
		auto o = firstScan(rel);
		if (!o) GTEST_SKIP() << "real data not found: " << realData(rel);
		CGroundAwareOccupancyGrid g;
		g.insertObservation(*o);
		const PointCensus c = pointCensus(g);
		std::cout << "[real] " << rel << ": floor cells " << c.floorOcc << " of " << c.floorKnown
				  << " occupied, object cells " << c.objectOcc << " of " << c.objectKnown << "\n";
		EXPECT_EQ(g.cameras().begin()->second.model, gam::CameraModel::Astra) << rel;
		ASSERT_GT(c.floorKnown, 100u) << rel;
		EXPECT_LE(double(c.floorOcc), 0.01 * double(c.floorKnown)) << rel;
		ASSERT_GE(c.objectKnown, 4u) << rel;
		EXPECT_GE(double(c.objectOcc), 0.9 * double(c.objectKnown)) << rel;
	}
}

TEST(RealData, MrptFloorScanGroundMatchesTheStoredPose)
{
	LOAD_OR_SKIP(o, "mrpt_3d_obs_ground/test-3d-obs-ground.rawlog");
	CGroundAwareOccupancyGrid g;
	g.insertObservation(*o);
	const auto& d = g.lastFrame().detection;
	ASSERT_TRUE(d.ok()) << d.describe();
	// With the stored sensor pose the floor is at z = 0.001 m with a 1.8 deg
	// residual tilt (dataset README): the detector must find that floor.
	const double tiltDeg = d.plane().tiltAngle() * 180 / M_PI;
	const double z = d.plane().heightAt(0.5, 0.0);
	std::cout << "[real] mrpt_3d_obs_ground: tilt " << tiltDeg << " deg, floor z at (0.5, 0) = " << z << " m, nodes "
			  << d.nodes.size() << "\n";
	EXPECT_NEAR(tiltDeg, 1.8, 1.0);
	EXPECT_NEAR(z, 0.001, 0.02);
	const Census c = census(g);
	EXPECT_GT(c.ground, 300u);
	EXPECT_LT(double(c.groundMarkedOcc), 0.02 * c.ground);
	// The blob in front of the robot (x 0.10-0.23, top 0.26 m) is an obstacle.
	EXPECT_GT(pOcc(g, 0.16, 0.0), 0.7);
}

TEST(RealData, ElevationMapMatchesMrptUnprojection)
{
	// Our range-image projection against MRPT's own unprojectInto().
	LOAD_OR_SKIP(o, "mrpt_tests_rgbd/tests_rgbd.rawlog");
	CElevation25DMap direct(-5, 5, -5, 5, 0.05), viaMrpt(-5, 5, -5, 5, 0.05);
	for (auto* m : {&direct, &viaMrpt})
	{
		auto opts = m->insertionOptions();
		opts.outliers.enabled = false;
		opts.projection.max_range = 100;
		opts.projection.z_min = -10;
		opts.projection.z_max = 10;
		m->setInsertionOptions(opts);
	}
	auto oc = *o;
	oc.hasPoints3D = false;  // force the range-image path
	oc.maxRange = 100;       // unprojectInto() ignores maxRange
	direct.insertObservation(oc);
	CSimplePointsMap pts;
	T3DPointsProjectionParams pp;
	pp.takeIntoAccountSensorPoseOnRobot = true;
	auto tmp = oc;
	tmp.unprojectInto(pts, pp);
	viaMrpt.insertPointCloud(pts);
	ASSERT_GT(pts.size(), 100000u);
	const auto &a = direct.grid(), &b = viaMrpt.grid();
	// Points on a cell boundary may round to the neighbour cell (float vs
	// double), so compare per-cell counts and heights with a small tolerance.
	size_t total = 0, countDiff = 0, cells = 0, zAgree = 0;
	for (uint32_t i : b.observedCells())
	{
		total += b.cell(i).count;
		countDiff += size_t(std::abs(int64_t(a.cell(i).count) - int64_t(b.cell(i).count)));
		cells++;
		zAgree +=
			std::abs(a.cell(i).z_max - b.cell(i).z_max) < 0.005 && std::abs(a.cell(i).z_min - b.cell(i).z_min) < 0.005;
	}
	std::cout << "[real] projection vs MRPT unprojectInto: " << total << " points, count difference " << countDiff
			  << ", heights agree in " << zAgree << " of " << cells << " cells\n";
	EXPECT_GT(total, 100000u);
	EXPECT_EQ(a.observedCount(), b.observedCount());
	EXPECT_LT(double(countDiff), 0.01 * total);
	EXPECT_GT(double(zAgree), 0.97 * cells);
}

TEST(RealData, NoFloorFrameGivesNoPlaneAndNoObstacles)
{
	LOAD_OR_SKIP(o, "mrpt_tests_rgbd/tests_rgbd.rawlog");
	CGroundAwareOccupancyGrid g;
	const auto before = g.getRawMap();
	EXPECT_NO_THROW(g.insertObservation(*o));
	EXPECT_FALSE(g.lastFrame().detection.ok()) << g.lastFrame().detection.describe();
	EXPECT_EQ(g.getRawMap(), before);
}

TEST(RealData, SmallObjectsOnCarpetAreObstaclesCarpetIsFree)
{
	LOAD_OR_SKIP(o, "pcl_milk_bottles_on_carpet/pcl_milk_bottles_on_carpet.rawlog");
	CGroundAwareOccupancyGrid g;
	g.insertObservation(*o);
	const auto& d = g.lastFrame().detection;
	ASSERT_TRUE(d.ok()) << d.describe();
	EXPECT_LT(d.plane().tiltAngle(), DEG2RAD(1.5));
	EXPECT_NEAR(d.plane().heightAt(1.0, 0.0), 0.0, 0.02);
	const Census c = census(g);
	EXPECT_GT(c.ground, 500u);
	EXPECT_LT(double(c.groundMarkedOcc), 0.02 * c.ground);
	// The bottles and cartons 0.5-0.8 m ahead.
	size_t occNear = 0;
	for (double x = 0.4; x <= 0.9; x += 0.05)
		for (double y = -0.5; y <= 0.5; y += 0.05) occNear += pOcc(g, x, y) > 0.7;
	std::cout << "[real] carpet: " << c.groundMarkedOcc << " of " << c.ground
			  << " ground cells occupied; object window: " << occNear << " cells above 0.7\n";
	EXPECT_GE(occNear, 8u);
}

TEST(RealData, FarNoisyCorridorFloorStaysFree)
{
	// Kinect v1, floor visible to 6 m: depth noise reaches several cm.
	LOAD_OR_SKIP(o, "pcl_five_people_corridor/pcl_five_people_corridor.rawlog");
	CGroundAwareOccupancyGrid g;
	g.insertObservation(*o);
	ASSERT_TRUE(g.lastFrame().detection.ok());
	const auto& fr = g.lastFrameElevation();
	const auto& geo = fr.geometry();
	const auto& pl = g.lastFrame().detection.plane();
	size_t flat = 0, flatOcc = 0;
	for (uint32_t i : fr.observedCells())
	{
		const auto& cell = fr.cell(i);
		const double x = geo.cx(int(i % uint32_t(geo.nx))), y = geo.cy(int(i / uint32_t(geo.nx)));
		// Surely floor: mean on the plane, thin, and 3.5-5 m away.
		if (x < 3.5 || std::abs(pl.signedDistance(x, y, cell.mean())) > 0.015 || cell.span() > 0.08) continue;
		flat++;
		flatOcc += pOcc(g, x, y) > 0.5;
	}
	std::cout << "[real] corridor far floor: " << flatOcc << " of " << flat << " cells occupied\n";
	ASSERT_GT(flat, 100u);
	EXPECT_LT(double(flatOcc), 0.03 * flat);
}

TEST(RealData, TheBandsOfADepthImageRegisteredToColourAreNoMissingFloor)
{
	// PCL's Kinect v1 frames are registered to the colour camera: the depth
	// camera does not cover the colour image's left and right borders, and
	// those columns return nothing in any row. Read as rays, they put a line
	// of missing floor along the edge of the view (`ground-aware-mapper` on
	// this frame: 190 missing-floor cells before 2026-11-29, all on that
	// line). The floor between the people has no hole.
	LOAD_OR_SKIP(o, "pcl_five_people_corridor/pcl_five_people_corridor.rawlog");
	CGroundAwareOccupancyGrid g;
	g.insertObservation(*o);
	ASSERT_TRUE(g.lastFrame().detection.ok());
	const auto& m = g.lastFrame().missing;
	std::cout << "[real] corridor: dead border columns " << m.dead_border_columns << ", missing-floor cells " << m.cells
			  << "\n";
	EXPECT_GE(m.dead_border_columns, 20u);
	EXPECT_EQ(m.cells, 0u);
	// The camera's summary carries them (the mapper prints them).
	ASSERT_EQ(g.cameras().size(), 1u);
	EXPECT_EQ(size_t(g.cameras().begin()->second.dead_border_columns), m.dead_border_columns);
}

TEST(RealData, AscendingStairsAreObstacles)
{
	LOAD_OR_SKIP(o, "walrus_kinect2_stairs_up/walrus_kinect2_stairs_up.rawlog");
	CGroundAwareOccupancyGrid g;
	g.insertObservation(*o);
	const auto& d = g.lastFrame().detection;
	ASSERT_TRUE(d.ok()) << d.describe();
	EXPECT_NEAR(d.plane().heightAt(1.8, 0.0), 0.0, 0.05);
	// Treads every 0.155 m up from x ~ 2.0 m: the flight is occupied.
	size_t occ = 0, seen = 0;
	for (double x = 2.1; x <= 3.5; x += 0.05)
		for (double y = -0.3; y <= 0.3; y += 0.05)
		{
			const double p = pOcc(g, x, y);
			if (p != 0.5) seen++;
			occ += p > 0.5;
		}
	ASSERT_GT(seen, 50u);
	EXPECT_GT(double(occ), 0.9 * seen);
}
