// Ground-aware mapping for MRPT -- tests: every bundled scene parses, has a
// path, and every object that matters shows up in its ground-truth grid.
#include <gtest/gtest.h>

#include <filesystem>
#include <set>

#include "gam/sim/SceneFile.h"

using namespace gam::sim;
namespace fs = std::filesystem;

TEST(SimScenes, BundledScenesParseAndLabelEveryObject)
{
	const fs::path dir = fs::path(GAM_SOURCE_DIR) / "config" / "scenes";
	std::set<std::string> names;
	for (const auto& e : fs::directory_iterator(dir))
	{
		if (e.path().extension() != ".scene") continue;
		names.insert(e.path().stem().string());
		SCOPED_TRACE(e.path().string());
		SceneFile sf = parseSceneFile(e.path().string());
		EXPECT_TRUE(sf.has_grid);
		EXPECT_FALSE(sf.scene.objects.empty());
		const auto frames = samplePath(sf.path);
		EXPECT_GE(frames.size(), 5u);
		EXPECT_LE(frames.size(), 400u);
		GroundTruthGrid gt;
		gt.build(sf.scene, sf.grid);
		std::set<int> seen(gt.objectId.begin(), gt.objectId.end());
		for (const auto& o : sf.scene.objects)
		{
			const bool matters =
				(o.bbox.max().z() > sf.grid.obstacle_min_height || o.bbox.min().z() < -sf.grid.drop_min_depth) &&
				o.bbox.min().z() < sf.grid.robot_height;
			if (matters)
			{
				EXPECT_TRUE(seen.count(o.id)) << o.name;
			}
		}
	}
	for (const char* s :
		 {"demo", "floor_outlets", "downward_stairs", "cable_protector", "small_boxes", "table", "ramp_6deg",
		  "tilted_rolled_mount", "office_traverse", "no_floor"})
		EXPECT_TRUE(names.count(s)) << s;
}
