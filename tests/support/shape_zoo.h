// A zoo of every shape type once, random poses, and random scenes over the zoo: the
// shared input of the public narrow-phase tests (tests/host/narrowphase/).
#pragma once

#include <cmath>
#include <random>
#include <vector>

#include "impact/impact.h"
#include "tests/support/test_support.h"

namespace impact::test {

inline Pose random_pose(std::mt19937& rng, float extent) {
  std::uniform_real_distribution<float> u(-extent, extent);
  std::normal_distribution<float> g(0.0f, 1.0f);
  Pose p;
  p.position = Eigen::Vector3f(u(rng), u(rng), u(rng));
  Eigen::Vector4f q(g(rng), g(rng), g(rng), g(rng));
  q.normalize();
  p.orientation = Eigen::Quaternionf(q[3], q[0], q[1], q[2]);
  return p;
}

/// Every shape type once (meshes: a 4x4 terrain patch; compound: two boxes and a sphere).
struct Zoo {
  ShapeSet set;
  std::vector<ShapeId> ids;
  ShapeId sphere, capsule, box, aabb, convex, cylinder, ellipsoid, half_space, mesh, compound;

  Zoo() {
    EXPECT_TRUE(test::IsOk(set.add_sphere(0.5f, &sphere)));
    EXPECT_TRUE(test::IsOk(set.add_capsule(0.3f, 0.6f, &capsule)));
    EXPECT_TRUE(test::IsOk(set.add_box(Eigen::Vector3f(0.4f, 0.3f, 0.7f), &box)));
    EXPECT_TRUE(test::IsOk(set.add_aabb(Eigen::Vector3f(0.5f, 0.2f, 0.3f), &aabb)));
    std::vector<Eigen::Vector3f> pts;
    std::mt19937 rng(7);
    std::normal_distribution<float> g(0.0f, 1.0f);
    for (int i = 0; i < 24; ++i) pts.push_back(Eigen::Vector3f(g(rng), g(rng), g(rng)).normalized() * 0.6f);
    EXPECT_TRUE(test::IsOk(set.add_convex_hull(pts, &convex)));
    EXPECT_TRUE(test::IsOk(set.add_cylinder(0.4f, 0.5f, &cylinder)));
    EXPECT_TRUE(test::IsOk(set.add_ellipsoid(Eigen::Vector3f(0.6f, 0.3f, 0.4f), &ellipsoid)));
    EXPECT_TRUE(test::IsOk(set.add_half_space(Eigen::Vector3f(0, 1, 0), -1.5f, &half_space)));
    std::vector<Eigen::Vector3f> v;
    std::vector<uint32_t> idx;
    const int n = 4;
    for (int i = 0; i <= n; ++i)
      for (int j = 0; j <= n; ++j)
        v.emplace_back(-2.0f + static_cast<float>(i), 0.3f * std::sin(static_cast<float>(i + 2 * j)),
                       -2.0f + static_cast<float>(j));
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j) {
        const auto a = static_cast<uint32_t>(i * (n + 1) + j), b = a + 1,
                   c = static_cast<uint32_t>((i + 1) * (n + 1) + j), d = c + 1;
        idx.insert(idx.end(), {a, b, c, b, d, c});
      }
    EXPECT_TRUE(test::IsOk(set.add_mesh(v, idx, &mesh)));
    Pose l0, l1, l2;
    l0.position = Eigen::Vector3f(-0.5f, 0, 0);
    l1.position = Eigen::Vector3f(0.5f, 0, 0);
    l1.orientation = Eigen::Quaternionf(Eigen::AngleAxisf(0.5f, Eigen::Vector3f(0, 0, 1)));
    l2.position = Eigen::Vector3f(0, 0.5f, 0);
    const CompoundChild kids[3] = {{box, l0}, {box, l1}, {sphere, l2}};
    EXPECT_TRUE(test::IsOk(set.add_compound(kids, &compound)));
    ids = {sphere, capsule, box, aabb, convex, cylinder, ellipsoid, half_space, mesh, compound};
  }
};

struct Scene {
  std::vector<ShapeId> shapes;
  std::vector<Pose> poses;
  std::vector<ShapePair> pairs;
};

inline Scene random_scene(const Zoo& z, uint32_t objects, uint32_t pairs, uint32_t seed) {
  std::mt19937 rng(seed);
  Scene s;
  for (uint32_t i = 0; i < objects; ++i) {
    s.shapes.push_back(z.ids[rng() % z.ids.size()]);
    s.poses.push_back(random_pose(rng, 1.2f));
  }
  for (uint32_t k = 0; k < pairs; ++k) {
    const auto a = static_cast<uint32_t>(rng() % objects);
    auto b = static_cast<uint32_t>(rng() % objects);
    if (b == a) b = (a + 1) % objects;
    if (s.shapes[a] == z.half_space && s.shapes[b] == z.half_space) continue;
    s.pairs.push_back({a, b});
  }
  return s;
}

}  // namespace impact::test
