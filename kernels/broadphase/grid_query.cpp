#include "kernels/broadphase/grid_query.h"

#include <algorithm>
#include <cmath>

#include "kernels/broadphase/grid_cells.h"

namespace impact::kernels {
namespace {

using namespace grid_cells;  // NOLINT: the grid's cell arithmetic, shared with grid.cpp

// Cells [lo, hi] on one axis that can hold the min corner of a box overlapping
// [q_min, q_max] (see grid_query.h). Both ends are clamped to the grid, never
// rejected: boxes outside the grid's range sit in its boundary cells (axis_cell), so
// a query beyond the range still visits them. Clamped in double before the integer
// conversion, so far-away queries cannot overflow it. Always true.
IMPACT_INLINE bool axis_range(const GridParams& g, int axis, float q_min, float q_max, int64_t* lo,
                              int64_t* hi) {
  const double o = g.origin[axis], inv = g.inv_cell, top = static_cast<double>(g.dims[axis]) - 1.0;
  const double a = std::floor((static_cast<double>(q_min) - o) * inv) - 1.0;
  const double b = std::floor((static_cast<double>(q_max) - o) * inv);
  *lo = static_cast<int64_t>(std::clamp(a, 0.0, top));
  *hi = static_cast<int64_t>(std::clamp(b, 0.0, top));
  return true;
}

template <QueryShape S, bool kFiltered>
IMPACT_INLINE void test_slot(const GridView& g, const QueryItem& q, uint32_t t, HitSink& sink) {
  const SortedBox& b = g.box[t];
  if constexpr (kFiltered) {
    if ((g.layer[t] & q.mask) == 0) return;
  }
  if (query_hits<S>(q, b)) sink.push(b.index);
}

// One query against one grid.
template <QueryShape S, bool kFiltered, bool kDense>
void query_grid(const GridView& g, const QueryItem& q, HitSink& sink) {
  const uint32_t n = g.bucket_start[g.params.bucket_count];
  int64_t x0, x1, y0, y1, z0, z1;
  if (!axis_range(g.params, 0, q.min_x, q.max_x, &x0, &x1) || !axis_range(g.params, 1, q.min_y, q.max_y, &y0, &y1) ||
      !axis_range(g.params, 2, q.min_z, q.max_z, &z0, &z1))
    return;
  const double rows = static_cast<double>(y1 - y0 + 1) * static_cast<double>(z1 - z0 + 1);
  const double xs = static_cast<double>(x1 - x0 + 1);
  const double buckets = static_cast<double>(g.params.bucket_count);
  double cost = rows * kGridQueryRowCost;
  if constexpr (!kDense) cost += rows * xs * static_cast<double>(n) / buckets;
  if ((!kDense && xs >= buckets) || cost >= static_cast<double>(n)) {
    for (uint32_t t = 0; t < n; ++t) test_slot<S, kFiltered>(g, q, t, sink);
    return;
  }
  const uint32_t mask = bucket_mask(g.params);
  for (int64_t z = z0; z <= z1; ++z) {
    for (int64_t y = y0; y <= y1; ++y) {
      const uint64_t base = row_base(g.params, static_cast<uint64_t>(y), static_cast<uint64_t>(z));
      const uint32_t b_lo = static_cast<uint32_t>(base + static_cast<uint64_t>(x0)) & mask;
      const uint32_t b_hi = static_cast<uint32_t>(base + static_cast<uint64_t>(x1)) & mask;
      if constexpr (kDense) {
        const uint32_t t1 = g.bucket_start[b_hi + 1];
        for (uint32_t t = g.bucket_start[b_lo]; t < t1; ++t) test_slot<S, kFiltered>(g, q, t, sink);
      } else {
        const uint64_t row = static_cast<uint64_t>(y) | (static_cast<uint64_t>(z) << kGridAxisBits);
        auto scan = [&](uint32_t t0, uint32_t t1) {
          for (uint32_t t = t0; t < t1; ++t) {
            const uint64_t c = g.cell[t];
            const int64_t x = static_cast<int64_t>(c & kAxisMask);
            if ((c >> kGridAxisBits) != row || x < x0 || x > x1) continue;
            test_slot<S, kFiltered>(g, q, t, sink);
          }
        };
        if (b_lo <= b_hi) {
          scan(g.bucket_start[b_lo], g.bucket_start[b_hi + 1]);
        } else {  // wraps: [b_lo, end of table), then [0, b_hi]
          scan(g.bucket_start[b_lo], g.bucket_start[mask + 1]);
          scan(g.bucket_start[0], g.bucket_start[b_hi + 1]);
        }
      }
    }
  }
}

}  // namespace

uint32_t grid_query_bucket(const GridParams& g, float x, float y, float z) {
  const uint64_t cx = axis_cell(x, g.origin[0], g.inv_cell, g.dims[0]);
  const uint64_t cy = axis_cell(y, g.origin[1], g.inv_cell, g.dims[1]);
  const uint64_t cz = axis_cell(z, g.origin[2], g.inv_cell, g.dims[2]);
  return static_cast<uint32_t>(row_base(g, cy, cz) + cx) & bucket_mask(g);
}

uint64_t grid_query(const GridView* grids, uint32_t grid_count, const QueryView& q,
                    uint32_t* IMPACT_RESTRICT out_count, uint32_t* IMPACT_RESTRICT out_hits, uint64_t capacity,
                    Range r) {
  HitSink sink{out_hits, capacity, 0};
  const bool filtered = grid_count > 0 && grids[0].layer != nullptr;
  dispatch_query(q.shape, filtered, [&]<QueryShape S, bool kF>() {
    for (uint32_t p = r.begin; p < r.end; ++p) {
      const uint32_t i = q.order ? q.order[p] : p;
      const QueryItem item = make_query_item<S>(q, i);
      const uint64_t k0 = sink.k;
      for (uint32_t l = 0; l < grid_count; ++l) {
        if (grids[l].params.dense) query_grid<S, kF, true>(grids[l], item, sink);
        else query_grid<S, kF, false>(grids[l], item, sink);
      }
      out_count[i] = finish_query(sink, k0);
    }
  });
  return sink.k;
}

}  // namespace impact::kernels
