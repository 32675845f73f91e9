// collide_convex_ellipsoid (kernels/narrowphase/pairs/convex/convex_ellipsoid.cpp) on both paths against
// an independent double-precision reference, the sphere-hull kernel where the ellipsoid is
// round and the box-ellipsoid kernel where the hull is a box.
//
// Reference (double, no piece enumeration, no secular-equation solve by steps): the support
// overlap h_A(n) + h_B(-n) minimised over densely sampled directions and refined by
// Nelder-Mead (tests/support/narrow_reference.h, more samples and starts than its default):
// depth (> 0) or minus the distance, and the normal. For separated pairs it is checked
// against the ellipsoid's signed distance (tests/support/ellipsoid_reference.h, bisection of
// the secular equation) at the hull's vertices: the distance is at most their least.
// Per lane, L = max(largest radius, the hull's radius), tol = kRel * L:
//  (a) count > 0 iff the reference depth > 0 (either where |depth_ref| <= tol);
//  (b) |depth - depth_ref| <= tol;
//  (c) n finite and unit; the reference overlap along n <= depth_ref + tol (a safe
//      displacement); angle(n, n_ref) <= kAngleTol where the minimum is unique (every
//      direction 0.02 rad from n_ref overlaps by more than depth_ref + 10 tol);
//  (d) point[0] - n depth/2 on the ellipsoid (level 1 within 1e-4), pdepth[0] == depth;
//  (e) the scalar and SIMD paths agree within tol and kAngleTol.
// Scenarios: random poses (about half overlapping) at sizes 1, 1e-4, 1e4 and 1e5 from the
// origin; constructed touching at a face, an edge (its normal-cone bisector) and a vertex,
// and the same pushed in (shallow and deep); needle and pancake ellipsoids (1e-4); flat
// hulls (1e-4 thick boxes); coincident centres; a round ellipsoid against sphere-hull; a
// box hull against box-ellipsoid.
// Registration, range partitions, shuffled buckets and the agreement with GJK / EPA:
// contract_test.cpp (every bucket of the table).
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <numeric>
#include <random>
#include <vector>

#include "kernels/narrowphase/pair_kernels.h"
#include "support/ellipsoid_reference.h"
#include "support/hull_input.h"
#include "support/leaf_lanes.h"
#include "support/narrow_reference.h"
#include "support/test_support.h"

namespace impact::kernels {
namespace {

using Vec3d = Eigen::Vector3d;
using Mat3d = Eigen::Matrix3d;
namespace nref = test::nref;
namespace hi = test::hull_input;

constexpr double kRel = 1e-5;
constexpr double kAngleTol = 1e-4;
/// A few float ulps of the overlap at size L (4 x 2^-24): its evaluation's rounding.
constexpr double kRoundingSlack = 2.4e-7;

struct Side {
  Vec3d p = Vec3d::Zero();
  Mat3d R = Mat3d::Identity();
  Vec3d e = Vec3d::Zero();
  uint32_t hull = 0;
};

struct Case {
  std::vector<Side> a, b;  // hull, ellipsoid
  void add(const Side& ha, const Side& eb) {
    a.push_back(ha);
    b.push_back(eb);
  }
};

Mat3d rounded_rotation(hi::Rng& g) {
  double r[9];
  test::random_rotation_rows(g, r);
  Mat3d m;
  for (int i = 0; i < 9; ++i) m(i / 3, i % 3) = test::round_to_float(r[i]);
  return m;
}

Vec3d rounded(const Vec3d& v) {
  return {test::round_to_float(v.x()), test::round_to_float(v.y()), test::round_to_float(v.z())};
}

struct Lanes {
  test::LeafLanes la, lb;
  test::ManifoldLanes out;
  explicit Lanes(const Case& c) : out(static_cast<uint32_t>(c.a.size())) {
    for (const auto& s : c.a) la.push(s);
    for (const auto& s : c.b) lb.push(s);
  }
  void go(PairKernel k, const HullView& hv, KernelPath path, Range r) {
    NarrowConfig cfg;
    cfg.hulls = hv;
    cfg.path = path;
    const LeafSoA a = la.soa(), b = lb.soa();
    k(a, b, out.view(), r, cfg);
  }
  uint32_t n() const { return static_cast<uint32_t>(la.ref.size()); }
};

/// The per-lane references and checks.
struct Checker {
  const hi::Hulls& hulls;
  int checked = 0, unique = 0, hits = 0;

  void check(const Lanes& run, const Lanes* scalar, uint32_t k) {
    const HullView hv = hulls.store.view();
    const LeafSoA a = run.la.soa(), b = run.lb.soa();
    const nref::Shape sa = nref::shape_from_leaf(a, k, kLeafConvex, &hv);
    const nref::Shape sb = nref::shape_from_leaf(b, k, kLeafEllipsoid);
    nref::Options opt;
    opt.samples = 6000;
    opt.starts = 8;
    const nref::PairResult ref = nref::solve_pair(sa, sb, {}, opt);
    const double L = std::max(sb.bound_radius(), sa.bound_radius());
    const double tol = kRel * L + 1e-6 * (std::fabs(sa.p.x) + std::fabs(sa.p.y) + std::fabs(sa.p.z)) * 1e-2;
    const test::PairResult got = run.out.result(k);
    ++checked;
    SCOPED_TRACE(::testing::Message() << "lane " << k << " ref depth " << ref.s << " got count " << got.count
                                      << " depth " << got.depth << " L " << L);
    if (std::fabs(ref.s) > tol) {
      ASSERT_EQ(got.count > 0, ref.s > 0);
    }
    if (got.count == 0) {
      if (ref.s < -tol) {
        // Independent check of a separated reference: the distance is at most the least
        // signed distance of a hull vertex to the ellipsoid.
        double dmin = 1e300;
        Mat3d R;
        for (int i = 0; i < 9; ++i) R(i / 3, i % 3) = b.r[i][k];
        const Vec3d pb(b.p[0][k], b.p[1][k], b.p[2][k]), eb(b.e[0][k], b.e[1][k], b.e[2][k]);
        for (const auto& q : sa.pts) {
          const Vec3d y = R.transpose() * (Vec3d(q.x, q.y, q.z) - pb);
          dmin = std::min(dmin, test::eref::signed_distance_local(eb, y));
        }
        EXPECT_LE(-ref.s, dmin + tol);
      }
      return;
    }
    ++hits;
    ASSERT_EQ(got.count, 1u);
    const Vec3d n = got.n;
    ASSERT_TRUE(std::isfinite(n.x()) && std::isfinite(n.y()) && std::isfinite(n.z()));
    EXPECT_NEAR(n.norm(), 1.0, 1e-5);
    EXPECT_NEAR(got.depth, ref.s, tol);
    const nref::V3 nv{n.x(), n.y(), n.z()};
    EXPECT_LE(nref::overlap(sa, sb, nref::normalized(nv)), ref.s + tol);
    if (ref.unique(10 * tol) && ref.s > tol) {
      ++unique;
      // Farther than kAngleTol only as good a direction as the reference's up to the
      // overlap's float rounding (kRoundingSlack L), within 10 kAngleTol (seen at
      // intensity 10: up to 2.3e-4 rad, 3 lanes in ~6000).
      const double ang = nref::angle(nv, ref.n);
      const bool as_good = nref::overlap(sa, sb, nref::normalized(nv)) <= ref.s + kRoundingSlack * L;
      EXPECT_TRUE(ang <= kAngleTol || (as_good && ang <= 10 * kAngleTol)) << "angle " << ang;
    }
    EXPECT_EQ(got.pd[0], got.depth);
    // point - n depth/2 lies on the ellipsoid.
    Mat3d R;
    for (int i = 0; i < 9; ++i) R(i / 3, i % 3) = b.r[i][k];
    const Vec3d pb(b.p[0][k], b.p[1][k], b.p[2][k]), eb(b.e[0][k], b.e[1][k], b.e[2][k]);
    const Vec3d xe = R.transpose() * (got.pt[0] - 0.5 * got.depth * n - pb);
    EXPECT_NEAR(test::eref::signed_distance_local(eb, xe), 0.0,
                tol + 1e-6 * L + 2.4e-7 * got.pt[0].cwiseAbs().maxCoeff());
    if (scalar != nullptr) {
      const test::PairResult s = scalar->out.result(k);
      if (s.count != got.count) {  // only at touching, within the tolerance
        EXPECT_LE(std::fabs(ref.s), tol);
        EXPECT_LE(got.depth, tol);
        return;
      }
      EXPECT_NEAR(s.depth, got.depth, tol);
      if (ref.unique(10 * tol)) {
        EXPECT_LE(nref::angle(nv, nref::V3{s.n.x(), s.n.y(), s.n.z()}), kAngleTol);
      }
    }
  }
};

/// Radii: random in [0.2, 1] * scale, or needle / pancake shapes.
Vec3d radii(hi::Rng& g, double scale, int kind) {
  Vec3d e(hi::uni(g, 0.2, 1.0), hi::uni(g, 0.2, 1.0), hi::uni(g, 0.2, 1.0));
  if (kind == 1) e = Vec3d(1.0, 1e-4, 1e-4);  // needle
  if (kind == 2) e = Vec3d(1.0, 0.7, 1e-4);   // pancake
  if (kind == 3) e = Vec3d(0.6, 0.6, 0.6);    // round
  return rounded(scale * e);
}

/// Random pairs at `scale` and `offset`: the ellipsoid's centre within 1.2 times the sum
/// of the bounding radii of the hull's origin (about half overlap).
void random_pairs(hi::Rng& g, const hi::Hulls& hulls, uint32_t first, uint32_t nh, double scale,
                  double offset, uint32_t count, int kind, Case& c) {
  for (uint32_t i = 0; i < count; ++i) {
    Side a, b;
    a.hull = first + static_cast<uint32_t>(g() % nh);
    a.R = rounded_rotation(g);
    const Vec3d base(offset, -0.5 * offset, 0.25 * offset);
    a.p = rounded(base + scale * Vec3d(hi::uni(g, -0.1, 0.1), hi::uni(g, -0.1, 0.1), hi::uni(g, -0.1, 0.1)));
    b.e = radii(g, scale, kind == 4 ? static_cast<int>(g() % 3) : kind);
    b.R = rounded_rotation(g);
    double rh = 0;
    for (const auto& v : hulls.data[a.hull].vertices) rh = std::max(rh, static_cast<double>(v.norm()));
    const hi::D3 u = hi::random_unit(g);
    const double dist = hi::uni(g, 0.0, 1.0) * (rh + b.e.maxCoeff()) * 0.9;
    b.p = rounded(a.p + dist * Vec3d(u.x, u.y, u.z));
    c.add(a, b);
  }
}

class ConvexEllipsoid : public ::testing::Test {
 protected:
  void SetUp() override {
    hi::Rng g(7);
    hi::add_random_hulls(g, &hulls, 12, 1.0);       // 0..11: size 1
    hi::add_random_hulls(g, &hulls, 4, 1e-4);       // 12..15
    hi::add_random_hulls(g, &hulls, 4, 1e4);        // 16..19
    hulls.add(hi::box_corners(1.0f, 0.5f, 1e-4f));  // 20: flat
    hulls.add(hi::box_corners(0.7f, 0.4f, 0.3f));   // 21: box
    hulls.add(hi::ellipsoid_points(g, 400, 1.0));   // 22: beyond the kernel's limits
  }

  /// Runs SIMD and scalar, checks every lane; returns the checker's counts.
  Checker run_all(const Case& c) {
    Lanes simd(c), scal(c);
    const HullView hv = hulls.store.view();
    simd.go(&collide_convex_ellipsoid, hv, KernelPath::kSimd, Range{0, simd.n()});
    scal.go(&collide_convex_ellipsoid, hv, KernelPath::kScalar, Range{0, scal.n()});
    Checker ch{hulls};
    for (uint32_t k = 0; k < simd.n(); ++k) {
      ch.check(simd, &scal, k);
      if (::testing::Test::HasFailure() && hi::failure_parts() > 20) break;
    }
    return ch;
  }

  hi::Hulls hulls;
};

uint32_t count_of(uint32_t n) {
  return static_cast<uint32_t>(n * test::intensity());
}

TEST_F(ConvexEllipsoid, RandomPosesUnitSize) {
  hi::Rng g(11);
  Case c;
  random_pairs(g, hulls, 0, 12, 1.0, 0.0, count_of(160), 0, c);
  const Checker ch = run_all(c);
  EXPECT_GT(ch.hits, ch.checked / 4);
  EXPECT_GT(ch.unique, ch.hits / 3);
}

TEST_F(ConvexEllipsoid, RandomPosesScalesAndFarFromOrigin) {
  hi::Rng g(12);
  Case c;
  random_pairs(g, hulls, 12, 4, 1e-4, 0.0, count_of(40), 0, c);
  random_pairs(g, hulls, 16, 4, 1e4, 0.0, count_of(40), 0, c);
  random_pairs(g, hulls, 0, 12, 1.0, 1e5, count_of(40), 0, c);
  run_all(c);
}

TEST_F(ConvexEllipsoid, NeedlesPancakesFlatAndRound) {
  hi::Rng g(13);
  Case c;
  random_pairs(g, hulls, 0, 12, 1.0, 0.0, count_of(50), 1, c);
  random_pairs(g, hulls, 0, 12, 1.0, 0.0, count_of(50), 2, c);
  random_pairs(g, hulls, 20, 1, 1.0, 0.0, count_of(40), 4, c);
  random_pairs(g, hulls, 0, 12, 1.0, 0.0, count_of(20), 3, c);
  run_all(c);
}

TEST_F(ConvexEllipsoid, TouchingAndPushedIn) {
  // The ellipsoid placed so that its surface point with outward normal -u lies on the
  // hull's support point along u (a face normal, an edge's cone bisector, a vertex's
  // direction from the hull's centroid), then moved in by delta along -u.
  hi::Rng g(14);
  const HullView hv = hulls.store.view();
  Case c;
  for (uint32_t i = 0; i < count_of(60); ++i) {
    Side a, b;
    a.hull = static_cast<uint32_t>(g() % 12);
    if (i % 7 == 6) a.hull = 20;
    a.R = rounded_rotation(g);
    a.p = rounded(Vec3d(hi::uni(g, -1, 1), hi::uni(g, -1, 1), hi::uni(g, -1, 1)));
    const int kind = static_cast<int>(i % 3);
    Vec3d ul;
    if (kind == 0) {
      const uint32_t f = hv.face_begin[a.hull] +
                         static_cast<uint32_t>(g() % (hv.face_begin[a.hull + 1] - hv.face_begin[a.hull]));
      ul = Vec3d(hv.fnx[f], hv.fny[f], hv.fnz[f]);
    } else if (kind == 1) {
      const uint32_t e = hv.adj_begin[a.hull] +
                         static_cast<uint32_t>(g() % (hv.adj_begin[a.hull + 1] - hv.adj_begin[a.hull]));
      ul = Vec3d(hv.emx[e], hv.emy[e], hv.emz[e]);
    } else {
      const auto& vs = hulls.data[a.hull].vertices;
      Vec3d cen = Vec3d::Zero();
      for (const auto& v : vs) cen += v.cast<double>();
      cen /= static_cast<double>(vs.size());
      ul = vs[g() % vs.size()].cast<double>() - cen;
    }
    ul.normalize();
    const Vec3d u = a.R * ul;
    b.e = radii(g, 1.0, static_cast<int>(g() % 4) == 0 ? 2 : 0);
    b.R = rounded_rotation(g);
    // Support point of the hull along u.
    double best = -1e300;
    Vec3d sp;
    for (const auto& v : hulls.data[a.hull].vertices) {
      const Vec3d w = a.p + a.R * v.cast<double>();
      if (w.dot(u) > best) best = w.dot(u), sp = w;
    }
    const Vec3d ul_e = b.R.transpose() * u;
    const Vec3d a2u(b.e.x() * b.e.x() * ul_e.x(), b.e.y() * b.e.y() * ul_e.y(), b.e.z() * b.e.z() * ul_e.z());
    const double hu = std::sqrt(ul_e.x() * a2u.x() + ul_e.y() * a2u.y() + ul_e.z() * a2u.z());
    const double delta = (i / 3) % 3 == 0 ? 0.0 : ((i / 3) % 3 == 1 ? 0.01 : 0.3);
    b.p = rounded(sp + (b.R * a2u) / hu - delta * u);
    c.add(a, b);
  }
  run_all(c);
}

TEST_F(ConvexEllipsoid, CoincidentCentres) {
  hi::Rng g(15);
  Case c;
  for (uint32_t i = 0; i < count_of(30); ++i) {
    Side a, b;
    a.hull = static_cast<uint32_t>(g() % 12);
    if (i % 5 == 4) a.hull = 20;
    a.R = rounded_rotation(g);
    a.p = rounded(Vec3d(hi::uni(g, -1, 1), hi::uni(g, -1, 1), hi::uni(g, -1, 1)));
    b.p = a.p;
    b.e = radii(g, 1.0, static_cast<int>(i % 4));
    b.R = i % 2 ? a.R : rounded_rotation(g);
    c.add(a, b);
  }
  run_all(c);
}

TEST_F(ConvexEllipsoid, RoundEllipsoidMatchesSphereHull) {
  hi::Rng g(16);
  Case c;
  random_pairs(g, hulls, 0, 12, 1.0, 0.0, count_of(300), 3, c);
  Lanes run(c);
  const HullView hv = hulls.store.view();
  run.go(&collide_convex_ellipsoid, hv, KernelPath::kSimd, Range{0, run.n()});
  // Sphere (A) against hull (B): the same pair seen from the other side.
  test::LeafLanes ls;
  for (const auto& s : c.b) ls.push(s);
  test::ManifoldLanes so(run.n());
  NarrowConfig cfg;
  cfg.hulls = hv;
  collide_sphere_convex(ls.soa(), run.la.soa(), so.view(), Range{0, run.n()}, cfg);
  int hits = 0;
  for (uint32_t k = 0; k < run.n(); ++k) {
    const test::PairResult x = run.out.result(k), y = so.result(k);
    const double tol = 1e-5 * 2.0;
    if (x.count != y.count) {
      EXPECT_LE(std::max(std::fabs(x.depth), std::fabs(y.depth)), tol) << k;
      continue;
    }
    if (x.count == 0) continue;
    ++hits;
    EXPECT_NEAR(x.depth, y.depth, tol) << k;
    if (x.depth > 1e-3) {
      // A vertex or edge contact's minimum is a valley: G rises as |c - q| t^2 / 2 a
      // direction t away (c the sphere's centre, q the hull's point nearest it, |c - q| =
      // r - depth), so directions whose overlap is within float rounding (4e-7 of the
      // pair's size, ~2) of the least are this far apart (the other kernels' valley rule;
      // 1.03e-3 seen at IMPACT_TEST_INTENSITY=30 with |c - q| = 0.345, both depths equal).
      const double dist = std::max(static_cast<double>(c.b[k].e[0]) - x.depth, 1e-9);
      const double valley = std::sqrt(2.0 * 4e-7 * 2.0 / dist);
      const double ang = nref::angle({x.n.x(), x.n.y(), x.n.z()}, {-y.n.x(), -y.n.y(), -y.n.z()});
      EXPECT_LE(ang, std::max(1e-3, valley)) << k;
    }
  }
  EXPECT_GT(hits, 50);
}

TEST_F(ConvexEllipsoid, BoxHullMatchesBoxEllipsoid) {
  hi::Rng g(17);
  Case c;
  random_pairs(g, hulls, 21, 1, 1.0, 0.0, count_of(300), 4, c);
  Lanes run(c);
  run.go(&collide_convex_ellipsoid, hulls.store.view(), KernelPath::kSimd, Range{0, run.n()});
  test::LeafLanes lbx;
  for (auto s : c.a) {
    s.e = Vec3d(0.7, 0.4, 0.3);
    lbx.push(s);
  }
  test::ManifoldLanes bo(run.n());
  NarrowConfig cfg;
  collide_box_ellipsoid(lbx.soa(), run.lb.soa(), bo.view(), Range{0, run.n()}, cfg);
  int hits = 0;
  for (uint32_t k = 0; k < run.n(); ++k) {
    const test::PairResult x = run.out.result(k), y = bo.result(k);
    const double tol = 2e-5;
    if (x.count != y.count) {
      EXPECT_LE(std::max(std::fabs(x.depth), std::fabs(y.depth)), tol) << k;
      continue;
    }
    if (x.count == 0) continue;
    ++hits;
    EXPECT_NEAR(x.depth, y.depth, tol) << k;
    if (x.depth > 1e-3) {
      EXPECT_LE(nref::angle({x.n.x(), x.n.y(), x.n.z()}, {y.n.x(), y.n.y(), y.n.z()}), 1e-3) << k;
    }
  }
  EXPECT_GT(hits, 50);
}

/// A hull beyond the kernel's stack limits (more than 256 vertices) goes through
/// GJK / EPA for its lanes: the same bytes as collide_gjk_epa, and still right.
TEST_F(ConvexEllipsoid, LargeHullsFallBackToGjkEpa) {
  ASSERT_GT(hulls.data[22].vertices.size(), 256u);
  hi::Rng g(23);
  Case c;
  random_pairs(g, hulls, 21, 2, 1.0, 0.0, count_of(40), 0, c);  // hulls 21 (kernel) and 22
  Lanes run(c), gj(c);
  const HullView hv = hulls.store.view();
  run.go(&collide_convex_ellipsoid, hv, KernelPath::kSimd, Range{0, run.n()});
  NarrowConfig cfg;
  cfg.hulls = hv;
  collide_gjk_epa(gj.la.soa(), gj.lb.soa(), gj.out.view(), Range{0, gj.n()}, cfg, kLeafConvex,
                  kLeafEllipsoid);
  int large = 0, hits = 0;
  for (uint32_t k = 0; k < run.n(); ++k) {
    if (c.a[k].hull != 22) continue;
    ++large;
    const test::PairResult x = run.out.result(k), y = gj.out.result(k);
    ASSERT_EQ(x.count, y.count) << k;
    if (x.count == 0) continue;
    ++hits;
    EXPECT_EQ(x.depth, y.depth) << k;
    EXPECT_EQ(x.n, y.n) << k;
  }
  EXPECT_GT(large, static_cast<int>(run.n()) / 4);
  EXPECT_GT(hits, 0);
}

}  // namespace
}  // namespace impact::kernels
