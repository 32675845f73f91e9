#include "kernels/broadphase/plane_pairs.h"

#include <bit>
#include <cmath>

namespace impact::kernels {

uint64_t plane_pair_masks(SphereView s, BodyFilter f, PlaneView p, uint32_t* IMPACT_RESTRICT masks,
                          uint32_t stride, Range r) {
  const uint32_t words = plane_mask_words(p.count);
  uint64_t total = 0;
  for (uint32_t w = 0; w < words; ++w) {
    uint32_t* IMPACT_RESTRICT m = masks + static_cast<uint64_t>(w) * stride;
    for (uint32_t i = r.begin; i < r.end; ++i) m[i] = 0;
    const uint32_t j_end = p.count < 32 * (w + 1) ? p.count : 32 * (w + 1);
    for (uint32_t j = 32 * w; j < j_end; ++j) {
      const float nx = p.normal_x[j], ny = p.normal_y[j], nz = p.normal_z[j], off = p.offset[j];
      const uint32_t player = p.layer[j], pmask = p.mask[j], bit = 1u << (j - 32 * w);
#pragma omp simd
      for (uint32_t i = r.begin; i < r.end; ++i) {
        const float c = nx * s.pos_x[i] + ny * s.pos_y[i] + nz * s.pos_z[i];
        const float rad = s.radius[i];
        const float slack = 1e-4f * (std::fabs(c) + std::fabs(off) + rad);
        const bool meets = f.inv_mass[i] > 0.0f && (f.layer[i] & pmask) != 0 && (player & f.mask[i]) != 0 &&
                           c - off <= rad + slack;
        m[i] |= meets ? bit : 0u;
      }
    }
    uint32_t count = 0;
#pragma omp simd reduction(+ : count)
    for (uint32_t i = r.begin; i < r.end; ++i) count += static_cast<uint32_t>(std::popcount(m[i]));
    total += count;
  }
  return total;
}

void plane_pair_write(const uint32_t* IMPACT_RESTRICT masks, uint32_t words, uint32_t stride, uint32_t plane_base,
                      Pair* IMPACT_RESTRICT out, uint64_t offset, Range r) {
  uint64_t at = offset;
  for (uint32_t i = r.begin; i < r.end; ++i) {
    for (uint32_t w = 0; w < words; ++w) {
      for (uint32_t bits = masks[static_cast<uint64_t>(w) * stride + i]; bits != 0; bits &= bits - 1)
        out[at++] = Pair{i, plane_base + 32 * w + static_cast<uint32_t>(std::countr_zero(bits))};
    }
  }
}

}  // namespace impact::kernels
