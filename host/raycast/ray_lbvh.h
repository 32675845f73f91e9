// An LBVH over primitive boxes for ray queries: the broad phase's LbvhBroadPhase
// (kernels/bvh/ build and refit, docs/lbvh.md: Morton codes 30/63-bit, radix sort,
// one-pass bottom-up build of the Karras tree, bottom-up refit) without its pair
// pass, traversed by kernels/raycast/ray_bvh.h. build() and refit() only bring the
// nodes and sorted leaves up to date. All passes chunk by n and a fixed grain, so the tree bytes are
// the same for any thread count.
#pragma once

#include <cstdint>

#include "host/broadphase/lbvh.h"
#include "host/parallel.h"
#include "kernels/broadphase/bounds.h"
#include "kernels/raycast/ray_bvh.h"

namespace impact::host {

class RayLbvh {
 public:
  RayLbvh();
  /// Builds over boxes[0, n) (n < 2^30).
  void build(const Executor& exec, kernels::AabbSoA boxes, uint32_t n);
  /// Same n and box indices as the last build, new bounds.
  void refit(const Executor& exec, kernels::AabbSoA boxes);

  kernels::RayTree tree() const;
  uint32_t size() const { return lbvh_.size(); }
  uint32_t morton_bits() const { return lbvh_.info().morton_bits; }

  static constexpr uint32_t kGrain = LbvhBroadPhase::kNodeGrain;

 private:
  LbvhBroadPhase lbvh_;
};

}  // namespace impact::host
