#include "kernels/bvh/lbvh_traverse.h"

namespace impact::kernels {
namespace {

template <class B>
IMPACT_INLINE bool overlaps(const SortedBox& q, const B& b) {
  return records_overlap(q, b);
}

template <class B>
IMPACT_INLINE double area(const B& b) {
  const double dx = static_cast<double>(b.max_x) - static_cast<double>(b.min_x);
  const double dy = static_cast<double>(b.max_y) - static_cast<double>(b.min_y);
  const double dz = static_cast<double>(b.max_z) - static_cast<double>(b.min_z);
  return 2.0 * (dx * dy + dy * dz + dz * dx);
}

// Calls emit(lo, hi) for every pair whose query leaf is s, in the documented order.
template <bool kFiltered, class Emit>
IMPACT_INLINE void visit_leaf(const LbvhView& t, uint32_t s, Emit&& emit) {
  const SortedBox q = t.leaves[s];
  uint32_t lq = 0, mq = 0;
  uint8_t sq = 0;
  if constexpr (kFiltered) {
    lq = t.layer[s];
    mq = t.mask[s];
    sq = t.is_static[s];
  }
  auto leaf = [&](uint32_t u) {
    const SortedBox& b = t.leaves[u];
    if (!overlaps(q, b)) return;
    if constexpr (kFiltered) {
      if (!pair_allowed(lq, mq, sq, t.layer[u], t.mask[u], t.is_static[u])) return;
    }
    const uint32_t ib = b.index;
    emit(q.index < ib ? q.index : ib, q.index < ib ? ib : q.index);
  };

  // Climb from leaf s to the root. Where the path arrives from a left child, the right
  // sibling subtree holds only leaves after s: test it and, if it overlaps, explore it
  // depth first. Right-arrivals are skipped (their left siblings hold leaves before s).
  uint32_t stack[kLbvhMaxDepth + 1];
  uint32_t child = s;
  bool child_is_leaf = true;
  for (uint32_t p = t.leaf_parent[s]; p != kInvalidBody; p = t.internal_parent[p]) {
    const LbvhNode& node = t.nodes[p];
    const uint32_t g = node.split & kLbvhSplitMask;
    const bool from_left = g == child && ((node.split & kLbvhLeftLeaf) != 0) == child_is_leaf;
    child = p;
    child_is_leaf = false;
    if (!from_left) continue;
    if (node.split & kLbvhRightLeaf) {
      leaf(g + 1);
      continue;
    }
    if (!overlaps(q, t.nodes[g + 1])) continue;
    // Pre-order over the sibling subtree: leaf children at once (left, then right),
    // internal children pushed right first so the left subtree comes first.
    uint32_t top = 0;
    stack[top++] = g + 1;
    while (top > 0) {
      const LbvhNode& m = t.nodes[stack[--top]];
      const uint32_t h = m.split & kLbvhSplitMask;
      uint32_t push_left = kInvalidBody, push_right = kInvalidBody;
      if (m.split & kLbvhLeftLeaf) leaf(h);
      else if (overlaps(q, t.nodes[h])) push_left = h;
      if (m.split & kLbvhRightLeaf) leaf(h + 1);
      else if (overlaps(q, t.nodes[h + 1])) push_right = h + 1;
      // At most one pending right sibling per level below g + 1, plus two new entries:
      // within kLbvhMaxDepth + 1 (see lbvh_build.h).
      if (push_right != kInvalidBody) stack[top++] = push_right;
      if (push_left != kInvalidBody) stack[top++] = push_left;
      IMPACT_ASSERT(top <= kLbvhMaxDepth + 1);
    }
  }
}

}  // namespace

uint64_t lbvh_find_pairs(const LbvhView& t, Pair* IMPACT_RESTRICT out, uint64_t capacity, Range r) {
  uint64_t k = 0;
  auto emit = [&](uint32_t a, uint32_t b) {
    if (k < capacity) out[k] = Pair{a, b};
    ++k;
  };
  if (t.layer) {
    for (uint32_t s = r.begin; s < r.end; ++s) visit_leaf<true>(t, s, emit);
  } else {
    for (uint32_t s = r.begin; s < r.end; ++s) visit_leaf<false>(t, s, emit);
  }
  return k;
}

double lbvh_area_sum(const LbvhView& t, Range r) {
  const uint32_t internal = t.n - 1;
  double sum = 0.0;
  for (uint32_t id = r.begin; id < r.end; ++id)
    sum += id < internal ? area(t.nodes[id]) : area(t.leaves[id - internal]);
  return sum;
}

}  // namespace impact::kernels
