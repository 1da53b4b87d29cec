#include <mrpt/core/initializer.h>
#include <mrpt/maps/CElevation25DMap.h>
#include <mrpt/maps/CGroundAwareOccupancyGrid.h>
#include <mrpt/maps/registerGroundAwareMaps.h>
#include <mrpt/rtti/CObject.h>

#include <cstdlib>
#include <iostream>
#include <string>

// Runs when the library is loaded: linked, dlopen()-ed as a plugin
// (rawlog-edit -p, RawLogViewer -l) or LD_PRELOAD-ed (observations2map).
// The .ini map types register themselves through MAP_DEFINITION_REGISTER.
MRPT_INITIALIZER(registerAllClasses_ground_aware_maps)
{
	mrpt::maps::registerGroundAwareMaps();
	// Stock apps say nothing about the plugins they load: set
	// GAM_PLUGIN_VERBOSE=1 to see that this one was.
	if (const char* v = std::getenv("GAM_PLUGIN_VERBOSE"); v && *v && std::string(v) != "0")
		std::cerr << "[ground_aware_maps] plugin loaded: map classes registered\n";
}

void mrpt::maps::registerGroundAwareMaps()
{
	// Idempotent: registerClass ignores classes it already knows.
	mrpt::rtti::registerClass(CLASS_ID(mrpt::maps::CElevation25DMap));
	mrpt::rtti::registerClass(CLASS_ID(mrpt::maps::CGroundAwareOccupancyGrid));
}
