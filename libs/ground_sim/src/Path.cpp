// Ground-aware mapping for MRPT -- scene simulator: robot path and odometry.
#include "gam/sim/Path.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace gam::sim
{
double wrapPi(double a)
{
	while (a > M_PI) a -= 2 * M_PI;
	while (a <= -M_PI) a += 2 * M_PI;
	return a;
}

Pose2 Pose2::compose(const Pose2& d) const
{
	const double c = std::cos(yaw), s = std::sin(yaw);
	return {x + c * d.x - s * d.y, y + s * d.x + c * d.y, wrapPi(yaw + d.yaw)};
}

Pose2 Pose2::inverseCompose(const Pose2& b) const
{
	const double c = std::cos(b.yaw), s = std::sin(b.yaw);
	const double dx = x - b.x, dy = y - b.y;
	return {c * dx + s * dy, -s * dx + c * dy, wrapPi(yaw - b.yaw)};
}

std::vector<Pose2> samplePath(const PathSpec& spec)
{
	if (spec.waypoints.empty()) throw std::invalid_argument("path: no waypoints");
	std::vector<Pose2> out;
	if (spec.waypoints.size() == 1)
	{
		out.assign(size_t(std::max(1, spec.frames)), spec.waypoints[0]);
		return out;
	}
	out.push_back(spec.waypoints[0]);
	for (size_t k = 0; k + 1 < spec.waypoints.size(); k++)
	{
		const Pose2 a = spec.waypoints[k], b = spec.waypoints[k + 1];
		const double len = std::hypot(b.x - a.x, b.y - a.y);
		const double dyaw = wrapPi(b.yaw - a.yaw);
		const int n = std::max(
			{1, int(std::ceil(len / std::max(1e-6, spec.spacing) - 1e-9)),
			 int(std::ceil(std::abs(dyaw) / std::max(1e-6, spec.turn_spacing) - 1e-9))});
		for (int i = 1; i <= n; i++)
		{
			const double u = double(i) / n;
			out.push_back({a.x + u * (b.x - a.x), a.y + u * (b.y - a.y), wrapPi(a.yaw + u * dyaw)});
		}
	}
	if (spec.frames > 0 && size_t(spec.frames) < out.size()) out.resize(size_t(spec.frames));
	return out;
}

std::vector<Pose2> simulateOdometry(const std::vector<Pose2>& truth, const OdometryNoise& n, std::mt19937& rng)
{
	std::vector<Pose2> odo;
	if (truth.empty()) return odo;
	odo.push_back(truth[0]);
	std::normal_distribution<double> g(0.0, 1.0);
	for (size_t i = 1; i < truth.size(); i++)
	{
		Pose2 d = truth[i].inverseCompose(truth[i - 1]);
		const double dist = std::hypot(d.x, d.y);
		if (n.random())
		{
			d.x += n.xy_per_m * dist * g(rng);
			d.y += n.xy_per_m * dist * g(rng);
			d.yaw += (n.yaw_per_m * dist + n.yaw_per_rad * std::abs(d.yaw)) * g(rng);
		}
		if (n.scale != 0 || n.yaw_bias_per_m != 0)
		{
			d.x *= 1 + n.scale;
			d.y *= 1 + n.scale;
			d.yaw += n.yaw_bias_per_m * dist;
		}
		odo.push_back(odo.back().compose(d));
	}
	return odo;
}

}  // namespace gam::sim
