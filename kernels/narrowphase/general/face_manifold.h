// The face manifold of the general convex routes (face_manifold.cpp): the contact points
// of a touching pair from its normal, depth and witnesses, shared by GJK / EPA, the
// separating axis test and the hull-cylinder kernel.
#pragma once

#include <cstdint>

#include "kernels/narrowphase/general/lane_contact.h"
#include "kernels/narrowphase/general/support.h"

namespace impact::kernels::cvx {

/// Faces of up to this many vertices are clipped into a manifold (more: the witness
/// point alone); large enough for a 64-gon prism (a cylinder as a hull) lying on a box.
inline constexpr uint32_t kMaxFaceVerts = 256;

/// The manifold of a touching pair (depth > 0) given its normal n (unit, A to B) and
/// witness points pa, pb on the cores: the clipped faces when both sides offer a flat
/// feature along n (reference face within ~26 degrees of n), else one point midway
/// between the surfaces. Sets out's count, n, depth, points and point depths.
void contact_manifold(const Leaf& A, const Leaf& B, V3 n, float depth, V3 pa, V3 pb, LaneContact* out);

/// Keeps at most 4 of n (point, depth) entries in place: the deepest, the farthest from
/// it, then the two that add most area (normal n). Returns the new count.
uint32_t reduce_manifold(V3* pts, float* depth, uint32_t n, V3 normal);

/// Face clipping can miss the deepest point: the incident face (the one most aligned
/// with the normal) need not hold the incident side's support point, and a cylinder's
/// cap is clipped as an inscribed polygon. Where no clipped point carries (1 - this) of
/// the pair's depth, the witnesses' midpoint (depth apart along the normal) joins with
/// the whole depth, if each witness lies in the other shape once moved by the depth,
/// within kWitnessReach of the depth (contact_manifold, the box-hull and the
/// hull-triangle manifolds). "Carries" allows this times the depth plus the pair's size
/// (EPA's depth on a curved side is that close to the clipped points'), so the witness
/// joins only real misses.
inline constexpr float kWitnessJoin = 1e-5f;
inline constexpr float kWitnessReach = 1e-3f;

}  // namespace impact::kernels::cvx
