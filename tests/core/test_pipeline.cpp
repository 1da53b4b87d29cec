// Ground-aware mapping for MRPT
// The whole pure pipeline (gam::GroundAwarePipeline) on a ray-cast depth
// image: projector -> 2.5D grid (3-sigma filter, IDW) -> RRT-GPD -> ISM; and
// its parameter table.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <limits>

#include <set>
#include <string>

#include "gam/core/GroundAwarePipeline.h"
#include "test_helpers.h"

using namespace gam;
using gamtest::deg2rad;

namespace
{
struct Box
{
	Eigen::Vector3d lo, hi;
};

/** Distance t >= 0 along o + t d to the first hit of the floor z = floorZ or
 * one of the boxes; +inf if none. */
double castRay(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double floorZ, const std::vector<Box>& boxes)
{
	double best = std::numeric_limits<double>::infinity();
	if (d.z() < -1e-12)
	{
		const double t = (floorZ - o.z()) / d.z();
		if (t > 0) best = t;
	}
	for (const Box& b : boxes)
	{
		double t0 = 0, t1 = best;
		bool hit = true;
		for (int k = 0; k < 3 && hit; k++)
		{
			if (std::abs(d[k]) < 1e-12)
			{
				if (o[k] < b.lo[k] || o[k] > b.hi[k]) hit = false;
				continue;
			}
			double ta = (b.lo[k] - o[k]) / d[k], tb = (b.hi[k] - o[k]) / d[k];
			if (ta > tb) std::swap(ta, tb);
			t0 = std::max(t0, ta);
			t1 = std::min(t1, tb);
			if (t0 > t1) hit = false;
		}
		if (hit && t0 > 0 && t0 < best) best = t0;
	}
	return best;
}
}  // namespace

TEST(Pipeline, DepthImageOfFloorAndBoxToEvidence)
{
	const PinholeIntrinsics K = gamtest::smallCamera();
	const Eigen::Vector3d camPos(0, 0, 1.0);
	const Eigen::Matrix3d R = Eigen::AngleAxisd(deg2rad(25), Eigen::Vector3d::UnitY()).toRotationMatrix();
	const Box box{{1.5, -0.2, 0.0}, {1.9, 0.2, 0.3}};

	const std::vector<uint16_t> depth = gamtest::renderDepth(K, R, [&](const Eigen::Vector3d& w) {
		const double t = castRay(camPos, w, 0.0, {box});
		return t < 4.5 ? t : -1.0;  // t is the depth along the sensor X axis since ray.x() = 1
	});
	SensorFrame frame = gamtest::depthFrame(depth, K, R, camPos);

	PipelineParams params;
	params.m_x = params.m_y = 240;  // x, y in [-6, 6): everything the camera sees up to 4.5 m
	GroundAwarePipeline pipeline(params);
	const FrameResult& res = pipeline.process(frame, Eigen::Vector3d(0, 0, 0), GridLattice{0, 0, 0.05});
	ASSERT_TRUE(res.valid);
	ASSERT_GT(res.points, 10000u);
	const ElevationGrid& grid = pipeline.frameGrid();
	const GridGeometry& g = grid.geometry();
	// Centred on the robot, on the lattice through (0, 0).
	EXPECT_DOUBLE_EQ(g.x_min, -6.0);
	EXPECT_DOUBLE_EQ(g.y_min, -6.0);

	// The box top cells hold heights ~0.3, the floor ~0.
	const ElevationCell& top = grid.cell(g.ix(1.75), g.iy(0.0));
	ASSERT_TRUE(top.observed());
	EXPECT_NEAR(top.z_max, 0.3, 0.002);
	const ElevationCell& fl = grid.cell(g.ix(1.2), g.iy(0.5));
	ASSERT_TRUE(fl.observed());
	EXPECT_NEAR(fl.mean(), 0.0, 0.002);

	const GroundDetection& gd = res.detection;
	ASSERT_EQ(gd.status, GroundDetection::Status::Ok) << gd.describe();
	EXPECT_NEAR(gd.plane().heightAt(1.0, 0.0), 0.0, 0.005);
	EXPECT_LT(gd.plane().tiltAngle(), deg2rad(0.5));

	const IsmStats& st = res.ism;
	const InverseSensorModel& ism = pipeline.ism();
	EXPECT_TRUE(st.applied);
	EXPECT_GT(st.ground, 500u);
	EXPECT_GT(st.obstacle, 10u);
	size_t boxCells = 0, boxOcc = 0, floorCells = 0, floorFree = 0;
	for (uint32_t idx : grid.observedCells())
	{
		const double x = g.cx(int(idx % uint32_t(g.nx))), y = g.cy(int(idx / uint32_t(g.nx)));
		const float e = ism.evidence()[idx];
		// Strictly inside the box footprint (not its border cells).
		if (x > 1.55 && x < 1.85 && std::abs(y) < 0.15)
		{
			boxCells++;
			boxOcc += e > 0.5f;
		}
		// Floor well away from the box.
		else if (x > 0.8 && x < 1.3 && std::abs(y) < 0.6)
		{
			floorCells++;
			floorFree += e < 0.5f;
		}
	}
	EXPECT_GT(boxCells, 20u);
	EXPECT_EQ(boxOcc, boxCells);
	EXPECT_GT(floorCells, 100u);
	EXPECT_EQ(floorFree, floorCells);
	// The floor hidden behind the box was not seen: no evidence at all.
	EXPECT_EQ(ism.evidence()[g.index(g.ix(2.3), g.iy(0.0))], 0.5f);
}

TEST(Pipeline, EveryParameterHasOneKeyAndOneRange)
{
	// Every key once, and every default inside its own range.
	std::set<std::string> keys;
	const PipelineParams defaults;
	size_t n = 0;
	PipelineParams::forEachParam(defaults, [&](const ParamInfo& info, const auto& v) {
		n++;
		EXPECT_TRUE(keys.insert(info.key).second) << "duplicate key " << info.key;
		EXPECT_LE(info.lo, double(v)) << info.key;
		EXPECT_GE(info.hi, double(v)) << info.key;
	});
	EXPECT_EQ(keys.size(), n);
	// Paper Table I names are the keys.
	for (const char* k :
		 {"K", "N_th", "E_th", "s_x", "s_y", "m_x", "m_y", "d_n", "d_pth", "K_g", "sigma2", "K_n", "d_min", "K_m"})
		EXPECT_EQ(keys.count(k), 1u) << k;
	EXPECT_NO_THROW(defaults.validate());
}

TEST(Pipeline, ParametersAreCheckedWhenSetNotPerFrame)
{
	GroundAwarePipeline pipeline;
	PipelineParams p;
	// K_g = 0.5 would make a ground voxel certain to be free: out of [0, 0.499].
	p.ism.K_g = 0.5;
	try
	{
		pipeline.setParams(p);
		FAIL() << "K_g=0.5 accepted";
	}
	catch (const std::invalid_argument& e)
	{
		EXPECT_NE(std::string(e.what()).find("K_g=0.5 is out of range 0 to 0.499"), std::string::npos) << e.what();
	}
	EXPECT_DOUBLE_EQ(pipeline.params().ism.K_g, 0.3);  // the old ones are kept

	// Rules between keys.
	p = PipelineParams{};
	p.projection.z_min = 1.0f;
	p.projection.z_max = 0.5f;
	EXPECT_THROW(pipeline.setParams(p), std::invalid_argument);
	p = PipelineParams{};
	p.rrt.neighbourhood_x = 4;
	EXPECT_THROW(pipeline.setParams(p), std::invalid_argument);
	p = PipelineParams{};
	p.m_x = p.m_y = 20000;  // 4e8 cells > the 2.5D map's 67M-cell limit
	EXPECT_THROW(pipeline.setParams(p), std::invalid_argument);

	// A bad input frame is an error too, not silent garbage.
	SensorFrame empty;
	EXPECT_THROW(pipeline.process(empty, Eigen::Vector3d(NAN, 0, 0), GridLattice{}), std::invalid_argument);
	const FrameResult& r = pipeline.process(empty, Eigen::Vector3d(0, 0, 0), GridLattice{});
	EXPECT_TRUE(r.valid);
	EXPECT_EQ(r.points, 0u);
	EXPECT_EQ(r.detection.status, GroundDetection::Status::EmptyGrid);
	EXPECT_FALSE(r.ism.applied);
}

TEST(Pipeline, CropsAtRobotHeightInTheRobotFrame)
{
	PipelineParams p;
	p.ism.robot_height = 1.2;
	const ProjectionFilter f = p.projectionFilter(0.5);  // robot floor at z = 0.5 in the map
	EXPECT_FLOAT_EQ(f.z_min, 0.5f - 3.0f);               // z_min = -3 (robot frame)
	EXPECT_FLOAT_EQ(f.z_max, 0.5f + 1.2f);               // min(z_max 2.5, robot_height 1.2)
	EXPECT_FLOAT_EQ(f.max_range, 5.0f);
}

TEST(Pipeline, AWallJustOutOfTheCamerasRangeLeavesNoObstacleInFrontOfIt)
{
	// A level camera 1 m up whose depth stops at 4.0 m (the frame's
	// max_range, as CObservation3DRangeScan::maxRange gives it), facing a
	// wall at x = 4.05: only the wall samples that the range noise brought
	// 9 cm nearer come back (depth 3.96, heights 0.05-0.95 m), all in the
	// cells [3.95, 4.00). With a level camera a pixel's depth is its x. The
	// camera's range sigma is 3 cm (camera_model = custom), so the walk from
	// those cells reaches 3 sigma + half a cell = 0.115 m on: its first step,
	// x = 4.025 (depth 4.025 > 4.0), is past the limit with nothing seen.
	const PinholeIntrinsics K = gamtest::smallCamera();
	const Eigen::Vector3d camPos(0, 0, 1.0);
	const Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
	const double wallX = 4.05, limit = 4.0, pulledTo = 3.96;
	const std::vector<uint16_t> depth = gamtest::renderDepth(K, R, [&](const Eigen::Vector3d& w) {
		const double floorT = w.z() < 0 ? -camPos.z() / w.z() : std::numeric_limits<double>::infinity();
		if (floorT <= limit) return floorT;
		const double zAtWall = camPos.z() + wallX * w.z();
		return wallX < floorT && zAtWall >= 0.05 && zAtWall <= 0.95 ? pulledTo : -1.0;
	});
	PipelineParams params;
	params.m_x = params.m_y = 240;
	params.projection.drop_flying_pixels = false;  // not what this is about
	params.camera.model = CameraModel::Custom;
	params.camera.custom.tof_c0 = 0.03;
	params.camera.range_of_trust = false;  // 3 cm at 4 m: no trust there, and so no evidence at all
	const auto wallRow = [&](double maxRange, size_t& cells, size_t& occupied) {
		SensorFrame frame = gamtest::depthFrame(depth, K, R, camPos);
		frame.max_range = float(maxRange);
		GroundAwarePipeline pipeline(params);
		const FrameResult& res = pipeline.process(frame, Eigen::Vector3d(0, 0, 0), GridLattice{0, 0, 0.05});
		EXPECT_EQ(res.detection.status, GroundDetection::Status::Ok) << res.detection.describe();
		const GridGeometry& g = pipeline.frameGrid().geometry();
		cells = occupied = 0;
		for (double y = -0.975; y < 1.0; y += 0.05)
		{
			const size_t idx = g.index(g.ix(3.975), g.iy(y));
			if (pipeline.frameGrid().cell(idx).count == 0) continue;
			cells++;
			occupied += pipeline.ism().evidence()[idx] > 0.5f;
		}
		return res.ism.smeared;
	};
	size_t cells = 0, occupied = 0;
	// The camera's limit, declared: those samples are the wall's beyond it.
	EXPECT_GE(wallRow(limit, cells, occupied), 30u);
	EXPECT_GE(cells, 35u);
	EXPECT_EQ(occupied, 0u);
	// Not declared (the projection's 5 m): the same samples are an object of
	// their own, a row of obstacles 5 cm in front of the wall.
	EXPECT_EQ(wallRow(std::numeric_limits<float>::infinity(), cells, occupied), 0u);
	EXPECT_GE(cells, 35u);
	EXPECT_EQ(occupied, cells);
}

TEST(Pipeline, RewindPatchesCountsAFrameRunTwiceOnce)
{
	// A frame that ran ahead on a worker and must run again in its turn
	// (CGroundAwareOccupancyGrid, threads > 1) counts once for the ramp
	// patches the pipeline remembers (patch_memory): rewindPatches() undoes
	// the first run. A 7.1 deg ramp (steps of 1 cm every 8 cm, under d_pth)
	// ahead of the camera is fitted as a patch in each run of frame A; a
	// patch is remembered once 2 frames fitted it. Frame B (the floor alone)
	// then gets it only if frame A counted twice.
	const PinholeIntrinsics K = gamtest::smallCamera();
	const Eigen::Vector3d camPos(0, 0, 1.0);
	const Eigen::Matrix3d R = Eigen::AngleAxisd(deg2rad(25), Eigen::Vector3d::UnitY()).toRotationMatrix();
	std::vector<Box> ramp;
	for (int k = 0; k < 14; k++) ramp.push_back({{1.4 + 0.08 * k, -0.5, 0.0}, {2.8, 0.5, 0.01 * (k + 1)}});
	auto render = [&](const std::vector<Box>& boxes) {
		return gamtest::renderDepth(K, R, [&](const Eigen::Vector3d& w) {
			const double t = castRay(camPos, w, 0.0, boxes);
			return t < 4.5 ? t : -1.0;
		});
	};
	// (A SensorFrame views its depth image: the images outlive the frames.)
	const std::vector<uint16_t> depthA = render(ramp), depthB = render({});
	const SensorFrame a = gamtest::depthFrame(depthA, K, R, camPos), b = gamtest::depthFrame(depthB, K, R, camPos);
	PipelineParams params;
	params.m_x = params.m_y = 240;
	const Eigen::Vector3d robot(0, 0, 0);
	const GridLattice lattice{0, 0, 0.05};

	GroundAwarePipeline once(params), twice(params);
	const FrameResult& ra = once.process(a, robot, lattice);
	ASSERT_TRUE(ra.valid);
	ASSERT_GE(ra.detection.planes.size(), 2u) << "frame A must fit the ramp: " << ra.detection.describe();
	once.rewindPatches();  // the run not taken
	once.process(a, robot, lattice);
	EXPECT_EQ(once.process(b, robot, lattice).remembered_planes.size(), 0u);

	twice.process(a, robot, lattice);
	twice.process(a, robot, lattice);
	EXPECT_GE(twice.process(b, robot, lattice).remembered_planes.size(), 1u);
}
