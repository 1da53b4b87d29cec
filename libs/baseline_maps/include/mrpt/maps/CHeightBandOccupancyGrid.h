// Ground-aware mapping for MRPT
#pragma once

#include <mrpt/config/CLoadableOptions.h>
#include <mrpt/maps/COccupancyGridMap2D.h>

#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/obs/T3DPointsTo2DScanParams.h>
#include "gam/core/Parameters.h"

namespace mrpt::maps
{
/** The paper's baseline, "pointcloud_to_laserscan + a 2D local map": every
 * CObservation3DRangeScan is turned into a virtual 2D scan with
 * CObservation3DRangeScan::convertTo2DScan(use_origin_sensor_pose = true),
 * keeping only the points whose robot-frame z is in [z_min, z_max], and that
 * scan goes through COccupancyGridMap2D's beam model. Obstacles lower than
 * z_min (small boxes, cables) and everything below the floor (holes, drops)
 * are invisible to it, by design. CObservation2DRangeScan goes straight to the
 * base class.
 *
 * .ini: the standard COccupancyGridMap2D sections plus
 * \code
 * [<prefix>_bandOpts]
 * z_min = 0.2               ; robot-frame band [m]
 * z_max = 1.5
 * oversampling_ratio = 1.2  ; virtual rays per image column
 * \endcode
 * Defaults of _insertOpts differ from the base class: a converted depth scan
 * reports "no return" for every column without a point in the band, which is
 * not evidence of free space (considerInvalidRangesAsFreeSpace = false), and the
 * virtual scan is planar by construction (horizontalTolerance = 10 deg).
 */
class CHeightBandOccupancyGrid : public COccupancyGridMap2D
{
	DEFINE_SERIALIZABLE(CHeightBandOccupancyGrid, mrpt::maps)

   public:
	CHeightBandOccupancyGrid(
		float min_x = -10.0f, float max_x = 10.0f, float min_y = -10.0f, float max_y = 10.0f, float resolution = 0.05f);

	struct THeightBandOptions : public mrpt::config::CLoadableOptions
	{
		double z_min = 0.2;               ///< lowest robot-frame z kept [m]
		double z_max = 1.5;               ///< highest robot-frame z kept [m]
		double oversampling_ratio = 1.2;  ///< virtual rays = image width * this

		template <class Self, class Visit>
		static void forEachParam(Self& o, Visit&& visit)
		{
			visit(gam::ParamInfo{"z_min", -100, 100, "lowest robot-frame z turned into the virtual scan [m]"}, o.z_min);
			visit(
				gam::ParamInfo{"z_max", -100, 100, "highest robot-frame z turned into the virtual scan [m]"}, o.z_max);
			visit(
				gam::ParamInfo{"oversampling_ratio", 0.1, 10, "virtual rays per depth-image column"},
				o.oversampling_ratio);
		}
		void loadFromConfigFile(const mrpt::config::CConfigFileBase& source, const std::string& section) override;
		void saveToConfigFile(mrpt::config::CConfigFileBase& target, const std::string& section) const override;
		/** Throws std::invalid_argument naming the key and its range. */
		void validate() const;
	} bandOptions;

	/** The virtual scan made from the last 3D observation (robot frame). */
	const mrpt::obs::CObservation2DRangeScan* lastVirtualScan() const { return m_hasLastScan ? &m_lastScan : nullptr; }
	/** What the map passes to CObservation3DRangeScan::convertTo2DScan() for a
	 * frame of sensor `sensorLabel`: bandOptions, robot-frame z, the sensor's
	 * own pose on the robot. */
	mrpt::obs::T3DPointsTo2DScanParams scanParams(const std::string& sensorLabel) const;

	std::string asString() const override;

	MAP_DEFINITION_START(CHeightBandOccupancyGrid)
	float min_x = -10.0f, max_x = 10.0f, min_y = -10.0f, max_y = 10.0f, resolution = 0.05f;
	mrpt::maps::COccupancyGridMap2D::TInsertionOptions insertionOpts;
	mrpt::maps::COccupancyGridMap2D::TLikelihoodOptions likelihoodOpts;
	mrpt::maps::CHeightBandOccupancyGrid::THeightBandOptions bandOpts;
	MAP_DEFINITION_END(CHeightBandOccupancyGrid)

   protected:
	bool internal_insertObservation(
		const mrpt::obs::CObservation& obs,
		const std::optional<const mrpt::poses::CPose3D>& robotPose = std::nullopt) override;

   private:
	mrpt::obs::CObservation2DRangeScan m_lastScan;
	bool m_hasLastScan = false;
};

}  // namespace mrpt::maps
