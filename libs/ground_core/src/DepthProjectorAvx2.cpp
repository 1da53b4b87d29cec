// Ground-aware mapping for MRPT
// The projector's row loop (and the flying-pixel filter's first pass) compiled for AVX2 (this file alone gets -mavx2;
// see CMakeLists.txt): 8 floats per instruction instead of SSE2's 4. No FMA, so the results are bit-identical to the
// SSE2 loop and maps do not depend on the CPU. DepthProjector.cpp calls it only when the CPU has AVX2.
#include "ProjectRow.h"

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
void flyingCandidatesAvx2(
	const uint16_t* u2, const uint16_t* u1, const uint16_t* row, const uint16_t* d1, const uint16_t* d2, int cols,
	int t, int h, uint8_t* keep)
{
	flyingCandidates(u2, u1, row, d1, d2, cols, t, h, keep);
}
#else
bool avx2RowLoopAvailable() { return false; }
void projectRowAvx2(
	bool, const RowParams&, const uint16_t*, const float*, const float*, const float*, int, int32_t*, float*)
{
}
void flyingCandidatesAvx2(
	const uint16_t*, const uint16_t*, const uint16_t*, const uint16_t*, const uint16_t*, int, int, int, uint8_t*)
{
}
#endif
}  // namespace gam::detail
