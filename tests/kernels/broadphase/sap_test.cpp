// Sweep-and-prune broad phase (kernels/broadphase/sap.h, host/broadphase/sap.h)
// against the independent double-precision reference of
// tests/support/aabb_reference.h: pairs compared as sets (each pair (a < b) once)
// on random and adversarial inputs, from scratch and after many frames through
// the incremental (insertion sort) path, including frames whose large jumps force
// the radix-sort fallback, with filters; pair order compared byte for byte across
// every backend and thread count, and between the incremental and from-scratch
// paths; the float -> uint32 key map preserves order.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cfloat>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "host/broadphase/sap.h"
#include "host/parallel.h"
#include "kernels/broadphase/sap.h"
#include "support/aabb_reference.h"
#include "support/kernel_views.h"
#include "support/test_support.h"

namespace impact {
namespace {

using host::Buffer;
using host::Executor;
using host::SapBroadPhase;
using host::SapOptions;
using kernels::Pair;
using test::Boxes;
using test::clustered_boxes;
using test::uniform_boxes;
using test::expect_same_set;
using test::PairVec;
using test::reference_pairs;
using test::scaled;

using test::count;
using test::filter_of;
using test::serial;
using test::soa;


bool same_bytes(const Buffer<Pair>& a, const Buffer<Pair>& b) {
  return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(Pair)) == 0);
}

// --- float key ----------------------------------------------------------------------------

TEST(SapFloatKey, PreservesOrder) {
  std::vector<float> v = {0.0f, -0.0f, FLT_MIN, -FLT_MIN, FLT_TRUE_MIN, -FLT_TRUE_MIN, FLT_MAX, -FLT_MAX,
                          std::numeric_limits<float>::infinity(), -std::numeric_limits<float>::infinity(),
                          1.0f, -1.0f, 1e-40f, -1e-40f, 1e30f, -1e30f, std::nextafter(0.0f, 1.0f),
                          std::nextafter(1.0f, 2.0f), std::nextafter(-1.0f, -2.0f)};
  std::mt19937 rng(7);
  std::uniform_int_distribution<uint32_t> bits;
  std::uniform_real_distribution<float> small(-10.0f, 10.0f);
  for (int i = 0; i < 20000; ++i) {
    const float f = std::bit_cast<float>(bits(rng));  // any float, incl. denormals
    if (!std::isnan(f)) v.push_back(f);
    v.push_back(small(rng));
  }
  for (float a : v) {
    for (int k = 0; k < 4; ++k) {
      const float b = v[bits(rng) % v.size()];
      const uint32_t ka = kernels::sap_float_key(a), kb = kernels::sap_float_key(b);
      if (a < b) {
        ASSERT_LT(ka, kb) << a << " " << b;
      }
      if (a > b) {
        ASSERT_GT(ka, kb) << a << " " << b;
      }
      if (std::bit_cast<uint32_t>(a) == std::bit_cast<uint32_t>(b)) {
        ASSERT_EQ(ka, kb);
      }
    }
  }
  EXPECT_LT(kernels::sap_float_key(-0.0f), kernels::sap_float_key(0.0f));
  EXPECT_EQ(kernels::sap_float_key(-0.0f) + 1, kernels::sap_float_key(0.0f));
  // Sorting by key sorts by value.
  std::vector<float> by_key = v;
  std::sort(by_key.begin(), by_key.end(),
            [](float a, float b) { return kernels::sap_float_key(a) < kernels::sap_float_key(b); });
  EXPECT_TRUE(std::is_sorted(by_key.begin(), by_key.end()));
}

TEST(SapInsertionSort, SortsAndCountsShifts) {
  std::vector<uint64_t> k = {5, 1, 4, 2, 3};
  EXPECT_EQ(kernels::sap_insertion_sort(k.data(), 100, {0, 5}), 6u);  // inversions
  EXPECT_TRUE(std::is_sorted(k.begin(), k.end()));
  std::vector<uint64_t> r(1000);
  for (uint32_t i = 0; i < 1000; ++i) r[i] = 1000 - i;
  const uint64_t got = kernels::sap_insertion_sort(r.data(), 50, {0, 1000});
  EXPECT_GT(got, 50u);  // gave up
  std::vector<uint64_t> sorted = r;
  std::sort(sorted.begin(), sorted.end());
  for (uint32_t i = 0; i < 1000; ++i) ASSERT_EQ(sorted[i], 1u + i);  // still a permutation
}

// --- generators ---------------------------------------------------------------------------



// Half-sizes log-uniform over [0.05, 50] (1000x), few large boxes.
Boxes mixed_size_boxes(uint32_t n, uint32_t seed) {
  std::mt19937 rng(seed);
  const float side = 4.0f * std::cbrt(static_cast<float>(n));
  std::uniform_real_distribution<float> pos(-0.5f * side, 0.5f * side);
  std::uniform_real_distribution<float> e(std::log(0.05f), std::log(50.0f));
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  Boxes b;
  for (uint32_t i = 0; i < n; ++i) {
    const float h = u(rng) < 0.02f ? std::exp(e(rng)) : 0.05f + 0.5f * u(rng);
    b.add(pos(rng), pos(rng), pos(rng), h, h * (0.5f + u(rng)), h);
  }
  return b;
}

Boxes scaled_boxes(Boxes b, float scale, float offset) {
  for (auto* v : {&b.min_x, &b.min_y, &b.min_z, &b.max_x, &b.max_y, &b.max_z})
    for (float& f : *v) f = offset + f * scale;
  if (scale < 0) {  // mirroring swaps the roles of min and max
    std::swap(b.min_x, b.max_x);
    std::swap(b.min_y, b.max_y);
    std::swap(b.min_z, b.max_z);
  }
  return b;
}

void check(const Boxes& boxes, const std::string& what, const SapOptions& opt = {}) {
  SCOPED_TRACE(what);
  const PairVec ref = reference_pairs(boxes);
  SapBroadPhase bp(opt);
  Buffer<Pair> out(1, Pair{7, 3});  // stale content must be replaced
  ASSERT_TRUE(test::IsOk(bp.find_pairs(serial(), soa(boxes), filter_of(boxes), count(boxes), &out)));
  expect_same_set(out, ref, boxes.size(), what);
  const Executor par(Backend::kDefault, 0);
  bp.reset();
  ASSERT_TRUE(test::IsOk(bp.find_pairs(par, soa(boxes), filter_of(boxes), count(boxes), &out)));
  expect_same_set(out, ref, boxes.size(), what + " parallel");
}

void check_with_filter(Boxes boxes, const std::string& what) {
  check(boxes, what);
  test::add_random_filter(boxes, 99, 0.3);
  check(boxes, what + " filtered");
}

// --- sets vs reference --------------------------------------------------------------------

TEST(Sap, SmallCounts) {
  for (uint32_t n : {0u, 1u, 2u, 3u}) {
    Boxes b;
    for (uint32_t i = 0; i < n; ++i) b.add(0.5f * static_cast<float>(i), 0.0f, 0.0f, 0.5f, 0.5f, 0.5f);
    check_with_filter(b, "n=" + std::to_string(n));
    Boxes apart;
    for (uint32_t i = 0; i < n; ++i) apart.add(10.0f * static_cast<float>(i), 0.0f, 0.0f, 0.5f, 0.5f, 0.5f);
    check(apart, "apart n=" + std::to_string(n));
  }
}

TEST(Sap, Uniform) {
  check_with_filter(uniform_boxes(scaled(5000), 1, 0.2f, 1.0f), "uniform");
  check(uniform_boxes(scaled(120000), 2, 0.5f, 0.5f), "uniform large");
}

TEST(Sap, Clustered) { check_with_filter(clustered_boxes(scaled(5000), 3), "clustered"); }

TEST(Sap, SizesSpan1000x) {
  check_with_filter(mixed_size_boxes(scaled(5000), 4), "mixed sizes");
  check(mixed_size_boxes(scaled(60000), 5), "mixed sizes large");
}

TEST(Sap, AllAtOnePoint) {
  Boxes b;
  for (uint32_t i = 0; i < 700; ++i) b.add(3.0f, -2.0f, 1.0f, 0.0f, 0.0f, 0.0f);
  check_with_filter(b, "one point, zero size");
  Boxes c;
  for (uint32_t i = 0; i < 700; ++i) c.add(3.0f, -2.0f, 1.0f, 0.5f, 0.5f, 0.5f);
  check(c, "one point");
}

TEST(Sap, ZeroSizeBoxes) {
  std::mt19937 rng(6);
  std::uniform_int_distribution<int> cell(-8, 8);
  Boxes b;  // points on a coarse lattice: many exact coincidences and touching
  for (uint32_t i = 0; i < 3000; ++i) {
    const float x = static_cast<float>(cell(rng)), y = static_cast<float>(cell(rng)),
                z = static_cast<float>(cell(rng));
    b.add_box(x, y, z, x, y, z);
  }
  check_with_filter(b, "zero size");
  Boxes t;  // unit boxes on a lattice of unit spacing: every neighbour touches
  for (int x = 0; x < 12; ++x)
    for (int y = 0; y < 12; ++y)
      for (int z = 0; z < 12; ++z) {
        const float fx = static_cast<float>(x), fy = static_cast<float>(y), fz = static_cast<float>(z);
        t.add_box(fx, fy, fz, fx + 1.0f, fy + 1.0f, fz + 1.0f);
      }
  check(t, "touching lattice");
}

TEST(Sap, Scales) {
  const Boxes base = uniform_boxes(scaled(4000), 7, 0.2f, 1.0f);
  check(scaled_boxes(base, 1e-4f, 0.0f), "tiny 1e-4");
  check(scaled_boxes(base, 1e4f, 0.0f), "huge 1e4");
  check_with_filter(uniform_boxes(scaled(4000), 8, 0.2f, 1.0f, 1e6f), "offset 1e6");
  check(scaled_boxes(base, 1.0f, -1000.0f), "negative");
  check(scaled_boxes(base, -1.0f, -5.0f), "negative mirrored");  // min/max swap roles
}

TEST(Sap, NegativeAndSigns) {
  Boxes b = uniform_boxes(scaled(4000), 9, 0.2f, 1.0f);
  for (size_t i = 0; i < b.size(); ++i) {
    b.min_x[i] -= 20.0f, b.max_x[i] -= 20.0f;  // straddle zero on x
  }
  check_with_filter(b, "straddle zero");
}

// --- incremental --------------------------------------------------------------------------

void move_boxes(Boxes& b, std::mt19937& rng, float step) {
  std::uniform_real_distribution<float> d(-step, step);
  for (size_t i = 0; i < b.size(); ++i) {
    const float dx = d(rng), dy = d(rng), dz = d(rng);
    b.min_x[i] += dx, b.max_x[i] += dx;
    b.min_y[i] += dy, b.max_y[i] += dy;
    b.min_z[i] += dz, b.max_z[i] += dz;
  }
}

TEST(Sap, IncrementalFrames) {
  for (bool filtered : {false, true}) {
    SCOPED_TRACE(filtered ? "filtered" : "unfiltered");
    Boxes b = uniform_boxes(scaled(3000), 10, 0.2f, 1.0f);
    if (filtered) test::add_random_filter(b, 11, 0.3);
    std::mt19937 rng(12);
    SapBroadPhase inc;        // incremental (default options)
    SapBroadPhase fresh;      // a new from-scratch sort every frame
    Buffer<Pair> got, want;
    uint32_t incremental_frames = 0, fallbacks = 0;
    for (int frame = 0; frame < 100; ++frame) {
      const bool jump = frame % 25 == 24;
      move_boxes(b, rng, jump ? 30.0f : 0.005f);
      ASSERT_TRUE(test::IsOk(inc.find_pairs(serial(), soa(b), filter_of(b), count(b), &got)));
      const host::SapInfo info = inc.info();
      if (frame > 0) {
        EXPECT_TRUE(info.tried_incremental) << frame;
      }
      if (info.tried_incremental && !info.resorted) ++incremental_frames;
      if (info.tried_incremental && info.resorted) ++fallbacks;
      if (jump) {
        EXPECT_TRUE(info.resorted) << "frame " << frame << " shifts " << info.shifts;
      }
      expect_same_set(got, reference_pairs(b), b.size(), "frame " + std::to_string(frame));
      fresh.reset();
      ASSERT_TRUE(test::IsOk(fresh.find_pairs(serial(), soa(b), filter_of(b), count(b), &want)));
      if (fresh.info().axis == info.axis) {
        EXPECT_TRUE(same_bytes(got, want)) << "frame " << frame;
      }
    }
    EXPECT_GE(incremental_frames, 90u);
    EXPECT_GE(fallbacks, 4u);
  }
}

TEST(Sap, IncrementalChangesOfCountAndAxis) {
  SapBroadPhase bp;
  Buffer<Pair> out;
  Boxes a = uniform_boxes(2000, 13, 0.2f, 1.0f);
  ASSERT_TRUE(test::IsOk(bp.find_pairs(serial(), soa(a), filter_of(a), count(a), &out)));
  Boxes b = uniform_boxes(2100, 14, 0.2f, 1.0f);  // new count: from scratch
  ASSERT_TRUE(test::IsOk(bp.find_pairs(serial(), soa(b), filter_of(b), count(b), &out)));
  EXPECT_FALSE(bp.info().tried_incremental);
  EXPECT_TRUE(bp.info().resorted);
  expect_same_set(out, reference_pairs(b), b.size(), "new count");
  // Stretch along x, then along z: the axis follows once the variance ratio is large.
  Boxes x = b, z = b;
  for (size_t i = 0; i < b.size(); ++i) {
    x.min_x[i] *= 10.0f, x.max_x[i] *= 10.0f;
    z.min_z[i] *= 10.0f, z.max_z[i] *= 10.0f;
  }
  ASSERT_TRUE(test::IsOk(bp.find_pairs(serial(), soa(x), filter_of(x), count(x), &out)));
  EXPECT_EQ(bp.info().axis, 0u);
  ASSERT_TRUE(test::IsOk(bp.find_pairs(serial(), soa(z), filter_of(z), count(z), &out)));
  EXPECT_EQ(bp.info().axis, 2u);
  EXPECT_TRUE(bp.info().resorted);
  expect_same_set(out, reference_pairs(z), z.size(), "axis switch");
  // Incremental off: always from scratch.
  SapBroadPhase off(SapOptions{.incremental = false});
  for (int k = 0; k < 2; ++k) {
    ASSERT_TRUE(test::IsOk(off.find_pairs(serial(), soa(z), filter_of(z), count(z), &out)));
    EXPECT_FALSE(off.info().tried_incremental);
    EXPECT_TRUE(off.info().resorted);
  }
}

// --- determinism --------------------------------------------------------------------------

TEST(Sap, SameBytesForEveryExecutor) {
  // Several radix (2^16) and sweep (2^11) chunks: three radix chunks, two under ASan +
  // UBSan (there the 150k boxes x 9 executors x 3 frames took ~50 s alone).
  Boxes b = uniform_boxes(test::kSanitized ? 70000 : scaled(150000), 15, 0.1f, 0.5f);
  test::add_random_filter(b, 16, 0.2);
  Boxes m = mixed_size_boxes(scaled(40000), 17);
  for (const Boxes* boxes : {&b, &m}) {
    std::vector<Buffer<Pair>> golden;  // frame 0 from scratch, then incremental frames
    for (const test::ExecCase& c : test::exec_cases()) {
      SCOPED_TRACE(test::to_string(c));
      Executor e(c.backend, c.threads);
      Boxes cur = *boxes;
      std::mt19937 rng(18);
      SapBroadPhase bp;
      for (int frame = 0; frame < 3; ++frame) {
        if (frame > 0) move_boxes(cur, rng, frame == 2 ? 50.0f : 0.0002f);
        Buffer<Pair> out;
        ASSERT_TRUE(test::IsOk(bp.find_pairs(e, soa(cur), filter_of(cur), count(cur), &out)));
        EXPECT_EQ(bp.info().resorted, frame != 1) << "frame " << frame;
        if (golden.size() <= static_cast<size_t>(frame)) {
          expect_same_set(out, reference_pairs(cur), cur.size(), "frame " + std::to_string(frame));
          golden.push_back(std::move(out));
        } else {
          EXPECT_TRUE(same_bytes(out, golden[frame])) << "frame " << frame;
        }
      }
    }
  }
}

TEST(Sap, PairOrderIsDocumented) {
  // Pairs come by query slot (sweep-axis min, then index), then by later slot.
  Boxes b;
  b.add_box(2, 0, 0, 3, 1, 1);   // 0
  b.add_box(0, 0, 0, 2.5f, 1, 1);  // 1
  b.add_box(2, 0, 0, 2.2f, 1, 1);  // 2
  b.add_box(1, 0, 0, 2, 1, 1);   // 3
  // x is the only spread axis; sorted: 1 (0), 3 (1), 0 (2), 2 (2: tie, index 2 after 0).
  SapBroadPhase bp;
  Buffer<Pair> out;
  ASSERT_TRUE(test::IsOk(bp.find_pairs(serial(), soa(b), filter_of(b), count(b), &out)));
  EXPECT_EQ(bp.info().axis, 0u);
  const PairVec want = {{1, 3}, {0, 1}, {1, 2}, {0, 3}, {2, 3}, {0, 2}};
  EXPECT_EQ(test::to_vec(out), want);
  const uint32_t order[4] = {1, 3, 0, 2};
  for (int s = 0; s < 4; ++s) EXPECT_EQ(bp.sorted_index()[s], order[s]);
}

}  // namespace
}  // namespace impact
