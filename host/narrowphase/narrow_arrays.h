// host::ArrayRunner: NarrowPhase::collide_arrays, the narrow phase's batch form over
// caller-owned SoA arrays (include/impact/narrowphase.h). Convex objects only, so a
// pair is one leaf pair and has one result slot, the pair's own index: no expansion,
// no output compaction, no conversion. Per call: one parallel pass over the objects
// (finite poses, unit quaternions, shape ids, leaf types), one over the pairs (indices,
// the bucket key of each), a bucket sort only when the pairs are not listed by type,
// then per block of kLaneBlock pairs of one bucket: gather the two poses into this
// thread's kernel lanes and run the pair kernel, writing into the caller's arrays at
// the pairs' own indices when the order is the identity (else into lane scratch,
// scattered to the pairs). Blocks depend only on the pairs, so the bytes do not depend
// on the thread count.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "host/buffer.h"
#include "host/parallel.h"
#include "host/radix_sort.h"
#include "host/shapes/shape_store.h"
#include "impact/narrowphase.h"
#include "impact/status.h"
#include "kernels/narrowphase/leaf/leaf.h"

namespace impact::host {

class ArrayRunner {
 public:
  /// Validates and runs one collide_arrays call (NarrowPhase::collide_arrays has the
  /// contract); cfg.hulls is set here.
  Status run(const Executor& exec, const ShapeStore& store, std::span<const ShapeId> shape_of,
             const PoseArrays& poses, std::span<const ShapePair> pairs, const kernels::NarrowConfig& cfg,
             const PairContactArrays& out);

 private:
  std::vector<uint8_t> leaf_;        // per object: its kernels::LeafType
  std::vector<uint32_t> first_bad_;  // per chunk: its first bad object or pair
  Buffer<uint64_t> keys_;            // per pair: bucket << 32 | pair
  RadixSorter sorter_;
  std::vector<uint32_t> blocks_;     // block starts (sorted positions), then the end
  std::vector<uint8_t> chunk_descends_;
};

}  // namespace impact::host
