// What a RayScene holds (host-owned SoA copies of the caller's geometry) and the
// interface its two tracing backends implement (host/raycast/lbvh_backend.cpp,
// host/raycast/embree_backend.cpp). Only this folder sees Embree.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include <Eigen/Core>

#include "host/buffer.h"
#include "host/parallel.h"
#include "host/shapes/shape_store.h"
#include "impact/raycast.h"
#include "impact/shape_queries.h"
#include "impact/status.h"
#include "kernels/raycast/ray_bvh.h"

namespace impact::host {

struct SceneData {
  // Static meshes, concatenated: triangle t of mesh m is global triangle
  // mesh_first_tri[m] + t; indices are global vertex indices.
  Buffer<float> vertices;          // xyz per vertex
  Buffer<uint32_t> indices;        // 3 per triangle
  Buffer<uint32_t> tri_layer;      // per triangle
  std::vector<uint32_t> mesh_first_tri;     // meshes + 1 entries
  std::vector<uint32_t> mesh_first_vertex;  // meshes + 1 entries
  std::vector<uint32_t> mesh_layer;

  // Dynamic spheres and capsules (SoA).
  Buffer<float> sx, sy, sz, sr;
  Buffer<uint32_t> s_layer;
  std::vector<BodyHandle> s_body;  // empty unless synced from a World
  Buffer<float> ax, ay, az, bx, by, bz, cr;
  Buffer<uint32_t> c_layer;

  // Static half-spaces (unit normals).
  Buffer<kernels::PlaneRecord> planes;
  std::vector<PlaneHandle> p_handle;  // empty unless synced from a World

  // Posed shapes (RayScene::set_shapes): the caller's ShapeSet storage (held, not
  // copied), and per object its shape record, frame (world = R * local + p; R is the
  // identity for AABB shapes) and layer; world bounds in ob_* (padded by a few ulps).
  struct ShapeObject {
    Eigen::Matrix3f R;
    Eigen::Vector3f p;
    uint32_t shape;
    uint32_t layer;
  };
  const ShapeStore* shape_store = nullptr;
  std::vector<ShapeObject> objects;
  std::vector<BodyHandle> o_body;  // empty unless synced from a World
  Buffer<float> ob_min_x, ob_min_y, ob_min_z, ob_max_x, ob_max_y, ob_max_z;

  uint32_t mesh_count() const { return static_cast<uint32_t>(mesh_layer.size()); }
  uint32_t triangle_count() const { return static_cast<uint32_t>(tri_layer.size()); }
  uint32_t sphere_count() const { return static_cast<uint32_t>(sr.size()); }
  uint32_t capsule_count() const { return static_cast<uint32_t>(cr.size()); }
  uint32_t shape_count() const { return static_cast<uint32_t>(objects.size()); }
};

/// What changed since the last commit.
struct SceneChanges {
  uint32_t meshes_added = 0;      // meshes [mesh_count - meshes_added, mesh_count) are new
  bool spheres = false, spheres_resized = false;
  bool capsules = false, capsules_resized = false;
  bool shapes = false, shapes_resized = false;
  bool any() const { return meshes_added != 0 || spheres || capsules || shapes; }
};

/// A tracing engine over SceneData. Queries take one chunk of validated rays (unit
/// directions) and reduce into best / hit; planes are done by the caller.
class TraceBackend {
 public:
  virtual ~TraceBackend() = default;
  /// Brings the acceleration structures up to date; sets *dynamic_rebuilt.
  virtual Status commit(const Executor& exec, const SceneData& data, const SceneChanges& changes,
                        bool* dynamic_rebuilt) = 0;
  /// Closest hits into best. When tri_normal is not null, a backend that knows the
  /// geometric normal of the triangles it hits (Embree's Ng) may store it, unnormalised,
  /// at tri_normal[3 * i] for each ray i whose best it set to a triangle, and returns
  /// true; false means the caller computes triangle normals from the vertices.
  /// coherent: the rays are known to be coherent (a camera's), a hint.
  virtual bool closest(const kernels::RayQuery* rays, kernels::RayBest* best, float* tri_normal, uint32_t n,
                       bool coherent) const = 0;
  virtual void any(const kernels::RayQuery* rays, uint8_t* hit, uint32_t n) const = 0;
  /// Threads of the backend's own parallel work (Embree's builders).
  virtual void set_threads(uint32_t) {}
};

/// Posed shape object i against the ray (host/shapes/shape_ray.h), its layer
/// checked against q.mask: the hit distance in [0, q.tmax], or -1.
float shape_ray_t(const SceneData& d, uint32_t i, const kernels::RayQuery& q);
/// The same as a kernels::RayUserTest (ctx = the SceneData).
float shape_user_test(const void* ctx, uint32_t i, const kernels::RayQuery& q);

std::unique_ptr<TraceBackend> make_lbvh_backend(const RaySceneDesc& desc);
/// Null with *status set when Embree cannot start.
std::unique_ptr<TraceBackend> make_embree_backend(const RaySceneDesc& desc, const SceneData& data,
                                                  uint32_t threads, Status* status);

}  // namespace impact::host
