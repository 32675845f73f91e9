// Host driver of the sweep-and-prune kernels (kernels/broadphase/sap.h); see
// docs/sap.md. Same contract as GridBroadPhase: given n boxes (SoA) and an
// optional filter, replace *out with every pair of overlapping boxes (a < b)
// that passes the filter, in an order that is the same bytes for every backend
// and thread count.
#pragma once

#include <cstdint>
#include <vector>

#include "host/buffer.h"
#include "host/parallel.h"
#include "host/radix_sort.h"
#include "impact/status.h"
#include "kernels/broadphase/bounds.h"
#include "kernels/broadphase/sap.h"
#include "kernels/common/pair.h"

namespace impact::host {

struct SapOptions {
  /// Reuse the last call's sorted order when n is unchanged (coherent scenes):
  /// refresh the keys in that order and repair it by insertion sort.
  bool incremental = true;
  /// The insertion sort gives up, and a full radix sort runs, once its element
  /// shifts exceed max_shifts_per_box * n (measured: docs/sap.md).
  double max_shifts_per_box = 1.0;
  /// While incremental, the sweep axis changes only when another axis's centre
  /// variance exceeds the current one's by this factor (a new axis needs a full sort).
  double axis_switch_ratio = 2.0;
};

/// What the last call did (for benchmarks, tests and diagnostics).
struct SapInfo {
  uint32_t axis = 0;          ///< sweep axis (0 = x, 1 = y, 2 = z)
  double variance[3] = {0, 0, 0};  ///< of box centres per axis, m^2
  bool tried_incremental = false;  ///< the insertion-sort path ran
  bool resorted = false;      ///< a full radix sort ran (from scratch or fallback)
  uint64_t shifts = 0;        ///< insertion-sort element shifts (> limit when it gave up)
};

class SapBroadPhase {
 public:
  SapBroadPhase() = default;
  explicit SapBroadPhase(const SapOptions& options) : options_(options) {}

  /// Sorts boxes[0, n) along the sweep axis from scratch (copies them into sorted
  /// order; the spans need not outlive the call).
  void build(const Executor& exec, kernels::AabbSoA boxes, kernels::PairFilter filter, uint32_t n);
  /// Like build, but reuses the last sorted order when n is unchanged and
  /// options().incremental (insertion sort, with the full sort as fallback).
  void update(const Executor& exec, kernels::AabbSoA boxes, kernels::PairFilter filter, uint32_t n);
  /// Every overlapping pair of the last build/update (the sweep).
  Status pairs(const Executor& exec, Buffer<kernels::Pair>* out);
  /// update + pairs. `summary` is accepted for interface parity with
  /// GridBroadPhase and unused: the axis comes from centre variances.
  Status find_pairs(const Executor& exec, kernels::AabbSoA boxes, kernels::PairFilter filter,
                    uint32_t n, Buffer<kernels::Pair>* out,
                    const kernels::BoundsSummary* summary = nullptr);

  const SapInfo& info() const { return info_; }
  const SapOptions& options() const { return options_; }
  void set_options(const SapOptions& options) { options_ = options; }
  /// Forgets the sorted order: the next call sorts from scratch.
  void reset() { have_order_ = false; }
  /// Boxes of the last build/update.
  uint32_t size() const { return last_n_; }
  /// The sorted boxes of the last build/update (n = 0 when fewer than 2 boxes).
  kernels::SapView view() const;

  /// Original box indices in sorted (sweep-axis min, index) order of the last call
  /// with n >= 2; null otherwise.
  const uint32_t* sorted_index() const { return have_order_ ? index_.data() : nullptr; }

  static constexpr uint32_t kKeyGrain = 1u << 14;   // boxes per chunk in streaming passes
  static constexpr uint32_t kPairGrain = 1u << 11;  // query slots per chunk in the sweep

 private:
  void sort(const Executor& exec, kernels::AabbSoA boxes, kernels::PairFilter filter, uint32_t n);

  SapOptions options_;
  SapInfo info_;
  bool filtered_ = false;
  RadixSorter sorter_;
  Buffer<uint64_t> keys_;  // sorted keys of the last call: mapped min << 32 | index
  bool have_order_ = false;
  uint32_t last_n_ = 0;
  uint32_t last_axis_ = 0;
  Buffer<float> min_[3], max_[3];
  Buffer<uint32_t> index_;
  Buffer<uint32_t> layer_, mask_;
  Buffer<uint8_t> static_;
  Buffer<kernels::SapMoments> partial_moments_;
  Buffer<uint64_t> chunk_offsets_;
  std::vector<Buffer<kernels::Pair>> chunk_pairs_;
};

}  // namespace impact::host
