#include <mrpt/core/initializer.h>
#include <mrpt/maps/CHeightBandOccupancyGrid.h>
#include <mrpt/maps/COctoMapGrid2D.h>
#include <mrpt/maps/registerBaselineMaps.h>
#include <mrpt/rtti/CObject.h>

#include <cstdlib>
#include <iostream>
#include <string>

// Runs when the library is loaded: linked, dlopen()-ed as a plugin
// (rawlog-edit -p, RawLogViewer -l) or LD_PRELOAD-ed (observations2map).
// The .ini map types register themselves through MAP_DEFINITION_REGISTER.
MRPT_INITIALIZER(registerAllClasses_baseline_maps)
{
	mrpt::maps::registerBaselineMaps();
	if (const char* v = std::getenv("GAM_PLUGIN_VERBOSE"); v && *v && std::string(v) != "0")
		std::cerr << "[baseline_maps] plugin loaded: map classes registered\n";
}

void mrpt::maps::registerBaselineMaps()
{
	// Idempotent: registerClass ignores classes it already knows.
	mrpt::rtti::registerClass(CLASS_ID(mrpt::maps::CHeightBandOccupancyGrid));
	mrpt::rtti::registerClass(CLASS_ID(mrpt::maps::COctoMapGrid2D));
}
