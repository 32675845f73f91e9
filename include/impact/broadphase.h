// Broad phase as a stand-alone stage: overlapping pairs of a caller's boxes.
// The world's step uses the same code; this entry point lets a user run only the
// broad phase over their own bounds (and lets tests and benchmarks do the same).
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "impact/status.h"
#include "impact/types.h"
#include "impact/world.h"

namespace impact {

/// Axis-aligned boxes as SoA spans of equal length n. layer/mask/is_static may be
/// empty: then every box collides with every box. Two boxes pair when they
/// overlap or touch (min <= max on all axes), (layer_a & mask_b) && (layer_b & mask_a),
/// and not both are static.
struct AabbInput {
  std::span<const float> min_x, min_y, min_z, max_x, max_y, max_z;
  std::span<const uint32_t> layer, mask;
  std::span<const uint8_t> is_static;
  size_t size() const { return min_x.size(); }
};

/// Where passes run. Results are identical for every value.
struct ExecConfig {
  Backend backend = Backend::kDefault;
  uint32_t threads = 0;  ///< 0 = all hardware threads
};

class BroadPhaseImpl;

/// Reusable broad phase: keeps its scratch buffers between calls, so steady-state
/// frames do not allocate.
class BroadPhase {
 public:
  explicit BroadPhase(BroadPhaseKind kind = BroadPhaseKind::kGrid);
  ~BroadPhase();
  BroadPhase(BroadPhase&&) noexcept;
  BroadPhase& operator=(BroadPhase&&) noexcept;

  /// Finds every overlapping pair (a < b, box indices), replacing *out. Boxes must
  /// be finite with min <= max; violations are reported naming the box and field.
  /// Pair order is deterministic (documented per structure in docs/broadphase.md)
  /// and independent of the thread count.
  Status find_pairs(const AabbInput& boxes, std::vector<BodyPair>* out, const ExecConfig& exec = {});

  BroadPhaseKind kind() const;

 private:
  std::unique_ptr<BroadPhaseImpl> impl_;
};

}  // namespace impact
