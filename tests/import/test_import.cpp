// Ground-aware mapping for MRPT -- tests of gam-import's parsing and conversion
// (rawlog_tools/gam-import/Import.h) with hand-derived expected values.
#include <gtest/gtest.h>
#include <mrpt/img/CImage.h>
#include <mrpt/maps/CSimplePointsMap.h>
#include <mrpt/obs/CObservation3DRangeScan.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>

#include "Import.h"

using namespace gam::import;
namespace fs = std::filesystem;

namespace
{
const double kDeg = M_PI / 180.0;

std::string tmpDir(const std::string& name)
{
	const std::string d = std::string(GAM_TEST_TMP_DIR) + "/unit_" + name;
	fs::remove_all(d);
	fs::create_directories(d);
	return d;
}

void writeText(const std::string& path, const std::string& text) { std::ofstream(path) << text; }

/** The message of the ImportError thrown by f ("" if none). */
template <typename F>
std::string errorOf(F f)
{
	try
	{
		f();
	}
	catch (const ImportError& e)
	{
		return e.what();
	}
	return "";
}

/** A 4x3 test camera: fx = fy = 2, cx = 1.5, cy = 1. */
Intrinsics k43() { return Intrinsics{4, 3, 2.0, 2.0, 1.5, 1.0}; }

void write16(const std::string& path, int w, int h, uint16_t (*value)(int r, int c))
{
	mrpt::img::CImage im;
	im.resize(w, h, mrpt::img::CH_GRAY, mrpt::img::PixelDepth::D16U);
	for (int r = 0; r < h; r++)
		// CImage::ptr<T>(col, row) steps col in bytes per channel, not per
		// 16-bit pixel: address a row, then index it.
		for (int c = 0; c < w; c++) im.ptr<uint16_t>(0, r)[c] = value(r, c);
	ASSERT_TRUE(im.saveToFile(path));
}
}  // namespace

// ------------------------------------------------------------- intrinsics

TEST(ImportIntrinsics, RejectsPrincipalPointOutsideAndBadFocalLength)
{
	EXPECT_EQ(errorOf([] { checkIntrinsics(k43(), "k"); }), "");
	EXPECT_NE(
		errorOf([] {
			checkIntrinsics({640, 480, 525, 525, 700, 240}, "k");
		}).find("cx = 700 is outside"),
		std::string::npos);
	EXPECT_NE(
		errorOf([] {
			checkIntrinsics({640, 480, 525, 525, 320, -1}, "k");
		}).find("cy = -1 is outside"),
		std::string::npos);
	EXPECT_NE(
		errorOf([] {
			checkIntrinsics({640, 480, 0, 525, 320, 240}, "k");
		}).find("fx and fy must be > 0"),
		std::string::npos);
	EXPECT_NE(
		errorOf([] { parseIntrinsics("640 480 525 525 320", "--intrinsics"); }).find("expected 6 numbers"),
		std::string::npos);
	EXPECT_NE(errorOf([] { parseIntrinsics("640.5 480 525 525 320 240", "x"); }).find("integers"), std::string::npos);
}

TEST(ImportCameraIni, ReadsEveryKeyAndRejectsUnknownOrIncomplete)
{
	const std::string d = tmpDir("ini");
	writeText(
		d + "/cam.ini",
		"# TUM freiburg1\n[camera]\nwidth = 640\nheight = 480\nfx = 517.3 ; comment\nfy = 516.5\ncx = 318.6\n"
		"cy = 255.3\ndepth_scale = 5000\nsensor_pose = 0.1 0 0.5 0 30 0\nlabel = KINECT\n");
	const CameraConfig c = readCameraIni(d + "/cam.ini");
	ASSERT_TRUE(c.intrinsics && c.depthScale && c.sensorPose && c.label);
	EXPECT_EQ(c.intrinsics->width, 640);
	EXPECT_DOUBLE_EQ(c.intrinsics->fx, 517.3);
	EXPECT_DOUBLE_EQ(c.intrinsics->cy, 255.3);
	EXPECT_DOUBLE_EQ(*c.depthScale, 5000);
	EXPECT_DOUBLE_EQ(c.sensorPose->x(), 0.1);
	EXPECT_NEAR(c.sensorPose->pitch(), 30 * kDeg, 1e-12);
	EXPECT_EQ(*c.label, "KINECT");

	writeText(d + "/typo.ini", "fx = 1\nfocal = 2\n");
	EXPECT_NE(
		errorOf([&] { readCameraIni(d + "/typo.ini"); }).find("typo.ini:2: unknown key 'focal'"), std::string::npos);
	writeText(d + "/part.ini", "fx = 500\nfy = 500\n");
	EXPECT_NE(errorOf([&] { readCameraIni(d + "/part.ini"); }).find("missing: width height cx cy"), std::string::npos);
	writeText(d + "/cx.ini", "width=320\nheight=240\nfx=300\nfy=300\ncx=320.5\ncy=239.5\n");
	EXPECT_NE(
		errorOf([&] { readCameraIni(d + "/cx.ini"); }).find("cx = 320.5 is outside the image (width 320)"),
		std::string::npos);
	EXPECT_NE(errorOf([&] { readCameraIni(d + "/none.ini"); }).find("missing file"), std::string::npos);
}

// ------------------------------------------------------------------ poses

TEST(ImportPoses, OpticalFrameIsTheTransposeOfR)
{
	// p_opt = R p_mrpt with R = [[0,-1,0],[0,0,-1],[1,0,0]]; the optical frame's
	// pose in the sensor frame rotates optical coordinates into MRPT's: R^T.
	const auto M = opticalInSensorFrame().getRotationMatrix();
	const double RT[3][3] = {{0, 0, 1}, {-1, 0, 0}, {0, -1, 0}};
	for (int i = 0; i < 3; i++)
		for (int j = 0; j < 3; j++) EXPECT_NEAR(M(i, j), RT[i][j], 1e-12) << i << "," << j;
}

TEST(ImportPoses, TumCameraPoseGivesTheRobotPoseWorkedOutByHand)
{
	// Robot at (1, 2) heading +y (yaw 90 deg); camera 0.2 m ahead of the robot
	// origin and 0.5 m up, level (sensorPose = (0.2, 0, 0.5, 0, 0, 0)).
	// Camera position: (1, 2) + 0.2 along +y, 0.5 up = (1, 2.2, 0.5).
	// Optical axes in the world: z (forward) = +y, x (right) = +x, y (down) = -z,
	// so R_world_opt has columns (1,0,0), (0,0,-1), (0,1,0) = a rotation of
	// -90 deg about x: quaternion qw = cos(-45 deg) = 0.70710678,
	// qx = sin(-45 deg) = -0.70710678, qy = qz = 0.
	const auto cam = poseFromTum(1, 2.2, 0.5, -0.70710678, 0, 0, 0.70710678);
	const auto robot = robotFromCamera(cam, mrpt::poses::CPose3D(0.2, 0, 0.5, 0, 0, 0));
	EXPECT_NEAR(robot.x(), 1, 1e-7);
	EXPECT_NEAR(robot.y(), 2, 1e-7);
	EXPECT_NEAR(robot.z(), 0, 1e-7);
	EXPECT_NEAR(robot.yaw(), 90 * kDeg, 1e-7);
	EXPECT_NEAR(robot.pitch(), 0, 1e-7);
	EXPECT_NEAR(robot.roll(), 0, 1e-7);
	const auto p2 = to2D(robot);
	EXPECT_NEAR(p2.phi(), M_PI / 2, 1e-7);

	// The same robot with the camera pitched 30 deg down: the optical axis
	// (world) = (0, cos 30, -sin 30). Build the camera pose from the robot and
	// check the round trip instead of a second quaternion by hand.
	const mrpt::poses::CPose3D mount(0.2, 0, 0.5, 0, 30 * kDeg, 0);
	const mrpt::poses::CPose3D robotTrue(1, 2, 0, 90 * kDeg, 0, 0);
	const auto optical = robotTrue + mount + opticalInSensorFrame();
	const auto zAxis = optical.getRotationMatrix().col(2);
	EXPECT_NEAR(zAxis[0], 0, 1e-12);
	EXPECT_NEAR(zAxis[1], std::cos(30 * kDeg), 1e-12);
	EXPECT_NEAR(zAxis[2], -std::sin(30 * kDeg), 1e-12);
	const auto back = robotFromCamera(optical, mount);
	EXPECT_NEAR(back.x(), 1, 1e-12);
	EXPECT_NEAR(back.y(), 2, 1e-12);
	EXPECT_NEAR(back.yaw(), 90 * kDeg, 1e-12);

	EXPECT_NE(errorOf([] { poseFromTum(0, 0, 0, 0, 0, 0, 0.5); }).find("not a unit quaternion"), std::string::npos);
}

TEST(ImportPoses, GroundTruthInterpolationAndGaps)
{
	// yaw 0 at t=10, yaw 90 deg at t=10.02 (quaternion about z: qz = sin 45, qw = cos 45)
	std::vector<TimedPose> gt = {
		{10.00, poseFromTum(0, 0, 0, 0, 0, 0, 1)}, {10.02, poseFromTum(0.2, 0.4, 0, 0, 0, 0.70710678, 0.70710678)}};
	const auto mid = poseAt(gt, 10.01, 0.05);
	ASSERT_TRUE(mid);
	EXPECT_NEAR(mid->x(), 0.1, 1e-9);
	EXPECT_NEAR(mid->y(), 0.2, 1e-9);
	EXPECT_NEAR(mid->yaw(), 45 * kDeg, 1e-6);  // slerp halfway
	const auto q = poseAt(gt, 10.015, 0.05);
	ASSERT_TRUE(q);
	EXPECT_NEAR(q->yaw(), 67.5 * kDeg, 1e-6);
	EXPECT_FALSE(poseAt(gt, 9.99, 0.05));    // before the first sample
	EXPECT_FALSE(poseAt(gt, 10.03, 0.05));   // after the last
	EXPECT_FALSE(poseAt(gt, 10.01, 0.005));  // samples 10 ms away, gap 5 ms
	EXPECT_TRUE(poseAt(gt, 10.02, 0.0));     // exact sample
}

TEST(ImportPoses, GroundTruthFileChecks)
{
	const std::string d = tmpDir("gt");
	writeText(
		d + "/gt.txt",
		"# ground truth trajectory\n# timestamp tx ty tz qx qy qz qw\n1305031098.6659 1.3563 0.6305 1.6380 0.6132 "
		"0.5962 -0.3311 -0.3986\n1305031098.6758 1.3543 0.6306 1.6360 0.6129 0.5966 -0.3316 -0.3980\n");
	const auto gt = readGroundTruth(d + "/gt.txt");
	ASSERT_EQ(gt.size(), 2u);
	EXPECT_DOUBLE_EQ(gt[0].t, 1305031098.6659);
	EXPECT_DOUBLE_EQ(gt[1].pose.x(), 1.3543);
	writeText(d + "/order.txt", "2.0 0 0 0 0 0 0 1\n1.5 0 0 0 0 0 0 1\n");
	EXPECT_NE(
		errorOf([&] {
			readGroundTruth(d + "/order.txt");
		}).find("line 2: timestamp 1.5 is not after the previous one (2): timestamps out of order"),
		std::string::npos);
	writeText(d + "/cols.txt", "2.0 0 0 0 0 0 1\n");
	EXPECT_NE(errorOf([&] { readGroundTruth(d + "/cols.txt"); }).find("expected 8 numbers"), std::string::npos);
	writeText(d + "/quat.txt", "2.0 0 0 0 0 0 0 2\n");
	EXPECT_NE(errorOf([&] { readGroundTruth(d + "/quat.txt"); }).find("not a unit quaternion"), std::string::npos);
}

// ------------------------------------------------------------ frame lists

TEST(ImportLists, TumDepthListAssociationsAndOrder)
{
	const std::string d = tmpDir("lists");
	writeText(
		d + "/depth.txt",
		"# depth maps\n# file: 'rgbd_dataset_freiburg1_xyz.bag'\n# timestamp filename\n"
		"1305031102.160407 depth/1305031102.160407.png\n1305031102.194330 depth/1305031102.194330.png\n");
	const auto l = readFrameList(d + "/depth.txt");
	ASSERT_EQ(l.size(), 2u);
	EXPECT_DOUBLE_EQ(l[0].t, 1305031102.160407);
	EXPECT_EQ(l[1].file, "depth/1305031102.194330.png");
	EXPECT_EQ(l[1].line, 5);
	// associate.py rgb.txt depth.txt, and the other order
	writeText(d + "/assoc.txt", "1.0 rgb/1.0.png 1.01 depth/1.01.png\n2.0 rgb/2.0.png 2.01 depth/2.01.png\n");
	const auto a = readFrameList(d + "/assoc.txt");
	EXPECT_DOUBLE_EQ(a[0].t, 1.01);
	EXPECT_EQ(a[1].file, "depth/2.01.png");
	writeText(d + "/assoc2.txt", "1.01 depth/1.01.png 1.0 rgb/1.0.png\n");
	EXPECT_DOUBLE_EQ(readFrameList(d + "/assoc2.txt")[0].t, 1.01);
	writeText(d + "/order.txt", "1.0 a.png\n1.0 b.png\n");
	EXPECT_NE(errorOf([&] { readFrameList(d + "/order.txt"); }).find("timestamps out of order"), std::string::npos);
	writeText(d + "/three.txt", "1.0 a.png extra\n");
	EXPECT_NE(
		errorOf([&] { readFrameList(d + "/three.txt"); }).find("expected 'timestamp filename'"), std::string::npos);
}

TEST(ImportLists, FolderInNaturalOrder)
{
	const std::string d = tmpDir("folder");
	for (const char* n : {"f10.png", "f2.png", "f1.PNG", "notes.txt"}) writeText(d + "/" + n, "");
	const auto names = listFolder(d, ".png");
	ASSERT_EQ(names.size(), 3u);
	EXPECT_EQ(names[0], "f1.PNG");
	EXPECT_EQ(names[1], "f2.png");
	EXPECT_EQ(names[2], "f10.png");
	EXPECT_NE(errorOf([&] { listFolder(d + "/none", ".png"); }).find("missing folder"), std::string::npos);
}

// -------------------------------------------------------------- depth PNG

TEST(ImportDepthPng, SixteenBitValuesKeptAndUnprojectedAsWorkedOutByHand)
{
	const std::string d = tmpDir("png");
	// TUM factor 5000: 10000 = 2.0 m everywhere, pixel (row 2, col 3) 5000 = 1.0 m.
	write16(d + "/d.png", 4, 3, [](int r, int c) -> uint16_t { return r == 2 && c == 3 ? 5000 : 10000; });
	const DepthFrame f = loadDepthPng(d + "/d.png", k43(), 5000);
	EXPECT_EQ(f.range.cols(), 4);
	EXPECT_EQ(f.range.rows(), 3);
	EXPECT_EQ(f.range(0, 0), 10000);
	EXPECT_EQ(f.range(2, 3), 5000);
	EXPECT_FLOAT_EQ(f.units, 1.0f / 5000);

	auto o = makeObservation(f, mrpt::poses::CPose3D(), "CAM", 1.5, 10);
	EXPECT_TRUE(o->range_is_depth);
	EXPECT_EQ(o->cameraParams.ncols, 4u);
	EXPECT_DOUBLE_EQ(o->cameraParams.cx(), 1.5);
	mrpt::maps::CSimplePointsMap pts;
	mrpt::obs::T3DPointsProjectionParams pp;
	o->unprojectInto(pts, pp);
	ASSERT_EQ(pts.size(), 12u);
	// Pixel (u=0, v=0), depth 2: optical x = (0 - 1.5) 2 / 2 = -1.5, y = (0 - 1) 2 / 2 = -1,
	// z = 2 -> MRPT sensor frame (x = z, y = -x, z = -y) = (2, 1.5, 1).
	// Pixel (u=3, v=2), depth 1: optical (0.75, 0.5, 1) -> (1, -0.75, -0.5).
	auto has = [&](double x, double y, double z) {
		for (size_t i = 0; i < pts.size(); i++)
		{
			float px, py, pz;
			pts.getPoint(i, px, py, pz);
			if (std::abs(px - x) < 1e-4 && std::abs(py - y) < 1e-4 && std::abs(pz - z) < 1e-4) return true;
		}
		return false;
	};
	EXPECT_TRUE(has(2, 1.5, 1));
	EXPECT_TRUE(has(1, -0.75, -0.5));
	// Pixel (u=3, v=1), depth 2: optical (1.5, 0, 2) -> (2, -1.5, 0).
	EXPECT_TRUE(has(2, -1.5, 0));
	// Pixel (u=0, v=2), depth 2: optical (-1.5, 1, 2) -> (2, 1.5, -1).
	EXPECT_TRUE(has(2, 1.5, -1));
	EXPECT_FALSE(has(2, -0.75 * 2, -0.5 * 2));  // (u=3, v=2) is at 1 m, not 2 m
}

TEST(ImportDepthPng, RejectsWrongFormatsAndSizes)
{
	const std::string d = tmpDir("pngbad");
	mrpt::img::CImage g8(4, 3, mrpt::img::CH_GRAY);
	g8.filledRectangle(0, 0, 3, 2, mrpt::img::TColor(100, 100, 100));
	ASSERT_TRUE(g8.saveToFile(d + "/gray8.png"));
	mrpt::img::CImage rgb(4, 3, mrpt::img::CH_RGB);
	rgb.filledRectangle(0, 0, 3, 2, mrpt::img::TColor(10, 20, 30));
	ASSERT_TRUE(rgb.saveToFile(d + "/rgb.png"));
	write16(d + "/big.png", 5, 3, [](int, int) -> uint16_t { return 1000; });
	writeText(d + "/fake.png", "not an image");

	EXPECT_NE(
		errorOf([&] {
			loadDepthPng(d + "/gray8.png", k43(), 5000);
		}).find("8-bit image with 1 channel(s); a depth PNG must be 16-bit with 1 channel"),
		std::string::npos);
	EXPECT_NE(
		errorOf([&] { loadDepthPng(d + "/rgb.png", k43(), 5000); }).find("8-bit image with 3 channel(s)"),
		std::string::npos);
	EXPECT_NE(
		errorOf([&] { loadDepthPng(d + "/big.png", k43(), 5000); }).find("image is 5x3 but the intrinsics are for 4x3"),
		std::string::npos);
	EXPECT_NE(errorOf([&] { loadDepthPng(d + "/fake.png", k43(), 5000); }).find("not a PNG file"), std::string::npos);
	EXPECT_NE(errorOf([&] { loadDepthPng(d + "/none.png", k43(), 5000); }).find("missing file"), std::string::npos);
}

// -------------------------------------------------------------------- LZF

TEST(ImportLzf, LiteralsAndOverlappingBackReference)
{
	// ctrl 2: 3 literal bytes "abc"; ctrl 0x80 = length (4 + 2) = 6, offset
	// ((0 << 8) | 2) + 1 = 3: copies "abcabc" from 3 bytes back (overlapping).
	const uint8_t in[] = {2, 'a', 'b', 'c', 0x80, 2};
	const auto out = lzfDecompress(in, sizeof in, 9);
	EXPECT_EQ(std::string(out.begin(), out.end()), "abcabcabc");
	// long match: ctrl 0xE0 (7) + extra byte 3 -> 7 + 3 + 2 = 12 bytes of 'x'
	const uint8_t in2[] = {0, 'x', 0xE0, 3, 0};
	EXPECT_EQ(lzfDecompress(in2, sizeof in2, 13), std::vector<uint8_t>(13, 'x'));
	EXPECT_NE(
		errorOf([&] { lzfDecompress(in, sizeof in, 10); }).find("9 bytes decompressed, header says 10"),
		std::string::npos);
	const uint8_t before[] = {0, 'a', 0x20, 5};  // back 6 bytes with 1 written
	EXPECT_NE(errorOf([&] { lzfDecompress(before, sizeof before, 4); }).find("before the start"), std::string::npos);
	EXPECT_NE(errorOf([&] { lzfDecompress(in, sizeof in, 5); }).find("output overrun"), std::string::npos);
}

// -------------------------------------------------------------------- PCD

namespace
{
/** The 4x3 test cloud: depth z = 1 + 0.25 row + 0.5 col [m], pixel (row 1,
 * col 2) invalid (NaN); x = (u - 1.5) z / 2, y = (v - 1) z / 2; colour = row*16+col. */
struct TestCloud
{
	float x[12], y[12], z[12];
	uint32_t rgb[12];
	TestCloud()
	{
		for (int r = 0; r < 3; r++)
			for (int c = 0; c < 4; c++)
			{
				const int i = r * 4 + c;
				const float zz = (r == 1 && c == 2) ? NAN : 1.0f + 0.25f * r + 0.5f * c;
				z[i] = zz;
				x[i] = float((c - 1.5) * zz / 2);
				y[i] = float((r - 1.0) * zz / 2);
				rgb[i] = uint32_t(r * 16 + c) << 16 | 0x0080FF;
			}
	}
};

std::string pcdHeader(const std::string& data)
{
	return "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\nFIELDS x y z rgb\nSIZE 4 4 4 4\nTYPE F F F U\n"
		   "COUNT 1 1 1 1\nWIDTH 4\nHEIGHT 3\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 12\nDATA " +
		   data + "\n";
}

void writePcds(const std::string& d)
{
	const TestCloud t;
	{
		std::ofstream f(d + "/a.pcd");
		f << pcdHeader("ascii");
		for (int i = 0; i < 12; i++)
		{
			char b[200];
			std::snprintf(b, sizeof b, "%.9g %.9g %.9g %u\n", t.x[i], t.y[i], t.z[i], t.rgb[i]);
			f << b;
		}
	}
	{
		std::ofstream f(d + "/b.pcd", std::ios::binary);
		f << pcdHeader("binary");
		for (int i = 0; i < 12; i++)
		{
			f.write(reinterpret_cast<const char*>(&t.x[i]), 4);
			f.write(reinterpret_cast<const char*>(&t.y[i]), 4);
			f.write(reinterpret_cast<const char*>(&t.z[i]), 4);
			f.write(reinterpret_cast<const char*>(&t.rgb[i]), 4);
		}
	}
	{
		// column-wise (all x, all y, all z, all rgb) = 192 bytes, stored as LZF
		// literal runs of at most 32 bytes (a valid LZF stream without matches).
		std::string cols;
		cols.append(reinterpret_cast<const char*>(t.x), 48);
		cols.append(reinterpret_cast<const char*>(t.y), 48);
		cols.append(reinterpret_cast<const char*>(t.z), 48);
		cols.append(reinterpret_cast<const char*>(t.rgb), 48);
		std::string lzf;
		for (size_t p = 0; p < cols.size(); p += 32)
		{
			const size_t n = std::min<size_t>(32, cols.size() - p);
			lzf.push_back(char(n - 1));
			lzf.append(cols, p, n);
		}
		std::ofstream f(d + "/c.pcd", std::ios::binary);
		f << pcdHeader("binary_compressed");
		const uint32_t sizes[2] = {uint32_t(lzf.size()), uint32_t(cols.size())};
		f.write(reinterpret_cast<const char*>(sizes), 8);
		f << lzf;
	}
}
}  // namespace

TEST(ImportPcd, AsciiBinaryAndCompressedGiveTheSameCloudAndIntrinsics)
{
	const std::string d = tmpDir("pcd");
	writePcds(d);
	const TestCloud t;
	for (const char* name : {"a.pcd", "b.pcd", "c.pcd"})
	{
		SCOPED_TRACE(name);
		const PcdCloud c = readPcd(d + "/" + name);
		ASSERT_EQ(c.width, 4);
		ASSERT_EQ(c.height, 3);
		ASSERT_EQ(c.rgb.size(), 12u);
		EXPECT_FLOAT_EQ(c.z[0], 1.0f);
		EXPECT_FLOAT_EQ(c.z[11], 1.0f + 0.5f + 1.5f);
		EXPECT_TRUE(std::isnan(c.z[6]));
		EXPECT_EQ(c.rgb[9], (uint32_t(2 * 16 + 1) << 16) | 0x0080FF);
		const IntrinsicsFit fit = fitIntrinsics(c);
		EXPECT_EQ(fit.points, 11u);
		EXPECT_NEAR(fit.k.fx, 2.0, 1e-5);
		EXPECT_NEAR(fit.k.fy, 2.0, 1e-5);
		EXPECT_NEAR(fit.k.cx, 1.5, 1e-5);
		EXPECT_NEAR(fit.k.cy, 1.0, 1e-5);
		EXPECT_LT(fit.rms_px, 1e-5);
		// depth in mm: z = 1 + 0.25 r + 0.5 c
		const DepthFrame f = depthFromPcd(c, fit.k, 0.001f);
		EXPECT_EQ(f.range(0, 0), 1000);
		EXPECT_EQ(f.range(2, 3), 3000);
		EXPECT_EQ(f.range(1, 1), 1750);
		EXPECT_EQ(f.range(1, 2), 0);  // NaN -> no data
		ASSERT_TRUE(f.rgb.has_value());
		// CImage is BGR in memory: pixel (row 2, col 1): R = 33, G = 0x80, B = 0xFF
		const uint8_t* px = f.rgb->ptr<uint8_t>(1, 2);
		EXPECT_EQ(px[0], 0xFF);
		EXPECT_EQ(px[1], 0x80);
		EXPECT_EQ(px[2], 33);
	}
}

TEST(ImportPcd, RejectsBadFiles)
{
	const std::string d = tmpDir("pcdbad");
	writePcds(d);
	std::string b;
	{
		std::ifstream f(d + "/b.pcd", std::ios::binary);
		b.assign((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
	}
	writeText(d + "/trunc.pcd", b.substr(0, b.size() - 10));
	EXPECT_NE(
		errorOf([&] { readPcd(d + "/trunc.pcd"); }).find("truncated: 182 data bytes, 192 expected"), std::string::npos);
	std::string c;
	{
		std::ifstream f(d + "/c.pcd", std::ios::binary);
		c.assign((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
	}
	writeText(d + "/ctrunc.pcd", c.substr(0, c.size() - 10));
	EXPECT_NE(errorOf([&] { readPcd(d + "/ctrunc.pcd"); }).find("truncated"), std::string::npos);
	std::string u = pcdHeader("ascii");
	u.replace(u.find("WIDTH 4\nHEIGHT 3"), 16, "WIDTH 12\nHEIGHT 1");
	writeText(d + "/unorg.pcd", u);
	EXPECT_NE(errorOf([&] { readPcd(d + "/unorg.pcd"); }).find("unorganized cloud (HEIGHT 1)"), std::string::npos);
	std::string nz = pcdHeader("ascii");
	nz.replace(nz.find("FIELDS x y z rgb"), 16, "FIELDS x y w rgb");
	writeText(d + "/noz.pcd", nz);
	EXPECT_NE(errorOf([&] { readPcd(d + "/noz.pcd"); }).find("no x, y and z fields"), std::string::npos);
	writeText(d + "/png.pcd", "\x89PNG\r\n");
	EXPECT_NE(errorOf([&] { readPcd(d + "/png.pcd"); }).find("not a PCD file"), std::string::npos);
	EXPECT_NE(errorOf([&] { readPcd(d + "/missing.pcd"); }).find("missing file"), std::string::npos);
}
