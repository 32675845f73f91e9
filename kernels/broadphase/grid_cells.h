// The uniform grid's cell and bucket arithmetic (kernels/broadphase/grid.h has the
// rules), shared by the pair passes (grid.cpp) and the queries (grid_query.cpp), so
// both always agree on which bucket holds a box.
#pragma once

#include "kernels/broadphase/grid.h"
#include "kernels/common/kernel.h"

namespace impact::kernels::grid_cells {

inline constexpr uint64_t kAxisMask = (1ull << kGridAxisBits) - 1;

/// Cell of coordinate v on one axis, clamped to [0, dim). The grid's range may
/// leave far outliers outside it (host grid_extent); they land in the boundary
/// cells. Clamping is monotone and 1-Lipschitz on cell indices, so two boxes whose
/// cells differ by at most one still do, and the neighbourhood passes stay exact.
/// The clamp is done in double, before the integer conversion (no overflow).
IMPACT_INLINE uint32_t axis_cell(float v, double origin, double inv_cell, uint32_t dim) {
  double u = (static_cast<double>(v) - origin) * inv_cell;
  const double top = static_cast<double>(dim) - 1.0;
  u = u > 0.0 ? u : 0.0;
  u = u < top ? u : top;
  return static_cast<uint32_t>(u);
}

IMPACT_INLINE uint64_t cell_id(uint64_t cx, uint64_t cy, uint64_t cz) {
  return cx | (cy << kGridAxisBits) | (cz << (2 * kGridAxisBits));
}

/// Bucket of the first cell (x = 0) of row (cy, cz); cell x of the row is at
/// row_base + x. Dense: the row-major index, so rows never overlap. Hashed: a
/// splitmix64 hash of the row (never std::hash), so cells of one row stay
/// consecutive (modulo the table size) while rows scatter over the table.
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

}  // namespace impact::kernels::grid_cells
