// LSD radix sort (kernels/sort/radix_sort.*, driven by host::RadixSorter) against
// std::stable_sort on the documented sort field: bits [lo_bit, hi_bit) of each
// 64-bit key, ties keeping input order. Keys follow the library's convention
// (primary key high, original index in the low 32 bits) unless a test says
// otherwise. The output must be the same bytes for every thread count and backend.
#include "host/radix_sort.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <random>
#include <utility>
#include <vector>

#include "host/parallel.h"
#include "kernels/sort/radix_sort.h"
#include "support/test_support.h"

namespace impact {
namespace {

uint64_t field(uint64_t key, uint32_t lo, uint32_t hi) {
  const uint32_t width = hi - lo;
  const uint64_t mask = width >= 64 ? ~0ull : ((1ull << width) - 1);
  return (key >> lo) & mask;
}

std::vector<uint64_t> reference_sort(std::vector<uint64_t> keys, uint32_t lo, uint32_t hi) {
  std::stable_sort(keys.begin(), keys.end(),
                   [&](uint64_t a, uint64_t b) { return field(a, lo, hi) < field(b, lo, hi); });
  return keys;
}

std::vector<uint64_t> radix(std::vector<uint64_t> keys, uint32_t lo, uint32_t hi,
                            const host::Executor& exec = host::Executor(Backend::kSerial, 1)) {
  host::RadixSorter sorter;
  sorter.sort(exec, keys.data(), static_cast<uint32_t>(keys.size()), lo, hi);
  return keys;
}

// primary(i) in the high half, index in the low half.
template <class Primary>
std::vector<uint64_t> indexed_keys(uint32_t n, Primary&& primary) {
  std::vector<uint64_t> k(n);
  for (uint32_t i = 0; i < n; ++i) k[i] = (static_cast<uint64_t>(primary(i)) << 32) | i;
  return k;
}

TEST(RadixSort, RandomPrimaryKeys) {
  std::mt19937_64 rng(1);
  for (uint32_t n : {2u, 3u, 255u, 256u, 1000u, test::scaled(100000)}) {
    const auto keys = indexed_keys(n, [&](uint32_t) { return static_cast<uint32_t>(rng()); });
    EXPECT_EQ(radix(keys, 32, 64), reference_sort(keys, 32, 64)) << "n=" << n;
  }
}

TEST(RadixSort, FullyRandom64BitKeys) {
  std::mt19937_64 rng(2);
  std::vector<uint64_t> keys(test::scaled(50000));
  for (auto& k : keys) k = rng();
  EXPECT_EQ(radix(keys, 0, 64), reference_sort(keys, 0, 64));
}

TEST(RadixSort, DuplicatePrimaryKeysAreStable) {
  std::mt19937_64 rng(3);
  const uint32_t n = test::scaled(200000);  // several 2^16-key chunks
  const auto keys = indexed_keys(n, [&](uint32_t) { return static_cast<uint32_t>(rng() % 16); });
  const auto sorted = radix(keys, 32, 36);
  EXPECT_EQ(sorted, reference_sort(keys, 32, 36));
  // Stability made explicit: within equal primaries, indices ascend.
  for (size_t i = 1; i < sorted.size(); ++i) {
    if ((sorted[i] >> 32) == (sorted[i - 1] >> 32)) {
      ASSERT_LT(static_cast<uint32_t>(sorted[i - 1]), static_cast<uint32_t>(sorted[i]));
    }
  }
}

TEST(RadixSort, AllEqualKeys) {
  const auto keys = indexed_keys(test::scaled(70000), [](uint32_t) { return 0xabcdu; });
  EXPECT_EQ(radix(keys, 32, 64), keys);
  std::vector<uint64_t> same(1000, 0x1234567812345678ull);
  EXPECT_EQ(radix(same, 0, 64), same);
}

TEST(RadixSort, ZeroAndOneKeys) {
  host::RadixSorter sorter;
  host::Executor exec(Backend::kSerial, 1);
  sorter.sort(exec, nullptr, 0, 0, 64);  // must not touch memory
  std::vector<uint64_t> one{0xdeadbeef00000000ull};
  sorter.sort(exec, one.data(), 1, 0, 64);
  EXPECT_EQ(one[0], 0xdeadbeef00000000ull);
  std::vector<uint64_t> empty;
  EXPECT_EQ(radix(empty, 32, 64), empty);
}

TEST(RadixSort, EmptyBitRangeLeavesOrder) {
  std::mt19937_64 rng(4);
  std::vector<uint64_t> keys(1000);
  for (auto& k : keys) k = rng();
  EXPECT_EQ(radix(keys, 32, 32), keys);
}

TEST(RadixSort, BitRanges) {
  // Sort fields of every width from 1 to 32 bits, including widths that are not a
  // multiple of any digit width, with 8-bit digits (fewer than kWideDigits keys) and
  // with the wide ones (up to 11 bits, passes of equal width: 30 bits as 3 x 10, 31
  // as 11 + 11 + 9). Bits at and above hi are zero (the library's callers size hi
  // with bits_for(max key)); bits below lo are random payload.
  std::mt19937_64 rng(5);
  for (uint32_t n : {test::scaled(20000), host::RadixSorter::kWideDigits + 999}) {
    for (uint32_t lo : {0u, 3u, 32u}) {
      for (uint32_t width : {1u, 5u, 7u, 8u, 9u, 11u, 12u, 13u, 16u, 21u, 22u, 24u, 30u, 31u, 32u}) {
        const uint32_t hi = lo + width;
        std::vector<uint64_t> keys(n);
        for (auto& k : keys) {
          const uint64_t f = rng() & ((1ull << width) - 1);
          const uint64_t below = lo == 0 ? 0 : (rng() & ((1ull << lo) - 1));
          k = (f << lo) | below;
        }
        EXPECT_EQ(radix(keys, lo, hi), reference_sort(keys, lo, hi))
            << "bits [" << lo << ", " << hi << ") n " << n;
      }
    }
  }
}

TEST(RadixSort, BitsAboveHiBitAreNotSortedOn) {
  // host/radix_sort.h: "Sorts on bits [lo_bit, hi_bit)". Keys whose bits at or
  // above hi_bit are set (payload the caller did not ask to sort on) must keep
  // their input order among equal [lo, hi) fields: the last pass's digit is cut at
  // hi_bit. With 8-bit digits and with the wide ones.
  std::mt19937_64 rng(6);
  for (uint32_t n : {4096u, host::RadixSorter::kWideDigits + 4096}) {
    std::vector<uint64_t> keys(n);
    for (auto& k : keys) k = rng();
    for (auto [lo, hi] : {std::pair{32u, 45u}, std::pair{0u, 4u}, std::pair{8u, 12u}, std::pair{32u, 62u}})
      EXPECT_EQ(radix(keys, lo, hi), reference_sort(keys, lo, hi))
          << "bits [" << lo << ", " << hi << ") n " << n;
  }
}

TEST(RadixSort, SkipsConstantDigitsCorrectly) {
  // Digits 0, 2 and 3 are constant (their passes are skipped); digit 1 varies.
  std::mt19937_64 rng(7);
  std::vector<uint64_t> keys(test::scaled(100000));
  for (auto& k : keys) k = 0x5a00000000ull | ((rng() & 0xff) << 8) | 0x11;
  EXPECT_EQ(radix(keys, 0, 40), reference_sort(keys, 0, 40));
}

TEST(RadixSort, SameBytesForEveryThreadCountAndBackend) {
  std::mt19937_64 rng(8);
  const uint32_t n = test::scaled(300000) + 17;  // > 4 chunks of 2^16, ragged tail
  const auto keys = indexed_keys(n, [&](uint32_t) { return static_cast<uint32_t>(rng() % 100000); });
  const auto expected = reference_sort(keys, 32, 49);
  for (const test::ExecCase& c : test::exec_cases()) {
    host::Executor exec(c.backend, c.threads);
    EXPECT_EQ(radix(keys, 32, 49, exec), expected) << test::to_string(c);
    // A sorter reused across calls (scratch already grown) too.
    host::RadixSorter sorter;
    std::vector<uint64_t> a = keys, b = keys;
    sorter.sort(exec, a.data(), n, 32, 49);
    sorter.sort(exec, b.data(), n, 32, 49);
    EXPECT_EQ(a, expected) << test::to_string(c);
    EXPECT_EQ(b, expected) << test::to_string(c);
  }
}

TEST(RadixSort, KeyValueSortMovesValuesWithKeys) {
  // sort_kv: the values follow their keys; stable, so equal keys keep input order.
  std::mt19937_64 rng(10);
  for (uint32_t n : {0u, 1u, 2u, 1000u, test::scaled(150000)}) {
    std::vector<uint64_t> keys(n);
    std::vector<uint32_t> values(n);
    std::vector<std::pair<uint64_t, uint32_t>> ref(n);
    for (uint32_t i = 0; i < n; ++i) {
      keys[i] = (rng() % 5000) << 20 | (rng() & 0xfffff);  // duplicates in the sorted field
      values[i] = static_cast<uint32_t>(rng());
      ref[i] = {keys[i], values[i]};
    }
    std::stable_sort(ref.begin(), ref.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
    for (const test::ExecCase& c : test::exec_cases()) {
      host::Executor exec(c.backend, c.threads);
      host::RadixSorter sorter;
      std::vector<uint64_t> k = keys;
      std::vector<uint32_t> v = values;
      sorter.sort_kv(exec, k.data(), v.data(), n, 0, 64);
      bool same = true;
      for (uint32_t i = 0; i < n && same; ++i) same = k[i] == ref[i].first && v[i] == ref[i].second;
      EXPECT_TRUE(same) << "n=" << n << " " << test::to_string(c);
    }
  }
}

TEST(RadixSort, KernelOffsetsAcrossChunks) {
  // radix_histogram + radix_offsets + radix_scatter by hand over uneven ranges:
  // one stable pass on the low byte equals a stable sort on that byte.
  std::mt19937_64 rng(9);
  std::vector<uint64_t> keys(5000), out(5000);
  for (auto& k : keys) k = rng();
  const std::vector<kernels::Range> ranges{{0, 1}, {1, 700}, {700, 701}, {701, 4999}, {4999, 5000}};
  std::vector<uint32_t> hist(ranges.size() * kernels::kRadixBuckets);
  for (size_t c = 0; c < ranges.size(); ++c)
    kernels::radix_histogram(keys.data(), kernels::RadixDigit{0, 0xff}, hist.data() + c * kernels::kRadixBuckets, ranges[c]);
  EXPECT_FALSE(kernels::radix_offsets(hist.data(), 0xff, static_cast<uint32_t>(ranges.size()), keys.size()));
  for (size_t c = 0; c < ranges.size(); ++c)
    kernels::radix_scatter(keys.data(), kernels::RadixDigit{0, 0xff}, hist.data() + c * kernels::kRadixBuckets, out.data(), ranges[c]);
  EXPECT_EQ(out, reference_sort(keys, 0, 8));
}

TEST(RadixSort, BitsFor) {
  EXPECT_EQ(host::bits_for(0), 0u);
  EXPECT_EQ(host::bits_for(1), 1u);
  EXPECT_EQ(host::bits_for(2), 2u);
  EXPECT_EQ(host::bits_for(255), 8u);
  EXPECT_EQ(host::bits_for(256), 9u);
  EXPECT_EQ(host::bits_for(~0ull), 64u);
}

}  // namespace
}  // namespace impact
