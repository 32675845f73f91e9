// Triangle (A) against triangle (B): a manifold of up to 4 points, vectorised across
// pairs (one lane = one pair).
//
// Inputs: LeafSoA lanes per leaf.h (both triangles p = v0, w0..w2 = v1, w3..w5 = v2;
// zero thickness, both sides solid). Outputs: ManifoldSoA lanes of the Range, point
// slots 0..3; n points from A to B. Everything is computed relative to A's v0 (poses
// far from the origin keep the precision of the inputs' differences).
//   1. SAT over 11 axes (Ericson 4.4 / 5.2.9; Moeller's triangle-triangle test): the
//      two triangle normals and the 9 crosses L = fa_i x fb_j of their edges. A flat
//      triangle's interval along an axis is its vertices' min..max, and the faces of
//      the Minkowski difference A - B are among these axes, so they hold the minimum
//      translation. Along an edge axis each triangle's interval is {its edge, its
//      opposite vertex}; the vertex's offset from the edge is a triple product that
//      does not depend on the edge (-fb_j.NA for A, fa_i.NB for B, NA / NB the
//      unnormalised normals), so an edge axis costs one cross and two dots: the offset
//      d of B's edge from A's along L is taken from their vertices' difference with its
//      part along fa_i removed (L's own rounding, ~eps |fa| |fb| in any direction, would
//      otherwise bring eps |r| / sin(angle) into d for near-parallel edges). A cross is
//      skipped where |L| < 1e-6 |fa_i| |fb_j| (within 1e-6 rad of parallel: the other
//      axes decide). Separated or exactly touching on any axis -> count 0.
//   2. Least overlap with the box-triangle tie rule: B's normal beats A's, and an edge
//      beats the best face, only when shallower by more than
//      tie = 1e-5 * overlap + 1e-6 * size (size: the longest edge of A plus B's); an
//      edge also by its own rounding, 2e-7 (size + |d| / (|L| sin(angle))). A winning
//      edge axis of edges within 0.05 rad of parallel (rare) is redone per lane in double
//      from the world floats: its float direction is off by ~eps / sin(angle), enough
//      for B moved along it by the depth to stay overlapping.
//   3. Face axis (n = +-A's or +-B's normal): both triangles projected along n onto a
//      plane (frame t1 = any_perpendicular(n), t2 = n x t1; heights h = n.x). At a
//      projected point where both exist the local penetration is hA - hB (A reaches
//      up to hA along n, B starts at hB). The overlap polygon's vertices are among 15
//      fixed candidates, each with a validity mask (branch-free, as box-triangle): A's
//      vertices inside B's projection and B's inside A's (the other's height by
//      barycentric interpolation; skipped where that triangle is within ~0.6 deg of
//      edge-on to n), and the 9 crossings of A's edges with B's. Candidates with
//      penetration > 0 are reduced to 4 (reduce4), pdepth = the penetration (<= depth);
//      each point lies midway between the two triangles. None left (grazing, rounding):
//      the incident triangle's deepest vertex.
//   4. Edge axis: one point midway between the closest points of A's support feature
//      and B's (each the edge of the axis or, when it reaches further than 1e-6 size
//      beyond it, the opposite vertex; a degenerate triangle's longest edge), pdepth =
//      depth. Two edges: the closest points of their lines by triple products with the
//      axis, conditioned as 1 / sin(angle) (near-parallel edges keep their points on both
//      edges within rounding), clamped to the edges.
// Coplanar triangles: A - B is flat, its least overlap (along +-the common normal) is
// 0: they touch, count 0, as GJK/EPA (gjk_epa.cpp) and the reference
// (tests/support/narrow_reference.h) have it. Float inputs are rarely exactly coplanar,
// and within rounding the overlap's sign (and the normal's) is noise; so a pair whose
// triangles both lie within 1e-6 size of one triangle's plane (their width along A's or
// B's normal) counts as coplanar: count 0 in either order, whatever the rounding. That
// drops contacts only of depth <= 1e-6 size. Tilted further (crossing at an angle above
// ~1e-6 rad), n is +-A's (or B's) normal, depth the SAT overlap and the points the part
// of the two triangles' overlap polygon in that plane where they interpenetrate, as for
// any face contact. Swapping A and B flips n and keeps the depth (the tie rule may pick
// the other, equally deep face). Two degenerate triangles (zero area within 1e-6 of the
// longest edge squared): their difference is flat too, count 0.
// Preconditions: finite inputs. A degenerate triangle against a proper one keeps a
// complete axis set (its segment's crosses with the other's edges; triangle_normal's
// fallback normal is a valid, if useless, extra axis; zero edges skip their crosses).
// Known limit: a sliver (height ~1e-6..1e-4 of its longest edge) has three nearly
// parallel edges whose axes tie within rounding; the one taken may name the wrong part
// of the sliver (an opposite vertex or the shorter edge) as its support, and the edge
// contact point then lies up to ~1e-4 L off the other triangle (measured: 1 lane in ~800
// sliver hits). Depth and normal are not affected; below 1e-6 the longest edge is used.
// Cost: ~450 flops SAT, ~550 flops face manifold, ~150 edge point (each run only for
// blocks where some lane needs it); measured per pair in docs/results.md ("Narrow phase").
#include <algorithm>
#include <cmath>
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
inline constexpr float kTieSize = 1e-6f;      // tie tolerance floor, relative to the size
inline constexpr float kEdgeRound = 2e-7f;    // edge axis rounding, relative to its length scale
inline constexpr float kEdgeSkipSq = 1e-12f;  // |L|^2 / (|fa|^2 |fb|^2) below this: skip the axis
/// Points inside a projected triangle need its barycentric coordinates; below this
/// |twice area|, relative to the squared edge lengths, they are not used.
inline constexpr float kFlatTri = 1e-2f;
/// Edge crossings of nearly parallel projected edges (|sin| below 1e-6) are skipped:
/// the overlap's ends are then vertex candidates.
inline constexpr float kParallelSq = 1e-12f;
/// Winning edge axes of edges within asin(kFixSin) of parallel are redone in double.
inline constexpr float kFixSin = 0.05f;
/// The rounding band of lengths along an axis, relative to the size: a pair whose
/// triangles both lie within it of one triangle's plane is coplanar (touching, count 0),
/// a triangle whose height over its longest edge is below it degenerate, and an edge
/// axis's opposite vertex must reach beyond its edge by more than it to be the support.
inline constexpr float kBand = 1e-6f;

/// A projected triangle: 2-D vertices, heights along n, and its barycentric setup.
template <class F>
struct Proj {
  F x[3], y[3], h[3];
  F dx1, dy1, dx2, dy2, inv_det;
  typename F::Mask ok;  // not within ~0.6 deg of edge-on

  IMPACT_INLINE void setup() {
    dx1 = x[1] - x[0], dy1 = y[1] - y[0], dx2 = x[2] - x[0], dy2 = y[2] - y[0];
    const F det = dx1 * dy2 - dx2 * dy1;  // twice the signed area
    ok = abs(det) > F(kFlatTri) * (dx1 * dx1 + dy1 * dy1 + dx2 * dx2 + dy2 * dy2);
    inv_det = F(1.0f) / select(ok, det, F(1.0f));
  }
  /// Whether (px, py) lies inside (within lo of the barycentric range), and the height there.
  IMPACT_INLINE typename F::Mask inside(F px, F py, F lo, F& height) const {
    const F rx = px - x[0], ry = py - y[0];
    const F l1 = (rx * dy2 - dx2 * ry) * inv_det;
    const F l2 = (dx1 * ry - dy1 * rx) * inv_det;
    const F l0 = F(1.0f) - l1 - l2;
    height = h[0] * l0 + h[1] * l1 + h[2] * l2;
    return ok & (l0 >= lo) & (l1 >= lo) & (l2 >= lo);
  }
};

/// The edge axis fa_i x fb_j of lane k, from the world floats in double (their
/// differences are exact there): the unit axis l, and the SAT overlap of the pair along
/// it (depth) with its side (pos: B is pushed along +l). For near-parallel edges, whose
/// float cross product points within ~eps / sin(angle) of the true axis.
void edge_axis_double(const LeafSoA& a, const LeafSoA& b, uint32_t k, int i, int j, float* l, float* depth,
                      float* pos) {
  double va[3][3], vb[3][3];
  for (int c = 0; c < 3; ++c) {
    const double o = a.p[c][k];
    va[0][c] = 0.0, va[1][c] = a.w[c][k] - o, va[2][c] = a.w[3 + c][k] - o;
    vb[0][c] = b.p[c][k] - o, vb[1][c] = b.w[c][k] - o, vb[2][c] = b.w[3 + c][k] - o;
  }
  double fa[3], fb[3];
  for (int c = 0; c < 3; ++c) fa[c] = va[(i + 1) % 3][c] - va[i][c], fb[c] = vb[(j + 1) % 3][c] - vb[j][c];
  double n[3] = {fa[1] * fb[2] - fa[2] * fb[1], fa[2] * fb[0] - fa[0] * fb[2], fa[0] * fb[1] - fa[1] * fb[0]};
  const double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
  if (!(len > 0)) return;  // keep the float axis
  for (double& c : n) c /= len;
  double amin = 1e300, amax = -1e300, bmin = 1e300, bmax = -1e300;
  for (int q = 0; q < 3; ++q) {
    const double ta = n[0] * va[q][0] + n[1] * va[q][1] + n[2] * va[q][2];
    const double tb = n[0] * vb[q][0] + n[1] * vb[q][1] + n[2] * vb[q][2];
    amin = std::min(amin, ta), amax = std::max(amax, ta), bmin = std::min(bmin, tb), bmax = std::max(bmax, tb);
  }
  const double op = amax - bmin, on = bmax - amin;
  for (int c = 0; c < 3; ++c) l[c] = static_cast<float>(n[c]);
  *depth = static_cast<float>(std::min(op, on));
  *pos = op <= on ? 1.0f : 0.0f;
}

template <class F>
IMPACT_INLINE void triangle_triangle_block(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out,
                                           uint32_t k) {
  using Mask = typename F::Mask;
  using Int = typename F::Int;
  const F zero(0.0f), one(1.0f), half(0.5f);
  const V3<F> pa = load_p<F>(a, k);
  const V3<F> zv{zero, zero, zero};
  // both triangles relative to A's v0
  const V3<F> va[3] = {zv, load_w<F>(a, k, 0) - pa, load_w<F>(a, k, 3) - pa};
  const V3<F> vb[3] = {load_p<F>(b, k) - pa, load_w<F>(b, k, 0) - pa, load_w<F>(b, k, 3) - pa};
  const V3<F> fa[3] = {va[1], va[2] - va[1], -va[2]};  // edge i: v[i] -> v[i+1]
  const V3<F> fb[3] = {vb[1] - vb[0], vb[2] - vb[1], vb[0] - vb[2]};
  const F lfa[3] = {length_sq(fa[0]), length_sq(fa[1]), length_sq(fa[2])};
  const F lfb[3] = {length_sq(fb[0]), length_sq(fb[1]), length_sq(fb[2])};
  const F fla[3] = {sqrt(lfa[0]), sqrt(lfa[1]), sqrt(lfa[2])};
  const F flb[3] = {sqrt(lfb[0]), sqrt(lfb[1]), sqrt(lfb[2])};
  const V3<F> big_na = cross(fa[0], va[2]);          // (a1 - a0) x (a2 - a0)
  const V3<F> big_nb = cross(fb[0], vb[2] - vb[0]);  // (b1 - b0) x (b2 - b0)
  const V3<F> na = triangle_normal(va[0], va[1], va[2]);
  const V3<F> nb = triangle_normal(vb[0], vb[1], vb[2]);
  const F size = max(fla[0], max(fla[1], fla[2])) + max(flb[0], max(flb[1], flb[2]));
  const F tie_floor = F(kTieSize) * size;

  // --- 1. SAT ---
  F best, min_all;
  F axis;    // 0 A's normal, 1 B's normal, 2 + 3i + j edge fa_i x fb_j
  Mask pos;  // n = +axis (B is pushed along +axis)
  F flat;    // the smaller width of both along a triangle normal: ~0 when coplanar
  {
    // A's normal: A's interval is ~a point (its rounding), B's its vertices'
    const F ta1 = dot(na, va[1]), ta2 = dot(na, va[2]);
    const F tb0 = dot(na, vb[0]), tb1 = dot(na, vb[1]), tb2 = dot(na, vb[2]);
    const F op = max(zero, max(ta1, ta2)) - min(tb0, min(tb1, tb2));
    const F on = max(tb0, max(tb1, tb2)) - min(zero, min(ta1, ta2));
    best = min(op, on);
    min_all = best;
    axis = zero;
    pos = op <= on;
    flat = max(op, on);
  }
  {
    const F ta1 = dot(nb, va[1]), ta2 = dot(nb, va[2]);
    const F tb0 = dot(nb, vb[0]), tb1 = dot(nb, vb[1]), tb2 = dot(nb, vb[2]);
    const F op = max(zero, max(ta1, ta2)) - min(tb0, min(tb1, tb2));
    const F on = max(tb0, max(tb1, tb2)) - min(zero, min(ta1, ta2));
    const F o = min(op, on);
    const F lim = best - mul_add(F(kTieRel), abs(best), tie_floor);
    min_all = min(min_all, o);
    flat = min(flat, max(op, on));
    const Mask take = (o < lim) & (o < best);
    best = select(take, o, best);
    axis = select(take, one, axis);
    pos = select(take, op <= on, pos);
  }
  const F lim_face = best - mul_add(F(kTieRel), abs(best), tie_floor);
  const F edge_round(kEdgeRound);
  const F ilfa[3] = {one / max(lfa[0], F(kTinySq)), one / max(lfa[1], F(kTinySq)), one / max(lfa[2], F(kTinySq))};
  // offsets of the opposite vertex from the axis's edge: A's by B's edge j, B's by A's edge i
  const F sa[3] = {-dot(fb[0], big_na), -dot(fb[1], big_na), -dot(fb[2], big_na)};
  const F sb[3] = {dot(fa[0], big_nb), dot(fa[1], big_nb), dot(fa[2], big_nb)};
  V3<F> edge_l = zv;  // the winning edge axis (unit)
  F edge_inv = zero;  // its 1 / |l|
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      const V3<F> l = cross(fa[i], fb[j]);
      const F ll = length_sq(l);
      const Mask ok = ll > F(kEdgeSkipSq) * lfa[i] * lfb[j];
      const F inv = one / sqrt(select(ok, ll, one));
      // A's interval {0, sa_j}, B's {d, d + sb_i} (times |l|)
      // B's edge start relative to A's edge line, across it (l is computed with an error
      // of ~eps |fa| |fb| in any direction: the part of r along the edges would bring
      // eps |r| / sin(angle) into d for near-parallel edges)
      const V3<F> r = vb[j] - va[i];
      const F d = dot(l, madd(r, -dot(r, fa[i]) * ilfa[i], fa[i]));
      const F op = max(zero, sa[j]) - min(zero, sb[i]) - d;
      const F on = d + max(zero, sb[i]) - min(zero, sa[j]);
      const F o = min(op, on) * inv;
      min_all = select(ok, min(min_all, o), min_all);
      // rounding of o: ~eps (size + |r across| / sin(angle)), |r across| ~ |d| / |l| + size sin
      const F amp = fla[i] * flb[j] * inv;  // 1 / sin(angle)
      const F round = edge_round * mul_add(abs(d) * inv, amp, size);
      const Mask take = ok & (o < lim_face - round) & (o < best);
      best = select(take, o, best);
      axis = select(take, F(static_cast<float>(2 + 3 * i + j)), axis);
      pos = select(take, op <= on, pos);
      edge_l = select(take, l * inv, edge_l);
      edge_inv = select(take, inv, edge_inv);
    }
  }
  // coplanar within rounding (one triangle within kBand * size of the other's plane): the
  // least overlap is 0 up to rounding, touching
  // both degenerate (zero area within rounding: the height over the longest edge below
  // kBand of it): A - B is flat, s <= 0, and the fallback normals are no SAT axes for it
  const F lma = max(lfa[0], max(lfa[1], lfa[2])), lmb = max(lfb[0], max(lfb[1], lfb[2]));
  const Mask deg_a = length_sq(big_na) <= F(kBand * kBand) * lma * lma;
  const Mask deg_b = length_sq(big_nb) <= F(kBand * kBand) * lmb * lmb;
  Mask hit = andnot((min_all > zero) & (flat > F(kBand) * size), deg_a & deg_b);
  if (simd::none(hit)) {
    store_no_contact<F>(out, k);
    return;
  }
  const Mask is_edge = axis >= F(2.0f);
  const Mask ref_a = axis == zero;
  const F e_idx = axis - F(2.0f);
  F ei = select(e_idx < F(3.0f), zero, select(e_idx < F(6.0f), one, F(2.0f)));
  F ej = e_idx - F(3.0f) * ei;
  // A near-parallel edge pair's float axis is off by ~eps / sin(angle): moving B along it
  // by the depth (exact for the true axis) may not separate them. Those lanes take the
  // axis and its overlap from the world floats in double (rare: 1 / sin > 20).
  {
    const F amp = edge_inv * pick3(ei, fla[0], fla[1], fla[2]) * pick3(ej, flb[0], flb[1], flb[2]);
    const Mask fix = hit & is_edge & (amp > F(1.0f / kFixSin));
    if (simd::any(fix)) {
      constexpr uint32_t W = F::kWidth;
      float lx[W], ly[W], lz[W], dep[W], pp[W], fi[W], fj[W];
      edge_l.x.store(lx), edge_l.y.store(ly), edge_l.z.store(lz), best.store(dep), ei.store(fi), ej.store(fj);
      select(pos, one, zero).store(pp);
      for (uint32_t q = 0; q < W; ++q) {
        if (!fix.lane(q)) continue;
        float l[3] = {lx[q], ly[q], lz[q]};
        edge_axis_double(a, b, k + q, static_cast<int>(fi[q]), static_cast<int>(fj[q]), l, &dep[q], &pp[q]);
        lx[q] = l[0], ly[q] = l[1], lz[q] = l[2];
      }
      edge_l = V3<F>{F::load(lx), F::load(ly), F::load(lz)};
      best = F::load(dep);
      pos = F::load(pp) > half;
      hit = andnot(hit, fix & (best <= zero));  // separated along the exact axis
    }
  }

  // Normal, A to B.
  V3<F> nl = select(is_edge, edge_l, select(ref_a, na, nb));
  nl = select(pos, nl, -nl);
  Lanes<F, 4> m;
  m.n = nl;
  m.depth = best;
  for (int q = 0; q < 4; ++q) {
    m.point[q] = zv;
    m.pdepth[q] = zero;
  }
  m.count = Int(0);

  // --- 4. edge axis: one point between A's and B's support features ---
  const Mask edge = hit & is_edge;
  if (simd::any(edge)) {
    // A's support along n is its max along +l (pos) or its min: the opposite vertex where
    // it lies beyond the edge by more than the rounding band, else the edge; B's the other
    // way. A degenerate triangle's support is its longest edge (its three edges are
    // collinear, and the axis's edge may be the shorter part).
    const F band = F(kBand) * size;
    const F sai = pick3(ej, sa[0], sa[1], sa[2]) * edge_inv, sbi = pick3(ei, sb[0], sb[1], sb[2]) * edge_inv;
    const Mask vert_a = andnot(select(pos, sai > band, sai < -band), deg_a);
    const Mask vert_b = andnot(select(pos, sbi < -band, sbi > band), deg_b);
    auto longest = [&](const F (&lf)[3]) {
      return select((lf[0] >= lf[1]) & (lf[0] >= lf[2]), zero, select(lf[1] >= lf[2], one, F(2.0f)));
    };
    ei = select(deg_a, longest(lfa), ei);
    ej = select(deg_b, longest(lfb), ej);
    const V3<F> fai = pick3(ei, fa[0], fa[1], fa[2]), fbj = pick3(ej, fb[0], fb[1], fb[2]);
    const V3<F> a0 = pick3(ei, va[0], va[1], va[2]), b0 = pick3(ej, vb[0], vb[1], vb[2]);
    // Both edges: the closest points of their lines, a0 + s fa and b0 + u fb, by
    // s = ((b0 - a0) x fb).l / |l|^2 (error ~eps / sin(angle) along the edges: stable for
    // near-parallel ones, where the usual normal equations lose eps / sin^2), clamped.
    const V3<F> l = cross(fai, fbj);
    const F il2 = one / max(length_sq(l), F(kTinySq));
    const V3<F> r = b0 - a0;
    const F s_line = clamp(dot(cross(r, fbj), l) * il2, zero, one);
    const F u_line = clamp(dot(cross(r, fai), l) * il2, zero, one);
    V3<F> p = (madd(a0, s_line, fai) + madd(b0, u_line, fbj)) * half;
    // A vertex on either side: closest points of segment and point (or two points).
    const Mask vert = vert_a | vert_b;
    if (simd::any(edge & vert)) {
      F la, lb;
      const V3<F> ua = normalize_or(fai, V3<F>{one, zero, zero}, la);
      const V3<F> ub = normalize_or(fbj, V3<F>{one, zero, zero}, lb);
      const V3<F> ca = select(vert_a, pick3(ei, va[2], va[0], va[1]), a0 + fai * half);
      const V3<F> cb = select(vert_b, pick3(ej, vb[2], vb[0], vb[1]), b0 + fbj * half);
      const F ha = select(vert_a, zero, half * la), hb = select(vert_b, zero, half * lb);
      F s, u;
      closest_segment_segment(ca, ua, ha, cb, ub, hb, s, u);
      p = select(vert, (madd(ca, s, ua) + madd(cb, u, ub)) * half, p);
    }
    m.point[0] = select(edge, p, m.point[0]);
    m.pdepth[0] = select(edge, best, m.pdepth[0]);
    m.count = select(edge, Int(1), m.count);
  }

  // --- 3. face axis: both triangles projected along n, 15 candidates ---
  const Mask face = hit & ~is_edge;
  if (simd::any(face)) {
    const V3<F> t1 = any_perpendicular(nl);
    const V3<F> t2 = cross(nl, t1);
    Proj<F> A, B;
    for (int q = 0; q < 3; ++q) {
      A.x[q] = dot(t1, va[q]), A.y[q] = dot(t2, va[q]), A.h[q] = dot(nl, va[q]);
      B.x[q] = dot(t1, vb[q]), B.y[q] = dot(t2, vb[q]), B.h[q] = dot(nl, vb[q]);
    }
    A.setup();
    B.setup();
    const F lo_s(-1e-6f), hi_s(1.0f + 1e-6f);
    constexpr int M = 15;
    F cx[M], cy[M], cd[M];
    Mask cv[M];
    int c = 0;
    // (1) A's vertices inside B, (2) B's inside A
    for (int q = 0; q < 3; ++q, ++c) {
      F hb;
      cv[c] = B.inside(A.x[q], A.y[q], lo_s, hb);
      cx[c] = A.x[q], cy[c] = A.y[q], cd[c] = A.h[q] - hb;
    }
    for (int q = 0; q < 3; ++q, ++c) {
      F ha;
      cv[c] = A.inside(B.x[q], B.y[q], lo_s, ha);
      cx[c] = B.x[q], cy[c] = B.y[q], cd[c] = ha - B.h[q];
    }
    // (3) A's edge i crossing B's edge j: A.v[i] + s dA = B.v[j] + u dB
    for (int i = 0; i < 3; ++i) {
      const int i1 = (i + 1) % 3;
      const F dax = A.x[i1] - A.x[i], day = A.y[i1] - A.y[i], dah = A.h[i1] - A.h[i];
      const F la2 = dax * dax + day * day;
      for (int j = 0; j < 3; ++j, ++c) {
        const int j1 = (j + 1) % 3;
        const F dbx = B.x[j1] - B.x[j], dby = B.y[j1] - B.y[j], dbh = B.h[j1] - B.h[j];
        const F rx = B.x[j] - A.x[i], ry = B.y[j] - A.y[i];
        const F den = dax * dby - day * dbx;
        const Mask ok = den * den > F(kParallelSq) * la2 * (dbx * dbx + dby * dby);
        const F inv = one / select(ok, den, one);
        const F s = (rx * dby - ry * dbx) * inv;
        const F u = (rx * day - ry * dax) * inv;
        cx[c] = mul_add(s, dax, A.x[i]);
        cy[c] = mul_add(s, day, A.y[i]);
        cd[c] = mul_add(s, dah, A.h[i]) - mul_add(u, dbh, B.h[j]);
        cv[c] = ok & (s >= lo_s) & (s <= hi_s) & (u >= lo_s) & (u <= hi_s);
      }
    }
    for (int i = 0; i < M; ++i) cv[i] = cv[i] & (cd[i] > zero);
    F ox[4], oy[4], od[4];
    Int cnt;
    reduce4<F, M>(cx, cy, cd, cv, F(1e-5f) * size, ox, oy, od, cnt);
    // the reference triangle's height (its plane; B's when B's normal won)
    const F third(1.0f / 3.0f);
    const F h_ref = select(ref_a, (A.h[0] + A.h[1] + A.h[2]) * third, (B.h[0] + B.h[1] + B.h[2]) * third);
    const F side = select(ref_a, F(-0.5f), half);  // midway: from A's plane down, from B's up
    for (int i = 0; i < 4; ++i) {
      const V3<F> p = madd(t1 * ox[i] + t2 * oy[i], mul_add(side, od[i], h_ref), nl);
      m.point[i] = select(face, p, m.point[i]);
      m.pdepth[i] = select(face, min(od[i], best), m.pdepth[i]);
    }
    // no candidate survived rounding (grazing contact): the incident triangle's deepest vertex
    const Mask none_left = face & (cnt == Int(0));
    const F hb_min = min(B.h[0], min(B.h[1], B.h[2]));
    const F ha_max = max(A.h[0], max(A.h[1], A.h[2]));
    const V3<F> deep_b = select(B.h[0] == hb_min, vb[0], select(B.h[1] == hb_min, vb[1], vb[2]));
    const V3<F> deep_a = select(A.h[0] == ha_max, va[0], select(A.h[1] == ha_max, va[1], va[2]));
    const V3<F> fallback = select(ref_a, madd(deep_b, half * best, nl), madd(deep_a, F(-0.5f) * best, nl));
    m.point[0] = select(none_left, fallback, m.point[0]);
    m.pdepth[0] = select(none_left, best, m.pdepth[0]);
    m.count = select(face, select(none_left, Int(1), cnt), m.count);
  }
  m.count = select(hit, m.count, Int(0));
  store(out, k, m, pa);
}

}  // namespace

void collide_triangle_triangle(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, Range r,
                               const NarrowConfig& cfg) {
  IMPACT_LANE_KERNEL_BODY(triangle_triangle_block, 4);
}

}  // namespace impact::kernels
