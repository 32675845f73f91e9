// Ray casts and point queries against posed shapes: the "ray/segment" and "point"
// columns of the proxy table, for every shape type of include/impact/shapes.h.
//
// Both calls are batched: query k names an object (an index into shape_of / poses, as
// in NarrowPhase::collide) and gets one result in out[k]. The work runs in fixed-size
// chunks, so results are the same bytes for every backend and thread count.
//
// Rules (tests/host/shapes/shape_queries_test.cpp checks them against a
// double-precision reference):
//  - Solids (every type but the mesh) contain their surface. A ray whose origin lies
//    inside or on one hits it at t = 0 with point = origin and normal = -direction.
//    Otherwise the hit is where the ray enters, 0 < t <= tmax, with the unit outward
//    surface normal there (at an edge or vertex: the normal of one adjacent face).
//  - Meshes are two-sided, infinitely thin triangles: the normal faces the ray; a ray
//    lying in a triangle's plane misses it; equal t goes to the lower triangle index.
//    A mesh encloses nothing: its point queries give the unsigned distance, inside is
//    always false.
//  - Compounds: the closest hit / the smallest signed distance over the children (the
//    lower child index on ties); child names the child. Outside the union that is the
//    exact distance; inside, it is the deepest child's, whose closest point may lie
//    inside another (overlapping) child.
//  - An AABB shape ignores the pose's orientation (include/impact/shapes.h).
//  - Precision: every query is solved in the shape's local frame relative to the pose
//    position, so poses far (1e5 m) from the world origin keep float accuracy relative
//    to the shape's size; the world point / closest point carry the rounding of their
//    own magnitude.
#pragma once

#include <cstdint>
#include <span>

#include <Eigen/Core>

#include "impact/broadphase.h"
#include "impact/narrowphase.h"
#include "impact/raycast.h"
#include "impact/shapes.h"
#include "impact/status.h"

namespace impact {

/// One ray against one object. Ray: origin (finite), direction (finite, non-zero;
/// normalised by the call), tmax (>= 0, may be +inf: m along the unit direction);
/// mask is ignored here. A segment from a to b is the ray (a, b - a, |b - a|).
struct ObjectRay {
  Ray ray;              ///< the ray, world frame
  uint32_t object = 0;  ///< index into shape_of / poses
};

/// Where a ray first meets its object.
struct ShapeRayHit {
  bool hit = false;  ///< the ray meets the object within [0, tmax]
  float t = 0.0f;                                    ///< m along the unit direction, in [0, tmax]
  Eigen::Vector3f point = Eigen::Vector3f::Zero();   ///< world: origin + t * unit direction
  /// Unit, world: the outward surface normal at the hit (-direction when t = 0 inside a
  /// solid; facing the ray for mesh triangles).
  Eigen::Vector3f normal = Eigen::Vector3f::Zero();
  uint32_t child = kNoChild;  ///< compound child / mesh triangle hit, else kNoChild
};

/// Closest hit of each ray with its object: out[k] for rays[k]; a miss is
/// ShapeRayHit{} (hit = false, zero vectors, child = kNoChild).
/// Errors (out unspecified): kSizeMismatch when shape_of and poses, or rays and out,
/// differ in length; kInvalidArgument naming the index and field for an unknown shape
/// id, a non-finite pose or a quaternion not unit within 1e-3 (object i), an object
/// index out of range, a non-finite origin, a zero or non-finite direction, or a NaN or
/// negative tmax (ray k); kUnsupported for a backend not built in.
Status raycast_shapes(const ShapeSet& shapes, std::span<const ShapeId> shape_of, std::span<const Pose> poses,
                      std::span<const ObjectRay> rays, std::span<ShapeRayHit> out,
                      const ExecConfig& exec = {});

/// One point against one object.
struct ObjectPoint {
  Eigen::Vector3f point = Eigen::Vector3f::Zero();  ///< world, finite
  uint32_t object = 0;                              ///< index into shape_of / poses
};

/// A point's relation to its object.
struct ShapePointResult {
  /// The point lies in the closed solid (distance <= 0); always false for meshes.
  bool inside = false;
  /// m, signed: < 0 inside, 0 on the surface, > 0 outside (meshes: unsigned).
  float distance = 0.0f;
  Eigen::Vector3f closest = Eigen::Vector3f::Zero();  ///< world: the nearest surface point
  /// Unit, world: the outward normal at closest (for inside points too); for a point
  /// off the surface, (point - closest) / distance up to rounding. Meshes: from the
  /// triangle to the point (the winding normal when the point lies on it).
  Eigen::Vector3f normal = Eigen::Vector3f::Zero();
  uint32_t child = kNoChild;  ///< compound child / mesh triangle nearest, else kNoChild
};

/// Signed distance, nearest surface point and normal of each point with respect to
/// its object: out[k] for points[k]. Errors as raycast_shapes (a non-finite point is
/// kInvalidArgument naming point k).
Status query_shape_points(const ShapeSet& shapes, std::span<const ShapeId> shape_of, std::span<const Pose> poses,
                          std::span<const ObjectPoint> points, std::span<ShapePointResult> out,
                          const ExecConfig& exec = {});

}  // namespace impact
