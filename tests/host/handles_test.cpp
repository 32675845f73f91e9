// Body handles (host/handle_table.h through World): destroy then create reuses
// the index with a new generation, the old handle goes stale, and swap-remove
// keeps every other handle valid and pointing at its own body. A randomized
// churn is checked against a plain std::map model of handle -> position.
#include <gtest/gtest.h>

#include <algorithm>
#include <limits>
#include <map>
#include <random>
#include <set>
#include <vector>

#include "impact/impact.h"
#include "support/test_support.h"

namespace impact {
namespace {

constexpr float kNaNf = std::numeric_limits<float>::quiet_NaN();

BodyDesc at(float x, float y = 0.0f) {
  BodyDesc d;
  d.position = {x, y, 0.0f};
  d.radius = 0.1f;  // far apart: no contacts disturb the positions
  return d;
}

Eigen::Vector3f position(const World& w, BodyHandle h) {
  Eigen::Vector3f p(kNaNf, kNaNf, kNaNf);
  EXPECT_TRUE(test::IsOk(w.get_positions(std::span(&h, 1), std::span(&p, 1))));
  return p;
}

TEST(Handles, NeverNullAndDistinct) {
  auto w = test::make_world(test::zero_gravity_desc());
  std::vector<BodyDesc> d;
  for (int i = 0; i < 100; ++i) d.push_back(at(static_cast<float>(i)));
  std::vector<BodyHandle> h(d.size());
  IMPACT_ASSERT_OK(w->create_bodies(d, h));
  std::set<std::pair<uint32_t, uint32_t>> seen;
  for (size_t i = 0; i < h.size(); ++i) {
    EXPECT_FALSE(h[i].is_null());
    EXPECT_TRUE(seen.insert({h[i].index, h[i].generation}).second);
    EXPECT_EQ(w->bodies().handles[i], h[i]);
  }
  EXPECT_TRUE(BodyHandle{}.is_null());
}

TEST(Handles, DestroyThenCreateReusesIndexWithNewGeneration) {
  auto w = test::make_world(test::zero_gravity_desc());
  std::vector<BodyDesc> d{at(0), at(1), at(2)};
  std::vector<BodyHandle> h(3);
  IMPACT_ASSERT_OK(w->create_bodies(d, h));
  const BodyHandle old = h[1];
  IMPACT_ASSERT_OK(w->destroy_bodies(std::span(&old, 1)));
  EXPECT_EQ(w->body_count(), 2u);
  BodyDesc n = at(7);
  BodyHandle fresh;
  IMPACT_ASSERT_OK(w->create_bodies(std::span(&n, 1), std::span(&fresh, 1)));
  EXPECT_EQ(fresh.index, old.index);
  EXPECT_NE(fresh.generation, old.generation);
  EXPECT_FALSE(fresh.is_null());
  // The old handle is stale, the new one reaches the new body.
  Eigen::Vector3f p;
  EXPECT_TRUE(
      test::IsError(w->get_positions(std::span(&old, 1), std::span(&p, 1)), StatusCode::kStaleHandle));
  EXPECT_EQ(position(*w, fresh), Eigen::Vector3f(7, 0, 0));
  EXPECT_EQ(position(*w, h[0]), Eigen::Vector3f(0, 0, 0));
  EXPECT_EQ(position(*w, h[2]), Eigen::Vector3f(2, 0, 0));
  // Destroying the same index again moves the generation on again.
  IMPACT_ASSERT_OK(w->destroy_bodies(std::span(&fresh, 1)));
  BodyHandle third;
  IMPACT_ASSERT_OK(w->create_bodies(std::span(&n, 1), std::span(&third, 1)));
  EXPECT_EQ(third.index, old.index);
  EXPECT_NE(third.generation, fresh.generation);
  EXPECT_NE(third.generation, old.generation);
}

TEST(Handles, SwapRemoveKeepsOtherHandlesValid) {
  auto w = test::make_world(test::zero_gravity_desc());
  std::vector<BodyDesc> d;
  for (int i = 0; i < 6; ++i) d.push_back(at(static_cast<float>(i) * 10.0f, static_cast<float>(i)));
  std::vector<BodyHandle> h(6);
  IMPACT_ASSERT_OK(w->create_bodies(d, h));
  // Slot 0 and the last slot in one call: the first removal moves the last body
  // into slot 0, so the second must be found at its new slot.
  std::vector<BodyHandle> gone{h[0], h[5]};
  IMPACT_ASSERT_OK(w->destroy_bodies(gone));
  EXPECT_EQ(w->body_count(), 4u);
  for (int i = 1; i < 5; ++i) {
    EXPECT_EQ(position(*w, h[i]), d[i].position) << i;
    uint32_t slot;
    IMPACT_ASSERT_OK(w->slot_of(h[i], &slot));
    EXPECT_EQ(w->bodies().handles[slot], h[i]);
    EXPECT_EQ(w->bodies().pos_x[slot], d[i].position.x());
  }
  // Velocities and other fields moved with their bodies too.
  std::vector<Eigen::Vector3f> v{{1, 2, 3}};
  IMPACT_ASSERT_OK(w->set_velocities(std::span(&h[4], 1), v));
  IMPACT_ASSERT_OK(w->destroy_bodies(std::span(&h[1], 1)));
  std::vector<Eigen::Vector3f> got(1);
  IMPACT_ASSERT_OK(w->get_velocities(std::span(&h[4], 1), got));
  EXPECT_EQ(got[0], v[0]);
}

TEST(Handles, RandomChurnMatchesModel) {
  WorldDesc desc = test::zero_gravity_desc();
  desc.interpolation = true;  // its prev arrays swap-remove too
  auto w = test::make_world(desc);
  std::mt19937 rng(1);
  struct Key {
    uint32_t index, generation;
    bool operator<(const Key& o) const {
      return index != o.index ? index < o.index : generation < o.generation;
    }
  };
  std::map<Key, Eigen::Vector3f> live;
  std::vector<BodyHandle> dead;
  float next_x = 0.0f;
  const int rounds = static_cast<int>(test::scaled(300));
  for (int round = 0; round < rounds; ++round) {
    // Create a few.
    std::vector<BodyDesc> d(rng() % 5);
    for (auto& b : d) b = at(next_x += 1.0f, static_cast<float>(round));
    std::vector<BodyHandle> h(d.size());
    IMPACT_ASSERT_OK(w->create_bodies(d, h));
    for (size_t i = 0; i < h.size(); ++i) {
      ASSERT_TRUE(live.emplace(Key{h[i].index, h[i].generation}, d[i].position).second) << "handle reissued";
      for (const BodyHandle& x : dead) ASSERT_FALSE(x == h[i]) << "a dead handle came back";
    }
    // Destroy a random subset in random order.
    std::vector<BodyHandle> kill;
    for (const auto& [k, p] : live)
      if (rng() % 3 == 0) kill.push_back({k.index, k.generation});
    std::shuffle(kill.begin(), kill.end(), rng);
    IMPACT_ASSERT_OK(w->destroy_bodies(kill));
    for (const BodyHandle& k : kill) {
      live.erase(Key{k.index, k.generation});
      dead.push_back(k);
    }
    // Occasionally step: resting bodies without gravity do not move.
    if (round % 10 == 0) {
      IMPACT_ASSERT_OK(w->step());
    }
    // Check the model.
    ASSERT_EQ(w->body_count(), live.size());
    const BodyArrays b = w->bodies();
    for (const auto& [k, p] : live) {
      const BodyHandle h1{k.index, k.generation};
      uint32_t slot;
      IMPACT_ASSERT_OK(w->slot_of(h1, &slot));
      ASSERT_LT(slot, b.size());
      ASSERT_EQ(b.handles[slot], h1);
      ASSERT_EQ(Eigen::Vector3f(b.pos_x[slot], b.pos_y[slot], b.pos_z[slot]), p);
    }
    if (!dead.empty()) {
      const BodyHandle d0 = dead[rng() % dead.size()];
      uint32_t slot;
      ASSERT_TRUE(test::IsError(w->slot_of(d0, &slot), StatusCode::kStaleHandle));
    }
  }
  std::vector<Eigen::Vector3f> interp(w->body_count());
  IMPACT_ASSERT_OK(w->interpolated_positions(interp));
  const BodyArrays b = w->bodies();
  for (size_t i = 0; i < b.size(); ++i)
    EXPECT_EQ(interp[i], Eigen::Vector3f(b.pos_x[i], b.pos_y[i], b.pos_z[i]));
}

TEST(Handles, PlaneHandlesReuseAndSwapRemove) {
  auto w = test::make_world(test::zero_gravity_desc());
  std::vector<PlaneDesc> p(3);
  p[0].normal = {1, 0, 0};
  p[1].normal = {0, 1, 0};
  p[2].normal = {0, 0, 1};
  p[2].offset = -5.0f;
  std::vector<PlaneHandle> h(3);
  IMPACT_ASSERT_OK(w->create_planes(p, h));
  IMPACT_ASSERT_OK(w->destroy_planes(std::span(&h[0], 1)));
  PlaneDesc q;
  PlaneHandle fresh;
  IMPACT_ASSERT_OK(w->create_planes(std::span(&q, 1), std::span(&fresh, 1)));
  EXPECT_EQ(fresh.index, h[0].index);
  EXPECT_NE(fresh.generation, h[0].generation);
  EXPECT_TRUE(test::IsError(w->destroy_planes(std::span(&h[0], 1)), StatusCode::kStaleHandle));
  // The moved plane (z = -5) still collides as itself: a sphere at z = -4.8 touches only it.
  BodyDesc b;
  b.position = {3, 3, -4.8f};
  BodyHandle bh;
  IMPACT_ASSERT_OK(w->create_bodies(std::span(&b, 1), std::span(&bh, 1)));
  IMPACT_ASSERT_OK(w->step());
  const ContactArrays c = w->contacts();
  ASSERT_EQ(c.size(), 1u);
  EXPECT_EQ(c.normal_z[0], -1.0f);
  EXPECT_NEAR(c.depth[0], 0.3f, 1e-6);
  IMPACT_ASSERT_OK(w->destroy_planes(std::span(&h[2], 1)));
  IMPACT_ASSERT_OK(w->step());
  EXPECT_EQ(w->contacts().size(), 0u);
}

}  // namespace
}  // namespace impact
