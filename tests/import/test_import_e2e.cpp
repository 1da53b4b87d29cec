// Ground-aware mapping for MRPT -- gam-import end to end: TUM sequences and
// depth PNG folders written here in the public formats, the real Kinect PCD
// files of ../shared/data/real (range image and maps compared with the stored
// rawlogs), bad inputs (one line, exit 1), and what Debian's rosbag2rawlog
// does with a depth bag (config/rosbag2rawlog-depth.yml).
#include <gtest/gtest.h>
#include <mrpt/img/CImage.h>
#include <mrpt/io/CFileGZInputStream.h>
#include <mrpt/maps/COccupancyGridMap2D.h>
#include <mrpt/maps/CSimplePointsMap.h>
#include <mrpt/obs/CActionCollection.h>
#include <mrpt/obs/CActionRobotMovement3D.h>
#include <mrpt/obs/CObservation3DRangeScan.h>
#include <mrpt/obs/CObservationOdometry.h>
#include <mrpt/obs/CRawlog.h>
#include <mrpt/serialization/CArchive.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "Import.h"

namespace fs = std::filesystem;
using mrpt::obs::CObservation3DRangeScan;
using mrpt::obs::CObservationOdometry;

namespace
{
const double kDeg = M_PI / 180.0;

std::string tmpDir(const std::string& name)
{
	const std::string d = std::string(GAM_TEST_TMP_DIR) + "/e2e_" + name;
	fs::remove_all(d);
	fs::create_directories(d);
	return d;
}

std::string readAll(const std::string& path)
{
	std::ifstream f(path, std::ios::binary);
	return std::string((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
}

void writeText(const std::string& path, const std::string& text) { std::ofstream(path) << text; }

struct ProcessResult
{
	int rc = -1;
	std::string out, err;
};

ProcessResult run(const std::string& cmd)
{
	// One pair of files per process: ctest runs these tests in parallel.
	const std::string stem = std::string(GAM_TEST_TMP_DIR) + "/run" + std::to_string(getpid());
	const std::string o = stem + ".out", e = stem + ".err";
	fs::create_directories(GAM_TEST_TMP_DIR);
	ProcessResult r;
	const int s = std::system((cmd + " >" + o + " 2>" + e).c_str());
	r.rc = WIFEXITED(s) ? WEXITSTATUS(s) : -1;
	r.out = readAll(o);
	r.err = readAll(e);
	return r;
}

ProcessResult import(const std::string& args) { return run(std::string(GAM_IMPORT_EXE) + " " + args); }

/** gam-import failed as documented: exit 1, one stderr line "gam-import: error: ...what...". */
void expectError(const ProcessResult& r, const std::string& what)
{
	EXPECT_EQ(r.rc, 1) << r.err;
	EXPECT_EQ(r.err.rfind("gam-import: error: ", 0), 0u) << r.err;
	EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
	EXPECT_NE(r.err.find(what), std::string::npos) << "expected '" << what << "' in: " << r.err;
}

void write16(const std::string& path, int w, int h, uint16_t base)
{
	mrpt::img::CImage im;
	im.resize(w, h, mrpt::img::CH_GRAY, mrpt::img::PixelDepth::D16U);
	for (int r = 0; r < h; r++)
		for (int c = 0; c < w; c++) im.ptr<uint16_t>(0, r)[c] = uint16_t(base + 10 * r + c);  // see test_import.cpp
	ASSERT_TRUE(im.saveToFile(path));
}

struct Entry
{
	CObservationOdometry::Ptr odo;
	CObservation3DRangeScan::Ptr scan;
};

std::vector<Entry> readRawlog(const std::string& path)
{
	mrpt::obs::CRawlog rl;
	EXPECT_TRUE(rl.loadFromRawLogFile(path)) << path;
	std::vector<Entry> out;
	for (size_t i = 0; i < rl.size(); i++)
	{
		if (rl.getType(i) != mrpt::obs::CRawlog::etObservation) continue;
		auto o = rl.getAsObservation(i);
		Entry e;
		e.odo = std::dynamic_pointer_cast<CObservationOdometry>(o);
		e.scan = std::dynamic_pointer_cast<CObservation3DRangeScan>(o);
		if (e.scan) e.scan->load();
		out.push_back(e);
	}
	return out;
}

/** A TUM sequence folder: 3 depth PNGs (4x3, factor 5000) at t = 1.0, 1.1, 1.2
 * and one at 3.0 (after the ground truth); the robot drives along +x at 1 m/s
 * from x = 0 at t = 1, heading +x (yaw 0); the camera is level, 0.2 m ahead of
 * the robot origin and 0.5 m up: optical pose = (t - 1 + 0.2, 0, 0.5) with the
 * rotation R^T (columns (0,-1,0), (0,0,-1), (1,0,0)), whose quaternion is the
 * ROS optical one: qx = -0.5, qy = 0.5, qz = -0.5, qw = 0.5. Ground truth every
 * 0.05 s from 0.9 to 1.3 s. */
std::string writeTumSequence(const std::string& name)
{
	const std::string d = tmpDir(name);
	fs::create_directories(d + "/depth");
	std::ostringstream list;
	list << "# depth maps\n# file: 'test.bag'\n# timestamp filename\n";
	const char* stamps[] = {"1.000000", "1.100000", "1.200000", "3.000000"};
	for (int i = 0; i < 4; i++)
	{
		write16(d + "/depth/" + stamps[i] + ".png", 4, 3, uint16_t(10000 + 1000 * i));
		list << stamps[i] << " depth/" << stamps[i] << ".png\n";
	}
	writeText(d + "/depth.txt", list.str());
	std::ostringstream gt;
	gt << "# ground truth trajectory\n# file: 'test.bag'\n# timestamp tx ty tz qx qy qz qw\n";
	for (int k = 0; k <= 8; k++)
	{
		const double t = 0.9 + 0.05 * k;
		char b[200];
		std::snprintf(b, sizeof b, "%.4f %.4f 0.0000 0.5000 -0.5 0.5 -0.5 0.5\n", t, t - 1 + 0.2);
		gt << b;
	}
	writeText(d + "/groundtruth.txt", gt.str());
	return d;
}

const std::string kTumArgs = "--intrinsics '4 3 2 2 1.5 1' --sensor-pose '0.2 0 0.5 0 0 0'";
}  // namespace

// -------------------------------------------------------------------- TUM

TEST(GamImportTum, SequenceGivesOdometryAndDepthFrames)
{
	const std::string d = writeTumSequence("tum");
	const ProcessResult r = import("tum -i " + d + " -o " + d + "/out.rawlog " + kTumArgs);
	ASSERT_EQ(r.rc, 0) << r.err;
	EXPECT_NE(r.out.find("3 frames + odometry"), std::string::npos) << r.out;
	EXPECT_NE(r.out.find("1 frames skipped: no ground truth within 0.05 s"), std::string::npos) << r.out;
	const auto e = readRawlog(d + "/out.rawlog");
	ASSERT_EQ(e.size(), 6u);
	for (int i = 0; i < 3; i++)
	{
		SCOPED_TRACE(i);
		const auto& odo = e[size_t(2 * i)].odo;
		const auto& scan = e[size_t(2 * i + 1)].scan;
		ASSERT_TRUE(odo && scan);
		// robot x = t - 1 = 0, 0.1, 0.2 (ground truth interpolated at 1.1 between 1.10 samples: exact)
		EXPECT_NEAR(odo->odometry.x(), 0.1 * i, 1e-6);
		EXPECT_NEAR(odo->odometry.y(), 0, 1e-6);
		EXPECT_NEAR(odo->odometry.phi(), 0, 1e-6);
		EXPECT_NEAR(mrpt::Clock::toDouble(scan->timestamp), 1.0 + 0.1 * i, 1e-6);
		EXPECT_EQ(scan->rangeImage(0, 0), 10000 + 1000 * i);
		EXPECT_EQ(scan->rangeImage(2, 3), 10000 + 1000 * i + 23);
		EXPECT_FLOAT_EQ(scan->rangeUnits, 1.0f / 5000);
		EXPECT_TRUE(scan->range_is_depth);
		EXPECT_DOUBLE_EQ(scan->cameraParams.fx(), 2);
		EXPECT_DOUBLE_EQ(scan->cameraParams.cy(), 1);
		EXPECT_NEAR(scan->sensorPose.x(), 0.2, 1e-12);
		EXPECT_NEAR(scan->sensorPose.z(), 0.5, 1e-12);
		EXPECT_EQ(scan->sensorLabel, "CAMERA");
	}
	// An associations file (associate.py rgb.txt depth.txt) gives the same frames.
	std::string assoc;
	for (const char* t : {"1.000000", "1.100000", "1.200000"})
		assoc += std::string(t) + " rgb/" + t + ".png " + t + " depth/" + t + ".png\n";
	writeText(d + "/associations.txt", assoc);
	const ProcessResult a =
		import("tum -i " + d + " --list " + d + "/associations.txt -o " + d + "/assoc.rawlog " + kTumArgs);
	ASSERT_EQ(a.rc, 0) << a.err;
	EXPECT_EQ(readAll(d + "/assoc.rawlog").size() > 0, true);
	EXPECT_EQ(readRawlog(d + "/assoc.rawlog").size(), 6u);
}

TEST(GamImportTum, BadInputsGiveOneLineErrors)
{
	const std::string d = writeTumSequence("tumbad");
	const std::string out = " -o " + d + "/out.rawlog ";
	// missing ground truth
	fs::rename(d + "/groundtruth.txt", d + "/gt.bak");
	expectError(import("tum -i " + d + out + kTumArgs), "missing file: " + d + "/groundtruth.txt");
	fs::rename(d + "/gt.bak", d + "/groundtruth.txt");
	// missing folder, missing depth PNG
	expectError(import("tum -i " + d + "/nope" + out + kTumArgs), "missing folder");
	fs::rename(d + "/depth/1.100000.png", d + "/moved.png");
	expectError(import("tum -i " + d + out + kTumArgs), "missing file: " + d + "/depth/1.100000.png");
	EXPECT_FALSE(fs::exists(d + "/out.rawlog"));  // no partial output left
	// an 8-bit PNG and an RGB PNG where a 16-bit depth image is expected
	mrpt::img::CImage g8(4, 3, mrpt::img::CH_GRAY);
	g8.filledRectangle(0, 0, 3, 2, mrpt::img::TColor(50, 50, 50));
	ASSERT_TRUE(g8.saveToFile(d + "/depth/1.100000.png"));
	expectError(import("tum -i " + d + out + kTumArgs), "1.100000.png: 8-bit image with 1 channel(s)");
	mrpt::img::CImage rgb(4, 3, mrpt::img::CH_RGB);
	rgb.filledRectangle(0, 0, 3, 2, mrpt::img::TColor(50, 60, 70));
	ASSERT_TRUE(rgb.saveToFile(d + "/depth/1.100000.png"));
	expectError(import("tum -i " + d + out + kTumArgs), "8-bit image with 3 channel(s)");
	fs::rename(d + "/moved.png", d + "/depth/1.100000.png");
	// intrinsics that do not fit the images
	expectError(
		import("tum -i " + d + out + "--intrinsics '4 3 2 2 4.5 1' --sensor-pose '0 0 0.5 0 0 0'"),
		"--intrinsics: cx = 4.5 is outside the image (width 4)");
	expectError(
		import("tum -i " + d + out + "--intrinsics '8 6 2 2 3 2' --sensor-pose '0 0 0.5 0 0 0'"),
		"image is 4x3 but the intrinsics are for 8x6");
	// timestamps out of order in depth.txt and in groundtruth.txt
	const std::string list = readAll(d + "/depth.txt");
	writeText(d + "/depth.txt", list + "2.000000 depth/1.000000.png\n");
	expectError(
		import("tum -i " + d + out + kTumArgs), "depth.txt line 8: timestamp 2 is not after the previous one (3)");
	writeText(d + "/depth.txt", list);
	const std::string gt = readAll(d + "/groundtruth.txt");
	writeText(d + "/groundtruth.txt", gt + "1.2 0 0 0 0 0 0 1\n");
	expectError(import("tum -i " + d + out + kTumArgs), "timestamps out of order");
	writeText(d + "/groundtruth.txt", gt);
	// no camera pose on the robot, no intrinsics
	expectError(
		import("tum -i " + d + out + "--intrinsics '4 3 2 2 1.5 1'"), "the camera's pose on the robot is needed");
	expectError(import("tum -i " + d + out + "--sensor-pose '0 0 0.5 0 0 0'"), "the intrinsics are needed");
	// and a clean run after all that
	EXPECT_EQ(import("tum -i " + d + out + kTumArgs).rc, 0);
	// a command-line error exits 2
	const ProcessResult c = import("bag -i " + d + out);
	EXPECT_EQ(c.rc, 2);
	EXPECT_NE(c.err.find("gam-import: error:"), std::string::npos);
}

// -------------------------------------------------------------- PNG folder

TEST(GamImportPng, FolderWithCameraIni)
{
	const std::string d = tmpDir("png");
	fs::create_directories(d + "/frames");
	write16(d + "/frames/frame_2.png", 4, 3, 1500);
	write16(d + "/frames/frame_10.png", 4, 3, 2500);
	writeText(
		d + "/cam.ini",
		"[camera]\nwidth = 4\nheight = 3\nfx = 2\nfy = 2\ncx = 1.5\ncy = 1\ndepth_scale = 1000  ; mm\n"
		"sensor_pose = 0 0 0.4 0 20 0\nlabel = DEPTH\n");
	const ProcessResult r = import("png -i " + d + "/frames -c " + d + "/cam.ini -o " + d + "/out.rawlog --fps 10");
	ASSERT_EQ(r.rc, 0) << r.err;
	EXPECT_NE(r.out.find("2 frames (no poses: robot at the origin)"), std::string::npos) << r.out;
	const auto e = readRawlog(d + "/out.rawlog");
	ASSERT_EQ(e.size(), 2u);
	ASSERT_TRUE(e[0].scan && e[1].scan);
	EXPECT_EQ(e[0].scan->rangeImage(0, 0), 1500);  // frame_2 before frame_10 (natural order)
	EXPECT_EQ(e[1].scan->rangeImage(1, 2), 2512);
	EXPECT_FLOAT_EQ(e[0].scan->rangeUnits, 0.001f);
	EXPECT_EQ(e[0].scan->sensorLabel, "DEPTH");
	EXPECT_NEAR(e[0].scan->sensorPose.pitch(), 20 * kDeg, 1e-12);
	EXPECT_NEAR(mrpt::Clock::toDouble(e[1].scan->timestamp) - mrpt::Clock::toDouble(e[0].scan->timestamp), 0.1, 1e-6);

	// bad: an RGB PNG in the folder, a camera .ini with cx outside the image, no PNGs
	mrpt::img::CImage rgb(4, 3, mrpt::img::CH_RGB);
	rgb.filledRectangle(0, 0, 3, 2, mrpt::img::TColor(1, 2, 3));
	ASSERT_TRUE(rgb.saveToFile(d + "/frames/frame_11.png"));
	expectError(
		import("png -i " + d + "/frames -c " + d + "/cam.ini -o " + d + "/bad.rawlog"),
		"frame_11.png: 8-bit image with 3 channel(s)");
	EXPECT_FALSE(fs::exists(d + "/bad.rawlog"));
	writeText(
		d + "/cx.ini", "width = 4\nheight = 3\nfx = 2\nfy = 2\ncx = -0.5\ncy = 1\nsensor_pose = 0 0 0.4 0 20 0\n");
	expectError(
		import("png -i " + d + "/frames -c " + d + "/cx.ini -o " + d + "/bad.rawlog"),
		"cx = -0.5 is outside the image");
	fs::create_directories(d + "/empty");
	expectError(import("png -i " + d + "/empty -c " + d + "/cam.ini -o " + d + "/bad.rawlog"), "no *.png files in");
	expectError(
		import("png -i " + d + "/frames -c " + d + "/none.ini -o " + d + "/bad.rawlog"),
		"missing file: " + d + "/none.ini");
}

// ------------------------------------------------------------ PCD (real)

namespace
{
std::string realData(const std::string& rel) { return std::string(GAM_REAL_DATA_DIR) + "/" + rel; }

CObservation3DRangeScan::Ptr firstScan(const std::string& path)
{
	for (const auto& e : readRawlog(path))
		if (e.scan) return e.scan;
	return {};
}

std::string poseArg(const mrpt::poses::CPose3D& p)
{
	char b[300];
	std::snprintf(
		b, sizeof b, "'%.17g %.17g %.17g %.17g %.17g %.17g'", p.x(), p.y(), p.z(), p.yaw() / kDeg, p.pitch() / kDeg,
		p.roll() / kDeg);
	return b;
}

/** Cells of a binary PGM (P5, maxval 255), or empty if unreadable. */
std::vector<uint8_t> pgmCells(const std::string& path, int& w, int& h)
{
	std::ifstream f(path, std::ios::binary);
	std::string magic;
	int maxv = 0;
	f >> magic;
	f.get();
	while (f.peek() == '#')  // comment lines
	{
		std::string comment;
		std::getline(f, comment);
	}
	f >> w >> h >> maxv;
	f.get();
	if (magic != "P5" || maxv != 255 || w <= 0 || h <= 0) return {};
	std::vector<uint8_t> c(size_t(w) * size_t(h));
	f.read(reinterpret_cast<char*>(c.data()), std::streamsize(c.size()));
	return f ? c : std::vector<uint8_t>{};
}
}  // namespace

class GamImportRealPcd : public ::testing::TestWithParam<std::string>
{
};

// The imported PCD and the stored rawlog converted from the same file: the same
// range image (every pixel), intrinsics within 1e-6 px (the stored ones were
// rounded to 6 decimals), and the mapper's grids equal cell for cell.
TEST_P(GamImportRealPcd, SameRangeImageAndSameMapsAsTheStoredRawlog)
{
	const std::string name = GetParam();
	const std::string stored = realData(name + "/" + name + ".rawlog");
	if (!fs::exists(stored)) GTEST_SKIP() << "no " << stored;
	std::string pcdDir = realData(name);
	const auto ref = firstScan(stored);
	ASSERT_TRUE(ref);
	const std::string d = tmpDir("real_" + name);
	const ProcessResult r =
		import("pcd -i " + pcdDir + " -o " + d + "/imported.rawlog --sensor-pose " + poseArg(ref->sensorPose));
	ASSERT_EQ(r.rc, 0) << r.err;
	std::cout << r.out;
	const auto imp = firstScan(d + "/imported.rawlog");
	ASSERT_TRUE(imp);
	ASSERT_EQ(imp->rangeImage.rows(), ref->rangeImage.rows());
	ASSERT_EQ(imp->rangeImage.cols(), ref->rangeImage.cols());
	size_t diff = 0, valid = 0;
	for (int i = 0; i < int(ref->rangeImage.rows()); i++)
		for (int j = 0; j < int(ref->rangeImage.cols()); j++)
		{
			diff += imp->rangeImage(i, j) != ref->rangeImage(i, j);
			valid += ref->rangeImage(i, j) != 0;
		}
	EXPECT_EQ(diff, 0u) << "of " << valid << " valid pixels";
	EXPECT_FLOAT_EQ(imp->rangeUnits, ref->rangeUnits);
	EXPECT_NEAR(imp->cameraParams.fx(), ref->cameraParams.fx(), 1e-6);
	EXPECT_NEAR(imp->cameraParams.fy(), ref->cameraParams.fy(), 1e-6);
	EXPECT_NEAR(imp->cameraParams.cx(), ref->cameraParams.cx(), 1e-6);
	EXPECT_NEAR(imp->cameraParams.cy(), ref->cameraParams.cy(), 1e-6);
	EXPECT_TRUE(imp->hasIntensityImage);
	EXPECT_EQ(imp->intensityImage.getWidth(), ref->intensityImage.getWidth());
	std::cout << name << ": range image " << ref->rangeImage.cols() << "x" << ref->rangeImage.rows() << ", " << valid
			  << " valid pixels, " << diff << " differ\n";

#ifdef GAM_MAPPER_EXE
	const std::string mapper = GAM_MAPPER_EXE;
	ASSERT_EQ(run(mapper + " -q -r " + stored + " -o " + d + "/maps_stored").rc, 0);
	ASSERT_EQ(run(mapper + " -q -r " + d + "/imported.rawlog -o " + d + "/maps_imported").rc, 0);
	for (const char* grid : {"ground_aware", "height_band", "octomap", "ground_aware_missing_floor"})
	{
		SCOPED_TRACE(grid);
		int w1 = 0, h1 = 0, w2 = 0, h2 = 0;
		const auto a = pgmCells(d + "/maps_stored/" + grid + ".pgm", w1, h1);
		const auto b = pgmCells(d + "/maps_imported/" + grid + ".pgm", w2, h2);
		ASSERT_FALSE(a.empty());
		ASSERT_EQ(w1, w2);
		ASSERT_EQ(h1, h2);
		size_t cellsDiff = 0, known = 0;
		for (size_t i = 0; i < a.size(); i++)
		{
			cellsDiff += a[i] != b[i];
			known += a[i] != 128;
		}
		EXPECT_EQ(cellsDiff, 0u);
		EXPECT_EQ(readAll(d + "/maps_stored/" + grid + ".yaml"), readAll(d + "/maps_imported/" + grid + ".yaml"));
		std::cout << name << " " << grid << ": " << a.size() << " cells (" << known << " observed), " << cellsDiff
				  << " differ\n";
	}
	for (const char* png : {"elevation_zmax.png", "elevation_span.png", "elevation_count.png"})
		EXPECT_EQ(readAll(d + "/maps_stored/" + png), readAll(d + "/maps_imported/" + png)) << png;
#endif
}

INSTANTIATE_TEST_SUITE_P(
	RealKinect, GamImportRealPcd,
	::testing::Values("pcl_milk_bottles_on_carpet", "pcl_office1", "pcl_five_people_corridor"));

namespace
{
size_t differingCells(const std::string& a, const std::string& b, size_t* total)
{
	int w1 = 0, h1 = 0, w2 = 0, h2 = 0;
	const auto ca = pgmCells(a, w1, h1), cb = pgmCells(b, w2, h2);
	if (ca.empty() || w1 != w2 || h1 != h2) return size_t(-1);
	size_t n = 0;
	for (size_t i = 0; i < ca.size(); i++) n += ca[i] != cb[i];
	*total = ca.size();
	return n;
}
}  // namespace

// Real depth through the PNG and TUM paths: the stored milk-bottles frame written
// as a 16-bit PNG (mm), imported with the stored intrinsics (png) and as a TUM
// sequence whose ground truth puts the robot at the origin (tum: the camera's
// optical pose = sensorPose (+) sensor<-optical), gives the stored rawlog's maps.
TEST(GamImportRealDepthPng, MilkFrameAsPngAndAsTumSequenceGiveTheStoredMaps)
{
	const std::string stored = realData("pcl_milk_bottles_on_carpet/pcl_milk_bottles_on_carpet.rawlog");
	if (!fs::exists(stored)) GTEST_SKIP() << "no " << stored;
	const auto ref = firstScan(stored);
	ASSERT_TRUE(ref);
	ASSERT_FLOAT_EQ(ref->rangeUnits, 0.001f);
	const std::string d = tmpDir("real_png");
	fs::create_directories(d + "/png");
	fs::create_directories(d + "/tum/depth");
	mrpt::img::CImage im;
	const int W = int(ref->rangeImage.cols()), H = int(ref->rangeImage.rows());
	im.resize(W, H, mrpt::img::CH_GRAY, mrpt::img::PixelDepth::D16U);
	for (int r = 0; r < H; r++)
		for (int c = 0; c < W; c++) im.ptr<uint16_t>(0, r)[c] = ref->rangeImage(r, c);
	ASSERT_TRUE(im.saveToFile(d + "/png/frame.png"));
	ASSERT_TRUE(im.saveToFile(d + "/tum/depth/1.000000.png"));
	const auto& cp = ref->cameraParams;
	char k[300];
	std::snprintf(k, sizeof k, "'%d %d %.17g %.17g %.17g %.17g'", W, H, cp.fx(), cp.fy(), cp.cx(), cp.cy());
	const std::string common = std::string(" --intrinsics ") + k + " --sensor-pose " + poseArg(ref->sensorPose);
	ProcessResult r = import("png -i " + d + "/png -o " + d + "/png.rawlog" + common);
	ASSERT_EQ(r.rc, 0) << r.err;

	writeText(d + "/tum/depth.txt", "# timestamp filename\n1.000000 depth/1.000000.png\n");
	const auto optical = ref->sensorPose + gam::import::opticalInSensorFrame();
	mrpt::math::CQuaternionDouble q;
	optical.getAsQuaternion(q);
	std::string gt = "# timestamp tx ty tz qx qy qz qw\n";
	for (const char* t : {"0.99", "1.01"})
	{
		char line[400];
		std::snprintf(
			line, sizeof line, "%s %.17g %.17g %.17g %.17g %.17g %.17g %.17g\n", t, optical.x(), optical.y(),
			optical.z(), q.x(), q.y(), q.z(), q.r());
		gt += line;
	}
	writeText(d + "/tum/groundtruth.txt", gt);
	r = import("tum -i " + d + "/tum -o " + d + "/tum.rawlog --depth-scale 1000" + common);
	ASSERT_EQ(r.rc, 0) << r.err;
	const auto e = readRawlog(d + "/tum.rawlog");
	ASSERT_EQ(e.size(), 2u);
	ASSERT_TRUE(e[0].odo);
	EXPECT_NEAR(e[0].odo->odometry.x(), 0, 1e-9);
	EXPECT_NEAR(e[0].odo->odometry.y(), 0, 1e-9);
	EXPECT_NEAR(e[0].odo->odometry.phi(), 0, 1e-9);

#ifdef GAM_MAPPER_EXE
	const std::string mapper = GAM_MAPPER_EXE;
	ASSERT_EQ(run(mapper + " -q -r " + stored + " -o " + d + "/maps_stored").rc, 0);
	ASSERT_EQ(run(mapper + " -q -r " + d + "/png.rawlog -o " + d + "/maps_png").rc, 0);
	ASSERT_EQ(run(mapper + " -q -r " + d + "/tum.rawlog -o " + d + "/maps_tum").rc, 0);
	for (const char* grid : {"ground_aware", "height_band", "octomap"})
	{
		SCOPED_TRACE(grid);
		const std::string f = std::string("/") + grid + ".pgm";
		size_t total = 0;
		const size_t dPng = differingCells(d + "/maps_stored" + f, d + "/maps_png" + f, &total);
		const size_t dTum = differingCells(d + "/maps_stored" + f, d + "/maps_tum" + f, &total);
		EXPECT_EQ(dPng, 0u);
		EXPECT_EQ(dTum, 0u);
		std::cout << "milk " << grid << " of " << total << " cells: png differs in " << dPng << ", tum in " << dTum
				  << "\n";
	}
#endif
}

TEST(GamImportPcd, KinectV2IntrinsicsAndBadFiles)
{
	const std::string walrus = realData("walrus_kinect2_stairs_up/1424402071410410.pcd");
	if (!fs::exists(walrus)) GTEST_SKIP() << "no " << walrus;
	const std::string d = tmpDir("pcd");
	fs::create_directories(d + "/one");
	fs::copy_file(walrus, d + "/one/1424402071410410.pcd");
	const ProcessResult r = import("pcd -i " + d + "/one -o " + d + "/w.rawlog --sensor-pose '0 0 0.88 0 0 0'");
	ASSERT_EQ(r.rc, 0) << r.err;
	const auto s = firstScan(d + "/w.rawlog");
	ASSERT_TRUE(s);
	// shared/data/real/README.md: fx 526.63, fy 529.57, cx 465.38, cy 259.11
	EXPECT_NEAR(s->cameraParams.fx(), 526.63, 0.005);
	EXPECT_NEAR(s->cameraParams.fy(), 529.57, 0.005);
	EXPECT_NEAR(s->cameraParams.cx(), 465.38, 0.005);
	EXPECT_NEAR(s->cameraParams.cy(), 259.11, 0.005);
	EXPECT_EQ(s->rangeImage.cols(), 960);
	// ... and the first frame of the stored 7-frame rawlog has the same range image
	const auto ref = firstScan(realData("walrus_kinect2_stairs_up/walrus_kinect2_stairs_up.rawlog"));
	ASSERT_TRUE(ref);
	size_t diff = 0;
	for (int i = 0; i < 540; i++)
		for (int j = 0; j < 960; j++) diff += s->rangeImage(i, j) != ref->rangeImage(i, j);
	EXPECT_EQ(diff, 0u);

	// a truncated copy of the real file; a folder without PCDs
	const std::string bytes = readAll(walrus);
	fs::create_directories(d + "/trunc");
	writeText(d + "/trunc/cut.pcd", bytes.substr(0, bytes.size() / 2));
	expectError(
		import("pcd -i " + d + "/trunc -o " + d + "/t.rawlog --sensor-pose '0 0 1 0 0 0'"), "cut.pcd: truncated");
	fs::create_directories(d + "/empty");
	expectError(
		import("pcd -i " + d + "/empty -o " + d + "/t.rawlog --sensor-pose '0 0 1 0 0 0'"), "no *.pcd files in");
	expectError(
		import("pcd -i " + d + "/one -o " + d + "/t.rawlog --sensor-pose '0 0 1 0 0 0' --intrinsics '960 540 1 1 1 1'"),
		"pcd: the intrinsics are fitted from each file");
}

// ---------------------------------------------------- ROS 1 bag (Debian)

// What Debian 12's rosbag2rawlog (mrpt-apps 2.5.8) makes of a depth-camera bag
// written by tests/import/make_test_bag.py: depth image, camera info, tf,
// tf_static and odometry. Measured, not wished: see config/rosbag2rawlog-depth.yml.
TEST(Rosbag2Rawlog, WhatDebianRosbag2rawlogDoesWithADepthBag)
{
	if (!fs::exists("/usr/bin/rosbag2rawlog")) GTEST_SKIP() << "no rosbag2rawlog (mrpt-apps)";
	if (run("/usr/bin/python3 -c 'import rosbag, sensor_msgs.msg, nav_msgs.msg, tf2_msgs.msg'").rc != 0)
		GTEST_SKIP() << "python3-rosbag / message packages not installed (scripts/install-deps.sh)";
	const std::string d = tmpDir("rosbag");
	const std::string script = std::string(GAM_SOURCE_DIR) + "/tests/import/make_test_bag.py";
	const std::string cfg = std::string(GAM_SOURCE_DIR) + "/config/rosbag2rawlog-depth.yml";
	ASSERT_EQ(run("/usr/bin/python3 " + script + " " + d + "/f32.bag 32FC1").rc, 0);
	ASSERT_EQ(run("/usr/bin/python3 " + script + " " + d + "/u16.bag 16UC1").rc, 0);
	ASSERT_EQ(run("/usr/bin/python3 " + script + " " + d + "/noframe.bag 32FC1 unknown_frame").rc, 0);
	for (const char* b : {"f32", "u16", "noframe"})
	{
		const ProcessResult r =
			run("/usr/bin/rosbag2rawlog -f base_link -c " + cfg + " -o " + d + "/" + b + ".rawlog -w " + d + "/" + b +
				".bag");
		ASSERT_EQ(r.rc, 0) << r.err;
		EXPECT_NE((r.out + r.err).find("Warning: unhandled topic '/odom'"), std::string::npos);
	}
	auto scansAndActions = [](const std::string& path, std::vector<CObservation3DRangeScan::Ptr>& scans,
							  std::vector<mrpt::poses::CPose3D>& moves) {
		mrpt::obs::CRawlog rl;
		ASSERT_TRUE(rl.loadFromRawLogFile(path));
		for (size_t i = 0; i < rl.size(); i++)
			if (rl.getType(i) == mrpt::obs::CRawlog::etObservation)
			{
				if (auto s = std::dynamic_pointer_cast<CObservation3DRangeScan>(rl.getAsObservation(i)))
					scans.push_back(s);
			}
			else if (rl.getType(i) == mrpt::obs::CRawlog::etActionCollection)
			{
				auto ac = rl.getAsAction(i);
				for (size_t k = 0; k < ac->size(); k++)
					if (auto m = std::dynamic_pointer_cast<mrpt::obs::CActionRobotMovement3D>(ac->get(k)))
						moves.push_back(m->poseChange.mean);
			}
	};
	std::vector<CObservation3DRangeScan::Ptr> scans;
	std::vector<mrpt::poses::CPose3D> moves;
	scansAndActions(d + "/f32.rawlog", scans, moves);
	// 32FC1: every frame converted, intrinsics from CameraInfo, depth in mm truncated (2.0 m -> 1999)
	ASSERT_EQ(scans.size(), 3u);
	for (const auto& s : scans)
	{
		s->load();
		EXPECT_EQ(s->sensorLabel, "depth_cam");
		EXPECT_TRUE(s->range_is_depth);
		EXPECT_EQ(s->rangeImage.cols(), 16);
		EXPECT_DOUBLE_EQ(s->cameraParams.fx(), 10);
		EXPECT_DOUBLE_EQ(s->cameraParams.cx(), 7.5);
		EXPECT_DOUBLE_EQ(s->cameraParams.cy(), 5.5);
		EXPECT_FLOAT_EQ(s->rangeUnits, 0.001f);
		EXPECT_EQ(s->rangeImage(0, 0), 999);
		EXPECT_EQ(s->rangeImage(5, 5), 1999);
		EXPECT_EQ(s->rangeImage(11, 15), 0);
		// sensorPose is not base_link -> optical frame from tf ((0.1, 0, 0.5) + optical
		// rotation) but always (0 0 0, yaw 90, pitch -90, roll 0): its x axis (MRPT's
		// forward) points up.
		EXPECT_NEAR(s->sensorPose.x(), 0, 1e-9);
		EXPECT_NEAR(s->sensorPose.z(), 0, 1e-9);
		EXPECT_NEAR(s->sensorPose.yaw(), 90 * kDeg, 1e-6);
		EXPECT_NEAR(s->sensorPose.pitch(), -90 * kDeg, 1e-6);
		const auto fwd = s->sensorPose.getRotationMatrix().col(0);
		EXPECT_NEAR(fwd[2], 1, 1e-6);
	}
	// One CActionRobotMovement3D before each frame, but not the robot's motion
	// (0.1 m per frame in /tf and /odom): below 1 cm.
	ASSERT_EQ(moves.size(), 3u);
	for (const auto& m : moves) EXPECT_LT(m.norm(), 0.01);
	// 16UC1 depth (mm): no frame at all; an image frame_id unknown to tf: no frame.
	for (const char* b : {"u16", "noframe"})
	{
		std::vector<CObservation3DRangeScan::Ptr> s2;
		std::vector<mrpt::poses::CPose3D> m2;
		scansAndActions(d + "/" + b + ".rawlog", s2, m2);
		EXPECT_EQ(s2.size(), 0u) << b;
	}
	// rawlog-edit --sensors-pose (the stock way to set sensor poses) writes an
	// empty rawlog from this output: it keeps no entry of this mixed format.
	if (fs::exists("/usr/bin/rawlog-edit"))
	{
		writeText(
			d + "/poses.ini",
			"[CAM]\nsensorLabel = depth_cam\npose_x = 0.1\npose_y = 0\npose_z = 0.5\npose_yaw = 0\npose_pitch = "
			"0\npose_roll = 0\n");
		const ProcessResult e =
			run("/usr/bin/rawlog-edit -i " + d + "/f32.rawlog -o " + d + "/posed.rawlog -w --sensors-pose " + d +
				"/poses.ini");
		EXPECT_EQ(e.rc, 0) << e.err;
		std::vector<CObservation3DRangeScan::Ptr> s3;
		std::vector<mrpt::poses::CPose3D> m3;
		scansAndActions(d + "/posed.rawlog", s3, m3);
		EXPECT_EQ(s3.size(), 0u);
		EXPECT_EQ(m3.size(), 0u);
	}
#ifdef GAM_MAPPER_EXE
	// The recipe's fix: the real sensorPose through the mapper's [sensor_poses]
	// (robot at the origin: the rawlog has no odometry).
	std::string ini = readAll(std::string(GAM_SOURCE_DIR) + "/config/ground-aware-mapper.ini");
	ini += "\n[sensor_poses]\ndepth_cam = 0.1 0 0.5 0 0 0\n";
	writeText(d + "/mapper.ini", ini);
	const ProcessResult m =
		run(std::string(GAM_MAPPER_EXE) + " -q -c " + d + "/mapper.ini -r " + d + "/f32.rawlog -o " + d + "/maps");
	EXPECT_EQ(m.rc, 0) << m.err;
	EXPECT_NE(m.out.find("frames: 3 (3 3D scans"), std::string::npos) << m.out;
#endif
}

#if defined(GAM_MAPPER_EXE) && defined(GAM_CALIBRATE_EXE)
namespace
{
/** "key,value" of the RealSense Viewer's metadata csv. */
double metadataValue(const std::string& csv, const std::string& key)
{
	std::istringstream in(csv);
	std::string line;
	while (std::getline(in, line))
		if (line.rfind(key + ",", 0) == 0) return std::stod(line.substr(key.size() + 1));
	ADD_FAILURE() << "no " << key << " in the metadata";
	return 0;
}
/** z, pitch, roll of gam-calibrate's first line "LABEL z=.. pitch=.. roll=.. ...". */
bool parseCalibration(const std::string& out, double& z, double& pitch, double& roll)
{
	const auto at = out.find(" z=");
	return at != std::string::npos &&
		   std::sscanf(out.c_str() + at, " z=%lf pitch=%lf roll=%lf", &z, &pitch, &roll) == 3;
}
}  // namespace

TEST(GamImportRealRealSense, EaselFrameFromARoughGuessToAMap)
{
	// The real D400 frame (848x480, the floor 2-5 m ahead, an easel's legs; see
	// ../shared/data/real/realsense_d400_basement_easel/README.md), imported with the
	// viewer's intrinsics and a rough mount (1.0 m high, pitched 10 deg down: the camera
	// is about 0.76 m up and level), calibrated from that guess, re-calibrated from the
	// answer, then mapped.
	const std::string dir = realData("realsense_d400_basement_easel");
	if (!fs::exists(dir + "/001_big_depth_z16.png")) GTEST_SKIP() << "no " << dir;
	const std::string meta = readAll(dir + "/001_big_depth_metadata.csv");
	const std::string d = tmpDir("realsense");
	fs::create_directories(d + "/png");
	fs::copy_file(dir + "/001_big_depth_z16.png", d + "/png/001.png", fs::copy_options::overwrite_existing);
	char intr[300];
	std::snprintf(
		intr, sizeof intr, "'%d %d %.9g %.9g %.9g %.9g'", int(metadataValue(meta, "Resolution x")),
		int(metadataValue(meta, "Resolution y")), metadataValue(meta, "Fx"), metadataValue(meta, "Fy"),
		metadataValue(meta, "PPx"), metadataValue(meta, "PPy"));
	ProcessResult r = import(
		"png -i " + d + "/png -o " + d + "/rs.rawlog --intrinsics " + intr +
		" --sensor-pose '0 0 1.0 0 10 0' --label REALSENSE_D400");
	ASSERT_EQ(r.rc, 0) << r.err;

	const std::string ini = d + "/rs.ini";
	fs::copy_file(
		std::string(GAM_SOURCE_DIR) + "/config/ground-aware-mapper.ini", ini, fs::copy_options::overwrite_existing);
	const std::string cal = std::string(GAM_CALIBRATE_EXE) + " --rawlog " + d + "/rs.rawlog --config " + ini;
	r = run(cal + " --write-ini " + ini);
	ASSERT_EQ(r.rc, 0) << r.out << r.err;
	double z = 0, pitch = 0, roll = 0;
	ASSERT_TRUE(parseCalibration(r.out, z, pitch, roll)) << r.out;
	// The dataset's own floor fit (RANSAC on the lower half, 2 cm inliers): 0.76 m,
	// pitch -1.3 deg, roll 0.4 deg, "an estimate, not ground truth": within a few cm.
	EXPECT_NEAR(z, 0.76, 0.04) << r.out;
	EXPECT_NEAR(pitch, -1.3, 1.5) << r.out;
	EXPECT_NEAR(roll, 0.4, 1.0) << r.out;
	// Calibrating again from the answer gives the same answer.
	const ProcessResult again = run(cal);
	ASSERT_EQ(again.rc, 0) << again.err;
	double z2 = 0, pitch2 = 0, roll2 = 0;
	ASSERT_TRUE(parseCalibration(again.out, z2, pitch2, roll2)) << again.out;
	EXPECT_NEAR(z2, z, 1e-4);
	EXPECT_NEAR(pitch2, pitch, 1e-3);
	EXPECT_NEAR(roll2, roll, 1e-3);

	// The frame's own points, placed with the calibrated mount: a floor cell has >= 5
	// points, all within 3 cm of z = 0 (this test's reading of the data, not the map's);
	// an object cell has >= 5 points 0.15-1.2 m up and none within 3 cm of the floor,
	// 1.5-3.5 m ahead (the easel's legs and what stands near it).
	auto obs = firstScan(d + "/rs.rawlog");
	ASSERT_TRUE(obs);
	obs->setSensorPose(mrpt::poses::CPose3D(0, 0, z, 0, mrpt::DEG2RAD(pitch), mrpt::DEG2RAD(roll)));
	mrpt::maps::CSimplePointsMap pts;
	mrpt::obs::T3DPointsProjectionParams pp;
	pp.takeIntoAccountSensorPoseOnRobot = true;
	obs->unprojectInto(pts, pp);
	struct Score
	{
		size_t floorKnown = 0, floorOcc = 0, objects = 0, objectsOcc = 0;
	};
	// The map of the calibrated .ini with `key=value` set in its ground-aware section.
	auto score = [&](const std::string& key, const std::string& value) {
		Score sc;
		std::string text = readAll(ini);
		if (!key.empty())
		{
			const auto at = text.find("\n" + key + "=");
			EXPECT_NE(at, std::string::npos) << key;
			if (at == std::string::npos) return sc;
			const auto eol = text.find_first_of(" \t;\n", at + key.size() + 2);
			text.replace(at + key.size() + 2, eol - (at + key.size() + 2), value);
		}
		const std::string variant = d + "/variant.ini", out = d + "/maps_" + (key.empty() ? "default" : key);
		writeText(variant, text);
		const ProcessResult m =
			run(std::string(GAM_MAPPER_EXE) + " -q -r " + d + "/rs.rawlog -c " + variant + " -o " + out);
		EXPECT_EQ(m.rc, 0) << m.err;
		mrpt::maps::COccupancyGridMap2D grid;  // the mapper writes the stock class
		mrpt::io::CFileGZInputStream f(out + "/ground_aware.gridmap.gz");
		auto a = mrpt::serialization::archiveFrom(f);
		a >> grid;
		struct CellStats
		{
			int n = 0, nFloor = 0, nHigh = 0;
		};
		std::map<std::pair<int, int>, CellStats> cells;
		for (size_t i = 0; i < pts.size(); i++)
		{
			float x, y, pz;
			pts.getPoint(i, x, y, pz);
			if (std::hypot(x, y) > 5.0) continue;  // the map's max_range
			auto& c = cells[{grid.x2idx(x), grid.y2idx(y)}];
			c.n++;
			c.nFloor += std::abs(pz) <= 0.03f;
			c.nHigh += pz >= 0.15f && pz <= 1.2f;
		}
		for (const auto& [k, c] : cells)
		{
			const float pOcc = 1.0f - grid.getCell(unsigned(k.first), unsigned(k.second));
			const double x = grid.idx2x(unsigned(k.first)), y = grid.idx2y(unsigned(k.second));
			if (std::abs(pOcc - 0.5f) < 1e-3f) continue;  // no evidence (beyond the range of trust)
			if (c.n >= 5 && c.nFloor == c.n)
			{
				sc.floorKnown++;
				sc.floorOcc += pOcc > 0.5f;
			}
			else if (c.nHigh >= 5 && c.nFloor == 0 && x > 1.5 && x < 3.5 && std::abs(y) < 1.5)
			{
				sc.objects++;
				sc.objectsOcc += pOcc > 0.5f;
			}
		}
		std::printf(
			"[ RealSense ] %s: floor cells the map knows %zu, %zu occupied; object cells 1.5-3.5 m ahead %zu, %zu "
			"occupied\n",
			key.empty() ? "default" : (key + "=" + value).c_str(), sc.floorKnown, sc.floorOcc, sc.objects,
			sc.objectsOcc);
		return sc;
	};
	std::printf("[ RealSense ] calibrated z=%.3f pitch=%.2f roll=%.2f\n", z, pitch, roll);
	const Score def = score("", "");
	ASSERT_GT(def.floorKnown, 100u);
	EXPECT_LE(double(def.floorOcc), 0.01 * double(def.floorKnown));  // the "<= 1 % occupied"
	ASSERT_GT(def.objects, 3u);
	EXPECT_GE(double(def.objectsOcc), 0.9 * double(def.objects));
	// The rules of issue #27 on this frame (their measured effect, printed).
	// Without max_ground_offset the tree's plane, fitted to the floor 2-3 m ahead and
	// tilted by the stereo noise there (0.65 m, -3.3 deg against the 0.79 m, -0.3 deg of
	// the image-wide fit), puts most of the floor above the ground band.
	const Score noOffset = score("max_ground_offset", "0");
	EXPECT_GT(noOffset.floorOcc, noOffset.floorKnown / 2);
	score("range_of_trust", "false");
	score("camera_model", "kinect_one");
	// Every 2nd pixel row and column (the option for active-stereo cameras,
	// doc/cameras.md): the floor stays within the 1 %.
	const Score decimated = score("decimation", "2");
	ASSERT_GT(decimated.floorKnown, 100u);
	EXPECT_LE(double(decimated.floorOcc), 0.01 * double(decimated.floorKnown));
	EXPECT_GE(double(decimated.objectsOcc), 0.9 * double(decimated.objects));
}
#endif
