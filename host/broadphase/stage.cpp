#include "host/broadphase/stage.h"

namespace impact::host {

BroadPhaseKind choose_broad_phase(const uint64_t* level_counts, uint64_t n) {
  uint32_t crowded = 0;
  for (uint32_t l = 0; l < kernels::kGridMaxLevels; ++l)
    if (level_counts[l] * kAutoLevelShare >= n && level_counts[l] > 0) ++crowded;
  return crowded >= kAutoLbvhLevels ? BroadPhaseKind::kLbvh : BroadPhaseKind::kGrid;
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
  return choose_broad_phase(total, n);
}

Status BroadPhaseStage::build(const Executor& exec, kernels::AabbSoA boxes, kernels::PairFilter filter,
                              uint32_t n, const kernels::BoundsSummary* summary) {
  built_ = false;
  n_ = n;
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

}  // namespace impact::host
