// Box arithmetic shared by the LBVH build and refit passes (internal to kernels/bvh).
#pragma once

#include <algorithm>

#include "kernels/bvh/lbvh_build.h"
#include "kernels/common/kernel.h"

namespace impact::kernels::lbvh_detail {

struct Bounds {
  float lo[3];
  float hi[3];
};

/// The bounds of anything with min_x .. max_z (SortedBox, LbvhNode, packed records).
template <class B>
IMPACT_INLINE Bounds bounds_of(const B& b) {
  return {{b.min_x, b.min_y, b.min_z}, {b.max_x, b.max_y, b.max_z}};
}

/// Exact union (min / max): the same bytes whatever the order of the two.
IMPACT_INLINE Bounds unite(const Bounds& a, const Bounds& b) {
  return {{std::min(a.lo[0], b.lo[0]), std::min(a.lo[1], b.lo[1]), std::min(a.lo[2], b.lo[2])},
          {std::max(a.hi[0], b.hi[0]), std::max(a.hi[1], b.hi[1]), std::max(a.hi[2], b.hi[2])}};
}

/// Writes u into the node's box fields (split and last untouched).
IMPACT_INLINE void store_bounds(LbvhNode& node, const Bounds& u) {
  node.min_x = u.lo[0];
  node.min_y = u.lo[1];
  node.min_z = u.lo[2];
  node.max_x = u.hi[0];
  node.max_y = u.hi[1];
  node.max_z = u.hi[2];
}

/// Leaves ahead of the current one whose records the build and refit gathers
/// prefetch: the gather packed[leaf_index[s]] is a random 32-byte read (a cache miss
/// at 1M boxes) that the climb after it keeps the core from overlapping by itself.
inline constexpr uint32_t kGatherAhead = 32;

/// Prefetches the packed record of sorted leaf s + kGatherAhead (when below end).
IMPACT_INLINE void prefetch_gather(const SortedBox* packed, const uint32_t* leaf_index, uint32_t s,
                                   uint32_t end) {
  if (packed && s + kGatherAhead < end) __builtin_prefetch(&packed[leaf_index[s + kGatherAhead]]);
}

}  // namespace impact::kernels::lbvh_detail
