// Sweep-and-prune broad phase over axis-aligned boxes (the seeds' "plane sweep"):
//
//   sap_moments      per range: sums of box centres and of their squares (double,
//                    shifted by a reference point) -> the host picks the sweep axis
//                    of greatest variance, combining one partial per chunk in order
//   sap_keys         per box: key = sap_float_key(min on the sweep axis) << 32 | index
//   (radix sort of the keys on bits [32, 64): stable, so ties keep index order)
//   sap_rekey        incremental mode: the keys of the last call's sorted order,
//                    refreshed with this call's boxes (same index per slot)
//   sap_insertion_sort  incremental mode: restores (mapped min, index) order in
//                    O(n + shifts), serially; gives up past a shift limit
//   sap_gather       per sorted slot: copy the box (sweep axis first) and its filter
//                    data into sorted SoA arrays; sap_pad appends kSapPad sentinels
//   sap_find_pairs   per sorted slot s: scan slots t > s while min0[t] <= max0[s]
//                    (min0 is sorted, so no later slot can overlap s on the sweep
//                    axis), testing the other two axes and the filter.
//
// Both sorts produce the same total order (mapped min, then index), so the pairs
// and their order do not depend on which path sorted them, nor on thread count.
// Pair order: by query slot s (sweep-axis min, ties by index), then by slot t
// increasing. Each pair holds (lo, hi) original box indices. Overlap includes
// touching (min <= max on every axis). Filter: (layer_a & mask_b) and
// (layer_b & mask_a) nonzero, and not both static (pair_allowed, kernels/common/pair.h).
// Preconditions: inputs finite with min <= max (validated at ingest); the
// sentinels (min = +inf, max = -inf) then never overlap a box and stop every scan.
// Layout: sorted SoA rather than 32-byte SortedBox records, so the candidate test
// runs 16 slots at a time over contiguous floats (the scan visits many candidates
// per real pair: about n * extent / world size).
// Cost: keys, gather O(n); radix sort O(n) per pass (3 passes for the 32-bit mapped
// min from 2^15 boxes, 4 below); sweep O(n + candidates); insertion sort O(n + shifts)
// serial.
// Method: sort and sweep, Baraff 1992 ("Dynamic Simulation of Non-penetrating
// Rigid Bodies", ch. 6: coherence + insertion sort) and Cohen et al. 1995
// (I-COLLIDE); the single-axis parallel sweep of Liu et al. 2010 ("Real-time
// Collision Culling of a Million Bodies on Graphics Processing Units"), which also
// picks the axis of greatest centre variance.
#pragma once

#include <bit>

#include "kernels/broadphase/bounds.h"
#include "kernels/common/kernel.h"
#include "kernels/common/pair.h"
#include "kernels/common/sorted_box.h"

namespace impact::kernels {

/// Sentinel slots after the last sorted slot (the sweep reads 16 slots at a time).
inline constexpr uint32_t kSapPad = 16;

/// Order-preserving map of a float to uint32: a < b (as floats) implies
/// key(a) < key(b); -0.0 maps just below +0.0 (they compare equal as floats, so
/// any order between them is consistent). Negative floats are inverted, positive
/// ones get the sign bit set. NaN is rejected before it gets here.
IMPACT_INLINE uint32_t sap_float_key(float f) {
  const uint32_t u = std::bit_cast<uint32_t>(f);
  return (u & 0x80000000u) ? ~u : (u | 0x80000000u);
}

/// Sums over a range of box centres c (per axis, c - shift, in double) and of
/// their squares.
struct SapMoments {
  double sum[3];
  double sum_sq[3];
};

/// Sorted SoA arrays (axis 0 = the sweep axis, then the next two cyclically),
/// each with room for n + kSapPad slots. Filter arrays null when unfiltered.
struct SapSorted {
  float* min[3];
  float* max[3];
  uint32_t* index;
  uint32_t* layer;
  uint32_t* mask;
  uint8_t* is_static;
};

struct SapView {
  const float* min[3];
  const float* max[3];
  const uint32_t* index;
  const uint32_t* layer;  // null when unfiltered
  const uint32_t* mask;
  const uint8_t* is_static;
  uint32_t n;  ///< sorted slots; n + kSapPad are readable (sentinels after n)
};

SapMoments sap_moments(AabbSoA boxes, const double shift[3], Range r);

/// out_keys[i] = sap_float_key(min on axis of box i) << 32 | i.
void sap_keys(AabbSoA boxes, uint32_t axis, uint64_t* IMPACT_RESTRICT out_keys, Range r);

/// io_keys[s] keeps its index i (low half) and gets this call's mapped min of box i.
void sap_rekey(AabbSoA boxes, uint32_t axis, uint64_t* IMPACT_RESTRICT io_keys, Range r);

/// Sorts io_keys[r.begin, r.end) ascending by insertion sort (keys distinct) and
/// returns the number of element shifts. Stops once the shifts exceed max_shifts
/// and returns a value > max_shifts; the keys are then a partly sorted permutation.
/// Serial: the host calls it on the whole array.
uint64_t sap_insertion_sort(uint64_t* IMPACT_RESTRICT io_keys, uint64_t max_shifts, Range r);

void sap_gather(const uint64_t* IMPACT_RESTRICT sorted_keys, AabbSoA boxes, uint32_t axis,
                PairFilter filter, SapSorted out, Range r);

/// Writes the kSapPad sentinel slots n .. n + kSapPad - 1.
void sap_pad(SapSorted out, uint32_t n);

/// Writes the pairs whose query slot lies in r to out[0, capacity) in the
/// documented order and returns how many there are; when that exceeds capacity
/// only the first `capacity` are written and the caller reruns with more room.
uint64_t sap_find_pairs(const SapView& v, Pair* IMPACT_RESTRICT out, uint64_t capacity, Range r);

}  // namespace impact::kernels
