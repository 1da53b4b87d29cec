// Ground-aware mapping for MRPT
// ElevationGrid: geometry, per-cell statistics, 3-sigma filter, IDW.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>

#include "gam/core/ElevationGrid.h"
#include "test_helpers.h"

using namespace gam;
using gamtest::makeGeometry;

TEST(GridGeometry, IndexingAndCentres)
{
	const GridGeometry g = makeGeometry(-2.0, 1.0, 0.5, 8, 4);
	EXPECT_DOUBLE_EQ(g.x_max(), 2.0);
	EXPECT_DOUBLE_EQ(g.y_max(), 3.0);
	EXPECT_EQ(g.cellCount(), 32u);
	EXPECT_EQ(g.ix(-2.0), 0);
	EXPECT_EQ(g.ix(-1.76), 0);
	EXPECT_EQ(g.ix(-1.5), 1);
	EXPECT_EQ(g.ix(1.99), 7);
	EXPECT_EQ(g.ix(-2.01), -1);  // floor, not truncation
	EXPECT_EQ(g.iy(2.3), 2);
	EXPECT_DOUBLE_EQ(g.cx(0), -1.75);
	EXPECT_DOUBLE_EQ(g.cy(3), 2.75);
	EXPECT_EQ(g.index(3, 2), 2u * 8u + 3u);
	EXPECT_TRUE(g.inside(7, 3));
	EXPECT_FALSE(g.inside(8, 0));
	EXPECT_FALSE(g.inside(0, -1));
}

TEST(GridGeometry, ValidateRejectsBadValues)
{
	EXPECT_NO_THROW(GridGeometry{}.validate());
	EXPECT_THROW(makeGeometry(0, 0, 0.0, 10, 10).validate(), std::invalid_argument);
	EXPECT_THROW(makeGeometry(0, 0, -0.1, 10, 10).validate(), std::invalid_argument);
	EXPECT_THROW(makeGeometry(0, 0, NAN, 10, 10).validate(), std::invalid_argument);
	EXPECT_THROW(makeGeometry(0, 0, 0.1, 0, 10).validate(), std::invalid_argument);
	EXPECT_THROW(makeGeometry(0, 0, 0.1, 10, -1).validate(), std::invalid_argument);
	EXPECT_THROW(makeGeometry(0, 0, 0.1, 100000, 100000).validate(), std::invalid_argument);
	EXPECT_THROW(makeGeometry(NAN, 0, 0.1, 10, 10).validate(), std::invalid_argument);
	EXPECT_THROW(makeGeometry(0, INFINITY, 0.1, 10, 10).validate(), std::invalid_argument);
	ElevationGrid grid;
	EXPECT_THROW(grid.resize(makeGeometry(0, 0, 0.0, 10, 10)), std::invalid_argument);
}

TEST(ElevationGrid, BinPointInsideAndOutside)
{
	ElevationGrid grid(makeGeometry(0, 0, 0.1, 10, 5));
	BinnedPoints b;
	EXPECT_TRUE(grid.binPoint(0.25, 0.31, 1.5f, b));
	ASSERT_EQ(b.size(), 1u);
	EXPECT_EQ(b.cells()[0], 3u * 10u + 2u);
	EXPECT_FLOAT_EQ(b.heights()[0], 1.5f);
	EXPECT_FALSE(grid.binPoint(-0.01, 0.2, 0.f, b));
	EXPECT_FALSE(grid.binPoint(1.0, 0.2, 0.f, b));
	EXPECT_FALSE(grid.binPoint(0.5, 0.5, 0.f, b));
	EXPECT_EQ(b.size(), 1u);
}

TEST(ElevationGrid, CellStatisticsByHand)
{
	ElevationGrid grid(makeGeometry(0, 0, 1.0, 4, 4));
	BinnedPoints b;
	for (float z : {0.1f, 0.2f, 0.6f}) grid.binPoint(1.5, 2.5, z, b);
	grid.binPoint(3.5, 0.5, -1.0f, b);
	OutlierFilterParams f;  // enabled, but 3 samples < min_count
	EXPECT_EQ(grid.insert(b, f), 4u);
	EXPECT_EQ(grid.observedCount(), 2u);

	const ElevationCell& c = grid.cell(1, 2);
	EXPECT_EQ(c.count, 3u);
	EXPECT_FLOAT_EQ(c.z_min, 0.1f);
	EXPECT_FLOAT_EQ(c.z_max, 0.6f);
	EXPECT_NEAR(c.mean(), 0.3, 1e-6);
	// (0.01 + 0.04 + 0.36) / 3 - 0.3^2 = 0.0466667
	EXPECT_NEAR(c.variance(), 0.41 / 3.0 - 0.09, 1e-6);
	EXPECT_NEAR(c.span(), 0.5, 1e-6);
	EXPECT_TRUE(std::isnan(c.z_idw));

	const ElevationCell& d = grid.cell(3, 0);
	EXPECT_EQ(d.count, 1u);
	EXPECT_FLOAT_EQ(d.mean(), -1.0f);
	EXPECT_FLOAT_EQ(d.variance(), 0.f);
	EXPECT_FALSE(grid.cell(0, 0).observed());

	// A second frame merges into the same statistics.
	b.clear();
	grid.binPoint(1.2, 2.9, 1.1f, b);
	grid.insert(b, f);
	EXPECT_EQ(grid.cell(1, 2).count, 4u);
	EXPECT_FLOAT_EQ(grid.cell(1, 2).z_max, 1.1f);
	EXPECT_NEAR(grid.cell(1, 2).mean(), (0.1 + 0.2 + 0.6 + 1.1) / 4.0, 1e-6);
	EXPECT_EQ(grid.observedCount(), 2u);  // no duplicate in the touched list

	grid.clear();
	EXPECT_EQ(grid.observedCount(), 0u);
	EXPECT_EQ(grid.cell(1, 2).count, 0u);
	EXPECT_FALSE(std::isfinite(grid.cell(1, 2).z_min));

	grid.binPoint(0.5, 0.5, 2.f, b);
	grid.insert(b, f);
	grid.recenter(10.0, 20.0);
	EXPECT_EQ(grid.observedCount(), 0u);
	EXPECT_EQ(grid.cell(0, 0).count, 0u);
	EXPECT_DOUBLE_EQ(grid.geometry().x_min, 10.0);
	EXPECT_DOUBLE_EQ(grid.geometry().y_min, 20.0);
	EXPECT_EQ(grid.geometry().nx, 4);
}

namespace
{
struct OutlierCase
{
	std::vector<float> clean;
	float outlier = 0.5f;
};
OutlierCase makeOutlierCase()
{
	std::mt19937 rng(12345);
	std::normal_distribution<float> N(0.f, 0.01f);
	OutlierCase oc;
	for (int i = 0; i < 40; i++) oc.clean.push_back(N(rng));
	return oc;
}
// Bins the 41 samples into cell (2,2) and 10 clean samples into cell (0,0).
void binOutlierCase(const ElevationGrid& grid, const OutlierCase& oc, BinnedPoints& b)
{
	for (float z : oc.clean) grid.binPoint(2.5, 2.5, z, b);
	grid.binPoint(2.5, 2.5, oc.outlier, b);
	for (int i = 0; i < 10; i++) grid.binPoint(0.5, 0.5, 1.0f + 0.001f * float(i), b);
}
}  // namespace

TEST(ElevationGridFilter, ThreeSigmaRemovesTheOutlier)
{
	const OutlierCase oc = makeOutlierCase();
	// Independent check of the premise: the band mean +- 3 std of the 41
	// samples excludes +0.5 and keeps every clean sample.
	double s = 0, s2 = 0;
	for (float z : oc.clean) s += z, s2 += double(z) * z;
	s += oc.outlier;
	s2 += double(oc.outlier) * oc.outlier;
	const double m = s / 41, sd = std::sqrt(s2 / 41 - m * m);
	ASSERT_GT(std::abs(oc.outlier - m), 3 * sd);
	for (float z : oc.clean) ASSERT_LE(std::abs(z - m), 3 * sd);

	ElevationGrid grid(makeGeometry(0, 0, 1.0, 4, 4));
	BinnedPoints b;
	binOutlierCase(grid, oc, b);
	OutlierFilterParams f;  // defaults: enabled, 3 sigma, min_count 4
	EXPECT_EQ(grid.insert(b, f), 50u);

	const ElevationCell& c = grid.cell(2, 2);
	EXPECT_EQ(c.count, 40u);
	EXPECT_FLOAT_EQ(c.z_max, *std::max_element(oc.clean.begin(), oc.clean.end()));
	EXPECT_FLOAT_EQ(c.z_min, *std::min_element(oc.clean.begin(), oc.clean.end()));
	double cm = 0;
	for (float z : oc.clean) cm += z;
	EXPECT_NEAR(c.mean(), cm / 40, 1e-5);
	EXPECT_LT(c.z_max, 0.1f);
	// The clean cell of the same frame is untouched.
	EXPECT_EQ(grid.cell(0, 0).count, 10u);
	EXPECT_FLOAT_EQ(grid.cell(0, 0).z_max, 1.009f);
}

TEST(ElevationGridFilter, SmallCellsKeepEverything)
{
	const OutlierCase oc = makeOutlierCase();
	ElevationGrid grid(makeGeometry(0, 0, 1.0, 4, 4));
	BinnedPoints b;
	binOutlierCase(grid, oc, b);
	OutlierFilterParams f;
	f.min_count = 42;  // the 41-sample cell is "too small" for the rule
	EXPECT_EQ(grid.insert(b, f), 51u);
	EXPECT_EQ(grid.cell(2, 2).count, 41u);
	EXPECT_FLOAT_EQ(grid.cell(2, 2).z_max, 0.5f);

	// Default min_count = 4: a 3-sample cell with a far sample keeps it.
	ElevationGrid g2(makeGeometry(0, 0, 1.0, 4, 4));
	b.clear();
	for (float z : {0.0f, 0.0f, 5.0f}) g2.binPoint(1.5, 1.5, z, b);
	EXPECT_EQ(g2.insert(b, OutlierFilterParams{}), 3u);
	EXPECT_EQ(g2.cell(1, 1).count, 3u);
	EXPECT_FLOAT_EQ(g2.cell(1, 1).z_max, 5.0f);
}

TEST(ElevationGridFilter, DisabledKeepsEverything)
{
	const OutlierCase oc = makeOutlierCase();
	ElevationGrid grid(makeGeometry(0, 0, 1.0, 4, 4));
	BinnedPoints b;
	binOutlierCase(grid, oc, b);
	OutlierFilterParams f;
	f.enabled = false;
	EXPECT_EQ(grid.insert(b, f), 51u);
	EXPECT_EQ(grid.cell(2, 2).count, 41u);
	EXPECT_FLOAT_EQ(grid.cell(2, 2).z_max, 0.5f);
}

TEST(ElevationGridFilter, FilterIsPerFrame)
{
	// The outlier arrives in its own frame: within that frame it is not an
	// outlier, so it is kept (documented: the rule applies within a frame).
	const OutlierCase oc = makeOutlierCase();
	double s = 0, s2 = 0;
	for (float z : oc.clean) s += z, s2 += double(z) * z;
	const double m = s / 40, sd = std::sqrt(s2 / 40 - m * m);
	for (float z : oc.clean) ASSERT_LE(std::abs(z - m), 3 * sd);  // premise
	ElevationGrid grid(makeGeometry(0, 0, 1.0, 4, 4));
	BinnedPoints b;
	for (float z : oc.clean) grid.binPoint(2.5, 2.5, z, b);
	OutlierFilterParams f;
	EXPECT_EQ(grid.insert(b, f), 40u);
	b.clear();
	grid.binPoint(2.5, 2.5, oc.outlier, b);
	EXPECT_EQ(grid.insert(b, f), 1u);
	EXPECT_EQ(grid.cell(2, 2).count, 41u);
	EXPECT_FLOAT_EQ(grid.cell(2, 2).z_max, 0.5f);
}

TEST(ElevationGridFilter, TighterSigmasRemoveMore)
{
	// Samples {0 x8, 1 x2}: mean 0.2, std 0.4. With 1 sigma (band [-0.2, 0.6])
	// the two 1's go; with 3 sigma (band [-1.0, 1.4]) nothing goes.
	ElevationGrid grid(makeGeometry(0, 0, 1.0, 2, 2));
	BinnedPoints b;
	for (int i = 0; i < 8; i++) grid.binPoint(0.5, 0.5, 0.f, b);
	for (int i = 0; i < 2; i++) grid.binPoint(0.5, 0.5, 1.f, b);
	OutlierFilterParams f;
	f.sigmas = 1.0f;
	EXPECT_EQ(grid.insert(b, f), 8u);
	EXPECT_EQ(grid.cell(0, 0).count, 8u);
	EXPECT_FLOAT_EQ(grid.cell(0, 0).z_max, 0.f);

	ElevationGrid g3(makeGeometry(0, 0, 1.0, 2, 2));
	EXPECT_EQ(g3.insert(b, OutlierFilterParams{}), 10u);
	EXPECT_EQ(g3.cell(0, 0).count, 10u);
}

TEST(ElevationGridFilter, KeepsInliersFarFromZeroHeight)
{
	// A floor at z = +-10 m (an upper storey in the map frame) with 3 mm noise
	// plus one sample 0.5 m above: only that sample may go. (The one-pass
	// variance of the float sums used to come out ~0 here and the filter threw
	// away good samples.)
	for (float base : {10.0f, -10.0f, 30.0f})
	{
		std::mt19937 rng(1);
		std::normal_distribution<float> N(0.f, 0.003f);
		std::vector<float> clean;
		for (int i = 0; i < 40; i++) clean.push_back(base + N(rng));
		double s = 0, s2 = 0;
		for (float z : clean) s += z;
		s += base + 0.5f;
		const double m = s / 41;
		for (float z : clean) s2 += (z - m) * (z - m);
		s2 += (base + 0.5 - m) * (base + 0.5 - m);
		const double sd = std::sqrt(s2 / 41);
		for (float z : clean) ASSERT_LE(std::abs(z - m), 3 * sd);  // premise
		ASSERT_GT(std::abs(base + 0.5 - m), 3 * sd);

		ElevationGrid grid(makeGeometry(0, 0, 1.0, 2, 2));
		BinnedPoints b;
		for (float z : clean) grid.binPoint(0.5, 0.5, z, b);
		grid.binPoint(0.5, 0.5, base + 0.5f, b);
		EXPECT_EQ(grid.insert(b, OutlierFilterParams{}), 40u) << base;
		EXPECT_EQ(grid.cell(0, 0).count, 40u) << base;
		EXPECT_FLOAT_EQ(grid.cell(0, 0).z_max, *std::max_element(clean.begin(), clean.end()));
		EXPECT_FLOAT_EQ(grid.cell(0, 0).z_min, *std::min_element(clean.begin(), clean.end()));

		// Without the outlier nothing at all is removed.
		ElevationGrid g2(makeGeometry(0, 0, 1.0, 2, 2));
		b.clear();
		for (float z : clean) g2.binPoint(0.5, 0.5, z, b);
		EXPECT_EQ(g2.insert(b, OutlierFilterParams{}), 40u) << base;
	}
}

TEST(ElevationGridFilter, AFlyingPixelLeavesTheKeptSamplesMeanAndVariance)
{
	// The cell's sums are taken relative to its first sample. Here that is
	// a flying pixel 1 m above a floor at z = 10 m with 1 mm noise: every
	// kept sample's deviation from it is ~1 m, and their spread is 1e-6 of
	// that. The kept samples' mean and variance must still be theirs. (A
	// second pass that subtracted the outliers from float sums, tried
	// 2026-11-29, got the variance 100 % off here.)
	std::mt19937 rng(7);
	std::normal_distribution<float> N(0.f, 0.001f);
	const float base = 10.0f, flying = base + 1.0f;
	std::vector<float> clean;
	for (int i = 0; i < 400; i++) clean.push_back(base + N(rng));
	// Premise, in double: the 401 samples' band mean +- 3 std excludes the
	// flying pixel only. (mean ~ 10 + 1/401 = 10.0025, std ~ sqrt(400)/401 ~ 0.05.)
	double all = flying;
	for (float z : clean) all += z;
	const double mAll = all / 401;
	double m2All = (flying - mAll) * (flying - mAll);
	for (float z : clean) m2All += (z - mAll) * (z - mAll);
	const double band = 3 * std::sqrt(m2All / 401);
	ASSERT_GT(std::abs(flying - mAll), band);
	for (float z : clean) ASSERT_LE(std::abs(z - mAll), band);
	// Expected: the clean samples' own mean and population variance.
	double m = 0;
	for (float z : clean) m += z;
	m /= 400;
	double var = 0;
	for (float z : clean) var += (z - m) * (z - m);
	var /= 400;  // ~1e-6 (1 mm noise)

	// The flying pixel first (the sums' reference), then last.
	for (bool first : {true, false})
	{
		ElevationGrid grid(makeGeometry(0, 0, 1.0, 2, 2));
		BinnedPoints b;
		if (first) grid.binPoint(0.5, 0.5, flying, b);
		for (float z : clean) grid.binPoint(0.5, 0.5, z, b);
		if (!first) grid.binPoint(0.5, 0.5, flying, b);
		EXPECT_EQ(grid.insert(b, OutlierFilterParams{}), 400u) << first;
		const ElevationCell& c = grid.cell(0, 0);
		EXPECT_EQ(c.count, 400u) << first;
		EXPECT_FLOAT_EQ(c.z_max, *std::max_element(clean.begin(), clean.end())) << first;
		EXPECT_FLOAT_EQ(c.z_min, *std::min_element(clean.begin(), clean.end())) << first;
		EXPECT_NEAR(c.mean(), m, 2e-6) << first;  // a float z_sum of 4000 m holds 2.4e-4 / 400
		EXPECT_NEAR(c.variance(), var, 0.01 * var) << first;
	}
}

TEST(ElevationGridFilter, MinimumBand)
{
	// {0 x8, 0.004 x2}: mean 0.0008, std 0.0016. A 1-sigma band (+-1.6 mm)
	// would drop the two 4 mm samples; the 5 mm minimum band keeps them.
	ElevationGrid grid(makeGeometry(0, 0, 1.0, 2, 2));
	BinnedPoints b;
	for (int i = 0; i < 8; i++) grid.binPoint(0.5, 0.5, 0.f, b);
	for (int i = 0; i < 2; i++) grid.binPoint(0.5, 0.5, 0.004f, b);
	OutlierFilterParams f;
	f.sigmas = 1.0f;
	EXPECT_EQ(grid.insert(b, f), 10u);
	EXPECT_EQ(grid.cell(0, 0).count, 10u);
	f.min_band = 0.f;
	ElevationGrid g2(makeGeometry(0, 0, 1.0, 2, 2));
	EXPECT_EQ(g2.insert(b, f), 8u);
	EXPECT_FLOAT_EQ(g2.cell(0, 0).z_max, 0.f);
}

namespace
{
// 10x10 cells of 1 m; observed: (4,5) z=1, (6,5) z=2, (6,6) z=3.
ElevationGrid makeIdwGrid()
{
	ElevationGrid grid(makeGeometry(0, 0, 1.0, 10, 10));
	gamtest::insertPoints(grid, {{4.5, 5.5, 1.0}, {6.5, 5.5, 2.0}, {6.5, 6.5, 3.0}});
	return grid;
}
}  // namespace

TEST(ElevationGridIdw, HandComputedWeightedAverages)
{
	ElevationGrid grid = makeIdwGrid();
	IdwParams p;
	p.radius_cells = 1;
	p.power = 2;
	p.min_neighbours = 3;
	// Only (5,5) and (5,6) see all three observed cells in their 3x3 window.
	EXPECT_EQ(grid.interpolateIdw(p), 2u);
	// (5,5): (4,5) d=1 w=1, (6,5) d=1 w=1, (6,6) d=sqrt2 w=1/2
	EXPECT_NEAR(grid.cell(5, 5).z_idw, (1 * 1.0 + 1 * 2.0 + 0.5 * 3.0) / 2.5, 1e-5);  // 1.8
	// (5,6): (4,5) w=1/2, (6,5) w=1/2, (6,6) w=1
	EXPECT_NEAR(grid.cell(5, 6).z_idw, (0.5 * 1.0 + 0.5 * 2.0 + 1 * 3.0) / 2.0, 1e-5);  // 2.25
	// min_neighbours respected: (7,6) and (5,4) see only two observed cells.
	EXPECT_TRUE(std::isnan(grid.cell(7, 6).z_idw));
	EXPECT_TRUE(std::isnan(grid.cell(5, 4).z_idw));
	EXPECT_TRUE(std::isnan(grid.cell(0, 0).z_idw));

	// Estimates are never observations.
	EXPECT_EQ(grid.cell(5, 5).count, 0u);
	EXPECT_FALSE(grid.cell(5, 5).observed());
	EXPECT_EQ(grid.observedCount(), 3u);
	EXPECT_NEAR(grid.surfaceHeight(5, 5), 1.8, 1e-5);
	EXPECT_TRUE(std::isnan(grid.surfaceHeight(0, 0)));

	// Observed cells are never overwritten.
	EXPECT_TRUE(std::isnan(grid.cell(4, 5).z_idw));
	EXPECT_EQ(grid.cell(4, 5).count, 1u);
	EXPECT_FLOAT_EQ(grid.surfaceHeight(4, 5), 1.0f);
	EXPECT_FLOAT_EQ(grid.surfaceHeight(6, 6), 3.0f);
}

TEST(ElevationGridIdw, PromotedEstimatesCountTheirValidNeighbours)
{
	// idw_in_ism (the paper's densified map): the two estimates of the test
	// above, 1.8 at (5,5) and 2.25 at (5,6), become observed cells whose N_z is
	// the number of valid neighbour voxels they came from (paper SIV-A): each
	// sees (4,5), (6,5) and (6,6) in its 3 x 3 window, so N_z = 3.
	ElevationGrid grid = makeIdwGrid();
	IdwParams p;
	p.radius_cells = 1;
	p.min_neighbours = 3;
	ASSERT_EQ(grid.interpolateIdw(p), 2u);
	EXPECT_EQ(grid.promoteIdwCells(p.radius_cells), 2u);
	EXPECT_EQ(grid.observedCount(), 5u);
	EXPECT_EQ(grid.cell(5, 5).count, 3u);
	EXPECT_EQ(grid.cell(5, 6).count, 3u);
	EXPECT_FLOAT_EQ(grid.cell(5, 5).variance(), 0.f);
	EXPECT_NEAR(grid.cell(5, 5).z_min, 1.8, 1e-5);
	EXPECT_NEAR(grid.cell(5, 5).z_max, 1.8, 1e-5);
	EXPECT_NEAR(grid.cell(5, 6).mean(), 2.25, 1e-5);
	EXPECT_FLOAT_EQ(grid.cell(5, 6).span(), 0.f);
	// Measured cells are left as they were; a second call adds nothing.
	EXPECT_EQ(grid.cell(4, 5).count, 1u);
	EXPECT_EQ(grid.promoteIdwCells(p.radius_cells), 0u);
	// The next frame starts empty.
	grid.clear();
	EXPECT_EQ(grid.observedCount(), 0u);
	EXPECT_EQ(grid.cell(5, 5).count, 0u);
}

TEST(ElevationGridIdw, FewerNeighboursAndOtherPower)
{
	ElevationGrid grid = makeIdwGrid();
	IdwParams p;
	p.radius_cells = 1;
	p.min_neighbours = 2;
	grid.interpolateIdw(p);
	// (7,6): (6,5) d=sqrt2 w=1/2 z=2, (6,6) d=1 w=1 z=3
	EXPECT_NEAR(grid.cell(7, 6).z_idw, (0.5 * 2.0 + 3.0) / 1.5, 1e-5);
	// (5,4): (4,5), (6,5) both at sqrt2 -> plain mean
	EXPECT_NEAR(grid.cell(5, 4).z_idw, 1.5, 1e-5);

	p.power = 1;
	p.min_neighbours = 3;
	EXPECT_EQ(grid.interpolateIdw(p), 2u);
	const double w = 1.0 / std::sqrt(2.0);
	EXPECT_NEAR(grid.cell(5, 5).z_idw, (1.0 + 2.0 + w * 3.0) / (2.0 + w), 1e-5);
	// The previous run's estimates are forgotten.
	EXPECT_TRUE(std::isnan(grid.cell(7, 6).z_idw));
	EXPECT_TRUE(std::isnan(grid.cell(5, 4).z_idw));

	// radius 0 disables it and forgets everything.
	p.radius_cells = 0;
	EXPECT_EQ(grid.interpolateIdw(p), 0u);
	EXPECT_TRUE(std::isnan(grid.cell(5, 5).z_idw));
}

TEST(ElevationGridIdw, LargerRadiusAndObservationReplacesEstimate)
{
	ElevationGrid grid = makeIdwGrid();
	IdwParams p;
	p.radius_cells = 2;
	p.min_neighbours = 3;
	grid.interpolateIdw(p);
	// (4,7): (4,5) d=2 w=1/4 z=1; (6,5) d=sqrt8 w=1/8 z=2; (6,6) d=sqrt5 w=1/5 z=3
	EXPECT_NEAR(grid.cell(4, 7).z_idw, (0.25 * 1 + 0.125 * 2 + 0.2 * 3) / (0.25 + 0.125 + 0.2), 1e-5);
	// (8,8): only (6,6) (d=sqrt8) within 2 cells
	EXPECT_TRUE(std::isnan(grid.cell(8, 8).z_idw));
	// (3,4) is within reach of (4,5) d=sqrt2 and (6,5)? dx=3 > 2: no. -> NaN
	EXPECT_TRUE(std::isnan(grid.cell(3, 4).z_idw));

	// A real observation in an interpolated cell replaces the estimate.
	gamtest::insertPoints(grid, {{4.5, 7.5, 7.0}});
	EXPECT_EQ(grid.cell(4, 7).count, 1u);
	EXPECT_TRUE(std::isnan(grid.cell(4, 7).z_idw));
	EXPECT_FLOAT_EQ(grid.surfaceHeight(4, 7), 7.0f);
	EXPECT_EQ(grid.observedCount(), 4u);

	// clear() also removes the estimates.
	grid.clear();
	for (const ElevationCell& c : grid.cells())
	{
		EXPECT_EQ(c.count, 0u);
		EXPECT_TRUE(std::isnan(c.z_idw));
	}
}

TEST(ElevationCellTest, VarianceKeepsItsPrecisionTenMetresUp)
{
	// Issue #30: an upper storey in a global map, z = 10 m, 3 mm floor noise.
	// Samples 10 + a, 10 - a (3 of each, a = 0.003): mean 10, every deviation
	// a, so the variance is 6 a^2 / 6 = a^2 = 9e-6 m^2 (std 3 mm). In float,
	// E[z^2] - E[z]^2 = 100.000009 - 100 is below the 7.6e-6 spacing of floats
	// near 100: it came out 7.6e-6 here, and 0 for the cells below.
	const float a = 0.003f;
	ElevationCell c;
	for (int k = 0; k < 3; k++)
	{
		c.add(10.0f + a);
		c.add(10.0f - a);
	}
	EXPECT_NEAR(c.mean(), 10.0, 1e-5);
	EXPECT_NEAR(c.variance(), 9e-6, 1e-8);

	// The same samples in two cells merged (Chan): cell A {10+a, 10+a, 10-a},
	// cell B {10-a, 10-a, 10+a}: means 10 + a/3 and 10 - a/3, each with
	// squared deviations 2 (2a/3)^2 + (4a/3)^2 = 24 a^2 / 9 (variance 8 a^2 / 9);
	// merged: 2 x 24 a^2 / 9 + (2a/3)^2 x 3 x 3 / 6 = 48 a^2 / 9 + 6 a^2 / 9 =
	// 6 a^2, over 6 samples: a^2.
	ElevationCell A, B;
	for (float z : {10.0f + a, 10.0f + a, 10.0f - a}) A.add(z);
	for (float z : {10.0f - a, 10.0f - a, 10.0f + a}) B.add(z);
	EXPECT_NEAR(A.variance(), 24.0 * 9e-6 / 9.0 / 3.0, 1e-8);
	A.merge(B);
	EXPECT_EQ(A.count, 6u);
	EXPECT_NEAR(A.variance(), 9e-6, 1e-8);

	// And through the grid's insertion (the 3-sigma filter's shifted sums).
	ElevationGrid grid(gamtest::makeGeometry(0, 0, 0.05, 4, 4));
	BinnedPoints b;
	for (int k = 0; k < 3; k++)
	{
		grid.binPoint(0.07, 0.07, 10.0f + a, b);
		grid.binPoint(0.07, 0.07, 10.0f - a, b);
	}
	OutlierFilterParams f;
	f.min_count = 4;  // the 3-sigma rule runs on this cell
	EXPECT_EQ(grid.insert(b, f), 6u);
	EXPECT_NEAR(grid.cell(1, 1).variance(), 9e-6, 1e-8);
}

TEST(ElevationGrid, SamplesInMarkedCellsAreListedInOrder)
{
	// Six samples in cells 3 1 3 2 0 3; cells 1 and 3 marked: the samples at
	// 0 (cell 3), 1 (cell 1), 2 (cell 3) and 5 (cell 3), in that order.
	BinnedPoints b;
	for (uint32_t c : {3u, 1u, 3u, 2u, 0u, 3u}) b.push(c, 0.f);
	const uint8_t marked[4] = {0, 1, 0, 7};
	std::vector<uint32_t> out;
	ASSERT_EQ(samplesInMarkedCells(b, marked, out), 4u);
	EXPECT_EQ(std::vector<uint32_t>(out.begin(), out.begin() + 4), (std::vector<uint32_t>{0, 1, 2, 5}));
	// No cell marked: none listed; the buffer is reused, not shrunk.
	const uint8_t none[4] = {0, 0, 0, 0};
	EXPECT_EQ(samplesInMarkedCells(b, none, out), 0u);
	EXPECT_GE(out.size(), 6u);
	// No samples: none listed.
	BinnedPoints empty;
	EXPECT_EQ(samplesInMarkedCells(empty, marked, out), 0u);
}

TEST(ElevationGrid, FewMarkedSkipsBlocksWithoutAMarkedCellButListsTheSame)
{
	// 40 samples: 0-15 in cell 0 (a block of 16 with no marked cell), 20 and
	// 37 in cell 1 (marked; 37 lies in the 8 left over after two blocks), the
	// rest in cell 2. Both ways list samples 20 and 37, in order.
	BinnedPoints b;
	for (uint32_t i = 0; i < 40; i++) b.push(i < 16 ? 0u : (i == 20 || i == 37) ? 1u : 2u, 0.f);
	const uint8_t marked[3] = {0, 1, 0};
	for (bool few : {false, true})
	{
		std::vector<uint32_t> out;
		ASSERT_EQ(samplesInMarkedCells(b, marked, out, few), 2u) << "fewMarked " << few;
		EXPECT_EQ(out[0], 20u);
		EXPECT_EQ(out[1], 37u);
	}
}
