// Scalar ray-primitive kernels (kernels/raycast/ray_primitives.h) against the
// double-precision reference of ray_reference.h on random and adversarial cases:
// origins inside, grazing, rays along a capsule's axis (which Embree's round curves
// miss), zero-length capsules, triangles hit on edges, rays parallel to faces.
#include <gtest/gtest.h>

#include <random>

#include "kernels/raycast/ray_primitives.h"
#include "kernels/raycast/ray_reference.h"
#include "support/test_support.h"

namespace impact::test {
namespace {

kernels::RayQuery query(const V3& o, const V3& d, double tmax) {
  kernels::RayQuery q;
  const V3 u = d.normalized();
  for (int k = 0; k < 3; ++k) {
    q.o[k] = static_cast<float>(o[k]);
    q.d[k] = static_cast<float>(u[k]);
  }
  q.tmax = static_cast<float>(tmax);
  q.mask = ~0u;
  return q;
}

// Reference on the float-rounded inputs the kernel sees.
V3 o_of(const kernels::RayQuery& q) { return V3(q.o[0], q.o[1], q.o[2]); }
V3 d_of(const kernels::RayQuery& q) { return V3(q.d[0], q.d[1], q.d[2]).normalized(); }

void expect_agrees(const RefHit& ref, float got, double scale, const std::string& what) {
  if (ref.state == Ref::kAmbiguous) return;
  if (ref.state == Ref::kMiss) {
    EXPECT_LT(got, 0.0f) << what;
    return;
  }
  ASSERT_GE(got, 0.0f) << what << " (reference t " << ref.t << ")";
  EXPECT_NEAR(got, ref.t, 1e-4 * scale) << what;
}

TEST(RayPrimitives, RandomAgainstReference) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1.0, 1.0), u01(0.0, 1.0);
  int hits[3] = {0, 0, 0};
  for (double off : {0.0, 1e4, 1e5}) {
    for (int i = 0; i < 20000; ++i) {
      const V3 c = V3::Constant(off) + V3(u(rng), u(rng), u(rng)) * 3.0;
      // Half the rays aimed near the primitive's centre, half random.
      const V3 from = V3::Constant(off) + V3(u(rng), u(rng), u(rng)) * 6.0;
      const V3 dir = i % 2 == 0 ? V3(c + V3(u(rng), u(rng), u(rng)) * 2.0 - from) : V3(u(rng), u(rng), u(rng));
      const kernels::RayQuery q = query(from, dir, i % 4 == 1 ? 5.0 * u01(rng) : 1e30);
      const V3 o = o_of(q), d = d_of(q);
      const double S = std::max(1.0, o.cwiseAbs().maxCoeff() + 10.0);
      const float r = static_cast<float>(0.2 + 2.0 * u01(rng));
      const V3 cf = test::round_to_float(c);
      // Sphere.
      const float ts = kernels::ray_sphere(q, static_cast<float>(c.x()), static_cast<float>(c.y()), static_cast<float>(c.z()), r);
      expect_agrees(ref_sphere(o, d, q.tmax, cf, r), ts, S, "sphere " + std::to_string(i));
      hits[0] += ts >= 0.0f;
      // Capsule (every 5th along a coordinate axis, every 9th of zero length).
      V3 ax = V3(u(rng), u(rng), u(rng)) * 3.0;
      if (i % 5 == 0) ax = V3(0, 0, 2.0);
      if (i % 9 == 0) ax.setZero();
      const Eigen::Vector3f a = c.cast<float>(), b = (c + ax).cast<float>();
      const float tc = kernels::ray_capsule(q, a.data(), b.data(), r);
      expect_agrees(ref_capsule(o, d, q.tmax, a.cast<double>(), b.cast<double>(), r), tc, S, "capsule " + std::to_string(i));
      hits[1] += tc >= 0.0f;
      // Triangle.
      const Eigen::Vector3f v0 = (c + V3(u(rng), u(rng), u(rng)) * 3.0).cast<float>();
      const Eigen::Vector3f v1 = (c + V3(u(rng), u(rng), u(rng)) * 3.0).cast<float>();
      const Eigen::Vector3f v2 = (c + V3(u(rng), u(rng), u(rng)) * 3.0).cast<float>();
      const float tt = kernels::ray_triangle(q, kernels::ray_shear(q), v0.data(), v1.data(), v2.data());
      expect_agrees(ref_triangle(o, d, q.tmax, v0.cast<double>(), v1.cast<double>(), v2.cast<double>()), tt, S,
                    "triangle " + std::to_string(i));
      hits[2] += tt >= 0.0f;
    }
  }
  for (int h : hits) EXPECT_GT(h, 3000);
}

TEST(RayPrimitives, InsideGivesZeroAndBehindMisses) {
  const kernels::RayQuery q = query(V3(0, 0, 0), V3(1, 0, 0), 1e30);
  EXPECT_EQ(kernels::ray_sphere(q, 0.5f, 0, 0, 1.0f), 0.0f);
  EXPECT_EQ(kernels::ray_sphere(q, 1.0f, 0, 0, 1.0f), 0.0f);   // origin on the surface
  EXPECT_LT(kernels::ray_sphere(q, -3.0f, 0, 0, 1.0f), 0.0f);  // behind
  const float a[3] = {-1, 0.5f, 0}, b[3] = {-1, 5, 0};
  EXPECT_LT(kernels::ray_capsule(q, a, b, 0.5f), 0.0f);  // behind
  const float a2[3] = {0, -1, 0}, b2[3] = {0, 1, 0};
  EXPECT_EQ(kernels::ray_capsule(q, a2, b2, 0.5f), 0.0f);  // origin on the axis
  const float n[3] = {0, 1, 0};
  EXPECT_EQ(kernels::ray_plane(q, n, 0.0f), 0.0f);   // origin on the surface
  EXPECT_LT(kernels::ray_plane(q, n, -1.0f), 0.0f);  // parallel, outside
}

TEST(RayPrimitives, AlongTheCapsuleAxis) {
  // Rays parallel to the axis enter through the end cap (Embree's round linear curves
  // miss these: the reason capsules are user geometry).
  const float a[3] = {10, 0, 0}, b[3] = {14, 0, 0};
  for (float y : {0.0f, 0.3f, 0.9f}) {
    const kernels::RayQuery q = query(V3(7, y, 0), V3(1, 0, 0), 1e30);
    const float t = kernels::ray_capsule(q, a, b, 1.0f);
    EXPECT_NEAR(t, 3.0f - std::sqrt(1.0f - y * y), 1e-5f) << y;
    const kernels::RayQuery back = query(V3(17, y, 0), V3(-1, 0, 0), 1e30);
    EXPECT_NEAR(kernels::ray_capsule(back, a, b, 1.0f), 3.0f - std::sqrt(1.0f - y * y), 1e-5f) << y;
  }
  // Across the body.
  const kernels::RayQuery q = query(V3(12, 5, 0), V3(0, -1, 0), 1e30);
  EXPECT_NEAR(kernels::ray_capsule(q, a, b, 1.0f), 4.0f, 1e-5f);
}

TEST(RayPrimitives, TriangleEdgesAreClosedAndCoplanarRaysMiss) {
  const float v0[3] = {0, 0, 0}, v1[3] = {1, 0, 0}, v2[3] = {0, 0, 1};
  for (const V3& p : {V3(0, 0, 0), V3(1, 0, 0), V3(0.5, 0, 0), V3(0.5, 0, 0.5), V3(0, 0, 0.25)}) {
    const kernels::RayQuery q = query(p + V3(0, 2, 0), V3(0, -1, 0), 1e30);
    EXPECT_EQ(kernels::ray_triangle(q, kernels::ray_shear(q), v0, v1, v2), 2.0f) << p.transpose();
  }
  const kernels::RayQuery outside = query(V3(0.5001, 2, 0.5001), V3(0, -1, 0), 1e30);
  EXPECT_LT(kernels::ray_triangle(outside, kernels::ray_shear(outside), v0, v1, v2), 0.0f);
  const kernels::RayQuery coplanar = query(V3(-1, 0, 0.2), V3(1, 0, 0), 1e30);
  EXPECT_LT(kernels::ray_triangle(coplanar, kernels::ray_shear(coplanar), v0, v1, v2), 0.0f);
  const kernels::RayQuery short_ray = query(V3(0.2, 2, 0.2), V3(0, -1, 0), 1.999);
  EXPECT_LT(kernels::ray_triangle(short_ray, kernels::ray_shear(short_ray), v0, v1, v2), 0.0f);
}

}  // namespace
}  // namespace impact::test
