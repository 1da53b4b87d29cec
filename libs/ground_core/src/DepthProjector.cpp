#include "gam/core/DepthProjector.h"

#include "ProjectRow.h"

#include <cmath>
#include <cstring>
#include <stdexcept>
#include <string>

namespace gam
{
void PinholeIntrinsics::validate() const
{
	if (width <= 0 || height <= 0)
		throw std::invalid_argument(
			"camera size must be positive (got " + std::to_string(width) + "x" + std::to_string(height) + ")");
	if (!(fx > 0) || !(fy > 0) || !std::isfinite(fx) || !std::isfinite(fy))
		throw std::invalid_argument(
			"camera focal lengths must be > 0 (got fx=" + std::to_string(fx) + ", fy=" + std::to_string(fy) + ")");
	if (!std::isfinite(cx) || !std::isfinite(cy)) throw std::invalid_argument("camera principal point must be finite");
	if (!std::isfinite(k1) || !std::isfinite(k2) || !std::isfinite(k3) || !std::isfinite(p1) || !std::isfinite(p2))
		throw std::invalid_argument("camera distortion coefficients must be finite");
}

void DepthProjector::updateLut(const PinholeIntrinsics& K)
{
	if (K == m_lutK && !m_rayY.empty()) return;
	m_lutK = K;
	m_decStep = 0;  // the decimated table follows the new one
	const size_t n = size_t(K.width) * size_t(K.height);
	m_rayY.resize(n);
	m_rayZ.resize(n);
	m_rayInvNorm.resize(n);
	m_rowCell.resize(size_t(K.width));
	m_rowZ.resize(size_t(K.width));
	m_rowKeep.resize(size_t(K.width));
	m_flyCols.resize(size_t(K.width));
	m_flyLines.resize(14 * size_t(K.width));
	m_flyAlong.resize(size_t(K.width));
	m_flyAgainstNothing.resize(size_t(K.width));
	m_flyZeros.assign(size_t(K.width), 0);
	const bool distorted = K.k1 != 0 || K.k2 != 0 || K.k3 != 0 || K.p1 != 0 || K.p2 != 0;
	for (int r = 0; r < K.height; r++)
	{
		// The undistortion correction changes little from one pixel to the next:
		// starting from the left neighbour's cuts the iterations (and the first
		// frame of a camera, which builds this table) several-fold.
		double corrX = 0, corrY = 0;
		for (int c = 0; c < K.width; c++)
		{
			// MRPT's convention (CObservation3DRangeScan::unprojectInto):
			// x = D, y = (cx - c) * D / fx, z = (cy - r) * D / fy, with (c, r)
			// first undistorted. Normalized image coordinates (right, down):
			const double xd = (c - K.cx) / K.fx, yd = (r - K.cy) / K.fy;
			double xu = xd + corrX, yu = yd + corrY;
			if (distorted)
			{
				// Invert the distortion by fixed-point iteration (converges in a
				// few steps for the mild distortion of depth cameras).
				for (int it = 0; it < 20; it++)
				{
					const double r2 = xu * xu + yu * yu;
					const double radial = 1 + r2 * (K.k1 + r2 * (K.k2 + r2 * K.k3));
					const double dx = 2 * K.p1 * xu * yu + K.p2 * (r2 + 2 * xu * xu);
					const double dy = K.p1 * (r2 + 2 * yu * yu) + 2 * K.p2 * xu * yu;
					const double nx = (xd - dx) / radial, ny = (yd - dy) / radial;
					const bool done = std::abs(nx - xu) + std::abs(ny - yu) < 1e-12;
					xu = nx;
					yu = ny;
					if (done) break;
				}
				corrX = xu - xd;
				corrY = yu - yd;
			}
			const float ky = float(-xu), kz = float(-yu);
			const size_t i = size_t(r) * size_t(K.width) + size_t(c);
			m_rayY[i] = ky;
			m_rayZ[i] = kz;
			m_rayInvNorm[i] = 1.0f / std::sqrt(1.0f + ky * ky + kz * kz);
		}
	}
	m_rowRayBounds.resize(size_t(K.height));
	for (int r = 0; r < K.height; r++)
	{
		const float* y = rayYRow(r);
		const float* z = rayZRow(r);
		RayBounds& b = m_rowRayBounds[size_t(r)];
		b.y_min = *std::min_element(y, y + K.width);
		b.y_max = *std::max_element(y, y + K.width);
		b.z_min = *std::min_element(z, z + K.width);
		b.z_max = *std::max_element(z, z + K.width);
	}
}

void DepthProjector::updateDecimatedLut(int dec)
{
	if (dec == m_decStep) return;
	m_decStep = dec;
	const int w = m_lutK.width, h = m_lutK.height;
	const size_t cols = size_t((w + dec - 1) / dec), rows = size_t((h + dec - 1) / dec);
	m_decRayY.resize(rows * cols);
	m_decRayZ.resize(rows * cols);
	m_decRayInvNorm.resize(rows * cols);
	m_decImage.resize(rows * cols);
	for (size_t r = 0; r < rows; r++)
		for (size_t k = 0; k < cols; k++)
		{
			const size_t from = r * size_t(dec) * size_t(w) + k * size_t(dec);
			m_decRayY[r * cols + k] = m_rayY[from];
			m_decRayZ[r * cols + k] = m_rayZ[from];
			m_decRayInvNorm[r * cols + k] = m_rayInvNorm[from];
		}
}

namespace
{
// A neighbour along the line within tol of the pixel, and the next one on
// that side within tol of it: a surface goes on there (the far floor just
// past a step's edge continues along its row while the column beyond it
// drops out). A mixed pixel's neighbours are other mixed pixels at random
// depths: one of them may come within tol, two in a row rarely do.
inline bool supportedAlong(const float* v, float tol)
{
	const auto near = [tol](float a, float b) { return a > 0 && std::abs(a - b) <= tol; };
	return (near(v[2], v[3]) && near(v[1], v[2])) || (near(v[4], v[3]) && near(v[5], v[4]));
}

// Both lines through pixel (r, c), neighbours `step` apart: h along its row,
// w along its column (offsets -3 ... +3, the pixel at [3]), 0 beyond the
// image's edge.
inline void linesAt(const RangeImageView& img, int r, int c, int step, float* h, float* w)
{
	const int reach = 3 * step;
	if (r >= reach && c >= reach && r + reach < img.rows && c + reach < img.cols)
	{
		const uint16_t* p = img.data + size_t(r) * img.stride + size_t(c);
		const ptrdiff_t down = ptrdiff_t(img.stride) * step;
		for (int o = -3; o <= 3; o++)
		{
			h[o + 3] = float(p[o * step]);
			w[o + 3] = float(p[o * down]);
		}
		return;
	}
	auto v = [&](int rr, int cc) -> float {
		return (rr < 0 || cc < 0 || rr >= img.rows || cc >= img.cols) ? 0.f : float(img.at(rr, cc));
	};
	for (int o = -3; o <= 3; o++)
	{
		h[o + 3] = v(r, c + o * step);
		w[o + 3] = v(r + o * step, c);
	}
}

// Neither flying test can hold without a spread along one of the lines
// (most pixels have none).
inline bool spreadOnEitherLine(const float* h, const float* w, float tol)
{
	const float wholeTol = std::floor(tol);
	return spreadAlong(h, wholeTol) || spreadAlong(w, wholeTol);
}

// Both lines through pixel (r, c), neighbours `step` apart.
bool flyingAt(const RangeImageView& img, int r, int c, int step, float tol)
{
	if (img.at(r, c) == 0) return false;
	float h[7], w[7];
	linesAt(img, r, c, step, h, w);
	if (!spreadOnEitherLine(h, w, tol)) return false;
	if (flyingAlong(h, tol) || flyingAlong(w, tol)) return true;
	if (!againstNothingAlong(h, tol) && !againstNothingAlong(w, tol)) return false;
	// Against no return, a pixel must also stand alone: no surface goes on
	// from it, i.e. no neighbour of the 8 within tol of it with the next
	// pixel the same way within tol of that one. The floor just past a
	// step's edge jumps as far (by the step's height over the camera's, 6 %
	// for 5 cm from 0.8 m) and may have a dropout beyond it, but it continues
	// along its row or diagonally; a mixed pixel's neighbours are the edge,
	// the void and other mixed pixels at random depths, one of which may come
	// within tol (which kept it, when one neighbour was enough).
	const float d = h[3];
	if (supportedAlong(h, tol) || supportedAlong(w, tol)) return false;
	for (int dr = -1; dr <= 1; dr += 2)
		for (int dc = -1; dc <= 1; dc += 2)
		{
			// The diagonal neighbour and the next pixel on that diagonal.
			const int rr = r + 2 * dr * step, cc = c + 2 * dc * step;
			if (rr < 0 || cc < 0 || rr >= img.rows || cc >= img.cols) continue;
			const float n = float(img.at(r + dr * step, c + dc * step)), m = float(img.at(rr, cc));
			if (n > 0 && std::abs(n - d) <= tol && m > 0 && std::abs(m - n) <= tol) return false;
		}
	return true;
}

// Scratch of markFlyingRow for one row's candidates (room for a row each):
// their columns, their two lines (14 floats each, see flyingLines) and the
// answers of the two tests.
struct FlyingBatch
{
	int32_t* cols;
	float* lines;
	size_t stride;
	uint8_t* along;
	uint8_t* againstNothing;
	const uint16_t* zeros;  // a row of 0: the rows beyond the image's edge
};

// The two lines of pixel (r, c) within 3 of the image's edge into
// line[o * stride], o = 0..13 (as flyingLines reads them), 0 beyond the edge.
// Returns false, and the pixel is not flying, where neither line has the
// spread the tests need (flyingAt's first test; most such pixels).
__attribute__((noinline)) bool gatherLinesAtEdge(
	const RangeImageView& img, int r, int c, float tol, float* line, size_t stride)
{
	// (A pixel with no return is never flying: known before its lines are
	// read, which at the edge is 14 bounds-checked reads.)
	if (img.at(r, c) == 0) return false;
	float h[7], w[7];
	linesAt(img, r, c, 1, h, w);
	if (!spreadOnEitherLine(h, w, tol)) return false;
	for (int o = 0; o < 7; o++)
	{
		line[size_t(o) * stride] = h[o];
		line[size_t(o + 7) * stride] = w[o];
	}
	return true;
}

// Marks the flying pixels of row r in keep[c] = 0. A vector pass
// (flyingCandidates, ProjectRow.h) clears every pixel that cannot be flying
// (but see flyingCandidatesIn on pairs); only the few candidates left get
// the full test, in one vector loop over the row's candidates
// (flyingLines). Beyond the image's edge both read 0, as flyingAt does: the
// rows above the first and below the last are a row of zeros, and a
// candidate within 3 pixels of the edge has its lines gathered with 0
// outside (gatherLinesAtEdge; the two pixels at each end of a row are always
// candidates). Those border pixels went to flyingAt one at a time before
// (2026-11-27, gam-bench, 3 + 3 alternating runs: projection 0.597 -> 0.575
// ms on the Kinect One demo, 0.989 -> 0.962 ms on the Femto's). A decimated
// frame comes here as its own smaller image (project()).
void markFlyingRow(const RangeImageView& img, int r, float tol, bool avx2, uint8_t* keep, const FlyingBatch& batch)
{
	const int cols = img.cols, rows = img.rows;
	if (cols < 5)
	{
		for (int c = 0; c < cols; c++) keep[c] = uint8_t(!flyingAt(img, r, c, 1, tol));
		return;
	}
	const uint16_t* row = img.data + size_t(r) * img.stride;
	const auto rowAt = [&](int rr) { return rr >= 0 && rr < rows ? img.data + size_t(rr) * img.stride : batch.zeros; };
	const uint16_t *u1 = rowAt(r - 1), *u2 = rowAt(r - 2);
	const uint16_t *d1 = rowAt(r + 1), *d2 = rowAt(r + 2);
	const int t = int(tol), h = int(tol / 2);
	// With AVX2 the first pass also lists its candidates (in batch.cols,
	// which visit() below compacts in place: it writes entry count <= i
	// after reading entry i); -1 where they are not listed.
	int listed = -1;
	if (avx2)
		listed = detail::flyingCandidatesAvx2(u2, u1, row, d1, d2, cols, t, h, keep, batch.cols);
	else
		flyingCandidates(u2, u1, row, d1, d2, cols, t, h, keep);
	// The candidates are few: read from the list, or skip 8 kept pixels at a
	// time. Gather their lines (three pixels each side, 0 beyond the edge).
	const bool innerRow = r >= 3 && r + 3 < rows;
	const ptrdiff_t down = ptrdiff_t(img.stride);
	int count = 0;
	const auto visit = [&](int c) {
		if (!innerRow || c < 3 || c + 3 >= cols)
		{
			if (!gatherLinesAtEdge(img, r, c, tol, batch.lines + count, batch.stride))
			{
				keep[c] = 1;
				return;
			}
		}
		else
		{
			const uint16_t* p = row + c;
			for (int o = -3; o <= 3; o++)
			{
				batch.lines[size_t(o + 3) * batch.stride + size_t(count)] = float(p[o]);
				batch.lines[size_t(o + 10) * batch.stride + size_t(count)] = float(p[o * down]);
			}
		}
		batch.cols[count++] = c;
	};
	if (listed >= 0)
		for (int i = 0; i < listed; i++) visit(batch.cols[i]);
	else
	{
		int k = 0;
		for (; k + 8 <= cols; k += 8)
		{
			uint64_t eight;
			std::memcpy(&eight, keep + k, 8);
			if (eight == 0x0101010101010101ull) continue;
			for (int j = k; j < k + 8; j++)
				if (!keep[j]) visit(j);
		}
		for (; k < cols; k++)
			if (!keep[k]) visit(k);
	}
	if (avx2)
		detail::flyingLinesAvx2(batch.lines, batch.stride, count, tol, batch.along, batch.againstNothing);
	else
		flyingLines(batch.lines, batch.stride, count, tol, batch.along, batch.againstNothing);
	// Against no return (rare), a pixel must also stand alone: flyingAt.
	for (int i = 0; i < count; i++)
	{
		const int c = batch.cols[i];
		keep[c] = batch.along[i] ? 0 : !batch.againstNothing[i] ? 1 : uint8_t(!flyingAt(img, r, c, 1, tol));
	}
}
}  // namespace

bool DepthProjector::isFlyingPixel(const RangeImageView& img, int row, int col, int step, float tol)
{
	if (row < 0 || col < 0 || row >= img.rows || col >= img.cols || step < 1) return false;
	return flyingAt(img, row, col, step, tol);
}

size_t DepthProjector::project(
	const RangeImageView& img, const PinholeIntrinsics& K, const RigidTransform& T, const ProjectionFilter& f,
	const ElevationGrid& grid, BinnedPoints& out)
{
	K.validate();
	if (!img.data || img.rows <= 0 || img.cols <= 0) return 0;
	if (img.rows != K.height || img.cols != K.width)
		throw std::invalid_argument(
			"range image is " + std::to_string(img.cols) + "x" + std::to_string(img.rows) +
			" but the camera parameters say " + std::to_string(K.width) + "x" + std::to_string(K.height));
	if (!(img.units > 0) || !std::isfinite(img.units))
		throw std::invalid_argument("rangeUnits must be > 0 (got " + std::to_string(img.units) + ")");
	if (!T.R.allFinite() || !T.t.allFinite()) throw std::invalid_argument("sensor pose is not finite");
	updateLut(K);

	detail::RowParams p;
	const GridGeometry& g = grid.geometry();
	const float inv_res = float(1.0 / g.resolution);
	// Work in cell units relative to the grid origin: floats stay precise far
	// from the map origin, and the cell index is just the integer part.
	const Eigen::Matrix3f Rc = T.R * inv_res;
	const Eigen::Vector3f tc = (T.t - Eigen::Vector3f(float(g.x_min), float(g.y_min), 0.f)) * inv_res;
	for (int j = 0; j < 3; j++)
	{
		p.rx[j] = Rc(0, j);
		p.ry[j] = Rc(1, j);
		p.rz[j] = T.R(2, j);
	}
	p.t[0] = tc.x();
	p.t[1] = tc.y();
	p.t[2] = T.t.z();
	p.min_range = std::max(0.0f, f.min_range);
	p.max_range = f.max_range;
	p.z_min = f.z_min;
	p.z_max = f.z_max;
	p.nx = float(g.nx);
	p.ny = float(g.ny);
	p.nx_cells = g.nx;
	p.units = img.units;

	// With decimation n the frame is its every n-th row and column, a smaller
	// camera's frame with its own ray table: the same row loop (same floats)
	// and the same flying-pixel filter (neighbours n apart in the full
	// frame) as at full resolution. The filter went pixel by pixel through
	// flyingAt here before (2026-11-27, gam-bench, decimation 2: projection
	// 1.00 ms on the Kinect One demo, more than at full resolution).
	const int dec = std::max(1, f.decimation);
	RangeImageView src = img;
	const float *rayY = m_rayY.data(), *rayZ = m_rayZ.data(), *rayInvNorm = m_rayInvNorm.data();
	if (dec > 1)
	{
		updateDecimatedLut(dec);
		src.cols = (img.cols + dec - 1) / dec;
		src.rows = (img.rows + dec - 1) / dec;
		src.stride = size_t(src.cols);
		uint16_t* pixels = m_decImage.data();
		for (int r = 0; r < src.rows; r++)
		{
			const uint16_t* row = img.data + size_t(r) * size_t(dec) * img.stride;
			for (int k = 0; k < src.cols; k++) *pixels++ = row[size_t(k) * size_t(dec)];
		}
		src.data = m_decImage.data();
		rayY = m_decRayY.data();
		rayZ = m_decRayZ.data();
		rayInvNorm = m_decRayInvNorm.data();
	}
	const size_t start = out.size();
	out.prepare(size_t(src.cols) * size_t(src.rows));
	uint32_t* outCell = out.cellBuffer();
	float* outZ = out.zBuffer();
	size_t n = start;
	int32_t* rowCell = m_rowCell.data();
	float* rowZ = m_rowZ.data();
	const bool useAvx2 = m_allowAvx2 && detail::avx2RowLoopAvailable();
	// Flying pixels: one grid cell of tolerance (a smaller error moves a point
	// by less than a cell), in image units. Raw depths are 16-bit: a tolerance
	// of 65536 units or more passes every difference alike, and the row pass
	// takes it as an int (a corrupt rangeUnits of 1e-13 made it 5e11: found by
	// tests/fuzz/fuzz_rawlog).
	const float flyTol = float(std::min(g.resolution / double(img.units), 65536.0));
	uint8_t* keep = m_rowKeep.data();
	const FlyingBatch flyingBatch{m_flyCols.data(),  m_flyLines.data(),          size_t(K.width),
								  m_flyAlong.data(), m_flyAgainstNothing.data(), m_flyZeros.data()};

	for (int r = 0; r < src.rows; r++)
	{
		const size_t lutRow = size_t(r) * size_t(src.cols);
		const uint16_t* row = src.data + size_t(r) * src.stride;
		const float* invN = src.is_depth ? nullptr : rayInvNorm + lutRow;
		if (useAvx2)
			detail::projectRowAvx2(src.is_depth, p, row, rayY + lutRow, rayZ + lutRow, invN, src.cols, rowCell, rowZ);
		else
			projectRow(src.is_depth, p, row, rayY + lutRow, rayZ + lutRow, invN, src.cols, rowCell, rowZ);
		// Only the valid pixels (and, with the filter, the ones it keeps) go out.
		const uint8_t* kept = nullptr;
		if (f.drop_flying_pixels)
		{
			markFlyingRow(src, r, flyTol, useAvx2, keep, flyingBatch);
			kept = keep;
		}
		n = useAvx2 ? detail::compactRowAvx2(rowCell, rowZ, kept, src.cols, outCell, outZ, n)
					: compactRow(rowCell, rowZ, kept, src.cols, outCell, outZ, n);
	}
	out.commit(n);
	return n - start;
}

}  // namespace gam

namespace gam
{
bool DepthProjector::avx2Available() { return detail::avx2RowLoopAvailable(); }

void ProjectionFilter::validate() const
{
	checkParamRanges(*this, "");
	requireParams(z_min < z_max, "", "z_min must be < z_max");
	requireParams(min_range < max_range, "", "min_range must be < max_range");
}
}  // namespace gam
