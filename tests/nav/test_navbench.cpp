// Issue #29: gam-navbench, the closed-loop navigation benchmark over generated
// scenes: the fall / collision judge (the walker's footprint over ground-truth
// cells, worked out by hand), the maps it builds (the mapper's .ini, the paper
// mode as gam-ablation-ini defines it), the table format, bad arguments, and a
// 3-run smoke run of the executable.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>

#include "NavBench.h"

using gam::navbench::footprintOver;
using gam::sim::GroundTruthGrid;
using gam::sim::Label;

namespace
{
/** A 2 x 1 m floor, 5 cm cells from (0, -0.5), with a 0.5 x 0.4 m hole at
 * x 1.0-1.5, y -0.2..0.2 (0.3 m deep). */
GroundTruthGrid holeGrid()
{
	gam::sim::Scene s;
	gam::sim::ObjectInfo o;
	o.id = 7;
	o.type = "hole";
	s.objects.push_back(o);
	gam::sim::Hole h;
	h.cx = 1.25, h.cy = 0, h.hx = 0.25, h.hy = 0.2, h.depth = 0.3, h.object_id = 7;
	s.holes.push_back(h);
	gam::sim::GridSpec spec;
	spec.min_x = 0, spec.max_x = 2.0, spec.min_y = -0.5, spec.max_y = 0.5, spec.resolution = 0.05;
	GroundTruthGrid gt;
	gt.build(s, spec);
	return gt;
}

std::string readFile(const std::string& f)
{
	std::ifstream in(f);
	std::stringstream ss;
	ss << in.rdbuf();
	return ss.str();
}
}  // namespace

TEST(NavBenchJudge, FootprintOverTheHoleIsAFallNextToItIsNot)
{
	const GroundTruthGrid gt = holeGrid();
	// The hole's cells: x cells 20..29 (1.00-1.50), y cells 6..13 (-0.20..0.20):
	// the 3x3 probes of cell 19 (0.95-1.00) are at 0.958, 0.975, 0.992 < 1.0,
	// outside; those of cell 20 at 1.008.. inside. 10 x 8 = 80 drop cells.
	size_t drops = 0;
	for (const auto l : gt.geomLabel) drops += l == Label::Drop;
	ASSERT_EQ(drops, 80u);

	// Walker (half side 0.25) at (0.70, 0), heading 0: covers x 0.45-0.95.
	// The nearest drop cell's centre is 1.025: not under it -> no fall.
	auto h = footprintOver(gt, 0.70, 0.0, 0.0, 0.25);
	EXPECT_EQ(h.dropCells, 0);
	EXPECT_EQ(h.obstacleCells, 0);
	// At (0.80, 0): covers x 0.55-1.05, so the drop cells with centre x 1.025
	// (x cell 20) are under it, those with |y centre| <= 0.175 (y cells 6..13,
	// all 8 within |y| <= 0.25): 8 cells -> a fall, into object 7.
	h = footprintOver(gt, 0.80, 0.0, 0.0, 0.25);
	EXPECT_EQ(h.dropCells, 8);
	EXPECT_EQ(h.dropObject, 7);
	// Beside it: centre (1.25, 0.50) covers y 0.25-0.75; the hole's cells end at
	// y centre 0.175 -> nothing.
	h = footprintOver(gt, 1.25, 0.50, 0.0, 0.25);
	EXPECT_EQ(h.dropCells, 0);
	// Turned 45 deg at (0.75, 0): the square's corner reaches 0.75 + 0.25 * sqrt(2)
	// = 1.104 along x at y = 0; the cell centre (1.025, 0.025) is at local
	// (0.7071 * (0.275 + 0.025), 0.7071 * (0.025 - 0.275)) = (0.212, -0.177),
	// inside the half side 0.25 -> a fall; heading 0 at the same place covers
	// x up to 1.00 only: cell 20's centre 1.025 is outside -> none.
	EXPECT_GT(footprintOver(gt, 0.75, 0.0, M_PI / 4, 0.25).dropCells, 0);
	EXPECT_EQ(footprintOver(gt, 0.75, 0.0, 0.0, 0.25).dropCells, 0);
}

TEST(NavBenchJudge, FootprintOverABoxIsACollision)
{
	gam::sim::Scene s;
	gam::sim::ObjectInfo o;
	o.id = 3;
	s.objects.push_back(o);
	// a 10 cm box at x 1.0-1.1, y -0.05..0.05
	s.solids.push_back(gam::sim::ConvexSolid::box(
		gam::sim::Pose3::fromXYZYPR(1.05, 0, 0.05, 0, 0, 0), Eigen::Vector3d(0.05, 0.05, 0.05), 3));
	gam::sim::GridSpec spec;
	spec.min_x = 0, spec.max_x = 2.0, spec.min_y = -0.5, spec.max_y = 0.5;
	GroundTruthGrid gt;
	gt.build(s, spec);
	// Box cells: x cells 20, 21 (centres 1.025, 1.075), y cells 9, 10 (-0.025, 0.025).
	// At (0.80, 0) the footprint reaches x 1.05: cell 20 only, 2 cells.
	const auto h = footprintOver(gt, 0.80, 0.0, 0.0, 0.25);
	EXPECT_EQ(h.obstacleCells, 2);
	EXPECT_EQ(h.obstacleObject, 3);
	EXPECT_EQ(h.dropCells, 0);
	EXPECT_EQ(footprintOver(gt, 0.70, 0.0, 0.0, 0.25).obstacleCells, 0);
}

TEST(NavBenchTable, FormatCountsAndMedians)
{
	using gam::navbench::RunResult;
	std::vector<RunResult> runs(5);
	const char* maps[] = {"ground_aware", "ground_aware", "ground_aware", "octomap", "octomap"};
	for (size_t i = 0; i < runs.size(); i++) runs[i].map = maps[i];
	// ground_aware: two arrivals (10 s / 5 m, 20 s / 7 m) and a fall;
	// octomap: one stuck, one collision.
	runs[0].arrived = true, runs[0].seconds = 10, runs[0].pathLength = 5;
	runs[1].arrived = true, runs[1].seconds = 20, runs[1].pathLength = 7;
	runs[2].fell = true, runs[2].seconds = 3;
	runs[3].stuck = true;
	runs[4].collided = true;
	const std::string t = gam::navbench::markdownTable(runs, {"ground_aware", "octomap"});
	EXPECT_EQ(
		t,
		"| map | arrivals | falls | collisions | stuck | median time to goal [s] | median path [m] |\n"
		"|---|---|---|---|---|---|---|\n"
		"| ground_aware | 2/3 | 1 | 0 | 0 | 15.0 | 6.0 |\n"  // medians of the arrivals: (10+20)/2, (5+7)/2
		"| octomap | 0/2 | 0 | 1 | 1 | - | - |\n");
}

TEST(NavBenchMaps, TheFourMapsAreTheMappersAndPaperIsTheAblationRow)
{
	gam::sim::GridSpec ext;
	ext.min_x = -1, ext.max_x = 4, ext.min_y = -2, ext.max_y = 2;
	const char* classes[] = {
		"CGroundAwareOccupancyGrid", "CGroundAwareOccupancyGrid", "CHeightBandOccupancyGrid", "COctoMapGrid2D"};
	for (size_t i = 0; i < 4; i++)
	{
		const auto m = gam::navbench::makeMap(gam::navbench::mapNames()[i], ext);
		ASSERT_NE(m->grid, nullptr);
		EXPECT_EQ(std::string(m->grid->GetRuntimeClass()->className), std::string("mrpt::maps::") + classes[i]);
		EXPECT_NEAR(m->grid->getXMin(), -1, 0.051);
		EXPECT_NEAR(m->grid->getYMax(), 2, 0.051);
	}
	// paper = the gam-ablation-ini row "paper|k=v k=v ...", key for key
	const std::string abl = readFile(std::string(GAM_SOURCE_DIR) + "/rawlog_tools/gam-ablation-ini");
	std::smatch mt;
	ASSERT_TRUE(std::regex_search(abl, mt, std::regex("\"paper\\|([^\"]*)\"")));
	std::string expected;
	for (const auto& [k, v] : gam::navbench::paperOverrides()) expected += (expected.empty() ? "" : " ") + k + "=" + v;
	EXPECT_EQ(mt[1].str(), expected);
	// and the paper map carries them
	const auto paper = gam::navbench::makeMap("paper", ext);
	const auto* ga = dynamic_cast<const mrpt::maps::CGroundAwareOccupancyGrid*>(paper->grid);
	ASSERT_NE(ga, nullptr);
	const auto def = gam::navbench::makeMap("ground_aware", ext);
	const auto* gd = dynamic_cast<const mrpt::maps::CGroundAwareOccupancyGrid*>(def->grid);
	ASSERT_NE(gd, nullptr);
	EXPECT_EQ(ga->groundOptions().pipeline.ism.model, gam::MethodVariant::Paper);
	EXPECT_EQ(gd->groundOptions().pipeline.ism.model, gam::MethodVariant::GroundAware);
	EXPECT_THROW(gam::navbench::makeMap("lidar", ext), std::invalid_argument);
}

TEST(NavBenchArgs, SeedRangesAndMapLists)
{
	unsigned a = 0, b = 0;
	gam::navbench::parseSeedRange("1-50", a, b);
	EXPECT_EQ(a, 1u);
	EXPECT_EQ(b, 50u);
	gam::navbench::parseSeedRange("7", a, b);
	EXPECT_EQ(a, 7u);
	EXPECT_EQ(b, 7u);
	for (const char* bad : {"", "5-3", "a-b", "1-", "-3", "1-2-3", "1.5"})
		EXPECT_THROW(gam::navbench::parseSeedRange(bad, a, b), std::invalid_argument) << bad;
	EXPECT_EQ(gam::navbench::parseMapList("octomap,ground_aware").size(), 2u);
	EXPECT_THROW(gam::navbench::parseMapList("ground_aware,lidar"), std::invalid_argument);
	EXPECT_THROW(gam::navbench::parseMapList("octomap,octomap"), std::invalid_argument);
}

namespace
{
int run(const std::string& cmd, std::string& out)
{
	out.clear();
	FILE* p = popen((cmd + " 2>&1").c_str(), "r");
	if (!p) return -1;
	char buf[4096];
	while (fgets(buf, sizeof buf, p)) out += buf;
	const int st = pclose(p);
	return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}
}  // namespace

TEST(NavBenchTool, BadArgumentsGiveOneClearError)
{
	std::string out;
	const std::string exe = GAM_NAVBENCH_EXE;
	EXPECT_EQ(run(exe + " --seeds 5-3 --out /tmp/x", out), 2);
	EXPECT_NE(out.find("gam-navbench: error: bad --seeds '5-3'"), std::string::npos) << out;
	EXPECT_EQ(run(exe + " --seeds 1-2 --out /tmp/x --maps ground_aware,lidar", out), 2);
	EXPECT_NE(out.find("unknown map 'lidar'"), std::string::npos) << out;
	EXPECT_EQ(run(exe + " --out /tmp/x", out), 2);  // --seeds missing (TCLAP's message)
	EXPECT_NE(out.find("gam-navbench: error:"), std::string::npos) << out;
	EXPECT_NE(out.find("required arguments missing"), std::string::npos) << out;
	EXPECT_EQ(run(exe + " --seeds 1 --out /tmp/x --jobs 0", out), 2);
	EXPECT_NE(out.find("--jobs must be in 1..64"), std::string::npos) << out;
}

TEST(NavBenchTool, SmokeThreeRunsTableAndFiles)
{
	// seeds 1-3 with the ground-aware map only (the octomap alone would take
	// minutes): 3 runs, counted in the table and one CSV row each.
	if (!std::filesystem::exists(gam::nav::ReactiveOptions{}.baseConfig))
		GTEST_SKIP() << "mrpt-common's reactive2d_config.ini is not installed";
	const std::string dir = std::string(GAM_TEST_TMP_DIR) + "/navbench_smoke" + std::to_string(getpid());
	std::filesystem::remove_all(dir);
	std::string out;
	ASSERT_EQ(run(std::string(GAM_NAVBENCH_EXE) + " --seeds 1-3 --maps ground_aware --out " + dir, out), 0) << out;
	// one progress line per run (stderr), then the table (stdout)
	EXPECT_NE(out.find("[gam-navbench 3/3] seed "), std::string::npos) << out;
	const std::regex header(
		"\\| map \\| arrivals \\| falls \\| collisions \\| stuck \\| median time to goal \\[s\\] \\| median path "
		"\\[m\\] "
		"\\|\n\\|---\\|---\\|---\\|---\\|---\\|---\\|---\\|\n");
	EXPECT_TRUE(std::regex_search(out, header)) << out;
	std::smatch m;
	const std::regex row(
		"\\| ground_aware \\| (\\d+)/(\\d+) \\| (\\d+) \\| (\\d+) \\| (\\d+) \\| ([0-9.]+|-) \\| ([0-9.]+|-) \\|");
	ASSERT_TRUE(std::regex_search(out, m, row)) << out;
	EXPECT_EQ(m[2].str(), "3") << "3 runs counted";
	const int arrivals = std::stoi(m[1]), falls = std::stoi(m[3]), coll = std::stoi(m[4]), stuck = std::stoi(m[5]);
	EXPECT_LE(arrivals + falls + coll + stuck, 3);
	// the files: the same table, a CSV with a header and 3 rows, the figure
	EXPECT_NE(out.find(readFile(dir + "/table.md")), std::string::npos);
	const std::string csv = readFile(dir + "/runs.csv");
	EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 4) << csv;
	EXPECT_EQ(csv.rfind(gam::navbench::csvHeader(), 0), 0u);
	EXPECT_GT(std::filesystem::file_size(dir + "/trajectories.png"), 1000u);
	std::filesystem::remove_all(dir);
}
