#include "kernels/bvh/lbvh_query.h"

namespace impact::kernels {
namespace {

template <QueryShape S, bool kFiltered>
void run(const LbvhView& t, const QueryView& qv, uint32_t* out_count, HitSink& sink, Range r) {
  uint32_t stack[kLbvhMaxDepth + 1];
  for (uint32_t p = r.begin; p < r.end; ++p) {
    const uint32_t i = qv.order ? qv.order[p] : p;
    const QueryItem q = make_query_item<S>(qv, i);
    const uint64_t k0 = sink.k;
    auto leaf = [&](uint32_t u) {
      if constexpr (kFiltered) {
        if ((t.layer[u] & q.mask) == 0) return;
      }
      const SortedBox& b = t.leaves[u];
      if (query_hits<S>(q, b)) sink.push(b.index);
    };
    if (t.n == 1) {
      leaf(0);
    } else if (t.n >= 2 && query_hits<S>(q, t.nodes[0])) {
      uint32_t top = 0;
      stack[top++] = 0;
      while (top > 0) {
        const LbvhNode& m = t.nodes[stack[--top]];
        const uint32_t h = m.split & kLbvhSplitMask;
        if (m.split & kLbvhLeftLeaf) leaf(h);
        else if (query_hits<S>(q, t.nodes[h])) stack[top++] = h;
        if (m.split & kLbvhRightLeaf) leaf(h + 1);
        else if (query_hits<S>(q, t.nodes[h + 1])) stack[top++] = h + 1;
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
