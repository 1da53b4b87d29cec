// ini-multimetric-map: the smallest program built against the installed
// ground-aware mapping SDK. It builds MRPT's CMultiMetricMap from an .ini (any
// map kinds, here a CGroundAwareOccupancyGrid), inserts every observation of a
// rawlog at its odometry pose and prints what the ground-aware grid made of it.
//
// usage: ini-multimetric-map MAPS.ini FILE.rawlog [SECTION]   (SECTION: default "map")
#include <mrpt/config/CConfigFile.h>
#include <mrpt/maps/CGroundAwareOccupancyGrid.h>
#include <mrpt/maps/CMultiMetricMap.h>
#include <mrpt/maps/registerGroundAwareMaps.h>
#include <mrpt/obs/CObservation3DRangeScan.h>
#include <mrpt/obs/CObservationOdometry.h>
#include <mrpt/obs/CRawlog.h>
#include <mrpt/system/filesystem.h>

#include <cstdio>
#include <exception>

int main(int argc, char** argv)
{
	if (argc < 3 || argc > 4)
	{
		std::fprintf(stderr, "usage: %s MAPS.ini FILE.rawlog [SECTION]\n", argv[0]);
		return 2;
	}
	try
	{
		// Keeps the plugin linked (--as-needed) and its map kinds known to the .ini loader.
		mrpt::maps::registerGroundAwareMaps();
		for (int i = 1; i < 3; i++)
			if (!mrpt::system::fileExists(argv[i]))
			{
				std::fprintf(stderr, "error: %s: no such file\n", argv[i]);
				return 1;
			}
		mrpt::config::CConfigFile ini(argv[1]);
		mrpt::maps::TSetOfMetricMapInitializers inits;
		inits.loadFromConfigFile(ini, argc == 4 ? argv[3] : "map");
		mrpt::maps::CMultiMetricMap maps;
		maps.setListOfMaps(inits);
		const auto grid = maps.mapByClass<mrpt::maps::CGroundAwareOccupancyGrid>();
		if (!grid)
		{
			std::fprintf(stderr, "error: %s defines no groundAwareGrid\n", argv[1]);
			return 1;
		}

		mrpt::obs::CRawlog rawlog;
		if (!rawlog.loadFromRawLogFile(argv[2]))
		{
			std::fprintf(stderr, "error: cannot read %s\n", argv[2]);
			return 1;
		}
		mrpt::poses::CPose3D pose;  // from odometry; the origin before any
		size_t depthFrames = 0, withGround = 0;
		for (size_t i = 0; i < rawlog.size(); i++)
		{
			if (rawlog.getType(i) != mrpt::obs::CRawlog::etObservation) continue;
			const auto obs = rawlog.getAsObservation(i);
			if (const auto odo = std::dynamic_pointer_cast<mrpt::obs::CObservationOdometry>(obs))
				pose = mrpt::poses::CPose3D(odo->odometry);
			obs->load();
			maps.insertObservation(*obs, pose);
			if (IS_CLASS(*obs, mrpt::obs::CObservation3DRangeScan))
			{
				depthFrames++;
				withGround += grid->lastFrame().detection.ok();
			}
		}
		size_t occupied = 0, free = 0;
		for (unsigned cy = 0; cy < grid->getSizeY(); cy++)
			for (unsigned cx = 0; cx < grid->getSizeX(); cx++)
			{
				const float pFree = grid->getCell(cx, cy);  // MRPT stores P(free)
				occupied += pFree < 0.45f;
				free += pFree > 0.55f;
			}
		std::printf(
			"%zu maps; %zu depth frames, ground plane in %zu; ground-aware grid: %zu occupied, %zu free cells\n",
			maps.maps.size(), depthFrames, withGround, occupied, free);
		return 0;
	}
	catch (const std::exception& e)
	{
		std::fprintf(stderr, "error: %s\n", e.what());
		return 1;
	}
}
