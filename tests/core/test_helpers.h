// Ground-aware mapping for MRPT
// Small helpers shared by the ground_core unit tests (synthetic scenes).
#pragma once

#include <array>
#include <cmath>
#include <functional>
#include <random>
#include <vector>

#include <Eigen/Geometry>

#include "gam/core/ElevationGrid.h"
#include "gam/core/SensorFrame.h"

namespace gamtest
{
inline constexpr double kPi = 3.14159265358979323846;
inline double deg2rad(double d) { return d * kPi / 180.0; }
inline double rad2deg(double r) { return r * 180.0 / kPi; }

/** A depth image (mm, 0 = no return) of a camera at `camPos` with rotation `R`
 * (sensor -> map, MRPT's sensor frame) and intrinsics K: `depthAlongX(w)`
 * gives, for the unit-less pixel ray w (map frame, its sensor x = 1), the depth
 * along the sensor's X, or a value <= 0 for no return. */
inline std::vector<uint16_t> renderDepth(
	const gam::PinholeIntrinsics& K, const Eigen::Matrix3d& R,
	const std::function<double(const Eigen::Vector3d& w)>& depthAlongX)
{
	std::vector<uint16_t> depth(size_t(K.width * K.height), 0);
	for (int r = 0; r < K.height; r++)
		for (int c = 0; c < K.width; c++)
		{
			const double t = depthAlongX(R * Eigen::Vector3d(1.0, (K.cx - c) / K.fx, (K.cy - r) / K.fy));
			if (t > 0 && std::isfinite(t)) depth[size_t(r * K.width + c)] = uint16_t(std::lround(t * 1000));
		}
	return depth;
}

/** The small camera of the pipeline tests: 160 x 120 pixels, fx = fy = 120
 * (67 x 53 deg), principal point at the image centre. */
inline gam::PinholeIntrinsics smallCamera()
{
	gam::PinholeIntrinsics K;
	K.width = 160;
	K.height = 120;
	K.fx = K.fy = 120;
	K.cx = 79.5;
	K.cy = 59.5;
	return K;
}

/** The SensorFrame of such an image (it must outlive the frame). */
inline gam::SensorFrame depthFrame(
	const std::vector<uint16_t>& depth, const gam::PinholeIntrinsics& K, const Eigen::Matrix3d& R,
	const Eigen::Vector3d& camPos)
{
	gam::SensorFrame frame;
	frame.has_image = true;
	frame.image.data = depth.data();
	frame.image.rows = K.height;
	frame.image.cols = K.width;
	frame.image.stride = size_t(K.width);
	frame.intrinsics = K;
	frame.sensor_to_map.R = R.cast<float>();
	frame.sensor_to_map.t = camPos.cast<float>();
	frame.sensor_position = camPos;
	return frame;
}

inline gam::GridGeometry makeGeometry(double x_min, double y_min, double res, int nx, int ny)
{
	gam::GridGeometry g;
	g.x_min = x_min;
	g.y_min = y_min;
	g.resolution = res;
	g.nx = nx;
	g.ny = ny;
	return g;
}

/** Inserts the points (x, y, z) into the grid, one frame, no outlier filter. */
inline void insertPoints(gam::ElevationGrid& grid, const std::vector<std::array<double, 3>>& pts)
{
	gam::BinnedPoints b;
	for (const auto& p : pts) grid.binPoint(p[0], p[1], float(p[2]), b);
	gam::OutlierFilterParams f;
	f.enabled = false;
	grid.insert(b, f);
}

/** Samples every cell whose centre lies in [x0, x1) x [y0, y1) with `n`
 * points spread over the cell (a regular sub-grid), heights z(x, y) plus
 * N(0, noise) noise. Returns the binned points (not inserted). */
inline void sampleSurface(
	const gam::ElevationGrid& grid, double x0, double x1, double y0, double y1,
	const std::function<double(double, double)>& z, int nPerAxis, double noise, std::mt19937& rng,
	gam::BinnedPoints& out)
{
	const gam::GridGeometry& g = grid.geometry();
	std::normal_distribution<double> N(0.0, noise > 0 ? noise : 1.0);
	for (int cy = 0; cy < g.ny; cy++)
		for (int cx = 0; cx < g.nx; cx++)
		{
			const double xc = g.cx(cx), yc = g.cy(cy);
			if (xc < x0 || xc >= x1 || yc < y0 || yc >= y1) continue;
			for (int j = 0; j < nPerAxis; j++)
				for (int i = 0; i < nPerAxis; i++)
				{
					const double x = g.x_min + (cx + (i + 0.5) / nPerAxis) * g.resolution;
					const double y = g.y_min + (cy + (j + 0.5) / nPerAxis) * g.resolution;
					const double zz = z(x, y) + (noise > 0 ? N(rng) : 0.0);
					grid.binPoint(x, y, float(zz), out);
				}
		}
}

/** Like sampleSurface, restricted to the cells whose centre passes `keep`. */
inline void sampleSurfaceIf(
	const gam::ElevationGrid& grid, const std::function<bool(double, double)>& keep,
	const std::function<double(double, double)>& z, int nPerAxis, double noise, std::mt19937& rng,
	gam::BinnedPoints& out)
{
	const gam::GridGeometry& g = grid.geometry();
	std::normal_distribution<double> N(0.0, noise > 0 ? noise : 1.0);
	for (int cy = 0; cy < g.ny; cy++)
		for (int cx = 0; cx < g.nx; cx++)
		{
			if (!keep(g.cx(cx), g.cy(cy))) continue;
			for (int j = 0; j < nPerAxis; j++)
				for (int i = 0; i < nPerAxis; i++)
				{
					const double x = g.x_min + (cx + (i + 0.5) / nPerAxis) * g.resolution;
					const double y = g.y_min + (cy + (j + 0.5) / nPerAxis) * g.resolution;
					grid.binPoint(x, y, float(z(x, y) + (noise > 0 ? N(rng) : 0.0)), out);
				}
		}
}

inline bool inRect(double x, double y, double x0, double x1, double y0, double y1)
{
	return x >= x0 && x < x1 && y >= y0 && y < y1;
}

/** Scene 1 (grid -5..5 m, 5 cm): floor z = 0 on [-3, 3)^2, a wall of
 * columns 0..2 m on x in [2.5, 2.6), nothing behind it, and a 0.5 x 0.5 m
 * box with its top at 0.4 m on [1.0, 1.5) x [0.5, 1.0). */
struct FloorWallBox
{
	static bool isWall(double x, double y) { return inRect(x, y, 2.5, 2.6, -3, 3); }
	static bool isBox(double x, double y) { return inRect(x, y, 1.0, 1.5, 0.5, 1.0); }
	static bool isFloor(double x, double y) { return inRect(x, y, -3, 2.5, -3, 3) && !isBox(x, y); }
};

/** Samples vertical columns (walls, box sides): every cell centre in the
 * rectangle gets points at heights z0, z0+dz, ..., z1. */
inline void sampleColumns(
	const gam::ElevationGrid& grid, double x0, double x1, double y0, double y1, double z0, double z1, double dz,
	gam::BinnedPoints& out)
{
	const gam::GridGeometry& g = grid.geometry();
	for (int cy = 0; cy < g.ny; cy++)
		for (int cx = 0; cx < g.nx; cx++)
		{
			const double xc = g.cx(cx), yc = g.cy(cy);
			if (xc < x0 || xc >= x1 || yc < y0 || yc >= y1) continue;
			for (double zz = z0; zz <= z1 + 1e-9; zz += dz) grid.binPoint(xc, yc, float(zz), out);
		}
}

inline void insertAll(gam::ElevationGrid& grid, const gam::BinnedPoints& b)
{
	gam::OutlierFilterParams f;
	f.enabled = false;
	grid.insert(b, f);
}

inline void buildFloorWallBox(gam::ElevationGrid& grid, std::mt19937& rng)
{
	gam::BinnedPoints b;
	sampleSurfaceIf(
		grid, FloorWallBox::isFloor, [](double, double) { return 0.0; }, 3, 0.003, rng, b);
	sampleSurfaceIf(
		grid, FloorWallBox::isBox, [](double, double) { return 0.4; }, 3, 0.003, rng, b);
	sampleColumns(grid, 2.5, 2.6, -3, 3, 0.0, 2.0, 0.05, b);
	insertAll(grid, b);
}

/** Scene 2: floor z = 0 for x in [-4, 1), then a 6 deg ramp up to x = 3,
 * y in [-3, 3). */
inline double rampHeight(double x, double deg = 6.0) { return x < 1.0 ? 0.0 : std::tan(deg2rad(deg)) * (x - 1.0); }
inline void buildRamp(gam::ElevationGrid& grid, std::mt19937& rng)
{
	gam::BinnedPoints b;
	sampleSurfaceIf(
		grid, [](double x, double y) { return inRect(x, y, -4, 3, -3, 3); },
		[](double x, double) { return rampHeight(x); }, 3, 0.003, rng, b);
	insertAll(grid, b);
}

}  // namespace gamtest
