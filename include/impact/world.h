// World: a batch of bodies (plain spheres, or any shape of World::shapes()) and static
// planes stored as structure-of-arrays, stepped by a fixed-timestep pipeline of flat
// data-parallel passes (the stages of host/pipeline/step.cpp).
//
// Thread safety: a World is not internally synchronised. Calls on one World must
// not overlap; different Worlds may be used from different threads.
#pragma once

#include <cstdint>
#include <memory>
#include <span>

#include <Eigen/Core>

#include "impact/narrowphase.h"
#include "impact/status.h"
#include "impact/types.h"

namespace impact {

/// The contact solver's method (docs/solver.md compares them on the same scenes).
enum class SolverKind : uint8_t {
  /// Rigid bodies: per step `substeps` substeps, each integrate velocities, warm start,
  /// solve with a soft bias, integrate positions, relax without bias; then one
  /// restitution pass. Gauss-Seidel over a deterministic graph colouring of the
  /// contacts; angular terms, Coulomb friction at a central anchor per manifold,
  /// twist and rolling resistance (Box2D v3 / Box3D's scheme). Manifolds deeper than
  /// max_push_speed * dt take a recovery path: kJacobi's velocity solve and position
  /// correction (position_iterations, position_correction), which add no energy.
  kSoftStep,
  /// Normal impulses only, no rotation or friction: Jacobi iteration with mass
  /// splitting, then position correction (the solver before rigid bodies).
  kJacobi,
};

/// How a World keeps fast bodies from tunnelling (docs/ccd.md has the design and the
/// measured cost and error of each mode).
enum class ContinuousMode : uint8_t {
  /// Contacts only where shapes overlap at the step's start: a body whose travel in a
  /// step exceeds the size of what it meets can pass through it.
  kOff,
  /// Speculative contacts (Catto, "Continuous collision", GDC 2013): every candidate
  /// pair (broad phase on swept bounds) whose gap could close within the step gets a
  /// one-point contact at its closest points with a negative depth (the gap), which
  /// the solver lets close but not cross. Cheap; misses what a gap along the step's
  /// start normal does not see (a fast spinning plank, a sphere that slides round a
  /// corner first).
  kSpeculative,
};

/// Continuous collision settings (WorldDesc::ccd).
struct ContinuousDesc {
  ContinuousMode mode = ContinuousMode::kOff;
  /// m, >= 0: gap added to every pair's reach (|relative velocity| dt plus the spin
  /// bound) under which a speculative contact is made.
  float speculative_margin = 0.01f;
};

/// Accuracy knobs of the contact solver (docs/solver.md has their measured cost and error).
struct SolverDesc {
  SolverKind kind = SolverKind::kSoftStep;
  /// kSoftStep: substeps per step, >= 1: the soft step's accuracy knob. With the
  /// automatic stiffness, more substeps = stiffer contacts (less sink, taller stacks
  /// stand), at a cost linear in substeps (docs/solver.md, "Stiffness and substeps").
  uint32_t substeps = 4;
  /// kSoftStep: stiffness of contacts, Hz (>= 0; 0 = automatic, an eighth of the
  /// substep rate: 30 Hz at 60 Hz and 4 substeps; larger values are capped there), and
  /// their damping ratio (>= 0).
  float contact_hertz = 0.0f;
  float contact_damping_ratio = 10.0f;
  /// kSoftStep: the fastest a contact pushes overlapping bodies apart, m/s (> 0); an
  /// overlap deeper than max_push_speed * dt takes the recovery path instead.
  float max_push_speed = 3.0f;
  /// kJacobi: velocity iterations. 1 is exact for an isolated pair; stacks and piles
  /// need more, or warm starting to spread work over steps.
  uint32_t velocity_iterations = 8;
  /// kJacobi, and kSoftStep's deep overlaps: position-correction iterations; 0 turns
  /// position correction off.
  uint32_t position_iterations = 4;
  /// kJacobi, and kSoftStep's deep overlaps: fraction of the penetration beyond slop
  /// removed per step, in [0, 1].
  float position_correction = 0.8f;
  /// Penetration left uncorrected, m, >= 0; keeps resting contacts persistent (the
  /// narrow phase reports overlaps only, so a contact pushed to zero depth would be
  /// lost the next step).
  float penetration_slop = 0.001f;
  /// Approach speeds below this (m/s, >= 0) get no bounce, so resting bodies settle.
  float restitution_threshold = 0.5f;
  /// Fraction of last step's impulse a persisting contact starts from, in [0, 1]
  /// (0 = cold start every step).
  float warm_start = 1.0f;
  /// kSoftStep: islands and sleeping (docs/solver.md, "Islands and sleeping"). Dynamic
  /// bodies joined by contacts form an island; an island whose every body has moved
  /// slower than sleep_speed (m/s, > 0; a body's speed is |v| + radius |w|) for
  /// sleep_time (s, > 0) falls asleep: its velocities are zeroed and the solver takes
  /// its bodies as static until a contact with an awake body (a dynamic one, or a
  /// moving kinematic one), wake_bodies() or a call that moves, pushes or removes a
  /// body wakes the island. A world whose every dynamic body sleeps skips its step.
  /// kJacobi keeps every body awake.
  bool sleep = true;
  float sleep_speed = 0.05f;
  float sleep_time = 0.5f;
};

/// Settings fixed at creation (some can be changed later through setters).
struct WorldDesc {
  Eigen::Vector3f gravity{0.0f, -9.81f, 0.0f};  ///< m/s^2
  float fixed_dt = 1.0f / 60.0f;                ///< s, length of one step; > 0
  /// Upper bound on steps run by one advance() call; time beyond it is dropped
  /// (and reported) so a slow frame cannot snowball ("spiral of death").
  uint32_t max_steps_per_frame = 8;
  SolverDesc solver;
  /// Steps between spatial re-sorts of body storage (0 = never). Re-sorting puts
  /// bodies that are close in space close in memory, which speeds up every pass
  /// of large scenes; it changes slots (bodies().handles maps them), never handles.
  uint32_t reorder_interval = 32;
  /// Keep last step's positions so interpolated_positions() can blend (costs 12 B/body).
  bool interpolation = false;
  /// Bodies that rotate take the gyroscopic torque -w x (I w) (stable at any spin; a
  /// T-handle spun about its middle axis flips as it should): kSoftStep keeps the
  /// world angular momentum of each substep, kJacobi takes an implicit Euler step.
  /// false: angular velocity changes only by contacts and torques (cheaper, but a
  /// torque-free body's angular momentum then drifts as it turns).
  bool gyroscopic = true;
  BroadPhaseKind broad_phase = BroadPhaseKind::kGrid;
  /// What an LBVH broad phase does from step to step (docs/lbvh.md): rebuild,
  /// refit, refit until its SAH cost grows by lbvh_refit_sah_limit (> 1), or keep a
  /// fat-box pair cache (kPairCache, margin lbvh_fat_margin; see BroadPhaseOptions).
  LbvhUpdate lbvh_update = LbvhUpdate::kRebuild;
  double lbvh_refit_sah_limit = 1.5;
  float lbvh_fat_margin = 0.2f;
  /// Broad-phase boxes cover each body's motion over the step (from p to
  /// p + v dt, v after gravity; a plain sphere's swept sphere, a shaped body's posed
  /// bounds joined with them moved by v dt) instead of its pose at the step's start, so bodies
  /// that meet within the step become candidate pairs even when fast. More pairs
  /// for slow scenes; the input continuous collision needs.
  bool swept_bounds = false;
  /// Continuous collision (kOff: none). Any mode but kOff implies swept_bounds.
  ContinuousDesc ccd{};
  /// Accuracy knobs of the general narrow phase that runs once a body has a shape
  /// (BodyDesc::shape): GJK / EPA iteration caps and tolerances, SIMD or scalar
  /// kernels (docs/narrowphase.md has their cost and error). Its `exec` is ignored:
  /// the world's backend and threads run every pass.
  NarrowPhaseOptions narrow_phase{};
  Backend backend = Backend::kDefault;
  /// Worker threads; 0 = all hardware threads. Results do not depend on it.
  uint32_t threads = 0;
};

/// Wall time of each pass of the last step, ms.
struct PassTimes {
  double integrate = 0;     ///< both halves of semi-implicit Euler
  double bounds = 0;        ///< the broad phase's boxes
  double broad_phase = 0;   ///< candidate body pairs
  double narrow_phase = 0;  ///< the plane filter and the contact manifolds
  double solve = 0;         ///< velocity solve and position correction
  double ccd = 0;           ///< speculative contacts (WorldDesc::ccd)
  double total = 0;         ///< the whole step (every stage, the re-sort included)
};

/// What the last step did.
struct StepStats {
  uint64_t pairs = 0;          ///< broad-phase candidate pairs (body-body)
  uint64_t manifolds = 0;      ///< contact manifolds (body-body plus body-plane)
  uint64_t contacts = 0;       ///< contact points of those manifolds (the solver's contacts)
  uint64_t plane_contacts = 0; ///< of which body-plane
  uint64_t asleep_bodies = 0;  ///< bodies asleep after the step (SolverDesc::sleep)
  bool skipped = false;        ///< every dynamic body slept: the step ran no stage
  uint64_t speculative = 0;    ///< of the manifolds, speculative ones (a gap, depth < 0)
  PassTimes ms;                ///< wall time per pass
};

/// What one advance() call did.
struct FrameResult {
  uint32_t steps = 0;      ///< fixed steps run
  float alpha = 0.0f;      ///< interpolation factor in [0, 1): leftover time / fixed_dt
  float dropped = 0.0f;    ///< s of frame time discarded by max_steps_per_frame
};

/// Read-only SoA view of the bodies in dense storage order. Valid until the next
/// call that creates or destroys bodies or steps (a step may re-sort slots, see
/// WorldDesc::reorder_interval). Slot i belongs to handles[i].
struct BodyArrays {
  std::span<const float> pos_x, pos_y, pos_z;         ///< position, m
  std::span<const float> vel_x, vel_y, vel_z;         ///< velocity, m/s
  std::span<const float> inv_mass;                    ///< 1/kg, 0 = static
  std::span<const float> radius;                      ///< m: the sphere, or a shape's bounding radius
  std::span<const float> restitution;                 ///< in [0, 1]
  std::span<const uint32_t> layer, mask;              ///< collision filter
  std::span<const BodyHandle> handles;                ///< slot -> handle
  /// Per body: 1 while it sleeps (SolverDesc::sleep); static bodies never do.
  std::span<const uint8_t> asleep;
  /// Per body: the index of its shape in World::shapes() (ShapeId::index), or
  /// kSphereBody for a plain sphere of `radius`; empty while no body has a shape.
  std::span<const uint32_t> shape;
  /// Orientation, a unit quaternion (qx, qy, qz, qw; the input normalised, see
  /// kUnitQuaternionTolerance in include/impact/types.h); empty while no body has a shape
  /// or can rotate (every body is then at the identity orientation).
  std::span<const float> qx, qy, qz, qw;
  /// Angular velocity, rad/s, world frame; empty while no body can rotate (every
  /// body's is then zero).
  std::span<const float> wx, wy, wz;
  std::span<const float> friction;            ///< Coulomb coefficient
  std::span<const float> rolling_resistance;  ///< see BodyDesc::rolling_resistance
  /// The shape index of a plain sphere body.
  static constexpr uint32_t kSphereBody = 0xffffffffu;
  /// Bodies.
  size_t size() const { return handles.size(); }
};

/// Read-only SoA view of the static planes (half-spaces {x : dot(normal, x) <= offset},
/// unit normals) in dense storage order. Valid until planes are created or destroyed.
/// Slot i belongs to handles[i]; it is the plane index of ContactArrays::b.
struct PlaneArrays {
  std::span<const float> normal_x, normal_y, normal_z;  ///< unit outward normal
  std::span<const float> offset;                        ///< m, along the normal
  std::span<const float> restitution;                   ///< in [0, 1]
  std::span<const float> friction;                      ///< Coulomb coefficient
  std::span<const uint32_t> layer, mask;                ///< collision filter
  std::span<const PlaneHandle> handles;                 ///< slot -> handle
  /// Planes.
  size_t size() const { return handles.size(); }
};

/// Collision data of the last step as contact manifolds, one per touching pair (or
/// compound child / mesh triangle pair), in a deterministic order: body-body manifolds
/// in broad-phase pair order, then body-plane ones by body slot then plane. Manifold m:
/// bodies a[m] and b[m] (b[m] is a plane index when b_is_plane[m]), a unit normal from
/// a to b, depth[m] > 0 the overlap (depth[m] < 0: a speculative contact of
/// WorldDesc::ccd, its one point midway across the gap -depth[m]); the safe (overlap-free) positions are
/// a - normal*depth*wa and b + normal*depth*wb with w = inv_mass / (inv_mass_a +
/// inv_mass_b). Its point_count[m] points (1 to 4) are entries first_point(m) ..
/// first_point(m) + point_count[m] - 1 of the point arrays: each midway between the two
/// surfaces, with its own depth along the normal and the solver's impulse.
struct ContactArrays {
  std::span<const uint32_t> a;        ///< body slot
  std::span<const uint32_t> b;        ///< body slot, or plane index if b_is_plane
  std::span<const uint8_t> b_is_plane;  ///< 1: b is a plane index
  std::span<const float> normal_x, normal_y, normal_z;  ///< unit, from a to b
  std::span<const float> depth;       ///< m, the manifold's (deepest point's) overlap; < 0: a gap
  std::span<const uint8_t> point_count;  ///< 1 to 4
  /// Per manifold: its first point. Empty when every manifold has one point, whose
  /// index is then the manifold's (a world of plain spheres); see first_point().
  std::span<const uint32_t> first_points;
  std::span<const float> point_x, point_y, point_z;  ///< per point, world, m
  std::span<const float> point_depth;                ///< per point: overlap along the normal, m
  /// Per point: its id within its manifold, kept while the contact persists (the
  /// solver's warm-start key); empty when every point's id is its slot (plain spheres).
  std::span<const uint32_t> point_feature;
  std::span<const float> impulse;                    ///< per point: accumulated normal impulse, N*s
  /// Manifolds.
  size_t size() const { return a.size(); }
  /// Points of all manifolds.
  size_t points() const { return point_x.size(); }
  /// Index of manifold m's first point.
  size_t first_point(size_t m) const { return first_points.empty() ? m : first_points[m]; }
};

class WorldImpl;
struct AabbQueries;
struct SphereQueries;
struct PointQueries;
struct QueryHits;

/// A simulated world: bodies, planes and shapes, stepped at a fixed timestep.
class World {
 public:
  /// Validates desc and makes a world. On error *out is left empty.
  [[nodiscard]] static Status create(const WorldDesc& desc, std::unique_ptr<World>* out);
  /// Frees every array of the world; its handles must not be used after.
  ~World();
  World(const World&) = delete;
  World& operator=(const World&) = delete;

  // --- bodies ------------------------------------------------------------------
  /// Adds bodies; out receives one handle each (out.size() == descs.size()).
  /// All-or-nothing: any invalid desc rejects the whole batch.
  Status create_bodies(std::span<const BodyDesc> descs, std::span<BodyHandle> out);
  /// Bulk import from column-major Eigen arrays (3 x n), read in place.
  /// velocities may have 0 columns (all zero); radii and inv_masses have n entries;
  /// every other field (restitution, filters, friction, damping, ...) comes from `common`.
  Status create_bodies(const Eigen::Ref<const Eigen::Matrix3Xf>& positions,
                       const Eigen::Ref<const Eigen::Matrix3Xf>& velocities,
                       const Eigen::Ref<const Eigen::VectorXf>& radii,
                       const Eigen::Ref<const Eigen::VectorXf>& inv_masses, const BodyDesc& common,
                       std::span<BodyHandle> out);
  /// Removes bodies; their handles go stale. All-or-nothing.
  Status destroy_bodies(std::span<const BodyHandle> handles);
  /// Moves bodies (m; a teleport: no interpolation across it). All-or-nothing.
  Status set_positions(std::span<const BodyHandle> handles, std::span<const Eigen::Vector3f> values);
  /// Sets velocities (m/s, finite). All-or-nothing.
  Status set_velocities(std::span<const BodyHandle> handles, std::span<const Eigen::Vector3f> values);
  /// Positions of the given bodies, out[i] for handles[i].
  Status get_positions(std::span<const BodyHandle> handles, std::span<Eigen::Vector3f> out) const;
  /// Velocities of the given bodies, out[i] for handles[i].
  Status get_velocities(std::span<const BodyHandle> handles, std::span<Eigen::Vector3f> out) const;
  /// Sets angular velocities (rad/s, world frame, finite); a body with
  /// BodyDesc::fixed_rotation accepts only zero. A static body that spins is a
  /// kinematic one (it turns, contacts never change it). All-or-nothing.
  Status set_angular_velocities(std::span<const BodyHandle> handles, std::span<const Eigen::Vector3f> values);
  /// Angular velocities, out[i] for handles[i] (zero for every body while none rotates).
  Status get_angular_velocities(std::span<const BodyHandle> handles, std::span<Eigen::Vector3f> out) const;
  /// Sets orientations (a teleport), plain spheres' too. Unit means finite with
  /// | |q|^2 - 1 | <= kUnitQuaternionTolerance (2e-3, include/impact/types.h); stored
  /// normalised. All-or-nothing: a NaN, Inf, zero or non-unit value is kInvalidArgument
  /// naming "body i" and "orientation", and nothing changes.
  Status set_orientations(std::span<const BodyHandle> handles, std::span<const Eigen::Quaternionf> values);
  /// Orientations, out[i] for handles[i].
  Status get_orientations(std::span<const BodyHandle> handles, std::span<Eigen::Quaternionf> out) const;
  /// Adds forces (N, finite) at the bodies' centres of mass for the next step only
  /// (the accumulators are cleared once it has used them). Static and kinematic bodies
  /// ignore forces, torques and impulses. All-or-nothing.
  Status apply_forces(std::span<const BodyHandle> handles, std::span<const Eigen::Vector3f> forces);
  /// Adds forces (N) applied at world points (m) for the next step: the force, and
  /// the torque (point - centre of mass) x force. All-or-nothing.
  Status apply_forces_at(std::span<const BodyHandle> handles, std::span<const Eigen::Vector3f> forces,
                         std::span<const Eigen::Vector3f> points);
  /// Adds torques (N m, world frame) for the next step. All-or-nothing.
  Status apply_torques(std::span<const BodyHandle> handles, std::span<const Eigen::Vector3f> torques);
  /// Applies impulses (N s) at world points (m) now: v += J / m,
  /// w += I_world^-1 ((point - centre of mass) x J). All-or-nothing.
  Status apply_impulses(std::span<const BodyHandle> handles, std::span<const Eigen::Vector3f> impulses,
                        std::span<const Eigen::Vector3f> points);
  /// Wakes the bodies' islands (SolverDesc::sleep): they move again from the next step.
  /// An awake body's sleep timer restarts. All-or-nothing.
  Status wake_bodies(std::span<const BodyHandle> handles);
  /// Dense slot of a live handle, or an error.
  Status slot_of(BodyHandle handle, uint32_t* out_slot) const;
  /// Live bodies.
  size_t body_count() const;
  /// Every body field as read-only spans in slot order (see BodyArrays for validity).
  BodyArrays bodies() const;

  /// The shapes bodies may carry (BodyDesc::shape). Add shapes before creating the
  /// bodies that use them; shapes are never removed.
  ShapeSet& shapes();
  /// Read-only access to the world's shapes.
  const ShapeSet& shapes() const;

  // --- planes ------------------------------------------------------------------
  /// Adds static planes (normals normalised, offsets scaled with them); out receives
  /// one handle each. All-or-nothing.
  Status create_planes(std::span<const PlaneDesc> descs, std::span<PlaneHandle> out);
  /// Removes planes; their handles go stale. All-or-nothing.
  Status destroy_planes(std::span<const PlaneHandle> handles);
  /// Live planes.
  size_t plane_count() const;
  /// Every plane field as read-only spans in slot order.
  PlaneArrays planes() const;

  // --- time --------------------------------------------------------------------
  /// Runs exactly one fixed step of desc().fixed_dt; last_step() then describes it.
  /// Fails when a capacity is exceeded (more than 2^32 - 1 pairs or 2^31 - 1 contact
  /// points) or a body left the supported range |x| <= 1e18 m; the bodies have then
  /// been integrated but not collided, and contacts() is empty.
  Status step();
  /// Adds frame_seconds (>= 0, finite) to the accumulator and runs as many fixed
  /// steps as fit (at most max_steps_per_frame). Invalid frame time runs nothing.
  Status advance(float frame_seconds, FrameResult* out = nullptr);
  /// Leftover accumulator time / fixed_dt after the last advance(), in [0, 1).
  float interpolation_alpha() const;
  /// (1-alpha)*previous + alpha*current per body, in slot order. Needs
  /// WorldDesc::interpolation; out.size() == body_count().
  Status interpolated_positions(std::span<Eigen::Vector3f> out) const;

  // --- results -------------------------------------------------------------------
  /// Counts and pass times of the last step.
  const StepStats& last_step() const;
  /// The last step's contact manifolds (see ContactArrays); valid until the next call
  /// that steps, creates or destroys bodies or planes.
  ContactArrays contacts() const;
  /// The last step's broad-phase pairs (body slots, a < b), in the order the contacts
  /// follow; valid like contacts().
  std::span<const BodyPair> pairs() const;
  /// 64-bit hash of the bytes of every body field (position, velocity, mass, radius,
  /// restitution, filters, handles, and orientation and shape once a body has one) in
  /// slot order; equal hashes across thread counts and backends are the determinism
  /// contract.
  uint64_t state_hash() const;

  // --- queries ("what is near me", include/impact/broadphase.h) --------------------
  /// Bodies near each query, answered by the world's own broad-phase structure over
  /// the boxes [p - r, p + r] of the bodies' current positions: a body is a hit when
  /// its box overlaps the query box / lies within the sphere's radius of its centre
  /// (box distance) / contains the point, and (its layer & the query's mask) != 0.
  /// Hits are body slots (bodies().handles[slot] is the handle), ascending per query;
  /// the same bytes for every broad-phase kind, backend and thread count. When bodies
  /// moved since the structure was last built (a step, set_positions, creation), the
  /// first query refreshes it through the structure's coherent update (LBVH refit per
  /// WorldDesc::lbvh_update, grid rebuild, ...), which the next step builds on.
  Status query_aabbs(const AabbQueries& queries, QueryHits* out);
  /// The sphere form of query_aabbs.
  Status query_spheres(const SphereQueries& queries, QueryHits* out);
  /// The point form of query_aabbs.
  Status query_points(const PointQueries& queries, QueryHits* out);

  // --- settings ------------------------------------------------------------------
  /// The settings in force (creation's, as changed by the setters below).
  const WorldDesc& desc() const;
  /// The thread runtime in use (kDefault resolved).
  Backend backend() const;
  /// Worker threads the runtime runs.
  uint32_t threads() const;
  /// Switches the thread runtime; kUnsupported if it was not built in.
  Status set_backend(Backend backend, uint32_t threads);
  /// Switches the broad-phase structure; the next step builds it afresh.
  Status set_broad_phase(BroadPhaseKind kind);
  /// Replaces the solver knobs (validated as in create()).
  Status set_solver(const SolverDesc& solver);
  /// Sets gravity, m/s^2 (finite).
  Status set_gravity(const Eigen::Vector3f& gravity);

 private:
  explicit World(std::unique_ptr<WorldImpl> impl);
  std::unique_ptr<WorldImpl> impl_;
};

/// Backends compiled into this build.
bool backend_available(Backend backend);
/// Hardware threads visible to the process.
uint32_t hardware_threads();

}  // namespace impact
