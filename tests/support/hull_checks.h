// An O(n log n) check of a convex hull's defining properties, for clouds too large for
// the brute-force checks of convex_hull_test (100k points on a sphere: ~2e10 point-plane
// tests brute force). Each property is checked exactly, in double from the float output:
//   - every vertex is an input point, and no two vertices are equal (sorted lookups);
//   - the faces form a closed 2-manifold (each directed edge once, with its reverse),
//     every vertex is used, and V - E + F = 2 (Euler's formula for a sphere);
//   - every face is planar within tol, its normal unit and outward, its corners convex
//     and counter-clockwise about the normal;
//   - every edge is convex: the far face's vertices lie on or below the near face's plane;
//   - every input point is on or below every face plane (within tol): a branch and bound
//     over a binary tree of the face planes (n, d), sorted by the Morton code of n,
//     each node bounding the planes below it by a box in (n, d); a node is opened only
//     when the box's largest n.p - d can exceed tol / 2, so no face is skipped that
//     could fail (cost O(log F + faces near p) per point);
//   - the edge directions are unit and pairwise non-parallel (|cos| < 1 - 1e-8), and every
//     polygon edge is parallel to one of them within 1 - 1e-5: a grid of cells of 1e-2
//     over the unit directions and their negatives (the 8 cells nearest a query hold
//     every direction within 5e-3 of it per axis; 1 - 1e-5 is within 4.5e-3).
#pragma once

#include <gtest/gtest.h>

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <map>
#include <unordered_map>
#include <vector>

#include "host/shapes/shape_store.h"

namespace impact::test {

namespace hull_checks_detail {

using Vec3d = Eigen::Vector3d;

inline bool less_xyz(const Eigen::Vector3f& a, const Eigen::Vector3f& b) {
  if (a.x() != b.x()) return a.x() < b.x();
  if (a.y() != b.y()) return a.y() < b.y();
  return a.z() < b.z();
}

/// 10-bit Morton code of a unit normal (each coordinate in [-1, 1]).
inline uint32_t morton_of(const Vec3d& n) {
  uint32_t code = 0;
  uint32_t q[3];
  for (int a = 0; a < 3; ++a) q[a] = static_cast<uint32_t>(std::clamp((n[a] + 1.0) * 511.5, 0.0, 1023.0));
  for (int bit = 9; bit >= 0; --bit)
    for (int a = 0; a < 3; ++a) code = (code << 1) | ((q[a] >> bit) & 1u);
  return code;
}

/// Face planes (n, d) in a binary tree of boxes; see the file comment.
class PlaneTree {
 public:
  explicit PlaneTree(std::vector<std::array<double, 4>> planes) : planes_(std::move(planes)) {
    std::vector<std::pair<uint32_t, uint32_t>> order(planes_.size());
    for (uint32_t i = 0; i < planes_.size(); ++i)
      order[i] = {morton_of(Vec3d(planes_[i][0], planes_[i][1], planes_[i][2])), i};
    std::sort(order.begin(), order.end());
    std::vector<std::array<double, 4>> sorted(planes_.size());
    for (size_t i = 0; i < order.size(); ++i) sorted[i] = planes_[order[i].second];
    planes_ = std::move(sorted);
    build(0, static_cast<uint32_t>(planes_.size()));
  }

  /// The largest n.p - d over the planes that can exceed `limit` (or a value <= limit).
  double max_above(const Vec3d& p, double limit) const { return visit(0, p, limit); }

 private:
  struct Node {
    double lo[4], hi[4];
    uint32_t begin, end, left, right;
  };

  uint32_t build(uint32_t b, uint32_t e) {
    const uint32_t id = static_cast<uint32_t>(nodes_.size());
    nodes_.push_back(Node{});
    Node nd{};
    for (int k = 0; k < 4; ++k) nd.lo[k] = INFINITY, nd.hi[k] = -INFINITY;
    for (uint32_t i = b; i < e; ++i)
      for (int k = 0; k < 4; ++k) {
        nd.lo[k] = std::min(nd.lo[k], planes_[i][k]);
        nd.hi[k] = std::max(nd.hi[k], planes_[i][k]);
      }
    nd.begin = b;
    nd.end = e;
    nd.left = nd.right = UINT32_MAX;
    if (e - b > 4) {
      const uint32_t m = b + (e - b) / 2;
      nd.left = build(b, m);
      nd.right = build(m, e);
    }
    nodes_[id] = nd;
    return id;
  }

  double visit(uint32_t id, const Vec3d& p, double limit) const {
    const Node& nd = nodes_[id];
    double bound = -nd.lo[3];
    for (int a = 0; a < 3; ++a) bound += p[a] >= 0 ? nd.hi[a] * p[a] : nd.lo[a] * p[a];
    if (bound <= limit) return bound;
    if (nd.left == UINT32_MAX) {
      double best = -INFINITY;
      for (uint32_t i = nd.begin; i < nd.end; ++i)
        best = std::max(best, planes_[i][0] * p[0] + planes_[i][1] * p[1] + planes_[i][2] * p[2] - planes_[i][3]);
      return best;
    }
    return std::max(visit(nd.left, p, limit), visit(nd.right, p, limit));
  }

  std::vector<std::array<double, 4>> planes_;
  std::vector<Node> nodes_;
};

/// Unit directions and their negatives in cells of 1e-2 (a hash map that only answers
/// lookups). Every direction within 5e-3 of +-d per axis is in one of the 2 x 2 x 2
/// cells nearest d.
class DirectionGrid {
 public:
  explicit DirectionGrid(const std::vector<Vec3d>& dirs) : dirs_(dirs) {
    for (uint32_t i = 0; i < dirs_.size(); ++i) {
      cells_[key(cell(dirs_[i].x()), cell(dirs_[i].y()), cell(dirs_[i].z()))].push_back(i);
      cells_[key(cell(-dirs_[i].x()), cell(-dirs_[i].y()), cell(-dirs_[i].z()))].push_back(i);
    }
  }
  /// The largest |cos| between d and a direction other than `skip` within 5e-3 of +-d.
  double best_cos(const Vec3d& d, uint32_t skip = UINT32_MAX) const {
    int64_t lo[3];
    for (int a = 0; a < 3; ++a) {
      const double c = (d[a] + 2.0) * 100.0;
      lo[a] = static_cast<int64_t>(std::floor(c)) - (c - std::floor(c) < 0.5 ? 1 : 0);
    }
    double best = 0;
    for (int k = 0; k < 8; ++k) {
      const auto it = cells_.find(key(lo[0] + (k & 1), lo[1] + ((k >> 1) & 1), lo[2] + (k >> 2)));
      if (it == cells_.end()) continue;
      for (uint32_t j : it->second)
        if (j != skip) best = std::max(best, std::fabs(dirs_[j].dot(d)));
    }
    return best;
  }

 private:
  static int64_t cell(double x) { return static_cast<int64_t>(std::floor((x + 2.0) * 100.0)); }
  static uint64_t key(int64_t x, int64_t y, int64_t z) {
    return (static_cast<uint64_t>(x) << 40) | (static_cast<uint64_t>(y) << 20) | static_cast<uint64_t>(z);
  }
  const std::vector<Vec3d>& dirs_;
  std::unordered_map<uint64_t, std::vector<uint32_t>> cells_;
};

}  // namespace hull_checks_detail

/// Checks h against pts as the file comment says; tol is relative to pts' bounding-box
/// diagonal (the brute-force checks of convex_hull_test use 1e-5).
inline void check_hull_scalable(const std::vector<Eigen::Vector3f>& pts, const HullData& h, double rel_tol = 1e-5) {
  using hull_checks_detail::Vec3d;
  ASSERT_EQ(h.faces.size(), h.face_normals.size());
  ASSERT_EQ(h.faces.size(), h.face_offsets.size());
  ASSERT_GE(h.vertices.size(), 4u);
  Eigen::Vector3f lo = pts[0], hi = pts[0];
  Vec3d centre = Vec3d::Zero();
  for (const auto& p : pts) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  const double D = (hi - lo).cast<double>().norm();
  const double tol = rel_tol * D;
  // Vertices: input points, distinct.
  std::vector<Eigen::Vector3f> sorted_pts = pts, sorted_verts = h.vertices;
  std::sort(sorted_pts.begin(), sorted_pts.end(), hull_checks_detail::less_xyz);
  std::sort(sorted_verts.begin(), sorted_verts.end(), hull_checks_detail::less_xyz);
  size_t not_input = 0, repeated = 0;
  for (size_t i = 0; i < sorted_verts.size(); ++i) {
    not_input += !std::binary_search(sorted_pts.begin(), sorted_pts.end(), sorted_verts[i], hull_checks_detail::less_xyz);
    repeated += i > 0 && sorted_verts[i] == sorted_verts[i - 1];
  }
  EXPECT_EQ(not_input, 0u);
  EXPECT_EQ(repeated, 0u);
  // Closed 2-manifold and Euler's formula.
  std::map<std::pair<uint32_t, uint32_t>, uint32_t> face_of;  // directed edge -> face
  std::vector<uint8_t> used(h.vertices.size(), 0);
  size_t corners = 0, repeated_edges = 0;
  for (uint32_t fi = 0; fi < h.faces.size(); ++fi) {
    const auto& f = h.faces[fi];
    ASSERT_GE(f.size(), 3u);
    corners += f.size();
    for (size_t k = 0; k < f.size(); ++k) {
      ASSERT_LT(f[k], h.vertices.size());
      used[f[k]] = 1;
      repeated_edges += !face_of.emplace(std::make_pair(f[k], f[(k + 1) % f.size()]), fi).second;
    }
  }
  EXPECT_EQ(repeated_edges, 0u);
  EXPECT_EQ(static_cast<size_t>(std::count(used.begin(), used.end(), 1)), h.vertices.size());
  size_t open_edges = 0;
  for (const auto& [e, fi] : face_of) open_edges += !face_of.count({e.second, e.first});
  EXPECT_EQ(open_edges, 0u);
  const long V = static_cast<long>(h.vertices.size()), E = static_cast<long>(corners / 2),
             F = static_cast<long>(h.faces.size());
  EXPECT_EQ(V - E + F, 2);
  for (const auto& v : h.vertices) centre += v.cast<double>();
  centre /= static_cast<double>(h.vertices.size());
  // Faces: planar, outward unit normal, convex counter-clockwise corners.
  size_t bad_normal = 0, not_planar = 0, reflex = 0, inward = 0, wound = 0;
  std::vector<std::array<double, 4>> planes(h.faces.size());  // about the centre
  for (size_t fi = 0; fi < h.faces.size(); ++fi) {
    const auto& f = h.faces[fi];
    const Vec3d n = h.face_normals[fi].cast<double>();
    const double d = h.face_offsets[fi];
    bad_normal += std::fabs(n.norm() - 1.0) > 1e-6;
    inward += !(n.dot(centre) < d - tol);
    Vec3d newell = Vec3d::Zero();
    for (size_t k = 0; k < f.size(); ++k) {
      const Vec3d p = h.vertices[f[k]].cast<double>(), q = h.vertices[f[(k + 1) % f.size()]].cast<double>(),
                  r = h.vertices[f[(k + 2) % f.size()]].cast<double>();
      not_planar += std::fabs(n.dot(p) - d) > tol;
      newell += p.cross(q);
      reflex += (q - p).cross(r - q).dot(n) < -tol * D;
    }
    wound += !(newell.normalized().dot(n) > 0.999);
    planes[fi] = {n.x(), n.y(), n.z(), d - n.dot(centre)};
  }
  EXPECT_EQ(bad_normal, 0u);
  EXPECT_EQ(inward, 0u);
  EXPECT_EQ(not_planar, 0u);
  EXPECT_EQ(reflex, 0u);
  EXPECT_EQ(wound, 0u);
  // Convex edges: the face across each directed edge lies on or below this face's plane.
  size_t concave = 0;
  for (const auto& [e, fi] : face_of) {
    const auto it = face_of.find({e.second, e.first});
    if (it == face_of.end()) continue;
    const Vec3d n = h.face_normals[fi].cast<double>();
    for (uint32_t v : h.faces[it->second]) concave += n.dot(h.vertices[v].cast<double>()) > h.face_offsets[fi] + tol;
  }
  EXPECT_EQ(concave, 0u);
  // Every input point on or below every face plane.
  const hull_checks_detail::PlaneTree tree(planes);
  size_t outside = 0;
  double worst = -INFINITY;
  for (const auto& p : pts) {
    const double m = tree.max_above(p.cast<double>() - centre, 0.5 * tol);
    if (m > tol) {
      ++outside;
      worst = std::max(worst, m);
    }
  }
  EXPECT_EQ(outside, 0u) << "worst " << worst / D << " of the extent above a face";
  // Edge directions: unit, pairwise non-parallel, covering every polygon edge.
  std::vector<Vec3d> dirs;
  size_t not_unit = 0;
  for (const auto& d : h.edge_dirs) {
    not_unit += std::fabs(d.norm() - 1.0f) > 1e-5f;
    dirs.push_back(d.cast<double>());
  }
  EXPECT_EQ(not_unit, 0u);
  const hull_checks_detail::DirectionGrid grid(dirs);
  size_t parallel = 0, uncovered = 0;
  for (uint32_t i = 0; i < dirs.size(); ++i) parallel += grid.best_cos(dirs[i], i) >= 1 - 1e-8;
  for (const auto& [e, fi] : face_of) {
    const Vec3d d = (h.vertices[e.second] - h.vertices[e.first]).normalized().cast<double>();
    uncovered += !(grid.best_cos(d) > 1 - 1e-5);
  }
  EXPECT_EQ(parallel, 0u);
  EXPECT_EQ(uncovered, 0u);
}

}  // namespace impact::test
