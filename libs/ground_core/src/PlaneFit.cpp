#include "gam/core/PlaneFit.h"

#include <Eigen/Dense>
#include <cmath>

namespace gam
{
double Plane::tiltAngle() const { return std::acos(std::min(1.0, std::abs(c))); }

Plane Plane::fromNormalAndPoint(const Eigen::Vector3d& n_in, const Eigen::Vector3d& p)
{
	Eigen::Vector3d n = n_in.normalized();
	if (n.z() < 0) n = -n;
	Plane pl;
	pl.a = n.x();
	pl.b = n.y();
	pl.c = n.z();
	pl.d = -n.dot(p);
	return pl;
}

std::optional<Plane> fitHeightPlaneLeastSquares(const std::vector<Eigen::Vector3d>& pts, double* rms)
{
	const size_t n = pts.size();
	if (n < 3) return std::nullopt;
	// Centre the samples for conditioning, then solve the 3x3 normal equations.
	Eigen::Vector3d mean = Eigen::Vector3d::Zero();
	for (const auto& p : pts) mean += p;
	mean /= double(n);
	double sxx = 0, sxy = 0, syy = 0, sxz = 0, syz = 0;
	for (const auto& p : pts)
	{
		const double x = p.x() - mean.x(), y = p.y() - mean.y(), z = p.z() - mean.z();
		sxx += x * x;
		sxy += x * y;
		syy += y * y;
		sxz += x * z;
		syz += y * z;
	}
	const double det = sxx * syy - sxy * sxy;
	// Collinear (or coincident) samples: the fit is undetermined.
	if (!(det > 1e-12 * std::max(1.0, sxx * syy))) return std::nullopt;
	const double p0 = (sxz * syy - syz * sxy) / det;
	const double p1 = (syz * sxx - sxz * sxy) / det;
	if (rms)
	{
		double s = 0;
		for (const auto& p : pts)
		{
			const double r = (p.z() - mean.z()) - p0 * (p.x() - mean.x()) - p1 * (p.y() - mean.y());
			s += r * r;
		}
		*rms = std::sqrt(s / double(n));
	}
	// z = p0 x + p1 y + k  <=>  -p0 x - p1 y + z - k = 0
	return Plane::fromNormalAndPoint(Eigen::Vector3d(-p0, -p1, 1.0), mean);
}

std::optional<Plane> fitPlaneTotalLeastSquares(const std::vector<Eigen::Vector3d>& pts)
{
	if (pts.size() < 3) return std::nullopt;
	Eigen::Vector3d mean = Eigen::Vector3d::Zero();
	for (const auto& p : pts) mean += p;
	mean /= double(pts.size());
	Eigen::Matrix3d C = Eigen::Matrix3d::Zero();
	for (const auto& p : pts)
	{
		const Eigen::Vector3d q = p - mean;
		C += q * q.transpose();
	}
	Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(C);
	if (es.info() != Eigen::Success) return std::nullopt;
	// Degenerate if the two largest spreads do not span a plane.
	if (!(es.eigenvalues()(1) > 1e-12)) return std::nullopt;
	return Plane::fromNormalAndPoint(es.eigenvectors().col(0), mean);
}

std::optional<RansacResult> fitPlaneRansac(
	const std::vector<Eigen::Vector3d>& pts, const RansacParams& p, std::mt19937& rng)
{
	RansacResult res;
	std::vector<Eigen::Vector3d> inl;
	if (!fitPlaneRansac(pts, p, rng, res, inl)) return std::nullopt;
	return res;
}

bool fitPlaneRansac(
	const std::vector<Eigen::Vector3d>& pts, const RansacParams& p, std::mt19937& rng, RansacResult& res,
	std::vector<Eigen::Vector3d>& inl)
{
	const size_t n = pts.size();
	if (n < 3 || n < p.min_inliers) return false;
	std::uniform_int_distribution<size_t> pick(0, n - 1);
	size_t bestCount = 0;
	Plane best;
	for (int it = 0; it < p.iterations; it++)
	{
		const size_t i = pick(rng), j = pick(rng), k = pick(rng);
		if (i == j || j == k || i == k) continue;
		const Eigen::Vector3d nrm = (pts[j] - pts[i]).cross(pts[k] - pts[i]);
		if (nrm.norm() < 1e-9) continue;
		const Plane cand = Plane::fromNormalAndPoint(nrm, pts[i]);
		if (cand.horizontalNormal() > p.max_horizontal_normal) continue;
		size_t cnt = 0;
		for (const auto& q : pts)
			if (std::abs(cand.signedDistance(q.x(), q.y(), q.z())) <= p.inlier_distance) cnt++;
		if (cnt > bestCount)
		{
			bestCount = cnt;
			best = cand;
			if (cnt == n) break;
		}
	}
	if (bestCount < std::max<size_t>(3, p.min_inliers)) return false;

	res.inliers.clear();
	inl.clear();
	for (size_t i = 0; i < n; i++)
		if (std::abs(best.signedDistance(pts[i].x(), pts[i].y(), pts[i].z())) <= p.inlier_distance)
		{
			res.inliers.push_back(i);
			inl.push_back(pts[i]);
		}
	if (!p.refine)
	{
		res.plane = best;
		return true;
	}
	const auto refined = fitPlaneTotalLeastSquares(inl);
	res.plane = (refined && refined->horizontalNormal() <= p.max_horizontal_normal) ? *refined : best;
	return true;
}

}  // namespace gam
