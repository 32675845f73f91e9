// Public particle integrators (include/impact/integrators.h): validation, the spring CSR
// (built once per call by a counting sort on particle index, so each particle's springs
// are in increasing id order), scratch, and the per-scheme list of chunked passes over
// kernels/integrate/particle_integrators.h. Every pass writes only its chunk's outputs;
// chunk boundaries depend only on n, so results are the same bytes for any thread count.
// Cost per step: 1 force evaluation (Euler, semi-implicit, Verlet) or 4 (RK4).
#include "impact/integrators.h"

#include <cmath>
#include <string>
#include <vector>

#include "host/parallel.h"
#include "kernels/integrate/particle_integrators.h"

namespace impact {
namespace {

constexpr uint32_t kGrain = 4096;

Status bad(std::string m) { return Status(StatusCode::kInvalidArgument, std::move(m)); }

Status check_array(std::span<const float> a, const char* what, const char* field, bool non_negative) {
  for (size_t i = 0; i < a.size(); ++i) {
    if (!std::isfinite(a[i]) || (non_negative && a[i] < 0.0f)) {
      return bad(std::string(what) + " " + std::to_string(i) + ": " + field + " must be finite" +
                 (non_negative ? " and >= 0" : ""));
    }
  }
  return {};
}

Status validate(const IntegrateDesc& d, const ParticleArrays& p) {
  if (!std::isfinite(d.dt) || !(d.dt > 0.0f)) return bad("integrate: dt must be finite and > 0");
  if (!d.gravity.allFinite()) return bad("integrate: gravity must be finite");
  if (!std::isfinite(d.linear_damping) || d.linear_damping < 0.0f) {
    return bad("integrate: linear_damping must be finite and >= 0");
  }
  const size_t n = p.x.size();
  if (p.y.size() != n || p.z.size() != n || p.vx.size() != n || p.vy.size() != n ||
      p.vz.size() != n || p.inv_mass.size() != n) {
    return Status(StatusCode::kSizeMismatch, "particles: x, y, z, vx, vy, vz, inv_mass lengths differ");
  }
  if (n > 0xfffffff0u) return Status(StatusCode::kCapacityExceeded, "particles: more than 2^32 - 16");
  const struct {
    std::span<const float> a;
    const char* f;
  } state[] = {{p.x, "x"}, {p.y, "y"}, {p.z, "z"}, {p.vx, "vx"}, {p.vy, "vy"}, {p.vz, "vz"}};
  for (const auto& s : state) {
    if (Status st = check_array(s.a, "particle", s.f, false); !st.ok()) return st;
  }
  if (Status st = check_array(p.inv_mass, "particle", "inv_mass", true); !st.ok()) return st;
  const SpringArrays& s = d.springs;
  const size_t m = s.a.size();
  if (s.b.size() != m || s.rest_length.size() != m || s.stiffness.size() != m || s.damping.size() != m) {
    return Status(StatusCode::kSizeMismatch, "springs: a, b, rest_length, stiffness, damping lengths differ");
  }
  for (size_t i = 0; i < m; ++i) {
    const std::string pre = "spring " + std::to_string(i) + ": ";
    if (s.a[i] >= n) return bad(pre + "a = " + std::to_string(s.a[i]) + " out of range");
    if (s.b[i] >= n) return bad(pre + "b = " + std::to_string(s.b[i]) + " out of range");
    if (s.a[i] == s.b[i]) return bad(pre + "a == b");
  }
  if (Status st = check_array(s.rest_length, "spring", "rest_length", true); !st.ok()) return st;
  if (Status st = check_array(s.stiffness, "spring", "stiffness", true); !st.ok()) return st;
  if (Status st = check_array(s.damping, "spring", "damping", true); !st.ok()) return st;
  return {};
}

/// Six owned arrays of n floats.
struct State6 {
  std::vector<float> a[6];
  void resize(size_t n) {
    for (auto& v : a) v.resize(n);
  }
  kernels::ParticleState view() {
    return {a[0].data(), a[1].data(), a[2].data(), a[3].data(), a[4].data(), a[5].data()};
  }
};

struct Accel {
  std::vector<float> a[3];
  void resize(size_t n) {
    for (auto& v : a) v.assign(n, 0.0f);
  }
  kernels::Vec3Arrays view() { return {a[0].data(), a[1].data(), a[2].data()}; }
};

class Integrator_ {
 public:
  Integrator_(const IntegrateDesc& d, uint32_t n, const ExecConfig& e)
      : d_(d), n_(n), exec_(e.backend, e.threads) {
    const SpringArrays& s = d.springs;
    const uint32_t m = static_cast<uint32_t>(s.a.size());
    if (m > 0) {
      // Counting sort of (particle, spring) incidences by particle; ids ascend within each.
      offset_.assign(n + 1, 0);
      for (uint32_t k = 0; k < m; ++k) {
        ++offset_[s.a[k] + 1];
        ++offset_[s.b[k] + 1];
      }
      for (uint32_t i = 0; i < n; ++i) offset_[i + 1] += offset_[i];
      spring_.resize(2 * static_cast<size_t>(m));
      std::vector<uint32_t> cursor(offset_.begin(), offset_.end() - 1);
      for (uint32_t k = 0; k < m; ++k) {
        spring_[cursor[s.a[k]]++] = k;
        spring_[cursor[s.b[k]]++] = k;
      }
      csr_ = {offset_.data(), spring_.data(), s.a.data(), s.b.data(),
              s.rest_length.data(), s.stiffness.data(), s.damping.data()};
    }
  }

  /// out_a = acceleration of `st`.
  void accelerations(const kernels::ParticleState& st, kernels::Vec3Arrays out_a, const float* w) {
    const float gx = d_.gravity.x(), gy = d_.gravity.y(), gz = d_.gravity.z();
    const float damp = d_.linear_damping;
    const bool springs = !spring_.empty();
    exec_.for_each_chunk(n_, kGrain, [&](uint32_t b, uint32_t e, uint32_t) {
      if (d_.field.fn != nullptr) {
        d_.field.fn(st.px, st.py, st.pz, st.vx, st.vy, st.vz, out_a.x, out_a.y, out_a.z, b, e,
                    d_.field.user);
      } else {
        for (float* f : {out_a.x, out_a.y, out_a.z}) std::fill(f + b, f + e, 0.0f);
      }
      if (springs) kernels::gather_spring_forces(csr_, st, out_a, {b, e});
      kernels::forces_to_accelerations(gx, gy, gz, damp, w, st, out_a, out_a, {b, e});
    });
  }

  template <class F>
  void each(F&& f) {
    exec_.for_each_chunk(n_, kGrain, [&](uint32_t b, uint32_t e, uint32_t) { f(kernels::Range{b, e}); });
  }

  void run(ParticleArrays p) {
    kernels::ParticleState io{p.x.data(), p.y.data(), p.z.data(), p.vx.data(), p.vy.data(), p.vz.data()};
    const float* w = p.inv_mass.data();
    const float dt = d_.dt;
    Accel a;
    a.resize(n_);
    kernels::Vec3Arrays av = a.view();
    switch (d_.scheme) {
      case Integrator::kExplicitEuler:
        for (uint32_t s = 0; s < d_.steps; ++s) {
          accelerations(io, av, w);
          each([&](kernels::Range r) { kernels::explicit_euler_update(dt, av, io, r); });
        }
        break;
      case Integrator::kSemiImplicitEuler:
        for (uint32_t s = 0; s < d_.steps; ++s) {
          accelerations(io, av, w);
          each([&](kernels::Range r) { kernels::semi_implicit_euler_update(dt, av, io, r); });
        }
        break;
      case Integrator::kVelocityVerlet:
        // Velocity-dependent forces (damping, dampers, field) see the half-step velocity.
        if (d_.steps > 0) accelerations(io, av, w);
        for (uint32_t s = 0; s < d_.steps; ++s) {
          each([&](kernels::Range r) { kernels::verlet_drift(dt, av, io, r); });
          accelerations(io, av, w);
          each([&](kernels::Range r) { kernels::verlet_kick(dt, av, io, r); });
        }
        break;
      case Integrator::kRk4: {
        // Two stage buffers, alternated, so a stage never overwrites the state it reads.
        State6 stage[2], acc;
        stage[0].resize(n_);
        stage[1].resize(n_);
        acc.resize(n_);
        kernels::ParticleState accv = acc.view();
        kernels::ParticleState sv[2] = {stage[0].view(), stage[1].view()};
        const float h[3] = {0.5f * dt, 0.5f * dt, dt};
        const float weight[4] = {1.0f, 2.0f, 2.0f, 1.0f};
        for (uint32_t s = 0; s < d_.steps; ++s) {
          // k1 at io; k2, k3, k4 at stage = io + h k_prev (1 x k1 + 2 k2 + 2 k3 + 1 k4 in acc).
          accelerations(io, av, w);
          each([&](kernels::Range r) { kernels::rk4_begin(h[0], io, av, sv[0], accv, r); });
          for (int k = 1; k < 4; ++k) {
            const kernels::ParticleState cur = sv[(k - 1) & 1];
            accelerations(cur, av, w);
            each([&](kernels::Range r) {
              kernels::rk4_accumulate(weight[k], cur, av, accv, r);
              if (k < 3) kernels::rk4_stage_state(h[k], io, cur, av, sv[k & 1], r);
            });
          }
          each([&](kernels::Range r) { kernels::rk4_finish(dt, accv, io, r); });
        }
        break;
      }
    }
  }

 private:
  const IntegrateDesc& d_;
  uint32_t n_;
  host::Executor exec_;
  std::vector<uint32_t> offset_, spring_;
  kernels::SpringCsr csr_{};
};

}  // namespace

Status integrate_particles(const IntegrateDesc& desc, ParticleArrays particles, const ExecConfig& exec) {
  if (Status st = validate(desc, particles); !st.ok()) return st;
  Backend b;
  if (!host::resolve_backend(exec.backend, &b)) {
    return Status(StatusCode::kUnsupported, "integrate: the requested thread backend is not built in");
  }
  const uint32_t n = static_cast<uint32_t>(particles.x.size());
  if (n == 0 || desc.steps == 0) return {};
  Integrator_ it(desc, n, exec);
  it.run(particles);
  return {};
}

}  // namespace impact
