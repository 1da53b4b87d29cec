// ground-aware-mapper --png-legend (issue #16): the grids' PNGs get a 1 m scale
// bar and a legend, and a ground-aware grid's missing floor is drawn orange.
// Run on an exact synthetic frame of a floor with a pit painted black (its
// rays return nothing: missing floor, doc/maps/CGroundAwareOccupancyGrid.md).
#include <gtest/gtest.h>
#include <mrpt/img/CImage.h>
#include <mrpt/obs/CRawlog.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include "../maps/synthetic_scene.h"

namespace fs = std::filesystem;

namespace
{
const std::string kExe = GAM_MAPPER_EXE;
const std::string kTmp = std::string(GAM_TEST_TMP_DIR) + "/legend" + std::to_string(getpid());

/** One frame of a Kinect One 0.8 m up, pitched 25 deg, over a floor with a
 * 0.4 x 0.6 m pit at x 2.5-2.9 whose rays return nothing. */
std::string darkHoleRawlog()
{
	const mrpt::poses::CPose3D kinect(0.1, 0, 0.8, 0, mrpt::DEG2RAD(25.0), 0);
	auto o = testscene::renderDepth(testscene::floorWithHole(-1, 8, -4, 4, 2.5, 2.9, -0.3, 0.3, 0.3), kinect);
	testscene::blackOut(*o, 2.5, 2.9, -0.3, 0.3);
	mrpt::obs::CRawlog log;
	log.insert(o);
	fs::create_directories(kTmp);
	const std::string path = kTmp + "/dark_hole.rawlog";
	EXPECT_TRUE(log.saveToRawLogFile(path));
	return path;
}

int run(const std::string& args)
{
	fs::create_directories(kTmp);
	const std::string cmd = "'" + kExe + "' " + args + " >/dev/null 2>&1 </dev/null";
	const int st = std::system(cmd.c_str());
	return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}

mrpt::img::CImage load(const std::string& path)
{
	mrpt::img::CImage im;
	EXPECT_TRUE(im.loadFromFile(path)) << path;
	return im;
}

bool isColour(const mrpt::img::CImage& im, int x, int y, int r, int g, int b)
{
	const uint8_t* p = im(x, y);  // BGR
	return p[2] == r && p[1] == g && p[0] == b;
}

size_t countColour(const mrpt::img::CImage& im, int rows, int r, int g, int b)
{
	size_t n = 0;
	for (int y = 0; y < rows; y++)
		for (int x = 0; x < int(im.getWidth()); x++) n += isColour(im, x, y, r, g, b);
	return n;
}

/** Missing-floor cells of a map_server PGM (value 0). */
size_t missingCells(const std::string& pgm)
{
	std::ifstream f(pgm, std::ios::binary);
	std::string magic;
	int v[3] = {0, 0, 0};
	f >> magic;
	for (int& x : v)
	{
		while (f >> std::ws && f.peek() == '#') f.ignore(1 << 20, '\n');  // comment lines
		f >> x;
	}
	f.get();
	const int w = v[0], h = v[1];
	size_t n = 0;
	for (int i = 0; i < w * h; i++) n += f.get() == 0;
	return n;
}
}  // namespace

TEST(MapperPngLegend, ScaleBarLegendAndMissingFloorInOrange)
{
	const std::string kRawlog = darkHoleRawlog();
	const std::string plain = kTmp + "/plain", legend = kTmp + "/legend";
	fs::remove_all(plain);
	fs::remove_all(legend);
	ASSERT_EQ(run("--rawlog '" + kRawlog + "' --out '" + plain + "' -q"), 0);
	ASSERT_EQ(run("--rawlog '" + kRawlog + "' --out '" + legend + "' -q --png-legend"), 0);

	// The map_server files are the same; only the pictures change.
	std::ifstream a(plain + "/ground_aware.pgm", std::ios::binary), b(legend + "/ground_aware.pgm", std::ios::binary);
	EXPECT_TRUE(std::equal(
		std::istreambuf_iterator<char>(a), std::istreambuf_iterator<char>(), std::istreambuf_iterator<char>(b)));

	const auto p = load(plain + "/ground_aware.png");
	const auto l = load(legend + "/ground_aware.png");
	// A 40 px strip below the map, at least 430 px wide for the legend.
	EXPECT_EQ(l.getHeight(), p.getHeight() + 40);
	EXPECT_EQ(l.getWidth(), std::max<size_t>(p.getWidth(), 430));
	const int y0 = int(p.getHeight());
	// The scale bar: blue (0, 90, 200) from x = 6, 4-7 px into the strip.
	EXPECT_TRUE(isColour(l, 7, y0 + 5, 0, 90, 200));
	// The legend's first swatch (free: white) at (6..18, y0 + 22..34), with a grey frame.
	EXPECT_TRUE(isColour(l, 12, y0 + 28, 255, 255, 255));
	EXPECT_TRUE(isColour(l, 6, y0 + 28, 120, 120, 120));

	// Missing floor: orange in the legend picture of the map (as many cells as the
	// layer has, times the scale squared), never in the plain one.
	const size_t cells = missingCells(legend + "/ground_aware_missing_floor.pgm");
	ASSERT_GT(cells, 30u) << "the black pit: about 8 x 12 cells";
	const size_t orange = countColour(l, y0, 255, 140, 0);
	EXPECT_EQ(countColour(p, int(p.getHeight()), 255, 140, 0), 0u);
	EXPECT_GT(orange, 0u);
	EXPECT_EQ(orange % cells, 0u) << "whole cells: " << orange << " px for " << cells << " cells";
	// The comparison maps get the strip but have no missing floor.
	const auto hb = load(legend + "/height_band.png");
	EXPECT_EQ(countColour(hb, int(hb.getHeight()) - 40, 255, 140, 0), 0u);
}
