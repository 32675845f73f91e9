// Fixed-timestep driver (World::advance, host/world.cpp): the accumulator runs
// floor(acc / dt) steps, at most max_steps_per_frame, drops (and reports) the
// excess, and leaves alpha = leftover / dt in [0, 1); interpolated_positions()
// blends the last two steps' positions. The reference is integer bookkeeping in
// units of 1/1024 s with dt = 1/64 s, where every float involved is exact.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "impact/impact.h"
#include "support/test_support.h"

namespace impact {
namespace {

constexpr float kDt = 1.0f / 64.0f;
constexpr int kUnitsPerStep = 16;  // 1 unit = 1/1024 s

float units(int u) {
  return static_cast<float>(u) / 1024.0f;
}

struct Mover {
  std::unique_ptr<World> world;
  BodyHandle h;
};

// One body moving at 1 m/s along x without gravity: x = steps * dt exactly.
Mover make_mover(uint32_t max_steps, bool interpolation) {
  WorldDesc d = test::zero_gravity_desc();
  d.fixed_dt = kDt;
  d.max_steps_per_frame = max_steps;
  d.interpolation = interpolation;
  Mover m;
  m.world = test::make_world(d);
  BodyDesc b;
  b.velocity = {1.0f, 0.0f, 0.0f};
  EXPECT_TRUE(test::IsOk(m.world->create_bodies(std::span(&b, 1), std::span(&m.h, 1))));
  return m;
}

float x_of(const Mover& m) {
  Eigen::Vector3f p;
  EXPECT_TRUE(test::IsOk(m.world->get_positions(std::span(&m.h, 1), std::span(&p, 1))));
  return p.x();
}

TEST(WorldAdvance, VariableFrameTimesRunFloorOfAccumulatedSteps) {
  for (bool interpolation : {false, true}) {
    SCOPED_TRACE(interpolation);
    const uint32_t max_steps = 8;
    Mover m = make_mover(max_steps, interpolation);
    std::mt19937 rng(1);
    std::uniform_int_distribution<int> frame(0, 3 * kUnitsPerStep);
    int acc = 0;          // units
    int64_t total = 0;    // steps
    int64_t dropped = 0;  // units
    for (int f = 0; f < 400; ++f) {
      // Mostly ordinary frames, sometimes a hitch far over the step budget.
      const int u = f % 37 == 36 ? 13 * kUnitsPerStep + 5 : frame(rng);
      FrameResult r;
      IMPACT_ASSERT_OK(m.world->advance(units(u), &r));
      acc += u;
      const int steps = std::min<int>(acc / kUnitsPerStep, static_cast<int>(max_steps));
      acc -= steps * kUnitsPerStep;
      const int drop = (acc / kUnitsPerStep) * kUnitsPerStep;
      acc -= drop;
      total += steps;
      dropped += drop;
      ASSERT_EQ(r.steps, static_cast<uint32_t>(steps)) << "frame " << f;
      EXPECT_EQ(r.dropped, units(drop)) << "frame " << f;
      EXPECT_EQ(r.alpha, static_cast<float>(acc) / kUnitsPerStep) << "frame " << f;
      EXPECT_GE(r.alpha, 0.0f);
      EXPECT_LT(r.alpha, 1.0f);
      EXPECT_EQ(m.world->interpolation_alpha(), r.alpha);
      ASSERT_EQ(x_of(m), static_cast<float>(total) * kDt) << "frame " << f;
    }
    EXPECT_GT(dropped, 0);
  }
}

TEST(WorldAdvance, SixtyHertzFramesRunOneStepEach) {
  WorldDesc d = test::zero_gravity_desc();  // fixed_dt = 1/60 (not a binary fraction)
  auto world = test::make_world(d);
  for (int f = 0; f < 120; ++f) {
    FrameResult r;
    IMPACT_ASSERT_OK(world->advance(d.fixed_dt, &r));
    ASSERT_EQ(r.steps, 1u) << "frame " << f;
    EXPECT_EQ(r.alpha, 0.0f);
  }
  for (int f = 0; f < 60; ++f) {  // 30 Hz: two steps per frame
    FrameResult r;
    IMPACT_ASSERT_OK(world->advance(2.0f * d.fixed_dt, &r));
    ASSERT_EQ(r.steps, 2u) << "frame " << f;
  }
  for (int f = 0; f < 60; ++f) {  // 120 Hz: zero and one alternate
    FrameResult r;
    IMPACT_ASSERT_OK(world->advance(0.5f * d.fixed_dt, &r));
    ASSERT_EQ(r.steps, static_cast<uint32_t>(f % 2)) << "frame " << f;
    EXPECT_EQ(r.alpha, f % 2 ? 0.0f : 0.5f);
  }
}

TEST(WorldAdvance, MaxStepsPerFrameDropsTimeAndReportsIt) {
  Mover m = make_mover(3, false);
  FrameResult r;
  IMPACT_ASSERT_OK(m.world->advance(10.5f * kDt, &r));
  EXPECT_EQ(r.steps, 3u);
  EXPECT_EQ(r.dropped, 7.0f * kDt);
  EXPECT_EQ(r.alpha, 0.5f);
  EXPECT_EQ(x_of(m), 3.0f * kDt);
  // The dropped time is gone: the next half step completes a step.
  IMPACT_ASSERT_OK(m.world->advance(0.5f * kDt, &r));
  EXPECT_EQ(r.steps, 1u);
  EXPECT_EQ(r.dropped, 0.0f);
  EXPECT_EQ(r.alpha, 0.0f);
}

TEST(WorldAdvance, ZeroFrameRunsNothing) {
  Mover m = make_mover(8, false);
  const uint64_t before = m.world->state_hash();
  FrameResult r;
  IMPACT_ASSERT_OK(m.world->advance(0.0f, &r));
  EXPECT_EQ(r.steps, 0u);
  EXPECT_EQ(r.alpha, 0.0f);
  EXPECT_EQ(r.dropped, 0.0f);
  EXPECT_EQ(m.world->state_hash(), before);
}

TEST(WorldAdvance, InvalidFrameTimeIsRejectedAndChangesNothing) {
  Mover m = make_mover(8, true);
  IMPACT_ASSERT_OK(m.world->advance(2.5f * kDt));
  const test::WorldSnapshot before = test::snapshot(*m.world);
  const float alpha = m.world->interpolation_alpha();
  for (float bad : {std::numeric_limits<float>::quiet_NaN(), -kDt, -std::numeric_limits<float>::denorm_min(),
                    std::numeric_limits<float>::infinity(), -std::numeric_limits<float>::infinity()}) {
    SCOPED_TRACE(bad);
    FrameResult r;
    EXPECT_TRUE(test::IsError(m.world->advance(bad, &r), StatusCode::kInvalidArgument, {"frame_seconds"}));
    EXPECT_TRUE(test::snapshot(*m.world) == before);
    EXPECT_EQ(m.world->interpolation_alpha(), alpha);
  }
  // The accumulator kept its half step: another half completes a step.
  FrameResult r;
  IMPACT_ASSERT_OK(m.world->advance(0.5f * kDt, &r));
  EXPECT_EQ(r.steps, 1u);
  EXPECT_EQ(r.alpha, 0.0f);
  EXPECT_EQ(x_of(m), 3.0f * kDt);
}

TEST(WorldAdvance, AlphaStaysBelowOne) {
  // Accumulated leftover just under dt: dt * (1 - 2^-26). No step fits, and the
  // documented alpha range is [0, 1), so alpha must not round up to 1.0f.
  Mover m = make_mover(8, true);
  FrameResult r;
  const float a = kDt - kDt * 0x1p-24f;         // float just below dt
  const float b = kDt * (0x1p-24f - 0x1p-26f);  // the rest, minus dt * 2^-26
  IMPACT_ASSERT_OK(m.world->advance(a, &r));
  EXPECT_EQ(r.steps, 0u);
  IMPACT_ASSERT_OK(m.world->advance(b, &r));
  EXPECT_EQ(r.steps, 0u);
  EXPECT_LT(r.alpha, 1.0f);
  EXPECT_LT(m.world->interpolation_alpha(), 1.0f);
}

TEST(WorldAdvance, InterpolatedPositionsBlendPreviousAndCurrent) {
  Mover m = make_mover(8, true);
  BodyDesc still;
  still.position = {0, 5, 0};
  BodyHandle hs;
  IMPACT_ASSERT_OK(m.world->create_bodies(std::span(&still, 1), std::span(&hs, 1)));
  std::vector<Eigen::Vector3f> out(2);
  // Before any step both buffers hold the creation positions.
  IMPACT_ASSERT_OK(m.world->interpolated_positions(out));
  EXPECT_EQ(out[0], Eigen::Vector3f::Zero());
  int64_t total = 0;
  std::mt19937 rng(2);
  std::uniform_int_distribution<int> frame(0, 40);
  for (int f = 0; f < 200; ++f) {
    FrameResult r;
    IMPACT_ASSERT_OK(m.world->advance(units(frame(rng)), &r));
    total += r.steps;
    IMPACT_ASSERT_OK(m.world->interpolated_positions(out));
    // Output is in slot order; steps may re-sort slots (WorldDesc::reorder_interval).
    uint32_t sm = 0, ss = 0;
    IMPACT_ASSERT_OK(m.world->slot_of(m.h, &sm));
    IMPACT_ASSERT_OK(m.world->slot_of(hs, &ss));
    const double prev = total > 0 ? static_cast<double>(total - 1) * kDt : 0.0;
    const double cur = static_cast<double>(total) * kDt;
    const double want = (1.0 - r.alpha) * prev + r.alpha * cur;
    ASSERT_NEAR(out[sm].x(), want, 1e-6 * (1 + cur)) << "frame " << f;
    EXPECT_EQ(out[sm].y(), 0.0f);
    EXPECT_EQ(out[ss], Eigen::Vector3f(0, 5, 0));  // a resting body stays put
  }
  // A teleport does not interpolate: both buffers take the new position.
  IMPACT_ASSERT_OK(m.world->advance(0.5f * kDt));
  const Eigen::Vector3f to(-7, 1, 2);
  IMPACT_ASSERT_OK(m.world->set_positions(std::span(&m.h, 1), std::span(&to, 1)));
  IMPACT_ASSERT_OK(m.world->interpolated_positions(out));
  uint32_t sm = 0;
  IMPACT_ASSERT_OK(m.world->slot_of(m.h, &sm));
  EXPECT_EQ(out[sm], to);
}

TEST(WorldAdvance, InterpolatedPositionsErrors) {
  Mover plain = make_mover(8, false);
  std::vector<Eigen::Vector3f> out(1);
  EXPECT_TRUE(
      test::IsError(plain.world->interpolated_positions(out), StatusCode::kUnsupported, {"interpolation"}));
  Mover interp = make_mover(8, true);
  std::vector<Eigen::Vector3f> wrong(2);
  EXPECT_TRUE(test::IsError(interp.world->interpolated_positions(wrong), StatusCode::kSizeMismatch));
}

}  // namespace
}  // namespace impact
