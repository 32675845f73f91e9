#include "host/raycast/ray_lbvh.h"

#include <algorithm>

#include "kernels/bvh/lbvh_refit.h"
#include "kernels/bvh/morton.h"

namespace impact::host {

void RayLbvh::build(const Executor& exec, kernels::AabbSoA boxes, uint32_t n) {
  n_ = n;
  if (n == 0) return;
  const uint32_t chunks = chunk_count(n, kGrain);
  kernels::BoundsSummary* partial = scratch(partial_, chunks);
  exec.for_each_chunk(n, kGrain, [&](uint32_t b, uint32_t e, uint32_t c) {
    partial[c] = kernels::reduce_bounds(boxes, {b, e});
  });
  kernels::BoundsSummary sum = kernels::empty_bounds_summary();
  for (uint32_t c = 0; c < chunks; ++c) sum = kernels::combine(sum, partial[c]);

  double extent = 0.0;
  for (int k = 0; k < 3; ++k)
    extent = std::max(extent, static_cast<double>(sum.hi[k]) - static_cast<double>(sum.lo[k]));
  bits_ = (n > (1u << 24) || extent / 1024.0 > 4.0 * static_cast<double>(sum.max_edge)) ? 63 : 30;
  const kernels::MortonParams mp = kernels::morton_params(sum.lo, sum.hi, bits_ == 30 ? 10 : 21);

  uint64_t* keys = scratch(keys_, n);
  uint32_t* index = scratch(leaf_index_, n);
  uint32_t shift = 0;
  if (bits_ == 30) {
    exec.for_each_chunk(n, kGrain, [&](uint32_t b, uint32_t e, uint32_t) {
      kernels::morton_keys30(mp, boxes, keys, {b, e});
    });
    sorter_.sort(exec, keys, n, 32, 62);
    exec.for_each_chunk(n, kGrain, [&](uint32_t b, uint32_t e, uint32_t) {
      kernels::morton_split_keys(keys, index, {b, e});
    });
    shift = 32;
  } else {
    exec.for_each_chunk(n, kGrain, [&](uint32_t b, uint32_t e, uint32_t) {
      kernels::morton_keys63(mp, boxes, keys, index, {b, e});
    });
    sorter_.sort_kv(exec, keys, index, n, 0, 63);
  }
  scratch(leaves_, n);
  scratch(leaf_parent_, n);
  if (n >= 2) {
    const kernels::LbvhTopology topo{scratch(nodes_, n - 1), scratch(internal_parent_, n - 1),
                                     leaf_parent_.data(), scratch(counters_, n - 1)};
    exec.for_each_chunk(n - 1, kGrain, [&](uint32_t b, uint32_t e, uint32_t) {
      kernels::lbvh_build(keys, shift, n, topo, {b, e});
    });
  } else {
    leaf_parent_[0] = kernels::kInvalidBody;
  }
  refit(exec, boxes);
}

void RayLbvh::refit(const Executor& exec, kernels::AabbSoA boxes) {
  const uint32_t n = n_;
  if (n == 0) return;
  const kernels::LbvhRefitIn in{leaf_index_.data(), n >= 2 ? internal_parent_.data() : nullptr,
                                leaf_parent_.data()};
  const kernels::LbvhRefitOut out{n >= 2 ? nodes_.data() : nullptr, leaves_.data(),
                                  n >= 2 ? counters_.data() : nullptr, nullptr, nullptr, nullptr};
  exec.for_each_chunk(n, kGrain, [&](uint32_t b, uint32_t e, uint32_t) {
    kernels::lbvh_refit(boxes, kernels::PairFilter{nullptr, nullptr, nullptr}, in, out, n, {b, e});
  });
}

}  // namespace impact::host
