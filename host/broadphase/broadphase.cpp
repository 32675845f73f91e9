#include "host/broadphase/broadphase.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "kernels/broadphase/bounds.h"
#include "kernels/sort/segments.h"

namespace impact::host {
namespace {

constexpr uint64_t kMaxPairs = 0xffffffffull;  // kernels index pairs with uint32

kernels::GridParams choose_grid(const kernels::BoundsSummary& s, uint32_t n, GridInfo* info) {
  kernels::GridParams g{};
  double extent[3];
  double max_extent = 0;
  for (int k = 0; k < 3; ++k) {
    g.origin[k] = s.lo[k];
    extent[k] = static_cast<double>(s.hi[k]) - static_cast<double>(s.lo[k]);
    max_extent = std::max(max_extent, extent[k]);
  }
  // The cell must exceed the largest box edge (see grid.h); the small relative
  // margin absorbs the rounding of the double cell computation.
  double cell = static_cast<double>(s.max_edge) * (1.0 + 0x1p-20);
  // Never more than kGridMaxDim - 1 cells across; zero-size boxes get a cell that
  // spreads them over roughly one cell per box.
  const double min_cell = max_extent / static_cast<double>(kernels::kGridMaxDim - 2);
  if (s.max_edge == 0.0f) cell = max_extent / std::max(1.0, std::cbrt(static_cast<double>(n)));
  cell = std::max(cell, min_cell);
  if (!(cell > 0.0) || !std::isfinite(cell)) cell = 1.0;
  auto count_cells = [&](double c) {
    const double inv = 1.0 / c;
    double cells = 1.0;
    for (int k = 0; k < 3; ++k)
      cells *= std::min<double>(std::floor(extent[k] * inv) + 1.0, kernels::kGridMaxDim);
    return cells;
  };
  // Dense (row-major buckets, no hashing, spatial locality) when the cell count is
  // a small multiple of n. A moderately sparse scene may coarsen its cells up to
  // 2x to stay dense (more candidates per cell, far fewer cache misses); sparser
  // scenes hash.
  const double dense_limit = std::max(4.0 * n, 4096.0);
  double cells = count_cells(cell);
  if (cells > dense_limit && count_cells(2.0 * cell) <= dense_limit) {
    // Smallest growth (in 1% steps) that fits; the "+1" per axis makes it inexact.
    double grow = std::max(1.0, std::cbrt(cells / dense_limit));
    while (count_cells(cell * grow) > dense_limit) grow *= 1.01;
    cell *= grow;
    cells = count_cells(cell);
  }
  g.inv_cell = 1.0 / cell;
  for (int k = 0; k < 3; ++k)
    g.dims[k] = static_cast<uint32_t>(std::min<double>(std::floor(extent[k] * g.inv_cell) + 1.0,
                                                       kernels::kGridMaxDim));
  cells = static_cast<double>(g.dims[0]) * g.dims[1] * g.dims[2];
  if (cells <= dense_limit) {
    g.dense = 1;
    g.table_bits = 0;
    g.bucket_count = static_cast<uint32_t>(cells);
  } else {
    g.dense = 0;
    // At least 4 buckets: the 3 cells of a row must land in 3 distinct buckets.
    g.table_bits = std::clamp<uint32_t>(bits_for(2ull * n - 1), 2, 31);
    g.bucket_count = 1u << g.table_bits;
  }
  info->cell = cell;
  for (int k = 0; k < 3; ++k) info->dims[k] = g.dims[k];
  info->dense = g.dense != 0;
  info->buckets = g.bucket_count;
  return g;
}

}  // namespace

kernels::BoundsSummary summarize_bounds(const Executor& exec, kernels::AabbSoA boxes, uint32_t n,
                                        Buffer<kernels::BoundsSummary>& partials) {
  constexpr uint32_t kGrain = GridBroadPhase::kKeyGrain;
  const uint32_t chunks = chunk_count(n, kGrain);
  kernels::BoundsSummary* partial = scratch(partials, chunks);
  exec.for_each_chunk(n, kGrain, [&](uint32_t b, uint32_t e, uint32_t c) {
    partial[c] = kernels::reduce_bounds(boxes, {b, e});
  });
  kernels::BoundsSummary sum = kernels::empty_bounds_summary();
  for (uint32_t c = 0; c < chunks; ++c) sum = kernels::combine(sum, partial[c]);
  return sum;
}

Status GridBroadPhase::find_pairs(const Executor& exec, kernels::AabbSoA boxes,
                                  kernels::PairFilter filter, uint32_t n,
                                  Buffer<kernels::Pair>* out, const kernels::BoundsSummary* summary) {
  out->clear();
  last_n_ = n;
  if (n < 2) return Status();

  // 1. Union of the boxes and largest edge.
  const kernels::BoundsSummary sum = summary ? *summary : summarize_bounds(exec, boxes, n, partial_bounds_);
  const kernels::GridParams g = choose_grid(sum, n, &info_);

  // 2. Keys, sorted on the bucket bits.
  uint64_t* keys = scratch(keys_, n);
  exec.for_each_chunk(n, kKeyGrain, [&](uint32_t b, uint32_t e, uint32_t) {
    kernels::grid_keys(g, boxes, keys, {b, e});
  });
  sorter_.sort(exec, keys, n, 32, 32 + bits_for(g.bucket_count - 1));

  // 3. Gather into sorted order.
  const bool filtered = filter.layer != nullptr;
  kernels::GridSorted sorted{scratch(sorted_box_, n),
                             scratch(cell_, n),
                             filtered ? scratch(layer_, n) : nullptr,
                             filtered ? scratch(mask_, n) : nullptr,
                             filtered ? scratch(static_, n) : nullptr};
  exec.for_each_chunk(n, kKeyGrain, [&](uint32_t b, uint32_t e, uint32_t) {
    kernels::grid_gather(g, keys, boxes, filter, sorted, {b, e});
  });

  // 4. Bucket ranges.
  uint32_t* starts = scratch(bucket_start_, static_cast<size_t>(g.bucket_count) + 1);
  exec.for_each_chunk(n, kKeyGrain, [&](uint32_t b, uint32_t e, uint32_t) {
    kernels::segment_starts(keys, n, 32, g.bucket_count, starts, {b, e});
  });

  // 5. Pairs: count, scan, write.
  const kernels::GridView view{g,
                               sorted.box,
                               sorted.cell,
                               sorted.layer,
                               sorted.mask,
                               sorted.is_static,
                               starts};
  return chunked_output<kernels::Pair>(
      exec, n, kPairGrain, chunk_pairs_, chunk_offsets_, kMaxPairs, "grid broad phase pairs",
      [&](uint32_t b, uint32_t e, kernels::Pair* dst, uint64_t capacity) {
        return kernels::grid_find_pairs(view, dst, capacity, {b, e});
      },
      out);
}

namespace {

template <bool kFiltered, class Emit>
void brute_force_row(kernels::AabbSoA x, kernels::PairFilter f, uint32_t n, uint32_t i, Emit&& emit) {
  for (uint32_t j = i + 1; j < n; ++j) {
    if (x.min_x[i] <= x.max_x[j] && x.min_x[j] <= x.max_x[i] && x.min_y[i] <= x.max_y[j] &&
        x.min_y[j] <= x.max_y[i] && x.min_z[i] <= x.max_z[j] && x.min_z[j] <= x.max_z[i]) {
      if constexpr (kFiltered) {
        if ((f.layer[i] & f.mask[j]) == 0 || (f.layer[j] & f.mask[i]) == 0) continue;
        if (f.is_static[i] && f.is_static[j]) continue;
      }
      emit(i, j);
    }
  }
}

}  // namespace

Status BruteForceBroadPhase::find_pairs(const Executor& exec, kernels::AabbSoA boxes,
                                        kernels::PairFilter filter, uint32_t n,
                                        Buffer<kernels::Pair>* out) {
  out->clear();
  if (n < 2) return Status();
  constexpr uint32_t kGrain = 64;
  auto rows = [&](uint32_t b, uint32_t e, auto&& emit) {
    for (uint32_t i = b; i < e; ++i) {
      if (filter.layer) brute_force_row<true>(boxes, filter, n, i, emit);
      else brute_force_row<false>(boxes, filter, n, i, emit);
    }
  };
  return chunked_output<kernels::Pair>(
      exec, n, kGrain, chunk_pairs_, chunk_offsets_, kMaxPairs, "brute-force broad phase pairs",
      [&](uint32_t b, uint32_t e, kernels::Pair* dst, uint64_t capacity) {
        uint64_t k = 0;
        rows(b, e, [&](uint32_t i, uint32_t j) {
          if (k < capacity) dst[k] = kernels::Pair{i, j};
          ++k;
        });
        return k;
      },
      out);
}

}  // namespace impact::host
