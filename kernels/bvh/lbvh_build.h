// LBVH hierarchy over sorted Morton codes: one independent pass per internal node.
//
// What: given n >= 2 leaves in Morton order (codes[s] >> code_shift, ties broken by
//   the sorted position s), builds the binary radix tree of Karras 2012: n leaves,
//   n - 1 internal nodes, internal node 0 the root. Internal node i covers the
//   contiguous sorted-leaf range [first, last] with i one of its ends; its split
//   gamma is the last position whose key shares the range's longest common prefix
//   plus one more bit with the first, so the left child covers [first, gamma] and the
//   right child [gamma + 1, last]. The left child is leaf gamma if gamma == first,
//   else internal node gamma; the right child is leaf gamma + 1 if gamma + 1 == last,
//   else internal node gamma + 1.
// Duplicate codes: the common prefix of two equal keys is 64 + clz32(s ^ t), i.e. the
//   sorted position extends the key (Karras 2012, section 4), so any code sequence,
//   including all-equal codes, gives a valid tree (a balanced one over equal runs).
// Depth: the common-prefix length strictly grows from a node to its children and lies
//   in [0, 96), so no root-to-leaf path has more than 96 internal nodes; traversal
//   stacks of kLbvhMaxDepth entries never overflow.
// Node layout: LbvhNode, 32 bytes, two per cache line (bounds written by lbvh_refit):
//   float min[3], uint32 split (gamma | kLbvhLeftLeaf | kLbvhRightLeaf),
//   float max[3], uint32 last (the rightmost sorted leaf of the subtree).
//   Leaves are kernels::SortedBox records in sorted order (box + original index), so
//   the traversal reads a child's bounds from one 32-byte record either way, and
//   knows a child's leaf range without loading it (left: [.., gamma], right: [.., last]).
//   Parents (for the bottom-up refit) live apart: internal_parent[n - 1] (root:
//   kInvalidBody) and leaf_parent[n].
// Inputs: codes[0, n) sorted ascending by (codes[s] >> code_shift, s).
// Outputs, per internal node i in r: nodes[i].split/.last, the parent entries of its two
//   children (each child has one parent, so each entry is written by one node),
//   and internal_parent[0] = kInvalidBody by the range holding node 0.
// Preconditions: 2 <= n < 2^30 (the flags use the top two bits of split).
// Cost: O(log n) code reads per internal node (exponential then binary search).
// Method: T. Karras, "Maximizing Parallelism in the Construction of BVHs, Octrees, and
//   k-d Trees", HPG 2012, Figure 4 (determineRange / findSplit).
#pragma once

#include "kernels/common/kernel.h"
#include "kernels/common/sorted_box.h"

namespace impact::kernels {

/// Internal node of the LBVH: bounds (m) plus split and rightmost leaf. 32 bytes.
struct alignas(32) LbvhNode {
  float min_x, min_y, min_z;
  uint32_t split;  ///< gamma | kLbvhLeftLeaf | kLbvhRightLeaf
  float max_x, max_y, max_z;
  uint32_t last;   ///< rightmost sorted-leaf position of the subtree
};
static_assert(sizeof(LbvhNode) == 32);

inline constexpr uint32_t kLbvhLeftLeaf = 1u << 31;   ///< left child is leaf gamma
inline constexpr uint32_t kLbvhRightLeaf = 1u << 30;  ///< right child is leaf gamma + 1
inline constexpr uint32_t kLbvhSplitMask = (1u << 30) - 1;
inline constexpr uint32_t kLbvhMaxLeaves = (1u << 30) - 1;
/// Bound on internal nodes on any root-to-leaf path (see "Depth" above).
inline constexpr uint32_t kLbvhMaxDepth = 96;

/// The sorted leaves' bounds again as six float arrays (min x, y, z, max x, y, z;
/// array k at data + k * stride), for the pair walk's lane tests
/// (lbvh_traverse.h). Whatever writes a leaf record writes its lanes too (build,
/// refit, pair-cache growth), so they always mirror the leaves. Each array is
/// padded past n (lbvh_lane_stride) so a cluster's load at any leaf stays inside;
/// the padding is +inf / -inf (lbvh_lane_padding) and never overlaps anything.
struct LbvhLanes {
  float* data;    ///< null: not kept (the leaf passes skip the writes)
  size_t stride;  ///< floats per array

  IMPACT_INLINE void store(uint32_t s, const SortedBox& b) const {
    if (data == nullptr) return;
    data[s] = b.min_x;
    data[stride + s] = b.min_y;
    data[2 * stride + s] = b.min_z;
    data[3 * stride + s] = b.max_x;
    data[4 * stride + s] = b.max_y;
    data[5 * stride + s] = b.max_z;
  }
};

/// Padding past n of each lane array: a whole query cluster's load (kLbvhCluster
/// lanes, lbvh_traverse.h, which checks the bound) from any leaf stays inside.
inline constexpr uint32_t kLbvhLanePad = 64;
/// Floats per lane array for n leaves: n + kLbvhLanePad, rounded up to a multiple of 16.
constexpr size_t lbvh_lane_stride(uint32_t n) {
  return (static_cast<size_t>(n) + kLbvhLanePad + 15) & ~size_t{15};
}

/// Fills the padding [n, stride) of each array (serial, O(kLbvhLanePad)).
IMPACT_INLINE void lbvh_lane_padding(LbvhLanes lanes, uint32_t n) {
  constexpr float inf = __builtin_inff();
  for (size_t s = n; s < lanes.stride; ++s)
    for (size_t k = 0; k < 6; ++k) lanes.data[k * lanes.stride + s] = k < 3 ? inf : -inf;
}

/// Arrays the build writes (n - 1 nodes and internal parents; n leaf parents).
struct LbvhTopology {
  LbvhNode* nodes;
  uint32_t* internal_parent;
  uint32_t* leaf_parent;
};

/// Builds internal nodes r (a sub-range of [0, n - 1)).
void lbvh_build(const uint64_t* IMPACT_RESTRICT codes, uint32_t code_shift, uint32_t n,
                LbvhTopology out, Range r);

}  // namespace impact::kernels
