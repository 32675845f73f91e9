// Batched queries of impact::BroadPhase (query_aabbs / query_spheres / query_points)
// through the public API, against the independent double-precision reference of
// tests/support/query_reference.h: every structure (grid, LBVH, sweep-and-prune,
// brute force, automatic) must return the reference's CSR byte for byte, on random
// and adversarial inputs, after many frames of coherent updates (LBVH refit, SAP
// insertion sort), for every backend and thread count; bad input is rejected naming
// the query and field, leaving the output untouched.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "impact/impact.h"
#include "support/aabb_reference.h"
#include "support/query_reference.h"
#include "support/test_support.h"

namespace impact {
namespace {

using test::Boxes;
using test::Csr;
using test::IsError;
using test::QShape;
using test::Queries;
using test::random_queries;
using test::scaled;

const std::vector<BroadPhaseKind>& all_kinds() {
  static const std::vector<BroadPhaseKind> k{BroadPhaseKind::kGrid, BroadPhaseKind::kLbvh,
                                             BroadPhaseKind::kSweepAndPrune, BroadPhaseKind::kBruteForce,
                                             BroadPhaseKind::kAuto};
  return k;
}

// The public query call for q's shape.
Status run_query(BroadPhase& bp, const Queries& q, QueryHits* out, const ExecConfig& exec = {}) {
  switch (q.shape) {
    case QShape::kAabb:
      return bp.query_aabbs(AabbQueries{q.x0, q.y0, q.z0, q.x1, q.y1, q.z1, q.mask}, out, exec);
    case QShape::kSphere: return bp.query_spheres(SphereQueries{q.x0, q.y0, q.z0, q.radius, q.mask}, out, exec);
    case QShape::kPoint: return bp.query_points(PointQueries{q.x0, q.y0, q.z0, q.mask}, out, exec);
  }
  return Status(StatusCode::kInvalidArgument, "shape");
}

Csr to_csr(const QueryHits& h) { return Csr{h.offsets, h.hits}; }

// Every kind, built over b, answers every query set like the reference.
void check_all(const Boxes& b, const std::vector<Queries>& sets, const std::string& what,
               const std::vector<ExecConfig>& execs = {ExecConfig{Backend::kSerial, 1}, ExecConfig{}}) {
  SCOPED_TRACE(what);
  std::vector<Csr> refs;
  for (const Queries& q : sets) refs.push_back(test::reference_query(b, q));
  for (BroadPhaseKind kind : all_kinds()) {
    BroadPhase bp(kind);
    IMPACT_ASSERT_OK(bp.build(b.input()));
    for (size_t s = 0; s < sets.size(); ++s)
      for (const ExecConfig& e : execs) {
        QueryHits got{{9u}, {9u}};  // stale content must be replaced
        IMPACT_ASSERT_OK(run_query(bp, sets[s], &got, e));
        EXPECT_TRUE(test::SameCsr(to_csr(got), refs[s]))
            << to_string(kind) << " " << test::to_string(sets[s].shape) << " set " << s << " "
            << to_string(e.backend) << "/" << e.threads;
        EXPECT_EQ(got.size(), sets[s].size());
      }
  }
}

std::vector<Queries> random_sets(const Boxes& b, float size, uint32_t n, uint32_t seed) {
  std::vector<Queries> v;
  for (QShape shape : {QShape::kAabb, QShape::kSphere, QShape::kPoint})
    for (int mask_kind : {0, 1}) v.push_back(random_queries(b, shape, n, seed++, size, mask_kind));
  return v;
}

Boxes filtered(Boxes b, uint32_t seed) {
  test::add_random_filter(b, seed, 0.3);
  return b;
}

// --- correctness vs reference --------------------------------------------------------------

TEST(BroadPhaseQueries, UniformAndClustered) {
  const Boxes u = test::uniform_boxes(scaled(4000), 1, 0.2f, 1.0f);
  check_all(u, random_sets(u, 2.0f, scaled(300), 1), "uniform");
  check_all(filtered(u, 2), random_sets(u, 2.0f, scaled(300), 11), "uniform filtered");
  const Boxes c = test::clustered_boxes(scaled(4000), 3);
  check_all(filtered(c, 3), random_sets(c, 1.5f, scaled(300), 21), "clustered filtered");
}

TEST(BroadPhaseQueries, SizesSpanning1000x) {
  std::mt19937 rng(4);
  std::uniform_real_distribution<float> logh(std::log(0.005f), std::log(5.0f));
  std::uniform_real_distribution<float> pos(-30.0f, 30.0f);
  Boxes b;
  for (uint32_t i = 0; i < scaled(4000); ++i) {
    const float h = std::exp(logh(rng));
    b.add(pos(rng), pos(rng), pos(rng), h, h * 0.6f, h * 1.4f);
  }
  check_all(b, random_sets(b, 3.0f, scaled(200), 31), "sizes over 1000x");
  check_all(filtered(b, 5), random_sets(b, 3.0f, scaled(200), 41), "sizes over 1000x filtered");
}

TEST(BroadPhaseQueries, ScalesAndOffsets) {
  for (float scale : {1e-4f, 1e4f}) {
    const Boxes b = test::uniform_boxes(scaled(2500), 6, 0.2f, 1.0f, 0.0f, scale);
    check_all(b, random_sets(b, 2.0f * scale, scaled(150), 51), "scale " + std::to_string(scale));
  }
  for (float offset : {1.0e6f, -1.0e6f}) {
    const Boxes b = test::uniform_boxes(scaled(2500), 7, 0.2f, 1.0f, offset);
    check_all(b, random_sets(b, 2.0f, scaled(150), 61), "offset " + std::to_string(offset));
  }
}

TEST(BroadPhaseQueries, ZeroOneTwoBoxes) {
  for (uint32_t n : {0u, 1u, 2u}) {
    Boxes b;
    if (n >= 1) b.add(0, 0, 0, 1, 1, 1);
    if (n >= 2) b.add(1.5f, 0.5f, -0.5f, 1, 1, 1);
    std::vector<Queries> sets(3);
    sets[0].shape = QShape::kAabb, sets[1].shape = QShape::kSphere, sets[2].shape = QShape::kPoint;
    for (float x : {-3.0f, -1.0f, 0.0f, 0.5f, 1.0f, 1.5f, 2.5f, 4.0f}) {
      sets[0].add_box(x - 0.5f, -0.5f, -0.5f, x, 0.5f, 0.5f);
      sets[1].add_sphere(x, 1.0f, 1.0f, 0.75f);
      sets[2].add_point(x, 0.5f, 0.5f);
    }
    check_all(b, sets, "n=" + std::to_string(n));
    if (n == 1) {  // the grid and SAP keep no copy of a single box: the stage does
      b.layer = {2u}, b.mask = {~0u}, b.is_static = {0};
      for (Queries& q : sets) {  // masks 0, 2 (hits layer 2), 1 (misses), 3, or none
        q.mask.assign(q.size(), 0u);
        q.mask[1] = 2u, q.mask[3] = 1u, q.mask[4] = 3u, q.mask[5] = ~0u;
      }
      check_all(b, sets, "n=1 filtered");
    }
  }
}

TEST(BroadPhaseQueries, AdversarialPlacements) {
  // All boxes at one point (zero size); zero-size queries; huge queries covering
  // everything; queries outside the scene; exact touching.
  Boxes point_cloud;
  for (uint32_t i = 0; i < scaled(300); ++i) point_cloud.add(2.0f, -1.0f, 5.0f, 0, 0, 0);
  std::vector<Queries> sets(3);
  sets[0].shape = QShape::kAabb, sets[1].shape = QShape::kSphere, sets[2].shape = QShape::kPoint;
  sets[0].add_box(2.0f, -1.0f, 5.0f, 2.0f, -1.0f, 5.0f);
  sets[0].add_box(1.0f, -2.0f, 4.0f, 2.0f, -1.0f, 5.0f);  // max corner on the points
  sets[0].add_box(std::nextafter(2.0f, 3.0f), -1.0f, 5.0f, 3.0f, 0.0f, 6.0f);
  sets[1].add_sphere(2.0f, -1.0f, 5.0f, 0.0f);
  sets[1].add_sphere(5.0f, 3.0f, 5.0f, 5.0f);  // 3-4-5: exactly on the sphere
  sets[1].add_sphere(5.0f, 3.0f, 5.0f, std::nextafter(5.0f, 0.0f));
  sets[2].add_point(2.0f, -1.0f, 5.0f);
  sets[2].add_point(2.0f, std::nextafter(-1.0f, 0.0f), 5.0f);
  check_all(point_cloud, sets, "all at one point");

  Boxes lattice;  // unit boxes at even coordinates: faces 1 apart
  for (int z = 0; z < 5; ++z)
    for (int y = 0; y < 5; ++y)
      for (int x = 0; x < 5; ++x)
        lattice.add_box(static_cast<float>(2 * x), static_cast<float>(2 * y), static_cast<float>(2 * z),
                        static_cast<float>(2 * x + 1), static_cast<float>(2 * y + 1), static_cast<float>(2 * z + 1));
  for (Queries& q : sets) q = test::empty_queries(q.shape);
  for (int x = -2; x < 12; ++x) {
    const float f = static_cast<float>(x);
    sets[0].add_box(f - 1.0f, 0.0f, 0.0f, f, 9.0f, 0.0f);  // max == a box min (touching)
    sets[0].add_box(-1e6f, -1e6f, -1e6f, 1e6f, 1e6f, 1e6f);  // everything
    sets[0].add_box(f + 100.0f, 0.0f, 0.0f, f + 101.0f, 1.0f, 1.0f);  // outside
    sets[1].add_sphere(f, 0.5f, 0.5f, 1.0f);
    sets[1].add_sphere(f, -4.0f, 0.5f, 4.0f);  // tangent to the y = 0 faces
    sets[1].add_sphere(4.0f, 4.0f, 4.0f, 1e7f);  // everything
    sets[2].add_point(f, 1.0f, 1.0f);
    sets[2].add_point(f, -1e5f, 0.0f);  // outside
  }
  check_all(lattice, sets, "touching lattice");
  check_all(filtered(lattice, 8), sets, "touching lattice filtered");
}

TEST(BroadPhaseQueries, FarOutliers) {
  // The grid spans the crowd and clamps far outliers into its boundary cells
  // (host::grid_extent), so queries beyond its range must still visit those cells:
  // queries at and around every outlier, far beyond them, and random ones.
  for (bool long_box : {false, true}) {
    const Boxes b = test::outlier_boxes(scaled(2000), 91, {1e9f, 1e15f}, long_box);  // queries <= 1e18
    std::vector<Queries> sets = random_sets(b, 2.0f, 200, 17);
    Queries near[3];
    near[0].shape = QShape::kAabb, near[1].shape = QShape::kSphere, near[2].shape = QShape::kPoint;
    for (size_t i = scaled(2000); i < b.size(); ++i) {
      const float x = b.min_x[i], y = b.min_y[i], z = b.min_z[i];
      near[0].add_box(x - 1.0f, y - 1.0f, z - 1.0f, x + 1.0f, y + 1.0f, z + 1.0f);
      near[0].add_box(x, y, z, x, y, z);
      near[0].add_box(2.0f * x, 2.0f * y, 2.0f * z, 2.0f * x + 1.0f, 2.0f * y + 1.0f, 2.0f * z + 1.0f);
      near[1].add_sphere(x, y, z, 1.0f);
      near[1].add_sphere(x, y, z, 0.0f);
      near[2].add_point(x, y, z);
      near[2].add_point(b.max_x[i], b.max_y[i], b.max_z[i]);
    }
    near[0].add_box(-1e18f, -1e18f, -1e18f, 1e18f, 1e18f, 1e18f);  // everything
    for (Queries& q : near) sets.push_back(q);
    check_all(b, sets, long_box ? "far outliers, long box" : "far outliers");
    check_all(filtered(b, 5), sets, "far outliers filtered");
  }
}

TEST(BroadPhaseQueries, SweptBoxesAreQueried) {
  // In swept mode the stored boxes are the unions of start and moved boxes.
  Boxes b = test::uniform_boxes(scaled(1500), 9, 0.2f, 0.5f);
  std::vector<float> dx(b.size()), dy(b.size()), dz(b.size());
  std::mt19937 rng(9);
  std::uniform_real_distribution<float> d(-3.0f, 3.0f);
  Boxes swept = b;
  for (size_t i = 0; i < b.size(); ++i) {
    dx[i] = d(rng), dy[i] = d(rng), dz[i] = d(rng);
    swept.min_x[i] = std::min(b.min_x[i], b.min_x[i] + dx[i]);
    swept.min_y[i] = std::min(b.min_y[i], b.min_y[i] + dy[i]);
    swept.min_z[i] = std::min(b.min_z[i], b.min_z[i] + dz[i]);
    swept.max_x[i] = std::max(b.max_x[i], b.max_x[i] + dx[i]);
    swept.max_y[i] = std::max(b.max_y[i], b.max_y[i] + dy[i]);
    swept.max_z[i] = std::max(b.max_z[i], b.max_z[i] + dz[i]);
  }
  AabbInput in = b.input();
  in.dx = dx, in.dy = dy, in.dz = dz;
  const std::vector<Queries> sets = random_sets(swept, 1.0f, 100, 71);
  for (BroadPhaseKind kind : all_kinds()) {
    BroadPhase bp(kind);
    IMPACT_ASSERT_OK(bp.build(in));
    for (const Queries& q : sets) {
      QueryHits got;
      IMPACT_ASSERT_OK(run_query(bp, q, &got));
      EXPECT_TRUE(test::SameCsr(to_csr(got), test::reference_query(swept, q))) << to_string(kind);
    }
  }
}

// --- coherent frames --------------------------------------------------------------------------

TEST(BroadPhaseQueries, HundredFramesOfMotion) {
  // Every structure and LBVH update policy, updated every frame; queries vs the
  // reference every 10th frame (after refits, SAP insertion sorts, grid rebuilds).
  struct Config {
    BroadPhaseOptions options;
    const char* name;
  };
  const std::vector<Config> configs{
      {{.kind = BroadPhaseKind::kGrid}, "grid"},
      {{.kind = BroadPhaseKind::kLbvh, .lbvh_update = LbvhUpdate::kRefit}, "lbvh refit"},
      {{.kind = BroadPhaseKind::kLbvh, .lbvh_update = LbvhUpdate::kAuto}, "lbvh auto"},
      {{.kind = BroadPhaseKind::kLbvh, .lbvh_update = LbvhUpdate::kPairCache}, "lbvh pair cache"},
      {{.kind = BroadPhaseKind::kSweepAndPrune}, "sap"},
      {{.kind = BroadPhaseKind::kBruteForce}, "brute force"},
  };
  const Boxes start = filtered(test::uniform_boxes(scaled(2000), 10, 0.2f, 1.0f), 10);
  for (const Config& c : configs) {
    SCOPED_TRACE(c.name);
    Boxes b = start;
    BroadPhase bp(c.options);
    IMPACT_ASSERT_OK(bp.build(b.input()));
    std::mt19937 rng(10);
    std::normal_distribution<float> small_step(0.0f, 0.03f), big_step(0.0f, 1.0f);
    for (int frame = 0; frame < 100; ++frame) {
      auto& step = frame % 25 == 12 ? big_step : small_step;
      for (size_t i = 0; i < b.size(); ++i) {
        const float d[3] = {step(rng), step(rng), step(rng)};
        b.min_x[i] += d[0], b.max_x[i] += d[0];
        b.min_y[i] += d[1], b.max_y[i] += d[1];
        b.min_z[i] += d[2], b.max_z[i] += d[2];
      }
      IMPACT_ASSERT_OK(bp.update(b.input()));
      if (frame % 10 != 9) continue;
      for (const Queries& q : random_sets(b, 2.0f, 60, 1000 + frame)) {
        QueryHits got;
        IMPACT_ASSERT_OK(run_query(bp, q, &got));
        EXPECT_TRUE(test::SameCsr(to_csr(got), test::reference_query(b, q)))
            << "frame " << frame << " " << test::to_string(q.shape);
      }
    }
  }
}

// --- determinism ------------------------------------------------------------------------------

TEST(BroadPhaseQueries, SameBytesForEveryBackendAndThreadCount) {
  // Enough queries for many chunks; hits grow the per-chunk buffers (huge boxes).
  const Boxes b = filtered(test::uniform_boxes(scaled(8000), 12, 0.2f, 1.0f), 12);
  std::vector<Queries> sets = random_sets(b, 3.0f, scaled(1000), 81);
  Queries big = test::empty_queries(QShape::kAabb);
  for (int i = 0; i < 100; ++i) big.add_box(-20.0f + static_cast<float>(i) * 0.1f, -20.0f, -20.0f, 20.0f, 20.0f, 20.0f);
  sets.push_back(big);
  std::vector<ExecConfig> execs;
  for (const test::ExecCase& c : test::exec_cases()) execs.push_back({c.backend, c.threads});
  check_all(b, sets, "all executors", execs);
}

// --- bad input ----------------------------------------------------------------------------------

TEST(BroadPhaseQueries, RejectsBadInputNamingQueryAndField) {
  const Boxes b = test::uniform_boxes(200, 13, 0.2f, 1.0f);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inf = std::numeric_limits<float>::infinity();
  Queries aabb = random_queries(b, QShape::kAabb, 8, 1, 1.0f);
  Queries sphere = random_queries(b, QShape::kSphere, 8, 2, 1.0f);
  Queries point = random_queries(b, QShape::kPoint, 8, 3, 1.0f);
  const QueryHits untouched{{5u, 6u}, {7u}};

  BroadPhase bp(BroadPhaseKind::kLbvh);
  {  // nothing built yet
    QueryHits out = untouched;
    EXPECT_TRUE(IsError(run_query(bp, aabb, &out), StatusCode::kInvalidArgument, {"query_aabbs", "built"}));
    EXPECT_EQ(out.offsets, untouched.offsets);
  }
  IMPACT_ASSERT_OK(bp.build(b.input()));
  auto expect_error = [&](const Queries& q, StatusCode code, std::initializer_list<const char*> fragments) {
    QueryHits out = untouched;
    EXPECT_TRUE(IsError(run_query(bp, q, &out), code, fragments));
    EXPECT_EQ(out.offsets, untouched.offsets);
    EXPECT_EQ(out.hits, untouched.hits);
  };
  {
    Queries q = aabb;
    q.y0[3] = nan;
    expect_error(q, StatusCode::kInvalidArgument, {"query_aabbs", "query 3", "min_y"});
  }
  {
    Queries q = aabb;
    q.z1[5] = inf;
    expect_error(q, StatusCode::kInvalidArgument, {"query 5", "max_z"});
  }
  {
    Queries q = aabb;
    q.x0[2] = q.x1[2] + 0.5f;  // min > max
    expect_error(q, StatusCode::kInvalidArgument, {"query 2", "min_x", "exceeds", "max_x"});
  }
  {
    Queries q = aabb;
    q.x0[1] = -2e18f;  // beyond the coordinate range
    expect_error(q, StatusCode::kInvalidArgument, {"query 1", "min_x", "1e18"});
  }
  {
    Queries q = aabb;
    q.y1.pop_back();
    expect_error(q, StatusCode::kSizeMismatch, {"max_y"});
  }
  {
    Queries q = aabb;
    q.mask.assign(3, 1u);
    expect_error(q, StatusCode::kSizeMismatch, {"mask"});
  }
  {
    Queries q = sphere;
    q.radius[4] = -1.0f;
    expect_error(q, StatusCode::kInvalidArgument, {"query_spheres", "query 4", "radius", ">= 0"});
  }
  {
    Queries q = sphere;
    q.radius[6] = nan;
    expect_error(q, StatusCode::kInvalidArgument, {"query 6", "radius"});
  }
  {
    Queries q = sphere;
    q.x0[0] = -inf;
    expect_error(q, StatusCode::kInvalidArgument, {"query 0", "x"});
  }
  {
    Queries q = sphere;
    q.radius.pop_back();
    expect_error(q, StatusCode::kSizeMismatch, {"radius"});
  }
  {
    Queries q = point;
    q.z0[7] = nan;
    expect_error(q, StatusCode::kInvalidArgument, {"query_points", "query 7", "z"});
  }
  {
    Queries q = point;
    q.y0.push_back(0.0f);
    expect_error(q, StatusCode::kSizeMismatch, {"y"});
  }
  EXPECT_TRUE(IsError(bp.query_points(PointQueries{point.x0, point.y0, point.z0}, nullptr),
                      StatusCode::kInvalidArgument, {"out"}));
  {  // a build rejected for bad input keeps the structure: queries answer as before
    Boxes bad = b;
    bad.min_x[0] = nan;
    EXPECT_FALSE(bp.build(bad.input()).ok());
    QueryHits out = untouched;
    IMPACT_EXPECT_OK(run_query(bp, point, &out));
    EXPECT_TRUE(test::SameCsr(to_csr(out), test::reference_query(b, point)));
    IMPACT_ASSERT_OK(bp.build(b.input()));
    IMPACT_EXPECT_OK(run_query(bp, point, &out));
    EXPECT_TRUE(test::SameCsr(to_csr(out), test::reference_query(b, point)));
  }
  {  // an empty batch is fine
    QueryHits out = untouched;
    IMPACT_EXPECT_OK(bp.query_points(PointQueries{}, &out));
    EXPECT_EQ(out.offsets, std::vector<uint32_t>{0u});
    EXPECT_TRUE(out.hits.empty());
  }
}

TEST(BroadPhaseQueries, HitsAccessor) {
  Boxes b;
  b.add_box(0, 0, 0, 1, 1, 1);
  b.add_box(2, 0, 0, 3, 1, 1);
  BroadPhase bp;
  IMPACT_ASSERT_OK(bp.build(b.input()));
  const std::vector<float> x{0.5f, 1.5f, 2.5f, 1.0f}, y{0.5f, 0.5f, 0.5f, 0.5f}, z{0.5f, 0.5f, 0.5f, 0.5f};
  QueryHits h;
  IMPACT_ASSERT_OK(bp.query_points(PointQueries{x, y, z}, &h));
  ASSERT_EQ(h.size(), 4u);
  EXPECT_EQ(std::vector<uint32_t>(h.of(0).begin(), h.of(0).end()), std::vector<uint32_t>{0u});
  EXPECT_TRUE(h.of(1).empty());
  EXPECT_EQ(std::vector<uint32_t>(h.of(2).begin(), h.of(2).end()), std::vector<uint32_t>{1u});
  EXPECT_EQ(std::vector<uint32_t>(h.of(3).begin(), h.of(3).end()), std::vector<uint32_t>{0u});
}

}  // namespace
}  // namespace impact
