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

IMPACT_INLINE uint32_t bucket_of(const GridParams& g, uint64_t cell) {
  const uint64_t cx = cell & kAxisMask;
  const uint64_t cy = (cell >> kGridAxisBits) & kAxisMask;
  const uint64_t cz = cell >> (2 * kGridAxisBits);
  if (g.dense) return static_cast<uint32_t>(cx + g.dims[0] * (cy + g.dims[1] * cz));
  if (g.table_bits == 0) return 0;
  // splitmix64 finaliser: a cheap, well-mixed, fixed hash (never std::hash).
  uint64_t h = cell + 0x9e3779b97f4a7c15ull;
  h = (h ^ (h >> 30)) * 0xbf58476d1ce4e5b9ull;
  h = (h ^ (h >> 27)) * 0x94d049bb133111ebull;
  h ^= h >> 31;
  return static_cast<uint32_t>(h >> (64 - g.table_bits));
}

IMPACT_INLINE uint64_t box_cell(const GridParams& g, float x, float y, float z) {
  return cell_id(axis_cell(x, g.origin[0], g.inv_cell, g.dims[0]),
                 axis_cell(y, g.origin[1], g.inv_cell, g.dims[1]),
                 axis_cell(z, g.origin[2], g.inv_cell, g.dims[2]));
}

// The 13 neighbour offsets (dx, dy, dz) that are lexicographically after (0,0,0)
// in (dz, dy, dx) order: the forward half of the 26-neighbourhood.
struct Offset {
  int8_t dx, dy, dz;
};
constexpr Offset kForward[13] = {
    {1, 0, 0},                                                                  // dz=0, dy=0
    {-1, 1, 0},  {0, 1, 0},  {1, 1, 0},                                         // dz=0, dy=1
    {-1, -1, 1}, {0, -1, 1}, {1, -1, 1}, {-1, 0, 1}, {0, 0, 1}, {1, 0, 1},      // dz=1
    {-1, 1, 1},  {0, 1, 1},  {1, 1, 1}};

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

  if constexpr (kDense) {
    // Row-major buckets: the cells x-1..x+1 of a row are consecutive buckets, so
    // each of the 5 forward rows of the half neighbourhood is one slot range:
    // own row from s + 1 to the end of cell x+1, then rows (dy, dz) = (1, 0),
    // (-1, 1), (0, 1), (1, 1), each over x-1..x+1.
    const int64_t x_lo = cx > 0 ? cx - 1 : 0;
    const int64_t x_hi = cx + 1 < dimx ? cx + 1 : dimx - 1;
    const uint32_t row0 = static_cast<uint32_t>(g.params.dims[0] * (cy + dimy * cz));
    for (uint32_t t = s + 1, end = g.bucket_start[row0 + x_hi + 1]; t < end; ++t) test(t);
    constexpr int8_t kRows[4][2] = {{1, 0}, {-1, 1}, {0, 1}, {1, 1}};
    for (const auto& row : kRows) {
      const int64_t ny = cy + row[0], nz = cz + row[1];
      if (ny < 0 || ny >= dimy || nz >= dimz) continue;
      const uint32_t base = static_cast<uint32_t>(dimx * (ny + dimy * nz));
      for (uint32_t t = g.bucket_start[base + x_lo], end = g.bucket_start[base + x_hi + 1]; t < end; ++t)
        test(t);
    }
  } else {
    // Hashed buckets hold several cells: visit cells one by one and skip slots
    // whose cell differs. Own cell first (slots after s), then the 13 forward cells.
    {
      const uint32_t end = g.bucket_start[bucket_of(g.params, cell) + 1];
      for (uint32_t t = s + 1; t < end; ++t)
        if (g.cell[t] == cell) test(t);
    }
    for (const Offset& o : kForward) {
      const int64_t nx = cx + o.dx, ny = cy + o.dy, nz = cz + o.dz;
      if (nx < 0 || ny < 0 || nx >= dimx || ny >= dimy || nz >= dimz) continue;  // dz >= 0
      const uint64_t ncell = cell_id(static_cast<uint64_t>(nx), static_cast<uint64_t>(ny),
                                     static_cast<uint64_t>(nz));
      const uint32_t b = bucket_of(g.params, ncell);
      for (uint32_t t = g.bucket_start[b], end = g.bucket_start[b + 1]; t < end; ++t)
        if (g.cell[t] == ncell) test(t);
    }
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
