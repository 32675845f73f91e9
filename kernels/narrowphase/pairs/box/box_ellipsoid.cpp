// Box (A) against ellipsoid (B): exact collision data by the local minima of the support
// overlap, vectorised across pairs (one lane = one pair), no GJK / EPA.
//
// Inputs: LeafSoA lanes per leaf.h (A a box: p, R, half extents e0, e1, e2 along R's
// columns; B an ellipsoid: p, R, radii e0, e1, e2 along R's columns), Range r.
// Outputs: ManifoldSoA lanes r.begin .. r.end: count (0 or 1), n (unit, A to B), depth,
// point[0] midway between the two surfaces (the ellipsoid's point touching along n, moved
// by depth / 2 along n: a face against a curved surface touches at a point), pdepth[0] =
// depth. Slots 1..3 untouched; count-0 lanes leave the other fields unspecified.
// Method, in the ellipsoid's frame scaled by its largest radius (radii a_i in (0, 1]; the
// box's centre c relative to the ellipsoid's, its unit axes b_i and half extents h_i):
// with m a direction from the ellipsoid towards the box,
//     G(m) = h_E(m) - min over the box of m.x,   h_E(m) = |diag(a) m|,
// is the support overlap along m; depth = min over unit m of G, n = -argmin (inside: the
// penetration depth; outside: minus the distance). The sphere of directions splits into
// the pieces of the Minkowski difference: the open cones where one box vertex is the
// box's lowest point along m (G = the distance from the vertex to the ellipsoid's surface,
// m its outward normal there), the open quarter circles perpendicular to an edge between
// its two faces' normals (G: the same in 2-D, on the ellipsoid's shadow across the edge,
// an ellipse), and the six face normals. The minimiser is a face normal or a local
// minimum of its piece's function: a vertex's nearest point or far local minimum on the
// ellipsoid, an edge's on the shadow (at most two each: ellipsoid_solve.h). So the
// candidates are the 3 face normals (the smaller-overlap sign of each axis), 8 x 2
// vertex and 12 x 2 edge candidates; each is scored by G itself (every direction's G is
// >= the minimum, so a candidate that is not a minimum never wins wrongly), a vertex's or
// edge's only on its own piece (within 1e-5 rad: ellipsoid_pieces.h), and the least wins
// (ties: faces in axis order, then vertices' and edges' nearest points, then far minima,
// pieces in index order).
// Pruning (exact: it drops only candidates that cannot count or cannot win):
//  1. A lane whose bounding spheres are apart or that a face axis separates (least face
//     overlap <= 0) has no contact: a first pass writes count 0 for those (half the
//     bench's lanes) and the others are gathered into full blocks for the rest.
//  2. An outside point's nearest-point candidate counts only if the ellipsoid's nearest
//     point lies in the feature's Voronoi region, so the ellipsoid must reach past the
//     feature's face planes (|A b_i| - sigma_i c.b_i - h_i >= 0); an inside point's
//     candidates score at least its distance to the surface, >= (1 - sqrt(level)) a_min,
//     and a far minimum at least the point's distance to the smallest axis's plane: no
//     win when that is not below the best so far.
//  3. The solution curve test (ellipsoid_pieces.h): a candidate lies on m(s) =
//     (s + d_i)^-1 y_i for s in a certified bracket of its root; if a face constraint of
//     the piece is violated along the whole curve (a sign test of a quadratic in s), the
//     piece is dropped. On the bench ~0.9 pieces per remaining lane survive.
//  4. The survivors' nearest points are solved packed, kSimdWidth (piece, lane) slots to
//     a solve; far minima (score > 0) only for lanes still above 0 afterwards, packed.
// Degenerate input: zero half extents (a rectangle, a segment, a point) have coincident
// vertices and their pieces still cover the sphere; a round ellipsoid has equal radii
// (the solver's ties); components of inside points below 1e-6 e_max are solved as 0
// (depth error <= 1e-6 e_max) and never pruned by the curve test.
// Preconditions: finite inputs, positive radii, half extents >= 0, orthonormal R
// (host-validated); no division without a guard, so finite inputs give finite outputs.
// Cost: see docs/narrowphase.md (measured per pair).
// Both paths run the same template (F = FloatW, or Float1 for the scalar reference).
#include <cstdint>

#include "kernels/narrowphase/solvers/ellipsoid_pieces.h"
#include "kernels/narrowphase/pair_kernels.h"
#include "kernels/narrowphase/lanes/lane_geometry.h"
#include "kernels/narrowphase/lanes/lane_io.h"
#include "kernels/narrowphase/lanes/live_lanes.h"

namespace impact::kernels {
namespace {

using namespace prim;  // NOLINT: lane helpers of this kernel family
using simd::dot;
using simd::length_sq;

/// Pieces: vertices 0..7 (bit i of the index: sigma_i = +1), then edges 8 + 4 k + j
/// along box axis k, j's bit 0 / 1 the signs along the other two axes (ascending).
constexpr int kPieces = 20;
constexpr int kVertexPieces = 8;

IMPACT_INLINE void edge_axes(int k, int& a0, int& a1) {
  a0 = k == 0 ? 1 : 0;
  a1 = k == 2 ? 1 : 2;
}

template <class F>
struct Best {
  F value;
  V3<F> m;
  F len;
};

/// One block of lanes in the ellipsoid's frame scaled by its largest radius: the box's
/// centre c, axes bx and half extents h, the radii av; rotation and position of the
/// ellipsoid for the output.
template <class F>
struct Frame {
  V3<F> pe;
  M3<F> re;
  F emax;
  F av[3];
  V3<F> c;
  V3<F> bx[3];
  F h[3];
};

template <class F>
IMPACT_INLINE Frame<F> make_frame(const V3<F>& pb, const M3<F>& rb, const V3<F>& eb, const V3<F>& pe,
                                  const M3<F>& re, const V3<F>& e) {
  Frame<F> f;
  f.pe = pe;
  f.re = re;
  f.emax = max(max(e.x, e.y), e.z);
  const F inv = F(1.0f) / f.emax;
  f.av[0] = e.x * inv, f.av[1] = e.y * inv, f.av[2] = e.z * inv;
  f.c = re.apply_t(pb - pe) * inv;
  for (int i = 0; i < 3; ++i) f.bx[i] = re.apply_t(rb.c[i]);
  f.h[0] = eb.x * inv, f.h[1] = eb.y * inv, f.h[2] = eb.z * inv;
  return f;
}

/// G(m) = h_E(m) - min over the box of m.x (m from the ellipsoid towards the box,
/// unnormalised), kept where valid and below the best so far.
template <class F>
IMPACT_INLINE void consider(const Frame<F>& f, Best<F>& best, const V3<F>& m, typename F::Mask valid) {
  const F one(1.0f);
  const F l2 = length_sq(m);
  const auto ok = valid & (l2 >= F(kTinySq));
  const F len = sqrt(select(ok, l2, one));
  const F ax = f.av[0] * m.x, ay = f.av[1] * m.y, az = f.av[2] * m.z;
  const F he = sqrt(ax * ax + ay * ay + az * az);
  const F lowest = dot(m, f.c) - f.h[0] * abs(dot(m, f.bx[0])) - f.h[1] * abs(dot(m, f.bx[1])) -
                   f.h[2] * abs(dot(m, f.bx[2]));
  const F value = (he - lowest) / len;
  const auto take = ok & (value < best.value);
  best.value = select(take, value, best.value);
  best.m = select(take, m, best.m);
  best.len = select(take, len, best.len);
}

/// The face candidates: m = +-b_i, the sign of c.b_i (the smaller of the two).
template <class F>
IMPACT_INLINE Best<F> face_best(const Frame<F>& f) {
  const F zero(0.0f), one(1.0f);
  Best<F> best{F(3.0e38f), V3<F>{zero, zero, one}, one};
  for (int i = 0; i < 3; ++i) {
    consider(f, best, select(dot(f.c, f.bx[i]) >= zero, f.bx[i], -f.bx[i]), typename F::Mask(true));
  }
  return best;
}

/// Lanes that may touch: the bounding spheres meet and no face axis separates.
template <class F>
IMPACT_INLINE typename F::Mask may_touch(const Frame<F>& f, const Best<F>& faces) {
  const F reach = F(1.0f) + sqrt(f.h[0] * f.h[0] + f.h[1] * f.h[1] + f.h[2] * f.h[2]);
  return (length_sq(f.c) < reach * reach) & (faces.value > F(0.0f));
}

/// The vertex and edge pieces of lanes that may touch (every lane of the block).
template <class F>
IMPACT_INLINE void pieces(const Frame<F>& fr, Best<F>& best) {
  using Mask = typename F::Mask;
  constexpr uint32_t W = F::kWidth;
  const F zero(0.0f), one(1.0f), big(3.0e38f);
  const F(&av)[3] = fr.av;
  const F(&h)[3] = fr.h;
  const V3<F>& c = fr.c;
  const V3<F>(&bx)[3] = fr.bx;
  V3<F> hb[3];
  for (int i = 0; i < 3; ++i) hb[i] = bx[i] * h[i];

  // Piece signs: sigma[p][i] in {-1, 0, +1} (0: the edge's own axis).
  auto sigma = [](int p, int i) -> float {
    if (p < kVertexPieces) return (p >> i) & 1 ? 1.0f : -1.0f;
    const int kk = (p - kVertexPieces) / 4, j = (p - kVertexPieces) % 4;
    int a0, a1;
    edge_axes(kk, a0, a1);
    if (i == a0) return j & 1 ? 1.0f : -1.0f;
    if (i == a1) return j & 2 ? 1.0f : -1.0f;
    return 0.0f;
  };
  // The feature is the box's lowest along m: sigma_i m.b_i <= 0 (within kPieceTol).
  auto on_piece = [&](int p, const V3<F>& m) {
    const F m2 = length_sq(m);
    const F tol2(ellip::kPieceTol * ellip::kPieceTol);
    Mask on(true);
    for (int i = 0; i < 3; ++i) {
      const float s = sigma(p, i);
      if (s == 0.0f) continue;
      const F x = dot(m, bx[i]) * F(s);
      on = on & ((x <= zero) | (x * x <= tol2 * m2));
    }
    return on;
  };

  ellip::PieceBatch<W, kPieces, 4> batch;
  for (int i = 0; i < 3; ++i) av[i].store(batch.rad[0][i]);
  uint32_t want_far[kPieces];
  F far_level[kPieces];  // level of inside points (2 outside), for the far minima's bound

  // Cheap filters first. An outside point's nearest-point candidate on its piece has
  // the ellipsoid's nearest point in the feature's Voronoi region (beyond each of its
  // face planes): the ellipsoid must reach past those planes, reach_i = |A b_i| -
  // sigma_i c.b_i - h_i >= 0 (minus the pieces' tolerance). An inside point's candidates
  // score at least its distance to the surface, >= (1 - sqrt(level)) a_min (the
  // ellipsoid holds the ball of radius a_min about its centre, scaled by 1 - sqrt(level)
  // about the point): if that is not below the best so far, they cannot win; i.e.
  // they can where level > (1 - best / a_min)^2 (or best >= a_min). Points in a band
  // 1e-4 around the surface count as inside. The curve tests (ellipsoid_pieces.h) run
  // only where a lane passed these.
  F reach[3][2];  // [axis][sigma > 0]
  for (int i = 0; i < 3; ++i) {
    const F ha = sqrt(length_sq(V3<F>{av[0] * bx[i].x, av[1] * bx[i].y, av[2] * bx[i].z}));
    const F cb = dot(c, bx[i]);
    reach[i][1] = ha - cb - h[i];
    reach[i][0] = ha + cb - h[i];
  }
  const F reach_tol = -F(ellip::kPruneMargin) * (sqrt(length_sq(c)) + h[0] + h[1] + h[2] + F(2.0f));
  const F band(1.0f + ellip::kPruneMargin);

  // Vertices: the nearest point and the far minimum of the distance from the vertex.
  const ellip::Radii3<F> r3 = ellip::radii3(av);
  const ellip::FarAxes3<F> fx = ellip::far_axes3(av);
  const F vfloor = ellip::level_floor(best.value, r3.am);
  for (int p = 0; p < kVertexPieces; ++p) {
    V3<F> w = c;
    Mask reach_ok(true);
    for (int i = 0; i < 3; ++i) {
      w = (p >> i) & 1 ? w + hb[i] : w - hb[i];
      reach_ok = reach_ok & (reach[i][(p >> i) & 1] >= reach_tol);
    }
    const F y[3] = {w.x, w.y, w.z};
    Mask keep;
    const F level = ellip::level_of(r3.inv, y, keep);
    const Mask inside = level < band;
    const Mask can = ~inside | (level > vfloor);
    Mask near_want = select(inside, can, reach_ok);
    // The far minimum lies across the smallest axis's plane: it scores at least |y_m|.
    const F ym = abs(select(fx.is_m[0], y[0], select(fx.is_m[1], y[1], y[2])));
    Mask far_want = can & (ym < best.value);
    if (simd::any(andnot(near_want, keep))) {
      F lo, hi;
      ellip::near_bracket(r3.a, r3.d, r3.am2, r3.dmax, y, level, lo, hi);
      Mask off(false);
      for (int i = 0; i < 3; ++i) off = off | ellip::near_off3(bx[i] * F(sigma(p, i)), y, r3, lo, hi);
      near_want = andnot(near_want, andnot(off, keep));
    }
    if (simd::any(andnot(far_want, keep))) {
      const ellip::FarBracket3<F> fb = ellip::far_bracket3(av, fx, y);
      Mask off = ~fb.exists;
      if (simd::any(andnot(far_want, keep | off))) {
        for (int i = 0; i < 3; ++i) off = off | ellip::far_off3(bx[i] * F(sigma(p, i)), y, r3, fx, fb);
      }
      far_want = andnot(far_want, andnot(off, keep));
    }
    batch.set[p] = 0;
    for (int i = 0; i < 3; ++i) y[i].store(batch.pt[p][i]);
    batch.want[p] = simd::bits(near_want);
    want_far[p] = simd::bits(far_want);
    far_level[p] = select(inside, level, F(2.0f));
  }

  // Edges: the same on the ellipsoid's shadow across each box axis.
  ellip::Shadow<F> sh[3];
  for (int kk = 0; kk < 3; ++kk) {
    sh[kk] = ellip::shadow(av, bx[kk]);
    const F sa[3] = {sh[kk].ax[0], sh[kk].ax[1], sh[kk].ax[0]};
    for (int i = 0; i < 3; ++i) sa[i].store(batch.rad[1 + kk][i]);
    const ellip::Radii2<F> r2 = ellip::radii2(sh[kk]);
    const F efloor = ellip::level_floor(best.value, sh[kk].ax[1]);
    int a0, a1;
    edge_axes(kk, a0, a1);
    const F u0[2] = {dot(bx[a0], sh[kk].e1), dot(bx[a0], sh[kk].e2)};
    const F u1[2] = {dot(bx[a1], sh[kk].e1), dot(bx[a1], sh[kk].e2)};
    // The edge's point in the shadow's coordinates, c +- h_a0 b_a0 +- h_a1 b_a1.
    const F yc[2] = {dot(sh[kk].e1, c), dot(sh[kk].e2, c)};
    const F y0[2] = {u0[0] * h[a0], u0[1] * h[a0]}, y1[2] = {u1[0] * h[a1], u1[1] * h[a1]};
    for (int j = 0; j < 4; ++j) {
      const int p = kVertexPieces + 4 * kk + j;
      const int b0 = j & 1, b1 = (j >> 1) & 1;
      const float s0 = b0 ? 1.0f : -1.0f, s1 = b1 ? 1.0f : -1.0f;
      const F y[2] = {yc[0] + F(s0) * y0[0] + F(s1) * y1[0], yc[1] + F(s0) * y0[1] + F(s1) * y1[1]};
      Mask keep;
      const F level = ellip::level_of(r2.inv, y, keep);
      const Mask inside = level < band;
      const Mask can = ~inside | (level > efloor);
      const Mask reach_ok = (reach[a0][b0] >= reach_tol) & (reach[a1][b1] >= reach_tol);
      Mask near_want = select(inside, can, reach_ok);
      Mask far_want = can & (abs(y[1]) < best.value);
      const F v0[2] = {u0[0] * F(s0), u0[1] * F(s0)}, v1[2] = {u1[0] * F(s1), u1[1] * F(s1)};
      if (simd::any(andnot(near_want, keep))) {
        F lo, hi;
        ellip::near_bracket(r2.a, r2.d, r2.am2, r2.dmax, y, level, lo, hi);
        const Mask off = ellip::near_off2(v0, y, r2, lo, hi) | ellip::near_off2(v1, y, r2, lo, hi);
        near_want = andnot(near_want, andnot(off, keep));
      }
      if (simd::any(andnot(far_want, keep))) {
        const ellip::FarBracket2<F> fb = ellip::far_bracket2(r2, y);
        Mask off = ~fb.exists;
        if (simd::any(andnot(far_want, keep | off))) {
          off = off | ellip::far_off2(v0, y, r2, fb) | ellip::far_off2(v1, y, r2, fb);
        }
        far_want = andnot(far_want, andnot(off, keep));
      }
      batch.set[p] = static_cast<uint8_t>(1 + kk);
      y[0].store(batch.pt[p][0]);
      y[1].store(batch.pt[p][1]);
      zero.store(batch.pt[p][2]);
      batch.want[p] = simd::bits(near_want);
      want_far[p] = simd::bits(far_want);
      far_level[p] = select(inside, level, F(2.0f));
    }
  }

  auto lift = [&](int p) {
    const V3<F> r{F::load(batch.res[p][0]), F::load(batch.res[p][1]), F::load(batch.res[p][2])};
    if (p < kVertexPieces) return r;
    const int kk = (p - kVertexPieces) / 4;
    return sh[kk].e1 * r.x + sh[kk].e2 * r.y;
  };
  auto lane_mask = [](uint32_t bits) {
    float f[W];
    for (uint32_t l = 0; l < W; ++l) f[l] = (bits >> l) & 1u ? 1.0f : 0.0f;
    return F::load(f) > F(0.0f);
  };

  ellip::solve_near_packed<F>(batch);

  for (int p = 0; p < kPieces; ++p) {
    if (batch.want[p] == 0) continue;
    const V3<F> m = lift(p);
    consider(fr, best, m, lane_mask(batch.want[p]) & on_piece(p, m));
  }

  // Far minima score > 0: only lanes still above 0 need them, and only pieces whose
  // bound is below the best so far.
  const Mask meets = best.value > zero;
  const uint32_t meets_bits = simd::bits(meets);
  if (meets_bits != 0) {
    bool any = false;
    for (int p = 0; p < kPieces; ++p) {
      const F am = p < kVertexPieces ? r3.am : sh[(p - kVertexPieces) / 4].ax[1];
      batch.want[p] =
          want_far[p] & meets_bits & simd::bits(far_level[p] > ellip::level_floor(best.value, am));
      any = any || batch.want[p] != 0;
    }
    if (any) {
      ellip::solve_far_packed<F>(batch);

      for (int p = 0; p < kPieces; ++p) {
        if (batch.want[p] == 0) continue;
        const V3<F> m = lift(p);
        const Mask ok = lane_mask(batch.want[p]) & (F::load(batch.ok[p]) > zero);
        consider(fr, best, m, ok & on_piece(p, m));
      }
    }
  }
}

/// Hands the group's collision data to o (the live driver writes it out).
template <class F>
IMPACT_INLINE void finish(const Frame<F>& fr, const Best<F>& best, LiveOut<F, 1>& o) {
  const F zero(0.0f), one(1.0f);
  // n from A to B: minus m; B's surface point: its support along m (towards the box).
  const V3<F> ml = best.m * (one / best.len);
  const V3<F> nw = -fr.re.apply(ml);
  const F depth = best.value * fr.emax;
  const V3<F> am{fr.av[0] * ml.x, fr.av[1] * ml.y, fr.av[2] * ml.z};
  const F he = sqrt(length_sq(am));
  const F s = fr.emax / select(he > zero, he, one);
  const V3<F> xb{fr.av[0] * am.x * s, fr.av[1] * am.y * s, fr.av[2] * am.z * s};
  Lanes<F, 1> m;
  m.count = simd::to_int(depth > zero);
  m.n = nw;
  m.depth = depth;
  m.point[0] = madd(fr.re.apply(xb), F(0.5f) * depth, nw);  // relative to fr.pe
  m.pdepth[0] = depth;
  o.put(m, fr.pe);
}

/// The range through prim::for_each_live_group: the screen writes count 0 for every lane
/// and lists those that may touch (bounding spheres overlapping and no face axis
/// separating: about half on the bench); the pieces run on full groups of them.
template <class F>
IMPACT_INLINE void box_ellipsoid_range(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, Range r) {
  for_each_live_group<F, 1>(
      a, b, out, r,
      [&](const LeafSoA& va, const LeafSoA& vb, uint32_t at, uint32_t, uint32_t, NoExtra*) {
        const Frame<F> fr = make_frame(load_p<F>(va, at), load_r<F>(va, at), load_e<F>(va, at),
                                       load_p<F>(vb, at), load_r<F>(vb, at), load_e<F>(vb, at));
        return simd::bits(may_touch(fr, face_best(fr)));
      },
      [&](const int32_t* index, const NoExtra*, uint32_t, LiveOut<F, 1>& o) {
        const GroupRows<F> rows(index, r);
        const Frame<F> fr =
            make_frame(rows.v3(a.p), rows.rot(a), rows.v3(a.e), rows.v3(b.p), rows.rot(b), rows.v3(b.e));
        Best<F> best = face_best(fr);
        pieces(fr, best);
        finish(fr, best, o);
      });
}

}  // namespace

void collide_box_ellipsoid(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, Range r,
                           const NarrowConfig& cfg) {
  if (cfg.path == KernelPath::kScalar) {
    box_ellipsoid_range<simd::Float1>(a, b, out, r);
  } else {
    box_ellipsoid_range<simd::FloatP>(a, b, out, r);
  }
}

}  // namespace impact::kernels
