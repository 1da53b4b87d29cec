// Ground-aware mapping for MRPT
// Internal to DepthProjector: the per-pixel kernel and the row loop, included
// by DepthProjector.cpp (SSE2, any x86-64) and DepthProjectorAvx2.cpp (compiled
// with -mavx2). Everything here has internal linkage, so the two compilations
// can never be mixed up by the linker.
#pragma once

#include <algorithm>
#include <cstdint>
#include <cstdlib>

#include "gam/core/DepthProjector.h"

namespace gam
{
namespace detail
{
/** The per-frame constants of the pixel loop (cell units in x and y). */
struct RowParams
{
	float rx[3], ry[3], rz[3], t[3];
	float min_range, max_range, z_min, z_max, nx, ny, units;
	int32_t nx_cells;
};

/** The row loop built for AVX2 (DepthProjectorAvx2.cpp) and whether this CPU
 * and build can run it. */
bool avx2RowLoopAvailable();
void projectRowAvx2(
	bool isDepth, const RowParams& p, const uint16_t* row, const float* ky, const float* kz, const float* invNorm,
	int cols, int32_t* cell, float* z);
void flyingCandidatesAvx2(
	const uint16_t* u2, const uint16_t* u1, const uint16_t* row, const uint16_t* d1, const uint16_t* d2, int cols,
	int t, int h, uint8_t* keep);
size_t compactRowAvx2(
	const int32_t* cell, const float* z, const uint8_t* keep, int cols, uint32_t* outCell, float* outZ, size_t n);
}  // namespace detail

namespace
{
using detail::RowParams;
// One pixel: its grid cell (-1 if it is dropped) and its height.
template <bool kDepth>
inline void projectPixel(const RowParams& p, uint16_t raw, float ky, float kz, float invNorm, int32_t& cell, float& z)
{
	const float v = float(raw) * p.units;  // 0 = no return: fails v > 0 below
	const float D = kDepth ? v : v * invNorm;
	// Sensor-frame point (D, D*ky, D*kz) mapped to the grid frame.
	const float sy = D * ky, sz = D * kz;
	const float fx = p.rx[0] * D + p.rx[1] * sy + p.rx[2] * sz + p.t[0];  // cells
	const float fy = p.ry[0] * D + p.ry[1] * sy + p.ry[2] * sz + p.t[1];
	const float gz = p.rz[0] * D + p.rz[1] * sy + p.rz[2] * sz + p.t[2];  // metres
	// Written so that NaN fails every comparison.
	const bool ok = (v > 0.f) & (v >= p.min_range) & (v <= p.max_range) & (gz >= p.z_min) & (gz <= p.z_max) &
					(fx >= 0.f) & (fy >= 0.f) & (fx < p.nx) & (fy < p.ny);
	// int() of a value outside the int range is UB: convert only in-grid values.
	const int32_t cx = int32_t(ok ? fx : 0.f), cy = int32_t(ok ? fy : 0.f);
	cell = ok ? cy * p.nx_cells + cx : -1;
	z = gz;
}

// A full row: no branches and unit strides, so the compiler vectorizes it.
template <bool kDepth>
void projectRowLoop(
	const RowParams& p, const uint16_t* __restrict row, const float* __restrict ky, const float* __restrict kz,
	const float* __restrict invNorm, int cols, int32_t* __restrict cell, float* __restrict z)
{
	for (int c = 0; c < cols; c++)
		projectPixel<kDepth>(p, row[c], ky[c], kz[c], kDepth ? 1.f : invNorm[c], cell[c], z[c]);
}

// The row loop for a depth image (invNorm unused) or a range image.
inline void projectRow(
	bool isDepth, const RowParams& p, const uint16_t* row, const float* ky, const float* kz, const float* invNorm,
	int cols, int32_t* cell, float* z)
{
	if (isDepth)
		projectRowLoop<true>(p, row, ky, kz, invNorm, cols, cell, z);
	else
		projectRowLoop<false>(p, row, ky, kz, invNorm, cols, cell, z);
}

// Compaction of a projected row: every pixel is written at outCell[n], only
// the kept ones (cell >= 0 and, with a filter, keep & 1) advance n
// (branch-free: kept and dropped pixels interleave at random). keep may be
// null. Returns the new n; writes up to cols slots from the old n on.
inline size_t compactRow(
	const int32_t* __restrict cell, const float* __restrict z, const uint8_t* __restrict keep, int cols,
	uint32_t* __restrict outCell, float* __restrict outZ, size_t n)
{
	if (keep)
		for (int k = 0; k < cols; k++)
		{
			outCell[n] = uint32_t(cell[k]);
			outZ[n] = z[k];
			n += size_t(cell[k] >= 0) & size_t(keep[k]);
		}
	else
		for (int k = 0; k < cols; k++)
		{
			outCell[n] = uint32_t(cell[k]);
			outZ[n] = z[k];
			n += size_t(cell[k] >= 0);
		}
	return n;
}

// The flying-pixel filter's first pass over a row (rows u2, u1 above it, d1,
// d2 below; see markFlyingRow in DepthProjector.cpp): keep[c] = 1 for every
// pixel that cannot be flying, 0 for the candidates (and the two pixels at
// each end). A line (p2, p1, x, n1, n2) clears x when one side continues to
// it in depth (|2 p1 - p2 - x| <= h, both of its pixels with a return), when
// x jumps by more than t to neither neighbour (then it is between none) or
// when a neighbour has no return and the other is not nearer by more than t.
// All in 16-bit arithmetic (16 pixels per AVX2 instruction): |e| <= h is
// tested as (e + h) mod 2^16 <= 2 h, which can wrongly clear a pixel only
// when |2 p1 - p2 - x| >= 2^16 - h, i.e. for depths over 2^15 units (33 m
// in millimetres); it never makes a kept pixel a candidate.
inline void flyingCandidates(
	const uint16_t* __restrict u2, const uint16_t* __restrict u1, const uint16_t* __restrict row,
	const uint16_t* __restrict d1, const uint16_t* __restrict d2, int cols, int t, int h, uint8_t* __restrict keep)
{
	const uint16_t T = uint16_t(std::min(t, 65535)), H = uint16_t(std::min(h, 16383)), H2 = uint16_t(2 * H);
	auto calm = [&](uint16_t p2, uint16_t p1, uint16_t x, uint16_t n1, uint16_t n2) -> uint16_t {
		const uint16_t el = uint16_t(uint16_t(2 * p1 - p2 - x) + H), er = uint16_t(uint16_t(2 * n1 - n2 - x) + H);
		const uint16_t dl = uint16_t(x > p1 ? x - p1 : p1 - x), dr = uint16_t(x > n1 ? x - n1 : n1 - x);
		// A side continues x only where both its pixels returned.
		const uint16_t contL = (el <= H2) & (p1 != 0) & (p2 != 0), contR = (er <= H2) & (n1 != 0) & (n2 != 0);
		// Next to a pixel without a return, x can be flying only when the
		// other neighbour is nearer by more than t.
		const uint16_t nearL = (p1 != 0) & (x > p1) & (dl > T), nearR = (n1 != 0) & (x > n1) & (dr > T);
		return uint16_t(contL | contR | ((dl <= T) & (dr <= T)) | ((p1 == 0) & !nearR) | ((n1 == 0) & !nearL));
	};
	keep[0] = keep[1] = keep[cols - 2] = keep[cols - 1] = 0;
	for (int c = 2; c < cols - 2; c++)
	{
		const uint16_t x = row[c];
		keep[c] = uint8_t(
			(calm(row[c - 2], row[c - 1], x, row[c + 1], row[c + 2]) & calm(u2[c], u1[c], x, d1[c], d2[c])) | (x == 0));
	}
}
}  // namespace
}  // namespace gam
