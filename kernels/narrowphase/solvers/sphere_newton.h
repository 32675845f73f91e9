// Multi-start trust-region Newton minimisation on the unit sphere, vectorised across
// pairs (one lane = one pair): the solve shared by the kernels that minimise a support
// overlap f(n) = h(n) - n.d directly (ellipsoid_ellipsoid.cpp, cylinder_ellipsoid.cpp).
//
// A Model provides
//     V3<F> d;                                        // f(-n) = f(n) + 2 n.d (h even)
//     void evaluate(const V3<F>& n, Start<F>& s) const;  // f, tangent basis, gradient
//                                                        // and Hessian at unit n
//     V3<F> restrict(const V3<F>& from, const V3<F>& trial) const;  // a trial kept to
//                                        // from's smooth piece (unit in, unit out)
//     Mask settled(const Start<F>& s) const;  // freeze s here as well (after each step)
// and the kernel supplies the starts (select_starts picks the least distinct ones of its
// candidates). Each start runs a trust-region Newton solve (Riemannian gradient and
// Hessian in a tangent basis; Levenberg-Marquardt shift mu = max(0, |g|_1 / radius -
// lambda_min), plus the least eigenvector at the trust radius where the Hessian is
// indefinite, so a start at a saddle (g = 0) leaves it; the trial mirrored to d's side;
// accepted when f does not rise by more than its rounding, else the radius shrinks x4;
// retraction by normalisation). All starts run kSpread steps (stage by stage over the
// starts: independent square-root / division chains side by side), then each lane keeps
// its kKeep least and runs them until they freeze (accepted step below kStepTol at a
// positive definite Hessian, or radius below kRadiusTol) or kMaxIterations; the block
// stops when every kept (lane, start) is frozen, so each lane's bytes depend on its own
// data only. The least f of those kept wins (ties: the lower start). minimise is
// minimise_front + minimise_finish; a kernel may instead stop the kept phase once few of
// a block's lanes still move and finish those packed with other blocks' (minimise_rest,
// each lane with its own count of steps: the same bytes; cylinder_ellipsoid.cpp).
#pragma once

#include <bit>

#include "kernels/narrowphase/lanes/lane_geometry.h"

namespace impact::kernels::newton {

using prim::M3;
using prim::V3;

constexpr int kSpread = 3;  // steps for every start
constexpr int kKeep = 2;    // starts kept after them
constexpr int kMaxIterations = 24;
constexpr float kStepTol = 1e-6f;    // rad: an accepted step this short freezes the start
constexpr float kRadiusTol = 1e-7f;  // rad: a trust radius this small freezes the start
constexpr float kDistinctCos = 0.9999f;
constexpr float kSlack = 2e-7f;      // of max(|f|, 1): f's rounding
constexpr float kKeyShift = 16.0f;   // f + this > 0 for the selection's tags
constexpr float kNoiseSlack = 8.0f;  // x kSlack: a rise accepted while the gradient shrinks

/// One start's state: the point, f there, its tangent basis, gradient and Hessian
/// (Riemannian, in that basis) and the trust radius.
template <class F>
struct Start {
  V3<F> n, t1, t2;
  F f, g1, g2, h11, h12, h22;
  F radius;
  typename F::Mask frozen;
};

/// A tangent basis at unit n: t1 = n x (the world axis least aligned with n), t2 = n x t1.
template <class F>
IMPACT_INLINE void tangent_basis(const V3<F>& n, Start<F>& s) {
  s.n = n;
  s.t1 = prim::any_perpendicular(n);
  s.t2 = simd::cross(n, s.t1);
}

/// The Riemannian gradient and Hessian at unit n of the sum of an ellipsoid's support
/// |diag(a) n| (a2 = a^2), a second one's sqrt(sum_j (v_j.n)^2) (j < NB) and -n.d, in the
/// basis of s (tangent_basis first): f, g and H into s. The second support's curvature
/// terms divide by it, floored at qb_floor (a flat second ellipsoid's support vanishes
/// along its normal: the floor keeps H finite there).
template <class F, int NB>
IMPACT_INLINE void ellipsoid_pair_terms(const F* a2, const V3<F>* v, const V3<F>& d, Start<F>& s,
                                        F qb_floor = F(1e-30f)) {
  using simd::dot;
  const F tiny(1e-30f), one(1.0f);
  const V3<F>& n = s.n;
  const V3<F> wa{a2[0] * n.x, a2[1] * n.y, a2[2] * n.z};
  const F qa = max(sqrt(dot(n, wa)), tiny);
  F pj[NB];
  F q2 = pj[0] = dot(v[0], n);
  q2 = q2 * q2;
  V3<F> wb = v[0] * pj[0];
  for (int j = 1; j < NB; ++j) {
    pj[j] = dot(v[j], n);
    q2 = q2 + pj[j] * pj[j];
    wb = wb + v[j] * pj[j];
  }
  const F qb = max(sqrt(q2), qb_floor);
  s.f = qa + qb - dot(n, d);
  const F ia = one / qa, ib = one / qb;
  const V3<F> grad = wa * ia + wb * ib - d;
  s.g1 = dot(s.t1, grad);
  s.g2 = dot(s.t2, grad);
  // A: (diag(a^2) - wa wa^T / qa^2) / qa in the basis.
  const F a1 = dot(s.t1, wa) * ia, a2b = dot(s.t2, wa) * ia;
  const F m11 = a2[0] * s.t1.x * s.t1.x + a2[1] * s.t1.y * s.t1.y + a2[2] * s.t1.z * s.t1.z;
  const F m12 = a2[0] * s.t1.x * s.t2.x + a2[1] * s.t1.y * s.t2.y + a2[2] * s.t1.z * s.t2.z;
  const F m22 = a2[0] * s.t2.x * s.t2.x + a2[1] * s.t2.y * s.t2.y + a2[2] * s.t2.z * s.t2.z;
  // B: (sum v v^T - wb wb^T / qb^2) / qb in the basis.
  F n11, n12, n22;
  {
    const F c1 = dot(v[0], s.t1), c2 = dot(v[0], s.t2);
    n11 = c1 * c1, n12 = c1 * c2, n22 = c2 * c2;
  }
  for (int j = 1; j < NB; ++j) {
    const F c1 = dot(v[j], s.t1), c2 = dot(v[j], s.t2);
    n11 = n11 + c1 * c1;
    n12 = n12 + c1 * c2;
    n22 = n22 + c2 * c2;
  }
  const F b1 = dot(s.t1, wb) * ib, b2 = dot(s.t2, wb) * ib;
  s.h11 = (m11 - a1 * a1) * ia + (n11 - b1 * b1) * ib - s.f;
  s.h12 = (m12 - a1 * a2b) * ia + (n12 - b1 * b2) * ib;
  s.h22 = (m22 - a2b * a2b) * ia + (n22 - b2 * b2) * ib - s.f;
}

/// The least eigenvector (unnormalised) of diag(a2) + w sum_j v_j v_j^T (j < NB), by
/// three steps of power iteration on the adjugate from its largest column, each product
/// scaled by 1 / trace (>= the dominant eigenvalue, <= 3 times it): no overflow or
/// underflow whatever the sizes. (h(n) = |diag(a) n| + |V^T n| is the least over w of
/// the support of the ellipsoid (1 + 1/w) diag(a2) + (1 + w) V V^T: these directions
/// start the deep, nearly concentric case.)
template <class F, int NB>
IMPACT_INLINE V3<F> least_eigenvector(const F* a2, const V3<F>* v, float w) {
  using Mask = typename F::Mask;
  const F zero(0.0f), one(1.0f);
  F b00 = zero, b01 = zero, b02 = zero, b11 = zero, b12 = zero, b22 = zero;
  for (int j = 0; j < NB; ++j) {
    b00 = b00 + v[j].x * v[j].x;
    b01 = b01 + v[j].x * v[j].y;
    b02 = b02 + v[j].x * v[j].z;
    b11 = b11 + v[j].y * v[j].y;
    b12 = b12 + v[j].y * v[j].z;
    b22 = b22 + v[j].z * v[j].z;
  }
  const F ww(w);
  const F m00 = a2[0] + ww * b00, m11 = a2[1] + ww * b11, m22 = a2[2] + ww * b22;
  const F m01 = ww * b01, m02 = ww * b02, m12 = ww * b12;
  const F c00 = m11 * m22 - m12 * m12, c11 = m00 * m22 - m02 * m02, c22 = m00 * m11 - m01 * m01;
  const F c01 = m02 * m12 - m01 * m22, c02 = m01 * m12 - m02 * m11, c12 = m01 * m02 - m00 * m12;
  const Mask use0 = (c00 >= c11) & (c00 >= c22), use1 = andnot(c11 >= c22, use0);
  V3<F> x{c02, c12, c22};
  x = select(use1, V3<F>{c01, c11, c12}, x);
  x = select(use0, V3<F>{c00, c01, c02}, x);
  const F tr = c00 + c11 + c22;
  const F it = one / select(tr > zero, tr, one);
  for (int rep = 0; rep < 3; ++rep) {
    x = V3<F>{(c00 * x.x + c01 * x.y + c02 * x.z) * it, (c01 * x.x + c11 * x.y + c12 * x.z) * it,
              (c02 * x.x + c12 * x.y + c22 * x.z) * it};
  }
  return x * it;
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

/// A trust-region Newton step's trial point from a start (the model's restrict(), then
/// mirrored to d's side).
template <class F, class Model>
IMPACT_INLINE Proposal<F> propose(const Model& p, const Start<F>& s) {
  using simd::dot;
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
  V3<F> m = simd::madd(simd::madd(s.n, x1, s.t1), x2, s.t2);
  m = p.restrict(s.n, m * (one / sqrt(simd::length_sq(m))));
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
  // asks for near the minimum is not refused by noise in f), or by a few times that while
  // the gradient shrinks: near the minimum f is a small difference of terms of order 1
  // and its noise can exceed that allowance, so a start sitting on a low rounding of f
  // would otherwise refuse every step and freeze short of the minimum.
  const F slack = F(kSlack) * (abs(s.f) + one);
  const F gs = s.g1 * s.g1 + s.g2 * s.g2, gt = t.g1 * t.g1 + t.g2 * t.g2;
  const auto ok = (t.f <= s.f + slack) | ((t.f <= s.f + F(kNoiseSlack) * slack) & (gt < gs));
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
template <class F, int N, class Model>
IMPACT_INLINE void step_all(const Model& p, Start<F>* st, int count) {
  Proposal<F> pr[N];
  Start<F> t[N];
  for (int s = 0; s < N; ++s)
    if (s < count) pr[s] = propose(p, st[s]);
  for (int s = 0; s < N; ++s)
    if (s < count) p.evaluate(pr[s].m, t[s]);
  for (int s = 0; s < N; ++s)
    if (s < count) {
      settle(st[s], t[s], pr[s]);
      st[s].frozen = st[s].frozen | p.settled(st[s]);
    }
}

/// The kStarts least distinct of kCand candidates (unit directions cx, cy, cz with f in
/// cf and tagged keys key, simd::tag(f + kKeyShift, index), or >= 1e30 where invalid):
/// the least key, then every candidate within kDistinctCos of it knocked out, kStarts
/// times. bf[s] = 3e38 where a lane ran out of candidates.
template <class F, int kCand, int kStarts>
IMPACT_INLINE void select_starts(const F* cx, const F* cy, const F* cz, const F* cf, F* key, V3<F>* bn,
                                 F* bf) {
  static_assert(kCand <= 32, "simd::tag keeps 5 bits of index");
  const F zero(0.0f), one(1.0f), big(3.0e38f);
  for (int s = 0; s < kStarts; ++s) {
    F m = key[0];
    for (int i = 1; i < kCand; ++i) m = min(m, key[i]);
    const auto any_left = m < F(1e30f);
    // A knocked-out key is untagged, so a lane with none left points at candidate 0.
    const typename F::Int idx = select(any_left, simd::tag_index(m), typename F::Int(0));
    const V3<F> c{simd::gather_lanes(cx, idx), simd::gather_lanes(cy, idx), simd::gather_lanes(cz, idx)};
    bf[s] = select(any_left, simd::gather_lanes(cf, idx), big);
    bn[s] = select(any_left, c, V3<F>{zero, zero, one});
    if (s + 1 == kStarts) break;  // no selection follows
    for (int i = 0; i < kCand; ++i) {
      const F cs = abs(cx[i] * c.x + cy[i] * c.y + cz[i] * c.z);
      key[i] = select(cs >= F(kDistinctCos), big, key[i]);
    }
  }
}

/// Runs the starts bn (f values bf; lanes in `done`, or whose start is 3e38, stay
/// frozen) as the header describes, up to the kept starts' phase: those (kept[0 ..
/// kKept)) run until every lane's are frozen or kMaxIterations steps are done, or, with
/// defer_at > 0, until no more than defer_at lanes still move. Returns those lanes (none
/// otherwise) and in *it the steps done; the caller finishes them with minimise_rest,
/// packed with other blocks' (their bytes do not depend on which lanes share a block).
template <class F, int kStarts, class Model, int kKept = kKeep>
IMPACT_INLINE typename F::Mask minimise_front(const Model& p, const V3<F>* bn, const F* bf,
                                              typename F::Mask done, Start<F>* kept, int* it,
                                              uint32_t defer_at) {
  using Mask = typename F::Mask;
  const F big(3.0e38f);
  Start<F> st[kStarts];
  for (int s = 0; s < kStarts; ++s) {
    st[s].radius = F(0.5f);
    p.evaluate(bn[s], st[s]);
    st[s].frozen = done | (bf[s] >= big);
  }
  auto all_frozen = [&](int count) {
    Mask all = st[0].frozen;
    for (int s = 1; s < count; ++s) all = all & st[s].frozen;
    return all;
  };
  for (int i = 0; i < kSpread; ++i) {
    if (simd::all(all_frozen(kStarts))) break;
    step_all<F, kStarts>(p, st, kStarts);
  }
  // The kKept least f in order, the first among ties (what a stable sort gives): their
  // indices first, then one select per start and field (not a bubble of whole starts).
  {
    using Int = typename F::Int;
    Int taken[kKept];
    for (int i = 0; i < kKept; ++i) {
      F least(INFINITY);
      Int at(0);
      for (int s = 0; s < kStarts; ++s) {
        Mask free(true);
        for (int j = 0; j < i; ++j) free = andnot(free, taken[j] == Int(s));
        const Mask lower = free & (st[s].f < least);
        least = select(lower, st[s].f, least);
        at = select(lower, Int(s), at);
      }
      taken[i] = at;
    }
    Start<F> chosen[kKept];
    for (int i = 0; i < kKept; ++i) {
      chosen[i] = st[0];
      for (int s = 1; s < kStarts; ++s) chosen[i] = pick(taken[i] == Int(s), st[s], chosen[i]);
    }
    for (int i = 0; i < kKept; ++i) st[i] = chosen[i];
  }
  Mask moving(false);
  int at = kSpread;
  for (; at < kMaxIterations; ++at) {
    const uint32_t m = simd::bits(~all_frozen(kKept));
    if (m == 0) break;
    if (static_cast<uint32_t>(std::popcount(m)) <= defer_at) {
      moving = ~all_frozen(kKept);
      break;
    }
    step_all<F, kStarts>(p, st, kKept);
  }
  for (int s = 0; s < kKept; ++s) kept[s] = st[s];
  *it = at;
  return moving;
}

/// The kept starts of minimise_front's deferred lanes, each with its own count of steps
/// done (it), run on until frozen or kMaxIterations (the same steps as without the
/// deferral).
template <class F, class Model, int kKept = kKeep>
IMPACT_INLINE void minimise_rest(const Model& p, Start<F>* st, typename F::Int it) {
  using Int = typename F::Int;
  for (;;) {
    const auto capped = it > Int(kMaxIterations - 1);
    auto all = st[0].frozen | capped;
    for (int s = 1; s < kKept; ++s) all = all & (st[s].frozen | capped);
    if (simd::all(all)) break;
    for (int s = 0; s < kKept; ++s) st[s].frozen = st[s].frozen | capped;
    step_all<F, kKept>(p, st, kKept);
    it = it + Int(1);
  }
}

/// The least f of the kept starts and its unit direction.
template <class F, int kKept = kKeep>
IMPACT_INLINE void minimise_finish(const Start<F>* st, F& best, V3<F>& n) {
  using Mask = typename F::Mask;
  best = st[0].f;
  n = st[0].n;
  // The least f; within f's noise (kNoiseSlack roundings) of it, the smaller gradient.
  F gb = st[0].g1 * st[0].g1 + st[0].g2 * st[0].g2;
  for (int s = 1; s < kKept; ++s) {
    const F slack = F(kNoiseSlack * kSlack) * (abs(best) + F(1.0f));
    const F gs = st[s].g1 * st[s].g1 + st[s].g2 * st[s].g2;
    const Mask take = (st[s].f < best - slack) | ((st[s].f < best + slack) & (gs < gb));
    best = select(take, st[s].f, best);
    gb = select(take, gs, gb);
    n = select(take, st[s].n, n);
  }
  n = n * (F(1.0f) / sqrt(simd::length_sq(n)));
}

/// minimise_front without deferral, then minimise_finish: the least f reached and its
/// unit direction.
template <class F, int kStarts, class Model, int kKept = kKeep>
IMPACT_INLINE void minimise(const Model& p, const V3<F>* bn, const F* bf, typename F::Mask done, F& best,
                            V3<F>& n) {
  Start<F> kept[kKept];
  int it;
  minimise_front<F, kStarts, Model, kKept>(p, bn, bf, done, kept, &it, 0u);
  minimise_finish<F, kKept>(kept, best, n);
}

}  // namespace impact::kernels::newton
