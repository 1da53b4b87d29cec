#include "gam/core/ElevationGrid.h"

#include <algorithm>
#include <cstddef>
#include <stdexcept>
#include <string>

namespace gam
{
void GridGeometry::validate() const
{
	if (!(resolution > 0) || !std::isfinite(resolution))
		throw std::invalid_argument("grid resolution must be > 0 (got " + std::to_string(resolution) + ")");
	if (nx <= 0 || ny <= 0)
		throw std::invalid_argument(
			"grid size must be at least 1x1 cells (got " + std::to_string(nx) + "x" + std::to_string(ny) + ")");
	// 2^26 cells = 1.5 GiB of ElevationCell: far beyond any sane 2.5D map.
	if (double(nx) * double(ny) > double(1u << 26))
		throw std::invalid_argument(
			"grid of " + std::to_string(nx) + "x" + std::to_string(ny) +
			" cells is too large (limit 67M cells); raise the resolution value or shrink the area");
	if (!std::isfinite(x_min) || !std::isfinite(y_min)) throw std::invalid_argument("grid origin must be finite");
}

size_t samplesInMarkedCells(const BinnedPoints& pts, const uint8_t* marked, std::vector<uint32_t>& out, bool fewMarked)
{
	const size_t n = pts.size();
	if (out.size() < pts.capacity()) out.resize(pts.capacity());
	const uint32_t* cellOf = pts.cells().begin();
	uint32_t* list = out.data();
	size_t listed = 0;
	// Where marked cells are few, a block of samples with none of them is
	// skipped after one test.
	constexpr size_t kBlock = 16;
	size_t i = 0;
	if (fewMarked)
		for (; i + kBlock <= n; i += kBlock)
		{
			uint32_t any = 0;
			for (size_t j = 0; j < kBlock; j++) any |= marked[cellOf[i + j]];
			if (!any) continue;
			for (size_t j = i; j < i + kBlock; j++)
			{
				list[listed] = uint32_t(j);  // kept only if the cell is marked
				listed += marked[cellOf[j]] != 0;
			}
		}
	for (; i < n; i++)
	{
		list[listed] = uint32_t(i);  // kept only if the cell is marked
		listed += marked[cellOf[i]] != 0;
	}
	return listed;
}

void ElevationGrid::resize(const GridGeometry& g)
{
	g.validate();
	m_geom = g;
	m_cells.assign(g.cellCount(), ElevationCell{});
	m_frame.assign(g.cellCount(), FrameCell{});
	m_filterMean.assign(g.cellCount(), 0.f);
	m_filterLimit.assign(g.cellCount(), 0.f);
	m_flagged.assign(g.cellCount(), 0);
	m_touched.clear();
	m_idwTouched.clear();
	m_frameTouched.clear();
}

void ElevationGrid::clear()
{
	// Touch only what was written: a frame fills a few thousand of 40k cells.
	for (uint32_t i : m_touched) m_cells[i] = ElevationCell{};
	for (uint32_t i : m_idwTouched) m_cells[i] = ElevationCell{};
	m_touched.clear();
	m_idwTouched.clear();
}

void ElevationGrid::recenter(double x_min, double y_min)
{
	clear();
	m_geom.x_min = x_min;
	m_geom.y_min = y_min;
}

namespace
{
// Sums of a cell's samples relative to its first sample (`ref`). The 3-sigma
// rule needs the std of each cell in one pass; the textbook E[z^2] - E[z]^2 of
// plain float sums cancels catastrophically when |z| >> std (a floor at
// z = 10 m with 3 mm noise got std ~0 and lost 15% of its samples), while the
// deviations from a sample of the same cell are at most the cell's span.
inline void accumulate(ElevationGrid::FrameCell& a, float z)
{
	if (!a.count) a.ref = z;
	const float d = z - a.ref;
	a.count++;
	a.s1 += d;
	a.s2 += d * d;
	a.z_min = std::min(a.z_min, z);
	a.z_max = std::max(a.z_max, z);
}

// f(i) for every i in [0, n): the four quarters of the range in lockstep,
// then the rest. (Each f updates a cell that the next index mostly updates
// too, after waiting for its store: four such chains overlap.)
template <class F>
inline void inLockstepQuarters(size_t n, F&& f)
{
	const size_t q = n / 4;
	for (size_t i = 0; i < q; i++)
	{
		f(i);
		f(q + i);
		f(2 * q + i);
		f(3 * q + i);
	}
	for (size_t i = 4 * q; i < n; i++) f(i);
}

ElevationCell toCell(const ElevationGrid::FrameCell& a)
{
	ElevationCell c;
	c.count = a.count;
	c.z_min = a.z_min;
	c.z_max = a.z_max;
	const double n = a.count, ref = a.ref, s1 = a.s1, s2 = a.s2;
	c.z_sum = float(n * ref + s1);
	// Deviations from the mean, from those from the first sample: no large
	// number is ever formed (they were turned back into sums of z^2 here).
	c.z_m2 = float(std::max(0.0, s2 - s1 * s1 / n));
	return c;
}
}  // namespace

size_t ElevationGrid::insert(const BinnedPoints& pts, const OutlierFilterParams& filter)
{
	const size_t n = pts.size();
	const uint32_t* cellOf = pts.cells().begin();
	const float* zOf = pts.heights().begin();
	// Pass 2's list, sized with the samples' buffer whether or not this frame
	// needs it: a later frame then allocates nothing.
	if (m_flaggedSamples.size() < pts.capacity()) m_flaggedSamples.resize(pts.capacity());
	// Pass 1: per-cell statistics of this frame. Neighbouring samples mostly
	// share a cell, and each update then waits for the previous one's store:
	// walking four quarters of the frame in lockstep interleaves four such
	// chains (different cells, far apart in the image). Summing runs of equal
	// cells in registers instead was tried: slower, the run ends mispredict.
	auto add = [&](size_t i) {
		FrameCell& a = m_frame[cellOf[i]];
		if (!a.count) m_frameTouched.push_back(cellOf[i]);
		accumulate(a, zOf[i]);
	};
	inLockstepQuarters(n, add);

	// Per cell, the band mean +- k*std; cells whose samples all lie in it (or
	// that are too small for the rule) are merged as they are; the others are
	// flagged with their band and re-accumulated without their outliers.
	size_t flagged = 0, flaggedCount = 0;
	for (uint32_t c : m_frameTouched)
	{
		FrameCell& a = m_frame[c];
		if (!filter.enabled || a.count < filter.min_count) continue;
		const float inv = 1.0f / float(a.count);
		const float m1 = a.s1 * inv;
		const float var = std::max(0.f, a.s2 * inv - m1 * m1);
		const float lim = std::max(filter.min_band, filter.sigmas * std::sqrt(var));
		const float mean = a.ref + m1;
		if (mean - lim <= a.z_min && mean + lim >= a.z_max) continue;
		m_filterMean[c] = mean;
		m_filterLimit[c] = lim;
		m_flagged[c] = 1;
		flaggedCount += a.count;
		a = FrameCell{};
		flagged++;
	}
	size_t kept = n;
	if (flagged)
	{
		// Pass 2, only if some cell had outliers: re-accumulate the flagged
		// cells (a byte per cell tells which: it stays in the L1 cache).
		// (Four quarters of the list in lockstep, as pass 1.) Where their
		// samples are under 1/8 of the frame's, most blocks of 16 samples
		// hold none: they are skipped (listing a Kinect One frame whose
		// flagged cells hold 2 % of its samples, 78 -> 55 us; a Femto or
		// D435 frame's hold 25-30 %, where skipping costs 25 %).
		const bool fewFlagged = 8 * flaggedCount < n;
		const size_t listed = samplesInMarkedCells(pts, m_flagged.data(), m_flaggedSamples, fewFlagged);
		const auto readd = [&](size_t k) {
			const uint32_t i = m_flaggedSamples[k];
			const uint32_t c = cellOf[i];
			if (std::abs(zOf[i] - m_filterMean[c]) <= m_filterLimit[c])
				accumulate(m_frame[c], zOf[i]);
			else
				kept--;
		};
		inLockstepQuarters(listed, readd);
	}

	// Merge into the grid and reset the scratch cells.
	for (uint32_t c : m_frameTouched)
	{
		FrameCell& a = m_frame[c];
		m_flagged[c] = 0;
		if (a.count)
		{
			ElevationCell& gc = m_cells[c];
			if (!gc.count) m_touched.push_back(c);
			gc.merge(toCell(a));
		}
		a = FrameCell{};
	}
	m_frameTouched.clear();
	return kept;
}

size_t ElevationGrid::interpolateIdw(const IdwParams& p)
{
	// Forget previous estimates.
	for (uint32_t i : m_idwTouched)
		if (!m_cells[i].count) m_cells[i].z_idw = std::numeric_limits<float>::quiet_NaN();
	m_idwTouched.clear();
	if (p.radius_cells <= 0 || m_touched.empty()) return 0;

	const int r = p.radius_cells;
	int x0 = m_geom.nx, y0 = m_geom.ny, x1 = -1, y1 = -1;
	for (uint32_t i : m_touched)
	{
		const int cx = int(i % uint32_t(m_geom.nx)), cy = int(i / uint32_t(m_geom.nx));
		x0 = std::min(x0, cx);
		x1 = std::max(x1, cx);
		y0 = std::min(y0, cy);
		y1 = std::max(y1, cy);
	}
	x0 = std::max(0, x0 - r);
	y0 = std::max(0, y0 - r);
	x1 = std::min(m_geom.nx - 1, x1 + r);
	y1 = std::min(m_geom.ny - 1, y1 + r);

	// Weights depend only on the offset: precompute them.
	const int W = 2 * r + 1;
	m_idwWeights.assign(size_t(W) * size_t(W), 0.f);
	for (int dy = -r; dy <= r; dy++)
		for (int dx = -r; dx <= r; dx++)
			if (dx || dy)
				m_idwWeights[size_t(dy + r) * size_t(W) + size_t(dx + r)] =
					1.0f / std::pow(std::sqrt(float(dx * dx + dy * dy)), p.power);

	// The window's cells once, as two planes padded by r (0 outside the
	// grid): seen (1 or 0) and the mean of the seen ones (0 elsewhere).
	// Every neighbour then adds w * seen and w * mean, the empty ones an
	// exact +0, in the order the cell-by-cell loop added the seen ones: the
	// same sums, bit for bit, as vector loops along a row (that loop read
	// each neighbour's cell and divided for its mean up to 8 times).
	// (Sized for the whole grid at once: a later frame's larger window then
	// allocates nothing.)
	const int bw = x1 - x0 + 1, pw = bw + 2 * r, ph = (y1 - y0 + 1) + 2 * r;
	const size_t whole = size_t(m_geom.nx + 2 * r) * size_t(m_geom.ny + 2 * r);
	if (m_idwSeen.size() < whole)
	{
		m_idwSeen.resize(whole);
		m_idwMean.resize(whole);
	}
	if (m_idwRow.size() < 3 * size_t(m_geom.nx)) m_idwRow.resize(3 * size_t(m_geom.nx));
	for (int py = 0; py < ph; py++)
	{
		float* __restrict seen = m_idwSeen.data() + size_t(py) * size_t(pw);
		float* __restrict mean = m_idwMean.data() + size_t(py) * size_t(pw);
		std::fill(seen, seen + pw, 0.f);
		std::fill(mean, mean + pw, 0.f);
		const int yy = y0 - r + py;
		if (yy < 0 || yy >= m_geom.ny) continue;
		const int from = std::max(0, r - x0), to = std::min(pw, m_geom.nx - (x0 - r));
		const ElevationCell* row = m_cells.data() + size_t(yy) * size_t(m_geom.nx);
		for (int px = from; px < to; px++)
		{
			const ElevationCell& o = row[x0 - r + px];
			seen[px] = o.count ? 1.f : 0.f;
			mean[px] = o.count ? o.mean() : 0.f;
		}
	}

	size_t filled = 0;
	float* __restrict sw = m_idwRow.data();
	float* __restrict swz = sw + bw;
	float* __restrict nb = swz + bw;
	for (int cy = y0; cy <= y1; cy++)
	{
		std::fill(sw, sw + 3 * bw, 0.f);
		const size_t centre = size_t(cy - y0 + r) * size_t(pw) + size_t(r);
		for (int dy = -r; dy <= r; dy++)
			for (int dx = -r; dx <= r; dx++)
			{
				if (!dx && !dy) continue;  // the cell itself is empty
				const float w = m_idwWeights[size_t(dy + r) * size_t(W) + size_t(dx + r)];
				const ptrdiff_t off = ptrdiff_t(dy) * pw + dx;
				const float* __restrict seen = m_idwSeen.data() + centre + off;
				const float* __restrict mean = m_idwMean.data() + centre + off;
				for (int k = 0; k < bw; k++)
				{
					sw[k] += w * seen[k];
					swz[k] += w * mean[k];
					nb[k] += seen[k];
				}
			}
		const float* seenHere = m_idwSeen.data() + centre;
		const float minNb = float(p.min_neighbours);
		for (int k = 0; k < bw; k++)
			if (seenHere[k] == 0.f && nb[k] >= minNb && sw[k] > 0)
			{
				const size_t i = m_geom.index(x0 + k, cy);
				m_cells[i].z_idw = swz[k] / sw[k];
				m_idwTouched.push_back(uint32_t(i));
				filled++;
			}
	}
	return filled;
}

size_t ElevationGrid::promoteIdwCells(int radiusCells)
{
	// Paper SIV-A: an interpolated voxel's N_z is the number of valid
	// neighbour voxels it was interpolated from. Count them first (before any
	// estimate becomes an observed cell), then promote.
	const int r = std::max(0, radiusCells);
	m_idwNeighbours.clear();
	for (uint32_t i : m_idwTouched)
	{
		const ElevationCell& c = m_cells[i];
		uint32_t nb = 0;
		if (!c.count && std::isfinite(c.z_idw))
		{
			const int cx = int(i % uint32_t(m_geom.nx)), cy = int(i / uint32_t(m_geom.nx));
			for (int y = std::max(0, cy - r); y <= std::min(m_geom.ny - 1, cy + r); y++)
				for (int x = std::max(0, cx - r); x <= std::min(m_geom.nx - 1, cx + r); x++)
					nb += m_cells[m_geom.index(x, y)].count > 0;
		}
		m_idwNeighbours.push_back(nb);
	}
	size_t n = 0;
	for (size_t k = 0; k < m_idwTouched.size(); k++)
	{
		ElevationCell& c = m_cells[m_idwTouched[k]];
		if (c.count || !std::isfinite(c.z_idw)) continue;
		for (uint32_t j = 0; j < std::max<uint32_t>(1, m_idwNeighbours[k]); j++) c.add(c.z_idw);
		m_touched.push_back(m_idwTouched[k]);
		n++;
	}
	return n;
}

}  // namespace gam
