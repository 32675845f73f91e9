// Free-motion particle integration as a knob: explicit Euler, semi-implicit Euler,
// velocity Verlet or RK4 under uniform gravity, linear damping, Hooke spring-dampers and
// a user force field. Kernels: kernels/integrate/particle_integrators.h; orders,
// stability, cost and measured errors: docs/integrators.md.
#pragma once

#include <cstdint>
#include <span>

#include <Eigen/Core>

#include "impact/broadphase.h"
#include "impact/status.h"

namespace impact {

/// The time-stepping scheme. Global order on smooth problems: 1, 1, 2, 4.
enum class Integrator { kExplicitEuler, kSemiImplicitEuler, kVelocityVerlet, kRk4 };

/// Particle state, SoA, all spans of equal length n. Units: m, m/s, 1/kg.
/// inv_mass 0 = pinned: no acceleration (the particle keeps its velocity).
struct ParticleArrays {
  std::span<float> x, y, z, vx, vy, vz;
  std::span<const float> inv_mass;
};

/// Hooke spring-dampers between particles a[s] and b[s] (a != b, both < n), SoA, equal
/// lengths. Force on a: (k (L - rest) + c (v_b - v_a).u) u, u = (p_b - p_a) / L; -that on b.
struct SpringArrays {
  std::span<const uint32_t> a, b;
  std::span<const float> rest_length, stiffness, damping;  ///< m, N/m, N s/m; all >= 0
};

/// A user force field: writes forces (N) out_f{x,y,z}[i] for i in [begin, end) from the
/// positions and velocities of all particles. Called concurrently on disjoint ranges whose
/// boundaries depend only on n, so a pure function gives thread-count independent bytes.
using ForceFieldFn = void (*)(const float* x, const float* y, const float* z, const float* vx,
                              const float* vy, const float* vz, float* out_fx, float* out_fy,
                              float* out_fz, uint32_t begin, uint32_t end, void* user);

/// Optional force field (fn null: none).
struct ForceField {
  ForceFieldFn fn = nullptr;
  void* user = nullptr;
};

/// One integration call: `steps` steps of `dt` seconds.
struct IntegrateDesc {
  Integrator scheme = Integrator::kSemiImplicitEuler;
  float dt = 1.0f / 60.0f;  ///< s, finite and > 0
  uint32_t steps = 1;
  Eigen::Vector3f gravity{0.0f, -9.81f, 0.0f};  ///< m/s^2, finite
  float linear_damping = 0.0f;                  ///< 1/s, finite and >= 0: a -= damping v
  SpringArrays springs{};
  ForceField field{};
};

/// Advances the particles in place. kInvalidArgument (naming index and field) for dt not
/// finite or <= 0, non-finite gravity, negative or non-finite damping, spring end out of
/// range or a == b, negative or non-finite spring parameters, non-finite or negative
/// inv_mass, non-finite state; kSizeMismatch for spans of unequal length. The same bytes
/// for every ExecConfig.
Status integrate_particles(const IntegrateDesc& desc, ParticleArrays particles,
                           const ExecConfig& exec = {});

}  // namespace impact
