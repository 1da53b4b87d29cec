// Helpers of the robustness tests: every map class of the plugin, fresh, and
// checks that a map survived an insertion (an exception is an acceptable answer
// to bad input, a crash or a silently corrupted map is not).
#pragma once

#include <mrpt/maps/CElevation25DMap.h>
#include <mrpt/maps/CGroundAwareOccupancyGrid.h>
#include <mrpt/maps/CHeightBandOccupancyGrid.h>
#include <mrpt/maps/COctoMapGrid2D.h>
#include <mrpt/maps/registerBaselineMaps.h>
#include <mrpt/maps/registerGroundAwareMaps.h>

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "../maps/synthetic_scene.h"

namespace robust
{
struct NamedMap
{
	std::string name;
	std::shared_ptr<mrpt::maps::CMetricMap> map;
};

/** One of each map class of the plugin, default options. */
inline std::vector<NamedMap> allMaps()
{
	mrpt::maps::registerGroundAwareMaps();
	mrpt::maps::registerBaselineMaps();
	return {
		{"CElevation25DMap", std::make_shared<mrpt::maps::CElevation25DMap>()},
		{"CGroundAwareOccupancyGrid", std::make_shared<mrpt::maps::CGroundAwareOccupancyGrid>()},
		{"CHeightBandOccupancyGrid", std::make_shared<mrpt::maps::CHeightBandOccupancyGrid>()},
		{"COctoMapGrid2D", std::make_shared<mrpt::maps::COctoMapGrid2D>()}};
}

/** A floor 6 x 6 m with a box, seen by a 256x212 depth camera 1 m up, pitched 25 deg down. */
inline std::vector<testscene::Box> floorAndBox()
{
	auto s = testscene::floorWithHole(-1, 6, -3, 3);
	s.push_back({1.5, 0.5, 0.0, 1.8, 0.8, 0.3});
	return s;
}
inline const mrpt::poses::CPose3D kMount(0, 0, 1.0, 0, mrpt::DEG2RAD(25.0), 0);

/** 2D grid cells as a vector (for "did it change" checks). */
inline std::vector<int> gridCells(const mrpt::maps::COccupancyGridMap2D& g)
{
	std::vector<int> v;
	v.reserve(g.getRawMap().size() + 2);
	v.push_back(int(g.getSizeX()));
	v.push_back(int(g.getSizeY()));
	for (auto c : g.getRawMap()) v.push_back(int(c));
	return v;
}

}  // namespace robust
