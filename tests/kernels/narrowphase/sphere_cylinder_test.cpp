// collide_sphere_cylinder (kernels/narrowphase/pairs/sphere/sphere_cylinder.cpp) on both paths
// against an independent double-precision reference: the distance from the sphere's
// centre to the solid cylinder by dense sampling of the cylinder's surface (outside),
// and the minimum translation out of it (inside: through the side or a cap), on random
// poses at sizes 1e-4, 1 and 1e4 and 1e5 from the origin; plus analytic cases (side,
// cap, rim, centre on the axis, centre at the cylinder's centre, exactly touching).
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <random>

#include "kernels/narrowphase/pair_kernels.h"
#include "support/kernel_checks.h"
#include "support/leaf_lanes.h"
#include "support/random_input.h"
#include "support/test_support.h"

namespace impact::kernels {
namespace {

using Vec3d = Eigen::Vector3d;
using Mat3d = Eigen::Matrix3d;

struct Cyl {
  Vec3d p;
  Mat3d R;  // column 2 = axis
  double r, h;
};

struct Hit {
  uint32_t count = 0;
  Vec3d n, pt;
  double depth = 0, pd = 0;
};

Hit run(const Vec3d& c, double ra, const Cyl& cy, KernelPath path) {
  float ap[3], ae[3] = {static_cast<float>(ra), 0, 0};
  float bp[3], br[9], be[3] = {static_cast<float>(cy.r), static_cast<float>(cy.h), 0};
  for (int i = 0; i < 3; ++i) ap[i] = static_cast<float>(c[i]), bp[i] = static_cast<float>(cy.p[i]);
  for (int i = 0; i < 9; ++i) br[i] = static_cast<float>(cy.R(i / 3, i % 3));
  LeafSoA a{}, b{};
  for (int i = 0; i < 3; ++i) a.p[i] = &ap[i], a.e[i] = &ae[i], b.p[i] = &bp[i], b.e[i] = &be[i];
  for (int i = 0; i < 9; ++i) b.r[i] = &br[i];
  test::ManifoldLanes out;
  NarrowConfig cfg;
  cfg.path = path;
  const PairKernel k = pair_kernel(kLeafSphere, kLeafCylinder);
  EXPECT_EQ(k, &collide_sphere_cylinder);
  k(a, b, out.view(), Range{0, 1}, cfg);
  const test::PairResult r = out.result();
  Hit h;
  h.count = r.count;
  if (r.count == 0) return h;
  h.n = r.n;
  h.pt = r.pt[0];
  h.depth = r.depth;
  h.pd = r.pd[0];
  return h;
}

/// Reference in double, in the cylinder frame: outside, the distance to the solid by
/// sampling its surface (side, caps) densely and refining around the best sample;
/// inside, the smaller of the side and cap penetrations. Returns the signed depth
/// (ra - distance, or ra + penetration) and the separating direction from the centre.
double reference(const Vec3d& c, double ra, const Cyl& cy, Vec3d* dir) {
  const Vec3d d = cy.R.transpose() * (c - cy.p);
  const double rq = std::hypot(d.x(), d.y());
  if (rq <= cy.r && std::fabs(d.z()) <= cy.h) {
    const double ps = cy.r - rq, pc = cy.h - std::fabs(d.z());
    const Vec3d radial = rq > 0 ? Vec3d(d.x() / rq, d.y() / rq, 0) : Vec3d(1, 0, 0);
    *dir = cy.R * (ps <= pc ? Vec3d(-radial) : Vec3d(0, 0, d.z() >= 0 ? -1.0 : 1.0));
    return ra + std::min(ps, pc);
  }
  // Surface points: (rho cos t, rho sin t, z) on the side (rho = r) and caps (z = +-h).
  double best = INFINITY;
  Vec3d best_x = Vec3d::Zero();
  auto consider = [&](const Vec3d& x) {
    const double dd = (x - d).norm();
    if (dd < best) best = dd, best_x = x;
  };
  double t0 = 0, tw = M_PI, z0 = 0, zw = cy.h, p0 = cy.r / 2, pw = cy.r / 2;
  for (int round = 0; round < 12; ++round) {
    const int m = 24;
    for (int i = 0; i <= m; ++i) {
      const double t = t0 - tw + 2 * tw * i / m;
      for (int j = 0; j <= m; ++j) {
        const double z = std::clamp(z0 - zw + 2 * zw * j / m, -cy.h, cy.h);
        consider(Vec3d(cy.r * std::cos(t), cy.r * std::sin(t), z));
        const double rho = std::clamp(p0 - pw + 2 * pw * j / m, 0.0, cy.r);
        consider(Vec3d(rho * std::cos(t), rho * std::sin(t), cy.h));
        consider(Vec3d(rho * std::cos(t), rho * std::sin(t), -cy.h));
      }
    }
    t0 = std::atan2(best_x.y(), best_x.x());
    z0 = best_x.z();
    p0 = std::hypot(best_x.x(), best_x.y());
    tw *= 0.25, zw *= 0.25, pw *= 0.25;
  }
  *dir = cy.R * (best_x - d).normalized();
  return ra - best;
}

class SphereCylinder : public ::testing::TestWithParam<std::tuple<double, double>> {};

TEST_P(SphereCylinder, RandomPosesAgainstDoubleReference) {
  const auto [size, offset] = GetParam();
  std::mt19937 g(17);
  std::uniform_real_distribution<double> u(-1, 1), s(0.2, 1.0);
  const int trials = static_cast<int>(test::scaled(400));
  const double tol = 4e-6 * size + 2e-7 * offset;
  int hits = 0, inside = 0;
  for (int k = 0; k < trials; ++k) {
    Cyl cy;
    cy.p = test::round_to_float((Vec3d(offset, -offset, 0.5 * offset) + Vec3d(u(g), u(g), u(g)) * size));
    cy.R = test::round_to_float(test::random_rotation(g));
    cy.r = test::round_to_float(s(g) * size);
    cy.h = test::round_to_float(s(g) * size);
    const double ra = test::round_to_float(s(g) * size);
    // centres from deep inside to well outside
    const Vec3d c = test::round_to_float((cy.p + Vec3d(u(g), u(g), u(g)) * (1.3 * size)));
    Vec3d dir;
    const double want = reference(c, ra, cy, &dir);
    for (KernelPath path : {KernelPath::kSimd, KernelPath::kScalar}) {
      const Hit h = run(c, ra, cy, path);
      if (std::fabs(want) < 4 * tol) continue;
      ASSERT_EQ(h.count > 0, want > 0) << k << " want " << want;
      if (want <= 0) continue;
      hits += path == KernelPath::kSimd;
      const Vec3d d = cy.R.transpose() * (c - cy.p);
      inside += path == KernelPath::kSimd && std::hypot(d.x(), d.y()) < cy.r && std::fabs(d.z()) < cy.h;
      EXPECT_NEAR(h.depth, want, 4 * tol) << k;
      EXPECT_NEAR(h.pd, h.depth, 0.0);
      EXPECT_NEAR(h.n.norm(), 1.0, 1e-6);
      // The direction matters only where it is unique (not at a tie of side and cap).
      EXPECT_GT(h.n.dot(dir), 1 - 1e-3) << k;
      // point +- n depth / 2: on the sphere and on the cylinder's surface
      const Vec3d on_a = h.pt + h.n * (0.5 * h.depth);
      EXPECT_NEAR((on_a - c).norm(), ra, 4 * tol) << k;
    }
  }
  EXPECT_GT(hits, trials / 5);
  EXPECT_GT(inside, trials / 50);
}

INSTANTIATE_TEST_SUITE_P(Scales, SphereCylinder, ::testing::ValuesIn(test::kernel_scales()));

TEST(SphereCylinderAnalytic, SideCapRimAxisAndTouching) {
  Cyl cy{Vec3d(3, -2, 1), Mat3d::Identity(), 1.0, 2.0};
  for (KernelPath path : {KernelPath::kSimd, KernelPath::kScalar}) {
    // beside the side, 0.1 deep: n towards the cylinder (-x)
    Hit h = run(cy.p + Vec3d(1.4, 0, 0.5), 0.5, cy, path);
    ASSERT_EQ(h.count, 1u);
    EXPECT_NEAR(h.depth, 0.1, 1e-6);
    EXPECT_NEAR((h.n - Vec3d(-1, 0, 0)).norm(), 0, 1e-6);
    EXPECT_NEAR((h.pt - (cy.p + Vec3d(0.95, 0, 0.5))).norm(), 0, 1e-6);
    // above the cap, 0.2 deep: n = -z
    h = run(cy.p + Vec3d(0.3, 0.2, 2.3), 0.5, cy, path);
    ASSERT_EQ(h.count, 1u);
    EXPECT_NEAR(h.depth, 0.2, 1e-6);
    EXPECT_NEAR((h.n - Vec3d(0, 0, -1)).norm(), 0, 1e-6);
    // off the rim, diagonally: distance sqrt(0.3^2 + 0.4^2) = 0.5 to the rim point
    h = run(cy.p + Vec3d(0, 1.3, 2.4), 0.6, cy, path);
    ASSERT_EQ(h.count, 1u);
    EXPECT_NEAR(h.depth, 0.1, 1e-6);
    EXPECT_NEAR((h.n - Vec3d(0, -0.6, -0.8)).norm(), 0, 1e-6);
    // inside near the side: out through it (depth = r + 0.1)
    h = run(cy.p + Vec3d(0, -0.9, 0.0), 0.5, cy, path);
    ASSERT_EQ(h.count, 1u);
    EXPECT_NEAR(h.depth, 0.6, 1e-6);
    EXPECT_NEAR((h.n - Vec3d(0, 1, 0)).norm(), 0, 1e-6);
    // inside near the lower cap: out through it
    h = run(cy.p + Vec3d(0.2, 0, -1.95), 0.5, cy, path);
    ASSERT_EQ(h.count, 1u);
    EXPECT_NEAR(h.depth, 0.55, 1e-6);
    EXPECT_NEAR((h.n - Vec3d(0, 0, 1)).norm(), 0, 1e-6);
    // on the axis, at the centre: the side (shallower: 1 < 2), along -R column 0
    h = run(cy.p, 0.5, cy, path);
    ASSERT_EQ(h.count, 1u);
    EXPECT_NEAR(h.depth, 1.5, 1e-6);
    EXPECT_NEAR((h.n - Vec3d(-1, 0, 0)).norm(), 0, 1e-6);
    EXPECT_TRUE(std::isfinite(h.pt.x()));
    // exactly touching the side and separated: no contact
    EXPECT_EQ(run(cy.p + Vec3d(1.5, 0, 0), 0.5, cy, path).count, 0u);
    EXPECT_EQ(run(cy.p + Vec3d(0, 0, 3.0), 0.5, cy, path).count, 0u);
  }
}

}  // namespace
}  // namespace impact::kernels
