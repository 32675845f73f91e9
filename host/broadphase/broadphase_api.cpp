// impact::BroadPhase: the stand-alone broad-phase stage over a caller's boxes.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <string>

#include "host/broadphase/query.h"
#include "host/broadphase/stage.h"
#include "impact/broadphase.h"

namespace impact {

class BroadPhaseImpl {
 public:
  explicit BroadPhaseImpl(const BroadPhaseOptions& o) : options(o), stage(o.kind) {
    host::LbvhOptions lo = stage.lbvh.options();
    lo.update = o.lbvh_update;
    lo.refit_sah_limit = o.lbvh_refit_sah_limit;
    lo.max_refits = o.lbvh_max_refits;
    lo.fat_margin = o.lbvh_fat_margin;
    stage.set_lbvh_options(lo);
  }
  BroadPhaseOptions options;
  host::BroadPhaseStage stage;
  host::Buffer<kernels::Pair> pairs;
  host::Buffer<float> swept[6];
  host::Buffer<uint8_t> chunk_ok;  // check_boxes: one validity flag per chunk
  host::Buffer<kernels::BoundsSummary> chunk_bounds;  // check_boxes: one summary per chunk
  host::Executor exec;
  Backend exec_backend = Backend::kDefault;
  uint32_t exec_threads = 0;
  bool exec_ready = false;
  // Set when a build or update failed after its boxes were validated (the structure is
  // then gone): pairs() and the queries report it until a build or update succeeds.
  // Bad input never sets it: boxes are validated before anything is changed.
  Status broken;

  Status check_options() const;
  Status ready(const ExecConfig& e);
  // Validates boxes, then runs build (from_scratch) or update. A validation error
  // leaves the structure as it was.
  Status ingest(const AabbInput& boxes, const ExecConfig& e, bool from_scratch);
  // Validates a query batch and answers it from the stage (host/broadphase/query.h).
  template <class Queries>
  Status query(const Queries& q, const char* what, QueryHits* out, const ExecConfig& e);
};

BroadPhase::BroadPhase(BroadPhaseKind kind) : BroadPhase(BroadPhaseOptions{.kind = kind}) {}
BroadPhase::BroadPhase(const BroadPhaseOptions& options) : impl_(std::make_unique<BroadPhaseImpl>(options)) {}
BroadPhase::~BroadPhase() = default;
BroadPhase::BroadPhase(BroadPhase&&) noexcept = default;
BroadPhase& BroadPhase::operator=(BroadPhase&&) noexcept = default;

BroadPhaseKind BroadPhase::kind() const { return impl_->options.kind; }
BroadPhaseKind BroadPhase::active_kind() const { return impl_->stage.active(); }
const BroadPhaseOptions& BroadPhase::options() const { return impl_->options; }
size_t BroadPhase::size() const { return impl_->stage.built() ? impl_->stage.size() : 0; }

namespace {

constexpr uint32_t kPairCopyGrain = 1u << 16;  // pairs per chunk when copying out
constexpr uint32_t kCheckGrain = 1u << 16;     // boxes per chunk when validating

// Branch-free validity of the moves of swept boxes (vectorised; the common case), the
// same rule as the per-box messages below: dx, dy, dz finite and the moved box within
// 1e18. The boxes themselves are checked by kernels::reduce_valid_bounds.
bool moves_valid(const AabbInput& in, size_t begin, size_t end) {
  const float* lo[3] = {in.min_x.data(), in.min_y.data(), in.min_z.data()};
  const float* hi[3] = {in.max_x.data(), in.max_y.data(), in.max_z.data()};
  const float* d[3] = {in.dx.data(), in.dy.data(), in.dz.data()};
  constexpr float kMax = 1e18f;
  int bad = 0;
  for (int k = 0; k < 3; ++k) {
    const float* a = lo[k];
    const float* b = hi[k];
    const float* m = d[k];
#pragma omp simd reduction(| : bad)
    for (size_t i = begin; i < end; ++i) {
      // NaN fails every comparison, so !(x <= y) catches it.
      const float l = a[i] + m[i], h = b[i] + m[i];
      bad |= static_cast<int>(!(l >= -kMax)) | static_cast<int>(!(h <= kMax)) |
             static_cast<int>(!(m[i] - m[i] == 0.0f));
    }
  }
  return bad == 0;
}

// Validates the boxes (and the moves of swept ones). Unswept input's summary comes from
// the same pass (*summary, for the stage, which would otherwise read the bounds again);
// *has_summary says whether it was set.
Status check_boxes(const host::Executor& exec, const AabbInput& in, host::Buffer<uint8_t>& chunk_flags,
                   host::Buffer<kernels::BoundsSummary>& chunk_bounds, kernels::BoundsSummary* summary,
                   bool* has_summary) {
  *has_summary = false;
  const size_t n = in.size();
  const std::span<const float>* f[6] = {&in.min_x, &in.min_y, &in.min_z, &in.max_x, &in.max_y, &in.max_z};
  const char* names[6] = {"min_x", "min_y", "min_z", "max_x", "max_y", "max_z"};
  for (int k = 0; k < 6; ++k)
    if (f[k]->size() != n)
      return Status(StatusCode::kSizeMismatch, std::string("broad phase: ") + names[k] + " has " +
                                                   std::to_string(f[k]->size()) + " entries, min_x has " +
                                                   std::to_string(n));
  const bool any_filter = !in.layer.empty() || !in.mask.empty() || !in.is_static.empty();
  if (any_filter && (in.layer.size() != n || in.mask.size() != n || in.is_static.size() != n))
    return Status(StatusCode::kSizeMismatch,
                  "broad phase: layer, mask and is_static must all be empty or all have one entry per box");
  const bool swept = !in.dx.empty() || !in.dy.empty() || !in.dz.empty();
  if (swept && (in.dx.size() != n || in.dy.size() != n || in.dz.size() != n))
    return Status(StatusCode::kSizeMismatch,
                  "broad phase: dx, dy and dz must all be empty or all have one entry per box");
  if (n > 0xfffffff0ull)
    return Status(StatusCode::kCapacityExceeded, "broad phase: more than 2^32 - 16 boxes");
  // One flag per chunk (each written by its chunk only), then all of them.
  const uint32_t chunks = host::chunk_count(n, kCheckGrain);
  uint8_t* chunk_ok = host::scratch(chunk_flags, chunks);
  const kernels::AabbSoA soa{in.min_x.data(), in.min_y.data(), in.min_z.data(),
                             in.max_x.data(), in.max_y.data(), in.max_z.data()};
  kernels::BoundsSummary* partial = host::scratch(chunk_bounds, chunks);
  exec.for_each_chunk(n, kCheckGrain, [&](uint32_t b, uint32_t e, uint32_t c) {
    bool ok = false;
    partial[c] = kernels::reduce_valid_bounds(soa, {b, e}, &ok);
    chunk_ok[c] = ok && (!swept || moves_valid(in, b, e)) ? 1 : 0;
  });
  if (std::all_of(chunk_ok, chunk_ok + chunks, [](uint8_t v) { return v != 0; })) {
    // Swept input: the stage needs the summary of the swept boxes (its own pass).
    if (!swept && n > 0) {  // min / max are exact: the same summary as the stage's own pass
      kernels::BoundsSummary sum = kernels::empty_bounds_summary();
      for (uint32_t c = 0; c < chunks; ++c) sum = kernels::combine(sum, chunk_bounds[c]);
      *summary = sum;
      *has_summary = true;
    }
    return Status();
  }
  // Something is wrong: find the first offending box for the message.
  for (size_t i = 0; i < n; ++i) {
    for (int k = 0; k < 6; ++k) {
      const float v = (*f[k])[i];
      if (!std::isfinite(v) || std::fabs(v) > 1e18f)
        return Status(StatusCode::kInvalidArgument, "broad phase: box " + std::to_string(i) + " " + names[k] +
                                                        " must be finite with magnitude <= 1e18, got " +
                                                        std::to_string(v));
    }
    for (int k = 0; k < 3; ++k)
      if ((*f[k])[i] > (*f[k + 3])[i])
        return Status(StatusCode::kInvalidArgument, "broad phase: box " + std::to_string(i) + " " + names[k] +
                                                        " exceeds " + names[k + 3]);
    if (swept) {
      const std::span<const float>* d[3] = {&in.dx, &in.dy, &in.dz};
      const char* dn[3] = {"dx", "dy", "dz"};
      for (int k = 0; k < 3; ++k) {
        const float v = (*d[k])[i];
        // The moved box must stay in range too.
        const float lo = (*f[k])[i] + v, hi = (*f[k + 3])[i] + v;
        if (!std::isfinite(v) || !(std::fabs(lo) <= 1e18f) || !(std::fabs(hi) <= 1e18f))
          return Status(StatusCode::kInvalidArgument,
                        "broad phase: box " + std::to_string(i) + " " + dn[k] +
                            " must be finite and keep the moved box within magnitude 1e18, got " +
                            std::to_string(v));
      }
    }
  }
  return Status();
}

}  // namespace

Status BroadPhaseImpl::check_options() const {
  const BroadPhaseOptions& o = options;
  if (o.kind != BroadPhaseKind::kGrid && o.kind != BroadPhaseKind::kBruteForce && o.kind != BroadPhaseKind::kLbvh &&
      o.kind != BroadPhaseKind::kSweepAndPrune && o.kind != BroadPhaseKind::kAuto)
    return Status(StatusCode::kInvalidArgument, "BroadPhaseOptions: kind is not a known BroadPhaseKind");
  if (o.lbvh_update != LbvhUpdate::kRebuild && o.lbvh_update != LbvhUpdate::kRefit &&
      o.lbvh_update != LbvhUpdate::kAuto && o.lbvh_update != LbvhUpdate::kPairCache)
    return Status(StatusCode::kInvalidArgument, "BroadPhaseOptions: lbvh_update is not a known LbvhUpdate");
  if (!(std::isfinite(o.lbvh_fat_margin) && o.lbvh_fat_margin >= 0.0f))
    return Status(StatusCode::kInvalidArgument, "BroadPhaseOptions: lbvh_fat_margin must be finite and >= 0, got " +
                                                    std::to_string(o.lbvh_fat_margin));
  if (!(std::isfinite(o.lbvh_refit_sah_limit) && o.lbvh_refit_sah_limit >= 1.0))
    return Status(StatusCode::kInvalidArgument, "BroadPhaseOptions: lbvh_refit_sah_limit must be finite and >= 1, got " +
                                                    std::to_string(o.lbvh_refit_sah_limit));
  if (o.lbvh_max_refits == 0)
    return Status(StatusCode::kInvalidArgument, "BroadPhaseOptions: lbvh_max_refits must be >= 1");
  return Status();
}

Status BroadPhaseImpl::ready(const ExecConfig& e) {
  if (Status s = check_options(); !s.ok()) return s;
  if (!exec_ready || exec_backend != e.backend || exec_threads != e.threads) {
    Backend resolved;
    if (!host::resolve_backend(e.backend, &resolved))
      return Status(StatusCode::kUnsupported,
                    std::string("broad phase: backend '") + to_string(e.backend) + "' is not built in");
    exec = host::Executor(e.backend, e.threads);
    exec_backend = e.backend;
    exec_threads = e.threads;
    exec_ready = true;
  }
  return Status();
}

Status BroadPhaseImpl::ingest(const AabbInput& boxes, const ExecConfig& e, bool from_scratch) {
  if (Status s = ready(e); !s.ok()) return s;
  kernels::BoundsSummary sum{};
  bool has_sum = false;
  // Everything that can reject the boxes runs before the structure is touched.
  if (Status s = check_boxes(exec, boxes, chunk_ok, chunk_bounds, &sum, &has_sum); !s.ok()) return s;
  if (options.kind == BroadPhaseKind::kLbvh && boxes.size() > kernels::kLbvhMaxLeaves)
    return Status(StatusCode::kCapacityExceeded, "broad phase: the LBVH holds at most " +
                                                     std::to_string(kernels::kLbvhMaxLeaves) + " boxes, got " +
                                                     std::to_string(boxes.size()));
  kernels::AabbSoA soa{boxes.min_x.data(), boxes.min_y.data(), boxes.min_z.data(),
                       boxes.max_x.data(), boxes.max_y.data(), boxes.max_z.data()};
  const uint32_t n = static_cast<uint32_t>(boxes.size());
  if (!boxes.dx.empty()) {
    const kernels::AabbSoAOut out{host::scratch(swept[0], n), host::scratch(swept[1], n),
                                  host::scratch(swept[2], n), host::scratch(swept[3], n),
                                  host::scratch(swept[4], n), host::scratch(swept[5], n)};
    exec.for_each_chunk(n, host::GridBroadPhase::kKeyGrain, [&](uint32_t b, uint32_t en, uint32_t) {
      kernels::sweep_boxes(soa, boxes.dx.data(), boxes.dy.data(), boxes.dz.data(), out, {b, en});
    });
    soa = kernels::AabbSoA{out.min_x, out.min_y, out.min_z, out.max_x, out.max_y, out.max_z};
  }
  const kernels::PairFilter filter{boxes.layer.empty() ? nullptr : boxes.layer.data(),
                                   boxes.mask.empty() ? nullptr : boxes.mask.data(),
                                   boxes.is_static.empty() ? nullptr : boxes.is_static.data()};
  const kernels::BoundsSummary* summary = has_sum ? &sum : nullptr;
  const Status s = from_scratch ? stage.build(exec, soa, filter, n, summary) : stage.update(exec, soa, filter, n, summary);
  if (s.ok()) {
    broken = Status();
  } else {
    stage.invalidate();
    broken = s;
  }
  return s;
}

// The error pairs() and the queries give while `broken` is set.
static Status broken_error(const Status& broken, const char* what) {
  return Status(broken.code(), std::string(what) + ": the last build/update failed (" + broken.message() +
                                   "); build or update with valid boxes first");
}

Status BroadPhase::build(const AabbInput& boxes, const ExecConfig& exec) {
  return impl_->ingest(boxes, exec, /*from_scratch=*/true);
}

Status BroadPhase::update(const AabbInput& boxes, const ExecConfig& exec) {
  return impl_->ingest(boxes, exec, /*from_scratch=*/false);
}

Status BroadPhase::pairs(std::vector<BodyPair>* out, const ExecConfig& exec) {
  if (out == nullptr) return Status(StatusCode::kInvalidArgument, "pairs: out must not be null");
  BroadPhaseImpl& b = *impl_;
  // *out is cleared on failure and resized (not cleared first) on success: resizing
  // to the last frame's size zero-fills nothing before the copy overwrites it.
  if (Status s = b.ready(exec); !s.ok()) {
    out->clear();
    return s;
  }
  if (!b.broken.ok()) {
    out->clear();
    return broken_error(b.broken, "pairs");
  }
  if (Status s = b.stage.pairs(b.exec, &b.pairs); !s.ok()) {
    out->clear();
    return s;
  }
  // Same two uint32 fields (asserted below): copy the bytes, in parallel chunks.
  static_assert(sizeof(BodyPair) == sizeof(kernels::Pair) &&
                offsetof(BodyPair, a) == offsetof(kernels::Pair, a) &&
                offsetof(BodyPair, b) == offsetof(kernels::Pair, b));
  out->resize(b.pairs.size());
  BodyPair* dst = out->data();
  const kernels::Pair* src = b.pairs.data();
  b.exec.for_each_chunk(b.pairs.size(), kPairCopyGrain, [&](uint32_t lo, uint32_t hi, uint32_t) {
    std::memcpy(static_cast<void*>(dst + lo), src + lo, sizeof(BodyPair) * (hi - lo));
  });
  return Status();
}

Status BroadPhase::find_pairs(const AabbInput& boxes, std::vector<BodyPair>* out, const ExecConfig& exec) {
  if (out == nullptr) return Status(StatusCode::kInvalidArgument, "find_pairs: out must not be null");
  if (Status s = update(boxes, exec); !s.ok()) {
    out->clear();
    return s;
  }
  return pairs(out, exec);
}

template <class Queries>
Status BroadPhaseImpl::query(const Queries& q, const char* what, QueryHits* out, const ExecConfig& e) {
  if (out == nullptr) return Status(StatusCode::kInvalidArgument, std::string(what) + ": out must not be null");
  if (Status s = ready(e); !s.ok()) return s;
  if (!broken.ok()) return broken_error(broken, what);
  host::QueryBatch batch{};
  if (Status s = host::make_batch(q, what, &batch); !s.ok()) return s;
  if (Status s = stage.query(exec, batch, &out->offsets, &out->hits); !s.ok())
    return Status(s.code(), std::string(what) + ": " + s.message());
  return Status();
}

Status BroadPhase::query_aabbs(const AabbQueries& queries, QueryHits* out, const ExecConfig& exec) {
  return impl_->query(queries, "query_aabbs", out, exec);
}

Status BroadPhase::query_spheres(const SphereQueries& queries, QueryHits* out, const ExecConfig& exec) {
  return impl_->query(queries, "query_spheres", out, exec);
}

Status BroadPhase::query_points(const PointQueries& queries, QueryHits* out, const ExecConfig& exec) {
  return impl_->query(queries, "query_points", out, exec);
}

}  // namespace impact
