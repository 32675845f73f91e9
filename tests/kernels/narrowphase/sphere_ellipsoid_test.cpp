// collide_sphere_ellipsoid (kernels/narrowphase/pairs/sphere/sphere_ellipsoid.cpp) on both paths
// against an independent double-precision reference.
//
// Reference (double, in the ellipsoid's frame, radii sorted;
// tests/support/ellipsoid_reference.h): the closest surface point
// by plain bisection of the secular equation to the last bit, with the cases of a point
// on a principal plane written out (a zero component has a zero closest coordinate,
// except an inside point on the smallest axis's plane whose nearest point lies off it;
// Eberly, "Distance from a Point to an Ellipse, an Ellipsoid, or a Hyperellipsoid",
// 2013). The reference is itself checked against a dense parametric sampling of the
// surface refined by pattern search (no secular equation) and against the Lagrange
// conditions. The kernel solves in float with a fixed count of Newton / pole steps.
//
// Per lane, L = max(largest radius, sphere radius), tol = kRel * L:
//  (a) count > 0 iff the reference depth > 0 (either where |depth_ref| <= tol);
//  (b) |depth - depth_ref| <= tol (centre inside: r + distance to the surface);
//  (c) n finite and unit; angle(n, n_ref) <= 1e-3 rad where the nearest point is well
//      conditioned (the reference's normal turns by < 1e-2 rad when the centre moves by
//      1e-5 L; elsewhere, near the medial axis, the nearest point is nearly not unique);
//  (d) point[0] +- n depth/2 lie on the sphere and on the ellipsoid (within tol plus an
//      ulp of the largest world coordinate), pdepth[0] == depth;
//  (e) the scalar and SIMD paths agree within tol (depth) and 1e-4 rad (normal).
// Scenarios: random poses (outside, touching, inside, deep) at sizes 1, 1e-4, 1e4 and
// 1e5 from the origin; needle and pancake ellipsoids (radius ratios 1e-3, 1e-4) with
// centres near their thin parts, rims and tips; centres exactly on principal planes and
// axes, and within 1e-7 .. 1e-20 of them; the centre at the ellipsoid's centre (depth r +
// the smallest radius along that axis; ties: the lowest axis index); exactly touching
// (count 0); a round ellipsoid against sphere-sphere. Range partitions and the agreement
// with GJK / EPA: contract_test.cpp.
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <random>
#include <vector>

#include "kernels/narrowphase/pair_kernels.h"
#include "support/ellipsoid_reference.h"
#include "support/kernel_checks.h"
#include "support/leaf_lanes.h"
#include "support/random_input.h"
#include "support/shape_geometry.h"
#include "support/test_support.h"

namespace impact::kernels {
namespace {

using Vec3d = Eigen::Vector3d;
using Mat3d = Eigen::Matrix3d;
using test::angle;
using test::eref::closest_local;
using test::eref::level;

constexpr double kRel = 1e-5;       // depth tolerance, of L
constexpr double kAngleTol = 1e-3;  // rad, where the nearest point is well conditioned
constexpr double kPathAngleTol = 1e-4;

struct Ell {
  Vec3d p;
  Mat3d R;  // columns: the axes of e
  Vec3d e;
};

struct Query {
  Vec3d c;  // sphere centre
  double r;
  Ell b;
};

/// The query as the kernel sees it: every input rounded to float.
Query rounded(Query q) {
  q.c = test::round_to_float(q.c);
  q.r = test::round_to_float(q.r);
  q.b.p = test::round_to_float(q.b.p);
  q.b.R = test::round_to_float(q.b.R);
  q.b.e = test::round_to_float(q.b.e);
  return q;
}

double largest(const Query& q) {
  return std::max(q.b.e.maxCoeff(), q.r);
}

/// A pair's two leaves as the kernel reads them.
std::pair<test::Leaf, test::Leaf> leaves(const Query& q) {
  return {test::sphere_leaf(q.c, q.r), test::posed_leaf(kLeafEllipsoid, q.b.p, q.b.R, q.b.e)};
}

std::vector<test::PairResult> run(const std::vector<Query>& qs, KernelPath path) {
  return test::run_table_kernel(kLeafSphere, kLeafEllipsoid, &collide_sphere_ellipsoid, qs, path, leaves);
}

// ---------------------------------------------------------------------------------------
// Reference
// ---------------------------------------------------------------------------------------

struct Ref {
  double depth;  // r - signed distance
  Vec3d n;       // world, A to B: minus the outward normal at the nearest point
  Vec3d x;       // nearest surface point, local frame
  bool inside;
};

Ref reference(const Query& q) {
  const Vec3d y = q.b.R.transpose() * (q.c - q.b.p);
  Ref f;
  f.x = closest_local(q.b.e, y);
  f.inside = level(q.b.e, y) < 1;
  const double dist = (y - f.x).norm();
  f.depth = f.inside ? q.r + dist : q.r - dist;
  const Vec3d grad = f.x.cwiseQuotient(q.b.e.cwiseProduct(q.b.e));
  f.n = -(q.b.R * grad.normalized());
  return f;
}

/// Signed distance of a world point to the ellipsoid's surface (< 0 inside).
double signed_distance(const Ell& b, const Vec3d& w) {
  const Vec3d y = b.R.transpose() * (w - b.p);
  const double d = (y - closest_local(b.e, y)).norm();
  return level(b.e, y) < 1 ? -d : d;
}

/// Largest turn of the reference normal when the centre moves by 1e-5 L along the axes.
double normal_sensitivity(const Query& q, const Vec3d& n_ref) {
  double worst = 0;
  const double h = 1e-5 * largest(q);
  for (int i = 0; i < 6; ++i) {
    Query p = q;
    p.c[i % 3] += (i < 3 ? h : -h);
    const Vec3d n = reference(p).n;
    worst = std::max(worst, angle(n, n_ref));
  }
  return worst;
}

/// Brute force: the distance from local y to the surface by sampling (u, v) densely and
/// refining the best samples by pattern search (no secular equation).
double brute_distance(const Vec3d& e, const Vec3d& y) {
  auto pt = [&](double u, double v) {
    return Vec3d(e[0] * std::cos(u) * std::sin(v), e[1] * std::sin(u) * std::sin(v), e[2] * std::cos(v));
  };
  auto f = [&](double u, double v) { return (pt(u, v) - y).squaredNorm(); };
  struct S {
    double d, u, v;
  };
  std::vector<S> s;
  const int nu = 240, nv = 120;
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j <= nv; ++j) {
      const double u = 2 * M_PI * i / nu, v = M_PI * j / nv;
      s.push_back({f(u, v), u, v});
    }
  std::partial_sort(s.begin(), s.begin() + 12, s.end(), [](const S& x, const S& z) { return x.d < z.d; });
  double best = s[0].d;
  for (int k = 0; k < 12; ++k) {
    double u = s[k].u, v = s[k].v, val = s[k].d;
    for (double step = 2 * M_PI / nu; step > 1e-15;) {
      bool moved = false;
      for (const auto& [du, dv] :
           {std::pair{1, 0}, {-1, 0}, {0, 1}, {0, -1}, {1, 1}, {-1, -1}, {1, -1}, {-1, 1}}) {
        const double fu = u + du * step, fv = v + dv * step, fval = f(fu, fv);
        if (fval < val) {
          u = fu, v = fv, val = fval, moved = true;
          break;
        }
      }
      if (!moved) step *= 0.5;
    }
    best = std::min(best, val);
  }
  return std::sqrt(best);
}

// ---------------------------------------------------------------------------------------
// The per-lane check
// ---------------------------------------------------------------------------------------

struct Stats {
  int lanes = 0, hits = 0, inside = 0, normal_checked = 0, ill_conditioned = 0;
  double worst_depth = 0, worst_angle = 0, worst_path_depth = 0, worst_path_angle = 0;
};

double coord_ulp(const Query& q) {
  const double m = std::max({q.c.cwiseAbs().maxCoeff(), q.b.p.cwiseAbs().maxCoeff()});
  return (m + largest(q)) * std::ldexp(1.0, -23);
}

/// Checks (a)-(e) for every lane of qs (already rounded to float).
void check_all(const std::vector<Query>& qs, const char* what, Stats* st_out = nullptr) {
  SCOPED_TRACE(what);
  const std::vector<test::PairResult> simd = run(qs, KernelPath::kSimd), scal = run(qs, KernelPath::kScalar);
  Stats st;
  for (size_t k = 0; k < qs.size(); ++k) {
    const Query& q = qs[k];
    const Ref f = reference(q);
    const double L = largest(q), tol = kRel * L;
    ++st.lanes;
    for (const test::PairResult* hp : {&simd[k], &scal[k]}) {
      const test::PairResult& h = *hp;
      const bool is_simd = hp == &simd[k];
      if (std::fabs(f.depth) <= tol) continue;
      ASSERT_EQ(h.count > 0, f.depth > 0) << what << " lane " << k << " depth_ref " << f.depth << " got "
                                          << h.depth << (is_simd ? " simd" : " scalar");
      if (f.depth <= 0) continue;
      ASSERT_EQ(h.count, 1u);
      if (is_simd) {
        ++st.hits;
        st.inside += f.inside;
      }
      const double dd = std::fabs(h.depth - f.depth);
      st.worst_depth = std::max(st.worst_depth, dd / L);
      EXPECT_LE(dd, tol) << what << " lane " << k << " depth " << h.depth << " ref " << f.depth
                         << (f.inside ? " inside" : " outside") << " e " << q.b.e.transpose() << " r " << q.r;
      EXPECT_EQ(h.pd[0], h.depth);
      ASSERT_TRUE(h.n.allFinite());
      EXPECT_NEAR(h.n.norm(), 1.0, 1e-6);
      // (d) the point, half the depth from each surface
      const double slack = tol + coord_ulp(q);
      const auto [on_a, on_b] = test::contact_sides(h);
      EXPECT_NEAR((on_a - q.c).norm(), q.r, slack) << what << " lane " << k;
      EXPECT_NEAR(signed_distance(q.b, on_b), 0.0, slack) << what << " lane " << k;
    }
    if (f.depth > tol) {
      // (c) normals where the nearest point is well conditioned
      const double sens = normal_sensitivity(q, f.n);
      const bool ok = sens < 1e-2;
      if (!ok) ++st.ill_conditioned;
      if (ok && simd[k].count) {
        ++st.normal_checked;
        for (const test::PairResult* hp : {&simd[k], &scal[k]}) {
          const double ang = angle(hp->n, f.n);
          st.worst_angle = std::max(st.worst_angle, ang);
          EXPECT_LE(ang, kAngleTol) << what << " lane " << k << " n " << hp->n.transpose() << " ref "
                                    << f.n.transpose() << " e " << q.b.e.transpose();
        }
      }
      // (e) scalar and SIMD paths
      if (simd[k].count && scal[k].count) {
        const double pd = std::fabs(simd[k].depth - scal[k].depth);
        const double pa = angle(simd[k].n, scal[k].n);
        st.worst_path_depth = std::max(st.worst_path_depth, pd / L);
        st.worst_path_angle = std::max(st.worst_path_angle, pa);
        EXPECT_LE(pd, tol) << what << " lane " << k;
        if (ok) {
          EXPECT_LE(pa, kPathAngleTol) << what << " lane " << k;
        }
      }
    }
  }
  std::printf(
      "  %-34s lanes %5d hits %5d inside %5d normals %5d (ill-conditioned %3d) | worst depth %.2g L, "
      "angle %.2g; simd-scalar %.2g L, %.2g\n",
      what, st.lanes, st.hits, st.inside, st.normal_checked, st.ill_conditioned, st.worst_depth,
      st.worst_angle, st.worst_path_depth, st.worst_path_angle);
  if (st_out != nullptr) *st_out = st;
}

// ---------------------------------------------------------------------------------------
// Generators
// ---------------------------------------------------------------------------------------

Ell random_ellipsoid(std::mt19937& g, const Vec3d& centre, const Vec3d& radii) {
  return Ell{centre, test::random_rotation(g), radii};
}

/// Random poses around an ellipsoid of radii in [0.2, 1] * size at `offset` from the
/// origin: centres from deep inside to well outside.
std::vector<Query> random_queries(std::mt19937& g, int n, double size, double offset) {
  std::uniform_real_distribution<double> u(-1, 1), s(0.2, 1.0), rr(0.05, 1.0);
  std::vector<Query> qs;
  for (int k = 0; k < n; ++k) {
    Query q;
    const Vec3d p = Vec3d(offset, -offset, 0.5 * offset) + Vec3d(u(g), u(g), u(g)) * size;
    q.b = random_ellipsoid(g, p, Vec3d(s(g), s(g), s(g)) * size);
    q.r = rr(g) * size;
    // Half the centres in a box around the ellipsoid, half in its scaled-up frame.
    const Vec3d v(u(g), u(g), u(g));
    q.c = p + (k % 2 ? Vec3d(q.b.R * v.cwiseProduct(q.b.e) * 1.3) : Vec3d(v * (1.4 * size)));
    qs.push_back(rounded(q));
  }
  return qs;
}

/// Spheres nearly touching the ellipsoid: centred on the outward normal line of a
/// random surface point at r (1 + f), |f| <= 1e-3, so depth = -r f.
std::vector<Query> touching_queries(std::mt19937& g, int n) {
  std::uniform_real_distribution<double> u(-1, 1), s(0.2, 1.0), f(-1e-3, 1e-3);
  std::vector<Query> qs;
  for (int k = 0; k < n; ++k) {
    Query q;
    q.b = random_ellipsoid(g, Vec3d(u(g), u(g), u(g)), Vec3d(s(g), s(g), s(g)));
    Vec3d dir(u(g), u(g), u(g));
    if (dir.norm() < 1e-3) continue;
    const Vec3d xs = dir / std::sqrt(level(q.b.e, dir));  // on the surface
    const Vec3d nrm = xs.cwiseQuotient(q.b.e.cwiseProduct(q.b.e)).normalized();
    q.r = s(g);
    q.c = q.b.p + q.b.R * (xs + nrm * (q.r * (1 + f(g))));
    qs.push_back(rounded(q));
  }
  return qs;
}

/// Needle and pancake ellipsoids (ratio 1e-3 or 1e-4, axes permuted) with centres near
/// their thin parts: inside, above the flat side, at the rim or tip, on the plane.
std::vector<Query> thin_queries(std::mt19937& g, int n) {
  std::uniform_real_distribution<double> u(-1, 1), u01(0, 1), rr(0.001, 1.0);
  std::vector<Query> qs;
  for (int k = 0; k < n; ++k) {
    const double ratio = (k % 2) ? 1e-3 : 1e-4;
    const bool needle = (k / 2) % 2;
    Vec3d e = needle ? Vec3d(1, ratio, ratio * (0.5 + u01(g))) : Vec3d(1, 0.5 + 0.5 * u01(g), ratio);
    // permute axes
    const int sh = k % 3;
    e = Vec3d(e[sh], e[(sh + 1) % 3], e[(sh + 2) % 3]);
    Query q;
    q.b = random_ellipsoid(g, Vec3d(u(g), u(g), u(g)), e);
    Vec3d y;
    switch ((k / 4) % 5) {
      case 0:  // inside, anywhere
        y = Vec3d(u(g), u(g), u(g)).cwiseProduct(e) * 0.6;
        break;
      case 1:  // near the surface (in or out by up to 2 thin radii)
        y = Vec3d(u(g), u(g), u(g));
        y = y / std::sqrt(level(e, y));
        y += Vec3d(u(g), u(g), u(g)) * (2 * ratio);
        break;
      case 2:  // near the rim / tip along the long axis
        y = Vec3d(u(g), u(g), u(g)).cwiseProduct(e) * 0.1;
        y[e[0] >= e[1] && e[0] >= e[2] ? 0 : (e[1] >= e[2] ? 1 : 2)] =
            (0.99 + 0.02 * u01(g)) * (u(g) < 0 ? -1 : 1);
        break;
      case 3:  // on the thin axis's plane, inside
        y = Vec3d(u(g), u(g), u(g)).cwiseProduct(e) * 0.7;
        y[e[0] <= e[1] && e[0] <= e[2] ? 0 : (e[1] <= e[2] ? 1 : 2)] = 0;
        break;
      default:  // outside, further away
        y = Vec3d(u(g), u(g), u(g)) * 1.5;
        break;
    }
    q.r = rr(g);
    q.c = q.b.p + q.b.R * y;
    qs.push_back(rounded(q));
  }
  return qs;
}

/// Centres with local components exactly 0 (one or two axes) or within 1e-7 .. 1e-20 of
/// the principal planes, inside and outside.
std::vector<Query> plane_queries(std::mt19937& g, int n) {
  std::uniform_real_distribution<double> u(-1, 1), s(0.2, 1.0), ex(-20, -7), rr(0.05, 1.0);
  std::vector<Query> qs;
  for (int k = 0; k < n; ++k) {
    Query q;
    // A pose with R = I (exactly) keeps the local zeros exact through the float rotation.
    const bool aligned = k % 2 == 0;
    q.b = aligned ? Ell{Vec3d(u(g), u(g), u(g)), Mat3d::Identity(), Vec3d(s(g), s(g), s(g))}
                  : random_ellipsoid(g, Vec3d(u(g), u(g), u(g)), Vec3d(s(g), s(g), s(g)));
    Vec3d y = Vec3d(u(g), u(g), u(g)).cwiseProduct(q.b.e) * ((k / 2) % 3 == 0 ? 1.6 : 0.9);
    const int i = k % 3, j = (k + 1) % 3;
    const int mode = (k / 6) % 3;
    if (mode == 0) y[i] = 0;
    if (mode == 1) y[i] = 0, y[j] = 0;
    if (mode == 2) {
      y[i] = std::pow(10.0, ex(g)) * q.b.e[i], y[j] *= std::pow(10.0, ex(g));
      if (aligned) q.b.p = Vec3d::Zero();  // so that the tiny components survive as floats
    }
    q.r = rr(g);
    q.c = q.b.p + q.b.R * y;
    qs.push_back(rounded(q));
  }
  return qs;
}

// ---------------------------------------------------------------------------------------
// Tests
// ---------------------------------------------------------------------------------------

TEST(SphereEllipsoidReference, MatchesBruteForceAndLagrange) {
  std::mt19937 g(5);
  std::uniform_real_distribution<double> u(-1, 1), s(0.3, 1.0);
  int inside = 0;
  const int n = static_cast<int>(test::scaled(150));
  for (int k = 0; k < n; ++k) {
    const Vec3d e(s(g), s(g), s(g));
    Vec3d y = Vec3d(u(g), u(g), u(g)) * 1.5;
    if (k % 2) y = y.cwiseProduct(e);  // inside more often
    if (k % 5 == 0) y[k % 3] = 0;      // on a principal plane (the special cases)
    const Vec3d x = closest_local(e, y);
    EXPECT_NEAR(level(e, x), 1.0, 1e-12) << k;
    const Vec3d grad = x.cwiseQuotient(e.cwiseProduct(e));
    const double dist = (y - x).norm();
    if (dist > 1e-9) {
      EXPECT_LT((y - x).normalized().cross(grad.normalized()).norm(), 1e-9) << k;
    }
    EXPECT_NEAR(dist, brute_distance(e, y), 1e-9) << k << " y " << y.transpose() << " e " << e.transpose();
    inside += level(e, y) < 1;
  }
  EXPECT_GT(inside, n / 10);
}

class SphereEllipsoid : public ::testing::TestWithParam<std::tuple<double, double>> {};

TEST_P(SphereEllipsoid, RandomPosesAgainstDoubleReference) {
  const auto [size, offset] = GetParam();
  std::mt19937 g(17);
  const int n = static_cast<int>(test::scaled(600));
  Stats st;
  check_all(random_queries(g, n, size, offset), "random", &st);
  EXPECT_GT(st.hits, n / 5);
  EXPECT_GT(st.inside, n / 20);
  EXPECT_GT(st.normal_checked, st.hits * 9 / 10);
}

INSTANTIATE_TEST_SUITE_P(Scales, SphereEllipsoid, ::testing::ValuesIn(test::kernel_scales()));

TEST(SphereEllipsoidCases, TouchingNeedlePancakeAndPlanes) {
  std::mt19937 g(29);
  Stats st;
  check_all(touching_queries(g, static_cast<int>(test::scaled(300))), "touching", &st);
  EXPECT_GT(st.hits, 50);
  const int n_thin = static_cast<int>(test::scaled(800));
  check_all(thin_queries(g, n_thin), "needle / pancake", &st);
  EXPECT_GT(st.inside, n_thin / 5);
  check_all(plane_queries(g, static_cast<int>(test::scaled(600))), "principal planes / axes", &st);
  EXPECT_GT(st.inside, 50);
}

TEST(SphereEllipsoidCases, CentreAtTheCentreTakesTheSmallestAxis) {
  struct C {
    Vec3d e;
    int axis;  // expected: the lowest index among the smallest radii
  };
  const C cases[] = {{{3, 2, 1}, 2}, {{1, 2, 3}, 0}, {{2, 1, 3}, 1},     {{2, 1, 1}, 1},
                     {{1, 2, 1}, 0}, {{1, 1, 1}, 0}, {{0.5, 1, 0.5}, 0}, {{1, 1e-4, 1e-4}, 1}};
  std::mt19937 g(3);
  for (const C& c : cases) {
    for (bool rotated : {false, true}) {
      Query q;
      q.b = Ell{Vec3d(1e5, -2, 3), rotated ? test::random_rotation(g) : Mat3d::Identity(), c.e};
      q.c = q.b.p;
      q.r = 0.25;
      q = rounded(q);
      for (KernelPath path : {KernelPath::kSimd, KernelPath::kScalar}) {
        const test::PairResult h = run({q}, path)[0];
        ASSERT_EQ(h.count, 1u);
        EXPECT_NEAR(h.depth, q.r + q.b.e[c.axis], 1e-6) << c.e.transpose();
        const Vec3d want = -q.b.R.col(c.axis);
        EXPECT_LT((h.n - want).norm(), 1e-6) << c.e.transpose() << " n " << h.n.transpose();
        EXPECT_TRUE(h.pt[0].allFinite());
        // midway between c + n r and the surface point c - n e_axis
        EXPECT_LT((h.pt[0] - (q.c + h.n * (0.5 * (q.r - q.b.e[c.axis])))).norm(), 0.02);
      }
    }
  }
}

TEST(SphereEllipsoidCases, AnalyticAxesRoundAndTouching) {
  const Ell b{Vec3d(3, -2, 1), Mat3d::Identity(), Vec3d(2, 1, 0.5)};
  for (KernelPath path : {KernelPath::kSimd, KernelPath::kScalar}) {
    auto one = [&](const Vec3d& c, double r) { return run({Query{c, r, b}}, path)[0]; };
    // beyond the x tip, 0.25 deep: n = -x
    test::PairResult h = one(b.p + Vec3d(2.75, 0, 0), 1.0);
    ASSERT_EQ(h.count, 1u);
    EXPECT_NEAR(h.depth, 0.25, 1e-6);
    EXPECT_LT((h.n - Vec3d(-1, 0, 0)).norm(), 1e-6);
    EXPECT_LT((h.pt[0] - (b.p + Vec3d(1.875, 0, 0))).norm(), 1e-6);
    // above the z pole, 0.1 deep: n = -z
    h = one(b.p + Vec3d(0, 0, 0.9), 0.5);
    ASSERT_EQ(h.count, 1u);
    EXPECT_NEAR(h.depth, 0.1, 1e-6);
    EXPECT_LT((h.n - Vec3d(0, 0, -1)).norm(), 1e-6);
    // inside on the x axis near the tip: out through the tip (the tip's radii of
    // curvature 1/8 and 1/2 exceed the distance 0.1), depth r + 0.1, n = minus the
    // outward normal (B moves along -x to uncover the sphere)
    h = one(b.p + Vec3d(1.9, 0, 0), 0.3);
    ASSERT_EQ(h.count, 1u);
    EXPECT_NEAR(h.depth, 0.4, 1e-6);
    EXPECT_LT((h.n - Vec3d(-1, 0, 0)).norm(), 1e-6);
    // inside near the z pole: out through it, n = -z
    h = one(b.p + Vec3d(0, 0, 0.45), 0.2);
    ASSERT_EQ(h.count, 1u);
    EXPECT_NEAR(h.depth, 0.25, 1e-6);
    EXPECT_LT((h.n - Vec3d(0, 0, -1)).norm(), 1e-6);
    // inside on the x axis at 1.0: the nearest point is off the axis (Eberly's case,
    // 1 < (e_x^2 - e_z^2) / e_x): x = e_x^2 * 1 / (e_x^2 - e_z^2) = 16/15, z from the
    // surface equation
    h = one(b.p + Vec3d(1.0, 0, 0), 0.5);
    ASSERT_EQ(h.count, 1u);
    {
      const double x = 16.0 / 15.0, z = 0.5 * std::sqrt(1 - (x / 2) * (x / 2));
      const double dist = std::hypot(x - 1.0, z);
      EXPECT_NEAR(h.depth, 0.5 + dist, 1e-6);
      EXPECT_LT((h.n - Vec3d(x / 4, 0, z / 0.25).normalized() * -1.0).norm(), 1e-5);
    }
    // exactly touching the x tip and separated: no contact
    EXPECT_EQ(one(b.p + Vec3d(3.0, 0, 0), 1.0).count, 0u);
    EXPECT_EQ(one(b.p + Vec3d(0, 0, 1.5), 1.0).count, 0u);
    EXPECT_EQ(one(b.p + Vec3d(5, 5, 5), 1.0).count, 0u);
  }
  // A round ellipsoid is a sphere: the same answer as sphere-sphere.
  std::mt19937 g(11);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int k = 0; k < 50; ++k) {
    Query q{Vec3d(u(g), u(g), u(g)), 0.3 + 0.2 * u(g),
            Ell{Vec3d(u(g), u(g), u(g)), test::random_rotation(g), Vec3d::Constant(0.6)}};
    q = rounded(q);
    const double dist = (q.b.p - q.c).norm();
    const test::PairResult h = run({q}, KernelPath::kSimd)[0];
    if (std::fabs(q.r + 0.6 - dist) < 1e-5) continue;
    ASSERT_EQ(h.count > 0, q.r + 0.6 > dist);
    if (h.count == 0) continue;
    EXPECT_NEAR(h.depth, q.r + 0.6 - dist, 2e-6);
    if (dist > 1e-3) {
      EXPECT_LT((h.n - (q.b.p - q.c) / dist).norm(), 1e-5);
    }
  }
}

}  // namespace
}  // namespace impact::kernels
