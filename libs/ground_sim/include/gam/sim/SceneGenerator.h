// Ground-aware mapping for MRPT -- scene simulator: seeded scene generator
// (issue #29, navigation benchmark).
//
// generateScene(seed) draws a corridor (optionally widened into a room) with
// walls, one hazard ON the straight line from the start to the goal (a hole,
// a floor outlet, a downward step, a stairwell, a cable protector, a small box
// or a table, cycling with the seed so that any 7 consecutive seeds have each
// kind once), 1-3 further hazards and ramps elsewhere, and 0-2 people who
// cross the corridor ahead of the walker (moving boxes, the scene model's
// `frames=` / `to=` motion), timed so that a walker of at most 0.5 m/s sees
// them cross and leave but cannot meet them. A layout is kept only if the straight start-goal line meets a
// hazard and a path exists around it on the ground truth (obstacle and drop
// cells grown by the walker's radius, people left out: they move); otherwise
// the next layout of the same random stream is drawn. The scene is made as
// scene-file text and parsed by parseScene(), so the text written by
// writeGeneratedScene() is exactly the scene used.
//
// Pure code, no I/O except writeGeneratedScene().
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "gam/sim/GroundTruth.h"
#include "gam/sim/SceneFile.h"

namespace gam::sim
{
enum class HazardKind : int
{
	Hole = 0,        ///< a pit 0.4-0.8 m wide, 0.2-0.6 m deep
	Outlet,          ///< a recessed floor outlet 8-25 cm, 5-10 cm deep
	StepDown,        ///< a sunken floor area from one wall, 10-20 cm down
	Stairwell,       ///< stairs_down from one wall, 2-4 steps
	CableProtector,  ///< 3-5 cm high, across part of the corridor
	SmallBox,        ///< 5-15 cm high
	Table,           ///< 0.45-0.75 m high (overhang: the user cannot pass under)
	Ramp,            ///< traversable 3-6 deg up, plateau, down (its raised sides are steps)
	Person           ///< a 0.4 x 0.3 x 1.7 m box crossing the corridor at 0.8-1.3 m/s
};
constexpr int kHazardKindCount = 9;
const char* hazardKindName(HazardKind k);

struct GeneratedHazard
{
	HazardKind kind = HazardKind::Hole;
	int objectId = 0;
	bool onLine = false;  ///< the hazard placed on the straight start-goal line
};

struct GeneratorOptions
{
	/** The path check grows the ground truth's obstacle and drop cells by this
	 * [m]: the walker's 0.5 m square footprint turning (0.354 m) plus 0.1 m,
	 * so the way around is at least 0.9 m wide (the nav example's planner
	 * radius is 0.30 m). */
	double walkerRadius = 0.45;
	double resolution = 0.05;  ///< ground-truth cell [m]
	int maxAttempts = 200;     ///< layouts drawn before giving up (throws)
};

struct GeneratedScene
{
	unsigned seed = 0;
	int attempts = 0;  ///< layouts drawn for this seed (1 = the first was kept)
	std::string text;  ///< the scene in the scene-file format (doc/simulator.md)
	SceneFile file;    ///< parseScene(text)
	Eigen::Vector2d start = Eigen::Vector2d::Zero(), goal = Eigen::Vector2d::Zero();
	double startYaw = 0;  ///< [rad] facing the goal
	std::vector<GeneratedHazard> hazards;
	HazardKind lineHazard = HazardKind::Hole;
	int lineHazardId = 0;
	/** Distance from the start along the straight line to its first hazard cell [m]. */
	double lineHazardAt = 0;
	/** Shortest 8-connected path on the ground truth grown by walkerRadius [m]. */
	double gtPathLength = 0;
};

/** The scene of `seed` (deterministic: the same seed gives the same text).
 * Throws std::runtime_error if no layout passes the checks in maxAttempts. */
GeneratedScene generateScene(unsigned seed, const GeneratorOptions& opts = {});

/** Writes g.text (a scene file gam-simulate and the nav example read; the
 * start, goal and hazards are in its header comments), with
 * approachMetres > 0 as withApproachPath(g, approachMetres). Throws on
 * failure. */
void writeGeneratedScene(const GeneratedScene& g, const std::string& file, double approachMetres = 0);

/** g.text with its path line (the start pose alone: one depth frame) replaced
 * by a drive of `metres` from the start straight toward the goal, facing it,
 * in round(metres / spacing) equal steps of about `spacing` (the ends are
 * written to 1 mm): the held-out protocol of doc/benchmark.md (1.5 m, 0.1 m:
 * 16 frames). Throws std::invalid_argument unless metres > 0
 * and spacing > 0, or if the text has no such path line. */
std::string withApproachPath(const GeneratedScene& g, double metres, double spacing = 0.1);

/** The scene without the objects that appear, leave or move (people). */
Scene staticPart(const Scene& scene);

/** Ground truth of the static part of sf.scene on sf.grid. */
GroundTruthGrid staticGroundTruth(const SceneFile& sf);

/** Cells blocked for a walker of `radius`: every cell whose centre is within
 * `radius` of the centre of an obstacle or drop cell (geometric labels). */
std::vector<uint8_t> blockedCells(const GroundTruthGrid& gt, double radius);

struct GridPath
{
	bool found = false;
	double length = 0;  ///< [m], 8-connected steps of 1 or sqrt(2) cells
};

/** Shortest 8-connected path from a to b over the cells not blocked for a
 * walker of `radius` (blockedCells). */
GridPath shortestFreePath(const GroundTruthGrid& gt, const Eigen::Vector2d& a, const Eigen::Vector2d& b, double radius);

/** Path distance [m] of every cell to `goal` over the cells not blocked for
 * `radius` (8-connected); +inf where unreachable. */
std::vector<float> distanceField(const GroundTruthGrid& gt, const Eigen::Vector2d& goal, double radius);

/** The first obstacle or drop cell on the segment a -> b (sampled every
 * resolution / 4) that belongs to an object other than those in `ignore`
 * (e.g. the walls); returns its object id (0: none) and, in `at`, its
 * distance from a. */
int firstHazardOnSegment(
	const GroundTruthGrid& gt, const Eigen::Vector2d& a, const Eigen::Vector2d& b, const std::vector<int>& ignore,
	double* at = nullptr);

/** The ground truth frame by frame, for scenes whose objects move (people):
 * built once, then, as gam-simulate does, labelled again where an object
 * appeared, left or moved (GroundTruthGrid::relabel on Scene::atFrame). */
class FrameGroundTruth
{
   public:
	FrameGroundTruth(const Scene& scene, const GridSpec& spec);
	/** Brings the labels to frame f (any frame, forwards or back). */
	void setFrame(int f);
	int frame() const { return m_frame; }
	const GroundTruthGrid& grid() const { return m_gt; }
	const Scene& scene() const { return m_scene; }

   private:
	Scene m_scene;
	GroundTruthGrid m_gt;
	int m_frame = 0;
};

}  // namespace gam::sim
