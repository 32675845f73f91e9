// Cylinder (A) against ellipsoid (B): the least support overlap of the two bodies over
// the unit sphere of directions, vectorised across pairs (one lane = one pair), no
// GJK / EPA.
//
// Inputs: LeafSoA lanes per leaf.h (A a cylinder: p, R column 2 = unit axis, e0 = radius,
// e1 = half length; B an ellipsoid: p, R, radii e0, e1, e2 along R's columns), Range r of
// the bucket.
// Outputs: ManifoldSoA lanes r.begin .. r.end: count (0 or 1), n (unit, A to B), depth,
// point[0] midway (the ellipsoid's point touching along n, moved by depth / 2 along n),
// pdepth[0] = depth. Slots 1..3 untouched; count-0 lanes leave the other fields
// unspecified. (The ellipsoid is strictly convex, so one point is the whole contact.)
// Method, in the ellipsoid's frame scaled by the pair's largest dimension L (its radii
// a_i; the cylinder's centre c, unit axis u, half length h, radius r, relative to the
// ellipsoid's centre, so poses far from the origin keep their precision): with m a
// direction from the ellipsoid towards the cylinder,
//     G(m) = h |m.u| + r |m x u| + |diag(a) m| - m.c
// is the support overlap along m, depth = L min G over unit m (> 0: they meet) and
// n = -argmin. G(-m) = G(m) + 2 m.c, so the minimiser has m.c >= 0. G is smooth except
// on the circle m.u = 0 (the side's kink) and at m = +-u (the caps' cone points), so the
// minimiser is one of
//  - a cap's normal +-u (closed form, the sign with m.c >= 0);
//  - on the circle: the minimum of G over the circle, r + the support overlap of the
//    ellipsoid's shadow on the plane perpendicular to u (an ellipse) and c's projection:
//    its nearest point (ellipsoid_solve.h, capsule-ellipsoid's circle candidate);
//  - inside a hemisphere s = sign(m.u): a local minimum of the rim's piece, where
//    h |m.u| + r |m x u| = h s m.u + r sqrt((e1.m)^2 + (e2.m)^2): the support of a flat
//    ellipsoid (the rim's disk, axes r e1, r e2) centred at c + s h u, so G there is
//    ellipsoid-ellipsoid's f with that disk as B (the same gradient and Hessian terms).
//    Found by sphere_newton.h's multi-start trust-region Newton solve, whose model takes
//    the hemisphere of each point it evaluates, from the kStarts = 8 least distinct of 31
//    candidates: c; the ellipsoid's axes; u x each axis; u made perpendicular to each
//    axis (a needle's kink circle nearest the cap normal); c made perpendicular to each
//    axis; the least eigenvectors of diag(a^2) + w r^2 (I - u u^T), w = 1/4, 1, 4; each
//    rim's points q at 6 angles (from the one nearest the ellipsoid's centre): at even
//    angles the ellipsoid's level normal there (q / a^2) kept to the directions that make
//    q the rim's point nearest the ellipsoid (its normal cone), at odd ones the middle of
//    that cone (45 degrees); the circle's candidate; and a start 0.05 rad off each cap's
//    normal down the slope of the rest of G there (a disk's edge beside the
//    cap). Three steps each, the two least kept until they freeze. Kink handling, so the
//    solve neither crawls nor stops short: a trial across the circle is projected onto it;
//    a start on the circle stops there where neither piece descends into its own
//    hemisphere (|G0's slope along u| <= h, G = G0 +- h m.u), one within 1e-3 rad of a
//    cap's normal where that normal is a strict local minimum (the rest's slope there
//    < 0.9 r); near the minimum, where f's rounding (~1e-7: terms of order 1) can exceed
//    the decrease of a step, a step is also taken while the gradient shrinks, and the two
//    kept starts are told apart by the gradient within that noise (sphere_newton.h).
// Every candidate is scored by G itself (G at any direction is >= the minimum, so none
// wins wrongly); the least wins (ties: caps, then the circle, then the solve). Global
// minimum by multi-start inside the hemispheres, without a proof (as ellipsoid-
// ellipsoid); the caps and the circle are exact. Measured (cylinder_ellipsoid_test.cpp at
// IMPACT_TEST_INTENSITY=10: random poses at 4 scales, deep pairs, cap / side / rim
// contacts built in closed form, near touching and near parallel, needles and pancakes,
// rings, against dense sampling refined in double): no miss. Each candidate family
// beyond ellipsoid-ellipsoid's was added for a miss found there: a ring's edge beside
// its cap (3.5e-3 L too deep), a thick disk's rim minimum 0.7 rad from every level normal
// (1.3e-2 L), a needle through a pancake (4.2e-3 L). At IMPACT_TEST_INTENSITY=30 (~2e4
// lanes) one miss remains, a ring around a long ellipsoid with two rim minima (1.4e-3 L
// too deep), and one rim contact's point 1.7e-4 L off the cylinder. A
// miss returns a valid separating direction with a depth too large.
// Lanes the bounding spheres or G along (c, u, the ellipsoid's axes) separate are written
// count 0 first and the rest gathered into full blocks (prim::for_each_live_group).
// Degenerate input: coincident centres (c = 0) take the candidates' signs as given (the
// normal is then one of two opposite minimisers); c's own candidate falls back to the
// axis when |c| is tiny; a zero-length cylinder is a disk, a zero radius a segment.
// Preconditions: finite inputs, positive radii and half length >= 0, unit axis,
// orthonormal R (host-validated); every division is guarded, so finite inputs give finite
// outputs. No FMA contraction in this file (no_contract.h, included first so it covers the
// shared solvers): both paths give the same bytes.
// Cost: a first pass (5 support overlaps per lane) over every lane; for the lanes that
// may touch, the shadow's nearest-point solve, 31 candidate evaluations, the selection,
// 8 x 3 Newton steps, then 2 x (mostly 1-3) steps; a group runs until its slowest lane
// freezes, so the lanes still moving once no more than a quarter of the group's do are
// set aside and finished packed, 16 to a block. Cost: measured per pair in docs/results.md ("Narrow phase").
// Both paths run the same template (F = FloatW, or Float1 for the scalar reference).
#include <cstdint>

// First: the pragma must precede the shared solvers' templates to cover them.
#include "kernels/narrowphase/lanes/no_contract.h"
//
#include "kernels/narrowphase/solvers/ellipsoid_solve.h"
#include "kernels/narrowphase/pair_kernels.h"
#include "kernels/narrowphase/lanes/lane_geometry.h"
#include "kernels/narrowphase/lanes/lane_io.h"
#include "kernels/narrowphase/lanes/live_lanes.h"
#include "kernels/narrowphase/solvers/sphere_newton.h"

namespace impact::kernels {
namespace {

using namespace prim;  // NOLINT: lane helpers of this kernel family
using simd::dot;
using simd::length_sq;

constexpr int kStarts = 8;
constexpr int kKept = 2;
constexpr float kKinkSin = 1e-4f;    // a start this close to the side's circle may stop
constexpr float kConeSin = 1e-3f;    // ... this close to a cap's normal may stop,
constexpr float kConeSlope = 0.9f;   // where the rest of G's slope is below this of r
constexpr float kConeStep = 0.05f;   // rad: the start beside each cap's normal
constexpr float kConeFloor = 1e-6f;  // the cone's curvature r / |m x u| capped at r / this
constexpr int kRimAngles = 6;        // rim points per rim among the candidates, 60 degrees apart
constexpr float kRimPointCos[kRimAngles] = {1.0f, 0.5f, -0.5f, -1.0f, -0.5f, 0.5f};
constexpr float kRimPointSin[kRimAngles] = {0.0f, 0.8660254f, 0.8660254f, 0.0f, -0.8660254f, -0.8660254f};

/// The pair in the ellipsoid's scaled frame: newton::minimise's model.
template <class F>
struct Pair {
  F a2[3];                       // the ellipsoid's radii squared
  V3<F> v[2];                    // the rim disk's axes, r e1 and r e2
  V3<F> u;                       // the cylinder's axis
  F h;                           // its half length
  V3<F> d;                       // its centre (c)
  typename F::Mask cone_min[2];  // +u, -u: the cap's normal is a strict local minimum
  V3<F> cone_slope[2];           // +u, -u: the rest of G's tangent gradient there
  F qb_floor;                    // kConeFloor r: r |m x u| below it counts as that

  /// G only.
  IMPACT_INLINE F overlap(const V3<F>& m) const {
    const F qa2 = a2[0] * m.x * m.x + a2[1] * m.y * m.y + a2[2] * m.z * m.z;
    const F p0 = dot(v[0], m), p1 = dot(v[1], m);
    return sqrt(qa2) + sqrt(p0 * p0 + p1 * p1) + h * abs(dot(m, u)) - dot(m, d);
  }

  /// G, the tangent basis, the Riemannian gradient and Hessian at unit m, on m's own
  /// hemisphere (the rim disk centred at c + s h u: ellipsoid-ellipsoid's terms).
  IMPACT_INLINE void evaluate(const V3<F>& m, newton::Start<F>& s) const {
    newton::tangent_basis(m, s);
    const F sh = select(dot(m, u) < F(0.0f), -h, h);
    newton::ellipsoid_pair_terms<F, 2>(a2, v, madd(d, -sh, u), s, qb_floor);
  }

  /// A trial across the side's circle from `from` is projected onto it (the circle is
  /// the kink between the two rims' pieces: a Newton step from one piece's model
  /// overshoots it, and the start then crawls to it in shrinking steps).
  IMPACT_INLINE V3<F> restrict(const V3<F>& from, const V3<F>& trial) const {
    const F tu = dot(trial, u);
    const auto across = tu * dot(from, u) < F(0.0f);
    F len;
    return select(across, normalize_or(madd(trial, -tu, u), trial, len), trial);
  }

  /// Starts that have reached a kink where it is a local minimum stop there (its exact
  /// candidate covers them; Newton on one piece's model would crawl to it):
  ///  - within kKinkSin of the side's circle where neither rim piece descends into its
  ///    own hemisphere: G = G0 +- h m.u on the two sides, so |G0's slope along u| <= h;
  ///  - within kConeSin of a cap's normal s u that is a strict local minimum (cone_min:
  ///    the rest of G's slope there below kConeSlope of the cone's, r).
  IMPACT_INLINE typename F::Mask settled(const newton::Start<F>& s) const {
    const F mu = dot(s.n, u);
    const V3<F> g = madd(s.t1 * s.g1, s.g2, s.t2);  // G's tangent gradient on m's side
    const F side_h = select(mu < F(0.0f), -h, h);
    const F g0u = dot(g, u) - side_h * (F(1.0f) - mu * mu);
    const auto valley = (abs(mu) < F(kKinkSin)) & (abs(g0u) <= h);
    const auto near_cap = length_sq(simd::cross(s.n, u)) < F(kConeSin * kConeSin);
    return valley | (near_cap & select(mu < F(0.0f), cone_min[1], cone_min[0]));
  }

  /// cone_min from the rest of G's tangent gradient at +-u: +-P(a^2 u) / |a u| - P c.
  IMPACT_INLINE void set_cones(F r) {
    const V3<F> w{a2[0] * u.x, a2[1] * u.y, a2[2] * u.z};
    const F wl = max(sqrt(dot(w, u)), F(1e-30f));
    const V3<F> pw = madd(w, -dot(w, u), u) * (F(1.0f) / wl), pc = madd(d, -dot(d, u), u);
    const F lim = F(kConeSlope) * r;
    cone_slope[0] = pw - pc;
    cone_slope[1] = -pw - pc;
    cone_min[0] = length_sq(cone_slope[0]) < lim * lim;
    cone_min[1] = length_sq(cone_slope[1]) < lim * lim;
  }
};

/// Lanes that may touch: bounding spheres overlapping and no separating direction among
/// the centres' offset, the axis and the ellipsoid's axes (G <= 0 along any certifies
/// separation).
template <class F>
IMPACT_INLINE typename F::Mask may_touch(const V3<F>& dw, const V3<F>& ua, F ra, F ha, const V3<F>& eb,
                                         const M3<F>& rb) {
  const F zero(0.0f);
  const F reach = max(max(eb.x, eb.y), eb.z) + sqrt(ra * ra + ha * ha);
  const F d2 = length_sq(dw);
  // Both supports at unnormalised n (positively homogeneous).
  auto support = [&](const V3<F>& n) {
    const V3<F> l = rb.apply_t(n);
    const F he = sqrt(eb.x * eb.x * l.x * l.x + eb.y * eb.y * l.y * l.y + eb.z * eb.z * l.z * l.z);
    const F nu = dot(n, ua);
    return he + ha * abs(nu) + ra * sqrt(max(length_sq(n) - nu * nu, zero));
  };
  auto m = (d2 < reach * reach) & (support(dw) >= d2);
  m = m & (support(ua) > abs(dot(ua, dw)));
  for (int i = 0; i < 3; ++i) m = m & (support(rb.c[i]) > abs(dot(rb.c[i], dw)));
  return m;
}

/// A lane's solve between solve_front and solve_back: the model, the kept starts and the
/// steps they have taken, the exact candidates, and what the output needs. Every member
/// is a vector of W 4-byte lanes, so lanes move in and out of it field by field
/// (prim::LaneQueue).
template <class F>
struct Solve {
  Pair<F> p;
  newton::Start<F> kept[kKept];
  V3<F> cap, circle, dw, pa;
  F cap_g, circle_g, least, size;
  F av[3];
  M3<F> rb;
  typename F::Int it, row;
};

/// The collision data of W lanes that may touch, part 1: the candidates and the solve up
/// to its kept starts' phase, which runs until no more than defer_at lanes still move
/// (0: to the end). Returns those lanes (to finish with newton::minimise_rest); the
/// others are ready for solve_back.
template <class F>
IMPACT_INLINE typename F::Mask solve_front(const V3<F>& dw, const V3<F>& ua, F ra, F ha, const V3<F>& eb,
                                           const M3<F>& rb, Solve<F>& sv, uint32_t defer_at) {
  using Mask = typename F::Mask;
  const F zero(0.0f), one(1.0f), big(3.0e38f);
  const F emax = max(max(eb.x, eb.y), eb.z);
  const F size = max(max(emax, ra), ha);
  const F inv = one / max(size, F(1e-30f));
  Pair<F>& p = sv.p;
  const F av[3] = {eb.x * inv, eb.y * inv, eb.z * inv};
  for (int i = 0; i < 3; ++i) p.a2[i] = av[i] * av[i];
  p.u = rb.apply_t(ua);
  p.h = ha * inv;
  const F r = ra * inv;
  p.d = rb.apply_t(dw) * (-inv);  // the cylinder's centre, from the ellipsoid's
  const V3<F> e1 = any_perpendicular(p.u), e2 = simd::cross(p.u, e1);
  p.v[0] = e1 * r;
  p.v[1] = e2 * r;
  p.set_cones(r);
  p.qb_floor = max(r * F(kConeFloor), F(1e-30f));

  // 1. The exact candidates: the cap's normal on c's side, the circle's minimiser.
  const V3<F> cap = select(dot(p.u, p.d) < zero, -p.u, p.u);
  const F cap_g = p.overlap(cap);
  V3<F> circle;
  {
    // ellipsoid_solve.h wants the ellipsoid's radii in (0, 1]: its own scale (the
    // direction does not depend on it).
    const F ie = one / max(emax * inv, F(1e-30f));
    const F ae[3] = {av[0] * ie, av[1] * ie, av[2] * ie};
    const ellip::Shadow<F> sh = ellip::shadow(ae, p.u);
    ellip::PointSolve<2, F> st;
    F len;
    circle = normalize_or(ellip::near_normal(sh, p.d * ie, st), e1, len);
    circle = select(dot(circle, p.d) < zero, -circle, circle);
  }
  const F circle_g = p.overlap(circle);

  // 2. Candidates for the rims' pieces, signed towards c, scored by G; the kStarts least
  //    distinct ones start the solve.
  constexpr int kCand = 19 + 2 * kRimAngles;  // as many as consider() calls below
  F cx[kCand], cy[kCand], cz[kCand], cf[kCand], key[kCand];
  int nc = 0;
  auto consider = [&](V3<F> c, Mask valid) {
    const F l2 = length_sq(c);
    const Mask ok = valid & (l2 >= F(1e-12f));
    c = c * (one / sqrt(select(ok, l2, one)));
    c = select(dot(c, p.d) < zero, -c, c);
    const F f = select(ok, p.overlap(c), big);
    cx[nc] = c.x, cy[nc] = c.y, cz[nc] = c.z, cf[nc] = f;
    // f > -4 for lanes that may touch (|c| < the reaches' sum <= 2): key > 0 for tag().
    key[nc] = simd::tag(select(ok, f + F(newton::kKeyShift), big), nc);
    ++nc;
  };
  const F dl2 = length_sq(p.d);
  const Mask has_d = dl2 >= F(1e-24f);
  consider(select(has_d, p.d, p.u), Mask(true));
  const V3<F> ax[3] = {V3<F>{one, zero, zero}, V3<F>{zero, one, zero}, V3<F>{zero, zero, one}};
  for (int i = 0; i < 3; ++i) consider(ax[i], Mask(true));
  for (int i = 0; i < 3; ++i) consider(simd::cross(ax[i], p.u), Mask(true));
  for (int i = 0; i < 3; ++i) consider(madd(p.u, -dot(p.u, ax[i]), ax[i]), Mask(true));
  for (int i = 0; i < 3; ++i) consider(madd(p.d, -dot(p.d, ax[i]), ax[i]), has_d);
  const float weights[3] = {0.25f, 1.0f, 4.0f};
  for (const float w : weights) consider(newton::least_eigenvector<F, 2>(p.a2, p.v, w), Mask(true));
  // Rim points from the one nearest the ellipsoid's centre (-c's direction in the
  // disk's plane), along the ellipsoid's level normal p / a^2 there.
  {
    F len;
    const V3<F> b1 = normalize_or(madd(-p.d, dot(p.d, p.u), p.u), e1, len);
    const V3<F> b2 = simd::cross(p.u, b1);
    const F ia2[3] = {one / max(p.a2[0], F(1e-30f)), one / max(p.a2[1], F(1e-30f)),
                      one / max(p.a2[2], F(1e-30f))};
    for (int side = 0; side < 2; ++side) {
      const V3<F> k = madd(p.d, side == 0 ? p.h : -p.h, p.u);
      const V3<F> su = side == 0 ? -p.u : p.u;  // towards the ellipsoid from this rim's cap
      for (int j = 0; j < kRimAngles; ++j) {
        const V3<F> rho = madd(b1 * F(kRimPointCos[j]), F(kRimPointSin[j]), b2);
        const V3<F> q = madd(k, r, rho);
        // Even angles: the level normal there, kept to the directions along which q is
        // the rim's point nearest the ellipsoid (m in the cone of -u s and -rho); odd
        // ones: the middle of that cone (level normals alone missed a thick disk's rim
        // minimum 0.7 rad from any of them).
        const V3<F> g{q.x * ia2[0], q.y * ia2[1], q.z * ia2[2]};
        const F ga = max(dot(g, su), zero), gb = max(-dot(g, rho), zero);
        if (j % 2 == 0)
          consider(madd(su * ga, -gb, rho), Mask(true));
        else
          consider(su - rho, Mask(true));
      }
    }
  }
  consider(circle, Mask(true));
  // Off each cap's normal down the rest of G's slope there: where the cone point is no
  // minimum, a rim piece's minimum can lie just beside it (a flat disk's edge).
  for (int i = 0; i < 2; ++i) {
    const V3<F> su = i == 0 ? p.u : -p.u;
    F len;
    const V3<F> down = normalize_or(p.cone_slope[i], su, len);
    consider(madd(su, F(-kConeStep), down), len > zero);
  }

  F bf[kStarts];
  V3<F> bn[kStarts];
  newton::select_starts<F, kCand, kStarts>(cx, cy, cz, cf, key, bn, bf);
  // The least score so far: <= 0 certifies separation (no solve needed).
  F least = min(cap_g, circle_g);
  for (int s = 0; s < kStarts; ++s) least = min(least, bf[s]);

  // 3. The solve (its kept phase possibly left to the caller).
  int it;
  const Mask moving = newton::minimise_front<F, kStarts, Pair<F>, kKept>(
      p, bn, bf, (least <= zero) | (size <= zero), sv.kept, &it, defer_at);
  sv.it = typename F::Int(it);
  sv.cap = cap, sv.circle = circle, sv.dw = dw;
  sv.cap_g = cap_g, sv.circle_g = circle_g, sv.least = least, sv.size = size;
  for (int i = 0; i < 3; ++i) sv.av[i] = av[i];
  sv.rb = rb;
  return moving;
}

/// Part 2: the least of the caps, the circle and the solve: count, n (world, A to B),
/// depth, and the point relative to A's centre (its depth in pdepth[0]).
template <class F>
IMPACT_INLINE Lanes<F, 1> solve_back(const Solve<F>& sv) {
  using Mask = typename F::Mask;
  const F zero(0.0f), one(1.0f);
  const Pair<F>& p = sv.p;
  const V3<F>&cap = sv.cap, &circle = sv.circle, &dw = sv.dw;
  const F cap_g = sv.cap_g, circle_g = sv.circle_g, least = sv.least, size = sv.size;
  const F* av = sv.av;
  const M3<F>& rb = sv.rb;
  F best;
  V3<F> m;
  newton::minimise_finish<F, kKept>(sv.kept, best, m);
  best = p.overlap(m);
  {
    const Mask take = circle_g <= best;
    best = select(take, circle_g, best);
    m = select(take, circle, m);
  }
  {
    const Mask take = cap_g <= best;
    best = select(take, cap_g, best);
    m = select(take, cap, m);
  }
  // Lanes certified apart stop at their first separating candidate: count 0 either way.
  best = min(best, least);

  // The ellipsoid's support point along m (towards A), relative to A's centre, world.
  const V3<F> am{av[0] * m.x, av[1] * m.y, av[2] * m.z};
  const F he = sqrt(length_sq(am));
  const F sc = size / select(he > zero, he, one);
  const V3<F> xb{av[0] * am.x * sc, av[1] * am.y * sc, av[2] * am.z * sc};
  Lanes<F, 1> out;
  out.depth = best * size;
  out.n = -rb.apply(m);
  out.point[0] = madd(dw + rb.apply(xb), F(0.5f) * out.depth, out.n);
  out.pdepth[0] = out.depth;
  out.count = simd::to_int(out.depth > zero);
  return out;
}

/// The range through prim::for_each_live_group: the screen writes count 0 for every lane
/// and lists those that may touch (may_touch); the solve runs on full groups of them.
/// The kept starts' phase runs in the group while more than a quarter of its lanes still
/// move (measured: ~8 steps per 16-lane group with ~1.5 lanes moving); the rest are set
/// aside and finished packed W at a time, the chunk's last ones before its expansion.
template <class F>
IMPACT_INLINE void cylinder_ellipsoid_range(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out,
                                            Range r) {
  using Int = typename F::Int;
  constexpr uint32_t W = F::kWidth;
  constexpr uint32_t kDeferAt = W > 1 ? W / 4 : 0;  // one lane: never set aside
  LaneQueue<F, Solve<F>> queue;
  auto finish = [&](LiveOut<F, 1>& o, uint32_t keep) {
    while (queue.n > keep) {
      Solve<F> sv;
      const uint32_t cnt = queue.pop(sv);
      newton::minimise_rest<F, Pair<F>, kKept>(sv.p, sv.kept, sv.it);
      int32_t rows[W];
      sv.row.store(rows);
      o.put_rows(solve_back(sv), sv.pa, rows, cnt);
    }
  };
  for_each_live_group<F, 1>(
      a, b, out, r,
      [&](const LeafSoA& va, const LeafSoA& vb, uint32_t at, uint32_t, uint32_t, NoExtra*) {
        const V3<F> dw = load_p<F>(vb, at) - load_p<F>(va, at);
        return simd::bits(may_touch(dw, load_axis_z<F>(va, at), ld<F>(va.e[0], at), ld<F>(va.e[1], at),
                                    load_e<F>(vb, at), load_r<F>(vb, at)));
      },
      [&](const int32_t* index, const NoExtra*, uint32_t cnt, LiveOut<F, 1>& o) {
        const GroupRows<F> rows(index, r);
        const V3<F> pa = rows.v3(a.p);
        const V3<F> dw = rows.v3(b.p) - pa;
        const M3<F> ra = rows.rot(a);
        Solve<F> sv;
        const auto moving =
            solve_front(dw, ra.c[2], rows(a.e[0]), rows(a.e[1]), rows.v3(b.e), rows.rot(b), sv, kDeferAt);
        o.put(solve_back(sv), pa);
        const uint32_t aside = simd::bits(moving) & ((1u << cnt) - 1u);  // padding lanes repeat a real one
        if (aside != 0) {
          sv.pa = pa;
          sv.row = simd::lane_ids<Int>(static_cast<int32_t>(o.row));
          queue.push(sv, aside);
          finish(o, W - 1);  // full groups only
        }
      },
      [&](LiveOut<F, 1>& o) { finish(o, 0); });
}

}  // namespace

void collide_cylinder_ellipsoid(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, Range r,
                                const NarrowConfig& cfg) {
  if (cfg.path == KernelPath::kScalar) {
    cylinder_ellipsoid_range<simd::Float1>(a, b, out, r);
  } else {
    cylinder_ellipsoid_range<simd::FloatP>(a, b, out, r);
  }
}

}  // namespace impact::kernels
