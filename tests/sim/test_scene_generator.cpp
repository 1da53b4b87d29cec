// Issue #29: the seeded scene generator of the navigation benchmark
// (libs/ground_sim SceneGenerator): deterministic per seed, a hazard on the
// straight start-goal line, a ground-truth path around it, every hazard kind
// across seeds, people that cross, and the per-frame ground truth.
#include <gtest/gtest.h>

#include <cmath>
#include <set>
#include <sstream>

#include "gam/sim/SceneGenerator.h"

using namespace gam::sim;

TEST(SceneGenerator, SameSeedSameSceneOtherSeedOtherScene)
{
	const GeneratedScene a = generateScene(7), b = generateScene(7), c = generateScene(8);
	EXPECT_EQ(a.text, b.text);
	EXPECT_EQ(a.start, b.start);
	EXPECT_EQ(a.goal, b.goal);
	EXPECT_NE(a.text, c.text);
	// The text is the scene: parsing it again gives the same solids and holes.
	std::istringstream in(a.text);
	const SceneFile again = parseScene(in, "again");
	EXPECT_EQ(again.scene.solids.size(), a.file.scene.solids.size());
	EXPECT_EQ(again.scene.holes.size(), a.file.scene.holes.size());
	EXPECT_EQ(again.scene.objects.size(), a.file.scene.objects.size());
}

TEST(SceneGenerator, StraightLineMeetsAHazardAndAGroundTruthPathGoesAround)
{
	const GeneratorOptions o;
	for (unsigned seed = 1; seed <= 14; seed++)
	{
		SCOPED_TRACE("seed " + std::to_string(seed));
		const GeneratedScene g = generateScene(seed, o);
		const GroundTruthGrid gt = staticGroundTruth(g.file);
		// The walls are the objects named *_wall; everything else on the line is a hazard.
		std::vector<int> walls;
		for (const auto& ob : g.file.scene.objects)
			if (ob.type == "wall") walls.push_back(ob.id);
		double at = -1;
		const int hit = firstHazardOnSegment(gt, g.start, g.goal, walls, &at);
		EXPECT_NE(hit, 0) << "the straight line meets no hazard";
		EXPECT_GT(at, 1.0) << "the hazard is too close to the start to be seen";
		// The cells of the straight line, grown by the walker's radius, are
		// blocked somewhere: the straight line is not a walker's path.
		const auto blocked = blockedCells(gt, o.walkerRadius);
		bool lineBlocked = false;
		for (double s = 0; s <= 1; s += 0.002)
		{
			const Eigen::Vector2d p = g.start + s * (g.goal - g.start);
			int ix, iy;
			ASSERT_TRUE(gt.cellOf(p.x(), p.y(), ix, iy));
			lineBlocked |= blocked[gt.idx(ix, iy)] != 0;
		}
		EXPECT_TRUE(lineBlocked);
		// and a path exists around it, not shorter than the straight line
		const GridPath p = shortestFreePath(gt, g.start, g.goal, o.walkerRadius);
		ASSERT_TRUE(p.found);
		EXPECT_NEAR(p.length, g.gtPathLength, 1e-4);
		EXPECT_GE(p.length, (g.goal - g.start).norm() - 0.05);
		// Start and goal are on free floor.
		for (const Eigen::Vector2d& q : {g.start, g.goal})
		{
			int ix, iy;
			ASSERT_TRUE(gt.cellOf(q.x(), q.y(), ix, iy));
			EXPECT_EQ(gt.geomLabel[gt.idx(ix, iy)], Label::Free);
		}
	}
}

TEST(SceneGenerator, EveryHazardKindAppearsAcrossSeeds)
{
	std::set<HazardKind> seen, onLine;
	for (unsigned seed = 1; seed <= 20; seed++)
	{
		const GeneratedScene g = generateScene(seed);
		for (const auto& h : g.hazards)
		{
			seen.insert(h.kind);
			if (h.onLine) onLine.insert(h.kind);
		}
		// the line hazard is one of the hazards, with its id
		bool found = false;
		for (const auto& h : g.hazards) found |= h.onLine && h.objectId == g.lineHazardId && h.kind == g.lineHazard;
		EXPECT_TRUE(found) << "seed " << seed;
	}
	for (int k = 0; k < kHazardKindCount; k++)
		EXPECT_TRUE(seen.count(HazardKind(k))) << hazardKindName(HazardKind(k)) << " never generated in seeds 1-20";
	// The line kinds cycle with the seed: 7 consecutive seeds have all 7.
	EXPECT_EQ(onLine.size(), 7u);
	EXPECT_FALSE(onLine.count(HazardKind::Ramp));
	EXPECT_FALSE(onLine.count(HazardKind::Person));
}

TEST(SceneGenerator, DropKindsAreDropCellsAndObstacleKindsObstacleCells)
{
	// seeds 1..7 put, in turn, outlet, step_down, stairwell, cable_protector,
	// small_box, table, hole on the line (seed % 7)
	const HazardKind kinds[7] = {HazardKind::Hole,      HazardKind::Outlet,         HazardKind::StepDown,
								 HazardKind::Stairwell, HazardKind::CableProtector, HazardKind::SmallBox,
								 HazardKind::Table};
	for (unsigned seed = 1; seed <= 7; seed++)
	{
		const GeneratedScene g = generateScene(seed);
		ASSERT_EQ(g.lineHazard, kinds[seed % 7]) << "seed " << seed;
		const GroundTruthGrid gt = staticGroundTruth(g.file);
		size_t cells = 0, right = 0;
		for (size_t i = 0; i < gt.geomLabel.size(); i++)
			if (gt.objectId[i] == g.lineHazardId)
			{
				cells++;
				const bool isDropKind = kinds[seed % 7] <= HazardKind::Stairwell;
				right += gt.geomLabel[i] == (isDropKind ? Label::Drop : Label::Obstacle);
			}
		EXPECT_GT(cells, 0u) << "seed " << seed;
		EXPECT_EQ(right, cells) << "seed " << seed << " (" << hazardKindName(g.lineHazard) << ")";
	}
}

TEST(SceneGenerator, PeopleCrossAndTheFrameGroundTruthFollowsThem)
{
	// the first seed with a person
	for (unsigned seed = 1; seed <= 30; seed++)
	{
		const GeneratedScene g = generateScene(seed);
		const ObjectInfo* person = nullptr;
		for (const auto& ob : g.file.scene.objects)
			if (ob.name == "person") person = &ob;
		if (!person) continue;
		ASSERT_TRUE(person->dynamic());
		// absent before its first frame, present in the middle of its crossing, absent after
		const int f0 = person->first_frame, f1 = person->last_frame, mid = (f0 + f1) / 2;
		ASSERT_GT(f1, f0);
		EXPECT_TRUE(g.file.scene.footprintAt(person->id, f0 - 1).isEmpty());
		EXPECT_TRUE(g.file.scene.footprintAt(person->id, f1 + 1).isEmpty());
		const Eigen::AlignedBox2d b = g.file.scene.footprintAt(person->id, mid);
		ASSERT_FALSE(b.isEmpty());
		// it moves along y only, so its x extent is its 0.40 m width
		EXPECT_NEAR(b.sizes().x(), 0.40, 1e-6);
		// the per-frame ground truth: the cell under its centre is an obstacle of
		// the person in the middle frame, and free of it before it came
		FrameGroundTruth ft(g.file.scene, g.file.grid);
		const Eigen::Vector2d c = b.center();
		int ix, iy;
		ASSERT_TRUE(ft.grid().cellOf(c.x(), c.y(), ix, iy));
		ft.setFrame(f0 - 1);
		EXPECT_NE(ft.grid().objectId[ft.grid().idx(ix, iy)], person->id);
		ft.setFrame(mid);
		EXPECT_EQ(ft.grid().geomLabel[ft.grid().idx(ix, iy)], Label::Obstacle);
		EXPECT_EQ(ft.grid().objectId[ft.grid().idx(ix, iy)], person->id);
		ft.setFrame(f1 + 1);
		EXPECT_NE(ft.grid().objectId[ft.grid().idx(ix, iy)], person->id);
		return;
	}
	FAIL() << "no person in seeds 1-30";
}

TEST(SceneGenerator, BlockedCellsGrowByTheRadius)
{
	// One 5 cm obstacle cell in an empty 1 m grid: with radius 0.10 m (2 cells
	// centre to centre) the blocked cells are those with dx^2 + dy^2 <= 4:
	// 1 + 4 (distance 1) + 4 (sqrt 2) + 4 (distance 2) = 13 cells.
	Scene s;
	s.objects.push_back(ObjectInfo{});
	s.objects.back().id = 1;
	s.solids.push_back(ConvexSolid::box(
		Pose3::fromXYZYPR(0.525, 0.525, 0.05, 0, 0, 0), Eigen::Vector3d(0.02, 0.02, 0.05), 1));  // inside cell (10,10)
	GridSpec spec;
	spec.min_x = spec.min_y = 0;
	spec.max_x = spec.max_y = 1.0;
	GroundTruthGrid gt;
	gt.build(s, spec);
	size_t obstacles = 0;
	for (const auto l : gt.geomLabel) obstacles += l == Label::Obstacle;
	ASSERT_EQ(obstacles, 1u);
	const auto b = blockedCells(gt, 0.10);
	size_t n = 0;
	for (const auto v : b) n += v;
	EXPECT_EQ(n, 13u);
	// A path from (0.1, 0.5) to (0.9, 0.5) goes around: longer than 0.8 m.
	const GridPath p = shortestFreePath(gt, {0.1, 0.5}, {0.9, 0.5}, 0.10);
	ASSERT_TRUE(p.found);
	EXPECT_GT(p.length, 0.8 - 1e-6);
}

TEST(SceneGenerator, TheHeldOutApproachPathDrivesTowardTheGoal)
{
	// The written scene's path is the start pose alone (one depth frame); the
	// held-out protocol drives 1.5 m from it straight toward the goal, a frame
	// every 0.1 m: 1.5 / 0.1 + 1 = 16 poses, 0.1 m apart, every one facing the
	// goal (the yaw is written to 0.01 deg, the positions to 1 mm).
	const GeneratedScene g = generateScene(3005);
	std::istringstream one(g.text);
	EXPECT_EQ(samplePath(parseScene(one, "seed_3005").path).size(), 1u);

	std::istringstream in(withApproachPath(g, 1.5));
	const std::vector<Pose2> poses = samplePath(parseScene(in, "seed_3005 (1.5 m)").path);
	ASSERT_EQ(poses.size(), 16u);
	EXPECT_NEAR(poses.front().x, g.start.x(), 1e-3);
	EXPECT_NEAR(poses.front().y, g.start.y(), 1e-3);
	const double heading = std::atan2(g.goal.y() - g.start.y(), g.goal.x() - g.start.x());
	EXPECT_NEAR(std::hypot(poses.back().x - poses.front().x, poses.back().y - poses.front().y), 1.5, 2e-3);
	EXPECT_NEAR(std::atan2(poses.back().y - poses.front().y, poses.back().x - poses.front().x), heading, 2e-3);
	for (size_t i = 1; i < poses.size(); i++)
	{
		EXPECT_NEAR(std::hypot(poses[i].x - poses[i - 1].x, poses[i].y - poses[i - 1].y), 0.1, 2e-4);
		EXPECT_NEAR(poses[i].yaw, heading, 0.01 * M_PI / 180 + 1e-9);
	}
	// Everything but the path line is the scene as generated.
	const std::string a = g.text, b = withApproachPath(g, 1.5);
	const size_t pa = a.find("\npath "), pb = b.find("\npath ");
	EXPECT_EQ(a.substr(0, pa), b.substr(0, pb));
	EXPECT_EQ(a.substr(a.find('\n', pa + 1)), b.substr(b.find('\n', pb + 1)));

	EXPECT_THROW(withApproachPath(g, 0), std::invalid_argument);
	EXPECT_THROW(withApproachPath(g, 1.5, 0), std::invalid_argument);
	GeneratedScene noPath = g;
	noPath.text = "wall id=1 x0=0 y0=0 x1=1 y1=0\n";
	EXPECT_THROW(withApproachPath(noPath, 1.5), std::invalid_argument);
}
