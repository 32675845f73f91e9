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

// A right-sibling subtree still to be tested by the current and later queries: its
// bounds (at the LbvhNode / SortedBox offsets, so records_overlap applies) and its
// reference (node index, or leaf position | kCandLeaf).
struct alignas(32) Candidate {
  float min_x, min_y, min_z;
  uint32_t ref;
  float max_x, max_y, max_z;
  uint32_t pad;
};
static_assert(sizeof(Candidate) == 32);
constexpr uint32_t kCandLeaf = 1u << 31;

template <class B>
IMPACT_INLINE Candidate candidate(const B& b, uint32_t ref) {
  return Candidate{b.min_x, b.min_y, b.min_z, ref, b.max_x, b.max_y, b.max_z, 0u};
}

// The candidate stack of one chunk of consecutive query leaves. For query s it holds,
// bottom to top, the right children of the ancestors of s whose left child holds s
// (root side first): exactly the subtrees made only of leaves after s that the old
// leaf-to-root climb met, so the top is the right child of the lowest such ancestor
// (the node whose split is s), whose first leaf is s + 1.
struct CandidateStack {
  Candidate item[kLbvhMaxDepth + 1];
  uint32_t size = 0;

  IMPACT_INLINE void push_child(const LbvhView& t, uint32_t ref, bool is_leaf) {
    IMPACT_ASSERT(size < kLbvhMaxDepth + 1);
    item[size++] = is_leaf ? candidate(t.leaves[ref], ref | kCandLeaf) : candidate(t.nodes[ref], ref);
  }
  // Walks down from internal node `node` along left children to its first leaf,
  // pushing each right child passed.
  IMPACT_INLINE void descend_left(const LbvhView& t, uint32_t node) {
    for (;;) {
      const LbvhNode& m = t.nodes[node];
      const uint32_t h = m.split & kLbvhSplitMask;
      push_child(t, h + 1, (m.split & kLbvhRightLeaf) != 0);
      if (m.split & kLbvhLeftLeaf) return;
      node = h;
    }
  }
};

// Builds the stack of query s from the root: one root-to-leaf walk per chunk.
IMPACT_INLINE void init_stack(const LbvhView& t, uint32_t s, CandidateStack& st) {
  st.size = 0;
  uint32_t node = 0;
  for (;;) {
    const LbvhNode& m = t.nodes[node];
    const uint32_t h = m.split & kLbvhSplitMask;
    if (s <= h) {
      st.push_child(t, h + 1, (m.split & kLbvhRightLeaf) != 0);
      if (m.split & kLbvhLeftLeaf) return;
      node = h;
    } else {
      if (m.split & kLbvhRightLeaf) return;
      node = h + 1;
    }
  }
}

// Query s -> s + 1: the top candidate is the subtree whose first leaf is s + 1; it is
// replaced by the right children along its left spine.
IMPACT_INLINE void advance_stack(const LbvhView& t, CandidateStack& st) {
  IMPACT_ASSERT(st.size > 0);
  const uint32_t ref = st.item[--st.size].ref;
  if ((ref & kCandLeaf) == 0) st.descend_left(t, ref);
}

// Calls emit(lo, hi) for every pair whose query leaf is s, in the documented order;
// st holds the candidates of s.
template <bool kFiltered, class Emit>
IMPACT_INLINE void visit_leaf(const LbvhView& t, uint32_t s, const CandidateStack& st, Emit&& emit) {
  const SortedBox q = t.leaves[s];
  uint32_t lq = 0, mq = 0;
  uint8_t sq = 0;
  if constexpr (kFiltered) {
    lq = t.layer[s];
    mq = t.mask[s];
    sq = t.is_static[s];
  }
  auto emit_leaf = [&](uint32_t u) {
    if constexpr (kFiltered) {
      if (!pair_allowed(lq, mq, sq, t.layer[u], t.mask[u], t.is_static[u])) return;
    }
    const uint32_t ib = t.leaves[u].index;
    emit(q.index < ib ? q.index : ib, q.index < ib ? ib : q.index);
  };
  auto leaf = [&](uint32_t u) {
    if (overlaps(q, t.leaves[u])) emit_leaf(u);
  };

  // Candidates overlapping q, from the top (the lowest ancestor) down, compacted
  // without branches.
  uint32_t hit[kLbvhMaxDepth + 1];
  uint32_t hits = 0;
  for (uint32_t k = st.size; k-- > 0;) {
    hit[hits] = k;
    hits += overlaps(q, st.item[k]) ? 1u : 0u;
  }
  uint32_t stack[kLbvhMaxDepth + 1];
  for (uint32_t c = 0; c < hits; ++c) {
    const uint32_t ref = st.item[hit[c]].ref;
    if (ref & kCandLeaf) {
      emit_leaf(ref & ~kCandLeaf);
      continue;
    }
    // Pre-order over the sibling subtree: leaf children at once (left, then right),
    // internal children pushed right first so the left subtree comes first.
    uint32_t top = 0;
    stack[top++] = ref;
    while (top > 0) {
      const LbvhNode& m = t.nodes[stack[--top]];
      const uint32_t h = m.split & kLbvhSplitMask;
      uint32_t push_left = kInvalidBody, push_right = kInvalidBody;
      if (m.split & kLbvhLeftLeaf) leaf(h);
      else if (overlaps(q, t.nodes[h])) push_left = h;
      if (m.split & kLbvhRightLeaf) leaf(h + 1);
      else if (overlaps(q, t.nodes[h + 1])) push_right = h + 1;
      // At most one pending right sibling per level below the candidate, plus two new
      // entries: within kLbvhMaxDepth + 1 (see lbvh_build.h).
      if (push_right != kInvalidBody) stack[top++] = push_right;
      if (push_left != kInvalidBody) stack[top++] = push_left;
      IMPACT_ASSERT(top <= kLbvhMaxDepth + 1);
    }
  }
}

}  // namespace

uint64_t lbvh_find_pairs(const LbvhView& t, Pair* IMPACT_RESTRICT out, uint64_t capacity, Range r) {
  uint64_t k = 0;
  if (r.begin >= r.end) return 0;
  auto emit = [&](uint32_t a, uint32_t b) {
    if (k < capacity) out[k] = Pair{a, b};
    ++k;
  };
  CandidateStack st;
  init_stack(t, r.begin, st);
  if (t.layer) {
    for (uint32_t s = r.begin; s < r.end; ++s) {
      visit_leaf<true>(t, s, st, emit);
      if (s + 1 < r.end) advance_stack(t, st);
    }
  } else {
    for (uint32_t s = r.begin; s < r.end; ++s) {
      visit_leaf<false>(t, s, st, emit);
      if (s + 1 < r.end) advance_stack(t, st);
    }
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
