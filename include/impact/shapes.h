// Geometric proxies (the seeds' proxy table) and their mass properties.
//
// A ShapeSet owns shape geometry; a shape is referred to by its ShapeId and placed
// in the world by a Pose. Every shape's local frame is centred where its
// description says; capsules and cylinders lie along their local z axis.
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "impact/status.h"

namespace impact {

/// The kind of a shape (ShapeSet::type).
enum class ShapeType : uint8_t {
  kSphere = 0,     ///< radius; centred at the origin
  kCapsule = 1,    ///< radius + half length of the core segment from (0,0,-h) to (0,0,+h)
  kBox = 2,        ///< half extents, oriented by the pose
  kAabb = 3,       ///< half extents, always axis-aligned in the world (pose orientation ignored)
  kConvex = 4,     ///< convex hull of a point cloud (vertices + face planes)
  kCylinder = 5,   ///< radius + half length, axis z
  kEllipsoid = 6,  ///< radii along x, y, z
  kHalfSpace = 7,  ///< { x : n.x <= offset } in the local frame; static, unbounded
  kMesh = 8,       ///< static triangle mesh with its own BVH
  kCompound = 9,   ///< union of convex children with local poses (concave as a whole)
};

/// Name of a shape type, for messages and logs.
const char* to_string(ShapeType type);

/// A rigid placement: world = orientation * local + position. The quaternion must be
/// unit length within 1e-3 (it is renormalised); NaN/Inf are rejected.
struct Pose {
  /// Where the shape's local origin lies, m.
  Eigen::Vector3f position = Eigen::Vector3f::Zero();
  /// Rotation from the local frame to the world.
  Eigen::Quaternionf orientation = Eigen::Quaternionf::Identity();
};

/// Index of a shape in its ShapeSet.
struct ShapeId {
  /// Position in the set, in order of addition; 0xffffffff: no shape.
  uint32_t index = 0xffffffffu;
  /// False for the default (invalid) id.
  bool valid() const { return index != 0xffffffffu; }
  /// Same index.
  friend bool operator==(const ShapeId&, const ShapeId&) = default;
};

/// A compound's child: a convex shape of the same set, placed in the compound's frame.
struct CompoundChild {
  /// The child's shape (convex: sphere, capsule, box, hull, cylinder or ellipsoid).
  ShapeId shape;
  /// The child's placement in the compound's frame.
  Pose local;
};

/// Uniform-density mass properties, in the shape's local frame.
struct MassProperties {
  double volume = 0.0;                                         ///< m^3
  double mass = 0.0;                                           ///< kg = density * volume
  Eigen::Vector3d center_of_mass = Eigen::Vector3d::Zero();    ///< m, local frame
  Eigen::Matrix3d inertia = Eigen::Matrix3d::Zero();           ///< kg m^2, about the centre of mass
};

/// The storage behind a ShapeSet (host/shapes/shape_store.h).
struct ShapeStore;

/// Owns shapes. Adding is all-or-nothing: invalid input returns an error naming the
/// field and leaves the set unchanged. Not thread-safe for concurrent adds; const
/// calls may run concurrently.
class ShapeSet {
 public:
  /// An empty set.
  ShapeSet();
  /// Frees every shape.
  ~ShapeSet();
  /// Moves the shapes; ids stay valid in the new set.
  ShapeSet(ShapeSet&&) noexcept;
  /// Moves the shapes; ids stay valid in the new set.
  ShapeSet& operator=(ShapeSet&&) noexcept;

  /// A sphere of radius (m, finite, > 0) centred at the origin.
  Status add_sphere(float radius, ShapeId* out);
  /// A capsule along local z: core segment of half_length (m, >= 0), radius (m, > 0).
  Status add_capsule(float radius, float half_length, ShapeId* out);
  /// An oriented box of half_extents (m, each > 0).
  Status add_box(const Eigen::Vector3f& half_extents, ShapeId* out);
  /// A world-axis-aligned box of half_extents (m, each > 0); ignores pose orientation.
  Status add_aabb(const Eigen::Vector3f& half_extents, ShapeId* out);
  /// Convex hull of the points (at least 4, not all coplanar within a relative 1e-6).
  Status add_convex_hull(std::span<const Eigen::Vector3f> points, ShapeId* out);
  /// A solid cylinder along local z: radius and half_length (m, each > 0).
  Status add_cylinder(float radius, float half_length, ShapeId* out);
  /// An ellipsoid with radii along local x, y, z (m, each > 0).
  Status add_ellipsoid(const Eigen::Vector3f& radii, ShapeId* out);
  /// normal: finite, non-zero (normalised here).
  Status add_half_space(const Eigen::Vector3f& normal, float offset, ShapeId* out);
  /// Triangles (3 indices each) over vertices. Degenerate (zero-area) triangles are
  /// rejected with their index. Static: a mesh never moves with dynamics.
  Status add_mesh(std::span<const Eigen::Vector3f> vertices, std::span<const uint32_t> indices,
                  ShapeId* out);
  /// Children must be sphere, capsule, box, convex, cylinder or ellipsoid shapes of
  /// this set (at least one).
  Status add_compound(std::span<const CompoundChild> children, ShapeId* out);

  /// Number of shapes added.
  size_t size() const;
  /// kInvalidArgument for an unknown id.
  Status type(ShapeId id, ShapeType* out) const;
  /// Uniform density (kg/m^3, > 0). Half-spaces and meshes have no finite/closed
  /// volume: kInvalidArgument (a mesh is static).
  Status mass_properties(ShapeId id, float density, MassProperties* out) const;
  /// World AABB of the shape at pose (half-spaces: kInvalidArgument, unbounded).
  Status bounds(ShapeId id, const Pose& pose, Eigen::Vector3f* min, Eigen::Vector3f* max) const;

  /// Internal storage (host/shapes/shape_store.h).
  const ShapeStore& store() const { return *store_; }

 private:
  std::unique_ptr<ShapeStore> store_;
};

}  // namespace impact
