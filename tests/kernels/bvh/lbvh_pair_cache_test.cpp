// LBVH fat-box pair cache (LbvhUpdate::kPairCache, kernels/bvh/lbvh_pair_cache.h)
// against the double-precision brute-force reference of tests/support/aabb_reference.h:
// every frame's pairs equal the reference as a set and come in ascending (a, b) order,
// through builds, incremental updates and the rebuilds the policy triggers; on the
// broad phase's adversarial scenes; with filters and a filter change; the grown tree
// still bounds its fat leaves, which contain the exact boxes; the same bytes for every
// backend and thread count; queries answered from the exact boxes.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "host/broadphase/lbvh.h"
#include "host/broadphase/query.h"
#include "host/parallel.h"
#include "kernels/bvh/lbvh_build.h"
#include "support/aabb_reference.h"
#include "support/kernel_views.h"
#include "support/query_reference.h"
#include "support/test_support.h"

namespace impact {
namespace {

using host::Buffer;
using host::LbvhBroadPhase;
using host::LbvhOptions;
using kernels::Pair;
using test::Boxes;
using test::count;
using test::expect_same_set;
using test::filter_of;
using test::reference_pairs;
using test::scaled;
using test::serial;
using test::soa;

LbvhOptions cache_options(float margin = 0.1f) {
  LbvhOptions o;
  o.update = LbvhUpdate::kPairCache;
  o.fat_margin = margin;
  return o;
}

// Ascending (a, b), strictly.
void expect_sorted(const Buffer<Pair>& out, const std::string& what) {
  for (size_t i = 1; i < out.size(); ++i) {
    const bool less = out[i - 1].a < out[i].a || (out[i - 1].a == out[i].a && out[i - 1].b < out[i].b);
    ASSERT_TRUE(less) << what << ": pairs " << i - 1 << " and " << i << " out of order";
  }
}

template <class A, class B>
bool contains(const A& outer, const B& inner) {
  return outer.min_x <= inner.min_x && outer.min_y <= inner.min_y && outer.min_z <= inner.min_z &&
         inner.max_x <= outer.max_x && inner.max_y <= outer.max_y && inner.max_z <= outer.max_z;
}

// The grown tree: each leaf's fat box contains box i's exact box, and every internal
// node contains both children (bounds may be loose, never short).
void check_tree(const LbvhBroadPhase& bp, const Boxes& b, const std::string& what) {
  const kernels::LbvhView v = bp.view();
  {
    SCOPED_TRACE(what);
    test::expect_lanes_mirror_leaves(v);  // grown fat leaves included
  }
  for (uint32_t s = 0; s < v.n; ++s) {
    const uint32_t i = v.leaves[s].index;
    const kernels::SortedBox e{b.min_x[i], b.min_y[i], b.min_z[i], i, b.max_x[i], b.max_y[i], b.max_z[i], 0};
    ASSERT_TRUE(contains(v.leaves[s], e)) << what << ": leaf " << s << " (box " << i << ") misses its box";
  }
  for (uint32_t p = 0; p + 1 < v.n; ++p) {
    const kernels::LbvhNode& m = v.nodes[p];
    const uint32_t h = m.split & kernels::kLbvhSplitMask;
    const bool l = (m.split & kernels::kLbvhLeftLeaf) ? contains(m, v.leaves[h]) : contains(m, v.nodes[h]);
    const bool r =
        (m.split & kernels::kLbvhRightLeaf) ? contains(m, v.leaves[h + 1]) : contains(m, v.nodes[h + 1]);
    ASSERT_TRUE(l && r) << what << ": node " << p << " does not bound its children";
  }
}

// Every box moves by a uniform step in [-step, step] per axis; a fraction `jumps`
// teleports inside [-side / 2, side / 2]^3 (scaled and offset like the scene).
void move(Boxes& b, std::mt19937& rng, float step, double jumps, float side, float offset) {
  std::uniform_real_distribution<float> d(-step, step), pos(-0.5f * side, 0.5f * side);
  std::bernoulli_distribution jump(jumps);
  for (size_t i = 0; i < b.size(); ++i) {
    float* lo[3] = {&b.min_x[i], &b.min_y[i], &b.min_z[i]};
    float* hi[3] = {&b.max_x[i], &b.max_y[i], &b.max_z[i]};
    const bool j = jump(rng);
    for (int k = 0; k < 3; ++k) {
      const float h = 0.5f * (*hi[k] - *lo[k]);
      const float c = j ? offset + pos(rng) : 0.5f * (*lo[k] + *hi[k]) + d(rng);
      *lo[k] = c - h;
      *hi[k] = c + h;
    }
  }
}

struct RunStats {
  int incremental = 0;  // updates that kept the cache (no rebuild)
  int with_movers = 0;  // ... among them, with at least one mover
  int rebuilds = 0;
  int refits = 0;       // updates that fell back to a refit (too many movers)
};

// Build, then `frames` updates of motion; every frame equals the reference.
RunStats run_frames(Boxes b, const std::string& what, int frames, float step, double jumps, float side,
                    float offset = 0.0f, const LbvhOptions& o = cache_options()) {
  RunStats st;
  std::mt19937 rng(7);
  LbvhBroadPhase bp(o);
  Buffer<Pair> out{{7, 3}};  // stale content must be replaced
  for (int f = 0; f <= frames; ++f) {
    const std::string w = what + " frame " + std::to_string(f);
    if (f == 0) {
      IMPACT_EXPECT_OK(bp.build(serial(), soa(b), filter_of(b), count(b)));
    } else {
      IMPACT_EXPECT_OK(bp.update(serial(), soa(b), filter_of(b), count(b)));
      if (bp.info().rebuilt) ++st.rebuilds;
      else if (!bp.info().cached) ++st.refits;
      else {
        ++st.incremental;
        st.with_movers += bp.info().movers > 0;
      }
    }
    IMPACT_EXPECT_OK(bp.pairs(serial(), &out));
    expect_same_set(out, reference_pairs(b), b.size(), w);
    expect_sorted(out, w);
    if (b.size() >= 2 && (f % 10 == 0 || f == frames)) check_tree(bp, b, w);
    if (::testing::Test::HasFailure()) return st;
    move(b, rng, step, jumps, side, offset);
  }
  return st;
}

float side_of(uint32_t n, float half_hi, float scale = 1.0f) {
  return scale * 2.2f * half_hi * std::cbrt(static_cast<float>(std::max(n, 1u)));
}

TEST(LbvhPairCache, SmallCounts) {
  for (uint32_t n : {0u, 1u, 2u, 3u, 5u}) {
    Boxes b = test::uniform_boxes(n, 100 + n, 0.4f, 0.6f);
    run_frames(b, "n=" + std::to_string(n), 30, 0.05f, 0.05, side_of(n, 0.6f));
  }
  Boxes two_touch;
  two_touch.add_box(0, 0, 0, 1, 1, 1);
  two_touch.add_box(1, 1, 1, 2, 2, 2);  // touching at a corner counts
  run_frames(two_touch, "n=2 touching", 5, 0.0f, 0.0, 1.0f);
}

// Slow motion: most updates keep the cache and re-query a few movers; the frames the
// policy rebuilds are checked too.
TEST(LbvhPairCache, UniformHundredFrames) {
  const uint32_t n = scaled(3000);
  const RunStats st = run_frames(test::uniform_boxes(n, 11, 0.2f, 0.6f), "uniform", 100, 0.03f, 0.002,
                                 side_of(n, 0.6f));
  EXPECT_GT(st.with_movers, 50) << "the incremental path barely ran";
  EXPECT_GT(st.rebuilds, 0) << "the movers never added up to a rebuild";
}

TEST(LbvhPairCache, SeveralChunksAndLargeMotion) {
  // Several cache chunks (kLbvhCacheGrain lo indices) and mover chunks; then motion
  // big enough that most updates refit instead (backing off 1, 2, 4, 8 updates between
  // cache rebuilds).
  const uint32_t n = scaled(40000);
  const RunStats slow = run_frames(test::uniform_boxes(n, 12, 0.2f, 0.6f), "uniform large", 12, 0.01f, 0.001,
                                   side_of(n, 0.6f));
  EXPECT_GT(slow.with_movers, 6);
  const RunStats fast = run_frames(test::uniform_boxes(scaled(3000), 13, 0.2f, 0.6f), "uniform fast", 20, 0.5f,
                                   0.05, side_of(scaled(3000), 0.6f));
  EXPECT_GT(fast.refits, 10);
  EXPECT_GE(fast.rebuilds, 3);
}

TEST(LbvhPairCache, Clustered) {
  const RunStats st = run_frames(test::clustered_boxes(scaled(4000), 21), "clustered", 60, 0.01f, 0.002, 100.0f);
  EXPECT_GT(st.with_movers, 20);
}

TEST(LbvhPairCache, SizesSpanning1000x) {
  // Half sizes log-uniform over [0.01, 10]: small boxes have small margins.
  std::mt19937 rng(31);
  std::uniform_real_distribution<float> pos(-60.0f, 60.0f), lg(std::log(0.01f), std::log(10.0f));
  Boxes b;
  for (uint32_t i = 0; i < scaled(4000); ++i)
    b.add(pos(rng), pos(rng), pos(rng), std::exp(lg(rng)), std::exp(lg(rng)), std::exp(lg(rng)));
  const RunStats st = run_frames(b, "mixed sizes", 60, 0.005f, 0.002, 120.0f);
  EXPECT_GT(st.with_movers, 20);
}

TEST(LbvhPairCache, AllBoxesAtOnePointAndZeroSizeBoxes) {
  Boxes one;
  for (uint32_t i = 0; i < 500; ++i) one.add(3, -2, 7, 0.5f, 0.5f, 0.5f);
  run_frames(one, "one point, unit boxes", 20, 0.01f, 0.0, 1.0f, 3.0f);
  // Points on a lattice (touching = same point), some repeated, some unit boxes: the
  // points' margin comes from the largest edge / 1024 floor.
  const Boxes z = test::point_lattice_boxes(2000, 5);
  run_frames(z, "zero-size, still", 5, 0.0f, 0.0, 6.0f);
  run_frames(z, "zero-size, moving", 30, 0.0005f, 0.01, 6.0f, 3.0f);
}

TEST(LbvhPairCache, Scales) {
  const uint32_t n = scaled(3000);
  struct Case {
    const char* name;
    float offset, scale;
  };
  for (const Case& c : {Case{"tiny 1e-4", 0.0f, 1e-4f}, Case{"huge 1e4", 0.0f, 1e4f},
                        Case{"offset 1e6", 1e6f, 1.0f}, Case{"offset -1e6, small", -1e6f, 1e-2f}}) {
    // At 1e6 a float step is 0.0625: motion and margins both round to it.
    const RunStats st = run_frames(test::uniform_boxes(n, 41, 0.2f, 0.6f, c.offset, c.scale), c.name, 40,
                                   0.01f * c.scale, 0.002, side_of(n, 0.6f, c.scale), c.offset);
    EXPECT_GT(st.incremental + st.rebuilds, 0);
  }
}

TEST(LbvhPairCache, FiltersAndFilterChange) {
  for (double static_fraction : {0.0, 0.3, 1.0}) {
    Boxes b = test::uniform_boxes(scaled(3000), 51, 0.2f, 0.8f);
    test::add_random_filter(b, 52, static_fraction);
    const RunStats st = run_frames(b, "filtered, static " + std::to_string(static_fraction), 40, 0.01f, 0.002,
                                   side_of(scaled(3000), 0.8f));
    EXPECT_GT(st.with_movers, 10);
  }
  // A filter change (and adding or dropping the filter) rebuilds; pairs follow it.
  Boxes b = test::uniform_boxes(scaled(3000), 53, 0.2f, 0.8f);
  LbvhBroadPhase bp(cache_options());
  Buffer<Pair> out;
  IMPACT_ASSERT_OK(bp.find_pairs(serial(), soa(b), filter_of(b), count(b), &out));
  expect_same_set(out, reference_pairs(b), b.size(), "unfiltered");
  test::add_random_filter(b, 54, 0.3);
  IMPACT_ASSERT_OK(bp.find_pairs(serial(), soa(b), filter_of(b), count(b), &out));
  EXPECT_TRUE(bp.info().rebuilt);
  expect_same_set(out, reference_pairs(b), b.size(), "filter added");
  IMPACT_ASSERT_OK(bp.find_pairs(serial(), soa(b), filter_of(b), count(b), &out));
  EXPECT_FALSE(bp.info().rebuilt);
  b.mask[17] = 0;
  b.is_static[18] ^= 1;
  IMPACT_ASSERT_OK(bp.find_pairs(serial(), soa(b), filter_of(b), count(b), &out));
  EXPECT_TRUE(bp.info().rebuilt);
  expect_same_set(out, reference_pairs(b), b.size(), "filter changed");
  b.layer.clear(), b.mask.clear(), b.is_static.clear();
  IMPACT_ASSERT_OK(bp.find_pairs(serial(), soa(b), filter_of(b), count(b), &out));
  EXPECT_TRUE(bp.info().rebuilt);
  expect_same_set(out, reference_pairs(b), b.size(), "filter dropped");
}

TEST(LbvhPairCache, PolicyRebuilds) {
  const uint32_t n = scaled(2000, 400);
  Boxes b = test::uniform_boxes(n, 61, 0.2f, 0.6f);
  LbvhOptions o = cache_options();
  o.max_refits = 3;
  LbvhBroadPhase bp(o);
  Buffer<Pair> out;
  IMPACT_ASSERT_OK(bp.find_pairs(serial(), soa(b), filter_of(b), n, &out));
  EXPECT_TRUE(bp.info().rebuilt);
  const uint64_t cached = bp.info().cached_pairs;
  EXPECT_GE(cached, out.size());
  // Still: no movers, the cache stands; after max_refits updates, a rebuild.
  for (int f = 0; f < 3; ++f) {
    IMPACT_ASSERT_OK(bp.find_pairs(serial(), soa(b), filter_of(b), n, &out));
    EXPECT_FALSE(bp.info().rebuilt);
    EXPECT_EQ(bp.info().movers, 0u);
    EXPECT_EQ(bp.info().cached_pairs, cached);
  }
  IMPACT_ASSERT_OK(bp.find_pairs(serial(), soa(b), filter_of(b), n, &out));
  EXPECT_TRUE(bp.info().rebuilt);
  // More than a quarter moving out at once: a refit instead, and once more (back-off
  // 1), then the cache is rebuilt.
  std::mt19937 rng(62);
  move(b, rng, 1.0f, 0.0, 1.0f, 0.0f);
  IMPACT_ASSERT_OK(bp.find_pairs(serial(), soa(b), filter_of(b), n, &out));
  EXPECT_FALSE(bp.info().rebuilt);
  EXPECT_FALSE(bp.info().cached);
  EXPECT_EQ(bp.info().cache_backoff, 1u);
  expect_same_set(out, reference_pairs(b), n, "after a big move");
  move(b, rng, 0.01f, 0.0, 1.0f, 0.0f);
  IMPACT_ASSERT_OK(bp.find_pairs(serial(), soa(b), filter_of(b), n, &out));
  EXPECT_FALSE(bp.info().rebuilt);
  EXPECT_FALSE(bp.info().cached);
  EXPECT_EQ(bp.info().cache_backoff, 0u);
  expect_same_set(out, reference_pairs(b), n, "backing off");
  IMPACT_ASSERT_OK(bp.find_pairs(serial(), soa(b), filter_of(b), n, &out));
  EXPECT_TRUE(bp.info().rebuilt);
  EXPECT_TRUE(bp.info().cached);
  expect_same_set(out, reference_pairs(b), n, "cache rebuilt");
  // One box teleported: one mover, no rebuild.
  const float d = 5.0f;
  b.min_x[9] += d, b.max_x[9] += d;
  IMPACT_ASSERT_OK(bp.find_pairs(serial(), soa(b), filter_of(b), n, &out));
  EXPECT_FALSE(bp.info().rebuilt);
  EXPECT_EQ(bp.info().movers, 1u);
  expect_same_set(out, reference_pairs(b), n, "one mover");
  // A margin of 0: every moving box is a mover (correct, only slower).
  LbvhBroadPhase tight(cache_options(0.0f));
  IMPACT_ASSERT_OK(tight.find_pairs(serial(), soa(b), filter_of(b), n, &out));
  b.min_y[3] += 0.001f, b.max_y[3] += 0.001f;
  IMPACT_ASSERT_OK(tight.find_pairs(serial(), soa(b), filter_of(b), n, &out));
  EXPECT_EQ(tight.info().movers, 1u);
  expect_same_set(out, reference_pairs(b), n, "margin 0");
}

// Leaving kPairCache drops the fat tree; refit() gives exact leaves back.
TEST(LbvhPairCache, SwitchingPolicyAndExplicitRefit) {
  const uint32_t n = scaled(2000, 400);
  Boxes b = test::uniform_boxes(n, 71, 0.2f, 0.6f);
  LbvhBroadPhase bp(cache_options());
  Buffer<Pair> out;
  IMPACT_ASSERT_OK(bp.find_pairs(serial(), soa(b), filter_of(b), n, &out));
  IMPACT_ASSERT_OK(bp.refit(serial(), soa(b), filter_of(b), n, &out));
  expect_same_set(out, reference_pairs(b), n, "explicit refit of a cache tree");
  IMPACT_ASSERT_OK(bp.find_pairs(serial(), soa(b), filter_of(b), n, &out));
  EXPECT_TRUE(bp.info().rebuilt);
  expect_same_set(out, reference_pairs(b), n, "update after refit");
  LbvhOptions o = bp.options();
  o.update = LbvhUpdate::kRefit;
  bp.set_options(o);
  IMPACT_ASSERT_OK(bp.find_pairs(serial(), soa(b), filter_of(b), n, &out));
  EXPECT_TRUE(bp.info().rebuilt);
  expect_same_set(out, reference_pairs(b), n, "switched to refit");
}

TEST(LbvhPairCache, SameBytesForEveryExecutor) {
  const uint32_t n = scaled(40000, 3000);
  std::vector<Pair> first;
  for (const test::ExecCase& c : test::exec_cases()) {
    SCOPED_TRACE(test::to_string(c));
    const host::Executor exec(c.backend, c.threads);
    Boxes b = test::uniform_boxes(n, 81, 0.2f, 0.6f);
    test::add_random_filter(b, 82, 0.2);
    std::mt19937 rng(83);
    LbvhBroadPhase bp(cache_options());
    Buffer<Pair> out;
    std::vector<Pair> all;
    for (int f = 0; f < 6; ++f) {
      IMPACT_ASSERT_OK(bp.find_pairs(exec, soa(b), filter_of(b), n, &out));
      if (first.empty()) {  // the other executors are held to these bytes
        expect_same_set(out, reference_pairs(b), n, "frame " + std::to_string(f));
        expect_sorted(out, "frame " + std::to_string(f));
      }
      all.insert(all.end(), out.begin(), out.end());
      move(b, rng, 0.02f, 0.002, side_of(n, 0.6f), 0.0f);
    }
    if (first.empty()) {
      first = all;
      continue;
    }
    ASSERT_EQ(all.size(), first.size());
    for (size_t i = 0; i < all.size(); ++i)
      ASSERT_TRUE(all[i].a == first[i].a && all[i].b == first[i].b) << "pair " << i;
  }
}

// Queries of a cache tree hit the exact boxes, not the fat ones.
TEST(LbvhPairCache, QueriesUseTheExactBoxes) {
  const uint32_t n = scaled(3000);
  Boxes b = test::uniform_boxes(n, 91, 0.2f, 0.6f);
  test::add_random_filter(b, 92, 0.2);
  std::mt19937 rng(93);
  LbvhBroadPhase bp(cache_options(0.5f));
  host::BroadPhaseQuery run;
  IMPACT_ASSERT_OK(bp.build(serial(), soa(b), filter_of(b), n));
  for (int frame = 0; frame < 4; ++frame) {
    for (test::QShape shape : {test::QShape::kAabb, test::QShape::kSphere, test::QShape::kPoint}) {
      const test::Queries q = test::random_queries(b, shape, 400, 94 + frame, 0.5f, 1);
      const test::Csr ref = test::reference_query(b, q);
      test::Csr got;
      IMPACT_ASSERT_OK(run.query(serial(), bp, test::query_batch(q), &got.offsets, &got.hits));
      EXPECT_TRUE(test::SameCsr(got, ref)) << test::to_string(shape) << " frame " << frame;
    }
    move(b, rng, 0.05f, 0.01, side_of(n, 0.6f), 0.0f);
    IMPACT_ASSERT_OK(bp.update(serial(), soa(b), filter_of(b), n));
  }
}

}  // namespace
}  // namespace impact
