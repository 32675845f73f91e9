// Segment starts of a sorted key array: out_start[s] = first position whose
// segment id (key >> shift) is >= s, for s in [0, segments], so segment s
// occupies [out_start[s], out_start[s + 1]). Empty segments get an empty range.
// Each entry of out_start is written by exactly one position (the one where the
// segment id steps over it), so ranges of positions can run in parallel; the
// range that holds position n - 1 also fills the tail up to `segments`.
// Precondition: keys sorted by segment id, every id <= segments.
// Cost: O(n + segments), one read of the keys.
#pragma once

#include "kernels/common/kernel.h"

namespace impact::kernels {

void segment_starts(const uint64_t* IMPACT_RESTRICT sorted_keys, uint32_t n, uint32_t shift,
                    uint32_t segments, uint32_t* IMPACT_RESTRICT out_start, Range r);

}  // namespace impact::kernels
