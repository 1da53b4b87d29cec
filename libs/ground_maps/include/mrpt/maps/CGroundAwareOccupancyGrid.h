// Ground-aware mapping for MRPT
#pragma once

#include <exception>
#include <functional>
#include <map>
#include <string>
#include <unordered_map>
#include <vector>

#include <mrpt/config/CLoadableOptions.h>
#include <mrpt/maps/COccupancyGridMap2D.h>

#include "gam/core/GroundAwarePipeline.h"
#include "gam/core/SensorMount.h"
#include "gam/maps/WorkerPool.h"

namespace mrpt::obs
{
class CObservation2DRangeScan;
class CSensoryFrame;
}  // namespace mrpt::obs

namespace mrpt::maps
{
/** A COccupancyGridMap2D that sees the ground: every 3D observation is
 * projected into a robot-centred 2.5D map, RRT-GPD finds the ground plane, and
 * the inverse sensor model turns each voxel into occupancy evidence:
 * obstacles sticking out of the ground, and also holes, drops and downward
 * steps below it, become occupied; seen floor becomes free. 2D scans (Leddar,
 * lidars) go through the base class's beam model into the same grid.
 *
 * Because it derives from COccupancyGridMap2D, planners, localization and
 * MRPT tools accept it; getCell() is, as always, the probability of FREE.
 *
 * Frame pipeline (per CObservation3DRangeScan / CObservationPointCloud):
 *  1. 2.5D projection into an m_x x m_y grid at this grid's resolution (d_r),
 *     centred on the robot, with the 3-sigma filter and IDW for the fits;
 *  2. RRT-GPD (K, N_th, E_th, s_x, s_y, d_n) + RANSAC -> ground plane(s);
 *  3. ISM eq. (4)-(6) (K_m, K_n, d_min, sigma2, K_g, d_pth) -> one piece of
 *     evidence per 2D cell and frame, fused in log-odds.
 * If no ground is found the frame changes nothing (see lastFrame().detection).
 *
 * Ground planes: planes[0] is the RANSAC plane of the tree nodes. Gentle ramps
 * (<= 8 deg) are not on it: they become extra planes fitted to the nodes the
 * tree placed on them, used within plane_support_radius of those nodes
 * ("local planes", option local_planes). With local_planes=false, one global
 * plane is used and a ramp rising more than d_pth above the floor is an obstacle.
 *
 * The method itself is gam::GroundAwarePipeline (pure code, libs/ground_core);
 * this class adapts observations to it and fuses its evidence in log-odds.
 *
 * .ini: the standard COccupancyGridMap2D sections (_creationOpts,
 * _insertOpts, _likelihoodOpts) plus `[<prefix>_groundOpts]` with the keys of
 * TGroundAwareOptions (paper Table I names), listed once in the parameter
 * structs of the core (forEachParam).
 */
class CGroundAwareOccupancyGrid : public COccupancyGridMap2D
{
	DEFINE_SERIALIZABLE(CGroundAwareOccupancyGrid, mrpt::maps)

   public:
	CGroundAwareOccupancyGrid(
		float min_x = -10.0f, float max_x = 10.0f, float min_y = -10.0f, float max_y = 10.0f, float resolution = 0.05f);

	/** Every ground-aware parameter; defaults = paper Table I. */
	struct TGroundAwareOptions : public mrpt::config::CLoadableOptions
	{
		/** The method's parameters, nested per stage (2.5D map, outliers, IDW,
		 * RRT-GPD, ISM); d_r is the grid resolution, from _creationOpts. */
		gam::PipelineParams pipeline;
		// 2D scans
		int sparse_scan_upsampling = 8;  ///< rays per beam for scans of < 64 beams (Leddar)
		/** Where a sparse scan's ranges recede from beam to beam, a beam's
		 * rays end on the surface through its and its neighbour's echoes at
		 * their cones' near edges, not on an arc at its echo's range (see
		 * upsampleSparseScan). */
		bool sparse_scan_near_edge = true;
		/** What a 2D scan may do to the grid (the walker's rule, issue #31):
		 * - `true`: a planar beam passes over holes, cables and small boxes, so
		 *   2D scans add their hits and make no cell freer: only floor the depth
		 *   camera saw is free. A grid that never gets a depth frame then has
		 *   no free cell (a one-line warning says so).
		 * - `false`: MRPT's beam model, as the stock COccupancyGridMap2D.
		 * - `auto` (default): `false` until the grid has received its first
		 *   depth frame (CObservation3DRangeScan or CObservationPointCloud),
		 *   `true` from then on. A lidar-only grid is then the stock grid, cell
		 *   for cell; the walker's configs set `true` so that Leddar scans that
		 *   come before the first depth frame free nothing either. */
		enum class ScanRule : int
		{
			BeamModel = 0,
			KeepCameraFloor = 1,
			Auto = 2
		};
		static constexpr const char* kScanRuleNames[] = {"false", "true", "auto", nullptr};
		ScanRule scan_keeps_3d_obstacles = ScanRule::Auto;
		/** > 0: a positive obstacle (something sticking out of the floor, or a
		 * 2D scan's hit) not re-observed as an obstacle for this many seconds
		 * returns to unknown -- people who left. Never a negative obstacle
		 * (hole, drop) or missing floor: those cannot walk away. 0 = off (the
		 * default, as STVL's voxel_decay): obstacles stay until seen free. [s] */
		double obstacle_decay_s = 0;
		/** The online check of the declared sensor mount (height, pitch, roll)
		 * against every frame's floor, and the option to map with the measured one. */
		gam::MountCheckParams mount;
		/** Threads for the depth frames of several cameras taken at one robot
		 * pose (insertObservations()): their pipelines run concurrently, and
		 * their evidence is fused in the order given, so the map is the same
		 * byte for byte whatever this is. 1 (the default) = one frame after
		 * the other in the calling thread; at most 64. */
		int threads = 1;

		/** Every `_groundOpts` key: the pipeline's, then the 2D-scan ones. */
		template <class Self, class Visit>
		static void forEachParam(Self& o, Visit&& visit)
		{
			gam::PipelineParams::forEachParam(o.pipeline, visit);
			visit(
				gam::ParamInfo{"sparse_scan_upsampling", 1, 1000, "rays per beam for scans with < 64 beams"},
				o.sparse_scan_upsampling);
			visit(
				gam::ParamInfo{
					"sparse_scan_near_edge", 0, 1,
					"a sparse scan's beam ends on the surface through its neighbours' near-edge echoes where the "
					"ranges recede (false: an arc at its echo's range)"},
				o.sparse_scan_near_edge);
			visit(
				gam::ParamInfo{
					"scan_keeps_3d_obstacles", 0, 2,
					"2D scans add their hits and free no cell (they take back their own hits): true | false (MRPT's "
					"beam model) | auto (false until the first depth frame)",
					kScanRuleNames},
				o.scan_keeps_3d_obstacles);
			visit(
				gam::ParamInfo{
					"obstacle_decay_s", 0, 1e9,
					"positive obstacles not re-observed for this long return to unknown [s]; 0 = never"},
				o.obstacle_decay_s);
			gam::MountCheckParams::forEachParam(o.mount, visit);
			visit(
				gam::ParamInfo{
					"threads", 1, 64,
					"threads for the depth frames of several cameras at one robot pose (insertObservations); the map "
					"is the same for any value"},
				o.threads);
		}
		/** Loads and validates (throws std::invalid_argument naming the key). */
		void loadFromConfigFile(const mrpt::config::CConfigFileBase& source, const std::string& section) override;
		void saveToConfigFile(mrpt::config::CConfigFileBase& target, const std::string& section) const override;
		/** Throws std::invalid_argument naming the key and its range. */
		void validate() const;
	};
	/** The options in use (validated). */
	const TGroundAwareOptions& groundOptions() const { return m_options; }
	/** Validates `o` (throws std::invalid_argument and keeps the current
	 * options if it is out of range), then uses it from the next frame on. */
	void setGroundOptions(const TGroundAwareOptions& o);

	/** Map-side times of the last 3D frame; the pipeline's stages are in lastFrame().ms. */
	struct TFrameTimes
	{
		double update = 0;  ///< log-odds fusion into this grid [ms]
		double total = 0;   ///< the whole insertion [ms]
	};
	/** Inserts observations taken at one robot pose (the depth frames of
	 * several cameras, e.g. one CSensoryFrame) and returns whether any was
	 * inserted. The result is, byte for byte, that of insertObservation() on
	 * each in the order given, for any `threads`: with threads > 1 the
	 * pipelines of the first depth frame of each sensor label run
	 * concurrently on the grid as it is at the call; then every observation
	 * is inserted in order, each depth frame taking its pipeline's result if
	 * what that pipeline ran on (the frame grid's corner on this grid's
	 * lattice, the sensor pose) is still what it would run on now, and
	 * running it again otherwise (the grid grew or was recentred in between
	 * by more than a whole number of cells, or the mount estimate moved).
	 * `afterEach(i)`, if given, is called after observation i was inserted
	 * (lastFrame() is then that frame's). Null pointers are skipped. An
	 * exception leaves the grid as insertObservation() would have: the
	 * observations before the failing one are inserted. */
	bool insertObservations(
		const std::vector<const mrpt::obs::CObservation*>& observations, const mrpt::poses::CPose3D& robotPose,
		const std::function<void(size_t)>& afterEach = {});
	/** The same for the observations of a sensory frame, in its order (what
	 * CSensoryFrame::insertObservationsInto() does one by one). */
	bool insertObservations(const mrpt::obs::CSensoryFrame& sf, const mrpt::poses::CPose3D& robotPose);

	/** insertObservations() with threads > 1 since the grid was created: depth
	 * frames whose pipeline ran ahead, concurrently, and whose result was
	 * fused; and those whose inputs had changed by their turn, run again. */
	struct TParallelStats
	{
		uint64_t ran_ahead = 0, run_again = 0;
		/** Of the frames that ran ahead: run by a worker thread (the others by
		 * the calling thread, which takes what no worker has taken yet). */
		uint64_t on_worker = 0;
	};
	const TParallelStats& parallelStats() const { return m_parallelStats; }

	/** What happened to the last 3D frame (for apps, viewers and logs). */
	const gam::FrameResult& lastFrame() const { return lastPipeline().result(); }
	const TFrameTimes& lastFrameTimes() const { return m_times; }
	/** The mount check per sensor label (gam::MountMonitor): the declared and
	 * the measured height, pitch and roll, the counters and the alarm. */
	const std::map<std::string, gam::MountMonitor>& mountChecks() const { return m_mounts; }
	/** True while the mount alarm of any sensor is on. */
	bool mountAlarm() const;
	/** The camera per sensor label, as the last depth frame of that label
	 * found it: its model (camera_model, or what `auto` read from the frame),
	 * its range of trust and the sensor's height above the floor. */
	struct TCameraInfo
	{
		gam::CameraModel model = gam::CameraModel::Custom;
		double trust_range = 0;  ///< [m]; +inf when not limited
		double height = 0;       ///< sensor above the robot's floor [m]
		int width = 0, height_px = 0;
		/** Image columns at the left and right borders that returned nothing in
		 * any row of the last frame (the band of a depth image registered to a
		 * colour camera, or a stereo camera's invalid band): no floor evidence
		 * there (missing::deadBorderColumns). */
		int dead_border_columns = 0;
	};
	const std::map<std::string, TCameraInfo>& cameras() const { return m_cameras; }
	/** The ramp patches that the depth frames of sensor `label` fitted, as
	 * its pipeline remembers them now (patch_memory); null before a depth
	 * frame of that label. */
	const gam::PatchMemory* rememberedPatches(const std::string& label) const;
	/** The label of the last depth frame's sensor (its entry in mountChecks()). */
	const std::string& lastSensorLabel() const { return m_lastSensorLabel; }

	/** The 2.5D map of the last 3D frame. */
	const gam::ElevationGrid& lastFrameElevation() const { return lastPipeline().frameGrid(); }
	/** The ISM evidence and voxel classes of the last 3D frame (frame grid). */
	const gam::InverseSensorModel& lastFrameIsm() const { return lastPipeline().ism(); }

	/** Missing floor (issue #13): where the ground plane predicted a floor
	 * return within range and the camera returned nothing. A grid of the same
	 * geometry as this one: occupied = missing floor (its last judgement),
	 * free = floor seen since, unknown = never judged. Missing floor within
	 * missing_floor_block_range of the sensor is also an obstacle in this grid;
	 * a cell clears from the layer as soon as floor is seen there. */
	const COccupancyGridMap2D& missingFloorLayer() const;
	/** Whether a cell of the layer is missing floor now (world coordinates). */
	bool isMissingFloor(float x, float y) const;

	/** Splits each beam of a sparse scan (< 64 beams, e.g. a 16-segment Leddar)
	 * into k rays, so the base beam model covers each segment's full width:
	 * beam i (at -aperture/2 + i s, s = aperture / (N - 1)) covers s around
	 * its direction, and its rays sit s / k apart inside that cone (the
	 * aperture grows to (N k - 1) s / k).
	 * With `nearEdge`, where the ranges recede from beam to beam (a surface
	 * seen obliquely), a beam's echo (the nearest return in its cone) lies at
	 * the cone's edge toward its nearer neighbour, and its rays end on the
	 * chord from that point to the neighbour's echo at the shared edge (never
	 * nearer than the echo; the arc where the chord meets the rays within
	 * kMinIncidence of grazing: a jump, not a surface). Where the beam's
	 * surface (the line through its nearer neighbour's echo and its own, a
	 * third echo within 3 sigma of the scan's range noise of it) passes
	 * behind the farther neighbour's echo, a concave corner: the rays end on
	 * that line, capped at that echo's range. */
	static mrpt::obs::CObservation2DRangeScan upsampleSparseScan(
		const mrpt::obs::CObservation2DRangeScan& in, int raysPerBeam, bool nearEdge = true);
	/** See upsampleSparseScan: 10 deg. [rad] */
	static constexpr double kMinIncidence = 10.0 * M_PI / 180.0;

	std::string asString() const override;

	/** Depth frames (CObservation3DRangeScan, CObservationPointCloud) this
	 * grid has received since it was created, cleared or loaded from a stock
	 * grid (serialized). */
	uint64_t depthFramesReceived() const { return m_depthFrames; }
	/** Whether the next 2D scan follows the walker's rule (adds hits, frees
	 * nothing): scan_keeps_3d_obstacles = true, or auto after a depth frame. */
	bool scanRuleActive() const;

	/** Stock grids in: this grid takes the extent, resolution and cells of
	 * `stock` (any COccupancyGridMap2D, e.g. one read from a `.gridmap` or a
	 * ROS map_server YAML; see gam/maps/GridIO.h readStockGrid()). Its own
	 * options (insertion, likelihood, ground) stay; the run state (missing
	 * floor layer, scan-only cells, obstacle ages, depth frames received) is
	 * reset, so a lidar-made map takes 2D scans as the stock grid would until
	 * a depth frame arrives (scan_keeps_3d_obstacles = auto). */
	void loadFromStockGrid(const COccupancyGridMap2D& stock);
	/** Stock grids out: a plain COccupancyGridMap2D with this grid's extent,
	 * cells and options, which any MRPT tool reads when serialized (a
	 * serialized CGroundAwareOccupancyGrid needs this plugin to be read, and
	 * `archive >> COccupancyGridMap2D` rejects it: the stored class differs). */
	COccupancyGridMap2D asStockGrid() const;

	MAP_DEFINITION_START(CGroundAwareOccupancyGrid)
	float min_x = -10.0f, max_x = 10.0f, min_y = -10.0f, max_y = 10.0f, resolution = 0.05f;
	mrpt::maps::COccupancyGridMap2D::TInsertionOptions insertionOpts;
	mrpt::maps::COccupancyGridMap2D::TLikelihoodOptions likelihoodOpts;
	mrpt::maps::CGroundAwareOccupancyGrid::TGroundAwareOptions groundOpts;
	MAP_DEFINITION_END(CGroundAwareOccupancyGrid)

   protected:
	/** The base's clear (cells unknown, extent +-10 m) and the run state. */
	void internal_clear() override;
	bool internal_insertObservation(
		const mrpt::obs::CObservation& obs,
		const std::optional<const mrpt::poses::CPose3D>& robotPose = std::nullopt) override;

   private:
	bool insert3D(const mrpt::obs::CObservation& obs, const mrpt::poses::CPose3D& robotPose);
	/** What a depth frame's pipeline runs on, given the state of the grid now. */
	struct TPreparedFrame
	{
		gam::GroundAwarePipeline* pipeline = nullptr;
		gam::SensorFrame frame;
		Eigen::Vector3d robot = Eigen::Vector3d::Zero();
		gam::GridLattice lattice;
		mrpt::poses::CPose3D declared, used;               ///< the sensor pose declared, and the one placing the points
		Eigen::Vector2d origin = Eigen::Vector2d::Zero();  ///< the frame grid's corner (gridOrigin())
		/** Same inputs, so the same result bit for bit (the observation being the same). */
		bool sameInputs(const TPreparedFrame& o) const;
	};
	/** Fills `p` (creates the label's pipeline on first use; the mount monitor is only read). */
	void prepareFrame(const mrpt::obs::CObservation& obs, const mrpt::poses::CPose3D& robotPose, TPreparedFrame& p);
	gam::GroundAwarePipeline& pipelineFor(const std::string& label);
	/** The pipeline of the last depth frame (an idle one before any). */
	const gam::GroundAwarePipeline& lastPipeline() const;
	/** A depth frame of insertObservations() whose pipeline ran ahead. */
	struct TBatchSlot
	{
		const mrpt::obs::CObservation* obs = nullptr;
		TPreparedFrame prepared;
		std::exception_ptr error;  ///< what process() threw
		bool ran = false, taken = false, onWorker = false;
	};
	static void runBatchSlot(void* grid, size_t i);
	bool insert2D(
		const mrpt::obs::CObservation2DRangeScan& scan, const std::optional<const mrpt::poses::CPose3D>& robotPose);
	void applyEvidence(const gam::GroundAwarePipeline& pipeline);
	/** Gives the missing-floor layer this grid's geometry (cells kept). */
	void syncMissingLayer() const;
	/** Gives a layer this grid's geometry, keeping the cells both cover. */
	void syncLayer(COccupancyGridMap2D& layer) const;
	/** obstacle_decay_s: records positive obstacle cells seen at time `t`,
	 * forgets negative ones, and returns to unknown the positive ones older
	 * than the decay time. */
	int64_t worldKeyOf(int cx, int cy) const;
	void notePositive(int cx, int cy, double t);
	void noteNegative(int cx, int cy);
	void decayObstacles(double t);

	TGroundAwareOptions m_options;
	// The method and its per-frame workspace, one per sensor label, so that
	// the frames of several cameras can run at once (not serialized). A
	// pipeline carries nothing from one frame to the next but buffers, so
	// this gives the maps one shared pipeline gave. (std::map: its nodes stay
	// put, so pointers to them hold while labels are added.)
	std::map<std::string, gam::GroundAwarePipeline> m_pipelines;
	gam::GroundAwarePipeline m_idlePipeline;  ///< lastFrame() before any depth frame
	bool m_lastHasPipeline = false;
	gam::maps::WorkerPool m_pool;
	std::vector<TBatchSlot> m_batch;  ///< during insertObservations() (capacity kept)
	TParallelStats m_parallelStats;
	std::thread::id m_batchCaller;
	std::vector<const mrpt::obs::CObservation*> m_sfObservations;  ///< scratch (capacity kept)
	TFrameTimes m_times;
	std::map<std::string, gam::MountMonitor> m_mounts;  // not serialized: state of a run
	std::string m_lastSensorLabel;
	std::map<std::string, TCameraInfo> m_cameras;  // not serialized: state of a run
	mutable COccupancyGridMap2D m_missingLayer;
	// The 2D scans' own evidence per cell, their ledger (log-odds as MRPT's
	// cells: their hits net of the rays passing since, <= 0; 1 where rays
	// have passed since the last echo; 0 where the camera marked an obstacle
	// since): the cell holds the rest plus min(0, ledger), see insert2D().
	// State of a run: not serialized, so a loaded map's obstacles all stay.
	COccupancyGridMap2D m_scanOnlyLayer;
	std::vector<cellType> m_scanBefore;  ///< insert2D()'s copy of the cells a scan can reach (scratch)
	// applyEvidence(): the grid's and the missing-floor layer's column (row)
	// of each column (row) of the frame grid, for this frame (scratch).
	std::vector<int> m_colOf, m_rowOf, m_layerColOf, m_layerRowOf;
	// obstacle_decay_s: last time each positive obstacle cell was seen as one,
	// keyed by its world cell (stable when the grid grows). Not serialized.
	std::unordered_map<int64_t, double> m_positiveSeen;
	// Depth frames received (scan_keeps_3d_obstacles = auto), serialized; and
	// 2D scans received while none had come (for the one-line warning).
	uint64_t m_depthFrames = 0;
	uint64_t m_scansBeforeDepth = 0;
	bool m_warnedNoFreeSpace = false;
	/** The state of a run, for a grid whose cells came from elsewhere (clear,
	 * a stock grid, deserialization): layers unknown at this grid's extent,
	 * no obstacle ages, no depth frame received. (The mount check stays: it is
	 * the camera's, not the map's.) */
	void resetRunState();
};

}  // namespace mrpt::maps
