#include "gam/core/MissingFloor.h"

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

namespace gam
{
void MissingFloorParams::validate() const { checkParamRanges(*this, ""); }

namespace missing
{
double emptyCellChance(double q, double p11, int n)
{
	if (n <= 0) return 1.0;
	q = std::clamp(q, 0.0, 1.0);
	const double next = std::max(q, std::min(p11, 1.0));
	return q * std::pow(next, n - 1);
}

bool isStepShadow(double edge, double far, double drop, double height, double slack)
{
	if (!(edge > 0) || !(drop > 0) || !(height > 0)) return false;
	return std::abs((far - edge) * height - drop * edge) <= slack * height;
}

std::pair<int, int> deadBorderColumns(const RangeImageView& img)
{
	// Column by column from each border, every row read (bottom up: the
	// floor's rows return first); the first column with a return ends the
	// band. (A column's pixels lie a stride apart, but a band of k columns
	// reads the same cache lines k times.)
	const auto returns = [&](int c) {
		for (int r = img.rows - 1; r >= 0; r--)
			if (img.at(r, c) != 0) return true;
		return false;
	};
	int left = 0;
	while (left < img.cols && !returns(left)) left++;
	if (left == img.cols) return {img.cols, 0};  // no return at all
	int right = 0;
	while (!returns(img.cols - 1 - right)) right++;
	return {left, right};
}

bool outsideSecondImager(int c, double z, double fxBaseline)
{
	// lround(c - d) < 0, i.e. c - d <= -0.5, without a libm call per pixel.
	return z > 0 && double(c) - fxBaseline / z + 0.5 <= 0.0;
}
}  // namespace missing

void MissingFloorDetector::clear()
{
	for (uint32_t c : m_touched)
	{
		m_empty[c] = 0;
		m_mark[c] = 0;
	}
	m_touched.clear();
	m_cells.clear();
	m_blocking.clear();
	m_p11 = -1;
	std::fill(m_binRays.begin(), m_binRays.end(), 0u);
	std::fill(m_binEmpty.begin(), m_binEmpty.end(), 0u);
}

double MissingFloorDetector::dropoutRate(double depth) const
{
	if (!(depth >= 0)) return 1.0;
	const size_t b = size_t(depth / m_params.range_bin);
	if (b >= m_binRays.size() || m_binRays[b] == 0) return 1.0;
	return double(m_binEmpty[b]) / double(m_binRays[b]);
}

namespace
{
// The rays of the ray table against the ground plane, in the frame grid's
// cell units (see MissingFloorDetector::compute). Float is plenty for a cell
// index; the row loop and the single pixel use the same expressions, so they
// give the same floats.
struct GroundRays
{
	float n0, n1, n2;              ///< the plane's normal in the sensor frame: down = n0 + n1 fy + n2 fz
	float mh;                      ///< minus the sensor's height over the plane (< 0)
	float bx, by;                  ///< the sensor, in cells
	float X0, X1, X2, Y0, Y1, Y2;  ///< rows 0 and 1 of the sensor's rotation, per cell

	/** Where the ray (1, fy, fz) meets the ground: depth t (<= 0 or -inf for
	 * rays parallel to the ground or rising: mh < 0) and the fractional cell
	 * (cx, cy). */
	void meet(float fy, float fz, float& t, float& cx, float& cy) const
	{
		t = mh / (n0 + n1 * fy + n2 * fz);
		cx = bx + t * (X0 + X1 * fy + X2 * fz);
		cy = by + t * (Y0 + Y1 * fy + Y2 * fz);
	}
};

// meet() for a whole row (no branch: the loop vectorizes).
void meetGroundRow(
	const GroundRays& rays, const float* __restrict fy, const float* __restrict fz, int cols, float* __restrict t,
	float* __restrict cx, float* __restrict cy)
{
	const GroundRays g = rays;
	for (int c = 0; c < cols; c++) g.meet(fy[c], fz[c], t[c], cx[c], cy[c]);
}

// The candidates of one image row (see compute(): its candidate()), as a
// vector loop; returns how many.
int candidateRow(
	const GroundRays& rays, float thrDown, const float* __restrict fy, const float* __restrict fz,
	const uint16_t* __restrict raw, int cols, bool statsRow, uint16_t rawInRange, uint8_t* __restrict isCandidate)
{
	const float n0 = rays.n0, n1 = rays.n1, n2 = rays.n2;
	const uint8_t all = statsRow;
	int candidates = 0;
	for (int c = 0; c < cols; c++)
	{
		const bool meets = n0 + n1 * fy[c] + n2 * fz[c] < thrDown;
		isCandidate[c] = uint8_t(meets & (all | (uint16_t(raw[c] - 1) >= rawInRange)));
		candidates += isCandidate[c];
	}
	return candidates;
}

// The pixels of one image row, columns [begin, end), that returned nothing
// within the range (raw 0, or beyond rawInRange), as a list of their columns,
// in order (room for end - begin); returns how many. Most pixels have a
// return: 8 at a time are tested in one vector, and only the empty ones are
// visited.
int emptyColumns(const uint16_t* __restrict raw, int begin, int end, uint16_t rawInRange, int32_t* __restrict list)
{
	int n = 0, c = begin;
#if defined(__SSE2__)
	const __m128i one = _mm_set1_epi16(1), range = _mm_set1_epi16(static_cast<short>(rawInRange)),
				  zero = _mm_setzero_si128();
	for (; c + 8 <= end; c += 8)
	{
		// raw - 1 >= rawInRange (unsigned, 0 wraps to 65535): rawInRange - (raw - 1) saturates at 0.
		const __m128i v = _mm_sub_epi16(_mm_loadu_si128(reinterpret_cast<const __m128i*>(raw + c)), one);
		const __m128i empty = _mm_cmpeq_epi16(_mm_subs_epu16(range, v), zero);
		for (unsigned mask = unsigned(_mm_movemask_epi8(_mm_packs_epi16(empty, zero))); mask; mask &= mask - 1)
			list[n++] = c + __builtin_ctz(mask);
	}
#endif
	for (; c < end; c++)
		if (uint16_t(raw[c] - 1) >= rawInRange) list[n++] = c;
	return n;
}

// The tests of judgeRay() in compute() that need no sample, for a whole
// statistics row of a depth image (a vector loop): which pixels are judged
// (ok), and each one's depth t and frame cell. Float bounds stand
// for judgeRay's double tests exactly: a float t <= maxRange (double) when t
// <= the largest float not above it; int(cx) < nx when cx < nx.
struct JudgeBounds
{
	float thrDown, maxRange, nx, ny;
	int32_t cellsPerRow;
};

void judgeableRow(
	const GroundRays& rays, const JudgeBounds& bounds, const float* __restrict fy, const float* __restrict fz, int cols,
	float* __restrict t, uint8_t* __restrict ok, int32_t* __restrict cell)
{
	const GroundRays g = rays;
	const JudgeBounds b = bounds;
	for (int c = 0; c < cols; c++)
	{
		float tc, cx, cy;
		g.meet(fy[c], fz[c], tc, cx, cy);
		const bool judged = (g.n0 + g.n1 * fy[c] + g.n2 * fz[c] < b.thrDown) & (tc > 0.f) & (tc <= b.maxRange) &
							(cx >= 0.f) & (cy >= 0.f) & (cx < b.nx) & (cy < b.ny);
		// Zeros where not judged: no float-to-int conversion out of range.
		const float x = judged ? cx : 0.f, y = judged ? cy : 0.f;
		t[c] = tc;
		ok[c] = uint8_t(judged);
		cell[c] = int32_t(y) * b.cellsPerRow + int32_t(x);
	}
}

// The range bin of a depth d >= 0, size_t(d / rangeBin), is monotone in d: so
// the bin of a float depth is b exactly where binEdge(b) <= d < binEdge(b + 1),
// with binEdge(b) the smallest float depth whose bin is at least b.
float binEdge(int b, double rangeBin)
{
	const auto binOf = [&](float d) { return double(d) / rangeBin; };
	float f = float(double(b) * rangeBin);
	while (f > 0.f && binOf(std::nextafter(f, 0.f)) >= double(b)) f = std::nextafter(f, 0.f);
	while (binOf(f) < double(b)) f = std::nextafter(f, std::numeric_limits<float>::infinity());
	return f;
}
}  // namespace

void MissingFloorDetector::compute(
	const SensorFrame& frame, const DepthProjector& projector, int decimation, double maxRange, const Plane& ground,
	const ElevationGrid& grid, const std::vector<VoxelClass>& classes, MissingFloorStats& stats,
	const PatchSupport& patches)
{
	clear();
	stats = MissingFloorStats{};
	const GridGeometry& g = grid.geometry();
	const size_t N = g.cellCount();
	if (m_empty.size() != N)
	{
		m_empty.assign(N, 0);
		m_mark.assign(N, 0);
		m_logChance.assign(N, 0.f);
		// Each list holds a cell at most once: reserved to that bound, so no
		// later frame allocates (grown on demand, a pipeline that had seen only
		// a few frames -- one per camera -- still grew them now and then).
		for (std::vector<uint32_t>* v : {&m_touched, &m_cells, &m_blocking, &m_queue, &m_region, &m_component})
			v->reserve(N);
		// A cell's ring around a sensor within the grid: at most its diagonal.
		const size_t rings = size_t(std::ceil(std::hypot(double(g.nx), double(g.ny)))) + 2;
		m_ringRays.assign(rings, 0u);
		m_ringEmpty.assign(rings, 0u);
	}
	if (!frame.has_image || classes.size() != N || !(maxRange > 0)) return;
	const RangeImageView& img = frame.image;
	const PinholeIntrinsics& K = frame.intrinsics;
	if (projector.rayTableSize() != size_t(K.width) * size_t(K.height) || img.rows != K.height || img.cols != K.width)
		return;
	const size_t bins = size_t(std::ceil(maxRange / m_params.range_bin)) + 1;
	if (m_binRays.size() < bins)
	{
		m_binRays.resize(bins, 0u);
		m_binEmpty.resize(bins, 0u);
	}

	// The plane in the map frame, normalized: n.p + d = 0, n pointing up.
	Eigen::Vector3d n(ground.a, ground.b, ground.c);
	double d = ground.d;
	const double nn = n.norm();
	if (!(nn > 0)) return;
	n /= nn;
	d /= nn;
	if (n.z() < 0)
	{
		n = -n;
		d = -d;
	}
	const Eigen::Vector3d s = frame.sensor_position;
	const double h = n.dot(s) + d;  // sensor height over the plane
	if (!(h > 0)) return;
	const Eigen::Matrix3d R = frame.sensor_to_map.R.cast<double>();
	// The ray of pixel (r, c) is R (1, fy, fz): its component along n, per
	// unit of depth, is n.R (1, fy, fz) = nr.(1, fy, fz).
	const Eigen::Vector3d nr = R.transpose() * n;
	const float units = img.units;
	const int step = std::max(1, decimation);
	// Depth from disparity: pixels in the second imager's invalid band return
	// nothing whatever lies there (range images: not applied).
	const double fxBaseline = img.is_depth ? K.fx * m_baseline : 0.0;
	// Disparity [px] of a raw depth u: fbf / u (hiddenFromSecondImager).
	const double fbu = fxBaseline / double(units);
	const float fbf = float(fbu);

	// 1. Every pixel whose ray meets the ground inside the range: one ray of
	// the cell it meets; empty if the camera returned nothing there. Along
	// each row, pairs of neighbours that both meet seen floor give p11.
	size_t pairsAfterEmpty = 0, pairsBothEmpty = 0;
	const int cols = img.cols;
	// Per ray (1, fy, fz): down = nr.(1, fy, fz), t = -h / down, and the map
	// point s + t R (1, fy, fz), as fractional cell indices.
	GroundRays rays;
	rays.n0 = float(nr.x());
	rays.n1 = float(nr.y());
	rays.n2 = float(nr.z());
	rays.mh = float(-h);
	const float invRes = float(1.0 / g.resolution);
	rays.bx = float((s.x() - g.x_min) / g.resolution);
	rays.by = float((s.y() - g.y_min) / g.resolution);
	rays.X0 = float(R(0, 0)) * invRes;
	rays.X1 = float(R(0, 1)) * invRes;
	rays.X2 = float(R(0, 2)) * invRes;
	rays.Y0 = float(R(1, 0)) * invRes;
	rays.Y1 = float(R(1, 1)) * invRes;
	rays.Y2 = float(R(1, 2)) * invRes;
	const float n0 = rays.n0, n1 = rays.n1, n2 = rays.n2, mh = rays.mh;
	// A return within the range is never an empty ray: raw values 1..rawInRange
	// are exactly those with double(v) * units <= maxRange (monotone in v).
	uint16_t rawInRange = uint16_t(std::min(65535.0, std::floor(maxRange / double(units))));
	while (rawInRange < 65535 && double(rawInRange + 1) * units <= maxRange) rawInRange++;
	while (rawInRange > 0 && double(rawInRange) * units > maxRange) rawInRange--;
	// A ray meets the ground within the range only where down < thrDown:
	// elsewhere t = mh / down is <= 0 (down >= 0) or, for mh / maxRange <= down
	// < 0, beyond the range (with a margin far above the round-off of t). The
	// test needs no division, so a vector loop clears most pixels.
	const float thrDown = float(double(mh) / maxRange * (1.0 - 1e-4));
	if (m_rowCandidate.size() < size_t(cols))
	{
		m_rowCandidate.resize(size_t(cols));
		m_rowT.resize(size_t(cols));
		m_rowCx.resize(size_t(cols));
		m_rowCy.resize(size_t(cols));
		m_rowCell.resize(size_t(cols));
	}
	// judgeRay()'s double tests as float bounds (see JudgeBounds).
	JudgeBounds bounds;
	bounds.thrDown = thrDown;
	bounds.maxRange = float(maxRange);
	if (double(bounds.maxRange) > maxRange) bounds.maxRange = std::nextafter(bounds.maxRange, 0.f);
	bounds.nx = float(g.nx);
	bounds.ny = float(g.ny);
	bounds.cellsPerRow = g.nx;

	// Whether every ray of a row meets the ground within the range (down <
	// thrDown), none does, or some do: down = n0 + n1 fy + n2 fz over the
	// row's box of (fy, fz), in double, with a margin of 1e-5 of the terms'
	// size (the float sum of three products is off by a few 1e-7 of it).
	enum class RowRays
	{
		Meet,
		None,
		Some
	};
	const auto rowRays = [&](const DepthProjector::RayBounds& b) {
		const double a1 = double(n1) * b.y_min, b1 = double(n1) * b.y_max;
		const double a2 = double(n2) * b.z_min, b2 = double(n2) * b.z_max;
		const double lo = double(n0) + std::min(a1, b1) + std::min(a2, b2);
		const double hi = double(n0) + std::max(a1, b1) + std::max(a2, b2);
		const double margin =
			1e-5 * (std::abs(double(n0)) + std::max(std::abs(a1), std::abs(b1)) + std::max(std::abs(a2), std::abs(b2)));
		if (hi + margin < double(thrDown)) return RowRays::Meet;
		if (lo - margin >= double(thrDown)) return RowRays::None;
		return RowRays::Some;
	};
	// The pixels judged: the columns [liveBegin, liveEnd), all but the dead
	// bands at the image's left and right borders (deadBorderColumns).
	const std::pair<int, int> dead = missing::deadBorderColumns(img);
	stats.dead_border_columns = size_t(dead.first + dead.second);
	const int liveBegin = dead.first, liveEnd = std::max(liveBegin, cols - dead.second), liveCols = liveEnd - liveBegin;
	// A decimated row's pixels are its columns 0, step, 2 step, ...
	const int firstDecimated = (liveBegin + step - 1) / step * step;
	size_t rayCount = 0, emptyCount = 0;  // stats.rays and stats.empty_rays, counted in registers
	for (int r = 0; r < img.rows && liveCols > 0; r += step)
	{
		const float* __restrict fyRow = projector.rayYRow(r);
		const float* __restrict fzRow = projector.rayZRow(r);
		const uint16_t* __restrict raw = img.data + size_t(r) * img.stride;
		int prev = 0;  // previous pixel of the row: 0 none, 1 seen floor, 2 empty on seen floor
		const bool statsRow = (r / step) % m_params.stats_row_step == 0;
		// Whether the second imager's view of an empty pixel is hidden by a
		// nearer surface of this row: a point at column k and disparity d_k
		// lands at lround(k - d_k) there, the largest disparity reaching a
		// column hides the others (a z-buffer, as the stereo matcher sees it).
		// Only pixels k with d_k > d + 0.5 hide the pixel's column x =
		// lround(c - d), and they lie in k <= x + 0.5 + d_max: a short scan
		// right of c, bounded by the row's largest disparity (its nearest
		// return, found once), that compares raw depths and divides only
		// for the pixels near enough.
		float rowMaxDisparity = -1.f;  // the row's largest disparity (0: no return), found at first use
		const auto hiddenFromSecondImager = [&](int c, double t) {
			if (rowMaxDisparity < 0.f)
			{
				uint16_t nearest = 65535;  // the smallest raw depth - 1 (0: no return, skipped)
				for (int k = 0; k < cols; k++) nearest = std::min<uint16_t>(nearest, uint16_t(raw[k] - 1));
				rowMaxDisparity = nearest == 65535 ? 0.f : fbf / float(nearest + 1);
			}
			const double d = fxBaseline / t;
			const long x = std::lround(double(c) - d);
			if (x < 0 || x >= cols || !(double(rowMaxDisparity) > d + 0.5)) return false;
			// d_k > d + 0.5 needs u_k < fbu / (d + 0.5): raw depths at or beyond
			// the bound (two units of margin over the float division) cannot.
			const double uBound = fbu / (d + 0.5) + 2.0;
			const long kEnd = std::min<long>(cols - 1, x + 1 + long(std::ceil(rowMaxDisparity)));
			for (long k = std::max(0L, long(c) - 1); k <= kEnd; k++)
			{
				const uint16_t u = raw[k];
				if (u == 0 || double(u) >= uBound) continue;
				const float dk = fbf / float(u);
				if (double(dk) > d + 0.5 && std::lround(float(k) - dk) == x) return true;
			}
			return false;
		};
		// (The bounds hold for every n-th pixel of a decimated row too.)
		const RowRays rowAll = rowRays(projector.rowRayBounds(r));
		if (rowAll == RowRays::None) continue;  // no ray meets the ground within the range: no candidate
		// A pixel whose ray meets the ground within the range at depth t
		// (`expected` in the image's own measure) in frame cell `cell`; the
		// previous pixel of the row was in state `before`. Counts the ray and,
		// if it came back empty, the cell's empty rays; returns the pixel's
		// state (0 none, 1 seen floor, 2 empty on seen floor).
		const auto countRay = [&](int c, double t, double expected, uint32_t cell, int before) {
			const uint16_t v = raw[c];
			if (v == 0 && fxBaseline > 0 &&
				(missing::outsideSecondImager(c, t, fxBaseline) || hiddenFromSecondImager(c, t)))
				return 0;
			// (v > rawInRange: a return beyond the range, see rawInRange.)
			const bool empty = v == 0 || (v > rawInRange && double(v) * units > expected + m_params.beyond_margin);
			rayCount += statsRow;
			emptyCount += empty;
			int now = 0;
			// (The ISM classified every cell this frame observed: its class,
			// a byte, says what the cell's count says, 24 bytes each.)
			if (statsRow && classes[cell] != VoxelClass::None)
			{
				// Seen floor (or whatever was seen there): its dropouts are the
				// camera's, not a hole's.
				const size_t bin = size_t(expected / m_params.range_bin);
				m_binRays[bin]++;
				if (empty) m_binEmpty[bin]++;
				now = empty ? 2 : 1;
				if (before == 2)
				{
					pairsAfterEmpty++;
					if (empty) pairsBothEmpty++;
				}
			}
			if (empty)
			{
				if (m_empty[cell] == 0) m_touched.push_back(cell);
				if (m_empty[cell] < 65535) m_empty[cell]++;
			}
			return now;
		};
		// One pixel whose ray may meet the ground within the range, at depth
		// tf in cell (cxf, cyf): the tests, then countRay(). (The statistics
		// rows of depth images run the tests for a whole row at once.)
		const auto judgeRay = [&](int c, float tf, float cxf, float cyf) {
			const int before = prev;
			prev = 0;
			const double t = tf;
			// (A range along the ray is >= the depth t: t beyond the range is too.)
			if (!(t > 0) || t > maxRange) return;
			double expected = t;  // in the image's own measure
			if (!img.is_depth)
			{
				const double fy = fyRow[c], fz = fzRow[c];
				expected = t * std::sqrt(1.0 + fy * fy + fz * fz);
			}
			if (expected > maxRange) return;
			if (!(cxf >= 0.f && cyf >= 0.f)) return;
			const int cx = int(cxf), cy = int(cyf);
			if (cx >= g.nx || cy >= g.ny) return;
			prev = countRay(c, t, expected, uint32_t(g.index(cx, cy)), before);
		};
		// The candidates: rays that may meet the ground within the range and,
		// outside the statistics rows (where only empty rays matter), that
		// are empty: no return, or one beyond the range.
		const auto candidate = [&](int c) {
			const bool meets = n0 + n1 * fyRow[c] + n2 * fzRow[c] < thrDown;
			return uint8_t(meets & (statsRow | (uint16_t(raw[c] - 1) >= rawInRange)));
		};
		const auto judgeOne = [&](int c) {
			float t, cxf, cyf;
			rays.meet(fyRow[c], fzRow[c], t, cxf, cyf);
			judgeRay(c, t, cxf, cyf);
		};
		if (step != 1)
		{
			// Where every ray meets the ground, candidate(c) is statsRow or an
			// empty pixel: no ray to read.
			const bool allMeet = rowAll == RowRays::Meet;
			for (int c = firstDecimated; c < liveEnd; c += step)
				if (allMeet ? statsRow || uint16_t(raw[c] - 1) >= rawInRange : bool(candidate(c)))
					judgeOne(c);
				else
					prev = 0;
			continue;
		}
		uint8_t* __restrict isCandidate = m_rowCandidate.data();
		if (statsRow && img.is_depth)
		{
			// A statistics row of a depth image: most of its pixels meet seen
			// floor. The tests of judgeRay() that need no sample run for the
			// whole row in one vector loop (judgeableRow); then countRay()'s
			// tests and counts in one loop with every count in a register
			// (countRay() per pixel, its counters in memory and a division for
			// the range bin, cost 18 cycles a pixel, 2026-11-27; this loop
			// takes the stage down by 12-32 %, speed-and-memory.md). The tests
			// are written out again here, not shared with countRay() as
			// lambdas: shared, the stage took 5-10 % longer (2026-11-28).
			judgeableRow(
				rays, bounds, fyRow + liveBegin, fzRow + liveBegin, liveCols, m_rowT.data() + liveBegin,
				isCandidate + liveBegin, m_rowCell.data() + liveBegin);
			const float* __restrict T = m_rowT.data();
			const int32_t* __restrict cellOf = m_rowCell.data();
			const VoxelClass* __restrict cls = classes.data();
			const double beyondMargin = m_params.beyond_margin, rangeBin = m_params.range_bin;
			size_t judged = 0, empty = 0, afterEmpty = 0, bothEmpty = 0;
			uint32_t state = 0;  // the previous pixel's, as countRay()'s: 0 none, 1 seen floor, 2 empty on seen floor
			// The dropout rate per range bin, on seen floor: a row's rays meet
			// the ground in one or two bins, so the bin's counts run in
			// registers until a depth leaves its edges (binEdge).
			int32_t runBin = -1;
			float runLo = 1.f, runHi = 0.f;
			uint32_t runRays = 0, runEmpty = 0;
			for (int c = liveBegin; c < liveEnd; c++)
			{
				const uint16_t v = raw[c];
				// Not judged, or (countRay()'s first test) no return where the
				// second imager could not have seen the point: no ray.
				if (!isCandidate[c] || (v == 0 && fxBaseline > 0 &&
										(missing::outsideSecondImager(c, double(T[c]), fxBaseline) ||
										 hiddenFromSecondImager(c, double(T[c])))))
				{
					state = 0;
					continue;
				}
				bool isEmpty = v == 0;
				// (A return beyond the range: rare, and the only test in double.)
				if (v > rawInRange) isEmpty = double(v) * units > double(T[c]) + beyondMargin;
				judged++;
				empty += isEmpty;
				if (isEmpty)
				{
					const uint32_t cell = uint32_t(cellOf[c]);
					if (m_empty[cell] == 0) m_touched.push_back(cell);
					if (m_empty[cell] < 65535) m_empty[cell]++;
				}
				// Seen floor (or whatever was seen there): its dropouts are
				// the camera's, not a hole's.
				const bool onSeen = cls[cellOf[c]] != VoxelClass::None;
				if (state == 2)
				{
					afterEmpty += onSeen;
					bothEmpty += onSeen & isEmpty;
				}
				state = uint32_t(onSeen) << uint32_t(isEmpty);
				if (onSeen & !(T[c] >= runLo && T[c] < runHi))
				{
					if (runBin >= 0)
					{
						m_binRays[size_t(runBin)] += runRays;
						m_binEmpty[size_t(runBin)] += runEmpty;
					}
					runBin = int32_t(double(T[c]) / rangeBin);
					runLo = binEdge(runBin, rangeBin);
					runHi = binEdge(runBin + 1, rangeBin);
					runRays = runEmpty = 0;
				}
				runRays += onSeen;
				runEmpty += onSeen & isEmpty;
			}
			if (runBin >= 0)
			{
				m_binRays[size_t(runBin)] += runRays;
				m_binEmpty[size_t(runBin)] += runEmpty;
			}
			rayCount += judged;
			emptyCount += empty;
			pairsAfterEmpty += afterEmpty;
			pairsBothEmpty += bothEmpty;
			continue;
		}
		// Where every ray of the row meets the ground within the range
		// (rowRays), outside the statistics rows only its empty pixels are
		// candidates: found from the depths alone, without reading the ray
		// table (8 bytes a pixel), as a list of their columns (m_rowCell is
		// free outside the statistics rows). Other rows mark theirs in
		// isCandidate.
		const bool listEmpty = rowAll == RowRays::Meet && !statsRow;
		int32_t* emptyCols = m_rowCell.data();
		const int candidates = listEmpty ? emptyColumns(raw, liveBegin, liveEnd, rawInRange, emptyCols)
										 : candidateRow(
											   rays, thrDown, fyRow + liveBegin, fzRow + liveBegin, raw + liveBegin,
											   liveCols, statsRow, rawInRange, isCandidate + liveBegin);
		// Where the rays meet the ground: in a vector loop for the whole row
		// where candidates are many (a statistics row, a row of dropouts),
		// else one candidate at a time.
		const bool wholeRow = 8 * candidates > liveCols;
		if (wholeRow)
			meetGroundRow(
				rays, fyRow + liveBegin, fzRow + liveBegin, liveCols, m_rowT.data() + liveBegin,
				m_rowCx.data() + liveBegin, m_rowCy.data() + liveBegin);
		const float* T = m_rowT.data();
		const float* CX = m_rowCx.data();
		const float* CY = m_rowCy.data();
		const auto judge = [&](int c) {
			if (wholeRow)
				judgeRay(c, T[c], CX[c], CY[c]);
			else
				judgeOne(c);
		};
		if (listEmpty && img.is_depth)
		{
			// judgeRay() and countRay() written out for a depth image's listed
			// pixels outside the statistics rows (prev stays 0 there, no ray is
			// counted, the depth is the expected range): one loop, no calls.
			const double beyondMargin = m_params.beyond_margin;
			for (int i = 0; i < candidates; i++)
			{
				const int c = emptyCols[i];
				float tf, cxf, cyf;
				if (wholeRow)
				{
					tf = T[c];
					cxf = CX[c];
					cyf = CY[c];
				}
				else
					rays.meet(fyRow[c], fzRow[c], tf, cxf, cyf);
				const double t = tf;
				if (!(t > 0) || t > maxRange || !(cxf >= 0.f && cyf >= 0.f)) continue;
				const int cx = int(cxf), cy = int(cyf);
				if (cx >= g.nx || cy >= g.ny) continue;
				const uint16_t v = raw[c];
				if (v == 0 && fxBaseline > 0 &&
					(missing::outsideSecondImager(c, t, fxBaseline) || hiddenFromSecondImager(c, t)))
					continue;
				if (v != 0 && !(v > rawInRange && double(v) * units > t + beyondMargin)) continue;
				emptyCount++;
				const uint32_t cell = uint32_t(g.index(cx, cy));
				if (m_empty[cell] == 0) m_touched.push_back(cell);
				if (m_empty[cell] < 65535) m_empty[cell]++;
			}
			continue;
		}
		if (listEmpty)
		{
			// (prev stays 0 outside the statistics rows: countRay() returns 0 there.)
			for (int i = 0; i < candidates; i++) judge(emptyCols[i]);
			continue;
		}
		// They are few: skip eight pixels without one at a time.
		int c = liveBegin;
		for (; c + 8 <= liveEnd; c += 8)
		{
			uint64_t eight;
			std::memcpy(&eight, isCandidate + c, 8);
			if (!eight)
			{
				prev = 0;
				continue;
			}
			for (int j = c; j < c + 8; j++)
				if (isCandidate[j])
					judge(j);
				else
					prev = 0;
		}
		for (; c < liveEnd; c++)
			if (isCandidate[c])
				judge(c);
			else
				prev = 0;
	}
	stats.rays = rayCount;
	stats.empty_rays = emptyCount;
	if (pairsAfterEmpty) m_p11 = double(pairsBothEmpty) / double(pairsAfterEmpty);

	// 2. Candidate cells: nothing was seen there, and floor with the dropout
	// rate measured at that range would rarely leave so many rays empty.
	// Cells whose own rays are too few for that are weak candidates, judged
	// together with the weak cells connected to them (step 3).
	const bool pool = m_params.step_shadows;
	const Eigen::Vector3d xAxis = R.col(0);
	// The ground point of (x, y) and its depth (range for range images).
	const auto groundPoint = [&](double x, double y) {
		return Eigen::Vector3d(x, y, -(n.x() * x + n.y() * y + d) / n.z());
	};
	const auto depthOf = [&](const Eigen::Vector3d& p) { return img.is_depth ? (p - s).dot(xAxis) : (p - s).norm(); };
	for (uint32_t cell : m_touched)
	{
		const int n_ = m_empty[cell];
		if (n_ < m_params.min_rays || grid.cell(cell).count > 0 || classes[cell] != VoxelClass::None) continue;
		const int cx = int(cell % uint32_t(g.nx)), cy = int(cell / uint32_t(g.nx));
		const double x = g.cx(cx), y = g.cy(cy);
		if (std::abs(n.z()) < 1e-9) continue;
		const double depth = depthOf(groundPoint(x, y));
		const double chance = missing::emptyCellChance(dropoutRate(depth), m_p11, n_);
		if (chance > m_params.alpha)
		{
			if (pool && chance < 1.0)
			{
				m_mark[cell] = kWeak;
				m_logChance[cell] = float(std::log(chance));
			}
			continue;
		}
		m_mark[cell] = kCandidate;
		stats.candidates++;
	}

	// 3. Connected regions of candidates (8-neighbours) with seen floor next
	// to them along the rays both nearer to the sensor and farther away: a gap
	// inside the floor. A gap with no floor beyond it is where the returns stop (a range
	// cutoff, the edge of the view); one with no floor before it is where they
	// start (the robot's own body, the near limit).
	const double block2 = m_params.block_range * m_params.block_range;
	const auto dist2 = [&](int cx, int cy) {
		const double dx = g.cx(cx) - s.x(), dy = g.cy(cy) - s.y();
		return dx * dx + dy * dy;
	};
	// Pooled evidence: a region of weak candidates is missing floor when the
	// chance that floor leaves all of its rays empty is below alpha / (the
	// cells judged): the product of its cells' chances, its exponent divided
	// by the expected length of a run of empty rays along a row, 1 / (1 -
	// p11), as the rows of a region may drop out together as the pixels of
	// a row do. Only the shadow of a step down is judged so (stepShadow).
	const double sensorHeight = n.dot(s) + d;
	const double logAlphaPooled = std::log(m_params.alpha / double(std::max<size_t>(1, m_touched.size())));
	// Whether the ray from the sensor through a gap to cell a (a surface
	// below the ground plane, beyond the gap) is the shadow of a step down
	// (missing::isStepShadow): back along the ray, the gap (no sample) must
	// start at seen floor, the edge. A drop from a ramp or landing patch is
	// judged against that patch, not the ground plane (no cell there is
	// missing floor, see compute()).
	// (ex, ey: the ray's unit direction.)
	const auto stepShadow = [&](double ex, double ey, int ax, int ay) {
		const size_t a = g.index(ax, ay);
		if (patches.applies(uint32_t(a))) return false;
		const double drop = -(n.x() * g.cx(ax) + n.y() * g.cy(ay) + n.z() * double(grid.cell(a).z_max) + d);
		if (!(drop > 0)) return false;
		const double fx = g.cx(ax) - s.x(), fy = g.cy(ay) - s.y();
		const double far = std::sqrt(fx * fx + fy * fy);
		const double slack = 2 * g.resolution;
		for (int step = 1;; step++)
		{
			const double r = far - step * g.resolution;
			// Stop once the gap is longer than any edge's shadow there.
			if (r <= 0 || (far - r - slack) * sensorHeight > drop * r) return false;
			const int bx = g.ix(s.x() + r * ex), by = g.iy(s.y() + r * ey);
			if (!g.inside(bx, by)) return false;
			const size_t b = g.index(bx, by);
			if (classes[b] == VoxelClass::Ground) return missing::isStepShadow(r, far, drop, sensorHeight, slack);
			// More of the lower surface, or the gap; anything else ends it.
			if (grid.cell(b).count > 0 && classes[b] != VoxelClass::Drop) return false;
		}
	};
	// Rule MF11: a step's shadow whose lower surface lies beyond the range
	// (the rays over the edge return nothing at all). A cell's ground
	// depth, and whether a pixel of the image looks at a point.
	// For a depth image the ground point's depth is affine in (x, y): the
	// plane's z is, and so is the dot product with the camera's axis.
	const double zx = -n.x() / n.z(), zy = -n.y() / n.z(), z0 = -d / n.z();
	const double depthX = xAxis.x() + zx * xAxis.z(), depthY = xAxis.y() + zy * xAxis.z();
	const double depth0 = (z0 - s.z()) * xAxis.z() - s.x() * xAxis.x() - s.y() * xAxis.y();
	const auto cellDepth = [&](uint32_t c) {
		const double x = g.cx(int(c % uint32_t(g.nx))), y = g.cy(int(c / uint32_t(g.nx)));
		return img.is_depth ? depthX * x + depthY * y + depth0 : depthOf(groundPoint(x, y));
	};
	const auto inImage = [&](const Eigen::Vector3d& p) {
		const Eigen::Vector3d q = R.transpose() * (p - s);
		if (!(q.x() > 0)) return false;
		const double u = K.cx - K.fx * q.y() / q.x(), v = K.cy - K.fy * q.z() / q.x();
		// (The live columns: a dead band at a border is no view.)
		return u >= liveBegin - 0.5 && u <= liveEnd - 0.5 && v >= -0.5 && v <= K.height - 0.5;
	};
	const auto horizontalDist = [&](uint32_t c) {
		return std::sqrt(dist2(int(c % uint32_t(g.nx)), int(c / uint32_t(g.nx))));
	};
	// Only a region that comes near the end of the range (or of the grid)
	// can run to it: the walks below are for those.
	const int nearEnd = 5;
	const auto nearRangeEnd = [&](const std::vector<uint32_t>& region) {
		for (uint32_t c : region)
		{
			const int cx = int(c % uint32_t(g.nx)), cy = int(c / uint32_t(g.nx));
			if (cx < nearEnd || cy < nearEnd || cx >= g.nx - nearEnd || cy >= g.ny - nearEnd ||
				cellDepth(c) > maxRange - nearEnd * g.resolution)
				return true;
		}
		return false;
	};
	// Its evidence: the region's cells nearer than where depth noise may
	// carry floor returns beyond the range, judged against the dropout rate
	// of every ray at the same distance from the sensor, the region's own
	// included (a floor cell holds a sample per returning ray): near the end
	// of a time-of-flight camera's range the floor drops out with its
	// incidence, which grows along a range bin and towards the image's sides
	// (the simulated Kinect One drops 58 % of the floor's pixels 4.0 m ahead,
	// 71 % 4.9 m away to the side), and where the range's end cuts off the
	// floor across the view, every ray there is empty (no evidence). And
	// the region was picked as a connected cluster of empty cells
	// among many: the chance that dropping-out floor leaves some cluster of
	// k cells empty around a given cell is at most (e (8 - 1))^(k - 1) times
	// that of one given cluster (the lattice animals of a graph of degree 8),
	// so each cell's chance counts e * 7 = 19 times. A hole at the end of a
	// D455's range (q = 0.40, 4-5 rays a cell: 0.016 a cell) stays evidence;
	// a cluster of the Kinect One's dropouts there (q = 0.6: 0.13) does not.
	bool ringsFilled = false;
	const auto rangeEndEvidence = [&](const std::vector<uint32_t>& region) {
		if (!ringsFilled)
		{
			// Rays and empty rays per ring (one cell wide) around the sensor:
			// floor cells' samples and empty rays, and the empty rays of cells
			// where nothing was seen.
			std::fill(m_ringRays.begin(), m_ringRays.end(), 0u);
			std::fill(m_ringEmpty.begin(), m_ringEmpty.end(), 0u);
			const auto add = [&](uint32_t c, uint32_t rays) {
				const size_t ring = size_t(horizontalDist(c) / g.resolution);
				if (ring >= m_ringRays.size()) return;
				m_ringRays[ring] += rays;
				m_ringEmpty[ring] += m_empty[c];
			};
			for (uint32_t c : grid.observedCells())
				if (classes[c] == VoxelClass::Ground) add(c, grid.cell(c).count + m_empty[c]);
			for (uint32_t c : m_touched)
				if (grid.cell(c).count == 0) add(c, m_empty[c]);
			ringsFilled = true;
		}
		double lo = std::numeric_limits<double>::infinity(), hi = 0;
		for (uint32_t c : region)
			if (cellDepth(c) <= maxRange - m_rangeEndMargin)
			{
				lo = std::min(lo, horizontalDist(c));
				hi = std::max(hi, horizontalDist(c));
			}
		if (!(hi > 0)) return 0.0;
		uint64_t rays = 0, empty = 0;
		const size_t r0 = size_t(std::max(0.0, lo / g.resolution - 1)), r1 = size_t(hi / g.resolution + 1);
		for (size_t r = r0; r <= r1 && r < m_ringRays.size(); r++)
		{
			rays += m_ringRays[r];
			empty += m_ringEmpty[r];
		}
		if (rays == 0) return 0.0;
		const double q = double(empty) / double(rays);
		const double logAnimals = std::log(std::exp(1.0) * 7.0);
		double logChance = 0;
		for (uint32_t c : region)
			if (cellDepth(c) <= maxRange - m_rangeEndMargin)
				logChance += logAnimals + std::log(std::max(missing::emptyCellChance(q, m_p11, m_empty[c]), 1e-300));
		return logChance;
	};
	// Whether at least min_rays rays of the region are a step's shadow that
	// runs to the end of the range. Back along the ray, through cells where
	// nothing was seen, seen floor (the edge; not under a ramp patch), and
	// from there to the sensor the ray passes above everything seen: it met
	// nothing before the gap (a surface it grazes there, as a ramp's way
	// down or a table's top, drops out on its own). On along the ray,
	// through cells where nothing was seen and within the image, the end of
	// the range (or of the grid, the map's own reach).
	const auto runsToRangeEnd = [&](const std::vector<uint32_t>& region) {
		int rays = 0;
		for (uint32_t c : region)
		{
			const double x0 = g.cx(int(c % uint32_t(g.nx))), y0 = g.cy(int(c / uint32_t(g.nx)));
			const double ux = x0 - s.x(), uy = y0 - s.y();
			const double len = std::sqrt(ux * ux + uy * uy);
			if (!(len > 0)) continue;
			// On along the ray first (a few cells to the end of the range, or a
			// seen cell), then back to the sensor.
			bool toEnd = false;
			for (int step = 1;; step++)
			{
				const double k = step * g.resolution / len;
				const double x = x0 + k * ux, y = y0 + k * uy;
				const int ax = g.ix(x), ay = g.iy(y);
				const bool inGrid = g.inside(ax, ay);
				if (inGrid && grid.cell(g.index(ax, ay)).count > 0) break;  // seen: not the range's end
				const Eigen::Vector3d p = groundPoint(x, y);
				if (!inImage(p)) break;  // the edge of the view
				if (!inGrid || depthOf(p) > maxRange - g.resolution)
				{
					toEnd = true;
					break;
				}
			}
			if (!toEnd) continue;
			bool edge = false, clear = true;
			for (int step = 1; clear && step * g.resolution < len; step++)
			{
				const double k = -step * g.resolution / len;
				const double x = x0 + k * ux, y = y0 + k * uy;
				const int bx = g.ix(x), by = g.iy(y);
				if (!g.inside(bx, by)) break;
				const size_t b = g.index(bx, by);
				const ElevationCell& cb = grid.cell(b);
				if (cb.count == 0) continue;
				if (!edge)
				{
					edge = classes[b] == VoxelClass::Ground && !patches.applies(uint32_t(b));
					clear = edge;
				}
				// The ray's height over the ground here, against the cell's top.
				const double rayHeight = sensorHeight * step * g.resolution / len;
				if (n.x() * x + n.y() * y + n.z() * double(cb.z_max) + d >= rayHeight) clear = false;
			}
			if (edge && clear && ++rays >= m_params.min_rays) return true;
		}
		return false;
	};
	// A step's shadow at the end of the range holds cells that count alone
	// and cells that do not (fewer rays): it is judged as one, the connected
	// component of the candidates of both kinds nearer than the range's
	// noisy end (where the range cuts the floor off along its whole arc,
	// which would join unrelated gaps; those cells stay unknown), from `seed`.
	// Each component is judged once a frame (its cells marked kJudged).
	const auto gatherComponent = [&](uint32_t seed) {
		m_component.clear();
		m_component.push_back(seed);
		m_mark[seed] |= kJudged;
		for (size_t qi = 0; qi < m_component.size(); qi++)
		{
			const int cx = int(m_component[qi] % uint32_t(g.nx)), cy = int(m_component[qi] / uint32_t(g.nx));
			for (int dy = -1; dy <= 1; dy++)
				for (int dx = -1; dx <= 1; dx++)
				{
					const int ax = cx + dx, ay = cy + dy;
					if ((!dx && !dy) || !g.inside(ax, ay)) continue;
					const uint32_t a = uint32_t(g.index(ax, ay));
					const uint8_t m = m_mark[a];
					if ((m & (kCandidate | kWeak)) && !(m & (kMissing | kJudged)) &&
						cellDepth(a) <= maxRange - m_rangeEndMargin)
					{
						m_mark[a] |= kJudged;
						m_component.push_back(a);
					}
				}
		}
	};
	const double nextP = std::clamp(m_p11, 0.0, 1.0 - 1e-9);
	// Marks a kept region's cells missing (but where a ramp or landing patch
	// applies: judged against the wrong surface, see compute()'s comment).
	const auto markMissing = [&](const std::vector<uint32_t>& region) {
		for (uint32_t c : region)
		{
			if (patches.applies(c))
			{
				stats.under_patches++;
				continue;
			}
			m_mark[c] = kMissing;
			m_cells.push_back(c);
			if (dist2(int(c % uint32_t(g.nx)), int(c / uint32_t(g.nx))) <= block2)
			{
				m_mark[c] |= kBlocking;
				m_blocking.push_back(c);
			}
		}
	};
	for (uint32_t seed : m_touched)
	{
		// (kJudged: a component judged as a step's shadow that runs to the
		// end of the range; no part of a region's own judgement.)
		const uint8_t kind = m_mark[seed] & uint8_t(~kJudged);
		if (kind != kCandidate && kind != kWeak) continue;
		m_region.clear();
		m_queue.clear();
		m_queue.push_back(seed);
		m_mark[seed] |= kVisited;
		bool nearer = false, farther = false;
		double logChance = 0;
		int shadowRays = 0;  // rays of the region that are a step's shadow
		for (size_t qi = 0; qi < m_queue.size(); qi++)
		{
			const uint32_t c = m_queue[qi];
			m_region.push_back(c);
			const int cx = int(c % uint32_t(g.nx)), cy = int(c / uint32_t(g.nx));
			// The first cell nearer and the first one farther along the ray
			// from the sensor through this cell that a ray reached (far away
			// the pixel rows are sparser than the cells: skip up to 3 cells
			// no ray met).
			const double ux = g.cx(cx) - s.x(), uy = g.cy(cy) - s.y();
			const double len = std::sqrt(ux * ux + uy * uy);
			if (len > 0)
				for (int side : {-1, 1})
					for (int step = 1; step <= 4; step++)
					{
						const double k = side * step * g.resolution / len;
						const int ax = g.ix(g.cx(cx) + k * ux), ay = g.iy(g.cy(cy) + k * uy);
						if (!g.inside(ax, ay)) break;
						const size_t a = g.index(ax, ay);
						if (a == c) continue;
						// Beyond the gap, the floor, or (in a step's shadow) the
						// surface below the step.
						const bool floorBeyond = classes[a] == VoxelClass::Ground;
						const bool stepBeyond = side > 0 && pool && !floorBeyond && classes[a] == VoxelClass::Drop &&
												stepShadow(ux / len, uy / len, ax, ay);
						if (floorBeyond || stepBeyond)
						{
							(side < 0 ? nearer : farther) |= floorBeyond;
							shadowRays += stepBeyond;
							break;
						}
						if (grid.cell(a).count > 0 || m_empty[a] > 0) break;  // seen, or a ray came back empty
					}
			for (int dy = -1; dy <= 1; dy++)
				for (int dx = -1; dx <= 1; dx++)
				{
					if (!dx && !dy) continue;
					const int ax = cx + dx, ay = cy + dy;
					if (!g.inside(ax, ay)) continue;
					const uint32_t a = uint32_t(g.index(ax, ay));
					if ((m_mark[a] & uint8_t(~kJudged)) == kind)
					{
						m_mark[a] |= kVisited;
						m_queue.push_back(a);
					}
				}
			if (kind == kWeak) logChance += double(m_logChance[c]);
		}
		// Beyond the gap, the lower surface of a step must be seen along
		// several rays (as many as a cell needs empty ones), not in one noisy
		// cell; a region of weak candidates is judged only as a step's shadow.
		const bool lowerSurfaceBeyond = shadowRays >= m_params.min_rays;
		const bool bordered = nearer && (lowerSurfaceBeyond || (farther && kind == kCandidate));
		if (!bordered)
		{
			stats.unbordered++;
			// A step's shadow that runs to the end of the range: the
			// components of the region's cells, each judged once.
			if (pool && nearRangeEnd(m_region))
				for (uint32_t c : m_region)
				{
					if ((m_mark[c] & (kJudged | kMissing)) || cellDepth(c) > maxRange - m_rangeEndMargin) continue;
					gatherComponent(c);
					// The rays first: on the Kinect One's frames most components
					// fail them, and the evidence's first call fills the rings from
					// every floor cell of the frame.
					if (runsToRangeEnd(m_component) && rangeEndEvidence(m_component) * (1.0 - nextP) <= logAlphaPooled)
					{
						stats.range_end_regions++;
						stats.regions++;
						markMissing(m_component);
					}
				}
			continue;
		}
		if (kind == kWeak)
		{
			if (logChance * (1.0 - nextP) > logAlphaPooled) continue;
			stats.pooled_regions++;
		}
		stats.regions++;
		markMissing(m_region);
	}
	stats.cells = m_cells.size();
	stats.blocking = m_blocking.size();
	stats.applied = true;
}

}  // namespace gam
