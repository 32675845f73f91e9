// raycast_shapes / query_shape_points (include/impact/shape_queries.h): validation,
// posing, dispatch by shape type, mesh BVH traversal and compound children.
//
// Each query is moved into the shape's local frame as R^T (x - position) in float: the
// difference is taken first, so a pose far from the world origin costs no precision
// relative to the shape. Leaf shapes are answered by kernels/narrowphase/leaf/leaf_queries.h.
// Meshes walk their BVH (host/shapes/shape_store.h) near child first, pruning by
// the best hit / distance so far; a node is pruned only when it is strictly worse,
// and hits are ordered by (t or distance, triangle index), so the result equals a
// brute force over all triangles whatever the visit order. Compounds loop over their
// children with the same ordering by child index. Batches run in chunks of a fixed
// grain (host/parallel.h): each result is written by one chunk from its own input.
#include "impact/shape_queries.h"

#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>
#include <utility>

#include <Eigen/Geometry>

#include "host/parallel.h"
#include "host/shapes/pose.h"
#include "host/shapes/shape_ray.h"
#include "host/shapes/shape_store.h"
#include "kernels/narrowphase/leaf/leaf_queries.h"
#include "kernels/raycast/ray_primitives.h"

namespace impact {

namespace {

using kernels::LeafPointResult;
using kernels::LeafRayHit;
using kernels::RayQuery;

constexpr uint32_t kQueryGrain = 256;
constexpr float kInf = std::numeric_limits<float>::infinity();

std::string fmt(float v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", static_cast<double>(v));
  return buf;
}

Status invalid(const std::string& m) { return Status(StatusCode::kInvalidArgument, m); }

// The objects' shape ids and poses (same rules and messages as NarrowPhase::collide).
Status check_objects(const ShapeStore& store, std::span<const ShapeId> shape_of, std::span<const Pose> poses) {
  if (shape_of.size() != poses.size()) {
    return Status(StatusCode::kSizeMismatch, "shape_of has " + std::to_string(shape_of.size()) +
                                                 " entries but poses has " + std::to_string(poses.size()));
  }
  if (shape_of.size() >= 0xffffffffu) return Status(StatusCode::kCapacityExceeded, "more than 2^32 - 2 objects");
  for (size_t i = 0; i < shape_of.size(); ++i) {
    if (shape_of[i].index >= store.shapes.size()) {
      return invalid("object " + std::to_string(i) + ": unknown shape id " + std::to_string(shape_of[i].index));
    }
    if (!host::check_pose(poses[i], "object").ok()) {
      const std::string who = "object " + std::to_string(i);  // named only on failure
      return host::check_pose(poses[i], who.c_str());
    }
  }
  return {};
}

Status check_exec(const ExecConfig& exec) {
  Backend resolved;
  if (!host::resolve_backend(exec.backend, &resolved)) {
    return Status(StatusCode::kUnsupported,
                  std::string("backend ") + to_string(exec.backend) + " is not built into this library");
  }
  return {};
}

// A pose as the queries use it: rotation (identity for AABB shapes) and position.
struct Frame {
  Eigen::Matrix3f R;
  Eigen::Vector3f p;
};

Frame object_frame(const ShapeRecord& rec, const Pose& pose) {
  Frame f;
  f.p = pose.position;
  if (rec.type == ShapeType::kAabb) {
    f.R.setIdentity();
  } else {
    f.R = host::normalized(pose).orientation.toRotationMatrix();
  }
  return f;
}

RayQuery make_query(const Eigen::Vector3f& o, const Eigen::Vector3f& d, float tmax) {
  RayQuery q;
  for (int i = 0; i < 3; ++i) {
    q.o[i] = o[i];
    q.d[i] = d[i];
  }
  q.tmax = tmax;
  q.mask = 0xffffffffu;
  return q;
}

// --- leaves ------------------------------------------------------------------------------

LeafRayHit ray_leaf(const ShapeStore& s, const ShapeRecord& rec, const RayQuery& q) {
  switch (rec.type) {
    case ShapeType::kSphere: return kernels::ray_leaf_sphere(q, rec.e[0]);
    case ShapeType::kCapsule: return kernels::ray_leaf_capsule(q, rec.e[0], rec.e[1]);
    case ShapeType::kBox:
    case ShapeType::kAabb: return kernels::ray_leaf_box(q, rec.e);
    case ShapeType::kConvex: {
      const kernels::HullView hv = s.hulls.view();
      return kernels::ray_leaf_hull(q, hv, rec.ref);
    }
    case ShapeType::kCylinder: return kernels::ray_leaf_cylinder(q, rec.e[0], rec.e[1]);
    case ShapeType::kEllipsoid: return kernels::ray_leaf_ellipsoid(q, rec.e);
    case ShapeType::kHalfSpace: return kernels::ray_leaf_half_space(q, rec.e, rec.offset);
    default: return {};
  }
}

LeafPointResult point_leaf(const ShapeStore& s, const ShapeRecord& rec, const float p[3]) {
  switch (rec.type) {
    case ShapeType::kSphere: return kernels::point_leaf_sphere(p, rec.e[0]);
    case ShapeType::kCapsule: return kernels::point_leaf_capsule(p, rec.e[0], rec.e[1]);
    case ShapeType::kBox:
    case ShapeType::kAabb: return kernels::point_leaf_box(p, rec.e);
    case ShapeType::kConvex: {
      const kernels::HullView hv = s.hulls.view();
      return kernels::point_leaf_hull(p, hv, rec.ref);
    }
    case ShapeType::kCylinder: return kernels::point_leaf_cylinder(p, rec.e[0], rec.e[1]);
    case ShapeType::kEllipsoid: return kernels::point_leaf_ellipsoid(p, rec.e);
    case ShapeType::kHalfSpace: return kernels::point_leaf_half_space(p, rec.e, rec.offset);
    default: return {};
  }
}

// --- meshes ------------------------------------------------------------------------------

// Entry distance of the ray into a node's box (conservatively widened), or +inf.
inline float ray_node(const MeshData::Node& nd, const RayQuery& q, const float inv[3], float tmax) {
  float tn = 0.0f, tf = tmax;
  for (int i = 0; i < 3; ++i) {
    if (q.d[i] == 0.0f) {
      if (q.o[i] < nd.lo[i] || q.o[i] > nd.hi[i]) return kInf;
      continue;
    }
    float t0 = (nd.lo[i] - q.o[i]) * inv[i];
    float t1 = (nd.hi[i] - q.o[i]) * inv[i];
    if (t0 > t1) std::swap(t0, t1);
    // Widen by a few ulps so float rounding never culls a box the triangle test
    // would hit (Ize, "Robust BVH Ray Traversal", JCGT 2(2), 2013).
    constexpr float kWiden = 4.0f * std::numeric_limits<float>::epsilon();
    t0 -= std::fabs(t0) * kWiden;
    t1 += std::fabs(t1) * kWiden;
    tn = std::fmax(tn, t0);
    tf = std::fmin(tf, t1);
  }
  return tn <= tf ? tn : kInf;
}

struct MeshRayHit {
  float t = kInf;
  uint32_t tri = kNoChild;
};

MeshRayHit ray_mesh(const MeshData& m, const RayQuery& q) {
  MeshRayHit best;
  if (m.nodes.empty()) return best;
  const kernels::RayShear sh = kernels::ray_shear(q);
  float inv[3];
  for (int i = 0; i < 3; ++i) inv[i] = q.d[i] != 0.0f ? 1.0f / q.d[i] : 0.0f;
  std::array<uint32_t, 64> stack;
  uint32_t top = 0;
  if (ray_node(m.nodes[0], q, inv, q.tmax) == kInf) return best;
  stack[top++] = 0;
  while (top > 0) {
    const MeshData::Node& nd = m.nodes[stack[--top]];
    if (nd.count > 0) {
      for (uint32_t k = nd.left_or_first; k < nd.left_or_first + nd.count; ++k) {
        const uint32_t tri = m.tri_order[k];
        const float* v0 = m.vertices[m.indices[3 * tri]].data();
        const float* v1 = m.vertices[m.indices[3 * tri + 1]].data();
        const float* v2 = m.vertices[m.indices[3 * tri + 2]].data();
        const float t = kernels::ray_triangle(q, sh, v0, v1, v2);
        if (t >= 0.0f && (t < best.t || (t == best.t && tri < best.tri))) {
          best.t = t;
          best.tri = tri;
        }
      }
      continue;
    }
    const float bound = best.t < q.tmax ? best.t : q.tmax;
    const float ta = ray_node(m.nodes[nd.left_or_first], q, inv, bound);
    const float tb = ray_node(m.nodes[nd.right], q, inv, bound);
    // Push the farther child first so the nearer one is visited next; a node whose
    // entry equals the best t may still hold a lower-indexed tie, so it is kept.
    const bool a_first = ta <= tb;
    const float t_far = a_first ? tb : ta, t_near = a_first ? ta : tb;
    const uint32_t far = a_first ? nd.right : nd.left_or_first, near = a_first ? nd.left_or_first : nd.right;
    if (t_far != kInf && top < stack.size()) stack[top++] = far;
    if (t_near != kInf && top < stack.size()) stack[top++] = near;
  }
  return best;
}

// Squared distance from p to a node's box.
inline float point_node2(const MeshData::Node& nd, const float p[3]) {
  float d2 = 0.0f;
  for (int i = 0; i < 3; ++i) {
    const float e = std::fmax(std::fmax(nd.lo[i] - p[i], p[i] - nd.hi[i]), 0.0f);
    d2 += e * e;
  }
  return d2;
}

struct MeshPoint {
  LeafPointResult r;
  uint32_t tri = kNoChild;
};

MeshPoint point_mesh(const MeshData& m, const float p[3]) {
  MeshPoint best;
  best.r.distance = kInf;
  if (m.nodes.empty()) return best;
  // A node is culled when its box is farther than the best distance by more than the
  // rounding of both (so exact ties are always visited).
  auto culled = [&](float box2) {
    const float bd = best.r.distance;
    return box2 * (1.0f - 8.0f * std::numeric_limits<float>::epsilon()) > bd * bd;
  };
  std::array<uint32_t, 64> stack;
  uint32_t top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const MeshData::Node& nd = m.nodes[stack[--top]];
    if (nd.count > 0) {
      for (uint32_t k = nd.left_or_first; k < nd.left_or_first + nd.count; ++k) {
        const uint32_t tri = m.tri_order[k];
        const float* v0 = m.vertices[m.indices[3 * tri]].data();
        const float* v1 = m.vertices[m.indices[3 * tri + 1]].data();
        const float* v2 = m.vertices[m.indices[3 * tri + 2]].data();
        const LeafPointResult r = kernels::point_leaf_triangle(p, v0, v1, v2);
        if (r.distance < best.r.distance || (r.distance == best.r.distance && tri < best.tri)) {
          best.r = r;
          best.tri = tri;
        }
      }
      continue;
    }
    const float da = point_node2(m.nodes[nd.left_or_first], p);
    const float db = point_node2(m.nodes[nd.right], p);
    const bool a_first = da <= db;
    const float d_far = a_first ? db : da, d_near = a_first ? da : db;
    const uint32_t far = a_first ? nd.right : nd.left_or_first, near = a_first ? nd.left_or_first : nd.right;
    if (!culled(d_far) && top < stack.size()) stack[top++] = far;
    if (!culled(d_near) && top < stack.size()) stack[top++] = near;
  }
  return best;
}

// --- one query ---------------------------------------------------------------------------

// A hit in some local frame: t, local normal, child.
struct LocalHit {
  float t = -1.0f;
  Eigen::Vector3f n = Eigen::Vector3f::Zero();
  uint32_t child = kNoChild;
};

LocalHit ray_local(const ShapeStore& s, const ShapeRecord& rec, const RayQuery& q) {
  LocalHit out;
  switch (rec.type) {
    case ShapeType::kMesh: {
      const MeshData& m = s.meshes[rec.ref];
      const MeshRayHit h = ray_mesh(m, q);
      if (h.tri == kNoChild) return out;
      const float* v0 = m.vertices[m.indices[3 * h.tri]].data();
      const float* v1 = m.vertices[m.indices[3 * h.tri + 1]].data();
      const float* v2 = m.vertices[m.indices[3 * h.tri + 2]].data();
      float n[3];
      kernels::triangle_normal(v0, v1, v2, n);
      out.t = h.t;
      out.n = Eigen::Vector3f(n[0], n[1], n[2]);
      if (out.n.dot(Eigen::Vector3f(q.d[0], q.d[1], q.d[2])) > 0.0f) out.n = -out.n;
      out.child = h.tri;
      return out;
    }
    case ShapeType::kCompound: {
      const Eigen::Vector3f o(q.o[0], q.o[1], q.o[2]), d(q.d[0], q.d[1], q.d[2]);
      const uint32_t cb = s.child_begin[rec.ref], ce = s.child_begin[rec.ref + 1];
      for (uint32_t c = cb; c < ce; ++c) {
        const CompoundChild& ch = s.children[c];
        const ShapeRecord& cr = s.shapes[ch.shape.index];
        const Eigen::Matrix3f Rc = ch.local.orientation.toRotationMatrix();
        const Eigen::Vector3f oc = Rc.transpose() * (o - ch.local.position);
        const Eigen::Vector3f dc = Rc.transpose() * d;
        const LeafRayHit h = ray_leaf(s, cr, make_query(oc, dc, q.tmax));
        if (h.t < 0.0f) continue;
        if (out.child == kNoChild || h.t < out.t) {
          out.t = h.t;
          out.n = Rc * Eigen::Vector3f(h.n[0], h.n[1], h.n[2]);
          out.child = c - cb;
        }
      }
      // An origin inside a child: normal = -d exactly (not through Rc round trips).
      if (out.child != kNoChild && out.t == 0.0f) out.n = -d;
      return out;
    }
    default: {
      const LeafRayHit h = ray_leaf(s, rec, q);
      out.t = h.t;
      out.n = Eigen::Vector3f(h.n[0], h.n[1], h.n[2]);
      return out;
    }
  }
}

ShapeRayHit ray_posed(const ShapeStore& s, const ShapeRecord& rec, const Eigen::Matrix3f& R,
                      const Eigen::Vector3f& p, const Eigen::Vector3f& origin, const Eigen::Vector3f& d,
                      float tmax) {
  ShapeRayHit out;
  const Eigen::Vector3f o = R.transpose() * (origin - p);
  const Eigen::Vector3f dl = R.transpose() * d;
  const LocalHit h = ray_local(s, rec, make_query(o, dl, tmax));
  if (h.t < 0.0f) return out;
  out.hit = true;
  out.t = h.t;
  out.point = origin + h.t * d;
  out.normal = h.t == 0.0f && rec.type != ShapeType::kMesh ? Eigen::Vector3f(-d) : Eigen::Vector3f(R * h.n);
  out.child = h.child;
  return out;
}

ShapeRayHit ray_one(const ShapeStore& s, const ShapeRecord& rec, const Pose& pose, const Ray& ray) {
  const Frame f = object_frame(rec, pose);
  const Eigen::Vector3f d = ray.direction.cast<double>().normalized().cast<float>();
  return ray_posed(s, rec, f.R, f.p, ray.origin, d, ray.tmax);
}

// A point result in some local frame.
struct LocalPoint {
  float distance = kInf;
  Eigen::Vector3f closest = Eigen::Vector3f::Zero(), n = Eigen::Vector3f::Zero();
  uint32_t child = kNoChild;
};

LocalPoint to_local_point(const LeafPointResult& r) {
  LocalPoint lp;
  lp.distance = r.distance;
  lp.closest = Eigen::Vector3f(r.closest[0], r.closest[1], r.closest[2]);
  lp.n = Eigen::Vector3f(r.n[0], r.n[1], r.n[2]);
  return lp;
}

LocalPoint point_local(const ShapeStore& s, const ShapeRecord& rec, const Eigen::Vector3f& p) {
  const float pl[3] = {p[0], p[1], p[2]};
  switch (rec.type) {
    case ShapeType::kMesh: {
      const MeshPoint mp = point_mesh(s.meshes[rec.ref], pl);
      LocalPoint lp = to_local_point(mp.r);
      lp.child = mp.tri;
      return lp;
    }
    case ShapeType::kCompound: {
      LocalPoint best;
      const uint32_t cb = s.child_begin[rec.ref], ce = s.child_begin[rec.ref + 1];
      for (uint32_t c = cb; c < ce; ++c) {
        const CompoundChild& ch = s.children[c];
        const ShapeRecord& cr = s.shapes[ch.shape.index];
        const Eigen::Matrix3f Rc = ch.local.orientation.toRotationMatrix();
        const Eigen::Vector3f pc = Rc.transpose() * (p - ch.local.position);
        const float pcl[3] = {pc[0], pc[1], pc[2]};
        const LeafPointResult r = point_leaf(s, cr, pcl);
        if (best.child == kNoChild || r.distance < best.distance) {
          best.distance = r.distance;
          best.closest = Rc * Eigen::Vector3f(r.closest[0], r.closest[1], r.closest[2]) + ch.local.position;
          best.n = Rc * Eigen::Vector3f(r.n[0], r.n[1], r.n[2]);
          best.child = c - cb;
        }
      }
      return best;
    }
    default: return to_local_point(point_leaf(s, rec, pl));
  }
}

ShapePointResult point_one(const ShapeStore& s, const ShapeRecord& rec, const Pose& pose,
                           const Eigen::Vector3f& x) {
  const Frame f = object_frame(rec, pose);
  const Eigen::Vector3f p = f.R.transpose() * (x - f.p);
  const LocalPoint lp = point_local(s, rec, p);
  ShapePointResult out;
  out.distance = lp.distance;
  out.inside = rec.type != ShapeType::kMesh && lp.distance <= 0.0f;
  out.closest = f.R * lp.closest + f.p;
  out.normal = f.R * lp.n;
  out.child = lp.child;
  return out;
}

}  // namespace

namespace host {

Eigen::Matrix3f shape_rotation(const ShapeRecord& rec, const Pose& pose) { return object_frame(rec, pose).R; }

ShapeRayHit ray_posed_shape(const ShapeStore& store, const ShapeRecord& rec, const Eigen::Matrix3f& R,
                            const Eigen::Vector3f& p, const Eigen::Vector3f& o, const Eigen::Vector3f& d,
                            float tmax) {
  return ray_posed(store, rec, R, p, o, d, tmax);
}

}  // namespace host

Status raycast_shapes(const ShapeSet& shapes, std::span<const ShapeId> shape_of, std::span<const Pose> poses,
                      std::span<const ObjectRay> rays, std::span<ShapeRayHit> out, const ExecConfig& exec) {
  const ShapeStore& store = shapes.store();
  if (Status st = check_objects(store, shape_of, poses); !st.ok()) return st;
  if (rays.size() != out.size()) {
    return Status(StatusCode::kSizeMismatch, "rays has " + std::to_string(rays.size()) +
                                                 " entries but out has " + std::to_string(out.size()));
  }
  if (Status st = check_exec(exec); !st.ok()) return st;
  for (size_t k = 0; k < rays.size(); ++k) {
    const ObjectRay& r = rays[k];
    auto who = [k] { return "ray " + std::to_string(k); };
    if (r.object >= shape_of.size()) {
      return invalid(who() + ": object " + std::to_string(r.object) + " is out of range (" +
                     std::to_string(shape_of.size()) + " objects)");
    }
    if (!r.ray.origin.allFinite()) return invalid(who() + ": origin is not finite");
    if (!r.ray.direction.allFinite()) return invalid(who() + ": direction is not finite");
    if (!(r.ray.direction.cast<double>().squaredNorm() > 0.0)) return invalid(who() + ": direction is zero");
    if (!(r.ray.tmax >= 0.0f)) return invalid(who() + ": tmax must be >= 0 (may be +inf), got " + fmt(r.ray.tmax));
  }
  const host::Executor ex(exec.backend, exec.threads);
  ex.for_each_chunk(rays.size(), kQueryGrain, [&](uint32_t b, uint32_t e, uint32_t) {
    for (uint32_t k = b; k < e; ++k) {
      const uint32_t obj = rays[k].object;
      out[k] = ray_one(store, store.shapes[shape_of[obj].index], poses[obj], rays[k].ray);
    }
  });
  return {};
}

Status query_shape_points(const ShapeSet& shapes, std::span<const ShapeId> shape_of, std::span<const Pose> poses,
                          std::span<const ObjectPoint> points, std::span<ShapePointResult> out,
                          const ExecConfig& exec) {
  const ShapeStore& store = shapes.store();
  if (Status st = check_objects(store, shape_of, poses); !st.ok()) return st;
  if (points.size() != out.size()) {
    return Status(StatusCode::kSizeMismatch, "points has " + std::to_string(points.size()) +
                                                 " entries but out has " + std::to_string(out.size()));
  }
  if (Status st = check_exec(exec); !st.ok()) return st;
  for (size_t k = 0; k < points.size(); ++k) {
    const ObjectPoint& q = points[k];
    auto who = [k] { return "point " + std::to_string(k); };
    if (q.object >= shape_of.size()) {
      return invalid(who() + ": object " + std::to_string(q.object) + " is out of range (" +
                     std::to_string(shape_of.size()) + " objects)");
    }
    if (!q.point.allFinite()) return invalid(who() + ": point is not finite");
  }
  const host::Executor ex(exec.backend, exec.threads);
  ex.for_each_chunk(points.size(), kQueryGrain, [&](uint32_t b, uint32_t e, uint32_t) {
    for (uint32_t k = b; k < e; ++k) {
      const uint32_t obj = points[k].object;
      out[k] = point_one(store, store.shapes[shape_of[obj].index], poses[obj], points[k].point);
    }
  });
  return {};
}

}  // namespace impact
