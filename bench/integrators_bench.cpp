// ns per particle-step of integrate_particles for each scheme at 100k particles, gravity
// only and with a spring chain; and the harmonic-oscillator position error after 10 s at
// dt = 0.05 s (omega = 1) per scheme, as counters.
#include <benchmark/benchmark.h>

#include <cmath>
#include <vector>

#include "impact/integrators.h"

namespace {

using impact::Integrator;

struct Particles {
  std::vector<float> x, y, z, vx, vy, vz, w;
  explicit Particles(size_t n) : x(n), y(n), z(n), vx(n), vy(n), vz(n), w(n, 1.0f) {
    for (size_t i = 0; i < n; ++i) x[i] = 0.01f * float(i);
  }
  impact::ParticleArrays arrays() { return {x, y, z, vx, vy, vz, w}; }
};

void harmonic(const float* x, const float*, const float*, const float*, const float*, const float*,
              float* fx, float* fy, float* fz, uint32_t b, uint32_t e, void*) {
  for (uint32_t i = b; i < e; ++i) {
    fx[i] = -x[i];
    fy[i] = 0.0f;
    fz[i] = 0.0f;
  }
}

void BM_Integrate(benchmark::State& state) {
  const auto scheme = static_cast<Integrator>(state.range(0));
  const bool springs = state.range(1) != 0;
  const uint32_t n = 100000, steps = 10;
  Particles p(n);
  std::vector<uint32_t> a, b;
  std::vector<float> rest, k, c;
  if (springs) {
    for (uint32_t i = 0; i + 1 < n; ++i) {
      a.push_back(i);
      b.push_back(i + 1);
      rest.push_back(0.01f);
      k.push_back(100.0f);
      c.push_back(0.1f);
    }
  }
  impact::IntegrateDesc d;
  d.scheme = scheme;
  d.dt = 1.0f / 600.0f;
  d.steps = steps;
  d.springs = {a, b, rest, k, c};
  for (auto _ : state) {
    if (!impact::integrate_particles(d, p.arrays()).ok()) state.SkipWithError("integrate failed");
    benchmark::DoNotOptimize(p.y.data());
  }
  // Seconds per particle-step (printed with an SI prefix: 1.3n = 1.3 ns).
  state.counters["s_per_particle_step"] = benchmark::Counter(
      double(n) * steps, benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}
BENCHMARK(BM_Integrate)->ArgsProduct({{0, 1, 2, 3}, {0, 1}})->ArgNames({"scheme", "springs"})
    ->Unit(benchmark::kMillisecond);

void BM_OscillatorError(benchmark::State& state) {
  const auto scheme = static_cast<Integrator>(state.range(0));
  double err = 0.0;
  for (auto _ : state) {
    Particles p(1);
    p.x[0] = 1.0f;
    impact::IntegrateDesc d;
    d.scheme = scheme;
    d.dt = 0.05f;
    d.steps = 200;
    d.gravity.setZero();
    d.field = {harmonic, nullptr};
    if (!impact::integrate_particles(d, p.arrays()).ok()) state.SkipWithError("integrate failed");
    err = std::abs(double(p.x[0]) - std::cos(10.0));
  }
  state.counters["abs_error_x_t10"] = err;
}
BENCHMARK(BM_OscillatorError)->DenseRange(0, 3)->ArgName("scheme");

}  // namespace
