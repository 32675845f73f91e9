// Time of impact of two posed, moving shapes of a ShapeStore (the World's continuous
// collision and impact::cast_shapes).
//
// Contract: A starts at (Ra, pa) and moves by the displacement da (m) while rotating by
// the rotation vector wa (rad, world axes, about its origin pa) over the interval [0, 1];
// B likewise. t is the first fraction at which the surfaces come within `target` (hit
// when the separation is within target +- tolerance; kernels/ccd/time_of_impact.h).
// Half-spaces and meshes are static (their d, w are ignored); a mesh is cast per
// triangle, the triangles pruned by the other side's swept bounds through the mesh BVH;
// a compound over its children. Ties in t go to the lower (child_a, child_b). A compound
// child's centre follows the chord of its arc (the rotation is exact about the child's
// centre): children far from a fast-spinning compound's origin are approximate.
// Leaves are posed relative to an origin at pa (double differences), so far poses keep
// their precision. Thread-safe (reads the store only). Rejects nothing: the caller
// validates (finite poses, displacements and rotations).
// Cost: one kernel call per leaf pair that survives the bounds test.
#pragma once

#include <cstdint>

#include <Eigen/Core>

#include "host/shapes/shape_store.h"
#include "kernels/narrowphase/leaf/leaf.h"

namespace impact::host {

struct PosedToi {
  bool hit = false;                    ///< a hit or an initial overlap in [0, 1]
  bool initially_overlapping = false;  ///< separation below target - tolerance at t = 0
  float t = 1.0f;                      ///< fraction of the motion at the hit (0 if overlapping)
  Eigen::Vector3f point = Eigen::Vector3f::Zero();   ///< world, midway between the surfaces
  Eigen::Vector3f normal = Eigen::Vector3f::Zero();  ///< unit, A to B
  uint32_t child_a = 0xffffffffu, child_b = 0xffffffffu;  ///< compound child / mesh triangle
  uint32_t iterations = 0;  ///< advancement steps over all leaf pairs
};

/// Advancement steps per leaf pair before a pair reports failure (counted as no hit).
inline constexpr uint32_t kToiMaxIterations = 64;

PosedToi toi_posed(const ShapeStore& store, const ShapeRecord& ra, const Eigen::Matrix3f& Ra,
                   const Eigen::Vector3f& pa, const Eigen::Vector3f& da, const Eigen::Vector3f& wa,
                   const ShapeRecord& rb, const Eigen::Matrix3f& Rb, const Eigen::Vector3f& pb,
                   const Eigen::Vector3f& db, const Eigen::Vector3f& wb, const kernels::NarrowConfig& cfg,
                   float target, float tolerance);

}  // namespace impact::host
