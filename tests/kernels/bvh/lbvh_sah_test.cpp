// Tree quality of the LBVH (host/broadphase/lbvh.h) against an independent binned-SAH
// build of the same boxes (tests/support/binned_sah.h), on uniform, clustered and
// mixed-size boxes:
//  - the reference tree is valid (every box in one leaf, every node contains its children);
//  - LbvhBroadPhase::sah_cost equals the same metric summed independently over the
//    LBVH's nodes (so the two numbers compared below measure the same thing);
//  - the LBVH's SAH cost is within a stated factor of the binned build's (see kMaxRatio),
//    and a few large boxes among small ones, the LBVH's weak spot (kMaxRatioFewLarge).
// Both costs are printed, so a run shows the gap.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>
#include <string>

#include "host/broadphase/lbvh.h"
#include "host/parallel.h"
#include "kernels/bvh/lbvh_traverse.h"
#include "support/aabb_reference.h"
#include "support/binned_sah.h"
#include "support/test_support.h"

namespace impact {
namespace {

using test::Boxes;

// Bounds on LBVH SAH / binned SAH, measured first at 20k and at 100k boxes (30-bit
// codes; the same to ~0.05 at both sizes), then set with headroom:
//   uniform 1.06, clustered 1.13, mixed sizes (per-axis extents 0.02..2) 1.09
//     -> kMaxRatio 1.3. On internal nodes alone (the leaves, the same boxes in both
//     trees, removed from both sums): 1.08, 1.14, 1.10. A Morton-order split ignores
//     box sizes and cuts at fixed power-of-two planes, which costs most inside tight
//     clusters.
//   a few large boxes among many small ones (0.5% large, 10-100x bigger) 1.83..1.88
//     -> kMaxRatioFewLarge 2.2. The Karras tree files a large box by its centroid
//     among small neighbours, so every ancestor up to the level of its size grows to
//     its extent; the binned build lifts it near the root instead. (The benchmarks'
//     mixed scene, 0.01% large, measures 1.21-1.26 at 100k-1M: BM_LbvhSahVsBinned*.)
// The headroom (~15%) is for seeds and sizes; a change that makes the build or the
// Morton quantisation markedly worse fails here.
constexpr double kMaxRatio = 1.3;
constexpr double kMaxRatioFewLarge = 2.2;
// Floor on the same ratio: the binned build is a greedy near-optimal heuristic, and a
// Morton-order tree beating it by more than a few percent would mean the two costs
// no longer measure the same thing.
constexpr double kMinRatio = 0.95;

test::SahBoxes sah_boxes(const Boxes& b) {
  return {b.min_x, b.min_y, b.min_z, b.max_x, b.max_y, b.max_z};
}

// The metric of binned_sah.h summed over the LBVH's own nodes and leaves, independently
// of LbvhBroadPhase::sah_cost.
double lbvh_sah_independent(const kernels::LbvhView& v) {
  auto area = [](const auto& b) {
    return test::sah_box_area({b.min_x, b.min_y, b.min_z}, {b.max_x, b.max_y, b.max_z});
  };
  double total = 0.0;
  for (uint32_t i = 0; i + 1 < v.n; ++i) total += area(v.nodes[i]);
  for (uint32_t s = 0; s < v.n; ++s) total += area(v.leaves[s]);
  const double root = area(v.nodes[0]);
  return root > 0.0 ? total / root : static_cast<double>(v.n);
}

void compare(const Boxes& boxes, const std::string& what, double max_ratio = kMaxRatio) {
  SCOPED_TRACE(what);
  const uint32_t n = static_cast<uint32_t>(boxes.size());
  const host::Executor exec(Backend::kSerial, 1);
  host::LbvhBroadPhase lbvh;
  host::Buffer<kernels::Pair> pairs;
  const kernels::AabbSoA soa{boxes.min_x.data(), boxes.min_y.data(), boxes.min_z.data(),
                             boxes.max_x.data(), boxes.max_y.data(), boxes.max_z.data()};
  IMPACT_ASSERT_OK(lbvh.find_pairs(exec, soa, {nullptr, nullptr, nullptr}, n, &pairs));
  const double lbvh_sah = lbvh.sah_cost(exec);
  EXPECT_NEAR(lbvh_sah, lbvh_sah_independent(lbvh.view()), 1e-9 * lbvh_sah);

  const test::BinnedBvh ref = test::build_binned_sah<32>(sah_boxes(boxes));
  const std::string why = test::validate_binned_bvh(ref, sah_boxes(boxes));
  ASSERT_TRUE(why.empty()) << why;
  const double binned_sah = test::sah_cost(ref);
  const double ratio = lbvh_sah / binned_sah;
  // The leaves' share, equal in both trees (the same boxes under the same root box).
  double leaves = 0.0;
  for (uint32_t i = 0; i < n; ++i)
    leaves += test::sah_box_area({boxes.min_x[i], boxes.min_y[i], boxes.min_z[i]},
                                 {boxes.max_x[i], boxes.max_y[i], boxes.max_z[i]});
  leaves /= test::sah_box_area(ref.nodes[0].lo, ref.nodes[0].hi);
  std::printf("[ sah      ] %-12s n=%u  LBVH %.1f  binned SAH %.1f  ratio %.3f  internal nodes only %.3f "
              "(%u-bit codes)\n",
              what.c_str(), n, lbvh_sah, binned_sah, ratio, (lbvh_sah - leaves) / (binned_sah - leaves),
              lbvh.info().morton_bits);
  ::testing::Test::RecordProperty(what + "_ratio", std::to_string(ratio));
  EXPECT_LE(ratio, max_ratio);
  EXPECT_GE(ratio, kMinRatio);
}

// Sizes: large enough that the trees have ~15 levels and the ratio is stable to ~1%,
// small enough for a fraction of a second in Release and a few seconds under ASan.
TEST(LbvhSah, UniformBoxes) {
  compare(test::uniform_boxes(test::scaled(20000), 71, 0.5f, 0.5f), "uniform");
}

TEST(LbvhSah, ClusteredBoxes) {
  compare(test::clustered_boxes(test::scaled(20000), 72), "clustered");
}

TEST(LbvhSah, MixedSizes) {
  // Half extents independent per axis in [0.02, 2]: a 100x spread of sizes and
  // elongated boxes.
  compare(test::uniform_boxes(test::scaled(20000), 73, 0.02f, 2.0f), "mixed sizes");
}

TEST(LbvhSah, FewLargeAmongSmall) {
  // As the benchmarks' mixed scene: small cubes (half extent 0.05) at ~1 overlap each,
  // plus 0.5% large ones (half extents log-uniform in [0.5, 5]).
  const uint32_t n = test::scaled(20000);
  const float side = std::cbrt(static_cast<float>(n) * 0.004f);
  std::mt19937 rng(74);
  std::uniform_real_distribution<float> pos(0.0f, side), expo(0.0f, 1.0f);
  Boxes b;
  for (uint32_t i = 0; i < n; ++i) {
    const float h = i % 200 == 0 ? 0.5f * std::pow(10.0f, expo(rng)) : 0.05f;
    b.add(pos(rng), pos(rng), pos(rng), h, h, h);
  }
  compare(b, "few large", kMaxRatioFewLarge);
}

// The reference builder on its own: tiny and degenerate inputs.
TEST(LbvhSah, BinnedBuilderEdgeCases) {
  Boxes one;
  one.add(1, 2, 3, 0.5f, 0.5f, 0.5f);
  test::BinnedBvh t = test::build_binned_sah<32>(sah_boxes(one));
  EXPECT_EQ(test::validate_binned_bvh(t, sah_boxes(one)), "");
  EXPECT_DOUBLE_EQ(test::sah_cost(t), 1.0);

  Boxes same;  // all centroids equal: splits in the middle
  for (int i = 0; i < 100; ++i) same.add(0, 0, 0, 0.1f * static_cast<float>(1 + i % 7), 0.2f, 0.3f);
  t = test::build_binned_sah<32>(sah_boxes(same));
  EXPECT_EQ(test::validate_binned_bvh(t, sah_boxes(same)), "");

  Boxes flat;  // zero extent on one axis
  for (int i = 0; i < 1000; ++i) flat.add(static_cast<float>(i % 37), static_cast<float>(i / 37), 0, 0.5f, 0.5f, 0);
  t = test::build_binned_sah<32>(sah_boxes(flat));
  EXPECT_EQ(test::validate_binned_bvh(t, sah_boxes(flat)), "");

  Boxes two;
  two.add(0, 0, 0, 1, 1, 1);
  two.add(4, 0, 0, 1, 1, 1);
  t = test::build_binned_sah<32>(sah_boxes(two));
  EXPECT_EQ(test::validate_binned_bvh(t, sah_boxes(two)), "");
  // Root 6 x 2 x 2 (area 56) plus two leaves of area 24: (56 + 48) / 56.
  EXPECT_NEAR(test::sah_cost(t), 104.0 / 56.0, 1e-12);
}

}  // namespace
}  // namespace impact
