// WorldImpl: the state behind impact::World (bodies, planes, shapes, handles, time)
// and the units its step keeps between steps. step() runs the stage list of
// host/pipeline/step.cpp over a host::StepContext made from these members.
#pragma once

#include <cstdint>
#include <span>

#include "host/body_store.h"
#include "host/broadphase/stage.h"
#include "host/buffer.h"
#include "host/contact_manifolds.h"
#include "host/handle_table.h"
#include "host/parallel.h"
#include "host/pipeline/step_context.h"
#include "host/plane_store.h"
#include "host/solver/contact_solver.h"
#include "impact/world.h"
#include "kernels/common/pair.h"

namespace impact {

class WorldImpl {
 public:
  explicit WorldImpl(const WorldDesc& desc);

  /// One fixed step (the stages of host/pipeline/step.cpp).
  Status step();
  /// The context the stages run on.
  host::StepContext context();
  /// Applies desc's broad-phase settings to the stage (next step builds afresh).
  void configure_broad_phase();
  /// Brings the broad-phase structure up to the bodies' current boxes for queries.
  Status prepare_queries();
  /// Body positions or slots changed: the next query refreshes the structure.
  void positions_changed() { queries_fresh = false; }
  /// Slot indices changed meaning (bodies or planes removed): last step's contact
  /// results and impulses no longer apply; when bodies moved, the broad-phase structure
  /// builds afresh and last step's pairs are gone too.
  void slots_changed(bool bodies_moved);
  void swap_remove_body(uint32_t slot);
  /// Switches the rigid field set on (angular velocity, inertia, centre of mass),
  /// giving the dynamic bodies that exist their inertia.
  void enable_rigid();
  /// Wakes the bodies in `slots` (their sleep timers restart) and every asleep body that
  /// shares a last-step manifold with one of them (a body resting on a moved or removed
  /// one); their islands wake in the next step's sleep stage. Cost: O(slots), plus one
  /// pass over the last step's manifolds while any body sleeps.
  void wake(std::span<const uint32_t> slots);
  /// Wakes every body.
  void wake_all();

  WorldDesc desc;
  host::Executor exec;
  ShapeSet shapes;
  uint32_t shaped_count = 0;  // bodies with a shape: the step runs the general narrow phase
  host::BodyStore bodies;
  host::PlaneStore planes;
  host::HandleTable body_handles;
  host::HandleTable plane_handles;

  double accumulator = 0.0;  // s, in double so long runs keep sub-step precision
  float alpha = 0.0f;
  StepStats last;
  bool queries_fresh = false;
  uint64_t steps_since_reorder = 0;
  bool frozen = false;  // every dynamic body asleep: step() skips its stages

  // Kept from step to step.
  host::BroadPhaseStage broad_phase;
  host::Buffer<kernels::Pair> pairs;  // the last step's broad-phase pairs
  host::NarrowStage narrow;
  host::ContactManifolds contacts;    // the last step's manifolds
  host::ContactSolver solver;          // SolverKind::kJacobi
  host::SoftStepSolver soft_solver;    // SolverKind::kSoftStep
  host::StepScratch scratch;
};

}  // namespace impact
