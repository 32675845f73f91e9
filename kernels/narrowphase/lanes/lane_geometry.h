// Lane geometry of the specialised narrow-phase kernels (kernels/narrowphase/pairs/): the
// closest point on a segment, the closest points of two segments (robust for parallel
// ones), the closest point on a triangle and its normal, a deterministic perpendicular
// for degenerate normals, a capsule's surface along a direction from a core point, and a
// 2-D segment clipped to a disk. Templates over the lane type F (simd::FloatW or
// simd::Float1); no branches on lane data.
// Citation: Ericson, Real-Time Collision Detection (2005) 5.1.2, 5.1.5, 5.1.9.
#pragma once

#include <cfloat>
#include <cstdint>

#include "kernels/simd/lanes.h"
#include "kernels/simd/vec3.h"

namespace impact::kernels::prim {

using simd::M3;
using simd::V3;

/// Squared lengths below this are treated as zero (normalising them would lose all
/// precision): the smallest normal float.
inline constexpr float kTinySq = FLT_MIN;

/// A unit vector perpendicular to unit u, chosen deterministically: u x (the world axis
/// least aligned with u).
template <class F>
IMPACT_INLINE V3<F> any_perpendicular(const V3<F>& u) {
  const F ax = abs(u.x), ay = abs(u.y), az = abs(u.z);
  const auto use_x = (ax <= ay) & (ax <= az);
  const auto use_y = andnot(ay <= az, use_x);
  // u x e_x = (0, uz, -uy); u x e_y = (-uz, 0, ux); u x e_z = (uy, -ux, 0)
  const F zero(0.0f);
  V3<F> c = {u.y, -u.x, zero};
  c = select(use_y, V3<F>{-u.z, zero, u.x}, c);
  c = select(use_x, V3<F>{zero, u.z, -u.y}, c);
  const F inv = F(1.0f) / sqrt(length_sq(c));
  return c * inv;
}

/// v / |v|, or fallback where |v|^2 < kTinySq. len receives |v| (0 where fallback).
template <class F>
IMPACT_INLINE V3<F> normalize_or(const V3<F>& v, const V3<F>& fallback, F& len) {
  const F l2 = length_sq(v);
  const auto ok = l2 >= F(kTinySq);
  const F l = sqrt(l2);
  const F inv = F(1.0f) / select(ok, l, F(1.0f));
  len = select(ok, l, F(0.0f));
  return select(ok, v * inv, fallback);
}

/// Parameter t in [-h, h] of the point of segment c + t*u (u unit) closest to q.
template <class F>
IMPACT_INLINE F closest_on_segment(const V3<F>& c, const V3<F>& u, F h, const V3<F>& q) {
  return clamp(dot(q - c, u), -h, h);
}

/// Distance lambda from the core point at axial parameter t (|t| <= h) along unit
/// direction n (s = n.axis) to the capsule's surface: through the cylinder, or through
/// an end cap where the cylinder exit would lie beyond the segment (capsule-capsule, -box,
/// -triangle, -half-space, -cylinder manifolds).
template <class F>
IMPACT_INLINE F capsule_exit(F t, F s, F r, F h) {
  const F c2 = max(F(1.0f) - s * s, F(1e-12f));  // sin^2 of the angle to the axis
  const F lc = r / sqrt(c2);
  const F ax = mul_add(lc, s, t);
  const auto over = ax > h, under = ax < -h;
  const F delta = select(over, t - h, t + h);  // from the cap's centre
  const F disc = max(r * r - delta * delta * c2, F(0.0f));
  const F lcap = sqrt(disc) - delta * s;
  return select(over | under, lcap, lc);
}

/// Closest points of segments A: pa + s*ua, s in [-ha, ha] and B: pb + t*ub, t in
/// [-hb, hb] (ua, ub unit). Robust for parallel and degenerate (h = 0) segments: with
/// near-parallel axes s is the middle of the overlap of B's projection onto A
/// (Ericson, Real-Time Collision Detection 5.1.9, with that parallel rule).
template <class F>
IMPACT_INLINE void closest_segment_segment(const V3<F>& pa, const V3<F>& ua, F ha, const V3<F>& pb,
                                           const V3<F>& ub, F hb, F& s, F& t) {
  const V3<F> r = pa - pb;
  const F b = dot(ua, ub);
  const F c = dot(ua, r);
  const F f = dot(ub, r);
  const F denom = length_sq(cross(ua, ub));  // 1 - b^2 without cancellation
  const auto parallel = denom < F(1e-10f);
  // Non-parallel: the unconstrained minimiser's s, clamped.
  const F s_gen = clamp((b * f - c) / select(parallel, F(1.0f), denom), -ha, ha);
  // Parallel: middle of [-ha, ha] intersected with B's projection [-c - |b|hb, -c + |b|hb].
  const F ext = abs(b) * hb;
  const F lo = max(-ha, -c - ext), hi = min(ha, -c + ext);
  const F s_par = clamp(F(0.5f) * (lo + hi), -ha, ha);
  s = select(parallel, s_par, s_gen);
  const F t_raw = mul_add(b, s, f);
  t = clamp(t_raw, -hb, hb);
  const F s_back = clamp(mul_add(b, t, -c), -ha, ha);
  s = select(t_raw != t, s_back, s);
}

/// Closest point of triangle (a, b, c) to q (Ericson 5.1.5, regions by selects; the
/// interior point is the projection onto the plane, which keeps its precision for
/// large triangles). Returns the point; region_face receives the interior lanes.
template <class F>
IMPACT_INLINE V3<F> closest_on_triangle(const V3<F>& a, const V3<F>& b, const V3<F>& c, const V3<F>& q,
                                        const V3<F>& unit_normal, typename F::Mask& region_face) {
  const V3<F> ab = b - a, ac = c - a, bc = c - b;
  const V3<F> ap = q - a, bp = q - b, cp = q - c;
  const F d1 = dot(ab, ap), d2 = dot(ac, ap);
  const F d3 = dot(ab, bp), d4 = dot(ac, bp);
  const F d5 = dot(ab, cp), d6 = dot(ac, cp);
  const F zero(0.0f), one(1.0f);
  const F vc = d1 * d4 - d3 * d2;
  const F vb = d5 * d2 - d1 * d6;
  const F va = d3 * d6 - d5 * d4;
  const auto in_a = (d1 <= zero) & (d2 <= zero);
  const auto in_b = (d3 >= zero) & (d4 <= d3);
  const auto in_ab = (vc <= zero) & (d1 >= zero) & (d3 <= zero);
  const auto in_c = (d6 >= zero) & (d5 <= d6);
  const auto in_ac = (vb <= zero) & (d2 >= zero) & (d6 <= zero);
  const auto in_bc = (va <= zero) & ((d4 - d3) >= zero) & ((d5 - d6) >= zero);
  // Edge points by projection onto the edge (accurate), clamped.
  const F lab = length_sq(ab), lac = length_sq(ac), lbc = length_sq(bc);
  const F tab = clamp(d1 / select(lab > zero, lab, one), zero, one);
  const F tac = clamp(d2 / select(lac > zero, lac, one), zero, one);
  const F tbc = clamp(dot(bc, bp) / select(lbc > zero, lbc, one), zero, one);
  V3<F> r = q - unit_normal * dot(unit_normal, ap);
  r = select(in_bc, madd(b, tbc, bc), r);
  r = select(in_ac, madd(a, tac, ac), r);
  r = select(in_c, c, r);
  r = select(in_ab, madd(a, tab, ab), r);
  r = select(in_b, b, r);
  r = select(in_a, a, r);
  region_face = ~(in_a | in_b | in_ab | in_c | in_ac | in_bc);
  return r;
}

/// Unit normal of triangle (a, b, c) (counter-clockwise); for a degenerate triangle a
/// unit vector perpendicular to its longest edge (or +z for a point).
template <class F>
IMPACT_INLINE V3<F> triangle_normal(const V3<F>& a, const V3<F>& b, const V3<F>& c) {
  const V3<F> ab = b - a, ac = c - a, bc = c - b;
  const V3<F> nrm = cross(ab, ac);
  F l;
  // Fallback: perpendicular to the longest edge.
  const F lab = length_sq(ab), lac = length_sq(ac), lbc = length_sq(bc);
  V3<F> e = select(lab >= lac, ab, ac);
  e = select(lbc > max(lab, lac), bc, e);
  F el;
  const V3<F> eu = normalize_or(e, V3<F>{F(0.0f), F(0.0f), F(1.0f)}, el);
  return normalize_or(nrm, any_perpendicular(eu), l);
}

/// The part t0 <= t1 of the 2-D segment a0 + a1 t, |t| <= h, inside the disk |p| <= r
/// (a quadratic in t); false where it is empty. A segment that does not move (|a1|^2 below
/// kTinySq) is inside or not as a whole.
template <class F>
IMPACT_INLINE typename F::Mask clip_segment_disk(F a0x, F a0y, F a1x, F a1y, F r, F h, F& t0, F& t1) {
  const F zero(0.0f), one(1.0f);
  const F qa = a1x * a1x + a1y * a1y, qb = a0x * a1x + a0y * a1y;
  const F qc = a0x * a0x + a0y * a0y - r * r;
  const F disc = qb * qb - qa * qc;
  const auto moving = qa > F(kTinySq);
  const F root = sqrt(max(disc, zero)), ia = one / select(moving, qa, one);
  t0 = max(select(moving, (-qb - root) * ia, -h), -h);
  t1 = min(select(moving, (root - qb) * ia, h), h);
  return select(moving, disc >= zero, qc <= zero) & (t0 <= t1);
}

}  // namespace impact::kernels::prim
