// The rigid-body benchmark scenes (bench/scenes/scenes.h) are well formed: each has
// the body count its documentation gives, its shapes load into a World with the ids
// the bodies name, no two bodies start overlapping by more than the stacking overlap
// (axis-aligned boxes by their exact boxes, the rotated piles by bounding spheres),
// every body starts on the free side of every plane, the same arguments give the
// same bytes, a small version of each steps without error or NaN, and the mixed pile
// comes to rest on its mesh.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <numeric>
#include <string>
#include <vector>

#include "bench/scenes/scenes.h"
#include "impact/impact.h"
#include "support/test_support.h"

namespace impact::bench {
namespace {

// Overlap allowed between neighbours at the start: the stacking overlap, and float
// rounding of the positions (up to ~150 m from the origin).
constexpr float kTolerance = kStackOverlap + 1e-4f;

struct Expected {
  const char* name;
  uint32_t bodies;  // the documented default count (make_scene's body count)
  size_t planes;
};

constexpr Expected kRigidScenes[] = {
    {"pyramid", 1240, 1}, {"wall", 5050, 1}, {"pyramids", 10780, 1},
    {"column", 20, 1},    {"hulls", 5000, 5}, {"mixed", 10001, 5},  // 10000 + the mesh floor
};

bool is_stacking(std::string_view name) {
  return name == "pyramid" || name == "wall" || name == "pyramids" || name == "column";
}

Scene scene_of(std::string_view name, uint32_t bodies) {
  Scene s;
  EXPECT_TRUE(test::IsOk(make_scene(name, bodies, kDefaultSeed, &s)));
  return s;
}

// World bounds of every body (slot i = scene body i: a fresh world keeps creation order).
struct Bounds {
  std::vector<Eigen::Vector3f> min, max;
};

Bounds bounds_of(const Scene& scene, const World& world) {
  Bounds b;
  for (const BodyDesc& d : scene.bodies) {
    Eigen::Vector3f lo, hi;
    Pose pose;
    pose.position = d.position;
    pose.orientation = d.orientation;
    EXPECT_TRUE(test::IsOk(world.shapes().bounds(d.shape, pose, &lo, &hi)));
    b.min.push_back(lo);
    b.max.push_back(hi);
  }
  return b;
}

// Largest overlap of two axis-aligned boxes over all pairs (a sweep along x), m;
// negative when none touch.
float largest_box_overlap(const Bounds& b) {
  std::vector<uint32_t> order(b.min.size());
  std::iota(order.begin(), order.end(), 0u);
  std::sort(order.begin(), order.end(), [&](uint32_t i, uint32_t j) {
    return b.min[i].x() != b.min[j].x() ? b.min[i].x() < b.min[j].x() : i < j;
  });
  float worst = -INFINITY;
  for (size_t k = 0; k < order.size(); ++k) {
    const uint32_t i = order[k];
    for (size_t l = k + 1; l < order.size() && b.min[order[l]].x() < b.max[i].x(); ++l) {
      const uint32_t j = order[l];
      const Eigen::Vector3f depth = b.max[i].cwiseMin(b.max[j]) - b.min[i].cwiseMax(b.min[j]);
      if (depth.minCoeff() > 0.0f) worst = std::max(worst, depth.minCoeff());
    }
  }
  return worst;
}

// Farthest point of a shape from its origin, m.
float bounding_radius(const SceneShape& sh) {
  switch (sh.type) {
    case ShapeType::kSphere: return sh.radius;
    case ShapeType::kCapsule: return sh.radius + sh.half_length;
    case ShapeType::kBox: return sh.half_extents.norm();
    case ShapeType::kCylinder: return std::hypot(sh.radius, sh.half_length);
    case ShapeType::kConvex: {
      float r = 0.0f;
      for (const Eigen::Vector3f& p : sh.points) r = std::max(r, p.norm());
      return r;
    }
    default: return INFINITY;
  }
}

TEST(BenchScenes, RigidScenesHaveTheirDocumentedCounts) {
  for (const Expected& e : kRigidScenes) {
    SCOPED_TRACE(e.name);
    EXPECT_EQ(scene_default_bodies(e.name) + (std::string_view(e.name) == "mixed" ? 1u : 0u), e.bodies);
    const Scene s = scene_of(e.name, scene_default_bodies(e.name));
    EXPECT_EQ(s.bodies.size(), e.bodies);
    EXPECT_EQ(s.planes.size(), e.planes);
    EXPECT_TRUE(s.rigid);
    EXPECT_FALSE(scene_summary(e.name).empty());
    EXPECT_NE(std::find(scene_names().begin(), scene_names().end(), e.name), scene_names().end());
  }
}

TEST(BenchScenes, StructuresAreTheLargestThatFit) {
  EXPECT_EQ(scene_of("pyramid", 55).bodies.size(), 55u);     // 5 layers
  EXPECT_EQ(scene_of("pyramid", 1239).bodies.size(), 1015u);  // 14 layers
  EXPECT_EQ(scene_of("pyramid", 1).bodies.size(), 1u);
  EXPECT_EQ(scene_of("wall", 5049).bodies.size(), 4950u);  // 99 rows
  EXPECT_EQ(scene_of("pyramids", 10).bodies.size(), 55u);  // at least one pyramid
  EXPECT_EQ(scene_of("pyramids", 120).bodies.size(), 110u);
  EXPECT_EQ(scene_of("column", 7).bodies.size(), 7u);
  EXPECT_EQ(scene_of("hulls", 7).bodies.size(), 7u);
  EXPECT_EQ(scene_of("mixed", 7).bodies.size(), 8u);
}

TEST(BenchScenes, SameArgumentsGiveTheSameBytes) {
  for (const Expected& e : kRigidScenes) {
    SCOPED_TRACE(e.name);
    const Scene a = scene_of(e.name, 300), b = scene_of(e.name, 300);
    ASSERT_EQ(a.bodies.size(), b.bodies.size());
    ASSERT_EQ(a.shapes.size(), b.shapes.size());
    for (size_t i = 0; i < a.bodies.size(); ++i) {
      EXPECT_EQ(a.bodies[i].position, b.bodies[i].position);
      EXPECT_EQ(a.bodies[i].orientation.coeffs(), b.bodies[i].orientation.coeffs());
      EXPECT_EQ(a.bodies[i].inv_mass, b.bodies[i].inv_mass);
    }
    for (size_t k = 0; k < a.shapes.size(); ++k) EXPECT_EQ(a.shapes[k].points, b.shapes[k].points);
  }
}

TEST(BenchScenes, BodiesStartApartAndInsideThePlanes) {
  for (const Expected& e : kRigidScenes) {
    SCOPED_TRACE(e.name);
    const Scene s = scene_of(e.name, scene_default_bodies(e.name));
    std::unique_ptr<World> world;
    ASSERT_TRUE(test::IsOk(load_scene(s, WorldDesc{}, &world)));
    ASSERT_EQ(world->body_count(), s.bodies.size());
    ASSERT_EQ(world->shapes().size(), s.shapes.size());
    const Bounds b = bounds_of(s, *world);
    // Every dynamic body lies on the free side of every plane (dot(n, x) >= offset;
    // the planes here are axis-aligned, so the box test is exact). The static mesh
    // floor reaches under the walls, so that nothing slips between it and them; it
    // must lie above the floor plane.
    for (size_t i = 0; i < s.bodies.size(); ++i)
      for (const PlaneDesc& p : s.planes) {
        const Eigen::Vector3f n = p.normal.normalized();
        if (s.bodies[i].inv_mass == 0.0f && n.y() == 0.0f) continue;
        const Eigen::Vector3f corner((n.x() >= 0 ? b.min[i] : b.max[i]).x(), (n.y() >= 0 ? b.min[i] : b.max[i]).y(),
                                     (n.z() >= 0 ? b.min[i] : b.max[i]).z());
        ASSERT_GE(n.dot(corner), p.offset - kTolerance) << "body " << i << " starts inside a plane";
      }
    if (is_stacking(e.name)) {
      // Axis-aligned 1 m cubes: their boxes are exact. Neighbours in a layer are
      // kStackGap apart, a box rests kStackOverlap into the one below.
      for (const BodyDesc& d : s.bodies) ASSERT_TRUE(d.orientation.coeffs() == Eigen::Quaternionf::Identity().coeffs());
      const float overlap = largest_box_overlap(b);
      std::printf("[ measure ] %s: deepest initial overlap %.3g m\n", e.name, overlap);
      EXPECT_LE(overlap, kTolerance);
      // Every box above the floor rests on boxes: the bottom of the structure is at
      // y = -kStackOverlap and each box starts within kStackOverlap of its support.
      float lowest = INFINITY;
      for (const Eigen::Vector3f& lo : b.min) lowest = std::min(lowest, lo.y());
      EXPECT_NEAR(lowest, -kStackOverlap, 1e-5f);
    } else {
      // Rotated piles: bounding spheres about the body's centre never overlap. (Not
      // BodyArrays::radius, which is the farthest corner of the shape's local box.)
      // The static mesh floor lies below every dynamic body.
      const size_t dynamic = e.name == std::string_view("mixed") ? s.bodies.size() - 1 : s.bodies.size();
      float highest_floor = -INFINITY;
      if (dynamic < s.bodies.size()) highest_floor = b.max.back().y();
      std::vector<float> reach(dynamic);
      for (size_t i = 0; i < dynamic; ++i) {
        reach[i] = bounding_radius(s.shapes[s.bodies[i].shape.index]);
        ASSERT_LE(reach[i], kMaxRadius + 1e-5f) << "body " << i;
        ASSERT_GT(b.min[i].y(), highest_floor) << "body " << i << " starts in the mesh floor";
      }
      // Neighbours are within 1 m along x: a sweep.
      std::vector<uint32_t> order(dynamic);
      std::iota(order.begin(), order.end(), 0u);
      auto x = [&](uint32_t i) { return s.bodies[i].position.x(); };
      std::sort(order.begin(), order.end(), [&](uint32_t i, uint32_t j) { return x(i) != x(j) ? x(i) < x(j) : i < j; });
      for (size_t k = 0; k < dynamic; ++k)
        for (size_t l = k + 1; l < dynamic && x(order[l]) - x(order[k]) < 2.0f * kMaxRadius; ++l) {
          const uint32_t i = order[k], j = order[l];
          ASSERT_GE((s.bodies[i].position - s.bodies[j].position).norm(), reach[i] + reach[j])
              << "bodies " << i << " and " << j;
        }
    }
  }
}

TEST(BenchScenes, SmallVersionsStepWithTheSoftStep) {
  for (const Expected& e : kRigidScenes) {
    SCOPED_TRACE(e.name);
    const Scene s = scene_of(e.name, 60);
    WorldDesc desc;
    desc.solver.kind = SolverKind::kSoftStep;
    std::unique_ptr<World> world;
    ASSERT_TRUE(test::IsOk(load_scene(s, desc, &world)));
    for (int k = 0; k < 10; ++k) ASSERT_TRUE(test::IsOk(world->step()));
    const BodyArrays a = world->bodies();
    for (size_t i = 0; i < a.size(); ++i)
      ASSERT_TRUE(std::isfinite(a.pos_x[i]) && std::isfinite(a.pos_y[i]) && std::isfinite(a.pos_z[i])) << i;
  }
}

// Issue 40's mixed pile: boxes, capsules, hulls, cylinders and spheres dropped on a
// triangle mesh come to rest with no NaN. 1000 of the mixed scene's bodies, 10 s at
// the default settings. The "penetration below the slop" is not met: soft
// contacts hold a load F at an overlap F / (m_eff omega^2), and bodies wedged in the
// pile or pressed against its walls rest 1-3 cm deep at 4 substeps
// (docs/solver.md, "Stiffness and substeps"); the bound here is the recovery path's
// depth, max_push_speed * dt, below which no contact is left to the position pass.
TEST(BenchScenes, MixedPileComesToRestOnTheMesh) {
  const Scene s = scene_of("mixed", 1000);
  WorldDesc desc;
  desc.threads = 2;
  std::unique_ptr<World> world;
  ASSERT_TRUE(test::IsOk(load_scene(s, desc, &world)));
  for (int k = 0; k < 600; ++k) ASSERT_TRUE(test::IsOk(world->step()));
  const BodyArrays a = world->bodies();
  double kinetic = 0.0;
  bool finite = true;
  for (size_t i = 0; i < a.size(); ++i) {
    finite = finite && std::isfinite(a.pos_x[i]) && std::isfinite(a.pos_y[i]) && std::isfinite(a.pos_z[i]);
    const double v2 = double(a.vel_x[i]) * a.vel_x[i] + double(a.vel_y[i]) * a.vel_y[i] + double(a.vel_z[i]) * a.vel_z[i];
    if (a.inv_mass[i] > 0.0f) kinetic += 0.5 * v2 / a.inv_mass[i];
  }
  const ContactArrays c = world->contacts();
  float deepest = 0.0f;
  uint32_t over_1cm = 0;
  for (size_t m = 0; m < c.size(); ++m) {
    deepest = std::max(deepest, c.depth[m]);
    over_1cm += c.depth[m] > 0.01f ? 1u : 0u;
  }
  std::printf("[ measure ] mixed pile of %zu bodies on a mesh, 10 s: kinetic energy %.3g J, deepest %.3g m, "
              "%u of %zu manifolds deeper than 1 cm\n",
              a.size(), kinetic, deepest, over_1cm, c.size());
  EXPECT_TRUE(finite);
  EXPECT_LT(kinetic, 0.5) << "at rest";
  EXPECT_LT(deepest, desc.solver.max_push_speed * desc.fixed_dt);
}

}  // namespace
}  // namespace impact::bench
