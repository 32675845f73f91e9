// Deterministic greedy graph colouring of contact constraints, so that Gauss-Seidel
// can run one colour's constraints in parallel: no two constraints of a colour share
// a dynamic body (inv_mass > 0). Static, kinematic and plane bodies take no colour,
// since the solver never writes them. Constraints whose bodies have used every colour
// go to the overflow colour kOverflowColour, which the solver runs in order on one
// thread. Greedy in manifold order (each constraint takes the lowest colour free at
// both its bodies), as Box2D v3's constraint graph does incrementally; here it is
// recomputed each step from the step's manifolds, which are in a deterministic order.
// Cost: one serial pass, O(manifolds + bodies), a 32-bit mask per body.
#pragma once

#include "kernels/common/contact_manifolds.h"
#include "kernels/common/kernel.h"

namespace impact::kernels {

inline constexpr uint32_t kColourCount = 24;
inline constexpr uint32_t kOverflowColour = kColourCount;

/// colour[m] for every manifold m < manifolds; body_masks has body_count entries,
/// zero on entry (left holding each body's used colours). counts[kColourCount + 1]
/// receives the constraints per colour (overflow last).
void colour_manifolds(const ContactManifoldArrays& c, const float* inv_mass, uint32_t manifolds,
                      uint32_t* IMPACT_RESTRICT body_masks, uint8_t* IMPACT_RESTRICT colour,
                      uint32_t* IMPACT_RESTRICT counts);

}  // namespace impact::kernels
