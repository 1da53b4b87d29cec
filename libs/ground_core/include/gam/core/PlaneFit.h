// Ground-aware mapping for MRPT
// Plane model and the two fits the method needs: a least-squares fit of local
// neighbourhoods (RRT-GPD node validation) and a RANSAC fit of the node centres
// (the final ground plane). Pure code.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <random>
#include <vector>

namespace gam
{
/** Plane a*x + b*y + c*z + d = 0 with (a, b, c) a unit normal pointing up (c >= 0),
 * so signedDistance() > 0 means "above". */
struct Plane
{
	double a = 0, b = 0, c = 1, d = 0;

	double signedDistance(double x, double y, double z) const { return a * x + b * y + c * z + d; }
	/** Height of the plane at (x, y); requires c != 0. */
	double heightAt(double x, double y) const { return -(a * x + b * y + d) / c; }
	Eigen::Vector3d normal() const { return {a, b, c}; }
	/** Angle between the normal and +Z, radians. */
	double tiltAngle() const;
	/** sin of the tilt: the horizontal part of the unit normal. */
	double horizontalNormal() const { return std::sqrt(a * a + b * b); }
	/** Builds a normalized, upward plane from n and a point on it. */
	static Plane fromNormalAndPoint(const Eigen::Vector3d& n, const Eigen::Vector3d& p);
};

/** Least-squares fit z = p0*x + p1*y + p2 of height samples (the 2.5D map
 * stores heights, so vertical residuals are the natural error). Returns
 * std::nullopt for fewer than 3 samples or a degenerate (collinear) layout.
 * `rms` gets the RMS vertical residual. */
std::optional<Plane> fitHeightPlaneLeastSquares(const std::vector<Eigen::Vector3d>& pts, double* rms = nullptr);

/** Total least squares (smallest eigenvector of the covariance): for general
 * 3D points, used to refine RANSAC inliers. */
std::optional<Plane> fitPlaneTotalLeastSquares(const std::vector<Eigen::Vector3d>& pts);

struct RansacParams
{
	int iterations = 200;
	double inlier_distance = 0.05;  ///< metres
	size_t min_inliers = 3;
	/** Reject candidate planes tilted more than this (sin of the angle); 1 = any. */
	double max_horizontal_normal = 1.0;
	/** Refit the best candidate to its inliers (total least squares); false =
	 * the candidate through 3 of the points, as plain RANSAC gives it. */
	bool refine = true;
};

struct RansacResult
{
	Plane plane;
	std::vector<size_t> inliers;
};

/** RANSAC plane fit, refined by total least squares over the inliers.
 * Deterministic for a given `rng` state. */
std::optional<RansacResult> fitPlaneRansac(
	const std::vector<Eigen::Vector3d>& pts, const RansacParams& p, std::mt19937& rng);

/** The same fit into caller-owned storage: `out.inliers` and `inlierScratch`
 * keep their capacity, so repeated calls need no heap allocation. Returns
 * false where the other overload returns std::nullopt (`out` is then
 * unspecified). Same result and same use of `rng` as the other overload. */
bool fitPlaneRansac(
	const std::vector<Eigen::Vector3d>& pts, const RansacParams& p, std::mt19937& rng, RansacResult& out,
	std::vector<Eigen::Vector3d>& inlierScratch);

}  // namespace gam
