// A cylinder's rim seen along a direction: the 2-D half-ellipse root solve shared by
// the lane kernels whose support overlap has a piece where a rim circle meets a
// segment's interior (capsule_cylinder.cpp: the core; cylinder_triangle.cpp: a
// triangle's edges; box_cylinder.cpp: a box's edges; cylinder_cylinder.cpp: a side's
// line), and CoreRims, the setup and finish of that piece for a core segment.
//
// Seen along a unit direction d (not along the axis z), a rim circle of radius rc is
// an ellipse in the plane perpendicular to d: semi-axis rc along w = z x d / |z x d|,
// rc |d_z| along v = d x w, and the two rims' ellipses lie 2 h v_z apart along v
// (v_z >= 0). On the great circle of directions perpendicular to d, the cylinder's
// support function is that shadow's (a stadium: the ellipse swept along v), and a
// direction with n_z > 0 (< 0) meets the top (bottom) rim: the upper (lower) half of
// its ellipse. The support overlap of the cylinder and a point p of the plane there is
// the 2-D signed distance of p to the half ellipse along its normal, whose local
// minimum is the solve below.
//
// Method: Eberly's secular equation for the point (t > -b^2: the nearest point; t in
// (-a^2, -b^2), the root next to -b^2: the second local minimum seen from the far side,
// which exists inside the ellipse's evolute), written with tau = |t + b^2| as
// 1/|q(tau)| = 1, q = (a X / (a^2 - b^2 +- tau), b |Y| / tau), whose left side is concave
// in tau on either range (Cauchy-Schwarz, as in sphere_ellipsoid.cpp): kArcIterations
// Newton steps from a certified lower bound (Newton on a concave function lands at or
// below the root), a certified upper bound from any evaluated point, and a pole step on
// the b|Y|/tau term where it dominates (Newton crawls there: points near the evolute's
// cusps). At most kArcIterations steps; a slot stops early after a step that moved
// none of its lanes (its state is its step's only input, so every later step would
// move nothing either): a lane's bytes are those of all kArcIterations steps and do
// not depend on its block. Most blocks stop after 6 to 9 steps (box-cylinder bench).
// Several solves of one block run as one loop over their slots (independent chains,
// so their divisions and square roots overlap).
// Cost per slot: at most kArcIterations steps of 3 divisions and 2 square roots.
// Reference: Eberly, "Distance from a Point to an Ellipse, an Ellipsoid, or a
// Hyperellipsoid", Geometric Tools, 2013.
#pragma once

#include "kernels/narrowphase/lanes/lane_geometry.h"

namespace impact::kernels::rim {

using prim::kTinySq;
using prim::normalize_or;
using prim::V3;
using simd::cross;
using simd::dot;
using simd::madd;

/// Fixed step count of the half-ellipse root solve: float precision is reached by 9
/// everywhere tried (points at the evolute's cusps of ellipses with axis ratio 1e-6..1,
/// 1e-8..1e3 of the radius from them); 10 for margin.
inline constexpr int kArcIterations = 10;
/// Smallest tau of the root solve (scaled units: the rim's radius is 1).
inline constexpr float kFloor = 1e-18f;

/// For each slot s < M: the unit normal (nx, ny), ny >= 0, at the local minimum of the
/// distance from the point (X, Y) to the upper half { (cos t, b sin t) : t in [0, pi] }
/// of the ellipse with semi-axes 1 and b in [0, 1] (Y >= 0: the nearest point of the
/// ellipse; Y < 0: the minimum on the far half, where one exists; where none does the
/// result is some unit normal of that half). See the file header for the solve.
template <class F, int M>
IMPACT_INLINE void half_ellipse_normals(const F (&b)[M], const F (&X)[M], const F (&Y)[M], F (&nx)[M],
                                        F (&ny)[M]) {
  using Mask = typename F::Mask;
  const F zero(0.0f), one(1.0f), fl(kFloor);
  F sx[M], ax[M], ay[M], sg[M], k[M], A[M], B[M], lo[M], hi[M], dmin[M], c[M];
  Mask same[M];
  for (int s = 0; s < M; ++s) {
    sx[s] = simd::sign_nonneg(X[s]);
    ax[s] = abs(X[s]), ay[s] = abs(Y[s]);
    same[s] = Y[s] >= zero;
    sg[s] = select(same[s], one, F(-1.0f));
    k[s] = (one - b[s]) * (one + b[s]);  // a^2 - b^2, exact for b in [0.5, 1]
    A[s] = ax[s], B[s] = b[s] * ay[s];
    // Each term of |q| alone >= 1 below these: certified lower bounds of the root. The
    // far side's root has q_1 <= 1, i.e. tau <= k - A.
    lo[s] = max(select(same[s], max(B[s], A[s] - k[s]), B[s]), fl);
    hi[s] = max(select(same[s], sqrt(A[s] * A[s] + B[s] * B[s]), k[s] - A[s]), lo[s]);
    dmin[s] = max(A[s], fl);  // k +- tau >= A at and below the root (q_1 <= 1)
    c[s] = lo[s];
  }
  bool run[M];
  for (int s = 0; s < M; ++s) run[s] = true;
  for (int i = 0; i < kArcIterations; ++i) {
    // A step that moves no lane of a slot moves none of it again (the slot's state is
    // its step's only input): that slot stops there, and the loop once all have, with
    // the bytes of all kArcIterations steps.
    bool any_run = false;
    for (int s = 0; s < M; ++s) {
      if (!run[s]) continue;
      const F lo0 = lo[s], hi0 = hi[s], c0 = c[s];
      const F d1 = max(mul_add(sg[s], c[s], k[s]), dmin[s]);
      const F rr = one / (d1 * c[s]);
      const F r1 = c[s] * rr, r2 = d1 * rr;  // 1 / d1, 1 / tau
      const F q1 = A[s] * r1, q2 = B[s] * r2;
      const F q1s = q1 * q1, q2s = q2 * q2;
      const F f = q1s + q2s;  // |q|^2
      // psi = 1/|q| - 1: psi' = dd / |q|^3, Newton step (|q| - 1) |q|^2 / dd.
      const F dd = sg[s] * q1s * r1 + q2s * r2;
      const Mask rising = dd > zero;
      const F tn = c[s] + (sqrt(f) - one) * f / select(rising, dd, one);
      hi[s] = select(f <= one, min(hi[s], c[s]), hi[s]);
      lo[s] = min(max(lo[s], select(rising, tn, lo[s])), hi[s]);
      // Pole step: the root if q_1 stayed as it is (exact where the b|Y|/tau term rules).
      const F tp = B[s] / sqrt(max(one - q1s, fl));
      const Mask pole = (q2s * r2 > q1s * r1) & (q1 < one) & (tp > lo[s]) & (tp < hi[s]);
      c[s] = select(pole, tp, lo[s]);
      run[s] = simd::any((lo[s] != lo0) | (hi[s] != hi0) | (c[s] != c0));
      any_run = any_run || run[s];
    }
    if (!any_run) break;
  }
  for (int s = 0; s < M; ++s) {
    // Normal at the foot (x / a^2, y / b^2) = (X / (k +- tau), |Y| / tau), scaled by tau
    // (k +- tau); on the axis inside the evolute (tau at its floor, Eberly's special case)
    // from the ellipse's equation instead, times b: (b q_1, sqrt(1 - q_1^2)).
    const F d1 = max(mul_add(sg[s], lo[s], k[s]), dmin[s]);
    F px = ax[s] * lo[s], py = ay[s] * d1;
    const Mask degenerate = px * px + py * py < F(kTinySq);
    const F q1 = min(A[s] / d1, one);
    px = select(degenerate, b[s] * q1, px);
    py = select(degenerate, sqrt(max(one - q1 * q1, zero)), py);
    const F l2 = px * px + py * py;
    const Mask ok = l2 >= F(kTinySq);
    const F inv = one / sqrt(select(ok, l2, one));
    nx[s] = select(ok, sx[s] * px * inv, zero);
    ny[s] = select(ok, py * inv, one);
  }
}

/// A core segment c + t u, |t| <= hs, against the rims of a cylinder (axis z, radius rc,
/// half length h): on the great circle n.u = 0 the cylinder's support is its shadow's
/// along u (rim_solve.h), and the local minimum on each rim's half ellipse is a
/// candidate (capsule-cylinder's core, cylinder-cylinder's sides). Setup writes the two
/// slots' solve inputs (b, X, Y: the upper and the lower half) and the shadow's basis;
/// finish turns the solved half-ellipse normals into n (from the core's side to the
/// cylinder), y (the cylinder's rim point along -n), t (the core parameter level with y)
/// and on (where t lies on the segment, within slack). (w and v are orthonormal only up to
/// rounding, which for a core along the axis is all of u's horizontal part: n is
/// normalised, so that the support overlap along it stays an upper bound.)
template <class F>
struct CoreRims {
  V3<F> w, v;
  IMPACT_INLINE void setup(const V3<F>& c, const V3<F>& u, F rc, F h, F* b, F* rx, F* ry) {
    const F zero(0.0f), one(1.0f), tiny(kTinySq);
    const F uxy2 = u.x * u.x + u.y * u.y;
    const auto tilted = uxy2 > tiny;
    const F inv_uxy = one / sqrt(select(tilted, uxy2, one));
    w = V3<F>{select(tilted, -u.y * inv_uxy, one), select(tilted, u.x * inv_uxy, zero), zero};
    v = cross(u, w);
    v = select(v.z < zero, -v, v);  // the shadow of +z along u is v.z v
    const F inv_rc = one / rc;
    const F bx = -(c.x * w.x + c.y * w.y) * inv_rc;  // the origin seen from the core's shadow
    const F by = -dot(c, v) * inv_rc;
    const F lr = h * v.z * inv_rc;
    b[0] = b[1] = abs(u.z);  // minor / major semi-axis of a rim's shadow
    rx[0] = rx[1] = bx;
    ry[0] = by - lr, ry[1] = -(by + lr);
  }
  IMPACT_INLINE void finish(const V3<F>& c, const V3<F>& u, F hs, F rc, F h, F slack, const F* ex,
                            const F* ey, V3<F> (&n)[2], V3<F> (&y)[2], F (&t)[2],
                            typename F::Mask (&on)[2]) const {
    const F one(1.0f), tiny(kTinySq);
    F len;
    n[0] = normalize_or(madd(w * ex[0], ey[0], v), w, len);
    n[1] = normalize_or(madd(w * ex[1], -ey[1], v), w, len);
    for (int i = 0; i < 2; ++i) {
      const F nxy2 = n[i].x * n[i].x + n[i].y * n[i].y;
      const F s = rc / sqrt(select(nxy2 > tiny, nxy2, one));
      y[i] = V3<F>{-s * n[i].x, -s * n[i].y, -h * simd::sign_nonneg(n[i].z)};
      t[i] = dot(y[i] - c, u);
      on[i] = abs(t[i]) <= hs + slack;
    }
  }
};

}  // namespace impact::kernels::rim
