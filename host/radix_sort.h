// Parallel LSD radix sort of 64-bit keys (kernels/sort/radix_sort.h) driven on an
// Executor. Sorts on bits [lo_bit, hi_bit); keys enter in the order that must win
// ties (by convention their low 32 bits hold the original index), and the result
// is the same bytes for any thread count. Passes whose digit is constant are skipped.
// The range is split into the fewest passes of equal width (at most 11 bits; 8 for
// small sorts).
#pragma once

#include <cstdint>

#include "host/buffer.h"
#include "host/parallel.h"

namespace impact::host {

class RadixSorter {
 public:
  /// Sorts keys[0, n) in place (tmp is scratch of n keys, grown as needed).
  void sort(const Executor& exec, uint64_t* keys, uint32_t n, uint32_t lo_bit, uint32_t hi_bit);

  /// Sorts keys[0, n) and moves values[0, n) with them.
  void sort_kv(const Executor& exec, uint64_t* keys, uint32_t* values, uint32_t n, uint32_t lo_bit,
               uint32_t hi_bit);

  /// Keys per chunk; fixed, so chunking does not depend on the thread count.
  static constexpr uint32_t kGrain = 1u << 16;
  /// Keys from which the passes use digits of up to kernels::kRadixMaxBits (else 8).
  static constexpr uint32_t kWideDigits = 1u << 15;

 private:
  template <bool kWithValues>
  void sort_impl(const Executor& exec, uint64_t* keys, uint32_t* values, uint32_t n, uint32_t lo_bit,
                 uint32_t hi_bit);

  Buffer<uint64_t> tmp_;
  Buffer<uint32_t> tmp_values_;
  Buffer<uint32_t> hist_;
};

/// Number of bits needed to represent values in [0, max_value].
inline uint32_t bits_for(uint64_t max_value) {
  uint32_t b = 0;
  while (b < 64 && (max_value >> b) != 0) ++b;
  return b;
}

}  // namespace impact::host
