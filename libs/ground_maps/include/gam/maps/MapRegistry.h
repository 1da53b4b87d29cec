// Ground-aware mapping for MRPT
// What tools need to know about a map class, declared by the library that
// defines the class: the .ini sections and keys it reads, how its outputs are
// written, its per-frame stage timings, its ground plane, and how it keeps a
// robot-centred window. ground-aware-mapper (and any other tool) looks the
// traits up by the map's MRPT class, so it names no map class itself: a new
// map class registers its traits next to MAP_DEFINITION_REGISTER and touches
// no tool.
#pragma once

#include <mrpt/maps/CMetricMap.h>
#include <mrpt/rtti/CObject.h>

#include <functional>
#include <string>
#include <vector>

namespace mrpt::maps
{
class COccupancyGridMap2D;
}

namespace gam::maps
{
/** A sub-section `<prefix><suffix>` of a map and the keys it accepts (empty =
 * any key: an MRPT options struct, whose unread keys are reported apart). */
struct IniSection
{
	std::string suffix;
	std::vector<std::string> keys;
};

/** Where and how a map's outputs are written. */
struct OutputContext
{
	std::string dir;                ///< folder (exists)
	std::string label;              ///< file name stem
	bool localMap = false;          ///< robot-centred window mode
	double robotX = 0, robotY = 0;  ///< last robot position (map frame)
	int localCells = 600;           ///< window size [cells]
	bool pngLegend = false;         ///< PNGs with a 1 m scale bar and a legend
};

/** Ground plane of the last depth frame, for ground_planes.csv. */
struct GroundPlaneRecord
{
	bool found = false;
	double a = 0, b = 0, c = 0, d = 0;  ///< a x + b y + c z + d = 0
	size_t nodes = 0;
	std::string status;
	/** The sensor mount this frame's floor says (see gam::MountMonitor). */
	bool mount_measured = false;
	double mount_z = 0, mount_pitch_deg = 0, mount_roll_deg = 0;
	bool mount_alarm = false;
	/** The frame's ramp patches (the tree's planes after the ground) and the
	 * patches of earlier frames that judged it too (patch_memory). */
	struct Patch
	{
		double a = 0, b = 0, c = 1, d = 0;  ///< a x + b y + c z + d = 0 (map frame)
		size_t nodes = 0;
		bool remembered = false;
	};
	std::vector<Patch> patches;
};

using StageSink = std::function<void(const char* stage, double ms)>;

struct MapTraits
{
	/** MRPT RTTI name, e.g. "mrpt::maps::CGroundAwareOccupancyGrid". */
	std::string className;
	/** The sections the class reads. Non-empty = a class of this project: any
	 * other sub-section or key is an error (for stock MRPT maps, a warning). */
	std::vector<IniSection> sections;
	/** Writes the outputs of `map` as files `<dir>/<label>*` and appends their
	 * names (relative to dir) to `files`. Throws std::runtime_error on I/O errors. */
	std::function<void(mrpt::maps::CMetricMap& map, const OutputContext& ctx, std::vector<std::string>& files)>
		writeOutputs;
	/** After an insertion (`depthFrame`: of a 3D observation): the stage times
	 * of that insertion, if the class measures any. */
	std::function<void(const mrpt::maps::CMetricMap& map, bool depthFrame, const StageSink& sink)> stageTimes;
	/** After a depth frame: its ground plane, if the class finds one. */
	std::function<bool(const mrpt::maps::CMetricMap& map, GroundPlaneRecord& out)> lastGroundPlane;
	/** After a run: lines for the mapper's summary (empty: nothing to say). */
	std::function<std::string(const mrpt::maps::CMetricMap& map)> runNote;
	/** Local-map mode: keep only an n x n cell window centred on (x, y). */
	std::function<void(mrpt::maps::CMetricMap& map, double x, double y, int cells)> keepWindow;
	/** `--initial-map`: the map starts from a stock occupancy grid (its extent,
	 * resolution and cells). Unset: the class cannot start from a grid (e.g.
	 * a projection of a 3D map, which the next frame would redraw). */
	std::function<void(mrpt::maps::CMetricMap& map, const mrpt::maps::COccupancyGridMap2D& stock)> startFromGrid;
};

/** Adds (or replaces) the traits of t.className. Called when a map library loads. */
void registerMapTraits(MapTraits t);

/** The traits of `cls` or of its nearest base class that has traits; nullptr
 * if none (a stock MRPT map with no registered base). */
const MapTraits* findMapTraits(const mrpt::rtti::TRuntimeClassId* cls);
const MapTraits* findMapTraits(const mrpt::maps::CMetricMap& map);
/** Exact class name only. */
const MapTraits* findMapTraits(const std::string& className);

/** The keys of a 2D grid map's `_creationOpts`: the extent and resolution,
 * MRPT's generic initializer switches, and the tools' output `label`. */
std::vector<std::string> gridCreationKeys();

/** Outputs of any COccupancyGridMap2D (also of derived classes): ROS map_server
 * `<label>.yaml` + `.pgm`, `<label>.gridmap.gz` (stock MRPT) and `<label>.png`;
 * in local-map mode cropped to the window first. */
void writeGridOutputs(mrpt::maps::CMetricMap& map, const OutputContext& ctx, std::vector<std::string>& files);

/** startFromGrid of a COccupancyGridMap2D: copyGridCells (GridIO.h). */
void startGridFromStock(mrpt::maps::CMetricMap& map, const mrpt::maps::COccupancyGridMap2D& stock);

/** keepWindow of a COccupancyGridMap2D (see GridIO.h recentreGrid). */
void keepGridWindow(mrpt::maps::CMetricMap& map, double x, double y, int cells);

}  // namespace gam::maps
