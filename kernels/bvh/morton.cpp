#include "kernels/bvh/morton.h"

#include "kernels/bvh/lbvh_refit.h"

namespace impact::kernels {
namespace {

// Inserts two zero bits between the low 10 bits of v.
IMPACT_INLINE uint32_t spread10(uint32_t v) {
  v &= 0x3ffu;
  v = (v | (v << 16)) & 0x030000ffu;
  v = (v | (v << 8)) & 0x0300f00fu;
  v = (v | (v << 4)) & 0x030c30c3u;
  v = (v | (v << 2)) & 0x09249249u;
  return v;
}

// Inserts two zero bits between the low 21 bits of v.
IMPACT_INLINE uint64_t spread21(uint64_t v) {
  v &= 0x1fffffull;
  v = (v | (v << 32)) & 0x1f00000000ffffull;
  v = (v | (v << 16)) & 0x1f0000ff0000ffull;
  v = (v | (v << 8)) & 0x100f00f00f00f00full;
  v = (v | (v << 4)) & 0x10c30c30c30c30c3ull;
  v = (v | (v << 2)) & 0x1249249249249249ull;
  return v;
}

// Cell of one centroid coordinate: centroid and offset in double, clamped to [0, 2^b - 1].
IMPACT_INLINE uint32_t axis_cell(float lo, float hi, double origin, double scale, uint32_t max_cell) {
  const double c = 0.5 * (static_cast<double>(lo) + static_cast<double>(hi));
  const double u = (c - origin) * scale;
  // u >= 0 when origin is the scene minimum; the clamps only guard rounding at the ends.
  if (!(u > 0.0)) return 0;
  if (u >= static_cast<double>(max_cell)) return max_cell;
  return static_cast<uint32_t>(u);
}

// The exported morton30 / morton63 can be interposed (PIC), so the compiler would keep
// a call per box in the key loops; they call these instead, inlined.
IMPACT_INLINE uint32_t interleave30(uint32_t x, uint32_t y, uint32_t z) {
  return spread10(x) | (spread10(y) << 1) | (spread10(z) << 2);
}

IMPACT_INLINE uint64_t interleave63(uint64_t x, uint64_t y, uint64_t z) {
  return spread21(x) | (spread21(y) << 1) | (spread21(z) << 2);
}

}  // namespace

MortonParams morton_params(const float lo[3], const float hi[3], uint32_t bits_per_axis) {
  MortonParams p{};
  p.bits_per_axis = bits_per_axis;
  const double cells = static_cast<double>(1ull << bits_per_axis);
  for (int k = 0; k < 3; ++k) {
    p.origin[k] = static_cast<double>(lo[k]);
    const double extent = static_cast<double>(hi[k]) - static_cast<double>(lo[k]);
    p.scale[k] = extent > 0.0 ? cells / extent : 0.0;
  }
  return p;
}

uint32_t morton30(uint32_t x, uint32_t y, uint32_t z) { return interleave30(x, y, z); }

uint64_t morton63(uint64_t x, uint64_t y, uint64_t z) { return interleave63(x, y, z); }

namespace {

// The key loops, optionally writing each box's packed record as well.
template <bool kPack>
IMPACT_INLINE void keys30(const MortonParams& p, AabbSoA b, uint64_t* IMPACT_RESTRICT out_keys,
                          SortedBox* IMPACT_RESTRICT out_packed, Range r) {
  IMPACT_ASSERT(p.bits_per_axis == 10);
  constexpr uint32_t kMax = (1u << 10) - 1;
  for (uint32_t i = r.begin; i < r.end; ++i) {
    const uint32_t x = axis_cell(b.min_x[i], b.max_x[i], p.origin[0], p.scale[0], kMax);
    const uint32_t y = axis_cell(b.min_y[i], b.max_y[i], p.origin[1], p.scale[1], kMax);
    const uint32_t z = axis_cell(b.min_z[i], b.max_z[i], p.origin[2], p.scale[2], kMax);
    out_keys[i] = (static_cast<uint64_t>(interleave30(x, y, z)) << 32) | i;
    if constexpr (kPack) out_packed[i] = pack(b, i);
  }
}

template <bool kPack>
IMPACT_INLINE void keys63(const MortonParams& p, AabbSoA b, uint64_t* IMPACT_RESTRICT out_codes,
                          uint32_t* IMPACT_RESTRICT out_values, SortedBox* IMPACT_RESTRICT out_packed,
                          Range r) {
  IMPACT_ASSERT(p.bits_per_axis == 21);
  constexpr uint32_t kMax = (1u << 21) - 1;
  for (uint32_t i = r.begin; i < r.end; ++i) {
    const uint32_t x = axis_cell(b.min_x[i], b.max_x[i], p.origin[0], p.scale[0], kMax);
    const uint32_t y = axis_cell(b.min_y[i], b.max_y[i], p.origin[1], p.scale[1], kMax);
    const uint32_t z = axis_cell(b.min_z[i], b.max_z[i], p.origin[2], p.scale[2], kMax);
    out_codes[i] = interleave63(x, y, z);
    out_values[i] = i;
    if constexpr (kPack) out_packed[i] = pack(b, i);
  }
}

}  // namespace

void morton_keys30(const MortonParams& p, AabbSoA b, uint64_t* IMPACT_RESTRICT out_keys, Range r) {
  keys30<false>(p, b, out_keys, nullptr, r);
}

void morton_keys63(const MortonParams& p, AabbSoA b, uint64_t* IMPACT_RESTRICT out_codes,
                   uint32_t* IMPACT_RESTRICT out_values, Range r) {
  keys63<false>(p, b, out_codes, out_values, nullptr, r);
}

void morton_keys30_packed(const MortonParams& p, AabbSoA b, uint64_t* IMPACT_RESTRICT out_keys,
                          SortedBox* IMPACT_RESTRICT out_packed, Range r) {
  keys30<true>(p, b, out_keys, out_packed, r);
}

void morton_keys63_packed(const MortonParams& p, AabbSoA b, uint64_t* IMPACT_RESTRICT out_codes,
                          uint32_t* IMPACT_RESTRICT out_values, SortedBox* IMPACT_RESTRICT out_packed,
                          Range r) {
  keys63<true>(p, b, out_codes, out_values, out_packed, r);
}

void morton_split_keys(const uint64_t* IMPACT_RESTRICT sorted_keys, uint32_t* IMPACT_RESTRICT out_index,
                       Range r) {
#pragma omp simd
  for (uint32_t s = r.begin; s < r.end; ++s) out_index[s] = static_cast<uint32_t>(sorted_keys[s]);
}

}  // namespace impact::kernels
