#include "host/broadphase/query.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <string>

#include "kernels/broadphase/grid_query.h"
#include "kernels/broadphase/sap_query.h"
#include "kernels/bvh/lbvh_query.h"

namespace impact::host {
namespace {

Status one_box_error(const char* what) {
  return Status(StatusCode::kInvalidArgument,
                std::string(what) + ": the structure was built over 1 box and keeps no copy of it; "
                                    "query it by brute force");
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
Status BroadPhaseQuery::run(const Executor& exec, uint32_t n, const char* what, Find&& find,
                            std::vector<uint32_t>* offsets, std::vector<uint32_t>* hits) {
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
  exec.for_each_chunk(n, g, [&](uint32_t b, uint32_t e, uint32_t c) {
    uint64_t at = off[c];
    for (uint32_t i = b; i < e; ++i) {
      o[i] = static_cast<uint32_t>(at);
      at += counts[i];
    }
    if (off[c + 1] > off[c]) std::memcpy(h + off[c], chunk_hits_[c].data(), sizeof(uint32_t) * (off[c + 1] - off[c]));
  });
  o[n] = static_cast<uint32_t>(total);
  return Status();
}

Status BroadPhaseQuery::query(const Executor& exec, const GridBroadPhase& grid, const QueryBatch& q,
                              std::vector<uint32_t>* offsets, std::vector<uint32_t>* hits) {
  if (grid.size() == 0) {
    no_hits(q.n, offsets, hits);
    return Status();
  }
  if (grid.size() == 1) return one_box_error("grid query");
  kernels::GridView views[kernels::kGridMaxLevels];
  uint32_t count = 0;
  for (uint32_t l = 0; l < kernels::kGridMaxLevels; ++l)
    if (const kernels::GridView* v = grid.level_view(l)) views[count++] = *v;
  return run(
      exec, q.n, "grid query",
      [&](uint32_t b, uint32_t e, uint32_t* counts, uint32_t* dst, uint64_t cap) {
        return kernels::grid_query(views, count, q.view, counts, dst, cap, {b, e});
      },
      offsets, hits);
}

Status BroadPhaseQuery::query(const Executor& exec, const LbvhBroadPhase& lbvh, const QueryBatch& q,
                              std::vector<uint32_t>* offsets, std::vector<uint32_t>* hits) {
  if (lbvh.size() == 0) {
    no_hits(q.n, offsets, hits);
    return Status();
  }
  const kernels::LbvhView t = lbvh.view();
  return run(
      exec, q.n, "LBVH query",
      [&](uint32_t b, uint32_t e, uint32_t* counts, uint32_t* dst, uint64_t cap) {
        return kernels::lbvh_query(t, q.view, counts, dst, cap, {b, e});
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
  if (v.n == 0) return one_box_error("sweep-and-prune query");
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
  return run(
      exec, q.n, "sweep-and-prune query",
      [&](uint32_t b, uint32_t e, uint32_t* counts, uint32_t* dst, uint64_t cap) {
        return kernels::sap_query(v, axis, extent, q.view, counts, dst, cap, {b, e});
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
      exec, q.n, "brute-force query",
      [&](uint32_t b, uint32_t e, uint32_t* counts, uint32_t* dst, uint64_t cap) {
        return kernels::brute_force_query(boxes, layer, n, q.view, counts, dst, cap, {b, e});
      },
      offsets, hits);
}

}  // namespace impact::host
