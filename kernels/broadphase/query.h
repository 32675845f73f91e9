// Batched proximity queries ("what is near me") over the broad-phase structures:
// the shared vocabulary, the one hit test every structure uses, and the brute-force
// kernel (the reference path). The structure kernels are grid_query.h, sap_query.h
// and kernels/bvh/lbvh_query.h.
//
// What: for each query i in a range, every stored box the query hits, where
//   AABB  [lo, hi]  hits box B  <=>  lo <= B.max and B.min <= hi on every axis
//                                    (touching counts, as kernels::boxes_overlap);
//   point p         hits box B  <=>  B.min <= p <= B.max on every axis (the AABB
//                                    test with lo = hi = p);
//   sphere (c, r)   hits box B  <=>  dist2(c, B) <= r * r, with, in double from the
//                                    float inputs (so every structure and the tests'
//                                    reference compute the same bits):
//                      d_k   = max(B.min_k - c_k, c_k - B.max_k, 0)   k = x, y, z
//                      dist2 = fma(d_z, d_z, fma(d_y, d_y, d_x * d_x))
//                    and r * r in double (exact). Explicit fma: the compiler's FMA
//                    contraction cannot make two call sites round differently.
//   and, when the structure was built with a filter, (B.layer & mask_i) != 0 (a null
//   mask array means all ones; unfiltered structures ignore masks). The "static
//   never pairs with static" rule of the pair filter does not apply to queries.
// Order: the range r holds processing positions p; position p answers query
//   i = order[p] (QueryView::order, a permutation of the batch; null = identity). The
//   host may process queries in a spatial order (Morton order of the query centres
//   for the LBVH, sweep-axis order for sweep-and-prune) so that consecutive queries
//   reuse cached nodes and slots; the answers do not depend on it.
// Output: out_count[i] = hits of query i, for each query of the range (every entry
//   written, whatever the capacity); the hit box indices of the range's queries, in
//   processing order, each query's hits sorted ascending, at out_hits[0, capacity);
//   the return value is the range's total. Past capacity nothing more is written (the
//   host reruns the range with room), and a query cut by the capacity is left
//   unsorted. Sorted hits make the bytes independent of the structure's traversal
//   order, of the chunking and of the thread count: every structure returns the same
//   CSR for the same boxes.
// Sphere bounds: the sphere also gets a float bounding box, rounded outwards after a
//   small relative margin, used to prune (cells, nodes, sweep slabs) and as the first
//   test; a box it rejects is provably rejected by the exact test too.
// Preconditions: finite query coordinates, min <= max, radius >= 0 (validated at the
//   API), |coordinates| <= 1e18 (so bounds and cell arithmetic stay finite).
// Method: the box-sphere test is Arvo's ("A Simple Method for Box-Sphere Intersection
//   Testing", Graphics Gems 1990): the squared distance from the centre to the box,
//   summed per axis over the axes where the centre lies outside the slab.
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>

#include "kernels/broadphase/bounds.h"
#include "kernels/common/kernel.h"
#include "kernels/common/sorted_box.h"

namespace impact::kernels {

enum class QueryShape : uint32_t {
  kAabb = 0,    ///< box [x0, x1] x [y0, y1] x [z0, z1]
  kSphere = 1,  ///< centre (x0, y0, z0), radius
  kPoint = 2,   ///< point (x0, y0, z0)
};

/// n queries of one shape as SoA arrays (indexed by query number).
struct QueryView {
  QueryShape shape;
  const float* x0;  ///< AABB min / sphere centre / point
  const float* y0;
  const float* z0;
  const float* x1;  ///< AABB max (unused otherwise)
  const float* y1;
  const float* z1;
  const float* radius;    ///< sphere radius, m (unused otherwise)
  const uint32_t* mask;   ///< per query; null = all ones
  const uint32_t* order = nullptr;  ///< processing position -> query; null = identity
};

/// A query's bounding box laid out like SortedBox / LbvhNode (32 bytes, min then max
/// in 16-byte halves), so the box test against those records is one 4-lane compare
/// (kernels::records_overlap).
struct alignas(32) QueryBox {
  float min_x, min_y, min_z;
  uint32_t mask;  ///< the query's mask (lane 3: ignored by the box test)
  float max_x, max_y, max_z;
  uint32_t pad;
};
static_assert(sizeof(QueryBox) == 32);

/// One query, prepared: its bounding box (exact for AABB and point queries,
/// conservative for spheres), its mask and, for spheres, centre and r^2 in double.
struct QueryItem : QueryBox {
  double cx, cy, cz, r2;
};

/// Largest float <= v / smallest float >= v (v finite, |v| < FLT_MAX).
IMPACT_INLINE float float_down(double v) {
  float f = static_cast<float>(v);
  if (static_cast<double>(f) > v) f = std::nextafter(f, -std::numeric_limits<float>::infinity());
  return f;
}
IMPACT_INLINE float float_up(double v) {
  float f = static_cast<float>(v);
  if (static_cast<double>(f) < v) f = std::nextafter(f, std::numeric_limits<float>::infinity());
  return f;
}

template <QueryShape S>
IMPACT_INLINE QueryItem make_query_item(const QueryView& q, uint32_t i) {
  QueryItem it{};
  it.mask = q.mask ? q.mask[i] : 0xffffffffu;
  if constexpr (S == QueryShape::kAabb) {
    it.min_x = q.x0[i], it.min_y = q.y0[i], it.min_z = q.z0[i];
    it.max_x = q.x1[i], it.max_y = q.y1[i], it.max_z = q.z1[i];
  } else if constexpr (S == QueryShape::kPoint) {
    it.min_x = it.max_x = q.x0[i];
    it.min_y = it.max_y = q.y0[i];
    it.min_z = it.max_z = q.z0[i];
  } else {
    const double r = q.radius[i];
    it.cx = q.x0[i], it.cy = q.y0[i], it.cz = q.z0[i];
    it.r2 = r * r;
    // Margin 2^-50 (|c| + r) covers the double rounding of c +- r and of the exact
    // test's subtraction, so the box never rejects a box the exact test accepts.
    const double c[3] = {it.cx, it.cy, it.cz};
    float lo[3], hi[3];
    for (int k = 0; k < 3; ++k) {
      const double m = r + (std::fabs(c[k]) + r) * 0x1p-50;
      lo[k] = float_down(c[k] - m);
      hi[k] = float_up(c[k] + m);
    }
    it.min_x = lo[0], it.min_y = lo[1], it.min_z = lo[2];
    it.max_x = hi[0], it.max_y = hi[1], it.max_z = hi[2];
  }
  return it;
}

/// Squared distance from (cx, cy, cz) to box b, as documented above (0 inside).
template <class B>
IMPACT_INLINE double sphere_box_dist2(double cx, double cy, double cz, const B& b) {
  const double dx = std::max(std::max(static_cast<double>(b.min_x) - cx, cx - static_cast<double>(b.max_x)), 0.0);
  const double dy = std::max(std::max(static_cast<double>(b.min_y) - cy, cy - static_cast<double>(b.max_y)), 0.0);
  const double dz = std::max(std::max(static_cast<double>(b.min_z) - cz, cz - static_cast<double>(b.max_z)), 0.0);
  return std::fma(dz, dz, std::fma(dy, dy, dx * dx));
}

/// The hit test of query q on box b (any type with min_x .. max_z), filter aside.
template <QueryShape S, class B>
IMPACT_INLINE bool query_hits(const QueryItem& q, const B& b) {
  if constexpr (sizeof(B) == 32 && alignof(B) >= 16) {
    if (!records_overlap(static_cast<const QueryBox&>(q), b)) return false;
  } else {
    if (!boxes_overlap(q, b)) return false;
  }
  if constexpr (S == QueryShape::kSphere) return sphere_box_dist2(q.cx, q.cy, q.cz, b) <= q.r2;
  return true;
}

/// Output cursor of a query kernel: writes while there is room, counts always.
struct HitSink {
  uint32_t* out;
  uint64_t capacity;
  uint64_t k;
  IMPACT_INLINE void push(uint32_t index) {
    if (k < capacity) out[k] = index;
    ++k;
  }
};

/// Ends the query whose hits started at position k0: sorts them ascending when they
/// were all written, returns their count.
uint32_t finish_query(HitSink& sink, uint64_t k0);

/// Calls fn.template operator()<S, kFiltered>() for the view's shape.
template <class Fn>
IMPACT_INLINE void dispatch_query(QueryShape shape, bool filtered, Fn&& fn) {
  switch (shape) {
    case QueryShape::kAabb:
      filtered ? fn.template operator()<QueryShape::kAabb, true>() : fn.template operator()<QueryShape::kAabb, false>();
      break;
    case QueryShape::kSphere:
      filtered ? fn.template operator()<QueryShape::kSphere, true>()
               : fn.template operator()<QueryShape::kSphere, false>();
      break;
    case QueryShape::kPoint:
      filtered ? fn.template operator()<QueryShape::kPoint, true>() : fn.template operator()<QueryShape::kPoint, false>();
      break;
  }
}

/// Brute force: every query of r against boxes [0, n) in index order (hits come out
/// sorted). layer: per box, null when unfiltered. Cost O(n) per query; the box test
/// runs 16 boxes at a time over the SoA arrays (wide compares), the exact sphere
/// test only on boxes inside the sphere's bounding box.
uint64_t brute_force_query(AabbSoA boxes, const uint32_t* layer, uint32_t n, const QueryView& q,
                           uint32_t* IMPACT_RESTRICT out_count, uint32_t* IMPACT_RESTRICT out_hits,
                           uint64_t capacity, Range r);

}  // namespace impact::kernels
