// Broad phase as a stand-alone stage: overlapping pairs of a caller's boxes.
// The world's step uses the same code; this entry point lets a user run only the
// broad phase over their own bounds (and lets tests and benchmarks do the same).
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "impact/status.h"
#include "impact/types.h"

namespace impact {

/// Axis-aligned boxes as SoA spans of equal length n. layer/mask/is_static may be
/// empty: then every box collides with every box. Two boxes pair when they
/// overlap or touch (min <= max on all axes), (layer_a & mask_b) && (layer_b & mask_a),
/// and not both are static.
///
/// Swept input mode: when dx/dy/dz are given (all three, one entry per box), box i
/// stands for its motion over the step: the union of the box and the box moved by
/// (dx, dy, dz)[i], so fast bodies that meet within the step pair up (the input of
/// continuous collision).
struct AabbInput {
  /// Box corners, m: finite, min <= max on every axis.
  std::span<const float> min_x, min_y, min_z, max_x, max_y, max_z;
  /// Layer bits each box belongs to / collides with: with is_static, all three empty
  /// (no filter) or all three of length n.
  std::span<const uint32_t> layer = {}, mask = {};
  /// Non-zero for a static box (two static boxes never pair).
  std::span<const uint8_t> is_static = {};
  /// Swept mode: each box's motion over the step, m (all three empty: off).
  std::span<const float> dx = {}, dy = {}, dz = {};
  /// Number of boxes (n).
  size_t size() const { return min_x.size(); }
};

/// Where passes run. Results are identical for every value.
struct ExecConfig {
  /// Thread runtime (kDefault: the build's)
  Backend backend = Backend::kDefault;
  uint32_t threads = 0;  ///< 0 = all hardware threads
};

/// Structure and update policy of a BroadPhase.
struct BroadPhaseOptions {
  /// The structure (kAuto: grid or LBVH per build)
  BroadPhaseKind kind = BroadPhaseKind::kGrid;
  /// LBVH only: what update() does when the box count is unchanged
  /// (docs/lbvh.md has the measured cost of each policy).
  LbvhUpdate lbvh_update = LbvhUpdate::kRebuild;
  /// LbvhUpdate::kAuto: rebuild once the refitted tree's SAH cost exceeds this
  /// multiple (>= 1) of its cost right after the last build.
  double lbvh_refit_sah_limit = 1.5;
  /// Either refit policy (and kPairCache) rebuilds after this many updates in a row (>= 1).
  uint32_t lbvh_max_refits = 1000;
  /// LbvhUpdate::kPairCache: the tree holds each box grown on every side by this
  /// fraction of its largest edge (at least of the scene's largest edge / 1024), and
  /// a box is re-queried only when it leaves that fat box. Larger: fewer re-queries,
  /// more cached candidate pairs. Finite, >= 0. Speed only: pairs are always exact.
  float lbvh_fat_margin = 0.2f;
};

// --- queries ("what is near me") ----------------------------------------------------------
// Batched queries of the structure as last built or updated: every stored box hit by
// each query, as CSR (QueryHits). Rules (docs/broadphase.md, "Queries"):
//   AABB    [min, max] hits box b  <=>  min <= b.max and b.min <= max on every axis
//                                       (touching counts, as for pairs)
//   sphere  (centre, radius)       <=>  squared distance from the centre to the box
//                                       <= radius^2, computed in double from the float
//                                       inputs by one documented formula, so every
//                                       structure returns the same boxes
//   point   p                      <=>  b.min <= p <= b.max on every axis
// plus, when the boxes were given a filter (layer/mask/is_static), (b.layer & mask) != 0
// with the query's mask (all ones when `mask` is empty); without a filter masks are
// ignored. Static flags play no part. In swept mode (AabbInput dx/dy/dz) the stored
// boxes are the swept boxes.

/// n box queries: SoA spans of equal length; mask empty or one per query.
struct AabbQueries {
  /// Query box corners, m: finite, |v| <= 1e18, min <= max.
  std::span<const float> min_x, min_y, min_z, max_x, max_y, max_z;
  /// Layers each query sees; empty: all.
  std::span<const uint32_t> mask = {};
  /// Number of queries (n).
  size_t size() const { return min_x.size(); }
};

/// n sphere queries: centres (x, y, z) and radii (>= 0), m.
struct SphereQueries {
  /// Centre and radius of each query, m.
  std::span<const float> x, y, z, radius;
  /// Layers each query sees; empty: all.
  std::span<const uint32_t> mask = {};
  /// Number of queries (n).
  size_t size() const { return x.size(); }
};

/// n point queries.
struct PointQueries {
  /// The points, m.
  std::span<const float> x, y, z;
  /// Layers each query sees; empty: all.
  std::span<const uint32_t> mask = {};
  /// Number of queries (n).
  size_t size() const { return x.size(); }
};

/// Answers of n queries: query i hit boxes hits[offsets[i], offsets[i + 1]) (box
/// indices of the last build/update, ascending). offsets has n + 1 entries. The bytes
/// are the same for every structure, backend and thread count.
struct QueryHits {
  /// N + 1 entries: where each query's hits start.
  std::vector<uint32_t> offsets;
  /// Box indices, ascending within each query.
  std::vector<uint32_t> hits;
  /// Number of queries answered (n).
  size_t size() const { return offsets.empty() ? 0 : offsets.size() - 1; }
  /// The hits of query i (i < size()).
  std::span<const uint32_t> of(size_t i) const {
    return std::span<const uint32_t>(hits).subspan(offsets[i], offsets[i + 1] - offsets[i]);
  }
};

/// The state behind a BroadPhase (host/broadphase/broadphase_api.cpp).
class BroadPhaseImpl;

/// Reusable broad phase: keeps its structure and scratch buffers between calls, so
/// steady-state frames do not allocate.
///
///   build(boxes)      the structure from scratch (kAuto chooses grid or LBVH here)
///   update(boxes)     next frame: same box count -> LBVH refit (per lbvh_update),
///                     sweep-and-prune insertion sort, grid rebuild; else build
///   pairs(out)        every overlapping pair of the structure as last built
///   find_pairs(b,out) update + pairs
///
/// The boxes are copied into the structure: the spans need not outlive a call.
///
/// Failure: build, update and find_pairs validate every box (and option) before they
/// change anything, so one rejected for bad input (a NaN or Inf anywhere, min > max,
/// mismatched spans: kInvalidArgument / kSizeMismatch naming the box and field) leaves
/// the structure exactly as the last successful call left it: pairs(), size() and the
/// queries answer as before, and the next valid update proceeds from there. A call
/// that fails after validation (kCapacityExceeded: more boxes than the structure
/// holds) discards the structure, and pairs() and the queries then fail with that
/// error until a build or update succeeds.
class BroadPhase {
 public:
  /// A broad phase of the given structure with default options.
  explicit BroadPhase(BroadPhaseKind kind = BroadPhaseKind::kGrid);
  /// Invalid options (unknown enum, limit < 1, max_refits 0) make every call fail
  /// with kInvalidArgument naming the field.
  explicit BroadPhase(const BroadPhaseOptions& options);
  /// Frees the structure and its scratch.
  ~BroadPhase();
  /// Moves the structure; the source is left empty.
  BroadPhase(BroadPhase&&) noexcept;
  /// Moves the structure; the source is left empty.
  BroadPhase& operator=(BroadPhase&&) noexcept;

  /// Finds every overlapping pair (a < b, box indices), replacing *out. Boxes must
  /// be finite with min <= max; violations are reported naming the box and field.
  /// Pair order is deterministic (documented per structure in docs/broadphase.md)
  /// and independent of the thread count.
  Status find_pairs(const AabbInput& boxes, std::vector<BodyPair>* out, const ExecConfig& exec = {});

  /// Builds the structure from scratch over boxes (validated as find_pairs does;
  /// on bad input the previous structure is kept unchanged, see "Failure" above).
  Status build(const AabbInput& boxes, const ExecConfig& exec = {});
  /// The coherent path for the next frame of the same boxes (see above).
  Status update(const AabbInput& boxes, const ExecConfig& exec = {});
  /// The pairs of the structure as last successfully built or updated (none before a
  /// build); fails while the structure is discarded (see "Failure" above).
  Status pairs(std::vector<BodyPair>* out, const ExecConfig& exec = {});

  /// The structure asked for (BroadPhaseOptions::kind).
  BroadPhaseKind kind() const;
  /// The structure in use: kind(), or for kAuto the last build's choice.
  BroadPhaseKind active_kind() const;
  /// The options given at construction.
  const BroadPhaseOptions& options() const;
  /// Boxes in the structure (0 before the first build).
  size_t size() const;

  /// Queries of the structure as of the last build / update / find_pairs, replacing
  /// *out (see "queries" above). Fails with kInvalidArgument before any successful
  /// build, with the failure's code after a build/update that discarded the structure
  /// (not after one rejected for bad input), on a non-finite value or one beyond 1e18 in
  /// magnitude, min > max, or a negative radius; kSizeMismatch on spans of unequal
  /// length; the message names the query index and field. More than 2^32 - 1 hits in
  /// one batch is kCapacityExceeded (split the batch). On error *out is unchanged.
  /// Cost per structure: docs/broadphase.md.
  Status query_aabbs(const AabbQueries& queries, QueryHits* out, const ExecConfig& exec = {});
  /// Sphere queries, with the rules and errors of query_aabbs.
  Status query_spheres(const SphereQueries& queries, QueryHits* out, const ExecConfig& exec = {});
  /// Point queries, with the rules and errors of query_aabbs.
  Status query_points(const PointQueries& queries, QueryHits* out, const ExecConfig& exec = {});

 private:
  std::unique_ptr<BroadPhaseImpl> impl_;
};

}  // namespace impact
