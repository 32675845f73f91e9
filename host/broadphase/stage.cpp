#include "host/broadphase/stage.h"

#include <algorithm>
#include <cmath>

namespace impact::host {

BroadPhaseKind choose_broad_phase(const uint64_t* level_counts, uint64_t n, const double extent[3],
                                  double top_edge) {
  uint64_t hashed = 0;
  uint32_t crowded = 0;
  double edge = top_edge;
  for (uint32_t l = 0; l < kernels::kGridMaxLevels; ++l, edge *= 0.25) {
    if (level_counts[l] == 0) continue;
    if (level_counts[l] * kAutoLevelShare >= n) ++crowded;
    // Cells of the level's grid with its cell coarsened 2x (what the grid tries
    // before it hashes); a zero edge (last level) behaves like a point set.
    const double cell = 2.0 * std::max(edge, 1e-30);
    double cells = 1.0;
    for (int k = 0; k < 3; ++k) cells *= std::min(std::floor(extent[k] / cell) + 1.0, static_cast<double>(kernels::kGridMaxDim));
    if (cells > grid_dense_limit(level_counts[l])) hashed += level_counts[l];
  }
  // hashed == n: every populated level hashes (a few huge boxes that widen the
  // extent sit in a level of their own that does not, so they do not count).
  const bool spread = crowded >= kAutoLevels;
  return spread || hashed == n ? BroadPhaseKind::kLbvh : BroadPhaseKind::kGrid;
}

void BroadPhaseStage::set_kind(BroadPhaseKind kind) {
  kind_ = kind;
  built_ = false;
  sap.reset();
}

BroadPhaseKind BroadPhaseStage::choose(const Executor& exec, kernels::AabbSoA boxes, uint32_t n,
                                       const kernels::BoundsSummary& sum) {
  if (n < 2 || !(sum.max_edge > 0.0f)) return BroadPhaseKind::kGrid;
  constexpr uint32_t L = kernels::kGridMaxLevels;
  constexpr uint32_t kGrain = GridBroadPhase::kKeyGrain;
  const uint32_t chunks = chunk_count(n, kGrain);
  uint8_t* level = scratch(level_, n);
  uint32_t* counts = scratch(level_counts_, static_cast<size_t>(chunks) * L);
  exec.for_each_chunk(n, kGrain, [&](uint32_t b, uint32_t e, uint32_t c) {
    kernels::grid_levels(boxes, sum.max_edge, level, counts + static_cast<size_t>(c) * L, {b, e});
  });
  uint64_t total[L] = {};
  for (uint32_t c = 0; c < chunks; ++c)
    for (uint32_t l = 0; l < L; ++l) total[l] += counts[static_cast<size_t>(c) * L + l];
  // The extent the grid itself would span (grid_extent: far outliers do not widen
  // it), so one far body cannot make a dense scene look sparse.
  double origin[3], extent[3];
  grid_extent(boxes, n, sum, static_cast<double>(sum.max_edge), origin, extent);
  return choose_broad_phase(total, n, extent, sum.max_edge);
}

Status BroadPhaseStage::build(const Executor& exec, kernels::AabbSoA boxes, kernels::PairFilter filter,
                              uint32_t n, const kernels::BoundsSummary* summary) {
  built_ = false;
  n_ = n;
  keep_single(boxes, filter, n);
  kernels::BoundsSummary sum{};
  const bool need_summary = kind_ == BroadPhaseKind::kAuto || kind_ == BroadPhaseKind::kGrid ||
                            kind_ == BroadPhaseKind::kLbvh;
  if (need_summary && n > 0) {
    sum = summary ? *summary : summarize_bounds(exec, boxes, n, partial_bounds_);
    summary = &sum;
  }
  active_ = kind_ == BroadPhaseKind::kAuto ? choose(exec, boxes, n, sum) : kind_;
  switch (active_) {
    case BroadPhaseKind::kGrid: grid.build(exec, boxes, filter, n, summary); break;
    case BroadPhaseKind::kLbvh:
      if (Status s = lbvh.build(exec, boxes, filter, n, summary); !s.ok()) return s;
      break;
    case BroadPhaseKind::kSweepAndPrune: sap.build(exec, boxes, filter, n); break;
    case BroadPhaseKind::kBruteForce: brute_force.build(exec, boxes, filter, n); break;
    default: return Status(StatusCode::kInvalidArgument, "broad phase: unknown BroadPhaseKind");
  }
  built_ = true;
  return Status();
}

Status BroadPhaseStage::update(const Executor& exec, kernels::AabbSoA boxes, kernels::PairFilter filter,
                               uint32_t n, const kernels::BoundsSummary* summary) {
  if (!built_ || n != n_) return build(exec, boxes, filter, n, summary);
  keep_single(boxes, filter, n);
  switch (active_) {
    case BroadPhaseKind::kLbvh: {
      if (lbvh.options().update == LbvhUpdate::kRebuild) return build(exec, boxes, filter, n, summary);
      built_ = false;
      if (Status s = lbvh.update(exec, boxes, filter, n, summary); !s.ok()) return s;
      built_ = true;
      return Status();
    }
    case BroadPhaseKind::kSweepAndPrune: sap.update(exec, boxes, filter, n); return Status();
    default: return build(exec, boxes, filter, n, summary);
  }
}

Status BroadPhaseStage::pairs(const Executor& exec, Buffer<kernels::Pair>* out) {
  if (!built_) {
    out->clear();
    return Status();
  }
  switch (active_) {
    case BroadPhaseKind::kGrid: return grid.pairs(exec, out);
    case BroadPhaseKind::kLbvh: return lbvh.pairs(exec, out);
    case BroadPhaseKind::kSweepAndPrune: return sap.pairs(exec, out);
    case BroadPhaseKind::kBruteForce: return brute_force.pairs(exec, out);
    default: break;
  }
  out->clear();
  return Status(StatusCode::kInvalidArgument, "broad phase: unknown BroadPhaseKind");
}

Status BroadPhaseStage::find_pairs(const Executor& exec, kernels::AabbSoA boxes, kernels::PairFilter filter,
                                   uint32_t n, Buffer<kernels::Pair>* out,
                                   const kernels::BoundsSummary* summary) {
  if (Status s = update(exec, boxes, filter, n, summary); !s.ok()) {
    out->clear();
    return s;
  }
  return pairs(exec, out);
}

bool BroadPhaseStage::spatial_order(const Executor& exec, uint32_t* order) const {
  if (!built_ || n_ < 2) return false;
  constexpr uint32_t kGrain = GridBroadPhase::kKeyGrain;
  if (active_ == BroadPhaseKind::kGrid && grid.sorted_count() == n_) {
    const kernels::SortedBox* s = grid.sorted();
    exec.for_each_chunk(n_, kGrain, [&](uint32_t b, uint32_t e, uint32_t) {
      for (uint32_t i = b; i < e; ++i) order[i] = s[i].index;
    });
    return true;
  }
  if (active_ == BroadPhaseKind::kLbvh && lbvh.size() == n_) {
    const kernels::SortedBox* leaves = lbvh.view().leaves;
    exec.for_each_chunk(n_, kGrain, [&](uint32_t b, uint32_t e, uint32_t) {
      for (uint32_t i = b; i < e; ++i) order[i] = leaves[i].index;
    });
    return true;
  }
  return false;
}

void BroadPhaseStage::keep_single(kernels::AabbSoA boxes, kernels::PairFilter filter, uint32_t n) {
  if (n != 1) return;
  const float v[6] = {boxes.min_x[0], boxes.min_y[0], boxes.min_z[0], boxes.max_x[0], boxes.max_y[0], boxes.max_z[0]};
  for (int k = 0; k < 6; ++k) single_box_[k] = v[k];
  single_filtered_ = filter.layer != nullptr;
  single_layer_ = single_filtered_ ? filter.layer[0] : 0u;
}

Status BroadPhaseStage::query(const Executor& exec, const QueryBatch& q, std::vector<uint32_t>* offsets,
                              std::vector<uint32_t>* hits) {
  if (!built_)
    return Status(StatusCode::kInvalidArgument,
                  "no broad-phase structure built yet (call build, update or find_pairs first)");
  const bool single = n_ == 1 && (active_ == BroadPhaseKind::kGrid || active_ == BroadPhaseKind::kSweepAndPrune);
  if (single) {
    const float* b = single_box_;
    return query_.query(exec, kernels::AabbSoA{b, b + 1, b + 2, b + 3, b + 4, b + 5},
                        single_filtered_ ? &single_layer_ : nullptr, 1, q, offsets, hits);
  }
  switch (active_) {
    case BroadPhaseKind::kGrid: return query_.query(exec, grid, q, offsets, hits);
    case BroadPhaseKind::kLbvh: return query_.query(exec, lbvh, q, offsets, hits);
    case BroadPhaseKind::kSweepAndPrune: return query_.query(exec, sap, q, offsets, hits);
    case BroadPhaseKind::kBruteForce: return query_.query(exec, brute_force, q, offsets, hits);
    default: break;
  }
  return Status(StatusCode::kInvalidArgument, "broad-phase query: unknown BroadPhaseKind");
}

}  // namespace impact::host
