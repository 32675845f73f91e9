// posed_leaf: one convex (or half-space) shape record at a pose, as the leaf the
// one-lane kernels take (kernels/narrowphase/general/support.h): the distance query
// (shape_distance.cpp) and the time of impact (shape_cast.cpp) share it.
// Contract: R is the rotation the record is posed with (an AABB's caller passes the
// frame its axes align with: identity in the world); p is the pose position minus the
// caller's origin, so far poses keep float precision. A half-space record (local
// { n.x <= offset }) becomes the leaf of world normal R n through p + R n offset.
// Mesh and compound records are not leaves (the callers expand them). Cost: O(1).
#pragma once

#include <Eigen/Core>

#include "host/shapes/shape_store.h"
#include "kernels/narrowphase/general/support.h"

namespace impact::host {

inline kernels::cvx::Leaf posed_leaf(const ShapeRecord& r, const Eigen::Matrix3f& R, const Eigen::Vector3f& p,
                                     const kernels::HullView* hulls) {
  using kernels::cvx::V3;
  kernels::cvx::Leaf l;
  l.p = V3{p.x(), p.y(), p.z()};
  for (int c = 0; c < 3; ++c) l.ax[c] = V3{R(0, c), R(1, c), R(2, c)};
  for (int i = 0; i < 3; ++i) l.e[i] = r.e[i];
  switch (r.type) {
    case ShapeType::kSphere: l.type = kernels::kLeafSphere; break;
    case ShapeType::kCapsule: l.type = kernels::kLeafCapsule; break;
    case ShapeType::kBox:
    case ShapeType::kAabb: l.type = kernels::kLeafBox; break;
    case ShapeType::kConvex:
      l.type = kernels::kLeafConvex;
      l.hulls = hulls;
      l.hull = r.ref;
      break;
    case ShapeType::kCylinder: l.type = kernels::kLeafCylinder; break;
    case ShapeType::kEllipsoid: l.type = kernels::kLeafEllipsoid; break;
    case ShapeType::kHalfSpace: {
      l.type = kernels::kLeafHalfSpace;
      const Eigen::Vector3f n = (R * Eigen::Vector3f(r.e[0], r.e[1], r.e[2])).normalized();
      const Eigen::Vector3f q = p + n * r.offset;
      l.p = V3{q.x(), q.y(), q.z()};
      for (int i = 0; i < 3; ++i) l.e[i] = n[i];
      break;
    }
    default: break;
  }
  return l;
}

}  // namespace impact::host
