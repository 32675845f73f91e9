// The solve stages. SolverKind::kSoftStep: host::SoftStepSolver solves and integrates
// the whole step (host/solver/soft_step_solver.h), then the force accumulators are
// cleared. kJacobi: host::ContactSolver (host/solver/contact_solver.h), the velocity
// solve before the positions move, the position correction after.
#include "host/pipeline/step_context.h"

namespace impact::host {

Status solve_velocities_stage(StepContext& ctx) {
  if (ctx.desc.solver.kind == SolverKind::kSoftStep) {
    const float* inv_mass = ctx.solver_inv_mass != nullptr ? ctx.solver_inv_mass : ctx.bodies.inv_mass.data();
    ctx.soft_solver.step(ctx.exec, ctx.desc, ctx.contacts, ctx.bodies, ctx.planes, ctx.dt, inv_mass);
    if (ctx.bodies.on(FieldSet::kForces)) clear_forces(ctx);
    return Status();
  }
  ctx.solver.solve_velocities(ctx.exec, ctx.desc.solver, ctx.contacts, ctx.bodies, ctx.planes.restitution.data(),
                              ctx.desc.ccd.mode != ContinuousMode::kOff ? ctx.dt : 0.0f);
  return Status();
}

Status correct_positions_stage(StepContext& ctx) {
  if (ctx.desc.solver.kind == SolverKind::kSoftStep) return Status();  // the relax passes did it
  ctx.solver.correct_positions(ctx.exec, ctx.desc.solver, ctx.contacts, ctx.bodies, ctx.dt);
  return Status();
}

}  // namespace impact::host
