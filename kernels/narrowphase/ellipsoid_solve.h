// Point-ellipsoid solvers shared by the ellipsoid lane kernels (sphere_ellipsoid.cpp,
// capsule_ellipsoid.cpp, ellipsoid_triangle.cpp), written once over the lane type F
// (simd::FloatW or simd::Float1) and over the dimension N (3: the ellipsoid; 2: its
// shadow, an ellipse, on a plane).
//
// Frame: the ellipsoid's own axes, scaled by its largest radius (radii a_i in (0, 1]),
// the point z in the first orthant (z_i = |y_i|; callers restore the signs).
// Stationary points of the distance from z to the surface sum (x_i / a_i)^2 = 1 are
// x_i = a_i^2 z_i / (s + d_i), d_i = a_i^2 - a_m^2 >= 0 (m: the smallest axis, the
// lowest index among equal smallest radii), where s is a root of the secular equation
// Q(s) = sum_i q_i^2 = 1, q_i = a_i z_i / (s + d_i) (the Lagrange condition; Eberly,
// "Distance from a Point to an Ellipse, an Ellipsoid, or a Hyperellipsoid", Geometric
// Tools, 2013, whose t is s - a_m^2). The outward surface gradient there is
// g_i = z_i / (s + d_i) = x_i / a_i^2.
//
// Which stationary points are local minima (the ones the kernels need: the contact
// normal is a local minimum of the support overlap over directions, and on a vertex
// piece of a Minkowski difference that is a local minimum of the distance from the
// vertex to the ellipsoid's surface): the Hessian of |x - z|^2 on the surface is
// 2 diag(1 + t / a_i^2) restricted to the tangent plane (t = s - a_m^2). With t > -a_m^2
// (the largest root s > 0) it is positive definite: the nearest point. With exactly one
// negative entry (t in (-a_p^2, -a_m^2), p the second smallest axis, i.e. s in (-d_p, 0))
// it is positive definite on the tangent plane iff sum w_i^2 / d_i < 0 for the gradient
// w (the bordered-Hessian test), which is dQ/ds > 0. Q is convex between its poles and
// grows without bound at both ends of (-d_p, 0), so there it has none or two roots, and
// the right one (closer to the pole at 0) is the other local minimum: the far side
// across the smallest axis (x_m has the opposite sign to z_m). With two or more
// negative entries no minimum. So a point has at most two local minima of the distance:
// the nearest point (closest_on_ellipsoid) and the far one (far_on_ellipsoid); on the
// smallest axis's plane (z_m = 0) the far one is the nearest point mirrored there.
//
// Solves: a fixed number of safeguarded steps, the same for every lane (no branch on
// lane data). psi(s) = Q^-1/2 - 1 is concave between consecutive poles
// (3 Q'^2 <= 2 Q Q'' by Cauchy-Schwarz on the terms w_i^2 / (s + d_i)^2, whatever the
// signs of s + d_i), so a Newton step on psi taken from beyond a root, on the side away
// from psi's maximum, lands between that point and the root; Newton on a term that
// dominates Q's derivative (the pole step) is exact when the other terms are constant.
#pragma once

#include <cfloat>

#include "kernels/narrowphase/primitives.h"

namespace impact::kernels::ellip {

using prim::V3;
using simd::cross;
using simd::dot;
using simd::length_sq;

/// Fixed iteration count of the nearest-point solve (8 reach float precision, see
/// sphere_ellipsoid.cpp's notes).
inline constexpr int kIterations = 10;
/// Fixed iteration count of the far-minimum solve. Measured in this solve's float model
/// against double roots on 89k adversarial points (random, pancakes and needles to
/// 1e-4, nearly equal smallest radii, components to 1e-6): the value reaches float
/// rounding with 6 steps, the normal 6e-5 rad with 8 (7: 4e-4, 6: 2.6e-3); the slow
/// cases are near a double root, where the minimum is flat.
inline constexpr int kFarIterations = 8;
/// Scaled components of an inside point below this are solved as 0 (distance error
/// <= kSnap e_max: the distance to a set is 1-Lipschitz).
inline constexpr float kSnap = 1e-6f;
/// Smallest s: the scaled secular equation's largest root is treated as 0 below it.
inline constexpr float kFloor = 1e-30f;

/// The secular function's terms at s.
template <int N, class F>
struct Secular {
  F r[N];    // 1 / (s + d_i)
  F q2[N];   // q_i^2
  F h[N];    // q_i^2 / (s + d_i): minus half of d(q_i^2)/ds
  F Q, D;    // sum q_i^2, sum h_i
  F Qr, Dr;  // the same without the smallest axis m
};

template <int N, class F>
IMPACT_INLINE Secular<N, F> secular(F s, const F (&w)[N], const F (&d)[N], const typename F::Mask (&is_m)[N]) {
  Secular<N, F> e;
  const F zero(0.0f);
  e.Q = zero, e.D = zero, e.Qr = zero, e.Dr = zero;
  for (int i = 0; i < N; ++i) {
    e.r[i] = F(1.0f) / (s + d[i]);
    const F q = w[i] * e.r[i];
    e.q2[i] = q * q;
    e.h[i] = e.q2[i] * e.r[i];
    e.Q += e.q2[i];
    e.D += e.h[i];
    e.Qr += select(is_m[i], zero, e.q2[i]);
    e.Dr += select(is_m[i], zero, e.h[i]);
  }
  return e;
}

/// The smallest radius; is_m marks its axis (the lowest index among equal smallest radii).
template <int N, class F>
IMPACT_INLINE F smallest_axis(const F (&a)[N], typename F::Mask (&is_m)[N]) {
  using Mask = typename F::Mask;
  F am = a[0];
  for (int i = 1; i < N; ++i) am = min(am, a[i]);
  Mask taken(false);
  for (int i = 0; i < N; ++i) {
    is_m[i] = andnot(a[i] == am, taken);
    taken = taken | is_m[i];
  }
  return am;
}

/// z with the components of inside points below kSnap set to 0.
template <int N, class F>
IMPACT_INLINE void snap(const F (&z_in)[N], typename F::Mask inside, F (&z)[N]) {
  for (int i = 0; i < N; ++i) z[i] = select(inside & (z_in[i] < F(kSnap)), F(0.0f), z_in[i]);
}

/// Nearest point x of the surface (radii a, max 1) to the point z (first orthant,
/// already snapped), and g, the outward surface gradient there (unnormalised).
/// The solve (s > 0 is the largest root):
///  - a certified lower bound lo (start: max_i (w_i - d_i) and |w| - max d_i, the roots
///    of one-term and all-terms minorants), raised by the Newton step on psi and by the
///    Newton step on the same function without the smallest axis's term (whose root is
///    below the full root; the fast one when that term is negligible);
///  - an upper bound hi (|w|, then any evaluated point with Q <= 1);
///  - the next point is lo, except where one term dominates psi's derivative (its pole
///    -d_p is near): there Newton on that term's q_p = v instead (s + d_p = w_p / v),
///    taken only inside (lo, hi). Newton on psi alone crawls there (about x1.5 per step
///    between a pole at 0 and a root far from it: points near a principal plane, near a
///    rim or a tip).
/// A point on the smallest axis's principal plane whose root is below kFloor (Eberly's
/// special case: an inside point whose nearest point is off that plane; also the
/// centre) has x_i = a_i^2 z_i / d_i on the other axes and x_m from the surface equation.
template <int N, class F>
IMPACT_INLINE void closest_snapped(const F (&a)[N], const F (&z)[N], F (&x)[N], F (&g)[N]) {
  using Mask = typename F::Mask;
  const F zero(0.0f), one(1.0f), tiny(FLT_MIN);
  Mask is_m[N];
  const F am = smallest_axis(a, is_m);
  F w[N], d[N];
  F wn2 = zero;
  for (int i = 0; i < N; ++i) {
    w[i] = a[i] * z[i];
    d[i] = (a[i] - am) * (a[i] + am);  // exactly 0 on the smallest axis
    wn2 += w[i] * w[i];
  }
  const F wn = sqrt(wn2);
  F dmax = d[0];
  for (int i = 1; i < N; ++i) dmax = max(dmax, d[i]);
  // Lower bounds of the root: each term alone, and all terms with the largest d.
  F lo = wn - dmax;
  for (int i = 0; i < N; ++i) lo = max(lo, w[i] - d[i]);
  lo = max(lo, F(kFloor));
  F hi = max(wn, lo);  // |q(s)| <= |w| / s
  F c = lo;
  Secular<N, F> e = secular(c, w, d, is_m);
  // Root below the floor: a point on the smallest axis's principal plane whose nearest
  // point is off that plane (Eberly's special case; also the centre itself).
  const Mask off_plane = (lo == F(kFloor)) & (e.Q < one);
  for (int k = 0; k < kIterations; ++k) {
    const F n = sqrt(e.Q), nr = sqrt(e.Qr);
    // Newton on psi = 1/|q| - 1 and on the same without term m: both below the root.
    const F s_full = c + (n - one) * e.Q / max(e.D, tiny);
    const F s_red = c + (nr - one) * e.Qr / max(e.Dr, tiny);
    hi = select(e.Q <= one, min(hi, c), hi);
    lo = min(max(lo, max(s_full, s_red)), hi);
    // The dominant term p of psi's derivative (lowest index among equal terms), and
    // Newton on v = q_p (s + d_p = w_p / v): v_new = v - (Q - 1) / dQ/dv with
    // dQ/dv = 2 v + 2 (D - h_p) (s + d_p) / v, i.e.
    // s_new = s + sigma (Q - 1) / (2 sigma D - (Q - 1)), sigma = s + d_p.
    F hp = e.h[0], dp = d[0];
    for (int i = 1; i < N; ++i) {
      const Mask more = e.h[i] > hp;
      hp = select(more, e.h[i], hp);
      dp = select(more, d[i], dp);
    }
    const F sigma = c + dp;
    const F qm1 = e.Q - one;
    const F den = F(2.0f) * sigma * e.D - qm1;
    const Mask den_ok = den > zero;
    const F s_pole = c + sigma * qm1 / select(den_ok, den, one);
    const Mask use_pole = den_ok & (hp > F(0.5f) * e.D) & (s_pole > lo) & (s_pole < hi);
    c = select(use_pole, s_pole, lo);
    e = secular(c, w, d, is_m);
  }
  F xm_off = zero;
  for (int i = 0; i < N; ++i) {
    x[i] = a[i] * a[i] * z[i] * e.r[i];
    g[i] = z[i] * e.r[i];
    xm_off = select(is_m[i], a[i], xm_off);
  }
  // Off the plane: (x_i / a_i)^2 = q_i^2 for i != m, x_m from the surface equation.
  xm_off = xm_off * sqrt(max(one - e.Qr, zero));
  const F gm_off = xm_off / (am * am);
  for (int i = 0; i < N; ++i) {
    const Mask use = off_plane & is_m[i];
    x[i] = select(use, xm_off, x[i]);
    g[i] = select(use, gm_off, g[i]);
  }
}

/// closest_snapped for an unsnapped z: inside = z lies inside (its components below
/// kSnap are then solved as 0).
template <int N, class F>
IMPACT_INLINE void closest_on_ellipsoid(const F (&a)[N], const F (&z_in)[N], typename F::Mask inside, F (&x)[N],
                                        F (&g)[N]) {
  F z[N];
  snap(z_in, inside, z);
  closest_snapped(a, z, x, g);
}

/// The other local minimum of the distance from z (first orthant, snapped) to the
/// surface: the right root of Q = 1 in (-d_p, 0), where Q rises back to its pole at 0.
/// Returns the lanes where it exists; g receives the outward gradient there
/// (unnormalised; g_m <= 0: across the smallest axis). g_near: closest_snapped's
/// gradient for the same z, whose mirror across the smallest axis's plane is the far
/// minimum of a point on that plane (where the pole at 0 vanishes).
/// Solve: from s = -w_m (where the term m alone is 1, so Q >= 1: right of the root),
/// each step takes the smaller of two upper bounds of the root: Newton on psi (concave,
/// decreasing right of the root) and the pole step s = -w_m / sqrt(1 - Q_r) (Q_r, the
/// other terms, grows as s falls). A lane whose step leaves (-d_p, 0), finds psi
/// increasing (past its maximum: no root) or Q_r >= 1 has no far minimum. Existence
/// needs w_m + w_p < d_p (each of the two pole terms below 1 somewhere in between).
template <int N, class F>
IMPACT_INLINE typename F::Mask far_on_ellipsoid(const F (&a)[N], const F (&z)[N], const F (&g_near)[N], F (&g)[N]) {
  using Mask = typename F::Mask;
  const F zero(0.0f), one(1.0f);
  Mask is_m[N];
  const F am = smallest_axis(a, is_m);
  // The second smallest radius (its axis p: the lowest index among the rest).
  F ap(3.0e38f);
  for (int i = 0; i < N; ++i) ap = select(is_m[i], ap, min(ap, a[i]));
  F w[N], d[N];
  F wm = zero, wp = zero;
  Mask taken(false);
  for (int i = 0; i < N; ++i) {
    w[i] = a[i] * z[i];
    d[i] = (a[i] - am) * (a[i] + am);
    wm = select(is_m[i], w[i], wm);
    const Mask is_p = andnot(a[i] == ap, taken | is_m[i]);
    taken = taken | is_p;
    wp = select(is_p, w[i], wp);
  }
  const F dp = (ap - am) * (ap + am);
  const Mask on_plane = wm <= zero;
  Mask alive = andnot(wm + wp < dp, on_plane);
  // Lanes without a candidate sit at s = -2 (below every -d_i > -1: finite terms).
  F s = select(alive, -wm, F(-2.0f));
  Secular<N, F> e = secular(s, w, d, is_m);
  for (int k = 0; k < kFarIterations; ++k) {
    alive = alive & (e.D < zero) & (e.Qr < one);
    const F s_newton = s + (sqrt(e.Q) - one) * e.Q / select(alive, e.D, -one);
    const F s_pole = -wm / sqrt(select(alive, one - e.Qr, one));
    const F next = min(s_newton, s_pole);
    alive = alive & (next > -dp);
    s = select(alive, next, s);
    e = secular(s, w, d, is_m);
  }
  for (int i = 0; i < N; ++i) {
    const F mirror = select(is_m[i], -g_near[i], g_near[i]);
    g[i] = select(on_plane, mirror, z[i] * e.r[i]);
  }
  return alive | on_plane;
}

/// The ellipsoid's shadow on the plane perpendicular to the unit direction v (local
/// frame, radii a): an ellipse with semi-axes ax[0] >= ax[1] along the unit local
/// directions e1, e2 (both perpendicular to v). Its Gram matrix S = B^T diag(a^2) B in
/// a basis B of the plane; det S = sum_k v_k^2 prod_{i != k} a_i^2 (Cauchy-Binet, no
/// cancellation), so the smaller eigenvalue is det / the larger.
template <class F>
struct Shadow {
  V3<F> e1, e2;
  F ax[2];
};

template <class F>
IMPACT_INLINE Shadow<F> shadow(const F (&a)[3], const V3<F>& v) {
  const F zero(0.0f), one(1.0f), half(0.5f);
  const V3<F> b1 = prim::any_perpendicular(v);
  const V3<F> b2 = cross(v, b1);
  const F a0 = a[0] * a[0], a1 = a[1] * a[1], a2 = a[2] * a[2];
  const F s11 = a0 * b1.x * b1.x + a1 * b1.y * b1.y + a2 * b1.z * b1.z;
  const F s22 = a0 * b2.x * b2.x + a1 * b2.y * b2.y + a2 * b2.z * b2.z;
  const F s12 = a0 * b1.x * b2.x + a1 * b1.y * b2.y + a2 * b1.z * b2.z;
  const F det = a1 * a2 * v.x * v.x + a0 * a2 * v.y * v.y + a0 * a1 * v.z * v.z;
  const F hd = half * (s11 - s22);
  const F disc = sqrt(hd * hd + s12 * s12);
  const F lp = half * (s11 + s22) + disc;
  const F lm = min(det / lp, lp);
  // Eigenvector of lp without cancellation: (lp - s22, s12) or (s12, lp - s11).
  const auto pos = hd >= zero;
  const F vx = select(pos, hd + disc, s12), vy = select(pos, s12, disc - hd);
  const F l2 = vx * vx + vy * vy;
  const auto ok = l2 > F(prim::kTinySq);
  const F inv = one / sqrt(select(ok, l2, one));
  const F cx = select(ok, vx * inv, one), cy = select(ok, vy * inv, zero);
  Shadow<F> sh;
  sh.e1 = b1 * cx + b2 * cy;
  sh.e2 = b2 * cx - b1 * cy;
  sh.ax[0] = sqrt(lp);
  sh.ax[1] = sqrt(lm);
  return sh;
}

/// One point's nearest-point solve, kept for its far-minimum solve: the snapped point
/// in the first orthant, the signs of the original components, the gradient found.
template <int N, class F>
struct PointSolve {
  F z[N];
  F sign[N];
  F g_near[N];
};

/// The outward gradient at the nearest point of the ellipsoid (radii a) to the point y
/// (local, scaled), signs restored; st keeps the solve for far_normal.
template <class F>
IMPACT_INLINE V3<F> near_normal(const F (&a)[3], const V3<F>& y, PointSolve<3, F>& st) {
  const F ys[3] = {y.x, y.y, y.z};
  F z_in[3], x[3];
  F level(0.0f);
  for (int i = 0; i < 3; ++i) {
    z_in[i] = abs(ys[i]);
    st.sign[i] = simd::sign_nonneg(ys[i]);
    const F t = ys[i] / a[i];
    level += t * t;
  }
  snap(z_in, level < F(1.0f), st.z);
  closest_snapped(a, st.z, x, st.g_near);
  return V3<F>{st.sign[0] * st.g_near[0], st.sign[1] * st.g_near[1], st.sign[2] * st.g_near[2]};
}

/// The outward gradient at the far local minimum of the same point (valid where ok).
template <class F>
IMPACT_INLINE V3<F> far_normal(const F (&a)[3], const PointSolve<3, F>& st, typename F::Mask& ok) {
  F g[3];
  ok = far_on_ellipsoid(a, st.z, st.g_near, g);
  return V3<F>{st.sign[0] * g[0], st.sign[1] * g[1], st.sign[2] * g[2]};
}

/// The same against the shadow sh (the 2-D problem in its plane: y's component along
/// the shadow's direction is ignored), lifted to 3-D.
template <class F>
IMPACT_INLINE V3<F> near_normal(const Shadow<F>& sh, const V3<F>& y, PointSolve<2, F>& st) {
  const F p[2] = {dot(sh.e1, y), dot(sh.e2, y)};
  F z_in[2], x[2];
  F level(0.0f);
  for (int i = 0; i < 2; ++i) {
    z_in[i] = abs(p[i]);
    st.sign[i] = simd::sign_nonneg(p[i]);
    const F t = p[i] / sh.ax[i];
    level += t * t;
  }
  snap(z_in, level < F(1.0f), st.z);
  closest_snapped(sh.ax, st.z, x, st.g_near);
  return sh.e1 * (st.sign[0] * st.g_near[0]) + sh.e2 * (st.sign[1] * st.g_near[1]);
}

template <class F>
IMPACT_INLINE V3<F> far_normal(const Shadow<F>& sh, const PointSolve<2, F>& st, typename F::Mask& ok) {
  F g[2];
  ok = far_on_ellipsoid(sh.ax, st.z, st.g_near, g);
  return sh.e1 * (st.sign[0] * g[0]) + sh.e2 * (st.sign[1] * g[1]);
}

}  // namespace impact::kernels::ellip
