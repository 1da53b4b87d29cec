// Ground-aware mapping for MRPT
// Internal to DepthProjector: the per-pixel kernel and the row loop, included
// by DepthProjector.cpp (SSE2, any x86-64) and DepthProjectorAvx2.cpp (compiled
// with -mavx2). Everything here has internal linkage, so the two compilations
// can never be mixed up by the linker.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
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
/** flyingCandidates, and the columns of its candidates (keep 0) in order
 * into candidates (room for cols); returns how many, or -1 for a row
 * narrower than 20 pixels, whose candidates it does not list. */
int flyingCandidatesAvx2(
	const uint16_t* u2, const uint16_t* u1, const uint16_t* row, const uint16_t* d1, const uint16_t* d2, int cols,
	int t, int h, uint8_t* keep, int32_t* candidates);
size_t compactRowAvx2(
	const int32_t* cell, const float* z, const uint8_t* keep, int cols, uint32_t* outCell, float* outZ, size_t n);
void flyingLinesAvx2(const float* lines, size_t stride, int count, float tol, uint8_t* along, uint8_t* againstNothing);
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

// --- The flying-pixel rule (DepthProjector::isFlyingPixel) ---
// Each test reads one line of the image through the pixel (a row or a
// column): the depths v[0..6] at offsets -3 ... +3 steps (0 outside the
// image), the pixel at v[3]. Written with & and | (every part evaluated, no
// branch) so that a batch of candidates runs as a vector loop
// (flyingLines); the answers are those of the short-circuit form.

// Whether the surface through `far` and `near` (the two pixels on one side,
// `near` the adjacent one) continues to depth d within tol: on a plane the
// inverse depth is affine in the pixel coordinates. (Without a return on
// that side, no: the quotients of a 0 are then never used.)
inline bool continues(float far, float near, float d, float tol)
{
	const float inv = 2.0f / near - 1.0f / far;
	return (far > 0) & (near > 0) & (inv > 0) & (std::abs(1.0f / inv - d) <= tol);
}

// Strictly between a and b, more than tol from each.
inline bool between(float a, float d, float b, float tol)
{
	return (a > 0) & (b > 0) & ((d - a) * (b - d) > 0) & (std::abs(d - a) > tol) & (std::abs(d - b) > tol);
}

// Relative depth jump from the near side that a pixel next to a no-return
// must show to count as flying (see againstNothingAlong).
constexpr float kAgainstNothingJump = 0.05f;

// Mixed pixels come alone or in pairs (both sides of an edge can mix): a
// pair is two pixels within tol of each other, between the pixels around
// it, that continues neither side.
inline bool flyingAlong(const float* v, float tol)
{
	const float d = v[3];
	const bool leftContinues = continues(v[1], v[2], d, tol), rightContinues = continues(v[5], v[4], d, tol);
	const bool alone = between(v[2], d, v[4], tol) & !leftContinues & !rightContinues;
	const bool pairedWithNext = (std::abs(v[4] - d) <= tol) & between(v[2], d, v[5], tol) &
								between(v[2], v[4], v[5], tol) & !leftContinues & !continues(v[6], v[5], v[4], tol);
	const bool pairedWithPrevious = (std::abs(v[2] - d) <= tol) & between(v[1], d, v[4], tol) &
									between(v[1], v[2], v[4], tol) & !continues(v[0], v[1], v[2], tol) &
									!rightContinues;
	return alone | pairedWithNext | pairedWithPrevious;
}

// Against no return, along one line: the background behind an edge beyond
// the range (or absorbing) returns nothing, but the mixed pixel still lies
// between the edge and that background. One side has no return, the other
// is nearer by more than tol and by more than kAgainstNothingJump of d, and d
// continues neither the near side nor a return just past the gap. (With only
// one side to compare with, the jump must also exceed what noise makes
// between two pixels of one surface: at most 4.2 % at p99.99 on simulated
// Kinect One frames, up to 78 deg incidence at 4.5 m; with tol alone, far
// floor next to a dropout was dropped, 700 pixels a frame.)
inline bool againstNothingAlong(const float* v, float tol)
{
	const float d = v[3], jump = std::max(tol, kAgainstNothingJump * d);
	const auto one = [&](float nearFar, float nearNext, float gap, float beyond) {
		return (gap == 0) & (nearNext > 0) & (d - nearNext > jump) & !continues(nearFar, nearNext, d, tol) &
			   !((beyond > 0) & (std::abs(beyond - d) <= tol));
	};
	return one(v[1], v[2], v[4], v[5]) | one(v[5], v[4], v[2], v[1]);
}

// What flyingAlong or againstNothingAlong needs along a line: a neighbour
// (+-1, +-2) with a return nearer than the pixel by more than t and, unless
// a pixel next to it has no return, one farther by more than t (t = tol
// rounded down: the depths are whole image units). Cheap, and false for
// most pixels: the full tests run only where it holds.
inline bool spreadAlong(const float* v, float t)
{
	const float d = v[3];
	bool nearer = false, farther = false;
	for (int o : {1, 2, 4, 5})
	{
		nearer |= (v[o] > 0) & (v[o] < d - t);
		farther |= v[o] > d + t;
	}
	return nearer & (farther | (v[2] == 0) | (v[4] == 0));
}

// For a batch of pixels, the two lines of each (lines[o * stride + k]: row
// line o = 0..6, column line o = 7..13, of pixel k): along[k] =
// flyingAlong on either line, againstNothing[k] = againstNothingAlong on
// either line. A vector loop: every pixel pays for every division, 8 at a
// time, instead of the mispredicted branches of one pixel at a time.
inline void flyingLines(
	const float* __restrict lines, size_t stride, int count, float tol, uint8_t* __restrict along,
	uint8_t* __restrict againstNothing)
{
	for (int k = 0; k < count; k++)
	{
		float h[7], w[7];
		for (int o = 0; o < 7; o++)
		{
			h[o] = lines[size_t(o) * stride + size_t(k)];
			w[o] = lines[size_t(o + 7) * stride + size_t(k)];
		}
		along[k] = uint8_t(flyingAlong(h, tol) | flyingAlong(w, tol));
		againstNothing[k] = uint8_t(againstNothingAlong(h, tol) | againstNothingAlong(w, tol));
	}
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
// Not quite "cannot": a side that continues x also clears x where x is the
// second pixel of a pair (p1, x) that the full rule flags, p1 being flying
// itself (5-13 pixels a frame on simulated Kinect One and Femto frames; test
// FirstPassKeepsThePairedPixelThatOneSideContinues). What project() drops
// is this pass, then the full rule on its candidates.
// All in 16-bit arithmetic (16 pixels per AVX2 instruction): |e| <= h is
// tested as (e + h) mod 2^16 <= 2 h, which can wrongly clear a pixel only
// when |2 p1 - p2 - x| >= 2^16 - h, i.e. for depths over 2^15 units (33 m
// in millimetres); it never makes a kept pixel a candidate.
// keep[c] for begin <= c < end (2 <= begin, end <= cols - 2), with T = t and
// H = h clamped (flyingCandidateLimits).
inline void flyingCandidatesIn(
	const uint16_t* __restrict u2, const uint16_t* __restrict u1, const uint16_t* __restrict row,
	const uint16_t* __restrict d1, const uint16_t* __restrict d2, int begin, int end, uint16_t T, uint16_t H,
	uint8_t* __restrict keep)
{
	const uint16_t H2 = uint16_t(2 * H);
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
	for (int c = begin; c < end; c++)
	{
		const uint16_t x = row[c];
		keep[c] = uint8_t(
			(calm(row[c - 2], row[c - 1], x, row[c + 1], row[c + 2]) & calm(u2[c], u1[c], x, d1[c], d2[c])) | (x == 0));
	}
}

// T and H of flyingCandidatesIn from the tolerances t and h.
inline void flyingCandidateLimits(int t, int h, uint16_t& T, uint16_t& H)
{
	T = uint16_t(std::min(t, 65535));
	H = uint16_t(std::min(h, 16383));
}

inline void flyingCandidates(
	const uint16_t* __restrict u2, const uint16_t* __restrict u1, const uint16_t* __restrict row,
	const uint16_t* __restrict d1, const uint16_t* __restrict d2, int cols, int t, int h, uint8_t* __restrict keep)
{
	uint16_t T, H;
	flyingCandidateLimits(t, h, T, H);
	keep[0] = keep[1] = keep[cols - 2] = keep[cols - 1] = 0;
	flyingCandidatesIn(u2, u1, row, d1, d2, 2, cols - 2, T, H, keep);
}
}  // namespace
}  // namespace gam
