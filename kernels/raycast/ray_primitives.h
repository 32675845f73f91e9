// Scalar ray-primitive tests shared by every ray path: the LBVH traversal
// (kernels/raycast/ray_bvh.h), Embree user geometry (host/raycast/) and the tests.
//
// What: for one ray (origin o, unit direction d, maximum distance tmax >= 0) and one
//   primitive, the distance t in [0, tmax] along d of the first point of the ray that
//   lies in the primitive, or "miss". Distances are in metres because d is unit.
// Solids: spheres, capsules and half-spaces are solid. A ray whose origin lies inside
//   or on one hits it at t = 0 (the caller reports normal = -d there). A ray starting
//   outside hits the surface where it enters.
// Triangles are two-sided and infinitely thin. Test: watertight ray-triangle
//   intersection (Woop, Benthin, Wald, "Watertight Ray/Triangle Intersection", JCGT
//   2(1), 2013): the triangle is sheared into ray space (sheared vertex coordinates
//   rounded to float), and the three edge functions are evaluated exactly in double
//   (the paper's double fallback, taken always), so their signs do not depend on FMA
//   contraction and a ray through a shared edge or vertex hits at least one of the
//   triangles around it (no ray leaks through a closed mesh). Edge rule: points on an edge or vertex belong to
//   every triangle that contains them (edge functions >= 0 on both orientations); the
//   closest-hit reduction then breaks the tie between equal t by the lower primitive
//   index. A ray lying in the triangle's plane (det == 0) misses it.
// Sphere: closest-approach form. The ray's nearest point to the centre is computed as a
//   vector (oc - tca d), so its squared distance does not suffer the cancellation of
//   |oc|^2 - tca^2 for spheres far away along the ray; r^2 - m^2 is factored
//   (r - m)(r + m). The entry distance tca - thc keeps full relative precision unless
//   the origin is within a few ulps of the surface.
// Capsule (segment a-b, radius r): origin inside <=> distance(o, segment) <= r. Else
//   the first entry is the least of: the entries of the two end balls and the entry of
//   the infinite cylinder when its axial coordinate lies in [0, |b - a|] (the flat
//   cylinder caps lie inside the balls, so they never come first). Cylinder in the
//   closest-approach form of the sphere, in the plane across the axis. A ray parallel
//   to the axis meets only the balls; a zero-length capsule is a sphere.
// Half-space {x : dot(n, x) <= offset}, n unit: s = dot(n, o) - offset; s <= 0 is inside
//   (t = 0); else the ray enters iff dot(n, d) < 0, at t = s / -dot(n, d).
// Preconditions: finite inputs, |d| = 1 (to float rounding), r > 0, n unit, tmax >= 0.
//   Inf is rejected at the API and never reaches these functions.
// Cost: a few tens of flops each; no branches on data beyond the accept/reject tests.
#pragma once

#include <cmath>
#include <cstdint>

#include "kernels/common/kernel.h"

namespace impact::kernels {

/// One ray as the kernels see it: unit direction, maximum distance, layer mask.
struct RayQuery {
  float o[3];
  float d[3];
  float tmax;     ///< m, >= 0
  uint32_t mask;  ///< layer bits the ray sees: a primitive is tested iff (layer & mask) != 0
};
static_assert(sizeof(RayQuery) == 32);

/// Kinds of primitive a hit can be on (RayBest::kind).
enum : uint32_t {
  kRayHitNone = 0,
  kRayHitTriangle = 1,
  kRayHitSphere = 2,
  kRayHitCapsule = 3,
  kRayHitPlane = 4,
  kRayHitShape = 5,  ///< a posed shape of RayScene::set_shapes (prim = object index)
};

/// The best hit of one ray so far. Reductions keep the smaller t; between equal t the
/// smaller (kind, prim) wins, so the result does not depend on visit order.
struct RayBest {
  float t;        ///< m; tmax when no hit yet
  uint32_t kind;  ///< kRayHit*
  uint32_t prim;  ///< index among primitives of that kind (triangles: over all meshes)
};

IMPACT_INLINE bool ray_best_better(float t, uint32_t kind, uint32_t prim, const RayBest& b) {
  if (t != b.t) return t < b.t;
  if (b.kind == kRayHitNone) return true;
  return kind != b.kind ? kind < b.kind : prim < b.prim;
}

IMPACT_INLINE float dot3(const float a[3], const float b[3]) {
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

/// Entry distance into the ball (c, r), or -1 when the ray misses it within tmax.
IMPACT_INLINE float ray_sphere(const RayQuery& q, float cx, float cy, float cz, float r) {
  const float oc[3] = {cx - q.o[0], cy - q.o[1], cz - q.o[2]};
  const float oc2 = dot3(oc, oc);
  if (oc2 <= r * r) return 0.0f;  // origin inside or on the sphere
  const float tca = dot3(oc, q.d);
  if (tca < 0.0f) return -1.0f;   // centre behind an origin outside: no entry ahead
  const float m[3] = {oc[0] - tca * q.d[0], oc[1] - tca * q.d[1], oc[2] - tca * q.d[2]};
  const float m2 = dot3(m, m);
  if (m2 > r * r) return -1.0f;
  const float mm = std::sqrt(m2);
  const float thc = std::sqrt((r - mm) * (r + mm));
  const float t = tca - thc;
  if (t > q.tmax) return -1.0f;
  return t < 0.0f ? 0.0f : t;  // rounding at the surface: the origin is on it
}

/// Entry distance into the capsule (segment a-b, radius r), or -1 on a miss within tmax.
IMPACT_INLINE float ray_capsule(const RayQuery& q, const float a[3], const float b[3], float r) {
  const float ab[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
  const float ao[3] = {q.o[0] - a[0], q.o[1] - a[1], q.o[2] - a[2]};
  const float len2 = dot3(ab, ab);
  // Origin inside: distance from o to the segment.
  {
    float s = len2 > 0.0f ? dot3(ao, ab) / len2 : 0.0f;
    s = s < 0.0f ? 0.0f : (s > 1.0f ? 1.0f : s);
    const float w[3] = {ao[0] - s * ab[0], ao[1] - s * ab[1], ao[2] - s * ab[2]};
    if (dot3(w, w) <= r * r) return 0.0f;
  }
  float best = -1.0f;
  auto take = [&](float t) {
    if (t >= 0.0f && (best < 0.0f || t < best)) best = t;
  };
  take(ray_sphere(q, a[0], a[1], a[2], r));
  take(ray_sphere(q, b[0], b[1], b[2], r));
  if (len2 > 0.0f) {
    const float inv_len = 1.0f / std::sqrt(len2);
    const float u[3] = {ab[0] * inv_len, ab[1] * inv_len, ab[2] * inv_len};
    // Across-axis parts of the direction and of (a - o).
    const float du = dot3(q.d, u);
    const float dp[3] = {q.d[0] - du * u[0], q.d[1] - du * u[1], q.d[2] - du * u[2]};
    const float A = dot3(dp, dp);
    if (A > 1e-12f) {
      const float oa[3] = {-ao[0], -ao[1], -ao[2]};
      const float wu = dot3(oa, u);
      const float wp[3] = {oa[0] - wu * u[0], oa[1] - wu * u[1], oa[2] - wu * u[2]};
      const float tca = dot3(wp, dp) / A;  // parameter of the closest approach to the axis
      if (tca >= 0.0f) {
        const float m[3] = {wp[0] - tca * dp[0], wp[1] - tca * dp[1], wp[2] - tca * dp[2]};
        const float m2 = dot3(m, m);
        if (m2 <= r * r) {
          const float mm = std::sqrt(m2);
          const float thc = std::sqrt((r - mm) * (r + mm) / A);
          float t = tca - thc;
          if (t < 0.0f) t = 0.0f;
          // Axial coordinate of the entry point, relative to a.
          const float y = dot3(ao, u) + t * du;
          if (y >= 0.0f && y * y <= len2) take(t);
        }
      }
    }
  }
  return best <= q.tmax ? best : -1.0f;
}

/// Per-ray set-up of the watertight triangle test.
struct RayShear {
  uint32_t kx, ky, kz;
  float sx, sy, sz;
};

IMPACT_INLINE RayShear ray_shear(const RayQuery& q) {
  const float ax = std::fabs(q.d[0]), ay = std::fabs(q.d[1]), az = std::fabs(q.d[2]);
  uint32_t kz = ax >= ay ? (ax >= az ? 0u : 2u) : (ay >= az ? 1u : 2u);
  uint32_t kx = kz == 2 ? 0 : kz + 1;
  uint32_t ky = kx == 2 ? 0 : kx + 1;
  if (q.d[kz] < 0.0f) {
    const uint32_t tmp = kx;
    kx = ky;
    ky = tmp;
  }
  RayShear s;
  s.kx = kx;
  s.ky = ky;
  s.kz = kz;
  s.sx = q.d[kx] / q.d[kz];
  s.sy = q.d[ky] / q.d[kz];
  s.sz = 1.0f / q.d[kz];
  return s;
}

/// Distance to the triangle (v0, v1, v2) along the ray, or -1 on a miss within tmax.
/// Watertight whatever the compiler does with FMA contraction: every step whose bits
/// decide an edge's sign is one rounding of an exact value. A vertex's sheared
/// coordinates are float(p_k - s_k p_z) evaluated in double, where the product of two
/// floats is exact, so fused or not they are the same bits in every triangle using the
/// vertex; the edge functions are products of those floats, again exact in double, so
/// their signs are the exact signs and an edge seen from its two triangles gives exactly
/// opposite values (in float, a contracted a*b - c*d rounds the two products
/// differently on the two sides and a ray through the edge can miss both). This is the
/// double re-evaluation of Woop et al. made unconditional: on scalar SSE/NEON code a
/// double multiply-add costs what a float one does.
IMPACT_INLINE float ray_triangle(const RayQuery& q, const RayShear& s, const float* v0, const float* v1,
                                 const float* v2) {
  const float A[3] = {v0[0] - q.o[0], v0[1] - q.o[1], v0[2] - q.o[2]};
  const float B[3] = {v1[0] - q.o[0], v1[1] - q.o[1], v1[2] - q.o[2]};
  const float C[3] = {v2[0] - q.o[0], v2[1] - q.o[1], v2[2] - q.o[2]};
  const double sx = s.sx, sy = s.sy;
  auto shear = [](const float* P, uint32_t k, double sk, uint32_t kz) {
    return static_cast<double>(static_cast<float>(static_cast<double>(P[k]) - sk * static_cast<double>(P[kz])));
  };
  const double ax = shear(A, s.kx, sx, s.kz), ay = shear(A, s.ky, sy, s.kz);
  const double bx = shear(B, s.kx, sx, s.kz), by = shear(B, s.ky, sy, s.kz);
  const double cx = shear(C, s.kx, sx, s.kz), cy = shear(C, s.ky, sy, s.kz);
  const double U = cx * by - cy * bx;
  const double V = ax * cy - ay * cx;
  const double W = bx * ay - by * ax;
  if ((U < 0.0 || V < 0.0 || W < 0.0) && (U > 0.0 || V > 0.0 || W > 0.0)) return -1.0f;
  const double det = U + V + W;
  if (det == 0.0) return -1.0f;
  const double sz = s.sz;
  const double T = U * (sz * A[s.kz]) + V * (sz * B[s.kz]) + W * (sz * C[s.kz]);
  const double t = T / det;
  if (!(t >= 0.0) || t > static_cast<double>(q.tmax)) return -1.0f;
  const float tf = static_cast<float>(t);
  return tf > q.tmax ? q.tmax : tf;  // float rounding may land just past tmax
}

/// Entry distance into the half-space {x : dot(n, x) <= offset} (n unit), or -1.
IMPACT_INLINE float ray_plane(const RayQuery& q, const float n[3], float offset) {
  const float s = dot3(n, q.o) - offset;
  if (s <= 0.0f) return 0.0f;
  const float dn = dot3(n, q.d);
  if (!(dn < 0.0f)) return -1.0f;
  const float t = s / -dn;
  return t <= q.tmax ? t : -1.0f;
}

}  // namespace impact::kernels
