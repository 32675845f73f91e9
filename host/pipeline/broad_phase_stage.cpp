// The broad-phase stage: the bounds stage's boxes through the world's structure
// (host/broadphase/stage.h: grid, LBVH, sweep-and-prune or brute force), filtered by
// collision layers and masks and by "both static", into the step's body pairs (i < j,
// a deterministic order). Also WorldImpl::prepare_queries, which brings the same
// structure up to the bodies' current boxes for World::query_*.
#include "host/pipeline/step_context.h"
#include "host/world_impl.h"
#include "kernels/broadphase/bounds.h"

namespace impact {
namespace host {

Status broad_phase_stage(StepContext& ctx) {
  const BodyStore& s = ctx.bodies;
  const auto n = static_cast<uint32_t>(s.size());
  const kernels::PairFilter filter{s.layer.data(), s.mask.data(), s.is_static.data()};
  // Fails only with more pairs than 32-bit indices can hold: never drops them silently.
  if (Status st = ctx.broad_phase.find_pairs(ctx.exec, ctx.boxes, filter, n, &ctx.pairs, &ctx.summary); !st.ok())
    return st;
  ctx.stats.pairs = ctx.pairs.size();
  return Status();
}

}  // namespace host

Status WorldImpl::prepare_queries() {
  if (queries_fresh && broad_phase.built()) return Status();
  const auto n = static_cast<uint32_t>(bodies.size());
  const host::BodyStore& s = bodies;
  host::Buffer<float>* box = scratch.box;
  const kernels::AabbSoAOut out{host::scratch(box[0], n), host::scratch(box[1], n), host::scratch(box[2], n),
                                host::scratch(box[3], n), host::scratch(box[4], n), host::scratch(box[5], n)};
  exec.for_each_chunk(n, 1u << 14, [&](uint32_t b, uint32_t e, uint32_t) {
    kernels::sphere_bounds(s.pos_x.data(), s.pos_y.data(), s.pos_z.data(), s.radius.data(), out, {b, e});
  });
  const kernels::AabbSoA boxes{out.min_x, out.min_y, out.min_z, out.max_x, out.max_y, out.max_z};
  const kernels::PairFilter filter{s.layer.data(), s.mask.data(), s.is_static.data()};
  // Positions are validated at the API and by every step's range check, so the
  // boxes are finite.
  if (Status st = broad_phase.update(exec, boxes, filter, n); !st.ok()) return st;
  queries_fresh = true;
  return Status();
}

}  // namespace impact
