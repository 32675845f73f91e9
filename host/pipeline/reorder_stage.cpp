// The reorder stage: every WorldDesc::reorder_interval steps, body storage is permuted
// into the broad phase's spatial order of the last step (grid cells or Morton order),
// so bodies close in space are close in memory and every later pass streams better.
// Every array of the body field table moves (host/body_store.h); handles keep pointing
// at their bodies, and the solver's warm-start cache is renumbered. Slots change,
// results do not (the state hash is taken in slot order, so it changes with them).
// Cost: one gather and one copy per body array, a sort of last step's contact keys.
#include <cstring>

#include "host/pipeline/step_context.h"
#include "kernels/common/permute.h"

namespace impact::host {
namespace {

constexpr uint32_t kBodyGrain = 1u << 14;

}  // namespace

void reorder_bodies(StepContext& ctx) {
  const uint32_t n = static_cast<uint32_t>(ctx.bodies.size());
  if (ctx.broad_phase.size() != n || n < 2) return;
  StepScratch& sc = ctx.scratch;
  uint32_t* p = scratch(sc.perm, n);
  if (!ctx.broad_phase.spatial_order(ctx.exec, p)) return;
  uint32_t* inv = scratch(sc.inv_perm, n);
  ctx.exec.for_each_chunk(n, kBodyGrain, [&](uint32_t b, uint32_t e, uint32_t) {
    kernels::invert_permutation(p, inv, {b, e});
  });
  auto permute = [&](auto& v, auto& tmp) {
    auto* dst = scratch(tmp, n);
    ctx.exec.for_each_chunk(n, kBodyGrain, [&](uint32_t b, uint32_t e, uint32_t) {
      kernels::gather(v.data(), p, dst, {b, e});
    });
    ctx.exec.for_each_chunk(n, kBodyGrain, [&](uint32_t b, uint32_t e, uint32_t) {
      std::memcpy(v.data() + b, dst + b, sizeof(v[0]) * (e - b));
    });
  };
  for_each_body_array(ctx.bodies, [&](auto& v) {
    using T = std::remove_reference_t<decltype(v[0])>;
    if constexpr (std::is_same_v<T, float>) {
      permute(v, sc.tmp_f32);
    } else if constexpr (std::is_same_v<T, uint32_t>) {
      permute(v, sc.tmp_u32);
    } else if constexpr (std::is_same_v<T, uint8_t>) {
      permute(v, sc.tmp_u8);
    } else {
      static_assert(std::is_same_v<T, BodyHandle>);
      permute(v, sc.tmp_handle);
    }
  });
  const Buffer<BodyHandle>& handles = ctx.bodies.handle;
  for (uint32_t i = 0; i < n; ++i) ctx.body_handles.rebind(handles[i].index, i);
  // Last step's contact keys name slots: renumber them.
  ctx.solver.remap_bodies(ctx.exec, inv, n);
  ctx.soft_solver.remap_bodies(ctx.exec, inv, n);
  // Results of the last step name old slots; so does a coherent structure's state.
  ctx.broad_phase.invalidate();
  ctx.pairs.clear();
  ctx.contacts.clear();
}

Status reorder_bodies_stage(StepContext& ctx) {
  if (ctx.desc.reorder_interval > 0 && ++ctx.steps_since_reorder >= ctx.desc.reorder_interval) {
    ctx.steps_since_reorder = 0;
    reorder_bodies(ctx);
  }
  return Status();
}

}  // namespace impact::host
