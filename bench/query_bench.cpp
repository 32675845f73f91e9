// Micro-benchmarks of the batched broad-phase queries (impact::BroadPhase::query_aabbs /
// query_spheres / query_points) through the public API.
//
// Stored boxes: n unit-radius spheres' boxes, uniform in a cube sized for about one
// overlapping pair per body (bench/scenes/scenes.h make_uniform_boxes, the scene of
// the pair benchmarks). The structure is built once, untimed; each iteration answers
// one batch of queries. Queries (deterministic, SplitMix64): centres uniform in the
// cube; AABB half extent 1 m (a body-sized box), sphere radius 1.5 m, points. A batch
// holds kQueries queries (kBruteForceQueries for brute force, whose every query scans
// all n boxes).
//
// Names: BM_Query<Structure><Shape>/<stored boxes>/<threads>. Counters:
// items_per_second = queries per second; ns_per_query (wall); hits_per_query.
#include <benchmark/benchmark.h>

#include <chrono>
#include <cstdint>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "bench/bench_threads.h"
#include "bench/scenes/scenes.h"
#include "impact/impact.h"

namespace {

using Clock = std::chrono::steady_clock;

constexpr uint32_t kQueries = 16384;
constexpr uint32_t kBruteForceQueries = 64;

enum class Shape { kAabb, kSphere, kPoint };

const impact::bench::UniformBoxes& stored_boxes(uint32_t n) {
  static std::map<uint32_t, impact::bench::UniformBoxes> cache;
  auto it = cache.find(n);
  if (it == cache.end())
    it = cache
             .emplace(n, impact::bench::make_uniform_boxes(n, /*radius=*/1.0f, /*pairs_per_body=*/1.0,
                                                           impact::bench::kDefaultSeed))
             .first;
  return it->second;
}

struct QuerySet {
  std::vector<float> x0, y0, z0, x1, y1, z1, radius;
};

QuerySet make_queries(float side, uint32_t count) {
  impact::bench::Rng rng(0x5eedu);
  QuerySet q;
  for (uint32_t i = 0; i < count; ++i) {
    const float x = rng.uniform() * side, y = rng.uniform() * side, z = rng.uniform() * side;
    q.x0.push_back(x), q.y0.push_back(y), q.z0.push_back(z);
    q.x1.push_back(x + 2.0f), q.y1.push_back(y + 2.0f), q.z1.push_back(z + 2.0f);
    q.radius.push_back(1.5f);
  }
  return q;
}

void run_query(benchmark::State& state, impact::BroadPhaseKind kind, Shape shape) {
  const uint32_t n = static_cast<uint32_t>(state.range(0));
  const impact::ExecConfig exec{impact::Backend::kDefault, static_cast<uint32_t>(state.range(1))};
  const impact::bench::UniformBoxes& boxes = stored_boxes(n);
  impact::BroadPhase bp(kind);
  if (impact::Status s = bp.build(boxes.view(), exec); !s.ok()) {
    state.SkipWithError(s.message().c_str());
    return;
  }
  const uint32_t count = kind == impact::BroadPhaseKind::kBruteForce ? kBruteForceQueries : kQueries;
  const QuerySet q = make_queries(boxes.side, count);
  impact::QueryHits hits;
  auto once = [&] {
    switch (shape) {
      case Shape::kAabb: return bp.query_aabbs({q.x0, q.y0, q.z0, q.x1, q.y1, q.z1}, &hits, exec);
      case Shape::kSphere: return bp.query_spheres({q.x0, q.y0, q.z0, q.radius}, &hits, exec);
      case Shape::kPoint: return bp.query_points({q.x0, q.y0, q.z0}, &hits, exec);
    }
    return impact::Status();
  };
  // One untimed call grows the scratch buffers and the output.
  if (impact::Status s = once(); !s.ok()) {
    state.SkipWithError(s.message().c_str());
    return;
  }
  const Clock::time_point t0 = Clock::now();
  for (auto _ : state) {
    const impact::Status s = once();
    if (!s.ok()) {
      state.SkipWithError(s.message().c_str());
      break;
    }
    benchmark::DoNotOptimize(hits.hits.data());
    benchmark::ClobberMemory();
  }
  const double ns = std::chrono::duration<double, std::nano>(Clock::now() - t0).count();
  const double queries = static_cast<double>(state.iterations()) * count;
  state.SetItemsProcessed(static_cast<int64_t>(queries));
  state.counters["ns_per_query"] = queries > 0 ? ns / queries : 0.0;
  state.counters["hits_per_query"] = static_cast<double>(hits.hits.size()) / count;
}

const bool kRegistered = [] {
  const std::pair<impact::BroadPhaseKind, const char*> kinds[] = {
      {impact::BroadPhaseKind::kGrid, "Grid"},
      {impact::BroadPhaseKind::kLbvh, "Lbvh"},
      {impact::BroadPhaseKind::kSweepAndPrune, "SweepAndPrune"},
      {impact::BroadPhaseKind::kBruteForce, "BruteForce"}};
  const std::pair<Shape, const char*> shapes[] = {{Shape::kAabb, "Aabb"}, {Shape::kSphere, "Sphere"},
                                                  {Shape::kPoint, "Point"}};
  for (const auto& [kind, kname] : kinds)
    for (const auto& [shape, sname] : shapes) {
      const std::string name = std::string("BM_Query") + kname + sname;
      benchmark::RegisterBenchmark(name.c_str(), run_query, kind, shape)
          ->ArgsProduct({{10000, 100000, 1000000}, impact::bench::bench_thread_counts()})
          ->UseRealTime()
          ->Unit(benchmark::kMillisecond);
    }
  return true;
}();

}  // namespace
