// impact::BroadPhase: the stand-alone broad-phase stage over a caller's boxes.
#include <cmath>
#include <string>

#include "host/broadphase/broadphase.h"
#include "host/broadphase/lbvh.h"
#include "host/broadphase/sap.h"
#include "impact/broadphase.h"

namespace impact {

class BroadPhaseImpl {
 public:
  explicit BroadPhaseImpl(BroadPhaseKind k) : kind(k) {}
  BroadPhaseKind kind;
  host::GridBroadPhase grid;
  host::BruteForceBroadPhase brute_force;
  host::LbvhBroadPhase lbvh;
  host::SapBroadPhase sap;
  host::Buffer<kernels::Pair> pairs;
  host::Executor exec;
  Backend exec_backend = Backend::kDefault;
  uint32_t exec_threads = 0;
  bool exec_ready = false;
};

BroadPhase::BroadPhase(BroadPhaseKind kind) : impl_(std::make_unique<BroadPhaseImpl>(kind)) {}
BroadPhase::~BroadPhase() = default;
BroadPhase::BroadPhase(BroadPhase&&) noexcept = default;
BroadPhase& BroadPhase::operator=(BroadPhase&&) noexcept = default;

BroadPhaseKind BroadPhase::kind() const { return impl_->kind; }

namespace {

Status check_boxes(const AabbInput& in) {
  const size_t n = in.size();
  const std::span<const float>* f[6] = {&in.min_x, &in.min_y, &in.min_z, &in.max_x, &in.max_y, &in.max_z};
  const char* names[6] = {"min_x", "min_y", "min_z", "max_x", "max_y", "max_z"};
  for (int k = 0; k < 6; ++k)
    if (f[k]->size() != n)
      return Status(StatusCode::kSizeMismatch, std::string("find_pairs: ") + names[k] + " has " +
                                                   std::to_string(f[k]->size()) + " entries, min_x has " +
                                                   std::to_string(n));
  const bool any_filter = !in.layer.empty() || !in.mask.empty() || !in.is_static.empty();
  if (any_filter && (in.layer.size() != n || in.mask.size() != n || in.is_static.size() != n))
    return Status(StatusCode::kSizeMismatch,
                  "find_pairs: layer, mask and is_static must all be empty or all have one entry per box");
  if (n > 0xfffffff0ull)
    return Status(StatusCode::kCapacityExceeded, "find_pairs: more than 2^32 - 16 boxes");
  for (size_t i = 0; i < n; ++i) {
    for (int k = 0; k < 6; ++k) {
      const float v = (*f[k])[i];
      if (!std::isfinite(v) || std::fabs(v) > 1e18f)
        return Status(StatusCode::kInvalidArgument, "find_pairs: box " + std::to_string(i) + " " + names[k] +
                                                        " must be finite with magnitude <= 1e18, got " +
                                                        std::to_string(v));
    }
    for (int k = 0; k < 3; ++k)
      if ((*f[k])[i] > (*f[k + 3])[i])
        return Status(StatusCode::kInvalidArgument, "find_pairs: box " + std::to_string(i) + " " + names[k] +
                                                        " exceeds " + names[k + 3]);
  }
  return Status();
}

}  // namespace

Status BroadPhase::find_pairs(const AabbInput& boxes, std::vector<BodyPair>* out, const ExecConfig& exec) {
  if (out == nullptr) return Status(StatusCode::kInvalidArgument, "find_pairs: out must not be null");
  if (Status s = check_boxes(boxes); !s.ok()) return s;
  BroadPhaseImpl& b = *impl_;
  if (!b.exec_ready || b.exec_backend != exec.backend || b.exec_threads != exec.threads) {
    Backend resolved;
    if (!host::resolve_backend(exec.backend, &resolved))
      return Status(StatusCode::kUnsupported,
                    std::string("find_pairs: backend '") + to_string(exec.backend) + "' is not built in");
    b.exec = host::Executor(exec.backend, exec.threads);
    b.exec_backend = exec.backend;
    b.exec_threads = exec.threads;
    b.exec_ready = true;
  }
  const kernels::AabbSoA soa{boxes.min_x.data(), boxes.min_y.data(), boxes.min_z.data(),
                             boxes.max_x.data(), boxes.max_y.data(), boxes.max_z.data()};
  const kernels::PairFilter filter{boxes.layer.empty() ? nullptr : boxes.layer.data(),
                                   boxes.mask.empty() ? nullptr : boxes.mask.data(),
                                   boxes.is_static.empty() ? nullptr : boxes.is_static.data()};
  const uint32_t n = static_cast<uint32_t>(boxes.size());
  Status s;
  switch (b.kind) {
    case BroadPhaseKind::kBruteForce: s = b.brute_force.find_pairs(b.exec, soa, filter, n, &b.pairs); break;
    case BroadPhaseKind::kLbvh: s = b.lbvh.find_pairs(b.exec, soa, filter, n, &b.pairs); break;
    case BroadPhaseKind::kSweepAndPrune: s = b.sap.find_pairs(b.exec, soa, filter, n, &b.pairs); break;
    case BroadPhaseKind::kGrid: s = b.grid.find_pairs(b.exec, soa, filter, n, &b.pairs); break;
    default: return Status(StatusCode::kInvalidArgument, "find_pairs: unknown BroadPhaseKind");
  }
  if (!s.ok()) return s;
  out->resize(b.pairs.size());
  for (size_t i = 0; i < b.pairs.size(); ++i) (*out)[i] = BodyPair{b.pairs[i].a, b.pairs[i].b};
  return Status();
}

}  // namespace impact
