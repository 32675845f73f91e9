// LSD radix sort building blocks for 64-bit keys, one digit of up to 11 bits per pass.
//
// A pass over n keys split into chunks (fixed by n and a grain, never by the
// thread count) is:
//   1. radix_histogram  per chunk: count of each digit value in the chunk;
//   2. radix_offsets    once (serial, (mask + 1) x chunks): exclusive scan in
//      digit-major, chunk-minor order -> where each chunk writes each digit;
//   3. radix_scatter    per chunk: stable scatter of the chunk's keys.
// Because chunk c's keys with digit d land after those of chunks < c, the sort
// is stable and its output bytes are the same for any number of workers.
// Keys carry their payload: by convention the primary key sits in the high bits
// and the original index in the low 32, so every tie has one defined winner.
// Cost per pass: two reads and one scattered write of the keys.
// Method: classic LSD radix sort (Knuth TAOCP vol. 3, 5.2.5); the per-chunk
// histogram layout follows GPU radix sorts (Merrill & Grimshaw 2011).
#pragma once

#include "kernels/common/kernel.h"

namespace impact::kernels {

/// Widest digit; the driver splits a sort range into the fewest passes of at most this
/// many bits, of equal width (30 bits: 3 x 10, 32 bits: 11 + 11 + 10).
inline constexpr uint32_t kRadixMaxBits = 11;
/// Histogram entries per chunk (the widest digit's values).
inline constexpr uint32_t kRadixBuckets = 1u << kRadixMaxBits;

/// One pass's digit: (key >> shift) & mask, mask = 2^bits - 1 with bits <= kRadixMaxBits
/// (the last pass narrower where the range ends, so bits above it never affect the order).
struct RadixDigit {
  uint32_t shift;
  uint32_t mask;
};

/// out_hist[d] = number of keys in r whose digit is d (d <= digit.mask; those entries
/// overwritten).
void radix_histogram(const uint64_t* IMPACT_RESTRICT keys, RadixDigit digit, uint32_t* out_hist, Range r);

/// Turns chunk histograms (chunk-major: hist[c * kRadixBuckets + d], d <= mask) into
/// scatter offsets in place. Returns true when one digit value holds every key (the pass
/// can be skipped).
bool radix_offsets(uint32_t* io_hist, uint32_t mask, uint32_t chunk_count, uint64_t n);

/// Stable scatter of the keys of r to out_keys at the chunk's offsets (mask + 1
/// entries, advanced in place).
void radix_scatter(const uint64_t* IMPACT_RESTRICT keys, RadixDigit digit, uint32_t* io_offsets,
                   uint64_t* IMPACT_RESTRICT out_keys, Range r);

/// radix_scatter that moves a 32-bit value with each key.
void radix_scatter_kv(const uint64_t* IMPACT_RESTRICT keys, const uint32_t* IMPACT_RESTRICT values,
                      RadixDigit digit, uint32_t* io_offsets, uint64_t* IMPACT_RESTRICT out_keys,
                      uint32_t* IMPACT_RESTRICT out_values, Range r);

}  // namespace impact::kernels
