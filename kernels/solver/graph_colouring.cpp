#include "kernels/solver/graph_colouring.h"

#include <bit>

namespace impact::kernels {

void colour_manifolds(const ContactManifoldArrays& c, const float* inv_mass, uint32_t manifolds,
                      uint32_t* IMPACT_RESTRICT body_masks, uint8_t* IMPACT_RESTRICT colour,
                      uint32_t* IMPACT_RESTRICT counts) {
  constexpr uint32_t kAll = (1u << kColourCount) - 1u;
  for (uint32_t k = 0; k <= kOverflowColour; ++k) counts[k] = 0;
  for (uint32_t m = 0; m < manifolds; ++m) {
    const uint32_t a = c.a[m];
    const bool da = inv_mass[a] > 0.0f;
    const bool db = c.b_is_plane[m] == 0 && inv_mass[c.b[m]] > 0.0f;
    const uint32_t used = (da ? body_masks[a] : 0u) | (db ? body_masks[c.b[m]] : 0u);
    const uint32_t free = ~used & kAll;
    uint32_t k = kOverflowColour;
    if (free != 0) {
      k = static_cast<uint32_t>(std::countr_zero(free));
      if (da) body_masks[a] |= 1u << k;
      if (db) body_masks[c.b[m]] |= 1u << k;
    }
    colour[m] = static_cast<uint8_t>(k);
    ++counts[k];
  }
}

}  // namespace impact::kernels
