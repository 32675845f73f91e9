// Triangle meshes with shared edges and vertices for the ray tests: a closed
// icosphere, a closed fan around one vertex, a heightfield strip (make_grid of
// tests/kernels/raycast/ray_reference.h), each with random per-triangle winding, and
// the targets on their shared edges and vertices that a watertight ray test must
// never let a ray through (Woop, Benthin, Wald, "Watertight Ray/Triangle
// Intersection", JCGT 2(1), 2013, section 2: the failure cases).
//
// Vertices are float (what the scenes get); targets are double points on or within a
// barycentric offset of an interior (two-triangle) edge, or at an interior vertex (one
// that every incident edge is interior around). Rays aimed at them must hit: a
// neighbourhood of every target lies in the union of the triangles around it.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <map>
#include <random>
#include <utility>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "support/test_support.h"

namespace impact::test {

/// A mesh as RayScene::add_mesh takes it.
struct TriMesh {
  Eigen::Matrix3Xf v;
  Eigen::Matrix<uint32_t, 3, Eigen::Dynamic> t;
};

/// An icosahedron subdivided `levels` times, projected onto the sphere of `radius`
/// about `centre`, randomly rotated, vertices rounded to float. Closed: every edge is
/// shared by exactly two triangles.
inline TriMesh make_icosphere(uint32_t levels, double radius, const Eigen::Vector3d& centre, std::mt19937& rng) {
  const double g = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<Eigen::Vector3d> p = {{-1, g, 0}, {1, g, 0}, {-1, -g, 0}, {1, -g, 0}, {0, -1, g}, {0, 1, g},
                                    {0, -1, -g}, {0, 1, -g}, {g, 0, -1}, {g, 0, 1}, {-g, 0, -1}, {-g, 0, 1}};
  std::vector<std::array<uint32_t, 3>> f = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                                            {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                                            {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                                            {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  for (uint32_t l = 0; l < levels; ++l) {
    std::map<std::pair<uint32_t, uint32_t>, uint32_t> mid;
    auto middle = [&](uint32_t a, uint32_t b) {
      const auto key = std::minmax(a, b);
      const auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      p.push_back((p[a] + p[b]) * 0.5);
      return mid[key] = static_cast<uint32_t>(p.size() - 1);
    };
    std::vector<std::array<uint32_t, 3>> next;
    for (const auto& t : f) {
      const uint32_t a = middle(t[0], t[1]), b = middle(t[1], t[2]), c = middle(t[2], t[0]);
      next.push_back({t[0], a, c});
      next.push_back({t[1], b, a});
      next.push_back({t[2], c, b});
      next.push_back({a, b, c});
    }
    f = std::move(next);
  }
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const Eigen::Matrix3d R =
      Eigen::Quaterniond(u(rng), u(rng), u(rng), u(rng) + 2.0).normalized().toRotationMatrix();
  TriMesh m;
  m.v.resize(3, static_cast<Eigen::Index>(p.size()));
  for (size_t i = 0; i < p.size(); ++i)
    m.v.col(static_cast<Eigen::Index>(i)) = (R * p[i].normalized() * radius + centre).cast<float>();
  m.t.resize(3, static_cast<Eigen::Index>(f.size()));
  std::bernoulli_distribution flip(0.5);
  for (size_t i = 0; i < f.size(); ++i) {
    auto t = f[i];
    if (flip(rng)) std::swap(t[1], t[2]);  // random winding: the test is two-sided
    m.t.col(static_cast<Eigen::Index>(i)) = Eigen::Matrix<uint32_t, 3, 1>(t[0], t[1], t[2]);
  }
  return m;
}

/// k triangles around the vertex `centre` (vertex 0), perimeter vertices at random
/// angles and radii in [0.5, 1.5] * size, heights in +-0.3 size along z: the fan
/// closes around vertex 0, so vertex 0 and the k spokes are interior.
inline TriMesh make_fan(uint32_t k, double size, const Eigen::Vector3d& centre, std::mt19937& rng) {
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  std::vector<double> ang(k);
  for (uint32_t i = 0; i < k; ++i)  // sorted angles, each gap under pi
    ang[i] = (static_cast<double>(i) + 0.2 + 0.6 * u01(rng)) * 2.0 * M_PI / static_cast<double>(k);
  TriMesh m;
  m.v.resize(3, k + 1);
  m.v.col(0) = centre.cast<float>();
  for (uint32_t i = 0; i < k; ++i) {
    const double r = size * (0.5 + u01(rng));
    const Eigen::Vector3d q(r * std::cos(ang[i]), r * std::sin(ang[i]), size * 0.6 * (u01(rng) - 0.5));
    m.v.col(i + 1) = (centre + q).cast<float>();
  }
  m.t.resize(3, k);
  for (uint32_t i = 0; i < k; ++i) {
    uint32_t a = i + 1, b = (i + 1) % k + 1;
    if (u01(rng) < 0.5) std::swap(a, b);
    m.t.col(i) = Eigen::Matrix<uint32_t, 3, 1>(0, a, b);
  }
  return m;
}

/// A point a ray is aimed at: on (or beside) a shared edge, or at a shared vertex.
struct MeshTarget {
  Eigen::Vector3d p;
  bool vertex;  ///< at a vertex (else on or beside an edge)
};

/// The mesh's interior edges (shared by exactly two triangles) as (a, b, opposite
/// vertex in the first triangle, opposite vertex in the second).
inline std::vector<std::array<uint32_t, 4>> interior_edges(const TriMesh& m) {
  std::map<std::pair<uint32_t, uint32_t>, std::vector<uint32_t>> opp;
  for (Eigen::Index i = 0; i < m.t.cols(); ++i)
    for (int k = 0; k < 3; ++k) {
      const uint32_t a = m.t(k, i), b = m.t((k + 1) % 3, i), c = m.t((k + 2) % 3, i);
      opp[std::minmax(a, b)].push_back(c);
    }
  std::vector<std::array<uint32_t, 4>> out;
  for (const auto& [e, o] : opp)
    if (o.size() == 2) out.push_back({e.first, e.second, o[0], o[1]});
  return out;
}

/// Vertices all of whose incident edges are interior (the triangles close around them).
inline std::vector<uint32_t> interior_vertices(const TriMesh& m) {
  std::map<std::pair<uint32_t, uint32_t>, int> count;
  for (Eigen::Index i = 0; i < m.t.cols(); ++i)
    for (int k = 0; k < 3; ++k) ++count[std::minmax(m.t(k, i), m.t((k + 1) % 3, i))];
  std::vector<uint8_t> open(static_cast<size_t>(m.v.cols()), 0), used(static_cast<size_t>(m.v.cols()), 0);
  for (const auto& [e, c] : count) {
    used[e.first] = used[e.second] = 1;
    if (c != 2) open[e.first] = open[e.second] = 1;
  }
  std::vector<uint32_t> out;
  for (uint32_t i = 0; i < m.v.cols(); ++i)
    if (used[i] && !open[i]) out.push_back(i);
  return out;
}

/// Targets on the interior edges and vertices: per edge, the float-rounded midpoint, a
/// random point, and points `offset` (barycentric) to each side of it towards the
/// opposite vertices; every interior vertex.
inline std::vector<MeshTarget> shared_targets(const TriMesh& m, double offset, std::mt19937& rng) {
  std::uniform_real_distribution<double> s01(0.05, 0.95);
  std::vector<MeshTarget> out;
  auto vd = [&](uint32_t i) { return Eigen::Vector3d(m.v.col(i).cast<double>()); };
  for (const auto& e : interior_edges(m)) {
    const Eigen::Vector3d a = vd(e[0]), b = vd(e[1]);
    out.push_back({round_to_float((a + b) * 0.5), false});
    const Eigen::Vector3d q = a + s01(rng) * (b - a);
    out.push_back({q, false});
    out.push_back({q + offset * (vd(e[2]) - q), false});
    out.push_back({q + offset * (vd(e[3]) - q), false});
  }
  for (const uint32_t i : interior_vertices(m)) out.push_back({vd(i), true});
  return out;
}

}  // namespace impact::test
