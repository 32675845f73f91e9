// Capsule (A) against box (B): collision data of 1 or 2 points per pair, vectorised
// across pairs (one lane = one pair).
// Method: in the box frame. (A core outside by less than its rounding takes the SAT path
// below: same depth, a well-defined axis.) The core's distance to the box is convex along
// the segment and its derivative is piecewise linear with kinks where the segment crosses
// the box's slab planes: the minimiser is found exactly by evaluating the derivative at
// those 6 kinks and interpolating. Core outside: n along the closest points, depth = r -
// distance; a segment parallel to the touching face gives the 2 ends of its clip against
// the face's side slabs. Core inside: SAT over the 3 face normals and the 3 axis x edge
// directions (exact minimum translation of a segment-swept sphere), with a tie tolerance
// favouring faces (kTieRel); face axes give the clipped ends, edge axes one point.
//
// Inputs: LeafSoA lanes per leaf.h (A a capsule: p, R column 2 = axis, e0 = radius, e1 =
// half length). Outputs: ManifoldSoA lanes of the Range, point slots 0 and 1
// (capsule_lanes.h finish). All arithmetic is relative to A's centre.
// Preconditions: finite inputs, positive radius, half lengths >= 0, unit axes.
// Cost: between capsule-half-space's ~60 and capsule-triangle's ~600 flops per pair, no
// branches on lane data except skipping work no lane of a block needs; both paths
// (kScalar, kSimd) run the same template.
#include <cstdint>

#include "kernels/narrowphase/pair_kernels.h"
#include "kernels/narrowphase/lanes/block_driver.h"
#include "kernels/narrowphase/lanes/lane_geometry.h"
#include "kernels/narrowphase/lanes/lane_io.h"
#include "kernels/narrowphase/pairs/capsule/capsule_lanes.h"

namespace impact::kernels {
namespace {

using namespace prim;           // NOLINT: lane helpers of this kernel family
using namespace capsule_lanes;  // NOLINT: tolerances and the two-point result
using simd::cross;
using simd::dot;
using simd::length_sq;

/// Sum over axes of u_k * (x_k - clamp(x_k)): half the derivative of the squared
/// distance from the segment point x = c + u*t to the box.
template <class F>
IMPACT_INLINE F dist_slope(const V3<F>& c, const V3<F>& u, const V3<F>& e, F t) {
  const V3<F> x = madd(c, t, u);
  return u.x * (x.x - clamp(x.x, -e.x, e.x)) + u.y * (x.y - clamp(x.y, -e.y, e.y)) +
         u.z * (x.z - clamp(x.z, -e.z, e.z));
}

/// Segment parameter interval where |c_j + u_j t| <= e_j, intersected into [lo, hi].
template <class F>
IMPACT_INLINE void clip_slab(F c, F u, F e, F& lo, F& hi) {
  const auto flat = abs(u) < F(1e-20f);
  const F inv = F(1.0f) / select(flat, F(1.0f), u);
  const F t0 = (-e - c) * inv, t1 = (e - c) * inv;
  const F tmin = min(t0, t1), tmax = max(t0, t1);
  const auto inside = abs(c) <= e;
  // flat and inside: no constraint; flat and outside: empty
  lo = select(flat, select(inside, lo, F(1e30f)), max(lo, tmin));
  hi = select(flat, select(inside, hi, F(-1e30f)), min(hi, tmax));
}

template <class F>
IMPACT_INLINE void capsule_box_block(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, uint32_t k) {
  using Mask = typename F::Mask;
  const V3<F> pa = load_p<F>(a, k);
  const V3<F> cb = load_p<F>(b, k) - pa;
  const M3<F> rot = load_r<F>(b, k);
  const V3<F> e = load_e<F>(b, k);
  const F ra = ld<F>(a.e[0], k), ha = ld<F>(a.e[1], k);
  const F zero(0.0f), one(1.0f), half(0.5f);
  // Capsule core in the box frame (box centre at the origin).
  const V3<F> c = rot.apply_t(-cb);
  const V3<F> u = rot.apply_t(load_axis_z<F>(a, k));

  // --- closest point of the core to the box: root of the piecewise-linear slope ---
  const F g_lo0 = dist_slope(c, u, e, -ha), g_hi0 = dist_slope(c, u, e, ha);
  F t_lo = -ha, g_lo = g_lo0, t_hi = ha, g_hi = g_hi0;
  auto visit = [&](F cc, F uu, F ee) {
    const auto flat = abs(uu) < F(1e-20f);
    const F inv = one / select(flat, one, uu);
    for (int sgn = -1; sgn <= 1; sgn += 2) {
      const F tb = clamp((F(static_cast<float>(sgn)) * ee - cc) * inv, -ha, ha);
      const F g = dist_slope(c, u, e, tb);
      const auto take_lo = andnot((g <= zero) & (tb > t_lo), flat);
      t_lo = select(take_lo, tb, t_lo);
      g_lo = select(take_lo, g, g_lo);
      const auto take_hi = andnot((g >= zero) & (tb < t_hi), flat);
      t_hi = select(take_hi, tb, t_hi);
      g_hi = select(take_hi, g, g_hi);
    }
  };
  visit(c.x, u.x, e.x);
  visit(c.y, u.y, e.y);
  visit(c.z, u.z, e.z);
  const F dg = g_hi - g_lo;
  F ts = t_lo - (t_hi - t_lo) * g_lo / select(dg > zero, dg, one);
  ts = clamp(ts, min(t_lo, t_hi), max(t_lo, t_hi));
  ts = select(g_lo0 >= zero, -ha, ts);
  ts = select(g_hi0 <= zero, ha, ts);
  const V3<F> ps = madd(c, ts, u);
  const V3<F> qs{clamp(ps.x, -e.x, e.x), clamp(ps.y, -e.y, e.y), clamp(ps.z, -e.z, e.z)};
  const V3<F> v = qs - ps;
  const F v2 = length_sq(v);
  // Core outside by more than rounding: n along the closest points. Closer than that,
  // their direction is noise; the SAT below gives the same depth (r - distance) there
  // with a well-defined axis.
  const F noise = F(kEdgeRound) * (ra + ha + e.x + e.y + e.z + abs(c.x) + abs(c.y) + abs(c.z));
  const Mask shallow = (v2 >= F(kTinySq)) & (v2 > noise * noise);
  const F dist = sqrt(v2);
  const V3<F> n_sh = v * (one / select(shallow, dist, one));

  // --- core inside: SAT over 3 faces and 3 axis x edge directions ---
  // face k: overlap = e_k + r + h|u_k| - |c_k|, n = -sign(c_k) axis_k
  const F ox = e.x + ra + ha * abs(u.x) - abs(c.x);
  const F oy = e.y + ra + ha * abs(u.y) - abs(c.y);
  const F oz = e.z + ra + ha * abs(u.z) - abs(c.z);
  const Mask fx = (ox <= oy) & (ox <= oz);
  const Mask fy = andnot(oy <= oz, fx);
  F best = select(fx, ox, select(fy, oy, oz));
  V3<F> n_dp{zero, zero, -simd::sign_nonneg(c.z)};
  n_dp = select(fy, V3<F>{zero, -simd::sign_nonneg(c.y), zero}, n_dp);
  n_dp = select(fx, V3<F>{-simd::sign_nonneg(c.x), zero, zero}, n_dp);
  Mask edge = Mask(false);
  F edge_axis(0.0f);  // which box edge direction (0, 1, 2) when `edge`
  const F size = ra + ha + e.x + e.y + e.z;
  const F lim_face = best - mul_add(F(kTieRel), abs(best), F(kTieSize) * size);
  const F edge_round = F(kEdgeRound) * (size + abs(c.x) + abs(c.y) + abs(c.z));
  auto edge_axis_try = [&](const V3<F>& l, float which) {
    const F l2 = length_sq(l);
    const Mask ok = l2 > F(1e-10f);
    const F inv = one / sqrt(select(ok, l2, one));
    const V3<F> ln = l * inv;
    const F cl = dot(c, ln);
    const F o = e.x * abs(ln.x) + e.y * abs(ln.y) + e.z * abs(ln.z) + ra - abs(cl);
    const Mask take = ok & (o < lim_face - edge_round * inv) & (o < best);
    best = select(take, o, best);
    n_dp = select(take, ln * -simd::sign_nonneg(cl), n_dp);
    edge = edge | take;
    edge_axis = select(take, F(which), edge_axis);
  };
  edge_axis_try(V3<F>{zero, u.z, -u.y}, 0.0f);  // u x e_x
  edge_axis_try(V3<F>{-u.z, zero, u.x}, 1.0f);  // u x e_y
  edge_axis_try(V3<F>{u.y, -u.x, zero}, 2.0f);  // u x e_z

  const V3<F> nl = select(shallow, n_sh, n_dp);
  const F depth = select(shallow, ra - dist, best);

  // --- face manifold: clip the core to the side slabs of the face nl points at ---
  const F ax = abs(nl.x), ay = abs(nl.y), az = abs(nl.z);
  const Mask kx = (ax >= ay) & (ax >= az);
  const Mask ky = andnot(ay >= az, kx);
  const F nk = select(kx, nl.x, select(ky, nl.y, nl.z));
  const Mask face_normal = abs(nk) > F(0.99999f);
  const Mask parallel_enough = abs(select(kx, u.x, select(ky, u.y, u.z))) < F(kParallelSin);
  const F snu = dot(nl, u);
  const F ek = select(kx, e.x, select(ky, e.y, e.z));
  F lo = -ha, hi = ha;
  {
    // Clip where the face points below meet the face, not the core: core point x(t)
    // moved along nl to the face plane x_k = -sign(n_k) e_k, a line in t. So those
    // points stay on the face even when nl leans a little off the face normal.
    const F nks = select(abs(nk) > half, nk, one);
    const F ck = select(kx, c.x, select(ky, c.y, c.z)), uk = select(kx, u.x, select(ky, u.y, u.z));
    const V3<F> cs = madd(c, (-simd::sign_nonneg(nk) * ek - ck) / nks, nl);
    const V3<F> us = madd(u, -uk / nks, nl);
    F lo_x = lo, hi_x = hi, lo_y = lo, hi_y = hi, lo_z = lo, hi_z = hi;
    clip_slab(cs.x, us.x, e.x, lo_x, hi_x);
    clip_slab(cs.y, us.y, e.y, lo_y, hi_y);
    clip_slab(cs.z, us.z, e.z, lo_z, hi_z);
    lo = select(kx, max(lo_y, lo_z), select(ky, max(lo_x, lo_z), max(lo_x, lo_y)));
    hi = select(kx, min(hi_y, hi_z), select(ky, min(hi_x, hi_z), min(hi_x, hi_y)));
  }
  // Face plane: x_k = -sign(n_k) e_k (the face of B that looks at the capsule).
  auto face_point = [&](F t, V3<F>& p, F& d) {
    // the capsule's surface along nl from core point x, then along -nl to the face
    // plane x_k = -sign(n_k) e_k
    const V3<F> on_a = madd(madd(c, t, u), capsule_exit(t, snu, ra, ha), nl);
    const F ak = select(kx, on_a.x, select(ky, on_a.y, on_a.z));
    d = (ak + simd::sign_nonneg(nk) * ek) / nk;
    p = madd(on_a, -half * d, nl);
  };
  V3<F> p0, p1;
  F d0, d1;
  face_point(lo, p0, d0);
  face_point(hi, p1, d1);
  const Mask clip_ok = hi - lo > F(1e-4f) * (ha + max(e.x, max(e.y, e.z)));
  // (a deep edge axis within 0.26 deg of a face normal is no face contact: its points
  // would be off the surfaces by that angle times the extents)
  Mask two = andnot(face_normal & clip_ok & (d0 > zero) & (d1 > zero) & (parallel_enough | ~shallow),
                    andnot(edge, shallow));
  // A deep face contact whose clip lost one end keeps the deeper end alone.
  const Mask deep_face = andnot(face_normal & clip_ok, shallow | two | edge);
  V3<F> pf;
  F df;
  {
    // shallow: midway between the closest points
    pf = (ps + qs + nl * ra) * half;
    df = depth;
    // deep, edge axis: the core against the box edge along axis `edge_axis` on the
    // side facing the capsule
    const V3<F> sgn{-simd::sign_nonneg(nl.x), -simd::sign_nonneg(nl.y), -simd::sign_nonneg(nl.z)};
    const Mask ex = edge_axis == zero, ey = edge_axis == one;
    const V3<F> emid{select(ex, zero, sgn.x * e.x), select(ey, zero, sgn.y * e.y),
                     select(andnot(~ex, ey), zero, sgn.z * e.z)};
    const V3<F> edir{select(ex, one, zero), select(ey, one, zero), select(ex | ey, zero, one)};
    const F eh = select(ex, e.x, select(ey, e.y, e.z));
    F s_seg, t_edge;
    closest_segment_segment(c, u, ha, emid, edir, eh, s_seg, t_edge);
    const V3<F> xs = madd(c, s_seg, u);
    const V3<F> xe = madd(emid, t_edge, edir);
    const V3<F> pe = (xs + xe + nl * ra) * half;
    const Mask use_edge = andnot(edge, shallow);
    pf = select(use_edge, pe, pf);
    // deep, face axis with one end clipped away: the deeper clipped end
    const Mask first = d0 >= d1;
    pf = select(deep_face, select(first, p0, p1), pf);
    df = select(deep_face, select(first, d0, d1), df);
    // deep face contact with nothing to clip (core inside the slab nowhere): core point
    const Mask deep_face_none = andnot(~shallow, edge | clip_ok);
    pf = select(deep_face_none, madd(ps, ra - half * depth, nl), pf);
  }
  two = two & (depth > zero);
  // back to the world frame, relative to A's centre
  L2<F> m;
  const V3<F> to_world = cb;
  finish(m, rot.apply(nl), depth, two, to_world + rot.apply(p0), d0, to_world + rot.apply(p1), d1,
         to_world + rot.apply(pf), df);
  store(out, k, m, pa);
}

}  // namespace

void collide_capsule_box(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, Range r,
                         const NarrowConfig& cfg) {
  IMPACT_LANE_KERNEL_BODY(capsule_box_block, 2);
}

}  // namespace impact::kernels
