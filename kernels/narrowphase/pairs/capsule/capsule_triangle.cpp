// Capsule (A) against triangle (B, two-sided, zero thickness): collision data of 1 or 2
// points per pair, vectorised across pairs (one lane = one pair).
// Method: two-sided triangle. Core outside: closest points of segment and triangle
// (endpoints vs triangle, segment vs edges); the normal is the face normal when an end
// point over the face's interior wins, and axis x edge when the segment's and an edge's
// interiors do (the points' difference has only rounding / gap precision); a segment
// parallel to the face gives 2 points clipped to the triangle's prism. Core crossing the
// triangle, or within the inputs' rounding of it: SAT over the face normal and the 3 axis
// x edge directions.
//
// Inputs: LeafSoA lanes per leaf.h (A a capsule: p, R column 2 = axis, e0 = radius, e1 =
// half length). Outputs: ManifoldSoA lanes of the Range, point slots 0 and 1
// (capsule_lanes.h finish). All arithmetic is relative to A's centre.
// Preconditions: finite inputs, positive radius, half lengths >= 0, unit axes, non-
// degenerate triangles for a meaningful face normal (degenerate ones still give finite
// output).
// Cost: ~600 flops per pair, no branches on lane data except skipping work no lane of a
// block needs; both paths (kScalar, kSimd) run the same template.
#include <cstdint>

#include "kernels/narrowphase/pair_kernels.h"
#include "kernels/narrowphase/lanes/block_driver.h"
#include "kernels/narrowphase/lanes/lane_geometry.h"
#include "kernels/narrowphase/lanes/lane_io.h"
#include "kernels/narrowphase/pairs/capsule/capsule_lanes.h"

namespace impact::kernels {
namespace {

using namespace prim;           // NOLINT: lane helpers of this kernel family
using namespace capsule_lanes;  // NOLINT: tolerances and the two-point result
using simd::cross;
using simd::dot;
using simd::length_sq;

template <class F>
IMPACT_INLINE void capsule_triangle_block(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out,
                                          uint32_t k) {
  using Mask = typename F::Mask;
  const V3<F> pa = load_p<F>(a, k);
  const V3<F> u = load_axis_z<F>(a, k);
  const F ra = ld<F>(a.e[0], k), ha = ld<F>(a.e[1], k);
  const V3<F> v[3] = {load_p<F>(b, k) - pa, load_w<F>(b, k, 0) - pa, load_w<F>(b, k, 3) - pa};
  const F zero(0.0f), one(1.0f), half(0.5f);
  const V3<F> c{zero, zero, zero};
  const V3<F> nf = triangle_normal(v[0], v[1], v[2]);

  // --- closest points of the core segment and the triangle ---
  // Also which feature pair won, so that a short gap takes its normal from the
  // features rather than from the difference of two nearly equal points: an end point
  // over the face's interior -> the face normal; a segment interior against an edge
  // interior -> their common perpendicular u x edge.
  // `winner` names the winner for its normal cone (0, 1: an end point; 2 + i: edge i).
  TriangleRegion<F> reg0, reg1;
  const auto face_of = [](const TriangleRegion<F>& g) IMPACT_LAMBDA_INLINE {
    return ~(g.in_a | g.in_b | g.in_ab | g.in_c | g.in_ac | g.in_bc);
  };
  const V3<F> e0 = u * (-ha), e1 = u * ha;
  V3<F> bp = e0, bq = closest_on_triangle(v[0], v[1], v[2], e0, nf, reg0);
  const Mask face0 = face_of(reg0);
  F bd = length_sq(bq - bp);
  Mask by_face = face0, by_edge = Mask(false);
  V3<F> edge_axis = nf;
  F winner = zero;
  auto consider = [&](const V3<F>& p, const V3<F>& q, Mask is_face, Mask is_edge, const V3<F>& axis, float id) {
    const F d = length_sq(q - p);
    const Mask take = d < bd;
    bd = select(take, d, bd);
    bp = select(take, p, bp);
    bq = select(take, q, bq);
    by_face = select(take, is_face, by_face);
    by_edge = select(take, is_edge, by_edge);
    edge_axis = select(take, axis, edge_axis);
    winner = select(take, F(id), winner);
  };
  const V3<F> q1 = closest_on_triangle(v[0], v[1], v[2], e1, nf, reg1);
  consider(e1, q1, face_of(reg1), Mask(false), nf, 1.0f);
  V3<F> ed[3], em[3];
  F eh[3], es[3], et[3];
  for (int i = 0; i < 3; ++i) {
    const V3<F> d = v[(i + 1) % 3] - v[i];
    F len;
    ed[i] = normalize_or(d, V3<F>{one, zero, zero}, len);
    eh[i] = half * len;
    em[i] = (v[i] + v[(i + 1) % 3]) * half;
    F s, t;
    closest_segment_segment(c, u, ha, em[i], ed[i], eh[i], s, t);
    es[i] = s;
    et[i] = t;
    const V3<F> l = cross(u, ed[i]);
    const F l2 = length_sq(l);
    const Mask interior = (abs(s) < ha) & (abs(t) < eh[i]) & (l2 > F(1e-10f));
    consider(u * s, madd(em[i], t, ed[i]), Mask(false), interior, l * (one / sqrt(select(interior, l2, one))),
             static_cast<float>(2 + i));
  }
  // segment crossing the triangle's interior
  const F hc = -dot(nf, v[0]);  // height of the centre above the plane
  const F hu = dot(nf, u);
  const F h0 = hc - hu * ha, h1 = hc + hu * ha;
  const Mask crosses_plane = ((h0 <= zero) & (h1 >= zero)) | ((h0 >= zero) & (h1 <= zero));
  const F tc = clamp(-hc / select(abs(hu) > F(1e-30f), hu, one), -ha, ha);
  const V3<F> xc = u * tc;
  Mask inside = crosses_plane;
  for (int i = 0; i < 3; ++i)
    inside = inside & (dot(cross(v[(i + 1) % 3] - v[i], xc - v[i]), nf) >= zero);
  bp = select(inside, xc, bp);
  bq = select(inside, xc, bq);
  bd = select(inside, zero, bd);

  // A gap within the rounding of the inputs has no reliable direction, not even its
  // sign: such lanes take the SAT below, as capsule-box does.
  const F size = ra + ha + eh[0] + eh[1] + eh[2];
  const F edge_round = F(kEdgeRound) * (size + abs(v[0].x) + abs(v[0].y) + abs(v[0].z));
  const Mask shallow = (bd >= F(kTinySq)) & (bd > edge_round * edge_round);
  const F dist = sqrt(bd);
  const V3<F> gap = bq - bp;
  V3<F> n_sh = gap * (one / select(shallow, dist, one));
  // Within kConeReach of the size, the gap goes back into the winner's normal cone: the
  // core's constraint at its parameter, and the edge segment's (segment pairs) or the
  // triangle region's (an end point against the triangle, then the end's own): rounding
  // of a core end on an edge or a vertex otherwise tilts it along the core or the edge,
  // each adding its length times the tilt to the overlap.
  const Mask near = shallow & (dist < F(kConeReach) * (size + abs(v[0].x) + abs(v[0].y) + abs(v[0].z)));
  if (any(near)) {
    const F slack = F(kNormalConeSlack) * dist;
    const Mask seg = winner >= F(1.5f), end1 = winner == one;
    V3<F> bed = ed[0];
    F bs = select(end1, ha, -ha), bt = et[0], beh = eh[0];
    for (int i = 0; i < 3; ++i) {
      const Mask w = winner == F(static_cast<float>(2 + i));
      bed = select(w, ed[i], bed);
      bs = select(w, es[i], bs);
      bt = select(w, et[i], bt);
      beh = select(w, eh[i], beh);
    }
    const HalfCone<F> core = segment_half_cone(u, bs, ha, true);
    V3<F> lb = cross(u, bed);
    lb = madd(lb, -dot(lb, u), u);
    lb = madd(lb, -dot(lb, bed), bed);
    F ll;
    const V3<F> lseg = normalize_or(lb, any_perpendicular(u), ll);
    const V3<F> g_seg = project_to_cone(gap, core, segment_half_cone(bed, bt, beh, false), lseg, slack);
    TriangleRegion<F> breg;
    breg.in_a = select(end1, reg1.in_a, reg0.in_a);
    breg.in_b = select(end1, reg1.in_b, reg0.in_b);
    breg.in_c = select(end1, reg1.in_c, reg0.in_c);
    breg.in_ab = select(end1, reg1.in_ab, reg0.in_ab);
    breg.in_ac = select(end1, reg1.in_ac, reg0.in_ac);
    breg.in_bc = select(end1, reg1.in_bc, reg0.in_bc);
    HalfCone<F> ta, tb;
    triangle_half_cones(v[0], v[1], v[2], nf, breg, ta, tb);
    const V3<F> g_tri = into_segment_cone(-project_to_cone(-gap, ta, tb, nf, slack), u, bs, ha);
    F gl;
    n_sh = select(near, normalize_or(select(seg, g_seg, g_tri), n_sh, gl), n_sh);
  }
  const V3<F> feature_axis = select(by_face, nf, edge_axis);
  const V3<F> n_feat = select(dot(feature_axis, gap) >= zero, feature_axis, -feature_axis);
  n_sh = select(by_face | by_edge, n_feat, n_sh);

  // --- core crossing: SAT over the face normal and 3 axis x edge directions ---
  // overlap along unit l: capsule [l.c - ha|u.l| - r, + ...] vs triangle [min l.v, max l.v]
  F best(3.0e38f);
  V3<F> n_dp = nf;
  Mask edge_win = Mask(false);
  F edge_which(0.0f);
  F lim_face(0.0f);  // set after the face axis: an edge axis must be below it
  auto axis = [&](const V3<F>& l, Mask ok, bool is_edge, float which, F round) {
    const F t0 = dot(l, v[0]), t1 = dot(l, v[1]), t2 = dot(l, v[2]);
    const F tmin = min(t0, min(t1, t2)), tmax = max(t0, max(t1, t2));
    const F ext = ha * abs(dot(l, u)) + ra;
    const F o_pos = ext - tmin;  // move the triangle along +l
    const F o_neg = tmax + ext;  // move the triangle along -l
    const Mask pos = o_pos <= o_neg;
    const F o = min(o_pos, o_neg);
    const Mask take = is_edge ? ok & (o < best) & (o < lim_face - round) : ok;
    best = select(take, o, best);
    n_dp = select(take, select(pos, l, -l), n_dp);
    if (is_edge) {
      edge_win = select(take, Mask(true), edge_win);
      edge_which = select(take, F(which), edge_which);
    }
  };
  axis(nf, Mask(true), false, 0.0f, zero);
  lim_face = best - mul_add(F(kTieRel), abs(best), F(kTieSize) * size);
  for (int i = 0; i < 3; ++i) {
    const V3<F> l = cross(u, ed[i]);
    const F l2 = length_sq(l);
    const Mask ok = l2 > F(1e-10f);
    const F inv = one / sqrt(select(ok, l2, one));
    axis(l * inv, ok, true, static_cast<float>(i), edge_round * inv);
  }
  const V3<F> n = select(shallow, n_sh, n_dp);
  const F depth = select(shallow, ra - dist, best);

  // --- face manifold: clip the core to the triangle's prism ---
  const F nn = dot(n, nf);
  const Mask face_normal = abs(nn) > F(0.99999f);
  // Clip where the face points below meet the triangle's plane, not the core: core
  // point u t moved along n to the plane, a line in t. So those points stay inside the
  // triangle even when n leans a little off the face normal.
  const F nns = select(abs(nn) > F(0.5f), nn, one);
  const V3<F> cs = madd(c, dot(nf, v[0] - c) / nns, n);
  const V3<F> us = madd(u, -dot(nf, u) / nns, n);
  F lo = -ha, hi = ha;
  for (int i = 0; i < 3; ++i) {
    // inward edge normal m: m.(x - v_i) >= 0 inside
    const V3<F> mi = cross(nf, ed[i]);
    const F a0 = dot(mi, cs - v[i]);  // at t = 0
    const F a1 = dot(mi, us);        // per unit t
    const Mask flat = abs(a1) < F(1e-20f);
    const F tcut = -a0 / select(flat, one, a1);
    lo = select(flat, select(a0 >= zero, lo, F(1e30f)), select(a1 > zero, max(lo, tcut), lo));
    hi = select(flat, select(a0 >= zero, hi, F(-1e30f)), select(a1 < zero, min(hi, tcut), hi));
  }
  const F snu = dot(n, u);
  auto face_point = [&](F t, V3<F>& p, F& d) {
    // the capsule's surface along n from core point u*t, then along -n to the plane
    const V3<F> on_a = madd(u * t, capsule_exit(t, snu, ra, ha), n);
    d = dot(nf, on_a - v[0]) / select(abs(nn) > F(0.5f), nn, one);
    p = madd(on_a, -half * d, n);
  };
  V3<F> p0, p1;
  F d0, d1;
  face_point(lo, p0, d0);
  face_point(hi, p1, d1);
  const Mask clip_ok = hi - lo > F(1e-4f) * ha;
  const Mask parallel_enough = abs(hu) < F(kParallelSin);
  const Mask two = andnot(
      face_normal & clip_ok & (d0 > zero) & (d1 > zero) & (parallel_enough | ~shallow) & (depth > zero),
      andnot(edge_win, shallow));
  // single point
  V3<F> pf = (bp + bq + n * ra) * half;
  F df = depth;
  {
    // deep, face axis: the deeper clipped end (inside the prism)
    const Mask deep_face = andnot(face_normal & clip_ok, shallow | edge_win);
    const Mask first = d0 >= d1;
    pf = select(deep_face, select(first, p0, p1), pf);
    df = select(deep_face, select(first, d0, d1), df);
    // deep, edge axis: the core against that edge
    const Mask deep_edge = andnot(edge_win, shallow);
    const Mask w0 = edge_which == zero, w1 = edge_which == one;
    const V3<F> emid = select(w0, em[0], select(w1, em[1], em[2]));
    const V3<F> edir = select(w0, ed[0], select(w1, ed[1], ed[2]));
    const F ehl = select(w0, eh[0], select(w1, eh[1], eh[2]));
    F s, t;
    closest_segment_segment(c, u, ha, emid, edir, ehl, s, t);
    const V3<F> xs = u * s;
    pf = select(deep_edge, madd(xs, ra - half * depth, n), pf);
    // deep, face axis, nothing inside the prism: the crossing point
    const Mask deep_none = andnot(~shallow, edge_win | clip_ok);
    pf = select(deep_none, madd(bp, ra - half * depth, n), pf);
  }
  L2<F> m;
  finish(m, n, depth, two, p0, d0, p1, d1, pf, df);
  store(out, k, m, pa);
}

}  // namespace

void collide_capsule_triangle(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, Range r,
                              const NarrowConfig& cfg) {
  IMPACT_LANE_KERNEL_BODY(capsule_triangle_block, 2);
}

}  // namespace impact::kernels
