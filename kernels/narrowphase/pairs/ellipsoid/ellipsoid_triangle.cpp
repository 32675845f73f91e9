// Ellipsoid (A) against triangle (B): exact collision data by the local minima of the
// support overlap, vectorised across pairs (one lane = one pair), no GJK / EPA.
//
// Inputs: LeafSoA lanes per leaf.h (A an ellipsoid: p, R, radii e0, e1, e2 along R's
// columns; B a triangle: p = v0, w0..w2 = v1, w3..w5 = v2, zero thickness, both sides
// solid), Range r of the bucket.
// Outputs: ManifoldSoA lanes r.begin .. r.end: count (0 or 1), n (unit, A to B), depth,
// point[0] midway between the two surfaces (the ellipsoid's point touching along n,
// moved by depth / 2 against n), pdepth[0] = depth. Slots 1..3 untouched; count-0
// lanes leave the other fields unspecified.
// Method, in the ellipsoid's frame scaled by its largest radius (radii a_i in (0, 1],
// the vertices w_j relative to the ellipsoid's centre, so poses far from the origin
// keep their precision): with n a direction from the ellipsoid towards the triangle,
//     G(n) = h_E(n) - min_j n.w_j,   h_E(n) = |diag(a) n| (the support function),
// is the support overlap of the pair along n, depth = min over unit n of G and the
// normal its argmin (inside: the penetration depth; outside: minus the distance). The
// unit sphere splits into the open regions where one vertex is the triangle's nearest
// point along n (G = h_E(n) - n.w_j: the distance from w_j to the ellipsoid's surface,
// n its outward normal there), the open half circles perpendicular to an edge where its
// two vertices tie (G is the support overlap of the ellipsoid's shadow on the plane
// perpendicular to the edge, an ellipse, and the vertex's projection), and the two
// face normals +-N where all three tie. The minimiser is
//  - in a vertex region: a local minimum of the distance from w_j to the surface: the
//    nearest point or the far local minimum across the smallest axis (at most these
//    two: ellipsoid_solve.h);
//  - on an edge's half circle: a local minimum of the 2-D problem on the whole circle,
//    the shadow's nearest point to the projection or its far local minimum (the half
//    circle is not the whole circle, so a minimum there need not be the circle's least);
//  - +N or -N.
// So fourteen candidate directions (two faces, three vertices x two, three edges x two)
// hold the minimiser; each is scored by G itself (every direction's G is >= the
// minimum, so a candidate that is not a local minimum never wins wrongly) and the least
// wins (ties: the earlier in that order: faces, vertices' and edges' nearest points,
// vertices' and edges' far minima). A vertex's or an edge's candidates count only on
// its own piece (within 1e-5 rad): off it they are no minimum, yet may score within
// float noise of it, and the neighbouring pieces' candidates cover the band between. Separated pairs
// (min G < 0) are a convex problem; the far minima (G > 0) matter only for triangles
// that meet the ellipsoid, and a block without such a lane skips their solves.
// Solves: ellipsoid_solve.h (nearest points: Eberly's secular equation by 10
// safeguarded steps, as sphere_ellipsoid.cpp; far minima: 8 steps from the pole side;
// the shadows' axes in closed form).
// Degenerate input: a zero-length edge gives a meaningless shadow and a sliver or
// collinear triangle an inaccurate face normal: their candidates are still scored by G,
// so they only cost a candidate (a segment-like triangle is covered by its other edges
// and vertices: the edge circle is then the whole tie set); components of inside points
// below 1e-6 e_max are solved as 0 (depth error <= 1e-6 e_max). Sliver triangles' face
// normals carry the cross product's rounding (~eps / sin of the smallest angle).
// Preconditions: finite inputs, positive radii, orthonormal R (host-validated); no
// division without a guard, so finite inputs give finite outputs.
// Cost: per lane 3 nearest-point solves and 3 on shadows (at most 11 evaluations of
// the secular function and 10 steps each; a block stops once every lane sits at a fixed
// point of its step), 14 scores; far minima only for the (lane, vertex or edge) slots
// whose triangle meets the ellipsoid and that pass the existence test, packed 8 to a
// solve (~3 slots per 8-lane block on the bench: one solve instead of six); no branch
// on lane data in the arithmetic (selects), no libm call. A block whose triangles all
// lie beyond e_max along their normal or whose bounding spheres are all farther than
// e_max from the ellipsoid's centre stops early.
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
using simd::cross;
using simd::dot;
using simd::length_sq;

/// A vertex's or an edge's candidate counts where it lies on that piece up to this (sine
/// of the angle past the piece's boundary).
constexpr float kPieceTol = 1e-5f;

template <class F>
IMPACT_INLINE void ellipsoid_triangle_block(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out,
                                            uint32_t k) {
  using Mask = typename F::Mask;
  const F zero(0.0f), one(1.0f), big(3.0e38f);
  const V3<F> pa = load_p<F>(a, k);
  const V3<F> e = load_e<F>(a, k);
  const F emax = max(max(e.x, e.y), e.z);
  const V3<F> v0 = load_p<F>(b, k) - pa, v1 = load_w<F>(b, k, 0) - pa, v2 = load_w<F>(b, k, 3) - pa;
  // No contact in every lane: the triangle beyond e_max along its (any) unit normal, or
  // its bounding sphere (about the centroid) farther than e_max from the ellipsoid's
  // centre. Both are separating tests for any triangle, degenerate ones included.
  {
    const V3<F> nw = triangle_normal(v0, v1, v2);
    const F s0 = dot(nw, v0), s1 = dot(nw, v1), s2 = dot(nw, v2);
    const Mask beyond = (min(min(s0, s1), s2) > emax) | (max(max(s0, s1), s2) < -emax);
    const V3<F> c = (v0 + v1 + v2) * F(1.0f / 3.0f);
    const F rt2 = max(max(length_sq(v0 - c), length_sq(v1 - c)), length_sq(v2 - c));
    const F gap = sqrt(length_sq(c)) - emax;
    const Mask far = (gap > zero) & (gap * gap > rt2);
    if (simd::all(beyond | far)) {
      store_no_contact<F>(out, k);
      return;
    }
  }
  const M3<F> rot = load_r<F>(a, k);
  const F inv = one / emax;
  const F av[3] = {e.x * inv, e.y * inv, e.z * inv};
  const V3<F> w[3] = {rot.apply_t(v0) * inv, rot.apply_t(v1) * inv, rot.apply_t(v2) * inv};

  F best = big, best_len = one;
  V3<F> best_m{zero, zero, one};
  auto consider = [&](const V3<F>& m, Mask valid) {
    const F l2 = length_sq(m);
    const Mask ok = valid & (l2 >= F(kTinySq));
    const F len = sqrt(select(ok, l2, one));
    const F ax = av[0] * m.x, ay = av[1] * m.y, az = av[2] * m.z;
    const F he = sqrt(ax * ax + ay * ay + az * az);
    const F lowest = min(min(dot(m, w[0]), dot(m, w[1])), dot(m, w[2]));
    const F value = (he - lowest) / len;
    const Mask take = ok & (value < best);
    best = select(take, value, best);
    best_m = select(take, m, best_m);
    best_len = select(take, len, best_len);
  };

  // A vertex's or an edge's candidates only on its own piece: vertex j lowest along m
  // (m.(w_j - w_k) <= 0 for the others, within kPieceTol of the angle), an edge's
  // vertices not above the third. Off it a candidate is no local minimum of G, though it
  // may score within float noise of the minimum; the neighbouring pieces' candidates
  // cover the band between.
  V3<F> dw[3];
  F dw2[3];
  for (int j = 0; j < 3; ++j) dw[j] = w[j] - w[(j + 1) % 3], dw2[j] = length_sq(dw[j]);  // w_j - w_{j+1}
  const F tol2(kPieceTol * kPieceTol);
  auto not_above = [&](const V3<F>& m, const F& m2, int j, float side) {  // side * m.dw_j <= tol
    const F dm = dot(m, dw[j]) * F(side);
    return (dm <= zero) | (dm * dm <= tol2 * m2 * dw2[j]);
  };
  // vertex j below w_{j+1} (dw_j) and below w_{j+2} (-dw_{j+2})
  auto on_vertex = [&](const V3<F>& m, int j) {
    const F m2 = length_sq(m);
    return not_above(m, m2, j, 1.0f) & not_above(m, m2, (j + 2) % 3, -1.0f);
  };
  // edge (w_j, w_{j+1}) below w_{j+2}: w_{j+1} - w_{j+2} = dw_{j+1}, w_j - w_{j+2} = -dw_{j+2}
  auto on_edge = [&](const V3<F>& m, int j) {
    const F m2 = length_sq(m);
    return not_above(m, m2, (j + 1) % 3, 1.0f) & not_above(m, m2, (j + 2) % 3, -1.0f);
  };

  // Faces, then the vertices' and edges' nearest points.
  const V3<F> nf = triangle_normal(w[0], w[1], w[2]);
  consider(nf, Mask(true));
  consider(-nf, Mask(true));
  ellip::PointSolve<3, F> vs[3];
  for (int j = 0; j < 3; ++j) {
    const V3<F> m = ellip::near_normal(av, w[j], vs[j]);
    consider(m, on_vertex(m, j));
  }
  ellip::Shadow<F> sh[3];
  ellip::PointSolve<2, F> es[3];
  Mask edge_ok[3];
  for (int j = 0; j < 3; ++j) {
    const V3<F> d = w[(j + 1) % 3] - w[j];
    F len;
    const V3<F> dir = normalize_or(d, any_perpendicular(nf), len);
    edge_ok[j] = len > zero;
    sh[j] = ellip::shadow(av, dir);
    const V3<F> m = ellip::near_normal(sh[j], w[j], es[j]);
    consider(m, edge_ok[j] & on_edge(m, j));
  }
  // Far minima score > 0: only a triangle that meets the ellipsoid (least score so far
  // >= 0) can need them. (The other lanes ignore them, so a lane's bytes do not depend
  // on its block.) Packed: only the slots that can have one are solved (far_packed).
  const Mask meets = best >= zero;
  if (simd::any(meets)) {
    // Vertices, then the edges' shadows as radii (ax0, ax1, ax0) with z_2 = 0.
    F fa[6][3], fz[6][3], fg[6][3], g[6][3];
    Mask want[6], ok[6];
    for (int j = 0; j < 3; ++j) {
      for (int i = 0; i < 3; ++i) fa[j][i] = av[i], fz[j][i] = vs[j].z[i], fg[j][i] = vs[j].g_near[i];
      want[j] = meets;
      const F ea[3] = {sh[j].ax[0], sh[j].ax[1], sh[j].ax[0]};
      const F ez[3] = {es[j].z[0], es[j].z[1], zero};
      const F eg[3] = {es[j].g_near[0], es[j].g_near[1], zero};
      for (int i = 0; i < 3; ++i) fa[3 + j][i] = ea[i], fz[3 + j][i] = ez[i], fg[3 + j][i] = eg[i];
      want[3 + j] = meets & edge_ok[j];
    }
    ellip::far_packed(fa, fz, fg, want, g, ok);
    for (int j = 0; j < 3; ++j) {
      const V3<F> m{vs[j].sign[0] * g[j][0], vs[j].sign[1] * g[j][1], vs[j].sign[2] * g[j][2]};
      consider(m, ok[j] & on_vertex(m, j));
    }
    for (int j = 0; j < 3; ++j) {
      const F* gj = g[3 + j];
      const V3<F> m = sh[j].e1 * (es[j].sign[0] * gj[0]) + sh[j].e2 * (es[j].sign[1] * gj[1]);
      consider(m, ok[3 + j] & on_edge(m, j));
    }
  }

  // n from A to B: the best direction; A's surface point: its support along n.
  const V3<F> nl = best_m * (one / best_len);
  const V3<F> n = rot.apply(nl);
  const F depth = best * emax;
  const V3<F> an{av[0] * nl.x, av[1] * nl.y, av[2] * nl.z};
  const F he = sqrt(length_sq(an));
  const F s = emax / select(he > zero, he, one);
  const V3<F> xa{av[0] * an.x * s, av[1] * an.y * s, av[2] * an.z * s};
  const V3<F> on_a = rot.apply(xa);
  Lanes<F, 1> m;
  m.count = simd::to_int(depth > zero);
  m.n = n;
  m.depth = depth;
  m.point[0] = madd(on_a, F(-0.5f) * depth, n);
  m.pdepth[0] = depth;
  store(out, k, m, pa);
}

}  // namespace

void collide_ellipsoid_triangle(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, Range r,
                                const NarrowConfig& cfg) {
  IMPACT_LANE_KERNEL_BODY(ellipsoid_triangle_block, 1);
}

}  // namespace impact::kernels
