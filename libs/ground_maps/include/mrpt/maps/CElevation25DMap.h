// Ground-aware mapping for MRPT
#pragma once

#include <mrpt/config/CLoadableOptions.h>
#include <mrpt/maps/CMetricMap.h>
#include <mrpt/maps/CPointsMap.h>
#include <mrpt/obs/obs_frwds.h>
#include <mrpt/poses/CPose3D.h>

#include "gam/core/DepthProjector.h"
#include "gam/core/ElevationGrid.h"

namespace mrpt::maps
{
/** The 2.5D map of the paper: an m_x x m_y grid at resolution d_r where every
 * cell keeps z-min, z-max and the sample count N_z of the points that fell in
 * it (after a per-frame 3-sigma outlier filter), plus an optional inverse
 * distance weighting (IDW) densification of empty cells.
 *
 * Inserts:
 *  - mrpt::obs::CObservation3DRangeScan straight from its range image (depth or
 *    range, rangeUnits, intrinsics, sensorPose on the robot); its points3D if
 *    it has no range image;
 *  - mrpt::obs::CObservation2DRangeScan (Leddar, lidars);
 *  - mrpt::obs::CObservationPointCloud, and any CPointsMap via insertPointCloud().
 * Invalid pixels (0, outside [min_range, max_range]) are skipped. The grid has a
 * fixed extent (like CHeightGridMap2D): points outside it are dropped.
 *
 * .ini (section prefix P as in any CMultiMetricMap):
 * \code
 * [P]
 * CElevation25DMap_count=1
 * [P_CElevation25DMap_00_creationOpts]
 * min_x=-5  max_x=5  min_y=-5  max_y=5  resolution=0.05   ; m_x = m_y = 200, d_r = 0.05
 * [P_CElevation25DMap_00_insertOpts]
 * z_min=-2  z_max=3  min_range=0  max_range=10  decimation=1
 * outlier_filter=true  outlier_sigmas=3  outlier_min_count=4
 * idw_radius=0  idw_power=2  idw_min_neighbours=3
 * \endcode
 */
class CElevation25DMap : public CMetricMap
{
	DEFINE_SERIALIZABLE(CElevation25DMap, mrpt::maps)

   public:
	CElevation25DMap(
		double x_min = -5, double x_max = 5, double y_min = -5, double y_max = 5, double resolution = 0.05);

	/** Re-creates the grid (empties it). Throws std::invalid_argument. */
	void setSize(double x_min, double x_max, double y_min, double y_max, double resolution);

	/** What is inserted and how: the projection band and ranges, the 3-sigma
	 * rule and IDW. The keys are those of the core structs (declared once, in
	 * gam/core: the ground-aware grid reads the same keys). */
	struct TInsertionOptions : public mrpt::config::CLoadableOptions
	{
		/** z_min, z_max in the map frame [m]; ranges along the sensor axis / ray
		 * [m] (the observation's own maxRange applies too); decimation of range images. */
		gam::ProjectionFilter projection = {0.0f, 10.0f, -2.0f, 3.0f, 1};
		gam::OutlierFilterParams outliers;  ///< the 3-sigma rule per cell and frame
		gam::IdwParams idw = {0, 2.0f, 3};  ///< radius 0 = no densification

		template <class Self, class Visit>
		static void forEachParam(Self& o, Visit&& visit)
		{
			gam::ProjectionFilter::forEachParam(o.projection, visit);
			gam::OutlierFilterParams::forEachParam(o.outliers, visit);
			gam::IdwParams::forEachParam(o.idw, visit);
		}
		void loadFromConfigFile(const mrpt::config::CConfigFileBase& source, const std::string& section) override;
		void saveToConfigFile(mrpt::config::CConfigFileBase& target, const std::string& section) const override;
		/** Throws std::invalid_argument naming the key and the allowed range. */
		void validate() const;
	};
	const TInsertionOptions& insertionOptions() const { return m_options; }
	/** Validates `o` (throws std::invalid_argument, keeping the current
	 * options), then uses it for the next insertions. */
	void setInsertionOptions(const TInsertionOptions& o);

	/** The grid (read-only), for RRT-GPD, apps and tests. */
	const gam::ElevationGrid& grid() const { return m_grid; }

	/** Inserts a point cloud whose points are in the frame `pose` (map frame for
	 * the identity). Returns the number of points kept. */
	size_t insertPointCloud(const mrpt::maps::CPointsMap& pts, const mrpt::poses::CPose3D& pose = {});

	/** Minimum and maximum observed z over the whole grid; false if empty. */
	bool getMinMaxHeight(float& zmin, float& zmax) const;

	// CMetricMap interface
	bool isEmpty() const override;
	void saveMetricMapRepresentationToFile(const std::string& filNamePrefix) const override;
	void getVisualizationInto(mrpt::opengl::CSetOfObjects& outObj) const override;
	std::string asString() const override;
	float compute3DMatchingRatio(
		const mrpt::maps::CMetricMap* otherMap, const mrpt::poses::CPose3D& otherMapPose,
		const TMatchingRatioParams& params) const override
	{
		return 0;
	}

	/** Writes PNGs of z-max (`<prefix>_zmax.png`), of the height span
	 * (`<prefix>_span.png`) and of N_z (`<prefix>_count.png`): one pixel per
	 * cell, +y up, black = no data; the colour scale is in `<prefix>_scale.txt`. */
	void saveAsPngs(const std::string& prefix) const;

	MAP_DEFINITION_START(CElevation25DMap)
	double min_x = -5, max_x = 5, min_y = -5, max_y = 5, resolution = 0.05;
	mrpt::maps::CElevation25DMap::TInsertionOptions insertionOpts;
	MAP_DEFINITION_END(CElevation25DMap)

   protected:
	void internal_clear() override;
	bool internal_insertObservation(
		const mrpt::obs::CObservation& obs,
		const std::optional<const mrpt::poses::CPose3D>& robotPose = std::nullopt) override;
	double internal_computeObservationLikelihood(
		const mrpt::obs::CObservation& obs, const mrpt::poses::CPose3D& takenFrom) const override
	{
		return 0;
	}
	bool internal_canComputeObservationLikelihood(const mrpt::obs::CObservation& obs) const override { return false; }

   private:
	void finishInsertion();

	TInsertionOptions m_options;
	gam::ElevationGrid m_grid;
	// Scratch reused between insertions (not serialized).
	gam::BinnedPoints m_bins;
	gam::DepthProjector m_projector;
};

}  // namespace mrpt::maps
