// Ground-aware mapping for MRPT -- gam-simulate: renders a scene file into an
// observations-only rawlog (odometry + depth camera(s) + Leddar IS16) and
// writes the ground-truth grid. See config/scenes/README.md.
//
// usage: gam-simulate --scene FILE.scene --out PREFIX [--seed N] [--no-noise]
//                     [--frames N] [--no-leddar] [--depth-images] [--camera MODEL]
// outputs: PREFIX.rawlog, PREFIX_gt.pgm, PREFIX_gt.yaml, PREFIX_gt_objects.csv,
//          PREFIX_gt_labels.csv, PREFIX_gt_path.csv, PREFIX_gt_sensors.csv and, for
//          scenes with motion or with --gt-frames, PREFIX_gt_frames.csv (per frame)
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

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>

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

/** PREFIX_gt_frames.csv, the per-frame ground truth (issue #14; format in
 * config/scenes/README.md): per frame the rawlog entries it wrote, the cells whose
 * geometric label changed (all non-free cells in frame 0), the cells each depth
 * camera saw (true footprint), the cells its measured, noisy points fell into and the
 * cells the Leddar's beams swept, as runs along grid rows. */
class FrameTruthWriter
{
   public:
	FrameTruthWriter(const std::string& path, const GridSpec& g) : m_f(path), m_g(g)
	{
		const size_t n = size_t(g.nx()) * size_t(g.ny());
		m_label.assign(n, Label::Free);
		m_obj.assign(n, 0);
		m_mask.assign(n, 0);
		m_f << "frame,kind,iy,ix0,ix1,label,object_id\n";
	}
	void entries(size_t frame, size_t first, size_t last)
	{
		m_f << frame << ",entries,0," << first << "," << last << ",,0\n";
	}
	/** The cells of rows y0..y1, columns x0..x1 whose label or object differs from the
	 * last written state. */
	void geometry(size_t frame, const GroundTruthGrid& gt, int x0, int y0, int x1, int y1)
	{
		for (int iy = y0; iy <= y1; iy++)
		{
			int run = -1;
			for (int ix = x0; ix <= x1 + 1; ix++)
			{
				const bool ch = ix <= x1 && differs(gt, ix, iy);
				const size_t i = gt.idx(std::min(ix, x1), iy);
				if (run >= 0 && (!ch || gt.geomLabel[i] != gt.geomLabel[gt.idx(run, iy)] ||
								 gt.objectId[i] != gt.objectId[gt.idx(run, iy)]))
				{
					const size_t r = gt.idx(run, iy);
					m_f << frame << ",geom," << iy << "," << run << "," << ix - 1 << "," << labelName(gt.geomLabel[r])
						<< "," << gt.objectId[r] << "\n";
					run = -1;
				}
				if (ch && run < 0) run = ix;
			}
			for (int ix = x0; ix <= x1; ix++)
			{
				m_label[gt.idx(ix, iy)] = gt.geomLabel[gt.idx(ix, iy)];
				m_obj[gt.idx(ix, iy)] = gt.objectId[gt.idx(ix, iy)];
			}
		}
	}
	/** Marks the cells holding these world points (seen by a depth camera). */
	void see(const GroundTruthGrid& gt, const std::vector<Eigen::Vector2d>& pts, uint8_t bit)
	{
		int ix, iy;
		for (const auto& p : pts)
			if (gt.cellOf(p.x(), p.y(), ix, iy)) mark(gt.idx(ix, iy), bit);
	}
	/** Marks the cells of the measured (noisy) points of a depth frame: its valid
	 * pixels unprojected with the pose the camera really had. */
	void seePoints(const GroundTruthGrid& gt, const KinectModel& km, const DepthFrame& fr, const Pose3& sensor)
	{
		int ix, iy;
		for (int r = 0; r < fr.height; r++)
			for (int c = 0; c < fr.width; c++)
			{
				const float d = fr.depth[fr.idx(r, c)];
				if (!(d > 0)) continue;
				const Eigen::Vector3d p = sensor.apply(double(d) * km.pixelRay(r, c));
				if (gt.cellOf(p.x(), p.y(), ix, iy)) mark(gt.idx(ix, iy), 4);
			}
	}
	/** Marks the cells along the 2D segment a -> b (clipped to the grid). */
	void sweep(const GroundTruthGrid& gt, const Eigen::Vector2d& a, const Eigen::Vector2d& b, uint8_t bit)
	{
		const double len = (b - a).norm(), step = 0.5 * m_g.resolution;
		int ix, iy;
		for (double t = 0; t <= len; t += step)
		{
			const Eigen::Vector2d p = a + (b - a) * (len > 0 ? t / len : 0.0);
			if (gt.cellOf(p.x(), p.y(), ix, iy))
				mark(gt.idx(ix, iy), bit);
			else if (t > 0)
				break;  // left the grid
		}
	}
	/** Writes the marked cells of this frame as `view` (bit 1), `points` (bit 4) and
	 * `leddar` (bit 2) runs and clears the marks. */
	void flush(size_t frame)
	{
		std::sort(m_touched.begin(), m_touched.end());
		const size_t nx = size_t(m_g.nx());
		for (uint8_t bit : {uint8_t(1), uint8_t(4), uint8_t(2)})
		{
			const char* kind = bit == 1 ? "view" : (bit == 2 ? "leddar" : "points");
			size_t k = 0;
			while (k < m_touched.size())
			{
				const size_t i = m_touched[k];
				if (!(m_mask[i] & bit))
				{
					k++;
					continue;
				}
				size_t j = k;
				while (j + 1 < m_touched.size() && m_touched[j + 1] == m_touched[j] + 1 &&
					   m_touched[j + 1] / nx == i / nx && (m_mask[m_touched[j + 1]] & bit))
					j++;
				m_f << frame << "," << kind << "," << i / nx << "," << i % nx << "," << m_touched[j] % nx << ",,0\n";
				k = j + 1;
			}
		}
		for (size_t i : m_touched) m_mask[i] = 0;
		m_touched.clear();
	}
	void close()
	{
		m_f.flush();
		if (!m_f) throw std::runtime_error("cannot write the per-frame ground truth");
	}

   private:
	bool differs(const GroundTruthGrid& gt, int ix, int iy) const
	{
		const size_t i = gt.idx(ix, iy);
		return gt.geomLabel[i] != m_label[i] || gt.objectId[i] != m_obj[i];
	}
	void mark(size_t i, uint8_t bit)
	{
		if (!m_mask[i]) m_touched.push_back(i);
		m_mask[i] |= bit;
	}
	std::ofstream m_f;
	GridSpec m_g;
	std::vector<Label> m_label;
	std::vector<int> m_obj;
	std::vector<uint8_t> m_mask;
	std::vector<size_t> m_touched;
};

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
		TCLAP::ValueArg<std::string> argCamera(
			"", "camera",
			"every depth camera of the scene becomes this model: kinect_one, d435, d455, femto, astra (the "
			"scene's model= and its other kinect keys otherwise; see doc/simulator.md)",
			false, "", "MODEL", cmd);
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
		TCLAP::SwitchArg argGtFrames(
			"", "gt-frames",
			"also write PREFIX_gt_frames.csv, the ground truth per frame (default: only when an object appears, "
			"disappears or moves, or with the scene's grid per_frame=1)",
			cmd);
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
		if (!argCamera.getValue().empty())
		{
			CameraModel model;
			if (!parseCameraModel(argCamera.getValue(), model))
			{
				std::cerr << "gam-simulate: error: --camera: unknown model '" << argCamera.getValue()
						  << "' (known: " << cameraModelNames() << ")" << std::endl;
				return 2;
			}
			setCameraModel(sf, model);
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
		// Moving objects (issue #14): each frame renders sf.scene.atFrame(i), and the
		// ground truth is labelled again where an object appeared, left or moved; the
		// final labels are those of the last frame.
		const bool dynamic = sf.scene.dynamic();
		const bool perFrame = argGtFrames.getValue() || sf.per_frame_truth == 1 || (sf.per_frame_truth < 0 && dynamic);
		std::unique_ptr<FrameTruthWriter> frameTruth;
		if (perFrame)
		{
			const std::filesystem::path parent = std::filesystem::path(prefix).parent_path();
			std::error_code ec;
			if (!parent.empty()) std::filesystem::create_directories(parent, ec);
			frameTruth = std::make_unique<FrameTruthWriter>(prefix + "_gt_frames.csv", gt.spec);
		}
		// Where object o is in frame f (empty box = absent); f = -1: as in the scene file.
		auto placed = [&](const ObjectInfo& o, int f) {
			if (f >= 0) return sf.scene.footprintAt(o.id, f);
			Eigen::AlignedBox2d b(o.bbox.min().head<2>(), o.bbox.max().head<2>());
			return b;
		};
		// Extra cameras: their own random streams, so the main camera's frames stay the same.
		std::vector<KinectModel> moreKinects;
		std::vector<std::mt19937> moreRng, moreSwayRng;
		for (size_t j = 0; j < sf.more_kinects.size(); j++)
		{
			sf.more_kinects[j].params.noise = noise;
			moreKinects.emplace_back(sf.more_kinects[j].params);
			moreRng.emplace_back(seed ^ (0x27d4eb2du * unsigned(j + 1)));
			moreSwayRng.emplace_back(seed ^ (0x165667b1u * unsigned(j + 1)));
		}

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
			std::vector<std::tuple<std::string, const char*, Pose3>> rows = {
				{sf.kinect_label, "true", sf.kinect_pose}, {sf.kinect_label, "declared", declared}};
			for (const auto& e : sf.more_kinects)
			{
				rows.emplace_back(e.label, "true", e.pose);
				rows.emplace_back(e.label, "declared", e.pose);
			}
			for (const auto& [label, kind, p] : rows)
			{
				const Eigen::Vector3d a = p.ypr() * 180.0 / M_PI;
				char b[200];
				std::snprintf(
					b, sizeof b, "%s,%s,%.6f,%.6f,%.6f,%.6f,%.6f,%.6f\n", label.c_str(), kind, p.t.x(), p.t.y(),
					p.t.z(), a[0], a[1], a[2]);
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
		size_t entry = 0;  // rawlog entries written so far (the mapper's numbering)
		Scene frameScene;
		for (size_t i = 0; i < truth.size(); i++)
		{
			const size_t firstEntry = entry;
			Eigen::AlignedBox2d changed;
			changed.setEmpty();
			if (dynamic)
			{
				frameScene = sf.scene.atFrame(int(i));
				for (const auto& ob : sf.scene.objects)
				{
					if (!ob.dynamic()) continue;
					const int prev = int(i) - 1;
					const bool wasThere = prev < 0 || ob.presentAt(prev), isThere = ob.presentAt(int(i));
					const Eigen::Vector2d offPrev = prev < 0 ? Eigen::Vector2d::Zero() : ob.offsetAt(prev);
					if (wasThere == isThere && (!isThere || offPrev == ob.offsetAt(int(i)))) continue;
					changed.extend(placed(ob, prev));
					changed.extend(placed(ob, int(i)));
				}
				gt.relabel(frameScene, changed);
			}
			const Scene& scene = dynamic ? frameScene : sf.scene;
			if (frameTruth && i == 0)
				frameTruth->geometry(i, gt, 0, 0, gt.spec.nx() - 1, gt.spec.ny() - 1);
			else if (frameTruth && !changed.isEmpty())
			{
				// the cells relabel() may have changed (one cell more around the region)
				const double r = gt.spec.resolution;
				const int x0 = std::max(0, int(std::floor((changed.min().x() - gt.spec.min_x) / r)) - 1);
				const int y0 = std::max(0, int(std::floor((changed.min().y() - gt.spec.min_y) / r)) - 1);
				const int x1 = std::min(gt.spec.nx() - 1, int(std::floor((changed.max().x() - gt.spec.min_x) / r)) + 1);
				const int y1 = std::min(gt.spec.ny() - 1, int(std::floor((changed.max().y() - gt.spec.min_y) / r)) + 1);
				if (x0 <= x1 && y0 <= y1) frameTruth->geometry(i, gt, x0, y0, x1, y1);
			}
			const double tsec = 1.7e9 + double(i) / sf.path.rate_hz;
			const auto ts = mrpt::Clock::fromDouble(tsec);
			const Pose3 robot = Pose3::fromXYZYPR(truth[i].x, truth[i].y, 0, truth[i].yaw, 0, 0);

			auto o = mrpt::obs::CObservationOdometry::Create();
			o->sensorLabel = "ODOMETRY";
			o->timestamp = ts;
			o->odometry = mrpt::poses::CPose2D(odo[i].x, odo[i].y, odo[i].yaw);
			ar << *o;
			entry++;

			// the walker rocks: the real Kinect pose may differ from the nominal one
			Pose3 sway;
			if (noise && sf.kinect_sway > 0)
			{
				const double dp = sf.kinect_sway * gauss(rngSway), dr = sf.kinect_sway * gauss(rngSway);
				sway = Pose3::fromXYZYPR(0, 0, 0, 0, dp, dr);
			}
			const DepthFrame fr = kinect.render(scene, robot * sf.kinect_pose * sway, rngKinect);
			gt.markObserved(fr.footprint);
			if (frameTruth)
			{
				frameTruth->see(gt, fr.footprint, 1);
				frameTruth->seePoints(gt, kinect, fr, robot * sf.kinect_pose * sway);
			}
			size_t frameValid = 0;
			auto k = toKinectObservation(sf.kinect, fr, kinPose, &frameValid);
			k->sensorLabel = sf.kinect_label;
			k->timestamp = ts;
			validPix += frameValid;
			ar << *k;
			entry++;
			for (size_t j = 0; j < moreKinects.size(); j++)
			{
				// each further camera: its own pose, label, rocking and noise stream
				const ExtraKinect& e = sf.more_kinects[j];
				Pose3 sw;
				if (noise && e.sway > 0)
				{
					const double dp = e.sway * gauss(moreSwayRng[j]), dr = e.sway * gauss(moreSwayRng[j]);
					sw = Pose3::fromXYZYPR(0, 0, 0, 0, dp, dr);
				}
				const DepthFrame fe = moreKinects[j].render(scene, robot * e.pose * sw, moreRng[j]);
				gt.markObserved(fe.footprint);
				if (frameTruth)
				{
					frameTruth->see(gt, fe.footprint, 1);
					frameTruth->seePoints(gt, moreKinects[j], fe, robot * e.pose * sw);
				}
				auto ke = toKinectObservation(e.params, fe, toCPose3D(e.pose));
				ke->sensorLabel = e.label;
				ke->timestamp = ts;
				ar << *ke;
				entry++;
			}
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
				const Pose3 ledWorld = robot * sf.leddar_pose;
				const LeddarScan ls = leddar.scan(scene, ledWorld, rngLeddar);
				if (frameTruth)
				{
					// the cells under the beams: each part of a segment's cone up
					// to where its own light stopped (the echo is the nearest of
					// them: the rest of the cone reaches farther, to the wall a
					// segment sees obliquely), or the range limit
					for (int sgm = 0; sgm < sf.leddar.segments; sgm++)
						for (int a = 0; a < sf.leddar.sub_h; a++)
						{
							const double h = sf.leddar.subRayAngle(sgm, a);
							const Eigen::Vector3d dir = ledWorld.R * Eigen::Vector3d(std::cos(h), std::sin(h), 0);
							const RayHit own = scene.cast(ledWorld.t, dir, 1e-6, sf.leddar.max_range);
							// up to there and 3 sigma beyond the echo (where its noisy range may put it)
							const double len =
								ls.valid[size_t(sgm)]
									? std::max(own.hit ? own.t : sf.leddar.max_range, double(ls.range[size_t(sgm)])) +
										  3 * sf.leddar.sigma
									: sf.leddar.max_range;
							const Eigen::Vector2d from = ledWorld.t.head<2>();
							frameTruth->sweep(gt, from, from + len * dir.head<2>().normalized(), 2);
						}
				}
				auto l = toLeddarObservation(sf.leddar, ls, ledPose);
				l->timestamp = ts;
				ar << *l;
				entry++;
			}
			if (frameTruth)
			{
				frameTruth->flush(i);
				// numbered as ground-aware-mapper numbers them: the rawlog's first object is 1
				frameTruth->entries(i, firstEntry + 1, entry);
			}
			char buf[256];
			std::snprintf(
				buf, sizeof(buf), "%zu,%.6f,%.6f,%.6f,%.6f,%.6f,%.6f,%.6f\n", i, tsec, truth[i].x, truth[i].y,
				truth[i].yaw, odo[i].x, odo[i].y, odo[i].yaw);
			pathCsv << buf;
		}
		fo.close();
		if (frameTruth) frameTruth->close();
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
