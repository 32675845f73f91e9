// Internals of the general convex path (gjk_epa.cpp), exposed for tests: GJK on the
// leaves' cores, EPA on the cores, and the one-lane contact routine behind
// collide_gjk_epa (its manifold: face_manifold.h). Coordinates are relative to the
// origin the leaves were loaded with.
#pragma once

#include <cstdint>

#include "kernels/narrowphase/general/lane_contact.h"
#include "kernels/narrowphase/general/support.h"

namespace impact::kernels::cvx {

/// A double 3-vector for the simplex and polytope arithmetic (supports stay float).
struct D3 {
  double x, y, z;
};

/// A vertex of the Minkowski difference A - B with the support points it came from.
struct SupportPoint {
  D3 w;     // a - b
  V3 a, b;  // on A's and B's cores
};

struct Simplex {
  SupportPoint v[4];
  double lambda[4];  // barycentric weights of the closest point (sum 1)
  uint32_t n = 0;
};

struct GjkResult {
  /// Cores overlap or are closer than the touching tolerance (1e-5 of the scale).
  bool overlap = false;
  /// The lower bound v.w/|v| exceeded the margin: separated, `distance` is not exact.
  bool separated_early = false;
  float distance = 0.0f;  // |pa - pb| of the cores when !overlap
  V3 pa{0, 0, 0}, pb{0, 0, 0};  // closest points of the cores
  V3 n{0, 1, 0};  // unit, from A's core to B's core (-v/|v|), when !overlap
  Simplex simplex;
  uint32_t iterations = 0;
};

/// GJK distance of A's and B's cores (van den Bergen 1999). margin: ra + rb; a lane
/// whose distance lower bound exceeds it stops early. scale: size for the tolerances.
GjkResult gjk_cores(const Leaf& A, const Leaf& B, float margin, float scale, uint32_t max_iterations,
                    float tolerance);

struct EpaResult {
  /// 0: converged or stopped at the cap or the vertex capacity (n, depth valid); 1: the
  /// Minkowski difference of the cores is flat (dimension < 3): n is the deterministic
  /// fallback, depth 0;
  /// 2: stopped early at an inconsistent polytope (rounding) or its capacity: n, depth
  /// are the last closest face's (a lower bound).
  int status = 0;
  V3 n{0, 1, 0};       // unit, from A to B
  float depth = 0.0f;  // of the cores (may be slightly < 0 when they barely touch)
  V3 pa{0, 0, 0}, pb{0, 0, 0};  // witness points on the cores
  uint32_t iterations = 0;  // polytope expansions (a smooth pair's Newton steps not counted)
};

/// EPA on the cores, seeded with GJK's final simplex (the origin on or in it). Pairs
/// of smooth cores (sphere, ellipsoid) finish with Newton's method once EPA has
/// bracketed the depth (gjk_epa.cpp, header block, step 3). max_iterations caps the
/// expansions of pairs without a hull side; a pair with a hull expands until it
/// converges or the polytope is full (a descent cannot finish it: step 3).
EpaResult epa_cores(const Leaf& A, const Leaf& B, const Simplex& start, float scale,
                    uint32_t max_iterations, float tolerance);

/// GJK + EPA + manifold for one pair of convex leaves (neither a half-space).
void collide_convex_lane(const Leaf& A, const Leaf& B, const NarrowConfig& cfg, LaneContact* out);

}  // namespace impact::kernels::cvx
