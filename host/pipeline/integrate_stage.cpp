// The integrate stages: semi-implicit (symplectic) Euler in two halves around the
// solve (kernels/integrate/semi_implicit_euler.h): velocities take gravity before the
// collision stages, positions move with the solved velocities after them. With
// WorldDesc::interpolation the positions the step starts from are kept first
// (World::interpolated_positions). Bodies that can rotate (the kRigid field set) take
// kernels/integrate/rigid_euler.h instead, with the force accumulators of
// World::apply_forces (cleared once used), damping and gravity scales when those
// field sets are on. Cost: one streaming pass per half. With SolverKind::kSoftStep
// both halves are the solver's (it integrates by substeps) and only the interpolation
// copy runs here.
#include <cstring>

#include "host/pipeline/step_context.h"
#include "kernels/integrate/rigid_euler.h"
#include "kernels/integrate/semi_implicit_euler.h"

namespace impact::host {
namespace {

constexpr uint32_t kBodyGrain = 1u << 14;

}  // namespace

kernels::RigidBodies rigid_view(BodyStore& s) {
  return {s.vel_x.data(), s.vel_y.data(), s.vel_z.data(), s.wx.data(),  s.wy.data(),  s.wz.data(),
          s.pos_x.data(), s.pos_y.data(), s.pos_z.data(), s.qx.data(),  s.qy.data(),  s.qz.data(),
          s.qw.data(),    s.inv_mass.data(), s.iix.data(), s.iiy.data(), s.iiz.data(), s.pqx.data(),
          s.pqy.data(),   s.pqz.data(),  s.pqw.data(),  s.cx.data(),  s.cy.data(),  s.cz.data()};
}

Status integrate_velocities_stage(StepContext& ctx) {
  BodyStore& s = ctx.bodies;
  const auto n = static_cast<uint32_t>(s.size());
  if (s.on(FieldSet::kInterpolation)) {
    ctx.exec.for_each_chunk(n, kBodyGrain, [&](uint32_t b, uint32_t e, uint32_t) {
      const size_t bytes = sizeof(float) * (e - b);
      std::memcpy(s.prev_x.data() + b, s.pos_x.data() + b, bytes);
      std::memcpy(s.prev_y.data() + b, s.pos_y.data() + b, bytes);
      std::memcpy(s.prev_z.data() + b, s.pos_z.data() + b, bytes);
    });
  }
  if (ctx.desc.solver.kind == SolverKind::kSoftStep) return Status();  // the solver integrates, by substeps
  const bool forces = s.on(FieldSet::kForces), damping = s.on(FieldSet::kDamping);
  if (!s.on(FieldSet::kRigid) && !forces && !damping) {
    const kernels::Vec3f g{ctx.desc.gravity.x(), ctx.desc.gravity.y(), ctx.desc.gravity.z()};
    ctx.exec.for_each_chunk(n, kBodyGrain, [&](uint32_t b, uint32_t e, uint32_t) {
      kernels::integrate_velocities(ctx.dt, g, s.inv_mass.data(), s.vel_x.data(), s.vel_y.data(), s.vel_z.data(),
                                    {b, e});
    });
    return Status();
  }
  // (World keeps kRigid on whenever forces or damping are.)
  const kernels::RigidBodies rb = rigid_view(s);
  const kernels::BodyForces fv{s.fx.data(), s.fy.data(), s.fz.data(), s.tx.data(), s.ty.data(), s.tz.data()};
  const kernels::BodyDamping dv{s.linear_damping.data(), s.angular_damping.data(), s.gravity_scale.data()};
  const kernels::Vec3 g{ctx.desc.gravity.x(), ctx.desc.gravity.y(), ctx.desc.gravity.z()};
  ctx.exec.for_each_chunk(n, kBodyGrain, [&](uint32_t b, uint32_t e, uint32_t) {
    kernels::integrate_rigid_velocities(ctx.dt, g, ctx.desc.gyroscopic, rb, forces ? &fv : nullptr,
                                        damping ? &dv : nullptr, {b, e});
  });
  if (forces) clear_forces(ctx);
  return Status();
}

void clear_forces(StepContext& ctx) {
  BodyStore& s = ctx.bodies;
  ctx.exec.for_each_chunk(s.size(), kBodyGrain, [&](uint32_t b, uint32_t e, uint32_t) {
    for (auto* v : {&s.fx, &s.fy, &s.fz, &s.tx, &s.ty, &s.tz}) std::memset(v->data() + b, 0, sizeof(float) * (e - b));
  });
}

Status integrate_positions_stage(StepContext& ctx) {
  BodyStore& s = ctx.bodies;
  const auto n = static_cast<uint32_t>(s.size());
  if (ctx.desc.solver.kind == SolverKind::kSoftStep) return Status();  // moved by the solver's substeps
  if (s.on(FieldSet::kRigid)) {
    const kernels::RigidBodies rb = rigid_view(s);
    ctx.exec.for_each_chunk(n, kBodyGrain, [&](uint32_t b, uint32_t e, uint32_t) {
      kernels::integrate_rigid_positions(ctx.dt, rb, {b, e});
    });
    return Status();
  }
  ctx.exec.for_each_chunk(n, kBodyGrain, [&](uint32_t b, uint32_t e, uint32_t) {
    kernels::integrate_positions(ctx.dt, s.vel_x.data(), s.vel_y.data(), s.vel_z.data(), s.pos_x.data(),
                                 s.pos_y.data(), s.pos_z.data(), {b, e});
  });
  return Status();
}

}  // namespace impact::host
