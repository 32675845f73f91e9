// A BroadPhase call rejected for bad input leaves no trace (include/impact/broadphase.h,
// "Failure"): for every structure (grid, LBVH under each update policy, sweep-and-prune,
// brute force, automatic choice), plain and swept input, NaN, +Inf and -Inf put in each
// field (box corners, swept moves) of boxes at every position of small sets (every
// SIMD lane and the scalar tail) and at chunk edges of a large one, update, build and
// find_pairs must fail naming the box and field, and afterwards pairs(), size() and the
// queries must give the same bytes as before, and the next valid update the same bytes
// as a twin broad phase that never saw the bad calls, which in turn match the
// all-pairs reference of tests/support/aabb_reference.h.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "impact/impact.h"
#include "support/aabb_reference.h"
#include "support/test_support.h"

namespace impact {
namespace {

using test::Boxes;
using test::IsError;

struct Config {
  std::string name;
  BroadPhaseOptions options;
};

std::vector<Config> configs() {
  std::vector<Config> c;
  c.push_back({"grid", BroadPhaseOptions{.kind = BroadPhaseKind::kGrid}});
  c.push_back({"sap", BroadPhaseOptions{.kind = BroadPhaseKind::kSweepAndPrune}});
  c.push_back({"brute", BroadPhaseOptions{.kind = BroadPhaseKind::kBruteForce}});
  c.push_back({"auto", BroadPhaseOptions{.kind = BroadPhaseKind::kAuto}});
  const std::pair<const char*, LbvhUpdate> policies[] = {{"rebuild", LbvhUpdate::kRebuild},
                                                         {"refit", LbvhUpdate::kRefit},
                                                         {"auto", LbvhUpdate::kAuto},
                                                         {"pair_cache", LbvhUpdate::kPairCache}};
  for (const auto& [name, u] : policies)
    c.push_back({std::string("lbvh_") + name, BroadPhaseOptions{.kind = BroadPhaseKind::kLbvh, .lbvh_update = u}});
  return c;
}

// The boxes of frame f: the same boxes moved a little each frame (coherent updates).
Boxes frame(const Boxes& base, int f) {
  Boxes b = base;
  for (size_t i = 0; i < b.size(); ++i) {
    const float d = 0.05f * static_cast<float>(f) * std::sin(static_cast<float>(i) + static_cast<float>(f));
    b.min_x[i] += d, b.max_x[i] += d;
    b.min_z[i] -= 0.5f * d, b.max_z[i] -= 0.5f * d;
  }
  return b;
}

struct Moves {
  std::vector<float> dx, dy, dz;
};

Moves moves_of(size_t n, int f) {
  Moves m;
  for (size_t i = 0; i < n; ++i) {
    m.dx.push_back(0.1f * std::cos(static_cast<float>(i * 3 + f)));
    m.dy.push_back(-0.2f * std::sin(static_cast<float>(i + f)));
    m.dz.push_back(0.05f * static_cast<float>(f));
  }
  return m;
}

AabbInput input_of(const Boxes& b, const Moves* m) {
  AabbInput in = b.input();
  if (m) {
    in.dx = m->dx;
    in.dy = m->dy;
    in.dz = m->dz;
  }
  return in;
}

// Everything observable of a broad phase: pairs, size, and a batch of box queries.
struct Observed {
  std::vector<BodyPair> pairs;
  size_t size = 0;
  QueryHits hits;
};

Observed observe(BroadPhase& bp, const Boxes& probe) {
  Observed o;
  EXPECT_TRUE(test::IsOk(bp.pairs(&o.pairs)));
  o.size = bp.size();
  const AabbQueries q{probe.min_x, probe.min_y, probe.min_z, probe.max_x, probe.max_y, probe.max_z};
  EXPECT_TRUE(test::IsOk(bp.query_aabbs(q, &o.hits)));
  return o;
}

bool same(const Observed& a, const Observed& b) {
  auto bytes = [](const std::vector<BodyPair>& p) {
    std::vector<uint32_t> v;
    for (const BodyPair& x : p) v.push_back(x.a), v.push_back(x.b);
    return v;
  };
  return bytes(a.pairs) == bytes(b.pairs) && a.size == b.size && a.hits.offsets == b.hits.offsets &&
         a.hits.hits == b.hits.hits;
}

const char* const kBoxFields[6] = {"min_x", "min_y", "min_z", "max_x", "max_y", "max_z"};

// Runs: frame 0 build, frame 1 update; then every value of `bad_values` in every field at
// every position in `at` through update (and, when all_calls, build and find_pairs),
// each checked to change nothing; then frame 2, compared with the twin.
void run(const Config& c, const Boxes& base, bool swept, const std::vector<uint32_t>& at,
         const std::vector<float>& bad_values, bool all_calls) {
  SCOPED_TRACE(c.name + (swept ? " swept" : "") + " n=" + std::to_string(base.size()));
  const Boxes f0 = frame(base, 0), f1 = frame(base, 1), f2 = frame(base, 2);
  const Moves m0 = moves_of(base.size(), 0), m1 = moves_of(base.size(), 1), m2 = moves_of(base.size(), 2);
  const Moves* mv[3] = {swept ? &m0 : nullptr, swept ? &m1 : nullptr, swept ? &m2 : nullptr};
  BroadPhase bp(c.options), twin(c.options);
  std::vector<BodyPair> out;
  for (BroadPhase* b : {&bp, &twin}) {
    IMPACT_ASSERT_OK(b->build(input_of(f0, mv[0])));
    IMPACT_ASSERT_OK(b->update(input_of(f1, mv[1])));
  }
  const Boxes probe = test::uniform_boxes(16, 99, 0.3f, 1.5f);
  const Observed before = observe(bp, probe);
  if (!swept) test::expect_same_set(before.pairs, test::reference_pairs(f1), f1.size(), "frame 1");
  int checked = 0;
  for (const float bad : bad_values) {
    for (int field = 0; field < (swept ? 9 : 6); ++field) {
      for (const uint32_t i : at) {
        Boxes b = frame(base, 2);
        Moves m = moves_of(base.size(), 2);
        std::vector<float>* fv[9] = {&b.min_x, &b.min_y, &b.min_z, &b.max_x, &b.max_y, &b.max_z, &m.dx, &m.dy, &m.dz};
        (*fv[field])[i] = bad;
        const char* name = field < 6 ? kBoxFields[field] : (field == 6 ? "dx" : field == 7 ? "dy" : "dz");
        const std::string box = "box " + std::to_string(i);
        const AabbInput in = input_of(b, swept ? &m : nullptr);
        const std::string what = box + " " + name + " = " + std::to_string(bad);
        ASSERT_TRUE(IsError(bp.update(in), StatusCode::kInvalidArgument, {box.c_str(), name})) << what;
        ASSERT_TRUE(same(observe(bp, probe), before)) << "update changed the structure: " << what;
        ++checked;
        if (!all_calls) continue;
        ASSERT_TRUE(IsError(bp.build(in), StatusCode::kInvalidArgument, {box.c_str(), name})) << what;
        ASSERT_TRUE(same(observe(bp, probe), before)) << "build changed the structure: " << what;
        out.assign(3, BodyPair{1, 2});
        ASSERT_TRUE(IsError(bp.find_pairs(in, &out), StatusCode::kInvalidArgument, {box.c_str(), name})) << what;
        EXPECT_TRUE(out.empty()) << what;
        ASSERT_TRUE(same(observe(bp, probe), before)) << "find_pairs changed the structure: " << what;
      }
    }
  }
  EXPECT_GT(checked, 0);
  // Recovery: the next valid update carries on as if the bad calls never happened.
  IMPACT_ASSERT_OK(bp.update(input_of(f2, mv[2])));
  IMPACT_ASSERT_OK(twin.update(input_of(f2, mv[2])));
  const Observed after = observe(bp, probe), twin_after = observe(twin, probe);
  EXPECT_TRUE(same(after, twin_after));
  if (!swept) test::expect_same_set(after.pairs, test::reference_pairs(f2), f2.size(), "frame 2");
}

const float kNan = std::numeric_limits<float>::quiet_NaN();
const float kInf = std::numeric_limits<float>::infinity();

TEST(BroadPhaseFailedUpdate, BadValuesInEveryLaneChangeNothing) {
  for (const Config& c : configs()) {
    for (const uint32_t n : {1u, 2u, 9u, 37u}) {
      const Boxes base = test::uniform_boxes(n, 5 + n, 0.3f, 1.0f);
      std::vector<uint32_t> at;
      for (uint32_t i = 0; i < n; ++i) at.push_back(i);
      for (const bool swept : {false, true}) run(c, base, swept, at, {kNan, kInf, -kInf}, true);
    }
  }
}

TEST(BroadPhaseFailedUpdate, BadValuesAtChunkEdgesChangeNothing) {
  // Validation runs in 65536-box chunks: the first box of the second chunk and the
  // last box of the tail (every lane position is covered by the small sets above).
  const uint32_t n = 65536 + 21;
  const Boxes base = test::uniform_boxes(n, 17, 0.2f, 0.6f);
  for (const Config& c : configs()) {
    if (c.options.kind == BroadPhaseKind::kBruteForce) continue;  // O(n^2)
    run(c, base, false, {65536u, n - 1}, {kNan}, false);
  }
}

TEST(BroadPhaseFailedUpdate, FilteredBoxesKeepTheirFilterAfterARejectedUpdate) {
  Boxes base = test::uniform_boxes(60, 3, 0.3f, 1.0f);
  test::add_random_filter(base, 4, 0.3);
  for (const Config& c : configs()) {
    run(c, base, false, {0u, 31u, 59u}, {kNan, -kInf}, true);
  }
}

}  // namespace
}  // namespace impact
