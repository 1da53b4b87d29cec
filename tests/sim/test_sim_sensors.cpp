// Ground-aware mapping for MRPT -- tests: Kinect One and Leddar IS16 models.
#include <gtest/gtest.h>

#include <cmath>
#include <sstream>

#include "gam/sim/SceneFile.h"

using namespace gam::sim;

namespace
{
SceneFile parse(const std::string& txt)
{
	std::stringstream ss("path waypoints=0,0,0\n" + txt);
	return parseScene(ss, "test.scene");
}
constexpr double kDeg = M_PI / 180;
}  // namespace

TEST(SimKinect, IntrinsicsMatchSpec)
{
	KinectParams p;
	EXPECT_EQ(p.width, 512);
	EXPECT_EQ(p.height, 424);
	// FOV back from the intrinsics
	EXPECT_NEAR(2 * std::atan(0.5 * p.width / p.fx()) / kDeg, 70.6, 1e-9);
	EXPECT_NEAR(2 * std::atan(0.5 * p.height / p.fy()) / kDeg, 60.0, 1e-9);
	EXPECT_NEAR(p.fx(), 361.6, 0.1);
	// the documented sigma values
	EXPECT_NEAR(p.sigma(1.0, 0.0), 1.3e-3, 1e-9);
	EXPECT_NEAR(p.sigma(4.0, 0.0), 4.3e-3, 1e-9);
	EXPECT_GT(p.sigma(3.0, 70 * kDeg), p.sigma(3.0, 0.0));
	EXPECT_GT(p.sigma(4.0, 0.0), p.sigma(2.0, 0.0));
}

TEST(SimKinect, NoiseOffGivesExactDepth)
{
	// a level camera 2 m from a wall: depth along +X = 2 on every pixel
	SceneFile sf = parse("floor present=0\nwall id=1 x0=2 y0=-10 x1=2 y1=10 thickness=0.01 height=20\n");
	sf.scene.solids[0] = ConvexSolid::box(Pose3::fromXYZYPR(2.005, 0, 0, 0, 0, 0), {0.005, 10, 10}, 1);
	KinectParams kp;
	kp.noise = false;
	KinectModel km(kp);
	std::mt19937 rng(1);
	const DepthFrame f = km.render(sf.scene, Pose3::fromXYZYPR(0, 0, 0, 0, 0, 0), rng);
	for (size_t i = 0; i < f.depth.size(); i++) ASSERT_NEAR(f.depth[i], 2.0, 1e-6);
	// a known pixel ray: floor 1 m below a camera pitched 45 deg down, centre pixel
	SceneFile fl = parse("");
	kp.width = 5;
	kp.height = 5;  // centre pixel exactly on the optical axis
	KinectModel small(kp);
	const DepthFrame g = small.render(fl.scene, Pose3::fromXYZYPR(0, 0, 1, 0, 45 * kDeg, 0), rng);
	EXPECT_NEAR(g.depth[g.idx(2, 2)], std::sqrt(2.0), 1e-6);
	EXPECT_NEAR(g.incidence[g.idx(2, 2)], 45 * kDeg, 1e-6);
}

TEST(SimKinect, NoiseStatisticsFollowTheModel)
{
	// fronto-parallel wall at 1.5 m and 4.0 m: the standardised error must be N(0,1)
	for (double dist : {1.5, 4.0})
	{
		SceneFile sf = parse("floor present=0\n");
		sf.scene.solids.push_back(ConvexSolid::box(Pose3::fromXYZYPR(dist + 0.5, 0, 0, 0, 0, 0), {0.5, 50, 50}, 1));
		KinectParams kp;
		kp.width = 64;
		kp.height = 54;
		kp.spike_prob = 0;
		KinectModel km(kp);
		std::mt19937 rng(42);
		double s = 0, s2 = 0, e = 0, e2 = 0;
		size_t n = 0;
		for (int rep = 0; rep < 30; rep++)
		{
			const DepthFrame f = km.render(sf.scene, Pose3::fromXYZYPR(0, 0, 0, 0, 0, 0), rng);
			for (size_t i = 0; i < f.depth.size(); i++)
			{
				ASSERT_TRUE(f.flags[i] & PixValid);
				const double err = f.depth[i] - f.true_depth[i];
				const double z = err / kp.sigma(f.true_depth[i], f.incidence[i]);
				s += z;
				s2 += z * z;
				e += err;
				e2 += err * err;
				n++;
			}
		}
		const double mean = s / n, sd = std::sqrt(s2 / n - mean * mean);
		EXPECT_NEAR(mean, 0.0, 4.0 / std::sqrt(double(n))) << dist;
		EXPECT_NEAR(sd, 1.0, 0.02) << dist;
		// at the centre the raw sigma is the model's (incidence up to ~35 deg at the corners)
		const double rawSd = std::sqrt(e2 / n - (e / n) * (e / n));
		EXPECT_GT(rawSd, 0.9 * kp.sigma(dist, 0));
		EXPECT_LT(rawSd, 1.3 * kp.sigma(dist, 0));
	}
}

TEST(SimKinect, DeterministicForASeed)
{
	const SceneFile sf = parse("box id=1 x=2 y=0 sx=0.3 sy=0.3 sz=0.3\n");
	KinectModel km;
	const Pose3 cam = Pose3::fromXYZYPR(0, 0, 1, 0, 25 * kDeg, 0);
	std::mt19937 a(5), b(5), c(6);
	const DepthFrame fa = km.render(sf.scene, cam, a), fb = km.render(sf.scene, cam, b),
					 fc = km.render(sf.scene, cam, c);
	EXPECT_EQ(fa.depth, fb.depth);
	EXPECT_NE(fa.depth, fc.depth);
}

TEST(SimKinect, DropoutsAtGrazingAngles)
{
	// a low level camera looking along the floor: incidence from ~60 to ~90 deg
	const SceneFile sf = parse("");
	KinectModel km;
	std::mt19937 rng(7);
	const DepthFrame f = km.render(sf.scene, Pose3::fromXYZYPR(0, 0, 0.4, 0, 0, 0), rng);
	size_t lowN = 0, lowDrop = 0, highN = 0, highDrop = 0, midN = 0, midDrop = 0;
	for (size_t i = 0; i < f.depth.size(); i++)
	{
		if (f.flags[i] & (PixOutOfRange | PixFlying | PixSpike | PixEdge)) continue;
		const double th = f.incidence[i] / kDeg;
		const bool drop = f.flags[i] & PixDropout;
		if (th < 70)
			lowN++, lowDrop += drop;
		else if (th > 85)
			highN++, highDrop += drop;
		else if (th > 76 && th < 79)
			midN++, midDrop += drop;
	}
	ASSERT_GT(lowN, 1000u);
	ASSERT_GT(highN, 100u);
	ASSERT_GT(midN, 1000u);
	EXPECT_EQ(lowDrop, 0u);
	EXPECT_EQ(highDrop, highN);
	// expected fraction at 76-79 deg: (77.5-70)/15 = 0.5
	EXPECT_NEAR(double(midDrop) / midN, 0.5, 0.07);
}

TEST(SimKinect, FlyingPixelsOnlyAtDepthEdges)
{
	// a box in front of a wall: flying pixels on its silhouette only
	SceneFile sf = parse("floor present=0\nbox id=1 x=1.5 y=0 z=-0.3 sx=0.4 sy=0.6 sz=0.6\n");
	sf.scene.solids.push_back(ConvexSolid::box(Pose3::fromXYZYPR(3.5, 0, 0, 0, 0, 0), {0.5, 50, 50}, 2));
	KinectParams kp;
	kp.spike_prob = 0;
	KinectModel km(kp);
	std::mt19937 rng(11);
	const DepthFrame f = km.render(sf.scene, Pose3::fromXYZYPR(0, 0, 0, 0, 0, 0), rng);
	size_t fly = 0, edges = 0;
	for (size_t i = 0; i < f.depth.size(); i++)
	{
		edges += (f.flags[i] & PixEdge) != 0;
		if (!(f.flags[i] & PixFlying)) continue;
		fly++;
		EXPECT_TRUE(f.flags[i] & PixEdge);
		// strictly between the box face (1.3) and the wall (3.0)
		EXPECT_GT(f.depth[i], 1.3 + 0.1);
		EXPECT_LT(f.depth[i], 3.0 - 0.1);
	}
	EXPECT_GT(edges, 500u);
	EXPECT_GT(fly, edges / 4);
	EXPECT_LT(fly, edges * 3 / 4);
	// no edge, no flying pixel: the wall alone
	sf.scene.solids.erase(sf.scene.solids.begin());
	const DepthFrame g = km.render(sf.scene, Pose3::fromXYZYPR(0, 0, 0, 0, 0, 0), rng);
	for (size_t i = 0; i < g.depth.size(); i++) ASSERT_FALSE(g.flags[i] & (PixFlying | PixEdge));
}

TEST(SimKinect, RareSpikes)
{
	SceneFile sf = parse("floor present=0\n");
	sf.scene.solids.push_back(ConvexSolid::box(Pose3::fromXYZYPR(2.5, 0, 0, 0, 0, 0), {0.5, 50, 50}, 1));
	KinectModel km;
	std::mt19937 rng(3);
	const DepthFrame f = km.render(sf.scene, Pose3::fromXYZYPR(0, 0, 0, 0, 0, 0), rng);
	size_t spikes = 0;
	for (auto fl : f.flags) spikes += (fl & PixSpike) != 0;
	// 512*424*1e-4 = 21.7 expected
	EXPECT_GT(spikes, 5u);
	EXPECT_LT(spikes, 50u);
}

TEST(SimLeddar, SegmentsAndNearestReturn)
{
	SceneFile sf = parse("floor present=0\nbox id=5 x=1.0 y=0 sx=0.1 sy=0.1 sz=2 z=-1\n");
	sf.scene.solids.push_back(ConvexSolid::box(Pose3::fromXYZYPR(5.5, 0, 0, 0, 0, 0), {0.5, 50, 50}, 6));
	LeddarParams lp;
	lp.noise = false;
	lp.quantum = 0;
	LeddarModel lm(lp);
	std::mt19937 rng(1);
	const LeddarScan s = lm.scan(sf.scene, Pose3::fromXYZYPR(0, 0, 0, 0, 0, 0), rng);
	ASSERT_EQ(s.range.size(), 16u);
	EXPECT_NEAR(lp.segmentAngle(0), -22.5 * kDeg, 1e-12);
	EXPECT_NEAR(lp.segmentAngle(15), 22.5 * kDeg, 1e-12);
	// Segment 15's cone: 22.5 -+ 45 / 16 / 2 = 21.09375 .. 23.90625 deg; its
	// echo from the near edge: 5 / cos 21.09375 = 5 / 0.932993 = 5.35910 m.
	EXPECT_NEAR(lp.subRayAngle(15, 0), 21.09375 * kDeg, 1e-12);
	EXPECT_NEAR(lp.subRayAngle(15, lp.sub_h - 1), 23.90625 * kDeg, 1e-12);
	EXPECT_NEAR(s.range[15], 5.35910, 1e-5);
	for (int i = 0; i < 16; i++)
	{
		ASSERT_TRUE(s.valid[size_t(i)]);
		const double a = lp.segmentAngle(i);
		if (std::abs(a) < 2 * kDeg)
		{
			// the thin post at 0.95 m hides the wall in the two central segments
			EXPECT_NEAR(s.range[size_t(i)], 0.95, 0.01) << i;
			EXPECT_EQ(s.object_id[size_t(i)], 5);
		}
		else
		{
			// nearest sub-ray on the wall at x = 5: the cone's near edge (the
			// sub-rays span the cone edge to edge; the middle vertical one is
			// level), 5 / cos(|a| - w / 2)
			const double w = 45.0 / 16 * kDeg;
			const double hmin = std::abs(a) - 0.5 * w;
			EXPECT_NEAR(s.range[size_t(i)], 5.0 / std::cos(hmin), 1e-5) << i;
			EXPECT_EQ(s.object_id[size_t(i)], 6);
		}
	}
	// nothing in range: invalid
	SceneFile empty = parse("floor present=0\n");
	const LeddarScan e = lm.scan(empty.scene, Pose3::fromXYZYPR(0, 0, 0, 0, 0, 0), rng);
	for (bool v : e.valid) EXPECT_FALSE(v);
}
