// host::StepContext: what the stages of one World step read and write
// (host/pipeline/step.cpp lists the stages; each lives in its own file of
// host/pipeline/). The context holds references to the world's storage and to the
// units that keep state between steps (broad phase, narrow phase, solver), plus the
// few values one stage hands the next (the bounds).
#pragma once

#include <cstdint>
#include <vector>

#include "host/body_store.h"
#include "host/broadphase/stage.h"
#include "host/buffer.h"
#include "host/contact_manifolds.h"
#include "host/handle_table.h"
#include "host/narrowphase/narrow_phase.h"
#include "host/parallel.h"
#include "host/plane_store.h"
#include "host/solver/contact_solver.h"
#include "host/solver/soft_step_solver.h"
#include "impact/shapes.h"
#include "impact/world.h"
#include "kernels/broadphase/bounds.h"
#include "kernels/common/pair.h"
#include "kernels/integrate/rigid_euler.h"

namespace impact::host {

/// Per-step scratch of the stages: buffers reused from step to step (grown, never
/// shrunk), so a steady scene allocates nothing.
struct StepScratch {
  Buffer<float> box[6];                          // bounds: min xyz, max xyz per body
  Buffer<kernels::BoundsSummary> bounds_partials;
  Buffer<uint32_t> perm, inv_perm;               // reorder
  Buffer<uint32_t> tmp_u32;
  Buffer<uint8_t> tmp_u8;
  Buffer<float> tmp_f32;
  Buffer<BodyHandle> tmp_handle;
  Buffer<float> solver_inv_mass;                 // sleep: inv_mass with the asleep bodies' zeroed
  Buffer<float> island_min;                      // sleep: per island root, its smallest timer
  Buffer<uint32_t> island_parent;
  Buffer<uint8_t> kept_awake;
};

/// One pair's speculative contact (valid when keep).
struct SpeculativeGap {
  float gap;       // m, > 0
  float n[3];      // unit, a to b
  float p[3];      // world, midway across the gap
  uint32_t child_a, child_b;
  bool keep;
};

/// The speculative-contact stage's state (host/pipeline/speculative_stage.cpp).
struct SpeculativeStage {
  Buffer<float> reach_radius;   // plane filter: radius + travel + margin per body
  Buffer<uint8_t> touched;      // per pair (body pairs, then plane pairs): has a manifold
  Buffer<uint64_t> offsets;     // count -> scan over chunks of pairs
  std::vector<SpeculativeGap> rows;  // per pair: its gap when it has no manifold
  ContactManifolds gaps;        // the speculative manifolds, in pair order
  ContactManifolds merged;      // the narrow phase's and the speculative ones, in pair order
};

/// The narrow-phase stage's state: the runner and the arrays it is given.
struct NarrowStage {
  NarrowRunner runner;
  Buffer<kernels::Pair> plane_pairs;            // (body, body_count + plane) from the plane filter
  Buffer<uint32_t> plane_masks;                 // the filter's per-body bits, 32 planes a word
  Buffer<uint64_t> plane_offsets;               // the filter's count -> scan
  std::vector<const ShapeRecord*> rec;          // shaped worlds: per object (bodies, then planes)
  std::vector<ShapeType> types;
  std::vector<PosedObject> poses;
  std::vector<ShapeRecord> records;             // sphere records of plain bodies, then plane records
  uint64_t body_plane_pairs = 0;                // this step's plane pairs (plane_pairs' valid prefix)
  SpeculativeStage speculative;
};

struct StepContext {
  const WorldDesc& desc;
  const Executor& exec;
  float dt;                       // s, desc.fixed_dt
  BodyStore& bodies;
  HandleTable& body_handles;
  const PlaneStore& planes;
  const ShapeSet& shapes;
  uint32_t shaped_count;          // bodies with a shape: the narrow phase runs the general route
  BroadPhaseStage& broad_phase;
  Buffer<kernels::Pair>& pairs;   // body pairs of the broad phase
  NarrowStage& narrow;
  ContactManifolds& contacts;     // the narrow phase's output, the solver's input
  ContactSolver& solver;          // SolverKind::kJacobi
  SoftStepSolver& soft_solver;    // SolverKind::kSoftStep
  StepScratch& scratch;
  StepStats& stats;
  uint64_t& steps_since_reorder;
  bool& frozen;                   // every dynamic body asleep, no kinematic one moving (sleep stage)

  // Handed from the bounds stage to the broad phase.
  kernels::AabbSoA boxes{};
  kernels::BoundsSummary summary{};
  // Handed from the sleep stage to the solver: the inverse masses it sees.
  const float* solver_inv_mass = nullptr;
};

/// The broad phase sees each body's motion over the step: asked for, or continuous
/// collision on (WorldDesc::ccd).
inline bool swept_step(const WorldDesc& d) { return d.swept_bounds || d.ccd.mode != ContinuousMode::kOff; }

/// The stages, in step order (host/pipeline/step.cpp).
Status reorder_bodies_stage(StepContext& ctx);
Status integrate_velocities_stage(StepContext& ctx);
Status bounds_stage(StepContext& ctx);
Status broad_phase_stage(StepContext& ctx);
Status narrow_phase_stage(StepContext& ctx);
Status speculative_contacts_stage(StepContext& ctx);
Status sleep_stage(StepContext& ctx);
Status solve_velocities_stage(StepContext& ctx);
Status integrate_positions_stage(StepContext& ctx);
Status correct_positions_stage(StepContext& ctx);

/// StepStats::manifolds, contacts and plane_contacts of ctx.contacts (pair order, the
/// plane pairs after the body pairs); kCapacityExceeded past 2^31 - 1 points.
Status count_contacts(StepContext& ctx);
/// Zeroes the force and torque accumulators (World::apply_forces) once a step used them.
void clear_forces(StepContext& ctx);

/// The kernels' view of a store's rigid fields (kRigid must be on).
kernels::RigidBodies rigid_view(BodyStore& s);

/// Permutes body storage into the broad phase's spatial order of the last step (the
/// reorder stage; also what WorldDesc::reorder_interval triggers).
void reorder_bodies(StepContext& ctx);

}  // namespace impact::host
