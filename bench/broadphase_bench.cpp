// Micro-benchmarks of the broad phase through the public impact::BroadPhase API,
// plus one whole World::step for context.
//
// Input: n unit-radius spheres' boxes at uniformly random centres in a cube sized
// for about one overlapping pair per body (bench/scenes/scenes.h). One BroadPhase
// object is reused across iterations, so the timings are the steady state (scratch
// buffers already grown), which is what a game sees from its second frame on.
//
// Benchmark names are BM_<what>/<bodies>/<threads>; run one size with e.g.
//   impact_microbench --benchmark_filter=/10000/
// Counters: items_per_second = bodies per second; ns_per_body = wall ns per body per
// call; pairs = pairs found (per call, or per step for the world benchmark).
#include <benchmark/benchmark.h>

#include <chrono>
#include <cstdint>
#include <map>
#include <memory>
#include <vector>

#include "bench/scenes/scenes.h"
#include "impact/impact.h"

namespace {

using Clock = std::chrono::steady_clock;

// One box set per size, shared by every benchmark of that size.
const impact::bench::UniformBoxes& boxes_for(uint32_t n) {
  static std::map<uint32_t, impact::bench::UniformBoxes> cache;
  auto it = cache.find(n);
  if (it == cache.end())
    it = cache
             .emplace(n, impact::bench::make_uniform_boxes(n, /*radius=*/1.0f, /*pairs_per_body=*/1.0,
                                                           impact::bench::kDefaultSeed))
             .first;
  return it->second;
}

const impact::bench::UniformBoxes& mixed_boxes_for(uint32_t n) {
  static std::map<uint32_t, impact::bench::UniformBoxes> cache;
  auto it = cache.find(n);
  if (it == cache.end()) it = cache.emplace(n, impact::bench::make_mixed_boxes(n, impact::bench::kDefaultSeed)).first;
  return it->second;
}

void run_broad_phase(benchmark::State& state, impact::BroadPhaseKind kind, bool mixed = false) {
  const uint32_t n = static_cast<uint32_t>(state.range(0));
  const impact::ExecConfig exec{impact::Backend::kDefault, static_cast<uint32_t>(state.range(1))};
  const impact::AabbInput input = mixed ? mixed_boxes_for(n).view() : boxes_for(n).view();
  impact::BroadPhase bp(kind);
  std::vector<impact::BodyPair> pairs;
  // One untimed call grows the scratch buffers and the output.
  if (impact::Status s = bp.find_pairs(input, &pairs, exec); !s.ok()) {
    state.SkipWithError(s.message().c_str());
    return;
  }
  const Clock::time_point t0 = Clock::now();
  for (auto _ : state) {
    const impact::Status s = bp.find_pairs(input, &pairs, exec);
    if (!s.ok()) {
      state.SkipWithError(s.message().c_str());
      break;
    }
    benchmark::DoNotOptimize(pairs.data());
    benchmark::ClobberMemory();
  }
  const double ns = std::chrono::duration<double, std::nano>(Clock::now() - t0).count();
  const double body_calls = static_cast<double>(state.iterations()) * n;
  state.SetItemsProcessed(static_cast<int64_t>(body_calls));
  state.counters["ns_per_body"] = body_calls > 0 ? ns / body_calls : 0.0;
  state.counters["pairs"] = static_cast<double>(pairs.size());
}

void BM_GridBroadPhase(benchmark::State& state) {
  run_broad_phase(state, impact::BroadPhaseKind::kGrid);
}
void BM_LbvhBroadPhase(benchmark::State& state) {
  run_broad_phase(state, impact::BroadPhaseKind::kLbvh);
}
void BM_SweepAndPruneBroadPhase(benchmark::State& state) {
  run_broad_phase(state, impact::BroadPhaseKind::kSweepAndPrune);
}
// Mixed sizes (100x): the grid switches to hierarchical levels.
void BM_GridMixedSizes(benchmark::State& state) {
  run_broad_phase(state, impact::BroadPhaseKind::kGrid, true);
}
void BM_LbvhMixedSizes(benchmark::State& state) {
  run_broad_phase(state, impact::BroadPhaseKind::kLbvh, true);
}
void BM_BruteForceBroadPhase(benchmark::State& state) {
  run_broad_phase(state, impact::BroadPhaseKind::kBruteForce);
}

// Steps before timing starts: by 2 s of simulated time the top of the grid has
// landed, so timed steps see the full contact load rather than free fall.
constexpr uint32_t kWorldWarmupSteps = 120;
// Steps timed after the warm-up (steps 121..150: the pile is landing).
constexpr int kWorldTimedSteps = 30;

void BM_WorldStepBox(benchmark::State& state) {
  const uint32_t n = static_cast<uint32_t>(state.range(0));
  impact::bench::Scene scene;
  if (impact::Status s = impact::bench::make_scene("box", n, impact::bench::kDefaultSeed, &scene); !s.ok()) {
    state.SkipWithError(s.message().c_str());
    return;
  }
  impact::WorldDesc desc;
  desc.threads = static_cast<uint32_t>(state.range(1));
  std::unique_ptr<impact::World> world;
  if (impact::Status s = impact::bench::load_scene(scene, desc, &world); !s.ok()) {
    state.SkipWithError(s.message().c_str());
    return;
  }
  for (uint32_t i = 0; i < kWorldWarmupSteps; ++i) {
    if (impact::Status s = world->step(); !s.ok()) {
      state.SkipWithError(s.message().c_str());
      return;
    }
  }
  double pairs = 0.0, contacts = 0.0;
  const Clock::time_point t0 = Clock::now();
  for (auto _ : state) {
    const impact::Status s = world->step();
    if (!s.ok()) {
      state.SkipWithError(s.message().c_str());
      break;
    }
    pairs += static_cast<double>(world->last_step().pairs);
    contacts += static_cast<double>(world->last_step().contacts);
  }
  const double ns = std::chrono::duration<double, std::nano>(Clock::now() - t0).count();
  const double steps = static_cast<double>(state.iterations());
  state.SetItemsProcessed(static_cast<int64_t>(steps * n));
  state.counters["ns_per_body"] = steps > 0 ? ns / (steps * n) : 0.0;
  state.counters["pairs"] = steps > 0 ? pairs / steps : 0.0;
  state.counters["contacts"] = steps > 0 ? contacts / steps : 0.0;
}

BENCHMARK(BM_GridBroadPhase)
    ->ArgsProduct({{10000, 100000, 1000000}, {1, 2}})
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_LbvhBroadPhase)
    ->ArgsProduct({{10000, 100000, 1000000}, {1, 2}})
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);
// 1M would take ~10 s per call: a one-axis sweep meets ~n^(2/3) boxes per box in 3D.
BENCHMARK(BM_SweepAndPruneBroadPhase)
    ->ArgsProduct({{10000, 100000}, {1, 2}})
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_GridMixedSizes)
    ->ArgsProduct({{100000, 1000000}, {1, 2}})
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_LbvhMixedSizes)
    ->ArgsProduct({{100000, 1000000}, {1, 2}})
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_BruteForceBroadPhase)
    ->ArgsProduct({{10000}, {1, 2}})
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);
// A fixed step count, so every thread count times the same stretch of the same simulation.
BENCHMARK(BM_WorldStepBox)
    ->ArgsProduct({{100000}, {1, 2}})
    ->Iterations(kWorldTimedSteps)
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
