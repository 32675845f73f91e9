// Islands and sleeping (SolverDesc::sleep; kernels/solver/islands.h,
// host/pipeline/sleep_stage.cpp). References: the timer rule itself (a body quiet for
// sleep_time sleeps after that many steps), the same scenes run with sleep off (a
// sleeping pile rests where the awake one does), and what must not happen (a resting
// body left floating when its support goes, a moving body put to sleep, a sleeping
// island that a contact does not wake).
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "impact/world.h"
#include "support/test_support.h"

namespace impact {
namespace {

constexpr float kH = 1.0f / 60.0f;

WorldDesc sleep_desc(bool sleep = true) {
  WorldDesc d;
  d.solver.sleep = sleep;
  return d;
}

void add_floor(World& w, float friction = 0.6f) {
  PlaneDesc p;
  p.normal = Eigen::Vector3f::UnitY();
  p.friction = friction;
  PlaneHandle h;
  ASSERT_TRUE(test::IsOk(w.create_planes(std::span(&p, 1), std::span(&h, 1))));
}

ShapeId unit_box(World& w) {
  ShapeId id;
  EXPECT_TRUE(test::IsOk(w.shapes().add_box(Eigen::Vector3f(0.5f, 0.5f, 0.5f), &id)));
  return id;
}

// `layers` 1 m boxes stacked at each of `cols` x `cols` places 3 m apart (separate
// islands: the stacks do not touch), 1 cm gaps to fall through.
std::vector<BodyHandle> add_stacks(World& w, int cols, int layers) {
  const ShapeId box = unit_box(w);
  std::vector<BodyDesc> ds;
  for (int i = 0; i < cols; ++i)
    for (int k = 0; k < cols; ++k)
      for (int j = 0; j < layers; ++j) {
        BodyDesc d;
        d.shape = box;
        d.inv_mass = 1.0f;
        d.friction = 0.6f;
        d.position = Eigen::Vector3f(3.0f * static_cast<float>(i), 0.51f + 1.01f * static_cast<float>(j),
                                     3.0f * static_cast<float>(k));
        ds.push_back(d);
      }
  std::vector<BodyHandle> h(ds.size());
  EXPECT_TRUE(test::IsOk(w.create_bodies(ds, h)));
  return h;
}

Eigen::Vector3f position(const World& w, BodyHandle h) {
  Eigen::Vector3f p;
  EXPECT_TRUE(test::IsOk(w.get_positions(std::span(&h, 1), std::span(&p, 1))));
  return p;
}

bool asleep(const World& w, BodyHandle h) {
  uint32_t slot = 0;
  EXPECT_TRUE(test::IsOk(w.slot_of(h, &slot)));
  return w.bodies().asleep[slot] != 0;
}

// Steps until every dynamic body sleeps (at most `limit` steps); returns the steps run.
int step_until_asleep(World& w, size_t dynamic, int limit) {
  for (int s = 1; s <= limit; ++s) {
    EXPECT_TRUE(test::IsOk(w.step()));
    if (w.last_step().asleep_bodies == dynamic) return s;
  }
  return -1;
}

TEST(Sleep, AQuietBodySleepsAfterSleepTime) {
  // Zero gravity, zero velocity: quiet from the first step, so asleep at the first step
  // whose timer (a sum of dt in float) reaches sleep_time.
  WorldDesc d = test::zero_gravity_desc();
  d.solver.sleep_time = 0.5f;
  auto w = test::make_world(d);
  BodyDesc b;
  b.inv_mass = 1.0f;
  BodyHandle h;
  IMPACT_ASSERT_OK(w->create_bodies(std::span(&b, 1), std::span(&h, 1)));
  float timer = 0.0f;
  int expected = 0;
  // The stage counts the step's own dt after the velocities the previous step left.
  while (!(timer >= d.solver.sleep_time)) {
    timer += d.fixed_dt;
    ++expected;
  }
  EXPECT_EQ(step_until_asleep(*w, 1, 200), expected);
  EXPECT_TRUE(asleep(*w, h));
  IMPACT_ASSERT_OK(w->step());
  EXPECT_TRUE(w->last_step().skipped) << "nothing awake: the step runs no stage";
}

TEST(Sleep, MovingBodiesStayAwakeSlowOnesSleep) {
  // Frictionless floor: a sphere keeps its speed. Above sleep_speed it never sleeps;
  // below it, it sleeps (and stops: the price of sleeping, bounded by sleep_speed).
  for (const float v : {0.2f, 0.02f}) {
    auto w = test::make_world(sleep_desc());
    add_floor(*w, 0.0f);
    BodyDesc b;
    b.inv_mass = 1.0f;
    b.radius = 0.5f;
    b.position = Eigen::Vector3f(0.0f, 0.499f, 0.0f);
    b.velocity = Eigen::Vector3f(v, 0.0f, 0.0f);
    BodyHandle h;
    IMPACT_ASSERT_OK(w->create_bodies(std::span(&b, 1), std::span(&h, 1)));
    for (int s = 0; s < 120; ++s) IMPACT_ASSERT_OK(w->step());
    if (v > w->desc().solver.sleep_speed) {
      EXPECT_FALSE(asleep(*w, h)) << v;
      EXPECT_NEAR(position(*w, h).x(), v * 120 * kH, 1e-3f) << "it slides freely";
    } else {
      EXPECT_TRUE(asleep(*w, h)) << v;
    }
  }
}

TEST(Sleep, ABouncingBallNeverSleeps) {
  // At the top of each bounce the speed passes through zero, but never for sleep_time.
  auto w = test::make_world(sleep_desc());
  PlaneDesc p;
  p.normal = Eigen::Vector3f::UnitY();
  p.restitution = 1.0f;
  PlaneHandle ph;
  IMPACT_ASSERT_OK(w->create_planes(std::span(&p, 1), std::span(&ph, 1)));
  BodyDesc b;
  b.inv_mass = 1.0f;
  b.radius = 0.25f;
  b.restitution = 1.0f;
  b.position = Eigen::Vector3f(0.0f, 2.0f, 0.0f);
  BodyHandle h;
  IMPACT_ASSERT_OK(w->create_bodies(std::span(&b, 1), std::span(&h, 1)));
  for (int s = 0; s < 600; ++s) {
    IMPACT_ASSERT_OK(w->step());
    ASSERT_EQ(w->last_step().asleep_bodies, 0u) << "step " << s;
  }
}

TEST(Sleep, SettledStacksSleepWhereTheyWouldRestAwake) {
  // 3 x 3 stacks of 3 boxes: with sleep every box sleeps, the world then skips its
  // steps and nothing moves by a single bit; without sleep the same stacks stand
  // within a millimetre of where the sleeping ones stopped.
  auto on = test::make_world(sleep_desc(true));
  auto off = test::make_world(sleep_desc(false));
  add_floor(*on);
  add_floor(*off);
  const std::vector<BodyHandle> hon = add_stacks(*on, 3, 3), hoff = add_stacks(*off, 3, 3);
  const int steps = step_until_asleep(*on, hon.size(), 600);
  ASSERT_GT(steps, 30) << "the stacks fall 1 cm first";
  const uint64_t hash = on->state_hash();
  for (int s = 0; s < 120; ++s) {
    IMPACT_ASSERT_OK(on->step());
    EXPECT_TRUE(on->last_step().skipped);
  }
  EXPECT_EQ(on->state_hash(), hash);
  EXPECT_GT(on->contacts().size(), 0u) << "a skipped step keeps the last contacts";
  for (int s = 0; s < steps + 120; ++s) IMPACT_ASSERT_OK(off->step());
  EXPECT_EQ(off->last_step().asleep_bodies, 0u);
  for (size_t i = 0; i < hon.size(); ++i)
    EXPECT_LT((position(*on, hon[i]) - position(*off, hoff[i])).norm(), 1e-3f) << "box " << i;
}

TEST(Sleep, IslandsSleepApart) {
  // Two stacks 3 m apart are two islands: one is kept busy by a push every step, the
  // other sleeps regardless.
  auto w = test::make_world(sleep_desc());
  add_floor(*w);
  const std::vector<BodyHandle> h = add_stacks(*w, 2, 2);  // stacks at x = 0 and x = 3 (z = 0, 3)
  const BodyHandle pushed = h[0];                         // bottom box of the stack at (0, 0)
  for (int s = 0; s < 240; ++s) {
    const Eigen::Vector3f f(0.0f, 0.0f, s % 2 == 0 ? 30.0f : -30.0f);  // rocks it without toppling
    IMPACT_ASSERT_OK(w->apply_forces(std::span(&pushed, 1), std::span(&f, 1)));
    IMPACT_ASSERT_OK(w->step());
  }
  EXPECT_FALSE(asleep(*w, h[0]));
  EXPECT_FALSE(asleep(*w, h[1])) << "the top box of the pushed stack shares its island";
  for (size_t i = 2; i < h.size(); ++i) EXPECT_TRUE(asleep(*w, h[i])) << "box " << i;
  EXPECT_EQ(w->last_step().asleep_bodies, h.size() - 2);
}

TEST(Sleep, AFallingBoxWakesTheWholeStackItHits) {
  auto w = test::make_world(sleep_desc());
  add_floor(*w);
  const std::vector<BodyHandle> stack = add_stacks(*w, 1, 4);
  ASSERT_GT(step_until_asleep(*w, stack.size(), 600), 0);
  BodyDesc ball;
  ball.shape = ShapeId{w->bodies().shape[0]};  // the stack's 1 m box
  ball.inv_mass = 1.0f;
  ball.friction = 0.6f;
  ball.position = position(*w, stack.back()) + Eigen::Vector3f(0.0f, 2.0f, 0.0f);
  BodyHandle bh;
  IMPACT_ASSERT_OK(w->create_bodies(std::span(&ball, 1), std::span(&bh, 1)));
  bool woke = false;
  for (int s = 0; s < 120 && !woke; ++s) {
    IMPACT_ASSERT_OK(w->step());
    EXPECT_FALSE(w->last_step().skipped);
    if (w->last_step().asleep_bodies == 0) {
      woke = true;
      for (const BodyHandle& h : stack) EXPECT_FALSE(asleep(*w, h));
    } else {
      ASSERT_EQ(w->last_step().asleep_bodies, stack.size()) << "the island wakes as one";
    }
  }
  ASSERT_TRUE(woke);
  // The stack takes the box and sleeps again, standing.
  ASSERT_GT(step_until_asleep(*w, stack.size() + 1, 900), 0);
  for (size_t j = 0; j < stack.size(); ++j)
    EXPECT_NEAR(position(*w, stack[j]).y(), 0.5f + 1.0f * static_cast<float>(j), 0.02f) << "box " << j;
}

TEST(Sleep, CallsWakeBodies) {
  // Each call that moves or pushes a sleeping body wakes it.
  enum Call { kImpulse, kVelocity, kForce, kTorque, kAngular, kPosition, kOrientation, kWake };
  for (int call = kImpulse; call <= kWake; ++call) {
    auto w = test::make_world(sleep_desc());
    add_floor(*w);
    const std::vector<BodyHandle> h = add_stacks(*w, 1, 1);
    ASSERT_GT(step_until_asleep(*w, 1, 600), 0);
    ASSERT_TRUE(asleep(*w, h[0]));
    const Eigen::Vector3f v(1.0f, 0.0f, 0.0f), p = position(*w, h[0]);
    switch (call) {
      case kImpulse: IMPACT_ASSERT_OK(w->apply_impulses(std::span(&h[0], 1), std::span(&v, 1), std::span(&p, 1))); break;
      case kVelocity: IMPACT_ASSERT_OK(w->set_velocities(std::span(&h[0], 1), std::span(&v, 1))); break;
      case kForce: IMPACT_ASSERT_OK(w->apply_forces(std::span(&h[0], 1), std::span(&v, 1))); break;
      case kTorque: IMPACT_ASSERT_OK(w->apply_torques(std::span(&h[0], 1), std::span(&v, 1))); break;
      case kAngular: IMPACT_ASSERT_OK(w->set_angular_velocities(std::span(&h[0], 1), std::span(&v, 1))); break;
      case kPosition: {
        const Eigen::Vector3f up = p + Eigen::Vector3f(0.0f, 1.0f, 0.0f);
        IMPACT_ASSERT_OK(w->set_positions(std::span(&h[0], 1), std::span(&up, 1)));
        break;
      }
      case kOrientation: {
        const Eigen::Quaternionf q(Eigen::AngleAxisf(0.3f, Eigen::Vector3f::UnitY()));
        IMPACT_ASSERT_OK(w->set_orientations(std::span(&h[0], 1), std::span(&q, 1)));
        break;
      }
      case kWake: IMPACT_ASSERT_OK(w->wake_bodies(std::span(&h[0], 1))); break;
    }
    EXPECT_FALSE(asleep(*w, h[0])) << "call " << call;
    IMPACT_ASSERT_OK(w->step());
    EXPECT_FALSE(w->last_step().skipped) << "call " << call;
    EXPECT_EQ(w->last_step().asleep_bodies, 0u) << "call " << call;
    if (call == kPosition) {
      EXPECT_LT(position(*w, h[0]).y(), p.y() + 1.0f) << "it falls from where it was put";
    }
    if (call == kWake) {
      // Nothing pushed it: a full sleep_time later it sleeps again.
      EXPECT_GT(step_until_asleep(*w, 1, 600), 25);
    }
  }
}

TEST(Sleep, RemovingOrMovingTheSupportWakesWhatRestsOnIt) {
  for (const bool destroy : {true, false}) {
    auto w = test::make_world(sleep_desc());
    add_floor(*w);
    const std::vector<BodyHandle> h = add_stacks(*w, 1, 3);
    ASSERT_GT(step_until_asleep(*w, 3, 600), 0);
    const float top = position(*w, h[2]).y();
    if (destroy) {
      IMPACT_ASSERT_OK(w->destroy_bodies(std::span(&h[0], 1)));
    } else {
      const Eigen::Vector3f away(20.0f, 0.5f, 0.0f);
      IMPACT_ASSERT_OK(w->set_positions(std::span(&h[0], 1), std::span(&away, 1)));
    }
    for (int s = 0; s < 90; ++s) IMPACT_ASSERT_OK(w->step());
    EXPECT_NEAR(position(*w, h[2]).y(), top - 1.0f, 0.03f) << (destroy ? "destroyed" : "moved")
                                                          << ": the boxes above fell onto the floor";
    EXPECT_NEAR(position(*w, h[1]).y(), 0.5f, 0.03f);
  }
}

TEST(Sleep, AMovingKinematicBodyKeepsWhatItCarriesAwake) {
  auto w = test::make_world(sleep_desc());
  const ShapeId box = unit_box(*w);
  ShapeId slab;
  IMPACT_ASSERT_OK(w->shapes().add_box(Eigen::Vector3f(10.0f, 0.25f, 10.0f), &slab));
  BodyDesc d[2];
  d[0].shape = slab;
  d[0].inv_mass = 0.0f;
  d[0].friction = 0.8f;
  d[0].velocity = Eigen::Vector3f(0.5f, 0.0f, 0.0f);
  d[1].shape = box;
  d[1].inv_mass = 1.0f;
  d[1].friction = 0.8f;
  d[1].position = Eigen::Vector3f(0.0f, 0.749f, 0.0f);
  BodyHandle h[2];
  IMPACT_ASSERT_OK(w->create_bodies(d, h));
  for (int s = 0; s < 180; ++s) IMPACT_ASSERT_OK(w->step());
  EXPECT_FALSE(asleep(*w, h[1])) << "carried by a moving platform: its speed is the platform's";
  EXPECT_NEAR(position(*w, h[1]).x(), 0.5f * 180 * kH, 0.05f);
  // Slow the platform below sleep_speed: the box is quiet, but still carried, so it
  // must stay awake; stop the platform: the box sleeps.
  const Eigen::Vector3f creep(0.01f, 0.0f, 0.0f), stop = Eigen::Vector3f::Zero();
  IMPACT_ASSERT_OK(w->set_velocities(std::span(&h[0], 1), std::span(&creep, 1)));
  for (int s = 0; s < 120; ++s) IMPACT_ASSERT_OK(w->step());
  EXPECT_FALSE(asleep(*w, h[1]));
  IMPACT_ASSERT_OK(w->set_velocities(std::span(&h[0], 1), std::span(&stop, 1)));
  EXPECT_GT(step_until_asleep(*w, 1, 300), 0);
}

TEST(Sleep, SleepOffOrJacobiKeepsEveryBodyAwake) {
  for (const bool jacobi : {false, true}) {
    WorldDesc d = sleep_desc(jacobi);  // jacobi: sleep on but ignored
    if (jacobi) d.solver.kind = SolverKind::kJacobi;
    auto w = test::make_world(d);
    add_floor(*w);
    BodyDesc b;
    b.inv_mass = 1.0f;
    b.radius = 0.5f;
    b.position = Eigen::Vector3f(0.0f, 0.5f, 0.0f);
    BodyHandle h;
    IMPACT_ASSERT_OK(w->create_bodies(std::span(&b, 1), std::span(&h, 1)));
    for (int s = 0; s < 120; ++s) {
      IMPACT_ASSERT_OK(w->step());
      ASSERT_EQ(w->last_step().asleep_bodies, 0u);
      ASSERT_FALSE(w->last_step().skipped);
    }
  }
  // Turning sleep off wakes a sleeping world.
  auto w = test::make_world(sleep_desc());
  add_floor(*w);
  const std::vector<BodyHandle> h = add_stacks(*w, 1, 2);
  ASSERT_GT(step_until_asleep(*w, 2, 600), 0);
  SolverDesc sd = w->desc().solver;
  sd.sleep = false;
  IMPACT_ASSERT_OK(w->set_solver(sd));
  EXPECT_FALSE(asleep(*w, h[0]));
  IMPACT_ASSERT_OK(w->step());
  EXPECT_FALSE(w->last_step().skipped);
  EXPECT_EQ(w->last_step().asleep_bodies, 0u);
}

TEST(Sleep, BitIdenticalForEveryBackendAndThreadCount) {
  // Stacks settle, sleep, get hit by a row of balls and wake: the hash at every
  // checkpoint is the same for every backend and thread count.
  auto run = [](Backend backend, uint32_t threads) {
    WorldDesc d = sleep_desc();
    d.backend = backend;
    d.threads = threads;
    auto w = test::make_world(d);
    add_floor(*w);
    add_stacks(*w, 3, 3);
    std::vector<uint64_t> hashes;
    for (int s = 1; s <= 240; ++s) {
      EXPECT_TRUE(test::IsOk(w->step()));
      if (s == 160) {
        std::vector<BodyDesc> balls(3);
        for (int i = 0; i < 3; ++i) {
          balls[i].inv_mass = 1.0f;
          balls[i].radius = 0.3f;
          balls[i].position = Eigen::Vector3f(3.0f * static_cast<float>(i) + 0.2f, 4.0f, 0.1f);
          balls[i].velocity = Eigen::Vector3f(0.0f, -5.0f, 0.0f);
        }
        std::vector<BodyHandle> bh(3);
        EXPECT_TRUE(test::IsOk(w->create_bodies(balls, bh)));
      }
      if (s % 20 == 0) hashes.push_back(w->state_hash());
    }
    return std::make_pair(hashes, w->last_step().asleep_bodies);
  };
  const auto ref = run(Backend::kSerial, 1);
  for (const test::ExecCase& c : test::exec_cases()) {
    const auto r = run(c.backend, c.threads);
    EXPECT_EQ(r.first, ref.first) << test::to_string(c);
  }
}

TEST(Sleep, InvalidKnobsAreRejected) {
  for (const float bad : {0.0f, -1.0f, NAN, INFINITY}) {
    WorldDesc d;
    d.solver.sleep_speed = bad;
    std::unique_ptr<World> w;
    EXPECT_TRUE(test::IsError(World::create(d, &w), StatusCode::kInvalidArgument, {"sleep_speed"}));
    d = WorldDesc{};
    d.solver.sleep_time = bad;
    EXPECT_TRUE(test::IsError(World::create(d, &w), StatusCode::kInvalidArgument, {"sleep_time"}));
  }
  auto w = test::make_world(WorldDesc{});
  const BodyHandle stale{12345, 7};
  EXPECT_TRUE(test::IsError(w->wake_bodies(std::span(&stale, 1)), StatusCode::kStaleHandle, {"wake_bodies"}));
}

}  // namespace
}  // namespace impact
