// Test helper: exact depth frames of scenes made of axis-aligned boxes.
// The floor is built from slabs, so a hole is simply where no slab is.
#pragma once

#include <mrpt/math/TPoint3D.h>
#include <mrpt/obs/CObservation3DRangeScan.h>
#include <mrpt/poses/CPose3D.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace testscene
{
struct Box
{
	double x0, y0, z0, x1, y1, z1;
};

/** Distance along the ray to the nearest box, or +inf. */
inline double castRay(const std::vector<Box>& boxes, const mrpt::math::TPoint3D& o, const mrpt::math::TPoint3D& d)
{
	double best = std::numeric_limits<double>::infinity();
	for (const Box& b : boxes)
	{
		double tmin = 0, tmax = best;
		const double lo[3] = {b.x0, b.y0, b.z0}, hi[3] = {b.x1, b.y1, b.z1};
		const double oo[3] = {o.x, o.y, o.z}, dd[3] = {d.x, d.y, d.z};
		bool hit = true;
		for (int k = 0; k < 3 && hit; k++)
		{
			if (std::abs(dd[k]) < 1e-12)
			{
				if (oo[k] < lo[k] || oo[k] > hi[k]) hit = false;
				continue;
			}
			double t0 = (lo[k] - oo[k]) / dd[k], t1 = (hi[k] - oo[k]) / dd[k];
			if (t0 > t1) std::swap(t0, t1);
			tmin = std::max(tmin, t0);
			tmax = std::min(tmax, t1);
			if (tmin > tmax) hit = false;
		}
		if (hit && tmin < best) best = tmin;
	}
	return best;
}

/** A solid floor (top at z = 0) over [x0,x1]x[y0,y1] with an optional
 * rectangular pit of the given depth: the pit has walls and a bottom. */
inline std::vector<Box> floorWithHole(
	double x0, double x1, double y0, double y1, double hx0 = 0, double hx1 = 0, double hy0 = 0, double hy1 = 0,
	double holeDepth = 0.5)
{
	const double zb = -holeDepth - 0.1;
	if (hx1 <= hx0) return {{x0, y0, zb, x1, y1, 0.0}};
	return {
		{x0, y0, zb, hx0, y1, 0.0},
		{hx1, y0, zb, x1, y1, 0.0},
		{hx0, y0, zb, hx1, hy0, 0.0},
		{hx0, hy1, zb, hx1, y1, 0.0},
		{hx0, hy0, -holeDepth - 0.1, hx1, hy1, -holeDepth}};
}

/** A Kinect-One-like depth frame (W x H, ~70x60 deg) of `boxes`, taken by a
 * sensor at `sensorPose` on a robot at `robotPose`. Depth along +X, mm. */
inline mrpt::obs::CObservation3DRangeScan::Ptr renderDepth(
	const std::vector<Box>& boxes, const mrpt::poses::CPose3D& sensorPose, const mrpt::poses::CPose3D& robotPose = {},
	int W = 256, int H = 212, double maxRange = 4.5)
{
	auto o = mrpt::obs::CObservation3DRangeScan::Create();
	o->sensorLabel = "KINECT";
	o->hasRangeImage = true;
	o->range_is_depth = true;
	o->rangeUnits = 0.001f;
	o->maxRange = float(maxRange);
	o->sensorPose = sensorPose;
	const double fx = W / (2 * std::tan(70.6 / 2 * M_PI / 180)), fy = H / (2 * std::tan(60.0 / 2 * M_PI / 180));
	o->cameraParams.ncols = W;
	o->cameraParams.nrows = H;
	o->cameraParams.setIntrinsicParamsFromValues(fx, fy, (W - 1) / 2.0, (H - 1) / 2.0);
	o->cameraParamsIntensity = o->cameraParams;
	o->rangeImage_setSize(H, W);
	const mrpt::poses::CPose3D P = robotPose + sensorPose;
	const auto R = P.getRotationMatrix();
	const mrpt::math::TPoint3D org(P.x(), P.y(), P.z());
	for (int r = 0; r < H; r++)
		for (int c = 0; c < W; c++)
		{
			const double ky = ((W - 1) / 2.0 - c) / fx, kz = ((H - 1) / 2.0 - r) / fy;
			const mrpt::math::TPoint3D ds(
				R(0, 0) + R(0, 1) * ky + R(0, 2) * kz, R(1, 0) + R(1, 1) * ky + R(1, 2) * kz,
				R(2, 0) + R(2, 1) * ky + R(2, 2) * kz);
			const double t = castRay(boxes, org, ds);  // ds has unit x-component in the sensor frame
			o->rangeImage(r, c) = (std::isfinite(t) && t <= maxRange) ? uint16_t(std::lround(t * 1000.0)) : 0;
		}
	return o;
}

/** The pixels of `o` (taken by a robot at the origin) whose ray meets the
 * floor level z = 0 inside [x0,x1]x[y0,y1] return nothing: a black mat on
 * the floor, or the opening of a pit whose walls and bottom absorb the light. */
inline void blackOut(mrpt::obs::CObservation3DRangeScan& o, double x0, double x1, double y0, double y1)
{
	const mrpt::poses::CPose3D P = o.sensorPose;
	const auto R = P.getRotationMatrix();
	const auto& K = o.cameraParams;
	for (int r = 0; r < int(o.rangeImage.rows()); r++)
		for (int c = 0; c < int(o.rangeImage.cols()); c++)
		{
			const double ky = (K.cx() - c) / K.fx(), kz = (K.cy() - r) / K.fy();
			const double dz = R(2, 0) + R(2, 1) * ky + R(2, 2) * kz;
			if (dz >= 0) continue;
			const double t = -P.z() / dz;  // depth at which the ray meets z = 0
			const double x = P.x() + t * (R(0, 0) + R(0, 1) * ky + R(0, 2) * kz);
			const double y = P.y() + t * (R(1, 0) + R(1, 1) * ky + R(1, 2) * kz);
			if (x >= x0 && x <= x1 && y >= y0 && y <= y1) o.rangeImage(r, c) = 0;
		}
}

}  // namespace testscene
