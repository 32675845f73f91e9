// collide_convex_halfspace (kernels/narrowphase/pairs/convex/convex_halfspace.cpp) against an
// independent brute force in double: every hull vertex posed in double, its depth below
// the plane; the deepest gives the depth, and the picks are checked by what they must
// maximise (the farthest vertex below from point 0, the largest area about the normal,
// the farthest outside the triangle), with vertices within rounding of the plane or of a
// tie allowed either way. Hulls: a tetrahedron, boxes (many exact ties), ellipsoid clouds
// of 24, 64 (the lane walk's largest) and 65 vertices (the per-pair fallback), ~250
// vertices, tiny (1e-4) and huge (1e4) hulls, needle and pancake boxes (1e-4). Poses:
// random (about half touching), 1e5 from the origin, deep (entirely below), touching,
// planes exactly through a face and a vertex. Also: the SIMD path against the scalar
// path and against collide_support_halfspace (the per-pair routine it replaces: the same
// rule). Registration, range partitions and shuffled buckets, and the agreement with the
// general route (collide_support_halfspace): contract_test.cpp.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <numeric>
#include <random>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "kernels/narrowphase/pair_kernels.h"
#include "support/hull_input.h"
#include "support/leaf_lanes.h"
#include "support/random_input.h"
#include "support/test_support.h"

namespace impact::kernels {
namespace {

using Vec3d = Eigen::Vector3d;
using Mat3d = Eigen::Matrix3d;
using test::hull_input::Hulls;

/// A hull lane (A) and its plane (B), float-exact doubles.
struct Case {
  Vec3d p = Vec3d::Zero();
  Mat3d R = Mat3d::Identity();
  Vec3d e = Vec3d::Zero();
  uint32_t hull = 0;
  Vec3d pb = Vec3d::Zero(), nh = Vec3d::UnitZ();  // solid: nh.(x - pb) <= 0
};

enum HullId : uint32_t { kTetra, kBox, kCloud24, kCloud64, kCloud65, kBig, kTiny, kHuge, kNeedle, kPancake, kHullKinds };
/// Hulls whose vertex counts are no multiple of the SIMD width (the listing pass's
/// clamped last step), used by the tests that name them.
enum OddHullId : uint32_t { kCloud13 = kHullKinds, kCloud30, kCloud47, kAllHulls };

struct TestHulls {
  Hulls h;
  uint32_t id[kAllHulls];
  double size[kAllHulls];  // bounding radius
};

/// An ellipsoid cloud whose hull has exactly `want` vertices (draws until it has).
std::vector<Eigen::Vector3f> cloud_with(std::mt19937& g, uint32_t want) {
  for (;;) {
    auto pts = test::hull_input::ellipsoid_points(g, static_cast<int>(want), 1.0);
    HullData d;
    if (build_convex_hull(pts, &d).ok() && d.vertices.size() == want) return pts;
  }
}

const TestHulls& hulls() {
  static const TestHulls t = [] {
    TestHulls r;
    std::mt19937 g(77);
    auto add = [&](HullId k, const std::vector<Eigen::Vector3f>& pts) {
      r.id[k] = r.h.add(pts);
      double rad = 0;
      for (const auto& v : r.h.data.back().vertices) rad = std::max(rad, static_cast<double>(v.norm()));
      r.size[k] = rad;
    };
    add(kTetra, {{1, 0.1f, -0.3f}, {-0.4f, 0.9f, -0.2f}, {-0.5f, -0.8f, -0.3f}, {0.1f, 0, 1}});
    add(kBox, test::hull_input::box_corners(1.0f, 0.7f, 0.5f));
    add(kCloud24, test::hull_input::ellipsoid_points(g, 24, 1.0));
    add(kCloud64, cloud_with(g, 64));
    add(kCloud65, cloud_with(g, 65));
    add(kBig, test::hull_input::ellipsoid_points(g, 260, 1.0));
    add(kTiny, test::hull_input::ellipsoid_points(g, 24, 1e-4));
    add(kHuge, test::hull_input::ellipsoid_points(g, 24, 1e4));
    add(kNeedle, test::hull_input::box_corners(1.0f, 1e-4f, 1e-4f));
    add(kPancake, test::hull_input::box_corners(1.0f, 1.0f, 1e-4f));
    add(static_cast<HullId>(kCloud13), cloud_with(g, 13));
    add(static_cast<HullId>(kCloud30), cloud_with(g, 30));
    add(static_cast<HullId>(kCloud47), cloud_with(g, 47));
    return r;
  }();
  return t;
}

TEST(ConvexHalfspace, HullsHaveTheSizesTheTestsNeed) {
  const TestHulls& t = hulls();
  EXPECT_EQ(t.h.data[t.id[kTetra]].vertices.size(), 4u);
  EXPECT_EQ(t.h.data[t.id[kCloud64]].vertices.size(), 64u);
  EXPECT_EQ(t.h.data[t.id[kCloud65]].vertices.size(), 65u);
  EXPECT_GT(t.h.data[t.id[kBig]].vertices.size(), 200u);
  EXPECT_EQ(pair_kernel(kLeafConvex, kLeafHalfSpace), &collide_convex_halfspace);
}

/// Runs the kernel (or the old per-pair routine) over the bucket, in the given pieces.
test::ManifoldLanes run(const std::vector<Case>& cs, KernelPath path, bool old = false,
                        const std::vector<uint32_t>& cuts = {}) {
  test::LeafLanes a, b;
  for (const Case& c : cs) {
    a.push(c);
    Case pl;
    pl.p = c.pb;
    pl.e = c.nh;
    pl.R = Mat3d::Zero();
    b.push(pl);
  }
  const auto n = static_cast<uint32_t>(cs.size());
  test::ManifoldLanes out(n);
  NarrowConfig cfg;
  cfg.hulls = hulls().h.store.view();
  cfg.path = path;
  std::vector<uint32_t> bounds = {0};
  for (uint32_t c : cuts) bounds.push_back(c);
  bounds.push_back(n);
  for (size_t i = 0; i + 1 < bounds.size(); ++i) {
    const Range r{bounds[i], bounds[i + 1]};
    if (old) {
      collide_support_halfspace(a.soa(), b.soa(), out.view(), r, cfg, kLeafConvex);
    } else {
      collide_convex_halfspace(a.soa(), b.soa(), out.view(), r, cfg);
    }
  }
  return out;
}

/// The brute force: vertices in world coordinates relative to p (double), depths.
struct Ref {
  std::vector<Vec3d> w;  // relative to the case's p
  std::vector<double> d;
  double depth = -INFINITY;
  double size = 0;
};

Ref reference(const Case& c) {
  Ref r;
  const HullData& h = hulls().h.data[c.hull];
  const double off = c.nh.dot(c.pb - c.p);
  for (const auto& v : h.vertices) {
    r.w.push_back(c.R * v.cast<double>());
    r.d.push_back(off - c.nh.dot(r.w.back()));
    r.depth = std::max(r.depth, r.d.back());
    r.size = std::max(r.size, r.w.back().norm());
  }
  return r;
}

/// Float rounding of the depths: the hull's size and the plane's offset from p.
double depth_tol(const Case& c, const Ref& r) { return 4e-6 * r.size + 4e-7 * (c.pb - c.p).norm(); }

/// Checks lane k of out against the brute force; returns false on a failure.
bool check(const Case& c, const test::PairResult& res, const char* what, int k) {
  const Ref ref = reference(c);
  const double tol = depth_tol(c, ref);
  const double ptol = tol + 2.4e-7 * c.p.cwiseAbs().maxCoeff();  // world float points
  SCOPED_TRACE(testing::Message() << what << " case " << k << " hull " << c.hull << " depth " << ref.depth);
  const int fails = test::hull_input::failure_parts();
  if (std::fabs(ref.depth) > tol) {
    EXPECT_EQ(res.count > 0, ref.depth > 0);
  }
  if (res.count == 0) return test::hull_input::failure_parts() == fails;
  EXPECT_LE(res.count, 4u);
  EXPECT_EQ(res.n, (-c.nh).eval());
  EXPECT_NEAR(res.depth, ref.depth, tol);
  EXPECT_EQ(res.pd[0], res.depth);
  // Each point: a vertex below, moved up by half its depth; distinct vertices. The
  // vertex: of those within the point's rounding and not taken by an earlier point, the
  // one whose depth is nearest pd (far from the origin a tiny hull's vertices, or a
  // pancake's twin vertices, lie within one float spacing of each other).
  // The picks below are checked on those vertices (exact, in double).
  Vec3d x[4];
  size_t at[4] = {0, 0, 0, 0};
  bool ambiguous = false;  // a point that two vertices match within rounding
  for (uint32_t j = 0; j < res.count; ++j) {
    EXPECT_GT(res.pd[j], 0.0);
    EXPECT_LE(res.pd[j], res.depth);
    const Vec3d xj = res.pt[j] - c.nh * (0.5 * res.pd[j]) - c.p;
    double best = INFINITY;
    int matches = 0;
    for (size_t i = 0; i < ref.w.size(); ++i) {
      if ((ref.w[i] - xj).norm() > 2 * ptol || std::find(at, at + j, i) != at + j) continue;
      matches += std::fabs(ref.d[i] - res.pd[j]) <= tol ? 1 : 0;
      if (std::fabs(ref.d[i] - res.pd[j]) < best) {
        best = std::fabs(ref.d[i] - res.pd[j]);
        at[j] = i;
      }
    }
    EXPECT_LE(best, tol) << "point " << j << " is no vertex below with its depth (or one taken before)";
    ambiguous = ambiguous || matches > 1;
    x[j] = ref.w[at[j]];
  }
  // Far from the origin a needle's end (2e-4 across) lies within one float spacing of
  // the world points (~0.008 at 1e5): where two of its corners also share a depth within
  // rounding, which vertex a point is cannot be told, nor checked against the picks
  // (found at IMPACT_TEST_INTENSITY=25: the farthest pick measured from the twin).
  if (ambiguous) return test::hull_input::failure_parts() == fails;
  // The picks: each the best of the vertices surely below, and no better than the best
  // of those maybe below (within tol of the plane), up to rounding.
  const double span = 2 * ref.size;
  auto extreme = [&](auto score, double lim) {
    double m = -INFINITY;
    for (size_t i = 0; i < ref.w.size(); ++i)
      if (ref.d[i] > lim) m = std::max(m, score(ref.w[i]));
    return m;
  };
  auto far = [&](const Vec3d& w) { return (w - x[0]).norm(); };
  const double far_in = extreme(far, tol), far_maybe = extreme(far, -tol);
  const double farj = res.count >= 2 ? far(x[1]) : 0.0;
  const double ftol = 1e-5 * ref.size;  // the kernel's float distances in the hull frame
  EXPECT_GE(farj, far_in - ftol);
  EXPECT_LE(farj, far_maybe + ftol);
  if (res.count < 2) return test::hull_input::failure_parts() == fails;
  const Vec3d e01 = x[1] - x[0];
  auto area = [&](const Vec3d& w) { return std::fabs(c.nh.dot(e01.cross(w - x[0]))); };
  const double atol = 4 * ftol * span + 2e-6 * e01.squaredNorm();
  const double a_in = extreme(area, tol), a_maybe = extreme(area, -tol);
  const double aj = res.count >= 3 ? area(x[2]) : 0.0;
  EXPECT_GE(aj, a_in - atol);
  EXPECT_LE(aj, a_maybe + atol);
  if (res.count < 3) return test::hull_input::failure_parts() == fails;
  const double sgn = c.nh.dot(e01.cross(x[2] - x[0])) >= 0 ? 1.0 : -1.0;
  auto outside = [&](const Vec3d& w) {
    double o = -INFINITY;
    for (int j = 0; j < 3; ++j) {
      const Vec3d& p = x[j];
      const Vec3d& q = x[(j + 1) % 3];
      o = std::max(o, -sgn * c.nh.dot((q - p).cross(w - p)));
    }
    return o;
  };
  const double o_in = extreme(outside, tol), o_maybe = extreme(outside, -tol);
  const double oj = res.count >= 4 ? outside(x[3]) : 0.0;
  EXPECT_GE(oj, o_in - atol);
  EXPECT_LE(oj, o_maybe + atol);
  return test::hull_input::failure_parts() == fails;
}

/// A random case: hull kind, rotation, position (offset from the origin), plane normal,
/// and the plane `sink` * (hull size) above the hull's lowest vertex along it.
Case random_case(std::mt19937& g, HullId kind, double offset, double sink) {
  const TestHulls& t = hulls();
  std::uniform_real_distribution<double> v(-1, 1);
  Case c;
  c.hull = t.id[kind];
  c.R = test::round_to_float(test::random_rotation(g));
  c.p = test::round_to_float(Vec3d(v(g), v(g), v(g)) * t.size[kind] + Vec3d(1, -2, 0.5) * offset);
  c.nh = test::round_to_float(Vec3d(v(g), v(g), v(g)).normalized());
  Ref r = reference(c);  // pb = 0 relative: r.d = -nh.(p + w)
  double lo = INFINITY;
  for (const Vec3d& w : r.w) lo = std::min(lo, c.nh.dot(c.p + w));
  c.pb = test::round_to_float(Vec3d(c.p + c.nh * (lo - c.nh.dot(c.p) + sink * t.size[kind])));
  return c;
}

std::vector<Case> random_cases(uint32_t n, uint32_t seed) {
  std::mt19937 g(seed);
  std::uniform_real_distribution<double> sink(-1.0, 1.2);
  std::vector<Case> cs;
  for (uint32_t k = 0; k < n; ++k) {
    const auto kind = static_cast<HullId>(k % kHullKinds);
    const double offset = (k / kHullKinds) % 3 == 2 ? 1e5 : 0.0;
    cs.push_back(random_case(g, kind, offset, sink(g)));
  }
  return cs;
}

TEST(ConvexHalfspace, RandomPosesAgreeWithBruteForceOnBothPaths) {
  const auto cs = random_cases(test::scaled(3000), 11);
  const test::ManifoldLanes simd = run(cs, KernelPath::kSimd), scalar = run(cs, KernelPath::kScalar);
  const test::ManifoldLanes old = run(cs, KernelPath::kSimd, true);
  int bad = 0, hits = 0, four = 0, differ = 0;
  for (uint32_t k = 0; k < cs.size() && bad < 10; ++k) {
    const auto rs = simd.result(k), rc = scalar.result(k), ro = old.result(k);
    bad += !check(cs[k], rs, "simd", static_cast<int>(k));
    bad += !check(cs[k], rc, "scalar", static_cast<int>(k));
    hits += rs.count > 0;
    four += rs.count == 4;
    // Scalar and the old routine: the same rule, so the same vertices up to rounding
    // (near-ties may resolve differently: counted, and bounded below).
    const Ref ref = reference(cs[k]);
    const double tol = depth_tol(cs[k], ref) + 2.4e-7 * cs[k].p.cwiseAbs().maxCoeff();
    for (const auto* other : {&rc, &ro}) {
      bool same = other->count == rs.count;
      for (uint32_t j = 0; same && j < rs.count; ++j) same = (other->pt[j] - rs.pt[j]).norm() <= 4 * tol;
      differ += !same;
    }
  }
  EXPECT_EQ(bad, 0);
  EXPECT_GT(hits, static_cast<int>(cs.size() / 3));
  EXPECT_GT(four, static_cast<int>(cs.size() / 10));
  EXPECT_LE(differ, static_cast<int>(cs.size() / 200)) << "picks differing from scalar / old path";
}

/// Exactly representable poses (axis permutations, integer offsets): exact ties and
/// exact touching.
TEST(ConvexHalfspace, AdversarialFacesVerticesTouchingAndDeep) {
  const TestHulls& t = hulls();
  std::vector<Case> cs;
  std::vector<uint32_t> want;  // expected count
  auto add = [&](HullId kind, const Mat3d& R, const Vec3d& p, const Vec3d& nh, const Vec3d& pb, uint32_t count) {
    Case c;
    c.hull = t.id[kind];
    c.R = R;
    c.p = test::round_to_float(p);
    c.nh = nh;
    c.pb = test::round_to_float(pb);
    cs.push_back(c);
    want.push_back(count);
  };
  const Mat3d I = Mat3d::Identity();
  Mat3d P;  // an exact axis permutation
  P << 0, 0, 1, 1, 0, 0, 0, 1, 0;
  const Mat3d Rx = Eigen::Vector3d(1, -1, -1).asDiagonal();  // half a turn about x
  const Vec3d z = Vec3d::UnitZ();
  for (double off : {0.0, 1e5}) {
    const Vec3d o = Vec3d(1, -2, 0.5) * off;
    // The box (half 1, 0.7, 0.5) resting on its face: exactly touching, then 0.25 deep
    // (4 tied vertices), through its middle, entirely below; rotated by P (z extent 0.7).
    add(kBox, I, o + Vec3d(0, 0, 0.5), z, o, 0);
    add(kBox, I, o + Vec3d(0, 0, 0.25), z, o, 4);
    add(kBox, I, o, z, o, 4);
    add(kBox, I, o + Vec3d(0, 0, -3), z, o, 4);
    add(kBox, P, o + Vec3d(0, 0, 0.5), z, o, 4);
    add(kBox, P, o + Vec3d(0, 0, 0.75), z, o, 0);
    // The needle and the pancake lying flat and sunk, and standing on end (near the
    // origin: 1e-4 steps are below the float spacing at 1e5).
    if (off == 0.0) {
    const double th = test::round_to_float(1e-4);  // the half thickness, 1e-4f
    add(kNeedle, I, o + Vec3d(0, 0, th), z, o, 0);
    add(kNeedle, I, o + Vec3d(0, 0, 0.5 * th), z, o, 4);
    add(kPancake, I, o + Vec3d(0, 0, th), z, o, 0);
    add(kPancake, I, o + Vec3d(0, 0, 0.5 * th), z, o, 4);
    add(kPancake, P, o + Vec3d(0, 0, 0.5), z, o, 4);
    }
    // The tetrahedron on its tip (vertex (0.1, 0, 1) at z = -1 below p): touching, sunk.
    add(kTetra, Rx, o + Vec3d(0, 0, 1), z, o, 0);
    add(kTetra, Rx, o + Vec3d(0, 0, 0.5), z, o, 1);
    add(kTetra, Rx, o + Vec3d(0, 0, -5), z, o, 4);
    // Plane normal along -x and through the box's centre.
    add(kBox, I, o, -Vec3d::UnitX(), o, 4);
  }
  for (KernelPath path : {KernelPath::kSimd, KernelPath::kScalar}) {
    const test::ManifoldLanes out = run(cs, path);
    for (uint32_t k = 0; k < cs.size(); ++k) {
      const auto r = out.result(k);
      SCOPED_TRACE(testing::Message() << (path == KernelPath::kSimd ? "simd" : "scalar") << " case " << k);
      check(cs[k], r, "adversarial", static_cast<int>(k));
      EXPECT_EQ(r.count, want[k]);
      if (r.count == 0) continue;
      EXPECT_TRUE(std::isfinite(r.n.norm()));
      // Exact ties: the first vertex in vertex order among the deepest is point 0.
      const Ref ref = reference(cs[k]);
      size_t first = 0;
      for (size_t i = 1; i < ref.d.size(); ++i)
        if (ref.d[i] > ref.d[first]) first = i;
      const Vec3d x0 = r.pt[0] - cs[k].nh * (0.5 * r.pd[0]) - cs[k].p;
      size_t at = 0;
      for (size_t i = 1; i < ref.w.size(); ++i)
        if ((ref.w[i] - x0).norm() < (ref.w[at] - x0).norm()) at = i;
      EXPECT_EQ(at, first) << "tie rule: point 0 is not the first deepest vertex";
    }
  }
}

/// Sinking from separated through touching to entirely below, for every hull kind.
TEST(ConvexHalfspace, EverySinkingOfEveryHull) {
  std::mt19937 g(5);
  std::vector<Case> cs;
  for (uint32_t kind = 0; kind < kHullKinds; ++kind)
    for (int s = -2; s <= 22; ++s) cs.push_back(random_case(g, static_cast<HullId>(kind), 0.0, 0.1 * s));
  for (KernelPath path : {KernelPath::kSimd, KernelPath::kScalar}) {
    const test::ManifoldLanes out = run(cs, path);
    int bad = 0;
    for (uint32_t k = 0; k < cs.size() && bad < 10; ++k) bad += !check(cs[k], out.result(k), "sinking", static_cast<int>(k));
    EXPECT_EQ(bad, 0);
  }
}

/// The bytes of lane k that the contract defines (count; n, depth and the count points
/// when count > 0).
std::vector<uint8_t> lane_bytes(const test::ManifoldLanes& o, uint32_t k) {
  std::vector<uint8_t> b;
  auto put = [&](float f) {
    uint8_t x[4];
    std::memcpy(x, &f, 4);
    b.insert(b.end(), x, x + 4);
  };
  b.push_back(o.count[k]);
  if (o.count[k] == 0) return b;
  for (int i = 0; i < 3; ++i) put(o.n[i][k]);
  put(o.depth[k]);
  for (uint32_t j = 0; j < o.count[k]; ++j) {
    for (int i = 0; i < 3; ++i) put(o.pt[j][i][k]);
    put(o.pd[j][k]);
  }
  return b;
}

/// The kernel lists the touching lanes of a chunk and runs the picks over groups of
/// them: buckets where no lane touches, where every lane does (deep), where they
/// alternate, and where hulls over 64 vertices (the per-pair fallback) sit between
/// lane-walk hulls (also of 13, 30 and 47 vertices: no multiple of the width); longer
/// than a chunk, with partly filled groups. Every lane against
/// the brute force on both paths, and its bytes the same as when it runs alone.
TEST(ConvexHalfspace, NoneEveryAndMixedTouchingLanesAndBigHullsBetween) {
  ASSERT_EQ(hulls().h.data[hulls().id[kCloud13]].vertices.size(), 13u);
  ASSERT_EQ(hulls().h.data[hulls().id[kCloud47]].vertices.size(), 47u);
  std::mt19937 g(17);
  const HullId small[] = {kTetra,
                          kBox,
                          kCloud24,
                          kCloud64,
                          kTiny,
                          kHuge,
                          kNeedle,
                          kPancake,
                          static_cast<HullId>(kCloud13),
                          static_cast<HullId>(kCloud30),
                          static_cast<HullId>(kCloud47)};
  const HullId big[] = {kCloud65, kBig};
  const uint32_t n = 300;  // more than one chunk of lanes, not a multiple of the width
  auto bucket = [&](int mode) {
    std::vector<Case> cs;
    for (uint32_t k = 0; k < n; ++k) {
      const bool is_big = mode == 3 && k % 3 == 1;
      const HullId kind = is_big ? big[k % 2] : small[k % 11];
      double sink = 0.0;
      if (mode == 0) sink = -0.5;                           // none touches
      if (mode == 1) sink = 2.5;                            // every lane, entirely below
      if (mode >= 2) sink = (k / 2) % 2 == 0 ? 0.3 : -0.3;  // pairs of lanes alternate
      // (1e5 from the origin except the 1e-4 hull: there float poses cannot keep it apart)
      cs.push_back(random_case(g, kind, k % 5 == 4 && kind != kTiny ? 1e5 : 0.0, sink));
    }
    return cs;
  };
  for (int mode = 0; mode < 4; ++mode) {
    const std::vector<Case> cs = bucket(mode);
    for (KernelPath path : {KernelPath::kSimd, KernelPath::kScalar}) {
      const test::ManifoldLanes out = run(cs, path);
      int bad = 0, touching = 0;
      for (uint32_t k = 0; k < n && bad < 10; ++k) {
        bad += !check(cs[k], out.result(k), "mode", static_cast<int>(k));
        touching += out.count[k] > 0 ? 1 : 0;
      }
      EXPECT_EQ(bad, 0) << "mode " << mode;
      if (mode == 0) {
        EXPECT_EQ(touching, 0);
      }
      if (mode == 1) {
        EXPECT_EQ(touching, static_cast<int>(n));
      }
      if (mode >= 2) {
        EXPECT_GT(touching, static_cast<int>(n) / 4);
        EXPECT_LT(touching, 3 * static_cast<int>(n) / 4);
      }
      for (uint32_t k = 0; k < n; k += 7) {
        const test::ManifoldLanes alone = run({cs[k]}, path);
        ASSERT_EQ(lane_bytes(alone, 0), lane_bytes(out, k)) << "mode " << mode << ", lane " << k;
      }
    }
  }
}

/// Both paths run the same template over the same per-lane arithmetic, but GCC contracts
/// multiply-adds differently in the one-lane and the vector code: where two vertices'
/// scores for a pick tie within rounding (a box's or a needle's symmetric vertices) the
/// paths may choose differently (at IMPACT_TEST_INTENSITY=10, 8 of 12,000 lanes: the
/// same four points with the widest and the outmost swapped). So: the same bytes on all
/// but a few lanes, and on those both answers meet the brute force's rules (random
/// poses, 1e5 from the origin, every hull kind).
TEST(ConvexHalfspace, ScalarPathGivesTheSimdPathsBytes) {
  const auto cs = random_cases(test::scaled(1200), 29);
  const test::ManifoldLanes simd = run(cs, KernelPath::kSimd);
  const test::ManifoldLanes one = run(cs, KernelPath::kScalar);
  uint32_t differ = 0;
  for (uint32_t k = 0; k < cs.size(); ++k) {
    if (lane_bytes(one, k) == lane_bytes(simd, k)) continue;
    ++differ;
    EXPECT_TRUE(check(cs[k], simd.result(k), "simd", static_cast<int>(k)));
    EXPECT_TRUE(check(cs[k], one.result(k), "scalar", static_cast<int>(k)));
  }
  EXPECT_LE(differ, cs.size() / 500) << "lanes whose one-lane and SIMD bytes differ";
}

}  // namespace
}  // namespace impact::kernels
