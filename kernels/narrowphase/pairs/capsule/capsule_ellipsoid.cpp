// Capsule (A) against ellipsoid (B): exact collision data by the local minima of the
// support overlap, vectorised across pairs (one lane = one pair), no GJK / EPA.
//
// Inputs: LeafSoA lanes per leaf.h (A a capsule: p, R column 2 = unit axis, e0 = radius
// r, e1 = half length; B an ellipsoid: p, R, radii e0, e1, e2 along R's columns), Range r
// of the bucket.
// Outputs: ManifoldSoA lanes r.begin .. r.end: count (0 or 1), n (unit, A to B), depth,
// point[0] midway between the two surfaces (the ellipsoid's point touching along n,
// moved by depth / 2 along n), pdepth[0] = depth. Slots 1..3 untouched; count-0 lanes
// leave the other fields unspecified.
// Method, in the ellipsoid's frame scaled by its largest radius (its radii a_i in
// (0, 1]; the core: centre q, unit axis v, half length h, relative to the ellipsoid's
// centre, so poses far from the origin keep their precision): with m a direction from the
// ellipsoid towards the capsule,
//     G(m) = h |m.v| + h_E(m) - m.q,   h_E(m) = |diag(a) m| (the support function),
// is the support function of the Minkowski difference core - ellipsoid at -m, and
// depth = r + min over unit m of G, n = -argmin (r - the signed distance of the core to
// the ellipsoid; inside: its penetration depth). The unit sphere splits into the
// hemispheres m.v < 0 and m.v > 0, where one end point P = q -+ h v is the core's
// nearest point along m and G(m) = h_E(m) - m.P, and the circle m.v = 0, where G is the
// support overlap of the ellipsoid's shadow on the plane perpendicular to v (an ellipse)
// and q's projection. The minimiser is
//  - inside a hemisphere: a local minimum of h_E(m) - m.P, i.e. of the distance from P to
//    the ellipsoid's surface (m its outward normal there): the nearest point or the far
//    local minimum across the smallest axis (at most these two: ellipsoid_solve.h);
//  - on the circle: the minimum of G over the circle, the nearest point of the shadow to
//    q's projection (a minimiser of G on the whole sphere that lies on the circle is one
//    over the circle).
// So the five candidate directions (two per end point, one on the circle) hold the
// minimiser; each is scored by G itself (every direction's G is >= the minimum, so a
// candidate that is not a local minimum never wins wrongly) and the least wins (ties:
// the earlier in that order). An end point's candidates count only on its own
// hemisphere (within 1e-5 rad): off it they are no minimum, yet may score within float
// noise of it (a short core's two ends, 3e-4 rad apart), and the circle's candidate
// covers the band between. Separated cores (min G < 0) are
// a convex problem; the far minima (G > 0) matter only for cores that meet the
// ellipsoid, and a block without such a lane skips their solves. A round ellipsoid or a
// zero-length core gives capsule-sphere's and sphere-ellipsoid's answers.
// Solves: ellipsoid_solve.h (nearest point: Eberly's secular equation by 10 safeguarded
// steps, as sphere_ellipsoid.cpp; far minimum: 8 steps from the pole side; the shadow's
// axes in closed form).
// Degenerate input: a zero-length core has two equal end points (sphere-ellipsoid's
// answer); the core on the ellipsoid's centre gives a finite unit normal (the end
// points' nearest points); components of inside points below 1e-6 e_max are solved as 0
// (depth error <= 1e-6 e_max).
// Preconditions: finite inputs, positive radii, half length >= 0, unit axis, orthonormal
// R (host-validated); no division without a guard, so finite inputs give finite outputs.
// Cost: per lane 2 nearest-point solves and 1 on the shadow (at most 11 evaluations of
// the secular function and 10 steps each; a block stops once every lane sits at a fixed
// point of its step), 5 scores; far minima only for the (lane, end) slots whose core
// meets the ellipsoid and that pass the existence test, packed 8 to a solve (~0.2 slots
// per 8-lane block on the bench); no branch on lane data in the arithmetic (selects),
// no libm call. A block whose cores are all farther than r + e_max from the
// ellipsoid's centre stops early.
// Measured per pair in docs/results.md ("Narrow phase").
// Both paths run the same template (F = FloatW, or Float1 for the scalar reference).
#include <cstdint>

#include "kernels/narrowphase/solvers/ellipsoid_solve.h"
#include "kernels/narrowphase/pair_kernels.h"
#include "kernels/narrowphase/lanes/block_driver.h"
#include "kernels/narrowphase/lanes/lane_geometry.h"
#include "kernels/narrowphase/lanes/lane_io.h"

namespace impact::kernels {
namespace {

using namespace prim;  // NOLINT: lane helpers of this kernel family
using simd::dot;
using simd::length_sq;

/// A candidate of an end point counts where it lies on that end's hemisphere up to this
/// (sine of the angle past the circle m.v = 0).
constexpr float kPieceTol = 1e-5f;

/// The least of the candidate directions' scores G(m) (m unnormalised).
template <class F>
struct Best {
  F value;
  V3<F> m;
  F len;
};

template <class F>
IMPACT_INLINE void capsule_ellipsoid_block(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out,
                                           uint32_t k) {
  using Mask = typename F::Mask;
  const F zero(0.0f), one(1.0f), big(3.0e38f);
  const V3<F> pa = load_p<F>(a, k);
  const V3<F> cb = load_p<F>(b, k) - pa;  // the ellipsoid's centre, from the capsule's
  const V3<F> u = load_axis_z<F>(a, k);
  const F r = ld<F>(a.e[0], k), hl = ld<F>(a.e[1], k);
  const V3<F> e = load_e<F>(b, k);
  const F emax = max(max(e.x, e.y), e.z);
  // Every lane's core farther than r + e_max from the ellipsoid's centre: no contact.
  {
    const V3<F> d = madd(cb, -closest_on_segment(V3<F>{zero, zero, zero}, u, hl, cb), u);
    const F reach = r + emax;
    if (simd::none(length_sq(d) < reach * reach)) {
      store_no_contact<F>(out, k);
      return;
    }
  }
  const M3<F> rot = load_r<F>(b, k);
  const F inv = one / emax;
  const F av[3] = {e.x * inv, e.y * inv, e.z * inv};
  const V3<F> q = rot.apply_t(cb) * (-inv);
  const V3<F> v = rot.apply_t(u);
  const F h = hl * inv;

  Best<F> best{big, V3<F>{zero, zero, one}, one};
  auto consider = [&](const V3<F>& m, Mask valid) {
    const F l2 = length_sq(m);
    const Mask ok = valid & (l2 >= F(kTinySq));
    const F len = sqrt(select(ok, l2, one));
    const F ax = av[0] * m.x, ay = av[1] * m.y, az = av[2] * m.z;
    const F he = sqrt(ax * ax + ay * ay + az * az);
    const F value = (h * abs(dot(m, v)) + he - dot(m, q)) / len;
    const Mask take = ok & (value < best.value);
    best.value = select(take, value, best.value);
    best.m = select(take, m, best.m);
    best.len = select(take, len, best.len);
  };

  // An end's candidates only on its own hemisphere (p0 = q - h v is the core's lowest
  // point along m where m.v >= 0), within kPieceTol: off it a candidate is no local
  // minimum of G, though it may score within float noise of the minimum (a short core's
  // two ends), and the circle's candidate covers the band between.
  auto on_end = [&](const V3<F>& m, float side) {
    const F mv = dot(m, v) * F(side);
    return (mv >= zero) | (mv * mv <= F(kPieceTol * kPieceTol) * length_sq(m));
  };
  // End points and the circle m.v = 0 (the shadow's nearest point to q's projection).
  const V3<F> p0 = madd(q, -h, v), p1 = madd(q, h, v);
  ellip::PointSolve<3, F> st0, st1;
  const V3<F> near0 = ellip::near_normal(av, p0, st0), near1 = ellip::near_normal(av, p1, st1);
  consider(near0, on_end(near0, 1.0f));
  consider(near1, on_end(near1, -1.0f));
  {
    const ellip::Shadow<F> sh = ellip::shadow(av, v);
    ellip::PointSolve<2, F> st;
    consider(ellip::near_normal(sh, q, st), Mask(true));
  }
  // Far minima score > 0: only a core that meets the ellipsoid (least score so far
  // >= 0) can need them. (The other lanes ignore them, so a lane's bytes do not depend
  // on its block.)
  const Mask meets = best.value >= zero;
  if (simd::any(meets)) {
    const F fa[2][3] = {{av[0], av[1], av[2]}, {av[0], av[1], av[2]}};
    const F fz[2][3] = {{st0.z[0], st0.z[1], st0.z[2]}, {st1.z[0], st1.z[1], st1.z[2]}};
    const F fg[2][3] = {{st0.g_near[0], st0.g_near[1], st0.g_near[2]},
                        {st1.g_near[0], st1.g_near[1], st1.g_near[2]}};
    const Mask want[2] = {meets, meets};
    F g[2][3];
    Mask ok[2];
    ellip::far_packed(fa, fz, fg, want, g, ok);
    const ellip::PointSolve<3, F>* st[2] = {&st0, &st1};
    for (int c = 0; c < 2; ++c) {
      const V3<F> m{st[c]->sign[0] * g[c][0], st[c]->sign[1] * g[c][1], st[c]->sign[2] * g[c][2]};
      consider(m, ok[c] & on_end(m, c == 0 ? 1.0f : -1.0f));
    }
  }

  // n from A to B: minus m; B's surface point: its support along m (towards A).
  const V3<F> ml = best.m * (one / best.len);
  const V3<F> n = -rot.apply(ml);
  const F depth = r + best.value * emax;
  const V3<F> am{av[0] * ml.x, av[1] * ml.y, av[2] * ml.z};
  const F he = sqrt(length_sq(am));
  const F s = emax / select(he > zero, he, one);
  const V3<F> xb{av[0] * am.x * s, av[1] * am.y * s, av[2] * am.z * s};
  const V3<F> on_b = cb + rot.apply(xb);
  Lanes<F, 1> m;
  m.count = simd::to_int(depth > zero);
  m.n = n;
  m.depth = depth;
  m.point[0] = madd(on_b, F(0.5f) * depth, n);
  m.pdepth[0] = depth;
  store(out, k, m, pa);
}

}  // namespace

void collide_capsule_ellipsoid(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, Range r,
                               const NarrowConfig& cfg) {
  IMPACT_LANE_KERNEL_BODY(capsule_ellipsoid_block, 1);
}

}  // namespace impact::kernels
