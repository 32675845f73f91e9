// Morton codes of box centroids, the sort keys of the LBVH (kernels/bvh/lbvh_build.h).
//
// What: per box i, the centroid c = (min + max) / 2 is quantised on a grid of
//   2^b cells per axis spanning the scene bounds, q_k = floor((c_k - lo_k) * scale_k)
//   clamped to [0, 2^b - 1], and the three b-bit cell coordinates are bit-interleaved
//   (x in the lowest bit of each triple) into a 3b-bit Morton code:
//     30-bit codes (b = 10): morton_keys30 writes key = code << 32 | i, the layout of
//       every sort key here (primary key high, original index low), sorted on bits
//       [32, 62) by host::RadixSorter::sort (3 passes of 10 bits; 4 of 8 below 2^15 keys);
//     63-bit codes (b = 21): morton_keys63 writes key = code and value = i, sorted on
//       bits [0, 63) by RadixSorter::sort_kv (6 passes of up to 11 bits; 8 of 8 below
//       2^15 keys). The keys enter in index order and the sort is stable, so equal
//       codes keep index order and the (code, index) order is the same total order as
//       in the 30-bit layout.
//   morton_split_keys turns sorted 30-bit keys back into the leaf-index array.
// Inputs: boxes (SoA, finite), MortonParams from morton_params (scene bounds).
// Outputs: out_keys[i] (and out_values[i]) for i in the range.
// Precision: centroid, offset and scale are computed in double from the float
//   inputs (as the grid does), so a scene 1e6 m from the origin quantises as well
//   as one at the origin: the offset c - lo is exact to ~1e-10 relative.
// Preconditions: finite boxes; lo <= every min (the union of the boxes). An axis of
//   zero extent maps every box to cell 0 on that axis. Inf is not accepted.
// Cost: O(1) per box; streaming reads of six floats, one (or two) streaming writes
//   (the *_packed variants also write each box as a 32-byte record).
// Method: Morton (Z-order) codes as used by Lauterbach et al. 2009 ("Fast BVH
//   Construction on GPUs") and Karras 2012; the bit spreading is the usual
//   "magic number" part-by-2 sequence (Baert, "Morton encoding/decoding through
//   bit interleaving", 2013).
#pragma once

#include "kernels/broadphase/bounds.h"
#include "kernels/common/kernel.h"
#include "kernels/common/sorted_box.h"

namespace impact::kernels {

/// Quantisation frame of the Morton codes.
struct MortonParams {
  double origin[3];        ///< min corner of the scene (union of the boxes), m
  double scale[3];         ///< cells per metre on each axis: 2^bits / extent (0 for a flat axis)
  uint32_t bits_per_axis;  ///< 10 (30-bit codes) or 21 (63-bit codes)
};

/// Frame for boxes whose union is [lo, hi], with 10 or 21 bits per axis.
MortonParams morton_params(const float lo[3], const float hi[3], uint32_t bits_per_axis);

/// Interleaves three 10-bit values (x lowest) into a 30-bit code.
uint32_t morton30(uint32_t x, uint32_t y, uint32_t z);
/// Interleaves three 21-bit values (x lowest) into a 63-bit code.
uint64_t morton63(uint64_t x, uint64_t y, uint64_t z);

/// out_keys[i] = morton30(centroid cell of box i) << 32 | i.  (bits_per_axis == 10)
void morton_keys30(const MortonParams& p, AabbSoA boxes, uint64_t* IMPACT_RESTRICT out_keys, Range r);

/// out_codes[i] = morton63(centroid cell of box i), out_values[i] = i.  (bits_per_axis == 21)
void morton_keys63(const MortonParams& p, AabbSoA boxes, uint64_t* IMPACT_RESTRICT out_codes,
                   uint32_t* IMPACT_RESTRICT out_values, Range r);

/// morton_keys30 / morton_keys63 that also write out_packed[i] = box i as the LBVH's
/// 32-byte leaf record (lbvh_refit.h pack: index i, spare word 0): the LBVH build's
/// keys and its gather source from one read of the six bound arrays.
void morton_keys30_packed(const MortonParams& p, AabbSoA boxes, uint64_t* IMPACT_RESTRICT out_keys,
                          SortedBox* IMPACT_RESTRICT out_packed, Range r);
void morton_keys63_packed(const MortonParams& p, AabbSoA boxes, uint64_t* IMPACT_RESTRICT out_codes,
                          uint32_t* IMPACT_RESTRICT out_values, SortedBox* IMPACT_RESTRICT out_packed,
                          Range r);

/// out_index[s] = low 32 bits of sorted_keys[s] (the original box index).
void morton_split_keys(const uint64_t* IMPACT_RESTRICT sorted_keys, uint32_t* IMPACT_RESTRICT out_index,
                       Range r);

}  // namespace impact::kernels
