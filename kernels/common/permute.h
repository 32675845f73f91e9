// Permutation passes used to reorder body storage spatially.
//
// gather:        dst[i] = src[perm[i]]          (perm: new slot -> old slot)
// invert:        inv[perm[i]] = i
// remap_pair_keys: contact keys (a << 32 | b, bit 31 of b marks a plane, bits 29-30
//                the manifold point index) with a
//                and body b renumbered through inv; body-body keys are rewritten
//                as (lower, higher) slot, the order the broad phase emits;
//                planes keep their index.
// perm must be a permutation of [0, n). Cost: one random read per element.
#pragma once

#include "kernels/common/kernel.h"

namespace impact::kernels {

template <class T>
void gather(const T* IMPACT_RESTRICT src, const uint32_t* IMPACT_RESTRICT perm, T* IMPACT_RESTRICT dst,
            Range r) {
  for (uint32_t i = r.begin; i < r.end; ++i) dst[i] = src[perm[i]];
}

void invert_permutation(const uint32_t* IMPACT_RESTRICT perm, uint32_t* IMPACT_RESTRICT inv, Range r);

void remap_pair_keys(const uint32_t* IMPACT_RESTRICT inv, uint64_t* IMPACT_RESTRICT io_keys, Range r);

}  // namespace impact::kernels
