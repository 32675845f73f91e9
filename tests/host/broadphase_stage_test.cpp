// The broad-phase stage behind impact::BroadPhase and World: build / update / pairs,
// the LBVH update policies, the automatic choice, and the swept-bounds input mode,
// each against the independent double-precision reference of
// tests/support/aabb_reference.h (pairs compared as sets).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "impact/impact.h"
#include "support/aabb_reference.h"
#include "support/test_support.h"

namespace impact {
namespace {

using test::Boxes;
using test::expect_same_set;
using test::IsError;
using test::PairVec;
using test::reference_pairs;
using test::scaled;

// Boxes whose largest edges are log-uniform over [e_min, e_max], centres uniform in
// a cube sized for a few overlaps per box (times `spread` per axis: sparse worlds).
Boxes log_uniform_boxes(uint32_t n, uint32_t seed, float h_min, float h_max, float spread = 1.0f) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> lh(std::log(h_min), std::log(h_max));
  // Volume-weighted mean of (2h)^3 for log-uniform h: sets the cube for ~2 pairs/box.
  const double mean_vol = 8.0 * (std::pow(h_max, 3.0) - std::pow(h_min, 3.0)) /
                          (3.0 * (std::log(h_max) - std::log(h_min)));
  const float side = spread * static_cast<float>(std::cbrt(n * mean_vol));
  std::uniform_real_distribution<float> pos(-0.5f * side, 0.5f * side);
  Boxes b;
  for (uint32_t i = 0; i < n; ++i) {
    const float h = std::exp(lh(rng));
    b.add(pos(rng), pos(rng), pos(rng), h, h, h);
  }
  return b;
}

// Every box moves by up to `step` per axis, reflected into [-side/2, side/2].
void jiggle(Boxes& b, std::mt19937& rng, float step) {
  std::uniform_real_distribution<float> d(-step, step);
  for (size_t i = 0; i < b.size(); ++i) {
    float* lo[3] = {&b.min_x[i], &b.min_y[i], &b.min_z[i]};
    float* hi[3] = {&b.max_x[i], &b.max_y[i], &b.max_z[i]};
    for (int k = 0; k < 3; ++k) {
      const float s = d(rng);
      *lo[k] += s;
      *hi[k] += s;
    }
  }
}

// Swept boxes in double, rounded the way the contract states: min(lo, lo + d), max(hi, hi + d)
// with the sums in float (as the caller's moved box would be).
Boxes swept_reference_boxes(const Boxes& b, const std::vector<float>& dx, const std::vector<float>& dy,
                            const std::vector<float>& dz) {
  Boxes s = b;
  for (size_t i = 0; i < b.size(); ++i) {
    s.min_x[i] = std::min(b.min_x[i], b.min_x[i] + dx[i]);
    s.min_y[i] = std::min(b.min_y[i], b.min_y[i] + dy[i]);
    s.min_z[i] = std::min(b.min_z[i], b.min_z[i] + dz[i]);
    s.max_x[i] = std::max(b.max_x[i], b.max_x[i] + dx[i]);
    s.max_y[i] = std::max(b.max_y[i], b.max_y[i] + dy[i]);
    s.max_z[i] = std::max(b.max_z[i], b.max_z[i] + dz[i]);
  }
  return s;
}

const BroadPhaseKind kAllKinds[] = {BroadPhaseKind::kGrid, BroadPhaseKind::kLbvh, BroadPhaseKind::kSweepAndPrune,
                                    BroadPhaseKind::kBruteForce, BroadPhaseKind::kAuto};

TEST(BroadPhaseStage, BuildThenPairsEqualsFindPairsForEveryKind) {
  Boxes b = test::uniform_boxes(scaled(3000), 3, 0.1f, 0.6f);
  test::add_random_filter(b, 4, 0.2);
  const PairVec ref = reference_pairs(b);
  for (BroadPhaseKind kind : kAllKinds) {
    SCOPED_TRACE(to_string(kind));
    BroadPhase bp(kind);
    std::vector<BodyPair> got{{1, 0}};
    IMPACT_ASSERT_OK(bp.pairs(&got));
    EXPECT_TRUE(got.empty()) << "pairs() before any build";
    EXPECT_EQ(bp.size(), 0u);
    IMPACT_ASSERT_OK(bp.build(b.input()));
    EXPECT_EQ(bp.size(), b.size());
    IMPACT_ASSERT_OK(bp.pairs(&got));
    expect_same_set(got, ref, b.size(), "build + pairs");
    // pairs() twice gives the same bytes; find_pairs on the same boxes too.
    std::vector<BodyPair> again, found;
    IMPACT_ASSERT_OK(bp.pairs(&again));
    IMPACT_ASSERT_OK(bp.find_pairs(b.input(), &found));
    ASSERT_EQ(again.size(), got.size());
    ASSERT_EQ(found.size(), got.size());
    EXPECT_TRUE(std::equal(got.begin(), got.end(), again.begin(),
                           [](BodyPair x, BodyPair y) { return x.a == y.a && x.b == y.b; }));
  }
}

// 100 frames of coherent motion through every update path (LBVH refit policies, SAP
// insertion sort, grid and brute-force rebuilds): every frame equals the reference.
TEST(BroadPhaseStage, HundredFramesOfMotionThroughEveryUpdatePolicy) {
  struct Case {
    BroadPhaseKind kind;
    LbvhUpdate update;
  };
  const Case cases[] = {{BroadPhaseKind::kGrid, LbvhUpdate::kRebuild},
                        {BroadPhaseKind::kLbvh, LbvhUpdate::kRebuild},
                        {BroadPhaseKind::kLbvh, LbvhUpdate::kRefit},
                        {BroadPhaseKind::kLbvh, LbvhUpdate::kAuto},
                        {BroadPhaseKind::kLbvh, LbvhUpdate::kPairCache},
                        {BroadPhaseKind::kSweepAndPrune, LbvhUpdate::kRebuild},
                        {BroadPhaseKind::kAuto, LbvhUpdate::kRefit}};
  const uint32_t n = scaled(1500, 300);
  const int frames = test::kSanitized ? 30 : 100;
  for (const Case& c : cases) {
    const std::string what = std::string(to_string(c.kind)) + "/" + to_string(c.update);
    SCOPED_TRACE(what);
    Boxes b = test::uniform_boxes(n, 11, 0.2f, 0.5f);
    test::add_random_filter(b, 12, 0.1);
    std::mt19937 rng(13);
    BroadPhaseOptions o;
    o.kind = c.kind;
    o.lbvh_update = c.update;
    o.lbvh_refit_sah_limit = 1.2;
    BroadPhase bp(o);
    std::vector<BodyPair> got;
    for (int f = 0; f < frames; ++f) {
      IMPACT_ASSERT_OK(f == 0 ? bp.build(b.input()) : bp.update(b.input()));
      IMPACT_ASSERT_OK(bp.pairs(&got));
      expect_same_set(got, reference_pairs(b), b.size(), what + " frame " + std::to_string(f));
      if (HasFailure()) return;
      jiggle(b, rng, 0.15f);
    }
  }
}

// An update with a different box count rebuilds (no stale tree or order is reused).
TEST(BroadPhaseStage, UpdateWithNewCountRebuilds) {
  for (BroadPhaseKind kind : kAllKinds) {
    SCOPED_TRACE(to_string(kind));
    BroadPhase bp(BroadPhaseOptions{.kind = kind, .lbvh_update = LbvhUpdate::kRefit});
    const Boxes a = test::uniform_boxes(500, 21, 0.2f, 0.5f);
    const Boxes c = test::clustered_boxes(700, 22);
    std::vector<BodyPair> got;
    IMPACT_ASSERT_OK(bp.update(a.input()));
    IMPACT_ASSERT_OK(bp.pairs(&got));
    expect_same_set(got, reference_pairs(a), a.size(), "first");
    IMPACT_ASSERT_OK(bp.update(c.input()));
    IMPACT_ASSERT_OK(bp.pairs(&got));
    expect_same_set(got, reference_pairs(c), c.size(), "second");
    IMPACT_ASSERT_OK(bp.update(Boxes{}.input()));
    IMPACT_ASSERT_OK(bp.pairs(&got));
    EXPECT_TRUE(got.empty());
  }
}

// The automatic choice: the LBVH when the sizes spread over many of the grid's
// levels or every level hashes, the grid otherwise (docs/broadphase.md has the
// measurements);
// pairs equal the reference either way.
TEST(BroadPhaseStage, AutoChoosesByTheSizeSpread) {
  struct Case {
    Boxes boxes;
    BroadPhaseKind expect;
    const char* what;
  };
  std::vector<Case> cases;
  cases.push_back({test::uniform_boxes(scaled(4000), 31, 0.3f, 0.6f), BroadPhaseKind::kGrid, "uniform"});
  // Clustered: the blobs leave most of the extent empty, so every level hashes: the
  // LBVH (measured 1.7-2.1x faster at 10k-1M: BM_AutoChoice/clustered). A fixed count:
  // clustered_boxes keeps its extent and blobs whatever n, so at 10x the boxes (as
  // IMPACT_TEST_INTENSITY=10 made them) the blobs fill enough cells that a level no
  // longer hashes and the rule sees a dense scene: another case than this line's.
  cases.push_back({test::clustered_boxes(4000, 32), BroadPhaseKind::kLbvh, "clustered"});
  // Dense but 1000x spread: the sizes span many levels, so the LBVH (3.5x faster at
  // 1M; 5.8x once the world is sparse too).
  cases.push_back({log_uniform_boxes(scaled(4000), 33, 0.01f, 10.0f), BroadPhaseKind::kLbvh, "1000x log-uniform"});
  cases.push_back({log_uniform_boxes(scaled(4000), 35, 0.01f, 10.0f, 10.0f), BroadPhaseKind::kLbvh,
                   "1000x log-uniform, sparse"});
  // One size, sparse: hashed at its only level, the LBVH (5.4x faster at 1M).
  cases.push_back({log_uniform_boxes(scaled(4000), 36, 0.5f, 0.6f, 10.0f), BroadPhaseKind::kLbvh,
                   "one size, sparse"});
  // Sizes 16x, dense: two levels, the LBVH (1.25-1.7x faster at 10k-1M).
  cases.push_back({log_uniform_boxes(scaled(4000), 37, 1.0f / 16, 1.0f), BroadPhaseKind::kLbvh,
                   "16x log-uniform"});
  // Sizes 4x, dense: one level, the grid (1.3-1.6x faster).
  cases.push_back({log_uniform_boxes(scaled(4000), 38, 1.0f / 4, 1.0f), BroadPhaseKind::kGrid,
                   "4x log-uniform"});
  {
    // A few huge boxes among small ones: the grid's levels handle it (2 levels).
    Boxes b = test::uniform_boxes(scaled(4000), 34, 0.2f, 0.4f);
    for (int i = 0; i < 3; ++i) b.add(10.0f * static_cast<float>(i), 0.0f, 0.0f, 30.0f, 30.0f, 30.0f);
    cases.push_back({std::move(b), BroadPhaseKind::kGrid, "few huge"});
  }
  // Far outliers do not make a dense scene look sparse (the rule measures the extent
  // the grid spans, host::grid_extent): still the grid, which they no longer slow
  // (BM_Outliers), while 10 of them slow the LBVH ~20x (its Morton codes span them).
  // Before, one outlier at 1e9 m or beyond turned the choice to the LBVH.
  for (int count : {1, 10}) {
    Boxes b = test::uniform_boxes(scaled(4000), 31, 0.3f, 0.6f);
    for (int i = 0; i < count; ++i)
      b.add(i % 2 ? -1e12f : 1e9f, static_cast<float>(i), 0.0f, 0.5f, 0.5f, 0.5f);
    cases.push_back({std::move(b), BroadPhaseKind::kGrid, count == 1 ? "one far outlier" : "ten far outliers"});
  }
  for (const Case& c : cases) {
    SCOPED_TRACE(c.what);
    BroadPhase bp(BroadPhaseKind::kAuto);
    EXPECT_EQ(bp.kind(), BroadPhaseKind::kAuto);
    std::vector<BodyPair> got;
    IMPACT_ASSERT_OK(bp.find_pairs(c.boxes.input(), &got));
    EXPECT_EQ(bp.active_kind(), c.expect) << to_string(bp.active_kind());
    expect_same_set(got, reference_pairs(c.boxes), c.boxes.size(), c.what);
  }
}

TEST(BroadPhaseStage, SweptInputEqualsReferenceOfSweptBoxes) {
  Boxes b = test::uniform_boxes(scaled(3000), 41, 0.1f, 0.4f);
  test::add_random_filter(b, 42, 0.1);
  std::mt19937 rng(43);
  std::uniform_real_distribution<float> d(-3.0f, 3.0f);
  std::bernoulli_distribution fast(0.1);
  std::vector<float> dx(b.size()), dy(b.size()), dz(b.size());
  for (size_t i = 0; i < b.size(); ++i)
    if (fast(rng)) dx[i] = d(rng), dy[i] = d(rng), dz[i] = d(rng);
  const PairVec ref = reference_pairs(swept_reference_boxes(b, dx, dy, dz));
  const PairVec still = reference_pairs(b);
  EXPECT_GT(ref.size(), still.size()) << "the motion must add candidate pairs";
  for (BroadPhaseKind kind : kAllKinds) {
    SCOPED_TRACE(to_string(kind));
    BroadPhase bp(kind);
    AabbInput in = b.input();
    in.dx = dx;
    in.dy = dy;
    in.dz = dz;
    std::vector<BodyPair> got;
    IMPACT_ASSERT_OK(bp.find_pairs(in, &got));
    expect_same_set(got, ref, b.size(), "swept");
  }
}

// Two boxes that pass through each other within the step: only the swept input pairs them.
TEST(BroadPhaseStage, SweptInputCatchesTunnelingPair) {
  Boxes b;
  b.add(-5.0f, 0.0f, 0.0f, 0.5f, 0.5f, 0.5f);
  b.add(5.0f, 0.0f, 0.0f, 0.5f, 0.5f, 0.5f);
  const std::vector<float> dx{10.0f, -10.0f}, zero{0.0f, 0.0f};
  for (BroadPhaseKind kind : kAllKinds) {
    SCOPED_TRACE(to_string(kind));
    BroadPhase bp(kind);
    std::vector<BodyPair> got;
    IMPACT_ASSERT_OK(bp.find_pairs(b.input(), &got));
    EXPECT_TRUE(got.empty());
    AabbInput in = b.input();
    in.dx = dx;
    in.dy = zero;
    in.dz = zero;
    IMPACT_ASSERT_OK(bp.find_pairs(in, &got));
    ASSERT_EQ(got.size(), 1u);
    EXPECT_EQ(got[0].a, 0u);
    EXPECT_EQ(got[0].b, 1u);
  }
}

TEST(BroadPhaseStage, RejectsBadOptionsAndSweptInput) {
  const Boxes b = test::uniform_boxes(10, 51, 0.2f, 0.5f);
  std::vector<BodyPair> got;
  {
    BroadPhase bp(BroadPhaseOptions{.kind = static_cast<BroadPhaseKind>(99)});
    EXPECT_TRUE(IsError(bp.build(b.input()), StatusCode::kInvalidArgument, {"kind"}));
  }
  {
    BroadPhase bp(BroadPhaseOptions{.kind = BroadPhaseKind::kLbvh, .lbvh_refit_sah_limit = 0.5});
    EXPECT_TRUE(IsError(bp.find_pairs(b.input(), &got), StatusCode::kInvalidArgument, {"lbvh_refit_sah_limit"}));
  }
  {
    BroadPhase bp(BroadPhaseOptions{.kind = BroadPhaseKind::kLbvh, .lbvh_max_refits = 0});
    EXPECT_TRUE(IsError(bp.update(b.input()), StatusCode::kInvalidArgument, {"lbvh_max_refits"}));
  }
  {
    BroadPhase bp(BroadPhaseOptions{.lbvh_update = static_cast<LbvhUpdate>(7)});
    EXPECT_TRUE(IsError(bp.pairs(&got), StatusCode::kInvalidArgument, {"lbvh_update"}));
  }
  for (float margin : {-0.1f, std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity()}) {
    BroadPhase bp(BroadPhaseOptions{.kind = BroadPhaseKind::kLbvh, .lbvh_update = LbvhUpdate::kPairCache,
                                    .lbvh_fat_margin = margin});
    EXPECT_TRUE(IsError(bp.build(b.input()), StatusCode::kInvalidArgument, {"lbvh_fat_margin"}));
  }
  BroadPhase bp;
  IMPACT_ASSERT_OK(bp.build(b.input()));
  std::vector<float> dx(b.size(), 0.0f), dy(b.size(), 0.0f), dz(b.size() - 1, 0.0f);
  AabbInput in = b.input();
  in.dx = dx;
  in.dy = dy;
  in.dz = dz;
  EXPECT_TRUE(IsError(bp.update(in), StatusCode::kSizeMismatch, {"dx, dy and dz"}));
  // A call rejected for bad input keeps the structure: pairs() are the last build's.
  IMPACT_ASSERT_OK(bp.pairs(&got));
  expect_same_set(got, reference_pairs(b), b.size(), "after a rejected update");
  dz.push_back(0.0f);
  dy[7] = std::nanf("");
  in.dz = dz;
  EXPECT_TRUE(IsError(bp.update(in), StatusCode::kInvalidArgument, {"box 7", "dy"}));
  dy[7] = 2e18f;
  EXPECT_TRUE(IsError(bp.update(in), StatusCode::kInvalidArgument, {"box 7", "dy"}));
  dy[7] = 1.0f;
  IMPACT_ASSERT_OK(bp.find_pairs(in, &got));
  // Swept input's boxes are checked too (the same pass as unswept input's).
  Boxes bad = b;
  bad.min_x[5] = bad.max_x[5] + 1.0f;
  AabbInput bad_in = bad.input();
  bad_in.dx = dx;
  bad_in.dy = dy;
  bad_in.dz = dz;
  EXPECT_TRUE(IsError(bp.update(bad_in), StatusCode::kInvalidArgument, {"box 5", "min_x"}));
}

// Same bytes for every backend and thread count through build/update/pairs, for the
// refitting and the pair-caching LBVH and the incremental sweep.
TEST(BroadPhaseStage, CoherentPathsIndependentOfThreads) {
  const uint32_t n = scaled(20000, 2000);
  struct Case {
    BroadPhaseKind kind;
    LbvhUpdate update;
  };
  for (const Case& k : {Case{BroadPhaseKind::kLbvh, LbvhUpdate::kRefit}, Case{BroadPhaseKind::kLbvh, LbvhUpdate::kPairCache},
                        Case{BroadPhaseKind::kSweepAndPrune, LbvhUpdate::kRefit},
                        Case{BroadPhaseKind::kAuto, LbvhUpdate::kRefit}}) {
    const BroadPhaseKind kind = k.kind;
    SCOPED_TRACE(std::string(to_string(kind)) + "/" + to_string(k.update));
    std::vector<BodyPair> first;
    bool have_first = false;
    for (const test::ExecCase& c : test::exec_cases()) {
      SCOPED_TRACE(test::to_string(c));
      const ExecConfig exec{c.backend, c.threads};
      Boxes b = test::uniform_boxes(n, 61, 0.2f, 0.5f);
      std::mt19937 rng(62);
      BroadPhase bp(BroadPhaseOptions{.kind = kind, .lbvh_update = k.update});
      std::vector<BodyPair> got;
      for (int f = 0; f < 4; ++f) {
        IMPACT_ASSERT_OK(bp.update(b.input(), exec));
        jiggle(b, rng, 0.1f);
      }
      IMPACT_ASSERT_OK(bp.pairs(&got, exec));
      if (!have_first) {
        first = got;
        have_first = true;
        continue;
      }
      ASSERT_EQ(got.size(), first.size());
      for (size_t i = 0; i < got.size(); ++i)
        ASSERT_TRUE(got[i].a == first[i].a && got[i].b == first[i].b) << "pair " << i;
    }
  }
}

// --- World ----------------------------------------------------------------------------

// Two spheres 10 m apart closing at 600 m/s each pass through each other within one
// 1/60 s step: with swept bounds they are a candidate pair that step, without not.
TEST(WorldSweptBounds, FastCrossingSpheresBecomeCandidates) {
  for (bool swept : {false, true}) {
    SCOPED_TRACE(swept ? "swept" : "static bounds");
    WorldDesc d = test::zero_gravity_desc();
    d.swept_bounds = swept;
    auto w = test::make_world(d);
    BodyDesc a, b;
    a.position = {-5.0f, 0.0f, 0.0f};
    a.velocity = {600.0f, 0.0f, 0.0f};
    b.position = {5.0f, 0.0f, 0.0f};
    b.velocity = {-600.0f, 0.0f, 0.0f};
    std::vector<BodyHandle> h(2);
    const BodyDesc descs[] = {a, b};
    IMPACT_ASSERT_OK(w->create_bodies(descs, h));
    IMPACT_ASSERT_OK(w->step());
    EXPECT_EQ(w->pairs().size(), swept ? 1u : 0u);
    EXPECT_EQ(w->last_step().pairs, swept ? 1u : 0u);
  }
}

// Swept world pairs equal the reference over the swept boxes the contract describes.
TEST(WorldSweptBounds, PairsMatchReferenceOfSweptSpheres) {
  WorldDesc d = test::zero_gravity_desc();
  d.swept_bounds = true;
  auto w = test::make_world(d);
  const uint32_t n = scaled(3000);
  std::mt19937 rng(71);
  const float side = 1.6f * std::cbrt(static_cast<float>(n));
  std::uniform_real_distribution<float> pos(-0.5f * side, 0.5f * side), vel(-120.0f, 120.0f), rad(0.1f, 0.5f);
  std::vector<BodyDesc> descs(n);
  for (BodyDesc& b : descs) {
    b.position = {pos(rng), pos(rng), pos(rng)};
    b.velocity = {vel(rng), vel(rng), vel(rng)};
    b.radius = rad(rng);
  }
  std::vector<BodyHandle> h(n);
  IMPACT_ASSERT_OK(w->create_bodies(descs, h));
  const BodyArrays a = w->bodies();
  Boxes boxes;
  std::vector<float> dx(n), dy(n), dz(n);
  const float dt = d.fixed_dt;
  for (size_t i = 0; i < n; ++i) {
    const float r = a.radius[i];
    boxes.add_box(a.pos_x[i] - r, a.pos_y[i] - r, a.pos_z[i] - r, a.pos_x[i] + r, a.pos_y[i] + r, a.pos_z[i] + r);
    // End pose as the integrator computes it; the swept box spans both sphere boxes.
    dx[i] = (a.pos_x[i] + a.vel_x[i] * dt) - a.pos_x[i];
    dy[i] = (a.pos_y[i] + a.vel_y[i] * dt) - a.pos_y[i];
    dz[i] = (a.pos_z[i] + a.vel_z[i] * dt) - a.pos_z[i];
  }
  Boxes swept = boxes;
  for (size_t i = 0; i < n; ++i) {
    const float r = a.radius[i];
    const float e[3] = {a.pos_x[i] + a.vel_x[i] * dt, a.pos_y[i] + a.vel_y[i] * dt, a.pos_z[i] + a.vel_z[i] * dt};
    swept.min_x[i] = std::min(swept.min_x[i], e[0] - r);
    swept.min_y[i] = std::min(swept.min_y[i], e[1] - r);
    swept.min_z[i] = std::min(swept.min_z[i], e[2] - r);
    swept.max_x[i] = std::max(swept.max_x[i], e[0] + r);
    swept.max_y[i] = std::max(swept.max_y[i], e[1] + r);
    swept.max_z[i] = std::max(swept.max_z[i], e[2] + r);
  }
  const PairVec ref = reference_pairs(swept);
  IMPACT_ASSERT_OK(w->step());
  const auto p = w->pairs();
  expect_same_set(std::vector<BodyPair>(p.begin(), p.end()), ref, n, "world swept pairs");
  EXPECT_GT(ref.size(), reference_pairs(boxes).size());
}

// World with the automatic choice and a refitting LBVH: same state hash for every
// backend and thread count, and bodies re-sorted into Morton order stay reachable by
// handle (a contact-free scene gives bit-identical positions with and without re-sorts).
TEST(WorldBroadPhaseStage, AutoAndRefitWorldsAreDeterministic) {
  struct Case {
    BroadPhaseKind kind;
    LbvhUpdate update;
  };
  for (const Case& k : {Case{BroadPhaseKind::kAuto, LbvhUpdate::kAuto}, Case{BroadPhaseKind::kLbvh, LbvhUpdate::kAuto},
                        Case{BroadPhaseKind::kLbvh, LbvhUpdate::kPairCache}}) {
    const BroadPhaseKind kind = k.kind;
    SCOPED_TRACE(std::string(to_string(kind)) + "/" + to_string(k.update));
    uint64_t first = 0;
    for (const test::ExecCase& c : test::exec_cases()) {
      WorldDesc d;
      d.broad_phase = kind;
      d.lbvh_update = k.update;
      d.reorder_interval = 5;
      d.backend = c.backend;
      d.threads = c.threads;
      auto w = test::make_world(d);
      std::mt19937 rng(81);
      // Sanitizer builds: a third of the bodies (the same passes, a third of the work).
      const uint32_t n = scaled(test::kSanitized ? 1000 : 3000, 500);
      const float side = 1.4f * std::cbrt(static_cast<float>(n));
      std::uniform_real_distribution<float> pos(-0.5f * side, 0.5f * side), lr(std::log(0.02f), std::log(2.0f));
      std::vector<BodyDesc> descs(n);
      for (BodyDesc& b : descs) {
        b.position = {pos(rng), pos(rng) + side, pos(rng)};
        b.radius = std::exp(lr(rng));
      }
      std::vector<BodyHandle> h(n);
      IMPACT_ASSERT_OK(w->create_bodies(descs, h));
      PlaneDesc floor;
      PlaneHandle ph;
      IMPACT_ASSERT_OK(w->create_planes(std::span<const PlaneDesc>(&floor, 1), std::span<PlaneHandle>(&ph, 1)));
      for (int s = 0; s < 40; ++s) IMPACT_ASSERT_OK(w->step());
      if (first == 0) first = w->state_hash();
      EXPECT_EQ(w->state_hash(), first) << test::to_string(c);
    }
  }
}

TEST(WorldBroadPhaseStage, MortonReorderIsInvisibleThroughHandles) {
  auto run = [](uint32_t reorder, std::vector<Eigen::Vector3f>* out) {
    WorldDesc d;
    d.broad_phase = BroadPhaseKind::kLbvh;
    d.reorder_interval = reorder;
    auto w = test::make_world(d);
    std::mt19937 rng(91);
    std::uniform_real_distribution<float> pos(-100.0f, 100.0f), vel(-3.0f, 3.0f);
    std::vector<BodyDesc> descs(2000);
    for (size_t i = 0; i < descs.size(); ++i) {
      // Far apart (a 10 m lattice), so no contact ever forms: positions depend only
      // on each body's own integration, not on slot order.
      descs[i].position = {10.0f * static_cast<float>(i % 20), 10.0f * static_cast<float>((i / 20) % 10),
                           10.0f * static_cast<float>(i / 200)};
      descs[i].velocity = {vel(rng), vel(rng), vel(rng)};
      descs[i].radius = 0.5f;
    }
    std::vector<BodyHandle> h(descs.size());
    ASSERT_TRUE(test::IsOk(w->create_bodies(descs, h)));
    for (int s = 0; s < 30; ++s) ASSERT_TRUE(test::IsOk(w->step()));
    out->resize(h.size());
    ASSERT_TRUE(test::IsOk(w->get_positions(h, *out)));
  };
  std::vector<Eigen::Vector3f> with, without;
  run(1, &with);
  run(0, &without);
  ASSERT_EQ(with.size(), without.size());
  for (size_t i = 0; i < with.size(); ++i) ASSERT_EQ(with[i], without[i]) << "body " << i;
}

}  // namespace
}  // namespace impact

// --- World queries ---------------------------------------------------------------------

namespace impact {
namespace {

// World queries against a double-precision brute force over the bodies' current boxes
// [p - r, p + r], for every broad-phase kind, after steps that moved the bodies.
TEST(WorldQueries, MatchBruteForceAfterSteps) {
  const uint32_t n = scaled(3000, 500);
  std::mt19937 rng(101);
  const float side = 1.5f * std::cbrt(static_cast<float>(n));
  std::uniform_real_distribution<float> pos(-0.5f * side, 0.5f * side), vel(-2.0f, 2.0f), lr(-3.0f, 0.5f);
  std::vector<BodyDesc> descs(n);
  for (uint32_t i = 0; i < n; ++i) {
    descs[i].position = {pos(rng), pos(rng), pos(rng)};
    descs[i].velocity = {vel(rng), vel(rng), vel(rng)};
    descs[i].radius = std::exp(lr(rng));
    descs[i].layer = 1u << (i % 3);
    descs[i].inv_mass = i % 7 == 0 ? 0.0f : 1.0f;
  }
  const uint32_t nq = 300;
  std::vector<float> qx0(nq), qy0(nq), qz0(nq), qx1(nq), qy1(nq), qz1(nq), px(nq), py(nq), pz(nq), pr(nq);
  std::vector<uint32_t> qmask(nq);
  std::uniform_real_distribution<float> ext(0.0f, 3.0f), rad(0.0f, 2.5f);
  for (uint32_t q = 0; q < nq; ++q) {
    qx0[q] = pos(rng), qy0[q] = pos(rng), qz0[q] = pos(rng);
    qx1[q] = qx0[q] + ext(rng), qy1[q] = qy0[q] + ext(rng), qz1[q] = qz0[q] + ext(rng);
    px[q] = pos(rng), py[q] = pos(rng), pz[q] = pos(rng), pr[q] = rad(rng);
    qmask[q] = q % 4 == 0 ? 0xffffffffu : (1u << (q % 3));
  }
  const AabbQueries aq{qx0, qy0, qz0, qx1, qy1, qz1, qmask};
  const SphereQueries sq{px, py, pz, pr, qmask};
  const PointQueries ptq{px, py, pz, qmask};

  for (BroadPhaseKind kind : kAllKinds) {
    SCOPED_TRACE(to_string(kind));
    WorldDesc d = test::zero_gravity_desc();
    d.broad_phase = kind;
    d.lbvh_update = LbvhUpdate::kRefit;
    d.reorder_interval = 3;
    auto w = test::make_world(d);
    std::vector<BodyHandle> h(n);
    IMPACT_ASSERT_OK(w->create_bodies(descs, h));
    for (int s = 0; s < 7; ++s) IMPACT_ASSERT_OK(w->step());
    QueryHits ha, hs, hp;
    IMPACT_ASSERT_OK(w->query_aabbs(aq, &ha));
    IMPACT_ASSERT_OK(w->query_spheres(sq, &hs));
    IMPACT_ASSERT_OK(w->query_points(ptq, &hp));
    // Reference over the current state, in slot order.
    const BodyArrays a = w->bodies();
    ASSERT_EQ(ha.size(), nq);
    size_t total = 0;
    for (uint32_t q = 0; q < nq; ++q) {
      std::vector<uint32_t> ref_a, ref_p;
      for (uint32_t i = 0; i < n; ++i) {
        if ((a.layer[i] & qmask[q]) == 0) continue;
        const float r = a.radius[i];
        const double lo[3] = {a.pos_x[i] - r, a.pos_y[i] - r, a.pos_z[i] - r};
        const double hi[3] = {a.pos_x[i] + r, a.pos_y[i] + r, a.pos_z[i] + r};
        if (lo[0] <= qx1[q] && qx0[q] <= hi[0] && lo[1] <= qy1[q] && qy0[q] <= hi[1] && lo[2] <= qz1[q] &&
            qz0[q] <= hi[2])
          ref_a.push_back(i);
        if (lo[0] <= px[q] && px[q] <= hi[0] && lo[1] <= py[q] && py[q] <= hi[1] && lo[2] <= pz[q] && pz[q] <= hi[2])
          ref_p.push_back(i);
        // Sphere: box distance in double; a disagreement is allowed only within 1e-5 of the radius.
        const double c[3] = {px[q], py[q], pz[q]};
        double d2 = 0;
        for (int k = 0; k < 3; ++k) {
          const double e = std::max({lo[k] - c[k], 0.0, c[k] - hi[k]});
          d2 += e * e;
        }
        const auto got = hs.of(q);
        const bool in_got = std::binary_search(got.begin(), got.end(), i);
        const bool in_ref = d2 <= static_cast<double>(pr[q]) * pr[q];
        if (in_got != in_ref) {
          EXPECT_NEAR(std::sqrt(d2), pr[q], 1e-5) << "sphere query " << q << " body " << i;
        }
      }
      const auto ga = ha.of(q), gp = hp.of(q);
      ASSERT_EQ(std::vector<uint32_t>(ga.begin(), ga.end()), ref_a) << "aabb query " << q;
      ASSERT_EQ(std::vector<uint32_t>(gp.begin(), gp.end()), ref_p) << "point query " << q;
      total += ref_a.size();
    }
    EXPECT_GT(total, nq / 2) << "queries should hit something";
  }
}

TEST(WorldQueries, RefreshAfterSetPositionsAndRejectBadInput) {
  for (BroadPhaseKind kind : {BroadPhaseKind::kGrid, BroadPhaseKind::kLbvh}) {
    SCOPED_TRACE(to_string(kind));
    WorldDesc d = test::zero_gravity_desc();
    d.broad_phase = kind;
    d.lbvh_update = LbvhUpdate::kRefit;
    auto w = test::make_world(d);
    std::vector<BodyDesc> descs(50);
    for (size_t i = 0; i < descs.size(); ++i) descs[i].position = {3.0f * static_cast<float>(i), 0.0f, 0.0f};
    std::vector<BodyHandle> h(descs.size());
    IMPACT_ASSERT_OK(w->create_bodies(descs, h));
    const std::vector<float> x{30.0f}, y{0.0f}, z{0.0f};
    QueryHits hits;
    IMPACT_ASSERT_OK(w->query_points(PointQueries{x, y, z}, &hits));  // before any step
    ASSERT_EQ(hits.of(0).size(), 1u);
    uint32_t slot = 0;
    IMPACT_ASSERT_OK(w->slot_of(h[10], &slot));
    EXPECT_EQ(hits.of(0)[0], slot);
    // Teleport body 10 away and body 20 onto the point: the next query sees it.
    const Eigen::Vector3f p10{500.0f, 0.0f, 0.0f}, p20{30.0f, 0.0f, 0.0f};
    IMPACT_ASSERT_OK(w->set_positions(std::span<const BodyHandle>(&h[10], 1), std::span<const Eigen::Vector3f>(&p10, 1)));
    IMPACT_ASSERT_OK(w->set_positions(std::span<const BodyHandle>(&h[20], 1), std::span<const Eigen::Vector3f>(&p20, 1)));
    IMPACT_ASSERT_OK(w->query_points(PointQueries{x, y, z}, &hits));
    ASSERT_EQ(hits.of(0).size(), 1u);
    IMPACT_ASSERT_OK(w->slot_of(h[20], &slot));
    EXPECT_EQ(hits.of(0)[0], slot);
    const std::vector<float> bad{std::nanf("")};
    EXPECT_TRUE(IsError(w->query_points(PointQueries{bad, y, z}, &hits), StatusCode::kInvalidArgument, {"query_points"}));
    EXPECT_TRUE(IsError(w->query_points(PointQueries{x, y, z}, nullptr), StatusCode::kInvalidArgument, {"null"}));
  }
}

}  // namespace
}  // namespace impact
