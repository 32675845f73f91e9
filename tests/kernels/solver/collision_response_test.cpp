// Collision response through World, for each SolverKind (the soft step,
// kernels/solver/soft_contact.*, and Jacobi, kernels/solver/contact_solver.*): two
// frictionless spheres (or a sphere and a plane) without gravity, solver defaults, just overlapping
// and approaching faster than solver.restitution_threshold; one step; read the
// velocities. A step detects contacts on the positions it starts from (after
// the gravity update of velocities), so bodies start at the overlapping pose.
//
// Analytic references (1D along the contact normal n, masses m = 1/inv_mass,
// restitution e = max(e_a, e_b) as contact_solver.h documents):
//   v_n' relative = -e v_n relative; momentum conserved; tangential parts kept.
//   e = 1, equal masses: normal velocities swap.   e = 1, static b: v_n flips.
//   e = 0, equal masses: both take the average.    e = 0, static b: v_n -> 0.
// Exact special cases are compared to a few ulps; random 3D impacts to 1e-5.
#include <gtest/gtest.h>

#include <cfloat>
#include <cmath>
#include <random>
#include <vector>

#include "impact/impact.h"
#include "support/test_support.h"

namespace impact {
namespace {

constexpr uint32_t kUlps = 4;

// The solver the running test uses (set by the fixture).
SolverKind g_kind = SolverKind::kSoftStep;

class CollisionResponse : public ::testing::TestWithParam<SolverKind> {
 protected:
  void SetUp() override { g_kind = GetParam(); }
};

struct Outcome {
  Eigen::Vector3f va, vb;
  Eigen::Vector3f normal;  // of the single contact, a -> b
  float impulse = 0;
  size_t contacts = 0;
};

// a and b are given at their detection-time (= starting) positions.
Outcome collide(BodyDesc a, BodyDesc b, const std::vector<PlaneDesc>& planes = {},
                const SolverDesc& solver = SolverDesc{}) {
  WorldDesc d = test::zero_gravity_desc();
  d.solver = solver;
  d.solver.kind = g_kind;
  auto world = test::make_world(d);
  Outcome o;
  if (!world) return o;
  std::vector<PlaneHandle> ph(planes.size());
  std::vector<PlaneDesc> frictionless = planes;
  for (PlaneDesc& p : frictionless) p.friction = 0.0f;
  EXPECT_TRUE(test::IsOk(world->create_planes(frictionless, ph)));
  std::vector<BodyDesc> descs{a};
  if (planes.empty()) descs.push_back(b);
  std::vector<BodyHandle> h(descs.size());
  EXPECT_TRUE(test::IsOk(world->create_bodies(descs, h)));
  EXPECT_TRUE(test::IsOk(world->step()));
  std::vector<Eigen::Vector3f> v(h.size());
  EXPECT_TRUE(test::IsOk(world->get_velocities(h, v)));
  o.va = v[0];
  if (v.size() > 1) o.vb = v[1];
  const ContactArrays c = world->contacts();
  o.contacts = c.size();
  if (c.size() == 1) {
    o.normal = {c.normal_x[0], c.normal_y[0], c.normal_z[0]};
    o.impulse = c.impulse[0];
  }
  return o;
}

// got == want to kUlps, or |got| tiny when want is zero (scale: the speeds involved).
::testing::AssertionResult Close(float got, double want, double scale) {
  if (want == 0.0) {
    if (std::abs(got) <= kUlps * FLT_EPSILON * scale) return ::testing::AssertionSuccess();
  } else if (test::ulp_distance(got, static_cast<float>(want)) <= kUlps) {
    return ::testing::AssertionSuccess();
  }
  return ::testing::AssertionFailure() << "got " << got << ", want " << want << " ("
                                       << test::ulp_distance(got, static_cast<float>(want)) << " ulps)";
}

void expect_vec(const Eigen::Vector3f& got, const Eigen::Vector3d& want, double scale, const char* what) {
  EXPECT_TRUE(Close(got.x(), want.x(), scale)) << what << ".x";
  EXPECT_TRUE(Close(got.y(), want.y(), scale)) << what << ".y";
  EXPECT_TRUE(Close(got.z(), want.z(), scale)) << what << ".z";
}

BodyDesc sphere(Eigen::Vector3f p, Eigen::Vector3f v, float restitution, float inv_mass = 1.0f) {
  BodyDesc d;
  d.position = p;
  d.velocity = v;
  d.restitution = restitution;
  d.inv_mass = inv_mass;
  d.radius = 0.5f;
  d.friction = 0.0f;  // the seeds' frictionless impulse
  return d;
}

// Unit axis k scaled by s.
Eigen::Vector3f axis(int k, float s) {
  Eigen::Vector3f v = Eigen::Vector3f::Zero();
  v[k] = s;
  return v;
}

TEST_P(CollisionResponse, ElasticEqualMassesSwapVelocities) {
  for (int k = 0; k < 3; ++k) {
    SCOPED_TRACE(k);
    const Outcome o =
        collide(sphere(axis(k, -0.495f), axis(k, 5.0f), 1.0f), sphere(axis(k, 0.495f), axis(k, -2.0f), 1.0f));
    ASSERT_EQ(o.contacts, 1u);
    expect_vec(o.va, axis(k, -2.0f).cast<double>(), 5.0, "va");
    expect_vec(o.vb, axis(k, 5.0f).cast<double>(), 5.0, "vb");
    // Impulse = m_eff (1 + e) |v_n| = 0.5 * 2 * 7.
    EXPECT_TRUE(Close(o.impulse, 7.0, 7.0));
  }
}

TEST_P(CollisionResponse, ElasticAgainstStaticFlipsVelocity) {
  // Dynamic first (slot 0) and static first: both orders of the pair.
  Outcome o = collide(sphere({-0.495f, 0, 0}, {3.0f, 0.0f, 0.75f}, 1.0f),
                      sphere({0.495f, 0, 0}, {0, 0, 0}, 1.0f, 0.0f));
  ASSERT_EQ(o.contacts, 1u);
  expect_vec(o.va, {-3.0, 0.0, 0.75}, 3.0, "va");
  expect_vec(o.vb, {0, 0, 0}, 3.0, "static vb");
  o = collide(sphere({0, 0.495f, 0}, {0, 0, 0}, 1.0f, 0.0f), sphere({0, -0.495f, 0}, {0.5f, 2.0f, 0}, 1.0f));
  ASSERT_EQ(o.contacts, 1u);
  expect_vec(o.vb, {0.5, -2.0, 0.0}, 2.0, "vb");
  expect_vec(o.va, {0, 0, 0}, 2.0, "static va");
}

TEST_P(CollisionResponse, InelasticEqualMassesTakeTheAverage) {
  for (int k = 0; k < 3; ++k) {
    SCOPED_TRACE(k);
    const Outcome o =
        collide(sphere(axis(k, -0.495f), axis(k, 4.0f), 0.0f), sphere(axis(k, 0.495f), axis(k, -2.0f), 0.0f));
    ASSERT_EQ(o.contacts, 1u);
    expect_vec(o.va, axis(k, 1.0f).cast<double>(), 4.0, "va");
    expect_vec(o.vb, axis(k, 1.0f).cast<double>(), 4.0, "vb");
  }
}

TEST_P(CollisionResponse, InelasticAgainstStaticStopsNormalComponent) {
  const Outcome o = collide(sphere({-0.495f, 0, 0}, {3.0f, -0.25f, 1.5f}, 0.0f),
                            sphere({0.495f, 0, 0}, {0, 0, 0}, 0.0f, 0.0f));
  ASSERT_EQ(o.contacts, 1u);
  expect_vec(o.va, {0.0, -0.25, 1.5}, 3.0, "va");  // tangential part unchanged
}

TEST_P(CollisionResponse, RestitutionIsTheMaximumOfTheTwo) {
  // e_a = 0, e_b = 1 -> elastic.
  const Outcome o =
      collide(sphere({-0.495f, 0, 0}, {5.0f, 0, 0}, 0.0f), sphere({0.495f, 0, 0}, {-2.0f, 0, 0}, 1.0f));
  expect_vec(o.va, {-2.0, 0, 0}, 5.0, "va");
  expect_vec(o.vb, {5.0, 0, 0}, 5.0, "vb");
}

TEST_P(CollisionResponse, UnequalMasses1D) {
  // Textbook 1D collision with coefficient e (double-precision reference).
  std::mt19937 rng(1);
  std::uniform_real_distribution<float> inv_mass(0.1f, 5.0f), speed(1.0f, 8.0f);
  for (int trial = 0; trial < 40; ++trial) {
    const float e = trial % 2 ? 1.0f : 0.0f;
    const float wa = inv_mass(rng), wb = inv_mass(rng);
    const float ua = speed(rng), ub = -speed(rng);
    const Outcome o =
        collide(sphere({-0.495f, 0, 0}, {ua, 0, 0}, e, wa), sphere({0.495f, 0, 0}, {ub, 0, 0}, e, wb));
    ASSERT_EQ(o.contacts, 1u);
    const double ma = 1.0 / wa, mb = 1.0 / wb;
    const double va = (ma * ua + mb * ub + mb * e * (ub - ua)) / (ma + mb);
    const double vb = (ma * ua + mb * ub + ma * e * (ua - ub)) / (ma + mb);
    const double scale = std::max(std::abs(ua), std::abs(ub));
    EXPECT_NEAR(o.va.x(), va, 2e-6 * scale) << "trial " << trial;
    EXPECT_NEAR(o.vb.x(), vb, 2e-6 * scale) << "trial " << trial;
    EXPECT_EQ(o.va.y(), 0.0f);
    EXPECT_EQ(o.vb.z(), 0.0f);
  }
}

TEST_P(CollisionResponse, Random3DElasticConservesMomentumAndEnergy) {
  std::mt19937 rng(2);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f), inv_mass(0.2f, 5.0f), rad(0.2f, 1.0f);
  for (int trial = 0; trial < 100; ++trial) {
    SCOPED_TRACE(trial);
    Eigen::Vector3f n(u(rng), u(rng), u(rng));
    if (n.norm() < 0.1f) n = Eigen::Vector3f::UnitX();
    n.normalize();
    BodyDesc a = sphere({u(rng), u(rng), u(rng)}, {}, 1.0f, inv_mass(rng));
    BodyDesc b = sphere({}, {}, 1.0f, inv_mass(rng));
    a.radius = rad(rng);
    b.radius = rad(rng);
    b.position = a.position + n * (a.radius + b.radius - 0.02f);
    a.velocity = Eigen::Vector3f(u(rng), u(rng), u(rng)) * 3.0f;
    b.velocity = Eigen::Vector3f(u(rng), u(rng), u(rng)) * 3.0f;
    // Make sure they approach along n faster than the restitution threshold.
    const float approach = (a.velocity - b.velocity).dot(n);
    if (approach < 1.0f) a.velocity += n * (1.0f - approach + 2.0f * std::abs(u(rng)));

    const Outcome o = collide(a, b);
    ASSERT_EQ(o.contacts, 1u);
    const Eigen::Vector3d nd = o.normal.cast<double>();
    EXPECT_NEAR(nd.norm(), 1.0, 1e-6);
    EXPECT_GT(nd.dot(n.cast<double>()), 0.9999);  // the contact normal is the centre line a -> b

    const double ma = 1.0 / a.inv_mass, mb = 1.0 / b.inv_mass;
    const Eigen::Vector3d ua = a.velocity.cast<double>(), ub = b.velocity.cast<double>();
    const Eigen::Vector3d va = o.va.cast<double>(), vb = o.vb.cast<double>();
    const Eigen::Vector3d p0 = ma * ua + mb * ub, p1 = ma * va + mb * vb;
    const double pscale = ma * ua.norm() + mb * ub.norm();
    EXPECT_LE((p1 - p0).norm(), 1e-5 * pscale) << "momentum";
    const double e0 = 0.5 * (ma * ua.squaredNorm() + mb * ub.squaredNorm());
    const double e1 = 0.5 * (ma * va.squaredNorm() + mb * vb.squaredNorm());
    EXPECT_NEAR(e1, e0, 1e-5 * e0) << "kinetic energy";
    // Only the normal component changes.
    auto tangential = [&](const Eigen::Vector3d& v) { return v - v.dot(nd) * nd; };
    EXPECT_LE((tangential(va) - tangential(ua)).norm(), 1e-5 * ua.norm() + 1e-6) << "tangential a";
    EXPECT_LE((tangential(vb) - tangential(ub)).norm(), 1e-5 * ub.norm() + 1e-6) << "tangential b";
    // Relative normal velocity reverses.
    const double before = (ub - ua).dot(nd), after = (vb - va).dot(nd);
    EXPECT_NEAR(after, -before, 1e-5 * (ua.norm() + ub.norm()));
  }
}

TEST_P(CollisionResponse, BelowRestitutionThresholdNoBounce) {
  SolverDesc s;
  ASSERT_GT(s.restitution_threshold, 0.4f);
  // Approach speed 0.4 < threshold: treated as inelastic even with e = 1.
  const Outcome o =
      collide(sphere({-0.495f, 0, 0}, {0.2f, 0, 0}, 1.0f), sphere({0.495f, 0, 0}, {-0.2f, 0, 0}, 1.0f));
  ASSERT_EQ(o.contacts, 1u);
  expect_vec(o.va, {0, 0, 0}, 0.2, "va");
  expect_vec(o.vb, {0, 0, 0}, 0.2, "vb");
}

TEST_P(CollisionResponse, SeparatingBodiesAreNotPulled) {
  // Overlapping but already moving apart: contacts push, never pull.
  const Outcome o =
      collide(sphere({-0.45f, 0, 0}, {-1.0f, 0.5f, 0}, 1.0f), sphere({0.45f, 0, 0}, {2.0f, 0, 0}, 1.0f));
  ASSERT_EQ(o.contacts, 1u);
  expect_vec(o.va, {-1.0, 0.5, 0}, 2.0, "va");
  expect_vec(o.vb, {2.0, 0, 0}, 2.0, "vb");
  EXPECT_EQ(o.impulse, 0.0f);
}

TEST_P(CollisionResponse, ElasticBallOnFloorFlipsNormalVelocity) {
  std::vector<PlaneDesc> floor(1);  // y = 0, normal +y
  const Outcome o = collide(sphere({0.3f, 0.49f, -0.2f}, {1.0f, -4.0f, 0.5f}, 1.0f), {}, floor);
  ASSERT_EQ(o.contacts, 1u);
  expect_vec(o.va, {1.0, 4.0, 0.5}, 4.0, "va");
  // Plane restitution counts too (e = max): an inelastic ball on an elastic floor bounces.
  floor[0].restitution = 1.0f;
  const Outcome p = collide(sphere({0, 0.49f, 0}, {0, -3.0f, 0}, 0.0f), {}, floor);
  expect_vec(p.va, {0.0, 3.0, 0.0}, 3.0, "va on elastic floor");
}

TEST_P(CollisionResponse, InelasticBallOnFloorStopsNormalVelocity) {
  std::vector<PlaneDesc> floor(1);
  const Outcome o = collide(sphere({0, 0.49f, 0}, {2.0f, -4.0f, -1.0f}, 0.0f), {}, floor);
  ASSERT_EQ(o.contacts, 1u);
  expect_vec(o.va, {2.0, 0.0, -1.0}, 4.0, "va");
}

TEST_P(CollisionResponse, ElasticBallOnTiltedPlane) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  for (int trial = 0; trial < 30; ++trial) {
    Eigen::Vector3f n(u(rng), u(rng), u(rng));
    if (n.norm() < 0.1f) n = Eigen::Vector3f::UnitY();
    std::vector<PlaneDesc> plane(1);
    plane[0].normal = n * 3.0f;  // not unit
    plane[0].offset = 0.0f;
    n.normalize();
    Eigen::Vector3f v = Eigen::Vector3f(u(rng), u(rng), u(rng)) * 2.0f;
    v -= n * (v.dot(n) + 2.0f);  // into the plane at >= 2 m/s
    const Outcome o = collide(sphere(n * 0.45f, v, 1.0f), {}, plane);
    ASSERT_EQ(o.contacts, 1u);
    const Eigen::Vector3d nd = n.cast<double>(), vd = v.cast<double>();
    const Eigen::Vector3d want = vd - 2.0 * vd.dot(nd) * nd;  // reflection
    EXPECT_LE((o.va.cast<double>() - want).norm(), 1e-5 * vd.norm()) << "trial " << trial;
  }
}

INSTANTIATE_TEST_SUITE_P(Solvers, CollisionResponse,
                         ::testing::Values(SolverKind::kSoftStep, SolverKind::kJacobi),
                         [](const ::testing::TestParamInfo<SolverKind>& i) {
                           return i.param == SolverKind::kSoftStep ? "SoftStep" : "Jacobi";
                         });

}  // namespace
}  // namespace impact
