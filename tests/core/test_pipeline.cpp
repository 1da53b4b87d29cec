// Ground-aware mapping for MRPT
// The whole pure pipeline on a ray-cast depth image: projector -> 2.5D grid
// (3-sigma filter) -> RRT-GPD -> ISM.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <limits>

#include "gam/DepthProjector.h"
#include "gam/InverseSensorModel.h"
#include "gam/RrtGroundDetector.h"
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
	PinholeIntrinsics K;
	K.width = 160;
	K.height = 120;
	K.fx = K.fy = 120;
	K.cx = 79.5;
	K.cy = 59.5;
	const Eigen::Vector3d camPos(0, 0, 1.0);
	const Eigen::Matrix3d R = Eigen::AngleAxisd(deg2rad(25), Eigen::Vector3d::UnitY()).toRotationMatrix();
	const Box box{{1.5, -0.2, 0.0}, {1.9, 0.2, 0.3}};

	std::vector<uint16_t> depth(size_t(K.width * K.height), 0);
	for (int r = 0; r < K.height; r++)
		for (int c = 0; c < K.width; c++)
		{
			const Eigen::Vector3d ray(1.0, (K.cx - c) / K.fx, (K.cy - r) / K.fy);
			const Eigen::Vector3d w = R * ray;
			const double t = castRay(camPos, w, 0.0, {box});
			// t is the depth along the sensor X axis since ray.x() = 1.
			if (std::isfinite(t) && t < 4.5) depth[size_t(r * K.width + c)] = uint16_t(std::lround(t * 1000));
		}
	RangeImageView img;
	img.data = depth.data();
	img.rows = K.height;
	img.cols = K.width;
	img.stride = size_t(K.width);
	RigidTransform T;
	T.R = R.cast<float>();
	T.t = camPos.cast<float>();

	ElevationGrid grid(gamtest::makeGeometry(-1, -3, 0.05, 120, 120));  // x in [-1, 5)
	DepthProjector proj;
	BinnedPoints pts;
	ProjectionFilter f;
	const size_t n = proj.project(img, K, T, f, grid, pts);
	ASSERT_GT(n, 10000u);
	grid.insert(pts, OutlierFilterParams{});
	const GridGeometry& g = grid.geometry();

	// The box top cells hold heights ~0.3, the floor ~0.
	const ElevationCell& top = grid.cell(g.ix(1.75), g.iy(0.0));
	ASSERT_TRUE(top.observed());
	EXPECT_NEAR(top.z_max, 0.3, 0.002);
	const ElevationCell& fl = grid.cell(g.ix(1.2), g.iy(0.5));
	ASSERT_TRUE(fl.observed());
	EXPECT_NEAR(fl.mean(), 0.0, 0.002);

	RrtGroundDetector det;
	GroundDetection gd;
	det.detect(grid, GroundSeedHint{0, 0, 0}, gd);
	ASSERT_EQ(gd.status, GroundDetection::Status::Ok) << gd.describe();
	EXPECT_NEAR(gd.plane().heightAt(1.0, 0.0), 0.0, 0.005);
	EXPECT_LT(gd.plane().tiltAngle(), deg2rad(0.5));

	InverseSensorModel ism;
	IsmStats st;
	ism.compute(grid, gd, camPos, st);
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
