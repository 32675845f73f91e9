// Batched AABB / sphere / point queries (kernels/broadphase/query.h, grid_query.h,
// sap_query.h, kernels/bvh/lbvh_query.h) driven through host::BroadPhaseQuery over
// each host structure, against the independent double-precision reference of
// tests/support/query_reference.h. Answers are compared byte for byte as CSR (each
// query's hits ascending), for every structure, on random and adversarial inputs,
// with and without filters and masks, and for every backend and thread count.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "host/broadphase/broadphase.h"
#include "host/broadphase/lbvh.h"
#include "host/broadphase/query.h"
#include "host/broadphase/sap.h"
#include "host/parallel.h"
#include "kernels/broadphase/grid.h"
#include "kernels/broadphase/grid_query.h"
#include "kernels/broadphase/query.h"
#include "support/aabb_reference.h"
#include "support/kernel_views.h"
#include "support/query_reference.h"
#include "support/test_support.h"

namespace impact {
namespace {

using host::BroadPhaseQuery;
using host::Executor;
using host::QueryBatch;
using test::Boxes;
using test::Csr;
using test::QShape;
using test::Queries;
using test::random_queries;
using test::scaled;

using test::count;
using test::filter_of;
using test::serial;
using test::soa;



// Every structure over one box set. The grid comes in two flavours (levels allowed,
// levels off) and the LBVH in both code widths.
struct Structures {
  host::GridBroadPhase grid, single_grid;
  host::LbvhBroadPhase lbvh30{host::LbvhOptions{.morton_bits = 30}};
  host::LbvhBroadPhase lbvh63{host::LbvhOptions{.morton_bits = 63}};
  host::SapBroadPhase sap;
  host::BruteForceBroadPhase brute;
  const Boxes* boxes = nullptr;

  explicit Structures(const Boxes& b, const Executor& exec = serial()) : boxes(&b) {
    single_grid.set_level_fraction(0);
    grid.build(exec, soa(b), filter_of(b), count(b));
    single_grid.build(exec, soa(b), filter_of(b), count(b));
    EXPECT_TRUE(test::IsOk(lbvh30.build(exec, soa(b), filter_of(b), count(b))));
    EXPECT_TRUE(test::IsOk(lbvh63.build(exec, soa(b), filter_of(b), count(b))));
    sap.build(exec, soa(b), filter_of(b), count(b));
    brute.build(exec, soa(b), filter_of(b), count(b));
  }

  // Calls fn(name, status, csr) for every structure's answer to q.
  template <class Fn>
  void each(const Executor& exec, const Queries& q, Fn&& fn) {
    BroadPhaseQuery run;
    const QueryBatch qb = test::query_batch(q);
    auto one = [&](const char* name, auto&& call) {
      Csr c{{7u}, {3u}};  // stale content must be replaced
      const Status s = call(&c);
      fn(name, s, c);
    };
    one("grid", [&](Csr* c) { return run.query(exec, grid, qb, &c->offsets, &c->hits); });
    one("single grid", [&](Csr* c) { return run.query(exec, single_grid, qb, &c->offsets, &c->hits); });
    one("lbvh30", [&](Csr* c) { return run.query(exec, lbvh30, qb, &c->offsets, &c->hits); });
    one("lbvh63", [&](Csr* c) { return run.query(exec, lbvh63, qb, &c->offsets, &c->hits); });
    one("sap", [&](Csr* c) { return run.query(exec, sap, qb, &c->offsets, &c->hits); });
    one("brute force", [&](Csr* c) { return run.query(exec, brute, qb, &c->offsets, &c->hits); });
    one("brute force (caller boxes)", [&](Csr* c) {
      return run.query(exec, soa(*boxes), boxes->filtered() ? boxes->layer.data() : nullptr, count(*boxes), qb,
                       &c->offsets, &c->hits);
    });
  }
};

// Every structure == reference, byte for byte, on the given executors.
void check(Structures& s, const Queries& q, const std::string& what, const std::vector<test::ExecCase>& execs) {
  SCOPED_TRACE(what + " (" + test::to_string(q.shape) + ")");
  const Csr ref = test::reference_query(*s.boxes, q);
  for (const test::ExecCase& c : execs) {
    const Executor exec(c.backend, c.threads);
    s.each(exec, q, [&](const char* name, const Status& st, const Csr& got) {
      ASSERT_TRUE(test::IsOk(st)) << name << " " << test::to_string(c);
      EXPECT_TRUE(test::SameCsr(got, ref)) << name << " " << test::to_string(c);
    });
  }
}

std::vector<test::ExecCase> serial_and_default() { return {{Backend::kSerial, 1}, {Backend::kDefault, 0}}; }

// All three shapes, random queries sized `size`, with and without masks.
void check_shapes(const Boxes& b, const std::string& what, float size, uint32_t nq = 0,
                  const std::vector<test::ExecCase>& execs = serial_and_default()) {
  Structures s(b);
  if (nq == 0) nq = scaled(300);
  uint32_t seed = 1;
  for (QShape shape : {QShape::kAabb, QShape::kSphere, QShape::kPoint})
    for (int mask_kind : {0, 1}) check(s, random_queries(b, shape, nq, seed++, size, mask_kind), what, execs);
}

Boxes with_filter(Boxes b, uint32_t seed) {
  test::add_random_filter(b, seed, 0.3);
  return b;
}

// Half sizes log-uniform over [h_lo, h_hi].
Boxes log_size_boxes(uint32_t n, uint32_t seed, float h_lo, float h_hi, float side) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> logh(std::log(h_lo), std::log(h_hi));
  std::uniform_real_distribution<float> pos(-0.5f * side, 0.5f * side);
  Boxes b;
  for (uint32_t i = 0; i < n; ++i) {
    const float h = std::exp(logh(rng));
    b.add(pos(rng), pos(rng), pos(rng), h, h * 0.7f, h * 1.3f);
  }
  return b;
}

// --- random scenes ---------------------------------------------------------------------------

TEST(BroadPhaseQuery, UniformAllExecutors) {
  const Boxes b = test::uniform_boxes(scaled(5000), 1, 0.2f, 1.0f);
  check_shapes(b, "uniform", 2.0f, scaled(500));
  check_shapes(with_filter(b, 2), "uniform filtered", 2.0f, scaled(500), test::exec_cases());
}

TEST(BroadPhaseQuery, Clustered) {
  const Boxes b = test::clustered_boxes(scaled(5000), 3);
  check_shapes(b, "clustered", 1.5f);
  check_shapes(with_filter(b, 4), "clustered filtered", 1.5f);
}

TEST(BroadPhaseQuery, SizesSpanning1000xUseGridLevels) {
  const Boxes b = log_size_boxes(scaled(5000), 5, 0.005f, 5.0f, 60.0f);
  {
    Structures s(b);
    EXPECT_TRUE(s.grid.hierarchical());
    EXPECT_GE(s.grid.levels_used(), 4u);
    EXPECT_FALSE(s.single_grid.hierarchical());
  }
  check_shapes(b, "sizes over 1000x", 3.0f);
  check_shapes(with_filter(b, 6), "sizes over 1000x, filtered", 3.0f);
}

TEST(BroadPhaseQuery, TinyAndHugeScales) {
  check_shapes(test::uniform_boxes(scaled(3000), 7, 0.2f, 1.0f, 0.0f, 1e-4f), "scale 1e-4", 2e-4f);
  check_shapes(test::uniform_boxes(scaled(3000), 8, 0.2f, 1.0f, 0.0f, 1e4f), "scale 1e4", 2e4f);
}

TEST(BroadPhaseQuery, SceneOffsetBy1e6) {
  // Queries come from the scene (random_queries centres half of them on box corners).
  check_shapes(test::uniform_boxes(scaled(3000), 9, 0.2f, 1.0f, 1.0e6f), "offset +1e6", 2.0f);
  check_shapes(test::uniform_boxes(scaled(3000), 10, 0.2f, 1.0f, -1.0e6f), "offset -1e6", 2.0f);
}

TEST(BroadPhaseQuery, SparseHugeWorldHashedGrid) {
  // 1e6 m across with 1 m boxes: the grid hashes its buckets. Small queries visit a
  // few rows; queries of 1e5 m cover ~1e14 cells and must fall back to a full scan.
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> pos(-5.0e5f, 5.0e5f);
  std::uniform_real_distribution<float> jitter(-1.0f, 1.0f);
  Boxes b;
  for (uint32_t i = 0; i < scaled(2000); ++i) {
    const float x = pos(rng), y = pos(rng), z = pos(rng);
    b.add(x, y, z, 1.0f, 1.0f, 1.0f);
    if (i % 3 == 0) b.add(x + jitter(rng), y + jitter(rng), z + jitter(rng), 0.8f, 1.2f, 0.9f);
  }
  {
    Structures s(b);
    EXPECT_FALSE(s.grid.info().dense);
  }
  check_shapes(b, "sparse world, small queries", 3.0f);
  check_shapes(b, "sparse world, 1e5 m queries", 1.0e5f, scaled(60));
}

// --- adversarial ---------------------------------------------------------------------------

TEST(BroadPhaseQuery, HugeQueriesCoverEverything) {
  const Boxes b = with_filter(test::uniform_boxes(scaled(4000), 12, 0.2f, 1.0f), 12);
  Structures s(b);
  for (QShape shape : {QShape::kAabb, QShape::kSphere}) {
    Queries q;
    q.shape = shape;
    for (int i = 0; i < 40; ++i) {
      if (shape == QShape::kAabb) q.add_box(-1e6f, -1e6f, -1e6f, 1e6f, 1e6f, 1e6f);
      else q.add_sphere(0.0f, 0.0f, 0.0f, 1e6f);
      q.mask.push_back(i % 2 ? 0xffffffffu : 1u << (i % 4));
    }
    const Csr ref = test::reference_query(b, q);
    EXPECT_EQ(ref.offsets[2] - ref.offsets[1], b.size());  // mask all ones: every box
    check(s, q, "covering everything", test::exec_cases());
  }
}

TEST(BroadPhaseQuery, QueriesOutsideTheScene) {
  const Boxes b = test::uniform_boxes(scaled(2000), 13, 0.2f, 1.0f);
  Structures s(b);
  float lo[3], hi[3];
  test::box_bounds(b, lo, hi);
  Queries aabb, sphere, point;
  aabb.shape = QShape::kAabb, sphere.shape = QShape::kSphere, point.shape = QShape::kPoint;
  for (int k = 0; k < 3; ++k)
    for (float side : {-1.0f, 1.0f}) {
      float c[3] = {0, 0, 0};
      c[k] = side < 0 ? lo[k] - 5.0f : hi[k] + 5.0f;
      aabb.add_box(c[0] - 1, c[1] - 1, c[2] - 1, c[0] + 1, c[1] + 1, c[2] + 1);
      sphere.add_sphere(c[0], c[1], c[2], 4.0f);
      point.add_point(c[0], c[1], c[2]);
      // Far away, including values that overflow int64 cell arithmetic if unclamped.
      aabb.add_box(c[0] * 1e16f, c[1] * 1e16f, c[2] * 1e16f, c[0] * 1e16f + 1e12f, c[1] * 1e16f + 1e12f,
                   c[2] * 1e16f + 1e12f);
      point.add_point(c[0] * 1e16f, c[1] * 1e16f, c[2] * 1e16f);
      // (radius twice the centre's distance from the origin: the scene's half side grows
      // as cbrt(n), so a fixed 3e17 stopped reaching it at IMPACT_TEST_INTENSITY=10)
      sphere.add_sphere(c[0] * 1e16f, c[1] * 1e16f, c[2] * 1e16f, 2.0f * std::fabs(c[k]) * 1e16f);
    }
  for (const Queries* q : {&aabb, &sphere, &point}) check(s, *q, "outside", serial_and_default());
  // Points and boxes outside hit nothing; the ~1e17 m spheres reach the whole scene.
  EXPECT_EQ(test::reference_query(b, point).hits.size(), 0u);
  EXPECT_EQ(test::reference_query(b, aabb).hits.size(), 0u);
  EXPECT_EQ(test::reference_query(b, sphere).offsets[2] - test::reference_query(b, sphere).offsets[1], b.size());
}

TEST(BroadPhaseQuery, EverythingAtOnePoint) {
  Boxes b;
  for (uint32_t i = 0; i < scaled(500); ++i) b.add(-1.0f, 4.0f, 2.0f, 0, 0, 0);
  Structures s(b);
  Queries point, aabb, sphere, miss;
  point.shape = QShape::kPoint, aabb.shape = QShape::kAabb, sphere.shape = QShape::kSphere, miss.shape = QShape::kPoint;
  point.add_point(-1.0f, 4.0f, 2.0f);
  aabb.add_box(-1.0f, 4.0f, 2.0f, -1.0f, 4.0f, 2.0f);  // zero-size query box
  aabb.add_box(-2.0f, 3.0f, 1.0f, -1.0f, 4.0f, 2.0f);  // touching with its max corner
  sphere.add_sphere(-1.0f, 4.0f, 2.0f, 0.0f);          // zero radius, centre on the points
  sphere.add_sphere(2.0f, 8.0f, 2.0f, 5.0f);           // distance exactly 5 (3-4-5)
  miss.add_point(std::nextafter(-1.0f, 0.0f), 4.0f, 2.0f);
  for (const Queries* q : {&point, &aabb, &sphere, &miss}) check(s, *q, "one point", serial_and_default());
  EXPECT_EQ(test::reference_query(b, sphere).offsets[2], 2 * b.size());
  EXPECT_EQ(test::reference_query(b, miss).hits.size(), 0u);
}

TEST(BroadPhaseQuery, ZeroSizeBoxesAndPointQueriesOnALattice) {
  std::mt19937 rng(14);
  std::uniform_int_distribution<int> c(-4, 5);
  Boxes b;
  for (uint32_t i = 0; i < scaled(1500); ++i)
    b.add(static_cast<float>(c(rng)), static_cast<float>(c(rng)), static_cast<float>(c(rng)), 0, 0, 0);
  for (int i = 0; i < 20; ++i) b.add(static_cast<float>(c(rng)) + 0.5f, 0.5f, 0.5f, 0.5f, 0.5f, 0.5f);
  Structures s(b);
  Queries point, aabb, sphere;
  point.shape = QShape::kPoint, aabb.shape = QShape::kAabb, sphere.shape = QShape::kSphere;
  for (int i = 0; i < 200; ++i) {
    const float x = static_cast<float>(c(rng)), y = static_cast<float>(c(rng)), z = static_cast<float>(c(rng));
    point.add_point(x, y, z);
    aabb.add_box(x, y, z, x, y, z);
    aabb.add_box(x, y, z, x + 1.0f, y, z);  // a segment of lattice points
    sphere.add_sphere(x, y, z, i % 3 == 0 ? 1.0f : i % 3 == 1 ? std::sqrt(2.0f) : 0.0f);
  }
  for (const Queries* q : {&point, &aabb, &sphere}) check(s, *q, "lattice", serial_and_default());
  EXPECT_GT(test::reference_query(b, point).hits.size(), 100u);
}

TEST(BroadPhaseQuery, TouchingExactly) {
  // Unit boxes [i, i + 1]^3 on a lattice; queries whose faces, edges, corners lie
  // exactly on box faces, and spheres exactly tangent (3-4-5 distances) or one ulp short.
  Boxes b;
  for (int z = 0; z < 6; ++z)
    for (int y = 0; y < 6; ++y)
      for (int x = 0; x < 6; ++x)
        b.add_box(static_cast<float>(2 * x), static_cast<float>(2 * y), static_cast<float>(2 * z),
                  static_cast<float>(2 * x + 1), static_cast<float>(2 * y + 1), static_cast<float>(2 * z + 1));
  Structures s(b);
  Queries aabb, sphere, point;
  aabb.shape = QShape::kAabb, sphere.shape = QShape::kSphere, point.shape = QShape::kPoint;
  for (int x = 0; x < 11; ++x) {
    const float f = static_cast<float>(x);
    aabb.add_box(f - 1.0f, 0.0f, 0.0f, f, 0.0f, 0.0f);  // max == some box's min (x even)
    aabb.add_box(f, 1.0f, 1.0f, f + 0.5f, 1.0f, 1.0f);   // min == some box's max (x odd)
    aabb.add_box(std::nextafter(f, 100.0f), 1.0f, 1.0f, f + 0.5f, 1.0f, 1.0f);
    point.add_point(f, 1.0f, 3.0f);
    point.add_point(f, std::nextafter(1.0f, 2.0f), 3.0f);
    // The box [2x, 2x+1] x [0, 1] x [0, 1] has its corner (2x+1, 1, 1); centre at
    // (2x+1+3, 1+4, 1): distance 5 exactly.
    const float cx = static_cast<float>(2 * (x % 6) + 1 + 3);
    sphere.add_sphere(cx, 5.0f, 1.0f, 5.0f);
    sphere.add_sphere(cx, 5.0f, 1.0f, std::nextafter(5.0f, 0.0f));
    sphere.add_sphere(cx, 1.0f, 1.0f, 3.0f);  // tangent to a face
  }
  for (const Queries* q : {&aabb, &sphere, &point}) check(s, *q, "touching", serial_and_default());
  const Csr ref = test::reference_query(b, sphere);
  EXPECT_GT(ref.offsets[1] - ref.offsets[0], ref.offsets[2] - ref.offsets[1]);  // tangent hits, ulp-short misses
}

TEST(BroadPhaseQuery, ZeroOneTwoBoxes) {
  for (uint32_t n : {0u, 1u, 2u}) {
    SCOPED_TRACE("n=" + std::to_string(n));
    Boxes b;
    if (n >= 1) b.add(0, 0, 0, 1, 1, 1);
    if (n >= 2) b.add(1.5f, 0.5f, -0.5f, 1, 1, 1);
    Structures s(b);
    for (QShape shape : {QShape::kAabb, QShape::kSphere, QShape::kPoint}) {
      Queries q = random_queries(b, shape, 50, 20 + n, 2.0f);
      if (n == 0) {  // random_queries needs boxes for its frame: use fixed queries
        q = Queries{};
        q.shape = shape;
        for (int i = 0; i < 5; ++i) {
          if (shape == QShape::kAabb) q.add_box(-1, -1, -1, 1, 1, 1);
          else if (shape == QShape::kSphere) q.add_sphere(0, 0, 0, 1);
          else q.add_point(0, 0, 0);
        }
      }
      const Csr ref = test::reference_query(b, q);
      s.each(serial(), q, [&](const char* name, const Status& st, const Csr& got) {
        const bool keeps_no_copy = n == 1 && (std::string(name) == "grid" || std::string(name) == "single grid" ||
                                              std::string(name) == "sap");
        if (keeps_no_copy) {
          EXPECT_TRUE(test::IsError(st, StatusCode::kInvalidArgument, {"no searchable boxes", "1 box"})) << name;
          EXPECT_TRUE((got == Csr{{7u}, {3u}})) << name << ": output touched on error";
          return;
        }
        ASSERT_TRUE(test::IsOk(st)) << name;
        EXPECT_TRUE(test::SameCsr(got, ref)) << name;
      });
    }
  }
}

// Small trees around the LBVH's leaf-scan size (kLbvhQueryRun: subtrees of up to 64
// leaves are scanned, a tree of up to 64 leaves entirely) and the pair clusters' 32.
TEST(BroadPhaseQuery, SmallCountsAroundTheScanSizes) {
  for (uint32_t n : {3u, 7u, 8u, 9u, 31u, 32u, 33u, 63u, 64u, 65u, 127u, 128u, 129u}) {
    SCOPED_TRACE("n=" + std::to_string(n));
    const Boxes b = test::uniform_boxes(n, 40 + n, 0.3f, 1.0f);
    Structures s(b);
    for (QShape shape : {QShape::kAabb, QShape::kSphere, QShape::kPoint}) {
      const Queries q = random_queries(b, shape, 60, 60 + n, 2.0f);
      const Csr ref = test::reference_query(b, q);
      ASSERT_GT(ref.hits.size(), 0u);
      s.each(serial(), q, [&](const char* name, const Status& st, const Csr& got) {
        ASSERT_TRUE(test::IsOk(st)) << name;
        EXPECT_TRUE(test::SameCsr(got, ref)) << name;
      });
    }
  }
}

TEST(BroadPhaseQuery, EmptyBatch) {
  const Boxes b = test::uniform_boxes(100, 15, 0.2f, 1.0f);
  Structures s(b);
  Queries q;
  s.each(serial(), q, [&](const char* name, const Status& st, const Csr& got) {
    ASSERT_TRUE(test::IsOk(st)) << name;
    EXPECT_TRUE((got == Csr{{0u}, {}})) << name;
  });
}

TEST(BroadPhaseQuery, LbvhRefitAndSapIncrementalFrames) {
  // 100 frames of random motion: the LBVH refits (topology of frame 0), SAP repairs
  // its order by insertion sort; queries stay equal to the reference every frame.
  Boxes b = with_filter(test::uniform_boxes(scaled(1500), 16, 0.2f, 1.0f), 16);
  host::LbvhBroadPhase lbvh(host::LbvhOptions{.update = LbvhUpdate::kRefit});
  host::SapBroadPhase sap;
  IMPACT_ASSERT_OK(lbvh.build(serial(), soa(b), filter_of(b), count(b)));
  sap.build(serial(), soa(b), filter_of(b), count(b));
  std::mt19937 rng(16);
  // Coherent motion (few insertion-sort shifts), with a large jump every 10th frame
  // (SAP falls back to a full sort; the refitted LBVH's bounds grow loose). The boxes
  // per unit length of the sweep axis grow as n^(2/3) at this density, and so do the
  // shifts a step causes: the small step shrinks with them, so that the incremental
  // path is taken at any IMPACT_TEST_INTENSITY (at 5 with the fixed step it was not).
  const float coherent = 0.02f * std::pow(1500.0f / static_cast<float>(b.size()), 2.0f / 3.0f);
  std::normal_distribution<float> small_step(0.0f, coherent), big_step(0.0f, 1.0f);
  BroadPhaseQuery run;
  bool sap_incremental = false;
  for (int frame = 0; frame < 100; ++frame) {
    for (size_t i = 0; i < b.size(); ++i) {
      auto& step = frame % 10 == 5 ? big_step : small_step;
      const float d[3] = {step(rng), step(rng), step(rng)};
      b.min_x[i] += d[0], b.max_x[i] += d[0];
      b.min_y[i] += d[1], b.max_y[i] += d[1];
      b.min_z[i] += d[2], b.max_z[i] += d[2];
    }
    IMPACT_ASSERT_OK(lbvh.update(serial(), soa(b), filter_of(b), count(b)));
    ASSERT_FALSE(lbvh.info().rebuilt);
    sap.update(serial(), soa(b), filter_of(b), count(b));
    sap_incremental |= sap.info().tried_incremental && !sap.info().resorted;
    if (frame % 10 != 9) continue;
    for (QShape shape : {QShape::kAabb, QShape::kSphere, QShape::kPoint}) {
      const Queries q = random_queries(b, shape, 100, 100 + frame, 2.0f, 1);
      const Csr ref = test::reference_query(b, q);
      Csr got;
      IMPACT_ASSERT_OK(run.query(serial(), lbvh, test::query_batch(q), &got.offsets, &got.hits));
      EXPECT_TRUE(test::SameCsr(got, ref)) << "lbvh frame " << frame;
      IMPACT_ASSERT_OK(run.query(serial(), sap, test::query_batch(q), &got.offsets, &got.hits));
      EXPECT_TRUE(test::SameCsr(got, ref)) << "sap frame " << frame;
    }
  }
  EXPECT_TRUE(sap_incremental);
}

TEST(BroadPhaseQuery, SpatialProcessingOrderGivesTheSameBytes) {
  // Large enough batches over large enough structures run in a spatial order (LBVH:
  // Morton order, SAP: sweep-axis order); the CSR must not change, on any executor.
  const uint32_t n = std::max<uint32_t>(scaled(40000), BroadPhaseQuery::kReorderMinBoxes + 1000);
  const uint32_t nq = std::max<uint32_t>(scaled(1500), BroadPhaseQuery::kReorderMinQueries + 100);
  const Boxes b = with_filter(test::uniform_boxes(n, 19, 0.2f, 1.0f), 19);
  host::LbvhBroadPhase lbvh;
  host::SapBroadPhase sap;
  IMPACT_ASSERT_OK(lbvh.build(serial(), soa(b), filter_of(b), count(b)));
  sap.build(serial(), soa(b), filter_of(b), count(b));
  BroadPhaseQuery run;
  uint32_t seed = 190;
  for (QShape shape : {QShape::kAabb, QShape::kSphere, QShape::kPoint}) {
    // Large AABBs (~100 hits each) overflow the first per-chunk buffers: rerun path.
    const Queries q = random_queries(b, shape, nq, seed++, shape == QShape::kAabb ? 6.0f : 2.5f, 1);
    Csr ref;
    if (shape == QShape::kAabb) {
      ref = test::reference_query(b, q);
    } else {  // the brute-force kernel, itself checked against the reference above
      IMPACT_ASSERT_OK(run.query(serial(), soa(b), b.layer.data(), n, test::query_batch(q), &ref.offsets, &ref.hits));
    }
    ASSERT_GT(ref.hits.size(), 100u);
    for (const test::ExecCase& c : test::exec_cases()) {
      const Executor exec(c.backend, c.threads);
      Csr got;
      IMPACT_ASSERT_OK(run.query(exec, lbvh, test::query_batch(q), &got.offsets, &got.hits));
      EXPECT_TRUE(test::SameCsr(got, ref)) << "lbvh " << test::to_string(shape) << " " << test::to_string(c);
      IMPACT_ASSERT_OK(run.query(exec, sap, test::query_batch(q), &got.offsets, &got.hits));
      EXPECT_TRUE(test::SameCsr(got, ref)) << "sap " << test::to_string(shape) << " " << test::to_string(c);
    }
  }
}

// --- the grid's cell arithmetic --------------------------------------------------------------

TEST(BroadPhaseQuery, GridBucketArithmeticMatchesGridKeys) {
  // grid_query.cpp and grid.cpp share kernels/broadphase/grid_cells.h; this pins the query side to
  // grid_bucket_count.
  std::mt19937 rng(17);
  std::uniform_real_distribution<float> pos(-5.0e5f, 5.0e5f);
  Boxes sparse;
  for (int i = 0; i < 3000; ++i) sparse.add(pos(rng), pos(rng), pos(rng), 1.0f, 1.0f, 1.0f);
  const Boxes dense = test::uniform_boxes(3000, 18, 0.2f, 1.0f);
  for (const Boxes* b : {static_cast<const Boxes*>(&sparse), &dense}) {
    host::GridBroadPhase grid;
    grid.set_level_fraction(0);
    grid.build(serial(), soa(*b), filter_of(*b), count(*b));
    const kernels::GridView* v = grid.level_view(0);
    ASSERT_NE(v, nullptr);
    EXPECT_EQ(v->params.dense != 0, b == &dense);
    const kernels::GridBlocks blocks = kernels::grid_blocks(v->params);
    std::vector<uint32_t> bucket(b->size());
    std::vector<uint32_t> block_count(blocks.count);
    kernels::grid_bucket_count(v->params, blocks, soa(*b), bucket.data(), block_count.data(), {0, count(*b)});
    for (size_t i = 0; i < b->size(); ++i)
      ASSERT_EQ(bucket[i], kernels::grid_query_bucket(v->params, b->min_x[i], b->min_y[i], b->min_z[i]))
          << "box " << i;
    // The per-block counts are those of the buckets' high bits.
    std::vector<uint32_t> want(blocks.count, 0);
    for (uint32_t k : bucket) ++want[k >> blocks.low_bits];
    EXPECT_EQ(block_count, want);
  }
}

}  // namespace
}  // namespace impact
