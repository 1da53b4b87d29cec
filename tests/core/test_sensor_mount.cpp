// Ground-aware mapping for MRPT
// The camera mount from the floor plane (issue #15): hand-computed cases in
// MRPT's yaw/pitch/roll convention (R = Rz(yaw) Ry(pitch) Rx(roll)).
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "gam/core/SensorMount.h"
#include "test_helpers.h"

using namespace gam;
using gamtest::deg2rad;
using gamtest::rad2deg;

namespace
{
Eigen::Isometry3d pose(double x, double y, double z, double yawDeg, double pitchDeg, double rollDeg)
{
	Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
	T.linear() = (Eigen::AngleAxisd(deg2rad(yawDeg), Eigen::Vector3d::UnitZ()) *
				  Eigen::AngleAxisd(deg2rad(pitchDeg), Eigen::Vector3d::UnitY()) *
				  Eigen::AngleAxisd(deg2rad(rollDeg), Eigen::Vector3d::UnitX()))
					 .toRotationMatrix();
	T.translation() = Eigen::Vector3d(x, y, z);
	return T;
}
}  // namespace

TEST(SensorMount, PitchAndRollFromTheFloorNormalByHand)
{
	// A Kinect 0.8 m high pitched 25 deg down: the floor's normal in its frame is
	// R^T (0,0,1) = (-sin 25, 0, cos 25) = (-0.4226183, 0, 0.9063078).
	auto m = mountFromFloor({{-0.4226183, 0.0, 0.9063078}, 0.8});
	ASSERT_TRUE(m);
	EXPECT_NEAR(m->height, 0.8, 1e-6);  // the normal is given to 7 digits
	EXPECT_NEAR(rad2deg(m->pitch), 25.0, 1e-4);
	EXPECT_NEAR(rad2deg(m->roll), 0.0, 1e-9);
	// Pitch 20, roll 5: (-sin 20, cos 20 sin 5, cos 20 cos 5)
	// = (-0.3420201, 0.9396926 * 0.0871557, 0.9396926 * 0.9961947) = (-0.3420201, 0.0818996, 0.9361168).
	m = mountFromFloor({{-0.3420201, 0.0818996, 0.9361168}, 0.55});
	ASSERT_TRUE(m);
	EXPECT_NEAR(m->height, 0.55, 1e-6);
	EXPECT_NEAR(rad2deg(m->pitch), 20.0, 1e-4);
	EXPECT_NEAR(rad2deg(m->roll), 5.0, 1e-4);
	// The same plane written the other way round (-n, -d), and not normalized
	// (x 2): the same mount.
	m = mountFromFloor({{0.6840402, -0.1637992, -1.8722336}, -1.1});
	ASSERT_TRUE(m);
	EXPECT_NEAR(m->height, 0.55, 1e-6);
	EXPECT_NEAR(rad2deg(m->pitch), 20.0, 1e-4);
	EXPECT_NEAR(rad2deg(m->roll), 5.0, 1e-4);
}

TEST(SensorMount, WorldPlaneBackIntoTheSensorFrame)
{
	// Floor z = 0; robot at (1, 2, 0), yaw 30; sensor on it at (0.1, 0, 0.8),
	// pitch 25, roll -3. In the sensor frame the floor's normal is the third row
	// of R_sensor (the robot's yaw does not move z): (-sin 25, cos 25 sin(-3),
	// cos 25 cos(-3)), and the sensor is 0.8 m above it.
	const Eigen::Isometry3d worldFromSensor = pose(1, 2, 0, 30, 0, 0) * pose(0.1, 0, 0.8, 0, 25, -3);
	const SensorPlane s = planeInSensorFrame(Plane{0, 0, 1, 0}, worldFromSensor);
	EXPECT_NEAR(s.normal.x(), -0.4226183, 1e-6);
	EXPECT_NEAR(s.normal.y(), 0.9063078 * -0.0523360, 1e-6);
	EXPECT_NEAR(s.normal.z(), 0.9063078 * 0.9986295, 1e-6);
	EXPECT_NEAR(s.d, 0.8, 1e-9);
	const auto m = mountFromFloor(s);
	ASSERT_TRUE(m);
	EXPECT_NEAR(m->height, 0.8, 1e-9);
	EXPECT_NEAR(rad2deg(m->pitch), 25.0, 1e-6);
	EXPECT_NEAR(rad2deg(m->roll), -3.0, 1e-6);
}

TEST(SensorMount, AWrongDeclaredPoseDoesNotFoolIt)
{
	// The camera is really 0.9 m high, pitched 30 deg; the .ini declares 0.8 m
	// and 25 deg. The map places the points with the declared pose, so its floor
	// plane is tilted; brought back with that same pose it is the true one.
	const SensorPlane truth{{-std::sin(deg2rad(30)), 0, std::cos(deg2rad(30))}, 0.9};
	const Eigen::Isometry3d declared = pose(0, 0, 0, 0, 0, 0) * pose(0.1, 0, 0.8, 0, 25, 0);
	// p_w = R p_s + t: n_w = R n_s, d_w = d_s - n_w . t.
	const Eigen::Vector3d nw = declared.linear() * truth.normal;
	Plane seen{nw.x(), nw.y(), nw.z(), truth.d - nw.dot(declared.translation())};
	EXPECT_GT(seen.tiltAngle(), deg2rad(4.9));  // the map's floor is tilted by 5 deg
	const auto m = mountFromFloor(planeInSensorFrame(seen, declared));
	ASSERT_TRUE(m);
	EXPECT_NEAR(m->height, 0.9, 1e-9);
	EXPECT_NEAR(rad2deg(m->pitch), 30.0, 1e-6);
	EXPECT_NEAR(rad2deg(m->roll), 0.0, 1e-6);
}

TEST(SensorMount, DegeneratePlanesGiveNothing)
{
	EXPECT_FALSE(mountFromFloor({{0, 0, 0}, 0.8}));             // no normal
	EXPECT_FALSE(mountFromFloor({{0, 0, 1}, 0.0}));             // through the sensor
	EXPECT_FALSE(mountFromFloor({{0, 0, std::nan("")}, 0.8}));  // not finite
	EXPECT_FALSE(mountFromFloor({{0, 0, 1}, std::numeric_limits<double>::infinity()}));
}

TEST(MountMonitor, AlarmAfterAlarmFramesInARowClearedAsMany)
{
	MountCheckParams p;  // 0.03 m, 1.5 deg, 5 frames
	MountMonitor mon(p);
	const SensorMount declared{0.80, deg2rad(25), 0.0};
	const SensorMount right{0.805, deg2rad(25.5), deg2rad(-0.4)};  // within 3 cm and 1.5 deg
	const SensorMount wrongZ{0.84, deg2rad(25), 0.0};              // 4 cm off
	const SensorMount wrongPitch{0.80, deg2rad(26.6), 0.0};        // 1.6 deg off
	for (int i = 0; i < 20; i++) mon.update(declared, right);
	EXPECT_FALSE(mon.status().alarm);
	EXPECT_EQ(mon.status().frames_disagreeing, 0u);
	// A frame without a floor plane is not checked.
	mon.update(declared, std::nullopt);
	EXPECT_EQ(mon.status().frames_checked, 20u);
	// Four wrong frames (a ramp, a table top): no alarm; a right one resets the count.
	for (int i = 0; i < 4; i++) mon.update(declared, wrongZ);
	EXPECT_FALSE(mon.status().alarm);
	mon.update(declared, right);
	for (int i = 0; i < 4; i++) mon.update(declared, wrongPitch);
	EXPECT_FALSE(mon.status().alarm);
	// The fifth in a row raises it.
	mon.update(declared, wrongPitch);
	EXPECT_TRUE(mon.status().alarm);
	EXPECT_EQ(mon.status().alarms_raised, 1u);
	EXPECT_EQ(mon.status().frames_disagreeing, 9u);
	// Four right frames keep it on; the fifth clears it.
	for (int i = 0; i < 4; i++) mon.update(declared, right);
	EXPECT_TRUE(mon.status().alarm);
	mon.update(declared, right);
	EXPECT_FALSE(mon.status().alarm);
	EXPECT_EQ(mon.status().alarms_raised, 1u);
}

TEST(MountMonitor, RunningEstimateIsTheMedianOfTheWindow)
{
	MountCheckParams p;
	p.window = 5;
	p.alarm_frames = 3;
	MountMonitor mon(p);
	const SensorMount declared{0.8, 0.0, 0.0};
	// Heights 0.90, 0.91, 0.70 (a bad plane), 0.92, 0.89, then 0.93:
	// after five frames the median of {0.89, 0.90, 0.91, 0.70, 0.92} is 0.90;
	// the sixth replaces the oldest (0.90): {0.91, 0.70, 0.92, 0.89, 0.93} -> 0.91.
	const double z[] = {0.90, 0.91, 0.70, 0.92, 0.89};
	for (int i = 0; i < 5; i++)
	{
		mon.update(declared, SensorMount{z[i], 0.0, 0.0});
		EXPECT_EQ(mon.status().has_estimate, i + 1 >= 3) << i;
	}
	EXPECT_DOUBLE_EQ(mon.status().estimate.height, 0.90);
	mon.update(declared, SensorMount{0.93, 0.0, 0.0});
	EXPECT_DOUBLE_EQ(mon.status().estimate.height, 0.91);
	// Disabled: nothing is counted.
	p.enabled = false;
	MountMonitor off(p);
	off.update(declared, SensorMount{0.93, 0.0, 0.0});
	EXPECT_EQ(off.status().frames_checked, 0u);
	// Bad parameters are refused.
	p.tolerance_z = 0;
	EXPECT_THROW(MountMonitor{p}, std::invalid_argument);
}

TEST(SensorMount, RobustEstimateRejectsFramesThatDisagree)
{
	// Seven frames: five good ones, one on a 6 deg ramp (pitch 31), one whose
	// plane was a table top (0.95 m).
	const double h[] = {0.800, 0.802, 0.798, 0.801, 0.799, 0.800, 0.950};
	const double p[] = {25.0, 25.05, 24.95, 25.0, 25.0, 31.0, 25.0};
	std::vector<SensorMount> frames;
	for (int i = 0; i < 7; i++) frames.push_back({h[i], deg2rad(p[i]), 0.0});
	const MountEstimate e = estimateMount(frames);
	// Height: median 0.800, deviations {0, .002, .002, .001, .001, 0, .150}, MAD 0.001,
	// 3 * 1.4826 * 0.001 = 0.0044 < the 5 mm floor: limit 5 mm, 0.95 rejected.
	// Pitch: median 25.0, MAD 0 -> the 0.1 deg floor: 31 rejected.
	EXPECT_EQ(e.used, 5u);
	// Mean of the five: 4.000 / 5 = 0.800; squared deviations 0 + 4e-6 + 4e-6 + 1e-6 + 1e-6
	// = 1e-5, / 4 = 2.5e-6, std 0.0015811, standard error 0.0015811 / sqrt 5 = 0.00070711.
	EXPECT_NEAR(e.mean.height, 0.800, 1e-12);
	EXPECT_NEAR(e.standard_error.height, 0.00070711, 1e-8);
	// Pitch: mean 25.0; squared deviations 0.0025 * 2 = 0.005 deg^2, / 4 = 0.00125,
	// std 0.035355 deg, standard error 0.015811 deg.
	EXPECT_NEAR(rad2deg(e.mean.pitch), 25.0, 1e-9);
	EXPECT_NEAR(rad2deg(e.standard_error.pitch), 0.015811, 1e-6);
	EXPECT_DOUBLE_EQ(e.mean.roll, 0.0);
	EXPECT_DOUBLE_EQ(e.standard_error.roll, 0.0);
	// No frames: nothing.
	EXPECT_EQ(estimateMount({}).used, 0u);
}

namespace
{
/** Sensor-frame points of a 64x48 camera (fx = fy = 50) mounted `height` above
 * the floor, pitched and rolled, looking at the floor, a table top 0.75 m high
 * (x 1.2..1.8, y -0.6..0.6 in the robot frame) and a wall at x = 4 m. */
std::vector<Eigen::Vector3d> floorTableWall(double height, double pitch, double roll)
{
	const Eigen::Matrix3d R =
		(Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) * Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()))
			.toRotationMatrix();
	const Eigen::Vector3d t(0, 0, height);
	std::vector<Eigen::Vector3d> pts;
	for (int r = 0; r < 48; r++)
		for (int c = 0; c < 64; c++)
		{
			const Eigen::Vector3d ray(1.0, (31.5 - c) / 50.0, (23.5 - r) / 50.0);
			const Eigen::Vector3d w = R * ray;
			double best = std::numeric_limits<double>::infinity();
			if (w.z() < 0) best = -t.z() / w.z();  // floor
			if (w.z() < 0)
			{
				const double tt = (0.75 - t.z()) / w.z();  // table top, from above
				const Eigen::Vector3d q = t + tt * w;
				if (tt > 0 && q.x() > 1.2 && q.x() < 1.8 && std::abs(q.y()) < 0.6) best = std::min(best, tt);
			}
			if (w.x() > 0) best = std::min(best, (4.0 - t.x()) / w.x());  // wall
			if (std::isfinite(best) && best < 6) pts.push_back(best * ray);
		}
	return pts;
}
}  // namespace

TEST(SensorMount, FloorSearchFromARoughGuess)
{
	// The camera is 0.90 m up, pitched 31 deg, rolled 3 deg; the guess says 1.0 m,
	// 20 deg, 0 deg (0.1 m, 11 deg and 3 deg off: inside 0.3 m / 20 deg / 10 deg).
	// The table top is 0.15 m below the camera (0.75 m off the guess: rejected), the
	// wall 90 deg off: the floor is found. The points are exact; the wall's foot
	// (points within the last, quarter band of the floor) may pull the fit by a
	// little, far within the 1 cm / 0.5 deg asked of a calibration.
	const auto pts = floorTableWall(0.90, deg2rad(31), deg2rad(3));
	size_t inliers = 0;
	const auto floor = searchFloor(pts, SensorMount{1.0, deg2rad(20), 0.0}, FloorSearchParams{}, 1, &inliers);
	ASSERT_TRUE(floor);
	const auto m = mountFromFloor(*floor);
	ASSERT_TRUE(m);
	EXPECT_NEAR(m->height, 0.90, 0.002);
	EXPECT_NEAR(rad2deg(m->pitch), 31.0, 0.1);
	EXPECT_NEAR(rad2deg(m->roll), 3.0, 0.1);
	EXPECT_GT(inliers, 500u);
	// Calibrating again from the answer finds the same plane.
	const auto again = searchFloor(pts, *m, FloorSearchParams{}, 1);
	ASSERT_TRUE(again);
	EXPECT_NEAR(again->d, floor->d, 1e-9);
	EXPECT_NEAR(again->normal.dot(floor->normal), 1.0, 1e-12);
	// A guess 25 deg off in pitch is outside the search: no floor (the wall and
	// the table are rejected too).
	EXPECT_FALSE(searchFloor(pts, SensorMount{0.9, deg2rad(56), 0.0}, FloorSearchParams{}, 1));
	// Too few points: nothing.
	EXPECT_FALSE(searchFloor({pts.begin(), pts.begin() + 100}, *m, FloorSearchParams{}, 1));
}
