// Ground-aware mapping for MRPT -- ground-aware-nav-example: maps a simulated
// scene with a floor hole on the straight line from start to goal with the
// ground-aware grid and with the height-band baseline, plans on both with
// mrpt::nav::PlannerSimple2D and exports the ground-aware obstacles as the
// robot-frame CSimplePointsMap MRPT's reactive navigator consumes, and
// drives CReactiveNavigationSystem with them (simulated robot).
//
// usage: ground-aware-nav-example [--scene config/scenes/nav_hole.scene]
//            [--start 0,0] [--goal 4.5,0] [--robot-radius 0.3] [--out DIR]
//            [--no-noise] [--seed N] [--no-reactive] [--reactive-config FILE]
#include <gam/common/CommandLine.h>
#include <gam/common/Version.h>
#include <mrpt/3rdparty/tclap/CmdLine.h>

#include <cstdio>
#include <filesystem>
#include <iostream>
#include <sstream>

#include "NavExample.h"

namespace
{
mrpt::math::TPoint2D parseXY(const std::string& s, const char* what)
{
	std::istringstream is(s);
	double x, y;
	char comma;
	if (!(is >> x >> comma >> y) || comma != ',')
		throw std::invalid_argument(std::string("bad ") + what + " '" + s + "' (expected X,Y)");
	return {x, y};
}

/** The closest a trajectory comes to a hole [m]; `traj` gets its points (for the picture). */
double trajectoryToHoles(
	const gam::sim::Scene& scene, const std::vector<mrpt::math::TPose2D>& trajectory, gam::nav::PlanResult& traj)
{
	double minHole = 1e9;
	for (const auto& p : trajectory)
	{
		minHole = std::min(minHole, gam::nav::distanceToHoles(scene, p.x, p.y));
		traj.path.emplace_back(p.x, p.y);
	}
	return minHole;
}
}  // namespace

int main(int argc, char** argv)
{
	try
	{
		TCLAP::CmdLine cmd("ground-aware-nav-example", ' ', GAM_VERSION);
		TCLAP::ValueArg<std::string> argScene(
			"", "scene", "scene file", false, "config/scenes/nav_hole.scene", "FILE", cmd);
		TCLAP::ValueArg<std::string> argStart("", "start", "start X,Y [m]", false, "0,0", "X,Y", cmd);
		TCLAP::ValueArg<std::string> argGoal("", "goal", "goal X,Y [m]", false, "4.5,0", "X,Y", cmd);
		TCLAP::ValueArg<double> argRadius("", "robot-radius", "robot radius [m]", false, 0.3, "R", cmd);
		TCLAP::ValueArg<std::string> argOut(
			"", "out", "write pictures, grids and obstacle points here", false, "", "DIR", cmd);
		TCLAP::ValueArg<unsigned> argSeed("", "seed", "noise seed", false, 1, "N", cmd);
		TCLAP::SwitchArg argNoNoise("", "no-noise", "exact sensor", cmd);
		TCLAP::SwitchArg argNoReactive("", "no-reactive", "skip the CReactiveNavigationSystem runs", cmd);
		TCLAP::ValueArg<std::string> argReactiveCfg(
			"", "reactive-config", "base reactive navigator .ini", false, gam::nav::ReactiveOptions{}.baseConfig,
			"FILE", cmd);
		if (const int rc = gam::parseCommandLine(cmd, argc, argv, "ground-aware-nav-example"); rc >= 0) return rc;

		const auto sf = gam::sim::parseSceneFile(argScene.getValue());
		const auto start = parseXY(argStart.getValue(), "--start");
		const auto goal = parseXY(argGoal.getValue(), "--goal");

		gam::nav::NavMaps maps;
		gam::nav::MapOptions mo;
		mo.noise = !argNoNoise.getValue();
		mo.seed = argSeed.getValue();
		gam::nav::buildMaps(sf, mo, maps);
		std::cout << "mapped " << maps.robotPoses.size() << " frames (" << maps.framesWithGround
				  << " with a ground plane)\n";

		gam::nav::PlanOptions po;
		po.robotRadius = float(argRadius.getValue());
		const std::string out = argOut.getValue();
		if (!out.empty()) std::filesystem::create_directories(out);

		struct Item
		{
			const char* name;
			const mrpt::maps::COccupancyGridMap2D* grid;
		} items[] = {{"ground_aware", &maps.groundAware}, {"height_band", &maps.heightBand}};
		for (const auto& it : items)
		{
			const auto plan = gam::nav::planPath(*it.grid, start, goal, po);
			double minHole = 1e9;
			for (const auto& p : plan.path) minHole = std::min(minHole, gam::nav::distanceToHoles(sf.scene, p.x, p.y));
			char buf[300];
			if (plan.found)
				std::snprintf(
					buf, sizeof(buf),
					"%-13s path: %zu points, %.2f m, max deviation from the straight line %.2f m, "
					"closest to a hole %.2f m -> %s\n",
					it.name, plan.path.size(), plan.length, plan.maxDeviation, minHole,
					minHole == 0 ? "CROSSES the hole" : "goes around the hole");
			else
				std::snprintf(buf, sizeof(buf), "%-13s path: not found\n", it.name);
			std::cout << buf;
			if (!out.empty())
			{
				gam::nav::savePathPicture(*it.grid, plan, start, goal, out + "/" + it.name + "_path.png");
				it.grid->saveAsBitmapFile(out + "/" + it.name + ".png");
			}
		}

		// MRPT's reactive navigator: on the grids mapped beforehand (static), then
		// in closed loop, the grid built while the robot drives.
		if (!argNoReactive.getValue())
		{
			gam::nav::ReactiveOptions ro;
			ro.baseConfig = argReactiveCfg.getValue();
			ro.cacheDir = std::filesystem::temp_directory_path().string();
			gam::nav::ClosedLoopOptions co;
			co.reactive.baseConfig = ro.baseConfig;
			co.reactive.cacheDir = ro.cacheDir;
			co.reactive.maxTime = 60;
			co.plan = po;
			// the closed loop's planner radius comes from the navigator's footprint unless given
			if (!argRadius.isSet()) co.plan.robotRadius = 0;
			co.seed = mo.seed;
			gam::sim::SceneFile live = sf;
			live.kinect.noise = mo.noise;
			mrpt::maps::CGroundAwareOccupancyGrid gaLive;
			mrpt::maps::CHeightBandOccupancyGrid hbLive;
			struct LiveItem
			{
				const char* name;
				mrpt::maps::COccupancyGridMap2D* grid;
			} live_items[] = {{"ground_aware", &gaLive}, {"height_band", &hbLive}};
			for (const auto& it : live_items)
			{
				const auto& ref = maps.groundAware;  // the same extent as the mapped grids
				it.grid->setSize(ref.getXMin(), ref.getXMax(), ref.getYMin(), ref.getYMax(), ref.getResolution(), 0.5f);
				const auto r = gam::nav::runClosedLoopNavigation(live, *it.grid, {start.x, start.y, 0}, goal, co);
				gam::nav::PlanResult traj;
				const double minHole = trajectoryToHoles(sf.scene, r.trajectory, traj);
				char buf[400];
				std::snprintf(
					buf, sizeof(buf),
					"%-13s closed loop (mapping while driving, PlannerSimple2D waypoints, CReactiveNavigationSystem): "
					"%s after %.1f s, %zu frames, %d plans, closest to a hole %.2f m -> %s\n",
					it.name, r.reached ? "goal reached" : "goal NOT reached", r.seconds, r.frames, r.plans, minHole,
					minHole < ro.robotHalfSize ? "FOOTPRINT OVER the hole" : "avoided the hole");
				std::cout << buf;
				if (!out.empty())
					gam::nav::savePathPicture(*it.grid, traj, start, goal, out + "/" + it.name + "_closed_loop.png");
			}
			for (const auto& it : items)
			{
				const auto r = gam::nav::runReactiveNavigation(*it.grid, {start.x, start.y, 0}, goal, ro);
				gam::nav::PlanResult traj;
				const double minHole = trajectoryToHoles(sf.scene, r.trajectory, traj);
				char buf[300];
				std::snprintf(
					buf, sizeof(buf),
					"%-13s reactive (CReactiveNavigationSystem): %s, %s after %.1f s, closest to a "
					"hole %.2f m -> %s\n",
					it.name, r.reached ? "goal reached" : "goal NOT reached", r.endState.c_str(), r.seconds, minHole,
					minHole == 0 ? "DROVE OVER the hole" : "avoided the hole");
				std::cout << buf;
				if (!out.empty())
					gam::nav::savePathPicture(*it.grid, traj, start, goal, out + "/" + it.name + "_reactive.png");
			}
		}

		// Obstacles for CReactiveNavigationSystem, as seen from the start pose.
		const mrpt::poses::CPose2D robot(start.x, start.y, 0);
		const auto obstacles = gam::nav::obstaclePointsRobotFrame(maps.groundAware, robot);
		size_t inHole = 0;
		for (size_t i = 0; i < obstacles.size(); i++)
		{
			float x, y, z;
			obstacles.getPoint(i, x, y, z);
			double gx, gy;
			robot.composePoint(x, y, gx, gy);
			inHole += gam::nav::distanceToHoles(sf.scene, gx, gy) == 0;
		}
		std::cout << "obstacle points (robot frame, for CReactiveNavigationSystem): " << obstacles.size() << ", "
				  << inHole << " of them inside a hole\n";
		if (!out.empty())
		{
			obstacles.save2D_to_text_file(out + "/obstacles_robot_frame.txt");
			std::cout << "outputs in " << out << "\n";
		}
		return 0;
	}
	catch (const TCLAP::ArgException& e)
	{
		std::cerr << "ground-aware-nav-example: error: " << e.error() << " for " << e.argId() << std::endl;
		return 2;
	}
	catch (const std::exception& e)
	{
		std::cerr << "ground-aware-nav-example: error: " << e.what() << std::endl;
		return 1;
	}
}
