// Resting contact sanity of the whole step: a single ball on a floor, and a
// vertical stack of 5 equal spheres on a floor plane, under default gravity and
// solver settings. After 300 steps (5 s) each body should be at rest (speed
// below 0.05 m/s, about a third of the g dt = 0.16 m/s a body gains per step, so
// the solver must cancel nearly all of each step's gravity) and no overlap may
// exceed 5% of the radius. The stack stays aligned on its axis: no contact
// normal has a horizontal component.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "impact/impact.h"
#include "support/test_support.h"

namespace impact {
namespace {

constexpr float kRadius = 0.5f;
constexpr float kMaxSpeed = 0.05f;              // m/s
constexpr float kMaxOverlap = 0.05f * kRadius;  // m

struct Stack {
  std::unique_ptr<World> world;
  std::vector<BodyHandle> h;
};

Stack make_stack(int n, float gap) {
  Stack s;
  s.world = test::make_world(WorldDesc{});
  PlaneDesc floor;  // y = 0
  PlaneHandle ph;
  EXPECT_TRUE(test::IsOk(s.world->create_planes(std::span(&floor, 1), std::span(&ph, 1))));
  std::vector<BodyDesc> d(n);
  for (int i = 0; i < n; ++i) {
    d[i].position = {0.0f, kRadius + static_cast<float>(i) * (2.0f * kRadius + gap), 0.0f};
    d[i].radius = kRadius;
    d[i].inv_mass = 1.0f;
    d[i].restitution = 0.0f;
  }
  s.h.resize(n);
  EXPECT_TRUE(test::IsOk(s.world->create_bodies(d, s.h)));
  return s;
}

void expect_settled(const Stack& s, const char* what) {
  SCOPED_TRACE(what);
  const size_t n = s.h.size();
  std::vector<Eigen::Vector3f> p(n), v(n);
  IMPACT_ASSERT_OK(s.world->get_positions(s.h, p));
  IMPACT_ASSERT_OK(s.world->get_velocities(s.h, v));
  for (size_t i = 0; i < n; ++i) {
    EXPECT_LT(v[i].norm(), kMaxSpeed) << "body " << i << " speed";
    EXPECT_EQ(p[i].x(), 0.0f) << "body " << i << " drifted sideways";
    EXPECT_EQ(p[i].z(), 0.0f) << "body " << i << " drifted sideways";
  }
  EXPECT_LT(kRadius - p[0].y(), kMaxOverlap) << "floor overlap " << kRadius - p[0].y();
  for (size_t i = 1; i < n; ++i) {
    const float overlap = 2.0f * kRadius - (p[i].y() - p[i - 1].y());
    EXPECT_LT(overlap, kMaxOverlap) << "overlap between " << i - 1 << " and " << i << ": " << overlap;
    EXPECT_GT(p[i].y(), p[i - 1].y()) << "stack order";
  }
}

TEST(Stacking, SingleBallRestsOnFloor) {
  Stack s = make_stack(1, 0.0f);
  for (int k = 0; k < 300; ++k) IMPACT_ASSERT_OK(s.world->step());
  expect_settled(s, "one ball");
  EXPECT_EQ(s.world->last_step().plane_contacts, 1u);
}

TEST(Stacking, FiveSphereStackSettles) {
  Stack s = make_stack(5, 0.0f);  // just touching
  for (int k = 0; k < 300; ++k) IMPACT_ASSERT_OK(s.world->step());
  expect_settled(s, "stack of 5 placed touching");
}

TEST(Stacking, FiveSphereStackDroppedSettles) {
  Stack s = make_stack(5, 0.05f);  // small gaps: they land on each other
  for (int k = 0; k < 300; ++k) IMPACT_ASSERT_OK(s.world->step());
  expect_settled(s, "stack of 5 dropped from 5 cm gaps");
}

}  // namespace
}  // namespace impact
