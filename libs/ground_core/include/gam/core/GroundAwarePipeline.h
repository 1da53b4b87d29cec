// Ground-aware mapping for MRPT
// The method of the paper in one place: a depth frame -> robot-centred 2.5D map
// (projection, 3-sigma filter, IDW; §IV.A) -> RRT-GPD ground planes (§IV.B,
// Alg. 1) -> inverse sensor model evidence per 2D cell (§IV.C). The pipeline
// owns every stage, their scratch buffers and their timings; the MRPT map
// (CGroundAwareOccupancyGrid) only adapts observations and fuses the evidence.
// Pure code: no MRPT, no I/O. After the first frame of a given size it makes
// no heap allocation.
#pragma once

#include <Eigen/Core>
#include <limits>
#include <vector>

#include "gam/core/CameraNoise.h"
#include "gam/core/DepthProjector.h"
#include "gam/core/ElevationGrid.h"
#include "gam/core/InverseSensorModel.h"
#include "gam/core/MissingFloor.h"
#include "gam/core/Parameters.h"
#include "gam/core/PatchMemory.h"
#include "gam/core/RrtGroundDetector.h"
#include "gam/core/SensorFrame.h"

namespace gam
{
/** Every parameter of the pipeline, nested per stage. Defaults: paper Table I
 * where the paper has the value. */
struct PipelineParams
{
	/** Cells of the robot-centred 2.5D map of one frame (its resolution d_r is
	 * that of the caller's grid, see GridLattice). */
	int m_x = 200, m_y = 200;
	/** What is projected. z_min and z_max are in the robot frame (floor = 0);
	 * points above ism.robot_height are dropped too (see projectionFilter()). */
	ProjectionFilter projection = {0.0f, 5.0f, -3.0f, 2.5f, 1};
	OutlierFilterParams outliers;  ///< 3-sigma rule
	IdwParams idw = {1, 2.0f, 3};  ///< IDW, for the local plane fits only (see idw_in_ism)
	/** The paper densifies the 2.5D map with IDW before the ISM: with this on,
	 * every IDW cell enters the ISM as a one-sample voxel at its estimated
	 * height (one estimate is one sample). Off by default: an estimate is no
	 * measurement, and only the plane fits use it. */
	bool idw_in_ism = false;
	RrtGpdParams rrt;
	IsmParams ism;
	/** Missing floor (depth images only; not in the paper's model). */
	MissingFloorParams missing;
	/** The camera's noise and the range of trust (not in the paper's model). */
	CameraParams camera;
	/** A ground plane whose height under the robot is farther than this from
	 * the floor the robot stands on (the mount's floor) is not the ground: the
	 * frame's ground becomes that floor (z = the robot's z, level) and the
	 * tree's plane is dropped. A raised stage or a long box top the tree grew
	 * on, or a plane fitted to a far floor by a noisy camera and tilted by
	 * its noise, would otherwise make everything on it free. 0.10 m: beyond
	 * what a mount within the mount check's tolerances (3 cm, 1.5 deg seen
	 * 2 m ahead: 5 cm) and a floor's unevenness explain. The same floor
	 * also stands in for a ground plane that holds significantly fewer of
	 * the tree's nodes than it does (within 2.5 cm, McNemar's test at
	 * 3 sigma: RrtGroundDetector, GroundSeedHint::judge_against_floor): a
	 * plane the refit tilted onto a step's lower level or a box top, which
	 * passes under the robot within 0.10 m. 0 = off (both); not in the
	 * paper's model. [m] */
	double max_ground_offset = 0.10;
	/** Ramp patches of this camera's earlier frames judge this frame's voxels
	 * too (see PatchMemory): a patch is forgotten once the robot has travelled
	 * this far since a frame last fitted it. 1.0 m: at an odometry drift of
	 * 2 % of the distance (the simulator's) the patch has moved 2 cm, which
	 * on an 8 deg ramp is 2.8 mm of height, under a tenth of d_pth. 0 = off;
	 * not in the paper's model. [m] */
	double patch_memory = 1.0;

	template <class Self, class Visit>
	static void forEachParam(Self& p, Visit&& visit)
	{
		visit(ParamInfo{"m_x", 3, 20000, "cells of the robot-centred 2.5D map along x"}, p.m_x);
		visit(ParamInfo{"m_y", 3, 20000, "cells of the robot-centred 2.5D map along y"}, p.m_y);
		ProjectionFilter::forEachParam(p.projection, visit);
		OutlierFilterParams::forEachParam(p.outliers, visit);
		IdwParams::forEachParam(p.idw, visit);
		visit(
			ParamInfo{"idw_in_ism", 0, 1, "IDW cells enter the ISM as one-sample voxels (paper Fig. 4)"}, p.idw_in_ism);
		RrtGpdParams::forEachParam(p.rrt, visit);
		IsmParams::forEachParam(p.ism, visit);
		MissingFloorParams::forEachParam(p.missing, visit);
		CameraParams::forEachParam(p.camera, visit);
		visit(
			ParamInfo{
				"max_ground_offset", 0, 100,
				"a ground plane this far from the robot's floor under the robot, or holding significantly fewer "
				"of the tree's nodes than that floor, is replaced by that floor [m]; 0 = off"},
			p.max_ground_offset);
		visit(
			ParamInfo{
				"patch_memory", 0, 1000,
				"ramp patches of earlier frames judge this frame until the robot has travelled this far [m]; 0 = "
				"off"},
			p.patch_memory);
	}
	/** Every range and every rule between parameters; throws
	 * std::invalid_argument naming the key. */
	void validate() const;

	/** The projector's filter for a robot standing at height `robotZ` (map
	 * frame): the robot-frame z band, cropped at robot_height. */
	ProjectionFilter projectionFilter(double robotZ) const;
	/** The 3-sigma rule as run: `outliers`, without the minimum band in the
	 * paper's model (the default's 5 mm keeps the samples of a perfectly
	 * flat cell from being cut by round-off). */
	OutlierFilterParams outlierFilter() const;
};

/** The cells of the frame grid are aligned with this lattice: its corner
 * (x0, y0) and its cell size (the caller's map grid). */
struct GridLattice
{
	double x0 = 0, y0 = 0, resolution = 0.05;
};

/** Milliseconds each stage of the last frame took. */
struct StageTimes
{
	double projection = 0;  ///< frame grid placement + binning
	double outliers = 0;    ///< 3-sigma filter + IDW
	double ground = 0;      ///< RRT-GPD + RANSAC
	double ism = 0;         ///< inverse sensor model
	double missing = 0;     ///< missing floor
};

/** What the last frame gave. */
struct FrameResult
{
	bool valid = false;               ///< a frame was processed
	size_t samples = 0;               ///< samples binned (before the 3-sigma filter)
	size_t points = 0;                ///< samples kept in the 2.5D map
	Eigen::Vector3d sensor{0, 0, 0};  ///< sensor position (map frame)
	GroundDetection detection;
	IsmStats ism;
	MissingFloorStats missing;
	/** The camera model whose noise was assumed (camera_model, or what `auto`
	 * found) and the range of trust it gave at the sensor's height: voxels
	 * farther away (2D) gave no evidence. +inf when off or not computed
	 * (paper mode, a frame without intrinsics). [m] */
	CameraModel camera = CameraModel::Custom;
	double trust_range = std::numeric_limits<double>::infinity();
	/** Ramp patches of earlier frames that judged this frame's voxels beside
	 * detection's planes (patch_memory): their planes (map frame) and nodes,
	 * in the order the ISM took them. */
	std::vector<Plane> remembered_planes;
	std::vector<size_t> remembered_support;
	StageTimes ms;
};

class GroundAwarePipeline
{
   public:
	/** Throws std::invalid_argument for parameters out of range. */
	explicit GroundAwarePipeline(const PipelineParams& p = {});
	/** Validates (throws std::invalid_argument, keeping the old parameters),
	 * then applies `p`: frames run with parameters checked once. */
	void setParams(const PipelineParams& p);
	const PipelineParams& params() const { return m_params; }

	/** Runs every stage on one frame taken by a robot at `robot` (map frame;
	 * z = the floor under it). The frame grid is m_x x m_y cells of `lattice`,
	 * centred on the robot. Throws std::invalid_argument for a non-finite
	 * robot position, a bad lattice or a malformed frame. */
	const FrameResult& process(const SensorFrame& frame, const Eigen::Vector3d& robot, const GridLattice& lattice);

	/** The corner (x_min, y_min) of the frame grid that process() lays for a
	 * robot at `robot` on `lattice`. Besides the lattice's resolution, the
	 * only way the lattice enters a frame's result: two lattices that give
	 * the same corner give the same result, bit for bit. */
	Eigen::Vector2d gridOrigin(const Eigen::Vector3d& robot, const GridLattice& lattice) const;

	/** Forgets the last frame (result().valid = false); buffers are kept. */
	void resetResult();
	/** Forgets the ramp patches of earlier frames (patch_memory) and the path
	 * travelled: a new map or run. */
	void forgetPatches();
	/** Undoes what the last process() did to the ramp patches remembered and
	 * the path travelled, before running a frame again whose first run is
	 * not taken (its inputs changed meanwhile): the frame then counts once,
	 * as without threads. */
	void rewindPatches();

	const FrameResult& result() const { return m_result; }
	/** The 2.5D map of the last frame. */
	const ElevationGrid& frameGrid() const { return m_grid; }
	/** Its evidence (P(occupied) per frame cell) and voxel classes. */
	const InverseSensorModel& ism() const { return m_ism; }
	/** Missing floor of the last frame (frame-grid cells). */
	const MissingFloorDetector& missingFloor() const { return m_missing; }
	/** The ramp patches this camera's frames fitted, as remembered now. */
	const PatchMemory& patchMemory() const { return m_patchMemory; }
	/** The projector, e.g. to force the baseline row loop in tests. */
	DepthProjector& projector() { return m_projector; }

   private:
	void placeGrid(const Eigen::Vector3d& robot, const GridLattice& lattice);

	PipelineParams m_params;
	DepthProjector m_projector;
	ElevationGrid m_grid;
	BinnedPoints m_bins;
	RrtGroundDetector m_rrt;
	InverseSensorModel m_ism;
	MissingFloorDetector m_missing;
	PatchMemory m_patchMemory;
	FrameResult m_result;
};

}  // namespace gam
