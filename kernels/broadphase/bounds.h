// Bounds passes.
//
// sphere_bounds: per body, the AABB [p - r, p + r]. Streaming, vectorised.
// reduce_bounds: over a range of boxes, the union box and the largest box edge
//   (max over boxes and axes of max - min), and the min over boxes of each box's
//   largest edge. The host combines one partial per
//   chunk in chunk order, so the result does not depend on thread count (min/max
//   are exact anyway).
// reduce_valid_bounds: reduce_bounds and the input check of the standalone broad
//   phase in the same pass (valid: every coordinate in [-1e18, 1e18], min <= max, no
//   NaN), so validating the boxes and summarising them read the bounds once.
// swept_sphere_bounds: per body, the AABB of the sphere at p and at p + v dt (the
//   motion over the step, for fast bodies: pairs that meet within the step are
//   candidates even when their start boxes are apart). Covers both end poses
//   exactly as float computes them; the path between is a straight segment, so
//   the box of the two end spheres bounds it.
// sweep_boxes: per box, the union of the box and the box moved by (dx, dy, dz).
// Inputs finite (validated at ingest).
#pragma once

#include "kernels/common/kernel.h"

namespace impact::kernels {

struct AabbSoA {
  const float* min_x;
  const float* min_y;
  const float* min_z;
  const float* max_x;
  const float* max_y;
  const float* max_z;
};

struct AabbSoAOut {
  float* min_x;
  float* min_y;
  float* min_z;
  float* max_x;
  float* max_y;
  float* max_z;
};

/// Union of a set of boxes plus the largest edge of any member, and the smallest
/// "largest edge" of a member (each box's max over axes, then the min over boxes),
/// which lets the grid see that no box is small enough for hierarchical levels
/// without a pass over the boxes. 0 (the default) claims nothing.
struct BoundsSummary {
  float lo[3];
  float hi[3];
  float max_edge;
  float min_edge = 0.0f;
};
/// Identity element of combine(): an empty summary.
BoundsSummary empty_bounds_summary();
BoundsSummary combine(const BoundsSummary& a, const BoundsSummary& b);

void sphere_bounds(const float* IMPACT_RESTRICT px, const float* IMPACT_RESTRICT py,
                   const float* IMPACT_RESTRICT pz, const float* IMPACT_RESTRICT radius,
                   AabbSoAOut out, Range r);

void swept_sphere_bounds(const float* IMPACT_RESTRICT px, const float* IMPACT_RESTRICT py,
                         const float* IMPACT_RESTRICT pz, const float* IMPACT_RESTRICT vx,
                         const float* IMPACT_RESTRICT vy, const float* IMPACT_RESTRICT vz,
                         const float* IMPACT_RESTRICT radius, float dt, AabbSoAOut out, Range r);

void sweep_boxes(AabbSoA boxes, const float* IMPACT_RESTRICT dx, const float* IMPACT_RESTRICT dy,
                 const float* IMPACT_RESTRICT dz, AabbSoAOut out, Range r);

BoundsSummary reduce_bounds(AabbSoA boxes, Range r);
BoundsSummary reduce_valid_bounds(AabbSoA boxes, Range r, bool* valid);

}  // namespace impact::kernels
