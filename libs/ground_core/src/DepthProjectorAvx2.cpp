// Ground-aware mapping for MRPT
// The projector's row loop (and the flying-pixel filter's first pass) compiled for AVX2 (this file alone gets -mavx2;
// see CMakeLists.txt): 8 floats per instruction instead of SSE2's 4. No FMA, so the results are bit-identical to the
// SSE2 loop and maps do not depend on the CPU. DepthProjector.cpp calls it only when the CPU has AVX2.
#include "ProjectRow.h"

#include <algorithm>

#if defined(GAM_HAVE_AVX2_ROW_LOOP)
#include <immintrin.h>
#endif

namespace gam::detail
{
#if defined(GAM_HAVE_AVX2_ROW_LOOP)
bool avx2RowLoopAvailable()
{
	static const bool has = __builtin_cpu_supports("avx2");
	return has;
}
void projectRowAvx2(
	bool isDepth, const RowParams& p, const uint16_t* row, const float* ky, const float* kz, const float* invNorm,
	int cols, int32_t* cell, float* z)
{
	projectRow(isDepth, p, row, ky, kz, invNorm, cols, cell, z);
}
int flyingCandidatesAvx2(
	const uint16_t* u2, const uint16_t* u1, const uint16_t* row, const uint16_t* d1, const uint16_t* d2, int cols,
	int t, int h, uint8_t* keep, int32_t* candidates)
{
	// flyingCandidates, but a block of 16 pixels where no pixel with a return
	// differs by more than t from a neighbour in its row or its column (most
	// of a smooth surface) keeps all 16 without the full pass: both its lines
	// are calm there (dl <= t and dr <= t). Other blocks run
	// flyingCandidatesIn's tests on 16 lanes (they went through its loop, which
	// the compiler vectorized only in part: projection 0.509-0.514 ->
	// 0.488-0.496 ms a frame, Kinect One demo, 2026-11-28).
	uint16_t T, H;
	flyingCandidateLimits(t, h, T, H);
	keep[0] = keep[1] = keep[cols - 2] = keep[cols - 1] = 0;
	if (cols - 4 < 16)
	{
		// Narrower than a block: keep alone (the caller finds the candidates there).
		flyingCandidatesIn(u2, u1, row, d1, d2, 2, cols - 2, T, H, keep);
		return -1;
	}
	int n = 0;
	candidates[n++] = 0;
	candidates[n++] = 1;
	const __m256i limit = _mm256_set1_epi16(static_cast<short>(T)), zero = _mm256_setzero_si256();
	const auto load = [](const uint16_t* p) { return _mm256_loadu_si256(reinterpret_cast<const __m256i*>(p)); };
	// Lanes where |a - b| > T are non-zero.
	const auto jump = [&](__m256i a, __m256i b) {
		return _mm256_subs_epu16(_mm256_or_si256(_mm256_subs_epu16(a, b), _mm256_subs_epu16(b, a)), limit);
	};
	const __m256i hv = _mm256_set1_epi16(static_cast<short>(H)), h2 = _mm256_set1_epi16(static_cast<short>(2 * H));
	const auto isZero = [&](__m256i a) { return _mm256_cmpeq_epi16(a, zero); };
	// Unsigned a <= b, lane by lane.
	const auto atMost = [&](__m256i a, __m256i b) { return isZero(_mm256_subs_epu16(a, b)); };
	// calm() of flyingCandidatesIn for the line (p2, p1, x, n1, n2).
	const auto calm = [&](__m256i p2, __m256i p1, __m256i x, __m256i n1, __m256i n2) {
		const auto ends = [&](__m256i a, __m256i b) {  // (2 a - b - x + H) mod 2^16
			return _mm256_add_epi16(_mm256_sub_epi16(_mm256_sub_epi16(_mm256_add_epi16(a, a), b), x), hv);
		};
		const __m256i noP1 = isZero(p1), noN1 = isZero(n1);
		// A side continues x only where both its pixels returned.
		const __m256i contL = _mm256_andnot_si256(_mm256_or_si256(noP1, isZero(p2)), atMost(ends(p1, p2), h2));
		const __m256i contR = _mm256_andnot_si256(_mm256_or_si256(noN1, isZero(n2)), atMost(ends(n1, n2), h2));
		const __m256i dl = _mm256_or_si256(_mm256_subs_epu16(x, p1), _mm256_subs_epu16(p1, x));
		const __m256i dr = _mm256_or_si256(_mm256_subs_epu16(x, n1), _mm256_subs_epu16(n1, x));
		// Not nearer by more than t on that side (x - p1 saturates at 0 where x <= p1).
		const __m256i notNearL = _mm256_or_si256(noP1, atMost(_mm256_subs_epu16(x, p1), limit));
		const __m256i notNearR = _mm256_or_si256(noN1, atMost(_mm256_subs_epu16(x, n1), limit));
		return _mm256_or_si256(
			_mm256_or_si256(contL, contR),
			_mm256_or_si256(
				_mm256_and_si256(atMost(dl, limit), atMost(dr, limit)),
				_mm256_or_si256(_mm256_and_si256(noP1, notNearR), _mm256_and_si256(noN1, notNearL))));
	};
	// The blocks of 16 from column 2; the last one ends at cols - 2 and may
	// overlap the one before it (a pixel's keep byte depends on the image
	// alone: written twice, the same). Without it, the 12 pixels left of a
	// 512-pixel row went through flyingCandidatesIn's scalar loop.
	const int last = cols - 2 - 16;
	int done = 2;  // the columns before it are listed
	for (int c = 2;; c = std::min(c + 16, last))
	{
		const __m256i x = load(row + c);
		const __m256i jumps = _mm256_or_si256(
			_mm256_or_si256(jump(x, load(row + c - 1)), jump(x, load(row + c + 1))),
			_mm256_or_si256(jump(x, load(u1 + c)), jump(x, load(d1 + c))));
		const __m256i busy = _mm256_andnot_si256(_mm256_cmpeq_epi16(x, zero), jumps);
		if (_mm256_testz_si256(busy, busy))
		{
			_mm_storeu_si128(reinterpret_cast<__m128i*>(keep + c), _mm_set1_epi8(1));
			done = c + 16;
			if (c == last) break;
			continue;
		}
		// flyingCandidatesIn's tests on 16 lanes (the same 16-bit arithmetic:
		// the same keep bytes; a lane is all ones where a test holds).
		const __m256i calmRow = calm(load(row + c - 2), load(row + c - 1), x, load(row + c + 1), load(row + c + 2));
		const __m256i calmCol = calm(load(u2 + c), load(u1 + c), x, load(d1 + c), load(d2 + c));
		const __m256i kept = _mm256_or_si256(_mm256_and_si256(calmRow, calmCol), isZero(x));
		const __m256i ones = _mm256_srli_epi16(kept, 15);
		const __m128i bytes = _mm_packus_epi16(_mm256_castsi256_si128(ones), _mm256_extracti128_si256(ones, 1));
		_mm_storeu_si128(reinterpret_cast<__m128i*>(keep + c), bytes);
		// The candidates' columns, in order (those of an overlapping last
		// block that the block before it listed, not again).
		unsigned mask = unsigned(_mm_movemask_epi8(_mm_cmpeq_epi8(bytes, _mm_setzero_si128())));
		mask &= ~((1u << (done - c)) - 1u);
		for (; mask; mask &= mask - 1) candidates[n++] = c + __builtin_ctz(mask);
		done = c + 16;
		if (c == last) break;
	}
	candidates[n++] = cols - 2;
	candidates[n++] = cols - 1;
	return n;
}

namespace
{
// Left-packing 8 lanes: for each 8-bit mask of kept lanes, the indices of the
// kept lanes first (one byte each), and how many there are.
struct PackTable
{
	uint64_t lanes[256] = {};
	uint8_t count[256] = {};
	constexpr PackTable()
	{
		for (int m = 0; m < 256; m++)
		{
			int j = 0;
			for (int b = 0; b < 8; b++)
				if (m >> b & 1) lanes[m] |= uint64_t(b) << (8 * j++);
			count[m] = uint8_t(j);
		}
	}
};
constexpr PackTable kPack{};
}  // namespace

size_t compactRowAvx2(
	const int32_t* cell, const float* z, const uint8_t* keep, int cols, uint32_t* outCell, float* outZ, size_t n)
{
	// compactRow 8 pixels at a time: the kept ones are moved to the front of
	// the 8 lanes and all 8 stored at outCell[n] (the slots past the kept
	// ones are scratch, as in compactRow). Same output.
	const __m256i minusOne = _mm256_set1_epi32(-1), one = _mm256_set1_epi32(1), zero = _mm256_setzero_si256();
	int k = 0;
	for (; k + 8 <= cols; k += 8)
	{
		const __m256i c = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(cell + k));
		const __m256 zz = _mm256_loadu_ps(z + k);
		__m256i kept = _mm256_cmpgt_epi32(c, minusOne);
		if (keep)
		{
			const __m256i bytes = _mm256_cvtepu8_epi32(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(keep + k)));
			kept = _mm256_andnot_si256(_mm256_cmpeq_epi32(_mm256_and_si256(bytes, one), zero), kept);
		}
		const unsigned mask = unsigned(_mm256_movemask_ps(_mm256_castsi256_ps(kept)));
		const __m256i lanes = _mm256_cvtepu8_epi32(_mm_cvtsi64_si128(static_cast<long long>(kPack.lanes[mask])));
		_mm256_storeu_si256(reinterpret_cast<__m256i*>(outCell + n), _mm256_permutevar8x32_epi32(c, lanes));
		_mm256_storeu_ps(outZ + n, _mm256_permutevar8x32_ps(zz, lanes));
		n += kPack.count[mask];
	}
	return compactRow(cell + k, z + k, keep ? keep + k : nullptr, cols - k, outCell, outZ, n);
}

void flyingLinesAvx2(const float* lines, size_t stride, int count, float tol, uint8_t* along, uint8_t* againstNothing)
{
	flyingLines(lines, stride, count, tol, along, againstNothing);
}
#else
bool avx2RowLoopAvailable() { return false; }
void projectRowAvx2(
	bool, const RowParams&, const uint16_t*, const float*, const float*, const float*, int, int32_t*, float*)
{
}
int flyingCandidatesAvx2(
	const uint16_t*, const uint16_t*, const uint16_t*, const uint16_t*, const uint16_t*, int, int, int, uint8_t*,
	int32_t*)
{
	return 0;
}
size_t compactRowAvx2(const int32_t*, const float*, const uint8_t*, int, uint32_t*, float*, size_t n) { return n; }
void flyingLinesAvx2(const float*, size_t, int, float, uint8_t*, uint8_t*) {}
#endif
}  // namespace gam::detail
