// Ground-aware mapping for MRPT
// The paper's method as printed (ism_model = paper, rrt_variant = paper).
// Every expected value is worked out by hand from the paper's formulas and its
// Table I (K_m = 0.8, K_n = 0.0005, d_min = 3, K_g = 0.3, sigma^2 = 0.02,
// d_pth = 0.03, d_r = 0.05, N_th = 0.2, E_th = 0.05, d_n = 0.4), not from the code.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <random>

#include "gam/core/InverseSensorModel.h"
#include "gam/core/PlaneFit.h"
#include "gam/core/RrtGroundDetector.h"
#include "test_helpers.h"

using namespace gam;

namespace
{
IsmParams paperIsm()
{
	IsmParams p;
	p.model = MethodVariant::Paper;
	return p;
}

GroundDetection floorDetection()
{
	GroundDetection d;
	d.status = GroundDetection::Status::Ok;
	d.planes.push_back(Plane{0, 0, 1, 0});  // z = 0
	d.plane_support.push_back(100);
	return d;
}

/** The evidence of the frame cell whose centre is nearest (x, y). */
float evidenceAt(const InverseSensorModel& ism, const ElevationGrid& grid, double x, double y)
{
	const GridGeometry& g = grid.geometry();
	return ism.evidence()[g.index(g.ix(x), g.iy(y))];
}
}  // namespace

TEST(PaperIsm, Eq4DensityByHand)
{
	const IsmParams p = paperIsm();
	// V_voxel = d_r^2 * max(span, d_r).
	EXPECT_DOUBLE_EQ(paper::voxelVolume(0.2, 0.05), 0.0025 * 0.2);   // 5e-4 m^3
	EXPECT_DOUBLE_EQ(paper::voxelVolume(0.0, 0.05), 0.0025 * 0.05);  // one sample: one cell tall, 1.25e-4
	// N_z = 20 over 0.2 m: exponent -0.0005 * (20 - 3) / 5e-4 = -17;
	// P = 0.8 / (1 + e^-17) = 0.8 / 1.0000000414 = 0.79999997.
	EXPECT_NEAR(paper::densityConfidence(20, 0.2, p, 0.05), 0.79999997, 1e-8);
	// N_z = 4, flat: -0.0005 * 1 / 1.25e-4 = -4; 0.8 / 1.0183156 = 0.785611.
	EXPECT_NEAR(paper::densityConfidence(4, 0.0, p, 0.05), 0.785611, 1e-6);
	// N_z = d_min = 3: exponent 0, P = K_m / 2 = 0.4 (d_min is a sample count).
	EXPECT_DOUBLE_EQ(paper::densityConfidence(3, 0.0, p, 0.05), 0.4);
	// N_z = 1: +0.0005 * 2 / 1.25e-4 = +8; 0.8 / (1 + 2980.958) = 2.6829e-4.
	EXPECT_NEAR(paper::densityConfidence(1, 0.0, p, 0.05), 2.6829e-4, 1e-8);
}

TEST(PaperIsm, Eq5And6AlongTheRayByHand)
{
	const IsmParams p = paperIsm();
	// Obstacle voxel at |c_v| = 2 m with P_rho = 0.785610 (N_z = 4):
	// at the voxel max(P_rho, 0.5) = 0.785610;
	EXPECT_NEAR(paper::obstacleRay(2.0, 2.0, 0.785610, p), 0.785610, 1e-9);
	// 0.1 m in front: 0.785610 * exp(-0.01 / 0.04) = 0.785610 * 0.7788008 = 0.611834;
	EXPECT_NEAR(paper::obstacleRay(1.9, 2.0, 0.785610, p), 0.611834, 1e-6);
	// 0.5 m in front: 0.785610 * exp(-0.25 / 0.04) = 0.785610 * 0.0019305 = 0.0015166: free.
	EXPECT_NEAR(paper::obstacleRay(1.5, 2.0, 0.785610, p), 0.0015166, 1e-7);
	// A sparse voxel (P_rho < 0.5) peaks at 0.5 (no evidence of an obstacle)
	// and still frees the cells in front of it: 0.5 * 0.7788008 = 0.3894004.
	EXPECT_DOUBLE_EQ(paper::obstacleRay(2.0, 2.0, 2.68e-4, p), 0.5);
	EXPECT_NEAR(paper::obstacleRay(1.9, 2.0, 2.68e-4, p), 0.3894004, 1e-7);
	// Ground voxel: K_g + (0.5 - K_g) / (1 + e^-(|c| - |c_v|)):
	// at the voxel 0.3 + 0.2 / 2 = 0.4;
	EXPECT_NEAR(paper::groundRay(2.0, 2.0, p), 0.4, 1e-12);
	// 0.5 m in front: 0.3 + 0.2 / (1 + e^0.5) = 0.3 + 0.2 / 2.6487213 = 0.3755081;
	EXPECT_NEAR(paper::groundRay(1.5, 2.0, p), 0.3755081, 1e-7);
	// 1 m in front: 0.3 + 0.2 / (1 + e^1) = 0.3 + 0.2 / 3.7182818 = 0.3537883.
	EXPECT_NEAR(paper::groundRay(1.0, 2.0, p), 0.3537883, 1e-7);
	// Eq. (6), behind the voxel (our reading): no evidence.
	EXPECT_DOUBLE_EQ(paper::groundRay(2.1, 2.0, p), 0.5);
	EXPECT_DOUBLE_EQ(paper::obstacleRay(2.1, 2.0, 0.785610, p), 0.5);
}

TEST(PaperIsm, ComputeWalksEachVoxelsRay)
{
	// Frame grid 0..5 m x -1..1 m of 5 cm cells; sensor at (0, 0.025, 1), floor z = 0.
	ElevationGrid grid(gamtest::makeGeometry(0.0, -1.0, 0.05, 100, 40));
	// A ground voxel (4 samples at z = 0) in the cell centred (2.025, 0.025) and
	// an obstacle voxel (20 samples, 0 to 0.2 m) in the cell centred (3.525, 0.025):
	// both on the line y = 0.025 from the sensor, 2.025 m and 3.525 m away.
	std::vector<std::array<double, 3>> pts;
	for (int i = 0; i < 4; i++) pts.push_back({2.01 + 0.01 * i, 0.025, 0.0});
	for (int i = 0; i < 20; i++) pts.push_back({3.525, 0.025, 0.2 * i / 19.0});
	gamtest::insertPoints(grid, pts);
	InverseSensorModel ism(paperIsm());
	IsmStats st;
	ism.compute(grid, floorDetection(), {0.0, 0.025, 1.0}, 4.5, st);
	EXPECT_EQ(st.ground, 1u);
	EXPECT_EQ(st.obstacle, 1u);
	// Obstacle: P_rho = 0.8 / (1 + e^(-0.0005 * 17 / (0.0025 * 0.2))) = 0.8 (to 3e-8).
	EXPECT_NEAR(evidenceAt(ism, grid, 3.525, 0.025), 0.8, 1e-6);
	// 0.1 m in front of it: 0.8 * exp(-0.25) = 0.6230406.
	EXPECT_NEAR(evidenceAt(ism, grid, 3.425, 0.025), 0.6230406, 1e-6);
	// The ground voxel's own cell, 1.5 m in front of the obstacle: the obstacle's
	// ray gives 0.8 * exp(-2.25 / 0.04) ~ 3e-25, the ground voxel 0.4; both are
	// free evidence, the strongest wins: ~0, i.e. the floor of 0.001 that the
	// grid clamps every update to.
	EXPECT_FLOAT_EQ(evidenceAt(ism, grid, 2.025, 0.025), ism::kEvidenceFloor);
	// 0.4 m in front of the obstacle: 0.8 * exp(-0.16 / 0.04) = 0.8 * 0.0183156 = 0.0146525.
	EXPECT_NEAR(evidenceAt(ism, grid, 3.125, 0.025), 0.0146525, 1e-6);
	// Behind the obstacle (eq. 6): nothing.
	EXPECT_FLOAT_EQ(evidenceAt(ism, grid, 3.625, 0.025), 0.5f);
	// Only the ground voxel's ray: a second run without the obstacle.
	ElevationGrid g2(gamtest::makeGeometry(0.0, -1.0, 0.05, 100, 40));
	pts.resize(4);
	gamtest::insertPoints(g2, pts);
	ism.compute(g2, floorDetection(), {0.0, 0.025, 1.0}, 4.5, st);
	EXPECT_NEAR(evidenceAt(ism, g2, 2.025, 0.025), 0.4, 1e-6);
	// 1 m (20 cells) in front: 0.3537883; 0.5 m: 0.3755081.
	EXPECT_NEAR(evidenceAt(ism, g2, 1.025, 0.025), 0.3537883, 1e-6);
	EXPECT_NEAR(evidenceAt(ism, g2, 1.525, 0.025), 0.3755081, 1e-6);
	EXPECT_FLOAT_EQ(evidenceAt(ism, g2, 2.525, 0.025), 0.5f);  // behind: nothing
	// The default model gives evidence to the voxel's own cell only.
	InverseSensorModel dflt;
	dflt.compute(g2, floorDetection(), {0.0, 0.025, 1.0}, 4.5, st);
	EXPECT_FLOAT_EQ(evidenceAt(dflt, g2, 1.025, 0.025), 0.5f);
}

TEST(PaperIsm, RayFanByHand)
{
	// d_r = 0.05 m, range 4.5 m: 4 pi * 4.5 / 0.05 = 1130.97 -> 1131 bins of
	// 2 pi / 1131 = 0.00555542 rad; at 4.5 m neighbouring rays are
	// 4.5 * 0.00555542 = 0.0250 m apart, half a cell.
	const paper::RayFan fan(0.05, 4.5);
	EXPECT_EQ(fan.bins, 1131);
	EXPECT_NEAR(fan.dtheta, 0.00555542, 1e-8);
	EXPECT_EQ(fan.binOf(1.0, 0.0), 0);
	EXPECT_EQ(fan.binOf(0.0, 1.0), 283);   // pi/2 / 0.00555542 = 282.75 -> 283
	EXPECT_EQ(fan.binOf(0.0, -1.0), 848);  // -282.75 -> -283, + 1131
	// atan2(-0.5, -1) = -(pi - atan(0.5)) = -2.677945; / 0.00555542 = -482.04
	// -> -482, + 1131 = 649.
	EXPECT_EQ(fan.binOf(-1.0, -0.5), 649);
	// Samples at r_k = (k + 1/2) d_r; a voxel 3.525 m away reaches k <= 70
	// (r_70 = 3.525), one 0.02 m away reaches none.
	EXPECT_EQ(fan.lastSample(3.525), 70);
	EXPECT_DOUBLE_EQ(fan.radius(70), 3.525);
	EXPECT_EQ(fan.lastSample(3.5249), 69);
	EXPECT_EQ(fan.lastSample(0.02), -1);
}

TEST(PaperIsm, RayFanBinIsTheNearestRayToAtan2sAngle)
{
	// binOf() takes the angle from a series (atanReduced) and atan2 only near
	// a bin's edge. Its bin must be the definition's: lround(atan2(dy, dx) /
	// dtheta) modulo the bins, for every direction, the hard ones included:
	// the axes and diagonals, signed zeros, and directions on a bin's edge and
	// one unit in the last place either side of it.
	const auto byDefinition = [](const paper::RayFan& f, double dx, double dy) {
		const long b = std::lround(std::atan2(dy, dx) / f.dtheta);
		return int(((b % f.bins) + f.bins) % f.bins);
	};
	std::mt19937_64 rng(7);
	std::uniform_real_distribution<double> coord(-6.0, 6.0), turn(-M_PI, M_PI);
	for (const auto& [res, range] : {std::pair{0.05, 4.5}, {0.05, 8.0}, {0.02, 10.0}, {0.1, 1.0}})
	{
		const paper::RayFan fan(res, range);
		std::vector<std::pair<double, double>> dirs = {
			{1, 0},
			{-1, 0},
			{0, 1},
			{0, -1},
			{1, 1},
			{-1, 1},
			{1, -1},
			{-1, -1},
			{0.0, 0.0},
			{-1.0, -0.0},
			{-1.0, 0.0},
			{1.0, -0.0},
			{0.0, -0.0},
			{-0.0, 0.0},
			{3.0, 1e-300},
			{1e-300, 3.0},
			{2.5, 2.5 * std::tan(M_PI / 16)}};
		for (int k = -fan.bins / 2 - 1; k <= fan.bins / 2 + 1; k++)  // each bin's edge, and one ulp either side
		{
			const double edge = (k + 0.5) * fan.dtheta;
			for (const double a : {std::nextafter(edge, -10.0), edge, std::nextafter(edge, 10.0)})
				dirs.push_back({std::cos(a), std::sin(a)});
		}
		for (int i = 0; i < 200000; i++) dirs.push_back({coord(rng), coord(rng)});
		for (int i = 0; i < 20000; i++)
		{
			const double a = turn(rng), r = 0.01 + 5.0 * std::abs(coord(rng));
			dirs.push_back({r * std::cos(a), r * std::sin(a)});
		}
		size_t wrong = 0;
		for (const auto& [dx, dy] : dirs)
			if (fan.binOf(dx, dy) != byDefinition(fan, dx, dy) && wrong++ < 5)
				ADD_FAILURE() << "res " << res << " range " << range << " (" << dx << ", " << dy
							  << "): " << fan.binOf(dx, dy) << " instead of " << byDefinition(fan, dx, dy);
		EXPECT_EQ(wrong, 0u) << "of " << dirs.size() << " directions";
	}
	// The series itself against std::atan, over [0, 1].
	double worst = 0;
	for (int i = 0; i <= 1000000; i++)
	{
		const double z = i / 1e6;
		worst = std::max(worst, std::abs(paper::RayFan::atanReduced(z) - std::atan(z)));
	}
	EXPECT_LT(worst, 1e-10);
}

TEST(PaperIsm, SweepingEachRayOnceEqualsWalkingEveryVoxelsRay)
{
	// compute() sweeps each ray bin once from far to near, keeping only the
	// farthest ground voxel and the obstacle voxels whose evidence has not
	// yet fallen to the grid's floor. Reference: every in-range voxel walks
	// its own ray sample by sample, and the values combine per cell. The
	// reference is written here from the paper, not with the code's ray
	// functions (RayFan, obstacleRay, groundRay: each checked by hand above):
	//  - rays: 2 pi / B apart, B = ceil(4 pi R / d_r) (half a cell apart at
	//    the range R); a voxel's ray is the nearest one to its direction;
	//  - samples at r_k = (k + 1/2) d_r for r_k <= |c_v| (the voxel's 2D distance);
	//  - eq. (4) P_rho = K_m / (1 + exp(-K_n (N_z - d_min) / V)), V = d_r^2 max(span, d_r);
	//  - eq. (5) obstacle: max(P_rho, 1/2) exp(-(r - |c_v|)^2 / (2 sigma^2));
	//  - eq. (6) ground: K_g + (1/2 - K_g) / (1 + exp(-(r - |c_v|)));
	//  - a cell's values combine as the strongest (the grid's one update per
	//    frame), each clamped to [0.001, 0.999].
	const GridGeometry g = gamtest::makeGeometry(-1.0, -3.0, 0.05, 120, 120);
	const Eigen::Vector3d sensor(-0.73, 0.11, 0.8);
	const double range = 4.5;
	const int bins = int(std::ceil(4.0 * M_PI * range / g.resolution));
	const double dtheta = 2.0 * M_PI / bins;
	std::mt19937 rng(7);
	std::uniform_real_distribution<double> ux(-1.0, 5.0), uy(-3.0, 3.0), noise(-0.01, 0.01), u01(0, 1);
	for (int round = 0; round < 3; round++)
	{
		ElevationGrid grid(g);
		std::vector<std::array<double, 3>> pts;
		for (int i = 0; i < 30000; i++)
		{
			const double x = ux(rng), y = uy(rng);
			// Floor, with 15 % of the samples on objects or in pits.
			const double kind = u01(rng);
			const double z = kind < 0.85 ? noise(rng) : kind < 0.95 ? 0.3 * u01(rng) : -0.2 * u01(rng);
			pts.push_back({x, y, z});
		}
		gamtest::insertPoints(grid, pts);
		const IsmParams p = paperIsm();
		InverseSensorModel ism(p);
		IsmStats st;
		ism.compute(grid, floorDetection(), sensor, range, st);
		ASSERT_GT(st.ground, 1000u);
		ASSERT_GT(st.obstacle + st.drop, 300u);

		std::vector<float> ref(g.cellCount(), 0.5f);
		auto add = [&](int qx, int qy, double v) {
			if (!g.inside(qx, qy)) return;
			const float c = std::clamp(float(v), 0.001f, 0.999f);
			float& e = ref[g.index(qx, qy)];
			if (e > 0.5f || c > 0.5f)
				e = std::max(e, c);
			else
				e = std::min(e, c);
		};
		for (uint32_t idx : grid.observedCells())
		{
			const VoxelClass cls = ism.classes()[idx];
			if (cls != VoxelClass::Ground && cls != VoxelClass::Obstacle && cls != VoxelClass::Drop) continue;
			const ElevationCell& c = grid.cell(idx);
			const int cx = int(idx % uint32_t(g.nx)), cy = int(idx / uint32_t(g.nx));
			const double dx = g.cx(cx) - sensor.x(), dy = g.cy(cy) - sensor.y();
			const double cv = std::hypot(dx, dy);
			const double V = g.resolution * g.resolution * std::max(double(c.span()), g.resolution);
			const double pRho = p.K_m / (1.0 + std::exp(-p.K_n * (double(c.count) - p.d_min) / V));
			auto value = [&](double r) {
				const double d = r - cv;
				return cls == VoxelClass::Ground ? p.K_g + (0.5 - p.K_g) / (1.0 + std::exp(-d))
												 : std::max(pRho, 0.5) * std::exp(-d * d / (2.0 * p.sigma2));
			};
			add(cx, cy, value(cv));
			const double a = std::lround(std::atan2(dy, dx) / dtheta) * dtheta;
			for (int k = 0; (k + 0.5) * g.resolution <= cv + 1e-9; k++)
			{
				const double r = (k + 0.5) * g.resolution;
				add(g.ix(sensor.x() + r * std::cos(a)), g.iy(sensor.y() + r * std::sin(a)), value(r));
			}
		}
		size_t differ = 0, withEvidence = 0;
		for (size_t i = 0; i < ref.size(); i++)
		{
			differ += std::abs(ref[i] - ism.evidence()[i]) > 1e-6f;
			withEvidence += ref[i] != 0.5f;
		}
		EXPECT_EQ(differ, 0u) << "round " << round;
		EXPECT_GT(withEvidence, 5000u);
	}
}

TEST(PaperRrt, NormalAndElevationTestsAtTheirBoundaries)
{
	RrtGpdParams rp;
	rp.variant = MethodVariant::Paper;
	RrtGroundDetector rrt(rp);
	GroundNode parent;
	parent.local = Plane{0, 0, 1, 0};  // z = 0
	parent.z = 0;
	// Line 14 as printed: |plane_local(z) - x_near(z)| <= E_th = 0.05, the new
	// local plane's height at the new node against the parent's height.
	EXPECT_TRUE(rrt.paperElevationOk(parent, 0.4, 0, Plane{0, 0, 1, -0.0499}));
	EXPECT_FALSE(rrt.paperElevationOk(parent, 0.4, 0, Plane{0, 0, 1, -0.0501}));
	// N_th = 0.2 as sin of the angle between the normals: asin(0.2) = 11.537 deg.
	auto tilted = [](double deg) {
		const double t = gamtest::deg2rad(deg);
		return Plane{-std::sin(t), 0, std::cos(t), 0};
	};
	EXPECT_TRUE(rrt.paperNormalOk(parent, tilted(11.5)));   // sin = 0.19937
	EXPECT_FALSE(rrt.paperNormalOk(parent, tilted(11.6)));  // sin = 0.20108
	// Against the parent's normal, not the vertical: a 20 deg patch passes
	// against a 10 deg parent (sin 10 deg = 0.1736), which the default's
	// vertical test (sin 20 deg = 0.342 > 0.2) refuses.
	GroundNode slope;
	slope.local = tilted(10);  // through the origin
	slope.z = 0;
	EXPECT_TRUE(rrt.paperNormalOk(slope, tilted(20)));
	EXPECT_FALSE(rrt.paperNormalOk(slope, tilted(22)));  // sin 12 deg = 0.2079
	// The printed elevation test on that 10 deg slope: a node d_n = 0.4 m up
	// it, on the same plane, is tan(10 deg) * 0.4 = 0.0705 m above the parent,
	// more than E_th: refused (the extrapolated reading of the parent's plane,
	// used until issue #30, gave 0 and took it). A 7 deg slope gives
	// tan(7 deg) * 0.4 = 0.0491: taken.
	EXPECT_FALSE(rrt.paperElevationOk(slope, 0.4, 0, tilted(10)));
	GroundNode seven;
	seven.local = tilted(7);
	seven.z = 0;
	EXPECT_TRUE(rrt.paperElevationOk(seven, 0.4, 0, tilted(7)));
}

namespace
{
/** A noisy 6 x 6 m floor (3 mm), 5 cm cells, 4 x 4 samples per cell. */
ElevationGrid noisyFloor(double noise)
{
	ElevationGrid grid(gamtest::makeGeometry(-3, -3, 0.05, 120, 120));
	std::mt19937 rng(7);
	BinnedPoints b;
	gamtest::sampleSurface(
		grid, -3, 3, -3, 3, [](double, double) { return 0.0; }, 4, noise, rng, b);
	gamtest::insertAll(grid, b);
	return grid;
}
double parentDistance(const GroundDetection& d, const GroundNode& n)
{
	const GroundNode& p = d.nodes[size_t(n.parent)];
	return std::hypot(double(n.x - p.x), double(n.y - p.y));
}
}  // namespace

TEST(PaperRrt, StepsOfExactlyDnAndTheFallbackThroughANeighbour)
{
	const ElevationGrid grid = noisyFloor(0.003);
	RrtGpdParams rp;
	rp.variant = MethodVariant::Paper;
	// A tight N_th (0.03: 1.7 deg; the 3 mm noise tilts a 3 x 3 local fit by
	// about rms / (sqrt(6) d_r) = 0.003 / 0.122 = 0.025 rad) so that some new
	// nodes fail the normal test against x_near; lines 17-22 then try the
	// other nodes within d_n (only after the normal test, as printed).
	rp.normal_threshold = 0.03;
	RrtGroundDetector rrt(rp);
	GroundDetection d;
	rrt.detect(grid, GroundSeedHint{}, d);
	ASSERT_TRUE(d.ok()) << d.describe();
	// x_new is exactly d_n = 0.4 m from x_near, then snapped to its cell
	// centre (parent on a centre too): off by at most half a cell diagonal,
	// 0.05 * sqrt(2) / 2 = 0.0354 m.
	const double snap = 0.05 * std::sqrt(2.0) / 2 + 1e-6;
	size_t viaNear = 0, viaNeighbour = 0;
	for (size_t i = 1; i < d.nodes.size(); i++)
	{
		const double pd = parentDistance(d, d.nodes[i]);
		EXPECT_LE(pd, 0.4 + snap) << "node " << i;
		// A parent closer than d_n - snap is not the x_near the step came from:
		// the node joined through the fallback over the nodes within d_n.
		(pd >= 0.4 - snap ? viaNear : viaNeighbour)++;
	}
	EXPECT_GT(viaNear, 0u);
	EXPECT_GT(viaNeighbour, 0u) << "no node joined through a neighbour (lines 17-22)";
	EXPECT_EQ(d.planes.size(), 1u) << "the paper fits one ground plane";

	// The default variant steps min(d_n, distance to q): short steps occur.
	RrtGpdParams dp;
	RrtGroundDetector dflt(dp);
	GroundDetection dd;
	dflt.detect(grid, GroundSeedHint{}, dd);
	ASSERT_TRUE(dd.ok());
	size_t shortSteps = 0;
	for (size_t i = 1; i < dd.nodes.size(); i++)
		if (parentDistance(dd, dd.nodes[i]) < 0.4 - snap) shortSteps++;
	EXPECT_GT(shortSteps, 0u);
}

TEST(PaperRrt, SearchWindowDriftsTowardTheNodes)
{
	const GridGeometry g = gamtest::makeGeometry(-3, -3, 0.05, 120, 120);  // -3..3 m
	PaperSearchWindow w;
	w.add(0.0, 0.0);  // the seed
	double x0, x1, y0, y1;
	// One node: centred on it, half side = the margin (1 m).
	w.bounds(g, 1.0, x0, x1, y0, y1);
	EXPECT_DOUBLE_EQ(x0, -1.0);
	EXPECT_DOUBLE_EQ(x1, 1.0);
	EXPECT_DOUBLE_EQ(y0, -1.0);
	EXPECT_DOUBLE_EQ(y1, 1.0);
	// Nodes at (0.4, 0) and (0.8, 0.4): centroid (1.2 / 3, 0.4 / 3) = (0.4, 0.13333).
	// x: largest offset max(0.4 - 0, 0.8 - 0.4) = 0.4, half side 1.4 -> [-1.0, 1.8];
	// y: max(0.13333 - 0, 0.4 - 0.13333) = 0.26667, half side 1.26667
	//    -> [0.13333 - 1.26667, 0.13333 + 1.26667] = [-1.13333, 1.4].
	w.add(0.4, 0.0);
	w.add(0.8, 0.4);
	w.bounds(g, 1.0, x0, x1, y0, y1);
	EXPECT_NEAR(x0, -1.0, 1e-12);
	EXPECT_NEAR(x1, 1.8, 1e-12);
	EXPECT_NEAR(y0, -1.133333333333, 1e-9);
	EXPECT_NEAR(y1, 1.4, 1e-12);
	// Five more nodes far along +x at (2.4, 0): centroid x = (1.2 + 12) / 8 = 1.65;
	// largest offset max(1.65 - 0, 2.4 - 1.65) = 1.65, half side 2.65 ->
	// [-1.0, 4.3], cut by the grid to [-1.0, 3.0]. The window's centre moved
	// from the seed to x = 1.65, toward the explored nodes.
	for (int i = 0; i < 5; i++) w.add(2.4, 0.0);
	w.bounds(g, 1.0, x0, x1, y0, y1);
	EXPECT_NEAR(x0, -1.0, 1e-12);
	EXPECT_DOUBLE_EQ(x1, 3.0);
	// The tree on a floor: every node lies in the final window, the window
	// has left the seed's [-1, 1]^2 box, and the nodes spread beyond it.
	const ElevationGrid grid = noisyFloor(0.003);
	RrtGpdParams rp;
	rp.variant = MethodVariant::Paper;
	RrtGroundDetector rrt(rp);
	GroundDetection d;
	rrt.detect(grid, GroundSeedHint{}, d);
	ASSERT_TRUE(d.ok()) << d.describe();
	double far = 0;
	for (const GroundNode& n : d.nodes)
		far = std::max(far, std::max(std::abs(double(n.x - d.nodes[0].x)), std::abs(double(n.y - d.nodes[0].y))));
	EXPECT_GT(far, 1.0 + 0.4) << "the tree never left the seed's first window";
}

namespace
{
/** The default finds no seed in `grid`; the paper's tree finds the ground at
 * height z (within tol) under the robot. */
void expectOnlyThePaperFindsGround(const ElevationGrid& grid, double z, double tol)
{
	RrtGpdParams paperParams;
	paperParams.variant = MethodVariant::Paper;
	GroundDetection dd, pd;
	RrtGroundDetector(RrtGpdParams{}).detect(grid, GroundSeedHint{}, dd);
	EXPECT_EQ(dd.status, GroundDetection::Status::NoValidSeed);
	RrtGroundDetector(paperParams).detect(grid, GroundSeedHint{}, pd);
	ASSERT_TRUE(pd.ok()) << pd.describe();
	EXPECT_NEAR(pd.plane().heightAt(0.5, 0.5), z, tol);
}
}  // namespace

TEST(PaperRrt, NoneOfTheDefaultGuards)
{
	// Issue #30: rrt_variant = paper runs without the default's guards. Each
	// case below is refused by the default and taken by the paper variant.

	// 1. max_cell_std (5 cm): a floor whose every cell holds the samples
	// -6 cm and +6 cm (std 6 cm, mean 0; two samples, below the 3-sigma
	// rule's minimum count). The default finds no cell it trusts, the paper
	// fits the cells' means: the plane z = 0.
	{
		ElevationGrid grid(gamtest::makeGeometry(-3, -3, 0.05, 120, 120));
		BinnedPoints b;
		for (int cy = 0; cy < 120; cy++)
			for (int cx = 0; cx < 120; cx++)
				for (float z : {-0.06f, 0.06f}) b.push(uint32_t(grid.geometry().index(cx, cy)), z);
		gamtest::insertAll(grid, b);
		expectOnlyThePaperFindsGround(grid, 0.0, 1e-3);
	}
	// 2. The seed's expected height (seed_height_tolerance 0.3 m): the floor
	// 0.5 m below where the robot expects it.
	{
		ElevationGrid grid(gamtest::makeGeometry(-3, -3, 0.05, 120, 120));
		std::mt19937 rng(3);
		BinnedPoints b;
		gamtest::sampleSurface(
			grid, -3, 3, -3, 3, [](double, double) { return -0.5; }, 4, 0.002, rng, b);
		gamtest::insertAll(grid, b);
		expectOnlyThePaperFindsGround(grid, -0.5, 0.01);
	}
	// 3. RANSAC without the refit: the paper's plane is the best candidate,
	// through three of the node centres; the default refits to the inliers.
	{
		std::vector<Eigen::Vector3d> pts;
		std::mt19937 rng(5);
		std::normal_distribution<double> n(0, 0.005);
		for (int i = 0; i < 40; i++) pts.emplace_back(0.1 * (i % 8), 0.1 * (i / 8), n(rng));
		RansacParams p;
		p.inlier_distance = 0.05;
		p.refine = false;
		std::mt19937 r1(1);
		const auto best = fitPlaneRansac(pts, p, r1);
		ASSERT_TRUE(best);
		int through = 0;
		for (const auto& q : pts) through += std::abs(best->plane.signedDistance(q.x(), q.y(), q.z())) < 1e-9;
		EXPECT_GE(through, 3) << "a candidate plane passes through its three points";
		p.refine = true;
		std::mt19937 r2(1);
		const auto refit = fitPlaneRansac(pts, p, r2);
		ASSERT_TRUE(refit);
		through = 0;
		for (const auto& q : pts) through += std::abs(refit->plane.signedDistance(q.x(), q.y(), q.z())) < 1e-9;
		EXPECT_LT(through, 3) << "the least-squares plane of 40 noisy points passes through none of them";
	}
}
