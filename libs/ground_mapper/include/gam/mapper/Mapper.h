// Ground-aware mapping for MRPT
// The engine of ground-aware-mapper: builds a CMultiMetricMap from an .ini
// (MRPT's [map]-style sections, validated), streams a rawlog into it map by
// map with per-map timing, and writes the output files atomically.
#pragma once

#include <mrpt/config/CConfigFileBase.h>
#include <mrpt/maps/CMultiMetricMap.h>
#include <mrpt/maps/TMetricMapInitializer.h>

#include <gam/mapper/RawlogFrames.h>

#include <atomic>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

namespace gam::mapper
{
/** Bad command line or configuration (exit code 2). */
struct ConfigError : std::runtime_error
{
	using std::runtime_error::runtime_error;
};
/** Bad input data or output failure (exit code 1). */
struct RunError : std::runtime_error
{
	using std::runtime_error::runtime_error;
};

struct MapperOptions
{
	std::string rawlogPath;
	std::string outDir;
	std::string configText;             ///< the .ini contents
	std::string configName = "config";  ///< for messages
	std::string section = "map";
	bool localMap = false;
	int localCells = 600;
	size_t maxFrames = 0;  ///< 0 = all
	/** If set: a stock occupancy grid (`.gridmap`, `.gridmap.gz` or a ROS
	 * map_server `.yaml`; gam::maps::readStockGrid) that every 2D grid of the
	 * .ini starts from (its extent, resolution and cells; the .ini's options
	 * stay). A ground-aware grid takes it with loadFromStockGrid(). */
	std::string initialMap;
	/** > 0: after every N-th frame, the map_server maps (`<label>.yaml` + `.pgm`)
	 * of every 2D grid as they are after that frame, in
	 * `outDir/snapshots/NNNNNN/` (NNNNNN = frames inserted so far), plus
	 * `outDir/snapshots/index.csv`. Published with the other outputs. */
	size_t snapshotEvery = 0;
	/** The PNGs of the 2D grids get a 1 m scale bar and a legend (free,
	 * occupied, unknown, missing floor); ground-aware grids show their
	 * missing floor in orange. The map_server files are unchanged. */
	bool pngLegend = false;
	bool progress = true;
	/** If set, checked before every frame: true stops the run (RunError
	 * "interrupted"; nothing is published in outDir). For SIGINT/SIGTERM
	 * handlers (gam/mapper/StopSignal.h). */
	const std::atomic<bool>* stopRequested = nullptr;
};

/** One map of the .ini, in CMultiMetricMap order. */
struct MapSpec
{
	std::string iniName;  ///< the name as spelled in `<iniName>_count`
	unsigned index = 0;
	std::string prefix;     ///< `<section>_<iniName>_NN`
	std::string className;  ///< RTTI name
	std::string label;      ///< output file name stem
};

/** Parses and validates the map definitions in `section` (the same order and
 * sections as TSetOfMetricMapInitializers::loadFromConfigFile), rejecting
 * unknown map types, unknown keys / sections of this project's map classes,
 * out-of-range values and bad or duplicate labels. Throws ConfigError.
 * Keys in the sections of stock MRPT maps that their loader never read
 * (typos) are reported in `warnings`. */
void loadMapDefinitions(
	const mrpt::config::CConfigFileBase& ini, const std::string& section,
	mrpt::maps::TSetOfMetricMapInitializers& inits, std::vector<MapSpec>& specs,
	std::vector<std::string>* warnings = nullptr);

/** Creates the maps of `section` in `out`, checked as the mapper checks them
 * (loadMapDefinitions). For tools that need the maps of the mapper's .ini.
 * Throws ConfigError. */
void createMaps(const mrpt::config::CConfigFileBase& ini, const std::string& section, mrpt::maps::CMultiMetricMap& out);

/** The [sensor_poses] section: `LABEL = x y z yaw pitch roll` (metres,
 * degrees) per sensor label; the mapper gives those observations this
 * sensorPose instead of the rawlog's. Throws ConfigError for a malformed entry. */
std::map<std::string, mrpt::poses::CPose3D> readSensorPoses(
	const mrpt::config::CConfigFileBase& ini, const std::string& configName);

struct MapTiming
{
	std::string label, className;
	std::vector<double> totalMs;     ///< per frame (all frames)
	std::vector<double> ms3D, ms2D;  ///< the same, split by frame kind
	/** Per set of frames inserted together (the depth frames of several
	 * cameras at one pose, threads > 1): the wall time of the set [ms]. A
	 * frame of a set has as its time in totalMs its own share: its fusion,
	 * and its pipeline's stages, which may have run alongside another's. */
	std::vector<double> setMs;
	/** Median / 95th percentile over the 3D frames (over all frames if there are none). */
	double median() const;
	double p95() const;
};

struct RunSummary
{
	size_t frames = 0, frames3D = 0, frames2D = 0, framesWithoutOdometry = 0;
	size_t snapshots = 0;  ///< folders written under snapshots/ (MapperOptions::snapshotEvery)
	double seconds = 0;
	std::vector<MapTiming> maps;
	std::vector<std::string> files;  ///< written, relative to outDir
	std::vector<std::string> notes;  ///< per-map remarks (e.g. the sensor mount check)
	std::string text() const;
};

double percentile(std::vector<double> v, double p);

class Mapper
{
   public:
	/** Parses the configuration and creates the maps. Throws ConfigError. */
	explicit Mapper(const MapperOptions& opts);
	~Mapper();
	/** Runs over the rawlog and writes the outputs. Throws RunError. */
	RunSummary run();

	/** @name The run in steps, for frames that do not come from a rawlog (the
	 * live mode, runLive()). run() is begin(), insert() per frame, end().
	 * @{ */
	/** Creates DIR and the run's private temporary folder in it; the run's
	 * files are written there. Throws RunError. */
	void begin();
	/** Inserts one frame into every map: [sensor_poses], timing.csv,
	 * ground_planes.csv, the local window, --snapshot-every. Throws RunError. */
	void insert(Frame& fr);
	/** Inserts depth frames of different cameras taken at one robot pose
	 * (run() forms them when a ground-aware grid has threads > 1): into a
	 * ground-aware grid at once (insertObservations()), into the other maps
	 * one by one; every frame is recorded as insert() records it. */
	void insertSet(std::vector<Frame>& set);
	/** The outputs of every map as they are now, moved into DIR file by file
	 * (each write is a rename, so DIR never holds a part-written file); the
	 * run goes on. Returns the file names. Throws RunError. */
	std::vector<std::string> publishMapsNow();
	/** Writes every output and moves them into DIR; ends the run. The caller
	 * checks first that there was a frame. Throws RunError. */
	RunSummary end();
	/** Ends the run without writing anything (removes the temporary folder). */
	void abort();
	/** The summary of the run so far (frames, per-map timing). */
	const RunSummary& runSoFar() const;
	/** @} */

	mrpt::maps::CMultiMetricMap& maps() { return m_maps; }
	const std::vector<MapSpec>& specs() const { return m_specs; }
	/** Configuration warnings (printed by the app before running). */
	const std::vector<std::string>& warnings() const { return m_warnings; }
	/** What --initial-map loaded, and into which grids ("" without it). */
	const std::string& initialMapNote() const { return m_initialMapNote; }

   private:
	void writeMaps(const std::string& dir, std::vector<std::string>& files);
	void applySensorPose(Frame& fr) const;
	void countFrame(const Frame& fr, bool is3D);
	/** timing.csv, per-map timing and ground_planes.csv rows of map i for a frame just inserted. */
	void recordFrame(size_t i, const Frame& fr, bool is3D, double ms);
	/** After a frame or a set: --snapshot-every. */
	void afterFrames(const Frame& last);
	/** Whether `fr` joins `set` (same pose and time, another camera's depth frame). */
	bool joinsSet(const std::vector<Frame>& set, const Frame& fr) const;
	/** A ground-aware grid has threads > 1: run() forms sets of frames. */
	bool m_frameSets = false;
	/** The map_server maps of every 2D grid into `dir` (created). Throws std::runtime_error. */
	void writeSnapshot(const std::string& dir) const;
	MapperOptions m_opts;
	mrpt::maps::CMultiMetricMap m_maps;
	std::vector<MapSpec> m_specs;
	std::vector<std::string> m_warnings;
	std::string m_initialMapNote;
	void loadInitialMap();
	mrpt::poses::CPose3D m_lastPose;
	/** [sensor_poses] of the .ini: sensorPose per sensor label, replacing the
	 * rawlog's (gam-calibrate --write-ini writes it). */
	std::map<std::string, mrpt::poses::CPose3D> m_sensorPoses;
	struct RunState;
	std::unique_ptr<RunState> m_run;  ///< between begin() and end()
};

}  // namespace gam::mapper
