// Ground-aware mapping for MRPT -- ground-aware-viewer, the GUI-free model.
//
// ViewerModel: a rawlog's frames grouped into steps (each 3D scan with the 2D
// scans before it), the three grids (ground-aware, height-band, octomap) fed
// step by step, the ground-aware options (editable: a change re-runs the
// current step from a snapshot of the grid taken before it). What is drawn
// is ViewerScene.h. Used by the wx GUI (ViewerApp.cpp), its batch mode and
// tests/viewer.
#pragma once

#include <mrpt/maps/CElevation25DMap.h>
#include <mrpt/maps/CGroundAwareOccupancyGrid.h>
#include <mrpt/maps/CHeightBandOccupancyGrid.h>
#include <mrpt/maps/COctoMapGrid2D.h>
#include <mrpt/math/TPoint3D.h>
#include <mrpt/obs/CObservation.h>
#include <mrpt/poses/CPoint3D.h>
#include <mrpt/poses/CPose3D.h>

#include <memory>
#include <string>
#include <vector>

namespace gam::viewer
{
/** One step of the viewer: the 2D scans since the previous 3D scan, then the
 * 3D scan (the last observation; a rawlog without 3D scans has one step per
 * 2D scan). */
struct Step
{
	std::vector<mrpt::obs::CObservation::Ptr> obs;
	std::vector<mrpt::poses::CPose3D> poses;  ///< robot pose of each observation
	bool has3D = false;
	size_t index3D = 0;     ///< position of the 3D scan in obs (when has3D)
	size_t firstFrame = 0;  ///< frame index (as ground-aware-mapper counts) of obs[0]
};

/** Per-step timings [ms] of each map's insertObservation(). */
struct StepTiming
{
	double groundAware = 0, heightBand = 0, octomap = 0, elevation = 0;
};

class ViewerModel
{
   public:
	ViewerModel();

	/** Reads the whole rawlog (either format; see gam::mapper::RawlogFrameReader).
	 * Throws std::runtime_error. Resets the maps. */
	void openRawlog(const std::string& path);
	/** Maps from an .ini in ground-aware-mapper's format (section `section`):
	 * the first map of each of the three grid classes and the first
	 * CElevation25DMap are used; missing ones get the class defaults (the
	 * elevation map then covers +-10 m). Empty path = class defaults. Throws on a bad .ini.
	 * Resets the maps (re-runs up to the current step). */
	void loadConfig(const std::string& iniPath, const std::string& section = "map");
	/** The ground-aware and height-band grids start from a stock occupancy
	 * grid (`.gridmap[.gz]` or ROS map_server `.yaml`, gam::maps::readStockGrid),
	 * also after a later loadConfig(); "" = from nothing again. Throws
	 * std::runtime_error on a bad file (the maps are then unchanged). Re-runs up
	 * to the current step. */
	void loadInitialMap(const std::string& path);
	const std::string& initialMapPath() const { return m_initialMapPath; }
	/** Writes the ground-aware grid as a stock COccupancyGridMap2D, which any
	 * MRPT tool reads: `.yaml` = ROS map_server pair (+ `.pgm` beside it),
	 * anything else = a gzip-serialized `.gridmap`. Throws std::runtime_error. */
	void saveGroundAwareAsStockGrid(const std::string& path) const;

	size_t stepCount() const { return m_steps.size(); }
	const Step& step(size_t i) const { return m_steps.at(i); }
	/** Index of the step whose result is shown, -1 before the first. */
	int current() const { return m_current; }
	/** Processes steps until `k` is the current one (forward incrementally,
	 * backward by re-running from the start). */
	void seek(int k);
	bool next();  ///< false at the end
	void prev() { seek(m_current - 1); }
	/** Restores the ground-aware grid as it was before the current step and
	 * inserts the step again (with the current groundOptions). */
	void rerunCurrent();

	/** The ground-aware options in use; to change them, edit a copy and call applyGroundOptions(). */
	const mrpt::maps::CGroundAwareOccupancyGrid::TGroundAwareOptions& groundOptions() const
	{
		return m_ga->groundOptions();
	}
	/** Validates (throws std::invalid_argument, options unchanged then) and re-runs the current step. */
	void applyGroundOptions(const mrpt::maps::CGroundAwareOccupancyGrid::TGroundAwareOptions& o);

	const mrpt::maps::CGroundAwareOccupancyGrid& groundAware() const { return *m_ga; }
	const mrpt::maps::CHeightBandOccupancyGrid& heightBand() const { return *m_hb; }
	const mrpt::maps::COctoMapGrid2D& octomap() const { return *m_oc; }
	/** The accumulated 2.5D map (CElevation25DMap). */
	const mrpt::maps::CElevation25DMap& elevation() const { return *m_el; }
	/** Map-frame points of every 3D scan up to the current step (decimated more). */
	const std::vector<mrpt::math::TPoint3Df>& mapPoints() const { return m_mapPoints; }

	/** Robot pose at the current step (its last observation). */
	mrpt::poses::CPose3D currentPose() const;
	/** Robot path up to the current step. */
	std::vector<mrpt::poses::CPose3D> pathSoFar() const;
	/** Map-frame points of the current step's 3D scan (decimated), empty if none. */
	const std::vector<mrpt::math::TPoint3Df>& framePoints() const { return m_points; }
	const StepTiming& timing() const { return m_timing; }
	/** Multi-line text: step, frame, detection status, voxel classes, stage timings. */
	std::string statusText() const;
	std::string rawlogPath() const { return m_rawlog; }

   private:
	void resetMaps();
	void applyInitialMap();
	void insertStep(size_t k);
	void updatePoints();

	std::string m_rawlog;
	std::string m_initialMapPath, m_configPath, m_configSection = "map";
	std::shared_ptr<mrpt::maps::COccupancyGridMap2D> m_initialMap;
	std::vector<Step> m_steps;
	int m_current = -1;
	std::shared_ptr<mrpt::maps::CGroundAwareOccupancyGrid> m_ga, m_gaTemplate, m_gaBefore;
	std::shared_ptr<mrpt::maps::CHeightBandOccupancyGrid> m_hb, m_hbTemplate;
	std::shared_ptr<mrpt::maps::COctoMapGrid2D> m_oc, m_ocTemplate;
	std::shared_ptr<mrpt::maps::CElevation25DMap> m_el, m_elTemplate;
	std::vector<mrpt::math::TPoint3Df> m_points, m_mapPoints;
	StepTiming m_timing;
};

}  // namespace gam::viewer
