// leaf_distance (kernels/distance/leaf_distance.cpp) against a double-precision
// certificate: for separated random sphere, capsule, box and half-space pairs, the
// gap between A's and B's double-precision supports along n (a separating-plane lower
// bound) must equal the reported distance (an upper bound, |pb - pa|), pa and pb must
// be support points (on the surfaces), and pb - pa = distance * n. Also: touching and
// overlapping pairs report overlap, parallel capsules and parallel box faces, and the
// same pair 1e5 m and 1e6 m from the world origin (leaves relative to an origin).
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "kernels/distance/leaf_distance.h"

namespace impact::kernels {
namespace {

using Vec3d = Eigen::Vector3d;
using cvx::V3;

Vec3d dv(V3 v) { return Vec3d(v.x, v.y, v.z); }

// Double support value max_x d.x of the whole leaf (sphere, capsule, box).
double support_value(const cvx::Leaf& l, const Vec3d& d) {
  const Vec3d p = dv(l.p);
  switch (l.type) {
    case kLeafSphere: return d.dot(p) + l.e[0] * d.norm();
    case kLeafCapsule: return d.dot(p) + l.e[1] * std::abs(d.dot(dv(l.ax[2]))) + l.e[0] * d.norm();
    case kLeafBox: {
      double s = d.dot(p);
      for (int i = 0; i < 3; ++i) s += l.e[i] * std::abs(d.dot(dv(l.ax[i])));
      return s;
    }
    default: return NAN;
  }
}

cvx::Leaf random_leaf(std::mt19937& rng, LeafType t, const Vec3d& centre) {
  std::uniform_real_distribution<float> u(0.05f, 1.5f);
  cvx::Leaf l;
  l.type = t;
  l.p = V3{float(centre.x()), float(centre.y()), float(centre.z())};
  const Eigen::Matrix3f R = Eigen::Quaternionf::UnitRandom().toRotationMatrix();
  for (int c = 0; c < 3; ++c) l.ax[c] = V3{R(0, c), R(1, c), R(2, c)};
  for (int i = 0; i < 3; ++i) l.e[i] = u(rng);
  return l;
}

struct Check {
  double tol;
};

void certify(const cvx::Leaf& a, const cvx::Leaf& b, const dist::LeafDistance& r, double tol) {
  ASSERT_FALSE(r.overlap);
  const Vec3d n = dv(r.n), pa = dv(r.pa), pb = dv(r.pb);
  EXPECT_NEAR(n.norm(), 1.0, 1e-5);
  EXPECT_NEAR((pb - pa).norm(), r.distance, tol);
  EXPECT_LT((pb - pa - r.distance * n).norm(), tol);
  const double ha = support_value(a, n);      // max over A of n.x
  const double hb = -support_value(b, -n);    // min over B of n.x
  // The plane n.x = ha separates: the gap hb - ha is a lower bound on the distance.
  EXPECT_NEAR(hb - ha, r.distance, tol);
  EXPECT_NEAR(n.dot(pa), ha, tol);
  EXPECT_NEAR(n.dot(pb), hb, tol);
}

TEST(LeafDistance, RandomSeparatedPairsCertified) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const LeafType types[] = {kLeafSphere, kLeafCapsule, kLeafBox};
  NarrowConfig cfg;
  int checked = 0;
  for (LeafType ta : types) {
    for (LeafType tb : types) {
      for (int k = 0; k < 200; ++k) {
        const cvx::Leaf a = random_leaf(rng, ta, Vec3d::Zero());
        const Vec3d dir = Vec3d(u(rng), u(rng), u(rng)).normalized();
        const cvx::Leaf b = random_leaf(rng, tb, dir * (6.0 + 2.0 * u(rng)));
        const dist::LeafDistance r = dist::leaf_distance(a, b, cfg);
        SCOPED_TRACE(testing::Message() << int(ta) << "-" << int(tb) << " k=" << k);
        certify(a, b, r, 1e-4);
        ++checked;
      }
    }
  }
  EXPECT_EQ(checked, 1800);
}

TEST(LeafDistance, OverlapAndTouching) {
  NarrowConfig cfg;
  cvx::Leaf a, b;
  a.type = b.type = kLeafSphere;
  a.e[0] = 1.0f;
  b.e[0] = 1.0f;
  b.p = V3{1.5f, 0, 0};
  EXPECT_TRUE(dist::leaf_distance(a, b, cfg).overlap);
  b.p = V3{2.0f, 0, 0};
  EXPECT_TRUE(dist::leaf_distance(a, b, cfg).overlap);  // touching: distance 0
  b.type = kLeafBox;
  b.ax[0] = V3{1, 0, 0};
  b.ax[1] = V3{0, 1, 0};
  b.ax[2] = V3{0, 0, 1};
  b.e[1] = b.e[2] = 1.0f;
  b.p = V3{1.8f, 0.2f, 0};
  EXPECT_TRUE(dist::leaf_distance(a, b, cfg).overlap);
}

TEST(LeafDistance, ParallelCapsulesAndBoxFaces) {
  NarrowConfig cfg;
  cvx::Leaf a, b;
  a.type = b.type = kLeafCapsule;
  for (cvx::Leaf* l : {&a, &b}) {
    l->ax[0] = V3{1, 0, 0};
    l->ax[1] = V3{0, 1, 0};
    l->ax[2] = V3{0, 0, 1};
    l->e[0] = 0.25f;
    l->e[1] = 1.0f;
  }
  b.p = V3{1.0f, 0, 0.5f};
  dist::LeafDistance r = dist::leaf_distance(a, b, cfg);
  certify(a, b, r, 1e-5);
  EXPECT_NEAR(r.distance, 0.5f, 1e-5f);
  a.type = b.type = kLeafBox;
  a.e[0] = a.e[1] = a.e[2] = b.e[0] = b.e[1] = b.e[2] = 0.5f;
  b.p = V3{1.25f, 0.3f, -0.2f};
  r = dist::leaf_distance(a, b, cfg);
  certify(a, b, r, 1e-5);
  EXPECT_NEAR(r.distance, 0.25f, 1e-5f);
}

TEST(LeafDistance, HalfSpaceEitherSide) {
  NarrowConfig cfg;
  cvx::Leaf h, b;
  h.type = kLeafHalfSpace;
  h.p = V3{0, 0, 1.0f};
  h.e[0] = 0;
  h.e[1] = 0;
  h.e[2] = 1.0f;
  b.type = kLeafSphere;
  b.e[0] = 0.5f;
  b.p = V3{0.3f, -0.2f, 3.0f};
  dist::LeafDistance r = dist::leaf_distance(h, b, cfg);
  ASSERT_FALSE(r.overlap);
  EXPECT_NEAR(r.distance, 1.5f, 1e-6f);
  EXPECT_NEAR(r.pb.z, 2.5f, 1e-6f);
  EXPECT_NEAR(r.pa.z, 1.0f, 1e-6f);
  r = dist::leaf_distance(b, h, cfg);
  ASSERT_FALSE(r.overlap);
  EXPECT_NEAR(r.distance, 1.5f, 1e-6f);
  EXPECT_NEAR(r.n.z, -1.0f, 1e-6f);
  b.p.z = 1.2f;
  EXPECT_TRUE(dist::leaf_distance(h, b, cfg).overlap);
}

TEST(LeafDistance, FarOriginMatchesOrigin) {
  // Leaves are relative to an origin: a pair posed 1e5 / 1e6 m away is loaded minus
  // that origin and must give the same bytes as the pair at the origin.
  std::mt19937 rng(3);
  NarrowConfig cfg;
  const cvx::Leaf a = random_leaf(rng, kLeafBox, Vec3d::Zero());
  const cvx::Leaf b = random_leaf(rng, kLeafCapsule, Vec3d(3.0, 1.0, -2.0));
  const dist::LeafDistance r0 = dist::leaf_distance(a, b, cfg);
  for (double far : {1e5, 1e6}) {
    const float fo = float(far);
    cvx::Leaf fa = a, fb = b;
    fa.p = fa.p + V3{fo, fo, fo};
    fb.p = fb.p + V3{fo, fo, fo};
    const V3 origin = fa.p;  // as a host would pick: A's centre
    fa.p = fa.p - origin;
    fb.p = fb.p - origin;
    const dist::LeafDistance r = dist::leaf_distance(fa, fb, cfg);
    EXPECT_NEAR(r.distance, r0.distance, 2e-1 * 1e-6 * far);  // float rounding of the centres
    certify(fa, fb, r, 1e-4);
  }
}

}  // namespace
}  // namespace impact::kernels
