// ground-aware-viewer: the batch mode (--screenshot-dir DIR --exit, CFBORender,
// no display) on a small simulated rawlog (nav_hole.scene: a 0.6 m floor
// hatch between two walls), and the GUI-free model/scene classes.
#include <gtest/gtest.h>
#include <mrpt/img/CImage.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <gam/maps/GridIO.h>

#include "ViewerScene.h"

namespace fs = std::filesystem;
using gam::viewer::View;
using gam::viewer::ViewerModel;
using gam::viewer::ViewerScene;

namespace
{
const std::string kTmp = std::string(GAM_TEST_TMP_DIR) + "/p" + std::to_string(getpid());

int run(const std::string& cmd, std::string* out = nullptr)
{
	FILE* p = popen((cmd + " 2>&1").c_str(), "r");
	if (!p) return -1;
	std::string s;
	char buf[4096];
	while (size_t n = fread(buf, 1, sizeof(buf), p)) s.append(buf, n);
	const int st = pclose(p);
	if (out) *out = s;
	return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}

struct Stats
{
	double mean = 0, variance = 0;
};
/** Grey-level mean and variance of a W x H block centred on (c, r). */
Stats blockStats(const mrpt::img::CImage& img, double c, double r, int half)
{
	Stats s;
	size_t n = 0;
	for (int y = int(r) - half; y <= int(r) + half; y++)
		for (int x = int(c) - half; x <= int(c) + half; x++)
		{
			if (x < 0 || y < 0 || x >= int(img.getWidth()) || y >= int(img.getHeight())) continue;
			const double v = img.getAsFloat(x, y) * 255.0;
			s.mean += v;
			s.variance += v * v;
			n++;
		}
	if (n)
	{
		s.mean /= double(n);
		s.variance = s.variance / double(n) - s.mean * s.mean;
	}
	return s;
}
Stats imageStats(const mrpt::img::CImage& img)
{
	return blockStats(img, img.getWidth() / 2, img.getHeight() / 2, int(std::max(img.getWidth(), img.getHeight())));
}

class Viewer : public ::testing::Test
{
   protected:
	static void SetUpTestSuite()
	{
		fs::create_directories(kTmp);
		rawlog = kTmp + "/nav.rawlog";
		std::string out;
		ASSERT_EQ(
			run(std::string(GAM_SIMULATE_EXE) + " --scene " + GAM_SOURCE_DIR + "/config/scenes/nav_hole.scene --out " +
					kTmp + "/nav --no-leddar",
				&out),
			0)
			<< out;
		shots = kTmp + "/shots";
		batchRc =
			run(std::string(GAM_VIEWER_EXE) + " " + rawlog + " --screenshot-dir " + shots +
					" --frame 10 --exit --width 640 --height 480",
				&batchOut);
		model = std::make_unique<ViewerModel>();
		model->openRawlog(rawlog);
		model->seek(10);
	}
	static void TearDownTestSuite()
	{
		model.reset();
		if (!::testing::UnitTest::GetInstance()->failed_test_count()) fs::remove_all(kTmp);
	}
	static mrpt::img::CImage load(const std::string& stem)
	{
		mrpt::img::CImage img;
		EXPECT_TRUE(img.loadFromFile(shots + "/" + stem + ".png")) << stem;
		return img;
	}
	static std::string rawlog, shots, batchOut;
	static int batchRc;
	static std::unique_ptr<ViewerModel> model;
};
std::string Viewer::rawlog, Viewer::shots, Viewer::batchOut;
int Viewer::batchRc = -1;
std::unique_ptr<ViewerModel> Viewer::model;
}  // namespace

TEST_F(Viewer, BatchModeWritesEveryViewWithoutADisplay)
{
	ASSERT_EQ(batchRc, 0) << batchOut;
	EXPECT_NE(batchOut.find("step 11 / 11"), std::string::npos) << batchOut;
	EXPECT_NE(batchOut.find("stages [ms]: projection"), std::string::npos) << batchOut;
	for (View v : gam::viewer::allViews())
	{
		const auto img = load(gam::viewer::viewName(v));
		ASSERT_EQ(img.getWidth(), 640u) << gam::viewer::viewName(v);
		ASSERT_EQ(img.getHeight(), 480u);
		const Stats s = imageStats(img);
		EXPECT_GT(s.variance, 200.0) << gam::viewer::viewName(v) << " looks blank";
	}
	std::ifstream t(shots + "/timings.txt");
	std::stringstream ss;
	ss << t.rdbuf();
	EXPECT_NE(ss.str().find("ground: ok"), std::string::npos) << ss.str();
}

TEST_F(Viewer, HoleIsDarkInTheGroundAwareViewOnly)
{
	ASSERT_EQ(batchRc, 0) << batchOut;
	const auto ga = load("grid_ground_aware"), hb = load("grid_height_band");
	double c, r;
	// the hatch: 0.6 x 0.6 m at (2.5, 0)
	ViewerScene::gridPixel(*model, 2.5, 0.0, 640, 480, c, r);
	const Stats gaHole = blockStats(ga, c, r, 4), hbHole = blockStats(hb, c, r, 4);
	EXPECT_LT(gaHole.mean, 60.0) << "hole not dark in the ground-aware view at " << c << "," << r;
	EXPECT_GT(hbHole.mean, 180.0) << "hole dark in the height-band view";
	// seen floor beside it: bright in both
	ViewerScene::gridPixel(*model, 2.5, 0.9, 640, 480, c, r);
	EXPECT_GT(blockStats(ga, c, r, 3).mean, 200.0);
	EXPECT_GT(blockStats(hb, c, r, 3).mean, 200.0);
	// the left wall (y = 1.45..1.55): a dark row in both, somewhere in y 1.3..1.7
	for (const auto* img : {&ga, &hb})
	{
		double darkest = 255;
		for (double y = 1.3; y <= 1.7; y += 0.01)
		{
			ViewerScene::gridPixel(*model, 2.5, y, 640, 480, c, r);
			darkest = std::min(darkest, blockStats(*img, c, r, 0).mean);
		}
		EXPECT_LT(darkest, 100.0) << (img == &ga ? "ground-aware" : "height-band") << " wall";
	}
}

TEST_F(Viewer, ModelMatchesTheBatchRun)
{
	EXPECT_EQ(model->stepCount(), 11u);
	EXPECT_EQ(model->current(), 10);
	EXPECT_TRUE(model->groundAware().lastFrame().detection.ok());
	EXPECT_EQ(model->framePoints().empty(), false);
	// the hatch cell is occupied in the ground-aware grid, not in the height band
	const auto& ga = model->groundAware();
	const auto& hb = model->heightBand();
	EXPECT_LT(ga.getPos(2.5, 0.0), 0.3f);
	EXPECT_GE(hb.getPos(2.5, 0.0), 0.5f);
}

TEST_F(Viewer, StatusWarnsOfAWrongDeclaredMount)
{
	// The fixture's rawlog declares the true mount: measured, no alarm.
	const std::string ok = model->statusText();
	EXPECT_NE(ok.find("mount KINECT: measured z 1.00"), std::string::npos) << ok;
	EXPECT_EQ(ok.find("MOUNT ALARM"), std::string::npos) << ok;
	// The simulated Kinect One (512x424) found by camera_model = auto; its noise
	// hides no 2 cm hazard within the map's 5 m (doc/cameras.md).
	EXPECT_NE(ok.find("camera: kinect_one, range of trust 5.00 m"), std::string::npos) << ok;
	// Declared 8 cm higher and 4 deg more pitched than it is: the alarm is on
	// after 5 disagreeing frames.
	std::string out;
	ASSERT_EQ(
		run(std::string(GAM_SIMULATE_EXE) + " --scene " + GAM_SOURCE_DIR + "/config/scenes/nav_hole.scene --out " +
				kTmp + "/wrong --no-leddar --frames 8 --declared-offset 0.08,4,0",
			&out),
		0)
		<< out;
	ViewerModel wrong;
	wrong.openRawlog(kTmp + "/wrong.rawlog");
	wrong.seek(3);
	EXPECT_EQ(wrong.statusText().find("MOUNT ALARM"), std::string::npos) << "4 frames: not yet";
	wrong.seek(7);
	const std::string st = wrong.statusText();
	EXPECT_NE(st.find("WARNING: MOUNT ALARM, KINECT"), std::string::npos) << st;
	EXPECT_NE(st.find("declared z 1.080, pitch 29.00"), std::string::npos) << st;
}

TEST_F(Viewer, ParameterChangeRerunsTheCurrentFrame)
{
	ViewerModel m;
	m.openRawlog(rawlog);
	m.seek(5);
	const size_t nodes = m.groundAware().lastFrame().detection.nodes.size();
	ASSERT_GT(nodes, 20u);
	auto o = m.groundOptions();
	o.pipeline.rrt.iterations = 20;  // K: far fewer RRT iterations
	m.applyGroundOptions(o);
	EXPECT_EQ(m.current(), 5);
	EXPECT_LT(m.groundAware().lastFrame().detection.nodes.size(), nodes);
	EXPECT_EQ(m.groundOptions().pipeline.rrt.iterations, 20);
	// back to the default: the same tree as before (the step is re-run from the snapshot)
	o.pipeline.rrt.iterations = 600;
	m.applyGroundOptions(o);
	EXPECT_EQ(m.groundAware().lastFrame().detection.nodes.size(), nodes);
	// invalid: rejected, options unchanged
	o.pipeline.rrt.normal_threshold = -1;
	EXPECT_THROW(m.applyGroundOptions(o), std::invalid_argument);
	EXPECT_DOUBLE_EQ(m.groundOptions().pipeline.rrt.normal_threshold, 0.2);
	// stepping keeps the edited options; going back re-runs from the start with them
	o = m.groundOptions();
	o.pipeline.ism.drop_rays = false;
	m.applyGroundOptions(o);
	m.seek(2);
	EXPECT_FALSE(m.groundOptions().pipeline.ism.drop_rays);
	EXPECT_EQ(m.current(), 2);
}

TEST_F(Viewer, ScenesHaveTheExpectedObjects)
{
	mrpt::opengl::COpenGLScene scene;
	mrpt::opengl::CCamera cam;
	ViewerScene::build(*model, View::Frame3D, scene, cam, 4.0 / 3.0);
	// point cloud, voxels, ground plane patch, tree edges + nodes, robot, path, floor grid
	size_t n = 0;
	for (const auto& o : *scene.getViewport()) n += o != nullptr;
	EXPECT_GE(n, 7u);
	ViewerScene::build(*model, View::Grids, scene, cam, 4.0 / 3.0);
	EXPECT_EQ(scene.getViewport()->size(), 3u);
	EXPECT_TRUE(cam.isOrthogonal());
}

TEST_F(Viewer, BadArgumentsFail)
{
	std::string out;
	EXPECT_EQ(run(std::string(GAM_VIEWER_EXE) + " --exit --screenshot-dir " + kTmp + "/x", &out), 2) << out;
	EXPECT_EQ(
		run(std::string(GAM_VIEWER_EXE) + " " + kTmp + "/missing.rawlog --exit --screenshot-dir " + kTmp + "/x", &out),
		1)
		<< out;
	EXPECT_NE(out.find("ground-aware-viewer: error:"), std::string::npos) << out;
}

TEST_F(Viewer, GuiStartsEditsAParameterAndDrawsUnderXvfb)
{
	if (run("command -v xvfb-run") != 0) GTEST_SKIP() << "xvfb-run not installed";
	const std::string png = kTmp + "/gui.png";
	std::string out;
	const int rc =
		run("xvfb-run -a -s '-screen 0 1400x900x24' " + std::string(GAM_VIEWER_EXE) + " " + rawlog +
				" --frame 5 --gui-snapshot " + png,
			&out);
	ASSERT_EQ(rc, 0) << out;
	EXPECT_NE(out.find("gui: K=100 applied"), std::string::npos) << out;
	EXPECT_NE(out.find("gui: snapshot written"), std::string::npos) << out;
	mrpt::img::CImage img;
	ASSERT_TRUE(img.loadFromFile(png));
	EXPECT_GT(img.getWidth(), 800u);
	EXPECT_GT(imageStats(img).variance, 200.0);
}

TEST_F(Viewer, StartsFromAStockMapAndSavesAsOne)
{
	// Issue #31: a stock map (a wall block behind the robot) in, the
	// ground-aware grid out as a plain COccupancyGridMap2D.
	mrpt::maps::COccupancyGridMap2D stock(-6, 6, -4, 4, 0.05f);
	for (float x = -3.0f; x < -2.5f; x += 0.05f)
		for (float y = 1.0f; y < 1.5f; y += 0.05f) stock.setPos(x + 0.025f, y + 0.025f, 0.05f);
	const std::string in = kTmp + "/stock.gridmap.gz";
	gam::maps::writeSerializedGz(stock, in);

	ViewerModel m;
	m.loadInitialMap(in);
	EXPECT_EQ(m.initialMapPath(), in);
	EXPECT_LT(m.groundAware().getPos(-2.8f, 1.2f), 0.1f);
	EXPECT_LT(m.heightBand().getPos(-2.8f, 1.2f), 0.1f);
	m.openRawlog(rawlog);
	m.seek(10);
	EXPECT_LT(m.groundAware().getPos(-2.8f, 1.2f), 0.1f) << "kept: nothing in the run sees it";
	EXPECT_LT(m.groundAware().getPos(2.5f, 0.0f), 0.3f) << "the hatch, mapped on top";
	m.loadConfig("");  // a new .ini keeps the initial map
	EXPECT_LT(m.groundAware().getPos(-2.8f, 1.2f), 0.1f);
	EXPECT_THROW(m.loadInitialMap(kTmp + "/missing.gridmap"), std::runtime_error);
	EXPECT_EQ(m.initialMapPath(), in) << "a bad file changes nothing";

	const std::string out = kTmp + "/saved.gridmap.gz";
	m.saveGroundAwareAsStockGrid(out);
	const auto back = gam::maps::readGridmapGz(out);  // as a stock tool reads it: `>> COccupancyGridMap2D`
	EXPECT_EQ(back.getRawMap(), m.groundAware().getRawMap());
	m.saveGroundAwareAsStockGrid(kTmp + "/saved.yaml");
	EXPECT_TRUE(fs::exists(kTmp + "/saved.pgm"));
	EXPECT_EQ(gam::maps::readStockGrid(kTmp + "/saved.yaml").getSizeX(), m.groundAware().getSizeX());
	m.loadInitialMap("");
	EXPECT_NEAR(m.groundAware().getPos(-2.8f, 1.2f), 0.5f, 1e-3f) << "from nothing again";
}
