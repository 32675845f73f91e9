#include "kernels/sort/radix_sort.h"

namespace impact::kernels {

void radix_histogram(const uint64_t* IMPACT_RESTRICT keys, RadixDigit digit, uint32_t* out_hist, Range r) {
  const uint32_t shift = digit.shift;
  const uint64_t m = digit.mask;
  // Four interleaved sub-histograms break the store-to-load dependency on hot digits.
  const uint32_t buckets = digit.mask + 1;
  uint32_t h[4][kRadixBuckets];
  for (uint32_t j = 0; j < 4; ++j)
    for (uint32_t d = 0; d < buckets; ++d) h[j][d] = 0;
  uint32_t i = r.begin;
  for (; i + 4 <= r.end; i += 4) {
    ++h[0][(keys[i + 0] >> shift) & m];
    ++h[1][(keys[i + 1] >> shift) & m];
    ++h[2][(keys[i + 2] >> shift) & m];
    ++h[3][(keys[i + 3] >> shift) & m];
  }
  for (; i < r.end; ++i) ++h[0][(keys[i] >> shift) & m];
  for (uint32_t d = 0; d < buckets; ++d) out_hist[d] = h[0][d] + h[1][d] + h[2][d] + h[3][d];
}

bool radix_offsets(uint32_t* io_hist, uint32_t mask, uint32_t chunk_count, uint64_t n) {
  uint32_t running = 0;
  bool single = false;
  for (uint32_t d = 0; d <= mask; ++d) {
    uint64_t digit_total = 0;
    for (uint32_t c = 0; c < chunk_count; ++c) {
      uint32_t& slot = io_hist[static_cast<uint64_t>(c) * kRadixBuckets + d];
      const uint32_t count = slot;
      slot = running;
      running += count;
      digit_total += count;
    }
    if (digit_total == n) single = true;
  }
  return single;
}

void radix_scatter(const uint64_t* IMPACT_RESTRICT keys, RadixDigit digit, uint32_t* io_offsets,
                   uint64_t* IMPACT_RESTRICT out_keys, Range r) {
  const uint32_t shift = digit.shift;
  const uint64_t m = digit.mask;
  for (uint32_t i = r.begin; i < r.end; ++i) {
    const uint64_t k = keys[i];
    out_keys[io_offsets[(k >> shift) & m]++] = k;
  }
}

void radix_scatter_kv(const uint64_t* IMPACT_RESTRICT keys, const uint32_t* IMPACT_RESTRICT values,
                      RadixDigit digit, uint32_t* io_offsets, uint64_t* IMPACT_RESTRICT out_keys,
                      uint32_t* IMPACT_RESTRICT out_values, Range r) {
  const uint32_t shift = digit.shift;
  const uint64_t m = digit.mask;
  for (uint32_t i = r.begin; i < r.end; ++i) {
    const uint64_t k = keys[i];
    const uint32_t dst = io_offsets[(k >> shift) & m]++;
    out_keys[dst] = k;
    out_values[dst] = values[i];
  }
}

}  // namespace impact::kernels
