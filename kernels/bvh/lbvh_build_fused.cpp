#include "kernels/bvh/lbvh_build_fused.h"

#include <algorithm>
#include <bit>

#include "kernels/bvh/lbvh_bounds.h"

namespace impact::kernels {
namespace {

constexpr uint32_t kBlocked = 0xffffffffu;

using lbvh_detail::Bounds;
using lbvh_detail::bounds_of;
using lbvh_detail::unite;

struct Ctx {
  const LbvhFusedIn& in;
  const LbvhFusedOut& out;
  uint32_t n;

  // Common prefix of keys i and i + 1 (lbvh_build.h: the position breaks ties).
  IMPACT_INLINE int delta(uint32_t i) const {
    const uint64_t a = in.codes[i] >> in.shift;
    const uint64_t b = in.codes[i + 1] >> in.shift;
    if (a != b) return std::countl_zero(a ^ b);
    return 64 + std::countl_zero(i ^ (i + 1));
  }
  // Subtree [l, r] (not the root) is the left child of the node split at r.
  IMPACT_INLINE bool is_left_child(uint32_t l, uint32_t r) const {
    if (l == 0) return true;
    if (r == n - 1) return false;
    return delta(r) > delta(l - 1);
  }
  IMPACT_INLINE Bounds child(bool leaf, uint32_t c) const {
    return leaf ? bounds_of(out.refit.leaves[c]) : bounds_of(out.topo.nodes[c]);
  }

  // Creates the node [l, r] split at g from its two complete children (bounds
  // `left` / `right`), then climbs on; `block` (the chunk start, 0 for none) stops
  // the climb at a left sibling outside the chunk. Returns the last leaf of a
  // blocked subtree, or kBlocked when the climb ended normally.
  IMPACT_INLINE uint32_t climb(uint32_t l, uint32_t r, Bounds cur, uint32_t block) const {
    for (;;) {
      if (l == 0 && r == n - 1) return kBlocked;  // the root is complete
      if (is_left_child(l, r)) {
        out.slot[r] = l;
        return kBlocked;
      }
      const uint32_t g = l - 1;
      if (l == block || out.slot[g] == kBlocked) {
        out.slot[r] = kBlocked;
        return r;
      }
      const uint32_t first = out.slot[g];
      cur = create(first, r, g, child(first == g, g), cur);
      l = first;
    }
  }

  // Writes node [l, r] split at g; returns its bounds.
  IMPACT_INLINE Bounds create(uint32_t l, uint32_t r, uint32_t g, const Bounds& left,
                              const Bounds& right) const {
    const bool root = l == 0 && r == n - 1;
    const uint32_t idx = root ? 0 : is_left_child(l, r) ? r : l;
    const bool left_leaf = l == g, right_leaf = r == g + 1;
    const Bounds u = unite(left, right);
    LbvhNode& node = out.topo.nodes[idx];
    lbvh_detail::store_bounds(node, u);
    node.split = g | (left_leaf ? kLbvhLeftLeaf : 0u) | (right_leaf ? kLbvhRightLeaf : 0u);
    node.last = r;
    (left_leaf ? out.topo.leaf_parent : out.topo.internal_parent)[g] = idx;
    (right_leaf ? out.topo.leaf_parent : out.topo.internal_parent)[g + 1] = idx;
    if (root) out.topo.internal_parent[0] = kInvalidBody;
    return u;
  }
};

}  // namespace

void lbvh_build_fused(AabbSoA boxes, PairFilter filter, LbvhFusedIn in, LbvhFusedOut out, uint32_t n,
                      Range r, LbvhBlocked* out_blocked) {
  IMPACT_ASSERT(n >= 1 && n <= kLbvhMaxLeaves);
  const Ctx ctx{in, out, n};
  out_blocked->count = 0;
  for (uint32_t s = r.begin; s < r.end; ++s) {
    lbvh_detail::prefetch_gather(in.packed, in.leaf_index, s, r.end);
    const uint32_t i = in.leaf_index[s];
    const SortedBox leaf = in.packed ? in.packed[i] : pack(boxes, i);
    out.refit.leaves[s] = leaf;
    out.refit.lanes.store(s, leaf);
    if (filter.layer) {
      out.refit.layer[s] = filter.layer[i];
      out.refit.mask[s] = filter.mask[i];
      out.refit.is_static[s] = filter.is_static[i];
    }
    if (n < 2) {
      out.topo.leaf_parent[0] = kInvalidBody;
      continue;
    }
    const uint32_t blocked = ctx.climb(s, s, bounds_of(leaf), r.begin);
    if (blocked != kBlocked) {
      IMPACT_ASSERT(out_blocked->count < kLbvhMaxDepth + 1);
      out_blocked->last[out_blocked->count++] = blocked;
    }
  }
}

void lbvh_build_fused_seam(LbvhFusedIn in, LbvhFusedOut out, uint32_t n, Range r,
                           const LbvhBlocked& blocked) {
  if (n < 2 || r.begin == 0) return;
  const Ctx ctx{in, out, n};
  // Item k: the subtree [g + 1, last[k]] with g = r.begin - 1 for the first item and
  // the previous item's last after that; its left sibling now ends complete at g.
  uint32_t g = r.begin - 1;
  for (uint32_t k = 0; k < blocked.count; ++k) {
    const uint32_t last = blocked.last[k];
    const uint32_t first = out.slot[g];
    IMPACT_ASSERT(first != kBlocked);
    const Bounds u = ctx.create(first, last, g, ctx.child(first == g, g), ctx.child(last == g + 1, g + 1));
    const uint32_t again = ctx.climb(first, last, u, 0);
    IMPACT_ASSERT(again == kBlocked);
    (void)again;
    g = last;
  }
}

}  // namespace impact::kernels
