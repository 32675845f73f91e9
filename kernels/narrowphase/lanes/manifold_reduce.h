// Manifold reduction of the specialised narrow-phase kernels (kernels/narrowphase/pairs/):
// a candidate set of contact points reduced to at most 4 (reduce4, reduce4_indices: the
// deepest, the farthest from it, the largest areas on both sides), lane-wise extremes by
// a tree, and the cap / side manifold tails against a cylinder (box-cylinder,
// cylinder-cylinder, cylinder-triangle). Templates over the lane type F; the choices are
// max/min trees over index-tagged keys and per-lane picks, no select chains.
#pragma once

#include <cstdint>

#include "kernels/narrowphase/lanes/lane_io.h"
#include "kernels/simd/lanes.h"
#include "kernels/simd/vec3.h"

namespace impact::kernels::prim {

using simd::M3;
using simd::V3;

/// Picks lane-wise among three values by an index lane holding 0, 1 or 2.
template <class F, class T>
IMPACT_INLINE T pick3(F idx, const T& v0, const T& v1, const T& v2) {
  return select(idx == F(0.0f), v0, select(idx == F(1.0f), v1, v2));
}

/// One level of tree_extreme: folds the top half of t[0 .. N) onto the bottom, then the
/// rest. N is a template parameter so every level unrolls completely and t stays in
/// registers (a run-time level count left GCC a loop over a stack copy of t).
template <bool Max, int N, class F>
IMPACT_INLINE F tree_fold(F* t) {
  if constexpr (N == 1) {
    return t[0];
  } else {
    constexpr int h = N / 2;
#pragma GCC unroll 16
    for (int i = 0; i < h; ++i) t[i] = Max ? max(t[i], t[N - 1 - i]) : min(t[i], t[N - 1 - i]);
    return tree_fold<Max, N - h>(t);
  }
}

/// Lane-wise maximum (Max = true) or minimum of M values, as a tree (depth log2 M, no
/// serial dependency). min/max of non-NaN floats is exact, so the order is free.
template <bool Max, class F, int M>
IMPACT_INLINE F tree_extreme(const F (&v)[M]) {
  F t[M];
#pragma GCC unroll 32
  for (int i = 0; i < M; ++i) t[i] = v[i];
  return tree_fold<Max, M>(t);
}

/// Reduces M <= 32 candidate points (2-D coordinates x, y in a plane, depth d, valid)
/// to at most 4: the deepest, the farthest from it, then the largest-area point on
/// each side of that diagonal. tol: lengths below it count as coincident.
/// Each choice is one max/min tree over keys that carry their candidate's index in
/// their low bits (simd::tag), then a per-lane pick of the winner (gather_lanes): no
/// select chain through the candidates. Keys equal to ~4e-6 relative may resolve
/// either way (deterministically). idx receives the chosen candidates' indices (slots
/// count .. 3 repeat chosen ones), for kernels that carry more than (x, y, d) per point,
/// and ox, oy their coordinates.
template <class F, int M>
IMPACT_INLINE void reduce4_indices(const F (&x)[M], const F (&y)[M], const F (&d)[M],
                                   const typename F::Mask (&valid)[M], F tol, typename F::Int (&idx)[4],
                                   typename F::Int& count, F (&ox)[4], F (&oy)[4]) {
  static_assert(M <= 32, "tag() holds indices below 32");
  using Mask = typename F::Mask;
  using Int = typename F::Int;
  const F zero(0.0f);
  const F neg(-3.0e38f), pos(3.0e38f);
  F key[M], key2[M];
  // deepest
  Mask any = valid[0];
  for (int i = 1; i < M; ++i) any = any | valid[i];
  for (int i = 0; i < M; ++i) key[i] = simd::tag(select(valid[i], d[i], neg), i);
  const Int ib = simd::tag_index(tree_extreme<true>(key));
  const F bx = simd::gather_lanes(x, ib), by = simd::gather_lanes(y, ib);
  // farthest from it
  for (int i = 0; i < M; ++i) {
    const F dx = x[i] - bx, dy = y[i] - by;
    key[i] = simd::tag(select(valid[i], dx * dx + dy * dy, neg), i);
  }
  const Int jf = simd::tag_index(tree_extreme<true>(key));
  const F fx = simd::gather_lanes(x, jf), fy = simd::gather_lanes(y, jf);
  const F fd2 = (fx - bx) * (fx - bx) + (fy - by) * (fy - by);
  const Mask v1 = fd2 > tol * tol;
  // largest signed area on either side of the diagonal
  const F ex = fx - bx, ey = fy - by;
  for (int i = 0; i < M; ++i) {
    const F ar = ex * (y[i] - by) - ey * (x[i] - bx);
    key[i] = simd::tag(select(valid[i], ar, neg), i);
    key2[i] = simd::tag(select(valid[i], ar, pos), i);
  }
  const Int jp = simd::tag_index(tree_extreme<true>(key)), jq = simd::tag_index(tree_extreme<false>(key2));
  const F px = simd::gather_lanes(x, jp), py = simd::gather_lanes(y, jp);
  const F qx = simd::gather_lanes(x, jq), qy = simd::gather_lanes(y, jq);
  const F amax = ex * (py - by) - ey * (px - bx), amin = ex * (qy - by) - ey * (qx - bx);
  const F area_tol = tol * sqrt(max(fd2, zero));
  const Mask v2 = v1 & (amax > area_tol);
  const Mask v3 = v1 & (-amin > area_tol);
  idx[0] = ib;
  idx[1] = jf;
  idx[2] = select(v2, jp, jq);
  idx[3] = jq;
  ox[0] = bx, oy[0] = by;
  ox[1] = fx, oy[1] = fy;
  ox[2] = select(v2, px, qx), oy[2] = select(v2, py, qy);
  ox[3] = qx, oy[3] = qy;
  const Int c = Int(1) + simd::to_int(v1) + simd::to_int(v2 | v3) + simd::to_int(v2 & v3);
  count = select(any, c, Int(0));
}

/// reduce4_indices, returning the chosen candidates' values: the outputs are the
/// candidates' exact values.
template <class F, int M>
IMPACT_INLINE void reduce4(const F (&x)[M], const F (&y)[M], const F (&d)[M],
                           const typename F::Mask (&valid)[M], F tol, F (&ox)[4], F (&oy)[4], F (&od)[4],
                           typename F::Int& count) {
  typename F::Int idx[4];
  reduce4_indices<F, M>(x, y, d, valid, tol, idx, count, ox, oy);
  for (int i = 0; i < 4; ++i) od[i] = simd::gather_lanes(d, idx[i]);
}

/// Candidate 0 of a clipped manifold is the winning candidate's witness (as deep as the
/// contact, on both surfaces, so never none). It stays only where no other candidate is
/// that deep (within tol): else it lies among them (the middle of a segment contact) and
/// would keep reduce4 from picking the contact's ends.
template <class F, int M>
IMPACT_INLINE void drop_shadowed_witness(const F (&d)[M], typename F::Mask (&valid)[M], F o, F tol) {
  F deepest(-3.0e38f);
  for (int i = 1; i < M; ++i) deepest = max(deepest, select(valid[i], d[i], F(-3.0e38f)));
  valid[0] = valid[0] & (deepest < o - tol);
}

/// The tail of a side-contact manifold against a cylinder (box-cylinder,
/// cylinder-triangle): M candidate points ca (0: the witness) with their gaps d and
/// validity, in the cylinder's frame, where (mx, my) is the side's horizontal unit
/// normal along n: candidates without a positive gap and a shadowed witness dropped,
/// reduced to 4 in the side's own 2-D coordinates (across (mx, my), and z), and the
/// chosen ones written to m where `use` (count, points, pdepth = min(gap, o)). kHalfBack:
/// each chosen point is moved by -gap/2 along n (candidates on the far surface).
template <class F, int M, bool kHalfBack>
IMPACT_INLINE void side_manifold_tail(const V3<F> (&ca)[M], F (&d)[M], typename F::Mask (&valid)[M], F o,
                                      F tol, F mx, F my, const V3<F>& n, typename F::Mask use,
                                      Lanes<F, 4>& m) {
  using Int = typename F::Int;
  F c2x[M], c2y[M], ax[M], ay[M], az[M];
  for (int i = 0; i < M; ++i) {
    valid[i] = valid[i] & (d[i] > F(0.0f));
    c2x[i] = ca[i].y * mx - ca[i].x * my, c2y[i] = ca[i].z;
    ax[i] = ca[i].x, ay[i] = ca[i].y, az[i] = ca[i].z;
  }
  drop_shadowed_witness<F, M>(d, valid, o, tol);
  Int idx[4], cnt;
  F ox[4], oy[4];
  reduce4_indices<F, M>(c2x, c2y, d, valid, tol, idx, cnt, ox, oy);
  const typename F::Mask on = use & (cnt > Int(0));
  m.count = select(on, cnt, m.count);
  for (int i = 0; i < 4; ++i) {
    V3<F> q{simd::gather_lanes(ax, idx[i]), simd::gather_lanes(ay, idx[i]), simd::gather_lanes(az, idx[i])};
    const F dq = simd::gather_lanes(d, idx[i]);
    if constexpr (kHalfBack) q = madd(q, F(-0.5f) * dq, n);
    m.point[i] = select(on, q, m.point[i]);
    m.pdepth[i] = select(on, min(dq, o), m.pdepth[i]);
  }
}

/// Rim samples of the cap manifolds against a cylinder (box-cylinder, cylinder-cylinder):
/// cos of multiples of 45 degrees (the sin of sample i is kRimCos[(i + 6) % 8]).
inline constexpr int kRimSamples = 8;
inline constexpr float kRimCos[kRimSamples] = {1.0f,  0.70710678f,  0.0f, -0.70710678f,
                                               -1.0f, -0.70710678f, 0.0f, 0.70710678f};

/// The tail of a cap-contact manifold against a cylinder (box-cylinder, cylinder-cylinder):
/// M candidate points (x, y) on the cap plane z = zc (0: the witness) with their gaps d
/// along n and validity: candidates without a positive gap and a shadowed witness dropped,
/// reduced to 4 in the plane, and the chosen ones written to m where `use` (count, the
/// points moved by half their gap along n, pdepth = min(gap, o)).
template <class F, int M>
IMPACT_INLINE void cap_manifold_tail(const F (&x)[M], const F (&y)[M], F (&d)[M],
                                     typename F::Mask (&valid)[M], F o, F tol, F zc, const V3<F>& n,
                                     typename F::Mask use, Lanes<F, 4>& m) {
  using Int = typename F::Int;
  for (int i = 0; i < M; ++i) valid[i] = valid[i] & (d[i] > F(0.0f));
  drop_shadowed_witness<F, M>(d, valid, o, tol);
  F ox[4], oy[4], od[4];
  Int cnt;
  reduce4<F, M>(x, y, d, valid, tol, ox, oy, od, cnt);
  const typename F::Mask on = use & (cnt > Int(0));
  m.count = select(on, cnt, m.count);
  for (int i = 0; i < 4; ++i) {
    const V3<F> p = madd(V3<F>{ox[i], oy[i], zc}, F(0.5f) * od[i], n);
    m.point[i] = select(on, p, m.point[i]);
    m.pdepth[i] = select(on, min(od[i], o), m.pdepth[i]);
  }
}

}  // namespace impact::kernels::prim
