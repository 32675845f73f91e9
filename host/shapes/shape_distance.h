// distance_posed: distance and closest points of two posed shapes (world frame), for
// the World's speculative contacts and impact::distance_shapes. Leaves go through
// kernels/distance/leaf_distance.h relative to A's position (far poses keep float
// precision); compounds take the minimum over children (lowest child index wins ties);
// a mesh against a bounded shape walks the mesh BVH near child first, pruning nodes
// whose box is farther than the best distance so far or than max_distance
// (branch and bound). Not supported: mesh-mesh, mesh vs half-space, half-space vs
// half-space (distance = NaN; the public call rejects them). Thread-safe: reads only.
// Cost: one leaf distance per leaf pair; a mesh visits O(log T + k) nodes when
// max_distance is small.
#pragma once

#include <cstdint>

#include <Eigen/Core>

#include "host/shapes/shape_store.h"
#include "kernels/narrowphase/leaf/leaf.h"

namespace impact::host {

struct PosedDistance {
  bool overlap = false;
  /// m, >= 0; +inf when farther than max_distance; NaN for an unsupported pair.
  float distance = 0.0f;
  Eigen::Vector3f pa = Eigen::Vector3f::Zero(), pb = Eigen::Vector3f::Zero();
  Eigen::Vector3f normal = Eigen::Vector3f::Zero();  ///< unit, from A to B
  uint32_t child_a = 0xffffffffu, child_b = 0xffffffffu;  ///< compound child / mesh triangle
};

/// Distance of shape ra at (Ra, pa) and rb at (Rb, pb); see the file header.
PosedDistance distance_posed(const ShapeStore& store, const ShapeRecord& ra, const Eigen::Matrix3f& Ra,
                             const Eigen::Vector3f& pa, const ShapeRecord& rb, const Eigen::Matrix3f& Rb,
                             const Eigen::Vector3f& pb, const kernels::NarrowConfig& cfg, float max_distance);

}  // namespace impact::host
