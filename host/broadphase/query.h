// Host drivers of the batched proximity queries (kernels/broadphase/query.h: AABB,
// sphere and point queries) over each broad-phase structure as last built. Rules,
// output order and cost per structure: docs/broadphase.md, "Queries".
//
// Passes: (LBVH and sweep-and-prune, large batches: a spatial processing order of the
// queries, by radix-sorted keys); one chunk of processing positions per task, each
// into its own hit buffer (grown and rerun when a chunk finds more hits than it has
// room for, so nothing is dropped); then an exclusive scan (of the chunk totals, or of
// the per-query counts when reordered), and per chunk the query offsets and a copy of
// its hits to their positions. Each query's hits are sorted by box index inside the
// kernel, so the CSR bytes do not depend on the structure, the processing order, the
// chunking, the backend or the thread count.
#pragma once

#include <cstdint>
#include <vector>

#include "host/broadphase/broadphase.h"
#include "host/broadphase/lbvh.h"
#include "host/broadphase/sap.h"
#include "host/buffer.h"
#include "host/parallel.h"
#include "host/radix_sort.h"
#include "impact/broadphase.h"
#include "impact/status.h"
#include "kernels/broadphase/bounds.h"
#include "kernels/broadphase/query.h"

namespace impact::host {

/// n queries of one shape (SoA arrays that outlive the call; validated: finite,
/// min <= max, radius >= 0, |values| <= 1e18).
struct QueryBatch {
  kernels::QueryView view;
  uint32_t n;
};

/// Validates a public batch (impact/broadphase.h) and views it as a QueryBatch:
/// spans of equal length (mask empty or one per query), at most 2^32 - 1 queries,
/// finite values of magnitude <= 1e18, min <= max, radius >= 0. Messages start with
/// `what` and name the query index and field.
Status make_batch(const AabbQueries& q, const char* what, QueryBatch* out);
Status make_batch(const SphereQueries& q, const char* what, QueryBatch* out);
Status make_batch(const PointQueries& q, const char* what, QueryBatch* out);

/// Runs query batches; keeps its scratch (per-chunk hit buffers) between calls, so
/// steady-state calls allocate only when the outputs grow.
///
/// Output (each call): offsets[n + 1] and hits[offsets[n]]: query i's hits are
/// hits[offsets[i], offsets[i + 1]), box indices ascending. On error neither vector is
/// touched. More than 2^32 - 1 hits in one batch is kCapacityExceeded, naming the count.
class BroadPhaseQuery {
 public:
  /// The grid (single or hierarchical) as last built. A grid built over one box keeps
  /// no copy of it: that case is kInvalidArgument (query the box by brute force; the
  /// BroadPhaseStage does).
  Status query(const Executor& exec, const GridBroadPhase& grid, const QueryBatch& q,
               std::vector<uint32_t>* offsets, std::vector<uint32_t>* hits);
  /// The LBVH as last built, updated or refitted (any n, 0 and 1 included).
  Status query(const Executor& exec, LbvhBroadPhase& lbvh, const QueryBatch& q,
               std::vector<uint32_t>* offsets, std::vector<uint32_t>* hits);
  /// Sweep-and-prune as last built or updated. One box (or reset()): kInvalidArgument,
  /// as the grid.
  /// Costs an extra O(n) pass per call (the largest extent on the sweep axis).
  Status query(const Executor& exec, const SapBroadPhase& sap, const QueryBatch& q,
               std::vector<uint32_t>* offsets, std::vector<uint32_t>* hits);
  /// Brute force over the copies of the last build (any n).
  Status query(const Executor& exec, const BruteForceBroadPhase& brute_force, const QueryBatch& q,
               std::vector<uint32_t>* offsets, std::vector<uint32_t>* hits);
  /// Brute force over a caller's boxes [0, n); layer null = unfiltered.
  Status query(const Executor& exec, kernels::AabbSoA boxes, const uint32_t* layer, uint32_t n,
               const QueryBatch& q, std::vector<uint32_t>* offsets, std::vector<uint32_t>* hits);

  /// Queries per chunk for a batch of n (a function of n alone; the bytes do not
  /// depend on it anyway, since every query's hits are sorted).
  static uint32_t grain(uint32_t n);
  static constexpr uint64_t kMaxHits = 0xffffffffull;
  /// LBVH and sweep-and-prune batches of at least kReorderMinQueries queries over at
  /// least kReorderMinBoxes boxes run in a spatial order (kernels/broadphase/query.h,
  /// "Order"): a radix sort of n keys buys cache reuse between consecutive queries.
  /// The grid gains nothing measurable from it (its rows are short and local).
  static constexpr uint32_t kReorderMinQueries = 1024;
  static constexpr uint32_t kReorderMinBoxes = 1u << 15;
  static constexpr uint32_t kKeyGrain = 1u << 14;  ///< queries per chunk, order keys

 private:
  enum class SortBy { kMorton, kSweepAxis };
  /// find(begin, end, out_count, out_hits, capacity) -> hits of processing positions
  /// [begin, end); order (null = identity) maps positions to queries.
  template <class Find>
  Status run(const Executor& exec, uint32_t n, const uint32_t* order, const char* what, Find&& find,
             std::vector<uint32_t>* offsets, std::vector<uint32_t>* hits);
  /// The batch's processing order: Morton order of the query centres in [lo, hi], or
  /// order of the query min on the sweep axis `axis` (ties by query index).
  const uint32_t* spatial_order(const Executor& exec, const QueryBatch& q, SortBy by, const float lo[3],
                                const float hi[3], uint32_t axis);

  Buffer<uint32_t> counts_;
  Buffer<uint64_t> chunk_offsets_, scan_partials_;
  std::vector<Buffer<uint32_t>> chunk_hits_;
  Buffer<double> partial_extent_;
  RadixSorter sorter_;
  Buffer<uint64_t> order_keys_;
  Buffer<uint32_t> order_;
};

}  // namespace impact::host
