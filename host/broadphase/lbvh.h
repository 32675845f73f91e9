// Host driver of the LBVH broad phase (kernels/bvh/): same contract as
// GridBroadPhase (host/broadphase/broadphase.h): given n boxes (SoA) and an optional
// filter, replace *out with every pair of overlapping boxes (a < b) that passes the
// filter, in an order that does not depend on the thread count.
//
// Passes of a rebuild: bounds summary -> Morton keys (30 or 63 bit) -> radix sort ->
// hierarchy and bounds in one bottom-up pass (lbvh_build_fused.h: Apetrei 2014 in
// leaf order per chunk, then the chunk seams; exact min/max unions) -> self traversal by
// leaf clusters (lbvh_traverse.h) into per-chunk buffers concatenated in chunk order
// (chunked_output). A refit reuses the sorted order and the hierarchy and only reruns
// the bounds (lbvh_refit.h) and the traversal.
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
#include "kernels/bvh/lbvh_build.h"
#include "kernels/bvh/lbvh_build_fused.h"
#include "kernels/bvh/lbvh_pair_cache.h"
#include "kernels/bvh/lbvh_traverse.h"
#include "kernels/bvh/morton.h"
#include "kernels/common/pair.h"
#include "kernels/common/sorted_box.h"

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
  /// kPairCache: each box's fat box is the box grown on every side by fat_margin
  /// times its largest edge (at least fat_margin * the scene's largest edge / 1024,
  /// so points get a margin too). >= 0.
  float fat_margin = 0.2f;
};

/// What the last call did (for benchmarks and diagnostics).
struct LbvhInfo {
  uint32_t leaves = 0;           ///< n of the current tree (0: none)
  uint32_t morton_bits = 0;      ///< 30 or 63
  bool rebuilt = false;          ///< the last call rebuilt (false: refitted)
  uint32_t refits_since_build = 0;
  double built_sah = 0.0;        ///< SAH right after the last build (update kAuto only)
  double last_sah = 0.0;         ///< SAH of the last refit (update kAuto only)
  uint32_t movers = 0;           ///< kPairCache: boxes that left their fat box in the last update
  uint64_t movers_since_build = 0;  ///< kPairCache: their sum since the last build
  uint64_t cached_pairs = 0;     ///< kPairCache: fat-overlapping pairs held
  uint32_t cache_backoff = 0;    ///< kPairCache: refits left before the cache is tried again
  bool cached = false;           ///< kPairCache: pairs() filters the cache (false: it traverses)
};

/// The 30/63-bit rule: 63-bit codes when n > 2^24, or when a 30-bit cell (largest
/// scene extent / 1024) is wider than 4 largest box edges (a sparse world whose boxes
/// would crowd into few cells and get index-ordered subtrees); else 30-bit (3 radix
/// passes instead of 6 from 2^15 boxes, 4 instead of 8 below). Zero-extent scenes use
/// 30-bit.
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
  /// Leaving kPairCache (or changing fat_margin) drops a fat tree: the next update
  /// builds, and pairs() is empty until then.
  void set_options(const LbvhOptions& o) {
    if (cache_valid_ && (o.update != LbvhUpdate::kPairCache || o.fat_margin != options_.fat_margin)) {
      built_ = false;
      cache_valid_ = false;
    }
    options_ = o;
  }
  const LbvhInfo& info() const {
    info_.cached = cache_valid_;
    return info_;
  }

  /// Boxes of the current tree (0 when none).
  uint32_t size() const { return built_ ? info_.leaves : 0; }
  /// The current tree (valid when info().leaves >= 2; nodes only then). Under
  /// kPairCache its leaves are the fat boxes: use query_view() for exact ones.
  kernels::LbvhView view() const;
  /// view() with the exact boxes as leaves (under kPairCache, gathered into sorted
  /// order on the first call after an update; the nodes bound them too).
  kernels::LbvhView query_view(const Executor& exec);
  const uint32_t* leaf_index() const { return leaf_index_.data(); }
  const uint32_t* internal_parent() const { return internal_parent_.data(); }
  const uint32_t* leaf_parent() const { return leaf_parent_.data(); }

  static constexpr uint32_t kKeyGrain = 1u << 14;   ///< boxes per chunk, streaming passes
  static constexpr uint32_t kNodeGrain = 1u << 14;  ///< nodes / leaves per chunk, build and refit
  static constexpr uint32_t kPairGrain = 1u << 11;  ///< query leaves per chunk, pair pass
  static constexpr uint32_t kMoverGrain = 1u << 10;  ///< movers per chunk, kPairCache re-query

 private:
  Status rebuild(const Executor& exec, kernels::AabbSoA boxes, kernels::PairFilter filter, uint32_t n,
                 const kernels::BoundsSummary* summary);
  Status traverse(const Executor& exec, Buffer<kernels::Pair>* out);
  void refit_bounds(const Executor& exec, kernels::AabbSoA boxes, kernels::PairFilter filter);
  /// The lane arrays for n leaves (padding filled), for the passes that write leaves.
  kernels::LbvhLanes lanes(uint32_t n);
  /// The boxes as records in original order (one random read per leaf in the gathers).
  const kernels::SortedBox* pack(const Executor& exec, kernels::AabbSoA boxes, uint32_t n);
  // kPairCache (kernels/bvh/lbvh_pair_cache.h).
  bool cache_mode() const { return options_.update == LbvhUpdate::kPairCache; }
  kernels::LbvhFatMargin fat_margin(const kernels::BoundsSummary& s) const;
  /// After a rebuild over fat boxes: the sorted cache of every fat pair.
  Status cache_build(const Executor& exec, kernels::AabbSoA boxes, kernels::PairFilter filter);
  /// One coherent update; *rebuild set when the movers call for a rebuild instead.
  Status cache_update(const Executor& exec, kernels::AabbSoA boxes, kernels::PairFilter filter,
                      bool* rebuild, bool* swamped);
  bool same_filter(kernels::PairFilter filter) const;
  Status cache_pairs(const Executor& exec, Buffer<kernels::Pair>* out);
  /// The m pairs as keys (a << w) | b, radix-sorted, in new_keys_.
  const uint64_t* sorted_keys(const Executor& exec, const kernels::Pair* pairs, uint64_t m, uint32_t w);
  /// traverse(), then sorted by (a, b): kPairCache's order when it refits instead.
  Status sorted_traverse(const Executor& exec, Buffer<kernels::Pair>* out);

  LbvhOptions options_;
  mutable LbvhInfo info_;
  bool filtered_ = false;
  bool built_ = false;  // a tree (possibly of 0 or 1 leaves) exists
  RadixSorter sorter_;
  Buffer<uint64_t> keys_;
  Buffer<uint32_t> leaf_index_;
  Buffer<kernels::LbvhNode> nodes_;
  Buffer<kernels::SortedBox> leaves_, packed_;
  Buffer<float> lanes_;  // leaves_ as lane arrays (kernels::LbvhLanes), for the pair walk
  Buffer<uint32_t> internal_parent_, leaf_parent_, slot_;
  Buffer<kernels::LbvhBlocked> blocked_;
  Buffer<uint32_t> layer_, mask_;
  Buffer<uint8_t> static_;
  Buffer<uint64_t> chunk_offsets_;
  std::vector<Buffer<kernels::Pair>> chunk_pairs_;
  Buffer<kernels::BoundsSummary> partial_bounds_;
  Buffer<double> partial_area_;
  // kPairCache state: fat and exact boxes (original order), movers, the cache (keys
  // (lo << key_shift_) | hi, one sorted buffer per kLbvhCacheGrain lo indices, double
  // buffered), the filter it was built with, and exact sorted leaves for queries.
  bool cache_valid_ = false;
  // kPairCache after an update with more than n / 4 movers: refit instead for
  // backoff_left_ more updates; backoff_ doubles on each such failure (at most
  // kMaxCacheBackoff) and resets once an update keeps the cache.
  static constexpr uint32_t kMaxCacheBackoff = 64;
  uint32_t backoff_ = 0, backoff_left_ = 0;
  bool exact_leaves_valid_ = false;
  uint32_t key_shift_ = 1;
  kernels::LbvhFatMargin margin_{};
  Buffer<kernels::SortedBox> fat_, exact_leaves_;
  Buffer<uint8_t> moved_;
  Buffer<uint32_t> movers_, leaf_pos_;
  Buffer<uint64_t> mover_offsets_, new_keys_, key_offsets_;
  std::vector<Buffer<uint64_t>> key_chunks_;
  std::vector<Buffer<uint32_t>> mover_chunks_;
  std::vector<Buffer<kernels::Pair>> cache_out_;
  Buffer<kernels::Pair> fat_pairs_;
  std::vector<Buffer<uint64_t>> cache_[2];
  std::vector<uint64_t> cache_count_[2];
  int cur_ = 0;
  Buffer<uint32_t> filter_layer_, filter_mask_;
  Buffer<uint8_t> filter_static_;
  bool cache_filtered_ = false;
};

}  // namespace impact::host
