#include "kernels/sort/segments.h"

namespace impact::kernels {

void segment_starts(const uint64_t* IMPACT_RESTRICT sorted_keys, uint32_t n, uint32_t shift,
                    uint32_t segments, uint32_t* IMPACT_RESTRICT out_start, Range r) {
  if (n == 0) {
    // Every segment is empty; the whole table belongs to the (single) range.
    for (uint32_t s = r.begin; s < r.end; ++s) out_start[s] = 0;
    return;
  }
  for (uint32_t i = r.begin; i < r.end; ++i) {
    const uint64_t id = sorted_keys[i] >> shift;
    const uint64_t prev = i == 0 ? 0 : (sorted_keys[i - 1] >> shift) + 1;
    for (uint64_t s = prev; s <= id; ++s) out_start[s] = i;
    if (i == n - 1)
      for (uint64_t s = id + 1; s <= segments; ++s) out_start[s] = n;
  }
}

}  // namespace impact::kernels
