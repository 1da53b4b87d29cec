// Plugin registration, CMultiMetricMap .ini construction and option checks.
#include <gam/maps/IniFields.h>
#include <gtest/gtest.h>
#include <mrpt/config/CConfigFile.h>
#include <mrpt/config/CConfigFileMemory.h>
#include <mrpt/maps/CElevation25DMap.h>
#include <mrpt/maps/CGroundAwareOccupancyGrid.h>
#include <mrpt/maps/CMultiMetricMap.h>
#include <mrpt/maps/registerGroundAwareMaps.h>
#include <mrpt/rtti/CObject.h>

using namespace mrpt::maps;

namespace
{
TSetOfMetricMapInitializers initsFrom(const std::string& ini, const std::string& section = "map")
{
	mrpt::config::CConfigFileMemory cfg(ini);
	TSetOfMetricMapInitializers inits;
	inits.loadFromConfigFile(cfg, section);
	return inits;
}
}  // namespace

TEST(Registration, ClassesKnownToMrptRtti)
{
	registerGroundAwareMaps();
	EXPECT_NE(mrpt::rtti::findRegisteredClass("mrpt::maps::CElevation25DMap"), nullptr);
	EXPECT_NE(mrpt::rtti::findRegisteredClass("mrpt::maps::CGroundAwareOccupancyGrid"), nullptr);
	for (const char* name :
		 {"CElevation25DMap", "elevation25DMap", "CGroundAwareOccupancyGrid", "groundAwareGrid",
		  "mrpt::maps::CGroundAwareOccupancyGrid"})
	{
		std::unique_ptr<TMetricMapInitializer> def(TMetricMapInitializer::factory(name));
		EXPECT_TRUE(def) << name;
	}
}

TEST(IniConstruction, BothMapsFromStandardSections)
{
	const auto inits = initsFrom(R"(
[map]
groundAwareGrid_count=1
CElevation25DMap_count=1
occupancyGrid_count=1
[map_groundAwareGrid_00_creationOpts]
min_x=-4
max_x=6
min_y=-3
max_y=3
resolution=0.1
[map_groundAwareGrid_00_groundOpts]
K=300
N_th=0.15
d_pth=0.04
local_planes=false
[map_CElevation25DMap_00_creationOpts]
resolution=0.02
min_x=-1
max_x=1
min_y=-1
max_y=1
[map_CElevation25DMap_00_insertOpts]
idw_radius=2
outlier_filter=false
)");
	CMultiMetricMap mm(inits);
	ASSERT_EQ(mm.maps.size(), 3u);
	auto ga = mm.mapByClass<CGroundAwareOccupancyGrid>();
	auto el = mm.mapByClass<CElevation25DMap>();
	ASSERT_TRUE(ga);
	ASSERT_TRUE(el);
	EXPECT_NEAR(ga->getResolution(), 0.1, 1e-6);
	EXPECT_NEAR(ga->getXMin(), -4, 1e-4);
	EXPECT_NEAR(ga->getXMax(), 6, 1e-4);
	const gam::PipelineParams& p = ga->groundOptions().pipeline;
	EXPECT_EQ(p.rrt.iterations, 300);
	EXPECT_DOUBLE_EQ(p.rrt.normal_threshold, 0.15);
	EXPECT_DOUBLE_EQ(p.ism.d_pth, 0.04);
	EXPECT_FALSE(p.ism.local_planes);
	EXPECT_EQ(p.rrt.neighbourhood_x, 3);  // untouched keys keep Table I defaults
	EXPECT_EQ(el->grid().geometry().nx, 100);
	EXPECT_DOUBLE_EQ(el->grid().geometry().resolution, 0.02);
	EXPECT_EQ(el->insertionOptions().idw.radius_cells, 2);
	EXPECT_FALSE(el->insertionOptions().outliers.enabled);
	// The derived grid is also found as a COccupancyGridMap2D (MRPT tools rely on it).
	EXPECT_EQ(mm.countMapsByClass<COccupancyGridMap2D>(), 2u);
}

TEST(IniConstruction, StockInsertionDefaultsAndTheWalkersLeddarSetting)
{
	// Issue #31: the stock options keep the stock defaults (an .ini written for
	// COccupancyGridMap2D means the same here) ...
	CMultiMetricMap mm(initsFrom("[map]\ngroundAwareGrid_count=1\n"));
	EXPECT_TRUE(mm.mapByClass<CGroundAwareOccupancyGrid>()->insertionOptions.considerInvalidRangesAsFreeSpace);
	EXPECT_TRUE(CGroundAwareOccupancyGrid().insertionOptions.considerInvalidRangesAsFreeSpace);
	// ... and the walker's configs say that a Leddar "no return" is not free space.
	for (const char* f : {"/config/ground-aware-grid.ini", "/config/ground-aware-mapper.ini"})
	{
		mrpt::config::CConfigFile cfg(std::string(GAM_SOURCE_DIR) + f);
		TSetOfMetricMapInitializers inits;
		inits.loadFromConfigFile(cfg, "map");
		CMultiMetricMap walker(inits);
		ASSERT_TRUE(walker.mapByClass<CGroundAwareOccupancyGrid>()) << f;
		EXPECT_FALSE(walker.mapByClass<CGroundAwareOccupancyGrid>()->insertionOptions.considerInvalidRangesAsFreeSpace)
			<< f;
		EXPECT_EQ(
			walker.mapByClass<CGroundAwareOccupancyGrid>()->groundOptions().scan_keeps_3d_obstacles,
			CGroundAwareOccupancyGrid::TGroundAwareOptions::ScanRule::KeepCameraFloor)
			<< f;
	}
}

TEST(IniConstruction, ScanRuleTakesItsNamesAndTheOldBooleans)
{
	using R = CGroundAwareOccupancyGrid::TGroundAwareOptions::ScanRule;
	const std::vector<std::pair<std::string, R>> cases = {
		{"auto", R::Auto},       {"true", R::KeepCameraFloor}, {"1", R::KeepCameraFloor}, {"yes", R::KeepCameraFloor},
		{"false", R::BeamModel}, {"0", R::BeamModel},          {"OFF", R::BeamModel}};
	for (const auto& [text, want] : cases)
	{
		CMultiMetricMap m(initsFrom(
			"[map]\ngroundAwareGrid_count=1\n[map_groundAwareGrid_00_groundOpts]\nscan_keeps_3d_obstacles=" + text +
			"\n"));
		EXPECT_EQ(m.mapByClass<CGroundAwareOccupancyGrid>()->groundOptions().scan_keeps_3d_obstacles, want) << text;
	}
	try
	{
		initsFrom("[map]\ngroundAwareGrid_count=1\n[map_groundAwareGrid_00_groundOpts]\nscan_keeps_3d_obstacles=2\n");
		ADD_FAILURE() << "scan_keeps_3d_obstacles=2 was accepted";
	}
	catch (const std::exception& e)
	{
		EXPECT_NE(std::string(e.what()).find("false | true | auto"), std::string::npos) << e.what();
	}
}

TEST(IniConstruction, DefaultsAreThePaperTableI)
{
	CGroundAwareOccupancyGrid g;
	const gam::PipelineParams& o = g.groundOptions().pipeline;
	EXPECT_EQ(o.rrt.iterations, 600);                   // K
	EXPECT_DOUBLE_EQ(o.rrt.normal_threshold, 0.2);      // N_th
	EXPECT_DOUBLE_EQ(o.rrt.elevation_threshold, 0.05);  // E_th
	EXPECT_EQ(o.rrt.neighbourhood_x, 3);                // s_x
	EXPECT_EQ(o.rrt.neighbourhood_y, 3);                // s_y
	EXPECT_EQ(o.m_x, 200);
	EXPECT_EQ(o.m_y, 200);
	EXPECT_NEAR(g.getResolution(), 0.05, 1e-7);       // d_r
	EXPECT_DOUBLE_EQ(o.rrt.expansion_distance, 0.4);  // d_n
	EXPECT_DOUBLE_EQ(o.ism.d_pth, 0.03);
	EXPECT_DOUBLE_EQ(o.ism.K_g, 0.3);
	EXPECT_DOUBLE_EQ(o.ism.sigma2, 0.02);
	EXPECT_DOUBLE_EQ(o.ism.K_n, 0.0005);
	EXPECT_DOUBLE_EQ(o.ism.d_min, 3);
	EXPECT_DOUBLE_EQ(o.ism.K_m, 0.8);
}

TEST(IniConstruction, ExampleConfigLoadsWithTableIValues)
{
	mrpt::config::CConfigFile cfg(std::string(GAM_SOURCE_DIR) + "/config/ground-aware-grid.ini");
	TSetOfMetricMapInitializers inits;
	inits.loadFromConfigFile(cfg, "map");
	CMultiMetricMap mm(inits);
	auto ga = mm.mapByClass<CGroundAwareOccupancyGrid>();
	ASSERT_TRUE(ga);
	CGroundAwareOccupancyGrid ref;
	// Every key of the example is spelled right and holds the default, and the
	// paper's Table I keys are all there. (Other keys may be left out: their
	// reference is the core's parameter table, so adding a parameter is one
	// edit of its struct.)
	using Options = CGroundAwareOccupancyGrid::TGroundAwareOptions;
	const std::string sec = "map_groundAwareGrid_00_groundOpts";
	std::vector<double> loaded, defaults;
	std::vector<std::string> names;
	Options::forEachParam(ga->groundOptions(), [&](const gam::ParamInfo& info, const auto& v) {
		names.push_back(info.key);
		loaded.push_back(double(v));
	});
	Options::forEachParam(
		ref.groundOptions(), [&](const gam::ParamInfo&, const auto& v) { defaults.push_back(double(v)); });
	ASSERT_EQ(loaded.size(), defaults.size());
	for (size_t i = 0; i < loaded.size(); i++)
	{
		// The walker's example has a Leddar that may start before its camera,
		// so it sets the scan rule on from the first scan (default: auto).
		if (names[i] == "scan_keeps_3d_obstacles")
			EXPECT_DOUBLE_EQ(loaded[i], double(Options::ScanRule::KeepCameraFloor));
		else
			EXPECT_DOUBLE_EQ(loaded[i], defaults[i]) << names[i];
	}
	for (const char* k :
		 {"K", "N_th", "E_th", "s_x", "s_y", "m_x", "m_y", "d_n", "d_pth", "K_g", "sigma2", "K_n", "d_min", "K_m"})
		EXPECT_TRUE(cfg.keyExists(sec, k)) << k << " missing in the example";
	// ... and it has no key the options do not know.
	std::vector<std::string> keys;
	cfg.getAllKeys(sec, keys);
	const auto known = gam::maps::ini::keys<Options>();
	for (const auto& k : keys) EXPECT_NE(std::find(known.begin(), known.end(), k), known.end()) << k;
}

TEST(IniConstruction, OutOfRangeValuesNameTheKey)
{
	struct Case
	{
		std::string section, key, value;
	};
	const std::vector<Case> bad = {
		{"groundOpts", "K", "0"},
		{"groundOpts", "s_x", "4"},
		{"groundOpts", "s_y", "1"},
		{"groundOpts", "N_th", "1.5"},
		{"groundOpts", "d_pth", "-0.1"},
		{"groundOpts", "K_m", "1.2"},
		{"groundOpts", "m_x", "0"},
		{"groundOpts", "E_th", "abc"},
		{"groundOpts", "drop_rays", "maybe"},
		{"creationOpts", "resolution", "-0.05"}};
	for (const auto& c : bad)
	{
		const std::string ini = "[map]\ngroundAwareGrid_count=1\n[map_groundAwareGrid_00_" + c.section + "]\n" + c.key +
								"=" + c.value + "\n";
		try
		{
			initsFrom(ini);
			ADD_FAILURE() << c.key << "=" << c.value << " was accepted";
		}
		catch (const std::exception& e)
		{
			const std::string msg = e.what();
			EXPECT_NE(msg.find(c.key), std::string::npos) << msg;
			EXPECT_NE(msg.find(c.value), std::string::npos) << msg;
		}
	}
	// Elevation map too.
	EXPECT_THROW(
		initsFrom("[map]\nCElevation25DMap_count=1\n[map_CElevation25DMap_00_insertOpts]\ndecimation=0\n"),
		std::exception);
	EXPECT_THROW(
		initsFrom("[map]\nCElevation25DMap_count=1\n[map_CElevation25DMap_00_insertOpts]\nz_min=2\nz_max=1\n"),
		std::exception);
}

TEST(IniConstruction, SaveThenLoadGivesTheSameOptions)
{
	CGroundAwareOccupancyGrid a;
	auto o = a.groundOptions();
	o.pipeline.rrt.iterations = 123;
	o.pipeline.ism.d_pth = 0.045;
	o.pipeline.ism.drop_rays = false;
	a.setGroundOptions(o);
	mrpt::config::CConfigFileMemory mem;
	a.groundOptions().saveToConfigFile(mem, "g");
	CGroundAwareOccupancyGrid::TGroundAwareOptions b;
	b.loadFromConfigFile(mem, "g");
	EXPECT_EQ(b.pipeline.rrt.iterations, 123);
	EXPECT_DOUBLE_EQ(b.pipeline.ism.d_pth, 0.045);
	EXPECT_FALSE(b.pipeline.ism.drop_rays);
}
