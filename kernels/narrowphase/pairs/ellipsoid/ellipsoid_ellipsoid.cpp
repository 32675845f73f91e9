// Ellipsoid (A) against ellipsoid (B): the least support overlap of the two bodies over
// the unit sphere of directions, by a multi-start trust-region Newton solve on the sphere,
// vectorised across pairs (one lane = one pair), no GJK / EPA.
//
// Inputs: LeafSoA lanes per leaf.h (both ellipsoids: p, R, radii e0, e1, e2 along R's
// columns), Range r of the bucket.
// Outputs: ManifoldSoA lanes r.begin .. r.end: count (0 or 1), n (unit, A to B), depth,
// point[0] midway between A's support point along n and B's along -n, pdepth[0] = depth.
// Slots 1..3 untouched; count-0 lanes leave the other fields unspecified.
// Method, in A's frame scaled by the pair's largest radius L (A's radii a_i, B's axes
// v_j = (b_j / L) u_j with u_j B's unit axes in A's frame, d = (c_B - c_A) / L in A's
// frame, so poses far from the origin keep their precision): the support function of the
// Minkowski difference B - A (centred) is h(n) = |diag(a) n| + sqrt(sum_j (v_j.n)^2), and
//     f(n) = h(n) - n.d
// is the support overlap along n: the pair overlaps iff f > 0 on the whole sphere; then
// depth = L min f over unit n and n = the minimiser (B moves along +n). Any n with
// f(n) <= 0 certifies separation (count 0).
//  0. A first pass over the range writes count 0 everywhere and lists the lanes that may
//     touch: bounding spheres overlapping and f > 0 along d and the six axes (any f <= 0
//     certifies separation: about half the bench's lanes stop here); those are gathered
//     kSimdWidth at a time into full blocks (prim::for_each_live_group).
//  1. Starts: f at 25 candidate directions, each signed so that n.d >= 0 (f(-n) =
//     f(n) + 2 n.d): d; A's and B's axes (a pancake's normal: a cone point of h); the nine
//     cross products of an A axis and a B axis (two needles: the minimiser is
//     perpendicular to both long axes); d made perpendicular to each of the six axes (a
//     needle's circle); the least eigenvectors of M_A + w M_B, w = 1/4, 1, 4 (h(n) is the
//     least over w of the support of the ellipsoid (1 + 1/w) M_A + (1 + w) M_B: the deep,
//     nearly concentric case; power iteration on the adjugate). The kStarts = 8 least
//     distinct ones start (the least key, then every candidate within |cos| >= 0.9999
//     of it dropped, eight times; keys f + 16 tagged with their index, simd::tag).
//  2. Each start runs sphere_newton.h's trust-region Newton solve on the sphere
//     (Riemannian gradient and Hessian in a tangent basis; Levenberg-Marquardt shift,
//     plus the least eigenvector at the trust radius where the Hessian is indefinite, so
//     a start at a saddle (g = 0) leaves it; the trial mirrored to d's side; accepted
//     when f does not rise by more than its rounding, or by a few roundings while the
//     gradient shrinks, else the radius shrinks x4). All eight run 3 steps, then each
//     lane keeps its two least and runs them until they freeze (accepted step below 1e-6
//     rad at a positive definite Hessian, or radius below 1e-7) or 24 steps; the block
//     stops when every kept (lane, start) is frozen (each lane's bytes depend on its own
//     data only). The least f of the two wins (within f's noise: the smaller gradient;
//     ties: the lower start).
// Global minimum: by multi-start, without a proof. f is convex on R^3 but not on the
// sphere: an interior d can give several local minima (long thin bodies, deep or
// coincident centres). The kernel finds the global one when its basin holds one of the
// two starts kept after three steps; it can fail where the global minimiser is far from
// all 25 candidates and eight other candidates score lower, or where the two kept after
// three steps both lie in other basins. Measured (ellipsoid_ellipsoid_test.cpp at
// IMPACT_TEST_INTENSITY=10, ~2e4 lanes: random poses, needles / pancakes (1e-4) at all
// angles, coincident centres, near touching, sizes 1e-4 / 1e4, 1e5 offsets, against
// dense sampling refined in double): no miss (at IMPACT_TEST_INTENSITY=30, ~6e4 lanes:
// 3 misses, up to 4.6e-3 L too deep or a normal 1.3 rad off, the same before and after
// the solver moved to sphere_newton.h); with 5 starts x 4 steps: 3 lanes missed
// (depth up to 3e-3 L too large), with the 22 candidates without the eigenvectors, 4.
// Degenerate input: coincident centres (d = 0) take the candidates' signs as given (h is
// even, the normal is then one of two opposite minimisers); spheres give d's direction
// (sphere-sphere's answer); d's own candidate falls back to +z when |d| is tiny.
// Preconditions: finite inputs, positive radii, orthonormal R (host-validated); every
// division is guarded, so finite inputs give finite outputs.
// Cost: a first pass (7 support overlaps per lane) over every lane; for the lanes that
// may touch, 25 candidate evaluations (2 square roots each), the selection (min over
// tagged keys, kStarts times, with the near-duplicates knocked out), 8 x 3 Newton steps,
// then 2 x (mostly 1-2) steps (each ~6 square roots and ~6 divisions); no branch on lane
// data in the arithmetic (selects), no libm call; about half the time is the candidates
// and their selection. Measured per pair in docs/results.md ("Narrow phase").
// Both paths run the same template (F = FloatW, or Float1 for the scalar reference).
#include <cstdint>

#include "kernels/narrowphase/pair_kernels.h"
#include "kernels/narrowphase/lanes/lane_io.h"
#include "kernels/narrowphase/lanes/live_lanes.h"
#include "kernels/narrowphase/solvers/sphere_newton.h"

namespace impact::kernels {
namespace {

using namespace prim;  // NOLINT: lane helpers of this kernel family
using simd::dot;
using simd::length_sq;

constexpr int kStarts = 8;

/// The pair in A's scaled frame: newton::minimise's model.
template <class F>
struct Pair {
  F a2[3];     // A's radii squared
  V3<F> v[3];  // B's axes scaled by its radii
  V3<F> d;     // B's centre

  /// f, the tangent basis, the Riemannian gradient and Hessian at unit n.
  IMPACT_INLINE void evaluate(const V3<F>& n, newton::Start<F>& s) const {
    newton::tangent_basis(n, s);
    newton::ellipsoid_pair_terms<F, 3>(a2, v, d, s);
  }
  IMPACT_INLINE V3<F> restrict(const V3<F>&, const V3<F>& trial) const { return trial; }
  IMPACT_INLINE typename F::Mask settled(const newton::Start<F>&) const { return typename F::Mask(false); }
};

/// f only.
template <class F>
IMPACT_INLINE F overlap(const Pair<F>& p, const V3<F>& n) {
  const F qa2 = p.a2[0] * n.x * n.x + p.a2[1] * n.y * n.y + p.a2[2] * n.z * n.z;
  const F p0 = dot(p.v[0], n), p1 = dot(p.v[1], n), p2 = dot(p.v[2], n);
  return sqrt(qa2) + sqrt(p0 * p0 + p1 * p1 + p2 * p2) - dot(n, p.d);
}

/// Lanes that may touch: bounding spheres overlapping and no separating direction among
/// d and the six axes (f(n) <= 0 certifies separation; about half the bench's lanes are
/// certified here).
template <class F>
IMPACT_INLINE typename F::Mask may_touch(const V3<F>& dw, const V3<F>& ea, const V3<F>& eb, const M3<F>& ra,
                                         const M3<F>& rb) {
  const F zero(0.0f);
  const F reach = max(max(ea.x, ea.y), ea.z) + max(max(eb.x, eb.y), eb.z);
  const F d2 = length_sq(dw);
  auto ha = [&](const V3<F>& n) {
    const V3<F> l = ra.apply_t(n);
    return sqrt(ea.x * ea.x * l.x * l.x + ea.y * ea.y * l.y * l.y + ea.z * ea.z * l.z * l.z);
  };
  auto hb = [&](const V3<F>& n) {
    const V3<F> l = rb.apply_t(n);
    return sqrt(eb.x * eb.x * l.x * l.x + eb.y * eb.y * l.y * l.y + eb.z * eb.z * l.z * l.z);
  };
  // Unnormalised d: f(d) |d| = h(d) - |d|^2 (h is positively homogeneous).
  auto m = (d2 < reach * reach) & (ha(dw) + hb(dw) >= d2);
  const F eas[3] = {ea.x, ea.y, ea.z}, ebs[3] = {eb.x, eb.y, eb.z};
  for (int i = 0; i < 3; ++i) {
    m = m & (eas[i] + hb(ra.c[i]) > abs(dot(ra.c[i], dw)));
    m = m & (ebs[i] + ha(rb.c[i]) > abs(dot(rb.c[i], dw)));
  }
  (void)zero;
  return m;
}

/// The collision data of W lanes that may touch: n (world, A to B), depth, and the
/// point relative to A's centre.
template <class F>
IMPACT_INLINE void solve(const V3<F>& dw, const V3<F>& ea, const V3<F>& eb, const M3<F>& ra, const M3<F>& rb,
                         V3<F>& out_n, F& out_depth, V3<F>& out_point) {
  using Mask = typename F::Mask;
  const F zero(0.0f), one(1.0f), big(3.0e38f);
  const F emax = max(max(max(ea.x, ea.y), max(ea.z, eb.x)), max(eb.y, eb.z));
  const F inv = one / max(emax, F(1e-30f));
  Pair<F> p;
  const F eas[3] = {ea.x * inv, ea.y * inv, ea.z * inv};
  const F ebs[3] = {eb.x * inv, eb.y * inv, eb.z * inv};
  V3<F> u[3];
  for (int i = 0; i < 3; ++i) {
    p.a2[i] = eas[i] * eas[i];
    u[i] = ra.apply_t(rb.c[i]);
    p.v[i] = u[i] * ebs[i];
  }
  p.d = ra.apply_t(dw) * inv;

  // 1. Candidates, signed towards d, scored by f; then the kStarts least distinct ones.
  constexpr int kCand = 25;  // as many as consider() calls below
  F cx[kCand], cy[kCand], cz[kCand], cf[kCand], key[kCand];
  int nc = 0;
  auto consider = [&](V3<F> c, Mask valid) {
    const F l2 = length_sq(c);
    const Mask ok = valid & (l2 >= F(1e-12f));
    c = c * (one / sqrt(select(ok, l2, one)));
    c = select(dot(c, p.d) < zero, -c, c);
    const F f = select(ok, overlap(p, c), big);
    cx[nc] = c.x, cy[nc] = c.y, cz[nc] = c.z, cf[nc] = f;
    // f > -4 for lanes that may touch (|d| < the radii sum <= 2): key > 0 for tag().
    key[nc] = simd::tag(select(ok, f + F(newton::kKeyShift), big), nc);
    ++nc;
  };
  const F dl2 = length_sq(p.d);
  const Mask has_d = dl2 >= F(1e-24f);
  consider(select(has_d, p.d, V3<F>{zero, zero, one}), Mask(true));
  const V3<F> ax[3] = {V3<F>{one, zero, zero}, V3<F>{zero, one, zero}, V3<F>{zero, zero, one}};
  for (int i = 0; i < 3; ++i) consider(ax[i], Mask(true));
  for (int j = 0; j < 3; ++j) consider(u[j], Mask(true));
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) consider(simd::cross(ax[i], u[j]), Mask(true));
  for (int i = 0; i < 3; ++i) consider(madd(p.d, -dot(p.d, ax[i]), ax[i]), has_d);
  for (int j = 0; j < 3; ++j) consider(madd(p.d, -dot(p.d, u[j]), u[j]), has_d);
  // The least eigenvector of M_A + w M_B (w = 1/4, 1, 4): h(n)^2 lies between
  // n^T (M_A + M_B) n and twice it, and h(n) = min over w of the support of the
  // ellipsoid (1 + 1/w) M_A + (1 + w) M_B; by power iteration on the adjugate.
  const float weights[3] = {0.25f, 1.0f, 4.0f};
  for (const float w : weights) {
    const V3<F> x = newton::least_eigenvector<F, 3>(p.a2, p.v, w);
    const F l2 = length_sq(x);
    consider(x * (one / sqrt(select(l2 > zero, l2, one))), Mask(true));
  }

  // The least key, then every candidate within kDistinctCos of it out; kStarts times.
  F bf[kStarts];
  V3<F> bn[kStarts];
  newton::select_starts<F, kCand, kStarts>(cx, cy, cz, cf, key, bn, bf);
  // bf[0] is the least candidate f: <= 0 certifies separation.
  for (int s = 1; s < kStarts; ++s) bf[0] = min(bf[0], bf[s]);

  // 2. Trust-region Newton from each start; lanes already separated (or tail padding:
  //    zero radii) are done.
  F best;
  V3<F> n;
  newton::minimise<F, kStarts>(p, bn, bf, (bf[0] <= zero) | (emax <= zero), best, n);

  // Support points (A's along n, B's along -n), relative to A's centre, world.
  const V3<F> wa{p.a2[0] * n.x, p.a2[1] * n.y, p.a2[2] * n.z};
  const F qa = max(sqrt(dot(n, wa)), F(1e-30f));
  const F pj[3] = {dot(p.v[0], n), dot(p.v[1], n), dot(p.v[2], n)};
  const F qb = max(sqrt(pj[0] * pj[0] + pj[1] * pj[1] + pj[2] * pj[2]), F(1e-30f));
  const V3<F> wb = p.v[0] * pj[0] + p.v[1] * pj[1] + p.v[2] * pj[2];
  const V3<F> sa = ra.apply(wa * (emax / qa));
  const V3<F> sb = dw - ra.apply(wb * (emax / qb));
  out_depth = best * emax;
  out_n = ra.apply(n);
  out_point = (sa + sb) * F(0.5f);
}

/// The range through prim::for_each_live_group: the screen writes count 0 for every lane
/// and lists those that may touch (may_touch); the solve runs on full groups of them.
template <class F>
IMPACT_INLINE void ellipsoid_ellipsoid_range(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, Range r) {
  for_each_live_group<F, 1>(
      a, b, out, r,
      [&](const LeafSoA& va, const LeafSoA& vb, uint32_t at, uint32_t, uint32_t, NoExtra*) {
        const V3<F> dw = load_p<F>(vb, at) - load_p<F>(va, at);
        return simd::bits(
            may_touch(dw, load_e<F>(va, at), load_e<F>(vb, at), load_r<F>(va, at), load_r<F>(vb, at)));
      },
      [&](const int32_t* index, const NoExtra*, uint32_t, LiveOut<F, 1>& o) {
        const GroupRows<F> rows(index, r);
        const V3<F> pa = rows.v3(a.p);
        const V3<F> dw = rows.v3(b.p) - pa;
        Lanes<F, 1> m;
        solve(dw, rows.v3(a.e), rows.v3(b.e), rows.rot(a), rows.rot(b), m.n, m.depth, m.point[0]);
        m.count = simd::to_int(m.depth > F(0.0f));
        m.pdepth[0] = m.depth;
        o.put(m, pa);
      });
}

}  // namespace

void collide_ellipsoid_ellipsoid(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, Range r,
                                 const NarrowConfig& cfg) {
  if (cfg.path == KernelPath::kScalar) {
    ellipsoid_ellipsoid_range<simd::Float1>(a, b, out, r);
  } else {
    ellipsoid_ellipsoid_range<simd::FloatP>(a, b, out, r);
  }
}

}  // namespace impact::kernels
