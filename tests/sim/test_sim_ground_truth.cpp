// Ground-aware mapping for MRPT -- tests: ground-truth labels of a small scene.
#include <gtest/gtest.h>

#include <sstream>

#include "gam/sim/SceneFile.h"

using namespace gam::sim;

namespace
{
const char* kScene = R"(
kinect pose=0.10,0,1.00,0,25,0
path waypoints=0,0,0
box id=3 name=small_box x=2.0 y=0.3 sx=0.10 sy=0.10 sz=0.07
hole id=4 name=outlet shape=rect x=2.0 y=-0.5 sx=0.20 sy=0.20 depth=0.05
table id=5 name=desk x=3.0 y=0 sx=0.8 sy=0.6 height=0.75
box id=6 name=cabinet x=2.5 y=1.0 sx=0.5 sy=0.4 sz=0.9
ramp id=7 name=ramp x=1.5 y=-1.2 yaw=0 length=1.0 width=0.6 angle=6
ramp id=8 name=steep x=1.5 y=1.6 yaw=0 length=0.5 width=0.3 angle=20
hole id=9 name=tiny shape=rect x=1.2 y=-0.2 sx=0.2 sy=0.2 depth=0.01
box id=10 name=high_board x=1.2 y=0.4 z=2.0 sx=0.3 sy=0.3 sz=0.05
grid resolution=0.05 min_x=-1 max_x=5 min_y=-3 max_y=3
)";

struct Fixture
{
	SceneFile sf;
	GroundTruthGrid gt;
	Fixture()
	{
		std::stringstream ss(kScene);
		sf = parseScene(ss, "gt.scene");
		gt.build(sf.scene, sf.grid);
		KinectParams kp;
		kp.noise = false;
		std::mt19937 rng(1);
		const DepthFrame f =
			KinectModel(kp).render(sf.scene, Pose3::fromXYZYPR(0, 0, 0, 0, 0, 0) * sf.kinect_pose, rng);
		gt.markObserved(f.footprint);
	}
};
}  // namespace

TEST(SimGroundTruth, LabelsIdsAndCategories)
{
	Fixture fx;
	const auto& gt = fx.gt;
	// geometric label (regardless of visibility)
	auto geom = [&](double x, double y) {
		int ix, iy;
		EXPECT_TRUE(gt.cellOf(x, y, ix, iy));
		return gt.geomLabel[gt.idx(ix, iy)];
	};
	// box: obstacle, its id, category small (7 cm)
	EXPECT_EQ(gt.labelAt(2.0, 0.3), Label::Obstacle);
	EXPECT_EQ(gt.objectAt(2.0, 0.3), 3);
	EXPECT_EQ(fx.sf.scene.object(3)->category, Category::Small);
	// hole: drop, negative
	EXPECT_EQ(gt.labelAt(2.0, -0.5), Label::Drop);
	EXPECT_EQ(gt.objectAt(2.0, -0.5), 4);
	EXPECT_EQ(fx.sf.scene.object(4)->category, Category::Negative);
	// a 1 cm deep recess is below drop_min (2 cm): free
	EXPECT_EQ(gt.labelAt(1.2, -0.2), Label::Free);
	// floor: free, id 0
	EXPECT_EQ(gt.labelAt(1.5, 0.0), Label::Free);
	EXPECT_EQ(gt.objectAt(1.5, 0.0), 0);
	// table: the top over free floor is an overhang obstacle; legs too
	EXPECT_EQ(gt.labelAt(3.0, 0.0), Label::Obstacle);
	EXPECT_EQ(gt.objectAt(3.0, 0.0), 5);
	EXPECT_EQ(gt.labelAt(2.63, -0.28), Label::Obstacle);
	EXPECT_EQ(fx.sf.scene.object(5)->category, Category::Overhang);
	// cabinet: large (its top is seen at ~2 deg grazing: too sparse to observe every cell)
	EXPECT_EQ(geom(2.5, 1.0), Label::Obstacle);
	EXPECT_EQ(gt.labelAt(2.3, 1.0), Label::Obstacle);
	EXPECT_EQ(fx.sf.scene.object(6)->category, Category::Large);
	// 6 deg ramp: traversable (free), keeps its id; 20 deg: obstacle
	EXPECT_EQ(gt.labelAt(2.0, -1.2), Label::Free);
	EXPECT_EQ(gt.objectAt(2.0, -1.2), 7);
	EXPECT_EQ(fx.sf.scene.object(7)->category, Category::Ramp);
	EXPECT_EQ(geom(1.9, 1.6), Label::Obstacle);
	EXPECT_EQ(gt.labelAt(1.9, 1.6), Label::Unobserved);  // 42 deg azimuth: outside the FOV
	EXPECT_EQ(fx.sf.scene.object(8)->category, Category::Small);
	// a board above the robot height blocks nothing
	int bx, by;
	ASSERT_TRUE(gt.cellOf(1.22, 0.42, bx, by));
	EXPECT_EQ(gt.geomLabel[gt.idx(bx, by)], Label::Free);
	EXPECT_EQ(fx.sf.scene.object(10)->category, Category::Overhang);
	// outside the field of view: unobserved (behind the robot, far to the side)
	EXPECT_EQ(gt.labelAt(-0.8, 0.0), Label::Unobserved);
	EXPECT_EQ(gt.labelAt(1.0, 2.9), Label::Unobserved);
	EXPECT_EQ(gt.labelAt(9.0, 0.0), Label::Unobserved);  // outside the grid
}

TEST(SimGroundTruth, CellEdgesAreConservative)
{
	// a 3 cm wide box straddling a cell corner still marks the cells it touches
	std::stringstream ss(
		"path waypoints=0,0,0\nbox id=1 x=1.0 y=1.0 sx=0.03 sy=0.03 sz=0.05\n"
		"grid resolution=0.05 min_x=0 max_x=2 min_y=0 max_y=2 subsamples=3\n");
	SceneFile sf = parseScene(ss, "edge.scene");
	GroundTruthGrid gt;
	gt.build(sf.scene, sf.grid);
	int ix, iy;
	ASSERT_TRUE(gt.cellOf(1.0, 1.0, ix, iy));
	int n = 0;
	for (int dy = -1; dy <= 0; dy++)
		for (int dx = -1; dx <= 0; dx++) n += gt.geomLabel[gt.idx(ix + dx, iy + dy)] == Label::Obstacle;
	EXPECT_EQ(n, 4);
}

TEST(SimGroundTruth, StepsInsideACellAreObstacles)
{
	// An 8 deg ramp with solid sides, 1.2 m long and 0.7 m wide, foot at x =
	// 0.98, its sides at y = 0.02 +- 0.35 = 0.37 and -0.33 (inside the cells
	// [0.35, 0.40) and [-0.35, -0.30)), then a 0.6 m plateau that ends in a
	// vertical face at x = 0.98 + 1.2 + 0.6 = 2.78 (inside [2.75, 2.80)).
	// Ramp height at u metres from the foot: u tan 8 deg = 0.1405 u, above the
	// 2 cm obstacle_min_height from u = 0.02 / 0.1405 = 0.142 m on; the
	// plateau is 1.2 tan 8 deg = 0.169 m high.
	std::stringstream ss(
		"path waypoints=0,0,0\n"
		"ramp id=1 name=r x=0.98 y=0.02 yaw=0 length=1.2 width=0.7 angle=8 sides=solid plateau=0.6\n"
		"grid resolution=0.05 min_x=0 max_x=4 min_y=-1 max_y=1 subsamples=3\n");
	SceneFile sf = parseScene(ss, "steps.scene");
	GroundTruthGrid gt;
	gt.build(sf.scene, sf.grid);
	auto at = [&](double x, double y) {
		int ix, iy;
		EXPECT_TRUE(gt.cellOf(x, y, ix, iy));
		return std::make_pair(gt.geomLabel[gt.idx(ix, iy)], gt.objectId[gt.idx(ix, iy)]);
	};
	// side cells at u = 0.52 (0.073 m high) and on the plateau (0.169 m): the
	// ramp's side face, an obstacle of the ramp
	EXPECT_EQ(at(1.525, 0.375), std::make_pair(Label::Obstacle, 1));
	EXPECT_EQ(at(1.525, -0.325), std::make_pair(Label::Obstacle, 1));
	EXPECT_EQ(at(2.425, 0.375), std::make_pair(Label::Obstacle, 1));
	// the plateau's end face
	EXPECT_EQ(at(2.775, 0.025), std::make_pair(Label::Obstacle, 1));
	// at the foot the side is at most 0.07 x 0.1405 = 0.010 m high: free
	EXPECT_EQ(at(1.025, 0.375).first, Label::Free);
	// on the slope a cell rises 0.05 x 0.1405 = 0.007 m across: free, the ramp's
	EXPECT_EQ(at(1.525, 0.025), std::make_pair(Label::Free, 1));
	EXPECT_EQ(at(2.425, 0.025), std::make_pair(Label::Free, 1));
	// the floor one cell beyond each face: free
	EXPECT_EQ(at(1.525, 0.425), std::make_pair(Label::Free, 0));
	EXPECT_EQ(at(2.825, 0.025), std::make_pair(Label::Free, 0));
}
