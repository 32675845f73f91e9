// The lane reductions of kernels/simd/lanes.h (all_lanes, max_lowest_index) against a
// brute-force loop over the lanes, at every width the vocabulary has (1, 4, 8, 16),
// on random scores with many exact ties (small integers), -inf lanes and shuffled
// indices: the maximum, and the lowest index among the lanes that hold it; and
// compact_store / expand_store against a loop over the set bits; bits_lt and load_clamped
// against a loop.
#include "kernels/simd/lanes.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <random>
#include <vector>

namespace impact::kernels::simd {
namespace {

template <uint32_t N>
void check_reductions(uint32_t seed) {
  using F = FloatN<N>;
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> small(-3, 3), pick(0, 9);
  for (int trial = 0; trial < 2000; ++trial) {
    float s[N], idx[N];
    for (uint32_t k = 0; k < N; ++k) {
      s[k] = pick(rng) == 0 ? -INFINITY : static_cast<float>(small(rng)) * 0.5f;
      idx[k] = static_cast<float>(k);
    }
    std::shuffle(idx, idx + N, rng);
    float want_max = -INFINITY, want_idx = 1e9f;
    for (uint32_t k = 0; k < N; ++k) want_max = std::max(want_max, s[k]);
    for (uint32_t k = 0; k < N; ++k)
      if (s[k] == want_max) want_idx = std::min(want_idx, idx[k]);
    float got_idx = -1.0f;
    const float got_max = max_lowest_index(F::load(s), F::load(idx), 1e9f, &got_idx);
    ASSERT_EQ(got_max, want_max) << "width " << N << " trial " << trial;
    ASSERT_EQ(got_idx, want_idx) << "width " << N << " trial " << trial;
    if constexpr (N > 1) {
      const F mx = all_lanes(F::load(s), [](F a, F b) { return max(a, b); });
      const F mn = all_lanes(F::load(idx), [](F a, F b) { return min(a, b); });
      for (uint32_t k = 0; k < N; ++k) {
        ASSERT_EQ(mx.lane(k), want_max) << "width " << N << " lane " << k;
        ASSERT_EQ(mn.lane(k), 0.0f) << "width " << N << " lane " << k;
      }
    }
  }
}

TEST(Lanes, AllLanesAndMaxLowestIndexMatchALoop) {
  check_reductions<1>(1);
  check_reductions<4>(2);
  check_reductions<8>(3);
  check_reductions<16>(4);
}

/// compact_store and expand_store against a plain loop over every mask (N <= 8) or
/// random masks (N = 16): the set lanes in order, the count, and the round trip.
template <uint32_t N>
void check_compact_expand(uint32_t seed) {
  std::mt19937 g(seed);
  int32_t src[N];
  for (uint32_t l = 0; l < N; ++l) src[l] = static_cast<int32_t>(g() % 100000) - 50000;
  const IntN<N> v = IntN<N>::load(src);
  const IntN<N> ids = lane_ids<IntN<N>>(-3);
  for (uint32_t l = 0; l < N; ++l) ASSERT_EQ(ids.lane(l), static_cast<int32_t>(l) - 3) << "width " << N;
  const uint32_t masks = N <= 8 ? (1u << N) : 4096u;
  for (uint32_t t = 0; t < masks; ++t) {
    const uint32_t bits = N <= 8 ? t : (t < 2 ? (t == 0 ? 0u : (1u << N) - 1u) : g() & ((1u << N) - 1u));
    int32_t want[N], got[N + 1];
    uint32_t cnt = 0;
    for (uint32_t l = 0; l < N; ++l)
      if ((bits >> l) & 1u) want[cnt++] = src[l];
    got[N] = 777;  // past the N entries it may write
    ASSERT_EQ(compact_store(got, v, bits), cnt) << "width " << N << " bits " << bits;
    for (uint32_t i = 0; i < cnt; ++i) ASSERT_EQ(got[i], want[i]) << "width " << N << " bits " << bits;
    ASSERT_EQ(got[N], 777);
    float packed[N], back[N];
    for (uint32_t i = 0; i < N; ++i) packed[i] = static_cast<float>(got[i]), back[i] = -1.0f;
    expand_store<N>(back, packed, bits);
    for (uint32_t l = 0; l < N; ++l)
      ASSERT_EQ(back[l], (bits >> l) & 1u ? static_cast<float>(src[l]) : -1.0f) << "width " << N;
  }
}

TEST(Lanes, CompactAndExpandMatchALoop) {
  check_compact_expand<1>(5);
  check_compact_expand<4>(6);
  check_compact_expand<8>(7);
  check_compact_expand<16>(8);
}

/// bits_lt(a, b) against the lane-by-lane comparison: ties, signed zeros, infinities and
/// NaN (false either side).
template <uint32_t N>
void check_bits_lt(uint32_t seed) {
  std::mt19937 g(seed);
  const float pool[] = {-INFINITY, -1.5f, -0.0f, 0.0f, 1e-38f, 0.5f, 0.5f, 2.0f, INFINITY, NAN};
  for (int trial = 0; trial < 4000; ++trial) {
    float a[N], b[N];
    uint32_t want = 0;
    for (uint32_t l = 0; l < N; ++l) {
      a[l] = pool[g() % 10], b[l] = pool[g() % 10];
      want |= (a[l] < b[l] ? 1u : 0u) << l;
    }
    ASSERT_EQ(bits_lt(FloatN<N>::load(a), FloatN<N>::load(b)), want) << "width " << N;
  }
}

TEST(Lanes, BitsLtMatchesALoop) {
  check_bits_lt<1>(11);
  check_bits_lt<4>(12);
  check_bits_lt<8>(13);
  check_bits_lt<16>(14);
}

/// load_clamped against the lane-by-lane clamp: every block start of arrays of 1 .. 3N
/// items (the permuted tail where n >= N, the scalar one below), each inside a buffer
/// of guard values (-1), so a lane that read past the array's last item would fail.
template <uint32_t N>
void check_load_clamped() {
  float buf[4 * N + 8];
  for (uint32_t n = 1; n <= 3 * N; ++n) {
    float* p = buf + 2;
    for (uint32_t k = 0; k < 4 * N + 8; ++k) buf[k] = -1.0f;
    for (uint32_t k = 0; k < n; ++k) p[k] = static_cast<float>(k) + 0.25f;
    for (uint32_t i = 0; i < n; ++i) {
      const FloatN<N> v = load_clamped<FloatN<N>>(p, i, n);
      for (uint32_t l = 0; l < N; ++l)
        ASSERT_EQ(v.lane(l), p[std::min(i + l, n - 1)]) << "width " << N << " n " << n << " i " << i;
    }
  }
}

TEST(Lanes, LoadClampedMatchesALoop) {
  check_load_clamped<1>();
  check_load_clamped<4>();
  check_load_clamped<8>();
  check_load_clamped<16>();
}

/// gather_xyz against reading the records lane by lane: random indices (repeats
/// included) into 40 distinct records, from a base that is not 16-byte aligned.
template <uint32_t N>
void check_gather_xyz(uint32_t seed) {
  std::mt19937 g(seed);
  float buf[4 * 40 + 1];
  float* rec = buf + 1;
  for (uint32_t k = 0; k < 4 * 40; ++k) rec[k] = static_cast<float>(k) + 0.5f;
  for (int round = 0; round < 200; ++round) {
    int32_t idx[N];
    for (uint32_t l = 0; l < N; ++l) idx[l] = static_cast<int32_t>(g() % 40);
    FloatN<N> x, y, z;
    gather_xyz(rec, idx, &x, &y, &z);
    for (uint32_t l = 0; l < N; ++l) {
      ASSERT_EQ(x.lane(l), rec[4 * idx[l]]) << "width " << N << " lane " << l;
      ASSERT_EQ(y.lane(l), rec[4 * idx[l] + 1]) << "width " << N << " lane " << l;
      ASSERT_EQ(z.lane(l), rec[4 * idx[l] + 2]) << "width " << N << " lane " << l;
    }
  }
}

/// gather4 against reading the records lane by lane: records of 12 floats, the four read
/// at offsets 0, 4 and 8 (as sat.cpp's edge records), random indices, an unaligned base.
template <uint32_t N>
void check_gather4(uint32_t seed) {
  std::mt19937 g(seed);
  float buf[12 * 30 + 1];
  float* rec = buf + 1;
  for (uint32_t k = 0; k < 12 * 30; ++k) rec[k] = static_cast<float>(k) - 100.25f;
  for (int round = 0; round < 200; ++round) {
    int32_t idx[N];
    for (uint32_t l = 0; l < N; ++l) idx[l] = static_cast<int32_t>(g() % 30);
    for (uint32_t at = 0; at < 12; at += 4) {
      FloatN<N> out[4];
      gather4(rec + at, 12, idx, out);
      for (uint32_t c = 0; c < 4; ++c)
        for (uint32_t l = 0; l < N; ++l)
          ASSERT_EQ(out[c].lane(l), rec[12 * idx[l] + at + c]) << "width " << N << " field " << at + c;
    }
  }
}

TEST(Lanes, Gather4MatchesALoop) {
  check_gather4<1>(25);
  check_gather4<4>(26);
  check_gather4<8>(27);
  check_gather4<16>(28);
}

TEST(Lanes, GatherXyzMatchesALoop) {
  check_gather_xyz<1>(21);
  check_gather_xyz<4>(22);
  check_gather_xyz<8>(23);
  check_gather_xyz<16>(24);
}

/// SortedGather against reading lane by lane: indices (repeats included, as a padded
/// group's) into an array of exactly `end` floats (so ASan sees any read past it),
/// spans from 0 to past the windowed case's 64, starts anywhere from begin to the
/// array's end, ranges shorter and longer than two windows; ascending (the use), and in
/// every fourth round shuffled (the lanes out of order must still read right).
template <uint32_t N>
void check_sorted_gather(uint32_t seed) {
  std::mt19937 g(seed);
  for (int round = 0; round < 2000; ++round) {
    const auto begin = static_cast<int32_t>(g() % 8);
    const auto end = begin + static_cast<int32_t>(N + g() % 300);
    std::vector<float> arr(static_cast<size_t>(end));
    for (size_t k = 0; k < arr.size(); ++k) arr[k] = static_cast<float>(k) * 0.5f + 1.0f;
    const int32_t max_span = std::min<int32_t>(end - begin, round % 2 == 0 ? 70 : 300);
    const auto span = static_cast<int32_t>(g() % static_cast<uint32_t>(max_span));
    const int32_t lo = begin + static_cast<int32_t>(g() % static_cast<uint32_t>(end - begin - span));
    int32_t idx[N];
    for (uint32_t l = 0; l < N; ++l)
      idx[l] = lo + static_cast<int32_t>(g() % static_cast<uint32_t>(span + 1));
    std::sort(idx, idx + N);
    if (round % 4 == 3) std::shuffle(idx, idx + N, g);
    const SortedGather<N> rows(IntN<N>::load(idx), begin, end);
    const FloatN<N> v = rows(arr.data());
    for (uint32_t l = 0; l < N; ++l)
      ASSERT_EQ(v.lane(l), arr[static_cast<size_t>(idx[l])])
          << "width " << N << " lane " << l << " round " << round;
  }
}

TEST(Lanes, SortedGatherMatchesALoop) {
  check_sorted_gather<1>(31);
  check_sorted_gather<4>(32);
  check_sorted_gather<8>(33);
  check_sorted_gather<16>(34);
}

/// load_transposed and store_transposed against a loop: rows of 16-float records (as
/// the soft step's SolverBody) at offsets 0 and N, one per lane, at random records with
/// repeats; store_transposed writes exactly the rows whose bit is set (the others keep
/// their canary bytes, repeated rows included when no set lane names them).
template <uint32_t N>
void check_transposed(uint32_t seed) {
  std::mt19937 g(seed);
  constexpr uint32_t kRecords = 20, kStride = 16;
  for (int round = 0; round < 200; ++round) {
    std::vector<float> rec(kRecords * kStride + 1);
    for (uint32_t k = 0; k < rec.size(); ++k) rec[k] = static_cast<float>(g() % 1000) - 500.5f;
    // Distinct records for the lanes that store (set bits), any record for the others.
    uint32_t bits = g() & ((N == 32 ? 0u : (1u << N)) - 1u);
    int32_t idx[N];
    std::vector<int32_t> pool(kRecords);
    for (uint32_t k = 0; k < kRecords; ++k) pool[k] = static_cast<int32_t>(k);
    std::shuffle(pool.begin(), pool.end(), g);
    for (uint32_t l = 0; l < N; ++l) idx[l] = (bits >> l) & 1u ? pool[l] : static_cast<int32_t>(g() % kRecords);
    for (uint32_t l = 0; l < N; ++l)
      if (!((bits >> l) & 1u))
        for (uint32_t m = 0; m < N; ++m)
          if ((bits >> m) & 1u && idx[m] == idx[l]) bits &= ~(1u << m);  // a read-only row stays unwritten
    for (uint32_t at = 0; at + N <= kStride; at += N) {
      float* base = rec.data() + 1;  // unaligned
      const float* crows[N];
      float* rows[N];
      for (uint32_t l = 0; l < N; ++l) rows[l] = base + kStride * idx[l] + at, crows[l] = rows[l];
      FloatN<N> out[N];
      load_transposed(crows, out);
      for (uint32_t j = 0; j < N; ++j)
        for (uint32_t l = 0; l < N; ++l) ASSERT_EQ(out[j].lane(l), rows[l][j]) << "width " << N;
      FloatN<N> in[N];
      for (uint32_t j = 0; j < N; ++j) in[j] = out[j] + FloatN<N>(static_cast<float>(j + 1));
      const std::vector<float> before = rec;
      store_transposed(rows, in, bits);
      std::vector<float> want = before;
      for (uint32_t l = 0; l < N; ++l)
        if ((bits >> l) & 1u)
          for (uint32_t j = 0; j < N; ++j) want[1 + kStride * idx[l] + at + j] = in[j].lane(l);
      ASSERT_EQ(0, std::memcmp(want.data(), rec.data(), sizeof(float) * rec.size())) << "width " << N;
    }
  }
}

TEST(Lanes, TransposedLoadAndStoreMatchALoop) {
  check_transposed<1>(41);
  check_transposed<4>(42);
  check_transposed<8>(43);
  check_transposed<16>(44);
}

TEST(Lanes, MaxLowestIndexReportsNoneForNaNOnly) {
  const float nan = std::nanf("");
  float s[8], idx[8];
  for (uint32_t k = 0; k < 8; ++k) {
    s[k] = nan;
    idx[k] = static_cast<float>(k);
  }
  float got = 0.0f;
  max_lowest_index(FloatN<8>::load(s), FloatN<8>::load(idx), 42.0f, &got);
  EXPECT_EQ(got, 42.0f);
  max_lowest_index(FloatN<1>(nan), FloatN<1>(0.0f), 42.0f, &got);
  EXPECT_EQ(got, 42.0f);
}

}  // namespace
}  // namespace impact::kernels::simd
