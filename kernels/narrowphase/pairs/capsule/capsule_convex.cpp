// Capsule (A) against convex hull (B): exact closest features / separating axes of the
// hull, no GJK / EPA.
//
// What: collide_capsule_convex writes, per lane k in r, the collision data of leaf.h for
// a capsule (centre p, axis u = R column 2, radius e0, half length e1: core segment S =
// p -+ e1 u) and a convex hull (pose p, R; hull ref in cfg.hulls): count 0, 1 or 2, unit
// normal n from the capsule to the hull (the hull moves along n by depth to separate),
// depth, points midway between the two surfaces with their own depths. Slots 2..3 are
// untouched; count 0 lanes leave everything else unspecified.
// Method, per lane, in the hull's local frame: the core's centre c = R^T (p - hull
// position) and axis u = R^T u_world in double (exact differences of the float inputs;
// the float passes use them rounded), so poses far from the origin keep their precision.
//  1. One pass over the hull's face planes, kSimdWidth faces per step, with
//     a_f = fn_f.c - fd_f and b_f = fn_f.u: the core's separation from each plane
//     a_f - h|b_f| and its maximum s_F (face f_F, the lowest index among ties), the two
//     end points' plane distances a_f -+ h b_f and their maxima (faces f_0, f_1), and the
//     core clipped by every plane (Cyrus-Beck: t in [-h, h] with a_f + b_f t <= 0).
//  2. s_F >= r: separated by a face axis (count 0; s_F = r is touching, also count 0).
//  3. The clip is empty: the core lies outside the hull, and the distance d from S to
//     the hull is attained (Ericson 5.1, Voronoi regions) at an end point above a face's
//     interior or between S and a hull edge (a closest pair inside S and inside a face
//     makes S parallel to that face, and sliding along S reaches an end point or the
//     face's boundary at the same distance). So d = the least of (a) an end point's
//     distance to its deepest plane f_i when it projects into f_i's polygon (or into a
//     face tied with f_i up to the planes' rounding, as in sphere_convex.cpp) and the
//     other end is not lower under that plane by more than its rounding (else the core
//     slants down past the face's edge: the face's normal is no contact normal, its
//     overlap exceeds r - the distance, and (b) holds the least distance), (b) the
//     segment-to-segment distance from S to every hull edge of the adjacency list
//     (Ericson 5.1.9, kSimdWidth edges per step in float, start ep and edge vector ed
//     loaded contiguously from HullView, no gather; the edges within twice its
//     rounding bound of the least are evaluated again in double and the nearest wins,
//     lowest index among exact ties: a distance is flat about its minimum, so float
//     alone could pick a neighbouring edge and tilt the normal). A face candidate wins
//     ties with an edge (within 1e-6 of the coordinates): n = -R fn exactly. d >= r:
//     count 0; else depth = r - d, n along the closest points. A closest-point offset
//     below 1e-6 of the coordinates (S touching the hull up to rounding) has a noisy
//     direction: such a lane takes step 4 instead.
//  4. The clip is not empty: the core meets the hull. The penetration of the capsule is
//     r plus the least overlap over the face normals of the Minkowski sum of S and -B:
//     the hull's face normals (the core's support on them is the lower end point:
//     s_F of step 1) and u x e for the hull edges e whose normal cone (the arc between
//     their two faces' normals) crosses the great circle perpendicular to u (the other
//     edges give no face of the sum). An edge's arc crosses iff its two normals lie on
//     either side of that circle: |m.u| cos(a) <= |m.(u x e)| sin(a) / |e| with the
//     arc's bisector m and half angle a (HullView em, ecos, esin, rounded outward), and
//     its axis u x e is oriented along m: the hull's support on it is the edge itself,
//     so its separation is (u x e).(c - v0)/|u x e|. One pass, kSimdWidth edges per step.
//     Least overlap wins; an edge axis only if it beats the best face by 1e-5 of the
//     overlap plus 1e-6 of the size plus its own rounding (as capsule-box,
//     capsule_box.cpp), so resting contacts keep their face normal.
//  5. Points as capsule-box does: where n is within 0.26 degrees of a face normal g and
//     the core lies within 2.9 degrees of parallel to g (or the core meets the hull by a
//     face axis), the core moved along n onto g's plane is clipped to g's polygon and
//     its two ends give two points (the capsule's surface along n and g's plane, each
//     with its own depth) when both reach below the plane; a deep face contact that
//     keeps one end keeps the deeper one; else one point: midway between the closest
//     points (core outside), the core point nearest the winning edge moved by r -
//     depth/2 along n (deep edge axis), the deepest core point likewise (deep face axis,
//     nothing clipped).
//  Hulls without faces or without edge adjacency in HullView go through the general
//  GJK / EPA lane (collide_convex_lane).
// Inputs: lanes per leaf.h (finite, radius > 0, half length >= 0, unit axes, R
// orthonormal), hulls as HullStore builds them (unit outward face normals,
// counter-clockwise polygons, edge adjacency padded to a multiple of kHullEdgePad).
// Precision: plane distances and the SAT axes are float (~1e-7 of the local
// coordinates), the chosen edge distance is exact in double for the float inputs; depth
// and normal are within ~1e-6 of the coordinates (tested against a double reference at
// 2e-5 of the size). A zero-length core gives the sphere-hull kernel's answer (same
// planes, same edge rule). No division without a guard: no NaN for finite input (Inf is
// not accepted). No allocation: hulls up to 512 faces / edges keep their pass values in
// stack buffers, larger hulls compute them again (no limit on the face or edge count).
// Paths: nothing here vectorises across lanes (each lane walks its own hull); cfg.path
// kSimd and kScalar run this same per-lane code (bit-identical results, as GJK / EPA
// and sphere-hull do); within a lane the face and edge passes run kSimdWidth at a time;
// the one-lane build (IMPACT_SIMD_SCALAR) runs them with kSimdWidth = 1.
// Cost: O(F) for lanes a face plane separates by r (43% of the bench's lanes), O(F + E)
// for the others (a few near-minimum edges again in double); the edge passes read
// each edge's start and vector contiguously (no gather). Measured per pair, with its
// profile, in docs/results.md ("Narrow phase") and docs/history.md.
// Method citations: Ericson, Real-Time Collision Detection (2005), 5.1.9 (closest points
// of two segments) and 5.3.8 / Cyrus-Beck (segment against a convex polyhedron);
// D. Gregorius, "The Separating Axis Test between Convex Polyhedra", GDC 2013 (Gauss-map
// pruning of edge axes).
#include <algorithm>
#include <bit>
#include <cfloat>
#include <cmath>
#include <cstdint>

#include "kernels/narrowphase/general/gjk_epa.h"
#include "kernels/narrowphase/general/hull_scan.h"
#include "kernels/narrowphase/pair_kernels.h"
#include "kernels/simd/lanes.h"

namespace impact::kernels {
namespace {

using cvx::V3;
using simd::FloatW;
using simd::kSimdWidth;
// The edge walks (nearest_edge, sat_edges) load whole blocks of the padded edge list.
static_assert(kHullEdgePad % kSimdWidth == 0, "the edge walks need whole padded blocks");
using namespace hull_scan;  // NOLINT: the hull kernels' shared passes

/// SAT tie rule (as capsule-box): an edge axis wins over the best face only when it
/// separates more by kTieRel * |overlap| + kTieSize * size + its own rounding,
/// kEdgeRound * (size + |c|) * |e| / |u x e|.
constexpr float kTieRel = 1e-5f;
constexpr float kTieSize = 1e-6f;
constexpr float kEdgeRound = 2e-7f;
/// Two-point face contacts (as capsule-box): n within acos(kFaceCos) of the face
/// normal, and (core outside) the axis within asin(kParallelSin) of the face.
constexpr float kFaceCos = 0.99999f;
constexpr float kParallelSin = 0.05f;

IMPACT_INLINE float clampf(float x, float lo, float hi) {
  return simd::fmin_nn(simd::fmax_nn(x, lo), hi);
}
IMPACT_INLINE double clampd(double x, double lo, double hi) {
  return x < lo ? lo : (x > hi ? hi : x);
}
IMPACT_INLINE float l1(V3 a) {
  return std::fabs(a.x) + std::fabs(a.y) + std::fabs(a.z);
}

// ---------------------------------------------------------------------------------------
// Step 1: the face pass
// ---------------------------------------------------------------------------------------

struct FacePass {
  float s_core = -INFINITY;  // max_f a_f - h|b_f|: the core's separation over face axes
  uint32_t f_core = 0;
  float s_end[2] = {-INFINITY, -INFINITY};  // max_f a_f -+ h b_f: end points c -+ h u
  uint32_t f_end[2] = {0, 0};
};

/// a_f = fn.c - fd, b_f = fn.u for faces i .. i + kSimdWidth.
IMPACT_INLINE void plane_ab(const HullView& h, uint32_t i, const FloatW* c, const FloatW* u, FloatW* a,
                            FloatW* b) {
  using F = FloatW;
  const F nx = F::load(h.fnx + i), ny = F::load(h.fny + i), nz = F::load(h.fnz + i);
  *a = c[0] * nx + c[1] * ny + c[2] * nz - F::load(h.fd + i);
  *b = u[0] * nx + u[1] * ny + u[2] * nz;
}
IMPACT_INLINE void plane_ab(const HullView& h, uint32_t i, V3 c, V3 u, float* a, float* b) {
  *a = c.x * h.fnx[i] + c.y * h.fny[i] + c.z * h.fnz[i] - h.fd[i];
  *b = u.x * h.fnx[i] + u.y * h.fny[i] + u.z * h.fnz[i];
}

/// Step 1 over faces [fb, fe) but the clip (core_meets_hull). keep_a / keep_b: null, or
/// room for fe - fb values each (wide path only): a_f, b_f at f - fb.
IMPACT_INLINE FacePass face_pass(const HullView& h, uint32_t fb, uint32_t fe, V3 c, V3 u, float hl,
                                 float* keep_a, float* keep_b) {
  FacePass fp;
  if (fe - fb >= kSimdWidth) {
    using F = FloatW;
    const F lane = simd::lane_index<F>(), H(hl);
    const F cw[3] = {F(c.x), F(c.y), F(c.z)}, uw[3] = {F(u.x), F(u.y), F(u.z)};
    F m(-INFINITY), mi(0.0f), m0(-INFINITY), i0(0.0f), m1(-INFINITY), i1(0.0f);
    for (uint32_t i = fb;; i = next_block(i, fe)) {
      F a, b;
      plane_ab(h, i, cw, uw, &a, &b);
      if (keep_a != nullptr) {
        a.store(keep_a + (i - fb));
        b.store(keep_b + (i - fb));
      }
      const F hb = H * b, idx = lane + F(static_cast<float>(i - fb));
      const F s = a - simd::abs(hb), s0 = a - hb, s1 = a + hb;
      // strict: each lane keeps its first maximum
      const auto g = s > m, g0 = s0 > m0, g1 = s1 > m1;
      m = select(g, s, m);
      mi = select(g, idx, mi);
      m0 = select(g0, s0, m0);
      i0 = select(g0, idx, i0);
      m1 = select(g1, s1, m1);
      i1 = select(g1, idx, i1);
      if (i + kSimdWidth == fe) break;
    }
    const float none = static_cast<float>(fe - fb);
    float bi;
    fp.s_core = simd::max_lowest_index(m, mi, none, &bi);
    fp.f_core = fb + static_cast<uint32_t>(bi);
    fp.s_end[0] = simd::max_lowest_index(m0, i0, none, &bi);
    fp.f_end[0] = fb + static_cast<uint32_t>(bi);
    fp.s_end[1] = simd::max_lowest_index(m1, i1, none, &bi);
    fp.f_end[1] = fb + static_cast<uint32_t>(bi);
  } else {
    for (uint32_t i = fb; i < fe; ++i) {
      float a, b;
      plane_ab(h, i, c, u, &a, &b);
      const float hb = hl * b;
      const float s = a - std::fabs(hb), s0 = a - hb, s1 = a + hb;
      if (s > fp.s_core) fp.s_core = s, fp.f_core = i;
      if (s0 > fp.s_end[0]) fp.s_end[0] = s0, fp.f_end[0] = i;
      if (s1 > fp.s_end[1]) fp.s_end[1] = s1, fp.f_end[1] = i;
    }
  }
  return fp;
}

/// Whether the core's clip by every face plane of [fb, fe) is not empty (Cyrus-Beck:
/// a_f + b_f t <= 0 bounds t from above where b_f > 0, from below where b_f < 0).
/// kept_a / kept_b: face_pass's values (or null: computed again, same formula).
IMPACT_INLINE bool core_meets_hull(const HullView& h, uint32_t fb, uint32_t fe, V3 c, V3 u, float hl,
                                   const float* kept_a, const float* kept_b) {
  if (fe - fb < kSimdWidth) {
    float tlo = -hl, thi = hl;
    for (uint32_t i = fb; i < fe; ++i) {
      float a, b;
      plane_ab(h, i, c, u, &a, &b);
      if (b > 0.0f) {
        thi = simd::fmin_nn(thi, -a / b);
      } else if (b < 0.0f) {
        tlo = simd::fmax_nn(tlo, -a / b);
      } else if (a > 0.0f) {
        return false;
      }
    }
    return tlo <= thi;
  }
  using F = FloatW;
  const F zero(0.0f), one(1.0f);
  const F cw[3] = {F(c.x), F(c.y), F(c.z)}, uw[3] = {F(u.x), F(u.y), F(u.z)};
  F lo(-hl), hi(hl);
  for (uint32_t i = fb;; i = next_block(i, fe)) {
    F a, b;
    if (kept_a != nullptr) {
      a = F::load(kept_a + (i - fb));
      b = F::load(kept_b + (i - fb));
    } else {
      plane_ab(h, i, cw, uw, &a, &b);
    }
    const auto pos = b > zero, neg = b < zero;
    const F cut = -a / select(pos | neg, b, one);
    hi = select(pos, simd::min(hi, cut), hi);
    lo = select(neg, simd::max(lo, cut), lo);
    lo = select(andnot(a > zero, pos | neg), F(INFINITY), lo);  // parallel and outside
    if (i + kSimdWidth == fe) break;
  }
  return lanes_max(lo) <= lanes_min(hi);
}

/// The lowest face g in [fb, fe), g != skip, whose plane distance of end point
/// p = c + sgn h u (a_g + sgn h b_g) is >= s_min (a tie with the deepest plane up to
/// rounding) and into whose polygon p projects, or fe when there is none. kept_a/b:
/// face_pass's values (or null: computed again, same formula).
IMPACT_INLINE uint32_t near_tie_face(const HullView& h, uint32_t fb, uint32_t fe, uint32_t skip, V3 c, V3 u,
                                     float sh, V3 p, float s_min, const float* kept_a, const float* kept_b,
                                     float* out_s) {
  if (fe - fb < kSimdWidth) {
    for (uint32_t i = fb; i < fe; ++i) {
      float a, b;
      plane_ab(h, i, c, u, &a, &b);
      const float s = a + sh * b;
      if (i != skip && s >= s_min && projects_into_face(h, i, p)) {
        *out_s = s;
        return i;
      }
    }
    return fe;
  }
  using F = FloatW;
  const F cw[3] = {F(c.x), F(c.y), F(c.z)}, uw[3] = {F(u.x), F(u.y), F(u.z)};
  const F lo(s_min), SH(sh);
  for (uint32_t i = fb;; i = next_block(i, fe)) {
    F a, b;
    if (kept_a != nullptr) {
      a = F::load(kept_a + (i - fb));
      b = F::load(kept_b + (i - fb));
    } else {
      plane_ab(h, i, cw, uw, &a, &b);
    }
    const F s = a + SH * b;
    const auto near = s >= lo;
    if (simd::any(near)) {
      for (uint32_t l = 0; l < kSimdWidth; ++l)
        if (near.lane(l) && i + l != skip && projects_into_face(h, i + l, p)) {
          *out_s = s.lane(l);
          return i + l;
        }
    }
    if (i + kSimdWidth == fe) break;
  }
  return fe;
}

// ---------------------------------------------------------------------------------------
// Step 3: the core's distance to the hull edges
// ---------------------------------------------------------------------------------------

/// Squared distance from the core (c + t u, |t| <= hl, unit u) to edges i .. i +
/// kSimdWidth of the adjacency list (start ep, edge vector ed: contiguous loads), in
/// float (Ericson 5.1.9: the lines' closest parameter of the core, clamped; the edge's
/// for it, clamped; the core's again for that, clamped).
IMPACT_INLINE FloatW edge_seg_dist2(const HullView& h, uint32_t i, const FloatW* c, const FloatW* u,
                                    FloatW hl, FloatW* out_tau) {
  using F = FloatW;
  const F zero(0.0f), one(1.0f);
  const F ax = F::load(h.epx + i), ay = F::load(h.epy + i), az = F::load(h.epz + i);
  const F ex = F::load(h.edx + i), ey = F::load(h.edy + i), ez = F::load(h.edz + i);
  const F wx = c[0] - ax, wy = c[1] - ay, wz = c[2] - az;
  const F be = u[0] * ex + u[1] * ey + u[2] * ez;
  const F ee = ex * ex + ey * ey + ez * ez;
  const F du = u[0] * wx + u[1] * wy + u[2] * wz;
  const F fe = ex * wx + ey * wy + ez * wz;
  // Lines nearly parallel: start from t = 0. One division for 1/den and 1/ee.
  const F den = ee - be * be;  // |u x e|^2
  const auto skew = den > F(1e-12f) * ee;
  const F dn = select(skew, den, one);
  const F q = one / simd::max(dn * ee, F(FLT_MIN));
  F t = select(skew, (be * fe - ee * du) * (ee * q), zero);
  t = simd::clamp(t, -hl, hl);
  const F tau = simd::clamp((fe + t * be) * (dn * q), zero, one);
  t = simd::clamp(tau * be - du, -hl, hl);
  *out_tau = tau;
  const F dx = wx + t * u[0] - tau * ex, dy = wy + t * u[1] - tau * ey, dz = wz + t * u[2] - tau * ez;
  return dx * dx + dy * dy + dz * dz;
}

/// The closest points of the core and one hull edge, in double.
struct SegEdge {
  double d2 = INFINITY;
  double x[3] = {0, 0, 0};  // on the core
  double y[3] = {0, 0, 0};  // on the edge
  double t = 0;             // core parameter
};

/// Core c + t u (|t| <= hl, u unit) against edge a..b: the same steps as
/// edge_seg_dist2, in double (a, b float exactly); branch-free clamps.
IMPACT_INLINE SegEdge seg_edge(const double c[3], const double u[3], double hl, V3 a, V3 b) {
  const double ad[3] = {a.x, a.y, a.z};
  const double e[3] = {static_cast<double>(b.x) - ad[0], static_cast<double>(b.y) - ad[1],
                       static_cast<double>(b.z) - ad[2]};
  const double w[3] = {c[0] - ad[0], c[1] - ad[1], c[2] - ad[2]};
  const double be = u[0] * e[0] + u[1] * e[1] + u[2] * e[2];
  const double ee = e[0] * e[0] + e[1] * e[1] + e[2] * e[2];
  const double du = u[0] * w[0] + u[1] * w[1] + u[2] * w[2];
  const double fe = e[0] * w[0] + e[1] * w[1] + e[2] * w[2];
  const double den = ee - be * be;
  const bool skew = den > 1e-24 * ee;
  const double q = 1.0 / std::max((skew ? den : 1.0) * ee, DBL_MIN);
  double t = skew ? (be * fe - ee * du) * (ee * q) : 0.0;
  t = std::min(std::max(t, -hl), hl);
  const double tau = std::min(std::max((fe + t * be) * ((skew ? den : 1.0) * q), 0.0), 1.0);
  t = std::min(std::max(tau * be - du, -hl), hl);
  SegEdge s;
  s.t = t;
  double d2 = 0;
  for (int i = 0; i < 3; ++i) {
    s.x[i] = c[i] + t * u[i];
    s.y[i] = ad[i] + tau * e[i];
    const double d = s.y[i] - s.x[i];
    d2 += d * d;
  }
  s.d2 = d2;
  return s;
}

/// max |v|_1 over the hull's vertices [vb, ve): bounds the edges' coordinates.
IMPACT_INLINE float hull_extent(const HullView& h, uint32_t vb, uint32_t ve) {
  using F = FloatW;
  float m = 0.0f;
  uint32_t i = vb;
  if (ve - vb >= kSimdWidth) {
    F mw(0.0f);
    for (;; i = next_block(i, ve)) {
      mw = simd::max(
          mw, simd::abs(F::load(h.vx + i)) + simd::abs(F::load(h.vy + i)) + simd::abs(F::load(h.vz + i)));
      if (i + kSimdWidth == ve) break;
    }
    return lanes_max(mw);
  }
  for (; i < ve; ++i) m = simd::fmax_nn(m, std::fabs(h.vx[i]) + std::fabs(h.vy[i]) + std::fabs(h.vz[i]));
  return m;
}

/// Core c + t u (|t| <= hl, u unit) against vertex v, in double: t = clamp(u.(v - c)).
IMPACT_INLINE SegEdge seg_vertex(const double c[3], const double u[3], double hl, V3 v) {
  const double vd[3] = {v.x, v.y, v.z};
  double t = u[0] * (vd[0] - c[0]) + u[1] * (vd[1] - c[1]) + u[2] * (vd[2] - c[2]);
  t = std::min(std::max(t, -hl), hl);
  SegEdge s;
  s.t = t;
  double d2 = 0;
  for (int i = 0; i < 3; ++i) {
    s.x[i] = c[i] + t * u[i];
    s.y[i] = vd[i];
    const double d = s.y[i] - s.x[i];
    d2 += d * d;
  }
  s.d2 = d2;
  return s;
}

/// The nearest of the hull's edges to the core (adjacency list [ab, ae), far ends by
/// hull-local index from vb, vertices [vb, ve)), exactly for the float inputs: a float
/// pass finds the least distance, every edge within twice its rounding bound is
/// evaluated again in double, the nearest wins (the lowest index among exact ties).
/// Where the float pass put an edge's closest point at one of its ends, that vertex is
/// evaluated instead of the edge (each vertex once: the edges that meet there tie; the
/// edge's own closest point lies within the float rounding of the vertex, and the
/// distance differs by its square). *out_e: the winner's index.
IMPACT_INLINE SegEdge nearest_edge(const HullView& h, uint32_t ab, uint32_t ae, uint32_t vb, uint32_t ve,
                                   V3 c, V3 u, float hl, const double cd[3], const double ud[3],
                                   uint32_t* out_e) {
  using F = FloatW;
  SegEdge best;
  *out_e = ab;
  const F cw[3] = {F(c.x), F(c.y), F(c.z)}, uw[3] = {F(u.x), F(u.y), F(u.z)}, H(hl);
  float kept[kKeep], kept_tau[kKeep];
  const bool keep = ae - ab <= kKeep;
  F m(INFINITY);
  // The edge list is padded to a multiple of kHullEdgePad (HullView): whole blocks.
  for (uint32_t i = ab; i < ae; i += kSimdWidth) {
    F tau;
    const F d2 = edge_seg_dist2(h, i, cw, uw, H, &tau);
    if (keep) {
      d2.store(kept + (i - ab));
      tau.store(kept_tau + (i - ab));
    }
    m = simd::min(m, d2);
  }
  // A float distance here is off by a few ulps of |c - start|_1 + |e|_1 + h (the
  // cancellation along the edge and the core) plus c's own rounding; 1e-6 of
  // 3 |v|_1 + 2 |c|_1 + h bounds that with a wide margin.
  const float err = 1e-6f * (3.0f * hull_extent(h, vb, ve) + 2.0f * l1(c) + hl);
  const float lim = std::sqrt(lanes_min(m)) + 2.0f * err;
  const F lim2(lim * lim);
  uint32_t seen[2 * kSimdWidth];  // vertices evaluated
  uint32_t nseen = 0;
  for (uint32_t i = ab; i < ae; i += kSimdWidth) {
    F tau;
    const F d2 = keep ? F::load(kept + (i - ab)) : edge_seg_dist2(h, i, cw, uw, H, &tau);
    uint32_t bits = simd::bits(d2 <= lim2);
    if (bits == 0) continue;
    if (keep) tau = F::load(kept_tau + (i - ab));
    for (; bits != 0; bits &= bits - 1) {
      const uint32_t lane = static_cast<uint32_t>(std::countr_zero(bits)), l = i + lane;
      const float tl = tau.lane(lane);
      SegEdge s;
      if (tl == 0.0f || tl == 1.0f) {
        const uint32_t v = tl == 0.0f ? h.ev0[l] : h.ev1[l];
        bool dup = false;
        for (uint32_t q = 0; q < nseen; ++q) dup = dup || seen[q] == v;
        if (dup) continue;
        if (nseen < 2 * kSimdWidth) seen[nseen++] = v;
        s = seg_vertex(cd, ud, hl, vertex(h, vb + v));
      } else {
        s = seg_edge(cd, ud, hl, V3{h.epx[l], h.epy[l], h.epz[l]}, vertex(h, vb + h.ev1[l]));
      }
      if (s.d2 < best.d2) {
        best = s;
        *out_e = l;
      }
    }
  }
  return best;
}

// ---------------------------------------------------------------------------------------
// Step 4: edge axes of the separating axis test
// ---------------------------------------------------------------------------------------

struct EdgeAxis {
  float key = -INFINITY;  // separation less its rounding bound
  float sep = -INFINITY;  // separation along the axis
  uint32_t e = 0;         // adjacency index
};

/// The edge axis u x e of greatest key (separation less kEdgeRound * scale * |e| / |u x e|)
/// over the edges [ab, ae) whose normal cone crosses the circle perpendicular to u.
IMPACT_INLINE EdgeAxis sat_edges(const HullView& h, uint32_t ab, uint32_t ae, V3 c, V3 u, float round_scale) {
  using F = FloatW;
  const F zero(0.0f), lane = simd::lane_index<F>();
  const F cw[3] = {F(c.x), F(c.y), F(c.z)}, uw[3] = {F(u.x), F(u.y), F(u.z)}, rs(round_scale);
  F mk(-INFINITY), ms(-INFINITY), mi(0.0f);
  for (uint32_t i = ab; i < ae; i += kSimdWidth) {
    const F ax = F::load(h.epx + i), ay = F::load(h.epy + i), az = F::load(h.epz + i);
    const F ex = F::load(h.edx + i), ey = F::load(h.edy + i), ez = F::load(h.edz + i);
    const F lx = uw[1] * ez - uw[2] * ey, ly = uw[2] * ex - uw[0] * ez, lz = uw[0] * ey - uw[1] * ex;
    const F mx = F::load(h.emx + i), my = F::load(h.emy + i), mz = F::load(h.emz + i);
    const F ll = lx * lx + ly * ly + lz * lz, ee = ex * ex + ey * ey + ez * ez;
    const F lm = lx * mx + ly * my + lz * mz, mu = mx * uw[0] + my * uw[1] + mz * uw[2];
    const F ec = F::load(h.ecos + i), es = F::load(h.esin + i);
    const auto crosses = (mu * ec) * (mu * ec) * ee <= (lm * es) * (lm * es);
    const auto ok = crosses & (ll > F(1e-10f) * ee);
    const F inv = F(1.0f) / simd::sqrt(simd::max(ll, F(FLT_MIN)));
    const F lw = lx * (cw[0] - ax) + ly * (cw[1] - ay) + lz * (cw[2] - az);
    const F sep = select(lm < zero, -lw, lw) * inv;
    const F key = select(ok, sep - rs * simd::sqrt(ee) * inv, F(-INFINITY));
    const auto g = key > mk;
    mk = select(g, key, mk);
    ms = select(g, sep, ms);
    mi = select(g, lane + F(static_cast<float>(i - ab)), mi);
  }
  EdgeAxis out;
  float bi;
  out.key = simd::max_lowest_index(mk, mi, static_cast<float>(ae - ab), &bi);
  if (!(out.key > -INFINITY)) return out;
  const uint32_t l = static_cast<uint32_t>(bi);
  out.e = ab + l;
  // The winning lane's separation (the lowest index among the keys' ties).
  for (uint32_t q = 0; q < kSimdWidth; ++q)
    if (mi.lane(q) == bi && mk.lane(q) == out.key) {
      out.sep = ms.lane(q);
      break;
    }
  return out;
}

// ---------------------------------------------------------------------------------------
// Step 5: points
// ---------------------------------------------------------------------------------------

/// Distance from the core point at axial parameter t (|t| <= hl) along unit n (s =
/// n.u) to the capsule's surface: through the cylinder, or an end cap where the
/// cylinder exit lies beyond the core (prim::capsule_exit, lanes/lane_geometry.h).
IMPACT_INLINE float capsule_exit(float t, float s, float r, float hl) {
  const float c2 = simd::fmax_nn(1.0f - s * s, 1e-12f);
  const float lc = r / std::sqrt(c2);
  const float ax = lc * s + t;
  if (!(ax > hl) && !(ax < -hl)) return lc;
  const float delta = ax > hl ? t - hl : t + hl;  // from the cap's centre
  const float disc = simd::fmax_nn(r * r - delta * delta * c2, 0.0f);
  return std::sqrt(disc) - delta * s;
}

struct Manifold {
  uint32_t count = 0;
  V3 p[2]{};
  float d[2]{0, 0};
};

/// The core moved along nl onto face g's plane, clipped to g's polygon: [*lo, *hi] in
/// the core's parameter (empty: *lo > *hi). Then the two clipped ends' points: the
/// capsule's surface along nl and g's plane, midway, with their depths.
IMPACT_INLINE bool face_clip(const HullView& h, uint32_t g, V3 c, V3 u, float hl, float r, V3 nl, V3 p[2],
                             float d[2]) {
  const V3 fg = face_normal(h, g);
  const float fgn = cvx::dot(fg, nl);  // ~ -1
  if (!(std::fabs(fgn) > 0.5f)) return false;
  const float inv = 1.0f / fgn;
  // y(t) = x(t) + lambda(t) nl on the plane: cs + t us.
  const V3 cs = c + nl * ((h.fd[g] - cvx::dot(fg, c)) * inv);
  const V3 us = u - nl * (cvx::dot(fg, u) * inv);
  float lo = -hl, hi = hl;
  const uint32_t b = h.face_vert_begin[g], e = h.face_vert_begin[g + 1];
  if (e - b < 3) return false;
  V3 a = vertex(h, h.face_verts[e - 1]);
  for (uint32_t j = b; j < e; ++j) {
    const V3 q = vertex(h, h.face_verts[j]);
    const V3 o = cvx::cross(q - a, fg);  // out of the polygon
    const float al = cvx::dot(o, cs - a), be = cvx::dot(o, us);
    if (std::fabs(be) < 1e-20f) {
      if (al > 0.0f) return false;
    } else if (be > 0.0f) {
      hi = simd::fmin_nn(hi, -al / be);
    } else {
      lo = simd::fmax_nn(lo, -al / be);
    }
    a = q;
  }
  if (!(hi - lo > 1e-4f * (hl + r))) return false;
  const float snu = cvx::dot(nl, u);
  const float ts[2] = {lo, hi};
  for (int i = 0; i < 2; ++i) {
    const V3 on_a = c + u * ts[i] + nl * capsule_exit(ts[i], snu, r, hl);
    d[i] = (cvx::dot(fg, on_a) - h.fd[g]) * inv;
    p[i] = on_a - nl * (0.5f * d[i]);
  }
  return true;
}

void capsule_convex_lane(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, uint32_t k,
                         const NarrowConfig& cfg) {
  const HullView& h = cfg.hulls;
  const uint32_t hull = b.ref[k];
  const uint32_t fb = h.face_begin != nullptr ? h.face_begin[hull] : 0u;
  const uint32_t fe = h.face_begin != nullptr ? h.face_begin[hull + 1] : 0u;
  const uint32_t ab = h.adj_begin != nullptr ? h.adj_begin[hull] : 0u;
  const uint32_t ae = h.adj_begin != nullptr ? h.adj_begin[hull + 1] : 0u;
  if (fe == fb || ae == ab || h.edx == nullptr) {  // no faces or no edge adjacency: the general path
    collide_gjk_epa(a, b, out, Range{k, k + 1}, cfg, kLeafCapsule, kLeafConvex);
    return;
  }
  const uint32_t vb = h.vert_begin[hull];
  const float r = a.e[0][k], hl = a.e[1][k];
  const V3 pb{b.p[0][k], b.p[1][k], b.p[2][k]};
  V3 ax[3];  // hull axes (R's columns)
  for (int col = 0; col < 3; ++col) ax[col] = V3{b.r[col][k], b.r[3 + col][k], b.r[6 + col][k]};
  // Centre and axis in the hull's frame, in double (exact difference, exact products).
  const double dw[3] = {static_cast<double>(a.p[0][k]) - pb.x, static_cast<double>(a.p[1][k]) - pb.y,
                        static_cast<double>(a.p[2][k]) - pb.z};
  const double uw[3] = {a.r[2][k], a.r[5][k], a.r[8][k]};
  double cd[3], ud[3];
  for (int col = 0; col < 3; ++col) {
    cd[col] = ax[col].x * dw[0] + ax[col].y * dw[1] + ax[col].z * dw[2];
    ud[col] = ax[col].x * uw[0] + ax[col].y * uw[1] + ax[col].z * uw[2];
  }
  const V3 c{static_cast<float>(cd[0]), static_cast<float>(cd[1]), static_cast<float>(cd[2])};
  const V3 u{static_cast<float>(ud[0]), static_cast<float>(ud[1]), static_cast<float>(ud[2])};
  {
    // A unit axis in double (the float one is ~1e-7 off unit), as seg_edge assumes.
    const double inv = 1.0 / std::sqrt(ud[0] * ud[0] + ud[1] * ud[1] + ud[2] * ud[2]);
    for (double& x : ud) x *= inv;
  }

  // --- 1, 2: face planes ---
  float kept_a[kKeep], kept_b[kKeep];
  const bool keep = fe - fb <= kKeep;
  const FacePass fp = face_pass(h, fb, fe, c, u, hl, keep ? kept_a : nullptr, keep ? kept_b : nullptr);
  if (!(fp.s_core < r)) {
    out.count[k] = 0;
    return;
  }
  const float scale = l1(c) + hl + std::fabs(h.fd[fp.f_core]);

  V3 nl;        // local normal, capsule to hull
  float depth;  // > 0
  // The core meets the hull: not where a face plane separates it, surely where an end
  // point is inside, else by the clip.
  bool deep = !(fp.s_core > 0.0f) &&
              (!(fp.s_end[0] > 0.0f) || !(fp.s_end[1] > 0.0f) ||
               core_meets_hull(h, fb, fe, c, u, hl, keep ? kept_a : nullptr, keep ? kept_b : nullptr));
  bool edge_axis = false;       // deep: an edge axis won
  uint32_t face = fe;           // a face whose normal nl may be (fe: none known)
  V3 xs{0, 0, 0}, yh{0, 0, 0};  // shallow: closest points (core, hull)
  uint32_t edge = ab;

  // --- 3: core outside: its distance to the hull ---
  if (!deep) {
    float face_d = INFINITY;
    int face_end = 0;
    // Only distances below r matter (and below a face candidate found): the nearer end
    // point first.
    float ub = r;
    const int first = fp.s_end[0] <= fp.s_end[1] ? 0 : 1;
    for (int q = 0; q < 2 && !deep; ++q) {
      const int i = q == 0 ? first : 1 - first;
      const float sh = i == 0 ? -hl : hl;
      const float s = fp.s_end[i];
      if (!(s > 0.0f)) {  // an end point on or in the hull: the clip said otherwise by rounding
        deep = true;
        break;
      }
      if (!(s < ub)) continue;
      const V3 p = c + u * sh;
      uint32_t f = fp.f_end[i];
      float sf = s;
      if (!projects_into_face(h, f, p)) {
        // Faces tied with f up to their planes' rounding may hold the closest point.
        const float slack = 1e-5f * (l1(p) + std::fabs(h.fd[f]));
        f = near_tie_face(h, fb, fe, f, c, u, sh, p, s - slack, keep ? kept_a : nullptr,
                          keep ? kept_b : nullptr, &sf);
      }
      // f's normal is the contact normal only where this end is the core's support
      // towards f's plane: where the other end lies lower by more than the planes'
      // rounding, the overlap along f's normal exceeds r - sf (the core slants down past
      // f's edge, and the edge candidate below holds the least distance).
      if (f != fe) {
        const V3 po = c + u * (i == 0 ? hl : -hl);
        const float so = cvx::dot(face_normal(h, f), po) - h.fd[f];
        if (so < sf - 1e-6f * (l1(po) + std::fabs(h.fd[f]))) f = fe;
      }
      if (f != fe && sf < face_d) {
        face_d = sf;
        face = f;
        face_end = i;
        ub = simd::fmin_nn(ub, sf);
      }
    }
    if (!deep) {
      // Edges whose bound is within the planes' rounding of ub are looked at too.
      SegEdge se;
      se = nearest_edge(h, ab, ae, vb, h.vert_begin[hull + 1], c, u, hl, cd, ud, &edge);
      const double ed = std::sqrt(se.d2);
      const double scale2 = cd[0] * cd[0] + cd[1] * cd[1] + cd[2] * cd[2] + static_cast<double>(hl) * hl +
                            static_cast<double>(h.fd[fp.f_core]) * h.fd[fp.f_core];
      if (face != fe && static_cast<double>(face_d) <= ed + 1e-6 * scale) {
        // An end point above face `face`'s interior.
        if (!(face_d < r)) {
          out.count[k] = 0;
          return;
        }
        const V3 fn = face_normal(h, face);
        nl = -fn;
        depth = r - face_d;
        xs = c + u * (face_end == 0 ? -hl : hl);
        yh = xs - fn * face_d;
      } else if (se.d2 > 1e-12 * scale2) {
        if (!(ed < static_cast<double>(r))) {
          out.count[k] = 0;
          return;
        }
        face = fe;
        const double inv = 1.0 / ed;
        nl = V3{static_cast<float>((se.y[0] - se.x[0]) * inv), static_cast<float>((se.y[1] - se.x[1]) * inv),
                static_cast<float>((se.y[2] - se.x[2]) * inv)};
        depth = static_cast<float>(static_cast<double>(r) - ed);
        xs = V3{static_cast<float>(se.x[0]), static_cast<float>(se.x[1]), static_cast<float>(se.x[2])};
        yh = V3{static_cast<float>(se.y[0]), static_cast<float>(se.y[1]), static_cast<float>(se.y[2])};
      } else {
        deep = true;  // touching up to rounding: the offset's direction is noise
      }
    }
  }

  // --- 4: core meets the hull: face axes and crossing edge axes ---
  if (deep) {
    float s = fp.s_core;
    face = fp.f_core;
    nl = -face_normal(h, face);
    const EdgeAxis ea = sat_edges(h, ab, ae, c, u, kEdgeRound * (scale + r));
    const float lim = s + kTieRel * std::fabs(s) + kTieSize * (scale + r);
    if (ea.key > lim && ea.sep > s) {
      edge_axis = true;
      edge = ea.e;
      s = ea.sep;
      const V3 e0{h.epx[edge], h.epy[edge], h.epz[edge]};
      const V3 ev = vertex(h, vb + h.ev1[edge]) - e0;
      const V3 l = cvx::cross(u, ev);
      const V3 m{h.emx[edge], h.emy[edge], h.emz[edge]};
      const float inv = 1.0f / cvx::len(l);
      nl = l * (cvx::dot(l, m) < 0.0f ? inv : -inv);  // -(axis oriented along m)
      face = fe;
    }
    if (!(s < r)) {
      out.count[k] = 0;
      return;
    }
    depth = r - s;
  }

  // --- 5: points ---
  Manifold mf;
  {
    // The face nl may belong to: known for face contacts; for a shallow edge contact
    // with the core near parallel to the surface, the face whose normal is nearest -nl.
    const bool parallel = std::fabs(cvx::dot(u, nl)) < kParallelSin;
    if (face == fe && !deep && parallel)
      face = cvx::argmax_dot(h.fnx, h.fny, h.fnz, fb, fe, -nl.x, -nl.y, -nl.z);
    V3 p[2];
    float d[2];
    bool clip = false;
    if (face != fe && -cvx::dot(face_normal(h, face), nl) > kFaceCos && (parallel || deep) && !edge_axis)
      clip = face_clip(h, face, c, u, hl, r, nl, p, d);
    if (clip && d[0] > 0.0f && d[1] > 0.0f) {
      mf.count = 2;
      mf.p[0] = p[0], mf.p[1] = p[1];
      mf.d[0] = simd::fmin_nn(d[0], depth), mf.d[1] = simd::fmin_nn(d[1], depth);
    } else if (clip && deep) {
      // A deep face contact that kept one end keeps the deeper one.
      const int i = d[0] >= d[1] ? 0 : 1;
      mf.count = 1;
      mf.p[0] = p[i];
      mf.d[0] = simd::fmin_nn(d[i], depth);
    } else if (!deep) {
      mf.count = 1;  // midway between the closest points
      mf.p[0] = (xs + nl * r + yh) * 0.5f;
      mf.d[0] = depth;
    } else {
      // Deep: the core point nearest the winning edge, or the deepest core point,
      // moved along nl by r - depth/2 (midway between the surfaces along nl).
      float t;
      if (edge_axis) {
        t = static_cast<float>(
            seg_edge(cd, ud, hl, V3{h.epx[edge], h.epy[edge], h.epz[edge]}, vertex(h, vb + h.ev1[edge])).t);
      } else {
        t = cvx::dot(nl, u) >= 0.0f ? hl : -hl;
      }
      mf.count = 1;
      mf.p[0] = c + u * t + nl * (r - 0.5f * depth);
      mf.d[0] = depth;
    }
  }

  // --- world frame ---
  hull_scan::store_from_frame(out, k, ax, pb, nl, depth, mf.count, mf.p, mf.d);
}

}  // namespace

void collide_capsule_convex(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, Range r,
                            const NarrowConfig& cfg) {
  // kSimd and kScalar run the same per-lane code (header block).
  for (uint32_t k = r.begin; k < r.end; ++k) capsule_convex_lane(a, b, out, k, cfg);
}

}  // namespace impact::kernels
