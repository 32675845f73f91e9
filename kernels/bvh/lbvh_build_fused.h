// One-pass LBVH build: hierarchy and bounds together, bottom-up in leaf order, no
// binary searches and no atomics. Produces exactly the tree of lbvh_build (Karras
// numbering, lbvh_build.h) with the bounds of lbvh_refit, byte for byte.
//
// What: the binary radix tree over the sorted keys is the tree that merges adjacent
//   ranges by decreasing common prefix: a complete subtree [l, r] is the left child of
//   the node split at r when delta(r) > delta(l - 1), else the right child of the node
//   split at l - 1 (delta(i): common prefix of keys i and i + 1, ties broken by the
//   position as in lbvh_build.h; the two never tie). Apetrei 2014 runs one thread per
//   leaf with an atomic exchange per node; here each chunk [b, e) of leaves runs
//   sequentially in leaf order: a subtree that is a left child records its first leaf
//   in slot[r] and stops; one that is a right child finds its left sibling complete
//   (all of its leaves are earlier) with first leaf slot[l - 1], so the parent [slot,
//   r] is created with its bounds (union of the children) and the climb goes on. The
//   parent's Karras index follows from its own side: r if it is a left child, its
//   first leaf if a right child, 0 for the root.
// Seams: the left sibling of a subtree starting at b lies in the previous chunk. The
//   climb stops there, records the subtree's last leaf R in out_blocked and sets
//   slot[R] = kBlocked; a later climb of the chunk reading a kBlocked slot stops the
//   same way (its left sibling holds the blocked node). The blocked nodes of a chunk
//   form one chain: item k + 1's split is item k's R. lbvh_build_fused_seam resumes
//   them, chunk by chunk in increasing order after the parallel pass, with every
//   earlier slot final.
// Inputs: codes[0, n) sorted ascending by (codes[s] >> shift, s); boxes (SoA,
//   original order, finite); filter (all null or all set); leaf_index[n].
// Outputs: nodes[0, n - 1) (bounds, split, last), internal_parent, leaf_parent,
//   leaves[0, n), sorted filter arrays, slot[0, n) (scratch), per chunk its
//   blocked list (at most kLbvhMaxDepth + 1 entries) and count.
// Preconditions: 1 <= n <= kLbvhMaxLeaves; the pass runs once on every chunk of one
//   partition of [0, n) into consecutive ranges (concurrently is fine), then the seam
//   pass once per chunk but the first, in increasing order, on one thread.
// Cost: O(n): per leaf one gather and ~one delta (two code reads), per internal node
//   one union; versus lbvh_build + lbvh_refit, no O(log n) searches per node.
// Method: C. Apetrei, "Fast and Simple Agglomerative LBVH Construction", CGVC 2014
//   (bottom-up merging by the delta comparison), sequentialised per chunk with the
//   in-order rule of lbvh_refit.h instead of atomics.
#pragma once

#include "kernels/broadphase/bounds.h"
#include "kernels/bvh/lbvh_build.h"
#include "kernels/bvh/lbvh_refit.h"
#include "kernels/common/kernel.h"
#include "kernels/common/pair.h"
#include "kernels/common/sorted_box.h"

namespace impact::kernels {

struct LbvhFusedIn {
  const uint64_t* codes;  ///< n sorted keys, compared as codes[s] >> shift
  uint32_t shift;
  const uint32_t* leaf_index;  ///< n: sorted leaf -> original box index
  const SortedBox* packed;     ///< n boxes as records (lbvh_pack_boxes), or null: read the SoA
};

struct LbvhFusedOut {
  LbvhTopology topo;  ///< nodes (all fields), internal_parent, leaf_parent
  LbvhRefitOut refit; ///< leaves, sorted filter arrays (its nodes must equal topo.nodes)
  /// n scratch: first leaf of the left child waiting at each split (slot[n - 1] only
  /// ever holds a blocked mark).
  uint32_t* slot;
};

/// Blocked list of one chunk: the last leaves of its seam-blocked subtrees, in order.
struct LbvhBlocked {
  uint32_t count;
  uint32_t last[kLbvhMaxDepth + 1];
};

/// Gathers the leaves of chunk r and builds every node the chunk can complete.
void lbvh_build_fused(AabbSoA boxes, PairFilter filter, LbvhFusedIn in, LbvhFusedOut out, uint32_t n,
                      Range r, LbvhBlocked* out_blocked);

/// Completes chunk r's blocked nodes (r.begin > 0) and what they unlock.
void lbvh_build_fused_seam(LbvhFusedIn in, LbvhFusedOut out, uint32_t n, Range r,
                           const LbvhBlocked& blocked);

}  // namespace impact::kernels
