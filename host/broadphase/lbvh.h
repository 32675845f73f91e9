// Host driver of the LBVH broad phase (kernels/bvh/): same contract as
// GridBroadPhase (host/broadphase/broadphase.h): given n boxes (SoA) and an optional
// filter, replace *out with every pair of overlapping boxes (a < b) that passes the
// filter, in an order that does not depend on the thread count.
//
// Passes of a rebuild: bounds summary -> Morton keys (30 or 63 bit) -> radix sort ->
// hierarchy and bounds in one bottom-up pass (lbvh_build_fused.h: Apetrei 2014 in
// leaf order per chunk, then the chunk seams; exact min/max unions) -> per-leaf self traversal into per-chunk
// buffers concatenated in chunk order (chunked_output). A refit reuses the sorted
// order and the hierarchy and only reruns the last two passes.
// See docs/lbvh.md for the rules (code width, refit policy) and the pair order.
#pragma once

#include <cstdint>
#include <vector>

#include "host/broadphase/broadphase.h"
#include "host/buffer.h"
#include "host/parallel.h"
#include "host/radix_sort.h"
#include "impact/status.h"
#include "impact/types.h"
#include "kernels/broadphase/bounds.h"
#include "kernels/broadphase/grid.h"
#include "kernels/bvh/lbvh_build.h"
#include "kernels/bvh/lbvh_build_fused.h"
#include "kernels/bvh/lbvh_traverse.h"
#include "kernels/bvh/morton.h"

namespace impact::host {

struct LbvhOptions {
  /// Morton code width: 0 = automatic (see choose_morton_bits), 30 or 63.
  uint32_t morton_bits = 0;
  /// What update() (and find_pairs()) does when n equals the tree's n: rebuild,
  /// refit, or refit until the refitted tree's SAH cost exceeds refit_sah_limit
  /// times the SAH right after the last build (kAuto: one extra pass over the
  /// 2n - 1 nodes per update). Either refit policy rebuilds after max_refits refits
  /// in a row. refit() always refits.
  LbvhUpdate update = LbvhUpdate::kRebuild;
  double refit_sah_limit = 1.5;
  uint32_t max_refits = 1000;
};

/// What the last call did (for benchmarks and diagnostics).
struct LbvhInfo {
  uint32_t leaves = 0;           ///< n of the current tree (0: none)
  uint32_t morton_bits = 0;      ///< 30 or 63
  bool rebuilt = false;          ///< the last call rebuilt (false: refitted)
  uint32_t refits_since_build = 0;
  double built_sah = 0.0;        ///< SAH right after the last build (update kAuto only)
  double last_sah = 0.0;         ///< SAH of the last refit (update kAuto only)
};

/// The 30/63-bit rule: 63-bit codes when n > 2^24, or when a 30-bit cell (largest
/// scene extent / 1024) is wider than 4 largest box edges (a sparse world whose boxes
/// would crowd into few cells and get index-ordered subtrees); else 30-bit (4 radix
/// passes instead of 8). Zero-extent scenes use 30-bit.
uint32_t choose_morton_bits(const kernels::BoundsSummary& s, uint32_t n);

class LbvhBroadPhase {
 public:
  explicit LbvhBroadPhase(LbvhOptions options = {}) : options_(options) {}

  /// Builds the tree over boxes[0, n) from scratch. `summary`, when given, is the
  /// boxes' union and largest edge. Fails (kInvalidArgument) when n >
  /// kernels::kLbvhMaxLeaves.
  Status build(const Executor& exec, kernels::AabbSoA boxes, kernels::PairFilter filter, uint32_t n,
               const kernels::BoundsSummary* summary = nullptr);
  /// Same n as the tree: rebuild or refit per options().update; otherwise build.
  Status update(const Executor& exec, kernels::AabbSoA boxes, kernels::PairFilter filter, uint32_t n,
                const kernels::BoundsSummary* summary = nullptr);
  /// Every overlapping pair of the current tree. Fails (kCapacityExceeded) when
  /// the pairs exceed 2^32 - 1.
  Status pairs(const Executor& exec, Buffer<kernels::Pair>* out);
  /// update + pairs.
  Status find_pairs(const Executor& exec, kernels::AabbSoA boxes, kernels::PairFilter filter,
                    uint32_t n, Buffer<kernels::Pair>* out,
                    const kernels::BoundsSummary* summary = nullptr);

  /// Keeps the last tree's sorted order and topology, recomputes all bounds from
  /// `boxes` (same n, same box indices, new positions) and writes the pairs. Pairs
  /// are exact for any motion; only traversal speed degrades as the tree ages.
  /// Fails (kInvalidArgument) when there is no tree or n differs from its n.
  Status refit(const Executor& exec, kernels::AabbSoA boxes, kernels::PairFilter filter, uint32_t n,
               Buffer<kernels::Pair>* out);

  /// SAH cost of the current tree: sum over its 2n - 1 nodes of area(node) / area(root)
  /// (kernels/bvh/lbvh_traverse.h); n when the root has zero area, 0 with no tree.
  /// Deterministic (chunk partials combined in chunk order).
  double sah_cost(const Executor& exec);

  const LbvhOptions& options() const { return options_; }
  void set_options(const LbvhOptions& o) { options_ = o; }
  const LbvhInfo& info() const { return info_; }

  /// Boxes of the current tree (0 when none).
  uint32_t size() const { return built_ ? info_.leaves : 0; }
  /// The current tree (valid when info().leaves >= 2; nodes only then).
  kernels::LbvhView view() const;
  const uint32_t* leaf_index() const { return leaf_index_.data(); }
  const uint32_t* internal_parent() const { return internal_parent_.data(); }
  const uint32_t* leaf_parent() const { return leaf_parent_.data(); }

  static constexpr uint32_t kKeyGrain = 1u << 14;   ///< boxes per chunk, streaming passes
  static constexpr uint32_t kNodeGrain = 1u << 14;  ///< nodes / leaves per chunk, build and refit
  static constexpr uint32_t kPairGrain = 1u << 11;  ///< query leaves per chunk, pair pass

 private:
  Status rebuild(const Executor& exec, kernels::AabbSoA boxes, kernels::PairFilter filter, uint32_t n,
                 const kernels::BoundsSummary* summary);
  Status traverse(const Executor& exec, Buffer<kernels::Pair>* out);
  void refit_bounds(const Executor& exec, kernels::AabbSoA boxes, kernels::PairFilter filter);
  /// The boxes as records in original order (one random read per leaf in the gathers).
  const kernels::SortedBox* pack(const Executor& exec, kernels::AabbSoA boxes, uint32_t n);

  LbvhOptions options_;
  LbvhInfo info_;
  bool filtered_ = false;
  bool built_ = false;  // a tree (possibly of 0 or 1 leaves) exists
  RadixSorter sorter_;
  Buffer<uint64_t> keys_;
  Buffer<uint32_t> leaf_index_;
  Buffer<kernels::LbvhNode> nodes_;
  Buffer<kernels::SortedBox> leaves_, packed_;
  Buffer<uint32_t> internal_parent_, leaf_parent_, slot_;
  Buffer<kernels::LbvhBlocked> blocked_;
  Buffer<uint32_t> layer_, mask_;
  Buffer<uint8_t> static_;
  Buffer<uint64_t> chunk_offsets_;
  std::vector<Buffer<kernels::Pair>> chunk_pairs_;
  Buffer<kernels::BoundsSummary> partial_bounds_;
  Buffer<double> partial_area_;
};

}  // namespace impact::host
