// Ground-aware mapping for MRPT
// The camera noise presets, the camera model found from a frame, and the range
// of trust (gam/core/CameraNoise.h), with the arithmetic worked out by hand
// from the makers' figures; and the pipeline giving no evidence beyond it.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>

#include "gam/core/CameraNoise.h"
#include "gam/core/GroundAwarePipeline.h"
#include "test_helpers.h"

using namespace gam;
using gamtest::deg2rad;

namespace
{
// D435 / D455 at 848x480 over 87 deg: fx = 424 / tan(43.5 deg) = 446.80 px.
constexpr double kFxD4 = 446.80;
}  // namespace

TEST(CameraNoise, PresetsFromTheMakersFigures)
{
	// Kinect One, Fankhauser et al. 2015: 1.5 - 0.5 z + 0.3 z^2 mm; at 4 m:
	// 1.5 - 2.0 + 4.8 = 4.3 mm, nothing correlated.
	const CameraNoise k1 = cameraNoisePreset(CameraModel::KinectOne);
	EXPECT_NEAR(k1.independent(4.0, 365), 0.0043, 1e-12);
	EXPECT_EQ(k1.correlated(4.0, 365), 0.0);
	// D435 at 2 m: fx b = 446.80 x 0.050 = 22.340 px m; one sample's independent part
	// z^2 hypot(0.08, (1/32)/sqrt(12) = 0.009021) / (fx b) = 4 x 0.080507 / 22.340 = 14.41 mm,
	// the correlated part 4 x 0.05 / 22.340 = 8.95 mm.
	const CameraNoise d435 = cameraNoisePreset(CameraModel::D435);
	EXPECT_NEAR(d435.independent(2.0, kFxD4), 0.014415, 2e-6);
	EXPECT_NEAR(d435.correlated(2.0, kFxD4), 0.0089526, 2e-6);
	// D455: the same at 95 mm, so 50/95 of it.
	const CameraNoise d455 = cameraNoisePreset(CameraModel::D455);
	EXPECT_NEAR(d455.independent(2.0, kFxD4), 0.014415 * 50 / 95, 2e-6);
	// Astra at 2 m: fx = 320 / tan(30 deg) = 554.26, fx b = 41.569; hypot(0.07, 0.125/sqrt(12)
	// = 0.036084) = 0.078753 -> 4 x 0.078753 / 41.569 = 7.578 mm; correlated 4 x 0.03 / 41.569 = 2.887 mm.
	const CameraNoise astra = cameraNoisePreset(CameraModel::Astra);
	EXPECT_NEAR(astra.independent(2.0, 554.26), 0.007578, 2e-6);
	EXPECT_NEAR(astra.correlated(2.0, 554.26), 0.002887, 2e-6);
	// Femto: the Kinect v2 form as the Kinect One, 1.5 - 0.5*4 + 0.3*16 = 4.3 mm at 4 m.
	EXPECT_NEAR(cameraNoisePreset(CameraModel::Femto).independent(4.0, 504), 0.0043, 1e-12);
}

TEST(CameraNoise, TheModelIsFoundFromTheLabelThenTheFrame)
{
	EXPECT_EQ(detectCameraModel("front_D455", 848, 480, kFxD4), CameraModel::D455);
	EXPECT_EQ(detectCameraModel("RealSense", 640, 480, 600), CameraModel::D435);  // the label wins
	EXPECT_EQ(detectCameraModel("AZURE_KINECT", 0, 0, 0), CameraModel::Femto);
	EXPECT_EQ(detectCameraModel("KINECT", 512, 424, 365), CameraModel::KinectOne);
	EXPECT_EQ(detectCameraModel("KINECT", 848, 480, kFxD4), CameraModel::D435);  // 87 deg
	EXPECT_EQ(detectCameraModel("", 640, 576, 504), CameraModel::Femto);
	// 640x480: 60 deg (fx 554) is an Astra or a Kinect v1 (structured light); a
	// D400 at 640x480 would be 74 deg wide (fx 426 over 640 px): unknown.
	EXPECT_EQ(detectCameraModel("", 640, 480, 554.26), CameraModel::Astra);
	// A Kinect v1 (MRPT labels it KINECT, as the Kinect One): its depth camera
	// fx 585, 2 atan(320 / 585) = 2 x 28.68 = 57.4 deg; registered to its
	// colour camera fx 525 (OpenNI, PCL), 2 atan(320 / 525) = 2 x 31.37 = 62.7
	// deg. Past 64 deg (fx < 320 / tan(32 deg) = 512.1) it is no Astra: fx 505
	// is 2 atan(0.6337) = 64.7 deg.
	EXPECT_EQ(detectCameraModel("KINECT", 640, 480, 585), CameraModel::Astra);
	EXPECT_EQ(detectCameraModel("KINECT", 640, 480, 525), CameraModel::Astra);
	EXPECT_EQ(detectCameraModel("", 640, 480, 505), CameraModel::Custom);
	// PrimeSense's structured light by its label, whatever the mode: MRPT's
	// COpenNI2Sensor frames (OPENNI2), an Xtion at 160x120.
	EXPECT_EQ(detectCameraModel("OPENNI2", 640, 480, 505), CameraModel::Astra);
	EXPECT_EQ(detectCameraModel("Xtion_front", 160, 120, 120), CameraModel::Astra);
	EXPECT_EQ(detectCameraModel("KINECT_V1", 0, 0, 0), CameraModel::Astra);
	EXPECT_EQ(detectCameraModel("", 640, 480, 426), CameraModel::Custom);
	EXPECT_EQ(detectCameraModel("", 160, 120, 120), CameraModel::Custom);
}

TEST(CameraNoise, RangeOfTrustWorkedByHand)
{
	// D435 1 m above the floor, 5 cm cells, 3 sigma, a 2 cm hazard. At rho = 2.5 m:
	//   r = hypot(2.5, 1) = 2.6926, vertical share h/r = 0.37139,
	//   N = 0.05^2 x 446.80^2 x 1 / 2.6926^3 = 499.08 / 19.521 = 25.57 samples,
	//   independent 2.6926^2 x 0.080507 / 22.340 = 26.127 mm -> x 0.37139 = 9.703 mm,
	//   correlated  2.6926^2 x 0.05 / 22.340     = 16.226 mm -> x 0.37139 = 6.026 mm,
	//   mean: sqrt(6.026^2 + 9.703^2 / 25.57) = 6.325 mm, x 3 = 18.97 mm <= 20: trusted.
	// At rho = 2.7 m: r = 2.8792, N = 20.91, 10.376 and 6.444 mm -> 6.832 x 3 = 20.50 mm > 20.
	const CameraNoise d435 = cameraNoisePreset(CameraModel::D435);
	const double t = trustRange(d435, kFxD4, 1.0, 0.05, 3.0, 0.02, 5.0);
	EXPECT_GT(t, 2.5);
	EXPECT_LT(t, 2.7);
	// The D455's 95 mm baseline: at rho = 4.4 m, 3 x 6.46 = 19.38 mm; at 4.6 m, 20.66 mm.
	const double t455 = trustRange(cameraNoisePreset(CameraModel::D455), kFxD4, 1.0, 0.05, 3.0, 0.02, 5.0);
	EXPECT_GT(t455, 4.4);
	EXPECT_LT(t455, 4.6);
	// Kinect One at 5 m: r = 5.099, sigma = 1.5 - 2.55 + 7.80 = 6.75 mm, x 0.1961 = 1.324 mm,
	// N = 0.0025 x 361.6^2 / 132.6 = 2.465: 1.324 / sqrt(2.465) x 3 = 2.53 mm << 20: its whole range.
	EXPECT_EQ(trustRange(cameraNoisePreset(CameraModel::KinectOne), 361.6, 1.0, 0.05, 3.0, 0.02, 5.0), 5.0);
	// No noise model (custom, all zero), no height, or 0 sigmas: not limited.
	EXPECT_EQ(trustRange(CameraNoise{}, kFxD4, 1.0, 0.05, 3.0, 0.02, 5.0), 5.0);
	EXPECT_EQ(trustRange(d435, kFxD4, 0.0, 0.05, 3.0, 0.02, 5.0), 5.0);
	EXPECT_EQ(trustRange(d435, kFxD4, 1.0, 0.05, 0.0, 0.02, 5.0), 5.0);
	// A bigger hazard is seen farther.
	EXPECT_GT(trustRange(d435, kFxD4, 1.0, 0.05, 3.0, 0.05, 5.0), t + 0.5);
}

TEST(CameraNoise, NoEvidenceBeyondTheRangeOfTrust)
{
	// A flat floor seen by an 848x480, 87 deg camera (a D435's frame) 1 m up, pitched
	// 25 deg down, exact depths out to 5 m. camera_model = auto finds a D435 from the
	// size and field of view, and its range of trust at 1 m (2.5-2.7 m, above) bounds
	// every evidence cell; with range_of_trust = false the floor is free out to ~5 m.
	PinholeIntrinsics K;
	K.width = 848;
	K.height = 480;
	K.fx = K.fy = kFxD4;
	K.cx = 423.5;
	K.cy = 239.5;
	const Eigen::Vector3d camPos(0, 0, 1.0);
	const Eigen::Matrix3d R = Eigen::AngleAxisd(deg2rad(25), Eigen::Vector3d::UnitY()).toRotationMatrix();
	const std::vector<uint16_t> depth = gamtest::renderDepth(K, R, [&](const Eigen::Vector3d& w) {
		const double t = w.z() < 0 ? -camPos.z() / w.z() : -1.0;  // depth along X (ray.x = 1)
		return t < 6.0 ? t : -1.0;
	});
	SensorFrame frame = gamtest::depthFrame(depth, K, R, camPos);
	frame.sensor_label = "KINECT";  // a label that names no model: the frame decides

	auto farthestEvidence = [&](bool trust, CameraModel& model, double& trustRangeOut) {
		PipelineParams params;
		params.camera.range_of_trust = trust;
		GroundAwarePipeline pipeline(params);
		const FrameResult& res = pipeline.process(frame, Eigen::Vector3d(0, 0, 0), GridLattice{0, 0, 0.05});
		EXPECT_EQ(res.detection.status, GroundDetection::Status::Ok) << res.detection.describe();
		model = res.camera;
		trustRangeOut = res.trust_range;
		const GridGeometry& g = pipeline.frameGrid().geometry();
		double far = 0;
		for (uint32_t idx : pipeline.ism().evidenceCells())
		{
			const double x = g.cx(int(idx % uint32_t(g.nx))), y = g.cy(int(idx / uint32_t(g.nx)));
			far = std::max(far, std::hypot(x, y));
		}
		return far;
	};
	CameraModel model;
	double trust = 0;
	const double farTrusted = farthestEvidence(true, model, trust);
	EXPECT_EQ(model, CameraModel::D435);
	EXPECT_GT(trust, 2.5);
	EXPECT_LT(trust, 2.7);
	// cell centres: within half a cell's diagonal of the bound
	EXPECT_LE(farTrusted, trust + 0.036);
	EXPECT_GT(farTrusted, trust - 0.2);
	const double farAll = farthestEvidence(false, model, trust);
	EXPECT_TRUE(std::isinf(trust));
	EXPECT_GT(farAll, 4.5);
}

TEST(GroundOffset, AStageTheTreeGrewOnIsNoFloor)
{
	// No floor near the robot is in view (it starts 2.4 m ahead), and a flat stage 0.20 m
	// high covers x 1.0..2.4 m: the tree seeds on the stage (within seed_height_tolerance
	// 0.3 m) and grows over it. Its plane is 0.20 m above the robot's floor under the
	// robot, more than max_ground_offset 0.10: the frame is judged against the robot's
	// floor (z = 0), and the stage top, 0.20 m above it, is an obstacle. With the rule
	// off the stage is ground: free.
	const PinholeIntrinsics K = gamtest::smallCamera();
	const Eigen::Vector3d camPos(0, 0, 1.0);
	const Eigen::Matrix3d R = Eigen::AngleAxisd(deg2rad(25), Eigen::Vector3d::UnitY()).toRotationMatrix();
	const std::vector<uint16_t> depth = gamtest::renderDepth(K, R, [&](const Eigen::Vector3d& w) {
		if (w.z() >= 0) return -1.0;
		double t = (0.20 - camPos.z()) / w.z();  // the stage's top
		Eigen::Vector3d q = camPos + t * w;
		if (!(q.x() >= 1.0 && q.x() <= 2.4 && std::abs(q.y()) <= 2.0))
		{
			t = -camPos.z() / w.z();  // the floor, seen only past the stage
			q = camPos + t * w;
			if (q.x() < 2.4) return -1.0;
		}
		return t < 4.5 ? t : -1.0;
	});
	const SensorFrame frame = gamtest::depthFrame(depth, K, R, camPos);

	auto stageEvidence = [&](double limit, bool& fromMount) {
		PipelineParams params;
		params.max_ground_offset = limit;
		GroundAwarePipeline pipeline(params);
		const FrameResult& res = pipeline.process(frame, Eigen::Vector3d(0, 0, 0), GridLattice{0, 0, 0.05});
		EXPECT_TRUE(res.detection.ok()) << res.detection.describe();
		fromMount = res.detection.ground_from_mount;
		const GridGeometry& g = pipeline.frameGrid().geometry();
		const float e = pipeline.ism().evidence()[size_t(g.iy(0.0)) * size_t(g.nx) + size_t(g.ix(1.7))];
		return e;
	};
	bool fromMount = false;
	EXPECT_GT(stageEvidence(0.10, fromMount), 0.5f);  // occupied
	EXPECT_TRUE(fromMount);
	EXPECT_LT(stageEvidence(0.0, fromMount), 0.5f);  // off: the stage is the ground, free
	EXPECT_FALSE(fromMount);
}
