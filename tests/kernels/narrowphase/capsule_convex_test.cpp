// Capsule against convex hull (kernels/narrowphase/pairs/capsule/capsule_convex.cpp, collide_capsule_convex)
// against an independent double-precision reference: the hull's polygons (HullData from
// build_convex_hull) posed in double relative to the hull position, face planes by
// Newell's method from the polygon vertices (not the kernel's float planes):
//  - the signed distance of a point to the hull (outside: the least point-to-polygon
//    distance over all faces; inside: minus the least plane distance);
//  - the core segment's least signed distance m = min_t sd(c + t u), by golden-section
//    search (sd is convex along a line), no closest-feature logic;
//  - m > 0 (core outside): depth_ref = r - m, normal from the core point at the
//    minimum to its closest hull point (unique: the offset of two disjoint convex sets'
//    closest points is);
//  - m <= 0 (core meets the hull): depth_ref = r + min over the axes n of every face
//    normal and every polygon edge x u (both signs) of max_S n.x - min_hull n.x, the
//    supports by brute force over the vertices.
// Per lane, tol = kRel * L (L = the larger of r + h and the hull's bounding radius):
//  (a) count > 0 iff depth_ref > 0 (either answer where |depth_ref| <= tol), count <= 2;
//  (b) |depth - depth_ref| <= tol;
//  (c) n unit (1e-6), depth is the capsule-hull overlap along n (brute-force supports)
//      within tol; where the reference normal is unique (core outside by more than
//      1e-3 L, or the two best axes more than 1e-3 L apart) angle(n, n_ref) <= 1e-3 rad;
//  (d) every point lies within depth/2 + tol of both surfaces (signed distances), with
//      0 < pdepth <= depth + tol;
//  (e) kSimd and kScalar give the same bytes; the general GJK / EPA path agrees on hits
//      away from touching (1e-3 L) and on depth within 1e-3 L.
// Scenarios: random poses around random hulls (boxes and 8..40-point clouds, about half
// overlapping, core outside / through / inside), tiny (1e-4) and huge (1e4) scales,
// poses 1e5 from the origin, a round hull of ~800 faces, exact features on a box (lying
// on a face: two points, as capsule-box gives; touching exactly: count 0; along an
// edge, an end near a vertex, core through and wholly inside, sunk along an edge
// direction where a face axis and edge axes tie exactly: the face wins), the capsule-box
// kernel's points for capsules lying on a box hull's face, nearly coplanar faces (plane
// distances tied up to float rounding), zero-length cores (sphere-hull's answers), a
// hull view without edge adjacency (the GJK / EPA fallback, same bytes as that path).
// Registration and range partitions: contract_test.cpp.
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <iterator>
#include <random>
#include <string>
#include <vector>

#include "host/shapes/convex_hull.h"
#include "host/shapes/shape_store.h"
#include "kernels/narrowphase/pair_kernels.h"
#include "support/hull_input.h"
#include "support/leaf_lanes.h"
#include "support/random_input.h"
#include "support/test_support.h"

namespace impact::test {
namespace {

namespace k = kernels;
using namespace hull_input;  // NOLINT: the hull tests' shared inputs

constexpr double kRel = 2e-5;  // of L; float arithmetic gives ~1e-6

// --- lanes ------------------------------------------------------------------------------------

struct Pair {
  float c[3];     // capsule centre
  float Ra[9];    // capsule rotation, row-major (column 2 = axis)
  float r, h;     // radius, half length
  float p[3];     // hull position
  float R[9];     // hull rotation, row-major
  uint32_t hull;  // index in Hulls
};

/// The capsule and the hull of a lane.
std::pair<test::Leaf, test::Leaf> leaves(const Pair& q) {
  test::Leaf a;
  a.t = k::kLeafCapsule;
  std::copy(q.c, q.c + 3, a.p);
  std::copy(q.Ra, q.Ra + 9, a.r);
  a.e[0] = q.r, a.e[1] = q.h;
  return {a, hull_leaf(q)};
}

struct Bucket : test::BucketLanes {
  explicit Bucket(const std::vector<Pair>& v) : BucketLanes(v, leaves) {}
};

ManifoldLanes run(k::PairKernel kern, const Bucket& bk, const k::HullView& hv, k::KernelPath path) {
  return bk.run(kern, hv, path);
}

// --- the reference ---------------------------------------------------------------------------

/// Signed distance of y to the hull (> 0 outside) and, outside, the closest hull point.
double signed_distance(const RefHull& H, D3 y, D3* closest = nullptr) {
  double best = -1e300;
  for (size_t f = 0; f < H.faces.size(); ++f) best = std::max(best, dot(H.fn[f], y) - H.fd[f]);
  if (best <= 0) return best;
  double dmin = 1e300;
  D3 x;
  for (size_t f = 0; f < H.faces.size(); ++f) {
    const auto& poly = H.faces[f];
    bool in = true;
    for (size_t i = 0; i < poly.size(); ++i) {
      const D3 p = H.v[poly[i]], q = H.v[poly[(i + 1) % poly.size()]];
      if (dot(cross(q - p, H.fn[f]), y - p) > 0) in = false;
    }
    if (in) {
      const double s = dot(H.fn[f], y) - H.fd[f];
      if (std::fabs(s) < dmin) dmin = std::fabs(s), x = y - s * H.fn[f];
    }
    for (size_t i = 0; i < poly.size(); ++i) {
      const D3 e = closest_on_segment(H.v[poly[i]], H.v[poly[(i + 1) % poly.size()]], y);
      if (norm(e - y) < dmin) dmin = norm(e - y), x = e;
    }
  }
  if (closest != nullptr) *closest = x;
  return dmin;
}

struct RefAnswer {
  double depth = 0;  // r - distance (outside) or r + penetration (core meets the hull)
  bool meets = false;
  D3 n;              // unit, capsule to hull
  bool unique = false;
};

/// Overlap of the capsule (core c -+ h u, radius r) and the hull along unit n (capsule to
/// hull): how far the hull must move along n to separate.
double overlap_along(const RefHull& H, D3 c, D3 u, double h, double r, D3 n) {
  double lo = 1e300;
  for (const D3& v : H.v) lo = std::min(lo, dot(n, v));
  return dot(n, c) + h * std::fabs(dot(n, u)) + r - lo;
}

RefAnswer reference(const RefHull& H, D3 c, D3 u, double h, double r) {
  RefAnswer a;
  const double L = std::max(r + h, H.radius);
  // Golden-section search of the least signed distance along the core.
  auto sd = [&](double t) { return signed_distance(H, c + t * u); };
  double lo = -h, hi = h;
  const double phi = 0.5 * (std::sqrt(5.0) - 1.0);
  double x1 = hi - phi * (hi - lo), x2 = lo + phi * (hi - lo), f1 = sd(x1), f2 = sd(x2);
  for (int it = 0; it < 90 && hi - lo > 1e-15 * L; ++it) {
    if (f1 <= f2) {
      hi = x2, x2 = x1, f2 = f1, x1 = hi - phi * (hi - lo), f1 = sd(x1);
    } else {
      lo = x1, x1 = x2, f1 = f2, x2 = lo + phi * (hi - lo), f2 = sd(x2);
    }
  }
  double tm = 0.5 * (lo + hi), m = sd(tm);
  for (const double t : {-h, h}) {
    const double s = sd(t);
    if (s < m) m = s, tm = t;
  }
  if (m > 0) {
    D3 y;
    signed_distance(H, c + tm * u, &y);
    a.depth = r - m;
    a.n = unit(y - (c + tm * u));
    a.unique = m > 1e-3 * L;
    return a;
  }
  // The core meets the hull: least overlap over face normals and edge x axis.
  std::vector<D3> axes = H.fn;
  for (const auto& poly : H.faces)
    for (size_t i = 0; i < poly.size(); ++i) {
      const D3 l = cross(u, H.v[poly[(i + 1) % poly.size()]] - H.v[poly[i]]);
      if (norm(l) > 1e-9 * L * L) axes.push_back(unit(l));
    }
  double best = 1e300, second = 1e300;
  for (const D3& ax : axes)
    for (const double sgn : {1.0, -1.0}) {
      const D3 n = sgn * ax;
      const double o = overlap_along(H, c, u, h, r, n);
      if (o < best - 1e-12 * L) {
        if (norm(n - a.n) > 1e-6) second = best;
        best = o, a.n = n;
      } else if (o < second && norm(n - a.n) > 1e-6) {
        second = o;
      }
    }
  a.meets = true;
  a.depth = best;
  a.unique = second - best > 1e-3 * L;
  return a;
}

/// Signed distance of y to the capsule.
double capsule_sd(D3 c, D3 u, double h, double r, D3 y) {
  return norm(y - closest_on_segment(c - h * u, c + h * u, y)) - r;
}

// --- the checks ------------------------------------------------------------------------------

struct Stats {
  uint32_t hits = 0, misses = 0, meets = 0, two = 0;
  double worst_depth = 0;  // / L
};

std::string lane_text(const Pair& q) {
  char buf[640];
  std::snprintf(buf, sizeof buf,
                "capsule c={%.9g, %.9g, %.9g} axis={%.9g, %.9g, %.9g} r=%.9g h=%.9g; hull %u p={%.9g, %.9g, "
                "%.9g} R={%.9g, %.9g, %.9g, %.9g, %.9g, %.9g, %.9g, %.9g, %.9g}",
                q.c[0], q.c[1], q.c[2], q.Ra[2], q.Ra[5], q.Ra[8], q.r, q.h, q.hull, q.p[0], q.p[1], q.p[2], q.R[0],
                q.R[1], q.R[2], q.R[3], q.R[4], q.R[5], q.R[6], q.R[7], q.R[8]);
  return buf;
}

/// Runs both paths and GJK / EPA on `pairs` and checks every lane; returns the counts.
Stats check_pairs(const std::string& name, const std::vector<Pair>& pairs, const Hulls& hulls) {
  SCOPED_TRACE(name);
  Stats st;
  const Bucket bk(pairs);
  const k::HullView hv = hulls.store.view();
  const k::PairKernel kern = k::pair_kernel(k::kLeafCapsule, k::kLeafConvex);
  EXPECT_EQ(kern, &k::collide_capsule_convex);
  const ManifoldLanes simd = run(kern, bk, hv, k::KernelPath::kSimd);
  const ManifoldLanes scalar = run(kern, bk, hv, k::KernelPath::kScalar);
  const ManifoldLanes gjk = run_gjk_epa<k::kLeafCapsule>(bk, hv);
  int failures = 0;
  for (uint32_t i = 0; i < bk.n && failures < 10; ++i) {
    const Pair& q = pairs[i];
    const RefHull H = pose(hulls.data[q.hull], q);
    const D3 c = D3{q.c[0], q.c[1], q.c[2]} - H.origin;  // exact in double
    const D3 u{q.Ra[2], q.Ra[5], q.Ra[8]};
    const double r = q.r, h = q.h;
    const double L = std::max(r + h, H.radius);
    const double tol = kRel * L;
    const RefAnswer ref = reference(H, c, u, h, r);
    const int before = failure_parts();
    SCOPED_TRACE("lane " + std::to_string(i) + ": " + lane_text(q) + "; depth_ref=" + std::to_string(ref.depth) +
                 (ref.meets ? " (core meets)" : " (core outside)"));

    EXPECT_EQ(simd.lane_bits(i), scalar.lane_bits(i)) << "paths differ";
    const PairResult res = simd.result(i);
    EXPECT_LE(res.count, 2u);
    if (std::fabs(ref.depth) > tol) {
      EXPECT_EQ(res.count > 0, ref.depth > 0) << "hit disagrees";
    }
    if (res.count > 0 && res.count <= 2) {
      ++st.hits;
      st.meets += ref.meets ? 1 : 0;
      st.two += res.count == 2 ? 1 : 0;
      const D3 n{res.n.x(), res.n.y(), res.n.z()};
      const double depth = res.depth;
      EXPECT_TRUE(std::isfinite(n.x) && std::isfinite(n.y) && std::isfinite(n.z) && std::isfinite(depth));
      EXPECT_NEAR(norm(n), 1.0, 1e-6);
      EXPECT_NEAR(depth, ref.depth, tol);
      st.worst_depth = std::max(st.worst_depth, std::fabs(depth - ref.depth) / L);
      EXPECT_NEAR(overlap_along(H, c, u, h, r, n), depth, tol) << "depth is not the overlap along n";
      if (ref.unique) {
        EXPECT_GE(dot(n, ref.n), std::cos(1e-3))
            << "normal; reference " << ref.n.x << ", " << ref.n.y << ", " << ref.n.z;
      }
      for (uint32_t j = 0; j < res.count; ++j) {
        const D3 pw{res.pt[j].x(), res.pt[j].y(), res.pt[j].z()};
        const double ulp = std::max({std::fabs(pw.x), std::fabs(pw.y), std::fabs(pw.z)}) * 0x1p-23;
        const D3 pt = pw - H.origin;
        const double lim = 0.5 * depth + tol + 2 * ulp;
        EXPECT_LE(std::fabs(capsule_sd(c, u, h, r, pt)), lim) << "point " << j << " off the capsule's surface";
        EXPECT_LE(std::fabs(signed_distance(H, pt)), lim) << "point " << j << " off the hull's surface";
        EXPECT_GT(res.pd[j], 0.0) << "pdepth " << j;
        EXPECT_LE(res.pd[j], depth + tol) << "pdepth " << j;
      }
    } else {
      ++st.misses;
    }
    // The general path: same hits away from touching, depth within 1e-3 L.
    const double tg = 1e-3 * L;
    if (std::fabs(ref.depth) > tg) {
      EXPECT_EQ(gjk.count[i] > 0, res.count > 0) << "GJK/EPA disagrees on the hit";
    }
    if (gjk.count[i] > 0 && res.count > 0) {
      EXPECT_NEAR(gjk.depth[i], res.depth, tg) << "GJK/EPA depth";
    }
    if (failure_parts() != before) ++failures;  // stop after 10 failing lanes
  }
  return st;
}

/// The capsule's centre c rounded to float.
void set_c(Pair* q, D3 c) {
  store_float(c, q->c);
}

/// A row-major rotation whose column 2 is the unit axis a (float rounded).
void axis_rotation(D3 a, float m[9]) {
  a = unit(a);
  const D3 t = unit(cross(a, std::fabs(a.x) < 0.6 ? D3{1, 0, 0} : D3{0, 1, 0}));
  const D3 b = cross(a, t);
  const D3 col[3] = {t, b, a};
  for (int r = 0; r < 3; ++r)
    for (int cc = 0; cc < 3; ++cc) {
      const D3& v = col[cc];
      m[3 * r + cc] = static_cast<float>(r == 0 ? v.x : (r == 1 ? v.y : v.z));
    }
}

/// Random lanes around hulls [h0, h1) of size ~scale at ~offset from the origin: the
/// capsule centre anywhere near the hull, near a vertex, an edge or a face; random axes.
std::vector<Pair> random_pairs(Rng& g, const Hulls& hulls, uint32_t h0, uint32_t h1, uint32_t n, double scale,
                               double offset) {
  return draw_cases(static_cast<int>(n), [&](int) {
    Pair q;
    random_hull_and_rotation(g, h0, h1, &q);
    random_rotation(g, q.Ra);
    random_hull_position(g, scale, offset, q.p);
    q.r = static_cast<float>(scale * uni(g, 0.05, 0.8));
    q.h = static_cast<float>(scale * (g() % 8 == 0 ? 0.0 : uni(g, 0.0, 1.0)));
    const HullData& h = hulls.data[q.hull];
    const double reach = q.r + q.h;
    Near where;
    D3 nw;
    const D3 c = point_near_hull(g, h, q, scale, reach, 1.3, &where, &nw);
    // Half of those near a face lie (nearly) parallel to it.
    if (where == Near::kFace && (g() & 1))
      axis_rotation(cross(nw, random_unit(g)) + uni(g, -0.03, 0.03) * nw, q.Ra);
    set_c(&q, c);
    return q;
  });
}

// --- tests ------------------------------------------------------------------------------------

TEST(CapsuleConvex, RandomPosesAgreeWithReference) {
  size_t n = 0;
  const Stats st = check_random_suite(random_pairs, check_pairs, &n);
  // Every branch exercised: misses, hits with the core outside and meeting the hull,
  // two-point contacts.
  EXPECT_GT(st.misses, n / 10);
  EXPECT_GT(st.hits - st.meets, n / 10);
  EXPECT_GT(st.meets, n / 20);
  EXPECT_GT(st.two, n / 50);
  RecordProperty("worst_depth_rel", std::to_string(st.worst_depth));
}

TEST(CapsuleConvex, TinyHugeFarAndManyFaceHulls) {
  check_scale_suites(random_pairs, check_pairs, 300u, 50u, 30u);
}

/// A capsule lane in a box hull's frame (identity rotation, hull at p).
Pair box_lane(D3 p, D3 c, D3 axis, double r, double h) {
  Pair q;
  const float I[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  std::copy(I, I + 9, q.R);
  axis_rotation(axis, q.Ra);
  store_float(p, q.p);
  set_c(&q, p + c);
  q.r = static_cast<float>(r);
  q.h = static_cast<float>(h);
  q.hull = 0;
  return q;
}

TEST(CapsuleConvex, ExactFeaturesOnABox) {
  // Box hull 1 x 0.5 x 0.25 (half extents), exact floats; capsule r = 0.3125, h = 0.5.
  Hulls hulls;
  hulls.add(box_corners(1.0f, 0.5f, 0.25f));
  const D3 p{3.0, -2.0, 1.0};
  const double r = 0.3125, h = 0.5, e = 1.0 / 1024;
  std::vector<Pair> pairs;
  // 0: lying on the top face (+y), 1/1024 deep: two points, each 1/1024 deep.
  pairs.push_back(box_lane(p, {0.125, 0.5 + r - e, 0.0}, {1, 0, 0}, r, h));
  // 1: touching the top face exactly: count 0.
  pairs.push_back(box_lane(p, {0.125, 0.5 + r, 0.0}, {1, 0, 0}, r, h));
  // 2: lying on the top face, overhanging the +x edge: two points, the outer one at
  //    the edge (clipped to the face).
  pairs.push_back(box_lane(p, {1.0, 0.5 + r - e, 0.0}, {1, 0, 0}, r, h));
  // 3: along the edge (+y, +z), parallel to it, touching it at 45 degrees, 1/1024 deep.
  pairs.push_back(box_lane(p, D3{0.0, 0.5, 0.25} + (r - e) * unit(D3{0, 1, 1}), {1, 0, 0}, r, h));
  // 4: an end point near the vertex (1, 0.5, 0.25), the core pointing away from it.
  pairs.push_back(box_lane(p, D3{1.0, 0.5, 0.25} + (r - e + h) * unit(D3{1, 1, 1}), {1, 1, 1}, r, h));
  // 5: standing on the top face, 1/16 deep: one point (below the lower end).
  pairs.push_back(box_lane(p, {0.25, 0.5 + h + r - 1.0 / 16, 0.0}, {0, 1, 0}, r, h));
  // 6: core through the box along z (deep): exit by the +y face (the least overlap:
  //    0.5 - 0.375 + r) or push along y.
  pairs.push_back(box_lane(p, {0.0, 0.375, 0.0}, {0, 0, 1}, r, h));
  // 7: core wholly inside, along x, at the centre: out through +-z: depth 0.25 + r.
  pairs.push_back(box_lane(p, {0.0, 0.0, 0.0}, {1, 0, 0}, r, 0.25));
  // 8: core crossing the box diagonally in the xy plane (an edge axis may win).
  pairs.push_back(box_lane(p, {0.9, 0.45, 0.0}, {1, -1, 0.3}, 0.0625, h));
  // 9: sunk 1/16 below the top face along x: the face axis +y ties with the edge axes
  //    x x z (= -+y) exactly and must win the tie: two points, depth r + 1/16.
  pairs.push_back(box_lane(p, {0.125, 0.5 - 1.0 / 16, 0.0}, {1, 0, 0}, r, h));
  // 10-12: one end just inside the top face's +x edge, 1/1024 under the top plane, the
  //    core slanting down past the edge (slopes 2e-3, 5e-4, 1e-4). The least distance
  //    lies past the edge, less than 1e-6 below the end's plane distance (within the
  //    face-over-edge tie), but the top face's normal is no contact normal: the overlap
  //    along it is up to 2e-3 larger than the depth. The edge's normal must win (the
  //    overlap along n is the depth: check_pairs). Seen at IMPACT_TEST_INTENSITY=30 in
  //    RandomPosesAgreeWithReference (8.2e-5 off), 2026-11-29.
  for (const double slope : {2e-3, 5e-4, 1e-4}) {
    const D3 u = unit(D3{1.0, -slope, 0.0});
    pairs.push_back(box_lane(p, D3{1.0 - 1e-5, 0.5 + r - e, 0.0} + h * u, u, r, h));
  }
  const Stats st = check_pairs("box features", pairs, hulls);
  EXPECT_EQ(st.hits, 12u);
  const Bucket bk(pairs);
  const ManifoldLanes o = run(&k::collide_capsule_convex, bk, hulls.store.view(), k::KernelPath::kSimd);
  // 0: n = -y, depth 1/1024, two points at x = 3 +- 0.375 (+0.125), y = p.y + 0.5 - e/2.
  ASSERT_EQ(o.count[0], 2);
  EXPECT_EQ(o.n[1][0], -1.0f);
  EXPECT_NEAR(o.depth[0], e, 1e-6);
  EXPECT_NEAR(std::min(o.pt[0][0][0], o.pt[1][0][0]), 3.0 + 0.125 - h, 1e-6);
  EXPECT_NEAR(std::max(o.pt[0][0][0], o.pt[1][0][0]), 3.0 + 0.125 + h, 1e-6);
  EXPECT_NEAR(o.pt[0][1][0], -2.0 + 0.5 - e / 2, 1e-6);
  EXPECT_NEAR(o.pd[0][0], e, 1e-6);
  EXPECT_NEAR(o.pd[1][0], e, 1e-6);
  EXPECT_EQ(o.count[1], 0);
  // 2: clipped to the face: the outer point at the edge x = 1 (world 4).
  ASSERT_EQ(o.count[2], 2);
  EXPECT_NEAR(std::max(o.pt[0][0][2], o.pt[1][0][2]), 4.0, 1e-6);
  EXPECT_NEAR(std::min(o.pt[0][0][2], o.pt[1][0][2]), 3.5, 1e-6);
  // 3: the edge normal (0, -1, -1)/sqrt 2, depth 1/1024.
  ASSERT_GE(o.count[3], 1);
  EXPECT_NEAR(o.n[1][3], -std::sqrt(0.5), 1e-5);
  EXPECT_NEAR(o.n[2][3], -std::sqrt(0.5), 1e-5);
  EXPECT_NEAR(o.depth[3], e, 1e-6);
  // 4: the vertex normal -(1, 1, 1)/sqrt 3.
  ASSERT_EQ(o.count[4], 1);
  EXPECT_NEAR(o.n[0][4], -1 / std::sqrt(3.0), 1e-5);
  EXPECT_NEAR(o.depth[4], e, 1e-5);
  // 5: standing: one point, depth 1/16.
  ASSERT_EQ(o.count[5], 1);
  EXPECT_NEAR(o.depth[5], 1.0 / 16, 1e-6);
  // 7: through +-z.
  ASSERT_GE(o.count[7], 1);
  EXPECT_NEAR(o.depth[7], 0.25 + r, 1e-6);
  EXPECT_EQ(std::fabs(o.n[2][7]), 1.0f);
  // 9: the face wins the tie.
  ASSERT_EQ(o.count[9], 2);
  EXPECT_EQ(o.n[1][9], -1.0f);
  EXPECT_NEAR(o.depth[9], r + 1.0 / 16, 1e-6);
}

TEST(CapsuleConvex, NearlyCoplanarFaces) {
  // A cube whose top corner (1, 1, 1) is raised by 2^-22: the top becomes two triangles
  // whose planes differ by ~1e-7 rad, the float rounding of the plane distances. An end
  // point's deepest plane in float is then often the wrong triangle, while it projects
  // into the other: the near-tie faces must be tried (else the nearest point falls to
  // the ridge edge, farther away).
  Hulls hulls;
  add_nearly_coplanar_cube(&hulls);
  Rng g(8);
  std::vector<Pair> pairs;
  for (int i = 0; i < 400; ++i) {
    const D3 p{uni(g, -3, 3), uni(g, -3, 3), uni(g, -3, 3)};
    // Standing on the top (the lower end point nearest), or tilted steeply.
    const D3 axis = unit(D3{uni(g, -0.5, 0.5), uni(g, -0.5, 0.5), 1.0});
    const double r = 0.6, h = uni(g, 0.0, 0.5);
    const D3 c = D3{uni(g, -0.9, 0.9), uni(g, -0.9, 0.9), 1.0 + uni(g, 0.05, 0.5)} + h * axis;
    pairs.push_back(box_lane(p, c, axis, r, h));
  }
  const Stats st = check_pairs("nearly coplanar", pairs, hulls);
  EXPECT_GT(st.hits, 200u);
}

TEST(CapsuleConvex, TwoPointsAsCapsuleBox) {
  // A box hull and the same box as a box leaf: a capsule lying on (or sunk into) a face
  // gets the same count, normal, depth and points from both kernels.
  Rng g(606);
  Hulls hulls;
  const float ex = 0.75f, ey = 0.5f, ez = 0.625f;
  hulls.add(box_corners(ex, ey, ez));
  std::vector<Pair> pairs;
  for (int i = 0; i < 200; ++i) {
    Pair q;
    random_rotation(g, q.R);
    const D3 p{uni(g, -5, 5), uni(g, -5, 5), uni(g, -5, 5)};
    store_float(p, q.p);
    q.hull = 0;
    q.r = static_cast<float>(uni(g, 0.1, 0.4));
    q.h = static_cast<float>(uni(g, 0.1, 0.6));
    // Above the +y face, axis within ~1.5 degrees of the face, depth up to 0.2.
    const D3 cl{uni(g, -0.5, 0.5), ey + q.r - uni(g, 0.001, 0.2), uni(g, -0.4, 0.4)};
    const double ang = uni(g, 0, 6.28);
    const D3 al{std::cos(ang), uni(g, -0.025, 0.025), std::sin(ang)};
    Pair world = q;
    set_c(&world, to_world(q, Eigen::Vector3f(static_cast<float>(cl.x), static_cast<float>(cl.y),
                                              static_cast<float>(cl.z))));
    const D3 aw = to_world(q, Eigen::Vector3f(static_cast<float>(al.x), static_cast<float>(al.y),
                                              static_cast<float>(al.z))) -
                  to_world(q, Eigen::Vector3f::Zero());
    axis_rotation(aw, world.Ra);
    pairs.push_back(world);
  }
  const Stats st = check_pairs("on a face", pairs, hulls);
  EXPECT_GT(st.two, 150u);
  const Bucket bk(pairs);
  const ManifoldLanes hull = run(&k::collide_capsule_convex, bk, hulls.store.view(), k::KernelPath::kSimd);
  // The box leaf: same pose, half extents.
  std::vector<float> be[3];
  for (uint32_t i = 0; i < bk.n; ++i) be[0].push_back(ex), be[1].push_back(ey), be[2].push_back(ez);
  k::LeafSoA b = bk.b();
  for (int j = 0; j < 3; ++j) b.e[j] = be[j].data();
  ManifoldLanes box(bk.n);
  k::NarrowConfig cfg;
  const k::LeafSoA a = bk.a();
  k::collide_capsule_box(a, b, box.view(), k::Range{0, bk.n}, cfg);
  for (uint32_t i = 0; i < bk.n; ++i) {
    SCOPED_TRACE("lane " + std::to_string(i) + ": " + lane_text(pairs[i]));
    const PairResult x = hull.result(i), y = box.result(i);
    ASSERT_EQ(x.count, y.count);
    if (x.count == 0) continue;
    EXPECT_LT((x.n - y.n).norm(), 1e-5);
    EXPECT_NEAR(x.depth, y.depth, 2e-6);
    // Same points, in either order.
    for (uint32_t j = 0; j < x.count; ++j) {
      double dmin = 1e300;
      for (uint32_t l = 0; l < y.count; ++l) dmin = std::min(dmin, (x.pt[j] - y.pt[l]).norm());
      EXPECT_LT(dmin, 2e-5) << "point " << j;
    }
  }
}

TEST(CapsuleConvex, ZeroLengthCoreIsSphereHull) {
  // h = 0: the sphere-hull kernel's answer (same planes, same edge rule), on random lanes.
  Rng g(31337);
  Hulls hulls;
  add_random_hulls(g, &hulls, 12, 1.0);
  auto pairs = random_pairs(g, hulls, 0, 12, scaled(1500), 1.0, 0.0);
  for (Pair& q : pairs) q.h = 0.0f;
  const Stats st = check_pairs("zero length", pairs, hulls);
  EXPECT_GT(st.hits, 200u);
  const Bucket bk(pairs);
  const ManifoldLanes caps = run(&k::collide_capsule_convex, bk, hulls.store.view(), k::KernelPath::kSimd);
  const ManifoldLanes sph = run(&k::collide_sphere_convex, bk, hulls.store.view(), k::KernelPath::kSimd);
  for (uint32_t i = 0; i < bk.n; ++i) {
    SCOPED_TRACE("lane " + std::to_string(i) + ": " + lane_text(pairs[i]));
    const PairResult x = caps.result(i), y = sph.result(i);
    ASSERT_EQ(x.count, y.count);
    if (x.count == 0) continue;
    EXPECT_LT((x.n - y.n).norm(), 1e-5);
    EXPECT_NEAR(x.depth, y.depth, 1e-6);
    EXPECT_LT((x.pt[0] - y.pt[0]).norm(), 1e-5);
  }
}

TEST(CapsuleConvex, WithoutEdgeAdjacencyTakesTheGeneralPath) {
  Rng g(2024);
  Hulls hulls;
  add_random_hulls(g, &hulls, 8, 1.0);
  const auto pairs = random_pairs(g, hulls, 0, 8, scaled(400), 1.0, 0.0);
  const Bucket bk(pairs);
  k::HullView no_adj = hulls.store.view();
  no_adj.adj_begin = nullptr;
  const ManifoldLanes o = run(&k::collide_capsule_convex, bk, no_adj, k::KernelPath::kSimd);
  const ManifoldLanes gjk = run_gjk_epa<k::kLeafCapsule>(bk, no_adj);
  uint32_t hits = 0;
  for (uint32_t i = 0; i < bk.n; ++i) {
    EXPECT_EQ(o.lane_bits(i), gjk.lane_bits(i)) << i;
    hits += o.count[i] > 0 ? 1 : 0;
  }
  EXPECT_GT(hits, 50u);
}

}  // namespace
}  // namespace impact::test
