#include "gam/DepthProjector.h"

#include <cmath>
#include <stdexcept>
#include <string>

namespace gam
{
void PinholeIntrinsics::validate() const
{
	if (width <= 0 || height <= 0)
		throw std::invalid_argument(
			"camera size must be positive (got " + std::to_string(width) + "x" +
			std::to_string(height) + ")");
	if (!(fx > 0) || !(fy > 0) || !std::isfinite(fx) || !std::isfinite(fy))
		throw std::invalid_argument(
			"camera focal lengths must be > 0 (got fx=" + std::to_string(fx) +
			", fy=" + std::to_string(fy) + ")");
	if (!std::isfinite(cx) || !std::isfinite(cy))
		throw std::invalid_argument("camera principal point must be finite");
	if (!std::isfinite(k1) || !std::isfinite(k2) || !std::isfinite(k3) || !std::isfinite(p1) ||
		!std::isfinite(p2))
		throw std::invalid_argument("camera distortion coefficients must be finite");
}

void DepthProjector::updateLut(const PinholeIntrinsics& K)
{
	if (K == m_lutK && !m_lut.empty()) return;
	m_lutK = K;
	m_lut.resize(size_t(K.width) * size_t(K.height));
	m_lutNorm.resize(m_lut.size());
	for (int r = 0; r < K.height; r++)
		for (int c = 0; c < K.width; c++)
		{
			// MRPT's convention (CObservation3DRangeScan::unprojectInto):
			// x = D, y = (cx - c) * D / fx, z = (cy - r) * D / fy, with (c, r)
			// first undistorted. Normalized image coordinates (right, down):
			const double xd = (c - K.cx) / K.fx, yd = (r - K.cy) / K.fy;
			double xu = xd, yu = yd;
			if (K.k1 != 0 || K.k2 != 0 || K.k3 != 0 || K.p1 != 0 || K.p2 != 0)
			{
				// Invert the distortion by fixed-point iteration (converges in a
				// few steps for the mild distortion of depth cameras).
				for (int it = 0; it < 20; it++)
				{
					const double r2 = xu * xu + yu * yu;
					const double radial = 1 + r2 * (K.k1 + r2 * (K.k2 + r2 * K.k3));
					const double dx = 2 * K.p1 * xu * yu + K.p2 * (r2 + 2 * xu * xu);
					const double dy = K.p1 * (r2 + 2 * yu * yu) + 2 * K.p2 * xu * yu;
					const double nx = (xd - dx) / radial, ny = (yd - dy) / radial;
					const bool done = std::abs(nx - xu) + std::abs(ny - yu) < 1e-12;
					xu = nx;
					yu = ny;
					if (done) break;
				}
			}
			const float ky = float(-xu), kz = float(-yu);
			const size_t i = size_t(r) * size_t(K.width) + size_t(c);
			m_lut[i] = {ky, kz};
			m_lutNorm[i] = std::sqrt(1.0f + ky * ky + kz * kz);
		}
}

size_t DepthProjector::project(
	const RangeImageView& img, const PinholeIntrinsics& K, const RigidTransform& T,
	const ProjectionFilter& f, const ElevationGrid& grid, BinnedPoints& out)
{
	K.validate();
	if (!img.data || img.rows <= 0 || img.cols <= 0) return 0;
	if (img.rows != K.height || img.cols != K.width)
		throw std::invalid_argument(
			"range image is " + std::to_string(img.cols) + "x" + std::to_string(img.rows) +
			" but the camera parameters say " + std::to_string(K.width) + "x" +
			std::to_string(K.height));
	if (!(img.units > 0) || !std::isfinite(img.units))
		throw std::invalid_argument(
			"rangeUnits must be > 0 (got " + std::to_string(img.units) + ")");
	if (!T.R.allFinite() || !T.t.allFinite())
		throw std::invalid_argument("sensor pose is not finite");
	updateLut(K);

	const int dec = std::max(1, f.decimation);
	const GridGeometry& g = grid.geometry();
	const float inv_res = float(1.0 / g.resolution);
	// Grid coordinates relative to the grid origin, to keep floats precise.
	const Eigen::Vector3f t0 = T.t - Eigen::Vector3f(float(g.x_min), float(g.y_min), 0.f);
	const Eigen::Matrix3f& R = T.R;
	const float minR = std::max(0.0f, f.min_range), maxR = f.max_range;
	const bool isDepth = img.is_depth;
	size_t binned = 0;

	for (int r = 0; r < img.rows; r += dec)
	{
		const uint16_t* row = img.data + size_t(r) * img.stride;
		const Eigen::Vector2f* lut = m_lut.data() + size_t(r) * size_t(K.width);
		const float* lutN = m_lutNorm.data() + size_t(r) * size_t(K.width);
		for (int c = 0; c < img.cols; c += dec)
		{
			const uint16_t raw = row[c];
			if (!raw) continue;
			const float v = float(raw) * img.units;
			if (v < minR || v > maxR) continue;
			const float D = isDepth ? v : v / lutN[c];
			// Sensor-frame point (D, D*ky, D*kz) mapped to the grid frame.
			const float sy = D * lut[c].x(), sz = D * lut[c].y();
			const float gx = R(0, 0) * D + R(0, 1) * sy + R(0, 2) * sz + t0.x();
			const float gy = R(1, 0) * D + R(1, 1) * sy + R(1, 2) * sz + t0.y();
			const float gz = R(2, 0) * D + R(2, 1) * sy + R(2, 2) * sz + t0.z();
			if (gz < f.z_min || gz > f.z_max) continue;
			const float fx_ = gx * inv_res, fy_ = gy * inv_res;
			if (!(fx_ >= 0.f) || !(fy_ >= 0.f)) continue;	// also rejects NaN
			// Compare as floats first: int() of a value beyond the int range is UB.
			if (fx_ >= float(g.nx) || fy_ >= float(g.ny)) continue;
			const int cx = int(fx_), cy = int(fy_);
			if (cx >= g.nx || cy >= g.ny) continue;
			out.push(uint32_t(cy) * uint32_t(g.nx) + uint32_t(cx), gz);
			binned++;
		}
	}
	return binned;
}

}  // namespace gam
