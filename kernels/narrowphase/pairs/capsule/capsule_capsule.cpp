// Capsule (A) against capsule, box, triangle and half-space (B): collision data of
// 1 or 2 points per pair, vectorised across pairs (one lane = one pair).
//
// Inputs: LeafSoA lanes per leaf.h (A a capsule: p, R column 2 = axis, e0 = radius,
// e1 = half length). Outputs: ManifoldSoA lanes of the Range, point slots 0 and 1.
// Methods (all relative to A's centre):
//  capsule-capsule  closest points of the two core segments (Ericson 5.1.9, with a
//                   parallel rule: middle of the overlap); near-parallel axes whose
//                   projections overlap give the 2 ends of the overlap interval, so a
//                   capsule lying on another rests on two points. Closest points
//                   inside both segments (|ua x ub| > 1e-3): n = +-ua x ub, exact
//                   where qb - qa is rounding noise (cores crossing); axes that meet
//                   and are parallel: a perpendicular.
//  capsule-box      in the box frame. (A core outside by less than its rounding
//                   takes the SAT path below: same depth, a well-defined axis.) The core's distance to the box is convex along
//                   the segment and its derivative is piecewise linear with kinks
//                   where the segment crosses the box's slab planes: the minimiser is
//                   found exactly by evaluating the derivative at those 6 kinks and
//                   interpolating. Core outside: n along the closest points, depth =
//                   r - distance; a segment parallel to the touching face gives the 2
//                   ends of its clip against the face's side slabs. Core inside: SAT
//                   over the 3 face normals and the 3 axis x edge directions (exact
//                   minimum translation of a segment-swept sphere), with a tie
//                   tolerance favouring faces (kTieRel); face axes give the clipped
//                   ends, edge axes one point.
//  capsule-triangle two-sided triangle. Core outside: closest points of segment and
//                   triangle (endpoints vs triangle, segment vs edges); the normal is
//                   the face normal when an end point over the face's interior wins,
//                   and axis x edge when the segment's and an edge's interiors do (the
//                   points' difference has only rounding / gap precision); a segment
//                   parallel to the face gives 2 points clipped to the triangle's
//                   prism. Core crossing the triangle, or within the inputs' rounding
//                   of it: SAT over the face normal and the 3 axis x edge directions.
//  capsule-halfspace the capsule's surface below each core endpoint (along the
//                   normal), where below the plane; one point when the capsule
//                   stands steep (both lines leave through the lower end's cap).
// Preconditions: finite inputs, positive radius, half lengths >= 0, unit axes,
// non-degenerate triangles for a meaningful face normal (degenerate ones still give
// finite output). Cost: 60 (half-space) to ~600 (triangle) flops per pair, no
// branches on lane data except skipping work no lane of a block needs.
#include <cstdint>

#include "kernels/narrowphase/pair_kernels.h"
#include "kernels/narrowphase/lanes/primitives.h"

namespace impact::kernels {
namespace {

using namespace prim;  // NOLINT: lane helpers of this kernel family
using simd::cross;
using simd::dot;
using simd::length_sq;

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

template <class F>
using L2 = Lanes<F, 2>;

/// Where the line o + n * lambda (unit n, travelling along +n) enters the capsule with
/// core cb + ub * t (|t| <= hb, unit ub) and radius rb: the smallest lambda on its
/// surface (cylinder or cap); `met` is false in lanes where the line misses it.
template <class F>
IMPACT_INLINE F capsule_entry(const V3<F>& o, const V3<F>& n, const V3<F>& cb, const V3<F>& ub, F hb, F rb,
                              typename F::Mask& met) {
  const F zero(0.0f), one(1.0f), far(3.0e38f);
  const V3<F> w = o - cb;
  const F wu = dot(w, ub), nu = dot(n, ub);
  const V3<F> wp = madd(w, -wu, ub), np = madd(n, -nu, ub);  // across the axis
  const F a = length_sq(np), b = dot(wp, np), c = length_sq(wp) - rb * rb;
  const F disc = b * b - a * c;
  const auto across = (a > F(1e-12f)) & (disc >= zero);
  const F lc = (-b - sqrt(max(disc, zero))) / select(a > F(1e-12f), a, one);
  const auto cyl = across & (abs(mul_add(nu, lc, wu)) <= hb);
  F best = select(cyl, lc, far);
  met = cyl;
  for (int sgn = -1; sgn <= 1; sgn += 2) {
    const V3<F> m = madd(w, F(static_cast<float>(-sgn)) * hb, ub);  // from the cap's centre
    const F mn = dot(m, n);
    const F d2 = mn * mn - (length_sq(m) - rb * rb);
    const auto ok = d2 >= zero;
    const F ls = -mn - sqrt(max(d2, zero));
    best = select(ok & (ls < best), ls, best);
    met = met | ok;
  }
  return best;
}

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

// ---------------------------------------------------------------------------------------
// capsule - capsule
// ---------------------------------------------------------------------------------------

template <class F>
IMPACT_INLINE void capsule_capsule_block(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, uint32_t k) {
  const V3<F> pa = load_p<F>(a, k);
  const V3<F> cb = load_p<F>(b, k) - pa;
  const V3<F> ua = load_axis_z<F>(a, k), ub = load_axis_z<F>(b, k);
  const F ra = ld<F>(a.e[0], k), ha = ld<F>(a.e[1], k);
  const F rb = ld<F>(b.e[0], k), hb = ld<F>(b.e[1], k);
  const F zero(0.0f), half(0.5f);
  const V3<F> ca{zero, zero, zero};
  F s, t;
  closest_segment_segment(ca, ua, ha, cb, ub, hb, s, t);
  const V3<F> qa = ua * s;
  const V3<F> qb = madd(cb, t, ub);
  // Fallback normal where the axes meet: ua x ub towards B (or any perpendicular).
  const V3<F> c = cross(ua, ub);
  const F c2 = length_sq(c);
  F cl;
  const V3<F> cu = normalize_or(c, any_perpendicular(ua), cl);
  const V3<F> fb = select(dot(cu, cb) < zero, -cu, cu);
  const V3<F> dq = qb - qa;
  F dist;
  V3<F> n = normalize_or(dq, fb, dist);
  // Closest points inside both segments: qb - qa is along ua x ub exactly, so take that
  // direction (oriented by qb - qa, or towards B where qb - qa is rounding noise): from
  // qb - qa alone it turns by rounding / |qb - qa| as the cores come to cross.
  {
    const F dc = dot(cu, dq);
    const F noise = F(kEdgeRound) * (ha + hb + abs(cb.x) + abs(cb.y) + abs(cb.z));
    // |ua x ub| > 1e-3: its direction is good to ~1e-4 rad (float rounding / |ua x ub|)
    const auto inner = (abs(s) < ha) & (abs(t) < hb) & (c2 > F(1e-6f));
    const V3<F> nc = select(abs(dc) > noise, select(dc < zero, -cu, cu), fb);
    n = select(inner, nc, n);
    dist = select(inner, abs(dc), dist);
  }
  const F rs = ra + rb;
  const F depth = rs - dist;
  const V3<F> pf = (qa + qb + n * (ra - rb)) * half;

  // Near-parallel: the ends of the overlap of B's projection onto A's axis.
  const F sb = dot(cb, ua), eb = abs(dot(ub, ua)) * hb;
  const F lo = max(-ha, sb - eb), hi = min(ha, sb + eb);
  const auto par = (c2 < F(kParallelSin * kParallelSin)) & (hi - lo > F(1e-4f) * (ha + hb));
  const F sna = dot(n, ua), snb = -dot(n, ub);
  auto end_point = [&](F sa, V3<F>& p, F& d) IMPACT_LAMBDA_INLINE {
    const V3<F> xa = ua * sa;
    const F tb = closest_on_segment(cb, ub, hb, xa);
    const V3<F> xb = madd(cb, tb, ub);
    // the surfaces along n from the two core points
    // B's surface on the same line along n (where it enters B from A's side), so both
    // surface points lie on one line along n even when the axes are not exactly
    // parallel; from B's closest core point where that line misses B.
    const V3<F> on_a = madd(xa, capsule_exit(sa, sna, ra, ha), n);
    typename F::Mask met;
    const F lb = capsule_entry(xa, n, cb, ub, hb, rb, met);
    const V3<F> on_b = select(met, madd(xa, lb, n), madd(xb, -capsule_exit(tb, snb, rb, hb), n));
    d = dot(n, on_a - on_b);
    p = (on_a + on_b) * half;
  };
  V3<F> p0, p1;
  F d0, d1;
  end_point(lo, p0, d0);
  end_point(hi, p1, d1);
  const auto two = par & (d0 > zero) & (d1 > zero);
  L2<F> m;
  finish(m, n, depth, two, p0, d0, p1, d1, pf, depth);
  store(out, k, m, pa);
}

// ---------------------------------------------------------------------------------------
// capsule - box
// ---------------------------------------------------------------------------------------

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

// ---------------------------------------------------------------------------------------
// capsule - triangle
// ---------------------------------------------------------------------------------------

template <class F>
IMPACT_INLINE void capsule_triangle_block(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out,
                                          uint32_t k) {
  using Mask = typename F::Mask;
  const V3<F> pa = load_p<F>(a, k);
  const V3<F> u = load_axis_z<F>(a, k);
  const F ra = ld<F>(a.e[0], k), ha = ld<F>(a.e[1], k);
  const V3<F> v[3] = {load_p<F>(b, k) - pa, load_w<F>(b, k, 0) - pa, load_w<F>(b, k, 3) - pa};
  const F zero(0.0f), one(1.0f), half(0.5f);
  const V3<F> c{zero, zero, zero};
  const V3<F> nf = triangle_normal(v[0], v[1], v[2]);

  // --- closest points of the core segment and the triangle ---
  // Also which feature pair won, so that a short gap takes its normal from the
  // features rather than from the difference of two nearly equal points: an end point
  // over the face's interior -> the face normal; a segment interior against an edge
  // interior -> their common perpendicular u x edge.
  Mask face0, face1;
  const V3<F> e0 = u * (-ha), e1 = u * ha;
  V3<F> bp = e0, bq = closest_on_triangle(v[0], v[1], v[2], e0, nf, face0);
  F bd = length_sq(bq - bp);
  Mask by_face = face0, by_edge = Mask(false);
  V3<F> edge_axis = nf;
  auto consider = [&](const V3<F>& p, const V3<F>& q, Mask is_face, Mask is_edge, const V3<F>& axis) {
    const F d = length_sq(q - p);
    const Mask take = d < bd;
    bd = select(take, d, bd);
    bp = select(take, p, bp);
    bq = select(take, q, bq);
    by_face = select(take, is_face, by_face);
    by_edge = select(take, is_edge, by_edge);
    edge_axis = select(take, axis, edge_axis);
  };
  const V3<F> q1 = closest_on_triangle(v[0], v[1], v[2], e1, nf, face1);
  consider(e1, q1, face1, Mask(false), nf);
  V3<F> ed[3], em[3];
  F eh[3];
  for (int i = 0; i < 3; ++i) {
    const V3<F> d = v[(i + 1) % 3] - v[i];
    F len;
    ed[i] = normalize_or(d, V3<F>{one, zero, zero}, len);
    eh[i] = half * len;
    em[i] = (v[i] + v[(i + 1) % 3]) * half;
    F s, t;
    closest_segment_segment(c, u, ha, em[i], ed[i], eh[i], s, t);
    const V3<F> l = cross(u, ed[i]);
    const F l2 = length_sq(l);
    const Mask interior = (abs(s) < ha) & (abs(t) < eh[i]) & (l2 > F(1e-10f));
    consider(u * s, madd(em[i], t, ed[i]), Mask(false), interior, l * (one / sqrt(select(interior, l2, one))));
  }
  // segment crossing the triangle's interior
  const F hc = -dot(nf, v[0]);  // height of the centre above the plane
  const F hu = dot(nf, u);
  const F h0 = hc - hu * ha, h1 = hc + hu * ha;
  const Mask crosses_plane = ((h0 <= zero) & (h1 >= zero)) | ((h0 >= zero) & (h1 <= zero));
  const F tc = clamp(-hc / select(abs(hu) > F(1e-30f), hu, one), -ha, ha);
  const V3<F> xc = u * tc;
  Mask inside = crosses_plane;
  for (int i = 0; i < 3; ++i)
    inside = inside & (dot(cross(v[(i + 1) % 3] - v[i], xc - v[i]), nf) >= zero);
  bp = select(inside, xc, bp);
  bq = select(inside, xc, bq);
  bd = select(inside, zero, bd);

  // A gap within the rounding of the inputs has no reliable direction, not even its
  // sign: such lanes take the SAT below, as capsule-box does.
  const F size = ra + ha + eh[0] + eh[1] + eh[2];
  const F edge_round = F(kEdgeRound) * (size + abs(v[0].x) + abs(v[0].y) + abs(v[0].z));
  const Mask shallow = (bd >= F(kTinySq)) & (bd > edge_round * edge_round);
  const F dist = sqrt(bd);
  const V3<F> gap = bq - bp;
  V3<F> n_sh = gap * (one / select(shallow, dist, one));
  const V3<F> feature_axis = select(by_face, nf, edge_axis);
  const V3<F> n_feat = select(dot(feature_axis, gap) >= zero, feature_axis, -feature_axis);
  n_sh = select(by_face | by_edge, n_feat, n_sh);

  // --- core crossing: SAT over the face normal and 3 axis x edge directions ---
  // overlap along unit l: capsule [l.c - ha|u.l| - r, + ...] vs triangle [min l.v, max l.v]
  F best(3.0e38f);
  V3<F> n_dp = nf;
  Mask edge_win = Mask(false);
  F edge_which(0.0f);
  F lim_face(0.0f);  // set after the face axis: an edge axis must be below it
  auto axis = [&](const V3<F>& l, Mask ok, bool is_edge, float which, F round) {
    const F t0 = dot(l, v[0]), t1 = dot(l, v[1]), t2 = dot(l, v[2]);
    const F tmin = min(t0, min(t1, t2)), tmax = max(t0, max(t1, t2));
    const F ext = ha * abs(dot(l, u)) + ra;
    const F o_pos = ext - tmin;  // move the triangle along +l
    const F o_neg = tmax + ext;  // move the triangle along -l
    const Mask pos = o_pos <= o_neg;
    const F o = min(o_pos, o_neg);
    const Mask take = is_edge ? ok & (o < best) & (o < lim_face - round) : ok;
    best = select(take, o, best);
    n_dp = select(take, select(pos, l, -l), n_dp);
    if (is_edge) {
      edge_win = select(take, Mask(true), edge_win);
      edge_which = select(take, F(which), edge_which);
    }
  };
  axis(nf, Mask(true), false, 0.0f, zero);
  lim_face = best - mul_add(F(kTieRel), abs(best), F(kTieSize) * size);
  for (int i = 0; i < 3; ++i) {
    const V3<F> l = cross(u, ed[i]);
    const F l2 = length_sq(l);
    const Mask ok = l2 > F(1e-10f);
    const F inv = one / sqrt(select(ok, l2, one));
    axis(l * inv, ok, true, static_cast<float>(i), edge_round * inv);
  }
  const V3<F> n = select(shallow, n_sh, n_dp);
  const F depth = select(shallow, ra - dist, best);

  // --- face manifold: clip the core to the triangle's prism ---
  const F nn = dot(n, nf);
  const Mask face_normal = abs(nn) > F(0.99999f);
  // Clip where the face points below meet the triangle's plane, not the core: core
  // point u t moved along n to the plane, a line in t. So those points stay inside the
  // triangle even when n leans a little off the face normal.
  const F nns = select(abs(nn) > F(0.5f), nn, one);
  const V3<F> cs = madd(c, dot(nf, v[0] - c) / nns, n);
  const V3<F> us = madd(u, -dot(nf, u) / nns, n);
  F lo = -ha, hi = ha;
  for (int i = 0; i < 3; ++i) {
    // inward edge normal m: m.(x - v_i) >= 0 inside
    const V3<F> mi = cross(nf, ed[i]);
    const F a0 = dot(mi, cs - v[i]);  // at t = 0
    const F a1 = dot(mi, us);        // per unit t
    const Mask flat = abs(a1) < F(1e-20f);
    const F tcut = -a0 / select(flat, one, a1);
    lo = select(flat, select(a0 >= zero, lo, F(1e30f)), select(a1 > zero, max(lo, tcut), lo));
    hi = select(flat, select(a0 >= zero, hi, F(-1e30f)), select(a1 < zero, min(hi, tcut), hi));
  }
  const F snu = dot(n, u);
  auto face_point = [&](F t, V3<F>& p, F& d) {
    // the capsule's surface along n from core point u*t, then along -n to the plane
    const V3<F> on_a = madd(u * t, capsule_exit(t, snu, ra, ha), n);
    d = dot(nf, on_a - v[0]) / select(abs(nn) > F(0.5f), nn, one);
    p = madd(on_a, -half * d, n);
  };
  V3<F> p0, p1;
  F d0, d1;
  face_point(lo, p0, d0);
  face_point(hi, p1, d1);
  const Mask clip_ok = hi - lo > F(1e-4f) * ha;
  const Mask parallel_enough = abs(hu) < F(kParallelSin);
  const Mask two = andnot(
      face_normal & clip_ok & (d0 > zero) & (d1 > zero) & (parallel_enough | ~shallow) & (depth > zero),
      andnot(edge_win, shallow));
  // single point
  V3<F> pf = (bp + bq + n * ra) * half;
  F df = depth;
  {
    // deep, face axis: the deeper clipped end (inside the prism)
    const Mask deep_face = andnot(face_normal & clip_ok, shallow | edge_win);
    const Mask first = d0 >= d1;
    pf = select(deep_face, select(first, p0, p1), pf);
    df = select(deep_face, select(first, d0, d1), df);
    // deep, edge axis: the core against that edge
    const Mask deep_edge = andnot(edge_win, shallow);
    const Mask w0 = edge_which == zero, w1 = edge_which == one;
    const V3<F> emid = select(w0, em[0], select(w1, em[1], em[2]));
    const V3<F> edir = select(w0, ed[0], select(w1, ed[1], ed[2]));
    const F ehl = select(w0, eh[0], select(w1, eh[1], eh[2]));
    F s, t;
    closest_segment_segment(c, u, ha, emid, edir, ehl, s, t);
    const V3<F> xs = u * s;
    pf = select(deep_edge, madd(xs, ra - half * depth, n), pf);
    // deep, face axis, nothing inside the prism: the crossing point
    const Mask deep_none = andnot(~shallow, edge_win | clip_ok);
    pf = select(deep_none, madd(bp, ra - half * depth, n), pf);
  }
  L2<F> m;
  finish(m, n, depth, two, p0, d0, p1, d1, pf, df);
  store(out, k, m, pa);
}

// ---------------------------------------------------------------------------------------
// capsule - half-space
// ---------------------------------------------------------------------------------------

template <class F>
IMPACT_INLINE void capsule_halfspace_block(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out,
                                           uint32_t k) {
  const V3<F> pa = load_p<F>(a, k);
  const V3<F> q = load_p<F>(b, k) - pa;
  const V3<F> nh = load_e<F>(b, k);
  const V3<F> u = load_axis_z<F>(a, k);
  const F ra = ld<F>(a.e[0], k), ha = ld<F>(a.e[1], k);
  const F zero(0.0f), half(0.5f);
  const F hc = -dot(nh, q);       // centre height above the plane
  const F hu = dot(nh, u) * ha;   // endpoint offset
  const V3<F> n = -nh;
  // the capsule's surface along n from each endpoint (its cap, or the cylinder when n
  // leans back along the axis), and its penetration below the plane
  const F snu = dot(n, u);
  const F l0 = capsule_exit(-ha, snu, ra, ha), l1 = capsule_exit(ha, snu, ra, ha);
  const F d0 = l0 - (hc - hu), d1 = l1 - (hc + hu);  // endpoints -ha, +ha
  const V3<F> x0 = u * (-ha), x1 = u * ha;
  const V3<F> p0 = madd(x0, l0 - half * d0, n), p1 = madd(x1, l1 - half * d1, n);
  // A steep capsule (the line down from the upper endpoint leaves through the lower
  // end's cap: r |s| > 2 h sin) touches with that cap alone; its second line would give
  // the same point for an upright capsule (or a zero-length core), so it keeps one.
  const auto steep = ra * abs(snu) > F(2.0f) * ha * sqrt(max(F(1.0f) - snu * snu, F(1e-12f)));
  const auto two = andnot((d0 > zero) & (d1 > zero), steep);
  const auto first = d0 >= d1;
  L2<F> m;
  finish(m, n, max(d0, d1), two, p0, d0, p1, d1, select(first, p0, p1), max(d0, d1));
  store(out, k, m, pa);
}

}  // namespace

IMPACT_LANE_KERNEL(collide_capsule_capsule, capsule_capsule_block, 2)
IMPACT_LANE_KERNEL(collide_capsule_box, capsule_box_block, 2)
IMPACT_LANE_KERNEL(collide_capsule_triangle, capsule_triangle_block, 2)
IMPACT_LANE_KERNEL(collide_capsule_halfspace, capsule_halfspace_block, 2)

}  // namespace impact::kernels
