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
//  2. Each start runs a trust-region Newton solve on the sphere (Riemannian gradient and
//     Hessian in a tangent basis; Levenberg-Marquardt shift mu = max(0, |g|_1 / radius -
//     lambda_min), plus the least eigenvector at the trust radius where the Hessian is
//     indefinite, so a start at a saddle (g = 0) leaves it; the trial mirrored to d's side;
//     accepted when f does not rise by more than its rounding, else the radius shrinks x4;
//     retraction by normalisation). All eight run kSpread = 3 steps (stage by stage over
//     the starts: independent square-root / division chains side by side), then each lane
//     keeps its two least and runs them until they freeze (accepted step below 1e-6 rad
//     at a positive definite Hessian, or radius below 1e-7) or kMaxIterations = 24; the
//     block stops when every kept (lane, start) is frozen (each lane's bytes depend on
//     its own data only). The least f of the two wins (ties: the lower start).
// Global minimum: by multi-start, without a proof. f is convex on R^3 but not on the
// sphere: an interior d can give several local minima (long thin bodies, deep or
// coincident centres). The kernel finds the global one when its basin holds one of the
// two starts kept after three steps; it can fail where the global minimiser is far from
// all 25 candidates and eight other candidates score lower, or where the two kept after
// three steps both lie in other basins. Measured (ellipsoid_ellipsoid_test.cpp at
// IMPACT_TEST_INTENSITY=10, ~2e4 lanes: random poses, needles / pancakes (1e-4) at all
// angles, coincident centres, near touching, sizes 1e-4 / 1e4, 1e5 offsets, against
// dense sampling refined in double): no miss; with 5 starts x 4 steps: 3 lanes missed
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
// data in the arithmetic (selects), no libm call. impact_narrowbench
// BM_Kernel/ellipsoid-ellipsoid/simd/4096 (8 lanes, loaded 2-core machine): ~237 ns per
// pair, FCL ~2070 in the same run (8.7x; ~208 in a single run), GJK / EPA ~1550 before
// (FCL ~1910 in that run); about half of it is the candidates and their selection.
// Both paths run the same template (F = FloatW, or Float1 for the scalar reference).
#include <cstdint>

#include "kernels/narrowphase/pair_kernels.h"
#include "kernels/narrowphase/primitives.h"

namespace impact::kernels {
namespace {

using namespace prim;  // NOLINT: lane helpers of this kernel family
using simd::dot;
using simd::length_sq;

constexpr int kStarts = 8;
constexpr int kSpread = 3;   // steps for every start
constexpr int kKeep = 2;     // starts kept after them
constexpr int kMaxIterations = 24;
constexpr float kStepTol = 1e-6f;     // rad: an accepted step this short freezes the start
constexpr float kRadiusTol = 1e-7f;   // rad: a trust radius this small freezes the start
constexpr float kDistinctCos = 0.9999f;
constexpr float kSlack = 2e-7f;       // of max(|f|, 1): f's rounding
constexpr float kKeyShift = 16.0f;    // f + this > 0 for the selection's tags

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
IMPACT_INLINE Proposal<F> propose(const Pair<F>& p, const Start<F>& s) {
  const F zero(0.0f), one(1.0f);
  // Levenberg-Marquardt shift: H + mu I >= (|g| / radius) I, so the step is at most the
  // trust radius and follows the least-curvature direction where H is indefinite; mu = 0
  // where H is positive definite and the Newton step fits.
  const F half_tr = F(0.5f) * (s.h11 + s.h22), half_df = F(0.5f) * (s.h11 - s.h22);
  const F lmin = half_tr - sqrt(half_df * half_df + s.h12 * s.h12);
  const F gnorm = abs(s.g1) + abs(s.g2);  // >= |g|: the step still fits the radius
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
  // The trial on d's side: f(-m) = f(m) + 2 m.d (h is even), so where m.d < 0 its mirror
  // is lower (a start that wandered past the equator comes back).
  m = select(dot(m, p.d) < zero, -m, m);
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
    if (s < count) pr[s] = propose(p, st[s]);
  for (int s = 0; s < N; ++s)
    if (s < count) evaluate(p, pr[s].m, t[s]);
  for (int s = 0; s < N; ++s)
    if (s < count) settle(st[s], t[s], pr[s]);
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
    key[nc] = simd::tag(select(ok, f + F(kKeyShift), big), nc);
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
    const F vx[3] = {p.v[0].x, p.v[1].x, p.v[2].x}, vy[3] = {p.v[0].y, p.v[1].y, p.v[2].y},
            vz[3] = {p.v[0].z, p.v[1].z, p.v[2].z};
    F b00 = zero, b01 = zero, b02 = zero, b11 = zero, b12 = zero, b22 = zero;
    for (int j = 0; j < 3; ++j) {
      b00 = b00 + vx[j] * vx[j];
      b01 = b01 + vx[j] * vy[j];
      b02 = b02 + vx[j] * vz[j];
      b11 = b11 + vy[j] * vy[j];
      b12 = b12 + vy[j] * vz[j];
      b22 = b22 + vz[j] * vz[j];
    }
    const F ww(w);
    const F m00 = p.a2[0] + ww * b00, m11 = p.a2[1] + ww * b11, m22 = p.a2[2] + ww * b22;
    const F m01 = ww * b01, m02 = ww * b02, m12 = ww * b12;
    const F c00 = m11 * m22 - m12 * m12, c11 = m00 * m22 - m02 * m02, c22 = m00 * m11 - m01 * m01;
    const F c01 = m02 * m12 - m01 * m22, c02 = m01 * m12 - m02 * m11, c12 = m01 * m02 - m00 * m12;
    const Mask use0 = (c00 >= c11) & (c00 >= c22), use1 = andnot(c11 >= c22, use0);
    V3<F> x{c02, c12, c22};
    x = select(use1, V3<F>{c01, c11, c12}, x);
    x = select(use0, V3<F>{c00, c01, c02}, x);
    // Each product scaled by 1 / trace (>= the dominant eigenvalue, <= 3 times it): no
    // overflow or underflow whatever the sizes.
    const F tr = c00 + c11 + c22;
    const F it = one / select(tr > zero, tr, one);
    for (int rep = 0; rep < 3; ++rep) {
      x = V3<F>{(c00 * x.x + c01 * x.y + c02 * x.z) * it, (c01 * x.x + c11 * x.y + c12 * x.z) * it,
                (c02 * x.x + c12 * x.y + c22 * x.z) * it};
    }
    x = x * it;
    const F l2 = length_sq(x);
    consider(x * (one / sqrt(select(l2 > zero, l2, one))), Mask(true));
  }

  // The least key, then every candidate within kDistinctCos of it out; kStarts times.
  F bf[kStarts];
  V3<F> bn[kStarts];
  for (int s = 0; s < kStarts; ++s) {
    F m = key[0];
    for (int i = 1; i < kCand; ++i) m = min(m, key[i]);
    const Mask any_left = m < F(1e30f);
    // A knocked-out key is untagged, so a lane with none left points at candidate 0.
    const typename F::Int idx = select(any_left, simd::tag_index(m), typename F::Int(0));
    const V3<F> c{simd::gather_lanes(cx, idx), simd::gather_lanes(cy, idx), simd::gather_lanes(cz, idx)};
    bf[s] = select(any_left, simd::gather_lanes(cf, idx), big);
    bn[s] = select(any_left, c, V3<F>{zero, zero, one});
    for (int i = 0; i < kCand; ++i) {
      const F cs = abs(cx[i] * c.x + cy[i] * c.y + cz[i] * c.z);
      key[i] = select(cs >= F(kDistinctCos), big, key[i]);
    }
  }
  // bf[0] is the least candidate f: <= 0 certifies separation.
  for (int s = 1; s < kStarts; ++s) bf[0] = min(bf[0], bf[s]);

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
  out_depth = best * emax;
  out_n = ra.apply(n);
  out_point = (sa + sb) * F(0.5f);
}

/// The range through prim::for_each_live_group: the screen writes count 0 for every lane
/// and lists those that may touch (may_touch); the solve runs on full groups of them.
template <class F>
IMPACT_INLINE void ellipsoid_ellipsoid_range(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, Range r) {
  using Int = typename F::Int;
  for_each_live_group<F>(
      a, b, out, r,
      [&](const LeafSoA& va, const LeafSoA& vb, uint32_t at, uint32_t, uint32_t, NoExtra*) {
        const V3<F> dw = load_p<F>(vb, at) - load_p<F>(va, at);
        return simd::bits(
            may_touch(dw, load_e<F>(va, at), load_e<F>(vb, at), load_r<F>(va, at), load_r<F>(vb, at)));
      },
      [&](const int32_t* index, const NoExtra*, uint32_t cnt) {
        const Int idx = Int::load(index);
        const V3<F> pa = gather3<F>(a.p, idx);
        const V3<F> dw = gather3<F>(b.p, idx) - pa;
        Lanes<F, 1> m;
        solve(dw, gather3<F>(a.e, idx), gather3<F>(b.e, idx), gather_r<F>(a, idx), gather_r<F>(b, idx), m.n,
              m.depth, m.point[0]);
        m.count = simd::to_int(m.depth > F(0.0f));
        m.pdepth[0] = m.depth;
        scatter(out, index, cnt, m, pa);
      });
}

}  // namespace

void collide_ellipsoid_ellipsoid(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, Range r,
                                 const NarrowConfig& cfg) {
  if (cfg.path == KernelPath::kScalar) {
    ellipsoid_ellipsoid_range<simd::Float1>(a, b, out, r);
  } else {
    ellipsoid_ellipsoid_range<simd::FloatW>(a, b, out, r);
  }
}

}  // namespace impact::kernels
