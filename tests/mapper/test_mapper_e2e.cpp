// End-to-end tests of ground-aware-mapper: run the real executable on a real
// rawlog and on generated ones (both rawlog formats), and check every output.
#include <gam/eval/Evaluation.h>
#include <gam/maps/GridIO.h>
#include <gtest/gtest.h>

#include <mrpt/img/CImage.h>
#include <mrpt/io/CFileGZInputStream.h>
#include <mrpt/io/CFileGZOutputStream.h>
#include <mrpt/maps/CElevation25DMap.h>
#include <mrpt/maps/registerBaselineMaps.h>
#include <mrpt/maps/registerGroundAwareMaps.h>
#include <mrpt/obs/CActionCollection.h>
#include <mrpt/obs/CActionRobotMovement2D.h>
#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/obs/CObservation3DRangeScan.h>
#include <mrpt/obs/CObservationOdometry.h>
#include <mrpt/obs/CSensoryFrame.h>
#include <mrpt/serialization/CArchive.h>
#include <algorithm>

#include <unistd.h>

#include <array>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <set>
#include <sstream>

namespace fs = std::filesystem;
using mrpt::maps::COccupancyGridMap2D;
using namespace gam::maps;

namespace
{
const std::string kExe = GAM_MAPPER_EXE;
// One work folder per process: ctest may run these tests in parallel.
const std::string kTmp = std::string(GAM_TEST_TMP_DIR) + "/p" + std::to_string(getpid());
const std::string kMilk =
	std::string(GAM_REAL_DATA_DIR) + "/pcl_milk_bottles_on_carpet/pcl_milk_bottles_on_carpet.rawlog";
const std::vector<std::string> kGrids = {"ground_aware", "height_band", "octomap"};

struct RunResult
{
	int rc = -1;
	std::string out, err;
};

std::string slurp(const std::string& f)
{
	std::ifstream i(f, std::ios::binary);
	std::ostringstream s;
	s << i.rdbuf();
	return s.str();
}

RunResult runMapper(const std::string& args)
{
	static int n = 0;
	fs::create_directories(kTmp);
	const std::string o = kTmp + "/run" + std::to_string(getpid()) + "_" + std::to_string(n) + ".out";
	const std::string e = kTmp + "/run" + std::to_string(getpid()) + "_" + std::to_string(n++) + ".err";
	const std::string cmd = "'" + kExe + "' " + args + " >'" + o + "' 2>'" + e + "' </dev/null";
	const int st = std::system(cmd.c_str());
	RunResult r;
	r.rc = WIFEXITED(st) ? WEXITSTATUS(st) : -1;
	r.out = slurp(o);
	r.err = slurp(e);
	return r;
}

std::string freshDir(const std::string& name)
{
	const std::string d = kTmp + "/" + name;
	fs::remove_all(d);
	return d;
}

// ------------------------------------------------------------ synthetic scene
struct Box
{
	double x0, x1, y0, y1, z0, z1;
};
// Floor (top z = 0, thick) with a 0.5 x 0.5 m hole 0.5 m deep, and a box.
const Box kBoxObstacle{1.4, 1.7, 0.3, 0.7, 0.0, 0.5};
const Box kHole{2.0, 2.5, -0.6, -0.1, -0.5, 0.0};  // the empty part
const std::vector<Box> kScene = {{-10, 2.0, -10, 10, -1, 0},       {2.5, 10, -10, 10, -1, 0},
								 {2.0, 2.5, -10, -0.6, -1, 0},     {2.0, 2.5, -0.1, 10, -1, 0},
								 {2.0, 2.5, -0.6, -0.1, -1, -0.5}, kBoxObstacle};

double rayBox(const mrpt::math::TPoint3D& o, const mrpt::math::TPoint3D& d, const Box& b)
{
	double t0 = 0, t1 = std::numeric_limits<double>::infinity();
	const double lo[3] = {b.x0, b.y0, b.z0}, hi[3] = {b.x1, b.y1, b.z1};
	const double oo[3] = {o.x, o.y, o.z}, dd[3] = {d.x, d.y, d.z};
	for (int k = 0; k < 3; k++)
	{
		if (std::abs(dd[k]) < 1e-12)
		{
			if (oo[k] < lo[k] || oo[k] > hi[k]) return -1;
			continue;
		}
		double a = (lo[k] - oo[k]) / dd[k], c = (hi[k] - oo[k]) / dd[k];
		if (a > c) std::swap(a, c);
		t0 = std::max(t0, a);
		t1 = std::min(t1, c);
		if (t0 > t1) return -1;
	}
	return t0;
}

mrpt::obs::CObservation3DRangeScan::Ptr makeFrame(
	double robotX, const std::string& label = "DEPTH",
	const mrpt::poses::CPose3D& sensorPose = mrpt::poses::CPose3D(0.1, 0, 0.6, 0, mrpt::DEG2RAD(30.0), 0))
{
	const int W = 160, H = 120;
	const double fx = 120, fy = 120, cx = 79.5, cy = 59.5;
	auto o = mrpt::obs::CObservation3DRangeScan::Create();
	o->sensorLabel = label;
	o->timestamp = mrpt::Clock::fromDouble(1000.0 + robotX);
	o->hasRangeImage = true;
	o->range_is_depth = true;
	o->rangeUnits = 0.001f;
	o->maxRange = 5.0f;
	o->sensorPose = sensorPose;
	o->cameraParams.ncols = W;
	o->cameraParams.nrows = H;
	o->cameraParams.setIntrinsicParamsFromValues(fx, fy, cx, cy);
	o->cameraParamsIntensity = o->cameraParams;
	o->rangeImage_setSize(H, W);
	const mrpt::poses::CPose3D sensorInWorld = mrpt::poses::CPose3D(robotX, 0, 0, 0, 0, 0) + o->sensorPose;
	const auto R = sensorInWorld.getRotationMatrix();
	const mrpt::math::TPoint3D org(sensorInWorld.x(), sensorInWorld.y(), sensorInWorld.z());
	for (int r = 0; r < H; r++)
		for (int c = 0; c < W; c++)
		{
			const double ds[3] = {1.0, (cx - c) / fx, (cy - r) / fy};
			mrpt::math::TPoint3D d(
				R(0, 0) * ds[0] + R(0, 1) * ds[1] + R(0, 2) * ds[2],
				R(1, 0) * ds[0] + R(1, 1) * ds[1] + R(1, 2) * ds[2],
				R(2, 0) * ds[0] + R(2, 1) * ds[1] + R(2, 2) * ds[2]);
			double best = std::numeric_limits<double>::infinity();
			for (const auto& b : kScene)
			{
				const double t = rayBox(org, d, b);
				if (t > 1e-6 && t < best) best = t;
			}
			// t is the depth along the sensor +X axis (ds has x = 1).
			o->rangeImage(r, c) = (std::isfinite(best) && best < 4.99) ? uint16_t(std::lround(best / 0.001)) : 0;
		}
	return o;
}

const std::vector<double> kPosesX = {0.0, 0.25, 0.5, 0.75};

void writeObsFormat(const std::string& path)
{
	mrpt::io::CFileGZOutputStream f(path);
	auto ar = mrpt::serialization::archiveFrom(f);
	for (double x : kPosesX)
	{
		auto odo = mrpt::obs::CObservationOdometry::Create();
		odo->sensorLabel = "ODOMETRY";
		odo->odometry = mrpt::poses::CPose2D(x, 0, 0);
		ar << *odo;
		ar << *makeFrame(x);
	}
}

// The action of a sensory-frame rawlog: odometry moved dx along x.
mrpt::obs::CActionCollection odometryStep(double dx)
{
	mrpt::obs::CActionCollection acts;
	mrpt::obs::CActionRobotMovement2D mov;
	mrpt::obs::CActionRobotMovement2D::TMotionModelOptions mm;
	mov.computeFromOdometry(mrpt::poses::CPose2D(dx, 0, 0), mm);
	acts.insert(mov);
	return acts;
}

void writeSfFormat(const std::string& path)
{
	mrpt::io::CFileGZOutputStream f(path);
	auto ar = mrpt::serialization::archiveFrom(f);
	double prev = 0;
	for (double x : kPosesX)
	{
		const mrpt::obs::CActionCollection acts = odometryStep(x - prev);
		prev = x;
		mrpt::obs::CSensoryFrame sf;
		sf.insert(makeFrame(x));
		ar << acts << sf;
	}
}

// Two cameras (issue #28): the forward one and one looking down at the near
// field, both at each pose with one timestamp, as observations and as
// sensory frames.
const mrpt::poses::CPose3D kDownCamera(0.05, 0, 0.5, 0, mrpt::DEG2RAD(60.0), 0);

void writeTwoCameraRawlogs(const std::string& obsPath, const std::string& sfPath)
{
	mrpt::io::CFileGZOutputStream fo(obsPath), fsf(sfPath);
	auto ao = mrpt::serialization::archiveFrom(fo);
	auto as = mrpt::serialization::archiveFrom(fsf);
	double prev = 0;
	for (double x : kPosesX)
	{
		auto odo = mrpt::obs::CObservationOdometry::Create();
		odo->sensorLabel = "ODOMETRY";
		odo->odometry = mrpt::poses::CPose2D(x, 0, 0);
		ao << *odo << *makeFrame(x) << *makeFrame(x, "DEPTH_DOWN", kDownCamera);
		const mrpt::obs::CActionCollection acts = odometryStep(x - prev);
		prev = x;
		mrpt::obs::CSensoryFrame sf;
		sf.insert(makeFrame(x));
		sf.insert(makeFrame(x, "DEPTH_DOWN", kDownCamera));
		as << acts << sf;
	}
}

/** p_free of the cell at (x, y). */
double pFree(const COccupancyGridMap2D& g, double x, double y) { return g.getPos(float(x), float(y)); }
/** The cells whose centre lies in the rectangle. */
template <class F>
void forCellsIn(const COccupancyGridMap2D& g, double x0, double x1, double y0, double y1, F f)
{
	for (int cy = std::max(0, g.y2idx(y0) - 1); cy <= std::min(int(g.getSizeY()) - 1, g.y2idx(y1) + 1); cy++)
		for (int cx = std::max(0, g.x2idx(x0) - 1); cx <= std::min(int(g.getSizeX()) - 1, g.x2idx(x1) + 1); cx++)
		{
			const double x = g.idx2x(cx), y = g.idx2y(cy);
			if (x >= x0 && x <= x1 && y >= y0 && y <= y1) f(double(g.getCell(cx, cy)));
		}
}
/** Lowest p_free over the cells inside a rectangle. */
double minPFree(const COccupancyGridMap2D& g, double x0, double x1, double y0, double y1)
{
	double m = 1;
	forCellsIn(g, x0, x1, y0, y1, [&](double p) { m = std::min(m, p); });
	return m;
}
double fractionOccupied(const COccupancyGridMap2D& g, double x0, double x1, double y0, double y1)
{
	int n = 0, occ = 0;
	forCellsIn(g, x0, x1, y0, y1, [&](double p) {
		n++;
		if (p < 0.4) occ++;
	});
	return n ? double(occ) / n : 0;
}

/** Every output of one run exists and parses; the PGM/PNG match the grid. */
void checkOutputs(const std::string& dir)
{
	for (const auto& name : kGrids)
	{
		SCOPED_TRACE(name);
		const std::string base = dir + "/" + name;
		for (const char* ext : {".yaml", ".pgm", ".gridmap.gz", ".png"})
			ASSERT_TRUE(fs::exists(base + ext)) << base + ext;
		// The evaluator's map_server reader (libs/ground_eval), not the writer's code.
		const gam::eval::RosMap y = gam::eval::loadRosMap(base + ".yaml");
		const COccupancyGridMap2D g = readGridmapGz(base + ".gridmap.gz");
		EXPECT_EQ(fs::path(y.imagePath).filename().string(), name + ".pgm");
		EXPECT_EQ(y.mode, "scale");
		EXPECT_EQ(y.negate, 0);
		EXPECT_NEAR(y.resolution, g.getResolution(), 1e-6);
		EXPECT_NEAR(y.origin_x, g.getXMin(), 1e-4);
		EXPECT_NEAR(y.origin_y, g.getYMin(), 1e-4);
		ASSERT_EQ(y.width, int(g.getSizeX()));
		ASSERT_EQ(y.height, int(g.getSizeY()));
		size_t bad = 0, occupied = 0;
		for (int row = 0; row < y.height; row++)
			for (int x = 0; x < y.width; x++)
			{
				const int cy = y.height - 1 - row;  // first row = highest y
				const double pOcc = 1.0 - double(g.getCell(x, cy));
				const int expect = int(std::lround(255.0 * (1.0 - pOcc)));
				const int pixel = y.pixels[size_t(row) * size_t(y.width) + size_t(x)];
				if (std::abs(pixel - expect) > 0) bad++;
				if (pOcc > 0.6) occupied++;
			}
		EXPECT_EQ(bad, 0u) << "PGM pixels differ from round(255*(1-p_occ))";
		EXPECT_GT(occupied, 0u) << "no occupied cell at all";

		mrpt::img::CImage png;
		ASSERT_TRUE(png.loadFromFile(base + ".png"));
		const PngView v = pngViewOf(g);
		ASSERT_EQ(int(png.getWidth()), v.w * v.scale);
		ASSERT_EQ(int(png.getHeight()), v.h * v.scale);
		size_t pbad = 0;
		for (int py = 0; py < int(png.getHeight()); py += 1)
			for (int px = 0; px < int(png.getWidth()); px += 1)
			{
				const int cx = v.cx0 + px / v.scale, cy = v.cy0 + v.h - 1 - py / v.scale;
				// CImage keeps OpenCV's BGR channel order.
				struct
				{
					uint8_t R, G, B;
				} c{png.at<uint8_t>(px, py, 2), png.at<uint8_t>(px, py, 1), png.at<uint8_t>(px, py, 0)};
				const auto raw = g.getRawMap()[size_t(cx) + size_t(cy) * g.getSizeX()];
				if (raw == 0)
				{
					if (!(c.R == kUnknownR && c.G == kUnknownG && c.B == kUnknownB)) pbad++;
				}
				else
				{
					const uint8_t p = pgmValue(raw);
					if (!(c.R == p && c.G == p && c.B == p)) pbad++;
				}
			}
		EXPECT_EQ(pbad, 0u) << "PNG pixels differ from the grid";
	}
	// Elevation map.
	for (const char* f : {"elevation.png", "elevation_span.png", "elevation_count.png", "elevation.map.gz"})
		EXPECT_TRUE(fs::exists(dir + "/" + f)) << f;
	{
		mrpt::maps::registerGroundAwareMaps();
		mrpt::maps::registerBaselineMaps();
		mrpt::io::CFileGZInputStream fi(dir + "/elevation.map.gz");
		mrpt::maps::CElevation25DMap em;
		mrpt::serialization::archiveFrom(fi) >> em;
		EXPECT_FALSE(em.isEmpty());
	}
	// CSVs.
	{
		std::ifstream f(dir + "/ground_planes.csv");
		std::string h;
		std::getline(f, h);
		EXPECT_EQ(h, "frame,a,b,c,d,nodes,status,mount_z,mount_pitch_deg,mount_roll_deg,mount_alarm,sensor");
	}
	{
		std::ifstream f(dir + "/timing.csv");
		std::string h, line;
		std::getline(f, h);
		EXPECT_EQ(h, "frame,map,stage,ms");
		std::set<std::string> maps;
		// Per (frame, map): the insertion's total and the sum of its stages.
		// The stages are disjoint parts of the one insertion the total times,
		// so they add up to at most the total (+ the 4-decimal rounding).
		std::map<std::pair<std::string, std::string>, std::pair<double, double>> perInsert;
		while (std::getline(f, line))
		{
			std::vector<std::string> c;
			std::stringstream ss(line);
			std::string t;
			while (std::getline(ss, t, ',')) c.push_back(t);
			ASSERT_EQ(c.size(), 4u) << line;
			maps.insert(c[1]);
			const double ms = std::stod(c[3]);
			ASSERT_TRUE(std::isfinite(ms) && ms >= 0) << line;
			auto& [total, stages] = perInsert[{c[0], c[1]}];
			(c[2] == "total" ? total : stages) += ms;
		}
		for (const auto& [key, ts] : perInsert)
		{
			EXPECT_GT(ts.first, 0.0) << "frame " << key.first << " " << key.second << ": no total";
			EXPECT_LE(ts.second, ts.first + 1e-3) << "frame " << key.first << " " << key.second;
		}
		for (const auto& n : kGrids) EXPECT_TRUE(maps.count(n)) << n;
		EXPECT_TRUE(maps.count("elevation"));
	}
	// Nothing temporary left behind.
	for (const auto& de : fs::directory_iterator(dir))
		EXPECT_NE(de.path().filename().string().rfind(".ground-aware-mapper.tmp", 0), 0u) << de.path();
}

/** Removes this process's work folder when every test passed. */
class CleanUp : public ::testing::Environment
{
   public:
	void TearDown() override
	{
		if (!::testing::UnitTest::GetInstance()->Failed()) fs::remove_all(kTmp);
	}
};
const auto* const kCleanUp = ::testing::AddGlobalTestEnvironment(new CleanUp);

class MapperE2E : public ::testing::Test
{
   protected:
	static void SetUpTestSuite()
	{
		fs::create_directories(kTmp);
		obsRawlog = kTmp + "/scene_obs.rawlog";
		sfRawlog = kTmp + "/scene_sf.rawlog";
		writeObsFormat(obsRawlog);
		writeSfFormat(sfRawlog);
		obsOut = freshDir("out_obs");
		sfOut = freshDir("out_sf");
		obsRun = runMapper("--rawlog '" + obsRawlog + "' --out '" + obsOut + "'");
		sfRun = runMapper("--rawlog '" + sfRawlog + "' --out '" + sfOut + "'");
	}
	static std::string obsRawlog, sfRawlog, obsOut, sfOut;
	static RunResult obsRun, sfRun;
};
std::string MapperE2E::obsRawlog, MapperE2E::sfRawlog, MapperE2E::obsOut, MapperE2E::sfOut;
RunResult MapperE2E::obsRun, MapperE2E::sfRun;

}  // namespace

// ----------------------------------------------------------------- tests
TEST(MapperReal, MilkBottlesAllOutputsParseAndMatch)
{
	if (!fs::exists(kMilk)) GTEST_SKIP() << "missing " << kMilk;
	const std::string out = freshDir("out_milk");
	const auto r = runMapper("--rawlog '" + kMilk + "' --out '" + out + "'");
	ASSERT_EQ(r.rc, 0) << r.err;
	EXPECT_NE(r.out.find("frames: 1 "), std::string::npos) << r.out;
	for (const auto& n : kGrids) EXPECT_NE(r.out.find(n), std::string::npos) << r.out;
	EXPECT_NE(r.out.find("median_ms"), std::string::npos);
	checkOutputs(out);
	// One frame, ground found: the plane is the floor (robot frame z = 0).
	std::ifstream f(out + "/ground_planes.csv");
	std::string h, row;
	std::getline(f, h);
	ASSERT_TRUE(std::getline(f, row));
	EXPECT_NE(row.find(",ok"), std::string::npos) << row;
	EXPECT_EQ(std::count(row.begin(), row.end(), ','), 11) << "12 columns, the last the camera's label: " << row;
	EXPECT_NE(row.back(), ',') << row;
	// The three bottles and cartons (0.21-0.26 m tall, 0.5-0.8 m ahead; the
	// dataset's README) are three separate obstacles in the ground-aware grid:
	// three 8-connected groups of occupied cells in x 0.4-0.9 m, |y| <= 0.4 m,
	// each at least 2 cells (each object is wider than a 5 cm cell).
	const auto g = readGridmapGz(out + "/ground_aware.gridmap.gz");
	std::set<std::pair<int, int>> occ;
	for (int cx = g.x2idx(0.4f); cx <= g.x2idx(0.9f); cx++)
		for (int cy = g.y2idx(-0.4f); cy <= g.y2idx(0.4f); cy++)
			if (g.getCell(unsigned(cx), unsigned(cy)) < 0.5f) occ.insert({cx, cy});
	std::vector<size_t> groups;
	while (!occ.empty())
	{
		std::vector<std::pair<int, int>> todo = {*occ.begin()};
		occ.erase(occ.begin());
		size_t n = 0;
		while (!todo.empty())
		{
			const auto [x, y] = todo.back();
			todo.pop_back();
			n++;
			for (int dx = -1; dx <= 1; dx++)
				for (int dy = -1; dy <= 1; dy++)
					if (occ.erase({x + dx, y + dy})) todo.push_back({x + dx, y + dy});
		}
		groups.push_back(n);
	}
	ASSERT_EQ(groups.size(), 3u) << "occupied groups in front of the camera";
	for (size_t n : groups) EXPECT_GE(n, 2u);
}

TEST(MapperReal, MilkBottlesSensoryFrameFormatGivesTheSameMaps)
{
	if (!fs::exists(kMilk)) GTEST_SKIP() << "missing " << kMilk;
	// Re-package the observations-only rawlog as CActionCollection (no odometry) + CSensoryFrame.
	fs::create_directories(kTmp);
	const std::string sf = kTmp + "/milk_sf.rawlog";
	{
		mrpt::io::CFileGZInputStream fi(kMilk);
		auto in = mrpt::serialization::archiveFrom(fi);
		mrpt::io::CFileGZOutputStream fo(sf);
		auto out = mrpt::serialization::archiveFrom(fo);
		size_t n = 0;
		try
		{
			for (;;)
			{
				auto obj = in.ReadObject();
				auto obs = std::dynamic_pointer_cast<mrpt::obs::CObservation>(obj);
				if (!obs) continue;
				mrpt::obs::CActionCollection acts;
				mrpt::obs::CSensoryFrame frame;
				frame.insert(obs);
				out << acts << frame;
				n++;
			}
		}
		catch (const mrpt::serialization::CExceptionEOF&)
		{
		}
		ASSERT_GT(n, 0u);
	}
	const std::string a = freshDir("out_milk_obs"), b = freshDir("out_milk_sf");
	ASSERT_EQ(runMapper("--rawlog '" + kMilk + "' --out '" + a + "' -q").rc, 0);
	const auto r = runMapper("--rawlog '" + sf + "' --out '" + b + "' -q");
	ASSERT_EQ(r.rc, 0) << r.err;
	for (const auto& n : kGrids)
	{
		SCOPED_TRACE(n);
		EXPECT_TRUE(
			readGridmapGz(a + "/" + n + ".gridmap.gz").getRawMap() ==
			readGridmapGz(b + "/" + n + ".gridmap.gz").getRawMap());
		EXPECT_EQ(slurp(a + "/" + n + ".pgm"), slurp(b + "/" + n + ".pgm"));
	}
	EXPECT_EQ(slurp(a + "/ground_planes.csv"), slurp(b + "/ground_planes.csv"));
}

TEST_F(MapperE2E, GeneratedRunsSucceedAndOutputsParse)
{
	ASSERT_EQ(obsRun.rc, 0) << obsRun.err;
	ASSERT_EQ(sfRun.rc, 0) << sfRun.err;
	EXPECT_EQ(obsRun.err, "");  // nothing on stderr (no progress line when not a tty and short)
	EXPECT_NE(obsRun.out.find("frames: 4 "), std::string::npos) << obsRun.out;
	EXPECT_NE(sfRun.out.find("frames: 4 "), std::string::npos) << sfRun.out;
	checkOutputs(obsOut);
	checkOutputs(sfOut);
}

TEST_F(MapperE2E, BothRawlogFormatsGiveTheSameMaps)
{
	ASSERT_EQ(obsRun.rc, 0);
	ASSERT_EQ(sfRun.rc, 0);
	for (const auto& n : kGrids)
	{
		SCOPED_TRACE(n);
		const auto a = readGridmapGz(obsOut + "/" + n + ".gridmap.gz");
		const auto b = readGridmapGz(sfOut + "/" + n + ".gridmap.gz");
		ASSERT_EQ(a.getSizeX(), b.getSizeX());
		ASSERT_EQ(a.getSizeY(), b.getSizeY());
		EXPECT_FLOAT_EQ(a.getXMin(), b.getXMin());
		EXPECT_FLOAT_EQ(a.getYMin(), b.getYMin());
		EXPECT_TRUE(a.getRawMap() == b.getRawMap());
		EXPECT_EQ(slurp(obsOut + "/" + n + ".pgm"), slurp(sfOut + "/" + n + ".pgm"));
	}
	EXPECT_EQ(slurp(obsOut + "/ground_planes.csv"), slurp(sfOut + "/ground_planes.csv"));
}

TEST_F(MapperE2E, KnownCellsHaveTheExpectedState)
{
	ASSERT_EQ(obsRun.rc, 0);
	const auto ga = readGridmapGz(obsOut + "/ground_aware.gridmap.gz");
	const auto hb = readGridmapGz(obsOut + "/height_band.gridmap.gz");
	const auto oc = readGridmapGz(obsOut + "/octomap.gridmap.gz");
	const Box& b = kBoxObstacle;
	// Box: occupied in all three (its front face at x = 1.4).
	EXPECT_LT(minPFree(ga, b.x0 - 0.05, b.x0 + 0.1, b.y0 + 0.05, b.y1 - 0.05), 0.3);
	EXPECT_LT(minPFree(hb, b.x0 - 0.05, b.x0 + 0.1, b.y0 + 0.05, b.y1 - 0.05), 0.3);
	EXPECT_LT(minPFree(oc, b.x0 - 0.05, b.x0 + 0.1, b.y0 + 0.05, b.y1 - 0.05), 0.3);
	// Floor in front of the robot: free in the ground-aware grid.
	EXPECT_GT(pFree(ga, 1.02, -0.48), 0.6);
	EXPECT_GT(pFree(ga, 1.87, -0.82), 0.6);
	// Hole: occupied in the ground-aware grid, invisible to the height band.
	const Box& h = kHole;
	EXPECT_GT(fractionOccupied(ga, h.x0 + 0.05, h.x1 - 0.05, h.y0 + 0.05, h.y1 - 0.05), 0.5);
	EXPECT_DOUBLE_EQ(fractionOccupied(hb, h.x0, h.x1, h.y0, h.y1), 0.0);
	EXPECT_GE(minPFree(hb, h.x0, h.x1, h.y0, h.y1), 0.5);
}

TEST_F(MapperE2E, LocalMapModeKeepsARobotCentredWindow)
{
	const std::string out = freshDir("out_local");
	const auto r = runMapper("--rawlog '" + obsRawlog + "' --out '" + out + "' --local-map --local-size-cells 80 -q");
	ASSERT_EQ(r.rc, 0) << r.err;
	for (const auto& n : kGrids)
	{
		SCOPED_TRACE(n);
		const auto g = readGridmapGz(out + "/" + n + ".gridmap.gz");
		EXPECT_EQ(g.getSizeX(), 80u);
		EXPECT_EQ(g.getSizeY(), 80u);
		// Centred on the last robot pose (x = 0.75, y = 0) within a cell.
		EXPECT_NEAR(0.5 * (g.getXMin() + g.getXMax()), kPosesX.back(), g.getResolution());
		EXPECT_NEAR(0.5 * (g.getYMin() + g.getYMax()), 0.0, g.getResolution());
	}
	const auto ga = readGridmapGz(out + "/ground_aware.gridmap.gz");
	const auto full = readGridmapGz(obsOut + "/ground_aware.gridmap.gz");
	// Inside the window the local map equals the global one.
	EXPECT_FLOAT_EQ(pFree(ga, 1.02, -0.48), pFree(full, 1.02, -0.48));
	EXPECT_FLOAT_EQ(pFree(ga, 1.42, 0.52), pFree(full, 1.42, 0.52));
}

// --snapshot-every N: the map_server maps after every N-th frame, each equal to
// the final maps of a run stopped there (--max-frames), plus an index.
TEST_F(MapperE2E, SnapshotEveryWritesTheMapsAfterEveryNthFrame)
{
	const std::string out = freshDir("out_snap");
	const auto r = runMapper("--rawlog '" + obsRawlog + "' --out '" + out + "' --snapshot-every 2 -q");
	ASSERT_EQ(r.rc, 0) << r.err;
	EXPECT_NE(r.out.find("; 2 snapshots"), std::string::npos) << r.out;
	const std::string snaps = out + "/snapshots";
	std::set<std::string> entries;
	for (const auto& de : fs::directory_iterator(snaps)) entries.insert(de.path().filename().string());
	EXPECT_EQ(entries, (std::set<std::string>{"000002", "000004", "index.csv"}));
	for (const char* n : {"000002", "000004"})
	{
		std::set<std::string> files;
		for (const auto& de : fs::directory_iterator(snaps + "/" + n)) files.insert(de.path().filename().string());
		std::set<std::string> expect;
		for (const auto& g : kGrids) expect.insert({g + ".yaml", g + ".pgm"});
		EXPECT_EQ(files, expect) << n;
	}
	// After the last frame = the final maps; after frame 2 = the final maps of --max-frames 2.
	const std::string two = freshDir("out_max2");
	ASSERT_EQ(runMapper("--rawlog '" + obsRawlog + "' --out '" + two + "' --max-frames 2 -q").rc, 0);
	for (const auto& g : kGrids)
	{
		SCOPED_TRACE(g);
		EXPECT_EQ(slurp(snaps + "/000004/" + g + ".pgm"), slurp(out + "/" + g + ".pgm"));
		EXPECT_EQ(slurp(snaps + "/000004/" + g + ".yaml"), slurp(out + "/" + g + ".yaml"));
		EXPECT_EQ(slurp(snaps + "/000002/" + g + ".pgm"), slurp(two + "/" + g + ".pgm"));
		// The evaluator reads a snapshot like any map.
		const gam::eval::RosMap y = gam::eval::loadRosMap(snaps + "/000002/" + g + ".yaml");
		EXPECT_EQ(fs::path(y.imagePath).filename().string(), g + ".pgm");
	}
	// The robot moved between frames 2 and 4: the ground-aware grid changed.
	EXPECT_NE(slurp(snaps + "/000002/ground_aware.pgm"), slurp(snaps + "/000004/ground_aware.pgm"));
	EXPECT_EQ(
		slurp(snaps + "/index.csv"),
		"snapshot,frames,frame_index,rawlog_entry,robot_x,robot_y,robot_yaw_deg\n"
		"000002,2,1,4,0.250000,0.000000,0.000000\n"
		"000004,4,3,8,0.750000,0.000000,0.000000\n");
	// A second run replaces the snapshots as a whole.
	ASSERT_EQ(runMapper("--rawlog '" + obsRawlog + "' --out '" + out + "' --snapshot-every 3 -q").rc, 0);
	entries.clear();
	for (const auto& de : fs::directory_iterator(snaps)) entries.insert(de.path().filename().string());
	EXPECT_EQ(entries, (std::set<std::string>{"000003", "index.csv"}));
	// Without the option: no snapshots folder.
	EXPECT_FALSE(fs::exists(obsOut + "/snapshots"));
	// A negative value is a command-line error.
	const auto bad = runMapper("--rawlog '" + obsRawlog + "' --out '" + out + "_bad' --snapshot-every -1");
	EXPECT_EQ(bad.rc, 2);
	EXPECT_EQ(bad.err, "ground-aware-mapper: error: --snapshot-every must be in [0, 1000000]\n");
	EXPECT_FALSE(fs::exists(out + "_bad"));
}

TEST(MapperCli, PrintDefaultConfigIsTheConfigFile)
{
	const auto r = runMapper("--print-default-config");
	ASSERT_EQ(r.rc, 0);
	EXPECT_EQ(r.out, slurp(std::string(GAM_SOURCE_DIR) + "/config/ground-aware-mapper.ini"));
}

namespace
{
void expectError(const RunResult& r, int rc, const std::vector<std::string>& needles, const std::string& outDir)
{
	EXPECT_EQ(r.rc, rc) << r.err;
	// Exactly one line, "ground-aware-mapper: error: ...".
	EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
	EXPECT_EQ(r.err.rfind("ground-aware-mapper: error: ", 0), 0u) << r.err;
	for (const auto& n : needles) EXPECT_NE(r.err.find(n), std::string::npos) << "'" << n << "' not in: " << r.err;
	// Never a map that looks complete.
	if (!outDir.empty() && fs::exists(outDir))
		for (const auto& de : fs::directory_iterator(outDir))
		{
			const std::string f = de.path().filename().string();
			EXPECT_EQ(f.find(".yaml"), std::string::npos) << f;
			EXPECT_EQ(f.find(".pgm"), std::string::npos) << f;
			EXPECT_EQ(f.find(".gridmap.gz"), std::string::npos) << f;
		}
}

std::string withDefaultConfigEdited(const std::string& name, const std::string& from, const std::string& to)
{
	std::string ini = slurp(std::string(GAM_SOURCE_DIR) + "/config/ground-aware-mapper.ini");
	const auto p = ini.find(from);
	EXPECT_NE(p, std::string::npos) << from;
	if (p != std::string::npos) ini.replace(p, from.size(), to);
	const std::string f = kTmp + "/" + name + ".ini";
	std::ofstream(f) << ini;
	return f;
}
}  // namespace

TEST_F(MapperE2E, BadInputsGiveOneLineErrors)
{
	const std::string out = freshDir("out_bad");
	// Missing rawlog.
	expectError(runMapper("--rawlog /nonexistent/x.rawlog --out '" + out + "'"), 1, {"not found", "x.rawlog"}, out);
	// Unreadable (not a rawlog).
	{
		const std::string f = kTmp + "/garbage.rawlog";
		std::ofstream(f) << "this is not a rawlog\n";
		expectError(runMapper("--rawlog '" + f + "' --out '" + out + "'"), 1, {"cannot read rawlog"}, out);
	}
	// A rawlog with no usable observation (odometry only).
	{
		const std::string f = kTmp + "/odometry_only.rawlog";
		{
			mrpt::io::CFileGZOutputStream fo(f);
			auto ar = mrpt::serialization::archiveFrom(fo);
			for (int i = 0; i < 3; i++)
			{
				mrpt::obs::CObservationOdometry odo;
				odo.odometry = mrpt::poses::CPose2D(0.1 * i, 0, 0);
				ar << odo;
			}
		}
		expectError(runMapper("--rawlog '" + f + "' --out '" + out + "'"), 1, {"no usable observation"}, out);
	}
	// Missing config file.
	expectError(
		runMapper("--rawlog '" + obsRawlog + "' --out '" + out + "' --config /nonexistent/c.ini"), 2, {"c.ini"}, out);
	// Unknown key (a typo in groundOpts).
	expectError(
		runMapper(
			"--rawlog '" + obsRawlog + "' --out '" + out + "' --config '" +
			withDefaultConfigEdited("typo", "\nd_n=0.4", "\nd_nn=0.4") + "'"),
		2, {"unknown key 'd_nn'", "map_groundAwareGrid_00_groundOpts"}, out);
	// Out-of-range value: names the key and the range.
	expectError(
		runMapper(
			"--rawlog '" + obsRawlog + "' --out '" + out + "' --config '" +
			withDefaultConfigEdited("range", "\nK=600", "\nK=0") + "'"),
		2, {"K=0", "out of range", "1 to 1e+06"}, out);
	expectError(
		runMapper(
			"--rawlog '" + obsRawlog + "' --out '" + out + "' --config '" +
			withDefaultConfigEdited("band", "\nz_min=0.2 ", "\nz_min=200 ") + "'"),
		2, {"z_min=200", "out of range"}, out);
	// A typo in a stock sub-section of one of our maps (never read by its loader).
	expectError(
		runMapper(
			"--rawlog '" + obsRawlog + "' --out '" + out + "' --config '" +
			withDefaultConfigEdited(
				"stocktypo", "\nmaxOccupancyUpdateCertainty=0.65", "\nmaxOccupancyUpdateCertainy=0.65") +
			"'"),
		2, {"maxOccupancyUpdateCertainy", "is not used by"}, out);
	// Unknown map type.
	expectError(
		runMapper(
			"--rawlog '" + obsRawlog + "' --out '" + out + "' --config '" +
			withDefaultConfigEdited("type", "heightBandGrid_count=1", "heightBandGird_count=1") + "'"),
		2, {"unknown map type 'heightBandGird'"}, out);
	// Unknown sub-section of one of our maps.
	expectError(
		runMapper(
			"--rawlog '" + obsRawlog + "' --out '" + out + "' --config '" +
			withDefaultConfigEdited("section", "[map_octoMapGrid_00_octoOpts]", "[map_octoMapGrid_00_octoOptions]") +
			"'"),
		2, {"unknown section [map_octoMapGrid_00_octoOptions]"}, out);
	// Unwritable output directory (its parent is a file).
	{
		const std::string file = kTmp + "/a_file";
		std::ofstream(file) << "x";
		expectError(runMapper("--rawlog '" + obsRawlog + "' --out '" + file + "/sub'"), 1, {"output directory"}, "");
	}
	// Bad command line.
	expectError(runMapper("--rawlog '" + obsRawlog + "'"), 2, {"--out"}, "");
	expectError(runMapper("--no-such-option"), 2, {"no-such-option"}, "");
}

namespace
{
/** 2D-scan-only rawlog: a level 181-ray scanner 0.3 m up sees a wall at x = 2 m. */
void write2DScanRawlog(const std::string& path)
{
	mrpt::io::CFileGZOutputStream f(path);
	auto ar = mrpt::serialization::archiveFrom(f);
	for (int k = 0; k < 3; k++)
	{
		mrpt::obs::CObservationOdometry odo;
		odo.odometry = mrpt::poses::CPose2D(0.1 * k, 0, 0);
		ar << odo;
		mrpt::obs::CObservation2DRangeScan s;
		s.sensorLabel = "LIDAR";
		s.aperture = float(M_PI);
		s.rightToLeft = true;
		s.maxRange = 10;
		s.sensorPose = mrpt::poses::CPose3D(0, 0, 0.3, 0, 0, 0);
		const size_t N = 181;
		s.resizeScan(N);
		for (size_t i = 0; i < N; i++)
		{
			const double a = -M_PI / 2 + M_PI * double(i) / double(N - 1);
			const bool ok = std::abs(a) < mrpt::DEG2RAD(60.0);
			s.setScanRange(i, ok ? float((2.0 - 0.1 * k) / std::cos(a)) : 0.f);
			s.setScanRangeValidity(i, ok);
		}
		ar << s;
	}
}

/** The mapper on the 2D-scan rawlog with the .ini `iniText`, into a fresh
 * `<name>` output folder (returned in `out`), quiet. */
RunResult runLidarOnly(const std::string& name, const std::string& iniText, std::string& out)
{
	fs::create_directories(kTmp);
	const std::string rawlog = kTmp + "/" + name + ".rawlog";
	write2DScanRawlog(rawlog);
	const std::string ini = kTmp + "/" + name + ".ini";
	std::ofstream(ini) << iniText;
	out = freshDir(name);
	return runMapper("--rawlog '" + rawlog + "' --out '" + out + "' --config '" + ini + "' -q");
}
}  // namespace

TEST(MapperCli, RetiredKeysAreIgnoredWithAWarning)
{
	// An .ini written for an older version sets keys of rules that were
	// retired (doc/rules.md): it still runs, each such key named in a warning;
	// a key that never existed is still an error (BadInputsGiveOneLineErrors).
	std::string out;
	const auto r = runLidarOnly(
		"out_retired",
		"[map]\n"
		"groundAwareGrid_count=1\n"
		"[map_groundAwareGrid_00_groundOpts]\n"
		"max_drop_ray_length=2.0\n"
		"missing_floor_min_range=0.5\n"
		"max_fit_rms=0.025\n"
		"min_drop_points=2\n"
		"drop_ray_min_points=3\n",
		out);
	ASSERT_EQ(r.rc, 0) << r.err;
	for (const char* key :
		 {"max_drop_ray_length", "missing_floor_min_range", "max_fit_rms", "min_drop_points", "drop_ray_min_points"})
		EXPECT_NE(
			r.err.find(
				std::string("warning: [map_groundAwareGrid_00_groundOpts] key '") + key +
				"' was retired and is ignored"),
			std::string::npos)
			<< key << "\n"
			<< r.err;
	EXPECT_TRUE(fs::exists(out + "/groundAwareGrid_00.pgm"));

	// Retired from the ground-aware section only: elsewhere the key is the
	// error it always was (MRPT's stock sub-section never read it).
	const auto elsewhere = runLidarOnly(
		"out_retired_elsewhere",
		"[map]\n"
		"groundAwareGrid_count=1\n"
		"[map_groundAwareGrid_00_insertOpts]\n"
		"max_fit_rms=0.025\n",
		out);
	EXPECT_EQ(elsewhere.rc, 2) << elsewhere.err;
	EXPECT_NE(elsewhere.err.find("key 'max_fit_rms' is not used by"), std::string::npos) << elsewhere.err;
}

TEST(MapperCli, MapsComeFromTheIniAlone)
{
	std::string out;
	const auto r = runLidarOnly(
		"out_custom",
		"[map]\n"
		"groundAwareGrid_count=1\n"
		"occupancyGrid_count=1\n"
		"pointsMap_count=1\n"
		"[map_occupancyGrid_00_creationOpts]\n"
		"label=stock\n"
		"min_x=-5\nmax_x=5\nmin_y=-5\nmax_y=5\nresolution=0.05\n"
		"[map_occupancyGrid_00_insertOpts]\n"
		"maxDistanceInsertoin=8\n",  // a typo: stock maps get a warning
		out);
	ASSERT_EQ(r.rc, 0) << r.err;
	EXPECT_NE(
		r.err.find("ground-aware-mapper: warning: [map_occupancyGrid_00_insertOpts] key 'maxDistanceInsertoin'"),
		std::string::npos)
		<< r.err;
	EXPECT_NE(r.out.find("frames: 3 (0 3D scans, 3 2D scans)"), std::string::npos) << r.out;
	for (const std::string n : {"stock", "groundAwareGrid_00"})
		for (const char* ext : {".yaml", ".pgm", ".gridmap.gz", ".png"})
			EXPECT_TRUE(fs::exists(out + "/" + n + ext)) << n << ext;
	EXPECT_TRUE(fs::exists(out + "/pointsMap_00.map.gz"));
	for (const char* absent : {"ground_aware.yaml", "height_band.yaml", "octomap.yaml", "elevation.png"})
		EXPECT_FALSE(fs::exists(out + "/" + absent)) << absent;
	// The wall (x = 2 m in the map frame) is occupied in both grids; the space before it
	// is free in the stock grid (the ground-aware grid lets 2D scans free only floor its
	// 3D frames saw, and there are none here).
	for (const std::string n : {"stock", "groundAwareGrid_00"})
	{
		SCOPED_TRACE(n);
		const auto g = readGridmapGz(out + "/" + n + ".gridmap.gz");
		EXPECT_LT(minPFree(g, 1.95, 2.1, -0.5, 0.5), 0.3);
	}
	EXPECT_GT(pFree(readGridmapGz(out + "/stock.gridmap.gz"), 1.02, 0.03), 0.6);
}

TEST_F(MapperE2E, InitialMapStartsEveryGridThatCanFromAStockMap)
{
	// Issue #31: a stock map (a wall block far behind the robot and a free
	// patch) in both stock formats; the run's grids start from it.
	COccupancyGridMap2D stock(-8, 4, -6, 6, 0.05f);
	for (float x = -6.0f; x < -5.5f; x += 0.05f)
		for (float y = 3.0f; y < 4.0f; y += 0.05f) stock.setPos(x + 0.025f, y + 0.025f, 0.05f);
	for (float x = -4.0f; x < -3.0f; x += 0.05f)
		for (float y = -4.0f; y < -3.0f; y += 0.05f) stock.setPos(x + 0.025f, y + 0.025f, 0.95f);
	const std::string gz = kTmp + "/initial.gridmap.gz";
	writeSerializedGz(stock, gz);
	writeRosMap(stock, kTmp + "/initial.yaml", kTmp + "/initial.pgm", "initial.pgm");
	for (const std::string& file : {gz, kTmp + "/initial.yaml"})
	{
		SCOPED_TRACE(file);
		const std::string out = freshDir("out_initial");
		const auto r = runMapper("--rawlog '" + obsRawlog + "' --out '" + out + "' --initial-map '" + file + "'");
		ASSERT_EQ(r.rc, 0) << r.err;
		EXPECT_NE(r.out.find("loaded into: ground_aware, height_band; not into elevation, octomap"), std::string::npos)
			<< r.out;
		for (const std::string n : {"ground_aware", "height_band"})
		{
			SCOPED_TRACE(n);
			const auto g = readGridmapGz(out + "/" + n + ".gridmap.gz");
			EXPECT_LE(g.getXMin(), -8.0f + 1e-3f);
			EXPECT_GE(g.getYMax(), 6.0f - 1e-3f);
			EXPECT_LT(pFree(g, -5.8, 3.5), 0.1) << "the stock map's wall";
			EXPECT_GT(pFree(g, -3.5, -3.5), 0.9) << "the stock map's free patch";
			EXPECT_NEAR(pFree(g, -7.0, 0.0), 0.5, 1e-3) << "unknown in the stock map, not seen in the run";
		}
		// The run still maps: the box in front of the robot, as without the initial map.
		const auto ga = readGridmapGz(out + "/ground_aware.gridmap.gz");
		const Box& b = kBoxObstacle;
		EXPECT_LT(minPFree(ga, b.x0 - 0.05, b.x0 + 0.1, b.y0 + 0.05, b.y1 - 0.05), 0.3);
		const auto oc = readGridmapGz(out + "/octomap.gridmap.gz");
		EXPECT_NEAR(pFree(oc, -5.8, 3.5), 0.5, 1e-3) << "the octomap's projection does not start from a grid";
	}
	// Bad files: one-line errors naming the file.
	const std::string out = freshDir("out_initial_bad");
	expectError(
		runMapper("--rawlog '" + obsRawlog + "' --out '" + out + "' --initial-map /nonexistent/m.gridmap"), 2,
		{"--initial-map", "cannot open /nonexistent/m.gridmap"}, out);
	expectError(
		runMapper("--rawlog '" + obsRawlog + "' --out '" + out + "' --initial-map '" + obsRawlog + "'"), 2,
		{"--initial-map", "not an occupancy grid"}, out);
	std::ofstream(kTmp + "/bad.yaml") << "image: missing.pgm\n";
	expectError(
		runMapper("--rawlog '" + obsRawlog + "' --out '" + out + "' --initial-map '" + kTmp + "/bad.yaml'"), 2,
		{"--initial-map", "bad.yaml", "not a ROS map_server map"}, out);
}

// Issue #28: with threads = 2 the mapper inserts the two cameras' frames of
// each pose as one set, and every output is byte-identical to threads = 1:
// the maps, the planes, the snapshots (a set ends at a snapshot) and the
// local window.
TEST(MapperThreads, TwoCamerasThreads2GivesTheSameOutputsAsThreads1)
{
	fs::create_directories(kTmp);
	const std::string obs = kTmp + "/two_obs.rawlog", sf = kTmp + "/two_sf.rawlog";
	writeTwoCameraRawlogs(obs, sf);
	const std::string t2 = withDefaultConfigEdited("threads2", "\nthreads=1 ", "\nthreads=2 ");
	for (const std::string& rawlog : {obs, sf})
		for (const std::string& extra :
			 {std::string(""), std::string(" --snapshot-every 3"), std::string(" --local-map --local-size-cells 80")})
		{
			SCOPED_TRACE(rawlog + extra);
			const std::string a = freshDir("thr1"), b = freshDir("thr2");
			const auto r1 = runMapper("--rawlog '" + rawlog + "' --out '" + a + "' -q" + extra);
			const auto r2 = runMapper("--rawlog '" + rawlog + "' --out '" + b + "' -q -c '" + t2 + "'" + extra);
			ASSERT_EQ(r1.rc, 0) << r1.err;
			ASSERT_EQ(r2.rc, 0) << r2.err;
			EXPECT_NE(r1.out.find("frames: 8 (8 3D scans"), std::string::npos) << r1.out;
			EXPECT_EQ(r1.out.find("sets of depth frames"), std::string::npos) << r1.out;
			// 4 poses: 4 sets, unless the snapshot after frame 3 splits the
			// second pose's pair (frames 2 | 3) and so leaves 3.
			EXPECT_NE(
				r2.out.find(
					std::string("ground_aware: ") + (extra.find("snapshot") != std::string::npos ? "3" : "4") +
					" sets of depth frames"),
				std::string::npos)
				<< r2.out;
			size_t compared = 0;
			for (const auto& de : fs::recursive_directory_iterator(a))
			{
				if (!de.is_regular_file()) continue;
				const std::string rel = fs::relative(de.path(), a).string();
				if (rel == "timing.csv" || rel == "config_used.ini") continue;
				EXPECT_EQ(slurp(de.path().string()), slurp(b + "/" + rel)) << rel;
				compared++;
			}
			EXPECT_GE(compared, 10u);
		}
}
