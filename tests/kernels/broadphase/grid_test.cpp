// Grid broad-phase kernels (kernels/broadphase/grid.*) driven through their host
// wrapper host::GridBroadPhase, so the test can see which bucket mode the grid
// chose (GridInfo) and force both: dense row-major buckets and hashed buckets,
// where unrelated cells share buckets. Pairs are compared with the independent
// double-precision reference of tests/support/aabb_reference.h.
#include "kernels/broadphase/grid.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "host/broadphase/broadphase.h"
#include "host/parallel.h"
#include "kernels/broadphase/bounds.h"
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
  double lo[3] = {1e300, 1e300, 1e300}, hi[3] = {-1e300, -1e300, -1e300}, edge = 0;
  for (size_t i = 0; i < b.size(); ++i) {
    const float mn[3] = {b.min_x[i], b.min_y[i], b.min_z[i]}, mx[3] = {b.max_x[i], b.max_y[i], b.max_z[i]};
    for (int k = 0; k < 3; ++k) {
      lo[k] = std::min<double>(lo[k], mn[k]);
      hi[k] = std::max<double>(hi[k], mx[k]);
      edge = std::max<double>(edge, mx[k] - mn[k]);  // float subtraction, as the kernel's edge
    }
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
  }
}

}  // namespace
}  // namespace impact
