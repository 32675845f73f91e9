#include "host/broadphase/sap.h"

#include <algorithm>

#include "host/broadphase/broadphase.h"
#include "host/scan.h"

namespace impact::host {
namespace {

constexpr uint64_t kMaxPairs = 0xffffffffull;  // kernels index pairs with uint32

// Centre variance per axis: one partial per chunk, combined in chunk order, in
// double, shifted by box 0's centre so far-from-origin scenes keep their digits.
void centre_variance(const Executor& exec, kernels::AabbSoA boxes, uint32_t n,
                     Buffer<kernels::SapMoments>& partials, double out[3]) {
  const double shift[3] = {0.5 * (static_cast<double>(boxes.min_x[0]) + boxes.max_x[0]),
                           0.5 * (static_cast<double>(boxes.min_y[0]) + boxes.max_y[0]),
                           0.5 * (static_cast<double>(boxes.min_z[0]) + boxes.max_z[0])};
  constexpr uint32_t kGrain = SapBroadPhase::kKeyGrain;
  const uint32_t chunks = chunk_count(n, kGrain);
  kernels::SapMoments* part = scratch(partials, chunks);
  exec.for_each_chunk(n, kGrain, [&](uint32_t b, uint32_t e, uint32_t c) {
    part[c] = kernels::sap_moments(boxes, shift, {b, e});
  });
  double sum[3] = {0, 0, 0}, sum_sq[3] = {0, 0, 0};
  for (uint32_t c = 0; c < chunks; ++c)
    for (int a = 0; a < 3; ++a) {
      sum[a] += part[c].sum[a];
      sum_sq[a] += part[c].sum_sq[a];
    }
  for (int a = 0; a < 3; ++a) {
    const double mean = sum[a] / n;
    out[a] = std::max(0.0, sum_sq[a] / n - mean * mean);
  }
}

}  // namespace

Status SapBroadPhase::find_pairs(const Executor& exec, kernels::AabbSoA boxes,
                                 kernels::PairFilter filter, uint32_t n, Buffer<kernels::Pair>* out,
                                 const kernels::BoundsSummary* /*summary*/) {
  update(exec, boxes, filter, n);
  return pairs(exec, out);
}

void SapBroadPhase::build(const Executor& exec, kernels::AabbSoA boxes, kernels::PairFilter filter,
                          uint32_t n) {
  have_order_ = false;
  sort(exec, boxes, filter, n);
}

void SapBroadPhase::update(const Executor& exec, kernels::AabbSoA boxes, kernels::PairFilter filter,
                           uint32_t n) {
  sort(exec, boxes, filter, n);
}

void SapBroadPhase::sort(const Executor& exec, kernels::AabbSoA boxes, kernels::PairFilter filter,
                         uint32_t n) {
  info_ = SapInfo{};
  filtered_ = filter.layer != nullptr;
  if (n < 2) {
    have_order_ = false;
    last_n_ = n;
    return;
  }

  // 1. Sweep axis: greatest centre variance (ties: lowest axis). While the last
  //    order can be reused, keep its axis unless another is clearly better.
  centre_variance(exec, boxes, n, partial_moments_, info_.variance);
  uint32_t best = 0;
  for (uint32_t a = 1; a < 3; ++a)
    if (info_.variance[a] > info_.variance[best]) best = a;
  const bool reuse = options_.incremental && have_order_ && last_n_ == n;
  uint32_t axis = best;
  if (reuse && info_.variance[best] <= options_.axis_switch_ratio * info_.variance[last_axis_])
    axis = last_axis_;
  info_.axis = axis;

  // 2. Sorted (mapped min, index) keys: repaired last order, or a full radix sort.
  uint64_t* keys = scratch(keys_, n);
  bool sorted = false;
  if (reuse && axis == last_axis_) {
    exec.for_each_chunk(n, kKeyGrain, [&](uint32_t b, uint32_t e, uint32_t) {
      kernels::sap_rekey(boxes, axis, keys, {b, e});
    });
    const double limit = std::max(0.0, options_.max_shifts_per_box) * n;
    const uint64_t max_shifts = static_cast<uint64_t>(std::min(limit, 1.8e19));
    info_.tried_incremental = true;
    info_.shifts = kernels::sap_insertion_sort(keys, max_shifts, {0, n});
    sorted = info_.shifts <= max_shifts;
  }
  if (!sorted) {
    // Index-ordered keys, so the stable sort on the high half breaks ties by index.
    exec.for_each_chunk(n, kKeyGrain, [&](uint32_t b, uint32_t e, uint32_t) {
      kernels::sap_keys(boxes, axis, keys, {b, e});
    });
    sorter_.sort(exec, keys, n, 32, 64);
    info_.resorted = true;
  }
  have_order_ = true;
  last_n_ = n;
  last_axis_ = axis;

  // 3. Gather into sorted SoA order, plus sentinels.
  const bool filtered = filter.layer != nullptr;
  const size_t slots = static_cast<size_t>(n) + kernels::kSapPad;
  kernels::SapSorted s{{scratch(min_[0], slots), scratch(min_[1], slots), scratch(min_[2], slots)},
                       {scratch(max_[0], slots), scratch(max_[1], slots), scratch(max_[2], slots)},
                       scratch(index_, slots),
                       filtered ? scratch(layer_, slots) : nullptr,
                       filtered ? scratch(mask_, slots) : nullptr,
                       filtered ? scratch(static_, slots) : nullptr};
  exec.for_each_chunk(n, kKeyGrain, [&](uint32_t b, uint32_t e, uint32_t) {
    kernels::sap_gather(keys, boxes, axis, filter, s, {b, e});
  });
  kernels::sap_pad(s, n);
}

kernels::SapView SapBroadPhase::view() const {
  return kernels::SapView{{min_[0].data(), min_[1].data(), min_[2].data()},
                          {max_[0].data(), max_[1].data(), max_[2].data()},
                          index_.data(),
                          filtered_ ? layer_.data() : nullptr,
                          filtered_ ? mask_.data() : nullptr,
                          filtered_ ? static_.data() : nullptr,
                          have_order_ ? last_n_ : 0};
}

Status SapBroadPhase::pairs(const Executor& exec, Buffer<kernels::Pair>* out) {
  out->clear();
  if (!have_order_ || last_n_ < 2) return Status();
  const uint32_t n = last_n_;
  // Sweep: per chunk of query slots into its own buffer, concatenated in order.
  const kernels::SapView view = this->view();
  return chunked_output<kernels::Pair>(
      exec, n, kPairGrain, chunk_pairs_, chunk_offsets_, kMaxPairs, "sweep-and-prune pairs",
      [&](uint32_t b, uint32_t e, kernels::Pair* dst, uint64_t capacity) {
        return kernels::sap_find_pairs(view, dst, capacity, {b, e});
      },
      out);
}

}  // namespace impact::host
