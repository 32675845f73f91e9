// The contact manifolds of one step as SoA: what the narrow phase writes and the
// solver reads (host/contact_manifolds.h owns the storage).
//
// Manifold m (one contact region of one leaf pair):
//   pair[m]              index into the pair list the narrow phase ran on
//   a[m], b[m]           objects of the pair (body slots in a World; b[m] is a plane
//                        index when b_is_plane[m])
//   child_a[m], child_b  compound child / mesh triangle, or kNoChildIndex (both arrays
//                        null when no manifold has a child: plain shapes only)
//   normal[0..2][m]      unit, from a to b
//   depth[m] > 0         moving b by normal * depth (or a by -normal * depth) is the
//                        smallest displacement that separates the pair: the safe position
//   count[m] in 1..4     points; they are rows first_point[m] .. + count[m] of the
//                        point arrays (with first_point null, every manifold has one
//                        point and its row is m)
// Point p:
//   point[0..2][p]       world position, midway between the two surfaces
//   point_depth[p]       penetration along the normal at the point (the deepest equals depth)
//   feature[p]           the point's warm-start key within its manifold, stable while
//                        the contact persists (the general narrow phase's quadrant ids,
//                        host/narrowphase/narrow_phase.cpp; null: the slot)
// Order: manifolds in the pair list's order (then child_a, child_b), points in slot
// order, so the layout is the same for any thread count.
#pragma once

#include "kernels/common/kernel.h"

namespace impact::kernels {

inline constexpr uint32_t kNoChildIndex = 0xffffffffu;
inline constexpr uint32_t kMaxContactPoints = 4;

struct ContactManifoldArrays {
  uint32_t* pair;
  uint32_t* a;
  uint32_t* b;
  uint8_t* b_is_plane;
  uint32_t* child_a;  ///< null: every manifold's children are kNoChildIndex
  uint32_t* child_b;
  float* normal[3];
  float* depth;
  uint8_t* count;
  uint32_t* first_point;  ///< null: one point per manifold, row m
  float* point[3];
  float* point_depth;
  uint32_t* feature;  ///< null: every point's key is its slot
};

/// Row of manifold m's point 0.
IMPACT_INLINE uint32_t first_point_of(const ContactManifoldArrays& c, uint32_t m) {
  return c.first_point != nullptr ? c.first_point[m] : m;
}

/// Children of manifold m.
IMPACT_INLINE uint32_t child_a_of(const ContactManifoldArrays& c, uint32_t m) {
  return c.child_a != nullptr ? c.child_a[m] : kNoChildIndex;
}
IMPACT_INLINE uint32_t child_b_of(const ContactManifoldArrays& c, uint32_t m) {
  return c.child_b != nullptr ? c.child_b[m] : kNoChildIndex;
}

/// Feature key of point p, point slot of manifold m.
IMPACT_INLINE uint32_t feature_of(const ContactManifoldArrays& c, uint32_t m, uint32_t p) {
  return c.feature != nullptr ? c.feature[p] : p - first_point_of(c, m);
}

}  // namespace impact::kernels
