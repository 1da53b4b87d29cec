// Ground-aware mapping for MRPT -- tests: the simulator over time (issue #14):
// objects that appear, move and leave (frames=, move=, to=, moving=), systematic
// odometry drift, several depth cameras and the per-frame ground truth
// (PREFIX_gt_frames.csv), with hand-derived expected values.
#include <gtest/gtest.h>
#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/obs/CObservation3DRangeScan.h>
#include <mrpt/obs/CObservationOdometry.h>
#include <mrpt/obs/CRawlog.h>

#include <unistd.h>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

#include "gam/sim/SceneFile.h"

using namespace gam::sim;
namespace fs = std::filesystem;

namespace
{
fs::path tmpDir()
{
	struct Dir
	{
		fs::path p = fs::temp_directory_path() / ("gam_sim_motion_test_" + std::to_string(::getpid()));
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

int runSim(const std::string& args)
{
	const std::string cmd =
		std::string(GAM_SIMULATE_EXE) + " " + args + " >/dev/null 2>" + (tmpDir() / "stderr.txt").string();
	return std::system(cmd.c_str());
}

std::string slurp(const fs::path& p)
{
	std::ifstream f(p, std::ios::binary);
	std::stringstream ss;
	ss << f.rdbuf();
	return ss.str();
}

SceneFile parse(const std::string& text)
{
	std::stringstream ss(text);
	return parseScene(ss, "m.scene");
}

std::string sceneError(const std::string& text)
{
	try
	{
		parse(text);
	}
	catch (const SceneError& e)
	{
		return e.what();
	}
	return "";
}

const char* kPath = "path waypoints=0,0,0 frames=4\n";
}  // namespace

TEST(SimMotion, FramesMoveToAndMovingKeys)
{
	const SceneFile sf = parse(
		std::string(kPath) +
		"box id=1 x=1 y=0 sx=0.2 sy=0.2 sz=0.5 frames=2-5 to=1,1\n"
		"box id=2 x=3 y=0 sx=0.2 sy=0.2 sz=0.5 frames=3- move=0.1,0\n"
		"hole id=3 shape=circle x=2 y=2 r=0.1 depth=0.1 move=0,-0.5 moving=1-3\n"
		"box id=4 x=0 y=3 sx=0.2 sy=0.2 sz=0.5\n");
	const auto& o = sf.scene.objects;
	ASSERT_EQ(o.size(), 4u);
	// box 1: present in frames 2..5, from (1,0) to (1,1) over frames 2..5: 1/3 m per frame
	EXPECT_TRUE(o[0].dynamic());
	EXPECT_FALSE(o[0].presentAt(1));
	EXPECT_TRUE(o[0].presentAt(2));
	EXPECT_TRUE(o[0].presentAt(5));
	EXPECT_FALSE(o[0].presentAt(6));
	EXPECT_NEAR(o[0].move_per_frame.y(), 1.0 / 3.0, 1e-12);
	EXPECT_NEAR(o[0].offsetAt(2).norm(), 0.0, 1e-12);
	EXPECT_NEAR(o[0].offsetAt(5).y(), 1.0, 1e-12);
	EXPECT_NEAR(o[0].offsetAt(9).y(), 1.0, 1e-12);  // held after the motion
	// box 2: from frame 3 on, 0.1 m per frame, open-ended
	EXPECT_FALSE(o[1].presentAt(2));
	EXPECT_TRUE(o[1].presentAt(1000));
	EXPECT_NEAR(o[1].offsetAt(13).x(), 1.0, 1e-12);
	// hole 3: always there, moves in frames 1..3 only: 3 x -0.5 m
	EXPECT_TRUE(o[2].presentAt(0));
	EXPECT_NEAR(o[2].offsetAt(0).y(), 0.0, 1e-12);
	EXPECT_NEAR(o[2].offsetAt(2).y(), -0.5, 1e-12);
	EXPECT_NEAR(o[2].offsetAt(7).y(), -1.0, 1e-12);
	// box 4: static
	EXPECT_FALSE(o[3].dynamic());
	EXPECT_TRUE(sf.scene.dynamic());
	EXPECT_FALSE(parse(std::string(kPath) + "box id=4 x=0 y=3 sx=0.2 sy=0.2 sz=0.5\n").scene.dynamic());
}

TEST(SimMotion, BadMotionKeysNameTheLine)
{
	const std::string p = kPath;
	EXPECT_NE(
		sceneError(p + "box id=1 x=1 y=0 sx=1 sy=1 sz=1 frames=5-2\n").find("m.scene:2: box: frames="),
		std::string::npos);
	EXPECT_NE(sceneError(p + "box id=1 x=1 y=0 sx=1 sy=1 sz=1 frames=a-2\n").find("bad number"), std::string::npos);
	EXPECT_NE(
		sceneError(p + "box id=1 x=1 y=0 sx=1 sy=1 sz=1 move=1,0 to=2,0 frames=0-3\n").find("not both"),
		std::string::npos);
	EXPECT_NE(
		sceneError(p + "box id=1 x=1 y=0 sx=1 sy=1 sz=1 moving=1-3\n").find("moving= needs move= or to="),
		std::string::npos);
	EXPECT_NE(sceneError(p + "box id=1 x=1 y=0 sx=1 sy=1 sz=1 to=2,0\n").find("closed range"), std::string::npos);
	EXPECT_NE(
		sceneError(p + "wall id=1 x0=0 y0=0 x1=1 y1=0 to=2,0 frames=0-3\n").find("to= needs the object's x="),
		std::string::npos);
	EXPECT_NE(sceneError(p + "box id=1 x=1 y=0 sx=1 sy=1 sz=1 move=1\n").find("move needs 2"), std::string::npos);
}

TEST(SimMotion, SceneAtFrameRemovesAndMovesParts)
{
	SceneFile sf = parse(std::string(kPath) + "box id=1 x=1 y=0 sx=0.2 sy=0.2 sz=0.5 frames=2-5 to=1,1\n");
	const Eigen::Vector3d down(0, 0, -1);
	// frame 1: absent -> the ray at (1, 0) meets the floor
	EXPECT_NEAR(sf.scene.atFrame(1).cast({1, 0, 2}, down).point.z(), 0.0, 1e-9);
	// frame 2: at (1, 0) -> the box top at 0.5
	const RayHit h2 = sf.scene.atFrame(2).cast({1, 0, 2}, down);
	EXPECT_NEAR(h2.point.z(), 0.5, 1e-9);
	EXPECT_EQ(h2.object_id, 1);
	// frame 5: at (1, 1); (1, 0) is floor again
	EXPECT_NEAR(sf.scene.atFrame(5).cast({1, 1, 2}, down).point.z(), 0.5, 1e-9);
	EXPECT_NEAR(sf.scene.atFrame(5).cast({1, 0, 2}, down).point.z(), 0.0, 1e-9);
	// the footprint moves with it
	const Eigen::AlignedBox2d b = sf.scene.footprintAt(1, 5);
	EXPECT_NEAR(b.min().x(), 0.9, 1e-9);
	EXPECT_NEAR(b.min().y(), 0.9, 1e-9);
	EXPECT_TRUE(sf.scene.footprintAt(1, 6).isEmpty());

	// the ground truth labelled again where it went: 0.1 m cells from (0, -1)
	sf.grid = GridSpec{};
	sf.grid.resolution = 0.1;
	sf.grid.min_x = 0;
	sf.grid.max_x = 2;
	sf.grid.min_y = -1;
	sf.grid.max_y = 2;
	GroundTruthGrid gt;
	gt.build(sf.scene, sf.grid);                             // as written: at (1, 0)
	EXPECT_EQ(gt.geomLabel[gt.idx(9, 9)], Label::Obstacle);  // cell x 0.9-1.0, y -0.1-0.0
	Eigen::AlignedBox2d region = sf.scene.footprintAt(1, 5);
	region.extend(Eigen::AlignedBox2d(Eigen::Vector2d(0.9, -0.1), Eigen::Vector2d(1.1, 0.1)));
	gt.relabel(sf.scene.atFrame(5), region);
	EXPECT_EQ(gt.geomLabel[gt.idx(9, 9)], Label::Free);
	EXPECT_EQ(gt.geomLabel[gt.idx(9, 19)], Label::Obstacle);   // x 0.9-1.0, y 0.9-1.0
	EXPECT_EQ(gt.geomLabel[gt.idx(10, 20)], Label::Obstacle);  // x 1.0-1.1, y 1.0-1.1
	EXPECT_EQ(gt.geomLabel[gt.idx(11, 20)], Label::Free);      // x 1.1-1.2
	EXPECT_EQ(gt.objectId[gt.idx(9, 19)], 1);
}

TEST(SimMotion, SystematicOdometryDrift)
{
	// 1 m straight in ten 0.1 m steps
	const std::vector<Pose2> truth = [] {
		std::vector<Pose2> t;
		for (int i = 0; i <= 10; i++) t.push_back({0.1 * i, 0, 0});
		return t;
	}();
	std::mt19937 rng(1);
	OdometryNoise scale;
	scale.scale = 0.1;  // 10 % too long
	const auto a = simulateOdometry(truth, scale, rng);
	EXPECT_NEAR(a.back().x, 1.1, 1e-12);
	EXPECT_NEAR(a.back().y, 0.0, 1e-12);
	OdometryNoise bias;
	bias.yaw_bias_per_m = 10 * M_PI / 180;  // 10 deg per metre: 1 deg per step
	const auto b = simulateOdometry(truth, bias, rng);
	EXPECT_NEAR(b.back().yaw, 10 * M_PI / 180, 1e-12);
	// each step goes 0.1 m along the heading before it: sum of 0.1 (cos k deg, sin k deg), k = 0..9
	double x = 0, y = 0;
	for (int k = 0; k < 10; k++) x += 0.1 * std::cos(k * M_PI / 180), y += 0.1 * std::sin(k * M_PI / 180);
	EXPECT_NEAR(b.back().x, x, 1e-12);
	EXPECT_NEAR(b.back().y, y, 1e-12);
	// the scene keys (degrees per metre)
	const SceneFile sf = parse(std::string(kPath) + "odometry_noise scale=0.02 yaw_bias=1.5\n");
	EXPECT_DOUBLE_EQ(sf.odometry_noise.scale, 0.02);
	EXPECT_NEAR(sf.odometry_noise.yaw_bias_per_m, 1.5 * M_PI / 180, 1e-15);
	EXPECT_NE(sceneError(std::string(kPath) + "odometry_noise scale=0.7\n").find("scale must be"), std::string::npos);
}

TEST(SimMotion, SeveralCamerasParse)
{
	const SceneFile sf = parse(
		std::string(kPath) +
		"kinect pose=0.10,0,0.80,0,25,0\n"
		"kinect pose=0.05,0,0.60,0,60,0 label=KINECT_DOWN sway=0.5\n");
	EXPECT_EQ(sf.kinect_label, "KINECT");
	EXPECT_NEAR(sf.kinect_pose.t.z(), 0.80, 1e-12);
	ASSERT_EQ(sf.more_kinects.size(), 1u);
	EXPECT_EQ(sf.more_kinects[0].label, "KINECT_DOWN");
	EXPECT_NEAR(sf.more_kinects[0].pose.t.z(), 0.60, 1e-12);
	EXPECT_NEAR(sf.more_kinects[0].pose.ypr()[1], 60 * M_PI / 180, 1e-12);
	EXPECT_NEAR(sf.more_kinects[0].sway, 0.5 * M_PI / 180, 1e-12);
	EXPECT_NE(
		sceneError(std::string(kPath) + "kinect pose=0,0,1,0,25,0\nkinect pose=0,0,1,0,25,0\n")
			.find("duplicate camera label 'KINECT'"),
		std::string::npos);
	EXPECT_NE(
		sceneError(std::string(kPath) + "kinect pose=0,0,1,0,25,0 label=a/b\n").find("label must be"),
		std::string::npos);
}

TEST(SimMotion, PerFrameGroundTruthOfABoxTakenAway)
{
	// A 0.2 m box at (2, 0), present in frames 0-1, gone in 2-3; 0.1 m cells from (0, -1):
	// it covers cells ix 19-20 (x 1.9-2.1), iy 9-10 (y -0.1-0.1).
	const fs::path d = tmpDir();
	const fs::path scene = d / "gone.scene";
	{
		std::ofstream f(scene);
		f << "kinect pose=0.10,0,1.00,0,25,0\npath waypoints=0,0,0 frames=4\n"
			 "box id=1 name=gone x=2.0 y=0 sx=0.2 sy=0.2 sz=0.3 frames=0-1\n"
			 "grid resolution=0.1 min_x=0 max_x=4 min_y=-1 max_y=1\n";
	}
	const std::string prefix = (d / "gone").string();
	ASSERT_EQ(runSim("--scene " + scene.string() + " --out " + prefix + " --no-noise --no-leddar"), 0);
	std::ifstream f(prefix + "_gt_frames.csv");
	std::string line;
	std::getline(f, line);
	EXPECT_EQ(line, "frame,kind,iy,ix0,ix1,label,object_id");
	std::vector<std::string> geom, entries;
	std::set<int> viewFrames;
	bool boxTopSeen = false;
	while (std::getline(f, line))
	{
		std::stringstream ss(line);
		std::string fr, kind, iy, ix0, ix1;
		std::getline(ss, fr, ',');
		std::getline(ss, kind, ',');
		std::getline(ss, iy, ',');
		std::getline(ss, ix0, ',');
		std::getline(ss, ix1, ',');
		if (kind == "geom") geom.push_back(line);
		if (kind == "entries") entries.push_back(line);
		if (kind == "view")
		{
			viewFrames.insert(std::stoi(fr));
			if (fr == "0" && iy == "9" && std::stoi(ix0) <= 19 && std::stoi(ix1) >= 20) boxTopSeen = true;
		}
		EXPECT_NE(kind, "leddar");  // --no-leddar
	}
	EXPECT_EQ(
		geom, std::vector<std::string>(
				  {"0,geom,9,19,20,obstacle,1", "0,geom,10,19,20,obstacle,1", "2,geom,9,19,20,free,0",
				   "2,geom,10,19,20,free,0"}));
	// rawlog entries as the mapper numbers them: odometry + one Kinect per frame
	EXPECT_EQ(
		entries, std::vector<std::string>(
					 {"0,entries,0,1,2,,0", "1,entries,0,3,4,,0", "2,entries,0,5,6,,0", "3,entries,0,7,8,,0"}));
	EXPECT_EQ(viewFrames, std::set<int>({0, 1, 2, 3}));
	EXPECT_TRUE(boxTopSeen);
	// the final ground truth is the last frame's: the box's cells are free floor
	const std::string labels = slurp(prefix + "_gt_labels.csv");
	EXPECT_NE(labels.find("\n19,9,1.9500,-0.0500,free,0,none\n"), std::string::npos);
	EXPECT_EQ(labels.find(",obstacle,"), std::string::npos);
}

TEST(SimMotion, StaticScenesWriteTheSameFilesWithOrWithoutPerFrameTruth)
{
	const fs::path d = tmpDir();
	const std::string scene = std::string(GAM_SOURCE_DIR) + "/config/scenes/demo.scene";
	const std::string a = (d / "a" / "demo").string(), b = (d / "b" / "demo").string();
	ASSERT_EQ(runSim("--scene " + scene + " --out " + a + " --frames 3"), 0);
	ASSERT_EQ(runSim("--scene " + scene + " --out " + b + " --frames 3 --gt-frames"), 0);
	EXPECT_FALSE(fs::exists(a + "_gt_frames.csv"));  // static: only on request
	EXPECT_TRUE(fs::exists(b + "_gt_frames.csv"));
	for (const char* suf :
		 {".rawlog", "_gt.pgm", "_gt.yaml", "_gt_objects.csv", "_gt_labels.csv", "_gt_path.csv", "_gt_sensors.csv"})
		EXPECT_EQ(slurp(a + suf), slurp(b + suf)) << suf;
}

TEST(SimMotion, TwoCamerasInTheRawlog)
{
	const fs::path d = tmpDir();
	const std::string prefix = (d / "two" / "two").string();
	ASSERT_EQ(
		runSim(
			"--scene " + std::string(GAM_SOURCE_DIR) + "/config/scenes/two_cameras.scene --out " + prefix +
			" --frames 2 --no-noise"),
		0);
	mrpt::obs::CRawlog rl;
	ASSERT_TRUE(rl.loadFromRawLogFile(prefix + ".rawlog"));
	ASSERT_EQ(rl.size(), 8u);  // 2 frames x (odometry, KINECT, KINECT_DOWN, LEDDAR)
	const char* labels[4] = {"ODOMETRY", "KINECT", "KINECT_DOWN", "LEDDAR"};
	for (size_t i = 0; i < rl.size(); i++) EXPECT_EQ(rl.getAsObservation(i)->sensorLabel, labels[i % 4]) << i;
	auto down = rl.asObservation<mrpt::obs::CObservation3DRangeScan>(2);
	ASSERT_TRUE(down);
	EXPECT_NEAR(down->sensorPose.z(), 0.60, 1e-9);
	EXPECT_NEAR(down->sensorPose.pitch(), 60 * M_PI / 180, 1e-9);
	// it sees the floor right below and in front of the robot: depth along its axis at the
	// image centre = 0.6 / sin(60 deg) = 0.693 m
	EXPECT_NEAR(down->rangeImage(211, 255) * 0.001, 0.6 / std::sin(60 * M_PI / 180), 0.003);
	const std::string sensors = slurp(prefix + "_gt_sensors.csv");
	EXPECT_NE(
		sensors.find("KINECT_DOWN,true,0.050000,0.000000,0.600000,0.000000,60.000000,0.000000"), std::string::npos)
		<< sensors;
	// the near box (x 0.40-0.50) is seen: it is in the final ground truth as an obstacle
	const std::string gtl = slurp(prefix + "_gt_labels.csv");
	EXPECT_NE(gtl.find(",obstacle,1,small"), std::string::npos);
}
