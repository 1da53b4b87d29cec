// Ground-aware mapping for MRPT
// Inverse sensor model: the formulas by hand, then end to end on synthetic
// frames with a hand-made (or detected) ground.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <set>
#include <stdexcept>
#include <vector>

#include "gam/core/InverseSensorModel.h"
#include "gam/core/RrtGroundDetector.h"
#include "test_helpers.h"

using namespace gam;
using gamtest::deg2rad;
using gamtest::inRect;

namespace
{
/** P(occ) of an obstacle/drop voxel, eq. (4)-(5) written out with the
 * paper's constants (K_n = 0.0005, d_min = 3, K_m = 0.8). */
double handObstacleP(int n, double span, double res)
{
	const double rho = n / (res * res * std::max(span, res));
	const double pr = 1.0 / (1.0 + std::exp(-(0.0005 * rho - 3.0)));
	return 0.5 + 0.4 * pr;
}

ElevationCell cellOf(std::initializer_list<float> zs)
{
	ElevationCell c;
	for (float z : zs) c.add(z);
	return c;
}

GroundDetection handDetection(const Plane& pl, GroundDetection::Status s = GroundDetection::Status::Ok)
{
	GroundDetection d;
	d.status = s;
	d.planes.push_back(pl);
	d.plane_support.push_back(100);
	return d;
}
const Plane kFloor{0, 0, 1, 0};  // z = 0

/** Consistency of evidence() and evidenceCells(). */
void checkEvidenceBookkeeping(const InverseSensorModel& ism)
{
	std::set<uint32_t> cells(ism.evidenceCells().begin(), ism.evidenceCells().end());
	EXPECT_EQ(cells.size(), ism.evidenceCells().size()) << "duplicates in evidenceCells()";
	size_t nonNeutral = 0;
	for (size_t i = 0; i < ism.evidence().size(); i++)
		if (ism.evidence()[i] != 0.5f)
		{
			nonNeutral++;
			EXPECT_TRUE(cells.count(uint32_t(i))) << i;
		}
	EXPECT_EQ(nonNeutral, cells.size());
}
}  // namespace

TEST(IsmFormulas, VoxelDensity)
{
	// N / (d_r^2 * max(span, d_r))
	EXPECT_NEAR(ism::voxelDensity(10, 0.2, 0.05), 10 / (0.0025 * 0.2), 1e-6);  // 20000
	EXPECT_NEAR(ism::voxelDensity(5, 0.01, 0.05), 40000.0, 1e-6);              // span < d_r -> d_r
	EXPECT_NEAR(ism::voxelDensity(1, 0.0, 0.1), 1000.0, 1e-9);
	EXPECT_EQ(ism::voxelDensity(0, 0.3, 0.05), 0.0);
}

TEST(IsmFormulas, DensityConfidence)
{
	const IsmParams p;  // K_n = 0.0005, d_min = 3
	EXPECT_DOUBLE_EQ(p.K_n, 0.0005);
	EXPECT_DOUBLE_EQ(p.d_min, 3.0);
	EXPECT_NEAR(ism::densityConfidence(6000, p), 0.5, 1e-12);                  // K_n rho = d_min
	EXPECT_NEAR(ism::densityConfidence(10000, p), 0.8807970779778823, 1e-12);  // 1/(1+e^-2)
	EXPECT_NEAR(ism::densityConfidence(0, p), 0.04742587317756678, 1e-12);     // 1/(1+e^3)
	EXPECT_NEAR(ism::densityConfidence(2000, p), 0.11920292202211755, 1e-12);  // 1/(1+e^2)
	EXPECT_GT(ism::densityConfidence(1e6, p), 0.999999);
}

TEST(IsmFormulas, ObstacleProbability)
{
	const IsmParams p;  // K_m = 0.8
	EXPECT_NEAR(ism::obstacleProbability(0.0, p), 0.5, 1e-12);
	EXPECT_NEAR(ism::obstacleProbability(0.5, p), 0.7, 1e-12);
	EXPECT_NEAR(ism::obstacleProbability(1.0, p), 0.9, 1e-12);
	EXPECT_NEAR(ism::obstacleProbability(0.8807970779778823, p), 0.5 + 0.4 * 0.8807970779778823, 1e-12);
}

TEST(IsmFormulas, GroundProbability)
{
	const IsmParams p;  // K_g = 0.3, sigma2 = 0.02
	EXPECT_NEAR(ism::groundProbability(0.0, p), 0.2, 1e-12);
	// d = 0.1: exp(-0.01 / 0.04) = exp(-0.25) = 0.7788007830714049
	EXPECT_NEAR(ism::groundProbability(0.1, p), 0.5 - 0.3 * 0.7788007830714049, 1e-12);
	EXPECT_NEAR(ism::groundProbability(-0.1, p), 0.26635976507857853, 1e-12);
	// d = 0.2: exp(-1)
	EXPECT_NEAR(ism::groundProbability(0.2, p), 0.38963616764856766, 1e-12);
	// d = d_pth = 0.03: exp(-0.0009 / 0.04) = exp(-0.0225) = 0.9777512371933363
	EXPECT_NEAR(ism::groundProbability(0.03, p), 0.5 - 0.3 * 0.9777512371933363, 1e-12);
	EXPECT_NEAR(ism::groundProbability(10.0, p), 0.5, 1e-12);
}

TEST(IsmFormulas, Combine)
{
	EXPECT_FLOAT_EQ(ism::combine(0.7f, 0.2f), 0.7f);  // occupied wins
	EXPECT_FLOAT_EQ(ism::combine(0.2f, 0.6f), 0.6f);
	EXPECT_FLOAT_EQ(ism::combine(0.6f, 0.9f), 0.9f);  // the largest occupied
	EXPECT_FLOAT_EQ(ism::combine(0.9f, 0.6f), 0.9f);
	EXPECT_FLOAT_EQ(ism::combine(0.3f, 0.2f), 0.2f);  // the strongest free
	EXPECT_FLOAT_EQ(ism::combine(0.5f, 0.3f), 0.3f);
	EXPECT_FLOAT_EQ(ism::combine(0.3f, 0.5f), 0.3f);
	EXPECT_FLOAT_EQ(ism::combine(0.5f, 0.5f), 0.5f);
	EXPECT_FLOAT_EQ(ism::combine(0.5f, 0.51f), 0.51f);
}

TEST(IsmParamsTest, ValidateAndDefaults)
{
	const IsmParams d;
	EXPECT_DOUBLE_EQ(d.K_g, 0.3);
	EXPECT_DOUBLE_EQ(d.sigma2, 0.02);
	EXPECT_DOUBLE_EQ(d.K_m, 0.8);
	EXPECT_DOUBLE_EQ(d.d_pth, 0.03);
	EXPECT_NO_THROW(d.validate());
	auto bad = [](auto mutate) {
		IsmParams p;
		mutate(p);
		return p;
	};
	EXPECT_THROW(bad([](IsmParams& p) { p.d_pth = 0; }).validate(), std::invalid_argument);
	EXPECT_THROW(bad([](IsmParams& p) { p.K_g = 0.5; }).validate(), std::invalid_argument);
	EXPECT_THROW(bad([](IsmParams& p) { p.K_g = -0.1; }).validate(), std::invalid_argument);
	EXPECT_THROW(bad([](IsmParams& p) { p.sigma2 = 0; }).validate(), std::invalid_argument);
	EXPECT_THROW(bad([](IsmParams& p) { p.K_n = 0; }).validate(), std::invalid_argument);
	EXPECT_THROW(bad([](IsmParams& p) { p.d_min = NAN; }).validate(), std::invalid_argument);
	EXPECT_THROW(bad([](IsmParams& p) { p.K_m = 1.0; }).validate(), std::invalid_argument);
	EXPECT_THROW(bad([](IsmParams& p) { p.noise_sigmas = -1; }).validate(), std::invalid_argument);
	EXPECT_THROW(bad([](IsmParams& p) { p.robot_height = 0; }).validate(), std::invalid_argument);

	// Parameters are checked when they are set, not on every frame.
	EXPECT_THROW(InverseSensorModel{bad([](IsmParams& p) { p.K_m = 2; })}, std::invalid_argument);
	InverseSensorModel ism;
	EXPECT_THROW(ism.setParams(bad([](IsmParams& p) { p.K_m = 2; })), std::invalid_argument);
	EXPECT_DOUBLE_EQ(ism.params().K_m, 0.8);
	// The sensor's range is an input of each frame.
	ElevationGrid grid;
	IsmStats st;
	EXPECT_THROW(ism.compute(grid, handDetection(kFloor), {0, 0, 1}, 0.0, st), std::invalid_argument);
}

TEST(InverseSensorModel, GroundBandNoiseModel)
{
	InverseSensorModel ism;  // d_pth 0.03, c0 0.0012, c2 0.0019, 3 sigmas
	// Sensor 1 m above the floor, voxel on the floor 3 m ahead: r^2 = 10.
	const double r = std::sqrt(10.0);
	EXPECT_NEAR(ism.groundBand({0, 0, 1}, 1.0, 3, 0, 0), 0.03 + 3 * (0.0012 + 0.0019 * 10) * (1 / r), 1e-12);
	// 0.049163...
	EXPECT_NEAR(ism.groundBand({0, 0, 1}, 1.0, 3, 0, 0), 0.0491627, 1e-6);
	// The sign of the sensor height does not matter.
	EXPECT_NEAR(ism.groundBand({0, 0, 1}, -1.0, 3, 0, 0), ism.groundBand({0, 0, 1}, 1.0, 3, 0, 0), 1e-15);
	// Straight below the sensor, h / r clamped to 1: 0.03 + 3 * (0.0012 + 0.0019).
	EXPECT_NEAR(ism.groundBand({0, 0, 1}, 5.0, 0, 0, 0), 0.03 + 3 * 0.0031, 1e-12);
	// At the sensor: just d_pth.
	EXPECT_NEAR(ism.groundBand({1, 2, 3}, 1.0, 1, 2, 3), 0.03, 1e-15);
	// Far floor gets a wider band than near floor.
	EXPECT_GT(ism.groundBand({0, 0, 1}, 1.0, 4.5, 0, 0), ism.groundBand({0, 0, 1}, 1.0, 1.5, 0, 0));

	IsmParams p;
	p.noise_sigmas = 0;  // the paper's fixed band
	ism.setParams(p);
	EXPECT_DOUBLE_EQ(ism.groundBand({0, 0, 1}, 1.0, 3, 0, 0), 0.03);
	p.noise_sigmas = 2;
	p.depth_noise_c0 = 0.01;
	p.depth_noise_c2 = 0.0;
	p.d_pth = 0.05;
	ism.setParams(p);
	// r = 4 (same height), h = 1: 0.05 + 2 * 0.01 * 1/4
	EXPECT_NEAR(ism.groundBand({0, 0, 1}, 1.0, 4, 0, 1), 0.055, 1e-12);
}

TEST(InverseSensorModel, ClassifyAgainstAPlane)
{
	InverseSensorModel ism;  // robot_height 1.8
	const double band = 0.05;
	double d = 99;
	EXPECT_EQ(ism.classify(cellOf({-0.01f, 0.02f}), 1, 1, kFloor, band, d), VoxelClass::Ground);
	EXPECT_NEAR(d, 0.005, 1e-6);                                                           // the mean's distance
	EXPECT_EQ(ism.classify(cellOf({0.049f}), 1, 1, kFloor, band, d), VoxelClass::Ground);  // inside the band
	EXPECT_EQ(ism.classify(cellOf({-0.049f}), 1, 1, kFloor, band, d), VoxelClass::Ground);
	EXPECT_EQ(ism.classify(cellOf({0.0f, 0.3f}), 1, 1, kFloor, band, d), VoxelClass::Obstacle);
	EXPECT_NEAR(d, 0.15, 1e-6);
	EXPECT_EQ(ism.classify(cellOf({0.06f}), 1, 1, kFloor, band, d), VoxelClass::Obstacle);
	EXPECT_EQ(ism.classify(cellOf({-0.4f, -0.3f}), 1, 1, kFloor, band, d), VoxelClass::Drop);
	EXPECT_EQ(ism.classify(cellOf({-0.06f}), 1, 1, kFloor, band, d), VoxelClass::Drop);
	// Top on the floor, bottom 20 cm below: edge of a hole.
	EXPECT_EQ(ism.classify(cellOf({-0.2f, 0.01f}), 1, 1, kFloor, band, d), VoxelClass::Drop);
	// Above the ground: an obstacle, however high (the pipeline does not
	// project what lies above robot_height; the ISM judges what it is given).
	EXPECT_EQ(ism.classify(cellOf({1.9f, 2.2f}), 1, 1, kFloor, band, d), VoxelClass::Obstacle);
	EXPECT_EQ(ism.classify(cellOf({1.0f, 2.0f}), 1, 1, kFloor, band, d), VoxelClass::Obstacle);
	// A wall through the plane (from below it to above it) is an obstacle.
	EXPECT_EQ(ism.classify(cellOf({-0.3f, 1.0f}), 1, 1, kFloor, band, d), VoxelClass::Obstacle);
	// The band matters.
	EXPECT_EQ(ism.classify(cellOf({0.04f}), 1, 1, kFloor, 0.03, d), VoxelClass::Obstacle);
	EXPECT_EQ(ism.classify(cellOf({0.04f}), 1, 1, kFloor, 0.045, d), VoxelClass::Ground);

	// A 10 deg plane z = tan(10 deg) x: distances are perpendicular.
	const double s = std::sin(deg2rad(10)), c = std::cos(deg2rad(10));
	const Plane tilted{-s, 0, c, 0};
	const float zp = float(std::tan(deg2rad(10)) * 1.0);  // 0.1763 at x = 1
	EXPECT_EQ(ism.classify(cellOf({zp - 0.01f, zp + 0.01f}), 1, 0, tilted, band, d), VoxelClass::Ground);
	EXPECT_NEAR(d, -s * 1.0 + c * zp, 1e-6);
	EXPECT_EQ(ism.classify(cellOf({zp + 0.1f}), 1, 0, tilted, band, d), VoxelClass::Obstacle);
	EXPECT_NEAR(d, c * 0.1, 1e-6);
	// Flat-floor height 0 at x = 1 is 17 cm below that plane.
	EXPECT_EQ(ism.classify(cellOf({0.0f}), 1, 0, tilted, band, d), VoxelClass::Drop);
}

TEST(InverseSensorModel, ClassifyByTheMeanOfNSamples)
{
	// Issue #17, second cause: a 4 cm cable protector or the bottom of a 5 cm
	// pit 4 m away lies inside the one-sample ground band there (measured floor
	// scatter ~8 mm: d_pth + 3 sigma = 0.03 + 0.024 = 0.054). Each sample alone
	// is plausible floor; 9 of them at +4 cm are not. Band of one sample here:
	// 0.045 = d_pth 0.03 + noise part 0.015. The mean of N samples has a noise
	// part 0.015 / sqrt(N); the d_pth part (plane error, uneven floor) stays.
	InverseSensorModel ism;
	const double band = 0.045;
	double d = 0;
	auto cellOfN = [](int n, float z) {
		ElevationCell c;
		for (int i = 0; i < n; i++) c.add(z);
		return c;
	};
	// N = 9: band of the mean 0.03 + 0.015 / 3 = 0.035 < 0.04.
	EXPECT_EQ(ism.classify(cellOfN(9, 0.04f), 1, 1, kFloor, band, d), VoxelClass::Obstacle);
	EXPECT_EQ(ism.classify(cellOfN(9, -0.04f), 1, 1, kFloor, band, d), VoxelClass::Drop);
	// N = 4: 0.03 + 0.015 / 2 = 0.0375 > 0.036: still floor.
	EXPECT_EQ(ism.classify(cellOfN(4, 0.036f), 1, 1, kFloor, band, d), VoxelClass::Ground);
	// N = 9 at 0.036 > 0.035: not floor.
	EXPECT_EQ(ism.classify(cellOfN(9, 0.036f), 1, 1, kFloor, band, d), VoxelClass::Obstacle);
	// One sample: the one-sample band (0.04 < 0.045 is floor).
	EXPECT_EQ(ism.classify(cellOfN(1, 0.04f), 1, 1, kFloor, band, d), VoxelClass::Ground);
	// Never narrower than d_pth, however many samples: 10000 at +2.9 cm are floor.
	EXPECT_EQ(ism.classify(cellOfN(10000, 0.029f), 1, 1, kFloor, band, d), VoxelClass::Ground);
	// Samples spread over the band with a mean near the plane: floor.
	EXPECT_EQ(ism.classify(cellOf({-0.04f, 0.04f, -0.03f, 0.03f, 0.0f}), 1, 1, kFloor, band, d), VoxelClass::Ground);
	// A band that is all d_pth (noise_sigmas = 0, the paper's) has no noise part to shrink.
	EXPECT_EQ(ism.classify(cellOfN(9, 0.029f), 1, 1, kFloor, 0.03, d), VoxelClass::Ground);

	IsmParams p;
	p.mean_test = false;  // only z_min / z_max against the one-sample band
	ism.setParams(p);
	EXPECT_EQ(ism.classify(cellOfN(9, 0.04f), 1, 1, kFloor, band, d), VoxelClass::Ground);
	EXPECT_EQ(ism.classify(cellOfN(9, -0.04f), 1, 1, kFloor, band, d), VoxelClass::Ground);
}

TEST(InverseSensorModel, ClassifyByTheMeanAgainstTheMeasuredFloorSpread)
{
	// Issue #13: with measure_floor_offset the fixed d_pth of the band of the
	// mean is replaced by tau, the measured spread of the floor cells' means
	// around the plane: band of the mean = k sqrt(tau^2 + sigma^2 / N), never
	// wider than d_pth + (b - d_pth) / sqrt(N) and never narrower than
	// traversable_step (2 cm). One-sample band b = 0.06 = d_pth 0.03 + 3 sigma
	// with sigma = 0.01; k = noise_sigmas = 3.
	InverseSensorModel ism;
	const double band = 0.06;
	double d = 0;
	auto cellOfN = [](int n, float z) {
		ElevationCell c;
		for (int i = 0; i < n; i++) c.add(z);
		return c;
	};
	// 16 samples 2.5 cm below the plane (a far pit's bottom). d_pth form:
	// 0.03 + 0.03 / 4 = 0.0375 > 0.025: floor. Flat floor, tau = 2 mm:
	// 3 sqrt(0.002^2 + 0.01^2 / 16) = 3 sqrt(4e-6 + 6.25e-6) = 3 * 0.0032016 =
	// 0.0096, raised to the 2 cm step: 0.02 < 0.025: a drop.
	EXPECT_EQ(ism.classify(cellOfN(16, -0.025f), 1, 1, kFloor, band, d), VoxelClass::Ground);
	EXPECT_EQ(ism.classify(cellOfN(16, -0.025f), 1, 1, kFloor, band, d, 0.002), VoxelClass::Drop);
	EXPECT_EQ(ism.classify(cellOfN(16, 0.025f), 1, 1, kFloor, band, d, 0.002), VoxelClass::Obstacle);
	// A 1.5 cm mat is beyond the measured 9.6 mm but below the 2 cm step: floor.
	EXPECT_EQ(ism.classify(cellOfN(16, 0.015f), 1, 1, kFloor, band, d, 0.002), VoxelClass::Ground);
	// A rough floor, tau = 2 cm: 3 sqrt(4e-4 + 6.25e-6) = 0.0605, capped at the
	// d_pth form 0.0375 > 0.025: floor.
	EXPECT_EQ(ism.classify(cellOfN(16, -0.025f), 1, 1, kFloor, band, d, 0.02), VoxelClass::Ground);
	// One sample: only the one-sample band counts, whatever tau.
	EXPECT_EQ(ism.classify(cellOfN(1, -0.025f), 1, 1, kFloor, band, d, 0.0), VoxelClass::Ground);
	// Nothing measured yet (no compute()): -1, the d_pth form.
	EXPECT_EQ(ism.floorOffset(Eigen::Vector3d(0, 0, 1), 3, 0, 0), -1.0);
}

TEST(IsmFormulas, BinomialTailAndNormalTail)
{
	// P(X >= k), X ~ Binomial(n, p), by hand.
	EXPECT_DOUBLE_EQ(ism::binomialTail(5, 0.3, 0), 1.0);
	EXPECT_NEAR(ism::binomialTail(2, 0.5, 1), 0.75, 1e-15);  // 1 - 0.5^2
	EXPECT_NEAR(ism::binomialTail(2, 0.5, 2), 0.25, 1e-15);
	EXPECT_NEAR(ism::binomialTail(3, 0.1, 2), 0.028, 1e-15);  // 3 * 0.01 * 0.9 + 0.001
	EXPECT_DOUBLE_EQ(ism::binomialTail(3, 0.1, 4), 0.0);      // k > n
	EXPECT_DOUBLE_EQ(ism::binomialTail(30, 0.0, 1), 0.0);
	// Standard normal tail (tables): P(Z < -3) = 0.0013499, P(Z < -2) = 0.0227501.
	EXPECT_NEAR(ism::normalTail(3.0), 0.0013499, 1e-7);
	EXPECT_NEAR(ism::normalTail(2.0), 0.0227501, 1e-7);
	EXPECT_NEAR(ism::normalTail(0.0), 0.5, 1e-15);
}

TEST(IsmFormulas, KthSmallestIsTheValueASortPutsThere)
{
	// By hand: {0.5, 0.1, 0.4, 0.2, 0.3} sorted is {0.1, 0.2, 0.3, 0.4, 0.5}.
	std::vector<float> five{0.5f, 0.1f, 0.4f, 0.2f, 0.3f};
	EXPECT_EQ(ism::kthSmallest(five.data(), 5, 2), 0.3f);
	// Long enough for the partition rounds (more than 16 values): random
	// values, many equal ones (a pivot repeated), ascending, descending and all
	// equal; every k against a sorted copy.
	std::mt19937 rng(7);
	std::uniform_real_distribution<float> u(0.f, 0.05f);
	std::uniform_int_distribution<int> few(0, 3);
	for (int kind = 0; kind < 5; kind++)
		for (size_t n : {17u, 40u, 301u})
		{
			std::vector<float> v(n);
			for (size_t i = 0; i < n; i++)
				v[i] = kind == 0   ? u(rng)
					   : kind == 1 ? 0.01f * float(few(rng))
					   : kind == 2 ? float(i)
					   : kind == 3 ? float(n - i)
								   : 0.02f;
			std::vector<float> sorted = v;
			std::sort(sorted.begin(), sorted.end());
			for (size_t k = 0; k < n; k++)
			{
				std::vector<float> w = v;
				ASSERT_EQ(ism::kthSmallest(w.data(), n, k), sorted[k]) << "kind " << kind << " n " << n << " k " << k;
			}
		}
}

namespace
{
// One cell at (1.025, 0.025) seen from (0, 0, 1) over the floor z = 0, the
// noise model alone (nothing measured): the deep-sample threshold by hand.
// r = |(1.025, 0.025, 0) - (0, 0, 1)| = sqrt(1.050625 + 0.000625 + 1) =
// 1.432219 (the cells' means of a few mm below 0 move it by < 3 mm, which
// moves T by < 0.01 mm); one sample's vertical noise sigma = (0.0012 +
// 0.0019 r^2) / r = 0.0050974 / 1.432219 = 0.0035591; tau = d_pth / 3 = 0.01;
// s = sqrt(sigma^2 + tau^2) = 0.0106145; T = max(0.02, 3 s) = 0.0318436 for a
// camera whose samples share part of their error (sharedNoise() below); with
// independent samples (the default camera) T is traversable_step = 0.02.
constexpr double kDeepX = 1.025, kDeepY = 0.025;
double handDeepThreshold()
{
	const double r = std::sqrt(1.025 * 1.025 + 0.025 * 0.025 + 1.0);
	const double sigma = (0.0012 + 0.0019 * r * r) / r;
	return std::max(0.02, 3.0 * std::sqrt(sigma * sigma + 0.01 * 0.01));
}
/** The D435's noise preset: a correlated part, so the deep-sample threshold
 * is max(traversable_step, 3 s). (The vertical sigma of these tests stays the
 * IsmParams model's: the camera's noise only says whether samples share an
 * error, and feeds range_smear.) */
void shareNoise(InverseSensorModel& ism) { ism.setCameraNoise(cameraNoisePreset(CameraModel::D435), 600); }
IsmParams deepParams()
{
	IsmParams p;
	p.measure_floor_noise = false;   // the model's sigma
	p.measure_floor_offset = false;  // tau = d_pth / 3
	return p;
}
/** A frame whose one cell holds `nFloor` samples at z = 0 and the `deep` ones. */
ElevationGrid deepCellFrame(int nFloor, const std::vector<float>& deep, BinnedPoints& b, bool outlierFilter = false)
{
	ElevationGrid grid;
	b.clear();
	for (int i = 0; i < nFloor; i++) grid.binPoint(kDeepX, kDeepY, 0.f, b);
	for (float z : deep) grid.binPoint(kDeepX, kDeepY, z, b);
	OutlierFilterParams f;
	f.enabled = outlierFilter;
	grid.insert(b, f);
	return grid;
}
}  // namespace

TEST(InverseSensorModel, DeepSamplesBeyondTheFloorNoiseMakeADrop)
{
	// Issue #13 item 3: a hole's far wall puts many samples a little below the
	// floor into a cell whose mean and z_min stay inside their bands.
	const double T = handDeepThreshold();
	ASSERT_NEAR(T, 0.0318436, 1e-6);
	const float below = float(-T - 0.001), above = float(-T + 0.001);
	InverseSensorModel ism(deepParams());
	shareNoise(ism);
	IsmStats st;
	BinnedPoints b;
	auto classOf = [&](const ElevationGrid& f, const BinnedPoints* samples) {
		ism.compute(f, handDetection(kFloor), {0, 0, 1}, 5.0, st, samples);
		return ism.classes()[f.geometry().index(f.geometry().ix(kDeepX), f.geometry().iy(kDeepY))];
	};
	// 27 floor samples and 3 at -3.28 cm. One-sample band: d_pth + 3 sigma =
	// 0.03 + 0.0106772 = 0.0406772 > 0.0328; mean -0.00328, band of the mean
	// 0.03 + 0.0106772 / sqrt(30) = 0.0319: floor by both. Deep samples: k = 3
	// of n = 30 with p0 = P(Z < -3) = 0.0013499 (T = 3 s here); P(X >= 3) ~
	// C(30, 3) p0^3 = 4060 * 2.4598e-9 = 1.0e-5 (exactly 0.97e-5) < 0.0013499: a drop.
	const ElevationGrid three = deepCellFrame(27, {below, below, below}, b);
	EXPECT_EQ(classOf(three, &b), VoxelClass::Drop);
	EXPECT_EQ(st.deep_drops, 1u);
	EXPECT_EQ(st.drop, 1u);
	EXPECT_EQ(st.ground, 0u);
	EXPECT_GT(ism.evidence()[three.geometry().index(three.geometry().ix(kDeepX), three.geometry().iy(kDeepY))], 0.5f);
	EXPECT_NEAR(ism::binomialTail(30, ism::normalTail(3.0), 3), 1.0e-5, 0.1e-5);
	// Without the frame's samples, or with the test off: z_min and mean only.
	EXPECT_EQ(classOf(three, nullptr), VoxelClass::Ground);
	IsmParams off = deepParams();
	off.deep_sample_test = false;
	InverseSensorModel noDeep(off);
	shareNoise(noDeep);
	noDeep.compute(three, handDetection(kFloor), {0, 0, 1}, 5.0, st, &b);
	EXPECT_EQ(st.ground, 1u);
	EXPECT_EQ(st.deep_drops, 0u);

	// 1 mm above -T the samples do not count.
	const ElevationGrid shallow = deepCellFrame(27, {above, above, above}, b);
	EXPECT_EQ(classOf(shallow, &b), VoxelClass::Ground);
	// Two deep samples are fewer than min_obstacle_points = 3 (a spike pair).
	const ElevationGrid two = deepCellFrame(28, {below, below}, b);
	EXPECT_EQ(classOf(two, &b), VoxelClass::Ground);
}

TEST(InverseSensorModel, WithIndependentSamplesTheDeepThresholdIsTheTraversableStep)
{
	// The default camera's samples are independent: the binomial tail is
	// exact at any threshold, and T = traversable_step = 0.02 counts the most
	// of a hole's wall. By hand (the cell of handDeepThreshold: s =
	// 0.0106145): p0 = Phi(-0.02 / 0.0106145) = Phi(-1.884220) = 0.029768.
	// Among n = 30: P(X >= 5) = 0.00179 > Phi(-3) = 0.00135 (floor), P(X >= 6)
	// = 0.000223 < 0.00135 (a drop). Samples at -0.021, 1 mm below T and
	// 1.1 cm above the 3 s threshold (0.0318) that a shared-noise camera uses.
	const double p0 = ism::normalTail(0.02 / 0.0106145);
	EXPECT_NEAR(p0, 0.029768, 1e-6);
	EXPECT_NEAR(ism::binomialTail(30, p0, 5), 0.00179, 0.00001);
	EXPECT_NEAR(ism::binomialTail(30, p0, 6), 0.000223, 0.000001);
	InverseSensorModel ism(deepParams());
	IsmStats st;
	BinnedPoints b;
	const ElevationGrid five = deepCellFrame(25, std::vector<float>(5, -0.021f), b);
	ism.compute(five, handDetection(kFloor), {0, 0, 1}, 5.0, st, &b);
	EXPECT_EQ(st.deep_drops, 0u);
	EXPECT_EQ(st.ground, 1u);
	const ElevationGrid six = deepCellFrame(24, std::vector<float>(6, -0.021f), b);
	ism.compute(six, handDetection(kFloor), {0, 0, 1}, 5.0, st, &b);
	EXPECT_EQ(st.deep_drops, 1u);
	EXPECT_EQ(st.drop, 1u);
	// 1 mm above T, the same six do not count.
	const ElevationGrid shallow = deepCellFrame(24, std::vector<float>(6, -0.019f), b);
	ism.compute(shallow, handDetection(kFloor), {0, 0, 1}, 5.0, st, &b);
	EXPECT_EQ(st.deep_drops, 0u);
	// A camera with shared noise keeps T = 3 s = 0.0318: the six lie above it.
	InverseSensorModel shared(deepParams());
	shareNoise(shared);
	shared.compute(six, handDetection(kFloor), {0, 0, 1}, 5.0, st, &b);
	EXPECT_EQ(st.deep_drops, 0u);
	EXPECT_EQ(st.ground, 1u);
}

TEST(IsmFormulas, ChiSquareQuantileByTheCubeRoot)
{
	// Wilson-Hilferty at z = 3 (upper tail Phi(-3) = 0.0013499), 29 degrees
	// of freedom: v = 2 / (9 * 29) = 0.0076628, q = 1 - v + 3 sqrt(v) = 1 -
	// 0.0076628 + 3 * 0.0875376 = 1.2549500, 29 q^3 = 29 * 1.9764203 = 57.3162
	// (the exact quantile, by the incomplete gamma function, is 57.2253).
	EXPECT_FALSE(ism::chiSquareAbove(57.31, 29, 3.0));
	EXPECT_TRUE(ism::chiSquareAbove(57.32, 29, 3.0));
	// 3 degrees of freedom: v = 0.0740741, q = 1 - v + 3 * 0.2721655 =
	// 1.7424224, 3 q^3 = 3 * 5.2899 = 15.870 (exact 15.631).
	EXPECT_FALSE(ism::chiSquareAbove(15.86, 3, 3.0));
	EXPECT_TRUE(ism::chiSquareAbove(15.88, 3, 3.0));
	EXPECT_FALSE(ism::chiSquareAbove(1e9, 0, 3.0));  // one sample has no spread
}

TEST(InverseSensorModel, RaisedSamplesSpreadOverMoreThanOneSurfaceMakeAnObstacle)
{
	// Issue #27's cable far away: a cell holds the floor and a low object's
	// face, seen as rows from 0 up, while its mean and top stay inside their
	// bands. The cell of handDeepThreshold, a Kinect One (time of flight:
	// independent samples; its vertical sigma stays the IsmParams model's):
	// sigma = 0.0035591, s = 0.0106145, T = traversable_step = 0.02, p0 =
	// Phi(-0.02 / 0.0106145) = 0.029768 (as for the deep samples).
	// 24 samples at 0 and 6 at 0.021: top 0.021 < one-sample band 0.0406772,
	// |mean| = 6 * 0.021 / 30 = 0.0042 < d_pth: floor by both. Count: k = 6 of
	// 30 above T, P(X >= 6) = 0.000223 < Phi(-3) = 0.0013499. Spread: var =
	// 6 * 0.021^2 / 30 - 0.0042^2 = 0.0000882 - 0.00001764 = 0.00007056, N var
	// / sigma^2 = 30 * 0.00007056 / 0.0035591^2 = 167.1 > 57.316 (29 degrees
	// of freedom, ChiSquareQuantileByTheCubeRoot): an obstacle.
	const auto timeOfFlight = [](InverseSensorModel& m) {
		m.setCameraNoise(cameraNoisePreset(CameraModel::KinectOne), 600);
	};
	InverseSensorModel ism(deepParams());
	timeOfFlight(ism);
	IsmStats st;
	BinnedPoints b;
	auto classOf = [&](InverseSensorModel& m, const ElevationGrid& f) {
		m.compute(f, handDetection(kFloor), {0, 0, 1}, 5.0, st, &b);
		return m.classes()[f.geometry().index(f.geometry().ix(kDeepX), f.geometry().iy(kDeepY))];
	};
	const ElevationGrid face = deepCellFrame(24, std::vector<float>(6, 0.021f), b);
	EXPECT_EQ(classOf(ism, face), VoxelClass::Obstacle);
	EXPECT_EQ(st.raised_obstacles, 1u);
	EXPECT_EQ(st.obstacle, 1u);
	EXPECT_EQ(st.ground, 0u);
	EXPECT_GT(ism.evidence()[face.geometry().index(face.geometry().ix(kDeepX), face.geometry().iy(kDeepY))], 0.5f);
	// Switched off, or a camera whose samples share part of their error (the
	// count is no binomial there), or one of unknown noise: the floor it was.
	IsmParams off = deepParams();
	off.raised_sample_test = false;
	InverseSensorModel noRaised(off);
	timeOfFlight(noRaised);
	EXPECT_EQ(classOf(noRaised, face), VoxelClass::Ground);
	EXPECT_EQ(st.raised_obstacles, 0u);
	InverseSensorModel shared(deepParams());
	shareNoise(shared);
	EXPECT_EQ(classOf(shared, face), VoxelClass::Ground);
	InverseSensorModel unknown(deepParams());
	unknown.setCameraNoise(cameraNoisePreset(CameraModel::Custom), 600);
	EXPECT_EQ(classOf(unknown, face), VoxelClass::Ground);
	// 5 such samples: P(X >= 5) = 0.00179 > Phi(-3), though they spread as
	// much (N var / sigma^2 = 145.1): floor.
	const ElevationGrid five = deepCellFrame(25, std::vector<float>(5, 0.021f), b);
	EXPECT_EQ(classOf(ism, five), VoxelClass::Ground);
	// 1 mm below T the six do not count.
	const ElevationGrid low = deepCellFrame(24, std::vector<float>(6, 0.019f), b);
	EXPECT_EQ(classOf(ism, low), VoxelClass::Ground);
	// One surface 2.1 cm up, as a ramp's cell where no patch applies: 15
	// samples at 0.018 and 15 at 0.024 (mean 0.021 < d_pth, floor by the
	// mean test). All 15 at 0.024 lie above T (P(X >= 15) is ~1e-14), but
	// they spread no more than one sample's noise: var = 0.003^2, N var /
	// sigma^2 = 30 * 0.000009 / 0.0035591^2 = 21.3 < 57.316: floor.
	std::vector<float> ramp(15, 0.018f);
	ramp.insert(ramp.end(), 15, 0.024f);
	const ElevationGrid plane = deepCellFrame(0, ramp, b);
	EXPECT_EQ(classOf(ism, plane), VoxelClass::Ground);
	EXPECT_EQ(st.raised_obstacles, 0u);
}

TEST(InverseSensorModel, DeepSampleCountIsJudgedAgainstTheCellsSampleCount)
{
	// The same 3 deep samples among n = 300: floor noise gives P(X >= 3) with
	// p0 = 0.0013499: (1 - p0)^300 = exp(300 ln(1 - p0)) = 0.66685 = P(0),
	// P(1) = 300 p0 / (1 - p0) P(0) = 0.27041, P(2) = 299/2 p0 / (1 - p0) P(1)
	// = 0.054646; P(X >= 3) = 1 - 0.99191 = 0.0081 > 0.0013499: floor.
	// Five: P(X >= 5) ~ 6e-5 (Poisson, lambda = 0.405): a drop.
	EXPECT_NEAR(ism::binomialTail(300, ism::normalTail(3.0), 3), 0.0081, 0.0001);
	const float below = float(-handDeepThreshold() - 0.001);
	InverseSensorModel ism(deepParams());
	shareNoise(ism);
	IsmStats st;
	BinnedPoints b;
	const ElevationGrid three = deepCellFrame(297, std::vector<float>(3, below), b);
	ism.compute(three, handDetection(kFloor), {0, 0, 1}, 5.0, st, &b);
	EXPECT_EQ(st.deep_drops, 0u);
	EXPECT_EQ(st.ground, 1u);
	const ElevationGrid five = deepCellFrame(295, std::vector<float>(5, below), b);
	ism.compute(five, handDetection(kFloor), {0, 0, 1}, 5.0, st, &b);
	EXPECT_EQ(st.deep_drops, 1u);
	EXPECT_EQ(st.drop, 1u);
}

TEST(InverseSensorModel, ACellThatSitsLowAsAWholeHasNoDeepDropWithAStereoCamera)
{
	// A stereo camera's samples of one matching window share part of their
	// error, so a whole cell can sit low (on a ramp, the plane's misfit adds
	// to it) and has samples below -T for that reason: 24 at -0.026 and 6 at
	// -0.0328.
	// By hand (the cell of DeepSamplesBeyondTheFloorNoiseMakeADrop, sensor at
	// (0, 0, 1) over z = 0, the model's noise): mean dMean = (24 * -0.026 + 6 *
	// -0.0328) / 30 = -0.02736; r = sqrt(1.025^2 + 0.025^2 + 1.02736^2) =
	// 1.451454; sigma = (0.0012 + 0.0019 r^2) / r = 0.0035845; s = sqrt(sigma^2
	// + 0.01^2) = 0.0106230; T = 3 s = 0.0318691; one-sample band 0.03 + 3 sigma
	// = 0.0407536 > 0.0328, the mean's band 0.03 + 0.0107536 / sqrt(30) =
	// 0.0319633 > 0.02736: ground by both; 6 samples below -T.
	// From the plane's noise alone, p0 = Phi(-3) = 0.0013499 and P(X >= 6 of
	// 30) = 3.5e-12: a drop. From the cell's own level, a sample lies below -T
	// with p0 = Phi(-(T + dMean) / sigma) = Phi(-1.2579) = 0.10421, and P(X >= 6
	// of 30) = 0.0857 > 0.0013499: no drop (the larger p0 is taken).
	const double pLevel = ism::normalTail((0.0318691 - 0.02736) / 0.0035845);
	EXPECT_NEAR(pLevel, 0.10421, 1e-4);
	EXPECT_NEAR(ism::binomialTail(30, pLevel, 6), 0.0857, 2e-4);
	EXPECT_NEAR(ism::binomialTail(30, ism::normalTail(3.0), 6), 3.5e-12, 0.1e-12);
	IsmStats st;
	BinnedPoints b;
	std::vector<float> samples(24, -0.026f);
	samples.insert(samples.end(), 6, -0.0328f);
	const ElevationGrid low = deepCellFrame(0, samples, b);
	// A time-of-flight camera (independent samples, the default): T = 0.02,
	// all 30 samples lie below it, p0 = Phi(-0.02 / s) = 0.0299: a drop.
	InverseSensorModel tof(deepParams());
	tof.compute(low, handDetection(kFloor), {0, 0, 1}, 5.0, st, &b);
	EXPECT_EQ(st.deep_drops, 1u);
	// The D435 (a correlated part in its noise): no drop.
	InverseSensorModel ism(deepParams());
	ism.setCameraNoise(cameraNoisePreset(CameraModel::D435), 600);
	ism.compute(low, handDetection(kFloor), {0, 0, 1}, 5.0, st, &b);
	EXPECT_EQ(st.deep_drops, 0u);
	EXPECT_EQ(st.ground, 1u);
	// The same 6 deep samples in a cell that sits on the floor (24 at 0: mean
	// -0.00656, (T + dMean) / sigma = 7.05, p0 = Phi(-3) again): a drop.
	std::vector<float> onFloor(24, 0.f);
	onFloor.insert(onFloor.end(), 6, -0.0328f);
	const ElevationGrid hole = deepCellFrame(0, onFloor, b);
	ism.compute(hole, handDetection(kFloor), {0, 0, 1}, 5.0, st, &b);
	EXPECT_EQ(st.deep_drops, 1u);
}

TEST(InverseSensorModel, DeepSamplesRejectedByTheThreeSigmaRuleDoNotCount)
{
	// 60 floor samples, 2 at -T - 1 mm (about -0.0328) and 3 spikes at -0.3.
	// 3-sigma rule over all 65: mean = (-0.0656 - 0.9) / 65 = -0.014855,
	// E[z^2] = (2 * 0.0010787 + 3 * 0.09) / 65 = 0.0041870, var = 0.0041870 -
	// 0.0002207 = 0.0039663, std 0.062979, band +-0.18894: the spikes (0.285
	// from the mean) go, the two (0.018) stay. Counted: 2 < 3, floor; the 5
	// of the unfiltered samples would have made it a drop.
	const float below = float(-handDeepThreshold() - 0.001);
	InverseSensorModel ism(deepParams());
	shareNoise(ism);
	IsmStats st;
	BinnedPoints b;
	const ElevationGrid f = deepCellFrame(60, {below, below, -0.3f, -0.3f, -0.3f}, b, true);
	const ElevationCell& c = f.cell(f.geometry().index(f.geometry().ix(kDeepX), f.geometry().iy(kDeepY)));
	ASSERT_EQ(c.count, 62u);
	ASSERT_FLOAT_EQ(c.z_min, below);
	ism.compute(f, handDetection(kFloor), {0, 0, 1}, 5.0, st, &b);
	EXPECT_EQ(st.deep_drops, 0u);
	EXPECT_EQ(st.ground, 1u);
	// Control: the same 60 + 2 with a third sample at -T - 1 mm is a drop.
	const ElevationGrid g3 = deepCellFrame(60, {below, below, below, -0.3f, -0.3f, -0.3f}, b, true);
	ism.compute(g3, handDetection(kFloor), {0, 0, 1}, 5.0, st, &b);
	EXPECT_EQ(st.deep_drops, 1u);
}

TEST(InverseSensorModel, ASpikeAmongFloorSamplesIsNoObstacle)
{
	// A cell of 20 floor samples and spikes at +0.3 m (or -0.3 m), no 3-sigma
	// rule: its top (bottom) is far beyond the band (0.0407, see
	// handDeepThreshold), so the cell is an obstacle (drop) by z_max (z_min).
	// With the frame's samples an obstacle or a drop counts only if
	// min_obstacle_points = 3 of them lie beyond the band (and a drop casts
	// its ray with as many).
	ASSERT_EQ(deepParams().min_obstacle_points, 3);
	InverseSensorModel ism(deepParams());
	IsmStats st;
	BinnedPoints b;
	const ElevationGrid one = deepCellFrame(20, {0.3f}, b);
	const uint32_t cell = uint32_t(one.geometry().index(one.geometry().ix(kDeepX), one.geometry().iy(kDeepY)));
	ism.compute(one, handDetection(kFloor), {0, 0, 1}, 5.0, st, &b);
	EXPECT_EQ(ism.classes()[cell], VoxelClass::Obstacle);
	EXPECT_EQ(st.sparse, 1u);
	EXPECT_EQ(st.obstacle, 0u);
	EXPECT_EQ(ism.evidence()[cell], 0.5f) << "one spike: no evidence";
	ism.compute(one, handDetection(kFloor), {0, 0, 1}, 5.0, st, nullptr);
	EXPECT_EQ(st.obstacle, 1u) << "without the samples: the cell count (21) decides";
	const ElevationGrid two = deepCellFrame(20, {0.3f, 0.31f}, b);
	ism.compute(two, handDetection(kFloor), {0, 0, 1}, 5.0, st, &b);
	EXPECT_EQ(st.sparse, 1u);
	EXPECT_EQ(st.obstacle, 0u) << "two spikes above: no evidence";
	const ElevationGrid three = deepCellFrame(20, {0.3f, 0.31f, 0.32f}, b);
	ism.compute(three, handDetection(kFloor), {0, 0, 1}, 5.0, st, &b);
	EXPECT_EQ(st.obstacle, 1u);
	EXPECT_GT(ism.evidence()[cell], 0.5f);

	const ElevationGrid down1 = deepCellFrame(20, {-0.3f}, b);
	ism.compute(down1, handDetection(kFloor), {0, 0, 1}, 5.0, st, &b);
	EXPECT_EQ(st.drop, 0u);
	EXPECT_EQ(st.sparse, 1u);
	const ElevationGrid down2 = deepCellFrame(20, {-0.3f, -0.31f}, b);
	ism.compute(down2, handDetection(kFloor), {0, 0, 1}, 5.0, st, &b);
	EXPECT_EQ(st.drop, 0u);
	EXPECT_EQ(st.sparse, 1u);
	EXPECT_EQ(ism.evidence()[cell], 0.5f) << "two spikes below: no evidence";
	const ElevationGrid down3 = deepCellFrame(20, {-0.3f, -0.31f, -0.32f}, b);
	ism.compute(down3, handDetection(kFloor), {0, 0, 1}, 5.0, st, &b);
	EXPECT_EQ(st.drop, 1u);
	EXPECT_GT(ism.evidence()[cell], 0.5f);
	EXPECT_GT(st.drop_ray_cells, 0u) << "three below: the ray is cast";
}

TEST(InverseSensorModel, ADropTakesTheObstacleCountBelowAPatchAndBelowTheFloor)
{
	// The floor z = 0 and a landing patch z = 0.20 with a node at the cell
	// (kDeepX, kDeepY). The cell's samples at z = 0.12 are 0.08 below the
	// landing and 0.12 above the floor: it is judged against the landing (the
	// plane it fits best) and is a drop there (0.08 > the ~4 cm band). Below
	// a patch that is what the far side of a ramp looks like at grazing
	// incidence, so it takes min_obstacle_points = 3 samples; so do samples
	// 0.08 below the floor plane (a drop below the ground plane took 2 until
	// 2026-11-27: doc/rules.md, I12).
	GroundDetection det = handDetection(kFloor);
	det.planes.push_back(Plane{0, 0, 1, -0.20});
	det.plane_support.push_back(10);
	GroundNode node;
	node.x = float(kDeepX);
	node.y = float(kDeepY);
	node.z = 0.20f;
	node.plane_id = 1;
	det.nodes.push_back(node);
	InverseSensorModel ism(deepParams());
	IsmStats st;
	BinnedPoints b;
	const ElevationGrid two = deepCellFrame(0, {0.12f, 0.12f}, b);
	const uint32_t cell = uint32_t(two.geometry().index(two.geometry().ix(kDeepX), two.geometry().iy(kDeepY)));
	ism.compute(two, det, {0, 0, 1}, 5.0, st, &b);
	EXPECT_EQ(ism.classes()[cell], VoxelClass::Drop);
	EXPECT_EQ(st.sparse, 1u);
	EXPECT_EQ(ism.evidence()[cell], 0.5f) << "two samples below a patch: no evidence";
	const ElevationGrid three = deepCellFrame(0, {0.12f, 0.12f, 0.12f}, b);
	ism.compute(three, det, {0, 0, 1}, 5.0, st, &b);
	EXPECT_EQ(st.drop, 1u);
	EXPECT_GT(ism.evidence()[cell], 0.5f);
	const ElevationGrid belowFloor = deepCellFrame(0, {-0.08f, -0.08f}, b);
	ism.compute(belowFloor, det, {0, 0, 1}, 5.0, st, &b);
	EXPECT_EQ(ism.classes()[cell], VoxelClass::Drop);
	EXPECT_EQ(st.drop, 0u);
	EXPECT_EQ(ism.evidence()[cell], 0.5f) << "two samples below the floor plane: no evidence";
	const ElevationGrid belowFloor3 = deepCellFrame(0, {-0.08f, -0.08f, -0.08f}, b);
	ism.compute(belowFloor3, det, {0, 0, 1}, 5.0, st, &b);
	EXPECT_EQ(st.drop, 1u);
	EXPECT_GT(ism.evidence()[cell], 0.5f) << "three samples below the floor plane: a drop";
}

TEST(InverseSensorModel, PatchAppliesWithinTheSupportRadiusOfItsNodes)
{
	// The default frame grid: x, y from -5 m, 5 cm cells; support in blocks
	// of 4 cells (0.2 m). One node of patch 1 at (1.025, 0.025): its block is
	// floor((1.025 + 5) / 0.2) = 30 along x, floor((0.025 + 5) / 0.2) = 25
	// along y; plane_support_radius 0.4 m = ceil(0.4 / 0.2) = 2 blocks, so the
	// patch applies on blocks 28-32 x 23-27: cells 112-131 x 92-111, i.e.
	// x in [0.6, 1.6) m, y in [-0.4, 0.6) m.
	GroundDetection det = handDetection(kFloor);
	det.planes.push_back(Plane{0, 0, 1, -0.20});
	det.plane_support.push_back(10);
	GroundNode node;
	node.x = 1.025f;
	node.y = 0.025f;
	node.z = 0.20f;
	node.plane_id = 1;
	det.nodes.push_back(node);
	ElevationGrid grid;
	BinnedPoints b;
	gamtest::sampleColumns(grid, 1.0, 1.05, 0.0, 0.05, 0.2, 0.2, 0.1, b);
	gamtest::insertAll(grid, b);
	InverseSensorModel ism;
	IsmStats st;
	ism.compute(grid, det, {0, 0, 1}, 5.0, st);
	const GridGeometry& g = grid.geometry();
	auto at = [&](double x, double y) { return ism.patchApplies(uint32_t(g.index(g.ix(x), g.iy(y))), g.nx); };
	EXPECT_TRUE(at(1.025, 0.025));
	EXPECT_TRUE(at(0.625, -0.375));  // cells 112, 92: the corner block
	EXPECT_TRUE(at(1.575, 0.575));   // cells 131, 111
	EXPECT_FALSE(at(1.625, 0.025));  // cell 132: block 33
	EXPECT_FALSE(at(0.575, 0.025));  // cell 111: block 27
	EXPECT_FALSE(at(1.025, 0.625));  // cell 112 along y: block 28
	// Without patches (one plane, or local_planes = false) nothing applies.
	IsmParams noLocal;
	noLocal.local_planes = false;
	InverseSensorModel ism2(noLocal);
	ism2.compute(grid, det, {0, 0, 1}, 5.0, st);
	EXPECT_FALSE(ism2.patchApplies(uint32_t(g.index(g.ix(1.025), g.iy(0.025))), g.nx));
}

namespace
{
// Frame of test ISM-1 (grid -5..5 m, 5 cm). Sensor at (0, 0, 1), ground z = 0.
bool isBox(double x, double y) { return inRect(x, y, 1.2, 1.3, 0.5, 0.6); }     // 2x2 cells
bool isHole(double x, double y) { return inRect(x, y, 1.5, 1.6, -0.5, -0.4); }  // 2x2 cells
bool isFloor(double x, double y) { return inRect(x, y, 0.5, 2.0, -1.0, 1.0) && !isBox(x, y) && !isHole(x, y); }
bool isBeam(double x, double y) { return inRect(x, y, 0.7, 0.8, 1.2, 1.3); }
bool isShelf(double x, double y) { return inRect(x, y, 0.7, 0.8, -1.3, -1.2); }
bool isFar(double x, double y) { return inRect(x, y, 4.2, 4.3, 0.0, 0.1); }

ElevationGrid sceneFrame()
{
	ElevationGrid grid;
	std::mt19937 rng(1);
	BinnedPoints b;
	auto zero = [](double, double) { return 0.0; };
	gamtest::sampleSurfaceIf(grid, isFloor, zero, 2, 0.0, rng, b);       // 4 pts at z = 0
	gamtest::sampleColumns(grid, 1.2, 1.3, 0.5, 0.6, 0.0, 0.4, 0.1, b);  // 5 pts, span 0.4
	gamtest::sampleSurfaceIf(
		grid, isHole, [](double, double) { return -0.3; }, 1, 0.0, rng, b);
	gamtest::sampleColumns(grid, 0.7, 0.8, 1.2, 1.3, 1.9, 2.3, 0.1, b);    // above 1.8
	gamtest::sampleColumns(grid, 0.7, 0.8, -1.3, -1.2, 1.0, 2.5, 0.1, b);  // 16 pts, span 1.5
	gamtest::sampleColumns(grid, 4.2, 4.3, 0.0, 0.1, 0.0, 0.4, 0.1, b);
	gamtest::insertAll(grid, b);
	return grid;
}
}  // namespace

TEST(InverseSensorModel, EndToEndFloorBoxHoleBeamRange)
{
	const ElevationGrid frame = sceneFrame();
	const GridGeometry& g = frame.geometry();
	IsmParams p;
	p.min_obstacle_points = 1;  // the hole cells have one sample each (see LoneSamples... below)
	InverseSensorModel ism(p);
	IsmStats st;
	ism.compute(frame, handDetection(kFloor), {0, 0, 1}, 4.0, st);  // max range 4 m
	EXPECT_TRUE(st.applied);

	const double pBox = handObstacleP(5, 0.4, 0.05);   // rho 5000: 0.651016 (the beam's too)
	const double pHole = handObstacleP(1, 0.0, 0.05);  // rho 8000: 0.792423
	const double pShelf = handObstacleP(16, 1.5, 0.05);
	EXPECT_NEAR(pBox, 0.5 + 0.4 / (1 + std::exp(0.5)), 1e-12);
	EXPECT_NEAR(pHole, 0.5 + 0.4 / (1 + std::exp(-1.0)), 1e-12);

	size_t nFloor = 0, nBox = 0, nHole = 0, nBeam = 0, nShelf = 0, nFar = 0;
	for (int cy = 0; cy < g.ny; cy++)
		for (int cx = 0; cx < g.nx; cx++)
		{
			const double x = g.cx(cx), y = g.cy(cy);
			const size_t i = g.index(cx, cy);
			const float e = ism.evidence()[i];
			const VoxelClass k = ism.classes()[i];
			if (isFloor(x, y))
			{
				nFloor++;
				EXPECT_EQ(k, VoxelClass::Ground) << x << "," << y;
				EXPECT_FLOAT_EQ(e, 0.2f) << x << "," << y;  // 0.5 - K_g: on the plane
			}
			else if (isBox(x, y))
			{
				nBox++;
				EXPECT_EQ(k, VoxelClass::Obstacle);
				EXPECT_NEAR(e, pBox, 1e-6);
				EXPECT_GT(e, 0.5f);
			}
			else if (isHole(x, y))
			{
				nHole++;
				EXPECT_EQ(k, VoxelClass::Drop);
				EXPECT_NEAR(e, pHole, 1e-6);
				EXPECT_GT(e, 0.5f);
			}
			else if (isBeam(x, y))
			{
				// 1.9-2.3 m up, 5 samples: an obstacle to the ISM, which judges
				// the 2.5D map it is given (the pipeline does not project it:
				// GroundAwareGrid.OverheadBeamDoesNotBlockButATableDoes).
				nBeam++;
				EXPECT_EQ(k, VoxelClass::Obstacle);
				EXPECT_NEAR(e, pBox, 1e-6);
			}
			else if (isShelf(x, y))
			{
				nShelf++;
				EXPECT_EQ(k, VoxelClass::Obstacle);
				EXPECT_NEAR(e, pShelf, 1e-6);
			}
			else if (isFar(x, y))
			{
				nFar++;
				EXPECT_EQ(k, VoxelClass::OutOfRange);  // 4.2 m > max_range 4
				EXPECT_EQ(e, 0.5f);
			}
			else
			{
				ASSERT_EQ(k, VoxelClass::None) << x << "," << y;
				ASSERT_EQ(e, 0.5f) << x << "," << y;
			}
		}
	ASSERT_EQ(nFloor, 30u * 40u - 8u);
	ASSERT_EQ(nBox, 4u);
	ASSERT_EQ(nHole, 4u);
	ASSERT_EQ(nBeam, 4u);
	ASSERT_EQ(nShelf, 4u);
	ASSERT_EQ(nFar, 4u);
	EXPECT_EQ(st.ground, nFloor);
	EXPECT_EQ(st.obstacle, nBox + nBeam + nShelf);
	EXPECT_EQ(st.drop, nHole);
	EXPECT_EQ(st.out_of_range, nFar);
	// The hole's rays crossed the plane over observed floor: nothing to mark.
	EXPECT_EQ(st.drop_ray_cells, 0u);
	EXPECT_EQ(ism.evidenceCells().size(), nFloor + nBox + nBeam + nHole + nShelf);
	checkEvidenceBookkeeping(ism);

	// With a 5 m max range the far box counts.
	ism.setParams(IsmParams{});
	ism.compute(frame, handDetection(kFloor), {0, 0, 1}, 5.0, st);
	EXPECT_EQ(st.out_of_range, 0u);
	EXPECT_EQ(st.obstacle, nBox + nBeam + nShelf + nFar);
	EXPECT_GT(ism.evidence()[g.index(g.ix(4.25), g.iy(0.05))], 0.5f);
	checkEvidenceBookkeeping(ism);
}

TEST(InverseSensorModel, GroundEvidenceFollowsPlaneDistance)
{
	// The same floor against a plane 1 cm above it: d = -0.01 for every cell.
	const ElevationGrid frame = sceneFrame();
	InverseSensorModel ism;
	IsmStats st;
	ism.compute(frame, handDetection(Plane{0, 0, 1, -0.01}), {0, 0, 1}, 5.0, st);
	const GridGeometry& g = frame.geometry();
	const size_t i = g.index(g.ix(1.0), g.iy(0.0));
	EXPECT_EQ(ism.classes()[i], VoxelClass::Ground);
	EXPECT_NEAR(ism.evidence()[i], 0.5 - 0.3 * std::exp(-0.0001 / 0.04), 1e-6);  // 0.200749
}

TEST(InverseSensorModel, NoPlaneNeverInventsObstacles)
{
	const ElevationGrid frame = sceneFrame();
	InverseSensorModel ism;
	IsmStats st;
	// First a normal frame, so that there is evidence to forget.
	ism.compute(frame, handDetection(kFloor), {0, 0, 1}, 5.0, st);
	ASSERT_FALSE(ism.evidenceCells().empty());

	for (auto s :
		 {GroundDetection::Status::EmptyGrid, GroundDetection::Status::NoValidSeed,
		  GroundDetection::Status::TooFewNodes, GroundDetection::Status::NoConsensus})
	{
		// Even with a plane in the result, a failed detection produces nothing.
		ism.compute(frame, handDetection(kFloor, s), {0, 0, 1}, 5.0, st);
		EXPECT_FALSE(st.applied);
		EXPECT_TRUE(ism.evidenceCells().empty()) << GroundDetection::statusName(s);
		EXPECT_EQ(st.obstacle + st.ground + st.drop + st.out_of_range, 0u);
		for (float e : ism.evidence()) ASSERT_EQ(e, 0.5f);
		for (VoxelClass k : ism.classes()) ASSERT_EQ(k, VoxelClass::None);
	}
	// Status Ok but no plane: nothing either.
	GroundDetection none;
	none.status = GroundDetection::Status::Ok;
	ism.compute(frame, none, {0, 0, 1}, 5.0, st);
	EXPECT_FALSE(st.applied);
	EXPECT_TRUE(ism.evidenceCells().empty());

	// A real detection failure on a real grid: no floor near z = 0.
	ElevationGrid table;
	std::mt19937 rng(4);
	BinnedPoints b;
	gamtest::sampleSurface(
		table, -1, 1, -1, 1, [](double, double) { return 0.9; }, 2, 0.002, rng, b);
	gamtest::insertAll(table, b);
	RrtGroundDetector det;
	GroundDetection out;
	det.detect(table, {0, 0, 0}, out);
	ASSERT_EQ(out.status, GroundDetection::Status::NoValidSeed);
	ism.compute(table, out, {0, 0, 1}, 5.0, st);
	EXPECT_TRUE(ism.evidenceCells().empty());
}

namespace
{
// Downward step: upper floor z = 0 on x in [0.5, 1.5), unseen gap, lower floor
// z = -0.3 on x in [2.6, 3.5) (1 point per cell), y in [-0.5, 0.5); an
// observed floor patch inside the gap at x in [2.2, 2.3), y in [-0.1, 0.1).
bool isUpper(double x, double y) { return inRect(x, y, 0.5, 1.5, -0.5, 0.5); }
bool isLower(double x, double y) { return inRect(x, y, 2.6, 3.5, -0.5, 0.5); }
bool isPatch(double x, double y) { return inRect(x, y, 2.2, 2.3, -0.1, 0.1); }
ElevationGrid stepFrame(int lowerSamples = 1)
{
	ElevationGrid grid;
	std::mt19937 rng(1);
	BinnedPoints b;
	gamtest::sampleSurfaceIf(
		grid, isUpper, [](double, double) { return 0.0; }, 2, 0.0, rng, b);
	gamtest::sampleSurfaceIf(
		grid, isPatch, [](double, double) { return 0.0; }, 2, 0.0, rng, b);
	// lowerSamples samples per lower cell, at -0.30, -0.31, ...
	for (int k = 0; k < lowerSamples; k++)
		gamtest::sampleSurfaceIf(
			grid, isLower, [k](double, double) { return -0.3 - 0.01 * k; }, 1, 0.0, rng, b);
	gamtest::insertAll(grid, b);
	return grid;
}
}  // namespace

TEST(InverseSensorModel, DropRaysMarkCellsBetweenCrossingAndVoxel)
{
	const ElevationGrid frame = stepFrame();
	const GridGeometry& g = frame.geometry();
	IsmParams prm;
	IsmStats st;
	// By default a drop voxel needs 3 samples to count, and so to cast a ray:
	// these have one.
	InverseSensorModel strict(prm);
	strict.compute(frame, handDetection(kFloor), {0, 0, 1}, 5.0, st);
	EXPECT_EQ(st.drop, 0u);
	EXPECT_EQ(st.sparse, 18u * 20u);
	EXPECT_EQ(st.drop_ray_cells, 0u);
	prm.min_obstacle_points = 1;  // the lower floor has one sample per cell
	InverseSensorModel ism(prm);
	// Sensor 1 m above the plane at the origin: the ray to a voxel at (x, y,
	// -0.3) crosses z = 0 at 1/1.3 of the way, e.g. x = 2.625 -> 2.019 and
	// x = 3.475 -> 2.673.
	ism.compute(frame, handDetection(kFloor), {0, 0, 1}, 5.0, st);
	const double pDrop = handObstacleP(1, 0.0, 0.05);
	EXPECT_EQ(st.drop, 18u * 20u);
	EXPECT_GT(st.drop_ray_cells, 0u);

	for (int cy = g.iy(-0.1); cy <= g.iy(0.1); cy++)
		for (int cx = g.ix(1.5); cx < g.ix(2.6); cx++)
		{
			const double x = g.cx(cx), y = g.cy(cy);
			const float e = ism.evidence()[g.index(cx, cy)];
			if (isPatch(x, y))
			{
				// Observed ground keeps its free evidence under the rays.
				EXPECT_EQ(ism.classes()[g.index(cx, cy)], VoxelClass::Ground);
				EXPECT_FLOAT_EQ(e, 0.2f) << x << "," << y;
			}
			else if (x < 2.0)
			{
				EXPECT_EQ(e, 0.5f) << "before every crossing: " << x << "," << y;
			}
			else if (x > 2.1)
			{
				EXPECT_NEAR(e, pDrop, 1e-6) << "under the rays: " << x << "," << y;
			}
		}
	// The upper floor is untouched.
	for (int cy = g.iy(-0.45); cy <= g.iy(0.45); cy++)
		for (int cx = g.ix(0.55); cx <= g.ix(1.45); cx++) EXPECT_FLOAT_EQ(ism.evidence()[g.index(cx, cy)], 0.2f);
	// Nothing is marked where no ray went: beside the lower floor, or behind it.
	EXPECT_EQ(ism.evidence()[g.index(g.ix(2.3), g.iy(1.0))], 0.5f);
	EXPECT_EQ(ism.evidence()[g.index(g.ix(3.6), g.iy(0.0))], 0.5f);
	checkEvidenceBookkeeping(ism);

	// A sensor far outside the grid, 100 m behind it, 1 m up (max range
	// 200 m): each ray crosses the floor at x = -100 + (x + 100) / 1.3, about
	// -21 m, and only its last part (at most the grid's diagonal) lies in the
	// grid: the gap's cells (x 2.0-2.6, not seen) are under the rays, the
	// upper floor keeps its free evidence (seen as ground), nothing is
	// written outside the grid. (The fixed band d_pth: the range noise model
	// at 100 m would take the lower floor for floor.)
	IsmParams far = prm;
	far.noise_sigmas = 0;
	ism.setParams(far);
	ism.compute(frame, handDetection(kFloor), {-100, 0, 1}, 200.0, st);
	EXPECT_GT(st.drop_ray_cells, 0u);
	EXPECT_NEAR(ism.evidence()[g.index(g.ix(2.05), g.iy(0.2))], pDrop, 1e-6);
	EXPECT_NEAR(ism.evidence()[g.index(g.ix(2.55), g.iy(0.2))], pDrop, 1e-6);
	EXPECT_FLOAT_EQ(ism.evidence()[g.index(g.ix(1.0), g.iy(0.2))], 0.2f);
	checkEvidenceBookkeeping(ism);

	IsmParams p;
	p.min_obstacle_points = 1;
	// Disabled: the gap stays unknown, the drop voxels still count.
	p.drop_rays = false;
	ism.setParams(p);
	ism.compute(frame, handDetection(kFloor), {0, 0, 1}, 5.0, st);
	EXPECT_EQ(st.drop_ray_cells, 0u);
	EXPECT_EQ(st.drop, 18u * 20u);
	for (int cx = g.ix(1.5); cx < g.ix(2.6); cx++)
	{
		if (!isPatch(g.cx(cx), 0.025))
		{
			EXPECT_EQ(ism.evidence()[g.index(cx, g.iy(0.025))], 0.5f);
		}
	}
	EXPECT_NEAR(ism.evidence()[g.index(g.ix(3.0), g.iy(0.0))], pDrop, 1e-6);
}

TEST(InverseSensorModel, DropRayIsNotCastThroughAnObstacle)
{
	// Sensor at (0, 0, 1) over the floor z = 0, floor seen on x 0.5-2.0. Drop
	// voxels at x 3.10-3.15 (cell centre 3.125), 4 samples at -0.10: the
	// deepest sample's ray crosses the floor at t = 1 / 1.1, x = 3.125 / 1.1 =
	// 2.841, and would paint the unseen cells 2.85-3.10. With a box at x
	// 2.0-2.2 between, the ray passes over it at height 1 - 2.2 / 2.841 = 0.226
	// (its far edge, the first cell seen walking back from the crossing): a
	// 0.5 m box stops it (the crossing is in its shadow, where no sensor
	// looked), a 0.1 m box does not.
	auto frameWith = [](double boxTop) {
		ElevationGrid grid;
		std::mt19937 rng(1);
		BinnedPoints b;
		auto zero = [](double, double) { return 0.0; };
		gamtest::sampleSurfaceIf(
			grid, [&](double x, double y) { return inRect(x, y, 0.5, 2.0, -0.5, 0.5); }, zero, 2, 0.0, rng, b);
		if (boxTop > 0) gamtest::sampleColumns(grid, 2.0, 2.2, -0.5, 0.5, 0.0, boxTop, boxTop / 4, b);
		gamtest::sampleSurfaceIf(
			grid, [](double x, double y) { return inRect(x, y, 3.1, 3.15, -0.1, 0.1); },
			[](double, double) { return -0.1; }, 2, 0.0, rng, b);
		gamtest::insertAll(grid, b);
		return grid;
	};
	InverseSensorModel ism;
	IsmStats st;
	for (double boxTop : {0.0, 0.1})
	{
		const ElevationGrid f = frameWith(boxTop);
		const GridGeometry& g = f.geometry();
		ism.compute(f, handDetection(kFloor), {0, 0, 1}, 5.0, st);
		ASSERT_EQ(st.drop, 4u) << boxTop;
		EXPECT_EQ(st.drop_rays_unsupported, 0u) << boxTop;
		EXPECT_GT(st.drop_ray_cells, 0u) << boxTop;
		EXPECT_GT(ism.evidence()[g.index(g.ix(2.875), g.iy(0.025))], 0.5f) << boxTop;
		EXPECT_GT(ism.evidence()[g.index(g.ix(3.025), g.iy(0.025))], 0.5f) << boxTop;
	}
	const ElevationGrid shadow = frameWith(0.5);
	const GridGeometry& g = shadow.geometry();
	ism.compute(shadow, handDetection(kFloor), {0, 0, 1}, 5.0, st);
	ASSERT_EQ(st.drop, 4u);
	EXPECT_EQ(st.drop_rays_unsupported, 4u);
	EXPECT_EQ(st.drop_ray_cells, 0u);
	for (double x = 2.825; x < 3.1; x += 0.05) EXPECT_EQ(ism.evidence()[g.index(g.ix(x), g.iy(0.025))], 0.5f) << x;
}

TEST(InverseSensorModel, ADropCastsItsRayWithTheCountItCountsWith)
{
	// Default min_obstacle_points = 3: lower cells with 3 samples are drops
	// and cast rays; with 2 they are neither (a spike pair paints nothing);
	// with min_obstacle_points = 2 those are drops and cast rays.
	IsmParams p;
	ASSERT_EQ(p.min_obstacle_points, 3);
	InverseSensorModel ism(p);
	IsmStats st;
	const ElevationGrid three = stepFrame(3);
	ism.compute(three, handDetection(kFloor), {0, 0, 1}, 5.0, st);
	EXPECT_EQ(st.drop, 18u * 20u);
	EXPECT_GT(st.drop_ray_cells, 50u);
	const GridGeometry& g = three.geometry();
	// Span 0.02 < d_r: rho = 3 / 0.05^3 = 24000 -> P_rho = 1/(1+e^-9).
	const double p3 = 0.5 + 0.4 / (1 + std::exp(-9.0));
	EXPECT_NEAR(ism.evidence()[g.index(g.ix(2.4), g.iy(0.0))], p3, 1e-6);

	const ElevationGrid two = stepFrame(2);
	ism.compute(two, handDetection(kFloor), {0, 0, 1}, 5.0, st);
	EXPECT_EQ(st.drop, 0u);
	EXPECT_EQ(st.sparse, 18u * 20u);
	EXPECT_EQ(st.drop_ray_cells, 0u);
	EXPECT_EQ(ism.evidence()[g.index(g.ix(2.4), g.iy(0.0))], 0.5f);

	p.min_obstacle_points = 2;
	ism.setParams(p);
	ism.compute(two, handDetection(kFloor), {0, 0, 1}, 5.0, st);
	EXPECT_EQ(st.drop, 18u * 20u);
	EXPECT_GT(st.drop_ray_cells, 50u);
	// rho = 2 / 0.05^3 = 16000 -> P_rho = 1/(1+e^-(K_n rho - d_min)) = 1/(1+e^-5).
	const double p2 = 0.5 + 0.4 / (1 + std::exp(-5.0));
	EXPECT_NEAR(ism.evidence()[g.index(g.ix(2.4), g.iy(0.0))], p2, 1e-6);
}

TEST(InverseSensorModel, NeutralEvidenceIsNeverListed)
{
	// K_g = 0 and K_m = 0 (both valid) make every voxel say exactly 0.5:
	// evidenceCells() ("cells with evidence != 0.5") must stay empty, and the
	// drop rays must not list their cells once per ray.
	const ElevationGrid frame = stepFrame();
	IsmParams p;
	p.K_g = 0;
	p.K_m = 0;
	p.min_obstacle_points = 1;  // the lower cells have one sample: let them count and cast rays
	InverseSensorModel ism(p);
	IsmStats st;
	ism.compute(frame, handDetection(kFloor), {0, 0, 1}, 5.0, st);
	EXPECT_GT(st.ground, 0u);
	EXPECT_GT(st.drop, 0u);
	EXPECT_GT(st.drop_ray_cells, 0u);  // the rays did run (over the gap)
	EXPECT_TRUE(ism.evidenceCells().empty()) << ism.evidenceCells().size() << " cells listed";
	checkEvidenceBookkeeping(ism);

	// Only K_m = 0: the floor is listed (free), the drops and rays are not.
	p.K_g = 0.3;
	ism.setParams(p);
	ism.compute(frame, handDetection(kFloor), {0, 0, 1}, 5.0, st);
	EXPECT_EQ(ism.evidenceCells().size(), st.ground);
	checkEvidenceBookkeeping(ism);
}

TEST(InverseSensorModel, RampIsGroundOnlyWithLocalPlanes)
{
	ElevationGrid grid;
	std::mt19937 rng(21);
	gamtest::buildRamp(grid, rng);
	RrtGroundDetector det;
	GroundDetection out;
	det.detect(grid, {0, 0, 0}, out);
	ASSERT_EQ(out.status, GroundDetection::Status::Ok) << out.describe();
	ASSERT_GE(out.planes.size(), 2u);
	const GridGeometry& g = grid.geometry();
	const Eigen::Vector3d sensor(0, 0, 1);

	auto fractions = [&](bool local, double& ground, double& obstacle, double& floorGround) {
		IsmParams p;
		p.local_planes = local;
		InverseSensorModel ism(p);
		IsmStats st;
		ism.compute(grid, out, sensor, 5.0, st);
		size_t n = 0, ng = 0, no = 0, nf = 0, nfg = 0;
		for (uint32_t idx : grid.observedCells())
		{
			const int cx = int(idx % uint32_t(g.nx)), cy = int(idx / uint32_t(g.nx));
			const double x = g.cx(cx), y = g.cy(cy);
			if (x >= 2.0 && x < 2.9 && std::abs(y) < 2.0)
			{
				// Ramp 10.5..20 cm above the floor plane.
				n++;
				ng += ism.classes()[idx] == VoxelClass::Ground;
				no += ism.classes()[idx] == VoxelClass::Obstacle;
				if (ism.classes()[idx] == VoxelClass::Ground)
				{
					EXPECT_LT(ism.evidence()[idx], 0.5f);
				}
				if (ism.classes()[idx] == VoxelClass::Obstacle)
				{
					EXPECT_GT(ism.evidence()[idx], 0.5f);
				}
			}
			else if (x < 0.8 && x > -2.0 && std::abs(y) < 2.0)
			{
				nf++;
				nfg += ism.classes()[idx] == VoxelClass::Ground;
			}
		}
		ASSERT_GT(n, 500u);
		ground = double(ng) / n;
		obstacle = double(no) / n;
		floorGround = double(nfg) / nf;
	};
	double g1, o1, f1, g0, o0, f0;
	fractions(true, g1, o1, f1);
	fractions(false, g0, o0, f0);
	std::cout << "ISM ramp cells: local planes -> " << 100 * g1 << "% ground, " << 100 * o1
			  << "% obstacle; single plane -> " << 100 * g0 << "% ground, " << 100 * o0 << "% obstacle" << std::endl;
	EXPECT_GT(g1, 0.95);
	EXPECT_LT(o1, 0.05);
	EXPECT_GT(o0, 0.95);
	EXPECT_LT(g0, 0.05);
	// The flat floor is ground either way.
	EXPECT_GT(f1, 0.99);
	EXPECT_GT(f0, 0.99);
}

TEST(InverseSensorModel, LoneSamplesGiveNoObstacleEvidence)
{
	// The hole cells of the scene frame hold one sample each: with the default
	// min_obstacle_points = 3 they are classified but give no evidence, like a
	// depth spike; the 5-sample box still does.
	const ElevationGrid frame = sceneFrame();
	const GridGeometry& g = frame.geometry();
	IsmParams p;
	ASSERT_EQ(p.min_obstacle_points, 3);
	InverseSensorModel ism(p);
	IsmStats st;
	ism.compute(frame, handDetection(kFloor), {0, 0, 1}, 4.0, st);
	EXPECT_EQ(st.sparse, 4u);
	EXPECT_EQ(st.drop, 0u);
	EXPECT_EQ(ism.evidence()[g.index(g.ix(1.55), g.iy(-0.45))], 0.5f);
	EXPECT_GT(ism.evidence()[g.index(g.ix(1.25), g.iy(0.55))], 0.5f);
	p.min_obstacle_points = 0;
	EXPECT_THROW(InverseSensorModel{p}, std::invalid_argument);
}

TEST(InverseSensorModel, FloorNoiseIsMeasuredPerRangeBin)
{
	// Sensor 1 m above the floor plane z = 0 at the origin. Two floor strips
	// (|y| <= 0.1 m), each cell with the 4 samples +a, -a, +a, -a: mean 0,
	// sample std a (sqrt of (4 a^2) / 4 - 0^2).
	//   near: x in [0.5, 0.9): 3D range sqrt(x^2 + y^2 + 1) in [1.118, 1.35), a = 1 cm, 8 x 4 = 32 cells
	//   far:  x in [1.2, 1.7): 3D range in [1.56, 1.98),                a = 2 cm, 10 x 4 = 40 cells
	ElevationGrid frame(gamtest::makeGeometry(-1, -1, 0.05, 60, 40));
	const GridGeometry& g = frame.geometry();
	BinnedPoints pts;
	for (int iy = g.iy(-0.1 + 1e-6); iy < g.iy(0.1 - 1e-6) + 1; iy++)
		for (int ix = g.ix(0.5 + 1e-6); ix < g.ix(1.7 - 1e-6) + 1; ix++)
		{
			const double x = g.cx(ix);
			if (x > 0.9 && x < 1.2) continue;
			const float a = x < 1.0 ? 0.01f : 0.02f;
			for (float z : {a, -a, a, -a}) pts.push(uint32_t(g.index(ix, iy)), z);
		}
	frame.insert(pts, OutlierFilterParams{});
	const Eigen::Vector3d sensor(0, 0, 1);
	IsmStats st;

	// Bins of 0.5 m: [1.0, 1.5) holds only the near strip, [1.5, 2.0) only the
	// far one, so the band is d_pth + noise_sigmas * a = 0.03 + 3 * 0.01 = 0.06
	// at 1.25 m and 0.03 + 3 * 0.02 = 0.09 at 1.75 m.
	InverseSensorModel half;
	half.compute(frame, handDetection(kFloor), sensor, 5.0, st);
	EXPECT_NEAR(half.groundBand(sensor, 1.0, std::sqrt(1.25 * 1.25 - 1), 0, 0), 0.06, 1e-6);
	EXPECT_NEAR(half.groundBand(sensor, 1.0, std::sqrt(1.75 * 1.75 - 1), 0, 0), 0.09, 1e-6);

	// One bin of 1 m, [1.0, 2.0): 72 cells, 40 of them with 2 cm, so the
	// median is 2 cm and the band 0.09 at both ranges.
	IsmParams p;
	p.floor_noise_bin = 1.0;
	InverseSensorModel whole(p);
	whole.compute(frame, handDetection(kFloor), sensor, 5.0, st);
	EXPECT_NEAR(whole.groundBand(sensor, 1.0, std::sqrt(1.25 * 1.25 - 1), 0, 0), 0.09, 1e-6);
	EXPECT_NEAR(whole.groundBand(sensor, 1.0, std::sqrt(1.75 * 1.75 - 1), 0, 0), 0.09, 1e-6);

	p.floor_noise_bin = 0;  // below its range 0.05 .. 10 m
	EXPECT_THROW(InverseSensorModel{p}, std::invalid_argument);
}

TEST(InverseSensorModel, FloorNoiseIsMeasuredOnAnUpperStoreyToo)
{
	// Issue #30: the same measurement as above on a floor at z = 10 m (a map
	// in a building's frame), sensor 1 m above it at (0, 0, 11). Cells of the
	// strip x in [0.5, 0.9), |y| <= 0.1 (3D range 1.118 .. 1.35 m, one bin of
	// [1.0, 1.5)) hold 10 + a, 10 - a, 10 + a, 10 - a with a = 3 mm: sample std
	// a, so the band is d_pth + noise_sigmas * a = 0.03 + 3 * 0.003 = 0.039 m.
	// With the variance as float E[z^2] - E[z]^2 the std came out between 0 and
	// ~5 mm (100.000009 - 100 is below float resolution near 100).
	ElevationGrid frame(gamtest::makeGeometry(-1, -1, 0.05, 60, 40));
	const GridGeometry& g = frame.geometry();
	BinnedPoints pts;
	const float a = 0.003f;
	size_t cells = 0;
	for (int iy = g.iy(-0.1 + 1e-6); iy < g.iy(0.1 - 1e-6) + 1; iy++)
		for (int ix = g.ix(0.5 + 1e-6); ix < g.ix(0.9 - 1e-6) + 1; ix++, cells++)
			for (float z : {10.0f + a, 10.0f - a, 10.0f + a, 10.0f - a}) pts.push(uint32_t(g.index(ix, iy)), z);
	ASSERT_GE(cells, 10u);  // floor_noise_min_cells
	frame.insert(pts, OutlierFilterParams{});
	const Eigen::Vector3d sensor(0, 0, 11);
	const Plane upperFloor{0, 0, 1, -10};  // z = 10
	IsmStats st;
	InverseSensorModel ism;
	ism.compute(frame, handDetection(upperFloor), sensor, 5.0, st);
	EXPECT_NEAR(ism.groundBand(sensor, 1.0, std::sqrt(1.25 * 1.25 - 1), 0, 10), 0.039, 1e-5);
}

TEST(InverseSensorModel, FloorOffsetIsMeasuredWithoutTheFloorNoise)
{
	// measure_floor_noise and measure_floor_offset are separate switches (the
	// ablation switches one off at a time). Ten floor cells at x = 1.025, y =
	// -0.225 ... 0.225, seen from (0, 0, 1): ranges sqrt(1.025^2 + y^2 + 1) =
	// 1.4322 ... 1.4496, all in the 0.5 m bin [1.0, 1.5); 4 samples each, the
	// cells' means alternately +4 mm and -4 mm. tau = 1.4826 x the median
	// |mean| = 1.4826 x 0.004 = 0.0059304.
	ElevationGrid grid;
	BinnedPoints b;
	for (int i = 0; i < 10; i++)
		for (int k = 0; k < 4; k++) grid.binPoint(1.025, -0.225 + 0.05 * i, i % 2 ? -0.004f : 0.004f, b);
	OutlierFilterParams f;
	f.enabled = false;
	grid.insert(b, f);
	const Eigen::Vector3d sensor(0, 0, 1);
	auto tauWith = [&](bool noise, bool offset) {
		IsmParams p;
		p.measure_floor_noise = noise;
		p.measure_floor_offset = offset;
		InverseSensorModel ism(p);
		IsmStats st;
		ism.compute(grid, handDetection(kFloor), sensor, 5.0, st, &b);
		return ism.floorOffset(sensor, 1.025, 0.025, 0.0);
	};
	EXPECT_NEAR(tauWith(true, true), 0.0059304, 1e-6);
	EXPECT_NEAR(tauWith(false, true), 0.0059304, 1e-6);
	EXPECT_EQ(tauWith(true, false), -1.0);
	EXPECT_EQ(tauWith(false, false), -1.0);
}

namespace
{
// range_smear. A camera with a flat 3 cm range sigma (custom time-of-flight
// c0 = 0.03) at (0, 0, 0.5) over the floor z = 0. A wall cell W at x = 4.075
// holds 300 samples from 0.1 to 0.5 m; the cell V in front of it (x = 4.025)
// holds 20 floor samples and `inFront` samples of the same heights. Both
// cells reach z = 0.5 = the sensor's height, so the rays are level: slant
// range r = rho and the horizontal sigma is sigma = 0.03 itself.
// By hand: a surface at W's centre leaves stay = 2 Phi(0.025 / 0.03) - 1 =
// 2 x 0.7976716 - 1 = 0.5953432 of its samples in W and moves Phi((0.05 +
// 0.025) / 0.03) - Phi((0.05 - 0.025) / 0.03) = 0.9937903 - 0.7976716 =
// 0.1961187 of them into V (centres 5 cm apart): lambda = 300 x 0.1961187 /
// 0.5953432 = 98.826, and with 3 Poisson deviations 98.826 + 3 sqrt(98.826)
// = 128.65. V's samples above the band are W's if there are at most 128.
constexpr double kSmearV = 4.025, kSmearW = 4.075, kSmearY = 0.025;
ElevationGrid smearFrame(int inFront, BinnedPoints& b, double wallX = kSmearW, bool floorBetween = false)
{
	ElevationGrid grid;
	b.clear();
	for (int i = 0; i < 300; i++) grid.binPoint(wallX, kSmearY, float(0.1 + 0.4 * i / 299.0), b);
	for (int i = 0; i < 20; i++) grid.binPoint(kSmearV, kSmearY, 0.f, b);
	for (int i = 0; i < inFront; i++)
		grid.binPoint(kSmearV, kSmearY, float(inFront > 1 ? 0.1 + 0.4 * i / (inFront - 1) : 0.5), b);
	if (floorBetween)
		for (int i = 0; i < 20; i++) grid.binPoint(0.5 * (kSmearV + wallX), kSmearY, 0.f, b);
	grid.insert(b, OutlierFilterParams{});
	return grid;
}
// The cell of a smearFrame() at x on its row.
uint32_t cellAt(const ElevationGrid& f, double x)
{
	return uint32_t(f.geometry().index(f.geometry().ix(x), f.geometry().iy(kSmearY)));
}
CameraNoise flatNoise(double sigma)
{
	CameraNoise n;
	n.tof_c0 = sigma;
	return n;
}
}  // namespace

TEST(InverseSensorModel, AWallsSamplesPushedTowardTheCameraGiveNoObstacleInFrontOfIt)
{
	const double lambda =
		300.0 * (ism::normalTail(-2.5) - ism::normalTail(-0.025 / 0.03)) / (2.0 * ism::normalTail(-0.025 / 0.03) - 1.0);
	EXPECT_NEAR(lambda, 98.826, 1e-3);
	EXPECT_NEAR(lambda + 3.0 * std::sqrt(lambda), 128.65, 1e-2);
	IsmParams p;
	ASSERT_TRUE(p.range_smear);
	ASSERT_EQ(p.noise_sigmas, 3.0);
	InverseSensorModel ism(p);
	ism.setCameraNoise(flatNoise(0.03), 500);
	IsmStats st;
	BinnedPoints b;
	const Eigen::Vector3d sensor{0, 0, 0.5};
	const ElevationGrid f128 = smearFrame(128, b);
	ism.compute(f128, handDetection(kFloor), sensor, 5.0, st, &b);
	EXPECT_EQ(ism.classes()[cellAt(f128, kSmearV)], VoxelClass::Obstacle);
	EXPECT_EQ(ism.evidence()[cellAt(f128, kSmearV)], 0.5f) << "128 <= 128.65: the wall's samples";
	EXPECT_GT(ism.evidence()[cellAt(f128, kSmearW)], 0.5f) << "the wall itself";
	EXPECT_EQ(st.smeared, 1u);
	EXPECT_EQ(st.obstacle, 1u);
	checkEvidenceBookkeeping(ism);

	const ElevationGrid f129 = smearFrame(129, b);
	ism.compute(f129, handDetection(kFloor), sensor, 5.0, st, &b);
	EXPECT_GT(ism.evidence()[cellAt(f129, kSmearV)], 0.5f) << "129 > 128.65: more than the wall's noise explains";
	EXPECT_EQ(st.smeared, 0u);
	EXPECT_EQ(st.obstacle, 2u);

	// Off: every such cell counts.
	IsmParams off = p;
	off.range_smear = false;
	InverseSensorModel noRule(off);
	noRule.setCameraNoise(flatNoise(0.03), 500);
	noRule.compute(f128, handDetection(kFloor), sensor, 5.0, st, &b);
	EXPECT_GT(noRule.evidence()[cellAt(f128, kSmearV)], 0.5f);
	EXPECT_EQ(st.smeared, 0u);

	// Floor seen between them (the wall a cell farther, x = 4.125): a separate
	// object. The walk (up to 3 sigma + half a cell = 0.115 m, in half cells)
	// meets the floor cell at 4.075 first.
	const ElevationGrid gap = smearFrame(60, b, 4.125, true);
	ism.compute(gap, handDetection(kFloor), sensor, 5.0, st, &b);
	EXPECT_EQ(ism.classes()[cellAt(gap, 4.075)], VoxelClass::Ground);
	EXPECT_GT(ism.evidence()[cellAt(gap, kSmearV)], 0.5f);
	EXPECT_EQ(st.smeared, 0u);
	// Without that floor the same 60 are the wall's (a cell between unseen;
	// centres 0.1 m apart: Phi(0.125 / 0.03) - Phi(0.075 / 0.03) = 0.0062 of
	// the wall's samples, lambda = 300 x 0.0062 / 0.5953 = 3.1, bound 8.4):
	// no, 60 > 8.4, they count.
	const ElevationGrid far = smearFrame(60, b, 4.125);
	ism.compute(far, handDetection(kFloor), sensor, 5.0, st, &b);
	EXPECT_GT(ism.evidence()[cellAt(far, kSmearV)], 0.5f);
	const ElevationGrid farFew = smearFrame(8, b, 4.125);
	ism.compute(farFew, handDetection(kFloor), sensor, 5.0, st, &b);
	EXPECT_EQ(ism.evidence()[cellAt(farFew, kSmearV)], 0.5f) << "8 <= 8.4";

	// A low object's top spread over both cells is as dense in each: a wall
	// cell of 20 samples (lambda = 20 x 0.1961187 / 0.5953432 = 6.588, bound
	// 6.588 + 3 sqrt(6.588) = 14.29) and 12 in front of it. 12 <= 14.29, but
	// 12 is nearer 20 than 6.588 in Poisson deviations: (12 - 6.588) /
	// sqrt(6.588) = 2.109 > (20 - 12) / sqrt(20) = 1.789: a surface of its
	// own, so they count. 6 of them: 0.229 < 3.130, the wall's.
	const auto lowTop = [&](int inFront) {
		ElevationGrid grid;
		b.clear();
		for (int i = 0; i < 20; i++) grid.binPoint(kSmearW, kSmearY, float(0.1 + 0.4 * i / 19.0), b);
		for (int i = 0; i < 20; i++) grid.binPoint(kSmearV, kSmearY, 0.f, b);
		for (int i = 0; i < inFront; i++) grid.binPoint(kSmearV, kSmearY, float(0.1 + 0.4 * i / (inFront - 1)), b);
		grid.insert(b, OutlierFilterParams{});
		return grid;
	};
	EXPECT_NEAR((12.0 - 6.588) / std::sqrt(6.588), 2.109, 1e-3);
	EXPECT_NEAR((20.0 - 12.0) / std::sqrt(20.0), 1.789, 1e-3);
	const ElevationGrid dense = lowTop(12);
	ism.compute(dense, handDetection(kFloor), sensor, 5.0, st, &b);
	EXPECT_GT(ism.evidence()[cellAt(dense, kSmearV)], 0.5f) << "2.109 > 1.789: its own surface";
	EXPECT_EQ(st.smeared, 0u);
	const ElevationGrid sparse = lowTop(6);
	ism.compute(sparse, handDetection(kFloor), sensor, 5.0, st, &b);
	EXPECT_EQ(ism.evidence()[cellAt(sparse, kSmearV)], 0.5f) << "6 <= 14.29, and 0.229 < 3.130";
	EXPECT_EQ(st.smeared, 1u);

	// A camera whose 3 sigma stays under a cell (3 mm: 3 sigma + half a cell
	// = 0.034 m < the next cell's 0.05): the rule never looks.
	InverseSensorModel fine(p);
	fine.setCameraNoise(flatNoise(0.003), 500);
	fine.compute(f128, handDetection(kFloor), sensor, 5.0, st, &b);
	EXPECT_GT(fine.evidence()[cellAt(f128, kSmearV)], 0.5f);
	EXPECT_EQ(st.smeared, 0u);
}

TEST(InverseSensorModel, AWallJustBeyondTheRangeLimitGivesNoObstacleInFrontOfIt)
{
	// A wall just beyond the camera's range limit returns only the samples
	// its range noise brings nearer. V (x = 4.025, seen from (0, 0, 0.5)) holds
	// 20 floor samples and 30 from 0.1 to 0.5 m; nothing was seen beyond it.
	// V's top sample is level with the sensor: rho = r = hypot(4.025, 0.025)
	// = 4.025078, sigma = 0.03 m all horizontal, the walk reaches 3 sigma +
	// half a cell = 0.115 m in half cells: t = 0.05 (x = 4.075, the cell
	// [4.05, 4.10)), 0.075 (the same cell, not looked at again), 0.1 (the
	// cell [4.10, 4.15)). Along V's ray the depth (the camera level: along
	// x) grows by 4.025 / 4.025078 = 0.9999807 per metre from V's 4.025: a
	// limit of 4.10 lies 0.075 / 0.9999807 = 0.0750014 m beyond V's centre.
	const double rho = std::hypot(4.025, 0.025);
	EXPECT_NEAR(rho, 4.025078, 1e-6);
	EXPECT_NEAR(4.025 / rho, 0.9999807, 1e-7);
	EXPECT_NEAR(0.075 / (4.025 / rho), 0.0750014, 1e-7);
	IsmParams p;
	ASSERT_TRUE(p.range_smear);
	ASSERT_EQ(p.noise_sigmas, 3.0);
	IsmStats st;
	BinnedPoints b;
	const Eigen::Vector3d sensor{0, 0, 0.5};
	const auto frame = [&](bool floorBeyond) {
		ElevationGrid grid;
		b.clear();
		for (int i = 0; i < 20; i++) grid.binPoint(kSmearV, kSmearY, 0.f, b);
		for (int i = 0; i < 30; i++) grid.binPoint(kSmearV, kSmearY, float(0.1 + 0.4 * i / 29.0), b);
		if (floorBeyond)
			for (int i = 0; i < 20; i++) grid.binPoint(4.075, kSmearY, 0.f, b);
		grid.insert(b, OutlierFilterParams{});
		return grid;
	};
	const ElevationGrid f = frame(false);
	const uint32_t v = uint32_t(f.geometry().index(f.geometry().ix(kSmearV), f.geometry().iy(kSmearY)));
	const auto evidenceWith = [&](const ElevationGrid& fr, const Eigen::Vector3d& forward, double limit) {
		InverseSensorModel ism(p);
		ism.setCameraNoise(flatNoise(0.03), 500);
		ism.setCameraRangeLimit(forward, limit);
		ism.compute(fr, handDetection(kFloor), sensor, 5.0, st, &b);
		EXPECT_EQ(ism.classes()[v], VoxelClass::Obstacle);
		return ism.evidence()[v];
	};
	const Eigen::Vector3d level(1, 0, 0);
	// t = 0.1 > 0.0750014, with only unseen cells on the way.
	EXPECT_EQ(evidenceWith(f, level, 4.10), 0.5f) << "the samples of a surface beyond the limit";
	EXPECT_EQ(st.smeared, 1u);
	// A limit at 4.20 (0.175 m on) is out of the walk's reach, and there is
	// none by default: they count.
	EXPECT_GT(evidenceWith(f, level, 4.20), 0.5f);
	EXPECT_EQ(st.smeared, 0u);
	{
		InverseSensorModel ism(p);
		ism.setCameraNoise(flatNoise(0.03), 500);
		ism.compute(f, handDetection(kFloor), sensor, 5.0, st, &b);
		EXPECT_GT(ism.evidence()[v], 0.5f) << "default: no limit";
	}
	// The limit is on the depth along the camera's axis: pitched 30 deg down,
	// V's depth is 4.025 cos 30 deg = 3.4857 and grows by 0.9999807 cos 30
	// deg = 0.86601 per metre of its ray: 4.10 lies 0.7093 m on, out of
	// reach. Measured as the range (a zero axis), 4.10 lies 4.10 - 4.025078
	// = 0.0749 m on, as for the level camera.
	EXPECT_NEAR(4.025 * std::cos(M_PI / 6), 3.4857, 1e-4);
	EXPECT_NEAR((4.10 - 4.025 * std::cos(M_PI / 6)) / (4.025 / rho * std::cos(M_PI / 6)), 0.7093, 1e-4);
	EXPECT_GT(evidenceWith(f, Eigen::Vector3d(std::cos(M_PI / 6), 0, -std::sin(M_PI / 6)), 4.10), 0.5f);
	EXPECT_EQ(evidenceWith(f, Eigen::Vector3d::Zero(), 4.10), 0.5f);
	// Floor seen beyond V (x = 4.075): the samples end on the floor, not at
	// the limit; V is an object of its own.
	const ElevationGrid seen = frame(true);
	EXPECT_GT(evidenceWith(seen, level, 4.10), 0.5f);
	EXPECT_EQ(st.smeared, 0u);
}

TEST(InverseSensorModel, AWallAtTheRangeLimitKeepsOnlyHalfItsSamples)
{
	// The wall W of AWallsSamplesPushedTowardTheCamera... (300 samples at x =
	// 4.075, sensor (0, 0, 0.5)), seen by a camera of sigma 2 cm, with 90
	// samples in front of it in V (4.025). The walk from V reaches 3 sigma +
	// half a cell = 0.085 m: W's cell only (t = 0.05, 0.075). W keeps 2
	// Phi(0.025 / 0.02) - 1 = 0.788700 of its surface's samples and moves
	// Phi(0.075 / 0.02) - Phi(0.025 / 0.02) = 0.105561 into V: lambda = 300 x
	// 0.105561 / 0.788700 = 40.153, bound 40.153 + 3 sqrt(40.153) = 59.16 <
	// 90: they count. With the limit at W's centre (4.075 along the level
	// axis: 0.05 / 0.9999807 = 0.05000096 m beyond V's centre, 0.00000096 m
	// beyond W's) the samples its noise moves past its centre are cut: it
	// keeps Phi(0.00000096 / 0.02) - Phi(-0.025 / 0.02) = 0.394369, lambda =
	// 300 x 0.105561 / 0.394369 = 80.301, bound 80.301 + 3 sqrt(80.301) =
	// 107.18 >= 90, and |90 - 80.301| / sqrt(80.301) = 1.082 < (300 - 90) /
	// sqrt(300) = 12.124: W's samples.
	const double stay = 1.0 - 2.0 * ism::normalTail(0.025 / 0.02);
	const double moved = ism::normalTail(-0.075 / 0.02) - ism::normalTail(-0.025 / 0.02);
	const double room = 0.05 / (4.025 / std::hypot(4.025, 0.025)) - 0.05;  // W's centre to the limit
	EXPECT_NEAR(room, 0.00000096, 1e-8);
	const double kept = ism::normalTail(-room / 0.02) - ism::normalTail(0.025 / 0.02);
	EXPECT_NEAR(stay, 0.788700, 1e-6);
	EXPECT_NEAR(moved, 0.105561, 1e-6);
	EXPECT_NEAR(kept, 0.394369, 1e-6);
	EXPECT_NEAR(300.0 * moved / stay, 40.153, 1e-3);
	EXPECT_NEAR(40.153 + 3.0 * std::sqrt(40.153), 59.16, 1e-2);
	const double lambda = 300.0 * moved / kept;
	EXPECT_NEAR(lambda, 80.301, 1e-3);
	EXPECT_NEAR(lambda + 3.0 * std::sqrt(lambda), 107.18, 1e-2);
	EXPECT_NEAR((90.0 - lambda) / std::sqrt(lambda), 1.082, 1e-3);
	EXPECT_NEAR(210.0 / std::sqrt(300.0), 12.124, 1e-3);
	IsmParams p;
	IsmStats st;
	BinnedPoints b;
	const Eigen::Vector3d sensor{0, 0, 0.5};
	const auto evidenceOfV = [&](const ElevationGrid& f, double sigma, double limit) {
		InverseSensorModel ism(p);
		ism.setCameraNoise(flatNoise(sigma), 500);
		if (std::isfinite(limit)) ism.setCameraRangeLimit(Eigen::Vector3d(1, 0, 0), limit);
		ism.compute(f, handDetection(kFloor), sensor, 5.0, st, &b);
		return ism.evidence()[f.geometry().index(f.geometry().ix(kSmearV), f.geometry().iy(kSmearY))];
	};
	const double none = std::numeric_limits<double>::infinity();
	const ElevationGrid f90 = smearFrame(90, b);
	EXPECT_GT(evidenceOfV(f90, 0.02, none), 0.5f) << "90 > 59.16";
	EXPECT_EQ(evidenceOfV(f90, 0.02, 4.075), 0.5f) << "90 <= 107.18: the samples of a wall cut by the limit";
	// Sigma 3 cm (the walk reaches 0.115 m) and 200 samples in V, more than
	// W's noise puts there (bound 128.65, see above). The limit at 4.12 lies
	// 0.0950018 m beyond V's centre and 0.0450018 m beyond W's, more than
	// half a cell: W is a surface seen inside the limit, as high as V, that
	// stands between them. The walk's t = 0.1 > 0.0950018, an unseen cell
	// past the limit, but V's samples are not a surface's beyond it. (W
	// itself, its walk past the limit at its first step, is taken for one.)
	const ElevationGrid f200 = smearFrame(200, b);
	EXPECT_GT(evidenceOfV(f200, 0.03, 4.12), 0.5f) << "a surface seen between V and the limit";
	EXPECT_EQ(st.smeared, 1u);
}

TEST(InverseSensorModel, AWallBeyondTheRangeOfTrustStillExplainsItsSamplesInFront)
{
	// The frame of AWallsSamplesPushedTowardTheCamera... (wall W at x = 4.075,
	// 300 samples 0.1-0.5 m; V at 4.025, 20 floor samples and 128 of the
	// wall's heights; sigma 3 cm, sensor (0, 0, 0.5)), judged out to 4.05 m
	// only (a camera's range of trust): V's centre lies hypot(4.025, 0.025) =
	// 4.025078 m from the sensor, inside; W's hypot(4.075, 0.025) = 4.075077
	// m, outside, so W is OutOfRange: seen, judged nowhere. Its samples still
	// move by the camera's noise: lambda = 98.826 as there, bound 128.65,
	// and 128 of them in V are W's.
	EXPECT_NEAR(std::hypot(4.025, 0.025), 4.025078, 1e-6);
	EXPECT_NEAR(std::hypot(4.075, 0.025), 4.075077, 1e-6);
	IsmParams p;
	ASSERT_TRUE(p.range_smear);
	InverseSensorModel ism(p);
	ism.setCameraNoise(flatNoise(0.03), 500);
	IsmStats st;
	BinnedPoints b;
	const Eigen::Vector3d sensor{0, 0, 0.5};
	const double trusted = 4.05;
	const ElevationGrid f128 = smearFrame(128, b);
	ism.compute(f128, handDetection(kFloor), sensor, trusted, st, &b);
	EXPECT_EQ(ism.classes()[cellAt(f128, kSmearW)], VoxelClass::OutOfRange);
	EXPECT_EQ(ism.classes()[cellAt(f128, kSmearV)], VoxelClass::Obstacle);
	EXPECT_EQ(ism.evidence()[cellAt(f128, kSmearV)], 0.5f) << "128 <= 128.65: the wall's samples";
	EXPECT_EQ(ism.evidence()[cellAt(f128, kSmearW)], 0.5f) << "beyond the range: no evidence";
	EXPECT_EQ(st.smeared, 1u);
	const ElevationGrid f129 = smearFrame(129, b);
	ism.compute(f129, handDetection(kFloor), sensor, trusted, st, &b);
	EXPECT_GT(ism.evidence()[cellAt(f129, kSmearV)], 0.5f) << "129 > 128.65: more than the wall's noise explains";
	EXPECT_EQ(st.smeared, 0u);
	// The wall a cell farther (x = 4.125) with floor beyond the range between
	// them (20 samples at z = 0 in the cell at 4.075: not as high as V's top,
	// less the vertical share of 3 sigma, 0 on a level ray): V is an object
	// of its own, as with that floor in range (AWallsSamplesPushed...'s
	// `gap`). Without the floor, 8 in V are the wall's there (centres 0.1 m
	// apart: lambda = 3.1, bound 8.4).
	const ElevationGrid gap = smearFrame(8, b, 4.125, true);
	ism.compute(gap, handDetection(kFloor), sensor, trusted, st, &b);
	EXPECT_EQ(ism.classes()[cellAt(gap, 4.075)], VoxelClass::OutOfRange);
	EXPECT_GT(ism.evidence()[cellAt(gap, kSmearV)], 0.5f) << "floor between: its own object";
	EXPECT_EQ(st.smeared, 0u);
	const ElevationGrid far = smearFrame(8, b, 4.125);
	ism.compute(far, handDetection(kFloor), sensor, trusted, st, &b);
	EXPECT_EQ(ism.evidence()[cellAt(far, kSmearV)], 0.5f) << "8 <= 8.4";
	EXPECT_EQ(st.smeared, 1u);
}

TEST(InverseSensorModel, AStepDownsSamplesPushedAwayGiveNoDropBeyondItsEdge)
{
	// The mirror case: the face of a step down (a drop cell W at x = 4.025,
	// 300 samples from -0.3 to -0.05) and the floor beyond its edge (V at
	// 4.075: 20 floor samples and `beyond` samples at the face's depths),
	// seen from (0, 0, 1). V's ray: rho = 4.075077, its deepest sample 1.3 m
	// below the sensor, r = sqrt(4.075077^2 + 1.3^2) = 4.277412; sigma = 0.03
	// gives 0.03 x 4.075077 / 4.277412 = 0.028581 horizontally and W (5 cm
	// nearer) moves Phi(0.075 / 0.028581) - Phi(0.025 / 0.028581) = 0.995656
	// - 0.809134 = 0.186522 of its samples into V and keeps 2 x 0.809134 - 1 =
	// 0.618268: lambda = 300 x 0.186522 / 0.618268 = 90.506, bound 90.506 + 3
	// sqrt(90.506) = 119.05.
	const double rho = std::hypot(4.075, 0.025), r = std::hypot(rho, 1.3), s2 = 0.03 * rho / r;
	EXPECT_NEAR(r, 4.277412, 1e-6);
	EXPECT_NEAR(s2, 0.028581, 1e-6);
	const double stay = 1.0 - 2.0 * ism::normalTail(0.025 / s2);
	const double lambda = 300.0 * (ism::normalTail(0.025 / s2) - ism::normalTail(0.075 / s2)) / stay;
	EXPECT_NEAR(stay, 0.618268, 1e-6);
	EXPECT_NEAR(lambda, 90.506, 1e-3);
	EXPECT_NEAR(lambda + 3.0 * std::sqrt(lambda), 119.05, 1e-2);
	const auto frame = [](int beyond, BinnedPoints& b) {
		ElevationGrid grid;
		b.clear();
		for (int i = 0; i < 300; i++) grid.binPoint(4.025, kSmearY, float(-0.3 + 0.25 * i / 299.0), b);
		for (int i = 0; i < 20; i++) grid.binPoint(4.075, kSmearY, 0.f, b);
		for (int i = 0; i < beyond; i++) grid.binPoint(4.075, kSmearY, float(-0.3 + 0.25 * i / (beyond - 1)), b);
		grid.insert(b, OutlierFilterParams{});
		return grid;
	};
	IsmParams p;
	p.drop_rays = false;  // the drop cells' own evidence only
	InverseSensorModel ism(p);
	ism.setCameraNoise(flatNoise(0.03), 500);
	IsmStats st;
	BinnedPoints b;
	const Eigen::Vector3d sensor{0, 0, 1};
	const ElevationGrid f119 = frame(119, b);
	const uint32_t v = uint32_t(f119.geometry().index(f119.geometry().ix(4.075), f119.geometry().iy(kSmearY)));
	const uint32_t w = uint32_t(f119.geometry().index(f119.geometry().ix(4.025), f119.geometry().iy(kSmearY)));
	ism.compute(f119, handDetection(kFloor), sensor, 5.0, st, &b);
	EXPECT_GT(ism.evidence()[w], 0.5f) << "the face";
	EXPECT_EQ(ism.evidence()[v], 0.5f) << "119 <= 119.05: the face's samples";
	EXPECT_EQ(st.smeared, 1u);
	EXPECT_EQ(st.drop, 1u);
	const ElevationGrid f120 = frame(120, b);
	ism.compute(f120, handDetection(kFloor), sensor, 5.0, st, &b);
	EXPECT_GT(ism.evidence()[v], 0.5f) << "120 > 119.05";
	EXPECT_EQ(st.smeared, 0u);
	EXPECT_EQ(st.drop, 2u);
	checkEvidenceBookkeeping(ism);
}
