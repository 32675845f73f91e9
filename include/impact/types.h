// Small value types shared by the public API: handles, descriptors, enums.
#pragma once

#include <cstdint>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "impact/shapes.h"

namespace impact {

/// Refers to a body. Generation 0 is never issued, so a zero handle is null.
/// A handle goes stale when its body is destroyed; using it then is reported as
/// StatusCode::kStaleHandle, never dereferenced.
struct BodyHandle {
  /// Slot in the world's handle table (not the body's storage slot).
  uint32_t index = 0;
  /// Generation of that slot when the handle was issued; 0: null.
  uint32_t generation = 0;
  /// True for the null handle.
  bool is_null() const { return generation == 0; }
  /// Same index and generation.
  friend bool operator==(const BodyHandle&, const BodyHandle&) = default;
};

/// Refers to a static plane collider. Same rules as BodyHandle.
struct PlaneHandle {
  /// Slot in the world's plane handle table.
  uint32_t index = 0;
  /// Generation of that slot when the handle was issued; 0: null.
  uint32_t generation = 0;
  /// True for the null handle.
  bool is_null() const { return generation == 0; }
  /// Same index and generation.
  friend bool operator==(const PlaneHandle&, const PlaneHandle&) = default;
};

/// What counts as a unit quaternion wherever the API takes an orientation (BodyDesc,
/// World::set_orientations, Pose in shape queries, narrow phase and ray scenes): q is
/// finite and | |q|^2 - 1 | <= kUnitQuaternionTolerance, evaluated in double (|q|
/// within about 1e-3 of 1: room for a quaternion composed and stored in float many
/// times, far from any genuine error such as a zero or doubled quaternion). An accepted
/// q is used as q / |q| (stored normalised). Anything else, NaN, Inf, zero or denormal
/// components included, is kInvalidArgument naming the body (or object) index and the
/// field `orientation`, also where the orientation is unused today (plain spheres).
inline constexpr double kUnitQuaternionTolerance = 2e-3;

/// A body: a sphere of `radius`, or any shape of World::shapes(). Units: m, m/s, 1/kg.
struct BodyDesc {
  Eigen::Vector3f position = Eigen::Vector3f::Zero();  ///< centre, m
  Eigen::Vector3f velocity = Eigen::Vector3f::Zero();  ///< m/s
  float inv_mass = 1.0f;      ///< 1/kg; 0 makes the body static (infinite mass). Must be >= 0.
  float radius = 0.5f;        ///< m; must be > 0
  float restitution = 0.0f;   ///< 0 = perfectly inelastic, 1 = perfectly elastic; in [0, 1]
  uint32_t layer = 1u;        ///< layer bits this body belongs to
  uint32_t mask = 0xffffffffu;  ///< layer bits this body collides with
  /// Collision shape from World::shapes(); the default (invalid id) is a sphere of
  /// `radius`. With a shape, `radius` is ignored and the body's bounding radius is
  /// stored in its place (BodyArrays::radius). Half-spaces are not bodies (use planes);
  /// a mesh body must be static (inv_mass 0).
  ShapeId shape{};
  /// Orientation of the shape (a plain sphere's too, checked though unused): a unit
  /// quaternion within kUnitQuaternionTolerance (| |q|^2 - 1 | <= 2e-3), normalised on input.
  Eigen::Quaternionf orientation = Eigen::Quaternionf::Identity();
  /// rad/s, world frame. A body with inv_mass 0 is kinematic when it moves: its
  /// velocity and angular velocity carry it, contacts never change them.
  Eigen::Vector3f angular_velocity = Eigen::Vector3f::Zero();
  /// Coulomb friction coefficient, >= 0. A pair uses sqrt(friction_a * friction_b).
  float friction = 0.6f;
  /// Rolling resistance, >= 0 (dimensionless, like friction): the torque that
  /// opposes rolling is at most rolling_resistance * normal force * 1 m. A pair uses
  /// the larger of the two.
  float rolling_resistance = 0.0f;
  /// Velocity damping, 1/s, >= 0: v *= 1 / (1 + dt * damping) every step.
  float linear_damping = 0.0f;
  /// Angular velocity damping, 1/s, >= 0.
  float angular_damping = 0.0f;
  /// Multiplies the world's gravity for this body (finite; 0 = floats, -1 = falls up).
  float gravity_scale = 1.0f;
  /// No rotation: contacts and torques never change the angular velocity (infinite
  /// inertia). Otherwise the inertia is the shape's (uniform density) scaled to the
  /// body's mass; a plain sphere's is that of a solid ball, 2/5 m r^2.
  bool fixed_rotation = false;
};

/// A static half-space { x : dot(normal, x) <= offset }. The normal points out of
/// the solid into free space; it need not be unit length (it is normalised) but
/// must be finite and non-zero.
struct PlaneDesc {
  /// Outward normal (finite, non-zero; normalised on creation).
  Eigen::Vector3f normal = Eigen::Vector3f::UnitY();
  float offset = 0.0f;        ///< m, signed distance of the surface from the origin along normal
  float restitution = 0.0f;   ///< in [0, 1]
  float friction = 0.6f;      ///< Coulomb coefficient, >= 0 (combined with a body's as sqrt(f_a f_b))
  /// Layer bits the plane belongs to.
  uint32_t layer = 1u;
  /// Layer bits the plane collides with.
  uint32_t mask = 0xffffffffu;
};

/// Which thread runtime executes the passes.
enum class Backend : int {
  kDefault = 0,  ///< the one chosen at build time by IMPACT_THREADS
  kSerial,       ///< one thread, same code path and same chunking
  kTbb,          ///< oneTBB task arena
  kOpenMP,       ///< OpenMP parallel for
};

/// Broad-phase structure (docs/broadphase.md has the measured trade-offs).
enum class BroadPhaseKind : int {
  kGrid = 0,        ///< parallel radix-sorted uniform grid, hierarchical levels for mixed sizes
  kBruteForce = 1,  ///< all pairs, O(n^2): the reference oracle
  kLbvh = 2,        ///< linear BVH: Morton sort + one-pass bottom-up build (docs/lbvh.md)
  /// Sweep-and-prune on the axis of greatest variance, incremental across calls
  /// (docs/sap.md). Suits scenes spread along one axis; slow for dense 3D crowds.
  kSweepAndPrune = 3,
  /// Grid or LBVH, chosen from the boxes at every from-scratch build by the
  /// measured rule in docs/broadphase.md ("Automatic choice").
  kAuto = 4,
};

/// What an LBVH does on a coherent update (same box count as its tree).
enum class LbvhUpdate : int {
  kRebuild = 0,  ///< rebuild the tree from scratch every time
  kRefit = 1,    ///< keep the tree's topology, recompute its bounds (until max_refits)
  /// Refit, and rebuild once the refitted tree's SAH cost exceeds refit_sah_limit
  /// times its cost right after the last build (one extra pass over the nodes).
  kAuto = 2,
  /// Tree over fat (margin-grown) boxes plus a cache of the fat-overlapping pairs:
  /// an update re-queries only the boxes that left their fat box and filters the
  /// cache by the exact boxes. Pairs come sorted by (a, b). Rebuilds once the movers
  /// since the build add up to n, after max_refits updates, or when the filter
  /// changes. When more than a quarter of the boxes move out in one update, that update
  /// and the next 1 (2, 4, ... 64 as it recurs) refit instead, pairs by traversal.
  kPairCache = 3,
};

/// A broad-phase candidate pair of body slots (or box indices), a < b.
struct BodyPair {
  /// The lower slot / index.
  uint32_t a;
  /// The higher slot / index.
  uint32_t b;
  /// Same a and b.
  friend bool operator==(const BodyPair&, const BodyPair&) = default;
};

/// Name of a backend, for messages and logs.
const char* to_string(Backend backend);
/// Name of a broad-phase structure, for messages and logs.
const char* to_string(BroadPhaseKind kind);
/// Name of an LBVH update policy, for messages and logs.
const char* to_string(LbvhUpdate update);

}  // namespace impact
