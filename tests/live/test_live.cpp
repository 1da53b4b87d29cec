// The live mode of ground-aware-mapper (issue #29, item 5): a simulated scene
// played through MRPT's CGenericSensor interface by a test driver
// (CSimulatedSceneSensor) into gam::mapper::runLive() in this process, with a
// real SIGINT; and the built program run as a child with the driver loaded as
// a plugin module (--plugins), stopped by SIGINT / --max-seconds.
#include <gam/mapper/Live.h>
#include <gam/maps/GridIO.h>
#include <gtest/gtest.h>
#include <mrpt/io/CFileGZInputStream.h>
#include <mrpt/maps/registerBaselineMaps.h>
#include <mrpt/maps/registerGroundAwareMaps.h>
#include <mrpt/obs/CObservation3DRangeScan.h>
#include <mrpt/obs/CObservationOdometry.h>
#include <mrpt/serialization/CArchive.h>

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>

#include "CSimulatedSceneSensor.h"

namespace fs = std::filesystem;
using gam::mapper::ConfigError;
using gam::mapper::RunError;
using mrpt::maps::COccupancyGridMap2D;

namespace
{
// One work folder per process: ctest runs the tests in parallel.
const std::string kTmp = std::string(GAM_TEST_TMP_DIR) + "/p" + std::to_string(getpid());
const std::vector<std::string> kGrids = {"ground_aware", "height_band", "octomap"};

// The scene: a floor, a 0.3 m box and a 0.3 m deep hole 2 m ahead of the
// robot's start; the robot stands at ROBOT (x,y,yaw in degrees).
const double kBoxX = 2.0, kBoxY = -0.5, kHoleX = 2.0, kHoleY = 0.5;
std::string sceneText(const std::string& robot)
{
	return "kinect pose=0.10,0,1.00,0,25,0\n"
		   "path waypoints=" +
		   robot +
		   " frames=1000 rate=10\n"
		   "box id=1 name=box x=2.0 y=-0.5 sx=0.3 sy=0.3 sz=0.3\n"
		   "hole id=2 name=hole shape=rect x=2.0 y=0.5 sx=0.4 sy=0.4 depth=0.3\n"
		   "grid resolution=0.05 min_x=-2 max_x=5 min_y=-3 max_y=3\n";
}

std::string slurp(const std::string& f)
{
	std::ifstream i(f, std::ios::binary);
	std::ostringstream s;
	s << i.rdbuf();
	return s.str();
}

std::string freshDir(const std::string& name)
{
	const std::string d = kTmp + "/" + name;
	fs::remove_all(d);
	fs::create_directories(d);
	return d;
}

void writeFile(const std::string& path, const std::string& text)
{
	std::ofstream f(path);
	f << text;
	ASSERT_TRUE(bool(f)) << path;
}

/** A sensors .ini with one simulated camera section (and `more` appended). */
std::string cameraIni(const std::string& dir, const std::string& robot, const std::string& extraKeys = "")
{
	writeFile(dir + "/test.scene", sceneText(robot));
	return "[global]\ntime_between_launches = 0\n\n[CAM]\ndriver = CSimulatedSceneSensor\nprocess_rate = 20\n"
		   "sensorLabel = SIM_KINECT\nscene = " +
		   dir + "/test.scene\nwidth = 256\nheight = 212\n" + extraKeys;
}

/** The mapper of the default .ini (the offline mode's map set), writing into `out`. */
gam::mapper::MapperOptions mapperOptions(const std::string& out)
{
	gam::mapper::MapperOptions o;
	o.outDir = out;
	o.configText = slurp(std::string(GAM_SOURCE_DIR) + "/config/ground-aware-mapper.ini");
	o.configName = "ground-aware-mapper.ini";
	o.progress = false;
	return o;
}

gam::mapper::LiveOptions liveOptions(const std::string& ini)
{
	gam::mapper::LiveOptions l;
	l.sensorsIniPath = ini;
	l.snapshotSeconds = 0;
	l.progress = false;
	// A guard, not a measurement: a run that misses its stop ends here and its
	// test fails on the stop reason instead of hanging.
	l.maxSeconds = 60;
	return l;
}

/** Largest P(occupied) among the cells whose centre lies in the rectangle. */
double maxOcc(const COccupancyGridMap2D& g, double x0, double x1, double y0, double y1)
{
	double m = 0;
	for (double y = y0; y <= y1 + 1e-9; y += g.getResolution())
		for (double x = x0; x <= x1 + 1e-9; x += g.getResolution())
			m = std::max(m, 1.0 - double(g.getPos(float(x), float(y))));
	return m;
}
/** Smallest P(free) in the rectangle. */
double minFree(const COccupancyGridMap2D& g, double x0, double x1, double y0, double y1)
{
	double m = 1;
	for (double y = y0; y <= y1 + 1e-9; y += g.getResolution())
		for (double x = x0; x <= x1 + 1e-9; x += g.getResolution())
			m = std::min(m, double(g.getPos(float(x), float(y))));
	return m;
}

/** The scene as the maps must show it: the box occupied in every grid, the
 * hole in the ground-aware grid, the floor between robot and objects free. */
void expectTheScene(const std::string& out, double dx = 0)
{
	for (const auto& L : kGrids)
	{
		SCOPED_TRACE(L);
		ASSERT_TRUE(fs::exists(out + "/" + L + ".yaml"));
		ASSERT_TRUE(fs::exists(out + "/" + L + ".pgm"));
		// Loadable by stock MRPT, as the offline mode's.
		const COccupancyGridMap2D g = gam::maps::readStockGrid(out + "/" + L + ".gridmap.gz");
		// Its whole footprint and one cell around it: a 2D-scan map marks only the face it sees.
		EXPECT_GT(maxOcc(g, kBoxX + dx - 0.2, kBoxX + dx + 0.2, kBoxY - 0.2, kBoxY + 0.2), 0.65);
	}
	const COccupancyGridMap2D ga = gam::maps::readStockGrid(out + "/ground_aware.gridmap.gz");
	EXPECT_GT(maxOcc(ga, kHoleX + dx - 0.15, kHoleX + dx + 0.15, kHoleY - 0.15, kHoleY + 0.15), 0.65);
	EXPECT_GT(minFree(ga, 1.2 + dx, 1.5 + dx, -0.15, 0.15), 0.65);
	EXPECT_TRUE(fs::exists(out + "/elevation.map.gz"));
	EXPECT_TRUE(fs::exists(out + "/timing.csv"));
	EXPECT_TRUE(fs::exists(out + "/config_used.ini"));
	// Nothing of the run is left behind.
	for (const auto& e : fs::directory_iterator(out))
		EXPECT_EQ(e.path().filename().string().rfind(".ground-aware-mapper.tmp", 0), std::string::npos);
}

/** Waits (at most `limitS`, a guard against a hang, not a timing check) for `cond`. */
template <class F>
bool waitFor(F cond, double limitS = 120)
{
	const auto t0 = std::chrono::steady_clock::now();
	while (!cond())
	{
		if (std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() > limitS) return false;
		std::this_thread::sleep_for(std::chrono::milliseconds(20));
	}
	return true;
}

class Environment : public ::testing::Environment
{
   public:
	void SetUp() override
	{
		mrpt::maps::registerGroundAwareMaps();
		mrpt::maps::registerBaselineMaps();
		// The test's driver, registered as MRPT documents for drivers outside
		// its libraries; from now on createSensorPtr("CSimulatedSceneSensor") works.
		using gam_test::CSimulatedSceneSensor;
		mrpt::hwdrivers::CGenericSensor::registerClass(SENSOR_CLASS_ID(CSimulatedSceneSensor));
	}
};
const auto* const kEnv = ::testing::AddGlobalTestEnvironment(new Environment);
}  // namespace

// Ctrl-C: a real SIGINT to this process after some frames; the handler only
// sets the flag, runLive() stops the sensor, writes the final maps and returns.
TEST(LiveInProcess, SigintAfterSomeFramesSavesMapsThatShowTheScene)
{
	const std::string dir = freshDir("sigint"), out = dir + "/out";
	writeFile(dir + "/sensors.ini", cameraIni(dir, "0,0,0"));
	gam::mapper::installStopSignalHandlers();
	ASSERT_FALSE(gam::mapper::stopSignalFlag());
	const size_t before = gam_test::CSimulatedSceneSensor::framesDelivered();
	std::thread killer([&] {
		if (waitFor([&] { return gam_test::CSimulatedSceneSensor::framesDelivered() >= before + 6; }))
			kill(getpid(), SIGINT);
	});
	gam::mapper::Mapper mapper(mapperOptions(out));
	gam::mapper::LiveSummary s;
	try
	{
		s = gam::mapper::runLive(mapper, liveOptions(dir + "/sensors.ini"), gam::mapper::stopSignalFlag());
	}
	catch (...)
	{
		killer.join();
		throw;
	}
	killer.join();
	EXPECT_TRUE(gam::mapper::stopSignalFlag());
	EXPECT_NE(s.stopReason.find("stop requested"), std::string::npos) << s.stopReason;
	EXPECT_FALSE(s.sensorFailed);
	EXPECT_GE(s.run.frames, 1u);
	EXPECT_EQ(s.run.frames, s.run.frames3D);
	EXPECT_EQ(s.run.frames + s.dropped, s.received);  // only depth frames came
	EXPECT_EQ(s.run.framesWithoutOdometry, s.run.frames);
	expectTheScene(out);
}

// --snapshot-seconds: the maps show up in the output folder while the run goes
// on, and are readable then; the run ends only when asked to.
TEST(LiveInProcess, SnapshotsAppearInTheOutputFolderWhileRunning)
{
	const std::string dir = freshDir("snap"), out = dir + "/out";
	writeFile(dir + "/sensors.ini", cameraIni(dir, "0,0,0"));
	auto live = liveOptions(dir + "/sensors.ini");
	live.snapshotSeconds = 0.2;
	std::atomic<bool> stop{false};
	// --snapshot-every (per frames) too: its folders are published at the end, as offline.
	auto mo = mapperOptions(out);
	mo.snapshotEvery = 1;
	gam::mapper::Mapper mapper(mo);
	gam::mapper::LiveSummary s;
	std::string error;
	std::thread run([&] {
		try
		{
			s = gam::mapper::runLive(mapper, live, stop);
		}
		catch (const std::exception& e)
		{
			error = e.what();
		}
	});
	const bool appeared = waitFor([&] { return fs::exists(out + "/ground_aware.yaml") || !error.empty(); });
	bool readable = false;
	size_t framesThen = 0;
	if (appeared && error.empty())
	{
		// A snapshot is a complete map (each file replaced at once).
		const COccupancyGridMap2D g = gam::maps::readStockGrid(out + "/ground_aware.gridmap.gz");
		readable = g.getSizeX() > 0;
		framesThen = gam_test::CSimulatedSceneSensor::framesDelivered();
	}
	// The run was still going: nothing asked it to stop yet.
	const bool stillRunning = !fs::exists(out + "/config_used.ini");
	stop = true;
	run.join();
	ASSERT_TRUE(error.empty()) << error;
	ASSERT_TRUE(appeared);
	EXPECT_TRUE(readable);
	EXPECT_TRUE(stillRunning);
	EXPECT_GT(framesThen, 0u);
	EXPECT_GE(s.snapshots, 1u);
	EXPECT_NE(s.stopReason.find("stop requested"), std::string::npos) << s.stopReason;
	expectTheScene(out);
	EXPECT_EQ(s.run.snapshots, s.run.frames);
	EXPECT_TRUE(fs::exists(out + "/snapshots/000001/ground_aware.pgm"));
	const std::string index = slurp(out + "/snapshots/index.csv");
	EXPECT_EQ(size_t(std::count(index.begin(), index.end(), '\n')), s.run.frames + 1) << index;
}

// Odometry from a sensor section of its own: the robot stands 1 m behind the
// origin, so the objects are where the scene puts them only if the frames take
// the odometry's pose (at the origin they would land 1 m further on).
TEST(LiveInProcess, OdometrySectionPutsTheFramesWhereTheRobotIs)
{
	const std::string dir = freshDir("odo"), out = dir + "/out";
	// The odometry section starts first and the camera 0.3 s later
	// (time_between_launches), so the first frame already has a pose.
	const std::string cam = cameraIni(dir, "-1.0,0,0");
	const std::string ini =
		"[global]\ntime_between_launches = 300\n\n[A_ODOMETRY]\ndriver = CSimulatedSceneSensor\n"
		"process_rate = 50\nsensorLabel = BASE\nscene = " +
		dir + "/test.scene\ndepth = false\nodometry = true\n\n" + cam.substr(cam.find("[CAM]"));
	writeFile(dir + "/sensors.ini", ini);
	auto live = liveOptions(dir + "/sensors.ini");
	live.maxFrames = 6;
	std::atomic<bool> stop{false};
	gam::mapper::Mapper mapper(mapperOptions(out));
	const auto s = gam::mapper::runLive(mapper, live, stop);
	EXPECT_EQ(s.stopReason, "--max-frames 6");
	EXPECT_EQ(s.run.frames, 6u);
	EXPECT_GT(s.odometry, 0u);
	expectTheScene(out);
	// ... and not 1 m further on, where a robot at the origin would put the box.
	const COccupancyGridMap2D g = gam::maps::readStockGrid(out + "/ground_aware.gridmap.gz");
	EXPECT_LE(maxOcc(g, kBoxX + 0.95, kBoxX + 1.05, kBoxY - 0.05, kBoxY + 0.05), 0.5);
}

// --max-frames and --record; no odometry: said once on stderr, robot at the origin.
TEST(LiveInProcess, MaxFramesEndsTheRunAndTheRecordHoldsEveryObservation)
{
	const std::string dir = freshDir("record"), out = dir + "/out";
	writeFile(dir + "/sensors.ini", cameraIni(dir, "0,0,0", "odometry = false\n"));
	auto live = liveOptions(dir + "/sensors.ini");
	live.maxFrames = 4;
	live.recordPath = dir + "/rec.rawlog";
	std::atomic<bool> stop{false};
	gam::mapper::Mapper mapper(mapperOptions(out));
	::testing::internal::CaptureStderr();
	const auto s = gam::mapper::runLive(mapper, live, stop);
	const std::string err = ::testing::internal::GetCapturedStderr();
	EXPECT_EQ(s.stopReason, "--max-frames 4");
	EXPECT_EQ(s.run.frames, 4u);
	EXPECT_EQ(s.run.framesWithoutOdometry, 4u);
	const std::string said = "no odometry (no CObservationOdometry received): the robot stays at the origin";
	ASSERT_NE(err.find(said), std::string::npos) << err;
	EXPECT_EQ(err.find(said), err.rfind(said)) << "said more than once: " << err;
	// Every observation received is in the rawlog, as rawlog-grabber writes them.
	EXPECT_EQ(s.recorded, s.received);
	mrpt::io::CFileGZInputStream in(live.recordPath);
	auto ar = mrpt::serialization::archiveFrom(in);
	size_t n = 0, scans = 0;
	try
	{
		for (;;)
		{
			auto o = ar.ReadObject();
			n++;
			if (auto k = std::dynamic_pointer_cast<mrpt::obs::CObservation3DRangeScan>(o))
			{
				scans++;
				EXPECT_EQ(k->sensorLabel, "SIM_KINECT");
				EXPECT_EQ(k->rangeImage.cols(), 256);
			}
		}
	}
	catch (const std::exception&)  // end of file
	{
	}
	EXPECT_EQ(n, s.received);
	EXPECT_EQ(scans, s.received);
	EXPECT_GE(n, 4u);
	// ... and the offline mode replays it: every recorded scan is a frame.
	auto offline = mapperOptions(dir + "/replay");
	offline.rawlogPath = live.recordPath;
	gam::mapper::Mapper replay(offline);
	EXPECT_EQ(replay.run().frames, scans);
}

// A driver that fails while running (a camera unplugged): the run ends, the
// maps of the frames so far are written, and the summary names the section.
TEST(LiveInProcess, SensorFailingWhileRunningEndsTheRunAndKeepsTheMaps)
{
	const std::string dir = freshDir("unplug"), out = dir + "/out";
	writeFile(dir + "/sensors.ini", cameraIni(dir, "0,0,0", "fail_after = 5\n"));
	std::atomic<bool> stop{false};
	gam::mapper::Mapper mapper(mapperOptions(out));
	const auto s = gam::mapper::runLive(mapper, liveOptions(dir + "/sensors.ini"), stop);
	EXPECT_TRUE(s.sensorFailed);
	EXPECT_EQ(s.stopReason, "[CAM] (CSimulatedSceneSensor) failed: simulated camera unplugged");
	EXPECT_EQ(s.run.frames + s.dropped, 5u);
	expectTheScene(out);
}

// initialize() failing: an error naming the section and MRPT's reason; no map
// is written, nothing is left in the output folder.
TEST(LiveInProcess, InitializeFailureNamesTheSectionAndTheReason)
{
	const std::string dir = freshDir("init"), out = dir + "/out";
	writeFile(dir + "/sensors.ini", cameraIni(dir, "0,0,0", "fail_initialize = cannot open /dev/video7\n"));
	std::atomic<bool> stop{false};
	gam::mapper::Mapper mapper(mapperOptions(out));
	try
	{
		gam::mapper::runLive(mapper, liveOptions(dir + "/sensors.ini"), stop);
		FAIL() << "no error";
	}
	catch (const RunError& e)
	{
		EXPECT_STREQ(e.what(), "[CAM] (CSimulatedSceneSensor): initialize() failed: cannot open /dev/video7");
	}
	EXPECT_TRUE(fs::is_empty(out));
}

// The sensors .ini: each problem is one line that names the file and section,
// found before any device is opened.
TEST(LiveInProcess, SensorsIniErrorsAreOneLineAndNameTheSection)
{
	const std::string dir = freshDir("ini");
	const std::string scene = dir + "/test.scene";
	writeFile(scene, sceneText("0,0,0"));
	auto err = [&](const std::string& text) -> std::string {
		writeFile(dir + "/s.ini", text);
		try
		{
			gam::mapper::checkSensorsIni(dir + "/s.ini");
		}
		catch (const ConfigError& e)
		{
			return e.what();
		}
		return "(no error)";
	};
	const std::string f = dir + "/s.ini: ";
	EXPECT_EQ(
		err("[global]\nrawlog_prefix = x\n"), f + "no sensor section (each sensor is a [SECTION] with driver = CLASS "
												  "and process_rate = HZ, besides [global])");
	// A calibration section rawlog-grabber skips is not a sensor either.
	EXPECT_EQ(
		err("[CAM_LEFT]\nrawlog-grabber-ignore = true\nfx = 500\n"),
		f + "no sensor section (each sensor is a [SECTION] with driver = CLASS and process_rate = HZ, besides "
			"[global])");
	EXPECT_EQ(err("[CAM]\nprocess_rate = 10\n"), f + "[CAM] has no driver = CLASS (e.g. COpenNI2Sensor)");
	EXPECT_EQ(
		err("[CAM]\ndriver = CNoSuchCamera\nprocess_rate = 10\n"),
		f + "[CAM] unknown driver 'CNoSuchCamera' (not a registered mrpt::hwdrivers sensor class, e.g. "
			"COpenNI2Sensor, CKinect, CHokuyoURG; --plugins loads more)");
	EXPECT_EQ(
		err("[CAM]\ndriver = CSimulatedSceneSensor\nscene = " + scene + "\n"),
		f + "[CAM] (CSimulatedSceneSensor): process_rate must be > 0 (Hz: how often doProcess() is called)");
	// The driver's own loadConfig() rejects its section: MRPT's message, one line.
	const std::string e = err("[CAM]\ndriver = CSimulatedSceneSensor\nprocess_rate = 10\n");
	EXPECT_EQ(e.rfind(f + "[CAM] (CSimulatedSceneSensor): ", 0), 0u) << e;
	EXPECT_NE(e.find("'scene'"), std::string::npos) << e;
	EXPECT_EQ(e.find('\n'), std::string::npos) << e;
	try
	{
		gam::mapper::checkSensorsIni(dir + "/missing.ini");
		ADD_FAILURE() << "no error";
	}
	catch (const ConfigError& ex)
	{
		EXPECT_EQ(std::string(ex.what()), "cannot read sensors file " + dir + "/missing.ini");
	}
	EXPECT_EQ(
		gam::mapper::checkSensorsIni(
			(writeFile(dir + "/ok.ini", cameraIni(dir, "0,0,0") + "\n[CAM_LEFT]\nrawlog-grabber-ignore = true\n"),
			 dir + "/ok.ini")),
		std::vector<std::string>{"CAM"});
}

// ------------------------------------------------------------ the program
namespace
{
const std::string kExe = GAM_MAPPER_EXE, kLiveExe = GAM_MAPPER_LIVE_EXE;
const std::string kPlugin = GAM_SIM_SENSOR_PLUGIN;

struct Child
{
	pid_t pid = -1;
	std::string outFile, errFile;
};

/** Starts the mapper with these arguments, stdout and stderr into files. */
Child startMapper(const std::string& dir, const std::vector<std::string>& args)
{
	static int n = 0;
	Child c;
	c.outFile = dir + "/stdout" + std::to_string(n) + ".txt";
	c.errFile = dir + "/stderr" + std::to_string(n++) + ".txt";
	c.pid = fork();
	if (c.pid == 0)
	{
		if (!freopen(c.outFile.c_str(), "w", stdout) || !freopen(c.errFile.c_str(), "w", stderr)) _exit(127);
		std::vector<char*> argv{const_cast<char*>(kExe.c_str())};
		for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
		argv.push_back(nullptr);
		execv(kExe.c_str(), argv.data());
		_exit(127);
	}
	return c;
}

int waitExit(const Child& c)
{
	int st = 0;
	if (waitpid(c.pid, &st, 0) != c.pid) return -1;
	return WIFEXITED(st) ? WEXITSTATUS(st) : 128 + (WIFSIGNALED(st) ? WTERMSIG(st) : 0);
}
}  // namespace

// The whole program: Ctrl-C (SIGINT from outside) once the first snapshot is
// there; it stops the driver, writes the final maps and exits 0.
TEST(LiveProgram, SigintSavesTheMapsAndExitsZero)
{
	const std::string dir = freshDir("prog_sigint"), out = dir + "/out";
	writeFile(dir + "/sensors.ini", cameraIni(dir, "0,0,0"));
	const Child c = startMapper(
		dir, {"--live", dir + "/sensors.ini", "--plugins", kPlugin, "--out", out, "--snapshot-seconds", "0.2",
			  "--max-seconds", "60", "-q"});
	ASSERT_GT(c.pid, 0);
	const bool snapshot = waitFor([&] { return fs::exists(out + "/ground_aware.yaml"); });
	kill(c.pid, SIGINT);
	const int rc = waitExit(c);
	ASSERT_TRUE(snapshot) << slurp(c.errFile);
	EXPECT_EQ(rc, 0) << slurp(c.errFile);
	const std::string so = slurp(c.outFile);
	EXPECT_NE(so.find("stopped: stop requested (SIGINT/SIGTERM)"), std::string::npos) << so;
	EXPECT_NE(so.find("ground_aware  mrpt::maps::CGroundAwareOccupancyGrid"), std::string::npos) << so;
	EXPECT_NE(slurp(c.errFile).find("the robot stays at the origin"), std::string::npos);
	expectTheScene(out);
}

// --max-seconds ends the run by itself (exit 0); SIGTERM is a stop too.
TEST(LiveProgram, MaxSecondsAndSigtermEndTheRunWithTheMaps)
{
	const std::string dir = freshDir("prog_max"), out = dir + "/out";
	writeFile(dir + "/sensors.ini", cameraIni(dir, "0,0,0"));
	const Child c =
		startMapper(dir, {"--live", dir + "/sensors.ini", "-p", kPlugin, "--out", out, "--max-seconds", "2.5", "-q"});
	EXPECT_EQ(waitExit(c), 0) << slurp(c.errFile);
	EXPECT_NE(slurp(c.outFile).find("stopped: --max-seconds 2.5"), std::string::npos) << slurp(c.outFile);
	expectTheScene(out);

	const std::string out2 = dir + "/out2";
	const Child t =
		startMapper(dir, {"--live", dir + "/sensors.ini", "-p", kPlugin, "--out", out2, "--max-seconds", "60", "-q"});
	const bool frames = waitFor([&] { return slurp(t.errFile).find("stays at the origin") != std::string::npos; });
	kill(t.pid, SIGTERM);
	EXPECT_EQ(waitExit(t), 0) << slurp(t.errFile);
	ASSERT_TRUE(frames);
	EXPECT_NE(slurp(t.outFile).find("stopped: stop requested (SIGINT/SIGTERM)"), std::string::npos) << slurp(t.outFile);
	expectTheScene(out2);
}

// The program's one-line errors and exit codes (2: command line / .ini; 1: a device).
TEST(LiveProgram, ErrorsAreOneLineWithExitCodes)
{
	const std::string dir = freshDir("prog_err"), out = dir + "/out";
	auto run = [&](const std::vector<std::string>& args, int& rc) {
		const Child c = startMapper(dir, args);
		rc = waitExit(c);
		return slurp(c.errFile);
	};
	int rc = 0;
	std::string e = run({"--live", dir + "/none.ini", "--out", out}, rc);
	EXPECT_EQ(rc, 2);
	EXPECT_EQ(e, "ground-aware-mapper: error: cannot read sensors file " + dir + "/none.ini\n");
	writeFile(dir + "/u.ini", "[CAM]\ndriver = CSimulatedSceneSensor\nprocess_rate = 10\n");
	// Without --plugins the program does not know the test's driver.
	e = run({"--live", dir + "/u.ini", "--out", out}, rc);
	EXPECT_EQ(rc, 2);
	EXPECT_NE(e.find("[CAM] unknown driver 'CSimulatedSceneSensor'"), std::string::npos) << e;
	EXPECT_EQ(std::count(e.begin(), e.end(), '\n'), 1) << e;
	writeFile(dir + "/f.ini", cameraIni(dir, "0,0,0", "fail_initialize = no device\n"));
	e = run({"--live", dir + "/f.ini", "-p", kPlugin, "--out", out}, rc);
	EXPECT_EQ(rc, 1);
	EXPECT_EQ(e, "ground-aware-mapper: error: [CAM] (CSimulatedSceneSensor): initialize() failed: no device\n");
	e = run({"--rawlog", dir + "/x.rawlog", "--record", dir + "/r.rawlog", "--out", out}, rc);
	EXPECT_EQ(rc, 2);
	EXPECT_EQ(e, "ground-aware-mapper: error: --snapshot-seconds, --max-seconds and --record go with --live\n");
	e = run({"--live", dir + "/f.ini", "-p", dir + "/nope.so", "--out", out}, rc);
	EXPECT_EQ(rc, 2);
	EXPECT_EQ(e.rfind("ground-aware-mapper: error: --plugins " + dir + "/nope.so: ", 0), 0u) << e;
	EXPECT_FALSE(fs::exists(out + "/ground_aware.yaml"));
}

// The offline program does not load MRPT's sensor drivers (they cost every run
// start-up time and memory); a --live command line goes to its live half.
TEST(LiveProgram, OnlyTheLiveHalfLinksTheSensorDrivers)
{
	const std::string dir = freshDir("prog_ldd");
	auto libs = [&](const std::string& exe) {
		EXPECT_EQ(std::system(("ldd '" + exe + "' > '" + dir + "/ldd.txt'").c_str()), 0);
		return slurp(dir + "/ldd.txt");
	};
	const std::string offline = libs(kExe), live = libs(kLiveExe);
	EXPECT_NE(offline.find("libmrpt-maps"), std::string::npos) << offline;
	EXPECT_EQ(offline.find("libmrpt-hwdrivers"), std::string::npos) << offline;
	EXPECT_NE(live.find("libmrpt-hwdrivers"), std::string::npos) << live;
}
