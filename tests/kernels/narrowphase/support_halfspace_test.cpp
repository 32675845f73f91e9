// The convex-leaf / half-space kernels (collide_convex_halfspace for hulls, which hands
// hulls over 64 vertices to collide_support_halfspace; the lane kernels of
// primitives_*.cpp for the others; through pair_kernel,
// on both paths) against closed forms in double: the deepest point of every convex
// leaf type below a plane, the normal, the manifold points (each one a point of A below
// the plane, midway to the plane), and the manifold sizes of resting boxes, cylinders
// and capsules.
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>
#include <random>
#include <vector>

#include "host/shapes/convex_hull.h"
#include "host/shapes/shape_store.h"
#include "kernels/narrowphase/pair_kernels.h"
#include "support/kernel_checks.h"
#include "support/leaf_lanes.h"
#include "support/random_input.h"
#include "support/test_support.h"

namespace impact::kernels {
namespace {

using Vec3d = Eigen::Vector3d;
using Mat3d = Eigen::Matrix3d;

/// Type names without pair_kernels.cpp (which also references the specialised kernels).
const char* tname(LeafType t) {
  static const char* const names[] = {"sphere", "capsule", "box", "convex", "cylinder", "ellipsoid", "triangle", "half-space"};
  return t < kLeafTypeCount ? names[t] : "unknown";
}

struct Leaf1 {
  LeafType type = kLeafSphere;
  Vec3d p = Vec3d::Zero();
  Mat3d R = Mat3d::Identity();
  Vec3d e = Vec3d::Zero();
  Vec3d v1 = Vec3d::Zero(), v2 = Vec3d::Zero();
  uint32_t hull = 0;
};

struct Arrays {
  float p[3], r[9], e[3], w[6];
  uint32_t ref;
  LeafSoA soa() {
    LeafSoA s{};
    for (int i = 0; i < 3; ++i) s.p[i] = &p[i];
    for (int i = 0; i < 9; ++i) s.r[i] = &r[i];
    for (int i = 0; i < 3; ++i) s.e[i] = &e[i];
    for (int i = 0; i < 6; ++i) s.w[i] = &w[i];
    s.ref = &ref;
    return s;
  }
};

Arrays arrays_of(const Leaf1& l) {
  Arrays a{};
  for (int i = 0; i < 3; ++i) a.p[i] = static_cast<float>(l.p[i]);
  for (int i = 0; i < 9; ++i) a.r[i] = static_cast<float>(l.R(i / 3, i % 3));
  for (int i = 0; i < 3; ++i) a.e[i] = static_cast<float>(l.e[i]);
  for (int i = 0; i < 3; ++i) a.w[i] = static_cast<float>(l.v1[i]);
  for (int i = 0; i < 3; ++i) a.w[3 + i] = static_cast<float>(l.v2[i]);
  a.ref = l.hull;
  return a;
}

/// The leaf as the kernel sees it (float).
Leaf1 rounded(Leaf1 l) {
  l.p = test::round_to_float(l.p);
  l.R = test::round_to_float(l.R);
  l.e = test::round_to_float(l.e);
  l.v1 = test::round_to_float(l.v1);
  l.v2 = test::round_to_float(l.v2);
  return l;
}

struct Plane {
  Vec3d p, n;  // solid: n.(x - p) <= 0
};

using Result = test::PairResult;

HullStore& store() {
  static HullStore s;
  return s;
}
std::vector<HullData>& hull_data() {
  static std::vector<HullData> d;
  return d;
}

/// One lane through the bucket's kernel (pair_kernel: the lane kernels of spheres,
/// capsules, boxes, cylinders and ellipsoids; the support routine of hulls and
/// triangles) on the given path. The tests check both paths: they may differ by
/// rounding, and where vertices tie by a different (equally valid) choice.
Result run(const Leaf1& l, const Plane& pl, KernelPath path = KernelPath::kSimd) {
  Arrays a = arrays_of(l);
  Arrays b{};
  for (int i = 0; i < 3; ++i) {
    b.p[i] = static_cast<float>(pl.p[i]);
    b.e[i] = static_cast<float>(pl.n[i]);
  }
  test::ManifoldLanes out;
  NarrowConfig cfg;
  cfg.hulls = store().view();
  cfg.path = path;
  const PairKernel kernel = pair_kernel(l.type, kLeafHalfSpace);
  EXPECT_NE(kernel, nullptr);
  if (kernel != nullptr) kernel(a.soa(), b.soa(), out.view(), Range{0, 1}, cfg);
  return out.result();
}

/// Signed distance of A's lowest point to the plane (closed forms, double).
double lowest(const Leaf1& l, const Plane& pl) {
  const Vec3d& n = pl.n;
  auto sd = [&](const Vec3d& x) { return n.dot(x - pl.p); };
  switch (l.type) {
    case kLeafSphere: return sd(l.p) - l.e[0];
    case kLeafCapsule: {
      const Vec3d u = l.R.col(2);
      return std::min(sd(l.p + u * l.e[1]), sd(l.p - u * l.e[1])) - l.e[0];
    }
    case kLeafBox: {
      double m = INFINITY;
      for (int i = 0; i < 8; ++i)
        m = std::min(m, sd(l.p + l.R * Vec3d((i & 1) ? l.e[0] : -l.e[0], (i & 2) ? l.e[1] : -l.e[1],
                                              (i & 4) ? l.e[2] : -l.e[2])));
      return m;
    }
    case kLeafConvex: {
      double m = INFINITY;
      for (const auto& v : hull_data()[l.hull].vertices) m = std::min(m, sd(l.p + l.R * v.cast<double>()));
      return m;
    }
    case kLeafCylinder: {
      const Vec3d u = l.R.col(2);
      // |n x u| = sin of the tilt (well conditioned, unlike sqrt(1 - (n.u)^2)).
      const double radial = l.e[0] * n.cross(u).norm();
      return std::min(sd(l.p + u * l.e[1]), sd(l.p - u * l.e[1])) - radial;
    }
    case kLeafEllipsoid: {
      const Vec3d nl = l.R.transpose() * n;
      return sd(l.p) - std::sqrt((nl.cwiseProduct(l.e)).squaredNorm());
    }
    case kLeafTriangle: return std::min({sd(l.p), sd(l.v1), sd(l.v2)});
    default: return 0;
  }
}

/// Is x in the leaf (within tol)?
bool contains(const Leaf1& l, const Vec3d& x, double tol) {
  const Vec3d q = l.R.transpose() * (x - l.p);
  switch (l.type) {
    case kLeafSphere: return (x - l.p).norm() <= l.e[0] + tol;
    case kLeafCapsule: {
      const double z = std::clamp(q.z(), -l.e[1], l.e[1]);
      return (q - Vec3d(0, 0, z)).norm() <= l.e[0] + tol;
    }
    case kLeafBox: return (q.cwiseAbs() - l.e).maxCoeff() <= tol;
    case kLeafConvex: {
      const HullData& h = hull_data()[l.hull];
      for (size_t f = 0; f < h.faces.size(); ++f)
        if (h.face_normals[f].cast<double>().dot(q) > h.face_offsets[f] + tol) return false;
      return true;
    }
    case kLeafCylinder: return std::hypot(q.x(), q.y()) <= l.e[0] + tol && std::fabs(q.z()) <= l.e[1] + tol;
    case kLeafEllipsoid: return q.cwiseQuotient(l.e).norm() <= 1 + tol / l.e.minCoeff();
    case kLeafTriangle: {
      const Vec3d nn = (l.v1 - l.p).cross(l.v2 - l.p).normalized();
      if (std::fabs(nn.dot(x - l.p)) > tol) return false;
      const Vec3d vs[3] = {l.p, l.v1, l.v2};
      for (int i = 0; i < 3; ++i)
        if ((vs[(i + 1) % 3] - vs[i]).normalized().cross(x - vs[i]).dot(nn) < -tol) return false;
      return true;
    }
    default: return false;
  }
}

uint32_t test_hull() {
  static const uint32_t id = [] {
    std::mt19937 g(5);
    std::normal_distribution<float> n;
    std::vector<Eigen::Vector3f> pts;
    for (int i = 0; i < 30; ++i) pts.emplace_back(n(g), 0.5f * n(g), 0.8f * n(g));
    HullData h;
    EXPECT_TRUE(test::IsOk(build_convex_hull(pts, &h)));
    hull_data().push_back(h);
    return store().add(h);
  }();
  return id;
}

Leaf1 random_leaf(LeafType t, std::mt19937& rng, const Vec3d& c, double size) {
  std::uniform_real_distribution<double> u(0.2, 1.0), v(-1, 1);
  Leaf1 l;
  l.type = t;
  l.p = c;
  l.R = test::random_rotation(rng);
  l.e = Vec3d(u(rng), u(rng), u(rng)) * size;
  if (t == kLeafConvex) l.hull = test_hull();
  if (t == kLeafTriangle) {
    l.p = c + Vec3d(v(rng), v(rng), v(rng)) * size;
    l.v1 = c + Vec3d(v(rng), v(rng), v(rng)) * size;
    l.v2 = c + Vec3d(v(rng), v(rng), v(rng)) * size;
  }
  return rounded(l);
}

class SupportHalfspace : public ::testing::TestWithParam<std::tuple<double, double>> {};

TEST_P(SupportHalfspace, DeepestPointAndManifoldAgreeWithClosedForms) {
  const auto [size, offset] = GetParam();
  std::mt19937 rng(31);
  std::uniform_real_distribution<double> v(-1, 1);
  const LeafType types[] = {kLeafSphere, kLeafCapsule, kLeafBox, kLeafConvex, kLeafCylinder, kLeafEllipsoid, kLeafTriangle};
  const int trials = static_cast<int>(test::scaled(300));
  // Float rounding of the inputs: the size's and the offset's.
  const double tol = 2e-6 * size + 4e-7 * offset;
  for (LeafType t : types) {
    if (t == kLeafConvex && size != 1.0) continue;  // the test hull has size ~1
    int hits = 0;
    for (int k = 0; k < trials; ++k) {
      const Vec3d c = Vec3d(1, -2, 0.5) * offset + Vec3d(v(rng), v(rng), v(rng)) * size;
      const Leaf1 l = random_leaf(t, rng, c, size);
      Plane pl;
      pl.n = Vec3d(v(rng), v(rng), v(rng)).normalized();
      if (k % 5 == 0) pl.n = l.R.col(k % 3);  // axis-aligned with the shape: flat contacts
      pl.n = test::round_to_float(pl.n);
      pl.p = test::round_to_float((Vec3d(1, -2, 0.5) * offset + Vec3d(v(rng), v(rng), v(rng)) * size * 0.5));
      const double depth = -lowest(l, pl);
      if (std::fabs(depth) < tol * 4) continue;
      for (KernelPath path : {KernelPath::kSimd, KernelPath::kScalar}) {
        const Result r = run(l, pl, path);
        ASSERT_EQ(r.count > 0, depth > 0) << tname(t) << " " << k << " depth " << depth;
        if (depth <= 0) continue;
        hits += path == KernelPath::kSimd;
        ASSERT_LE(r.count, 4u);
        EXPECT_NEAR(r.depth, depth, tol * 4) << tname(t) << " " << k;
        EXPECT_NEAR((r.n + pl.n).norm(), 0.0, 1e-6);
        double maxpd = 0;
        for (uint32_t j = 0; j < r.count; ++j) {
          EXPECT_GT(r.pd[j], 0.0);
          EXPECT_LE(r.pd[j], r.depth + tol);
          maxpd = std::max(maxpd, r.pd[j]);
          // A's point x = pt - nh pd/2 lies in A, pd below the plane.
          const Vec3d x = r.pt[j] - pl.n * (0.5 * r.pd[j]);
          EXPECT_NEAR(pl.n.dot(x - pl.p), -r.pd[j], tol * 4) << tname(t) << " " << k;
          EXPECT_TRUE(contains(l, x, tol * 4)) << tname(t) << " " << k;
        }
        EXPECT_NEAR(maxpd, r.depth, tol * 4);
        // Distinct points.
        for (uint32_t i = 0; i < r.count; ++i)
          for (uint32_t j = i + 1; j < r.count; ++j)
            EXPECT_GT((r.pt[i] - r.pt[j]).norm(), 1e-6 * size) << tname(t) << " " << k << " points " << i << " " << j;
      }
    }
    EXPECT_GT(hits, trials / 10) << tname(t);
  }
}

INSTANTIATE_TEST_SUITE_P(Scales, SupportHalfspace, ::testing::ValuesIn(test::kernel_scales()));

void resting_shapes(KernelPath path) {
  SCOPED_TRACE(path == KernelPath::kSimd ? "simd" : "scalar");
  const Plane ground{Vec3d::Zero(), Vec3d::UnitZ()};
  const Mat3d I = Mat3d::Identity();
  // A box resting flat, 0.01 deep: 4 corners.
  Leaf1 b;
  b.type = kLeafBox;
  b.p = Vec3d(3, 4, 0.49);
  b.R = Eigen::AngleAxisd(0.4, Vec3d::UnitZ()).toRotationMatrix();
  b.e = Vec3d(1, 0.7, 0.5);
  Result r = run(rounded(b), ground, path);
  ASSERT_EQ(r.count, 4u);
  for (uint32_t j = 0; j < 4; ++j) {
    EXPECT_NEAR(r.pd[j], 0.01, 1e-6);
    EXPECT_NEAR(r.pt[j].z(), -0.005, 1e-6);
  }
  // A box on an edge: 2 points.
  b.p = Vec3d(0, 0, 0.5 * std::sqrt(2.0) - 0.01);
  b.R = Eigen::AngleAxisd(M_PI / 4, Vec3d::UnitX()).toRotationMatrix();
  b.e = Vec3d(1, 0.5, 0.5);
  r = run(rounded(b), ground, path);
  ASSERT_EQ(r.count, 2u);
  EXPECT_NEAR(std::fabs(r.pt[0].x() - r.pt[1].x()), 2.0, 1e-5);
  // An upright cylinder: 4 rim points; lying on its side: 2; tilted on its rim: 1.
  Leaf1 c;
  c.type = kLeafCylinder;
  c.p = Vec3d(0, 0, 0.99);
  c.R = I;
  c.e = Vec3d(0.5, 1.0, 0);
  r = run(rounded(c), ground, path);
  ASSERT_EQ(r.count, 4u);
  for (uint32_t j = 0; j < 4; ++j) EXPECT_NEAR(Vec3d(r.pt[j].x(), r.pt[j].y(), 0).norm(), 0.5, 1e-6);
  c.p = Vec3d(0, 0, 0.49);
  c.R = Eigen::AngleAxisd(M_PI / 2, Vec3d::UnitY()).toRotationMatrix();
  r = run(rounded(c), ground, path);
  ASSERT_EQ(r.count, 2u);
  EXPECT_NEAR(std::fabs(r.pt[0].x() - r.pt[1].x()), 2.0, 1e-5);
  c.R = Eigen::AngleAxisd(0.3, Vec3d::UnitY()).toRotationMatrix();
  c.p = Vec3d(0, 0, std::cos(0.3) * 1.0 + std::sin(0.3) * 0.5 - 0.01);
  r = run(rounded(c), ground, path);
  ASSERT_EQ(r.count, 1u);
  EXPECT_NEAR(r.depth, 0.01, 1e-6);
  // A capsule lying flat: 2 points; a sphere and an ellipsoid: 1.
  Leaf1 k;
  k.type = kLeafCapsule;
  k.p = Vec3d(0, 0, 0.29);
  k.R = Eigen::AngleAxisd(M_PI / 2, Vec3d::UnitX()).toRotationMatrix();
  k.e = Vec3d(0.3, 1.0, 0);
  r = run(rounded(k), ground, path);
  ASSERT_EQ(r.count, 2u);
  EXPECT_NEAR(r.pd[0], 0.01, 1e-6);
  // Standing upright, sunk 0.4: one point (the surface below both endpoints is the lower
  // cap's tip); tilted 0.2 rad, still steep: one; tilted 1.4 rad and sunk 0.5: two.
  k.R = I;
  k.p = Vec3d(0, 0, 0.9);
  r = run(rounded(k), ground, path);
  ASSERT_EQ(r.count, 1u);
  EXPECT_NEAR(r.depth, 0.4, 1e-6);
  EXPECT_NEAR(r.pt[0].x(), 0.0, 1e-6);
  k.R = Eigen::AngleAxisd(0.2, Vec3d::UnitX()).toRotationMatrix();
  r = run(rounded(k), ground, path);
  ASSERT_EQ(r.count, 1u);
  EXPECT_NEAR(r.depth, 0.3 + std::cos(0.2) - 0.9, 1e-6);
  k.R = Eigen::AngleAxisd(1.4, Vec3d::UnitX()).toRotationMatrix();
  k.p = Vec3d(0, 0, -0.2 + std::cos(1.4));
  r = run(rounded(k), ground, path);
  ASSERT_EQ(r.count, 2u);
  EXPECT_NEAR(r.depth, 0.5, 1e-6);
  EXPECT_GT((r.pt[0] - r.pt[1]).norm(), 1.5);
  // A cylinder upright and entirely below: its 4 lower rim points, the deepest first; on
  // its side sunk past its axis: the 2 ends of the lowest line.
  c.R = I;
  c.p = Vec3d(0, 0, -5);
  r = run(rounded(c), ground, path);
  ASSERT_EQ(r.count, 4u);
  for (uint32_t j = 0; j < 4; ++j) EXPECT_NEAR(r.pd[j], 6.0, 1e-5);
  c.R = Eigen::AngleAxisd(M_PI / 2, Vec3d::UnitY()).toRotationMatrix();
  c.p = Vec3d(0, 0, -0.2);
  r = run(rounded(c), ground, path);
  ASSERT_EQ(r.count, 2u);
  EXPECT_NEAR(r.depth, 0.7, 1e-6);
  Leaf1 e;
  e.type = kLeafEllipsoid;
  e.p = Vec3d(0, 0, 0.19);
  e.e = Vec3d(1, 2, 0.2);
  r = run(rounded(e), ground, path);
  ASSERT_EQ(r.count, 1u);
  EXPECT_NEAR(r.depth, 0.01, 1e-6);
  // A triangle with two vertices below (0.3 and 0.1 deep): those two, deepest first,
  // whatever the vertex order; all three below: all three.
  Leaf1 t;
  t.type = kLeafTriangle;
  t.p = Vec3d(1, 0, -0.1);
  t.v1 = Vec3d(0, 1, 0.5);
  t.v2 = Vec3d(-1, 0, -0.3);
  r = run(rounded(t), ground, path);
  ASSERT_EQ(r.count, 2u);
  EXPECT_NEAR(r.depth, 0.3, 1e-6);
  EXPECT_NEAR(r.pd[0], 0.3, 1e-6);
  EXPECT_NEAR(r.pd[1], 0.1, 1e-6);
  EXPECT_NEAR(r.pt[0].x(), -1.0, 1e-6);
  EXPECT_NEAR(r.pt[1].x(), 1.0, 1e-6);
  t.v1.z() = -0.2;
  r = run(rounded(t), ground, path);
  ASSERT_EQ(r.count, 3u);
  EXPECT_NEAR(r.pd[1], 0.2, 1e-6);
  EXPECT_NEAR(r.pt[1].y(), 1.0, 1e-6);
  // Separated, and a box exactly touching: nothing.
  e.p = Vec3d(0, 0, 0.2001);
  EXPECT_EQ(run(rounded(e), ground, path).count, 0u);
  e.p = Vec3d(0, 0, 0.3);
  EXPECT_EQ(run(rounded(e), ground, path).count, 0u);
  b.p = Vec3d(0.25, 0, 0.5);
  b.R = I;
  EXPECT_EQ(run(rounded(b), ground, path).count, 0u);
}

TEST(SupportHalfspaceManifold, RestingShapesGiveTheirContactPatch) {
  resting_shapes(KernelPath::kSimd);
  resting_shapes(KernelPath::kScalar);
}

/// A deeply sunk hull: the 4 points spread out (the deepest first, then the farthest).
TEST(SupportHalfspaceManifold, SunkHullKeepsDeepestAndSpreadPoints) {
  Leaf1 h;
  h.type = kLeafConvex;
  h.hull = test_hull();
  h.p = Vec3d(0, 0, -10);  // entirely below
  const Result r = run(rounded(h), Plane{Vec3d::Zero(), Vec3d::UnitZ()});
  ASSERT_EQ(r.count, 4u);
  for (uint32_t j = 1; j < 4; ++j) EXPECT_LE(r.pd[j], r.pd[0]);
  EXPECT_NEAR(r.pd[0], r.depth, 1e-6);
  EXPECT_GT((r.pt[1] - r.pt[0]).norm(), 1.0);
}

/// A hull of ~400 vertices (points on an ellipsoid) sunk from barely to entirely below
/// the plane, so that the vertices below range from one to all of them (through
/// collide_convex_halfspace's big-hull fallback, collide_support_halfspace): both the
/// candidate list of that routine (up to 32 vertices below, kBelowList) and its fallback over all
/// vertices. Against a brute force over the vertices in double: depth = the deepest
/// vertex's, pd[0] is it, count = min(4, vertices below) where they span an area,
/// every point is a vertex below moved up by pd/2, and point 1 is the vertex below
/// farthest from point 0.
TEST(SupportHalfspaceManifold, ManyVertexHullAtEverySinking) {
  static const uint32_t big = [] {
    std::mt19937 g(8);
    std::normal_distribution<float> n;
    std::vector<Eigen::Vector3f> pts;
    for (int i = 0; i < 400; ++i) {
      Eigen::Vector3f u(n(g), n(g), n(g));
      u.normalize();
      pts.emplace_back(u.x(), 0.6f * u.y(), 0.8f * u.z());
    }
    HullData h;
    EXPECT_TRUE(test::IsOk(build_convex_hull(pts, &h)));
    hull_data().push_back(h);
    return store().add(h);
  }();
  const HullData& hd = hull_data()[big];
  ASSERT_GT(hd.vertices.size(), 200u);
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> v(-1, 1), sink(0.0, 2.2);
  int few = 0, many = 0;
  for (int k = 0; k < 200; ++k) {
    Leaf1 l;
    l.type = kLeafConvex;
    l.hull = big;
    l.R = test::random_rotation(rng);
    l.p = Vec3d(v(rng), v(rng), v(rng)) * (k % 2 == 0 ? 1.0 : 1e5);
    l = rounded(l);
    Plane pl;
    pl.n = test::round_to_float(Vec3d(v(rng), v(rng), v(rng)).normalized());
    // The lowest vertex, then the plane `sink` above it.
    std::vector<Vec3d> w;
    double lo = INFINITY;
    for (const auto& x : hd.vertices) {
      w.push_back(l.p + l.R * x.cast<double>());
      lo = std::min(lo, pl.n.dot(w.back()));
    }
    pl.p = test::round_to_float((l.p + pl.n * (lo - pl.n.dot(l.p) + sink(rng))));
    const double off = pl.n.dot(pl.p);
    // Float rounding: the hull's (size 1) and the world coordinates' (ulp of |p|).
    const double tol = 1e-5 + 1e-7 * l.p.norm();
    std::vector<Vec3d> below;
    double depth = 0;
    for (const Vec3d& x : w) {
      const double d = off - pl.n.dot(x);
      if (d > tol) below.push_back(x);
      depth = std::max(depth, d);
    }
    if (below.size() < 5) continue;  // few points: ties at the threshold
    (below.size() <= 32 ? few : many)++;
    const Result r = run(l, pl);
    ASSERT_EQ(r.count, 4u) << k << " below " << below.size();
    EXPECT_NEAR(r.depth, depth, tol) << k;
    EXPECT_NEAR(r.pd[0], depth, tol) << k;
    Vec3d x[4];
    for (uint32_t j = 0; j < 4; ++j) {
      x[j] = r.pt[j] - pl.n * (0.5 * r.pd[j]);
      double best = INFINITY;
      for (const Vec3d& y : w) best = std::min(best, (y - x[j]).norm());
      EXPECT_LT(best, 4 * tol) << k << " point " << j << " is no vertex";
      EXPECT_NEAR(off - pl.n.dot(x[j]), r.pd[j], 4 * tol) << k;
    }
    // Vertices within rounding of the plane may count either way: the farthest of
    // those surely below bounds it from below, of those possibly below from above.
    double far_in = 0, far_maybe = 0;
    for (const Vec3d& y : below) far_in = std::max(far_in, (y - x[0]).norm());
    for (const Vec3d& y : w)
      if (off - pl.n.dot(y) > -tol) far_maybe = std::max(far_maybe, (y - x[0]).norm());
    EXPECT_GE((x[1] - x[0]).norm(), far_in - 8 * tol) << k;
    EXPECT_LE((x[1] - x[0]).norm(), far_maybe + 8 * tol) << k;
  }
  EXPECT_GT(few, 10);
  EXPECT_GT(many, 10);
}

}  // namespace
}  // namespace impact::kernels
