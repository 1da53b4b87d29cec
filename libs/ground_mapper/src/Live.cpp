// The live mode of ground-aware-mapper: MRPT sensor drivers, configured and
// run as rawlog-grabber (MRPT 2.5.8, libs/apps/src/RawlogGrabberApp.cpp) runs
// them, feed the maps of a gam::mapper::Mapper.
#include <gam/common/Strings.h>
#include <gam/mapper/Errors.h>
#include <gam/mapper/Live.h>
#include <gam/mapper/RawlogFrames.h>
#include <mrpt/config/CConfigFileMemory.h>
#include <mrpt/hwdrivers/CGenericSensor.h>
#include <mrpt/hwdrivers/COpenNI2Sensor.h>
#include <mrpt/io/CFileGZOutputStream.h>
#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/obs/CObservation3DRangeScan.h>
#include <mrpt/obs/CObservationOdometry.h>
#include <mrpt/serialization/CArchive.h>
#include <mrpt/system/CRateTimer.h>
#include <mrpt/system/thread_name.h>

#include <unistd.h>

#include <chrono>
#include <condition_variable>
#include <fstream>
#include <future>
#include <iomanip>
#include <iostream>
#include <map>
#include <mutex>
#include <sstream>
#include <thread>

namespace gam::mapper
{
namespace
{
using mrpt::hwdrivers::CGenericSensor;
using clk = std::chrono::steady_clock;
constexpr const char* kApp = "ground-aware-mapper";

std::string readFile(const std::string& path)
{
	std::ifstream f(path, std::ios::binary);
	if (!f) throw ConfigError("cannot read sensors file " + path);
	std::ostringstream ss;
	ss << f.rdbuf();
	if (!f && !f.eof()) throw ConfigError("cannot read sensors file " + path);
	return ss.str();
}

struct SensorSection
{
	std::string section, driver;
	CGenericSensor::Ptr sensor;
	std::string where() const { return "[" + section + "] (" + driver + ")"; }
};

/** rawlog-grabber's rule: every section but [global] is a sensor, unless it
 * says `rawlog-grabber-ignore = true` (a camera's calibration sections). */
std::vector<std::string> sensorSectionNames(const mrpt::config::CConfigFileBase& ini)
{
	std::vector<std::string> all, out;
	ini.getAllSections(all);
	for (const auto& s : all)
		if (!s.empty() && s != "global" && !ini.read_bool(s, "rawlog-grabber-ignore", false, false)) out.push_back(s);
	return out;
}

/** createSensorPtr(), but a COpenNI2Sensor that has no device `deviceNumber`
 * is never destroyed: in MRPT 2.5.8 its destructor calls close(deviceNumber),
 * which throws "No OpenNI2 devices found." out of the destructor and so ends
 * the program (std::terminate), also for a sensor whose initialize() was never
 * called. The object is left to the end of the process instead. */
CGenericSensor::Ptr createSensor(const std::string& driver, int deviceNumber)
{
	CGenericSensor* raw = CGenericSensor::createSensor(driver);
	if (!raw) return {};
	return CGenericSensor::Ptr(raw, [deviceNumber](CGenericSensor* p) {
		if (const auto* oni = dynamic_cast<const mrpt::hwdrivers::COpenNI2Sensor*>(p);
			oni && oni->getNumDevices() <= deviceNumber)
			return;
		delete p;
	});
}

/** Creates and configures every sensor; no device is touched (initialize()
 * is not called). Throws ConfigError. */
std::vector<SensorSection> createSensors(const std::string& path, const mrpt::config::CConfigFileBase& ini)
{
	const auto names = sensorSectionNames(ini);
	if (names.empty())
		throw ConfigError(
			path +
			": no sensor section (each sensor is a [SECTION] with driver = CLASS and process_rate = HZ, "
			"besides [global])");
	std::vector<SensorSection> out;
	for (const auto& name : names)
	{
		SensorSection s;
		s.section = name;
		s.driver = gam::trim(ini.read_string(name, "driver", "", false));
		if (s.driver.empty()) throw ConfigError(path + ": [" + name + "] has no driver = CLASS (e.g. COpenNI2Sensor)");
		s.sensor = createSensor(s.driver, ini.read_int(name, "device_number", 0, false));
		if (!s.sensor)
			throw ConfigError(
				path + ": [" + name + "] unknown driver '" + s.driver +
				"' (not a registered mrpt::hwdrivers sensor class, e.g. COpenNI2Sensor, CKinect, CHokuyoURG; "
				"--plugins loads more)");
		try
		{
			s.sensor->loadConfig(ini, name);
		}
		catch (const std::exception& e)
		{
			throw ConfigError(path + ": " + s.where() + ": " + conciseError(e.what()));
		}
		// rawlog-grabber asserts this too: it is the rate of the driver's loop.
		if (!(s.sensor->getProcessRate() > 0))
			throw ConfigError(
				path + ": " + s.where() + ": process_rate must be > 0 (Hz: how often doProcess() is called)");
		out.push_back(std::move(s));
	}
	return out;
}

/** What the sensor threads and the mapping thread share. */
struct Shared
{
	std::mutex mtx;
	std::condition_variable cv;
	CGenericSensor::TListObservations queue;  ///< by timestamp, as rawlog-grabber's
	std::atomic<bool> mustExit{false};
	bool failed = false;  ///< a sensor failed after initialize()
	std::string failure;
};

/** One sensor's thread, as rawlog-grabber's SensorThread: initialize(), then
 * doProcess() + getObservations() at process_rate; the driver is destroyed in
 * this thread too. `init` gets "" or initialize()'s error. */
void sensorThread(SensorSection s, Shared& sh, std::promise<std::string> init)
{
	try
	{
		s.sensor->initialize();
	}
	catch (const std::exception& e)
	{
		init.set_value(conciseError(e.what()));
		return;
	}
	catch (...)
	{
		init.set_value("unknown exception");
		return;
	}
	// MRPT 2.5.8's COpenNI2Sensor::initialize() returns without error when no
	// OpenNI2 device is connected, and the first doProcess() then aborts the
	// whole program on an assert (Debian builds keep asserts): this is the one
	// place to turn that into an error.
	if (const auto* oni = dynamic_cast<const mrpt::hwdrivers::COpenNI2Sensor*>(s.sensor.get());
		oni && oni->getNumDevices() <= 0)
	{
		init.set_value("no OpenNI2 device found (is the camera plugged in, and may this user open it?)");
		return;
	}
	init.set_value("");
	try
	{
		mrpt::system::CRateTimer rate(s.sensor->getProcessRate());
		CGenericSensor::TListObservations got;
		while (!sh.mustExit)
		{
			s.sensor->doProcess();
			s.sensor->getObservations(got);
			if (!got.empty())
			{
				std::lock_guard<std::mutex> lk(sh.mtx);
				sh.queue.insert(got.begin(), got.end());
				got.clear();
				sh.cv.notify_one();
			}
			rate.sleep();
		}
	}
	catch (const std::exception& e)
	{
		std::lock_guard<std::mutex> lk(sh.mtx);
		if (!sh.failed) sh.failure = s.where() + " failed: " + conciseError(e.what());
		sh.failed = true;
		sh.cv.notify_one();
	}
	catch (...)
	{
		std::lock_guard<std::mutex> lk(sh.mtx);
		if (!sh.failed) sh.failure = s.where() + " failed: unknown exception";
		sh.failed = true;
		sh.cv.notify_one();
	}
}

/** Stops and joins the sensor threads on every way out of runLive(): a
 * std::thread still joinable when destroyed would end the program. */
struct SensorThreads
{
	Shared& sh;
	std::vector<std::thread> threads;
	explicit SensorThreads(Shared& s) : sh(s) {}
	void stop()
	{
		sh.mustExit = true;
		for (auto& t : threads)
			if (t.joinable()) t.join();
	}
	~SensorThreads() { stop(); }
};

std::string fmt1(double v)
{
	std::ostringstream s;
	s << std::fixed << std::setprecision(1) << v;
	return s.str();
}
}  // namespace

std::vector<std::string> checkSensorsIni(const std::string& sensorsIniPath)
{
	const mrpt::config::CConfigFileMemory ini(readFile(sensorsIniPath));
	std::vector<std::string> out;
	for (const auto& s : createSensors(sensorsIniPath, ini)) out.push_back(s.section);
	return out;
}

std::string LiveSummary::text() const
{
	std::ostringstream s;
	s << run.text();
	s << "live: " << received << " observations received (" << odometry << " odometry), " << dropped
	  << " scans dropped (a newer one was waiting)";
	if (recorded) s << ", " << recorded << " recorded";
	s << ", " << snapshots << " snapshots; " << fmt1(seconds) << " s; stopped: " << stopReason << "\n";
	return s.str();
}

LiveSummary runLive(Mapper& mapper, const LiveOptions& live, const std::atomic<bool>& stop)
{
	LiveSummary out;
	if (live.snapshotSeconds < 0 || live.maxSeconds < 0)
		throw ConfigError("--snapshot-seconds and --max-seconds must be >= 0");

	// 1. Everything that can be checked without a device: the .ini, each
	// driver's own configuration, the record file, the output folder.
	const mrpt::config::CConfigFileMemory ini(readFile(live.sensorsIniPath));
	std::vector<SensorSection> sensors = createSensors(live.sensorsIniPath, ini);
	// rawlog-grabber's [global] keys that mean something here.
	const int launchGapMs = ini.read_int("global", "time_between_launches", 300, false);
	const int gzLevel = ini.read_int("global", "rawlog_GZ_compress_level", 1, false);

	mapper.begin();
	mrpt::io::CFileGZOutputStream recordFile;
	mrpt::serialization::CArchive::UniquePtr record;
	if (!live.recordPath.empty())
	{
		if (!recordFile.open(live.recordPath, std::max(0, std::min(9, gzLevel))))
		{
			mapper.abort();
			throw RunError("cannot write --record file " + live.recordPath);
		}
		record = mrpt::serialization::archiveUniquePtrFrom(recordFile);
	}

	// 2. The sensors: one thread each, started one after the other; each
	// initialize() must succeed before the next device is opened.
	Shared sh;
	SensorThreads threads(sh);
	try
	{
		for (size_t i = 0; i < sensors.size(); i++)
		{
			const std::string where = sensors[i].where(), name = sensors[i].section;
			std::promise<std::string> p;
			std::future<std::string> f = p.get_future();
			threads.threads.emplace_back(sensorThread, std::move(sensors[i]), std::ref(sh), std::move(p));
			mrpt::system::thread_name(name.substr(0, 15), threads.threads.back());
			const std::string err = f.get();
			if (!err.empty()) throw RunError(where + ": initialize() failed: " + err);
			// A driver's initialize() cannot be interrupted; a stop asked meanwhile
			// ends the run before the next device is opened.
			if (stop) throw RunError("stopped while the sensors were starting (after " + where + ")");
			if (i + 1 < sensors.size() && launchGapMs > 0)
				std::this_thread::sleep_for(std::chrono::milliseconds(launchGapMs));
		}
	}
	catch (...)
	{
		threads.stop();
		mapper.abort();
		throw;
	}

	// 3. Mapping: the observations in timestamp order; the newest odometry is
	// the robot pose; a scan is skipped if a newer one of the same sensor is
	// already waiting (the maps show the present, not a growing backlog).
	const bool tty = isatty(2) != 0;
	const auto tStart = clk::now();
	auto lastProgress = tStart, lastSnapshot = tStart;
	size_t framesAtSnapshot = 0;
	bool progressShown = false, saidNoOdometry = false, saidOtherOdometry = false, hasOdometry = false;
	std::string odometryLabel;
	mrpt::poses::CPose3D robotPose;
	bool frameLimit = false;

	auto clearProgress = [&] {
		if (progressShown && tty) std::cerr << "\r" << std::string(78, ' ') << "\r" << std::flush;
		progressShown = false;
	};
	auto note = [&](const std::string& msg) {
		clearProgress();
		std::cerr << kApp << ": " << msg << std::endl;
	};
	auto process = [&](const CGenericSensor::TListObservations& batch) {
		if (record)
			for (const auto& [t, o] : batch)
			{
				*record << *o;
				out.recorded++;
			}
		std::map<std::string, const mrpt::serialization::CSerializable*> newest;
		for (const auto& [t, o] : batch)
			if (const auto* ob = dynamic_cast<const mrpt::obs::CObservation*>(o.get()); ob && isUsableScan(*ob))
				newest[ob->sensorLabel] = o.get();
		for (const auto& [t, o] : batch)
		{
			const size_t entry = out.received++;
			auto ob = std::dynamic_pointer_cast<mrpt::obs::CObservation>(o);
			if (!ob) continue;
			if (const auto* odo = dynamic_cast<const mrpt::obs::CObservationOdometry*>(ob.get()))
			{
				if (odometryLabel.empty()) odometryLabel = odo->sensorLabel;
				if (odo->sensorLabel != odometryLabel)
				{
					if (!saidOtherOdometry)
						note(
							"odometry from '" + odo->sensorLabel + "' ignored: the robot pose is that of '" +
							odometryLabel + "' (the first odometry received)");
					saidOtherOdometry = true;
					continue;
				}
				robotPose = mrpt::poses::CPose3D(odo->odometry);
				hasOdometry = true;
				out.odometry++;
				continue;
			}
			if (!isUsableScan(*ob) || frameLimit) continue;
			if (newest[ob->sensorLabel] != o.get())
			{
				out.dropped++;
				continue;
			}
			if (!hasOdometry && !saidNoOdometry)
			{
				note("no odometry (no CObservationOdometry received): the robot stays at the origin");
				saidNoOdometry = true;
			}
			Frame fr;
			fr.index = mapper.runSoFar().frames;
			fr.entry = entry;
			fr.robotPose = robotPose;
			fr.hasOdometry = hasOdometry;
			fr.obs = ob;
			mapper.insert(fr);
			if (live.maxFrames && mapper.runSoFar().frames >= live.maxFrames) frameLimit = true;
		}
	};

	try
	{
		CGenericSensor::TListObservations batch;
		while (true)
		{
			{
				std::unique_lock<std::mutex> lk(sh.mtx);
				// A short wait: the stop flag is polled, a signal handler cannot notify.
				sh.cv.wait_for(lk, std::chrono::milliseconds(50), [&] { return !sh.queue.empty() || sh.failed; });
				batch.swap(sh.queue);
				if (sh.failed)
				{
					out.sensorFailed = true;
					out.stopReason = sh.failure;
				}
			}
			process(batch);
			batch.clear();
			const auto now = clk::now();
			const double el = std::chrono::duration<double>(now - tStart).count();
			const size_t frames = mapper.runSoFar().frames;
			if (out.sensorFailed) break;
			if (stop)
			{
				out.stopReason = "stop requested (SIGINT/SIGTERM)";
				break;
			}
			if (frameLimit)
			{
				out.stopReason = "--max-frames " + std::to_string(live.maxFrames);
				break;
			}
			if (live.maxSeconds > 0 && el >= live.maxSeconds)
			{
				out.stopReason = "--max-seconds " + fmt1(live.maxSeconds);
				break;
			}
			if (live.snapshotSeconds > 0 && frames > framesAtSnapshot &&
				std::chrono::duration<double>(now - lastSnapshot).count() >= live.snapshotSeconds)
			{
				mapper.publishMapsNow();
				out.snapshots++;
				framesAtSnapshot = frames;
				lastSnapshot = now;
			}
			if (live.progress && std::chrono::duration<double>(now - lastProgress).count() >= (tty ? 0.5 : 5.0))
			{
				lastProgress = now;
				std::cerr << (tty ? "\r" : "") << kApp << ": live: " << frames << " frames, "
						  << fmt1(el > 0 ? double(frames) / el : 0.0) << " frames/s, " << out.received
						  << " observations, " << out.dropped << " dropped, " << out.snapshots << " snapshots, "
						  << fmt1(el) << " s" << (tty ? "   " : "\n") << std::flush;
				progressShown = true;
			}
		}
		// 4. Stop the sensors, then what they delivered meanwhile.
		threads.stop();
		out.seconds = std::chrono::duration<double>(clk::now() - tStart).count();
		{
			std::lock_guard<std::mutex> lk(sh.mtx);
			batch.swap(sh.queue);
		}
		process(batch);
		clearProgress();
		if (record)
		{
			record.reset();
			recordFile.close();
		}
	}
	catch (...)
	{
		clearProgress();
		threads.stop();
		mapper.abort();
		throw;
	}

	if (mapper.runSoFar().frames == 0)
	{
		mapper.abort();
		if (out.sensorFailed) throw RunError(out.stopReason);
		throw RunError(
			"no frame in " + fmt1(out.seconds) + " s: the sensors delivered " + std::to_string(out.received) +
			" observations, none a CObservation3DRangeScan or CObservation2DRangeScan with data");
	}
	out.run = mapper.end();
	return out;
}

}  // namespace gam::mapper
