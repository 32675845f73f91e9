// build_convex_hull (host/shapes/convex_hull.cpp): exact face counts of the
// Platonic-ish inputs (with redundant points), and on random clouds the hull's defining
// properties checked by brute force in double: every input point inside or on it, every
// vertex an input point and extreme, closed 2-manifold with V - E + F = 2, planar convex
// faces wound counter-clockwise about outward unit normals, edge directions one per
// parallel class. Degenerate inputs are rejected with a message. Large clouds (100k
// points on a sphere, in a cube, lattices, prisms, pancakes, duplicates) are checked by
// test::check_hull_scalable (tests/support/hull_checks.h), itself checked here to
// agree with the brute-force checks and to catch corrupted hulls.
#include <gtest/gtest-spi.h>
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <random>
#include <set>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "host/shapes/convex_hull.h"
#include "host/shapes/shape_store.h"
#include "support/hull_checks.h"
#include "support/test_support.h"

namespace impact {
namespace {

using V = Eigen::Vector3f;
using Vec3d = Eigen::Vector3d;

double extent(const std::vector<V>& pts) {
  V lo = pts[0], hi = pts[0];
  for (const V& p : pts) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  return (hi - lo).cast<double>().norm();
}

/// Every property of a valid hull of pts, brute force in double.
/// strict_merge: also require that no two adjacent faces are coplanar within 1e-8 of the
/// extent (random clouds may keep such a pair apart when merging it would make a
/// non-convex polygon).
void check_hull(const std::vector<V>& pts, const HullData& h, bool strict_merge = true) {
  const double D = extent(pts);
  const double tol = 1e-5 * D;
  ASSERT_EQ(h.faces.size(), h.face_normals.size());
  ASSERT_EQ(h.faces.size(), h.face_offsets.size());
  ASSERT_GE(h.vertices.size(), 4u);
  // Vertices are input points, distinct.
  for (const V& v : h.vertices) {
    bool found = false;
    for (const V& p : pts) found = found || p == v;
    EXPECT_TRUE(found) << v.transpose();
  }
  for (size_t i = 0; i < h.vertices.size(); ++i)
    for (size_t j = i + 1; j < h.vertices.size(); ++j) EXPECT_NE(h.vertices[i], h.vertices[j]);
  // Closed 2-manifold: each directed edge once, with its reverse.
  std::map<std::pair<uint32_t, uint32_t>, int> directed;
  std::set<uint32_t> used;
  size_t corners = 0;
  for (const auto& f : h.faces) {
    ASSERT_GE(f.size(), 3u);
    corners += f.size();
    for (size_t k = 0; k < f.size(); ++k) {
      ASSERT_LT(f[k], h.vertices.size());
      used.insert(f[k]);
      directed[{f[k], f[(k + 1) % f.size()]}]++;
    }
  }
  EXPECT_EQ(used.size(), h.vertices.size());
  for (const auto& [e, c] : directed) {
    EXPECT_EQ(c, 1);
    EXPECT_EQ(directed.count({e.second, e.first}), 1u) << "open edge " << e.first << "-" << e.second;
  }
  const long V_ = static_cast<long>(h.vertices.size()), E = static_cast<long>(corners / 2),
             F = static_cast<long>(h.faces.size());
  EXPECT_EQ(V_ - E + F, 2);
  // Interior point: the vertices' mean.
  Vec3d c = Vec3d::Zero();
  for (const V& v : h.vertices) c += v.cast<double>();
  c /= static_cast<double>(h.vertices.size());
  for (size_t fi = 0; fi < h.faces.size(); ++fi) {
    const auto& f = h.faces[fi];
    const Vec3d n = h.face_normals[fi].cast<double>();
    const double d = h.face_offsets[fi];
    EXPECT_NEAR(n.norm(), 1.0, 1e-6);
    EXPECT_LT(n.dot(c), d - tol) << "normal not outward";
    // Planar, and counter-clockwise convex seen from outside.
    Vec3d newell = Vec3d::Zero();
    for (size_t k = 0; k < f.size(); ++k) {
      const Vec3d p = h.vertices[f[k]].cast<double>(), q = h.vertices[f[(k + 1) % f.size()]].cast<double>(),
                  r = h.vertices[f[(k + 2) % f.size()]].cast<double>();
      EXPECT_NEAR(n.dot(p), d, tol);
      newell += p.cross(q);
      EXPECT_GE((q - p).cross(r - q).dot(n), -tol * D) << "reflex corner";
    }
    EXPECT_GT(newell.normalized().dot(n), 0.999);
    // Every input point below or on the plane.
    for (const V& p : pts) EXPECT_LE(n.dot(p.cast<double>()), d + tol);
  }
  // Adjacent faces are not coplanar (they would have been merged): some vertex of the
  // neighbour lies clearly below the face's plane.
  std::map<std::pair<uint32_t, uint32_t>, size_t> face_of;
  for (size_t fi = 0; fi < h.faces.size(); ++fi)
    for (size_t k = 0; k < h.faces[fi].size(); ++k)
      face_of[{h.faces[fi][k], h.faces[fi][(k + 1) % h.faces[fi].size()]}] = fi;
  for (const auto& [e, fi] : face_of) {
    const size_t fj = face_of[{e.second, e.first}];
    double lowest = 0;
    for (uint32_t v : h.faces[fj])
      lowest = std::min(lowest, h.face_normals[fi].cast<double>().dot(h.vertices[v].cast<double>()) - h.face_offsets[fi]);
    if (strict_merge) {
      EXPECT_LT(lowest, -1e-8 * D) << "coplanar neighbours " << fi << " " << fj;
    }
  }
  // Edge directions: unit, pairwise non-parallel, covering every polygon edge.
  for (size_t i = 0; i < h.edge_dirs.size(); ++i) {
    EXPECT_NEAR(h.edge_dirs[i].norm(), 1.0f, 1e-5f);
    for (size_t j = i + 1; j < h.edge_dirs.size(); ++j)
      EXPECT_LT(std::fabs(h.edge_dirs[i].cast<double>().dot(h.edge_dirs[j].cast<double>())), 1 - 1e-8);
  }
  for (const auto& f : h.faces)
    for (size_t k = 0; k < f.size(); ++k) {
      const V e = (h.vertices[f[(k + 1) % f.size()]] - h.vertices[f[k]]).normalized();
      bool covered = false;
      for (const V& d : h.edge_dirs) covered = covered || std::fabs(d.dot(e)) > 1 - 1e-5f;
      EXPECT_TRUE(covered);
    }
}

HullData build_ok(const std::vector<V>& pts) {
  HullData h;
  const Status s = build_convex_hull(pts, &h);
  EXPECT_TRUE(test::IsOk(s));
  return h;
}

std::vector<V> cube_corners(float a = 1.0f) {
  std::vector<V> v;
  for (int i = 0; i < 8; ++i) v.emplace_back((i & 1) ? a : -a, (i & 2) ? a : -a, (i & 4) ? a : -a);
  return v;
}

TEST(ConvexHull, CubeHasSixQuads) {
  const auto pts = cube_corners();
  const HullData h = build_ok(pts);
  check_hull(pts, h);
  EXPECT_EQ(h.vertices.size(), 8u);
  ASSERT_EQ(h.faces.size(), 6u);
  for (const auto& f : h.faces) EXPECT_EQ(f.size(), 4u);
  EXPECT_EQ(h.edge_dirs.size(), 3u);
}

TEST(ConvexHull, RedundantPointsDoNotChangeTheCube) {
  std::mt19937 rng(1);
  std::uniform_real_distribution<float> u(-1, 1);
  auto pts = cube_corners();
  // Face centres, edge midpoints, points on faces, interior points, duplicates.
  for (int a = 0; a < 3; ++a)
    for (float s : {-1.0f, 1.0f}) {
      V c = V::Zero();
      c[a] = s;
      pts.push_back(c);
      for (int k = 0; k < 5; ++k) {
        V p(u(rng), u(rng), u(rng));
        p[a] = s;
        pts.push_back(p);
      }
    }
  for (int i = 0; i < 8; ++i)
    for (int j = i + 1; j < 8; ++j) {
      const V m = 0.5f * (pts[i] + pts[j]);
      if ((m.array().abs() == 1.0f).count() >= 2) pts.push_back(m);  // an edge midpoint
    }
  for (int k = 0; k < 50; ++k) pts.emplace_back(0.9f * u(rng), 0.9f * u(rng), 0.9f * u(rng));
  for (int k = 0; k < 8; ++k) pts.push_back(pts[k]);
  std::shuffle(pts.begin(), pts.end(), rng);
  const HullData h = build_ok(pts);
  check_hull(pts, h);
  EXPECT_EQ(h.vertices.size(), 8u);
  ASSERT_EQ(h.faces.size(), 6u);
  for (const auto& f : h.faces) EXPECT_EQ(f.size(), 4u);
}

TEST(ConvexHull, RotatedCubeStillHasSixQuads) {
  std::mt19937 rng(2);
  std::normal_distribution<float> g;
  for (int t = 0; t < 20; ++t) {
    Eigen::Quaternionf q(g(rng), g(rng), g(rng), g(rng));
    q.normalize();
    std::vector<V> pts;
    for (const V& c : cube_corners(3.0f)) pts.push_back(q * c + V(100, -50, 7));
    const HullData h = build_ok(pts);
    check_hull(pts, h);
    EXPECT_EQ(h.faces.size(), 6u);
    EXPECT_EQ(h.edge_dirs.size(), 3u);
  }
}

TEST(ConvexHull, TetrahedronAndOctahedron) {
  const std::vector<V> tet = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  HullData h = build_ok(tet);
  check_hull(tet, h);
  EXPECT_EQ(h.faces.size(), 4u);
  EXPECT_EQ(h.edge_dirs.size(), 6u);
  std::vector<V> oct = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}, {0, 0, 0}};
  h = build_ok(oct);
  check_hull(oct, h);
  EXPECT_EQ(h.vertices.size(), 6u);
  EXPECT_EQ(h.faces.size(), 8u);
  for (const auto& f : h.faces) EXPECT_EQ(f.size(), 3u);
  EXPECT_EQ(h.edge_dirs.size(), 6u);  // 12 edges in opposite pairs
}

TEST(ConvexHull, RandomClouds) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(-1, 1);
  std::normal_distribution<float> g;
  const int clouds = static_cast<int>(test::scaled(40));
  for (int t = 0; t < clouds; ++t) {
    std::vector<V> pts;
    const int n = 4 + (t * 37) % 300;
    const float scale = std::pow(10.0f, static_cast<float>(t % 7) - 3.0f);  // 1e-3 .. 1e3
    for (int i = 0; i < n; ++i) {
      V p;
      switch (t % 5) {
        case 0: p = V(u(rng), u(rng), u(rng)); break;
        case 1: p = V(g(rng), 0.2f * g(rng), g(rng)); break;
        case 2: p = V(g(rng), g(rng), g(rng)).normalized(); break;  // all extreme
        case 3: p = V(u(rng), u(rng), 1e-3f * u(rng)); break;      // pancake
        default: p = V(1e-3f * u(rng), 1e-3f * u(rng), u(rng)); break;  // needle
      }
      pts.push_back(p * scale);
    }
    const HullData h = build_ok(pts);
    SCOPED_TRACE(t);
    check_hull(pts, h, /*strict_merge=*/false);
    if (t % 5 == 2) {
      EXPECT_EQ(h.vertices.size(), pts.size());
    }
  }
}

/// Lattices and prisms: many coplanar and collinear points.
TEST(ConvexHull, StructuredClouds) {
  std::vector<V> grid;
  for (int i = 0; i < 5; ++i)
    for (int j = 0; j < 5; ++j)
      for (int k = 0; k < 5; ++k) grid.emplace_back(static_cast<float>(i), static_cast<float>(j), static_cast<float>(k));
  std::mt19937 rng(5);
  std::shuffle(grid.begin(), grid.end(), rng);
  HullData h = build_ok(grid);
  check_hull(grid, h);
  EXPECT_EQ(h.faces.size(), 6u);
  EXPECT_EQ(h.vertices.size(), 8u);
  // A 24-gon prism: 24 side quads and two 24-gon caps.
  std::vector<V> prism;
  for (int i = 0; i < 24; ++i) {
    const float a = static_cast<float>(i) * 6.2831853f / 24.0f;
    prism.emplace_back(std::cos(a), std::sin(a), -2.0f);
    prism.emplace_back(std::cos(a), std::sin(a), 2.0f);
    prism.emplace_back(std::cos(a), std::sin(a), 0.5f);  // on the side faces
  }
  h = build_ok(prism);
  check_hull(prism, h);
  EXPECT_EQ(h.faces.size(), 26u);
  EXPECT_EQ(h.vertices.size(), 48u);
  size_t caps = 0;
  for (const auto& f : h.faces) caps += f.size() == 24;
  EXPECT_EQ(caps, 2u);
  // A pancake 1e-3 of its width thick.
  std::vector<V> pancake;
  std::uniform_real_distribution<float> u(-1, 1);
  for (int i = 0; i < 200; ++i) pancake.emplace_back(u(rng), u(rng), 1e-3f * u(rng));
  h = build_ok(pancake);
  check_hull(pancake, h);
}

TEST(ConvexHull, ManyPointsOnASphere) {
  std::mt19937 rng(4);
  std::normal_distribution<float> g;
  std::vector<V> pts;
  for (int i = 0; i < 2000; ++i) pts.push_back(V(g(rng), g(rng), g(rng)).normalized());
  const HullData h = build_ok(pts);
  check_hull(pts, h);
  EXPECT_EQ(h.vertices.size(), 2000u);
  // Triangles but for the odd merged near-cocircular quad: F = 2V - 4 for triangles.
  EXPECT_LE(h.faces.size(), 2 * 2000u - 4);
  EXPECT_GE(h.faces.size(), 2 * 2000u - 40);
}

std::vector<V> sphere_points(std::mt19937& rng, int n) {
  std::normal_distribution<float> g;
  std::vector<V> pts;
  while (static_cast<int>(pts.size()) < n) {
    const V p(g(rng), g(rng), g(rng));
    if (p.norm() > 1e-3f) pts.push_back(p.normalized());
  }
  return pts;
}

/// Points that are all hull vertices: the case that made the hull quadratic (the edge
/// classes compared every edge with every class kept; every point re-marked every face).
TEST(ConvexHull, LargeSphereEveryPointAVertex) {
  std::mt19937 rng(21);
  // 30k points keep the O(n log n) checker to seconds; the builder's 100k case is
  // bench/convex_hull_bench.cpp (BM_ConvexHullSphere).
  const int n = test::kSanitized ? 5000 : 30000;
  const auto pts = sphere_points(rng, n);
  const HullData h = build_ok(pts);
  test::check_hull_scalable(pts, h);
  // Every point but the odd one within 1e-9 of the extent of a face (dropped as on it).
  EXPECT_GE(h.vertices.size(), pts.size() - 10);
  EXPECT_GE(h.faces.size(), 2 * h.vertices.size() - 4 - h.vertices.size() / 100);
}

/// Uniform in a cube, on a sphere with duplicates and interior points (shuffled), a
/// lattice (coplanar and collinear points by the thousand), a prism with points along
/// its side lines, the cube's corners with points on its faces and edges, a pancake
/// 1e-3 of its width thick, and a sphere 1e3 m from the origin.
TEST(ConvexHull, LargeAdversarialClouds) {
  std::mt19937 rng(22);
  std::uniform_real_distribution<float> u(-1, 1);
  const int n = test::kSanitized ? 5000 : 20000;
  {
    std::vector<V> pts(static_cast<size_t>(n));
    for (V& p : pts) p = V(u(rng), u(rng), u(rng));
    SCOPED_TRACE("cube");
    test::check_hull_scalable(pts, build_ok(pts));
  }
  {
    const auto sphere = sphere_points(rng, n / 2);
    std::vector<V> pts = sphere;
    pts.insert(pts.end(), sphere.begin(), sphere.end());
    for (int i = 0; i < n / 4; ++i) pts.push_back(0.999f * sphere[static_cast<size_t>(i)]);
    std::shuffle(pts.begin(), pts.end(), rng);
    SCOPED_TRACE("sphere with duplicates");
    const HullData h = build_ok(pts);
    test::check_hull_scalable(pts, h);
    EXPECT_EQ(h.vertices.size(), sphere.size());
  }
  {
    const int k = test::kSanitized ? 16 : 36;
    std::vector<V> pts;
    for (int i = 0; i < k; ++i)
      for (int j = 0; j < k; ++j)
        for (int l = 0; l < k; ++l) pts.emplace_back(static_cast<float>(i), static_cast<float>(j), static_cast<float>(l));
    std::shuffle(pts.begin(), pts.end(), rng);
    SCOPED_TRACE("lattice");
    const HullData h = build_ok(pts);
    test::check_hull_scalable(pts, h);
    EXPECT_EQ(h.vertices.size(), 8u);
    EXPECT_EQ(h.faces.size(), 6u);
    EXPECT_EQ(h.edge_dirs.size(), 3u);
  }
  {
    const int sides = 64;
    std::vector<V> pts;
    for (int i = 0; i < n; ++i) {
      const int s = i % sides;
      const float a = static_cast<float>(s) * 6.2831853f / sides;
      const float z = i < 2 * sides ? (i < sides ? -2.0f : 2.0f) : 2.0f * u(rng);
      pts.emplace_back(std::cos(a), std::sin(a), z);
    }
    std::shuffle(pts.begin(), pts.end(), rng);
    SCOPED_TRACE("prism");
    const HullData h = build_ok(pts);
    test::check_hull_scalable(pts, h);
    EXPECT_EQ(h.vertices.size(), 2u * sides);
    EXPECT_EQ(h.faces.size(), sides + 2u);
  }
  {
    std::vector<V> pts = cube_corners();
    for (int i = 0; i < n; ++i) {
      V p(u(rng), u(rng), u(rng));
      p[i % 3] = (i & 8) ? 1.0f : -1.0f;
      if (i % 5 == 0) p[(i + 1) % 3] = (i & 16) ? 1.0f : -1.0f;  // on an edge
      pts.push_back(p);
    }
    std::shuffle(pts.begin(), pts.end(), rng);
    SCOPED_TRACE("cube faces");
    const HullData h = build_ok(pts);
    test::check_hull_scalable(pts, h);
    EXPECT_EQ(h.vertices.size(), 8u);
    EXPECT_EQ(h.faces.size(), 6u);
  }
  {
    std::vector<V> pts(static_cast<size_t>(n));
    for (V& p : pts) p = V(u(rng), u(rng), 1e-3f * u(rng));
    SCOPED_TRACE("pancake");
    test::check_hull_scalable(pts, build_ok(pts));
  }
  {
    std::vector<V> pts = sphere_points(rng, n / 5);
    for (V& p : pts) p = 10.0f * p + V(1e3f, -1e3f, 5e2f);
    SCOPED_TRACE("far sphere");
    test::check_hull_scalable(pts, build_ok(pts));
  }
}

/// The messages of the failures check_hull_scalable(pts, h) reports (none reach the
/// test's own result).
std::string scalable_check_failures(const std::vector<V>& pts, const HullData& h) {
  ::testing::TestPartResultArray results;
  {
    const ::testing::ScopedFakeTestPartResultReporter reporter(
        ::testing::ScopedFakeTestPartResultReporter::INTERCEPT_ONLY_CURRENT_THREAD, &results);
    test::check_hull_scalable(pts, h);
  }
  std::string all;
  for (int i = 0; i < results.size(); ++i) all += std::string(results.GetTestPartResult(i).message()) + "\n";
  return all;
}

/// check_hull_scalable agrees with the brute-force checks on small clouds, and fails on
/// hulls corrupted in each way it checks (a point outside, a face dropped, a concave
/// edge, a vertex not an input point, a missing edge class).
TEST(ConvexHull, ScalableCheckAgreesAndCatchesFaults) {
  std::mt19937 rng(23);
  for (int t = 0; t < 10; ++t) {
    const auto pts = sphere_points(rng, 50 + 40 * t);
    const HullData h = build_ok(pts);
    check_hull(pts, h);
    EXPECT_EQ(scalable_check_failures(pts, h), "");
  }
  const auto pts = sphere_points(rng, 2000);
  const HullData good = build_ok(pts);
  {
    std::vector<V> more = pts;
    more.push_back(V(0.0f, 0.0f, 1.01f));  // outside
    EXPECT_NE(scalable_check_failures(more, good).find("outside"), std::string::npos);
  }
  {
    HullData bad = good;
    bad.faces.pop_back();
    bad.face_normals.pop_back();
    bad.face_offsets.pop_back();
    EXPECT_NE(scalable_check_failures(pts, bad).find("open_edges"), std::string::npos);
  }
  {
    HullData bad = good;  // the plane of face 0 pushed inward: its neighbours rise above it
    bad.face_offsets[0] -= 0.01f;
    EXPECT_NE(scalable_check_failures(pts, bad).find("concave"), std::string::npos);
  }
  {
    HullData bad = good;
    bad.vertices[0] *= 1.0f + 1e-6f;
    EXPECT_NE(scalable_check_failures(pts, bad).find("not_input"), std::string::npos);
  }
  {
    HullData bad = good;
    bad.edge_dirs.erase(bad.edge_dirs.begin() + 7);
    EXPECT_NE(scalable_check_failures(pts, bad).find("uncovered"), std::string::npos);
  }
}

TEST(ConvexHull, RejectsDegenerateInput) {
  HullData h;
  h.vertices.push_back(V(7, 7, 7));  // must stay unchanged on error
  EXPECT_TRUE(test::IsError(build_convex_hull(std::vector<V>{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, &h),
                            StatusCode::kInvalidArgument, {"at least 4"}));
  EXPECT_TRUE(test::IsError(build_convex_hull(std::vector<V>{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, NAN}, {1, 1, 1}}, &h),
                            StatusCode::kInvalidArgument, {"point 3", "finite"}));
  EXPECT_TRUE(test::IsError(
      build_convex_hull(std::vector<V>{{0, 0, 0}, {1, 0, 0}, {0, INFINITY, 0}, {0, 0, 1}}, &h),
      StatusCode::kInvalidArgument, {"point 2"}));
  EXPECT_TRUE(test::IsError(build_convex_hull(std::vector<V>(5, V(1, 2, 3)), &h), StatusCode::kInvalidArgument,
                            {"coincide"}));
  std::vector<V> line, plane, near_plane, bumped;
  for (int i = 0; i < 10; ++i) line.push_back(V(1, 2, 3) * static_cast<float>(i));
  EXPECT_TRUE(test::IsError(build_convex_hull(line, &h), StatusCode::kInvalidArgument, {"collinear"}));
  for (int i = 0; i < 5; ++i)
    for (int j = 0; j < 5; ++j) plane.push_back(V(static_cast<float>(i), static_cast<float>(j), 2.0f));
  EXPECT_TRUE(test::IsError(build_convex_hull(plane, &h), StatusCode::kInvalidArgument, {"coplanar"}));
  near_plane = plane;
  near_plane[12].z() += 1e-6f;  // 1.8e-7 of the extent: still coplanar
  EXPECT_TRUE(test::IsError(build_convex_hull(near_plane, &h), StatusCode::kInvalidArgument, {"coplanar"}));
  EXPECT_EQ(h.vertices.size(), 1u);
  bumped = plane;
  bumped[12].z() += 1e-2f;  // a flat pyramid: valid
  const HullData ok = build_ok(bumped);
  check_hull(bumped, ok);
  EXPECT_EQ(ok.faces.size(), 5u);  // the square base + 4 triangles
}

TEST(ConvexHull, HullStoreConcatenates) {
  HullStore s;
  const auto cube = build_ok(cube_corners());
  const auto tet = build_ok(std::vector<V>{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}});
  EXPECT_EQ(s.add(cube), 0u);
  EXPECT_EQ(s.add(tet), 1u);
  EXPECT_EQ(s.size(), 2u);
  const kernels::HullView v = s.view();
  EXPECT_EQ(v.vert_begin[1] - v.vert_begin[0], 8u);
  EXPECT_EQ(v.vert_begin[2] - v.vert_begin[1], 4u);
  EXPECT_EQ(v.face_begin[1], 6u);
  EXPECT_EQ(v.face_begin[2], 10u);
  EXPECT_EQ(v.edge_begin[2] - v.edge_begin[1], 6u);
  // Face vertex indices are absolute and match the HullData polygons.
  for (uint32_t f = v.face_begin[1]; f < v.face_begin[2]; ++f) {
    const auto& poly = tet.faces[f - v.face_begin[1]];
    ASSERT_EQ(v.face_vert_begin[f + 1] - v.face_vert_begin[f], poly.size());
    for (size_t k = 0; k < poly.size(); ++k) {
      const uint32_t i = v.face_verts[v.face_vert_begin[f] + k];
      EXPECT_EQ(i, v.vert_begin[1] + poly[k]);
      EXPECT_EQ(V(v.vx[i], v.vy[i], v.vz[i]), tet.vertices[poly[k]]);
    }
    EXPECT_EQ(v.fd[f], tet.face_offsets[f - v.face_begin[1]]);
    EXPECT_EQ(v.fnx[f], tet.face_normals[f - v.face_begin[1]].x());
  }
}

}  // namespace
}  // namespace impact
