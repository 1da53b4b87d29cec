#include "CSimulatedSceneSensor.h"

#include <gam/sim/KinectObservation.h>
#include <mrpt/core/Clock.h>
#include <mrpt/core/exceptions.h>
#include <mrpt/obs/CObservationOdometry.h>

#include <chrono>

IMPLEMENTS_GENERIC_SENSOR(CSimulatedSceneSensor, gam_test)

namespace gam_test
{
std::atomic<size_t> CSimulatedSceneSensor::s_frames{0};

CSimulatedSceneSensor::CSimulatedSceneSensor() { m_sensorLabel = "SIM_KINECT"; }

size_t CSimulatedSceneSensor::framesDelivered() { return s_frames.load(); }

void CSimulatedSceneSensor::loadConfig_sensorSpecific(
	const mrpt::config::CConfigFileBase& cfg, const std::string& section)
{
	// Like a real driver: a missing required key is an exception from loadConfig().
	m_scenePath = cfg.read_string(section, "scene", "", true);
	m_width = cfg.read_int(section, "width", 0);
	m_height = cfg.read_int(section, "height", 0);
	m_depth = cfg.read_bool(section, "depth", true);
	m_odometry = cfg.read_bool(section, "odometry", false);
	m_noise = cfg.read_bool(section, "noise", true);
	m_seed = unsigned(cfg.read_int(section, "seed", 1));
	m_failInitialize = cfg.read_string(section, "fail_initialize", "");
	m_failAfter = cfg.read_int(section, "fail_after", -1);
}

void CSimulatedSceneSensor::initialize()
{
	if (!m_failInitialize.empty()) THROW_EXCEPTION(m_failInitialize);
	// A driver opens its device here; this one reads its scene.
	m_scene = std::make_unique<gam::sim::SceneFile>(gam::sim::parseSceneFile(m_scenePath));
	if (m_width > 0) m_scene->kinect.width = m_width;
	if (m_height > 0) m_scene->kinect.height = m_height;
	m_scene->kinect.noise = m_noise;
	m_kinect = std::make_unique<gam::sim::KinectModel>(m_scene->kinect);
	m_path = gam::sim::samplePath(m_scene->path);
	m_rng.seed(m_seed);
	m_state = ssWorking;
}

void CSimulatedSceneSensor::doProcess()
{
	if (m_failAfter >= 0 && long(m_step) >= m_failAfter)
	{
		m_state = ssError;
		THROW_EXCEPTION("simulated camera unplugged");
	}
	const gam::sim::Pose2& p = m_path[std::min(m_step, m_path.size() - 1)];
	m_step++;
	const auto now = mrpt::Clock::now();
	std::vector<mrpt::serialization::CSerializable::Ptr> objs;
	if (m_odometry)
	{
		auto o = mrpt::obs::CObservationOdometry::Create();
		o->sensorLabel = m_sensorLabel + "_ODO";
		// Before the frame: a robot base reports where it is, then the camera sees.
		o->timestamp = now - std::chrono::microseconds(1);
		o->odometry = mrpt::poses::CPose2D(p.x, p.y, p.yaw);
		objs.push_back(o);
	}
	if (m_depth)
	{
		const auto robot = gam::sim::Pose3::fromXYZYPR(p.x, p.y, 0, p.yaw, 0, 0);
		const gam::sim::DepthFrame fr = m_kinect->render(m_scene->scene, robot * m_scene->kinect_pose, m_rng);
		const Eigen::Vector3d a = m_scene->kinect_pose.ypr();
		const auto& t = m_scene->kinect_pose.t;
		auto k = gam::sim::toKinectObservation(
			m_scene->kinect, fr, mrpt::poses::CPose3D(t.x(), t.y(), t.z(), a[0], a[1], a[2]));
		k->sensorLabel = m_sensorLabel;
		k->timestamp = now;
		objs.push_back(k);
	}
	appendObservations(objs);
	if (m_depth) s_frames++;
}

}  // namespace gam_test
