// ShapeStore: the storage behind impact::ShapeSet. Plain vectors, append-only.
#pragma once

#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "impact/shapes.h"
#include "kernels/narrowphase/leaf/leaf.h"

namespace impact {

/// A convex hull as built by host/shapes/convex_hull.h, in its local frame.
struct HullData {
  std::vector<Eigen::Vector3f> vertices;
  /// Faces as polygons of vertex indices, counter-clockwise seen from outside;
  /// coplanar triangles are merged into one polygon.
  std::vector<std::vector<uint32_t>> faces;
  std::vector<Eigen::Vector3f> face_normals;  ///< unit, outward
  std::vector<float> face_offsets;            ///< plane n.x = offset
  std::vector<Eigen::Vector3f> edge_dirs;     ///< unit, one per parallel class (SAT)
};

/// All hulls concatenated (the arrays behind kernels::HullView).
struct HullStore {
  std::vector<uint32_t> vert_begin{0}, face_begin{0}, face_vert_begin{0}, edge_begin{0};
  std::vector<float> vx, vy, vz, fnx, fny, fnz, fd, ex, ey, ez;
  std::vector<float> vxyz;  ///< the vertices again, 4 floats each (x, y, z, 0)
  std::vector<uint32_t> face_verts;
  /// Edge adjacency (kernels::HullView, hull-local indices), from the faces in add().
  std::vector<uint32_t> adj_begin{0}, ev0, ev1, ef0, ef1;
  std::vector<float> emx, emy, emz, ecos, esin, epx, epy, epz, edx, edy, edz;
  uint32_t size() const { return static_cast<uint32_t>(vert_begin.size() - 1); }
  /// Appends a hull; returns its index.
  uint32_t add(const HullData& h);
  kernels::HullView view() const;
};

/// A static triangle mesh with a BVH over its triangles.
struct MeshData {
  std::vector<Eigen::Vector3f> vertices;
  std::vector<uint32_t> indices;  ///< 3 per triangle
  /// BVH over the triangles (a binary tree in one array; node 0 is the root).
  /// Node i: bounds [lo, hi]; an inner node has children left/right (right = left + 1
  /// is not assumed), a leaf has count > 0 triangles tri_order[first .. first + count).
  struct Node {
    float lo[3], hi[3];
    uint32_t left_or_first;
    uint32_t count;  ///< 0 for an inner node
    uint32_t right;
  };
  std::vector<Node> nodes;
  std::vector<uint32_t> tri_order;
  uint32_t triangle_count() const { return static_cast<uint32_t>(indices.size() / 3); }
};

struct ShapeRecord {
  ShapeType type = ShapeType::kSphere;
  /// sphere: e0 = r; capsule/cylinder: e0 = r, e1 = half length; box/aabb: half
  /// extents; ellipsoid: radii; half-space: e = unit normal, offset = plane offset.
  float e[3] = {0, 0, 0};
  float offset = 0.0f;
  /// convex: hull index; mesh: mesh index; compound: compound index.
  uint32_t ref = 0;
  /// Local bounds (not for half-spaces).
  Eigen::Vector3f local_min = Eigen::Vector3f::Zero(), local_max = Eigen::Vector3f::Zero();
};

struct ShapeStore {
  std::vector<ShapeRecord> shapes;
  HullStore hulls;
  std::vector<MeshData> meshes;
  /// compound c: children child_begin[c] .. child_begin[c + 1]
  std::vector<uint32_t> child_begin{0};
  std::vector<CompoundChild> children;
};

}  // namespace impact
