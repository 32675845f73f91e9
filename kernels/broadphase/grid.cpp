#include "kernels/broadphase/grid.h"

namespace impact::kernels {
namespace {

constexpr uint64_t kAxisMask = (1ull << kGridAxisBits) - 1;

IMPACT_INLINE uint32_t axis_cell(float v, double origin, double inv_cell, uint32_t dim) {
  const double u = (static_cast<double>(v) - origin) * inv_cell;
  // u >= 0 because origin is the minimum; the clamps only guard rounding at the ends.
  int64_t c = static_cast<int64_t>(u);
  c = c < 0 ? 0 : c;
  c = c >= static_cast<int64_t>(dim) ? static_cast<int64_t>(dim) - 1 : c;
  return static_cast<uint32_t>(c);
}

IMPACT_INLINE uint64_t cell_id(uint64_t cx, uint64_t cy, uint64_t cz) {
  return cx | (cy << kGridAxisBits) | (cz << (2 * kGridAxisBits));
}

// Bucket of the first cell (x = 0) of row (cy, cz); cell x of the row is at
// row_base + x. Dense: the row-major index, so rows never overlap. Hashed: a
// splitmix64 hash of the row (never std::hash), so cells of one row stay
// consecutive (modulo the table size) while rows scatter over the table.
IMPACT_INLINE uint64_t row_base(const GridParams& g, uint64_t cy, uint64_t cz) {
  if (g.dense) return g.dims[0] * (cy + g.dims[1] * cz);
  uint64_t h = (cy | (cz << kGridAxisBits)) + 0x9e3779b97f4a7c15ull;
  h = (h ^ (h >> 30)) * 0xbf58476d1ce4e5b9ull;
  h = (h ^ (h >> 27)) * 0x94d049bb133111ebull;
  return h ^ (h >> 31);
}

IMPACT_INLINE uint32_t bucket_mask(const GridParams& g) {
  return g.dense ? 0xffffffffu : (g.table_bits == 0 ? 0u : (1u << g.table_bits) - 1u);
}

IMPACT_INLINE uint32_t bucket_of(const GridParams& g, uint64_t cell) {
  const uint64_t cx = cell & kAxisMask;
  const uint64_t cy = (cell >> kGridAxisBits) & kAxisMask;
  const uint64_t cz = cell >> (2 * kGridAxisBits);
  return static_cast<uint32_t>(row_base(g, cy, cz) + cx) & bucket_mask(g);
}

IMPACT_INLINE uint64_t box_cell(const GridParams& g, float x, float y, float z) {
  return cell_id(axis_cell(x, g.origin[0], g.inv_cell, g.dims[0]),
                 axis_cell(y, g.origin[1], g.inv_cell, g.dims[1]),
                 axis_cell(z, g.origin[2], g.inv_cell, g.dims[2]));
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
    // Bitwise & (not &&): one hard-to-predict branch instead of six.
    const bool overlap = (A.min_x <= B.max_x) & (B.min_x <= A.max_x) &  //
                         (A.min_y <= B.max_y) & (B.min_y <= A.max_y) &  //
                         (A.min_z <= B.max_z) & (B.min_z <= A.max_z);
    if (!overlap) return;
    if constexpr (kFiltered) {
      if ((la & g.mask[t]) == 0 || (g.layer[t] & ma) == 0) return;
      if (sa && g.is_static[t]) return;
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
  const uint32_t mask = bucket_mask(g.params);

  // Slots [t0, t1) of buckets that hold cells x_lo..x_hi of row (ny, nz), calling
  // test() on those that really are in that row and x range (hashed tables may
  // mix in other cells; dense ones never do). The buckets of a row are
  // consecutive, except where a hashed row wraps around the table end.
  auto scan = [&](uint32_t t0, uint32_t t1, uint64_t row, int64_t lo, int64_t hi) {
    for (uint32_t t = t0; t < t1; ++t) {
      if constexpr (!kDense) {
        const uint64_t c = g.cell[t];
        const int64_t x = static_cast<int64_t>(c & kAxisMask);
        if ((c >> kGridAxisBits) != row || x < lo || x > hi) continue;
      }
      test(t);
    }
  };
  auto visit_row = [&](int64_t ny, int64_t nz, int64_t lo, int64_t hi, uint32_t first_slot) {
    const uint64_t row = static_cast<uint64_t>(ny) | (static_cast<uint64_t>(nz) << kGridAxisBits);
    const uint64_t base = row_base(g.params, static_cast<uint64_t>(ny), static_cast<uint64_t>(nz));
    const uint32_t b_lo = static_cast<uint32_t>(base + static_cast<uint64_t>(lo)) & mask;
    const uint32_t b_hi = static_cast<uint32_t>(base + static_cast<uint64_t>(hi)) & mask;
    if (b_lo <= b_hi) {
      const uint32_t t0 = first_slot != kInvalidBody ? first_slot : g.bucket_start[b_lo];
      scan(t0, g.bucket_start[b_hi + 1], row, lo, hi);
    } else {  // wraps: [b_lo, end of table) then [0, b_hi]
      const uint32_t t0 = first_slot != kInvalidBody ? first_slot : g.bucket_start[b_lo];
      scan(t0, g.bucket_start[mask + 1], row, lo, hi);
      scan(g.bucket_start[0], g.bucket_start[b_hi + 1], row, lo, hi);
    }
  };

  // The half neighbourhood as 5 row ranges: the own row from slot s + 1 to the
  // end of cell x + 1 (slots before s in the own cell met s already), then rows
  // (dy, dz) = (1, 0), (-1, 1), (0, 1), (1, 1) over x - 1 .. x + 1.
  visit_row(cy, cz, cx, x_hi, s + 1);
  constexpr int8_t kRows[4][2] = {{1, 0}, {-1, 1}, {0, 1}, {1, 1}};
  for (const auto& r : kRows) {
    const int64_t ny = cy + r[0], nz = cz + r[1];
    if (ny < 0 || ny >= dimy || nz >= dimz) continue;
    visit_row(ny, nz, x_lo, x_hi, kInvalidBody);
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

void grid_keys(const GridParams& g, AabbSoA boxes, uint64_t* IMPACT_RESTRICT out_keys, Range r) {
  for (uint32_t i = r.begin; i < r.end; ++i) {
    const uint64_t cell = box_cell(g, boxes.min_x[i], boxes.min_y[i], boxes.min_z[i]);
    out_keys[i] = (static_cast<uint64_t>(bucket_of(g, cell)) << 32) | i;
  }
}

void grid_gather(const GridParams& g, const uint64_t* IMPACT_RESTRICT sorted_keys, AabbSoA boxes,
                 PairFilter filter, GridSorted out, Range r) {
  for (uint32_t s = r.begin; s < r.end; ++s) {
    const uint32_t i = static_cast<uint32_t>(sorted_keys[s]);
    const float x0 = boxes.min_x[i], y0 = boxes.min_y[i], z0 = boxes.min_z[i];
    out.cell[s] = box_cell(g, x0, y0, z0);
    out.box[s] = SortedBox{x0, y0, z0, i, boxes.max_x[i], boxes.max_y[i], boxes.max_z[i], 0u};
    if (filter.layer) {
      out.layer[s] = filter.layer[i];
      out.mask[s] = filter.mask[i];
      out.is_static[s] = filter.is_static[i];
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

}  // namespace impact::kernels
