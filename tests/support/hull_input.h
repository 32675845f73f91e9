// Inputs and double-precision geometry of the exact hull-kernel tests
// (sphere_convex_test, capsule_convex_test): a small double vector, random draws, hulls
// built by the library's quickhull into one HullStore (boxes, ellipsoid point clouds),
// and hulls posed in double for the references. A lane is any struct with the hull's
// position p[3] and row-major rotation R[9] (and, for hull_leaf, its index hull).
#pragma once

#include <gtest/gtest.h>

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include "host/shapes/convex_hull.h"
#include "host/shapes/shape_store.h"
#include "kernels/narrowphase/pair_kernels.h"
#include "support/leaf_lanes.h"
#include "support/random_input.h"
#include "support/test_support.h"

namespace impact::test::hull_input {

struct D3 {
  double x = 0, y = 0, z = 0;
};
inline D3 operator+(D3 a, D3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
inline D3 operator-(D3 a, D3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
inline D3 operator*(double s, D3 a) { return {s * a.x, s * a.y, s * a.z}; }
inline double dot(D3 a, D3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline D3 cross(D3 a, D3 b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
inline double norm(D3 a) { return std::sqrt(dot(a, a)); }
inline D3 unit(D3 a) { return (1.0 / norm(a)) * a; }

using Rng = std::mt19937;
inline double uni(Rng& g, double a, double b) { return std::uniform_real_distribution<double>(a, b)(g); }
/// test::random_normal_draws, normalised as a D3.
inline D3 random_unit(Rng& g) {
  const Eigen::Vector3d v = random_normal_draws(g);
  return unit(D3{v.x(), v.y(), v.z()});
}
/// Row-major rotation (test::random_rotation_rows) in float.
inline void random_rotation(Rng& g, float m[9]) {
  double r[9];
  test::random_rotation_rows(g, r);
  for (int i = 0; i < 9; ++i) m[i] = static_cast<float>(r[i]);
}

/// v rounded to float into out[3].
inline void store_float(D3 v, float out[3]) {
  out[0] = static_cast<float>(v.x), out[1] = static_cast<float>(v.y), out[2] = static_cast<float>(v.z);
}

/// Hulls in one store, with their HullData for the references.
struct Hulls {
  HullStore store;
  std::vector<HullData> data;
  uint32_t add(const std::vector<Eigen::Vector3f>& pts) {
    HullData h;
    EXPECT_TRUE(build_convex_hull(pts, &h).ok());
    data.push_back(h);
    return store.add(h);
  }
};

inline std::vector<Eigen::Vector3f> box_corners(float hx, float hy, float hz) {
  std::vector<Eigen::Vector3f> c;
  for (int i = 0; i < 8; ++i) c.emplace_back((i & 1) ? hx : -hx, (i & 2) ? hy : -hy, (i & 4) ? hz : -hz);
  return c;
}

/// np points on an ellipsoid with half axes in [0.3, 1] * scale.
inline std::vector<Eigen::Vector3f> ellipsoid_points(Rng& g, int np, double scale) {
  const double ax[3] = {uni(g, 0.3, 1.0), uni(g, 0.3, 1.0), uni(g, 0.3, 1.0)};
  std::vector<Eigen::Vector3f> pts;
  for (int i = 0; i < np; ++i) {
    const D3 u = random_unit(g);
    pts.emplace_back(static_cast<float>(scale * ax[0] * u.x), static_cast<float>(scale * ax[1] * u.y),
                     static_cast<float>(scale * ax[2] * u.z));
  }
  return pts;
}

/// Random hulls of size ~scale: boxes and ellipsoid point clouds of 8..40 points.
inline void add_random_hulls(Rng& g, Hulls* hulls, uint32_t count, double scale) {
  for (uint32_t i = 0; i < count; ++i) {
    if (i % 4 == 0) {
      hulls->add(box_corners(static_cast<float>(scale * uni(g, 0.1, 1.0)),
                             static_cast<float>(scale * uni(g, 0.1, 1.0)),
                             static_cast<float>(scale * uni(g, 0.1, 1.0))));
    } else {
      hulls->add(ellipsoid_points(g, 8 + static_cast<int>(g() % 33), scale));
    }
  }
}

/// Hull-local point l in world coordinates for lane q (double).
template <class Lane>
D3 to_world(const Lane& q, const Eigen::Vector3f& l) {
  const double x = l.x(), y = l.y(), z = l.z();
  return D3{q.p[0] + q.R[0] * x + q.R[1] * y + q.R[2] * z, q.p[1] + q.R[3] * x + q.R[4] * y + q.R[5] * z,
            q.p[2] + q.R[6] * x + q.R[7] * y + q.R[8] * z};
}

/// A hull posed in double, relative to its position (exact for the float inputs, and
/// no cancellation far from the origin): vertices, polygons, Newell planes.
struct RefHull {
  D3 origin;  // the hull position (world)
  std::vector<D3> v;
  std::vector<std::vector<uint32_t>> faces;
  std::vector<D3> fn;
  std::vector<double> fd;
  double radius = 0;  // about the position
  D3 centroid;
};

template <class Lane>
RefHull pose(const HullData& h, const Lane& q) {
  RefHull out;
  out.origin = D3{q.p[0], q.p[1], q.p[2]};
  for (const auto& l : h.vertices) {
    const double x = l.x(), y = l.y(), z = l.z();
    const D3 w{q.R[0] * x + q.R[1] * y + q.R[2] * z, q.R[3] * x + q.R[4] * y + q.R[5] * z,
               q.R[6] * x + q.R[7] * y + q.R[8] * z};
    out.radius = std::max(out.radius, norm(w));
    out.v.push_back(w);
    out.centroid = out.centroid + out.v.back();
  }
  out.centroid = (1.0 / static_cast<double>(out.v.size())) * out.centroid;
  out.faces = h.faces;
  for (const auto& f : h.faces) {
    D3 nn, m;
    for (size_t i = 0; i < f.size(); ++i) {
      const D3 a = out.v[f[i]], b = out.v[f[(i + 1) % f.size()]];
      nn = nn + cross(a, b);  // Newell: 2 * area * normal (counter-clockwise from outside)
      m = m + a;
    }
    nn = unit(nn);
    m = (1.0 / static_cast<double>(f.size())) * m;
    out.fn.push_back(nn);
    out.fd.push_back(dot(nn, m));
  }
  return out;
}

/// The point of segment [a, b] closest to c (a when the segment has no length).
inline D3 closest_on_segment(D3 a, D3 b, D3 c) {
  const D3 d = b - a;
  if (!(dot(d, d) > 0)) return a;
  const double t = std::clamp(dot(c - a, d) / dot(d, d), 0.0, 1.0);
  return a + t * d;
}

/// Test part results (failures) recorded so far in the running test.
inline int failure_parts() {
  return ::testing::UnitTest::GetInstance()->current_test_info()->result()->total_part_count();
}

/// HullData from vertices and convex polygons given in cyclic order (either
/// orientation): planes by Newell's method in double, polygons turned counter-clockwise
/// seen from outside, offsets = the largest n.v over the hull (every vertex behind), one edge direction
/// per parallel class.
inline HullData hull_from_polygons(const std::vector<Eigen::Vector3f>& v,
                                   std::vector<std::vector<uint32_t>> polys) {
  HullData h;
  h.vertices = v;
  D3 centre;
  for (const auto& q : v) centre = centre + D3{q.x(), q.y(), q.z()};
  centre = (1.0 / static_cast<double>(v.size())) * centre;
  auto at = [&](uint32_t i) { return D3{v[i].x(), v[i].y(), v[i].z()}; };
  for (auto& poly : polys) {
    D3 nn, m;
    for (size_t i = 0; i < poly.size(); ++i) {
      nn = nn + cross(at(poly[i]), at(poly[(i + 1) % poly.size()]));
      m = m + at(poly[i]);
    }
    m = (1.0 / static_cast<double>(poly.size())) * m;
    if (dot(nn, m - centre) < 0) {
      std::reverse(poly.begin(), poly.end());
      nn = -1.0 * nn;
    }
    nn = unit(nn);
    double off = -1e300;
    for (uint32_t i = 0; i < v.size(); ++i) off = std::max(off, dot(nn, at(i)));
    h.faces.push_back(poly);
    h.face_normals.emplace_back(static_cast<float>(nn.x), static_cast<float>(nn.y), static_cast<float>(nn.z));
    h.face_offsets.push_back(static_cast<float>(off));
    for (size_t i = 0; i < poly.size(); ++i) {
      const D3 ed = unit(at(poly[(i + 1) % poly.size()]) - at(poly[i]));
      bool dup = false;
      for (const auto& x : h.edge_dirs) dup = dup || std::fabs(dot(ed, D3{x.x(), x.y(), x.z()})) > 1 - 1e-12;
      if (!dup)
        h.edge_dirs.emplace_back(static_cast<float>(ed.x), static_cast<float>(ed.y),
                                 static_cast<float>(ed.z));
    }
  }
  return h;
}

/// The scale suites of the hull tests, pairs(g, hulls, 0, hull_count, scaled(n), scale,
/// offset) (a test's random_pairs) around random hulls checked by check(name, pairs,
/// hulls) (statistics with hits and misses): tiny (1e-4), huge (1e4) and far (1e5 from the origin), 800 pairs
/// around 12 hulls each, more than 100 hits and 100 misses; and many_n pairs around a 400-point hull (more
/// than 500 faces) 3 from the origin, more than many_hits hits and many_misses misses.
template <class Pairs, class Check>
void check_scale_suites(Pairs pairs, Check check, uint32_t many_n, uint32_t many_hits, uint32_t many_misses) {
  for (const double scale : {1e-4, 1e4}) {
    Rng g(777 + static_cast<uint32_t>(scale > 1));
    Hulls hulls;
    add_random_hulls(g, &hulls, 12, scale);
    const auto st =
        check("scale " + std::to_string(scale), pairs(g, hulls, 0, 12, scaled(800), scale, 0.0), hulls);
    EXPECT_GT(st.hits, 100u);
    EXPECT_GT(st.misses, 100u);
  }
  {
    Rng g(4242);
    Hulls hulls;
    add_random_hulls(g, &hulls, 12, 1.0);
    const auto st = check("far 1e5", pairs(g, hulls, 0, 12, scaled(800), 1.0, 1e5), hulls);
    EXPECT_GT(st.hits, 100u);
    EXPECT_GT(st.misses, 100u);
  }
  Rng g(99);
  Hulls hulls;
  hulls.add(ellipsoid_points(g, 400, 1.0));
  ASSERT_GT(hulls.data[0].faces.size(), 500u);
  const auto st = check("400-point hull", pairs(g, hulls, 0, 1, scaled(many_n), 1.0, 3.0), hulls);
  EXPECT_GT(st.hits, many_hits);
  EXPECT_GT(st.misses, many_misses);
}

/// Where point_near_hull put its point.
enum class Near { kBox, kVertex, kEdge, kFace };

/// A random point near hull h posed as lane q (p, R): uniform in the box of +-2 scale
/// about its origin, within reach * [0, spread] of a vertex or of an edge point, or along
/// a face's normal within reach * [-spread, spread] of the face's centroid (*face_normal:
/// that normal in the world, unnormalised by the pose's float rotation), one in four each.
template <class Lane>
D3 point_near_hull(Rng& g, const HullData& h, const Lane& q, double scale, double reach, double spread,
                   Near* where = nullptr, D3* face_normal = nullptr) {
  const uint32_t pick = static_cast<uint32_t>(g() % 4);
  if (where != nullptr) *where = static_cast<Near>(pick);
  switch (pick) {
    case 0:
      return to_world(q, Eigen::Vector3f::Zero()) +
             D3{uni(g, -2 * scale, 2 * scale), uni(g, -2 * scale, 2 * scale), uni(g, -2 * scale, 2 * scale)};
    case 1:
      return to_world(q, h.vertices[g() % h.vertices.size()]) +
             (reach * uni(g, 0.0, spread)) * random_unit(g);
    case 2: {
      const auto& f = h.faces[g() % h.faces.size()];
      const size_t j = g() % f.size();
      const D3 a = to_world(q, h.vertices[f[j]]), b = to_world(q, h.vertices[f[(j + 1) % f.size()]]);
      return a + uni(g, 0, 1) * (b - a) + (reach * uni(g, 0.0, spread)) * random_unit(g);
    }
    default: {
      const size_t fi = g() % h.faces.size();
      const auto& f = h.faces[fi];
      D3 m;
      for (uint32_t v : f) m = m + to_world(q, h.vertices[v]);
      m = (1.0 / static_cast<double>(f.size())) * m;
      const D3 nw = to_world(q, h.face_normals[fi]) - to_world(q, Eigen::Vector3f::Zero());
      if (face_normal != nullptr) *face_normal = nw;
      return m + (reach * uni(g, -spread, spread)) * nw;
    }
  }
}

/// The hull of lane q as a kernel reads it: its pose and its index in the store.
template <class Lane>
Leaf hull_leaf(const Lane& q) {
  Leaf b;
  b.t = kernels::kLeafConvex;
  std::copy(q.p, q.p + 3, b.p);
  std::copy(q.R, q.R + 9, b.r);
  b.ref = q.hull;
  return b;
}

/// GJK + EPA (collide_gjk_epa, the general route) for bucket (A, hull) over bk, SIMD path.
template <kernels::LeafType A>
ManifoldLanes run_gjk_epa(const BucketLanes& bk, const kernels::HullView& hv) {
  return bk.run(
      [](const kernels::LeafSoA& a, const kernels::LeafSoA& b, const kernels::ManifoldSoA& o,
         kernels::Range r, const kernels::NarrowConfig& cfg) {
        kernels::collide_gjk_epa(a, b, o, r, cfg, A, kernels::kLeafConvex);
      },
      hv, kernels::KernelPath::kSimd);
}

/// A random lane's hull, one of [h0, h1), and its rotation.
template <class Lane>
void random_hull_and_rotation(Rng& g, uint32_t h0, uint32_t h1, Lane* q) {
  q->hull = h0 + static_cast<uint32_t>(g() % (h1 - h0));
  random_rotation(g, q->R);
}

/// The hull's position for a random lane: within scale per axis of a point offset from
/// the origin in a random direction, rounded to float into p[3].
inline void random_hull_position(Rng& g, double scale, double offset, float p[3]) {
  const D3 x =
      offset * random_unit(g) + D3{uni(g, -scale, scale), uni(g, -scale, scale), uni(g, -scale, scale)};
  store_float(x, p);
}

/// A cube of half extent 1 whose top corner (1, 1, 1) is raised by 2^-22: the top face
/// becomes two triangles whose planes differ by ~1e-7 rad (the float rounding of the
/// plane distances), so a point's deepest plane in float is often the wrong one of the
/// two. Added to hulls as its next hull.
inline void add_nearly_coplanar_cube(Hulls* hulls) {
  std::vector<Eigen::Vector3f> v = box_corners(1.0f, 1.0f, 1.0f);
  v[7].z() = 1.0f + 0x1p-22f;
  hulls->data.push_back(hull_from_polygons(
      v, {{0, 1, 3, 2}, {0, 2, 6, 4}, {1, 3, 7, 5}, {0, 1, 5, 4}, {2, 3, 7, 6}, {4, 5, 7}, {4, 7, 6}}));
  hulls->store.add(hulls->data.back());
}

/// The hull tests' main random suite: 24 random hulls of size 1 (seed 12345) and
/// scaled(3000) pairs(g, hulls, 0, 24, n, 1, 10) around them (a test's random_pairs), 10
/// from the origin, checked by check("random", pairs, hulls); returns the statistics,
/// *n_pairs the pair count.
template <class Pairs, class Check>
auto check_random_suite(Pairs pairs, Check check, size_t* n_pairs) {
  Rng g(12345);
  Hulls hulls;
  add_random_hulls(g, &hulls, 24, 1.0);
  const auto ps = pairs(g, hulls, 0, 24, scaled(3000), 1.0, 10.0);
  *n_pairs = ps.size();
  return check("random", ps, hulls);
}

}  // namespace impact::test::hull_input
