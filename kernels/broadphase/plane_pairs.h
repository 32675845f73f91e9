// The plane filter: which (body, static plane) pairs go to the narrow phase. One rule
// for every world (spheres or shapes): a body meets plane j when it is dynamic
// (inv_mass > 0), its layer is in the plane's mask and the plane's layer in its mask,
// and its bounding sphere (centre p, radius r: the body's `radius`, which bounds a
// shaped body's whole shape) reaches the plane: n.p - offset <= r, with a slack of
// 1e-4 (|n.p| + |offset| + r) that covers float rounding (~1e-7 of the same) many times,
// so no contact the narrow phase would find is lost (it decides the exact touch).
//
// plane_pair_masks  per range of bodies: bit j % 32 of masks[(j / 32) * stride + i] says
//                   whether body i meets plane j (plane_mask_words(count) words per
//                   body); returns the number of set bits, the range's pair count
// plane_pair_write  the same bodies again: pairs (body, plane_base + j) for the set
//                   bits, from out[offset], by body slot then plane (the serial order
//                   for any chunking)
// Cost: the mask pass is one vectorised float test per body and plane; the write pass
// reads one word per body and group of 32 planes and writes only the pairs.
// Preconditions: finite positions and planes, unit plane normals; stride >= the
// bodies' slot range.
#pragma once

#include "kernels/common/body_views.h"
#include "kernels/common/pair.h"

namespace impact::kernels {

/// Mask words per body for `planes` planes.
inline uint32_t plane_mask_words(uint32_t planes) { return (planes + 31) / 32; }

uint64_t plane_pair_masks(SphereView s, BodyFilter f, PlaneView planes, uint32_t* IMPACT_RESTRICT masks,
                          uint32_t stride, Range r);

void plane_pair_write(const uint32_t* IMPACT_RESTRICT masks, uint32_t words, uint32_t stride, uint32_t plane_base,
                      Pair* IMPACT_RESTRICT out, uint64_t offset, Range r);

}  // namespace impact::kernels
