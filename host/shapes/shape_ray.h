// One ray against one posed shape: the per-object ray code of impact::raycast_shapes
// (host/shapes/shape_queries.cpp), shared with RayScene's shape geometry
// (host/raycast/) so both give the same hits.
#pragma once

#include <Eigen/Core>

#include "host/shapes/shape_store.h"
#include "impact/shape_queries.h"
#include "impact/shapes.h"

namespace impact::host {

/// The rotation a query uses for an object: identity for AABB shapes (they ignore the
/// pose's orientation), else the normalised pose's rotation matrix.
Eigen::Matrix3f shape_rotation(const ShapeRecord& rec, const Pose& pose);

/// The first hit of the ray (origin o, unit direction d, 0 <= tmax, may be +inf) with
/// the shape rec (not a half-space) placed at world = R * local + p; the rules of
/// include/impact/shape_queries.h (hit = false on a miss).
ShapeRayHit ray_posed_shape(const ShapeStore& store, const ShapeRecord& rec, const Eigen::Matrix3f& R,
                            const Eigen::Vector3f& p, const Eigen::Vector3f& o, const Eigen::Vector3f& d,
                            float tmax);

}  // namespace impact::host
