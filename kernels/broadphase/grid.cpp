#include "kernels/broadphase/grid.h"

#include <algorithm>
#include <cmath>

#include "kernels/broadphase/grid_cells.h"
#include "kernels/simd/lanes.h"

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

// Candidate slots of one query slot, in visiting order. Dense grids
// (visit_dense_range) collect the short slot ranges of the 5 rows into one list with
// fixed-width stores and test them in one loop: one hard-to-predict loop exit per
// query instead of one per row (uniform scenes hold about 1.4 candidates per row range). A range longer than
// kRun is tested in place after the list so far, which keeps the order.
struct CandidateList {
  static constexpr uint32_t kRun = 8;
  static constexpr uint32_t kCapacity = 6 * kRun;  // 5 rows plus slack, all of them short
  uint32_t slot[kCapacity];
  uint32_t count = 0;
};

// The pair pass's output: every candidate is stored, at out[k] while k < capacity and
// into `sink` after; only a result advances k. A store that is not a result is
// overwritten by the next one, so out[0, min(k, capacity)) holds exactly the results
// (no data-dependent branch in the hot loop). put<true> skips the capacity select
// where room(m) said the next m stores fit.
struct PairSink {
  Pair* out;
  uint64_t capacity;
  uint64_t k = 0;
  Pair sink{};
  IMPACT_INLINE bool room(uint32_t m) const { return k <= capacity && capacity - k >= m; }
  template <bool kRoom>
  IMPACT_INLINE void put(uint32_t a, uint32_t b, bool ok) {
    Pair* dst = kRoom ? out + k : (k < capacity ? out + k : &sink);
    *dst = Pair{a, b};
    k += ok ? 1u : 0u;
  }
};

// One query slot of the pair pass: its box and filter fields, and the test of a
// candidate slot t, storing (lo, hi) with whether it is a result.
template <bool kFiltered>
struct SlotQuery {
  SortedBox a;
  uint32_t layer = 0, mask = 0;
  uint8_t is_static = 0;
  IMPACT_INLINE SlotQuery(const GridView& g, uint32_t s) : a(g.box[s]) {
    if constexpr (kFiltered) {
      layer = g.layer[s];
      mask = g.mask[s];
      is_static = g.is_static[s];
    }
  }
  template <bool kRoom>
  IMPACT_INLINE void test(const GridView& g, uint32_t t, PairSink& out) const {
    const SortedBox& b = g.box[t];
    bool ok = sorted_boxes_overlap(a, b);
    if constexpr (kFiltered)
      ok = ok && pair_allowed(layer, mask, is_static, g.layer[t], g.mask[t], g.is_static[t]);
    const uint32_t ia = a.index, ib = b.index;
    out.put<kRoom>(ia < ib ? ia : ib, ia < ib ? ib : ia, ok);
  }
};

// Hashed grids: every candidate of query slot s into out (PairSink: stored either
// way, counted if a result, so the hot loop has no data-dependent branch), in the
// documented order. The half neighbourhood as 5 row ranges: the own row from slot
// s + 1 to the end of cell x + 1 (slots before s in the own cell met s already), then
// rows (dy, dz) = (1, 0), (-1, 1), (0, 1), (1, 1) over x - 1 .. x + 1.
template <bool kFiltered>
IMPACT_INLINE void visit_slot(const GridView& g, uint32_t s, PairSink& out) {
  const SlotQuery<kFiltered> q(g, s);
  auto test = [&](uint32_t t) { q.template test<false>(g, t, out); };
  const uint64_t cell = g.cell[s];
  const int64_t cx = static_cast<int64_t>(cell & kAxisMask);
  const int64_t cy = static_cast<int64_t>((cell >> kGridAxisBits) & kAxisMask);
  const int64_t cz = static_cast<int64_t>(cell >> (2 * kGridAxisBits));
  const int64_t dimx = g.params.dims[0], dimy = g.params.dims[1], dimz = g.params.dims[2];
  const int64_t x_lo = cx > 0 ? cx - 1 : 0;
  const int64_t x_hi = cx + 1 < dimx ? cx + 1 : dimx - 1;
  constexpr int8_t kRows[4][2] = {{1, 0}, {-1, 1}, {0, 1}, {1, 1}};
  scan_row<false>(g, cy, cz, cx, x_hi, s + 1, test);
  for (const auto& r : kRows) {
    const int64_t ny = cy + r[0], nz = cz + r[1];
    if (ny < 0 || ny >= dimy || nz >= dimz) continue;
    scan_row<false>(g, ny, nz, x_lo, x_hi, kInvalidBody, test);
  }
}

// Dense grids: the same half neighbourhood and order as visit_slot, for the slots of
// range r, walked row by row. A row (cy, cz) holds consecutive slots (buckets are
// row-major cells, so a row's cells x_lo .. x_hi are buckets base + x_lo .. base +
// x_hi, holding only those cells' boxes), so its own and neighbour rows' bucket bases
// are computed once per row, and a slot needs only its x cell (one conversion instead
// of three). The row ranges go through one CandidateList per slot.
template <bool kFiltered>
IMPACT_INLINE void visit_dense_range(const GridView& g, Range r, PairSink& out) {
  if (r.begin >= r.end) return;
  const uint32_t* start = g.bucket_start;
  const int64_t dimx = g.params.dims[0], dimy = g.params.dims[1], dimz = g.params.dims[2];
  constexpr int8_t kRows[4][2] = {{1, 0}, {-1, 1}, {0, 1}, {1, 1}};
  uint64_t own = 0;        // bucket of cell (0, cy, cz)
  uint64_t base[4] = {};   // bucket of cell (0, ny, nz) per neighbour row
  uint32_t rows = 0;       // bit i: neighbour row kRows[i] lies inside the grid
  uint32_t row_end = 0;    // first slot past the current row
  CandidateList list;
  for (uint32_t s = r.begin; s < r.end; ++s) {
    const SlotQuery<kFiltered> q(g, s);
    const SortedBox& A = q.a;
    if (s >= row_end) {  // the first slot of r, or the first of a later row
      const int64_t cy = axis_cell(A.min_y, g.params.origin[1], g.params.inv_cell, g.params.dims[1]);
      const int64_t cz = axis_cell(A.min_z, g.params.origin[2], g.params.inv_cell, g.params.dims[2]);
      own = static_cast<uint64_t>(dimx) * (static_cast<uint64_t>(cy) + static_cast<uint64_t>(dimy) * cz);
      row_end = start[own + static_cast<uint64_t>(dimx)];
      rows = 0;
      for (uint32_t i = 0; i < 4; ++i) {
        const int64_t ny = cy + kRows[i][0], nz = cz + kRows[i][1];
        if (ny < 0 || ny >= dimy || nz >= dimz) continue;
        rows |= 1u << i;
        base[i] =
            static_cast<uint64_t>(dimx) * (static_cast<uint64_t>(ny) + static_cast<uint64_t>(dimy) * nz);
      }
    }
    auto flush = [&] {
      if (out.room(list.count)) {
        for (uint32_t i = 0; i < list.count; ++i) q.template test<true>(g, list.slot[i], out);
      } else {
        for (uint32_t i = 0; i < list.count; ++i) q.template test<false>(g, list.slot[i], out);
      }
      list.count = 0;
    };
    auto add = [&](uint32_t t0, uint32_t t1) {
      const uint32_t m = t1 - t0;
      if (m <= CandidateList::kRun) {
        uint32_t* dst = list.slot + list.count;
        for (uint32_t j = 0; j < CandidateList::kRun; ++j) dst[j] = t0 + j;
        list.count += m;
      } else {
        flush();
        for (uint32_t t = t0; t < t1; ++t) q.template test<false>(g, t, out);
      }
    };
    const int64_t cx = axis_cell(A.min_x, g.params.origin[0], g.params.inv_cell, g.params.dims[0]);
    const uint64_t x_lo = static_cast<uint64_t>(cx > 0 ? cx - 1 : 0);
    const uint64_t x_hi = static_cast<uint64_t>(cx + 1 < dimx ? cx + 1 : dimx - 1);
    add(s + 1, start[own + x_hi + 1]);
    for (uint32_t i = 0; i < 4; ++i) {
      if ((rows >> i & 1u) == 0) continue;
      add(start[base[i] + x_lo], start[base[i] + x_hi + 1]);
    }
    flush();
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

GridBlocks grid_blocks(const GridParams& g) {
  uint32_t bits = 0;  // bits of the largest bucket id
  while (bits < 32 && ((g.bucket_count - 1) >> bits) != 0) ++bits;
  const uint32_t low = bits > kGridMaxBlockBits ? bits - kGridMaxBlockBits : 0;
  return GridBlocks{low, static_cast<uint32_t>(((static_cast<uint64_t>(g.bucket_count) - 1) >> low) + 1)};
}

void grid_bucket_count(const GridParams& g, GridBlocks blocks, AabbSoA boxes,
                       uint32_t* IMPACT_RESTRICT out_bucket, uint32_t* IMPACT_RESTRICT out_block_count,
                       Range r) {
  for (uint32_t k = 0; k < blocks.count; ++k) out_block_count[k] = 0;
  // Buckets first (a loop without the histogram's store-to-load chain vectorises),
  // then the counts.
  const float* IMPACT_RESTRICT x = boxes.min_x;
  const float* IMPACT_RESTRICT y = boxes.min_y;
  const float* IMPACT_RESTRICT z = boxes.min_z;
  if (g.dense) {
    // bucket_of(box_cell(..)) spelled out for dense grids (row-major cell index).
    const double ox = g.origin[0], oy = g.origin[1], oz = g.origin[2], inv = g.inv_cell;
    const int64_t dx = g.dims[0], dy = g.dims[1];
    const double tx = g.dims[0] - 1.0, ty = g.dims[1] - 1.0, tz = g.dims[2] - 1.0;
    // Clamped in double as axis_cell does (outliers beyond the grid's range).
#pragma omp simd
    for (uint32_t i = r.begin; i < r.end; ++i) {
      const int64_t cx = static_cast<int64_t>(std::clamp((static_cast<double>(x[i]) - ox) * inv, 0.0, tx));
      const int64_t cy = static_cast<int64_t>(std::clamp((static_cast<double>(y[i]) - oy) * inv, 0.0, ty));
      const int64_t cz = static_cast<int64_t>(std::clamp((static_cast<double>(z[i]) - oz) * inv, 0.0, tz));
      out_bucket[i] = static_cast<uint32_t>(cx + dx * (cy + dy * cz));
    }
  } else {
    for (uint32_t i = r.begin; i < r.end; ++i) out_bucket[i] = bucket_of(g, box_cell(g, x[i], y[i], z[i]));
  }
  for (uint32_t i = r.begin; i < r.end; ++i) ++out_block_count[out_bucket[i] >> blocks.low_bits];
}

void grid_scatter_blocks(GridBlocks blocks, AabbSoA boxes, PairFilter filter, const uint32_t* original_index,
                         const uint32_t* IMPACT_RESTRICT bucket, uint32_t* IMPACT_RESTRICT io_offsets,
                         SortedBox* IMPACT_RESTRICT out_box, FilterRecord* IMPACT_RESTRICT out_filter,
                         Range r) {
  auto put_filter = [&](uint32_t slot, uint32_t k) {
    if (out_filter) out_filter[slot] = FilterRecord{filter.layer[k], filter.mask[k], filter.is_static[k], 0u};
  };
  uint32_t i = r.begin;
  if constexpr (simd::kSimdWidth == 8) {
    // Eight boxes at a time: their records by one 8 x 8 transpose of the eight source
    // rows (simd::load_transposed: 8 loads and 24 shuffles) and one 32-byte store each,
    // instead of six scalar loads, inserts and partial stores per box. The same bytes.
    alignas(32) uint32_t iota[8];
    for (; i + 8 <= r.end; i += 8) {
      const uint32_t* id = original_index ? original_index + i : iota;
      if (!original_index)
        for (uint32_t k = 0; k < 8; ++k) iota[k] = i + k;
      const float* rows[8] = {boxes.min_x + i, boxes.min_y + i, boxes.min_z + i,
                              reinterpret_cast<const float*>(id), boxes.max_x + i, boxes.max_y + i,
                              boxes.max_z + i, reinterpret_cast<const float*>(bucket + i)};
      simd::FloatN<8> rec[8];
      simd::load_transposed<8>(rows, rec);
      for (uint32_t k = 0; k < 8; ++k) {
        const uint32_t slot = io_offsets[bucket[i + k] >> blocks.low_bits]++;
        rec[k].store(reinterpret_cast<float*>(out_box + slot));
        put_filter(slot, i + k);
      }
    }
  }
  for (; i < r.end; ++i) {
    const uint32_t b = bucket[i];
    const uint32_t slot = io_offsets[b >> blocks.low_bits]++;
    const uint32_t id = original_index ? original_index[i] : i;
    out_box[slot] = SortedBox{boxes.min_x[i], boxes.min_y[i], boxes.min_z[i], id,
                              boxes.max_x[i], boxes.max_y[i], boxes.max_z[i], b};
    put_filter(slot, i);
  }
}

void grid_sort_blocks(const GridParams& g, GridBlocks blocks, const uint32_t* IMPACT_RESTRICT block_start,
                      const SortedBox* IMPACT_RESTRICT in_box, const FilterRecord* IMPACT_RESTRICT in_filter,
                      GridSorted out, uint32_t* IMPACT_RESTRICT out_bucket_start, Range r) {
  for (uint32_t k = r.begin; k < r.end; ++k) {
    const uint32_t s0 = block_start[k], s1 = block_start[k + 1];
    const uint32_t b0 = k << blocks.low_bits;
    const uint32_t b1 = static_cast<uint32_t>(
        std::min<uint64_t>(static_cast<uint64_t>(b0) + (1ull << blocks.low_bits), g.bucket_count));
    // The block's slice of bucket_start holds the counts, then (inclusive scan) each
    // bucket's end; filling slots from the back moves each end down to its start.
    uint32_t* cursor = out_bucket_start + b0;
    const uint32_t nb = b1 - b0;
    for (uint32_t j = 0; j < nb; ++j) cursor[j] = 0;
    for (uint32_t s = s0; s < s1; ++s) ++cursor[in_box[s].pad - b0];
    uint32_t end = s0;
    for (uint32_t j = 0; j < nb; ++j) {
      end += cursor[j];
      cursor[j] = end;
    }
    for (uint32_t s = s1; s-- > s0;) {
      SortedBox box = in_box[s];
      const uint32_t t = --cursor[box.pad - b0];
      box.pad = 0;
      out.box[t] = box;
      if (out.cell) out.cell[t] = box_cell(g, box.min_x, box.min_y, box.min_z);
      if (in_filter) {
        const FilterRecord f = in_filter[s];
        out.layer[t] = f.layer;
        out.mask[t] = f.mask;
        out.is_static[t] = static_cast<uint8_t>(f.is_static);
      }
    }
    if (b1 == g.bucket_count) out_bucket_start[b1] = s1;
  }
}

uint64_t grid_find_pairs(const GridView& g, Pair* IMPACT_RESTRICT out, uint64_t capacity, Range r) {
  PairSink sink{out, capacity};
  dispatch(g, [&]<bool kF, bool kD>() {
    if constexpr (kD) {
      visit_dense_range<kF>(g, r, sink);
    } else {
      for (uint32_t s = r.begin; s < r.end; ++s) visit_slot<kF>(g, s, sink);
    }
  });
  return sink.k;
}

uint64_t grid_query_pairs(const GridView& g, const SortedBox* IMPACT_RESTRICT queries, PairFilter query_filter,
                          Pair* IMPACT_RESTRICT out, uint64_t capacity, Range r) {
  uint64_t k = 0;
  const bool filtered = g.layer != nullptr;
  const int64_t dims[3] = {g.params.dims[0], g.params.dims[1], g.params.dims[2]};
  // Cell range [lo, hi] on one axis holding the min corners of boxes that can
  // overlap [q_min, q_max]: those corners lie in [q_min - cell, q_max].
  auto axis_range = [&](float q_min, float q_max, int axis, int64_t* lo, int64_t* hi) {
    // Both ends clamped in double to the grid (boxes outside its range sit in the
    // boundary cells, axis_cell), so the range is never empty.
    const double o = g.params.origin[axis], inv = g.params.inv_cell;
    const double top = static_cast<double>(dims[axis] - 1);
    *lo = static_cast<int64_t>(std::clamp(std::floor((static_cast<double>(q_min) - o) * inv - 1.0), 0.0, top));
    *hi = static_cast<int64_t>(std::clamp(std::floor((static_cast<double>(q_max) - o) * inv), 0.0, top));
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
