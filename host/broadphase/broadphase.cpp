#include "host/broadphase/broadphase.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "host/scan.h"
#include "kernels/broadphase/bounds.h"
#include "kernels/common/permute.h"

namespace impact::host {
namespace {

constexpr uint64_t kMaxPairs = 0xffffffffull;  // kernels index pairs with uint32

kernels::GridParams choose_grid(kernels::AabbSoA boxes, const kernels::BoundsSummary& s, uint32_t n,
                                GridInfo* info) {
  kernels::GridParams g{};
  double extent[3];
  double max_extent = 0;
  grid_extent(boxes, n, s, static_cast<double>(s.max_edge) * (1.0 + 0x1p-20), g.origin, extent);
  for (int k = 0; k < 3; ++k) max_extent = std::max(max_extent, extent[k]);
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
  const double dense_limit = grid_dense_limit(n);
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

void grid_extent(kernels::AabbSoA boxes, uint32_t n, const kernels::BoundsSummary& s, double cell,
                 double origin[3], double extent[3]) {
  double max_extent = 0;
  for (int k = 0; k < 3; ++k) {
    origin[k] = s.lo[k];
    extent[k] = static_cast<double>(s.hi[k]) - static_cast<double>(s.lo[k]);
    max_extent = std::max(max_extent, extent[k]);
  }
  const double limit = static_cast<double>(kernels::kGridMaxDim - 2);
  // Point sets (cell 0) take about one cell per box (choose_grid): the core is then
  // worth finding whenever the extent is not tiny against the crowd's spread, which
  // only the sample can tell; use it for them whenever there are enough boxes.
  const bool capped = cell > 0.0 ? max_extent > limit * cell : n >= 64;
  if (n < 2 || !capped) return;
  constexpr uint32_t kSample = 4096;
  const uint32_t m = std::min(n, kSample);
  std::vector<float> v(m);
  const float* mins[3] = {boxes.min_x, boxes.min_y, boxes.min_z};
  for (int k = 0; k < 3; ++k) {
    for (uint32_t j = 0; j < m; ++j) v[j] = mins[k][static_cast<uint64_t>(j) * n / m];
    // Order statistics of a fixed sample: the values are unique whatever the
    // selection algorithm does with ties.
    const uint32_t r = m / 16;
    std::nth_element(v.begin(), v.begin() + r, v.end());
    const double q_lo = v[r];
    std::nth_element(v.begin(), v.begin() + (m - 1 - r), v.end());
    const double q_hi = v[m - 1 - r];
    const double w = std::max(q_hi - q_lo, 64.0 * cell);
    const double a = q_lo - w, b = q_hi + w;
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    const float* x = mins[k];
    for (uint32_t i = 0; i < n; ++i) {
      const double u = x[i];
      if (u >= a && u <= b) {
        lo = std::min(lo, u);
        hi = std::max(hi, u);
      }
    }
    // The quantiles are sampled min corners, so the window holds at least one box.
    origin[k] = lo;
    extent[k] = hi - lo;
  }
}

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

// Per-level state of the hierarchical grid.
struct GridBroadPhase::Levels {
  static constexpr uint32_t L = kernels::kGridMaxLevels;
  Buffer<uint8_t> level;            // per box
  Buffer<uint32_t> chunk_counts;    // chunks x L, then scatter offsets
  Buffer<uint32_t> order;           // original indices, level by level
  uint32_t start[L + 1] = {};
  GridBroadPhase grid[L];
  Buffer<float> box[L][6];
  Buffer<uint32_t> layer[L], mask[L];
  Buffer<uint8_t> is_static[L];
  Buffer<kernels::Pair> pairs[L];       // within level l
  Buffer<kernels::Pair> cross[L][L];    // level l queried against coarser level m
  std::vector<Buffer<kernels::Pair>> chunk_pairs;
  Buffer<uint64_t> chunk_offsets;
};

GridBroadPhase::GridBroadPhase() = default;
GridBroadPhase::~GridBroadPhase() = default;
GridBroadPhase::GridBroadPhase(GridBroadPhase&&) noexcept = default;
GridBroadPhase& GridBroadPhase::operator=(GridBroadPhase&&) noexcept = default;

void GridBroadPhase::build_grid(const Executor& exec, kernels::AabbSoA boxes, kernels::PairFilter filter,
                                const uint32_t* original_index, uint32_t n,
                                const kernels::BoundsSummary& sum) {
  built_n_ = n;
  const kernels::GridParams g = choose_grid(boxes, sum, n, &info_);

  // Sort by bucket (kernels/broadphase/grid.h): count per block, scan, partition
  // by block, then a counting sort inside each block that also fills the bucket ranges.
  const bool filtered = filter.layer != nullptr;
  const kernels::GridBlocks blocks = kernels::grid_blocks(g);
  const uint32_t chunks = chunk_count(n, kKeyGrain);
  uint32_t* bucket = scratch(bucket_, n);
  uint32_t* offsets = scratch(block_offsets_, static_cast<size_t>(chunks) * blocks.count);
  exec.for_each_chunk(n, kKeyGrain, [&](uint32_t b, uint32_t e, uint32_t c) {
    kernels::grid_bucket_count(g, blocks, boxes, bucket, offsets + static_cast<size_t>(c) * blocks.count,
                               {b, e});
  });
  uint32_t* block_start = scratch(block_start_, static_cast<size_t>(blocks.count) + 1);
  uint32_t running = 0;
  for (uint32_t k = 0; k < blocks.count; ++k) {
    block_start[k] = running;
    for (uint32_t c = 0; c < chunks; ++c) {
      uint32_t& slot = offsets[static_cast<size_t>(c) * blocks.count + k];
      const uint32_t cnt = slot;
      slot = running;
      running += cnt;
    }
  }
  block_start[blocks.count] = running;
  kernels::SortedBox* packed = scratch(packed_box_, n);
  kernels::FilterRecord* packed_filter = filtered ? scratch(packed_filter_, n) : nullptr;
  exec.for_each_chunk(n, kKeyGrain, [&](uint32_t b, uint32_t e, uint32_t c) {
    kernels::grid_scatter_blocks(blocks, boxes, filter, original_index, bucket,
                                 offsets + static_cast<size_t>(c) * blocks.count, packed, packed_filter,
                                 {b, e});
  });
  kernels::GridSorted sorted{scratch(sorted_box_, n), g.dense ? nullptr : scratch(cell_, n),
                             filtered ? scratch(layer_, n) : nullptr, filtered ? scratch(mask_, n) : nullptr,
                             filtered ? scratch(static_, n) : nullptr};
  uint32_t* starts = scratch(bucket_start_, static_cast<size_t>(g.bucket_count) + 1);
  exec.for_each_chunk(blocks.count, kBlockGrain, [&](uint32_t b, uint32_t e, uint32_t) {
    kernels::grid_sort_blocks(g, blocks, block_start, packed, packed_filter, sorted, starts, {b, e});
  });
  view_ = kernels::GridView{g, sorted.box, sorted.cell, sorted.layer, sorted.mask, sorted.is_static, starts};
}

Status GridBroadPhase::self_pairs(const Executor& exec, Buffer<kernels::Pair>* out) {
  const kernels::GridView view = view_;
  return chunked_output<kernels::Pair>(
      exec, built_n_, kPairGrain, chunk_pairs_, chunk_offsets_, kMaxPairs, "grid broad phase pairs",
      [&](uint32_t b, uint32_t e, kernels::Pair* dst, uint64_t capacity) {
        return kernels::grid_find_pairs(view, dst, capacity, {b, e});
      },
      out);
}

void GridBroadPhase::build(const Executor& exec, kernels::AabbSoA boxes, kernels::PairFilter filter,
                           uint32_t n, const kernels::BoundsSummary* summary) {
  last_n_ = n;
  levels_used_ = 1;
  hierarchical_ = false;
  built_n_ = 0;
  if (n < 2) return;
  const kernels::BoundsSummary sum = summary ? *summary : summarize_bounds(exec, boxes, n, partial_bounds_);

  // Levels need boxes 16x or more smaller than the largest (grid_levels' level 2
  // and finer, the same float bound); when the summary's smallest box edge rules
  // that out, skip counting the levels.
  const float fine_bound = sum.max_edge * 0.25f * 0.25f;
  if (level_fraction_ > 0 && sum.max_edge > 0.0f && !(sum.min_edge > fine_bound)) {
    // Size spread: count boxes per level (one count per chunk, summed in order).
    if (!levels_) levels_ = std::make_unique<Levels>();
    Levels& lv = *levels_;
    constexpr uint32_t L = Levels::L;
    const uint32_t chunks = chunk_count(n, kKeyGrain);
    uint8_t* level = scratch(lv.level, n);
    uint32_t* counts = scratch(lv.chunk_counts, static_cast<size_t>(chunks) * L);
    exec.for_each_chunk(n, kKeyGrain, [&](uint32_t b, uint32_t e, uint32_t c) {
      kernels::grid_levels(boxes, sum.max_edge, level, counts + static_cast<size_t>(c) * L, {b, e});
    });
    uint64_t fine = 0;
    for (uint32_t c = 0; c < chunks; ++c)
      for (uint32_t l = 2; l < L; ++l) fine += counts[static_cast<size_t>(c) * L + l];
    if (fine * level_fraction_ >= n) {
      hierarchical_ = true;
      build_levels(exec, boxes, filter, n);
      return;
    }
  }
  build_grid(exec, boxes, filter, nullptr, n, sum);
}

Status GridBroadPhase::pairs(const Executor& exec, Buffer<kernels::Pair>* out) {
  if (last_n_ < 2) {
    out->clear();
    return Status();
  }
  // self_pairs sizes *out itself (chunked_output): no clear first, so a frame with as
  // many pairs as the last one zero-fills nothing before the copy overwrites it.
  if (!hierarchical_) return self_pairs(exec, out);
  out->clear();
  return levels_pairs(exec, out);
}

Status GridBroadPhase::find_pairs(const Executor& exec, kernels::AabbSoA boxes,
                                  kernels::PairFilter filter, uint32_t n,
                                  Buffer<kernels::Pair>* out, const kernels::BoundsSummary* summary) {
  build(exec, boxes, filter, n, summary);
  return pairs(exec, out);
}

const kernels::GridView* GridBroadPhase::level_view(uint32_t level) const {
  if (last_n_ < 2 || level >= kernels::kGridMaxLevels) return nullptr;
  if (!hierarchical_) return level == 0 ? &view_ : nullptr;
  const Levels& lv = *levels_;
  return lv.start[level + 1] > lv.start[level] ? &lv.grid[level].view_ : nullptr;
}

uint32_t GridBroadPhase::level_size(uint32_t level) const {
  if (last_n_ < 2 || level >= kernels::kGridMaxLevels) return 0;
  if (!hierarchical_) return level == 0 ? last_n_ : 0;
  return levels_->start[level + 1] - levels_->start[level];
}

void GridBroadPhase::build_levels(const Executor& exec, kernels::AabbSoA boxes, kernels::PairFilter filter,
                                  uint32_t n) {
  Levels& lv = *levels_;
  constexpr uint32_t L = Levels::L;
  const uint32_t chunks = chunk_count(n, kKeyGrain);
  uint32_t* counts = lv.chunk_counts.data();
  // Scatter offsets, level-major then chunk: a stable split by level.
  uint32_t running = 0;
  for (uint32_t l = 0; l < L; ++l) {
    lv.start[l] = running;
    for (uint32_t c = 0; c < chunks; ++c) {
      uint32_t& slot = counts[static_cast<size_t>(c) * L + l];
      const uint32_t k = slot;
      slot = running;
      running += k;
    }
  }
  lv.start[L] = running;
  uint32_t* order = scratch(lv.order, n);
  const uint8_t* level = lv.level.data();
  exec.for_each_chunk(n, kKeyGrain, [&](uint32_t b, uint32_t e, uint32_t c) {
    uint32_t* off = counts + static_cast<size_t>(c) * L;
    for (uint32_t i = b; i < e; ++i) order[off[level[i]]++] = i;
  });

  // One grid per non-empty level, over that level's boxes, reporting original indices.
  const bool filtered = filter.layer != nullptr;
  uint32_t used = 0;
  for (uint32_t l = 0; l < L; ++l) {
    const uint32_t nl = lv.start[l + 1] - lv.start[l];
    if (nl == 0) continue;
    ++used;
    const uint32_t* idx = order + lv.start[l];
    float* bx[6];
    for (int k = 0; k < 6; ++k) bx[k] = scratch(lv.box[l][k], nl);
    const float* src[6] = {boxes.min_x, boxes.min_y, boxes.min_z, boxes.max_x, boxes.max_y, boxes.max_z};
    uint32_t* layer = filtered ? scratch(lv.layer[l], nl) : nullptr;
    uint32_t* mask = filtered ? scratch(lv.mask[l], nl) : nullptr;
    uint8_t* is_static = filtered ? scratch(lv.is_static[l], nl) : nullptr;
    exec.for_each_chunk(nl, kKeyGrain, [&](uint32_t b, uint32_t e, uint32_t) {
      for (int k = 0; k < 6; ++k) kernels::gather(src[k], idx, bx[k], {b, e});
      if (filtered) {
        kernels::gather(filter.layer, idx, layer, {b, e});
        kernels::gather(filter.mask, idx, mask, {b, e});
        kernels::gather(filter.is_static, idx, is_static, {b, e});
      }
    });
    const kernels::PairFilter lf{layer, mask, is_static};
    const kernels::AabbSoA lb{bx[0], bx[1], bx[2], bx[3], bx[4], bx[5]};
    GridBroadPhase& grid = lv.grid[l];
    grid.level_fraction_ = 0;
    grid.build_grid(exec, lb, lf, idx, nl, summarize_bounds(exec, lb, nl, partial_bounds_));
    grid.last_n_ = nl;
  }
  levels_used_ = used;

  // The spatial order for World's re-sort: each level's sorted boxes in turn.
  kernels::SortedBox* all = scratch(sorted_box_, n);
  for (uint32_t l = 0; l < L; ++l) {
    const uint32_t nl = lv.start[l + 1] - lv.start[l];
    if (nl > 0) std::memcpy(all + lv.start[l], lv.grid[l].view_.box, sizeof(kernels::SortedBox) * nl);
  }
}

Status GridBroadPhase::levels_pairs(const Executor& exec, Buffer<kernels::Pair>* out) {
  Levels& lv = *levels_;
  constexpr uint32_t L = Levels::L;
  for (uint32_t l = 0; l < L; ++l) {
    lv.pairs[l].clear();
    if (lv.start[l + 1] == lv.start[l]) continue;
    if (Status st = lv.grid[l].self_pairs(exec, &lv.pairs[l]); !st.ok()) return st;
  }

  // Across levels: every box of level l queries each coarser level m < l.
  for (uint32_t l = 0; l < L; ++l) {
    const uint32_t nl = lv.start[l + 1] - lv.start[l];
    for (uint32_t m = 0; m < L; ++m) lv.cross[l][m].clear();
    if (nl == 0) continue;
    const kernels::GridView& fine = lv.grid[l].view_;
    const kernels::PairFilter qf{fine.layer, fine.mask, fine.is_static};
    for (uint32_t m = 0; m < l; ++m) {
      if (lv.start[m + 1] == lv.start[m]) continue;
      const kernels::GridView coarse = lv.grid[m].view_;
      Status st = chunked_output<kernels::Pair>(
          exec, nl, kPairGrain, lv.chunk_pairs, lv.chunk_offsets, kMaxPairs, "grid broad phase pairs",
          [&](uint32_t b, uint32_t e, kernels::Pair* dst, uint64_t capacity) {
            return kernels::grid_query_pairs(coarse, fine.box, qf, dst, capacity, {b, e});
          },
          &lv.cross[l][m]);
      if (!st.ok()) return st;
    }
  }

  // Concatenate: level pairs (coarse to fine), then cross pairs (l, m ascending).
  std::vector<const Buffer<kernels::Pair>*> parts;
  for (uint32_t l = 0; l < L; ++l) parts.push_back(&lv.pairs[l]);
  for (uint32_t l = 0; l < L; ++l)
    for (uint32_t m = 0; m < l; ++m) parts.push_back(&lv.cross[l][m]);
  uint64_t total = 0;
  for (const auto* p : parts) total += p->size();
  if (total > kMaxPairs)
    return Status(StatusCode::kCapacityExceeded, "grid broad phase pairs: " + std::to_string(total) +
                                                     " outputs exceed the limit of " + std::to_string(kMaxPairs));
  out->resize(total);
  uint64_t at = 0;
  for (const auto* p : parts) {
    if (!p->empty()) std::memcpy(out->data() + at, p->data(), sizeof(kernels::Pair) * p->size());
    at += p->size();
  }
  return Status();
}

namespace {

template <bool kFiltered, class Emit>
void brute_force_row(kernels::AabbSoA x, kernels::PairFilter f, uint32_t n, uint32_t i, Emit&& emit) {
  for (uint32_t j = i + 1; j < n; ++j) {
    if (x.min_x[i] <= x.max_x[j] && x.min_x[j] <= x.max_x[i] && x.min_y[i] <= x.max_y[j] &&
        x.min_y[j] <= x.max_y[i] && x.min_z[i] <= x.max_z[j] && x.min_z[j] <= x.max_z[i]) {
      if constexpr (kFiltered) {
        if (!kernels::pair_allowed(f.layer[i], f.mask[i], f.is_static[i], f.layer[j], f.mask[j], f.is_static[j]))
          continue;
      }
      emit(i, j);
    }
  }
}

}  // namespace

void BruteForceBroadPhase::build(const Executor& exec, kernels::AabbSoA boxes, kernels::PairFilter filter,
                                 uint32_t n) {
  n_ = n;
  filtered_ = filter.layer != nullptr;
  const float* src[6] = {boxes.min_x, boxes.min_y, boxes.min_z, boxes.max_x, boxes.max_y, boxes.max_z};
  float* dst[6];
  for (int k = 0; k < 6; ++k) dst[k] = scratch(box_[k], n);
  uint32_t* layer = filtered_ ? scratch(layer_, n) : nullptr;
  uint32_t* mask = filtered_ ? scratch(mask_, n) : nullptr;
  uint8_t* is_static = filtered_ ? scratch(static_, n) : nullptr;
  exec.for_each_chunk(n, GridBroadPhase::kKeyGrain, [&](uint32_t b, uint32_t e, uint32_t) {
    for (int k = 0; k < 6; ++k) std::memcpy(dst[k] + b, src[k] + b, sizeof(float) * (e - b));
    if (filtered_) {
      std::memcpy(layer + b, filter.layer + b, sizeof(uint32_t) * (e - b));
      std::memcpy(mask + b, filter.mask + b, sizeof(uint32_t) * (e - b));
      std::memcpy(is_static + b, filter.is_static + b, e - b);
    }
  });
}

kernels::AabbSoA BruteForceBroadPhase::boxes() const {
  return kernels::AabbSoA{box_[0].data(), box_[1].data(), box_[2].data(),
                          box_[3].data(), box_[4].data(), box_[5].data()};
}

kernels::PairFilter BruteForceBroadPhase::filter() const {
  return filtered_ ? kernels::PairFilter{layer_.data(), mask_.data(), static_.data()}
                   : kernels::PairFilter{nullptr, nullptr, nullptr};
}

Status BruteForceBroadPhase::find_pairs(const Executor& exec, kernels::AabbSoA boxes,
                                        kernels::PairFilter filter, uint32_t n,
                                        Buffer<kernels::Pair>* out) {
  build(exec, boxes, filter, n);
  return pairs(exec, out);
}

Status BruteForceBroadPhase::pairs(const Executor& exec, Buffer<kernels::Pair>* out) {
  out->clear();
  const uint32_t n = n_;
  if (n < 2) return Status();
  const kernels::AabbSoA boxes = this->boxes();
  const kernels::PairFilter filter = this->filter();
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
