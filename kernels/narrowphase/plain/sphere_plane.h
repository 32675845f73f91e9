// The sphere-half-space bucket of a world of plain spheres: collision data of the
// (body, plane) pairs the plane filter found (kernels/broadphase/plane_pairs.h), read
// straight from the body and plane stores, written as one-point manifolds of
// kernels/common/contact_manifolds.h (plain: no children or feature arrays).
//
// sphere_plane_count  per range of pairs: how many touch (h = n.p - offset < r, h in
//                     double, rounded once: exact far from the origin)
// sphere_plane_write  the same pairs again: manifold c = point c from out's index
//                     `offset`, pair index pair_base + k, a = the body, b = the plane
//                     index (pair.b - plane_base) with b_is_plane set, normal -n (from
//                     the sphere into the plane), depth r - h, the point midway between
//                     p - n r and p - n h.
// Cost: ~10 flops a pair. Preconditions: unit plane normals, finite inputs.
#pragma once

#include "kernels/common/body_views.h"
#include "kernels/common/contact_manifolds.h"
#include "kernels/common/pair.h"

namespace impact::kernels {

uint64_t sphere_plane_count(const Pair* IMPACT_RESTRICT pairs, SphereView s, PlaneView planes,
                            uint32_t plane_base, Range r);

void sphere_plane_write(const Pair* IMPACT_RESTRICT pairs, SphereView s, PlaneView planes, uint32_t plane_base,
                        uint32_t pair_base, const ContactManifoldArrays& out, uint64_t offset, Range r);

}  // namespace impact::kernels
