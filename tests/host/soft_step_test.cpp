// The soft-step rigid contact solver (SolverKind::kSoftStep,
// kernels/solver/soft_contact.*) against answers known in advance: a block on a
// slope (static friction holds, kinetic friction gives a = g (sin t - mu cos t)), a
// box sliding to rest without turning (stopping distance v^2 / (2 mu g)), a ball
// that slides into rolling (v = 5/7 v0 for a solid ball), a stack and a pyramid
// that stand, an elastic bounce that keeps its height, and bit-identical results
// for every backend and thread count.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

#include "impact/world.h"
#include "support/test_support.h"

namespace impact {
namespace {

constexpr float kG = 9.81f;
constexpr float kH = 1.0f / 60.0f;

WorldDesc soft_desc() {
  WorldDesc d;
  d.gravity = Eigen::Vector3f(0.0f, -kG, 0.0f);
  d.solver.kind = SolverKind::kSoftStep;
  return d;
}

PlaneHandle add_plane(World& w, const Eigen::Vector3f& normal, float friction, float restitution = 0.0f) {
  PlaneDesc p;
  p.normal = normal;
  p.friction = friction;
  p.restitution = restitution;
  PlaneHandle h;
  EXPECT_TRUE(test::IsOk(w.create_planes(std::span(&p, 1), std::span(&h, 1))));
  return h;
}

Eigen::Vector3f get(const World& w, BodyHandle h, bool velocity) {
  Eigen::Vector3f out;
  if (velocity)
    EXPECT_TRUE(test::IsOk(w.get_velocities(std::span(&h, 1), std::span(&out, 1))));
  else
    EXPECT_TRUE(test::IsOk(w.get_positions(std::span(&h, 1), std::span(&out, 1))));
  return out;
}

Eigen::Vector3f spin(const World& w, BodyHandle h) {
  Eigen::Vector3f out;
  EXPECT_TRUE(test::IsOk(w.get_angular_velocities(std::span(&h, 1), std::span(&out, 1))));
  return out;
}

// A 1 m cube resting on a plane through the origin tilted by `angle` about z
// (downhill is -x along the slope), friction mu for both.
struct Slope {
  std::unique_ptr<World> world;
  BodyHandle box;
  Eigen::Vector3f downhill;
};

Slope make_slope(float angle, float mu) {
  Slope s;
  s.world = test::make_world(soft_desc());
  const Eigen::Quaternionf tilt(Eigen::AngleAxisf(angle, Eigen::Vector3f::UnitZ()));
  const Eigen::Vector3f n = tilt * Eigen::Vector3f::UnitY();
  s.downhill = tilt * -Eigen::Vector3f::UnitX();
  add_plane(*s.world, n, mu);
  ShapeId cube;
  EXPECT_TRUE(test::IsOk(s.world->shapes().add_box(Eigen::Vector3f(0.5f, 0.5f, 0.5f), &cube)));
  BodyDesc d;
  d.shape = cube;
  d.inv_mass = 1.0f;
  d.friction = mu;
  d.orientation = tilt;
  d.position = n * 0.499f;
  EXPECT_TRUE(test::IsOk(s.world->create_bodies(std::span(&d, 1), std::span(&s.box, 1))));
  return s;
}

TEST(SoftStep, BlockOnASlopeHoldsWithStaticFriction) {
  // tan 30 deg = 0.577 < 0.8: the block must not creep.
  Slope s = make_slope(std::numbers::pi_v<float> / 6.0f, 0.8f);
  for (int i = 0; i < 30; ++i) IMPACT_ASSERT_OK(s.world->step());
  const Eigen::Vector3f p0 = get(*s.world, s.box, false);
  for (int i = 0; i < 240; ++i) IMPACT_ASSERT_OK(s.world->step());
  const Eigen::Vector3f p1 = get(*s.world, s.box, false);
  std::printf("[ measure ] block on a 30 deg slope, mu 0.8: moved %.3g m in 4 s\n", (p1 - p0).norm());
  EXPECT_LT((p1 - p0).norm(), 2e-3f) << "the block crept";
  EXPECT_LT(spin(*s.world, s.box).norm(), 1e-2f);
}

TEST(SoftStep, BlockOnASlopeSlidesWithKineticFriction) {
  // a = g (sin t - mu cos t) along the slope, within 1%.
  const float t = std::numbers::pi_v<float> / 6.0f, mu = 0.3f;
  Slope s = make_slope(t, mu);
  for (int i = 0; i < 30; ++i) IMPACT_ASSERT_OK(s.world->step());
  const float v0 = get(*s.world, s.box, true).dot(s.downhill);
  const int n = 60;
  for (int i = 0; i < n; ++i) IMPACT_ASSERT_OK(s.world->step());
  const float v1 = get(*s.world, s.box, true).dot(s.downhill);
  const double a = (v1 - v0) / (n * double(kH));
  const double want = kG * (std::sin(t) - mu * std::cos(t));
  std::printf("[ measure ] block on a 30 deg slope, mu 0.3: a = %.5g m/s^2 (exact %.5g)\n", a, want);
  EXPECT_NEAR(a, want, 0.01 * want);
  EXPECT_LT(spin(*s.world, s.box).norm(), 1e-2f) << "a sliding block does not tumble";
}

TEST(SoftStep, SlidingBoxStopsWithoutTurning) {
  // Stopping distance v^2 / (2 mu g); no yaw while it slides.
  auto world = test::make_world(soft_desc());
  const float mu = 0.5f, v0 = 4.0f;
  add_plane(*world, Eigen::Vector3f::UnitY(), mu);
  ShapeId box;
  IMPACT_ASSERT_OK(world->shapes().add_box(Eigen::Vector3f(0.5f, 0.25f, 0.3f), &box));
  BodyDesc d;
  d.shape = box;
  d.inv_mass = 1.0f;
  d.friction = mu;
  d.position = Eigen::Vector3f(0.0f, 0.249f, 0.0f);
  BodyHandle h;
  IMPACT_ASSERT_OK(world->create_bodies(std::span(&d, 1), std::span(&h, 1)));
  for (int i = 0; i < 20; ++i) IMPACT_ASSERT_OK(world->step());  // settle
  const Eigen::Vector3f start = get(*world, h, false);
  const Eigen::Vector3f push(v0, 0.0f, 0.0f);
  IMPACT_ASSERT_OK(world->set_velocities(std::span(&h, 1), std::span(&push, 1)));
  for (int i = 0; i < 180; ++i) IMPACT_ASSERT_OK(world->step());
  const Eigen::Vector3f end = get(*world, h, false);
  const double want = v0 * v0 / (2.0 * mu * kG);
  std::printf("[ measure ] box sliding at 4 m/s, mu 0.5: stopped after %.4g m (exact %.4g), z drift %.2g m\n",
              end.x() - start.x(), want, end.z() - start.z());
  EXPECT_NEAR(end.x() - start.x(), want, 0.02 * want);
  EXPECT_LT(get(*world, h, true).norm(), 1e-2f);
  EXPECT_LT(std::abs(end.z() - start.z()), 1e-3f);
  Eigen::Quaternionf q;
  IMPACT_ASSERT_OK(world->get_orientations(std::span(&h, 1), std::span(&q, 1)));
  EXPECT_LT(q.angularDistance(Eigen::Quaternionf::Identity()), 2e-3f) << "the box turned while sliding";
}

TEST(SoftStep, SlidingBallEndsRollingAtFiveSevenths) {
  // A solid ball thrown along the floor without spin: friction slows it and spins
  // it up until it rolls, v = v0 - mu g t, w r = (5/2) mu g t, so v_roll = 5/7 v0.
  auto world = test::make_world(soft_desc());
  add_plane(*world, Eigen::Vector3f::UnitY(), 0.4f);
  BodyDesc d;
  d.radius = 0.5f;
  d.inv_mass = 1.0f;
  d.friction = 0.4f;
  d.position = Eigen::Vector3f(0.0f, 0.499f, 0.0f);
  BodyHandle h;
  IMPACT_ASSERT_OK(world->create_bodies(std::span(&d, 1), std::span(&h, 1)));
  for (int i = 0; i < 10; ++i) IMPACT_ASSERT_OK(world->step());
  const Eigen::Vector3f v0(7.0f, 0.0f, 0.0f);
  IMPACT_ASSERT_OK(world->set_velocities(std::span(&h, 1), std::span(&v0, 1)));
  for (int i = 0; i < 120; ++i) IMPACT_ASSERT_OK(world->step());
  const Eigen::Vector3f v = get(*world, h, true), w = spin(*world, h);
  std::printf("[ measure ] ball thrown at 7 m/s: rolls at %.5g m/s (exact 5), w r = %.5g\n", v.x(), -w.z() * 0.5f);
  EXPECT_NEAR(v.x(), 5.0f, 0.05f);
  // Rolling without slipping about the contact point, which lies the resting overlap
  // (a few mm) inside the radius: w r exceeds v by that fraction, ~0.5%.
  EXPECT_NEAR(-w.z() * 0.5f, v.x(), 0.01f * v.x()) << "rolling without slipping";
}

// A pyramid of 1 m cubes, `base` on the bottom row, in the x-y plane, on a floor.
std::vector<BodyDesc> pyramid(ShapeId cube, int base) {
  std::vector<BodyDesc> out;
  for (int row = 0; row < base; ++row)
    for (int i = 0; i < base - row; ++i) {
      BodyDesc d;
      d.shape = cube;
      d.inv_mass = 1.0f;
      d.position = Eigen::Vector3f(float(i) * 1.05f + 0.525f * float(row), 0.499f + float(row) * 0.999f, 0.0f);
      out.push_back(d);
    }
  return out;
}

TEST(SoftStep, PyramidAndStackStand) {
  for (const bool stack : {true, false}) {
    SCOPED_TRACE(stack ? "stack of 10" : "pyramid of 10 rows");
    auto world = test::make_world(soft_desc());
    add_plane(*world, Eigen::Vector3f::UnitY(), 0.6f);
    ShapeId cube;
    IMPACT_ASSERT_OK(world->shapes().add_box(Eigen::Vector3f(0.5f, 0.5f, 0.5f), &cube));
    std::vector<BodyDesc> d;
    if (stack) {
      for (int i = 0; i < 10; ++i) {
        BodyDesc b;
        b.shape = cube;
        b.inv_mass = 1.0f;
        b.position = Eigen::Vector3f(0.0f, 0.499f + float(i) * 0.999f, 0.0f);
        d.push_back(b);
      }
    } else {
      d = pyramid(cube, 10);
    }
    std::vector<BodyHandle> h(d.size());
    IMPACT_ASSERT_OK(world->create_bodies(d, h));
    for (int i = 0; i < 300; ++i) IMPACT_ASSERT_OK(world->step());
    std::vector<Eigen::Vector3f> p(h.size()), v(h.size());
    IMPACT_ASSERT_OK(world->get_positions(h, p));
    IMPACT_ASSERT_OK(world->get_velocities(h, v));
    float drift = 0.0f, sink = 0.0f, speed = 0.0f;
    for (size_t i = 0; i < h.size(); ++i) {
      const Eigen::Vector3f dp = p[i] - d[i].position;
      drift = std::max(drift, Eigen::Vector2f(dp.x(), dp.z()).norm());
      sink = std::max(sink, -dp.y());
      speed = std::max(speed, v[i].norm());
    }
    std::printf("[ measure ] %s after 5 s: largest sideways drift %.3g m, sink %.3g m, speed %.3g m/s\n",
                stack ? "stack of 10 cubes" : "pyramid of 55 cubes", drift, sink, speed);
    EXPECT_LT(drift, 0.01f) << "nothing slides or topples";
    // Each contact rests about 3 mm deep (slop plus the soft contact's give under
    // the weight above): ten layers sink a few cm at the top.
    EXPECT_LT(sink, 0.04f);
    EXPECT_LT(speed, 0.05f);
  }
}

// How a structure of 1 m cubes on a floor (friction 0.6) stands over `steps` steps at
// `substeps` substeps (automatic stiffness): the largest displacement of its top box
// (the highest at the start) and of any box at any step, and the fastest box at the end.
struct Standing {
  float top = 0.0f, any = 0.0f, speed = 0.0f;
};

Standing stand(std::vector<BodyDesc> d, uint32_t substeps, int steps) {
  WorldDesc wd = soft_desc();
  wd.solver.substeps = substeps;
  auto world = test::make_world(wd);
  add_plane(*world, Eigen::Vector3f::UnitY(), 0.6f);
  ShapeId cube;
  EXPECT_TRUE(test::IsOk(world->shapes().add_box(Eigen::Vector3f(0.5f, 0.5f, 0.5f), &cube)));
  size_t top = 0;
  for (size_t i = 0; i < d.size(); ++i) {
    d[i].shape = cube;
    d[i].friction = 0.6f;
    if (d[i].position.y() > d[top].position.y()) top = i;
  }
  std::vector<BodyHandle> h(d.size());
  EXPECT_TRUE(test::IsOk(world->create_bodies(d, h)));
  std::vector<Eigen::Vector3f> p(h.size()), v(h.size());
  Standing out;
  for (int k = 0; k < steps; ++k) {
    EXPECT_TRUE(test::IsOk(world->step()));
    EXPECT_TRUE(test::IsOk(world->get_positions(h, p)));
    for (size_t i = 0; i < h.size(); ++i) {
      const float moved = (p[i] - d[i].position).norm();
      out.any = std::max(out.any, moved);
      if (i == top) out.top = std::max(out.top, moved);
    }
  }
  EXPECT_TRUE(test::IsOk(world->get_velocities(h, v)));
  for (const Eigen::Vector3f& x : v) out.speed = std::max(out.speed, x.norm());
  return out;
}

// The stacking targets: a column of 20 boxes and a 20-row pyramid stand 10 s at
// 60 Hz, the top box never more than 1 cm from where it started (Bullet's top box
// drifts 28 cm, ODE's 9 cm). Soft contacts are springs of stiffness m_eff omega^2 per
// point, so a column buckles once its weight times its height outgrows the joints'
// rotational stiffness (a 20-box column at 4 substeps, 30 Hz, falls); the automatic
// stiffness grows with the substep rate, and these are the fewest substeps that meet
// the target. Each box starts 1 mm (the slop) into the one below.
TEST(SoftStep, ColumnOfTwentyAndPyramidOfTwentyRowsStand) {
  std::vector<BodyDesc> column(20);
  for (int i = 0; i < 20; ++i) column[i].position = Eigen::Vector3f(0.0f, 0.499f + float(i) * 0.999f, 0.0f);
  for (const bool is_column : {true, false}) {
    const uint32_t substeps = is_column ? 16 : 8;
    const Standing s = stand(is_column ? column : pyramid(ShapeId{}, 20), substeps, 600);
    std::printf("[ measure ] %s, %u substeps, 10 s: top box moved at most %.3g m, any box %.3g m, "
                "fastest at the end %.3g m/s\n",
                is_column ? "column of 20 boxes" : "pyramid of 20 rows (210 boxes)", substeps, s.top, s.any,
                s.speed);
    EXPECT_LT(s.top, 0.01f) << "the top box stays within 1 cm (the issue's target)";
    EXPECT_LT(s.any, 0.02f) << "nothing slides or topples";
    EXPECT_LT(s.speed, 0.01f) << "at rest";
  }
}

// A cube dropped onto one edge, turned 40 degrees about that edge's direction (5 off
// balance): its centre of mass is outside the edge, so it topples back onto a face
// and comes to rest there: one local axis vertical, the centre at half the edge above
// the floor (less the resting overlap), still.
TEST(SoftStep, BoxDroppedOnAnEdgeTopplesOntoAFace) {
  auto world = test::make_world(soft_desc());
  add_plane(*world, Eigen::Vector3f::UnitY(), 0.6f);
  ShapeId cube;
  IMPACT_ASSERT_OK(world->shapes().add_box(Eigen::Vector3f(0.5f, 0.5f, 0.5f), &cube));
  BodyDesc d;
  d.shape = cube;
  d.inv_mass = 1.0f;
  d.friction = 0.6f;
  const float tilt = 40.0f * std::numbers::pi_v<float> / 180.0f;
  d.orientation = Eigen::Quaternionf(Eigen::AngleAxisf(tilt, Eigen::Vector3f::UnitZ()));
  // Lowest corner height of the turned cube: 0.5 (cos t + sin t); dropped from 0.2 m above.
  d.position = Eigen::Vector3f(0.0f, 0.5f * (std::cos(tilt) + std::sin(tilt)) + 0.2f, 0.0f);
  BodyHandle h;
  IMPACT_ASSERT_OK(world->create_bodies(std::span(&d, 1), std::span(&h, 1)));
  for (int i = 0; i < 240; ++i) IMPACT_ASSERT_OK(world->step());
  Eigen::Quaternionf q;
  IMPACT_ASSERT_OK(world->get_orientations(std::span(&h, 1), std::span(&q, 1)));
  const Eigen::Matrix3f r = q.toRotationMatrix();
  float best = 0.0f;  // |cos| of the angle between the most vertical local axis and y
  for (int k = 0; k < 3; ++k) best = std::max(best, std::abs(r.col(k).y()));
  const float off_vertical = std::acos(std::min(best, 1.0f));
  const Eigen::Vector3f p = get(*world, h, false);
  const float speed = get(*world, h, true).norm(), turn = spin(*world, h).norm();
  std::printf("[ measure ] cube dropped on an edge at 40 deg: after 4 s a face down within %.3g rad, centre "
              "at %.4g m, speed %.3g m/s, spin %.3g rad/s\n",
              off_vertical, p.y(), speed, turn);
  EXPECT_LT(off_vertical, 0.01f) << "rests on a face";
  EXPECT_NEAR(p.y(), 0.5f, 0.005f);
  EXPECT_LT(speed, 0.01f);
  EXPECT_LT(turn, 0.01f);
}

TEST(SoftStep, ElasticBallKeepsItsBounceHeight) {
  // Restitution 1 on a floor of restitution 1, ten bounces from 2 m. The restitution
  // pass restores the relative speed the contact had at the start of its step, which
  // is up to g dt short of the speed at impact (contacts are found after the bodies
  // overlap; speculative contacts, issue 41, remove that): measured ~1% of the
  // height per bounce.
  auto world = test::make_world(soft_desc());
  add_plane(*world, Eigen::Vector3f::UnitY(), 0.0f, 1.0f);
  BodyDesc d;
  d.radius = 0.25f;
  d.inv_mass = 1.0f;
  d.friction = 0.0f;
  d.restitution = 1.0f;
  d.position = Eigen::Vector3f(0.0f, 2.0f, 0.0f);
  BodyHandle h;
  IMPACT_ASSERT_OK(world->create_bodies(std::span(&d, 1), std::span(&h, 1)));
  float apex = 0.0f, last_vy = 0.0f;
  int bounces = 0;
  for (int i = 0; i < 60 * 12 && bounces < 10; ++i) {
    IMPACT_ASSERT_OK(world->step());
    const float vy = get(*world, h, true).y(), y = get(*world, h, false).y();
    if (last_vy > 0.0f && vy <= 0.0f) {
      ++bounces;
      apex = y;
    }
    last_vy = vy;
  }
  std::printf("[ measure ] elastic ball from 2 m: apex after %d bounces %.4g m\n", bounces, apex);
  EXPECT_GE(bounces, 10);
  EXPECT_GT(apex, 2.0f * std::pow(0.985f, float(bounces)));
  EXPECT_LT(apex, 2.0f) << "no energy from nowhere";
}

TEST(SoftStep, PyramidIsBitIdenticalForAnyThreadCount) {
  auto run = [](const test::ExecCase& c) {
    WorldDesc wd = soft_desc();
    wd.backend = c.backend;
    wd.threads = c.threads;
    auto world = test::make_world(wd);
    add_plane(*world, Eigen::Vector3f::UnitY(), 0.6f);
    ShapeId cube;
    EXPECT_TRUE(test::IsOk(world->shapes().add_box(Eigen::Vector3f(0.5f, 0.5f, 0.5f), &cube)));
    std::vector<BodyDesc> d = pyramid(cube, 20);
    // A second pyramid of spheres behind it: sphere contacts and friction too.
    for (int i = 0; i < 100; ++i) {
      BodyDesc b;
      b.radius = 0.4f;
      b.inv_mass = 1.0f;
      b.position = Eigen::Vector3f(float(i % 10) * 0.81f, 0.41f + float(i / 10) * 0.9f, 3.0f);
      b.velocity = Eigen::Vector3f(0.0f, 0.0f, float(i % 3) - 1.0f);
      d.push_back(b);
    }
    std::vector<BodyHandle> h(d.size());
    EXPECT_TRUE(test::IsOk(world->create_bodies(d, h)));
    for (int i = 0; i < 200; ++i) EXPECT_TRUE(test::IsOk(world->step()));
    return world->state_hash();
  };
  test::expect_same_for_every_exec_case(run);
}

// Issue 40's determinism check: a 20-row pyramid of boxes (210), 1000 steps, the same
// state hash serial and on TBB and OpenMP at 2, 3 and 8 threads (fewer steps under the
// sanitizers). The 200-step test above covers every backend and thread count.
TEST(SoftStep, PyramidHashOverAThousandStepsIsTheSameForAnyThreadCount) {
  const int steps = test::kSanitized ? 200 : 1000;
  auto run = [&](Backend backend, uint32_t threads) {
    WorldDesc wd = soft_desc();
    wd.backend = backend;
    wd.threads = threads;
    auto world = test::make_world(wd);
    add_plane(*world, Eigen::Vector3f::UnitY(), 0.6f);
    ShapeId cube;
    EXPECT_TRUE(test::IsOk(world->shapes().add_box(Eigen::Vector3f(0.5f, 0.5f, 0.5f), &cube)));
    const std::vector<BodyDesc> d = pyramid(cube, 20);
    std::vector<BodyHandle> h(d.size());
    EXPECT_TRUE(test::IsOk(world->create_bodies(d, h)));
    for (int i = 0; i < steps; ++i) EXPECT_TRUE(test::IsOk(world->step()));
    return world->state_hash();
  };
  const uint64_t ref = run(Backend::kSerial, 1);
  for (Backend b : {Backend::kTbb, Backend::kOpenMP}) {
    if (!backend_available(b)) continue;
    for (uint32_t t : {2u, 3u, 8u}) EXPECT_EQ(run(b, t), ref) << to_string(b) << " with " << t << " threads";
  }
}

}  // namespace
}  // namespace impact
