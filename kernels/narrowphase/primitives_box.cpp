// Box (A) against box and half-space (B): manifolds of up to 4 points, vectorised
// across pairs (one lane = one pair).
//
// Inputs: LeafSoA lanes per leaf.h (boxes: p, R, half extents e0..e2; the AABB proxy
// is a box with R = I). Outputs: ManifoldSoA lanes of the Range, point slots 0..3.
// box-box (separating-axis test, then clipping; Gottschalk's OBB test, Ericson 4.4.1,
// and the reference/incident-face manifold of Box2D / Bullet / ODE dBoxBox):
//   1. SAT over 15 axes in A's frame: 3 + 3 face normals and the 9 edge cross
//      products a_i x b_j. A cross product is skipped where |a_i x b_j| < 1e-6 (the
//      axes are unit, so the threshold is relative): it is then within 1e-6 rad of
//      parallel and the face axes decide. Its components come straight from the
//      rotation B->A (no 1 - c^2 cancellation), so near-parallel edges, needles and
//      pancakes keep their precision. Overlap per axis is computed on the normalised
//      axis; separated (or exactly touching) on any axis -> count 0.
//   2. The axis of least overlap, with a tie tolerance so resting contacts do not
//      flip: a B face beats an A face, and an edge beats the best face, only when
//      shallower by more than tie = 1e-5 * overlap + 1e-6 * (sum of all extents);
//      an edge axis also by its own rounding error, ~2e-7 * (extents + |t|) / |a_i x
//      b_j| (its components lose relative precision as the edges become parallel).
//      So the depth is the true minimum to ~1e-5 relative.
//   3. Face axis: the reference face (on the box owning the axis) and the incident
//      face (the other box's face most anti-parallel to it). Their intersection in
//      the reference face's frame is found without a variable-length polygon: its
//      vertices are among 24 fixed candidates - the 4 incident corners inside the
//      reference rectangle, the 4 rectangle corners inside the incident
//      parallelogram, and the 16 crossings of incident edges with rectangle edges -
//      each computed with a validity mask (the Sutherland-Hodgman result, branch-free).
//      Candidates below the reference face are reduced to at most 4: the deepest,
//      then the farthest from it, then the two of largest area on either side of that
//      diagonal. Each point lies midway between the incident surface and the
//      reference face; pdepth is its own depth.
//   4. Edge axis: one point midway between the closest points of the two edges.
//   n points from A to B. All arithmetic relative to A's centre.
// box-halfspace: the vertices below the plane; more than 4 -> deepest + spread (the
//   same reduction).
// Preconditions: finite inputs, positive half extents, orthonormal R.
// Cost: SAT ~250 flops; the face manifold ~700 flops, run only for blocks where some
// lane has a face contact.
#include <cstdint>

#include "kernels/narrowphase/pair_kernels.h"
#include "kernels/narrowphase/primitives.h"

namespace impact::kernels {
namespace {

using namespace prim;  // NOLINT: lane helpers of this kernel family
using simd::cross;
using simd::dot;
using simd::length_sq;

inline constexpr float kTieRel = 1e-5f;       // tie tolerance, relative to the overlap
inline constexpr float kTieSize = 1e-6f;      // tie tolerance floor, relative to the boxes' size
inline constexpr float kEdgeRound = 2e-7f;    // edge axis rounding, relative to size / |a_i x b_j|
inline constexpr float kEdgeSkipSq = 1e-12f;  // |a_i x b_j|^2 below this: skip the axis

template <class F>
using L4 = Lanes<F, 4>;

/// Picks lane-wise among three values by an index lane holding 0, 1 or 2.
template <class F, class T>
IMPACT_INLINE T pick3(F idx, const T& v0, const T& v1, const T& v2) {
  return select(idx == F(0.0f), v0, select(idx == F(1.0f), v1, v2));
}

/// Reduces M candidate points (2-D coordinates x, y in a plane, depth d, valid) to at
/// most 4: the deepest, the farthest from it, then the largest-area point on each
/// side of that diagonal. tol: lengths below it count as coincident.
template <class F, int M>
IMPACT_INLINE void reduce4(const F (&x)[M], const F (&y)[M], const F (&d)[M], const typename F::Mask (&valid)[M],
                           F tol, F (&ox)[4], F (&oy)[4], F (&od)[4], typename F::Int& count) {
  using Mask = typename F::Mask;
  const F zero(0.0f);
  const F neg(-3.0e38f);
  // deepest
  F bd = neg, bx = zero, by = zero;
  Mask any = Mask(false);
  for (int i = 0; i < M; ++i) {
    const Mask t = valid[i] & (d[i] > bd);
    bd = select(t, d[i], bd);
    bx = select(t, x[i], bx);
    by = select(t, y[i], by);
    any = any | valid[i];
  }
  // farthest from it
  F fd2 = neg, fx = bx, fy = by, fdp = bd;
  for (int i = 0; i < M; ++i) {
    const F dx = x[i] - bx, dy = y[i] - by;
    const F l2 = dx * dx + dy * dy;
    const Mask t = valid[i] & (l2 > fd2);
    fd2 = select(t, l2, fd2);
    fx = select(t, x[i], fx);
    fy = select(t, y[i], fy);
    fdp = select(t, d[i], fdp);
  }
  const Mask v1 = fd2 > tol * tol;
  // largest signed area on either side of the diagonal
  const F ex = fx - bx, ey = fy - by;
  F amax = zero, amin = zero, px = bx, py = by, pd = bd, qx = bx, qy = by, qd = bd;
  for (int i = 0; i < M; ++i) {
    const F ar = ex * (y[i] - by) - ey * (x[i] - bx);
    const Mask tp = valid[i] & (ar > amax);
    amax = select(tp, ar, amax);
    px = select(tp, x[i], px);
    py = select(tp, y[i], py);
    pd = select(tp, d[i], pd);
    const Mask tn = valid[i] & (ar < amin);
    amin = select(tn, ar, amin);
    qx = select(tn, x[i], qx);
    qy = select(tn, y[i], qy);
    qd = select(tn, d[i], qd);
  }
  const F area_tol = tol * sqrt(max(fd2, zero));
  const Mask v2 = v1 & (amax > area_tol);
  const Mask v3 = v1 & (-amin > area_tol);
  ox[0] = bx, oy[0] = by, od[0] = bd;
  ox[1] = fx, oy[1] = fy, od[1] = fdp;
  ox[2] = select(v2, px, qx), oy[2] = select(v2, py, qy), od[2] = select(v2, pd, qd);
  ox[3] = qx, oy[3] = qy, od[3] = qd;
  using Int = typename F::Int;
  const Int c = Int(1) + simd::to_int(v1) + simd::to_int(v2 | v3) + simd::to_int(v2 & v3);
  count = select(any, c, Int(0));
}

// ---------------------------------------------------------------------------------------
// box - box
// ---------------------------------------------------------------------------------------

template <class F>
IMPACT_INLINE void box_box_block(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, uint32_t k) {
  using Mask = typename F::Mask;
  using Int = typename F::Int;
  const F zero(0.0f), one(1.0f), half(0.5f);
  const V3<F> pa = load_p<F>(a, k);
  const V3<F> t = load_p<F>(b, k) - pa;
  const M3<F> ra = load_r<F>(a, k), rb = load_r<F>(b, k);
  const V3<F> ea = load_e<F>(a, k), eb = load_e<F>(b, k);
  const F eA[3] = {ea.x, ea.y, ea.z}, eB[3] = {eb.x, eb.y, eb.z};

  // --- 1. SAT in A's frame ---
  F R[3][3], AR[3][3];
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      R[i][j] = dot(ra.c[i], rb.c[j]);
      AR[i][j] = abs(R[i][j]);
    }
  const V3<F> ta = ra.apply_t(t);
  const F tA[3] = {ta.x, ta.y, ta.z};
  const V3<F> tb = rb.apply_t(t);
  const F tB[3] = {tb.x, tb.y, tb.z};

  F best(3.0e38f), min_all(3.0e38f);
  F axis(0.0f);  // 0..2 A face, 3..5 B face, 6 + 3i + j edge
  for (int i = 0; i < 3; ++i) {
    const F o = eA[i] + eB[0] * AR[i][0] + eB[1] * AR[i][1] + eB[2] * AR[i][2] - abs(tA[i]);
    const Mask take = o < best;
    best = select(take, o, best);
    axis = select(take, F(static_cast<float>(i)), axis);
  }
  min_all = best;
  const F size = eA[0] + eA[1] + eA[2] + eB[0] + eB[1] + eB[2];
  const F tie_floor = F(kTieSize) * size;
  {
    const F best_a = best;
    const F lim_a = best_a - mul_add(F(kTieRel), abs(best_a), tie_floor);
    for (int j = 0; j < 3; ++j) {
      const F o = eB[j] + eA[0] * AR[0][j] + eA[1] * AR[1][j] + eA[2] * AR[2][j] - abs(tB[j]);
      min_all = min(min_all, o);
      const Mask take = (o < lim_a) & (o < best);
      best = select(take, o, best);
      axis = select(take, F(static_cast<float>(3 + j)), axis);
    }
  }
  const F best_face = best;
  const F lim_face = best_face - mul_add(F(kTieRel), abs(best_face), tie_floor);
  const F edge_round = F(kEdgeRound) * (size + abs(ta.x) + abs(ta.y) + abs(ta.z));
  F edge_len(1.0f);
  V3<F> edge_l{zero, zero, zero};  // the winning edge axis in A's frame (normalised)
  for (int i = 0; i < 3; ++i) {
    const int i1 = (i + 1) % 3, i2 = (i + 2) % 3;
    for (int j = 0; j < 3; ++j) {
      // L = e_i x R[:, j] in A's frame: L_i = 0, L_i1 = -R[i2][j], L_i2 = R[i1][j]
      F l[3];
      l[i] = zero;
      l[i1] = -R[i2][j];
      l[i2] = R[i1][j];
      const F l2 = l[i1] * l[i1] + l[i2] * l[i2];
      const Mask ok = l2 > F(kEdgeSkipSq);
      const F len = sqrt(select(ok, l2, one));
      const F ra_ = eA[i1] * abs(l[i1]) + eA[i2] * abs(l[i2]);
      F rb_ = zero;
      for (int m = 0; m < 3; ++m) rb_ += eB[m] * abs(l[0] * R[0][m] + l[1] * R[1][m] + l[2] * R[2][m]);
      const F tl = l[0] * tA[0] + l[1] * tA[1] + l[2] * tA[2];
      const F o = (ra_ + rb_ - abs(tl)) / len;
      min_all = select(ok, min(min_all, o), min_all);
      const Mask take = ok & (o < lim_face - edge_round / len) & (o < best);
      best = select(take, o, best);
      axis = select(take, F(static_cast<float>(6 + 3 * i + j)), axis);
      const F inv = one / len;
      edge_l = select(take, V3<F>{l[0] * inv, l[1] * inv, l[2] * inv}, edge_l);
      edge_len = select(take, len, edge_len);
    }
  }
  const Mask hit = min_all > zero;
  const Mask face_a = axis < F(3.0f);
  const Mask face_b = andnot(axis < F(6.0f), face_a);
  const Mask is_edge = axis >= F(6.0f);

  // Normal (world, A to B).
  V3<F> n;
  {
    const F ia = axis, ib = axis - F(3.0f);
    const V3<F> na = pick3(ia, ra.c[0], ra.c[1], ra.c[2]) * simd::sign_nonneg(pick3(ia, tA[0], tA[1], tA[2]));
    const V3<F> nb = pick3(ib, rb.c[0], rb.c[1], rb.c[2]) * simd::sign_nonneg(pick3(ib, tB[0], tB[1], tB[2]));
    const V3<F> ne = ra.apply(edge_l) * simd::sign_nonneg(dot(edge_l, ta));
    n = select(face_a, na, select(face_b, nb, ne));
  }
  L4<F> m;
  m.n = n;
  m.depth = best;
  for (int q = 0; q < 4; ++q) {
    m.point[q] = V3<F>{zero, zero, zero};
    m.pdepth[q] = zero;
  }
  m.count = Int(0);
  if (simd::none(hit)) {
    store(out, k, m, pa);
    return;
  }

  // --- 4. edge-edge: one point between the two edges' closest points ---
  if (simd::any(hit & is_edge)) {
    const F e_idx = axis - F(6.0f);
    const F ei = select(e_idx < F(3.0f), zero, select(e_idx < F(6.0f), one, F(2.0f)));
    const F ej = e_idx - F(3.0f) * ei;
    // support points: A's vertex furthest along n, B's furthest along -n
    const F sa[3] = {simd::sign_nonneg(dot(n, ra.c[0])), simd::sign_nonneg(dot(n, ra.c[1])),
                     simd::sign_nonneg(dot(n, ra.c[2]))};
    const F sb[3] = {-simd::sign_nonneg(dot(n, rb.c[0])), -simd::sign_nonneg(dot(n, rb.c[1])),
                     -simd::sign_nonneg(dot(n, rb.c[2]))};
    V3<F> va = ra.c[0] * (sa[0] * eA[0]) + ra.c[1] * (sa[1] * eA[1]) + ra.c[2] * (sa[2] * eA[2]);
    V3<F> vb = t + rb.c[0] * (sb[0] * eB[0]) + rb.c[1] * (sb[1] * eB[1]) + rb.c[2] * (sb[2] * eB[2]);
    const V3<F> da = pick3(ei, ra.c[0], ra.c[1], ra.c[2]);
    const V3<F> db = pick3(ej, rb.c[0], rb.c[1], rb.c[2]);
    const F ha = pick3(ei, eA[0], eA[1], eA[2]), hb = pick3(ej, eB[0], eB[1], eB[2]);
    // edge centres: drop the edge's own axis from the support vertex
    va = va - da * (pick3(ei, sa[0], sa[1], sa[2]) * ha);
    vb = vb - db * (pick3(ej, sb[0], sb[1], sb[2]) * hb);
    F s, u;
    closest_segment_segment(va, da, ha, vb, db, hb, s, u);
    const V3<F> xa = madd(va, s, da), xb = madd(vb, u, db);
    const Mask e = hit & is_edge;
    m.point[0] = select(e, (xa + xb) * half, m.point[0]);
    m.pdepth[0] = select(e, best, m.pdepth[0]);
    m.count = select(e, Int(1), m.count);
  }

  // --- 3. face contact: reference and incident faces, 24 clip candidates ---
  const Mask face = hit & ~is_edge;
  if (simd::any(face)) {
    // reference box: A for A's face axes, B for B's
    const F fk = select(face_a, axis, axis - F(3.0f));  // face axis index 0..2
    const V3<F> cr = select(face_a, V3<F>{zero, zero, zero}, t);
    const V3<F> rc0 = select(face_a, ra.c[0], rb.c[0]), rc1 = select(face_a, ra.c[1], rb.c[1]),
                rc2 = select(face_a, ra.c[2], rb.c[2]);
    const F rh0 = select(face_a, eA[0], eB[0]), rh1 = select(face_a, eA[1], eB[1]), rh2 = select(face_a, eA[2], eB[2]);
    const V3<F> ic = select(face_a, t, V3<F>{zero, zero, zero});
    const V3<F> ic0 = select(face_a, rb.c[0], ra.c[0]), ic1 = select(face_a, rb.c[1], ra.c[1]),
                ic2 = select(face_a, rb.c[2], ra.c[2]);
    const F ih0 = select(face_a, eB[0], eA[0]), ih1 = select(face_a, eB[1], eA[1]), ih2 = select(face_a, eB[2], eA[2]);
    // outward normal of the reference face, towards the incident box
    const V3<F> mref = select(face_a, n, -n);
    const V3<F> u1 = pick3(fk, rc1, rc2, rc0), u2 = pick3(fk, rc2, rc0, rc1);
    const F w1 = pick3(fk, rh1, rh2, rh0), w2 = pick3(fk, rh2, rh0, rh1), wk = pick3(fk, rh0, rh1, rh2);
    const V3<F> cf = madd(cr, wk, mref);  // reference face centre
    // incident face: most anti-parallel to mref
    const F d0 = dot(ic0, mref), d1 = dot(ic1, mref), d2 = dot(ic2, mref);
    const F a0 = abs(d0), a1 = abs(d1), a2 = abs(d2);
    const Mask j0 = (a0 >= a1) & (a0 >= a2);
    const Mask j1 = andnot(a1 >= a2, j0);
    const F fj = select(j0, zero, select(j1, one, F(2.0f)));
    const V3<F> inrm = pick3(fj, ic0, ic1, ic2);
    const F sgn = -simd::sign_nonneg(pick3(fj, d0, d1, d2));
    const V3<F> icen = madd(ic, sgn * pick3(fj, ih0, ih1, ih2), inrm);
    const V3<F> T1 = pick3(fj, ic1, ic2, ic0) * pick3(fj, ih1, ih2, ih0);
    const V3<F> T2 = pick3(fj, ic2, ic0, ic1) * pick3(fj, ih2, ih0, ih1);
    // incident face in the reference face's frame (x, y in the face, z along mref)
    const V3<F> dc = icen - cf;
    const F xc = dot(dc, u1), yc = dot(dc, u2), zc = dot(dc, mref);
    const F ax1 = dot(T1, u1), ay1 = dot(T1, u2), az1 = dot(T1, mref);
    const F ax2 = dot(T2, u1), ay2 = dot(T2, u2), az2 = dot(T2, mref);
    const F scale = w1 + w2;
    const F tol_in = F(1e-6f) * scale;
    const F one_in(1.0f + 1e-6f);

    constexpr int M = 24;
    F cx[M], cy[M], cz[M];
    Mask cv[M];
    int q = 0;
    // (1) incident corners inside the rectangle
    for (int s1 = -1; s1 <= 1; s1 += 2)
      for (int s2 = -1; s2 <= 1; s2 += 2) {
        const F f1(static_cast<float>(s1)), f2(static_cast<float>(s2));
        cx[q] = xc + f1 * ax1 + f2 * ax2;
        cy[q] = yc + f1 * ay1 + f2 * ay2;
        cz[q] = zc + f1 * az1 + f2 * az2;
        cv[q] = (abs(cx[q]) <= w1 + tol_in) & (abs(cy[q]) <= w2 + tol_in);
        ++q;
      }
    // (2) rectangle corners inside the incident parallelogram (alpha, beta in [-1, 1])
    const F det = ax1 * ay2 - ax2 * ay1;
    const Mask det_ok = abs(det) > F(1e-12f) * scale * scale;
    const F inv_det = one / select(det_ok, det, one);
    for (int s1 = -1; s1 <= 1; s1 += 2)
      for (int s2 = -1; s2 <= 1; s2 += 2) {
        const F X = F(static_cast<float>(s1)) * w1, Y = F(static_cast<float>(s2)) * w2;
        const F rx = X - xc, ry = Y - yc;
        const F al = (rx * ay2 - ax2 * ry) * inv_det;
        const F be = (ax1 * ry - ay1 * rx) * inv_det;
        cx[q] = X;
        cy[q] = Y;
        cz[q] = zc + al * az1 + be * az2;
        cv[q] = det_ok & (abs(al) <= one_in) & (abs(be) <= one_in);
        ++q;
      }
    // (3) incident edges crossing rectangle edges. Edge (s, param p): point =
    // centre + s*E_fixed + p*E_run, p in [-1, 1]; lines x = +-w1 and y = +-w2.
    auto crossings = [&](F fx, F fy, F fz, F rx, F ry, F rz) {
      const Mask okx = abs(rx) > F(1e-20f), oky = abs(ry) > F(1e-20f);
      const F irx = one / select(okx, rx, one), iry = one / select(oky, ry, one);
      for (int s = -1; s <= 1; s += 2) {
        const F fs(static_cast<float>(s));
        const F bx = xc + fs * fx, by = yc + fs * fy, bz = zc + fs * fz;
        for (int side = -1; side <= 1; side += 2) {
          const F sd(static_cast<float>(side));
          {  // x = side * w1
            const F p = (sd * w1 - bx) * irx;
            cx[q] = sd * w1;
            cy[q] = by + p * ry;
            cz[q] = bz + p * rz;
            cv[q] = okx & (abs(p) <= one_in) & (abs(cy[q]) <= w2 + tol_in);
            ++q;
          }
          {  // y = side * w2
            const F p = (sd * w2 - by) * iry;
            cx[q] = bx + p * rx;
            cy[q] = sd * w2;
            cz[q] = bz + p * rz;
            cv[q] = oky & (abs(p) <= one_in) & (abs(cx[q]) <= w1 + tol_in);
            ++q;
          }
        }
      }
    };
    crossings(ax1, ay1, az1, ax2, ay2, az2);  // edges at +-T1, running along T2
    crossings(ax2, ay2, az2, ax1, ay1, az1);  // edges at +-T2, running along T1
    // keep those below the reference face
    F cd[M];
    for (int i = 0; i < M; ++i) {
      cd[i] = -cz[i];
      cv[i] = cv[i] & (cd[i] > zero);
    }
    F ox[4], oy[4], od[4];
    Int cnt;
    reduce4<F, M>(cx, cy, cd, cv, F(1e-5f) * scale, ox, oy, od, cnt);
    for (int i = 0; i < 4; ++i) {
      // midway between the incident point (height -od) and the reference face (0)
      const V3<F> p = madd(madd(madd(cf, ox[i], u1), oy[i], u2), F(-0.5f) * od[i], mref);
      m.point[i] = select(face, p, m.point[i]);
      m.pdepth[i] = select(face, min(od[i], best), m.pdepth[i]);
    }
    m.count = select(face, cnt, m.count);
  }
  m.count = select(hit, m.count, Int(0));
  store(out, k, m, pa);
}

// ---------------------------------------------------------------------------------------
// box - half-space
// ---------------------------------------------------------------------------------------

template <class F>
IMPACT_INLINE void box_halfspace_block(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, uint32_t k) {
  using Mask = typename F::Mask;
  const F half(0.5f);
  const V3<F> pa = load_p<F>(a, k);
  const V3<F> q = load_p<F>(b, k) - pa;
  const M3<F> ra = load_r<F>(a, k);
  const V3<F> ea = load_e<F>(a, k);
  const V3<F> nh = load_e<F>(b, k);
  // in-plane 2-D frame for the reduction
  const V3<F> t1 = any_perpendicular(nh);
  const V3<F> t2 = cross(nh, t1);
  const V3<F> h0 = ra.c[0] * ea.x, h1 = ra.c[1] * ea.y, h2 = ra.c[2] * ea.z;
  const F hc = -dot(nh, q);
  const F g0 = dot(nh, h0), g1 = dot(nh, h1), g2 = dot(nh, h2);
  F cx[8], cy[8], cd[8];
  Mask cv[8];
  V3<F> v[8];
  for (int i = 0; i < 8; ++i) {
    const F s0((i & 1) ? 1.0f : -1.0f), s1((i & 2) ? 1.0f : -1.0f), s2((i & 4) ? 1.0f : -1.0f);
    v[i] = h0 * s0 + h1 * s1 + h2 * s2;
    cd[i] = -(hc + s0 * g0 + s1 * g1 + s2 * g2);
    cx[i] = dot(v[i], t1);
    cy[i] = dot(v[i], t2);
    cv[i] = cd[i] > F(0.0f);
  }
  F ox[4], oy[4], od[4];
  typename F::Int cnt;
  reduce4<F, 8>(cx, cy, cd, cv, F(1e-5f) * (ea.x + ea.y + ea.z), ox, oy, od, cnt);
  L4<F> m;
  m.count = cnt;
  m.n = -nh;
  m.depth = od[0];
  for (int i = 0; i < 4; ++i) {
    // the vertex is x t1 + y t2 + (nh.q - depth) nh; the point lies half its depth up
    const V3<F> p = madd(madd(t1 * ox[i], oy[i], t2), mul_add(-half, od[i], dot(nh, q)), nh);
    m.point[i] = p;
    m.pdepth[i] = od[i];
  }
  store(out, k, m, pa);
}

#define IMPACT_BOX_KERNEL(name, block)                                                              \
  void name(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, Range r,                   \
            const NarrowConfig& cfg) {                                                              \
    if (cfg.path == KernelPath::kScalar) {                                                          \
      for_each_block<simd::Float1, 4>(a, b, out, r, [](const LeafSoA& aa, const LeafSoA& bb,        \
                                                       const ManifoldSoA& o, uint32_t k) {          \
        block<simd::Float1>(aa, bb, o, k);                                                          \
      });                                                                                           \
    } else {                                                                                        \
      for_each_block<simd::FloatW, 4>(a, b, out, r, [](const LeafSoA& aa, const LeafSoA& bb,        \
                                                       const ManifoldSoA& o, uint32_t k) {          \
        block<simd::FloatW>(aa, bb, o, k);                                                          \
      });                                                                                           \
    }                                                                                               \
  }

}  // namespace

IMPACT_BOX_KERNEL(collide_box_box, box_box_block)
IMPACT_BOX_KERNEL(collide_box_halfspace, box_halfspace_block)

}  // namespace impact::kernels
