#include <mrpt/core/initializer.h>
#include <mrpt/maps/CElevation25DMap.h>
#include <mrpt/maps/CGroundAwareOccupancyGrid.h>
#include <mrpt/maps/CHeightBandOccupancyGrid.h>
#include <mrpt/maps/COctoMapGrid2D.h>
#include <mrpt/maps/registerGroundAwareMaps.h>
#include <mrpt/rtti/CObject.h>

// Runs when the library is loaded: linked, dlopen()-ed as a plugin
// (rawlog-edit -p, RawLogViewer -l) or LD_PRELOAD-ed (observations2map).
// The .ini map types register themselves through MAP_DEFINITION_REGISTER.
MRPT_INITIALIZER(registerAllClasses_ground_aware_maps)
{
	mrpt::rtti::registerClass(CLASS_ID(mrpt::maps::CElevation25DMap));
	mrpt::rtti::registerClass(CLASS_ID(mrpt::maps::CGroundAwareOccupancyGrid));
	mrpt::rtti::registerClass(CLASS_ID(mrpt::maps::CHeightBandOccupancyGrid));
	mrpt::rtti::registerClass(CLASS_ID(mrpt::maps::COctoMapGrid2D));
}

void mrpt::maps::registerGroundAwareMaps()
{
	// Idempotent: registerClass ignores classes it already knows.
	mrpt::rtti::registerClass(CLASS_ID(mrpt::maps::CElevation25DMap));
	mrpt::rtti::registerClass(CLASS_ID(mrpt::maps::CGroundAwareOccupancyGrid));
	mrpt::rtti::registerClass(CLASS_ID(mrpt::maps::CHeightBandOccupancyGrid));
	mrpt::rtti::registerClass(CLASS_ID(mrpt::maps::COctoMapGrid2D));
}
