// Ground-aware mapping for MRPT
// The 2.5D grid of the paper (§IV.A): every cell keeps z-min, z-max and the
// sample count N_z of the points that fell into it, plus the sums the 3-sigma
// filter needs. Pure data + algorithm: no MRPT, no I/O.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "gam/core/Parameters.h"

namespace gam
{
/** Axis-aligned, regular 2D grid: cell (ix, iy) covers
 *  [x_min + ix*res, x_min + (ix+1)*res) x [y_min + iy*res, ...). */
struct GridGeometry
{
	double x_min = -5, y_min = -5;
	double resolution = 0.05;
	int nx = 200, ny = 200;

	double x_max() const { return x_min + nx * resolution; }
	double y_max() const { return y_min + ny * resolution; }
	size_t cellCount() const { return size_t(nx) * size_t(ny); }
	/** Cell index along x, possibly outside [0, nx); saturated for far or
	 * non-finite coordinates (NaN gives INT_MIN: outside). */
	int ix(double x) const { return toIndex(std::floor((x - x_min) / resolution)); }
	int iy(double y) const { return toIndex(std::floor((y - y_min) / resolution)); }
	static int toIndex(double f)
	{
		// A plain int(f) is undefined behaviour beyond the int range (UBSan, fuzz_rawlog).
		if (f >= 2147483647.0) return std::numeric_limits<int>::max();
		if (!(f > -2147483648.0)) return std::numeric_limits<int>::min();
		return int(f);
	}
	bool inside(int cx, int cy) const { return cx >= 0 && cy >= 0 && cx < nx && cy < ny; }
	double cx(int ix_) const { return x_min + (ix_ + 0.5) * resolution; }
	double cy(int iy_) const { return y_min + (iy_ + 0.5) * resolution; }
	size_t index(int cx_, int cy_) const { return size_t(cy_) * size_t(nx) + size_t(cx_); }

	/** Throws std::invalid_argument naming the bad value. */
	void validate() const;
	bool operator==(const GridGeometry& o) const
	{
		return x_min == o.x_min && y_min == o.y_min && resolution == o.resolution && nx == o.nx && ny == o.ny;
	}
};

/** One column of the 2.5D map. Heights in metres, in the grid's frame. */
struct ElevationCell
{
	float z_min = std::numeric_limits<float>::infinity();
	float z_max = -std::numeric_limits<float>::infinity();
	uint32_t count = 0;  ///< N_z, after outlier removal
	float z_sum = 0;     ///< sum of z (for the mean)
	/** Sum of the squared deviations from the cell's mean (Welford's update,
	 * Chan's merge): the variance keeps its precision at any height. The sum
	 * of z^2 it replaces gave E[z^2] - E[z]^2 in float, which at z = 10 m (an
	 * upper storey in a global map) loses a 3 mm floor noise entirely. */
	float z_m2 = 0;
	/** Inverse-distance-weighted height estimate for cells with count == 0
	 * (NaN when not interpolated). Never counts as an observation. */
	float z_idw = std::numeric_limits<float>::quiet_NaN();

	bool observed() const { return count > 0; }
	float mean() const { return count ? z_sum / float(count) : std::numeric_limits<float>::quiet_NaN(); }
	/** Population variance of the samples (sum of squared deviations / N). */
	float variance() const { return count < 2 ? 0.f : std::max(0.f, z_m2 / float(count)); }
	float span() const { return count ? z_max - z_min : 0.f; }
	void add(float z)
	{
		if (z < z_min) z_min = z;
		if (z > z_max) z_max = z;
		const float before = count ? z_sum / float(count) : z;
		++count;
		z_sum += z;
		z_m2 += (z - before) * (z - z_sum / float(count));
	}
	void merge(const ElevationCell& o)
	{
		if (!o.count) return;
		if (count)
		{
			const float delta = o.mean() - mean();
			const float n = float(count) + float(o.count);
			z_m2 += o.z_m2 + delta * delta * (float(count) * float(o.count) / n);
		}
		else
			z_m2 = o.z_m2;
		z_min = std::min(z_min, o.z_min);
		z_max = std::max(z_max, o.z_max);
		count += o.count;
		z_sum += o.z_sum;
		z_idw = std::numeric_limits<float>::quiet_NaN();
	}
};

/** A read-only view of `n` contiguous values (std::span is C++20). */
template <class T>
struct ConstSpan
{
	const T* first = nullptr;
	size_t n = 0;
	const T* begin() const { return first; }
	const T* end() const { return first + n; }
	size_t size() const { return n; }
	const T& operator[](size_t i) const { return first[i]; }
};

/** Height samples of one frame, already binned: the cell index and the z of each
 * point. Filled by the projectors (DepthProjector, or any point source), then
 * merged into an ElevationGrid. Reused between frames: the buffers only grow,
 * so a steady stream of frames allocates nothing. */
class BinnedPoints
{
   public:
	void clear() { m_size = 0; }
	size_t size() const { return m_size; }
	/** Samples it holds without allocating. */
	size_t capacity() const { return m_cell.size(); }
	bool empty() const { return m_size == 0; }
	ConstSpan<uint32_t> cells() const { return {m_cell.data(), m_size}; }
	ConstSpan<float> heights() const { return {m_z.data(), m_size}; }
	void push(uint32_t c, float zz)
	{
		if (m_size == m_cell.size()) grow(m_size + 1);
		m_cell[m_size] = c;
		m_z[m_size] = zz;
		m_size++;
	}
	/** For bulk writers: room for `extra` more samples at cellBuffer()[size()...]
	 * and zBuffer()[size()...]; then commit() the new size. */
	void prepare(size_t extra) { grow(m_size + extra); }
	uint32_t* cellBuffer() { return m_cell.data(); }
	float* zBuffer() { return m_z.data(); }
	void commit(size_t newSize) { m_size = std::min(newSize, m_cell.size()); }

   private:
	void grow(size_t need)
	{
		if (need <= m_cell.size()) return;
		const size_t n = std::max<size_t>({need, 2 * m_cell.size(), 1024});
		m_cell.resize(n);
		m_z.resize(n);
	}
	std::vector<uint32_t> m_cell;
	std::vector<float> m_z;
	size_t m_size = 0;
};

/** The indices of the samples whose cell is marked (`marked`: a byte per cell,
 * non-zero = marked), in order, in `out[0..returned)`; `out` only grows, to
 * `pts.capacity()` (so it allocates when `pts` does). Every
 * sample's cell must have its byte: the samples are binned on the grid the
 * bytes are for (as ElevationGrid::insert requires). Written without a branch
 * per sample: marked cells interleave with others along an image row, a few
 * samples each, and a test per sample mispredicted at many of those changes
 * (D435 demo: the 3-sigma stage took 0.13 ms and the ISM 0.09 ms longer).
 * `fewMarked`: most blocks of 16 samples touch no marked cell, so each such
 * block is skipped after one test. The ISM's tail count asks for it (with the
 * drop-ray loop of the same change, not timed apart: Astra demo ISM
 * 0.36 -> 0.33 ms). The 3-sigma filter asks for it only where its flagged
 * cells hold under 1/8 of the samples: on the D435 demo they hold a quarter
 * (with it, 3-sigma stage 0.99 -> 1.03 ms), on a Kinect One frame 2 %. */
size_t samplesInMarkedCells(
	const BinnedPoints& pts, const uint8_t* marked, std::vector<uint32_t>& out, bool fewMarked = false);

/** Per-cell outlier removal (paper §IV.A: the 3-sigma rule). */
struct OutlierFilterParams
{
	bool enabled = true;
	float sigmas = 3.0f;  ///< keep |z - mean| <= sigmas * std
	/** Cells with fewer samples keep all of them: with n points no sample can be
	 * more than (n-1)/sqrt(n) std away, so the rule is void for n <= 10 anyway. */
	uint32_t min_count = 4;
	/** The band never gets narrower than +-this [m]: on a flat, near surface
	 * the std of depths in whole millimetres is ~1 mm, and a sample one step
	 * off is then beyond 3 std. 5 mm is below any depth camera's noise.
	 * Measured (issue #27, doc/rules.md): without it no cell count of the 27
	 * scenes changes with any camera model, but more Kinect One cells need
	 * the filter's second pass (0.05 ms more per frame, 0.42 -> 0.47 ms). */
	float min_band = 0.005f;

	/** The .ini keys, shared by every map that keeps a 2.5D grid. */
	template <class Self, class Visit>
	static void forEachParam(Self& p, Visit&& visit)
	{
		visit(ParamInfo{"outlier_filter", 0, 1, "3-sigma rule per cell and frame"}, p.enabled);
		visit(ParamInfo{"outlier_sigmas", 0.5, 100, "k of the k-sigma rule"}, p.sigmas);
		visit(ParamInfo{"outlier_min_count", 2, 1000000, "cells with fewer samples are not filtered"}, p.min_count);
	}
};

/** Inverse distance weighting densification (fills empty cells). */
struct IdwParams
{
	int radius_cells = 0;  ///< 0 disables it
	float power = 2.0f;
	int min_neighbours = 3;  ///< observed cells needed in the window

	/** The .ini keys, shared by every map that keeps a 2.5D grid. */
	template <class Self, class Visit>
	static void forEachParam(Self& p, Visit&& visit)
	{
		visit(ParamInfo{"idw_radius", 0, 50, "IDW window radius [cells], 0 = off"}, p.radius_cells);
		visit(ParamInfo{"idw_power", 0.1, 10, "IDW distance exponent"}, p.power);
		visit(ParamInfo{"idw_min_neighbours", 1, 10000, "observed cells needed to interpolate"}, p.min_neighbours);
	}
};

class ElevationGrid
{
   public:
	ElevationGrid() { resize(GridGeometry{}); }
	explicit ElevationGrid(const GridGeometry& g) { resize(g); }

	/** Sets the geometry and empties every cell. */
	void resize(const GridGeometry& g);
	/** Moves the grid (same size and resolution) and empties it; cheap when only
	 * a few cells were touched since the last clear. */
	void recenter(double x_min, double y_min);
	void clear();

	const GridGeometry& geometry() const { return m_geom; }
	const ElevationCell& cell(int cx, int cy) const { return m_cells[m_geom.index(cx, cy)]; }
	const ElevationCell& cell(size_t idx) const { return m_cells[idx]; }
	ElevationCell& cellMutable(size_t idx) { return m_cells[idx]; }
	const std::vector<ElevationCell>& cells() const { return m_cells; }
	std::vector<ElevationCell>& cellsMutable() { return m_cells; }
	/** Indices of the cells with count > 0 (in first-touched order). */
	const std::vector<uint32_t>& observedCells() const { return m_touched; }
	size_t observedCount() const { return m_touched.size(); }

	/** Bins one point; returns false (and does nothing) if it falls outside. */
	bool binPoint(double x, double y, float z, BinnedPoints& out) const
	{
		const int cx = m_geom.ix(x), cy = m_geom.iy(y);
		if (!m_geom.inside(cx, cy)) return false;
		out.push(uint32_t(m_geom.index(cx, cy)), z);
		return true;
	}

	/** Adds a frame's samples: they are accumulated per cell, optionally
	 * filtered with the 3-sigma rule (within this frame), then merged into the
	 * grid. Returns the number of samples kept. */
	size_t insert(const BinnedPoints& pts, const OutlierFilterParams& filter);

	/** Sets a cell's statistics directly (deserialization). */
	void restoreCell(size_t idx, const ElevationCell& c)
	{
		if (!m_cells[idx].count && c.count) m_touched.push_back(uint32_t(idx));
		m_cells[idx] = c;
	}

	/** Fills z_idw of empty cells from observed ones in a (2r+1)^2 window.
	 * Returns how many cells got an estimate. Restricted to the bounding box of
	 * the observed cells grown by r. */
	size_t interpolateIdw(const IdwParams& p);
	/** Turns every cell that holds only an IDW estimate into an observed cell
	 * at that height (the paper's densified map) whose sample count N_z is the
	 * number of observed cells in its (2 radiusCells + 1)^2 window, the valid
	 * neighbour voxels it was interpolated from (paper SIV-A; pass the IDW
	 * radius). Returns how many. clear() and recenter() empty them like any
	 * observed cell. */
	size_t promoteIdwCells(int radiusCells);

	/** Surface height of a cell for ground fitting: the mean of an observed cell,
	 * else the IDW estimate; NaN if neither. */
	float surfaceHeight(int cx, int cy) const
	{
		const ElevationCell& c = cell(cx, cy);
		return c.count ? c.mean() : c.z_idw;
	}

	/** One frame's samples of a cell, relative to its first sample (see insert()). */
	struct FrameCell
	{
		float ref = 0, s1 = 0, s2 = 0;
		float z_min = std::numeric_limits<float>::infinity();
		float z_max = -std::numeric_limits<float>::infinity();
		uint32_t count = 0;
	};

   private:
	GridGeometry m_geom;
	std::vector<ElevationCell> m_cells;
	std::vector<uint32_t> m_touched;     // cells with count > 0
	std::vector<uint32_t> m_idwTouched;  // cells holding an IDW value
	// Frame scratch (kept to avoid per-frame allocations):
	std::vector<FrameCell> m_frame;
	std::vector<uint32_t> m_frameTouched;
	std::vector<float> m_filterMean, m_filterLimit;
	std::vector<uint8_t> m_flagged;          // 1: the cell's samples are re-accumulated within mean +- limit
	std::vector<uint32_t> m_flaggedSamples;  // pass 2: the samples of flagged cells
	std::vector<float> m_idwWeights;
	std::vector<float> m_idwSeen, m_idwMean;  // interpolateIdw's padded window
	std::vector<float> m_idwRow;              // its sums along a row
	std::vector<uint32_t> m_idwNeighbours;
};

}  // namespace gam
