// collide_capsule_ellipsoid (kernels/narrowphase/pairs/capsule/capsule_ellipsoid.cpp) on both paths
// against independent double-precision references.
//
// References (double, no candidate enumeration, no secular-equation solve by steps):
//  - core outside the ellipsoid: the signed distance of a point to the ellipsoid
//    (tests/support/ellipsoid_reference.h: bisection of the secular equation) is convex
//    along the core, so its minimum over the core by golden-section search gives the
//    distance d and the closest points: depth = r - d, n from the core point to the
//    ellipsoid's nearest point;
//  - core meeting the ellipsoid: the support overlap h_A(n) + h_B(-n) minimised over
//    densely sampled directions and refined by Nelder-Mead
//    (tests/support/narrow_reference.h, with more samples and starts than its default).
// The two are checked against each other on separated lanes (ReferencesAgree).
//
// Per lane, L = max(largest radius, r + half length), tol = kRel * L:
//  (a) count > 0 iff the reference depth > 0 (either where |depth_ref| <= tol);
//  (b) |depth - depth_ref| <= tol;
//  (c) n finite and unit; as good a separating direction as the reference's (the
//      reference overlap along n <= depth_ref + tol); angle(n, n_ref) <= kAngleTol where
//      the minimum is well conditioned (below);
//  (d) point[0] -+ n depth/2 lie on the ellipsoid and on the capsule (within tol plus
//      an ulp of the largest world coordinate; on the capsule plus 1e-6 of the
//      ellipsoid's largest radius of curvature: its support point slides by that much
//      under the normal's rounding), pdepth[0] == depth;
//  (e) the scalar and SIMD paths agree within tol (depth) and kAngleTol (normal).
// Well conditioned: outside, the reference normal turns by < 1e-2 rad when B moves by
// 1e-5 L, and no core point within 2e-7 L (float noise) of the least distance has a
// normal more than kAngleTol / 2 away (a short core across the normal: its ends score
// alike); inside, every direction 0.02 rad or more from n_ref overlaps by more than
// depth_ref + tol and the overlap rises by >= 1e-6 L at 3e-3 rad from n_ref in every
// direction (64 samples of the ring, the lowest refined: a needle's flat valley is
// narrow); there the normal's bound grows to the angle at which the overlap rises by
// kValleyNoise L where that is larger than kAngleTol (at IMPACT_TEST_INTENSITY=30 a
// lane 1e5 from the origin was 1.9e-4 rad off, its depth exact).
// Scenarios: random poses (outside, touching, through, deep) at sizes 1, 1e-4, 1e4 and
// 1e5 from the origin; constructed touching (side and end on a surface point's normal:
// exact depth and normal; count 0 at exactly touching within tol); pancakes and needles
// (ratios 1e-3, 1e-4) pierced by the core or lying across them; the core through the
// ellipsoid's centre (coincident centres: finite unit normal); analytic cases (a
// pancake pierced along its normal, axis-aligned sides and ends); a round ellipsoid
// against sphere-capsule; a zero-length core against sphere-ellipsoid; the core's two
// directions (u, -u: same answer).
// Registration, range partitions, shuffled buckets and the agreement with GJK / EPA:
// contract_test.cpp (every bucket of the table).
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <numeric>
#include <random>
#include <vector>

#include "kernels/narrowphase/pair_kernels.h"
#include "support/ellipsoid_input.h"
#include "support/ellipsoid_reference.h"
#include "support/kernel_checks.h"
#include "support/lane_checks.h"
#include "support/leaf_lanes.h"
#include "support/narrow_reference.h"
#include "support/random_input.h"
#include "support/same_answers.h"
#include "support/shape_geometry.h"
#include "support/test_support.h"

namespace impact::kernels {
namespace {

using Vec3d = Eigen::Vector3d;
using Mat3d = Eigen::Matrix3d;
namespace nref = test::nref;
using test::angle;

constexpr double kRel = 1e-5;       // depth tolerance, of L
constexpr double kAngleTol = 1e-4;  // rad, where the minimum is well conditioned
constexpr double kValleyNoise = 4e-7;  // of L: twice the worst depth error measured

struct Cap {
  Vec3d p;
  Vec3d u;  // unit axis (as rounded to float: not exactly unit)
  double r, h;
};

using Ell = test::PosedSolid;

struct Query {
  Cap a;
  Ell b;
};

Query rounded(Query q) {
  q.a.p = test::round_to_float(q.a.p);
  q.a.u = test::round_to_float(q.a.u);
  q.a.r = test::round_to_float(q.a.r);
  q.a.h = test::round_to_float(q.a.h);
  q.b = test::rounded(q.b);
  return q;
}

double size_of(const Query& q) {
  return std::max(q.b.e.maxCoeff(), q.a.r + q.a.h);
}

/// The capsule (R's column 2 exactly the rounded axis the references use) and the ellipsoid.
std::pair<test::Leaf, test::Leaf> leaves(const Query& q) {
  return {test::axial_leaf(kLeafCapsule, q.a.p, q.a.u, q.a.r, q.a.h),
          test::posed_leaf(kLeafEllipsoid, q.b.p, q.b.R, q.b.e)};
}

std::vector<test::PairResult> run(const std::vector<Query>& qs, KernelPath path) {
  return test::run_table_kernel(kLeafCapsule, kLeafEllipsoid, &collide_capsule_ellipsoid, qs, path, leaves);
}

// ---------------------------------------------------------------------------------------
// References
// ---------------------------------------------------------------------------------------

/// Golden-section minimum of the (convex) signed distance along the core: parameter t.
double core_minimum(const Query& q, double* sd_out) {
  const double g = 0.5 * (std::sqrt(5.0) - 1.0);
  double lo = -q.a.h, hi = q.a.h;
  auto f = [&](double t) { return test::eref::signed_distance_posed(q.b, q.a.p + t * q.a.u); };
  double x1 = hi - g * (hi - lo), x2 = lo + g * (hi - lo), f1 = f(x1), f2 = f(x2);
  for (int it = 0; it < 200 && hi - lo > 1e-15 * (1 + q.a.h); ++it) {
    if (f1 < f2) {
      hi = x2, x2 = x1, f2 = f1, x1 = hi - g * (hi - lo), f1 = f(x1);
    } else {
      lo = x1, x1 = x2, f1 = f2, x2 = lo + g * (hi - lo), f2 = f(x2);
    }
  }
  double t = 0.5 * (lo + hi), best = f(t);
  for (double c : {-q.a.h, q.a.h})
    if (f(c) < best) best = f(c), t = c;
  *sd_out = best;
  return t;
}

nref::Shape capsule_shape(const Query& q) {
  nref::Shape s = nref::make_axial(kLeafCapsule, {q.a.p.x(), q.a.p.y(), q.a.p.z()},
                                   {q.a.u.x(), q.a.u.y(), q.a.u.z()}, q.a.r, q.a.h * q.a.u.norm());
  return s;
}

nref::Shape ellipsoid_shape(const Ell& b) {
  return test::posed_shape(kLeafEllipsoid, b.p, b.R, b.e);
}

struct Ref {
  double s;      // depth (> 0 overlapping)
  Vec3d n;       // A to B
  bool through;  // the core meets the ellipsoid (support-overlap reference)
  bool conditioned;
  // Where conditioned: the angle a normal may be off, kAngleTol or, through, in a flat
  // valley, the angle at which the overlap rises by kValleyNoise L (the valley taken as
  // quadratic from its rise at 3e-3 rad): a float kernel's overlap is only that exact.
  double angle_tol = kAngleTol;
};

/// The overlap of the two shapes along n (A to B), the reference's function.
double overlap(const Query& q, const Vec3d& n) {
  return nref::overlap(capsule_shape(q), ellipsoid_shape(q.b), test::v3(n.normalized()));
}

/// n = minus the outward normal at the ellipsoid's point nearest the core (not the
/// difference of the two points: at small distances that would amplify the ~6e-8 by
/// which the float-rounded R is not orthonormal).
Ref outside_reference(const Query& q, double sd, double t) {
  const Vec3d c = q.a.p + t * q.a.u;
  const Vec3d x = test::eref::closest_local(q.b.e, q.b.R.transpose() * (c - q.b.p));
  Ref f;
  f.s = q.a.r - sd;
  f.n = -(q.b.R * x.cwiseQuotient(q.b.e.cwiseProduct(q.b.e))).normalized();
  f.through = false;
  return f;
}

Ref reference(const Query& q, bool check_conditioning = true) {
  double sd = 0;
  const double t = core_minimum(q, &sd);
  const double L = size_of(q);
  if (sd > 0) {
    Ref f = outside_reference(q, sd, t);
    f.conditioned = true;
    if (check_conditioning) {
      // Core points within float noise (2e-7 L) of the least distance whose nearest
      // points turn the normal by more than kAngleTol / 2: the minimum is a near tie
      // (a short core across the normal: its two ends score alike), the normal rounding.
      for (int i = 0; i <= 64 && f.conditioned; ++i) {
        const double ti = q.a.h * (2.0 * i / 64 - 1);
        const double sdi = test::eref::signed_distance_posed(q.b, q.a.p + ti * q.a.u);
        if (sdi <= sd + 2e-7 * L && angle(outside_reference(q, sdi, ti).n, f.n) > 0.5 * kAngleTol)
          f.conditioned = false;
      }
      for (int i = 0; i < 6; ++i) {
        Query p = q;
        p.b.p[i % 3] += (i < 3 ? 1e-5 : -1e-5) * L;
        double sd2 = 0;
        const double t2 = core_minimum(p, &sd2);
        if (!(sd2 > 0) || angle(outside_reference(p, sd2, t2).n, f.n) > 1e-2) f.conditioned = false;
      }
    }
    return f;
  }
  const nref::Shape a = capsule_shape(q), b = ellipsoid_shape(q.b);
  const nref::PairResult r = nref::solve_pair(a, b, {}, nref::dense_options());
  Ref f;
  f.s = r.s;
  f.n = test::ev(r.n);
  f.through = true;
  f.conditioned = r.unique(kRel * L);
  if (f.conditioned) {
    const double rise = nref::ring_rise(a, b, r.n);
    f.conditioned = rise >= 1e-6 * L;
    if (f.conditioned) f.angle_tol = nref::valley_angle(kAngleTol, rise, 3e-3, kValleyNoise * L);
  }
  return f;
}

// ---------------------------------------------------------------------------------------
// The per-lane check
// ---------------------------------------------------------------------------------------

double coord_ulp(const Query& q) {
  return test::coordinate_ulp(size_of(q), {q.a.p, q.b.p});
}

double sd_capsule(const Query& q, const Vec3d& x) {
  const double t = std::clamp((x - q.a.p).dot(q.a.u) / q.a.u.squaredNorm(), -q.a.h, q.a.h);
  return (x - (q.a.p + t * q.a.u)).norm() - q.a.r;
}

using Stats = test::LaneStats;

/// The pair for test::check_lanes: the references above and the distance of the moved pair
/// for the translation check.
void check_all(const std::vector<Query>& qs, const char* what, Stats* out_stats = nullptr) {
  // The points on both surfaces (+ for A the slide of B's support point under the
  // normal's rounding: 1e-6 of the largest radius of curvature e_max^2 / e_min; a
  // pancake's face: 1e4 L).
  static const test::PairModel<Query> model{
      .rel = kRel,
      .max_points = 1,
      .flag_name = "through",
      .reference =
          [](const Query& q) {
            const Ref f = reference(q);
            return test::LaneRef{f.s, f.n, f.conditioned, f.angle_tol, f.through};
          },
      .size = size_of,
      .coord_ulp = coord_ulp,
      .overlap = overlap,
      .sd_a = sd_capsule,
      .sd_b = [](const Query& q, const Vec3d& x) { return test::eref::signed_distance_posed(q.b, x); },
      .side_slack =
          [](const Query& q, const test::LaneRef&, const test::PairResult&, bool b_side) {
            return b_side ? 0.0 : 1e-6 * test::eref::largest_curvature_radius(q.b.e);
          },
      .same_bytes_paths = false,
      .point_ulps = 1};
  test::check_lanes_on_both_paths(model, qs, run, what, out_stats);
}

// ---------------------------------------------------------------------------------------
// Generators
// ---------------------------------------------------------------------------------------

/// Random poses around an ellipsoid of radii in [0.2, 1] * size at `offset` from the
/// origin: capsules from deep through it to well outside, about half touching.
std::vector<Query> random_queries(std::mt19937& g, int n, double size, double offset) {
  std::uniform_real_distribution<double> u(-1, 1), s(0.2, 1.0), rr(0.05, 0.8), hh(0.0, 1.0);
  return test::draw_cases(n, [&](int k) {
    Query q;
    const Vec3d p = Vec3d(offset, -offset, 0.5 * offset) + Vec3d(u(g), u(g), u(g)) * size;
    q.b = Ell{p, test::random_rotation(g), Vec3d(s(g), s(g), s(g)) * size};
    q.a.r = rr(g) * size;
    q.a.h = (k % 7 == 0 ? 0.0 : hh(g)) * size;
    q.a.u = test::random_unit_vector(g);
    const Vec3d v(u(g), u(g), u(g));
    q.a.p = p + (k % 2 ? Vec3d(q.b.R * v.cwiseProduct(q.b.e) * 1.2) : Vec3d(v * (1.6 * size)));
    return rounded(q);
  });
}

/// Capsules touching the ellipsoid at a random surface point x (outward normal m):
/// the core's nearest point at x + (r + f) m with the axis across m (side) or leaving
/// along a direction w with w.m >= 0 (end); depth = -f, n = -m exactly.
using Touch = test::Built<Query>;
std::vector<Touch> touching_queries(std::mt19937& g, int n) {
  std::uniform_real_distribution<double> u(-1, 1), s(0.2, 1.0), f(-1e-3, 1e-3), u01(0, 1);
  return test::draw_cases(n, [&](int k) {
    Query q;
    q.b = test::random_ellipsoid(g);
    const auto [x, m] = test::eref::surface_point(q.b, test::random_unit_vector(g));
    q.a.r = 0.05 + 0.5 * u01(g);
    q.a.h = 0.6 * u01(g);
    const double ff = (k % 5 == 0) ? 0.0 : f(g) * q.a.r;
    const Vec3d c = x + (q.a.r + ff) * m;  // the core point nearest the ellipsoid
    Vec3d w = test::random_unit_vector(g);
    if (k % 2 == 0) {
      w = (w - w.dot(m) * m).normalized();  // side: across m
      q.a.u = w;
      q.a.p = c + (2 * u01(g) - 1) * q.a.h * w;
    } else {
      if (w.dot(m) < 0) w = -w;  // end: leaving the surface
      q.a.u = w;
      q.a.p = c + q.a.h * w;
    }
    Touch t{rounded(q), -ff, -m};
    return t;
  });
}

/// Needle and pancake ellipsoids (ratio 1e-3 or 1e-4, axes permuted, rotated) with cores
/// through them (along, across, tilted), lying across a flat side, near a rim or tip.
std::vector<Query> thin_queries(std::mt19937& g, int n) {
  std::uniform_real_distribution<double> u(-1, 1), u01(0, 1);
  return test::draw_cases(n, [&](int k) {
    const Vec3d e = test::thin_radii(g, k);
    Query q;
    q.b = test::random_ellipsoid(g, e);
    const int thin = test::thinnest_axis(e);
    const int lng = e[0] >= e[1] && e[0] >= e[2] ? 0 : (e[1] >= e[2] ? 1 : 2);
    Vec3d y, ul;
    q.a.r = (k % 3 == 0 ? 0.01 : 0.3) * u01(g) + 1e-3;
    q.a.h = 0.05 + 0.8 * u01(g);
    switch ((k / 4) % 5) {
      case 0:  // through, tilted, centre inside
        y = Vec3d(u(g), u(g), u(g)).cwiseProduct(e) * 0.7;
        ul = test::random_unit_vector(g);
        break;
      case 1:  // along the thin axis (piercing a pancake), off centre
        y = Vec3d(u(g), u(g), u(g)).cwiseProduct(e) * 0.8;
        ul = Vec3d::Unit(thin) + 0.3 * Vec3d(u(g), u(g), u(g));
        break;
      case 2:  // near the rim / tip
        y = Vec3d(u(g), u(g), u(g)).cwiseProduct(e) * 0.1;
        y[lng] = (0.95 + 0.1 * u01(g)) * (u(g) < 0 ? -1 : 1);
        ul = test::random_unit_vector(g);
        break;
      case 3:  // lying across the flat side, just above or below it
        y = Vec3d(u(g), u(g), u(g)).cwiseProduct(e) * 0.6;
        y[thin] = e[thin] + q.a.r * (1 + 0.2 * u(g));
        ul = Vec3d(u(g), u(g), u(g));
        ul[thin] *= 1e-2;
        break;
      default:  // anywhere nearby
        y = Vec3d(u(g), u(g), u(g)) * 1.3;
        ul = test::random_unit_vector(g);
        break;
    }
    q.a.u = (q.b.R * ul).normalized();
    q.a.p = q.b.p + q.b.R * y;
    return rounded(q);
  });
}

/// Cores through (or ending at) the ellipsoid's centre, and capsule centre = ellipsoid
/// centre, at several proportions.
std::vector<Query> centre_queries(std::mt19937& g, int n) {
  std::uniform_real_distribution<double> u(-1, 1), s(0.2, 1.0), u01(0, 1);
  return test::draw_cases(n, [&](int k) {
    Query q;
    Vec3d e(s(g), s(g), s(g));
    if (k % 4 == 1) e = Vec3d(1, 1, 1) * s(g);  // round
    if (k % 4 == 2) e = Vec3d(s(g), 0.5, 0.5);  // two equal radii
    q.b = Ell{Vec3d(u(g), u(g), u(g)), k % 3 == 0 ? Mat3d::Identity() : test::random_rotation(g), e};
    q.a.r = 0.05 + 0.5 * u01(g);
    q.a.h = (k % 5 == 0) ? 0.0 : 1.5 * u01(g);
    q.a.u = (k % 3 == 0) ? Vec3d::Unit(k % 3) : test::random_unit_vector(g);
    q.a.p = q.b.p + ((k / 2) % 2 ? Vec3d::Zero() : Vec3d(q.a.u * q.a.h * u(g)));
    return rounded(q);
  });
}

// ---------------------------------------------------------------------------------------
// Tests
// ---------------------------------------------------------------------------------------

TEST(CapsuleEllipsoidReference, ReferencesAgree) {
  // Separated lanes: the golden-section distance and the support-overlap minimum.
  std::mt19937 g(3);
  int compared = 0;
  for (const Query& q : random_queries(g, static_cast<int>(test::scaled(60)), 1.0, 0.0)) {
    double sd = 0;
    const double t = core_minimum(q, &sd);
    if (!(sd > 1e-3)) continue;
    const Ref f = outside_reference(q, sd, t);
    const nref::PairResult r =
        nref::solve_pair(capsule_shape(q), ellipsoid_shape(q.b), {}, nref::dense_options());
    // (The float-rounded R is orthonormal to ~6e-8: the support function reads it as a
    // linear map, the point reference inverts it by its transpose.)
    EXPECT_NEAR(r.s, f.s, 2e-7) << compared;
    EXPECT_LT(angle(test::ev(r.n), f.n), 1e-5) << compared;
    ++compared;
  }
  EXPECT_GT(compared, 10);
}

class CapsuleEllipsoid : public ::testing::TestWithParam<std::tuple<double, double>> {};

TEST_P(CapsuleEllipsoid, RandomPosesAgainstDoubleReference) {
  test::random_pose_suite(GetParam(), 17, static_cast<int>(test::scaled(400)), random_queries, check_all,
                          {.flagged_div = 20, .normals_div = 2});
}

INSTANTIATE_TEST_SUITE_P(Scales, CapsuleEllipsoid, ::testing::ValuesIn(test::kernel_scales()));

TEST(CapsuleEllipsoidCases, ConstructedTouching) {
  std::mt19937 g(29);
  const std::vector<Touch> ts = touching_queries(g, static_cast<int>(test::scaled(400)));
  // (in a flat valley, the bound of check_all: an end nearly tangent to the surface has
  // the circle's candidate 3e-4 rad away within float noise of the minimum)
  const auto angle_tol = [&](size_t k, double L) {
    const double rise =
        nref::ring_rise(capsule_shape(ts[k].q), ellipsoid_shape(ts[k].q.b), test::v3(ts[k].n));
    return nref::valley_angle(kAngleTol, std::max(rise, 1e-6 * L), 3e-3, kValleyNoise * L);
  };
  test::expect_built_on_both_paths(ts, run, kRel, size_of, angle_tol, "touching");
}

TEST(CapsuleEllipsoidCases, NeedlesPancakesAndCentres) {
  std::mt19937 g(31);
  Stats st;
  const int n_thin = static_cast<int>(test::scaled(500));
  check_all(thin_queries(g, n_thin), "needle / pancake", &st);
  EXPECT_GT(st.flagged, n_thin / 5);
  check_all(centre_queries(g, static_cast<int>(test::scaled(200))), "through the centre", &st);
  EXPECT_GT(st.flagged, 50);
}

TEST(CapsuleEllipsoidCases, Analytic) {
  // Dyadic sizes and offsets: the float inputs are the exact configurations.
  for (KernelPath path : {KernelPath::kSimd, KernelPath::kScalar}) {
    auto one = [&](const Query& q) { return run({q}, path)[0]; };
    const Ell pancake{Vec3d(1, -2, 3), Mat3d::Identity(), Vec3d(2, 1.5, 0.125)};
    // Pierced along the normal, the capsule centre 0.0625 above the pancake's centre:
    // out through the top face (the end caps): depth = r + h + 0.125 - 0.0625, n = -z.
    test::PairResult h = one(Query{Cap{pancake.p + Vec3d(0, 0, 0.0625), Vec3d(0, 0, 1), 0.25, 0.5}, pancake});
    ASSERT_EQ(h.count, 1u);
    EXPECT_NEAR(h.depth, 0.25 + 0.5 + 0.125 - 0.0625, 1e-6);
    EXPECT_LT((h.n - Vec3d(0, 0, -1)).norm(), 1e-6) << h.n.transpose();
    // Lying on the top face, 1/64 deep, axis along x: n = -z.
    h = one(
        Query{Cap{pancake.p + Vec3d(0.25, 0, 0.125 + 0.25 - 0.015625), Vec3d(1, 0, 0), 0.25, 0.5}, pancake});
    ASSERT_EQ(h.count, 1u);
    EXPECT_NEAR(h.depth, 0.015625, 1e-6);
    EXPECT_LT((h.n - Vec3d(0, 0, -1)).norm(), 1e-5) << h.n.transpose();
    // End on the x tip, 1/16 deep, axis along x: n = -x.
    h = one(Query{Cap{pancake.p + Vec3d(2 + 0.25 + 0.5 - 0.0625, 0, 0), Vec3d(1, 0, 0), 0.25, 0.5}, pancake});
    ASSERT_EQ(h.count, 1u);
    EXPECT_NEAR(h.depth, 0.0625, 1e-6);
    EXPECT_LT((h.n - Vec3d(-1, 0, 0)).norm(), 1e-6) << h.n.transpose();
    // Side against the y rim (axis z, centre beyond the y tip), 1/32 deep: n = -y.
    h = one(Query{Cap{pancake.p + Vec3d(0, 1.5 + 0.25 - 0.03125, 0), Vec3d(0, 0, 1), 0.25, 0.5}, pancake});
    ASSERT_EQ(h.count, 1u);
    EXPECT_NEAR(h.depth, 0.03125, 1e-6);
    EXPECT_LT((h.n - Vec3d(0, -1, 0)).norm(), 1e-6) << h.n.transpose();
    // Centred along the smallest axis: the two ends tie (depth r + h + 0.125 either
    // way). The ends' nearest points (the poles next to them) are off their pieces: the
    // -z pole's normal makes the end at +h the core's lowest point. The tie goes to the
    // first candidate on its piece, the end at -h's far minimum, the +z pole: n = -z.
    h = one(Query{Cap{pancake.p, Vec3d(0, 0, 1), 0.25, 0.5}, pancake});
    ASSERT_EQ(h.count, 1u);
    EXPECT_NEAR(h.depth, 0.25 + 0.5 + 0.125, 1e-6);
    EXPECT_EQ(h.n, Vec3d(0, 0, -1));
    // Exactly touching (top face, y tip) and separated: no contact.
    EXPECT_EQ(one(Query{Cap{pancake.p + Vec3d(0, 0, 0.375), Vec3d(1, 0, 0), 0.25, 0.5}, pancake}).count, 0u);
    EXPECT_EQ(one(Query{Cap{pancake.p + Vec3d(0, 1.75, 0), Vec3d(0, 0, 1), 0.25, 0.5}, pancake}).count, 0u);
    EXPECT_EQ(one(Query{Cap{pancake.p + Vec3d(0, 0, 1.0), Vec3d(0, 1, 0), 0.25, 0.5}, pancake}).count, 0u);
  }
}

TEST(CapsuleEllipsoidCases, RoundEllipsoidIsSphereCapsule) {
  std::mt19937 g(11);
  std::uniform_real_distribution<double> u(-1, 1), u01(0, 1);
  const std::vector<Query> qs = test::draw_cases(200, [&](int) {
    Query q;
    q.b = test::random_round_ellipsoid(g);
    q.a = Cap{Vec3d(u(g), u(g), u(g)), test::random_unit_vector(g), 0.05 + 0.4 * u01(g), u01(g)};
    return rounded(q);
  });
  // sphere (A) - capsule (B): the same pairs with the roles swapped; sphere-capsule's
  // normal points from the sphere (our B) to the capsule (our A).
  const std::vector<test::PairResult> sphere =
      test::run_queries(&collide_sphere_capsule, qs, KernelPath::kSimd, [](const Query& q) {
        return std::pair{test::sphere_leaf(q.b.p, q.b.e[0]), leaves(q).first};
      });
  const int hits =
      test::expect_same_answers(run(qs, KernelPath::kSimd), sphere, {.same_count = true}, [&](size_t k) {
        return test::LaneRule{.normal = sphere[k].depth < 0.9 * (qs[k].a.r + qs[k].b.e[0]),
                              .point = true,
                              .map = -Mat3d::Identity()};
      });
  EXPECT_GT(hits, 40);
}

TEST(CapsuleEllipsoidCases, ZeroLengthCoreIsSphereEllipsoid) {
  std::mt19937 g(13);
  std::vector<Query> qs = random_queries(g, 200, 1.0, 0.0);
  for (Query& q : qs) q.a.h = 0;
  const std::vector<test::PairResult> sphere =
      test::run_queries(&collide_sphere_ellipsoid, qs, KernelPath::kSimd, [](const Query& q) {
        return std::pair{test::sphere_leaf(q.a.p, q.a.r), leaves(q).second};
      });
  const int hits = test::expect_same_answers(
      run(qs, KernelPath::kSimd), sphere, {.angle = 1e-4},
      [&](size_t k) { return test::LaneRule{.scale = size_of(qs[k]), .normal = true}; });
  EXPECT_GT(hits, 40);
}

TEST(CapsuleEllipsoidCases, AxisDirectionDoesNotMatter) {
  std::mt19937 g(19);
  std::vector<Query> qs = random_queries(g, 160, 1.0, 0.0);
  std::vector<Query> flipped = qs;
  for (Query& q : flipped) q.a.u = -q.a.u;
  test::expect_same_answers(run(qs, KernelPath::kSimd), run(flipped, KernelPath::kSimd),
                            {.depth = 1e-6, .angle = kAngleTol}, [&](size_t k) {
                              return test::LaneRule{.scale = size_of(qs[k]),
                                                    .normal = reference(qs[k]).conditioned};
                            });
}

}  // namespace
}  // namespace impact::kernels
