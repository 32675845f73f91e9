// LBVH broad phase (kernels/bvh/, host/broadphase/lbvh.h) against the independent
// double-precision reference of tests/support/aabb_reference.h: pairs compared as
// sets (each pair (a < b) once), on random and adversarial inputs, after many frames
// of refit, with filters; pair order compared byte for byte across every backend and
// thread count; tree invariants (every leaf reachable once, parent links, node
// bounds exactly the union of the children, subtree leaf ranges, depth bound).
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include "host/broadphase/lbvh.h"
#include "host/parallel.h"
#include "kernels/bvh/lbvh_build.h"
#include "kernels/bvh/lbvh_build_fused.h"
#include "kernels/bvh/lbvh_refit.h"
#include "kernels/bvh/lbvh_traverse.h"
#include "kernels/bvh/morton.h"
#include "support/aabb_reference.h"
#include "support/kernel_views.h"
#include "support/test_support.h"

namespace impact {
namespace {

using host::Buffer;
using host::Executor;
using host::LbvhBroadPhase;
using host::LbvhOptions;
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


// --- tree invariants ----------------------------------------------------------------------

template <class A, class B>
bool same_bounds(const A& a, const B& b) {
  return a.min_x == b.min_x && a.min_y == b.min_y && a.min_z == b.min_z && a.max_x == b.max_x &&
         a.max_y == b.max_y && a.max_z == b.max_z;
}

// Every leaf and internal node reachable from the root exactly once; parent links
// match; each internal node's bounds are exactly the union of its children's (so
// they contain them); `last` is the subtree's rightmost leaf and subtrees cover
// contiguous leaf ranges; depth within kLbvhMaxDepth; leaves hold the boxes.
void check_tree(const LbvhBroadPhase& bp, const Boxes& boxes, const std::string& what) {
  SCOPED_TRACE(what);
  const kernels::LbvhView v = bp.view();
  const uint32_t n = v.n;
  ASSERT_EQ(n, boxes.size());
  if (n == 0) return;
  test::expect_lanes_mirror_leaves(v);
  std::vector<int> seen_box(n, 0);
  for (uint32_t s = 0; s < n; ++s) {
    const uint32_t i = bp.leaf_index()[s];
    ASSERT_LT(i, n);
    ++seen_box[i];
    const kernels::SortedBox& l = v.leaves[s];
    ASSERT_EQ(l.index, i);
    ASSERT_TRUE(l.min_x == boxes.min_x[i] && l.min_y == boxes.min_y[i] && l.min_z == boxes.min_z[i] &&
                l.max_x == boxes.max_x[i] && l.max_y == boxes.max_y[i] && l.max_z == boxes.max_z[i]);
  }
  for (uint32_t i = 0; i < n; ++i) ASSERT_EQ(seen_box[i], 1) << "box " << i;
  if (n < 2) return;
  ASSERT_EQ(bp.internal_parent()[0], kernels::kInvalidBody);
  std::vector<int> seen_leaf(n, 0), seen_node(n - 1, 0);
  struct Item {
    uint32_t node, depth, first, last;
  };
  std::vector<Item> stack{{0, 1, 0, n - 1}};
  while (!stack.empty()) {
    const Item it = stack.back();
    stack.pop_back();
    ASSERT_LT(it.node, n - 1);
    ASSERT_LE(it.depth, kernels::kLbvhMaxDepth);
    ++seen_node[it.node];
    const kernels::LbvhNode& node = v.nodes[it.node];
    ASSERT_EQ(node.last, it.last);
    const uint32_t g = node.split & kernels::kLbvhSplitMask;
    ASSERT_GE(g, it.first);
    ASSERT_LT(g, it.last);
    float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    auto grow = [&](const auto& b) {
      lo[0] = std::min(lo[0], b.min_x), lo[1] = std::min(lo[1], b.min_y), lo[2] = std::min(lo[2], b.min_z);
      hi[0] = std::max(hi[0], b.max_x), hi[1] = std::max(hi[1], b.max_y), hi[2] = std::max(hi[2], b.max_z);
    };
    // Left child [first, g], right child [g + 1, last]; a leaf child iff its range is one leaf.
    const bool left_leaf = (node.split & kernels::kLbvhLeftLeaf) != 0;
    const bool right_leaf = (node.split & kernels::kLbvhRightLeaf) != 0;
    ASSERT_EQ(left_leaf, g == it.first);
    ASSERT_EQ(right_leaf, g + 1 == it.last);
    if (left_leaf) {
      ++seen_leaf[g];
      ASSERT_EQ(bp.leaf_parent()[g], it.node);
      grow(v.leaves[g]);
    } else {
      ASSERT_EQ(bp.internal_parent()[g], it.node);
      grow(v.nodes[g]);
      stack.push_back({g, it.depth + 1, it.first, g});
    }
    if (right_leaf) {
      ++seen_leaf[g + 1];
      ASSERT_EQ(bp.leaf_parent()[g + 1], it.node);
      grow(v.leaves[g + 1]);
    } else {
      ASSERT_EQ(bp.internal_parent()[g + 1], it.node);
      grow(v.nodes[g + 1]);
      stack.push_back({g + 1, it.depth + 1, g + 1, it.last});
    }
    const kernels::SortedBox u{lo[0], lo[1], lo[2], 0, hi[0], hi[1], hi[2], 0};
    ASSERT_TRUE(same_bounds(node, u)) << "node " << it.node << " is not the union of its children";
  }
  for (uint32_t s = 0; s < n; ++s) ASSERT_EQ(seen_leaf[s], 1) << "leaf " << s;
  for (uint32_t i = 0; i + 1 < n; ++i) ASSERT_EQ(seen_node[i], 1) << "node " << i;
}

// Rebuild with each code width; pairs == reference as sets; tree invariants hold.
void check_all(const Boxes& boxes, const std::string& what) {
  const PairVec ref = reference_pairs(boxes);
  for (uint32_t bits : {0u, 30u, 63u}) {
    LbvhOptions o;
    o.morton_bits = bits;
    LbvhBroadPhase bp(o);
    Buffer<Pair> out{{7, 3}};  // stale content must be replaced
    const std::string w = what + " bits=" + std::to_string(bits);
    IMPACT_ASSERT_OK(bp.find_pairs(serial(), soa(boxes), filter_of(boxes), count(boxes), &out));
    expect_same_set(out, ref, boxes.size(), w);
    check_tree(bp, boxes, w);
    if (bits != 0 && boxes.size() > 0) {
      EXPECT_EQ(bp.info().morton_bits, bits);
    }
  }
}

// --- generators ---------------------------------------------------------------------------



// Half sizes log-uniform over [0.01, 10]: 1000x.
Boxes mixed_size_boxes(uint32_t n, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> pos(-60.0f, 60.0f);
  std::uniform_real_distribution<float> lg(std::log(0.01f), std::log(10.0f));
  Boxes b;
  for (uint32_t i = 0; i < n; ++i)
    b.add(pos(rng), pos(rng), pos(rng), std::exp(lg(rng)), std::exp(lg(rng)), std::exp(lg(rng)));
  return b;
}

// --- Morton codes -------------------------------------------------------------------------

uint64_t naive_interleave(uint64_t x, uint64_t y, uint64_t z, uint32_t bits) {
  uint64_t c = 0;
  for (uint32_t k = 0; k < bits; ++k)
    c |= ((x >> k) & 1) << (3 * k) | ((y >> k) & 1) << (3 * k + 1) | ((z >> k) & 1) << (3 * k + 2);
  return c;
}

TEST(LbvhMorton, InterleaveMatchesNaive) {
  std::mt19937_64 rng(1);
  for (int t = 0; t < 20000; ++t) {
    const uint64_t r = rng();
    const uint32_t x = r & 0x3ff, y = (r >> 10) & 0x3ff, z = (r >> 20) & 0x3ff;
    ASSERT_EQ(kernels::morton30(x, y, z), naive_interleave(x, y, z, 10));
    const uint64_t X = r & 0x1fffff, Y = (r >> 21) & 0x1fffff, Z = (r >> 42) & 0x1fffff;
    ASSERT_EQ(kernels::morton63(X, Y, Z), naive_interleave(X, Y, Z, 21));
  }
  EXPECT_EQ(kernels::morton30(1023, 1023, 1023), (1u << 30) - 1);
  EXPECT_EQ(kernels::morton63(0x1fffff, 0x1fffff, 0x1fffff), (1ull << 63) - 1);
}

TEST(LbvhMorton, KeysQuantiseInDoubleFarFromOrigin) {
  // Two boxes 1e6 m from the origin, 0.5 m apart on x, in a 1 m scene: different cells.
  Boxes b;
  b.add(1e6f, 1e6f, 1e6f, 0.25f, 0.25f, 0.25f);
  b.add(1e6f + 0.5f, 1e6f, 1e6f, 0.25f, 0.25f, 0.25f);
  const float lo[3] = {b.min_x[0], b.min_y[0], b.min_z[0]};
  const float hi[3] = {b.max_x[1], b.max_y[1], b.max_z[1]};
  const kernels::MortonParams p = kernels::morton_params(lo, hi, 10);
  uint64_t keys[2];
  kernels::morton_keys30(p, soa(b), keys, {0, 2});
  EXPECT_EQ(static_cast<uint32_t>(keys[0]), 0u);
  EXPECT_EQ(static_cast<uint32_t>(keys[1]), 1u);
  // x: centres 0.25 and 0.75 of a 1 m extent -> cells 256, 768; y, z: mid-extent -> 512.
  EXPECT_EQ(keys[0] >> 32, kernels::morton30(256, 512, 512));
  EXPECT_EQ(keys[1] >> 32, kernels::morton30(768, 512, 512));
  uint64_t codes[2];
  uint32_t values[2];
  kernels::morton_keys63(kernels::morton_params(lo, hi, 21), soa(b), codes, values, {0, 2});
  EXPECT_EQ(codes[0], kernels::morton63(1u << 19, 1u << 20, 1u << 20));
  EXPECT_EQ(codes[1], kernels::morton63(3u << 19, 1u << 20, 1u << 20));
  EXPECT_EQ(values[1], 1u);
}

TEST(LbvhMorton, PackedKeysEqualKeysAndRecords) {
  // The build's fused pass: the same keys as the plain loops, and each box's record.
  std::mt19937 rng(77);
  std::uniform_real_distribution<float> pos(-50.0f, 50.0f), half(0.0f, 2.0f);
  Boxes b;
  for (int i = 0; i < 1000; ++i) b.add(pos(rng), pos(rng), pos(rng), half(rng), half(rng), half(rng));
  const float lo[3] = {-52, -52, -52}, hi[3] = {52, 52, 52};
  const uint32_t n = static_cast<uint32_t>(b.size());
  for (uint32_t bits : {10u, 21u}) {
    const kernels::MortonParams p = kernels::morton_params(lo, hi, bits);
    std::vector<uint64_t> want(n), got(n, 1);
    std::vector<uint32_t> want_v(n), got_v(n, 7);
    std::vector<kernels::SortedBox> packed(n);
    for (const kernels::Range r : {kernels::Range{0, 333}, kernels::Range{333, n}}) {
      if (bits == 10) {
        kernels::morton_keys30(p, soa(b), want.data(), r);
        kernels::morton_keys30_packed(p, soa(b), got.data(), packed.data(), r);
      } else {
        kernels::morton_keys63(p, soa(b), want.data(), want_v.data(), r);
        kernels::morton_keys63_packed(p, soa(b), got.data(), got_v.data(), packed.data(), r);
      }
    }
    EXPECT_EQ(got, want) << bits << " bits per axis";
    if (bits == 21) {
      EXPECT_EQ(got_v, want_v);
    }
    for (uint32_t i = 0; i < n; ++i) {
      const kernels::SortedBox w = kernels::pack(soa(b), i);
      ASSERT_EQ(std::memcmp(&packed[i], &w, sizeof(w)), 0) << "record " << i;
    }
  }
}

TEST(LbvhMorton, BitsRule) {
  kernels::BoundsSummary s{{0, 0, 0}, {100, 100, 100}, 1.0f};
  EXPECT_EQ(host::choose_morton_bits(s, 1000), 30u);
  EXPECT_EQ(host::choose_morton_bits(s, (1u << 24) + 1), 63u);
  s.hi[0] = 10000;  // 30-bit cell ~9.8 m > 4 x 1 m boxes
  EXPECT_EQ(host::choose_morton_bits(s, 1000), 63u);
  kernels::BoundsSummary point{{5, 5, 5}, {5, 5, 5}, 0.0f};
  EXPECT_EQ(host::choose_morton_bits(point, 1000), 30u);
}

// --- pairs vs reference -------------------------------------------------------------------

TEST(Lbvh, SmallCounts) {
  check_all(Boxes{}, "n=0");
  Boxes one;
  one.add(1, 2, 3, 0.5f, 0.5f, 0.5f);
  check_all(one, "n=1");
  Boxes two_apart, two_touch, two_over;
  two_apart.add(0, 0, 0, 0.5f, 0.5f, 0.5f);
  two_apart.add(2, 0, 0, 0.5f, 0.5f, 0.5f);
  check_all(two_apart, "n=2 apart");
  two_touch.add_box(0, 0, 0, 1, 1, 1);
  two_touch.add_box(1, 1, 1, 2, 2, 2);  // touching at a corner counts
  check_all(two_touch, "n=2 touching");
  two_over.add(0, 0, 0, 1, 1, 1);
  two_over.add(0.5f, 0.5f, 0.5f, 1, 1, 1);
  check_all(two_over, "n=2 overlapping");
  for (int variant = 0; variant < 8; ++variant) {
    Boxes three;
    for (int k = 0; k < 3; ++k) {
      const float x = ((variant >> k) & 1) ? 0.9f * static_cast<float>(k) : 3.0f * static_cast<float>(k);
      three.add(x, 0, 0, 0.5f, 0.5f, 0.5f);
    }
    check_all(three, "n=3 variant " + std::to_string(variant));
  }
  Boxes same3;
  for (int k = 0; k < 3; ++k) same3.add(1, 1, 1, 0.1f, 0.1f, 0.1f);
  check_all(same3, "n=3 identical");
}

TEST(Lbvh, Uniform) {
  check_all(uniform_boxes(scaled(3000), 11, 0.2f, 0.6f), "uniform");
  // Several build, refit and pair chunks; sweep reference.
  check_all(uniform_boxes(scaled(70000), 12, 0.2f, 0.6f), "uniform large");
}

TEST(Lbvh, Clustered) { check_all(clustered_boxes(scaled(4000), 21), "clustered"); }

TEST(Lbvh, SizesSpanning1000x) { check_all(mixed_size_boxes(scaled(4000), 31), "mixed sizes"); }

TEST(Lbvh, AllBoxesAtOnePoint) {
  // Every Morton code equal: the tree splits on the sorted position alone.
  Boxes b;
  for (uint32_t i = 0; i < 700; ++i) b.add(3, -2, 7, 0.5f, 0.5f, 0.5f);
  check_all(b, "one point, unit boxes");
  Boxes z;
  for (uint32_t i = 0; i < 300; ++i) z.add(3, -2, 7, 0, 0, 0);
  check_all(z, "one point, zero-size boxes");
}

TEST(Lbvh, DeepTreeFromExponentialSpacing) {
  // Centres at 2^k on every axis: each new code differs in a higher bit, so the tree
  // is a long chain (plus index-split runs of duplicates at the low end), the worst
  // case for the traversal stack; the depth check in check_tree covers it.
  Boxes b;
  for (int rep = 0; rep < 40; ++rep)
    for (int k = 0; k < 40; ++k) {
      const float c = std::ldexp(1.0f, k - 8);
      b.add(c, c, c, 0.25f * c, 0.25f * c, 0.25f * c);
    }
  check_all(b, "exponential spacing");
}

TEST(Lbvh, ZeroSizeBoxes) {
  // Points on a lattice (touching = same point), some repeated, plus a few unit boxes.
  check_all(test::point_lattice_boxes(2500, 5), "zero-size");
}

TEST(Lbvh, Scales) {
  check_all(uniform_boxes(scaled(3000), 41, 0.2f, 0.6f, 0.0f, 1e-4f), "tiny 1e-4");
  check_all(uniform_boxes(scaled(3000), 42, 0.2f, 0.6f, 0.0f, 1e4f), "huge 1e4");
  check_all(uniform_boxes(scaled(3000), 43, 0.2f, 0.6f, 1e6f), "offset 1e6");
  check_all(uniform_boxes(scaled(3000), 44, 0.2f, 0.6f, -1e6f, 1e-2f), "offset -1e6, small boxes");
}

TEST(Lbvh, Filters) {
  for (double static_fraction : {0.0, 0.3, 1.0}) {
    Boxes b = uniform_boxes(scaled(4000), 51, 0.2f, 0.8f);
    test::add_random_filter(b, 52, static_fraction);
    check_all(b, "filtered, static fraction " + std::to_string(static_fraction));
  }
  Boxes c = clustered_boxes(scaled(3000), 53);
  test::add_random_filter(c, 54, 0.2);
  check_all(c, "filtered clustered");
}

// --- refit ----------------------------------------------------------------------------------

// Random motion: most boxes jitter, a fraction `jumps` teleports across the scene,
// sizes change too.
void move(Boxes& b, std::mt19937& rng, float side, double jumps = 0.01) {
  std::normal_distribution<float> jitter(0.0f, 0.15f);
  std::uniform_real_distribution<float> pos(-0.5f * side, 0.5f * side);
  std::uniform_real_distribution<float> half(0.1f, 0.7f);
  std::bernoulli_distribution jump(jumps);
  for (size_t i = 0; i < b.size(); ++i) {
    float c[3] = {0.5f * (b.min_x[i] + b.max_x[i]), 0.5f * (b.min_y[i] + b.max_y[i]),
                  0.5f * (b.min_z[i] + b.max_z[i])};
    if (jump(rng)) {
      for (float& v : c) v = pos(rng);
    } else {
      for (float& v : c) v += jitter(rng);
    }
    const float h = half(rng);
    b.min_x[i] = c[0] - h, b.min_y[i] = c[1] - h, b.min_z[i] = c[2] - h;
    b.max_x[i] = c[0] + h, b.max_y[i] = c[1] + h, b.max_z[i] = c[2] + h;
  }
}

TEST(Lbvh, RefitHundredFrames) {
  const uint32_t n = scaled(1500);
  Boxes b = uniform_boxes(n, 61, 0.2f, 0.6f);
  test::add_random_filter(b, 62, 0.2);
  const float side = 2.2f * 0.6f * std::cbrt(static_cast<float>(n));
  std::mt19937 rng(63);
  LbvhBroadPhase bp;
  Buffer<Pair> out;
  IMPACT_ASSERT_OK(bp.find_pairs(serial(), soa(b), filter_of(b), n, &out));
  const double sah0 = bp.sah_cost(serial());
  for (int frame = 0; frame < 100; ++frame) {
    move(b, rng, side);
    IMPACT_ASSERT_OK(bp.refit(serial(), soa(b), filter_of(b), n, &out));
    EXPECT_FALSE(bp.info().rebuilt);
    expect_same_set(out, test::reference_pairs_n2(b), n, "refit frame " + std::to_string(frame));
    if (frame % 10 == 9) check_tree(bp, b, "refit frame " + std::to_string(frame));
    if (HasFailure()) return;
  }
  EXPECT_EQ(bp.info().refits_since_build, 100u);
  // The aged tree is worse than a fresh one over the same boxes.
  const double aged = bp.sah_cost(serial());
  LbvhBroadPhase fresh;
  IMPACT_ASSERT_OK(fresh.find_pairs(serial(), soa(b), filter_of(b), n, &out));
  EXPECT_GT(aged, fresh.sah_cost(serial()));
  EXPECT_GT(aged, sah0);
}

// lbvh_refit over irregular chunkings (1-leaf chunks, small, random sizes, one chunk),
// each followed by the seam passes in order, gives the same node bytes as the host's
// refit, frame after frame (stale seam marks of one chunking never leak into the next).
TEST(Lbvh, RefitChunkingsAndSeamsGiveTheSameNodes) {
  for (const bool clustered : {false, true}) {
    const uint32_t n = 3001;
    Boxes b = clustered ? clustered_boxes(n, 71) : uniform_boxes(n, 71, 0.2f, 0.6f);
    std::mt19937 rng(72);
    const float side = 2.2f * 0.6f * std::cbrt(static_cast<float>(n));
    LbvhBroadPhase bp;
    Buffer<Pair> out;
    IMPACT_ASSERT_OK(bp.find_pairs(serial(), soa(b), filter_of(b), n, &out));
    std::vector<kernels::LbvhNode> nodes(bp.view().nodes, bp.view().nodes + (n - 1));
    std::vector<kernels::SortedBox> leaves(n);
    const kernels::LbvhRefitIn in{bp.leaf_index(), bp.internal_parent(), bp.leaf_parent(), nullptr};
    const size_t stride = kernels::lbvh_lane_stride(n);
    std::vector<float> lanes(6 * stride);
    const kernels::LbvhRefitOut kout{nodes.data(), leaves.data(), nullptr, nullptr, nullptr,
                                     {lanes.data(), stride}};
    for (int frame = 0; frame < 6; ++frame) {
      move(b, rng, side);
      IMPACT_ASSERT_OK(bp.refit(serial(), soa(b), filter_of(b), n, &out));
      const kernels::LbvhView v = bp.view();
      // Chunk starts: every leaf, every 7th, random, one chunk.
      std::vector<std::vector<uint32_t>> cuts(4);
      for (uint32_t s = 0; s < n; ++s) cuts[0].push_back(s);
      for (uint32_t s = 0; s < n; s += 7) cuts[1].push_back(s);
      for (uint32_t s = 0; s < n; s += 1 + static_cast<uint32_t>(rng() % 200)) cuts[2].push_back(s);
      cuts[3].push_back(0);
      for (const std::vector<uint32_t>& c : cuts) {
        SCOPED_TRACE("clustered=" + std::to_string(clustered) + " frame " + std::to_string(frame) +
                     " chunks " + std::to_string(c.size()));
        // Chunks in reverse order: the seams must not depend on the chunks' order.
        for (size_t k = c.size(); k-- > 0;) {
          const uint32_t e = k + 1 < c.size() ? c[k + 1] : n;
          kernels::lbvh_refit(soa(b), kernels::PairFilter{}, in, kout, n, {c[k], e});
        }
        for (size_t k = 1; k < c.size(); ++k) {
          const uint32_t e = k + 1 < c.size() ? c[k + 1] : n;
          kernels::lbvh_refit_seam(in, kout, n, {c[k], e});
        }
        ASSERT_EQ(0, std::memcmp(nodes.data(), v.nodes, nodes.size() * sizeof(kernels::LbvhNode)));
        ASSERT_EQ(0, std::memcmp(leaves.data(), v.leaves, n * sizeof(kernels::SortedBox)));
        test::expect_lanes_mirror_leaves(v);
        for (size_t k = 0; k < 6; ++k)
          ASSERT_EQ(0, std::memcmp(lanes.data() + k * stride, v.lanes + k * stride, n * sizeof(float)));
      }
    }
  }
}

// The one-pass build (lbvh_build_fused) against the Karras build (lbvh_build) plus
// lbvh_refit over the same sorted codes: the same node bytes, parents and leaves, for
// every chunking (1-leaf chunks, 7, random sizes, one chunk; packed records or SoA).
// Codes: random, many duplicates, all equal (ties broken by position), n = 2, 3.
TEST(Lbvh, FusedBuildEqualsKarrasBuildPlusRefit) {
  std::mt19937 rng(81);
  for (const uint32_t n : {2u, 3u, 5u, 64u, 1000u, 4099u}) {
    for (int kind = 0; kind < 3; ++kind) {
      const Boxes b = uniform_boxes(n, 82 + static_cast<uint32_t>(kind), 0.2f, 0.6f);
      // Sorted codes: kind 0 random 30-bit (shift 32), 1 few distinct values, 2 all equal.
      std::vector<uint64_t> codes(n);
      for (uint32_t s = 0; s < n; ++s) {
        const uint64_t c = kind == 0 ? rng() & 0x3fffffffu : kind == 1 ? rng() % 5 : 7;
        codes[s] = c << 32;
      }
      std::sort(codes.begin(), codes.end());
      std::vector<uint32_t> leaf_index(n);
      for (uint32_t s = 0; s < n; ++s) leaf_index[s] = s;
      std::shuffle(leaf_index.begin(), leaf_index.end(), rng);
      // Reference: Karras + refit in one chunk.
      std::vector<kernels::LbvhNode> ref_nodes(n - 1);
      std::vector<uint32_t> ref_ip(n - 1), ref_lp(n);
      std::vector<kernels::SortedBox> ref_leaves(n);
      kernels::lbvh_build(codes.data(), 32, n, {ref_nodes.data(), ref_ip.data(), ref_lp.data()}, {0, n - 1});
      const kernels::LbvhRefitIn rin{leaf_index.data(), ref_ip.data(), ref_lp.data(), nullptr};
      kernels::lbvh_refit(soa(b), kernels::PairFilter{}, rin,
                          {ref_nodes.data(), ref_leaves.data(), nullptr, nullptr, nullptr, {nullptr, 0}}, n,
                          {0, n});
      std::vector<kernels::SortedBox> packed(n);
      kernels::lbvh_pack_boxes(soa(b), packed.data(), {0, n});
      std::vector<std::vector<uint32_t>> cuts(4);
      for (uint32_t s = 0; s < n; ++s) cuts[0].push_back(s);
      for (uint32_t s = 0; s < n; s += 7) cuts[1].push_back(s);
      for (uint32_t s = 0; s < n; s += 1 + static_cast<uint32_t>(rng() % 100)) cuts[2].push_back(s);
      cuts[3].push_back(0);
      for (size_t ci = 0; ci < cuts.size(); ++ci) {
        const std::vector<uint32_t>& c = cuts[ci];
        SCOPED_TRACE("n=" + std::to_string(n) + " kind=" + std::to_string(kind) + " chunks=" +
                     std::to_string(c.size()));
        std::vector<kernels::LbvhNode> nodes(n - 1);
        std::vector<uint32_t> ip(n - 1, 12345u), lp(n, 12345u), slot(n, 0xffffffffu);
        std::vector<kernels::SortedBox> leaves(n);
        std::vector<kernels::LbvhBlocked> blocked(c.size());
        const size_t stride = kernels::lbvh_lane_stride(n);
        std::vector<float> lanes(6 * stride, 12345.0f);
        const kernels::LbvhFusedIn in{codes.data(), 32, leaf_index.data(), ci % 2 ? packed.data() : nullptr};
        const kernels::LbvhFusedOut out{{nodes.data(), ip.data(), lp.data()},
                                        {nodes.data(), leaves.data(), nullptr, nullptr, nullptr,
                                         {lanes.data(), stride}},
                                        slot.data()};
        for (size_t k = c.size(); k-- > 0;)  // chunks in reverse: order must not matter
          kernels::lbvh_build_fused(soa(b), kernels::PairFilter{}, in, out, n,
                                    {c[k], k + 1 < c.size() ? c[k + 1] : n}, &blocked[k]);
        for (size_t k = 1; k < c.size(); ++k)
          kernels::lbvh_build_fused_seam(in, out, n, {c[k], k + 1 < c.size() ? c[k + 1] : n}, blocked[k]);
        ASSERT_EQ(0, std::memcmp(nodes.data(), ref_nodes.data(), (n - 1) * sizeof(kernels::LbvhNode)));
        ASSERT_EQ(ip, ref_ip);
        ASSERT_EQ(lp, ref_lp);
        ASSERT_EQ(0, std::memcmp(leaves.data(), ref_leaves.data(), n * sizeof(kernels::SortedBox)));
        for (uint32_t s = 0; s < n; ++s) {
          const kernels::SortedBox& l = ref_leaves[s];
          const float want[6] = {l.min_x, l.min_y, l.min_z, l.max_x, l.max_y, l.max_z};
          for (size_t k = 0; k < 6; ++k) ASSERT_EQ(lanes[k * stride + s], want[k]) << "leaf " << s << " lane " << k;
        }
      }
    }
  }
}

TEST(Lbvh, RefitKnobRebuildsWhenTreeDegrades) {
  const uint32_t n = scaled(2000);
  Boxes b = uniform_boxes(n, 71, 0.2f, 0.6f);
  const float side = 2.2f * 0.6f * std::cbrt(static_cast<float>(n));
  std::mt19937 rng(72);
  LbvhOptions o;
  o.update = impact::LbvhUpdate::kAuto;
  o.refit_sah_limit = 1.3;
  LbvhBroadPhase bp(o);
  Buffer<Pair> out;
  int rebuilds = 0, refits = 0;
  for (int frame = 0; frame < 60; ++frame) {
    IMPACT_ASSERT_OK(bp.find_pairs(serial(), soa(b), filter_of(b), n, &out));
    (bp.info().rebuilt ? rebuilds : refits)++;
    if (!bp.info().rebuilt) {
      EXPECT_LE(bp.info().last_sah, 1.3 * bp.info().built_sah);
    }
    expect_same_set(out, test::reference_pairs_n2(b), n, "knob frame " + std::to_string(frame));
    if (HasFailure()) return;
    move(b, rng, side, 0.0);  // coherent motion: the tree ages slowly
  }
  EXPECT_GT(refits, 0);
  EXPECT_GT(rebuilds, 1);  // the first call plus at least one forced by SAH growth
  // A different n always rebuilds.
  b.add(0, 0, 0, 1, 1, 1);
  IMPACT_ASSERT_OK(bp.find_pairs(serial(), soa(b), filter_of(b), n + 1, &out));
  EXPECT_TRUE(bp.info().rebuilt);
}

TEST(Lbvh, RefitRejectsMissingTreeOrOtherCount) {
  Boxes b = uniform_boxes(100, 81, 0.2f, 0.6f);
  LbvhBroadPhase bp;
  Buffer<Pair> out{{1, 2}};
  EXPECT_TRUE(test::IsError(bp.refit(serial(), soa(b), filter_of(b), 100, &out),
                            StatusCode::kInvalidArgument, {"LBVH refit"}));
  EXPECT_TRUE(out.empty());
  IMPACT_ASSERT_OK(bp.find_pairs(serial(), soa(b), filter_of(b), 100, &out));
  EXPECT_TRUE(test::IsError(bp.refit(serial(), soa(b), filter_of(b), 99, &out),
                            StatusCode::kInvalidArgument, {"99"}));
  IMPACT_EXPECT_OK(bp.refit(serial(), soa(b), filter_of(b), 100, &out));
  expect_same_set(out, reference_pairs(b), 100, "refit same boxes");
  LbvhBroadPhase empty;
  IMPACT_ASSERT_OK(empty.find_pairs(serial(), soa(b), filter_of(b), 0, &out));
  IMPACT_EXPECT_OK(empty.refit(serial(), soa(b), filter_of(b), 0, &out));
  EXPECT_TRUE(out.empty());
}

// --- SAH ------------------------------------------------------------------------------------

TEST(Lbvh, SahCost) {
  // Two unit cubes 2 m apart: root 3x1x1 (area 14), two leaves (area 6 each).
  Boxes b;
  b.add_box(0, 0, 0, 1, 1, 1);
  b.add_box(2, 0, 0, 3, 1, 1);
  LbvhBroadPhase bp;
  Buffer<Pair> out;
  IMPACT_ASSERT_OK(bp.find_pairs(serial(), soa(b), filter_of(b), 2, &out));
  EXPECT_DOUBLE_EQ(bp.sah_cost(serial()), (14.0 + 6.0 + 6.0) / 14.0);
  // Degenerate root: n.
  Boxes p;
  for (int i = 0; i < 5; ++i) p.add(1, 1, 1, 0, 0, 0);
  IMPACT_ASSERT_OK(bp.find_pairs(serial(), soa(p), filter_of(p), 5, &out));
  EXPECT_EQ(bp.sah_cost(serial()), 5.0);
  EXPECT_EQ(out.size(), 10u);
}

// --- determinism ----------------------------------------------------------------------------

TEST(Lbvh, PairOrderIdenticalAcrossExecutors) {
  const uint32_t n = scaled(60000);
  Boxes b = uniform_boxes(n, 91, 0.2f, 0.7f);
  test::add_random_filter(b, 92, 0.2);
  Boxes moved = b;
  std::mt19937 rng(93);
  move(moved, rng, 2.2f * 0.7f * std::cbrt(static_cast<float>(n)));
  const PairVec ref = reference_pairs(b), ref_moved = reference_pairs(moved);
  for (uint32_t bits : {30u, 63u}) {
    std::vector<Pair> first_build, first_refit;
    std::vector<kernels::LbvhNode> first_nodes;
    double first_sah = 0;
    for (const test::ExecCase& c : test::exec_cases()) {
      const std::string what = test::to_string(c) + " bits=" + std::to_string(bits);
      SCOPED_TRACE(what);
      const Executor exec(c.backend, c.threads);
      LbvhOptions o;
      o.morton_bits = bits;
      LbvhBroadPhase bp(o);
      Buffer<Pair> out;
      IMPACT_ASSERT_OK(bp.find_pairs(exec, soa(b), filter_of(b), n, &out));
      std::vector<Pair> build(out.begin(), out.end());
      const double sah = bp.sah_cost(exec);
      IMPACT_ASSERT_OK(bp.refit(exec, soa(moved), filter_of(moved), n, &out));
      std::vector<Pair> refit(out.begin(), out.end());
      const kernels::LbvhView v = bp.view();
      std::vector<kernels::LbvhNode> nodes(v.nodes, v.nodes + (n - 1));
      if (first_build.empty()) {
        expect_same_set(build, ref, n, what + " build");
        expect_same_set(refit, ref_moved, n, what + " refit");
        first_build = build;
        first_refit = refit;
        first_nodes = nodes;
        first_sah = sah;
        continue;
      }
      ASSERT_EQ(build.size(), first_build.size());
      EXPECT_EQ(0, std::memcmp(build.data(), first_build.data(), build.size() * sizeof(Pair)));
      ASSERT_EQ(refit.size(), first_refit.size());
      EXPECT_EQ(0, std::memcmp(refit.data(), first_refit.data(), refit.size() * sizeof(Pair)));
      EXPECT_EQ(0, std::memcmp(nodes.data(), first_nodes.data(), nodes.size() * sizeof(kernels::LbvhNode)));
      EXPECT_EQ(sah, first_sah);
    }
  }
}

// Cluster of each sorted leaf, computed from the tree the plainest way: walk down from
// the root; a subtree of at most kLbvhCluster leaves is a cluster, numbered in leaf
// order.
std::vector<uint32_t> clusters_of(const kernels::LbvhView& t) {
  std::vector<uint32_t> cluster(t.n);
  uint32_t next = 0;
  std::function<void(uint32_t, uint32_t, uint32_t)> walk = [&](uint32_t node, uint32_t first, uint32_t last) {
    if (last - first + 1 <= kernels::kLbvhCluster) {
      for (uint32_t s = first; s <= last; ++s) cluster[s] = next;
      ++next;
      return;
    }
    const uint32_t h = t.nodes[node].split & kernels::kLbvhSplitMask;
    walk(h, first, h);
    walk(h + 1, h + 1, last);
  };
  walk(0, 0, t.n - 1);
  return cluster;
}

// The kernel over any partition of the leaves into ranges (cuts inside clusters, at
// their ends, one-leaf ranges, empty ones) concatenates to the whole range's bytes;
// with too little room it writes the first pairs and still returns the full count.
TEST(Lbvh, PairRangesConcatenateToTheWhole) {
  for (const char* what : {"uniform", "crowd"}) {
    SCOPED_TRACE(what);
    Boxes b = uniform_boxes(3000, 121, 0.2f, 0.8f);
    if (std::string(what) == "crowd")
      for (uint32_t i = 0; i < 300; ++i) b.min_x[i] = b.max_x[i] = b.min_y[i] = b.max_y[i] = 0.5f;
    LbvhBroadPhase bp;
    Buffer<Pair> out;
    IMPACT_ASSERT_OK(bp.find_pairs(serial(), soa(b), filter_of(b), count(b), &out));
    const kernels::LbvhView t = bp.view();
    const uint64_t total = kernels::lbvh_find_pairs(t, nullptr, 0, {0, t.n});
    ASSERT_EQ(total, out.size());
    std::vector<Pair> whole(total);
    ASSERT_EQ(kernels::lbvh_find_pairs(t, whole.data(), total, {0, t.n}), total);
    ASSERT_EQ(0, std::memcmp(whole.data(), out.data(), total * sizeof(Pair)));
    std::mt19937 rng(122);
    for (int trial = 0; trial < 20; ++trial) {
      std::vector<uint32_t> cuts{0, t.n};
      // trial 0-1: every leaf its own range
      const uint32_t k = trial < 2 ? t.n - 1 : 1 + static_cast<uint32_t>(rng() % 40);
      for (uint32_t i = 0; i < k; ++i) cuts.push_back(trial < 2 ? i + 1 : static_cast<uint32_t>(rng() % (t.n + 1)));
      std::sort(cuts.begin(), cuts.end());
      std::vector<Pair> cat;
      for (size_t i = 0; i + 1 < cuts.size(); ++i) {
        const kernels::Range r{cuts[i], cuts[i + 1]};
        const uint64_t c = kernels::lbvh_find_pairs(t, nullptr, 0, r);
        std::vector<Pair> part(c + 1, Pair{7, 7});
        ASSERT_EQ(kernels::lbvh_find_pairs(t, part.data(), c, r), c);
        ASSERT_EQ(part[c].a, 7u) << "wrote past its capacity";
        if (c > 2) {  // short of room: the prefix, the full count
          std::vector<Pair> head(c / 2);
          ASSERT_EQ(kernels::lbvh_find_pairs(t, head.data(), head.size(), r), c);
          ASSERT_EQ(0, std::memcmp(head.data(), part.data(), head.size() * sizeof(Pair)));
        }
        cat.insert(cat.end(), part.begin(), part.begin() + static_cast<ptrdiff_t>(c));
      }
      ASSERT_EQ(cat.size(), whole.size());
      ASSERT_EQ(0, std::memcmp(cat.data(), whole.data(), whole.size() * sizeof(Pair)));
    }
  }
}

TEST(Lbvh, PairOrderIsByClusterThenLaterLeaf) {
  // Pairs come grouped by the cluster of the earlier leaf (sorted position), clusters
  // in leaf order; within one, by the later leaf's position, then the earlier one's.
  Boxes b = uniform_boxes(5000, 101, 0.2f, 0.8f);
  LbvhBroadPhase bp;
  Buffer<Pair> out;
  IMPACT_ASSERT_OK(bp.find_pairs(serial(), soa(b), filter_of(b), count(b), &out));
  ASSERT_GT(out.size(), 1000u);
  std::vector<uint32_t> slot(b.size());
  for (uint32_t s = 0; s < b.size(); ++s) slot[bp.leaf_index()[s]] = s;
  const std::vector<uint32_t> cluster = clusters_of(bp.view());
  EXPECT_GT(cluster.back(), 100u);
  std::array<uint32_t, 3> prev{0, 0, 0};
  bool first = true;
  for (const Pair& p : out) {
    const uint32_t s = std::min(slot[p.a], slot[p.b]), t = std::max(slot[p.a], slot[p.b]);
    const std::array<uint32_t, 3> key{cluster[s], t, s};
    if (!first) {
      ASSERT_LT(prev, key);
    }
    prev = key;
    first = false;
  }
}

}  // namespace
}  // namespace impact

namespace impact {
namespace {

// The documented order, written independently of the walk: every overlapping pair of
// sorted positions s < t that passes the filter (found by a sweep along x), sorted by
// (cluster of s, t, s).
std::vector<Pair> documented_order(const LbvhBroadPhase& bp) {
  const kernels::LbvhView t = bp.view();
  const std::vector<uint32_t> cluster = clusters_of(t);
  std::vector<uint32_t> by_x(t.n);
  for (uint32_t s = 0; s < t.n; ++s) by_x[s] = s;
  std::sort(by_x.begin(), by_x.end(), [&](uint32_t a, uint32_t b) {
    return t.leaves[a].min_x < t.leaves[b].min_x || (t.leaves[a].min_x == t.leaves[b].min_x && a < b);
  });
  std::vector<std::array<uint32_t, 3>> keys;
  for (uint32_t i = 0; i < t.n; ++i) {
    const kernels::SortedBox& a = t.leaves[by_x[i]];
    for (uint32_t j = i + 1; j < t.n && t.leaves[by_x[j]].min_x <= a.max_x; ++j) {
      const kernels::SortedBox& b = t.leaves[by_x[j]];
      if (!(a.min_y <= b.max_y && b.min_y <= a.max_y && a.min_z <= b.max_z && b.min_z <= a.max_z)) continue;
      const uint32_t s = std::min(by_x[i], by_x[j]), u = std::max(by_x[i], by_x[j]);
      if (t.layer && !kernels::pair_allowed(t.layer[s], t.mask[s], t.is_static[s], t.layer[u], t.mask[u],
                                            t.is_static[u]))
        continue;
      keys.push_back({cluster[s], u, s});
    }
  }
  std::sort(keys.begin(), keys.end());
  std::vector<Pair> out;
  for (const auto& k : keys) {
    const uint32_t a = t.leaves[k[2]].index, b = t.leaves[k[1]].index;
    out.push_back(Pair{std::min(a, b), std::max(a, b)});
  }
  return out;
}

// The pair pass (candidate stack carried along chunks, leaf clusters, the walk's
// deferred right children) gives exactly the documented order, byte for byte:
// uniform, clustered, crowded (every box at one point), mixed sizes, filtered; after a
// refit too.
TEST(Lbvh, PairBytesEqualTheDocumentedOrder) {
  std::vector<std::pair<std::string, Boxes>> scenes;
  scenes.emplace_back("uniform", uniform_boxes(20000, 111, 0.2f, 0.8f));
  scenes.emplace_back("clustered", clustered_boxes(6000, 112));
  scenes.emplace_back("mixed", mixed_size_boxes(6000, 113));
  Boxes crowd = uniform_boxes(700, 114, 0.2f, 0.8f);
  for (uint32_t i = 0; i < 700; ++i) {
    crowd.min_x[i] = crowd.min_y[i] = crowd.min_z[i] = 1.0f;
    crowd.max_x[i] = crowd.max_y[i] = crowd.max_z[i] = 1.0f + 0.001f * static_cast<float>(i % 3);
  }
  scenes.emplace_back("crowd", crowd);
  Boxes filtered = uniform_boxes(20000, 115, 0.2f, 0.8f);
  test::add_random_filter(filtered, 116, 0.2);
  scenes.emplace_back("filtered", filtered);
  for (auto& [what, b] : scenes) {
    SCOPED_TRACE(what);
    for (uint32_t bits : {30u, 63u}) {
      LbvhOptions o;
      o.morton_bits = bits;
      LbvhBroadPhase bp(o);
      Buffer<Pair> out;
      IMPACT_ASSERT_OK(bp.find_pairs(Executor(Backend::kDefault, 2), soa(b), filter_of(b), count(b), &out));
      std::vector<Pair> ref = documented_order(bp);
      ASSERT_EQ(out.size(), ref.size());
      EXPECT_EQ(0, std::memcmp(out.data(), ref.data(), ref.size() * sizeof(Pair)));
      std::mt19937 rng(117);
      move(b, rng, 2.2f * 0.8f * std::cbrt(static_cast<float>(count(b))));
      IMPACT_ASSERT_OK(bp.refit(serial(), soa(b), filter_of(b), count(b), &out));
      ref = documented_order(bp);
      ASSERT_EQ(out.size(), ref.size());
      EXPECT_EQ(0, std::memcmp(out.data(), ref.data(), ref.size() * sizeof(Pair)));
    }
  }
}

}  // namespace
}  // namespace impact
