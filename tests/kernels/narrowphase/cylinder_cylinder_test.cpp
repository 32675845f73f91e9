// collide_cylinder_cylinder (kernels/narrowphase/pairs/cylinder/cylinder_cylinder.cpp) on both paths
// against independent double-precision references.
//
// References (double, the inputs rounded to float as the kernel sees them; no candidate
// enumeration, no root solve by steps):
//  - the signed distance of a point to a solid cylinder in closed form (its own frame:
//    the radial and axial excess; inside, minus the nearer of side and caps);
//  - the solid minimum: the least signed distance to B over the solid A, by nested
//    golden-section search over A's axial coordinate, then a chord coordinate of its
//    disk, then the coordinate along the chord (the signed distance to a convex set is
//    convex, A's solid is convex and its parametrisation affine, so every partial
//    minimum is convex in the coordinates left). It is > 0 iff the two are apart, and
//    then their distance; no surface pieces, no inside-the-other special case;
//  - apart: depth_ref = -that distance, normal from A's point at the minimum to its
//    closest point of B (unique: the offset of two disjoint convex sets' closest points
//    is);
//  - meeting: depth_ref = the least support overlap h_A(n) + h_B(-n) over unit n by
//    dense sampling and Nelder-Mead (tests/support/narrow_reference.h);
//  - the translation check, with the solid minimum alone: B moved by n (depth + d) is
//    apart by at least d - 2 tol, and moved by n (depth - d) still meets A.
// The references are checked against closed forms and each other first
// (ReferenceMatchesClosedForms), and every feature scenario against its construction
// (apart: the built points are each other's closest points, at the built distance;
// meeting: the overlap along the built normal is the built depth, an upper bound).
// Per lane, L = the larger bounding radius sqrt(r^2 + h^2) of the two, tol = kRel L:
//  (a) count > 0 iff depth_ref > 0 (either answer where |depth_ref| <= tol), count <= 4;
//  (b) |depth - depth_ref| <= tol;
//  (c) n finite and unit; as good a direction as the reference's (the support overlap
//      along n within tol of depth_ref); angle(n, n_ref) <= kAngleTol where the minimum
//      is unique and well conditioned (no direction outside a 0.02 rad cone around
//      n_ref within 2 tol of depth_ref, by nref's own probes, a dense ring on the cone
//      and dense probes of the great circles where whole circles of minima occur: those
//      perpendicular to either axis and the one through both; and the overlap rising by
//      >= 1e-6 L at 3e-3 rad from n_ref);
//  (d) each point p with depth d: p + n d/2 on A's surface, p - n d/2 on B's (within
//      tol plus ulps of the largest coordinate), 0 < d <= depth + tol, and the deepest
//      point carries the depth (max d >= depth - tol);
//  (e) the scalar and SIMD paths give the same bytes.
// Scenarios: random poses at sizes 1, 1e-4, 1e4 and 1e5 from the origin (about half
// meeting); deep (coincident centres, one wholly inside the other, a long thin one
// through a fat one); feature pairs built in closed form, apart and meeting: cap face on
// cap face (offset disks), a rim against a cap face (both ways), the sides crossed
// (normal = the axes' cross product), a side against a rim (both ways), rim against
// rim, a side on a cap, parallel sides; manifolds (axis-aligned, exact, both paths and
// both orders): a cylinder standing on the other's cap, concentric and offset (3-4
// points in the disks' overlap, spread over it, at the built depth), lying on the cap
// (2 points: the side line clipped to the disk), side by side (2 points: the overlap of
// the heights); near-parallel tilts (0..1e-2 rad) of those; exactly touching (count 0);
// needles and pancakes (1e-4); symmetries (a rigid motion of the whole pair, A and B
// swapped, an axis reversed). Registration, range partitions, shuffled buckets and the agreement with GJK /
// EPA: contract_test.cpp (every bucket of the table). Lane counts scale with IMPACT_TEST_INTENSITY; a
// sanitizer build runs a quarter of them.
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
using test::angle, test::columns, test::rot, test::radial, test::tangential, test::frame_of, test::v3,
    test::ev;

constexpr double kRel = 1e-5;       // depth tolerance, of L
constexpr double kAngleTol = 1e-4;  // rad, where the minimum is unique and conditioned
/// Golden-section steps per level of the solid minimum: brackets of 0.618^40 ~ 4e-9 of
/// a cylinder's length or diameter.
constexpr int kGoldenIters = 40;

using Cyl = test::PosedCylinder;
using Piece = test::CylinderPiece;
using test::rounded;

struct Query {
  Cyl a, b;
};

/// The query as the kernel sees it: every input rounded to float.
Query rounded(const Query& q) {
  return {rounded(q.a), rounded(q.b)};
}

Query swapped(const Query& q) {
  return {q.b, q.a};
}

double size_of(const Query& q) {
  return std::max(std::hypot(q.a.r, q.a.h), std::hypot(q.b.r, q.b.h));
}

double coord_ulp(const Query& q) {
  return test::coordinate_ulp(size_of(q), {q.a.p, q.b.p});
}

// --- running the kernel -----------------------------------------------------------------------

/// A cylinder as the kernel reads it (e0 = radius, e1 = half length).
test::Leaf leaf_of(const Cyl& c) {
  return test::posed_leaf(kLeafCylinder, c.p, c.R, Vec3d(c.r, c.h, 0.0));
}

/// Runs the kernel under test on one bucket of qs.
std::vector<test::PairResult> run(const std::vector<Query>& qs, KernelPath path) {
  return test::run_queries(&collide_cylinder_cylinder, qs, path, [](const Query& q) {
    return std::pair{leaf_of(q.a), leaf_of(q.b)};
  });
}

// --- references -------------------------------------------------------------------------------

/// Signed distance of x to the solid cylinder c moved by `shift` (< 0 inside).
double cyl_sd(const Cyl& c, const Vec3d& x, const Vec3d& shift = Vec3d::Zero()) {
  return test::cylinder_sd(c.p + shift, c.R, c.r, c.h, x);
}

Vec3d cyl_closest(const Cyl& c, const Vec3d& x) {
  return test::cylinder_closest(c.p, c.R, c.r, c.h, x);
}

/// The least signed distance to B (moved by `shift`) over the solid A: A's point
/// (u, v, t) = p_A + R_A (u, v, t), t in [-h, h], u in [-r, r], v across the disk's chord
/// at u; nested golden-section search over t, then u, then v. > 0: the distance between
/// A and the moved B; <= 0: they meet (minus how deep A's deepest point lies in B).
/// where = A's point at the minimum.
double solid_minimum(const Query& q, const Vec3d& shift = Vec3d::Zero(), Vec3d* where = nullptr) {
  const Cyl& a = q.a;
  const Cyl& b = q.b;
  const Mat3d m = b.R.transpose() * a.R;  // A's axes in B's frame
  const Vec3d o = b.R.transpose() * (a.p - b.p - shift);
  const Vec3d mu = m.col(0), mv = m.col(1), mt = m.col(2);
  auto over_v = [&](const Vec3d& base, double u, double* v_at) {
    const double w = std::sqrt(std::max(0.0, a.r * a.r - u * u));
    const Vec3d bu = base + u * mu;
    return test::golden_section_min([&](double v) { return test::cylinder_sd_local(bu + v * mv, b.r, b.h); },
                                    -w, w, kGoldenIters, v_at);
  };
  auto over_uv = [&](double t, double* u_at, double* v_at) {
    const Vec3d base = o + t * mt;
    double v_inner = 0;
    const double best = test::golden_section_min([&](double u) { return over_v(base, u, &v_inner); }, -a.r,
                                                 a.r, kGoldenIters, u_at);
    over_v(base, *u_at, v_at);
    return best;
  };
  double t = 0, u = 0, v = 0;
  const double best = test::golden_section_min(
      [&](double tt) {
        double uu = 0, vv = 0;
        return over_uv(tt, &uu, &vv);
      },
      -a.h, a.h, kGoldenIters, &t);
  if (where != nullptr) {
    over_uv(t, &u, &v);
    *where = a.p + a.R * Vec3d(u, v, t);
  }
  return best;
}

nref::Shape shape_of(const Cyl& c) {
  return test::posed_shape(kLeafCylinder, c.p, c.R, Vec3d(c.r, c.h, 0));
}

/// The support overlap of A and B along n.
double overlap_along(const Query& q, const Vec3d& n) {
  return nref::overlap(shape_of(q.a), shape_of(q.b), v3(n.normalized()));
}

/// Whether n_ref is the only minimiser within 0.02 rad: every direction outside that
/// cone overlaps by more than depth + 2 tol (nref's second best, a dense ring at 0.02 rad,
/// and the great circles where whole circles of minima occur: those perpendicular to
/// either axis, where the side terms vanish, and the one through both axes), and the
/// overlap rises by >= 1e-6 L at 3e-3 rad from n_ref in every direction (its flat
/// valleys).
bool unique_minimum(const Query& q, const Vec3d& n_ref, double depth, double second, double tol) {
  const nref::Shape sa = shape_of(q.a), sb = shape_of(q.b);
  auto o = [&](const Vec3d& n) { return nref::overlap(sa, sb, v3(n.normalized())); };
  test::GreatCircles circles{{q.a.R.col(2), q.b.R.col(2)}};
  const Vec3d both = q.a.R.col(2).cross(q.b.R.col(2));
  if (both.norm() > 1e-6) circles.poles.push_back(both.normalized());
  return test::unique_minimum(o, n_ref, depth, second, tol, circles, 1e-6 * size_of(q));
}

/// The reference (test::LaneRef): depth (> 0 penetration, else minus the distance), the
/// normal, apart (the distance in closed form), unique and, where unique, the angle a
/// normal may be off.
using Ref = test::LaneRef;

Ref reference(const Query& q) {
  Ref f;
  f.angle_tol = kAngleTol;
  Vec3d x = q.a.p;
  const double m = solid_minimum(q, Vec3d::Zero(), &x);
  const double tol = kRel * size_of(q);
  if (m > 0) {
    f.apart = true;
    f.depth = -m;
    f.n = (cyl_closest(q.b, x) - x).normalized();
    f.unique = m > 1e-3 * size_of(q);
    return f;
  }
  const nref::PairResult s = nref::solve_pair(shape_of(q.a), shape_of(q.b), {}, nref::dense_options());
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
      .carries = test::Carries::kDeepestWithinTol,
      .reference = reference,
      .size = size_of,
      .coord_ulp = coord_ulp,
      .overlap = overlap_along,
      .sd_a = [](const Query& q, const Vec3d& x) { return cyl_sd(q.a, x); },
      .sd_b = [](const Query& q, const Vec3d& x) { return cyl_sd(q.b, x); },
      .apart = [](const Query& q, const Vec3d& shift) { return solid_minimum(q, shift); }};
  test::check_lanes_on_both_paths(model, qs, run, what, out_stats);
}

// --- inputs -----------------------------------------------------------------------------------

/// A random pair at size `size`, `offset` from the origin, A's centre within `spread`
/// (of the pair's reach) of B's.
Query random_query(std::mt19937& g, double size, double offset, double spread) {
  std::uniform_real_distribution<double> uni(0, 1);
  Query q;
  q.b = test::random_posed_cylinder(g, size);
  q.b.p = Vec3d(offset, -offset, 0.5 * offset) + size * Vec3d(uni(g) - 0.5, uni(g) - 0.5, uni(g) - 0.5);
  q.a = test::random_posed_cylinder(g, size);
  const double reach = std::hypot(q.a.r, q.a.h) + std::hypot(q.b.r, q.b.h);
  q.a.p = q.b.p + spread * reach * uni(g) * test::random_unit_vector(g);
  return rounded(q);
}

std::vector<Query> random_queries(std::mt19937& g, int n, double size, double offset) {
  return test::draw_cases(n, [&](int) { return random_query(g, size, offset, 1.4); });
}

/// A query in A's frame (centre 0, axis z): B's centre and rotation are local; the pair
/// posed by a random rotation and offset.
Query posed(std::mt19937& g, double ra, double ha, const Cyl& b_local, double offset = 0.0) {
  return test::posed_in_cylinder_frame<Query>(g, ra, ha, b_local, offset);
}

/// An axis-aligned A (R = I) at p, B at p + c with rotation Rb: exact in float for the
/// analytic cases (dyadic values, Rb a signed permutation).
Query aligned(const Vec3d& p, double ra, double ha, const Vec3d& c, const Mat3d& Rb, double rb, double hb) {
  Query q;
  q.a.p = p, q.a.r = ra, q.a.h = ha;
  q.b.p = p + c, q.b.R = Rb, q.b.r = rb, q.b.h = hb;
  return rounded(q);
}

/// Column 2 = +x, +y: rotations exact in float.
Mat3d along_x() {
  return columns(Vec3d(0, 0, -1), Vec3d(0, 1, 0), Vec3d(1, 0, 0));
}
Mat3d along_y() {
  return columns(Vec3d(0, 0, 1), Vec3d(1, 0, 0), Vec3d(0, 1, 0));
}

/// The cylinder of radius r, half length h whose top rim holds x with outward normal m
/// there, m at psi (0 < psi < pi/2) from the rim's radial direction towards its axis;
/// w (unit, perpendicular to m) picks the turn about m.
Cyl rim_at(const Vec3d& x, const Vec3d& m, double psi, const Vec3d& w, double r, double h) {
  const Vec3d u = std::sin(psi) * m - std::cos(psi) * w, out = std::cos(psi) * m + std::sin(psi) * w;
  Cyl c;
  c.R = columns(out, u.cross(out), u);
  c.p = x - r * out - h * u;
  c.r = r, c.h = h;
  return c;
}

struct Built {
  Query q;
  double delta;  // > 0: overlap along n; < 0: minus the distance
  Vec3d n;       // world, from A to B
};

/// A pair built in A's frame: A's piece at a point xa where n is an outward normal of A,
/// B's piece at xb = xa - delta n where -n is an outward normal of B. The planes through
/// xa and xb normal to n bound A and B, so for delta < 0 the two points are the closest
/// pair, at distance -delta; for delta > 0 the overlap along n is delta (an upper bound
/// of the depth). Normals are kept 0.3 rad inside the rims' normal cones, B's side 0.3
/// rad off A's axis unless `parallel`, the points 0.3 of a half extent inside their
/// piece. One lane in three is apart.
Built build(Piece pa, Piece pb, bool parallel, std::mt19937& g, int i) {
  std::uniform_real_distribution<double> uni(-1, 1);
  auto mag = [&](double lo, double hi) { return lo + (hi - lo) * std::fabs(uni(g)); };
  const double ra = mag(0.3, 1.0), ha = mag(0.3, 1.0), rb = mag(0.3, 1.0), hb = mag(0.3, 1.0);
  const double a = M_PI * uni(g), s = uni(g) > 0 ? 1.0 : -1.0;
  const double delta = (i % 3 == 0 ? -1.0 : 1.0) * mag(0.01, 0.1);
  const Vec3d z = Vec3d::UnitZ();
  const auto [xa, n] = test::cylinder_piece_point(pa, ra, ha, a, s, g);
  const Vec3d xb = xa - delta * n;
  const Vec3d w = rot(M_PI * uni(g), n) * n.unitOrthogonal();  // a random unit normal to n
  Cyl b;
  b.r = rb, b.h = hb;
  switch (pb) {
    case Piece::kCap:  // B's bottom cap (outward -u_B = -n) holds xb
      b.R = frame_of(n, M_PI * uni(g));
      b.p = xb + hb * n + 0.7 * rb * std::fabs(uni(g)) * w;
      break;
    case Piece::kRim:
      b = rim_at(xb, -n, mag(0.3, 1.27), w, rb, hb);
      break;
    case Piece::kSide: {
      Vec3d u = w;
      if (parallel) {
        u = z;
      } else if (pa == Piece::kSide) {
        const double al = 1.27 * uni(g);  // from A's tangent, >= 0.3 rad off its axis
        u = std::cos(al) * tangential(a) + std::sin(al) * z;
      }
      b.R = frame_of(u, M_PI * uni(g));
      b.p = xb + rb * n + 0.7 * hb * uni(g) * u;
      break;
    }
  }
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
int check_built(Piece pa, Piece pb, bool parallel, uint32_t seed, const char* what, Stats* st,
                int* meeting_lanes) {
  std::mt19937 g(seed);
  return test::check_built_features(
      test::scenario_lanes(48), [&](int i) { return build(pa, pb, parallel, g, i); }, check_all, reference,
      what, st, meeting_lanes);
}

double spread(const test::PairResult& r) {
  double far = 0;
  for (uint32_t i = 0; i < r.count; ++i)
    for (uint32_t j = 0; j < r.count; ++j) far = std::max(far, (r.pt[i] - r.pt[j]).norm());
  return far;
}

/// The area of the polygon of the points' xy coordinates taken in angular order about
/// their mean (the convex hull's area for points in convex position, less otherwise).
double xy_area(const test::PairResult& r) {
  Eigen::Vector2d c = Eigen::Vector2d::Zero();
  for (uint32_t i = 0; i < r.count; ++i) c += r.pt[i].head<2>() / static_cast<double>(r.count);
  std::vector<Eigen::Vector2d> ps;
  for (uint32_t i = 0; i < r.count; ++i) ps.push_back(r.pt[i].head<2>() - c);
  std::sort(ps.begin(), ps.end(), [](const Eigen::Vector2d& x, const Eigen::Vector2d& y) {
    return std::atan2(x.y(), x.x()) < std::atan2(y.y(), y.x());
  });
  double area = 0;
  for (size_t i = 0; i < ps.size(); ++i) {
    const Eigen::Vector2d& x = ps[i];
    const Eigen::Vector2d& y = ps[(i + 1) % ps.size()];
    area += 0.5 * (x.x() * y.y() - x.y() * y.x());
  }
  return std::fabs(area);
}

/// The intersection of the disks of radii r1 (at 0) and r2 (at distance D): its area and
/// a lower bound of its diameter (its extent along the centre line, and the common chord).
void disk_overlap(double r1, double r2, double D, double* area, double* diameter) {
  const double lo = std::min(r1, r2), hi = std::max(r1, r2);
  if (D + lo <= hi) {
    *area = M_PI * lo * lo;
    *diameter = 2 * lo;
    return;
  }
  const double x1 = (D * D + r1 * r1 - r2 * r2) / (2 * D), x2 = D - x1;
  const double chord = std::sqrt(std::max(0.0, r1 * r1 - x1 * x1));
  *area = r1 * r1 * std::acos(x1 / r1) - x1 * chord + r2 * r2 * std::acos(x2 / r2) - x2 * chord;
  *diameter = std::max(r1 + r2 - D, 2 * chord);
}

// ---------------------------------------------------------------------------------------------

/// The references against closed forms (the point distances they use: reference_self_test):
/// the solid minimum of pairs
/// apart (caps, sides, crossed sides, coplanar rims, rims in perpendicular planes) and of
/// one inside the other; the full reference on those and on meeting pairs (cap on cap,
/// side by side, crossed sides, a small one inside, a long thin one through the
/// middle); a tie (coaxial, coincident centres); and nref against the solid minimum
/// (distance and normal) on random separated lanes.
TEST(CylinderCylinder, ReferenceMatchesClosedForms) {
  Cyl c;
  c.p = Vec3d(1, 2, 3);
  c.r = 1.0, c.h = 2.0;
  struct Case {
    const char* what;
    Vec3d c;  // B's centre from A's
    Mat3d Rb;
    double rb, hb;
    double depth;  // > 0: depth, else minus the distance
    Vec3d n;
  };
  const Mat3d I = Mat3d::Identity();
  const Case cases[] = {
      {"cap over cap, apart", Vec3d(0.25, 0, 3.5), I, 0.5, 1.0, -0.5, Vec3d(0, 0, 1)},
      {"cap on cap", Vec3d(0.25, 0, 2.9), I, 0.5, 1.0, 0.1, Vec3d(0, 0, 1)},
      {"side by side, apart", Vec3d(2, 0, 0.5), I, 0.5, 1.0, -0.5, Vec3d(1, 0, 0)},
      {"side by side", Vec3d(1.4, 0, 0.5), I, 0.5, 1.0, 0.1, Vec3d(1, 0, 0)},
      {"crossed sides, apart", Vec3d(2, 0, 0.5), along_y(), 0.5, 1.5, -0.5, Vec3d(1, 0, 0)},
      {"crossed sides", Vec3d(1.4, 0, 0.5), along_y(), 0.5, 1.5, 0.1, Vec3d(1, 0, 0)},
      // B's bottom rim in A's top cap plane: the rims' closest points (1, 0, 2), (1.5, 0, 2)
      {"coplanar rims, apart", Vec3d(2, 0, 3), I, 0.5, 1.0, -0.5, Vec3d(1, 0, 0)},
      // B along x, its rim in the plane x = 1.3, lowest point (1.3, 0, 2.4); A's rim point
      // (1, 0, 2): each offset in the other's normal cone
      {"rims in perpendicular planes", Vec3d(2.3, 0, 2.9), along_x(), 0.5, 1.0, -0.5, Vec3d(0.6, 0, 0.8)},
      {"small, inside", Vec3d(0.7, 0, 0), I, 0.25, 0.25, 0.55, Vec3d(1, 0, 0)},
      {"long and thin, through", Vec3d(0.1, 0, 0.2), along_y(), 0.25, 3.0, 1.15, Vec3d(1, 0, 0)},
  };
  for (const Case& cs : cases) {
    SCOPED_TRACE(cs.what);
    Query q;
    q.a = c;
    q.b.p = c.p + cs.c, q.b.R = cs.Rb, q.b.r = cs.rb, q.b.h = cs.hb;
    if (cs.depth < 0) {
      EXPECT_NEAR(solid_minimum(q), -cs.depth, 1e-9);
    }
    const Ref f = reference(q);
    EXPECT_EQ(f.apart, cs.depth < 0);
    EXPECT_NEAR(f.depth, cs.depth, 1e-9);
    EXPECT_TRUE(f.unique);
    EXPECT_LT(angle(f.n, cs.n), 1e-6) << f.n.transpose();
    // the other order: the same depth, the normal reversed
    const Ref s = reference(swapped(q));
    EXPECT_NEAR(s.depth, cs.depth, 1e-9);
    EXPECT_LT(angle(s.n, -cs.n), 1e-6) << s.n.transpose();
  }
  // the solid minimum where A holds B: minus B's inradius; over B, minus A's radius (B's
  // centre on A's axis, 1.5 from A's caps)
  {
    Query q;
    q.a = c;
    q.b.p = c.p + Vec3d(0, 0, 0.5), q.b.R = rot(0.4, Vec3d(1, 1, 0)), q.b.r = 0.25, q.b.h = 0.375;
    EXPECT_NEAR(solid_minimum(q), -0.25, 1e-9);
    EXPECT_NEAR(solid_minimum(swapped(q)), -1.0, 1e-9);
  }
  // a tie: coaxial, coincident centres (every horizontal direction, depth ra + rb)
  {
    Query q;
    q.a = c;
    q.b.p = c.p, q.b.r = 0.25, q.b.h = 0.5;
    const Ref f = reference(q);
    EXPECT_NEAR(f.depth, 1.25, 1e-9);
    EXPECT_FALSE(f.unique);
  }
  // nref against the solid minimum where the two are apart
  std::mt19937 g(5);
  int compared = 0;
  for (int i = 0; i < 60; ++i) {
    const Query w = random_query(g, 1.0, 0.0, 1.0);
    Vec3d x;
    const double d = solid_minimum(w, Vec3d::Zero(), &x);
    if (d <= 1e-3) continue;
    const nref::PairResult s = nref::solve_pair(shape_of(w.a), shape_of(w.b), {}, nref::dense_options());
    // (the float-rounded rotations are orthonormal to ~1e-8: the point distances read
    // all of R, nref's cylinder only the axis)
    EXPECT_NEAR(s.s, -d, 1e-7) << i;
    EXPECT_LT(angle(ev(s.n), cyl_closest(w.b, x) - x), 1e-5) << i;
    ++compared;
  }
  EXPECT_GT(compared, 10);
}

class CylinderCylinderScales : public ::testing::TestWithParam<std::tuple<double, double>> {};

TEST_P(CylinderCylinderScales, RandomPosesAgainstReference) {
  const auto [size, offset] = GetParam();
  const int n = test::scenario_lanes(offset == 0 && size == 1.0 ? 240 : 160);
  test::random_pose_suite(test::scale_seed(21, size, offset), n, size, offset, random_queries, check_all,
                          {.max_hit_tenths = 9, .normals_div = 2});
}

INSTANTIATE_TEST_SUITE_P(Scales, CylinderCylinderScales, ::testing::ValuesIn(test::kernel_scales()));

/// Deep pairs: coincident centres (any axes), one wholly inside the other (both ways),
/// a long thin one through the middle of a fat one (both ways).
TEST(CylinderCylinder, DeepPairs) {
  std::mt19937 g(29);
  std::uniform_real_distribution<double> uni(-1, 1);
  auto mag = [&](double lo, double hi) { return lo + (hi - lo) * std::fabs(uni(g)); };
  std::vector<Query> qs;
  const int n = test::scenario_lanes(12);
  for (int i = 0; i < n; ++i) {
    const double ra = mag(0.3, 1.0), ha = mag(0.3, 1.0);
    // coincident centres
    Cyl b;
    b.R = test::random_rotation(g), b.r = mag(0.2, 1.0), b.h = mag(0.2, 1.0);
    qs.push_back(posed(g, ra, ha, b));
    // B wholly inside A, then A wholly inside B
    const double s = 0.3 * std::min(ra, ha);
    b.R = test::random_rotation(g), b.r = s * mag(0.3, 1.0), b.h = s * mag(0.3, 1.0);
    b.p = Vec3d(0.3 * ra * uni(g), 0.3 * ra * uni(g), 0.3 * ha * uni(g));
    const Query inside = posed(g, ra, ha, b);
    qs.push_back(inside);
    qs.push_back(swapped(inside));
    // a long thin B through A's middle, then the other way round
    b.R = test::random_rotation(g), b.r = mag(0.03, 0.2), b.h = 1.5 * std::hypot(ra, ha) * mag(1.0, 1.5);
    b.p = 0.1 * Vec3d(uni(g), uni(g), uni(g));
    const Query through = posed(g, ra, ha, b);
    qs.push_back(through);
    qs.push_back(swapped(through));
  }
  Stats st;
  check_all(qs, "deep", &st);
  EXPECT_EQ(st.hits, static_cast<int>(qs.size()));
  EXPECT_GT(st.normals_checked, st.hits / 3);
}

/// Cap face on cap face: B's bottom cap over A's cap (parallel axes), the disks offset
/// (the built point within both); normal A's axis; meeting, 3-4 points.
TEST(CylinderCylinder, CapFaceOnCapFace) {
  Stats st;
  int meeting = 0;
  const int on = check_built(Piece::kCap, Piece::kCap, false, 71, "cap on cap", &st, &meeting);
  EXPECT_GE(on, meeting * 3 / 4);
  EXPECT_EQ(st.hits, meeting);
  EXPECT_GE(st.counts[3] + st.counts[4], st.hits * 9 / 10);  // the disks clipped to each other
}

/// A rim against a cap face, both ways: A's rim into B's cap (normal B's axis), B's rim
/// into A's cap (normal A's axis).
TEST(CylinderCylinder, RimAgainstACapFace) {
  test::expect_feature_pairs([](Stats* s, int* m) {
    return check_built(Piece::kRim, Piece::kCap, false, 73, "A's rim on B's cap", s, m);
  });
  test::expect_feature_pairs([](Stats* s, int* m) {
    return check_built(Piece::kCap, Piece::kRim, false, 79, "B's rim on A's cap", s, m);
  });
}

/// The sides crossed (the axes >= 0.3 rad apart): normal the axes' cross product.
TEST(CylinderCylinder, SidesCrossed) {
  test::expect_feature_pairs([](Stats* s, int* m) {
    return check_built(Piece::kSide, Piece::kSide, false, 83, "sides crossed", s, m);
  });
}

/// A side against the other's rim, both ways (normal the side's radial direction).
TEST(CylinderCylinder, SideAgainstARim) {
  test::expect_feature_pairs([](Stats* s, int* m) {
    return check_built(Piece::kSide, Piece::kRim, false, 89, "A's side, B's rim", s, m);
  });
  test::expect_feature_pairs([](Stats* s, int* m) {
    return check_built(Piece::kRim, Piece::kSide, false, 97, "A's rim, B's side", s, m);
  });
}

/// Rim against rim: each rim's normal 0.3..1.27 rad from its radial direction, the
/// rims' planes turned at random about the normal (the circle-circle pieces). Crossing
/// rims often meet elsewhere too: about a quarter of the meeting lanes have a smaller
/// overlap through a cap or a side (measured: 177 of 240), hence 2/3 at the built pair.
TEST(CylinderCylinder, RimAgainstRim) {
  Stats st;
  int meeting = 0;
  const int on = check_built(Piece::kRim, Piece::kRim, false, 101, "rim against rim", &st, &meeting);
  EXPECT_GE(on, meeting * 2 / 3);
  EXPECT_EQ(st.hits, meeting);
}

/// Parallel sides (the built point within both heights), and a side on a cap face;
/// meeting, 2 points each.
TEST(CylinderCylinder, ParallelSidesAndSideOnACap) {
  Stats st;
  int meeting = 0;
  int on = check_built(Piece::kSide, Piece::kSide, true, 103, "parallel sides", &st, &meeting);
  EXPECT_GE(on, meeting * 3 / 4);
  EXPECT_EQ(st.hits, meeting);
  EXPECT_EQ(st.counts[2], st.hits);  // the heights' overlap
  on = check_built(Piece::kCap, Piece::kSide, false, 107, "B's side on A's cap", &st, &meeting);
  EXPECT_GE(on, meeting * 3 / 4);
  EXPECT_EQ(st.hits, meeting);
  EXPECT_EQ(st.counts[2], st.hits);  // the side line clipped to the disk
}

/// A cylinder standing on the other's top cap, 0.125 deep (axis-aligned, exact), both
/// paths and both orders: 3-4 points in the disks' overlap, at its plane's midway
/// height, each 0.125 deep, spread over it (spanning 0.85 of its diameter where one disk
/// holds the other, 0.6 of it for a lens) and enclosing a quarter of its area.
TEST(CylinderCylinder, StandingOnTheCap) {
  const Vec3d p(1, -2, 0.5);
  const double ra = 0.5, ha = 1.0, d = 0.125;
  struct Case {
    Vec3d off;  // B's axis from A's
    double rb, hb;
  };
  const Case cases[] = {
      {Vec3d(0, 0, 0), 0.25, 0.5},           // concentric, smaller
      {Vec3d(0, 0, 0), 0.5, 0.25},           // concentric, equal disks
      {Vec3d(0.125, 0.0625, 0), 0.25, 0.5},  // offset, within
      {Vec3d(0.5, 0, 0), 0.25, 1.0},         // offset over the rim: a lens
      {Vec3d(0.375, 0.25, 0), 0.75, 0.5},    // a larger B, offset: a lens
      {Vec3d(-0.25, 0, 0), 1.0, 0.5},        // a larger B holding A's disk
  };
  for (KernelPath path : {KernelPath::kSimd, KernelPath::kScalar}) {
    SCOPED_TRACE(path == KernelPath::kSimd ? "simd" : "scalar");
    for (const Case& cs : cases) {
      SCOPED_TRACE(cs.off.transpose());
      const Query q =
          aligned(p, ra, ha, cs.off + Vec3d(0, 0, ha - d + cs.hb), Mat3d::Identity(), cs.rb, cs.hb);
      double area = 0, diameter = 0;
      disk_overlap(ra, cs.rb, cs.off.norm(), &area, &diameter);
      const bool held = cs.off.norm() + std::min(ra, cs.rb) <= std::max(ra, cs.rb);
      for (bool b_on_a : {true, false}) {
        SCOPED_TRACE(b_on_a ? "B on A" : "A on B");
        const auto r = run({b_on_a ? q : swapped(q)}, path)[0];
        ASSERT_GE(r.count, 3u);
        EXPECT_LT(angle(r.n, Vec3d(0, 0, b_on_a ? 1 : -1)), 1e-6);
        EXPECT_NEAR(r.depth, d, 1e-6);
        for (uint32_t i = 0; i < r.count; ++i) {
          const Vec3d l = r.pt[i] - p;
          EXPECT_NEAR(l.z(), ha - d / 2, 1e-6) << i;
          EXPECT_NEAR(r.pd[i], d, 1e-6) << i;
          EXPECT_LE(std::hypot(l.x(), l.y()), ra + 1e-6) << i << " " << l.transpose();
          EXPECT_LE(std::hypot(l.x() - cs.off.x(), l.y() - cs.off.y()), cs.rb + 1e-6)
              << i << " " << l.transpose();
        }
        EXPECT_GE(spread(r), (held ? 0.85 : 0.6) * diameter);
        EXPECT_GE(xy_area(r), 0.25 * area);
      }
    }
  }
}

/// A cylinder lying on the other's top cap (axis along x), 0.125 deep, both paths and
/// both orders: 2 points, the side line's ends clipped to the disk.
TEST(CylinderCylinder, LyingOnTheCap) {
  const Vec3d p(2, 1, -0.5);
  const double ra = 1.25, ha = 0.5, rb = 0.25, d = 0.125;
  struct Case {
    double x, y;    // B's centre across A's axis
    double hb;      // B's half length
    double x0, x1;  // the expected ends (the disk's chord at y: |x| <= sqrt(ra^2 - y^2))
  };
  const Case cases[] = {
      {0.25, 0, 0.5, -0.25, 0.75},  // within the disk
      {0.5, 0.75, 1.0, -0.5, 1.0},  // over the rim at one end (the chord's half: 1)
      {0, 0.75, 2.0, -1.0, 1.0},    // over the rim at both ends
  };
  for (KernelPath path : {KernelPath::kSimd, KernelPath::kScalar}) {
    SCOPED_TRACE(path == KernelPath::kSimd ? "simd" : "scalar");
    for (const Case& cs : cases) {
      SCOPED_TRACE(cs.x);
      const Query q = aligned(p, ra, ha, Vec3d(cs.x, cs.y, ha - d + rb), along_x(), rb, cs.hb);
      for (bool b_on_a : {true, false}) {
        SCOPED_TRACE(b_on_a ? "B on A" : "A on B");
        test::expect_line_contact(run({b_on_a ? q : swapped(q)}, path)[0],
                                  {.n = Vec3d(0, 0, b_on_a ? 1 : -1),
                                   .d = d,
                                   .origin = p,
                                   .axis = 0,
                                   .lo = cs.x0,
                                   .hi = cs.x1,
                                   .at = Vec3d(0, cs.y, ha - d / 2)});
      }
    }
  }
}

/// Side by side, axes parallel, 0.125 deep along a horizontal direction, both paths and
/// both orders: 2 points on the line midway between the sides, at the ends of the
/// heights' overlap.
TEST(CylinderCylinder, SideBySide) {
  const Vec3d p(-1, 0.5, 2);
  const double ra = 0.5, ha = 1.0, rb = 0.25, d = 0.125;
  struct Case {
    Vec3d dir;      // the normal (a dyadic multiple of it is representable)
    double z, hb;   // B's centre height, half length
    double z0, z1;  // the heights' overlap
  };
  const Case cases[] = {
      {Vec3d(1, 0, 0), 0.25, 0.5, -0.25, 0.75},
      {Vec3d(0, -1, 0), 1.0, 0.75, 0.25, 1.0},
      {Vec3d(0.6, 0.8, 0), 0.0, 2.0, -1.0, 1.0},
  };
  for (KernelPath path : {KernelPath::kSimd, KernelPath::kScalar}) {
    SCOPED_TRACE(path == KernelPath::kSimd ? "simd" : "scalar");
    for (const Case& cs : cases) {
      SCOPED_TRACE(cs.dir.transpose());
      const Query q =
          aligned(p, ra, ha, (ra + rb - d) * cs.dir + Vec3d(0, 0, cs.z), Mat3d::Identity(), rb, cs.hb);
      for (bool b_by_a : {true, false}) {
        SCOPED_TRACE(b_by_a ? "A, B" : "B, A");
        test::expect_line_contact(run({b_by_a ? q : swapped(q)}, path)[0],
                                  {.n = b_by_a ? cs.dir : Vec3d(-cs.dir),
                                   .d = d,
                                   .origin = p,
                                   .axis = 2,
                                   .lo = cs.z0,
                                   .hi = cs.z1,
                                   .at = Vec3d((ra - d / 2) * cs.dir.x(), (ra - d / 2) * cs.dir.y(), 0)});
      }
    }
  }
}

/// Near-parallel tilts (0..1e-2 rad) of the three manifolds, posed: B standing on A's
/// cap (within the disk: 3-4 points), lying on it (2 points), side by side (2 points).
TEST(CylinderCylinder, NearParallelManifolds) {
  std::mt19937 g(37);
  std::uniform_real_distribution<double> uni(-1, 1);
  const double tilts[] = {0.0, 1e-7, 1e-5, 1e-3, 1e-2};
  std::vector<Query> standing, lying, beside;
  const double ra = 0.5, ha = 1.0, d = 0.05;
  for (int i = 0; i < test::scenario_lanes(5); ++i)
    for (double tilt : tilts) {
      const Mat3d tilted = rot(tilt, radial(M_PI * uni(g))) * rot(M_PI * uni(g), Vec3d::UnitZ());
      const Vec3d u = tilted.col(2);
      // standing on the top cap, its disk within A's
      Cyl b;
      b.r = 0.15 + 0.15 * std::fabs(uni(g)), b.h = 0.2 + 0.3 * std::fabs(uni(g)), b.R = tilted;
      b.p = Vec3d(0.08 * uni(g), 0.08 * uni(g), ha - d) + b.h * u;
      standing.push_back(posed(g, ra, ha, b));
      // lying on the top cap across its centre (its axis tilted from the horizontal
      // about its own normal direction: the ends at depths d +- tilt h)
      const double a = M_PI * uni(g);
      b.r = 0.1 + 0.2 * std::fabs(uni(g)), b.h = 0.2 + 0.5 * std::fabs(uni(g));
      b.R = frame_of(rot(tilt, tangential(a)) * radial(a), M_PI * uni(g));
      b.p = Vec3d(0.1 * uni(g), 0.1 * uni(g), ha - d + b.r);
      lying.push_back(posed(g, ra, ha, b));
      // side by side along radial(a), tilted about a random horizontal axis
      b.r = 0.1 + 0.3 * std::fabs(uni(g)), b.h = 0.3 + 0.7 * std::fabs(uni(g)), b.R = tilted;
      b.p = (ra + b.r - d) * radial(a) + 0.3 * uni(g) * Vec3d::UnitZ();
      beside.push_back(posed(g, ra, ha, b));
    }
  Stats st;
  check_all(standing, "standing on the cap", &st);
  EXPECT_EQ(st.hits, static_cast<int>(standing.size()));
  EXPECT_GE(st.counts[3] + st.counts[4], st.hits * 9 / 10);
  check_all(lying, "lying on the cap", &st);
  EXPECT_EQ(st.hits, static_cast<int>(lying.size()));
  EXPECT_EQ(st.counts[2], st.hits);
  check_all(beside, "side by side", &st);
  EXPECT_EQ(st.hits, static_cast<int>(beside.size()));
  EXPECT_GE(st.counts[2], st.hits * 9 / 10);
}

/// Exactly touching (representable) configurations: count 0; B moved onto touching by
/// the reference's depth along its normal: depth within 4 tol.
TEST(CylinderCylinder, Touching) {
  const Vec3d p(4, 5, -6);
  const double ra = 0.5, ha = 1.0;
  const Mat3d I = Mat3d::Identity();
  const struct {
    const char* what;
    Vec3d c;
    Mat3d Rb;
    double rb;
  } cases[] = {
      {"cap on cap", Vec3d(0.125, 0, 1.5), I, 0.25},
      {"side by side", Vec3d(0.75, 0, 0.25), I, 0.25},
      {"sides crossed", Vec3d(0.75, 0, 0.25), along_y(), 0.25},
      {"lying on the cap", Vec3d(0.125, 0, 1.25), along_x(), 0.25},
      {"coplanar rims", Vec3d(0.75, 0, 1.5), I, 0.25},
      // B along y, its side through A's rim point (0.5, 0, 1) with normal (0.6, 0, 0.8)
      {"a side on a rim point", Vec3d(0.6875, 0, 1.25), along_y(), 0.3125},
  };
  for (KernelPath path : {KernelPath::kSimd, KernelPath::kScalar})
    for (const auto& cs : cases) {
      const Query q = aligned(p, ra, ha, cs.c, cs.Rb, cs.rb, 0.5);
      EXPECT_LE(solid_minimum(q), 1e-9) << cs.what;
      EXPECT_GE(solid_minimum(q), -1e-9) << cs.what;
      EXPECT_EQ(run({q}, path)[0].count, 0u) << cs.what;
      EXPECT_EQ(run({swapped(q)}, path)[0].count, 0u) << cs.what;
    }
  std::mt19937 g(43);
  test::expect_touching_after_push(
      g, test::scenario_lanes(40), 10 * test::scenario_lanes(40),
      [](std::mt19937& gg) { return random_query(gg, 1.0, 0.0, 0.5); }, reference,
      [](Query& q, const Vec3d& s) { q.b.p = test::round_to_float(Vec3d(q.b.p + s)); },
      [](const std::vector<Query>& qs) { return run(qs, KernelPath::kSimd); }, size_of, kRel);
}

/// Needles and pancakes (1e-4 proportions) of either cylinder or both: radius 1e-4 of
/// the half length, half length 1e-4 of the radius.
TEST(CylinderCylinder, NeedlesAndPancakes) {
  std::mt19937 g(53);
  const int n = test::scenario_lanes(48);
  const std::vector<Query> qs = test::draw_cases(n, [&](int i) {
    Query q = random_query(g, 1.0, 0.0, 0.0);
    switch (i % 6) {
      case 0:
        q.a.r = 1e-4 * q.a.h;
        break;  // needle A
      case 1:
        q.a.h = 1e-4 * q.a.r;
        break;  // pancake A (a disk)
      case 2:
        q.b.r = 1e-4 * q.b.h;
        break;  // needle B
      case 3:
        q.b.h = 1e-4 * q.b.r;
        break;  // pancake B
      case 4:
        q.a.r = 1e-4 * q.a.h, q.b.r = 1e-4 * q.b.h;
        break;  // two needles
      default:
        q.a.h = 1e-4 * q.a.r, q.b.h = 1e-4 * q.b.r;
        break;  // two disks
    }
    const double reach = std::hypot(q.a.r, q.a.h) + std::hypot(q.b.r, q.b.h);
    q.a.p = q.b.p + 0.3 * reach * test::random_unit_vector(g);
    return rounded(q);
  });
  test::expect_thin_pairs_meet(qs, check_all);
}

/// Two coins (half length 1e-4 of the radius) whose four rim pairs each give the most
/// brackets (kArcSlots = 6; found by the needle / pancake test at
/// IMPACT_TEST_INTENSITY=10), repeated over a whole bucket: phase B's unit queue then
/// takes 24 units per lane. It once flushed 4 W units per group of W items whatever
/// was left, so a run of such lanes overflowed the queue (a stack overwrite in either
/// path: the scalar one after 3 lanes, the 16-lane one after 4 groups). Every lane is
/// checked against the reference, and all give the same bytes.
TEST(CylinderCylinder, CoinsWithTheMostRimBracketsFillABucket) {
  Query q;
  q.b.p = Vec3d::Zero();
  q.b.R = Mat3d::Identity();
  q.b.r = 0.783263862, q.b.h = 7.83263895e-05;
  q.a.p = Vec3d(0.354156226, -0.193492845, 0.072137773);
  q.a.R = columns(Vec3d(0.324249327, -0.587805152, 0.741179705), Vec3d(0.940862298, 0.281716436, -0.18818593),
                  Vec3d(-0.0981858373, 0.7583673, 0.644390106));
  q.a.r = 0.583280742, q.a.h = 5.83280744e-05;
  // Orthonormalise the printed (9-digit) axes (the kernel's precondition): keep the axis.
  const Vec3d u = q.a.R.col(2).normalized();
  const Vec3d x = (q.a.R.col(0) - q.a.R.col(0).dot(u) * u).normalized();
  q.a.R = columns(x, u.cross(x), u);
  const std::vector<Query> qs(200, rounded(q));
  check_all(qs, "coins, 6 brackets per rim pair");
  const auto simd = run(qs, KernelPath::kSimd), scal = run(qs, KernelPath::kScalar);
  for (size_t k = 1; k < qs.size(); ++k) {
    EXPECT_TRUE(test::same_bytes(simd[k], simd[0])) << "lane " << k;
    EXPECT_TRUE(test::same_bytes(scal[k], scal[0])) << "lane " << k;
  }
}

/// Symmetries: turning and moving the whole pair turns the normal and keeps the depth;
/// A and B swapped reverse the normal; either axis reversed (R's columns 0 and 2
/// negated) is the same solid: the same answer within tol.
TEST(CylinderCylinder, Symmetries) {
  std::mt19937 g(59);
  std::vector<Query> base, turned, swaps, flip_a, flip_b;
  std::vector<Mat3d> turns;
  for (int i = 0; i < test::scenario_lanes(80); ++i) {
    const Query q = random_query(g, 1.0, 0.0, 0.7);
    base.push_back(q);
    const Mat3d turn = test::random_rotation(g);
    const Vec3d move = test::random_unit_vector(g);
    Query t = q;
    for (Cyl* c : {&t.a, &t.b}) {
      c->p = turn * c->p + move;
      c->R = turn * c->R;
    }
    turned.push_back(rounded(t));
    turns.push_back(turn);
    swaps.push_back(swapped(q));
    Query f = q;
    f.a.R.col(0) = -q.a.R.col(0);
    f.a.R.col(2) = -q.a.R.col(2);
    flip_a.push_back(f);
    f = q;
    f.b.R.col(0) = -q.b.R.col(0);
    f.b.R.col(2) = -q.b.R.col(2);
    flip_b.push_back(f);
  }
  test::expect_symmetric(
      run(base, KernelPath::kSimd),
      {{run(turned, KernelPath::kSimd), 2, [&](size_t k) { return turns[k]; }},
       {run(swaps, KernelPath::kSimd), 1, [](size_t) { return Mat3d(-Mat3d::Identity()); }},
       {run(flip_a, KernelPath::kSimd)},
       {run(flip_b, KernelPath::kSimd)}},
      kAngleTol, [&](size_t k) {
        const Ref f = reference(base[k]);
        return test::SymmetryLane{kRel * size_of(base[k]), f.depth, f.unique};
      });
}

}  // namespace
}  // namespace impact::kernels
