// Arc visibility of a firing solution (impact::arc_clear): a wall between shooter and
// target blocks the low arc but not the high one; chords follow the parabola; both
// backends agree; bad input.
#include <gtest/gtest.h>

#include <vector>

#include "impact/impact.h"
#include "support/test_support.h"

namespace impact::test {
namespace {

std::unique_ptr<RayScene> wall_scene(RayBackend backend, float height) {
  RaySceneDesc d;
  d.backend = backend;
  std::unique_ptr<RayScene> s;
  EXPECT_TRUE(IsOk(RayScene::create(d, &s)));
  // A wall in the plane x = 20 from y = 0 to `height`, z in [-50, 50]: two triangles.
  Eigen::Matrix3Xf v(3, 4);
  v.col(0) = Eigen::Vector3f(20, 0, -50);
  v.col(1) = Eigen::Vector3f(20, 0, 50);
  v.col(2) = Eigen::Vector3f(20, height, 50);
  v.col(3) = Eigen::Vector3f(20, height, -50);
  Eigen::Matrix<uint32_t, 3, Eigen::Dynamic> t(3, 2);
  t.col(0) = Eigen::Matrix<uint32_t, 3, 1>(0, 1, 2);
  t.col(1) = Eigen::Matrix<uint32_t, 3, 1>(0, 2, 3);
  MeshHandle h;
  EXPECT_TRUE(IsOk(s->add_mesh(v, t, 1u, &h)));
  EXPECT_TRUE(IsOk(s->commit()));
  return s;
}

TEST(RaycastFiring, WallBlocksLowArcOnly) {
  for (RayBackend b : {RayBackend::kLbvh, RayBackend::kEmbree}) {
    auto scene = wall_scene(b, 8.0f);
    FiringQuery q;
    q.origin = Eigen::Vector3f(0, 0.1f, 0);
    q.target = Eigen::Vector3f(40, 0.1f, 0);
    q.speed = 25.0f;
    FiringSolution sol;
    IMPACT_ASSERT_OK(firing_solutions({&q, 1}, {&sol, 1}));
    ASSERT_EQ(sol.count, 2u);
    // The low arc peaks below the wall top, the high arc well above it.
    const Eigen::Vector3f low_mid = trajectory_point(q, sol.shots[0], 0.5f * sol.shots[0].time);
    const Eigen::Vector3f high_mid = trajectory_point(q, sol.shots[1], 0.5f * sol.shots[1].time);
    ASSERT_LT(low_mid.y(), 8.0f);
    ASSERT_GT(high_mid.y(), 8.0f);
    const std::vector<FiringQuery> qs{q, q};
    const std::vector<FiringShot> shots{sol.shots[0], sol.shots[1]};
    std::vector<uint8_t> clear(2);
    ArcCheckDesc desc;
    desc.segments = 32;
    IMPACT_ASSERT_OK(arc_clear(*scene, qs, shots, desc, clear));
    EXPECT_EQ(clear[0], 0) << "low arc should hit the wall";
    EXPECT_EQ(clear[1], 1) << "high arc should clear the wall";
    // Masked out, the wall blocks nothing.
    desc.mask = 2u;
    IMPACT_ASSERT_OK(arc_clear(*scene, qs, shots, desc, clear));
    EXPECT_EQ(clear[0], 1);
  }
}

TEST(RaycastFiring, ChordsTrackTheParabola) {
  // A thin horizontal slab just under the apex of a vertical shot: with enough chords
  // the arc touches it; a slab above the apex is never touched.
  for (RayBackend b : {RayBackend::kLbvh, RayBackend::kEmbree}) {
    RaySceneDesc d;
    d.backend = b;
    std::unique_ptr<RayScene> s;
    IMPACT_ASSERT_OK(RayScene::create(d, &s));
    FiringQuery q;
    q.speed = 10.0f;
    q.target = Eigen::Vector3f(1.0f, 0, 0);
    FiringSolution sol;
    IMPACT_ASSERT_OK(firing_solutions({&q, 1}, {&sol, 1}));
    ASSERT_EQ(sol.count, 2u);
    const FiringShot high = sol.shots[1];
    Eigen::Vector3f apex = Eigen::Vector3f::Zero();
    for (int k = 0; k <= 1000; ++k) {
      const Eigen::Vector3f p = trajectory_point(q, high, high.time * static_cast<float>(k) / 1000.0f);
      if (p.y() > apex.y()) apex = p;
    }
    for (float dy : {-0.05f, 0.05f}) {
      // A ball of radius 0.2 whose lowest point is dy above the apex.
      const std::vector<float> x{apex.x()}, y{apex.y() + dy + 0.2f}, z{apex.z()}, r{0.2f};
      IMPACT_ASSERT_OK(s->set_spheres(x, y, z, r));
      IMPACT_ASSERT_OK(s->commit());
      ArcCheckDesc desc;
      desc.segments = 64;  // chord sag |g| (T/64)^2 / 8 ~ 5e-4 m at T ~ 2 s
      uint8_t clear = 0;
      IMPACT_ASSERT_OK(arc_clear(*s, {&q, 1}, {&high, 1}, desc, {&clear, 1}));
      EXPECT_EQ(clear, dy < 0.0f ? 0 : 1) << "dy " << dy;
    }
  }
}

TEST(RaycastFiring, BadInput) {
  auto scene = wall_scene(RayBackend::kLbvh, 1.0f);
  FiringQuery q;
  FiringShot shot;
  uint8_t clear = 0;
  ArcCheckDesc desc;
  desc.segments = 0;
  EXPECT_TRUE(IsError(arc_clear(*scene, {&q, 1}, {&shot, 1}, desc, {&clear, 1}), StatusCode::kInvalidArgument, {"segments"}));
  desc = ArcCheckDesc{};
  desc.skip_start = 0.7f;
  desc.skip_end = 0.4f;
  EXPECT_TRUE(IsError(arc_clear(*scene, {&q, 1}, {&shot, 1}, desc, {&clear, 1}), StatusCode::kInvalidArgument, {"skip"}));
  desc = ArcCheckDesc{};
  q.speed = -1.0f;
  EXPECT_TRUE(IsError(arc_clear(*scene, {&q, 1}, {&shot, 1}, desc, {&clear, 1}), StatusCode::kInvalidArgument, {"query 0", "speed"}));
}

}  // namespace
}  // namespace impact::test
