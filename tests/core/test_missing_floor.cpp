// Missing floor (issue #13): a camera 1 m above the floor looking straight
// down, so every pixel's floor point and the expected depth (1 m) are known by
// hand, and each 5 cm cell of the grid receives exactly 4 x 4 pixels.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <vector>

#include "gam/core/MissingFloor.h"
#include "test_helpers.h"

using namespace gam;

namespace
{
// 40 x 40 pixels, fx = fy = 80, principal point at the image centre. Looking
// down from h = 1 m, pixel (r, c) meets the floor at
//   x = h (cy - r) / fy = (19.5 - r) / 80,  y = (19.5 - c) / 80,
// so a pixel covers 12.5 mm and 4 x 4 pixels fill one 5 cm cell. The grid
// starts at -0.5, so cell index = floor((x + 0.5) / 0.05): rows 0-3 give x in
// [0.20625, 0.24375] (cell 14), rows 4-7 cell 13, ..., rows 16-19 (x 0.04375
// .. 0.00625) cell 10, rows 20-23 (x -0.00625 .. -0.04375) cell 9; the same
// for columns and y.
constexpr int kSize = 40;
constexpr double kH = 1.0;

struct Scene
{
	std::vector<uint16_t> depth = std::vector<uint16_t>(kSize * kSize, 1000);  // 1 m in mm: floor
	uint16_t& at(int r, int c) { return depth[size_t(r) * kSize + size_t(c)]; }
};

/** The floor with columns [from, to) returning nothing in every row. */
Scene emptyColumns(int from, int to)
{
	Scene s;
	for (int r = 0; r < kSize; r++)
		for (int c = from; c < to; c++) s.at(r, c) = 0;
	return s;
}

/** The 8 x 8 pixel hole of DarkHoleInSeenFloorIsMarked (rows 16-23,
 * columns 24-31: x cells 9-10, y cells 7-8), each pixel set to `value` (0: no
 * return). */
void addDarkHole(Scene& s, uint16_t value = 0)
{
	for (int r = 16; r < 24; r++)
		for (int c = 24; c < 32; c++) s.at(r, c) = value;
}

struct Result
{
	MissingFloorDetector det;
	MissingFloorStats stats;
	ElevationGrid grid;
};

/** A depth frame of `depth` (mm, K.width x K.height) from a camera `height`
 * above the floor at the map's origin, rotated by R (sensor to map); max
 * range 4.5 m. The frame views `depth`, which must outlive it. */
SensorFrame depthFrame(
	const std::vector<uint16_t>& depth, const PinholeIntrinsics& K, const Eigen::Matrix3d& R, double height)
{
	SensorFrame frame;
	frame.has_image = true;
	frame.image.data = depth.data();
	frame.image.rows = K.height;
	frame.image.cols = K.width;
	frame.image.stride = K.width;
	frame.image.units = 0.001f;
	frame.image.is_depth = true;
	frame.intrinsics = K;
	frame.sensor_to_map.R = R.cast<float>();
	frame.sensor_to_map.t = Eigen::Vector3f(0, 0, float(height));
	frame.sensor_position = Eigen::Vector3d(0, 0, height);
	frame.max_range = 4.5f;
	return frame;
}

/** Projects `frame` into `grid` (resized to `g`) with the 3-sigma filter and
 * returns the ISM's classes as the tests take them: Ground wherever a cell
 * has samples, None elsewhere. */
std::vector<VoxelClass> seenFloorClasses(
	const SensorFrame& frame, const GridGeometry& g, ElevationGrid& grid, DepthProjector& proj)
{
	grid.resize(g);
	BinnedPoints bins;
	ProjectionFilter f;
	f.max_range = 4.5f;
	proj.project(frame.image, frame.intrinsics, frame.sensor_to_map, f, grid, bins);
	grid.insert(bins, OutlierFilterParams{});
	std::vector<VoxelClass> classes(g.cellCount(), VoxelClass::None);
	for (size_t i = 0; i < g.cellCount(); i++)
		if (grid.cell(i).count) classes[i] = VoxelClass::Ground;
	return classes;
}

/** Runs the projector, the 2.5D map, hand-made classes (every cell with
 * samples is Ground) and the detector (range maxRange) on `values`: depths,
 * or ranges along the rays (MRPT's range_is_depth = false) if !isDepth, from
 * a 40 x 40 camera 1 m above the floor looking straight down. The grid is 20
 * x 20 cells from (-0.5, -0.5): the image sees only its middle 10 x 10 cells. */
void runCamera(
	const std::vector<uint16_t>& values, bool isDepth, double maxRange, Result& out, const MissingFloorParams& p,
	double baseline = 0, const PatchSupport& patches = {})
{
	PinholeIntrinsics K;
	K.width = K.height = kSize;
	K.fx = K.fy = 80;
	K.cx = K.cy = 19.5;
	// Pitch 90 deg (nose down): sensor +X -> world -Z, +Y -> +Y, +Z -> +X.
	const Eigen::Matrix3d R = Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitY()).toRotationMatrix();
	SensorFrame frame = depthFrame(values, K, R, kH);
	frame.image.is_depth = isDepth;

	GridGeometry g;
	g.x_min = g.y_min = -0.5;
	g.resolution = 0.05;
	g.nx = g.ny = 20;
	DepthProjector proj;
	const std::vector<VoxelClass> classes = seenFloorClasses(frame, g, out.grid, proj);

	out.det.setParams(p);
	out.det.setSecondImagerBaseline(baseline);
	out.det.compute(frame, proj, 1, maxRange, Plane{} /* z = 0 */, out.grid, classes, out.stats, patches);
}

/** runCamera() on the depth image `scene`, range 4.5 m, every row a
 * statistics row (for the hand counts below). */
void run(
	const Scene& scene, Result& out, MissingFloorParams p = {}, double baseline = 0, const PatchSupport& patches = {})
{
	p.stats_row_step = 1;
	runCamera(scene.depth, true, 4.5, out, p, baseline, patches);
}

uint32_t cellOf(int ix, int iy) { return uint32_t(iy * 20 + ix); }

/** With the hole of addDarkHole() cut into `scene`, run() still finds it:
 * its 64 empty pixels, its 4 cells (x 9-10, y 7-8) missing floor, whatever
 * else the scene leaves out of the evidence. */
void expectTheDarkHoleFound(Scene scene, double baseline = 0)
{
	addDarkHole(scene);
	Result hole;
	run(scene, hole, {}, baseline);
	EXPECT_EQ(hole.stats.empty_rays, 64u);
	EXPECT_EQ(hole.stats.cells, 4u);
	EXPECT_TRUE(hole.det.isMissing(cellOf(9, 7)));
	EXPECT_TRUE(hole.det.isMissing(cellOf(10, 8)));
}

/** The floor as run()'s camera sees it in a range image (MRPT's
 * range_is_depth = false: each pixel the distance along its ray, in mm): the
 * ray (1, a, b) of pixel (r, c), a = (19.5 - r) / 80 and b = (19.5 - c) / 80,
 * meets the floor 1 m down at depth 1 m and range sqrt(1 + a^2 + b^2) m. */
std::vector<uint16_t> floorRanges()
{
	std::vector<uint16_t> range(size_t(kSize * kSize));
	for (int r = 0; r < kSize; r++)
		for (int c = 0; c < kSize; c++)
		{
			const double a = (19.5 - r) / 80, b = (19.5 - c) / 80;
			range[size_t(r * kSize + c)] = uint16_t(std::lround(1000 * std::sqrt(1 + a * a + b * b)));
		}
	return range;
}
}  // namespace

TEST(MissingFloor, EmptyCellChance)
{
	// Independent dropouts (p11 = q, or unknown: -1): floor that drops 4 % of
	// its rays leaves 16 rays all empty with 0.04^16.
	EXPECT_NEAR(missing::emptyCellChance(0.04, -1, 16), std::pow(0.04, 16), 1e-30);
	EXPECT_DOUBLE_EQ(missing::emptyCellChance(0.5, 0.5, 3), 0.125);
	EXPECT_DOUBLE_EQ(missing::emptyCellChance(1.0, -1, 50), 1.0);  // all floor drops: no evidence
	EXPECT_DOUBLE_EQ(missing::emptyCellChance(0.3, -1, 0), 1.0);
	// Blocky dropouts: 4 % of the rays empty, but 9 in 10 neighbours of an
	// empty ray empty too: 0.04 * 0.9^15 = 0.04 * 0.205891 = 0.0082356.
	EXPECT_NEAR(missing::emptyCellChance(0.04, 0.9, 16), 0.04 * std::pow(0.9, 15), 1e-12);
	EXPECT_NEAR(missing::emptyCellChance(0.04, 0.9, 16), 0.0082356, 1e-6);
	// Anti-correlated (p11 < q) is not trusted: q^n.
	EXPECT_DOUBLE_EQ(missing::emptyCellChance(0.5, 0.1, 3), 0.125);
}

TEST(MissingFloor, DarkHoleInSeenFloorIsMarked)
{
	// An 8 x 8 pixel hole returning nothing: rows 16-23, cols 24-31, i.e.
	// x cells 10 (rows 16-19) and 9 (rows 20-23); y = (19.5 - c) / 80 is
	// -0.05625 .. -0.09375 for cols 24-27 (floor(8.875) .. floor(8.125) = 8)
	// and -0.10625 .. -0.14375 for cols 28-31 (7).
	Scene s;
	addDarkHole(s);
	Result res;
	MissingFloorParams p;
	// The hole's cells are at 2D distances sqrt(0.025^2 + 0.075^2) = 0.079 m
	// (y cell 8, centre -0.075) and sqrt(0.025^2 + 0.125^2) = 0.127 m (y cell
	// 7, centre -0.125) from the sensor: a 0.1 m block range keeps the first two.
	p.block_range = 0.1;
	run(s, res, p);
	// Every one of the 1600 rays meets the floor at depth 1 m; 64 are empty.
	EXPECT_EQ(res.stats.rays, 1600u);
	EXPECT_EQ(res.stats.empty_rays, 64u);
	// No empty ray lies on seen floor: the floor's dropout rate is 0, and
	// there are no neighbour statistics (independent).
	EXPECT_EQ(res.det.dropoutRate(1.0), 0.0);
	EXPECT_EQ(res.det.neighbourDropoutRate(), -1);
	// Each hole cell: 16 empty rays, 0^16 = 0 <= alpha = 1e-3.
	for (int ix : {9, 10})
		for (int iy : {7, 8})
		{
			EXPECT_EQ(res.det.emptyRays(cellOf(ix, iy)), 16) << ix << "," << iy;
			EXPECT_TRUE(res.det.isMissing(cellOf(ix, iy))) << ix << "," << iy;
		}
	EXPECT_EQ(res.stats.cells, 4u);
	EXPECT_EQ(res.stats.regions, 1u);
	EXPECT_EQ(res.stats.blocking, 2u);
	for (uint32_t c : res.det.blockingCells()) EXPECT_EQ(int(c / 20), 8);
	// The floor around it is not missing.
	EXPECT_FALSE(res.det.isMissing(cellOf(11, 8)));
	EXPECT_FALSE(res.det.isMissing(cellOf(9, 9)));
}

TEST(MissingFloor, NoMissingFloorWhereARampPatchApplies)
{
	// The hole of DarkHoleInSeenFloorIsMarked (cells x 9-10, y 7-8), with a
	// ramp patch applying on blocks of 4 x 4 cells: block (bx, by) = (x / 4,
	// y / 4) holds cells x 8-11, y 4-7 for (2, 1), index by * 5 + bx = 7 in
	// a table 5 blocks wide. It covers the hole's y = 7 cells; the y = 8
	// cells lie in block (2, 2), which no patch covers.
	Scene s;
	addDarkHole(s);
	std::vector<uint8_t> blocks(25, 0);
	blocks[7] = 1;
	const PatchSupport patches{blocks.data(), blocks.size(), 4, 5, 20};
	ASSERT_TRUE(patches.applies(cellOf(9, 7)));
	ASSERT_FALSE(patches.applies(cellOf(9, 8)));
	Result res;
	MissingFloorParams p;
	p.block_range = 0.1;
	run(s, res, p, 0, patches);
	// Still one bordered region of 4 candidate cells; the 2 under the patch
	// are left out, the other 2 (0.079 m from the sensor) are missing and block.
	EXPECT_EQ(res.stats.regions, 1u);
	EXPECT_EQ(res.stats.under_patches, 2u);
	EXPECT_EQ(res.stats.cells, 2u);
	EXPECT_EQ(res.stats.blocking, 2u);
	for (int ix : {9, 10})
	{
		EXPECT_FALSE(res.det.isMissing(cellOf(ix, 7))) << ix;
		EXPECT_FALSE(res.det.isBlocking(cellOf(ix, 7))) << ix;
		EXPECT_TRUE(res.det.isMissing(cellOf(ix, 8))) << ix;
		EXPECT_TRUE(res.det.isBlocking(cellOf(ix, 8))) << ix;
	}
	for (uint32_t c : res.det.cells()) EXPECT_EQ(int(c / 20), 8);
}

TEST(MissingFloor, OutsideTheFieldOfViewIsNotMarked)
{
	// The image covers x, y in [-0.25, 0.25]: grid cells 5-14. The 20 x 20
	// grid's outer ring (e.g. cell (0, 0) at -0.475, -0.475) gets no ray at all,
	// so nothing can be said there, even with a dark hole inside the view.
	Scene s;
	addDarkHole(s);
	Result res;
	run(s, res);
	for (int ix = 0; ix < 20; ix++)
		for (int iy = 0; iy < 20; iy++)
		{
			const bool inView = ix >= 5 && ix <= 14 && iy >= 5 && iy <= 14;
			if (inView) continue;
			EXPECT_EQ(res.det.emptyRays(cellOf(ix, iy)), 0) << ix << "," << iy;
			EXPECT_FALSE(res.det.isMissing(cellOf(ix, iy))) << ix << "," << iy;
		}
}

TEST(MissingFloor, FloorThatDropsOutOftenIsNotAHole)
{
	// A shiny floor: 9 of every 10 pixels return nothing (index % 10 != 0:
	// with 40 columns only columns 0, 10, 20 and 30 return), and the cell of
	// rows 0-3, cols 0-3 (x and y cell 14) returns nothing at all. Many cells
	// (e.g. cols 4-7) get no return either: dropouts, not holes. Columns
	// 31-39 return nothing in any row: a dead band at the image's right
	// border (missing::deadBorderColumns), whose 9 x 40 = 360 pixels are no
	// rays.
	Scene s;
	for (int i = 0; i < kSize * kSize; i++)
		if (i % 10 != 0) s.depth[size_t(i)] = 0;
	for (int r = 0; r < 4; r++)
		for (int c = 0; c < 4; c++) s.at(r, c) = 0;
	Result res;
	run(s, res);
	EXPECT_EQ(res.stats.dead_border_columns, 9u);
	// Valid pixels: i % 10 == 0 gives 160, minus those in rows 0-3, cols 0-3
	// (i = 0, 40, 80, 120: 4 of them) = 156; empty = 1600 - 156 - 360 = 1084.
	EXPECT_EQ(res.stats.empty_rays, 1084u);
	// Seen cells: y cells 12 (cols 8-11) and 9 (cols 20-23) in all 40 rows,
	// 7 (cols 28-30 now: 31 is dead) in all rows and 14 (cols 0-3) in rows
	// 4-39: 2 * 40 * 4 + 40 * 3 + 36 * 4 = 584 rays, 156 valid: q = 428 / 584
	// = 0.73288.
	const double q = 428.0 / 584.0;
	EXPECT_NEAR(res.det.dropoutRate(1.0), q, 1e-12);
	// 0.733^16 = 0.0069 (more with p11 > q): such floor leaves cells empty.
	EXPECT_GT(missing::emptyCellChance(q, -1, 16), 1e-3);
	EXPECT_EQ(res.det.emptyRays(cellOf(14, 14)), 16);
	EXPECT_FALSE(res.det.isMissing(cellOf(14, 14)));
	EXPECT_EQ(res.det.emptyRays(cellOf(12, 13)), 16);  // cols 4-7 (y cell 13): all empty
	EXPECT_FALSE(res.det.isMissing(cellOf(12, 13)));
	EXPECT_EQ(res.stats.cells, 0u);
}

TEST(MissingFloor, BlockyDropoutsOnSeenFloorAreNotAHole)
{
	// A structured-light camera loses whole blocks: rows 8-15 lose columns
	// 1-14. Rows 8-11 are x cell 12 and rows 12-15 x cell 11; the y index is
	// floor(10 + (19.5 - c) / 4): cols 0-3 -> 14, 4-7 -> 13, 8-11 -> 12,
	// 12-15 -> 11. So cells (11..12, 12..13) are entirely empty, while y cells
	// 14 (col 0 returns) and 11 (col 15 returns) are seen floor with empty
	// rays. Pairs of neighbours on seen floor, per row: (1,2), (2,3), (12,13),
	// (13,14) both empty, (14,15) empty then valid ((3,4) and (11,12) touch an
	// unseen cell): p11 = 4 / 5 = 0.8. Every cell but the 4 empty ones is
	// seen: 1600 - 4 * 16 = 1536 rays, 112 - 64 = 48 of them empty:
	// q = 48 / 1536 = 0.03125. A fully empty cell: 0.03125 * 0.8^15 =
	// 0.03125 * 0.0351844 = 0.0010995 > alpha = 1e-3: blocky dropouts, not a
	// hole (with independent dropouts it would be: 0.03125^16 = 8.7e-25).
	Scene s;
	for (int r = 8; r < 16; r++)
		for (int c = 1; c < 15; c++) s.at(r, c) = 0;
	Result res;
	run(s, res);
	EXPECT_EQ(res.stats.empty_rays, 112u);
	EXPECT_DOUBLE_EQ(res.det.neighbourDropoutRate(), 0.8);
	EXPECT_NEAR(res.det.dropoutRate(1.0), 0.03125, 1e-12);
	EXPECT_NEAR(missing::emptyCellChance(0.03125, 0.8, 16), 0.0010995, 1e-7);
	for (int ix : {11, 12})
		for (int iy : {12, 13})
		{
			EXPECT_EQ(res.det.emptyRays(cellOf(ix, iy)), 16) << ix << "," << iy;
			EXPECT_FALSE(res.det.isMissing(cellOf(ix, iy))) << ix << "," << iy;
		}
	EXPECT_EQ(res.stats.cells, 0u);
	// The same empty block with independent dropouts would be a hole:
	EXPECT_LT(missing::emptyCellChance(0.03125, -1, 16), 1e-3);
}

TEST(MissingFloor, ReturnsFarBelowTheFloorCountAsNoFloor)
{
	// A hole deeper than the range: the camera returns 6 m where the floor is
	// at 1 m (beyond the 4.5 m range and more than the 0.10 m margin below the
	// floor) -> empty rays: rows 16-23 and cols 24-31 are x cells 9, 10 and
	// y cells 7, 8 (as the dark hole above).
	Scene s;
	addDarkHole(s, 6000);
	Result res;
	run(s, res);
	EXPECT_EQ(res.stats.empty_rays, 64u);
	EXPECT_EQ(res.stats.cells, 4u);
	EXPECT_TRUE(res.det.isMissing(cellOf(9, 7)));
	EXPECT_TRUE(res.det.isMissing(cellOf(10, 8)));
}

TEST(MissingFloor, WhereTheReturnsStopIsNotAHole)
{
	// Rows 0-7 return nothing: x cells 13 and 14, the far edge of the view
	// (as a range cutoff, or an image border the camera does not fill). Floor
	// is seen nearer (x cell 12) but nothing beyond: not a gap in the floor.
	// (The seen floor drops nothing, q = 0: its cells pass the cell test.)
	Scene s;
	for (int r = 0; r < 8; r++)
		for (int c = 0; c < kSize; c++) s.at(r, c) = 0;
	Result res;
	run(s, res);
	EXPECT_EQ(res.stats.empty_rays, 320u);
	EXPECT_GT(res.stats.candidates, 0u);
	EXPECT_EQ(res.stats.cells, 0u);
	EXPECT_EQ(res.stats.unbordered, 1u);
	EXPECT_FALSE(res.det.isMissing(cellOf(14, 10)));
}

TEST(MissingFloor, NoSeenFloorAroundMeansNoRegion)
{
	// Everything returns nothing: no cell has samples, no cell is Ground.
	// Every column is dead (no return in any row): no ray at all, and the
	// dropout rate is 1 (no evidence): nothing is marked.
	Scene s;
	std::fill(s.depth.begin(), s.depth.end(), 0);
	Result res;
	run(s, res);
	EXPECT_EQ(res.stats.dead_border_columns, 40u);
	EXPECT_EQ(res.stats.rays, 0u);
	EXPECT_EQ(res.stats.empty_rays, 0u);
	EXPECT_DOUBLE_EQ(res.det.dropoutRate(1.0), 1.0);
	EXPECT_EQ(res.stats.cells, 0u);
}

TEST(MissingFloor, ParametersAreValidated)
{
	MissingFloorParams p;
	p.min_rays = 0;
	EXPECT_THROW(MissingFloorDetector{p}, std::invalid_argument);
	p = {};
	p.alpha = 2;
	EXPECT_THROW(MissingFloorDetector{p}, std::invalid_argument);
	p = {};
	p.range_bin = 0;
	EXPECT_THROW(MissingFloorDetector{p}, std::invalid_argument);
}

TEST(MissingFloor, OutsideTheSecondImager)
{
	// A D435-like camera: fx = 640 px, baseline 0.05 m, fx b = 32 px m. Floor
	// at 2 m has a disparity of 32 / 2 = 16 px: column c lands at c - 16 in
	// the second image, outside it for c - 16 <= -0.5 (lround < 0): c <= 15.
	EXPECT_TRUE(missing::outsideSecondImager(0, 2.0, 32.0));
	EXPECT_TRUE(missing::outsideSecondImager(15, 2.0, 32.0));
	EXPECT_FALSE(missing::outsideSecondImager(16, 2.0, 32.0));
	// Nearer floor, a wider band: at 1 m, 32 px (c <= 31); at 4 m, 8 px.
	EXPECT_TRUE(missing::outsideSecondImager(31, 1.0, 32.0));
	EXPECT_FALSE(missing::outsideSecondImager(32, 1.0, 32.0));
	EXPECT_TRUE(missing::outsideSecondImager(7, 4.0, 32.0));
	EXPECT_FALSE(missing::outsideSecondImager(8, 4.0, 32.0));
	// The tie: d = 28 / 8 = 3.5 px, c - d = 3 - 3.5 = -0.5 rounds to -1
	// (std::lround: half away from zero): outside; c = 4 gives 0.5 -> 1.
	EXPECT_TRUE(missing::outsideSecondImager(3, 8.0, 28.0));
	EXPECT_FALSE(missing::outsideSecondImager(4, 8.0, 28.0));
	EXPECT_FALSE(missing::outsideSecondImager(16, 0.0, 32.0));  // no depth: no claim
	EXPECT_FALSE(missing::outsideSecondImager(0, 2.0, 0.0));    // time of flight: no band
}

TEST(MissingFloor, TheStereoInvalidBandIsNoEvidence)
{
	// fx = 80, baseline 0.05 m: fx b = 4 px m; the floor (1 m) has a
	// disparity of 4 px, so columns 0-3 (c - 4 <= -1) are outside the second
	// imager: a stereo camera returns nothing there. Their 40 x 4 = 160
	// pixels fill the 10 cells of y cell 14 ((19.5 - c) / 80 = 0.244 ..
	// 0.206), 16 rays each.
	// One pixel of the band, (39, 0), returns the floor: the band is no dead
	// band (missing::deadBorderColumns), its other 159 pixels are judged.
	// That pixel meets the floor at x = (19.5 - 39) / 80 = -0.244 (x cell 5),
	// y cell 14: that cell is seen, the band's 9 others (x cells 6-14) are not.
	Scene s = emptyColumns(0, 4);
	s.at(39, 0) = 1000;

	// Read as a time-of-flight camera: 159 empty rays, 9 candidate cells (16
	// empty rays each; none missing: at the edge of the view, no floor beyond
	// them). The seen floor's dropout rate: 15 empty of the 1600 - 9 x 16 =
	// 1456 rays into seen cells.
	Result tof;
	run(s, tof);
	EXPECT_EQ(tof.stats.dead_border_columns, 0u);
	EXPECT_EQ(tof.stats.rays, 1600u);
	EXPECT_EQ(tof.stats.empty_rays, 159u);
	EXPECT_NEAR(tof.det.dropoutRate(1.0), 15.0 / 1456.0, 1e-12);
	EXPECT_EQ(tof.stats.candidates, 9u);

	// With the baseline the 159 empty pixels are no rays at all: 1600 - 159
	// = 1441 (the pixel that returned is one).
	Result stereo;
	run(s, stereo, {}, 0.05);
	EXPECT_EQ(stereo.stats.rays, 1441u);
	EXPECT_EQ(stereo.stats.empty_rays, 0u);
	EXPECT_EQ(stereo.stats.candidates, 0u);

	// A dark hole the second imager does see (rows 16-23, columns 24-31: the
	// hole of DarkHoleInSeenFloorIsMarked) is still a hole: its 4 cells.
	expectTheDarkHoleFound(s, 0.05);
}

TEST(MissingFloor, ADeadBandAtTheImagesBorderIsNoEvidence)
{
	// A depth image registered to a colour camera: columns 36-39 return
	// nothing in any row (the depth camera does not see that far right).
	// Those 4 x 40 = 160 pixels fill the 10 cells of y cell 5 ((19.5 - c) /
	// 80 = -0.206 .. -0.244), 16 rays each, beside seen floor: read as rays,
	// they would be 10 candidates. A dead band is no ray at all.
	Scene s = emptyColumns(36, 40);
	Result dead;
	run(s, dead);
	EXPECT_EQ(dead.stats.dead_border_columns, 4u);
	EXPECT_EQ(dead.stats.rays, 1440u);
	EXPECT_EQ(dead.stats.empty_rays, 0u);
	EXPECT_EQ(dead.stats.candidates, 0u);

	// A dark hole inside the live columns (rows 16-23, columns 24-31: the
	// hole of DarkHoleInSeenFloorIsMarked) is still a hole: its 4 cells.
	expectTheDarkHoleFound(s);

	// A band with one return (row 20, column 39: x cell 9, y cell 5) is not
	// dead: its other 159 pixels are rays again. That return makes cell (9, 5)
	// seen floor with 15 empty rays of 16: q = 15 / (1600 - 9 x 16) = 15 /
	// 1456, and along its rows 20-23 an empty pixel is followed by another in
	// 11 of 12 pairs (36-37, 37-38 both empty in row 20, 38-39 not; all three
	// in rows 21-23): p11 = 11 / 12. Each other cell of the band, 16 empty
	// rays: 15 / 1456 x (11 / 12)^15 = 0.010302 x 0.27114 = 0.0027933 > alpha
	// = 1e-3: blocky dropouts, no candidate.
	Scene alive = s;
	alive.at(20, 39) = 1000;
	Result a;
	run(alive, a);
	EXPECT_EQ(a.stats.dead_border_columns, 0u);
	EXPECT_EQ(a.stats.rays, 1600u);
	EXPECT_EQ(a.stats.empty_rays, 159u);
	EXPECT_NEAR(a.det.dropoutRate(1.0), 15.0 / 1456.0, 1e-12);
	EXPECT_NEAR(a.det.neighbourDropoutRate(), 11.0 / 12.0, 1e-12);
	EXPECT_NEAR(missing::emptyCellChance(15.0 / 1456.0, 11.0 / 12.0, 16), 0.0027933, 1e-6);
	EXPECT_EQ(a.stats.candidates, 0u);

	// Dead columns that do not reach the border (16-19) are evidence: 160
	// empty rays, the 10 cells of y cell 10 candidates.
	Scene strip = emptyColumns(16, 20);
	Result st;
	run(strip, st);
	EXPECT_EQ(st.stats.dead_border_columns, 0u);
	EXPECT_EQ(st.stats.empty_rays, 160u);
	EXPECT_EQ(st.stats.candidates, 10u);
}

TEST(MissingFloor, FloorHiddenFromTheSecondImagerByANearerSurfaceIsNoEvidence)
{
	// fx = 80, baseline 0.05 m: fx b = 4 px m. A point at column c and depth
	// z lands at column c - 4 / z in the second imager: the floor (1 m) at
	// c - 4, a box top 0.5 m from the camera (rows 8-31, columns 20-27) at
	// k - 8, i.e. columns 12-19 there. The floor pixels with c - 4 in 12..15
	// and c left of the box, columns 16-19, are hidden behind it from the
	// second imager (8 px of box disparity > 4 + 0.5): a stereo camera
	// returns nothing there, 24 rows x 4 columns = 96 pixels. The same 96
	// empty pixels right of the box (columns 28-31) are seen by both
	// imagers (c - 4 = 24..27: only the floor lands there), so they are
	// empty rays as a dark patch's would be.
	Scene s;
	for (int r = 8; r < 32; r++)
	{
		for (int c = 20; c < 28; c++) s.at(r, c) = 500;
		for (int c = 16; c < 20; c++) s.at(r, c) = 0;
		for (int c = 28; c < 32; c++) s.at(r, c) = 0;
	}
	// Read as a time-of-flight camera: every one of the 40 x 40 pixels is a
	// ray (the box's too: their rays meet the floor), 2 x 96 of them empty.
	Result tof;
	run(s, tof);
	EXPECT_EQ(tof.stats.rays, 1600u);
	EXPECT_EQ(tof.stats.empty_rays, 192u);
	// With the baseline the 96 hidden pixels are no rays at all.
	Result stereo;
	run(s, stereo, {}, 0.05);
	EXPECT_EQ(stereo.stats.rays, 1600u - 96u);
	EXPECT_EQ(stereo.stats.empty_rays, 96u);
	// A box top 0.9 m from the camera (disparity 4000 / 900 = 4.44 px, within
	// half a pixel of the floor's 4 px) hides nothing: it lands at
	// lround(k - 4.44) = k - 4, columns 16-23, none of the hidden columns'
	// 12-15, and it is not nearer by more than half a pixel anyway.
	for (int r = 8; r < 32; r++)
		for (int c = 20; c < 28; c++) s.at(r, c) = 900;
	Result low;
	run(s, low, {}, 0.05);
	EXPECT_EQ(low.stats.rays, 1600u);
	EXPECT_EQ(low.stats.empty_rays, 192u);
}

TEST(MissingFloor, EmptyRaysDoNotDependOnTheStatisticsRows)
{
	// A camera 1 m up, pitched 10 deg down and rolled 5 deg, fx = fy = 40 on
	// 64 x 48 pixels (+-31 deg vertically): the top rows look above the
	// horizon, the rows below it meet the floor beyond the 4.5 m range (their
	// rays must not count) and, with the roll, some rows do both. Every pixel
	// returns the floor (depth = x in the sensor frame: t for the ray (1, y/x,
	// z/x)), nothing above the horizon or beyond 6 m. The statistics rows are
	// judged one way (every pixel), the other rows another (only empty pixels,
	// the ray table read only where a row's rays are not all on one side of
	// the ground): the empty rays per cell must not depend on which rows are
	// statistics rows.
	constexpr int W = 64, H = 48;
	PinholeIntrinsics K;
	K.width = W;
	K.height = H;
	K.fx = K.fy = 40;
	K.cx = 31.5;
	K.cy = 23.5;
	const Eigen::Matrix3d R = (Eigen::AngleAxisd(10.0 * M_PI / 180, Eigen::Vector3d::UnitY()) *
							   Eigen::AngleAxisd(5.0 * M_PI / 180, Eigen::Vector3d::UnitX()))
								  .toRotationMatrix();
	std::vector<uint16_t> depth(size_t(W * H), 0);
	int expectedEmpty = 0;
	for (int r = 0; r < H; r++)
		for (int c = 0; c < W; c++)
		{
			const Eigen::Vector3d d = R * Eigen::Vector3d(1, (K.cx - c) / K.fx, (K.cy - r) / K.fy);
			if (!(d.z() < 0)) continue;  // above the horizon: no return
			const double t = 1.0 / -d.z();
			if (t > 6.0) continue;
			depth[size_t(r * W + c)] = uint16_t(std::lround(t * 1000));
			// Dark pixels well inside [0.5, 4.5] m: a block and every 7th pixel
			// of some rows (dropouts) at 1 - 3 m, and every 5th pixel at 3.6 -
			// 4.3 m, where the rolled rows also hold floor beyond the range.
			const bool block = r >= 34 && r < 40 && c >= 20 && c < 30;
			const bool dropout = r >= 30 && r < 44 && c % 7 == 3;
			const bool far = c % 5 == 1 && t > 3.6 && t < 4.3;
			if (((block || dropout) && t > 1.0 && t < 3.0) || far)
			{
				depth[size_t(r * W + c)] = 0;
				expectedEmpty++;
			}
		}
	ASSERT_GT(expectedEmpty, 60);

	const SensorFrame frame = depthFrame(depth, K, R, 1.0);
	GridGeometry g;
	g.x_min = 0;  // the floor within 4.5 m, |y| < 3.6 m at the view's edges
	g.y_min = -4;
	g.resolution = 0.05;
	g.nx = 100;
	g.ny = 160;
	ElevationGrid grid;
	DepthProjector proj;
	const std::vector<VoxelClass> classes = seenFloorClasses(frame, g, grid, proj);

	std::vector<std::vector<uint16_t>> emptyPerCell;
	for (int statsRows : {1, 3, 4})
	{
		MissingFloorParams p;
		p.stats_row_step = statsRows;
		MissingFloorDetector det(p);
		MissingFloorStats stats;
		det.compute(frame, proj, 1, 4.5, Plane{}, grid, classes, stats);
		// Every dark pixel meets the floor within the range: each is one empty
		// ray; the empty pixels above the horizon and the floor beyond 4.5 m
		// are none.
		EXPECT_EQ(stats.empty_rays, size_t(expectedEmpty)) << statsRows;
		std::vector<uint16_t> perCell(g.cellCount());
		for (size_t i = 0; i < perCell.size(); i++) perCell[i] = det.emptyRays(uint32_t(i));
		emptyPerCell.push_back(perCell);
	}
	EXPECT_EQ(emptyPerCell[0], emptyPerCell[1]);
	EXPECT_EQ(emptyPerCell[0], emptyPerCell[2]);
}

TEST(MissingFloor, DropoutRateIsCountedPerRangeBinAlongARow)
{
	// The 40 x 40 camera of run(), 1 m up looking down, turned 20 deg about
	// its image's vertical axis: the ray (1, fy, fz) of column c (fy = (19.5 -
	// c) / 80) drops cos 20 - fy sin 20 per unit of depth, so it meets the
	// floor at depth t = 1 / (0.9396926 - 0.3420201 fy): 1.1678 m at column 0
	// (fy = 0.24375), 0.9774 m at column 39. With 1.05 m range bins a row
	// spans two: column 22 (fy = -0.03125) t = 1 / 0.9503807 = 1.05221 m, bin
	// 1; column 23 (fy = -0.04375) t = 1 / 0.9546560 = 1.04750 m, bin 0.
	// Dark pixels: rows 4, 8, ..., 36 (9) at even columns 2..22 (11), all in
	// bin 1; each has returning neighbours in its 5 cm cell (pixels 1.2 - 1.5
	// cm apart on the floor), so every cell is seen floor. Turned -20 deg, the
	// same with column c as column 39 - c: the depth then rises along a row.
	const double cos20 = std::cos(20.0 * M_PI / 180), sin20 = std::sin(20.0 * M_PI / 180);
	ASSERT_NEAR(cos20, 0.9396926, 1e-7);
	ASSERT_NEAR(sin20, 0.3420201, 1e-7);
	PinholeIntrinsics K;
	K.width = K.height = kSize;
	K.fx = K.fy = 80;
	K.cx = K.cy = 19.5;
	for (int turn : {1, -1})
	{
		const Eigen::Matrix3d R = (Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitY()) *
								   Eigen::AngleAxisd(turn * 20.0 * M_PI / 180, Eigen::Vector3d::UnitZ()))
									  .toRotationMatrix();
		std::vector<uint16_t> depth(size_t(kSize * kSize));
		for (int r = 0; r < kSize; r++)
			for (int col = 0; col < kSize; col++)
			{
				const int c = turn > 0 ? col : kSize - 1 - col;  // the column of the +20 deg frame
				const double fy = (19.5 - c) / 80;
				const bool dark = r >= 4 && r % 4 == 0 && c >= 2 && c <= 22 && c % 2 == 0;
				depth[size_t(r * kSize + col)] = dark ? 0 : uint16_t(std::lround(1000 / (cos20 - fy * sin20)));
			}
		const SensorFrame frame = depthFrame(depth, K, R, kH);
		GridGeometry g;  // the floor seen: |x| < 0.3 m, |y| from 0.1 to 0.7 m
		g.x_min = g.y_min = -1;
		g.resolution = 0.05;
		g.nx = g.ny = 40;
		ElevationGrid grid;
		DepthProjector proj;
		const std::vector<VoxelClass> classes = seenFloorClasses(frame, g, grid, proj);
		MissingFloorParams p;
		p.stats_row_step = 1;
		p.range_bin = 1.05;
		MissingFloorDetector det(p);
		MissingFloorStats stats;
		det.compute(frame, proj, 1, 4.5, Plane{}, grid, classes, stats);
		EXPECT_EQ(stats.rays, 1600u) << turn;
		EXPECT_EQ(stats.empty_rays, 99u) << turn;  // 9 x 11
		// Bin 1 (1.05 - 2.1 m): columns 0-22 of 40 rows, 920 rays, 99 empty:
		// 99 / 920 = 0.1076087. Bin 0: columns 23-39, 680 rays, none empty.
		EXPECT_NEAR(det.dropoutRate(1.1), 99.0 / 920.0, 1e-12) << turn;
		EXPECT_NEAR(det.dropoutRate(1.1), 0.1076087, 1e-7) << turn;
		EXPECT_EQ(det.dropoutRate(1.0), 0.0) << turn;
		// Each dark pixel has returning neighbours: 99 pairs after an empty
		// ray (the next pixel of the row), none of them both empty.
		EXPECT_EQ(det.neighbourDropoutRate(), 0.0) << turn;
	}
}

TEST(MissingFloor, ARangeImageIsJudgedByTheRangeAlongEachRay)
{
	// A range image (floorRanges()): every ray meets the floor at depth 1 m,
	// at range sqrt(1 + (u^2 + v^2) / 6400) m with u = 19.5 - r, v = 19.5 - c
	// (half-integers). What the detector compares with the range, the bins and
	// the margin below the floor, must be that range, not the depth.
	MissingFloorParams every;
	every.stats_row_step = 1;

	// 1. A range of 1.02 m judges the rays with u^2 + v^2 <= (1.02^2 - 1) x
	// 6400 = 258.56 (a depth image would judge all 1600 at 1 m). Per |u| =
	// 0.5, 1.5, ..., the |v| <= sqrt(258.56 - u^2): 16.07, 16.01, 15.88,
	// 15.69, 15.44, 15.11, 14.71, 14.22, 13.65, 12.97, 12.18, 11.24, 10.12,
	// 8.74, 6.95, 4.28 (none from |u| = 16.5), i.e. 16, 16, 16, 16, 15, 15,
	// 15, 14, 14, 13, 12, 11, 10, 9, 7, 4 half-integers: 203 per quadrant,
	// 812 rays. (The nearest u^2 + v^2 on either side, 254.5 and 260.5, are
	// 1.01969 and 1.02015 m: far from 1.02 m in float.)
	EXPECT_EQ(16 + 16 + 16 + 16 + 15 + 15 + 15 + 14 + 14 + 13 + 12 + 11 + 10 + 9 + 7 + 4, 203);
	{
		Result res;
		runCamera(floorRanges(), false, 1.02, res, every);
		EXPECT_EQ(res.stats.rays, 812u);
		EXPECT_EQ(res.stats.empty_rays, 0u);
	}

	// 2. A return beyond the range is no floor only beyond the floor's range
	// plus beyond_margin (0.10 m). 1.110 m at the centre pixel (19, 19),
	// range sqrt(1 + 0.5 / 6400) = 1.000039 m: beyond 1.100039, empty. 1.110 m
	// at pixel (11, 6), u = 8.5, v = 13.5, u^2 + v^2 = 72.25 + 182.25 = 254.5,
	// range sqrt(1 + 254.5 / 6400) = 1.019689 m: within 1.119689, not empty
	// (against its depth, 1 + 0.10 < 1.110, it would be). Both pixels lie in
	// statistics rows with every row one, in other rows with every 4th
	// (rows 0, 4, ..., 36: rays counted there only, u = 19.5, 15.5, 11.5,
	// 7.5, 3.5, 0.5, 4.5, 8.5, 12.5, 16.5, 2 x (0 + 4 + 11 + 14 + 16 + 16 +
	// 15 + 14 + 10 + 0) = 200 of them, from the list above).
	for (int statsRows : {1, 4})
	{
		std::vector<uint16_t> range = floorRanges();
		range[size_t(19 * kSize + 19)] = 1110;
		range[size_t(11 * kSize + 6)] = 1110;
		MissingFloorParams p;
		p.stats_row_step = statsRows;
		Result res;
		runCamera(range, false, 1.02, res, p);
		EXPECT_EQ(res.stats.rays, statsRows == 1 ? 812u : 200u) << statsRows;
		EXPECT_EQ(res.stats.empty_rays, 1u) << statsRows;
		// The centre pixel meets the floor at x = y = 0.5 / 80 = 0.00625 m:
		// cell floor((0.00625 + 0.5) / 0.05) = 10 on both axes.
		EXPECT_EQ(res.det.emptyRays(cellOf(10, 10)), 1) << statsRows;
	}

	// 3. The dropout rate per range bin (1.0101 m, 4.5 m range: all 1600 rays
	// judged): bin 0 holds u^2 + v^2 < (1.0101^2 - 1) x 6400 = 129.93: per |u|
	// = 0.5 ... 10.5, |v| < 11.39, 11.30, 11.12, 10.85, 10.47, 9.98, 9.36,
	// 8.58, 7.59, 6.30, 4.44, i.e. 11, 11, 11, 11, 10, 10, 9, 9, 8, 6, 4: 100
	// per quadrant, 400 rays; bin 1 the other 1200. Row 19 (u = 0.5) dark:
	// |v| >= 11.5 in bin 1, 9 a side, 18 rays; the other 22 in bin 0. (Each
	// cell keeps the returns of its other rows: it is seen floor.)
	EXPECT_EQ(11 + 11 + 11 + 11 + 10 + 10 + 9 + 9 + 8 + 6 + 4, 100);
	{
		std::vector<uint16_t> range = floorRanges();
		for (int c = 0; c < kSize; c++) range[size_t(19 * kSize + c)] = 0;
		MissingFloorParams p = every;
		p.range_bin = 1.0101;
		Result res;
		runCamera(range, false, 4.5, res, p);
		EXPECT_EQ(res.stats.rays, 1600u);
		EXPECT_EQ(res.stats.empty_rays, 40u);
		EXPECT_NEAR(res.det.dropoutRate(1.0), 22.0 / 400.0, 1e-12);    // 0.055
		EXPECT_NEAR(res.det.dropoutRate(1.02), 18.0 / 1200.0, 1e-12);  // 0.015
	}

	// 4. A dark hole, 8 x 8 pixels at rows and columns 16-23 (cells 9 and 10
	// on both axes, 16 rays each), whichever rows are statistics rows.
	for (int statsRows : {1, 3, 4})
	{
		std::vector<uint16_t> range = floorRanges();
		for (int r = 16; r < 24; r++)
			for (int c = 16; c < 24; c++) range[size_t(r * kSize + c)] = 0;
		MissingFloorParams p;
		p.stats_row_step = statsRows;
		Result res;
		runCamera(range, false, 4.5, res, p);
		EXPECT_EQ(res.stats.empty_rays, 64u) << statsRows;
		for (int ix : {9, 10})
			for (int iy : {9, 10}) EXPECT_EQ(res.det.emptyRays(cellOf(ix, iy)), 16) << statsRows;
	}
}

namespace
{
// A step down near the end of the camera's range: a camera 1 m above the
// floor at the map's origin, 60 x 80 pixels, fx = 120, fy = 240, pitched
// down by atan(1 / 2.2) (its centre row meets the floor 2.2 m ahead),
// returning nothing beyond a depth of 2.75 m. From x = 2.0 m on, a pit 0.2
// m deep and 0.6 m wide (|y| < 0.3 m), the floor on either side of it (where
// the dropout rate of seen floor is measured at every range). A ray that passes
// the edge meets the lower floor 1.2 times as far as it would have met the
// upper one: only those that would have met it within 2.75 / 1.2 = 2.29 m
// of depth (x up to 2.08 m) return, from x = 2.4 m on; the others are
// empty. Every other column returns nothing anywhere (a camera that drops
// half its pixels: q = 0.5 on seen floor, and after an empty pixel comes a
// returning one but where that one lies in the shadow, in a cell that also
// holds floor samples: p11 small). Around 2.2 m a row is 1 / (240 sin^2 24.4 deg) = 2.4 cm
// of floor deep and a column 2.4 / 120 = 2.0 cm wide: a 5 cm cell holds
// 2-3 rows of 2-3 columns, a few rays, and each alone is no evidence
// (0.5^n > alpha = 1e-3 for n <= 9).
constexpr double kStepEdge = 2.0, kStepDrop = 0.2, kStepH = 1.0, kStepRange = 2.75;

struct StepScene
{
	PinholeIntrinsics K;
	Eigen::Matrix3d R;
	std::vector<uint16_t> depth;
	GridGeometry g;
};

/** The step scene with a pit `drop` deep (0: flat floor), every
 * `dropEvery`-th column returning nothing (2: every other one); floor rays
 * of columns arcFrom..arcTo - 1 whose depth is within `emptyArc` of the
 * range's end return nothing either (as if the depth noise had carried them
 * beyond it). */
StepScene stepScene(double drop = kStepDrop, int dropEvery = 2, double emptyArc = 0, int arcFrom = 0, int arcTo = 0)
{
	StepScene s;
	s.K.width = 80;
	s.K.height = 60;
	s.K.fx = 120;
	s.K.fy = 240;
	s.K.cx = 39.5;
	s.K.cy = 29.5;
	s.R = Eigen::AngleAxisd(std::atan2(kStepH, 2.2), Eigen::Vector3d::UnitY()).toRotationMatrix();
	s.depth.assign(size_t(s.K.width * s.K.height), 0);
	for (int r = 0; r < s.K.height; r++)
		for (int c = 0; c < s.K.width; c++)
		{
			if (c % dropEvery == dropEvery - 1) continue;
			// The projector's ray of pixel (r, c): (1, -(c - cx) / fx, -(r - cy) / fy)
			// in the sensor frame, depth 1 along it.
			const Eigen::Vector3d ray = s.R * Eigen::Vector3d(1, -(c - s.K.cx) / s.K.fx, -(r - s.K.cy) / s.K.fy);
			if (ray.z() >= 0) continue;
			double t = kStepH / -ray.z();  // depth where the ray meets z = 0
			if (c >= arcFrom && c < arcTo && t > kStepRange - emptyArc) continue;
			if (drop > 0 && t * ray.x() >= kStepEdge && std::abs(t * ray.y()) < 0.3)
				t = (kStepH + drop) / -ray.z();  // past the edge: the pit's floor
			if (t <= kStepRange) s.depth[size_t(r * s.K.width + c)] = uint16_t(std::lround(1000 * t));
		}
	s.g.x_min = -0.5;
	s.g.y_min = -1.0;
	s.g.resolution = 0.05;
	s.g.nx = 100;
	s.g.ny = 40;
	return s;
}

/** Missing floor on the step scene: the ISM's classes as the map gives them
 * (cells whose samples lie 0.1 m or more below the ground plane z = 0 are
 * Drop, other seen cells Ground). */
void runStep(const StepScene& s, Result& out, MissingFloorParams p, double rangeEndMargin = 0)
{
	p.stats_row_step = 1;
	const SensorFrame frame = depthFrame(s.depth, s.K, s.R, kStepH);
	DepthProjector proj;
	std::vector<VoxelClass> classes = seenFloorClasses(frame, s.g, out.grid, proj);
	for (size_t i = 0; i < s.g.cellCount(); i++)
		if (out.grid.cell(i).count && out.grid.cell(i).z_max < -0.1) classes[i] = VoxelClass::Drop;
	out.det.setParams(p);
	out.det.setRangeEndMargin(rangeEndMargin);
	out.det.compute(frame, proj, 1, kStepRange, Plane{}, out.grid, classes, out.stats);
}

uint32_t stepCell(double x, double y)
{
	return uint32_t(std::floor((y + 1.0) / 0.05) * 100 + std::floor((x + 0.5) / 0.05));
}

/** The pit's cells with centres from x = 2.125 m to below xEnd, |y| < 0.25 m. */
std::vector<uint32_t> pitCells(double xEnd)
{
	std::vector<uint32_t> cells;
	for (double x = 2.125; x < xEnd; x += 0.05)
		for (double y = -0.225; y < 0.25; y += 0.05) cells.push_back(stepCell(x, y));
	return cells;
}
}  // namespace

TEST(MissingFloor, IsStepShadowComparesTheGapWithTheEdgesShadow)
{
	// Edge 2.0 m from a sensor 1.0 m up, a surface 0.2 m down: the ray over
	// the edge descends 1 / 2 per metre and meets it 0.2 * 2.0 / 1.0 = 0.4 m
	// beyond the edge, at 2.4 m. Slack 0.1 m: a gap ending at 2.3-2.5 m is
	// that shadow.
	EXPECT_TRUE(missing::isStepShadow(2.0, 2.4, 0.2, 1.0, 0.1));
	EXPECT_TRUE(missing::isStepShadow(2.0, 2.49, 0.2, 1.0, 0.1));
	EXPECT_TRUE(missing::isStepShadow(2.0, 2.31, 0.2, 1.0, 0.1));
	// 0.9 m of gap before that surface: longer than any shadow of the edge
	// (a ramp down at grazing incidence); 0.1 m: shorter (no edge's shadow).
	EXPECT_FALSE(missing::isStepShadow(2.0, 2.9, 0.2, 1.0, 0.1));
	EXPECT_FALSE(missing::isStepShadow(2.0, 2.1, 0.2, 1.0, 0.1));
	// The Kinect One case: 0.8 m up, a 0.10 m step 4.0 m ahead: 0.1 * 4.0 /
	// 0.8 = 0.5 m of shadow, the lower floor from 4.5 m.
	EXPECT_TRUE(missing::isStepShadow(4.0, 4.55, 0.1, 0.8, 0.1));
	EXPECT_FALSE(missing::isStepShadow(4.0, 4.75, 0.1, 0.8, 0.1));
	// No drop, no height, no edge: no shadow.
	EXPECT_FALSE(missing::isStepShadow(2.0, 2.0, 0.0, 1.0, 0.1));
	EXPECT_FALSE(missing::isStepShadow(2.0, 2.4, 0.2, 0.0, 0.1));
	EXPECT_FALSE(missing::isStepShadow(0.0, 0.1, 0.2, 1.0, 0.1));
}

TEST(MissingFloor, AStepsShadowIsJudgedAsOneRegion)
{
	const StepScene s = stepScene();
	// The shadow's cells that no returning ray meets, x 2.1-2.35 (the rays
	// of x 2.0-2.08 return the lower floor), |y| < 0.25.
	const std::vector<uint32_t> shadow = pitCells(2.35);
	{
		Result res;
		MissingFloorParams p;
		p.step_shadows = false;
		runStep(s, res, p);
		// Half the rays on seen floor (a few rows straddle the shadow's cells).
		for (double depth : {1.8, 2.2})
		{
			EXPECT_NEAR(res.det.dropoutRate(depth), 0.5, 0.02) << depth;
		}
		const double q = res.det.dropoutRate(2.2), p11 = res.det.neighbourDropoutRate();
		EXPECT_GE(p11, 0.0);
		EXPECT_LT(p11, 0.5);
		// Each shadow cell alone: 3 to 9 empty rays, its chance q max(q,
		// p11)^(n - 1) >= 0.48^9 = 0.0014 > alpha.
		for (uint32_t c : shadow)
		{
			EXPECT_GE(res.det.emptyRays(c), 3) << c;
			EXPECT_LE(res.det.emptyRays(c), 9) << c;
			EXPECT_GT(missing::emptyCellChance(q, p11, res.det.emptyRays(c)), p.alpha) << c;
			EXPECT_FALSE(res.det.isMissing(c)) << c;
		}
	}
	Result res;
	runStep(s, res, MissingFloorParams{});
	// Together: the region's rays number at least 3 x 50 = 150, its chance at
	// most 0.52^150 = 3e-43, the exponent taken (1 - p11) > 0.5 times as the
	// rows may drop out together: 6e-22, against alpha / (cells with an
	// empty ray, at most the grid's 4000) = 2.5e-7 at the least. Beyond it,
	// the lower floor from 2.4 m: the shadow of the edge (isStepShadow).
	EXPECT_EQ(res.stats.pooled_regions, 1u);
	for (uint32_t c : shadow) EXPECT_TRUE(res.det.isMissing(c)) << c;
	// The floors on either side are not missing.
	EXPECT_FALSE(res.det.isMissing(stepCell(1.8, 0)));
	EXPECT_FALSE(res.det.isMissing(stepCell(2.45, 0)));
}

TEST(MissingFloor, AStepsShadowMayRunToTheEndOfTheRange)
{
	// The pit 0.5 m deep: a ray over the edge meets its floor (1 + 0.5) / 1
	// = 1.5 times as deep as the upper floor, so only rays that would have met
	// the upper floor within 2.75 / 1.5 = 1.83 m of depth could return from
	// it; past the edge (depth 2.0 cos 24.4 deg + 1.0 sin 24.4 deg = 2.24 m)
	// none does. The gap runs from the edge to where the upper floor itself
	// leaves the range: depth 2.75 m, x = (2.75 - 0.413) / 0.911 = 2.57 m.
	// Beside the pit the floor is seen out to there. A camera that drops
	// every 4th column: q = 0.25 on seen floor, and the pixel after an empty
	// one returns (p11 = 0).
	const StepScene s = stepScene(0.5, 4);
	const std::vector<uint32_t> shadow = pitCells(2.5);
	{
		// No surface beyond the gap closes it: without the rule, nothing.
		Result res;
		MissingFloorParams p;
		p.step_shadows = false;
		runStep(s, res, p);
		for (uint32_t c : shadow) EXPECT_FALSE(res.det.isMissing(c)) << c;
	}
	Result res;
	runStep(s, res, MissingFloorParams{}, 0.05);
	EXPECT_NEAR(res.det.dropoutRate(2.2), 0.25, 0.02);
	// With it: the gap's rays run through unseen cells to where the range
	// ends (x = 2.57 m). Its cells nearer than the range's end less the
	// margin (0.05 m: x < 2.51 m) have 3 or more empty rays (the pit's 2-3
	// rows and 2-3 columns a cell), q^n <= 0.25^3 = 0.016 a cell, x e 7 =
	// 19 as the region is a cluster picked among many: 0.30; some 70 of them:
	// at most 0.30^70 = 1e-37, against alpha / (cells with an empty ray, at
	// most the grid's 4000) = 2.5e-7. Each judged cell is missing floor (a
	// cell the rows straddle gets 2 rays, and is not judged).
	int judged = 0;
	for (uint32_t c : shadow)
		if (res.det.emptyRays(c) >= 3)
		{
			judged++;
			EXPECT_TRUE(res.det.isMissing(c)) << c;
		}
	EXPECT_GE(judged, 60);
	EXPECT_FALSE(res.det.isMissing(stepCell(1.8, 0)));
	EXPECT_FALSE(res.det.isMissing(stepCell(2.3, 0.45)));
}

TEST(MissingFloor, TheRangesNoisyEndIsNoStepsShadow)
{
	// Flat floor. Rays of columns 30-49 (y from -0.2 to +0.2 m at 2.4 m)
	// within 0.3 m of the range's end (depth 2.45-2.75 m, x = 2.24-2.57 m)
	// return nothing: what depth noise of that size does at a hard range
	// limit; the other columns see floor out to the end. Floor nearer, the
	// range's end beyond: to the map, the same gap as a step's shadow 0.4 m
	// wide (q = 0.25 besides, p11 = 0).
	const StepScene s = stepScene(0.0, 4, 0.3, 30, 50);
	const uint32_t arc = stepCell(2.4, 0.0);
	{
		// With a margin shorter than the arc, its near part (x < 2.51 m) is
		// taken for a step's shadow that runs to the end of the range.
		Result res;
		runStep(s, res, MissingFloorParams{}, 0.05);
		EXPECT_TRUE(res.det.isMissing(arc));
		EXPECT_EQ(res.stats.range_end_regions, 1u);
	}
	// A margin of the arc's depth (0.3 m: three sigma of a depth noise of
	// 0.1 m there): no cell of the arc is evidence, nothing is missing.
	Result res;
	runStep(s, res, MissingFloorParams{}, 0.3);
	EXPECT_EQ(res.stats.cells, 0u);
	EXPECT_FALSE(res.det.isMissing(arc));
	// Neither is the floor seen beside it.
	EXPECT_FALSE(res.det.isMissing(stepCell(2.4, 0.45)));
}

TEST(MissingFloor, AnArcAcrossTheViewIsNoStepsShadow)
{
	// The same empty arc across the whole image, as the range's end leaves
	// it: no floor is seen at its depth (its cells beyond 2.5 m of depth
	// fall in a range bin with no seen floor, whose dropout rate is 1, no
	// evidence), even with a margin shorter than the arc.
	const StepScene s = stepScene(0.0, 4, 0.3, 0, 80);
	Result res;
	runStep(s, res, MissingFloorParams{}, 0.05);
	EXPECT_EQ(res.det.dropoutRate(2.6), 1.0);
	EXPECT_EQ(res.stats.cells, 0u);
	EXPECT_FALSE(res.det.isMissing(stepCell(2.4, 0.0)));
}

TEST(MissingFloor, DropoutsAtTheEndOfTheRangeAreNoStepsShadow)
{
	// The pit of AStepsShadowMayRunToTheEndOfTheRange seen by the camera
	// that drops every other column (q = 0.5, 3-9 empty rays a cell). A
	// cluster of empty cells that large turns up among dropping-out floor
	// by chance: q^3 x e x 7 = 0.125 x 19 = 2.4 > 1 a cell. Its rays run to
	// the end of the range all the same: nothing is marked.
	const StepScene s = stepScene(0.5, 2);
	Result res;
	runStep(s, res, MissingFloorParams{}, 0.05);
	for (double x = 2.125; x < 2.5; x += 0.05) EXPECT_FALSE(res.det.isMissing(stepCell(x, 0.025))) << x;
}
