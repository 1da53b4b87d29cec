// Real depth frames from ../shared/data/real (see its README).
#include <gtest/gtest.h>
#include <mrpt/maps/CGroundAwareOccupancyGrid.h>
#include <mrpt/maps/CElevation25DMap.h>
#include <mrpt/obs/CObservation3DRangeScan.h>
#include <mrpt/obs/CRawlog.h>
#include <mrpt/system/filesystem.h>

#include <iostream>

using namespace mrpt::maps;
using namespace mrpt::obs;

namespace
{
std::string realData(const std::string& rel) { return std::string(GAM_REAL_DATA_DIR) + "/" + rel; }

CObservation3DRangeScan::Ptr firstScan(const std::string& file)
{
	CRawlog rl;
	if (!rl.loadFromRawLogFile(file)) return {};
	for (size_t i = 0; i < rl.size(); i++)
	{
		if (rl.getType(i) == CRawlog::etObservation)
			if (auto o = std::dynamic_pointer_cast<CObservation3DRangeScan>(rl.getAsObservation(i))) { o->load(); return o; }
		if (rl.getType(i) == CRawlog::etSensoryFrame)
			if (auto o = rl.getAsObservations(i)->getObservationByClass<CObservation3DRangeScan>()) { o->load(); return o; }
	}
	return {};
}
}  // namespace

TEST(RealData, Explore)
{
	for (const char* f : {"mrpt_3d_obs_ground/test-3d-obs-ground.rawlog", "mrpt_tests_rgbd/tests_rgbd.rawlog",
						  "pcl_milk_bottles_on_carpet/pcl_milk_bottles_on_carpet.rawlog", "pcl_office1/pcl_office1.rawlog",
						  "pcl_five_people_corridor/pcl_five_people_corridor.rawlog", "walrus_kinect2_stairs_up/walrus_kinect2_stairs_up.rawlog"})
	{
		auto o = firstScan(realData(f));
		ASSERT_TRUE(o) << f;
		CGroundAwareOccupancyGrid g;
		g.insertObservation(*o);
		const auto& d = g.lastFrame();
		std::cout << f << ": " << o->rangeImage.cols() << "x" << o->rangeImage.rows() << " pts " << d.points
				  << " cells " << g.lastFrameElevation().observedCount() << "\n  " << d.detection.describe()
				  << "\n  ism g/o/d/oh/oor " << d.ism.ground << "/" << d.ism.obstacle << "/" << d.ism.drop << "/"
				  << d.ism.overhead << "/" << d.ism.out_of_range << " dropray " << d.ism.drop_ray_cells
				  << "\n  ms proj " << d.ms_projection << " out " << d.ms_outliers << " rrt " << d.ms_ground << " ism "
				  << d.ms_ism << " upd " << d.ms_update << " total " << d.ms_total << "\n";
		g.saveMetricMapRepresentationToFile(std::string("/tmp/explore_") + mrpt::system::extractFileName(f));
	}
}
