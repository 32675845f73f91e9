#include "kernels/bvh/lbvh_refit.h"

#include <algorithm>
#include <atomic>

namespace impact::kernels {
namespace {

struct Bounds {
  float lo[3];
  float hi[3];
};

IMPACT_INLINE Bounds bounds_of(const SortedBox& b) {
  return {{b.min_x, b.min_y, b.min_z}, {b.max_x, b.max_y, b.max_z}};
}
IMPACT_INLINE Bounds bounds_of(const LbvhNode& b) {
  return {{b.min_x, b.min_y, b.min_z}, {b.max_x, b.max_y, b.max_z}};
}

}  // namespace

void lbvh_refit(AabbSoA boxes, PairFilter filter, LbvhRefitIn in, LbvhRefitOut out, uint32_t n,
                Range r) {
  for (uint32_t s = r.begin; s < r.end; ++s) {
    const uint32_t i = in.leaf_index[s];
    out.leaves[s] = SortedBox{boxes.min_x[i], boxes.min_y[i], boxes.min_z[i], i,
                              boxes.max_x[i], boxes.max_y[i], boxes.max_z[i], 0u};
    if (filter.layer) {
      out.layer[s] = filter.layer[i];
      out.mask[s] = filter.mask[i];
      out.is_static[s] = filter.is_static[i];
    }
    if (n < 2) continue;
    uint32_t p = in.leaf_parent[s];
    while (p != kInvalidBody) {
      std::atomic_ref<uint32_t> counter(out.refit_counter[p]);
      // acq_rel: publishes this child's bounds to the sibling's climb (release) and,
      // for the second arrival, makes the sibling's bounds visible here (acquire).
      if ((counter.fetch_add(1, std::memory_order_acq_rel) & 1u) == 0) break;
      LbvhNode& node = out.nodes[p];
      const uint32_t g = node.split & kLbvhSplitMask;
      const Bounds a = (node.split & kLbvhLeftLeaf) ? bounds_of(out.leaves[g]) : bounds_of(out.nodes[g]);
      const Bounds b =
          (node.split & kLbvhRightLeaf) ? bounds_of(out.leaves[g + 1]) : bounds_of(out.nodes[g + 1]);
      node.min_x = std::min(a.lo[0], b.lo[0]);
      node.min_y = std::min(a.lo[1], b.lo[1]);
      node.min_z = std::min(a.lo[2], b.lo[2]);
      node.max_x = std::max(a.hi[0], b.hi[0]);
      node.max_y = std::max(a.hi[1], b.hi[1]);
      node.max_z = std::max(a.hi[2], b.hi[2]);
      p = in.internal_parent[p];
    }
  }
}

}  // namespace impact::kernels
