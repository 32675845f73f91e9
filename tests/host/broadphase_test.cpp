// Broad phase (impact::BroadPhase and the world's broad-phase pass) against an
// independent double-precision reference: an O(n^2) all-pairs test for small and
// medium inputs, and a sort-and-sweep on x for large ones (tests/support/aabb_reference.h),
// both written from the documented contract (world.h / broadphase.h):
//   boxes i < j pair  <=>  min <= max on all axes (touching counts),
//                          (layer_i & mask_j) && (layer_j & mask_i),
//                          not (static_i && static_j).
// Pairs are compared as sets; each pair must have a < b and appear once.
// Pair order must be the same bytes for every backend and thread count.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>
#include <set>
#include <utility>
#include <vector>

#include "impact/impact.h"
#include "support/aabb_reference.h"
#include "support/test_support.h"

namespace impact {
namespace {

using test::Boxes;
using test::clustered_boxes;
using test::uniform_boxes;
using test::exec_cases;
using test::ExecCase;
using test::expect_same_set;
using test::IsError;
using test::PairVec;
using test::reference_pairs;
using test::scaled;

// Grid and brute-force structures vs the reference, serial and default executors.
void check_all(const Boxes& boxes, const char* what) {
  SCOPED_TRACE(what);
  const PairVec ref = reference_pairs(boxes);
  for (BroadPhaseKind kind : {BroadPhaseKind::kGrid, BroadPhaseKind::kLbvh, BroadPhaseKind::kSweepAndPrune,
                              BroadPhaseKind::kBruteForce}) {
    if (kind == BroadPhaseKind::kBruteForce && boxes.size() > 20000) continue;
    BroadPhase bp(kind);
    EXPECT_EQ(bp.kind(), kind);
    for (ExecConfig exec : {ExecConfig{Backend::kSerial, 1}, ExecConfig{}}) {
      std::vector<BodyPair> pairs{{7, 3}};  // stale content must be replaced
      IMPACT_ASSERT_OK(bp.find_pairs(boxes.input(), &pairs, exec));
      expect_same_set(pairs, ref, boxes.size(), to_string(kind));
    }
  }
}

// --- generators -------------------------------------------------------------------------



// Half sizes log-uniform over 100x.
Boxes wide_size_boxes(uint32_t n, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> logh(std::log(0.05f), std::log(5.0f));
  std::uniform_real_distribution<float> pos(-30.0f, 30.0f);
  Boxes b;
  for (uint32_t i = 0; i < n; ++i) {
    const float h = std::exp(logh(rng));
    b.add(pos(rng), pos(rng), pos(rng), h, h * 0.7f, h);
  }
  return b;
}

// --- correctness vs reference -----------------------------------------------------------

TEST(BroadPhase, EmptyOneTwo) {
  Boxes none;
  check_all(none, "n=0");
  Boxes one;
  one.add(0, 0, 0, 1, 1, 1);
  check_all(one, "n=1");

  Boxes overlap;
  overlap.add(0, 0, 0, 1, 1, 1);
  overlap.add(1.5f, 0.5f, -0.5f, 1, 1, 1);
  check_all(overlap, "n=2 overlapping");
  EXPECT_EQ(reference_pairs(overlap).size(), 1u);

  Boxes touching;  // max_x of 0 == min_x of 1: touching counts as overlap
  touching.add_box(0, 0, 0, 1, 1, 1);
  touching.add_box(1, 1, 1, 2, 2, 2);
  check_all(touching, "n=2 touching at a corner");
  EXPECT_EQ(reference_pairs(touching).size(), 1u);

  Boxes apart;
  apart.add_box(0, 0, 0, 1, 1, 1);
  apart.add_box(std::nextafter(1.0f, 2.0f), 0, 0, 2, 1, 1);
  check_all(apart, "n=2 one ulp apart");
  EXPECT_EQ(reference_pairs(apart).size(), 0u);
}

TEST(BroadPhase, UniformRandom) {
  for (uint32_t seed : {1u, 2u, 3u}) check_all(uniform_boxes(scaled(3000), seed, 0.2f, 1.0f), "uniform");
}

TEST(BroadPhase, NegativeAndPositiveCoordinates) {
  Boxes b = uniform_boxes(scaled(2000), 11, 0.1f, 0.6f, -3.0f);
  check_all(b, "straddling zero");
}

TEST(BroadPhase, ClusteredGaussianBlobs) {
  check_all(clustered_boxes(scaled(3000), 4), "clustered");
}

TEST(BroadPhase, RadiiSpanning100x) {
  check_all(wide_size_boxes(scaled(3000), 5), "sizes over 100x");
}

TEST(BroadPhase, EverythingInOneCell) {
  Boxes b;
  const uint32_t n = scaled(600);
  for (uint32_t i = 0; i < n; ++i) b.add(3.0f, -2.0f, 7.0f, 0.5f, 0.5f, 0.5f);
  check_all(b, "identical boxes");
  EXPECT_EQ(reference_pairs(b).size(), static_cast<size_t>(n) * (n - 1) / 2);
}

TEST(BroadPhase, AllZeroSizeAtOnePoint) {
  Boxes b;
  const uint32_t n = scaled(300);
  for (uint32_t i = 0; i < n; ++i) b.add(-1.0f, 4.0f, 2.0f, 0, 0, 0);
  check_all(b, "points at one place");
  EXPECT_EQ(reference_pairs(b).size(), static_cast<size_t>(n) * (n - 1) / 2);
}

TEST(BroadPhase, ZeroSizeBoxesOnALattice) {
  // Points drawn from a small lattice: coincident points pair, all others do not.
  std::mt19937 rng(6);
  std::uniform_int_distribution<int> c(-4, 5);
  Boxes b;
  for (uint32_t i = 0; i < scaled(1500); ++i)
    b.add(static_cast<float>(c(rng)), static_cast<float>(c(rng)), static_cast<float>(c(rng)), 0, 0, 0);
  check_all(b, "zero-size lattice points");
  EXPECT_GT(reference_pairs(b).size(), 0u);
  // Mixed with a few real boxes.
  for (int i = 0; i < 20; ++i) b.add(static_cast<float>(c(rng)) + 0.5f, 0.5f, 0.5f, 0.5f, 0.5f, 0.5f);
  check_all(b, "zero-size points plus unit boxes");
}

TEST(BroadPhase, TouchingUnitLattice) {
  // Unit boxes [i, i+1]^3 on an integer lattice: every box touches its 26
  // neighbours exactly (max == min). The cell edge equals the box edge here, the
  // tightest case of the grid's "cell > largest edge" argument.
  Boxes b;
  const int k = 9;
  for (int z = 0; z < k; ++z)
    for (int y = 0; y < k; ++y)
      for (int x = 0; x < k; ++x)
        b.add_box(static_cast<float>(x), static_cast<float>(y), static_cast<float>(z),
                  static_cast<float>(x + 1), static_cast<float>(y + 1), static_cast<float>(z + 1));
  check_all(b, "touching lattice");
  // Neighbour pairs in a k^3 lattice with the 26-neighbourhood.
  const size_t km = static_cast<size_t>(k), k1 = km - 1;
  const size_t expected = 3 * k1 * km * km + 6 * k1 * k1 * km + 4 * k1 * k1 * k1;
  EXPECT_EQ(reference_pairs(b).size(), expected);
}

TEST(BroadPhase, CoordinatesOffsetBy1e5) {
  check_all(uniform_boxes(scaled(2000), 7, 0.2f, 1.0f, 1.0e5f), "offset +1e5");
  check_all(uniform_boxes(scaled(2000), 8, 0.2f, 1.0f, -1.0e5f), "offset -1e5");
}

TEST(BroadPhase, LayerMaskAndStaticFilters) {
  for (uint32_t seed : {21u, 22u}) {
    Boxes b = uniform_boxes(scaled(3000), seed, 0.3f, 1.2f);
    test::add_random_filter(b, seed, 0.3);
    check_all(b, "filtered");
    // The filter removes something, and static-static pairs never appear.
    Boxes unfiltered = b;
    unfiltered.layer.clear();
    unfiltered.mask.clear();
    unfiltered.is_static.clear();
    EXPECT_LT(reference_pairs(b).size(), reference_pairs(unfiltered).size());
  }
  // All static: no pairs at all, even though every box overlaps.
  Boxes b;
  for (int i = 0; i < 50; ++i) b.add(0, 0, 0, 1, 1, 1);
  b.layer.assign(50, 1u);
  b.mask.assign(50, 0xffffffffu);
  b.is_static.assign(50, 1);
  check_all(b, "all static");
  std::vector<BodyPair> pairs;
  BroadPhase grid;
  IMPACT_ASSERT_OK(grid.find_pairs(b.input(), &pairs));
  EXPECT_TRUE(pairs.empty());
  // One dynamic among them pairs with every static one.
  b.is_static[17] = 0;
  IMPACT_ASSERT_OK(grid.find_pairs(b.input(), &pairs));
  EXPECT_EQ(pairs.size(), 49u);
  for (const BodyPair& p : pairs) EXPECT_TRUE(p.a == 17 || p.b == 17);
}

TEST(BroadPhase, SparseHugeWorld) {
  // A few boxes over 1e6 m: the dense grid would need ~1e18 cells, so the grid
  // must hash (tests/kernels/broadphase/grid_test.cpp asserts the mode). Some
  // boxes are placed in overlapping clumps so there are pairs to find.
  std::mt19937 rng(9);
  std::uniform_real_distribution<float> pos(-5.0e5f, 5.0e5f);
  std::uniform_real_distribution<float> jitter(-1.0f, 1.0f);
  Boxes b;
  for (int i = 0; i < 300; ++i) {
    const float x = pos(rng), y = pos(rng), z = pos(rng);
    b.add(x, y, z, 1.0f, 1.0f, 1.0f);
    if (i % 3 == 0) b.add(x + jitter(rng), y + jitter(rng), z + jitter(rng), 0.8f, 1.2f, 0.9f);
  }
  check_all(b, "sparse 1e6 m world");
  EXPECT_GE(reference_pairs(b).size(), 100u);
}

// --- determinism of pair order ------------------------------------------------------------

TEST(BroadPhase, PairOrderIndependentOfThreadsAndBackend) {
  // Large enough for several key, sort and pair chunks (grains 2^14, 2^16, 2^11).
  Boxes b = uniform_boxes(scaled(150000), 31, 0.2f, 1.0f);
  test::add_random_filter(b, 31, 0.1);
  const PairVec ref = reference_pairs(b);
  BroadPhase grid(BroadPhaseKind::kGrid);
  std::vector<BodyPair> first;
  IMPACT_ASSERT_OK(grid.find_pairs(b.input(), &first, ExecConfig{Backend::kSerial, 1}));
  expect_same_set(first, ref, b.size(), "serial");
  for (const ExecCase& c : exec_cases()) {
    std::vector<BodyPair> pairs;
    IMPACT_ASSERT_OK(grid.find_pairs(b.input(), &pairs, ExecConfig{c.backend, c.threads}));
    EXPECT_TRUE(pairs == first) << test::to_string(c);
    // A fresh instance (no reused scratch) gives the same bytes too.
    BroadPhase fresh;
    std::vector<BodyPair> again;
    IMPACT_ASSERT_OK(fresh.find_pairs(b.input(), &again, ExecConfig{c.backend, c.threads}));
    EXPECT_TRUE(again == first) << test::to_string(c) << " fresh";
  }
}

// --- bad input --------------------------------------------------------------------------

TEST(BroadPhase, RejectsNonFiniteAndInvertedBoxes) {
  Boxes good = uniform_boxes(8, 1, 0.5f, 1.0f);
  BroadPhase bp;
  std::vector<BodyPair> pairs;
  IMPACT_ASSERT_OK(bp.find_pairs(good.input(), &pairs));

  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inf = std::numeric_limits<float>::infinity();
  {
    Boxes b = good;
    b.min_y[3] = nan;
    EXPECT_TRUE(IsError(bp.find_pairs(b.input(), &pairs), StatusCode::kInvalidArgument, {"box 3", "min_y"}));
  }
  {
    Boxes b = good;
    b.max_z[5] = inf;
    EXPECT_TRUE(IsError(bp.find_pairs(b.input(), &pairs), StatusCode::kInvalidArgument, {"box 5", "max_z"}));
  }
  {
    Boxes b = good;
    b.min_x[6] = -inf;
    EXPECT_TRUE(IsError(bp.find_pairs(b.input(), &pairs), StatusCode::kInvalidArgument, {"box 6", "min_x"}));
  }
  {
    Boxes b = good;
    b.min_z[2] = b.max_z[2] + 0.25f;  // min > max
    EXPECT_TRUE(IsError(bp.find_pairs(b.input(), &pairs), StatusCode::kInvalidArgument, {"box 2", "min_z"}));
  }
  {
    Boxes c = good;
    c.max_y.pop_back();
    EXPECT_TRUE(IsError(bp.find_pairs(c.input(), &pairs), StatusCode::kSizeMismatch, {"max_y"}));
  }
  {
    Boxes b = good;
    test::add_random_filter(b, 3, 0.5);
    b.mask.pop_back();
    EXPECT_TRUE(IsError(bp.find_pairs(b.input(), &pairs), StatusCode::kSizeMismatch));
  }
  EXPECT_TRUE(IsError(bp.find_pairs(good.input(), nullptr), StatusCode::kInvalidArgument));
  // The brute-force structure validates the same way.
  BroadPhase brute(BroadPhaseKind::kBruteForce);
  Boxes b = good;
  b.max_x[4] = nan;
  EXPECT_TRUE(IsError(brute.find_pairs(b.input(), &pairs), StatusCode::kInvalidArgument, {"box 4", "max_x"}));
}

TEST(BroadPhase, RejectsBadBoxesInAnyChunkAndLane) {
  // Validation runs in 65536-box chunks of 8-lane blocks plus a scalar tail, together with
  // the bounds summary: a bad box anywhere (a later chunk, the last block, the tail) is
  // still found, and the good input's pairs are still right.
  const uint32_t n = 3 * 65536 + 13;
  Boxes good = uniform_boxes(n, 7, 0.2f, 0.6f);
  BroadPhase bp(BroadPhaseKind::kLbvh);
  std::vector<BodyPair> pairs;
  IMPACT_ASSERT_OK(bp.find_pairs(good.input(), &pairs));
  expect_same_set(pairs, reference_pairs(good), good.size(), "lbvh");
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (const uint32_t at : {70001u, n - 14, n - 9, n - 1}) {
    const std::string box = "box " + std::to_string(at) + " ";
    {
      Boxes b = good;
      b.max_y[at] = nan;
      EXPECT_TRUE(IsError(bp.find_pairs(b.input(), &pairs), StatusCode::kInvalidArgument,
                          {(box + "max_y").c_str()}));
    }
    {
      Boxes b = good;
      b.min_x[at] = -2e18f;
      EXPECT_TRUE(IsError(bp.find_pairs(b.input(), &pairs), StatusCode::kInvalidArgument,
                          {(box + "min_x").c_str()}));
    }
    {
      Boxes b = good;
      b.min_z[at] = b.max_z[at] + 1e-3f;
      EXPECT_TRUE(IsError(bp.find_pairs(b.input(), &pairs), StatusCode::kInvalidArgument,
                          {(box + "min_z").c_str()}));
    }
  }
}

// --- world level ------------------------------------------------------------------------

struct SphereScene {
  std::vector<BodyDesc> descs;
};

SphereScene random_spheres(uint32_t n, uint32_t seed, bool with_filters) {
  std::mt19937 rng(seed);
  const float side = 1.6f * std::cbrt(static_cast<float>(n));
  std::uniform_real_distribution<float> pos(-0.5f * side, 0.5f * side);
  std::uniform_real_distribution<float> logr(std::log(0.05f), std::log(1.0f));
  std::uniform_int_distribution<uint32_t> bits(0, 2);
  std::bernoulli_distribution is_static(0.25);
  SphereScene s;
  for (uint32_t i = 0; i < n; ++i) {
    BodyDesc d;
    d.position = {pos(rng), pos(rng), pos(rng)};
    d.radius = std::exp(logr(rng));
    if (with_filters) {
      d.layer = 1u << bits(rng);
      d.mask = (i % 2) ? 0xffffffffu : (0x7u & ~(1u << bits(rng)));
      d.inv_mass = is_static(rng) ? 0.0f : 1.0f;
    }
    s.descs.push_back(d);
  }
  return s;
}

// The boxes the world builds for its spheres: [p - r, p + r] in float.
Boxes world_boxes(const World& w) {
  const BodyArrays a = w.bodies();
  Boxes b;
  for (size_t i = 0; i < a.size(); ++i) {
    const float r = a.radius[i];
    b.add_box(a.pos_x[i] - r, a.pos_y[i] - r, a.pos_z[i] - r, a.pos_x[i] + r, a.pos_y[i] + r, a.pos_z[i] + r);
    b.layer.push_back(a.layer[i]);
    b.mask.push_back(a.mask[i]);
    b.is_static.push_back(a.inv_mass[i] == 0.0f ? 1 : 0);
  }
  return b;
}

std::vector<BodyPair> copy_pairs(const World& w) {
  const auto p = w.pairs();
  return {p.begin(), p.end()};
}

TEST(WorldBroadPhase, PairsMatchReferenceWithFilters) {
  for (bool filters : {false, true}) {
    SCOPED_TRACE(filters ? "filtered" : "unfiltered");
    const SphereScene scene = random_spheres(scaled(4000), filters ? 41 : 42, filters);
    auto world = test::make_world(test::zero_gravity_desc());
    ASSERT_TRUE(world);
    std::vector<BodyHandle> h(scene.descs.size());
    IMPACT_ASSERT_OK(world->create_bodies(scene.descs, h));
    // At rest without gravity the integrator leaves positions bit-identical, so the
    // boxes of the step are the boxes of the creation-time positions.
    const Boxes boxes = world_boxes(*world);
    IMPACT_ASSERT_OK(world->step());
    const PairVec ref = reference_pairs(boxes);
    ASSERT_GT(ref.size(), 0u);
    expect_same_set(copy_pairs(*world), ref, boxes.size(), "world grid");
    EXPECT_EQ(world->last_step().pairs, ref.size());

    // Same set through the brute-force structure, on an identical fresh world.
    auto brute = test::make_world(test::zero_gravity_desc());
    IMPACT_ASSERT_OK(brute->set_broad_phase(BroadPhaseKind::kBruteForce));
    IMPACT_ASSERT_OK(brute->create_bodies(scene.descs, h));
    IMPACT_ASSERT_OK(brute->step());
    expect_same_set(copy_pairs(*brute), ref, boxes.size(), "world brute force");

    // And through the LBVH.
    auto lbvh = test::make_world(test::zero_gravity_desc());
    IMPACT_ASSERT_OK(lbvh->set_broad_phase(BroadPhaseKind::kLbvh));
    IMPACT_ASSERT_OK(lbvh->create_bodies(scene.descs, h));
    IMPACT_ASSERT_OK(lbvh->step());
    expect_same_set(copy_pairs(*lbvh), ref, boxes.size(), "world lbvh");

    // And through sweep-and-prune.
    auto sap = test::make_world(test::zero_gravity_desc());
    IMPACT_ASSERT_OK(sap->set_broad_phase(BroadPhaseKind::kSweepAndPrune));
    IMPACT_ASSERT_OK(sap->create_bodies(scene.descs, h));
    IMPACT_ASSERT_OK(sap->step());
    expect_same_set(copy_pairs(*sap), ref, boxes.size(), "world sweep-and-prune");
  }
}

TEST(WorldBroadPhase, LbvhWorldStateIndependentOfThreadsAndBackend) {
  // A falling, colliding scene stepped with the LBVH broad phase: the same state
  // bytes for every backend and thread count.
  const SphereScene scene = random_spheres(scaled(3000), 44, true);
  uint64_t first = 0;
  for (const ExecCase& c : exec_cases()) {
    WorldDesc d;
    d.broad_phase = BroadPhaseKind::kLbvh;
    d.backend = c.backend;
    d.threads = c.threads;
    auto world = test::make_world(d);
    ASSERT_TRUE(world);
    std::vector<BodyHandle> h(scene.descs.size());
    IMPACT_ASSERT_OK(world->create_bodies(scene.descs, h));
    for (int k = 0; k < 30; ++k) IMPACT_ASSERT_OK(world->step());
    ASSERT_GT(world->last_step().contacts, 0u);
    if (first == 0) {
      first = world->state_hash();
      continue;
    }
    EXPECT_EQ(world->state_hash(), first) << test::to_string(c);
  }
}

TEST(WorldBroadPhase, PairOrderIndependentOfThreadsAndBackend) {
  const SphereScene scene = random_spheres(scaled(30000), 43, true);
  std::vector<BodyPair> first;
  for (const ExecCase& c : exec_cases()) {
    WorldDesc d = test::zero_gravity_desc();
    d.backend = c.backend;
    d.threads = c.threads;
    auto world = test::make_world(d);
    ASSERT_TRUE(world);
    std::vector<BodyHandle> h(scene.descs.size());
    IMPACT_ASSERT_OK(world->create_bodies(scene.descs, h));
    IMPACT_ASSERT_OK(world->step());
    const std::vector<BodyPair> pairs = copy_pairs(*world);
    if (first.empty()) {
      first = pairs;
      ASSERT_FALSE(first.empty());
      continue;
    }
    EXPECT_TRUE(pairs == first) << test::to_string(c);
  }
}

}  // namespace
}  // namespace impact
