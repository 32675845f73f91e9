#include "kernels/broadphase/query.h"

#include <algorithm>

namespace impact::kernels {

uint32_t finish_query(HitSink& sink, uint64_t k0) {
  const uint64_t count = sink.k - k0;
  if (sink.k <= sink.capacity && count > 1) {
    uint32_t* first = sink.out + k0;
    uint32_t* last = sink.out + sink.k;
    // Box indices are distinct within a query, so the ascending order is unique:
    // no tie for an unstable sort to break differently.
    if (count <= 16) {
      for (uint32_t* p = first + 1; p < last; ++p) {
        const uint32_t v = *p;
        uint32_t* q = p;
        for (; q > first && q[-1] > v; --q) *q = q[-1];
        *q = v;
      }
    } else if (!std::is_sorted(first, last)) {
      std::sort(first, last);
    }
  }
  return static_cast<uint32_t>(count);
}

namespace {

constexpr uint32_t kBlock = 16;

template <QueryShape S, bool kFiltered>
uint64_t brute_force(AabbSoA b, const uint32_t* layer, uint32_t n, const QueryView& qv, uint32_t* out_count,
                     HitSink& sink, Range r) {
  const float* IMPACT_RESTRICT min_x = b.min_x;
  const float* IMPACT_RESTRICT min_y = b.min_y;
  const float* IMPACT_RESTRICT min_z = b.min_z;
  const float* IMPACT_RESTRICT max_x = b.max_x;
  const float* IMPACT_RESTRICT max_y = b.max_y;
  const float* IMPACT_RESTRICT max_z = b.max_z;
  const uint32_t blocks_end = n - n % kBlock;
  for (uint32_t p = r.begin; p < r.end; ++p) {
    const uint32_t i = qv.order ? qv.order[p] : p;
    const QueryItem q = make_query_item<S>(qv, i);
    const float q0x = q.min_x, q0y = q.min_y, q0z = q.min_z, q1x = q.max_x, q1y = q.max_y, q1z = q.max_z;
    const uint32_t mask = q.mask;
    const uint64_t k0 = sink.k;
    auto lane = [&](uint32_t u) -> uint32_t {
      // Bitwise &: branch-free, so the block loop vectorises.
      uint32_t h = static_cast<uint32_t>((min_x[u] <= q1x) & (q0x <= max_x[u]) & (min_y[u] <= q1y) &
                                         (q0y <= max_y[u]) & (min_z[u] <= q1z) & (q0z <= max_z[u]));
      if constexpr (kFiltered) h &= static_cast<uint32_t>((layer[u] & mask) != 0);
      return h;
    };
    auto emit = [&](uint32_t u) {
      if constexpr (S == QueryShape::kSphere) {
        const struct {
          float min_x, min_y, min_z, max_x, max_y, max_z;
        } box{min_x[u], min_y[u], min_z[u], max_x[u], max_y[u], max_z[u]};
        if (!(sphere_box_dist2(q.cx, q.cy, q.cz, box) <= q.r2)) return;
      }
      sink.push(u);
    };
    for (uint32_t t = 0; t < blocks_end; t += kBlock) {
      uint32_t hit[kBlock];
      for (uint32_t j = 0; j < kBlock; ++j) hit[j] = lane(t + j);
      uint32_t any = 0;
      for (uint32_t j = 0; j < kBlock; ++j) any |= hit[j];
      if (any == 0) continue;
      for (uint32_t j = 0; j < kBlock; ++j)
        if (hit[j]) emit(t + j);
    }
    for (uint32_t u = blocks_end; u < n; ++u)
      if (lane(u)) emit(u);
    out_count[i] = finish_query(sink, k0);  // index order: already sorted
  }
  return sink.k;
}

}  // namespace

uint64_t brute_force_query(AabbSoA boxes, const uint32_t* layer, uint32_t n, const QueryView& q,
                           uint32_t* IMPACT_RESTRICT out_count, uint32_t* IMPACT_RESTRICT out_hits,
                           uint64_t capacity, Range r) {
  HitSink sink{out_hits, capacity, 0};
  dispatch_query(q.shape, layer != nullptr, [&]<QueryShape S, bool kF>() {
    brute_force<S, kF>(boxes, layer, n, q, out_count, sink, r);
  });
  return sink.k;
}

}  // namespace impact::kernels
