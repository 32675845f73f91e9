// Box (A) against triangle (B): a manifold of up to 4 points, vectorised across pairs
// (one lane = one pair).
//
// Inputs: LeafSoA lanes per leaf.h (A: box p, R, half extents e0..e2; B: triangle
// p = v0, w0..w2 = v1, w3..w5 = v2; zero thickness, both sides solid). Outputs:
// ManifoldSoA lanes of the Range, point slots 0..3; n points from the box to the
// triangle. Everything is computed in the box's frame (triangle vertices taken
// relative to the box centre and rotated by R^T), where the box is the AABB [-e, e].
//   1. SAT over 13 axes (Ericson 4.4 / 5.2.9 and Akenine-Moeller's triangle-box test):
//      the 3 box face normals, the triangle normal, and the 9 crosses e_i x f_j of box
//      axes with triangle edges. The triangle's interval along an axis is its
//      vertices' min..max (a flat triangle is a degenerate polytope: its Gauss map is
//      +-normal plus 3 edge arcs, so these 13 axes hold the minimum translation). A
//      cross is skipped where |e_i x f_j| < 1e-6 |f_j| (within 1e-6 rad of parallel:
//      the face axes decide). Separated or exactly touching on any axis -> count 0.
//   2. Least overlap with the box-box tie rule: the triangle normal beats the best box
//      face, and an edge beats the best face, only when shallower by more than
//      tie = 1e-5 * overlap + 1e-6 * size; an edge also by its own rounding,
//      ~2e-7 * (size + |v0|) * |f_j| / |e_i x f_j|.
//   3. Face axis (box face or triangle normal): the box face most aligned with n (the
//      reference face itself for a box axis) and the triangle, both projected along n
//      onto that face's plane. The intersection polygon's vertices are among 19 fixed
//      candidates, each with a validity mask (branch-free Sutherland-Hodgman): the 3
//      triangle vertices inside the face rectangle, the 4 rectangle corners inside the
//      projected triangle (heights by barycentric interpolation; skipped where the
//      triangle is within ~0.6 deg of edge-on to n), and the 12 crossings of triangle
//      edges with rectangle edges. The gap along n between the box face and the
//      triangle at a candidate is its depth; candidates with depth > 0 are reduced to
//      4 (reduce4). Each point lies midway between the box face and the triangle.
//   4. Edge axis: one point midway between the closest points of the box's support
//      edge and the triangle's support edge (or vertex).
// Preconditions: finite inputs, positive half extents, orthonormal R. Degenerate
// triangles give finite output (triangle_normal's fallback). Cost: ~350 flops SAT,
// ~500 flops face manifold (run only for blocks where some lane has a face contact).
#include <cstdint>

#include "kernels/narrowphase/pair_kernels.h"
#include "kernels/narrowphase/lanes/block_driver.h"
#include "kernels/narrowphase/lanes/lane_geometry.h"
#include "kernels/narrowphase/lanes/lane_io.h"
#include "kernels/narrowphase/lanes/manifold_reduce.h"

namespace impact::kernels {
namespace {

using namespace prim;  // NOLINT: lane helpers of this kernel family
using simd::cross;
using simd::dot;
using simd::length_sq;

inline constexpr float kTieRel = 1e-5f;       // tie tolerance, relative to the overlap
inline constexpr float kTieSize = 1e-6f;      // tie tolerance floor, relative to the shapes' size
inline constexpr float kEdgeRound = 2e-7f;    // edge axis rounding, relative to size * |f| / |e_i x f|
inline constexpr float kEdgeSkipSq = 1e-12f;  // |e_i x f|^2 / |f|^2 below this: skip the axis
/// Rectangle corners inside the projected triangle need its barycentric coordinates;
/// below this |twice area|, relative to the squared edge lengths, they are not used.
inline constexpr float kFlatTri = 1e-2f;

template <class F>
IMPACT_INLINE const F& comp(const V3<F>& v, int i) {
  return i == 0 ? v.x : (i == 1 ? v.y : v.z);
}

template <class F>
IMPACT_INLINE void box_triangle_block(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, uint32_t k) {
  using Mask = typename F::Mask;
  using Int = typename F::Int;
  const F zero(0.0f), one(1.0f), half(0.5f);
  const V3<F> pa = load_p<F>(a, k);
  const M3<F> ra = load_r<F>(a, k);
  const V3<F> ev = load_e<F>(a, k);
  const F e[3] = {ev.x, ev.y, ev.z};
  // triangle in the box's frame
  const V3<F> v[3] = {ra.apply_t(load_p<F>(b, k) - pa), ra.apply_t(load_w<F>(b, k, 0) - pa),
                      ra.apply_t(load_w<F>(b, k, 3) - pa)};
  const V3<F> f[3] = {v[1] - v[0], v[2] - v[1], v[0] - v[2]};  // edge j: v[j] -> v[j+1]
  const F lf[3] = {length_sq(f[0]), length_sq(f[1]), length_sq(f[2])};
  const F flen[3] = {sqrt(lf[0]), sqrt(lf[1]), sqrt(lf[2])};
  const V3<F> nf = triangle_normal(v[0], v[1], v[2]);
  const F size = e[0] + e[1] + e[2] + max(flen[0], max(flen[1], flen[2]));
  const F tie_floor = F(kTieSize) * size;

  // --- 1. SAT ---
  F best(3.0e38f);
  F axis(0.0f);  // 0..2 box face, 3 triangle normal, 4 + 3i + j edge e_i x f_j
  Mask pos = Mask(true);  // n = +axis (the triangle is pushed along +axis)
  for (int i = 0; i < 3; ++i) {
    const F t0 = comp(v[0], i), t1 = comp(v[1], i), t2 = comp(v[2], i);
    const F op = e[i] - min(t0, min(t1, t2)), on = max(t0, max(t1, t2)) + e[i];
    const F o = min(op, on);
    const Mask take = o < best;
    best = select(take, o, best);
    axis = select(take, F(static_cast<float>(i)), axis);
    pos = select(take, op <= on, pos);
  }
  F min_all = best;
  {
    const F lim = best - mul_add(F(kTieRel), abs(best), tie_floor);
    const F t0 = dot(nf, v[0]), t1 = dot(nf, v[1]), t2 = dot(nf, v[2]);
    const F r = e[0] * abs(nf.x) + e[1] * abs(nf.y) + e[2] * abs(nf.z);
    const F op = r - min(t0, min(t1, t2)), on = max(t0, max(t1, t2)) + r;
    const F o = min(op, on);
    min_all = min(min_all, o);
    const Mask take = (o < lim) & (o < best);
    best = select(take, o, best);
    axis = select(take, F(3.0f), axis);
    pos = select(take, op <= on, pos);
  }
  const F lim_face = best - mul_add(F(kTieRel), abs(best), tie_floor);
  const F edge_round = F(kEdgeRound) * (size + abs(v[0].x) + abs(v[0].y) + abs(v[0].z));
  V3<F> edge_l{zero, zero, zero};  // the winning edge axis (unit)
  Mask vert_win = Mask(false);     // its triangle feature is the vertex opposite edge j
  for (int i = 0; i < 3; ++i) {
    const int i1 = (i + 1) % 3, i2 = (i + 2) % 3;
    for (int j = 0; j < 3; ++j) {
      // l = e_i x f_j: l_i = 0, l_i1 = -f_i2, l_i2 = f_i1
      const F l1 = -comp(f[j], i2), l2 = comp(f[j], i1);
      const F ll = l1 * l1 + l2 * l2;
      const Mask ok = ll > F(kEdgeSkipSq) * lf[j];
      const F inv = one / sqrt(select(ok, ll, one));
      const F r = e[i1] * abs(l1) + e[i2] * abs(l2);
      const int ja = j, jc = (j + 2) % 3;  // edge j's first vertex, the opposite vertex
      const F ta = l1 * comp(v[ja], i1) + l2 * comp(v[ja], i2);
      const F tb = l1 * comp(v[(j + 1) % 3], i1) + l2 * comp(v[(j + 1) % 3], i2);
      const F tc = l1 * comp(v[jc], i1) + l2 * comp(v[jc], i2);
      const F emin = min(ta, tb), emax = max(ta, tb);
      const F op = r - min(emin, tc), on = max(emax, tc) + r;
      const F o = min(op, on) * inv;
      min_all = select(ok, min(min_all, o), min_all);
      const Mask take = ok & (o < lim_face - edge_round * flen[j] * inv) & (o < best);
      best = select(take, o, best);
      axis = select(take, F(static_cast<float>(4 + 3 * i + j)), axis);
      const Mask p = op <= on;
      pos = select(take, p, pos);
      vert_win = select(take, select(p, tc < emin, tc > emax), vert_win);
      V3<F> l;
      if (i == 0) l = V3<F>{zero, l1 * inv, l2 * inv};
      if (i == 1) l = V3<F>{l2 * inv, zero, l1 * inv};
      if (i == 2) l = V3<F>{l1 * inv, l2 * inv, zero};
      edge_l = select(take, l, edge_l);
    }
  }
  const Mask hit = min_all > zero;
  if (simd::none(hit)) {
    store_no_contact<F>(out, k);
    return;
  }
  const Mask face_box = axis < F(3.0f);
  const Mask is_edge = axis >= F(4.0f);
  const Mask face_tri = andnot(~is_edge, face_box);

  // Normal (box frame), A to B.
  V3<F> nl;
  {
    const V3<F> nb = pick3(axis, V3<F>{one, zero, zero}, V3<F>{zero, one, zero}, V3<F>{zero, zero, one});
    nl = select(face_box, nb, select(face_tri, nf, edge_l));
    nl = select(pos, nl, -nl);
  }
  Lanes<F, 4> m;
  m.n = ra.apply(nl);
  m.depth = best;
  for (int q = 0; q < 4; ++q) {
    m.point[q] = V3<F>{zero, zero, zero};
    m.pdepth[q] = zero;
  }
  m.count = Int(0);
  // the box's support vertex along n (deepest box point)
  const V3<F> sv{simd::sign_nonneg(nl.x) * e[0], simd::sign_nonneg(nl.y) * e[1], simd::sign_nonneg(nl.z) * e[2]};
  V3<F> pl[4];  // points in the box frame
  for (int q = 0; q < 4; ++q) pl[q] = V3<F>{zero, zero, zero};

  // --- 4. edge axis: one point between the box edge and the triangle edge / vertex ---
  const Mask edge = hit & is_edge;
  if (simd::any(edge)) {
    const F e_idx = axis - F(4.0f);
    const F ei = select(e_idx < F(3.0f), zero, select(e_idx < F(6.0f), one, F(2.0f)));
    const F ej = e_idx - F(3.0f) * ei;
    const V3<F> da = pick3(ei, V3<F>{one, zero, zero}, V3<F>{zero, one, zero}, V3<F>{zero, zero, one});
    const F ha = pick3(ei, e[0], e[1], e[2]);
    const V3<F> ca = sv - da * dot(da, sv);  // the support edge's centre
    F fl;
    const V3<F> fj = pick3(ej, f[0], f[1], f[2]);
    const V3<F> db = normalize_or(fj, V3<F>{one, zero, zero}, fl);
    const V3<F> mid = pick3(ej, v[0], v[1], v[2]) + fj * half;
    const V3<F> opp = pick3(ej, v[2], v[0], v[1]);
    const V3<F> cb = select(vert_win, opp, mid);
    const F hb = select(vert_win, zero, half * fl);
    F s, u;
    closest_segment_segment(ca, da, ha, cb, db, hb, s, u);
    const V3<F> p = (madd(ca, s, da) + madd(cb, u, db)) * half;
    pl[0] = select(edge, p, pl[0]);
    m.pdepth[0] = select(edge, best, m.pdepth[0]);
    m.count = select(edge, Int(1), m.count);
  }

  // --- 3. face axis: box face and triangle projected along n, 19 candidates ---
  const Mask face = hit & ~is_edge;
  if (simd::any(face)) {
    // the box face most aligned with n: index j, on the side s of its axis
    const F ax = abs(nl.x), ay = abs(nl.y), az = abs(nl.z);
    const Mask j0 = (ax >= ay) & (ax >= az);
    const Mask j1 = andnot(ay >= az, j0);
    // coordinates permuted to (j+1, j+2, j): the face is z = zf, |x| <= w1, |y| <= w2
    auto perm = [&](const V3<F>& p) -> V3<F> {
      return {select(j0, p.y, select(j1, p.z, p.x)), select(j0, p.z, select(j1, p.x, p.y)),
              select(j0, p.x, select(j1, p.y, p.z))};
    };
    const V3<F> np = perm(nl);
    const V3<F> wp = perm(ev);
    const F w1 = wp.x, w2 = wp.y;
    const F zf = simd::sign_nonneg(np.z) * wp.z;
    const F inz = one / np.z;  // |np.z| >= 1/sqrt(3)
    // triangle vertex p projected along n onto the face: p + t n, t = its depth
    F x[3], y[3], t[3];
    for (int q = 0; q < 3; ++q) {
      const V3<F> p = perm(v[q]);
      t[q] = (zf - p.z) * inz;
      x[q] = mul_add(t[q], np.x, p.x);
      y[q] = mul_add(t[q], np.y, p.y);
    }
    const F scale = w1 + w2;
    const F tol_in = F(1e-6f) * scale;
    const F lo_s(-1e-6f), hi_s(1.0f + 1e-6f);
    constexpr int M = 19;
    F cx[M], cy[M], cd[M];
    Mask cv[M];
    int c = 0;
    // (1) triangle vertices inside the rectangle
    for (int q = 0; q < 3; ++q) {
      cx[c] = x[q];
      cy[c] = y[q];
      cd[c] = t[q];
      cv[c] = (abs(x[q]) <= w1 + tol_in) & (abs(y[q]) <= w2 + tol_in);
      ++c;
    }
    // (2) rectangle corners inside the projected triangle
    const F dx1 = x[1] - x[0], dy1 = y[1] - y[0], dx2 = x[2] - x[0], dy2 = y[2] - y[0];
    const F det = dx1 * dy2 - dx2 * dy1;  // twice the signed area
    const Mask det_ok = abs(det) > F(kFlatTri) * (dx1 * dx1 + dy1 * dy1 + dx2 * dx2 + dy2 * dy2);
    const F inv_det = one / select(det_ok, det, one);
    for (int s1 = -1; s1 <= 1; s1 += 2)
      for (int s2 = -1; s2 <= 1; s2 += 2) {
        const F X = F(static_cast<float>(s1)) * w1, Y = F(static_cast<float>(s2)) * w2;
        // barycentric weights of vertices 1 and 2 (edge functions / det)
        const F rx = X - x[0], ry = Y - y[0];
        const F l1 = (rx * dy2 - dx2 * ry) * inv_det;
        const F l2 = (dx1 * ry - dy1 * rx) * inv_det;
        const F l0 = one - l1 - l2;
        cx[c] = X;
        cy[c] = Y;
        cd[c] = t[0] * l0 + t[1] * l1 + t[2] * l2;
        cv[c] = det_ok & (l0 >= lo_s) & (l1 >= lo_s) & (l2 >= lo_s);
        ++c;
      }
    // (3) triangle edges crossing the rectangle's edges x = +-w1, y = +-w2
    for (int q = 0; q < 3; ++q) {
      const int q1 = (q + 1) % 3;
      const F ex = x[q1] - x[q], ey = y[q1] - y[q], et = t[q1] - t[q];
      const Mask okx = abs(ex) > F(1e-30f), oky = abs(ey) > F(1e-30f);
      const F iex = one / select(okx, ex, one), iey = one / select(oky, ey, one);
      for (int side = -1; side <= 1; side += 2) {
        const F sd(static_cast<float>(side));
        {
          const F X = sd * w1;
          const F s = (X - x[q]) * iex;
          cx[c] = X;
          cy[c] = mul_add(s, ey, y[q]);
          cd[c] = mul_add(s, et, t[q]);
          cv[c] = okx & (s >= lo_s) & (s <= hi_s) & (abs(cy[c]) <= w2 + tol_in);
          ++c;
        }
        {
          const F Y = sd * w2;
          const F s = (Y - y[q]) * iey;
          cx[c] = mul_add(s, ex, x[q]);
          cy[c] = Y;
          cd[c] = mul_add(s, et, t[q]);
          cv[c] = oky & (s >= lo_s) & (s <= hi_s) & (abs(cx[c]) <= w1 + tol_in);
          ++c;
        }
      }
    }
    for (int i = 0; i < M; ++i) cv[i] = cv[i] & (cd[i] > zero);
    F ox[4], oy[4], od[4];
    Int cnt;
    reduce4<F, M>(cx, cy, cd, cv, F(1e-5f) * scale, ox, oy, od, cnt);
    // back to the box frame: (x, y, zf) permuted (j+1, j+2, j) -> (0, 1, 2)
    auto unperm = [&](F X, F Y, F Z) -> V3<F> {
      return {select(j0, Z, select(j1, Y, X)), select(j0, X, select(j1, Z, Y)), select(j0, Y, select(j1, X, Z))};
    };
    for (int i = 0; i < 4; ++i) {
      // the box face point minus half the gap along n
      const V3<F> p = madd(unperm(ox[i], oy[i], zf), F(-0.5f) * od[i], nl);
      pl[i] = select(face, p, pl[i]);
      m.pdepth[i] = select(face, min(od[i], best), m.pdepth[i]);
    }
    // no candidate survived rounding (grazing contact): the box's deepest vertex
    const Mask none_left = face & (cnt == Int(0));
    pl[0] = select(none_left, madd(sv, F(-0.5f) * best, nl), pl[0]);
    m.pdepth[0] = select(none_left, best, m.pdepth[0]);
    m.count = select(face, select(none_left, Int(1), cnt), m.count);
  }
  m.count = select(hit, m.count, Int(0));
  for (int q = 0; q < 4; ++q) m.point[q] = ra.apply(pl[q]);
  store(out, k, m, pa);
}

}  // namespace

void collide_box_triangle(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, Range r,
                          const NarrowConfig& cfg) {
  IMPACT_LANE_KERNEL_BODY(box_triangle_block, 4);
}

}  // namespace impact::kernels
