// Batched AABB / sphere / point queries over the sorted arrays of sweep-and-prune
// (sap.h). Hit rules, output layout and order: kernels/broadphase/query.h.
//
// What: the slots are sorted by min on the sweep axis only, so a box overlapping the
//   query's bounding box [lo, hi] on that axis has min0 <= hi0 (a prefix of the
//   slots) and max0 >= lo0. With E = the largest box extent on the sweep axis
//   (sap_max_extent), such a box also has min0 >= lo0 - E, so per query:
//     first = first slot with min0 >= lo0 - E (minus a rounding margin)  binary search
//     last  = first slot with min0 >  hi0                                 binary search
//   and the slots [first, last) are tested 16 at a time over the SoA arrays (all
//   three axes and the mask in one wide compare; the sentinels after slot n end the
//   last block), the exact sphere test only on the rare lanes that pass, in the
//   original axis order (the arrays are stored sweep axis first).
// Cost: O(log n) + the slots whose min0 lies in the slab [lo0 - E, hi0]: about
//   n (extent_q + E) / world extent on the sweep axis. One large box makes E large and
//   every query slow (the slab grows to cover it): a structure limitation, not a
//   rounding one; the grid levels or the LBVH suit such scenes. sap_max_extent is
//   O(n) per batch (the host computes it once per query call).
// Inputs: a SapView of n >= 1 slots plus kSapPad sentinels, the sweep axis its
//   arrays start with, finite queries.
// Method: a 1-D stabbing/range query over intervals sorted by their lower end, bounded
//   by the largest interval length (the "maximum extent" trick of sorted interval
//   lists; cf. Ericson, "Real-Time Collision Detection", 7.5 sort and sweep).
#pragma once

#include "kernels/broadphase/query.h"
#include "kernels/broadphase/sap.h"
#include "kernels/common/kernel.h"

namespace impact::kernels {

/// Largest max0 - min0 (sweep axis, in double) over the slots in r; 0 for an empty range.
double sap_max_extent(const SapView& v, Range r);

/// Queries r against the sorted slots of v, whose arrays start with axis `axis`
/// (0 = x); max_extent from sap_max_extent over all n slots.
uint64_t sap_query(const SapView& v, uint32_t axis, double max_extent, const QueryView& q,
                   uint32_t* IMPACT_RESTRICT out_count, uint32_t* IMPACT_RESTRICT out_hits, uint64_t capacity,
                   Range r);

}  // namespace impact::kernels
