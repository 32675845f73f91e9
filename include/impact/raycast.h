// RayScene: batched ray queries (closest hit for picking, any hit for line of sight)
// against static triangle meshes, dynamic spheres and capsules, posed shapes of a
// ShapeSet (boxes, convex hulls, compounds, ...), and static half-spaces,
// through Embree 3 or through impact's own LBVH (docs/raycast.md).
//
// Rules (the same for both backends; tests/host/raycast_test.cpp checks them against a
// double-precision brute force):
//  - A ray's direction need not be unit; it is normalised, and every distance (tmax, t)
//    is in metres along it. Hits have 0 <= t <= tmax; tmax == 0 never hits.
//  - Spheres, capsules and half-spaces are solid: a ray that starts inside or on one
//    hits it at t = 0, with point = origin and normal = -direction.
//  - Triangles are two-sided; edges and vertices belong to every triangle sharing them
//    (the LBVH path gives the tie to the lower triangle index, Embree to either one);
//    a ray lying in a triangle's plane misses it.
//  - The normal is unit and faces the ray (dot(normal, direction) <= 0).
//  - Layers: a primitive is seen by a ray iff (primitive layer & ray mask) != 0.
//  - Segments (any hit) are closed: a primitive touching either end point occludes.
//  - Posed shapes (set_shapes) hit as impact::raycast_shapes does (the same per-shape
//    code, include/impact/shape_queries.h): solids hit at t = 0 from inside, meshes
//    used as shapes are two-sided triangles, compounds report the child hit.
// Not yet: instancing of meshes.
//
// Thread safety: queries are const and may run concurrently; the setters and commit()
// must not overlap any other call on the same scene.
#pragma once

#include <cstdint>
#include <limits>
#include <memory>
#include <span>

#include <Eigen/Core>

#include "impact/shapes.h"
#include "impact/status.h"
#include "impact/types.h"

namespace impact {

/// Declared in impact/world.h (RayScene::sync_spheres, sync_world).
class World;

/// Which engine traces the rays.
enum class RayBackend : int {
  kEmbree = 0,  ///< Embree 3 (two-level: static meshes in their own instanced scene)
  kLbvh = 1,    ///< impact's LBVH (docs/lbvh.md; ordered traversal); bit-identical across threads
};

/// How dynamic geometry (spheres, capsules, posed shapes) is brought up to date by
/// commit() when only its positions changed (same counts). Embree: the geometry's
/// build quality; LBVH: refit keeps the tree topology and recomputes bounds, rebuild
/// re-sorts.
enum class DynamicUpdate : int {
  kRefit = 0,          ///< Embree RTC_BUILD_QUALITY_REFIT; LBVH refit
  kRebuildLow = 1,     ///< Embree RTC_BUILD_QUALITY_LOW; LBVH rebuild
  kRebuildMedium = 2,  ///< Embree RTC_BUILD_QUALITY_MEDIUM; LBVH rebuild
};

/// How Embree represents spheres.
enum class EmbreeSpheres : int {
  /// User geometry calling impact's ray-sphere kernel: exactly the rules above.
  kUserGeometry = 0,
  /// Embree's built-in sphere points (RTC_GEOMETRY_TYPE_SPHERE_POINT). Faster to
  /// trace, but a ray starting inside a sphere hits its far side instead of t = 0.
  kBuiltin = 1,
};

/// Whether Embree traces each chunk of rays as one stream (rtcIntersect1M /
/// rtcOccluded1M, coherent flag) instead of one rtcIntersect1 / rtcOccluded1 per ray.
/// Streams pay for coherent rays on triangle meshes (camera picking on a level) and
/// lose badly with user geometry (spheres, capsules, posed shapes); docs/raycast.md.
enum class EmbreeStreams : int {
  kAuto = 0,    ///< pick() when the scene's Embree geometry is triangle meshes only
  kNever = 1,   ///< one call per ray (or per packet)
  kAlways = 2,  ///< every query: for coherent rays of your own
};

/// Settings of a RayScene.
struct RaySceneDesc {
  /// The engine that traces the rays.
  RayBackend backend = RayBackend::kEmbree;
  /// How commit() updates moved spheres, capsules and posed shapes.
  DynamicUpdate dynamic_update = DynamicUpdate::kRefit;
  /// Embree: how spheres are represented.
  EmbreeSpheres embree_spheres = EmbreeSpheres::kUserGeometry;
  /// Embree: rays per rtcIntersectN/rtcOccludedN call: 1, 4, 8 or 16 (packets help
  /// coherent rays such as a camera grid; measured in docs/raycast.md).
  uint32_t packet_width = 1;
  /// Embree: streams of rays (see EmbreeStreams); only with packet_width 1 (kAuto
  /// defers to packets, kAlways with packets is an error).
  EmbreeStreams embree_streams = EmbreeStreams::kAuto;
  /// Embree RTC_SCENE_FLAG_ROBUST on the static meshes: watertight edges, a bit slower.
  bool robust = true;
  Backend backend_threads = Backend::kDefault;  ///< thread runtime of the batched queries
  uint32_t threads = 0;                         ///< 0 = all hardware threads
};

/// Refers to a static triangle mesh of a RayScene.
struct MeshHandle {
  /// Mesh id, as RayHit::id reports it; 0xffffffff: null.
  uint32_t id = 0xffffffffu;
  /// True for the null handle.
  bool is_null() const { return id == 0xffffffffu; }
};

/// One ray. direction must be finite and non-zero; origin finite; tmax >= 0 (may be +inf).
struct Ray {
  /// Start point, m.
  Eigen::Vector3f origin = Eigen::Vector3f::Zero();
  /// Direction (any length; normalised by the call).
  Eigen::Vector3f direction = Eigen::Vector3f::UnitZ();
  float tmax = std::numeric_limits<float>::infinity();  ///< m along the normalised direction
  uint32_t mask = 0xffffffffu;                           ///< layers the ray sees
};

/// A closed segment for line-of-sight queries (any hit). from == to never hits.
struct Segment {
  /// First end point, m (finite).
  Eigen::Vector3f from = Eigen::Vector3f::Zero();
  /// Second end point, m (finite).
  Eigen::Vector3f to = Eigen::Vector3f::Zero();
  /// Layers the segment sees.
  uint32_t mask = 0xffffffffu;
};

/// What a ray hit: nothing, a mesh triangle, a sphere, a capsule, a half-space
/// (set_planes) or a posed shape (set_shapes).
enum class HitKind : uint8_t { kNone = 0, kTriangle, kSphere, kCapsule, kPlane, kShape };

/// The closest hit of one ray.
struct RayHit {
  /// What was hit; kNone on a miss (the other fields then keep their defaults).
  HitKind kind = HitKind::kNone;
  /// Mesh id (kTriangle), sphere index, capsule index, plane index or shape object
  /// index (kShape: the index into set_shapes' shape_of / poses).
  uint32_t id = 0xffffffffu;
  /// Triangle index within the mesh (kTriangle); for kShape the compound child or the
  /// triangle of a mesh shape (0 for other shapes); 0 otherwise.
  uint32_t prim = 0;
  /// The body hit, for spheres and shapes filled by sync_spheres / sync_world; null otherwise.
  BodyHandle body;
  /// The plane hit, for planes filled by sync_world; null otherwise.
  PlaneHandle plane;
  float t = std::numeric_limits<float>::infinity();  ///< m along the normalised direction
  Eigen::Vector3f point = Eigen::Vector3f::Zero();    ///< origin + t * unit direction
  Eigen::Vector3f normal = Eigen::Vector3f::Zero();   ///< unit, facing the ray
  /// True unless the ray missed.
  bool hit() const { return kind != HitKind::kNone; }
};

/// A pinhole camera. forward and up need not be unit or orthogonal (up is
/// re-orthogonalised against forward) but must not be parallel.
struct Camera {
  /// Eye point, m: every ray's origin.
  Eigen::Vector3f position = Eigen::Vector3f::Zero();
  /// Viewing direction (the screen centre's ray).
  Eigen::Vector3f forward = -Eigen::Vector3f::UnitZ();
  /// Screen up (y = 0 is the top edge).
  Eigen::Vector3f up = Eigen::Vector3f::UnitY();
  float vertical_fov = 1.0471976f;  ///< radians, in (0, pi)
  float aspect = 16.0f / 9.0f;      ///< width / height, > 0
};

/// Counters of the last commit() (for benchmarks).
struct RaySceneInfo {
  /// What the scene held at the last commit.
  uint32_t meshes = 0, triangles = 0, spheres = 0, capsules = 0, planes = 0, shapes = 0;
  bool dynamic_rebuilt = false;  ///< the last commit rebuilt (not refitted) dynamic geometry
  double commit_ms = 0.0;        ///< wall time of the last commit()
};

/// The state behind a RayScene (host/raycast/ray_scene.cpp).
class RaySceneImpl;

/// Geometry that rays are traced against, and the batched queries (rules at the top of
/// this file). Set geometry, commit(), then query.
class RayScene {
 public:
  /// Validates desc and makes an empty scene. kUnsupported if the backend is not built in.
  [[nodiscard]] static Status create(const RaySceneDesc& desc, std::unique_ptr<RayScene>* out);
  /// Releases the scene and its backend's structures.
  ~RayScene();
  /// Not copyable (it owns backend structures).
  RayScene(const RayScene&) = delete;
  /// Not copyable.
  RayScene& operator=(const RayScene&) = delete;

  // --- geometry (takes effect at commit()) ----------------------------------------
  /// Adds a static mesh: vertices 3 x V (m), triangles 3 x T vertex indices < V.
  /// Degenerate triangles are allowed (they are never hit).
  Status add_mesh(const Eigen::Ref<const Eigen::Matrix3Xf>& vertices,
                  const Eigen::Ref<const Eigen::Matrix<uint32_t, 3, Eigen::Dynamic>>& triangles,
                  uint32_t layer, MeshHandle* out);
  /// Replaces all spheres (SoA: centres, radii > 0, layers; layer may be empty = all 1).
  /// Same count as before: an update (refit or rebuild per DynamicUpdate); else rebuild.
  Status set_spheres(std::span<const float> x, std::span<const float> y, std::span<const float> z,
                     std::span<const float> radius, std::span<const uint32_t> layer = {});
  /// Spheres from a World's bodies (slot i -> sphere i; hits report the body handle).
  /// Bodies with shapes (BodyDesc::shape) appear as their bounding spheres
  /// (BodyArrays::radius); sync_world gives them their exact shapes.
  Status sync_spheres(const World& world);
  /// Everything a World holds that rays can hit, as its step sees it: bodies without a
  /// shape become spheres, bodies with a shape become posed shapes (World::shapes() at
  /// the body's position and orientation; meshes too), the world's planes become
  /// half-spaces, each with its layer. Hits report the body's handle (RayHit::body) or
  /// the plane's (RayHit::plane); RayHit::id indexes the scene's own spheres, shapes
  /// or planes, in body / plane slot order. Replaces what set_spheres, set_shapes and
  /// set_planes gave (meshes and capsules stay). As with set_shapes, the scene keeps a
  /// pointer to the world's ShapeSet storage: the World must outlive the scene or the
  /// next sync. Call it again after the world steps, then commit().
  Status sync_world(const World& world);
  /// Replaces all capsules: segment end points a, b (3 x n), radii > 0, layers (may be empty).
  Status set_capsules(const Eigen::Ref<const Eigen::Matrix3Xf>& a, const Eigen::Ref<const Eigen::Matrix3Xf>& b,
                      std::span<const float> radius, std::span<const uint32_t> layer = {});
  /// Replaces all static half-spaces {x : dot(normal, x) <= offset}; normals need not
  /// be unit but must be finite and non-zero. layer may be empty (all 1).
  Status set_planes(const Eigen::Ref<const Eigen::Matrix3Xf>& normals, std::span<const float> offsets,
                    std::span<const uint32_t> layer = {});
  /// Replaces all posed shapes: object i is shapes' shape shape_of[i] at poses[i]
  /// (unit quaternion within 1e-3, renormalised), seen by rays whose mask meets
  /// layer[i] (layer may be empty = all 1). Every shape type but the half-space (use
  /// set_planes). The scene keeps a pointer to `shapes` (its storage, so moving the
  /// ShapeSet is fine): the ShapeSet must outlive the scene, or stay alive until the
  /// next set_shapes, and must not be changed (shapes added) while queries run. Poses
  /// are copied. Same count as before: an update (refit or rebuild per DynamicUpdate);
  /// else rebuild. Errors: kSizeMismatch, kInvalidArgument naming the object for an
  /// unknown shape id, a half-space, a non-finite or non-unit pose.
  Status set_shapes(const ShapeSet& shapes, std::span<const ShapeId> shape_of, std::span<const Pose> poses,
                    std::span<const uint32_t> layer = {});
  /// Builds or updates acceleration structures for everything set since the last commit.
  Status commit();

  // --- queries (after commit(); kInvalidArgument while changes are pending) ----------
  /// Closest hit per ray; out.size() == rays.size(). On error out is unspecified.
  Status closest_hit(std::span<const Ray> rays, std::span<RayHit> out) const;
  /// 1 per segment that something blocks, else 0; out.size() == segments.size().
  Status any_hit(std::span<const Segment> segments, std::span<uint8_t> out) const;
  /// Picking: rays from the camera through screen points in [0,1]^2 ((0,0) top left,
  /// x right, y down; exactly camera_rays' rays), then closest hits (as Embree streams
  /// under EmbreeStreams::kAuto on mesh-only scenes).
  Status pick(const Camera& camera, std::span<const Eigen::Vector2f> screen, uint32_t mask,
              std::span<RayHit> out) const;

  /// Switches the thread runtime of the queries (results do not depend on it).
  Status set_threads(Backend backend, uint32_t threads);
  /// The settings the scene was created with.
  const RaySceneDesc& desc() const;
  /// Counters of the last commit().
  const RaySceneInfo& info() const;

 private:
  explicit RayScene(std::unique_ptr<RaySceneImpl> impl);
  std::unique_ptr<RaySceneImpl> impl_;
  friend class RaySceneImpl;
};

/// Rays from a camera through screen points in [0,1]^2 (see RayScene::pick); the
/// rays get tmax = +inf and `mask`. Points outside [0,1]^2 are allowed (off-screen).
Status camera_rays(const Camera& camera, std::span<const Eigen::Vector2f> screen, uint32_t mask,
                   std::span<Ray> out);

}  // namespace impact
