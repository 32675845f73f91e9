// Self-pair query of an LBVH (kernels/bvh/lbvh_build.h, bounds by lbvh_refit.h):
// every pair of overlapping leaves, each pair once.
//
// What: per query leaf s in r (sorted position), the subtrees holding only leaves after
//   s are the right siblings of the ancestors of s reached from their left child
//   (subtrees are contiguous leaf ranges). Each one whose bounds overlap leaf s is
//   explored depth first with a fixed stack of kLbvhMaxDepth + 1 entries. Each
//   overlapping leaf t > s that passes the filter gives the pair (min, max) of the two
//   original box indices. A pair {s, t} is thus met only by the query min(s, t): each
//   pair once, no duplicate removal.
// Candidate stack: those right siblings are kept, with a copy of their bounds, in a
//   stack (root side at the bottom) carried from query s to s + 1 along a chunk: the
//   top is the subtree whose first leaf is s + 1; s + 1's stack replaces it by the
//   right children along its left spine. So the per-query climb to the root (a chain
//   of ~log2 n dependent parent loads and unpredictable left/right branches) becomes
//   amortised O(1) pushes per query plus a branch-free scan of ~log2 n / 2 candidate
//   boxes held in L1; each chunk starts with one root-to-leaf walk. 1M uniform boxes,
//   one thread: 211 -> 159 ms (the leaf-to-root climb it replaces had taken 290 ->
//   219 ms over a root-down traversal).
// Query groups: a run of up to 16 consecutive queries whose own stack entries cover
//   exactly the leaves between them shares every entry below those: the shared
//   candidates are explored once with the union box of the run's leaves, the leaves
//   overlapping it collected in pre-order (at most 256; beyond, the run's queries go
//   one by one), and each query filters that list after its own entries. Same pairs,
//   same order; 1M uniform: ~6.6 -> ~5.2 node visits per query, ~5% faster.
// Order (independent of the thread count): by query leaf s (Morton order); within a
//   query, by ancestor from the leaf upwards; within one sibling subtree, pre-order
//   depth first: at each internal node popped, its leaf children are emitted (left,
//   then right), then its internal children are pushed right first, so the left
//   subtree is explored before the right one.
// Overlap includes touching (min <= max on all axes). Filter, as the grid's:
//   (layer_a & mask_b) && (layer_b & mask_a), and not both static.
// Output: like grid_find_pairs, writes the first `capacity` pairs of the range to
//   out and returns how many there are (the host reruns with more room).
// Preconditions: n >= 2; the tree built and refitted for these leaves; bounds finite.
// Cost: O(depth + k) node tests per query for well-distributed boxes (k = overlaps;
//   depth ~ log2 n); worst case O(n) per query (every box overlapping every other).
// Method: Karras, "Thinking Parallel, Part II/III" (NVIDIA blog, 2012): per-leaf
//   independent traversal of the LBVH for self-collision, pruning subtrees at or
//   before the query leaf; here started bottom-up from the query leaf.
//
// lbvh_area_sum: part of the tree's surface-area (SAH) cost. The host sums the
//   partials of fixed chunks of node ids (internal 0..n-2, then leaf s as n - 1 + s)
//   in chunk order and divides by the root's area:
//     SAH = sum over all nodes (internal and leaf) of area(node) / area(root),
//   i.e. each node costs 1 (one box test when its parent is entered) weighted by the
//   probability that a small random query inside the root reaches it (Goldsmith &
//   Salmon 1987; MacDonald & Booth 1990). Area = 2 (dx dy + dy dz + dz dx) in double.
#pragma once

#include "kernels/broadphase/grid.h"
#include "kernels/bvh/lbvh_build.h"
#include "kernels/common/kernel.h"

namespace impact::kernels {

/// A built and refitted LBVH with its sorted leaves and filter data.
struct LbvhView {
  const LbvhNode* nodes;     ///< n - 1 internal nodes, root 0
  const uint32_t* internal_parent;  ///< n - 1 (root: kInvalidBody)
  const uint32_t* leaf_parent;      ///< n
  const SortedBox* leaves;   ///< n leaves in sorted order
  const uint32_t* layer;     ///< sorted order; null when unfiltered
  const uint32_t* mask;
  const uint8_t* is_static;
  uint32_t n;
};

/// Writes the pairs whose query leaf lies in r (see the order above) to out[0, capacity)
/// and returns their count.
uint64_t lbvh_find_pairs(const LbvhView& t, Pair* IMPACT_RESTRICT out, uint64_t capacity, Range r);

/// Sum of node surface areas (m^2) over the node ids in r (internal 0..n-2, then leaves).
double lbvh_area_sum(const LbvhView& t, Range r);

}  // namespace impact::kernels
