// Ground-aware mapping for MRPT -- tests: the rawlog written by gam-simulate,
// read back with MRPT and unprojected by MRPT itself (proves the depth convention).
#include <gtest/gtest.h>
#include <mrpt/maps/CSimplePointsMap.h>
#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/obs/CObservation3DRangeScan.h>
#include <mrpt/obs/CObservationOdometry.h>
#include <mrpt/obs/CRawlog.h>

#include <unistd.h>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace fs = std::filesystem;

namespace
{
fs::path tmpDir()
{
	// one folder per process, removed when the process ends
	struct Dir
	{
		fs::path p = fs::temp_directory_path() / ("gam_sim_test_" + std::to_string(::getpid()));
		Dir() { fs::create_directories(p); }
		~Dir()
		{
			std::error_code ec;
			fs::remove_all(p, ec);
		}
	};
	static Dir d;
	return d.p;
}

int run(const std::string& args, std::string* err = nullptr)
{
	const fs::path errFile = tmpDir() / "stderr.txt";
	const std::string cmd = std::string(GAM_SIMULATE_EXE) + " " + args + " >/dev/null 2>" + errFile.string();
	const int rc = std::system(cmd.c_str());
	if (err)
	{
		std::ifstream f(errFile);
		std::stringstream ss;
		ss << f.rdbuf();
		*err = ss.str();
	}
	return rc;
}
}  // namespace

TEST(SimRawlog, GamSimulateWritesALoadableRawlog)
{
	const fs::path d = tmpDir();
	const fs::path scene = d / "t.scene";
	{
		std::ofstream f(scene);
		f << "kinect pose=0.10,0.05,1.00,0,25,0\n"
			 "leddar pose=0.20,0,0.30,0,0,0\n"
			 "path waypoints=0,0,0;1,0,0 spacing=0.1\n"
			 "box id=1 name=block x=3.25 y=0 sx=0.5 sy=0.6 sz=0.5\n"
			 "grid resolution=0.05 min_x=-1 max_x=5 min_y=-3 max_y=3\n";
	}
	const std::string prefix = (d / "out").string();
	ASSERT_EQ(run("--scene " + scene.string() + " --out " + prefix + " --no-noise --frames 2"), 0);
	for (const char* suf : {".rawlog", "_gt.pgm", "_gt.yaml", "_gt_objects.csv", "_gt_labels.csv", "_gt_path.csv"})
		EXPECT_TRUE(fs::exists(prefix + suf)) << suf;

	mrpt::obs::CRawlog rl;
	ASSERT_TRUE(rl.loadFromRawLogFile(prefix + ".rawlog"));
	ASSERT_EQ(rl.size(), 6u);  // 2 frames x (odometry, kinect, leddar)
	for (size_t i = 0; i < rl.size(); i++) EXPECT_EQ(rl.getType(i), mrpt::obs::CRawlog::etObservation);

	auto odo1 = rl.asObservation<mrpt::obs::CObservationOdometry>(3);
	ASSERT_TRUE(odo1);
	EXPECT_NEAR(odo1->odometry.x(), 0.1, 1e-9);
	EXPECT_NEAR(odo1->odometry.y(), 0.0, 1e-9);

	auto led = rl.asObservation<mrpt::obs::CObservation2DRangeScan>(2);
	ASSERT_TRUE(led);
	EXPECT_EQ(led->sensorLabel, "LEDDAR");
	EXPECT_EQ(led->getScanSize(), 16u);
	EXPECT_NEAR(led->aperture, 45.0 * M_PI / 180, 1e-6);
	EXPECT_TRUE(led->rightToLeft);
	EXPECT_NEAR(led->getScanRange(8), 3.0 - 0.2, 0.02);  // box face at x=3, sensor at x=0.2

	auto k = rl.asObservation<mrpt::obs::CObservation3DRangeScan>(1);
	ASSERT_TRUE(k);
	EXPECT_EQ(k->sensorLabel, "KINECT");
	ASSERT_TRUE(k->hasRangeImage);
	EXPECT_TRUE(k->range_is_depth);
	EXPECT_EQ(k->rangeImage.cols(), 512);
	EXPECT_EQ(k->rangeImage.rows(), 424);
	EXPECT_EQ(k->cameraParams.ncols, 512u);
	EXPECT_NEAR(k->maxRange, 4.5, 1e-6);
	EXPECT_NEAR(k->sensorPose.z(), 1.0, 1e-9);
	EXPECT_NEAR(k->sensorPose.pitch(), 25 * M_PI / 180, 1e-9);

	// MRPT's own unprojection with the sensor pose: robot frame (robot at the origin in frame 0)
	mrpt::maps::CSimplePointsMap pts;
	mrpt::obs::T3DPointsProjectionParams pp;
	pp.takeIntoAccountSensorPoseOnRobot = true;
	k->unprojectInto(pts, pp);
	ASSERT_GT(pts.size(), 100000u);
	size_t nFloor = 0, nFace = 0;
	double maxFloorErr = 0, maxFaceErr = 0;
	for (size_t i = 0; i < pts.size(); i++)
	{
		float x, y, z;
		pts.getPoint(i, x, y, z);
		if (x < 2.9)
		{
			nFloor++;
			maxFloorErr = std::max(maxFloorErr, double(std::abs(z)));
		}
		else if (z > 0.05 && z < 0.45 && std::abs(y) < 0.25)
		{
			nFace++;
			maxFaceErr = std::max(maxFaceErr, std::abs(x - 3.0));
		}
	}
	EXPECT_GT(nFloor, 50000u);
	EXPECT_GT(nFace, 1000u);
	EXPECT_LT(maxFloorErr, 0.005);  // 1 mm depth quantisation
	EXPECT_LT(maxFaceErr, 0.002);
}

TEST(SimRawlog, CameraOptionLabelsTheFramesAfterTheModel)
{
	// --camera d455 on a scene that labels no camera: the frames say "D455", the
	// only thing that tells them from a D435's (camera_model = auto reads the label).
	const fs::path d = tmpDir();
	const fs::path scene = d / "d455.scene";
	{
		std::ofstream f(scene);
		f << "kinect pose=0.10,0,1.00,0,25,0\n"
			 "path waypoints=0,0,0\n";
	}
	const std::string prefix = (d / "d455").string();
	ASSERT_EQ(run("--scene " + scene.string() + " --out " + prefix + " --no-leddar --frames 1 --camera d455"), 0);
	mrpt::obs::CRawlog rl;
	ASSERT_TRUE(rl.loadFromRawLogFile(prefix + ".rawlog"));
	auto k = rl.asObservation<mrpt::obs::CObservation3DRangeScan>(1);
	ASSERT_TRUE(k);
	EXPECT_EQ(k->sensorLabel, "D455");
	EXPECT_EQ(k->cameraParams.ncols, 848u);
}

TEST(SimRawlog, BadSceneFileFailsWithFileAndLine)
{
	const fs::path d = tmpDir();
	const fs::path scene = d / "bad.scene";
	{
		std::ofstream f(scene);
		f << "path waypoints=0,0,0\n# comment\nbox id=1 x=1 y=0 sx=0.1 sy=0.1\n";
	}
	std::string err;
	const int rc = run("--scene " + scene.string() + " --out " + (d / "bad").string(), &err);
	EXPECT_NE(rc, 0);
	EXPECT_NE(err.find("bad.scene:3: box: missing sz="), std::string::npos) << err;
	EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;
	EXPECT_NE(run("--scene " + (d / "missing.scene").string() + " --out " + (d / "x").string(), &err), 0);
	EXPECT_NE(err.find("cannot open"), std::string::npos) << err;
}

TEST(SimRawlog, SameSeedSameBytes)
{
	const fs::path d = tmpDir();
	const fs::path scene = d / "seed.scene";
	{
		std::ofstream f(scene);
		f << "kinect pose=0.10,0,1.00,0,25,0\n"
			 "path waypoints=0,0,0;0.3,0,0 spacing=0.1\n"
			 "odometry_noise xy=0.02 yaw=1\n"
			 "box id=1 x=2.5 y=0 sx=0.1 sy=0.1 sz=0.1\n"
			 "grid resolution=0.05 min_x=-1 max_x=5 min_y=-3 max_y=3\n";
	}
	auto slurp = [](const std::string& p) {
		std::ifstream f(p, std::ios::binary);
		std::stringstream ss;
		ss << f.rdbuf();
		return ss.str();
	};
	const std::string a = (d / "a").string(), b = (d / "b").string(), c = (d / "c").string();
	ASSERT_EQ(run("--scene " + scene.string() + " --out " + a + " --seed 7 --frames 2"), 0);
	ASSERT_EQ(run("--scene " + scene.string() + " --out " + b + " --seed 7 --frames 2"), 0);
	ASSERT_EQ(run("--scene " + scene.string() + " --out " + c + " --seed 8 --frames 2"), 0);
	EXPECT_TRUE(slurp(a + ".rawlog") == slurp(b + ".rawlog"));
	EXPECT_TRUE(slurp(a + "_gt_path.csv") == slurp(b + "_gt_path.csv"));
	EXPECT_FALSE(slurp(a + ".rawlog") == slurp(c + ".rawlog"));
	EXPECT_FALSE(slurp(a + "_gt_path.csv") == slurp(c + "_gt_path.csv"));
	// without sensor sway the ground truth does not depend on the noise
	EXPECT_TRUE(slurp(a + "_gt.pgm") == slurp(c + "_gt.pgm"));
}

TEST(SimRawlog, TiltedRolledMountUnprojectsOntoTheFloor)
{
	// yaw, pitch and roll of the mount all end up in sensorPose the way MRPT reads them
	const fs::path d = tmpDir();
	const fs::path scene = d / "tilt.scene";
	{
		std::ofstream f(scene);
		f << "kinect pose=0.05,0.08,0.95,4,30,6\n"
			 "path waypoints=0,0,0\n"
			 "box id=1 name=block x=2.25 y=0 sx=0.5 sy=1.0 sz=0.6\n"
			 "grid resolution=0.05 min_x=-1 max_x=5 min_y=-3 max_y=3\n";
	}
	const std::string prefix = (d / "tilt").string();
	ASSERT_EQ(run("--scene " + scene.string() + " --out " + prefix + " --no-noise --no-leddar"), 0);
	mrpt::obs::CRawlog rl;
	ASSERT_TRUE(rl.loadFromRawLogFile(prefix + ".rawlog"));
	ASSERT_EQ(rl.size(), 2u);
	auto k = rl.asObservation<mrpt::obs::CObservation3DRangeScan>(1);
	ASSERT_TRUE(k);
	EXPECT_NEAR(k->sensorPose.roll(), 6 * M_PI / 180, 1e-9);
	EXPECT_NEAR(k->sensorPose.yaw(), 4 * M_PI / 180, 1e-9);
	mrpt::maps::CSimplePointsMap pts;
	mrpt::obs::T3DPointsProjectionParams pp;
	pp.takeIntoAccountSensorPoseOnRobot = true;
	k->unprojectInto(pts, pp);
	size_t nFloor = 0, nFace = 0;
	double maxFloorErr = 0, maxFaceErr = 0;
	for (size_t i = 0; i < pts.size(); i++)
	{
		float x, y, z;
		pts.getPoint(i, x, y, z);
		if (x < 1.9)
		{
			nFloor++;
			maxFloorErr = std::max(maxFloorErr, double(std::abs(z)));
		}
		else if (z > 0.1 && z < 0.5 && std::abs(y) < 0.4)
		{
			nFace++;
			maxFaceErr = std::max(maxFaceErr, std::abs(x - 2.0));
		}
	}
	EXPECT_GT(nFloor, 50000u);
	EXPECT_GT(nFace, 1000u);
	EXPECT_LT(maxFloorErr, 0.005);
	EXPECT_LT(maxFaceErr, 0.002);
}
