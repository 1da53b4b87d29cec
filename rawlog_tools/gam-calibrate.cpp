// Ground-aware mapping for MRPT -- gam-calibrate: the camera mount measured
// from the floor (issue #15). For each depth camera of a rawlog, every frame's
// ground plane (RRT-GPD + RANSAC, as CGroundAwareOccupancyGrid finds it) gives
// the sensor's height above the floor, its pitch and its roll; frames whose
// plane disagrees with the others are rejected; the rest give the estimate.
//
// usage: gam-calibrate --rawlog FILE [--label CAM] [--config FILE.ini] [--write-ini FILE.ini]
// prints one line per camera:
//   CAM z=<m> pitch=<deg> roll=<deg> (+-<m>, +-<deg>, +-<deg>) frames=<used>/<total>
// (the +- are the standard errors of the means over the frames used), then
// the declared sensorPose for comparison. MRPT's yaw/pitch/roll convention.
// The declared pose is a rough guess: each frame is first searched for the
// floor within height +- 0.3 m, pitch +- 20 deg, roll +- 10 deg of it
// (gam::searchFloor), and that floor places the points for the map's plane.
// x, y and yaw are not observable from a floor: --write-ini keeps the
// declared ones and writes `CAM = x y z yaw pitch roll` into the file's
// [sensor_poses] section, which ground-aware-mapper applies to the
// observations of that label.
// exit: 0 ok, 1 bad input or no estimate, 2 command line.
#include <gam/common/CommandLine.h>
#include <gam/common/Version.h>
#include <mrpt/3rdparty/tclap/CmdLine.h>
#include <mrpt/config/CConfigFileMemory.h>
#include <mrpt/maps/CGroundAwareOccupancyGrid.h>
#include <mrpt/maps/CMultiMetricMap.h>
#include <mrpt/maps/registerBaselineMaps.h>
#include <mrpt/maps/registerGroundAwareMaps.h>
#include <mrpt/obs/CObservation3DRangeScan.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <map>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "gam/mapper/Mapper.h"
#include "gam/mapper/RawlogFrames.h"

using mrpt::maps::CGroundAwareOccupancyGrid;

namespace
{
struct Failure : std::runtime_error
{
	using std::runtime_error::runtime_error;
};

std::string readText(const std::string& path)
{
	std::ifstream f(path);
	if (!f) throw Failure("cannot read " + path);
	return std::string((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
}

/** The ground-aware grid of the mapper's .ini (its plane detection settings). */
CGroundAwareOccupancyGrid gridFromConfig(const mrpt::config::CConfigFileBase& ini, const std::string& path)
{
	mrpt::maps::CMultiMetricMap mm;
	gam::mapper::createMaps(ini, "map", mm);
	const auto ga = mm.mapByClass<CGroundAwareOccupancyGrid>();
	if (!ga) throw Failure(path + " defines no groundAwareGrid (its plane detection settings are needed)");
	return *ga;
}

struct Camera
{
	std::vector<gam::SensorMount> perFrame;
	size_t frames = 0;
	std::vector<gam::SensorMount> searchedMounts;  ///< what the search found near the declared mount, per frame
	size_t mapPlaneOverruled = 0;                  ///< frames where the map's plane left the search's
	mrpt::poses::CPose3D declared;
};

/** Sensor-frame points of a depth frame, every `step`-th pixel of every
 * `step`-th row (ray (1, (cx - c) / fx, (cy - r) / fy) times the depth;
 * MRPT's convention), zero and out-of-range pixels skipped. */
std::vector<Eigen::Vector3d> sensorPoints(const mrpt::obs::CObservation3DRangeScan& o, int step)
{
	std::vector<Eigen::Vector3d> pts;
	if (!o.hasRangeImage || !o.range_is_depth) return pts;
	const auto& cp = o.cameraParams;
	const double fx = cp.fx(), fy = cp.fy(), cx = cp.cx(), cy = cp.cy();
	if (!(fx > 0) || !(fy > 0)) return pts;
	const int rows = int(o.rangeImage.rows()), cols = int(o.rangeImage.cols());
	const double maxR = o.maxRange > 0 ? o.maxRange : 1e9;
	for (int r = 0; r < rows; r += step)
		for (int c = 0; c < cols; c += step)
		{
			const double d = o.rangeImage(r, c) * double(o.rangeUnits);
			if (!(d > 0) || d > maxR) continue;
			pts.emplace_back(d, (cx - c) / fx * d, (cy - r) / fy * d);
		}
	return pts;
}

/** Writes `label = x y z yaw pitch roll` into [sensor_poses] of `path`,
 * keeping the rest of the file (created if missing). */
void writeSensorPose(const std::string& path, const std::string& label, const mrpt::poses::CPose3D& p)
{
	std::vector<std::string> lines;
	{
		std::ifstream f(path);
		std::string l;
		while (f && std::getline(f, l)) lines.push_back(l);
	}
	char value[256];
	const double k = 180.0 / M_PI;
	std::snprintf(
		value, sizeof value, "%s = %.4f %.4f %.4f %.3f %.3f %.3f  ; x y z [m] yaw pitch roll [deg], gam-calibrate",
		label.c_str(), p.x(), p.y(), p.z(), p.yaw() * k, p.pitch() * k, p.roll() * k);
	auto trim = [](std::string s) {
		s.erase(0, s.find_first_not_of(" \t"));
		s.erase(s.find_last_not_of(" \t\r") + 1);
		return s;
	};
	int section = -1, end = int(lines.size());
	for (int i = 0; i < int(lines.size()); i++)
	{
		const std::string t = trim(lines[size_t(i)]);
		if (t.size() > 1 && t.front() == '[')
		{
			if (section >= 0 && i > section)
			{
				end = i;
				break;
			}
			if (t == "[sensor_poses]") section = i;
		}
	}
	if (section < 0)
	{
		if (!lines.empty() && !trim(lines.back()).empty()) lines.push_back("");
		lines.push_back("[sensor_poses]");
		lines.push_back("# sensorPose per sensor label, applied by ground-aware-mapper in place of the rawlog's");
		lines.push_back(value);
	}
	else
	{
		bool replaced = false;
		for (int i = section + 1; i < end; i++)
		{
			const std::string t = trim(lines[size_t(i)]);
			const auto eq = t.find('=');
			if (eq != std::string::npos && trim(t.substr(0, eq)) == label)
			{
				lines[size_t(i)] = value;
				replaced = true;
			}
		}
		if (!replaced) lines.insert(lines.begin() + end, value);
	}
	std::ofstream f(path);
	for (const auto& l : lines) f << l << "\n";
	if (!f) throw Failure("cannot write " + path);
}
}  // namespace

int main(int argc, char** argv)
{
	try
	{
		TCLAP::CmdLine cmd(
			"gam-calibrate: height, pitch and roll of each depth camera measured from the floor", ' ', GAM_VERSION);
		TCLAP::ValueArg<std::string> argRawlog("", "rawlog", "rawlog with depth frames", true, "", "FILE", cmd);
		TCLAP::ValueArg<std::string> argLabel("", "label", "only this camera (sensorLabel)", false, "", "CAM", cmd);
		TCLAP::ValueArg<std::string> argConfig(
			"", "config", "the mapper's .ini (plane detection settings, [sensor_poses]); default: built-in defaults",
			false, "", "FILE", cmd);
		TCLAP::ValueArg<std::string> argWrite(
			"", "write-ini", "write the measured poses into [sensor_poses] of this .ini", false, "", "FILE", cmd);
		if (const int rc = gam::parseCommandLine(cmd, argc, argv, "gam-calibrate"); rc >= 0) return rc;

		// The mapper's .ini may define the comparison maps too: know their kinds.
		mrpt::maps::registerGroundAwareMaps();
		mrpt::maps::registerBaselineMaps();
		CGroundAwareOccupancyGrid base;
		std::map<std::string, mrpt::poses::CPose3D> overrides;
		if (!argConfig.getValue().empty())
		{
			const mrpt::config::CConfigFileMemory ini(readText(argConfig.getValue()));
			base = gridFromConfig(ini, argConfig.getValue());
			overrides = gam::mapper::readSensorPoses(ini, argConfig.getValue());
		}
		// Collect every frame's measurement; the map's own check is not used
		// for the decision, only its per-frame value.
		auto opts = base.groundOptions();
		opts.mount.enabled = true;
		opts.mount.use_measured = false;
		base.setGroundOptions(opts);

		std::map<std::string, Camera> cams;
		std::map<std::string, CGroundAwareOccupancyGrid> grids;  // one per camera
		gam::mapper::RawlogFrameReader reader(argRawlog.getValue());
		gam::mapper::Frame fr;
		size_t n = 0;
		while (reader.next(fr))
		{
			const auto* o3 = dynamic_cast<const mrpt::obs::CObservation3DRangeScan*>(fr.obs.get());
			if (!o3) continue;
			const std::string& label = fr.obs->sensorLabel;
			if (!argLabel.getValue().empty() && label != argLabel.getValue()) continue;
			if (const auto it = overrides.find(label); it != overrides.end()) fr.obs->setSensorPose(it->second);
			auto g = grids.find(label);
			if (g == grids.end()) g = grids.emplace(label, base).first;
			Camera& cam = cams[label];
			cam.frames++;
			fr.obs->getSensorPose(cam.declared);
			// Search the frame for the floor near the declared mount first: a
			// rough guess (height +- 0.3 m, pitch +- 20 deg, roll +- 10 deg) tilts
			// the floor too much for the map's own plane detection. The plane
			// found places the points; the map's plane then refines it. The
			// result does not depend on the guess (calibrating again from it
			// gives the same answer): the search's points and seed are the frame's.
			std::optional<gam::SensorMount> searched;
			{
				const mrpt::poses::CPose3D& dp = cam.declared;
				const auto floor = gam::searchFloor(
					sensorPoints(*o3, 4), gam::SensorMount{dp.z(), dp.pitch(), dp.roll()}, gam::FloorSearchParams{},
					unsigned(cam.frames));
				if (const auto m = floor ? gam::mountFromFloor(*floor) : std::nullopt)
				{
					fr.obs->setSensorPose(mrpt::poses::CPose3D(dp.x(), dp.y(), m->height, dp.yaw(), m->pitch, m->roll));
					cam.searchedMounts.push_back(*m);
					searched = m;
				}
			}
			const size_t before =
				g->second.mountChecks().count(label) ? g->second.mountChecks().at(label).status().frames_checked : 0;
			// A fresh grid per frame would also do: only the plane of this frame counts.
			g->second.insertObservation(*fr.obs, fr.robotPose);
			const gam::MountStatus& s = g->second.mountChecks().at(label).status();
			if (s.frames_checked > before)
			{
				// The map's plane refines the search's, unless it left it by more
				// than the mount check's tolerances: a plane fitted to a far floor
				// by a noisy camera (a RealSense seeing the floor only 2-5 m
				// ahead: 14 cm off under the robot) is worse than the image-wide
				// floor fit, which then stands.
				const auto& mp = g->second.groundOptions().mount;
				const bool agrees =
					!searched || (std::abs(s.last.height - searched->height) <= mp.tolerance_z &&
								  std::abs(s.last.pitch - searched->pitch) <= mp.tolerance_deg * M_PI / 180 &&
								  std::abs(s.last.roll - searched->roll) <= mp.tolerance_deg * M_PI / 180);
				cam.perFrame.push_back(agrees ? s.last : *searched);
				cam.mapPlaneOverruled += !agrees;
			}
			else if (searched)
				cam.perFrame.push_back(*searched);
			if (++n % 50 == 0) std::cerr << "gam-calibrate: " << n << " depth frames\n";
		}
		if (cams.empty())
			throw Failure(
				"no CObservation3DRangeScan" +
				(argLabel.getValue().empty() ? std::string() : " labelled '" + argLabel.getValue() + "'") + " in " +
				argRawlog.getValue());

		int status = 0;
		const double k = 180.0 / M_PI;
		for (const auto& [label, cam] : cams)
		{
			const gam::MountEstimate e = gam::estimateMount(cam.perFrame);
			if (!e.used)
			{
				std::cout << label << " no estimate: no frame had a floor plane (" << cam.frames << " frames)\n";
				status = 1;
				continue;
			}
			std::printf(
				"%s z=%.4f pitch=%.3f roll=%.3f (+-%.4f, +-%.3f, +-%.3f) frames=%zu/%zu\n", label.c_str(),
				e.mean.height, e.mean.pitch * k, e.mean.roll * k, e.standard_error.height, e.standard_error.pitch * k,
				e.standard_error.roll * k, e.used, cam.frames);
			std::printf(
				"  declared sensorPose: z=%.4f pitch=%.3f roll=%.3f (x=%.4f y=%.4f yaw=%.3f kept: not observable from "
				"the floor); floor found by the search in %zu frames; %zu frames had a floor plane, %zu rejected\n",
				cam.declared.z(), cam.declared.pitch() * k, cam.declared.roll() * k, cam.declared.x(), cam.declared.y(),
				cam.declared.yaw() * k, cam.searchedMounts.size(), cam.perFrame.size(), cam.perFrame.size() - e.used);
			if (!cam.searchedMounts.empty())
			{
				const gam::MountEstimate se = gam::estimateMount(cam.searchedMounts);
				std::printf(
					"  the search alone (floor RANSAC in the image, before the map's plane): z=%.4f pitch=%.3f "
					"roll=%.3f; the map's plane left it beyond the mount tolerances in %zu frames (the search's "
					"kept there)\n",
					se.mean.height, se.mean.pitch * k, se.mean.roll * k, cam.mapPlaneOverruled);
			}
			if (!argWrite.getValue().empty())
			{
				const mrpt::poses::CPose3D p(
					cam.declared.x(), cam.declared.y(), e.mean.height, cam.declared.yaw(), e.mean.pitch, e.mean.roll);
				writeSensorPose(argWrite.getValue(), label, p);
				std::printf("  written to [sensor_poses] of %s\n", argWrite.getValue().c_str());
			}
		}
		return status;
	}
	catch (const std::exception& e)
	{
		std::cerr << "gam-calibrate: error: " << e.what() << "\n";
		return 1;
	}
}
