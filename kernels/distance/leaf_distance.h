// Distance and closest points of two separated leaves (kernels/narrowphase/leaf/leaf.h
// types). Contract: coordinates are relative to the origin the leaves were loaded
// with (cvx::load_leaf), so far poses keep float precision. When separated, distance
// is the surface distance (> 0), pa lies on A's surface, pb on B's, n is unit from A
// to B and pb - pa = distance * n. overlap = true when the shapes touch or overlap
// (distance 0; pa, pb, n best effort). Half-space/half-space is rejected by the host.
// Cost: closed form for sphere-sphere and anything vs a half-space (one support call);
// GJK on the cores otherwise, O(iterations * support cost).
// Method: van den Bergen, "A Fast and Robust GJK Implementation for Collision
// Detection of Convex Objects", JGT 1999; cores plus radii as in Box2D b2ShapeDistance.
#pragma once

#include <cstdint>

#include "kernels/narrowphase/general/support.h"
#include "kernels/narrowphase/leaf/leaf.h"

namespace impact::kernels::dist {

struct LeafDistance {
  bool overlap = false;
  float distance = 0.0f;  // m, >= 0
  cvx::V3 pa{0, 0, 0}, pb{0, 0, 0};  // on A's and B's surfaces, minus origin
  cvx::V3 n{0, 1, 0};  // unit, from A to B
  uint32_t iterations = 0;  // GJK iterations (0 for closed forms)
};

/// Distance of leaves a and b; see the file header.
LeafDistance leaf_distance(const cvx::Leaf& a, const cvx::Leaf& b, const NarrowConfig& cfg);

}  // namespace impact::kernels::dist
