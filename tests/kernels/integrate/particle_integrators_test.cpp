// integrate_particles against analytic solutions in double: projectile, harmonic
// oscillator energy over many periods, order of convergence, central-force orbit, damped
// oscillator, a two-body spring, pinned particles, bad input and thread-count determinism.
#include "impact/integrators.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>
#include <vector>

namespace impact {
namespace {

constexpr Integrator kAll[] = {Integrator::kExplicitEuler, Integrator::kSemiImplicitEuler,
                               Integrator::kVelocityVerlet, Integrator::kRk4};

struct Particles {
  std::vector<float> x, y, z, vx, vy, vz, w;
  explicit Particles(size_t n) : x(n), y(n), z(n), vx(n), vy(n), vz(n), w(n, 1.0f) {}
  ParticleArrays arrays() { return {x, y, z, vx, vy, vz, w}; }
};

/// f = -k x (per unit mass with w = 1): an isotropic oscillator about the origin.
struct Harmonic {
  float k;
};
void harmonic_field(const float* x, const float* y, const float* z, const float*, const float*,
                    const float*, float* fx, float* fy, float* fz, uint32_t b, uint32_t e, void* u) {
  const float k = static_cast<Harmonic*>(u)->k;
  for (uint32_t i = b; i < e; ++i) {
    fx[i] = -k * x[i];
    fy[i] = -k * y[i];
    fz[i] = -k * z[i];
  }
}

/// f = -mu x / |x|^3 (unit mass): Kepler central force.
void central_field(const float* x, const float* y, const float* z, const float*, const float*,
                   const float*, float* fx, float* fy, float* fz, uint32_t b, uint32_t e, void* u) {
  const float mu = *static_cast<float*>(u);
  for (uint32_t i = b; i < e; ++i) {
    const float r2 = x[i] * x[i] + y[i] * y[i] + z[i] * z[i];
    const float s = -mu / (r2 * std::sqrt(r2));
    fx[i] = s * x[i];
    fy[i] = s * y[i];
    fz[i] = s * z[i];
  }
}

IntegrateDesc desc_of(Integrator s, float dt, uint32_t steps, Eigen::Vector3f g = Eigen::Vector3f::Zero()) {
  IntegrateDesc d;
  d.scheme = s;
  d.dt = dt;
  d.steps = steps;
  d.gravity = g;
  return d;
}

TEST(ParticleIntegrators, ProjectileMatchesAnalyticErrors) {
  const double g = -9.81, vy0 = 12.0, vx0 = 3.0, dt = 1.0 / 64.0;  // dt exact in binary
  const uint32_t n_steps = 128;
  const double t = dt * n_steps;
  for (Integrator s : kAll) {
    Particles p(1);
    p.vx[0] = static_cast<float>(vx0);
    p.vy[0] = static_cast<float>(vy0);
    ASSERT_TRUE(integrate_particles(desc_of(s, dt, n_steps, {0.0f, -9.81f, 0.0f}), p.arrays()).ok());
    const double y_exact = vy0 * t + 0.5 * g * t * t;
    // Explicit Euler lags the velocity by one step: error -g t dt / 2; semi-implicit leads: +g t dt / 2.
    double y_expect = y_exact;
    if (s == Integrator::kExplicitEuler) y_expect -= 0.5 * g * t * dt;
    if (s == Integrator::kSemiImplicitEuler) y_expect += 0.5 * g * t * dt;
    EXPECT_NEAR(p.y[0], y_expect, 2e-5 * std::abs(y_exact) + 1e-4) << static_cast<int>(s);
    EXPECT_NEAR(p.x[0], vx0 * t, 1e-5);
    EXPECT_NEAR(p.vy[0], vy0 + g * t, 1e-4);
    if (s != Integrator::kVelocityVerlet && s != Integrator::kRk4) {
      EXPECT_GT(std::abs(p.y[0] - y_exact), 0.1 * t * dt);  // the O(dt) error is really there
    }
  }
}

double energy(const Particles& p, double k) {
  return 0.5 * (double(p.vx[0]) * p.vx[0] + double(p.vy[0]) * p.vy[0]) +
         0.5 * k * (double(p.x[0]) * p.x[0] + double(p.y[0]) * p.y[0]);
}

TEST(ParticleIntegrators, OscillatorEnergyBehaviour) {
  Harmonic h{1.0f};  // omega = 1, period 2 pi
  const double wdt = 0.2;
  const uint32_t per_period = static_cast<uint32_t>(std::lround(2.0 * M_PI / wdt));
  for (Integrator s : kAll) {
    Particles p(1);
    p.x[0] = 1.0f;
    IntegrateDesc d = desc_of(s, float(wdt), 1);
    d.field = {harmonic_field, &h};
    const double e0 = energy(p, h.k);
    const uint32_t periods = s == Integrator::kExplicitEuler ? 10 : 1000;
    const uint32_t n_steps = periods * per_period;
    double lo = e0, hi = e0, first_hi = 0.0, last_hi = 0.0;
    for (uint32_t k = 0; k < n_steps; ++k) {  // one step a call: sample every step
      ASSERT_TRUE(integrate_particles(d, p.arrays()).ok());
      const double e = energy(p, h.k);
      lo = std::min(lo, e);
      hi = std::max(hi, e);
      if (k < 10 * per_period) first_hi = hi;
      if (k + 10 * per_period >= n_steps) last_hi = std::max(last_hi, e);
    }
    hi = std::max(hi, last_hi);
    const double e = energy(p, h.k), steps = double(n_steps);
    switch (s) {
      case Integrator::kExplicitEuler:  // E_n = E_0 (1 + (w dt)^2)^n exactly
        EXPECT_NEAR(std::log(e / e0), steps * std::log1p(wdt * wdt), 1e-3 * steps * wdt * wdt);
        break;
      case Integrator::kSemiImplicitEuler:  // conserves a modified energy: bounded, no trend
        EXPECT_LT(hi / e0, 1.0 + 0.6 * wdt);
        EXPECT_GT(lo / e0, 1.0 - 0.6 * wdt);
        EXPECT_LT(last_hi, first_hi * (1.0 + 1e-4));  // the last 10 periods peak no higher than the first 10
        break;
      case Integrator::kVelocityVerlet:  // bounded, O((w dt)^2)
        EXPECT_LT(hi / e0, 1.0 + 0.3 * wdt * wdt);
        EXPECT_GT(lo / e0, 1.0 - 0.3 * wdt * wdt);
        EXPECT_LT(last_hi, first_hi * (1.0 + 1e-5));
        break;
      case Integrator::kRk4:  // amplification |R|^2 = 1 - (w dt)^6 / 72 + O(dt^8) per step
        EXPECT_NEAR(std::log(e / e0), -steps * std::pow(wdt, 6) / 72.0, 0.05 * steps * std::pow(wdt, 6) / 72.0);
        break;
    }
  }
}

TEST(ParticleIntegrators, OrderOfConvergence) {
  Harmonic h{1.0f};
  const double t_end = 8.0;
  const struct {
    Integrator s;
    double dt, ratio, tol;
  } cases[] = {{Integrator::kExplicitEuler, 1.0 / 256, 2.0, 0.15},
               {Integrator::kSemiImplicitEuler, 1.0 / 256, 2.0, 0.15},
               {Integrator::kVelocityVerlet, 1.0 / 64, 4.0, 0.3},
               {Integrator::kRk4, 1.0 / 4, 16.0, 1.5}};
  for (const auto& c : cases) {
    double err[2];
    for (int k = 0; k < 2; ++k) {
      const double dt = c.dt / (1 << k);
      Particles p(1);
      p.x[0] = 1.0f;
      IntegrateDesc d = desc_of(c.s, float(dt), uint32_t(std::lround(t_end / dt)));
      d.field = {harmonic_field, &h};
      ASSERT_TRUE(integrate_particles(d, p.arrays()).ok());
      err[k] = std::abs(p.x[0] - std::cos(t_end));
    }
    EXPECT_NEAR(err[0] / err[1], c.ratio, c.tol) << static_cast<int>(c.s) << " " << err[0] << " " << err[1];
  }
}

TEST(ParticleIntegrators, CircularOrbitRadius) {
  float mu = 1.0f;  // r = 1, v = 1, period 2 pi
  const struct {
    Integrator s;
    double bound;
  } cases[] = {{Integrator::kExplicitEuler, 0.5}, {Integrator::kSemiImplicitEuler, 2e-3},
               {Integrator::kVelocityVerlet, 1e-4}, {Integrator::kRk4, 4e-5}};
  const double dt = 2.0 * M_PI / 1000.0;
  for (const auto& c : cases) {
    Particles p(1);
    p.x[0] = 1.0f;
    p.vy[0] = 1.0f;
    IntegrateDesc d = desc_of(c.s, float(dt), 1000);
    d.field = {central_field, &mu};
    double dev = 0.0;
    for (int k = 0; k < 10; ++k) {
      ASSERT_TRUE(integrate_particles(d, p.arrays()).ok());
      dev = std::max(dev, std::abs(std::hypot(double(p.x[0]), double(p.y[0])) - 1.0));
    }
    EXPECT_LT(dev, c.bound) << static_cast<int>(c.s);
    if (c.s == Integrator::kExplicitEuler) {
      EXPECT_GT(dev, 0.05);  // explicit Euler spirals out
    }
  }
}

TEST(ParticleIntegrators, DampedOscillatorMatchesExact) {
  // x'' = -k x - c x', k = 4, c = 0.4: x = e^{-c t/2} (cos(wd t) + (c / (2 wd)) sin(wd t)).
  Harmonic h{4.0f};
  const double c = 0.4, wd = std::sqrt(4.0 - c * c / 4.0), t = 5.0;
  const double exact = std::exp(-c * t / 2) * (std::cos(wd * t) + c / (2 * wd) * std::sin(wd * t));
  const struct {
    Integrator s;
    double tol;
  } cases[] = {{Integrator::kExplicitEuler, 2e-2}, {Integrator::kSemiImplicitEuler, 2e-2},
               {Integrator::kVelocityVerlet, 1e-3}, {Integrator::kRk4, 1e-5}};
  for (const auto& cs : cases) {
    Particles p(1);
    p.x[0] = 1.0f;
    IntegrateDesc d = desc_of(cs.s, 1.0f / 1024, 5 * 1024);
    d.field = {harmonic_field, &h};
    d.linear_damping = float(c);
    ASSERT_TRUE(integrate_particles(d, p.arrays()).ok());
    EXPECT_NEAR(p.x[0], exact, cs.tol) << static_cast<int>(cs.s);
  }
}

TEST(ParticleIntegrators, TwoBodySpringFrequency) {
  // Masses 1 and 3 (w 1, 1/3), k = 12: reduced mass 3/4, omega = 4; stretch 0.1 from rest 1.
  const uint32_t a[] = {0}, b[] = {1};
  const float rest[] = {1.0f}, kk[] = {12.0f}, damp[] = {0.0f};
  const double omega = 4.0, t = 3.0;
  for (Integrator s : kAll) {
    Particles p(2);
    p.w = {1.0f, 1.0f / 3.0f};
    p.x = {0.0f, 1.1f};
    IntegrateDesc d = desc_of(s, 1.0f / 4096, 3 * 4096);
    d.springs = {a, b, rest, kk, damp};
    ASSERT_TRUE(integrate_particles(d, p.arrays()).ok());
    const double len = double(p.x[1]) - p.x[0], exact = 1.0 + 0.1 * std::cos(omega * t);
    EXPECT_NEAR(len, exact, s == Integrator::kExplicitEuler || s == Integrator::kSemiImplicitEuler ? 2e-3 : 2e-5)
        << static_cast<int>(s);
    // Momentum is conserved (forces exactly antisymmetric): m0 v0 + m1 v1 = 0.
    EXPECT_NEAR(p.vx[0] + 3.0 * p.vx[1], 0.0, 1e-5);
    EXPECT_EQ(p.y[0], 0.0f);
  }
}

TEST(ParticleIntegrators, PinnedParticlesStay) {
  const uint32_t a[] = {0, 1}, b[] = {1, 2};
  const float rest[] = {0.5f, 0.5f}, kk[] = {100.0f, 100.0f}, damp[] = {1.0f, 1.0f};
  for (Integrator s : kAll) {
    Particles p(3);
    p.w = {0.0f, 1.0f, 0.0f};
    p.x = {0.0f, 0.3f, 1.0f};
    IntegrateDesc d = desc_of(s, 1.0f / 240, 240, {0.0f, -9.81f, 0.0f});
    d.springs = {a, b, rest, kk, damp};
    ASSERT_TRUE(integrate_particles(d, p.arrays()).ok());
    EXPECT_EQ(p.x[0], 0.0f);
    EXPECT_EQ(p.y[0], 0.0f);
    EXPECT_EQ(p.x[2], 1.0f);
    EXPECT_EQ(p.vy[2], 0.0f);
    EXPECT_LT(p.y[1], 0.0f);  // the free one sags
  }
}

TEST(ParticleIntegrators, RejectsBadInput) {
  Particles p(3);
  const uint32_t a[] = {0}, b_bad[] = {3}, b_same[] = {0}, b[] = {1};
  const float rest[] = {1.0f}, kk[] = {1.0f}, kneg[] = {-1.0f}, damp[] = {0.0f};
  auto code = [&](IntegrateDesc d, ParticleArrays arr) { return integrate_particles(d, arr).code(); };
  IntegrateDesc d = desc_of(Integrator::kRk4, 0.01f, 1);
  for (float dt : {0.0f, -1.0f, NAN, INFINITY}) {
    IntegrateDesc e = d;
    e.dt = dt;
    EXPECT_EQ(code(e, p.arrays()), StatusCode::kInvalidArgument);
  }
  IntegrateDesc e = d;
  e.springs = {a, b_bad, rest, kk, damp};
  Status st = integrate_particles(e, p.arrays());
  EXPECT_EQ(st.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(st.message().find("spring 0"), std::string::npos) << st.message();
  e.springs = {a, b_same, rest, kk, damp};
  EXPECT_EQ(code(e, p.arrays()), StatusCode::kInvalidArgument);
  e.springs = {a, b, rest, kneg, damp};
  st = integrate_particles(e, p.arrays());
  EXPECT_NE(st.message().find("stiffness"), std::string::npos) << st.message();
  e.springs = {a, b, rest, kk, std::span<const float>()};
  EXPECT_EQ(code(e, p.arrays()), StatusCode::kSizeMismatch);
  Particles q = p;
  q.vy[2] = NAN;
  st = integrate_particles(d, q.arrays());
  EXPECT_EQ(st.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(st.message().find("particle 2: vy"), std::string::npos) << st.message();
  q = p;
  q.w.pop_back();
  EXPECT_EQ(code(d, q.arrays()), StatusCode::kSizeMismatch);
  q = p;
  q.w[1] = -1.0f;
  EXPECT_EQ(code(d, q.arrays()), StatusCode::kInvalidArgument);
}

TEST(ParticleIntegrators, EmptyAndZeroStepsLeaveStateAlone) {
  for (Integrator s : kAll) {
    Particles e(0);
    EXPECT_TRUE(integrate_particles(desc_of(s, 0.01f, 3), e.arrays()).ok());
    Particles p(2);
    p.x = {1.0f, -2.0f};
    p.vy = {3.0f, 4.0f};
    const Particles before = p;
    EXPECT_TRUE(integrate_particles(desc_of(s, 0.01f, 0, {0.0f, -9.81f, 0.0f}), p.arrays()).ok());
    EXPECT_EQ(p.x, before.x);
    EXPECT_EQ(p.vy, before.vy);
  }
}

TEST(ParticleIntegrators, SameBytesForAnyThreadCount) {
  const uint32_t n = 20000;
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  Particles p0(n);
  for (uint32_t i = 0; i < n; ++i) {
    p0.x[i] = float(i) * 0.01f;
    p0.y[i] = u(rng);
    p0.z[i] = u(rng);
    p0.vx[i] = u(rng);
    p0.w[i] = i % 97 == 0 ? 0.0f : 1.0f + 0.5f * u(rng);
  }
  std::vector<uint32_t> a, b;
  std::vector<float> rest, kk, damp;
  for (uint32_t i = 0; i + 1 < n; ++i) {  // a chain plus random long links
    a.push_back(i);
    b.push_back(i + 1);
    const uint32_t j = uint32_t(rng() % n);
    if (j != i) {
      a.push_back(j);
      b.push_back(i);
    }
  }
  for (size_t s = 0; s < a.size(); ++s) {
    rest.push_back(0.01f);
    kk.push_back(50.0f);
    damp.push_back(0.1f);
  }
  Harmonic h{0.5f};
  for (Integrator s : kAll) {
    std::vector<float> ref;
    for (uint32_t threads : {1u, 2u, 3u, 8u, 16u}) {
      Particles p = p0;
      IntegrateDesc d = desc_of(s, 1.0f / 120, 5, {0.0f, -9.81f, 0.0f});
      d.springs = {a, b, rest, kk, damp};
      d.field = {harmonic_field, &h};
      d.linear_damping = 0.1f;
      ExecConfig ex;
      ex.threads = threads;
      ASSERT_TRUE(integrate_particles(d, p.arrays(), ex).ok());
      std::vector<float> all;
      for (auto* v : {&p.x, &p.y, &p.z, &p.vx, &p.vy, &p.vz}) all.insert(all.end(), v->begin(), v->end());
      for (float f : all) ASSERT_TRUE(std::isfinite(f));
      if (ref.empty()) {
        ref = all;
      } else {
        EXPECT_EQ(0, std::memcmp(ref.data(), all.data(), all.size() * sizeof(float)))
            << static_cast<int>(s) << " threads " << threads;
      }
    }
  }
}

}  // namespace
}  // namespace impact
