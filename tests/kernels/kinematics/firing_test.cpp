// The firing solution (kernels/kinematics/firing.h, include/impact/firing.h): every
// returned shot, integrated analytically in double, passes the target within the
// stated tolerance at the stated time with the stated speed; the count (0, 1, 2) agrees
// with an independent range test; special cases (straight up/down, g = 0, target at the
// origin, exactly at maximum range) and bad input.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include <Eigen/Geometry>

#include "impact/impact.h"
#include "kernels/kinematics/firing.h"
#include "support/test_support.h"

namespace impact::test {
namespace {

// Position at t by the closed form, in double.
Eigen::Vector3d arc(const FiringQuery& q, const FiringShot& s, double t) {
  return q.origin.cast<double>() + static_cast<double>(q.speed) * s.direction.cast<double>() * t +
         0.5 * q.gravity.cast<double>() * t * t;
}

// Independent range test: the target is reachable iff some launch angle works. For
// gravity g (|g| > 0) along -up, with horizontal distance x and height y of the target
// relative to the origin, reachable iff s^4 >= |g| (|g| x^2 + 2 y s^2).
bool reachable(const FiringQuery& q) {
  const Eigen::Vector3d g = q.gravity.cast<double>();
  const Eigen::Vector3d d = (q.target - q.origin).cast<double>();
  const double gl = g.norm();
  if (gl == 0.0) return true;
  const Eigen::Vector3d up = -g / gl;
  const double y = d.dot(up);
  const double x = (d - y * up).norm();
  const double s2 = static_cast<double>(q.speed) * q.speed;
  return s2 * s2 >= gl * (gl * x * x + 2.0 * y * s2);
}

double tolerance(const FiringQuery& q, const FiringShot& s) {
  const double dist = (q.target - q.origin).cast<double>().norm();
  return 1e-5 * std::max({1.0, dist, static_cast<double>(q.speed) * s.time});
}

void expect_hits(const FiringQuery& q, const FiringSolution& sol, const std::string& what) {
  for (uint32_t k = 0; k < sol.count; ++k) {
    const FiringShot& s = sol.shots[k];
    EXPECT_NEAR(s.direction.norm(), 1.0f, 1e-6f) << what;
    EXPECT_GE(s.time, 0.0f) << what;
    const double miss = (arc(q, s, s.time) - q.target.cast<double>()).norm();
    EXPECT_LE(miss, tolerance(q, s)) << what << " shot " << k << " misses by " << miss << " m";
    // Public helper agrees with the closed form.
    EXPECT_LE((trajectory_point(q, s, s.time).cast<double>() - arc(q, s, s.time)).norm(), tolerance(q, s));
  }
  if (sol.count == 2) {
    EXPECT_LE(sol.shots[0].time, sol.shots[1].time) << what << ": low arc first";
  }
}

TEST(Firing, RandomTargetsHitOrAreOutOfRange) {
  std::mt19937 rng(1);
  std::uniform_real_distribution<float> pos(-100.0f, 100.0f), speed(5.0f, 60.0f), u01(0.0f, 1.0f);
  const uint32_t n = scaled(20000);
  std::vector<FiringQuery> qs(n);
  for (uint32_t i = 0; i < n; ++i) {
    qs[i].origin = Eigen::Vector3f(pos(rng), pos(rng), pos(rng));
    qs[i].target = qs[i].origin + 0.5f * Eigen::Vector3f(pos(rng), pos(rng), pos(rng));
    qs[i].speed = speed(rng);
    // Mostly -y gravity; some tilted, some strong, some far from the origin.
    if (i % 5 == 0) qs[i].gravity = Eigen::Vector3f(pos(rng), pos(rng), pos(rng)) * 0.2f;
    if (i % 11 == 0) {
      qs[i].origin += Eigen::Vector3f(1e4f, 0, 1e4f);
      qs[i].target += Eigen::Vector3f(1e4f, 0, 1e4f);
    }
  }
  std::vector<FiringSolution> sol(n);
  IMPACT_ASSERT_OK(firing_solutions(qs, sol));
  uint32_t counts[3] = {0, 0, 0};
  for (uint32_t i = 0; i < n; ++i) {
    ASSERT_LE(sol[i].count, 2u);
    ++counts[sol[i].count];
    const bool r = reachable(qs[i]);
    // Away from the edge of range, the count follows the independent test.
    const Eigen::Vector3d g = qs[i].gravity.cast<double>();
    const double s2 = static_cast<double>(qs[i].speed) * qs[i].speed;
    const Eigen::Vector3d d = (qs[i].target - qs[i].origin).cast<double>();
    const double edge = std::fabs((d.dot(g) + s2) * (d.dot(g) + s2) - g.squaredNorm() * d.squaredNorm()) /
                        ((std::fabs(d.dot(g)) + s2) * (std::fabs(d.dot(g)) + s2));
    if (edge > 1e-6) {
      EXPECT_EQ(sol[i].count > 0, r) << "query " << i;
      if (r && g.squaredNorm() > 0.0) {
        EXPECT_EQ(sol[i].count, 2u) << "query " << i;
      }
    }
    expect_hits(qs[i], sol[i], "query " + std::to_string(i));
  }
  EXPECT_GT(counts[0], n / 20);  // some out of range
  EXPECT_GT(counts[2], n / 2);
}

TEST(Firing, MaximumRangeGivesOneShotAt45Degrees) {
  // Flat ground, g = 9.81: maximum range s^2 / g at 45 degrees.
  FiringQuery q;
  q.speed = 20.0f;
  const double range = 20.0 * 20.0 / 9.81;
  q.target = Eigen::Vector3f(static_cast<float>(range), 0, 0);
  FiringSolution s;
  IMPACT_ASSERT_OK(firing_solutions({&q, 1}, {&s, 1}));
  ASSERT_GE(s.count, 1u);
  // Float rounding of the target puts it a hair inside or outside: one shot, or two
  // nearly equal ones, both at 45 degrees.
  for (uint32_t k = 0; k < s.count; ++k)
    EXPECT_NEAR(std::atan2(s.shots[k].direction.y(), s.shots[k].direction.x()), M_PI / 4, 2e-3);
  expect_hits(q, s, "max range");
  // 1 mm further: out of range.
  q.target.x() += 1e-3f;
  IMPACT_ASSERT_OK(firing_solutions({&q, 1}, {&s, 1}));
  EXPECT_EQ(s.count, 0u);
  // The kernel's double root: exactly at the edge of the discriminant.
  kernels::FiringProblem p{{0, 0, 0}, {0, 0, 0}, {0, -8, 0}, 4.0f};
  p.target[0] = 2.0f;  // s^2 / g = 16 / 8 = 2, exact in float
  const kernels::FiringResult r = kernels::firing_solution(p);
  ASSERT_EQ(r.count, 1u);
  EXPECT_NEAR(r.shots[0].dir[0], std::sqrt(0.5f), 1e-6f);
  EXPECT_NEAR(r.shots[0].dir[1], std::sqrt(0.5f), 1e-6f);
}

TEST(Firing, StraightUpAndDown) {
  FiringQuery up;
  up.speed = 10.0f;
  up.target = Eigen::Vector3f(0, 3, 0);  // below the apex s^2 / 2g = 5.1 m: two shots, both up
  FiringSolution s;
  IMPACT_ASSERT_OK(firing_solutions({&up, 1}, {&s, 1}));
  ASSERT_EQ(s.count, 2u);
  for (int k = 0; k < 2; ++k) EXPECT_TRUE(s.shots[k].direction.isApprox(Eigen::Vector3f(0, 1, 0), 1e-5f));
  expect_hits(up, s, "up");
  up.target.y() = 6.0f;  // above the apex
  IMPACT_ASSERT_OK(firing_solutions({&up, 1}, {&s, 1}));
  EXPECT_EQ(s.count, 0u);
  FiringQuery down = up;
  down.target = Eigen::Vector3f(0, -20, 0);
  IMPACT_ASSERT_OK(firing_solutions({&down, 1}, {&s, 1}));
  ASSERT_EQ(s.count, 2u);
  EXPECT_TRUE(s.shots[0].direction.isApprox(Eigen::Vector3f(0, -1, 0), 1e-5f));  // straight down first
  EXPECT_TRUE(s.shots[1].direction.isApprox(Eigen::Vector3f(0, 1, 0), 1e-5f));   // up and back down
  expect_hits(down, s, "down");
}

TEST(Firing, ZeroGravityAndTargetAtOrigin) {
  FiringQuery q;
  q.gravity = Eigen::Vector3f::Zero();
  q.speed = 4.0f;
  q.origin = Eigen::Vector3f(1, 2, 3);
  q.target = Eigen::Vector3f(5, 2, 6);  // 5 m away
  FiringSolution s;
  IMPACT_ASSERT_OK(firing_solutions({&q, 1}, {&s, 1}));
  ASSERT_EQ(s.count, 1u);
  EXPECT_NEAR(s.shots[0].time, 1.25f, 1e-6f);
  EXPECT_TRUE(s.shots[0].direction.isApprox(Eigen::Vector3f(0.8f, 0, 0.6f), 1e-6f));
  expect_hits(q, s, "g = 0");
  q.target = q.origin;
  IMPACT_ASSERT_OK(firing_solutions({&q, 1}, {&s, 1}));
  ASSERT_EQ(s.count, 1u);
  EXPECT_EQ(s.shots[0].time, 0.0f);
  EXPECT_TRUE(s.shots[0].direction.isApprox(Eigen::Vector3f(0, 1, 0)));
  q.gravity = Eigen::Vector3f(0, 0, -9.81f);
  IMPACT_ASSERT_OK(firing_solutions({&q, 1}, {&s, 1}));
  ASSERT_EQ(s.count, 1u);
  EXPECT_TRUE(s.shots[0].direction.isApprox(Eigen::Vector3f(0, 0, 1)));
}

TEST(Firing, BadInputIsRejected) {
  std::vector<FiringQuery> q(3);
  std::vector<FiringSolution> s(3);
  q[2].speed = 0.0f;
  EXPECT_TRUE(IsError(firing_solutions(q, s), StatusCode::kInvalidArgument, {"firing query 2", "speed"}));
  q[2].speed = 1.0f;
  q[1].target.x() = std::nanf("");
  EXPECT_TRUE(IsError(firing_solutions(q, s), StatusCode::kInvalidArgument, {"firing query 1", "target"}));
  q[1].target.x() = 0.0f;
  q[0].gravity.y() = std::numeric_limits<float>::infinity();
  EXPECT_TRUE(IsError(firing_solutions(q, s), StatusCode::kInvalidArgument, {"firing query 0", "gravity"}));
  q[0].gravity.y() = -9.81f;
  s.pop_back();
  EXPECT_TRUE(IsError(firing_solutions(q, s), StatusCode::kSizeMismatch));
}

}  // namespace
}  // namespace impact::test
