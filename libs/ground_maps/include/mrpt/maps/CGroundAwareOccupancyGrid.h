// Ground-aware mapping for MRPT
#pragma once

#include <mrpt/maps/COccupancyGridMap2D.h>
#include <mrpt/maps/gam_ini_fields.h>

#include "gam/DepthProjector.h"
#include "gam/ElevationGrid.h"
#include "gam/InverseSensorModel.h"
#include "gam/RrtGroundDetector.h"

namespace mrpt::obs
{
class CObservation2DRangeScan;
}

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
 * .ini: the standard COccupancyGridMap2D sections (_creationOpts,
 * _insertOpts, _likelihoodOpts) plus `[<prefix>_groundOpts]` with the keys of
 * TGroundAwareOptions (paper Table I names).
 */
class CGroundAwareOccupancyGrid : public COccupancyGridMap2D
{
	DEFINE_SERIALIZABLE(CGroundAwareOccupancyGrid, mrpt::maps)

   public:
	CGroundAwareOccupancyGrid(
		float min_x = -10.0f, float max_x = 10.0f, float min_y = -10.0f, float max_y = 10.0f,
		float resolution = 0.05f);

	/** Every ground-aware parameter; defaults = paper Table I. */
	struct TGroundAwareOptions : public mrpt::config::CLoadableOptions
	{
		// 2.5D map (d_r is the grid resolution, from _creationOpts)
		int m_x = 200, m_y = 200;  ///< cells of the robot-centred 2.5D map
		float z_min = -3.0f;  ///< points below robot-frame z (floor = 0) are dropped [m]
		float z_max = 2.5f;	 ///< points above it are dropped [m]
		float min_range = 0.0f, max_range = 5.0f;	///< sensor range limits [m]
		int decimation = 1;
		bool outlier_filter = true;
		float outlier_sigmas = 3.0f;
		int outlier_min_count = 4;
		int idw_radius = 1;	 ///< IDW for the local plane fits [cells], 0 = off
		// RRT-GPD
		int K = 600;
		double N_th = 0.2, E_th = 0.05;
		int s_x = 3, s_y = 3;
		double d_n = 0.4;
		double max_cell_std = 0.05, max_fit_rms = 0.025;
		int min_valid_cells = 5;
		double seed_search_radius = 5.0, seed_height_tolerance = 0.3, window_margin = 1.0;
		int seed_attempts = 3;
		int min_nodes = 8, ransac_iterations = 100;
		double ransac_inlier_distance = 0.025;
		int min_nodes_per_extra_plane = 3, max_planes = 3;
		int random_seed = 1;
		// Inverse sensor model
		double d_pth = 0.03, K_g = 0.3, sigma2 = 0.02, K_n = 0.0005, d_min = 3.0, K_m = 0.8;
		double depth_noise_c0 = 0.0012, depth_noise_c2 = 0.0019, noise_sigmas = 3.0;
		bool measure_floor_noise = true;
		int floor_noise_min_cells = 10;
		int min_obstacle_points = 2;
		double robot_height = 1.8;
		bool drop_rays = true;
		double max_drop_ray_length = 2.0;
		int drop_ray_min_points = 3;
		bool local_planes = true;
		double plane_support_radius = 0.4;
		// 2D scans
		int sparse_scan_upsampling = 8;	 ///< rays per beam for scans of < 64 beams (Leddar)
		/** A planar beam passes over holes, cables and small boxes: with this
		 * on, 2D scans add their hits and reinforce cells already free, but
		 * never make an unknown or occupied cell freer (only seen floor is free). */
		bool scan_keeps_3d_obstacles = true;

		gam::ini::Fields fields();
		void loadFromConfigFile(const mrpt::config::CConfigFileBase& source, const std::string& section) override;
		void saveToConfigFile(mrpt::config::CConfigFileBase& target, const std::string& section) const override;
		/** Throws std::invalid_argument naming the key and its range. */
		void validate() const;
		gam::RrtGpdParams rrtParams() const;
		gam::IsmParams ismParams() const;
		gam::ProjectionFilter projectionFilter(double robotZ) const;
		gam::OutlierFilterParams outlierParams() const;
	} groundOptions;

	/** What happened to the last 3D frame (for apps, viewers and logs). */
	struct TFrameDiagnostics
	{
		bool valid = false;	 ///< a 3D frame was processed
		gam::GroundDetection detection;
		gam::IsmStats ism;
		size_t points = 0;	///< points kept in the 2.5D map
		Eigen::Vector3d sensor{0, 0, 0};  ///< sensor position (map frame)
		double ms_projection = 0, ms_outliers = 0, ms_ground = 0, ms_ism = 0, ms_update = 0,
			   ms_total = 0;
	};
	const TFrameDiagnostics& lastFrame() const { return m_last; }
	/** The 2.5D map of the last 3D frame. */
	const gam::ElevationGrid& lastFrameElevation() const { return m_frame; }
	/** The ISM evidence and voxel classes of the last 3D frame (frame grid). */
	const gam::InverseSensorModel& lastFrameIsm() const { return m_ism; }

	/** Splits each beam of a sparse scan (< 64 beams, e.g. a 16-segment Leddar)
	 * into k rays, so the base beam model covers each segment's full width. */
	static mrpt::obs::CObservation2DRangeScan upsampleSparseScan(
		const mrpt::obs::CObservation2DRangeScan& in, int raysPerBeam);

	std::string asString() const override;

	MAP_DEFINITION_START(CGroundAwareOccupancyGrid)
	float min_x = -10.0f, max_x = 10.0f, min_y = -10.0f, max_y = 10.0f, resolution = 0.05f;
	mrpt::maps::COccupancyGridMap2D::TInsertionOptions insertionOpts;
	mrpt::maps::COccupancyGridMap2D::TLikelihoodOptions likelihoodOpts;
	mrpt::maps::CGroundAwareOccupancyGrid::TGroundAwareOptions groundOpts;
	MAP_DEFINITION_END(CGroundAwareOccupancyGrid)

   protected:
	bool internal_insertObservation(
		const mrpt::obs::CObservation& obs,
		const std::optional<const mrpt::poses::CPose3D>& robotPose = std::nullopt) override;

   private:
	bool insert3D(const mrpt::obs::CObservation& obs, const mrpt::poses::CPose3D& robotPose);
	bool insert2D(
		const mrpt::obs::CObservation2DRangeScan& scan,
		const std::optional<const mrpt::poses::CPose3D>& robotPose);
	void applyEvidence();
	void resetLastFrame();

	// Per-frame workspace (not serialized).
	gam::ElevationGrid m_frame;
	gam::BinnedPoints m_bins;
	gam::DepthProjector m_projector;
	gam::RrtGroundDetector m_rrt;
	gam::InverseSensorModel m_ism;
	TFrameDiagnostics m_last;
};

}  // namespace mrpt::maps
