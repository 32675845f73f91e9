// One lane's collision data on the general convex routes (GJK / EPA, SAT, the face
// manifold), in the frame of the origin its leaves were loaded with, and its store into
// a bucket's ManifoldSoA.
#pragma once

#include <cstdint>

#include "kernels/narrowphase/general/support.h"

namespace impact::kernels::cvx {

/// The collision data of one lane (points relative to the origin of the leaves).
struct LaneContact {
  uint32_t count = 0;
  V3 n{0, 1, 0};
  float depth = 0.0f;
  V3 point[kMaxManifoldPoints]{};
  float pdepth[kMaxManifoldPoints]{};
  uint32_t gjk_iterations = 0, epa_iterations = 0;
  bool used_epa = false;
  int epa_status = 0;
};

/// Lane k of out from one lane's collision data (points relative to origin, moved back).
void write_lane(const ManifoldSoA& out, uint32_t k, const LaneContact& c, V3 origin);

}  // namespace impact::kernels::cvx
