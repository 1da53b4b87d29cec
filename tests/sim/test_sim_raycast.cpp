// Ground-aware mapping for MRPT -- tests: exact ray casting of the simulator.
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
}  // namespace

TEST(SimRaycast, FloorAtKnownRange)
{
	const SceneFile sf = parse("");
	const RayHit h = sf.scene.cast({0, 0, 1}, {1, 0, -1});
	ASSERT_TRUE(h.hit);
	EXPECT_NEAR(h.t, 1.0, 1e-12);
	EXPECT_NEAR(h.point.x(), 1.0, 1e-12);
	EXPECT_NEAR(h.point.z(), 0.0, 1e-12);
	EXPECT_NEAR(h.normal.z(), 1.0, 1e-12);
	EXPECT_EQ(h.object_id, 0);
	// upwards: nothing
	EXPECT_FALSE(sf.scene.cast({0, 0, 1}, {1, 0, 0.1}).hit);
	// beyond tmax: nothing
	EXPECT_FALSE(sf.scene.cast({0, 0, 1}, {1, 0, -1}, 0, 0.99).hit);
}

TEST(SimRaycast, BoxFaceAndYawedBox)
{
	const SceneFile sf = parse(
		"box id=7 x=2.0 y=0 sx=0.2 sy=0.4 sz=0.3\n"
		"box id=8 x=0 y=3 sx=0.2 sy=0.2 sz=0.3 yaw=45\n");
	RayHit h = sf.scene.cast({0, 0, 0.05}, {1, 0, 0});
	ASSERT_TRUE(h.hit);
	EXPECT_NEAR(h.t, 1.9, 1e-12);
	EXPECT_EQ(h.object_id, 7);
	EXPECT_NEAR(h.normal.x(), -1.0, 1e-12);
	// over the box: the floor behind it
	h = sf.scene.cast({0, 0, 0.35}, {1, 0, 0});
	EXPECT_FALSE(h.hit);
	// box top from above
	h = sf.scene.cast({2.0, 0.1, 1.0}, {0, 0, -1});
	ASSERT_TRUE(h.hit);
	EXPECT_NEAR(h.point.z(), 0.3, 1e-12);
	// yawed 45 deg: the corner points at -y, at y = 3 - 0.1*sqrt(2)
	h = sf.scene.cast({0, 0, 0.1}, {0, 1, 0});
	ASSERT_TRUE(h.hit);
	EXPECT_NEAR(h.point.y(), 3.0 - 0.1 * std::sqrt(2.0), 1e-9);
	EXPECT_EQ(h.object_id, 8);
}

TEST(SimRaycast, HoleBottomWallAndBottomless)
{
	const SceneFile sf = parse(
		"hole id=1 shape=rect x=2.0 y=0 sx=0.4 sy=0.4 depth=0.1\n"
		"hole id=2 shape=circle x=0 y=2 r=0.1 depth=0.05\n"
		"hole id=3 shape=rect x=0 y=-2 sx=0.5 sy=0.5 depth=inf\n");
	// the floor level is crossed inside the hole: the ray reaches the bottom
	RayHit h = sf.scene.cast({0, 0, 1}, {2, 0, -1.1});
	ASSERT_TRUE(h.hit);
	EXPECT_NEAR(h.t, 1.0, 1e-9);
	EXPECT_NEAR(h.point.x(), 2.0, 1e-9);
	EXPECT_NEAR(h.point.z(), -0.1, 1e-9);
	EXPECT_EQ(h.object_id, 1);
	// steeper: the far wall of the pit at x = 2.2
	h = sf.scene.cast({0, 0, 1}, {2.19, 0, -1.05});
	ASSERT_TRUE(h.hit);
	EXPECT_NEAR(h.point.x(), 2.2, 1e-9);
	EXPECT_GT(h.point.z(), -0.1);
	EXPECT_LT(h.point.z(), 0.0);
	EXPECT_NEAR(h.normal.x(), -1.0, 1e-12);
	EXPECT_EQ(h.object_id, 1);
	// before the hole: the floor
	h = sf.scene.cast({0, 0, 1}, {1.5, 0, -1});
	ASSERT_TRUE(h.hit);
	EXPECT_NEAR(h.point.x(), 1.5, 1e-12);
	EXPECT_EQ(h.object_id, 0);
	// circular outlet, vertical ray
	h = sf.scene.cast({0.05, 2.0, 1}, {0, 0, -1});
	ASSERT_TRUE(h.hit);
	EXPECT_NEAR(h.point.z(), -0.05, 1e-12);
	EXPECT_EQ(h.object_id, 2);
	// bottomless: a vertical ray never returns
	EXPECT_FALSE(sf.scene.cast({0, -2, 1}, {0, 0, -1}).hit);
	// bottomless, slanted: the far wall
	h = sf.scene.cast({0, -2, 1}, {0.1, 0, -1});
	ASSERT_TRUE(h.hit);
	EXPECT_NEAR(h.point.x(), 0.25, 1e-9);
	EXPECT_NEAR(h.point.z(), 1 - 2.5, 1e-9);
}

TEST(SimRaycast, RampStairsTable)
{
	const SceneFile sf = parse(
		"ramp id=1 x=1 y=0 yaw=0 length=2 width=1 angle=6\n"
		"stairs_down id=2 x=0 y=5 yaw=90 width=1 steps=3 rise=0.17 run=0.3 landing=1\n"
		"table id=3 x=-3 y=0 sx=1.2 sy=0.8 height=0.75 top=0.04 leg=0.05\n"
		"stairs_up id=4 x=0 y=-5 yaw=-90 width=1 steps=2 rise=0.15 run=0.3\n");
	RayHit h = sf.scene.cast({2, 0, 1}, {0, 0, -1});
	ASSERT_TRUE(h.hit);
	EXPECT_NEAR(h.point.z(), std::tan(6 * M_PI / 180), 1e-9);
	EXPECT_EQ(h.object_id, 1);
	EXPECT_NEAR(h.normal.x(), -std::sin(6 * M_PI / 180), 1e-9);
	// stairs going down along +y from y=5: tread k at z=-k*rise for y in [5+(k-1)run, 5+k run]
	for (int k = 1; k <= 3; k++)
	{
		h = sf.scene.cast({0, 5 + (k - 0.5) * 0.3, 1}, {0, 0, -1});
		ASSERT_TRUE(h.hit);
		EXPECT_NEAR(h.point.z(), -k * 0.17, 1e-9) << "tread " << k;
		EXPECT_EQ(h.object_id, 2);
	}
	// landing (lower floor)
	h = sf.scene.cast({0, 5 + 0.9 + 0.5, 1}, {0, 0, -1});
	EXPECT_NEAR(h.point.z(), -0.51, 1e-9);
	// under the table top (between legs) a horizontal ray passes through
	h = sf.scene.cast({-3, -3, 0.5}, {0, 1, 0});
	EXPECT_FALSE(h.hit);
	// at the height of the top it hits the top's side at y = -0.4
	h = sf.scene.cast({-3, -3, 0.73}, {0, 1, 0});
	ASSERT_TRUE(h.hit);
	EXPECT_NEAR(h.point.y(), -0.4, 1e-9);
	EXPECT_EQ(h.object_id, 3);
	// stairs up along -y from y=-5: second riser at y=-5.3
	h = sf.scene.cast({0, 0, 0.2}, {0, -1, 0});
	ASSERT_TRUE(h.hit);
	EXPECT_NEAR(h.point.y(), -5.3, 1e-9);
	EXPECT_EQ(h.object_id, 4);
}

TEST(SimScene, ParserErrorsNameFileAndLine)
{
	auto err = [](const std::string& txt) -> std::string {
		std::stringstream ss(txt);
		try
		{
			parseScene(ss, "bad.scene");
		}
		catch (const SceneError& e)
		{
			return e.what();
		}
		return "";
	};
	EXPECT_NE(err("path waypoints=0,0,0\n# c\nbox id=1 x=1 sx=1 sy=1 sz=1\n").find("bad.scene:3"), std::string::npos);
	EXPECT_NE(err("path waypoints=0,0,0\nbox id=1 x=1 sx=1 sy=1 sz=1\n").find("missing y="), std::string::npos);
	EXPECT_NE(
		err("path waypoints=0,0,0\nbox id=1 x=1 y=0 sx=1 sy=1 sz=1 colour=red\n").find("unknown key 'colour'"),
		std::string::npos);
	EXPECT_NE(
		err("path waypoints=0,0,0\nbox id=1 x=1 y=0 sx=1 sy=1 sz=1\nbox id=1 x=3 y=0 sx=1 sy=1 sz=1\n")
			.find("bad.scene:3: box: duplicate id 1"),
		std::string::npos);
	EXPECT_NE(
		err("path waypoints=0,0,0\nspaceship id=1\n").find("bad.scene:2: unknown statement 'spaceship'"),
		std::string::npos);
	EXPECT_NE(
		err("path waypoints=0,0,0\nbox id=1 x=abc y=0 sx=1 sy=1 sz=1\n").find("bad number for x"), std::string::npos);
	EXPECT_NE(err("box id=1 x=1 y=0 sx=1 sy=1 sz=1\n").find("no 'path'"), std::string::npos);
	EXPECT_NE(err("path waypoints=0,0,0\nkinect pose=1,2,3\n").find("pose needs 6"), std::string::npos);
	EXPECT_EQ(err("path waypoints=0,0,0;1,0,0 spacing=0.1\n"), "");
}

TEST(SimPath, SpacingAndOdometry)
{
	PathSpec p;
	p.waypoints = {{0, 0, 0}, {1, 0, 0}, {1, 0, M_PI / 2}};
	p.spacing = 0.1;
	p.turn_spacing = 10 * M_PI / 180;
	const auto fr = samplePath(p);
	ASSERT_EQ(fr.size(), 1u + 10u + 9u);
	EXPECT_NEAR(fr[10].x, 1.0, 1e-12);
	EXPECT_NEAR(fr.back().yaw, M_PI / 2, 1e-12);
	std::mt19937 rng(3);
	auto odo = simulateOdometry(fr, OdometryNoise{}, rng);
	for (size_t i = 0; i < fr.size(); i++)
	{
		EXPECT_NEAR(odo[i].x, fr[i].x, 1e-9);
		EXPECT_NEAR(odo[i].yaw, fr[i].yaw, 1e-9);
	}
	OdometryNoise n;
	n.xy_per_m = 0.05;
	n.yaw_per_m = 0.02;
	odo = simulateOdometry(fr, n, rng);
	EXPECT_GT(std::hypot(odo[10].x - 1.0, odo[10].y), 1e-5);
}
