// Fat-box pair cache of an LBVH (LbvhUpdate::kPairCache; host/broadphase/lbvh.h drives
// it, docs/lbvh.md has the rules and the measured cost).
//
// What: the tree is built over *fat* boxes (each box inflated on every side by a margin),
//   and the host keeps the set C of fat-overlapping pairs that pass the filter, as keys
//   (lo << w) | hi sorted ascending, in chunks of kLbvhCacheGrain lo indices. A frame
//   then costs one streaming pass over the boxes plus work for the boxes that left their
//   fat box (the movers), instead of a traversal for every box:
//   lbvh_cache_check   per box: its exact record (for the exact filter); a box whose
//                      exact box is no longer inside its fat box is a mover and gets a
//                      new fat box around its exact one
//   lbvh_cache_movers  the movers' indices, in the tree's leaf order
//   lbvh_cache_grow    (serial) each mover's leaf takes its new fat box and its
//                      ancestors grow to contain it (min / max unions, never shrink),
//                      stopping at the first ancestor that already does; the topology
//                      is unchanged, so every node still bounds its leaves
//   lbvh_cache_query   each mover against the tree, root down: every other leaf whose
//                      fat box overlaps its new fat box and that passes the filter, as a
//                      key; a pair of two movers once (from the lower index)
//   lbvh_cache_merge   per chunk: the old keys without a mover on either side, merged
//                      with the new keys of that chunk (sorted by the host's radix sort)
//   lbvh_cache_pairs   per chunk: the keys whose exact boxes overlap, as pairs
// Why it is exact: pairs without a mover keep both fat boxes, so their fat overlap is
//   unchanged; every pair with a mover is recomputed against the updated tree. So C is
//   always exactly the set of fat-overlapping allowed pairs, and since each exact box
//   lies inside its fat box, every exactly overlapping allowed pair is in C; the exact
//   filter keeps just those. Output order: ascending (lo, hi), whatever the history.
// Margin: box i's fat box is its box grown by m_i = fraction * max(largest edge of i,
//   floor) on each side (floor: a scene-wide minimum edge, so points get a margin too);
//   in float, min - m rounds to at most min and max + m to at least max, so the exact
//   box is always inside. A bigger margin means fewer movers but more cached pairs.
// Determinism: every pass is per index or per chunk with fixed chunking; the set C and
//   so its sorted bytes do not depend on the thread count or the order of the unions.
// Method: the fat ("enlarged") AABB and the persistent overlapping-pair cache of
//   incremental broad phases (Bullet's btDbvtBroadphase, Box2D's dynamic tree), on a
//   fixed LBVH topology with grow-only refits.
#pragma once

#include <cstdint>

#include "kernels/broadphase/bounds.h"
#include "kernels/bvh/lbvh_traverse.h"
#include "kernels/common/kernel.h"
#include "kernels/common/pair.h"
#include "kernels/common/sorted_box.h"

namespace impact::kernels {

/// Lo indices per cache chunk (chunk c holds the keys with lo in [c G, (c + 1) G)).
inline constexpr uint32_t kLbvhCacheGrain = 1u << 14;

/// Margin rule of the fat boxes: m_i = fraction * max(largest edge of box i, floor).
struct LbvhFatMargin {
  float fraction;
  float floor;
};

/// fat[i] for i in r: box i grown by its margin (index = i, pad = 0).
void lbvh_pack_fat(AabbSoA boxes, LbvhFatMargin margin, SortedBox* IMPACT_RESTRICT fat, Range r);

/// For i in r: exact[i] = box i as a record; moved[i] = 1 when box i is not inside
/// fat[i], and then fat[i] = its new fat box; else moved[i] = 0. Returns the movers in r.
uint32_t lbvh_cache_check(AabbSoA boxes, LbvhFatMargin margin, SortedBox* IMPACT_RESTRICT fat,
                          SortedBox* IMPACT_RESTRICT exact, uint8_t* IMPACT_RESTRICT moved, Range r);

/// Writes the movers among the sorted leaves s in r, i = leaf_index[s] with moved[i]
/// != 0, to out in leaf (Morton) order, and returns their count: consecutive queries
/// then walk through the same cached nodes.
uint32_t lbvh_cache_movers(const uint8_t* IMPACT_RESTRICT moved, const uint32_t* IMPACT_RESTRICT leaf_index,
                           uint32_t* IMPACT_RESTRICT out, Range r);

/// The tree's arrays that lbvh_cache_grow changes and follows.
struct LbvhGrowView {
  LbvhNode* nodes;                  ///< n - 1 internal nodes (null when n < 2)
  SortedBox* leaves;                ///< n sorted leaves
  const uint32_t* internal_parent;  ///< n - 1
  const uint32_t* leaf_parent;      ///< n
  const uint32_t* leaf_pos;         ///< n: sorted position of box i
  LbvhLanes lanes;                  ///< the leaves' lane copy, kept equal
};

/// For each of the `count` movers: its leaf takes fat[i] and its ancestors grow to
/// contain it. Serial (the unions' bytes do not depend on the order).
void lbvh_cache_grow(const LbvhGrowView& t, const SortedBox* fat, const uint32_t* movers, uint32_t count);

/// Movers movers[r] against tree t (n >= 2; leaves are fat boxes): keys
/// (lo << key_shift) | hi of every allowed pair (mover, other) whose fat boxes
/// overlap, other != mover, skipping others that are movers with a lower index.
/// Writes the first `capacity` keys to out and returns the count.
uint64_t lbvh_cache_query(const LbvhView& t, const uint32_t* leaf_pos, const SortedBox* fat,
                          const uint8_t* moved, const uint32_t* movers, uint32_t key_shift,
                          uint64_t* IMPACT_RESTRICT out, uint64_t capacity, Range r);

/// old_keys without the keys that have a mover on either side, merged with new_keys
/// (both sorted ascending, disjoint), into out (room for old + new); returns the count.
uint64_t lbvh_cache_merge(const uint64_t* old_keys, uint64_t old_count, const uint64_t* new_keys,
                          uint64_t new_count, const uint8_t* moved, uint32_t key_shift,
                          uint64_t* IMPACT_RESTRICT out);

/// The keys whose exact boxes overlap (touching included), as pairs in key order.
/// Writes the first `capacity` to out and returns the count.
uint64_t lbvh_cache_pairs(const uint64_t* keys, uint64_t count, const SortedBox* exact, uint32_t key_shift,
                          Pair* IMPACT_RESTRICT out, uint64_t capacity);

}  // namespace impact::kernels
