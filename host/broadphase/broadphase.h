// Host drivers of the broad-phase kernels. Both structures share one contract:
// given n boxes (SoA) and an optional filter, replace *out with every pair of
// overlapping boxes (a < b) that passes the filter, in a deterministic order.
#pragma once

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "host/buffer.h"
#include "host/parallel.h"
#include "host/radix_sort.h"
#include "impact/status.h"
#include "kernels/broadphase/bounds.h"
#include "kernels/broadphase/grid.h"

namespace impact::host {

/// What the last grid build chose (for benchmarks and diagnostics).
struct GridInfo {
  double cell = 0;
  uint32_t dims[3] = {0, 0, 0};
  bool dense = false;
  uint32_t buckets = 0;
};

/// Most cells a grid over n boxes may have and still use dense (row-major, unhashed)
/// buckets; a scene needing more, even with cells coarsened 2x, is hashed.
inline double grid_dense_limit(uint64_t n) { return std::max(4.0 * static_cast<double>(n), 4096.0); }

/// The range a grid over `boxes` spans: per axis an origin and an extent holding the
/// boxes' min corners. Normally the summary's bounds. When `cell` (the grid's cell
/// before any coarsening; 0 for point sets) would need more than kGridMaxDim - 2
/// cells across the summary (a few far outliers would then force cells so coarse
/// that the crowd shares a handful of them), the range is the "core" instead: per
/// axis, quantiles 1/16 and 15/16 of the min corners of up to 4096 boxes at fixed
/// indices (i * n / 4096) bound a window widened by their spread (at least 64
/// cells) on each side, and the core is the exact range of the min corners inside
/// that window. Boxes outside the core are clamped into its boundary cells (still
/// exact: clamping keeps two cells at most one apart), so outliers cost their
/// boundary cells' neighbours, not the crowd. Deterministic (fixed sample, exact
/// min/max); cost O(4096 log 4096 + n) when the core is used, nothing otherwise.
/// Fewer than 1/16 of the sampled boxes far away cannot widen the core.
void grid_extent(kernels::AabbSoA boxes, uint32_t n, const kernels::BoundsSummary& s, double cell,
                 double origin[3], double extent[3]);

class GridBroadPhase {
 public:
  GridBroadPhase();
  ~GridBroadPhase();
  GridBroadPhase(GridBroadPhase&&) noexcept;
  GridBroadPhase& operator=(GridBroadPhase&&) noexcept;

  /// Builds the grid over boxes[0, n) (copies them into sorted order; the spans need
  /// not outlive the call). `summary`, when given, is the boxes' union and largest
  /// edge (the caller computed it already); otherwise it is computed here. Boxes
  /// whose sizes span orders of magnitude switch to hierarchical levels
  /// (kernels/broadphase/grid.h).
  void build(const Executor& exec, kernels::AabbSoA boxes, kernels::PairFilter filter, uint32_t n,
             const kernels::BoundsSummary* summary = nullptr);
  /// Every overlapping pair of the last build, in the documented order.
  Status pairs(const Executor& exec, Buffer<kernels::Pair>* out);
  /// build + pairs.
  Status find_pairs(const Executor& exec, kernels::AabbSoA boxes, kernels::PairFilter filter,
                    uint32_t n, Buffer<kernels::Pair>* out,
                    const kernels::BoundsSummary* summary = nullptr);
  const GridInfo& info() const { return info_; }
  /// Boxes of the last build.
  uint32_t size() const { return last_n_; }
  /// Levels the last build used (1 = a single grid).
  uint32_t levels_used() const { return levels_used_; }
  /// The grids of the last build (n >= 2): one for a single grid, else one per
  /// level, coarse to fine (kernels::kGridMaxLevels slots); null for an empty
  /// level. Their SortedBox::index fields are the caller's box indices.
  bool hierarchical() const { return hierarchical_; }
  const kernels::GridView* level_view(uint32_t level) const;
  uint32_t level_size(uint32_t level) const;
  /// The boxes of the last build in sorted (spatial) order, level by level when
  /// hierarchical; null if it had < 2 boxes.
  const kernels::SortedBox* sorted() const { return last_n_ >= 2 ? sorted_box_.data() : nullptr; }
  uint32_t sorted_count() const { return last_n_ >= 2 ? last_n_ : 0; }
  /// Hierarchical levels when at least 1/kLevelFraction of the boxes are 16x or
  /// more smaller than the largest (0 disables levels).
  void set_level_fraction(uint32_t f) { level_fraction_ = f; }

  static constexpr uint32_t kKeyGrain = 1u << 14;   // boxes per chunk in streaming passes
  static constexpr uint32_t kPairGrain = 1u << 11;  // query slots per chunk in the pair pass
  static constexpr uint32_t kLevelFraction = 8;
  static constexpr uint32_t kBlockGrain = 4;  // blocks per chunk in the block sort

 private:
  struct Levels;
  // Builds one sorted grid over boxes (reported as original_index[i] when given).
  void build_grid(const Executor& exec, kernels::AabbSoA boxes, kernels::PairFilter filter,
                  const uint32_t* original_index, uint32_t n, const kernels::BoundsSummary& sum);
  Status self_pairs(const Executor& exec, Buffer<kernels::Pair>* out);
  void build_levels(const Executor& exec, kernels::AabbSoA boxes, kernels::PairFilter filter, uint32_t n);
  Status levels_pairs(const Executor& exec, Buffer<kernels::Pair>* out);

  Buffer<uint32_t> bucket_;         // per box, input order
  Buffer<uint32_t> block_offsets_;  // chunks x blocks: counts, then scatter offsets
  Buffer<uint32_t> block_start_;    // blocks + 1
  Buffer<kernels::SortedBox> sorted_box_;
  Buffer<kernels::SortedBox> packed_box_;  // partitioned by block
  Buffer<kernels::FilterRecord> packed_filter_;
  uint32_t last_n_ = 0;
  uint32_t built_n_ = 0;
  Buffer<uint64_t> cell_;
  Buffer<uint32_t> layer_, mask_;
  Buffer<uint8_t> static_;
  Buffer<uint32_t> bucket_start_;
  Buffer<uint64_t> chunk_offsets_;
  std::vector<Buffer<kernels::Pair>> chunk_pairs_;
  Buffer<kernels::BoundsSummary> partial_bounds_;
  kernels::GridView view_{};
  GridInfo info_;
  uint32_t levels_used_ = 1;
  bool hierarchical_ = false;
  uint32_t level_fraction_ = kLevelFraction;
  std::unique_ptr<Levels> levels_;
};

/// All pairs, O(n^2): the reference oracle. build() copies the boxes.
class BruteForceBroadPhase {
 public:
  void build(const Executor& exec, kernels::AabbSoA boxes, kernels::PairFilter filter, uint32_t n);
  Status pairs(const Executor& exec, Buffer<kernels::Pair>* out);
  Status find_pairs(const Executor& exec, kernels::AabbSoA boxes, kernels::PairFilter filter,
                    uint32_t n, Buffer<kernels::Pair>* out);
  uint32_t size() const { return n_; }
  /// The copies of the last build (filter all null when built unfiltered).
  kernels::AabbSoA boxes() const;
  kernels::PairFilter filter() const;

 private:
  uint32_t n_ = 0;
  bool filtered_ = false;
  Buffer<float> box_[6];
  Buffer<uint32_t> layer_, mask_;
  Buffer<uint8_t> static_;
  Buffer<uint64_t> chunk_offsets_;
  std::vector<Buffer<kernels::Pair>> chunk_pairs_;
};

/// Union box and largest edge of n boxes: one partial per chunk, combined in chunk order.
kernels::BoundsSummary summarize_bounds(const Executor& exec, kernels::AabbSoA boxes, uint32_t n,
                                        Buffer<kernels::BoundsSummary>& partials);

}  // namespace impact::host
