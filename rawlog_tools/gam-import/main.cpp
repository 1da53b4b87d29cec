// Ground-aware mapping for MRPT -- gam-import: your own depth data into an
// observations-only rawlog (issue #16): CObservationOdometry (when poses are
// known) + CObservation3DRangeScan per frame, which ground-aware-mapper,
// RawLogViewer and rawlog-edit read.
//
// usage: gam-import tum|pcd|png --in PATH --out FILE.rawlog [options]
//   tum  a TUM RGB-D sequence folder: depth.txt (or --list associations.txt),
//        depth/*.png (16-bit, 5000 per metre), groundtruth.txt (camera poses)
//   pcd  a folder of organized PCD files (ascii, binary, binary_compressed);
//        intrinsics fitted per file
//   png  a folder of 16-bit depth PNGs (intrinsics from --camera/--intrinsics)
// Formats, options and errors: doc/tools/gam-import.md.
// exit: 0 ok, 1 bad input (one line on stderr), 2 command line.
#include <gam/common/CommandLine.h>
#include <gam/common/Version.h>
#include <mrpt/3rdparty/tclap/CmdLine.h>
#include <mrpt/io/CFileGZOutputStream.h>
#include <mrpt/obs/CObservationOdometry.h>
#include <mrpt/serialization/CArchive.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

#include "Import.h"

using namespace gam::import;

namespace
{
std::string g_partialOutput;  ///< removed when the import fails

struct Source
{
	std::string path;
	double t = 0;
};

std::string dirOf(const std::string& file)
{
	const auto p = std::filesystem::path(file).parent_path().string();
	return p.empty() ? "." : p;
}
}  // namespace

int main(int argc, char** argv)
{
	try
	{
		TCLAP::CmdLine cmd(
			"gam-import: TUM RGB-D sequences, organized PCD folders or depth PNG folders -> observations-only rawlog "
			"(doc/tools/gam-import.md)",
			' ', GAM_VERSION);
		std::vector<std::string> formats = {"tum", "pcd", "png"};
		TCLAP::ValuesConstraint<std::string> formatC(formats);
		TCLAP::UnlabeledValueArg<std::string> argFormat(
			"format", "input kind: tum, pcd or png", true, "", &formatC, cmd);
		TCLAP::ValueArg<std::string> argIn(
			"i", "in", "tum: the sequence folder; pcd, png: the folder of frames (not needed with --list)", false, "",
			"PATH", cmd);
		TCLAP::ValueArg<std::string> argOut(
			"o", "out", "output rawlog (gzip, observations only)", true, "", "FILE", cmd);
		TCLAP::ValueArg<std::string> argList(
			"", "list",
			"frames with timestamps: 'timestamp filename' lines or TUM associations (paths relative to the list's "
			"folder); tum default: IN/depth.txt",
			false, "", "FILE", cmd);
		TCLAP::ValueArg<std::string> argGt(
			"", "groundtruth",
			"camera (optical frame) poses 'timestamp tx ty tz qx qy qz qw' (TUM); tum default: IN/groundtruth.txt",
			false, "", "FILE", cmd);
		TCLAP::ValueArg<std::string> argCamera(
			"c", "camera", "camera .ini: width height fx fy cx cy depth_scale sensor_pose label", false, "", "FILE.ini",
			cmd);
		TCLAP::ValueArg<std::string> argIntr(
			"", "intrinsics", "'width height fx fy cx cy' (overrides --camera)", false, "", "\"W H FX FY CX CY\"", cmd);
		TCLAP::ValueArg<std::string> argPose(
			"", "sensor-pose",
			"the camera on the robot, MRPT sensor frame (x forward, y left, z up): 'x y z yaw pitch roll' [m, deg] "
			"(overrides --camera)",
			false, "", "\"X Y Z YAW PITCH ROLL\"", cmd);
		TCLAP::ValueArg<double> argScale(
			"", "depth-scale", "PNG value per metre (tum default 5000, png default 1000)", false, 0, "S", cmd);
		TCLAP::ValueArg<std::string> argLabel(
			"", "label", "sensorLabel of the frames (default CAMERA)", false, "", "NAME", cmd);
		TCLAP::ValueArg<double> argMaxRange("", "max-range", "maxRange of the frames [m]", false, 10.0, "M", cmd);
		TCLAP::ValueArg<double> argFps(
			"", "fps", "frame rate of the nominal timestamps (folders without --list)", false, 30.0, "HZ", cmd);
		TCLAP::ValueArg<double> argGap(
			"", "max-gt-gap", "a frame needs ground-truth samples within this many seconds on both sides", false, 0.05,
			"S", cmd);
		TCLAP::ValueArg<double> argUnits(
			"", "range-units", "pcd: metres per range-image unit (depth quantized to it)", false, 0.001, "M", cmd);
		TCLAP::ValueArg<double> argMaxFit(
			"", "max-fit-rms", "pcd: largest rms residual [px] of the intrinsics fit accepted", false, 0.1, "PX", cmd);
		TCLAP::SwitchArg argQuiet("q", "quiet", "no per-file lines", cmd);
		if (const int rc = gam::parseCommandLine(cmd, argc, argv, "gam-import"); rc >= 0) return rc;

		const std::string format = argFormat.getValue();
		CameraConfig cam;
		if (argCamera.isSet()) cam = readCameraIni(argCamera.getValue());
		if (argIntr.isSet()) cam.intrinsics = parseIntrinsics(argIntr.getValue(), "--intrinsics");
		if (argPose.isSet()) cam.sensorPose = parseSensorPose(argPose.getValue(), "--sensor-pose");
		if (argScale.isSet()) cam.depthScale = argScale.getValue();
		if (argLabel.isSet()) cam.label = argLabel.getValue();
		if (!cam.sensorPose)
			throw ImportError(
				"the camera's pose on the robot is needed: --sensor-pose 'x y z yaw pitch roll' or sensor_pose in "
				"--camera (if unknown, give an estimate and measure it with gam-calibrate)");
		if (format != "pcd" && !cam.intrinsics)
			throw ImportError("the intrinsics are needed: --intrinsics 'W H fx fy cx cy' or --camera FILE.ini");
		if (format == "pcd" && cam.intrinsics)
			throw ImportError("pcd: the intrinsics are fitted from each file; do not give them");
		const double scale = cam.depthScale.value_or(format == "tum" ? 5000.0 : 1000.0);
		if (!(scale > 0) || !std::isfinite(scale)) throw ImportError("--depth-scale must be > 0");
		if (!(argFps.getValue() > 0)) throw ImportError("--fps must be > 0");
		if (!(argGap.getValue() >= 0)) throw ImportError("--max-gt-gap must be >= 0");
		if (!(argUnits.getValue() > 0) || argUnits.getValue() > 1) throw ImportError("--range-units must be in (0, 1]");
		if (!(argMaxRange.getValue() > 0)) throw ImportError("--max-range must be > 0");
		const std::string label = cam.label.value_or("CAMERA");

		// The frames and their timestamps.
		std::string listPath = argList.getValue(), gtPath = argGt.getValue();
		if (format == "tum")
		{
			if (!argIn.isSet()) throw ImportError("tum: --in SEQUENCE_FOLDER is needed");
			if (!std::filesystem::is_directory(argIn.getValue()))
				throw ImportError("missing folder: " + argIn.getValue());
			if (listPath.empty()) listPath = argIn.getValue() + "/depth.txt";
			if (gtPath.empty()) gtPath = argIn.getValue() + "/groundtruth.txt";
		}
		std::vector<Source> sources;
		if (!listPath.empty())
		{
			const std::string base = dirOf(listPath);
			for (const auto& e : readFrameList(listPath)) sources.push_back({base + "/" + e.file, e.t});
		}
		else
		{
			if (!argIn.isSet()) throw ImportError(format + ": --in FOLDER or --list FILE is needed");
			if (!gtPath.empty()) throw ImportError("--groundtruth needs --list (the frames' timestamps)");
			const auto names = listFolder(argIn.getValue(), format == "pcd" ? ".pcd" : ".png");
			for (size_t i = 0; i < names.size(); i++)
				sources.push_back({argIn.getValue() + "/" + names[i], double(i) / argFps.getValue()});
		}
		std::vector<TimedPose> gt;
		if (!gtPath.empty()) gt = readGroundTruth(gtPath);

		{
			const auto parent = std::filesystem::path(argOut.getValue()).parent_path();
			std::error_code ec;
			if (!parent.empty() && !std::filesystem::is_directory(parent, ec))
				throw ImportError("cannot write " + argOut.getValue() + ": no folder " + parent.string());
		}
		mrpt::io::CFileGZOutputStream fo;
		if (!fo.open(argOut.getValue(), 1)) throw ImportError("cannot write " + argOut.getValue());
		g_partialOutput = argOut.getValue();
		auto ar = mrpt::serialization::archiveFrom(fo);

		size_t written = 0, noGt = 0, dropped = 0;
		double zMin = 1e300, zMax = -1e300, tiltMax = 0;
		for (const Source& s : sources)
		{
			std::optional<mrpt::poses::CPose3D> robot;
			if (!gt.empty())
			{
				const auto cameraPose = poseAt(gt, s.t, argGap.getValue());
				if (!cameraPose)
				{
					noGt++;
					continue;
				}
				robot = robotFromCamera(*cameraPose, *cam.sensorPose);
			}
			DepthFrame f;
			if (format == "pcd")
			{
				const PcdCloud c = readPcd(s.path);
				IntrinsicsFit fit;
				try
				{
					fit = fitIntrinsics(c);
					checkIntrinsics(fit.k, "fitted intrinsics");
				}
				catch (const ImportError& e)
				{
					throw ImportError(s.path + ": " + e.what());
				}
				if (fit.rms_px > argMaxFit.getValue())
				{
					char b[160];
					std::snprintf(
						b, sizeof b, "%.3g px (> --max-fit-rms %.3g): not a pinhole depth image", fit.rms_px,
						argMaxFit.getValue());
					throw ImportError(s.path + ": intrinsics fit rms " + b);
				}
				size_t d = 0;
				f = depthFromPcd(c, fit.k, float(argUnits.getValue()), &d);
				dropped += d;
				if (!argQuiet.getValue())
					std::printf(
						"gam-import: %s: %dx%d %s, fx %.6f fy %.6f cx %.6f cy %.6f (fit over %zu px, rms %.2g px, max "
						"%.2g px)\n",
						s.path.c_str(), c.width, c.height, c.dataKind.c_str(), fit.k.fx, fit.k.fy, fit.k.cx, fit.k.cy,
						fit.points, fit.rms_px, fit.max_px);
			}
			else
				f = loadDepthPng(s.path, *cam.intrinsics, scale);

			if (robot)
			{
				auto odo = mrpt::obs::CObservationOdometry::Create();
				odo->sensorLabel = "ODOMETRY";
				odo->timestamp = mrpt::Clock::fromDouble(s.t);
				odo->odometry = to2D(*robot);
				ar << *odo;
				zMin = std::min(zMin, robot->z());
				zMax = std::max(zMax, robot->z());
				tiltMax = std::max({tiltMax, std::abs(robot->pitch()), std::abs(robot->roll())});
			}
			ar << *makeObservation(f, *cam.sensorPose, label, s.t, float(argMaxRange.getValue()));
			written++;
		}
		fo.close();
		g_partialOutput.clear();
		if (written == 0)
			throw ImportError(
				"no frame has ground truth within --max-gt-gap " + std::to_string(argGap.getValue()) +
				" s: nothing written");
		std::printf(
			"gam-import: %zu frames%s -> %s\n", written,
			gt.empty() ? " (no poses: robot at the origin)" : " + odometry", argOut.getValue().c_str());
		if (noGt) std::printf("gam-import: %zu frames skipped: no ground truth within %g s\n", noGt, argGap.getValue());
		if (dropped) std::printf("gam-import: %zu points beyond the range image's 65535 units dropped\n", dropped);
		if (!gt.empty())
		{
			std::printf(
				"gam-import: robot frame from the ground truth: z %.3f..%.3f m, |pitch|,|roll| <= %.2f deg "
				"(the odometry keeps x, y, yaw)\n",
				zMin, zMax, tiltMax * 180 / M_PI);
			if (tiltMax > 5 * M_PI / 180)
				std::printf(
					"gam-import: warning: the robot tilts by more than 5 deg: check --sensor-pose and that the "
					"ground truth's z axis is vertical\n");
		}
		return 0;
	}
	catch (const std::exception& e)
	{
		std::string msg = e.what();
		for (auto& c : msg)
			if (c == '\n' || c == '\r') c = ' ';
		std::cerr << "gam-import: error: " << msg << std::endl;
		if (!g_partialOutput.empty())
		{
			std::error_code ec;
			std::filesystem::remove(g_partialOutput, ec);
		}
		return 1;
	}
}
