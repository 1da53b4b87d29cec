// Ground-aware mapping for MRPT
#pragma once

namespace mrpt::maps
{
/** Registers the comparison maps CHeightBandOccupancyGrid (heightBandGrid) and
 * COctoMapGrid2D (octoMapGrid) with MRPT's RTTI (deserialization) and map-type
 * (.ini) registries, and their traits (gam/maps/MapRegistry.h). This already
 * happens when the library is loaded; an executable that links the library but
 * uses none of its symbols calls this so that `--as-needed` linking keeps it. */
void registerBaselineMaps();
}  // namespace mrpt::maps
