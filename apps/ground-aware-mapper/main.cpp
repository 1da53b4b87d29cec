// ground-aware-mapper: builds the ground-aware grid and the comparison maps
// from a rawlog. All the work is in libs/ground_mapper (gam::mapper::Mapper).
#include <default_config.h>
#include <gam/common/CommandLine.h>
#include <gam/common/Version.h>
#include <gam/mapper/Errors.h>
#include <gam/mapper/Mapper.h>
#include <mrpt/3rdparty/tclap/CmdLine.h>
#include <mrpt/maps/registerBaselineMaps.h>
#include <mrpt/maps/registerGroundAwareMaps.h>

#include <csignal>
#include <fstream>
#include <iostream>
#include <sstream>

namespace
{
constexpr const char* kApp = "ground-aware-mapper";

volatile std::sig_atomic_t gStop = 0;
extern "C" void onSignal(int) { gStop = 1; }

int fail(int code, std::string msg)
{
	for (auto& c : msg)
		if (c == '\n' || c == '\r') c = ' ';
	std::cerr << kApp << ": error: " << msg << std::endl;
	return code;
}
}  // namespace

int main(int argc, char** argv)
{
	// The map plugins this program offers: the product and the comparison maps.
	mrpt::maps::registerGroundAwareMaps();
	mrpt::maps::registerBaselineMaps();
	gam::mapper::MapperOptions o;
	try
	{
		TCLAP::CmdLine cmd(
			"Ground-aware 2D occupancy mapping from a rawlog (depth cameras, 2D scans). Writes, for every "
			"2D grid of the .ini, <label>.yaml/.pgm (ROS map_server), <label>.gridmap.gz and <label>.png, "
			"plus the elevation map, ground_planes.csv and timing.csv into --out.",
			' ', GAM_VERSION);
		TCLAP::ValueArg<std::string> aRawlog(
			"r", "rawlog", "input rawlog (either format)", false, "", "FILE.rawlog", cmd);
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
		if (aRawlog.getValue().empty()) return fail(2, "missing --rawlog FILE.rawlog (see --help)");
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
		o.stopRequested = &gStop;
		std::signal(SIGINT, onSignal);
		std::signal(SIGTERM, onSignal);
		gam::mapper::Mapper mapper(o);
		for (const auto& w : mapper.warnings()) std::cerr << kApp << ": warning: " << w << std::endl;
		if (!mapper.initialMapNote().empty()) std::cout << kApp << ": " << mapper.initialMapNote() << std::endl;
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
