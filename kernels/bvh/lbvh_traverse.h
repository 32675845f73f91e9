// Self-pair query of an LBVH (kernels/bvh/lbvh_build.h, bounds by lbvh_refit.h):
// every pair of overlapping leaves, each pair once.
//
// What: the queries are clusters, not leaves: the maximal subtrees of at most
//   kLbvhCluster leaves (subtrees are contiguous ranges of sorted leaves, so the
//   clusters partition [0, n) into consecutive ranges). Per cluster C with leaves
//   [a, b] and bounds B (its subtree's node): (1) each leaf u in (a, b] against the
//   leaves of C before it (only the vectors holding them); (2) the subtrees holding
//   only leaves after b are the right siblings of C's ancestors reached from their
//   left child; each one whose bounds overlap B is walked depth first (a fixed stack
//   of kLbvhMaxDepth + 2 entries), pruning by B, down to target subtrees of at most
//   kLbvhTarget leaves, whose leaves are then tested: first against B, one SIMD
//   vector of consecutive leaves at a time from the lane arrays (LbvhLanes), the
//   survivors against all of C's leaves at once, C's leaves held one per SIMD lane.
//   Each overlapping pair that passes the filter gives (min, max) of the two
//   original box indices. A pair of sorted positions s < t is met only by the
//   cluster holding s: each pair once.
// SIMD width: 16 lanes where AVX-512 is enabled, else kSimdWidth (the leaf tests
//   are compares only: any width gives the same pairs, in the same order).
// Why clusters: a per-leaf query walks ~5 nodes per leaf with a dependent load and an
//   unpredictable branch each; a cluster walks its neighbourhood once for all of its
//   leaves, and the leaf tests it adds are SIMD and branch-free (the sizes
//   kLbvhCluster and kLbvhTarget were chosen by measurement: docs/lbvh.md).
// Candidate stack: those right siblings are kept, with a copy of their bounds, in a
//   stack (root side at the bottom) carried from one cluster to the next along a
//   chunk: the top is the subtree that starts right after the cluster; the next
//   cluster replaces it by the right children along its left spine. Each chunk starts
//   with one root-to-cluster walk; a cluster belongs to the chunk holding its first
//   leaf.
// Branches: the tests are branch-free, and so is whether a tested leaf hit: a target's
//   survivors of the bounds test are compacted over all its vectors first, then each
//   tested against the cluster's leaves with its hits listed branch-free (the in-cluster
//   tests likewise), and the pairs emitted after the loop, in the same order: about
//   half the tested leaves hit, unpredictably, so a branch per leaf (or per vector of
//   survivors) would mispredict often.
// Order (independent of the thread count and of the chunks): by cluster (leaf order);
//   within a cluster, by the later leaf's sorted position t, then by the earlier
//   leaf's s. That is, the pairs (s < t) sorted by (cluster of s, t, s). The walk
//   produces it directly: left subtrees first, a right child small enough to test
//   waits on the stack behind an internal left sibling.
// Overlap includes touching (min <= max on all axes). Filter, as the grid's:
//   (layer_a & mask_b) && (layer_b & mask_a), and not both static.
// Output: like grid_find_pairs, writes the first `capacity` pairs of the range to
//   out and returns how many there are (the host reruns with more room).
// Preconditions: n >= 2; the tree built and refitted for these leaves; bounds finite.
// Cost: per cluster O(depth) candidate tests plus the subtrees its bounds reach, plus
//   one vector test per kW leaves of each reached target and kLbvhCluster / kW vector
//   tests per leaf overlapping B; worst case O(n) per cluster (every box overlapping
//   every other).
// Method: Karras, "Thinking Parallel, Part II/III" (NVIDIA blog, 2012): independent
//   traversal of the LBVH per query for self-collision, pruning subtrees at or before
//   the query; here the query is a leaf cluster (as BVHs with multi-primitive leaves
//   do), started bottom-up from the cluster.
//
// lbvh_area_sum: part of the tree's surface-area (SAH) cost. The host sums the
//   partials of fixed chunks of node ids (internal 0..n-2, then leaf s as n - 1 + s)
//   in chunk order and divides by the root's area:
//     SAH = sum over all nodes (internal and leaf) of area(node) / area(root),
//   i.e. each node costs 1 (one box test when its parent is entered) weighted by the
//   probability that a small random query inside the root reaches it (Goldsmith &
//   Salmon 1987; MacDonald & Booth 1990). Area = 2 (dx dy + dy dz + dz dx) in double.
#pragma once

#include "kernels/bvh/lbvh_build.h"
#include "kernels/common/kernel.h"
#include "kernels/common/pair.h"
#include "kernels/common/sorted_box.h"

namespace impact::kernels {

/// Largest subtree the self-pair query treats as one query cluster (see above; at
/// most 64: one bit per leaf in a 64-bit word).
inline constexpr uint32_t kLbvhCluster = 64;
/// Largest subtree the walk tests leaf by leaf instead of descending into.
inline constexpr uint32_t kLbvhTarget = 128;

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
  /// The leaves' bounds as lane arrays (LbvhLanes, lbvh_build.h): array k at
  /// lanes + k * lane_stride. lbvh_find_pairs needs them; the other walks do not.
  const float* lanes;
  size_t lane_stride;
  /// The leaves' body indices in sorted order (leaves[s].index, 4 bytes a leaf):
  /// lbvh_find_pairs reads them instead of the 32-byte records, which a leaf tested
  /// from the lane arrays has not brought into cache.
  const uint32_t* ids;
};

/// Writes the pairs whose query leaf lies in r (see the order above) to out[0, capacity)
/// and returns their count.
uint64_t lbvh_find_pairs(const LbvhView& t, Pair* IMPACT_RESTRICT out, uint64_t capacity, Range r);

/// Sum of node surface areas (m^2) over the node ids in r (internal 0..n-2, then leaves).
double lbvh_area_sum(const LbvhView& t, Range r);

}  // namespace impact::kernels
