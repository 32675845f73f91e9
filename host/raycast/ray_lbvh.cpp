#include "host/raycast/ray_lbvh.h"

#include <limits>

namespace impact::host {

namespace {
constexpr kernels::PairFilter kNoFilter{nullptr, nullptr, nullptr};
}  // namespace

RayLbvh::RayLbvh() {
  // update() then always refits (never rebuilds on its own): refit() below.
  LbvhOptions o;
  o.update = LbvhUpdate::kRefit;
  o.max_refits = std::numeric_limits<uint32_t>::max();
  lbvh_.set_options(o);
}

void RayLbvh::build(const Executor& exec, kernels::AabbSoA boxes, uint32_t n) {
  // n < kLbvhMaxLeaves is the caller's precondition, the only way build fails.
  (void)lbvh_.build(exec, boxes, kNoFilter, n);
}

void RayLbvh::refit(const Executor& exec, kernels::AabbSoA boxes) {
  (void)lbvh_.update(exec, boxes, kNoFilter, lbvh_.size());
}

kernels::RayTree RayLbvh::tree() const {
  const kernels::LbvhView v = lbvh_.view();
  return {v.nodes, v.leaves, lbvh_.size()};
}

}  // namespace impact::host
