#include "kernels/bvh/lbvh_traverse.h"

#include <bit>

#include "kernels/simd/lanes.h"

namespace impact::kernels {
namespace {

// The cluster's leaf tests are the walk's arithmetic: the widest lanes (16 with
// AVX-512).
constexpr uint32_t kW = simd::kWideWidth;
using F = simd::FloatN<kW>;
using I = simd::IntN<kW>;
constexpr uint32_t kVecs = kLbvhCluster / kW;
static_assert(kLbvhCluster % kW == 0 && kLbvhCluster <= 64 && kLbvhTarget >= kLbvhCluster);
// QueryCluster::load reads kLbvhCluster lanes from a cluster's first leaf, test_target
// kW from any leaf of a target: both inside the lane arrays' padding.
static_assert(kLbvhLanePad >= kLbvhCluster && kLbvhLanePad >= kW);
using Bits = uint64_t;  // one bit per query-cluster lane

template <class B>
IMPACT_INLINE double area(const B& b) {
  const double dx = static_cast<double>(b.max_x) - static_cast<double>(b.min_x);
  const double dy = static_cast<double>(b.max_y) - static_cast<double>(b.min_y);
  const double dz = static_cast<double>(b.max_z) - static_cast<double>(b.min_z);
  return 2.0 * (dx * dy + dy * dz + dz * dx);
}

// A subtree of at most kLbvhCluster leaves: a query cluster when maximal.
IMPACT_INLINE bool is_cluster(uint32_t first, uint32_t last) { return last - first < kLbvhCluster; }
// A subtree of at most kLbvhTarget leaves: tested leaf by leaf, not descended into.
IMPACT_INLINE bool is_target(uint32_t first, uint32_t last) { return last - first < kLbvhTarget; }

// Prefetches the child records of internal node m (about to be pushed): the walk pops
// a pushed node and then tests its children, one dependent cache miss per level at
// 1M boxes; issuing it at push time overlaps it with the work in between.
IMPACT_INLINE void prefetch_children(const LbvhView& t, const LbvhNode& m) {
  const uint32_t h = m.split & kLbvhSplitMask;
  __builtin_prefetch((m.split & kLbvhLeftLeaf) ? static_cast<const void*>(&t.leaves[h]) : &t.nodes[h]);
  __builtin_prefetch((m.split & kLbvhRightLeaf) ? static_cast<const void*>(&t.leaves[h + 1]) : &t.nodes[h + 1]);
}

// A subtree: its bounds (at the LbvhNode / SortedBox offsets, so records_overlap
// applies), ref (internal node index, or kCandLeaf | leaf position), its leaf range
// [first, last]. 32 bytes as a record, first kept beside it.
struct alignas(32) Rec {
  float min_x, min_y, min_z;
  uint32_t ref;
  float max_x, max_y, max_z;
  uint32_t last;
};
static_assert(sizeof(Rec) == 32);
constexpr uint32_t kCandLeaf = 1u << 31;

struct Sub {
  Rec rec;
  uint32_t first;
};

IMPACT_INLINE Sub sub_of(const LbvhView& t, uint32_t pos, bool leaf, uint32_t first, uint32_t last) {
  if (leaf) {
    const SortedBox& b = t.leaves[pos];
    return Sub{Rec{b.min_x, b.min_y, b.min_z, pos | kCandLeaf, b.max_x, b.max_y, b.max_z, last}, first};
  }
  const LbvhNode& b = t.nodes[pos];
  return Sub{Rec{b.min_x, b.min_y, b.min_z, pos, b.max_x, b.max_y, b.max_z, last}, first};
}
IMPACT_INLINE bool is_cluster(const Sub& s) { return is_cluster(s.first, s.rec.last); }

// The pair output of one range: the first `capacity` pairs go to out, the count goes
// on.
struct PairSink {
  Pair* out;
  uint64_t capacity;
  uint64_t k = 0;

  IMPACT_INLINE void put(uint32_t a, uint32_t b) {
    if (k < capacity) out[k] = Pair{a < b ? a : b, a < b ? b : a};
    ++k;
  }
};

// The leaves of one query cluster, one per lane, straight from the lane arrays (lanes
// past its size hold the next leaves: `valid` masks their bits), with its bounds
// (also broadcast) and range.
struct QueryCluster {
  F min_x[kVecs], min_y[kVecs], min_z[kVecs], max_x[kVecs], max_y[kVecs], max_z[kVecs];
  Rec bounds;
  F b_min_x, b_min_y, b_min_z, b_max_x, b_max_y, b_max_z;
  uint32_t first;
  Bits valid;  // bit i: lane i holds a leaf of the cluster

  IMPACT_INLINE void load(const LbvhView& t, const Sub& c) {
    bounds = c.rec;
    b_min_x = F(c.rec.min_x);
    b_min_y = F(c.rec.min_y);
    b_min_z = F(c.rec.min_z);
    b_max_x = F(c.rec.max_x);
    b_max_y = F(c.rec.max_y);
    b_max_z = F(c.rec.max_z);
    first = c.first;
    valid = ~Bits{0} >> (63 - (c.rec.last - c.first));
    const float* L = t.lanes + c.first;
    const size_t S = t.lane_stride;
    for (uint32_t v = 0; v < kVecs; ++v) {
      min_x[v] = F::load(L + v * kW);
      min_y[v] = F::load(L + S + v * kW);
      min_z[v] = F::load(L + 2 * S + v * kW);
      max_x[v] = F::load(L + 3 * S + v * kW);
      max_y[v] = F::load(L + 4 * S + v * kW);
      max_z[v] = F::load(L + 5 * S + v * kW);
    }
  }

  // Bit i set: query leaf i overlaps leaf u (touching counts), read from the lane
  // arrays (a leaf tested here has just been read there).
  // Only the first `vecs` vectors (the later lanes' bits stay clear).
  IMPACT_INLINE Bits hits(const LbvhView& t, uint32_t u, uint32_t vecs = kVecs) const {
    const float* L = t.lanes + u;
    const size_t S = t.lane_stride;
    const F bx0(L[0]), by0(L[S]), bz0(L[2 * S]), bx1(L[3 * S]), by1(L[4 * S]), bz1(L[5 * S]);
    Bits m = 0;
    for (uint32_t v = 0; v < vecs; ++v) {
      const auto o = (min_x[v] <= bx1) & (bx0 <= max_x[v]) & (min_y[v] <= by1) & (by0 <= max_y[v]) &
                     (min_z[v] <= bz1) & (bz0 <= max_z[v]);
      m |= static_cast<Bits>(simd::bits(o)) << (v * kW);
    }
    return m;
  }
};

// Emits the pairs of leaf u with the query leaves of the bits of m (not zero: the
// callers list only the leaves that hit, Pending below), ascending.
template <bool kFiltered>
IMPACT_INLINE void emit(const LbvhView& t, const QueryCluster& q, uint32_t u, Bits m, PairSink& sink) {
  // A hit reads the 4-byte id (t.ids), not the leaf's 32-byte record, which the lane
  // tests did not bring into cache.
  IMPACT_ASSERT(m != 0);
  const uint32_t b = t.ids[u];
  while (m != 0) {
    const uint32_t i = static_cast<uint32_t>(std::countr_zero(m));
    m &= m - 1;
    if constexpr (kFiltered) {
      const uint32_t s = q.first + i;
      if (!pair_allowed(t.layer[s], t.mask[s], t.is_static[s], t.layer[u], t.mask[u], t.is_static[u]))
        continue;
    }
    sink.put(t.ids[q.first + i], b);
  }
}

// A tested leaf u with hits m (not zero), listed until its loop is done: the loop stores
// every leaf's entry and advances past a hit only, so whether a leaf hit is no branch
// (about half of the tested leaves do, unpredictably), and the pairs are emitted after
// the tests, in the same order.
struct Pending {
  uint32_t u;
  Bits m;
};

// Every leaf of the target subtree [first, last] (at most kLbvhTarget leaves) against
// the query cluster, in leaf order.
template <bool kFiltered>
IMPACT_INLINE void test_target(const LbvhView& t, const QueryCluster& q, uint32_t first, uint32_t last,
                               PairSink& sink) {
  // kW consecutive leaves at a time against the query cluster's bounds (from the
  // lane arrays; lanes past `last` masked off), then the survivors against the
  // query leaves.
  const size_t S = t.lane_stride;
  const uint32_t size = last - first + 1;
  // The survivors of all vectors first, compacted (simd::compact_store: one
  // unpredictable loop exit per target instead of one per vector), then their tests.
  int32_t surv[kLbvhTarget + kW];
  uint32_t ns = 0;
  const I lanes = simd::lane_ids<I>(static_cast<int32_t>(first));
  for (uint32_t o = 0; o < size; o += kW) {
    const float* L = t.lanes + first + o;
    const auto ov = (F::load(L) <= q.b_max_x) & (q.b_min_x <= F::load(L + 3 * S)) &
                    (F::load(L + S) <= q.b_max_y) & (q.b_min_y <= F::load(L + 4 * S)) &
                    (F::load(L + 2 * S) <= q.b_max_z) & (q.b_min_z <= F::load(L + 5 * S));
    uint32_t m = simd::bits(ov);
    if (size - o < kW) m &= (1u << (size - o)) - 1u;
    ns += simd::compact_store(surv + ns, lanes + I(static_cast<int32_t>(o)), m);
  }
  Pending pend[kLbvhTarget];
  uint32_t np = 0;
  for (uint32_t i = 0; i < ns; ++i) {
    const auto u = static_cast<uint32_t>(surv[i]);
    pend[np] = Pending{u, q.hits(t, u) & q.valid};
    np += pend[np].m != 0 ? 1u : 0u;
  }
  for (uint32_t i = 0; i < np; ++i) emit<kFiltered>(t, q, pend[i].u, pend[i].m, sink);
}

// Depth-first walk of internal node `node` (leaves [first, ..], more than
// kLbvhTarget) with the query cluster's bounds, left child first, down to targets
// (subtrees of at most kLbvhTarget leaves), tested in increasing leaf order.
template <bool kFiltered>
IMPACT_INLINE void explore(const LbvhView& t, const QueryCluster& q, uint32_t node, uint32_t first,
                           PairSink& sink) {
  // Record arrays by leaf flag (0: nodes, 1: leaves; both 32-byte records), indexed
  // rather than selected so that the choice compiles without a branch.
  const float* const base[2] = {&t.nodes[0].min_x, &t.leaves[0].min_x};
  constexpr uint32_t kStride = sizeof(LbvhNode) / sizeof(float);
  constexpr uint32_t kTargetItem = 1u << 31;
  struct Item {
    uint32_t ref;  ///< internal node, or kTargetItem for a target
    uint32_t first, last;
  };
  // One pending right sibling per level below the root plus two new entries:
  // within kLbvhMaxDepth + 1 (lbvh_build.h); the slot past them takes the
  // unconditional stores.
  Item stack[kLbvhMaxDepth + 2];
  uint32_t top = 0;
  stack[top++] = Item{node, first, 0};
  while (top > 0) {
    const Item cur = stack[--top];
    if (cur.ref & kTargetItem) {
      test_target<kFiltered>(t, q, cur.first, cur.last, sink);
      continue;
    }
    const LbvhNode& m = t.nodes[cur.ref];
    const uint32_t h = m.split & kLbvhSplitMask;
    const uint32_t left_leaf = m.split >> 31, right_leaf = (m.split >> 30) & 1u;
    const bool lo = records_overlap_at(q.bounds, base[left_leaf] + static_cast<size_t>(h) * kStride);
    const bool ro = records_overlap_at(q.bounds, base[right_leaf] + static_cast<size_t>(h + 1) * kStride);
    const bool lc = is_target(cur.first, h), rc = is_target(h + 1, m.last);
    // A target child is tested at once unless an internal left sibling's leaves
    // must come first; then it waits on the stack as a target item.
    const bool left_waits = lo && !lc;
    if (lo && lc) test_target<kFiltered>(t, q, cur.first, h, sink);
    if (ro && rc && !left_waits) test_target<kFiltered>(t, q, h + 1, m.last, sink);
    stack[top] = Item{(h + 1) | (rc ? kTargetItem : 0u), h + 1, m.last};
    top += static_cast<uint32_t>(ro && (!rc || left_waits));
    stack[top] = Item{h, cur.first, h};
    top += static_cast<uint32_t>(left_waits);
    IMPACT_ASSERT(top <= kLbvhMaxDepth + 1);
    // The children of every internal child pushed, at once (not only the stack's top,
    // popped next: a right sibling popped later would have its children's records
    // fetched only then).
    if (ro && !rc) prefetch_children(t, t.nodes[h + 1]);
    if (left_waits) prefetch_children(t, t.nodes[h]);
  }
}

// The subtrees after the current query cluster: the right children of its ancestors
// reached from their left child, root side at the bottom, so the top is the subtree
// that starts right after the cluster. A right child's first leaf is its own index
// (internal node or leaf position: lbvh_build.h).
struct CandidateStack {
  const LbvhView& t;
  Rec item[kLbvhMaxDepth + 1];
  uint32_t size = 0;

  explicit CandidateStack(const LbvhView& tree) : t(tree) {}

  IMPACT_INLINE void push(const Rec& s) {
    IMPACT_ASSERT(size < kLbvhMaxDepth + 1);
    item[size++] = s;
    if ((s.ref & kCandLeaf) == 0) prefetch_children(t, t.nodes[s.ref]);
  }
  // From subtree s (internal, more than kLbvhCluster leaves) down its left spine to
  // its first cluster, pushing each right child passed; returns that cluster.
  IMPACT_INLINE Sub descend_left(Sub s) {
    for (;;) {
      const LbvhNode& m = t.nodes[s.rec.ref];
      const uint32_t h = m.split & kLbvhSplitMask;
      push(sub_of(t, h + 1, (m.split & kLbvhRightLeaf) != 0, h + 1, m.last).rec);
      s = sub_of(t, h, (m.split & kLbvhLeftLeaf) != 0, s.first, h);
      if (is_cluster(s)) return s;
    }
  }
  // The cluster after the current one (the stack is not empty).
  IMPACT_INLINE Sub next() {
    IMPACT_ASSERT(size > 0);
    const Rec& top = item[--size];
    const Sub s{top, top.ref & ~kCandLeaf};
    return is_cluster(s) ? s : descend_left(s);
  }
};

// The first cluster that starts at or after position `begin`, with the stack of the
// subtrees after it; false when none does.
IMPACT_INLINE bool first_cluster(const LbvhView& t, uint32_t begin, CandidateStack& st, Sub& out) {
  Sub s = sub_of(t, 0, false, 0, t.n - 1);
  while (!is_cluster(s)) {
    const LbvhNode& m = t.nodes[s.rec.ref];
    const uint32_t h = m.split & kLbvhSplitMask;
    const Sub right = sub_of(t, h + 1, (m.split & kLbvhRightLeaf) != 0, h + 1, s.rec.last);
    if (begin <= h) {
      st.push(right.rec);
      s = sub_of(t, h, (m.split & kLbvhLeftLeaf) != 0, s.first, h);
    } else {
      s = right;
    }
  }
  if (s.first >= begin) {
    out = s;
    return true;
  }
  // The cluster holding `begin` starts before it: it belongs to the range before.
  if (st.size == 0) return false;
  out = st.next();
  return true;
}

template <bool kFiltered>
IMPACT_INLINE void run_queries(const LbvhView& t, Range r, PairSink& sink) {
  CandidateStack st(t);
  Sub c;
  if (!first_cluster(t, r.begin, st, c)) return;
  QueryCluster q;
  while (c.first < r.end) {
    q.load(t, c);
    // Within the cluster: each leaf u with the query leaves before it.
    // Leaf first + k needs the lanes below k only: ceil(k / kW) vectors.
    Pending pend[kLbvhCluster];
    uint32_t np = 0;
    for (uint32_t u = c.first + 1; u <= c.rec.last; ++u) {
      const uint32_t k = u - c.first;
      pend[np] = Pending{u, q.hits(t, u, (k + kW - 1) / kW) & ((Bits{1} << k) - 1u)};
      np += pend[np].m != 0 ? 1u : 0u;
    }
    for (uint32_t i = 0; i < np; ++i) emit<kFiltered>(t, q, pend[i].u, pend[i].m, sink);
    // The subtrees after it overlapping its bounds, from the top (the lowest
    // ancestor) down, compacted without branches.
    uint32_t hit[kLbvhMaxDepth + 1];
    uint32_t hits = 0;
    for (uint32_t k = st.size; k-- > 0;) {
      hit[hits] = k;
      hits += records_overlap(c.rec, st.item[k]) ? 1u : 0u;
    }
    for (uint32_t i = 0; i < hits; ++i) {
      const Rec& s = st.item[hit[i]];
      const uint32_t first = s.ref & ~kCandLeaf;
      if (is_target(first, s.last)) test_target<kFiltered>(t, q, first, s.last, sink);
      else explore<kFiltered>(t, q, s.ref, first, sink);
    }
    if (st.size == 0) return;
    c = st.next();
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
