// Convex hull (A) against cylinder (B): exact normal and depth by the candidate
// directions of the Minkowski difference's pieces, one pair at a time with kSimdWidth
// hull features per step; the manifold of the general route (cvx::contact_manifold).
// No GJK / EPA.
//
// Inputs: LeafSoA lanes per leaf.h (A a hull: pose p, R, ref into cfg.hulls; B a
// cylinder C: p centre, R column 2 = unit axis, e0 = radius rc, e1 = half length h, flat
// caps with sharp rims), Range r. Outputs: ManifoldSoA lanes r.begin .. r.end: count
// (0..4), n (unit, A to B), depth, points midway between the surfaces with their depths
// along n (the same contract and manifold routine as collide_gjk_epa, which it
// replaces for this bucket); count-0 lanes leave the other fields unspecified.
// Method, in the cylinder's frame relative to its centre (y_v the hull's vertices):
//     o(n) = max_v n.y_v + rc |n_xy| + h |n_z|
// is the support function of the Minkowski difference A - C. Its minimum over unit n is
// the depth when the shapes meet and minus their distance when apart, and every unit n
// gives an upper bound, so the answer is the least o over a candidate set sure to hold
// the minimiser (box_cylinder.cpp's method, the box's features replaced by the hull's):
// one candidate per boundary piece of A - C (a hull feature minus a cylinder feature
// whose normal sets meet), each the critical point of o on its piece:
//  1. face x anything: n = the face normal (o from the face plane: exact, no vertex
//     loop). The least is the first bound; o <= 0 anywhere means no contact (count 0).
//  2. anything x cap: n = +-z.
//  3. edge x side (two lines): n = +-(e x z) / |e x z|, the sign inside the edge's
//     normal arc (its two faces' normals; HullView's bisector em and half angle).
//  4. vertex x side: n horizontal, from the vertex towards the axis.
//  5. vertex x rim: n from the vertex towards the rim point nearest it: a curve of
//     A - C, a minimiser only when the shapes are apart, so only on pairs not certified
//     to meet (a hull vertex in the cylinder, or the cylinder's centre in the hull).
//  6. edge interior x rim: n on the great circle n.e = 0, the local minimum of the 2-D
//     distance from the edge's shadow point to the rim's half-ellipse shadow (rim_solve.h,
//     the solve shared with capsule-, box- and cylinder-cylinder): the only costly
//     pieces. A slot (edge, rim) is kept where (a) the edge's arc reaches the rim's half
//     sphere (an end normal on that side), (b) a lower bound of o on the arc (the least
//     of n.y_0 over the arc, in closed form from em and the half angle, plus
//     min(rc, h)) is below the least o so far, and (c) a lower bound of the edge
//     segment's distance to the rim circle (radial and height gaps bounded along the
//     segment: |o| of the piece's candidate is that distance) is at most the least o so
//     far on a pair certified to meet, elsewhere at most the larger of that and the
//     nearest vertex's distance to the cylinder (if the shapes are apart, their distance
//     is no more than that point pair's). The survivors of a chunk of kChunk pairs are queued
//     and solved together, two kSimdWidth blocks per loop (independent chains).
// Scores: a face's from its plane, a cap's from the hull's highest and lowest vertex, an
// edge candidate's from the edge's own ends (exact where n lies inside the edge's normal
// arc: the edge is then the hull's support along n; outside it the candidate is not
// offered), a vertex candidate's from all vertices. Every offered score is thus o(n)
// itself, an upper bound of the minimum, and all of them bound the prunings and the
// early exits. Only a candidate on its own piece competes for the answer: a vertex that
// is the support along its direction (within rounding), an edge-side crossing on the
// edge and within the side's height, an edge-rim point on the edge; near the minimum o
// is flat, and a direction of another piece ~1e-4 rad off could otherwise tie the true
// minimum within rounding and bring witnesses that miss the shapes. The least o on its
// piece wins (ties: the first in the order faces, caps, edge-sides, vertex-sides,
// vertex-rims, edge-rims, each in index order); the least of all where it is lower by
// more than rounding. A face that won against a rim point whose image (moved by o along
// n) lies beyond one of the face's edges won a rounding tie against that edge's rim
// piece: that edge's candidate is solved and taken instead (within rounding of o).
// Witnesses for the manifold, from the two support features along n (the hull's
// vertices within rounding of its highest): a single vertex; else a unique rim point;
// else the side line against the feature's crossing of the line's plane (the middle of
// the crossing's height range clamped to the side; where the feature misses the line,
// its vertices nearest it: the side is round across, so the cylinder's point is off it
// only to second order); else the cap against the feature's centroid (or the rim point
// towards it). The other witness is that one moved by the depth along n.
// cvx::contact_manifold then clips the hull face against the cap's octagon or the side
// line where both offer a flat feature along n, else gives one point midway.
// Big or open hulls (no edge adjacency, more than kMaxVerts / kMaxFaces / kMaxEdges)
// take the general GJK / EPA lane for that pair.
// Preconditions: finite inputs, positive sizes, orthonormal R, unit axes, hulls as
// HullStore builds them (host-validated). Degenerate input: an edge along the axis has
// no edge-side candidate (its pieces are covered by the faces and the vertices); a
// vertex on the axis takes x as its radial direction; zero-length edges are skipped.
// Deterministic: each candidate's arithmetic is lane-wise and the winner is the least
// (o, index), so a pair's bytes do not depend on its neighbours or on the range's
// partition (the chunk's solve is lane-wise too). The same template runs kSimdWidth
// lanes (kSimd) or one (kScalar); the two agree to rounding, not to the byte: the
// shared helpers (prim::, rim_solve.h), defined before this file's no-contraction
// pragma, fuse multiply-adds differently at the two widths (a few lanes in a hundred of
// the tests' random ones differ in the last bits of the depth).
// Cost: impact_narrowbench BM_Kernel/convex-cylinder (24-point hulls, half the pairs
// overlapping); see docs/narrowphase.md.
// References: Minkowski-difference support functions for penetration depth (van den
// Bergen, Collision Detection in Interactive 3D Environments, 2003, ch. 4); the secular
// equation of the point-ellipse distance (Eberly, "Distance from a Point to an Ellipse,
// an Ellipsoid, or a Hyperellipsoid", Geometric Tools, 2013).
#include <bit>
#include <cmath>
#include <cstdint>

#include "kernels/narrowphase/general/face_manifold.h"
#include "kernels/narrowphase/general/gjk_epa.h"
#include "kernels/narrowphase/general/hull_scan.h"
#include "kernels/narrowphase/pair_kernels.h"
#include "kernels/narrowphase/lanes/lane_geometry.h"
#include "kernels/narrowphase/solvers/rim_solve.h"

// No FMA contraction in this file (see no_contract.h).
#include "kernels/narrowphase/lanes/no_contract.h"  // last: its pragma covers what follows

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
/// Rounding allowance, times the pair's size: how far a candidate's witness may miss its
/// piece (an edge-rim point beyond the edge's ends, an edge-side crossing, a vertex below
/// the highest along its direction) and still count on it; the support features gather
/// the vertices this close to the highest.
constexpr float kSlackRel = 4e-6f;
/// |n_xy| (|n_z|) at or below this: the cylinder's support feature is its cap (side
/// line).
constexpr float kFree = 1e-6f;

/// Pairs per chunk: their edge-rim slots are solved together.
constexpr uint32_t kChunk = 32;

template <uint32_t W>
struct Scratch {
  static constexpr uint32_t kE = kMaxEdges + W;
  float yx[kMaxVerts + W], yy[kMaxVerts + W], yz[kMaxVerts + W];
  // per edge, from the edge-side pass for the edge-rim slots: first vertex and direction,
  // arc bisector and half-angle cosine; a lower bound of o on the arc; the rims' half
  // spheres it reaches (1 / 0: n_z > 0, n_z < 0)
  float y0x[kE], y0y[kE], y0z[kE], dx[kE], dy[kE], dz[kE], bx[kE], by[kE], bz[kE], cs[kE];
  float low[kE], up[kE], down[kE];
};

/// A pair still live after the closed-form candidates: its frame and its least (o,
/// index) so far.
struct Live {
  uint32_t k;
  float o, id, n[3];     // the least (o, index) on its piece
  float ao, aid, an[3];  // the least (o, index) of every candidate
  float rr[9], c[3];     // hull local -> cylinder frame (row-major), the hull's origin there
  float rb[9], pc[3];    // the cylinder's rotation, its centre relative to A's position
  float rc, hh, slack;
  uint32_t v0, nv, a0, f0, nf, na;
  IMPACT_INLINE void take(float o2, float id2, float nx, float ny, float nz) {
    if (o2 < o || (o2 == o && id2 < id)) o = o2, id = id2, n[0] = nx, n[1] = ny, n[2] = nz;
  }
  IMPACT_INLINE void take_any(float o2, float id2, float nx, float ny, float nz) {
    if (o2 < ao || (o2 == ao && id2 < aid)) ao = o2, aid = id2, an[0] = nx, an[1] = ny, an[2] = nz;
  }
};

/// Edge-rim slots of a chunk's pairs waiting for the packed solve: the edge's midpoint,
/// unit direction, half length, arc bisector and half-angle cosine, the rim (0: n_z > 0),
/// the cylinder, the candidate index and the pair.
template <uint32_t W>
struct Queue {
  static constexpr uint32_t kCap = 256;
  static constexpr uint32_t kPad = kCap + 2 * W;
  float c[3][kPad], u[3][kPad], m[3][kPad], hs[kPad], cosh[kPad], slot[kPad], rc[kPad], hh[kPad], slack[kPad],
      id[kPad];
  uint32_t pair[kPad];
  uint32_t n = 0;
};

/// Lanes i + k < n.
template <class F>
IMPACT_INLINE typename F::Mask valid(uint32_t i, uint32_t n) {
  return simd::lane_index<F>() < F(static_cast<float>(n - i));
}

/// The pair in the cylinder's frame and the running least (o, index) per lane.
template <class F>
struct Pair {
  static constexpr uint32_t W = F::kWidth;
  const HullView* h;
  Scratch<W>* s;
  uint32_t v0, nv, f0, nf, a0, na;
  float rr[9];  // hull local -> cylinder frame, row-major
  float c[3];   // the hull's origin in the cylinder frame
  float rc, hh, slack;
  F bo, bid, bx, by, bz;  // the least (o, index) on its piece
  F ao, aid, ax, ay, az;  // the least (o, index) of every candidate

  IMPACT_INLINE V3<F> rotate(const V3<F>& l) const {
    return {F(rr[0]) * l.x + F(rr[1]) * l.y + F(rr[2]) * l.z,
            F(rr[3]) * l.x + F(rr[4]) * l.y + F(rr[5]) * l.z,
            F(rr[6]) * l.x + F(rr[7]) * l.y + F(rr[8]) * l.z};
  }
  /// The cylinder's part of o: rc |n_xy| + h |n_z|.
  IMPACT_INLINE F cyl(const V3<F>& n) const { return F(rc) * sqrt(n.x * n.x + n.y * n.y) + F(hh) * abs(n.z); }
  /// o(n) by the hull's highest vertex.
  IMPACT_INLINE F score(const V3<F>& n) const {
    F top(-kBig);
    for (uint32_t v = 0; v < nv; ++v)
      top = max(top, n.x * F(s->yx[v]) + n.y * F(s->yy[v]) + n.z * F(s->yz[v]));
    return top + cyl(n);
  }
  /// Lanes ok offer o at n (an upper bound of the minimum); those also `on` their
  /// piece compete for the answer, the others only for the bounds.
  IMPACT_INLINE void offer(F o, const V3<F>& n, F id, typename F::Mask ok, typename F::Mask on) {
    const auto any = ok & (o < ao);
    ao = select(any, o, ao);
    aid = select(any, id, aid);
    ax = select(any, n.x, ax), ay = select(any, n.y, ay), az = select(any, n.z, az);
    const auto take = ok & on & (o < bo);
    bo = select(take, o, bo);
    bid = select(take, id, bid);
    bx = select(take, n.x, bx), by = select(take, n.y, by), bz = select(take, n.z, bz);
  }
  IMPACT_INLINE void offer(F o, const V3<F>& n, F id, typename F::Mask ok) { offer(o, n, id, ok, ok); }
  /// The least o so far of every candidate (exact: a minimum over lanes).
  IMPACT_INLINE float least() const {
    float m = ao.lane(0);
    for (uint32_t l = 1; l < W; ++l) m = simd::fmin_nn(m, ao.lane(l));
    return m;
  }
};

/// Candidate indices (the tie order).
struct Ids {
  uint32_t cap, edge_side, vert_side, vert_rim, edge_rim;
  Ids(uint32_t nf, uint32_t na, uint32_t nv)
      : cap(nf),
        edge_side(nf + 2),
        vert_side(nf + 2 + na),
        vert_rim(nf + 2 + na + nv),
        edge_rim(nf + 2 + na + 3 * nv) {}
};

/// An edge block: its first vertex, direction, bisector and half angle in the frame.
template <class F>
struct EdgeBlock {
  V3<F> y0, d, m;
  F cosh, sinh;
};

template <class F>
IMPACT_INLINE EdgeBlock<F> load_edges(const Pair<F>& p, uint32_t i) {
  const HullView& h = *p.h;
  const uint32_t a0 = p.a0, na = p.na;
  EdgeBlock<F> e;
  const V3<F> lp{block<F>(h.epx + a0, i, na), block<F>(h.epy + a0, i, na), block<F>(h.epz + a0, i, na)};
  e.y0 = p.rotate(lp) + V3<F>{F(p.c[0]), F(p.c[1]), F(p.c[2])};
  e.d =
      p.rotate(V3<F>{block<F>(h.edx + a0, i, na), block<F>(h.edy + a0, i, na), block<F>(h.edz + a0, i, na)});
  e.m =
      p.rotate(V3<F>{block<F>(h.emx + a0, i, na), block<F>(h.emy + a0, i, na), block<F>(h.emz + a0, i, na)});
  e.cosh = block<F>(h.ecos + a0, i, na);
  e.sinh = block<F>(h.esin + a0, i, na);
  return e;
}

/// One edge-rim slot of rim_solve.h's half-ellipse solve, split around the solve so that
/// several slots run it as independent chains: setup gives the solve's inputs for the
/// edge c + t u (u unit) against the rim its normals reach (upper: n_z > 0, the bottom
/// rim); finish turns the solved normal into n (hull to cylinder), the parameter t along
/// the edge level with the rim point, and n's squared horizontal length.
template <class F>
struct RimSlot {
  rim::CoreRims<F> cr;
  typename F::Mask upper;
  IMPACT_INLINE void setup(const V3<F>& c, const V3<F>& u, F rc, F hh, typename F::Mask up, F& b, F& X,
                           F& Y) {
    F rb[2], rx[2], ry[2];
    cr.setup(c, u, rc, hh, rb, rx, ry);
    upper = up;
    b = rb[0], X = rx[0], Y = select(up, ry[0], ry[1]);
  }
  IMPACT_INLINE V3<F> finish(F ex, F ey, const V3<F>& c, const V3<F>& u, F rc, F hh, F& t, F& nxy2) const {
    F len;
    const V3<F> n = normalize_or(madd(cr.w * ex, select(upper, ey, -ey), cr.v), cr.w, len);
    nxy2 = n.x * n.x + n.y * n.y;
    const F sc = rc / sqrt(select(nxy2 > F(kTinySq), nxy2, F(1.0f)));
    const V3<F> y{-sc * n.x, -sc * n.y, -hh * simd::sign_nonneg(n.z)};
    t = dot(y - c, u);
    return n;
  }
};

/// Solves the queued slots two blocks at a time (independent chains in one loop),
/// scores the solutions that lie on their pieces and offers them to their pairs.
template <class F>
void flush(Queue<F::kWidth>& q, Live* live) {
  constexpr uint32_t W = F::kWidth;
  const F zero(0.0f);
  const uint32_t n = q.n;
  for (uint32_t i = 0; i < n; i += 2 * W) {
    RimSlot<F> rs[2];
    V3<F> c[2], u[2];
    F hs[2], rc[2], hh[2], b[2], X[2], Y[2], ex[2], ey[2];
    for (uint32_t j = 0; j < 2; ++j) {
      const uint32_t at = i + j * W;
      c[j] = V3<F>{block<F>(q.c[0], at, n), block<F>(q.c[1], at, n), block<F>(q.c[2], at, n)};
      u[j] = V3<F>{block<F>(q.u[0], at, n), block<F>(q.u[1], at, n), block<F>(q.u[2], at, n)};
      hs[j] = block<F>(q.hs, at, n), rc[j] = block<F>(q.rc, at, n), hh[j] = block<F>(q.hh, at, n);
      rs[j].setup(c[j], u[j], rc[j], hh[j], block<F>(q.slot, at, n) == zero, b[j], X[j], Y[j]);
    }
    rim::half_ellipse_normals<F, 2>(b, X, Y, ex, ey);
    for (uint32_t j = 0; j < 2; ++j) {
      const uint32_t at = i + j * W;
      if (at >= n) break;
      F t, nxy2;
      const V3<F> nn = rs[j].finish(ex[j], ey[j], c[j], u[j], rc[j], hh[j], t, nxy2);
      const V3<F> m{block<F>(q.m[0], at, n), block<F>(q.m[1], at, n), block<F>(q.m[2], at, n)};
      // inside the arc the score below is exact (an upper bound); on the piece where the
      // rim point also lies on the edge
      const uint32_t arc = simd::bits((dot(nn, m) >= block<F>(q.cosh, at, n)) & valid<F>(at, n));
      const uint32_t on = arc & simd::bits(abs(t) <= hs[j] + block<F>(q.slack, at, n));
      if (arc == 0) continue;
      // inside the arc the edge is the hull's support along nn: o from its ends
      const F o = dot(nn, c[j]) + hs[j] * abs(dot(nn, u[j])) + rc[j] * sqrt(nxy2) + hh[j] * abs(nn.z);
      float ov[W], nx[W], ny[W], nz[W];
      o.store(ov), nn.x.store(nx), nn.y.store(ny), nn.z.store(nz);
      for (uint32_t l = 0; l < W; ++l) {
        if (((arc >> l) & 1u) == 0) continue;
        Live& lv = live[q.pair[at + l]];
        lv.take_any(ov[l], q.id[at + l], nx[l], ny[l], nz[l]);
        if (((on >> l) & 1u) != 0) lv.take(ov[l], q.id[at + l], nx[l], ny[l], nz[l]);
      }
    }
  }
  q.n = 0;
}

/// What phase A left of a pair.
enum class State { kDone, kGeneral, kLive };

/// Phase A of one pair: the closed-form candidates, then the edge-rim slots that can
/// still win queued for the chunk's packed solve. kDone: lane k of out is written (no
/// contact); kGeneral: the hull is beyond the kernel's limits (the caller runs GJK /
/// EPA); kLive: lv holds the pair, live[self] is lv.
template <class F>
State convex_cylinder_pair(const LeafSoA& A, const LeafSoA& B, const ManifoldSoA& out, uint32_t k,
                           const HullView& h, Scratch<F::kWidth>& scratch, Live& lv, uint32_t self,
                           Queue<F::kWidth>& q, Live* live) {
  constexpr uint32_t W = F::kWidth;
  using Mask = typename F::Mask;
  const uint32_t hid = A.ref[k];
  Pair<F> p;
  p.h = &h;
  p.s = &scratch;
  p.v0 = h.vert_begin[hid], p.nv = h.vert_begin[hid + 1] - p.v0;
  p.f0 = h.face_begin[hid], p.nf = h.face_begin[hid + 1] - p.f0;
  // (a view without edge adjacency: every hull takes GJK / EPA)
  p.a0 = h.adj_begin != nullptr ? h.adj_begin[hid] : 0u;
  p.na = h.adj_begin != nullptr ? h.adj_begin[hid + 1] - p.a0 : 0u;
  if (p.nv == 0 || p.nf == 0 || p.na == 0 || p.nv > kMaxVerts || p.nf > kMaxFaces || p.na > kMaxEdges)
    return State::kGeneral;
  const Ids ids(p.nf, p.na, p.nv);

  // Frames: world = R local + p (row-major r[3 row + col]).
  float ra[9], rb[9];
  for (int i = 0; i < 9; ++i) ra[i] = A.r[i][k], rb[i] = B.r[i][k];
  const float dw[3] = {A.p[0][k] - B.p[0][k], A.p[1][k] - B.p[1][k], A.p[2][k] - B.p[2][k]};
  for (int i = 0; i < 3; ++i) {
    p.c[i] = rb[i] * dw[0] + rb[3 + i] * dw[1] + rb[6 + i] * dw[2];
    for (int j = 0; j < 3; ++j)
      p.rr[3 * i + j] = rb[i] * ra[j] + rb[3 + i] * ra[3 + j] + rb[6 + i] * ra[6 + j];
  }
  p.rc = B.e[0][k], p.hh = B.e[1][k];
  const F zero(0.0f), one(1.0f), lane = simd::lane_index<F>();
  const V3<F> c{F(p.c[0]), F(p.c[1]), F(p.c[2])};
  p.bo = F(kBig), p.bid = F(0.0f), p.bx = p.by = zero, p.bz = one;
  p.ao = F(kBig), p.aid = F(0.0f), p.ax = p.ay = zero, p.az = one;

  // 1. Faces: o from the plane offsets.
  F dmin(kBig);
  for (uint32_t i = 0; i < p.nf; i += W) {
    const V3<F> n = p.rotate(V3<F>{block<F>(h.fnx + p.f0, i, p.nf), block<F>(h.fny + p.f0, i, p.nf),
                                   block<F>(h.fnz + p.f0, i, p.nf)});
    const F d = dot(n, c) + block<F>(h.fd + p.f0, i, p.nf);
    p.offer(d + p.cyl(n), n, lane + F(static_cast<float>(i)), valid<F>(i, p.nf));
    dmin = min(dmin, d);
  }
  if (!(p.least() > 0.0f)) {
    out.count[k] = 0;
    return State::kDone;
  }

  // 2. Vertices into the frame; the caps.
  F zmax(-kBig), zmin(kBig), rmax(0.0f), gap(kBig);
  Mask inside(false);
  const float r2 = p.rc * p.rc;
  for (uint32_t i = 0; i < p.nv; i += W) {
    const V3<F> y = p.rotate(V3<F>{block<F>(h.vx + p.v0, i, p.nv), block<F>(h.vy + p.v0, i, p.nv),
                                   block<F>(h.vz + p.v0, i, p.nv)}) +
                    c;
    y.x.store(scratch.yx + i), y.y.store(scratch.yy + i), y.z.store(scratch.yz + i);
    zmax = max(zmax, y.z), zmin = min(zmin, y.z);
    rmax = max(rmax, abs(y.x) + abs(y.y) + abs(y.z));
    inside = inside | ((y.x * y.x + y.y * y.y <= F(r2)) & (abs(y.z) <= F(p.hh)));
    // the squared distance from the vertex to the cylinder
    const F dr = max(sqrt(y.x * y.x + y.y * y.y) - F(p.rc), zero), dz = max(abs(y.z) - F(p.hh), zero);
    gap = min(gap, select(valid<F>(i, p.nv), dr * dr + dz * dz, F(kBig)));
  }
  float ztop = zmax.lane(0), zbot = zmin.lane(0), reach = rmax.lane(0), dlow = dmin.lane(0);
  float near2 = gap.lane(0);
  for (uint32_t l = 1; l < W; ++l) {
    ztop = simd::fmax_nn(ztop, zmax.lane(l)), zbot = simd::fmin_nn(zbot, zmin.lane(l));
    reach = simd::fmax_nn(reach, rmax.lane(l)), dlow = simd::fmin_nn(dlow, dmin.lane(l));
    near2 = simd::fmin_nn(near2, gap.lane(l));
  }
  p.slack = kSlackRel * (p.rc + p.hh + reach);
  // Certified to meet: a vertex in the cylinder or the cylinder's centre in the hull.
  const bool meets = simd::any(inside) || dlow >= 0.0f;
  {
    const Mask up = lane == zero;
    const F o = select(up, F(ztop + p.hh), F(p.hh - zbot));
    p.offer(o, V3<F>{zero, zero, select(up, one, F(-1.0f))}, lane + F(static_cast<float>(ids.cap)),
            valid<F>(0, 2));
    if constexpr (W == 1)
      p.offer(F(p.hh - zbot), V3<F>{zero, zero, F(-1.0f)}, F(static_cast<float>(ids.cap + 1)), Mask(true));
  }
  if (!(p.least() > 0.0f)) {
    out.count[k] = 0;
    return State::kDone;
  }

  // 3. Edges against the side lines; the edge-rim slots' data and bounds for step 6.
  const F tiny(kTinySq), floor(p.rc < p.hh ? p.rc : p.hh), rc(p.rc), hh(p.hh);
  for (uint32_t i = 0; i < p.na; i += W) {
    const EdgeBlock<F> e = load_edges(p, i);
    const F dxy2 = e.d.x * e.d.x + e.d.y * e.d.y;
    const F l2 = length_sq(e.d);
    // (relative: a product with kTinySq would be subnormal, an assist per lane)
    const Mask tilted = dxy2 > F(1e-12f) * l2;
    const F inv = one / sqrt(select(tilted, dxy2, one));
    V3<F> n{e.d.y * inv, -e.d.x * inv, zero};
    n = select(dot(n, e.m) < zero, -n, n);
    // inside the arc the edge is the hull's support along n: o from its ends
    const V3<F> y1 = e.y0 + e.d;
    const F o = max(dot(n, e.y0), dot(n, y1)) + rc;
    // on its piece where the edge crosses the side line (seen along n) within both:
    // the crossing's parameter on the edge and its height on the side
    const F sv = -((e.y0.x + rc * n.x) * e.d.x + (e.y0.y + rc * n.y) * e.d.y) / select(tilted, dxy2, one);
    const F zc = e.y0.z + sv * e.d.z, ss = F(p.slack);
    const Mask long_enough = l2 > tiny;
    const F len = sqrt(select(long_enough, l2, one));
    const Mask crosses = (sv * len >= -ss) & ((sv - one) * len <= ss) & (abs(zc) <= hh + ss);
    const Mask ok = tilted & (dot(n, e.m) >= e.cosh) & valid<F>(i, p.na);
    p.offer(o, n, lane + F(static_cast<float>(ids.edge_side + i)), ok, crosses);
    // edge-rim: the least of n.y0 over the arc (n = cos t m + sin t (u x m), |t| <= the
    // half angle) plus min(rc, h), the least of the cylinder's part
    const V3<F> u = e.d * (one / len);
    const V3<F> tm = simd::cross(u, e.m);
    const F a = dot(e.m, e.y0), b = dot(tm, e.y0);
    const F big_r = sqrt(a * a + b * b);
    const F low = select(-a >= big_r * e.cosh, -big_r, e.cosh * a - e.sinh * abs(b)) + floor;
    select(long_enough, low, F(kBig)).store(scratch.low + i);
    // the arc's end normals' heights: which rims' half spheres it reaches
    const F z0 = e.m.z * e.cosh + e.sinh * tm.z, z1 = e.m.z * e.cosh - e.sinh * tm.z;
    select(max(z0, z1) > zero, one, zero).store(scratch.up + i);
    select(min(z0, z1) < zero, one, zero).store(scratch.down + i);
    e.y0.x.store(scratch.y0x + i), e.y0.y.store(scratch.y0y + i), e.y0.z.store(scratch.y0z + i);
    e.d.x.store(scratch.dx + i), e.d.y.store(scratch.dy + i), e.d.z.store(scratch.dz + i);
    e.m.x.store(scratch.bx + i), e.m.y.store(scratch.by + i), e.m.z.store(scratch.bz + i);
    e.cosh.store(scratch.cs + i);
  }
  if (!(p.least() > 0.0f)) {
    out.count[k] = 0;
    return State::kDone;
  }
  // 4. Vertices against the side: o >= rc - rho (the vertex's own n.y), so only where
  // that is below the least so far.
  for (uint32_t i = 0; i < p.nv; i += W) {
    const F yx = F::load(scratch.yx + i), yy = F::load(scratch.yy + i);
    const F rho2 = yx * yx + yy * yy;
    const Mask off = rho2 > tiny;
    const F rho = sqrt(rho2);
    const Mask ok = off & (F(p.rc) - rho < F(p.least())) & valid<F>(i, p.nv);
    if (simd::none(ok)) continue;
    const F ri = one / select(off, rho, one);
    const V3<F> n{-yx * ri, -yy * ri, zero};
    // on its piece only where the vertex is the hull's support along n (within
    // rounding): near the minimum o is flat, and another vertex's direction, 1e-4 rad
    // off, could tie the true minimum within rounding
    const F o = p.score(n);
    p.offer(o, n, lane + F(static_cast<float>(ids.vert_side + i)), ok, F(p.rc) - rho >= o - F(p.slack));
  }
  // 5. Vertices against the rims, where the pair is not certified to meet.
  if (!meets) {
    if (!(p.least() > 0.0f)) {
      out.count[k] = 0;
      return State::kDone;
    }
    for (uint32_t i = 0; i < p.nv; i += W) {
      const V3<F> y{F::load(scratch.yx + i), F::load(scratch.yy + i), F::load(scratch.yz + i)};
      const F rho2 = y.x * y.x + y.y * y.y;
      const Mask off = rho2 > tiny;
      const F ri = one / sqrt(select(off, rho2, one));
      const F qx = F(p.rc) * select(off, y.x * ri, one), qy = F(p.rc) * select(off, y.y * ri, zero);
      for (int sgn = 0; sgn < 2; ++sgn) {
        const V3<F> rim{qx, qy, F(sgn == 0 ? p.hh : -p.hh)};
        F len;
        const V3<F> n = normalize_or(rim - y, V3<F>{zero, zero, F(sgn == 0 ? 1.0f : -1.0f)}, len);
        const F o = p.score(n);
        const Mask ok = (len > zero) & valid<F>(i, p.nv);
        const F id = F(2.0f) * (lane + F(static_cast<float>(i))) + F(static_cast<float>(ids.vert_rim + sgn));
        p.offer(o, n, id, ok, dot(n, y) + p.cyl(n) >= o - F(p.slack));
      }
    }
  }
  if (!(p.least() > 0.0f)) {
    out.count[k] = 0;
    return State::kDone;
  }
  // The least (o, index) so far, and the frame for the solve and phase C.
  lv.k = k;
  lv.o = p.bo.lane(0), lv.id = p.bid.lane(0), lv.n[0] = p.bx.lane(0), lv.n[1] = p.by.lane(0),
  lv.n[2] = p.bz.lane(0);
  for (uint32_t l = 1; l < W; ++l)
    lv.take(p.bo.lane(l), p.bid.lane(l), p.bx.lane(l), p.by.lane(l), p.bz.lane(l));
  lv.ao = p.ao.lane(0), lv.aid = p.aid.lane(0), lv.an[0] = p.ax.lane(0), lv.an[1] = p.ay.lane(0),
  lv.an[2] = p.az.lane(0);
  for (uint32_t l = 1; l < W; ++l)
    lv.take_any(p.ao.lane(l), p.aid.lane(l), p.ax.lane(l), p.ay.lane(l), p.az.lane(l));
  for (int i = 0; i < 9; ++i) lv.rr[i] = p.rr[i], lv.rb[i] = rb[i];
  for (int i = 0; i < 3; ++i) lv.c[i] = p.c[i], lv.pc[i] = -dw[i];
  lv.rc = p.rc, lv.hh = p.hh, lv.slack = p.slack;
  lv.v0 = p.v0, lv.nv = p.nv, lv.a0 = p.a0, lv.f0 = p.f0, lv.nf = p.nf, lv.na = p.na;
  // 6. Edge interiors against the rims: the slots that can win, queued for the solve:
  // the arc's lower bound below the least o so far, and a lower bound of the segment's
  // distance to the rim circle (|o| of the piece's candidate) at most the least o so far
  // on a pair certified to meet; elsewhere at most the larger of that and the nearest
  // vertex's distance to the cylinder (a point pair's: the distance if they are apart
  // is no more).
  {
    const float best = p.least();
    const F fb(best), fb2(meets ? best * best : simd::fmax_nn(best * best, near2));
    for (uint32_t i = 0; i < p.na; i += W) {
      const Mask keep = (F::load(scratch.low + i) < fb) & valid<F>(i, p.na);
      Mask slot[2] = {keep & (F::load(scratch.up + i) > zero), keep & (F::load(scratch.down + i) > zero)};
      if (simd::none(slot[0] | slot[1])) continue;
      // the segment's distance to each rim circle, bounded below by its radial and height
      // gaps (the least distance to the axis: a 2-D point-segment distance)
      const V3<F> y0{F::load(scratch.y0x + i), F::load(scratch.y0y + i), F::load(scratch.y0z + i)};
      const V3<F> d{F::load(scratch.dx + i), F::load(scratch.dy + i), F::load(scratch.dz + i)};
      const V3<F> y1 = y0 + d;
      const F dxy2 = d.x * d.x + d.y * d.y;
      const F rhi = sqrt(max(y0.x * y0.x + y0.y * y0.y, y1.x * y1.x + y1.y * y1.y));
      const F tt = clamp(-(y0.x * d.x + y0.y * d.y) / select(dxy2 > tiny, dxy2, one), zero, one);
      const F px = y0.x + tt * d.x, py = y0.y + tt * d.y;
      const F rg = max(max(sqrt(px * px + py * py) - rc, rc - rhi), zero);
      const F zlo = min(y0.z, y1.z), zhi = max(y0.z, y1.z);
      const F hg0 = max(max(zlo + hh, -hh - zhi), zero), hg1 = max(max(zlo - hh, hh - zhi), zero);
      slot[0] = slot[0] & (rg * rg + hg0 * hg0 <= fb2);
      slot[1] = slot[1] & (rg * rg + hg1 * hg1 <= fb2);
      const uint32_t bits[2] = {simd::bits(slot[0]), simd::bits(slot[1])};
      if ((bits[0] | bits[1]) == 0) continue;
      for (uint32_t sl = 0; sl < 2; ++sl) {
        for (uint32_t mb = bits[sl]; mb != 0; mb &= mb - 1u) {
          if (q.n == Queue<W>::kCap) flush<F>(q, live);
          const uint32_t j = q.n++, x = i + static_cast<uint32_t>(std::countr_zero(mb));
          const float e[3] = {scratch.dx[x], scratch.dy[x], scratch.dz[x]};
          const float len = std::sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]), il = 1.0f / len;
          q.c[0][j] = scratch.y0x[x] + 0.5f * e[0], q.c[1][j] = scratch.y0y[x] + 0.5f * e[1],
          q.c[2][j] = scratch.y0z[x] + 0.5f * e[2];
          q.u[0][j] = e[0] * il, q.u[1][j] = e[1] * il, q.u[2][j] = e[2] * il;
          q.m[0][j] = scratch.bx[x], q.m[1][j] = scratch.by[x], q.m[2][j] = scratch.bz[x];
          q.hs[j] = 0.5f * len, q.cosh[j] = scratch.cs[x];
          q.slot[j] = static_cast<float>(sl);
          q.rc[j] = p.rc, q.hh[j] = p.hh, q.slack[j] = p.slack;
          q.id[j] = static_cast<float>(ids.edge_rim + 2 * x + sl);
          q.pair[j] = self;
        }
      }
    }
  }
  return State::kLive;
}

/// Phase C of a live pair: count 0 where its least o is not positive, else the
/// witnesses of the winning candidate and the manifold.
template <class F>
void finish_pair(const LeafSoA& A, const LeafSoA& B, const ManifoldSoA& out, const HullView& h,
                 const Live& lv) {
  const uint32_t k = lv.k;
  // The least candidate on its piece; the least of all where that is lower by more than
  // rounding (then no candidate of the minimiser's piece passed its test).
  const bool any = lv.ao < lv.o - lv.slack;
  float o = any ? lv.ao : lv.o;
  float n[3] = {any ? lv.an[0] : lv.n[0], any ? lv.an[1] : lv.n[1], any ? lv.an[2] : lv.n[2]};
  const float won = any ? lv.aid : lv.id;
  if (!(o > 0.0f)) {
    out.count[k] = 0;
    return;
  }
  const float hh = lv.hh, rc = lv.rc;

  // the vertices in the frame, F::kWidth at a time
  constexpr uint32_t W = F::kWidth;
  float yv[kMaxVerts][3];
  float size = rc + hh;
  {
    float tx[kMaxVerts + W], ty[kMaxVerts + W], tz[kMaxVerts + W];
    for (uint32_t i = 0; i < lv.nv; i += W) {
      const V3<F> l{block<F>(h.vx + lv.v0, i, lv.nv), block<F>(h.vy + lv.v0, i, lv.nv),
                    block<F>(h.vz + lv.v0, i, lv.nv)};
      for (int j = 0; j < 3; ++j) {
        const F y =
            F(lv.rr[3 * j]) * l.x + F(lv.rr[3 * j + 1]) * l.y + F(lv.rr[3 * j + 2]) * l.z + F(lv.c[j]);
        y.store((j == 0 ? tx : j == 1 ? ty : tz) + i);
      }
    }
    for (uint32_t v = 0; v < lv.nv; ++v) {
      yv[v][0] = tx[v], yv[v][1] = ty[v], yv[v][2] = tz[v];
      size = simd::fmax_nn(size, std::fabs(tx[v]) + std::fabs(ty[v]) + std::fabs(tz[v]));
    }
  }
  const float tol = kSlackRel * size;
  auto score = [&](const float* m) {
    float t = -kBig;
    for (uint32_t v = 0; v < lv.nv; ++v)
      t = simd::fmax_nn(t, m[0] * yv[v][0] + m[1] * yv[v][1] + m[2] * yv[v][2]);
    return t + rc * std::sqrt(m[0] * m[0] + m[1] * m[1]) + hh * std::fabs(m[2]);
  };
  // A face won against a rim point: the rim point moved by o along n lies in the face
  // where the face's piece holds the minimum. Beyond a face edge by more than rounding,
  // the face won a rounding tie against the piece beside it (that edge against the rim,
  // o flat there: a direction ~1e-4 rad off ties within rounding, and its witnesses
  // would miss the shapes by ~sqrt(rounding x depth)); that edge's candidate instead.
  const Ids ids(lv.nf, lv.na, lv.nv);
  if (won < static_cast<float>(ids.cap) && std::fabs(n[2]) > kFree &&
      n[0] * n[0] + n[1] * n[1] > kFree * kFree) {
    const float sc = rc / std::sqrt(n[0] * n[0] + n[1] * n[1]);
    const float x[3] = {-sc * n[0] + o * n[0], -sc * n[1] + o * n[1], (n[2] >= 0.0f ? -hh : hh) + o * n[2]};
    const uint32_t f = lv.f0 + static_cast<uint32_t>(won);
    const uint32_t fb = h.face_vert_begin[f], fe = h.face_vert_begin[f + 1];
    float worst = tol;
    const float* ea = nullptr;
    const float* eb = nullptr;
    for (uint32_t i = fb; i < fe; ++i) {
      const float* a = yv[h.face_verts[i] - lv.v0];
      const float* b = yv[h.face_verts[i + 1 < fe ? i + 1 : fb] - lv.v0];
      const float e[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
      // outward in the face's plane (vertices counter-clockwise about n)
      const float c[3] = {e[1] * n[2] - e[2] * n[1], e[2] * n[0] - e[0] * n[2], e[0] * n[1] - e[1] * n[0]};
      const float cl = std::sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
      if (!(cl > 0.0f)) continue;
      const float out_by = (c[0] * (x[0] - a[0]) + c[1] * (x[1] - a[1]) + c[2] * (x[2] - a[2])) / cl;
      if (out_by > worst) worst = out_by, ea = a, eb = b;
    }
    if (ea != nullptr) {
      using F1 = simd::Float1;
      const V3<F1> a1{F1(ea[0]), F1(ea[1]), F1(ea[2])},
          d1{F1(eb[0] - ea[0]), F1(eb[1] - ea[1]), F1(eb[2] - ea[2])};
      const F1 len = sqrt(length_sq(d1));
      const V3<F1> u = d1 * (F1(1.0f) / len), c = madd(a1, F1(0.5f), d1);
      const F1 hs = F1(0.5f) * len;
      RimSlot<F1> rs;
      F1 b1[1], X1[1], Y1[1], ex[1], ey[1];
      rs.setup(c, u, F1(rc), F1(hh), typename F1::Mask(n[2] > 0.0f), b1[0], X1[0], Y1[0]);
      rim::half_ellipse_normals<F1, 1>(b1, X1, Y1, ex, ey);
      F1 t, nxy2;
      const V3<F1> nn = rs.finish(ex[0], ey[0], c, u, F1(rc), F1(hh), t, nxy2);
      const float m[3] = {nn.x.lane(0), nn.y.lane(0), nn.z.lane(0)};
      const float om = score(m);
      if (std::fabs(t.lane(0)) <= hs.lane(0) + tol && om <= o + tol) {
        o = om;
        for (int j = 0; j < 3; ++j) n[j] = m[j];
      }
    }
  }
  // Witnesses in the cylinder frame, xa on the hull and xb on the cylinder with
  // xa - xb = o n, from the two support features along n (not from the winning
  // candidate's kind: near the minimum a candidate of another piece can win a rounding
  // tie, and its own feature need not be where the shapes touch).
  // The hull's support feature: its vertices within rounding of the highest along n.
  float top = -kBig;
  for (uint32_t v = 0; v < lv.nv; ++v)
    top = simd::fmax_nn(top, n[0] * yv[v][0] + n[1] * yv[v][1] + n[2] * yv[v][2]);
  uint32_t feat[kMaxVerts];
  uint32_t nfeat = 0;
  float cen[3] = {0.0f, 0.0f, 0.0f};
  for (uint32_t v = 0; v < lv.nv; ++v) {
    if (n[0] * yv[v][0] + n[1] * yv[v][1] + n[2] * yv[v][2] >= top - tol) {
      feat[nfeat++] = v;
      for (int j = 0; j < 3; ++j) cen[j] += yv[v][j];
    }
  }
  for (int j = 0; j < 3; ++j) cen[j] /= static_cast<float>(nfeat);
  const float nxy2 = n[0] * n[0] + n[1] * n[1];
  const bool side = std::fabs(n[2]) <= kFree, cap = nxy2 <= kFree * kFree;
  float xa[3], xb[3];
  if (nfeat == 1 || !(side || cap)) {
    if (nfeat == 1) {
      // a vertex: the hull's point
      for (int j = 0; j < 3; ++j) xa[j] = yv[feat[0]][j], xb[j] = xa[j] - o * n[j];
    } else {
      // a rim point: the cylinder's (its support along -n is unique)
      const float sc = rc / std::sqrt(nxy2);
      xb[0] = -sc * n[0], xb[1] = -sc * n[1], xb[2] = n[2] >= 0.0f ? -hh : hh;
      for (int j = 0; j < 3; ++j) xa[j] = xb[j] + o * n[j];
    }
  } else if (side) {
    // the side line (w = 0 across, z in [-h, h]) against the feature seen along n: the
    // feature's z range where it crosses w = 0, clamped to the side, and its middle.
    // Where the feature misses w = 0 (n then lies within rounding of a neighbouring
    // piece's minimiser: a vertex or a vertical edge beside a face), its vertices
    // nearest w = 0 instead: the hull's point there (the side is round across, so the
    // cylinder's point along -n is off it only to second order).
    const float il = 1.0f / std::sqrt(nxy2);
    const float wx = -n[1] * il, wy = n[0] * il;
    float zlo = kBig, zhi = -kBig, wmin = kBig, wmax = -kBig;
    for (uint32_t i = 0; i < nfeat; ++i) {
      const float* p = yv[feat[i]];
      const float wi = wx * p[0] + wy * p[1];
      wmin = simd::fmin_nn(wmin, wi), wmax = simd::fmax_nn(wmax, wi);
      for (uint32_t j = i; j < nfeat; ++j) {
        const float* r = yv[feat[j]];
        const float wj = wx * r[0] + wy * r[1];
        if ((wi <= 0.0f && wj >= 0.0f) || (wi >= 0.0f && wj <= 0.0f)) {
          const float t = wi == wj ? 0.0f : wi / (wi - wj);
          const float z = p[2] + t * (r[2] - p[2]);
          zlo = simd::fmin_nn(zlo, z), zhi = simd::fmax_nn(zhi, z);
        }
      }
    }
    auto clamp_h = [hh](float z) { return z < -hh ? -hh : (z > hh ? hh : z); };
    if (zlo <= zhi) {
      xb[0] = -rc * n[0] * il, xb[1] = -rc * n[1] * il, xb[2] = 0.5f * (clamp_h(zlo) + clamp_h(zhi));
      for (int j = 0; j < 3; ++j) xa[j] = xb[j] + o * n[j];
    } else {
      const float wnear = wmin > 0.0f ? wmin : wmax;
      const float* lo = nullptr;
      const float* hi = nullptr;
      for (uint32_t i = 0; i < nfeat; ++i) {
        const float* p = yv[feat[i]];
        if (std::fabs(wx * p[0] + wy * p[1] - wnear) > tol) continue;
        if (lo == nullptr || p[2] < lo[2]) lo = p;
        if (hi == nullptr || p[2] > hi[2]) hi = p;
      }
      const float zm = 0.5f * (clamp_h(lo[2]) + clamp_h(hi[2]));
      const float t = hi[2] > lo[2] ? (zm - lo[2]) / (hi[2] - lo[2]) : 0.0f;
      for (int j = 0; j < 3; ++j) xa[j] = lo[j] + t * (hi[j] - lo[j]), xb[j] = xa[j] - o * n[j];
    }
  } else {
    // a cap against the feature: the feature's centroid where it lies over the disk,
    // else the rim point towards it
    const float c2 = cen[0] * cen[0] + cen[1] * cen[1];
    if (c2 <= rc * rc) {
      for (int j = 0; j < 3; ++j) xa[j] = cen[j], xb[j] = xa[j] - o * n[j];
    } else {
      const float sc = rc / std::sqrt(c2);
      xb[0] = cen[0] * sc, xb[1] = cen[1] * sc, xb[2] = n[2] >= 0.0f ? -hh : hh;
      for (int j = 0; j < 3; ++j) xa[j] = xb[j] + o * n[j];
    }
  }
  // Back to the world frame, relative to A's position (the general route's origin).
  const float* rb = lv.rb;
  const float* pc = lv.pc;  // the cylinder's centre
  float nw[3], pa[3], pb[3];
  for (int i = 0; i < 3; ++i) {
    nw[i] = rb[3 * i] * n[0] + rb[3 * i + 1] * n[1] + rb[3 * i + 2] * n[2];
    pa[i] = rb[3 * i] * xa[0] + rb[3 * i + 1] * xa[1] + rb[3 * i + 2] * xa[2] + pc[i];
    pb[i] = rb[3 * i] * xb[0] + rb[3 * i + 1] * xb[1] + rb[3 * i + 2] * xb[2] + pc[i];
  }
  const cvx::V3 origin{A.p[0][k], A.p[1][k], A.p[2][k]};
  const cvx::Leaf la = cvx::load_leaf(A, k, kLeafConvex, &h, origin);
  const cvx::Leaf lb = cvx::load_leaf(B, k, kLeafCylinder, &h, origin);
  cvx::LaneContact lc;
  cvx::contact_manifold(la, lb, cvx::V3{nw[0], nw[1], nw[2]}, o, cvx::V3{pa[0], pa[1], pa[2]},
                        cvx::V3{pb[0], pb[1], pb[2]}, &lc);
  cvx::write_lane(out, k, lc, origin);
}

template <class F>
void convex_cylinder_range(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, Range r,
                           const NarrowConfig& cfg) {
  Scratch<F::kWidth> scratch;
  Queue<F::kWidth> q;
  Live live[kChunk];
  for (uint32_t k0 = r.begin; k0 < r.end; k0 += kChunk) {
    const uint32_t k1 = r.end - k0 < kChunk ? r.end : k0 + kChunk;
    uint32_t nl = 0;
    for (uint32_t k = k0; k < k1; ++k) {
      const State st = convex_cylinder_pair<F>(a, b, out, k, cfg.hulls, scratch, live[nl], nl, q, live);
      if (st == State::kLive) {
        ++nl;
      } else if (st == State::kGeneral) {
        collide_gjk_epa(a, b, out, Range{k, k + 1}, cfg, kLeafConvex, kLeafCylinder);
      }
    }
    if (q.n > 0) flush<F>(q, live);
    for (uint32_t i = 0; i < nl; ++i) finish_pair<F>(a, b, out, cfg.hulls, live[i]);
  }
}

}  // namespace

void collide_convex_cylinder(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, Range r,
                             const NarrowConfig& cfg) {
  if (cfg.path == KernelPath::kScalar) {
    convex_cylinder_range<simd::Float1>(a, b, out, r, cfg);
  } else {
    convex_cylinder_range<simd::FloatW>(a, b, out, r, cfg);
  }
}

}  // namespace impact::kernels
