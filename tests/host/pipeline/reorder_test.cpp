// Spatial re-sort of body storage (WorldImpl::reorder_bodies, host/pipeline/step.cpp;
// WorldDesc::reorder_interval). A re-sort "changes slots, never handles": seen
// through handles, a world that re-sorts must behave like one that never does.
//
// Exactness argument for the stack scenes below: every body has at most two
// contacts, so each body's impulse sum has at most two terms and is the same in
// either order; swapping a contact's a and b negates its normal exactly
// (IEEE subtraction is sign-symmetric) and with it the side signs, so every
// impulse, velocity and position is bit-identical whatever the slot order.
// Any difference therefore comes from state lost in the re-sort, such as warm-
// starting impulses that no longer find their contact.
#include <gtest/gtest.h>

#include <random>
#include <vector>

#include "impact/impact.h"
#include "support/test_support.h"

namespace impact {
namespace {

struct State {
  std::vector<Eigen::Vector3f> p, v;
};

// A vertical stack of n spheres on a floor, created top first (so the grid's
// spatial order, bottom first, reverses the slots), stepped `steps` times.
State run_stack(uint32_t reorder_interval, int n, float gap, int steps, bool top_first = true) {
  WorldDesc d;
  d.reorder_interval = reorder_interval;
  auto world = test::make_world(d);
  State s;
  if (!world) return s;
  PlaneDesc floor;
  PlaneHandle ph;
  EXPECT_TRUE(test::IsOk(world->create_planes(std::span(&floor, 1), std::span(&ph, 1))));
  std::vector<BodyDesc> bodies(n);
  for (int i = 0; i < n; ++i) {
    const int level = top_first ? n - 1 - i : i;
    bodies[i].position = {0.0f, 0.5f + static_cast<float>(level) * (1.0f + gap), 0.0f};
  }
  std::vector<BodyHandle> h(n);
  EXPECT_TRUE(test::IsOk(world->create_bodies(bodies, h)));
  for (int k = 0; k < steps; ++k) EXPECT_TRUE(test::IsOk(world->step()));
  s.p.resize(n);
  s.v.resize(n);
  EXPECT_TRUE(test::IsOk(world->get_positions(h, s.p)));
  EXPECT_TRUE(test::IsOk(world->get_velocities(h, s.v)));
  // The re-sort really happened (or not) as configured.
  if (reorder_interval == 1) {
    uint32_t slot = 0;
    EXPECT_TRUE(test::IsOk(world->slot_of(h[top_first ? 0 : n - 1], &slot)));
    EXPECT_EQ(slot, static_cast<uint32_t>(n - 1)) << "the top body should be last in spatial order";
  }
  return s;
}

void expect_same(const State& a, const State& b, const char* what) {
  ASSERT_EQ(a.p.size(), b.p.size());
  for (size_t i = 0; i < a.p.size(); ++i) {
    EXPECT_EQ(a.p[i], b.p[i]) << what << ": position of body " << i << " (" << a.p[i].y() << " vs "
                              << b.p[i].y() << ")";
    EXPECT_EQ(a.v[i], b.v[i]) << what << ": velocity of body " << i << " (" << a.v[i].y() << " vs "
                              << b.v[i].y() << ")";
  }
}

TEST(Reorder, IdentityOrderChangesNothing) {
  // Created bottom first: the spatial order is the creation order.
  const State never = run_stack(0, 5, 0.0f, 100, false);
  expect_same(never, run_stack(1, 5, 0.0f, 100, false), "re-sort every step");
  expect_same(never, run_stack(32, 5, 0.0f, 100, false), "re-sort every 32 steps");
}

TEST(Reorder, ReversedOrderIsInvisibleThroughHandles) {
  // Created top first: the first re-sort reverses every slot.
  for (float gap : {0.0f, 0.05f}) {
    SCOPED_TRACE(gap);
    const State never = run_stack(0, 5, gap, 100);
    expect_same(never, run_stack(32, 5, gap, 100), "re-sort every 32 steps");
    expect_same(never, run_stack(1, 5, gap, 100), "re-sort every step");
  }
}

TEST(Reorder, SlotsAndHandlesStayConsistentInALargeScene) {
  WorldDesc d = test::zero_gravity_desc();
  d.reorder_interval = 3;
  auto world = test::make_world(d);
  std::mt19937 rng(1);
  std::uniform_real_distribution<float> pos(-20.0f, 20.0f), vel(-1.0f, 1.0f);
  std::vector<BodyDesc> bodies(test::scaled(5000));
  for (auto& b : bodies) {
    b.position = {pos(rng), pos(rng), pos(rng)};
    b.velocity = {vel(rng), vel(rng), vel(rng)};
    b.radius = 0.1f;  // sparse: almost no contacts, so motion is ballistic
  }
  std::vector<BodyHandle> h(bodies.size());
  IMPACT_ASSERT_OK(world->create_bodies(bodies, h));
  for (int k = 0; k < 10; ++k) IMPACT_ASSERT_OK(world->step());
  const BodyArrays b = world->bodies();
  size_t moved = 0;
  for (size_t i = 0; i < h.size(); ++i) {
    uint32_t slot = 0;
    IMPACT_ASSERT_OK(world->slot_of(h[i], &slot));
    ASSERT_EQ(b.handles[slot], h[i]);
    moved += slot != i;
    // Radius and velocity travelled with the body (no contacts for most of them).
    EXPECT_EQ(b.radius[slot], 0.1f);
  }
  EXPECT_GT(moved, h.size() / 2) << "the scene should have been re-sorted";
}

TEST(Reorder, EveryBodyFieldTravelsWithItsBody) {
  // Each body gets its own value of every per-body field (mass, radius, restitution,
  // layer, mask, shape, orientation, and the interpolation's previous position); far
  // apart and without gravity nothing collides, so after re-sorts every field read back
  // through the body's handle must be the one it was created with.
  WorldDesc d = test::zero_gravity_desc();
  d.reorder_interval = 1;
  d.interpolation = true;
  auto world = test::make_world(d);
  ShapeId box;
  IMPACT_ASSERT_OK(world->shapes().add_box(Eigen::Vector3f(0.1f, 0.1f, 0.1f), &box));
  const uint32_t n = 400;
  std::vector<BodyDesc> bodies(n);
  for (uint32_t i = 0; i < n; ++i) {
    BodyDesc& b = bodies[i];
    // Created in reverse spatial order, so the grid's order permutes every slot.
    b.position = {static_cast<float>(n - i) * 2.0f, 0.0f, 0.0f};
    b.inv_mass = 1.0f + static_cast<float>(i);
    b.radius = 0.2f + 0.001f * static_cast<float>(i);
    b.restitution = static_cast<float>(i) / static_cast<float>(n);
    b.layer = 1u << (i % 31);
    b.mask = ~(1u << (i % 29));
    if (i % 3 == 0) {
      b.shape = box;
      b.orientation = Eigen::Quaternionf(Eigen::AngleAxisf(0.01f * static_cast<float>(i), Eigen::Vector3f::UnitZ()));
    }
  }
  std::vector<BodyHandle> h(n);
  IMPACT_ASSERT_OK(world->create_bodies(bodies, h));
  for (int k = 0; k < 3; ++k) IMPACT_ASSERT_OK(world->step());
  IMPACT_ASSERT_OK(world->advance(0.5f * d.fixed_dt));  // no step: alpha 0.5
  std::vector<Eigen::Vector3f> interp(n);
  IMPACT_ASSERT_OK(world->interpolated_positions(interp));
  const BodyArrays b = world->bodies();
  ASSERT_EQ(b.shape.size(), n);
  size_t moved = 0;
  for (uint32_t i = 0; i < n; ++i) {
    uint32_t slot = 0;
    IMPACT_ASSERT_OK(world->slot_of(h[i], &slot));
    moved += slot != i;
    const BodyDesc& e = bodies[i];
    EXPECT_EQ(b.inv_mass[slot], e.inv_mass) << i;
    EXPECT_EQ(b.restitution[slot], e.restitution) << i;
    EXPECT_EQ(b.layer[slot], e.layer) << i;
    EXPECT_EQ(b.mask[slot], e.mask) << i;
    EXPECT_EQ(b.shape[slot], i % 3 == 0 ? box.index : BodyArrays::kSphereBody) << i;
    if (i % 3 != 0) {
      EXPECT_EQ(b.radius[slot], e.radius) << i;
    }
    const Eigen::Quaternionf q = e.orientation.normalized();
    EXPECT_EQ(b.qx[slot], q.x()) << i;
    EXPECT_EQ(b.qz[slot], q.z()) << i;
    EXPECT_EQ(b.qw[slot], q.w()) << i;
    // At rest: the previous position is the position, so the blend is it exactly.
    EXPECT_EQ(interp[slot].x(), e.position.x()) << i;
    EXPECT_EQ(b.pos_x[slot], e.position.x()) << i;
  }
  EXPECT_GT(moved, n / 2) << "the scene should have been re-sorted";
}

}  // namespace
}  // namespace impact
