// Semi-implicit Euler (kernels/integrate/semi_implicit_euler.*): a ball thrown up
// at v0 = 10 m/s under g = 10 m/s^2, no planes, stepped through World.
//
// Discrete solution. The scheme is v_k = v_{k-1} - g dt, y_k = y_{k-1} + v_k dt
// (positions use the already-updated velocity), so with y_0 = 0
//   v_k = v0 - k g dt,   y_k = k v0 dt - g dt^2 k (k + 1) / 2.
// With N = v0 / (g dt) an integer, v_N = 0 and the discrete peak is
//   y_N = y_{N-1} = v0^2 / (2 g) - v0 dt / 2 = 5 - 5 dt.
// Error bound. The exact peak is v0^2/(2g) = 5 m, reached at T = v0/g = 1 s. Each
// step's position update uses the end-of-step velocity, which undershoots the
// mean velocity over the step by g dt / 2; over the T/dt steps of the ascent the
// position therefore lags by at most (T/dt) * (g dt/2) * dt = g T dt / 2 (here
// exactly 5 dt). So |peak - 5| <= g T dt / 2, with 1e-4 slack for float rounding.
// SolverKind::kJacobi runs this scheme once per step; kSoftStep runs it once per
// substep, h = dt / substeps, so every formula holds with dt -> h and k -> k S
// (sampled every S substeps; the peak sample is exact since N is a multiple of S).
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "impact/impact.h"
#include "support/test_support.h"

namespace impact {
namespace {

struct Flight {
  std::vector<float> y, v;  // after each step; y[0], v[0] are the initial state
};

class SemiImplicitEuler : public ::testing::TestWithParam<SolverKind> {
 protected:
  // Integration substeps per step of the solver under test.
  uint32_t substeps() const { return GetParam() == SolverKind::kJacobi ? 1u : SolverDesc{}.substeps; }
  Flight throw_up(float dt, uint32_t steps, float vx = 0.0f) const;
};

Flight SemiImplicitEuler::throw_up(float dt, uint32_t steps, float vx) const {
  WorldDesc d;
  d.gravity = {0.0f, -10.0f, 0.0f};
  d.fixed_dt = dt;
  d.solver.kind = GetParam();
  auto world = test::make_world(d);
  Flight f;
  if (!world) return f;
  BodyDesc b;
  b.position = {0, 0, 0};
  b.velocity = {vx, 10.0f, 0};
  BodyHandle h;
  EXPECT_TRUE(test::IsOk(world->create_bodies(std::span(&b, 1), std::span(&h, 1))));
  f.y.push_back(0);
  f.v.push_back(10);
  for (uint32_t k = 0; k < steps; ++k) {
    EXPECT_TRUE(test::IsOk(world->step()));
    Eigen::Vector3f p, v;
    EXPECT_TRUE(test::IsOk(world->get_positions(std::span(&h, 1), std::span(&p, 1))));
    EXPECT_TRUE(test::IsOk(world->get_velocities(std::span(&h, 1), std::span(&v, 1))));
    f.y.push_back(p.y());
    f.v.push_back(v.y());
    EXPECT_EQ(world->last_step().contacts, 0u);
  }
  return f;
}

TEST_P(SemiImplicitEuler, PeakWithinBoundAndMatchesDiscreteFormula) {
  const double g = 10.0, v0 = 10.0, T = v0 / g;
  for (int steps_per_second : {10, 50, 60, 64, 100, 128, 240}) {
    SCOPED_TRACE(steps_per_second);
    const float dt = 1.0f / static_cast<float>(steps_per_second);
    const Flight f = throw_up(dt, static_cast<uint32_t>(steps_per_second) * 2);
    const double S = substeps(), h = dt / S;
    ASSERT_FALSE(f.y.empty());
    double peak = -1e30;
    size_t at = 0;
    for (size_t k = 0; k < f.y.size(); ++k)
      if (f.y[k] > peak) {
        peak = f.y[k];
        at = k;
      }
    EXPECT_LE(std::abs(peak - 5.0), g * T * h / 2 + 1e-4);
    EXPECT_NEAR(peak, 5.0 - 5.0 * h, 1e-4);
    // The peak is at substep N - 1 or N (equal heights in exact arithmetic).
    const double n = v0 / (g * h);
    EXPECT_NEAR(static_cast<double>(at) * S, n - 0.5 * S, 0.5 * S + 1e-3);
    // The whole trajectory follows the discrete solution.
    for (size_t k = 0; k < f.y.size(); ++k) {
      const double kk = static_cast<double>(k) * S;
      EXPECT_NEAR(f.v[k], v0 - kk * g * h, 2e-5 * (1 + kk)) << "step " << k;
      EXPECT_NEAR(f.y[k], kk * v0 * h - g * h * h * kk * (kk + 1) / 2, 2e-6 * (1 + kk)) << "step " << k;
    }
  }
}

TEST_P(SemiImplicitEuler, ExactInBinaryFractions) {
  // dt = 1/64: g dt = 5/32 and every v_k, y_k is a short binary fraction, so float
  // arithmetic is exact and the peak is exactly 5 - 5/64.
  // With S substeps h = 1/(64 S) is a binary fraction too (S = 1 or 4).
  const Flight f = throw_up(1.0f / 64.0f, 128);
  ASSERT_EQ(f.y.size(), 129u);
  const float S = static_cast<float>(substeps()), h = 1.0f / (64.0f * S), K = 128.0f * S;
  EXPECT_EQ(f.v[64], 0.0f);
  EXPECT_EQ(f.y[64], 5.0f - 5.0f * h);
  if (S == 1.0f) {
    EXPECT_EQ(f.y[63], 5.0f - 5.0f * h);
  }
  float peak = 0;
  for (float y : f.y) peak = std::max(peak, y);
  EXPECT_EQ(peak, 5.0f - 5.0f * h);
  EXPECT_EQ(f.y[128], K * 10.0f * h - 10.0f * h * h * K * (K + 1) / 2);  // back to 0 minus the lag
}

TEST_P(SemiImplicitEuler, HorizontalVelocityIsConstant) {
  WorldDesc d;
  d.gravity = {0.0f, -10.0f, 0.0f};
  d.fixed_dt = 1.0f / 64.0f;
  d.solver.kind = GetParam();
  auto world = test::make_world(d);
  BodyDesc b[2];
  b[0].velocity = {3.0f, 10.0f, -1.0f};
  b[1].position = {100, 0, 0};
  b[1].velocity = {2.0f, 1.0f, 0.5f};
  b[1].inv_mass = 0.0f;  // static: gravity does not act, velocity is kept (kinematic)
  BodyHandle h[2];
  IMPACT_ASSERT_OK(world->create_bodies(b, h));
  for (int k = 0; k < 64; ++k) IMPACT_ASSERT_OK(world->step());
  Eigen::Vector3f p[2], v[2];
  IMPACT_ASSERT_OK(world->get_positions(h, p));
  IMPACT_ASSERT_OK(world->get_velocities(h, v));
  EXPECT_EQ(p[0].x(), 3.0f);
  EXPECT_EQ(p[0].z(), -1.0f);
  EXPECT_EQ(v[0].x(), 3.0f);
  EXPECT_EQ(v[0].y(), 0.0f);
  EXPECT_EQ(p[1], Eigen::Vector3f(102.0f, 1.0f, 0.5f));
  EXPECT_EQ(v[1], Eigen::Vector3f(2.0f, 1.0f, 0.5f));
}

INSTANTIATE_TEST_SUITE_P(Solvers, SemiImplicitEuler, ::testing::Values(SolverKind::kSoftStep, SolverKind::kJacobi),
                         [](const ::testing::TestParamInfo<SolverKind>& i) {
                           return i.param == SolverKind::kSoftStep ? "SoftStep" : "Jacobi";
                         });

}  // namespace
}  // namespace impact
