// The box-record verb of the SIMD vocabulary: do two boxes overlap, each given as two
// 16-byte halves (min x, y, z + a spare lane; max x, y, z + a spare lane)? One 4-lane
// compare per half and one movemask, instead of six compare-and-branches; the spare
// lane is ignored. kernels/common/sorted_box.h builds the record tests on it.
//
// Preconditions: each pointer 16-byte aligned with four readable floats; inputs
// NaN-free (then every path below gives the same answer). Touching counts as overlap
// (min <= max on every axis).
// Paths: SSE2 (every x86-64 target) unless -DIMPACT_SIMD_SCALAR, whose one-lane
// backend takes the plain comparisons, as it does for every verb of kernels/simd/.
#pragma once

#if defined(__SSE2__) && !defined(IMPACT_SIMD_SCALAR)
#include <immintrin.h>
#endif

#include "kernels/common/kernel.h"

namespace impact::kernels::simd {

/// a_min[0..2] <= b_max[0..2] and b_min[0..2] <= a_max[0..2], lane 3 ignored.
IMPACT_INLINE bool box_halves_overlap(const float* a_min, const float* a_max, const float* b_min,
                                      const float* b_max) {
#if defined(__SSE2__) && !defined(IMPACT_SIMD_SCALAR)
  const __m128 a_lo = _mm_load_ps(a_min), a_hi = _mm_load_ps(a_max);
  const __m128 b_lo = _mm_load_ps(b_min), b_hi = _mm_load_ps(b_max);
  const __m128 le = _mm_and_ps(_mm_cmple_ps(a_lo, b_hi), _mm_cmple_ps(b_lo, a_hi));
  return (_mm_movemask_ps(le) & 7) == 7;
#else
  return a_min[0] <= b_max[0] && b_min[0] <= a_max[0] && a_min[1] <= b_max[1] && b_min[1] <= a_max[1] &&
         a_min[2] <= b_max[2] && b_min[2] <= a_max[2];
#endif
}

}  // namespace impact::kernels::simd
