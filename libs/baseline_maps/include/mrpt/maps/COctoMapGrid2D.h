// Ground-aware mapping for MRPT
#pragma once

#include <mrpt/config/CLoadableOptions.h>
#include <mrpt/maps/COccupancyGridMap2D.h>
#include <mrpt/maps/COctoMap.h>

#include "gam/core/Parameters.h"

namespace mrpt::maps
{
/** The second baseline: an OctoMap (mrpt::maps::COctoMap, voxel size
 * `voxel_size`) fed with every depth frame, and its octomap_server-style
 * "projected map" as this COccupancyGridMap2D:
 *  - a cell is OCCUPIED if an occupied leaf voxel whose centre z is in
 *    [z_min, z_max] (z_max = the robot height) lies over it;
 *  - otherwise FREE if a free voxel overlaps the band there;
 *  - otherwise unknown (0.5).
 * The projection is ternary (p_free = 0, 1 or 0.5), like octomap_server's
 * nav_msgs/OccupancyGrid (100 / 0 / -1).
 *
 * Frames: COctoMap 2.5.8 transforms a 3D scan's points3D by the robot pose
 * only (it ignores sensorPose; see the MRPT notes), so this class never hands
 * it a 3D scan: it unprojects the range image itself (sensor pose applied,
 * every `decimation`-th pixel) into map-frame points and calls
 * COctoMap::insertPointCloud() with the real sensor origin. 2D scans use
 * COctoMap::insertObservation() (correct for them).
 *
 * .ini: `_creationOpts` (min_x..max_x, min_y..max_y, resolution of the 2D
 * grid; it grows to hold the projection) plus
 * \code
 * [<prefix>_octoOpts]
 * voxel_size = 0.05  z_min = 0.05  z_max = 1.8  decimation = 4  max_range = 5
 * prob_hit = 0.7  prob_miss = 0.4  clamping_min = 0.1192  clamping_max = 0.971
 * occupancy_thres = 0.5  project_every = 1  mark_free = true
 * \endcode
 */
class COctoMapGrid2D : public COccupancyGridMap2D
{
	DEFINE_SERIALIZABLE(COctoMapGrid2D, mrpt::maps)

   public:
	COctoMapGrid2D(
		float min_x = -10.0f, float max_x = 10.0f, float min_y = -10.0f, float max_y = 10.0f, float resolution = 0.05f);

	struct TOctoOptions : public mrpt::config::CLoadableOptions
	{
		double voxel_size = 0.05;  ///< octomap resolution [m]
		double z_min = 0.05;       ///< projection band, robot/map frame [m]
		double z_max = 1.8;        ///< the robot height [m]
		int decimation = 4;        ///< every n-th range-image pixel (rounded down to a divisor of W and H)
		double max_range = 5.0;    ///< rays are truncated here (octomap maxrange) [m]
		double prob_hit = 0.7, prob_miss = 0.4;
		double clamping_min = 0.1192, clamping_max = 0.971;
		double occupancy_thres = 0.5;
		int project_every = 1;  ///< re-project every n inserted frames; 0 = only on request / when saved
		bool mark_free = true;  ///< free voxels in the band make free cells

		template <class Self, class Visit>
		static void forEachParam(Self& o, Visit&& visit)
		{
			using gam::ParamInfo;
			visit(ParamInfo{"voxel_size", 0.005, 10, "octomap voxel size [m]"}, o.voxel_size);
			visit(ParamInfo{"z_min", -100, 100, "lowest voxel-centre z projected [m]"}, o.z_min);
			visit(ParamInfo{"z_max", -100, 100, "highest voxel-centre z projected (robot height) [m]"}, o.z_max);
			visit(ParamInfo{"decimation", 1, 64, "use every n-th range-image pixel"}, o.decimation);
			visit(ParamInfo{"max_range", 0.01, 1000, "rays are truncated at this range [m]"}, o.max_range);
			visit(ParamInfo{"prob_hit", 0.5001, 1, "octomap hit probability"}, o.prob_hit);
			visit(ParamInfo{"prob_miss", 0, 0.4999, "octomap miss probability"}, o.prob_miss);
			visit(ParamInfo{"clamping_min", 0, 1, "octomap lower clamping probability"}, o.clamping_min);
			visit(ParamInfo{"clamping_max", 0, 1, "octomap upper clamping probability"}, o.clamping_max);
			visit(ParamInfo{"occupancy_thres", 0, 1, "a voxel is occupied above this probability"}, o.occupancy_thres);
			visit(
				ParamInfo{"project_every", 0, 1000000, "re-project every n frames (0 = only when saved)"},
				o.project_every);
			visit(ParamInfo{"mark_free", 0, 1, "free voxels in the band make free cells"}, o.mark_free);
		}
		void loadFromConfigFile(const mrpt::config::CConfigFileBase& source, const std::string& section) override;
		void saveToConfigFile(mrpt::config::CConfigFileBase& target, const std::string& section) const override;
		void validate() const;
	} octoOptions;

	/** The 3D octomap. */
	const COctoMap& octomap() const { return m_octomap; }
	/** Rebuilds the 2D projection from the octomap now (grows the grid to the
	 * octomap's extent). Cheap if nothing was inserted since the last one. */
	void updateProjection();
	/** True if frames were inserted since the last projection. */
	bool projectionOutdated() const { return m_dirty; }
	/** Milliseconds the last projection took (0 if none yet). */
	double lastProjectionMs() const { return m_lastProjectionMs; }
	/** Milliseconds the last octomap insertion took. */
	double lastInsertionMs() const { return m_lastInsertMs; }

	std::string asString() const override;
	void saveMetricMapRepresentationToFile(const std::string& filNamePrefix) const override;

	MAP_DEFINITION_START(COctoMapGrid2D)
	float min_x = -10.0f, max_x = 10.0f, min_y = -10.0f, max_y = 10.0f, resolution = 0.05f;
	mrpt::maps::COctoMapGrid2D::TOctoOptions octoOpts;
	MAP_DEFINITION_END(COctoMapGrid2D)

   protected:
	void internal_clear() override;
	bool internal_insertObservation(
		const mrpt::obs::CObservation& obs,
		const std::optional<const mrpt::poses::CPose3D>& robotPose = std::nullopt) override;

   private:
	void applyOctoOptions();

	COctoMap m_octomap;
	bool m_dirty = false;
	int m_sinceProjection = 0;
	double m_lastProjectionMs = 0, m_lastInsertMs = 0;
};

}  // namespace mrpt::maps
