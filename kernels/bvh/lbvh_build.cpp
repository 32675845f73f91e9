#include "kernels/bvh/lbvh_build.h"

#include <bit>

namespace impact::kernels {
namespace {

// Length of the common prefix of the keys at sorted positions i and j, with the
// position appended to the key to break ties; -1 when j is outside [0, n).
IMPACT_INLINE int delta(const uint64_t* IMPACT_RESTRICT codes, uint32_t shift, int64_t n, int64_t i,
                        int64_t j) {
  if (j < 0 || j >= n) return -1;
  const uint64_t a = codes[i] >> shift;
  const uint64_t b = codes[j] >> shift;
  if (a != b) return std::countl_zero(a ^ b);
  return 64 + std::countl_zero(static_cast<uint32_t>(i ^ j));
}

}  // namespace

void lbvh_build(const uint64_t* IMPACT_RESTRICT codes, uint32_t shift, uint32_t n_leaves,
                LbvhTopology out, Range r) {
  IMPACT_ASSERT(n_leaves >= 2 && n_leaves <= kLbvhMaxLeaves);
  const int64_t n = n_leaves;
  for (uint32_t node = r.begin; node < r.end; ++node) {
    const int64_t i = node;
    // Direction of the range: towards the neighbour sharing the longer prefix.
    const int64_t d = delta(codes, shift, n, i, i + 1) - delta(codes, shift, n, i, i - 1) > 0 ? 1 : -1;
    // Upper bound on the range length, then its exact length by binary search.
    const int delta_min = delta(codes, shift, n, i, i - d);
    int64_t l_max = 2;
    while (delta(codes, shift, n, i, i + l_max * d) > delta_min) l_max *= 2;
    int64_t l = 0;
    for (int64_t t = l_max / 2; t >= 1; t /= 2)
      if (delta(codes, shift, n, i, i + (l + t) * d) > delta_min) l += t;
    const int64_t j = i + l * d;
    // Split: the last position (from i towards j) sharing more than delta_node bits with i.
    const int delta_node = delta(codes, shift, n, i, j);
    int64_t s = 0;
    int64_t step = l;
    do {
      step = (step + 1) >> 1;
      if (s + step < l && delta(codes, shift, n, i, i + (s + step) * d) > delta_node) s += step;
    } while (step > 1);
    const int64_t gamma = i + s * d + (d < 0 ? -1 : 0);
    const int64_t first = i < j ? i : j;
    const int64_t last = i < j ? j : i;
    const bool left_leaf = first == gamma;
    const bool right_leaf = last == gamma + 1;
    const uint32_t g = static_cast<uint32_t>(gamma);
    out.nodes[node].split = g | (left_leaf ? kLbvhLeftLeaf : 0u) | (right_leaf ? kLbvhRightLeaf : 0u);
    out.nodes[node].last = static_cast<uint32_t>(last);
    (left_leaf ? out.leaf_parent : out.internal_parent)[g] = node;
    (right_leaf ? out.leaf_parent : out.internal_parent)[g + 1] = node;
    if (node == 0) out.internal_parent[0] = kInvalidBody;
  }
}

}  // namespace impact::kernels
