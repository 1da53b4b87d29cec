// Ground-aware mapping for MRPT
// The live mode of ground-aware-mapper (`--live SENSORS.ini`): the maps are
// built as frames arrive from MRPT sensor drivers (mrpt::hwdrivers::
// CGenericSensor), configured as rawlog-grabber configures them. Library
// target ground_mapper_live (built when libmrpt-hwdrivers-dev is installed).
#pragma once

#include <gam/mapper/Mapper.h>
#include <gam/mapper/StopSignal.h>

#include <atomic>
#include <string>
#include <vector>

namespace gam::mapper
{
struct LiveOptions
{
	/** The sensors, in rawlog-grabber's format: `[global]` plus one section
	 * per sensor with `driver = <CGenericSensor class>` and `process_rate`
	 * [Hz]; sections with `rawlog-grabber-ignore = true` are not sensors. */
	std::string sensorsIniPath;
	/** Every this many seconds the maps' outputs are written into
	 * MapperOptions::outDir (Mapper::publishMapsNow); 0 = only at the end. */
	double snapshotSeconds = 10;
	double maxSeconds = 0;  ///< > 0: end the run this long after every sensor has started
	size_t maxFrames = 0;   ///< > 0: end the run after this many frames were inserted
	/** If set: every observation received (all classes, in the order they were
	 * processed) goes into this rawlog (observations format, gzip level of
	 * [global] rawlog_GZ_compress_level, default 1), as rawlog-grabber writes it. */
	std::string recordPath;
	bool progress = true;  ///< progress line on stderr
};

struct LiveSummary
{
	RunSummary run;          ///< frames, timing, files (as the offline mode's)
	size_t received = 0;     ///< observations the sensors delivered
	size_t odometry = 0;     ///< of them CObservationOdometry that set the robot pose
	size_t dropped = 0;      ///< scans not inserted: a newer one of the same sensor was waiting
	size_t recorded = 0;     ///< written to LiveOptions::recordPath
	size_t snapshots = 0;    ///< times the maps were written during the run
	double seconds = 0;      ///< from the sensors' start to their stop
	std::string stopReason;  ///< "stop requested", "--max-frames", "--max-seconds", or the sensor failure
	/** A sensor failed while running (its doProcess() threw): the run ended
	 * there, the maps so far were saved, and stopReason says which and why. */
	bool sensorFailed = false;
	std::string text() const;
};

/** Checks the sensors .ini without touching a device: readable, at least one
 * sensor section, each with a `driver` that names a registered sensor class
 * and `process_rate` > 0, and each driver's loadConfig() accepts its section.
 * Returns the sensor section names. Throws ConfigError naming the section. */
std::vector<std::string> checkSensorsIni(const std::string& sensorsIniPath);

/** Runs the live mode: the maps of `mapper` (built from MapperOptions whose
 * rawlogPath and maxFrames are not used here; outDir, localMap, snapshotEvery...
 * are), fed by the sensors of `live`. Each sensor runs in a thread of its own as in
 * rawlog-grabber (initialize(), then doProcess() + getObservations() at its
 * process_rate); the calling thread maps. The run ends when `stop` becomes
 * true (e.g. from a SIGINT handler), at maxFrames / maxSeconds, or when a
 * sensor fails; then the sensors stop and the final maps are written as the
 * offline mode writes them. Throws ConfigError (the sensors .ini, as
 * checkSensorsIni()), RunError (a sensor's initialize() failing, naming its
 * section and MRPT's reason; a stop while the sensors start; no frame at all;
 * a frame a map rejects; output errors); then the final outputs are not
 * written (snapshots already in outDir stay). */
LiveSummary runLive(Mapper& mapper, const LiveOptions& live, const std::atomic<bool>& stop);

}  // namespace gam::mapper
