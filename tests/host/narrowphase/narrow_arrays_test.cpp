// NarrowPhase::collide_arrays (host/narrowphase/narrow_arrays.cpp), the batch form
// over caller-owned arrays, against NarrowPhase::collide on the same pairs (a
// different route through the library: posed objects, expansion, compaction and the
// Manifold structs): the same hits and the same bytes of every number, in random pair
// order (the bucket sort) and in bucket order (the kernels write the caller's arrays
// in place), for every backend and thread count; the swap (b, a) gives the opposite
// normal; bad input is named.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <random>
#include <vector>

#include "host/narrowphase/narrow_phase.h"
#include "host/shapes/shape_store.h"
#include "impact/impact.h"
#include "tests/support/shape_zoo.h"
#include "tests/support/test_support.h"

namespace impact {
namespace {

using test::IsError;
using test::IsOk;

/// Caller-owned arrays for collide_arrays: poses of a scene and results per pair.
struct Arrays {
  std::vector<float> px, py, pz, qx, qy, qz, qw;
  std::vector<uint8_t> count;
  std::vector<float> nx, ny, nz, depth, x[4], y[4], z[4], d[4];

  explicit Arrays(const test::Scene& s) {
    for (const Pose& p : s.poses) {
      px.push_back(p.position.x());
      py.push_back(p.position.y());
      pz.push_back(p.position.z());
      qx.push_back(p.orientation.x());
      qy.push_back(p.orientation.y());
      qz.push_back(p.orientation.z());
      qw.push_back(p.orientation.w());
    }
    const size_t n = s.pairs.size();
    count.assign(n, 0xee);  // stale values: collide_arrays must write every count
    for (auto* v : {&nx, &ny, &nz, &depth}) v->assign(n, -7.0f);
    for (int k = 0; k < 4; ++k)
      for (auto* v : {&x[k], &y[k], &z[k], &d[k]}) v->assign(n, -7.0f);
  }
  PoseArrays poses() const { return {px, py, pz, qx, qy, qz, qw}; }
  PairContactArrays out() {
    PairContactArrays o;
    o.count = count;
    o.normal_x = nx;
    o.normal_y = ny;
    o.normal_z = nz;
    o.depth = depth;
    for (int k = 0; k < 4; ++k) {
      o.point_x[k] = x[k];
      o.point_y[k] = y[k];
      o.point_z[k] = z[k];
      o.point_depth[k] = d[k];
    }
    return o;
  }
};

bool same_bits(float a, float b) { return std::memcmp(&a, &b, sizeof a) == 0; }

// Every pair: a hit in one iff in the other, and then the same bytes of every number.
void expect_same_as_collide(const std::vector<Manifold>& ref, const Arrays& a, size_t pairs) {
  std::vector<int> of(pairs, -1);
  for (size_t m = 0; m < ref.size(); ++m) {
    ASSERT_EQ(of[ref[m].pair], -1) << "a convex pair has one manifold";
    of[ref[m].pair] = static_cast<int>(m);
  }
  size_t hits = 0;
  for (size_t i = 0; i < pairs; ++i) {
    if (of[i] < 0) {
      EXPECT_EQ(a.count[i], 0) << "pair " << i;
      continue;
    }
    ++hits;
    const Manifold& m = ref[static_cast<size_t>(of[i])];
    ASSERT_EQ(a.count[i], m.point_count) << "pair " << i;
    EXPECT_TRUE(same_bits(a.nx[i], m.normal.x()) && same_bits(a.ny[i], m.normal.y()) &&
                same_bits(a.nz[i], m.normal.z()))
        << "pair " << i;
    EXPECT_TRUE(same_bits(a.depth[i], m.depth)) << "pair " << i;
    for (uint32_t k = 0; k < m.point_count; ++k) {
      EXPECT_TRUE(same_bits(a.x[k][i], m.points[k].x()) && same_bits(a.y[k][i], m.points[k].y()) &&
                  same_bits(a.z[k][i], m.points[k].z()) && same_bits(a.d[k][i], m.point_depth[k]))
          << "pair " << i << " point " << k;
    }
  }
  EXPECT_EQ(hits, ref.size());
}

// The zoo without meshes and compounds, which collide_arrays does not take.
test::Scene convex_scene(const test::Zoo& z, uint32_t objects, uint32_t pairs, uint32_t seed) {
  test::Scene s = test::random_scene(z, objects, pairs, seed);
  std::mt19937 rng(seed + 1);
  const ShapeId convex[] = {z.sphere, z.capsule, z.box, z.aabb, z.convex, z.cylinder, z.ellipsoid, z.half_space};
  for (ShapeId& id : s.shapes)
    if (id == z.mesh || id == z.compound) id = convex[rng() % 7];  // not a half-space: no half-space pair
  return s;
}

uint32_t bucket_of(const test::Zoo& z, const test::Scene& s, const ShapePair& p) {
  const auto ta = static_cast<uint32_t>(host::leaf_type_of(z.set.store().shapes[s.shapes[p.a].index].type));
  const auto tb = static_cast<uint32_t>(host::leaf_type_of(z.set.store().shapes[s.shapes[p.b].index].type));
  return std::min(ta, tb) * 64 + std::max(ta, tb);
}

TEST(NarrowArrays, SameNumbersAsCollideInAnyPairOrder) {
  test::Zoo z;
  test::Scene s = convex_scene(z, 600, test::scaled(8000), 21);
  for (const bool by_type : {false, true}) {
    SCOPED_TRACE(by_type ? "pairs listed by type: written in place" : "random order: bucket sort");
    if (by_type)
      std::stable_sort(s.pairs.begin(), s.pairs.end(), [&](const ShapePair& a, const ShapePair& b) {
        return bucket_of(z, s, a) < bucket_of(z, s, b);
      });
    NarrowPhase ref_phase;
    std::vector<Manifold> ref;
    IMPACT_ASSERT_OK(ref_phase.collide(z.set, s.shapes, s.poses, s.pairs, &ref));
    ASSERT_GT(ref.size(), s.pairs.size() / 20) << "the scene should touch often";
    for (const test::ExecCase& c : test::exec_cases()) {
      SCOPED_TRACE(test::to_string(c));
      NarrowPhaseOptions o;
      o.exec.backend = c.backend;
      o.exec.threads = c.threads;
      NarrowPhase phase(o);
      Arrays a(s);
      IMPACT_ASSERT_OK(phase.collide_arrays(z.set, s.shapes, a.poses(), s.pairs, a.out()));
      expect_same_as_collide(ref, a, s.pairs.size());
    }
  }
}

TEST(NarrowArrays, OneBucketWrittenInPlaceAcrossBlocks) {
  // 5000 sphere-sphere pairs (ten lane blocks and a tail), touching about half the time,
  // and the same with a box-box bucket; coincident centres included.
  test::Zoo z;
  for (const ShapeId id : {z.sphere, z.box}) {
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> u(-0.9f, 0.9f);
    test::Scene s;
    for (uint32_t k = 0; k < 5000; ++k) {
      Pose a = test::random_pose(rng, 10.0f), b = test::random_pose(rng, 1.0f);
      b.position = k % 97 == 0 ? a.position : a.position + Eigen::Vector3f(u(rng), u(rng), u(rng));
      s.shapes.insert(s.shapes.end(), {id, id});
      s.poses.insert(s.poses.end(), {a, b});
      s.pairs.push_back({2 * k, 2 * k + 1});
    }
    NarrowPhase phase;
    std::vector<Manifold> ref;
    IMPACT_ASSERT_OK(phase.collide(z.set, s.shapes, s.poses, s.pairs, &ref));
    Arrays a(s);
    IMPACT_ASSERT_OK(phase.collide_arrays(z.set, s.shapes, a.poses(), s.pairs, a.out()));
    expect_same_as_collide(ref, a, s.pairs.size());
  }
}

TEST(NarrowArrays, SwappedPairsGiveTheOppositeNormal) {
  test::Zoo z;
  test::Scene s = convex_scene(z, 300, test::scaled(3000), 22);
  test::Scene t = s;
  for (ShapePair& p : t.pairs) std::swap(p.a, p.b);
  NarrowPhase phase;
  Arrays a(s), b(t);
  IMPACT_ASSERT_OK(phase.collide_arrays(z.set, s.shapes, a.poses(), s.pairs, a.out()));
  IMPACT_ASSERT_OK(phase.collide_arrays(z.set, t.shapes, b.poses(), t.pairs, b.out()));
  size_t hits = 0;
  for (size_t i = 0; i < s.pairs.size(); ++i) {
    ASSERT_EQ(a.count[i] > 0, b.count[i] > 0) << "pair " << i;
    if (a.count[i] == 0) continue;
    ++hits;
    // Two kernel orders for mixed types (A is the lower type either way): the same
    // lanes, so the exact negation; a same-type pair runs the other way round and
    // agrees to rounding.
    const Eigen::Vector3f na(a.nx[i], a.ny[i], a.nz[i]), nb(b.nx[i], b.ny[i], b.nz[i]);
    EXPECT_LT((na + nb).norm(), 2e-3f) << "pair " << i;
    EXPECT_NEAR(a.depth[i], b.depth[i], 2e-3f) << "pair " << i;
  }
  EXPECT_GT(hits, 0u);
}

TEST(NarrowArrays, BadInputIsNamed) {
  test::Zoo z;
  test::Scene s = convex_scene(z, 20, 60, 23);
  NarrowPhase phase;
  {
    Arrays a(s);
    a.qw.pop_back();
    EXPECT_TRUE(IsError(phase.collide_arrays(z.set, s.shapes, a.poses(), s.pairs, a.out()),
                        StatusCode::kSizeMismatch, {"poses.qw"}));
  }
  {
    Arrays a(s);
    a.d[3].pop_back();
    EXPECT_TRUE(IsError(phase.collide_arrays(z.set, s.shapes, a.poses(), s.pairs, a.out()),
                        StatusCode::kSizeMismatch, {"out.point_depth[3]"}));
  }
  for (const ShapeId bad : {z.mesh, z.compound}) {
    test::Scene t = s;
    t.shapes[7] = bad;
    Arrays a(t);
    EXPECT_TRUE(IsError(phase.collide_arrays(z.set, t.shapes, a.poses(), t.pairs, a.out()),
                        StatusCode::kInvalidArgument, {"object 7", "NarrowPhase::collide"}));
  }
  {
    test::Scene t = s;
    t.shapes[3] = ShapeId{9999};
    t.shapes[5] = z.mesh;  // the lowest bad object is named
    Arrays a(t);
    EXPECT_TRUE(IsError(phase.collide_arrays(z.set, t.shapes, a.poses(), t.pairs, a.out()),
                        StatusCode::kInvalidArgument, {"object 3", "unknown shape id"}));
  }
  {
    Arrays a(s);
    a.qx[4] = 2.0f;
    EXPECT_TRUE(IsError(phase.collide_arrays(z.set, s.shapes, a.poses(), s.pairs, a.out()),
                        StatusCode::kInvalidArgument, {"object 4", "unit quaternion"}));
    a.qx[4] = NAN;
    EXPECT_TRUE(IsError(phase.collide_arrays(z.set, s.shapes, a.poses(), s.pairs, a.out()),
                        StatusCode::kInvalidArgument, {"object 4", "not finite"}));
  }
  {
    test::Scene t = s;
    t.pairs[11] = {2, 2};
    t.pairs[12] = {0, 20};
    Arrays a(t);
    EXPECT_TRUE(IsError(phase.collide_arrays(z.set, t.shapes, a.poses(), t.pairs, a.out()),
                        StatusCode::kInvalidArgument, {"pair 11", "itself"}));
    t.pairs[11] = {1, 2};
    EXPECT_TRUE(IsError(phase.collide_arrays(z.set, t.shapes, a.poses(), t.pairs, a.out()),
                        StatusCode::kInvalidArgument, {"pair 12", "out of range"}));
    t.shapes[0] = t.shapes[1] = z.half_space;
    t.pairs[12] = {0, 1};
    Arrays b(t);
    EXPECT_TRUE(IsError(phase.collide_arrays(z.set, t.shapes, b.poses(), t.pairs, b.out()),
                        StatusCode::kInvalidArgument, {"pair 12", "half-spaces"}));
  }
  {  // empty input: nothing to do
    test::Scene t;
    Arrays a(t);
    IMPACT_EXPECT_OK(phase.collide_arrays(z.set, t.shapes, a.poses(), t.pairs, a.out()));
  }
}

}  // namespace
}  // namespace impact
