// Batched AABB / sphere / point queries over an LBVH (lbvh_build.h, bounds by
// lbvh_refit.h). Hit rules, output layout and order: kernels/broadphase/query.h.
//
// What: per query i in r, a depth-first descent from the root with a fixed stack:
//   at each internal node popped, each child is tested against the query's bounding
//   box (and, for spheres, with the exact box-sphere distance: a node's distance is
//   never larger than that of a box inside it, in the same rounding, so pruning
//   cannot lose a hit); a child of at most kLbvhQueryRun leaves that passes has its
//   leaves (contiguous sorted records) each go through query_hits and the mask,
//   bigger children that pass are pushed. The hits are then sorted by box index.
// Stack: kLbvhMaxDepth + 1 entries (the depth bound of lbvh_build.h), so it never
//   overflows.
// Cost: O(log n + k) node tests for a small query (k = hits), O(n) for a query that
//   covers everything; plus k log k to sort the hits. One leaf (n == 1) is tested
//   directly; n == 0 gives no hits.
// Inputs: the tree built and refitted for its boxes; finite queries.
// Method: the per-query stack traversal of a BVH as in Karras, "Thinking Parallel,
//   Part II: Tree Traversal on the GPU" (NVIDIA blog, 2012), with a top-down start
//   (the query is not a leaf of the tree).
#pragma once

#include "kernels/broadphase/query.h"
#include "kernels/bvh/lbvh_build.h"
#include "kernels/bvh/lbvh_traverse.h"
#include "kernels/common/kernel.h"

namespace impact::kernels {

/// Largest subtree a query scans leaf by leaf instead of descending into. Measured
/// (BM_QueryLbvh{Aabb,Sphere,Point}/1000000/1, ms for 16,384 queries, 2026-11-24):
/// descending to single leaves 21.6 / 28.4 / 14.4; scanning subtrees of up to 8
/// leaves 19.0 / 24.9 / 14.4, 16: 15.6 / 20.0 / 11.7, 32: 13.4 / 17.7 / 10.5,
/// 64: 12.6 / 15.6 / 9.76, 128: 11.6 / 14.0 / 9.09 (but point queries at 10k boxes
/// 3.20 against 2.87 ms at 64).
inline constexpr uint32_t kLbvhQueryRun = 64;

/// Queries r against tree t (t.n >= 0; filtered iff t.layer is set).
uint64_t lbvh_query(const LbvhView& t, const QueryView& q, uint32_t* IMPACT_RESTRICT out_count,
                    uint32_t* IMPACT_RESTRICT out_hits, uint64_t capacity, Range r);

}  // namespace impact::kernels
