#include "impact/status.h"
#include "impact/types.h"

namespace impact {

const char* to_string(StatusCode code) {
  switch (code) {
    case StatusCode::kOk: return "ok";
    case StatusCode::kInvalidArgument: return "invalid argument";
    case StatusCode::kSizeMismatch: return "size mismatch";
    case StatusCode::kStaleHandle: return "stale handle";
    case StatusCode::kCapacityExceeded: return "capacity exceeded";
    case StatusCode::kUnsupported: return "unsupported";
  }
  return "?";
}

const char* to_string(BroadPhaseKind kind) {
  switch (kind) {
    case BroadPhaseKind::kGrid: return "grid";
    case BroadPhaseKind::kBruteForce: return "brute-force";
    case BroadPhaseKind::kLbvh: return "lbvh";
    case BroadPhaseKind::kSweepAndPrune: return "sweep-and-prune";
    case BroadPhaseKind::kAuto: return "auto";
  }
  return "?";
}

const char* to_string(LbvhUpdate update) {
  switch (update) {
    case LbvhUpdate::kRebuild: return "rebuild";
    case LbvhUpdate::kRefit: return "refit";
    case LbvhUpdate::kAuto: return "auto";
    case LbvhUpdate::kPairCache: return "pair_cache";
  }
  return "?";
}

}  // namespace impact
