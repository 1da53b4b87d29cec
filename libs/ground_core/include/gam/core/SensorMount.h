// Ground-aware mapping for MRPT
// The camera mount measured from the floor (issue #15): every frame's ground
// plane, brought into the sensor's own frame, gives the sensor's height above
// the floor, its pitch and its roll. Pure code.
#pragma once

#include <Eigen/Geometry>
#include <cmath>
#include <cstddef>
#include <optional>
#include <vector>

#include "gam/core/Parameters.h"
#include "gam/core/PlaneFit.h"

namespace gam
{
/** Height above the floor [m], pitch and roll [rad] of a sensor on the robot,
 * in MRPT's convention for `sensorPose` (R = Rz(yaw) Ry(pitch) Rx(roll); robot
 * and sensor frames x forward, y left, z up; positive pitch looks down).
 * x, y and yaw are not observable from a floor: any of them leaves the floor
 * where it is. */
struct SensorMount
{
	double height = 0, pitch = 0, roll = 0;
};

/** The plane `world` (in the frame of the map) in the sensor's own frame,
 * given the pose `worldFromSensor` that placed the sensor's points in that
 * frame (robot pose composed with the declared sensorPose). The plane in the
 * sensor frame is what the camera measured, whatever pose was declared. */
struct SensorPlane
{
	Eigen::Vector3d normal;  ///< unit
	double d = 0;            ///< normal . p + d = 0
};
SensorPlane planeInSensorFrame(const Plane& world, const Eigen::Isometry3d& worldFromSensor);

/** The mount that puts this floor at z = 0 under the robot: with the floor's
 * unit normal n in the sensor frame, oriented toward the sensor (d > 0),
 * n = R^T (0, 0, 1) = (-sin pitch, cos pitch sin roll, cos pitch cos roll)
 * and the height is d. std::nullopt if the normal is not finite or the floor
 * plane passes through the sensor (d <= 0 after orientation). */
std::optional<SensorMount> mountFromFloor(const SensorPlane& floorInSensor);

/** How far from the declared mount the floor may be (issue #27: a rough
 * guess of height +- 0.3 m, pitch +- 20 deg, roll +- 10 deg). */
struct FloorSearchParams
{
	double height_tolerance = 0.30;            ///< [m]
	double pitch_tolerance = 20 * M_PI / 180;  ///< [rad]
	double roll_tolerance = 10 * M_PI / 180;   ///< [rad]
	/** A point within this of a candidate plane is its inlier: 2 cm, or
	 * 1 % of the point's range where the camera is noisier (stereo, far). [m] */
	double inlier_distance = 0.02;
	double inlier_distance_per_m = 0.01;
	int iterations = 400;
	size_t min_inliers = 200;
};
/** Searches sensor-frame points (MRPT's sensor frame) for the floor of a
 * camera mounted about at `guess`: RANSAC over planes through 3 points whose
 * mount (mountFromFloor) lies within the tolerances of the guess; the one
 * with the most inliers, refitted to them (total least squares). A table top
 * or a wall lies outside the tolerances (a table is more than 0.3 m nearer
 * than the floor, a wall is 90 deg off), so the floor wins even when it
 * fills less of the image. The result does not depend on the guess as long
 * as the floor is within the tolerances of it: calibrating again from the
 * answer finds the same plane (same points, same `seed`). std::nullopt if no
 * plane has min_inliers. */
std::optional<SensorPlane> searchFloor(
	const std::vector<Eigen::Vector3d>& sensorPoints, const SensorMount& guess, const FloorSearchParams& p,
	unsigned seed = 1, size_t* inliers = nullptr);

/** A mount estimated from many frames: the mean of the frames kept, and the
 * standard error of each mean (std / sqrt(used)). */
struct MountEstimate
{
	SensorMount mean, standard_error;
	size_t used = 0;  ///< frames kept
};

/** Robust estimate over frames: a frame farther than 3 robust sigmas
 * (1.4826 x the median absolute deviation, but at least 5 mm / 0.1 deg) from
 * the median in height, pitch or roll is rejected (a frame on a ramp, a plane
 * fitted to a table top); the others are averaged. used = 0 for no frames. */
MountEstimate estimateMount(const std::vector<SensorMount>& frames);

/** The online check of the declared mount (CGroundAwareOccupancyGrid). */
struct MountCheckParams
{
	bool enabled = true;         ///< compare every frame's floor with the declared mount
	double tolerance_z = 0.03;   ///< [m] a frame disagrees beyond this in height...
	double tolerance_deg = 1.5;  ///< ... or beyond this in pitch or roll [deg]
	/** This many disagreeing frames in a row raise the alarm; as many agreeing
	 * ones in a row clear it. */
	int alarm_frames = 5;
	/** Frames in the running estimate (median of the last ones). */
	int window = 31;
	/** Map with the measured height, pitch and roll (the running estimate,
	 * once it has `alarm_frames` frames) instead of the declared ones. */
	bool use_measured = false;

	template <class Self, class Visit>
	static void forEachParam(Self& p, Visit&& visit)
	{
		visit(ParamInfo{"mount_check", 0, 1, "compare each frame's floor with the declared sensor mount"}, p.enabled);
		visit(ParamInfo{"mount_tolerance_z", 1e-4, 10, "mount height disagreement threshold [m]"}, p.tolerance_z);
		visit(
			ParamInfo{"mount_tolerance_deg", 0.01, 45, "mount pitch/roll disagreement threshold [deg]"},
			p.tolerance_deg);
		visit(
			ParamInfo{"mount_alarm_frames", 1, 100000, "disagreeing frames in a row that raise the mount alarm"},
			p.alarm_frames);
		visit(ParamInfo{"mount_window", 1, 10000, "frames in the running mount estimate (median)"}, p.window);
		visit(
			ParamInfo{"use_measured_mount", 0, 1, "map with the measured sensor height, pitch and roll"},
			p.use_measured);
	}
};

/** What the check has seen so far. */
struct MountStatus
{
	size_t frames_checked = 0;      ///< frames with a floor plane
	size_t frames_disagreeing = 0;  ///< of those, beyond the tolerances
	size_t alarms_raised = 0;       ///< times the alarm went on
	int disagreeing_in_a_row = 0, agreeing_in_a_row = 0;
	bool alarm = false;
	bool has_last = false, has_estimate = false;
	SensorMount declared;  ///< of the last checked frame
	SensorMount last;      ///< measured on the last checked frame
	SensorMount estimate;  ///< median of the last `window` measurements
};

/** Compares each frame's measured mount with the declared one. Pure code;
 * no allocation per frame after the first `window` frames. */
class MountMonitor
{
   public:
	explicit MountMonitor(const MountCheckParams& p = {}) { setParams(p); }
	void setParams(const MountCheckParams& p);
	const MountCheckParams& params() const { return m_params; }
	/** One frame: the mount it was mapped with and, if the frame had a floor,
	 * the mount that floor says. */
	void update(const SensorMount& declared, const std::optional<SensorMount>& measured);
	const MountStatus& status() const { return m_status; }
	void reset();

   private:
	MountCheckParams m_params;
	MountStatus m_status;
	std::vector<SensorMount> m_ring;  // the last `window` measurements
	size_t m_next = 0;
	std::vector<double> m_scratch;
};
}  // namespace gam
