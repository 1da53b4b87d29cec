// Ground-aware mapping for MRPT
#pragma once

namespace mrpt::maps
{
/** Registers CElevation25DMap and CGroundAwareOccupancyGrid with MRPT's RTTI
 * (deserialization) and map-type (.ini) registries. This already happens when
 * the library is loaded; an executable that links the library but uses none of
 * its symbols calls this so that `--as-needed` linking keeps the library. */
void registerGroundAwareMaps();
}  // namespace mrpt::maps
