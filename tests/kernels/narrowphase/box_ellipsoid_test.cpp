// collide_box_ellipsoid (kernels/narrowphase/pairs/box/box_ellipsoid.cpp) on both paths against
// independent double-precision references, the sphere-box kernel where the ellipsoid is
// round.
//
// References (double, no piece enumeration, no secular-equation solve by steps):
//  - the support overlap h_A(n) + h_B(-n) minimised over densely sampled directions and
//    refined by Nelder-Mead (tests/support/narrow_reference.h, with more samples and
//    starts than its default): depth (> 0) or minus the distance, and the normal;
//  - for separated pairs, checked against it: the ellipsoid's signed distance
//    (tests/support/ellipsoid_reference.h: bisection of the secular equation) is convex,
//    so its minimum over the solid box by nested golden-section search is the distance
//    (ReferencesAgree).
// Per lane, L = max(largest radius, the box's half diagonal), tol = kRel * L:
//  (a) count > 0 iff the reference depth > 0 (either where |depth_ref| <= tol);
//  (b) |depth - depth_ref| <= tol;
//  (c) n finite and unit; as good a separating direction as the reference's (the
//      reference overlap along n <= depth_ref + tol); angle(n, n_ref) <= kAngleTol where
//      the minimum is well conditioned (below);
//  (d) point[0] - n depth/2 lies on the ellipsoid, point[0] + n depth/2 on the box's
//      surface where the minimum is well conditioned (within tol + ulp, plus 1e-6 of the
//      ellipsoid's largest radius of curvature: its support point slides by that much
//      under the normal's rounding), pdepth[0] == depth;
//  (e) the scalar and SIMD paths agree within tol (depth) and kAngleTol (normal).
// Well conditioned (overlapping pairs; separated ones have no contact): every direction
// 0.02 rad or more from n_ref overlaps by more than depth_ref + tol, and the overlap
// rises by >= 1e-6 L at 3e-3 rad from n_ref in every direction.
// Scenarios: random poses (outside, touching, through, deep) at sizes 1, 1e-4, 1e4 and
// 1e5 from the origin; constructed touching (a face, an edge and a vertex on a surface
// point's normal: exact depth and normal; count 0 at exactly touching within tol);
// needles and pancakes (ratios 1e-3, 1e-4) through boxes, lying on them, inside them,
// poking out at a vertex or an edge; flat, needle and point boxes (extents 1e-4 .. 0);
// large boxes against small ellipsoids; coincident centres; analytic cases (dyadic);
// a round ellipsoid against sphere-box; relabelled box axes (symmetry).
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
/// A few float ulps of the overlap at size L (4 x 2^-24): its evaluation's rounding.
constexpr double kRoundingSlack = 2.4e-7;

using Posed = test::PosedSolid;  // box: half extents; ellipsoid: radii
using test::rounded;

struct Query {
  Posed a;  // box
  Posed b;  // ellipsoid
};

Query rounded(Query q) {
  return Query{rounded(q.a), rounded(q.b)};
}

double size_of(const Query& q) {
  return std::max(q.b.e.maxCoeff(), q.a.e.norm());
}

/// A pair's two leaves as the kernel reads them.
std::pair<test::Leaf, test::Leaf> leaves(const Query& q) {
  return {test::posed_leaf(kLeafBox, q.a.p, q.a.R, q.a.e), test::posed_leaf(kLeafEllipsoid, q.b.p, q.b.R, q.b.e)};
}

std::vector<test::PairResult> run(const std::vector<Query>& qs, KernelPath path) {
  return test::run_table_kernel(kLeafBox, kLeafEllipsoid, &collide_box_ellipsoid, qs, path, leaves);
}

// ---------------------------------------------------------------------------------------
// References
// ---------------------------------------------------------------------------------------

double sd_box(const Posed& a, const Vec3d& x) {
  return test::box_sd(a.p, a.R, a.e, x);
}

/// The least signed distance to the ellipsoid over the solid box (convex: nested
/// golden-section search over the box's three coordinates).
double box_minimum(const Query& q, int iters) {
  const Posed& a = q.a;
  auto point = [&](double u, double v, double w) { return Vec3d(a.p + a.R * Vec3d(u, v, w)); };
  auto over_w = [&](double u, double v) {
    double w;
    return test::golden_section_min(
        [&](double ww) { return test::eref::signed_distance_posed(q.b, point(u, v, ww)); }, -a.e[2], a.e[2],
        iters, &w);
  };
  auto over_vw = [&](double u) {
    double v;
    return test::golden_section_min([&](double vv) { return over_w(u, vv); }, -a.e[1], a.e[1], iters, &v);
  };
  double u;
  return test::golden_section_min(over_vw, -a.e[0], a.e[0], iters, &u);
}

struct Ref {
  double s;  // depth (> 0 overlapping)
  Vec3d n;   // A to B
  bool conditioned;
};

double overlap(const Query& q, const Vec3d& n) {
  return nref::overlap(test::posed_shape(kLeafBox, q.a.p, q.a.R, q.a.e),
                       test::posed_shape(kLeafEllipsoid, q.b.p, q.b.R, q.b.e), test::v3(n.normalized()));
}

Ref reference(const Query& q) {
  const nref::Shape a = test::posed_shape(kLeafBox, q.a.p, q.a.R, q.a.e),
                    b = test::posed_shape(kLeafEllipsoid, q.b.p, q.b.R, q.b.e);
  const nref::PairResult r = nref::solve_pair(a, b, {}, nref::dense_options());
  const double L = size_of(q);
  Ref f;
  f.s = r.s;
  f.n = test::ev(r.n);
  f.conditioned = r.s > 0 && nref::well_conditioned(a, b, r, kRel * L, L);
  return f;
}

// ---------------------------------------------------------------------------------------
// The per-lane check
// ---------------------------------------------------------------------------------------

double coord_ulp(const Query& q) {
  return test::coordinate_ulp(size_of(q), {q.a.p, q.b.p});
}

using Stats = test::LaneStats;

/// The pair for test::check_lanes: the references above and the distance of the moved pair
/// for the translation check.
void check_all(const std::vector<Query>& qs, const char* what, Stats* out_stats = nullptr) {
  // The ellipsoid's point on its surface; the box's where conditioned, up to the slide
  // of the ellipsoid's support point under the normal's error (rho per rad, rho =
  // e_max^2 / e_min the largest radius of curvature; the error: the angle to the
  // reference's normal plus 1e-6).
  // A normal farther than kAngleTol is accepted only when it is as good a separating
  // direction as the reference's up to the overlap's float rounding (kRoundingSlack L),
  // and within 10 kAngleTol: the overlap then rises by less than its rounding over that
  // angle (seen: 3.1e-4 rad, 6.9e-8 L worse, 1 lane in ~1600 at intensity 10).
  static const test::PairModel<Query> model{
      .rel = kRel,
      .max_points = 1,
      .reference =
          [](const Query& q) {
            const Ref f = reference(q);
            return test::LaneRef{f.s, f.n, f.conditioned, kAngleTol, false};
          },
      .size = size_of,
      .coord_ulp = coord_ulp,
      .overlap = overlap,
      .sd_a = [](const Query& q, const Vec3d& x) { return sd_box(q.a, x); },
      .sd_b = [](const Query& q, const Vec3d& x) { return test::eref::signed_distance_posed(q.b, x); },
      .side_slack =
          [](const Query& q, const test::LaneRef& f, const test::PairResult& h, bool b_side) {
            if (b_side) return 0.0;
            return f.unique ? (angle(h.n, f.n) + 1e-6) * test::eref::largest_curvature_radius(q.b.e) : -1.0;
          },
      .normal_ok =
          [](const Query& q, const test::LaneRef& f, const test::PairResult& h, double ang) {
            const bool as_good = overlap(q, h.n) <= f.depth + kRoundingSlack * size_of(q);
            return ang <= kAngleTol || (as_good && ang <= 10 * kAngleTol);
          },
      .same_bytes_paths = false,
      .point_ulps = 1};
  test::check_lanes_on_both_paths(model, qs, run, what, out_stats);
}

// ---------------------------------------------------------------------------------------
// Generators
// ---------------------------------------------------------------------------------------

/// Random poses around a box of half extents in [0.2, 1] * size at `offset` from the
/// origin: ellipsoids from deep through it to well outside, about half touching.
std::vector<Query> random_queries(std::mt19937& g, int n, double size, double offset) {
  std::uniform_real_distribution<double> u(-1, 1), s(0.2, 1.0);
  return test::draw_cases(n, [&](int k) {
    Query q;
    const Vec3d p = Vec3d(offset, -offset, 0.5 * offset) + Vec3d(u(g), u(g), u(g)) * size;
    q.a = Posed{p, test::random_rotation(g), Vec3d(s(g), s(g), s(g)) * size};
    const Vec3d e = Vec3d(s(g), s(g), s(g)) * size;
    const Vec3d v(u(g), u(g), u(g));
    // Half near the box's surface (its corner region scaled by 1.1 plus the radii), half
    // anywhere within reach.
    const Vec3d c =
        k % 2
            ? Vec3d(p + q.a.R * v.cwiseProduct(q.a.e) * 1.1 + test::random_unit_vector(g) * (0.8 * e.mean()))
            : Vec3d(p + v * (1.6 * size));
    q.b = Posed{c, test::random_rotation(g), e};
    return rounded(q);
  });
}

/// Boxes touching the ellipsoid at a random surface point x (outward normal m) at
/// x + f m with -m in the piece's cone: a face (the box above the tangent plane), an
/// edge across m (its two faces tilted away), or a vertex (its three edges rising from
/// it): depth = -f, n = -m (box to ellipsoid).
using Touch = test::Built<Query>;
std::vector<Touch> touching_queries(std::mt19937& g, int n) {
  std::uniform_real_distribution<double> s(0.2, 1.0), w(0.15, 1.0);
  return test::draw_cases(n, [&](int k) {
    Query q;
    const auto [ell, x, m, c, ff] = test::random_surface_touch(g, k);  // c: the touching feature's point
    q.b = ell;
    const Vec3d h(s(g), s(g), s(g));
    // Box frame D (columns d_i) with the box in the corner c + sum t_i d_i, t_i in
    // [0, 2 h_i] (vertex), the edge along d_0 through c, or the face's centre at c.
    Vec3d ml;  // m in D's coordinates: all components >= 0 on the box's side
    switch (k % 3) {
      case 0:
        ml = Vec3d(0, 0, 1);
        break;
      case 1:
        ml = Vec3d(0, w(g), w(g)).normalized();
        break;
      default:
        ml = Vec3d(w(g), w(g), w(g)).normalized();
        break;
    }
    // D with D ml = m: a rotation taking ml to m, turned about m at random.
    const Mat3d A = test::frame_with_z(g, m), B = test::frame_with_z(g, ml);
    const Mat3d D = A * B.transpose();
    Vec3d centre_local = h;  // the corner at the origin of t
    if (k % 3 == 0) centre_local = Vec3d(0, 0, h[2]);
    if (k % 3 == 1) centre_local = Vec3d(0, h[1], h[2]);
    q.a = Posed{c + D * centre_local, D, h};
    return Touch{rounded(q), -ff, -m};
  });
}

/// Needle and pancake ellipsoids (ratio 1e-3 or 1e-4, axes permuted, rotated) against
/// boxes through them, lying on them, holding them, poking a vertex or an edge into a
/// pancake's face, and nearby.
std::vector<Query> thin_queries(std::mt19937& g, int n) {
  std::uniform_real_distribution<double> u(-1, 1), u01(0, 1), s(0.2, 1.0);
  return test::draw_cases(n, [&](int k) {
    const double ratio = (k % 2) ? 1e-3 : 1e-4;
    const Vec3d e = test::thin_radii(g, k);
    Query q;
    q.b = test::random_ellipsoid(g, e);
    const int thin = test::thinnest_axis(e);
    Posed box{Vec3d::Zero(), test::random_rotation(g), Vec3d(s(g), s(g), s(g)) * 0.5};
    switch ((k / 4) % 5) {
      case 0:  // through, near the centre
        box.p = Vec3d(u(g), u(g), u(g)).cwiseProduct(e) * 0.5;
        break;
      case 1: {  // a face lying across the thin axis just above / below
        box.R = Mat3d::Identity();
        box.R.col(2) = Vec3d::Unit(thin);
        box.R.col(0) = Vec3d::Unit((thin + 1) % 3);
        box.R.col(1) = box.R.col(2).cross(box.R.col(0));
        Vec3d c = Vec3d(u(g), u(g), u(g)).cwiseProduct(e) * 0.5;
        c[thin] = e[thin] * (1 + 0.5 * u(g)) + box.e[2];
        box.p = c;
        break;
      }
      case 2: {  // a vertex poking into the thin side from outside
        Vec3d c = Vec3d(u(g), u(g), u(g)).cwiseProduct(e) * 0.5;
        c[thin] = e[thin] * (1 - 0.5 * u01(g));
        // the vertex at c, the box on the outer side of the thin axis
        const Vec3d corner = box.R * box.e;
        box.p = c + corner * (c[thin] * corner[thin] > 0 ? 1.0 : -1.0);
        break;
      }
      case 3: {  // the whole ellipsoid inside a large box, or the box inside a pancake
        box.e = Vec3d(s(g), s(g), s(g)) * (k % 8 < 4 ? 1.5 : 0.5 * ratio);
        box.p = Vec3d(u(g), u(g), u(g)).cwiseProduct(e) * 0.3;
        break;
      }
      default:  // anywhere nearby
        box.p = Vec3d(u(g), u(g), u(g)) * 1.3;
        break;
    }
    box.p = q.b.p + q.b.R * box.p;
    box.R = q.b.R * box.R;
    q.a = box;
    return rounded(q);
  });
}

/// Degenerate and extreme boxes: flat (one extent 1e-4 .. 0), needles (two), points
/// (three), and large boxes (10 .. 1e4 times the ellipsoid) through, under and near it.
std::vector<Query> odd_box_queries(std::mt19937& g, int n) {
  std::uniform_real_distribution<double> u(-1, 1), s(0.2, 1.0), ex(1, 4), u01(0, 1);
  return test::draw_cases(n, [&](int k) {
    Query q;
    q.b = test::random_ellipsoid(g);
    Vec3d h(s(g), s(g), s(g));
    const double tiny = (k / 5) % 2 ? 0.0 : 1e-4 * u01(g);
    Vec3d c = q.b.p + Vec3d(u(g), u(g), u(g)) * 0.9;
    switch (k % 5) {
      case 0:
        h[k % 3] = tiny;
        break;
      case 1:
        h[k % 3] = tiny, h[(k + 1) % 3] = tiny;
        break;
      case 2:
        h = Vec3d::Constant(tiny);
        break;
      default: {  // large
        const double big = std::pow(10.0, ex(g));
        h = Vec3d(big, big * s(g), s(g));
        const Mat3d R = test::random_rotation(g);
        // its top face 1.2 * u from the ellipsoid's centre along R's z
        c = q.b.p - R.col(2) * (h[2] - 1.2 * u(g)) + (k % 2 ? Vec3d(R.col(0) * (0.9 * big)) : Vec3d::Zero());
        q.a = Posed{c, R, h};
        return rounded(q);
      }
    }
    q.a = Posed{c, test::random_rotation(g), h};
    return rounded(q);
  });
}

// ---------------------------------------------------------------------------------------
// Tests
// ---------------------------------------------------------------------------------------

TEST(BoxEllipsoidReference, ReferencesAgree) {
  std::mt19937 g(3);
  int compared = 0;
  for (const Query& q : random_queries(g, static_cast<int>(test::scaled(40)), 1.0, 0.0)) {
    const nref::PairResult r =
        nref::solve_pair(test::posed_shape(kLeafBox, q.a.p, q.a.R, q.a.e),
                         test::posed_shape(kLeafEllipsoid, q.b.p, q.b.R, q.b.e), {}, nref::dense_options());
    if (!(r.s < -1e-3)) continue;
    const double sd = box_minimum(q, 28);
    EXPECT_NEAR(r.s, -sd, 1e-6) << compared;
    ++compared;
  }
  EXPECT_GT(compared, 6);
}

class BoxEllipsoid : public ::testing::TestWithParam<std::tuple<double, double>> {};

TEST_P(BoxEllipsoid, RandomPosesAgainstDoubleReference) {
  test::random_pose_suite(GetParam(), 17, static_cast<int>(test::scaled(160)), random_queries, check_all,
                          {.normals_div = 3});
}

INSTANTIATE_TEST_SUITE_P(Scales, BoxEllipsoid, ::testing::ValuesIn(test::kernel_scales()));

TEST(BoxEllipsoidCases, ConstructedTouching) {
  std::mt19937 g(29);
  const std::vector<Touch> ts = touching_queries(g, static_cast<int>(test::scaled(300)));
  test::expect_built_on_both_paths(ts, run, kRel, size_of, test::every_pair_angle_tol(kAngleTol), "touching");
}

TEST(BoxEllipsoidCases, NeedlesPancakesOddBoxes) {
  std::mt19937 g(31);
  Stats st;
  const int n_thin = static_cast<int>(test::scaled(240));
  check_all(thin_queries(g, n_thin), "needle / pancake", &st);
  EXPECT_GT(st.hits, n_thin / 5);
  check_all(odd_box_queries(g, static_cast<int>(test::scaled(200))), "flat / point / large boxes", &st);
  EXPECT_GT(st.hits, 40);
}

TEST(BoxEllipsoidCases, CoincidentCentres) {
  // The ellipsoid's centre at the box's centre (and on a face, an edge, a vertex): finite
  // unit normal, exact depth.
  std::mt19937 g(37);
  std::uniform_real_distribution<double> u(-1, 1), s(0.2, 1.0);
  const std::vector<Query> qs = test::draw_cases(static_cast<int>(test::scaled(120)), [&](int k) {
    Query q;
    const Vec3d e = k % 4 == 1 ? Vec3d::Constant(s(g)) : Vec3d(s(g), s(g), s(g));
    const Vec3d h = k % 4 == 2 ? Vec3d::Constant(s(g)) : Vec3d(s(g), s(g), s(g));
    q.a = Posed{Vec3d(u(g), u(g), u(g)), k % 3 == 0 ? Mat3d::Identity() : test::random_rotation(g), h};
    Vec3d at = Vec3d::Zero();
    if (k % 5 == 1) at = Vec3d(h[0], 0, 0);
    if (k % 5 == 2) at = Vec3d(h[0], -h[1], 0);
    if (k % 5 == 3) at = Vec3d(-h[0], h[1], h[2]);
    q.b = Posed{q.a.p + q.a.R * at, k % 3 == 1 ? q.a.R : test::random_rotation(g), e};
    return rounded(q);
  });
  test::expect_all_meet(qs, check_all, "coincident centres");
}

TEST(BoxEllipsoidCases, Analytic) {
  // Dyadic sizes and offsets: the float inputs are the exact configurations.
  for (KernelPath path : {KernelPath::kSimd, KernelPath::kScalar}) {
    auto one = [&](const Query& q) { return run({q}, path)[0]; };
    const Posed box{Vec3d(1, -2, 3), Mat3d::Identity(), Vec3d(2, 1, 0.5)};
    const Vec3d p = box.p;
    // A pancake resting 1/16 deep on the top face (z = 0.5): n = +z, depth 1/16; the
    // point midway: 1/32 below the face, above the pancake's lower pole.
    test::PairResult h = one(Query{
        box, Posed{p + Vec3d(0.25, 0.5, 0.5 + 0.125 - 0.0625), Mat3d::Identity(), Vec3d(1, 0.75, 0.125)}});
    ASSERT_EQ(h.count, 1u);
    EXPECT_NEAR(h.depth, 0.0625, 1e-6);
    EXPECT_LT((h.n - Vec3d(0, 0, 1)).norm(), 1e-6) << h.n.transpose();
    EXPECT_LT((h.pt[0] - (p + Vec3d(0.25, 0.5, 0.5 - 0.03125))).norm(), 1e-6) << h.pt[0].transpose();
    // A sphere-like ellipsoid over the +x+y+z vertex along the diagonal, 1/8 inside:
    // n = the diagonal direction... use a sphere of radius 1 centred on the diagonal.
    {
      const Vec3d v = p + Vec3d(2, 1, 0.5);
      const Vec3d dgl = Vec3d(1, 1, 1).normalized();
      const Posed ball{v + dgl * 0.875, Mat3d::Identity(), Vec3d(1, 1, 1)};
      h = one(Query{box, rounded(ball)});
      ASSERT_EQ(h.count, 1u);
      EXPECT_NEAR(h.depth, 0.125, 2e-6);
      EXPECT_LT(angle(h.n, dgl), 1e-5) << h.n.transpose();
    }
    // A needle along y through the +x+z edge's middle (parallel to it), its axis 1/4
    // outside the box on the diagonal of the edge, radii 1/2: the needle's round side
    // touches the edge: depth 1/2 - 1/4 = 1/4, n along (1, 0, 1) / sqrt 2.
    {
      const Vec3d d = Vec3d(1, 0, 1).normalized();
      const Posed needle{p + Vec3d(2, 0, 0.5) + d * 0.25, Mat3d::Identity(), Vec3d(0.5, 4, 0.5)};
      h = one(Query{box, rounded(needle)});
      ASSERT_EQ(h.count, 1u);
      EXPECT_NEAR(h.depth, 0.25, 2e-6);
      EXPECT_LT(angle(h.n, d), 1e-5) << h.n.transpose();
    }
    // Exactly touching the top face, and separated: no contact.
    EXPECT_EQ(
        one(Query{box, Posed{p + Vec3d(0, 0, 0.5 + 0.125), Mat3d::Identity(), Vec3d(1, 0.75, 0.125)}}).count,
        0u);
    EXPECT_EQ(one(Query{box, Posed{p + Vec3d(3.5, 0, 0), Mat3d::Identity(), Vec3d(1, 0.75, 0.125)}}).count,
              0u);
    // Coincident centres, axis aligned: the least overlap is along z (h 0.5 + e 0.125).
    h = one(Query{box, Posed{p, Mat3d::Identity(), Vec3d(1, 0.75, 0.125)}});
    ASSERT_EQ(h.count, 1u);
    EXPECT_NEAR(h.depth, 0.625, 1e-6);
    EXPECT_NEAR(std::fabs(h.n.z()), 1.0, 1e-6);
  }
}

TEST(BoxEllipsoidCases, RoundEllipsoidIsSphereBox) {
  std::mt19937 g(11);
  std::uniform_real_distribution<double> u(-1, 1), u01(0, 1);
  const std::vector<Query> qs = test::draw_cases(200, [&](int) {
    Query q;
    q.a = Posed{Vec3d(u(g), u(g), u(g)), test::random_rotation(g),
                Vec3d(0.2 + 0.8 * u01(g), 0.2 + 0.8 * u01(g), 0.2 + 0.8 * u01(g))};
    const double r = 0.2 + 0.6 * u01(g);
    q.b = Posed{q.a.p + Vec3d(u(g), u(g), u(g)) * 1.5, test::random_rotation(g), Vec3d::Constant(r)};
    return rounded(q);
  });
  const std::vector<test::PairResult> sphere =
      test::run_queries(&collide_sphere_box, qs, KernelPath::kSimd, [](const Query& q) {
        return std::pair{test::sphere_leaf(q.b.p, q.b.e[0]), test::posed_leaf(kLeafBox, q.a.p, q.a.R, q.a.e)};
      });
  // sphere-box's normal (sphere to box) is minus ours; unique unless the centre is
  // inside the box on a medial plane.
  const int hits = test::expect_same_answers(run(qs, KernelPath::kSimd), sphere, {}, [&](size_t k) {
    const bool outside = sd_box(qs[k].a, qs[k].b.p) > 1e-3;
    return test::LaneRule{.normal = outside, .point = outside, .map = -Mat3d::Identity()};
  });
  EXPECT_GT(hits, 30);
}

TEST(BoxEllipsoidCases, RelabelledBoxAxes) {
  // The same box with its axes permuted (and one flipped to keep a rotation): the same
  // solid, so the same depth and, where unique, the same normal.
  std::mt19937 g(19);
  const std::vector<Query> qs = random_queries(g, 120, 1.0, 0.0);
  const std::vector<test::PairResult> h0 = run(qs, KernelPath::kSimd);
  std::vector<Query> other = qs;
  for (Query& q : other) {
    Mat3d R;
    R.col(0) = q.a.R.col(1), R.col(1) = q.a.R.col(2), R.col(2) = q.a.R.col(0);
    q.a.R = R;
    q.a.e = Vec3d(q.a.e[1], q.a.e[2], q.a.e[0]);
  }
  test::expect_same_answers(h0, run(other, KernelPath::kSimd), {.angle = kAngleTol}, [&](size_t k) {
    return test::LaneRule{.scale = size_of(qs[k]), .normal = reference(qs[k]).conditioned};
  });
}

}  // namespace
}  // namespace impact::kernels
