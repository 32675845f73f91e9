// Free-motion particle integrators over SoA state: the per-particle passes of explicit
// Euler, semi-implicit Euler, velocity Verlet and classical RK4, and the deterministic
// spring-force gather they call.
//
// State: positions p, velocities v, inverse mass w (w = 0: pinned, zero acceleration;
// the particle keeps its velocity, which is kinematic motion). Acceleration model:
//   a_i = w_i f_i + [w_i > 0] (g - damping v_i),
// with f_i the user field force plus the Hooke spring-dampers touching i.
// Springs: gather_spring_forces walks a per-particle CSR list (built by the host once per
// call) in spring order, so each f_i is summed by one lane in a fixed order: no atomics,
// the same bytes for any chunking. A spring's force on its two ends is computed from the
// same operands and negated, so it is exactly antisymmetric.
// Inputs finite (validated at the API); a spring of length 0 has no direction and adds
// only nothing (its direction is taken as 0). Cost: O(n) per pass, streaming; the
// element-wise passes vectorise by `omp simd` (checked with -fopt-info-vec, see
// docs/integrators.md); the gather is O(n + springs) with scalar indirect loads.
// Method: Hairer, Norsett & Wanner, "Solving Ordinary Differential Equations I", II.1
// (RK4); Hairer, Lubich & Wanner, "Geometric Numerical Integration", I.1 (symplectic
// Euler, Stormer-Verlet).
#pragma once

#include "kernels/common/kernel.h"

namespace impact::kernels {

/// Six SoA state arrays.
struct ParticleState {
  float* IMPACT_RESTRICT px;
  float* IMPACT_RESTRICT py;
  float* IMPACT_RESTRICT pz;
  float* IMPACT_RESTRICT vx;
  float* IMPACT_RESTRICT vy;
  float* IMPACT_RESTRICT vz;
};

/// Three SoA force / acceleration arrays.
struct Vec3Arrays {
  float* IMPACT_RESTRICT x;
  float* IMPACT_RESTRICT y;
  float* IMPACT_RESTRICT z;
};

/// Springs in CSR form around particles: entries [offset[i], offset[i+1]) list spring ids
/// touching particle i, in increasing id order; `a`, `b` are each spring's ends.
struct SpringCsr {
  const uint32_t* offset;
  const uint32_t* spring;
  const uint32_t* a;
  const uint32_t* b;
  const float* rest_length;
  const float* stiffness;
  const float* damping;
};

/// io_f[i] += spring forces on i, for i in r (reads any particle's state).
void gather_spring_forces(const SpringCsr& s, const ParticleState& state, Vec3Arrays io_f, Range r);

/// out_a = w f + [w > 0] (g - damping v) for i in r. f may alias out_a.
void forces_to_accelerations(float gx, float gy, float gz, float damping,
                             const float* IMPACT_RESTRICT inv_mass, const ParticleState& state,
                             const Vec3Arrays& f, Vec3Arrays out_a, Range r);

/// Explicit Euler: p += dt v; v += dt a (a from the state at the step's start).
void explicit_euler_update(float dt, const Vec3Arrays& a, ParticleState io, Range r);

/// Semi-implicit Euler: v += dt a; p += dt v (the new velocity).
void semi_implicit_euler_update(float dt, const Vec3Arrays& a, ParticleState io, Range r);

/// Velocity Verlet, first half: v += dt/2 a; p += dt v.
void verlet_drift(float dt, const Vec3Arrays& a, ParticleState io, Range r);

/// Velocity Verlet, second half: v += dt/2 a (a at the new positions).
void verlet_kick(float dt, const Vec3Arrays& a, ParticleState io, Range r);

/// RK4 stage state: out = base + h k, with k = (velocity, acceleration) of stage k_v, k_a.
void rk4_stage_state(float h, const ParticleState& base, const ParticleState& kv,
                     const Vec3Arrays& ka, ParticleState out, Range r);

/// RK4 first stage: out_acc = (v, a) of base (k1), out_stage = base + h k1.
void rk4_begin(float h, const ParticleState& base, const Vec3Arrays& ka, ParticleState out_stage,
               ParticleState out_acc, Range r);

/// RK4 accumulation: acc_v += weight k_v, acc_a += weight k_a (acc starts at 0).
void rk4_accumulate(float weight, const ParticleState& kv, const Vec3Arrays& ka,
                    ParticleState io_acc, Range r);

/// RK4 final: io += dt/6 acc, where acc's position arrays hold the velocity sums and its
/// velocity arrays the acceleration sums (k1 + 2 k2 + 2 k3 + k4).
void rk4_finish(float dt, const ParticleState& acc, ParticleState io, Range r);

}  // namespace impact::kernels
