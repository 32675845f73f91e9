// Convex hull against triangle (kernels/narrowphase/pairs/convex/convex_triangle.cpp,
// collide_convex_triangle) against independent double-precision references:
//  - a brute-force separating axis test in double over ALL axes, no pruning: every face
//    normal of the hull (Newell normals of the HullData polygons, posed in double
//    relative to the hull position: not the kernel's float planes), both normals of the
//    triangle, and the cross product of every polygon edge with every triangle edge,
//    both signs; each axis's separation min_tri n.x - max_hull n.x by brute-force
//    supports over all vertices. For a polytope and a triangle these axes hold the
//    minimum translation, so depth_ref = -max separation;
//  - tests/support/narrow_reference.h without its polytope hints (dense sampling of the
//    support overlap and Nelder-Mead), on a subset of the random lanes, to check the
//    brute force itself;
//  - collide_box_triangle where the hull is a box (depth and the overlap along the normal).
// Per lane, L = the larger of the hull's and the triangle's bounding radius, tol = kRel L:
//  (a) count > 0 iff depth_ref > 0 (either answer where |depth_ref| <= tol), count <= 4;
//  (b) |depth - depth_ref| <= tol;
//  (c) n finite and unit (1e-6), the separation along n is -depth within tol (moving the
//      triangle by n depth separates), and where the minimum is unique (every axis more
//      than kAngle from the best separates by 1e-3 L less) n is within kAngle of it;
//  (d) every point finite, 0 < pdepth <= depth + tol, within pdepth/2 + tol of both
//      surfaces (the hull's signed distance, the triangle's distance);
//  (e) kSimd and kScalar each pass (a)-(d) (their bytes differ only where FMAs fuse
//      differently and nearly tied candidates go either way: counted, not required);
//      the general GJK / EPA path agrees on hits away from touching (1e-4 L) and on the
//      depth within 1e-4 L.
// Scenarios: random hulls (boxes, 4..40-point clouds, a tetrahedron, the benchmark's
// 24-point clouds) and random triangles moved along a random direction to 0.6..1.4
// times their touching distance (about half overlapping); tiny (1e-4) and huge (1e4)
// sizes; poses 1e5 from the origin; deep (common centre); touching (B moved to the
// brute force's touching distance) and exactly touching (a triangle on a box face:
// count 0); a triangle lying on a face, slightly sunk (the face wins the tie: its
// normal, the clipped polygon as points); a face of the hull lying on the triangle; a
// hull edge across a triangle edge at angles 0 .. 1e-2 rad from parallel; a triangle
// edge parallel to a hull face; degenerate triangles (collinear, two or three coincident
// vertices, slivers of height 1e-3 .. 1e-7): their answers are the segment's or the
// point's (GJK / EPA's and the brute force's without the normal axes); needle and
// pancake hulls (1 x 1e-4); a hull with 80-gon faces (no clip: one point); the winding
// of the triangle (same answer); a hull view without edge adjacency (the GJK / EPA
// fallback, same bytes as that path). Registration and range partitions: contract_test.cpp.
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "host/shapes/convex_hull.h"
#include "host/shapes/shape_store.h"
#include "kernels/narrowphase/pair_kernels.h"
#include "support/hull_input.h"
#include "support/leaf_lanes.h"
#include "support/narrow_reference.h"
#include "support/random_input.h"
#include "support/test_support.h"

namespace impact::test {
namespace {

namespace k = kernels;
using namespace hull_input;  // NOLINT: the hull tests' shared inputs
namespace nref = test::nref;

constexpr double kRel = 1e-5;    // of L; float arithmetic gives ~1e-6
constexpr double kAngle = 1e-4;  // rad, where the minimum is unique
/// The kernel's face bias (convex_triangle.cpp kTieRel): a face axis stands unless an
/// edge axis separates more by this of |separation| (plus 1e-6 of the size, within
/// kRel), so a deep pair's depth may exceed the least overlap by that much.
constexpr double kFaceBias = 1e-5;

// --- lanes ------------------------------------------------------------------------------------

struct Pair {
  float p[3];     // hull position
  float R[9];     // hull rotation, row-major
  uint32_t hull;  // index in Hulls
  float v[3][3];  // triangle vertices (world)
};

/// The hull and the triangle of a lane.
std::pair<test::Leaf, test::Leaf> leaves(const Pair& q) {
  test::Leaf a, b;
  a.t = k::kLeafConvex, b.t = k::kLeafTriangle;
  std::copy(q.p, q.p + 3, a.p);
  std::copy(q.R, q.R + 9, a.r);
  a.ref = q.hull;
  std::copy(q.v[0], q.v[0] + 3, b.p);
  std::copy(q.v[1], q.v[1] + 3, b.w);
  std::copy(q.v[2], q.v[2] + 3, b.w + 3);
  return {a, b};
}

struct Bucket : test::BucketLanes {
  explicit Bucket(const std::vector<Pair>& v) : BucketLanes(v, leaves) {}
};

ManifoldLanes run(const Bucket& bk, const k::HullView& hv, k::KernelPath path) {
  return bk.run(&k::collide_convex_triangle, hv, path);
}

ManifoldLanes run_gjk(const Bucket& bk, const k::HullView& hv) {
  return bk.run(
      [](const k::LeafSoA& a, const k::LeafSoA& b, const k::ManifoldSoA& o, k::Range r,
         const k::NarrowConfig& cfg) {
        k::collide_gjk_epa(a, b, o, r, cfg, k::kLeafConvex, k::kLeafTriangle);
      },
      hv, k::KernelPath::kSimd);
}

// --- the reference ---------------------------------------------------------------------------

/// Angle between two nonzero vectors (accurate near 0, unlike acos of a float dot).
double angle(D3 a, D3 b) {
  return std::atan2(norm(cross(a, b)), dot(a, b));
}

/// The triangle relative to the hull position (exact in double).
struct RefTri {
  D3 v[3];
};
RefTri ref_tri(const Pair& q) {
  RefTri t;
  for (int i = 0; i < 3; ++i)
    t.v[i] = D3{static_cast<double>(q.v[i][0]) - q.p[0], static_cast<double>(q.v[i][1]) - q.p[1],
                static_cast<double>(q.v[i][2]) - q.p[2]};
  return t;
}

/// min over the triangle of n.x - max over the hull of n.x.
double separation(const RefHull& H, const RefTri& T, D3 n) {
  double hi = -1e300, lo = 1e300;
  for (const D3& v : H.v) hi = std::max(hi, dot(n, v));
  for (const D3& v : T.v) lo = std::min(lo, dot(n, v));
  return lo - hi;
}

struct SatRef {
  double s = -1e300;  // max separation over all axes (-depth when overlapping)
  D3 n;               // its axis
  bool unique = false;
};

/// Every axis of the brute-force SAT: the hull's face normals, +-the triangle's normal,
/// every polygon edge x triangle edge, both signs. normal_axes: include the triangle's
/// normals (false for a degenerate triangle, whose set of points has none).
std::vector<D3> sat_axes(const RefHull& H, const RefTri& T, bool normal_axes = true) {
  std::vector<D3> axes = H.fn;
  const D3 f[3] = {T.v[1] - T.v[0], T.v[2] - T.v[1], T.v[0] - T.v[2]};
  const D3 nt = cross(f[0], T.v[2] - T.v[0]);
  if (normal_axes && norm(nt) > 0) {
    axes.push_back(unit(nt));
    axes.push_back(-1.0 * unit(nt));
  }
  for (const auto& poly : H.faces)
    for (size_t i = 0; i < poly.size(); ++i) {
      const D3 e = H.v[poly[(i + 1) % poly.size()]] - H.v[poly[i]];
      for (const D3& fj : f) {
        const D3 c = cross(e, fj);
        if (norm(c) > 1e-12 * norm(e) * norm(fj)) {
          axes.push_back(unit(c));
          axes.push_back(-1.0 * unit(c));
        }
      }
    }
  return axes;
}

/// The largest separation over sat_axes (for a polytope and a triangle these axes hold
/// the minimum translation: -depth when they overlap), its axis, and whether every axis
/// more than kAngle from it separates by 1e-3 L less.
SatRef brute_sat(const RefHull& H, const RefTri& T, double L, bool normal_axes = true) {
  const std::vector<D3> axes = sat_axes(H, T, normal_axes);
  SatRef r;
  std::vector<double> s(axes.size());
  for (size_t i = 0; i < axes.size(); ++i) {
    s[i] = separation(H, T, axes[i]);
    if (s[i] > r.s) r.s = s[i], r.n = axes[i];
  }
  double second = -1e300;
  for (size_t i = 0; i < axes.size(); ++i)
    if (angle(axes[i], r.n) > kAngle) second = std::max(second, s[i]);
  r.unique = r.s - second > 1e-3 * L;
  return r;
}

/// Signed distance of y to the hull (> 0 outside).
double hull_sd(const RefHull& H, D3 y) {
  double best = -1e300;
  for (size_t f = 0; f < H.faces.size(); ++f) best = std::max(best, dot(H.fn[f], y) - H.fd[f]);
  if (best <= 0) return best;
  double dmin = 1e300;
  for (size_t f = 0; f < H.faces.size(); ++f) {
    const auto& poly = H.faces[f];
    bool in = true;
    for (size_t i = 0; i < poly.size(); ++i) {
      const D3 p = H.v[poly[i]], q = H.v[poly[(i + 1) % poly.size()]];
      if (dot(cross(q - p, H.fn[f]), y - p) > 0) in = false;
    }
    if (in) dmin = std::min(dmin, std::fabs(dot(H.fn[f], y) - H.fd[f]));
    for (size_t i = 0; i < poly.size(); ++i)
      dmin = std::min(dmin, norm(closest_on_segment(H.v[poly[i]], H.v[poly[(i + 1) % poly.size()]], y) - y));
  }
  return dmin;
}

/// Distance of y to the triangle.
double tri_distance(const RefTri& T, D3 y) {
  double d = 1e300;
  for (int i = 0; i < 3; ++i) d = std::min(d, norm(closest_on_segment(T.v[i], T.v[(i + 1) % 3], y) - y));
  const D3 n = cross(T.v[1] - T.v[0], T.v[2] - T.v[0]);
  if (norm(n) > 0) {
    const D3 u = unit(n);
    const D3 p = y - dot(u, y - T.v[0]) * u;
    bool in = true;
    for (int i = 0; i < 3; ++i)
      if (dot(cross(T.v[(i + 1) % 3] - T.v[i], p - T.v[i]), n) < 0) in = false;
    if (in) d = std::min(d, std::fabs(dot(u, y - T.v[0])));
  }
  return d;
}

double tri_radius(const RefTri& T) {
  const D3 c = (1.0 / 3.0) * (T.v[0] + T.v[1] + T.v[2]);
  double r = 0;
  for (const D3& v : T.v) r = std::max(r, norm(v - c));
  return r;
}

bool degenerate(const RefTri& T) {
  return !(norm(cross(T.v[1] - T.v[0], T.v[2] - T.v[0])) > 0);
}

// --- the checks ------------------------------------------------------------------------------

struct Stats {
  uint32_t hits = 0, misses = 0, face = 0, tri_face = 0, edge = 0, multi = 0, same_bytes = 0;
  double worst_depth = 0;  // / L
};

std::string lane_text(const Pair& q) {
  char buf[1024];
  std::snprintf(buf, sizeof buf,
                "hull %u p={%.9g, %.9g, %.9g} R={%.9g, %.9g, %.9g, %.9g, %.9g, %.9g, %.9g, %.9g, %.9g}; "
                "triangle {%.9g, %.9g, %.9g}, {%.9g, %.9g, %.9g}, {%.9g, %.9g, %.9g}",
                q.hull, q.p[0], q.p[1], q.p[2], q.R[0], q.R[1], q.R[2], q.R[3], q.R[4], q.R[5], q.R[6],
                q.R[7], q.R[8], q.v[0][0], q.v[0][1], q.v[0][2], q.v[1][0], q.v[1][1], q.v[1][2], q.v[2][0],
                q.v[2][1], q.v[2][2]);
  return buf;
}

/// Runs both paths and GJK / EPA on `pairs` and checks every lane; returns the counts.
/// rel: the depth tolerance relative to L.
Stats check_pairs(const std::string& name, const std::vector<Pair>& pairs, const Hulls& hulls,
                  double rel = kRel) {
  SCOPED_TRACE(name);
  Stats st;
  const Bucket bk(pairs);
  const k::HullView hv = hulls.store.view();
  const ManifoldLanes simd = run(bk, hv, k::KernelPath::kSimd);
  const ManifoldLanes scalar = run(bk, hv, k::KernelPath::kScalar);
  const ManifoldLanes gjk = run_gjk(bk, hv);
  int failures = 0;
  for (uint32_t i = 0; i < bk.n && failures < 10; ++i) {
    const Pair& q = pairs[i];
    const RefHull H = pose(hulls.data[q.hull], q);
    const RefTri T = ref_tri(q);
    const double L = std::max(H.radius, tri_radius(T));
    const double tol = rel * L;
    const SatRef ref = brute_sat(H, T, L, !degenerate(T));
    const double depth_ref = -ref.s;
    const int before = failure_parts();
    SCOPED_TRACE("lane " + std::to_string(i) + ": " + lane_text(q) +
                 "; depth_ref=" + std::to_string(depth_ref));

    // Both paths against the reference (they may round differently where FMAs fuse
    // differently: nearly tied candidates can go either way, each a valid answer).
    st.same_bytes += simd.lane_bits(i) == scalar.lane_bits(i) ? 1 : 0;
    for (const ManifoldLanes* path : {&simd, &scalar}) {
      SCOPED_TRACE(path == &simd ? "simd path" : "scalar path");
      const PairResult res = path->result(i);
      const bool main = path == &simd;
      EXPECT_LE(res.count, 4u);
      if (std::fabs(depth_ref) > tol) {
        EXPECT_EQ(res.count > 0, depth_ref > 0) << "hit disagrees";
      }
      if (!(res.count > 0 && res.count <= 4)) {
        st.misses += main ? 1 : 0;
        continue;
      }
      const D3 n{res.n.x(), res.n.y(), res.n.z()};
      const double depth = res.depth;
      EXPECT_TRUE(std::isfinite(n.x) && std::isfinite(n.y) && std::isfinite(n.z) && std::isfinite(depth));
      EXPECT_NEAR(norm(n), 1.0, 1e-6);
      // (a face axis held against a tied edge axis stood 1.13e-5 above the least
      // overlap at depth 0.586, IMPACT_TEST_INTENSITY=30, against kRel's 1.04e-5)
      EXPECT_NEAR(depth, depth_ref, tol + kFaceBias * std::fabs(depth_ref));
      st.worst_depth = std::max(st.worst_depth, std::fabs(depth - depth_ref) / L);
      EXPECT_NEAR(separation(H, T, n), -depth, tol) << "depth is not the overlap along n";
      if (ref.unique) {
        EXPECT_LE(angle(n, ref.n), kAngle)
            << "normal; reference " << ref.n.x << ", " << ref.n.y << ", " << ref.n.z;
      }
      // Which feature: a hull face normal, the triangle's normal, else an edge pair.
      bool face = false;
      for (const D3& fn : H.fn) face = face || dot(fn, n) > 1 - 1e-6;
      const D3 nt = cross(T.v[1] - T.v[0], T.v[2] - T.v[0]);
      const bool tface = !face && norm(nt) > 0 && std::fabs(dot(unit(nt), n)) > 1 - 1e-6;
      if (main) {
        ++st.hits;
        st.multi += res.count > 1 ? 1 : 0;
        st.face += face ? 1 : 0;
        st.tri_face += tface ? 1 : 0;
        st.edge += !face && !tface ? 1 : 0;
      }
      for (uint32_t j = 0; j < res.count; ++j) {
        const D3 pw{res.pt[j].x(), res.pt[j].y(), res.pt[j].z()};
        EXPECT_TRUE(std::isfinite(pw.x) && std::isfinite(pw.y) && std::isfinite(pw.z));
        const double ulp = std::max({std::fabs(pw.x), std::fabs(pw.y), std::fabs(pw.z)}) * 0x1p-23;
        const D3 pt = pw - H.origin;
        const double lim = 0.5 * res.pd[j] + tol + 2 * ulp;
        EXPECT_LE(tri_distance(T, pt), lim)
            << "point " << j << " of " << res.count << " off the triangle ("
            << (face ? "hull face" : (tface ? "triangle face" : "edges")) << ")";
        EXPECT_LE(std::fabs(hull_sd(H, pt)), lim)
            << "point " << j << " of " << res.count << " off the hull's surface ("
            << (face ? "hull face" : (tface ? "triangle face" : "edges")) << "; depth " << depth << ", n " << n.x
            << " " << n.y << " " << n.z << ", point " << pt.x << " " << pt.y << " " << pt.z << ")";
        EXPECT_GT(res.pd[j], 0.0) << "pdepth " << j;
        EXPECT_LE(res.pd[j], depth + tol) << "pdepth " << j;
      }
    }
    const PairResult res = simd.result(i);
    // The general path: same hits away from touching, the same depth.
    const double tg = 1e-4 * L;
    if (std::fabs(depth_ref) > tg) {
      EXPECT_EQ(gjk.count[i] > 0, res.count > 0) << "GJK/EPA disagrees on the hit";
    }
    if (gjk.count[i] > 0 && res.count > 0) {
      EXPECT_NEAR(gjk.depth[i], res.depth, tg) << "GJK/EPA depth";
    }
    if (failure_parts() != before) ++failures;  // stop after 10 failing lanes
  }
  return st;
}

void set_v(Pair* q, int i, D3 x) {
  q->v[i][0] = static_cast<float>(x.x), q->v[i][1] = static_cast<float>(x.y),
  q->v[i][2] = static_cast<float>(x.z);
}
void set_p(Pair* q, D3 x) {
  q->p[0] = static_cast<float>(x.x), q->p[1] = static_cast<float>(x.y), q->p[2] = static_cast<float>(x.z);
}
D3 get_v(const Pair& q, int i) {
  return D3{q.v[i][0], q.v[i][1], q.v[i][2]};
}

/// Moves the triangle by t (world, rounded to float).
Pair shifted(Pair q, D3 t) {
  for (int i = 0; i < 3; ++i) set_v(&q, i, get_v(q, i) + t);
  return q;
}

/// A triangle about centre c, radius r * [0.5, 1.5], in a random plane (vertices spread).
void random_triangle(Rng& g, D3 c, double r, Pair* q) {
  const D3 n = random_unit(g);
  const D3 t = unit(cross(n, std::fabs(n.x) < 0.6 ? D3{1, 0, 0} : D3{0, 1, 0}));
  const D3 b = cross(n, t);
  const double a0 = uni(g, 0, 6.283185307179586);
  for (int i = 0; i < 3; ++i) {
    const double ang = a0 + i * 2.0943951023931953 + uni(g, -0.5, 0.5);
    const double rad = r * uni(g, 0.5, 1.5);
    set_v(q, i, c + (rad * std::cos(ang)) * t + (rad * std::sin(ang)) * b);
  }
}

/// The translation t along unit u at which the overlapping triangle of q just touches
/// the hull: each axis's separation grows as s + t n.u, so t = the least -s / n.u over
/// the axes with n.u > 0 (exact, the same axes as brute_sat).
double touching_distance(const Hulls& hulls, const Pair& q, D3 u) {
  const RefHull H = pose(hulls.data[q.hull], q);
  const RefTri T = ref_tri(q);
  double t = 1e300;
  for (const D3& n : sat_axes(H, T)) {
    const double nu = dot(n, u);
    if (nu > 1e-12) t = std::min(t, -separation(H, T, n) / nu);
  }
  return t;
}

/// Random lanes: hull h0..h1 at `offset` from the origin, sizes ~scale; a triangle
/// about the hull's origin, moved along a random direction to f * its touching distance,
/// f in [0.6, 1.4] (about half overlap).
std::vector<Pair> random_pairs(Rng& g, const Hulls& hulls, uint32_t h0, uint32_t h1, uint32_t n, double scale,
                               double offset, double fmin = 0.6, double fmax = 1.4, double centre = 0.2) {
  std::vector<Pair> out;
  for (uint32_t i = 0; i < n; ++i) {
    Pair q;
    q.hull = h0 + static_cast<uint32_t>(g() % (h1 - h0));
    random_rotation(g, q.R);
    set_p(&q, offset * random_unit(g));
    // About the hull's vertex centroid (inside it); the triangle moves from a pose that
    // overlaps the hull (its centroid at the hull's) when `centre` did not.
    const RefHull H = pose(hulls.data[q.hull], q);
    const D3 in = H.origin + H.centroid;
    const double r = scale * uni(g, 0.3, 1.2);
    random_triangle(g, in + (centre * scale) * random_unit(g), r, &q);
    if (fmax > 0 && !(brute_sat(H, ref_tri(q), 1.0).s < 0)) random_triangle(g, in, r, &q);
    if (fmax == 0) {  // deep: the triangle stays about the hull's origin
      out.push_back(q);
      continue;
    }
    const D3 u = random_unit(g);
    const double d = touching_distance(hulls, q, u);
    out.push_back(shifted(q, uni(g, fmin, fmax) * d * u));
  }
  return out;
}

/// The benchmark's hulls: 24 points on an ellipsoid of half axes 0.4..1.
void add_bench_hulls(Rng& g, Hulls* hulls, uint32_t count) {
  for (uint32_t i = 0; i < count; ++i) {
    const double sx = uni(g, 0.4, 1.0), sy = uni(g, 0.4, 1.0), sz = uni(g, 0.4, 1.0);
    std::vector<Eigen::Vector3f> pts;
    for (int j = 0; j < 24; ++j) {
      const D3 u = random_unit(g);
      pts.emplace_back(static_cast<float>(sx * u.x), static_cast<float>(sy * u.y),
                       static_cast<float>(sz * u.z));
    }
    hulls->add(pts);
  }
}

Hulls& shared_hulls() {
  static Hulls* h = [] {
    auto* hs = new Hulls;
    Rng g(7);
    add_random_hulls(g, hs, 16, 1.0);  // 0..15: boxes and 8..40-point clouds
    add_bench_hulls(g, hs, 8);         // 16..23
    hs->add({Eigen::Vector3f(0, 0, 0), Eigen::Vector3f(1, 0, 0), Eigen::Vector3f(0, 1, 0),
             Eigen::Vector3f(0.2f, 0.3f, 0.9f)});  // 24: tetrahedron (4 faces, 4 vertices)
    return hs;
  }();
  return *h;
}
constexpr uint32_t kHullsRandom = 24, kTetra = 24;

// --- tests ------------------------------------------------------------------------------------

TEST(ConvexTriangle, RandomPosesAgreeWithReference) {
  Rng g(2024);
  const Hulls& hulls = shared_hulls();
  const auto pairs = random_pairs(g, hulls, 0, kHullsRandom + 1, scaled(4000), 1.0, 0.0);
  const Stats st = check_pairs("random", pairs, hulls);
  EXPECT_GT(st.misses, pairs.size() / 4);
  EXPECT_GT(st.hits, pairs.size() / 4);
  EXPECT_GT(st.face, pairs.size() / 20);
  EXPECT_GT(st.tri_face, pairs.size() / 50);
  EXPECT_GT(st.edge, pairs.size() / 20);
  EXPECT_GT(st.multi, pairs.size() / 20);
  RecordProperty("worst_depth_rel", std::to_string(st.worst_depth));
  // The two paths run the same per-lane code over different widths: nearly always the
  // same bytes.
  EXPECT_GT(st.same_bytes, pairs.size() * 95 / 100);
  std::printf("random: hits %u misses %u face %u tri_face %u edge %u multi %u same bytes %u worst %.3g\n",
              st.hits, st.misses, st.face, st.tri_face, st.edge, st.multi, st.same_bytes, st.worst_depth);
}

TEST(ConvexTriangle, TinyHugeAndFar) {
  for (const double scale : {1e-4, 1e4}) {
    Rng g(scale < 1 ? 31 : 32);
    Hulls hulls;
    add_random_hulls(g, &hulls, 8, scale);
    const auto pairs = random_pairs(g, hulls, 0, 8, scaled(500), scale, 0.0);
    const Stats st = check_pairs(scale < 1 ? "tiny 1e-4" : "huge 1e4", pairs, hulls);
    EXPECT_GT(st.hits, pairs.size() / 5);
    EXPECT_GT(st.misses, pairs.size() / 5);
  }
  {
    // 1e5 from the origin: the float inputs are exact, so the same tolerance holds.
    Rng g(33);
    const Hulls& hulls = shared_hulls();
    const auto pairs = random_pairs(g, hulls, 0, kHullsRandom, scaled(500), 1.0, 1e5);
    const Stats st = check_pairs("far 1e5", pairs, hulls);
    EXPECT_GT(st.hits, pairs.size() / 5);
  }
}

TEST(ConvexTriangle, DeepCoincidentCentresAndTouching) {
  Rng g(34);
  const Hulls& hulls = shared_hulls();
  const uint32_t n = scaled(500);
  check_pairs("deep", random_pairs(g, hulls, 0, kHullsRandom + 1, n, 1.0, 0.0, 0.0, 0.0, 0.3), hulls);
  check_pairs("coincident centres", random_pairs(g, hulls, 0, kHullsRandom + 1, n, 1.0, 0.0, 0.0, 0.0, 0.0),
              hulls);
  // Moved to the brute force's touching distance (then rounded to float): either
  // answer, a hit of depth within tol.
  check_pairs("touching", random_pairs(g, hulls, 0, kHullsRandom + 1, n, 1.0, 0.0, 1.0, 1.0), hulls);
  check_pairs("grazing", random_pairs(g, hulls, 0, kHullsRandom + 1, n, 1.0, 0.0, 0.999, 1.001), hulls);
}

/// A box hull (half extents 0.5, 0.25, 0.75: exact floats) at the identity pose.
struct BoxWorld {
  Hulls hulls;
  uint32_t box;
  BoxWorld() { box = hulls.add(box_corners(0.5f, 0.25f, 0.75f)); }
  Pair pair(D3 a, D3 b, D3 c) const {
    Pair q{};
    q.hull = box;
    const float R[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    std::copy(R, R + 9, q.R);
    set_v(&q, 0, a), set_v(&q, 1, b), set_v(&q, 2, c);
    return q;
  }
  ManifoldLanes run1(const Pair& q) const {
    return run(Bucket({q}), hulls.store.view(), k::KernelPath::kSimd);
  }
};

TEST(ConvexTriangle, ExactFacesOnABox) {
  const BoxWorld w;
  const double dz = 0x1p-10;
  // The kernel works in float: 4 ulps of the box's coordinates (in [0.5, 1)) for
  // every position and depth; how the compiler contracts the transforms moves a clipped
  // corner by 2 of them (seen at -O1 under ASan).
  const double tol = 4 * 0x1p-24;
  // On the top face exactly: touching, count 0.
  EXPECT_EQ(w.run1(w.pair({-0.2, -0.1, 0.75}, {0.3, -0.1, 0.75}, {0.0, 0.2, 0.75})).count[0], 0);
  // Sunk by dz, inside the face: the face's normal (it wins the tie with the
  // triangle's), depth dz, the three vertices midway.
  {
    const auto o = w.run1(w.pair({-0.2, -0.1, 0.75 - dz}, {0.3, -0.1, 0.75 - dz}, {0.0, 0.2, 0.75 - dz}));
    const PairResult r = o.result();
    ASSERT_EQ(r.count, 3u);
    EXPECT_EQ(r.n, Eigen::Vector3d(0, 0, 1));
    EXPECT_NEAR(r.depth, dz, tol);
    for (uint32_t j = 0; j < 3; ++j) {
      EXPECT_NEAR(r.pt[j].z(), 0.75 - 0.5 * dz, tol);
      EXPECT_NEAR(r.pd[j], dz, tol);
    }
  }
  // Tilted by 1e-6 about x: the triangle's normal axis separates less than the top
  // face's by ~5e-7, within the tie tolerance: the face keeps the contact (its normal
  // exactly).
  {
    const double z = 0.75 - dz;
    const auto o = w.run1(w.pair({-0.2, -0.1, z}, {0.3, -0.1, z}, {0.0, 0.2, z + 1e-6}));
    const PairResult r = o.result();
    ASSERT_EQ(r.count, 3u);
    EXPECT_EQ(r.n, Eigen::Vector3d(0, 0, 1));
    EXPECT_NEAR(r.depth, dz, tol);
  }
  // A large triangle under the box, its plane dz above the bottom face: the bottom face
  // (clipped: its four corners), normal -z from the box to the triangle.
  {
    const double z = -0.75 + dz;
    const auto o = w.run1(w.pair({-3, -3, z}, {3, -3, z}, {0, 4, z}));
    const PairResult r = o.result();
    ASSERT_EQ(r.count, 4u);
    EXPECT_EQ(r.n, Eigen::Vector3d(0, 0, -1));
    EXPECT_NEAR(r.depth, dz, tol);
    for (uint32_t j = 0; j < 4; ++j) {
      EXPECT_NEAR(std::fabs(r.pt[j].x()), 0.5, tol);
      EXPECT_NEAR(std::fabs(r.pt[j].y()), 0.25, tol);
      EXPECT_NEAR(r.pt[j].z(), -0.75 + 0.5 * dz, tol);
    }
  }
  // Across the top face's edge x = 0.5, sunk by dz: the part over the face, clipped
  // at x = 0.5 (points with |x| <= 0.5 only).
  {
    const double z = 0.75 - dz;
    const auto o = w.run1(w.pair({0.2, -0.1, z}, {1.2, -0.1, z}, {0.2, 0.2, z}));
    const PairResult r = o.result();
    ASSERT_GE(r.count, 3u);
    EXPECT_EQ(r.n, Eigen::Vector3d(0, 0, 1));
    for (uint32_t j = 0; j < r.count; ++j) EXPECT_LE(r.pt[j].x(), 0.5 + tol);
  }
  // A vertex pushed into the bottom face's centre from below, the triangle tilted: the
  // face wins (vertex contact), one point.
  {
    const auto o = w.run1(w.pair({0, 0, -0.75 + dz}, {1, 0.3, -1.5}, {-0.4, 1, -1.6}));
    const PairResult r = o.result();
    ASSERT_EQ(r.count, 1u);
    EXPECT_EQ(r.n, Eigen::Vector3d(0, 0, -1));
    EXPECT_NEAR(r.depth, dz, tol);
  }
}

TEST(ConvexTriangle, FaceAndEdgeFeaturesOnRandomBoxes) {
  // Random poses of box hulls against random triangles: the reference checks, plus
  // the separation along each answer's normal equals the box-triangle kernel's depth.
  Rng g(35);
  Hulls hulls;
  std::vector<D3> ext;
  for (int i = 0; i < 8; ++i) {
    const D3 e{uni(g, 0.1, 1.0), uni(g, 0.1, 1.0), uni(g, 0.1, 1.0)};
    hulls.add(box_corners(static_cast<float>(e.x), static_cast<float>(e.y), static_cast<float>(e.z)));
    ext.push_back(D3{test::round_to_float(e.x), test::round_to_float(e.y), test::round_to_float(e.z)});
  }
  const auto pairs = random_pairs(g, hulls, 0, 8, scaled(1000), 1.0, 0.0);
  const Stats st = check_pairs("boxes", pairs, hulls);
  EXPECT_GT(st.edge, pairs.size() / 20);
  EXPECT_GT(st.face, pairs.size() / 20);
  // The box-triangle kernel on the same lanes (a box leaf: p, R, half extents).
  const Bucket bk(pairs);
  std::vector<float> be[3];
  for (const Pair& q : pairs)
    for (int c = 0; c < 3; ++c)
      be[c].push_back(static_cast<float>(c == 0 ? ext[q.hull].x : (c == 1 ? ext[q.hull].y : ext[q.hull].z)));
  k::LeafSoA box = bk.a();
  for (int c = 0; c < 3; ++c) box.e[c] = be[c].data();
  ManifoldLanes bt(bk.n);
  k::NarrowConfig cfg;
  k::collide_box_triangle(box, bk.b(), bt.view(), k::Range{0, bk.n}, cfg);
  const ManifoldLanes ct = run(bk, hulls.store.view(), k::KernelPath::kSimd);
  uint32_t both = 0;
  for (uint32_t i = 0; i < bk.n; ++i) {
    const RefHull H = pose(hulls.data[pairs[i].hull], pairs[i]);
    const RefTri T = ref_tri(pairs[i]);
    const double tol = kRel * std::max(H.radius, tri_radius(T));
    const PairResult x = ct.result(i), y = bt.result(i);
    if (x.count == 0 || y.count == 0) {
      EXPECT_LT(std::max(x.count ? x.depth : 0.0, y.count ? y.depth : 0.0), 10 * tol) << "lane " << i;
      continue;
    }
    ++both;
    EXPECT_NEAR(x.depth, y.depth, 2 * tol) << "lane " << i;
    const D3 nx{x.n.x(), x.n.y(), x.n.z()}, ny{y.n.x(), y.n.y(), y.n.z()};
    EXPECT_NEAR(separation(H, T, nx), separation(H, T, ny), 2 * tol) << "lane " << i;
  }
  EXPECT_GT(both, bk.n / 4);
}

TEST(ConvexTriangle, NearParallelEdges) {
  // A box standing on an edge (turned 45 degrees about x: the edge on top along x) and a
  // vertical triangle whose bottom edge crosses it, turned by tiny angles about z and
  // about the box's diagonal: parallel and nearly parallel edge pairs.
  Hulls hulls;
  const uint32_t box = hulls.add(box_corners(1, 1, 1));
  std::vector<Pair> pairs;
  for (const double ang : {0.0, 1e-7, 1e-6, 1e-5, 1e-4, 1e-3, 1e-2}) {
    for (int kk = 0; kk < 4; ++kk) {
      Pair q{};
      q.hull = box;
      const double c = std::cos(M_PI / 4 + kk * ang), sn = std::sin(M_PI / 4 + kk * ang);
      const float R[9] = {1,
                          0,
                          0,
                          0,
                          static_cast<float>(c),
                          static_cast<float>(-sn),
                          0,
                          static_cast<float>(sn),
                          static_cast<float>(c)};
      std::copy(R, R + 9, q.R);
      const double h = std::sqrt(2.0) - 0.01 * (kk + 1);
      const D3 d{std::cos(ang), std::sin(ang), 0};
      const D3 o{0.1 * kk, 0.0, h};
      set_v(&q, 0, o - 2.0 * d), set_v(&q, 1, o + 2.0 * d), set_v(&q, 2, o + D3{0.3 * kk, 0.2 * ang, 1.0});
      pairs.push_back(q);
      // The same triangle turned about its bottom edge (no longer vertical).
      Pair q2 = q;
      set_v(&q2, 2, o + D3{0.3 * kk, 0.6, 0.8});
      pairs.push_back(q2);
    }
  }
  const Stats st = check_pairs("near-parallel edges", pairs, hulls);
  EXPECT_EQ(st.misses, 0u);
}

TEST(ConvexTriangle, DegenerateTriangles) {
  // Collinear (exact in float and rounded), two or three coincident vertices, slivers:
  // the set of points is a segment or a point (or a thin triangle), and the answers are
  // the brute force's over its axes, and GJK / EPA's.
  Rng g(36);
  const Hulls& hulls = shared_hulls();
  std::vector<Pair> pairs;
  for (uint32_t i = 0; i < scaled(300); ++i) {
    const auto base = random_pairs(g, hulls, 0, kHullsRandom + 1, 1, 1.0, 0.0)[0];
    const D3 a = get_v(base, 0), b = get_v(base, 1);
    Pair q = base;
    // collinear: the midpoint (rounded: nearly collinear)
    set_v(&q, 2, 0.5 * (a + b));
    pairs.push_back(q);
    // collinear exactly: b - a along a float-exact direction
    q = base;
    set_v(&q, 1, a + D3{0.5, 0, 0}), set_v(&q, 2, a + D3{1.25, 0, 0});
    pairs.push_back(q);
    // two coincident vertices
    q = base;
    std::copy(q.v[1], q.v[1] + 3, q.v[2]);
    pairs.push_back(q);
    // a point
    q = base;
    std::copy(q.v[0], q.v[0] + 3, q.v[1]);
    std::copy(q.v[0], q.v[0] + 3, q.v[2]);
    pairs.push_back(q);
    // slivers of height 1e-3 .. 1e-7 of the base
    for (const double hgt : {1e-3, 1e-5, 1e-7}) {
      q = base;
      const D3 perp = unit(cross(b - a, random_unit(g)));
      set_v(&q, 2, 0.3 * a + 0.7 * b + (hgt * norm(b - a)) * perp);
      pairs.push_back(q);
    }
  }
  const Stats st = check_pairs("degenerate", pairs, hulls);
  EXPECT_GT(st.hits, pairs.size() / 5);
  EXPECT_GT(st.misses, pairs.size() / 5);
}

TEST(ConvexTriangle, NeedlePancakeAndLargeFaces) {
  Rng g(37);
  Hulls hulls;
  hulls.add(box_corners(1.0f, 1e-4f, 1e-4f));  // 0: needle box
  hulls.add(box_corners(1.0f, 1.0f, 1e-4f));   // 1: pancake box
  {
    std::vector<Eigen::Vector3f> pts;  // 2: needle cloud, 3: pancake cloud
    for (int i = 0; i < 24; ++i) {
      const D3 u = random_unit(g);
      pts.emplace_back(static_cast<float>(u.x), static_cast<float>(1e-4 * u.y),
                       static_cast<float>(1e-4 * u.z));
    }
    hulls.add(pts);
    pts.clear();
    for (int i = 0; i < 24; ++i) {
      const D3 u = random_unit(g);
      pts.emplace_back(static_cast<float>(u.x), static_cast<float>(u.y), static_cast<float>(1e-4 * u.z));
    }
    hulls.add(pts);
  }
  {
    std::vector<Eigen::Vector3f> pts;  // 4: an 80-gon prism (caps of 80 vertices)
    for (int i = 0; i < 80; ++i) {
      const double t = 2 * M_PI * i / 80;
      for (const float z : {-0.2f, 0.2f})
        pts.emplace_back(static_cast<float>(0.8 * std::cos(t)), static_cast<float>(0.8 * std::sin(t)), z);
    }
    hulls.add(pts);
  }
  const auto pairs = random_pairs(g, hulls, 0, 5, scaled(500), 1.0, 0.0);
  const Stats st = check_pairs("needle, pancake, 80-gon", pairs, hulls);
  EXPECT_GT(st.hits, pairs.size() / 5);
  {
    std::vector<Eigen::Vector3f> pts;  // 5: a 300-gon prism (caps over kMaxFaceVerts = 256)
    for (int i = 0; i < 300; ++i) {
      const double t = 2 * M_PI * i / 300;
      for (const float z : {-0.2f, 0.2f})
        pts.emplace_back(static_cast<float>(0.8 * std::cos(t)), static_cast<float>(0.8 * std::sin(t)), z);
    }
    hulls.add(pts);
  }
  // A triangle lying on the 80-gon cap: a face contact, clipped (the triangle's three
  // vertices below the cap); on the 300-gon's cap, too large to clip: one point, the
  // deepest vertex.
  Pair q{};
  const float R[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  std::copy(R, R + 9, q.R);
  const double z = 0.2 - 1e-3;
  set_v(&q, 0, {-0.3, -0.2, z}), set_v(&q, 1, {0.4, -0.2, z - 1e-4}), set_v(&q, 2, {0.0, 0.3, z});
  for (const uint32_t hull : {4u, 5u}) {
    q.hull = hull;
    check_pairs(hull == 4 ? "on an 80-gon" : "on a 300-gon", {q}, hulls);
    const PairResult r = run(Bucket({q}), hulls.store.view(), k::KernelPath::kSimd).result();
    ASSERT_EQ(r.count, hull == 4 ? 3u : 1u);
    EXPECT_NEAR(r.n.z(), 1.0, 1e-6);
    EXPECT_NEAR(r.depth, 1.1e-3, 1e-6);
  }
}

TEST(ConvexTriangle, EdgeAxisAmongNearTies) {
  // A triangle edge nearly parallel to a hull face: the three edge axes of that face's
  // edges lie within 1e-4 rad of each other and separate within 2e-6; the winner's two
  // edges need not meet where the triangle touches (their closest points 0.013 apart,
  // depth 0.012), so the point comes from where the moved triangle edge touches the hull.
  // (Found by the random test at IMPACT_TEST_INTENSITY=10.)
  const Hulls& hulls = shared_hulls();
  Pair q{};
  q.hull = 6;
  const float R[9] = {0.862498283f, 0.255927533f, 0.436575115f,  -0.483454734f, 0.161743909f,
                      0.860296726f, 0.149560258f, -0.953068733f, 0.263233215f};
  std::copy(R, R + 9, q.R);
  set_v(&q, 0, {-1.55485225, -0.0603146963, 0.501388371});
  set_v(&q, 1, {-0.531383216, 0.122595489, -0.994282961});
  set_v(&q, 2, {-0.00481640548, 0.519059598, 0.872050345});
  const Stats st = check_pairs("edge axis among near ties", {q}, hulls);
  EXPECT_EQ(st.hits, 1u);
}

TEST(ConvexTriangle, WindingDoesNotMatter) {
  Rng g(38);
  const Hulls& hulls = shared_hulls();
  const auto pairs = random_pairs(g, hulls, 0, kHullsRandom + 1, scaled(1000), 1.0, 0.0);
  std::vector<Pair> flipped = pairs;
  for (Pair& q : flipped) std::swap(q.v[1], q.v[2]);
  const ManifoldLanes x = run(Bucket(pairs), hulls.store.view(), k::KernelPath::kSimd);
  const ManifoldLanes y = run(Bucket(flipped), hulls.store.view(), k::KernelPath::kSimd);
  for (uint32_t i = 0; i < pairs.size(); ++i) {
    const PairResult a = x.result(i), b = y.result(i);
    const RefHull H = pose(hulls.data[pairs[i].hull], pairs[i]);
    const RefTri T = ref_tri(pairs[i]);
    const double tol = kRel * std::max(H.radius, tri_radius(T));
    if (a.count == 0 || b.count == 0) {
      EXPECT_LT(std::max(a.count ? a.depth : 0.0, b.count ? b.depth : 0.0), tol) << "lane " << i;
      continue;
    }
    EXPECT_NEAR(a.depth, b.depth, tol) << "lane " << i;
    EXPECT_NEAR(separation(H, T, D3{b.n.x(), b.n.y(), b.n.z()}), -a.depth, tol) << "lane " << i;
  }
}

TEST(ConvexTriangle, HullWithoutAdjacencyTakesGjkEpa) {
  Rng g(40);
  const Hulls& hulls = shared_hulls();
  const auto pairs = random_pairs(g, hulls, 0, kHullsRandom + 1, 200, 1.0, 0.0);
  const Bucket bk(pairs);
  k::HullView hv = hulls.store.view();
  hv.adj_begin = nullptr;
  const ManifoldLanes x = run(bk, hv, k::KernelPath::kSimd);
  const ManifoldLanes y = run_gjk(bk, hv);
  for (uint32_t i = 0; i < bk.n; ++i) EXPECT_EQ(x.lane_bits(i), y.lane_bits(i)) << "lane " << i;
}

TEST(ConvexTriangle, BruteForceAgreesWithTheSampledReference) {
  // The brute-force SAT (this file's reference) against narrow_reference.h's sampled
  // minimum of the support overlap, without its polytope hints.
  Rng g(41);
  const Hulls& hulls = shared_hulls();
  const auto pairs = random_pairs(g, hulls, 0, kHullsRandom + 1, scaled(40), 1.0, 0.0, 0.6, 1.2);
  nref::Options opt;
  opt.use_hints = false;
  for (const Pair& q : pairs) {
    const RefHull H = pose(hulls.data[q.hull], q);
    const RefTri T = ref_tri(q);
    std::vector<nref::V3> pts;
    for (const D3& v : H.v) pts.push_back(nref::V3{v.x, v.y, v.z});
    const nref::Shape a = nref::make_convex(pts);
    const nref::Shape b =
        nref::make_triangle(nref::V3{T.v[0].x, T.v[0].y, T.v[0].z}, nref::V3{T.v[1].x, T.v[1].y, T.v[1].z},
                            nref::V3{T.v[2].x, T.v[2].y, T.v[2].z});
    const nref::PairResult r = nref::solve_pair(a, b, {}, opt);
    const SatRef s = brute_sat(H, T, std::max(H.radius, tri_radius(T)));
    const double L = std::max(H.radius, tri_radius(T));
    if (-s.s > 0) {
      EXPECT_NEAR(-s.s, r.s, 1e-7 * L) << lane_text(q);  // the depth
    } else {
      EXPECT_LE(r.s, 1e-9 * L) << lane_text(q);  // apart; the SAT's gap is at most the distance
      EXPECT_LE(s.s, -r.s + 1e-9 * L) << lane_text(q);
    }
  }
}

}  // namespace
}  // namespace impact::test
