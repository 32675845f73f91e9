// Shared by the capsule (A) lane kernels (capsule_capsule.cpp, capsule_box.cpp,
// capsule_triangle.cpp, capsule_halfspace.cpp): the separating-axis tie tolerances and
// the two-point result. Internal to kernels/narrowphase/pairs/capsule.
#pragma once

#include "kernels/narrowphase/lanes/lane_io.h"

namespace impact::kernels::capsule_lanes {

using namespace prim;  // NOLINT: lane helpers of this kernel family

/// SAT tie tolerance: an edge axis wins over the best face axis only when shallower by
/// more than kTieRel * overlap + kTieSize * (the shapes' size) + its own rounding,
/// kEdgeRound * (size + offset) / |axis x edge| (an axis x edge direction loses
/// relative precision as the two become parallel). So resting contacts keep their face
/// normal under rounding, and the depth is the true minimum to ~1e-5 relative.
inline constexpr float kTieRel = 1e-5f;
inline constexpr float kTieSize = 1e-6f;
inline constexpr float kEdgeRound = 2e-7f;
/// |ua x ub| below this: capsule axes near-parallel enough for a 2-point manifold.
inline constexpr float kParallelSin = 0.05f;

/// |ua x ub|^2 above this: the cross product's direction is good to ~1e-2 rad (float
/// rounding / |ua x ub|), a normal for cores that meet; below it, a perpendicular of A's axis.
inline constexpr float kCrossSq = 1e-10f;

template <class F>
using L2 = Lanes<F, 2>;

/// Two candidate points p0 (depth d0) and p1 (d1) and a single fallback point pf (df):
/// the result holds both where `two`, else the fallback alone.
template <class F>
IMPACT_INLINE void finish(L2<F>& m, const V3<F>& n, F depth, typename F::Mask two, const V3<F>& p0, F d0,
                          const V3<F>& p1, F d1, const V3<F>& pf, F df) {
  const F zero(0.0f);
  const auto hit = depth > zero;
  m.n = n;
  m.depth = depth;
  m.point[0] = select(two, p0, pf);
  m.pdepth[0] = select(two, min(d0, depth), df);
  m.point[1] = p1;
  m.pdepth[1] = min(d1, depth);
  m.count = select(hit, select(two, typename F::Int(2), typename F::Int(1)), typename F::Int(0));
}

}  // namespace impact::kernels::capsule_lanes
