// Grid broad-phase kernels (kernels/broadphase/grid.*) driven through their host
// wrapper host::GridBroadPhase, so the test can see which bucket mode the grid
// chose (GridInfo) and force both: dense row-major buckets and hashed buckets,
// where unrelated cells share buckets. Pairs are compared with the independent
// double-precision reference of tests/support/aabb_reference.h.
#include "kernels/broadphase/grid.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>
#include <random>
#include <string>
#include <vector>

#include "host/broadphase/broadphase.h"
#include "host/parallel.h"
#include "kernels/broadphase/bounds.h"
#include "kernels/broadphase/grid_query.h"
#include "support/aabb_reference.h"
#include "support/test_support.h"

namespace impact {
namespace {

using test::Boxes;
using test::PairVec;

kernels::AabbSoA soa(const Boxes& b) {
  return {b.min_x.data(), b.min_y.data(), b.min_z.data(), b.max_x.data(), b.max_y.data(), b.max_z.data()};
}

kernels::PairFilter filter(const Boxes& b) {
  if (!b.filtered()) return {nullptr, nullptr, nullptr};
  return {b.layer.data(), b.mask.data(), b.is_static.data()};
}

// Runs the grid on every executor case; checks the set against the reference
// and that the order is the same bytes everywhere. Returns the chosen mode.
host::GridInfo run_grid(const Boxes& b, const char* what, uint32_t* levels_used = nullptr) {
  SCOPED_TRACE(what);
  const PairVec ref = test::reference_pairs(b);
  host::GridBroadPhase grid;
  host::Buffer<kernels::Pair> first;
  host::GridInfo info;
  bool have_first = false;
  for (const test::ExecCase& c : test::exec_cases()) {
    host::Executor exec(c.backend, c.threads);
    host::Buffer<kernels::Pair> pairs;
    IMPACT_EXPECT_OK(grid.find_pairs(exec, soa(b), filter(b), static_cast<uint32_t>(b.size()), &pairs));
    if (!have_first) {
      test::expect_same_set(pairs, ref, b.size(), "grid");
      first = pairs;
      info = grid.info();
      if (levels_used) *levels_used = grid.levels_used();
      have_first = true;
      continue;
    }
    bool same = pairs.size() == first.size();
    for (size_t k = 0; same && k < pairs.size(); ++k)
      same = pairs[k].a == first[k].a && pairs[k].b == first[k].b;
    EXPECT_TRUE(same) << test::to_string(c) << ": pair order differs from the first executor";
  }
  return info;
}

TEST(GridBroadPhase, DenseModeForCompactScenes) {
  std::mt19937 rng(1);
  std::uniform_real_distribution<float> pos(-5.0f, 5.0f);
  Boxes b;  // ~14^3 cells of 0.8 m for 3000 boxes: within the dense limit of 4n
  for (int i = 0; i < 3000; ++i) b.add(pos(rng), pos(rng), pos(rng), 0.4f, 0.4f, 0.4f);
  const host::GridInfo info = run_grid(b, "compact");
  EXPECT_TRUE(info.dense);
  // The cell must exceed the largest box edge (the correctness argument of grid.h).
  EXPECT_GT(info.cell, 0.8);
}

TEST(GridBroadPhase, HashedModeForSparseHugeWorld) {
  // 1e6 m across with 1 m boxes: ~1e18 cells, far beyond 4n, so buckets are hashed.
  std::mt19937 rng(2);
  std::uniform_real_distribution<float> pos(-5.0e5f, 5.0e5f);
  std::uniform_real_distribution<float> jitter(-1.5f, 1.5f);
  Boxes b;
  for (int i = 0; i < 400; ++i) {
    const float x = pos(rng), y = pos(rng), z = pos(rng);
    for (int k = 0; k < 3; ++k) b.add(x + jitter(rng), y + jitter(rng), z + jitter(rng), 1.0f, 1.0f, 1.0f);
  }
  const host::GridInfo info = run_grid(b, "sparse");
  EXPECT_FALSE(info.dense);
  EXPECT_GT(test::reference_pairs(b).size(), 400u);
}

TEST(GridBroadPhase, HashedModeWithManyOccupiedCells) {
  // Many occupied cells and about 2n buckets: distinct cells must share buckets,
  // which the pair pass has to tell apart by cell id.
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> pos(0.0f, 2000.0f);
  std::uniform_real_distribution<float> jitter(-0.6f, 0.6f);
  std::uniform_real_distribution<float> half(0.1f, 0.5f);
  Boxes b;
  const uint32_t clumps = test::scaled(3000);
  for (uint32_t i = 0; i < clumps; ++i) {
    const float x = pos(rng), y = pos(rng), z = pos(rng);
    for (int k = 0; k < 3; ++k)
      b.add(x + jitter(rng), y + jitter(rng), z + jitter(rng), half(rng), half(rng), half(rng));
  }
  test::add_random_filter(b, 3, 0.2);
  const host::GridInfo info = run_grid(b, "hashed, many cells");
  EXPECT_FALSE(info.dense);
  EXPECT_LT(info.buckets, 1u << 20);
}

TEST(GridBroadPhase, CellCountClampedPerAxis) {
  // Tiny boxes over a long line: extent / edge exceeds 2^21 cells per axis, so the
  // cell grows to extent / (2^21 - 2) and several boxes share cells.
  std::mt19937 rng(4);
  std::uniform_real_distribution<float> pos(0.0f, 4.0e4f);
  std::uniform_real_distribution<float> jitter(-2e-3f, 2e-3f);
  Boxes b;
  for (int i = 0; i < 2000; ++i) {
    const float x = pos(rng);
    b.add(x, 0.0f, 0.0f, 1e-3f, 1e-3f, 1e-3f);
    b.add(x + jitter(rng), jitter(rng), jitter(rng), 1e-3f, 1e-3f, 1e-3f);
  }
  const host::GridInfo info = run_grid(b, "clamped dims");
  EXPECT_LE(info.dims[0], kernels::kGridMaxDim);
  EXPECT_GT(info.cell, 2e-3);
  EXPECT_GT(test::reference_pairs(b).size(), 1000u);
}

TEST(GridBroadPhase, HierarchicalLevelsForSizesSpanning1000x) {
  // Log-uniform sizes over 1000x: one grid would need cells as large as the
  // largest box (quadratic in the crowded small ones); the levels keep each
  // size class in its own grid and pair across levels by queries.
  std::mt19937 rng(6);
  std::uniform_real_distribution<float> pos(0.0f, 60.0f);
  std::uniform_real_distribution<float> expo(0.0f, 3.0f);
  for (bool filtered : {false, true}) {
    Boxes b;
    for (uint32_t i = 0; i < test::scaled(6000); ++i) {
      const float h = 0.005f * std::pow(10.0f, expo(rng));  // half extent 0.005 .. 5
      b.add(pos(rng), pos(rng), pos(rng), h, h * 0.7f, h * 1.3f);
    }
    if (filtered) test::add_random_filter(b, 6, 0.3);
    uint32_t levels = 0;
    run_grid(b, filtered ? "1000x filtered" : "1000x", &levels);
    EXPECT_GE(levels, 4u);
  }
}

TEST(GridBroadPhase, HierarchicalFewHugeAmongManySmall) {
  // A handful of huge boxes (a floor slab, walls) among many small ones, some
  // levels holding a single box, plus zero-size boxes (the finest level).
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> pos(-20.0f, 20.0f);
  Boxes b;
  b.add_box(-25.0f, -1.0f, -25.0f, 25.0f, 0.0f, 25.0f);   // floor slab
  b.add_box(-25.0f, 0.0f, -25.0f, -24.0f, 10.0f, 25.0f);  // wall
  b.add(0.0f, 3.0f, 0.0f, 2.0f, 2.0f, 2.0f);               // one mid-size box
  for (int i = 0; i < 3000; ++i) b.add(pos(rng), std::abs(pos(rng)) * 0.25f, pos(rng), 0.1f, 0.1f, 0.1f);
  for (int i = 0; i < 50; ++i) b.add(pos(rng), 0.0f, pos(rng), 0.0f, 0.0f, 0.0f);
  test::add_random_filter(b, 7, 0.1);
  uint32_t levels = 0;
  run_grid(b, "few huge", &levels);
  EXPECT_GE(levels, 3u);
}

TEST(GridBroadPhase, BoundsReductionMatchesReference) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> pos(-100.0f, 100.0f);
  std::uniform_real_distribution<float> half(0.0f, 3.0f);
  Boxes b;
  for (int i = 0; i < 1000; ++i) b.add(pos(rng), pos(rng), pos(rng), half(rng), half(rng), half(rng));
  // Any partition into ranges, combined in order, gives the exact union and max edge.
  double lo[3] = {1e300, 1e300, 1e300}, hi[3] = {-1e300, -1e300, -1e300}, edge = 0, min_edge = 1e300;
  for (size_t i = 0; i < b.size(); ++i) {
    const float mn[3] = {b.min_x[i], b.min_y[i], b.min_z[i]}, mx[3] = {b.max_x[i], b.max_y[i], b.max_z[i]};
    double box_edge = 0;
    for (int k = 0; k < 3; ++k) {
      lo[k] = std::min<double>(lo[k], mn[k]);
      hi[k] = std::max<double>(hi[k], mx[k]);
      edge = std::max<double>(edge, mx[k] - mn[k]);  // float subtraction, as the kernel's edge
      box_edge = std::max<double>(box_edge, mx[k] - mn[k]);
    }
    min_edge = std::min(min_edge, box_edge);
  }
  for (uint32_t parts : {1u, 3u, 7u, 1000u}) {
    kernels::BoundsSummary s = kernels::empty_bounds_summary();
    const uint32_t n = static_cast<uint32_t>(b.size());
    for (uint32_t p = 0; p < parts; ++p)
      s = kernels::combine(s, kernels::reduce_bounds(soa(b), {n * p / parts, n * (p + 1) / parts}));
    for (int k = 0; k < 3; ++k) {
      EXPECT_EQ(static_cast<double>(s.lo[k]), lo[k]);
      EXPECT_EQ(static_cast<double>(s.hi[k]), hi[k]);
    }
    EXPECT_EQ(static_cast<double>(s.max_edge), edge);
    EXPECT_EQ(static_cast<double>(s.min_edge), min_edge);
  }
}

// --- the block sort and the pair order ---------------------------------------------------------

TEST(GridBroadPhase, BlocksCoverEveryBucketWithinTheLimit) {
  for (uint32_t buckets :
       {1u, 2u, 255u, 256u, 257u, 4096u, 30000u, 1u << 21, (1u << 21) + 1, 0x80000000u, 0xffffffffu}) {
    kernels::GridParams g{};
    g.bucket_count = buckets;
    const kernels::GridBlocks blocks = kernels::grid_blocks(g);
    SCOPED_TRACE(buckets);
    EXPECT_GE(blocks.count, 1u);
    EXPECT_LE(blocks.count, kernels::kGridMaxBlocks);
    // The blocks tile [0, buckets): the last one starts inside, and they reach the end.
    EXPECT_LT(static_cast<uint64_t>(blocks.count - 1) << blocks.low_bits, buckets);
    EXPECT_GE(static_cast<uint64_t>(blocks.count) << blocks.low_bits, buckets);
    if (buckets <= kernels::kGridMaxBlocks) {
      EXPECT_EQ(blocks.low_bits, 0u);
    }
  }
}

// The sorted view against a std::stable_sort of the input positions by bucket
// (bucket ids from grid_query_bucket, pinned to the build's by query_test.cpp):
// slot order, bucket ranges, the per-slot filter data and (hashed) cells, on every
// executor case.
void expect_sorted_by_bucket(const Boxes& b, const char* what, bool want_dense, bool want_one_bucket_blocks) {
  SCOPED_TRACE(what);
  const uint32_t n = static_cast<uint32_t>(b.size());
  for (const test::ExecCase& c : test::exec_cases()) {
    SCOPED_TRACE(test::to_string(c));
    host::Executor exec(c.backend, c.threads);
    host::GridBroadPhase grid;
    grid.set_level_fraction(0);
    grid.build(exec, soa(b), filter(b), n);
    const kernels::GridView* v = grid.level_view(0);
    ASSERT_NE(v, nullptr);
    ASSERT_EQ(v->params.dense != 0, want_dense);
    ASSERT_EQ(kernels::grid_blocks(v->params).low_bits == 0, want_one_bucket_blocks);
    std::vector<uint32_t> bucket(n), order(n);
    for (uint32_t i = 0; i < n; ++i)
      bucket[i] = kernels::grid_query_bucket(v->params, b.min_x[i], b.min_y[i], b.min_z[i]);
    std::iota(order.begin(), order.end(), 0u);
    std::stable_sort(order.begin(), order.end(),
                     [&](uint32_t x, uint32_t y) { return bucket[x] < bucket[y]; });
    const uint32_t buckets = v->params.bucket_count;
    std::vector<uint32_t> start(static_cast<size_t>(buckets) + 1, 0);
    for (uint32_t i = 0; i < n; ++i) ++start[bucket[i] + 1];
    for (uint32_t k = 0; k < buckets; ++k) start[k + 1] += start[k];
    for (uint32_t k = 0; k <= buckets; ++k) ASSERT_EQ(v->bucket_start[k], start[k]) << "bucket " << k;
    EXPECT_EQ(v->cell == nullptr, want_dense);
    for (uint32_t s = 0; s < n; ++s) {
      const uint32_t i = order[s];
      const kernels::SortedBox& box = v->box[s];
      ASSERT_EQ(box.index, i) << "slot " << s;
      ASSERT_EQ(box.pad, 0u);
      ASSERT_EQ(box.min_x, b.min_x[i]);
      ASSERT_EQ(box.min_y, b.min_y[i]);
      ASSERT_EQ(box.min_z, b.min_z[i]);
      ASSERT_EQ(box.max_x, b.max_x[i]);
      ASSERT_EQ(box.max_y, b.max_y[i]);
      ASSERT_EQ(box.max_z, b.max_z[i]);
      if (b.filtered()) {
        ASSERT_EQ(v->layer[s], b.layer[i]);
        ASSERT_EQ(v->mask[s], b.mask[i]);
        ASSERT_EQ(v->is_static[s], b.is_static[i]);
      }
      if (v->cell) {
        // The cell's bucket is the slot's bucket; its axes are within the grid.
        const uint64_t cell = v->cell[s];
        const uint64_t axis = (1ull << kernels::kGridAxisBits) - 1;
        ASSERT_LT(cell & axis, v->params.dims[0]);
        ASSERT_LT((cell >> kernels::kGridAxisBits) & axis, v->params.dims[1]);
        ASSERT_LT(cell >> (2 * kernels::kGridAxisBits), v->params.dims[2]);
      }
    }
  }
}

TEST(GridBroadPhase, BlockSortEqualsStableSortByBucket) {
  // More boxes than one chunk of the block passes (kKeyGrain), so chunk offsets matter.
  const uint32_t n = test::scaled(3 * host::GridBroadPhase::kKeyGrain + 77);
  std::mt19937 rng(11);
  {
    // A 3x3x3-cell world: 27 buckets, one per block (low_bits 0); crowded buckets.
    std::uniform_real_distribution<float> pos(0.0f, 5.0f);
    Boxes b;
    for (uint32_t i = 0; i < n; ++i) b.add(pos(rng), pos(rng), pos(rng), 0.9f, 0.9f, 0.9f);
    test::add_random_filter(b, 12, 0.2);
    expect_sorted_by_bucket(b, "27 buckets", true, true);
  }
  {
    // Dense with thousands of buckets: several buckets per block.
    std::uniform_real_distribution<float> pos(0.0f, 30.0f);
    Boxes b;
    for (uint32_t i = 0; i < n; ++i) b.add(pos(rng), pos(rng), pos(rng), 0.25f, 0.25f, 0.25f);
    expect_sorted_by_bucket(b, "dense, many buckets", true, false);
  }
  {
    // Hashed: a huge sparse world.
    std::uniform_real_distribution<float> pos(-1.0e5f, 1.0e5f);
    Boxes b;
    for (uint32_t i = 0; i < n; ++i) b.add(pos(rng), pos(rng), pos(rng), 1.0f, 1.0f, 1.0f);
    test::add_random_filter(b, 13, 0.2);
    expect_sorted_by_bucket(b, "hashed", false, false);
  }
}

// The documented pair order (grid.h), written out plainly over the sorted view:
// per query slot, its own row from the next slot over cells x..x+1, then rows
// (dy, dz) = (1,0), (-1,1), (0,1), (1,1) over x-1..x+1, each in slot order.
test::PairVec documented_order(const kernels::GridView& v, uint32_t n) {
  const int64_t dims[3] = {v.params.dims[0], v.params.dims[1], v.params.dims[2]};
  auto cell_of = [&](uint32_t t) {
    const kernels::SortedBox& q = v.box[t];
    const float p[3] = {q.min_x, q.min_y, q.min_z};
    int64_t c[3];
    for (int k = 0; k < 3; ++k) {
      c[k] = static_cast<int64_t>((static_cast<double>(p[k]) - v.params.origin[k]) * v.params.inv_cell);
      c[k] = std::clamp<int64_t>(c[k], 0, dims[k] - 1);
    }
    return std::array<int64_t, 3>{c[0], c[1], c[2]};
  };
  test::PairVec out;
  for (uint32_t s = 0; s < n; ++s) {
    const kernels::SortedBox& A = v.box[s];
    const auto c = cell_of(s);
    const int64_t rows[5][4] = {{0, 0, 0, 1}, {1, 0, -1, 1}, {-1, 1, -1, 1}, {0, 1, -1, 1}, {1, 1, -1, 1}};
    for (int r = 0; r < 5; ++r) {
      const int64_t y = c[1] + rows[r][0], z = c[2] + rows[r][1];
      if (y < 0 || y >= dims[1] || z >= dims[2]) continue;
      const int64_t x0 = std::max<int64_t>(c[0] + rows[r][2], 0),
                    x1 = std::min<int64_t>(c[0] + rows[r][3], dims[0] - 1);
      // Dense buckets are row-major cells, so the row's cells are one slot range.
      const uint64_t base =
          static_cast<uint64_t>(dims[0]) * (static_cast<uint64_t>(y) + static_cast<uint64_t>(dims[1]) * z);
      const uint32_t t0 = r == 0 ? s + 1 : v.bucket_start[base + x0];
      for (uint32_t t = t0; t < v.bucket_start[base + x1 + 1]; ++t) {
        const kernels::SortedBox& B = v.box[t];
        const auto cb = cell_of(t);
        EXPECT_TRUE(cb[1] == y && cb[2] == z && cb[0] >= x0 && cb[0] <= x1)
            << "slot " << t << " in the wrong bucket";
        if (!kernels::boxes_overlap(A, B)) continue;
        if (v.layer && !kernels::pair_allowed(v.layer[s], v.mask[s], v.is_static[s], v.layer[t], v.mask[t],
                                              v.is_static[t]))
          continue;
        out.emplace_back(std::min(A.index, B.index), std::max(A.index, B.index));
      }
    }
  }
  return out;
}

TEST(GridBroadPhase, DensePairOrderIsTheDocumentedOrder) {
  // Mostly sparse cells (short row ranges, collected into one candidate list) with
  // dense clumps (row ranges longer than the list's run, tested in place): the two
  // must interleave in the documented order.
  std::mt19937 rng(21);
  std::uniform_real_distribution<float> pos(0.0f, 40.0f);
  std::uniform_real_distribution<float> jitter(-0.3f, 0.3f);
  for (bool filtered : {false, true}) {
    Boxes b;
    for (uint32_t i = 0; i < test::scaled(8000); ++i) b.add(pos(rng), pos(rng), pos(rng), 0.5f, 0.5f, 0.5f);
    for (int clump = 0; clump < 30; ++clump) {
      const float x = pos(rng), y = pos(rng), z = pos(rng);
      for (int k = 0; k < 1 + clump; ++k)
        b.add(x + jitter(rng), y + jitter(rng), z + jitter(rng), 0.5f, 0.5f, 0.5f);
    }
    if (filtered) test::add_random_filter(b, 22, 0.2);
    SCOPED_TRACE(filtered ? "filtered" : "unfiltered");
    const uint32_t n = static_cast<uint32_t>(b.size());
    host::GridBroadPhase grid;
    grid.set_level_fraction(0);
    host::Executor exec(Backend::kSerial, 1);
    host::Buffer<kernels::Pair> pairs;
    IMPACT_EXPECT_OK(grid.find_pairs(exec, soa(b), filter(b), n, &pairs));
    const kernels::GridView* v = grid.level_view(0);
    ASSERT_NE(v, nullptr);
    ASSERT_TRUE(v->params.dense);
    const test::PairVec want = documented_order(*v, n);
    EXPECT_EQ(test::to_vec(pairs), want);
    test::expect_same_set(pairs, test::reference_pairs(b), b.size(), "grid");
    // The kernel over ranges of any length, starting anywhere in a row (the dense
    // pass walks its range row by row), concatenates to the same pairs.
    for (uint32_t grain : {1u, 3u, 37u, 1000u}) {
      std::vector<kernels::Pair> part(pairs.size() + 64);
      uint64_t at = 0;
      for (uint32_t lo = 0; lo < n; lo += grain) {
        const uint32_t hi = std::min(n, lo + grain);
        ASSERT_LE(at, pairs.size());
        at += kernels::grid_find_pairs(*v, part.data() + at, part.size() - at, {lo, hi});
      }
      part.resize(at);
      EXPECT_EQ(test::to_vec(part), want) << "ranges of " << grain << " slots";
    }
    // A short output: the full count comes back and the stored prefix is exact.
    for (uint64_t cap : {uint64_t{0}, uint64_t{1}, uint64_t{5}, uint64_t{want.size() / 2}}) {
      std::vector<kernels::Pair> part(cap + 1, kernels::Pair{0xdeadu, 0xbeefu});
      EXPECT_EQ(kernels::grid_find_pairs(*v, part.data(), cap, {0, n}), want.size()) << "capacity " << cap;
      EXPECT_TRUE(part[cap].a == 0xdeadu && part[cap].b == 0xbeefu) << "wrote past capacity " << cap;
      part.resize(cap);
      EXPECT_EQ(test::to_vec(part), test::PairVec(want.begin(), want.begin() + static_cast<ptrdiff_t>(cap)))
          << "capacity " << cap;
    }
    // A row range longer than the candidate list's run occurred.
    uint32_t longest = 0;
    for (uint32_t k = 0; k < v->params.bucket_count; ++k)
      longest = std::max(longest, v->bucket_start[k + 1] - v->bucket_start[k]);
    EXPECT_GT(longest, 8u);
  }
}

TEST(GridBroadPhase, LevelDecisionSameWithOrWithoutSmallestEdge) {
  // Boxes at the level bound: 1/8 of them with edge 1, exactly 16x smaller than
  // the largest (grid_levels puts them on level 2), then with edge 1.0625 (level 1).
  // The summary's min_edge may skip the level count only when no box is that
  // small; a summary that claims nothing (min_edge 0) must decide the same way.
  // Integer corners keep every edge exact in float.
  std::mt19937 rng(31);
  std::uniform_int_distribution<int> pos(0, 200);
  for (float small_edge : {1.0f, 1.0625f}) {
    Boxes b;
    b.add_box(0.0f, 0.0f, 0.0f, 16.0f, 16.0f, 16.0f);
    for (int i = 0; i < 799; ++i) {
      const float e = i % 8 == 0 ? small_edge : 8.0f;
      const float x = static_cast<float>(pos(rng)), y = static_cast<float>(pos(rng)),
                  z = static_cast<float>(pos(rng));
      b.add_box(x, y, z, x + e, y + e * 0.5f, z + e * 0.25f);
    }
    const uint32_t n = static_cast<uint32_t>(b.size());
    host::Executor exec(Backend::kSerial, 1);
    host::Buffer<kernels::BoundsSummary> partials;
    kernels::BoundsSummary sum = host::summarize_bounds(exec, soa(b), n, partials);
    EXPECT_EQ(sum.min_edge, small_edge);
    host::GridBroadPhase with, without;
    with.build(exec, soa(b), filter(b), n, &sum);
    kernels::BoundsSummary blind = sum;
    blind.min_edge = 0.0f;
    without.build(exec, soa(b), filter(b), n, &blind);
    EXPECT_EQ(with.hierarchical(), without.hierarchical()) << small_edge;
    EXPECT_EQ(with.hierarchical(), small_edge == 1.0f) << small_edge;
  }
}


// Far outliers (1e9 m and beyond) must not coarsen the crowd's cells: the grid spans
// a core range (host::grid_extent) and clamps outliers into its boundary cells. The
// old grid spanned the outliers, so its cell grew to extent / 2^21 (~477 m at 1e9,
// the whole crowd in one cell, ~80x slower): the cell check below fails there.
// Pairs: the reference's set and one byte order for every executor (run_grid).
TEST(GridBroadPhase, FarOutliersKeepTheCrowdsCells) {
  const uint32_t n = test::scaled(4000);
  const std::vector<std::vector<float>> cases = {{1e9f}, {1e12f}, {1e18f}, {1e9f, 1e12f, 1e18f}, {3e6f}};
  for (const std::vector<float>& d : cases) {
    const Boxes b = test::outlier_boxes(n, 77, d, /*long_box=*/false);
    const PairVec ref = test::reference_pairs(b);
    // Pairs among the outliers themselves (indices >= n) are part of the set.
    size_t far_pairs = 0;
    for (const auto& p : ref) far_pairs += p.first >= n && p.second >= n;
    EXPECT_GE(far_pairs, 30u * d.size());
    uint32_t levels = 0;
    const host::GridInfo info = run_grid(b, ("outliers at " + std::to_string(d.back())).c_str(), &levels);
    EXPECT_EQ(levels, 1u);
    EXPECT_LE(info.cell, 2.0 * 2.0 * 1.0001) << "cell follows the outliers, not the crowd";
    EXPECT_TRUE(info.dense);
  }
}

// One long box from the crowd to the outliers (a size outlier too: hierarchical
// levels) pairs with crowd boxes and with the far clump it reaches; zero-size
// outliers (point sets) take the same core range.
TEST(GridBroadPhase, FarOutliersWithLevelsAndPointSets) {
  const uint32_t n = test::scaled(3000);
  for (float d : {1e9f, 1e18f}) {
    const Boxes b = test::outlier_boxes(n, 78, {d}, /*long_box=*/true);
    const PairVec ref = test::reference_pairs(b);
    const uint32_t long_box = static_cast<uint32_t>(b.size() - 1);
    size_t with_crowd = 0;
    for (const auto& p : ref) with_crowd += p.second == long_box && p.first < n;
    EXPECT_GT(with_crowd, 0u);
    uint32_t levels = 0;
    run_grid(b, "long box", &levels);
    EXPECT_GT(levels, 1u);
  }
  // Points on a lattice plus far points, some coincident (touching).
  Boxes pts;
  for (int z = 0; z < 16; ++z)
    for (int y = 0; y < 16; ++y)
      for (int x = 0; x < 16; ++x)
        for (int r = 0; r < 1 + (x + y + z) % 2; ++r) pts.add(0.5f * static_cast<float>(x), 0.5f * static_cast<float>(y), 0.5f * static_cast<float>(z), 0, 0, 0);
  for (int j = 0; j < 5; ++j) pts.add(1e12f, 2.0f, -1e15f * static_cast<float>(j % 2), 0, 0, 0);
  const host::GridInfo info = run_grid(pts, "point set with far points");
  EXPECT_LE(info.cell, 8.0) << "point cell follows the outliers";
}

}  // namespace
}  // namespace impact
