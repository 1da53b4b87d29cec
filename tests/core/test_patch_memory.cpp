// Ground-aware mapping for MRPT
// PatchMemory: the ramp patches of a camera's earlier frames (issue #27), on
// hand-built detections: a floor z = 0 and a 6 deg ramp rising along +x from
// a foot at x = 1.0 (z = tan 6 deg (x - 1) = 0.1051 (x - 1)).
#include <gtest/gtest.h>

#include <cmath>

#include "gam/core/PatchMemory.h"

using namespace gam;

namespace
{
const double kTan6 = std::tan(6.0 * M_PI / 180.0);  // 0.1051
constexpr double kBand = 0.01, kReach = 0.4, kForget = 1.0, kRise = 0.02;

Plane floorPlane() { return Plane{0, 0, 1, 0}; }
// z = t (x - 1): t x - z - t = 0, normalised.
Plane rampPlane(double t)
{
	const double n = std::sqrt(1.0 + t * t);
	return Plane{-t / n, 0, 1 / n, t / n};
}

GroundNode node(double x, double y, const Plane& on, int id)
{
	GroundNode g;
	g.x = float(x);
	g.y = float(y);
	g.z = float(on.heightAt(x, y));
	g.plane_id = id;
	return g;
}

// A frame's detection: the floor (4 nodes) and, if `ramp`, the ramp's
// patch with 3 x 3 nodes on x in {1.2, 1.4, 1.6}, y in {-0.2, 0, 0.2}.
GroundDetection frame(bool ramp, double slope = kTan6)
{
	GroundDetection d;
	d.status = GroundDetection::Status::Ok;
	d.planes.push_back(floorPlane());
	d.plane_support.push_back(4);
	for (double x : {0.2, 0.4, 0.6, 0.8}) d.nodes.push_back(node(x, 0.0, floorPlane(), 0));
	if (ramp)
	{
		d.planes.push_back(rampPlane(slope));
		d.plane_support.push_back(9);
		for (double x : {1.2, 1.4, 1.6})
			for (double y : {-0.2, 0.0, 0.2}) d.nodes.push_back(node(x, y, d.planes[1], 1));
	}
	d.patch_inlier_distance = kBand;
	return d;
}
}  // namespace

TEST(PatchMemory, APatchTwoFramesFittedJudgesAFrameWithoutIt)
{
	PatchMemory m;
	const GroundDetection withRamp = frame(true), without = frame(false);
	// Frames 1 and 2 fit the ramp themselves: they are judged as they are.
	EXPECT_EQ(&m.apply(withRamp, 0.0, kForget, kBand, kReach, kRise), &withRamp);
	EXPECT_EQ(&m.apply(withRamp, 0.1, kForget, kBand, kReach, kRise), &withRamp);
	EXPECT_EQ(m.size(), 1u);  // the second repeats the first: one patch, two frames
	// Frame 3 does not: the remembered ramp joins its planes, after its own.
	const GroundDetection& judged = m.apply(without, 0.2, kForget, kBand, kReach, kRise);
	ASSERT_NE(&judged, &without);
	EXPECT_EQ(m.applied(), 1u);
	ASSERT_EQ(judged.planes.size(), 2u);
	EXPECT_EQ(judged.remembered_from, 1u);
	EXPECT_TRUE(judged.ok());
	// Its height 1 m past the foot: tan 6 deg = 0.1051 m.
	EXPECT_NEAR(judged.planes[1].heightAt(2.0, 0.0), 0.1051, 1e-4);
	EXPECT_NEAR(judged.planes[0].heightAt(2.0, 0.0), 0.0, 1e-12);
	size_t rampNodes = 0;
	for (const GroundNode& g : judged.nodes) rampNodes += g.plane_id == 1;
	EXPECT_EQ(rampNodes, 9u);  // its 9 nodes, where the ISM applies it
	// The frame's own detection is untouched.
	EXPECT_EQ(without.planes.size(), 1u);
}

TEST(PatchMemory, OneFramesPatchIsNotRemembered)
{
	// One frame's tree can fit a patch to the top of a cable protector: one
	// frame is not enough (kMinFrames = 2).
	PatchMemory m;
	const GroundDetection withRamp = frame(true), without = frame(false);
	m.apply(withRamp, 0.0, kForget, kBand, kReach, kRise);
	EXPECT_EQ(&m.apply(without, 0.1, kForget, kBand, kReach, kRise), &without);
	EXPECT_EQ(m.applied(), 0u);
}

TEST(PatchMemory, ForgottenAfterTravellingForgetAfter)
{
	PatchMemory m;
	const GroundDetection withRamp = frame(true), without = frame(false);
	m.apply(withRamp, 0.0, kForget, kBand, kReach, kRise);
	m.apply(withRamp, 0.1, kForget, kBand, kReach, kRise);  // last fitted at 0.1 m
	// 1.05 m later: 0.95 m since, remembered.
	m.apply(without, 1.05, kForget, kBand, kReach, kRise);
	EXPECT_EQ(m.applied(), 1u);
	// 1.15 m: 1.05 m since it was last fitted, more than 1.0 m: forgotten.
	EXPECT_EQ(&m.apply(without, 1.15, kForget, kBand, kReach, kRise), &without);
	EXPECT_EQ(m.applied(), 0u);
	EXPECT_EQ(m.size(), 0u);
}

TEST(PatchMemory, AFramesOwnDifferentPatchLeavesTheRememberedOneBesideIt)
{
	// The third frame fits the same ramp 1 deg steeper: at its far node
	// (x = 1.6) that is 0.6 (tan 7 - tan 6) = 0.6 x 0.0177 = 10.6 mm from the
	// remembered plane, more than the 10 mm band: not the same surface, so
	// the remembered one is offered beside it (the ISM applies it only where
	// the frame's own patch does not).
	PatchMemory m;
	const GroundDetection withRamp = frame(true), steeper = frame(true, std::tan(7.0 * M_PI / 180.0));
	m.apply(withRamp, 0.0, kForget, kBand, kReach, kRise);
	m.apply(withRamp, 0.1, kForget, kBand, kReach, kRise);
	const GroundDetection& judged = m.apply(steeper, 0.2, kForget, kBand, kReach, kRise);
	EXPECT_EQ(m.applied(), 1u);
	ASSERT_EQ(judged.planes.size(), 3u);
	EXPECT_EQ(judged.remembered_from, 2u);
	// 6.5 deg: 0.6 (tan 6.5 - tan 6) = 5.3 mm at x = 1.6, within the band:
	// the same surface, which the frame's own patch supersedes.
	PatchMemory m2;
	const GroundDetection close = frame(true, std::tan(6.5 * M_PI / 180.0));
	m2.apply(withRamp, 0.0, kForget, kBand, kReach, kRise);
	m2.apply(withRamp, 0.1, kForget, kBand, kReach, kRise);
	EXPECT_EQ(&m2.apply(close, 0.2, kForget, kBand, kReach, kRise), &close);
	EXPECT_EQ(m2.size(), 1u);
}

TEST(PatchMemory, OffOrAFrameWithoutGroundRemembersNothing)
{
	PatchMemory m;
	const GroundDetection withRamp = frame(true), without = frame(false);
	m.apply(withRamp, 0.0, kForget, kBand, kReach, kRise);
	m.apply(withRamp, 0.1, kForget, kBand, kReach, kRise);
	GroundDetection none;  // the tree found no ground: judged as it is
	EXPECT_EQ(&m.apply(none, 0.2, kForget, kBand, kReach, kRise), &none);
	EXPECT_EQ(m.size(), 1u);
	// patch_memory = 0: no memory at all.
	EXPECT_EQ(&m.apply(without, 0.3, 0.0, kBand, kReach, kRise), &without);
	EXPECT_EQ(m.size(), 0u);
	m.apply(withRamp, 0.4, kForget, kBand, kReach, kRise);
	m.clear();
	EXPECT_EQ(m.size(), 0u);
}

TEST(PatchMemory, OnlyAPatchWhoseNodesMeasureASlopeIsRemembered)
{
	// A level patch 3.4 cm above the floor on 4 nodes (the top of a cable
	// protector, as trees fitted it in cable_protector): it rises 0 across
	// its nodes, not more than the 20 mm traversable step, so two frames
	// fitting it leave nothing to remember. The ramp's 9 nodes span x = 1.2
	// to 1.6 along its gradient: it rises tan 6 deg x 0.4 = 0.1051 x 0.4 =
	// 42 mm > 20 mm.
	GroundDetection level = frame(false);
	const Plane top{0, 0, 1, -0.034};
	level.planes.push_back(top);
	level.plane_support.push_back(4);
	for (double x : {2.9, 3.0})
		for (double y : {0.4, 0.6}) level.nodes.push_back(node(x, y, top, 1));
	EXPECT_FALSE(PatchMemory::sloped(level, 1, kRise));
	EXPECT_TRUE(PatchMemory::sloped(frame(true), 1, kRise));
	// 42 mm is not more than 45 mm.
	EXPECT_FALSE(PatchMemory::sloped(frame(true), 1, 0.045));
	// A protector's top tilted 2.8 deg by the noise (held-out seed_3007),
	// nodes x = 4.62 to 4.88: it rises tan 2.8 deg x 0.26 = 0.0489 x 0.26 =
	// 12.7 mm, under 20 mm.
	GroundDetection tilted = frame(false);
	const double t = std::tan(2.8 * M_PI / 180.0), n = std::sqrt(1.0 + t * t);
	const Plane top2{-t / n, 0, 1 / n, (t * 4.75 - 0.038) / n};  // z = 0.038 + t (x - 4.75)
	ASSERT_NEAR(top2.heightAt(4.75, 1.0), 0.038, 1e-12);
	tilted.planes.push_back(top2);
	tilted.plane_support.push_back(9);
	for (double x : {4.62, 4.75, 4.88})
		for (double y : {0.7, 1.0, 1.3}) tilted.nodes.push_back(node(x, y, top2, 1));
	EXPECT_FALSE(PatchMemory::sloped(tilted, 1, kRise));
	EXPECT_TRUE(PatchMemory::sloped(tilted, 1, 0.012));

	PatchMemory m;
	m.apply(level, 0.0, kForget, kBand, kReach, kRise);
	m.apply(level, 0.1, kForget, kBand, kReach, kRise);
	EXPECT_EQ(m.size(), 0u);
	const GroundDetection without = frame(false);
	EXPECT_EQ(&m.apply(without, 0.2, kForget, kBand, kReach, kRise), &without);
}

TEST(PatchMemory, RestoreUndoesTheFramesSinceSave)
{
	// A frame run twice (ahead on a worker, then again in its turn) counts
	// once: after restore() the second fit of the ramp never happened, so
	// it has one frame, too few to judge the next frame.
	PatchMemory m;
	const GroundDetection withRamp = frame(true), without = frame(false);
	m.apply(withRamp, 0.0, kForget, kBand, kReach, kRise);
	m.save();
	m.apply(withRamp, 0.1, kForget, kBand, kReach, kRise);  // the run not taken
	m.restore();
	EXPECT_EQ(&m.apply(without, 0.1, kForget, kBand, kReach, kRise), &without);
	EXPECT_EQ(m.applied(), 0u);
	// Without the restore it would have judged it.
	PatchMemory m2;
	m2.apply(withRamp, 0.0, kForget, kBand, kReach, kRise);
	m2.apply(withRamp, 0.1, kForget, kBand, kReach, kRise);
	m2.apply(without, 0.1, kForget, kBand, kReach, kRise);
	EXPECT_EQ(m2.applied(), 1u);
}
