// Orientation validation of every World call that takes a quaternion (create_bodies
// from BodyDesc, the Eigen bulk create_bodies' common desc, set_orientations), written
// from the rule in include/impact/world.h: finite, | |q|^2 - 1 | <= kUnitQuaternionTolerance
// (2e-3), normalised on input; anything else is kInvalidArgument naming the body index
// and "orientation", for every body kind (static and dynamic plain spheres, spheres
// with fixed rotation, shaped bodies), and a rejected batch changes nothing. The
// reference for the accepted values is q / |q| in double.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "impact/impact.h"
#include "support/test_support.h"

namespace impact {
namespace {

using test::IsError;

const float kNan = std::numeric_limits<float>::quiet_NaN();
const float kInf = std::numeric_limits<float>::infinity();

Eigen::Quaternionf quat(float x, float y, float z, float w) { return Eigen::Quaternionf(w, x, y, z); }

// A random unit direction in R^4 scaled so that |q|^2 = n2 (in double, then rounded).
Eigen::Quaternionf with_norm2(double n2, std::mt19937& rng) {
  std::normal_distribution<double> g;
  Eigen::Vector4d v(g(rng), g(rng), g(rng), g(rng));
  v *= std::sqrt(n2) / v.norm();
  return quat(static_cast<float>(v[0]), static_cast<float>(v[1]), static_cast<float>(v[2]), static_cast<float>(v[3]));
}

struct Named {
  std::string name;
  Eigen::Quaternionf q;
};

// Every kind of invalid orientation: NaN and +-Inf in each component, zero, length 2,
// just outside the tolerance on both sides, denormal.
std::vector<Named> bad_orientations() {
  std::mt19937 rng(5);
  std::vector<Named> out;
  for (int k = 0; k < 4; ++k)
    for (const float v : {kNan, kInf, -kInf}) {
      Eigen::Quaternionf q = Eigen::Quaternionf::Identity();
      q.coeffs()[k] = v;
      out.push_back({"component " + std::to_string(k) + " = " + std::to_string(v), q});
    }
  out.push_back({"zero", quat(0, 0, 0, 0)});
  out.push_back({"length 2 (0, 0, 0, 2)", quat(0, 0, 0, 2)});
  out.push_back({"length 2 random", with_norm2(4.0, rng)});
  out.push_back({"|q|^2 = 1 + 2.2e-3", with_norm2(1.0 + 2.2e-3, rng)});
  out.push_back({"|q|^2 = 1 - 2.2e-3", with_norm2(1.0 - 2.2e-3, rng)});
  out.push_back({"denormal", quat(1e-40f, 0, 0, 0)});
  return out;
}

// Accepted: unit, and slightly off unit within the tolerance on both sides.
std::vector<Named> good_orientations() {
  std::mt19937 rng(6);
  return {{"identity", Eigen::Quaternionf::Identity()},
          {"random unit", with_norm2(1.0, rng)},
          {"-identity", quat(0, 0, 0, -1)},
          {"|q|^2 = 1 + 1.8e-3", with_norm2(1.0 + 1.8e-3, rng)},
          {"|q|^2 = 1 - 1.8e-3", with_norm2(1.0 - 1.8e-3, rng)}};
}

// Body kinds: static and dynamic plain spheres, a sphere that cannot turn, a box body.
std::vector<BodyDesc> body_kinds(World& w) {
  ShapeId box;
  EXPECT_TRUE(test::IsOk(w.shapes().add_box(Eigen::Vector3f(0.5f, 0.3f, 0.2f), &box)));
  std::vector<BodyDesc> d(4);
  d[0].inv_mass = 0.0f;
  d[1].inv_mass = 1.0f;
  d[2].inv_mass = 1.0f;
  d[2].fixed_rotation = true;
  d[3].inv_mass = 1.0f;
  d[3].shape = box;
  for (size_t i = 0; i < d.size(); ++i) d[i].position = Eigen::Vector3f(3.0f * static_cast<float>(i), 0.0f, 0.0f);
  return d;
}

std::vector<Eigen::Quaternionf> orientations(const World& w) {
  const BodyArrays b = w.bodies();
  std::vector<Eigen::Quaternionf> q(b.handles.size());
  EXPECT_TRUE(test::IsOk(w.get_orientations(b.handles, q)));
  return q;
}

void expect_normalised(const Eigen::Quaternionf& got, const Eigen::Quaternionf& given, const std::string& what) {
  const Eigen::Vector4d want = given.coeffs().cast<double>().normalized();
  EXPECT_LE((got.coeffs().cast<double>() - want).norm(), 1e-6) << what;
}

TEST(WorldOrientation, CreateBodiesRejectsEveryBadOrientationNamingTheBody) {
  for (const Named& bad : bad_orientations()) {
    auto world = test::make_world(WorldDesc{});
    const std::vector<BodyDesc> kinds = body_kinds(*world);
    for (size_t kind = 0; kind < kinds.size(); ++kind) {
      // A batch of five with the bad entry at k: nothing is created, body k is named.
      for (const size_t k : {size_t{0}, size_t{2}, size_t{4}}) {
        std::vector<BodyDesc> batch(5, kinds[kind]);
        for (size_t i = 0; i < batch.size(); ++i) batch[i].position.y() = 2.0f * static_cast<float>(i);
        batch[k].orientation = bad.q;
        std::vector<BodyHandle> h(batch.size());
        const std::string body = "body " + std::to_string(k);
        EXPECT_TRUE(IsError(world->create_bodies(batch, h), StatusCode::kInvalidArgument,
                            {"create_bodies", body.c_str(), "orientation"}))
            << bad.name << ", body kind " << kind << ", bad entry " << k;
        EXPECT_EQ(world->body_count(), 0u) << bad.name;
      }
    }
    // The Eigen bulk import: its common desc's orientation.
    BodyDesc common;
    common.orientation = bad.q;
    Eigen::Matrix3Xf p(3, 3);
    p << 0, 2, 4, 0, 0, 0, 0, 0, 0;
    const Eigen::VectorXf r = Eigen::VectorXf::Constant(3, 0.5f), m = Eigen::VectorXf::Constant(3, 1.0f);
    std::vector<BodyHandle> h(3);
    EXPECT_TRUE(IsError(world->create_bodies(p, Eigen::Matrix3Xf(3, 0), r, m, common, h),
                        StatusCode::kInvalidArgument, {"create_bodies", "common", "orientation"}))
        << bad.name;
    EXPECT_EQ(world->body_count(), 0u) << bad.name;
  }
}

TEST(WorldOrientation, CreateBodiesNormalisesOrientationsWithinTheTolerance) {
  auto world = test::make_world(WorldDesc{});
  const std::vector<BodyDesc> kinds = body_kinds(*world);
  std::vector<BodyDesc> all;
  std::vector<Eigen::Quaternionf> given;
  for (const Named& good : good_orientations())
    for (BodyDesc d : kinds) {
      d.orientation = good.q;
      d.position.z() = 3.0f * static_cast<float>(all.size());
      all.push_back(d);
      given.push_back(good.q);
    }
  std::vector<BodyHandle> h(all.size());
  IMPACT_ASSERT_OK(world->create_bodies(all, h));
  const std::vector<Eigen::Quaternionf> q = orientations(*world);
  ASSERT_EQ(q.size(), given.size());
  for (size_t i = 0; i < q.size(); ++i) expect_normalised(q[i], given[i], "body " + std::to_string(i));
  // The bulk import's common orientation, slightly off unit.
  std::mt19937 rng(7);
  BodyDesc common;
  common.orientation = with_norm2(1.0 + 1.5e-3, rng);
  Eigen::Matrix3Xf p(3, 2);
  p << 0, 2, 50, 50, 0, 0;
  const Eigen::VectorXf r = Eigen::VectorXf::Constant(2, 0.5f), m = Eigen::VectorXf::Constant(2, 1.0f);
  std::vector<BodyHandle> hb(2);
  IMPACT_ASSERT_OK(world->create_bodies(p, Eigen::Matrix3Xf(3, 0), r, m, common, hb));
  std::vector<Eigen::Quaternionf> qb(2);
  IMPACT_ASSERT_OK(world->get_orientations(hb, qb));
  for (const Eigen::Quaternionf& x : qb) expect_normalised(x, common.orientation, "bulk");
}

TEST(WorldOrientation, SetOrientationsRejectsEveryBadOrientationAndChangesNothing) {
  auto world = test::make_world(WorldDesc{});
  std::vector<BodyDesc> kinds = body_kinds(*world);
  std::vector<BodyHandle> h(kinds.size());
  IMPACT_ASSERT_OK(world->create_bodies(kinds, h));
  const test::WorldSnapshot before = test::snapshot(*world);
  const std::vector<Eigen::Quaternionf> q_before = orientations(*world);
  for (const Named& bad : bad_orientations()) {
    for (size_t k = 0; k < h.size(); ++k) {
      std::mt19937 rng(static_cast<uint32_t>(k));
      std::vector<Eigen::Quaternionf> v(h.size());
      for (auto& x : v) x = with_norm2(1.0, rng);
      v[k] = bad.q;
      const std::string body = "body " + std::to_string(k);
      EXPECT_TRUE(IsError(world->set_orientations(h, v), StatusCode::kInvalidArgument,
                          {"set_orientations", body.c_str(), "orientation"}))
          << bad.name << " at " << k;
      EXPECT_EQ(test::snapshot(*world), before) << bad.name;
      const std::vector<Eigen::Quaternionf> q = orientations(*world);
      for (size_t i = 0; i < q.size(); ++i) EXPECT_EQ(q[i].coeffs(), q_before[i].coeffs()) << bad.name;
    }
  }
  // Within the tolerance: accepted, stored normalised, on every body kind.
  for (const Named& good : good_orientations()) {
    const std::vector<Eigen::Quaternionf> v(h.size(), good.q);
    IMPACT_ASSERT_OK(world->set_orientations(h, v));
    const std::vector<Eigen::Quaternionf> q = orientations(*world);
    for (size_t i = 0; i < q.size(); ++i) expect_normalised(q[i], good.q, good.name + " body " + std::to_string(i));
  }
}

}  // namespace
}  // namespace impact
