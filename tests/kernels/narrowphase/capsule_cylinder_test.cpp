// collide_capsule_cylinder (kernels/narrowphase/pairs/capsule/capsule_cylinder.cpp) on both paths
// against independent double-precision references.
//
// References (double, the inputs rounded to float as the kernel sees them):
//  - the signed distance of a point to the solid cylinder in closed form (its frame:
//    radial and axial excess; inside, minus the nearer of side and caps);
//  - the core's least signed distance m = min_t sd(c + t u), by golden-section search
//    (the signed distance to a convex set is convex along a line); no feature logic;
//  - m > 0 (core outside): depth_ref = r - m, normal from the core point at the minimum
//    to its closest cylinder point (unique: the offset of two disjoint convex sets'
//    closest points is);
//  - m <= 0 (core meets the cylinder): depth_ref = the least support overlap
//    h_A(n) + h_B(-n) over unit n by dense sampling and Nelder-Mead
//    (tests/support/narrow_reference.h, no candidate enumeration);
//  - the translation check, with the golden-section distance alone: B moved by
//    n (depth + d) is apart by at least d - tol, and moved by n (depth - d) still meets A.
// The references are checked against closed forms first (ReferenceMatchesClosedForms).
// Per lane, L = the larger bounding radius (r + hs, sqrt(rc^2 + h^2)), tol = kRel L:
//  (a) count > 0 iff depth_ref > 0 (either answer where |depth_ref| <= tol), count <= 2;
//  (b) |depth - depth_ref| <= tol;
//  (c) n finite and unit; as good a direction as the reference's (the support overlap
//      along n within tol of depth_ref); angle(n, n_ref) <= kAngleTol where the minimum
//      is unique (core outside by more than 1e-3 L; core inside: no direction outside a
//      0.02 rad cone around n_ref within 2 tol of depth_ref, by nref's own probes and by
//      a dense ring on the cone and the two circles where whole circles of minima occur:
//      the cylinder's horizontal one and the one perpendicular to the core);
//  (d) each point p with depth d: p + n d/2 on the capsule's surface, p - n d/2 on the
//      cylinder's (within tol plus an ulp of the largest coordinate), 0 < d <= depth;
//  (e) the scalar and SIMD paths give the same bytes.
// Scenarios: random poses at sizes 1, 1e-4, 1e4 and 1e5 from the origin (about half
// overlapping); deep: cores through the cylinder's middle, along its axis, crossing a rim,
// wholly inside, coincident centres (the tie rule of a core along the axis); cores lying
// across the cap inside the cylinder (the rims' far-side minima); short cores off a rim; near-parallel cores
// (0..1e-2 rad) beside the side and on the cap: two points at the analytic ends; exactly touching (count 0);
// zero-length cores (sphere-cylinder's answers); needle and pancake proportions (1e-4); symmetries (the flip
// that maps the cylinder onto itself, the core's axis reversed, a rotation of the whole pair).
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

namespace impact::kernels {
namespace {

using Vec3d = Eigen::Vector3d;
using Mat3d = Eigen::Matrix3d;
namespace nref = test::nref;
using test::angle, test::v3, test::ev;

constexpr double kRel = 1e-5;       // depth tolerance, of L
constexpr double kAngleTol = 1e-4;  // rad, where the normal is unique

struct Query : test::FlatCylinder {
  Vec3d c, u;    // capsule centre and axis
  double r, hs;  // radius, half length of the core
};

/// The query as the kernel sees it: every input rounded to float.
Query rounded(Query q) {
  q.c = test::round_to_float(q.c);
  q.u = test::round_to_float(q.u);
  q.r = test::round_to_float(q.r);
  q.hs = test::round_to_float(q.hs);
  test::round_cylinder(&q);
  return q;
}

double size_of(const Query& q) {
  return std::max(q.r + q.hs, std::hypot(q.rc, q.h));
}

double coord_ulp(const Query& q) {
  return test::coordinate_ulp(size_of(q), {q.c, q.p});
}

// --- running the kernel -----------------------------------------------------------------------

/// Runs `kern` (the kernel under test unless given) on lanes [begin, end) of one bucket
/// (the capsule's R: column 2, the axis, as rounded).
std::vector<test::PairResult> run(const std::vector<Query>& qs, KernelPath path, PairKernel kern = nullptr,
                                  uint32_t begin = 0, uint32_t end = ~0u) {
  return test::run_queries(
      kern != nullptr ? kern : pair_kernel(kLeafCapsule, kLeafCylinder), qs, path,
      [](const Query& q) {
        return std::pair{test::axial_leaf(kLeafCapsule, q.c, q.u, q.r, q.hs),
                         test::posed_leaf(kLeafCylinder, q.p, q.R, Vec3d(q.rc, q.h, 0))};
      },
      begin, end);
}

// --- references -------------------------------------------------------------------------------

/// Signed distance of x to the solid cylinder of q (< 0 inside), shifted by `shift`.
double cyl_sd(const Query& q, const Vec3d& x, const Vec3d& shift = Vec3d::Zero()) {
  return test::cylinder_sd(q.p + shift, q.R, q.rc, q.h, x);
}

Vec3d cyl_closest(const Query& q, const Vec3d& x) {
  return test::cylinder_closest(q.p, q.R, q.rc, q.h, x);
}

/// Signed distance of x to the capsule (< 0 inside).
double cap_sd(const Query& q, const Vec3d& x) {
  const double t = std::clamp((x - q.c).dot(q.u) / q.u.squaredNorm(), -q.hs, q.hs);
  return (x - q.c - t * q.u).norm() - q.r;
}

/// min over the core of cyl_sd (convex along the core): golden-section search.
double core_min(const Query& q, const Vec3d& shift = Vec3d::Zero(), double* t_out = nullptr) {
  auto f = [&](double t) { return cyl_sd(q, q.c + t * q.u, shift); };
  double lo = -q.hs, hi = q.hs;
  const double g = 0.5 * (3.0 - std::sqrt(5.0));
  double x1 = lo + g * (hi - lo), x2 = hi - g * (hi - lo), f1 = f(x1), f2 = f(x2);
  for (int it = 0; it < 200 && hi - lo > 1e-17 * (q.hs + 1e-300); ++it) {
    if (f1 <= f2) {
      hi = x2, x2 = x1, f2 = f1, x1 = lo + g * (hi - lo), f1 = f(x1);
    } else {
      lo = x1, x1 = x2, f1 = f2, x2 = hi - g * (hi - lo), f2 = f(x2);
    }
  }
  double t = 0.5 * (lo + hi), best = f(t);
  for (double e : {-q.hs, q.hs})
    if (f(e) < best) best = f(e), t = e;
  if (t_out != nullptr) *t_out = t;
  return best;
}

nref::Shape capsule_shape(const Query& q) {
  nref::Shape s;
  s.type = kLeafCapsule;
  s.p = {q.c.x(), q.c.y(), q.c.z()};
  for (int i = 0; i < 9; ++i) s.r[i] = i % 3 == 2 ? q.u[i / 3] : 0.0;
  s.e[0] = q.r;
  s.e[1] = q.hs;
  return s;
}
nref::Shape cylinder_shape(const Query& q) {
  return test::posed_shape(kLeafCylinder, q.p, q.R, Vec3d(q.rc, q.h, 0));
}

/// The support overlap of A and B along n (the reference's o(n), plus the capsule radius).
double overlap_along(const Query& q, const Vec3d& n) {
  return nref::overlap(capsule_shape(q), cylinder_shape(q), v3(n));
}

struct Ref {
  double depth = 0;  // > 0: penetration depth; else minus the gap
  Vec3d n = Vec3d::UnitZ();
  bool core_outside = false;
  bool unique = false;  // the normal is unique at this tolerance
};

/// Whether n_ref is the only minimiser of the support overlap within 0.02 rad: every
/// direction outside that cone overlaps by more than depth + 2 tol. Beyond nref's own
/// second best (samples, other basins, a ring), a dense ring at 0.02 rad and the two
/// circles where o has kinks and where whole circles of minima occur (the cylinder's
/// horizontal circle, the great circle perpendicular to the core), finely sampled.
bool unique_minimum(const Query& q, const Vec3d& n_ref, double depth, double second, double tol) {
  double best = second;
  Vec3d t1 = n_ref.unitOrthogonal(), t2 = n_ref.cross(t1);
  const double cone = 0.02;
  for (int i = 0; i < 720; ++i) {
    const double a = 2 * M_PI * i / 720;
    best = std::min(
        best,
        overlap_along(q, (n_ref + std::tan(cone) * (std::cos(a) * t1 + std::sin(a) * t2)).normalized()));
  }
  const Vec3d axes[2] = {q.R.col(2), q.u.normalized()};
  for (const Vec3d& ax : axes) {
    const Vec3d e1 = ax.unitOrthogonal(), e2 = ax.cross(e1);
    for (int i = 0; i < 6284; ++i) {
      const double a = 1e-3 * i;
      const Vec3d n = std::cos(a) * e1 + std::sin(a) * e2;
      if (angle(n, n_ref) > cone) best = std::min(best, overlap_along(q, n));
    }
  }
  return best > depth + 2 * tol;
}

Ref reference(const Query& q) {
  Ref f;
  double t;
  const double m = core_min(q, Vec3d::Zero(), &t);
  const double tol = kRel * size_of(q);
  if (m > 0) {
    f.core_outside = true;
    f.depth = q.r - m;
    const Vec3d x = q.c + t * q.u;
    f.n = (cyl_closest(q, x) - x).normalized();
    f.unique = m > 1e-3 * size_of(q);
    return f;
  }
  const nref::PairResult s = nref::solve_pair(capsule_shape(q), cylinder_shape(q));
  f.depth = s.s;
  f.n = ev(s.n);
  f.unique = s.unique(2 * tol) && unique_minimum(q, f.n, s.s, s.second, tol);
  return f;
}

// --- the per-lane check -----------------------------------------------------------------------

using Stats = test::LaneStats;

/// The pair for test::check_lanes: the references above and the distance of the moved pair
/// for the translation check.
void check_all(const std::vector<Query>& qs, const char* what, Stats* out_stats = nullptr) {
  static const test::PairModel<Query> model{
      .rel = kRel,
      .max_points = 2,
      .flag_name = "core-inside",
      .reference =
          [](const Query& q) {
            const Ref f = reference(q);
            return test::LaneRef{f.depth, f.n, f.unique, kAngleTol, !f.core_outside};
          },
      .size = size_of,
      .coord_ulp = coord_ulp,
      .overlap = overlap_along,
      .sd_a = cap_sd,
      .sd_b = [](const Query& q, const Vec3d& x) { return cyl_sd(q, x); },
      .apart = [](const Query& q, const Vec3d& shift) { return core_min(q, shift) - q.r; }};
  test::check_lanes_on_both_paths(
      model, qs, [](const std::vector<Query>& v, KernelPath path) { return run(v, path); }, what, out_stats);
}

// --- inputs -----------------------------------------------------------------------------------

/// A random pair at size `size`, `offset` from the origin, the capsule centre within
/// `spread` (of the pair's reach) of the cylinder's.
Query random_query(std::mt19937& g, double size, double offset, double spread) {
  std::uniform_real_distribution<double> uni(0, 1);
  Query q;
  test::random_cylinder(g, size, offset, &q);
  q.r = size * (0.05 + 0.55 * uni(g));
  q.hs = size * uni(g);
  q.u = test::random_unit_vector(g);
  const double reach = q.r + q.hs + std::hypot(q.rc, q.h);
  q.c = q.p + spread * reach * uni(g) * test::random_unit_vector(g);
  return rounded(q);
}

std::vector<Query> random_queries(std::mt19937& g, int n, double size, double offset) {
  return test::draw_cases(n, [&](int) { return random_query(g, size, offset, 0.9); });
}

/// A query in the cylinder's frame (centre 0, axis z, size 1 parts) posed by a random
/// rotation and offset; c and u are local.
Query posed(std::mt19937& g, const Vec3d& c, const Vec3d& u, double r, double hs, double rc, double h,
            double offset = 0.0) {
  Query q;
  q.R = test::random_rotation(g);
  q.p = Vec3d(offset, 0.3 * offset, -0.7 * offset) + Vec3d(0.25, -0.5, 0.75);
  q.c = q.p + q.R * c;
  q.u = (q.R * u).normalized();
  q.r = r, q.hs = hs, q.rc = rc, q.h = h;
  return rounded(q);
}

// ---------------------------------------------------------------------------------------------

/// The references against closed forms (the point distances they use: reference_self_test):
/// a core beside the side / above
/// the cap / at a rim (apart: r - distance), a core through the middle, along the axis
/// and a parallel core inside near the side (penetration), and nref against the
/// golden-section distance on random separated lanes.
TEST(CapsuleCylinder, ReferenceMatchesClosedForms) {
  Query q;
  q.p = Vec3d(1, 2, 3);
  q.R = Mat3d::Identity();
  q.rc = 1.0, q.h = 2.0;
  q.r = 0.5, q.hs = 1.0;
  struct Case {
    Vec3d c, u;
    double depth;
    Vec3d n;
  };
  const Case cases[] = {
      {Vec3d(1.4, 0, 0.3), Vec3d(0, 0, 1), 0.1, Vec3d(-1, 0, 0)},    // beside the side, parallel
      {Vec3d(0.2, 0, 2.45), Vec3d(1, 0, 0), 0.05, Vec3d(0, 0, -1)},  // lying on the cap
      {Vec3d(2, 0, 2.4), Vec3d(1, 0, 0), 0.5 - std::hypot(0.4, 0.0), Vec3d(0, 0, -1)},  // end over the rim
      {Vec3d(0, 0, 0), Vec3d(1, 0, 0), 0.5 + 1.0, Vec3d(0, 1, 0)},     // through the middle, level
      {Vec3d(0, 0, 0.25), Vec3d(0, 0, 1), 0.5 + 1.0, Vec3d(1, 0, 0)},  // along the axis: out by the side
      {Vec3d(0.7, 0, 0), Vec3d(0, 0, 1), 0.5 + 0.3, Vec3d(-1, 0, 0)},  // parallel, inside, near the side
  };
  for (const Case& cs : cases) {
    Query w = q;
    w.c = q.p + cs.c;
    w.u = cs.u;
    const Ref f = reference(w);
    EXPECT_NEAR(f.depth, cs.depth, 1e-9) << cs.c.transpose();
    if (f.unique) {
      EXPECT_LT(angle(f.n, cs.n), 1e-6) << cs.c.transpose();
    }
  }
  // a rim from outside, diagonally: the end 0.3 / 0.4 off the rim point (1, 0, 2)
  {
    Query w = q;
    w.c = q.p + Vec3d(1.3 + 1.0, 0, 2.4);
    w.u = Vec3d(1, 0, 0);
    const Ref f = reference(w);
    EXPECT_NEAR(f.depth, 0.5 - 0.5, 1e-12);
    EXPECT_LT(angle(f.n, Vec3d(-0.6, 0, -0.8)), 1e-6);
  }
  // nref against the golden-section distance where the core is outside
  std::mt19937 g(5);
  int compared = 0;
  for (int i = 0; i < 60; ++i) {
    const Query w = random_query(g, 1.0, 0.0, 1.2);
    double t;
    const double m = core_min(w, Vec3d::Zero(), &t);
    if (m <= 1e-3) continue;
    const nref::PairResult s = nref::solve_pair(capsule_shape(w), cylinder_shape(w));
    // (the float-rounded rotation is orthonormal to ~1e-8: cyl_sd reads all of R, nref
    // only the axis)
    EXPECT_NEAR(s.s, w.r - m, 1e-7) << i;
    ++compared;
  }
  EXPECT_GT(compared, 10);
}

class CapsuleCylinderScales : public ::testing::TestWithParam<std::tuple<double, double>> {};

TEST_P(CapsuleCylinderScales, RandomPosesAgainstReference) {
  const auto [size, offset] = GetParam();
  const int n = static_cast<int>(test::scaled(offset == 0 && size == 1.0 ? 300 : 80));
  test::random_pose_suite(test::scale_seed(17, size, offset), n, size, offset, random_queries, check_all,
                          {.flagged_div = 20});
}

INSTANTIATE_TEST_SUITE_P(Scales, CapsuleCylinderScales, ::testing::ValuesIn(test::kernel_scales()));

TEST(CapsuleCylinder, DeepCores) {
  std::mt19937 g(29);
  std::uniform_real_distribution<double> uni(-1, 1);
  std::vector<Query> qs;
  const int n = static_cast<int>(test::scaled(24));
  for (int i = 0; i < n; ++i) {
    const double rc = 0.3 + 0.7 * std::fabs(uni(g)), h = 0.3 + 0.7 * std::fabs(uni(g));
    const double r = 0.05 + 0.3 * std::fabs(uni(g)), hs = 0.2 + 1.5 * std::fabs(uni(g));
    // through the middle, any direction
    qs.push_back(posed(g, 0.05 * Vec3d(uni(g), uni(g), uni(g)), test::random_unit_vector(g), r, hs, rc, h));
    // level through the middle (the side or a cap, by rc vs h)
    qs.push_back(posed(g, Vec3d(0.1 * uni(g), 0.1 * uni(g), 0.5 * h * uni(g)),
                       Vec3d(uni(g), uni(g), 0).normalized(), r, hs, rc, h));
    // along the axis
    qs.push_back(posed(g, Vec3d(0, 0, h * uni(g)), Vec3d(0, 0, 1), r, hs, rc, h));
    qs.push_back(
        posed(g, Vec3d(0.3 * rc * uni(g), 0.3 * rc * uni(g), h * uni(g)), Vec3d(0, 0, -1), r, hs, rc, h));
    // crossing a rim
    const double a = M_PI * uni(g);
    const Vec3d rim(rc * std::cos(a), rc * std::sin(a), h * (uni(g) > 0 ? 1 : -1));
    qs.push_back(
        posed(g, rim + 0.1 * Vec3d(uni(g), uni(g), uni(g)), test::random_unit_vector(g), r, hs, rc, h));
    // wholly inside, short core
    qs.push_back(posed(g, Vec3d(0.3 * rc * uni(g), 0.3 * rc * uni(g), 0.3 * h * uni(g)),
                       test::random_unit_vector(g), 0.05, 0.2 * std::min(rc, h), rc, h));
    // coincident centres
    Query c = posed(g, Vec3d::Zero(), test::random_unit_vector(g), r, hs, rc, h);
    c.c = c.p;
    qs.push_back(c);
  }
  Stats st;
  check_all(qs, "deep", &st);
  EXPECT_GT(st.flagged, st.hits * 9 / 10);
  EXPECT_GT(st.hits, static_cast<int>(qs.size()) * 9 / 10);
}

/// Coincident centres with the axes aligned or perpendicular: finite unit normals, the
/// closed-form depths; a core exactly along the axis ties every horizontal direction:
/// the first candidate, R's x axis (as sphere-cylinder's centre on the axis).
TEST(CapsuleCylinder, CoincidentCentresClosedForms) {
  std::mt19937 g(3);
  for (KernelPath path : {KernelPath::kSimd, KernelPath::kScalar}) {
    {
      Query q;
      q.p = Vec3d(2, -1, 0.5);
      q.R = Mat3d::Identity();
      q.c = q.p, q.u = Vec3d(0, 0, 1), q.r = 0.25, q.hs = 0.5, q.rc = 0.5, q.h = 2.0;
      const auto h = run({q}, path)[0];
      ASSERT_GE(h.count, 1u);
      EXPECT_NEAR(h.depth, 0.75, 1e-6);
      EXPECT_EQ(h.n, Vec3d(1, 0, 0));
    }
    // along the axis, rc < h: out by the side, depth r + rc
    Query q = posed(g, Vec3d::Zero(), Vec3d(0, 0, 1), 0.25, 0.5, 0.5, 2.0);
    q.c = q.p;
    auto h = run({q}, path)[0];
    ASSERT_EQ(h.count, 2u);
    EXPECT_NEAR(h.depth, 0.75, 1e-6);
    EXPECT_NEAR(std::fabs(h.n.dot(q.R.col(2))), 0.0, 1e-6);
    EXPECT_NEAR(h.n.norm(), 1.0, 1e-6);
    // along the axis, long core through a short cylinder: still the side
    q = posed(g, Vec3d::Zero(), Vec3d(0, 0, 1), 0.25, 3.0, 1.0, 0.5);
    q.c = q.p;
    h = run({q}, path)[0];
    ASSERT_GE(h.count, 1u);
    EXPECT_NEAR(h.depth, 1.25, 1e-6);
    // level core in a pancake: out through a cap, depth r + h
    q = posed(g, Vec3d::Zero(), Vec3d(1, 0, 0), 0.25, 0.5, 2.0, 0.3);
    q.c = q.p;
    h = run({q}, path)[0];
    ASSERT_GE(h.count, 1u);
    EXPECT_NEAR(h.depth, 0.55, 1e-6);
    EXPECT_NEAR(std::fabs(h.n.dot(q.R.col(2))), 1.0, 1e-6);
    // level core longer than the cylinder is wide: sideways (perpendicular to the core)
    q = posed(g, Vec3d::Zero(), Vec3d(1, 0, 0), 0.25, 3.0, 0.5, 2.0);
    q.c = q.p;
    h = run({q}, path)[0];
    ASSERT_GE(h.count, 1u);
    EXPECT_NEAR(h.depth, 0.75, 1e-6);
    EXPECT_NEAR(h.n.dot(q.u), 0.0, 1e-6);
    EXPECT_NEAR(h.n.dot(q.R.col(2)), 0.0, 1e-6);
  }
}

/// Short cores (1e-6 .. 1e-3 of the size) off a rim: the end and interior candidates'
/// directions differ by up to hs / distance while their o tie within rounding (only
/// candidates whose witness lies on their piece may win).
TEST(CapsuleCylinder, ShortCoresAtARim) {
  std::mt19937 g(71);
  std::uniform_real_distribution<double> uni(-1, 1);
  std::vector<Query> qs;
  const double lengths[] = {1e-6, 1e-5, 1e-4, 1e-3};
  for (int i = 0; i < static_cast<int>(test::scaled(60)); ++i)
    for (double hs : lengths) {
      const double rc = 0.3 + 0.7 * std::fabs(uni(g)), h = 0.3 + 0.7 * std::fabs(uni(g));
      const double a = M_PI * uni(g), side = uni(g) > 0 ? 1.0 : -1.0;
      const Vec3d rim(rc * std::cos(a), rc * std::sin(a), side * h);
      // off the rim diagonally (outside), 0.02 .. 0.3 away
      const Vec3d out =
          (Vec3d(std::cos(a), std::sin(a), 0) * (0.2 + std::fabs(uni(g))) + Vec3d(0, 0, side)).normalized();
      const double dist = 0.02 + 0.28 * std::fabs(uni(g));
      qs.push_back(posed(g, rim + dist * out, test::random_unit_vector(g), dist * (0.5 + std::fabs(uni(g))),
                         hs, rc, h));
      // the core perpendicular to the offset, its nearest point to the rim just beyond an
      // end: the interior (rim) candidate's direction ties the end's within rounding
      const Vec3d u = out.cross(test::random_unit_vector(g)).normalized();
      const double beyond = hs + dist * std::pow(10.0, -5 + 2 * std::fabs(uni(g)));
      qs.push_back(posed(g, rim + dist * out + (uni(g) > 0 ? beyond : -beyond) * u, u,
                         dist * (0.5 + std::fabs(uni(g))), hs, rc, h));
    }
  Stats st;
  check_all(qs, "short cores at a rim", &st);
  EXPECT_GT(st.hits, static_cast<int>(qs.size()) / 4);
}

/// Long, nearly level cores crossing the cylinder just below a cap: the minimum lies on
/// a rim's shadow seen from its far side (the second local minimum of the half ellipse).
TEST(CapsuleCylinder, CoresAcrossTheCapInside) {
  std::mt19937 g(31);
  std::uniform_real_distribution<double> uni(-1, 1);
  std::vector<Query> qs;
  const double tilts[] = {0.0, 1e-6, 1e-4, 1e-3, 1e-2, 0.05, 0.2};
  const int n = static_cast<int>(test::scaled(16));
  for (int i = 0; i < n; ++i)
    for (double tilt : tilts) {
      const double rc = 0.5 + 0.5 * std::fabs(uni(g)), h = 0.3 + 0.7 * std::fabs(uni(g));
      const double a = M_PI * uni(g);
      const Vec3d u = Vec3d(std::cos(a) * std::cos(tilt), std::sin(a) * std::cos(tilt), std::sin(tilt));
      const double below = 0.02 + 0.2 * std::fabs(uni(g));  // the core below the top cap
      const Vec3d c(0.5 * rc * uni(g), 0.5 * rc * uni(g), (h - below) * (uni(g) > 0 ? 1 : -1));
      qs.push_back(posed(g, c, u, 0.02 + 0.1 * std::fabs(uni(g)), 2.0 + std::fabs(uni(g)), rc, h));
    }
  Stats st;
  check_all(qs, "across the cap", &st);
  EXPECT_GT(st.hits, static_cast<int>(qs.size()) * 9 / 10);
}

/// Near-parallel cores beside the side and on the cap: two points at the clipped ends
/// (analytic for the exactly parallel ones), depth and normal against the reference.
TEST(CapsuleCylinder, NearParallelTwoPoints) {
  std::mt19937 g(37);
  std::uniform_real_distribution<double> uni(-1, 1);
  const double tilts[] = {0.0, 1e-7, 1e-5, 1e-3, 1e-2};
  std::vector<Query> qs;
  for (int i = 0; i < static_cast<int>(test::scaled(6)); ++i)
    for (double tilt : tilts) {
      const double rc = 0.5, h = 1.0, r = 0.2, hs = 0.6, d = 0.05;
      const double a = M_PI * uni(g);
      const Vec3d radial(std::cos(a), std::sin(a), 0), side_dir(-std::sin(a), std::cos(a), 0);
      // beside the side, axis tilted by `tilt`, overlapping the side's height in part
      const Vec3d us = (Vec3d(0, 0, 1) + tilt * (uni(g) > 0 ? radial : side_dir)).normalized();
      qs.push_back(posed(g, radial * (rc + r - d) + Vec3d(0, 0, 0.7 * uni(g)), us, r, hs, rc, h));
      // on the top cap, level up to `tilt`, its middle over the disk, an end over the rim
      const Vec3d uc = (radial + tilt * Vec3d(0, 0, uni(g) > 0 ? 1 : -1)).normalized();
      qs.push_back(posed(g, Vec3d(0.2 * uni(g), 0.2 * uni(g), h + r - d), uc, r, hs, rc, h));
    }
  Stats st;
  check_all(qs, "near-parallel", &st);
  EXPECT_EQ(st.counts[2], st.hits);
  EXPECT_GT(st.hits, static_cast<int>(qs.size()) * 3 / 4);
  // Exactly parallel, axis-aligned: the points' positions in closed form.
  for (KernelPath path : {KernelPath::kSimd, KernelPath::kScalar}) {
    Query q;
    q.p = Vec3d(1, -2, 0.5);
    q.R = Mat3d::Identity();
    q.rc = 0.5, q.h = 1.0, q.r = 0.25, q.hs = 1.0;
    // beside the side, 0.125 deep, the core z in [0.25, 2.25] -> clipped to [0.25, 1]
    q.c = q.p + Vec3d(0.625, 0, 1.25);
    q.u = Vec3d(0, 0, 1);
    auto h = run({q}, path)[0];
    ASSERT_EQ(h.count, 2u);
    EXPECT_NEAR(h.depth, 0.125, 1e-6);
    EXPECT_LT(angle(h.n, Vec3d(-1, 0, 0)), 1e-6);
    const double z0 = std::min(h.pt[0].z(), h.pt[1].z()) - q.p.z(),
                 z1 = std::max(h.pt[0].z(), h.pt[1].z()) - q.p.z();
    EXPECT_NEAR(z0, 0.25, 1e-6);
    EXPECT_NEAR(z1, 1.0, 1e-6);
    for (int i = 0; i < 2; ++i) {
      EXPECT_NEAR(h.pt[i].x() - q.p.x(), 0.5 - 0.0625, 1e-6);
      EXPECT_NEAR(h.pd[i], 0.125, 1e-6);
    }
    // lying on the cap, 0.0625 deep, the core x in [0, 2] -> clipped to [0, 0.5]
    q.c = q.p + Vec3d(1.0, 0, 1.1875);
    q.u = Vec3d(1, 0, 0);
    h = run({q}, path)[0];
    ASSERT_EQ(h.count, 2u);
    EXPECT_NEAR(h.depth, 0.0625, 1e-6);
    EXPECT_LT(angle(h.n, Vec3d(0, 0, -1)), 1e-6);
    const double x0 = std::min(h.pt[0].x(), h.pt[1].x()) - q.p.x(),
                 x1 = std::max(h.pt[0].x(), h.pt[1].x()) - q.p.x();
    EXPECT_NEAR(x0, 0.0, 1e-6);
    EXPECT_NEAR(x1, 0.5, 1e-6);
    for (int i = 0; i < 2; ++i) EXPECT_NEAR(h.pt[i].z() - q.p.z(), 1.0 - 0.03125, 1e-6);
  }
}

/// Exactly touching (representable) configurations: count 0; B moved onto touching by
/// the reference's depth along its normal: depth within tol.
TEST(CapsuleCylinder, Touching) {
  for (KernelPath path : {KernelPath::kSimd, KernelPath::kScalar}) {
    Query q;
    q.p = Vec3d(4, 5, -6);
    q.R = Mat3d::Identity();
    q.rc = 0.5, q.h = 1.0, q.r = 0.25, q.hs = 0.75;
    q.c = q.p + Vec3d(0.75, 0, 0.5), q.u = Vec3d(0, 0, 1);  // beside the side
    EXPECT_EQ(run({q}, path)[0].count, 0u);
    q.c = q.p + Vec3d(0.25, 0, 1.25), q.u = Vec3d(1, 0, 0);  // on the cap
    EXPECT_EQ(run({q}, path)[0].count, 0u);
    q.c = q.p + Vec3d(0, 0, -2.0), q.u = Vec3d(0, 0, 1);  // end on the lower cap
    EXPECT_EQ(run({q}, path)[0].count, 0u);
    q.c = q.p + Vec3d(0.5, 0, 2.0), q.u = Vec3d(0, 0, 1);  // end on the rim, axis through it
    EXPECT_EQ(run({q}, path)[0].count, 0u);
  }
  std::mt19937 g(43);
  test::expect_touching_after_push(
      g, static_cast<int>(test::scaled(40)), 400,
      [](std::mt19937& gg) { return random_query(gg, 1.0, 0.0, 0.6); }, reference, test::move_cylinder<Query>,
      [](const std::vector<Query>& qs) { return run(qs, KernelPath::kSimd); }, size_of, kRel);
}

/// A zero-length core is a sphere: sphere-cylinder's answers.
TEST(CapsuleCylinder, ZeroLengthCoreIsSphereCylinder) {
  std::mt19937 g(47);
  std::vector<Query> qs = random_queries(g, static_cast<int>(test::scaled(200)), 1.0, 0.0);
  for (Query& q : qs) q.hs = 0.0;
  check_all(qs, "zero-length core");
  // sphere lanes: A's p and e0 as the capsule's
  const auto mine = run(qs, KernelPath::kSimd), sphere = run(qs, KernelPath::kSimd, &collide_sphere_cylinder);
  for (uint32_t k = 0; k < qs.size(); ++k) {
    const test::PairResult& s = sphere[k];
    const double tol = kRel * size_of(qs[k]);
    if (s.count == 0 || s.depth < tol) continue;
    ASSERT_EQ(mine[k].count, 1u) << k;
    EXPECT_NEAR(mine[k].depth, s.depth, tol) << k;
    if (s.depth < qs[k].r - 1e-3) {  // centre outside
      EXPECT_LT(angle(mine[k].n, s.n), kAngleTol) << k;
    }
  }
}

/// Needles and pancakes (1e-4 proportions) of both shapes.
TEST(CapsuleCylinder, NeedlesAndPancakes) {
  std::mt19937 g(53);
  const int n = static_cast<int>(test::scaled(40));
  const std::vector<Query> qs = test::draw_cases(n, [&](int i) {
    Query q = random_query(g, 1.0, 0.0, 0.6);
    switch (i % 4) {
      case 0:
        q.rc = 1e-4 * q.h;
        break;  // needle cylinder
      case 1:
        q.h = 1e-4 * q.rc;
        break;  // pancake (a disk)
      case 2:
        q.r = 1e-4 * std::max(q.hs, 0.1);
        break;  // needle capsule
      default:
        q.rc = 1e-4 * q.h, q.r = 1e-4 * std::max(q.hs, 0.1);
        break;
    }
    const double reach = q.r + q.hs + std::hypot(q.rc, q.h);
    q.c = q.p + 0.3 * reach * test::random_unit_vector(g);
    return rounded(q);
  });
  test::expect_thin_pairs_meet(qs, check_all);
}

/// Symmetries: the half-turn about the cylinder's x axis maps it onto itself (same
/// depth, the normal turned); reversing the core's axis changes nothing; turning the
/// whole pair turns the normal.
TEST(CapsuleCylinder, Symmetries) {
  std::mt19937 g(59);
  std::vector<Query> base, flipped, reversed, turned;
  for (int i = 0; i < static_cast<int>(test::scaled(120)); ++i) {
    Query q = random_query(g, 1.0, 0.0, 0.7);
    base.push_back(q);
    const Mat3d flip = q.R * Eigen::AngleAxisd(M_PI, Vec3d::UnitX()).toRotationMatrix() * q.R.transpose();
    Query f = q;
    f.c = test::round_to_float(Vec3d(q.p + flip * (q.c - q.p)));
    f.u = test::round_to_float(Vec3d(flip * q.u));
    flipped.push_back(f);
    Query r = q;
    r.u = -q.u;
    reversed.push_back(r);
    const Mat3d turn = test::random_rotation(g);
    Query t = q;
    t.c = test::round_to_float(Vec3d(turn * q.c));
    t.p = test::round_to_float(Vec3d(turn * q.p));
    t.u = test::round_to_float(Vec3d(turn * q.u));
    t.R = test::round_to_float(Mat3d(turn * q.R));
    turned.push_back(t);
  }
  const auto flip = [&](size_t k) {
    return Mat3d(base[k].R * Eigen::AngleAxisd(M_PI, Vec3d::UnitX()).toRotationMatrix() *
                 base[k].R.transpose());
  };
  test::expect_symmetric(run(base, KernelPath::kSimd),
                         {{run(flipped, KernelPath::kSimd), 2, flip},
                          {run(reversed, KernelPath::kSimd)},
                          {run(turned, KernelPath::kSimd), 2,
                           [&](size_t k) { return Mat3d(turned[k].R * base[k].R.transpose()); }}},
                         kAngleTol, [&](size_t k) {
                           const Ref f = reference(base[k]);
                           return test::SymmetryLane{kRel * size_of(base[k]), f.depth, f.unique};
                         });
}

}  // namespace
}  // namespace impact::kernels
