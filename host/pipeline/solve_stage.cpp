// The solve stages: the step's contact manifolds through host::ContactSolver
// (host/solver/contact_solver.h): the velocity solve before the positions move, the
// position correction after.
#include "host/pipeline/step_context.h"

namespace impact::host {

Status solve_velocities_stage(StepContext& ctx) {
  ctx.solver.solve_velocities(ctx.exec, ctx.desc.solver, ctx.contacts, ctx.bodies, ctx.planes.restitution.data());
  return Status();
}

Status correct_positions_stage(StepContext& ctx) {
  ctx.solver.correct_positions(ctx.exec, ctx.desc.solver, ctx.contacts, ctx.bodies, ctx.dt);
  return Status();
}

}  // namespace impact::host
