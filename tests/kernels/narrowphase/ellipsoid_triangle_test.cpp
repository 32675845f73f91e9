// collide_ellipsoid_triangle (kernels/narrowphase/pairs/ellipsoid/ellipsoid_triangle.cpp) on both paths
// against independent double-precision references.
//
// References (double, no candidate enumeration, no secular-equation solve by steps):
//  - triangle outside the ellipsoid: the signed distance of a point to the ellipsoid
//    (tests/support/ellipsoid_reference.h: bisection of the secular equation) is convex,
//    so its minimum over the triangle by nested golden-section search (over one
//    barycentric coordinate, the other inside) gives the distance d and the closest
//    points: depth = -d, n = the outward normal at the ellipsoid's nearest point;
//  - triangle meeting the ellipsoid: the support overlap h_A(n) + h_B(-n) minimised over
//    densely sampled directions and refined by Nelder-Mead
//    (tests/support/narrow_reference.h, with more samples and starts than its default).
// The two are checked against each other on separated lanes (ReferencesAgree).
//
// Per lane, L = max(largest radius, the triangle's bounding radius), tol = kRel * L:
//  (a) count > 0 iff the reference depth > 0 (either where |depth_ref| <= tol);
//  (b) |depth - depth_ref| <= tol;
//  (c) n finite and unit; as good a separating direction as the reference's (the
//      reference overlap along n <= depth_ref + tol); angle(n, n_ref) <= kAngleTol where
//      the minimum is well conditioned (below);
//  (d) point[0] + n depth/2 lies on the ellipsoid, point[0] - n depth/2 on the
//      triangle where the minimum is well conditioned (within tol + ulp, plus 1e-6 of
//      the ellipsoid's largest radius of curvature: its support point slides by that
//      much under the normal's rounding), pdepth[0] == depth;
//  (e) the scalar and SIMD paths agree within tol (depth) and kAngleTol (normal).
// Well conditioned (triangles that meet the ellipsoid; separated ones have no contact):
// every direction 0.02 rad or more from n_ref overlaps by more than depth_ref + tol and
// the overlap rises by >= 1e-6 L at 3e-3 rad from n_ref in every direction (64
// samples of the ring, the lowest refined: a needle's flat valley is narrow).
// Scenarios: random poses (outside, touching, through, deep) at sizes 1, 1e-4, 1e4 and
// 1e5 from the origin; large triangles against small ellipsoids (terrain); constructed
// touching (a face, an edge and a vertex on a surface point's normal: exact depth and
// normal; count 0 at exactly touching within tol); pancakes and needles (ratios 1e-3,
// 1e-4) pierced by the triangle, lying on it or inside it, a vertex outside while the
// triangle is deep inside; the ellipsoid's centre on the triangle; sliver, collinear
// and point triangles; small triangles grazing the surface (their vertices' candidates
// 1e-4 rad apart, scoring alike); analytic cases (a pancake on a flat triangle, tips
// and rims);
// a round ellipsoid against sphere-triangle; vertex order and orientation.
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

using Ell = test::PosedSolid;

struct Tri {
  Vec3d v[3];
};

struct Query {
  Ell a;
  Tri b;
};

Query rounded(Query q) {
  q.a = test::rounded(q.a);
  for (Vec3d& v : q.b.v) v = test::round_to_float(v);
  return q;
}

double tri_radius(const Tri& t) {
  const Vec3d c = (t.v[0] + t.v[1] + t.v[2]) / 3.0;
  return std::max({(t.v[0] - c).norm(), (t.v[1] - c).norm(), (t.v[2] - c).norm()});
}

double size_of(const Query& q) {
  return std::max(q.a.e.maxCoeff(), tri_radius(q.b));
}

std::pair<test::Leaf, test::Leaf> leaves(const Query& q) {
  return {test::posed_leaf(kLeafEllipsoid, q.a.p, q.a.R, q.a.e),
          test::triangle_leaf(q.b.v[0], q.b.v[1], q.b.v[2])};
}

std::vector<test::PairResult> run(const std::vector<Query>& qs, KernelPath path) {
  return test::run_table_kernel(kLeafEllipsoid, kLeafTriangle, &collide_ellipsoid_triangle, qs, path, leaves);
}

// ---------------------------------------------------------------------------------------
// References
// ---------------------------------------------------------------------------------------

/// The least signed distance to the ellipsoid over the triangle (convex: nested
/// golden-section search over the barycentric coordinates); y = where.
double triangle_minimum(const Query& q, Vec3d* where) {
  const Tri& t = q.b;
  auto point = [&](double u, double v) {
    return Vec3d(t.v[0] + u * (t.v[1] - t.v[0]) + v * (t.v[2] - t.v[0]));
  };
  auto inner = [&](double u, double* v_at) {
    return test::golden_section_min(
        [&](double v) { return test::eref::signed_distance_posed(q.a, point(u, v)); }, 0.0, 1.0 - u, 44,
        v_at);
  };
  double u = 0, v = 0;
  const double best = test::golden_section_min(
      [&](double uu) {
        double vv;
        return inner(uu, &vv);
      },
      0.0, 1.0, 44, &u);
  inner(u, &v);
  *where = point(u, v);
  return best;
}

nref::Shape ellipsoid_shape(const Ell& b) {
  return test::posed_shape(kLeafEllipsoid, b.p, b.R, b.e);
}

nref::Shape triangle_shape(const Tri& t) {
  return nref::make_triangle(test::v3(t.v[0]), test::v3(t.v[1]), test::v3(t.v[2]));
}

struct Ref {
  double s;  // depth (> 0 overlapping)
  Vec3d n;   // A to B
  bool through;
  bool conditioned;
};

double overlap(const Query& q, const Vec3d& n) {
  return nref::overlap(ellipsoid_shape(q.a), triangle_shape(q.b), test::v3(n.normalized()));
}

/// n = the outward normal at the ellipsoid's point nearest y (see capsule_ellipsoid_test:
/// not the difference of two nearby points).
Vec3d outward_normal_nearest(const Ell& a, const Vec3d& y) {
  const Vec3d x = test::eref::closest_local(a.e, a.R.transpose() * (y - a.p));
  return (a.R * x.cwiseQuotient(a.e.cwiseProduct(a.e))).normalized();
}

/// Separated lanes (min signed distance > 0) have no contact, so their normal is never
/// checked: only the distance is needed.
Ref reference(const Query& q) {
  Vec3d y;
  const double sd = triangle_minimum(q, &y);
  const double L = size_of(q);
  if (sd > 0) {
    Ref f;
    f.s = -sd;
    f.n = outward_normal_nearest(q.a, y);
    f.through = false;
    f.conditioned = false;
    return f;
  }
  const nref::Shape a = ellipsoid_shape(q.a), b = triangle_shape(q.b);
  const nref::PairResult r = nref::solve_pair(a, b, {}, nref::dense_options());
  Ref f;
  f.s = r.s;
  f.n = test::ev(r.n);
  f.through = true;
  f.conditioned = nref::well_conditioned(a, b, r, kRel * L, L);
  return f;
}

// ---------------------------------------------------------------------------------------
// The per-lane check
// ---------------------------------------------------------------------------------------

double coord_ulp(const Query& q) {
  return test::coordinate_ulp(size_of(q), {q.a.p, q.b.v[0], q.b.v[1], q.b.v[2]});
}

double triangle_distance(const Tri& t, const Vec3d& x) {
  return nref::triangle_distance(test::v3(x), test::v3(t.v[0]), test::v3(t.v[1]), test::v3(t.v[2]));
}

using Stats = test::LaneStats;

/// The pair for test::check_lanes: the references above and the distance of the moved pair
/// for the translation check.
void check_all(const std::vector<Query>& qs, const char* what, Stats* out_stats = nullptr) {
  // A's point on the ellipsoid; B's on the triangle where the minimiser is unique, up to
  // the slide of A's support point under the normal's rounding: rho * 1e-6 rad for the
  // largest radius of curvature rho = e_max^2 / e_min (a pancake's face: 1e4 L).
  static const test::PairModel<Query> model{
      .rel = kRel,
      .max_points = 1,
      .flag_name = "through",
      .reference =
          [](const Query& q) {
            const Ref f = reference(q);
            return test::LaneRef{f.s, f.n, f.conditioned, kAngleTol, f.through};
          },
      .size = size_of,
      .coord_ulp = coord_ulp,
      .overlap = overlap,
      .sd_a = [](const Query& q, const Vec3d& x) { return test::eref::signed_distance_posed(q.a, x); },
      .sd_b = [](const Query& q, const Vec3d& x) { return triangle_distance(q.b, x); },  // unsigned
      .side_slack =
          [](const Query& q, const test::LaneRef& f, const test::PairResult&, bool b_side) {
            if (!b_side) return 0.0;
            return f.unique ? 1e-6 * test::eref::largest_curvature_radius(q.a.e) : -1.0;
          },
      .same_bytes_paths = false,
      .point_ulps = 1};
  test::check_lanes_on_both_paths(model, qs, run, what, out_stats);
}

// ---------------------------------------------------------------------------------------
// Generators
// ---------------------------------------------------------------------------------------

/// A triangle with vertices around c within `reach` (not too thin).
Tri random_triangle(std::mt19937& g, const Vec3d& c, double reach) {
  std::uniform_real_distribution<double> u(-1, 1);
  for (;;) {
    Tri t{{c + Vec3d(u(g), u(g), u(g)) * reach, c + Vec3d(u(g), u(g), u(g)) * reach,
           c + Vec3d(u(g), u(g), u(g)) * reach}};
    if ((t.v[1] - t.v[0]).cross(t.v[2] - t.v[0]).norm() > 0.05 * reach * reach) return t;
  }
}

/// Random poses around an ellipsoid of radii in [0.2, 1] * size at `offset` from the
/// origin: triangles from deep through it to well outside, about half touching.
std::vector<Query> random_queries(std::mt19937& g, int n, double size, double offset) {
  std::uniform_real_distribution<double> u(-1, 1), s(0.2, 1.0), rr(0.2, 1.2);
  return test::draw_cases(n, [&](int k) {
    Query q;
    const Vec3d p = Vec3d(offset, -offset, 0.5 * offset) + Vec3d(u(g), u(g), u(g)) * size;
    q.a = Ell{p, test::random_rotation(g), Vec3d(s(g), s(g), s(g)) * size};
    const Vec3d v(u(g), u(g), u(g));
    const Vec3d c = p + (k % 2 ? Vec3d(q.a.R * v.cwiseProduct(q.a.e) * 1.1) : Vec3d(v * (1.1 * size)));
    q.b = random_triangle(g, c, rr(g) * size);
    return rounded(q);
  });
}

/// Large triangles (10..1e4 times the ellipsoid) through, under and near small ellipsoids.
std::vector<Query> terrain_queries(std::mt19937& g, int n) {
  std::uniform_real_distribution<double> u(-1, 1), s(0.2, 1.0), ex(1, 4);
  return test::draw_cases(n, [&](int k) {
    Query q;
    q.a = test::random_ellipsoid(g);
    const double big = std::pow(10.0, ex(g));
    const Vec3d nrm = test::random_unit_vector(g);
    const Vec3d t1 = nrm.unitOrthogonal(), t2 = nrm.cross(t1);
    const double h = 1.2 * u(g);  // plane offset from the ellipsoid's centre
    const Vec3d c = q.a.p + h * nrm + (k % 3 == 0 ? Vec3d(t1 * (big * 0.3)) : Vec3d::Zero());
    q.b = Tri{{c + big * t1, c - 0.5 * big * t1 + 0.87 * big * t2, c - 0.5 * big * t1 - 0.87 * big * t2}};
    return rounded(q);
  });
}

/// Triangles touching the ellipsoid at a random surface point x (outward normal m): a
/// face in the plane m.(y - x) = f containing x + f m, an edge across m through x + f m
/// (third vertex above), or a vertex at x + f m (the others above): depth = -f, n = m.
using Touch = test::Built<Query>;
std::vector<Touch> touching_queries(std::mt19937& g, int n) {
  std::uniform_real_distribution<double> u01(0, 1);
  return test::draw_cases(n, [&](int k) {
    Query q;
    const auto [ell, x, m, c, ff] = test::random_surface_touch(g, k);  // c: the touching feature's point
    q.a = ell;
    const Vec3d t1 = m.unitOrthogonal(), t2 = m.cross(t1);
    const double r = 0.2 + 0.8 * u01(g);
    const double a0 = 2 * M_PI * u01(g);
    auto tan_dir = [&](double a) { return Vec3d(std::cos(a) * t1 + std::sin(a) * t2); };
    switch (k % 3) {
      case 0:  // face: c inside the triangle
        q.b = Tri{{c + r * tan_dir(a0), c + r * tan_dir(a0 + 2.1), c + r * tan_dir(a0 + 4.2)}};
        break;
      case 1:  // edge through c across m, third vertex above
        q.b = Tri{{c + r * tan_dir(a0), c - 0.7 * r * tan_dir(a0),
                   c + r * (0.5 * u01(g) + 0.2) * m + r * tan_dir(a0 + 1.5)}};
        break;
      default:  // vertex at c, the others above
        q.b = Tri{{c, c + r * (tan_dir(a0) + (0.2 + u01(g)) * m),
                   c + r * (tan_dir(a0 + 2.0) + (0.2 + u01(g)) * m)}};
        break;
    }
    return Touch{rounded(q), -ff, m};
  });
}

/// Small triangles (1e-4 .. 1e-2 of the ellipsoid) grazing its surface at a random point:
/// their vertices' nearest points lie 1e-4 rad or less apart and score alike.
std::vector<Query> grazing_queries(std::mt19937& g, int n) {
  std::uniform_real_distribution<double> u(-1, 1), s(0.2, 1.0), ex(2, 4), u01(0, 1);
  return test::draw_cases(n, [&](int) {
    Query q;
    q.a = test::random_ellipsoid(g);
    const Vec3d dir = test::random_unit_vector(g);
    const Vec3d xs = dir / std::sqrt(test::eref::level(q.a.e, dir));
    const Vec3d m = q.a.R * xs.cwiseQuotient(q.a.e.cwiseProduct(q.a.e)).normalized();
    const double size = std::pow(10.0, -ex(g));
    const Vec3d c = q.a.p + q.a.R * xs + m * (size * u(g));
    q.b = random_triangle(g, c, size);
    return rounded(q);
  });
}

/// Needle and pancake ellipsoids (ratio 1e-3 or 1e-4, axes permuted, rotated) against
/// triangles through them, lying on them, inside a pancake, a vertex outside while the
/// triangle is deep inside, and nearby.
std::vector<Query> thin_queries(std::mt19937& g, int n) {
  std::uniform_real_distribution<double> u(-1, 1), u01(0, 1);
  return test::draw_cases(n, [&](int k) {
    const double ratio = (k % 2) ? 1e-3 : 1e-4;
    const Vec3d e = test::thin_radii(g, k);
    Query q;
    q.a = test::random_ellipsoid(g, e);
    const int thin = test::thinnest_axis(e);
    Tri t;
    switch ((k / 4) % 5) {
      case 0:  // through, random orientation, near the centre
        t = random_triangle(g, Vec3d(u(g), u(g), u(g)).cwiseProduct(e) * 0.5, 0.3 + 0.7 * u01(g));
        break;
      case 1: {  // lying across the thin axis just above / below (pancake face down)
        const double h = e[thin] * (1 + 0.5 * u(g));
        Vec3d c = Vec3d(u(g), u(g), u(g)).cwiseProduct(e) * 0.5;
        c[thin] = h;
        t = random_triangle(g, c, 0.2 + 0.5 * u01(g));
        for (Vec3d& v : t.v) v[thin] = h + 1e-2 * ratio * u(g);
        break;
      }
      case 2: {  // small triangle inside, one vertex poking out through the thin side
        Vec3d c = Vec3d(u(g), u(g), u(g)).cwiseProduct(e) * 0.3;
        t = Tri{{c, c + Vec3d(u(g), u(g), u(g)).cwiseProduct(e) * 0.2, c}};
        t.v[2][thin] += (u(g) < 0 ? -1 : 1) * e[thin] * (1.5 + u01(g));
        break;
      }
      case 3:  // needle / pancake piercing a small triangle, off centre
        t = random_triangle(g, Vec3d(u(g), u(g), u(g)).cwiseProduct(e) * 0.9, 0.05 + 0.1 * u01(g));
        break;
      default:  // anywhere nearby
        t = random_triangle(g, Vec3d(u(g), u(g), u(g)) * 1.3, 0.3 + 0.7 * u01(g));
        break;
    }
    for (Vec3d& v : t.v) v = q.a.p + q.a.R * v;
    q.b = t;
    return rounded(q);
  });
}

/// Degenerate triangles: slivers (height 1e-3 .. 1e-7 of the base), exactly collinear,
/// two equal vertices, a point; through and near ellipsoids.
std::vector<Query> degenerate_queries(std::mt19937& g, int n) {
  std::uniform_real_distribution<double> u(-1, 1), s(0.2, 1.0), ex(3, 7), u01(0, 1);
  return test::draw_cases(n, [&](int k) {
    Query q;
    q.a = test::random_ellipsoid(g);
    const Vec3d c = q.a.p + Vec3d(u(g), u(g), u(g)) * 0.7;
    const Vec3d d = test::random_unit_vector(g) * (0.3 + u01(g));
    switch (k % 4) {
      case 0: {  // sliver
        const Vec3d side =
            d.cross(test::random_unit_vector(g)).normalized() * (d.norm() * std::pow(10.0, -ex(g)));
        q.b = Tri{{c - d, c + d, c + 0.3 * d + side}};
        break;
      }
      case 1:  // collinear (the middle vertex exactly on the segment in double)
        q.b = Tri{{c - d, c + d, c + 0.25 * d}};
        break;
      case 2:  // two equal vertices
        q.b = Tri{{c - d, c + d, c + d}};
        break;
      default:  // a point
        q.b = Tri{{c, c, c}};
        break;
    }
    return rounded(q);
  });
}

// ---------------------------------------------------------------------------------------
// Tests
// ---------------------------------------------------------------------------------------

TEST(EllipsoidTriangleReference, ReferencesAgree) {
  std::mt19937 g(3);
  int compared = 0;
  for (const Query& q : random_queries(g, static_cast<int>(test::scaled(50)), 1.0, 0.0)) {
    Vec3d y;
    const double sd = triangle_minimum(q, &y);
    if (!(sd > 1e-3)) continue;
    const nref::PairResult r =
        nref::solve_pair(ellipsoid_shape(q.a), triangle_shape(q.b), {}, nref::dense_options());
    // (The float-rounded R is orthonormal to ~6e-8: see capsule_ellipsoid_test.)
    EXPECT_NEAR(r.s, -sd, 2e-7) << compared;
    EXPECT_LT(angle(test::ev(r.n), outward_normal_nearest(q.a, y)), 1e-5) << compared;
    ++compared;
  }
  EXPECT_GT(compared, 8);
}

class EllipsoidTriangle : public ::testing::TestWithParam<std::tuple<double, double>> {};

TEST_P(EllipsoidTriangle, RandomPosesAgainstDoubleReference) {
  test::random_pose_suite(GetParam(), 17, static_cast<int>(test::scaled(200)), random_queries, check_all,
                          {.flagged_div = 5, .normals_div = 2});
}

INSTANTIATE_TEST_SUITE_P(Scales, EllipsoidTriangle, ::testing::ValuesIn(test::kernel_scales()));

TEST(EllipsoidTriangleCases, ConstructedTouching) {
  std::mt19937 g(29);
  const std::vector<Touch> ts = touching_queries(g, static_cast<int>(test::scaled(300)));
  test::expect_built_on_both_paths(ts, run, kRel, size_of, test::every_pair_angle_tol(kAngleTol), "touching");
}

TEST(EllipsoidTriangleCases, TerrainNeedlesPancakesDegenerate) {
  std::mt19937 g(31);
  Stats st;
  check_all(terrain_queries(g, static_cast<int>(test::scaled(150))), "large triangles", &st);
  EXPECT_GT(st.hits, 30);
  const int n_thin = static_cast<int>(test::scaled(300));
  check_all(thin_queries(g, n_thin), "needle / pancake", &st);
  EXPECT_GT(st.flagged, n_thin / 5);
  check_all(degenerate_queries(g, static_cast<int>(test::scaled(200))), "degenerate triangles", &st);
  EXPECT_GT(st.hits, 30);
  check_all(grazing_queries(g, static_cast<int>(test::scaled(200))), "small grazing triangles", &st);
  EXPECT_GT(st.normals_checked, 50);
}

TEST(EllipsoidTriangleCases, CentreOnTheTriangle) {
  // The ellipsoid's centre on the triangle (inside it, on an edge, at a vertex): the
  // triangle cuts the ellipsoid through its centre; finite unit normal, exact depth.
  std::mt19937 g(37);
  std::uniform_real_distribution<double> u(-1, 1), s(0.2, 1.0), u01(0, 1);
  const std::vector<Query> qs = test::draw_cases(static_cast<int>(test::scaled(120)), [&](int k) {
    Query q;
    const Vec3d e = k % 4 == 1 ? Vec3d::Constant(s(g)) : Vec3d(s(g), s(g), s(g));
    q.a = Ell{Vec3d(u(g), u(g), u(g)), k % 3 == 0 ? Mat3d::Identity() : test::random_rotation(g), e};
    Tri t = random_triangle(g, Vec3d::Zero(), 0.5 + u01(g));
    const double b0 = u01(g), b1 = (1 - b0) * u01(g);
    Vec3d at = t.v[0] + b0 * (t.v[1] - t.v[0]) + b1 * (t.v[2] - t.v[0]);
    if (k % 5 == 1) at = 0.5 * (t.v[0] + t.v[1]);
    if (k % 5 == 2) at = t.v[2];
    for (Vec3d& v : t.v) v = v - at + q.a.p;
    q.b = t;
    return rounded(q);
  });
  test::expect_all_meet(qs, check_all, "centre on the triangle");
}

TEST(EllipsoidTriangleCases, Analytic) {
  // Dyadic sizes and offsets: the float inputs are the exact configurations.
  for (KernelPath path : {KernelPath::kSimd, KernelPath::kScalar}) {
    auto one = [&](const Query& q) { return run({q}, path)[0]; };
    const Ell pancake{Vec3d(1, -2, 3), Mat3d::Identity(), Vec3d(2, 1.5, 0.125)};
    const Vec3d p = pancake.p;
    // A flat triangle 1/16 below the top face (z = 0.125): n = +z, depth 1/16; the
    // point midway: 1/32 below the face, above the pancake's pole.
    test::PairResult h = one(
        Query{pancake, Tri{{p + Vec3d(-1, -1, 0.0625), p + Vec3d(1, -1, 0.0625), p + Vec3d(0, 1, 0.0625)}}});
    ASSERT_EQ(h.count, 1u);
    EXPECT_NEAR(h.depth, 0.0625, 1e-6);
    EXPECT_LT((h.n - Vec3d(0, 0, 1)).norm(), 1e-6) << h.n.transpose();
    EXPECT_LT((h.pt[0] - (p + Vec3d(0, 0, 0.09375))).norm(), 1e-6) << h.pt[0].transpose();
    // The same through the centre plane (z = 0): out through either face, depth 1/8;
    // the tie goes to the first candidate, +N (N = (v1 - v0) x (v2 - v0) = +z).
    h = one(Query{pancake, Tri{{p + Vec3d(-4, -4, 0), p + Vec3d(4, -4, 0), p + Vec3d(0, 4, 0)}}});
    ASSERT_EQ(h.count, 1u);
    EXPECT_NEAR(h.depth, 0.125, 1e-6);
    EXPECT_EQ(h.n, Vec3d(0, 0, 1));
    // A vertex 1/16 inside the top pole, the triangle leaving upwards: n = +z, 1/16.
    h = one(Query{pancake, Tri{{p + Vec3d(0, 0, 0.0625), p + Vec3d(1, 0, 1), p + Vec3d(-1, 0.5, 1)}}});
    ASSERT_EQ(h.count, 1u);
    EXPECT_NEAR(h.depth, 0.0625, 1e-6);
    EXPECT_LT((h.n - Vec3d(0, 0, 1)).norm(), 1e-6) << h.n.transpose();
    // An edge across the y rim, 1/8 inside, parallel to z: n = +y, depth 1/8.
    h = one(Query{pancake, Tri{{p + Vec3d(0, 1.375, -1), p + Vec3d(0, 1.375, 1), p + Vec3d(0, 3, 0)}}});
    ASSERT_EQ(h.count, 1u);
    EXPECT_NEAR(h.depth, 0.125, 1e-6);
    EXPECT_LT((h.n - Vec3d(0, 1, 0)).norm(), 1e-6) << h.n.transpose();
    // Exactly touching the top face and separated: no contact.
    EXPECT_EQ(
        one(Query{pancake, Tri{{p + Vec3d(-1, -1, 0.125), p + Vec3d(1, -1, 0.125), p + Vec3d(0, 1, 0.125)}}})
            .count,
        0u);
    EXPECT_EQ(one(Query{pancake, Tri{{p + Vec3d(2.5, 0, 0), p + Vec3d(3, 1, 0), p + Vec3d(3, -1, 0)}}}).count,
              0u);
  }
}

TEST(EllipsoidTriangleCases, RoundEllipsoidIsSphereTriangle) {
  std::mt19937 g(11);
  std::uniform_real_distribution<double> u(-1, 1), u01(0, 1);
  const std::vector<Query> qs = test::draw_cases(200, [&](int) {
    Query q;
    q.a = test::random_round_ellipsoid(g);
    q.b = random_triangle(g, q.a.p + Vec3d(u(g), u(g), u(g)) * 1.2, 0.3 + u01(g));
    return rounded(q);
  });
  const std::vector<test::PairResult> sphere =
      test::run_queries(&collide_sphere_triangle, qs, KernelPath::kSimd, [](const Query& q) {
        return std::pair{test::sphere_leaf(q.a.p, q.a.e[0]), leaves(q).second};
      });
  // sphere-triangle's normal is the centre-to-triangle direction (unique unless the
  // centre is on the triangle)
  const int hits = test::expect_same_answers(run(qs, KernelPath::kSimd), sphere, {}, [&](size_t k) {
    const bool off = sphere[k].depth < 0.95 * qs[k].a.e[0];
    return test::LaneRule{.normal = off, .point = off};
  });
  EXPECT_GT(hits, 30);
}

TEST(EllipsoidTriangleCases, VertexOrderAndOrientation) {
  std::mt19937 g(19);
  const std::vector<Query> qs = random_queries(g, 120, 1.0, 0.0);
  const std::vector<test::PairResult> h0 = run(qs, KernelPath::kSimd);
  for (int variant = 0; variant < 2; ++variant) {
    std::vector<Query> other = qs;
    for (Query& q : other)
      q.b = variant == 0 ? Tri{{q.b.v[1], q.b.v[2], q.b.v[0]}} : Tri{{q.b.v[0], q.b.v[2], q.b.v[1]}};
    test::expect_same_answers(h0, run(other, KernelPath::kSimd), {.angle = kAngleTol}, [&](size_t k) {
      return test::LaneRule{.scale = size_of(qs[k]), .normal = reference(qs[k]).conditioned};
    });
  }
}

}  // namespace
}  // namespace impact::kernels
