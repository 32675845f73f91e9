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

// Prefetches the child records of internal node m (about to be pushed): the DFS pops
// a pushed node and then tests its children, one dependent cache miss per level at
// 1M boxes; issuing it at push time overlaps it with the work in between.
IMPACT_INLINE void prefetch_children(const LbvhView& t, const LbvhNode& m) {
  const uint32_t h = m.split & kLbvhSplitMask;
  __builtin_prefetch((m.split & kLbvhLeftLeaf) ? static_cast<const void*>(&t.leaves[h]) : &t.nodes[h]);
  __builtin_prefetch((m.split & kLbvhRightLeaf) ? static_cast<const void*>(&t.leaves[h + 1]) : &t.nodes[h + 1]);
}

// Pre-order depth-first walk of the subtree of internal node `root` with query box q:
// at each internal node popped, on_leaf(u, hit) for its leaf children (left, then
// right; hit: the leaf overlaps q), then its internal children overlapping q are
// pushed right first, so the left subtree comes first. Branch-free per child (the
// overlap and leaf tests of a random box are unpredictable): on_leaf gets every
// child position u, leaf or not, with hit false for internal children, and must act
// on hit without branching on it. The walk ends early once stop() is true (checked
// before each node).
template <class B, class OnLeaf, class Stop>
IMPACT_INLINE void explore(const LbvhView& t, const B& q, uint32_t root, OnLeaf&& on_leaf, Stop&& stop) {
  // Record arrays by leaf flag (0: nodes, 1: leaves; both 32-byte records), indexed
  // rather than selected so that the choice compiles without a branch.
  const float* const base[2] = {&t.nodes[0].min_x, &t.leaves[0].min_x};
  constexpr uint32_t kStride = sizeof(LbvhNode) / sizeof(float);
  uint32_t stack[kLbvhMaxDepth + 2];
  uint32_t top = 0;
  stack[top++] = root;
  while (top > 0 && !stop()) {
    const uint32_t split = t.nodes[stack[--top]].split;
    const uint32_t h = split & kLbvhSplitMask;
    const uint32_t left_leaf = split >> 31, right_leaf = (split >> 30) & 1u;
    const bool lo = records_overlap_at(q, base[left_leaf] + static_cast<size_t>(h) * kStride);
    const bool ro = records_overlap_at(q, base[right_leaf] + static_cast<size_t>(h + 1) * kStride);
    on_leaf(h, left_leaf != 0 && lo);
    on_leaf(h + 1, right_leaf != 0 && ro);
    // At most one pending right sibling per level below the root, plus two new
    // entries: within kLbvhMaxDepth + 1 (see lbvh_build.h); the slot past them takes
    // the unconditional stores.
    stack[top] = h + 1;
    top += (right_leaf ^ 1u) & static_cast<uint32_t>(ro);
    stack[top] = h;
    top += (left_leaf ^ 1u) & static_cast<uint32_t>(lo);
    IMPACT_ASSERT(top <= kLbvhMaxDepth + 1);
    if (top > 0) prefetch_children(t, t.nodes[stack[top - 1]]);
  }
}

// The pair output of one range: the first `capacity` pairs go to out, the count goes
// on; put() stores without branching on `keep` (a dropped pair lands in a spare slot).
struct PairSink {
  Pair* out;
  uint64_t capacity;
  uint64_t k = 0;
  Pair spare{};

  IMPACT_INLINE void put(uint32_t a, uint32_t b, bool keep) {
    Pair* dst = k < capacity ? out + k : &spare;
    *dst = Pair{a < b ? a : b, a < b ? b : a};
    k += static_cast<uint64_t>(keep);
  }
};

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

// pad: the subtree's last sorted leaf.
IMPACT_INLINE Candidate candidate(const SortedBox& b, uint32_t pos) {
  return Candidate{b.min_x, b.min_y, b.min_z, pos | kCandLeaf, b.max_x, b.max_y, b.max_z, pos};
}
IMPACT_INLINE Candidate candidate(const LbvhNode& b, uint32_t node) {
  return Candidate{b.min_x, b.min_y, b.min_z, node, b.max_x, b.max_y, b.max_z, b.last};
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
    if (is_leaf) {
      item[size++] = candidate(t.leaves[ref], ref);
    } else {
      item[size++] = candidate(t.nodes[ref], ref);
      prefetch_children(t, t.nodes[ref]);
    }
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

// Emits every pair whose query leaf is s into sink, in the documented order; st holds
// the candidates of s, of which those below lo are left out (a group's shared ones).
template <bool kFiltered>
IMPACT_INLINE void visit_leaf(const LbvhView& t, uint32_t s, const CandidateStack& st, uint32_t lo,
                              PairSink& sink) {
  const SortedBox q = t.leaves[s];
  uint32_t lq = 0, mq = 0;
  uint8_t sq = 0;
  if constexpr (kFiltered) {
    lq = t.layer[s];
    mq = t.mask[s];
    sq = t.is_static[s];
  }
  auto emit_leaf = [&](uint32_t u, bool hit) {
    if constexpr (kFiltered) hit = hit && pair_allowed(lq, mq, sq, t.layer[u], t.mask[u], t.is_static[u]);
    sink.put(q.index, t.leaves[u].index, hit);
  };

  // Candidates overlapping q, from the top (the lowest ancestor) down, compacted
  // without branches.
  uint32_t hit[kLbvhMaxDepth + 1];
  uint32_t hits = 0;
  for (uint32_t k = st.size; k-- > lo;) {
    hit[hits] = k;
    hits += overlaps(q, st.item[k]) ? 1u : 0u;
  }
  for (uint32_t c = 0; c < hits; ++c) {
    const uint32_t ref = st.item[hit[c]].ref;
    if (ref & kCandLeaf) emit_leaf(ref & ~kCandLeaf, true);
    else explore(t, q, ref, emit_leaf, [] { return false; });
  }
}

// Queries per group and leaf records kept for a group's shared candidates.
constexpr uint32_t kGroupMax = 16;
constexpr uint32_t kSharedMax = 256;

// Runs the queries of r in groups. A group is a run [s, end) of queries such that the
// top stack entries of query s cover exactly the leaves (s, end): the entries below
// them ("shared") are then candidates of every query of the group, after (below) its
// own. The shared candidates are explored once, with the union box of the group's
// leaves, collecting in pre-order every leaf record overlapping that box; each query
// then handles its own entries as before and filters the collected list by its box.
// A leaf overlapping a query overlaps the union box, and a pruned subtree holds none,
// so each query emits exactly its pairs in the documented order. When the list would
// overflow kSharedMax (crowded scenes), the group's queries run one by one.
template <bool kFiltered>
IMPACT_INLINE void run_queries(const LbvhView& t, Range r, PairSink& sink) {
  CandidateStack st;
  init_stack(t, r.begin, st);
  // index: original box; pad: sorted position. Two spare slots take the stores of
  // one node's children past an overflow.
  SortedBox shared[kSharedMax + 2];
  uint32_t s = r.begin;
  while (s < r.end) {
    uint32_t end = s + 1, lo = st.size;
    for (uint32_t j = st.size; j-- > 0;) {
      const uint32_t last = st.item[j].pad;
      if (last + 1 - s > kGroupMax || last >= r.end) break;
      end = last + 1;
      lo = j;
    }
    uint32_t m = 0;
    bool grouped = end - s > 1;
    if (grouped) {
      SortedBox g = t.leaves[s];
      for (uint32_t u = s + 1; u < end; ++u) {
        const SortedBox& b = t.leaves[u];
        g.min_x = b.min_x < g.min_x ? b.min_x : g.min_x;
        g.min_y = b.min_y < g.min_y ? b.min_y : g.min_y;
        g.min_z = b.min_z < g.min_z ? b.min_z : g.min_z;
        g.max_x = b.max_x > g.max_x ? b.max_x : g.max_x;
        g.max_y = b.max_y > g.max_y ? b.max_y : g.max_y;
        g.max_z = b.max_z > g.max_z ? b.max_z : g.max_z;
      }
      // Leaves overlapping g, in pre-order; m past kSharedMax: overflow (the walk
      // stops at the next node, so at most two stores land past kSharedMax - 1).
      auto add = [&](uint32_t u, bool hit) {
        shared[m] = t.leaves[u];
        shared[m].pad = u;
        m += static_cast<uint32_t>(hit);
      };
      for (uint32_t k = lo; k-- > 0 && m <= kSharedMax;) {
        const Candidate& c = st.item[k];
        if (!overlaps(g, c)) continue;
        if (c.ref & kCandLeaf) add(c.pad, true);
        else explore(t, g, c.ref, add, [&] { return m > kSharedMax; });
      }
      grouped = m <= kSharedMax;
    }
    for (uint32_t u = s; u < end; ++u) {
      visit_leaf<kFiltered>(t, u, st, grouped ? lo : 0u, sink);
      if (grouped) {
        const SortedBox q = t.leaves[u];
        for (uint32_t i = 0; i < m; ++i) {
          bool keep = overlaps(q, shared[i]);
          if constexpr (kFiltered) {
            const uint32_t v = shared[i].pad;
            keep = keep && pair_allowed(t.layer[u], t.mask[u], t.is_static[u], t.layer[v], t.mask[v],
                                        t.is_static[v]);
          }
          sink.put(q.index, shared[i].index, keep);
        }
      }
      if (u + 1 < r.end) advance_stack(t, st);
    }
    s = end;
  }
}

}  // namespace

uint64_t lbvh_find_pairs(const LbvhView& t, Pair* IMPACT_RESTRICT out, uint64_t capacity, Range r) {
  if (r.begin >= r.end) return 0;
  PairSink sink{out, capacity};
  if (t.layer) run_queries<true>(t, r, sink);
  else run_queries<false>(t, r, sink);
  return sink.k;
}

double lbvh_area_sum(const LbvhView& t, Range r) {
  const uint32_t internal = t.n - 1;
  double sum = 0.0;
  for (uint32_t id = r.begin; id < r.end; ++id)
    sum += id < internal ? area(t.nodes[id]) : area(t.leaves[id - internal]);
  return sum;
}

}  // namespace impact::kernels
