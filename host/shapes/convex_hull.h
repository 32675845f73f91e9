// 3D convex hulls of point clouds for ShapeSet::add_convex_hull.
#pragma once

#include <span>

#include <Eigen/Core>

#include "host/shapes/shape_store.h"
#include "impact/status.h"

namespace impact {

/// Convex hull of `points` (quickhull, Barber, Dobkin, Huhdanpaa 1996, in double).
/// Coplanar triangles are merged into polygons (counter-clockwise seen from outside);
/// face normals are unit and outward with offsets (every vertex v: n.v <= offset);
/// one unit edge direction per parallel class. Vertices are input points (float, as
/// given), numbered in order of first use by the faces. Points within a relative 1e-9
/// of the extent of the hull's surface count as on it (duplicates, face centres).
/// Errors (kInvalidArgument, *out unchanged): fewer than 4 points, a non-finite point
/// (named by index), all points collinear or coplanar within a relative 1e-6 of the
/// bounding box diagonal.
Status build_convex_hull(std::span<const Eigen::Vector3f> points, HullData* out);

}  // namespace impact
