// Ground-aware mapping for MRPT -- gam-simulate: renders a scene file into an
// observations-only rawlog (odometry + Kinect One depth + Leddar IS16) and
// writes the ground-truth grid. See config/scenes/README.md.
//
// usage: gam-simulate --scene FILE.scene --out PREFIX [--seed N] [--no-noise]
//                     [--frames N] [--no-leddar] [--depth-images]
// outputs: PREFIX.rawlog, PREFIX_gt.pgm, PREFIX_gt.yaml, PREFIX_gt_objects.csv,
//          PREFIX_gt_labels.csv, PREFIX_gt_path.csv
#include <gam/common/CommandLine.h>
#include <gam/common/Version.h>
#include <mrpt/3rdparty/tclap/CmdLine.h>
#include <mrpt/core/Clock.h>
#include <mrpt/io/CFileGZOutputStream.h>
#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/obs/CObservation3DRangeScan.h>
#include <mrpt/obs/CObservationOdometry.h>
#include <mrpt/poses/CPose3D.h>
#include <mrpt/serialization/CArchive.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>

#include "gam/sim/GroundTruth.h"
#include "gam/sim/KinectObservation.h"
#include "gam/sim/SceneFile.h"
#include "gam/sim/Sensors.h"

using namespace gam::sim;

namespace
{
mrpt::poses::CPose3D toCPose3D(const Pose3& p)
{
	const Eigen::Vector3d a = p.ypr();
	return mrpt::poses::CPose3D(p.t.x(), p.t.y(), p.t.z(), a[0], a[1], a[2]);
}

/** "a,b,c" -> three numbers; throws naming the option. */
Eigen::Vector3d parseTriple(const std::string& opt, const std::string& v)
{
	Eigen::Vector3d out;
	char extra = 0;
	if (std::sscanf(v.c_str(), "%lf,%lf,%lf%c", &out[0], &out[1], &out[2], &extra) != 3 || !out.allFinite())
		throw std::invalid_argument("--" + opt + " wants three numbers a,b,c (got '" + v + "')");
	return out;
}

/** Grey level per label in PREFIX_gt.pgm. */
uint8_t grey(Label l)
{
	switch (l)
	{
		case Label::Free: return 254;
		case Label::Obstacle: return 0;
		case Label::Drop: return 64;
		case Label::Unobserved: return 205;
	}
	return 205;
}

std::string baseName(const std::string& p)
{
	const auto s = p.find_last_of('/');
	return s == std::string::npos ? p : p.substr(s + 1);
}

void writeGroundTruth(const std::string& prefix, const SceneFile& sf, const GroundTruthGrid& gt)
{
	const GridSpec& g = gt.spec;
	const int nx = g.nx(), ny = g.ny();
	{
		std::ofstream f(prefix + "_gt.pgm", std::ios::binary);
		f << "P5\n# gam-simulate ground truth: free=254 obstacle=0 drop=64 unobserved=205\n"
		  << nx << " " << ny << "\n255\n";
		for (int iy = ny - 1; iy >= 0; iy--)
			for (int ix = 0; ix < nx; ix++) f.put(char(grey(gt.label(ix, iy))));
		if (!f) throw std::runtime_error("cannot write " + prefix + "_gt.pgm");
	}
	{
		std::ofstream f(prefix + "_gt.yaml");
		f << "# gam-simulate ground truth (ROS map_server format).\n"
		  << "# grey levels: free=254, obstacle=0, drop=64, unobserved=205\n"
		  << "# (drop reads as occupied, unobserved as unknown with these thresholds)\n"
		  << "image: " << baseName(prefix) << "_gt.pgm\n"
		  << "resolution: " << g.resolution << "\n"
		  << "origin: [" << g.min_x << ", " << g.min_y << ", 0.0]\n"
		  << "negate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n";
	}
	{
		std::ofstream f(prefix + "_gt_objects.csv");
		f << "id,name,type,category,min_x,min_y,min_z,max_x,max_y,max_z\n";
		for (const auto& o : sf.scene.objects)
		{
			const auto& b = o.bbox;
			f << o.id << "," << o.name << "," << o.type << "," << categoryName(o.category) << "," << b.min().x() << ","
			  << b.min().y() << "," << b.min().z() << "," << b.max().x() << "," << b.max().y() << "," << b.max().z()
			  << "\n";
		}
	}
	{
		std::ofstream f(prefix + "_gt_labels.csv");
		f << "ix,iy,x,y,label,object_id,category\n";
		char buf[160];
		for (int iy = 0; iy < ny; iy++)
			for (int ix = 0; ix < nx; ix++)
			{
				const int id = gt.objectId[gt.idx(ix, iy)];
				const ObjectInfo* o = id ? sf.scene.object(id) : nullptr;
				std::snprintf(
					buf, sizeof(buf), "%d,%d,%.4f,%.4f,%s,%d,%s\n", ix, iy, g.cellX(ix), g.cellY(iy),
					labelName(gt.label(ix, iy)), id, o ? categoryName(o->category) : "none");
				f << buf;
			}
	}
}
}  // namespace

int main(int argc, char** argv)
{
	try
	{
		TCLAP::CmdLine cmd("gam-simulate", ' ', GAM_VERSION);
		TCLAP::ValueArg<std::string> argScene("", "scene", "scene file (.scene)", true, "", "FILE", cmd);
		TCLAP::ValueArg<std::string> argOut("", "out", "output prefix", true, "", "PREFIX", cmd);
		TCLAP::ValueArg<unsigned> argSeed("", "seed", "random seed (default 1)", false, 1, "N", cmd);
		TCLAP::ValueArg<int> argFrames("", "frames", "keep only the first N frames", false, 0, "N", cmd);
		TCLAP::SwitchArg argNoNoise("", "no-noise", "exact sensors and odometry", cmd);
		TCLAP::SwitchArg argNoLeddar("", "no-leddar", "do not simulate the Leddar", cmd);
		TCLAP::ValueArg<std::string> argMount(
			"", "mount",
			"the Kinect's true height, pitch and roll on the robot: z,pitch,roll [m, deg] (x, y, yaw stay the "
			"scene's)",
			false, "", "Z,PITCH,ROLL", cmd);
		TCLAP::ValueArg<std::string> argDeclared(
			"", "declared-offset",
			"write the Kinect's sensorPose off the true one by dz,dpitch,droll [m, deg]: a wrong declared mount "
			"(the frames are rendered with the true one)",
			false, "", "DZ,DPITCH,DROLL", cmd);
		TCLAP::SwitchArg argDepthPgm(
			"", "depth-images", "also write PREFIX_depth_NNNN.pgm (16-bit, millimetres) per frame", cmd);
		if (const int rc = gam::parseCommandLine(cmd, argc, argv, "gam-simulate"); rc >= 0) return rc;

		const auto t0 = std::chrono::steady_clock::now();
		SceneFile sf;
		try
		{
			sf = parseSceneFile(argScene.getValue());
		}
		catch (const SceneError& e)
		{
			std::cerr << "gam-simulate: error: " << e.what() << std::endl;
			return 2;
		}
		const std::string prefix = argOut.getValue();
		const bool noise = !argNoNoise.getValue();
		sf.kinect.noise = noise;
		sf.leddar.noise = noise;
		if (!noise) sf.odometry_noise = OdometryNoise{};
		const bool leddarOn = sf.leddar_enabled && !argNoLeddar.getValue();

		std::vector<Pose2> truth = samplePath(sf.path);
		if (argFrames.getValue() > 0 && size_t(argFrames.getValue()) < truth.size())
			truth.resize(size_t(argFrames.getValue()));
		const unsigned seed = argSeed.getValue();
		std::mt19937 rngKinect(seed), rngLeddar(seed ^ 0x9e3779b9u), rngOdo(seed ^ 0x85ebca6bu),
			rngSway(seed ^ 0xc2b2ae35u);
		std::normal_distribution<double> gauss(0.0, 1.0);
		const std::vector<Pose2> odo = simulateOdometry(truth, sf.odometry_noise, rngOdo);

		GroundTruthGrid gt;
		gt.build(sf.scene, sf.grid);

		const KinectModel kinect(sf.kinect);
		const LeddarModel leddar(sf.leddar);
		if (!argMount.getValue().empty())
		{
			const Eigen::Vector3d m = parseTriple("mount", argMount.getValue());
			if (!(m[0] > 0) || std::abs(m[1]) >= 90 || std::abs(m[2]) >= 90)
				throw std::invalid_argument("--mount: z must be > 0 and |pitch|, |roll| < 90 deg");
			const Eigen::Vector3d a = sf.kinect_pose.ypr();
			sf.kinect_pose = Pose3::fromXYZYPR(
				sf.kinect_pose.t.x(), sf.kinect_pose.t.y(), m[0], a[0], m[1] * M_PI / 180, m[2] * M_PI / 180);
		}
		// The pose written into the rawlog (the true one unless --declared-offset).
		Pose3 declared = sf.kinect_pose;
		if (!argDeclared.getValue().empty())
		{
			const Eigen::Vector3d d = parseTriple("declared-offset", argDeclared.getValue());
			const Eigen::Vector3d a = sf.kinect_pose.ypr();
			declared = Pose3::fromXYZYPR(
				sf.kinect_pose.t.x(), sf.kinect_pose.t.y(), sf.kinect_pose.t.z() + d[0], a[0], a[1] + d[1] * M_PI / 180,
				a[2] + d[2] * M_PI / 180);
		}
		const mrpt::poses::CPose3D kinPose = toCPose3D(declared), ledPose = toCPose3D(sf.leddar_pose);
		{
			// The true and the declared mount, for scoring a calibration.
			const std::filesystem::path parent = std::filesystem::path(prefix).parent_path();
			std::error_code ec;
			if (!parent.empty()) std::filesystem::create_directories(parent, ec);
			std::ofstream f(prefix + "_gt_sensors.csv");
			f << "label,kind,x,y,z,yaw_deg,pitch_deg,roll_deg\n";
			for (const auto& [kind, p] :
				 {std::pair<const char*, Pose3>{"true", sf.kinect_pose}, {"declared", declared}})
			{
				const Eigen::Vector3d a = p.ypr() * 180.0 / M_PI;
				char b[200];
				std::snprintf(
					b, sizeof b, "KINECT,%s,%.6f,%.6f,%.6f,%.6f,%.6f,%.6f\n", kind, p.t.x(), p.t.y(), p.t.z(), a[0],
					a[1], a[2]);
				f << b;
			}
			if (!f) throw std::runtime_error("cannot write " + prefix + "_gt_sensors.csv");
		}

		{
			// create the output folder if needed
			const std::filesystem::path parent = std::filesystem::path(prefix).parent_path();
			std::error_code ec;
			if (!parent.empty()) std::filesystem::create_directories(parent, ec);
		}
		mrpt::io::CFileGZOutputStream fo;
		if (!fo.open(prefix + ".rawlog", 1))
		{
			std::cerr << "gam-simulate: error: cannot write " << prefix << ".rawlog" << std::endl;
			return 3;
		}
		auto ar = mrpt::serialization::archiveFrom(fo);
		std::ofstream pathCsv(prefix + "_gt_path.csv");
		pathCsv << "frame,timestamp,x,y,yaw,odo_x,odo_y,odo_yaw\n";
		size_t validPix = 0;
		for (size_t i = 0; i < truth.size(); i++)
		{
			const double tsec = 1.7e9 + double(i) / sf.path.rate_hz;
			const auto ts = mrpt::Clock::fromDouble(tsec);
			const Pose3 robot = Pose3::fromXYZYPR(truth[i].x, truth[i].y, 0, truth[i].yaw, 0, 0);

			auto o = mrpt::obs::CObservationOdometry::Create();
			o->sensorLabel = "ODOMETRY";
			o->timestamp = ts;
			o->odometry = mrpt::poses::CPose2D(odo[i].x, odo[i].y, odo[i].yaw);
			ar << *o;

			// the walker rocks: the real Kinect pose may differ from the nominal one
			Pose3 sway;
			if (noise && sf.kinect_sway > 0)
			{
				const double dp = sf.kinect_sway * gauss(rngSway), dr = sf.kinect_sway * gauss(rngSway);
				sway = Pose3::fromXYZYPR(0, 0, 0, 0, dp, dr);
			}
			const DepthFrame fr = kinect.render(sf.scene, robot * sf.kinect_pose * sway, rngKinect);
			gt.markObserved(fr.footprint);
			size_t frameValid = 0;
			auto k = toKinectObservation(sf.kinect, fr, kinPose, &frameValid);
			k->timestamp = ts;
			validPix += frameValid;
			ar << *k;
			if (argDepthPgm.getValue())
			{
				char name[32];
				std::snprintf(name, sizeof(name), "_depth_%04zu.pgm", i);
				std::ofstream f(prefix + name, std::ios::binary);
				f << "P5\n" << fr.width << " " << fr.height << "\n65535\n";
				for (int r = 0; r < fr.height; r++)
					for (int c = 0; c < fr.width; c++)
					{
						const uint16_t v = k->rangeImage(r, c);
						f.put(char(v >> 8));
						f.put(char(v & 0xff));
					}
			}

			if (leddarOn)
			{
				const LeddarScan ls = leddar.scan(sf.scene, robot * sf.leddar_pose, rngLeddar);
				auto l = mrpt::obs::CObservation2DRangeScan::Create();
				l->sensorLabel = "LEDDAR";
				l->timestamp = ts;
				l->aperture = float(sf.leddar.hfov_deg * M_PI / 180.0);
				l->rightToLeft = true;
				l->maxRange = float(sf.leddar.max_range);
				l->stdError = float(sf.leddar.sigma);
				l->beamAperture = float(sf.leddar.hfov_deg / sf.leddar.segments * M_PI / 180.0);
				l->sensorPose = ledPose;
				l->resizeScan(size_t(sf.leddar.segments));
				for (int s = 0; s < sf.leddar.segments; s++)
				{
					l->setScanRange(size_t(s), ls.valid[size_t(s)] ? ls.range[size_t(s)] : 0.0f);
					l->setScanRangeValidity(size_t(s), ls.valid[size_t(s)]);
				}
				ar << *l;
			}
			char buf[256];
			std::snprintf(
				buf, sizeof(buf), "%zu,%.6f,%.6f,%.6f,%.6f,%.6f,%.6f,%.6f\n", i, tsec, truth[i].x, truth[i].y,
				truth[i].yaw, odo[i].x, odo[i].y, odo[i].yaw);
			pathCsv << buf;
		}
		fo.close();
		writeGroundTruth(prefix, sf, gt);
		const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
		size_t nObs = 0, nDrop = 0, nFree = 0, nUnobs = 0;
		for (int iy = 0; iy < gt.spec.ny(); iy++)
			for (int ix = 0; ix < gt.spec.nx(); ix++)
			{
				const Label l = gt.label(ix, iy);
				nObs += l == Label::Obstacle;
				nDrop += l == Label::Drop;
				nFree += l == Label::Free;
				nUnobs += l == Label::Unobserved;
			}
		std::cout << "gam-simulate: " << truth.size() << " frames -> " << prefix << ".rawlog ("
				  << (leddarOn ? "odometry+kinect+leddar" : "odometry+kinect") << ", " << (noise ? "noisy" : "exact")
				  << ", seed " << seed << "), " << double(validPix) / std::max<size_t>(1, truth.size())
				  << " valid px/frame; GT " << gt.spec.nx() << "x" << gt.spec.ny() << " cells: free " << nFree
				  << ", obstacle " << nObs << ", drop " << nDrop << ", unobserved " << nUnobs << "; " << secs << " s"
				  << std::endl;
		return 0;
	}
	catch (const TCLAP::ArgException& e)
	{
		std::cerr << "gam-simulate: error: " << e.error() << " for " << e.argId() << std::endl;
		return 1;
	}
	catch (const std::exception& e)
	{
		std::cerr << "gam-simulate: error: " << e.what() << std::endl;
		return 1;
	}
}
