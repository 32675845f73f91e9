#include "kernels/broadphase/grid.h"

#include <algorithm>
#include <cmath>

#include "kernels/broadphase/grid_cells.h"

namespace impact::kernels {
namespace {

using namespace grid_cells;  // NOLINT: the shared cell arithmetic (grid_cells.h)

// Calls test(t) for the slots t of grid g whose cell lies in row (ny, nz) with x
// in [lo, hi], starting at slot first_slot if it is not kInvalidBody (it must then
// lie in the bucket of cell lo). Slots in the row's bucket range that belong to
// other cells (hashed tables) are skipped; dense tables never have any. The
// buckets of a row are consecutive, except where a hashed row wraps the table end.
template <bool kDense, class Test>
IMPACT_INLINE void scan_row(const GridView& g, int64_t ny, int64_t nz, int64_t lo, int64_t hi,
                            uint32_t first_slot, Test&& test) {
  const uint32_t mask = bucket_mask(g.params);
  const uint64_t row = static_cast<uint64_t>(ny) | (static_cast<uint64_t>(nz) << kGridAxisBits);
  auto scan = [&](uint32_t t0, uint32_t t1) {
    for (uint32_t t = t0; t < t1; ++t) {
      if constexpr (!kDense) {
        const uint64_t c = g.cell[t];
        const int64_t x = static_cast<int64_t>(c & kAxisMask);
        if ((c >> kGridAxisBits) != row || x < lo || x > hi) continue;
      }
      test(t);
    }
  };
  const uint64_t base = row_base(g.params, static_cast<uint64_t>(ny), static_cast<uint64_t>(nz));
  const uint32_t b_lo = static_cast<uint32_t>(base + static_cast<uint64_t>(lo)) & mask;
  const uint32_t b_hi = static_cast<uint32_t>(base + static_cast<uint64_t>(hi)) & mask;
  const uint32_t t0 = first_slot != kInvalidBody ? first_slot : g.bucket_start[b_lo];
  if (b_lo <= b_hi) {
    scan(t0, g.bucket_start[b_hi + 1]);
  } else {  // wraps: [b_lo, end of table) then [0, b_hi]
    scan(t0, g.bucket_start[mask + 1]);
    scan(g.bucket_start[0], g.bucket_start[b_hi + 1]);
  }
}

// Calls emit(lo, hi) for every pair whose query slot is s, in the documented order.
template <bool kFiltered, bool kDense, class Emit>
IMPACT_INLINE void visit_slot(const GridView& g, uint32_t s, Emit&& emit) {
  const SortedBox A = g.box[s];
  const uint32_t ia = A.index;
  uint32_t la = 0, ma = 0;
  uint8_t sa = 0;
  if constexpr (kFiltered) {
    la = g.layer[s];
    ma = g.mask[s];
    sa = g.is_static[s];
  }
  const uint64_t cell = g.cell[s];

  auto test = [&](uint32_t t) {
    const SortedBox& B = g.box[t];
    if (!sorted_boxes_overlap(A, B)) return;
    if constexpr (kFiltered) {
      if (!pair_allowed(la, ma, sa, g.layer[t], g.mask[t], g.is_static[t])) return;
    }
    const uint32_t ib = B.index;
    emit(ia < ib ? ia : ib, ia < ib ? ib : ia);
  };

  const int64_t cx = static_cast<int64_t>(cell & kAxisMask);
  const int64_t cy = static_cast<int64_t>((cell >> kGridAxisBits) & kAxisMask);
  const int64_t cz = static_cast<int64_t>(cell >> (2 * kGridAxisBits));
  const int64_t dimx = g.params.dims[0], dimy = g.params.dims[1], dimz = g.params.dims[2];
  const int64_t x_lo = cx > 0 ? cx - 1 : 0;
  const int64_t x_hi = cx + 1 < dimx ? cx + 1 : dimx - 1;

  // The half neighbourhood as 5 row ranges: the own row from slot s + 1 to the
  // end of cell x + 1 (slots before s in the own cell met s already), then rows
  // (dy, dz) = (1, 0), (-1, 1), (0, 1), (1, 1) over x - 1 .. x + 1.
  scan_row<kDense>(g, cy, cz, cx, x_hi, s + 1, test);
  constexpr int8_t kRows[4][2] = {{1, 0}, {-1, 1}, {0, 1}, {1, 1}};
  for (const auto& r : kRows) {
    const int64_t ny = cy + r[0], nz = cz + r[1];
    if (ny < 0 || ny >= dimy || nz >= dimz) continue;
    scan_row<kDense>(g, ny, nz, x_lo, x_hi, kInvalidBody, test);
  }
}

template <class Fn>
IMPACT_INLINE void dispatch(const GridView& g, Fn&& fn) {
  const bool filtered = g.layer != nullptr;
  if (filtered) {
    if (g.params.dense) fn.template operator()<true, true>();
    else fn.template operator()<true, false>();
  } else {
    if (g.params.dense) fn.template operator()<false, true>();
    else fn.template operator()<false, false>();
  }
}

}  // namespace

void grid_keys_pack(const GridParams& g, AabbSoA boxes, PairFilter filter, const uint32_t* original_index,
                    uint64_t* IMPACT_RESTRICT out_keys, SortedBox* IMPACT_RESTRICT out_packed,
                    FilterRecord* IMPACT_RESTRICT out_filter, Range r) {
  for (uint32_t i = r.begin; i < r.end; ++i) {
    const float x0 = boxes.min_x[i], y0 = boxes.min_y[i], z0 = boxes.min_z[i];
    const uint64_t cell = box_cell(g, x0, y0, z0);
    out_keys[i] = (static_cast<uint64_t>(bucket_of(g, cell)) << 32) | i;
    const uint32_t id = original_index ? original_index[i] : i;
    out_packed[i] = SortedBox{x0, y0, z0, id, boxes.max_x[i], boxes.max_y[i], boxes.max_z[i], 0u};
  }
  if (out_filter) {
    for (uint32_t i = r.begin; i < r.end; ++i)
      out_filter[i] = FilterRecord{filter.layer[i], filter.mask[i], filter.is_static[i], 0u};
  }
}

void grid_gather_packed(const GridParams& g, const uint64_t* IMPACT_RESTRICT sorted_keys,
                        const SortedBox* IMPACT_RESTRICT packed, const FilterRecord* IMPACT_RESTRICT packed_filter,
                        GridSorted out, Range r) {
  // The reads are random for an unordered input: prefetch a few slots ahead so
  // several misses are in flight (the loop body alone keeps too few).
  constexpr uint32_t kAhead = 16;
  for (uint32_t s = r.begin; s < r.end; ++s) {
    if (s + kAhead < r.end) __builtin_prefetch(&packed[static_cast<uint32_t>(sorted_keys[s + kAhead])]);
    const SortedBox b = packed[static_cast<uint32_t>(sorted_keys[s])];
    out.box[s] = b;
    out.cell[s] = box_cell(g, b.min_x, b.min_y, b.min_z);
  }
  if (packed_filter) {
    for (uint32_t s = r.begin; s < r.end; ++s) {
      const FilterRecord f = packed_filter[static_cast<uint32_t>(sorted_keys[s])];
      out.layer[s] = f.layer;
      out.mask[s] = f.mask;
      out.is_static[s] = static_cast<uint8_t>(f.is_static);
    }
  }
}

uint64_t grid_find_pairs(const GridView& g, Pair* IMPACT_RESTRICT out, uint64_t capacity, Range r) {
  uint64_t k = 0;
  dispatch(g, [&]<bool kF, bool kD>() {
    for (uint32_t s = r.begin; s < r.end; ++s)
      visit_slot<kF, kD>(g, s, [&](uint32_t a, uint32_t b) {
        if (k < capacity) out[k] = Pair{a, b};
        ++k;
      });
  });
  return k;
}

uint64_t grid_query_pairs(const GridView& g, const SortedBox* IMPACT_RESTRICT queries, PairFilter query_filter,
                          Pair* IMPACT_RESTRICT out, uint64_t capacity, Range r) {
  uint64_t k = 0;
  const bool filtered = g.layer != nullptr;
  const int64_t dims[3] = {g.params.dims[0], g.params.dims[1], g.params.dims[2]};
  // Cell range [lo, hi] on one axis holding the min corners of boxes that can
  // overlap [q_min, q_max]: those corners lie in [q_min - cell, q_max].
  auto axis_range = [&](float q_min, float q_max, int axis, int64_t* lo, int64_t* hi) {
    const double o = g.params.origin[axis], inv = g.params.inv_cell;
    *lo = static_cast<int64_t>(std::floor((static_cast<double>(q_min) - o) * inv - 1.0));
    *hi = static_cast<int64_t>(std::floor((static_cast<double>(q_max) - o) * inv));
    if (*lo < 0) *lo = 0;
    if (*hi > dims[axis] - 1) *hi = dims[axis] - 1;
    return *lo <= *hi;
  };
  auto run = [&]<bool kDense>() {
    for (uint32_t s = r.begin; s < r.end; ++s) {
      const SortedBox A = queries[s];
      int64_t x0, x1, y0, y1, z0, z1;
      if (!axis_range(A.min_x, A.max_x, 0, &x0, &x1) || !axis_range(A.min_y, A.max_y, 1, &y0, &y1) ||
          !axis_range(A.min_z, A.max_z, 2, &z0, &z1))
        continue;
      auto test = [&](uint32_t t) {
        const SortedBox& B = g.box[t];
        if (!sorted_boxes_overlap(A, B)) return;
        if (filtered && !pair_allowed(query_filter.layer[s], query_filter.mask[s], query_filter.is_static[s],
                                      g.layer[t], g.mask[t], g.is_static[t]))
          return;
        const uint32_t ia = A.index, ib = B.index;
        if (k < capacity) out[k] = Pair{ia < ib ? ia : ib, ia < ib ? ib : ia};
        ++k;
      };
      for (int64_t z = z0; z <= z1; ++z)
        for (int64_t y = y0; y <= y1; ++y) scan_row<kDense>(g, y, z, x0, x1, kInvalidBody, test);
    }
  };
  if (g.params.dense) run.template operator()<true>();
  else run.template operator()<false>();
  return k;
}

void grid_levels(AabbSoA boxes, float top_edge, uint8_t* IMPACT_RESTRICT out_level,
                 uint32_t* IMPACT_RESTRICT out_count, Range r) {
  for (uint32_t l = 0; l < kGridMaxLevels; ++l) out_count[l] = 0;
  for (uint32_t i = r.begin; i < r.end; ++i) {
    const float e = std::max(boxes.max_x[i] - boxes.min_x[i],
                             std::max(boxes.max_y[i] - boxes.min_y[i], boxes.max_z[i] - boxes.min_z[i]));
    uint32_t l = 0;
    float bound = top_edge * 0.25f;  // level l holds edges in (top / 4^(l+1), top / 4^l]
    while (l + 1 < kGridMaxLevels && !(e > bound)) {
      ++l;
      bound *= 0.25f;
    }
    out_level[i] = static_cast<uint8_t>(l);
    ++out_count[l];
  }
}

}  // namespace impact::kernels
