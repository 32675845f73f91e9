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

/// Largest subtree a query scans leaf by leaf instead of descending into: the
/// contiguous leaf scan is cheaper than the dependent node loads it replaces (the
/// sweep of sizes behind 64: docs/history.md, "From code comments").
inline constexpr uint32_t kLbvhQueryRun = 64;

/// Queries r against tree t (t.n >= 0; filtered iff t.layer is set).
uint64_t lbvh_query(const LbvhView& t, const QueryView& q, uint32_t* IMPACT_RESTRICT out_count,
                    uint32_t* IMPACT_RESTRICT out_hits, uint64_t capacity, Range r);

}  // namespace impact::kernels
