// Numerical stability of the whole step at the extremes, through the public World
// API (spheres and planes only). Each test compares with an analytic result or
// with a reference run of the same scene at ordinary magnitudes:
//   1. scale invariance: one scene at length scales 1e-3, 1 and 1e3;
//   2. far from the origin: the same scene translated by 1e4 m and 1e5 m;
//   3. extreme mass ratios: heavy-on-light and light-on-heavy stacks (1e3, 1e6),
//      and a 1-D elastic collision at mass ratio 1e6 against the closed form;
//   4. very fast bodies: 100 and 1000 m/s against a static sphere and a plane
//      (discrete collision: the documented tunnelling limit), and a fast head-on
//      collision inside the detection window;
//   5. near-degenerate geometry: coincident and nearly coincident centres,
//      exact touching, a 0.1 mm sphere on a floor, a radius ratio of 1e4;
//   6. 1000 spheres released at one point.
// Every test runs for both solvers (SolverKind::kSoftStep, the default, and kJacobi);
// where their designs give different bounds, the check says which and why.
// Figures worth tracking (overlaps, errors, times) are printed as "[ measure ]"
// lines. Tolerances are stated next to each check, with the physics behind them.
// Where a check encodes a known limitation of the solver design (Jacobi with mass
// splitting and warm starting, position correction by iterations on displacements,
// the soft step's recovery path for deep overlaps, discrete collision detection)
// its comment says so with "LIMITATION".
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <vector>

#include "impact/impact.h"
#include "support/test_support.h"

namespace impact {
namespace {

using Vec3d = Eigen::Vector3d;

constexpr double kG = 9.81;         // m/s^2, default gravity magnitude
constexpr double kDt = 1.0 / 60.0;  // s, default fixed step

struct Scene {
  std::unique_ptr<World> world;
  std::vector<BodyHandle> h;
};

std::vector<Eigen::Vector3f> positions(const Scene& s) {
  std::vector<Eigen::Vector3f> p(s.h.size());
  EXPECT_TRUE(test::IsOk(s.world->get_positions(s.h, p)));
  return p;
}

std::vector<Eigen::Vector3f> velocities(const Scene& s) {
  std::vector<Eigen::Vector3f> v(s.h.size());
  EXPECT_TRUE(test::IsOk(s.world->get_velocities(s.h, v)));
  return v;
}

void add_floor(World& w, double height, float restitution = 0.0f) {
  PlaneDesc floor;  // { y <= height }
  floor.offset = static_cast<float>(height);
  floor.restitution = restitution;
  PlaneHandle ph;
  ASSERT_TRUE(test::IsOk(w.create_planes(std::span(&floor, 1), std::span(&ph, 1))));
}

// The solver the running test uses (set by the fixture): every test runs for both.
SolverKind g_kind = SolverKind::kSoftStep;
[[maybe_unused]] bool soft() { return g_kind == SolverKind::kSoftStep; }

class Extremes : public ::testing::TestWithParam<SolverKind> {
 protected:
  void SetUp() override { g_kind = GetParam(); }
};

Scene make_bodies(WorldDesc d, const std::vector<BodyDesc>& bodies) {
  d.solver.kind = g_kind;
  Scene s;
  s.world = test::make_world(d);
  s.h.resize(bodies.size());
  EXPECT_TRUE(test::IsOk(s.world->create_bodies(bodies, s.h)));
  return s;
}

void run(Scene& s, int steps) {
  for (int k = 0; k < steps; ++k) ASSERT_TRUE(test::IsOk(s.world->step())) << "step " << k;
}

void expect_all_finite(const Scene& s) {
  const BodyArrays b = s.world->bodies();
  for (size_t i = 0; i < b.size(); ++i) {
    ASSERT_TRUE(std::isfinite(b.pos_x[i]) && std::isfinite(b.pos_y[i]) && std::isfinite(b.pos_z[i]))
        << "slot " << i << " position not finite";
    ASSERT_TRUE(std::isfinite(b.vel_x[i]) && std::isfinite(b.vel_y[i]) && std::isfinite(b.vel_z[i]))
        << "slot " << i << " velocity not finite";
  }
  const ContactArrays c = s.world->contacts();
  for (size_t k = 0; k < c.size(); ++k) {
    ASSERT_TRUE(std::isfinite(c.normal_x[k]) && std::isfinite(c.normal_y[k]) &&
                std::isfinite(c.normal_z[k]) && std::isfinite(c.depth[k]) && std::isfinite(c.impulse[k]))
        << "contact " << k << " not finite";
  }
}

// ---------------------------------------------------------------------------------
// The reference scene of tests 1 and 2: a stack of three touching spheres on a
// floor and, beside it, a ball dropped from 4 m with restitution 0.7. At length
// scale s every length (positions, radii, plane offset, slop) and every
// acceleration (gravity) is multiplied by s while time (dt) is unchanged, so
// velocities scale by s too: the restitution threshold (m/s) is scaled as well,
// otherwise at s = 1e-3 the ball (at most ~9 mm/s) would never exceed 0.5 m/s and
// never bounce. Masses are unchanged. Every equation of the step is then
// homogeneous in s, so positions / s are scale-free up to float rounding.
// ---------------------------------------------------------------------------------
constexpr int kStack = 3;
constexpr int kSceneBodies = kStack + 1;  // + the bouncing ball (last)

Scene make_reference_scene(double s, const Vec3d& offset) {
  WorldDesc d;
  d.gravity = Eigen::Vector3f(0.0f, static_cast<float>(-kG * s), 0.0f);
  d.solver.penetration_slop = static_cast<float>(0.001 * s);
  d.solver.restitution_threshold = static_cast<float>(0.5 * s);
  d.solver.max_push_speed = static_cast<float>(3.0 * s);
  // Sleeping off: its threshold is a decision, and a resting stack whose speed hovers
  // near sleep_speed falls asleep a step earlier or later as rounding differs with the
  // scale (0.5 mm of difference), which says nothing about the step's equations.
  d.solver.sleep = false;
  std::vector<BodyDesc> b(kSceneBodies);
  for (int i = 0; i < kStack; ++i) {
    b[i].position = (offset + s * Vec3d(0.0, 0.5 + i, 0.0)).cast<float>();
    b[i].radius = static_cast<float>(0.5 * s);
    b[i].restitution = 0.0f;
  }
  BodyDesc& ball = b[kStack];
  ball.position = (offset + s * Vec3d(3.0, 4.0, 0.0)).cast<float>();
  ball.radius = static_cast<float>(0.5 * s);
  ball.restitution = 0.7f;
  Scene sc = make_bodies(d, b);
  add_floor(*sc.world, offset.y());
  return sc;
}

// Positions relative to offset, divided by s, in double.
std::vector<Vec3d> scene_state(const Scene& sc, double s, const Vec3d& offset) {
  std::vector<Vec3d> out;
  for (const Eigen::Vector3f& p : positions(sc)) out.push_back((p.cast<double>() - offset) / s);
  return out;
}

// The reference run itself is sane: the stack rests on the floor in order, the
// ball is above the floor. Lengths in units of the scene scale.
void expect_reference_sane(const std::vector<Vec3d>& p) {
  EXPECT_GT(p[0].y(), 0.5 - 0.05);
  for (int i = 1; i < kStack; ++i) EXPECT_GT(p[i].y() - p[i - 1].y(), 1.0 - 0.05) << "stack " << i;
  EXPECT_GT(p[kStack].y(), 0.5 - 0.05) << "ball";
}

constexpr int kSceneSteps = 120;

// Runs the reference scene at scale s; returns positions / s and whether the
// ball (last body) moved upwards at some step, i.e. bounced.
std::vector<Vec3d> run_scaled_scene(double s, bool* ball_bounced) {
  Scene sc = make_reference_scene(s, Vec3d::Zero());
  *ball_bounced = false;
  for (int k = 0; k < kSceneSteps; ++k) {
    EXPECT_TRUE(test::IsOk(sc.world->step()));
    if (velocities(sc)[kStack].y() > 0.0f) *ball_bounced = true;
  }
  expect_all_finite(sc);
  // The stack has settled: speeds below 0.05 m/s at scale 1 (stacking_test's bar).
  const std::vector<Eigen::Vector3f> v = velocities(sc);
  for (int i = 0; i < kStack; ++i) EXPECT_LT(v[i].norm() / s, 0.05) << "stack body " << i;
  return scene_state(sc, s, Vec3d::Zero());
}

TEST_P(Extremes, ScaleInvariance) {
  bool ref_bounced = false;
  const std::vector<Vec3d> p_ref = run_scaled_scene(1.0, &ref_bounced);
  expect_reference_sane(p_ref);
  EXPECT_TRUE(ref_bounced) << "the reference ball never bounced: the scene does not test restitution";
  for (double s : {1e-3, 1e3}) {
    SCOPED_TRACE(::testing::Message() << "scale " << s);
    bool bounced = false;
    const std::vector<Vec3d> p = run_scaled_scene(s, &bounced);
    EXPECT_EQ(bounced, ref_bounced);
    double err = 0.0;
    for (int i = 0; i < kSceneBodies; ++i) err = std::max(err, (p[i] - p_ref[i]).norm());
    std::printf("[ measure ] scale %g: max |p/s - p_ref| = %.3g (units of s)\n", s, err);
    // Inputs at scale s differ from s * (inputs at scale 1) by float rounding,
    // ~6e-8 relative, and 120 steps of a resting stack and one bounce do not
    // amplify that much (measured 3e-6 at 1e-3, 1e-6 at 1e3). 1e-4 of the scene
    // size (1e-4 * s m) is ~1000x float epsilon: a real scale dependence (an
    // absolute length or speed constant left in the step) would show as 1e-3 .. 1.
    for (int i = 0; i < kSceneBodies; ++i)
      EXPECT_LT((p[i] - p_ref[i]).norm(), 1e-4)
          << "body " << i << ": " << p[i].transpose() << " vs " << p_ref[i].transpose();
  }
}

// ---------------------------------------------------------------------------------
// Test 2. The same scene translated by (D, D, D), D = 1e4 and 1e5 m; the floor's
// offset moves by D. Float positions near D are quantised to ulp(D) (2^-10 m =
// 0.98 mm at 1e4, 2^-7 m = 7.8 mm at 1e5), and every position update x += v dt is
// rounded to that grid, so a body resting (or moving at under half an ulp per
// step) moves in ulp-sized jerks. Physics must not otherwise depend on D: the
// stack must rest on the translated floor, nothing may fall through, and the
// state relative to D must match the run at the origin within a few ulp(D).
TEST_P(Extremes, FarFromOrigin) {
  const Vec3d origin = Vec3d::Zero();
  Scene ref = make_reference_scene(1.0, origin);
  double ref_lowest = 1e30;  // lowest end-of-step height of the bottom sphere's centre
  for (int k = 0; k < kSceneSteps; ++k) {
    ASSERT_TRUE(test::IsOk(ref.world->step()));
    ref_lowest = std::min(ref_lowest, static_cast<double>(positions(ref)[0].y()));
  }
  const std::vector<Vec3d> p_ref = scene_state(ref, 1.0, origin);
  for (double dist : {1e4, 1e5}) {
    SCOPED_TRACE(::testing::Message() << "offset " << dist);
    const double ulp = std::nextafter(static_cast<float>(dist), 1e30f) - static_cast<float>(dist);
    const Vec3d off(dist, dist, dist);
    Scene sc = make_reference_scene(1.0, off);
    double max_stack_err = 0.0, max_ball_err = 0.0;
    double min_stack_gap = 1e30;
    int steps_with_floor_contact = 0;
    for (int k = 0; k < kSceneSteps; ++k) {
      ASSERT_TRUE(test::IsOk(sc.world->step()));
      steps_with_floor_contact += sc.world->last_step().plane_contacts > 0 ? 1 : 0;
      const Eigen::Vector3f p0 = positions(sc)[0];
      min_stack_gap = std::min(min_stack_gap, static_cast<double>(p0.y()) - dist);
    }
    std::printf(
        "[ measure ] offset %g: floor contact in %d of %d steps, lowest bottom centre %.4g m "
        "(at the origin %.4g m)\n",
        dist, steps_with_floor_contact, kSceneSteps, min_stack_gap, ref_lowest);
    // Nothing sinks into the floor deeper than in the origin run, give or take the
    // quantisation of the rest height (2 ulp): the floor holds at any offset.
    EXPECT_GT(min_stack_gap, ref_lowest - 2.0 * ulp);
    // A resting body at 1e5 m gains v = g dt per step but moves only when
    // |v dt| > ulp/2, so the floor contact comes and goes; it must not vanish.
    EXPECT_GE(steps_with_floor_contact, kSceneSteps / 4);
    expect_all_finite(sc);
    const std::vector<Vec3d> p = scene_state(sc, 1.0, off);
    expect_reference_sane(p);
    for (int i = 0; i < kStack; ++i) max_stack_err = std::max(max_stack_err, (p[i] - p_ref[i]).norm());
    max_ball_err = (p[kStack] - p_ref[kStack]).norm();
    std::printf("[ measure ] offset %g (ulp %g m): stack err %.3g m = %.2f ulp, ball err %.3g m = %.2f ulp\n",
                dist, ulp, max_stack_err, max_stack_err / ulp, max_ball_err, max_ball_err / ulp);
    // The stack is re-anchored by its contacts every step, so its quantisation
    // error does not accumulate: a few ulp (4) cover rounding of the rest height
    // through three contacts. The soft step's contacts are springs that answer the
    // quantised depth with a push over later steps (measured 5.4 ulp at 1e4): 8.
    EXPECT_LE(max_stack_err, (soft() ? 8.0 : 4.0) * ulp);
    // The ball's x += v dt is rounded every step (<= ulp/2), and that error adds
    // up over its flight: kSceneSteps * ulp / 2 = 60 ulp in the worst case. The
    // roundings of successive steps mostly cancel (measured: 0.3 ulp at 1e4,
    // 0.2 ulp at 1e5), so 8 ulp still leaves room while catching any real drift.
    EXPECT_LE(max_ball_err, 8.0 * ulp);
    // Horizontal coordinates never move (all forces vertical): exact.
    for (int i = 0; i < kSceneBodies; ++i) {
      EXPECT_EQ(p[i].x(), p_ref[i].x()) << "body " << i;
      EXPECT_EQ(p[i].z(), p_ref[i].z()) << "body " << i;
    }
  }
}

// ---------------------------------------------------------------------------------
// Test 3. Extreme mass ratios.
// ---------------------------------------------------------------------------------

// Two equal-radius spheres stacked on a floor, bottom mass m_bottom, top mass
// m_top, released touching; 300 steps (5 s). Both must come to rest and the
// overlaps stay bounded.
struct TwoStackResult {
  double speed_bottom, speed_top;
  double floor_overlap;      // m, max over the last second of r - y_bottom
  double pair_overlap;       // m, max of 2r - (y_top - y_bottom)
  double top_floor_overlap;  // m, max of r - y_top (negative while the stack stands)
};

TwoStackResult run_two_stack(double m_bottom, double m_top) {
  constexpr float r = 0.5f;
  std::vector<BodyDesc> b(2);
  b[0].position = {0.0f, r, 0.0f};
  b[0].inv_mass = static_cast<float>(1.0 / m_bottom);
  b[1].position = {0.0f, 3.0f * r, 0.0f};
  b[1].inv_mass = static_cast<float>(1.0 / m_top);
  for (BodyDesc& d : b) d.radius = r;
  Scene sc = make_bodies(WorldDesc{}, b);
  add_floor(*sc.world, 0.0);
  TwoStackResult out{};
  double max_floor = -1e30, max_pair = -1e30, max_top_floor = -1e30;
  for (int k = 0; k < 300; ++k) {
    EXPECT_TRUE(test::IsOk(sc.world->step()));
    const std::vector<Eigen::Vector3f> p = positions(sc);
    // Overlaps at the end of the last 60 steps (1 s), once the stack has settled.
    if (k >= 240) {
      max_floor = std::max(max_floor, static_cast<double>(r - p[0].y()));
      max_pair = std::max(max_pair, static_cast<double>(2.0f * r - (p[1].y() - p[0].y())));
      max_top_floor = std::max(max_top_floor, static_cast<double>(r - p[1].y()));
    }
  }
  expect_all_finite(sc);
  const std::vector<Eigen::Vector3f> v = velocities(sc);
  out.speed_bottom = v[0].norm();
  out.speed_top = v[1].norm();
  out.floor_overlap = max_floor;
  out.pair_overlap = max_pair;
  out.top_floor_overlap = max_top_floor;
  std::printf(
      "[ measure ] bottom %g kg, top %g kg: speeds %.3g / %.3g m/s, max overlap floor %.3g m, "
      "pair %.3g m (r = 0.5 m)\n",
      m_bottom, m_top, out.speed_bottom, out.speed_top, max_floor, max_pair);
  return out;
}

// A resting body at the end of a step has v ~ 0 (the solve cancels the g dt =
// 0.16 m/s gained); 0.05 m/s is the bar of stacking_test. The end-of-step overlap
// of a resting contact stays near the slop (measured ~1 mm); 5% of the radius
// (25 mm) is the bar of stacking_test.
TEST_P(Extremes, LightOnHeavyRests) {
  for (double ratio : {1e3, 1e6}) {
    const TwoStackResult r = run_two_stack(ratio, 1.0);
    EXPECT_LT(r.speed_bottom, 0.05) << "ratio " << ratio;
    EXPECT_LT(r.speed_top, 0.05) << "ratio " << ratio;
    EXPECT_LT(r.floor_overlap, 0.025) << "ratio " << ratio;
    EXPECT_LT(r.pair_overlap, 0.025) << "ratio " << ratio;
  }
}

// Heavy on light. Physically the light sphere holds the heavy one up (rigid
// spheres: any mass ratio rests at the same heights).
//
// LIMITATION (solver design, measured): contacts are found on the starting
// poses and velocities are solved before positions move, so a resting stack does
// not sink by g dt^2 each step; ratio 10 rests with ~1 mm overlaps. From a ratio
// of ~1e3 up the light sphere is still crushed: the heavy one ends on the floor,
// overlapping the light one by about r, and keeps a residual speed below one
// step of gravity (measured 0.09 m/s at 1e3). Cause: Jacobi with mass splitting
// converges like (1 - 1/ratio) per iteration on such a chain; warm starting
// carries impulses across steps but position correction (also Jacobi) cannot
// hold a 1e3 x heavier body. A direct or shock-propagation solver would.
// So this test asserts what the design meets:
//   ratio 10: the 5%-of-radius bar of stacking_test;
//   ratio 1e3 and 1e6: finite, slower than one step of gravity (g dt = 0.16 m/s),
//   and neither body leaves the floor's half-space beyond the resting overlap
//   (heavy) or its own radius (light).
// DISABLED_HeavyOnLightWithinFivePercent below holds the physical target.
TEST_P(Extremes, HeavyOnLightRests) {
  {
    const TwoStackResult r = run_two_stack(1.0, 10.0);
    EXPECT_LT(r.speed_bottom, 0.05);
    EXPECT_LT(r.speed_top, 0.05);
    EXPECT_LT(r.floor_overlap, 0.025);
    EXPECT_LT(r.pair_overlap, 0.025);
  }
  if (soft()) {
    // 100:1 heavy on light stands (issue 40's bar for the soft step): at rest, the
    // light body's contacts giving under 100x its weight by 2.9 cm (measured; 7%
    // of the radius asserted, against the 5% of lighter stacks).
    const TwoStackResult r = run_two_stack(1.0, 100.0);
    EXPECT_LT(r.speed_bottom, 0.05);
    EXPECT_LT(r.speed_top, 0.05);
    EXPECT_LT(r.floor_overlap, 0.035);
    EXPECT_LT(r.pair_overlap, 0.035);
  }
  for (double ratio : {1e3, 1e6}) {
    SCOPED_TRACE(::testing::Message() << "ratio " << ratio);
    const TwoStackResult r = run_two_stack(1.0, ratio);
    // The soft step crushes the light body too; the crushed pair is deeper than
    // max_push_speed * dt and takes the recovery path, whose residual speed is below
    // two steps of gravity (measured 0.18 / 0.19 m/s at 1e3).
    const double bound = soft() ? 2.0 * kG * kDt : 0.15;
    EXPECT_LT(r.speed_bottom, bound);
    EXPECT_LT(r.speed_top, bound);
    // Light body's centre stays above -r (it is not pushed through the floor).
    EXPECT_LT(r.floor_overlap, 2.0 * 0.5);
    // Heavy body: sinks at most as deep as any body resting on the floor (the
    // end-of-step resting overlap, slop + (1-c)/c g dt^2 = 1.7 mm; 4.5 mm bound).
    EXPECT_LT(r.top_floor_overlap, 0.0045);
  }
}

// The physical target for heavy on light (see the LIMITATION above). Disabled:
// fails today with floor and pair overlaps of 0.50 m at ratios 1e3 and 1e6.
// Run with --gtest_also_run_disabled_tests.
TEST_P(Extremes, DISABLED_HeavyOnLightWithinFivePercent) {
  for (double ratio : {1e3, 1e6}) {
    const TwoStackResult r = run_two_stack(1.0, ratio);
    EXPECT_LT(r.floor_overlap, 0.025) << "ratio " << ratio;
    EXPECT_LT(r.pair_overlap, 0.025) << "ratio " << ratio;
  }
}

// 1-D elastic collision, no gravity: body 1 (mass m1, speed u) hits body 2 (mass
// m2, at rest). Closed form: v1 = (m1 - m2) / (m1 + m2) u, v2 = 2 m1 / (m1 + m2) u;
// momentum m1 u and energy m1 u^2 / 2 are conserved. An isolated pair is solved
// exactly by one Jacobi iteration, so the only error is float rounding of the
// effective mass 1 / (1/m1 + 1/m2) and of v += impulse / m: a few float epsilons
// of the incoming momentum / energy.
TEST_P(Extremes, ElasticCollisionMassRatio1e6) {
  WorldDesc d = test::zero_gravity_desc();
  const double u = 2.0;  // m/s, above restitution_threshold
  for (bool light_moves : {true, false}) {
    const double m1 = light_moves ? 1.0 : 1e6, m2 = light_moves ? 1e6 : 1.0;
    SCOPED_TRACE(::testing::Message() << "m1 " << m1 << " hits m2 " << m2);
    std::vector<BodyDesc> b(2);
    b[0].position = {0.0f, 0.0f, 0.0f};
    b[0].velocity = {static_cast<float>(u), 0.0f, 0.0f};
    b[0].inv_mass = static_cast<float>(1.0 / m1);
    b[1].position = {0.98f, 0.0f, 0.0f};  // 2 cm overlap: contacts are found on the starting poses
    b[1].inv_mass = static_cast<float>(1.0 / m2);
    for (BodyDesc& x : b) {
      x.radius = 0.5f;
      x.restitution = 1.0f;
    }
    Scene sc = make_bodies(d, b);
    run(sc, 1);
    ASSERT_EQ(sc.world->last_step().contacts, 1u);
    run(sc, 5);  // they separate; no further impulse
    expect_all_finite(sc);
    const std::vector<Eigen::Vector3f> v = velocities(sc);
    const double v1 = (m1 - m2) / (m1 + m2) * u, v2 = 2.0 * m1 / (m1 + m2) * u;
    const double p0 = m1 * u, e0 = 0.5 * m1 * u * u;
    const double p1 = m1 * v[0].x() + m2 * v[1].x();
    const double e1 = 0.5 * m1 * v[0].squaredNorm() + 0.5 * m2 * v[1].squaredNorm();
    std::printf(
        "[ measure ] elastic m1=%g m2=%g: v1 %.9g (exact %.9g), v2 %.9g (exact %.9g), "
        "momentum rel err %.3g, energy rel err %.3g\n",
        m1, m2, v[0].x(), v1, v[1].x(), v2, std::fabs(p1 - p0) / p0, std::fabs(e1 - e0) / e0);
    constexpr double eps = std::numeric_limits<float>::epsilon();  // 1.19e-7
    // Each velocity to a few float ulps of the larger of u and itself.
    EXPECT_NEAR(v[0].x(), v1, 4.0 * eps * u);
    EXPECT_NEAR(v[1].x(), v2, 4.0 * eps * u);
    EXPECT_LE(std::fabs(p1 - p0), 8.0 * eps * p0);
    EXPECT_LE(std::fabs(e1 - e0), 8.0 * eps * e0);
    // Motion stays on the x axis.
    for (const Eigen::Vector3f& x : v) {
      EXPECT_EQ(x.y(), 0.0f);
      EXPECT_EQ(x.z(), 0.0f);
    }
  }
}

// ---------------------------------------------------------------------------------
// Test 4. Very fast bodies. Contacts are found on the positions after x += v dt
// (discrete detection, no continuous collision yet). A sphere pair (radius sum
// R) is detected only if the centre distance at the end of some step is < R; the
// normal points the right way (from the mover towards the target) only if the
// mover's centre has not yet passed the target's. So with d = |v_rel| dt:
//   d < R        : always detected on the approach side -> correct response;
//   R <= d < 2R  : depends on where the step lands (fraction R/d correct, the rest
//                  is pushed through);
//   d >= 2R      : may be missed entirely (tunnelling).
// LIMITATION: the last two are the known limitation that the "continuous
// collision" issue removes. The tests assert only what holds either way: the
// world stays valid and finite, no kinetic energy is created, no overlap is left,
// and every run that lands on the approach side responds correctly.
// ---------------------------------------------------------------------------------

// A sphere (r 0.5, elastic) flies along +x at a static sphere (r 0.5) at the
// origin, from a sweep of start phases.
TEST_P(Extremes, FastSphereAgainstStaticSphere) {
  constexpr float r = 0.5f;
  constexpr double R = 2.0 * r;
  constexpr int kPhases = 16;
  for (double speed : {100.0, 1000.0}) {
    SCOPED_TRACE(::testing::Message() << "speed " << speed);
    const double d = speed * kDt;
    int bounced = 0, approach_side = 0;
    for (int ph = 0; ph < kPhases; ++ph) {
      // Start so that the first step landing within R of the target is at
      // -R + (ph + 0.5) / kPhases * min(d, 2R): spread over the detection window.
      const double land = -R + (ph + 0.5) / kPhases * std::min(d, 2.0 * R);
      const double x0 = land - 3.0 * d;
      std::vector<BodyDesc> b(2);
      b[0].position = {static_cast<float>(x0), 0.0f, 0.0f};
      b[0].velocity = {static_cast<float>(speed), 0.0f, 0.0f};
      b[1].inv_mass = 0.0f;  // static target at the origin
      for (BodyDesc& x : b) {
        x.radius = r;
        x.restitution = 1.0f;
      }
      Scene sc = make_bodies(test::zero_gravity_desc(), b);
      double max_speed = 0.0;
      for (int k = 0; k < 8; ++k) {
        ASSERT_TRUE(test::IsOk(sc.world->step()));
        expect_all_finite(sc);
        max_speed = std::max(max_speed, static_cast<double>(velocities(sc)[0].norm()));
      }
      const Eigen::Vector3f p = positions(sc)[0], v = velocities(sc)[0];
      // Elastic against static: speed is conserved, never gained (float: 4 eps).
      EXPECT_LE(max_speed, speed * (1.0 + 4.0 * std::numeric_limits<float>::epsilon()));
      // Whatever happened, the mover is no longer inside the target.
      EXPECT_GE(p.norm(), R - 0.001) << "phase " << ph;
      EXPECT_EQ(p.y(), 0.0f);
      EXPECT_EQ(p.z(), 0.0f);
      const bool landed_before_centre = land < 0.0;
      approach_side += landed_before_centre ? 1 : 0;
      const bool b_back = v.x() < 0.0f;
      bounced += b_back ? 1 : 0;
      // Approach-side landing: exact elastic reflection, v -> -v.
      if (landed_before_centre) {
        EXPECT_TRUE(b_back) << "phase " << ph << " landed at " << land << " but did not bounce";
        EXPECT_NEAR(v.x(), -speed, 4.0 * std::numeric_limits<float>::epsilon() * speed) << "phase " << ph;
      }
    }
    std::printf(
        "[ measure ] %g m/s (step %.3g m, radius sum %.3g m) vs static sphere: %d of %d start phases "
        "bounce, %d tunnel (approach-side landings %d)\n",
        speed, d, R, bounced, kPhases, kPhases - bounced, approach_side);
    EXPECT_EQ(bounced, approach_side);
  }
}

// A sphere hits a floor plane at 100 and 1000 m/s (16.7 m per step, 33 radii).
// A plane is a half-space, so it cannot be tunnelled: the sphere is found deep
// inside, its normal velocity is removed in one iteration (restitution 0), and
// position correction takes back 80% of the depth per step (exactly, for an
// isolated contact), so after ~10 steps it rests on the floor like any body.
// With restitution 1 it leaves at the incoming speed, never faster.
TEST_P(Extremes, FastSphereAgainstPlane) {
  for (double speed : {100.0, 1000.0}) {
    for (float e : {0.0f, 1.0f}) {
      SCOPED_TRACE(::testing::Message() << "speed " << speed << " restitution " << e);
      BodyDesc b;
      b.position = {0.0f, 5.0f, 0.0f};
      b.velocity = {0.0f, static_cast<float>(-speed), 0.0f};
      b.restitution = e;
      Scene sc = make_bodies(WorldDesc{}, {b});
      add_floor(*sc.world, 0.0);
      double deepest = 0.0;
      for (int k = 0; k < 60; ++k) {
        ASSERT_TRUE(test::IsOk(sc.world->step()));
        expect_all_finite(sc);
        const ContactArrays c = sc.world->contacts();
        for (size_t i = 0; i < c.size(); ++i) deepest = std::max(deepest, static_cast<double>(c.depth[i]));
        // No energy from nowhere: |v| <= incoming speed + g t.
        EXPECT_LE(velocities(sc)[0].norm(), speed + kG * kDt * (k + 1) + 1e-3) << "step " << k;
      }
      const Eigen::Vector3f p = positions(sc)[0], v = velocities(sc)[0];
      std::printf(
          "[ measure ] %g m/s into a plane, e = %g: deepest contact %.4g m, after 1 s y = %.4g m, "
          "v = %.4g m/s\n",
          speed, e, deepest, p.y(), v.y());
      EXPECT_GT(deepest, 0.0);  // it was found, not skipped
      EXPECT_EQ(p.x(), 0.0f);
      EXPECT_EQ(p.z(), 0.0f);
      if (e == 0.0f) {
        // At rest on the floor with the ordinary resting overlap (<= 4.5 mm).
        EXPECT_GT(p.y(), 0.5 - 0.0045);
        EXPECT_LT(p.y(), 0.5 + 1e-3);
        EXPECT_LT(v.norm(), 0.05);
      } else {
        // Bounced: moving up (speed minus 1 s of gravity), above the floor.
        EXPECT_GT(p.y(), 0.5);
        EXPECT_GT(v.y(), 0.0f);
      }
    }
  }
}

// Two equal elastic spheres meet head-on at +-v with radius R = 1.25 v dt each:
// the closing distance per step 2 v dt is less than the radius sum 2R, so the
// contact is always found on the approach side and the isolated pair is solved
// exactly: the velocities swap (v -> -v) to float precision and the centres never
// pass each other.
TEST_P(Extremes, FastHeadOnCollisionSwapsVelocities) {
  for (double speed : {100.0, 1000.0}) {
    SCOPED_TRACE(::testing::Message() << "speed " << speed);
    const double radius = 1.25 * speed * kDt;
    std::vector<BodyDesc> b(2);
    b[0].position = {static_cast<float>(-6.1 * speed * kDt), 0.0f, 0.0f};
    b[0].velocity = {static_cast<float>(speed), 0.0f, 0.0f};
    b[1].position = {static_cast<float>(6.1 * speed * kDt), 0.0f, 0.0f};
    b[1].velocity = {static_cast<float>(-speed), 0.0f, 0.0f};
    for (BodyDesc& x : b) {
      x.radius = static_cast<float>(radius);
      x.restitution = 1.0f;
    }
    Scene sc = make_bodies(test::zero_gravity_desc(), b);
    int contact_steps = 0;
    for (int k = 0; k < 12; ++k) {
      ASSERT_TRUE(test::IsOk(sc.world->step()));
      contact_steps += sc.world->last_step().contacts > 0 ? 1 : 0;
      const std::vector<Eigen::Vector3f> p = positions(sc);
      ASSERT_LT(p[0].x(), p[1].x()) << "centres passed each other at step " << k;
    }
    expect_all_finite(sc);
    const std::vector<Eigen::Vector3f> v = velocities(sc);
    const double tol = 4.0 * std::numeric_limits<float>::epsilon() * speed;
    std::printf("[ measure ] head-on at +-%g m/s: v after = %.9g, %.9g (exact -+%g), contact in %d step(s)\n",
                speed, v[0].x(), v[1].x(), speed, contact_steps);
    EXPECT_EQ(contact_steps, 1);
    EXPECT_NEAR(v[0].x(), -speed, tol);
    EXPECT_NEAR(v[1].x(), speed, tol);
    EXPECT_EQ(v[0].y(), 0.0f);
    EXPECT_EQ(v[1].y(), 0.0f);
  }
}

// ---------------------------------------------------------------------------------
// Test 5. Near-degenerate geometry.
// ---------------------------------------------------------------------------------

// Two spheres with exactly the same centre: the direction between them is
// undefined, and the narrow phase documents +y for it. No gravity, inelastic:
// the approach speed is 0, so no velocity impulse; position correction separates
// them along +-y, by equal amounts (equal masses), in a few steps (80% of the
// remaining depth per step). The midpoint (centre of mass) does not move.
TEST_P(Extremes, CoincidentCentresSeparate) {
  std::vector<BodyDesc> b(2);
  for (BodyDesc& x : b) x.position = {1.0f, 2.0f, 3.0f};
  Scene sc = make_bodies(test::zero_gravity_desc(), b);
  ASSERT_TRUE(test::IsOk(sc.world->step()));
  ASSERT_EQ(sc.world->contacts().size(), 1u);
  const ContactArrays c = sc.world->contacts();
  EXPECT_EQ(c.normal_x[0], 0.0f);
  EXPECT_EQ(c.normal_y[0], 1.0f);
  EXPECT_EQ(c.normal_z[0], 0.0f);
  EXPECT_FLOAT_EQ(c.depth[0], 1.0f);
  run(sc, 19);
  expect_all_finite(sc);
  const std::vector<Eigen::Vector3f> p = positions(sc), v = velocities(sc);
  const float dist = (p[1] - p[0]).norm();
  std::printf("[ measure ] coincident centres: distance after 20 steps %.6g m (radius sum 1)\n", dist);
  // Separated to within the slop (1 mm) plus float rounding. The soft step: the
  // recovery path takes the overlap down to max_push_speed * dt (5 cm), then the
  // soft contact closes the rest exponentially (measured 3.9 mm left at 20 steps).
  EXPECT_GT(dist, soft() ? 1.0f - 0.005f : 1.0f - 0.001f - 1e-5f);
  EXPECT_LT(dist, 1.0f + 1e-5f);  // and not flung apart
  for (int i = 0; i < 2; ++i) {
    EXPECT_EQ(p[i].x(), 1.0f);
    EXPECT_EQ(p[i].z(), 3.0f);
    // No kinetic energy from position correction (the soft push leaves rounding).
    if (soft())
      EXPECT_LT(v[i].norm(), 1e-6f);
    else
      EXPECT_EQ(v[i].norm(), 0.0f);
  }
  EXPECT_NEAR(0.5f * (p[0].y() + p[1].y()), 2.0f, 1e-6f);
}

// Centres a hair apart (1e-19 .. 1e-23 m): the squared distance is subnormal or
// underflows to 0. Whichever branch the narrow phase takes, the contact normal
// must be a unit vector (contact.h promises it) and everything finite.
// BUG (fails today): for separations 1e-21, 1e-22 and 3e-23 m the squared
// distance is subnormal (> 0 but < FLT_MIN), so sqrt and 1/dist lose precision
// and |n| = 0.99974, 1.0097 and 0.80. Taking the +y branch of
// kernels/narrowphase/plain/sphere_sphere.cpp when d2 < FLT_MIN (instead of d2 == 0)
// makes this pass.
TEST_P(Extremes, NearlyCoincidentCentresGiveUnitNormal) {
  for (float eps : {1e-19f, 1e-20f, 1e-21f, 1e-22f, 3e-23f, 1e-25f, 1e-38f, 1e-44f}) {
    SCOPED_TRACE(::testing::Message() << "separation " << eps);
    for (const Eigen::Vector3f& dir : {Eigen::Vector3f(1, 0, 0), Eigen::Vector3f(1, 1, 1).normalized()}) {
      std::vector<BodyDesc> b(2);
      b[0].position = {0.0f, 0.0f, 0.0f};
      b[1].position = eps * dir;
      Scene sc = make_bodies(test::zero_gravity_desc(), b);
      ASSERT_TRUE(test::IsOk(sc.world->step()));
      const ContactArrays c = sc.world->contacts();
      ASSERT_EQ(c.size(), 1u);
      const Eigen::Vector3f n(c.normal_x[0], c.normal_y[0], c.normal_z[0]);
      EXPECT_NEAR(n.norm(), 1.0f, 1e-5f)
          << "normal " << n.transpose() << ", offset " << b[1].position.transpose();
      run(sc, 19);
      expect_all_finite(sc);
      const std::vector<Eigen::Vector3f> p = positions(sc);
      EXPECT_GT((p[1] - p[0]).norm(), soft() ? 1.0f - 0.005f : 1.0f - 0.001f - 1e-5f);
    }
  }
}

// Exactly touching is not a contact (contact.h: |d| < ra + rb, h < r). Sphere on
// a plane at h == r, and two spheres at distance exactly ra + rb (all values
// exact in float): no contact, nothing moves. One ulp closer is a contact.
TEST_P(Extremes, ExactTouchingIsNoContact) {
  std::vector<BodyDesc> b(3);
  b[0].position = {0.0f, 0.5f, 0.0f};  // on the floor y = 0, h == r
  b[1].position = {5.0f, 0.75f, 0.0f};
  b[1].radius = 0.75f;
  b[2].position = {6.0f, 0.75f, 0.0f};  // touches b[1]: 1.0 = 0.75 + 0.25
  b[2].radius = 0.25f;
  Scene sc = make_bodies(test::zero_gravity_desc(), b);
  add_floor(*sc.world, 0.0);
  const std::vector<Eigen::Vector3f> p0 = positions(sc);
  run(sc, 3);
  EXPECT_EQ(sc.world->last_step().contacts, 0u);
  EXPECT_EQ(sc.world->last_step().pairs, 1u);  // the broad phase counts touching boxes
  EXPECT_EQ(positions(sc), p0);
  // One ulp into overlap: now both are contacts.
  std::vector<Eigen::Vector3f> p1 = p0;
  p1[0].y() = std::nextafter(0.5f, 0.0f);
  p1[2].x() = std::nextafter(6.0f, 0.0f);
  ASSERT_TRUE(test::IsOk(sc.world->set_positions(sc.h, p1)));
  run(sc, 1);
  EXPECT_EQ(sc.world->last_step().contacts, 2u);
  EXPECT_EQ(sc.world->last_step().plane_contacts, 1u);
  expect_all_finite(sc);
}

// A 0.1 mm sphere on a floor, 300 steps.
//
// LIMITATION (design, measured): with the default settings its end-of-step
// overlap is not relative to its size: each step a resting body first sinks
// g dt^2 = 2.7 mm (positions are integrated before contacts are found), and
// position correction leaves slop + (1-c)/c g dt^2 = 1 + 0.68 = 1.7 mm: the centre
// of a 0.1 mm sphere rests ~1.6 mm below the floor surface (17 radii). It is held
// by the half-space (normal = plane normal), so it rests and cannot fall out. The
// design-met bound asserted: overlap <= slop + (1-c)/c g dt^2 + 10%.
// With settings scaled to the body (lengths x s, dt x sqrt(s), s = r / 0.5 m: the
// same dimensionless problem as a 0.5 m ball at dt = 1/60 s) it meets the 5%-of-
// radius bar of stacking_test; that is the second half.
TEST_P(Extremes, TinySphereRestsOnFloor) {
  constexpr float r = 1e-4f;
  BodyDesc b;
  b.position = {0.0f, r, 0.0f};
  b.radius = r;
  {
    WorldDesc d;
    Scene sc = make_bodies(d, {b});
    add_floor(*sc.world, 0.0);
    double max_overlap = 0.0;
    for (int k = 0; k < 300; ++k) {
      ASSERT_TRUE(test::IsOk(sc.world->step()));
      if (k >= 240) max_overlap = std::max(max_overlap, static_cast<double>(r - positions(sc)[0].y()));
    }
    expect_all_finite(sc);
    const double c = d.solver.position_correction;
    const double design = d.solver.penetration_slop + (1.0 - c) / c * kG * kDt * kDt;
    const float speed = velocities(sc)[0].norm();
    std::printf(
        "[ measure ] r = 1e-4 m, default settings: overlap %.4g m (%.1f radii; design %.4g m), "
        "speed %.3g m/s\n",
        max_overlap, max_overlap / r, design, speed);
    EXPECT_LT(speed, 0.05f);
    EXPECT_GT(max_overlap, 0.0);  // in contact
    EXPECT_LT(max_overlap, 1.1 * design);
    EXPECT_EQ(sc.world->last_step().plane_contacts, 1u);
  }
  {
    const double s = r / 0.5;
    WorldDesc d;
    d.fixed_dt = static_cast<float>(kDt * std::sqrt(s));
    d.solver.penetration_slop = static_cast<float>(0.001 * s);
    d.solver.restitution_threshold = static_cast<float>(0.5 * std::sqrt(s));  // m/s scale as sqrt(s)
    d.solver.max_push_speed = static_cast<float>(3.0 * std::sqrt(s));
    d.solver.contact_hertz = static_cast<float>(30.0 / std::sqrt(s));  // 1/s as 1/sqrt(s)
    Scene sc = make_bodies(d, {b});
    add_floor(*sc.world, 0.0);
    double max_overlap = 0.0;
    for (int k = 0; k < 300; ++k) {
      ASSERT_TRUE(test::IsOk(sc.world->step()));
      if (k >= 240) max_overlap = std::max(max_overlap, static_cast<double>(r - positions(sc)[0].y()));
    }
    expect_all_finite(sc);
    const float speed = velocities(sc)[0].norm();
    std::printf(
        "[ measure ] r = 1e-4 m, scaled settings (dt %.3g s): overlap %.4g m (%.3f radii), "
        "speed %.3g m/s\n",
        d.fixed_dt, max_overlap, max_overlap / r, speed);
    EXPECT_LT(max_overlap, 0.05 * r);
    EXPECT_LT(speed, 0.05 * std::sqrt(s));
  }
}

// Radius ratio 1e4.
// (a) A 0.1 mm sphere resting on top of a 1 m sphere that rests on a floor. In
// this design a resting overlap is an absolute length, set by slop, g dt^2 and
// the contact graph, not by the radii (see TinySphereRestsOnFloor), so the top
// contact's overlap must equal that of the same two-body stack of equal 0.5 m
// spheres (measured 2.9 mm for both): 10% + 0.1 mm. The tiny sphere stays on the
// axis (every normal is vertical: x = z = 0 exactly), on top, at rest.
// (b) A 1 m sphere dropped onto a single 0.1 mm sphere lying on the floor under
// its lowest point (equal masses). Physically the big one rests on the tiny one
// (centre at 1.0002 m); in this design the tiny one is squeezed into the floor
// (measured: tiny centre at -1.8 mm, big sphere resting on the floor with 1.9 mm
// overlap), the same LIMITATION as heavy on light. Asserted: finite, at rest,
// and neither body deeper in the floor than kRestingOverlap = 4.5 mm (= resting
// overlap of an isolated contact, 1.7 mm, plus one step's sink g dt^2 = 2.7 mm).
TEST_P(Extremes, RadiusRatio1e4) {
  constexpr double kRestingOverlap = 0.0045;  // m
  const TwoStackResult equal = run_two_stack(1.0, 1.0);
  {
    std::vector<BodyDesc> b(2);
    b[0].position = {0.0f, 1.0f, 0.0f};
    b[0].radius = 1.0f;
    b[1].position = {0.0f, 2.0f + 1e-4f, 0.0f};
    b[1].radius = 1e-4f;
    Scene sc = make_bodies(WorldDesc{}, b);
    add_floor(*sc.world, 0.0);
    run(sc, 300);
    expect_all_finite(sc);
    const std::vector<Eigen::Vector3f> p = positions(sc), v = velocities(sc);
    const double overlap = 1.0 + 1e-4 - (p[1] - p[0]).norm();
    std::printf(
        "[ measure ] 1e-4 m sphere on a 1 m sphere: overlap %.4g m (equal-size stack %.4g m), "
        "speeds %.3g / %.3g m/s\n",
        overlap, equal.pair_overlap, v[0].norm(), v[1].norm());
    EXPECT_EQ(p[1].x(), 0.0f);
    EXPECT_EQ(p[1].z(), 0.0f);
    EXPECT_GT(p[1].y(), p[0].y() + 0.99f);  // still on top
    EXPECT_NEAR(overlap, equal.pair_overlap, 0.1 * equal.pair_overlap + 1e-4);
    EXPECT_LT(v[0].norm(), 0.05f);
    EXPECT_LT(v[1].norm(), 0.05f);
  }
  {
    std::vector<BodyDesc> b(2);
    b[0].position = {0.0f, 1e-4f, 0.0f};
    b[0].radius = 1e-4f;
    b[1].position = {0.0f, 1.0f + 2e-4f + 0.01f, 0.0f};  // 1 cm above it
    b[1].radius = 1.0f;
    Scene sc = make_bodies(WorldDesc{}, b);
    add_floor(*sc.world, 0.0);
    run(sc, 300);
    expect_all_finite(sc);
    const std::vector<Eigen::Vector3f> p = positions(sc), v = velocities(sc);
    std::printf(
        "[ measure ] 1 m sphere on a 1e-4 m sphere: tiny at y = %.4g m, big at y = %.6g m "
        "(physical: 1.0002), speeds %.3g / %.3g m/s\n",
        p[0].y(), p[1].y(), v[0].norm(), v[1].norm());
    EXPECT_GT(p[0].y(), 1e-4 - kRestingOverlap);
    EXPECT_GT(p[1].y(), 1.0 - kRestingOverlap);
    EXPECT_LT(v[0].norm(), 0.05f);
    EXPECT_LT(v[1].norm(), 0.05f);
  }
}

// ---------------------------------------------------------------------------------
// Test 6. 1000 spheres (r 0.5 m, no gravity) created at one point. Every pair is
// a contact with the fallback normal +y, and each body is in 999 contacts, so
// mass splitting gives each contact 1/1998 of its target per iteration. All
// normals are +-y, so the spheres spread along the y axis only (x, z exact) into
// a column; its final length is 999 m (touching), reached over many steps. The
// broad phase sees all boxes in one cell: 499,500 pairs, so this is also the
// worst case of the grid (runtime printed).
// ---------------------------------------------------------------------------------
TEST_P(Extremes, ThousandSpheresAtOnePoint) {
  const uint32_t n = 1000;
  const int steps = test::kSanitized ? 4 : 10;
  std::vector<BodyDesc> b(n);
  for (BodyDesc& x : b) x.position = {2.0f, 3.0f, 4.0f};
  Scene sc = make_bodies(test::zero_gravity_desc(), b);
  const auto t0 = std::chrono::steady_clock::now();
  float prev_span = 0.0f;
  for (int k = 0; k < steps; ++k) {
    ASSERT_TRUE(test::IsOk(sc.world->step()));
    expect_all_finite(sc);
    const BodyArrays a = sc.world->bodies();
    float lo = a.pos_y[0], hi = a.pos_y[0];
    for (size_t i = 0; i < a.size(); ++i) {
      ASSERT_EQ(a.pos_x[i], 2.0f);
      ASSERT_EQ(a.pos_z[i], 4.0f);
      lo = std::min(lo, a.pos_y[i]);
      hi = std::max(hi, a.pos_y[i]);
    }
    if (k == 0) {
      const PassTimes& t = sc.world->last_step().ms;
      std::printf(
          "[ measure ] 1000 spheres at one point, first step: %.1f ms (broad phase %.1f, narrow %.1f, "
          "solve %.1f)\n",
          t.total, t.broad_phase, t.narrow_phase, t.solve);
      EXPECT_EQ(sc.world->last_step().pairs, uint64_t{n} * (n - 1) / 2);
      EXPECT_EQ(sc.world->last_step().contacts, uint64_t{n} * (n - 1) / 2);
    }
    // The column only grows.
    EXPECT_GE(hi - lo, prev_span) << "step " << k;
    prev_span = hi - lo;
  }
  const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  // Spread out: no two spheres left at the same point.
  std::vector<float> ys(sc.world->bodies().pos_y.begin(), sc.world->bodies().pos_y.end());
  std::sort(ys.begin(), ys.end());
  float min_gap = 1e30f;
  for (size_t i = 1; i < ys.size(); ++i) min_gap = std::min(min_gap, ys[i] - ys[i - 1]);
  const double ke = [&] {
    double e = 0.0;
    for (const Eigen::Vector3f& v : velocities(sc)) e += 0.5 * v.squaredNorm();
    return e;
  }();
  std::printf(
      "[ measure ] 1000 spheres at one point: %d steps in %.0f ms (%.1f ms/step, %llu contacts/step at "
      "the end); column length %.4g m, smallest gap %.3g m, kinetic energy %.3g J\n",
      steps, ms, ms / steps, static_cast<unsigned long long>(sc.world->last_step().contacts), prev_span,
      min_gap, ke);
  EXPECT_GT(min_gap, 0.0f);
  EXPECT_GT(prev_span, 1.0f);
  if (soft()) {
    // Overlaps deeper than max_push_speed * dt take the recovery path (no energy);
    // the shallower ones are pushed at most at max_push_speed each, which a body in
    // several sums: no sphere may leave faster than twice that.
    double fastest = 0.0;
    for (const Eigen::Vector3f& v : velocities(sc)) fastest = std::max(fastest, double(v.norm()));
    std::printf("[ measure ] 1000 spheres at one point, soft step: fastest %.3g m/s\n", fastest);
    EXPECT_LT(fastest, 2.0 * SolverDesc{}.max_push_speed);
  } else {
    // Inelastic, zero approach speed: position correction adds no kinetic energy.
    EXPECT_EQ(ke, 0.0);
  }
}

INSTANTIATE_TEST_SUITE_P(Solvers, Extremes, ::testing::Values(SolverKind::kSoftStep, SolverKind::kJacobi),
                         [](const ::testing::TestParamInfo<SolverKind>& i) {
                           return i.param == SolverKind::kSoftStep ? "SoftStep" : "Jacobi";
                         });

}  // namespace
}  // namespace impact
