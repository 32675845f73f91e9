#include "kernels/broadphase/sap.h"

#include <limits>

namespace impact::kernels {
namespace {

IMPACT_INLINE const float* axis_min(AabbSoA b, uint32_t axis) {
  return axis == 0 ? b.min_x : axis == 1 ? b.min_y : b.min_z;
}
IMPACT_INLINE const float* axis_max(AabbSoA b, uint32_t axis) {
  return axis == 0 ? b.max_x : axis == 1 ? b.max_y : b.max_z;
}

// Pairs of query slots in r. The candidate test runs on blocks of kSapPad slots (a
// fixed-trip inner loop the compiler turns into wide compares); the block whose
// last slot starts past max0[s] is the last one, and the sentinels end any scan
// that reaches slot n.
template <bool kFiltered>
uint64_t sweep(const SapView& v, Pair* IMPACT_RESTRICT out, uint64_t capacity, Range r) {
  const float* IMPACT_RESTRICT min0 = v.min[0];
  const float* IMPACT_RESTRICT max0 = v.max[0];
  const float* IMPACT_RESTRICT min1 = v.min[1];
  const float* IMPACT_RESTRICT max1 = v.max[1];
  const float* IMPACT_RESTRICT min2 = v.min[2];
  const float* IMPACT_RESTRICT max2 = v.max[2];
  uint64_t k = 0;
  for (uint32_t s = r.begin; s < r.end; ++s) {
    const float a_min0 = min0[s], a_max0 = max0[s];
    const float a_min1 = min1[s], a_max1 = max1[s];
    const float a_min2 = min2[s], a_max2 = max2[s];
    const uint32_t ia = v.index[s];
    uint32_t la = 0, ma = 0;
    uint8_t sa = 0;
    if constexpr (kFiltered) {
      la = v.layer[s];
      ma = v.mask[s];
      sa = v.is_static[s];
    }
    // t <= n on entry to every block: a block is followed only when its last slot
    // is a real box (sentinels fail the test), so every slot read is < n + kSapPad.
    for (uint32_t t = s + 1;; t += kSapPad) {
      // One word per lane (float-width, so the lane loop vectorises at full
      // width), OR-reduced to one test; the rare hits are emitted in slot order
      // by the scalar loop below.
      // Block-relative pointers: indexing with the 32-bit t + j made GCC emit
      // scalar gathers (vinsertps) instead of contiguous 8-wide loads.
      uint32_t hit[kSapPad];
      const float* b_min0 = min0 + t;
      const float* b_max0 = max0 + t;
      const float* b_min1 = min1 + t;
      const float* b_max1 = max1 + t;
      const float* b_min2 = min2 + t;
      const float* b_max2 = max2 + t;
      for (uint32_t j = 0; j < kSapPad; ++j) {
        // Bitwise & (not &&): branch-free, so the lanes vectorise.
        hit[j] = static_cast<uint32_t>((b_min0[j] <= a_max0) & (a_min0 <= b_max0[j]) &  //
                                       (b_min1[j] <= a_max1) & (a_min1 <= b_max1[j]) &  //
                                       (b_min2[j] <= a_max2) & (a_min2 <= b_max2[j]));
      }
      uint32_t any = 0;
      for (uint32_t j = 0; j < kSapPad; ++j) any |= hit[j];
      if (any != 0) {
        for (uint32_t j = 0; j < kSapPad; ++j) {
          if (!hit[j]) continue;
          const uint32_t u = t + j;
          if constexpr (kFiltered) {
            if (!pair_allowed(la, ma, sa, v.layer[u], v.mask[u], v.is_static[u])) continue;
          }
          const uint32_t ib = v.index[u];
          if (k < capacity) out[k] = Pair{ia < ib ? ia : ib, ia < ib ? ib : ia};
          ++k;
        }
      }
      if (min0[t + kSapPad - 1] > a_max0) break;
    }
  }
  return k;
}

}  // namespace

SapMoments sap_moments(AabbSoA boxes, const double shift[3], Range r) {
  SapMoments m{};
  for (uint32_t a = 0; a < 3; ++a) {
    const float* lo = axis_min(boxes, a);
    const float* hi = axis_max(boxes, a);
    double sum = 0, sum_sq = 0;
    for (uint32_t i = r.begin; i < r.end; ++i) {
      const double c = 0.5 * (static_cast<double>(lo[i]) + static_cast<double>(hi[i])) - shift[a];
      sum += c;
      sum_sq += c * c;
    }
    m.sum[a] = sum;
    m.sum_sq[a] = sum_sq;
  }
  return m;
}

void sap_keys(AabbSoA boxes, uint32_t axis, uint64_t* IMPACT_RESTRICT out_keys, Range r) {
  const float* lo = axis_min(boxes, axis);
  for (uint32_t i = r.begin; i < r.end; ++i)
    out_keys[i] = (static_cast<uint64_t>(sap_float_key(lo[i])) << 32) | i;
}

void sap_rekey(AabbSoA boxes, uint32_t axis, uint64_t* IMPACT_RESTRICT io_keys, Range r) {
  const float* lo = axis_min(boxes, axis);
  for (uint32_t s = r.begin; s < r.end; ++s) {
    const uint32_t i = static_cast<uint32_t>(io_keys[s]);
    io_keys[s] = (static_cast<uint64_t>(sap_float_key(lo[i])) << 32) | i;
  }
}

uint64_t sap_insertion_sort(uint64_t* IMPACT_RESTRICT io_keys, uint64_t max_shifts, Range r) {
  uint64_t shifts = 0;
  for (uint32_t i = r.begin + 1; i < r.end; ++i) {
    const uint64_t key = io_keys[i];
    if (io_keys[i - 1] < key) continue;  // the common, coherent case
    uint32_t j = i;
    while (j > r.begin && io_keys[j - 1] > key) {
      io_keys[j] = io_keys[j - 1];
      --j;
    }
    io_keys[j] = key;
    shifts += i - j;
    if (shifts > max_shifts) return shifts;
  }
  return shifts;
}

void sap_gather(const uint64_t* IMPACT_RESTRICT sorted_keys, AabbSoA boxes, uint32_t axis,
                PairFilter filter, SapSorted out, Range r) {
  const uint32_t a1 = axis == 2 ? 0 : axis + 1;
  const uint32_t a2 = a1 == 2 ? 0 : a1 + 1;
  const float* lo[3] = {axis_min(boxes, axis), axis_min(boxes, a1), axis_min(boxes, a2)};
  const float* hi[3] = {axis_max(boxes, axis), axis_max(boxes, a1), axis_max(boxes, a2)};
  for (uint32_t s = r.begin; s < r.end; ++s) {
    const uint32_t i = static_cast<uint32_t>(sorted_keys[s]);
    out.index[s] = i;
    for (uint32_t a = 0; a < 3; ++a) {
      out.min[a][s] = lo[a][i];
      out.max[a][s] = hi[a][i];
    }
    if (filter.layer) {
      out.layer[s] = filter.layer[i];
      out.mask[s] = filter.mask[i];
      out.is_static[s] = filter.is_static[i];
    }
  }
}

void sap_pad(SapSorted out, uint32_t n) {
  constexpr float kInf = std::numeric_limits<float>::infinity();
  for (uint32_t s = n; s < n + kSapPad; ++s) {
    for (uint32_t a = 0; a < 3; ++a) {
      out.min[a][s] = kInf;
      out.max[a][s] = -kInf;
    }
    out.index[s] = kInvalidBody;
    if (out.layer) {
      out.layer[s] = 0;
      out.mask[s] = 0;
      out.is_static[s] = 1;
    }
  }
}

uint64_t sap_find_pairs(const SapView& v, Pair* IMPACT_RESTRICT out, uint64_t capacity, Range r) {
  return v.layer ? sweep<true>(v, out, capacity, r) : sweep<false>(v, out, capacity, r);
}

}  // namespace impact::kernels
