// The sphere-sphere bucket of a world of plain spheres: collision data of candidate
// body pairs read straight from the body store (no posing, no gather), written as
// one-point manifolds of kernels/common/contact_manifolds.h (plain: no
// children or feature arrays).
//
// sphere_sphere_count  per range of pairs: how many overlap (|d| < r_a + r_b)
// sphere_sphere_write  the same pairs again: manifold c = point c, from out's index
//                      `offset` (the chunk's exclusive-scanned count), pair index
//                      pair_base + k, normal d / |d| from a to b (+y when the centres
//                      coincide below FLT_MIN), depth r_a + r_b - |d|, the point midway
//                      between the two surfaces' deepest points.
// Cost: ~15 flops and two random body reads a pair; count is vectorised.
// Preconditions: finite positions, radii > 0 (validated at the API).
// The posed-shape kernel of the same pair (collide_sphere_sphere) computes the same
// contact relative to a's centre; so does this one (d = b - a, the point a + d / 2 +
// n (r_a - r_b) / 2), so far from the origin the point rounds once, at the world
// coordinate.
#pragma once

#include "kernels/common/body_views.h"
#include "kernels/common/contact_manifolds.h"
#include "kernels/common/pair.h"

namespace impact::kernels {

uint64_t sphere_sphere_count(const Pair* IMPACT_RESTRICT pairs, SphereView s, Range r);

void sphere_sphere_write(const Pair* IMPACT_RESTRICT pairs, SphereView s, uint32_t pair_base,
                         const ContactManifoldArrays& out, uint64_t offset, Range r);

}  // namespace impact::kernels
