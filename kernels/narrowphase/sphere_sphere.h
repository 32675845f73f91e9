// Sphere-sphere narrow phase over a list of candidate pairs.
//
// A pair collides when |pb - pa| < ra + rb (touching is not a contact). Then
//   n     = (pb - pa) / |pb - pa|, or +y when the centres coincide or |pb - pa|^2
//           is below FLT_MIN (so the normal is always finite and unit),
//   depth = ra + rb - |pb - pa|,
//   point = midpoint of pa + n*ra and pb - n*rb.
// count: number of colliding pairs in r. write: their contacts at out[offset ...]
// in pair order. Inputs finite. Cost: O(pairs), one sqrt per colliding pair.
// Method: the seeds' sphere test on squared distances (no sqrt to reject).
#pragma once

#include "kernels/broadphase/grid.h"
#include "kernels/narrowphase/contact.h"

namespace impact::kernels {

uint64_t sphere_sphere_count(const Pair* IMPACT_RESTRICT pairs, SphereView s, Range r);

void sphere_sphere_write(const Pair* IMPACT_RESTRICT pairs, SphereView s, ContactSoA out,
                         uint64_t offset, Range r);

}  // namespace impact::kernels
