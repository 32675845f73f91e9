// simd::box_halves_overlap (kernels/simd/box_overlap.h) against the six plain
// comparisons, on boxes with small integer corners (so touching faces are common) and
// a spare lane holding anything (NaN included): the verb ignores lane 3, and the SSE
// path and the one-lane (-DIMPACT_SIMD_SCALAR) path give the same answer.
#include "kernels/simd/box_overlap.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <random>

namespace impact::kernels::simd {
namespace {

struct alignas(16) Half {
  float v[4];
};

TEST(BoxOverlap, MatchesPlainComparisons) {
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> coord(-4, 4), spare(0, 3);
  const float spares[4] = {0.0f, -1e30f, 1e30f, NAN};
  uint32_t hits = 0;
  for (int trial = 0; trial < 20000; ++trial) {
    Half lo[2], hi[2];
    for (int s = 0; s < 2; ++s) {
      for (int k = 0; k < 3; ++k) {
        const float a = static_cast<float>(coord(rng)) * 0.5f, b = static_cast<float>(coord(rng)) * 0.5f;
        lo[s].v[k] = std::fmin(a, b);
        hi[s].v[k] = std::fmax(a, b);
      }
      lo[s].v[3] = spares[spare(rng)];
      hi[s].v[3] = spares[spare(rng)];
    }
    bool want = true;
    for (int k = 0; k < 3; ++k) want = want && lo[0].v[k] <= hi[1].v[k] && lo[1].v[k] <= hi[0].v[k];
    const bool got = box_halves_overlap(lo[0].v, hi[0].v, lo[1].v, hi[1].v);
    ASSERT_EQ(got, want) << "trial " << trial;
    hits += got ? 1u : 0u;
  }
  EXPECT_GT(hits, 1000u);  // both answers exercised
  EXPECT_LT(hits, 19000u);
}

}  // namespace
}  // namespace impact::kernels::simd
