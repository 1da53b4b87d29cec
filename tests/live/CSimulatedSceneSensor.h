// A test sensor driver: plays a gam-simulate scene through MRPT's
// CGenericSensor interface, as a camera driver such as COpenNI2Sensor would
// deliver its frames, so the live mode is tested on the code path real
// drivers take. Test code only: registered by the tests (in-process) or by
// the plugin module libgam_test_sim_sensor.so (for the program, --plugins).
#pragma once

#include <gam/sim/Path.h>
#include <gam/sim/SceneFile.h>
#include <gam/sim/Sensors.h>
#include <mrpt/hwdrivers/CGenericSensor.h>
#include <mrpt/poses/CPose3D.h>

#include <atomic>
#include <memory>
#include <random>
#include <string>
#include <vector>

namespace gam_test
{
/** Keys of its .ini section (besides driver, process_rate, sensorLabel):
 *  - scene = FILE.scene (required): the scene, its kinect and path;
 *  - width, height: the depth image size (default the scene's, 512 x 424);
 *  - depth = true: deliver a CObservation3DRangeScan per doProcess();
 *  - odometry = false: deliver a CObservationOdometry with the true path pose
 *    (just before the frame's timestamp when both are on);
 *  - noise = true, seed = 1: the simulator's sensor noise;
 *  - fail_initialize = TEXT: initialize() throws TEXT (tests the error path);
 *  - fail_after = N: the (N+1)-th doProcess() throws (a camera unplugged).
 * Step i of doProcess() is the path's pose i; after the last pose the robot
 * stays there and frames keep coming, as from a camera on a robot at rest. */
class CSimulatedSceneSensor : public mrpt::hwdrivers::CGenericSensor
{
	DEFINE_GENERIC_SENSOR(CSimulatedSceneSensor)

   public:
	CSimulatedSceneSensor();
	void initialize() override;
	void doProcess() override;

	/** Frames delivered by all instances since the process started: tests
	 * wait on it before they raise SIGINT. */
	static size_t framesDelivered();

   protected:
	void loadConfig_sensorSpecific(const mrpt::config::CConfigFileBase& cfg, const std::string& section) override;

   private:
	std::string m_scenePath, m_failInitialize;
	int m_width = 0, m_height = 0;
	bool m_depth = true, m_odometry = false, m_noise = true;
	unsigned m_seed = 1;
	long m_failAfter = -1;
	size_t m_step = 0;
	std::unique_ptr<gam::sim::SceneFile> m_scene;
	std::unique_ptr<gam::sim::KinectModel> m_kinect;
	std::vector<gam::sim::Pose2> m_path;
	std::mt19937 m_rng;
	static std::atomic<size_t> s_frames;
};

}  // namespace gam_test
