// Ground-aware mapping for MRPT -- gam-navbench (issue #29): closed-loop
// navigation over generated scenes, one run per seed and map; a thin
// command line over gam::navbench::runNavBench (NavBench.h).
//
// usage: gam-navbench --seeds A-B --out DIR [--maps ground_aware,paper,height_band,octomap]
//            [--jobs N] [--figure-scenes 3] [--write-scenes [--write-scenes-path M]] [--save-maps]
//            [--reactive-config FILE]
#include <gam/common/CommandLine.h>
#include <gam/common/Version.h>
#include <mrpt/3rdparty/tclap/CmdLine.h>

#include <chrono>
#include <filesystem>
#include <iostream>

#include "NavBench.h"

int main(int argc, char** argv)
{
	try
	{
		TCLAP::CmdLine cmd(
			"gam-navbench: closed-loop navigation benchmark over generated scenes (issue #29). For each seed and map, "
			"the walker drives from the scene's start to its goal while the map is built; falls, collisions, stuck "
			"and time-outs are judged on the ground truth. Writes DIR/runs.csv, DIR/table.md, DIR/trajectories.png "
			"and prints the table.",
			' ', GAM_VERSION);
		TCLAP::ValueArg<std::string> argSeeds("", "seeds", "seed range A-B (or one seed A)", true, "", "A-B", cmd);
		TCLAP::ValueArg<std::string> argOut("", "out", "output folder", true, "", "DIR", cmd);
		TCLAP::ValueArg<std::string> argMaps(
			"", "maps", "comma-separated maps", false, "ground_aware,paper,height_band,octomap", "LIST", cmd);
		TCLAP::ValueArg<int> argJobs("", "jobs", "runs in parallel (threads)", false, 1, "N", cmd);
		TCLAP::ValueArg<int> argFigure(
			"", "figure-scenes", "the first N seeds drawn in trajectories.png", false, 3, "N", cmd);
		TCLAP::SwitchArg argWrite("", "write-scenes", "also write DIR/scenes/seed_N.scene", cmd);
		TCLAP::ValueArg<double> argWritePath(
			"", "write-scenes-path",
			"with --write-scenes: each scene's path drives M m from the start toward the goal, a frame every 0.1 m "
			"(the held-out protocol of doc/benchmark.md: 1.5); 0 = the start pose alone (one depth frame)",
			false, 0.0, "M", cmd);
		TCLAP::SwitchArg argSaveMaps(
			"", "save-maps", "also write DIR/maps/seed_N_MAP.png: each run's map at its end with the trajectory", cmd);
		TCLAP::ValueArg<std::string> argReactiveCfg(
			"", "reactive-config", "base reactive navigator .ini", false, gam::nav::ReactiveOptions{}.baseConfig,
			"FILE", cmd);
		if (const int rc = gam::parseCommandLine(cmd, argc, argv, "gam-navbench"); rc >= 0) return rc;

		gam::navbench::NavBenchOptions o;
		try
		{
			gam::navbench::parseSeedRange(argSeeds.getValue(), o.firstSeed, o.lastSeed);
			o.maps = gam::navbench::parseMapList(argMaps.getValue());
			if (argJobs.getValue() < 1 || argJobs.getValue() > 64)
				throw std::invalid_argument("--jobs must be in 1..64");
			if (argFigure.getValue() < 0) throw std::invalid_argument("--figure-scenes must be >= 0");
			if (!(argWritePath.getValue() >= 0) || argWritePath.getValue() > 100)
				throw std::invalid_argument("--write-scenes-path must be in 0..100 m");
			if (argWritePath.getValue() > 0 && !argWrite.getValue())
				throw std::invalid_argument("--write-scenes-path needs --write-scenes");
			if (!std::filesystem::exists(argReactiveCfg.getValue()))
				throw std::invalid_argument("--reactive-config: cannot read " + argReactiveCfg.getValue());
		}
		catch (const std::invalid_argument& e)
		{
			std::cerr << "gam-navbench: error: " << e.what() << std::endl;
			return 2;
		}
		o.outDir = argOut.getValue();
		o.jobs = argJobs.getValue();
		o.figureScenes = argFigure.getValue();
		o.writeScenes = argWrite.getValue();
		o.writeScenesPath = argWritePath.getValue();
		o.saveMaps = argSaveMaps.getValue();
		o.bench.reactiveConfig = argReactiveCfg.getValue();
		o.bench.cacheDir = std::filesystem::temp_directory_path().string();
		const auto t0 = std::chrono::steady_clock::now();
		const std::string table = gam::navbench::runNavBench(o, std::cerr);
		const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
		std::cout << "seeds " << o.firstSeed << "-" << o.lastSeed << ", " << o.maps.size() << " maps, "
				  << (o.lastSeed - o.firstSeed + 1) * o.maps.size() << " runs in " << std::lround(wall) << " s wall ("
				  << o.jobs << " job" << (o.jobs > 1 ? "s" : "") << ")\n\n"
				  << table;
		return 0;
	}
	catch (const TCLAP::ArgException& e)
	{
		std::cerr << "gam-navbench: error: " << e.error() << " for " << e.argId() << std::endl;
		return 2;
	}
	catch (const std::exception& e)
	{
		std::cerr << "gam-navbench: error: " << e.what() << std::endl;
		return 1;
	}
}
