// Ground-aware mapping for MRPT -- scene simulator: robot path and odometry.
#pragma once

#include <random>
#include <vector>

namespace gam::sim
{
/** A planar robot pose (x, y [m], yaw [rad]). */
struct Pose2
{
	double x = 0, y = 0, yaw = 0;
	Pose2 compose(const Pose2& d) const;         ///< this ⊕ d
	Pose2 inverseCompose(const Pose2& b) const;  ///< this ⊖ b (b⁻¹ ⊕ this)
};

double wrapPi(double a);

struct PathSpec
{
	std::vector<Pose2> waypoints;              ///< at least one
	double spacing = 0.10;                     ///< metres between frames along straight parts
	double turn_spacing = 5.0 * M_PI / 180.0;  ///< radians between frames while turning
	int frames = 0;                            ///< single-waypoint path: number of frames to take there (>=1)
	double rate_hz = 10.0;                     ///< frame rate, for timestamps
};

/** Frames along the polyline of waypoints: the yaw is interpolated linearly
 * (shortest way) along each segment; each segment is split into
 * max(ceil(len/spacing), ceil(|dyaw|/turn_spacing)) steps. The first waypoint
 * is the first frame. */
std::vector<Pose2> samplePath(const PathSpec& spec);

/** Odometry error model: each increment between frames gets Gaussian noise
 * with sigma_xy = xy_per_m * dist (both axes), sigma_yaw = yaw_per_m * dist +
 * yaw_per_rad * |dyaw|, and a systematic drift: its translation is scaled by
 * (1 + scale) and yaw_bias_per_m * dist is added to its rotation. */
struct OdometryNoise
{
	double xy_per_m = 0.0;
	double yaw_per_m = 0.0;  ///< radians per metre
	double yaw_per_rad = 0.0;
	double scale = 0.0;           ///< systematic: every increment's translation times (1 + scale)
	double yaw_bias_per_m = 0.0;  ///< systematic: radians added per metre travelled
	bool random() const { return xy_per_m > 0 || yaw_per_m > 0 || yaw_per_rad > 0; }
	bool enabled() const { return random() || scale != 0 || yaw_bias_per_m != 0; }
};

/** The absolute odometry readings for the true path (starts at truth[0]). */
std::vector<Pose2> simulateOdometry(const std::vector<Pose2>& truth, const OdometryNoise& n, std::mt19937& rng);

}  // namespace gam::sim
