#include "kernels/bvh/lbvh_query.h"

namespace impact::kernels {
namespace {

template <QueryShape S, bool kFiltered>
void run(const LbvhView& t, const QueryView& qv, uint32_t* out_count, HitSink& sink, Range r) {
  struct Item {
    uint32_t node, first;
  };
  Item stack[kLbvhMaxDepth + 1];
  for (uint32_t p = r.begin; p < r.end; ++p) {
    const uint32_t i = qv.order ? qv.order[p] : p;
    const QueryItem q = make_query_item<S>(qv, i);
    const uint64_t k0 = sink.k;
    auto leaves = [&](uint32_t first, uint32_t last) {
      for (uint32_t u = first; u <= last; ++u) {
        if constexpr (kFiltered) {
          if ((t.layer[u] & q.mask) == 0) continue;
        }
        const SortedBox& b = t.leaves[u];
        if (query_hits<S>(q, b)) sink.push(b.index);
      }
    };
    if (t.n >= 1 && t.n <= kLbvhQueryRun) {
      leaves(0, t.n - 1);
    } else if (t.n > kLbvhQueryRun && query_hits<S>(q, t.nodes[0])) {
      uint32_t top = 0;
      stack[top++] = Item{0, 0};
      while (top > 0) {
        const Item cur = stack[--top];
        const LbvhNode& m = t.nodes[cur.node];
        const uint32_t h = m.split & kLbvhSplitMask;
        // A child of at most kLbvhQueryRun leaves is scanned (contiguous records)
        // once its bounds pass; a bigger one is pushed.
        if (h - cur.first < kLbvhQueryRun) {
          if ((m.split & kLbvhLeftLeaf) != 0 || query_hits<S>(q, t.nodes[h])) leaves(cur.first, h);
        } else if (query_hits<S>(q, t.nodes[h])) {
          stack[top++] = Item{h, cur.first};
        }
        if (m.last - h <= kLbvhQueryRun) {
          if ((m.split & kLbvhRightLeaf) != 0 || query_hits<S>(q, t.nodes[h + 1])) leaves(h + 1, m.last);
        } else if (query_hits<S>(q, t.nodes[h + 1])) {
          stack[top++] = Item{h + 1, h + 1};
        }
        // Each level below the root leaves at most one pending sibling, plus the two
        // just pushed: within kLbvhMaxDepth + 1 (lbvh_build.h).
        IMPACT_ASSERT(top <= kLbvhMaxDepth + 1);
      }
    }
    out_count[i] = finish_query(sink, k0);
  }
}

}  // namespace

uint64_t lbvh_query(const LbvhView& t, const QueryView& q, uint32_t* IMPACT_RESTRICT out_count,
                    uint32_t* IMPACT_RESTRICT out_hits, uint64_t capacity, Range r) {
  HitSink sink{out_hits, capacity, 0};
  dispatch_query(q.shape, t.layer != nullptr, [&]<QueryShape S, bool kF>() {
    run<S, kF>(t, q, out_count, sink, r);
  });
  return sink.k;
}

}  // namespace impact::kernels
