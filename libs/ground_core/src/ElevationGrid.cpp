#include "gam/ElevationGrid.h"

#include <algorithm>
#include <stdexcept>
#include <string>

namespace gam
{
void GridGeometry::validate() const
{
	if (!(resolution > 0) || !std::isfinite(resolution))
		throw std::invalid_argument(
			"grid resolution must be > 0 (got " + std::to_string(resolution) + ")");
	if (nx <= 0 || ny <= 0)
		throw std::invalid_argument(
			"grid size must be at least 1x1 cells (got " + std::to_string(nx) + "x" +
			std::to_string(ny) + ")");
	// 2^26 cells = 1.5 GiB of ElevationCell: far beyond any sane 2.5D map.
	if (double(nx) * double(ny) > double(1u << 26))
		throw std::invalid_argument(
			"grid of " + std::to_string(nx) + "x" + std::to_string(ny) +
			" cells is too large (limit 67M cells); raise the resolution value or shrink the area");
	if (!std::isfinite(x_min) || !std::isfinite(y_min))
		throw std::invalid_argument("grid origin must be finite");
}

void ElevationGrid::resize(const GridGeometry& g)
{
	g.validate();
	m_geom = g;
	m_cells.assign(g.cellCount(), ElevationCell{});
	m_frame.assign(g.cellCount(), ElevationCell{});
	m_filterMean.assign(g.cellCount(), 0.f);
	m_filterLimit.assign(g.cellCount(), 0.f);
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

size_t ElevationGrid::insert(const BinnedPoints& pts, const OutlierFilterParams& filter)
{
	const size_t n = pts.size();
	// Pass 1: per-cell statistics of this frame.
	for (size_t i = 0; i < n; i++)
	{
		const uint32_t c = pts.cell[i];
		ElevationCell& fc = m_frame[c];
		if (!fc.count) m_frameTouched.push_back(c);
		fc.add(pts.z[i]);
	}

	size_t kept = n;
	if (filter.enabled)
	{
		// Pass 2: per cell, the band mean +- k*std; cells whose samples all lie in
		// it (or that are too small for the rule) are left untouched.
		// The std comes from a second pass over the samples (sum of (z - mean)^2):
		// the one-pass E[z^2] - E[z]^2 of the float sums cancels catastrophically
		// when |z| >> std (a floor at z = 10 m with 3 mm noise got std ~0 and lost
		// 15% of its samples, even with min_band).
		for (uint32_t c : m_frameTouched)
		{
			m_filterMean[c] = m_frame[c].mean();
			m_filterLimit[c] = 0.f;	 // sum of squared deviations, for now
		}
		for (size_t i = 0; i < n; i++)
		{
			const uint32_t c = pts.cell[i];
			const float d = pts.z[i] - m_filterMean[c];
			m_filterLimit[c] += d * d;
		}
		bool anyFiltered = false;
		for (uint32_t c : m_frameTouched)
		{
			ElevationCell& fc = m_frame[c];
			const float ssd = m_filterLimit[c];
			m_filterLimit[c] = std::numeric_limits<float>::infinity();
			if (fc.count < filter.min_count) continue;
			const float m = m_filterMean[c];
			const float lim =
				std::max(filter.min_band, filter.sigmas * std::sqrt(ssd / float(fc.count)));
			if (m - lim <= fc.z_min && m + lim >= fc.z_max) continue;
			anyFiltered = true;
			m_filterLimit[c] = lim;
			fc = ElevationCell{};
		}
		// Pass 3: re-accumulate the cells that had outliers, without them.
		if (anyFiltered)
		{
			kept = 0;
			for (size_t i = 0; i < n; i++)
			{
				const uint32_t c = pts.cell[i];
				const float lim = m_filterLimit[c];
				if (std::isinf(lim))
					kept++;
				else if (std::abs(pts.z[i] - m_filterMean[c]) <= lim)
				{
					m_frame[c].add(pts.z[i]);
					kept++;
				}
			}
		}
	}

	// Merge into the grid and reset the scratch cells.
	for (uint32_t c : m_frameTouched)
	{
		ElevationCell& fc = m_frame[c];
		if (fc.count)
		{
			ElevationCell& gc = m_cells[c];
			if (!gc.count) m_touched.push_back(c);
			gc.merge(fc);
		}
		fc = ElevationCell{};
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
	m_idwWeights.assign(size_t(2 * r + 1) * size_t(2 * r + 1), 0.f);
	for (int dy = -r; dy <= r; dy++)
		for (int dx = -r; dx <= r; dx++)
			if (dx || dy)
				m_idwWeights[size_t(dy + r) * size_t(2 * r + 1) + size_t(dx + r)] =
					1.0f / std::pow(std::sqrt(float(dx * dx + dy * dy)), p.power);

	size_t filled = 0;
	for (int cy = y0; cy <= y1; cy++)
		for (int cx = x0; cx <= x1; cx++)
		{
			ElevationCell& c = m_cells[m_geom.index(cx, cy)];
			if (c.count) continue;
			float sw = 0, swz = 0;
			int nb = 0;
			for (int dy = -r; dy <= r; dy++)
			{
				const int yy = cy + dy;
				if (yy < 0 || yy >= m_geom.ny) continue;
				for (int dx = -r; dx <= r; dx++)
				{
					const int xx = cx + dx;
					if (xx < 0 || xx >= m_geom.nx) continue;
					const ElevationCell& o = m_cells[m_geom.index(xx, yy)];
					if (!o.count) continue;
					const float w = m_idwWeights[size_t(dy + r) * size_t(2 * r + 1) + size_t(dx + r)];
					sw += w;
					swz += w * o.mean();
					nb++;
				}
			}
			if (nb >= p.min_neighbours && sw > 0)
			{
				c.z_idw = swz / sw;
				m_idwTouched.push_back(uint32_t(m_geom.index(cx, cy)));
				filled++;
			}
		}
	return filled;
}

}  // namespace gam
