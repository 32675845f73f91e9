// Rigid-body motion through the World API: orientation and angular velocity, the
// inertia of shapes, forces, torques and impulses, damping and gravity scale,
// kinematic bodies, and the validation of every new field. References: closed forms
// (box and ball inertia, the integrator's exact per-step rotation), and Euler's
// equations of a torque-free body integrated by RK4 in double precision.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

#include "impact/world.h"
#include "support/test_support.h"

namespace impact {
namespace {

constexpr float kH = 1.0f / 60.0f;

// Moments of inertia of a solid box of half extents e and mass m about its axes.
Eigen::Vector3d box_moments(const Eigen::Vector3f& e, double m) {
  const Eigen::Vector3d d = e.cast<double>();
  return m / 3.0 * Eigen::Vector3d(d.y() * d.y() + d.z() * d.z(), d.x() * d.x() + d.z() * d.z(),
                                   d.x() * d.x() + d.y() * d.y());
}

struct OneBody {
  std::unique_ptr<World> world;
  BodyHandle h;
};

OneBody make_body(const WorldDesc& wd, const Eigen::Vector3f& half, BodyDesc d) {
  OneBody b;
  b.world = test::make_world(wd);
  ShapeId box;
  EXPECT_TRUE(test::IsOk(b.world->shapes().add_box(half, &box)));
  d.shape = box;
  EXPECT_TRUE(test::IsOk(b.world->create_bodies(std::span(&d, 1), std::span(&b.h, 1))));
  return b;
}

Eigen::Vector3f angular_velocity(const World& w, BodyHandle h) {
  Eigen::Vector3f out;
  EXPECT_TRUE(test::IsOk(w.get_angular_velocities(std::span(&h, 1), std::span(&out, 1))));
  return out;
}

Eigen::Quaternionf orientation(const World& w, BodyHandle h) {
  Eigen::Quaternionf out;
  EXPECT_TRUE(test::IsOk(w.get_orientations(std::span(&h, 1), std::span(&out, 1))));
  return out;
}

Eigen::Vector3f velocity(const World& w, BodyHandle h) {
  Eigen::Vector3f out;
  EXPECT_TRUE(test::IsOk(w.get_velocities(std::span(&h, 1), std::span(&out, 1))));
  return out;
}

Eigen::Vector3f position(const World& w, BodyHandle h) {
  Eigen::Vector3f out;
  EXPECT_TRUE(test::IsOk(w.get_positions(std::span(&h, 1), std::span(&out, 1))));
  return out;
}

// Torque-free Euler equations in the principal frame, I w' = (I w) x w, by RK4.
Eigen::Vector3d euler_rate(const Eigen::Vector3d& I, const Eigen::Vector3d& w) {
  return (I.cwiseProduct(w)).cross(w).cwiseQuotient(I);
}
Eigen::Vector3d rk4(const Eigen::Vector3d& I, const Eigen::Vector3d& w, double h) {
  const Eigen::Vector3d k1 = euler_rate(I, w), k2 = euler_rate(I, w + 0.5 * h * k1),
                        k3 = euler_rate(I, w + 0.5 * h * k2), k4 = euler_rate(I, w + h * k3);
  return w + h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
}

TEST(RigidBody, SpinAboutAPrincipalAxisTurnsByTheIntegratorsExactAngle) {
  // q' = normalise(q + h/2 (w, 0) q) turns by 2 atan(h |w| / 2) a substep about w:
  // the scheme's exact answer, which the float state must track to rounding.
  BodyDesc d;
  d.inv_mass = 1.0f;
  d.angular_velocity = Eigen::Vector3f(0.0f, 3.0f, 0.0f);
  OneBody b = make_body(test::zero_gravity_desc(), Eigen::Vector3f(0.5f, 0.2f, 0.1f), d);
  const int steps = 120;
  for (int i = 0; i < steps; ++i) IMPACT_ASSERT_OK(b.world->step());
  const Eigen::Vector3f w = angular_velocity(*b.world, b.h);
  EXPECT_NEAR(w.y(), 3.0f, 1e-5f);
  EXPECT_NEAR(w.x(), 0.0f, 1e-5f);
  EXPECT_NEAR(w.z(), 0.0f, 1e-5f);
  const double sub = SolverDesc{}.substeps;
  const double angle = steps * sub * 2.0 * std::atan(kH / sub * 3.0 / 2.0);
  const Eigen::Quaterniond want(Eigen::AngleAxisd(angle, Eigen::Vector3d::UnitY()));
  const Eigen::Quaterniond got = orientation(*b.world, b.h).cast<double>();
  EXPECT_LT(got.angularDistance(want), 2e-4) << "angle " << angle;
  // The exact rigid rotation differs only by the scheme's error, (h w)^3 / 12 a step.
  EXPECT_LT(got.angularDistance(Eigen::Quaterniond(Eigen::AngleAxisd(6.0, Eigen::Vector3d::UnitY()))), 2e-3);
  EXPECT_EQ(position(*b.world, b.h), Eigen::Vector3f::Zero()) << "the centre of a box is its centre of mass";
}

TEST(RigidBody, FreeAsymmetricBodyKeepsItsAngularMomentum) {
  // Torque-free: the world angular momentum L = R I R^T w is constant. The soft step
  // re-derives w from L at each substep's new orientation, so L is kept to rounding
  // (a thin box tumbling at 2.3 rad/s for 10 s: the bar is 0.1%), and the
  // energy, which that scheme does not hold exactly, within 0.1% too. Without the
  // gyroscopic term w stays fixed in the world while the body turns: L wanders.
  const Eigen::Vector3f half(0.6f, 0.3f, 0.1f);
  const double m = 2.0;
  const Eigen::Vector3d I = box_moments(half, m);
  auto run = [&](bool gyroscopic, double* drift, double* energy_ratio) {
    WorldDesc wd = test::zero_gravity_desc();
    wd.gyroscopic = gyroscopic;
    BodyDesc d;
    d.inv_mass = static_cast<float>(1.0 / m);
    d.angular_velocity = Eigen::Vector3f(1.0f, 2.0f, 0.5f);
    OneBody b = make_body(wd, half, d);
    auto momentum = [&](double* energy) {
      const Eigen::Matrix3d r = orientation(*b.world, b.h).cast<double>().toRotationMatrix();
      const Eigen::Vector3d w = angular_velocity(*b.world, b.h).cast<double>();
      const Eigen::Vector3d wb = r.transpose() * w;
      *energy = 0.5 * wb.dot(I.cwiseProduct(wb));
      return Eigen::Vector3d(r * I.cwiseProduct(wb));
    };
    double e0 = 0, e = 0;
    const Eigen::Vector3d l0 = momentum(&e0);
    *drift = 0.0;
    for (int i = 0; i < 600; ++i) {
      IMPACT_ASSERT_OK(b.world->step());
      *drift = std::max(*drift, (momentum(&e) - l0).norm() / l0.norm());
      if (gyroscopic) {
        EXPECT_NEAR(e / e0, 1.0, 1e-3) << "step " << i;
      }
    }
    *energy_ratio = e / e0;
  };
  double drift_on = 0, drift_off = 0, energy_on = 0, energy_off = 0;
  run(true, &drift_on, &energy_on);
  run(false, &drift_off, &energy_off);
  std::printf("[ measure ] free body 10 s: L drift %.3g (gyroscopic) / %.3g (off), energy ratio %.6f / %.6f\n",
              drift_on, drift_off, energy_on, energy_off);
  EXPECT_LT(drift_on, 1e-3) << "gyroscopic on";
  EXPECT_GT(drift_off, 0.1) << "gyroscopic off: L is not conserved";
}

TEST(RigidBody, IntermediateAxisSpinFlipsLikeEulersEquations) {
  // Dzhanibekov: a spin about the intermediate principal axis is unstable; the body
  // flips over periodically. The time of the first flip (the intermediate component of
  // the body-frame angular velocity changes sign) matches RK4 on Euler's equations.
  const Eigen::Vector3f half(0.4f, 0.2f, 0.05f);  // moments x < y < z: y is intermediate
  const double m = 1.0;
  const Eigen::Vector3d I = box_moments(half, m);
  const Eigen::Vector3d w0(0.02, 6.0, 0.02);
  double t_ref = -1.0;
  {
    Eigen::Vector3d w = w0;
    const double h = 1e-4;
    for (int i = 1; i < 400000 && t_ref < 0; ++i) {
      w = rk4(I, w, h);
      if (w.y() < 0.0) t_ref = i * h;
    }
  }
  ASSERT_GT(t_ref, 0.0);
  BodyDesc d;
  d.inv_mass = static_cast<float>(1.0 / m);
  d.angular_velocity = w0.cast<float>();
  OneBody b = make_body(test::zero_gravity_desc(), half, d);
  double t_flip = -1.0;
  for (int i = 1; i <= static_cast<int>(3.0 * t_ref / kH) && t_flip < 0; ++i) {
    IMPACT_ASSERT_OK(b.world->step());
    const Eigen::Vector3f wb = orientation(*b.world, b.h).conjugate() * angular_velocity(*b.world, b.h);
    if (wb.y() < 0.0f) t_flip = i * double(kH);
  }
  ASSERT_GT(t_flip, 0.0) << "no flip within 3x the reference time " << t_ref << " s";
  EXPECT_NEAR(t_flip, t_ref, 0.15 * t_ref);
  // A spin about the largest axis is stable: no flip.
  d.angular_velocity = Eigen::Vector3f(0.02f, 0.02f, 6.0f);
  OneBody s = make_body(test::zero_gravity_desc(), half, d);
  for (int i = 0; i < static_cast<int>(3.0 * t_ref / kH); ++i) {
    IMPACT_ASSERT_OK(s.world->step());
    const Eigen::Vector3f wb = orientation(*s.world, s.h).conjugate() * angular_velocity(*s.world, s.h);
    ASSERT_GT(wb.z(), 5.9f) << "step " << i;
  }
}

TEST(RigidBody, ForcesAndTorquesActForOneStep) {
  // A solid ball, I = 2/5 m r^2: dv = F/m h, dw = T/I h, and nothing on the next step.
  auto world = test::make_world(test::zero_gravity_desc());
  BodyDesc d;
  d.radius = 0.5f;
  d.inv_mass = 0.5f;
  BodyHandle h;
  IMPACT_ASSERT_OK(world->create_bodies(std::span(&d, 1), std::span(&h, 1)));
  const double I = 0.4 * 2.0 * 0.25;
  const Eigen::Vector3f f(4.0f, 0.0f, 0.0f), t(0.0f, 0.0f, 1.0f);
  IMPACT_ASSERT_OK(world->apply_forces(std::span(&h, 1), std::span(&f, 1)));
  IMPACT_ASSERT_OK(world->apply_torques(std::span(&h, 1), std::span(&t, 1)));
  IMPACT_ASSERT_OK(world->step());
  EXPECT_NEAR(velocity(*world, h).x(), 2.0 * kH, 1e-7);
  EXPECT_NEAR(angular_velocity(*world, h).z(), kH / I, 1e-6);
  IMPACT_ASSERT_OK(world->step());
  EXPECT_NEAR(velocity(*world, h).x(), 2.0 * kH, 1e-7) << "forces last one step";
  EXPECT_NEAR(angular_velocity(*world, h).z(), kH / I, 1e-6);
  // A force at a point off the centre: the same push plus the torque r x F.
  const Eigen::Vector3f up(0.0f, 2.0f, 0.0f), at = position(*world, h) + Eigen::Vector3f(0.5f, 0.0f, 0.0f);
  const Eigen::Vector3f v0 = velocity(*world, h), w0 = angular_velocity(*world, h);
  IMPACT_ASSERT_OK(world->apply_forces_at(std::span(&h, 1), std::span(&up, 1), std::span(&at, 1)));
  IMPACT_ASSERT_OK(world->step());
  EXPECT_NEAR(velocity(*world, h).y() - v0.y(), 1.0 * kH, 1e-6);
  EXPECT_NEAR(angular_velocity(*world, h).z() - w0.z(), 0.5 * 2.0 / I * kH, 1e-5);
}

TEST(RigidBody, ImpulseAtAPointOfATurnedBox) {
  // v += J/m, w += R I^-1 R^T (r x J), with the box's closed-form inertia in double.
  const Eigen::Vector3f half(0.5f, 0.25f, 0.125f);
  const double m = 3.0;
  BodyDesc d;
  d.inv_mass = static_cast<float>(1.0 / m);
  d.position = Eigen::Vector3f(1.0f, 2.0f, -3.0f);
  d.orientation = Eigen::Quaternionf(Eigen::AngleAxisf(0.7f, Eigen::Vector3f(1, 2, 3).normalized()));
  d.friction = 0.0f;
  OneBody b = make_body(test::zero_gravity_desc(), half, d);
  const Eigen::Vector3f j(0.3f, -1.0f, 2.0f), at = d.position + Eigen::Vector3f(0.4f, 0.1f, -0.2f);
  IMPACT_ASSERT_OK(b.world->apply_impulses(std::span(&b.h, 1), std::span(&j, 1), std::span(&at, 1)));
  const Eigen::Matrix3d r = d.orientation.cast<double>().toRotationMatrix();
  const Eigen::Vector3d arm = (at - d.position).cast<double>();
  const Eigen::Vector3d want_w =
      r * box_moments(half, m).cwiseInverse().asDiagonal() * r.transpose() * arm.cross(j.cast<double>());
  const Eigen::Vector3d got_w = angular_velocity(*b.world, b.h).cast<double>();
  EXPECT_LT((got_w - want_w).norm(), 1e-5 * want_w.norm()) << got_w.transpose() << " vs " << want_w.transpose();
  EXPECT_LT((velocity(*b.world, b.h).cast<double>() - j.cast<double>() / m).norm(), 1e-6);
}

TEST(RigidBody, OffCentreHullTurnsAboutItsCentreOfMass) {
  // A unit cube hull with its origin at a corner: the centre of mass is (0.5, 0.5, 0.5)
  // in the shape frame. A force there turns nothing; a spin keeps the centre fixed
  // while the body origin circles it.
  auto world = test::make_world(test::zero_gravity_desc());
  std::vector<Eigen::Vector3f> corners;
  for (int i = 0; i < 8; ++i) corners.emplace_back(float(i & 1), float((i >> 1) & 1), float((i >> 2) & 1));
  ShapeId hull;
  IMPACT_ASSERT_OK(world->shapes().add_convex_hull(corners, &hull));
  BodyDesc d;
  d.shape = hull;
  d.inv_mass = 1.0f;
  BodyHandle h;
  IMPACT_ASSERT_OK(world->create_bodies(std::span(&d, 1), std::span(&h, 1)));
  const Eigen::Vector3f com(0.5f, 0.5f, 0.5f), f(0.0f, 0.0f, 6.0f);
  IMPACT_ASSERT_OK(world->apply_forces_at(std::span(&h, 1), std::span(&f, 1), std::span(&com, 1)));
  IMPACT_ASSERT_OK(world->step());
  EXPECT_LT(angular_velocity(*world, h).norm(), 1e-6f);
  EXPECT_NEAR(velocity(*world, h).z(), 6.0f * kH, 1e-6f);
  const Eigen::Vector3f w(0.0f, 0.0f, 2.0f);
  const Eigen::Vector3f zero = Eigen::Vector3f::Zero();
  IMPACT_ASSERT_OK(world->set_velocities(std::span(&h, 1), std::span(&zero, 1)));
  IMPACT_ASSERT_OK(world->set_angular_velocities(std::span(&h, 1), std::span(&w, 1)));
  const Eigen::Vector3f centre = position(*world, h) + orientation(*world, h) * com;
  for (int i = 0; i < 90; ++i) IMPACT_ASSERT_OK(world->step());
  const Eigen::Vector3f centre1 = position(*world, h) + orientation(*world, h) * com;
  EXPECT_LT((centre1 - centre).norm(), 1e-5f);
  EXPECT_GT((position(*world, h) - centre).norm(), 0.5f) << "the origin moved off its start";
}

TEST(RigidBody, DampingAndGravityScale) {
  WorldDesc wd;
  wd.gravity = Eigen::Vector3f(0.0f, -10.0f, 0.0f);
  auto world = test::make_world(wd);
  std::vector<BodyDesc> d(3);
  for (size_t i = 0; i < d.size(); ++i) {
    d[i].position = Eigen::Vector3f(5.0f * float(i), 0.0f, 0.0f);
    d[i].inv_mass = 1.0f;
  }
  d[0].linear_damping = 2.0f;
  d[0].gravity_scale = 0.0f;
  d[0].velocity = Eigen::Vector3f(10.0f, 0.0f, 0.0f);
  d[0].angular_damping = 3.0f;
  d[0].angular_velocity = Eigen::Vector3f(0.0f, 4.0f, 0.0f);
  d[1].gravity_scale = 2.0f;
  d[2].gravity_scale = -1.0f;
  std::vector<BodyHandle> h(d.size());
  IMPACT_ASSERT_OK(world->create_bodies(d, h));
  const int n = 30;
  for (int i = 0; i < n; ++i) IMPACT_ASSERT_OK(world->step());
  EXPECT_NEAR(velocity(*world, h[0]).x(), 10.0 * std::pow(1.0 + 2.0 * kH, -n), 1e-4);
  EXPECT_EQ(velocity(*world, h[0]).y(), 0.0f);
  EXPECT_NEAR(angular_velocity(*world, h[0]).y(), 4.0 * std::pow(1.0 + 3.0 * kH, -n), 1e-4);
  EXPECT_NEAR(velocity(*world, h[1]).y(), -20.0 * n * double(kH), 1e-4);
  EXPECT_NEAR(velocity(*world, h[2]).y(), 10.0 * n * double(kH), 1e-4);
}

TEST(RigidBody, KinematicPlatformCarriesARestingBall) {
  // inv_mass 0 with a velocity: a kinematic body. It moves exactly by its velocity,
  // contacts never slow it, and a ball resting on it rides up with it.
  WorldDesc wd;
  auto world = test::make_world(wd);
  ShapeId slab;
  IMPACT_ASSERT_OK(world->shapes().add_box(Eigen::Vector3f(2.0f, 0.1f, 2.0f), &slab));
  std::vector<BodyDesc> d(2);
  d[0].shape = slab;
  d[0].inv_mass = 0.0f;
  d[0].velocity = Eigen::Vector3f(0.0f, 1.0f, 0.0f);
  d[0].angular_velocity = Eigen::Vector3f(0.0f, 0.5f, 0.0f);
  d[1].radius = 0.5f;
  d[1].inv_mass = 1.0f;
  d[1].position = Eigen::Vector3f(0.0f, 0.6f, 0.0f);
  std::vector<BodyHandle> h(2);
  IMPACT_ASSERT_OK(world->create_bodies(d, h));
  const int n = 60;
  for (int i = 0; i < n; ++i) IMPACT_ASSERT_OK(world->step());
  EXPECT_NEAR(position(*world, h[0]).y(), 1.0f, 1e-5f);
  EXPECT_EQ(velocity(*world, h[0]), d[0].velocity) << "contacts do not change a kinematic body";
  EXPECT_EQ(angular_velocity(*world, h[0]), d[0].angular_velocity);
  const Eigen::Quaterniond want(Eigen::AngleAxisd(n * 2.0 * std::atan(kH * 0.5 / 2.0), Eigen::Vector3d::UnitY()));
  EXPECT_LT(orientation(*world, h[0]).cast<double>().angularDistance(want), 1e-4);
  const float gap = position(*world, h[1]).y() - position(*world, h[0]).y();
  EXPECT_NEAR(gap, 0.6f, 0.02f) << "the ball rides on the platform";
  EXPECT_NEAR(velocity(*world, h[1]).y(), 1.0f, 0.1f);
}

TEST(RigidBody, FrictionlessSpheresPayNothingForRotation) {
  // A world of frictionless plain spheres never switches the rotation fields on; a
  // sphere with friction (it can roll) does.
  auto world = test::make_world(WorldDesc{});
  std::vector<BodyDesc> d(2);
  d[1].position = Eigen::Vector3f(3.0f, 0.0f, 0.0f);
  for (BodyDesc& b : d) {
    b.inv_mass = 1.0f;
    b.friction = 0.0f;
  }
  std::vector<BodyHandle> h(2);
  IMPACT_ASSERT_OK(world->create_bodies(d, h));
  IMPACT_ASSERT_OK(world->step());
  EXPECT_TRUE(world->bodies().wx.empty());
  EXPECT_TRUE(world->bodies().qx.empty());
  EXPECT_EQ(angular_velocity(*world, h[0]), Eigen::Vector3f::Zero());
  BodyDesc rough;
  rough.inv_mass = 1.0f;
  rough.position = Eigen::Vector3f(6.0f, 0.0f, 0.0f);
  BodyHandle r;
  IMPACT_ASSERT_OK(world->create_bodies(std::span(&rough, 1), std::span(&r, 1)));
  EXPECT_EQ(world->bodies().wx.size(), 3u);
  EXPECT_EQ(world->bodies().friction[2], 0.6f) << "the documented default";
}

TEST(RigidBody, RejectsInvalidMotionFields) {
  auto world = test::make_world(WorldDesc{});
  auto create = [&](auto edit) {
    BodyDesc d;
    d.inv_mass = 1.0f;
    edit(d);
    BodyHandle h;
    return world->create_bodies(std::span(&d, 1), std::span(&h, 1));
  };
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  EXPECT_TRUE(test::IsError(create([&](BodyDesc& d) { d.orientation.coeffs() << nan, 0, 0, 1; }),
                            StatusCode::kInvalidArgument, {"body 0", "orientation"}))
      << "a plain sphere's orientation is checked too";
  EXPECT_TRUE(test::IsError(create([](BodyDesc& d) { d.orientation.coeffs() << 0, 0, 0, 2; }),
                            StatusCode::kInvalidArgument, {"unit quaternion"}));
  EXPECT_TRUE(test::IsError(create([&](BodyDesc& d) { d.angular_velocity.x() = inf; }),
                            StatusCode::kInvalidArgument, {"angular_velocity"}));
  EXPECT_TRUE(test::IsError(create([](BodyDesc& d) { d.friction = -0.1f; }), StatusCode::kInvalidArgument,
                            {"friction", ">= 0"}));
  EXPECT_TRUE(test::IsError(create([&](BodyDesc& d) { d.rolling_resistance = nan; }),
                            StatusCode::kInvalidArgument, {"rolling_resistance"}));
  EXPECT_TRUE(test::IsError(create([](BodyDesc& d) { d.linear_damping = -1.0f; }),
                            StatusCode::kInvalidArgument, {"linear_damping"}));
  EXPECT_TRUE(test::IsError(create([&](BodyDesc& d) { d.angular_damping = inf; }),
                            StatusCode::kInvalidArgument, {"angular_damping"}));
  EXPECT_TRUE(test::IsError(create([&](BodyDesc& d) { d.gravity_scale = nan; }), StatusCode::kInvalidArgument,
                            {"gravity_scale"}));
  EXPECT_EQ(world->body_count(), 0u) << "rejected batches create nothing";

  std::vector<BodyDesc> d(2);
  d[0].inv_mass = 1.0f;
  d[0].fixed_rotation = true;
  d[1].inv_mass = 1.0f;
  d[1].friction = 0.0f;  // neither body can rotate yet: no rigid fields
  d[1].position = Eigen::Vector3f(3.0f, 0.0f, 0.0f);
  std::vector<BodyHandle> h(2);
  IMPACT_ASSERT_OK(world->create_bodies(d, h));
  const test::WorldSnapshot before = test::snapshot(*world);
  const std::vector<Eigen::Vector3f> spin = {Eigen::Vector3f::Zero(), Eigen::Vector3f(0, 1, 0)};
  const std::vector<Eigen::Vector3f> bad = {Eigen::Vector3f(0, 0, 0), Eigen::Vector3f(0, nan, 0)};
  EXPECT_TRUE(test::IsError(world->set_angular_velocities(h, std::vector<Eigen::Vector3f>{{0, 1, 0}, {0, 0, 0}}),
                            StatusCode::kInvalidArgument, {"body 0", "fixed_rotation"}));
  EXPECT_TRUE(test::IsError(world->set_angular_velocities(h, bad), StatusCode::kInvalidArgument,
                            {"body 1", "finite"}));
  EXPECT_TRUE(test::IsError(world->apply_forces(h, bad), StatusCode::kInvalidArgument, {"body 1", "force"}));
  EXPECT_TRUE(test::IsError(world->apply_torques(h, bad), StatusCode::kInvalidArgument, {"torque"}));
  EXPECT_TRUE(test::IsError(world->apply_impulses(h, spin, bad), StatusCode::kInvalidArgument, {"point"}));
  EXPECT_TRUE(test::IsError(world->apply_forces_at(h, spin, std::span(spin).first(1)), StatusCode::kSizeMismatch));
  const std::vector<Eigen::Quaternionf> q = {Eigen::Quaternionf::Identity(), Eigen::Quaternionf(0, 0, 0, 0)};
  EXPECT_TRUE(test::IsError(world->set_orientations(h, q), StatusCode::kInvalidArgument, {"body 1", "orientation"}));
  const BodyHandle stale{h[1].index, h[1].generation + 1};
  EXPECT_TRUE(test::IsError(world->apply_impulses(std::span(&stale, 1), std::span(spin).first(1),
                                                  std::span(spin).first(1)),
                            StatusCode::kStaleHandle));
  EXPECT_EQ(test::snapshot(*world), before) << "rejected calls change nothing";
  EXPECT_TRUE(world->bodies().wx.empty()) << "and switch nothing on";
}

TEST(RigidBody, TumblingBoxesAreBitIdenticalForAnyThreadCount) {
  // 512 spinning boxes dropped on a floor and each other: the rigid integrator is a
  // per-body pass, so the state is the same bytes for every backend and thread count.
  auto run = [](const test::ExecCase& c) {
    WorldDesc wd;
    wd.backend = c.backend;
    wd.threads = c.threads;
    auto world = test::make_world(wd);
    ShapeId box;
    EXPECT_TRUE(test::IsOk(world->shapes().add_box(Eigen::Vector3f(0.3f, 0.2f, 0.1f), &box)));
    std::vector<BodyDesc> d(512);
    for (size_t i = 0; i < d.size(); ++i) {
      d[i].shape = box;
      d[i].inv_mass = 1.0f;
      d[i].position = Eigen::Vector3f(float(i % 8) * 0.8f, 0.5f + float(i / 64) * 0.7f, float((i / 8) % 8) * 0.8f);
      d[i].angular_velocity = Eigen::Vector3f(float(i % 5) - 2.0f, float(i % 3), float(i % 7) - 3.0f);
    }
    std::vector<BodyHandle> h(d.size());
    EXPECT_TRUE(test::IsOk(world->create_bodies(d, h)));
    PlaneDesc floor;
    PlaneHandle fh;
    EXPECT_TRUE(test::IsOk(world->create_planes(std::span(&floor, 1), std::span(&fh, 1))));
    for (int i = 0; i < 120; ++i) EXPECT_TRUE(test::IsOk(world->step()));
    return world->state_hash();
  };
  test::expect_same_for_every_exec_case(run);
}

}  // namespace
}  // namespace impact
