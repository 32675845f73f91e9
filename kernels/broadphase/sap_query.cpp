#include "kernels/broadphase/sap_query.h"

#include <algorithm>
#include <cmath>

namespace impact::kernels {
namespace {

template <QueryShape S, bool kFiltered>
void run(const SapView& v, uint32_t axis, double max_extent, const QueryView& qv, uint32_t* out_count,
         HitSink& sink, Range r) {
  const float* IMPACT_RESTRICT min0 = v.min[0];
  const float* IMPACT_RESTRICT max0 = v.max[0];
  const float* IMPACT_RESTRICT min1 = v.min[1];
  const float* IMPACT_RESTRICT max1 = v.max[1];
  const float* IMPACT_RESTRICT min2 = v.min[2];
  const float* IMPACT_RESTRICT max2 = v.max[2];
  const uint32_t* IMPACT_RESTRICT layer = v.layer;
  // Original axis k is stored in array slot[k]; arrays 1 and 2 hold axis + 1, axis + 2.
  const uint32_t a1 = axis == 2 ? 0 : axis + 1;
  const uint32_t a2 = a1 == 2 ? 0 : a1 + 1;
  uint32_t slot[3];
  slot[axis] = 0, slot[a1] = 1, slot[a2] = 2;
  for (uint32_t p = r.begin; p < r.end; ++p) {
    const uint32_t i = qv.order ? qv.order[p] : p;
    const QueryItem q = make_query_item<S>(qv, i);
    const float lo[3] = {q.min_x, q.min_y, q.min_z};
    const float hi[3] = {q.max_x, q.max_y, q.max_z};
    const float lo0 = lo[axis], hi0 = hi[axis], lo1 = lo[a1], hi1 = hi[a1], lo2 = lo[a2], hi2 = hi[a2];
    const uint32_t mask = q.mask;
    const uint64_t k0 = sink.k;
    // Slab [lo0 - E, hi0]: the margin covers the rounding of lo0 - E and of E itself.
    const double e = max_extent + (std::fabs(static_cast<double>(lo0)) + max_extent) * 0x1p-50;
    const float start = float_down(static_cast<double>(lo0) - e);
    const uint32_t first = static_cast<uint32_t>(std::lower_bound(min0, min0 + v.n, start) - min0);
    const uint32_t last = static_cast<uint32_t>(std::upper_bound(min0 + first, min0 + v.n, hi0) - min0);
    // Blocks of kSapPad slots; lanes at or past `last` fail min0 <= hi0 (sorted), and
    // the sentinels after slot n fail every test, so no tail loop is needed.
    for (uint32_t t = first; t < last; t += kSapPad) {
      // Block-relative pointers: with a uint32 index t + j (which may wrap, as far as
      // the compiler knows) the loads become scalar gathers; with a pointer plus j
      // they are contiguous vector loads.
      const float* IMPACT_RESTRICT b_min0 = min0 + t;
      const float* IMPACT_RESTRICT b_max0 = max0 + t;
      const float* IMPACT_RESTRICT b_min1 = min1 + t;
      const float* IMPACT_RESTRICT b_max1 = max1 + t;
      const float* IMPACT_RESTRICT b_min2 = min2 + t;
      const float* IMPACT_RESTRICT b_max2 = max2 + t;
      const uint32_t* IMPACT_RESTRICT b_layer = kFiltered ? layer + t : nullptr;
      uint32_t hit[kSapPad];
      for (uint32_t j = 0; j < kSapPad; ++j) {
        uint32_t h = static_cast<uint32_t>((b_min0[j] <= hi0) & (lo0 <= b_max0[j]) & (b_min1[j] <= hi1) &
                                           (lo1 <= b_max1[j]) & (b_min2[j] <= hi2) & (lo2 <= b_max2[j]));
        if constexpr (kFiltered) h &= static_cast<uint32_t>((b_layer[j] & mask) != 0);
        hit[j] = h;
      }
      uint32_t any = 0;
      for (uint32_t j = 0; j < kSapPad; ++j) any |= hit[j];
      if (any == 0) continue;
      for (uint32_t j = 0; j < kSapPad; ++j) {
        if (!hit[j]) continue;
        const uint32_t u = t + j;
        if constexpr (S == QueryShape::kSphere) {
          const struct {
            float min_x, min_y, min_z, max_x, max_y, max_z;
          } box{v.min[slot[0]][u], v.min[slot[1]][u], v.min[slot[2]][u],
                v.max[slot[0]][u], v.max[slot[1]][u], v.max[slot[2]][u]};
          if (!(sphere_box_dist2(q.cx, q.cy, q.cz, box) <= q.r2)) continue;
        }
        sink.push(v.index[u]);
      }
    }
    out_count[i] = finish_query(sink, k0);
  }
}

}  // namespace

double sap_max_extent(const SapView& v, Range r) {
  // Pointers to the range and a size_t count: contiguous vector loads (a uint32 slot
  // index here compiled to scalar gathers).
  const float* IMPACT_RESTRICT min0 = v.min[0] + r.begin;
  const float* IMPACT_RESTRICT max0 = v.max[0] + r.begin;
  const size_t count = r.end > r.begin ? r.end - r.begin : 0;
  double e = 0.0;
#pragma omp simd reduction(max : e)
  for (size_t s = 0; s < count; ++s) e = std::max(e, static_cast<double>(max0[s]) - static_cast<double>(min0[s]));
  return e;
}

uint64_t sap_query(const SapView& v, uint32_t axis, double max_extent, const QueryView& q,
                   uint32_t* IMPACT_RESTRICT out_count, uint32_t* IMPACT_RESTRICT out_hits, uint64_t capacity,
                   Range r) {
  HitSink sink{out_hits, capacity, 0};
  dispatch_query(q.shape, v.layer != nullptr, [&]<QueryShape S, bool kF>() {
    run<S, kF>(v, axis, max_extent, q, out_count, sink, r);
  });
  return sink.k;
}

}  // namespace impact::kernels
