#include "kernels/integrate/particle_integrators.h"

#include <cmath>

namespace impact::kernels {

void gather_spring_forces(const SpringCsr& s, const ParticleState& st, Vec3Arrays io_f, Range r) {
  for (uint32_t i = r.begin; i < r.end; ++i) {
    float fx = 0.0f, fy = 0.0f, fz = 0.0f;
    for (uint32_t k = s.offset[i]; k < s.offset[i + 1]; ++k) {
      const uint32_t id = s.spring[k];
      const uint32_t a = s.a[id], b = s.b[id];
      // Force on a, from the same operands whichever end is asking.
      const float dx = st.px[b] - st.px[a], dy = st.py[b] - st.py[a], dz = st.pz[b] - st.pz[a];
      const float len = std::sqrt(dx * dx + dy * dy + dz * dz);
      const float inv = len > 0.0f ? 1.0f / len : 0.0f;
      const float nx = dx * inv, ny = dy * inv, nz = dz * inv;
      const float rel = (st.vx[b] - st.vx[a]) * nx + (st.vy[b] - st.vy[a]) * ny +
                        (st.vz[b] - st.vz[a]) * nz;
      const float mag = s.stiffness[id] * (len - s.rest_length[id]) + s.damping[id] * rel;
      const float sign = i == a ? 1.0f : -1.0f;
      fx += sign * (mag * nx);
      fy += sign * (mag * ny);
      fz += sign * (mag * nz);
    }
    io_f.x[i] += fx;
    io_f.y[i] += fy;
    io_f.z[i] += fz;
  }
}

void forces_to_accelerations(float gx, float gy, float gz, float damping,
                             const float* IMPACT_RESTRICT w, const ParticleState& st,
                             const Vec3Arrays& f, Vec3Arrays out, Range r) {
  const float* fx = f.x;
  const float* fy = f.y;
  const float* fz = f.z;
  const float* vx = st.vx;
  const float* vy = st.vy;
  const float* vz = st.vz;
  float* ax = out.x;
  float* ay = out.y;
  float* az = out.z;
#pragma omp simd
  for (uint32_t i = r.begin; i < r.end; ++i) {
    const float on = w[i] > 0.0f ? 1.0f : 0.0f;
    ax[i] = w[i] * fx[i] + on * (gx - damping * vx[i]);
    ay[i] = w[i] * fy[i] + on * (gy - damping * vy[i]);
    az[i] = w[i] * fz[i] + on * (gz - damping * vz[i]);
  }
}

void explicit_euler_update(float dt, const Vec3Arrays& a, ParticleState io, Range r) {
#pragma omp simd
  for (uint32_t i = r.begin; i < r.end; ++i) {
    io.px[i] += dt * io.vx[i];
    io.py[i] += dt * io.vy[i];
    io.pz[i] += dt * io.vz[i];
    io.vx[i] += dt * a.x[i];
    io.vy[i] += dt * a.y[i];
    io.vz[i] += dt * a.z[i];
  }
}

void semi_implicit_euler_update(float dt, const Vec3Arrays& a, ParticleState io, Range r) {
#pragma omp simd
  for (uint32_t i = r.begin; i < r.end; ++i) {
    io.vx[i] += dt * a.x[i];
    io.vy[i] += dt * a.y[i];
    io.vz[i] += dt * a.z[i];
    io.px[i] += dt * io.vx[i];
    io.py[i] += dt * io.vy[i];
    io.pz[i] += dt * io.vz[i];
  }
}

void verlet_drift(float dt, const Vec3Arrays& a, ParticleState io, Range r) {
  const float h = 0.5f * dt;
#pragma omp simd
  for (uint32_t i = r.begin; i < r.end; ++i) {
    io.vx[i] += h * a.x[i];
    io.vy[i] += h * a.y[i];
    io.vz[i] += h * a.z[i];
    io.px[i] += dt * io.vx[i];
    io.py[i] += dt * io.vy[i];
    io.pz[i] += dt * io.vz[i];
  }
}

void verlet_kick(float dt, const Vec3Arrays& a, ParticleState io, Range r) {
  const float h = 0.5f * dt;
#pragma omp simd
  for (uint32_t i = r.begin; i < r.end; ++i) {
    io.vx[i] += h * a.x[i];
    io.vy[i] += h * a.y[i];
    io.vz[i] += h * a.z[i];
  }
}

void rk4_stage_state(float h, const ParticleState& base, const ParticleState& kv,
                     const Vec3Arrays& ka, ParticleState out, Range r) {
#pragma omp simd
  for (uint32_t i = r.begin; i < r.end; ++i) {
    out.px[i] = base.px[i] + h * kv.vx[i];
    out.py[i] = base.py[i] + h * kv.vy[i];
    out.pz[i] = base.pz[i] + h * kv.vz[i];
    out.vx[i] = base.vx[i] + h * ka.x[i];
    out.vy[i] = base.vy[i] + h * ka.y[i];
    out.vz[i] = base.vz[i] + h * ka.z[i];
  }
}

void rk4_begin(float h, const ParticleState& base, const Vec3Arrays& ka, ParticleState out,
               ParticleState acc, Range r) {
#pragma omp simd
  for (uint32_t i = r.begin; i < r.end; ++i) {
    acc.px[i] = base.vx[i];
    acc.py[i] = base.vy[i];
    acc.pz[i] = base.vz[i];
    acc.vx[i] = ka.x[i];
    acc.vy[i] = ka.y[i];
    acc.vz[i] = ka.z[i];
    out.px[i] = base.px[i] + h * base.vx[i];
    out.py[i] = base.py[i] + h * base.vy[i];
    out.pz[i] = base.pz[i] + h * base.vz[i];
    out.vx[i] = base.vx[i] + h * ka.x[i];
    out.vy[i] = base.vy[i] + h * ka.y[i];
    out.vz[i] = base.vz[i] + h * ka.z[i];
  }
}

void rk4_accumulate(float weight, const ParticleState& kv, const Vec3Arrays& ka,
                    ParticleState io, Range r) {
#pragma omp simd
  for (uint32_t i = r.begin; i < r.end; ++i) {
    io.px[i] += weight * kv.vx[i];
    io.py[i] += weight * kv.vy[i];
    io.pz[i] += weight * kv.vz[i];
    io.vx[i] += weight * ka.x[i];
    io.vy[i] += weight * ka.y[i];
    io.vz[i] += weight * ka.z[i];
  }
}

void rk4_finish(float dt, const ParticleState& acc, ParticleState io, Range r) {
  const float h = dt / 6.0f;
#pragma omp simd
  for (uint32_t i = r.begin; i < r.end; ++i) {
    io.px[i] += h * acc.px[i];
    io.py[i] += h * acc.py[i];
    io.pz[i] += h * acc.pz[i];
    io.vx[i] += h * acc.vx[i];
    io.vy[i] += h * acc.vy[i];
    io.vz[i] += h * acc.vz[i];
  }
}

}  // namespace impact::kernels
