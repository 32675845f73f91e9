#include "host/broadphase/query.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <string>

#include "host/scan.h"
#include "kernels/broadphase/grid_query.h"
#include "kernels/broadphase/sap.h"
#include "kernels/broadphase/sap_query.h"
#include "kernels/bvh/lbvh_query.h"
#include "kernels/bvh/morton.h"

namespace impact::host {
namespace {

Status no_boxes_error(const char* what) {
  return Status(StatusCode::kInvalidArgument,
                std::string(what) + ": the structure holds no searchable boxes (built over 1 box, which it "
                                    "keeps no copy of, or reset since); query such boxes by brute force");
}

// Answers a batch against an empty structure: n empty lists.
void no_hits(uint32_t n, std::vector<uint32_t>* offsets, std::vector<uint32_t>* hits) {
  offsets->assign(static_cast<size_t>(n) + 1, 0u);
  hits->clear();
}

// Spans of one batch for validation: values[k] named names[k], all of length n.
struct Fields {
  const std::span<const float>* values[6];
  const char* names[6];
  int count;
};

Status check_fields(const Fields& f, std::span<const uint32_t> mask, const char* what, bool aabb, bool sphere) {
  const size_t n = f.values[0]->size();
  for (int k = 1; k < f.count; ++k)
    if (f.values[k]->size() != n)
      return Status(StatusCode::kSizeMismatch, std::string(what) + ": " + f.names[k] + " has " +
                                                   std::to_string(f.values[k]->size()) + " entries, " + f.names[0] +
                                                   " has " + std::to_string(n));
  if (!mask.empty() && mask.size() != n)
    return Status(StatusCode::kSizeMismatch, std::string(what) + ": mask has " + std::to_string(mask.size()) +
                                                 " entries, expected 0 or " + std::to_string(n));
  if (n > 0xffffffffull)
    return Status(StatusCode::kCapacityExceeded, std::string(what) + ": more than 2^32 - 1 queries");
  for (size_t i = 0; i < n; ++i) {
    for (int k = 0; k < f.count; ++k) {
      const float v = (*f.values[k])[i];
      if (!std::isfinite(v) || std::fabs(v) > 1e18f)
        return Status(StatusCode::kInvalidArgument, std::string(what) + ": query " + std::to_string(i) + " " +
                                                        f.names[k] + " must be finite with magnitude <= 1e18, got " +
                                                        std::to_string(v));
    }
    if (aabb)
      for (int k = 0; k < 3; ++k)
        if ((*f.values[k])[i] > (*f.values[k + 3])[i])
          return Status(StatusCode::kInvalidArgument, std::string(what) + ": query " + std::to_string(i) + " " +
                                                          f.names[k] + " exceeds " + f.names[k + 3] + " (" +
                                                          std::to_string((*f.values[k])[i]) + " > " +
                                                          std::to_string((*f.values[k + 3])[i]) + ")");
    if (sphere && (*f.values[3])[i] < 0.0f)
      return Status(StatusCode::kInvalidArgument, std::string(what) + ": query " + std::to_string(i) +
                                                      " radius must be >= 0, got " +
                                                      std::to_string((*f.values[3])[i]));
  }
  return Status();
}

}  // namespace

Status make_batch(const AabbQueries& q, const char* what, QueryBatch* out) {
  const Fields f{{&q.min_x, &q.min_y, &q.min_z, &q.max_x, &q.max_y, &q.max_z},
                 {"min_x", "min_y", "min_z", "max_x", "max_y", "max_z"},
                 6};
  if (Status s = check_fields(f, q.mask, what, true, false); !s.ok()) return s;
  *out = QueryBatch{kernels::QueryView{kernels::QueryShape::kAabb, q.min_x.data(), q.min_y.data(), q.min_z.data(),
                                       q.max_x.data(), q.max_y.data(), q.max_z.data(), nullptr,
                                       q.mask.empty() ? nullptr : q.mask.data()},
                    static_cast<uint32_t>(q.size())};
  return Status();
}

Status make_batch(const SphereQueries& q, const char* what, QueryBatch* out) {
  const Fields f{{&q.x, &q.y, &q.z, &q.radius, nullptr, nullptr}, {"x", "y", "z", "radius", "", ""}, 4};
  if (Status s = check_fields(f, q.mask, what, false, true); !s.ok()) return s;
  *out = QueryBatch{kernels::QueryView{kernels::QueryShape::kSphere, q.x.data(), q.y.data(), q.z.data(), nullptr,
                                       nullptr, nullptr, q.radius.data(), q.mask.empty() ? nullptr : q.mask.data()},
                    static_cast<uint32_t>(q.size())};
  return Status();
}

Status make_batch(const PointQueries& q, const char* what, QueryBatch* out) {
  const Fields f{{&q.x, &q.y, &q.z, nullptr, nullptr, nullptr}, {"x", "y", "z", "", "", ""}, 3};
  if (Status s = check_fields(f, q.mask, what, false, false); !s.ok()) return s;
  *out = QueryBatch{kernels::QueryView{kernels::QueryShape::kPoint, q.x.data(), q.y.data(), q.z.data(), nullptr,
                                       nullptr, nullptr, nullptr, q.mask.empty() ? nullptr : q.mask.data()},
                    static_cast<uint32_t>(q.size())};
  return Status();
}

uint32_t BroadPhaseQuery::grain(uint32_t n) {
  // About 64 chunks for load balance (queries vary in cost), 16..512 queries each.
  return std::clamp<uint32_t>((n + 63) / 64, 16, 512);
}

template <class Find>
Status BroadPhaseQuery::run(const Executor& exec, uint32_t n, const uint32_t* order, const char* what, Find&& find,
                            std::vector<uint32_t>* offsets, std::vector<uint32_t>* hits) {
  // 1. Per chunk of processing positions: hits into the chunk's own buffer (grown and
  //    rerun when it overflows), counts per query.
  const uint32_t g = grain(n);
  const uint32_t chunks = chunk_count(n, g);
  if (chunk_hits_.size() < chunks) chunk_hits_.resize(chunks);
  uint32_t* counts = scratch(counts_, n);
  uint64_t* off = scratch(chunk_offsets_, static_cast<size_t>(chunks) + 1);
  exec.for_each_chunk(n, g, [&](uint32_t b, uint32_t e, uint32_t c) {
    Buffer<uint32_t>& buf = chunk_hits_[c];
    if (buf.empty()) buf.resize(8ull * g);
    uint64_t k = find(b, e, counts, buf.data(), static_cast<uint64_t>(buf.size()));
    if (k > buf.size()) {
      buf.resize(k + k / 4);
      k = find(b, e, counts, buf.data(), static_cast<uint64_t>(buf.size()));
    }
    off[c] = k;
  });
  const uint64_t total = exclusive_scan_chunks(off, chunks);
  if (total > kMaxHits)
    return Status(StatusCode::kCapacityExceeded, std::string(what) + ": " + std::to_string(total) +
                                                     " hits exceed the limit of " + std::to_string(kMaxHits) +
                                                     " per batch (split the batch)");
  offsets->resize(static_cast<size_t>(n) + 1);
  hits->resize(total);
  uint32_t* o = offsets->data();
  uint32_t* h = hits->data();
  o[n] = static_cast<uint32_t>(total);
  if (order == nullptr) {
    // 2a. Processing order is query order: chunk c's hits go to off[c] as one block.
    exec.for_each_chunk(n, g, [&](uint32_t b, uint32_t e, uint32_t c) {
      uint64_t at = off[c];
      for (uint32_t i = b; i < e; ++i) {
        o[i] = static_cast<uint32_t>(at);
        at += counts[i];
      }
      if (off[c + 1] > off[c])
        std::memcpy(h + off[c], chunk_hits_[c].data(), sizeof(uint32_t) * (off[c + 1] - off[c]));
    });
    return Status();
  }
  // 2b. Reordered: offsets by an exclusive scan of the counts in query order (one
  //     partial per chunk of query indices, combined in order), then each processing
  //     chunk scatters its queries' hit runs to their offsets.
  uint64_t* part = scratch(scan_partials_, static_cast<size_t>(chunks) + 1);
  exec.for_each_chunk(n, g, [&](uint32_t b, uint32_t e, uint32_t c) {
    uint64_t sum = 0;
    for (uint32_t i = b; i < e; ++i) sum += counts[i];
    part[c] = sum;
  });
  exclusive_scan_chunks(part, chunks);
  exec.for_each_chunk(n, g, [&](uint32_t b, uint32_t e, uint32_t c) {
    uint64_t at = part[c];
    for (uint32_t i = b; i < e; ++i) {
      o[i] = static_cast<uint32_t>(at);
      at += counts[i];
    }
  });
  exec.for_each_chunk(n, g, [&](uint32_t b, uint32_t e, uint32_t c) {
    const uint32_t* src = chunk_hits_[c].data();
    for (uint32_t p = b; p < e; ++p) {
      const uint32_t i = order[p];
      if (counts[i] > 0) std::memcpy(h + o[i], src, sizeof(uint32_t) * counts[i]);
      src += counts[i];
    }
  });
  return Status();
}

const uint32_t* BroadPhaseQuery::spatial_order(const Executor& exec, const QueryBatch& q, SortBy by,
                                               const float lo[3], const float hi[3], uint32_t axis) {
  const uint32_t n = q.n;
  // AABB queries by their box; spheres and points by their centre (min = max = centre).
  const kernels::QueryView& v = q.view;
  const bool box = v.shape == kernels::QueryShape::kAabb;
  const kernels::AabbSoA soa{v.x0, v.y0, v.z0, box ? v.x1 : v.x0, box ? v.y1 : v.y0, box ? v.z1 : v.z0};
  uint64_t* keys = scratch(order_keys_, n);
  uint32_t* order = scratch(order_, n);
  const kernels::MortonParams mp = kernels::morton_params(lo, hi, 10);
  exec.for_each_chunk(n, kKeyGrain, [&](uint32_t b, uint32_t e, uint32_t) {
    if (by == SortBy::kMorton) kernels::morton_keys30(mp, soa, keys, {b, e});
    else kernels::sap_keys(soa, axis, keys, {b, e});  // min on the sweep axis
  });
  sorter_.sort(exec, keys, n, 32, by == SortBy::kMorton ? 62 : 64);
  exec.for_each_chunk(n, kKeyGrain, [&](uint32_t b, uint32_t e, uint32_t) {
    kernels::morton_split_keys(keys, order, {b, e});
  });
  return order;
}

Status BroadPhaseQuery::query(const Executor& exec, const GridBroadPhase& grid, const QueryBatch& q,
                              std::vector<uint32_t>* offsets, std::vector<uint32_t>* hits) {
  if (grid.size() == 0) {
    no_hits(q.n, offsets, hits);
    return Status();
  }
  if (grid.size() == 1) return no_boxes_error("grid query");
  kernels::GridView views[kernels::kGridMaxLevels];
  uint32_t count = 0;
  for (uint32_t l = 0; l < kernels::kGridMaxLevels; ++l)
    if (const kernels::GridView* v = grid.level_view(l)) views[count++] = *v;
  return run(
      exec, q.n, nullptr, "grid query",
      [&](uint32_t b, uint32_t e, uint32_t* counts, uint32_t* dst, uint64_t cap) {
        return kernels::grid_query(views, count, q.view, counts, dst, cap, {b, e});
      },
      offsets, hits);
}

Status BroadPhaseQuery::query(const Executor& exec, LbvhBroadPhase& lbvh, const QueryBatch& q,
                              std::vector<uint32_t>* offsets, std::vector<uint32_t>* hits) {
  if (lbvh.size() == 0) {
    no_hits(q.n, offsets, hits);
    return Status();
  }
  const kernels::LbvhView t = lbvh.query_view(exec);
  kernels::QueryView view = q.view;
  if (t.n >= kReorderMinBoxes && q.n >= kReorderMinQueries) {
    // Morton order of the query centres in the root's bounds: consecutive queries
    // descend through the same cached nodes (1M boxes: ~1.4x per query).
    const kernels::LbvhNode& root = t.nodes[0];
    const float lo[3] = {root.min_x, root.min_y, root.min_z}, hi[3] = {root.max_x, root.max_y, root.max_z};
    view.order = spatial_order(exec, q, SortBy::kMorton, lo, hi, 0);
  }
  return run(
      exec, q.n, view.order, "LBVH query",
      [&](uint32_t b, uint32_t e, uint32_t* counts, uint32_t* dst, uint64_t cap) {
        return kernels::lbvh_query(t, view, counts, dst, cap, {b, e});
      },
      offsets, hits);
}

Status BroadPhaseQuery::query(const Executor& exec, const SapBroadPhase& sap, const QueryBatch& q,
                              std::vector<uint32_t>* offsets, std::vector<uint32_t>* hits) {
  if (sap.size() == 0) {
    no_hits(q.n, offsets, hits);
    return Status();
  }
  const kernels::SapView v = sap.view();
  if (v.n == 0) return no_boxes_error("sweep-and-prune query");
  const uint32_t axis = sap.info().axis;
  // Largest extent on the sweep axis: one partial per chunk (max is exact, so the
  // combination order does not matter).
  constexpr uint32_t kGrain = SapBroadPhase::kKeyGrain;
  const uint32_t chunks = chunk_count(v.n, kGrain);
  double* part = scratch(partial_extent_, chunks);
  exec.for_each_chunk(v.n, kGrain, [&](uint32_t b, uint32_t e, uint32_t c) {
    part[c] = kernels::sap_max_extent(v, {b, e});
  });
  double extent = 0.0;
  for (uint32_t c = 0; c < chunks; ++c) extent = std::max(extent, part[c]);
  kernels::QueryView view = q.view;
  if (v.n >= kReorderMinBoxes && q.n >= kReorderMinQueries) {
    // Sweep-axis order of the queries: consecutive queries scan overlapping slabs of
    // cached slots (1M boxes: ~3.7x per query).
    const float unused[3] = {0.0f, 0.0f, 0.0f};
    view.order = spatial_order(exec, q, SortBy::kSweepAxis, unused, unused, axis);
  }
  return run(
      exec, q.n, view.order, "sweep-and-prune query",
      [&](uint32_t b, uint32_t e, uint32_t* counts, uint32_t* dst, uint64_t cap) {
        return kernels::sap_query(v, axis, extent, view, counts, dst, cap, {b, e});
      },
      offsets, hits);
}

Status BroadPhaseQuery::query(const Executor& exec, const BruteForceBroadPhase& brute_force, const QueryBatch& q,
                              std::vector<uint32_t>* offsets, std::vector<uint32_t>* hits) {
  return query(exec, brute_force.boxes(), brute_force.filter().layer, brute_force.size(), q, offsets, hits);
}

Status BroadPhaseQuery::query(const Executor& exec, kernels::AabbSoA boxes, const uint32_t* layer, uint32_t n,
                              const QueryBatch& q, std::vector<uint32_t>* offsets, std::vector<uint32_t>* hits) {
  if (n == 0) {
    no_hits(q.n, offsets, hits);
    return Status();
  }
  return run(
      exec, q.n, nullptr, "brute-force query",
      [&](uint32_t b, uint32_t e, uint32_t* counts, uint32_t* dst, uint64_t cap) {
        return kernels::brute_force_query(boxes, layer, n, q.view, counts, dst, cap, {b, e});
      },
      offsets, hits);
}

}  // namespace impact::host
