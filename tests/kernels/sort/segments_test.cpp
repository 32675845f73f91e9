// segment_starts (kernels/sort/segments.*) against a brute-force reference:
// start[s] = first position whose id (key >> shift) is >= s, for s in [0, segments].
// The kernel must be correct for any partition of the positions into ranges.
#include "kernels/sort/segments.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <vector>

namespace impact {
namespace {

std::vector<uint32_t> reference_starts(const std::vector<uint64_t>& keys, uint32_t shift, uint32_t segments) {
  std::vector<uint32_t> start(segments + 1);
  for (uint32_t s = 0; s <= segments; ++s) {
    uint32_t i = 0;
    while (i < keys.size() && (keys[i] >> shift) < s) ++i;
    start[s] = i;
  }
  return start;
}

// Runs the kernel over the given cut points (ranges [cuts[k], cuts[k+1]), in a
// shuffled order to show the ranges are independent).
std::vector<uint32_t> run(const std::vector<uint64_t>& keys, uint32_t shift, uint32_t segments,
                          std::vector<uint32_t> cuts, uint32_t seed) {
  std::vector<uint32_t> start(segments + 1, 0xdeadbeefu);
  const uint32_t n = static_cast<uint32_t>(keys.size());
  std::vector<kernels::Range> ranges;
  for (size_t k = 0; k + 1 < cuts.size(); ++k) ranges.push_back({cuts[k], cuts[k + 1]});
  std::shuffle(ranges.begin(), ranges.end(), std::mt19937(seed));
  if (n == 0) ranges = {{0, segments + 1}};  // documented: the single range fills the table
  for (const kernels::Range& r : ranges)
    kernels::segment_starts(keys.data(), n, shift, segments, start.data(), r);
  return start;
}

TEST(SegmentStarts, RandomSortedIdsWithGapsAnyPartition) {
  std::mt19937 rng(1);
  for (int trial = 0; trial < 50; ++trial) {
    const uint32_t segments = 1 + static_cast<uint32_t>(rng() % 300);
    const uint32_t n = static_cast<uint32_t>(rng() % 2000);
    std::vector<uint64_t> keys(n);
    // Skewed ids: many empty segments, long runs.
    for (uint32_t i = 0; i < n; ++i) {
      const uint32_t id =
          static_cast<uint32_t>(std::min<uint64_t>(segments - 1, (rng() % segments) * (rng() % 2)));
      keys[i] = (static_cast<uint64_t>(id) << 32) | i;
    }
    std::sort(keys.begin(), keys.end());
    std::vector<uint32_t> cuts{0};
    for (uint32_t i = 1; i < n; ++i)
      if (rng() % 97 == 0) cuts.push_back(i);
    cuts.push_back(n);
    EXPECT_EQ(run(keys, 32, segments, cuts, trial), reference_starts(keys, 32, segments))
        << "trial " << trial;
  }
}

TEST(SegmentStarts, SentinelSegmentAndEmptyInput) {
  // Ids may equal `segments` (the solver's static-body sentinel).
  std::vector<uint64_t> keys{0ull << 32, 2ull << 32, 2ull << 32, 5ull << 32, 5ull << 32};
  EXPECT_EQ(run(keys, 32, 5, {0, 2, 5}, 1), reference_starts(keys, 32, 5));
  EXPECT_EQ(run(keys, 32, 5, {0, 5}, 1), (std::vector<uint32_t>{0, 1, 1, 3, 3, 3}));
  std::vector<uint64_t> none;
  EXPECT_EQ(run(none, 32, 4, {0, 0}, 1), (std::vector<uint32_t>{0, 0, 0, 0, 0}));
}

TEST(SegmentStarts, AllInOneSegment) {
  std::vector<uint64_t> keys(100, 3ull << 32);
  EXPECT_EQ(run(keys, 32, 8, {0, 10, 50, 100}, 2), reference_starts(keys, 32, 8));
}

}  // namespace
}  // namespace impact
