#include "host/radix_sort.h"

#include <algorithm>
#include <cstring>
#include <utility>

#include "kernels/sort/radix_sort.h"

namespace impact::host {

void RadixSorter::sort(const Executor& exec, uint64_t* keys, uint32_t n, uint32_t lo_bit,
                       uint32_t hi_bit) {
  sort_impl<false>(exec, keys, nullptr, n, lo_bit, hi_bit);
}

void RadixSorter::sort_kv(const Executor& exec, uint64_t* keys, uint32_t* values, uint32_t n,
                          uint32_t lo_bit, uint32_t hi_bit) {
  sort_impl<true>(exec, keys, values, n, lo_bit, hi_bit);
}

template <bool kWithValues>
void RadixSorter::sort_impl(const Executor& exec, uint64_t* keys, uint32_t* values, uint32_t n,
                            uint32_t lo_bit, uint32_t hi_bit) {
  if (n < 2 || hi_bit <= lo_bit) return;
  using kernels::kRadixBuckets;
  const uint32_t chunks = chunk_count(n, kGrain);
  uint32_t* hist = scratch(hist_, static_cast<size_t>(chunks) * kRadixBuckets);
  uint64_t* src = keys;
  uint64_t* dst = scratch(tmp_, n);
  uint32_t* vsrc = values;
  uint32_t* vdst = kWithValues ? scratch(tmp_values_, n) : nullptr;
  hi_bit = std::min<uint32_t>(hi_bit, 64);
  // The fewest passes of at most kRadixMaxBits, equally wide: each pass reads the keys
  // twice and scatters them once, so a pass saved (30 bits: 3 x 10 instead of 4 x 8)
  // is worth the wider histograms; below kWideDigits keys, whose passes cost less than
  // clearing and scanning 2048-entry histograms, 8-bit digits.
  const uint32_t max_bits = n >= kWideDigits ? kernels::kRadixMaxBits : 8;
  const uint32_t passes = (hi_bit - lo_bit + max_bits - 1) / max_bits;
  const uint32_t width = (hi_bit - lo_bit + passes - 1) / passes;
  for (uint32_t shift = lo_bit; shift < hi_bit; shift += width) {
    const uint32_t bits = std::min(width, hi_bit - shift);
    const kernels::RadixDigit digit{shift, (1u << bits) - 1};
    exec.for_each_chunk(n, kGrain, [&](uint32_t b, uint32_t e, uint32_t c) {
      kernels::radix_histogram(src, digit, hist + static_cast<size_t>(c) * kRadixBuckets, {b, e});
    });
    if (kernels::radix_offsets(hist, digit.mask, chunks, n)) continue;  // one digit value: order unchanged
    exec.for_each_chunk(n, kGrain, [&](uint32_t b, uint32_t e, uint32_t c) {
      uint32_t* off = hist + static_cast<size_t>(c) * kRadixBuckets;
      if constexpr (kWithValues) kernels::radix_scatter_kv(src, vsrc, digit, off, dst, vdst, {b, e});
      else kernels::radix_scatter(src, digit, off, dst, {b, e});
    });
    std::swap(src, dst);
    if constexpr (kWithValues) std::swap(vsrc, vdst);
  }
  if (src != keys) {
    exec.for_each_chunk(n, kGrain, [&](uint32_t b, uint32_t e, uint32_t) {
      std::memcpy(keys + b, src + b, sizeof(uint64_t) * (e - b));
      if constexpr (kWithValues) std::memcpy(values + b, vsrc + b, sizeof(uint32_t) * (e - b));
    });
  }
}

}  // namespace impact::host
