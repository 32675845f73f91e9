// impact::ShapeSet: validation at the API boundary, local bounds, the mesh BVH.
#include <algorithm>
#include <cmath>
#include <numeric>
#include <string>

#include "host/shapes/convex_hull.h"
#include "host/shapes/mass.h"
#include "host/shapes/pose.h"
#include "host/shapes/shape_store.h"
#include "impact/shapes.h"

namespace impact {

const char* to_string(ShapeType type) {
  switch (type) {
    case ShapeType::kSphere: return "sphere";
    case ShapeType::kCapsule: return "capsule";
    case ShapeType::kBox: return "box";
    case ShapeType::kAabb: return "aabb";
    case ShapeType::kConvex: return "convex";
    case ShapeType::kCylinder: return "cylinder";
    case ShapeType::kEllipsoid: return "ellipsoid";
    case ShapeType::kHalfSpace: return "half-space";
    case ShapeType::kMesh: return "mesh";
    case ShapeType::kCompound: return "compound";
  }
  return "unknown";
}

namespace {

Status invalid(const std::string& what) { return Status(StatusCode::kInvalidArgument, what); }

std::string fmt(float v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", static_cast<double>(v));
  return buf;
}

Status check_positive(const char* shape, const char* field, float v) {
  if (!std::isfinite(v) || !(v > 0.0f)) {
    return invalid(std::string(shape) + ": " + field + " must be finite and > 0, got " + fmt(v));
  }
  return {};
}

Status check_vec_positive(const char* shape, const char* field, const Eigen::Vector3f& v) {
  for (int i = 0; i < 3; ++i) {
    if (!std::isfinite(v[i]) || !(v[i] > 0.0f)) {
      return invalid(std::string(shape) + ": " + field + "[" + std::to_string(i) +
                     "] must be finite and > 0, got " + fmt(v[i]));
    }
  }
  return {};
}

bool finite(const Eigen::Vector3f& v) { return v.allFinite(); }

// Median-split BVH over triangle bounds, leaves of at most 4 triangles. Built once
// when the mesh is added (serial). The split is on the longest axis of the centroid
// bounds, by (centroid, triangle index): a total order, so the tree is the same on
// every run.
void build_mesh_bvh(MeshData* m) {
  const uint32_t nt = m->triangle_count();
  std::vector<Eigen::Vector3f> lo(nt), hi(nt), c(nt);
  for (uint32_t t = 0; t < nt; ++t) {
    const Eigen::Vector3f& a = m->vertices[m->indices[3 * t]];
    const Eigen::Vector3f& b = m->vertices[m->indices[3 * t + 1]];
    const Eigen::Vector3f& d = m->vertices[m->indices[3 * t + 2]];
    lo[t] = a.cwiseMin(b).cwiseMin(d);
    hi[t] = a.cwiseMax(b).cwiseMax(d);
    c[t] = (lo[t] + hi[t]) * 0.5f;
  }
  m->tri_order.resize(nt);
  std::iota(m->tri_order.begin(), m->tri_order.end(), 0u);
  m->nodes.clear();
  m->nodes.reserve(nt > 0 ? 2 * nt : 1);
  struct Task {
    uint32_t node, first, count;
  };
  std::vector<Task> stack;
  m->nodes.push_back({});
  stack.push_back({0, 0, nt});
  while (!stack.empty()) {
    const Task t = stack.back();
    stack.pop_back();
    Eigen::Vector3f blo = Eigen::Vector3f::Constant(INFINITY), bhi = Eigen::Vector3f::Constant(-INFINITY);
    Eigen::Vector3f clo = blo, chi = bhi;
    for (uint32_t i = t.first; i < t.first + t.count; ++i) {
      const uint32_t tri = m->tri_order[i];
      blo = blo.cwiseMin(lo[tri]);
      bhi = bhi.cwiseMax(hi[tri]);
      clo = clo.cwiseMin(c[tri]);
      chi = chi.cwiseMax(c[tri]);
    }
    MeshData::Node& node = m->nodes[t.node];
    for (int k = 0; k < 3; ++k) {
      node.lo[k] = blo[k];
      node.hi[k] = bhi[k];
    }
    if (t.count <= 4) {
      node.left_or_first = t.first;
      node.count = t.count;
      node.right = 0;
      continue;
    }
    int axis = 0;
    const Eigen::Vector3f ext = chi - clo;
    if (ext[1] > ext[axis]) axis = 1;
    if (ext[2] > ext[axis]) axis = 2;
    const uint32_t half = t.count / 2;
    auto begin = m->tri_order.begin() + t.first;
    std::nth_element(begin, begin + half, begin + t.count, [&](uint32_t x, uint32_t y) {
      return c[x][axis] < c[y][axis] || (c[x][axis] == c[y][axis] && x < y);
    });
    const auto left = static_cast<uint32_t>(m->nodes.size());
    m->nodes.push_back({});
    m->nodes.push_back({});
    MeshData::Node& parent = m->nodes[t.node];  // push_back may have moved it
    parent.left_or_first = left;
    parent.count = 0;
    parent.right = left + 1;
    stack.push_back({left + 1, t.first + half, t.count - half});
    stack.push_back({left, t.first, half});
  }
}

}  // namespace

ShapeSet::ShapeSet() : store_(std::make_unique<ShapeStore>()) {}
ShapeSet::~ShapeSet() = default;
ShapeSet::ShapeSet(ShapeSet&&) noexcept = default;
ShapeSet& ShapeSet::operator=(ShapeSet&&) noexcept = default;

size_t ShapeSet::size() const { return store_->shapes.size(); }

namespace {
Status push(ShapeStore* s, const ShapeRecord& rec, ShapeId* out) {
  if (out == nullptr) return invalid("out must not be null");
  if (s->shapes.size() >= 0xfffffffeu) return Status(StatusCode::kCapacityExceeded, "too many shapes");
  s->shapes.push_back(rec);
  out->index = static_cast<uint32_t>(s->shapes.size() - 1);
  return {};
}
}  // namespace

Status ShapeSet::add_sphere(float radius, ShapeId* out) {
  if (Status st = check_positive("sphere", "radius", radius); !st.ok()) return st;
  ShapeRecord r;
  r.type = ShapeType::kSphere;
  r.e[0] = radius;
  r.local_min = Eigen::Vector3f::Constant(-radius);
  r.local_max = Eigen::Vector3f::Constant(radius);
  return push(store_.get(), r, out);
}

Status ShapeSet::add_capsule(float radius, float half_length, ShapeId* out) {
  if (Status st = check_positive("capsule", "radius", radius); !st.ok()) return st;
  if (!std::isfinite(half_length) || half_length < 0.0f) {
    return invalid("capsule: half_length must be finite and >= 0, got " + fmt(half_length));
  }
  ShapeRecord r;
  r.type = ShapeType::kCapsule;
  r.e[0] = radius;
  r.e[1] = half_length;
  r.local_max = Eigen::Vector3f(radius, radius, radius + half_length);
  r.local_min = -r.local_max;
  return push(store_.get(), r, out);
}

Status ShapeSet::add_box(const Eigen::Vector3f& half_extents, ShapeId* out) {
  if (Status st = check_vec_positive("box", "half_extents", half_extents); !st.ok()) return st;
  ShapeRecord r;
  r.type = ShapeType::kBox;
  for (int i = 0; i < 3; ++i) r.e[i] = half_extents[i];
  r.local_max = half_extents;
  r.local_min = -half_extents;
  return push(store_.get(), r, out);
}

Status ShapeSet::add_aabb(const Eigen::Vector3f& half_extents, ShapeId* out) {
  if (Status st = check_vec_positive("aabb", "half_extents", half_extents); !st.ok()) return st;
  ShapeRecord r;
  r.type = ShapeType::kAabb;
  for (int i = 0; i < 3; ++i) r.e[i] = half_extents[i];
  r.local_max = half_extents;
  r.local_min = -half_extents;
  return push(store_.get(), r, out);
}

Status ShapeSet::add_convex_hull(std::span<const Eigen::Vector3f> points, ShapeId* out) {
  if (out == nullptr) return invalid("out must not be null");
  HullData hull;
  if (Status st = build_convex_hull(points, &hull); !st.ok()) return st;
  ShapeRecord r;
  r.type = ShapeType::kConvex;
  r.local_min = Eigen::Vector3f::Constant(INFINITY);
  r.local_max = Eigen::Vector3f::Constant(-INFINITY);
  for (const Eigen::Vector3f& v : hull.vertices) {
    r.local_min = r.local_min.cwiseMin(v);
    r.local_max = r.local_max.cwiseMax(v);
  }
  r.ref = store_->hulls.add(hull);
  return push(store_.get(), r, out);
}

Status ShapeSet::add_cylinder(float radius, float half_length, ShapeId* out) {
  if (Status st = check_positive("cylinder", "radius", radius); !st.ok()) return st;
  if (Status st = check_positive("cylinder", "half_length", half_length); !st.ok()) return st;
  ShapeRecord r;
  r.type = ShapeType::kCylinder;
  r.e[0] = radius;
  r.e[1] = half_length;
  r.local_max = Eigen::Vector3f(radius, radius, half_length);
  r.local_min = -r.local_max;
  return push(store_.get(), r, out);
}

Status ShapeSet::add_ellipsoid(const Eigen::Vector3f& radii, ShapeId* out) {
  if (Status st = check_vec_positive("ellipsoid", "radii", radii); !st.ok()) return st;
  ShapeRecord r;
  r.type = ShapeType::kEllipsoid;
  for (int i = 0; i < 3; ++i) r.e[i] = radii[i];
  r.local_max = radii;
  r.local_min = -radii;
  return push(store_.get(), r, out);
}

Status ShapeSet::add_half_space(const Eigen::Vector3f& normal, float offset, ShapeId* out) {
  if (!finite(normal)) return invalid("half-space: normal must be finite");
  if (!std::isfinite(offset)) return invalid("half-space: offset must be finite, got " + fmt(offset));
  const double len = normal.cast<double>().norm();
  if (!(len > 1e-30)) return invalid("half-space: normal must be non-zero");
  ShapeRecord r;
  r.type = ShapeType::kHalfSpace;
  const Eigen::Vector3f n = (normal.cast<double>() / len).cast<float>();
  for (int i = 0; i < 3; ++i) r.e[i] = n[i];
  r.offset = offset;
  return push(store_.get(), r, out);
}

Status ShapeSet::add_mesh(std::span<const Eigen::Vector3f> vertices, std::span<const uint32_t> indices,
                          ShapeId* out) {
  if (out == nullptr) return invalid("out must not be null");
  if (indices.empty() || indices.size() % 3 != 0) {
    return invalid("mesh: indices must hold 3 per triangle and at least one triangle, got " +
                   std::to_string(indices.size()));
  }
  if (indices.size() / 3 >= (1u << 30)) return Status(StatusCode::kCapacityExceeded, "mesh: more than 2^30 triangles");
  for (size_t i = 0; i < vertices.size(); ++i) {
    if (!finite(vertices[i])) return invalid("mesh: vertex " + std::to_string(i) + " is not finite");
  }
  for (size_t i = 0; i < indices.size(); ++i) {
    if (indices[i] >= vertices.size()) {
      return invalid("mesh: index " + std::to_string(i) + " = " + std::to_string(indices[i]) +
                     " is out of range (" + std::to_string(vertices.size()) + " vertices)");
    }
  }
  MeshData m;
  m.vertices.assign(vertices.begin(), vertices.end());
  m.indices.assign(indices.begin(), indices.end());
  for (uint32_t t = 0; t < m.triangle_count(); ++t) {
    const Eigen::Vector3d a = m.vertices[m.indices[3 * t]].cast<double>();
    const Eigen::Vector3d b = m.vertices[m.indices[3 * t + 1]].cast<double>();
    const Eigen::Vector3d c = m.vertices[m.indices[3 * t + 2]].cast<double>();
    const double area2 = (b - a).cross(c - a).norm();
    const double scale = std::max({(b - a).squaredNorm(), (c - a).squaredNorm(), (c - b).squaredNorm()});
    if (!(area2 > 1e-12 * scale) || !(scale > 0.0)) {
      return invalid("mesh: triangle " + std::to_string(t) + " is degenerate (zero area)");
    }
  }
  build_mesh_bvh(&m);
  ShapeRecord r;
  r.type = ShapeType::kMesh;
  const MeshData::Node& root = m.nodes[0];
  r.local_min = Eigen::Vector3f(root.lo[0], root.lo[1], root.lo[2]);
  r.local_max = Eigen::Vector3f(root.hi[0], root.hi[1], root.hi[2]);
  r.ref = static_cast<uint32_t>(store_->meshes.size());
  store_->meshes.push_back(std::move(m));
  if (Status st = push(store_.get(), r, out); !st.ok()) {
    store_->meshes.pop_back();
    return st;
  }
  return {};
}

Status ShapeSet::add_compound(std::span<const CompoundChild> children, ShapeId* out) {
  if (out == nullptr) return invalid("out must not be null");
  if (children.empty()) return invalid("compound: needs at least one child");
  ShapeRecord r;
  r.type = ShapeType::kCompound;
  r.local_min = Eigen::Vector3f::Constant(INFINITY);
  r.local_max = Eigen::Vector3f::Constant(-INFINITY);
  for (size_t i = 0; i < children.size(); ++i) {
    const CompoundChild& c = children[i];
    const std::string who = "compound: child " + std::to_string(i);
    if (c.shape.index >= store_->shapes.size()) return invalid(who + ": unknown shape id");
    const ShapeType t = store_->shapes[c.shape.index].type;
    if (t == ShapeType::kHalfSpace || t == ShapeType::kMesh || t == ShapeType::kCompound ||
        t == ShapeType::kAabb) {
      return invalid(who + ": a " + to_string(t) +
                     " cannot be a compound child (sphere, capsule, box, convex, cylinder, ellipsoid)");
    }
    if (Status st = host::check_pose(c.local, who.c_str()); !st.ok()) return st;
    Eigen::Vector3f lo, hi;
    host::posed_bounds(store_->shapes[c.shape.index], host::normalized(c.local), store_->hulls, &lo, &hi);
    r.local_min = r.local_min.cwiseMin(lo);
    r.local_max = r.local_max.cwiseMax(hi);
  }
  r.ref = static_cast<uint32_t>(store_->child_begin.size() - 1);
  for (const CompoundChild& c : children) {
    CompoundChild n = c;
    n.local = host::normalized(c.local);
    store_->children.push_back(n);
  }
  store_->child_begin.push_back(static_cast<uint32_t>(store_->children.size()));
  if (Status st = push(store_.get(), r, out); !st.ok()) {
    store_->children.resize(store_->child_begin[store_->child_begin.size() - 2]);
    store_->child_begin.pop_back();
    return st;
  }
  return {};
}

Status ShapeSet::type(ShapeId id, ShapeType* out) const {
  if (id.index >= store_->shapes.size()) return invalid("unknown shape id " + std::to_string(id.index));
  if (out == nullptr) return invalid("out must not be null");
  *out = store_->shapes[id.index].type;
  return {};
}

Status ShapeSet::mass_properties(ShapeId id, float density, MassProperties* out) const {
  if (id.index >= store_->shapes.size()) return invalid("unknown shape id " + std::to_string(id.index));
  if (out == nullptr) return invalid("out must not be null");
  if (Status st = check_positive("mass_properties", "density", density); !st.ok()) return st;
  return shape_mass_properties(*store_, id.index, density, out);
}

Status ShapeSet::bounds(ShapeId id, const Pose& pose, Eigen::Vector3f* min, Eigen::Vector3f* max) const {
  if (id.index >= store_->shapes.size()) return invalid("unknown shape id " + std::to_string(id.index));
  if (min == nullptr || max == nullptr) return invalid("min and max must not be null");
  const ShapeRecord& r = store_->shapes[id.index];
  if (r.type == ShapeType::kHalfSpace) return invalid("bounds: a half-space is unbounded");
  if (Status st = host::check_pose(pose, "pose"); !st.ok()) return st;
  host::posed_bounds(r, host::normalized(pose), store_->hulls, min, max);
  return {};
}

}  // namespace impact
