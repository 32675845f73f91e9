// Pruning and packed solves for the polytope-ellipsoid lane kernels (box_ellipsoid.cpp,
// convex_ellipsoid.cpp): which vertex and edge pieces of the Minkowski difference can
// hold a candidate normal, decided without solving, and the solves of the few that can,
// packed kSimdWidth (piece, lane) slots to a solve. Internal to kernels/narrowphase.
//
// Frame and notation as ellipsoid_solve.h: the ellipsoid's axes scaled by its largest
// radius (radii a_i in (0, 1]), d_i = a_i^2 - a_m^2 (m: the smallest axis). A polytope
// vertex at y (relative to the ellipsoid's centre) has at most two candidate normals,
// the outward normals at the local minima of the distance from y to the surface:
//     m(s)_i = y_i / (s + d_i)
// at a root s of the secular equation: the nearest point's s is the largest root
// (s > a_m^2 outside, 0 < s <= a_m^2 inside), the far minimum's s lies in (-d_p, -w_m]
// (w = a * |y|, p the second smallest axis; see far_solve). An edge's candidates are the
// same in 2-D, on the ellipsoid's shadow across the edge (ellip::shadow). So as s runs
// over a bracket of the root, m(s) traces a curve that holds the candidate; a piece's
// candidate counts only if the piece's feature is the polytope's lowest along m, i.e.
// u.m <= 0 for each of the piece's constraint directions u (a box vertex: sigma_k b_k;
// a hull vertex: its edges towards the neighbours; an edge: the two faces' sides). If
// for some u, u.m(s) > kPruneMargin |m(s)| on the whole bracket, the candidate lies off
// its piece by more than the kernels' kPieceTol: the piece needs no solve.
//
// The test is polynomial: multiplied by P(s) = prod_j (s + d_j) (> 0 on the near
// bracket, < 0 on the far one), u.m(s) - margin |m(s)|_1 becomes
//     q(s) = sum_i beta_i prod_{j != i} (s + d_j)
// (a quadratic in 3-D, linear in 2-D), and the piece is pruned when q > E on the
// bracket, E a bound of q's rounding (kPolyRound of the magnitudes of its terms). The
// brackets are the solver's own certified bounds (ellipsoid_solve.h), widened by 1e-4.
// Inside points with a component below 2 kSnap (the solver then snaps it to 0 and may
// move the minimum off the curve: Eberly's special case) are never pruned.
// Method: Eberly, "Distance from a Point to an Ellipse, an Ellipsoid, or a
// Hyperellipsoid" (2013) for the parametrisation of the stationary points; the pruning
// by the normal-cone constraints along that curve is this project's.
#pragma once

#include <cstdint>

#include "kernels/narrowphase/solvers/ellipsoid_solve.h"

namespace impact::kernels::ellip {

/// A piece's candidate counts where it lies on its piece within this (sine of the angle
/// past the piece's boundary), as in ellipsoid_triangle.cpp.
inline constexpr float kPieceTol = 1e-5f;
/// A piece is pruned when its curve leaves the piece by more than this (of |m|_1) on the
/// whole bracket: ten times kPieceTol, so a pruned candidate is one the kernel rejects.
inline constexpr float kPruneMargin = 1e-4f;
/// Rounding bound of the pruning polynomials, relative to the magnitude of their terms
/// (a few float operations: ~1e-6; generous).
inline constexpr float kPolyRound = 1e-5f;
/// Relative widening of the brackets (the solver's root may sit on its bound's rounding).
inline constexpr float kWiden = 1e-4f;

/// The level above which an inside point's candidates can still beat `value` on an
/// ellipsoid of smallest radius am (scaled frame): such a candidate scores at least the
/// point's distance to the surface, >= (1 - sqrt(level)) am; -1 (every level) when
/// value >= am.
template <class F>
IMPACT_INLINE F level_floor(F value, F am) {
  const F t = F(1.0f) - value / am;
  return select(t > F(0.0f), t * t, F(-1.0f));
}

/// The smallest-axis data of radii a (N = 3) used by every curve test of one ellipsoid.
template <class F>
struct Radii3 {
  F a[3], inv[3];
  F d[3];        // a_i^2 - a_m^2
  F S[3], P[3];  // d_j + d_l, d_j d_l over the two other axes
  F am, am2, dmax;
};

template <class F>
IMPACT_INLINE Radii3<F> radii3(const F (&a)[3]) {
  Radii3<F> r;
  typename F::Mask is_m[3];
  r.am = smallest_axis(a, is_m);
  r.am2 = r.am * r.am;
  for (int i = 0; i < 3; ++i) {
    r.a[i] = a[i];
    r.inv[i] = F(1.0f) / a[i];
    r.d[i] = (a[i] - r.am) * (a[i] + r.am);
  }
  r.dmax = max(max(r.d[0], r.d[1]), r.d[2]);
  for (int i = 0; i < 3; ++i) {
    const int j = (i + 1) % 3, l = (i + 2) % 3;
    r.S[i] = r.d[j] + r.d[l];
    r.P[i] = r.d[j] * r.d[l];
  }
  return r;
}

/// sum (y_i / a_i)^2 of the point y (< 1 inside), and keep: an inside point with a
/// component below 2 kSnap (the solver snaps it to 0 and may leave the curve there:
/// never pruned).
template <int N, class F>
IMPACT_INLINE F level_of(const F (&inv)[N], const F (&y)[N], typename F::Mask& keep) {
  F level(0.0f), zmin(3.0e38f);
  for (int i = 0; i < N; ++i) {
    const F t = y[i] * inv[i];
    level += t * t;
    zmin = min(zmin, abs(y[i]));
  }
  keep = (level < F(1.0f)) & (zmin < F(2.0f * kSnap));
  return level;
}

/// Near-point bracket [lo, hi] of s for the point y (N components, radii a, d as above,
/// level from level_of): the solver's lower bounds (each term alone, all terms with the
/// largest d), |a y| above, then a_m^2 splits inside from outside; widened by kWiden.
template <int N, class F>
IMPACT_INLINE void near_bracket(const F (&a)[N], const F (&d)[N], F am2, F dmax, const F (&y)[N], F level,
                                F& lo, F& hi) {
  const F zero(0.0f);
  F wn2 = zero;
  lo = zero;
  for (int i = 0; i < N; ++i) {
    const F w = a[i] * abs(y[i]);
    wn2 += w * w;
    lo = max(lo, w - d[i]);
  }
  const F wn = sqrt(wn2);
  lo = max(lo, wn - dmax);
  hi = max(wn, lo);
  const auto inside = level < F(1.0f);
  hi = select(inside, min(hi, am2), hi);
  lo = select(inside, lo, max(lo, am2));
  lo = lo * F(1.0f - kWiden);
  hi = hi * F(1.0f + kWiden);
}

/// q(s) = sum_i beta_i (s + d_j)(s + d_l) > its rounding bound on [lo, hi] (3-D).
/// Without division: a convex q's vertex s_v = -B / 2A within (a generous margin of)
/// the bracket iff 2A (lo - slack) < -B < 2A (hi + slack), and its value C - B^2 / 4A
/// exceeds E iff 4AC - B^2 > 4AE (the rounding of B^2 / 4A is that of A s_v^2, within E).
template <class F>
IMPACT_INLINE typename F::Mask positive_on3(const F (&beta)[3], const Radii3<F>& r, F lo, F hi) {
  const F zero(0.0f);
  const F A = beta[0] + beta[1] + beta[2];
  const F B = beta[0] * r.S[0] + beta[1] * r.S[1] + beta[2] * r.S[2];
  const F C = beta[0] * r.P[0] + beta[1] * r.P[1] + beta[2] * r.P[2];
  const F ql = (A * lo + B) * lo + C, qh = (A * hi + B) * hi + C;
  const F sa = max(abs(lo), abs(hi));
  const F s2 = sa * sa;
  F mag = zero;
  for (int i = 0; i < 3; ++i) mag += abs(beta[i]) * (s2 + r.S[i] * sa + r.P[i]);
  const F E = F(kPolyRound) * mag;
  const F slack = F(1e-3f) * (hi - lo);
  const F two_a = A + A;
  const auto in = (A > zero) & (two_a * (lo - slack) < -B) & (-B < two_a * (hi + slack));
  const auto vertex_ok = (F(4.0f) * A * C - B * B) > F(4.0f) * A * E;
  return (min(ql, qh) > E) & (~in | vertex_ok);
}

/// Whether a 3-D point's nearest-point candidate leaves its piece by more than
/// kPruneMargin on the whole bracket, for constraint direction u (the candidate counts
/// only where u.m <= 0): beta_i = u_i y_i - margin |y_i|.
template <class F>
IMPACT_INLINE typename F::Mask near_off3(const V3<F>& u, const F (&y)[3], const Radii3<F>& r, F lo, F hi) {
  const F mg(kPruneMargin);
  const F uu[3] = {u.x, u.y, u.z};
  F beta[3];
  for (int i = 0; i < 3; ++i) beta[i] = uu[i] * y[i] - mg * abs(y[i]);
  return positive_on3(beta, r, lo, hi);
}

/// The far minimum's axes of one ellipsoid (far_axes without the point): m (smallest,
/// lowest index among equal), p (second smallest), q; and each term's sign of
/// prod_{j != i} (s + d_j) on the far bracket (+1 for m, -1 for the others).
template <class F>
struct FarAxes3 {
  typename F::Mask is_m[3], is_p[3];
  F dp, dq;
  F t[3];
};

template <class F>
IMPACT_INLINE FarAxes3<F> far_axes3(const F (&a)[3]) {
  using Mask = typename F::Mask;
  const F one(1.0f);
  FarAxes3<F> r;
  const F am = smallest_axis(a, r.is_m);
  F ap(3.0e38f);
  for (int i = 0; i < 3; ++i) ap = select(r.is_m[i], ap, min(ap, a[i]));
  r.dq = one;
  Mask taken(false);
  for (int i = 0; i < 3; ++i) {
    r.is_p[i] = andnot(a[i] == ap, taken | r.is_m[i]);
    taken = taken | r.is_p[i];
    const Mask is_q = ~(r.is_m[i] | r.is_p[i]);
    r.dq = select(is_q, (a[i] - am) * (a[i] + am), r.dq);
    r.t[i] = select(r.is_m[i], one, -one);
  }
  r.dp = (ap - am) * (ap + am);
  return r;
}

/// Whether the point y can have a far minimum (far_cases on the unsnapped point) and its
/// bracket [-d_p, -w_m], widened.
template <class F>
struct FarBracket3 {
  typename F::Mask exists;
  F lo, hi;
};

template <class F>
IMPACT_INLINE FarBracket3<F> far_bracket3(const F (&a)[3], const FarAxes3<F>& fx, const F (&y)[3]) {
  const F zero(0.0f);
  F wm = zero, wp = zero, wq = zero;
  for (int i = 0; i < 3; ++i) {
    const F w = a[i] * abs(y[i]);
    wm = select(fx.is_m[i], w, wm);
    wp = select(fx.is_p[i], w, wp);
    wq = select(fx.is_m[i] | fx.is_p[i], wq, w);
  }
  FarBracket3<F> b;
  b.exists = (wm > zero) & (wm + wp < fx.dp) & (wq < fx.dq);
  b.lo = -fx.dp * F(1.0f + kWiden);
  b.hi = -wm * F(1.0f - kWiden);
  return b;
}

/// far counterpart of near_off3: P(s) < 0 on the far bracket, so
/// beta_i = -u_i y_i - margin t_i |y_i|.
template <class F>
IMPACT_INLINE typename F::Mask far_off3(const V3<F>& u, const F (&y)[3], const Radii3<F>& r,
                                        const FarAxes3<F>& fx, const FarBracket3<F>& fb) {
  const F mg(kPruneMargin);
  const F uu[3] = {u.x, u.y, u.z};
  F beta[3];
  for (int i = 0; i < 3; ++i) beta[i] = -(uu[i] * y[i]) - mg * fx.t[i] * abs(y[i]);
  return positive_on3(beta, r, fb.lo, fb.hi);
}

/// The 2-D (shadow) data of one edge direction: semi-axes ax0 >= ax1, d0 = ax0^2 - ax1^2
/// (d1 = 0).
template <class F>
struct Radii2 {
  F a[2], inv[2], d[2];
  F am2, dmax;
};

template <class F>
IMPACT_INLINE Radii2<F> radii2(const Shadow<F>& sh) {
  Radii2<F> r;
  for (int i = 0; i < 2; ++i) {
    r.a[i] = sh.ax[i];
    r.inv[i] = F(1.0f) / sh.ax[i];
  }
  r.d[0] = (sh.ax[0] - sh.ax[1]) * (sh.ax[0] + sh.ax[1]);
  r.d[1] = F(0.0f);
  r.am2 = sh.ax[1] * sh.ax[1];
  r.dmax = r.d[0];
  return r;
}

/// q(s) = beta_0 (s + d_1) + beta_1 (s + d_0) > its rounding bound on [lo, hi] (2-D).
template <class F>
IMPACT_INLINE typename F::Mask positive_on2(const F (&beta)[2], const Radii2<F>& r, F lo, F hi) {
  const F ql = beta[0] * (lo + r.d[1]) + beta[1] * (lo + r.d[0]);
  const F qh = beta[0] * (hi + r.d[1]) + beta[1] * (hi + r.d[0]);
  const F sa = max(abs(lo), abs(hi));
  const F mag = abs(beta[0]) * (sa + r.d[1]) + abs(beta[1]) * (sa + r.d[0]);
  return min(ql, qh) > F(kPolyRound) * mag;
}

/// 2-D near_off3: u and y in the shadow's coordinates.
template <class F>
IMPACT_INLINE typename F::Mask near_off2(const F (&u)[2], const F (&y)[2], const Radii2<F>& r, F lo, F hi) {
  const F mg(kPruneMargin);
  const F beta[2] = {u[0] * y[0] - mg * abs(y[0]), u[1] * y[1] - mg * abs(y[1])};
  return positive_on2(beta, r, lo, hi);
}

/// 2-D far data: the smallest axis is 1 (ax1 <= ax0; equal axes have no far minimum).
template <class F>
struct FarBracket2 {
  typename F::Mask exists;
  F lo, hi;
};

template <class F>
IMPACT_INLINE FarBracket2<F> far_bracket2(const Radii2<F>& r, const F (&y)[2]) {
  const F wm = r.a[1] * abs(y[1]), wp = r.a[0] * abs(y[0]);
  FarBracket2<F> b;
  b.exists = (wm > F(0.0f)) & (wm + wp < r.d[0]);
  b.lo = -r.d[0] * F(1.0f + kWiden);
  b.hi = -wm * F(1.0f - kWiden);
  return b;
}

template <class F>
IMPACT_INLINE typename F::Mask far_off2(const F (&u)[2], const F (&y)[2], const Radii2<F>& r,
                                        const FarBracket2<F>& fb) {
  const F mg(kPruneMargin);
  // t = -1 for axis 0, +1 for the smallest axis 1.
  const F beta[2] = {-(u[0] * y[0]) + mg * abs(y[0]), -(u[1] * y[1]) - mg * abs(y[1])};
  return positive_on2(beta, r, fb.lo, fb.hi);
}

// ---------------------------------------------------------------------------------------
// Packed solves
// ---------------------------------------------------------------------------------------

/// K pieces of one block of W lanes: each piece's solve problem (radii set `set[p]` of S
/// sets, point pt[p]; 2-D problems as radii (ax0, ax1, ax0) and point (y0, y1, 0), as
/// far_packed does) and the lanes that want it solved (want[p], lane bits). The solves
/// write res[p] (the candidate normal in the problem's frame, signs restored,
/// unnormalised) and ok[p] (1 where the far minimum exists).
template <uint32_t W, int K, int S>
struct PieceBatch {
  float rad[S][3][W];
  uint8_t set[K];
  float pt[K][3][W];
  uint32_t want[K];
  float res[K][3][W];
  float ok[K][W];
};

/// The (piece, lane) slots of want, in (piece, lane) order, as float offsets: pt[p][0][l]
/// (also res[p][0][l]) and rad[set[p]][0][l] from their arrays' starts; returns their
/// count. The offsets after the last repeat it up to the next multiple of W (padding).
template <uint32_t W, int K, int S>
IMPACT_INLINE uint32_t list_slots(const PieceBatch<W, K, S>& b, int32_t* off, int32_t* roff) {
  uint32_t n = 0;
  for (int p = 0; p < K; ++p) {
    const int32_t po = p * 3 * static_cast<int32_t>(W), ro = b.set[p] * 3 * static_cast<int32_t>(W);
    for (uint32_t bits = b.want[p]; bits != 0; bits &= bits - 1) {
      const int32_t l = __builtin_ctz(bits);
      off[n] = po + l;
      roff[n] = ro + l;
      ++n;
    }
  }
  for (uint32_t k = n; n > 0 && k % W != 0; ++k) off[k] = off[n - 1], roff[k] = roff[n - 1];
  return n;
}

/// Gathers slots n0 .. n0 + W of the list (list_slots) into lanes: radii a, point y.
template <class F, int K, int S>
IMPACT_INLINE void gather_slots(const PieceBatch<F::kWidth, K, S>& b, const int32_t* off, const int32_t* roff,
                                uint32_t n0, F (&a)[3], F (&y)[3]) {
  constexpr uint32_t W = F::kWidth;
  using Int = typename F::Int;
  const Int po = Int::load(off + n0), ro = Int::load(roff + n0);
  for (int i = 0; i < 3; ++i) {
    a[i] = simd::gather(&b.rad[0][0][0] + i * W, ro);
    y[i] = simd::gather(&b.pt[0][0][0] + i * W, po);
  }
}

/// The snapped first-orthant point of y and its signs (as near_normal).
template <class F>
IMPACT_INLINE void orthant(const F (&a)[3], const F (&y)[3], F (&z)[3], F (&sign)[3]) {
  F z_in[3];
  F level(0.0f);
  for (int i = 0; i < 3; ++i) {
    z_in[i] = abs(y[i]);
    sign[i] = simd::sign_nonneg(y[i]);
    const F t = y[i] / a[i];
    level += t * t;
  }
  snap(z_in, level < F(1.0f), z);
}

/// Nearest-point candidates of every wanted slot: res[p] where want[p].
template <class F, int K, int S>
IMPACT_INLINE void solve_near_packed(PieceBatch<F::kWidth, K, S>& b) {
  constexpr uint32_t W = F::kWidth;
  int32_t off[K * W + W], roff[K * W + W];
  const uint32_t n = list_slots(b, off, roff);
  for (uint32_t n0 = 0; n0 < n; n0 += W) {
    F a[3], y[3], z[3], sign[3], x[3], g[3];
    gather_slots<F, K, S>(b, off, roff, n0, a, y);
    orthant(a, y, z, sign);
    closest_snapped(a, z, x, g);
    float r[3][W];
    for (int i = 0; i < 3; ++i) (sign[i] * g[i]).store(r[i]);
    float* res = &b.res[0][0][0];
    for (uint32_t k = 0; k < W && n0 + k < n; ++k) {
      const int32_t o = off[n0 + k];
      for (int i = 0; i < 3; ++i) res[o + i * static_cast<int32_t>(W)] = r[i][k];
    }
  }
}

/// Far-minimum candidates of every wanted slot: res[p] and ok[p] where want[p] (a point
/// on the smallest axis's plane takes its nearest point mirrored, as far_on_ellipsoid).
template <class F, int K, int S>
IMPACT_INLINE void solve_far_packed(PieceBatch<F::kWidth, K, S>& b) {
  constexpr uint32_t W = F::kWidth;
  using Mask = typename F::Mask;
  int32_t off[K * W + W], roff[K * W + W];
  const uint32_t n = list_slots(b, off, roff);
  for (uint32_t n0 = 0; n0 < n; n0 += W) {
    F a[3], y[3], z[3], sign[3], g[3];
    gather_slots<F, K, S>(b, off, roff, n0, a, y);
    orthant(a, y, z, sign);
    const FarAxes<3, F> f = far_axes(a, z);
    Mask mirror, solve;
    far_cases(f, mirror, solve);
    const Mask alive = far_solve(f, solve, z, g);
    if (simd::any(mirror)) {
      F x[3], gn[3];
      closest_snapped(a, z, x, gn);
      for (int i = 0; i < 3; ++i) g[i] = select(mirror, select(f.is_m[i], -gn[i], gn[i]), g[i]);
    }
    const Mask ok = mirror | (solve & alive);
    float r[3][W], o[W];
    for (int i = 0; i < 3; ++i) (sign[i] * g[i]).store(r[i]);
    select(ok, F(1.0f), F(0.0f)).store(o);
    float* res = &b.res[0][0][0];
    for (uint32_t k = 0; k < W && n0 + k < n; ++k) {
      const int32_t of = off[n0 + k];
      for (int i = 0; i < 3; ++i) res[of + i * static_cast<int32_t>(W)] = r[i][k];
      const int32_t p = of / (3 * static_cast<int32_t>(W)), l = of % (3 * static_cast<int32_t>(W));
      b.ok[p][l] = o[k];
    }
  }
}

}  // namespace impact::kernels::ellip
