// Cylinder (A) against triangle (B): exact collision data of 1 to 4 points per pair,
// vectorised across pairs (one lane = one pair), no GJK / EPA.
//
// Inputs: LeafSoA lanes per leaf.h (A a cylinder C: p centre, R column 2 = unit axis,
// e0 = radius rc, e1 = half length h, flat caps with sharp rims; B a triangle T: p = v0,
// w0..w2 = v1, w3..w5 = v2, zero thickness, both sides solid), Range r of the bucket.
// Outputs: ManifoldSoA lanes r.begin .. r.end: count (0..4), n (unit, A to B: the
// separating direction), depth, point slots midway between the surfaces with their
// depths along n; count-0 lanes leave the other fields unspecified.
//
// Method, in the cylinder's frame relative to its centre (w_j the vertices, e_j =
// w_j+1 - w_j): o(n) = h_C(n) - min_j n.w_j = h |n_z| + rc |n_xy| - min_j n.w_j is the
// support function of the Minkowski difference C - T; its minimum over unit n is minus
// the distance when apart and the depth when they meet (no case split), and every unit
// n gives an upper bound, so the answer is the least o over a candidate set sure to
// hold the minimiser (as capsule_cylinder.cpp). One candidate per boundary piece of
// C - T (a cylinder feature summed with a triangle feature whose normal sets meet):
//  - cap x vertex: n = +-z, o = h -+ (lowest / highest vertex height);
//  - rim point x face: n = +-N (the triangle's normal);
//  - side x vertex / edge: n horizontal minimising o over the horizontal circle, where
//    o = rc + the support of the triangle's shadow: per edge the direction from the axis
//    to the shadow's point nearest it, and +-(z x e_j) where that is the perpendicular's
//    foot (the axis inside the shadow);
//  - rim x vertex (an edge of C - T, only a minimiser when apart): n from the rim
//    circle's point nearest the vertex, each rim;
//  - rim x edge interior: n on the great circle n.e = 0, where o is the 2D signed
//    distance from the edge's shadow point to the rim's shadow along e (an ellipse; the
//    upper / lower half for the top / bottom rim): the nearest point, or from the far
//    side the second local minimum, by the fixed-step solve of Eberly's secular
//    equation shared with capsule-cylinder (rim_solve.h), 6 slots (3 edges x 2 rims).
// Those are all the pieces: the rims' normal sets are the open half spheres minus the
// cap normals, the side's the horizontal circle, the edges' the half great circles
// n.e = 0, the vertices' 2D regions. Each candidate's o is the exact support overlap
// along its n; a candidate whose witness lies off its piece (beyond kSlackRel of the
// pair's size) is dropped from the choice (near the minimum o is flat, and such a
// candidate could tie the true one within rounding with a direction 1e-4 rad off); if
// none is left, the least o of all. Ties keep the first in the order caps, faces,
// sides, vertex-rims, edge-rims.
// Contact points: one, midway between the triangle's witness and the cylinder's surface
// point o along n. Where n is within kParallelSin of the axis (a cap): the triangle seen
// along n on the cap plane clipped to the disk (its vertices inside, its edges' rim
// crossings, the 8 rim samples kRimCos inside a well shaped triangle: the cap polygon),
// each with its own gap along n, reduced to 4 (reduce4). Where n is within kParallelSin
// of the horizontal (the side): the side's line along n clipped to the triangle's face
// (a face lying on the side; only a triangle of area >= kSideShape times its longest
// edge squared, whose plane is well defined in float) and each edge clipped to the
// side's height (an edge along the side; depth = where the line from it along n leaves
// the cylinder), reduced to 4. Points with no positive gap are dropped; the witness
// stays only where no other point is as deep.
// Preconditions: finite inputs, rc > 0, h > 0, unit axis, orthonormal R. Degenerate
// input: a collinear triangle or a point gets the same candidates (its "face" normal is
// triangle_normal's fallback, perpendicular to the longest edge, and its face candidates
// need a real plane); a needle or pancake cylinder (1e-4) needs nothing special; an edge
// along the axis takes the x axis as its horizontal normal; coincident centres give a
// finite unit normal (the ties above decide it).
// Cost: 25 candidate directions in closed form and the 6-slot root solve of
// kArcIterations steps (3 divisions, 2 square roots each), plus the two manifold
// clips, run only where a lane of the block needs them; no other branch on lane data
// (selects) except a block whose lanes are all farther apart than their bounding
// spheres. The one-lane path runs the 25 candidates and the 6-slot solve one pair at a
// time: the reference path, not a fast one. Cost: measured per pair in docs/results.md ("Narrow phase").
// Both paths run the same template (F = FloatW, or Float1 for the scalar reference).
// References: Minkowski-difference support functions for penetration depth (van den
// Bergen, Collision Detection in Interactive 3D Environments, 2003, ch. 4); the
// secular equation of the point-ellipse distance (Eberly, "Distance from a Point to an
// Ellipse, an Ellipsoid, or a Hyperellipsoid", Geometric Tools, 2013); contact
// clipping and reduction to 4 points as in the other lane kernels (lanes/manifold_reduce.h).
#include <cstdint>

#include "kernels/narrowphase/pair_kernels.h"
#include "kernels/narrowphase/lanes/block_driver.h"
#include "kernels/narrowphase/lanes/lane_geometry.h"
#include "kernels/narrowphase/lanes/lane_io.h"
#include "kernels/narrowphase/lanes/manifold_reduce.h"
#include "kernels/narrowphase/solvers/rim_solve.h"

// No FMA contraction in this file (see no_contract.h).
#include "kernels/narrowphase/lanes/no_contract.h"  // last: its pragma covers what follows

namespace impact::kernels {
namespace {

using namespace prim;  // NOLINT: lane helpers of this kernel family
using simd::cross;
using simd::dot;
using simd::length_sq;

/// Witness tests accept a candidate whose witness lies off its piece by up to this
/// times (rc + h + the vertices' largest coordinate in the cylinder frame).
constexpr float kSlackRel = 1e-6f;
/// |sin| between n and the axis (the cap plane) below which the contact is a cap (side)
/// contact with a clipped manifold.
constexpr float kParallelSin = 0.05f;
/// Points sampled on a cap's rim for the cap manifold (the cap polygon): cos of
/// multiples of 45 degrees (sin = cos 90 degrees earlier).
constexpr int kRimSamples = 8;
constexpr float kRimCos[kRimSamples] = {1.0f,  0.70710678f,  0.0f, -0.70710678f,
                                        -1.0f, -0.70710678f, 0.0f, 0.70710678f};
/// Rim samples count only on a triangle whose shadow's area is at least this times its
/// longest edge squared (an equilateral one: 0.43).
constexpr float kShape = 0.05f;
/// The side's line is clipped to the triangle's face only on a triangle whose area is
/// at least this times its longest edge squared (its plane then known to ~1e-5 L).
constexpr float kSideShape = 0.02f;
/// Candidate classes (for the manifold).
constexpr float kClassCap = 0.0f, kClassFace = 1.0f, kClassSide = 2.0f, kClassRim = 3.0f;

/// The least-so-far valid candidate: o, its normal, the triangle's witness point, class.
template <class F>
struct Best {
  F o;
  V3<F> n;
  V3<F> b;
  F cls;
  IMPACT_INLINE void take(F o2, const V3<F>& n2, const V3<F>& b2, float cls2) {
    const auto m = o2 < o;
    o = select(m, o2, o);
    n = select(m, n2, n);
    b = select(m, b2, b);
    cls = select(m, F(cls2), cls);
  }
};

template <class F>
IMPACT_INLINE F min3(F a, F b, F c) {
  return min(min(a, b), c);
}
template <class F>
IMPACT_INLINE F max3(F a, F b, F c) {
  return max(max(a, b), c);
}

template <class F>
IMPACT_INLINE void cylinder_triangle_block(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out,
                                           uint32_t k) {
  using Mask = typename F::Mask;
  using Int = typename F::Int;
  const F zero(0.0f), one(1.0f), half(0.5f), tiny(kTinySq), never(3.0e38f);
  const V3<F> pa = load_p<F>(a, k);
  const F rc = ld<F>(a.e[0], k), h = ld<F>(a.e[1], k);
  const V3<F> u0 = load_p<F>(b, k) - pa, u1 = load_w<F>(b, k, 0) - pa, u2 = load_w<F>(b, k, 3) - pa;
  // No contact in every lane: the triangle beyond the cylinder's bounding sphere along
  // its (any) unit normal, or its bounding sphere (about the centroid) apart from it.
  {
    const F reach = sqrt(rc * rc + h * h);
    const V3<F> nw = triangle_normal(u0, u1, u2);
    const F s0 = dot(nw, u0), s1 = dot(nw, u1), s2 = dot(nw, u2);
    const Mask beyond = (min3(s0, s1, s2) > reach) | (max3(s0, s1, s2) < -reach);
    const V3<F> c = (u0 + u1 + u2) * F(1.0f / 3.0f);
    const F rt2 = max3(length_sq(u0 - c), length_sq(u1 - c), length_sq(u2 - c));
    const F gap = sqrt(length_sq(c)) - reach;
    const Mask far = (gap > zero) & (gap * gap > rt2);
    if (simd::all(beyond | far)) {
      store_no_contact<F>(out, k);
      return;
    }
  }
  const M3<F> rot = load_r<F>(a, k);
  const V3<F> w[3] = {rot.apply_t(u0), rot.apply_t(u1), rot.apply_t(u2)};
  V3<F> e[3];
  for (int j = 0; j < 3; ++j) e[j] = w[(j + 1) % 3] - w[j];
  F mw = zero;
  for (int j = 0; j < 3; ++j) mw = max(mw, max3(abs(w[j].x), abs(w[j].y), abs(w[j].z)));
  const F slack = F(kSlackRel) * (rc + h + mw);
  const F rin = rc + slack, rin2 = rin * rin;

  // o(n) = h_C(n) - min_j n.w_j for unit n; lo receives min_j n.w_j.
  auto score = [&](const V3<F>& n, F& lo) {
    lo = min3(dot(n, w[0]), dot(n, w[1]), dot(n, w[2]));
    return mul_add(h, abs(n.z), rc * sqrt(n.x * n.x + n.y * n.y)) - lo;
  };
  // The cylinder's support point along n: a rim point (m = n's horizontal direction;
  // x for n along the axis).
  auto rim_point = [&](const V3<F>& n) {
    const F nxy2 = n.x * n.x + n.y * n.y;
    const Mask ok = nxy2 > tiny;
    const F s = rc / sqrt(select(ok, nxy2, one));
    return V3<F>{select(ok, s * n.x, rc), select(ok, s * n.y, zero), h * simd::sign_nonneg(n.z)};
  };

  Best<F> best;
  F any_o = never;  // the least o of every candidate, valid or not (a safety net)
  V3<F> any_n{zero, zero, one};
  auto consider = [&](F o, const V3<F>& n, const V3<F>& wb, Mask valid, float cls) {
    const Mask m = o < any_o;
    any_o = select(m, o, any_o);
    any_n = select(m, n, any_n);
    best.take(select(valid, o, never), n, wb, cls);
  };

  // --- shared 2-D quantities: each vertex's and each edge's distance from the axis ---
  F rho2[3];
  for (int j = 0; j < 3; ++j) rho2[j] = w[j].x * w[j].x + w[j].y * w[j].y;
  F tq[3], dq2[3];  // the point of edge j's shadow on z = 0 nearest the axis: w_j + tq e_j
  Mask tilted[3];
  for (int j = 0; j < 3; ++j) {
    const F exy2 = e[j].x * e[j].x + e[j].y * e[j].y;
    tilted[j] = exy2 > tiny;
    const F tf = -(w[j].x * e[j].x + w[j].y * e[j].y) / select(tilted[j], exy2, one);
    tq[j] = clamp(select(tilted[j], tf, zero), zero, one);
    const F qx = mul_add(tq[j], e[j].x, w[j].x), qy = mul_add(tq[j], e[j].y, w[j].y);
    dq2[j] = qx * qx + qy * qy;
  }
  // the axis inside the triangle's shadow on z = 0 (either orientation)
  Mask axis_in;
  {
    F cz[3];
    for (int j = 0; j < 3; ++j) cz[j] = w[j].x * w[(j + 1) % 3].y - w[j].y * w[(j + 1) % 3].x;
    axis_in = ((cz[0] >= zero) & (cz[1] >= zero) & (cz[2] >= zero)) |
              ((cz[0] <= zero) & (cz[1] <= zero) & (cz[2] <= zero));
  }
  // The triangle's lowest feature along +-z (vertices within slack of the least height)
  // meets the disk of radius rc + slack in the shadow.
  auto meets_disk = [&](const Mask(&low)[3]) {
    Mask m = low[0] & low[1] & low[2] & axis_in;
    for (int j = 0; j < 3; ++j) {
      const int j1 = (j + 1) % 3;
      m = m | (low[j] & (rho2[j] <= rin2)) | (low[j] & low[j1] & (dq2[j] <= rin2));
    }
    return m;
  };
  auto lowest_vertex = [&](F hz0, F hz1, F hz2) {  // the vertex of least height
    V3<F> v = select(hz1 < hz0, w[1], w[0]);
    return select(hz2 < min(hz0, hz1), w[2], v);
  };

  // --- caps: n = +-z ---
  {
    const F zmin = min3(w[0].z, w[1].z, w[2].z), zmax = max3(w[0].z, w[1].z, w[2].z);
    Mask lo_up[3], lo_dn[3];
    for (int j = 0; j < 3; ++j) lo_up[j] = w[j].z <= zmin + slack, lo_dn[j] = w[j].z >= zmax - slack;
    const V3<F> n_up{zero, zero, one}, n_dn{zero, zero, F(-1.0f)};
    best.o = never;
    best.n = n_up;
    best.b = w[0];
    best.cls = F(kClassCap);
    consider(h - zmin, n_up, lowest_vertex(w[0].z, w[1].z, w[2].z), meets_disk(lo_up), kClassCap);
    consider(h + zmax, n_dn, lowest_vertex(-w[0].z, -w[1].z, -w[2].z), meets_disk(lo_dn), kClassCap);
  }

  // --- faces: n = +-N; valid where the cylinder's support set along n (a rim point;
  // the cap disk or the side line where n is that close to the axis / the horizontal)
  // lies over the triangle ---
  const V3<F> nf = triangle_normal(w[0], w[1], w[2]);
  V3<F> en[3];  // in-plane inward edge normals (unnormalised, |e_j|)
  F elen[3];
  for (int j = 0; j < 3; ++j) en[j] = cross(nf, e[j]), elen[j] = sqrt(length_sq(e[j]));
  auto over_triangle = [&](const V3<F>& x) {  // x's shadow along nf inside, within slack
    Mask m(true);
    for (int j = 0; j < 3; ++j) m = m & (dot(en[j], x - w[j]) >= -slack * elen[j]);
    return m;
  };
  // The face's witness where the rim point is not over the triangle: on the side line
  // (the middle of its clipped part) or in the cap disk (the axis where the shadow holds
  // it, else the shadow's edge point nearest the axis).
  const Mask planar = length_sq(cross(e[0], e[2])) > tiny;  // nf is the triangle's own
  F fx = zero, fy = zero;
  {
    F best_d2 = never;
    for (int j = 0; j < 3; ++j) {
      const Mask m = dq2[j] < best_d2;
      best_d2 = select(m, dq2[j], best_d2);
      fx = select(m, mul_add(tq[j], e[j].x, w[j].x), fx);
      fy = select(m, mul_add(tq[j], e[j].y, w[j].y), fy);
    }
    fx = select(axis_in, zero, fx), fy = select(axis_in, zero, fy);
  }
  for (int sgn = 0; sgn < 2; ++sgn) {
    const V3<F> n = sgn == 0 ? nf : -nf;
    F lo;
    const F o = score(n, lo);
    const V3<F> r = rim_point(n);
    const F nxy = sqrt(n.x * n.x + n.y * n.y);
    const F sz = simd::sign_nonneg(n.z);
    const Mask over = over_triangle(r);
    // cap disk: the triangle's shadow within rc + slack of the axis
    const Mask all_low[3] = {Mask(true), Mask(true), Mask(true)};
    const Mask disk = (F(2.0f) * rc * nxy <= slack) & meets_disk(all_low);
    // side line r .. r - 2h z: clipped by the three edge planes (g0 + g1 t >= 0 for the
    // point r - t sz z)
    F tlo = zero, thi = F(2.0f) * h;
    for (int j = 0; j < 3; ++j) {
      const F g0 = mul_add(slack, elen[j], dot(en[j], r - w[j])), g1 = -en[j].z * sz;
      const Mask pos = g1 > zero, neg = g1 < zero;
      const F tb = g0 / select(pos | neg, g1, one);
      thi = select(neg, min(thi, -tb), thi);
      tlo = select(pos, max(tlo, -tb), tlo);
      tlo = select(~(pos | neg) & (g0 < zero), F(3.0e38f), tlo);
    }
    const Mask line = (F(2.0f) * h * abs(n.z) <= slack) & (tlo <= thi);
    const V3<F> on_line{r.x, r.y, r.z - sz * half * (tlo + thi)};
    const V3<F> on_disk{fx, fy, r.z};
    const V3<F> x = select(over, r, select(line, on_line, on_disk));
    consider(o, n, x - o * n, planar & (over | line | disk), kClassFace);
  }

  // --- sides: horizontal n. Per edge: the direction to its shadow's point nearest the
  // axis and, where that is the perpendicular's foot, +-(z x e) (the shadow passing the
  // axis). Valid where the witness (the triangle's points in the plane of n and the
  // axis) reaches the side's height and lies on the triangle's lowest feature ---
  for (int j = 0; j < 3; ++j) {
    const F exy2 = e[j].x * e[j].x + e[j].y * e[j].y;
    const F ie = one / sqrt(select(tilted[j], exy2, one));
    const F wx = select(tilted[j], -e[j].y * ie, one), wy = select(tilted[j], e[j].x * ie, zero);
    const F qx = mul_add(tq[j], e[j].x, w[j].x), qy = mul_add(tq[j], e[j].y, w[j].y);
    const Mask off = dq2[j] > tiny;
    const F qi = one / sqrt(select(off, dq2[j], one));
    const V3<F> dirs[3] = {
        {select(off, qx * qi, wx), select(off, qy * qi, wy), zero}, {wx, wy, zero}, {-wx, -wy, zero}};
    for (int c = 0; c < 3; ++c) {
      const V3<F>& n = dirs[c];
      const F lo = min3(dot(n, w[0]), dot(n, w[1]), dot(n, w[2]));
      const F o = rc - lo;
      // the edge's points within slack of the plane of n and z: s in [s0, s1]
      const F al = -n.y * w[j].x + n.x * w[j].y, be = -n.y * e[j].x + n.x * e[j].y;
      const Mask moves = abs(be) > tiny;
      const F ib = one / select(moves, be, one);
      const F sa = (-slack - al) * ib, sb = (slack - al) * ib;
      F s0 = select(moves, min(sa, sb), select(abs(al) <= slack, zero, one)),
        s1 = select(moves, max(sa, sb), select(abs(al) <= slack, one, zero));
      s0 = max(s0, zero), s1 = min(s1, one);
      const F z0 = mul_add(s0, e[j].z, w[j].z), z1 = mul_add(s1, e[j].z, w[j].z);
      Mask valid = (s0 <= s1) & (min(z0, z1) <= h + slack) & (max(z0, z1) >= -h - slack);
      // the witness: the foot (for an edge along the axis, the middle of its part within
      // the side's height)
      const Mask rises = abs(e[j].z) > tiny;
      const F iz = one / select(rises, e[j].z, one);
      const F za = (-h - w[j].z) * iz, zb = (h - w[j].z) * iz;
      const F c0 = select(rises, max(s0, min(za, zb)), s0), c1 = select(rises, min(s1, max(za, zb)), s1);
      const F sw = clamp(select(moves, -al * ib, half * (c0 + c1)), c0, c1);
      const V3<F> wb = madd(w[j], sw, e[j]);
      valid = valid & (dot(n, wb) <= lo + slack);
      if (c > 0) valid = valid & (tq[j] > zero) & (tq[j] < one);  // +-(z x e) only at the foot
      consider(o, n, wb, valid, kClassSide);
    }
  }

  // --- a vertex against a rim (the vertex beyond both the side and the cap): n from
  // the rim point nearest it ---
  for (int j = 0; j < 3; ++j) {
    const Mask off = rho2[j] > tiny;
    const F rho = sqrt(rho2[j]);
    const F ri = one / select(off, rho, one);
    const F mx = select(off, w[j].x * ri, one), my = select(off, w[j].y * ri, zero);
    for (int s = 0; s < 2; ++s) {
      const F sg(s == 0 ? 1.0f : -1.0f);
      const V3<F> r{rc * mx, rc * my, sg * h};
      F len;
      const V3<F> n =
          normalize_or(w[j] - r, V3<F>{mx * F(0.70710678f), my * F(0.70710678f), sg * F(0.70710678f)}, len);
      F lo;
      const F o = score(n, lo);
      const Mask valid = (rho >= rc - slack) & (sg * w[j].z >= h - slack) & (dot(n, w[j]) <= lo + slack);
      consider(o, n, w[j], valid, kClassRim);
    }
  }

  // --- an edge's interior against a rim: on the circle of directions perpendicular to
  // the edge, the rim's shadow (an ellipse) against the edge's shadow point ---
  {
    F rb[6], rx[6], ry[6], ex[6], ey[6];
    V3<F> wd[3], vd[3], ed[3];
    F len[3];
    const F inv_rc = one / rc;
    for (int j = 0; j < 3; ++j) {
      ed[j] = normalize_or(e[j], V3<F>{zero, zero, one}, len[j]);
      const F exy2 = ed[j].x * ed[j].x + ed[j].y * ed[j].y;
      const Mask tl = exy2 > tiny;
      const F ie = one / sqrt(select(tl, exy2, one));
      wd[j] = V3<F>{select(tl, -ed[j].y * ie, one), select(tl, ed[j].x * ie, zero), zero};
      vd[j] = cross(ed[j], wd[j]);
      vd[j] = select(vd[j].z < zero, -vd[j], vd[j]);
      const F lr = h * vd[j].z * inv_rc;  // the rims' shadows at +-lr along v (scaled)
      const F px = dot(w[j], wd[j]) * inv_rc, py = dot(w[j], vd[j]) * inv_rc;
      rb[2 * j] = rb[2 * j + 1] = abs(ed[j].z);
      rx[2 * j] = rx[2 * j + 1] = px;
      ry[2 * j] = py - lr;
      ry[2 * j + 1] = -(py + lr);
    }
    rim::half_ellipse_normals(rb, rx, ry, ex, ey);
    for (int j = 0; j < 3; ++j) {
      for (int s = 0; s < 2; ++s) {
        const F sg(s == 0 ? 1.0f : -1.0f);
        F l;
        const V3<F> n = normalize_or(madd(wd[j] * ex[2 * j + s], sg * ey[2 * j + s], vd[j]), wd[j], l);
        F lo;
        const F o = score(n, lo);
        // witness: the edge point level (along e) with the rim point along n
        V3<F> r = rim_point(n);
        r.z = sg * h;
        const F sig = dot(r - w[j], ed[j]);
        const Mask on_edge = (len[j] > zero) & (sig >= -slack) & (sig <= len[j] + slack);
        const V3<F> wb = madd(w[j], clamp(sig, zero, len[j]), ed[j]);
        const Mask valid = on_edge & (dot(n, wb) <= lo + slack);
        consider(o, n, wb, valid, kClassRim);
      }
    }
  }

  // --- the answer ---
  const Mask none_valid = best.o >= never;
  const F o = select(none_valid, any_o, best.o);
  const V3<F> n = select(none_valid, any_n, best.n);
  const F cls = select(none_valid, F(kClassRim), best.cls);
  // the triangle's witness (faces and rims: below the cylinder's rim point along n)
  const V3<F> wit = select(cls == F(kClassRim), rim_point(n) - o * n, best.b);
  const Mask hit = o > zero;
  const F nxy2 = n.x * n.x + n.y * n.y;
  const F par2(kParallelSin * kParallelSin);
  const F tol = F(1e-5f) * (rc + h + max3(elen[0], elen[1], elen[2]));
  const F facing = abs(dot(nf, n));  // the triangle not within ~0.6 degrees of edge-on to n
  const Mask flat = facing > F(0.01f);
  // the triangle's plane well defined in float (twice its area >= kSideShape times its
  // longest edge squared): else nf, and so the face clip, carries the vertices' rounding
  const F emax2 = max3(length_sq(e[0]), length_sq(e[1]), length_sq(e[2]));
  const Mask shaped = length_sq(cross(e[0], e[2])) > max(F(kSideShape * kSideShape) * emax2 * emax2, tiny);

  Lanes<F, 4> m;
  // One point: midway between the witness and the cylinder's surface point o along n.
  {
    const V3<F> p1 = madd(wit, half * o, n);
    m.count = select(hit, Int(1), Int(0));
    for (int i = 0; i < 4; ++i) m.point[i] = p1, m.pdepth[i] = o;
  }
  // Cap contact (n within kParallelSin of the axis): the triangle seen along n on the cap
  // plane z = s h, clipped to the disk: its vertices inside, its edges' crossings of the
  // rim, the rim samples inside it (a cap polygon), and the witness, each with the gap
  // along n between the cap and the triangle; reduced to 4.
  const Mask cap_like = hit & (nxy2 < par2);
  if (simd::any(cap_like)) {
    constexpr int M = 1 + 3 + 6 + kRimSamples;
    F cx[M], cy[M], cd[M];
    Mask cv[M];
    const F sg = simd::sign_nonneg(n.z);
    const F nz = select(abs(n.z) > half, n.z, one);
    F px[3], py[3], pd[3];
    for (int j = 0; j < 3; ++j) {
      const F mu = (w[j].z - sg * h) / nz;
      px[j] = w[j].x - mu * n.x, py[j] = w[j].y - mu * n.y, pd[j] = -mu;
    }
    {
      const V3<F> aw = madd(wit, o, n);
      cx[0] = aw.x, cy[0] = aw.y, cd[0] = o;
      cv[0] = aw.x * aw.x + aw.y * aw.y <= rin2;
    }
    const F rr = rc * rc;
    for (int j = 0; j < 3; ++j) {
      cx[1 + j] = px[j], cy[1 + j] = py[j], cd[1 + j] = pd[j];
      cv[1 + j] = px[j] * px[j] + py[j] * py[j] <= rr;
    }
    for (int j = 0; j < 3; ++j) {
      const int j1 = (j + 1) % 3;
      const F dx = px[j1] - px[j], dy = py[j1] - py[j], dd = pd[j1] - pd[j];
      const F qa = dx * dx + dy * dy, qb = px[j] * dx + py[j] * dy, qc = px[j] * px[j] + py[j] * py[j] - rr;
      const F disc = qb * qb - qa * qc;
      const Mask ok = (qa > tiny) & (disc >= zero);
      const F root = sqrt(max(disc, zero)), ia = one / select(ok, qa, one);
      for (int c = 0; c < 2; ++c) {
        const F t = (c == 0 ? -qb - root : root - qb) * ia;
        const int i = 4 + 2 * j + c;
        cx[i] = mul_add(t, dx, px[j]), cy[i] = mul_add(t, dy, py[j]), cd[i] = mul_add(t, dd, pd[j]);
        cv[i] = ok & (t >= zero) & (t <= one);
      }
    }
    {
      // (only for a triangle within 60 degrees of level and well shaped as seen: a sliver's
      // barycentric coordinates, and so the gap, carry its rounding / its thinness)
      const F area = (px[1] - px[0]) * (py[2] - py[0]) - (py[1] - py[0]) * (px[2] - px[0]);
      F le2 = zero;
      for (int j = 0; j < 3; ++j) {
        const int j1 = (j + 1) % 3;
        le2 = max(le2, (px[j1] - px[j]) * (px[j1] - px[j]) + (py[j1] - py[j]) * (py[j1] - py[j]));
      }
      const Mask ok = (facing >= half) & (abs(area) >= F(kShape) * le2) & (abs(area) > tiny);
      const F ia = one / select(ok, area, one);
      for (int i = 0; i < kRimSamples; ++i) {
        const F sx = rc * F(kRimCos[i]), sy = rc * F(kRimCos[(i + 6) % 8]);
        F l[3];
        for (int j = 0; j < 3; ++j) {
          const int j1 = (j + 1) % 3, j2 = (j + 2) % 3;
          l[j] = ((px[j1] - sx) * (py[j2] - sy) - (py[j1] - sy) * (px[j2] - sx)) * ia;
        }
        const int c = 10 + i;
        cx[c] = sx, cy[c] = sy;
        cd[c] = pd[0] + l[1] * (pd[1] - pd[0]) + l[2] * (pd[2] - pd[0]);
        cv[c] = ok & (l[0] >= zero) & (l[1] >= zero) & (l[2] >= zero);
      }
    }
    for (int i = 0; i < M; ++i) cv[i] = cv[i] & (cd[i] > zero);
    drop_shadowed_witness<F, M>(cd, cv, o, tol);
    F ox[4], oy[4], od[4];
    Int cnt;
    reduce4<F, M>(cx, cy, cd, cv, tol, ox, oy, od, cnt);
    const Mask use = cap_like & (cnt > Int(0));
    m.count = select(use, cnt, m.count);
    for (int i = 0; i < 4; ++i) {
      const V3<F> p = madd(V3<F>{ox[i], oy[i], sg * h}, F(-0.5f) * od[i], n);
      m.point[i] = select(use, p, m.point[i]);
      m.pdepth[i] = select(use, min(od[i], o), m.pdepth[i]);
    }
  }
  // Side contact (n within kParallelSin of the horizontal): the side's line along n
  // clipped to the triangle seen along n (a face lying on the side), the triangle's edges
  // clipped to the side's height (an edge along the side; each point's gap is where the
  // line from it along n leaves the cylinder) and the witness; reduced to 4.
  const Mask side_like = andnot(hit & (n.z * n.z < par2), cap_like);
  if (simd::any(side_like)) {
    constexpr int M = 1 + 2 + 6;
    V3<F> ca[M];
    F cd[M];
    Mask cv[M];
    const Mask okxy = nxy2 > tiny;
    const F ixy = one / sqrt(select(okxy, nxy2, one));
    const F mx = select(okxy, n.x * ixy, one), my = select(okxy, n.y * ixy, zero);
    ca[0] = madd(wit, o, n), cd[0] = o, cv[0] = Mask(true);
    {
      // S(t) = (rc m, t) - lam(t) n on the triangle's plane, lam = lam0 + lam1 t
      const V3<F> s0{rc * mx, rc * my, zero};
      const F nn = dot(nf, n);
      const F inn = one / select(flat, nn, one);
      const F lam0 = dot(nf, s0 - w[0]) * inn, lam1 = nf.z * inn;
      F tlo = -h, thi = h;
      Mask ok = flat & shaped;
      for (int j = 0; j < 3; ++j) {
        const F en_n = dot(en[j], n);
        const F g0 = dot(en[j], s0 - w[j]) - lam0 * en_n, g1 = en[j].z - lam1 * en_n;
        const Mask pos = g1 > zero, neg = g1 < zero;
        const F tb = -g0 / select(pos | neg, g1, one);  // g0 + g1 t >= 0
        tlo = select(pos, max(tlo, tb), tlo);
        thi = select(neg, min(thi, tb), thi);
        ok = ok & ((pos | neg) | (g0 >= zero));
      }
      ok = ok & (tlo <= thi);
      for (int c = 0; c < 2; ++c) {
        const F t = c == 0 ? tlo : thi;
        ca[1 + c] = V3<F>{s0.x, s0.y, t};
        cd[1 + c] = mul_add(lam1, t, lam0);
        cv[1 + c] = ok;
      }
    }
    for (int j = 0; j < 3; ++j) {
      const Mask rises = abs(e[j].z) > tiny;
      const F iz = one / select(rises, e[j].z, one);
      const F za = (-h - w[j].z) * iz, zb = (h - w[j].z) * iz;
      const F s0 = select(rises, max(min(za, zb), zero), zero);
      const F s1 = select(rises, min(max(za, zb), one), select(abs(w[j].z) <= h, one, F(-1.0f)));
      for (int c = 0; c < 2; ++c) {
        // (an end clipped to a cap plane may round past it: held to the plane)
        V3<F> bq = madd(w[j], c == 0 ? s0 : s1, e[j]);
        const Mask within = abs(bq.z) <= h + slack;
        bq.z = clamp(bq.z, -h, h);
        const F bb = bq.x * n.x + bq.y * n.y, cc = bq.x * bq.x + bq.y * bq.y - rc * rc;
        const F d_side = (sqrt(max(bb * bb - nxy2 * cc, zero)) - bb) / select(okxy, nxy2, one);
        const Mask up = abs(n.z) > tiny;
        const F d_cap = select(up, (simd::sign_nonneg(n.z) * h - bq.z) / select(up, n.z, one), F(3.0e38f));
        // (the cap only where it cuts the line short by more than slack along z: an end on
        // a cap plane with n level to rounding keeps its side depth)
        const F d = select(abs(n.z) * (d_side - d_cap) > slack, min(d_side, d_cap), d_side);
        const int i = 3 + 2 * j + c;
        ca[i] = madd(bq, d, n), cd[i] = d;
        cv[i] = (s0 <= s1) & (cc <= zero) & within;
      }
    }
    side_manifold_tail<F, M, true>(ca, cd, cv, o, tol, mx, my, n, side_like, m);
  }

  m.count = select(hit, m.count, Int(0));
  m.n = rot.apply(n);
  m.depth = o;
  for (int i = 0; i < 4; ++i) m.point[i] = rot.apply(m.point[i]);
  store(out, k, m, pa);
}

}  // namespace

void collide_cylinder_triangle(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, Range r,
                               const NarrowConfig& cfg) {
  IMPACT_LANE_KERNEL_BODY(cylinder_triangle_block, 4);
}

}  // namespace impact::kernels
