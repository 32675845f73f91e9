// The 32-byte box record shared by the broad phases, the LBVH and the ray BVH
// (SortedBox: min corner + index, max corner + a spare word), and the box overlap
// tests on it. A record is one cache line half, so a pair pass touches one line
// per candidate instead of one per field, and its two 16-byte halves are tested
// in one 4-lane compare each (simd::box_halves_overlap, kernels/simd/box_overlap.h).
// Overlap includes touching (min <= max); inputs NaN-free.
#pragma once

#include <cstddef>
#include <cstdint>

#include "kernels/common/kernel.h"
#include "kernels/simd/box_overlap.h"

namespace impact::kernels {

/// Overlap of two boxes (any types with min_x .. max_z), touching included.
/// Bitwise & (not &&): one hard-to-predict branch instead of six.
template <class A, class B>
IMPACT_INLINE bool boxes_overlap(const A& a, const B& b) {
  return (a.min_x <= b.max_x) & (b.min_x <= a.max_x) & (a.min_y <= b.max_y) & (b.min_y <= a.max_y) &
         (a.min_z <= b.max_z) & (b.min_z <= a.max_z);
}

/// A box in sorted-slot order with its original index: 32 bytes, so the pair
/// pass touches one cache line per candidate instead of one per field.
struct alignas(32) SortedBox {
  float min_x, min_y, min_z;
  uint32_t index;
  float max_x, max_y, max_z;
  uint32_t pad;
};
static_assert(sizeof(SortedBox) == 32);

/// boxes_overlap for two 32-byte box records laid out as SortedBox (min_x..min_z +
/// a 32-bit word, max_x..max_z + a 32-bit word, 16-byte aligned halves: SortedBox,
/// LbvhNode): one 4-lane compare per half (the 4th lane is ignored), so the test
/// costs two compares and one branch instead of six compare-and-branches. Same
/// result as boxes_overlap (NaN-free inputs). records_overlap_at takes the second
/// record by address (b[0..2] min, b[4..6] max, 16-byte aligned), for code that
/// picks among record arrays by index rather than by type.
template <class A>
IMPACT_INLINE bool records_overlap_at(const A& a, const float* b) {
  static_assert(sizeof(A) == 32 && alignof(A) >= 16);
  return simd::box_halves_overlap(&a.min_x, &a.max_x, b, b + 4);
}

template <class A, class B>
IMPACT_INLINE bool records_overlap(const A& a, const B& b) {
  static_assert(sizeof(B) == 32 && alignof(B) >= 16);
  static_assert(offsetof(B, min_x) == 0 && offsetof(B, max_x) == 16);
  return records_overlap_at(a, &b.min_x);
}

IMPACT_INLINE bool sorted_boxes_overlap(const SortedBox& a, const SortedBox& b) { return records_overlap(a, b); }

}  // namespace impact::kernels
