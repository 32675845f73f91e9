// collide_box_cylinder (kernels/narrowphase/pairs/box/box_cylinder.cpp) on both paths against
// independent double-precision references.
//
// References (double, the inputs rounded to float as the kernel sees them; no candidate
// enumeration, no root solve by steps):
//  - the signed distances of a point to the solid box and to the solid cylinder in
//    closed form (each in its own frame: the box's excess per axis; the cylinder's
//    radial and axial excess; inside, minus the nearest face);
//  - the gap: the least signed distance to the cylinder over the box's six faces, by
//    nested golden-section search over each face's two coordinates (the signed distance
//    to a convex set is convex, and so is its minimum over one coordinate). The two
//    are apart iff the gap is > 0 and the cylinder's centre lies outside the box (a
//    cylinder that meets no face of the box and is not inside it misses it); the gap is
//    then their distance;
//  - apart: depth_ref = -gap, normal from the box's point at the minimum to its closest
//    cylinder point (unique: the offset of two disjoint convex sets' closest points is);
//  - meeting: depth_ref = the least support overlap h_A(n) + h_B(-n) over unit n by
//    dense sampling and Nelder-Mead (tests/support/narrow_reference.h);
//  - the translation check, with the gap alone: B moved by n (depth + d) is apart by at
//    least d - 2 tol, and moved by n (depth - d) still meets A.
// The references are checked against closed forms and each other first
// (ReferenceMatchesClosedForms), and every feature scenario against its construction
// (apart: the built features are each other's closest points, at the built distance;
// meeting: the overlap along the built normal is the built depth, an upper bound).
// Per lane, L = the larger bounding radius (the box's half diagonal, sqrt(rc^2 + h^2)),
// tol = kRel L:
//  (a) count > 0 iff depth_ref > 0 (either answer where |depth_ref| <= tol), count <= 4;
//  (b) |depth - depth_ref| <= tol;
//  (c) n finite and unit; as good a direction as the reference's (the support overlap
//      along n within tol of depth_ref); angle(n, n_ref) <= kAngleTol where the minimum
//      is unique and well conditioned (no direction outside a 0.02 rad cone around
//      n_ref within 2 tol of depth_ref, by nref's own probes, a dense ring on the cone
//      and dense probes of the great circles where whole circles of minima occur: the
//      cylinder's horizontal one and those perpendicular to each box axis; and the
//      overlap rising by >= 1e-6 L 3e-3 rad from n_ref); in a flat valley the bound is
//      the angle at which the overlap rises by kValleyNoise L, if that is larger (the
//      valley as a quadratic through that rise; at IMPACT_TEST_INTENSITY=30 three
//      needle / pancake lanes were 1.7-3.6e-4 rad off, depth within 2.1e-7 L);
//  (d) each point p with depth d: p + n d/2 on the box's surface, p - n d/2 on the
//      cylinder's (within tol plus ulps of the largest coordinate), 0 < d <= depth, a
//      single point carries the depth;
//  (e) the scalar and SIMD paths give the same bytes.
// Scenarios: random poses at sizes 1, 1e-4, 1e4 and 1e5 from the origin (about half
// meeting); deep (a long box through the middle, coincident centres, a box wholly
// inside, the cylinder wholly inside a big box, a box over a rim); feature pairs built in
// closed form, apart and meeting: a box edge across a rim (the minimum on an edge-rim
// piece), a box vertex at a rim, an edge against the side (normal edge x axis), a vertex
// against the side, a face against a rim, a vertex into a cap; apart pairs that only the
// edge-rim piece separates (an edge just off a rim, D away, the least closed-form overlap
// in (0, D/2)); manifolds (axis-aligned, both paths): a box resting flat on the cap (its
// 4 face corners, or rim points within the face), the cylinder standing on a box face
// (rim points), lying on it (the side line's 2 ends, clipped to the face); near-parallel
// tilts (0..1e-2 rad) of those; exactly touching (count 0); needle and pancake boxes and
// cylinders (1e-4); symmetries (a rotation and translation of the whole pair, the
// cylinder's axis reversed, the box's axes relabelled).
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
using test::angle, test::columns, test::rot, test::turn_to, test::radial, test::tangential, test::v3,
    test::ev;

constexpr double kRel = 1e-5;       // depth tolerance, of L
constexpr double kAngleTol = 1e-4;  // rad, where the minimum is unique and conditioned
constexpr double kValleyNoise = 4e-7;  // of L: twice the worst depth error measured
/// Golden-section steps per coordinate of the gap: brackets of 0.618^48 ~ 1e-10 of a face.
constexpr int kGoldenIters = 48;

struct Query : test::FlatCylinder {
  Vec3d c;  // box centre
  Mat3d Q;  // box rotation (columns: its axes)
  Vec3d e;  // box half extents
};

/// The query as the kernel sees it: every input rounded to float.
Query rounded(Query q) {
  q.c = test::round_to_float(q.c);
  q.Q = test::round_to_float(q.Q);
  q.e = test::round_to_float(q.e);
  test::round_cylinder(&q);
  return q;
}

double size_of(const Query& q) {
  return std::max(q.e.norm(), std::hypot(q.rc, q.h));
}

double coord_ulp(const Query& q) {
  return test::coordinate_ulp(size_of(q), {q.c, q.p});
}

// --- running the kernel -----------------------------------------------------------------------

/// Runs the kernel under test on one bucket of qs.
std::vector<test::PairResult> run(const std::vector<Query>& qs, KernelPath path) {
  return test::run_queries(
      &collide_box_cylinder, qs, path, [](const Query& q) {
        return std::pair{test::posed_leaf(kLeafBox, q.c, q.Q, q.e),
                         test::posed_leaf(kLeafCylinder, q.p, q.R, Vec3d(q.rc, q.h, 0))};
      });
}

// --- references -------------------------------------------------------------------------------

double box_sd(const Query& q, const Vec3d& x) {
  return test::box_sd(q.c, q.Q, q.e, x);
}

/// Signed distance of x to the solid cylinder of q moved by `shift` (< 0 inside).
double cyl_sd(const Query& q, const Vec3d& x, const Vec3d& shift = Vec3d::Zero()) {
  return test::cylinder_sd(q.p + shift, q.R, q.rc, q.h, x);
}

Vec3d cyl_closest(const Query& q, const Vec3d& x) {
  return test::cylinder_closest(q.p, q.R, q.rc, q.h, x);
}

/// The least signed distance to the cylinder (moved by `shift`) over the box's surface:
/// per face, nested golden-section search over its two coordinates; where = the point.
double surface_minimum(const Query& q, const Vec3d& shift, Vec3d* where) {
  double best = std::numeric_limits<double>::infinity();
  for (int i = 0; i < 3; ++i)
    for (double s : {-1.0, 1.0}) {
      const int j = (i + 1) % 3, k = (i + 2) % 3;
      auto point = [&](double u, double v) {
        Vec3d l;
        l[i] = s * q.e[i], l[j] = u, l[k] = v;
        return Vec3d(q.c + q.Q * l);
      };
      auto inner = [&](double u, double* v_at) {
        return test::golden_section_min([&](double v) { return cyl_sd(q, point(u, v), shift); }, -q.e[k],
                                        q.e[k], kGoldenIters, v_at);
      };
      double u = 0, v = 0;
      const double m = test::golden_section_min(
          [&](double uu) {
            double vv;
            return inner(uu, &vv);
          },
          -q.e[j], q.e[j], kGoldenIters, &u);
      if (m < best) {
        best = m;
        inner(u, &v);
        if (where != nullptr) *where = point(u, v);
      }
    }
  return best;
}

/// > 0: the distance between the box and the cylinder moved by `shift` (where = the
/// box's closest point); <= 0: they meet (the value is then only an upper bound of the
/// least signed distance over the box).
double gap(const Query& q, const Vec3d& shift = Vec3d::Zero(), Vec3d* where = nullptr) {
  const double m = surface_minimum(q, shift, where);
  if (m > 0 && box_sd(q, q.p + shift) < 0) return -std::min(q.rc, q.h);  // the cylinder inside the box
  return m;
}

nref::Shape box_shape(const Query& q) {
  return test::posed_shape(kLeafBox, q.c, q.Q, q.e);
}
nref::Shape cylinder_shape(const Query& q) {
  return test::posed_shape(kLeafCylinder, q.p, q.R, Vec3d(q.rc, q.h, 0));
}

/// The support overlap of A and B along n.
double overlap_along(const Query& q, const Vec3d& n) {
  return nref::overlap(box_shape(q), cylinder_shape(q), v3(n.normalized()));
}

/// Whether n_ref is the only minimiser within 0.02 rad: every direction outside that
/// cone overlaps by more than depth + 2 tol (nref's second best, a dense ring at 0.02 rad,
/// and the great circles where whole circles of minima occur: the cylinder's horizontal
/// one, those perpendicular to each box axis), and the overlap rises by >= 1e-6 L at
/// 3e-3 rad from n_ref in every direction (its flat valleys); *rise: that least rise.
bool unique_minimum(const Query& q, const Vec3d& n_ref, double depth, double second, double tol,
                    double* rise) {
  const nref::Shape sa = box_shape(q), sb = cylinder_shape(q);
  auto o = [&](const Vec3d& n) { return nref::overlap(sa, sb, v3(n.normalized())); };
  const test::GreatCircles circles{
      {q.R.col(2).normalized(), q.Q.col(0).normalized(), q.Q.col(1).normalized(), q.Q.col(2).normalized()}};
  return test::unique_minimum(o, n_ref, depth, second, tol, circles, 1e-6 * size_of(q), rise);
}

/// The reference (test::LaneRef): depth (> 0 penetration, else minus the distance), the
/// normal, apart (the distance in closed form), unique and, where unique, the angle a
/// normal may be off.
using Ref = test::LaneRef;

Ref reference(const Query& q) {
  Ref f;
  f.angle_tol = kAngleTol;
  Vec3d x = q.c;
  const double m = gap(q, Vec3d::Zero(), &x);
  const double tol = kRel * size_of(q);
  if (m > 0) {
    f.apart = true;
    f.depth = -m;
    f.n = (cyl_closest(q, x) - x).normalized();
    f.unique = m > 1e-3 * size_of(q);
    return f;
  }
  const nref::PairResult s = nref::solve_pair(box_shape(q), cylinder_shape(q), {}, nref::dense_options());
  f.depth = s.s;
  f.n = ev(s.n);
  double rise = 0;
  f.unique = s.unique(2 * tol) && unique_minimum(q, f.n, s.s, s.second, tol, &rise);
  if (f.unique) f.angle_tol = nref::valley_angle(kAngleTol, rise, 3e-3, kValleyNoise * size_of(q));
  return f;
}

// --- the per-lane check -----------------------------------------------------------------------

using Stats = test::LaneStats;

/// The pair for test::check_lanes: the references above, the gap for the translation check.
void check_all(const std::vector<Query>& qs, const char* what, Stats* out_stats = nullptr) {
  static const test::PairModel<Query> model{
      .rel = kRel,
      .reference = reference,
      .size = size_of,
      .coord_ulp = coord_ulp,
      .overlap = overlap_along,
      .sd_a = box_sd,
      .sd_b = [](const Query& q, const Vec3d& x) { return cyl_sd(q, x); },
      .apart = [](const Query& q, const Vec3d& shift) { return gap(q, shift); }};
  test::check_lanes_on_both_paths(model, qs, run, what, out_stats);
}

// --- inputs -----------------------------------------------------------------------------------

/// A random pair at size `size`, `offset` from the origin, the box centre within
/// `spread` (of the pair's reach) of the cylinder's.
Query random_query(std::mt19937& g, double size, double offset, double spread) {
  std::uniform_real_distribution<double> uni(0, 1);
  Query q;
  test::random_cylinder(g, size, offset, &q);
  q.Q = test::random_rotation(g);
  q.e = size * Vec3d(0.1 + 0.9 * uni(g), 0.1 + 0.9 * uni(g), 0.1 + 0.9 * uni(g));
  const double reach = q.e.norm() + std::hypot(q.rc, q.h);
  q.c = q.p + spread * reach * uni(g) * test::random_unit_vector(g);
  return rounded(q);
}

std::vector<Query> random_queries(std::mt19937& g, int n, double size, double offset) {
  return test::draw_cases(n, [&](int) { return random_query(g, size, offset, 1.3); });
}

/// A query in the cylinder's frame (centre 0, axis z): the box's centre c and axes Qb are
/// local; posed by a random rotation and offset.
Query posed(std::mt19937& g, const Vec3d& c, const Mat3d& Qb, const Vec3d& e, double rc, double h,
            double offset = 0.0) {
  Query q;
  q.R = test::random_rotation(g);
  q.p = Vec3d(offset, 0.3 * offset, -0.7 * offset) + Vec3d(0.25, -0.5, 0.75);
  q.c = q.p + q.R * c;
  q.Q = q.R * Qb;
  q.e = e, q.rc = rc, q.h = h;
  return rounded(q);
}

/// An axis-aligned cylinder (R = I) at p, the box at p + c: exact in float for the
/// analytic cases (dyadic values, Qb = I).
Query aligned(const Vec3d& p, const Vec3d& c, const Mat3d& Qb, const Vec3d& e, double rc, double h) {
  Query q;
  q.R = Mat3d::Identity();
  q.p = p;
  q.c = p + c;
  q.Q = Qb;
  q.e = e, q.rc = rc, q.h = h;
  return rounded(q);
}

/// A box with the edge along unit e through x0 (its midpoint) as its support along unit
/// n (n perpendicular to e): the edge's two faces at psi and pi/2 - psi from n.
void edge_box(const Vec3d& x0, const Vec3d& e, const Vec3d& n, double psi, const Vec3d& half, Vec3d* c,
              Mat3d* Qb) {
  const Vec3d w = e.cross(n);
  const Vec3d f1 = std::cos(psi) * n - std::sin(psi) * w, f2 = std::sin(psi) * n + std::cos(psi) * w;
  *Qb = columns(e, f1, f2);  // right-handed: f1 x f2 = n x w = e
  *c = x0 - half[1] * f1 - half[2] * f2;
}

/// A box with its vertex at v as its support along unit n, n at least 0.25 (in each
/// local coordinate) inside the vertex's normal cone: a pointed vertex.
void vertex_box(std::mt19937& g, const Vec3d& v, const Vec3d& n, const Vec3d& half, Vec3d* c, Mat3d* Qb) {
  Vec3d l;
  do {
    *Qb = test::random_rotation(g);
    l = Qb->transpose() * n;
  } while (l.cwiseAbs().minCoeff() < 0.25);
  const Vec3d s(l.x() > 0 ? 1 : -1, l.y() > 0 ? 1 : -1, l.z() > 0 ? 1 : -1);
  *c = v - *Qb * s.cwiseProduct(half);
}

/// Whether x lies (across the cylinder's axis) at a corner of the box's face across that
/// axis (box axes 0 and 1) inside the cap's disk, or on the rim within that face: the
/// vertices of the face clipped to the disk.
bool corner_or_rim(const Query& q, const Vec3d& x, double eps) {
  const Vec3d l = q.R.transpose() * (x - q.p);
  const double rho = std::hypot(l.x(), l.y());
  const Vec3d b = q.Q.transpose() * (x - q.c);
  const double bx = std::fabs(b.x()), by = std::fabs(b.y());
  const bool corner = std::fabs(bx - q.e.x()) <= eps && std::fabs(by - q.e.y()) <= eps && rho <= q.rc + eps;
  const bool rim = std::fabs(rho - q.rc) <= eps && bx <= q.e.x() + eps && by <= q.e.y() + eps;
  return corner || rim;
}

double spread(const test::PairResult& r) {
  double far = 0;
  for (uint32_t i = 0; i < r.count; ++i)
    for (uint32_t j = 0; j < r.count; ++j) far = std::max(far, (r.pt[i] - r.pt[j]).norm());
  return far;
}

// ---------------------------------------------------------------------------------------------

/// The references against closed forms (the point distances they use: reference_self_test):
/// a box beside the side, on the
/// cap, an edge and a vertex off a rim (apart), an edge across a rim, a level box through
/// the middle, a small box inside, the cylinder inside a big box; and nref against the
/// gap (distance and normal) on random separated lanes.
TEST(BoxCylinder, ReferenceMatchesClosedForms) {
  Query q;
  q.p = Vec3d(1, 2, 3);
  q.R = Mat3d::Identity();
  q.rc = 1.0, q.h = 2.0;
  q.c = Vec3d(-1, 0.5, 2);
  q.Q = Mat3d::Identity();
  q.e = Vec3d(0.5, 1, 2);
  struct Case {
    Vec3d c, e;
    Mat3d Q;
    double depth;
    Vec3d n;
  };
  const Mat3d I = Mat3d::Identity();
  const Vec3d m = Vec3d(0.6, 0, 0.8);  // a direction in the rim (1, 0, 2)'s normal cone
  const Mat3d diag = turn_to(Vec3d(1, 1, 1), m);
  const Vec3d diag_vertex = Vec3d(1, 0, 2) + 0.25 * m;
  // an edge across the rim (1, 0, 2), 0.1 inside along -(1, 0, 1)/sqrt 2
  const Vec3d nd = -Vec3d(1, 0, 1).normalized();
  Vec3d edge_c;
  Mat3d edge_Q;
  edge_box(Vec3d(1, 0, 2) + 0.1 * nd, Vec3d(-1, 0, 1).normalized(), nd, M_PI / 4, Vec3d(1, 0.5, 0.5), &edge_c,
           &edge_Q);
  const Case cases[] = {
      {Vec3d(1.4, 0, 0.3), Vec3d(0.5, 0.5, 0.5), I, 0.1, Vec3d(-1, 0, 0)},    // beside the side
      {Vec3d(0.2, 0.1, 2.4), Vec3d(0.3, 0.3, 0.5), I, 0.1, Vec3d(0, 0, -1)},  // on the cap
      {Vec3d(1.8, 0, 2.9), Vec3d(0.5, 0.5, 0.5), I, -0.5, -m},                // an edge off the rim
      {diag_vertex + 0.5 * std::sqrt(3.0) * m, Vec3d(0.5, 0.5, 0.5), diag, -0.25, -m},  // a vertex off it
      {edge_c, Vec3d(1, 0.5, 0.5), edge_Q, 0.1, nd},                          // an edge across it
      {Vec3d(0, 0.1, 0), Vec3d(3, 0.25, 0.25), I, 1.15, Vec3d(0, -1, 0)},     // level through the middle
      {Vec3d(0.3, 0, 0), Vec3d(0.1, 0.1, 0.1), I, 0.8, Vec3d(-1, 0, 0)},      // small, inside
      {Vec3d(-0.5, 0, 0), Vec3d(3, 3, 3), I, 3.5, Vec3d(1, 0, 0)},            // the cylinder inside
  };
  for (const Case& cs : cases) {
    Query w = q;
    w.c = q.p + cs.c, w.e = cs.e, w.Q = cs.Q;
    const Ref f = reference(w);
    EXPECT_NEAR(f.depth, cs.depth, 1e-9) << cs.c.transpose();
    EXPECT_TRUE(f.unique) << cs.c.transpose();
    EXPECT_LT(angle(f.n, cs.n), 1e-6) << cs.c.transpose() << " n " << f.n.transpose();
  }
  // ties: a long box along the axis (4 horizontal directions), coincident centres
  {
    Query w = q;
    w.c = q.p, w.e = Vec3d(0.25, 0.25, 3), w.Q = I;
    const Ref f = reference(w);
    EXPECT_NEAR(f.depth, 1.25, 1e-9);
    EXPECT_FALSE(f.unique);
  }
  // nref against the gap where the two are apart
  std::mt19937 g(5);
  int compared = 0;
  for (int i = 0; i < 60; ++i) {
    const Query w = random_query(g, 1.0, 0.0, 1.1);
    Vec3d x;
    const double d = gap(w, Vec3d::Zero(), &x);
    if (d <= 1e-3) continue;
    const nref::PairResult s = nref::solve_pair(box_shape(w), cylinder_shape(w), {}, nref::dense_options());
    // (the float-rounded rotations are orthonormal to ~1e-8: the point distances read
    // all of R and Q, nref's cylinder only the axis)
    EXPECT_NEAR(s.s, -d, 1e-7) << i;
    EXPECT_LT(angle(ev(s.n), cyl_closest(w, x) - x), 1e-5) << i;
    ++compared;
  }
  EXPECT_GT(compared, 10);
}

class BoxCylinderScales : public ::testing::TestWithParam<std::tuple<double, double>> {};

TEST_P(BoxCylinderScales, RandomPosesAgainstReference) {
  const auto [size, offset] = GetParam();
  const int n = static_cast<int>(test::scaled(offset == 0 && size == 1.0 ? 300 : 200));
  test::random_pose_suite(test::scale_seed(17, size, offset), n, size, offset, random_queries, check_all,
                          {.max_hit_tenths = 9, .normals_div = 2});
}

INSTANTIATE_TEST_SUITE_P(Scales, BoxCylinderScales, ::testing::ValuesIn(test::kernel_scales()));

TEST(BoxCylinder, DeepBoxes) {
  std::mt19937 g(29);
  std::uniform_real_distribution<double> uni(-1, 1);
  std::vector<Query> qs;
  const int n = static_cast<int>(test::scaled(16));
  for (int i = 0; i < n; ++i) {
    const double rc = 0.3 + 0.7 * std::fabs(uni(g)), h = 0.3 + 0.7 * std::fabs(uni(g));
    const Vec3d e(0.1 + 0.5 * std::fabs(uni(g)), 0.1 + 0.5 * std::fabs(uni(g)), 0.1 + 0.5 * std::fabs(uni(g)));
    // a long box through the middle, any direction
    qs.push_back(posed(g, 0.05 * Vec3d(uni(g), uni(g), uni(g)), test::random_rotation(g),
                       Vec3d(1.5 + std::fabs(uni(g)), 0.05 + 0.3 * std::fabs(uni(g)), 0.05 + 0.3 * std::fabs(uni(g))),
                       rc, h));
    // coincident centres
    Query c = posed(g, Vec3d::Zero(), test::random_rotation(g), e, rc, h);
    c.c = c.p;
    qs.push_back(c);
    // a box wholly inside
    const double s = 0.25 * std::min(rc, h);
    qs.push_back(posed(g, Vec3d(0.3 * rc * uni(g), 0.3 * rc * uni(g), 0.3 * h * uni(g)), test::random_rotation(g),
                       s * Vec3d(0.3 + 0.7 * std::fabs(uni(g)), 0.3 + 0.7 * std::fabs(uni(g)), 1.0), rc, h));
    // the cylinder wholly inside a big box
    const double big = 1.2 * std::hypot(rc, h);
    qs.push_back(posed(g, 0.2 * Vec3d(uni(g), uni(g), uni(g)), test::random_rotation(g),
                       big * Vec3d(1 + std::fabs(uni(g)), 1 + std::fabs(uni(g)), 1 + std::fabs(uni(g))), rc, h));
    // a box centred near a rim: the offset (|.| <= 0.05 sqrt 3 < 0.1 <= every half
    // extent) keeps the rim point inside the box, so the pair meets
    const double a = M_PI * uni(g);
    const Vec3d rim = rc * radial(a) + Vec3d(0, 0, h * (uni(g) > 0 ? 1 : -1));
    qs.push_back(posed(g, rim + 0.05 * Vec3d(uni(g), uni(g), uni(g)), test::random_rotation(g), e, rc, h));
  }
  Stats st;
  check_all(qs, "deep", &st);
  EXPECT_EQ(st.hits, static_cast<int>(qs.size()));
  EXPECT_GT(st.normals_checked, st.hits / 3);
}

/// Feature pairs built in closed form (the cylinder's frame, then posed): the box's
/// feature at `delta` along the built normal n past the cylinder's (delta < 0: apart).
enum class Feature { kEdgeRim, kVertexRim, kEdgeSide, kVertexSide, kFaceRim, kVertexCap };

struct Built {
  Query q;
  double delta;  // > 0: overlap along n; < 0: minus the distance
  Vec3d n;       // world, from the box to the cylinder
};

Built build(Feature f, std::mt19937& g, int i, double gap_scale = 1.0) {
  std::uniform_real_distribution<double> uni(-1, 1);
  const double rc = 0.3 + 0.7 * std::fabs(uni(g)), h = 0.3 + 0.7 * std::fabs(uni(g));
  const double a = M_PI * uni(g), s = uni(g) > 0 ? 1.0 : -1.0;
  const double delta = (i % 3 == 0 ? -1.0 : 1.0) * gap_scale * (0.01 + 0.09 * std::fabs(uni(g)));
  const Vec3d rim = rc * radial(a) + s * h * Vec3d::UnitZ();
  const double phi = 0.3 + 0.97 * std::fabs(uni(g));
  const Vec3d m = std::cos(phi) * radial(a) + std::sin(phi) * s * Vec3d::UnitZ();  // the rim's outward normal
  const Vec3d side = rc * radial(a) + 0.5 * h * uni(g) * Vec3d::UnitZ();
  const double psi = 0.3 + 0.97 * std::fabs(uni(g));
  // (every feature sets them; zero for the compiler, which cannot see the switch is total)
  Vec3d c = Vec3d::Zero(), n = Vec3d::Zero(), x0 = Vec3d::Zero();
  Mat3d Qb = Mat3d::Identity();
  Vec3d half(0.5 + 0.7 * std::fabs(uni(g)), 0.1 + 0.4 * std::fabs(uni(g)), 0.1 + 0.4 * std::fabs(uni(g)));
  switch (f) {
    case Feature::kEdgeRim: {
      n = -m;
      const double al = uni(g);
      const Vec3d e = std::cos(al) * m.cross(tangential(a)).normalized() + std::sin(al) * tangential(a);
      edge_box(rim + delta * n, e, n, psi, half, &c, &Qb);
      break;
    }
    case Feature::kEdgeSide: {
      n = -radial(a);
      const double al = i % 5 == 1 ? 0.0 : 1.3 * uni(g);  // some exactly level
      const Vec3d e = std::cos(al) * tangential(a) + std::sin(al) * Vec3d::UnitZ();
      half[0] = 0.2 + 0.5 * std::fabs(uni(g));
      edge_box(side + delta * n, e, n, psi, half, &c, &Qb);
      break;
    }
    case Feature::kVertexRim:
    case Feature::kVertexSide:
    case Feature::kVertexCap: {
      const Vec3d cap = 0.7 * rc * std::fabs(uni(g)) * radial(a) + s * h * Vec3d::UnitZ();
      n = f == Feature::kVertexRim ? -m : (f == Feature::kVertexSide ? -radial(a) : Vec3d(0, 0, -s));
      x0 = (f == Feature::kVertexRim ? rim : (f == Feature::kVertexSide ? side : cap)) + delta * n;
      half = Vec3d(0.1 + 0.5 * std::fabs(uni(g)), 0.1 + 0.5 * std::fabs(uni(g)), 0.1 + 0.5 * std::fabs(uni(g)));
      if (gap_scale < 1.0) half[i % 3] *= 10.0, half[(i + 1) % 3] *= 0.2;  // needles, slabs
      vertex_box(g, x0, n, half, &c, &Qb);
      break;
    }
    case Feature::kFaceRim: {
      n = -m;
      const Vec3d t1 = rot(M_PI * uni(g), n) * n.unitOrthogonal(), t2 = n.cross(t1);
      Qb = columns(t1, t2, n);
      half = Vec3d(0.2 + 0.5 * std::fabs(uni(g)), 0.2 + 0.5 * std::fabs(uni(g)), 0.1 + 0.4 * std::fabs(uni(g)));
      c = rim + delta * n - half[2] * n + 0.5 * uni(g) * half[0] * t1 + 0.5 * uni(g) * half[1] * t2;
      break;
    }
  }
  Built b;
  b.q = posed(g, c, Qb, half, rc, h);
  b.delta = delta;
  b.n = (b.q.R * n).normalized();
  return b;
}

/// check_all on the built lanes, and the references against the construction: apart
/// lanes at exactly -delta along n (the built features are each other's closest
/// points); meeting ones at most delta (the overlap along n). Returns how many meeting
/// lanes have their minimum at the built pair (depth_ref = delta, n_ref = n).
int check_built(Feature f, uint32_t seed, const char* what, Stats* st, int* meeting_lanes,
                double gap_scale = 1.0) {
  std::mt19937 g(seed);
  // (the reference's direction from a gap of 1e-4 L is good to ~1e-3 rad)
  return test::check_built_features(
      static_cast<int>(test::scaled(48)), [&](int i) { return build(f, g, i, gap_scale); }, check_all,
      reference, what, st, meeting_lanes, 1e-4 / gap_scale);
}

/// A box edge across a rim: the minimum on the edge-rim piece of the Minkowski
/// difference (normal perpendicular to the edge and the rim's tangent).
TEST(BoxCylinder, EdgeAcrossARim) {
  test::expect_feature_pairs(
      [](Stats* s, int* m) { return check_built(Feature::kEdgeRim, 71, "edge across a rim", s, m); });
}

/// A box vertex at a rim: apart, the vertex and the rim point are the closest pair;
/// meeting, the vertex pokes past the rim (cap, side, edge and face pieces nearly tie).
TEST(BoxCylinder, VertexAtARim) {
  Stats st;
  int meeting = 0;
  check_built(Feature::kVertexRim, 73, "vertex at a rim", &st, &meeting);
  EXPECT_EQ(st.hits, meeting);
}

/// The same a hair apart or overlapping (gaps 1e-4..1e-3 of the sizes, 10-100x the
/// tolerance), with needle and slab boxes (one half extent x10, the next x0.2): the
/// point pair from the box centre starts far from the vertex, and the yes / no rests on
/// the rim pieces (the vertex-rims dropped alone, or with the point pair, this still
/// passes: the edge-rim slots show such lanes apart; the edge-rim slots dropped, it fails).
TEST(BoxCylinder, VertexAHairFromARim) {
  Stats st;
  int meeting = 0;
  check_built(Feature::kVertexRim, 74, "vertex a hair from a rim", &st, &meeting, 1e-2);
  EXPECT_EQ(st.hits, meeting);
}

/// A box edge against the side, skew to the axis (normal edge x axis), some level.
TEST(BoxCylinder, EdgeAgainstTheSide) {
  test::expect_feature_pairs(
      [](Stats* s, int* m) { return check_built(Feature::kEdgeSide, 79, "edge against the side", s, m); });
}

/// A box vertex against the side (normal radial through the vertex).
TEST(BoxCylinder, VertexAgainstTheSide) {
  test::expect_feature_pairs([](Stats* s, int* m) {
    return check_built(Feature::kVertexSide, 83, "vertex against the side", s, m);
  });
}

/// A box face against a rim (the face's normal), and a box vertex into a cap.
TEST(BoxCylinder, FaceAgainstARimAndVertexIntoACap) {
  test::expect_feature_pairs(
      [](Stats* s, int* m) { return check_built(Feature::kFaceRim, 89, "face against a rim", s, m); });
  test::expect_feature_pairs(
      [](Stats* s, int* m) { return check_built(Feature::kVertexCap, 97, "vertex into a cap", s, m); });
}

/// The least support overlap over the closed-form directions the kernel's header lists
/// (the caps, the faces, edge x side, every vertex towards the axis and towards each
/// rim, and the direction of the point pair from three alternating nearest-point steps
/// from the box centre), each evaluated by nref: an upper bound of the least overlap.
double closed_form_least_overlap(const Query& q) {
  const Vec3d z = q.R.col(2);
  double least = std::numeric_limits<double>::infinity();
  auto take = [&](const Vec3d& n) {
    if (n.norm() > 1e-12) least = std::min(least, overlap_along(q, n));
  };
  auto local = [&](const Vec3d& x) { return Vec3d(q.R.transpose() * (x - q.p)); };
  take(z), take(-z);
  for (int i = 0; i < 3; ++i) {
    take(q.Q.col(i)), take(-q.Q.col(i));
    take(q.Q.col(i).cross(z)), take(z.cross(q.Q.col(i)));
  }
  for (int k = 0; k < 8; ++k) {
    Vec3d v = q.c;
    for (int i = 0; i < 3; ++i) v += ((k >> i) & 1 ? -q.e[i] : q.e[i]) * q.Q.col(i);
    const Vec3d l = local(v);
    const double rho = std::hypot(l.x(), l.y());
    const Vec3d r = rho > 0 ? Vec3d(l.x() / rho, l.y() / rho, 0.0) : Vec3d::UnitX();
    take(q.R * -r);
    for (double zs : {1.0, -1.0}) {
      const double radial = std::fabs(rho - q.rc), vert = std::fabs(l.z() - zs * q.h);
      take(q.R * Vec3d(-radial * r.x(), -radial * r.y(), -zs * vert));
    }
  }
  auto to_cyl = [&](const Vec3d& x) {
    const Vec3d l = local(x);
    const double rho = std::hypot(l.x(), l.y()), s = rho > q.rc ? q.rc / rho : 1.0;
    return Vec3d(q.p + q.R * Vec3d(l.x() * s, l.y() * s, std::clamp(l.z(), -q.h, q.h)));
  };
  auto to_box = [&](const Vec3d& x) {
    const Vec3d l = q.Q.transpose() * (x - q.c);
    return Vec3d(q.c + q.Q * l.cwiseMax(-q.e).cwiseMin(q.e));
  };
  Vec3d y = to_cyl(q.c), x = to_box(y);
  y = to_cyl(x), x = to_box(y), y = to_cyl(x);
  take(y - x);
  return least;
}

/// Apart pairs that only the edge-rim piece separates: a box edge D (5e-4..2e-3 of the
/// size) off a rim, in the plane normal to the rim's normal and 0.2..0.6 rad off the rim's
/// tangent, its nearer end within 0.3 D of the closest point; kept where the least
/// closed-form overlap lies in (0.05 D, 0.5 D), so no closed-form direction separates
/// them. The minimum (-D) is on that edge's and rim's slot, whose edge-to-rim lower bound
/// (at most D) may exceed every closed-form overlap: only the point pair's distance in
/// the pruning bound keeps it. Both paths count 0 (the reference: apart at the built D
/// along the built normal).
TEST(BoxCylinder, EdgeOffARimOnlyTheRimPieceSeparates) {
  std::mt19937 g(101);
  std::uniform_real_distribution<double> u01(0, 1);
  auto uni = [&](double lo, double hi) { return lo + (hi - lo) * u01(g); };
  auto logu = [&](double lo, double hi) { return lo * std::pow(hi / lo, u01(g)); };
  const int want = static_cast<int>(test::scaled(32));
  std::vector<Query> qs;
  std::vector<double> ds;
  std::vector<Vec3d> ns;
  int tries = 0;
  for (; tries < 4000 * want && static_cast<int>(qs.size()) < want; ++tries) {
    const double h = uni(0.3, 1.0), rc = h * logu(0.1, 10.0), L0 = std::hypot(rc, h);
    const double a = M_PI * uni(-1, 1), s = u01(g) < 0.5 ? 1.0 : -1.0;
    const double phi = uni(0.7, 1.1);  // the rim normal's elevation
    const Vec3d m = std::cos(phi) * radial(a) + std::sin(phi) * s * Vec3d::UnitZ();
    const Vec3d rim = rc * radial(a) + s * h * Vec3d::UnitZ();
    // the edge normal to m, at al from m x t (0.2..0.6 rad off the rim's tangent t)
    const double al = (u01(g) < 0.5 ? 1.0 : -1.0) * uni(1.0, 1.35);
    const Vec3d e = std::cos(al) * m.cross(tangential(a)).normalized() + std::sin(al) * tangential(a);
    const double psi = uni(0.3, 1.3);
    const Vec3d half = L0 * Vec3d(logu(0.05, 0.3), logu(0.05, 0.3), logu(0.05, 0.3));
    const double d = L0 * logu(5e-4, 2e-3);
    const double end = d * logu(0.01, 0.3);  // the nearer end's distance from the closest point
    Vec3d c;
    Mat3d Qb;
    edge_box(rim + d * m, e, -m, psi, half, &c, &Qb);
    c += (u01(g) < 0.5 ? 1.0 : -1.0) * (half[0] - end) * e;
    const Query q = posed(g, c, Qb, half, rc, h);
    const double least = closed_form_least_overlap(q);
    if (!(least > 0.05 * d && least < 0.5 * d)) continue;
    qs.push_back(q);
    ds.push_back(d);
    ns.push_back((q.R * -m).normalized());
  }
  ASSERT_EQ(static_cast<int>(qs.size()), want) << "after " << tries << " tries";
  for (size_t k = 0; k < qs.size(); ++k) {
    const Ref r = reference(qs[k]);
    EXPECT_TRUE(r.apart) << k;
    EXPECT_NEAR(r.depth, -ds[k], 1e-6 * size_of(qs[k])) << k;
    EXPECT_LT(angle(r.n, ns[k]), 1e-5 + 2 * coord_ulp(qs[k]) / ds[k]) << k;  // the inputs' rounding over D
  }
  check_all(qs, "edge off a rim, rim piece");  // (a): count 0 on both paths
  std::printf("  %d lanes from %d tries\n", want, tries);
}

/// A box resting flat on the top cap, 0.125 deep (axis-aligned, exact), both paths: its
/// bottom face within the disk gives its 4 corners; overhanging the rim or covering the
/// disk, the points are corners inside the disk or rim points within the face.
TEST(BoxCylinder, BoxRestingOnTheCap) {
  const Vec3d p(1, -2, 0.5);
  const double rc = 0.5, h = 1.0, d = 0.125;
  struct Case {
    Vec3d off;  // the box centre across the axis
    double yaw;
    Vec3d e;
    bool within;  // the face within the disk
    bool covers;  // the face covers the disk
  };
  const Case cases[] = {
      {Vec3d(0.0625, 0.0625, 0), 0.0, Vec3d(0.25, 0.125, 0.5), true, false},
      {Vec3d(-0.125, 0, 0), 0.5, Vec3d(0.25, 0.125, 0.25), true, false},
      {Vec3d(0.25, 0, 0), 0.0, Vec3d(0.5, 0.25, 0.5), false, false},
      {Vec3d(0.125, -0.25, 0), 0.3, Vec3d(0.375, 0.375, 0.25), false, false},
      {Vec3d(0.0625, 0, 0), 0.3, Vec3d(1, 0.75, 0.5), false, true},
  };
  for (KernelPath path : {KernelPath::kSimd, KernelPath::kScalar}) {
    SCOPED_TRACE(path == KernelPath::kSimd ? "simd" : "scalar");
    for (const Case& cs : cases) {
      SCOPED_TRACE(cs.off.transpose());
      const Query q = aligned(p, cs.off + Vec3d(0, 0, h + cs.e.z() - d), rot(cs.yaw, Vec3d::UnitZ()), cs.e, rc, h);
      const auto r = run({q}, path)[0];
      if (cs.within) {
        ASSERT_EQ(r.count, 4u);
      } else {
        ASSERT_GE(r.count, 3u);
      }
      EXPECT_LT(angle(r.n, Vec3d(0, 0, -1)), 1e-6);
      EXPECT_NEAR(r.depth, d, 1e-6);
      int corners = 0;
      for (uint32_t i = 0; i < r.count; ++i) {
        EXPECT_NEAR(r.pt[i].z() - p.z(), h - d / 2, 1e-6) << i;
        EXPECT_NEAR(r.pd[i], d, 1e-6) << i;
        EXPECT_TRUE(corner_or_rim(q, r.pt[i], 1e-6)) << i << " " << (r.pt[i] - p).transpose();
        const Vec3d b = q.Q.transpose() * (r.pt[i] - q.c);
        corners |= 1 << ((b.x() > 0 ? 1 : 0) + 2 * (b.y() > 0 ? 1 : 0));
      }
      if (cs.within) {
        EXPECT_EQ(corners & 0xf, 0xf) << "not the face's 4 corners";
      }
      if (cs.covers) {
        EXPECT_GE(spread(r), 1.7 * rc);
      }
    }
  }
}

/// The cylinder standing on a box's top face, 0.125 deep (axis-aligned, exact), both
/// paths: within the face, several rim points spanning the disk; overhanging an edge or
/// a corner, rim points within the face or face corners inside the disk.
TEST(BoxCylinder, CylinderStandingOnABoxFace) {
  const Vec3d p(-1, 0.5, 2);
  const double rc = 0.5, h = 1.0, d = 0.125;
  const Vec3d e(2, 1.5, 0.5);
  const Vec3d offs[] = {Vec3d(0.25, -0.125, 0), Vec3d(1.75, 0, 0), Vec3d(1.875, 1.375, 0)};
  for (KernelPath path : {KernelPath::kSimd, KernelPath::kScalar}) {
    SCOPED_TRACE(path == KernelPath::kSimd ? "simd" : "scalar");
    for (int c = 0; c < 3; ++c) {
      SCOPED_TRACE(c);
      // the box's top face at the cylinder's bottom cap + d
      const Query q = aligned(p, -offs[c] - Vec3d(0, 0, h - d + e.z()), Mat3d::Identity(), e, rc, h);
      const auto r = run({q}, path)[0];
      ASSERT_GE(r.count, 3u);
      EXPECT_LT(angle(r.n, Vec3d(0, 0, 1)), 1e-6);
      EXPECT_NEAR(r.depth, d, 1e-6);
      for (uint32_t i = 0; i < r.count; ++i) {
        EXPECT_NEAR(r.pt[i].z() - p.z(), -h + d / 2, 1e-6) << i;
        EXPECT_NEAR(r.pd[i], d, 1e-6) << i;
        EXPECT_TRUE(corner_or_rim(q, r.pt[i], 1e-6)) << i << " " << (r.pt[i] - p).transpose();
        if (c == 0) {
          const Vec3d l = r.pt[i] - p;
          EXPECT_NEAR(std::hypot(l.x(), l.y()), rc, 1e-6) << i;
        }
      }
      if (c == 0) {
        EXPECT_GE(spread(r), 1.7 * rc);
      }
    }
  }
}

/// The cylinder lying on a box's top face (axis along x), 0.125 deep, both paths: the
/// side line's 2 ends, clipped to the face where it is shorter.
TEST(BoxCylinder, CylinderLyingOnABoxFace) {
  const Vec3d p(2, 1, -0.5);
  const double rc = 0.5, h = 1.0, d = 0.125;
  Mat3d along_x;
  along_x << 0, 0, 1, 0, 1, 0, -1, 0, 0;  // column 2 = +x
  struct Case {
    double box_x, ex;  // the box centre's x (from the cylinder's centre), half extent along x
    double x0, x1;     // the expected ends
  };
  const Case cases[] = {{0.25, 3.0, -h, h}, {0.5, 1.0, -0.5, h}, {-0.75, 1.0, -h, 0.25}};
  for (KernelPath path : {KernelPath::kSimd, KernelPath::kScalar}) {
    SCOPED_TRACE(path == KernelPath::kSimd ? "simd" : "scalar");
    for (const Case& cs : cases) {
      SCOPED_TRACE(cs.box_x);
      Query q = aligned(p, Vec3d(cs.box_x, 0.25, -(rc - d) - 0.5), Mat3d::Identity(), Vec3d(cs.ex, 3, 0.5), rc, h);
      q.R = along_x;
      test::expect_line_contact(run({q}, path)[0], {.n = Vec3d(0, 0, 1),
                                                    .d = d,
                                                    .origin = p,
                                                    .axis = 0,
                                                    .lo = cs.x0,
                                                    .hi = cs.x1,
                                                    .at = Vec3d(0, 0.0, -rc + d / 2)});
    }
  }
}

/// Near-parallel tilts (0..1e-2 rad) of the three manifolds, posed: a box on the cap
/// (within the disk: 4 points), the cylinder standing on a large face (3-4 points),
/// lying on it (2 points).
TEST(BoxCylinder, NearParallelManifolds) {
  std::mt19937 g(37);
  std::uniform_real_distribution<double> uni(-1, 1);
  const double tilts[] = {0.0, 1e-7, 1e-5, 1e-3, 1e-2};
  std::vector<Query> on_cap, standing, lying;
  const double rc = 0.5, h = 1.0, d = 0.05;
  for (int i = 0; i < static_cast<int>(test::scaled(5)); ++i)
    for (double tilt : tilts) {
      const double a = M_PI * uni(g);
      const Mat3d tilted = rot(tilt, radial(a)) * rot(M_PI * uni(g), Vec3d::UnitZ());
      // a box on the top cap, within the disk
      const Vec3d e(0.1 + 0.15 * std::fabs(uni(g)), 0.1 + 0.15 * std::fabs(uni(g)), 0.3);
      const Vec3d foot(0.08 * uni(g), 0.08 * uni(g), h - d);
      on_cap.push_back(posed(g, foot + e.z() * tilted.col(2), tilted, e, rc, h));
      // standing on a large face below the bottom cap
      const Vec3d big(2, 2, 0.5);
      const Vec3d top(0.2 * uni(g), 0.2 * uni(g), -h + d);
      standing.push_back(posed(g, top - big.z() * tilted.col(2), tilted, big, rc, h));
      // lying on a large face beside the side (its normal tilted from -radial about the
      // tangent: the side line's ends at depths d +- tilt h)
      const Vec3d f = -(rot(tilt, tangential(a)) * radial(a));
      const Vec3d t1 = rot(M_PI * uni(g), f) * f.unitOrthogonal();
      const Vec3d foot2 = (rc - d) * radial(a) + 0.2 * uni(g) * Vec3d::UnitZ();
      lying.push_back(posed(g, foot2 - big.z() * f, columns(t1, f.cross(t1), f), big, rc, h));
    }
  Stats st;
  check_all(on_cap, "box on the cap", &st);
  EXPECT_EQ(st.hits, static_cast<int>(on_cap.size()));
  EXPECT_GE(st.counts[4], st.hits * 9 / 10);
  check_all(standing, "standing on a face", &st);
  EXPECT_EQ(st.hits, static_cast<int>(standing.size()));
  EXPECT_GE(st.counts[3] + st.counts[4], st.hits * 9 / 10);
  check_all(lying, "lying on a face", &st);
  EXPECT_EQ(st.hits, static_cast<int>(lying.size()));
  EXPECT_EQ(st.counts[2], st.hits);
}

/// Exactly touching (representable) configurations: count 0; B moved onto touching by
/// the reference's depth along its normal: depth within tol.
TEST(BoxCylinder, Touching) {
  const Vec3d p(4, 5, -6);
  const double rc = 0.5, h = 1.0;
  const Mat3d I = Mat3d::Identity();
  for (KernelPath path : {KernelPath::kSimd, KernelPath::kScalar}) {
    // a box face on the cap's plane
    EXPECT_EQ(run({aligned(p, Vec3d(0.125, 0, h + 0.25), I, Vec3d(0.25, 0.25, 0.25), rc, h)}, path)[0].count, 0u);
    // a box face on the side's tangent plane
    EXPECT_EQ(run({aligned(p, Vec3d(rc + 0.25, 0, 0.25), I, Vec3d(0.25, 0.25, 0.25), rc, h)}, path)[0].count, 0u);
    // a box edge on the rim's tangent line
    EXPECT_EQ(run({aligned(p, Vec3d(rc + 0.5, 0, h + 0.5), I, Vec3d(0.5, 0.5, 0.5), rc, h)}, path)[0].count, 0u);
    // a box vertex on the rim
    EXPECT_EQ(run({aligned(p, Vec3d(rc + 0.5, 0.5, h + 0.5), I, Vec3d(0.5, 0.5, 0.5), rc, h)}, path)[0].count, 0u);
    // a box vertex on the cap, the box standing on it on that vertex (a diagonal
    // vertical): touching up to the rounding of Q and c
    {
      const Mat3d diag = turn_to(Vec3d(1, 1, 1), Vec3d(0, 0, 1));
      const Query q = aligned(p, Vec3d(0.125, 0, h) + diag * Vec3d(0.25, 0.25, 0.25), diag,
                              Vec3d(0.25, 0.25, 0.25), rc, h);
      const auto r = run({q}, path)[0];
      if (r.count > 0) {
        EXPECT_LE(r.depth, 4 * kRel * size_of(q));
      }
    }
  }
  std::mt19937 g(43);
  test::expect_touching_after_push(
      g, static_cast<int>(test::scaled(40)), 400,
      [](std::mt19937& gg) { return random_query(gg, 1.0, 0.0, 0.5); }, reference, test::move_cylinder<Query>,
      [](const std::vector<Query>& qs) { return run(qs, KernelPath::kSimd); }, size_of, kRel);
}

/// Needles and pancakes (1e-4 proportions) of both shapes: boxes 1 x 1e-4 x 1e-4 and
/// 1 x 1 x 1e-4, cylinders of radius 1e-4 h and of half length 1e-4 rc.
TEST(BoxCylinder, NeedlesAndPancakes) {
  std::mt19937 g(53);
  const int n = static_cast<int>(test::scaled(48));
  const std::vector<Query> qs = test::draw_cases(n, [&](int i) {
    Query q = random_query(g, 1.0, 0.0, 0.0);
    switch (i % 4) {
      case 0:
        q.e = Vec3d(q.e.x(), 1e-4 * q.e.x(), 1e-4 * q.e.x());
        break;  // needle box
      case 1:
        q.e = Vec3d(q.e.x(), q.e.y(), 1e-4 * std::max(q.e.x(), q.e.y()));
        break;  // pancake box
      case 2:
        q.rc = 1e-4 * q.h;
        break;  // needle cylinder
      default:
        q.h = 1e-4 * q.rc;
        break;  // pancake cylinder (a disk)
    }
    const double reach = q.e.norm() + std::hypot(q.rc, q.h);
    q.c = q.p + 0.3 * reach * test::random_unit_vector(g);
    return rounded(q);
  });
  test::expect_thin_pairs_meet(qs, check_all);
}

/// Symmetries: turning and moving the whole pair turns the normal and keeps the depth;
/// the cylinder's axis reversed (R's columns 0 and 2 negated) and the box's axes
/// relabelled (cycled, two negated) are the same solids: the same answer within tol.
TEST(BoxCylinder, Symmetries) {
  std::mt19937 g(59);
  std::vector<Query> base, turned, flipped, relabelled;
  std::vector<Mat3d> turns;
  for (int i = 0; i < static_cast<int>(test::scaled(100)); ++i) {
    const Query q = random_query(g, 1.0, 0.0, 0.7);
    base.push_back(q);
    const Mat3d turn = test::random_rotation(g);
    const Vec3d move = test::random_unit_vector(g);
    Query t = q;
    t.c = test::round_to_float(Vec3d(turn * q.c + move));
    t.p = test::round_to_float(Vec3d(turn * q.p + move));
    t.Q = test::round_to_float(Mat3d(turn * q.Q));
    t.R = test::round_to_float(Mat3d(turn * q.R));
    turned.push_back(t);
    turns.push_back(turn);
    Query f = q;
    f.R.col(0) = -q.R.col(0);
    f.R.col(2) = -q.R.col(2);
    flipped.push_back(f);
    Query r = q;
    r.Q = columns(-q.Q.col(1), -q.Q.col(2), q.Q.col(0));
    r.e = Vec3d(q.e.y(), q.e.z(), q.e.x());
    relabelled.push_back(r);
  }
  test::expect_symmetric(run(base, KernelPath::kSimd),
                         {{run(turned, KernelPath::kSimd), 2, [&](size_t k) { return turns[k]; }},
                          {run(flipped, KernelPath::kSimd)},
                          {run(relabelled, KernelPath::kSimd)}},
                         kAngleTol, [&](size_t k) {
                           const Ref f = reference(base[k]);
                           return test::SymmetryLane{kRel * size_of(base[k]), f.depth, f.unique};
                         });
}

}  // namespace
}  // namespace impact::kernels
