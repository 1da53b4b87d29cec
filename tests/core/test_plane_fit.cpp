// Ground-aware mapping for MRPT
// Plane model, least-squares height fit, total least squares and RANSAC.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <iostream>
#include <random>

#include "gam/core/PlaneFit.h"
#include "test_helpers.h"

using namespace gam;
using gamtest::deg2rad;
using gamtest::rad2deg;

namespace
{
/** Ground truth: unit normal tilted by `tiltDeg` towards azimuth 30 deg,
 * through (0, 0, 0.4). */
Plane truePlane(double tiltDeg)
{
	const double t = deg2rad(tiltDeg), az = deg2rad(30);
	return Plane::fromNormalAndPoint(
		Eigen::Vector3d(std::sin(t) * std::cos(az), std::sin(t) * std::sin(az), std::cos(t)),
		Eigen::Vector3d(0, 0, 0.4));
}

/** n points with x, y uniform in [-2, 2], vertical N(0, noise) noise; the
 * points with i % 10 < 10 * outlierFrac are moved 0.1..1.0 m up or down. */
std::vector<Eigen::Vector3d> samplePlane(
	const Plane& pl, size_t n, double noise, double outlierFrac, std::mt19937& rng,
	std::vector<bool>* isOutlier = nullptr)
{
	std::uniform_real_distribution<double> U(-2.0, 2.0), G(0.1, 1.0);
	std::normal_distribution<double> N(0.0, noise);
	std::bernoulli_distribution sign(0.5);
	std::vector<Eigen::Vector3d> pts;
	const int outTenths = int(std::lround(outlierFrac * 10));
	for (size_t i = 0; i < n; i++)
	{
		const double x = U(rng), y = U(rng);
		double z = pl.heightAt(x, y) + N(rng);
		const bool out = int(i % 10) < outTenths;
		if (out) z += (sign(rng) ? 1.0 : -1.0) * G(rng);
		pts.emplace_back(x, y, z);
		if (isOutlier) isOutlier->push_back(out);
	}
	return pts;
}

double angleErrorDeg(const Plane& est, const Plane& truth)
{
	const double c = std::abs(est.normal().dot(truth.normal()));
	return rad2deg(std::acos(std::min(1.0, c)));
}
double offsetErrorMm(const Plane& est, const Plane& truth) { return 1000.0 * std::abs(est.d - truth.d); }

void report(const char* method, double tilt, const char* outliers, double angErr, double offErr)
{
	char buf[256];
	std::snprintf(
		buf, sizeof(buf), "plane fit (%s): tilt %.0f deg, noise 1 cm, %s: angle error %.4f deg, offset error %.3f mm",
		method, tilt, outliers, angErr, offErr);
	std::cout << buf << std::endl;
}
}  // namespace

TEST(Plane, BasicGeometry)
{
	// A downward normal is flipped up.
	const Plane p = Plane::fromNormalAndPoint({0, 0, -2}, {1, 2, 3});
	EXPECT_DOUBLE_EQ(p.a, 0);
	EXPECT_DOUBLE_EQ(p.b, 0);
	EXPECT_DOUBLE_EQ(p.c, 1);
	EXPECT_DOUBLE_EQ(p.d, -3);
	EXPECT_DOUBLE_EQ(p.signedDistance(7, -4, 5), 2);  // above: positive
	EXPECT_DOUBLE_EQ(p.signedDistance(0, 0, 2.5), -0.5);
	EXPECT_DOUBLE_EQ(p.heightAt(10, 10), 3);
	EXPECT_DOUBLE_EQ(p.tiltAngle(), 0);
	EXPECT_DOUBLE_EQ(p.horizontalNormal(), 0);

	// 45 deg plane z = -x through the origin.
	const Plane q = Plane::fromNormalAndPoint({-3, 0, -3}, {0, 0, 0});
	EXPECT_NEAR(q.a, std::sqrt(0.5), 1e-12);
	EXPECT_NEAR(q.c, std::sqrt(0.5), 1e-12);
	EXPECT_NEAR(q.tiltAngle(), deg2rad(45), 1e-12);
	EXPECT_NEAR(q.horizontalNormal(), std::sqrt(0.5), 1e-12);
	EXPECT_NEAR(q.heightAt(1, 5), -1, 1e-12);
	EXPECT_NEAR(q.signedDistance(0, 0, 1), std::sqrt(0.5), 1e-12);
}

TEST(PlaneFitLeastSquares, ExactThreePoints)
{
	// z = 0.1 x + 0.2 y + 0.3  <=>  (-0.1, -0.2, 1) . p - 0.3 = 0
	std::vector<Eigen::Vector3d> pts{{0, 0, 0.3}, {1, 0, 0.4}, {0, 1, 0.5}};
	double rms = -1;
	const auto p = fitHeightPlaneLeastSquares(pts, &rms);
	ASSERT_TRUE(p);
	const double k = 1.0 / std::sqrt(1.0 + 0.01 + 0.04);
	EXPECT_NEAR(p->a, -0.1 * k, 1e-12);
	EXPECT_NEAR(p->b, -0.2 * k, 1e-12);
	EXPECT_NEAR(p->c, k, 1e-12);
	EXPECT_NEAR(p->d, -0.3 * k, 1e-12);
	EXPECT_NEAR(rms, 0, 1e-12);
	EXPECT_NEAR(p->heightAt(2, 3), 0.2 + 0.6 + 0.3, 1e-12);
}

TEST(PlaneFitLeastSquares, RmsOfKnownResiduals)
{
	// Four corners of a square, heights +e, -e, +e, -e around z = 1 in a
	// saddle: the best plane is z = 1 and every residual is e.
	const double e = 0.02;
	std::vector<Eigen::Vector3d> pts{{0, 0, 1 + e}, {1, 0, 1 - e}, {1, 1, 1 + e}, {0, 1, 1 - e}};
	double rms = 0;
	const auto p = fitHeightPlaneLeastSquares(pts, &rms);
	ASSERT_TRUE(p);
	EXPECT_NEAR(p->c, 1, 1e-12);
	EXPECT_NEAR(p->heightAt(0.5, 0.5), 1, 1e-12);
	EXPECT_NEAR(rms, e, 1e-12);
}

TEST(PlaneFitLeastSquares, DegenerateInputs)
{
	EXPECT_FALSE(fitHeightPlaneLeastSquares({}));
	EXPECT_FALSE(fitHeightPlaneLeastSquares({{0, 0, 0}, {1, 1, 1}}));
	// Collinear in (x, y), whatever the heights.
	EXPECT_FALSE(fitHeightPlaneLeastSquares({{0, 0, 0}, {1, 1, 1}, {2, 2, 5}, {3, 3, -1}}));
	EXPECT_FALSE(fitHeightPlaneLeastSquares({{0, 1, 0}, {0, 2, 1}, {0, 3, 0}}));
	// Coincident.
	EXPECT_FALSE(fitHeightPlaneLeastSquares({{1, 1, 0}, {1, 1, 1}, {1, 1, 2}}));
}

TEST(PlaneFitTotalLeastSquares, ExactAndDegenerate)
{
	// A vertical plane x = 2 (a wall): TLS handles it, the height fit cannot.
	std::vector<Eigen::Vector3d> wall{{2, 0, 0}, {2, 1, 0}, {2, 0, 1}, {2, 1, 1}};
	const auto p = fitPlaneTotalLeastSquares(wall);
	ASSERT_TRUE(p);
	EXPECT_NEAR(std::abs(p->a), 1, 1e-9);
	EXPECT_NEAR(p->signedDistance(2, 5, 7), 0, 1e-9);
	EXPECT_NEAR(p->tiltAngle(), deg2rad(90), 1e-6);
	EXPECT_FALSE(fitHeightPlaneLeastSquares(wall));

	EXPECT_FALSE(fitPlaneTotalLeastSquares({{0, 0, 0}, {1, 1, 1}}));
	EXPECT_FALSE(fitPlaneTotalLeastSquares({{0, 0, 0}, {1, 1, 1}, {2, 2, 2}, {-1, -1, -1}}));
}

TEST(PlaneFitLeastSquares, TiltedNoisyPlanes)
{
	for (double tilt : {5.0, 10.0})
	{
		std::mt19937 rng(20240501u + unsigned(tilt));
		const Plane truth = truePlane(tilt);
		const auto pts = samplePlane(truth, 500, 0.01, 0.0, rng);
		double rms = 0;
		const auto p = fitHeightPlaneLeastSquares(pts, &rms);
		ASSERT_TRUE(p);
		const double ang = angleErrorDeg(*p, truth), off = offsetErrorMm(*p, truth);
		report("least squares", tilt, "no outliers", ang, off);
		// Expected std: 0.01 / (sqrt(500) * 1.15 m) = 0.022 deg; 0.45 mm.
		EXPECT_LT(ang, 0.15) << "tilt " << tilt;
		EXPECT_LT(off, 3.0) << "tilt " << tilt;
		EXPECT_NEAR(rad2deg(p->tiltAngle()), tilt, 0.15);
		EXPECT_NEAR(rms, 0.01, 0.0015);
		EXPECT_GT(p->c, 0);
	}
}

TEST(PlaneFitRansac, TiltedNoisyPlanesWithOutliers)
{
	for (double tilt : {5.0, 10.0})
	{
		std::mt19937 data(777u + unsigned(tilt));
		const Plane truth = truePlane(tilt);
		std::vector<bool> isOut;
		const auto pts = samplePlane(truth, 500, 0.01, 0.3, data, &isOut);
		size_t nOut = 0;
		for (bool b : isOut) nOut += b;
		ASSERT_EQ(nOut, 150u);

		// Least squares alone is pulled by the outliers (reported for contrast).
		const auto ls = fitHeightPlaneLeastSquares(pts);
		ASSERT_TRUE(ls);
		report("least squares", tilt, "30% outliers", angleErrorDeg(*ls, truth), offsetErrorMm(*ls, truth));

		RansacParams rp;
		rp.iterations = 200;
		rp.inlier_distance = 0.03;
		std::mt19937 rng(42);
		const auto r = fitPlaneRansac(pts, rp, rng);
		ASSERT_TRUE(r);
		const double ang = angleErrorDeg(r->plane, truth), off = offsetErrorMm(r->plane, truth);
		report("RANSAC+TLS", tilt, "30% outliers", ang, off);
		EXPECT_LT(ang, 0.25) << "tilt " << tilt;
		EXPECT_LT(off, 4.0) << "tilt " << tilt;
		EXPECT_GT(r->plane.c, 0);

		// Outliers are >= 0.1 m off vertically (>= 9.8 cm off the plane): never
		// inliers; nearly all true inliers (|noise| <= 3 sigma) are found.
		size_t outInl = 0;
		for (size_t i : r->inliers) outInl += isOut[i];
		EXPECT_EQ(outInl, 0u);
		EXPECT_GE(r->inliers.size(), 340u);
		EXPECT_LE(r->inliers.size(), 350u);
	}
}

TEST(PlaneFitRansac, DeterministicForASeed)
{
	std::mt19937 data(5);
	const auto pts = samplePlane(truePlane(7), 300, 0.01, 0.3, data);
	RansacParams rp;
	rp.iterations = 50;
	std::mt19937 r1(9), r2(9);
	const auto a = fitPlaneRansac(pts, rp, r1), b = fitPlaneRansac(pts, rp, r2);
	ASSERT_TRUE(a && b);
	EXPECT_EQ(a->plane.a, b->plane.a);
	EXPECT_EQ(a->plane.b, b->plane.b);
	EXPECT_EQ(a->plane.c, b->plane.c);
	EXPECT_EQ(a->plane.d, b->plane.d);
	EXPECT_EQ(a->inliers, b->inliers);
}

TEST(PlaneFitRansac, TiltLimitAndDegenerateInputs)
{
	// Noise-free 10 deg plane: every sample triple gives exactly that plane.
	std::mt19937 data(3);
	const Plane truth = truePlane(10);
	const auto pts = samplePlane(truth, 100, 0.0 + 1e-12, 0.0, data);
	RansacParams rp;
	std::mt19937 rng(1);
	rp.max_horizontal_normal = 0.1;  // 5.7 deg: the plane is too steep
	EXPECT_FALSE(fitPlaneRansac(pts, rp, rng));
	rp.max_horizontal_normal = 0.2;  // 11.5 deg
	const auto ok = fitPlaneRansac(pts, rp, rng);
	ASSERT_TRUE(ok);
	EXPECT_LT(angleErrorDeg(ok->plane, truth), 1e-6);
	EXPECT_EQ(ok->inliers.size(), 100u);

	rp = RansacParams{};
	EXPECT_FALSE(fitPlaneRansac({}, rp, rng));
	EXPECT_FALSE(fitPlaneRansac({{0, 0, 0}, {1, 0, 0}}, rp, rng));
	// Collinear points: no candidate plane at all.
	std::vector<Eigen::Vector3d> line;
	for (int i = 0; i < 20; i++) line.emplace_back(0.1 * i, 0.2 * i, 0.05 * i);
	EXPECT_FALSE(fitPlaneRansac(line, rp, rng));
	// Fewer points than min_inliers.
	rp.min_inliers = 200;
	EXPECT_FALSE(fitPlaneRansac(pts, rp, rng));
}
