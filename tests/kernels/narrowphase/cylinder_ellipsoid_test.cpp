// collide_cylinder_ellipsoid (kernels/narrowphase/pairs/cylinder/cylinder_ellipsoid.cpp) on both paths
// against independent double-precision references.
//
// References (double, the inputs rounded to float as the kernel sees them; nothing of
// the kernel's candidate scheme):
//  - the signed distance of a point to the solid cylinder in closed form (its own frame:
//    the radial and axial excess; inside, minus the nearer of side and caps), and to the
//    ellipsoid by bisection of the secular equation (tests/support/ellipsoid_reference.h);
//  - the solid minimum: the least signed distance to the cylinder A over the solid
//    ellipsoid B, written as B's centre plus R diag(e) w over the unit ball of w, by
//    nested golden-section search over w's third coordinate, then its first across the
//    disk of that height, then its second along the chord (the signed distance to a
//    convex set is convex, the ball is convex and the map affine, so every partial
//    minimum is convex in the coordinates left). It is > 0 iff the two are apart, and
//    then their distance; no surface pieces, no inside-the-other special case;
//  - apart: depth_ref = -that distance, normal from A's point nearest B's minimiser to it;
//  - meeting: depth_ref = the least support overlap o(n) = h_A(n) + h_B(-n) - n.(p_B - p_A)
//    over unit n: dense sampling (6000 Fibonacci directions plus dense great circles
//    perpendicular to the cylinder's axis and to each ellipsoid axis, rings at 1e-4..0.15
//    rad around +-u, the axes and their crosses) refined by Nelder-Mead
//    (tests/support/narrow_reference.h); the great circle perpendicular to u, where
//    h_A has its kink, also minimised in 1-D (golden-section at its sampled local minima,
//    then Nelder-Mead off it), and o(+-u) (h_A's cone points) taken exactly. Where the
//    kernel's own normal scores lower in double, the reference is refined from there
//    (counted and printed as "ref improved": none so far);
//  - the translation check, with the solid minimum alone: B moved by n (depth + d) is
//    apart by d within [-2 tol, +2 tol], and moved by n (depth - d) still meets A.
// The references are checked against closed forms and each other first
// (ReferenceMatchesClosedForms: point distances to the ellipsoid; a cap on an ellipsoid's pole, a side on
// an axis end, an axis end into the side, an ellipsoid on a rim at 53 degrees, apart and
// meeting; spheres against rho - sd_A(centre); a cigar through the cylinder; a tie) and
// on random, ring, needle / pancake, deep and near-parallel lanes (ReferencesAgree:
// apart, the overlap minimum against minus the solid distance and their normals;
// meeting, the translation certificate: B moved by n_ref (depth_ref + eps) is apart by
// exactly eps iff depth_ref is the global minimum; measured within 5e-8 L and 9e-8 L,
// asserted 2e-7 L, the closed forms within 1e-9);
// every feature scenario against its construction (apart: the built points are each
// other's closest points, at the built distance; meeting: the overlap along the built
// normal is the built depth, an upper bound).
// Per lane, L = the larger bounding radius of the two (sqrt(r^2 + h^2), the largest
// radius), tol = kRel L:
//  (a) count > 0 iff depth_ref > 0 (either answer where |depth_ref| <= tol), count <= 1;
//  (b) |depth - depth_ref| <= tol;
//  (c) n finite and unit; as good a direction as the reference's (the support overlap
//      along n within tol of depth_ref); angle(n, n_ref) <= kAngleTol where the minimum
//      is unique and well conditioned (no direction outside a 0.02 rad cone around n_ref
//      within 2 tol of depth_ref: the Fibonacci samples, the other local minima found, a
//      dense ring on the cone and the great circles above; and the overlap rising by
//      >= 1e-6 L at 3e-3 rad from n_ref in every direction, the ring's lowest samples
//      refined: a needle's valley is narrow);
//  (d) point[0] midway: point -+ n depth/2 on B's and A's surfaces (within tol plus
//      ulps of the largest coordinate; A's side plus 1e-6 of B's largest radius of
//      curvature e_max^2 / e_min: B's support point slides by that much per radian of
//      the normal's rounding), the support planes of A and B along n depth/2 either side
//      of it, pdepth[0] == depth;
//  (e) the scalar and SIMD paths give the same bytes (count, n, depth, point, pdepth).
// Scenarios: random poses at sizes 1, 1e-4, 1e4 and 1e5 from the origin (B at 0.6-1.4
// of an estimated touching distance along a random direction: about half meeting);
// deep (coincident centres, the ellipsoid inside the cylinder, the cylinder inside the
// ellipsoid, a long thin cylinder through a fat ellipsoid, a needle ellipsoid through a
// pancake cylinder); feature pairs built in closed form, apart and meeting: the cap face
// on the ellipsoid (normal = the axis), the side against it (normal across the axis), a
// rim against it (normal 0.3..1.27 rad from the rim's radial direction); analytic lanes
// with dyadic inputs (exact depth, normal and point, both paths; exactly touching: count
// 0 or depth <= tol); near touching (B moved along n_ref to depth_ref = +-3e-5 L and
// +-1e-3 L); near-parallel (0..1e-2 rad) pancakes on the cap and on the side, needles
// along the side and across the cap; needle and pancake cylinders and ellipsoids (aspect
// 1e4, both ways and mixed); rings (a wide flat cylinder around / over an elongated
// ellipsoid: several local minima along the rim); spheres (equal radii) against the
// closed form rho - sd_A(centre); symmetries (a rigid motion of the whole pair, the
// cylinder's axis reversed, the ellipsoid's axes permuted / negated with its radii);
// range partitions and shuffled buckets of ring and thin lanes (same bytes);
// NaN-free outputs on degenerate but valid inputs. Registration, the general
// partitions and the agreement with GJK / EPA: contract_test.cpp. A failing lane prints itself as a C++
// literal (lane(...), below). Lane counts scale with IMPACT_TEST_INTENSITY; a sanitizer build runs a quarter
// of them.
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <limits>
#include <numeric>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "kernels/narrowphase/pair_kernels.h"
#include "support/cylinder_frame.h"
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
using test::angle, test::columns, test::rot, test::radial, test::tangential, test::frame_of, test::v3,
    test::ev;

constexpr double kRel = 1e-5;       // depth tolerance, of L
constexpr double kAngleTol = 1e-3;  // rad, where the minimum is unique and conditioned
/// Golden-section steps per level of the solid minimum: brackets of 0.618^40 ~ 4e-9 of
/// the unit ball's chord.
constexpr int kGoldenIters = 40;
constexpr double kInf = std::numeric_limits<double>::infinity();

/// The solid cylinder A.
using Cyl = test::PosedCylinder;
using Piece = test::CylinderPiece;

/// The ellipsoid B.
using Ell = test::PosedSolid;

struct Query {
  Cyl a;
  Ell b;
};

/// The query as the kernel sees it: every input rounded to float.
Query rounded(Query q) {
  return {test::rounded(q.a), test::rounded(q.b)};
}

double size_of(const Query& q) {
  return std::max(std::hypot(q.a.r, q.a.h), q.b.e.maxCoeff());
}

double coord_ulp(const Query& q) {
  return test::coordinate_ulp(size_of(q), {q.a.p, q.b.p});
}

/// B's largest radius of curvature.
double curvature_radius(const Ell& b) {
  return test::eref::largest_curvature_radius(b.e);
}

/// A lane from the numbers literal() prints (rounded to float: the kernel's input).
Query lane(const std::array<double, 3>& pa, const std::array<double, 9>& ra, double r, double h,
           const std::array<double, 3>& pb, const std::array<double, 9>& rb, const std::array<double, 3>& e) {
  Query q;
  for (int i = 0; i < 3; ++i) q.a.p[i] = pa[i], q.b.p[i] = pb[i], q.b.e[i] = e[i];
  for (int i = 0; i < 9; ++i) q.a.R(i / 3, i % 3) = ra[i], q.b.R(i / 3, i % 3) = rb[i];
  q.a.r = r, q.a.h = h;
  return rounded(q);
}

/// The lane as C++ source: lane(A's centre, A's rows, r, h, B's centre, B's rows, radii)
/// (%.9g: every input is a float, so this reproduces it exactly).
std::string literal(const Query& q) {
  std::string s = "lane(";
  char buf[64];
  auto num = [&](double v, const char* sep) {
    std::snprintf(buf, sizeof buf, "%.9g%s", v, sep);
    s += buf;
  };
  auto vec = [&](const Vec3d& v, const char* tail) {
    s += "{";
    num(v[0], ", "), num(v[1], ", "), num(v[2], "}");
    s += tail;
  };
  auto mat = [&](const Mat3d& m, const char* tail) {
    s += "{";
    for (int i = 0; i < 9; ++i) num(m(i / 3, i % 3), i < 8 ? ", " : "}");
    s += tail;
  };
  vec(q.a.p, ", ");
  mat(q.a.R, ", ");
  num(q.a.r, ", ");
  num(q.a.h, ", ");
  vec(q.b.p, ", ");
  mat(q.b.R, ", ");
  vec(q.b.e, ")");
  return s;
}

// --- running the kernel -----------------------------------------------------------------------

/// The leaves as the kernel reads them (cylinder: e0 = radius, e1 = half length).
test::Leaf leaf_of(const Cyl& c) {
  return test::posed_leaf(kLeafCylinder, c.p, c.R, Vec3d(c.r, c.h, 0.0));
}
test::Leaf leaf_of(const Ell& s) {
  return test::posed_leaf(kLeafEllipsoid, s.p, s.R, s.e);
}

/// Runs `kern` (the kernel under test unless given) on lanes [begin, end) of one bucket;
/// `keep`, if given, receives the output lanes.
std::vector<test::PairResult> run(const std::vector<Query>& qs, KernelPath path, PairKernel kern = nullptr,
                                  uint32_t begin = 0, uint32_t end = ~0u,
                                  test::ManifoldLanes* keep = nullptr) {
  return test::run_queries(
      kern != nullptr ? kern : &collide_cylinder_ellipsoid, qs, path,
      [](const Query& q) {
        return std::pair{leaf_of(q.a), leaf_of(q.b)};
      },
      begin, end, keep);
}

// --- references -------------------------------------------------------------------------------

double cyl_sd(const Cyl& c, const Vec3d& x) {
  return test::cylinder_sd(c.p, c.R, c.r, c.h, x);
}

Vec3d cyl_closest(const Cyl& c, const Vec3d& x) {
  return test::cylinder_closest(c.p, c.R, c.r, c.h, x);
}

/// Signed distance of x to the ellipsoid's surface (< 0 inside), by bisection of the
/// secular equation.
double ell_sd(const Ell& b, const Vec3d& x) {
  return test::eref::signed_distance_local(b.e, b.R.transpose() * (x - b.p));
}

/// The least signed distance to A over the solid B moved by `shift`: B's point
/// p_B + shift + R_B diag(e) (u, v, t) over the unit ball, t in [-1, 1], u across the
/// disk of that height, v along the chord at u; nested golden-section search over t,
/// then u, then v. > 0: the distance between A and the moved B; <= 0: they meet (minus
/// how deep B's deepest point lies in A). where = B's point at the minimum.
double solid_minimum(const Query& q, const Vec3d& shift = Vec3d::Zero(), Vec3d* where = nullptr) {
  const Cyl& a = q.a;
  const Ell& b = q.b;
  const Mat3d m = a.R.transpose() * b.R * b.e.asDiagonal();  // B's scaled axes in A's frame
  const Vec3d o = a.R.transpose() * (b.p + shift - a.p);
  const Vec3d mu = m.col(0), mv = m.col(1), mt = m.col(2);
  auto over_v = [&](const Vec3d& base, double chord, double u, double* v_at) {
    const double w = std::sqrt(std::max(0.0, chord * chord - u * u));
    const Vec3d bu = base + u * mu;
    return test::golden_section_min([&](double v) { return test::cylinder_sd_local(bu + v * mv, a.r, a.h); },
                                    -w, w, kGoldenIters, v_at);
  };
  auto over_uv = [&](double t, double* u_at, double* v_at) {
    const Vec3d base = o + t * mt;
    const double chord = std::sqrt(std::max(0.0, 1.0 - t * t));
    double v_inner = 0;
    const double best = test::golden_section_min([&](double u) { return over_v(base, chord, u, &v_inner); },
                                                 -chord, chord, kGoldenIters, u_at);
    over_v(base, chord, *u_at, v_at);
    return best;
  };
  double t = 0, u = 0, v = 0;
  const double best = test::golden_section_min(
      [&](double tt) {
        double uu = 0, vv = 0;
        return over_uv(tt, &uu, &vv);
      },
      -1.0, 1.0, kGoldenIters, &t);
  if (where != nullptr) {
    over_uv(t, &u, &v);
    *where = b.p + shift + b.R * b.e.cwiseProduct(Vec3d(u, v, t));
  }
  return best;
}

nref::Shape cyl_shape(const Cyl& c) {
  return test::posed_shape(kLeafCylinder, c.p, c.R, Vec3d(c.r, c.h, 0));
}

nref::Shape ell_shape(const Ell& b) {
  return test::posed_shape(kLeafEllipsoid, b.p, b.R, b.e);
}

/// The support overlap of A and B along n.
double overlap_along(const Query& q, const Vec3d& n) {
  return nref::overlap(cyl_shape(q.a), ell_shape(q.b), v3(n.normalized()));
}

using Minimum = std::pair<double, Vec3d>;  // (overlap, unit direction)

/// count points of the great circle perpendicular to `axis`, from angle `phase`.
std::vector<Vec3d> great_circle(const Vec3d& axis, int count, double phase = 0.0) {
  const Vec3d a = axis.normalized(), e1 = a.unitOrthogonal(), e2 = a.cross(e1);
  std::vector<Vec3d> out;
  for (int i = 0; i < count; ++i) {
    const double t = phase + 2 * M_PI * i / count;
    out.push_back(std::cos(t) * e1 + std::sin(t) * e2);
  }
  return out;
}

/// count points of the ring at `cone` rad around the unit c.
std::vector<Vec3d> ring_around(const Vec3d& c, double cone, int count) {
  const Vec3d t1 = c.unitOrthogonal(), t2 = c.cross(t1);
  std::vector<Vec3d> out;
  for (int i = 0; i < count; ++i) {
    const double a = 2 * M_PI * i / count;
    out.push_back((c + std::tan(cone) * (std::cos(a) * t1 + std::sin(a) * t2)).normalized());
  }
  return out;
}

struct OverlapMin {
  double value = kInf;
  Vec3d n = Vec3d::UnitZ();
  std::vector<Minimum> minima;  // every local minimum found
  double nref_second = kInf;    // nref's best value outside 0.02 rad of its own minimiser
  Vec3d nref_n = Vec3d::UnitZ();
};

/// The least support overlap over unit n (see the header): nref's sampled minimiser with
/// the extra candidates, the kink circle perpendicular to u in 1-D, and o(+-u).
OverlapMin overlap_minimum(const Query& q) {
  const nref::Shape sa = cyl_shape(q.a), sb = ell_shape(q.b);
  auto f = [&](const nref::V3& n) { return nref::overlap(sa, sb, n); };
  auto fe = [&](const Vec3d& n) { return nref::overlap(sa, sb, v3(n.normalized())); };
  const Vec3d u = q.a.R.col(2).normalized();
  std::vector<nref::V3> cand;
  auto add = [&](const Vec3d& d) {
    cand.push_back(v3(d));
    cand.push_back(v3(-d));
  };
  add(u);
  for (int c = 0; c < 3; ++c) {
    add(q.b.R.col(c));
    add(u.cross(q.b.R.col(c)));
  }
  cand.push_back(v3(q.b.p - q.a.p));
  for (const Vec3d& d : great_circle(u, 720)) cand.push_back(v3(d));
  for (int c = 0; c < 3; ++c)
    for (const Vec3d& d : great_circle(q.b.R.col(c), 360, 0.004)) cand.push_back(v3(d));
  for (double s : {1.0, -1.0})
    for (double cone : {1e-4, 1e-3, 1e-2, 0.05, 0.15})
      for (const Vec3d& d : ring_around(s * u, cone, 24)) cand.push_back(v3(d));
  nref::Options opt;
  opt.samples = 6000;
  opt.starts = 8;
  const nref::SphereMin m = nref::minimise_on_sphere(f, cand, opt);
  OverlapMin out;
  out.minima.push_back({m.value, ev(m.n)});
  out.nref_second = m.second;
  out.nref_n = ev(m.n);
  // the kink circle n.u = 0 in 1-D, then off it
  const Vec3d e1 = u.unitOrthogonal(), e2 = u.cross(e1);
  auto g = [&](double t) { return fe(std::cos(t) * e1 + std::sin(t) * e2); };
  constexpr int kCircle = 1440;
  std::vector<double> gv(kCircle);
  for (int i = 0; i < kCircle; ++i) gv[static_cast<size_t>(i)] = g(2 * M_PI * i / kCircle);
  std::vector<std::pair<double, int>> local;
  for (int i = 0; i < kCircle; ++i) {
    const double prev = gv[static_cast<size_t>((i + kCircle - 1) % kCircle)];
    const double next = gv[static_cast<size_t>((i + 1) % kCircle)];
    if (gv[static_cast<size_t>(i)] <= prev && gv[static_cast<size_t>(i)] <= next)
      local.push_back({gv[static_cast<size_t>(i)], i});
  }
  std::sort(local.begin(), local.end());
  for (size_t j = 0; j < local.size() && j < 4; ++j) {
    const double t0 = 2 * M_PI * local[j].second / kCircle, step = 2 * M_PI / kCircle;
    double at = t0;
    const double v = test::golden_section_min(g, t0 - step, t0 + step, 60, &at);
    const Vec3d n = std::cos(at) * e1 + std::sin(at) * e2;
    out.minima.push_back({v, n});
    const auto off = nref::detail::refine(f, v3(n), v, 1e-3);
    out.minima.push_back({off.first, ev(off.second)});
  }
  // h_A's cone points
  out.minima.push_back({fe(u), u});
  out.minima.push_back({fe(-u), -u});
  for (const Minimum& mm : out.minima)
    if (mm.first < out.value) out.value = mm.first, out.n = mm.second;
  return out;
}

/// The least rise of the overlap over its value at n along the ring 3e-3 rad around n:
/// 64 samples, the best 4 refined by golden-section search on the ring's angle.
double ring_rise(const Query& q, const Vec3d& n) {
  const Vec3d t1 = n.unitOrthogonal(), t2 = n.cross(t1);
  const double th = std::tan(3e-3), s = overlap_along(q, n);
  auto f = [&](double a) { return overlap_along(q, n + th * (std::cos(a) * t1 + std::sin(a) * t2)) - s; };
  std::vector<std::pair<double, double>> samples;
  for (int i = 0; i < 64; ++i) samples.push_back({f(2 * M_PI * i / 64), 2 * M_PI * i / 64});
  std::partial_sort(samples.begin(), samples.begin() + 4, samples.end());
  double best = samples[0].first;
  for (int k = 0; k < 4; ++k) {
    double at = 0;
    best = std::min(
        best, test::golden_section_min(f, samples[static_cast<size_t>(k)].second - 2 * M_PI / 64,
                                       samples[static_cast<size_t>(k)].second + 2 * M_PI / 64, 40, &at));
  }
  return best;
}

/// Whether n_ref is the only minimiser within 0.02 rad and well conditioned: every
/// direction outside that cone overlaps by more than depth + 2 tol (the Fibonacci
/// samples, the other local minima found, nref's own second best, a dense ring on the
/// cone, the great circles perpendicular to u and to each ellipsoid axis, where whole
/// circles of minima and narrow valleys occur), and the overlap rises by >= 1e-6 L at
/// 3e-3 rad from n_ref in every direction.
bool unique_minimum(const Query& q, const OverlapMin& m, double tol) {
  const Vec3d& n = m.n;
  const double depth = m.value;
  double best = kInf;
  for (const Minimum& x : m.minima)
    if (angle(x.second, n) > 0.02) best = std::min(best, x.first);
  if (angle(m.nref_n, n) < 0.005) best = std::min(best, m.nref_second);
  auto probe = [&](const Vec3d& d) {
    if (angle(d, n) > 0.02) best = std::min(best, overlap_along(q, d));
  };
  for (const nref::V3& d : nref::fibonacci_sphere(6000)) probe(ev(d));
  for (const Vec3d& d : great_circle(q.a.R.col(2), 2000)) probe(d);
  for (int c = 0; c < 3; ++c)
    for (const Vec3d& d : great_circle(q.b.R.col(c), 1000)) probe(d);
  for (const Vec3d& d : ring_around(n, 0.0201, 720)) best = std::min(best, overlap_along(q, d));
  if (!(best > depth + 2 * tol)) return false;
  return ring_rise(q, n) >= 1e-6 * size_of(q);
}

struct Ref {
  double depth = 0;  // > 0: penetration depth; else minus the distance
  Vec3d n = Vec3d::UnitZ();
  bool apart = false;
  bool unique = false;  // the normal is unique and conditioned at this tolerance
  OverlapMin om;        // meeting lanes: the overlap minimum
};

Ref reference(const Query& q, bool want_unique = true) {
  Ref f;
  Vec3d x = q.b.p;
  const double m = solid_minimum(q, Vec3d::Zero(), &x);
  const double tol = kRel * size_of(q);
  if (m > 0) {
    f.apart = true;
    f.depth = -m;
    f.n = (x - cyl_closest(q.a, x)).normalized();
    f.unique = m > 1e-3 * size_of(q);
    return f;
  }
  f.om = overlap_minimum(q);
  f.depth = f.om.value;
  f.n = f.om.n;
  f.unique = want_unique && unique_minimum(q, f.om, tol);
  return f;
}

// --- the per-lane check -----------------------------------------------------------------------

/// A lane's output, for failure messages (%.9g: the floats exactly).
std::string describe(const test::PairResult& r) {
  char buf[256];
  if (r.count == 0) return "count 0";
  std::snprintf(buf, sizeof buf,
                "count %u depth %.9g n (%.9g, %.9g, %.9g) point (%.9g, %.9g, %.9g) pdepth %.9g", r.count,
                r.depth, r.n.x(), r.n.y(), r.n.z(), r.pt[0].x(), r.pt[0].y(), r.pt[0].z(), r.pd[0]);
  return buf;
}

/// (d): point[0] -+ n depth/2 on B's and A's surfaces, the support planes along n
/// depth/2 either side, pdepth == depth.
void check_point(const Query& q, const test::LaneRef&, const test::PairResult& h, double /*tol*/, double ptol,
                 const std::string& where) {
  ASSERT_TRUE(h.pt[0].allFinite()) << where;
  EXPECT_EQ(h.pd[0], h.depth) << where;
  const Vec3d n = h.n.normalized();
  const Vec3d on_a = h.pt[0] + 0.5 * h.depth * n, on_b = h.pt[0] - 0.5 * h.depth * n;
  EXPECT_LE(std::fabs(ell_sd(q.b, on_b)), ptol) << where << ": point - n depth/2 off B";
  EXPECT_LE(std::fabs(cyl_sd(q.a, on_a)), ptol + 1e-6 * curvature_radius(q.b))
      << where << ": point + n depth/2 off A";
  const double ha = nref::support(cyl_shape(q.a), v3(n)), hb = nref::support(ell_shape(q.b), v3(-n));
  EXPECT_NEAR(n.dot(on_a), ha, ptol) << where << ": not on A's support plane";
  EXPECT_NEAR(n.dot(on_b), -hb, ptol) << where << ": not on B's support plane";
}

/// Checks (a)-(e) and the translation check for every lane of qs (already rounded).
using Stats = test::LaneStats;

/// The pair for test::check_lanes: the references above, a kernel normal scoring lower in
/// double than the reference's minimum refining the reference from there (the sampling
/// missed that basin; the kernel's depth must match it), one point on both support planes
/// (check_point), and the solid minimum for the translation check (bounded on both sides).
void check_all(const std::vector<Query>& qs, const char* what, Stats* out_stats = nullptr) {
  static const test::PairModel<Query> model{
      .rel = kRel,
      .max_points = 1,
      .reference =
          [](const Query& q) {
            const Ref f = reference(q);
            test::LaneRef r{f.depth, f.n, f.unique, kAngleTol, false};
            r.apart = f.apart;
            return r;
          },
      .size = size_of,
      .coord_ulp = coord_ulp,
      .overlap = overlap_along,
      .apart = [](const Query& q, const Vec3d& shift) { return solid_minimum(q, shift); },
      .points = check_point,
      .improve =
          [](const Query& q, test::LaneRef& f, const test::PairResult& h, Stats& st) {
            if (f.apart || h.count == 0 || !h.n.allFinite() || !(h.n.norm() > 0.5)) return;
            const double ok = overlap_along(q, h.n);
            if (!(ok < f.depth - 1e-9 * size_of(q))) return;
            const nref::Shape sa = cyl_shape(q.a), sb = ell_shape(q.b);
            const auto r = nref::detail::refine([&](const nref::V3& n) { return nref::overlap(sa, sb, n); },
                                                v3(h.n.normalized()), ok, 1e-3);
            f.depth = r.first, f.n = ev(r.second), f.unique = false;
            ++st.improved;
          },
      .literal = literal,
      .apart_at_most_d = true};
  test::check_lanes_on_both_paths(
      model, qs, [](const std::vector<Query>& v, KernelPath path) { return run(v, path); }, what, out_stats);
}

// --- inputs -----------------------------------------------------------------------------------

/// Column 2 = +x: a rotation exact in float.
Mat3d along_x() {
  return columns(Vec3d(0, 0, -1), Vec3d(0, 1, 0), Vec3d(1, 0, 0));
}

/// How far each shape reaches from its centre along the unit w: to its boundary on the
/// ray (ext) and its support (sup).
double ext_of(const Cyl& c, const Vec3d& w) {
  const Vec3d u = c.R.col(2);
  return 1.0 / std::max(std::fabs(w.dot(u)) / c.h, (w - w.dot(u) * u).norm() / c.r);
}
double ext_of(const Ell& b, const Vec3d& w) {
  return 1.0 / (b.R.transpose() * w).cwiseQuotient(b.e).norm();
}
double sup_of(const Cyl& c, const Vec3d& w) {
  const Vec3d u = c.R.col(2);
  return c.h * std::fabs(w.dot(u)) + c.r * (w - w.dot(u) * u).norm();
}
double sup_of(const Ell& b, const Vec3d& w) {
  return (b.R.transpose() * w).cwiseProduct(b.e).norm();
}

/// B's centre at `t` of an estimated touching distance from A's along w: they meet for
/// t <= ext_A + ext_B and are apart beyond sup_A + sup_B; the estimate is the middle.
void place(Query& q, const Vec3d& w, double t) {
  const double touch = 0.5 * (ext_of(q.a, w) + ext_of(q.b, w) + sup_of(q.a, w) + sup_of(q.b, w));
  q.b.p = q.a.p + t * touch * w;
}

Ell random_ell(std::mt19937& g, double size) {
  std::uniform_real_distribution<double> uni(0, 1);
  Ell b;
  b.R = test::random_rotation(g);
  for (int i = 0; i < 3; ++i) b.e[i] = size * (0.1 + 0.9 * uni(g));
  return b;
}

/// A random pair at size `size`, `offset` from the origin, B at 0.6-1.4 of a touching
/// distance from A along a random direction.
Query random_query(std::mt19937& g, double size, double offset, bool round = true) {
  std::uniform_real_distribution<double> uni(0, 1);
  Query q;
  q.a = test::random_posed_cylinder(g, size);
  q.a.p = Vec3d(offset, -offset, 0.5 * offset) + size * Vec3d(uni(g) - 0.5, uni(g) - 0.5, uni(g) - 0.5);
  q.b = random_ell(g, size);
  place(q, test::random_unit_vector(g), 0.6 + 0.8 * uni(g));
  return round ? rounded(q) : q;
}

std::vector<Query> random_queries(std::mt19937& g, int n, double size, double offset) {
  return test::draw_cases(n, [&](int) { return random_query(g, size, offset); });
}

/// A query in A's frame (centre 0, axis z): B's centre and rotation are local; the pair
/// posed by a random rotation and offset.
Query posed(std::mt19937& g, double ra, double ha, const Ell& b_local, double offset = 0.0) {
  return test::posed_in_cylinder_frame<Query>(g, ra, ha, b_local, offset);
}

/// The ellipsoid of radii e whose surface holds x with outward normal m there (unit),
/// touching at its local point diag(e) w (w unit), turned by `spin` about m.
Ell ellipsoid_at(const Vec3d& x, const Vec3d& m, const Vec3d& e, const Vec3d& w, double spin) {
  const Vec3d y = e.cwiseProduct(w), m_loc = w.cwiseQuotient(e).normalized();
  Ell b;
  b.e = e;
  b.R = frame_of(m, spin) * frame_of(m_loc, 0.0).transpose();
  b.p = x - b.R * y;
  return b;
}

struct Built {
  Query q;
  double delta;  // > 0: overlap along n; < 0: minus the distance
  Vec3d n;       // world, from A to B
};

/// A pair built in A's frame: A's piece at a point xa where n is an outward normal of A,
/// B's surface at xb = xa - delta n with outward normal -n there. The planes through xa
/// and xb normal to n bound A and B, so for delta < 0 the two points are the closest
/// pair, at distance -delta; for delta > 0 the overlap along n is delta (an upper bound
/// of the depth; a stationary point of the overlap, a local minimum while delta is below
/// B's radii of curvature: delta <= 0.03 < 0.04 <= e_min^2 / e_max). Rim normals are kept
/// 0.3 rad inside the rim's normal cone, the points 0.3 of a half extent inside their
/// piece. One lane in three is apart.
Built build(Piece pa, std::mt19937& g, int i) {
  std::uniform_real_distribution<double> uni(-1, 1);
  auto mag = [&](double lo, double hi) { return lo + (hi - lo) * std::fabs(uni(g)); };
  const double ra = mag(0.3, 1.0), ha = mag(0.3, 1.0);
  const double a = M_PI * uni(g), s = uni(g) > 0 ? 1.0 : -1.0;
  const double delta = i % 3 == 0 ? -mag(0.01, 0.1) : mag(0.003, 0.03);
  const auto [xa, n] = test::cylinder_piece_point(pa, ra, ha, a, s, g);
  const Vec3d e(mag(0.2, 1.0), mag(0.2, 1.0), mag(0.2, 1.0));
  const Ell b = ellipsoid_at(xa - delta * n, -n, e, test::random_unit_vector(g), M_PI * uni(g));
  Built out;
  out.q = posed(g, ra, ha, b);
  out.delta = delta;
  out.n = (out.q.a.R * n).normalized();
  return out;
}

/// check_all on the built lanes, and the references against the construction: apart
/// lanes at exactly -delta along n (the built points are each other's closest points);
/// meeting ones at most delta (the overlap along n). Returns how many meeting lanes have
/// their minimum at the built pair (depth_ref = delta, n_ref = n).
int check_built(Piece pa, uint32_t seed, const char* what, Stats* st, int* meeting_lanes) {
  std::mt19937 g(seed);
  return test::check_built_features(
      test::scenario_lanes(64), [&](int i) { return build(pa, g, i); }, check_all,
      [](const Query& q) { return reference(q, false); }, what, st, meeting_lanes, 1e-4, literal);
}

/// An axis-aligned A (R = I, radius 0.5, half length 1) at (1, -2, 0.5), or lying along
/// x; B at A's centre + c with rotation Rb and radii e: exact in float for dyadic values.
Query aligned(const Vec3d& c, const Mat3d& Rb, const Vec3d& e, bool a_along_x = false) {
  Query q;
  q.a.p = Vec3d(1, -2, 0.5);
  q.a.R = a_along_x ? along_x() : Mat3d::Identity();
  q.a.r = 0.5, q.a.h = 1.0;
  q.b.p = q.a.p + c, q.b.R = Rb, q.b.e = e;
  return rounded(q);
}

/// A closed-form lane: the query, its depth (> 0) or minus its distance, the normal,
/// and (meeting) the midway point.
struct Analytic {
  const char* what;
  Query q;
  double depth;
  Vec3d n, pt;
};

/// Lanes whose answers are known in closed form (A at (1, -2, 0.5), r 0.5, h 1):
///  - standing on the pole: B's lowest pole 1/16 below A's top cap, inside the disk
///    with margin 0.375: depth 1/16 (the pole is 1/16 inside A, and o(z) = 1/16), n = z;
///  - lying on its side (A along x) on B's top pole, 1/32 deep: n = -z;
///  - B's -x axis end 1/8 into A's side: n = x;
///  - an ellipsoid on the rim: B's support point along -n at A's rim point (0.5, 0, 1)
///    moved 1/16 along -n, n = (0.6, 0, 0.8) (53 degrees from the radial direction);
///  - the same four apart (gaps 1/16, 1/32, 1/8, 1/16): count 0, and exactly touching.
std::vector<Analytic> analytic_lanes() {
  const Mat3d I = Mat3d::Identity();
  std::vector<Analytic> out;
  const Vec3d pa(1, -2, 0.5);
  auto add = [&](const char* what, const Query& q, double depth, const Vec3d& n, const Vec3d& pt_local) {
    out.push_back({what, q, depth, n, pa + pt_local});
  };
  const Vec3d z = Vec3d::UnitZ(), x = Vec3d::UnitX();
  add("standing on the pole", aligned(Vec3d(0.125, 0, 1.1875), I, Vec3d(0.75, 0.5, 0.25)), 0.0625, z,
      Vec3d(0.125, 0, 0.96875));
  add("lying on the pole", aligned(Vec3d(0.25, 0, -0.84375), I, Vec3d(0.25, 0.5, 0.375), true), 0.03125, -z,
      Vec3d(0.25, 0, -0.484375));
  add("axis end into the side", aligned(Vec3d(0.75, 0, 0.25), I, Vec3d(0.375, 0.25, 0.5)), 0.125, x,
      Vec3d(0.4375, 0, 0.25));
  // the rim: B axis-aligned, its support point along -n is -diag(e^2) n / |diag(e) n|
  const Vec3d e_rim(0.5, 0.25, 0.375), n_rim(0.6, 0, 0.8), rim(0.5, 0, 1);
  const Vec3d sb = -(e_rim.cwiseProduct(e_rim).cwiseProduct(n_rim)) / e_rim.cwiseProduct(n_rim).norm();
  for (double d : {0.0625, -0.0625}) {
    const Vec3d xb = rim - d * n_rim;
    add(d > 0 ? "ellipsoid on the rim" : "ellipsoid off the rim", aligned(xb - sb, I, e_rim), d, n_rim,
        xb + 0.5 * d * n_rim);
  }
  add("over the pole", aligned(Vec3d(0.125, 0, 1.3125), I, Vec3d(0.75, 0.5, 0.25)), -0.0625, z,
      Vec3d::Zero());
  add("over the pole, lying", aligned(Vec3d(0.25, 0, -0.90625), I, Vec3d(0.25, 0.5, 0.375), true), -0.03125,
      -z, Vec3d::Zero());
  add("axis end beside the side", aligned(Vec3d(1.0, 0, 0.25), I, Vec3d(0.375, 0.25, 0.5)), -0.125, x,
      Vec3d::Zero());
  add("touching the pole", aligned(Vec3d(0.125, 0, 1.25), I, Vec3d(0.75, 0.5, 0.25)), 0.0, z, Vec3d::Zero());
  add("touching the side", aligned(Vec3d(0.875, 0, 0.25), I, Vec3d(0.375, 0.25, 0.5)), 0.0, x, Vec3d::Zero());
  return out;
}

/// A sphere-shaped ellipsoid (equal radii rho) against the cylinder: depth rho - sd_A(c)
/// for its centre c (the boundary of A + ball(rho) is A's offset surface); the normal
/// from A's nearest point to c (outside), or the nearer of the side's radial direction
/// and the cap's axis (inside); unique where that is (1e-3 L margin).
struct SphereCase {
  double depth;
  Vec3d n;
  bool unique;
};

SphereCase sphere_closed_form(const Query& q) {
  const Vec3d c = q.b.p;
  const double rho = q.b.e[0];
  SphereCase s;
  const double sd = cyl_sd(q.a, c);
  s.depth = rho - sd;
  const Vec3d l = q.a.R.transpose() * (c - q.a.p);
  const double rr = std::hypot(l.x(), l.y());
  const double L = size_of(q);
  if (sd > 0) {
    s.n = (c - cyl_closest(q.a, c)).normalized();
    s.unique = sd > 1e-3 * L;
  } else {
    const double side = q.a.r - rr, cap = q.a.h - std::fabs(l.z());
    s.n = side < cap ? Vec3d(q.a.R * Vec3d(l.x(), l.y(), 0).normalized())
                     : Vec3d(q.a.R.col(2) * (l.z() < 0 ? -1.0 : 1.0));
    s.unique = std::fabs(side - cap) > 1e-3 * L && rr > 1e-3 * L && std::fabs(l.z()) > 1e-3 * L;
    if (side < cap) s.unique = s.unique && rr > 1e-2 * L;
  }
  return s;
}

std::vector<Query> sphere_queries(std::mt19937& g, int n, bool round = true) {
  std::uniform_real_distribution<double> uni(0, 1);
  const std::vector<Query> qs = test::draw_cases(n, [&](int i) {
    Query q;
    q.a = test::random_posed_cylinder(g, 1.0);
    q.a.p = Vec3d(uni(g), uni(g), uni(g)) - Vec3d::Constant(0.5);
    q.b.R = test::random_rotation(g);
    q.b.e = Vec3d::Constant(0.1 + 0.9 * uni(g));
    place(q, test::random_unit_vector(g), (i % 4 == 0 ? 0.2 : 0.6) + 0.8 * uni(g));
    return round ? rounded(q) : q;
  });
  return qs;
}

/// Wide flat cylinders (r 0.8-1.2, h 0.01-0.05) and elongated ellipsoids (1-1.3 x
/// 0.08-0.25 x 0.08-0.25), the long axis within 0.3 rad of tangent to the rim, the
/// centre 0.3-1.2 r from the axis and up to 0.35 above or below the disk: the ellipsoid
/// lies across / along / over the rim, which meets it in one or two places (several
/// local minima of the overlap along the rim).
std::vector<Query> ring_queries(std::mt19937& g, int n) {
  std::uniform_real_distribution<double> uni(-1, 1);
  auto mag = [&](double lo, double hi) { return lo + (hi - lo) * std::fabs(uni(g)); };
  const std::vector<Query> qs = test::draw_cases(n, [&](int) {
    const double ra = mag(0.8, 1.2), ha = mag(0.01, 0.05);
    const double a = M_PI * uni(g);
    Ell b;
    b.e = Vec3d(mag(0.08, 0.25), mag(0.08, 0.25), mag(1.0, 1.3));
    const Vec3d along = rot(0.3 * uni(g), radial(a)) * rot(0.3 * uni(g), Vec3d::UnitZ()) * tangential(a);
    b.R = frame_of(along.normalized(), M_PI * uni(g));
    b.p = mag(0.3, 1.2) * ra * radial(a) + 0.35 * uni(g) * Vec3d::UnitZ();
    return posed(g, ra, ha, b);
  });
  return qs;
}

/// Needles and pancakes (aspect 1e4) of either shape or both: cylinder radius 1e-4 of
/// its half length or the reverse; ellipsoid radii (1, 1e-4, 1e-4) or (1, 1, 1e-4) in
/// a random order; B at 0.2-1.2 of the touching estimate.
std::vector<Query> thin_queries(std::mt19937& g, int n) {
  std::uniform_real_distribution<double> uni(0, 1);
  const std::vector<Query> qs = test::draw_cases(n, [&](int i) {
    Query q;
    q.a = test::random_posed_cylinder(g, 1.0);
    q.b = random_ell(g, 1.0);
    const int kind = i % 8;
    const bool needle_a = kind == 0 || kind == 4 || kind == 7,
               pancake_a = kind == 1 || kind == 5 || kind == 6;
    const bool needle_b = kind == 2 || kind == 4 || kind == 6,
               pancake_b = kind == 3 || kind == 5 || kind == 7;
    if (needle_a) q.a.r = 1e-4 * q.a.h;
    if (pancake_a) q.a.h = 1e-4 * q.a.r;
    const double big = 0.3 + 0.7 * uni(g);
    const int axis = static_cast<int>(g() % 3);
    if (needle_b) q.b.e = Vec3d::Constant(1e-4 * big), q.b.e[axis] = big;
    if (pancake_b) q.b.e = Vec3d::Constant(big), q.b.e[axis] = 1e-4 * big;
    place(q, test::random_unit_vector(g), 0.2 + uni(g));
    return rounded(q);
  });
  return qs;
}

/// Deep pairs (in A's frame, posed): coincident centres; B wholly inside A; A wholly
/// inside B; a long thin A through a fat B's middle; a needle B through a pancake A.
std::vector<Query> deep_queries(std::mt19937& g, int n) {
  std::uniform_real_distribution<double> uni(-1, 1);
  auto mag = [&](double lo, double hi) { return lo + (hi - lo) * std::fabs(uni(g)); };
  std::vector<Query> qs;
  for (int i = 0; i < n; ++i) {
    const double ra = mag(0.3, 1.0), ha = mag(0.3, 1.0);
    // coincident centres
    Ell b;
    b.R = test::random_rotation(g), b.e = Vec3d(mag(0.2, 1.0), mag(0.2, 1.0), mag(0.2, 1.0));
    qs.push_back(posed(g, ra, ha, b));
    // B wholly inside A
    const double s = 0.3 * std::min(ra, ha);
    b.R = test::random_rotation(g), b.e = s * Vec3d(mag(0.3, 1.0), mag(0.3, 1.0), mag(0.3, 1.0));
    b.p = Vec3d(0.3 * ra * uni(g), 0.3 * ra * uni(g), 0.3 * ha * uni(g));
    qs.push_back(posed(g, ra, ha, b));
    // A wholly inside B (B's smallest radius beyond A's bounding radius)
    const double big = std::hypot(ra, ha);
    b.R = test::random_rotation(g), b.e = big * Vec3d(mag(1.3, 2.0), mag(1.3, 2.0), mag(1.3, 2.0));
    b.p = 0.2 * big * Vec3d(uni(g), uni(g), uni(g));
    qs.push_back(posed(g, ra, ha, b));
    // a long thin A through a fat B (A's centre near B's)
    b.R = test::random_rotation(g), b.e = Vec3d(mag(0.5, 1.0), mag(0.5, 1.0), mag(0.5, 1.0));
    b.p = 0.1 * Vec3d(uni(g), uni(g), uni(g));
    qs.push_back(posed(g, mag(0.03, 0.2), 1.5 * b.e.maxCoeff() * mag(1.0, 1.5), b));
    // a needle B through a pancake A (within 1 rad of A's axis, inside the disk)
    const double rp = mag(0.5, 1.0), hp = mag(0.01, 0.05);
    const Vec3d dir = rot(uni(g), radial(M_PI * uni(g))) * Vec3d::UnitZ();
    b.R = frame_of(dir, M_PI * uni(g)), b.e = Vec3d(mag(0.02, 0.05), mag(0.02, 0.05), mag(0.6, 1.2));
    b.p = 0.5 * rp * Vec3d(uni(g), uni(g), 0) + 0.5 * hp * uni(g) * Vec3d::UnitZ();
    qs.push_back(posed(g, rp, hp, b));
  }
  return qs;
}

/// Near-parallel contacts tilted by 0..1e-2 rad, 0.005 deep along the untilted normal:
/// a pancake ellipsoid (thin radius 0.01) flat on the top cap (within the disk or over
/// the rim) and flat against the side; a needle (thin radii 0.01) along the side and
/// lying across the cap.
std::vector<Query> near_parallel_queries(std::mt19937& g, int reps) {
  std::uniform_real_distribution<double> uni(-1, 1);
  auto mag = [&](double lo, double hi) { return lo + (hi - lo) * std::fabs(uni(g)); };
  const double tilts[] = {0.0, 1e-7, 1e-5, 1e-3, 1e-2};
  const double ra = 0.5, ha = 0.75, d = 0.005, thin = 0.01;
  std::vector<Query> qs;
  for (int i = 0; i < reps; ++i)
    for (double tilt : tilts) {
      const double a = M_PI * uni(g);
      Ell b;
      // a pancake flat on the top cap
      b.e = Vec3d(mag(0.15, 0.45), mag(0.15, 0.45), thin);
      b.R = rot(tilt, radial(M_PI * uni(g))) * rot(M_PI * uni(g), Vec3d::UnitZ());
      b.p = mag(0.0, 0.4) * radial(a) + (ha + thin - d) * Vec3d::UnitZ();
      qs.push_back(posed(g, ra, ha, b));
      // a pancake flat against the side (its thin axis radial), within the height
      b.e = Vec3d(mag(0.1, 0.3), mag(0.1, 0.5), thin);
      b.R = rot(tilt, tangential(a) + uni(g) * Vec3d::UnitZ()) * frame_of(radial(a), M_PI * uni(g));
      b.p = (ra + thin - d) * radial(a) + 0.2 * uni(g) * Vec3d::UnitZ();
      qs.push_back(posed(g, ra, ha, b));
      // a needle along the side
      b.e = Vec3d(thin, thin, mag(0.2, 0.6));
      b.R = rot(tilt, tangential(a) + uni(g) * radial(a)) * frame_of(Vec3d::UnitZ(), M_PI * uni(g));
      b.p = (ra + thin - d) * radial(a) + 0.1 * uni(g) * Vec3d::UnitZ();
      qs.push_back(posed(g, ra, ha, b));
      // a needle lying across the cap (its ends within or over the rim)
      b.e = Vec3d(thin, thin, mag(0.2, 0.7));
      b.R = rot(tilt, radial(a) + uni(g) * Vec3d::UnitZ()) * frame_of(tangential(a), M_PI * uni(g));
      b.p = mag(0.0, 0.3) * radial(a) + (ha + thin - d) * Vec3d::UnitZ();
      qs.push_back(posed(g, ra, ha, b));
    }
  return qs;
}

// ---------------------------------------------------------------------------------------------

/// The references against closed forms: point distances to the ellipsoid (the
/// cylinder's: reference_self_test); the analytic lanes (solid minimum of the apart ones, the full reference
/// of all, both the depth and the normal, unique); spheres (rho - sd_A(centre)); a cigar through the
/// cylinder, offset; a tie (coincident centres, a coaxial spheroid); the literal printer.
TEST(CylinderEllipsoid, ReferenceMatchesClosedForms) {
  Cyl c;
  c.p = Vec3d(1, 2, 3);
  c.r = 1.0, c.h = 2.0;
  {
    Ell b;
    b.p = Vec3d(-1, 0.5, 2), b.R = rot(0.7, Vec3d(1, 2, 3)), b.e = Vec3d(1, 0.5, 0.25);
    EXPECT_NEAR(ell_sd(b, b.p + b.R * Vec3d(2, 0, 0)), 1.0, 1e-14);
    EXPECT_NEAR(ell_sd(b, b.p + b.R * Vec3d(0, -0.75, 0)), 0.25, 1e-14);
    EXPECT_NEAR(ell_sd(b, b.p), -0.25, 1e-14);
    EXPECT_NEAR(ell_sd(b, b.p + b.R * Vec3d(0, 0, 0.125)), -0.125, 1e-14);
    // a sphere: |x - p| - rho
    b.e = Vec3d::Constant(0.75);
    EXPECT_NEAR(ell_sd(b, b.p + Vec3d(0.3, -0.4, 1.2)), 0.55, 1e-14);
  }
  for (const Analytic& an : analytic_lanes()) {
    SCOPED_TRACE(an.what);
    const Ref f = reference(an.q);
    // (the rim lanes' centres are rounded to float: 1e-7)
    if (an.depth < 0) {
      EXPECT_NEAR(solid_minimum(an.q), -an.depth, 1e-7);
      EXPECT_TRUE(f.apart);
    } else if (an.depth == 0) {
      EXPECT_NEAR(solid_minimum(an.q), 0.0, 1e-9);
      EXPECT_NEAR(f.depth, 0.0, 1e-9);
      continue;
    }
    EXPECT_NEAR(f.depth, an.depth, 1e-7);
    EXPECT_TRUE(f.unique);
    EXPECT_LT(angle(f.n, an.n), 1e-6) << f.n.transpose();
    if (an.depth > 0) {
      // the overlap minimum and the translation certificate agree
      EXPECT_NEAR(solid_minimum(an.q, (an.depth + 0.01) * an.n), 0.01, 1e-7);
    }
  }
  // spheres: rho - sd_A(centre), exact inputs in double
  std::mt19937 g(5);
  int meeting = 0, apart = 0;
  for (const Query& q : sphere_queries(g, 40, false)) {
    SCOPED_TRACE(literal(q));
    const SphereCase s = sphere_closed_form(q);
    if (s.depth < 0) {
      ++apart;
      EXPECT_NEAR(solid_minimum(q), -s.depth, 1e-9);
    }
    const Ref f = reference(q);
    EXPECT_NEAR(f.depth, s.depth, 1e-9);
    if (s.unique) {
      EXPECT_LT(angle(f.n, s.n), 1e-6) << f.n.transpose() << " / " << s.n.transpose();
    }
    meeting += s.depth > 0;
  }
  EXPECT_GT(meeting, 10);
  EXPECT_GT(apart, 5);
  // a cigar (0.25, 0.5, 2) along A's axis through A (r 1, h 2), centre 1/16 along x:
  // o(n) >= (1 + 0.25 - 0.0625) |n_perp| + 2 |n_z| >= 1.1875, equality only at n = x
  {
    Query q;
    q.a = c;
    q.b.p = c.p + Vec3d(0.0625, 0, 0), q.b.e = Vec3d(0.25, 0.5, 2.0);
    const Ref f = reference(q);
    EXPECT_NEAR(f.depth, 1.1875, 1e-9);
    EXPECT_LT(angle(f.n, Vec3d::UnitX()), 1e-6) << f.n.transpose();
    EXPECT_TRUE(f.unique);
    // centred: +x and -x tie
    q.b.p = c.p;
    const Ref t = reference(q);
    EXPECT_NEAR(t.depth, 1.25, 1e-9);
    EXPECT_FALSE(t.unique);
    // a coaxial spheroid: every direction across the axis ties (r + 0.5)
    q.b.e = Vec3d(0.5, 0.5, 3.0);
    const Ref s = reference(q);
    EXPECT_NEAR(s.depth, 1.5, 1e-9);
    EXPECT_FALSE(s.unique);
  }
  // the literal printer reproduces the lane
  {
    const Query q = random_query(g, 1.0, 1e5);
    const std::string s = literal(q);
    EXPECT_EQ(s.rfind("lane({", 0), 0u) << s;
    const Query back = lane({q.a.p.x(), q.a.p.y(), q.a.p.z()},
                            {q.a.R(0, 0), q.a.R(0, 1), q.a.R(0, 2), q.a.R(1, 0), q.a.R(1, 1), q.a.R(1, 2),
                             q.a.R(2, 0), q.a.R(2, 1), q.a.R(2, 2)},
                            q.a.r, q.a.h, {q.b.p.x(), q.b.p.y(), q.b.p.z()},
                            {q.b.R(0, 0), q.b.R(0, 1), q.b.R(0, 2), q.b.R(1, 0), q.b.R(1, 1), q.b.R(1, 2),
                             q.b.R(2, 0), q.b.R(2, 1), q.b.R(2, 2)},
                            {q.b.e.x(), q.b.e.y(), q.b.e.z()});
    EXPECT_EQ(literal(back), s);
    double v[31];
    ASSERT_EQ(
        std::sscanf(s.c_str(),
                    "lane({%lf, %lf, %lf}, {%lf, %lf, %lf, %lf, %lf, %lf, %lf, %lf, %lf}, %lf, %lf, {%lf, "
                    "%lf, %lf}, {%lf, %lf, %lf, %lf, %lf, %lf, %lf, %lf, %lf}, {%lf, %lf, %lf})",
                    &v[0], &v[1], &v[2], &v[3], &v[4], &v[5], &v[6], &v[7], &v[8], &v[9], &v[10], &v[11],
                    &v[12], &v[13], &v[14], &v[15], &v[16], &v[17], &v[18], &v[19], &v[20], &v[21], &v[22],
                    &v[23], &v[24], &v[25], &v[26], &v[27], &v[28]),
        29);
    // (%.9g round-trips a float, not the double holding it)
    EXPECT_EQ(test::round_to_float(v[0]), q.a.p.x());
    EXPECT_EQ(test::round_to_float(v[12]), q.a.r);
    EXPECT_EQ(test::round_to_float(v[28]), q.b.e.z());
  }
}

/// The two references against each other (the random lanes unrounded): apart,
/// the overlap minimum is minus the solid distance and its normal the closest points'
/// direction; meeting, B moved by n_ref (depth_ref + eps) is apart by exactly eps (more
/// would mean a smaller overlap elsewhere: the sampled minimum missed the global one).
TEST(CylinderEllipsoid, ReferencesAgree) {
  std::mt19937 g(7);
  std::vector<Query> qs;
  for (int i = 0; i < test::scenario_lanes(60); ++i) qs.push_back(random_query(g, 1.0, 0.0, false));
  for (const Query& q : ring_queries(g, test::scenario_lanes(24))) qs.push_back(q);
  for (const Query& q : thin_queries(g, test::scenario_lanes(24))) qs.push_back(q);
  for (const Query& q : deep_queries(g, test::scenario_lanes(4))) qs.push_back(q);
  for (const Query& q : near_parallel_queries(g, test::scenario_lanes(1))) qs.push_back(q);
  int apart = 0, meeting = 0;
  double worst_apart = 0, worst_cert = 0;
  for (size_t k = 0; k < qs.size(); ++k) {
    const Query& q = qs[k];
    SCOPED_TRACE("lane " + std::to_string(k) + " as C++: " + literal(q));
    const double L = size_of(q);
    Vec3d x;
    const double d = solid_minimum(q, Vec3d::Zero(), &x);
    const OverlapMin m = overlap_minimum(q);
    if (d > 1e-3 * L) {
      ++apart;
      worst_apart = std::max(worst_apart, std::fabs(m.value + d) / L);
      // (the float-rounded rotations are orthonormal to ~6e-8: the point distances read
      // R^T as R's inverse, the support functions R as a linear map)
      EXPECT_NEAR(m.value, -d, 2e-7 * L) << k;
      // (the golden-section minimiser is placed to ~1e-8 L, 0.618^40 of the ball's
      // chord, and the nested searches' flat directions leave a few times that: the
      // closest points' direction turns by up to that over the distance; up to 5.5e-8 L
      // / d seen at IMPACT_TEST_INTENSITY=30)
      EXPECT_LT(angle(m.n, x - cyl_closest(q.a, x)), 1e-6 + 1e-7 * L / d)
          << k << " distance " << d / L << " L";
    } else if (m.value > 1e-3 * L) {
      ++meeting;
      const double eps = 1e-3 * L;
      const double cert = solid_minimum(q, (m.value + eps) * m.n) - eps;
      worst_cert = std::max(worst_cert, std::fabs(cert) / L);
      EXPECT_NEAR(cert, 0.0, 2e-7 * L) << k << " depth_ref " << m.value;
    }
  }
  std::printf("  apart %d (worst |o_min + distance| %.2g L), meeting %d (worst certificate %.2g L)\n", apart,
              worst_apart, meeting, worst_cert);
  EXPECT_GE(apart, 4);
  EXPECT_GT(meeting, static_cast<int>(qs.size()) / 3);
}

class CylinderEllipsoidScales : public ::testing::TestWithParam<std::tuple<double, double>> {};

TEST_P(CylinderEllipsoidScales, RandomPosesAgainstReference) {
  const auto [size, offset] = GetParam();
  const int n = test::scenario_lanes(offset == 0 && size == 1.0 ? 300 : 150);
  test::random_pose_suite(test::scale_seed(21, size, offset), n, size, offset, random_queries, check_all,
                          {.max_hit_tenths = 9, .normals_div = 2});
}

INSTANTIATE_TEST_SUITE_P(Scales, CylinderEllipsoidScales, ::testing::ValuesIn(test::kernel_scales()));

/// Deep pairs: coincident centres, the ellipsoid inside the cylinder, the cylinder
/// inside the ellipsoid, a long thin cylinder through a fat ellipsoid, a needle
/// ellipsoid through a pancake cylinder.
TEST(CylinderEllipsoid, DeepPairs) {
  std::mt19937 g(29);
  const std::vector<Query> qs = deep_queries(g, test::scenario_lanes(16));
  Stats st;
  check_all(qs, "deep", &st);
  EXPECT_EQ(st.hits, static_cast<int>(qs.size()));
  EXPECT_GT(st.normals_checked, st.hits / 3);
}

/// The cap face on the ellipsoid (normal = the axis), apart and meeting.
TEST(CylinderEllipsoid, CapFaceOnTheEllipsoid) {
  test::expect_feature_pairs(
      [](Stats* s, int* m) { return check_built(Piece::kCap, 71, "cap on the ellipsoid", s, m); });
}

/// The side against the ellipsoid (normal across the axis), apart and meeting.
TEST(CylinderEllipsoid, SideAgainstTheEllipsoid) {
  test::expect_feature_pairs(
      [](Stats* s, int* m) { return check_built(Piece::kSide, 73, "side against the ellipsoid", s, m); });
}

/// A rim against the ellipsoid, the normal 0.3..1.27 rad from the rim's radial direction
/// (strictly inside the rim's normal cone), apart and meeting.
TEST(CylinderEllipsoid, RimAgainstTheEllipsoid) {
  test::expect_feature_pairs(
      [](Stats* s, int* m) { return check_built(Piece::kRim, 79, "rim against the ellipsoid", s, m); });
}

/// The analytic lanes on both paths: exact depth, normal and midway point; apart and
/// exactly touching lanes: count 0 (touching: or a depth within tol).
TEST(CylinderEllipsoid, AnalyticLanes) {
  const std::vector<Analytic> as = analytic_lanes();
  std::vector<Query> qs;
  for (const Analytic& an : as) qs.push_back(an.q);
  for (KernelPath path : {KernelPath::kSimd, KernelPath::kScalar}) {
    SCOPED_TRACE(path == KernelPath::kSimd ? "simd" : "scalar");
    const auto res = run(qs, path);
    for (size_t k = 0; k < as.size(); ++k) {
      const Analytic& an = as[k];
      SCOPED_TRACE(std::string(an.what) + " as C++: " + literal(an.q));
      const test::PairResult& r = res[k];
      const double tol = kRel * size_of(an.q);
      if (an.depth == 0) {
        if (r.count > 0) {
          EXPECT_LE(r.depth, tol);
        }
        continue;
      }
      if (an.depth < 0) {
        EXPECT_EQ(r.count, 0u);
        continue;
      }
      ASSERT_EQ(r.count, 1u);
      EXPECT_NEAR(r.depth, an.depth, tol);
      EXPECT_LT(angle(r.n, an.n), kAngleTol) << r.n.transpose();
      EXPECT_LT((r.pt[0] - an.pt).norm(), tol + 4 * coord_ulp(an.q)) << r.pt[0].transpose();
      EXPECT_EQ(r.pd[0], r.depth);
    }
  }
  Stats st;
  check_all(qs, "analytic", &st);
}

/// Near touching: random lanes with B moved along the reference normal to depth_ref =
/// +-3e-5 L (just outside the count tolerance) and +-1e-3 L.
TEST(CylinderEllipsoid, NearTouching) {
  std::mt19937 g(43);
  std::vector<Query> qs;
  const double targets[] = {3e-5, -3e-5, 1e-3, -1e-3};
  for (int i = 0;
       qs.size() < static_cast<size_t>(test::scenario_lanes(64)) && i < 20 * test::scenario_lanes(64); ++i) {
    Query q = random_query(g, 1.0, 0.0);
    const Ref f = reference(q, false);
    if (f.apart || f.depth < 1e-2 * size_of(q)) continue;
    const double target = targets[qs.size() % 4] * size_of(q);
    q.b.p = q.b.p + (f.depth - target) * f.n;
    qs.push_back(rounded(q));
  }
  Stats st;
  check_all(qs, "near touching", &st);
  EXPECT_GE(st.hits, static_cast<int>(qs.size()) / 2 - 2);
}

/// Near-parallel (0..1e-2 rad) pancakes on the cap and against the side, needles along
/// the side and across the cap: all meeting.
TEST(CylinderEllipsoid, NearParallel) {
  std::mt19937 g(37);
  const std::vector<Query> qs = near_parallel_queries(g, test::scenario_lanes(6));
  Stats st;
  check_all(qs, "near parallel", &st);
  EXPECT_EQ(st.hits, static_cast<int>(qs.size()));
}

/// Needle and pancake cylinders and ellipsoids (aspect 1e4), alone and mixed.
TEST(CylinderEllipsoid, NeedlesAndPancakes) {
  std::mt19937 g(53);
  test::expect_thin_pairs_meet(thin_queries(g, test::scenario_lanes(128)), check_all);
}

/// A wide flat cylinder around / over an elongated ellipsoid: several local minima
/// along the rim.
TEST(CylinderEllipsoid, Rings) {
  std::mt19937 g(59);
  const int n = test::scenario_lanes(128);
  Stats st;
  check_all(ring_queries(g, n), "rings", &st);
  EXPECT_GT(st.hits, n / 3);
}

/// Spheres (equal radii) against the closed form rho - sd_A(centre), and the full checks.
TEST(CylinderEllipsoid, SpheresMatchClosedForm) {
  std::mt19937 g(61);
  const std::vector<Query> qs = sphere_queries(g, test::scenario_lanes(120));
  int hits = 0, normals = 0;
  for (KernelPath path : {KernelPath::kSimd, KernelPath::kScalar}) {
    const auto res = run(qs, path);
    for (size_t k = 0; k < qs.size(); ++k) {
      SCOPED_TRACE("lane " + std::to_string(k) + " as C++: " + literal(qs[k]));
      const SphereCase s = sphere_closed_form(qs[k]);
      const double tol = kRel * size_of(qs[k]);
      if (std::fabs(s.depth) <= tol) continue;
      ASSERT_EQ(res[k].count > 0, s.depth > 0) << k << " depth " << s.depth;
      if (res[k].count == 0) continue;
      hits += path == KernelPath::kSimd;
      EXPECT_NEAR(res[k].depth, s.depth, tol) << k;
      if (s.unique) {
        normals += path == KernelPath::kSimd;
        EXPECT_LT(angle(res[k].n, s.n), kAngleTol) << k << " n " << res[k].n.transpose();
      }
    }
  }
  EXPECT_GT(hits, static_cast<int>(qs.size()) / 3);
  EXPECT_GT(normals, hits / 2);
  Stats st;
  check_all(qs, "spheres", &st);
}

/// Symmetries: a rigid motion of the whole pair turns the normal and keeps the depth;
/// the cylinder's axis reversed (R's columns 0 and 2 negated) and the ellipsoid's axes
/// permuted with its radii (cyclically; a swap with one column negated) or two of them
/// negated describe the same solids: the same answer within tol.
TEST(CylinderEllipsoid, Symmetries) {
  std::mt19937 g(67);
  std::vector<Query> base, turned, flip_a, cyc_b, swap_b, neg_b;
  std::vector<Mat3d> turns;
  for (int i = 0; i < test::scenario_lanes(100); ++i) {
    const Query q = random_query(g, 1.0, 0.0);
    base.push_back(q);
    const Mat3d turn = test::random_rotation(g);
    const Vec3d move = test::random_unit_vector(g);
    Query t = q;
    t.a.p = turn * q.a.p + move, t.a.R = turn * q.a.R;
    t.b.p = turn * q.b.p + move, t.b.R = turn * q.b.R;
    turned.push_back(rounded(t));
    turns.push_back(turn);
    Query f = q;
    f.a.R.col(0) = -q.a.R.col(0);
    f.a.R.col(2) = -q.a.R.col(2);
    flip_a.push_back(f);
    f = q;
    f.b.R = columns(q.b.R.col(1), q.b.R.col(2), q.b.R.col(0));
    f.b.e = Vec3d(q.b.e[1], q.b.e[2], q.b.e[0]);
    cyc_b.push_back(f);
    f = q;
    f.b.R = columns(q.b.R.col(1), q.b.R.col(0), -q.b.R.col(2));
    f.b.e = Vec3d(q.b.e[1], q.b.e[0], q.b.e[2]);
    swap_b.push_back(f);
    f = q;
    f.b.R = columns(-q.b.R.col(0), q.b.R.col(1), -q.b.R.col(2));
    neg_b.push_back(f);
  }
  test::expect_symmetric(run(base, KernelPath::kSimd),
                         {{run(turned, KernelPath::kSimd), 2, [&](size_t k) { return turns[k]; }},
                          {run(flip_a, KernelPath::kSimd)},
                          {run(cyc_b, KernelPath::kSimd)},
                          {run(swap_b, KernelPath::kSimd)},
                          {run(neg_b, KernelPath::kSimd)}},
                         kAngleTol, [&](size_t k) {
                           const Ref f = reference(base[k]);
                           return test::SymmetryLane{
                               kRel * size_of(base[k]), f.depth, f.unique,
                               "lane " + std::to_string(k) + " as C++: " + literal(base[k])};
                         });
}

/// Any partition of a bucket's range gives the same bytes, nothing outside the range is
/// written (the output lanes start poisoned: count 0xff, NaN floats), and a lane's bytes
/// do not depend on which lanes share its block (a shuffled bucket).
/// The ring and thin lanes (the solve's rim pieces and its flattest valleys) among random
/// ones: every split of the range and a shuffled bucket give each lane its bytes, and
/// nothing is written outside the range (the table-wide check, contract_test.cpp, draws
/// no rings).
TEST(CylinderEllipsoid, RingAndThinLanesPartitionsAndShuffle) {
  std::mt19937 g(71);
  std::vector<Query> qs = random_queries(g, 25, 1.0, 0.0);
  for (const Query& q : thin_queries(g, 8)) qs.push_back(q);
  for (const Query& q : ring_queries(g, 8)) qs.push_back(q);
  const uint32_t n = static_cast<uint32_t>(qs.size());
  for (KernelPath path : {KernelPath::kSimd, KernelPath::kScalar}) {
    int hits = 0;
    for (const test::PairResult& r : run(qs, path)) hits += r.count == 1;
    EXPECT_GT(hits, 5);
    const auto run_range = [&](const std::vector<Query>& q, uint32_t begin, uint32_t end) {
      test::ManifoldLanes o(n);
      const auto r = run(q, path, nullptr, begin, end, &o);
      for (uint32_t k = 0; k < n; ++k) {
        if (k < begin || k >= end) {
          EXPECT_TRUE(o.untouched(k)) << "lane " << k << " written outside its range";
        }
      }
      return r;
    };
    test::expect_partition_invariant(qs, {1u, 3u, 8u, 11u, 16u, 23u, n - 1}, run_range, test::same_bytes, g);
  }
}

/// Degenerate but valid inputs (every size > 0, every value finite): centres coincident,
/// on the cylinder's axis, rim and side; exactly touching; coaxial spheroids (circles of
/// tied minima); aspect 1e6 either way; sizes 1e-6 and 1e4 at 1e5 from the origin; axis-
/// aligned frames (zeros everywhere); far apart. Every output finite, n unit, pdepth ==
/// depth > 0, both paths the same bytes; each lane also in 24 random rigid motions.
TEST(CylinderEllipsoid, FiniteOutputsOnDegenerateInputs) {
  const Mat3d I = Mat3d::Identity();
  std::vector<Query> base;
  auto add = [&](const Vec3d& c, const Mat3d& Rb, const Vec3d& e, double r = 0.5, double h = 1.0,
                 const Mat3d& Ra = Mat3d::Identity()) {
    Query q;
    q.a.p = Vec3d(1, -2, 0.5), q.a.R = Ra, q.a.r = r, q.a.h = h;
    q.b.p = q.a.p + c, q.b.R = Rb, q.b.e = e;
    base.push_back(rounded(q));
  };
  add(Vec3d::Zero(), I, Vec3d(0.5, 0.5, 0.25));                  // coincident, coaxial spheroid
  add(Vec3d::Zero(), I, Vec3d(0.5, 0.5, 1.0));                   // the same sizes as A
  add(Vec3d::Zero(), I, Vec3d::Constant(0.25));                  // a sphere at the centre
  add(Vec3d::Zero(), along_x(), Vec3d(0.5, 0.5, 1.0));           // crossed, equal
  add(Vec3d(0, 0, 1.5), I, Vec3d(0.5, 0.5, 0.75));               // on the axis, over the cap
  add(Vec3d(0, 0, 1.0), I, Vec3d::Constant(0.25));               // centre on the cap's centre
  add(Vec3d(0.5, 0, 1.0), I, Vec3d(0.25, 0.125, 0.375));         // centre on the rim
  add(Vec3d(0.5, 0, 0.0), I, Vec3d(0.25, 0.125, 0.375));         // centre on the side
  add(Vec3d(0, 0, 1.25), I, Vec3d::Constant(0.25));              // touching the cap
  add(Vec3d(0.75, 0, 0), I, Vec3d::Constant(0.25));              // touching the side
  add(Vec3d(0.75, 0, 1.25), I, Vec3d::Constant(0.25));           // touching the rim's corner
  add(Vec3d(0, 0, 0.5), I, Vec3d(1.0, 1.0, 1e-6));               // a 1e-6 pancake in the middle
  add(Vec3d(0.25, 0, 0), along_x(), Vec3d(1e-6, 1e-6, 2.0));     // a 1e-6 needle through
  add(Vec3d(0.25, 0, 0), I, Vec3d(0.25, 0.5, 0.75), 1e-6, 1.0);  // a 1e-6 needle cylinder
  add(Vec3d(0.25, 0, 0), I, Vec3d(0.25, 0.5, 0.75), 1.0, 1e-6);  // a 1e-6 disk
  add(Vec3d(0, 0, 0.5), I, Vec3d(0.5, 0.5, 0.25), 0.5, 0.25, along_x());
  add(Vec3d(1e-6, 0, 0), I, Vec3d::Constant(1e-6), 1e-6, 1e-6);  // tiny
  add(Vec3d(3e6, 0, 0), I, Vec3d(0.5, 0.5, 0.25));               // far apart
  add(Vec3d(0.5, 0.5, 0.5), I, Vec3d(1e4, 1e4, 1e4));            // huge B holding A
  {
    Query q;  // 1e-6 sizes at 1e5 from the origin (the inputs' ulp is 1e-2)
    q.a.p = Vec3d(1e5, -1e5, 5e4), q.a.r = 1e-6, q.a.h = 1e-6;
    q.b.p = q.a.p, q.b.e = Vec3d::Constant(1e-6);
    base.push_back(rounded(q));
  }
  std::mt19937 g(73);
  std::vector<Query> qs = base;
  for (int rep = 0; rep < 24; ++rep)
    for (const Query& q : base) {
      const Mat3d turn = test::random_rotation(g);
      Query t = q;
      t.a.p = turn * q.a.p, t.a.R = turn * q.a.R;
      t.b.p = turn * q.b.p, t.b.R = turn * q.b.R;
      qs.push_back(rounded(t));
    }
  const auto simd = run(qs, KernelPath::kSimd), scal = run(qs, KernelPath::kScalar);
  int hits = 0;
  for (size_t k = 0; k < qs.size(); ++k) {
    SCOPED_TRACE("lane " + std::to_string(k) + " as C++: " + literal(qs[k]));
    for (const auto* r : {&simd[k], &scal[k]}) {
      ASSERT_LE(r->count, 1u) << k;
      if (r->count == 0) continue;
      hits += r == &simd[k];
      EXPECT_TRUE(r->n.allFinite() && std::isfinite(r->depth) && r->pt[0].allFinite() &&
                  std::isfinite(r->pd[0]))
          << k << " n " << r->n.transpose() << " depth " << r->depth << " pt " << r->pt[0].transpose();
      EXPECT_NEAR(r->n.norm(), 1.0, 1e-5) << k;
      EXPECT_GT(r->depth, 0.0) << k;
      EXPECT_EQ(r->pd[0], r->depth) << k;
    }
    EXPECT_TRUE(test::same_bytes(simd[k], scal[k])) << k << ": the SIMD and scalar paths differ\n simd   "
                                                    << describe(simd[k]) << "\n scalar " << describe(scal[k]);
  }
  EXPECT_GT(hits, static_cast<int>(qs.size()) / 2);
}

}  // namespace
}  // namespace impact::kernels
