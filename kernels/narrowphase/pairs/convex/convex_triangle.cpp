// Convex hull (A) against triangle (B): the exact separating axis test in the hull's
// frame, no GJK / EPA.
//
// What: collide_convex_triangle writes, per lane k in r, the collision data of leaf.h for
// a convex hull (pose p, R; hull ref in cfg.hulls) and a triangle (p = v0, w = v1, v2;
// zero thickness, both sides solid): count 0..4, unit normal n from the hull to the
// triangle (the triangle moves along n by depth to separate), depth = the smallest such
// translation, points midway between the two surfaces with their own depths. Slots past
// count are untouched; count 0 lanes leave everything else unspecified.
// Method, per lane (D. Gregorius, "The Separating Axis Test between Convex Polyhedra",
// GDC 2013; a triangle is a flat polytope: faces +-N, three edges, three vertices), in
// the hull's local frame (the triangle's vertices transformed once):
//  1. One pass over the hull's vertices (kSimdWidth per step): the hull's extent along
//     the triangle's unit normal (separations along +N and -N, exact supports on both
//     sides) and along the line from the hull's origin to the triangle's centroid (a
//     cheap separating axis that stops ~20% of the bench's lanes). Separated or touching
//     (separation >= 0) on any axis: count 0.
//  2. One pass over the hull's face planes (kSimdWidth faces per step): min over the
//     triangle's three vertices of fn.v - fd, the largest (lowest index among ties).
//  3. Edge axes (hull edge a x triangle edge f_j, one pass over the hull's edge list,
//     kSimdWidth edges per step): the pair forms a face of the Minkowski difference only
//     where the great circle perpendicular to f_j crosses edge a's normal arc (the arc
//     between its two faces' normals: bisector m, half angle theta in HullView; the arc
//     crosses iff |m.f| cos(theta) <= |(m x e).f| sin(theta) / |e|); the triangle side's
//     arc (the half circle from +N through the edge's outward normal to -N) is not
//     tested: the separation is taken with the triangle's exact support instead (the
//     lesser of n.v_j and n.v_opposite), so a pair that fails it only scores lower. The
//     axis is L = e x f_j oriented along m; with K = p_a x e, G_j = f_j x v_j and N =
//     (v1 - v0) x (v2 - v0), L.(v_j - p_a) = e.G_j - f_j.K and the opposite vertex adds
//     e.N; dot products with f_2 come from f_0's and f_1's (f_2 = -(f_0 + f_1)).
//     Candidates are ranked without roots by k |k| / |L|^2 (k = separation |L| less a
//     rounding band kEdgeRound (size + coordinates) |e| |f_j|), and by separation |s|.
//     Edge pairs within 1e-6 rad of parallel and triangle edges shorter than 1e-6 of the
//     coordinates get no axis (their Minkowski faces are slivers beside other axes').
//     Blocks of edges whose cone bound (for n in the cone, the separation is at most
//     min over the triangle's vertices v of n.(v - p_a) <= max(m.d, cos m.d) + sin |d|,
//     as sat.cpp's) cannot beat the best face are skipped (~half the bench's blocks).
//  4. Feature choice (tie rule as box-triangle): the triangle's normal beats the hull's
//     best face only by more than 1e-5 |separation| + 1e-6 size, an edge axis the best
//     face only when its key does (the key carries its own rounding band); the winning
//     edge axis is computed again in double (exact products of the float inputs), and
//     its separation there is the depth. A candidate of positive separation is
//     confirmed against the exact supports along its axis (count 0), or, if not
//     confirmed (rounding noise of a nearly parallel pair that could hide another), the
//     lane goes to GJK / EPA.
//  5. Points: a hull face wins: the triangle clipped by the face's side planes
//     (Sutherland-Hodgman), the points below the face, midway between the triangle and
//     the face plane; the triangle's normal wins: the hull face most aligned with n,
//     clipped by the triangle's side planes, the points beyond the triangle's plane;
//     where no point carries the depth (within cvx::kWitnessJoin), the deepest vertex of
//     the incident side (the triangle's, or the hull's) joins them if it lies within
//     the reference face's side planes (the clip misses it when the depth comes from a
//     vertex beyond the clipped face: deep pairs);
//     reduced to 4 (deepest, farthest, largest area: cvx::reduce_manifold); nothing left
//     after rounding (grazing): one point, at the incident side's deepest vertex or at
//     the clipped polygon's deepest point, whichever lies nearer the reference side
//     (that vertex can lie outside the reference face: touching pairs at a face's
//     rim); a face of more than 256 vertices: at that vertex. An edge axis wins: one
//     point midway between the closest points of hull edge a and the triangle's
//     support feature along -n (edge j, or a vertex, or
//     the longest edge of a collinear triangle), where those are depth apart along n;
//     else (a winner among nearly tied axes, e.g. a triangle edge nearly parallel to a
//     hull face) the middle of the part of that feature, moved by depth along n, that
//     lies within rounding of every face plane (where it touches the hull).
// Inputs: lanes per leaf.h (finite, R orthonormal), hulls as HullStore builds them
// (unit outward face normals, counter-clockwise polygons, edge adjacency padded to
// kHullEdgePad).
// Hulls without faces or edge adjacency in HullView go through GJK / EPA (this lane).
// Degenerate triangles: the set of points is what counts, as for GJK / EPA. A collinear
// triangle (or two coincident vertices) is a segment: the hull faces and hull edge x
// segment axes give its exact answer (its normal axes, where rounding leaves a normal,
// are valid axes too and never beat the true ones); three coincident vertices: a point
// (hull faces only). Exact zero area: no normal axes.
// Precision: face and vertex passes in float (~1e-7 of the local coordinates); the
// winning edge axis in double; depth within ~2e-7 of the size on the tests' random
// poses, ~5e-6 at worst where edge axes tie within the rounding band (asserted 1e-5 L,
// normals 1e-4 rad where unique, against a brute-force double SAT).
// No division without a guard: no NaN for finite input. No allocation (stack buffers:
// the clip polygons, 2 x 260 points, and the manifold, 261).
// Paths: cfg.path kSimd runs the hull passes kSimdWidth faces / vertices / edges per
// step, kScalar the same code one at a time (F = simd::Float1): the same formulas and
// tie rules (bytes may differ where the two fuse multiply-adds differently and nearly
// tied candidates go either way; identical on the tests' random lanes); the
// one-lane build (IMPACT_SIMD_SCALAR) runs both one at a time. One pair per iteration.
// Cost: O(V) for lanes the centre line or the triangle's normal separates (they stop
// after the vertex pass), O(V + F) for those a hull face separates, O(V + F + E) for the
// rest (the edge pass, about half its blocks skipped by the bound). Measured per pair,
// with the split by pass, in docs/results.md ("Narrow phase") and docs/history.md.
#include <cfloat>
#include <cmath>
#include <cstdint>

#include "kernels/narrowphase/general/face_manifold.h"
#include "kernels/narrowphase/general/gjk_epa.h"
#include "kernels/narrowphase/general/hull_scan.h"
#include "kernels/narrowphase/pair_kernels.h"
#include "kernels/simd/lanes.h"

namespace impact::kernels {
namespace {

using cvx::cross;
using cvx::dot;
using cvx::V3;

/// Tie rule (as box-triangle, box_triangle.cpp): the triangle's normal beats
/// the best hull face, and an edge axis the best face, only when it separates more by
/// kTieRel * |separation| + kTieSize * size; an edge axis also by its own rounding,
/// kEdgeRound * (size + |coordinates|) / sin(angle of the two edges).
constexpr float kTieRel = 1e-5f;
constexpr float kTieSize = 1e-6f;
constexpr float kEdgeRound = 2e-7f;
/// Edge pairs within asin(1e-6) of parallel are skipped: their Minkowski face is a
/// sliver whose neighbours (other axes of the test) hold the depth to ~1e-6 of the size.
constexpr float kEdgeSkipSq = 1e-12f;
/// Triangle edges shorter than this times the local coordinates' magnitude get no axes.
constexpr float kTinyEdge = 1e-6f;
/// The float pass's key of the best edge axis is within this times (size + coordinates)
/// of the double one (only a near-winner is computed again in double).
constexpr float kKeySlack = 1e-4f;
/// An edge contact's point: the triangle's feature moved by depth along n touches the
/// hull within this times (size + coordinates) of its face planes.
constexpr float kTouchSlack = 2e-6f;
/// Clip buffers: a face polygon of up to kMaxFaceVerts vertices clipped by a triangle
/// (or a triangle by such a face) has at most kMaxFaceVerts + 3 vertices. 256: a cylinder
/// or disk approximated by up to 256 segments keeps its clipped manifold (at 64, an
/// 80-gon cap lying on a triangle got one point, at the hull's deepest vertex, which
/// can lie outside the triangle); ~10 KB of stack per lane, untouched unless clipped.
constexpr uint32_t kMaxFaceVerts = 256;
constexpr uint32_t kMaxClip = kMaxFaceVerts + 4;

IMPACT_INLINE float l1(V3 a) {
  return std::fabs(a.x) + std::fabs(a.y) + std::fabs(a.z);
}
IMPACT_INLINE V3 vertex(const HullView& h, uint32_t i) {
  return V3{h.vx[i], h.vy[i], h.vz[i]};
}
IMPACT_INLINE V3 face_normal(const HullView& h, uint32_t f) {
  return V3{h.fnx[f], h.fny[f], h.fnz[f]};
}

/// Block starts of a W-wide pass over [0, n), n >= W: 0, W, ..., and n - W for the last
/// (overlapping) block, which revisits items: harmless for min / max and for an argmax
/// that keeps the lowest index among ties.
template <uint32_t W>
IMPACT_INLINE uint32_t next_block(uint32_t i, uint32_t n) {
  return i + 2 * W <= n ? i + W : n - W;
}

template <class F>
IMPACT_INLINE float lanes_max(F v) {
  float m = v.lane(0);
  for (uint32_t l = 1; l < F::kWidth; ++l) m = simd::fmax_nn(m, v.lane(l));
  return m;
}
template <class F>
IMPACT_INLINE float lanes_min(F v) {
  float m = v.lane(0);
  for (uint32_t l = 1; l < F::kWidth; ++l) m = simd::fmin_nn(m, v.lane(l));
  return m;
}

/// The triangle in the hull's frame.
struct Tri {
  V3 v[3];
  V3 f[3];                    // edge j = v[j + 1] - v[j]
  float ff[3], fl[3];         // |f_j|^2, |f_j|
  float gx[3], gy[3], gz[3];  // f_j x v_j
  V3 nraw;                    // (v1 - v0) x (v2 - v0): twice the area times the unit normal
};

// ---------------------------------------------------------------------------------------
// Passes over the hull, W = F::kWidth items per step
// ---------------------------------------------------------------------------------------

/// Over the hull's vertices (n of them, n >= W): max and min of a.x, max of u.x.
template <class F>
IMPACT_INLINE void vertex_pass(const float* vx, const float* vy, const float* vz, uint32_t n, V3 a, V3 u,
                               float* amax, float* amin, float* umax) {
  constexpr uint32_t W = F::kWidth;
  const F ax(a.x), ay(a.y), az(a.z), ux(u.x), uy(u.y), uz(u.z);
  F mx(-INFINITY), mn(INFINITY), mu(-INFINITY);
  for (uint32_t i = 0;; i = next_block<W>(i, n)) {
    const F x = F::load(vx + i), y = F::load(vy + i), z = F::load(vz + i);
    const F s = ax * x + ay * y + az * z;
    mx = simd::max(mx, s);
    mn = simd::min(mn, s);
    mu = simd::max(mu, ux * x + uy * y + uz * z);
    if (i + W == n) break;
  }
  *amax = lanes_max(mx);
  *amin = lanes_min(mn);
  *umax = lanes_max(mu);
}

/// Over the hull's vertices (n >= W): the index of the largest a.x (lowest among ties).
template <class F>
IMPACT_INLINE uint32_t vertex_argmax(const float* vx, const float* vy, const float* vz, uint32_t n, V3 a) {
  constexpr uint32_t W = F::kWidth;
  const F ax(a.x), ay(a.y), az(a.z), lane = simd::lane_index<F>();
  F m(-INFINITY), mi(0.0f);
  for (uint32_t i = 0;; i = next_block<W>(i, n)) {
    const F s = ax * F::load(vx + i) + ay * F::load(vy + i) + az * F::load(vz + i);
    const auto g = s > m;
    m = simd::select(g, s, m);
    mi = simd::select(g, lane + F(static_cast<float>(i)), mi);
    if (i + W == n) break;
  }
  float bi;
  simd::max_lowest_index(m, mi, static_cast<float>(n), &bi);
  return static_cast<uint32_t>(bi);
}

struct FacePass {
  float sep = -INFINITY;  // max over faces of (min over the triangle's vertices of fn.v) - fd
  uint32_t face = 0;      // its face (hull-local index, the lowest among ties)
  float dmax = 0.0f;      // max |fd|: the hull's size
};

/// Over faces [0, n) of the hull's face arrays (already offset), n >= W.
template <class F>
IMPACT_INLINE FacePass face_pass(const float* fnx, const float* fny, const float* fnz, const float* fd,
                                 uint32_t n, const Tri& T) {
  constexpr uint32_t W = F::kWidth;
  const F lane = simd::lane_index<F>();
  const F x0(T.v[0].x), y0(T.v[0].y), z0(T.v[0].z), x1(T.v[1].x), y1(T.v[1].y), z1(T.v[1].z), x2(T.v[2].x),
      y2(T.v[2].y), z2(T.v[2].z);
  F m(-INFINITY), mi(0.0f), dm(0.0f);
  for (uint32_t i = 0;; i = next_block<W>(i, n)) {
    const F nx = F::load(fnx + i), ny = F::load(fny + i), nz = F::load(fnz + i), d = F::load(fd + i);
    const F a0 = nx * x0 + ny * y0 + nz * z0, a1 = nx * x1 + ny * y1 + nz * z1,
            a2 = nx * x2 + ny * y2 + nz * z2;
    const F s = simd::min(a0, simd::min(a1, a2)) - d;
    const auto g = s > m;
    m = simd::select(g, s, m);
    mi = simd::select(g, lane + F(static_cast<float>(i)), mi);
    dm = simd::max(dm, simd::abs(d));
    if (i + W == n) break;
  }
  FacePass fp;
  float bi;
  fp.sep = simd::max_lowest_index(m, mi, static_cast<float>(n), &bi);
  fp.face = static_cast<uint32_t>(bi);
  fp.dmax = lanes_max(dm);
  return fp;
}

/// Over faces [0, n) (n >= W): the index of the largest fn.a (lowest among ties).
template <class F>
IMPACT_INLINE uint32_t face_argmax(const float* fnx, const float* fny, const float* fnz, uint32_t n, V3 a) {
  return vertex_argmax<F>(fnx, fny, fnz, n, a);
}

/// The part [*lo, *hi] of the segment p + t d, t in [0, 1], within `slack` of every face
/// plane of [0, n) (n >= W): Cyrus-Beck, fn.(p + t d) - fd - slack <= 0 bounds t from
/// above where fn.d > 0, from below where fn.d < 0. Empty: *lo > *hi.
template <class F>
IMPACT_INLINE void clip_segment(const float* fnx, const float* fny, const float* fnz, const float* fd,
                                uint32_t n, V3 p, V3 d, float slack, float* lo, float* hi) {
  constexpr uint32_t W = F::kWidth;
  const F zero(0.0f), one(1.0f), px(p.x), py(p.y), pz(p.z), dx(d.x), dy(d.y), dz(d.z), sl(slack);
  F tlo(0.0f), thi(1.0f);
  for (uint32_t i = 0;; i = next_block<W>(i, n)) {
    const F nx = F::load(fnx + i), ny = F::load(fny + i), nz = F::load(fnz + i);
    const F a = nx * px + ny * py + nz * pz - F::load(fd + i) - sl, b = nx * dx + ny * dy + nz * dz;
    const auto pos = b > zero, neg = b < zero;
    const F cut = -a / simd::select(pos | neg, b, one);
    thi = simd::select(pos, simd::min(thi, cut), thi);
    tlo = simd::select(neg, simd::max(tlo, cut), tlo);
    tlo = simd::select(andnot(a > zero, pos | neg), F(INFINITY), tlo);  // parallel and outside
    if (i + W == n) break;
  }
  *lo = lanes_max(tlo);
  *hi = lanes_min(thi);
}

struct EdgeBest {
  float q = -INFINITY;    // key |key| of the candidate of largest key (-inf: none)
  uint32_t edge = 0;      // its hull edge (adjacency index relative to the hull's first)
  uint32_t tri_edge = 0;  // its triangle edge
  float qs = -INFINITY;   // s |s| of the candidate of largest separation s
  uint32_t sep_edge = 0, sep_tri_edge = 0;
};

/// The edge axes: every hull edge (adjacency list [0, ne), padded to kHullEdgePad)
/// against the triangle's three edges, W hull edges per step. A pair (a, j) is a
/// candidate when the great circle perpendicular to triangle edge f_j crosses hull edge
/// a's normal arc (the arc from bisector m within angle theta: the arc's two ends lie
/// on either side of the circle, |m.f| cos(theta) <= |w.f| sin(theta) / |e| with
/// w = m x e); the axis is then n = L / |L|, L = e x f oriented along m (sign of
/// m.L = w.f): hull edge a is the hull's support along n, so the separation is the
/// least of n.(v - p_a) over the triangle's vertices, of which v_j and the opposite
/// vertex suffice (v_j+1 projects as v_j). With K = p_a x e and G_j = f_j x v_j,
/// L.(v_j - p_a) = e.G_j - f_j.K, and at the opposite vertex e.N more (N = the
/// triangle's unnormalised normal: f_j x (v_opp - v_j) = N for every j); the dot
/// products with f_2 = -(f_0 + f_1) come from those with f_0 and f_1. The key is that
/// separation less its rounding (pen |f_j| / |L|, pen ~ |e|); candidates are ranked by
/// key |key| (monotone in the key, no square root): q = k |k| / |L|^2, k = key |L|, and
/// separately by their separation (qs = s |s|, for a separating axis).
/// Blocks whose every edge is ruled out by the bound min over the triangle's vertices v
/// of the max over the cone of n.(v - p_a) <= thr (the cone bound as sat.cpp's) are
/// skipped: no candidate of theirs beats thr (<= 0).
/// stop: return once a candidate's separation is positive (a separating axis, to be
/// confirmed by the caller).
template <class F>
IMPACT_INLINE EdgeBest edge_pass(const HullView& h, uint32_t eb, uint32_t ne, uint32_t vb, const Tri& T,
                                 float rs, float thr, bool stop, bool* stopped) {
  using I = typename F::Int;
  constexpr uint32_t W = F::kWidth;
  static_assert(kHullEdgePad % W == 0, "the edge walk loads whole blocks of the padded edge list");
  const F zero(0.0f), one(1.0f), skip(kEdgeSkipSq), RS(rs), TH(thr), step(static_cast<float>(4 * W));
  const F nx(T.nraw.x), ny(T.nraw.y), nz(T.nraw.z);
  const F f0x(T.f[0].x), f0y(T.f[0].y), f0z(T.f[0].z), f1x(T.f[1].x), f1y(T.f[1].y), f1z(T.f[1].z);
  // Lane constants, broadcast once.
  F vx[3], vy[3], vz[3], gx[3], gy[3], gz[3], ff[3], fl[3], jo[3];
  for (uint32_t j = 0; j < 3; ++j) {
    vx[j] = F(T.v[j].x), vy[j] = F(T.v[j].y), vz[j] = F(T.v[j].z);
    gx[j] = F(T.gx[j]), gy[j] = F(T.gy[j]), gz[j] = F(T.gz[j]);
    ff[j] = F(T.ff[j]), fl[j] = F(T.fl[j]), jo[j] = F(static_cast<float>(j));
  }
  const float* bx = h.vx + vb;
  const float* by = h.vy + vb;
  const float* bz = h.vz + vb;
  F best(-INFINITY), bidx(0.0f), sbest(-INFINITY), sidx(0.0f);
  F idx0 = simd::lane_index<F>() * F(4.0f);  // 4 x the edge index
  *stopped = false;
  for (uint32_t i = 0; i < ne; i += W, idx0 = idx0 + step) {
    const uint32_t g = eb + i;
    const F px = F::load(h.epx + g), py = F::load(h.epy + g), pz = F::load(h.epz + g);
    const F mx = F::load(h.emx + g), my = F::load(h.emy + g), mz = F::load(h.emz + g);
    const F c = F::load(h.ecos + g), s = F::load(h.esin + g), s2 = s * s;
    {
      // Bound: for n in the cone, the separation is at most n.(v - p) for each vertex v,
      // and n.d <= max(m.d, cos m.d) + sin |d| (without the root: r = thr - max(..),
      // the bound exceeds thr iff r < 0 or sin^2 |d|^2 > r^2).
      auto live = zero <= zero;
      for (uint32_t v = 0; v < 3; ++v) {
        const F dx = vx[v] - px, dy = vy[v] - py, dz = vz[v] - pz;
        const F md = mx * dx + my * dy + mz * dz, dd = dx * dx + dy * dy + dz * dz;
        const F r = TH - simd::max(md, c * md);
        live = live & ((r < zero) | (s2 * dd > r * r));
      }
      if (simd::none(live)) continue;
    }
    const I j1 = I::load(reinterpret_cast<const int32_t*>(h.ev1 + g));
    const F ex = simd::gather(bx, j1) - px, ey = simd::gather(by, j1) - py, ez = simd::gather(bz, j1) - pz;
    const F ee = ex * ex + ey * ey + ez * ez;
    const F wx = my * ez - mz * ey, wy = mz * ex - mx * ez, wz = mx * ey - my * ex;
    const F kx = py * ez - pz * ey, ky = pz * ex - px * ez, kz = px * ey - py * ex;
    const F en = ex * nx + ey * ny + ez * nz;
    const F pen = RS * (simd::abs(ex) + simd::abs(ey) + simd::abs(ez));  // >= rs |e|
    const F cee = c * c * ee, skee = skip * ee;
    // dot products with f_0, f_1 (f_2 = -(f_0 + f_1))
    const F mf0 = mx * f0x + my * f0y + mz * f0z, mf1 = mx * f1x + my * f1y + mz * f1z;
    const F wf0 = wx * f0x + wy * f0y + wz * f0z, wf1 = wx * f1x + wy * f1y + wz * f1z;
    const F ef0 = ex * f0x + ey * f0y + ez * f0z, ef1 = ex * f1x + ey * f1y + ez * f1z;
    const F kf0 = kx * f0x + ky * f0y + kz * f0z, kf1 = kx * f1x + ky * f1y + kz * f1z;
    const F mfs[3] = {mf0, mf1, -(mf0 + mf1)}, wfs[3] = {wf0, wf1, -(wf0 + wf1)};
    const F efs[3] = {ef0, ef1, -(ef0 + ef1)}, kfs[3] = {kf0, kf1, -(kf0 + kf1)};
    for (uint32_t j = 0; j < 3; ++j) {
      const F mf = mfs[j], wf = wfs[j], ef = efs[j];
      const auto arc = mf * mf * cee <= wf * wf * s2;
      const F ll = ee * ff[j] - ef * ef;  // |e x f_j|^2
      const F t0 = ex * gx[j] + ey * gy[j] + ez * gz[j] - kfs[j];
      const F t1 = t0 + en;  // at the opposite vertex
      const F sn = simd::select(wf < zero, -simd::max(t0, t1), simd::min(t0, t1));
      const F kn = sn - pen * fl[j];
      const auto ok = arc & (ll > skee * ff[j]);
      const F inv = one / simd::select(ok, ll, one);
      const F q = simd::select(ok, kn * simd::abs(kn) * inv, F(-INFINITY));
      const F qs = simd::select(ok, sn * simd::abs(sn) * inv, F(-INFINITY));
      const F idx = idx0 + jo[j];
      const auto gt = q > best, gs = qs > sbest;
      best = simd::select(gt, q, best);
      bidx = simd::select(gt, idx, bidx);
      sbest = simd::select(gs, qs, sbest);
      sidx = simd::select(gs, idx, sidx);
    }
    if (stop && simd::any(sbest > zero)) {
      *stopped = true;
      break;
    }
  }
  EdgeBest out;
  float bi;
  out.q = simd::max_lowest_index(best, bidx, INFINITY, &bi);
  out.edge = static_cast<uint32_t>(bi) / 4;
  out.tri_edge = static_cast<uint32_t>(bi) % 4;
  out.qs = simd::max_lowest_index(sbest, sidx, INFINITY, &bi);
  out.sep_edge = static_cast<uint32_t>(bi) / 4;
  out.sep_tri_edge = static_cast<uint32_t>(bi) % 4;
  return out;
}

// ---------------------------------------------------------------------------------------
// One edge axis, again in double
// ---------------------------------------------------------------------------------------

struct EdgeAxis {
  V3 n;       // unit, hull to triangle
  float sep;  // min over the triangle's vertices of n.v - n.p_a
  float key;  // sep less its rounding
  V3 pa, ea;  // the hull edge: start, vector
};

EdgeAxis edge_axis(const HullView& h, uint32_t g, uint32_t vb, const Tri& T, uint32_t j, float rs) {
  EdgeAxis ax;
  ax.pa = V3{h.epx[g], h.epy[g], h.epz[g]};
  ax.ea = vertex(h, vb + h.ev1[g]) - ax.pa;
  const double e[3] = {ax.ea.x, ax.ea.y, ax.ea.z};
  const double f[3] = {T.f[j].x, T.f[j].y, T.f[j].z};
  // L = e x f (exact products of floats), oriented along the bisector.
  double l[3] = {e[1] * f[2] - e[2] * f[1], e[2] * f[0] - e[0] * f[2], e[0] * f[1] - e[1] * f[0]};
  if (l[0] * h.emx[g] + l[1] * h.emy[g] + l[2] * h.emz[g] < 0.0)
    for (double& x : l) x = -x;
  // The separation times |L| (no root on this chain), then one root and one division.
  double sl = INFINITY;
  for (const V3& v : T.v) {
    const double s = l[0] * (static_cast<double>(v.x) - ax.pa.x) +
                     l[1] * (static_cast<double>(v.y) - ax.pa.y) +
                     l[2] * (static_cast<double>(v.z) - ax.pa.z);
    sl = s < sl ? s : sl;
  }
  const double ll = l[0] * l[0] + l[1] * l[1] + l[2] * l[2];
  const double ef =
      std::sqrt((e[0] * e[0] + e[1] * e[1] + e[2] * e[2]) * (f[0] * f[0] + f[1] * f[1] + f[2] * f[2]));
  const double inv = 1.0 / std::sqrt(ll);
  ax.n = V3{static_cast<float>(l[0] * inv), static_cast<float>(l[1] * inv), static_cast<float>(l[2] * inv)};
  ax.sep = static_cast<float>(sl * inv);
  ax.key = static_cast<float>((sl - rs * ef) * inv);
  return ax;
}

/// Closest points of segments p1 + s d1 and p2 + t d2, s, t in [0, 1] (Ericson 5.1.9).
void closest_segments(V3 p1, V3 d1, V3 p2, V3 d2, V3* c1, V3* c2) {
  const V3 r = p1 - p2;
  const float a = dot(d1, d1), e = dot(d2, d2), f = dot(d2, r), c = dot(d1, r), b = dot(d1, d2);
  const auto clamp01 = [](float x) { return simd::fmin_nn(simd::fmax_nn(x, 0.0f), 1.0f); };
  const float denom = a * e - b * b;
  float s = denom > 1e-12f * a * e ? clamp01((b * f - c * e) / denom) : 0.0f;
  float t = e > 0.0f ? (b * s + f) / e : 0.0f;
  if (t < 0.0f) {
    t = 0.0f;
    s = a > 0.0f ? clamp01(-c / a) : 0.0f;
  } else if (t > 1.0f) {
    t = 1.0f;
    s = a > 0.0f ? clamp01((b - c) / a) : 0.0f;
  }
  *c1 = p1 + d1 * s;
  *c2 = p2 + d2 * t;
}

// ---------------------------------------------------------------------------------------
// Face manifold
// ---------------------------------------------------------------------------------------

/// Keeps the part of polygon in[0, n) with o.x <= od (Sutherland-Hodgman, one plane).
uint32_t clip_plane(const V3* in, uint32_t n, V3 o, float od, V3* out) {
  uint32_t m = 0;
  for (uint32_t i = 0; i < n; ++i) {
    const V3 p = in[i], q = in[i + 1 == n ? 0 : i + 1];
    const float dp = dot(o, p) - od, dq = dot(o, q) - od;
    if (dp <= 0.0f) out[m++] = p;
    if ((dp < 0.0f && dq > 0.0f) || (dp > 0.0f && dq < 0.0f)) out[m++] = p + (q - p) * (dp / (dp - dq));
  }
  return m;
}

struct Manifold {
  uint32_t count = 0;
  V3 p[kMaxClip + 1];
  float d[kMaxClip + 1];

  /// The deepest point so far.
  float deepest() const {
    float m = 0.0f;
    for (uint32_t i = 0; i < count; ++i) m = simd::fmax_nn(m, d[i]);
    return m;
  }
};

/// Reference face f of the hull (n = its normal): the triangle clipped by the face's
/// side planes; points below the face plane, midway between the triangle and the plane.
/// Then (cvx::kWitnessJoin) the triangle's deepest vertex wit, where it is inside the
/// side planes. *graze (where no point is below the plane): the one point of a grazing
/// contact, left as wit (the caller's) or set to the clipped triangle's deepest point,
/// whichever lies nearer the hull: wit's distance outside the side planes against that
/// point's height above the plane.
void hull_face_manifold(const HullView& h, uint32_t f, const Tri& T, float depth, V3 wit, Manifold* mf,
                        V3* graze) {
  const uint32_t b = h.face_vert_begin[f], e = h.face_vert_begin[f + 1];
  if (e - b < 3 || e - b > kMaxFaceVerts) return;
  const V3 n = face_normal(h, f);
  V3 buf[2][kMaxClip];
  uint32_t cnt = 3;
  for (uint32_t i = 0; i < 3; ++i) buf[0][i] = T.v[i];
  uint32_t cur = 0;
  V3 a = vertex(h, h.face_verts[e - 1]);
  for (uint32_t i = b; i < e && cnt > 0; ++i) {
    const V3 q = vertex(h, h.face_verts[i]);
    const V3 o = cross(q - a, n);  // out of the polygon (counter-clockwise from outside)
    cnt = clip_plane(buf[cur], cnt, o, dot(o, a), buf[1 - cur]);
    cur = 1 - cur;
    a = q;
  }
  const float fd = h.fd[f];
  const auto keep = [&](V3 x) {
    const float s = fd - dot(n, x);
    if (!(s > 0.0f)) return;
    const float pd = simd::fmin_nn(s, depth);
    mf->p[mf->count] = x + n * (0.5f * pd);
    mf->d[mf->count] = pd;
    ++mf->count;
  };
  float smax = -INFINITY;
  V3 top = wit;
  for (uint32_t i = 0; i < cnt; ++i) {
    keep(buf[cur][i]);
    const float s = fd - dot(n, buf[cur][i]);
    if (s > smax) smax = s, top = buf[cur][i];
  }
  // wit against the side planes, walked once where needed: inside every one, and its
  // largest distance outside one (0 inside).
  bool walked = false, inside = true;
  float out = 0.0f;
  const auto walk = [&] {
    if (walked) return;
    walked = true;
    V3 p = vertex(h, h.face_verts[e - 1]);
    for (uint32_t i = b; i < e; ++i) {
      const V3 q = vertex(h, h.face_verts[i]);
      const V3 o = cross(q - p, n);
      inside = inside && dot(o, wit) <= dot(o, p);
      const float oo = dot(o, o);
      if (oo > 0.0f) out = simd::fmax_nn(out, dot(o, wit - p) / std::sqrt(oo));
      p = q;
    }
  };
  if (mf->count == 0 && cnt > 0) {
    walk();
    if (-smax < out) *graze = top;
  }
  if (!(mf->deepest() < depth * (1.0f - cvx::kWitnessJoin))) return;
  walk();
  if (inside) keep(wit);
}

/// Reference face: the triangle (n = +-its normal, hull to triangle); incident: hull face
/// g, clipped by the triangle's side planes; points beyond the triangle's plane, midway.
/// Then (cvx::kWitnessJoin) the hull's deepest vertex wit, where it is inside the side
/// planes. *graze: as hull_face_manifold's (wit or the clipped face's deepest point).
void triangle_face_manifold(const HullView& h, uint32_t g, const Tri& T, V3 n, float depth, V3 wit,
                            Manifold* mf, V3* graze) {
  const uint32_t b = h.face_vert_begin[g], e = h.face_vert_begin[g + 1];
  if (e - b < 3 || e - b > kMaxFaceVerts) return;
  V3 buf[2][kMaxClip];
  uint32_t cnt = e - b;
  for (uint32_t i = b; i < e; ++i) buf[0][i - b] = vertex(h, h.face_verts[i]);
  uint32_t cur = 0;
  bool inside = true;  // wit
  float out = 0.0f;    // wit's distance outside the side planes
  for (uint32_t j = 0; j < 3; ++j) {
    const V3 a = T.v[j], q = T.v[j == 2 ? 0 : j + 1], opp = T.v[j == 0 ? 2 : j - 1];
    V3 o = cross(q - a, T.nraw);  // out of the triangle for counter-clockwise about nraw
    if (dot(o, opp - a) > 0.0f) o = -o;
    inside = inside && dot(o, wit) <= dot(o, a);
    const float oo = dot(o, o);
    if (oo > 0.0f) out = simd::fmax_nn(out, dot(o, wit - a) / std::sqrt(oo));
    if (cnt == 0) continue;
    cnt = clip_plane(buf[cur], cnt, o, dot(o, a), buf[1 - cur]);
    cur = 1 - cur;
  }
  const float nd = dot(n, T.v[0]);
  const auto keep = [&](V3 x) {
    const float s = dot(n, x) - nd;
    if (!(s > 0.0f)) return;
    const float pd = simd::fmin_nn(s, depth);
    mf->p[mf->count] = x - n * (0.5f * pd);
    mf->d[mf->count] = pd;
    ++mf->count;
  };
  float smax = -INFINITY;
  V3 top = wit;
  for (uint32_t i = 0; i < cnt; ++i) {
    keep(buf[cur][i]);
    const float s = dot(n, buf[cur][i]) - nd;
    if (s > smax) smax = s, top = buf[cur][i];
  }
  if (mf->count == 0 && cnt > 0 && -smax < out) *graze = top;
  if (inside && mf->deepest() < depth * (1.0f - cvx::kWitnessJoin)) keep(wit);
}

// ---------------------------------------------------------------------------------------
// One lane
// ---------------------------------------------------------------------------------------

template <class F>
void convex_triangle_lane(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, uint32_t k,
                          const NarrowConfig& cfg) {
  constexpr uint32_t W = F::kWidth;
  using F1 = simd::Float1;
  const HullView& h = cfg.hulls;
  const uint32_t hull = a.ref[k];
  const uint32_t fb = h.face_begin != nullptr ? h.face_begin[hull] : 0u;
  const uint32_t fe = h.face_begin != nullptr ? h.face_begin[hull + 1] : 0u;
  const uint32_t eb = h.adj_begin != nullptr ? h.adj_begin[hull] : 0u;
  const uint32_t ee = h.adj_begin != nullptr ? h.adj_begin[hull + 1] : 0u;
  if (fe == fb || ee == eb) {  // no faces or no edge adjacency: the general path, this lane
    collide_gjk_epa(a, b, out, Range{k, k + 1}, cfg, kLeafConvex, kLeafTriangle);
    return;
  }
  const uint32_t vb = h.vert_begin[hull], nv = h.vert_begin[hull + 1] - vb, nf = fe - fb;
  const V3 pw{a.p[0][k], a.p[1][k], a.p[2][k]};
  V3 ax[3];  // hull axes (R's columns)
  for (int col = 0; col < 3; ++col) ax[col] = V3{a.r[col][k], a.r[3 + col][k], a.r[6 + col][k]};
  const auto to_local = [&](float x, float y, float z) {
    const V3 d{x - pw.x, y - pw.y, z - pw.z};
    return V3{dot(ax[0], d), dot(ax[1], d), dot(ax[2], d)};
  };
  Tri T;
  T.v[0] = to_local(b.p[0][k], b.p[1][k], b.p[2][k]);
  T.v[1] = to_local(b.w[0][k], b.w[1][k], b.w[2][k]);
  T.v[2] = to_local(b.w[3][k], b.w[4][k], b.w[5][k]);
  // Edges: f_2 = -(f_0 + f_1) (the edge pass derives its dot products so). An edge
  // within 1e-6 of the coordinates of zero length is rounding noise in direction (two
  // coincident vertices, after the transform): it gets no axes (the ones it would give
  // are slivers of the Minkowski difference, within its length of their neighbours).
  const float cmag = simd::fmax_nn(l1(T.v[0]), simd::fmax_nn(l1(T.v[1]), l1(T.v[2])));
  const float tiny2 = (kTinyEdge * cmag) * (kTinyEdge * cmag);
  T.f[0] = T.v[1] - T.v[0];
  T.f[1] = T.v[2] - T.v[1];
  for (uint32_t j = 0; j < 2; ++j)
    if (!(dot(T.f[j], T.f[j]) > tiny2)) T.f[j] = V3{0, 0, 0};
  T.f[2] = -(T.f[0] + T.f[1]);
  float fmax = 0.0f;
  for (uint32_t j = 0; j < 3; ++j) {
    const V3 g = cross(T.f[j], T.v[j]);
    const float ff = dot(T.f[j], T.f[j]);
    T.ff[j] = ff > tiny2 ? ff : 0.0f;
    T.fl[j] = std::sqrt(T.ff[j]);
    T.gx[j] = g.x, T.gy[j] = g.y, T.gz[j] = g.z;
    fmax = simd::fmax_nn(fmax, T.fl[j]);
  }
  T.nraw = cross(T.v[1] - T.v[0], T.v[2] - T.v[0]);
  const auto no_contact = [&]() { out.count[k] = 0; };

  // --- 1. the triangle's normal (both signs) and the line from the hull's origin to the
  // triangle's centroid: one pass over the hull's vertices ---
  const float n2 = dot(T.nraw, T.nraw);
  const bool has_normal = n2 > 0.0f;
  const V3 nu = has_normal ? T.nraw * (1.0f / std::sqrt(n2)) : V3{0, 0, 1};
  const V3 cen = (T.v[0] + T.v[1] + T.v[2]) * (1.0f / 3.0f);
  const float c2 = dot(cen, cen);
  const V3 cu = c2 > 0.0f ? cen * (1.0f / std::sqrt(c2)) : V3{0, 0, 1};
  float hmax, hmin, cmax;
  if (nv >= W)
    vertex_pass<F>(h.vx + vb, h.vy + vb, h.vz + vb, nv, nu, cu, &hmax, &hmin, &cmax);
  else
    vertex_pass<F1>(h.vx + vb, h.vy + vb, h.vz + vb, nv, nu, cu, &hmax, &hmin, &cmax);
  float tmin = INFINITY, tmax = -INFINITY, cmin = INFINITY;
  for (const V3& v : T.v) {
    const float s = dot(nu, v), sc = dot(cu, v);
    tmin = simd::fmin_nn(tmin, s), tmax = simd::fmax_nn(tmax, s), cmin = simd::fmin_nn(cmin, sc);
  }
  if (!(cmin - cmax < 0.0f)) return no_contact();
  const float s_np = has_normal ? tmin - hmax : -INFINITY;  // n = +nu
  const float s_nm = has_normal ? hmin - tmax : -INFINITY;  // n = -nu
  if (!(s_np < 0.0f) || !(s_nm < 0.0f)) return no_contact();

  // --- 2. the hull's faces ---
  const FacePass fp = nf >= W ? face_pass<F>(h.fnx + fb, h.fny + fb, h.fnz + fb, h.fd + fb, nf, T)
                              : face_pass<F1>(h.fnx + fb, h.fny + fb, h.fnz + fb, h.fd + fb, nf, T);
  if (!(fp.sep < 0.0f)) return no_contact();
  const float size = fp.dmax + fmax;
  const float tie_size = kTieSize * size;
  // The better face axis: the hull's face unless the triangle's normal beats it.
  const float s_n = simd::fmax_nn(s_np, s_nm);
  const bool tri_face = s_n > fp.sep + kTieRel * std::fabs(fp.sep) + tie_size;
  float s_best = tri_face ? s_n : fp.sep;
  const float s_top = simd::fmax_nn(s_n, fp.sep);

  // --- 3. edge axes ---
  const float rs = kEdgeRound * (size + l1(T.v[0]) + l1(T.v[1]) + l1(T.v[2]));
  // A candidate of positive separation: confirmed by the exact supports along its
  // axis (in double), the pair is apart; else that candidate was rounding noise (a
  // nearly parallel edge pair) that may hide another: the lane goes to GJK / EPA.
  bool stopped;
  const float thr = simd::fmin_nn(s_top + kTieRel * std::fabs(s_top) + tie_size, 0.0f);
  const EdgeBest be = edge_pass<F>(h, eb, ee - eb, vb, T, rs, thr, true, &stopped);
  int feature = tri_face ? 1 : 0;                // 0: hull face, 1: triangle face, 2: edge pair
  const auto confirm = [&](const EdgeAxis& x) {  // the exact separation along x.n
    float amax, amin_unused, umax_unused;
    if (nv >= W)
      vertex_pass<F>(h.vx + vb, h.vy + vb, h.vz + vb, nv, x.n, x.n, &amax, &amin_unused, &umax_unused);
    else
      vertex_pass<F1>(h.vx + vb, h.vy + vb, h.vz + vb, nv, x.n, x.n, &amax, &amin_unused, &umax_unused);
    float bmin = INFINITY;
    for (const V3& v : T.v) bmin = simd::fmin_nn(bmin, dot(x.n, v));
    return bmin - amax;
  };
  if (be.qs > 0.0f) {
    if (!(confirm(edge_axis(h, eb + be.sep_edge, vb, T, be.sep_tri_edge, rs)) < 0.0f)) return no_contact();
    collide_gjk_epa(a, b, out, Range{k, k + 1}, cfg, kLeafConvex, kLeafTriangle);
    return;
  }
  EdgeAxis ea{};
  // The edge axis of largest key, where it may beat the faces by the tie rule (its key
  // from the float pass, within kKeySlack of the size of it): again in double. Its
  // separation is exact along its axis (hull edge a is the hull's support there).
  const float win = s_top + kTieRel * std::fabs(s_top) + tie_size;
  const float key_est = be.q >= 0.0f ? std::sqrt(be.q) : -std::sqrt(-be.q);
  if (be.q > -INFINITY && key_est > win - kKeySlack * (size + cmag)) {
    ea = edge_axis(h, eb + be.edge, vb, T, be.tri_edge, rs);
    if (!(ea.sep < 0.0f)) return no_contact();  // touching along it (rounding)
    if (ea.key > win && ea.sep > s_best) {
      s_best = ea.sep;
      feature = 2;
    }
  }
  const float depth = -s_best;

  // --- 4. normal and points (hull frame) ---
  V3 nl;
  Manifold mf;
  if (feature == 0) {
    nl = face_normal(h, fb + fp.face);
    uint32_t i = 0;  // the triangle's deepest vertex
    for (uint32_t q = 1; q < 3; ++q)
      if (dot(nl, T.v[q]) < dot(nl, T.v[i])) i = q;
    V3 graze = T.v[i];
    hull_face_manifold(h, fb + fp.face, T, depth, T.v[i], &mf, &graze);
    if (mf.count == 0) {  // nothing below the face after rounding: the clip's deepest point
      mf.count = 1;
      mf.p[0] = graze + nl * (0.5f * depth);
      mf.d[0] = depth;
    }
  } else if (feature == 1) {
    nl = s_np >= s_nm ? nu : -nu;
    const uint32_t g = nf >= W ? face_argmax<F>(h.fnx + fb, h.fny + fb, h.fnz + fb, nf, nl)
                               : face_argmax<F1>(h.fnx + fb, h.fny + fb, h.fnz + fb, nf, nl);
    // the hull's deepest vertex
    const uint32_t i = nv >= W ? vertex_argmax<F>(h.vx + vb, h.vy + vb, h.vz + vb, nv, nl)
                               : vertex_argmax<F1>(h.vx + vb, h.vy + vb, h.vz + vb, nv, nl);
    V3 graze = vertex(h, vb + i);
    triangle_face_manifold(h, fb + g, T, nl, depth, graze, &mf, &graze);
    if (mf.count == 0) {  // nothing beyond the triangle after rounding: the clip's deepest point
      mf.count = 1;
      mf.p[0] = graze - nl * (0.5f * depth);
      mf.d[0] = depth;
    }
  } else {
    nl = ea.n;
    // The triangle's support feature along -n: its vertices within rounding of the
    // least n.v (edge j for a proper edge pair; a vertex, or the longest edge of a
    // collinear triangle, where rounding chose a neighbouring candidate).
    float tv[3];
    for (uint32_t q = 0; q < 3; ++q) tv[q] = dot(nl, T.v[q]);
    const float lo = simd::fmin_nn(tv[0], simd::fmin_nn(tv[1], tv[2]));
    const float tol = 1e-6f * (size + l1(T.v[0]) + l1(T.v[1]) + l1(T.v[2]));
    uint32_t sup[3], ns = 0;
    for (uint32_t q = 0; q < 3; ++q)
      if (tv[q] <= lo + tol) sup[ns++] = q;
    V3 va = T.v[sup[0]], vq = va;
    if (ns == 2) vq = T.v[sup[1]];
    if (ns == 3) {
      float best = -1.0f;
      for (uint32_t q = 0; q < 3; ++q) {
        const V3 d = T.v[q == 2 ? 0 : q + 1] - T.v[q];
        if (dot(d, d) > best) best = dot(d, d), va = T.v[q], vq = T.v[q == 2 ? 0 : q + 1];
      }
    }
    // One point midway between the closest points of hull edge a and that feature,
    // where they are depth apart along n (a proper edge crossing). Else (the edge axis
    // won among nearly tied neighbours whose edge pairs do not meet there, as on a face
    // nearly parallel to a triangle edge): the feature moved by depth along n touches
    // the hull, at a vertex or along the part of the segment within rounding of every
    // face plane; one point at its middle, moved back halfway.
    V3 on_a, on_b;
    closest_segments(ea.pa, ea.ea, va, vq - va, &on_a, &on_b);
    const float slack = kTouchSlack * (size + cmag);
    const V3 gap = on_a - on_b - nl * depth;
    mf.count = 1;
    mf.d[0] = depth;
    mf.p[0] = (on_a + on_b) * 0.5f;
    if (!(dot(gap, gap) <= 16.0f * slack * slack)) {
      if (ns == 1) {
        mf.p[0] = va + nl * (0.5f * depth);
      } else {
        float t_lo, t_hi;
        const V3 d = vq - va, q0 = va + nl * depth;
        if (nf >= W)
          clip_segment<F>(h.fnx + fb, h.fny + fb, h.fnz + fb, h.fd + fb, nf, q0, d, slack, &t_lo, &t_hi);
        else
          clip_segment<F1>(h.fnx + fb, h.fny + fb, h.fnz + fb, h.fd + fb, nf, q0, d, slack, &t_lo, &t_hi);
        if (t_lo <= t_hi) mf.p[0] = va + d * (0.5f * (t_lo + t_hi)) + nl * (0.5f * depth);
      }
    }
  }
  if (mf.count > kMaxManifoldPoints) mf.count = cvx::reduce_manifold(mf.p, mf.d, mf.count, nl);

  // --- world frame ---
  hull_scan::store_from_frame(out, k, ax, pw, nl, depth, mf.count, mf.p, mf.d);
}

}  // namespace

void collide_convex_triangle(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, Range r,
                             const NarrowConfig& cfg) {
  if (cfg.path == KernelPath::kScalar) {
    for (uint32_t k = r.begin; k < r.end; ++k) convex_triangle_lane<simd::Float1>(a, b, out, k, cfg);
  } else {
    for (uint32_t k = r.begin; k < r.end; ++k) convex_triangle_lane<simd::FloatW>(a, b, out, k, cfg);
  }
}

}  // namespace impact::kernels
