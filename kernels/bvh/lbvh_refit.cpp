#include "kernels/bvh/lbvh_refit.h"

#include <algorithm>
#include <bit>

#include "kernels/bvh/lbvh_bounds.h"

namespace impact::kernels {
namespace {

using lbvh_detail::Bounds;
using lbvh_detail::bounds_of;
using lbvh_detail::store_bounds;
using lbvh_detail::unite;

// min_x of a node marked "straddles a chunk seam, computed by lbvh_refit_seam" (a
// quiet NaN: never a valid bound).
constexpr uint32_t kSeamMark = 0x7fc5ea11u;


IMPACT_INLINE bool marked(const LbvhNode& node) { return std::bit_cast<uint32_t>(node.min_x) == kSeamMark; }

IMPACT_INLINE Bounds child_bounds(const LbvhRefitOut& out, uint32_t split, uint32_t leaf_flag, uint32_t c) {
  return (split & leaf_flag) ? bounds_of(out.leaves[c]) : bounds_of(out.nodes[c]);
}

}  // namespace

void lbvh_pack_boxes(AabbSoA boxes, SortedBox* IMPACT_RESTRICT out, Range r) {
  for (uint32_t i = r.begin; i < r.end; ++i) out[i] = pack(boxes, i);
}

void lbvh_refit(AabbSoA boxes, PairFilter filter, LbvhRefitIn in, LbvhRefitOut out, uint32_t n,
                Range r) {
  const uint32_t b = r.begin;
  for (uint32_t s = r.begin; s < r.end; ++s) {
    lbvh_detail::prefetch_gather(in.packed, in.leaf_index, s, r.end);
    const uint32_t i = in.leaf_index[s];
    const SortedBox leaf = in.packed ? in.packed[i] : pack(boxes, i);
    out.leaves[s] = leaf;
    out.lanes.store(s, leaf);
    if (filter.layer) {
      out.layer[s] = filter.layer[i];
      out.mask[s] = filter.mask[i];
      out.is_static[s] = filter.is_static[i];
    }
    if (n < 2) continue;
    // Climb while the finished node (leaf s first) is its parent's right child; the
    // bounds of the finished node stay in registers.
    Bounds cur = bounds_of(leaf);
    bool seam = false;
    for (uint32_t p = in.leaf_parent[s]; p != kInvalidBody; p = in.internal_parent[p]) {
      LbvhNode& node = out.nodes[p];
      if (node.last != s) break;  // came from the left child
      const uint32_t g = node.split & kLbvhSplitMask;
      if (!seam) {
        // The left child ends at g: before b it belongs to the previous chunk; a marked
        // left child straddles b.
        seam = g + 1 == b || (!(node.split & kLbvhLeftLeaf) && marked(out.nodes[g]));
        if (!seam) {
          cur = unite(child_bounds(out, node.split, kLbvhLeftLeaf, g), cur);
          store_bounds(node, cur);
          continue;
        }
      }
      node.min_x = std::bit_cast<float>(kSeamMark);
    }
  }
}

void lbvh_refit_seam(LbvhRefitIn in, LbvhRefitOut out, uint32_t n, Range r) {
  const uint32_t b = r.begin;
  if (n < 2 || b == 0 || b >= n) return;
  // P_b: the node whose children end at b - 1 and start at b. Its right child is leaf
  // b or internal node b (lbvh_build.h numbering).
  const uint32_t q = in.leaf_parent[b];
  uint32_t p = (out.nodes[q].split & kLbvhSplitMask) + 1 == b ? q : in.internal_parent[b];
  // The chain P_b, parent, ... whose last leaf lies in r: exactly the nodes this chunk
  // marked. Children are final: left ones end before b (earlier chunks and seams),
  // right ones in r (this chunk, or lower on this chain).
  while (p != kInvalidBody && out.nodes[p].last < r.end) {
    LbvhNode& node = out.nodes[p];
    const uint32_t g = node.split & kLbvhSplitMask;
    store_bounds(node, unite(child_bounds(out, node.split, kLbvhLeftLeaf, g),
                      child_bounds(out, node.split, kLbvhRightLeaf, g + 1)));
    p = in.internal_parent[p];
  }
}

}  // namespace impact::kernels
