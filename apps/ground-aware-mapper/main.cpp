// ground-aware-mapper: builds the ground-aware grid and the comparison maps
// from a rawlog, or live from MRPT sensor drivers (--live). All the work is in
// libs/ground_mapper (gam::mapper::Mapper, gam::mapper::runLive).
//
// Built twice: ground-aware-mapper (without GAM_HAVE_LIVE) and
// ground-aware-mapper-live (with it, linked with MRPT's sensor drivers). The
// first hands a --live command line over to the second (exec, same process):
// mrpt-hwdrivers and what it loads (OpenCV, ffmpeg, wxWidgets, OpenNI2) cost
// every run ~0.6 s of start-up and ~47 MB of memory, which the offline mode
// does not need.
#include <default_config.h>
#include <gam/common/CommandLine.h>
#include <gam/common/Version.h>
#include <gam/mapper/Errors.h>
#include <gam/mapper/Mapper.h>
#include <gam/mapper/StopSignal.h>
#ifdef GAM_HAVE_LIVE
#include <gam/mapper/Live.h>
#endif
#include <mrpt/3rdparty/tclap/CmdLine.h>
#include <mrpt/maps/registerBaselineMaps.h>
#include <mrpt/maps/registerGroundAwareMaps.h>
#include <mrpt/system/os.h>

#include <unistd.h>

#include <cerrno>
#include <climits>
#include <cstring>
#include <fstream>
#include <iostream>
#include <sstream>

namespace
{
constexpr const char* kApp = "ground-aware-mapper";

int fail(int code, std::string msg)
{
	for (auto& c : msg)
		if (c == '\n' || c == '\r') c = ' ';
	std::cerr << kApp << ": error: " << msg << std::endl;
	return code;
}
#ifndef GAM_HAVE_LIVE
/** --live: runs ground-aware-mapper-live, installed beside this program, with
 * the same arguments (execv: same process, so signals and exit code are its). */
int execLiveProgram(char** argv)
{
	char self[PATH_MAX];
	const ssize_t n = readlink("/proc/self/exe", self, sizeof(self) - 1);
	if (n <= 0) return fail(1, "--live: cannot find this program's folder (/proc/self/exe)");
	self[n] = 0;
	std::string live(self);
	live = live.substr(0, live.rfind('/') + 1) + "ground-aware-mapper-live";
	if (access(live.c_str(), X_OK) != 0)
		return fail(
			2, "--live: this build has no live mode (" + live +
				   " is missing); it needs MRPT's sensor drivers (Debian: libmrpt-hwdrivers-dev, in "
				   "scripts/install-deps.sh all) and a rebuild");
	execv(live.c_str(), argv);
	return fail(1, "--live: cannot start " + live + ": " + std::strerror(errno));
}
#endif
}  // namespace

int main(int argc, char** argv)
{
#ifndef GAM_HAVE_LIVE
	for (int i = 1; i < argc; i++)
		if (std::strcmp(argv[i], "--live") == 0 || std::strncmp(argv[i], "--live=", 7) == 0)
			return execLiveProgram(argv);
#endif
	// The map plugins this program offers: the product and the comparison maps.
	mrpt::maps::registerGroundAwareMaps();
	mrpt::maps::registerBaselineMaps();
	gam::mapper::MapperOptions o;
	std::string livePath;
#ifdef GAM_HAVE_LIVE
	gam::mapper::LiveOptions live;
#endif
	try
	{
		TCLAP::CmdLine cmd(
			"Ground-aware 2D occupancy mapping from a rawlog or live from MRPT sensor drivers (depth cameras, 2D "
			"scans). Writes, for every 2D grid of the .ini, <label>.yaml/.pgm (ROS map_server), <label>.gridmap.gz "
			"and <label>.png, plus the elevation map, ground_planes.csv, ground_patches.csv and timing.csv into --out.",
			' ', GAM_VERSION);
		TCLAP::ValueArg<std::string> aRawlog(
			"r", "rawlog", "input rawlog (either format)", false, "", "FILE.rawlog", cmd);
		TCLAP::ValueArg<std::string> aLive(
			"", "live",
			"map live from the sensors of SENSORS.ini (rawlog-grabber's format: [global] plus one section per "
			"sensor with driver = CLASS, e.g. COpenNI2Sensor, and process_rate = HZ) until Ctrl-C / SIGTERM, "
			"--max-frames or --max-seconds; instead of --rawlog",
			false, "", "SENSORS.ini", cmd);
		TCLAP::ValueArg<double> aSnapshotSeconds(
			"", "snapshot-seconds",
			"(--live) every S seconds, write the maps' outputs into --out (each file replaced at once); 0 = only "
			"at the end",
			false, 10, "S", cmd);
		TCLAP::ValueArg<double> aMaxSeconds(
			"", "max-seconds", "(--live) stop after S seconds of mapping (0 = until Ctrl-C)", false, 0, "S", cmd);
		TCLAP::ValueArg<std::string> aRecord(
			"", "record", "(--live) also write every observation received into this rawlog", false, "", "FILE.rawlog",
			cmd);
		TCLAP::ValueArg<std::string> aPlugins(
			"p", "plugins",
			"load these modules first (comma-separated .so paths, as rawlog-grabber -p): more sensor drivers for "
			"--live, or map classes",
			false, "", "A.so[,B.so]", cmd);
		TCLAP::ValueArg<std::string> aOut("o", "out", "output directory (created if missing)", false, "", "DIR", cmd);
		TCLAP::ValueArg<std::string> aConfig(
			"c", "config", "map configuration (.ini); default: the embedded config/ground-aware-mapper.ini", false, "",
			"FILE.ini", cmd);
		TCLAP::ValueArg<std::string> aSection(
			"s", "section", "section of the .ini with the <map>_count keys", false, "map", "NAME", cmd);
		TCLAP::ValueArg<std::string> aInitial(
			"", "initial-map",
			"start every 2D grid that can from a stock occupancy grid: .gridmap / .gridmap.gz (a serialized "
			"COccupancyGridMap2D or subclass) or a ROS map_server .yaml; its extent, resolution and cells "
			"(the .ini's options stay)",
			false, "", "FILE", cmd);
		TCLAP::SwitchArg aPrint("", "print-default-config", "print the embedded default .ini and exit", cmd);
		TCLAP::SwitchArg aLocal(
			"", "local-map", "robot-centred local maps: every 2D grid is kept as a window that follows the robot", cmd);
		TCLAP::ValueArg<int> aLocalCells(
			"", "local-size-cells", "side of the local window in cells (with --local-map)", false, 600, "N", cmd);
		TCLAP::ValueArg<long> aMaxFrames("n", "max-frames", "stop after N frames (0 = all)", false, 0, "N", cmd);
		TCLAP::ValueArg<long> aSnapshotEvery(
			"", "snapshot-every",
			"after every N-th frame, write the map_server maps (<label>.yaml/.pgm) of every 2D grid into "
			"DIR/snapshots/NNNNNN/ (NNNNNN = frames so far; index in DIR/snapshots/index.csv); 0 = none",
			false, 0, "N", cmd);
		TCLAP::SwitchArg aPngLegend(
			"", "png-legend",
			"PNGs with a 1 m scale bar and a legend (free, occupied, unknown, missing floor; missing floor in orange)",
			cmd);
		TCLAP::SwitchArg aQuiet("q", "quiet", "no progress line on stderr", cmd);
		if (const int rc = gam::parseCommandLine(cmd, argc, argv, "ground-aware-mapper"); rc >= 0) return rc;

		if (aPrint.getValue())
		{
			std::cout << kDefaultConfigIni << std::flush;
			return 0;
		}
		livePath = aLive.getValue();
		if (aRawlog.getValue().empty() && livePath.empty())
			return fail(2, "missing --rawlog FILE.rawlog or --live SENSORS.ini (see --help)");
		if (!aRawlog.getValue().empty() && !livePath.empty()) return fail(2, "--rawlog and --live exclude each other");
		if (livePath.empty() && (aSnapshotSeconds.isSet() || aMaxSeconds.isSet() || aRecord.isSet()))
			return fail(2, "--snapshot-seconds, --max-seconds and --record go with --live");
#ifdef GAM_HAVE_LIVE
		if (!(aSnapshotSeconds.getValue() >= 0) || !(aMaxSeconds.getValue() >= 0))
			return fail(2, "--snapshot-seconds and --max-seconds must be >= 0");
		live.sensorsIniPath = livePath;
		live.snapshotSeconds = aSnapshotSeconds.getValue();
		live.maxSeconds = aMaxSeconds.getValue();
		live.maxFrames = size_t(std::max(0L, aMaxFrames.getValue()));
		live.recordPath = aRecord.getValue();
		live.progress = !aQuiet.getValue();
#else
		if (!livePath.empty()) return fail(2, "--live: not handed over to ground-aware-mapper-live");
#endif
		if (!aPlugins.getValue().empty())
		{
			std::string errs;
			if (!mrpt::system::loadPluginModules(aPlugins.getValue(), errs))
				return fail(2, "--plugins " + aPlugins.getValue() + ": " + gam::mapper::conciseError(errs));
		}
		if (aOut.getValue().empty()) return fail(2, "missing --out DIR (see --help)");
		if (aMaxFrames.getValue() < 0) return fail(2, "--max-frames must be >= 0");
		if (aSnapshotEvery.getValue() < 0 || aSnapshotEvery.getValue() > 1000000)
			return fail(2, "--snapshot-every must be in [0, 1000000]");
		o.rawlogPath = aRawlog.getValue();
		o.outDir = aOut.getValue();
		o.section = aSection.getValue();
		o.localMap = aLocal.getValue();
		o.localCells = aLocalCells.getValue();
		o.maxFrames = size_t(aMaxFrames.getValue());
		o.initialMap = aInitial.getValue();
		o.snapshotEvery = size_t(aSnapshotEvery.getValue());
		o.pngLegend = aPngLegend.getValue();
		o.progress = !aQuiet.getValue();
		if (aConfig.getValue().empty())
		{
			o.configText = kDefaultConfigIni;
			o.configName = "embedded default config";
		}
		else
		{
			std::ifstream f(aConfig.getValue(), std::ios::binary);
			if (!f) return fail(2, "cannot read config file " + aConfig.getValue());
			std::ostringstream ss;
			ss << f.rdbuf();
			o.configText = ss.str();
			o.configName = aConfig.getValue();
		}
	}
	catch (TCLAP::ArgException& e)
	{
		return fail(2, e.argId() + ": " + e.error() + " (see --help)");
	}

	try
	{
		// The handlers only set a flag; both loops poll it. Offline, Ctrl-C
		// abandons the run; live, it is the normal end: the maps are saved.
		gam::mapper::installStopSignalHandlers();
		o.stopRequested = &gam::mapper::stopSignalFlag();
		gam::mapper::Mapper mapper(o);
		for (const auto& w : mapper.warnings()) std::cerr << kApp << ": warning: " << w << std::endl;
		if (!mapper.initialMapNote().empty()) std::cout << kApp << ": " << mapper.initialMapNote() << std::endl;
#ifdef GAM_HAVE_LIVE
		if (!livePath.empty())
		{
			const auto ls = gam::mapper::runLive(mapper, live, gam::mapper::stopSignalFlag());
			std::cout << kApp << ": " << ls.text() << "outputs: " << ls.run.files.size() << " files in " << o.outDir
					  << std::endl;
			if (ls.sensorFailed) return fail(1, ls.stopReason + " (the maps so far were written to " + o.outDir + ")");
			return 0;
		}
#endif
		const auto s = mapper.run();
		std::cout << kApp << ": " << s.text() << "outputs: " << s.files.size() << " files in " << o.outDir << std::endl;
		return 0;
	}
	catch (const gam::mapper::ConfigError& e)
	{
		return fail(2, e.what());
	}
	catch (const gam::mapper::RunError& e)
	{
		return fail(1, e.what());
	}
	catch (const std::exception& e)
	{
		return fail(1, gam::mapper::conciseError(e.what()));
	}
}
