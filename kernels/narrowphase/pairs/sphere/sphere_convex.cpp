// Sphere (A) against convex hull (B): exact closest feature of the hull, no GJK / EPA.
//
// What: collide_sphere_convex writes, per lane k in r, the collision data of leaf.h for
// a sphere (centre p, radius e0) and a convex hull (pose p, R; hull ref in cfg.hulls):
// count 0 or 1, unit normal n from the sphere to the hull (the hull moves along n by
// depth to separate), depth, point[0] midway between the two surfaces, pdepth[0] =
// depth. Slots 1..3 are untouched; count 0 lanes leave everything else unspecified.
// Method, per lane, in the hull's local frame: c = R^T (centre - hull position), in
// double (exact differences of the float inputs; the float passes use it rounded), so
// poses far from the origin keep their precision.
//  1. One pass over the hull's face planes, kSimdWidth faces per step: s = max_f
//     (fn_f.c - fd_f) and its face f* (the lowest index among ties). s is a lower bound
//     of the distance from c to the hull, and minus the depth of c when c is inside.
//  2. s >= r: separated (count 0; s = r is touching, also count 0).
//  3. s <= 0: c inside (or on) the hull; the nearest face is f* (for a point in a
//     convex polytope the distance to the boundary is the least plane distance), so
//     n = -R fn*, depth = r - s, the hull point c - s fn* on that face.
//  4. 0 < s < r: c outside. If the closest point x of the hull lies inside a face f,
//     then c - x = |c - x| fn_f, and every other face g has fn_g.c - fd_g < |c - x|:
//     f is f*. So: c's projection on f*'s plane inside the polygon f* (one side test
//     per polygon edge) -> x = that projection, distance s, n = -R fn*. Faces within
//     the planes' float rounding of s (nearly coplanar neighbours) are tried the same
//     way (their values kept from step 1). Otherwise x lies on an edge (or a vertex):
//     the least distance from c to a hull edge segment over the hull's edge list
//     (HullView adj_*: every edge once, padded to a multiple of 8; the far end
//     gathered by index). A float pass, kSimdWidth edges per step, finds the least
//     distance; the edges within twice its rounding bound are evaluated again in
//     double and the nearest wins (lowest index among exact ties): a distance is flat
//     about its minimum, so float alone could pick a neighbouring edge and tilt the
//     normal by ~sqrt(1e-7 / distance). n = R (x - c)/|x - c|, depth = r - |x - c|
//     (count 0 when |x - c| >= r). When |x - c| is below 1e-6 of the coordinates (c on
//     an edge up to rounding) its direction is noise: the lane keeps step 3's answer
//     with f* (n = -R fn*, depth = r - s: the exact overlap along that n, less than
//     |x - c| from r - |x - c|).
//  Hulls without edge adjacency (faces that do not close into a 2-manifold) scan the
//  face polygons' edges in double instead (each edge twice); a hull without faces in
//  HullView goes through the general GJK / EPA lane (collide_convex_lane).
// Inputs: lanes per leaf.h (finite, radius > 0, R orthonormal), hulls as HullStore
// builds them (unit outward face normals, counter-clockwise polygons).
// Precision: the plane distances (float) carry ~1e-7 of the local coordinates, the
// edge distances are exact in double for the float inputs; depth and normal are then
// within ~1e-7 of the coordinates (tested against a double reference at 2e-5 of the
// size). Points are written relative to the hull position. No division without a
// guard: no NaN for finite input (Inf is not accepted). No allocation: hulls up to 512
// faces / edges keep their pass values in stack buffers, larger hulls compute them
// again (no limit on the face or edge count).
// Paths: nothing here vectorises across lanes (each lane walks its own hull); cfg.path
// kSimd and kScalar run this same per-lane code (bit-identical results, as GJK / EPA
// do); within a lane the face and edge passes run kSimdWidth at a time; the one-lane
// build (IMPACT_SIMD_SCALAR) runs them with kSimdWidth = 1.
// Cost: O(F) for separated and deep lanes, O(F + E) for the others (a second look at
// the kept values and a few edges in double). Measured per pair in
// docs/results.md ("Narrow phase").
// Method citations: the Voronoi-region view of the closest point on a convex
// polyhedron, Ericson, Real-Time Collision Detection (2005), ch. 5.1; the
// minimum-translation rule for an interior point as in sphere-box (sphere_box.cpp).
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
using namespace hull_scan;  // NOLINT: the hull kernels' shared passes

/// fn.c - fd of faces i .. i + kSimdWidth.
IMPACT_INLINE FloatW plane_dist(const HullView& h, uint32_t i, FloatW X, FloatW Y, FloatW Z) {
  using F = FloatW;
  return X * F::load(h.fnx + i) + Y * F::load(h.fny + i) + Z * F::load(h.fnz + i) - F::load(h.fd + i);
}
IMPACT_INLINE float plane_dist(const HullView& h, uint32_t i, V3 c) {
  return c.x * h.fnx[i] + c.y * h.fny[i] + c.z * h.fnz[i] - h.fd[i];
}

/// s = max over faces f in [b, e) of fn_f.c - fd_f, in *out_f the lowest f that has it.
/// keep: null, or room for e - b values: each face's value at f - b (wide path only).
IMPACT_INLINE float deepest_plane(const HullView& h, uint32_t b, uint32_t e, V3 c, uint32_t* out_f,
                                  float* keep) {
  float best_s = -INFINITY;
  uint32_t best = b;
  if (e - b >= kSimdWidth) {
    using F = FloatW;
    const F lane = simd::lane_index<F>(), X(c.x), Y(c.y), Z(c.z);
    F m(-INFINITY), idx(0.0f);
    for (uint32_t i = b;; i = next_block(i, e)) {
      const F s = plane_dist(h, i, X, Y, Z);
      if (keep != nullptr) s.store(keep + (i - b));
      const auto gt = s > m;  // strict: each lane keeps its first maximum
      m = select(gt, s, m);
      idx = select(gt, lane + F(static_cast<float>(i - b)), idx);
      if (i + kSimdWidth == e) break;
    }
    float bi;
    best_s = simd::max_lowest_index(m, idx, static_cast<float>(e - b), &bi);
    best = b + static_cast<uint32_t>(bi);
  } else {
    for (uint32_t i = b; i < e; ++i) {
      const float s = plane_dist(h, i, c);
      if (s > best_s) {
        best_s = s;
        best = i;
      }
    }
  }
  *out_f = best;
  return best_s;
}

/// The lowest face g in [b, e), g != skip, with fn_g.c - fd_g >= s_min (the faces that
/// tie with the deepest plane up to rounding) into whose polygon c projects, or e when
/// there is none. kept: deepest_plane's values (or null: computed again, same formula).
IMPACT_INLINE uint32_t near_tie_face(const HullView& h, uint32_t b, uint32_t e, uint32_t skip, V3 c,
                                     float s_min, const float* kept) {
  if (e - b < kSimdWidth) {
    for (uint32_t i = b; i < e; ++i)
      if (i != skip && plane_dist(h, i, c) >= s_min && projects_into_face(h, i, c)) return i;
    return e;
  }
  using F = FloatW;
  const F X(c.x), Y(c.y), Z(c.z), lo(s_min);
  // Ascending; the last block's revisits were looked at already.
  for (uint32_t i = b;; i = next_block(i, e)) {
    const F s = kept != nullptr ? F::load(kept + (i - b)) : plane_dist(h, i, X, Y, Z);
    const auto near = s >= lo;
    if (simd::any(near)) {
      for (uint32_t l = 0; l < kSimdWidth; ++l)
        if (near.lane(l) && i + l != skip && projects_into_face(h, i + l, c)) return i + l;
    }
    if (i + kSimdWidth == e) break;
  }
  return e;
}

/// Squared distance from c to edges i .. i + kSimdWidth of the adjacency list (start ep,
/// far end gathered through ev1 from (bx, by, bz) = the hull's vertices), in float; in
/// *size |w|_1 + |d|_1 (w = c - start, d = the edge), which bounds its rounding.
IMPACT_INLINE FloatW edge_dist2(const HullView& h, uint32_t i, const float* bx, const float* by,
                                const float* bz, FloatW cx, FloatW cy, FloatW cz, FloatW* size) {
  using F = FloatW;
  const F ax = F::load(h.epx + i), ay = F::load(h.epy + i), az = F::load(h.epz + i);
  const simd::IntW j = simd::IntW::load(reinterpret_cast<const int32_t*>(h.ev1 + i));
  const F dx = simd::gather(bx, j) - ax, dy = simd::gather(by, j) - ay, dz = simd::gather(bz, j) - az;
  const F wx = cx - ax, wy = cy - ay, wz = cz - az;
  const F dd = dx * dx + dy * dy + dz * dz;
  const F wd = wx * dx + wy * dy + wz * dz;
  // dd > 0 for a hull edge; the guard only keeps a zero-length edge finite (t = 0).
  const F t = simd::clamp(wd / simd::max(dd, F(FLT_MIN)), F(0.0f), F(1.0f));
  const F ex = wx - t * dx, ey = wy - t * dy, ez = wz - t * dz;
  *size = simd::abs(wx) + simd::abs(wy) + simd::abs(wz) + simd::abs(dx) + simd::abs(dy) + simd::abs(dz);
  return ex * ex + ey * ey + ez * ez;
}

/// A point-to-segment offset in double: e = c - x for the closest point x of a..b.
struct EdgeOffset {
  double d2 = INFINITY;
  double e[3] = {0, 0, 0};
};

/// c - x for the closest point x of segment a..b to c, in double (a, b float exactly).
IMPACT_INLINE EdgeOffset offset_from_edge(V3 a, V3 b, const double c[3]) {
  const double ad[3] = {a.x, a.y, a.z};
  const double d[3] = {static_cast<double>(b.x) - ad[0], static_cast<double>(b.y) - ad[1],
                       static_cast<double>(b.z) - ad[2]};
  const double w[3] = {c[0] - ad[0], c[1] - ad[1], c[2] - ad[2]};
  const double dd = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
  const double wd = w[0] * d[0] + w[1] * d[1] + w[2] * d[2];
  double t = dd > 0.0 ? wd / dd : 0.0;
  t = t < 0.0 ? 0.0 : (t > 1.0 ? 1.0 : t);
  EdgeOffset o;
  for (int i = 0; i < 3; ++i) o.e[i] = w[i] - t * d[i];
  o.d2 = o.e[0] * o.e[0] + o.e[1] * o.e[1] + o.e[2] * o.e[2];
  return o;
}

/// Keeps o if it is strictly nearer than *best.
IMPACT_INLINE void keep_nearer(const EdgeOffset& o, EdgeOffset* best) {
  if (o.d2 < best->d2) *best = o;
}

/// The nearest of hull h's edges to c (adjacency list [ab, ae), far ends by hull-local
/// index from vb), exactly for the float inputs. A float pass, kSimdWidth edges per
/// step, finds the least distance; every edge within twice the rounding bound of it is
/// then evaluated in double and the nearest wins (the lowest index among exact ties).
/// Why not float alone: a distance is flat about its minimum, so edges that meet near
/// the closest point differ by less than the float rounding (~1e-7 of the coordinates),
/// and picking the wrong one tilts the normal by ~sqrt(1e-7 / distance).
/// c and cd: the centre in float and in double.
IMPACT_INLINE EdgeOffset nearest_edge(const HullView& h, uint32_t ab, uint32_t ae, uint32_t vb, V3 c,
                                      const double cd[3]) {
  EdgeOffset best;
  const float* bx = h.vx + vb;
  const float* by = h.vy + vb;
  const float* bz = h.vz + vb;
  if (ae - ab < kSimdWidth) {
    for (uint32_t i = ab; i < ae; ++i)
      keep_nearer(offset_from_edge(V3{h.epx[i], h.epy[i], h.epz[i]}, vertex(h, vb + h.ev1[i]), cd), &best);
    return best;
  }
  using F = FloatW;
  const F X(c.x), Y(c.y), Z(c.z);
  float kept[kKeep];
  const bool keep = ae - ab <= kKeep;
  F m(INFINITY), big(0.0f);
  for (uint32_t i = ab;; i = next_block(i, ae)) {
    F size;
    const F d2 = edge_dist2(h, i, bx, by, bz, X, Y, Z, &size);
    if (keep) d2.store(kept + (i - ab));
    m = simd::min(m, d2);
    big = simd::max(big, size);
    if (i + kSimdWidth == ae) break;
  }
  // A float distance here is off by a few ulps of |w|_1 + |d|_1 (the cancellation along
  // the edge) plus c's own rounding; 1e-6 of them bounds that with a wide margin.
  const float err = 1e-6f * (lanes_max(big) + std::fabs(c.x) + std::fabs(c.y) + std::fabs(c.z));
  const float lim = std::sqrt(lanes_min(m)) + 2.0f * err;
  const F lim2(lim * lim);
  for (uint32_t i = ab;; i = next_block(i, ae)) {
    F size;
    const F d2 = keep ? F::load(kept + (i - ab)) : edge_dist2(h, i, bx, by, bz, X, Y, Z, &size);
    const auto cand = d2 <= lim2;
    if (simd::any(cand)) {
      for (uint32_t l = 0; l < kSimdWidth; ++l)
        if (cand.lane(l))
          keep_nearer(offset_from_edge(V3{h.epx[i + l], h.epy[i + l], h.epz[i + l]},
                                       vertex(h, vb + h.ev1[i + l]), cd),
                      &best);
    }
    if (i + kSimdWidth == ae) break;
  }
  return best;
}

/// nearest_edge for a hull without edge adjacency: every polygon edge of faces
/// [fb, fe) (each hull edge twice), one at a time, in double.
IMPACT_INLINE EdgeOffset nearest_polygon_edge(const HullView& h, uint32_t fb, uint32_t fe,
                                              const double cd[3]) {
  EdgeOffset best;
  for (uint32_t f = fb; f < fe; ++f) {
    const uint32_t b = h.face_vert_begin[f], e = h.face_vert_begin[f + 1];
    if (e == b) continue;
    V3 p = vertex(h, h.face_verts[e - 1]);
    for (uint32_t j = b; j < e; ++j) {
      const V3 q = vertex(h, h.face_verts[j]);
      keep_nearer(offset_from_edge(p, q, cd), &best);
      p = q;
    }
  }
  return best;
}

void sphere_convex_lane(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, uint32_t k,
                        const NarrowConfig& cfg) {
  const HullView& h = cfg.hulls;
  const uint32_t hull = b.ref[k];
  const uint32_t fb = h.face_begin != nullptr ? h.face_begin[hull] : 0u;
  const uint32_t fe = h.face_begin != nullptr ? h.face_begin[hull + 1] : 0u;
  if (fe == fb) {  // a hull HullView holds no faces for: the general path, this lane
    collide_gjk_epa(a, b, out, Range{k, k + 1}, cfg, kLeafSphere, kLeafConvex);
    return;
  }
  const float r = a.e[0][k];
  const V3 pb{b.p[0][k], b.p[1][k], b.p[2][k]};
  // Hull axes (R's columns) and the centre in the hull's frame.
  V3 ax[3];
  for (int col = 0; col < 3; ++col) ax[col] = V3{b.r[col][k], b.r[3 + col][k], b.r[6 + col][k]};
  // In double (the edge distances near the closest point need it; the float passes
  // use its rounding): the difference of two floats is exact there, as is a product.
  const double dw[3] = {static_cast<double>(a.p[0][k]) - pb.x, static_cast<double>(a.p[1][k]) - pb.y,
                        static_cast<double>(a.p[2][k]) - pb.z};
  double cd[3];
  for (int col = 0; col < 3; ++col)
    cd[col] = static_cast<double>(ax[col].x) * dw[0] + static_cast<double>(ax[col].y) * dw[1] +
              static_cast<double>(ax[col].z) * dw[2];
  const V3 c{static_cast<float>(cd[0]), static_cast<float>(cd[1]), static_cast<float>(cd[2])};

  uint32_t f;
  float kept[kKeep];  // the faces' plane distances, for near_tie_face
  const bool keep = fe - fb <= kKeep;
  const float s = deepest_plane(h, fb, fe, c, &f, keep ? kept : nullptr);
  if (!(s < r)) {
    out.count[k] = 0;
    return;
  }
  const V3 fn{h.fnx[f], h.fny[f], h.fnz[f]};
  // Default: face f* (inside, or outside with the projection in the polygon).
  V3 nl = -fn;
  float depth = r - s;
  V3 x = c - fn * s;  // hull point, local
  if (s > 0.0f && !projects_into_face(h, f, c)) {
    // Faces that tie with f* up to the rounding of their planes (nearly coplanar
    // neighbours: their s differ by ~1e-7 of the coordinates) may hold the closest
    // point instead: any face with s_g >= s - slack whose polygon c projects into.
    const float slack = 1e-5f * (std::fabs(c.x) + std::fabs(c.y) + std::fabs(c.z) + std::fabs(h.fd[f]));
    const uint32_t g = near_tie_face(h, fb, fe, f, c, s - slack, keep ? kept : nullptr);
    if (g != fe) {
      const V3 gn{h.fnx[g], h.fny[g], h.fnz[g]};
      const float sg = c.x * gn.x + c.y * gn.y + c.z * gn.z - h.fd[g];
      nl = -gn;
      depth = r - sg;
      x = c - gn * sg;
    } else {
      // Outside, nearest point on an edge or a vertex.
      const EdgeOffset o =
          h.adj_begin != nullptr && h.adj_begin[hull + 1] > h.adj_begin[hull]
              ? nearest_edge(h, h.adj_begin[hull], h.adj_begin[hull + 1], h.vert_begin[hull], c, cd)
              : nearest_polygon_edge(h, fb, fe, cd);
      const double dist = std::sqrt(o.d2);
      if (!(dist < static_cast<double>(r))) {
        out.count[k] = 0;
        return;
      }
      // The direction of a (near) zero offset is noise: keep face f* (see the header).
      const double scale2 =
          cd[0] * cd[0] + cd[1] * cd[1] + cd[2] * cd[2] + static_cast<double>(h.fd[f]) * h.fd[f];
      if (o.d2 > 1e-12 * scale2) {
        const double inv = -1.0 / dist;
        nl = V3{static_cast<float>(o.e[0] * inv), static_cast<float>(o.e[1] * inv),
                static_cast<float>(o.e[2] * inv)};
        depth = static_cast<float>(static_cast<double>(r) - dist);
        x = V3{static_cast<float>(cd[0] - o.e[0]), static_cast<float>(cd[1] - o.e[1]),
               static_cast<float>(cd[2] - o.e[2])};
      }
    }
  }
  // World normal and the point midway between the sphere's deepest point and x.
  const V3 n = ax[0] * nl.x + ax[1] * nl.y + ax[2] * nl.z;
  const V3 mid = (c + nl * r + x) * 0.5f;
  out.count[k] = 1;
  out.n[0][k] = n.x;
  out.n[1][k] = n.y;
  out.n[2][k] = n.z;
  out.depth[k] = depth;
  out.point[0][0][k] = pb.x + (ax[0].x * mid.x + ax[1].x * mid.y + ax[2].x * mid.z);
  out.point[0][1][k] = pb.y + (ax[0].y * mid.x + ax[1].y * mid.y + ax[2].y * mid.z);
  out.point[0][2][k] = pb.z + (ax[0].z * mid.x + ax[1].z * mid.y + ax[2].z * mid.z);
  out.pdepth[0][k] = depth;
}

}  // namespace

void collide_sphere_convex(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, Range r,
                           const NarrowConfig& cfg) {
  // kSimd and kScalar run the same per-lane code (header block).
  for (uint32_t k = r.begin; k < r.end; ++k) sphere_convex_lane(a, b, out, k, cfg);
}

}  // namespace impact::kernels
