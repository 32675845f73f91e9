// Time of impact of two moving convex leaves (kernels/narrowphase/general/support.h).
//
// What: the first fraction t in [0, 1] of a motion at which the surfaces of A and B come
// within `target` of each other (hit when the separation is in target +- tolerance), the
// unit normal from A to B and the contact point there. Each leaf translates by Motion::v
// and rotates by the rotation vector Motion::w (angle * unit axis, rad) about its centre
// (leaf_center) over the interval, the rotation growing linearly with t.
// Method: a translating sphere against a sphere or a half-space is solved in closed form
// (the swept-sphere quadratic written without cancellation, t = c / (-b' + sqrt(b'^2 - ac)));
// every other pair uses conservative advancement (Mirtich, "Impulse-based dynamic
// simulation of rigid body systems", 1996, ch. 3) on the exact core distance of GJK
// (gjk_cores with margin +inf, minus the leaves' radii): t += (d - target) / mu with
// mu = |v_rel . n| + |w_a| r_a + |w_b| r_b, r = the largest distance of the leaf's points
// from its centre. The target/tolerance band follows Catto, "Continuous collision",
// GDC 2013. A half-space side (static or translating) uses its support-plane distance.
// Inputs: leaves relative to one origin near the pair (far poses keep precision), finite
// motions, target >= 0, tolerance > 0. Half-space vs half-space returns kFailed.
// Cost: closed form O(1); otherwise one GJK per advancement step, at most max_iterations.
#pragma once

#include <cstdint>

#include "kernels/narrowphase/general/support.h"
#include "kernels/narrowphase/leaf/leaf.h"

namespace impact::kernels::ccd {

/// Motion of a leaf over the interval [0, 1]: linear displacement (m) and rotation
/// vector (angle * unit axis, rad) about the leaf's centre.
struct Motion {
  cvx::V3 v{0, 0, 0};
  cvx::V3 w{0, 0, 0};
};

struct ToiResult {
  /// kSeparated: no hit in [0, 1]; kHit: t valid; kOverlapAtStart: separation below
  /// target - tolerance at t = 0; kFailed: the iteration cap was reached (t is the last
  /// safe fraction).
  enum State : uint8_t { kSeparated, kHit, kOverlapAtStart, kFailed } state = kSeparated;
  float t = 1.0f;
  cvx::V3 normal{0, 1, 0};  // unit, A to B, at t (kHit, kOverlapAtStart)
  cvx::V3 point{0, 0, 0};   // midway between the surfaces at t, relative to the origin
  uint32_t iterations = 0;  // advancement steps (0 for the closed forms)
};

/// Signed separation of the posed surfaces of a and b (<= 0: touching or overlapping),
/// with the normal A to B and the midpoint between the closest points.
float leaf_separation(const cvx::Leaf& a, const cvx::Leaf& b, const NarrowConfig& cfg, cvx::V3* normal,
                      cvx::V3* point);

/// Leaf l moved by the fraction t of motion m (rotation about leaf_center).
cvx::Leaf leaf_at(const cvx::Leaf& l, const Motion& m, float t);

/// Largest distance of the leaf's points from leaf_center (an upper bound for hulls).
float leaf_reach(const cvx::Leaf& l);

ToiResult time_of_impact(const cvx::Leaf& a, const Motion& ma, const cvx::Leaf& b, const Motion& mb, float target,
                         float tolerance, uint32_t max_iterations, const NarrowConfig& cfg);

}  // namespace impact::kernels::ccd
