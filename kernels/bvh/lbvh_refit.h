// Bottom-up bounds of an LBVH (kernels/bvh/lbvh_build.h), in one parallel pass over
// the leaves.
//
// What: per sorted leaf s in r: leaves[s] = box leaf_index[s] (and its filter data,
//   when filtered), then climb: at each parent p, an integer atomic fetch_add on
//   refit_counter[p] tells whether this is the first (even old value: stop, the
//   sibling's climb will finish p) or the second (odd old value: both children are
//   final) arrival; the second computes p's bounds as the union of its children's
//   and continues to p's parent. Each node is written by exactly one climb, after
//   both children are written (the acq_rel fetch_add orders the sibling's writes
//   before the read).
// Determinism: the union of boxes is exact (min/max of floats, no rounding), so the
//   node bytes do not depend on which child arrives last or on the thread count.
//   No float atomics. The counters never need a reset between refits: every refit
//   adds exactly 2 to each counter, so parity alone tells first from second (the
//   build sets them to 0; uint32 wrap-around keeps parity).
// Inputs: boxes (SoA, original order, finite), filter (all null or all set),
//   leaf_index[n] (sorted leaf -> box), topology from lbvh_build.
// Outputs: leaves[0, n) (SortedBox with the original index), nodes[0, n - 1) bounds,
//   sorted filter arrays (when filtered).
// Preconditions: every range of [0, n) runs exactly once per refit, all in one pass;
//   ranges may run concurrently. n >= 1 (n == 1: just the leaf).
// Cost: O(n) total: one gather per leaf plus one union per internal node; about half
//   of the climbs stop at the first parent.
// Method: Karras 2012, section 4 ("Bounding boxes": atomic flags, the second thread
//   to reach a node processes it); Apetrei 2014 for the same idea fused with the build.
#pragma once

#include "kernels/broadphase/bounds.h"
#include "kernels/broadphase/grid.h"
#include "kernels/bvh/lbvh_build.h"
#include "kernels/common/kernel.h"

namespace impact::kernels {

/// What the refit reads besides the boxes.
struct LbvhRefitIn {
  const uint32_t* leaf_index;       ///< n: sorted leaf -> original box index
  const uint32_t* internal_parent;  ///< n - 1
  const uint32_t* leaf_parent;      ///< n
};

/// What the refit writes (counters are read-modify-write).
struct LbvhRefitOut {
  LbvhNode* nodes;          ///< n - 1: bounds written, split/last read
  SortedBox* leaves;        ///< n
  uint32_t* refit_counter;  ///< n - 1
  uint32_t* layer;          ///< n, sorted order; null when unfiltered
  uint32_t* mask;
  uint8_t* is_static;
};

void lbvh_refit(AabbSoA boxes, PairFilter filter, LbvhRefitIn in, LbvhRefitOut out, uint32_t n,
                Range r);

}  // namespace impact::kernels
