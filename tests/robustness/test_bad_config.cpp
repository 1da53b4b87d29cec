// Invalid .ini values for every map class of the plugin, through the same path
// as the mapper (gam::mapper::loadMapDefinitions + CMultiMetricMap), and maps too
// large for memory: a clear error naming the section, before anything is allocated.
// Already covered elsewhere (not repeated): tests/maps/test_registration_ini.cpp
// IniConstruction.OutOfRangeValuesNameTheKey (K=0, s_x=4, N_th=1.5, d_pth<0, K_m>1,
// m_x=0, E_th=abc, resolution<0 for groundAwareGrid; elevation decimation=0, z_min>z_max)
// and tests/mapper (unknown keys / sections / map kinds).
#include <gam/mapper/Mapper.h>
#include <gtest/gtest.h>
#include <mrpt/config/CConfigFileMemory.h>
#include <mrpt/maps/CMultiMetricMap.h>

#include <fstream>
#include <sstream>

#include "robustness_helpers.h"

using namespace mrpt::maps;

namespace
{
const std::vector<std::string> kKinds = {"groundAwareGrid", "heightBandGrid", "octoMapGrid", "CElevation25DMap"};

/** Builds the maps of `ini` as the mapper does; returns the error ("" = accepted). */
std::string buildError(const std::string& ini)
{
	try
	{
		mrpt::config::CConfigFileMemory cfg(ini);
		TSetOfMetricMapInitializers inits;
		std::vector<gam::mapper::MapSpec> specs;
		gam::mapper::loadMapDefinitions(cfg, "map", inits, specs);
		CMultiMetricMap mm;
		mm.setListOfMaps(inits);
		return "";
	}
	catch (const std::exception& e)
	{
		return e.what();
	}
}

std::string oneMap(const std::string& kind, const std::string& sub, const std::string& body)
{
	return "[map]\n" + kind + "_count=1\n[map_" + kind + "_00_" + sub + "]\n" + body;
}

}  // namespace

TEST(RobustConfig, EveryMapKindRejectsBadExtentsAndResolution)
{
	const std::vector<std::pair<std::string, std::string>> bad = {
		{"resolution=-0.05\n", "resolution"},
		{"resolution=0\n", "resolution"},
		{"resolution=nan\n", "resolution"},
		{"resolution=inf\n", "resolution"},
		{"min_x=2\nmax_x=2\n", "min_x < max_x"},   // zero cells
		{"min_y=3\nmax_y=-3\n", "min_x < max_x"},  // negative size
		{"min_x=abc\n", "min_x"}};
	for (const auto& kind : kKinds)
		for (const auto& [body, expect] : bad)
		{
			const std::string err = buildError(oneMap(kind, "creationOpts", body));
			EXPECT_NE(err, "") << kind << ": " << body << " accepted";
			EXPECT_NE(err.find(expect), std::string::npos) << kind << ": " << body << " -> " << err;
			EXPECT_NE(err.find("map_" + kind + "_00_creationOpts"), std::string::npos) << err;
		}
}

TEST(RobustConfig, MapsTooLargeForMemoryAreRefusedBeforeAllocating)
{
	// 200 km x 200 km at 1 mm: 4e16 cells. Each must fail with a clear error
	// before allocating (an allocation that size could only end in
	// std::bad_alloc, not in this message). How fast: tests/bench, not here.
	for (const auto& kind : kKinds)
	{
		const std::string err = buildError(oneMap(
			kind, "creationOpts", "min_x=-100000\nmax_x=100000\nmin_y=-100000\nmax_y=100000\nresolution=0.001\n"));
		EXPECT_NE(err.find("too large"), std::string::npos) << kind << ": " << err;
	}
	{
		// The ground-aware grid's per-frame 2.5D map: m_x x m_y, checked at load time.
		const std::string err = buildError(oneMap("groundAwareGrid", "groundOpts", "m_x=20000\nm_y=20000\n"));
		EXPECT_NE(err.find("too large"), std::string::npos) << err;
		EXPECT_NE(err.find("m_x"), std::string::npos) << err;
	}
	// Just over the limits: 2D grids 2^28 cells, the elevation map 2^26.
	for (const auto& kind : {"groundAwareGrid", "heightBandGrid", "octoMapGrid"})
	{
		EXPECT_EQ(
			buildError(oneMap(kind, "creationOpts", "min_x=0\nmax_x=1600\nmin_y=0\nmax_y=1600\nresolution=0.1\n")), "")
			<< kind << ": 16000 x 16000 cells are fine";
		EXPECT_NE(
			buildError(oneMap(kind, "creationOpts", "min_x=0\nmax_x=1700\nmin_y=0\nmax_y=1700\nresolution=0.1\n"))
				.find("too large"),
			std::string::npos)
			<< kind << ": 17000 x 17000 cells";
	}
	EXPECT_NE(
		buildError(
			oneMap("CElevation25DMap", "creationOpts", "min_x=0\nmax_x=900\nmin_y=0\nmax_y=900\nresolution=0.1\n"))
			.find("too large"),
		std::string::npos);
}

TEST(RobustConfig, ThresholdsOutOfRangeForTheComparisonAndElevationMaps)
{
	struct Case
	{
		std::string kind, sub, body, expect;
	};
	const std::vector<Case> bad = {
		{"heightBandGrid", "bandOpts", "z_min=1\nz_max=0.5\n", "z_min"},
		{"heightBandGrid", "bandOpts", "oversampling_ratio=0\n", "oversampling_ratio"},
		{"heightBandGrid", "bandOpts", "z_max=nan\n", "z_max"},
		{"octoMapGrid", "octoOpts", "voxel_size=0\n", "voxel_size"},
		{"octoMapGrid", "octoOpts", "prob_hit=0.3\n", "prob_hit"},
		{"octoMapGrid", "octoOpts", "prob_miss=0.7\n", "prob_miss"},
		{"octoMapGrid", "octoOpts", "clamping_min=0.9\nclamping_max=0.1\n", "clamping_min"},
		{"octoMapGrid", "octoOpts", "decimation=-1\n", "decimation"},
		{"octoMapGrid", "octoOpts", "max_range=1e9\n", "max_range"},
		{"CElevation25DMap", "insertOpts", "outlier_sigmas=0\n", "outlier_sigmas"},
		{"CElevation25DMap", "insertOpts", "max_range=-1\n", "max_range"},
		{"CElevation25DMap", "insertOpts", "idw_power=inf\n", "idw_power"},
		{"groundAwareGrid", "groundOpts", "K=-5\n", "K"},
		{"groundAwareGrid", "groundOpts", "K=1e12\n", "K"},
		{"groundAwareGrid", "groundOpts", "K=2.5\n", "K"},
		{"groundAwareGrid", "groundOpts", "ransac_iterations=0\n", "ransac_iterations"},
		{"groundAwareGrid", "groundOpts", "K_g=0.5\n", "K_g"},
		{"groundAwareGrid", "groundOpts", "sigma2=0\n", "sigma2"},
		{"groundAwareGrid", "groundOpts", "min_range=5\nmax_range=1\n", "min_range"},
		{"groundAwareGrid", "groundOpts", "robot_height=\n", "robot_height"},
		{"groundAwareGrid", "groundOpts", "random_seed=-1\n", "random_seed"}};
	for (const auto& c : bad)
	{
		const std::string err = buildError(oneMap(c.kind, c.sub, c.body));
		EXPECT_NE(err, "") << c.kind << " " << c.body << " accepted";
		EXPECT_NE(err.find(c.expect), std::string::npos) << c.kind << " " << c.body << " -> " << err;
	}
}

TEST(RobustConfig, GarbageIniTextGivesAnErrorOrTheDefaults)
{
	// Each text with its right outcome: an error containing `error`, or (error
	// "") accepted with `maps` maps, the ground-aware one with Table I's K.
	struct Case
	{
		std::string text, error;
		size_t maps;
	};
	const std::vector<Case> cases = {
		{"", "no [map] section", 0},
		{"[map]\n", "no maps defined in [map]", 0},
		{"[map]\ngroundAwareGrid_count=-1\n", "groundAwareGrid_count", 0},
		{"[map]\ngroundAwareGrid_count=1e9\n", "groundAwareGrid_count", 0},
		{"[map]\ngroundAwareGrid_count=\n", "groundAwareGrid_count", 0},
		// A broken section header: the [map] section does not exist.
		{"[map\ngroundAwareGrid_count=1\n", "no [map] section", 0},
		// Lines with no key name and a key without '=': MRPT's .ini parser
		// drops them before any map sees them, so the options keep their defaults.
		{"[map]\ngroundAwareGrid_count=1\n[map_groundAwareGrid_00_groundOpts]\n=\n==\nK\n", "", 1},
		// Bytes after a NUL are never read (the text is a C string to MRPT).
		{[] {
			 static const char raw[] = "[map]\ngroundAwareGrid_count=1\n\0\xff\xfe[x]\n";
			 return std::string(raw, sizeof(raw) - 1);  // with the NUL byte inside
		 }(),
		 "", 1},
		{"[map]\nCElevation25DMap_count=1\n[map_CElevation25DMap_00_creationOpts]\nlabel=../../etc/passwd\n", "label",
		 0}};
	for (const auto& c : cases)
	{
		SCOPED_TRACE(c.text);
		std::string err;
		size_t maps = 0;
		int K = 0;
		try
		{
			mrpt::config::CConfigFileMemory cfg(c.text);
			TSetOfMetricMapInitializers inits;
			std::vector<gam::mapper::MapSpec> specs;
			gam::mapper::loadMapDefinitions(cfg, "map", inits, specs);
			CMultiMetricMap mm;
			mm.setListOfMaps(inits);
			maps = mm.maps.size();
			if (auto ga = mm.mapByClass<CGroundAwareOccupancyGrid>()) K = ga->groundOptions().pipeline.rrt.iterations;
		}
		catch (const std::exception& e)
		{
			err = e.what();
		}
		if (c.error.empty())
		{
			EXPECT_EQ(err, "");
			EXPECT_EQ(maps, c.maps);
			EXPECT_EQ(K, 600) << "Table I's K";
		}
		else
			EXPECT_NE(err.find(c.error), std::string::npos) << err;
	}
}
