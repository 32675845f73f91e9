// Checks shared by the lane-kernel tests: a lane's output depends only on its own inputs.
//   expect_partition_invariant  the same bytes for every split of the lane range and for
//                               a shuffled bucket (each lane among other neighbours, in
//                               other SIMD vectors and blocks)
//   expect_chunk_invariant      the same bytes when the range is run in many small
//                               chunks (random partitions) and lane by lane
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <initializer_list>
#include <numeric>
#include <random>
#include <vector>

namespace impact::test {

/// run(qs, begin, end) gives one result per query (those outside [begin, end) unused);
/// same(x, y) says whether two results are the same bytes. Every lane of qs split at
/// each cut, and of a shuffled copy of qs (drawn from g), must equal the whole run's.
template <class Query, class Run, class Same>
void expect_partition_invariant(const std::vector<Query>& qs, std::initializer_list<uint32_t> cuts, Run run,
                                Same same, std::mt19937& g) {
  const uint32_t n = static_cast<uint32_t>(qs.size());
  const auto all = run(qs, 0u, n);
  for (uint32_t cut : cuts) {
    ASSERT_LE(cut, n);
    const auto lo = run(qs, 0u, cut), hi = run(qs, cut, n);
    for (uint32_t k = 0; k < n; ++k)
      EXPECT_TRUE(same(k < cut ? lo[k] : hi[k], all[k])) << "cut " << cut << " lane " << k;
  }
  std::vector<uint32_t> perm(n);
  std::iota(perm.begin(), perm.end(), 0u);
  std::shuffle(perm.begin(), perm.end(), g);
  std::vector<Query> shuffled(n);
  for (uint32_t k = 0; k < n; ++k) shuffled[k] = qs[perm[k]];
  const auto sh = run(shuffled, 0u, n);
  for (uint32_t k = 0; k < n; ++k) EXPECT_TRUE(same(sh[k], all[perm[k]])) << "shuffled lane " << k;
}

/// The same run (see expect_partition_invariant) over `reps` random partitions of the
/// lanes into ranges of 1..max_chunk lanes (drawn from g), and once lane by lane: every
/// lane must equal the whole run's.
template <class Query, class Run, class Same>
void expect_chunk_invariant(const std::vector<Query>& qs, Run run, Same same, std::mt19937& g, int reps = 4,
                            uint32_t max_chunk = 13) {
  const uint32_t n = static_cast<uint32_t>(qs.size());
  const auto all = run(qs, 0u, n);
  for (int rep = 0; rep <= reps; ++rep) {
    const bool single = rep == reps;
    for (uint32_t b = 0; b < n;) {
      const uint32_t e = single ? b + 1 : std::min(n, b + 1 + static_cast<uint32_t>(g() % max_chunk));
      const auto part = run(qs, b, e);
      for (uint32_t k = b; k < e; ++k)
        EXPECT_TRUE(same(part[k], all[k]))
            << (single ? "lane by lane" : "chunks") << " [" << b << ", " << e << ") lane " << k;
      b = e;
    }
  }
}

}  // namespace impact::test
