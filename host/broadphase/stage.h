// The broad-phase stage: one of the four structures (grid, LBVH, sweep-and-prune,
// brute force) behind one interface, plus the automatic choice between the grid and
// the LBVH. World's step and the public impact::BroadPhase both drive this class,
// so the step, the stand-alone stage, the queries and the benchmarks switch
// structure with one setting.
//
//   build(boxes)   from scratch (kAuto re-chooses the structure here)
//   update(boxes)  coherent frame: same n and structure -> LBVH refit per policy,
//                  SAP insertion sort, grid / brute force rebuild; else build
//   pairs(out)     every overlapping pair of the structure as last built/updated
//
// Every structure copies what it needs, so the boxes need not outlive the call.
#pragma once

#include <cstdint>

#include "host/broadphase/broadphase.h"
#include "host/broadphase/lbvh.h"
#include "host/broadphase/query.h"
#include "host/broadphase/sap.h"
#include "host/buffer.h"
#include "host/parallel.h"
#include "impact/status.h"
#include "impact/types.h"
#include "kernels/broadphase/bounds.h"
#include "kernels/broadphase/grid.h"

namespace impact::host {

/// The automatic choice (docs/broadphase.md, "Automatic choice"): the LBVH when the
/// boxes' sizes spread over at least kAutoLevels of the grid's size levels (4x
/// apart) with at least 1/kAutoLevelShare of the boxes in each, or when the grid
/// would have to hash the cells of every populated level (a sparse world: more cells
/// than grid_dense_limit even with 2x coarser cells; uniform sparse worlds,
/// clustered worlds); else the grid. Both are estimated per level l
/// (kernels::grid_levels; level_counts has kernels::kGridMaxLevels entries) from
/// the scene extent and the level's largest possible edge, top_edge / 4^l.
/// Measured basis: docs/broadphase.md (bench BM_AutoChoice).
BroadPhaseKind choose_broad_phase(const uint64_t* level_counts, uint64_t n, const double extent[3],
                                  double top_edge);
inline constexpr uint32_t kAutoLevels = 2;
inline constexpr uint32_t kAutoLevelShare = 10;

class BroadPhaseStage {
 public:
  explicit BroadPhaseStage(BroadPhaseKind kind = BroadPhaseKind::kGrid) : kind_(kind) {}

  /// Changes the structure; the next update() builds from scratch.
  void set_kind(BroadPhaseKind kind);
  BroadPhaseKind kind() const { return kind_; }
  /// The structure in use: kind() unless that is kAuto (then the last build's
  /// choice; kGrid before any build).
  BroadPhaseKind active() const { return active_; }

  /// A change of update policy or fat margin also forgets coherence (a kPairCache
  /// tree holds fat boxes).
  void set_lbvh_options(const LbvhOptions& o) {
    if (o.update != lbvh.options().update || o.fat_margin != lbvh.options().fat_margin) built_ = false;
    lbvh.set_options(o);
  }

  /// `summary`, when given, is the boxes' union and largest edge.
  Status build(const Executor& exec, kernels::AabbSoA boxes, kernels::PairFilter filter, uint32_t n,
               const kernels::BoundsSummary* summary = nullptr);
  Status update(const Executor& exec, kernels::AabbSoA boxes, kernels::PairFilter filter, uint32_t n,
                const kernels::BoundsSummary* summary = nullptr);
  Status pairs(const Executor& exec, Buffer<kernels::Pair>* out);
  /// update + pairs.
  Status find_pairs(const Executor& exec, kernels::AabbSoA boxes, kernels::PairFilter filter, uint32_t n,
                    Buffer<kernels::Pair>* out, const kernels::BoundsSummary* summary = nullptr);

  /// True once build/update has run (since the last set_kind / invalidate).
  bool built() const { return built_; }
  /// Boxes of the last build/update.
  uint32_t size() const { return n_; }
  /// Forgets coherence (the box indices changed meaning): the next update builds.
  void invalidate() { built_ = false; }

  /// Writes the last build's boxes in the structure's spatial order (grid cells or
  /// Morton order) to order[0, n) and returns true; false when the structure has
  /// none (sweep-and-prune, brute force, fewer than 2 boxes).
  bool spatial_order(const Executor& exec, uint32_t* order) const;

  /// Queries (host/broadphase/query.h) of the structure as last built/updated, by
  /// the active structure. kInvalidArgument when nothing is built.
  Status query(const Executor& exec, const QueryBatch& q, std::vector<uint32_t>* offsets,
               std::vector<uint32_t>* hits);

  GridBroadPhase grid;
  LbvhBroadPhase lbvh;
  SapBroadPhase sap;
  BruteForceBroadPhase brute_force;

 private:
  BroadPhaseKind choose(const Executor& exec, kernels::AabbSoA boxes, uint32_t n,
                        const kernels::BoundsSummary& sum);

  BroadPhaseKind kind_;
  BroadPhaseKind active_ = BroadPhaseKind::kGrid;
  bool built_ = false;
  uint32_t n_ = 0;
  // The grid and sweep-and-prune keep no copy of a single box: queries need it.
  void keep_single(kernels::AabbSoA boxes, kernels::PairFilter filter, uint32_t n);
  BroadPhaseQuery query_;
  float single_box_[6] = {};
  uint32_t single_layer_ = 0;
  bool single_filtered_ = false;

  Buffer<kernels::BoundsSummary> partial_bounds_;
  Buffer<uint8_t> level_;
  Buffer<uint32_t> level_counts_;
};

}  // namespace impact::host
