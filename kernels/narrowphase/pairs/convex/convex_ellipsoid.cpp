// Convex hull (A) against ellipsoid (B): exact collision data by the local minima of the
// support overlap, one pair at a time with kSimdWidth hull features per step; no GJK / EPA.
//
// Inputs: LeafSoA lanes per leaf.h (A a hull: pose p, R, ref into cfg.hulls; B an
// ellipsoid: p, R, radii e0, e1, e2 along R's columns), Range r.
// Outputs: ManifoldSoA lanes r.begin .. r.end: count (0 or 1), n (unit, A to B), depth,
// point[0] midway between the two surfaces (the ellipsoid's point touching along n, moved
// by depth / 2 along n: a face against a curved surface touches at a point), pdepth[0] =
// depth. Slots 1..3 untouched; count-0 lanes leave the other fields unspecified.
// Method (box_ellipsoid.cpp's, with the box's pieces replaced by the hull's), in the
// ellipsoid's frame scaled by its largest radius (radii a_i in (0, 1]; the hull's
// vertices y_v): with m a direction from the ellipsoid towards the hull,
//     G(m) = h_E(m) - min_v m.y_v,   h_E(m) = |diag(a) m|,
// is the support overlap along m; depth = min over unit m of G, n = -argmin. The sphere
// of directions splits into the pieces of the Minkowski difference: each face's normal,
// each edge's arc of normals (perpendicular to the edge, between its two faces'
// normals; G there is the 2-D problem on the ellipsoid's shadow across the edge) and
// each vertex's cone. The minimiser is a face normal or a local minimum of its piece's
// function: a vertex's nearest point or far local minimum on the ellipsoid, an edge's on
// the shadow (ellipsoid_solve.h). Every candidate is scored by G itself (the hull's
// lowest vertex along m, not only its own feature), so a candidate that is off its
// piece only scores an upper bound and never wins wrongly; the least wins (ties: faces
// in index order, then nearest points, then far minima, vertices before edges, each in
// index order).
// Per pair:
//  1. Faces, kSimdWidth per step: G_f = |A n_f| + n_f.c + fd_f in closed form (c: the
//     hull's origin); the least is the first bound `best`. best <= 0: count 0.
//  2. Vertices: y_v and the level L_v = |A^-1 y_v|^2. U = an upper bound of the distance
//     between the shapes: min_v (sqrt(L_v) - 1) (|y_v| / sqrt(L_v) <= 1 is on the
//     surface), 0 when the ellipsoid's centre or its deepest point along the best face
//     normal lies in the hull.
//  3. Pruning (exact: drops only candidates that are off their piece or cannot win):
//     a point (vertex, or an edge's line) outside has candidates of G = minus its
//     distance >= (sqrt(L) - 1) a_min (E dilated by d lies in (1 + d / a_min) E): they
//     can be the minimum only if that is <= U. An inside point's candidates score at
//     least (1 - sqrt(L)) a_min (>= the distance to the surface): they can win only
//     below best. A far minimum scores at least the point's distance to the smallest
//     axis's plane, and exists only under far_bracket's test. An edge's line level is
//     min over the line of the level (the shadow's level, a Schur complement); edges
//     that pass get the shadow and ellipsoid_pieces.h's sign test along each candidate's
//     solution curve against the edge's two face constraints (n_1 - (n_0.n_1) n_0 and
//     the converse: the edge is lowest along m iff -m lies between the face normals).
//  4. The survivors are solved packed, kSimdWidth slots to a solve (near points first;
//     far minima only if best is still > 0), each scored by G over all vertices.
// Degenerate input: flat hulls (two faces back to back) have edges whose constraint
// vanishes (never pruned by the sign test); zero-length edges are skipped (their
// vertices' pieces cover them); a round ellipsoid has equal radii (the solver's ties);
// coincident centres are inside points. Hulls with no faces, no edge adjacency or more
// than kMaxVerts vertices (kMaxFaces faces, kMaxEdges edges) take the general GJK / EPA
// lane for that pair.
// Preconditions: finite inputs, positive radii, orthonormal R, hulls as HullStore builds
// them (host-validated); no division without a guard: finite inputs give finite outputs.
// Cost: one pass over the hull's faces, then the vertex and edge pieces the bounds keep,
// solved packed 8 slots to a solve. Cost: measured per pair in docs/results.md ("Narrow phase").
// Paths: the per-pair code is one template over the lane type: F = FloatW (kSimd) runs
// kSimdWidth faces / vertices / edges / solves per step, Float1 (kScalar) one at a time.
// Method citation: Eberly, "Distance from a Point to an Ellipse, an Ellipsoid, or a
// Hyperellipsoid" (2013) for the candidates; the piece decomposition of the Minkowski
// difference as in van den Bergen, Collision Detection in Interactive 3D Environments
// (2003), ch. 4.
#include <cmath>
#include <cstdint>

#include "kernels/narrowphase/solvers/ellipsoid_pieces.h"
#include "kernels/narrowphase/general/hull_scan.h"
#include "kernels/narrowphase/pair_kernels.h"
#include "kernels/narrowphase/lanes/lane_geometry.h"

namespace impact::kernels {
namespace {

using namespace prim;  // NOLINT: lane helpers of this kernel family
using hull_scan::block;
using simd::dot;
using simd::length_sq;

/// Stack scratch limits (hulls beyond them take GJK / EPA).
constexpr uint32_t kMaxVerts = 256;
constexpr uint32_t kMaxFaces = 512;
constexpr uint32_t kMaxEdges = 800;
constexpr float kBig = 3.0e38f;

/// Per pair: the hull in the ellipsoid's scaled frame.
template <uint32_t W>
struct Scratch {
  float yx[kMaxVerts + W], yy[kMaxVerts + W], yz[kMaxVerts + W];
  float nx[kMaxFaces + W], ny[kMaxFaces + W], nz[kMaxFaces + W], pc[kMaxFaces + W];
  int32_t e0[kMaxEdges + W], e1[kMaxEdges + W], f0[kMaxEdges + W], f1[kMaxEdges + W];
};

/// Candidate problems waiting for a packed solve: radii a (2-D: (ax0, ax1, ax0)), point
/// y (2-D: (y0, y1, 0)) and the basis lifting the problem's normal to the frame.
template <uint32_t W>
struct Slots {
  static constexpr uint32_t kCap = 4 * W;
  float a[3][kCap], y[3][kCap], b[9][kCap];
  uint32_t n = 0;
};

struct Best {
  float value;
  float m[3];
  float len;
};

/// The lanes i + k < n.
template <class F>
IMPACT_INLINE uint32_t valid_bits(uint32_t i, uint32_t n) {
  constexpr uint32_t W = F::kWidth;
  const uint32_t c = n - i < W ? n - i : W;
  return c >= 32 ? 0xffffffffu : (1u << c) - 1u;
}

/// The pair's frame and running state.
template <class F>
struct Pair {
  static constexpr uint32_t W = F::kWidth;
  const HullView* h;
  uint32_t v0, nv, f0, nf, a0, na;
  float av[3];  // scaled radii
  float inv_a[3];
  float rs[9];  // hull local -> scaled ellipsoid frame, row-major
  float rr[9];  // the rotation alone
  float c[3];   // hull origin, scaled ellipsoid frame
  float am;
  Scratch<W>* s;
  Best best;
};

/// Scores W candidate directions m (lanes of `bits`) by G over all vertices and keeps the
/// least in order.
template <class F>
IMPACT_INLINE void score(Pair<F>& p, const V3<F>& m, uint32_t bits) {
  constexpr uint32_t W = F::kWidth;
  F lowest(kBig);
  for (uint32_t v = 0; v < p.nv; ++v) {
    lowest = min(lowest, m.x * F(p.s->yx[v]) + m.y * F(p.s->yy[v]) + m.z * F(p.s->yz[v]));
  }
  const F l2 = length_sq(m);
  const F ax = F(p.av[0]) * m.x, ay = F(p.av[1]) * m.y, az = F(p.av[2]) * m.z;
  const F he = sqrt(ax * ax + ay * ay + az * az);
  const auto ok = l2 >= F(kTinySq);
  const F len = sqrt(select(ok, l2, F(1.0f)));
  const F value = (he - lowest) / len;
  bits &= simd::bits(ok);
  float vv[W], mx[W], my[W], mz[W], ll[W];
  value.store(vv), m.x.store(mx), m.y.store(my), m.z.store(mz), len.store(ll);
  for (uint32_t k = 0; k < W; ++k) {
    if (((bits >> k) & 1u) && vv[k] < p.best.value) {
      p.best.value = vv[k];
      p.best.m[0] = mx[k], p.best.m[1] = my[k], p.best.m[2] = mz[k];
      p.best.len = ll[k];
    }
  }
}

/// Solves the waiting slots (near: nearest points; else far minima) and scores them.
template <class F>
IMPACT_INLINE void flush(Pair<F>& p, Slots<F::kWidth>& q, bool near) {
  constexpr uint32_t W = F::kWidth;
  using Mask = typename F::Mask;
  for (uint32_t i = 0; i < q.n; i += W) {
    F a[3], y[3], z[3], sign[3], g[3];
    for (int j = 0; j < 3; ++j) a[j] = block<F>(q.a[j], i, q.n), y[j] = block<F>(q.y[j], i, q.n);
    ellip::orthant(a, y, z, sign);
    Mask ok(true);
    if (near) {
      F x[3];
      ellip::closest_snapped(a, z, x, g);
    } else {
      const ellip::FarAxes<3, F> f = ellip::far_axes(a, z);
      Mask mirror, solve;
      ellip::far_cases(f, mirror, solve);
      const Mask alive = ellip::far_solve(f, solve, z, g);
      if (simd::any(mirror)) {
        F x[3], gn[3];
        ellip::closest_snapped(a, z, x, gn);
        for (int j = 0; j < 3; ++j) g[j] = select(mirror, select(f.is_m[j], -gn[j], gn[j]), g[j]);
      }
      ok = mirror | (solve & alive);
    }
    F ml[3];
    for (int j = 0; j < 3; ++j) ml[j] = sign[j] * g[j];
    V3<F> m{F(0.0f), F(0.0f), F(0.0f)};
    for (int j = 0; j < 3; ++j) {
      const V3<F> bj{block<F>(q.b[3 * j], i, q.n), block<F>(q.b[3 * j + 1], i, q.n),
                     block<F>(q.b[3 * j + 2], i, q.n)};
      m = madd(m, ml[j], bj);
    }
    score(p, m, simd::bits(ok) & valid_bits<F>(i, q.n));
  }
  q.n = 0;
}

/// Appends the lanes of `bits` as slots (flushing first when full).
template <class F>
IMPACT_INLINE void push(Pair<F>& p, Slots<F::kWidth>& q, bool near, uint32_t bits, const F (&a)[3],
                        const F (&y)[3], const V3<F> (&basis)[3]) {
  constexpr uint32_t W = F::kWidth;
  if (bits == 0) return;
  float ta[3][W], ty[3][W], tb[9][W];
  for (int j = 0; j < 3; ++j) {
    a[j].store(ta[j]), y[j].store(ty[j]);
    basis[j].x.store(tb[3 * j]), basis[j].y.store(tb[3 * j + 1]), basis[j].z.store(tb[3 * j + 2]);
  }
  for (uint32_t k = 0; k < W; ++k) {
    if (((bits >> k) & 1u) == 0) continue;
    if (q.n == Slots<W>::kCap) flush(p, q, near);
    for (int j = 0; j < 3; ++j) q.a[j][q.n] = ta[j][k], q.y[j][q.n] = ty[j][k];
    for (int j = 0; j < 9; ++j) q.b[j][q.n] = tb[j][k];
    ++q.n;
  }
}

/// One pair: writes lane k of out. Returns false when the hull is beyond the kernel's
/// limits (the caller runs GJK / EPA).
template <class F>
bool convex_ellipsoid_pair(const LeafSoA& A, const LeafSoA& B, const ManifoldSoA& out, uint32_t k,
                           const HullView& h, Scratch<F::kWidth>& scratch) {
  constexpr uint32_t W = F::kWidth;
  using Mask = typename F::Mask;
  using Int = typename F::Int;
  const uint32_t hid = A.ref[k];
  Pair<F> p;
  p.h = &h;
  p.s = &scratch;
  p.v0 = h.vert_begin[hid], p.nv = h.vert_begin[hid + 1] - p.v0;
  p.f0 = h.face_begin[hid], p.nf = h.face_begin[hid + 1] - p.f0;
  p.a0 = h.adj_begin[hid], p.na = h.adj_begin[hid + 1] - p.a0;
  if (p.nv == 0 || p.nf == 0 || p.na == 0 || p.nv > kMaxVerts || p.nf > kMaxFaces || p.na > kMaxEdges)
    return false;

  // Frames: world = R local + p (row-major r[3 row + col]).
  float ra[9], re[9];
  for (int i = 0; i < 9; ++i) ra[i] = A.r[i][k], re[i] = B.r[i][k];
  const float e[3] = {B.e[0][k], B.e[1][k], B.e[2][k]};
  const float emax = e[0] > e[1] ? (e[0] > e[2] ? e[0] : e[2]) : (e[1] > e[2] ? e[1] : e[2]);
  const float inv = 1.0f / emax;
  for (int i = 0; i < 3; ++i) p.av[i] = e[i] * inv, p.inv_a[i] = 1.0f / p.av[i];
  p.am =
      p.av[0] < p.av[1] ? (p.av[0] < p.av[2] ? p.av[0] : p.av[2]) : (p.av[1] < p.av[2] ? p.av[1] : p.av[2]);
  const float d[3] = {A.p[0][k] - B.p[0][k], A.p[1][k] - B.p[1][k], A.p[2][k] - B.p[2][k]};
  for (int i = 0; i < 3; ++i) {
    p.c[i] = (re[i] * d[0] + re[3 + i] * d[1] + re[6 + i] * d[2]) * inv;
    for (int j = 0; j < 3; ++j) {
      // (Re^T Ra)_ij = column i of Re . column j of Ra
      p.rr[3 * i + j] = re[i] * ra[j] + re[3 + i] * ra[3 + j] + re[6 + i] * ra[6 + j];
      p.rs[3 * i + j] = p.rr[3 * i + j] * inv;
    }
  }
  const F zero(0.0f), one(1.0f);
  const F av[3] = {F(p.av[0]), F(p.av[1]), F(p.av[2])};
  const F ia[3] = {F(p.inv_a[0]), F(p.inv_a[1]), F(p.inv_a[2])};
  const V3<F> c{F(p.c[0]), F(p.c[1]), F(p.c[2])};
  const F lane = simd::lane_index<F>();

  // 1. Faces.
  F fbest(kBig), fidx(0.0f), cmin(kBig);
  for (uint32_t i = 0; i < p.nf; i += W) {
    const V3<F> nl{block<F>(h.fnx + p.f0, i, p.nf), block<F>(h.fny + p.f0, i, p.nf),
                   block<F>(h.fnz + p.f0, i, p.nf)};
    const V3<F> ne{F(p.rr[0]) * nl.x + F(p.rr[1]) * nl.y + F(p.rr[2]) * nl.z,
                   F(p.rr[3]) * nl.x + F(p.rr[4]) * nl.y + F(p.rr[5]) * nl.z,
                   F(p.rr[6]) * nl.x + F(p.rr[7]) * nl.y + F(p.rr[8]) * nl.z};
    const F pc = dot(ne, c) + block<F>(h.fd + p.f0, i, p.nf) * F(inv);
    const F ax = av[0] * ne.x, ay = av[1] * ne.y, az = av[2] * ne.z;
    const F g = sqrt(ax * ax + ay * ay + az * az) + pc;
    ne.x.store(scratch.nx + i), ne.y.store(scratch.ny + i), ne.z.store(scratch.nz + i),
        pc.store(scratch.pc + i);
    const Mask take = g < fbest;
    fbest = select(take, g, fbest);
    fidx = select(take, lane + F(static_cast<float>(i)), fidx);
    cmin = min(cmin, pc);
  }
  float fi;
  const float best_face = -simd::max_lowest_index(-fbest, fidx, static_cast<float>(p.nf), &fi);
  if (!(best_face > 0.0f)) {
    out.count[k] = 0;
    return true;
  }
  const uint32_t bf = static_cast<uint32_t>(fi);
  p.best.value = best_face;
  p.best.m[0] = -scratch.nx[bf], p.best.m[1] = -scratch.ny[bf], p.best.m[2] = -scratch.nz[bf];
  p.best.len = 1.0f;
  float cmin_s = cmin.lane(0);
  for (uint32_t l = 1; l < W; ++l) cmin_s = simd::fmin_nn(cmin_s, cmin.lane(l));

  // 2. Vertices: positions, levels, the distance bound U.
  F umin(kBig), ymax(0.0f);
  for (uint32_t i = 0; i < p.nv; i += W) {
    const V3<F> vl{block<F>(h.vx + p.v0, i, p.nv), block<F>(h.vy + p.v0, i, p.nv),
                   block<F>(h.vz + p.v0, i, p.nv)};
    const V3<F> y{F(p.rs[0]) * vl.x + F(p.rs[1]) * vl.y + F(p.rs[2]) * vl.z + c.x,
                  F(p.rs[3]) * vl.x + F(p.rs[4]) * vl.y + F(p.rs[5]) * vl.z + c.y,
                  F(p.rs[6]) * vl.x + F(p.rs[7]) * vl.y + F(p.rs[8]) * vl.z + c.z};
    y.x.store(scratch.yx + i), y.y.store(scratch.yy + i), y.z.store(scratch.yz + i);
    const F tx = y.x * ia[0], ty = y.y * ia[1], tz = y.z * ia[2];
    umin = min(umin, tx * tx + ty * ty + tz * tz);
    ymax = max(ymax, length_sq(y));
  }
  float lmin = umin.lane(0), ym2 = ymax.lane(0);
  for (uint32_t l = 1; l < W; ++l)
    lmin = simd::fmin_nn(lmin, umin.lane(l)), ym2 = simd::fmax_nn(ym2, ymax.lane(l));
  float U = std::sqrt(lmin) - 1.0f;
  if (cmin_s >= 0.0f) U = U < 0.0f ? U : 0.0f;  // the ellipsoid's centre is in the hull
  if (U > 0.0f) {
    // The ellipsoid's deepest point along the best face normal, in the hull?
    const float m[3] = {p.best.m[0], p.best.m[1], p.best.m[2]};
    const float q[3] = {p.av[0] * m[0], p.av[1] * m[1], p.av[2] * m[2]};
    const float hq = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2]);
    const F x0(p.av[0] * q[0] / hq), x1(p.av[1] * q[1] / hq), x2(p.av[2] * q[2] / hq);
    F worst(-kBig);
    for (uint32_t i = 0; i < p.nf; i += W) {
      const F s = x0 * block<F>(scratch.nx, i, p.nf) + x1 * block<F>(scratch.ny, i, p.nf) +
                  x2 * block<F>(scratch.nz, i, p.nf) - block<F>(scratch.pc, i, p.nf);
      worst = max(worst, s);
    }
    float w = worst.lane(0);
    for (uint32_t l = 1; l < W; ++l) w = simd::fmax_nn(w, worst.lane(l));
    if (w <= 0.0f) U = 0.0f;
  }
  const float ukeep = (U > 0.0f ? U : 0.0f) + 1e-5f * (1.0f + (U > 0.0f ? U : 0.0f) + std::sqrt(ym2));
  const F Uk(ukeep), am(p.am), band(1.0f + ellip::kPruneMargin);
  const bool far_outside = 2.0f * p.am * p.am < 1.0f;  // an outside point may have a far minimum

  Slots<W> near_q, far_q;
  const V3<F> ident[3] = {{one, zero, zero}, {zero, one, zero}, {zero, zero, one}};

  // 3a. Vertex candidates.
  const ellip::FarAxes3<F> fx = ellip::far_axes3(av);
  {
    const F bestv(p.best.value);
    const F vfloor = ellip::level_floor(bestv, am);
    for (uint32_t i = 0; i < p.nv; i += W) {
      const F y[3] = {block<F>(scratch.yx, i, p.nv), block<F>(scratch.yy, i, p.nv),
                      block<F>(scratch.yz, i, p.nv)};
      const F tx = y[0] * ia[0], ty = y[1] * ia[1], tz = y[2] * ia[2];
      const F level = tx * tx + ty * ty + tz * tz;
      const Mask inside = level < band;
      const Mask can = ~inside | (level > vfloor);
      const Mask near_want = select(inside, can, (sqrt(level) - one) * am <= Uk);
      const F ym = abs(select(fx.is_m[0], y[0], select(fx.is_m[1], y[1], y[2])));
      Mask far_want = can & (ym < bestv);
      if (simd::any(far_want)) far_want = far_want & ellip::far_bracket3(av, fx, y).exists;
      const uint32_t vb = valid_bits<F>(i, p.nv);
      push(p, near_q, true, simd::bits(near_want) & vb, av, y, ident);
      push(p, far_q, false, simd::bits(far_want) & vb, av, y, ident);
    }
  }

  // 3b. Edges: the line level first, the shadow and the curve tests for those that pass.
  {
    const F bestv(p.best.value);
    const F vfloor = ellip::level_floor(bestv, am);
    uint32_t ne = 0;
    for (uint32_t i = 0; i < p.na; i += W) {
      // The adjacency list is padded to a multiple of kHullEdgePad (W divides it).
      static_assert(kHullEdgePad % W == 0, "the edge walk needs whole padded blocks");
      const Int i0 = Int::load(reinterpret_cast<const int32_t*>(h.ev0 + p.a0 + i));
      const Int i1 = Int::load(reinterpret_cast<const int32_t*>(h.ev1 + p.a0 + i));
      const V3<F> P{simd::gather(scratch.yx, i0), simd::gather(scratch.yy, i0), simd::gather(scratch.yz, i0)};
      const V3<F> Q{simd::gather(scratch.yx, i1), simd::gather(scratch.yy, i1), simd::gather(scratch.yz, i1)};
      const V3<F> t = Q - P;
      const V3<F> ps{P.x * ia[0], P.y * ia[1], P.z * ia[2]}, ts{t.x * ia[0], t.y * ia[1], t.z * ia[2]};
      const F tt = length_sq(ts), pt = dot(ps, ts);
      const Mask ok = (tt > F(kTinySq)) & (length_sq(t) > F(1e-24f));
      const F level = max(length_sq(ps) - pt * pt / select(ok, tt, one), zero);
      const Mask inside = level < band;
      const Mask can = ~inside | (level > vfloor);
      const Mask outside_ok = ((sqrt(level) - one) * am <= Uk) | Mask(far_outside);
      const uint32_t want = simd::bits(ok & select(inside, can, outside_ok));
      for (uint32_t kk = 0; kk < W; ++kk) {
        if (((want >> kk) & 1u) == 0) continue;
        const uint32_t j = p.a0 + i + kk;
        scratch.e0[ne] = static_cast<int32_t>(h.ev0[j]), scratch.e1[ne] = static_cast<int32_t>(h.ev1[j]);
        scratch.f0[ne] = static_cast<int32_t>(h.ef0[j]), scratch.f1[ne] = static_cast<int32_t>(h.ef1[j]);
        ++ne;
      }
    }
    for (uint32_t i = ne; i < ne + W; ++i) {  // padding repeats the last
      const uint32_t l = ne == 0 ? 0 : ne - 1;
      scratch.e0[i] = scratch.e0[l], scratch.e1[i] = scratch.e1[l], scratch.f0[i] = scratch.f0[l],
      scratch.f1[i] = scratch.f1[l];
    }
    for (uint32_t i = 0; i < ne; i += W) {
      const Int i0 = Int::load(scratch.e0 + i), i1 = Int::load(scratch.e1 + i);
      const Int j0 = Int::load(scratch.f0 + i), j1 = Int::load(scratch.f1 + i);
      const V3<F> P{simd::gather(scratch.yx, i0), simd::gather(scratch.yy, i0), simd::gather(scratch.yz, i0)};
      const V3<F> Q{simd::gather(scratch.yx, i1), simd::gather(scratch.yy, i1), simd::gather(scratch.yz, i1)};
      const V3<F> n0{simd::gather(scratch.nx, j0), simd::gather(scratch.ny, j0),
                     simd::gather(scratch.nz, j0)};
      const V3<F> n1{simd::gather(scratch.nx, j1), simd::gather(scratch.ny, j1),
                     simd::gather(scratch.nz, j1)};
      const V3<F> t = Q - P;
      const V3<F> tu = t * (one / sqrt(length_sq(t)));
      const ellip::Shadow<F> sh = ellip::shadow(av, tu);
      const ellip::Radii2<F> r2 = ellip::radii2(sh);
      const F y[2] = {dot(sh.e1, P), dot(sh.e2, P)};
      Mask keep;
      const F level = ellip::level_of(r2.inv, y, keep);
      const Mask inside = level < band;
      const Mask can = ~inside | (level > ellip::level_floor(bestv, sh.ax[1]));
      Mask near_want = select(inside, can, (sqrt(level) - one) * sh.ax[1] <= Uk);
      Mask far_want = can & (abs(y[1]) < bestv);
      const F c01 = dot(n0, n1);
      const V3<F> w0 = n1 - n0 * c01, w1 = n0 - n1 * c01;
      const F u0[2] = {dot(w0, sh.e1), dot(w0, sh.e2)}, u1[2] = {dot(w1, sh.e1), dot(w1, sh.e2)};
      if (simd::any(andnot(near_want, keep))) {
        F lo, hi;
        ellip::near_bracket(r2.a, r2.d, r2.am2, r2.dmax, y, level, lo, hi);
        const Mask off = ellip::near_off2(u0, y, r2, lo, hi) | ellip::near_off2(u1, y, r2, lo, hi);
        near_want = andnot(near_want, andnot(off, keep));
      }
      if (simd::any(far_want)) {
        const ellip::FarBracket2<F> fb = ellip::far_bracket2(r2, y);
        Mask off = ~fb.exists;
        if (simd::any(andnot(far_want, keep | off))) {
          off = off | ellip::far_off2(u0, y, r2, fb) | ellip::far_off2(u1, y, r2, fb);
        }
        far_want = andnot(far_want, andnot(off, keep));
      }
      const F a3[3] = {sh.ax[0], sh.ax[1], sh.ax[0]};
      const F y3[3] = {y[0], y[1], zero};
      const V3<F> basis[3] = {sh.e1, sh.e2, {zero, zero, zero}};
      const uint32_t vb = valid_bits<F>(i, ne);
      push(p, near_q, true, simd::bits(near_want) & vb, a3, y3, basis);
      push(p, far_q, false, simd::bits(far_want) & vb, a3, y3, basis);
    }
  }

  // 4. The packed solves.
  flush(p, near_q, true);
  if (p.best.value > 0.0f) flush(p, far_q, false);
  if (!(p.best.value > 0.0f)) {
    out.count[k] = 0;
    return true;
  }

  // Output: n from A to B is minus m (world); B's surface point is its support along m.
  const float il = 1.0f / p.best.len;
  const float ml[3] = {p.best.m[0] * il, p.best.m[1] * il, p.best.m[2] * il};
  float nw[3];
  for (int i = 0; i < 3; ++i) nw[i] = -(re[3 * i] * ml[0] + re[3 * i + 1] * ml[1] + re[3 * i + 2] * ml[2]);
  const float depth = p.best.value * emax;
  const float q[3] = {p.av[0] * ml[0], p.av[1] * ml[1], p.av[2] * ml[2]};
  const float hq = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2]);
  const float sc = emax / (hq > 0.0f ? hq : 1.0f);
  const float xb[3] = {p.av[0] * q[0] * sc, p.av[1] * q[1] * sc, p.av[2] * q[2] * sc};
  out.count[k] = 1;
  for (int i = 0; i < 3; ++i) {
    out.n[i][k] = nw[i];
    const float xw = re[3 * i] * xb[0] + re[3 * i + 1] * xb[1] + re[3 * i + 2] * xb[2];
    out.point[0][i][k] = B.p[i][k] + (xw + 0.5f * depth * nw[i]);
  }
  out.depth[k] = depth;
  out.pdepth[0][k] = depth;
  return true;
}

template <class F>
void convex_ellipsoid_range(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, Range r,
                            const NarrowConfig& cfg) {
  Scratch<F::kWidth> scratch;
  for (uint32_t k = r.begin; k < r.end; ++k) {
    if (!convex_ellipsoid_pair<F>(a, b, out, k, cfg.hulls, scratch)) {
      collide_gjk_epa(a, b, out, Range{k, k + 1}, cfg, kLeafConvex, kLeafEllipsoid);
    }
  }
}

}  // namespace

void collide_convex_ellipsoid(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, Range r,
                              const NarrowConfig& cfg) {
  if (cfg.path == KernelPath::kScalar) {
    convex_ellipsoid_range<simd::Float1>(a, b, out, r, cfg);
  } else {
    convex_ellipsoid_range<simd::FloatW>(a, b, out, r, cfg);
  }
}

}  // namespace impact::kernels
