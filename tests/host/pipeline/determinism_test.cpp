// Determinism of the whole step (host/pipeline/step.cpp): a 10k-sphere scene in
// a box of 5 planes, with gravity, mixed radii, masses and restitution, stepped
// 200 times, gives a bit-identical state_hash() for every backend built in
// (serial, TBB, OpenMP) and thread counts 1, 2, 3 and 8. Hashes are compared at
// checkpoints along the run, so a failure says when the runs diverged.
// IMPACT_TEST_INTENSITY scales the body count; sanitizer builds run fewer steps
// (kSteps below).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include "impact/impact.h"
#include "support/test_support.h"

namespace impact {
namespace {

struct Scene {
  std::vector<BodyDesc> bodies;
  std::vector<PlaneDesc> planes;
};

Scene box_scene(uint32_t n, uint32_t seed) {
  Scene s;
  const float half = 0.55f * std::cbrt(static_cast<float>(n)) * 0.5f;  // box half-width, m
  // Floor and four walls; normals point into the box.
  const Eigen::Vector3f normals[5] = {{0, 1, 0}, {1, 0, 0}, {-1, 0, 0}, {0, 0, 1}, {0, 0, -1}};
  const float offsets[5] = {0.0f, -half, -half, -half, -half};
  for (int k = 0; k < 5; ++k) {
    PlaneDesc p;
    p.normal = normals[k];
    p.offset = offsets[k];
    p.restitution = k == 0 ? 0.2f : 0.5f;
    s.planes.push_back(p);
  }
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> xz(-half + 0.3f, half - 0.3f);
  std::uniform_real_distribution<float> y(0.3f, 4.0f * half);
  std::uniform_real_distribution<float> rad(0.08f, 0.25f);
  std::uniform_real_distribution<float> e(0.0f, 0.9f);
  std::uniform_real_distribution<float> w(0.2f, 3.0f);
  std::uniform_real_distribution<float> v(-2.0f, 2.0f);
  for (uint32_t i = 0; i < n; ++i) {
    BodyDesc b;
    b.position = {xz(rng), y(rng), xz(rng)};
    b.velocity = {v(rng), v(rng), v(rng)};
    b.radius = rad(rng);
    b.restitution = e(rng);
    b.inv_mass = i % 50 == 0 ? 0.0f : w(rng);  // a few static obstacles
    b.layer = 1u << (i % 3);
    b.mask = i % 7 == 0 ? 0x5u : 0xffffffffu;
    s.bodies.push_back(b);
  }
  return s;
}

struct RunResult {
  std::vector<uint64_t> hashes;  // at every checkpoint
  uint64_t contacts = 0;
  bool finite = true;
};

RunResult simulate(const Scene& scene, Backend backend, uint32_t threads, uint32_t steps, uint32_t every) {
  WorldDesc d;
  d.backend = backend;
  d.threads = threads;
  auto world = test::make_world(d);
  RunResult r;
  if (!world) return r;
  std::vector<PlaneHandle> ph(scene.planes.size());
  EXPECT_TRUE(test::IsOk(world->create_planes(scene.planes, ph)));
  std::vector<BodyHandle> bh(scene.bodies.size());
  EXPECT_TRUE(test::IsOk(world->create_bodies(scene.bodies, bh)));
  r.hashes.push_back(world->state_hash());
  for (uint32_t s = 1; s <= steps; ++s) {
    const Status st = world->step();
    if (!st.ok()) {
      ADD_FAILURE() << st.message();
      break;
    }
    if (s % every == 0 || s == steps) r.hashes.push_back(world->state_hash());
  }
  r.contacts = world->last_step().contacts;
  const BodyArrays b = world->bodies();
  for (size_t i = 0; i < b.size(); ++i)
    r.finite = r.finite && std::isfinite(b.pos_x[i]) && std::isfinite(b.pos_y[i]) &&
               std::isfinite(b.pos_z[i]) && std::isfinite(b.vel_x[i]) && std::isfinite(b.vel_y[i]) &&
               std::isfinite(b.vel_z[i]);
  return r;
}

// Under ASan + UBSan the run stops at 120 steps (~20k contacts by then): the
// sanitizers see every pass with contacts, and the Release suite checks the hashes of
// the landed pile at 200 (the highest sphere has fallen for 2.2 s by then; each of the
// nine runs takes tens of seconds on 2 cores with the rigid soft step).
constexpr uint32_t kSteps = test::kSanitized ? 120 : 200;

TEST(Determinism, SameHashForEveryBackendAndThreadCount) {
  const Scene scene = box_scene(test::scaled(10000, 100), 1);
  const uint32_t steps = kSteps, every = 20;
  const RunResult ref = simulate(scene, Backend::kSerial, 1, steps, every);
  ASSERT_GT(ref.hashes.size(), 2u);
  EXPECT_TRUE(ref.finite);
  EXPECT_GT(ref.contacts, scene.bodies.size() / 4) << "the scene should be a settled pile by now";
  EXPECT_NE(ref.hashes.front(), ref.hashes.back());
  std::printf("serial/1 final hash %016llx, %llu contacts\n",
              static_cast<unsigned long long>(ref.hashes.back()),
              static_cast<unsigned long long>(ref.contacts));
  for (const test::ExecCase& c : test::exec_cases()) {
    if (c.backend == Backend::kSerial) continue;
    const RunResult r = simulate(scene, c.backend, c.threads, steps, every);
    ASSERT_EQ(r.hashes.size(), ref.hashes.size()) << test::to_string(c);
    for (size_t k = 0; k < r.hashes.size(); ++k) {
      if (r.hashes[k] != ref.hashes[k]) {
        ADD_FAILURE() << test::to_string(c) << " diverges from serial by step "
                      << std::min(k * every, size_t{steps});
        break;
      }
    }
  }
}

TEST(Determinism, RepeatedRunsAndMidRunBackendSwitch) {
  const Scene scene = box_scene(test::scaled(3000, 100), 2);
  const uint32_t steps = 150;
  const RunResult a = simulate(scene, Backend::kDefault, 0, steps, steps);
  const RunResult b = simulate(scene, Backend::kDefault, 0, steps, steps);
  EXPECT_EQ(a.hashes, b.hashes);

  // Switching the runtime halfway through changes nothing.
  auto world = test::make_world(WorldDesc{});
  std::vector<PlaneHandle> ph(scene.planes.size());
  IMPACT_ASSERT_OK(world->create_planes(scene.planes, ph));
  std::vector<BodyHandle> bh(scene.bodies.size());
  IMPACT_ASSERT_OK(world->create_bodies(scene.bodies, bh));
  const std::vector<test::ExecCase> cases = test::exec_cases();
  for (uint32_t s = 0; s < steps; ++s) {
    const test::ExecCase& c = cases[s % cases.size()];
    IMPACT_ASSERT_OK(world->set_backend(c.backend, c.threads));
    IMPACT_ASSERT_OK(world->step());
  }
  EXPECT_EQ(world->state_hash(), a.hashes.back());
}

TEST(Determinism, StateHashCoversPositionsAndVelocities) {
  // The determinism checks rely on the hash seeing every state bit.
  auto world = test::make_world(test::zero_gravity_desc());
  BodyDesc d;
  BodyHandle h;
  IMPACT_ASSERT_OK(world->create_bodies(std::span(&d, 1), std::span(&h, 1)));
  const uint64_t h0 = world->state_hash();
  Eigen::Vector3f p(0, std::nextafter(0.0f, 1.0f), 0);
  IMPACT_ASSERT_OK(world->set_positions(std::span(&h, 1), std::span(&p, 1)));
  const uint64_t h1 = world->state_hash();
  EXPECT_NE(h1, h0);
  Eigen::Vector3f v(0, 0, -0.0f);  // -0 and +0 differ in bits
  IMPACT_ASSERT_OK(world->set_velocities(std::span(&h, 1), std::span(&v, 1)));
  EXPECT_NE(world->state_hash(), h1);
}

TEST(Determinism, StateHashCoversEveryBodyField) {
  // The hash walks the body field table (host/body_store.h): a world that differs from
  // another in any one field of one body, including the fields no step changes, hashes
  // differently; the same world built twice hashes the same.
  auto hash_of = [](auto&& edit, bool with_shape) {
    auto world = test::make_world(test::zero_gravity_desc());
    ShapeId box;
    EXPECT_TRUE(test::IsOk(world->shapes().add_box(Eigen::Vector3f(0.5f, 0.5f, 0.5f), &box)));
    std::vector<BodyDesc> d(3);
    for (int i = 0; i < 3; ++i) d[i].position = Eigen::Vector3f(3.0f * static_cast<float>(i), 0, 0);
    if (with_shape) d[2].shape = box;
    edit(d[1], box);
    std::vector<BodyHandle> h(d.size());
    EXPECT_TRUE(test::IsOk(world->create_bodies(d, h)));
    return world->state_hash();
  };
  const auto none = [](BodyDesc&, ShapeId) {};
  for (bool shaped : {false, true}) {
    SCOPED_TRACE(shaped ? "with a shaped body" : "spheres only");
    const uint64_t base = hash_of(none, shaped);
    EXPECT_EQ(hash_of(none, shaped), base);
    EXPECT_NE(hash_of([](BodyDesc& b, ShapeId) { b.inv_mass = 0.5f; }, shaped), base) << "inv_mass";
    EXPECT_NE(hash_of([](BodyDesc& b, ShapeId) { b.inv_mass = 0.0f; }, shaped), base) << "static";
    EXPECT_NE(hash_of([](BodyDesc& b, ShapeId) { b.radius = 0.75f; }, shaped), base) << "radius";
    EXPECT_NE(hash_of([](BodyDesc& b, ShapeId) { b.restitution = 0.25f; }, shaped), base) << "restitution";
    EXPECT_NE(hash_of([](BodyDesc& b, ShapeId) { b.layer = 2; }, shaped), base) << "layer";
    EXPECT_NE(hash_of([](BodyDesc& b, ShapeId) { b.mask = 5; }, shaped), base) << "mask";
    EXPECT_NE(hash_of([](BodyDesc& b, ShapeId) { b.friction = 0.3f; }, shaped), base) << "friction";
    EXPECT_NE(hash_of([](BodyDesc& b, ShapeId) { b.rolling_resistance = 0.1f; }, shaped), base) << "rolling";
    EXPECT_NE(hash_of([](BodyDesc& b, ShapeId) { b.fixed_rotation = true; }, shaped), base) << "fixed_rotation";
    EXPECT_NE(hash_of([](BodyDesc& b, ShapeId) { b.angular_velocity.y() = 1.0f; }, shaped), base) << "spin";
    EXPECT_NE(hash_of([](BodyDesc& b, ShapeId) { b.linear_damping = 0.5f; }, shaped),
              hash_of([](BodyDesc& b, ShapeId) { b.angular_damping = 0.5f; }, shaped))
        << "damping";
    EXPECT_NE(hash_of([](BodyDesc& b, ShapeId) { b.gravity_scale = 0.5f; }, shaped),
              hash_of([](BodyDesc& b, ShapeId) { b.gravity_scale = 0.25f; }, shaped))
        << "gravity_scale";
  }
  const uint64_t shaped = hash_of(none, true);
  EXPECT_NE(hash_of([](BodyDesc& b, ShapeId box) { b.shape = box; }, true), shaped) << "shape";
  EXPECT_NE(hash_of([](BodyDesc& b, ShapeId box) {
              b.shape = box;
              b.orientation = Eigen::Quaternionf(Eigen::AngleAxisf(0.5f, Eigen::Vector3f::UnitX()));
            }, true),
            hash_of([](BodyDesc& b, ShapeId box) { b.shape = box; }, true))
      << "orientation";
}

}  // namespace
}  // namespace impact
