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

#include "kernels/narrowphase/lanes/lane_geometry.h"

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
  // A lane whose step leaves (c, lo, hi) unchanged is at a fixed point: it stops there
  // (state and the terms it returns frozen), so its result depends on its own data
  // only, not on how many steps its block runs; the block stops when all lanes have.
  Mask done(false);
  F r_out[N], qr_out = e.Qr;
  for (int i = 0; i < N; ++i) r_out[i] = e.r[i];
  for (int k = 0; k < kIterations; ++k) {
    const F n = sqrt(e.Q), nr = sqrt(e.Qr);
    // Newton on psi = 1/|q| - 1 and on the same without term m: both below the root.
    const F s_full = c + (n - one) * e.Q / max(e.D, tiny);
    const F s_red = c + (nr - one) * e.Qr / max(e.Dr, tiny);
    const F hi_new = select(e.Q <= one, min(hi, c), hi);
    const F lo_new = min(max(lo, max(s_full, s_red)), hi_new);
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
    const Mask use_pole = den_ok & (hp > F(0.5f) * e.D) & (s_pole > lo_new) & (s_pole < hi_new);
    const F c_new = select(use_pole, s_pole, lo_new);
    done = done | ((c_new == c) & (lo_new == lo) & (hi_new == hi));
    c = select(done, c, c_new), lo = select(done, lo, lo_new), hi = select(done, hi, hi_new);
    if (simd::all(done)) break;
    e = secular(c, w, d, is_m);
    for (int i = 0; i < N; ++i) r_out[i] = select(done, r_out[i], e.r[i]);
    qr_out = select(done, qr_out, e.Qr);
  }
  F xm_off = zero;
  for (int i = 0; i < N; ++i) {
    x[i] = a[i] * a[i] * z[i] * r_out[i];
    g[i] = z[i] * r_out[i];
    xm_off = select(is_m[i], a[i], xm_off);
  }
  // Off the plane: (x_i / a_i)^2 = q_i^2 for i != m, x_m from the surface equation.
  xm_off = xm_off * sqrt(max(one - qr_out, zero));
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

/// The axes the far minimum involves: m (smallest radius, lowest index among equal), p
/// (second smallest, lowest index among the rest), and the terms of z there.
template <int N, class F>
struct FarAxes {
  typename F::Mask is_m[N];
  F w[N], d[N];
  F wm, wp, dp;
  F wq, dq;  // the third axis (N = 3; 0 and 1 for N = 2)
};

template <int N, class F>
IMPACT_INLINE FarAxes<N, F> far_axes(const F (&a)[N], const F (&z)[N]) {
  using Mask = typename F::Mask;
  const F zero(0.0f);
  FarAxes<N, F> f;
  const F am = smallest_axis(a, f.is_m);
  F ap(3.0e38f);
  for (int i = 0; i < N; ++i) ap = select(f.is_m[i], ap, min(ap, a[i]));
  f.wm = zero, f.wp = zero, f.wq = zero, f.dq = F(1.0f);
  Mask taken(false);
  for (int i = 0; i < N; ++i) {
    f.w[i] = a[i] * z[i];
    f.d[i] = (a[i] - am) * (a[i] + am);
    f.wm = select(f.is_m[i], f.w[i], f.wm);
    const Mask is_p = andnot(a[i] == ap, taken | f.is_m[i]);
    taken = taken | is_p;
    f.wp = select(is_p, f.w[i], f.wp);
    if constexpr (N == 3) {
      const Mask is_q = ~(f.is_m[i] | is_p);
      f.wq = select(is_q, f.w[i], f.wq);
      f.dq = select(is_q, f.d[i], f.dq);
    }
  }
  f.dp = (ap - am) * (ap + am);
  return f;
}

/// Which lanes can have a far minimum: mirror, a point on the smallest axis's plane
/// (z_m = 0; the far minimum is the nearest point mirrored across that plane, or the
/// nearest point itself, and needs no solve); solve, the others where a root may exist
/// (necessary: w_m + w_p < d_p, each pole term below 1 somewhere in between, and
/// w_q < d_q, the third term below 1 there).
template <int N, class F>
IMPACT_INLINE void far_cases(const FarAxes<N, F>& f, typename F::Mask& mirror, typename F::Mask& solve) {
  mirror = f.wm <= F(0.0f);
  solve = andnot((f.wm + f.wp < f.dp) & (f.wq < f.dq), mirror);
}

/// The other local minimum of the distance from z (first orthant, snapped) to the
/// surface, for the lanes of `solve` (far_cases): the right root of Q = 1 in (-d_p, 0),
/// where Q rises back to its pole at 0. Returns the lanes where it exists; g receives the
/// outward gradient there (unnormalised; g_m < 0: across the smallest axis).
/// From s = -w_m (where the term m alone is 1, so Q >= 1: right of the root), each step
/// takes the smaller of two upper bounds of the root: Newton on psi (concave,
/// decreasing right of the root) and the pole step s = -w_m / sqrt(1 - Q_r) (Q_r, the
/// other terms, grows as s falls). A lane whose step leaves (-d_p, 0), finds psi
/// increasing (past its maximum: no root) or Q_r >= 1 has no far minimum. Lanes
/// outside `solve` sit at s = -2 (below every -d_i > -1: finite terms) and return false.
template <int N, class F>
IMPACT_INLINE typename F::Mask far_solve(const FarAxes<N, F>& f, typename F::Mask solve, const F (&z)[N],
                                         F (&g)[N]) {
  using Mask = typename F::Mask;
  const F zero(0.0f), one(1.0f);
  Mask alive = solve;
  F s = select(alive, -f.wm, F(-2.0f));
  Secular<N, F> e = secular(s, f.w, f.d, f.is_m);
  // Lanes stop at a fixed point of the step (see closest_snapped); lanes without a
  // candidate from the start.
  Mask done = ~alive;
  F r_out[N];
  for (int i = 0; i < N; ++i) r_out[i] = e.r[i];
  for (int k = 0; k < kFarIterations; ++k) {
    const Mask live = alive & (e.D < zero) & (e.Qr < one);
    const F s_newton = s + (sqrt(e.Q) - one) * e.Q / select(live, e.D, -one);
    const F s_pole = -f.wm / sqrt(select(live, one - e.Qr, one));
    const F next = min(s_newton, s_pole);
    const Mask alive_new = live & (next > -f.dp);
    const F s_new = select(alive_new, next, s);
    done = done | ((s_new == s) & ~(alive_new ^ alive));
    s = select(done, s, s_new), alive = select(done, alive, alive_new);
    if (simd::all(done)) break;
    e = secular(s, f.w, f.d, f.is_m);
    for (int i = 0; i < N; ++i) r_out[i] = select(done, r_out[i], e.r[i]);
  }
  for (int i = 0; i < N; ++i) g[i] = z[i] * r_out[i];
  return alive;
}

/// The far minimum of every lane (far_cases, far_solve and the mirror): valid lanes
/// returned, g as for far_solve. g_near: closest_snapped's gradient for the same z.
template <int N, class F>
IMPACT_INLINE typename F::Mask far_on_ellipsoid(const F (&a)[N], const F (&z)[N], const F (&g_near)[N], F (&g)[N]) {
  using Mask = typename F::Mask;
  const FarAxes<N, F> f = far_axes(a, z);
  Mask mirror, solve;
  far_cases(f, mirror, solve);
  const Mask alive = far_solve(f, solve, z, g);
  for (int i = 0; i < N; ++i) g[i] = select(mirror, select(f.is_m[i], -g_near[i], g_near[i]), g[i]);
  return alive | mirror;
}

/// far_on_ellipsoid for K (3-D) points per lane, solving only the (lane, point) slots
/// in want that can have a far minimum (far_cases), packed kSimdWidth to a solve: few
/// slots need one (most points fail the existence test), so the packed solves cost a
/// fraction of K full ones. A slot's result does not depend on the others packed with
/// it (the solve is lane-wise), so the bytes match the one-lane path's. A 2-D problem
/// (an ellipse with semi-axes ax0 >= ax1) enters as radii (ax0, ax1, ax0) and
/// z = (z0, z1, 0): the third term is 0 (the same roots). Returns in ok the slots of
/// want with a far minimum.
template <class F, int K>
IMPACT_INLINE void far_packed(const F (&a)[K][3], const F (&z)[K][3], const F (&g_near)[K][3],
                              const typename F::Mask (&want)[K], F (&g)[K][3], typename F::Mask (&ok)[K]) {
  using Mask = typename F::Mask;
  constexpr uint32_t W = F::kWidth;
  FarAxes<3, F> f[K];
  Mask mirror[K], solve[K], alive[K];
  F gs[K][3];
  for (int c = 0; c < K; ++c) {
    f[c] = far_axes(a[c], z[c]);
    far_cases(f[c], mirror[c], solve[c]);
    mirror[c] = mirror[c] & want[c];
    solve[c] = solve[c] & want[c];
  }
  if constexpr (W == 1) {
    for (int c = 0; c < K; ++c) {
      alive[c] = Mask(false);
      for (int i = 0; i < 3; ++i) gs[c][i] = F(0.0f);
      if (simd::any(solve[c])) alive[c] = far_solve(f[c], solve[c], z[c], gs[c]);
    }
  } else {
    // Slots to solve, in (point, lane) order.
    uint8_t slot_c[K * W], slot_l[K * W];
    uint32_t n = 0;
    for (int c = 0; c < K; ++c) {
      for (uint32_t bits = simd::bits(solve[c]); bits != 0; bits &= bits - 1) {
        slot_c[n] = static_cast<uint8_t>(c);
        slot_l[n] = static_cast<uint8_t>(__builtin_ctz(bits));
        ++n;
      }
    }
    float out_g[K][3][W] = {}, out_ok[K][W] = {};
    if (n > 0) {
      float la[K][3][W], lz[K][3][W];
      for (int c = 0; c < K; ++c) {
        for (int i = 0; i < 3; ++i) {
          a[c][i].store(la[c][i]);
          z[c][i].store(lz[c][i]);
        }
      }
      for (uint32_t s0 = 0; s0 < n; s0 += W) {
        float pa[3][W], pz[3][W];
        for (uint32_t k = 0; k < W; ++k) {
          const uint32_t s = s0 + k < n ? s0 + k : n - 1;  // padding repeats the last slot
          for (int i = 0; i < 3; ++i) {
            pa[i][k] = la[slot_c[s]][i][slot_l[s]];
            pz[i][k] = lz[slot_c[s]][i][slot_l[s]];
          }
        }
        F fa[3], fz[3], fg[3];
        for (int i = 0; i < 3; ++i) fa[i] = F::load(pa[i]), fz[i] = F::load(pz[i]);
        const FarAxes<3, F> pf = far_axes(fa, fz);
        const uint32_t got = simd::bits(far_solve(pf, Mask(true), fz, fg));
        float rg[3][W];
        for (int i = 0; i < 3; ++i) fg[i].store(rg[i]);
        for (uint32_t k = 0; k < W && s0 + k < n; ++k) {
          const uint32_t s = s0 + k;
          for (int i = 0; i < 3; ++i) out_g[slot_c[s]][i][slot_l[s]] = rg[i][k];
          out_ok[slot_c[s]][slot_l[s]] = ((got >> k) & 1u) ? 1.0f : 0.0f;
        }
      }
    }
    for (int c = 0; c < K; ++c) {
      for (int i = 0; i < 3; ++i) gs[c][i] = F::load(out_g[c][i]);
      alive[c] = F::load(out_ok[c]) > F(0.0f);
    }
  }
  for (int c = 0; c < K; ++c) {
    for (int i = 0; i < 3; ++i) g[c][i] = select(mirror[c], select(f[c].is_m[i], -g_near[c][i], g_near[c][i]), gs[c][i]);
    ok[c] = mirror[c] | (solve[c] & alive[c]);
  }
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
/// (local, scaled), signs restored; st keeps the solve for far_packed.
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

}  // namespace impact::kernels::ellip
