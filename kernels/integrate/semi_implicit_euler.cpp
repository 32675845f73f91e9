#include "kernels/integrate/semi_implicit_euler.h"

namespace impact::kernels {

void integrate_velocities(float dt, Vec3f gravity, const float* IMPACT_RESTRICT inv_mass,
                          float* IMPACT_RESTRICT io_vx, float* IMPACT_RESTRICT io_vy,
                          float* IMPACT_RESTRICT io_vz, Range r) {
  const float gx = gravity.x * dt, gy = gravity.y * dt, gz = gravity.z * dt;
#pragma omp simd
  for (uint32_t i = r.begin; i < r.end; ++i) {
    const float on = inv_mass[i] > 0.0f ? 1.0f : 0.0f;
    io_vx[i] += on * gx;
    io_vy[i] += on * gy;
    io_vz[i] += on * gz;
  }
}

void integrate_positions(float dt, const float* IMPACT_RESTRICT vx, const float* IMPACT_RESTRICT vy,
                         const float* IMPACT_RESTRICT vz, float* IMPACT_RESTRICT io_px,
                         float* IMPACT_RESTRICT io_py, float* IMPACT_RESTRICT io_pz, Range r) {
#pragma omp simd
  for (uint32_t i = r.begin; i < r.end; ++i) {
    io_px[i] += vx[i] * dt;
    io_py[i] += vy[i] * dt;
    io_pz[i] += vz[i] * dt;
  }
}

}  // namespace impact::kernels
