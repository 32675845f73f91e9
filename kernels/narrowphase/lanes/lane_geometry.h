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

/// How far (sine of the angle) a closest-feature direction may lie outside its normal
/// cone and be kept (project_to_cone's tolerance, times the direction's length): float
/// rounding of unit directions, with room.
inline constexpr float kNormalConeSlack = 1e-5f;

/// Closest-feature directions shorter than this times the coordinates' magnitude are put
/// back into their normal cone; longer ones lie off it by less than ~2e-5 rad (float
/// rounding / kConeReach: an overlap left of 2e-5 of the size at most), so they keep their
/// bytes and a block with none skips the work.
inline constexpr float kConeReach = 0.01f;

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

/// The closest-point direction e of a segment c + t*u (|t| <= h, unit u) to another
/// shape, from the segment's closest point (parameter t) to the other's, moved back into
/// the cone where the first-order optimality of t puts it: u.e = 0 for an interior t,
/// u.e >= 0 at t = h, u.e <= 0 at t = -h, free for a point (h = 0). Rounding breaks
/// that cone once e is as small as the coordinates' rounding (a point on the core,
/// parallel cores that meet): normalising e then gives an arbitrary direction, possibly
/// along the axis, where the overlap is larger. The returned vector is e with its u
/// component clamped into the cone (so only noise is removed; exact inputs pass through).
/// Cost: ~12 flops. Citation: the KKT conditions of the segment's closest point
/// (Ericson, Real-Time Collision Detection (2005) 5.1.2 and 5.1.9).
template <class F>
IMPACT_INLINE V3<F> into_segment_cone(const V3<F>& e, const V3<F>& u, F t, F h) {
  const F zero(0.0f);
  const F x = dot(e, u);
  const auto hi = (t >= h) & (t > -h), lo = (t <= -h) & (t < h), inside = abs(t) < h;
  const F allowed = select(hi, max(x, zero), select(lo, min(x, zero), select(inside, zero, x)));
  return madd(e, allowed - x, u);
}

/// One homogeneous constraint on a direction x: u.x >= 0 where `ge`, u.x <= 0 where `le`
/// (both: u.x = 0; neither: none), unit u. Two of them bound the cone of valid normals at
/// a closest feature (segment_half_cone, sphere_triangle.cpp).
template <class F>
struct HalfCone {
  V3<F> u;
  typename F::Mask ge, le;
};

/// The constraint into_segment_cone applies, on the direction from the segment's closest
/// point (parameter t of c + t*u, |t| <= h) to the other shape's: u.e = 0 inside, >= 0
/// at t = h, <= 0 at t = -h, none for a point. `towards` false: the same constraint on the
/// opposite direction (from the other shape to the segment).
template <class F>
IMPACT_INLINE HalfCone<F> segment_half_cone(const V3<F>& u, F t, F h, bool towards) {
  const auto hi = (t >= h) & (t > -h), lo = (t <= -h) & (t < h), inside = abs(t) < h;
  const auto ge = hi | inside, le = lo | inside;
  return towards ? HalfCone<F>{u, ge, le} : HalfCone<F>{u, le, ge};
}

/// How far x lies outside c (the length of the u component its projection would remove).
template <class F>
IMPACT_INLINE F cone_excess(const V3<F>& x, const HalfCone<F>& c) {
  const F ux = dot(x, c.u), zero(0.0f);
  return max(select(c.ge, max(-ux, zero), zero), select(c.le, max(ux, zero), zero));
}

/// The projection of x onto the cone of constraints a and b, whose planes meet along the
/// unit `line` (line.a.u = line.b.u = 0): the longest of x, x on a's plane, x on b's
/// plane and x on the line that lies inside both within tol (the Euclidean projection
/// onto a polyhedral cone is the orthogonal projection onto the span of the face holding
/// it, and |x - p|^2 = |x|^2 - |p|^2 makes it the longest feasible one; Boyd and
/// Vandenberghe, Convex Optimization (2004) 8.1). Restores a closest-feature direction
/// that rounding has pushed out of its normal cone (into_segment_cone's reason, for a
/// feature bounded by two constraints: a segment's end against another's, a triangle's
/// edge or vertex). Cost: ~60 flops.
template <class F>
IMPACT_INLINE V3<F> project_to_cone(const V3<F>& x, const HalfCone<F>& a, const HalfCone<F>& b, const V3<F>& line,
                                    F tol) {
  auto inside = [&](const V3<F>& y) IMPACT_LAMBDA_INLINE { return (cone_excess(y, a) <= tol) & (cone_excess(y, b) <= tol); };
  const V3<F> pa = madd(x, -dot(x, a.u), a.u), pb = madd(x, -dot(x, b.u), b.u);
  V3<F> best = line * dot(line, x);
  F bl = length_sq(best);
  const auto use_a = (a.ge | a.le) & inside(pa) & (length_sq(pa) > bl);
  best = select(use_a, pa, best);
  bl = select(use_a, length_sq(pa), bl);
  const auto use_b = (b.ge | b.le) & inside(pb) & (length_sq(pb) > bl);
  best = select(use_b, pb, best);
  return select(inside(x), x, best);
}

/// The Voronoi region of a triangle's closest point (closest_on_triangle): a vertex, an
/// edge's interior, or (none set) the face.
template <class F>
struct TriangleRegion {
  typename F::Mask in_a, in_b, in_c, in_ab, in_ac, in_bc;
};

/// Closest point of triangle (a, b, c) to q (Ericson 5.1.5, regions by selects; the
/// interior point is the projection onto the plane, which keeps its precision for
/// large triangles). Returns the point; reg receives each lane's region.
template <class F>
IMPACT_INLINE V3<F> closest_on_triangle(const V3<F>& a, const V3<F>& b, const V3<F>& c, const V3<F>& q,
                                        const V3<F>& unit_normal, TriangleRegion<F>& reg) {
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
  // The selects' precedence, as masks: a, b, ab, c, ac, bc.
  reg.in_a = in_a;
  reg.in_b = andnot(in_b, in_a);
  reg.in_ab = andnot(in_ab, in_a | in_b);
  reg.in_c = andnot(in_c, in_a | in_b | in_ab);
  reg.in_ac = andnot(in_ac, in_a | in_b | in_ab | in_c);
  reg.in_bc = andnot(in_bc, in_a | in_b | in_ab | in_c | in_ac);
  return r;
}

/// The same; region_face receives the interior lanes.
template <class F>
IMPACT_INLINE V3<F> closest_on_triangle(const V3<F>& a, const V3<F>& b, const V3<F>& c, const V3<F>& q,
                                        const V3<F>& unit_normal, typename F::Mask& region_face) {
  TriangleRegion<F> reg;
  const V3<F> r = closest_on_triangle(a, b, c, q, unit_normal, reg);
  region_face = ~(reg.in_a | reg.in_b | reg.in_ab | reg.in_c | reg.in_ac | reg.in_bc);
  return r;
}

/// The two constraints bounding the cone of directions from a triangle's closest point
/// (in region reg) to the point it is closest to: the face, along +-normal (two in-plane
/// equalities); an edge, across it and not inwards; a vertex, not along either edge
/// leaving it. Both constraints' planes hold the unit normal n. Edges of zero length take
/// the normal's perpendicular (a degenerate triangle's cone is not bounded here).
template <class F>
IMPACT_INLINE void triangle_half_cones(const V3<F>& a, const V3<F>& b, const V3<F>& c, const V3<F>& n,
                                       const TriangleRegion<F>& reg, HalfCone<F>& ca, HalfCone<F>& cb) {
  F l;
  const V3<F> perp = any_perpendicular(n);
  const V3<F> eab = normalize_or(b - a, perp, l), eac = normalize_or(c - a, perp, l);
  const V3<F> ebc = normalize_or(c - b, perp, l);
  // outwards across each edge, in the plane: edge x n for a counter-clockwise triangle,
  // turned away from the third vertex whatever the winding
  const auto out = [&](const V3<F>& e, const V3<F>& other) IMPACT_LAMBDA_INLINE {
    const V3<F> o = cross(e, n);
    return select(dot(o, other) > F(0.0f), -o, o);
  };
  const auto t = reg.in_a | ~reg.in_a;  // every lane
  // defaults: the face (two equalities)
  ca = {eab, t, t};
  cb = {out(eab, c - a), t, t};
  const auto edge = reg.in_ab | reg.in_ac | reg.in_bc;
  const V3<F> ee = select(reg.in_ab, eab, select(reg.in_ac, eac, ebc));
  const V3<F> eo = select(reg.in_ab, out(eab, c - a), select(reg.in_ac, out(eac, b - a), out(ebc, a - b)));
  ca.u = select(edge, ee, ca.u);
  cb.u = select(edge, eo, cb.u);
  cb.le = andnot(cb.le, edge);  // across the edge: o.x >= 0
  // vertices: x.e <= 0 along both edges leaving it
  const auto vtx = reg.in_a | reg.in_b | reg.in_c;
  const V3<F> v1 = select(reg.in_a, eab, select(reg.in_b, -eab, -eac));
  const V3<F> v2 = select(reg.in_a, eac, select(reg.in_b, ebc, -ebc));
  ca.u = select(vtx, v1, ca.u);
  cb.u = select(vtx, v2, cb.u);
  ca.ge = andnot(ca.ge, vtx);
  cb.ge = andnot(cb.ge, vtx);
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
