// The integrate stages: semi-implicit (symplectic) Euler in two halves around the
// solve (kernels/integrate/semi_implicit_euler.h): velocities take gravity before the
// collision stages, positions move with the solved velocities after them. With
// WorldDesc::interpolation the positions the step starts from are kept first
// (World::interpolated_positions). Cost: one streaming, vectorised pass per half.
#include <cstring>

#include "host/pipeline/step_context.h"
#include "kernels/integrate/semi_implicit_euler.h"

namespace impact::host {
namespace {

constexpr uint32_t kBodyGrain = 1u << 14;

}  // namespace

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
  const kernels::Vec3f g{ctx.desc.gravity.x(), ctx.desc.gravity.y(), ctx.desc.gravity.z()};
  ctx.exec.for_each_chunk(n, kBodyGrain, [&](uint32_t b, uint32_t e, uint32_t) {
    kernels::integrate_velocities(ctx.dt, g, s.inv_mass.data(), s.vel_x.data(), s.vel_y.data(), s.vel_z.data(),
                                  {b, e});
  });
  return Status();
}

Status integrate_positions_stage(StepContext& ctx) {
  BodyStore& s = ctx.bodies;
  const auto n = static_cast<uint32_t>(s.size());
  ctx.exec.for_each_chunk(n, kBodyGrain, [&](uint32_t b, uint32_t e, uint32_t) {
    kernels::integrate_positions(ctx.dt, s.vel_x.data(), s.vel_y.data(), s.vel_z.data(), s.pos_x.data(),
                                 s.pos_y.data(), s.pos_z.data(), {b, e});
  });
  return Status();
}

}  // namespace impact::host
