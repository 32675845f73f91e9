#include "kernels/common/permute.h"

namespace impact::kernels {

void invert_permutation(const uint32_t* IMPACT_RESTRICT perm, uint32_t* IMPACT_RESTRICT inv, Range r) {
  for (uint32_t i = r.begin; i < r.end; ++i) inv[perm[i]] = i;
}

void remap_pair_keys(const uint32_t* IMPACT_RESTRICT inv, uint64_t* IMPACT_RESTRICT io_keys, Range r) {
  for (uint32_t k = r.begin; k < r.end; ++k) {
    const uint64_t key = io_keys[k];
    const uint32_t a = inv[key >> 32];
    const uint32_t lo = static_cast<uint32_t>(key);
    if (lo & 0x80000000u) {  // body-plane: a is the body, the plane index stays
      io_keys[k] = (static_cast<uint64_t>(a) << 32) | lo;
    } else {  // body-body keys are (lower slot, higher slot), as the broad phase emits them
      const uint32_t point = lo & 0x60000000u;  // manifold point index (bits 29-30)
      const uint32_t b = inv[lo & 0x1fffffffu];
      io_keys[k] = (static_cast<uint64_t>(a < b ? a : b) << 32) | (a < b ? b : a) | point;
    }
  }
}

}  // namespace impact::kernels
