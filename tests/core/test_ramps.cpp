// Ground-aware mapping for MRPT
// Issue #13 item 5, "ramps stay free": hand-built 2.5D maps of a floor with a
// narrow, steep ramp (8 deg, 0.7 m wide, as in config/scenes/ramp_8deg_0.7m),
// a 4 cm cable protector lying across it, and a ramp whose landing is larger
// than the floor around the robot. Default parameters throughout: nothing is
// tuned to these grids.
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <random>

#include "gam/core/InverseSensorModel.h"
#include "gam/core/PatchMemory.h"
#include "gam/core/RrtGroundDetector.h"
#include "test_helpers.h"

using namespace gam;
using gamtest::deg2rad;
using gamtest::inRect;
using gamtest::rad2deg;

namespace
{
// Floor z = 0 on x in [-1, 4.5), y in [-2.5, 2.5); the robot stands at (0, 0).
// Ramp (as config/scenes/ramp_8deg_0.7m): 0.7 m wide (|y| < 0.35), foot at
// x = 1.0, rising along +x at 8 deg for 1.2 m, a 0.6 m landing, and 1.2 m
// down again at 8 deg to the floor at x = 4.0; solid sides (vertical steps).
// Heights, by hand: tan 8 deg = 0.1405, so the ramp is 0.1405 m up 1 m past
// its foot and 0.1686 m at its top (x = 2.2); the landing is flat at
// 0.1686 m on x in [2.2, 2.8); the way down is 0.1686 - 0.1405 (x - 2.8).
constexpr double kFoot = 1.0, kRampLen = 1.2, kLanding = 0.6, kHalfWidth = 0.35;
const double kTan8 = std::tan(deg2rad(8.0));              // 0.1405
const double kTop = kTan8 * kRampLen;                     // 0.1686 m
constexpr double kEnd = kFoot + 2 * kRampLen + kLanding;  // 4.0 m

bool onRamp(double x, double y) { return x >= kFoot && x < kEnd && std::abs(y) < kHalfWidth; }
double rampZ(double x, double y)
{
	if (!onRamp(x, y)) return 0.0;
	if (x < kFoot + kRampLen) return kTan8 * (x - kFoot);
	if (x < kFoot + kRampLen + kLanding) return kTop;
	return kTop - kTan8 * (x - kFoot - kRampLen - kLanding);
}

// The cable protector: 4 cm high, 8 cm long (along x), lying across the whole
// ramp 0.5 m past its foot, its bottom on the ramp: top = tan 8 deg * 0.5 +
// 0.04 = 0.0703 + 0.04 = 0.1103 m at x = 1.5.
constexpr double kCableX0 = 1.5, kCableX1 = 1.58, kCableH = 0.04;
bool onCable(double x, double y) { return x >= kCableX0 && x < kCableX1 && std::abs(y) < kHalfWidth; }

// The surface z(x, y) where `where` holds, 3 x 3 samples per 5 cm cell with
// `noise` [m], into the 2.5D map as the pipeline puts them (3-sigma filter,
// IDW).
template <class Where, class Height>
void sampleIntoGrid(ElevationGrid& grid, Where where, Height z, double noise, std::mt19937& rng)
{
	BinnedPoints b;
	gamtest::sampleSurfaceIf(grid, where, z, 3, noise, rng, b);
	gamtest::insertAll(grid, b);
	grid.interpolateIdw(IdwParams{});
}

// RRT-GPD from a robot at the origin on the floor.
GroundDetection detectFromOrigin(const ElevationGrid& grid)
{
	RrtGroundDetector det;
	GroundDetection out;
	det.detect(grid, {0, 0, 0}, out);
	return out;
}

// 3 x 3 samples per 5 cm cell with 2 mm noise (a Kinect One 2-3 m away).
void buildRampScene(ElevationGrid& grid, bool cable, uint32_t seed = 13, double noise = 0.002)
{
	std::mt19937 rng(seed);
	sampleIntoGrid(
		grid, [](double x, double y) { return inRect(x, y, -1.0, 4.5, -2.5, 2.5); },
		[cable](double x, double y) { return rampZ(x, y) + (cable && onCable(x, y) ? kCableH : 0.0); }, noise, rng);
}

// The camera: 1 m above the floor at the robot.
const Eigen::Vector3d kSensor(0.0, 0.0, 1.0);

struct RampCells
{
	size_t ramp = 0, rampObstacle = 0, rampFree = 0;  ///< ramp cells off its sides and the cable
	size_t cable = 0, cableObstacle = 0;
};

// Ramp cells: inside the footprint, one cell (5 cm) away from its sides (the
// side cells hold both the floor and the ramp's edge: a real step of up to
// 17 cm) and from the cable protector.
RampCells classifyRamp(const ElevationGrid& grid, const InverseSensorModel& ism)
{
	const GridGeometry& g = grid.geometry();
	RampCells r;
	for (uint32_t idx : grid.observedCells())
	{
		const int cx = int(idx % uint32_t(g.nx)), cy = int(idx / uint32_t(g.nx));
		const double x = g.cx(cx), y = g.cy(cy);
		const float p = ism.evidence()[idx];
		if (onCable(x, y))
		{
			r.cable++;
			r.cableObstacle += p > 0.5f;
			continue;
		}
		if (!onRamp(x, y) || std::abs(y) > kHalfWidth - 0.05) continue;
		if (x >= kCableX0 - 0.05 && x < kCableX1 + 0.05) continue;
		r.ramp++;
		r.rampObstacle += p > 0.5f;
		r.rampFree += p < 0.5f;
	}
	return r;
}
}  // namespace

TEST(Ramps, NarrowSteepRampGetsItsOwnPatch)
{
	ElevationGrid grid;
	buildRampScene(grid, false);
	RrtGroundDetector det;
	GroundDetection out;
	det.detect(grid, {0, 0, 0}, out);
	ASSERT_EQ(out.status, GroundDetection::Status::Ok) << out.describe();
	std::cout << "8 deg, 0.7 m ramp: " << out.describe() << ", " << out.fill_nodes << " filled nodes" << std::endl;
	// planes[0]: the floor under the robot.
	EXPECT_LT(rad2deg(out.plane().tiltAngle()), 0.3);
	EXPECT_NEAR(out.plane().heightAt(0, 0), 0.0, 0.005);
	// An extra plane is the way up: 8 deg, 0.1405 m up 1 m past the foot
	// (x = 2.0), 0 at the foot; one is the landing, flat at 0.1686 m.
	int ramp = -1, landing = -1;
	for (size_t k = 1; k < out.planes.size(); k++)
	{
		const Plane& pl = out.planes[k];
		if (std::abs(rad2deg(pl.tiltAngle()) - 8.0) < 1.0 && std::abs(pl.heightAt(2.0, 0.0) - kTan8) < 0.01)
			ramp = int(k);
		if (rad2deg(pl.tiltAngle()) < 1.0 && std::abs(pl.heightAt(2.5, 0.0) - kTop) < 0.01) landing = int(k);
	}
	ASSERT_GE(ramp, 1) << out.describe();
	EXPECT_NEAR(out.planes[size_t(ramp)].heightAt(kFoot, 0.0), 0.0, 0.01);
	EXPECT_GE(landing, 1) << out.describe();
	// The random tree alone put few nodes on it; fill_patches tiled it.
	EXPECT_GT(out.fill_nodes, 0u);
	size_t onIt = 0;
	for (const GroundNode& n : out.nodes) onIt += n.plane_id == ramp;
	EXPECT_GE(onIt, 15u);
	// The extra patches were fitted with the measured noise, not 2.5 cm:
	// 3 sigma (sigma ~ 1-2 mm here) + d_r / 2 * tan(asin 0.2) = 5.1 mm.
	EXPECT_GT(out.patch_inlier_distance, 0.005);
	EXPECT_LT(out.patch_inlier_distance, 0.015);

	// Without filling, the tree's own nodes on the 0.7 m ramp (one every
	// ~d_n = 0.4 m, reached only through its foot) make no 8 deg patch here.
	RrtGpdParams p;
	p.fill_patches = false;
	det.setParams(p);
	GroundDetection bare;
	det.detect(grid, {0, 0, 0}, bare);
	ASSERT_TRUE(bare.ok());
	EXPECT_EQ(bare.fill_nodes, 0u);
	size_t bareOnRamp = 0;
	for (const GroundNode& n : bare.nodes) bareOnRamp += onRamp(n.x, n.y) && n.x > kFoot + 0.2;
	std::cout << "  tree nodes on the ramp without filling: " << bareOnRamp << std::endl;
	EXPECT_LT(bareOnRamp, onIt);
}

TEST(Ramps, NoisyFloorBeyondTheEvidenceRangeIsLeftOut)
{
	// The ramp scene seen by a noisy wide camera: the floor and ramp within
	// 2.9 m (2D) of the sensor with 2 mm of noise per sample, the floor
	// beyond with 25 mm (a D435's far floor). The map takes evidence within
	// 2.9 m only (its range of trust), so fill_patches adds no node beyond
	// it, and the patches' inlier distance is the noise within it.
	ElevationGrid grid;
	std::mt19937 rng(13);
	BinnedPoints b;
	const auto near = [](double x, double y) { return inRect(x, y, -1.0, 4.5, -2.5, 2.5) && std::hypot(x, y) < 2.9; };
	const auto far = [](double x, double y) { return inRect(x, y, -1.0, 4.5, -2.5, 2.5) && std::hypot(x, y) >= 2.9; };
	gamtest::sampleSurfaceIf(grid, near, rampZ, 3, 0.002, rng, b);
	gamtest::sampleSurfaceIf(grid, far, rampZ, 3, 0.025, rng, b);
	gamtest::insertAll(grid, b);
	grid.interpolateIdw(IdwParams{});

	RrtGroundDetector det;
	GroundSeedHint all{0, 0, 0};  // fill and noise band over the whole grid
	GroundDetection wide;
	det.detect(grid, all, wide);
	ASSERT_TRUE(wide.ok()) << wide.describe();

	GroundSeedHint hint = all;
	hint.fill_range = 2.9;
	GroundDetection inRange;
	det.detect(grid, hint, inRange);
	ASSERT_TRUE(inRange.ok()) << inRange.describe();
	std::cout << "patch inlier distance: whole grid " << wide.patch_inlier_distance << " m, within 2.9 m "
			  << inRange.patch_inlier_distance << " m; filled nodes " << wide.fill_nodes << " / " << inRange.fill_nodes
			  << std::endl;

	// Every filled node lies within 2.9 m of the sensor (at (0, 0)).
	ASSERT_GT(inRange.fill_nodes, 0u);
	for (size_t i = inRange.nodes.size() - inRange.fill_nodes; i < inRange.nodes.size(); i++)
		EXPECT_LE(std::hypot(inRange.nodes[i].x, inRange.nodes[i].y), 2.9 + 1e-6);
	size_t farFilled = 0;
	for (size_t i = wide.nodes.size() - wide.fill_nodes; i < wide.nodes.size(); i++)
		farFilled += std::hypot(wide.nodes[i].x, wide.nodes[i].y) > 2.9;
	EXPECT_GT(farFilled, 0u);  // without the bound the noisy far floor draws filled nodes
	// The band within 2.9 m is that of 2 mm noise (3 sigma of the nodes plus
	// d_r / 2 * tan(asin 0.2) = 5.1 mm, as NarrowSteepRampGetsItsOwnPatch);
	// the far floor's noise widens the whole grid's.
	EXPECT_LT(inRange.patch_inlier_distance, 0.015);
	EXPECT_GT(wide.patch_inlier_distance, inRange.patch_inlier_distance);
	// And the way up is fitted at its own 8 deg.
	bool ramp8 = false;
	for (size_t k = 1; k < inRange.planes.size(); k++)
		ramp8 |= std::abs(rad2deg(inRange.planes[k].tiltAngle()) - 8.0) < 1.0 &&
				 std::abs(inRange.planes[k].heightAt(2.0, 0.0) - kTan8) < 0.01;
	EXPECT_TRUE(ramp8) << inRange.describe();
}

TEST(Ramps, TheWayDownIsFittedAtItsOwnSlope)
{
	// The way down (x in [2.8, 4.0)) is a patch at 8 deg: 0.1686 - 0.1405 *
	// 0.6 = 0.0843 m high at x = 3.4. The landing's last nodes (x < 2.8, flat)
	// lie within a centimetre of it near the crest, but their own local
	// planes part from it by 8 deg (sine 0.139), more than the inlier
	// distance across a 15 cm window (~0.01 / 0.15 = 0.07) plus 3 sigma of a
	// flat 3 x 3 fit's slope (3 rms / (sqrt(6) d_r): 0.025 for an rms of
	// 1 mm): they stay out of it, and it keeps its slope.
	// 4 mm per sample (a Kinect One ~3.5 m away): the patches' inlier band
	// widens with the noise. Without the crease rule this scene's way down
	// took the landing's last nodes and came out at 7.4 deg (1 seed of the 5
	// tried; the rule holds all 5 at 8 +- 0.5 deg).
	ElevationGrid grid;
	buildRampScene(grid, false, 13, 0.004);
	RrtGroundDetector det;
	GroundDetection out;
	det.detect(grid, {0, 0, 0}, out);
	ASSERT_EQ(out.status, GroundDetection::Status::Ok) << out.describe();
	int down = -1;
	for (size_t k = 1; k < out.planes.size(); k++)
		if (std::abs(out.planes[k].heightAt(3.4, 0.0) - (kTop - kTan8 * 0.6)) < 0.02 && out.planes[k].a > 0.05)
			down = int(k);
	ASSERT_GE(down, 1) << out.describe();
	const Plane& pl = out.planes[size_t(down)];
	EXPECT_NEAR(rad2deg(pl.tiltAngle()), 8.0, 0.5) << out.describe();
	EXPECT_NEAR(pl.heightAt(3.4, 0.0), kTop - kTan8 * 0.6, 0.005);
	for (const GroundNode& n : out.nodes)
	{
		if (n.plane_id == down)
		{
			EXPECT_GE(n.x, kFoot + kRampLen + kLanding - 0.05) << "a landing node in the way down";
		}
	}
}

TEST(Ramps, NarrowSteepRampCellsGetNoObstacleEvidence)
{
	ElevationGrid grid;
	buildRampScene(grid, false);
	RrtGroundDetector det;
	GroundDetection out;
	det.detect(grid, {0, 0, 0}, out);
	ASSERT_TRUE(out.ok()) << out.describe();
	InverseSensorModel ism;
	IsmStats st;
	ism.compute(grid, out, kSensor, 5.0, st);
	const RampCells r = classifyRamp(grid, ism);
	std::cout << "ramp cells: " << r.ramp << ", obstacle " << r.rampObstacle << ", free " << r.rampFree << std::endl;
	// 3 m x 0.6 m of ramp, landing and way down off its sides: 60 x 12 cells
	// (fewer where the way down is steeper than the line of sight... not here:
	// every cell of the grid is sampled).
	ASSERT_GT(r.ramp, 600u);
	EXPECT_EQ(r.rampObstacle, 0u);
	EXPECT_GE(double(r.rampFree), 0.98 * double(r.ramp));

	// The same frame against the floor plane alone: the ramp is above the
	// band (d_pth 3 cm + 3 sigma of a 2 mm floor) from 0.25 m past its foot
	// (tan 8 deg * 0.25 = 3.5 cm), i.e. most of it is an obstacle.
	IsmParams single;
	single.local_planes = false;
	InverseSensorModel ism1(single);
	ism1.compute(grid, out, kSensor, 5.0, st);
	const RampCells r1 = classifyRamp(grid, ism1);
	EXPECT_GT(double(r1.rampObstacle), 0.8 * double(r1.ramp));
}

TEST(Ramps, TheFirstRowsOfALandingAreTheRampsCrestNotALine)
{
	// The ramp scene seen only to x = 2.45 m (the rest beyond the camera's
	// range of trust): the landing (flat at 0.1686 m from x = 2.2) shows
	// 0.25 m, one or two rows of filled nodes, a line by the patch rule
	// (what the top of a cable protector also is). Its nodes lie below the
	// ramp's plane extended (0.1686 + 0.1405 (x - 2.2): 1.8 cm above the
	// landing 0.125 m past the top) and it meets the ramp at the crest: it is
	// the landing all the same, and its cells (x in [2.2, 2.45): 5 x 12 off
	// the sides) are free. Without the rule (measured): 2 planes, and 24 of
	// the 60 cells got obstacle evidence against the ramp's plane extended.
	ElevationGrid grid;
	std::mt19937 rng(13);
	sampleIntoGrid(
		grid, [](double x, double y) { return inRect(x, y, -1.0, 2.45, -2.5, 2.5); }, rampZ, 0.002, rng);
	const GroundDetection out = detectFromOrigin(grid);
	ASSERT_TRUE(out.ok()) << out.describe();
	std::cout << "ramp seen to 2.45 m: " << out.describe() << std::endl;
	int landing = -1;
	for (size_t k = 1; k < out.planes.size(); k++)
		if (rad2deg(out.planes[k].tiltAngle()) < 1.0 && std::abs(out.planes[k].heightAt(2.35, 0.0) - kTop) < 0.01)
			landing = int(k);
	ASSERT_GE(landing, 1) << out.describe();
	InverseSensorModel ism;
	IsmStats st;
	ism.compute(grid, out, kSensor, 5.0, st);
	const GridGeometry& g = grid.geometry();
	size_t cells = 0, obstacle = 0;
	for (uint32_t idx : grid.observedCells())
	{
		const double x = g.cx(int(idx % uint32_t(g.nx))), y = g.cy(int(idx / uint32_t(g.nx)));
		if (x < kFoot + kRampLen || x >= 2.45 || std::abs(y) > kHalfWidth - 0.05) continue;
		cells++;
		obstacle += ism.evidence()[idx] > 0.5f;
	}
	std::cout << "landing cells " << cells << ", obstacle " << obstacle << std::endl;
	ASSERT_EQ(cells, 60u);
	EXPECT_EQ(obstacle, 0u);
}

TEST(Ramps, CableProtectorOnTheRampIsStillAnObstacle)
{
	ElevationGrid grid;
	buildRampScene(grid, true);
	RrtGroundDetector det;
	GroundDetection out;
	det.detect(grid, {0, 0, 0}, out);
	ASSERT_TRUE(out.ok()) << out.describe();
	std::cout << "ramp + cable: " << out.describe() << std::endl;
	InverseSensorModel ism;
	IsmStats st;
	ism.compute(grid, out, kSensor, 5.0, st);
	const RampCells r = classifyRamp(grid, ism);
	std::cout << "cable cells " << r.cable << ", obstacle " << r.cableObstacle << "; ramp cells " << r.ramp
			  << ", obstacle " << r.rampObstacle << std::endl;
	// 2 cells along x (1.5-1.58 m: cell centres 1.525, 1.575) x 14 across.
	ASSERT_GE(r.cable, 26u);
	// Its top is 4 cm above the ramp plane: beyond the ground band of 3 cm +
	// 3 x 2 mm = 3.6 cm. The cells of the row at 1.55-1.60 m are 60 % cable:
	// their top is ~3.9 cm above the ramp, 3 mm outside the band, so a ramp
	// plane fitted 3 mm high there takes one in (1 of 28 with this seed).
	EXPECT_GE(double(r.cableObstacle), 0.9 * double(r.cable));
	// And the ramp around it stays free.
	EXPECT_EQ(r.rampObstacle, 0u);
	// No extra patch is the cable's top: a row of nodes 8 cm wide is a line.
	for (size_t k = 1; k < out.planes.size(); k++)
		EXPECT_GT(std::abs(out.planes[k].signedDistance(1.54, 0.0, kTan8 * 0.54 + kCableH)), 0.02)
			<< "plane " << k << " holds the cable's top";
}

TEST(Ramps, GroundPlaneIsTheFloorUnderTheRobotEvenWhenTheLandingIsLarger)
{
	// Floor only near the robot: x in [-1, 1) (2 m x 4 m = 8 m^2); a 6 deg ramp
	// 4 m wide on x in [1, 2) (1 m: up to tan 6 deg = 0.1051 m); a landing at
	// 0.1051 m on x in [2, 5) (3 m x 4 m = 12 m^2, 1.5 x the floor). The
	// largest consensus among the nodes is the landing (or a plane tilted
	// onto the ramp through the seed); the ground plane must be the floor
	// the seed lies on: height 0 and tilt 0 at the robot.
	const double tan6 = std::tan(deg2rad(6.0));
	GridGeometry g;
	g.x_min = -1.5;
	g.y_min = -2.5;
	g.nx = 140;
	g.ny = 100;
	ElevationGrid grid(g);
	std::mt19937 rng(5);
	sampleIntoGrid(
		grid, [](double x, double y) { return inRect(x, y, -1.0, 5.0, -2.0, 2.0); },
		[tan6](double x, double) { return x < 1.0   ? 0.0
										  : x < 2.0 ? tan6 * (x - 1.0)
													: tan6; }, 0.002, rng);
	const GroundDetection out = detectFromOrigin(grid);
	ASSERT_TRUE(out.ok()) << out.describe();
	size_t floorNodes = 0, landingNodes = 0;
	for (const GroundNode& n : out.nodes)
	{
		floorNodes += n.x < 1.0;
		landingNodes += n.x >= 2.0;
	}
	std::cout << "floor nodes " << floorNodes << ", landing nodes " << landingNodes << ": " << out.describe()
			  << std::endl;
	EXPECT_GT(landingNodes, floorNodes);  // the premise: the landing has more nodes
	EXPECT_NEAR(out.plane().heightAt(0, 0), 0.0, 0.005);
	EXPECT_LT(rad2deg(out.plane().tiltAngle()), 0.3);
	// The landing is a patch of its own, 0.1051 m up.
	bool landing = false;
	for (size_t k = 1; k < out.planes.size(); k++)
		landing |= std::abs(out.planes[k].heightAt(3.5, 0.0) - tan6) < 0.01 && rad2deg(out.planes[k].tiltAngle()) < 1.0;
	EXPECT_TRUE(landing) << out.describe();

	// And the robot's floor is ground in the ISM, the landing too.
	InverseSensorModel ism;
	IsmStats st;
	ism.compute(grid, out, kSensor, 5.0, st);
	size_t floorCells = 0, floorObstacle = 0, landingCells = 0, landingObstacle = 0;
	for (uint32_t idx : grid.observedCells())
	{
		const int cx = int(idx % uint32_t(g.nx)), cy = int(idx / uint32_t(g.nx));
		const double x = g.cx(cx), y = g.cy(cy);
		if (std::abs(y) > 1.9) continue;
		if (x > -0.9 && x < 0.9)
		{
			floorCells++;
			floorObstacle += ism.evidence()[idx] > 0.5f;
		}
		else if (x > 2.1 && x < 4.4)
		{
			landingCells++;
			landingObstacle += ism.evidence()[idx] > 0.5f;
		}
	}
	EXPECT_GT(floorCells, 1000u);
	EXPECT_EQ(floorObstacle, 0u);
	EXPECT_GT(landingCells, 1000u);
	EXPECT_LT(double(landingObstacle), 0.01 * double(landingCells));
}

TEST(Ramps, FlatFloorAddsNoFilledNodes)
{
	// Nothing off the ground plane, no node tilted against it (noise-free
	// floor): fill_patches adds nothing and the result is the tree's.
	ElevationGrid grid;
	std::mt19937 rng(3);
	BinnedPoints b;
	gamtest::sampleSurfaceIf(
		grid, [](double x, double y) { return inRect(x, y, -3, 3, -3, 3); }, [](double, double) { return 0.0; }, 3, 0.0,
		rng, b);
	gamtest::insertAll(grid, b);
	RrtGroundDetector det;
	GroundDetection out;
	det.detect(grid, {0, 0, 0}, out);
	ASSERT_TRUE(out.ok());
	EXPECT_EQ(out.fill_nodes, 0u);
	EXPECT_EQ(out.planes.size(), 1u);
	RrtGpdParams p;
	p.fill_patches = false;
	RrtGroundDetector bare(p);
	GroundDetection ref;
	bare.detect(grid, {0, 0, 0}, ref);
	ASSERT_EQ(ref.nodes.size(), out.nodes.size());
	EXPECT_EQ(ref.plane().d, out.plane().d);
}

TEST(Ramps, ASliverOfARampEarlierFramesFittedIsJudgedAgainstTheirPatch)
{
	// Two frames see the whole ramp and fit its patch; a third sees only a
	// sliver of it: the way up along its side, y in [0.2, 0.35), x in
	// [1.5, 2.2) (the ramp at the side edge of the view, as the D435 sees
	// office_traverse's). Three columns of cells: too narrow for a patch of
	// its own, so that frame's ground is the floor plane alone, against
	// which the sliver stands tan 8 deg * (1.5 - 1.0) = 0.070 m to
	// tan 8 deg * 1.2 = 0.169 m high: obstacles, far beyond the band (d_pth
	// 3 cm + 3 sigma of the 2 mm noise). Judged also against the patch the
	// earlier frames fitted (patch_memory), the sliver is ramp: free.
	ElevationGrid whole;
	buildRampScene(whole, false);
	const GroundDetection seen = detectFromOrigin(whole);
	ASSERT_TRUE(seen.ok());
	ASSERT_GE(seen.planes.size(), 2u) << seen.describe();
	const double band = seen.patch_inlier_distance, reach = IsmParams{}.plane_support_radius;
	PatchMemory memory;
	memory.apply(seen, 0.0, 1.0, band, reach, IsmParams{}.traversable_step);  // the first frame that fits it
	memory.apply(seen, 0.1, 1.0, band, reach, IsmParams{}.traversable_step);  // the second

	auto inSliver = [](double x, double y) { return x >= 1.5 && x < 2.2 && y >= 0.2 && y < kHalfWidth; };
	ElevationGrid grid;
	std::mt19937 rng(17);
	sampleIntoGrid(
		grid,
		[&](double x, double y) { return inRect(x, y, -1.0, 4.5, -2.5, 2.5) && (!onRamp(x, y) || inSliver(x, y)); },
		rampZ, 0.002, rng);
	const GroundDetection sliver = detectFromOrigin(grid);
	ASSERT_TRUE(sliver.ok()) << sliver.describe();
	ASSERT_EQ(sliver.planes.size(), 1u) << "the sliver got a patch of its own: " << sliver.describe();

	auto obstacleCells = [&](const GroundDetection& det) {
		InverseSensorModel ism;
		IsmStats st;
		ism.compute(grid, det, kSensor, 5.0, st);
		const GridGeometry& g = grid.geometry();
		size_t cells = 0, obstacle = 0;
		for (uint32_t idx : grid.observedCells())
		{
			const double x = g.cx(int(idx % uint32_t(g.nx))), y = g.cy(int(idx / uint32_t(g.nx)));
			// Off the ramp's side (the cell at y in [0.3, 0.35) holds its edge).
			if (!inSliver(x, y) || y >= kHalfWidth - 0.05) continue;
			cells++;
			obstacle += ism.evidence()[idx] > 0.5f;
		}
		return std::make_pair(cells, obstacle);
	};
	// 14 x 2 cells: x in [1.5, 2.2) by 5 cm, y in [0.2, 0.3).
	const auto [cells, alone] = obstacleCells(sliver);
	ASSERT_EQ(cells, 28u);
	EXPECT_EQ(alone, cells) << "against the floor alone every sliver cell is an obstacle";
	const GroundDetection& judged = memory.apply(sliver, 0.2, 1.0, band, reach, IsmParams{}.traversable_step);
	// The way up and the way down; the landing is level (PatchMemory::sloped).
	ASSERT_EQ(seen.planes.size(), 4u) << seen.describe();
	EXPECT_EQ(memory.applied(), 2u);
	EXPECT_EQ(judged.remembered_from, 1u);
	const auto [cells2, remembered] = obstacleCells(judged);
	EXPECT_EQ(cells2, cells);
	EXPECT_EQ(remembered, 0u);
}

TEST(Ramps, ARememberedPatchDoesNotJudgeWhereTheFramesOwnPatchApplies)
{
	// The ramp with its cable protector, whose frame fits the ramp's patch
	// itself. Earlier frames (twice) fitted a wrong patch: the ramp's plane
	// 4 cm higher, on nodes around the cable, the plane of the cable's top.
	// Offered beside the frame's planes everywhere, it would hold the cable's
	// cells (each voxel is judged against the plane it fits best): where the
	// frame's own patch applies, it is not offered, and the cable stays an
	// obstacle as without any memory (CableProtectorOnTheRampIsStillAnObstacle).
	ElevationGrid grid;
	buildRampScene(grid, true);
	const GroundDetection out = detectFromOrigin(grid);
	ASSERT_TRUE(out.ok()) << out.describe();
	ASSERT_GE(out.planes.size(), 2u) << out.describe();

	// z = tan 8 deg (x - 1) + 0.04: tan8 x - z + (0.04 - tan8) = 0, normalised.
	const double n = std::sqrt(1.0 + kTan8 * kTan8);
	const Plane cableTop{-kTan8 / n, 0, 1 / n, (kTan8 - kCableH) / n};
	EXPECT_NEAR(cableTop.heightAt(1.54, 0.0), kTan8 * 0.54 + kCableH, 1e-9);
	GroundDetection wrong;
	wrong.status = GroundDetection::Status::Ok;
	wrong.planes = {out.planes[0], cableTop};
	wrong.plane_support = {1, 9};
	for (double x : {1.45, 1.55, 1.65})
		for (double y : {-0.2, 0.0, 0.2})
		{
			GroundNode g;
			g.x = float(x);
			g.y = float(y);
			g.z = float(cableTop.heightAt(x, y));
			g.plane_id = 1;
			wrong.nodes.push_back(g);
		}
	const double band = out.patch_inlier_distance, reach = IsmParams{}.plane_support_radius;
	PatchMemory memory;
	memory.apply(wrong, 0.0, 1.0, band, reach, IsmParams{}.traversable_step);
	memory.apply(wrong, 0.1, 1.0, band, reach, IsmParams{}.traversable_step);
	const GroundDetection& judged = memory.apply(out, 0.2, 1.0, band, reach, IsmParams{}.traversable_step);
	ASSERT_EQ(memory.applied(), 1u) << "the cable's plane is 4 cm from the ramp's: not the same surface";

	auto cableObstacles = [&](const GroundDetection& det) {
		InverseSensorModel ism;
		IsmStats st;
		ism.compute(grid, det, kSensor, 5.0, st);
		return classifyRamp(grid, ism);
	};
	const RampCells own = cableObstacles(out), withMemory = cableObstacles(judged);
	EXPECT_EQ(withMemory.cableObstacle, own.cableObstacle);
	EXPECT_GE(double(withMemory.cableObstacle), 0.9 * double(withMemory.cable));
	EXPECT_EQ(withMemory.rampObstacle, 0u);
	// Offered beside the frame's planes everywhere (the same planes, every
	// remembered node counted as the frame's own), it frees the cable's
	// cells whose samples all lie within its band (measured: 14 of 28 stay
	// obstacles, the row that is only partly cable).
	GroundDetection everywhere = judged;
	everywhere.remembered_from = 0;
	const size_t freed = cableObstacles(everywhere).cableObstacle;
	std::cout << "cable obstacle cells: own planes " << own.cableObstacle << ", with memory "
			  << withMemory.cableObstacle << ", memory everywhere " << freed << std::endl;
	EXPECT_LT(double(freed), 0.7 * double(own.cableObstacle));
}
