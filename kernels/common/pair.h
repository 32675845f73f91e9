// A candidate pair of bodies (or boxes) and the broad phases' pair filter: the
// vocabulary every broad phase writes (grid, sweep-and-prune, LBVH, plane pairs)
// and the narrow phase reads. A pair holds two indices, (lo, hi) wherever a
// broad phase emits it; the filter is the layer / mask / static rule all broad
// phases apply, so any two of them report the same pair set.
#pragma once

#include <cstdint>

#include "kernels/common/kernel.h"

namespace impact::kernels {

/// Two body (or box) indices; a broad phase writes them as a < b.
struct Pair {
  uint32_t a;
  uint32_t b;
};

/// The pair filter of every broad phase: each body's layer is in the other's
/// mask, and static never pairs with static.
IMPACT_INLINE bool pair_allowed(uint32_t layer_a, uint32_t mask_a, uint8_t static_a, uint32_t layer_b,
                                uint32_t mask_b, uint8_t static_b) {
  return (layer_a & mask_b) != 0 && (layer_b & mask_a) != 0 && !(static_a && static_b);
}

/// Optional pair filter, per box (all null = no filter).
struct PairFilter {
  const uint32_t* layer;
  const uint32_t* mask;
  const uint8_t* is_static;
};

}  // namespace impact::kernels
