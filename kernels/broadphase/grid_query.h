// Batched AABB / sphere / point queries over the sorted grid(s) of grid.h. Hit rules,
// output layout and order: kernels/broadphase/query.h.
//
// What: per query i in r, per grid l (a single grid, or every level of the
//   hierarchical grid): the cell ranges that can hold an overlapping box, then each
//   candidate slot through query_hits and the mask; hits of all grids are appended,
//   then sorted by box index.
// Cell range: every stored box lies in the cell of its min corner and is smaller than
//   a cell (grid.h), so a box overlapping the query's bounding box [lo, hi] has its
//   min corner in (lo - cell, hi]: cells floor((lo - o) / cell) - 1 .. floor((hi - o)
//   / cell) per axis, clamped to the grid (in double, as the grid computes cells; the
//   cell exceeds the largest edge by 2^-20 relative, far above the rounding). A query
//   outside the grid's bounds gets an empty range and costs O(1).
// Rows: cells x0..x1 of row (y, z) are consecutive buckets (dense: row-major; hashed:
//   hash(y, z) + x mod 2^bits, possibly wrapping the table end), so each row is one or
//   two slot ranges; hashed slots whose cell lies outside the visited row range are
//   skipped (collisions cost time, never a duplicate).
// Full scan: when visiting the rows would cost about as much as testing every slot
//   (rows * kGridQueryRowCost, plus for hashed grids the expected slots of the
//   visited buckets, >= the grid's box count; or a hashed row range covering the
//   whole table), the query tests every slot of that grid instead: a huge query box
//   over a sparse hashed world costs O(n), not O(cells).
// Cost: O(rows + candidates) per query and grid, capped near O(n); plus k log k to
//   sort k hits (insertion sort up to 16).
// Inputs: finite queries (|v| <= 1e18); grids built by grid_bucket_count / grid_scatter_blocks
//   / grid_sort_blocks.
// Method: the region query of a uniform (hashed) grid: visit the cells the query's
//   bounds overlap, widened by one cell where boxes are stored by their min corner
//   (Teschner et al. 2003; Ericson, "Real-Time Collision Detection", 7.1).
#pragma once

#include "kernels/broadphase/grid.h"
#include "kernels/broadphase/query.h"
#include "kernels/common/kernel.h"

namespace impact::kernels {

/// Estimated cost of visiting one row, in slot tests (two bucket_start loads, often
/// cache misses, plus loop overhead).
inline constexpr double kGridQueryRowCost = 8.0;

/// Queries r against grids[0, grid_count) (each with >= 1 box; SortedBox::index is
/// the reported box index). Filtered iff grids[0].layer is set (all grids alike).
uint64_t grid_query(const GridView* grids, uint32_t grid_count, const QueryView& q,
                    uint32_t* IMPACT_RESTRICT out_count, uint32_t* IMPACT_RESTRICT out_hits, uint64_t capacity,
                    Range r);

/// Bucket of the cell holding point (x, y, z) under g: the bucket grid_bucket_count gives a
/// box whose min corner is that point. Exposed so tests can check that the queries
/// use the same cell and bucket arithmetic as grid_bucket_count (grid_cells.h).
uint32_t grid_query_bucket(const GridParams& g, float x, float y, float z);

}  // namespace impact::kernels
