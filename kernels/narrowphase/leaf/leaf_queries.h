// Ray and point queries against one leaf shape in its own local frame: the "point"
// and "ray/segment" columns of the proxy table (host/shapes/shape_queries.cpp
// poses them, walks mesh BVHs and compound children, and runs them in batches).
//
// What
//   ray_leaf_*:   for one ray (RayQuery: origin o, unit direction d, tmax >= 0, may be
//                 +inf; mask ignored) the distance t in [0, tmax] of the first point of
//                 the ray inside the leaf, and the unit outward surface normal there.
//                 Solids (every type but the triangle) contain their surface: a ray
//                 whose origin is inside or on one hits at t = 0 with normal = -d (as in
//                 kernels/raycast/ray_primitives.h); otherwise t > 0 is where it enters.
//                 Triangles are two-sided and thin: their normal faces the ray
//                 (dot(n, d) <= 0); a ray in the triangle's plane misses.
//   point_leaf_*: for one point p the signed distance to the surface (< 0 inside,
//                 0 on the surface), the nearest surface point and the unit outward
//                 normal there (for points inside too). Triangles: the unsigned
//                 distance, normal (p - closest)/|p - closest|, or the winding normal
//                 when p lies on the triangle.
// Local frames (include/impact/shapes.h): sphere, box, ellipsoid and hull as given;
//   capsule and cylinder along z, centred; half-space { x : n.x <= offset }.
// Methods
//   sphere, capsule: ray_sphere / ray_capsule of ray_primitives.h; point: clamp to the
//     core (point / segment), then the ball around it.
//   box, cylinder, hull: the ray's parameter interval inside each slab (box), the
//     infinite cylinder and the z slab (cylinder), or each face plane (hull: Cyrus and
//     Beck, "Generalized two- and three-dimensional clipping", Computers & Graphics
//     3(1), 1978) is intersected; the constraint that sets the entry gives the normal.
//     Box and cylinder points are products of 1-D / 2-D clamps. Hull points: inside,
//     the nearest face plane (the projection onto it lies on the hull); outside, the
//     exact closest point over the faces the point is in front of: the projection onto
//     the face when it falls inside the polygon, else the nearest point of its edges.
//   ellipsoid: ray by scaling to the unit sphere. Point: the closest point by the
//     Lagrange condition x_i = e_i^2 y_i / (e_i^2 + s), solved for s by bisection in
//     double on the monotone secular function, with the cases of points on the
//     coordinate planes treated separately (Eberly, "Distance from a Point to an
//     Ellipse, an Ellipsoid, or a Hyperellipsoid", Geometric Tools, 2013). Robust for
//     points near the axes, at the centre and inside.
//   triangle: the watertight ray_triangle of ray_primitives.h; the closest point by
//     Voronoi regions (Ericson, "Real-Time Collision Detection", 2005, sec. 5.1.5).
//   half-space: ray_plane; the point's plane distance.
// Ties (a point equally near two faces, an entry through an edge) go to the first
// constraint in a fixed order (x, y, z; side before cap; lowest face index), so every
// result is a deterministic function of the input bytes. Points on a symmetry axis use
// a fixed fallback direction (+x; sphere centre +x).
// Preconditions: finite inputs, |d| = 1 to float rounding, positive sizes (capsule
//   half length >= 0), unit half-space normal, a valid hull index. Inf never reaches
//   these functions (the host rejects it), except tmax = +inf.
// Cost: tens of flops (hull: O(faces) for rays, O(face vertices) for outside points;
//   ellipsoid points: up to ~150 bisection steps in double).
#pragma once

#include <cmath>
#include <cstdint>

#include "kernels/narrowphase/leaf/leaf.h"
#include "kernels/raycast/ray_primitives.h"

namespace impact::kernels {

/// A ray's entry into one leaf: t < 0 is a miss.
struct LeafRayHit {
  float t = -1.0f;        ///< m along the unit direction; < 0: no hit within tmax
  float n[3] = {0, 0, 0}; ///< unit outward normal at the hit (-d when t == 0 on a solid)
};

/// A point's relation to one leaf.
struct LeafPointResult {
  float distance = 0.0f;        ///< m, signed: < 0 inside (triangles: unsigned)
  float closest[3] = {0, 0, 0}; ///< nearest surface point
  float n[3] = {0, 0, 0};       ///< unit outward normal at closest
};

LeafRayHit ray_leaf_sphere(const RayQuery& q, float radius);
LeafRayHit ray_leaf_capsule(const RayQuery& q, float radius, float half_length);
LeafRayHit ray_leaf_box(const RayQuery& q, const float half[3]);
LeafRayHit ray_leaf_hull(const RayQuery& q, const HullView& hulls, uint32_t hull);
LeafRayHit ray_leaf_cylinder(const RayQuery& q, float radius, float half_length);
LeafRayHit ray_leaf_ellipsoid(const RayQuery& q, const float radii[3]);
LeafRayHit ray_leaf_half_space(const RayQuery& q, const float n[3], float offset);

LeafPointResult point_leaf_sphere(const float p[3], float radius);
LeafPointResult point_leaf_capsule(const float p[3], float radius, float half_length);
LeafPointResult point_leaf_box(const float p[3], const float half[3]);
LeafPointResult point_leaf_hull(const float p[3], const HullView& hulls, uint32_t hull);
LeafPointResult point_leaf_cylinder(const float p[3], float radius, float half_length);
LeafPointResult point_leaf_ellipsoid(const float p[3], const float radii[3]);
LeafPointResult point_leaf_half_space(const float p[3], const float n[3], float offset);

/// Unit normal of the triangle by its winding (v1 - v0) x (v2 - v0).
IMPACT_INLINE void triangle_normal(const float* v0, const float* v1, const float* v2, float out[3]) {
  const float e1[3] = {v1[0] - v0[0], v1[1] - v0[1], v1[2] - v0[2]};
  const float e2[3] = {v2[0] - v0[0], v2[1] - v0[1], v2[2] - v0[2]};
  const double c[3] = {static_cast<double>(e1[1]) * e2[2] - static_cast<double>(e1[2]) * e2[1],
                       static_cast<double>(e1[2]) * e2[0] - static_cast<double>(e1[0]) * e2[2],
                       static_cast<double>(e1[0]) * e2[1] - static_cast<double>(e1[1]) * e2[0]};
  const double l = std::sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
  if (!(l > 0.0)) {
    out[0] = 0.0f;
    out[1] = 0.0f;
    out[2] = 1.0f;
    return;
  }
  for (int i = 0; i < 3; ++i) out[i] = static_cast<float>(c[i] / l);
}

/// Ray against the two-sided triangle (v0, v1, v2): ray_triangle's t, normal facing
/// the ray. s = ray_shear(q).
IMPACT_INLINE LeafRayHit ray_leaf_triangle(const RayQuery& q, const RayShear& s, const float* v0,
                                           const float* v1, const float* v2) {
  LeafRayHit h;
  h.t = ray_triangle(q, s, v0, v1, v2);
  if (h.t < 0.0f) return h;
  triangle_normal(v0, v1, v2, h.n);
  if (dot3(h.n, q.d) > 0.0f) {
    for (float& c : h.n) c = -c;
  }
  return h;
}

/// Unsigned distance from p to the triangle (v0, v1, v2), the nearest point and the
/// normal (see the file header).
IMPACT_INLINE LeafPointResult point_leaf_triangle(const float p[3], const float* v0, const float* v1,
                                                  const float* v2) {
  LeafPointResult r;
  const float ab[3] = {v1[0] - v0[0], v1[1] - v0[1], v1[2] - v0[2]};
  const float ac[3] = {v2[0] - v0[0], v2[1] - v0[1], v2[2] - v0[2]};
  const float ap[3] = {p[0] - v0[0], p[1] - v0[1], p[2] - v0[2]};
  auto finish_at = [&](float cx, float cy, float cz) {
    r.closest[0] = cx;
    r.closest[1] = cy;
    r.closest[2] = cz;
    const float dv[3] = {p[0] - cx, p[1] - cy, p[2] - cz};
    const float d2 = dot3(dv, dv);
    if (d2 > 0.0f) {
      const float l = std::sqrt(d2);
      r.distance = l;
      for (int i = 0; i < 3; ++i) r.n[i] = dv[i] / l;
    } else {
      r.distance = 0.0f;
      triangle_normal(v0, v1, v2, r.n);
    }
  };
  const float d1 = dot3(ab, ap), d2 = dot3(ac, ap);
  if (d1 <= 0.0f && d2 <= 0.0f) {  // vertex v0
    finish_at(v0[0], v0[1], v0[2]);
    return r;
  }
  const float bp[3] = {p[0] - v1[0], p[1] - v1[1], p[2] - v1[2]};
  const float d3 = dot3(ab, bp), d4 = dot3(ac, bp);
  if (d3 >= 0.0f && d4 <= d3) {  // vertex v1
    finish_at(v1[0], v1[1], v1[2]);
    return r;
  }
  const float vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0f && d1 >= 0.0f && d3 <= 0.0f) {  // edge v0-v1
    const float v = d1 / (d1 - d3);
    finish_at(v0[0] + v * ab[0], v0[1] + v * ab[1], v0[2] + v * ab[2]);
    return r;
  }
  const float cp[3] = {p[0] - v2[0], p[1] - v2[1], p[2] - v2[2]};
  const float d5 = dot3(ab, cp), d6 = dot3(ac, cp);
  if (d6 >= 0.0f && d5 <= d6) {  // vertex v2
    finish_at(v2[0], v2[1], v2[2]);
    return r;
  }
  const float vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0f && d2 >= 0.0f && d6 <= 0.0f) {  // edge v0-v2
    const float w = d2 / (d2 - d6);
    finish_at(v0[0] + w * ac[0], v0[1] + w * ac[1], v0[2] + w * ac[2]);
    return r;
  }
  const float va = d3 * d6 - d5 * d4;
  if (va <= 0.0f && (d4 - d3) >= 0.0f && (d5 - d6) >= 0.0f) {  // edge v1-v2
    const float w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    finish_at(v1[0] + w * (v2[0] - v1[0]), v1[1] + w * (v2[1] - v1[1]), v1[2] + w * (v2[2] - v1[2]));
    return r;
  }
  // Inside the face region: the plane distance along the winding normal is the most
  // accurate form (no cancellation in p - closest).
  float n[3];
  triangle_normal(v0, v1, v2, n);
  const float s = dot3(ap, n);
  r.distance = std::fabs(s);
  for (int i = 0; i < 3; ++i) {
    r.closest[i] = p[i] - s * n[i];
    r.n[i] = s < 0.0f ? -n[i] : n[i];
  }
  return r;
}

}  // namespace impact::kernels
