// Read-only views of a World's plain spheres and static planes, shared by the kernels
// that read them straight from the body store: the plane filter
// (kernels/broadphase/plane_pairs.h) and the sphere buckets of the narrow phase
// (kernels/narrowphase/plain/sphere_sphere.h, sphere_plane.h).
#pragma once

#include "kernels/common/kernel.h"

namespace impact::kernels {

/// Spheres (or bounding spheres): centre and radius per body slot.
struct SphereView {
  const float* pos_x;
  const float* pos_y;
  const float* pos_z;
  const float* radius;
};

/// What decides whether a body meets planes: dynamic (inv_mass > 0) and the
/// collision layer / mask pair.
struct BodyFilter {
  const float* inv_mass;
  const uint32_t* layer;
  const uint32_t* mask;
};

/// Static planes { x : n.x <= offset }, unit normals, with their filter data.
struct PlaneView {
  const float* normal_x;
  const float* normal_y;
  const float* normal_z;
  const float* offset;
  const uint32_t* layer;
  const uint32_t* mask;
  uint32_t count;
};

}  // namespace impact::kernels
