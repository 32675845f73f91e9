// Narrow phase as a stand-alone stage: collision data for a caller's own pair list
// over posed shapes (include/impact/shapes.h). The world's step uses the same code.
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "impact/broadphase.h"
#include "impact/shapes.h"
#include "impact/status.h"

namespace impact {

/// A pair of objects: indices into the shapes / poses spans of a collide() call.
struct ShapePair {
  uint32_t a;  ///< first object
  uint32_t b;  ///< second object; normals point from a to b
  /// Equal when both indices are.
  friend bool operator==(const ShapePair&, const ShapePair&) = default;
};

/// Accuracy knobs and execution of the narrow phase (docs/narrowphase.md has the
/// measured cost and error of each).
struct NarrowPhaseOptions {
  /// false: every kernel runs its scalar reference path (same results up to rounding).
  bool simd = true;
  /// GJK (distance / overlap of general convex pairs): iteration cap and relative
  /// tolerance on the distance.
  uint32_t gjk_max_iterations = 64;
  float gjk_tolerance = 1e-6f;
  /// EPA (penetration depth of general convex pairs): iteration cap and relative
  /// tolerance on the depth. The cap does not stop pairs with a convex hull side:
  /// around a deep core a hull's support function has a local minimum at every face
  /// holding the core's projection, so a capped EPA could end on a wrong face. Those
  /// expand until the tolerance is met or the polytope (512 vertices) is full
  /// (docs/narrowphase.md, "Accuracy knobs"). Every pair without a hull side has a lane kernel of
  /// its own, so today the cap reaches no pair of the step or of NarrowPhase::collide;
  /// it still bounds the general path, which takes any shape pair without a kernel. The
  /// tolerance reaches the pairs that still take GJK/EPA: box-hull and hull-hull pairs
  /// above sat_max_vertices, and hulls a hull kernel leaves to the general path (no
  /// edge adjacency, or beyond its scratch limits).
  uint32_t epa_max_iterations = 64;
  float epa_tolerance = 1e-5f;
  /// Pairs of polytopes (boxes other than box-box, convex hulls) whose vertex counts
  /// sum to at most this (a box has 8) take the separating axis test (exact for
  /// polytopes, no iteration cap) instead of GJK/EPA; larger pairs, where SAT's
  /// face-vertex and edge-edge work outgrows GJK/EPA's, keep GJK/EPA. 0: always GJK/EPA.
  /// Both give the same collision data within the tolerances (docs/narrowphase.md).
  uint32_t sat_max_vertices = 96;
  ExecConfig exec{};
};

inline constexpr uint32_t kNoChild = 0xffffffffu;

/// Collision data of one contact region (the seeds' "collision data").
struct Manifold {
  uint32_t pair = 0;            ///< index into the pair list
  uint32_t child_a = kNoChild;  ///< compound child / mesh triangle of a, or kNoChild
  uint32_t child_b = kNoChild;
  Eigen::Vector3f normal = Eigen::Vector3f::UnitY();  ///< unit, from a to b
  /// > 0. Moving b by normal*depth (or a by -normal*depth) is the smallest
  /// displacement that separates them: the safe position.
  float depth = 0.0f;
  uint32_t point_count = 0;     ///< 1..4
  Eigen::Vector3f points[4];    ///< world, midway between the two surfaces
  float point_depth[4] = {0, 0, 0, 0};  ///< penetration along normal at each point
};

/// Object poses as caller-owned arrays, one entry per object (the batch form of
/// NarrowPhase::collide_arrays): position, m, and unit orientation (x, y, z, w).
struct PoseArrays {
  std::span<const float> px, py, pz;
  std::span<const float> qx, qy, qz, qw;
};

/// Collision data per pair in caller-owned arrays of pairs.size() entries each: the
/// kernels' own layout, written in place. Pair i touches when count[i] > 0 (1..4): a
/// unit normal (a to b), depth > 0 (the safe displacement, as Manifold::depth) and
/// points k < count[i] at (point_x[k][i], point_y[k][i], point_z[k][i]) with overlap
/// point_depth[k][i]. The other entries of a pair (all of them when count[i] == 0) are
/// unspecified.
struct PairContactArrays {
  std::span<uint8_t> count;
  std::span<float> normal_x, normal_y, normal_z;
  std::span<float> depth;
  std::span<float> point_x[4], point_y[4], point_z[4];
  std::span<float> point_depth[4];
};

/// Runs the narrow phase; keeps its scratch between calls. Internally it fills the
/// library's one contact layout (SoA manifolds and points) and converts it to
/// Manifold structs at the end of collide().
class NarrowPhase {
 public:
  /// Invalid options are kept out: the defaults stay and every collide() fails with
  /// the options' error until set_options() succeeds.
  explicit NarrowPhase(const NarrowPhaseOptions& options = {});
  /// Frees the scratch.
  ~NarrowPhase();
  /// Moves the options and scratch.
  NarrowPhase(NarrowPhase&&) noexcept;
  /// Moves the options and scratch.
  NarrowPhase& operator=(NarrowPhase&&) noexcept;

  /// Validates options (kInvalidArgument naming the field).
  Status set_options(const NarrowPhaseOptions& options);
  /// The options in force.
  const NarrowPhaseOptions& options() const;

  /// Collision data of every pair: object i is shapes[shape_of[i]] at poses[i].
  /// Manifolds come out sorted by (pair, child_a, child_b): the same bytes for every
  /// backend, thread count and pair order within a bucket. A pair of two convex
  /// shapes gives at most one manifold; mesh and compound pairs one per touching
  /// child pair. Errors: size mismatch, unknown shape id, index out of range,
  /// non-finite pose or unnormalised quaternion (naming the object), a pair of two
  /// half-spaces (unbounded, no finite collision data).
  Status collide(const ShapeSet& shapes, std::span<const ShapeId> shape_of,
                 std::span<const Pose> poses, std::span<const ShapePair> pairs,
                 std::vector<Manifold>* out);

  /// The batch form of collide() for convex objects (sphere, capsule, box, AABB,
  /// cylinder, ellipsoid, convex hull, half-space): poses read from arrays, one result
  /// slot per pair written into the caller's arrays, nothing allocated per call once
  /// the scratch has grown. The same numbers as collide() for the same pairs (without
  /// its per-point feature ids). Cost beyond the pair kernels: one pass over the
  /// objects (validation), one over the pairs (bucket keys), the gather of each pair's
  /// two poses into the kernels' lanes; pairs listed by type skip the bucket sort and
  /// their results are written by the kernels in place (docs/narrowphase.md, "The
  /// batch call"). Errors as collide(), and: a mesh or compound object (kInvalidArgument
  /// naming it: collide() takes those), an array shorter or longer than its count
  /// (kSizeMismatch naming it).
  Status collide_arrays(const ShapeSet& shapes, std::span<const ShapeId> shape_of, const PoseArrays& poses,
                        std::span<const ShapePair> pairs, const PairContactArrays& out);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace impact
