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
//  1. Starts: f at 22 candidate directions, each signed so that n.d >= 0 (f(-n) >= f(n)
//     there): d; A's and B's axes (the minimisers when one body is a pancake: a cone
//     point of h at its normal); the nine cross products of an A axis and a B axis (two
//     needles: the minimiser is perpendicular to both long axes, on the intersection of
//     the two near-kink circles of h); d made perpendicular to each of the six axes (a
//     needle parallel to the other body's axis: the minimiser lies on the needle's
//     circle). The five least distinct ones (|cos| < 0.9999 to the kept ones) start.
//  2. Each start runs a trust-region Newton solve on the sphere (Riemannian gradient and
//     Hessian in a tangent basis; Levenberg-Marquardt shift mu = max(0, |g| / radius -
//     lambda_min), plus the least eigenvector at the trust radius where the Hessian is
//     indefinite, so a start at a saddle (g = 0) leaves it; accepted when f does not rise
//     by more than its rounding, else the radius shrinks x4; retraction by
//     normalisation). All five run kSpread = 4 steps, then each lane keeps its two least
//     and runs them until they freeze (accepted step below 1e-6 rad at a positive
//     definite Hessian, or radius below 1e-7) or kMaxIterations = 24; the block stops
//     when every kept (lane, start) is frozen (each lane's bytes depend on its own data
//     only). The least f of the two wins (ties: the lower start).
// Global minimum: NOT guaranteed. f is convex on R^3 but not on the sphere: an interior d
// can give several local minima (long thin bodies, deep or coincident centres). The
// kernel finds the global one when it lies in the basin of a kept start. Measured
// (tests/kernels/narrowphase/ellipsoid_ellipsoid_test.cpp at IMPACT_TEST_INTENSITY=10,
// ~2e4 lanes against dense sampling refined in double): 4 random-pose lanes in 6000 and
// 1-2 coincident-centre lanes in 2000 end in another local minimum, depth 1e-3 .. 4.5e-2
// L too large; needles / pancakes (aspect 1e-4) at all angles, tiny / huge / far poses
// and near touching: no failure seen. For that reason the kernel is not registered in
// pair_kernel() (ellipsoid pairs take GJK / EPA).
// Degenerate input: coincident centres (d = 0) take the candidates' signs as given (h is
// even, the normal is then one of two opposite minimisers); spheres give d's direction
// (sphere-sphere's answer); d's own candidate falls back to +z when |d| is tiny.
// Preconditions: finite inputs, positive radii, orthonormal R (host-validated); every
// division is guarded, so finite inputs give finite outputs.
// Cost: 22 candidate evaluations (2 square roots each), 5 x 4 Newton steps, then 2 x
// (mostly 1-2) steps (each ~6 square roots and ~6 divisions), the starts' steps
// interleaved stage by stage; a block whose bounding spheres or d's own direction
// separate every lane stops early; no branch on lane data in the arithmetic (selects),
// no libm call. impact_narrowbench BM_Kernel/ellipsoid-ellipsoid/simd/4096 (8 lanes,
// loaded 2-core machine, registered for the run): ~271 ns per pair, FCL ~1810 in the
// same run (6.7x, short of the 10x target); GJK / EPA ~1550 (FCL ~1910) before.
// Both paths run the same template (F = FloatW, or Float1 for the scalar reference).
#include <cstdint>

#include "kernels/narrowphase/pair_kernels.h"
#include "kernels/narrowphase/primitives.h"

namespace impact::kernels {
namespace {

using namespace prim;  // NOLINT: lane helpers of this kernel family
using simd::dot;
using simd::length_sq;

constexpr int kStarts = 5;
constexpr int kSpread = 4;   // steps for every start
constexpr int kKeep = 2;     // starts kept after them
constexpr int kMaxIterations = 24;
constexpr float kStepTol = 1e-6f;     // rad: an accepted step this short freezes the start
constexpr float kRadiusTol = 1e-7f;   // rad: a trust radius this small freezes the start
constexpr float kDistinctCos = 0.9999f;
constexpr float kSlack = 2e-7f;       // of max(|f|, 1): f's rounding

/// The pair in A's scaled frame.
template <class F>
struct Pair {
  F a2[3];     // A's radii squared
  V3<F> v[3];  // B's axes scaled by its radii
  V3<F> d;     // B's centre
};

/// f only.
template <class F>
IMPACT_INLINE F overlap(const Pair<F>& p, const V3<F>& n) {
  const F qa2 = p.a2[0] * n.x * n.x + p.a2[1] * n.y * n.y + p.a2[2] * n.z * n.z;
  const F p0 = dot(p.v[0], n), p1 = dot(p.v[1], n), p2 = dot(p.v[2], n);
  return sqrt(qa2) + sqrt(p0 * p0 + p1 * p1 + p2 * p2) - dot(n, p.d);
}

/// One start's state: the point, f there, its tangent basis, gradient and Hessian
/// (Riemannian, in that basis) and the trust radius.
template <class F>
struct Start {
  V3<F> n, t1, t2;
  F f, g1, g2, h11, h12, h22;
  F radius;
  typename F::Mask frozen;
};

/// f, the tangent basis, the Riemannian gradient and Hessian at unit n.
template <class F>
IMPACT_INLINE void evaluate(const Pair<F>& p, const V3<F>& n, Start<F>& s) {
  const F tiny(1e-30f), one(1.0f);
  // A tangent basis: t1 = n x (the world axis least aligned with n), t2 = n x t1.
  s.n = n;
  s.t1 = any_perpendicular(n);
  s.t2 = simd::cross(n, s.t1);
  const V3<F> wa{p.a2[0] * n.x, p.a2[1] * n.y, p.a2[2] * n.z};
  const F qa = max(sqrt(dot(n, wa)), tiny);
  const F pj[3] = {dot(p.v[0], n), dot(p.v[1], n), dot(p.v[2], n)};
  const F qb = max(sqrt(pj[0] * pj[0] + pj[1] * pj[1] + pj[2] * pj[2]), tiny);
  const V3<F> wb = p.v[0] * pj[0] + p.v[1] * pj[1] + p.v[2] * pj[2];
  s.f = qa + qb - dot(n, p.d);
  const F ia = one / qa, ib = one / qb;
  const V3<F> grad = wa * ia + wb * ib - p.d;
  s.g1 = dot(s.t1, grad);
  s.g2 = dot(s.t2, grad);
  // A: (diag(a^2) - wa wa^T / qa^2) / qa in the basis.
  const F a1 = dot(s.t1, wa) * ia, a2 = dot(s.t2, wa) * ia;
  const F m11 = p.a2[0] * s.t1.x * s.t1.x + p.a2[1] * s.t1.y * s.t1.y + p.a2[2] * s.t1.z * s.t1.z;
  const F m12 = p.a2[0] * s.t1.x * s.t2.x + p.a2[1] * s.t1.y * s.t2.y + p.a2[2] * s.t1.z * s.t2.z;
  const F m22 = p.a2[0] * s.t2.x * s.t2.x + p.a2[1] * s.t2.y * s.t2.y + p.a2[2] * s.t2.z * s.t2.z;
  // B: (sum v v^T - wb wb^T / qb^2) / qb in the basis.
  const F c1[3] = {dot(p.v[0], s.t1), dot(p.v[1], s.t1), dot(p.v[2], s.t1)};
  const F c2[3] = {dot(p.v[0], s.t2), dot(p.v[1], s.t2), dot(p.v[2], s.t2)};
  const F n11 = c1[0] * c1[0] + c1[1] * c1[1] + c1[2] * c1[2];
  const F n12 = c1[0] * c2[0] + c1[1] * c2[1] + c1[2] * c2[2];
  const F n22 = c2[0] * c2[0] + c2[1] * c2[1] + c2[2] * c2[2];
  const F b1 = dot(s.t1, wb) * ib, b2 = dot(s.t2, wb) * ib;
  s.h11 = (m11 - a1 * a1) * ia + (n11 - b1 * b1) * ib - s.f;
  s.h12 = (m12 - a1 * a2) * ia + (n12 - b1 * b2) * ib;
  s.h22 = (m22 - a2 * a2) * ia + (n22 - b2 * b2) * ib - s.f;
}

/// a where m, else b (every field).
template <class F>
IMPACT_INLINE Start<F> pick(typename F::Mask m, const Start<F>& a, const Start<F>& b) {
  Start<F> r;
  r.n = select(m, a.n, b.n);
  r.t1 = select(m, a.t1, b.t1);
  r.t2 = select(m, a.t2, b.t2);
  r.f = select(m, a.f, b.f);
  r.g1 = select(m, a.g1, b.g1);
  r.g2 = select(m, a.g2, b.g2);
  r.h11 = select(m, a.h11, b.h11);
  r.h12 = select(m, a.h12, b.h12);
  r.h22 = select(m, a.h22, b.h22);
  r.radius = select(m, a.radius, b.radius);
  r.frozen = select(m, a.frozen, b.frozen);
  return r;
}

/// What a step's acceptance needs from its proposal.
template <class F>
struct Proposal {
  V3<F> m;
  F lmin, taken;
};

/// A trust-region Newton step's trial point from a start.
template <class F>
IMPACT_INLINE Proposal<F> propose(const Start<F>& s) {
  const F zero(0.0f), one(1.0f);
  // Levenberg-Marquardt shift: H + mu I >= (|g| / radius) I, so the step is at most the
  // trust radius and follows the least-curvature direction where H is indefinite; mu = 0
  // where H is positive definite and the Newton step fits.
  const F half_tr = F(0.5f) * (s.h11 + s.h22), half_df = F(0.5f) * (s.h11 - s.h22);
  const F lmin = half_tr - sqrt(half_df * half_df + s.h12 * s.h12);
  const F gnorm = sqrt(s.g1 * s.g1 + s.g2 * s.g2);
  const F floor = F(1e-6f) * (abs(s.h11) + abs(s.h22) + abs(s.f)) + F(1e-30f);
  const F mu = max(zero, gnorm / s.radius - lmin) + floor;
  const F k11 = s.h11 + mu, k22 = s.h22 + mu, k12 = s.h12;
  const F det = k11 * k22 - k12 * k12;
  const F idet = one / max(det, F(1e-30f));
  F x1 = -(k22 * s.g1 - k12 * s.g2) * idet;
  F x2 = -(k11 * s.g2 - k12 * s.g1) * idet;
  // Negative curvature: add the least eigenvector's direction at the trust radius (downhill
  // sign, + where the gradient is orthogonal), so a start at a saddle or a maximum of f
  // (g = 0: an axis with coincident centres) still leaves it.
  {
    const F va1 = s.h12, va2 = lmin - s.h11, vb1 = lmin - s.h22, vb2 = s.h12;
    const auto use_a = va1 * va1 + va2 * va2 >= vb1 * vb1 + vb2 * vb2;
    F v1 = select(use_a, va1, vb1), v2 = select(use_a, va2, vb2);
    const F vl2 = v1 * v1 + v2 * v2;
    const auto neg = (lmin < -floor) & (vl2 > F(1e-30f));
    const F sc = select(s.g1 * v1 + s.g2 * v2 > zero, -s.radius, s.radius) / sqrt(select(neg, vl2, one));
    x1 = x1 + select(neg, sc * v1, zero);
    x2 = x2 + select(neg, sc * v2, zero);
  }
  const F len = sqrt(x1 * x1 + x2 * x2);
  const F clip = min(one, s.radius / max(len, F(1e-30f)));
  x1 = x1 * clip;
  x2 = x2 * clip;
  const F taken = len * clip;
  V3<F> m = madd(madd(s.n, x1, s.t1), x2, s.t2);
  m = m * (one / sqrt(length_sq(m)));
  return {m, lmin, taken};
}

/// Accepts or refuses trial t of a start (frozen lanes keep their bytes).
template <class F>
IMPACT_INLINE void settle(Start<F>& s, const Start<F>& t, const Proposal<F>& pr) {
  const F zero(0.0f), one(1.0f);
  const F lmin = pr.lmin, taken = pr.taken;
  // Accepted where f does not rise by more than its rounding (so a step that the gradient
  // asks for near the minimum is not refused by noise in f).
  const auto ok = t.f <= s.f + F(kSlack) * (abs(s.f) + one);
  const auto accept = andnot(ok, s.frozen);
  const auto reject = andnot(~ok, s.frozen);
  s.n = select(accept, t.n, s.n);
  s.t1 = select(accept, t.t1, s.t1);
  s.t2 = select(accept, t.t2, s.t2);
  s.f = select(accept, t.f, s.f);
  s.g1 = select(accept, t.g1, s.g1);
  s.g2 = select(accept, t.g2, s.g2);
  s.h11 = select(accept, t.h11, s.h11);
  s.h12 = select(accept, t.h12, s.h12);
  s.h22 = select(accept, t.h22, s.h22);
  const F grown = min(max(s.radius, F(2.0f) * taken), one);
  s.radius = select(accept, grown, select(reject, F(0.25f) * taken, s.radius));
  s.frozen = s.frozen | (accept & (taken < F(kStepTol)) & (lmin > zero)) | (s.radius < F(kRadiusTol));
}

/// One step of `count` starts, stage by stage over the starts (independent chains of
/// square roots and divisions side by side, not one start's chain after another's).
template <class F, int N>
IMPACT_INLINE void step_all(const Pair<F>& p, Start<F>* st, int count) {
  Proposal<F> pr[N];
  Start<F> t[N];
  for (int s = 0; s < N; ++s)
    if (s < count) pr[s] = propose(st[s]);
  for (int s = 0; s < N; ++s)
    if (s < count) evaluate(p, pr[s].m, t[s]);
  for (int s = 0; s < N; ++s)
    if (s < count) settle(st[s], t[s], pr[s]);
}

template <class F>
IMPACT_INLINE void ellipsoid_ellipsoid_block(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out,
                                             uint32_t k) {
  using Mask = typename F::Mask;
  const F zero(0.0f), one(1.0f), big(3.0e38f);
  const V3<F> pa = load_p<F>(a, k);
  const V3<F> dw = load_p<F>(b, k) - pa;  // B's centre from A's (world)
  const V3<F> ea = load_e<F>(a, k), eb = load_e<F>(b, k);
  const F emax = max(max(max(ea.x, ea.y), max(ea.z, eb.x)), max(eb.y, eb.z));
  // Bounding spheres apart in every lane: no contact.
  {
    const F reach = max(max(ea.x, ea.y), ea.z) + max(max(eb.x, eb.y), eb.z);
    if (simd::none(length_sq(dw) < reach * reach)) {
      store_no_contact<F>(out, k);
      return;
    }
  }
  const M3<F> ra = load_r<F>(a, k), rb = load_r<F>(b, k);
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

  // 1. Candidates, signed towards d; keep the three least distinct ones.
  F bf[kStarts];
  V3<F> bn[kStarts];
  for (int s = 0; s < kStarts; ++s) {
    bf[s] = big;
    bn[s] = V3<F>{zero, zero, one};
  }
  auto consider = [&](V3<F> c, Mask valid) {
    const F l2 = length_sq(c);
    const Mask ok = valid & (l2 >= F(1e-12f));
    c = c * (one / sqrt(select(ok, l2, one)));
    c = select(dot(c, p.d) < zero, -c, c);
    const F f = select(ok, overlap(p, c), big);
    Mask dup = Mask(false);
    for (int s = 0; s < kStarts; ++s) dup = dup | ((abs(dot(c, bn[s])) >= F(kDistinctCos)) & (bf[s] < big));
    // Insert into the sorted list (a duplicate of a kept one is dropped).
    Mask place = andnot(f < bf[kStarts - 1], dup);
    for (int s = kStarts - 1; s >= 0; --s) {
      const Mask here = place & ((s == 0) ? Mask(true) : ~(f < bf[s - 1]));
      if (s > 0) {
        const Mask shift = place & (f < bf[s - 1]);
        bf[s] = select(here, f, select(shift, bf[s - 1], bf[s]));
        bn[s] = select(here, c, select(shift, bn[s - 1], bn[s]));
      } else {
        bf[s] = select(here, f, bf[s]);
        bn[s] = select(here, c, bn[s]);
      }
      place = andnot(place, here);
    }
  };
  const F dl2 = length_sq(p.d);
  const Mask has_d = dl2 >= F(1e-24f);
  consider(select(has_d, p.d, V3<F>{zero, zero, one}), Mask(true));
  // d's own direction separates every lane: no contact.
  if (simd::none(bf[0] > zero)) {
    store_no_contact<F>(out, k);
    return;
  }
  const V3<F> ax[3] = {V3<F>{one, zero, zero}, V3<F>{zero, one, zero}, V3<F>{zero, zero, one}};
  for (int i = 0; i < 3; ++i) consider(ax[i], Mask(true));
  for (int j = 0; j < 3; ++j) consider(u[j], Mask(true));
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) consider(simd::cross(ax[i], u[j]), Mask(true));
  for (int i = 0; i < 3; ++i) consider(madd(p.d, -dot(p.d, ax[i]), ax[i]), has_d);
  for (int j = 0; j < 3; ++j) consider(madd(p.d, -dot(p.d, u[j]), u[j]), has_d);

  // 2. Trust-region Newton from each start; lanes already separated are done.
  const Mask apart = bf[0] <= zero;
  Start<F> st[kStarts];
  for (int s = 0; s < kStarts; ++s) {
    st[s].radius = F(0.5f);
    evaluate(p, bn[s], st[s]);
    st[s].frozen = apart | (bf[s] >= big) | (emax <= zero);  // (zero radii: tail padding)
  }
  // Every start for kSpread steps (each settles into its basin), then the kKeep least
  // ones (per lane; ties: the lower start) until they freeze or kMaxIterations.
  auto run = [&](int count, int from, int to) {
    for (int it = from; it < to; ++it) {
      Mask all = st[0].frozen;
      for (int s = 1; s < count; ++s) all = all & st[s].frozen;
      if (simd::all(all)) break;
      step_all<F, kStarts>(p, st, count);
    }
  };
  run(kStarts, 0, kSpread);
  for (int i = 0; i < kKeep; ++i) {
    for (int j = kStarts - 1; j > i; --j) {
      const Mask lower = st[j].f < st[j - 1].f;
      const Start<F> hi = st[j - 1], lo = st[j];
      st[j - 1] = pick(lower, lo, hi);
      st[j] = pick(lower, hi, lo);
    }
  }
  run(kKeep, kSpread, kMaxIterations);
  F best = st[0].f;
  V3<F> n = st[0].n;
  for (int s = 1; s < kKeep; ++s) {
    const Mask take = st[s].f < best;
    best = select(take, st[s].f, best);
    n = select(take, st[s].n, n);
  }
  n = n * (one / sqrt(length_sq(n)));

  // Support points (A's along n, B's along -n), relative to A's centre, world.
  const V3<F> wa{p.a2[0] * n.x, p.a2[1] * n.y, p.a2[2] * n.z};
  const F qa = max(sqrt(dot(n, wa)), F(1e-30f));
  const F pj[3] = {dot(p.v[0], n), dot(p.v[1], n), dot(p.v[2], n)};
  const F qb = max(sqrt(pj[0] * pj[0] + pj[1] * pj[1] + pj[2] * pj[2]), F(1e-30f));
  const V3<F> wb = p.v[0] * pj[0] + p.v[1] * pj[1] + p.v[2] * pj[2];
  const V3<F> sa = ra.apply(wa * (emax / qa));
  const V3<F> sb = dw - ra.apply(wb * (emax / qb));
  const F depth = best * emax;
  Lanes<F, 1> m;
  m.count = simd::to_int(depth > zero);
  m.n = ra.apply(n);
  m.depth = depth;
  m.point[0] = (sa + sb) * F(0.5f);
  m.pdepth[0] = depth;
  store(out, k, m, pa);
}

}  // namespace

IMPACT_LANE_KERNEL(collide_ellipsoid_ellipsoid, ellipsoid_ellipsoid_block, 1)

}  // namespace impact::kernels
