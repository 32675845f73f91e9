#include "host/broadphase/lbvh.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "kernels/bvh/lbvh_build_fused.h"
#include "kernels/bvh/lbvh_refit.h"
#include "kernels/bvh/lbvh_traverse.h"

namespace impact::host {
namespace {

constexpr uint64_t kMaxPairs = 0xffffffffull;  // kernels index pairs with uint32

}  // namespace

uint32_t choose_morton_bits(const kernels::BoundsSummary& s, uint32_t n) {
  if (n > (1u << 24)) return 63;
  double max_extent = 0.0;
  for (int k = 0; k < 3; ++k)
    max_extent = std::max(max_extent, static_cast<double>(s.hi[k]) - static_cast<double>(s.lo[k]));
  if (!(max_extent > 0.0)) return 30;
  const double cell30 = max_extent / 1024.0;
  return cell30 > 4.0 * static_cast<double>(s.max_edge) ? 63 : 30;
}

kernels::LbvhView LbvhBroadPhase::view() const {
  return kernels::LbvhView{nodes_.data(),
                           internal_parent_.data(),
                           leaf_parent_.data(),
                           leaves_.data(),
                           filtered_ ? layer_.data() : nullptr,
                           filtered_ ? mask_.data() : nullptr,
                           filtered_ ? static_.data() : nullptr,
                           info_.leaves};
}

Status LbvhBroadPhase::rebuild(const Executor& exec, kernels::AabbSoA boxes, kernels::PairFilter filter,
                               uint32_t n, const kernels::BoundsSummary* summary) {
  info_ = LbvhInfo{};
  info_.rebuilt = true;
  built_ = false;
  if (n > kernels::kLbvhMaxLeaves)
    return Status(StatusCode::kInvalidArgument, "LBVH broad phase: " + std::to_string(n) +
                                                    " boxes exceed the limit of " +
                                                    std::to_string(kernels::kLbvhMaxLeaves));
  info_.leaves = n;
  built_ = true;
  if (n == 0) return Status();

  // 1. Scene bounds and code width.
  const kernels::BoundsSummary sum = summary ? *summary : summarize_bounds(exec, boxes, n, partial_bounds_);
  const uint32_t bits = options_.morton_bits == 30 || options_.morton_bits == 63
                            ? options_.morton_bits
                            : choose_morton_bits(sum, n);
  info_.morton_bits = bits;
  const kernels::MortonParams mp = kernels::morton_params(sum.lo, sum.hi, bits == 30 ? 10 : 21);

  // 2. Keys, sorted. 30-bit: code << 32 | index, sorted on [32, 62). 63-bit: code with
  //    the index as value, sorted on [0, 63). Either way the sorted codes are in keys_
  //    and the build reads them as keys_ >> shift.
  uint64_t* keys = scratch(keys_, n);
  uint32_t* index = scratch(leaf_index_, n);
  uint32_t shift = 0;
  if (bits == 30) {
    exec.for_each_chunk(n, kKeyGrain, [&](uint32_t b, uint32_t e, uint32_t) {
      kernels::morton_keys30(mp, boxes, keys, {b, e});
    });
    sorter_.sort(exec, keys, n, 32, 62);
    exec.for_each_chunk(n, kKeyGrain, [&](uint32_t b, uint32_t e, uint32_t) {
      kernels::morton_split_keys(keys, index, {b, e});
    });
    shift = 32;
  } else {
    exec.for_each_chunk(n, kKeyGrain, [&](uint32_t b, uint32_t e, uint32_t) {
      kernels::morton_keys63(mp, boxes, keys, index, {b, e});
    });
    sorter_.sort_kv(exec, keys, index, n, 0, 63);
  }

  // 3. Hierarchy and bounds in one pass (lbvh_build_fused.h): chunks in parallel, then
  //    the chunk seams in order.
  filtered_ = filter.layer != nullptr;
  const kernels::LbvhFusedIn in{keys, shift, index, pack(exec, boxes, n)};
  const kernels::LbvhFusedOut out{
      {n >= 2 ? scratch(nodes_, n - 1) : nullptr, n >= 2 ? scratch(internal_parent_, n - 1) : nullptr,
       scratch(leaf_parent_, n)},
      {n >= 2 ? nodes_.data() : nullptr, scratch(leaves_, n), filtered_ ? scratch(layer_, n) : nullptr,
       filtered_ ? scratch(mask_, n) : nullptr, filtered_ ? scratch(static_, n) : nullptr},
      n >= 2 ? scratch(slot_, n) : nullptr};
  kernels::LbvhBlocked* blocked = scratch(blocked_, chunk_count(n, kNodeGrain));
  exec.for_each_chunk(n, kNodeGrain, [&](uint32_t b, uint32_t e, uint32_t c) {
    kernels::lbvh_build_fused(boxes, filter, in, out, n, {b, e}, &blocked[c]);
  });
  for (uint32_t c = 1, b = kNodeGrain; b < n; ++c, b += kNodeGrain)
    kernels::lbvh_build_fused_seam(in, out, n, {b, std::min(n, b + kNodeGrain)}, blocked[c]);
  return Status();
}

const kernels::SortedBox* LbvhBroadPhase::pack(const Executor& exec, kernels::AabbSoA boxes, uint32_t n) {
  kernels::SortedBox* packed = scratch(packed_, n);
  exec.for_each_chunk(n, kKeyGrain, [&](uint32_t b, uint32_t e, uint32_t) {
    kernels::lbvh_pack_boxes(boxes, packed, {b, e});
  });
  return packed;
}

void LbvhBroadPhase::refit_bounds(const Executor& exec, kernels::AabbSoA boxes,
                                  kernels::PairFilter filter) {
  const uint32_t n = info_.leaves;
  filtered_ = filter.layer != nullptr;
  const kernels::LbvhRefitIn in{leaf_index_.data(), n >= 2 ? internal_parent_.data() : nullptr,
                                leaf_parent_.data(), pack(exec, boxes, n)};
  const kernels::LbvhRefitOut out{n >= 2 ? nodes_.data() : nullptr,
                                  leaves_.data(),
                                  filtered_ ? scratch(layer_, n) : nullptr,
                                  filtered_ ? scratch(mask_, n) : nullptr,
                                  filtered_ ? scratch(static_, n) : nullptr};
  exec.for_each_chunk(n, kNodeGrain, [&](uint32_t b, uint32_t e, uint32_t) {
    kernels::lbvh_refit(boxes, filter, in, out, n, {b, e});
  });
  // Nodes across chunk seams, chunk by chunk in order (O(depth) each).
  for (uint32_t b = kNodeGrain; b < n; b += kNodeGrain)
    kernels::lbvh_refit_seam(in, out, n, {b, std::min(n, b + kNodeGrain)});
}

Status LbvhBroadPhase::traverse(const Executor& exec, Buffer<kernels::Pair>* out) {
  const uint32_t n = info_.leaves;
  if (n < 2) {
    out->clear();
    return Status();
  }
  const kernels::LbvhView v = view();
  return chunked_output<kernels::Pair>(
      exec, n, kPairGrain, chunk_pairs_, chunk_offsets_, kMaxPairs, "LBVH broad phase pairs",
      [&](uint32_t b, uint32_t e, kernels::Pair* dst, uint64_t capacity) {
        return kernels::lbvh_find_pairs(v, dst, capacity, {b, e});
      },
      out);
}

double LbvhBroadPhase::sah_cost(const Executor& exec) {
  const uint32_t n = info_.leaves;
  if (n == 0) return 0.0;
  const kernels::LbvhView v = view();
  const uint64_t nodes = 2ull * n - 1;
  const uint32_t chunks = chunk_count(nodes, kNodeGrain);
  double* partial = scratch(partial_area_, chunks);
  exec.for_each_chunk(nodes, kNodeGrain, [&](uint32_t b, uint32_t e, uint32_t c) {
    partial[c] = kernels::lbvh_area_sum(v, {b, e});
  });
  double total = 0.0;
  for (uint32_t c = 0; c < chunks; ++c) total += partial[c];
  const double root = kernels::lbvh_area_sum(v, {0, 1});
  return root > 0.0 ? total / root : static_cast<double>(n);
}

Status LbvhBroadPhase::build(const Executor& exec, kernels::AabbSoA boxes, kernels::PairFilter filter,
                             uint32_t n, const kernels::BoundsSummary* summary) {
  const Status s = rebuild(exec, boxes, filter, n, summary);
  if (!s.ok()) return s;
  if (options_.update == LbvhUpdate::kAuto) info_.built_sah = info_.last_sah = sah_cost(exec);
  return Status();
}

Status LbvhBroadPhase::update(const Executor& exec, kernels::AabbSoA boxes, kernels::PairFilter filter,
                              uint32_t n, const kernels::BoundsSummary* summary) {
  const bool can_refit = options_.update != LbvhUpdate::kRebuild && built_ && info_.leaves == n &&
                         n >= 2 && info_.refits_since_build < options_.max_refits;
  if (can_refit) {
    refit_bounds(exec, boxes, filter);
    bool keep = true;
    if (options_.update == LbvhUpdate::kAuto) {
      info_.last_sah = sah_cost(exec);
      keep = info_.last_sah <= options_.refit_sah_limit * info_.built_sah;
    }
    if (keep) {
      info_.rebuilt = false;
      ++info_.refits_since_build;
      return Status();
    }
  }
  return build(exec, boxes, filter, n, summary);
}

Status LbvhBroadPhase::pairs(const Executor& exec, Buffer<kernels::Pair>* out) {
  if (!built_) {
    out->clear();
    return Status();
  }
  return traverse(exec, out);
}

Status LbvhBroadPhase::find_pairs(const Executor& exec, kernels::AabbSoA boxes,
                                  kernels::PairFilter filter, uint32_t n, Buffer<kernels::Pair>* out,
                                  const kernels::BoundsSummary* summary) {
  if (Status s = update(exec, boxes, filter, n, summary); !s.ok()) {
    out->clear();
    return s;
  }
  return pairs(exec, out);
}

Status LbvhBroadPhase::refit(const Executor& exec, kernels::AabbSoA boxes, kernels::PairFilter filter,
                             uint32_t n, Buffer<kernels::Pair>* out) {
  if (!built_ || n != info_.leaves) {
    out->clear();
    return Status(StatusCode::kInvalidArgument,
                  "LBVH refit: " + std::to_string(n) + " boxes, but " +
                      (built_ ? "the tree was built over " + std::to_string(info_.leaves)
                              : std::string("there is no tree yet")) +
                      " (rebuild with find_pairs)");
  }
  if (n == 0) {
    out->clear();
    return Status();
  }
  refit_bounds(exec, boxes, filter);
  info_.rebuilt = false;
  ++info_.refits_since_build;
  return traverse(exec, out);
}

}  // namespace impact::host
