// Ground-aware mapping for MRPT
// DepthProjector against synthetic range images of known geometry.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <random>
#include <stdexcept>
#include <vector>

#include "gam/core/DepthProjector.h"
#include "test_helpers.h"

using namespace gam;
using gamtest::deg2rad;
using gamtest::makeGeometry;

namespace
{
constexpr int W = 64, H = 48;

PinholeIntrinsics camera()
{
	PinholeIntrinsics K;
	K.width = W;
	K.height = H;
	K.fx = 50;
	K.fy = 50;
	K.cx = 31.5;
	K.cy = 23.5;
	return K;
}

struct Image
{
	std::vector<uint16_t> px;
	int rows = H, cols = W;
	size_t stride = W;
	Image(int r = H, int c = W, size_t s = W) : px(size_t(r) * s, 0), rows(r), cols(c), stride(s) {}
	uint16_t& at(int r, int c) { return px[size_t(r) * stride + size_t(c)]; }
	RangeImageView view(bool isDepth = true, float units = 0.001f) const
	{
		RangeImageView v;
		v.data = px.data();
		v.rows = rows;
		v.cols = cols;
		v.stride = stride;
		v.units = units;
		v.is_depth = isDepth;
		return v;
	}
};

/** Ray of pixel (r, c) in the sensor frame, x = 1 (MRPT convention). */
Eigen::Vector3d pixelRay(const PinholeIntrinsics& K, int r, int c)
{
	return {1.0, (K.cx - c) / K.fx, (K.cy - r) / K.fy};
}

RigidTransform pose(const Eigen::Matrix3d& R, const Eigen::Vector3d& t)
{
	RigidTransform T;
	T.R = R.cast<float>();
	T.t = t.cast<float>();
	return T;
}
Eigen::Matrix3d pitchDown(double deg)
{
	// Rotation about +Y by +deg maps +X to (cos, 0, -sin): looking down.
	return Eigen::AngleAxisd(deg2rad(deg), Eigen::Vector3d::UnitY()).toRotationMatrix();
}
Eigen::Matrix3d yaw(double deg) { return Eigen::AngleAxisd(deg2rad(deg), Eigen::Vector3d::UnitZ()).toRotationMatrix(); }

/** The cell `idx` must contain (x, y), up to a tolerance for float rounding at
 * the cell borders. */
void expectInCell(const GridGeometry& g, uint32_t idx, double x, double y, double tol = 1e-4)
{
	const int cx = int(idx % uint32_t(g.nx)), cy = int(idx / uint32_t(g.nx));
	const double x0 = g.x_min + cx * g.resolution, y0 = g.y_min + cy * g.resolution;
	EXPECT_GE(x, x0 - tol) << "cell " << cx << "," << cy;
	EXPECT_LT(x, x0 + g.resolution + tol) << "cell " << cx << "," << cy;
	EXPECT_GE(y, y0 - tol) << "cell " << cx << "," << cy;
	EXPECT_LT(y, y0 + g.resolution + tol) << "cell " << cx << "," << cy;
}

/** Projects each listed pixel alone (every 5th row and column) and compares it
 * with the analytic point R * (D * ray) + t. */
void checkPixelsOneByOne(
	const Image& img, bool isDepth, const RigidTransform& T, const Eigen::Matrix3d& R, const Eigen::Vector3d& t,
	const ElevationGrid& grid, int* checked)
{
	const PinholeIntrinsics K = camera();
	DepthProjector proj;
	ProjectionFilter f;
	f.max_range = 60;
	for (int r = 0; r < H; r += 5)
		for (int c = 0; c < W; c += 5)
		{
			const uint16_t raw = img.px[size_t(r) * img.stride + size_t(c)];
			if (!raw) continue;
			Image one;
			one.at(r, c) = raw;
			BinnedPoints out;
			ASSERT_EQ(proj.project(one.view(isDepth), K, T, f, grid, out), 1u) << r << "," << c;
			ASSERT_EQ(out.size(), 1u);
			const Eigen::Vector3d ray = pixelRay(K, r, c);
			const double v = raw * 0.001;
			const double D = isDepth ? v : v / ray.norm();
			const Eigen::Vector3d P = R * (D * ray) + t;
			expectInCell(grid.geometry(), out.cells()[0], P.x(), P.y());
			EXPECT_NEAR(out.heights()[0], P.z(), 1e-4) << r << "," << c;
			++*checked;
		}
}

uint16_t toRaw(double metres) { return uint16_t(std::lround(metres * 1000.0)); }

/** Depth image of the wall x = X (sensor at the origin of its frame). */
Image wallDepthImage(double X)
{
	Image img;
	for (int r = 0; r < H; r++)
		for (int c = 0; c < W; c++) img.at(r, c) = toRaw(X);
	return img;
}

}  // namespace

TEST(DepthProjector, RayLutFollowsMrptConvention)
{
	const PinholeIntrinsics K = camera();
	DepthProjector proj;
	ElevationGrid grid;
	BinnedPoints out;
	Image img;
	proj.project(img.view(), K, RigidTransform{}, ProjectionFilter{}, grid, out);
	ASSERT_EQ(proj.rayTableSize(), size_t(W * H));
	for (int r : {0, 10, 47})
		for (int c : {0, 31, 63})
		{
			const Eigen::Vector2f k = proj.rayFactor(r, c);
			EXPECT_NEAR(k.x(), (31.5 - c) / 50.0, 1e-6);
			EXPECT_NEAR(k.y(), (23.5 - r) / 50.0, 1e-6);
		}
	EXPECT_EQ(out.size(), 0u);  // an all-zero image bins nothing
}

TEST(DepthProjector, RowRayBoundsAreTheRowsExtremeRayFactors)
{
	// camera(): 64x48, cx = 31.5, cy = 23.5, fx = fy = 50. Without distortion
	// a row's y/x factor (31.5 - c) / 50 runs from 31.5 / 50 = 0.63 (c = 0)
	// down to -31.5 / 50 = -0.63 (c = 63); its z/x factor (23.5 - r) / 50 is
	// the same along the row: 0.47 on row 0, 0.01 on row 23, -0.47 on row 47.
	DepthProjector proj;
	ElevationGrid grid;
	BinnedPoints out;
	Image img;
	proj.project(img.view(), camera(), RigidTransform{}, ProjectionFilter{}, grid, out);
	for (const auto& [r, z] : {std::pair{0, 0.47}, {23, 0.01}, {47, -0.47}})
	{
		const DepthProjector::RayBounds& b = proj.rowRayBounds(r);
		EXPECT_NEAR(b.y_min, -0.63, 1e-6) << r;
		EXPECT_NEAR(b.y_max, 0.63, 1e-6) << r;
		EXPECT_NEAR(b.z_min, z, 1e-6) << r;
		EXPECT_NEAR(b.z_max, z, 1e-6) << r;
	}
	// With distortion the factors bend along a row: the bounds are still the
	// smallest and largest of the row's table entries.
	PinholeIntrinsics K = camera();
	K.k1 = 0.12;
	K.p1 = 0.001;
	proj.project(img.view(), K, RigidTransform{}, ProjectionFilter{}, grid, out);
	for (int r = 0; r < H; r += 5)
	{
		float yLo = 1e9f, yHi = -1e9f, zLo = 1e9f, zHi = -1e9f;
		for (int c = 0; c < W; c++)
		{
			const Eigen::Vector2f k = proj.rayFactor(r, c);
			yLo = std::min(yLo, k.x());
			yHi = std::max(yHi, k.x());
			zLo = std::min(zLo, k.y());
			zHi = std::max(zHi, k.y());
		}
		const DepthProjector::RayBounds& b = proj.rowRayBounds(r);
		EXPECT_EQ(b.y_min, yLo) << r;
		EXPECT_EQ(b.y_max, yHi) << r;
		EXPECT_EQ(b.z_min, zLo) << r;
		EXPECT_EQ(b.z_max, zHi) << r;
		EXPECT_LT(b.z_min, b.z_max) << r;  // k1 bends the row's z/x factor
	}
}

TEST(DepthProjector, WallAtThreeMetresLandsInItsColumn)
{
	// Sensor at (0, 0, 0.5) looking along +X; wall x = 3.02 (column 160 of a
	// grid from -5 with 5 cm cells: (3.02 + 5) / 0.05 = 160.4).
	const Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
	const Eigen::Vector3d t(0, 0, 0.5);
	const RigidTransform T = pose(R, t);
	ElevationGrid grid;  // -5..5, 0.05
	const Image img = wallDepthImage(3.02);

	DepthProjector proj;
	BinnedPoints out;
	EXPECT_EQ(proj.project(img.view(), camera(), T, ProjectionFilter{}, grid, out), size_t(W * H));
	ASSERT_EQ(out.size(), size_t(W * H));
	const int col = int(std::floor((3.02 + 5.0) / 0.05));
	ASSERT_EQ(col, 160);
	double zmin = 1e9, zmax = -1e9;
	for (size_t i = 0; i < out.size(); i++)
	{
		EXPECT_EQ(int(out.cells()[i] % 200u), col);
		zmin = std::min(zmin, double(out.heights()[i]));
		zmax = std::max(zmax, double(out.heights()[i]));
	}
	// Heights of the top and bottom rows: 0.5 + 3.02 * (23.5 - r) / 50.
	EXPECT_NEAR(zmax, 0.5 + 3.02 * 23.5 / 50, 1e-4);
	EXPECT_NEAR(zmin, 0.5 + 3.02 * (23.5 - 47) / 50, 1e-4);

	// Into the grid: pixel column c sees y = 3.02 * (31.5 - c) / 50 (6 cm
	// apart, so some 5 cm cells in between stay empty); 48 points each.
	gamtest::insertAll(grid, out);
	const GridGeometry& g = grid.geometry();
	std::vector<int> expectedCount(size_t(g.ny), 0);
	for (int c = 0; c < W; c++)
	{
		const double y = 3.02 * (31.5 - c) / 50, fy = (y + 5) / 0.05;
		ASSERT_GT(std::abs(fy - std::round(fy)), 0.01);  // no pixel on a cell border
		expectedCount[size_t(std::floor(fy))] += H;
	}
	for (int cy = 0; cy < g.ny; cy++)
		for (int cx = 0; cx < g.nx; cx++)
		{
			const ElevationCell& c = grid.cell(cx, cy);
			if (cx != col)
				ASSERT_FALSE(c.observed()) << cx << "," << cy;
			else
				EXPECT_EQ(int(c.count), expectedCount[size_t(cy)]) << "y=" << g.cy(cy);
		}

	int checked = 0;
	checkPixelsOneByOne(img, true, T, R, t, grid, &checked);
	EXPECT_GT(checked, 100);
}

TEST(DepthProjector, YawedSensorSeesWallInItsRow)
{
	// Sensor at (1, 2, 0.5) yawed +90 deg (looking along +Y): the wall at
	// depth 2.02 is the line y = 4.02, row floor((4.02 + 5) / 0.05) = 180.
	const Eigen::Matrix3d R = yaw(90);
	const Eigen::Vector3d t(1, 2, 0.5);
	const RigidTransform T = pose(R, t);
	ElevationGrid grid;
	const Image img = wallDepthImage(2.02);
	DepthProjector proj;
	BinnedPoints out;
	EXPECT_EQ(proj.project(img.view(), camera(), T, ProjectionFilter{}, grid, out), size_t(W * H));
	for (size_t i = 0; i < out.size(); i++) EXPECT_EQ(int(out.cells()[i] / 200u), 180);
	// Pixel column 0 looks left of the optical axis: +Y of the sensor = -X of
	// the grid, so x = 1 - 2.02 * 31.5 / 50.
	Image one;
	one.at(23, 0) = toRaw(2.02);
	out.clear();
	ASSERT_EQ(proj.project(one.view(), camera(), T, ProjectionFilter{}, grid, out), 1u);
	expectInCell(grid.geometry(), out.cells()[0], 1 - 2.02 * 31.5 / 50, 4.02);
	int checked = 0;
	checkPixelsOneByOne(img, true, T, R, t, grid, &checked);
	EXPECT_GT(checked, 100);
}

TEST(DepthProjector, FloorFromPitchedCameraLandsAtZeroHeight)
{
	// Camera 1 m above the floor, pitched 45 deg down: every pixel sees the
	// floor z = 0 at D = 1 / -(R * ray).z along the sensor X axis.
	const Eigen::Matrix3d R = pitchDown(45);
	const Eigen::Vector3d t(0.3, -0.2, 1.0);
	const RigidTransform T = pose(R, t);
	const PinholeIntrinsics K = camera();
	Image img;
	double farthest = 0;
	for (int r = 0; r < H; r++)
		for (int c = 0; c < W; c++)
		{
			const Eigen::Vector3d w = R * pixelRay(K, r, c);
			ASSERT_LT(w.z(), -0.1);
			const double D = 1.0 / -w.z();
			farthest = std::max(farthest, D);
			img.at(r, c) = toRaw(D);
		}
	ASSERT_LT(farthest, 5.0);  // all within the default max range

	ElevationGrid grid;
	DepthProjector proj;
	BinnedPoints out;
	EXPECT_EQ(proj.project(img.view(), K, T, ProjectionFilter{}, grid, out), size_t(W * H));
	// Depth quantization is 0.5 mm along X: |dz| <= 0.5 mm * |w.z| / 1 < 1 mm.
	for (float z : out.heights()) EXPECT_NEAR(z, 0.0, 1e-3);
	gamtest::insertAll(grid, out);
	for (uint32_t idx : grid.observedCells()) EXPECT_NEAR(grid.cell(idx).mean(), 0.0, 1e-3);
	// Nearest floor point: bottom row, centre column.
	{
		const Eigen::Vector3d w = R * pixelRay(K, H - 1, 31);
		const Eigen::Vector3d P = t + (1.0 / -w.z()) * w;
		EXPECT_TRUE(grid.cell(grid.geometry().ix(P.x()), grid.geometry().iy(P.y())).observed());
		// Nothing is closer to the camera than that row, in x.
		for (uint32_t idx : grid.observedCells()) EXPECT_GE(grid.geometry().cx(int(idx % 200u)), P.x() - 0.06);
	}
	int checked = 0;
	checkPixelsOneByOne(img, true, T, R, t, grid, &checked);
	EXPECT_GT(checked, 100);
}

TEST(DepthProjector, RangeModeUsesEuclideanRange)
{
	// Same wall x = 3.02, but the image stores the range along each ray.
	const Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
	const Eigen::Vector3d t(0, 0, 0.5);
	const RigidTransform T = pose(R, t);
	const PinholeIntrinsics K = camera();
	Image img;
	for (int r = 0; r < H; r++)
		for (int c = 0; c < W; c++) img.at(r, c) = toRaw(3.02 * pixelRay(K, r, c).norm());
	ElevationGrid grid;
	DepthProjector proj;
	BinnedPoints out;
	ProjectionFilter f;
	f.max_range = 10;
	EXPECT_EQ(proj.project(img.view(false), K, T, f, grid, out), size_t(W * H));
	for (size_t i = 0; i < out.size(); i++) EXPECT_EQ(int(out.cells()[i] % 200u), 160);
	int checked = 0;
	checkPixelsOneByOne(img, false, T, R, t, grid, &checked);
	EXPECT_GT(checked, 100);

	// Read as depth, the corner pixel would land at x = range, not at 3.02.
	Image one;
	one.at(0, 0) = img.at(0, 0);
	out.clear();
	ASSERT_EQ(proj.project(one.view(true), K, T, f, grid, out), 1u);
	const double xr = 3.02 * pixelRay(K, 0, 0).norm();  // 3.84 m
	EXPECT_EQ(int(out.cells()[0] % 200u), int(std::floor((xr + 5) / 0.05)));

	// Range limits apply to the range along the ray in this mode: a wall at
	// x = 3.5 has ranges 3.5 |ray| in [3.5, 4.55]; max_range 4 keeps the pixels
	// with |ray| <= 4 / 3.5.
	Image w35;
	size_t expected = 0;
	for (int r = 0; r < H; r++)
		for (int c = 0; c < W; c++)
		{
			const double range = 3.5 * pixelRay(K, r, c).norm();
			w35.at(r, c) = toRaw(range);
			if (w35.at(r, c) * 0.001 <= 4.0) expected++;
		}
	ASSERT_GT(expected, 100u);
	ASSERT_LT(expected, size_t(W * H));
	f.max_range = 4.0;
	out.clear();
	EXPECT_EQ(proj.project(w35.view(false), K, T, f, grid, out), expected);
	// As a depth image, every pixel is at 3.5..4.55 "depth": only raw <= 4000.
}

TEST(DepthProjector, DecimationUsesEveryNthRowAndColumn)
{
	const RigidTransform T = pose(Eigen::Matrix3d::Identity(), {0, 0, 0.5});
	ElevationGrid grid;
	const Image img = wallDepthImage(3.02);
	DepthProjector proj;
	BinnedPoints out;
	ProjectionFilter f;
	f.decimation = 2;
	EXPECT_EQ(proj.project(img.view(), camera(), T, f, grid, out), size_t(24 * 32));
	// Only even rows: z = 0.5 + 3.02 * (23.5 - r) / 50 with r even.
	for (float z : out.heights())
	{
		const double r = 23.5 - (z - 0.5) * 50 / 3.02;
		const double nearest = std::round(r);
		EXPECT_NEAR(r, nearest, 0.01);
		EXPECT_EQ(int(nearest) % 2, 0) << "row " << nearest;
	}
	f.decimation = 3;
	out.clear();
	EXPECT_EQ(proj.project(img.view(), camera(), T, f, grid, out), size_t(16 * 22));
	f.decimation = 0;  // treated as 1
	out.clear();
	EXPECT_EQ(proj.project(img.view(), camera(), T, f, grid, out), size_t(W * H));

	// A lone pixel at an odd row is skipped with decimation 2, at (2, 4) kept.
	f.decimation = 2;
	Image one;
	one.at(1, 1) = 3020;
	out.clear();
	EXPECT_EQ(proj.project(one.view(), camera(), T, f, grid, out), 0u);
	one.at(1, 1) = 0;
	one.at(2, 4) = 3020;
	EXPECT_EQ(proj.project(one.view(), camera(), T, f, grid, out), 1u);
}

namespace
{
// Random depths (one in 9 missing, some beyond any range) on a 61-pixel-wide
// camera (not a multiple of 8: the row loops' scalar tail) with lens
// distortion, pitched, rolled and yawed.
struct RandomScene
{
	PinholeIntrinsics K;
	Image img;
	RigidTransform T;
};
RandomScene randomDistortedScene(unsigned seed)
{
	std::mt19937 rng(seed);
	std::uniform_int_distribution<int> depth(0, 7000);
	RandomScene r{camera(), Image(H, 61, 61), {}};
	r.K.width = 61;
	r.K.k1 = 0.05;
	r.K.p2 = 0.001;
	for (auto& v : r.img.px) v = uint16_t(rng() % 9 == 0 ? 0 : depth(rng));
	r.T = pose(
		(Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(0.4, Eigen::Vector3d::UnitY()) *
		 Eigen::AngleAxisd(0.05, Eigen::Vector3d::UnitX()))
			.toRotationMatrix(),
		{0.3, -0.2, 1.1});
	return r;
}
}  // namespace

TEST(DepthProjector, DecimatedSamplesAreThoseOfTheFullImageAtTheKeptPixels)
{
	// Reference: the full-resolution projection of the same image with every
	// pixel off the decimation lattice (row or column not a multiple of n)
	// set to 0 (no return): same pixels, same rays, same order, so the same
	// samples bit for bit. Odd width (a scalar tail after the 8-wide loop),
	// distortion, a pitched and rolled camera, depth and range images, both
	// row loops; then a second camera, whose decimated ray table must follow.
	const RandomScene scene = randomDistortedScene(11);
	const PinholeIntrinsics& K = scene.K;
	const Image& img = scene.img;
	const RigidTransform& T = scene.T;
	ElevationGrid grid(makeGeometry(-2, -4, 0.05, 120, 160));
	PinholeIntrinsics K2 = K;
	K2.fx *= 1.1;
	K2.k1 = 0;
	for (int n : {2, 3})
	{
		Image lattice = img;
		for (int r = 0; r < H; r++)
			for (int c = 0; c < 61; c++)
				if (r % n || c % n) lattice.at(r, c) = 0;
		for (bool avx2 : {true, false})
			for (bool isDepth : {true, false})
			{
				DepthProjector decimated, full;
				decimated.setAllowAvx2(avx2);
				for (const PinholeIntrinsics& cam : {K, K2})
				{
					ProjectionFilter f;
					f.min_range = 0.4f;
					f.z_min = -1.f;
					f.z_max = 1.5f;
					// (The flying-pixel filter reads neighbours n apart when
					// decimated: a different rule on the lattice image.)
					f.drop_flying_pixels = false;
					BinnedPoints a, b;
					f.decimation = n;
					const size_t na = decimated.project(img.view(isDepth), cam, T, f, grid, a);
					f.decimation = 1;
					const size_t nb = full.project(lattice.view(isDepth), cam, T, f, grid, b);
					ASSERT_EQ(na, nb) << "n=" << n;
					ASSERT_GT(na, 20u);
					for (size_t i = 0; i < na; i++)
					{
						ASSERT_EQ(a.cells()[i], b.cells()[i]) << i;
						ASSERT_EQ(a.heights()[i], b.heights()[i]) << i;
					}
				}
			}
	}
}

TEST(DepthProjector, HeightBandAndRangeLimits)
{
	const RigidTransform T = pose(Eigen::Matrix3d::Identity(), {0, 0, 0.5});
	ElevationGrid grid;
	DepthProjector proj;
	BinnedPoints out;

	// z band [0, 1] on the wall x = 3.02: rows with |3.02 (23.5 - r) / 50| <= 0.5.
	const Image wall = wallDepthImage(3.02);
	size_t rowsIn = 0;
	for (int r = 0; r < H; r++)
	{
		const double z = 0.5 + 3.02 * (23.5 - r) / 50;
		if (z >= 0 && z <= 1) rowsIn++;
	}
	ASSERT_EQ(rowsIn, 16u);  // r = 16..31
	ProjectionFilter f;
	f.z_min = 0.0f;
	f.z_max = 1.0f;
	EXPECT_EQ(proj.project(wall.view(), camera(), T, f, grid, out), rowsIn * W);
	for (float z : out.heights())
	{
		EXPECT_GE(z, 0.f);
		EXPECT_LE(z, 1.f);
	}

	// Left half of the image at 2 m, right half at 4.5 m.
	Image img;
	for (int r = 0; r < H; r++)
		for (int c = 0; c < W; c++) img.at(r, c) = c < 32 ? 2000 : 4500;
	ProjectionFilter g;
	g.max_range = 4.0f;
	out.clear();
	EXPECT_EQ(proj.project(img.view(), camera(), T, g, grid, out), size_t(32 * H));
	for (uint32_t idx : out.cells()) EXPECT_EQ(int(idx % 200u), int(std::floor((2.0 + 5) / 0.05)));
	g.max_range = 5.0f;
	g.min_range = 3.0f;
	out.clear();
	EXPECT_EQ(proj.project(img.view(), camera(), T, g, grid, out), size_t(32 * H));
	for (uint32_t idx : out.cells()) EXPECT_EQ(int(idx % 200u), int(std::floor((4.5 + 5) / 0.05)));
	g.min_range = 0;
	out.clear();
	EXPECT_EQ(proj.project(img.view(), camera(), T, g, grid, out), size_t(W * H));
}

TEST(DepthProjector, InvalidPixelsAndOutOfGridPointsAreSkipped)
{
	const RigidTransform T = pose(Eigen::Matrix3d::Identity(), {0, 0, 0.5});
	DepthProjector proj;
	BinnedPoints out;
	// Checkerboard of zeros: half the pixels.
	Image img = wallDepthImage(3.02);
	for (int r = 0; r < H; r++)
		for (int c = 0; c < W; c++)
			if ((r + c) % 2) img.at(r, c) = 0;
	ElevationGrid grid;
	EXPECT_EQ(proj.project(img.view(), camera(), T, ProjectionFilter{}, grid, out), size_t(W * H / 2));

	// A grid covering y in [0, 5) only: the columns c <= 31 (y > 0) stay.
	ElevationGrid half(makeGeometry(-5, 0, 0.05, 200, 100));
	const Image wall = wallDepthImage(3.02);
	out.clear();
	EXPECT_EQ(proj.project(wall.view(), camera(), T, ProjectionFilter{}, half, out), size_t(32 * H));
	// And one that ends before the wall: nothing.
	ElevationGrid shortGrid(makeGeometry(-5, -5, 0.05, 150, 200));  // x < 2.5
	out.clear();
	EXPECT_EQ(proj.project(wall.view(), camera(), T, ProjectionFilter{}, shortGrid, out), 0u);

	// A grid starting 1 cm beyond the wall: the points are 1 cm before its
	// first column (not truncated into column 0); starting 2 cm before it, all
	// land in column 0.
	ElevationGrid after(makeGeometry(3.03, -5, 0.05, 20, 200));
	out.clear();
	EXPECT_EQ(proj.project(wall.view(), camera(), T, ProjectionFilter{}, after, out), 0u);
	ElevationGrid beforeWall(makeGeometry(3.0, -5, 0.05, 20, 200));
	out.clear();
	EXPECT_EQ(proj.project(wall.view(), camera(), T, ProjectionFilter{}, beforeWall, out), size_t(W * H));
	for (uint32_t idx : out.cells()) EXPECT_EQ(idx % 20u, 0u);

	// Row padding (stride > cols) is never read, even if it holds values.
	Image padded(H, W, W + 5);
	for (int r = 0; r < H; r++)
		for (int c = 0; c < W + 5; c++) padded.at(r, c) = c < W ? 3020 : 1000;
	out.clear();
	EXPECT_EQ(proj.project(padded.view(), camera(), T, ProjectionFilter{}, grid, out), size_t(W * H));
	for (uint32_t idx : out.cells()) EXPECT_EQ(int(idx % 200u), 160);

	// project() appends.
	const size_t before = out.size();
	proj.project(padded.view(), camera(), T, ProjectionFilter{}, grid, out);
	EXPECT_EQ(out.size(), 2 * before);
}

TEST(DepthProjector, RejectsInconsistentInputs)
{
	const Image img = wallDepthImage(3.02);
	const RigidTransform T = pose(Eigen::Matrix3d::Identity(), {0, 0, 0.5});
	ElevationGrid grid;
	DepthProjector proj;
	BinnedPoints out;
	const ProjectionFilter f;

	// Image size vs intrinsics.
	PinholeIntrinsics K = camera();
	K.width = W + 1;
	EXPECT_THROW(proj.project(img.view(), K, T, f, grid, out), std::invalid_argument);
	K = camera();
	K.height = H - 1;
	EXPECT_THROW(proj.project(img.view(), K, T, f, grid, out), std::invalid_argument);
	K = camera();
	K.width = 0;
	EXPECT_THROW(proj.project(img.view(), K, T, f, grid, out), std::invalid_argument);

	// Focal lengths.
	for (double bad : {0.0, -50.0, double(NAN), double(INFINITY)})
	{
		K = camera();
		K.fx = bad;
		EXPECT_THROW(proj.project(img.view(), K, T, f, grid, out), std::invalid_argument) << bad;
		K = camera();
		K.fy = bad;
		EXPECT_THROW(proj.project(img.view(), K, T, f, grid, out), std::invalid_argument) << bad;
	}
	K = camera();
	K.cx = NAN;
	EXPECT_THROW(proj.project(img.view(), K, T, f, grid, out), std::invalid_argument);

	// rangeUnits.
	for (float units : {0.0f, -0.001f, float(NAN)})
		EXPECT_THROW(proj.project(img.view(true, units), camera(), T, f, grid, out), std::invalid_argument) << units;

	// Non-finite pose.
	RigidTransform bad = T;
	bad.t.x() = NAN;
	EXPECT_THROW(proj.project(img.view(), camera(), bad, f, grid, out), std::invalid_argument);
	bad = T;
	bad.R(1, 2) = INFINITY;
	EXPECT_THROW(proj.project(img.view(), camera(), bad, f, grid, out), std::invalid_argument);

	EXPECT_EQ(out.size(), 0u);  // nothing was binned by the failed calls
	EXPECT_NO_THROW(proj.project(img.view(), camera(), T, f, grid, out));
	EXPECT_EQ(out.size(), size_t(W * H));
}

TEST(DepthProjector, LensDistortionIsInvertedInTheRayTable)
{
	// Each ray (1, ky, kz) of the table is the undistorted normalized point
	// (xu, yu) = (-ky, -kz); distorting it with the Brown-Conrady model
	// (MRPT's TCamera::dist order k1, k2, p1, p2, k3) must give back the pixel.
	PinholeIntrinsics K = camera();
	K.k1 = 0.12;
	K.k2 = -0.05;
	K.p1 = 0.001;
	K.p2 = -0.002;
	K.k3 = 0.01;
	DepthProjector proj;
	ElevationGrid grid;
	BinnedPoints out;
	Image img;
	proj.project(img.view(), K, RigidTransform{}, ProjectionFilter{}, grid, out);
	ASSERT_EQ(proj.rayTableSize(), size_t(W * H));
	for (int r = 0; r < H; r += 7)
		for (int c = 0; c < W; c += 9)
		{
			const Eigen::Vector2f k = proj.rayFactor(r, c);
			const double xu = -k.x(), yu = -k.y();
			const double r2 = xu * xu + yu * yu;
			const double radial = 1 + K.k1 * r2 + K.k2 * r2 * r2 + K.k3 * r2 * r2 * r2;
			const double xd = xu * radial + 2 * K.p1 * xu * yu + K.p2 * (r2 + 2 * xu * xu);
			const double yd = yu * radial + K.p1 * (r2 + 2 * yu * yu) + 2 * K.p2 * xu * yu;
			EXPECT_NEAR(xd, (c - K.cx) / K.fx, 2e-6) << r << "," << c;
			EXPECT_NEAR(yd, (r - K.cy) / K.fy, 2e-6) << r << "," << c;
		}
	// Barrel distortion (k1 > 0): the corner ray is less oblique than the
	// distorted pixel position says.
	const Eigen::Vector2f corner = proj.rayFactor(0, 0);
	EXPECT_LT(std::abs(corner.x()), 31.5 / 50.0);
	EXPECT_LT(std::abs(corner.y()), 23.5 / 50.0);

	// The table follows the intrinsics: back to no distortion.
	proj.project(img.view(), camera(), RigidTransform{}, ProjectionFilter{}, grid, out);
	EXPECT_NEAR(proj.rayFactor(0, 0).x(), 31.5 / 50.0, 1e-6);
	EXPECT_NEAR(proj.rayFactor(0, 0).y(), 23.5 / 50.0, 1e-6);

	K = camera();
	K.k1 = NAN;
	EXPECT_THROW(proj.project(img.view(), K, RigidTransform{}, ProjectionFilter{}, grid, out), std::invalid_argument);
}

TEST(DepthProjector, Avx2AndBaselineRowLoopsAgreeBitForBit)
{
	if (!DepthProjector::avx2Available()) GTEST_SKIP() << "no AVX2 on this CPU or build";
	// Random depths (some 0, some beyond the range, odd widths that leave a
	// scalar tail), a pitched, rolled camera, range and depth images, distortion.
	const RandomScene scene = randomDistortedScene(7);
	const PinholeIntrinsics& K = scene.K;
	const Image& img = scene.img;
	const RigidTransform& T = scene.T;
	ProjectionFilter f;
	f.min_range = 0.4f;
	f.z_min = -1.f;
	f.z_max = 1.5f;
	ElevationGrid grid(makeGeometry(-2, -4, 0.05, 120, 160));
	for (bool isDepth : {true, false})
	{
		DepthProjector fast, base;
		base.setAllowAvx2(false);
		BinnedPoints a, b;
		const size_t na = fast.project(img.view(isDepth), K, T, f, grid, a);
		const size_t nb = base.project(img.view(isDepth), K, T, f, grid, b);
		ASSERT_EQ(na, nb);
		ASSERT_GT(na, 100u);
		ASSERT_LT(na, img.px.size());
		for (size_t i = 0; i < na; i++)
		{
			ASSERT_EQ(a.cells()[i], b.cells()[i]) << i;
			ASSERT_EQ(a.heights()[i], b.heights()[i]) << i;  // exact: no FMA in the AVX2 loop
		}
	}
}

namespace
{
/** One image row of depths in millimetres, in a 5-row image (the same row
 * repeated: no vertical edge), for the flying-pixel test along the row. */
Image rowImage(const std::vector<int>& mm)
{
	Image img(5, int(mm.size()), mm.size());
	for (int r = 0; r < 5; r++)
		for (size_t c = 0; c < mm.size(); c++) img.at(r, int(c)) = uint16_t(mm[c]);
	return img;
}

// rowImage() with rows 1 and 3 without a return: pixel (2, c) then has no
// neighbour above or below it (nor diagonally) to lean on.
Image loneRowImage(const std::vector<int>& mm)
{
	Image img = rowImage(mm);
	for (size_t c = 0; c < mm.size(); c++) img.at(1, int(c)) = img.at(3, int(c)) = 0;
	return img;
}
}  // namespace

TEST(DepthProjector, FlyingPixelsAreTheMixedPixelsOfAnEdge)
{
	const float tol = 50;  // mm: one 5 cm cell
	// A desk edge at 1.0 m in front of a wall at 2.0 m; pixel 5 is mixed
	// (1.5 m): between 1000 and 2000, 500 mm from each; the pixels on its left
	// predict 1 / (2/1000 - 1/1000) = 1000 and those on its right 2000, both
	// 500 > 50 mm from 1500: flying. The edge pixels 4 (1000 on the desk)
	// and 6 (2000 on the wall) each continue their own side: not flying.
	{
		const Image img = rowImage({1000, 1000, 1000, 1000, 1000, 1500, 2000, 2000, 2000, 2000, 2000});
		EXPECT_TRUE(DepthProjector::isFlyingPixel(img.view(), 2, 5, 1, tol));
		EXPECT_FALSE(DepthProjector::isFlyingPixel(img.view(), 2, 4, 1, tol));
		EXPECT_FALSE(DepthProjector::isFlyingPixel(img.view(), 2, 6, 1, tol));
	}
	// Both sides mixed: 1300 and 1320 are within 50 mm of each other and
	// between 1000 and 2000 as a pair: both flying.
	{
		const Image img = rowImage({1000, 1000, 1000, 1000, 1000, 1300, 1320, 2000, 2000, 2000, 2000, 2000});
		EXPECT_TRUE(DepthProjector::isFlyingPixel(img.view(), 2, 5, 1, tol));
		EXPECT_TRUE(DepthProjector::isFlyingPixel(img.view(), 2, 6, 1, tol));
	}
	// A thin object (a cable 1 pixel wide at 0.8 m) is nearer than both
	// neighbours, not between them: kept.
	{
		const Image img = rowImage({1000, 1000, 1000, 1000, 1000, 800, 1000, 1000, 1000, 1000, 1000});
		EXPECT_FALSE(DepthProjector::isFlyingPixel(img.view(), 2, 5, 1, tol));
	}
	// A surface seen at a grazing angle: on a plane the inverse depth is
	// affine in the pixel, here 1/d = (250 - 3 c) / 1e6 per mm, so d = 4000,
	// 4049, 4098, 4149, 4202, 4255, 4310, ... mm: steps of ~50-55 mm, each
	// pixel between its neighbours and more than 50 mm from the next, but
	// each side predicts it exactly: not flying.
	{
		std::vector<int> mm;
		for (int c = 0; c < 11; c++) mm.push_back(int(std::lround(1e6 / (250.0 - 3.0 * c))));
		const Image img = rowImage(mm);
		EXPECT_FALSE(DepthProjector::isFlyingPixel(img.view(), 2, 5, 1, tol));
	}
	// A neighbour without a return (0) predicts nothing and is no side:
	// 1500 next to a dropout is kept.
	{
		const Image img = rowImage({1000, 1000, 1000, 1000, 0, 1500, 2000, 2000, 2000, 2000, 2000});
		EXPECT_FALSE(DepthProjector::isFlyingPixel(img.view(), 2, 5, 1, tol));
	}
	// A door jamb at 2.0 m with the room behind it beyond the range (0): the
	// mixed pixel 3200 lies between the jamb and a background that returned
	// nothing. It is 1200 mm beyond the jamb, more than 50 mm and more than
	// 5 % of 3200 (160 mm); the jamb side predicts 1 / (2/2000 - 1/2000) =
	// 2000, 1200 mm from 3200; nothing past the gap returned. Above and below
	// it, other mixed pixels at random depths (3900, 2600 | 2700, 3800): not
	// between their neighbours in the column (2600 < 3200 > 2700), and none
	// of its 8 neighbours is within 50 mm: it stands alone, flying.
	{
		Image img = rowImage({2000, 2000, 2000, 2000, 2000, 3200, 0, 0, 0, 0, 0});
		const int column[5] = {3900, 2600, 3200, 2700, 3800};
		for (int r = 0; r < 5; r++) img.at(r, 5) = uint16_t(column[r]);
		EXPECT_TRUE(DepthProjector::isFlyingPixel(img.view(), 2, 5, 1, tol));
		EXPECT_FALSE(DepthProjector::isFlyingPixel(img.view(), 2, 4, 1, tol)) << "the jamb itself";
		// Two mixed pixels that happen to lie within 50 mm of each other: 3230
		// diagonally up and right of 3200, and nothing (0) two pixels off on
		// that diagonal. A pair at random depths, not a surface that goes on:
		// flying.
		img.at(1, 6) = 3230;
		EXPECT_TRUE(DepthProjector::isFlyingPixel(img.view(), 2, 5, 1, tol));
		img.at(1, 6) = 0;
		// The floor just past a step's edge looks the same along its column
		// (here the row): 4000 on the upper floor, then 4270 (a 5 cm step seen
		// from 0.8 m: 5/80 = 6.25 % farther, more than 5 % of 4270 = 213.5 mm),
		// then a dropout. But the lower floor goes on across the image: in the
		// other line 4265 is within 50 mm of it and 4255 within 50 mm of 4265
		// (and 4280, 4290 below). Kept.
		Image step = rowImage({4000, 4000, 4000, 4000, 4000, 4270, 0, 0, 0, 0, 0});
		const int floorColumn[5] = {4255, 4265, 4270, 4280, 4290};
		for (int r = 0; r < 5; r++) step.at(r, 5) = uint16_t(floorColumn[r]);
		EXPECT_FALSE(DepthProjector::isFlyingPixel(step.view(), 2, 5, 1, tol));
		// Without them (a dropout above and below), the floor going on
		// diagonally: 4300 and 4310 one pixel off (30 and 40 mm away), 4320 and
		// 4330 two pixels off on the same diagonals (20 mm from those). Kept.
		step.at(1, 5) = step.at(3, 5) = 0;
		step.at(1, 6) = 4300;
		step.at(3, 6) = 4310;
		step.at(0, 7) = 4320;
		step.at(4, 7) = 4330;
		EXPECT_FALSE(DepthProjector::isFlyingPixel(step.view(), 2, 5, 1, tol));
		// The diagonal neighbours alone, nothing two pixels off (a mixed
		// pixel's neighbours at random depths can come that near): flying.
		step.at(0, 7) = step.at(4, 7) = 0;
		EXPECT_TRUE(DepthProjector::isFlyingPixel(step.view(), 2, 5, 1, tol));
		// With no neighbour within 50 mm at all: flying.
		step.at(1, 6) = step.at(3, 6) = 0;
		EXPECT_TRUE(DepthProjector::isFlyingPixel(step.view(), 2, 5, 1, tol));
	}
	// In the rest, rows 1 and 3 returned nothing: the pixel stands alone.
	// A return just past the gap within 50 mm of 3200 (3210: a surface with
	// a dropout in it): kept.
	{
		const Image img = loneRowImage({2000, 2000, 2000, 2000, 2000, 3200, 0, 3210, 3205, 3200, 3195});
		EXPECT_FALSE(DepthProjector::isFlyingPixel(img.view(), 2, 5, 1, tol));
	}
	// The last floor pixel before the range ends, at a grazing angle: 1/d =
	// (250 - 3 c) / 1e6 per mm gives 4000, 4049, 4098, 4149, 4202, 4255
	// (c = 0..5), then nothing. Pixel 5 is 53 mm beyond pixel 4, but the two
	// pixels before it predict 1 / (2/4202 - 1/4149) = 4256 mm, 1 mm from
	// 4255: it continues the floor (and 53 < 5 % of 4255 = 213 mm), kept.
	{
		std::vector<int> mm;
		for (int c = 0; c < 6; c++) mm.push_back(int(std::lround(1e6 / (250.0 - 3.0 * c))));
		for (int c = 6; c < 11; c++) mm.push_back(0);
		const Image img = loneRowImage(mm);
		EXPECT_FALSE(DepthProjector::isFlyingPixel(img.view(), 2, 5, 1, tol));
		// The same pixel 250 mm farther, 4505: 249 mm from the prediction and
		// 303 mm beyond 4202, more than 5 % of 4505 (225 mm): flying.
		mm[5] = 4505;
		EXPECT_TRUE(DepthProjector::isFlyingPixel(loneRowImage(mm).view(), 2, 5, 1, tol));
	}
	// Far floor with noise next to a dropout: 4150, 4200, then 4330. The near
	// side predicts 1 / (2/4200 - 1/4150) = 4251 mm, 79 mm from 4330, so it
	// does not continue within 50 mm; but the jump, 130 mm, is less than 5 %
	// of 4330 = 216.5 mm: what noise makes between two pixels of one surface
	// at that range, kept.
	{
		const Image img = loneRowImage({4000, 4050, 4100, 4150, 4200, 4330, 0, 0, 0, 0, 0});
		EXPECT_FALSE(DepthProjector::isFlyingPixel(img.view(), 2, 5, 1, tol));
		// 4450 instead: 199 mm from 4251 and a 250 mm jump, more than 5 % of
		// 4450 (222.5 mm): flying.
		const Image far = loneRowImage({4000, 4050, 4100, 4150, 4200, 4450, 0, 0, 0, 0, 0});
		EXPECT_TRUE(DepthProjector::isFlyingPixel(far.view(), 2, 5, 1, tol));
	}
}

/** Image `img` seen by a camera at the origin looking along +X (every pixel
 * with a return in range and on the grid): project() with the flying-pixel
 * filter keeps exactly the samples of the pixels isFlyingPixel() does not
 * flag, sample by sample in pixel order, with and without AVX2. Returns the
 * flagged pixels (row, column). */
std::vector<std::pair<int, int>> expectFilterKeepsTheUnflaggedPixels(const Image& img)
{
	const ElevationGrid grid(makeGeometry(-5, -5, 0.05, 200, 200));
	const RigidTransform T = pose(Eigen::Matrix3d::Identity(), Eigen::Vector3d::Zero());
	const float tol = float(0.05 / double(0.001f));  // one cell, in image units (as project())
	ProjectionFilter keepAll, dropFlying;
	keepAll.drop_flying_pixels = false;
	keepAll.max_range = dropFlying.max_range = 10;
	BinnedPoints all;
	DepthProjector().project(img.view(), camera(), T, keepAll, grid, all);
	std::vector<std::pair<int, int>> flagged;
	std::vector<uint32_t> expectCell;
	std::vector<float> expectZ;
	size_t sample = 0;
	for (int r = 0; r < img.rows; r++)
		for (int c = 0; c < img.cols; c++)
		{
			if (img.px[size_t(r) * img.stride + size_t(c)] == 0) continue;
			if (DepthProjector::isFlyingPixel(img.view(), r, c, 1, tol))
				flagged.emplace_back(r, c);
			else if (sample < all.size())
			{
				expectCell.push_back(all.cells()[sample]);
				expectZ.push_back(all.heights()[sample]);
			}
			sample++;
		}
	EXPECT_EQ(all.size(), sample) << "every pixel with a return must be in range and on the grid";
	for (const bool avx2 : {true, false})
	{
		SCOPED_TRACE(avx2 ? "AVX2 (where the CPU has it)" : "baseline");
		DepthProjector proj;
		proj.setAllowAvx2(avx2);
		BinnedPoints kept;
		proj.project(img.view(), camera(), T, dropFlying, grid, kept);
		EXPECT_EQ(kept.size(), expectCell.size());
		for (size_t i = 0; i < std::min(kept.size(), expectCell.size()); i++)
		{
			EXPECT_EQ(kept.cells()[i], expectCell[i]) << "sample " << i;
			EXPECT_EQ(kept.heights()[i], expectZ[i]) << "sample " << i;
			if (kept.cells()[i] != expectCell[i] || kept.heights()[i] != expectZ[i]) break;
		}
	}
	return flagged;
}

namespace
{
// A pixel on the outline (`edge`) of a box face at 1.5 m in front of a
// background `behind` mm away mixes the two with chance `mixChance`, at a
// depth 15-85 % of the way back (as the simulator's flying pixels do);
// otherwise it keeps its own depth `own`.
double mixedOutlineDepth(double own, bool edge, double behind, double mixChance, std::mt19937& rng)
{
	std::uniform_real_distribution<double> u(0, 1);
	return edge && u(rng) < mixChance ? 1500 + (0.15 + 0.7 * u(rng)) * (behind - 1500) : own;
}

// A wall at 3 m with a box face at 1.5 m in front of it (rows r0 to r1 - 1,
// columns 20-43), the box's outline mixed at random (chance 0.6), 3 mm of
// noise. With `nothingRight`, right of the box in the image's upper half the
// background is beyond the range (no return, 0) and the outline there mixes
// with 6 m.
Image boxInFrontOfWall(int r0, int r1, unsigned seed, bool nothingRight)
{
	Image img;
	std::mt19937 rng(seed);
	std::normal_distribution<double> noise(0, 3);
	for (int r = 0; r < H; r++)
		for (int c = 0; c < W; c++)
		{
			const bool box = r >= r0 && r < r1 && c >= 20 && c < 44;
			const bool edge = box && (r == r0 || r == r1 - 1 || c == 20 || c == 43);
			const bool nothing = nothingRight && !box && c >= 44 && r < H / 2;
			const double behind = nothing ? 6000 : 3000;
			const double mm = mixedOutlineDepth(box ? 1500 : behind, edge, behind, 0.6, rng);
			img.at(r, c) = nothing ? 0 : uint16_t(std::lround(mm + noise(rng)));
		}
	return img;
}
}  // namespace

TEST(DepthProjector, FlyingPixelFilterDropsExactlyTheFlyingPixels)
{
	// A wall at 3 m with a box face at 1.5 m in front of it, random mixed
	// pixels on the box's outline and noise: project() with the filter keeps
	// the pixels its own projection keeps minus those isFlyingPixel() flags
	// (on this image the fast first pass loses none; where it does, see
	// FirstPassKeepsThePairedPixelThatOneSideContinues). Right of the box,
	// in its upper half, the background is beyond the range.
	Image img = boxInFrontOfWall(12, 36, 7, true);
	img.at(5, 5) = 0;  // a dropout
	EXPECT_GT(expectFilterKeepsTheUnflaggedPixels(img).size(), 20u) << "the outline's mixed pixels";
}

TEST(DepthProjector, FlyingPixelFilterAtTheImageEdgeIsTheSameTest)
{
	// Mixed pixels on the image's outermost rows and columns, where a pixel's
	// lines run off the image (0 there, as for no return): the filter in
	// project() drops exactly the pixels isFlyingPixel() flags there too.
	Image img;
	std::mt19937 rng(11);
	std::normal_distribution<double> noise(0, 3);
	for (int r = 0; r < H; r++)
		for (int c = 0; c < W; c++)
		{
			// A box face at 1.5 m covering the top-left corner (rows < 20,
			// columns < 30) in front of a wall at 3 m; its outline and the
			// image's border rows and columns mix the two at random.
			const bool box = r < 20 && c < 30;
			const bool edge = (box && (r == 19 || c == 29)) || r < 3 || c < 3 || r >= H - 3 || c >= W - 3;
			const double mm = mixedOutlineDepth(box ? 1500 : 3000, edge, 3000, 0.3, rng);
			img.at(r, c) = uint16_t(std::lround(mm + noise(rng)));
		}
	// Dropouts next to the border (a pixel beside one can be flying
	// against nothing).
	for (int r : {1, H - 2}) img.at(r, 10) = 0;
	for (int c : {1, W - 2}) img.at(24, c) = 0;
	size_t atBorder = 0;
	for (const auto& [r, c] : expectFilterKeepsTheUnflaggedPixels(img))
		atBorder += r < 3 || c < 3 || r >= H - 3 || c >= W - 3;
	EXPECT_GT(atBorder, 10u) << "the test must flag pixels within 3 of the edge";
}

TEST(DepthProjector, FirstPassKeepsThePairedPixelThatOneSideContinues)
{
	// What project() drops is the vector first pass, then isFlyingPixel() on
	// its candidates; the first pass keeps a pixel that one side continues in
	// depth, linearly (|2 p1 - p2 - x| <= h = floor(tol / 2)), and so keeps
	// the second pixel of a pair that the full rule flags as flying (found
	// on simulated Femto frames: 5-13 pixels a frame). A column of a noisy
	// slant with dropouts, the same in every image column (rows 20-26):
	//   0, 3839, 3788, 3760, 3696, 0, 3675 mm, every other row 0.
	// tol = d_r / units = 0.05 / 0.001f = 49.999998 mm: t = 49, h = 24.
	// Row 22 (3788) and row 23 (3760) are a pair by the full rule: within
	// tol of each other (28), both strictly between 3839 and 3696 by more
	// than tol (51 and 92; 79 and 64), continued by neither side (the pixels
	// beyond them, rows 20 and 25, returned nothing).
	// The first pass: row 23 is continued from above, |2*3788 - 3839 - 3760|
	// = 23 <= 24: kept without the full test. Row 22: |2*3760 - 3696 - 3788|
	// = 36 > 24 from below, nothing two rows above, a jump of 51 > 49 up:
	// a candidate, then flagged. The two pixels at each end of a row are
	// always candidates (their row line runs off the image): flagged.
	Image img;
	const uint16_t column[7] = {0, 3839, 3788, 3760, 3696, 0, 3675};
	for (int r = 20; r <= 26; r++)
		for (int c = 0; c < W; c++) img.at(r, c) = column[r - 20];
	const ElevationGrid grid(makeGeometry(-5, -5, 0.05, 200, 200));
	const float tol = float(0.05 / double(0.001f));
	for (int c = 0; c < W; c++)
	{
		EXPECT_TRUE(DepthProjector::isFlyingPixel(img.view(), 22, c, 1, tol)) << c;
		EXPECT_TRUE(DepthProjector::isFlyingPixel(img.view(), 23, c, 1, tol)) << c;
		for (int r : {21, 24, 26})
			EXPECT_FALSE(DepthProjector::isFlyingPixel(img.view(), r, c, 1, tol)) << r << "," << c;
	}
	const RigidTransform T = pose(Eigen::Matrix3d::Identity(), Eigen::Vector3d::Zero());
	ProjectionFilter keepAll, dropFlying;
	keepAll.drop_flying_pixels = false;
	BinnedPoints all;
	DepthProjector().project(img.view(), camera(), T, keepAll, grid, all);
	ASSERT_EQ(all.size(), size_t(5 * W));  // rows 21, 22, 23, 24, 26 in order
	for (const bool avx2 : {true, false})
	{
		SCOPED_TRACE(avx2 ? "AVX2 (where the CPU has it)" : "baseline");
		DepthProjector proj;
		proj.setAllowAvx2(avx2);
		BinnedPoints kept;
		proj.project(img.view(), camera(), T, dropFlying, grid, kept);
		// Row 21, row 23 without its two pixels at each end, rows 24 and 26.
		ASSERT_EQ(kept.size(), size_t(4 * W - 4));
		for (int c = 2; c < W - 2; c++)
		{
			const size_t k = size_t(W + c - 2), a = size_t(2 * W + c);
			EXPECT_EQ(kept.cells()[k], all.cells()[a]) << c;
			EXPECT_EQ(kept.heights()[k], all.heights()[a]) << c;
		}
	}
}

TEST(DepthProjector, DecimatedFlyingFilterIsTheFullFilterOnTheDecimatedFrame)
{
	// With decimation 2, a 128x96 frame is its every other row and column: a
	// 64x48 frame with fx, fy, cx, cy halved. fx = 100, cx = 63 here, and
	// camera() has fx = 50, cx = 31.5: pixel 2k of the large camera has
	// (2k - 63) / 100, pixel k of the small one (k - 31.5) / 50, the same
	// real number, so the same double and the same rays bit for bit. The
	// filter on the decimated frame must then drop exactly what it drops on
	// the small frame, sample by sample; the odd rows and columns (random
	// junk here) must play no part.
	// The small frame: a box in front of a wall (rows 8-23, its outline
	// mixed), and in rows 38-44 of every column the pair of
	// FirstPassKeepsThePairedPixelThatOneSideContinues (0, 3839, 3788, 3760,
	// 3696, 0, 3675): the full rule flags rows 40 and 41; the filter keeps
	// row 41, which the side below continues (|2*3788 - 3839 - 3760| = 23
	// <= 24). Reading the decimated frame pixel by pixel with neighbours 2
	// apart (isFlyingPixel(step 2), what project() did before) drops it.
	Image small = boxInFrontOfWall(8, 24, 5, false);
	const uint16_t column[7] = {0, 3839, 3788, 3760, 3696, 0, 3675};
	for (int r = 38; r <= 44; r++)
		for (int c = 0; c < W; c++) small.at(r, c) = column[r - 38];
	Image large(2 * H, 2 * W, 2 * W);
	std::mt19937 rng(5);
	std::uniform_int_distribution<int> junk(0, 6000);
	for (int r = 0; r < 2 * H; r++)
		for (int c = 0; c < 2 * W; c++)
			large.at(r, c) = r % 2 == 0 && c % 2 == 0 ? small.at(r / 2, c / 2) : uint16_t(junk(rng));
	PinholeIntrinsics Klarge = camera();
	Klarge.width = 2 * W;
	Klarge.height = 2 * H;
	Klarge.fx = Klarge.fy = 100;
	Klarge.cx = 63;
	Klarge.cy = 47;

	const ElevationGrid grid(makeGeometry(-5, -5, 0.05, 200, 200));
	const RigidTransform T = pose(pitchDown(10), {0, 0, 1.0});
	ProjectionFilter f;
	f.max_range = 10;
	BinnedPoints all;
	f.drop_flying_pixels = false;
	DepthProjector().project(small.view(), camera(), T, f, grid, all);
	f.drop_flying_pixels = true;
	for (const bool avx2 : {true, false})
	{
		SCOPED_TRACE(avx2 ? "AVX2 (where the CPU has it)" : "baseline");
		DepthProjector onSmall, decimated;
		onSmall.setAllowAvx2(avx2);
		decimated.setAllowAvx2(avx2);
		BinnedPoints a, b;
		f.decimation = 1;
		onSmall.project(small.view(), camera(), T, f, grid, a);
		f.decimation = 2;
		decimated.project(large.view(), Klarge, T, f, grid, b);
		ASSERT_GT(all.size(), a.size() + 20) << "the filter must drop the outline's mixed pixels";
		ASSERT_EQ(a.size(), b.size());
		for (size_t i = 0; i < a.size(); i++)
		{
			ASSERT_EQ(a.cells()[i], b.cells()[i]) << i;
			ASSERT_EQ(a.heights()[i], b.heights()[i]) << i;
		}
	}
	const float tol = float(0.05 / double(0.001f));
	for (int c = 0; c < W; c++) EXPECT_TRUE(DepthProjector::isFlyingPixel(large.view(), 2 * 41, 2 * c, 2, tol)) << c;
}
