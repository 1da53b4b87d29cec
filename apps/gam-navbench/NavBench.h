// Ground-aware mapping for MRPT -- gam-navbench (issue #29): the closed-loop
// navigation benchmark over generated scenes (library part, used by the
// gam-navbench app and tests/nav).
//
// For each seed, gam::sim::generateScene(seed) gives a scene with a start, a
// goal and a hazard on the straight line between them; for each map (the
// mapper's default .ini: ground_aware, the paper's method as gam-ablation-ini
// defines it, height_band, octomap) gam::nav::runClosedLoopNavigation() drives
// the walker from the start to the goal while the map is built from its own
// simulated frames. Each run is judged on the ground truth, step by step
// (every 0.05 s of simulated time), with the walker's footprint: the nav
// example's square of half side ReactiveOptions::robotHalfSize (0.25 m) at the
// TRUE pose, turned with the heading; a GT cell is under it if its centre is.
//  * fall: a drop cell (hole, outlet, step, stairwell) under the footprint;
//  * collision: an obstacle cell (walls, boxes, tables, cable protectors, the
//    people where they are in that frame: gam::sim::FrameGroundTruth);
//  * stuck: the path distance to the goal on the ground truth has not dropped
//    by stuckProgress in stuckSeconds, or the navigator gave up (NAV_ERROR);
//  * time-out: none of these and not arrived by the time limit;
//  * arrival: the run ended with the true pose within goalTolerance of the goal.
// A fall or a collision ends the run (the walker tipped or hit something).
#pragma once

#include <mrpt/maps/CMultiMetricMap.h>
#include <mrpt/maps/COccupancyGridMap2D.h>
#include <mrpt/math/TPose2D.h>

#include <iosfwd>
#include <memory>
#include <string>
#include <vector>

#include "NavExample.h"
#include "gam/sim/SceneGenerator.h"

namespace gam::navbench
{
/** The benchmark's maps, in table order: ground_aware, paper, height_band, octomap. */
const std::vector<std::string>& mapNames();

/** The keys the `paper` map sets in the ground-aware grid's _groundOpts: the
 * `paper` row of rawlog_tools/gam-ablation-ini (the paper's method as printed). */
const std::vector<std::pair<std::string, std::string>>& paperOverrides();

/** The mapper's default .ini (config/ground-aware-mapper.ini, embedded). */
const char* defaultMapperIni();

/** One map of the benchmark, made from `iniText` (the mapper's .ini) as
 * ground-aware-mapper makes it (gam::mapper::createMaps), with only that map
 * and its extent set to `extent`'s. */
struct BenchMap
{
	mrpt::maps::CMultiMetricMap multi;
	mrpt::maps::COccupancyGridMap2D* grid = nullptr;  ///< multi's only map
};
std::unique_ptr<BenchMap> makeMap(
	const std::string& map, const gam::sim::GridSpec& extent, const std::string& iniText = defaultMapperIni());

/** The ground-truth cells under the walker's footprint: the square of half
 * side `halfSize` centred on (x, y) and turned by `yaw`; a cell counts if its
 * centre is inside or on the square. Geometric labels (seen or not). */
struct FootprintHit
{
	int dropCells = 0, obstacleCells = 0;
	int dropObject = 0, obstacleObject = 0;  ///< the object of the first such cell
};
FootprintHit footprintOver(const gam::sim::GroundTruthGrid& gt, double x, double y, double yaw, double halfSize);

struct BenchOptions
{
	std::string reactiveConfig = gam::nav::ReactiveOptions{}.baseConfig;
	std::string cacheDir = "/tmp";  ///< PTG look-up tables
	/** Arrival: the true pose this close to the goal when the run ends [m]
	 * (the navigator's targetAllowedDistance 0.3 m plus 0.1 m, the closed
	 * loop's own `reached` rule). */
	double goalTolerance = 0.4;
	double stuckSeconds = 15;    ///< no progress for this long = stuck [s]
	double stuckProgress = 0.2;  ///< progress = path distance to the goal down by this [m]
	/** Time limit = timeBase + timePerMetre * the ground-truth path length
	 * (6 s/m = three times the walker's 0.5 m/s). */
	double timeBase = 30, timePerMetre = 6;
	/** PlannerSimple2D's robot radius [m]; 0: from the navigator's footprint
	 * (gam::nav::plannerRadiusForFootprint of the half side grown by its
	 * margin: 0.375 m on 5 cm cells, ceil() = 8 cells). */
	double planRadius = 0;
	/** If set: DIR/seed_<N>_<map>.png, the map at the end with the trajectory
	 * (red), start (green) and goal (blue), and DIR/seed_<N>_<map>_trajectory.csv
	 * (t, x, y, phi of the true pose every simulation step). */
	std::string mapPictureDir;
};

struct RunResult
{
	unsigned seed = 0;
	std::string map;
	std::string outcome;  ///< arrived, fall, collision, stuck, timeout
	bool arrived = false, fell = false, collided = false, stuck = false, timedOut = false;
	double seconds = 0;        ///< simulated time of the run [s]
	double pathLength = 0;     ///< of the true trajectory [m]
	double finalDistance = 0;  ///< true pose to goal at the end [m]
	double gtPathLength = 0;   ///< shortest ground-truth path (GeneratorOptions::walkerRadius 0.45 m) [m]
	int hitObject = 0;         ///< the object fallen into or hit (0: none)
	std::string hitName;
	std::string endState;  ///< the navigator's state at the end
	std::string lineHazard;
	size_t frames = 0;
	int plans = 0, failedPlans = 0;
	double turningSeconds = 0;
	int partialPlans = 0, backups = 0, planFollows = 0;  ///< see gam::nav::ClosedLoopResult
	double wallSeconds = 0;
	std::vector<mrpt::math::TPose2D> trajectory;
};

/** One closed-loop run of `map` on the generated scene. */
RunResult runOne(const gam::sim::GeneratedScene& g, const std::string& map, const BenchOptions& o = {});

/** The Markdown table, one row per map (in `maps` order):
 * `| map | arrivals | falls | collisions | stuck | median time to goal [s] | median path [m] |`;
 * arrivals = arrived/runs, falls, collisions and stuck = runs ending so,
 * medians over the arrived runs ("-" if none). */
std::string markdownTable(const std::vector<RunResult>& runs, const std::vector<std::string>& maps);

std::string csvHeader();
std::string csvRow(const RunResult& r);

/** PNG: one panel per scene, its static ground truth (free white, obstacle
 * black, drop orange, people's crossing paths grey) and the trajectory of
 * each map's run (colours in the legend), start and goal marked. */
void drawTrajectories(
	const std::vector<const gam::sim::GeneratedScene*>& scenes, const std::vector<RunResult>& runs,
	const std::vector<std::string>& maps, const std::string& file, int scale = 4);

/** "A-B" or "A" (A <= B, both >= 0); throws std::invalid_argument. */
void parseSeedRange(const std::string& s, unsigned& first, unsigned& last);
/** "ground_aware,octomap" -> names checked against mapNames(); throws std::invalid_argument. */
std::vector<std::string> parseMapList(const std::string& s);

struct NavBenchOptions
{
	unsigned firstSeed = 1, lastSeed = 1;
	std::vector<std::string> maps = mapNames();
	std::string outDir;
	int jobs = 1;              ///< runs in parallel (threads)
	int figureScenes = 3;      ///< the first seeds drawn in trajectories.png
	bool writeScenes = false;  ///< DIR/scenes/seed_N.scene
	/** > 0: the written scenes drive this far from the start toward the goal,
	 * a frame every 0.1 m (the held-out protocol: 1.5); 0: the start pose. */
	double writeScenesPath = 0;
	bool saveMaps = false;  ///< DIR/maps/seed_N_<map>.png (BenchOptions::mapPictureDir)
	BenchOptions bench;
};

/** Runs every seed x map, writes DIR/runs.csv, DIR/table.md and
 * DIR/trajectories.png, prints one progress line per run to `progress`, and
 * returns the table. Throws on bad options or unwritable outputs. */
std::string runNavBench(const NavBenchOptions& o, std::ostream& progress);

}  // namespace gam::navbench
