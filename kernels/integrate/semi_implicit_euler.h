// Semi-implicit (symplectic) Euler over SoA bodies.
//
// integrate_velocities: v += g*dt for dynamic bodies (inv_mass > 0); static bodies
//   keep their velocity (kinematic motion stays possible).
// integrate_positions:  x += v*dt, with the velocity already updated this step,
//   which is what makes the scheme symplectic (energy drifts boundedly).
// Inputs finite (validated at the API). Cost: O(n), streaming, vectorised by
// `omp simd` (checked with -fopt-info-vec). Method: e.g. Hairer, Lubich & Wanner,
// "Geometric Numerical Integration", ch. 1 (symplectic Euler).
#pragma once

#include "kernels/common/kernel.h"

namespace impact::kernels {

struct Vec3f {
  float x, y, z;
};

void integrate_velocities(float dt, Vec3f gravity, const float* IMPACT_RESTRICT inv_mass,
                          float* IMPACT_RESTRICT io_vx, float* IMPACT_RESTRICT io_vy,
                          float* IMPACT_RESTRICT io_vz, Range r);

void integrate_positions(float dt, const float* IMPACT_RESTRICT vx, const float* IMPACT_RESTRICT vy,
                         const float* IMPACT_RESTRICT vz, float* IMPACT_RESTRICT io_px,
                         float* IMPACT_RESTRICT io_py, float* IMPACT_RESTRICT io_pz, Range r);

}  // namespace impact::kernels
