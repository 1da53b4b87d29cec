// Ground-aware mapping for MRPT -- scene simulator: Kinect One and Leddar IS16 models.
#include "gam/sim/Sensors.h"

#include <algorithm>
#include <cmath>

namespace gam::sim
{
namespace
{
constexpr double kDeg = M_PI / 180.0;
constexpr double kFar = 20.0;  // ray-cast horizon for the true depth [m]
}  // namespace

double KinectParams::fx() const { return 0.5 * width / std::tan(0.5 * hfov_deg * kDeg); }
double KinectParams::fy() const { return 0.5 * height / std::tan(0.5 * vfov_deg * kDeg); }

double KinectParams::sigma(double z, double theta) const
{
	theta = std::clamp(theta, 0.0, M_PI / 2 - 1e-3);
	const double g = theta * theta / ((M_PI / 2 - theta) * (M_PI / 2 - theta));
	const double mm = 1.5 - 0.5 * z + 0.3 * z * z + 0.1 * std::pow(z, 1.5) * g;
	return noise_scale * 1e-3 * std::max(mm, 0.1);
}

double KinectParams::dropoutProb(double theta) const
{
	const double a = grazing_start_deg * kDeg, b = grazing_end_deg * kDeg;
	if (theta <= a) return 0.0;
	if (theta >= b) return 1.0;
	return (theta - a) / (b - a);
}

Eigen::Vector3d KinectModel::pixelRay(int r, int c) const
{
	return {1.0, (p.cx() - c) / p.fx(), (p.cy() - r) / p.fy()};
}

DepthFrame KinectModel::render(const Scene& scene, const Pose3& sensor, std::mt19937& rng) const
{
	DepthFrame f;
	f.width = p.width;
	f.height = p.height;
	const size_t N = size_t(p.width) * size_t(p.height);
	f.depth.assign(N, 0.0f);
	f.true_depth.assign(N, std::numeric_limits<float>::infinity());
	f.incidence.assign(N, 0.0f);
	f.object_id.assign(N, 0);
	f.flags.assign(N, 0);
	f.footprint.reserve(N / 2);

	// 1) exact ray casting
	for (int r = 0; r < p.height; r++)
		for (int c = 0; c < p.width; c++)
		{
			const size_t i = f.idx(r, c);
			const Eigen::Vector3d dir = sensor.R * pixelRay(r, c);  // t == depth along +X
			const RayHit h = scene.cast(sensor.t, dir, 1e-6, kFar);
			if (h.hit)
			{
				f.true_depth[i] = float(h.t);
				const double cosi = std::min(1.0, std::abs(h.normal.dot(dir)) / dir.norm());
				f.incidence[i] = float(std::acos(cosi));
				f.object_id[i] = h.object_id;
				if (h.t >= p.min_range && h.t <= p.max_range)
				{
					// 5 mm into the surface, so that a face lying on a cell
					// border marks the cell of the object, not the one in front
					const Eigen::Vector3d q = h.point - 0.005 * h.normal;
					f.footprint.emplace_back(q.x(), q.y());
				}
			}
			if (dir.z() < 0 && sensor.t.z() > 0)
			{
				// rays entering a pit (hitting its walls or bottom, or lost in
				// it): the opening they crossed at the floor level was seen too
				const double t0 = -sensor.t.z() / dir.z();
				if ((!h.hit || h.t > t0 + 1e-6) && t0 >= p.min_range && t0 <= p.max_range)
				{
					const Eigen::Vector3d q = sensor.t + t0 * dir;
					f.footprint.emplace_back(q.x(), q.y());
				}
			}
			const bool inRange = h.hit && h.t >= p.min_range && h.t <= p.max_range;
			if (!inRange) f.flags[i] |= PixOutOfRange;
		}

	// 2) depth edges (on the true depth; +inf neighbours do not count)
	std::vector<float> edgeOther(N, 0.0f);
	for (int r = 0; r < p.height; r++)
		for (int c = 0; c < p.width; c++)
		{
			const size_t i = f.idx(r, c);
			const float z = f.true_depth[i];
			if (!std::isfinite(z)) continue;
			float bestGap = 0;
			const int dr[4] = {-1, 1, 0, 0}, dc[4] = {0, 0, -1, 1};
			for (int k = 0; k < 4; k++)
			{
				const int rr = r + dr[k], cc = c + dc[k];
				if (rr < 0 || cc < 0 || rr >= p.height || cc >= p.width) continue;
				const float zn = f.true_depth[f.idx(rr, cc)];
				if (!std::isfinite(zn)) continue;
				const float gap = std::abs(zn - z);
				const double thr = std::max(p.flying_jump_abs, p.flying_jump_rel * std::min(z, zn));
				if (gap > thr && gap > bestGap)
				{
					bestGap = gap;
					edgeOther[i] = zn;
					f.flags[i] |= PixEdge;
				}
			}
		}

	// 3) materials, noise, dropouts, flying pixels, spikes
	std::normal_distribution<double> gauss(0.0, 1.0);
	std::uniform_real_distribution<double> uni(0.0, 1.0);
	for (size_t i = 0; i < N; i++)
	{
		const double z = f.true_depth[i];
		double d = z;
		if (f.object_id[i] != 0 && std::isfinite(z))
		{
			// Absorbing surfaces return nothing; shiny ones drop out at random.
			const ObjectInfo* oi = scene.object(f.object_id[i]);
			const Material m = oi ? oi->material : Material::Normal;
			if (m == Material::Absorbing || (m == Material::Specular && p.noise && uni(rng) < oi->dropout))
			{
				f.flags[i] |= PixDropout;
				continue;
			}
		}
		if (p.noise)
		{
			if (f.flags[i] & PixEdge)
			{
				if (uni(rng) < p.flying_prob)
				{
					const double u = 0.15 + 0.7 * uni(rng);
					d = z + u * (double(edgeOther[i]) - z);
					f.flags[i] |= PixFlying;
				}
			}
			if (std::isfinite(d) && !(f.flags[i] & PixFlying))
			{
				const double th = f.incidence[i];
				if (uni(rng) < p.dropoutProb(th))
				{
					d = 0;
					f.flags[i] |= PixDropout;
				}
				else
					d += p.sigma(z, th) * gauss(rng);
			}
			if (uni(rng) < p.spike_prob)
			{
				d = p.min_range + (p.max_range - p.min_range) * uni(rng);
				f.flags[i] |= PixSpike;
			}
		}
		if (std::isfinite(d) && d >= p.min_range && d <= p.max_range)
		{
			f.depth[i] = float(d);
			f.flags[i] |= PixValid;
		}
	}
	return f;
}

double LeddarParams::segmentAngle(int i) const
{
	const double ap = hfov_deg * kDeg;
	return segments > 1 ? -0.5 * ap + i * ap / (segments - 1) : 0.0;
}

LeddarScan LeddarModel::scan(const Scene& scene, const Pose3& sensor, std::mt19937& rng) const
{
	LeddarScan s;
	s.range.assign(size_t(p.segments), 0.0f);
	s.valid.assign(size_t(p.segments), false);
	s.object_id.assign(size_t(p.segments), 0);
	std::normal_distribution<double> gauss(0.0, 1.0);
	const double w = p.hfov_deg * kDeg / p.segments, vf = p.vfov_deg * kDeg;
	for (int i = 0; i < p.segments; i++)
	{
		double best = std::numeric_limits<double>::infinity();
		int obj = 0;
		for (int a = 0; a < p.sub_h; a++)
			for (int b = 0; b < p.sub_v; b++)
			{
				const double h = p.segmentAngle(i) - 0.5 * w + (a + 0.5) * w / p.sub_h;
				const double v = -0.5 * vf + (b + 0.5) * vf / p.sub_v;
				const Eigen::Vector3d dl(std::cos(v) * std::cos(h), std::cos(v) * std::sin(h), std::sin(v));
				const RayHit hit = scene.cast(sensor.t, sensor.R * dl, 1e-6, p.max_range);
				if (hit.hit && scene.materialOf(hit.object_id) == Material::Absorbing) continue;  // no echo
				if (hit.hit && hit.t >= p.min_range && hit.t < best)
				{
					best = hit.t;
					obj = hit.object_id;
				}
			}
		if (!std::isfinite(best)) continue;
		double r = best;
		if (p.noise) r += p.sigma * gauss(rng);
		if (p.quantum > 0) r = std::round(r / p.quantum) * p.quantum;
		if (r <= 0 || r > p.max_range) continue;
		s.range[size_t(i)] = float(r);
		s.valid[size_t(i)] = true;
		s.object_id[size_t(i)] = obj;
	}
	return s;
}

}  // namespace gam::sim
