// The sleep stage (SolverDesc::sleep, kSoftStep only), between the narrow phase and
// the solve: timers from the velocities the last step left, the islands of this step's
// manifolds, and per island asleep or awake (kernels/solver/islands.h). An island
// wakes in the same step a contact joins it to an awake body, before the solver runs;
// a sleeping one gets zero velocities and reaches the solver with zero inverse masses
// (ctx.solver_inv_mass), so it neither moves nor is solved. When every dynamic body
// sleeps and no kinematic body moves, ctx.frozen tells the next steps to skip their
// stages (WorldImpl::step) until a call wakes a body. kJacobi, or sleep off: every
// body is awake. Cost: one parallel pass over the bodies for the timers and one for
// the solver's masses, and a serial union-find, O(manifolds + bodies).
#include <cstring>

#include "host/pipeline/step_context.h"
#include "kernels/solver/islands.h"

namespace impact::host {
namespace {

constexpr uint32_t kBodyGrain = 1u << 14;

}  // namespace

Status sleep_stage(StepContext& ctx) {
  BodyStore& s = ctx.bodies;
  const SolverDesc& sd = ctx.desc.solver;
  const auto n = static_cast<uint32_t>(s.size());
  ctx.solver_inv_mass = nullptr;
  ctx.frozen = false;
  if (!sd.sleep || sd.kind != SolverKind::kSoftStep) {
    std::memset(s.asleep.data(), 0, n);
    return Status();
  }
  const bool rot = s.on(FieldSet::kRigid);
  const float* wx = rot ? s.wx.data() : nullptr;
  const float* wy = rot ? s.wy.data() : nullptr;
  const float* wz = rot ? s.wz.data() : nullptr;
  ctx.exec.for_each_chunk(n, kBodyGrain, [&](uint32_t b, uint32_t e, uint32_t) {
    kernels::update_sleep_timers(ctx.dt, sd.sleep_speed, s.inv_mass.data(), s.radius.data(), s.vel_x.data(),
                                 s.vel_y.data(), s.vel_z.data(), wx, wy, wz, s.asleep.data(), s.sleep_time.data(),
                                 {b, e});
  });
  const kernels::IslandArrays ia{s.inv_mass.data(), s.vel_x.data(), s.vel_y.data(), s.vel_z.data(),
                                 wx,                wy,              wz,
                                 scratch(ctx.scratch.island_parent, n), scratch(ctx.scratch.kept_awake, n)};
  kernels::find_islands(ctx.contacts.view(), static_cast<uint32_t>(ctx.contacts.manifolds), n, ia);
  const uint32_t asleep = kernels::decide_sleep(
      sd.sleep_time, n, ia, s.vel_x.data(), s.vel_y.data(), s.vel_z.data(), rot ? s.wx.data() : nullptr,
      rot ? s.wy.data() : nullptr, rot ? s.wz.data() : nullptr, s.sleep_time.data(),
      scratch(ctx.scratch.island_min, n), s.asleep.data());
  ctx.stats.asleep_bodies = asleep;
  if (asleep == 0) return Status();
  float* m = scratch(ctx.scratch.solver_inv_mass, n);
  ctx.exec.for_each_chunk(n, kBodyGrain, [&](uint32_t b, uint32_t e, uint32_t) {
    for (uint32_t i = b; i < e; ++i) m[i] = s.asleep[i] ? 0.0f : s.inv_mass[i];
  });
  ctx.solver_inv_mass = m;
  // Frozen: no awake dynamic body, no moving kinematic one.
  bool frozen = true;
  for (uint32_t i = 0; i < n && frozen; ++i) {
    if (s.inv_mass[i] > 0.0f) {
      frozen = s.asleep[i] != 0;
    } else {
      frozen = s.vel_x[i] == 0.0f && s.vel_y[i] == 0.0f && s.vel_z[i] == 0.0f &&
               (!rot || (s.wx[i] == 0.0f && s.wy[i] == 0.0f && s.wz[i] == 0.0f));
    }
  }
  ctx.frozen = frozen;
  return Status();
}

}  // namespace impact::host
