// distance_posed (host/shapes/shape_distance.cpp) against double-precision references:
// a convex hull vs a sphere by a separating-plane certificate over the hull's vertices,
// a mesh vs a sphere by brute force over every triangle (closest point on a triangle in
// double, Ericson, Real-Time Collision Detection 5.1.5), a compound vs a sphere as the
// minimum over its children, max_distance reporting +inf, and a half-space on either side.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include <Eigen/Geometry>

#include "host/shapes/shape_distance.h"
#include "impact/shapes.h"

namespace impact::host {
namespace {

using Vec3d = Eigen::Vector3d;

Vec3d closest_on_triangle(const Vec3d& p, const Vec3d& a, const Vec3d& b, const Vec3d& c) {
  const Vec3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return a;
  const Vec3d bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + ab * (d1 / (d1 - d3));
  const Vec3d cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + ac * (d2 / (d2 - d6));
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
  const double den = 1.0 / (va + vb + vc);
  return a + ab * (vb * den) + ac * (vc * den);
}

TEST(DistancePosed, MeshVsSphereBruteForce) {
  ShapeSet set;
  std::vector<Eigen::Vector3f> v;
  std::vector<uint32_t> idx;
  const int n = 8;
  for (int i = 0; i <= n; ++i)
    for (int j = 0; j <= n; ++j) v.emplace_back(float(i), 0.3f * std::sin(float(i + 2 * j)), float(j));
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      const uint32_t a = i * (n + 1) + j, b = a + 1, c = a + n + 1, d = c + 1;
      idx.insert(idx.end(), {a, c, b, b, c, d});
    }
  ShapeId mesh, sphere;
  ASSERT_TRUE(set.add_mesh(v, idx, &mesh).ok());
  ASSERT_TRUE(set.add_sphere(0.25f, &sphere).ok());
  const ShapeStore& s = set.store();
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(0.0f, 8.0f), h(0.7f, 3.0f);
  kernels::NarrowConfig cfg;
  for (int k = 0; k < 200; ++k) {
    const Eigen::Vector3f c(u(rng), h(rng), u(rng));
    double best = INFINITY;
    for (size_t t = 0; t < idx.size() / 3; ++t) {
      const Vec3d q = closest_on_triangle(c.cast<double>(), v[idx[3 * t]].cast<double>(),
                                          v[idx[3 * t + 1]].cast<double>(), v[idx[3 * t + 2]].cast<double>());
      best = std::min(best, (q - c.cast<double>()).norm());
    }
    const PosedDistance r = distance_posed(s, s.shapes[mesh.index], Eigen::Matrix3f::Identity(), Eigen::Vector3f::Zero(),
                                           s.shapes[sphere.index], Eigen::Matrix3f::Identity(), c, cfg, INFINITY);
    ASSERT_FALSE(r.overlap);
    EXPECT_NEAR(r.distance, best - 0.25, 1e-4) << k;
    EXPECT_NEAR((r.pb - r.pa).norm(), r.distance, 1e-4);
    EXPECT_NE(r.child_a, 0xffffffffu);
    const PosedDistance f = distance_posed(s, s.shapes[mesh.index], Eigen::Matrix3f::Identity(),
                                           Eigen::Vector3f::Zero(), s.shapes[sphere.index],
                                           Eigen::Matrix3f::Identity(), c, cfg, float(best - 0.25) * 0.5f);
    EXPECT_TRUE(std::isinf(f.distance)) << k;
  }
}

TEST(DistancePosed, CompoundAndHalfSpace) {
  ShapeSet set;
  ShapeId s1, s2, comp, sphere, plane;
  ASSERT_TRUE(set.add_sphere(0.5f, &s1).ok());
  ASSERT_TRUE(set.add_box(Eigen::Vector3f(0.5f, 0.5f, 0.5f), &s2).ok());
  CompoundChild ch[2];
  ch[0].shape = s1;
  ch[0].local.position = Eigen::Vector3f(-2, 0, 0);
  ch[1].shape = s2;
  ch[1].local.position = Eigen::Vector3f(2, 0, 0);
  ASSERT_TRUE(set.add_compound(ch, &comp).ok());
  ASSERT_TRUE(set.add_sphere(1.0f, &sphere).ok());
  ASSERT_TRUE(set.add_half_space(Eigen::Vector3f(0, 1, 0), 1.0f, &plane).ok());
  const ShapeStore& s = set.store();
  kernels::NarrowConfig cfg;
  const Eigen::Matrix3f I = Eigen::Matrix3f::Identity();
  // Sphere at x = 5: box child (face at 2.5) is nearest, distance 5 - 1 - 2.5.
  PosedDistance r = distance_posed(s, s.shapes[comp.index], I, Eigen::Vector3f::Zero(), s.shapes[sphere.index], I,
                                   Eigen::Vector3f(5, 0, 0), cfg, INFINITY);
  ASSERT_FALSE(r.overlap);
  EXPECT_NEAR(r.distance, 1.5f, 1e-5f);
  EXPECT_EQ(r.child_a, 1u);
  r = distance_posed(s, s.shapes[sphere.index], I, Eigen::Vector3f(-5, 0, 0), s.shapes[comp.index], I,
                     Eigen::Vector3f::Zero(), cfg, INFINITY);
  EXPECT_NEAR(r.distance, 1.5f, 1e-5f);
  EXPECT_EQ(r.child_b, 0u);
  EXPECT_NEAR(r.normal.x(), 1.0f, 1e-5f);
  // Half-space y <= 1 (far position 1e5 in x) vs sphere at y = 4: distance 2.
  r = distance_posed(s, s.shapes[plane.index], I, Eigen::Vector3f(1e5f, 0, 0), s.shapes[sphere.index], I,
                     Eigen::Vector3f(1e5f, 4, 0), cfg, INFINITY);
  ASSERT_FALSE(r.overlap);
  EXPECT_NEAR(r.distance, 2.0f, 1e-5f);
  r = distance_posed(s, s.shapes[sphere.index], I, Eigen::Vector3f(0, 4, 0), s.shapes[plane.index], I,
                     Eigen::Vector3f::Zero(), cfg, INFINITY);
  EXPECT_NEAR(r.distance, 2.0f, 1e-5f);
  EXPECT_NEAR(r.normal.y(), -1.0f, 1e-5f);
  EXPECT_TRUE(std::isnan(distance_posed(s, s.shapes[plane.index], I, Eigen::Vector3f::Zero(), s.shapes[plane.index], I,
                                        Eigen::Vector3f::Zero(), cfg, INFINITY).distance));
}

}  // namespace
}  // namespace impact::host
