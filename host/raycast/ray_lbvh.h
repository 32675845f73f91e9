// An LBVH over primitive boxes for ray queries (kernels/bvh/ build and refit, traversed
// by kernels/raycast/ray_bvh.h). Unlike the broad-phase LbvhBroadPhase it emits no
// pairs: build() and refit() only bring the nodes and sorted leaves up to date.
//
// Passes of build(): bounds summary (per-chunk partials in chunk order) -> Morton keys
// (30-bit, or 63-bit when n > 2^24 or a 30-bit cell is wider than 4 largest box edges,
// the rule of docs/lbvh.md) -> radix sort -> Karras hierarchy -> bottom-up refit.
// refit() reruns only the last pass. All passes chunk by n and a fixed grain, so the
// tree bytes are the same for any thread count.
#pragma once

#include <cstdint>

#include "host/buffer.h"
#include "host/parallel.h"
#include "host/radix_sort.h"
#include "kernels/broadphase/bounds.h"
#include "kernels/bvh/lbvh_build.h"
#include "kernels/raycast/ray_bvh.h"

namespace impact::host {

class RayLbvh {
 public:
  /// Builds over boxes[0, n) (n < 2^30).
  void build(const Executor& exec, kernels::AabbSoA boxes, uint32_t n);
  /// Same n and box indices as the last build, new bounds.
  void refit(const Executor& exec, kernels::AabbSoA boxes);

  kernels::RayTree tree() const { return {nodes_.data(), leaves_.data(), n_}; }
  uint32_t size() const { return n_; }
  uint32_t morton_bits() const { return bits_; }

  static constexpr uint32_t kGrain = 1u << 14;

 private:
  uint32_t n_ = 0;
  uint32_t bits_ = 30;
  RadixSorter sorter_;
  Buffer<uint64_t> keys_;
  Buffer<uint32_t> leaf_index_;
  Buffer<kernels::LbvhNode> nodes_;
  Buffer<kernels::SortedBox> leaves_;
  Buffer<uint32_t> internal_parent_, leaf_parent_, counters_;
  Buffer<kernels::BoundsSummary> partial_;
};

}  // namespace impact::host
