// collide_cylinder_triangle (kernels/narrowphase/pairs/cylinder/cylinder_triangle.cpp) on both paths
// against independent double-precision references, and against the capsule-cylinder
// kernel on the same lanes.
//
// References (double, the inputs rounded to float as the kernel sees them; no candidate
// enumeration, no root solve by steps):
//  - the signed distance of a point to the solid cylinder in closed form (its frame:
//    radial and axial excess; inside, minus the nearer of side and caps);
//  - the triangle's least signed distance m = min over the triangle of sd(x), by nested
//    golden-section search over the barycentric coordinates (the signed distance to a
//    convex set is convex, and so is its minimum over one coordinate);
//  - m > 0 (the triangle outside): depth_ref = -m, normal from the cylinder's point
//    nearest the minimiser to it (unique: the offset of two disjoint convex sets'
//    closest points is);
//  - m <= 0 (they meet): depth_ref = the least support overlap h_A(n) + h_B(-n) over unit
//    n by dense sampling and Nelder-Mead (tests/support/narrow_reference.h);
//  - the translation check, with the golden-section minimum alone: B moved by
//    n (depth + d) is apart by at least d - tol, and moved by n (depth - d) still meets A.
// The references are checked against closed forms and each other first
// (ReferenceMatchesClosedForms).
// Per lane, L = the larger bounding radius (sqrt(rc^2 + h^2), the triangle's about its
// centroid), tol = kRel L:
//  (a) count > 0 iff depth_ref > 0 (either answer where |depth_ref| <= tol), count <= 4;
//  (b) |depth - depth_ref| <= tol;
//  (c) n finite and unit; as good a direction as the reference's (the support overlap
//      along n within tol of depth_ref); angle(n, n_ref) <= kAngleTol where the minimum
//      is unique and well conditioned (triangle outside by more than 1e-3 L; meeting:
//      no direction outside a 0.02 rad cone around n_ref within 2 tol of depth_ref, by
//      nref's own probes and dense probes of the circles where whole circles of minima
//      occur: the cylinder's horizontal one and those perpendicular to the edges; and
//      the overlap rising by >= 1e-6 L 3e-3 rad from n_ref); in a flat valley the bound
//      is the angle at which the overlap rises by kValleyNoise L, if that is larger (the
//      valley as a quadratic through that rise; at IMPACT_TEST_INTENSITY=30 one lane
//      near-parallel to the side was 1.19e-4 rad off);
//  (d) each point p with depth d: p + n d/2 on the cylinder's surface, p - n d/2 on the
//      triangle (within tol plus ulps of the largest coordinate), 0 < d <= depth;
//  (e) the scalar and SIMD paths give the same bytes.
// Scenarios: random poses at sizes 1, 1e-4, 1e4 and 1e5 from the origin (about half
// meeting); large triangles (terrain); deep (through the middle, coincident centres, a
// vertex deep in a cap, an edge through the side, triangles inside); analytic cases
// (standing on a large triangle: 4 rim points; lying on it: the side's 2 ends; an edge
// along the side: its 2 clipped ends; a vertex into a cap; an edge across the side; a
// vertex off a rim); near-parallel caps and edges (tilts 0..1e-2); exactly touching
// (count 0); degenerate triangles (collinear, a point, two equal vertices, slivers
// 1e-3..1e-7) and the capsule-cylinder kernel on segment-like slivers; needles and
// pancakes (1e-4); symmetries (vertex order, the flip that maps the cylinder onto itself,
// a rotation of the whole pair).
// Registration, range partitions, shuffled buckets and the agreement with GJK / EPA:
// contract_test.cpp (every bucket of the table).
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <limits>
#include <numeric>
#include <random>
#include <vector>

#include "kernels/narrowphase/pair_kernels.h"
#include "support/cylinder_frame.h"
#include "support/kernel_checks.h"
#include "support/leaf_lanes.h"
#include "support/narrow_reference.h"
#include "support/random_input.h"
#include "support/same_answers.h"
#include "support/shape_geometry.h"
#include "support/test_support.h"
#include "support/unique_minimum.h"

namespace impact::kernels {
namespace {

using Vec3d = Eigen::Vector3d;
using Mat3d = Eigen::Matrix3d;
namespace nref = test::nref;
using test::angle, test::v3, test::ev;

constexpr double kRel = 1e-5;       // depth tolerance, of L
constexpr double kAngleTol = 1e-4;  // rad, where the minimum is unique and conditioned
constexpr double kValleyNoise = 4e-7;  // of L: twice the worst depth error measured

struct Query : test::FlatCylinder {
  Vec3d v[3];  // triangle
};

/// The query as the kernel sees it: every input rounded to float.
Query rounded(Query q) {
  test::round_cylinder(&q);
  for (Vec3d& v : q.v) v = test::round_to_float(v);
  return q;
}

double triangle_radius(const Query& q) {
  const Vec3d c = (q.v[0] + q.v[1] + q.v[2]) / 3.0;
  return std::max({(q.v[0] - c).norm(), (q.v[1] - c).norm(), (q.v[2] - c).norm()});
}

double size_of(const Query& q) {
  return std::max(std::hypot(q.rc, q.h), triangle_radius(q));
}

double coord_ulp(const Query& q) {
  return test::coordinate_ulp(size_of(q), {q.p, q.v[0], q.v[1], q.v[2]});
}

// --- running the kernel -----------------------------------------------------------------------

/// The cylinder and the triangle of a query.
test::Leaf cylinder_leaf(const Query& q) {
  return test::posed_leaf(kLeafCylinder, q.p, q.R, Vec3d(q.rc, q.h, 0));
}

/// Runs the kernel under test on one bucket of qs.
std::vector<test::PairResult> run(const std::vector<Query>& qs, KernelPath path) {
  return test::run_queries(pair_kernel(kLeafCylinder, kLeafTriangle), qs, path, [](const Query& q) {
    return std::pair{cylinder_leaf(q), test::triangle_leaf(q.v[0], q.v[1], q.v[2])};
  });
}

// --- references -------------------------------------------------------------------------------

double cyl_sd(const Query& q, const Vec3d& x) {
  return test::cylinder_sd(q.p, q.R, q.rc, q.h, x);
}

Vec3d cyl_closest(const Query& q, const Vec3d& x) {
  return test::cylinder_closest(q.p, q.R, q.rc, q.h, x);
}

/// The least signed distance to the cylinder over the triangle moved by `shift` (convex:
/// nested golden-section search over the barycentric coordinates); where = the point.
double triangle_minimum(const Query& q, const Vec3d& shift = Vec3d::Zero(), Vec3d* where = nullptr) {
  auto point = [&](double u, double v) {
    return Vec3d(q.v[0] + u * (q.v[1] - q.v[0]) + v * (q.v[2] - q.v[0]) + shift);
  };
  auto inner = [&](double u, double* v_at) {
    return test::golden_section_min([&](double v) { return cyl_sd(q, point(u, v)); }, 0.0, 1.0 - u, 60, v_at);
  };
  double u = 0, v = 0;
  const double best = test::golden_section_min(
      [&](double uu) {
        double vv;
        return inner(uu, &vv);
      },
      0.0, 1.0, 60, &u);
  inner(u, &v);
  if (where != nullptr) *where = point(u, v);
  return best;
}

nref::Shape cylinder_shape(const Query& q) {
  return test::posed_shape(kLeafCylinder, q.p, q.R, Vec3d(q.rc, q.h, 0));
}
nref::Shape triangle_shape(const Query& q) {
  return nref::make_triangle(v3(q.v[0]), v3(q.v[1]), v3(q.v[2]));
}
double tri_distance(const Query& q, const Vec3d& x) {
  return nref::triangle_distance(v3(x), v3(q.v[0]), v3(q.v[1]), v3(q.v[2]));
}

/// The support overlap of A and B along n.
double overlap_along(const Query& q, const Vec3d& n) {
  return nref::overlap(cylinder_shape(q), triangle_shape(q), v3(n.normalized()));
}

/// Whether n_ref is the only minimiser within 0.02 rad: every direction outside that
/// cone overlaps by more than depth + 2 tol (nref's second best, a dense ring at 0.02 rad,
/// and the circles where whole circles of minima occur: the cylinder's horizontal
/// circle, the great circles perpendicular to the triangle's edges), and the overlap
/// rises by >= 1e-6 L at 3e-3 rad from n_ref in every direction (its flat valleys);
/// *rise: that least rise.
bool unique_minimum(const Query& q, const Vec3d& n_ref, double depth, double second, double tol,
                    double* rise) {
  test::GreatCircles circles{{q.R.col(2)}, 3142, 2e-3};
  for (int j = 0; j < 3; ++j) {
    const Vec3d e = q.v[(j + 1) % 3] - q.v[j];
    if (e.norm() > 0) circles.poles.push_back(e.normalized());
  }
  return test::unique_minimum([&](const Vec3d& n) { return overlap_along(q, n); }, n_ref, depth, second, tol,
                              circles, 1e-6 * size_of(q), rise);
}

struct Ref {
  double depth = 0;  // > 0: penetration depth; else minus the gap
  Vec3d n = Vec3d::UnitZ();
  bool outside = false;
  bool unique = false;  // the normal is unique at this tolerance
  // Where unique: the angle a normal may be off, kAngleTol or, in a flat valley, the
  // angle at which the overlap rises by kValleyNoise L (the valley taken as quadratic
  // from its rise at 3e-3 rad): a float kernel's overlap is only that exact.
  double angle_tol = kAngleTol;
};

Ref reference(const Query& q) {
  Ref f;
  Vec3d x;
  const double m = triangle_minimum(q, Vec3d::Zero(), &x);
  const double tol = kRel * size_of(q);
  if (m > 0) {
    f.outside = true;
    f.depth = -m;
    f.n = (x - cyl_closest(q, x)).normalized();
    f.unique = m > 1e-3 * size_of(q);
    return f;
  }
  const nref::PairResult s =
      nref::solve_pair(cylinder_shape(q), triangle_shape(q), {}, nref::dense_options());
  f.depth = s.s;
  f.n = ev(s.n);
  double rise = 0;
  f.unique = s.unique(2 * tol) && unique_minimum(q, f.n, s.s, s.second, tol, &rise);
  if (f.unique) f.angle_tol = nref::valley_angle(kAngleTol, rise, 3e-3, kValleyNoise * size_of(q));
  return f;
}

// --- the per-lane check -----------------------------------------------------------------------

using Stats = test::LaneStats;

/// The pair for test::check_lanes: the references above and the distance of the moved pair
/// for the translation check.
void check_all(const std::vector<Query>& qs, const char* what, Stats* out_stats = nullptr) {
  static const test::PairModel<Query> model{
      .rel = kRel,
      .flag_name = "meeting",
      .carries = test::Carries::kNoRule,
      .reference =
          [](const Query& q) {
            const Ref f = reference(q);
            return test::LaneRef{f.depth, f.n, f.unique, f.angle_tol, !f.outside};
          },
      .size = size_of,
      .coord_ulp = coord_ulp,
      .overlap = overlap_along,
      .sd_a = cyl_sd,
      .sd_b = tri_distance,  // unsigned: the triangle has no inside
      .apart = [](const Query& q, const Vec3d& shift) { return triangle_minimum(q, shift); }};
  test::check_lanes_on_both_paths(model, qs, run, what, out_stats);
}

// --- inputs -----------------------------------------------------------------------------------

/// A triangle of circumradius ~r around c in a random plane, its angles spread.
void random_triangle(std::mt19937& g, const Vec3d& c, double r, Vec3d (&v)[3]) {
  std::uniform_real_distribution<double> uni(0, 1);
  const Vec3d n = test::random_unit_vector(g), t = n.unitOrthogonal(), b = n.cross(t);
  const double a0 = 2 * M_PI * uni(g);
  for (int i = 0; i < 3; ++i) {
    const double ang = a0 + i * 2 * M_PI / 3 + (uni(g) - 0.5);
    const double rad = r * (0.5 + uni(g));
    v[i] = c + rad * (std::cos(ang) * t + std::sin(ang) * b);
  }
}

/// A random pair at size `size`, `offset` from the origin, the triangle's centroid within
/// `spread` (of the pair's reach) of the cylinder's centre.
Query random_query(std::mt19937& g, double size, double offset, double spread) {
  std::uniform_real_distribution<double> uni(0, 1);
  Query q;
  test::random_cylinder(g, size, offset, &q);
  const double tr = size * (0.1 + 1.2 * uni(g));
  const double reach = std::hypot(q.rc, q.h) + tr;
  random_triangle(g, q.p + spread * reach * uni(g) * test::random_unit_vector(g), tr, q.v);
  return rounded(q);
}

std::vector<Query> random_queries(std::mt19937& g, int n, double size, double offset) {
  return test::draw_cases(n, [&](int) { return random_query(g, size, offset, 0.8); });
}

/// A query in the cylinder's frame (centre 0, axis z) posed by a random rotation and
/// offset; the vertices are local.
Query posed(std::mt19937& g, const Vec3d& v0, const Vec3d& v1, const Vec3d& v2, double rc, double h,
            double offset = 0.0) {
  Query q;
  q.R = test::random_rotation(g);
  q.p = Vec3d(offset, 0.3 * offset, -0.7 * offset) + Vec3d(0.25, -0.5, 0.75);
  q.v[0] = q.p + q.R * v0, q.v[1] = q.p + q.R * v1, q.v[2] = q.p + q.R * v2;
  q.rc = rc, q.h = h;
  return rounded(q);
}

/// An axis-aligned query (R = I): exact in float for the analytic cases.
Query aligned(const Vec3d& p, const Vec3d& v0, const Vec3d& v1, const Vec3d& v2, double rc, double h) {
  Query q;
  q.R = Mat3d::Identity();
  q.p = p;
  q.v[0] = p + v0, q.v[1] = p + v1, q.v[2] = p + v2;
  q.rc = rc, q.h = h;
  return rounded(q);
}

// ---------------------------------------------------------------------------------------------

/// The references against closed forms (the point distance: reference_self_test; a
/// triangle on a cap, beside
/// the side, off a rim, through the middle) and against each other (nref's sampled
/// minimum against the golden-section distance on separated lanes).
TEST(CylinderTriangle, ReferenceMatchesClosedForms) {
  Query q;
  q.p = Vec3d(1, 2, 3);
  q.R = Mat3d::Identity();
  q.rc = 1.0, q.h = 2.0;
  struct Case {
    Vec3d v0, v1, v2;
    double depth;
    Vec3d n;
  };
  const Case cases[] = {
      // a large level triangle 0.25 into the top cap
      {Vec3d(-10, -10, 1.75), Vec3d(10, -10, 1.75), Vec3d(0, 10, 1.75), 0.25, Vec3d(0, 0, 1)},
      // a vertical triangle 0.1 into the side
      {Vec3d(0.9, -5, -5), Vec3d(0.9, 5, -5), Vec3d(0.9, 0, 5), 0.1, Vec3d(1, 0, 0)},
      // a vertex 0.3 / 0.4 off the rim point (1, 0, 2), the triangle leaning away
      {Vec3d(1.3, 0, 2.4), Vec3d(3, 1, 3), Vec3d(3, -1, 3), -0.5, Vec3d(0.6, 0, 0.8)},
      // a vertex 0.2 into the bottom cap
      {Vec3d(0.3, 0.2, -1.8), Vec3d(1, 2, -4), Vec3d(-1, 2, -4), 0.2, Vec3d(0, 0, -1)},
  };
  for (const Case& cs : cases) {
    Query w = q;
    w.v[0] = q.p + cs.v0, w.v[1] = q.p + cs.v1, w.v[2] = q.p + cs.v2;
    const Ref f = reference(w);
    EXPECT_NEAR(f.depth, cs.depth, 1e-9) << cs.v0.transpose();
    EXPECT_TRUE(f.unique) << cs.v0.transpose();
    EXPECT_LT(angle(f.n, cs.n), 1e-6) << cs.v0.transpose();
  }
  // nref against the golden-section distance where the triangle is outside
  std::mt19937 g(5);
  int compared = 0;
  for (int i = 0; i < 60; ++i) {
    const Query w = random_query(g, 1.0, 0.0, 1.2);
    const double m = triangle_minimum(w);
    if (m <= 1e-3) continue;
    const nref::PairResult s =
        nref::solve_pair(cylinder_shape(w), triangle_shape(w), {}, nref::dense_options());
    // (the float-rounded rotation is orthonormal to ~1e-8: cyl_sd reads all of R, nref
    // only the axis)
    EXPECT_NEAR(s.s, -m, 1e-7) << i;
    ++compared;
  }
  EXPECT_GT(compared, 10);
}

class CylinderTriangleScales : public ::testing::TestWithParam<std::tuple<double, double>> {};

TEST_P(CylinderTriangleScales, RandomPosesAgainstReference) {
  const auto [size, offset] = GetParam();
  const int n = static_cast<int>(test::scaled(offset == 0 && size == 1.0 ? 300 : 80));
  test::random_pose_suite(test::scale_seed(17, size, offset), n, size, offset, random_queries, check_all,
                          {.flagged_div = 8});
}

INSTANTIATE_TEST_SUITE_P(Scales, CylinderTriangleScales, ::testing::ValuesIn(test::kernel_scales()));

/// Large triangles (10 .. 1e4 times the cylinder: terrain) through, under and beside it.
TEST(CylinderTriangle, LargeTriangles) {
  std::mt19937 g(19);
  std::uniform_real_distribution<double> uni(-1, 1);
  std::vector<Query> qs;
  const double scales[] = {10.0, 100.0, 1e4};
  for (int i = 0; i < static_cast<int>(test::scaled(30)); ++i)
    for (double sc : scales) {
      Query q = random_query(g, 1.0, 0.0, 0.0);
      // the triangle's plane through a point within the cylinder's reach, its centroid
      // up to half its size away along the plane
      const double reach = std::hypot(q.rc, q.h);
      const Vec3d n = test::random_unit_vector(g), t = n.unitOrthogonal(), b = n.cross(t);
      const Vec3d c = q.p + 1.2 * reach * uni(g) * n + 0.5 * sc * (uni(g) * t + uni(g) * b) * reach;
      random_triangle(g, c, sc * reach, q.v);
      // project the vertices onto the plane through c (random_triangle's plane is random)
      for (Vec3d& v : q.v) v = c + (v - c) - (v - c).dot(n) * n + 0.0 * n;
      qs.push_back(rounded(q));
    }
  Stats st;
  check_all(qs, "large triangles", &st);
  EXPECT_GT(st.hits, static_cast<int>(qs.size()) / 5);
}

TEST(CylinderTriangle, DeepTriangles) {
  std::mt19937 g(29);
  std::uniform_real_distribution<double> uni(-1, 1);
  std::vector<Query> qs;
  const int n = static_cast<int>(test::scaled(24));
  for (int i = 0; i < n; ++i) {
    const double rc = 0.3 + 0.7 * std::fabs(uni(g)), h = 0.3 + 0.7 * std::fabs(uni(g));
    Vec3d v[3];
    // through the middle, any plane
    random_triangle(g, 0.05 * Vec3d(uni(g), uni(g), uni(g)), 1.0 + std::fabs(uni(g)), v);
    qs.push_back(posed(g, v[0], v[1], v[2], rc, h));
    // coincident centres: the centroid at the cylinder's centre
    random_triangle(g, Vec3d::Zero(), 0.3 + std::fabs(uni(g)), v);
    const Vec3d c = (v[0] + v[1] + v[2]) / 3.0;
    qs.push_back(posed(g, v[0] - c, v[1] - c, v[2] - c, rc, h));
    // a vertex deep in a cap, the triangle leaning out
    const double sz = uni(g) > 0 ? 1.0 : -1.0;
    const Vec3d tip(0.5 * rc * uni(g), 0.5 * rc * uni(g), sz * h * (1 - 0.3 * std::fabs(uni(g))));
    const Vec3d out = (Vec3d(0.5 * uni(g), 0.5 * uni(g), sz)).normalized(), side = out.unitOrthogonal();
    qs.push_back(posed(g, tip, tip + 2 * h * out + side, tip + 2 * h * out - side, rc, h));
    // an edge through the side, the triangle outside
    const double a = M_PI * uni(g);
    const Vec3d radial(std::cos(a), std::sin(a), 0), along = Vec3d(-std::sin(a), std::cos(a), 0);
    const Vec3d dir = (along + 0.5 * uni(g) * Vec3d::UnitZ()).normalized();
    const Vec3d m0 = radial * rc * (1 - 0.4 * std::fabs(uni(g))) + Vec3d(0, 0, 0.8 * h * uni(g));
    qs.push_back(posed(g, m0 - 2 * rc * dir, m0 + 2 * rc * dir, m0 + 2 * rc * radial, rc, h));
    // a small triangle inside
    random_triangle(g, Vec3d(0.3 * rc * uni(g), 0.3 * rc * uni(g), 0.3 * h * uni(g)), 0.2 * std::min(rc, h),
                    v);
    qs.push_back(posed(g, v[0], v[1], v[2], rc, h));
  }
  Stats st;
  check_all(qs, "deep", &st);
  EXPECT_GT(st.flagged, st.hits * 9 / 10);
  EXPECT_GT(st.hits, static_cast<int>(qs.size()) * 9 / 10);
}

/// Closed-form answers (axis-aligned, exact in float), both paths: standing on a large
/// triangle (4 rim points), lying on it (the side line's 2 ends), an edge along the side
/// (its 2 ends clipped to the side's height), a vertex into a cap (1 point), an edge
/// lying across a cap (its 2 crossings of the rim), an edge across the side (1 point).
TEST(CylinderTriangle, AnalyticCases) {
  const Vec3d p(1, -2, 0.5);
  const double rc = 0.5, h = 1.0, d = 0.125;
  for (KernelPath path : {KernelPath::kSimd, KernelPath::kScalar}) {
    SCOPED_TRACE(path == KernelPath::kSimd ? "simd" : "scalar");
    // standing on a large level triangle, d into the bottom cap
    {
      const Query q =
          aligned(p, Vec3d(-10, -10, -h + d), Vec3d(10, -10, -h + d), Vec3d(0, 10, -h + d), rc, h);
      const auto r = run({q}, path)[0];
      ASSERT_EQ(r.count, 4u);
      EXPECT_EQ(r.n, Vec3d(0, 0, -1));
      EXPECT_NEAR(r.depth, d, 1e-6);
      for (uint32_t i = 0; i < r.count; ++i) {
        const Vec3d l = r.pt[i] - p;
        EXPECT_NEAR(l.z(), -h + d / 2, 1e-6);
        EXPECT_NEAR(std::hypot(l.x(), l.y()), rc, 1e-6);
        EXPECT_NEAR(r.pd[i], d, 1e-6);
      }
      // (the 4 points span the disk: the farthest pair a diameter)
      double far = 0;
      for (uint32_t i = 0; i < 4; ++i)
        for (uint32_t j = 0; j < 4; ++j) far = std::max(far, (r.pt[i] - r.pt[j]).norm());
      EXPECT_NEAR(far, 2 * rc, 1e-6);
    }
    // lying on a large level triangle (axis along x), d into the side
    {
      Query q = aligned(p, Vec3d(-10, -10, -rc + d), Vec3d(10, -10, -rc + d), Vec3d(0, 10, -rc + d), rc, h);
      q.R << 0, 0, 1, 0, 1, 0, -1, 0, 0;  // column 2 = +x
      test::expect_line_contact(run({q}, path)[0], {.n = Vec3d(0, 0, -1),
                                                    .d = d,
                                                    .origin = p,
                                                    .axis = 0,
                                                    .lo = -h,
                                                    .hi = h,
                                                    .at = Vec3d(0, 0.0, -rc + d / 2)});
    }
    // an edge along the side, d inside, z in [-0.5, 2.5] -> clipped to [-0.5, h]
    {
      const Query q = aligned(p, Vec3d(rc - d, 0, -0.5), Vec3d(rc - d, 0, 2.5), Vec3d(rc + 3, 0, 1.0), rc, h);
      const double unchecked = std::numeric_limits<double>::quiet_NaN();
      test::expect_line_contact(run({q}, path)[0], {.n = Vec3d(1, 0, 0),
                                                    .d = d,
                                                    .origin = p,
                                                    .axis = 2,
                                                    .lo = -0.5,
                                                    .hi = h,
                                                    .at = Vec3d(rc - d / 2, unchecked, unchecked)});
    }
    // a vertex into the top cap, the triangle leaning out: 1 point
    {
      const Query q = aligned(p, Vec3d(0.125, 0.25, h - d), Vec3d(1, 1, 3), Vec3d(-1, 1, 3), rc, h);
      const auto r = run({q}, path)[0];
      ASSERT_EQ(r.count, 1u);
      EXPECT_EQ(r.n, Vec3d(0, 0, 1));
      EXPECT_NEAR(r.depth, d, 1e-6);
      EXPECT_LT((r.pt[0] - (p + Vec3d(0.125, 0.25, h - d / 2))).norm(), 1e-6);
    }
    // an edge lying across the top cap (y = 0.25), the triangle rising away: the 2 rim
    // crossings x = +-sqrt(rc^2 - 0.25^2)
    {
      const Query q = aligned(p, Vec3d(-2, 0.25, h - d), Vec3d(2, 0.25, h - d), Vec3d(0, 3, h + 5), rc, h);
      const double xc = std::sqrt(rc * rc - 0.25 * 0.25);
      test::expect_line_contact(run({q}, path)[0], {.n = Vec3d(0, 0, 1),
                                                    .d = d,
                                                    .origin = p,
                                                    .axis = 0,
                                                    .lo = -xc,
                                                    .hi = xc,
                                                    .points_carry_depth = false});
    }
    // an edge across the side (horizontal, along y, d inside), the triangle in the plane
    // z = 0 reaching out: n = +x, one point
    {
      const Query q = aligned(p, Vec3d(rc - d, -2, 0), Vec3d(rc - d, 2, 0), Vec3d(rc + 2, 0, 0), rc, h);
      const auto r = run({q}, path)[0];
      ASSERT_GE(r.count, 1u);
      EXPECT_LT(angle(r.n, Vec3d(1, 0, 0)), 1e-6);
      EXPECT_NEAR(r.depth, d, 1e-6);
    }
    // a vertex 0.3 / 0.4 off the rim, apart
    {
      const Query q =
          aligned(p, Vec3d(rc + 0.3, 0, h + 0.4), Vec3d(rc + 2, 1, h + 1), Vec3d(rc + 2, -1, h + 1), rc, h);
      EXPECT_EQ(run({q}, path)[0].count, 0u);
    }
  }
}

/// Near-parallel contacts: a large triangle tilted 0..1e-2 rad from level on a cap
/// (several points), an edge tilted from the axis beside the side (also one past both
/// caps) and the cylinder lying tilted on a triangle (2 points).
TEST(CylinderTriangle, NearParallelManifolds) {
  std::mt19937 g(37);
  std::uniform_real_distribution<double> uni(-1, 1);
  const double tilts[] = {0.0, 1e-7, 1e-5, 1e-3, 1e-2};
  std::vector<Query> caps, sides;
  for (int i = 0; i < static_cast<int>(test::scaled(6)); ++i)
    for (double tilt : tilts) {
      const double rc = 0.5, h = 1.0, d = 0.05;
      const double a = M_PI * uni(g);
      const Vec3d radial(std::cos(a), std::sin(a), 0), tang(-std::sin(a), std::cos(a), 0);
      // a large triangle on the top cap, d deep, tilted about a random horizontal axis
      const Vec3d nrm = (Vec3d::UnitZ() + tilt * radial).normalized(), t1 = nrm.cross(tang).normalized(),
                  t2 = nrm.cross(t1);
      const Vec3d c(0.3 * uni(g), 0.3 * uni(g), h - d);
      caps.push_back(posed(g, c + 4 * t1, c - 2 * t1 + 3.5 * t2, c - 2 * t1 - 3.5 * t2, rc, h));
      // an edge beside the side, d deep, tilted from the axis, the triangle outside
      const Vec3d ax = (Vec3d::UnitZ() + tilt * (uni(g) > 0 ? radial : tang)).normalized();
      const Vec3d m0 = radial * (rc - d) + Vec3d(0, 0, 0.5 * uni(g));
      sides.push_back(posed(g, m0 - 0.8 * ax, m0 + 0.8 * ax, m0 + 2 * radial + 0.3 * tang, rc, h));
      // an edge along the side past both caps (its ends clipped to the cap planes)
      const Vec3d m1 = radial * (rc - d);
      sides.push_back(posed(g, m1 - 1.5 * h * ax, m1 + 1.5 * h * ax, m1 + 2 * radial + 0.3 * tang, rc, h));
      // lying on a large triangle (the axis tilted from its plane)
      const Vec3d up = (radial + tilt * Vec3d::UnitZ()).normalized(), s1 = up.cross(tang).normalized(),
                  s2 = up.cross(s1);
      const Vec3d cs = radial * (rc - d) + 0.2 * uni(g) * tang;
      sides.push_back(posed(g, cs + 5 * s1, cs - 2.5 * s1 + 4 * s2, cs - 2.5 * s1 - 4 * s2, rc, h));
    }
  Stats st;
  check_all(caps, "near-level on a cap", &st);
  EXPECT_EQ(st.hits, static_cast<int>(caps.size()));
  EXPECT_GE(st.counts[3] + st.counts[4], st.hits * 9 / 10);
  check_all(sides, "near-parallel to the side", &st);
  EXPECT_EQ(st.hits, static_cast<int>(sides.size()));
  EXPECT_EQ(st.counts[1], 0);  // every contact has more than one point
}

/// Exactly touching (representable) configurations: count 0; B moved onto touching by
/// the reference's depth along its normal: depth within tol.
TEST(CylinderTriangle, Touching) {
  const Vec3d p(4, 5, -6);
  const double rc = 0.5, h = 1.0;
  for (KernelPath path : {KernelPath::kSimd, KernelPath::kScalar}) {
    // a large triangle on the cap plane
    EXPECT_EQ(run({aligned(p, Vec3d(-5, -5, h), Vec3d(5, -5, h), Vec3d(0, 5, h), rc, h)}, path)[0].count, 0u);
    // a vertical triangle tangent to the side
    EXPECT_EQ(run({aligned(p, Vec3d(rc, -5, -5), Vec3d(rc, 5, -5), Vec3d(rc, 0, 5), rc, h)}, path)[0].count,
              0u);
    // a vertex on the rim, the triangle leaning out
    EXPECT_EQ(run({aligned(p, Vec3d(rc, 0, h), Vec3d(2, 1, 2), Vec3d(2, -1, 2), rc, h)}, path)[0].count, 0u);
    // an edge on the rim's tangent line in the cap plane
    EXPECT_EQ(run({aligned(p, Vec3d(rc, -2, h), Vec3d(rc, 2, h), Vec3d(2, 0, 2), rc, h)}, path)[0].count, 0u);
  }
  std::mt19937 g(43);
  test::expect_touching_after_push(
      g, static_cast<int>(test::scaled(40)), 400,
      [](std::mt19937& gg) { return random_query(gg, 1.0, 0.0, 0.5); }, reference,
      [](Query& q, const Vec3d& s) {
        for (Vec3d& v : q.v) v = test::round_to_float(Vec3d(v + s));
      },
      [](const std::vector<Query>& qs) { return run(qs, KernelPath::kSimd); }, size_of, kRel);
}

/// Degenerate triangles: collinear (exactly), a point, two equal vertices, slivers of
/// height 1e-3 .. 1e-7 of their base: the references handle them as the sets they are.
TEST(CylinderTriangle, DegenerateTriangles) {
  std::mt19937 g(41);
  std::uniform_real_distribution<double> uni(-1, 1);
  std::vector<Query> qs;
  for (int i = 0; i < static_cast<int>(test::scaled(30)); ++i) {
    Query q = random_query(g, 1.0, 0.0, 0.6);
    const Vec3d a = q.v[0], b = q.v[1];
    Query c = q;  // collinear: the midpoint (exact in float up to one rounding)
    c.v[2] = test::round_to_float(Vec3d(0.5 * (a + b)));
    qs.push_back(c);
    Query pt = q;  // a point
    pt.v[1] = pt.v[2] = a;
    qs.push_back(pt);
    Query two = q;  // two equal vertices
    two.v[2] = b;
    qs.push_back(two);
    for (double hgt : {1e-3, 1e-5, 1e-7}) {  // slivers
      Query s = q;
      const Vec3d ab = b - a, perp = ab.cross(test::random_unit_vector(g)).normalized();
      s.v[2] = test::round_to_float(Vec3d(a + (0.3 + 0.4 * std::fabs(uni(g))) * ab + hgt * ab.norm() * perp));
      qs.push_back(s);
    }
  }
  Stats st;
  check_all(qs, "degenerate triangles", &st);
  EXPECT_GT(st.hits, static_cast<int>(qs.size()) / 5);
}

/// A segment-like sliver is a capsule of radius ~0: capsule-cylinder's answers (depth
/// minus the capsule's radius, the normal reversed: A and B swap).
TEST(CylinderTriangle, SliverIsCapsuleCylinder) {
  std::mt19937 g(47);
  const std::vector<Query> qs = test::draw_cases(static_cast<int>(test::scaled(200)), [&](int) {
    Query q = random_query(g, 1.0, 0.0, 0.6);
    const Vec3d a = q.v[0], b = q.v[1], perp = (b - a).cross(test::random_unit_vector(g)).normalized();
    q.v[2] = test::round_to_float(Vec3d(0.5 * (a + b) + 1e-7 * (b - a).norm() * perp));
    return q;
  });
  const auto mine = run(qs, KernelPath::kSimd);
  // capsule lanes: core v0 .. v1, radius r
  const double r = 1e-6;
  const auto sliver =
      test::run_queries(&collide_capsule_cylinder, qs, KernelPath::kSimd, [&](const Query& q) {
        const Vec3d c = 0.5 * (q.v[0] + q.v[1]), u = (q.v[1] - q.v[0]).normalized();
        return std::pair{test::axial_leaf(kLeafCapsule, c, u, r, 0.5 * (q.v[1] - q.v[0]).norm()),
                         cylinder_leaf(q)};
      });
  int compared = 0;
  for (uint32_t k = 0; k < qs.size(); ++k) {
    const test::PairResult& s = sliver[k];
    const double tol = kRel * size_of(qs[k]);
    if (s.count == 0 || s.depth - r < 2 * tol) continue;
    ASSERT_GE(mine[k].count, 1u) << k;
    ++compared;
    EXPECT_NEAR(mine[k].depth, s.depth - r, tol) << k;
    const Ref f = reference(qs[k]);
    if (f.unique) {
      EXPECT_LT(angle(mine[k].n, -s.n), kAngleTol) << k;
    }
  }
  EXPECT_GT(compared, static_cast<int>(qs.size()) / 5);
}

/// Needles and pancakes (1e-4 proportions) of the cylinder, against triangles of the
/// larger size.
TEST(CylinderTriangle, NeedlesAndPancakes) {
  std::mt19937 g(53);
  const int n = static_cast<int>(test::scaled(40));
  const std::vector<Query> qs = test::draw_cases(n, [&](int i) {
    Query q = random_query(g, 1.0, 0.0, 0.5);
    if (i % 2 == 0) {
      q.rc = test::round_to_float(1e-4 * q.h);  // needle
    } else {
      q.h = test::round_to_float(1e-4 * q.rc);  // pancake (a disk)
    }
    return q;
  });
  test::expect_thin_pairs_meet(qs, check_all);
}

/// Symmetries: the vertex order (cyclic and reversed) changes nothing; the half-turn
/// about the cylinder's x axis maps it onto itself (the normal turned); turning the whole
/// pair turns the normal.
TEST(CylinderTriangle, Symmetries) {
  std::mt19937 g(59);
  std::vector<Query> base, cyc, rev, flipped, turned;
  for (int i = 0; i < static_cast<int>(test::scaled(120)); ++i) {
    const Query q = random_query(g, 1.0, 0.0, 0.6);
    base.push_back(q);
    Query c = q;
    c.v[0] = q.v[1], c.v[1] = q.v[2], c.v[2] = q.v[0];
    cyc.push_back(c);
    Query r = q;
    std::swap(r.v[1], r.v[2]);
    rev.push_back(r);
    const Mat3d flip = q.R * Eigen::AngleAxisd(M_PI, Vec3d::UnitX()).toRotationMatrix() * q.R.transpose();
    Query f = q;
    for (int j = 0; j < 3; ++j) f.v[j] = test::round_to_float(Vec3d(q.p + flip * (q.v[j] - q.p)));
    flipped.push_back(f);
    const Mat3d turn = test::random_rotation(g);
    Query t = q;
    t.p = test::round_to_float(Vec3d(turn * q.p));
    t.R = test::round_to_float(Mat3d(turn * q.R));
    for (int j = 0; j < 3; ++j) t.v[j] = test::round_to_float(Vec3d(turn * q.v[j]));
    turned.push_back(t);
  }
  const auto flip = [&](size_t k) {
    return Mat3d(base[k].R * Eigen::AngleAxisd(M_PI, Vec3d::UnitX()).toRotationMatrix() *
                 base[k].R.transpose());
  };
  test::expect_symmetric(run(base, KernelPath::kSimd),
                         {{run(cyc, KernelPath::kSimd)},
                          {run(rev, KernelPath::kSimd)},
                          {run(flipped, KernelPath::kSimd), 2, flip},
                          {run(turned, KernelPath::kSimd), 2,
                           [&](size_t k) { return Mat3d(turned[k].R * base[k].R.transpose()); }}},
                         kAngleTol, [&](size_t k) {
                           const Ref f = reference(base[k]);
                           return test::SymmetryLane{kRel * size_of(base[k]), f.depth, f.unique};
                         });
}

}  // namespace
}  // namespace impact::kernels
