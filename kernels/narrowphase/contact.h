// Collision data as SoA: the output of the narrow phase and the input of the
// response. For contact c: bodies a[c] and b[c] (b[c] is a plane index when
// b_is_plane[c]), unit normal n pointing from a to b, depth > 0 (overlap, m),
// and a contact point midway between the two surfaces' deepest points. Moving a
// by -n*depth*wa and b by +n*depth*wb (wa + wb = 1) gives the safe, overlap-free
// positions of the seeds' "collision data".
#pragma once

#include "kernels/common/kernel.h"

namespace impact::kernels {

struct ContactSoA {
  uint32_t* a;
  uint32_t* b;
  uint8_t* b_is_plane;
  float* normal_x;
  float* normal_y;
  float* normal_z;
  float* depth;
  float* point_x;
  float* point_y;
  float* point_z;
};

/// Read-only sphere bodies for the narrow phase.
struct SphereView {
  const float* pos_x;
  const float* pos_y;
  const float* pos_z;
  const float* radius;
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
