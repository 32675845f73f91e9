// Bottom-up bounds of an LBVH (kernels/bvh/lbvh_build.h): one parallel pass over
// chunks of sorted leaves, in leaf order inside each chunk, then a short serial pass
// over the chunk seams. No atomics.
//
// What: per sorted leaf s of a chunk [b, e), in increasing s: leaves[s] = box
//   leaf_index[s] (and its filter data, when filtered), then climb while the node
//   just finished is the right child of its parent p (nodes[p].last == s): every leaf
//   of p's left child lies before s, so in leaf order the left child is already
//   final and p = union(left, right) is final too. A left child stops the climb (its
//   parent is finished later by its right child's climb). So each node is written
//   once, by the chunk that holds its last leaf, in the climb from that leaf.
// Seams: a node whose leaf range straddles the chunk start b (it holds b - 1 and b:
//   the node P_b whose split is b - 1, and its ancestors) needs the previous chunk's
//   result, which may still be running. The climb marks such nodes (min_x = a NaN
//   pattern, never a valid bound: bounds are finite) instead of reading across the
//   seam: P_b (split + 1 == b), and any node whose left or right child is marked.
//   lbvh_refit_seam then recomputes, for each chunk in increasing order after the
//   parallel pass, the chain from P_b up to the last ancestor whose last leaf is in
//   the chunk: exactly the nodes that chunk marked. O(depth) per chunk.
// Determinism: the union of boxes is exact (min/max of floats, no rounding), and
//   every node is the union of the same two final children whatever the chunking or
//   thread count, so the node bytes never depend on either. No float atomics.
// Inputs: boxes (SoA, original order, finite; or the same boxes packed as records by
//   lbvh_pack_boxes: the gather is random access, one record is one cache miss where
//   the SoA arrays cost six), filter (all null or all set), leaf_index[n] (sorted leaf
//   -> box), topology from lbvh_build.
// Outputs: leaves[0, n) (SortedBox with the original index), nodes[0, n - 1) bounds,
//   sorted filter arrays (when filtered).
// Preconditions: lbvh_refit runs once on every chunk of one fixed partition of [0, n)
//   into consecutive ranges (concurrently is fine), then lbvh_refit_seam runs once per
//   chunk but the first, in increasing order, on one thread. n >= 1 (n == 1: just the
//   leaf).
// Cost: O(n): one gather per leaf plus one union per internal node, climbs in leaf
//   order (the nodes a chunk writes are its own, mostly cache-resident); no atomic
//   visit counters, whose lock-prefixed updates would serialise the gather's misses.
// Method: Karras 2012, section 4 ("Bounding boxes"; there with atomic flags); the
//   sequential right-child rule is that of an in-order (post-order) tree walk.
#pragma once

#include "kernels/broadphase/bounds.h"
#include "kernels/bvh/lbvh_build.h"
#include "kernels/common/kernel.h"
#include "kernels/common/pair.h"
#include "kernels/common/sorted_box.h"

namespace impact::kernels {

/// Box i of a SoA as a SortedBox record (index i).
IMPACT_INLINE SortedBox pack(AabbSoA boxes, uint32_t i) {
  return SortedBox{boxes.min_x[i], boxes.min_y[i], boxes.min_z[i], i,
                   boxes.max_x[i], boxes.max_y[i], boxes.max_z[i], 0u};
}

/// What the refit reads besides the boxes.
struct LbvhRefitIn {
  const uint32_t* leaf_index;       ///< n: sorted leaf -> original box index
  const uint32_t* internal_parent;  ///< n - 1
  const uint32_t* leaf_parent;      ///< n
  /// n: the boxes as records in original order (lbvh_pack_boxes), or null to gather
  /// from the SoA arrays (six random reads per leaf instead of one).
  const SortedBox* packed;
};

/// What the refit writes.
struct LbvhRefitOut {
  LbvhNode* nodes;          ///< n - 1: bounds written, split/last read
  SortedBox* leaves;        ///< n
  uint32_t* layer;          ///< n, sorted order; null when unfiltered
  uint32_t* mask;
  uint8_t* is_static;
  LbvhLanes lanes;          ///< the leaves' lane copy (data null: none)
};

/// out[i] = box i as a SortedBox record (index i), i in r: a sequential pass that lets
/// the leaf gathers read one 32-byte record per leaf instead of six scattered floats.
void lbvh_pack_boxes(AabbSoA boxes, SortedBox* IMPACT_RESTRICT out, Range r);

/// Gathers the leaves of chunk r and computes the nodes whose leaf range lies in r.
void lbvh_refit(AabbSoA boxes, PairFilter filter, LbvhRefitIn in, LbvhRefitOut out, uint32_t n,
                Range r);

/// Completes the nodes straddling the start of chunk r (r.begin > 0) whose last leaf is
/// in r. Runs after lbvh_refit over all chunks, for chunk 1, 2, ... in order.
void lbvh_refit_seam(LbvhRefitIn in, LbvhRefitOut out, uint32_t n, Range r);

}  // namespace impact::kernels
