// The plugin inside stock MRPT apps: rawlog-edit -p and observations2map (LD_PRELOAD).
#include <gtest/gtest.h>
#include <mrpt/config/CConfigFile.h>
#include <mrpt/io/CFileGZInputStream.h>
#include <mrpt/maps/CGroundAwareOccupancyGrid.h>
#include <mrpt/maps/CSimpleMap.h>
#include <mrpt/obs/CSensoryFrame.h>
#include <mrpt/poses/CPose3DPDFGaussian.h>
#include <mrpt/serialization/CArchive.h>
#include <mrpt/system/filesystem.h>

#include <cstdlib>
#include <fstream>
#include <regex>
#include <sstream>

#include "synthetic_scene.h"

using namespace mrpt::maps;

namespace
{
std::string tempDir(const std::string& name)
{
	const std::string d = mrpt::system::getTempFileName() + "_" + name;
	mrpt::system::createDirectory(d);
	return d;
}
int run(const std::string& cmd) { return std::system(cmd.c_str()); }
std::string slurp(const std::string& f)
{
	std::ifstream in(f);
	std::stringstream s;
	s << in.rdbuf();
	return s.str();
}
bool haveApp(const char* app) { return run(std::string("command -v ") + app + " >/dev/null 2>&1") == 0; }
}  // namespace

TEST(StockApps, Observations2mapBuildsOurMapsThroughLdPreload)
{
	if (!haveApp("observations2map")) GTEST_SKIP() << "mrpt-apps not installed";
	const std::string dir = tempDir("o2m");
	// A simplemap with one frame of a floor, a box and a hole.
	auto scene = testscene::floorWithHole(-1, 6, -3, 3, 2.0, 2.4, -0.3, 0.3);
	scene.push_back({1.5, 0.6, 0.0, 1.7, 0.8, 0.1});
	auto sf = mrpt::obs::CSensoryFrame::Create();
	sf->insert(testscene::renderDepth(scene, mrpt::poses::CPose3D(0, 0, 1.0, 0, mrpt::DEG2RAD(25.0), 0)));
	CSimpleMap sm;
	sm.insert(mrpt::poses::CPose3DPDFGaussian::Create(), sf);
	ASSERT_TRUE(sm.saveToFile(dir + "/in.simplemap"));
	// The example .ini as it is, with observations2map's section name.
	const std::string ini = std::regex_replace(
		slurp(std::string(GAM_SOURCE_DIR) + "/config/ground-aware-grid.ini"),
		std::regex("^\\[map", std::regex::multiline), "[MappingApplication");
	std::ofstream(dir + "/o2m.ini") << ini;

	const std::string cmd = "cd " + dir + " && LD_PRELOAD=" + GAM_PLUGIN_PATH +
							" observations2map o2m.ini in.simplemap out </dev/null >log.txt 2>&1";
	ASSERT_EQ(run(cmd), 0) << slurp(dir + "/log.txt");
	EXPECT_TRUE(mrpt::system::fileExists(dir + "/out_mrpt__maps__CElevation25DMap_00_zmax.png"));
	EXPECT_TRUE(mrpt::system::fileExists(dir + "/out_mrpt__maps__CGroundAwareOccupancyGrid_01.png"));
	// The saved grid is our class (needs the plugin to read it): it saw the box.
	const std::string gm = dir + "/out_gridmap_no00.gridmap";
	ASSERT_TRUE(mrpt::system::fileExists(gm));
	mrpt::io::CFileGZInputStream f(gm);
	auto obj = mrpt::serialization::archiveFrom(f).ReadObject();
	auto grid = std::dynamic_pointer_cast<CGroundAwareOccupancyGrid>(obj);
	ASSERT_TRUE(grid);
	EXPECT_LT(grid->getPos(1.6f, 0.7f), 0.3f) << "box occupied";
	EXPECT_LT(grid->getPos(2.2f, 0.0f), 0.3f) << "hole occupied";
	EXPECT_GT(grid->getPos(1.0f, -0.5f), 0.7f) << "floor free";
}

TEST(StockApps, RawlogEditLoadsThePlugin)
{
	if (!haveApp("rawlog-edit")) GTEST_SKIP() << "mrpt-apps not installed";
	const std::string dir = tempDir("redit");
	const std::string rl = std::string(GAM_REAL_DATA_DIR) + "/mrpt_3d_obs_ground/test-3d-obs-ground.rawlog";
	if (!mrpt::system::fileExists(rl)) GTEST_SKIP() << "real data not found";
	// rawlog-edit exits 0 even when a plugin fails to load: look for the
	// plugin's own line (GAM_PLUGIN_VERBOSE) and compare with a bogus path.
	auto edit = [&](const std::string& plugin) {
		const std::string cmd = "GAM_PLUGIN_VERBOSE=1 rawlog-edit -p " + plugin + " -i " + rl + " --info >" + dir +
								"/log.txt 2>&1 </dev/null";
		EXPECT_EQ(run(cmd), 0) << slurp(dir + "/log.txt");
		return slurp(dir + "/log.txt");
	};
	const std::string ok = edit(GAM_PLUGIN_PATH);
	EXPECT_NE(ok.find("[ground_aware_maps] plugin loaded"), std::string::npos) << ok;
	EXPECT_NE(ok.find("Observations format"), std::string::npos) << ok;
	const std::string bogus = edit(dir + "/nonexistent.so");
	EXPECT_EQ(bogus.find("[ground_aware_maps] plugin loaded"), std::string::npos) << bogus;
}
