// One fixed step of a World: the stage list. Each stage is a function over the step's
// host::StepContext in its own file of host/pipeline/ (Box2D v3's b2SolverStage idea):
//
//   reorder bodies        every WorldDesc::reorder_interval steps: slots into spatial order
//   integrate velocities  v += g dt                                   (integrate_stage.cpp)
//   bounds                a box per body (swept over the step if asked) (bounds_stage.cpp)
//   broad phase           candidate body pairs                        (broad_phase_stage.cpp)
//   narrow phase          body-plane pairs by the plane filter, then the contact
//                         manifolds of every pair, on the poses the step starts from
//                                                                     (narrow_phase_stage.cpp)
//   speculative contacts  WorldDesc::ccd: one-point contacts across the gaps that could
//                         close within the step                   (speculative_stage.cpp)
//   sleep                 islands; which sleep, which wake           (sleep_stage.cpp)
//   solve velocities      warm start + iterations on the manifolds' points (solve_stage.cpp)
//   integrate positions   x += v dt with the solved velocities        (integrate_stage.cpp)
//   correct positions     iterations on displacements                 (solve_stage.cpp)
//
// Solving velocities before positions move keeps resting contacts from sinking by
// g dt^2 every step. Every pass inside a stage is for_each_chunk over a kernel, and
// variable-size outputs use count -> scan -> write or chunk-local buffers, so results
// are identical for any thread count. A stage that fails ends the step: the bodies
// keep what the earlier stages did, and the step has no contacts. When the last step
// left every dynamic body asleep and nothing has woken one since (WorldImpl::frozen),
// the step runs no stage: nothing would move, and last step's contacts still hold.
#include <chrono>

#include "host/pipeline/step_context.h"
#include "host/world_impl.h"

namespace impact {
namespace {

using Clock = std::chrono::steady_clock;

struct Stage {
  const char* name;
  Status (*run)(host::StepContext&);
  double PassTimes::*time;  ///< where its wall time goes (null: only into total)
};

constexpr Stage kStages[] = {
    {"reorder bodies", &host::reorder_bodies_stage, nullptr},
    {"integrate velocities", &host::integrate_velocities_stage, &PassTimes::integrate},
    {"bounds", &host::bounds_stage, &PassTimes::bounds},
    {"broad phase", &host::broad_phase_stage, &PassTimes::broad_phase},
    {"narrow phase", &host::narrow_phase_stage, &PassTimes::narrow_phase},
    {"speculative contacts", &host::speculative_contacts_stage, &PassTimes::ccd},
    {"sleep", &host::sleep_stage, &PassTimes::solve},
    {"solve velocities", &host::solve_velocities_stage, &PassTimes::solve},
    {"integrate positions", &host::integrate_positions_stage, &PassTimes::integrate},
    {"correct positions", &host::correct_positions_stage, &PassTimes::solve},
};

}  // namespace

host::StepContext WorldImpl::context() {
  return host::StepContext{desc,    exec,        desc.fixed_dt, bodies, body_handles, planes,  shapes,
                           shaped_count, broad_phase, pairs,  narrow, contacts,     solver,  soft_solver, scratch,
                           last,    steps_since_reorder, frozen};
}

Status WorldImpl::step() {
  if (frozen && desc.solver.sleep && desc.solver.kind == SolverKind::kSoftStep) {
    const auto t0 = Clock::now();
    last.ms = PassTimes{};
    last.skipped = true;
    last.ms.total = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
    return Status();
  }
  last = StepStats{};
  positions_changed();  // the step moves bodies (and its structure sees start poses)
  host::StepContext ctx = context();
  const auto t_start = Clock::now();
  auto t = t_start;
  Status status;
  for (const Stage& stage : kStages) {
    status = stage.run(ctx);
    const auto now = Clock::now();
    if (stage.time != nullptr) last.ms.*stage.time += std::chrono::duration<double, std::milli>(now - t).count();
    t = now;
    if (!status.ok()) {
      contacts.clear();
      solver.clear_impulses();
      soft_solver.clear_impulses();
      break;
    }
  }
  last.ms.total = std::chrono::duration<double, std::milli>(Clock::now() - t_start).count();
  return status;
}

}  // namespace impact
