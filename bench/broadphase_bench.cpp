// Micro-benchmarks of the broad phase through the public impact::BroadPhase API,
// plus one whole World::step for context. The peer libraries (Bullet, FCL) run on
// the same boxes in bench/peers_bench.cpp, in the same executable.
//
// Scenes (bench/scenes/micro_common.h): unit-radius spheres' boxes at uniformly
// random centres in a cube sized for about one overlapping pair per body
// ("uniform", the README's scene); the same bodies in 8 gaussian blobs ("clustered",
// ~2 pairs per body); 100x mixed sizes ("mixed sizes").
//
// What is timed:
//   BM_<Grid|Lbvh>BroadPhase, ...Clustered, ...MixedSizes   from scratch, steady state:
//       one BroadPhase reused, find_pairs each call (the LBVH rebuilds every call; its
//       scratch buffers are already grown, as from a game's second frame on)
//   BM_<Grid|Lbvh>ColdStart   from scratch with a new BroadPhase per call (allocation
//       and first touch included, as the peers' from-scratch runs)
//   BM_AutoChoice/<scene>/<grid|lbvh|auto>   from scratch on the scenes behind
//       BroadPhaseKind::kAuto's rule (size spread 1x..1000x, dense and sparse, and the
//       clustered scene); counter lbvh_active: what kAuto picked (docs/broadphase.md)
//   BM_LbvhBuild / BM_LbvhRefit / BM_LbvhTraverse   the LBVH's phases apart:
//       build() from scratch; update() as a refit after one frame of motion; pairs()
//       on a fresh tree
//   BM_RadixSortMorton30   the host's parallel radix sort alone on the LBVH's 30-bit
//       Morton keys (code << 32 | index, random codes, sorted on bits [32, 62)): the
//       unsorted keys copied in untimed before each sort; counter ns_per_key
//   BM_<Grid|Lbvh>Coherent[Clustered|MixedSizes]   frame to frame: every box moves up
//       to 0.05 m per axis, then update() + pairs() (LBVH: refit policy; grid: rebuild);
//       64-frame episodes, the first move after each build untimed (micro_common.h)
//   BM_LbvhCacheCoherent[Clustered|MixedSizes]   the same walk through the LBVH's
//       kPairCache policy (fat boxes + pair cache, docs/lbvh.md); BM_LbvhCacheMargin/<m>
//       sweeps its fat margin on the uniform walk (counters: movers per frame, cached
//       pairs per exact pair, share of updates that rebuilt)
//   BM_LbvhSahVsBinned[Clustered|MixedSizes]   the LBVH tree's SAH cost against an
//       independent binned-SAH build of the same boxes (tests/support/binned_sah.h):
//       counters lbvh_sah, binned_sah, sah_ratio; the time is one sah_cost() pass
//
// Benchmark names are BM_<what>/<bodies>/<threads>; run one size with e.g.
//   impact_microbench --benchmark_filter=/10000/
// and the 1M one-thread comparison with the peers with e.g. (a filter matches the whole
// name, suffixes such as /real_time included, hence the trailing "/")
//   impact_microbench --benchmark_filter='/1000000/1/' --benchmark_repetitions=3
//       --benchmark_report_aggregates_only=true
// Counters: ms_per_frame, ns_per_body, pairs, pairs_per_second, items_per_second
// (bodies per second); see bench/scenes/micro_common.h.
//
// 10M bodies: set IMPACT_BENCH_LARGE=1 to also register the grid and LBVH cases at
// 10,000,000 bodies (scratch, phases, coherent; the thread counts of bench_threads.h:
// 1 and 2 unless IMPACT_BENCH_THREADS lists others). They need several
// GB of memory and seconds per iteration, so they are off by default and CI never
// runs them.
#include <benchmark/benchmark.h>

#include <chrono>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <map>
#include <memory>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "bench/bench_threads.h"
#include "bench/scenes/micro_common.h"
#include "bench/scenes/scenes.h"
#include "host/broadphase/lbvh.h"
#include "host/parallel.h"
#include "host/radix_sort.h"
#include "impact/impact.h"
#include "tests/support/binned_sah.h"

namespace {

using impact::bench::BoxScene;
using impact::bench::FrameTimer;
using impact::bench::report_frames;
using impact::bench::scene_boxes;
using Clock = std::chrono::steady_clock;

impact::ExecConfig exec_of(const benchmark::State& state) {
  return impact::ExecConfig{impact::Backend::kDefault, static_cast<uint32_t>(state.range(1))};
}

bool check(benchmark::State& state, const impact::Status& s) {
  if (!s.ok()) state.SkipWithError(s.message().c_str());
  return s.ok();
}

// --- from scratch ---------------------------------------------------------------------------

// find_pairs from scratch on `boxes` (n = state.range(0) of them) per iteration.
void run_broad_phase(benchmark::State& state, impact::BroadPhaseKind kind, const impact::bench::UniformBoxes& boxes) {
  const uint32_t n = static_cast<uint32_t>(state.range(0));
  const impact::ExecConfig exec = exec_of(state);
  const impact::AabbInput input = boxes.view();
  impact::BroadPhase bp(kind);
  std::vector<impact::BodyPair> pairs;
  // One untimed call grows the scratch buffers and the output.
  if (!check(state, bp.find_pairs(input, &pairs, exec))) return;
  FrameTimer timer;
  timer.start();
  for (auto _ : state) {
    if (!check(state, bp.find_pairs(input, &pairs, exec))) break;
    benchmark::DoNotOptimize(pairs.data());
    benchmark::ClobberMemory();
  }
  timer.stop();
  report_frames(state, n, timer, pairs.size());
  state.counters["lbvh_active"] = bp.active_kind() == impact::BroadPhaseKind::kLbvh ? 1.0 : 0.0;
}

void run_broad_phase(benchmark::State& state, impact::BroadPhaseKind kind, BoxScene scene) {
  run_broad_phase(state, kind, scene_boxes(scene, static_cast<uint32_t>(state.range(0))));
}

// A new BroadPhase per call: the first frame's cost, allocations included.
void run_cold_start(benchmark::State& state, impact::BroadPhaseKind kind) {
  const uint32_t n = static_cast<uint32_t>(state.range(0));
  const impact::ExecConfig exec = exec_of(state);
  const impact::AabbInput input = scene_boxes(BoxScene::kUniform, n).view();
  FrameTimer timer;
  size_t found = 0;
  for (auto _ : state) {
    auto bp = std::make_unique<impact::BroadPhase>(kind);
    std::vector<impact::BodyPair> pairs;
    timer.start();
    const bool ok = check(state, bp->find_pairs(input, &pairs, exec));
    state.SetIterationTime(timer.stop());
    if (!ok) break;
    found = pairs.size();
    benchmark::DoNotOptimize(pairs.data());
  }
  report_frames(state, n, timer, found);
}

void BM_GridBroadPhase(benchmark::State& state) {
  run_broad_phase(state, impact::BroadPhaseKind::kGrid, BoxScene::kUniform);
}
void BM_LbvhBroadPhase(benchmark::State& state) {
  run_broad_phase(state, impact::BroadPhaseKind::kLbvh, BoxScene::kUniform);
}
void BM_SweepAndPruneBroadPhase(benchmark::State& state) {
  run_broad_phase(state, impact::BroadPhaseKind::kSweepAndPrune, BoxScene::kUniform);
}
void BM_GridClustered(benchmark::State& state) {
  run_broad_phase(state, impact::BroadPhaseKind::kGrid, BoxScene::kClustered);
}
void BM_LbvhClustered(benchmark::State& state) {
  run_broad_phase(state, impact::BroadPhaseKind::kLbvh, BoxScene::kClustered);
}
// Mixed sizes (100x): the grid switches to hierarchical levels.
void BM_GridMixedSizes(benchmark::State& state) {
  run_broad_phase(state, impact::BroadPhaseKind::kGrid, BoxScene::kMixed);
}
void BM_LbvhMixedSizes(benchmark::State& state) {
  run_broad_phase(state, impact::BroadPhaseKind::kLbvh, BoxScene::kMixed);
}
void BM_BruteForceBroadPhase(benchmark::State& state) {
  run_broad_phase(state, impact::BroadPhaseKind::kBruteForce, BoxScene::kUniform);
}
void BM_GridColdStart(benchmark::State& state) {
  run_cold_start(state, impact::BroadPhaseKind::kGrid);
}
void BM_LbvhColdStart(benchmark::State& state) {
  run_cold_start(state, impact::BroadPhaseKind::kLbvh);
}

// --- the automatic choice's scenes -----------------------------------------------------------

// Size spread (largest / smallest box, log-uniform) and sparsity (per axis) of the
// BM_AutoChoice scenes (make_size_spread_boxes); ratio 0 stands for the clustered scene.
struct SpreadScene {
  const char* name;
  double ratio, sparsity;
};
constexpr SpreadScene kSpreadScenes[] = {{"1x_dense", 1, 1},       {"4x_dense", 4, 1},
                                         {"16x_dense", 16, 1},     {"1000x_dense", 1000, 1},
                                         {"1x_sparse", 1, 10},     {"16x_sparse", 16, 10},
                                         {"1000x_sparse", 1000, 10}, {"clustered", 0, 0}};

const impact::bench::UniformBoxes& spread_boxes(const SpreadScene& sc, uint32_t n) {
  static std::map<std::pair<std::string, uint32_t>, impact::bench::UniformBoxes> cache;
  const std::pair<std::string, uint32_t> key{sc.name, n};
  if (auto it = cache.find(key); it != cache.end()) return it->second;
  if (sc.ratio == 0) return scene_boxes(BoxScene::kClustered, n);
  return cache
      .emplace(key, impact::bench::make_size_spread_boxes(n, sc.ratio, sc.sparsity, impact::bench::kDefaultSeed))
      .first->second;
}

// BM_AutoChoice/<scene>/<grid|lbvh|auto>/<bodies>/<threads>: the table behind
// kAuto's rule; counter lbvh_active says what kAuto picked.
const int kAutoChoiceRegistered = [] {
  const std::pair<const char*, impact::BroadPhaseKind> kinds[] = {{"grid", impact::BroadPhaseKind::kGrid},
                                                                  {"lbvh", impact::BroadPhaseKind::kLbvh},
                                                                  {"auto", impact::BroadPhaseKind::kAuto}};
  for (const SpreadScene& sc : kSpreadScenes) {
    for (const auto& [kind_name, kind] : kinds) {
      const std::string name = std::string("BM_AutoChoice/") + sc.name + "/" + kind_name;
      benchmark::RegisterBenchmark(name.c_str(),
                                   [sc, kind](benchmark::State& state) {
                                     run_broad_phase(state, kind,
                                                     spread_boxes(sc, static_cast<uint32_t>(state.range(0))));
                                   })
          ->ArgsProduct({{10000, 100000, 1000000}, {1}})
          ->UseRealTime()
          ->Unit(benchmark::kMillisecond);
    }
  }
  return 0;
}();

// --- far outliers ----------------------------------------------------------------------------

// BM_Outliers/<count>_at_<distance>/<grid|lbvh|auto>/<bodies>/<threads>: the uniform
// scene with `count` of its boxes (every n/count-th, 0: none) moved, unchanged in size,
// to `distance` m from the origin along alternating axis directions (the outliers
// overlap each other in pairs; 1e18 m is the largest coordinate the API accepts). The grid's extent used to follow them (docs/broadphase.md).
const impact::bench::UniformBoxes& outlier_boxes(uint32_t n, uint32_t count, double distance) {
  static std::map<std::tuple<uint32_t, uint32_t, double>, impact::bench::UniformBoxes> cache;
  const auto key = std::make_tuple(n, count, distance);
  if (auto it = cache.find(key); it != cache.end()) return it->second;
  impact::bench::UniformBoxes b = scene_boxes(BoxScene::kUniform, n);
  for (uint32_t j = 0; j < count; ++j) {
    const uint32_t i = static_cast<uint32_t>(static_cast<uint64_t>(j) * n / count);
    const float d = static_cast<float>((j / 2) % 2 == 0 ? distance : -distance);
    const int axis = static_cast<int>((j / 4) % 3);
    float* lo[3] = {&b.min_x[i], &b.min_y[i], &b.min_z[i]};
    float* hi[3] = {&b.max_x[i], &b.max_y[i], &b.max_z[i]};
    for (int k = 0; k < 3; ++k) {
      const float half = 0.5f * (*hi[k] - *lo[k]);
      const float c = k == axis ? d : 0.0f;
      *lo[k] = c - half;
      *hi[k] = c + half + (j % 2 == 0 ? 0.0f : half);  // outliers j, j+1 overlap
    }
  }
  return cache.emplace(key, std::move(b)).first->second;
}

const int kOutliersRegistered = [] {
  const std::pair<const char*, impact::BroadPhaseKind> kinds[] = {{"grid", impact::BroadPhaseKind::kGrid},
                                                                  {"lbvh", impact::BroadPhaseKind::kLbvh},
                                                                  {"auto", impact::BroadPhaseKind::kAuto}};
  const uint32_t counts[] = {0, 1, 10};
  const std::pair<const char*, double> distances[] = {{"1e9", 1e9}, {"1e12", 1e12}, {"1e18", 1e18}};
  for (uint32_t count : counts) {
    for (const auto& [dist_name, dist] : distances) {
      if (count == 0 && dist != 1e9) continue;  // no outlier: one row
      for (const auto& [kind_name, kind] : kinds) {
        const std::string name = "BM_Outliers/" + std::to_string(count) + "_at_" + dist_name + "/" + kind_name;
        benchmark::RegisterBenchmark(name.c_str(),
                                     [count, dist, kind](benchmark::State& state) {
                                       run_broad_phase(state, kind,
                                                       outlier_boxes(static_cast<uint32_t>(state.range(0)),
                                                                     count, dist));
                                     })
            ->ArgsProduct({{10000, 100000}, {1}})
            ->UseRealTime()
            ->Unit(benchmark::kMillisecond);
      }
    }
  }
  return 0;
}();

// --- LBVH phases ----------------------------------------------------------------------------

impact::BroadPhaseOptions lbvh_refit_options() {
  impact::BroadPhaseOptions o;
  o.kind = impact::BroadPhaseKind::kLbvh;
  o.lbvh_update = impact::LbvhUpdate::kRefit;
  // Episodes restart with a build every kCoherentFrames frames; never rebuild inside one.
  o.lbvh_max_refits = std::numeric_limits<uint32_t>::max();
  return o;
}

// Pairs of bp's current structure (untimed; for the pairs counter of phase benchmarks).
size_t pair_count(benchmark::State& state, impact::BroadPhase& bp, const impact::ExecConfig& exec) {
  std::vector<impact::BodyPair> pairs;
  return check(state, bp.pairs(&pairs, exec)) ? pairs.size() : 0;
}

void BM_LbvhBuild(benchmark::State& state) {
  const uint32_t n = static_cast<uint32_t>(state.range(0));
  const impact::ExecConfig exec = exec_of(state);
  const impact::AabbInput input = scene_boxes(BoxScene::kUniform, n).view();
  impact::BroadPhase bp(impact::BroadPhaseKind::kLbvh);
  if (!check(state, bp.build(input, exec))) return;
  FrameTimer timer;
  timer.start();
  for (auto _ : state) {
    if (!check(state, bp.build(input, exec))) break;
    benchmark::ClobberMemory();
  }
  timer.stop();
  report_frames(state, n, timer, pair_count(state, bp, exec), /*pair_rate=*/false);
}

void BM_RadixSortMorton30(benchmark::State& state) {
  const uint32_t n = static_cast<uint32_t>(state.range(0));
  const impact::host::Executor exec(impact::Backend::kDefault, static_cast<uint32_t>(state.range(1)));
  std::vector<uint64_t> keys(n), work(n);
  impact::bench::Rng rng(0x9e3779b97f4a7c15ull);  // a fixed, reproducible key set
  for (uint32_t i = 0; i < n; ++i) keys[i] = ((rng.next_u64() & ((uint64_t{1} << 30) - 1)) << 32) | i;
  impact::host::RadixSorter sorter;
  work = keys;
  sorter.sort(exec, work.data(), n, 32, 62);  // grows the sorter's scratch
  double seconds = 0.0;
  for (auto _ : state) {
    std::memcpy(work.data(), keys.data(), sizeof(uint64_t) * n);
    const auto t0 = std::chrono::steady_clock::now();
    sorter.sort(exec, work.data(), n, 32, 62);
    const double dt = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    state.SetIterationTime(dt);
    seconds += dt;
    benchmark::DoNotOptimize(work.data());
  }
  const double sorts = static_cast<double>(state.iterations());
  state.SetItemsProcessed(static_cast<int64_t>(sorts * n));
  state.counters["ns_per_key"] = sorts > 0 && n > 0 ? seconds * 1e9 / (sorts * n) : 0.0;
}

void BM_LbvhTraverse(benchmark::State& state) {
  const uint32_t n = static_cast<uint32_t>(state.range(0));
  const impact::ExecConfig exec = exec_of(state);
  impact::BroadPhase bp(impact::BroadPhaseKind::kLbvh);
  if (!check(state, bp.build(scene_boxes(BoxScene::kUniform, n).view(), exec))) return;
  std::vector<impact::BodyPair> pairs;
  if (!check(state, bp.pairs(&pairs, exec))) return;
  FrameTimer timer;
  timer.start();
  for (auto _ : state) {
    if (!check(state, bp.pairs(&pairs, exec))) break;
    benchmark::DoNotOptimize(pairs.data());
    benchmark::ClobberMemory();
  }
  timer.stop();
  report_frames(state, n, timer, pairs.size());
}

// --- frame to frame -------------------------------------------------------------------------

// update() (+ pairs() when with_pairs) per frame on bp, built at each episode's frame 0.
void run_coherent_api(benchmark::State& state, impact::BroadPhase& bp, BoxScene scene, bool with_pairs) {
  const uint32_t n = static_cast<uint32_t>(state.range(0));
  const impact::ExecConfig exec = exec_of(state);
  std::vector<impact::BodyPair> pairs;
  const bool ok = impact::bench::run_coherent(
      state, scene_boxes(scene, n),
      [&](const impact::bench::UniformBoxes& b) {
        return check(state, bp.build(b.view(), exec)) && check(state, bp.pairs(&pairs, exec));
      },
      [&](const impact::bench::UniformBoxes& b) -> int64_t {
        if (!check(state, bp.update(b.view(), exec))) return -1;
        if (!with_pairs) return 0;
        if (!check(state, bp.pairs(&pairs, exec))) return -1;
        benchmark::DoNotOptimize(pairs.data());
        return static_cast<int64_t>(pairs.size());
      },
      with_pairs);
  // Refit alone finds no pairs: report those of the last refitted tree.
  if (ok && !with_pairs) state.counters["pairs"] = static_cast<double>(pair_count(state, bp, exec));
}

void BM_LbvhRefit(benchmark::State& state) {
  impact::BroadPhase bp(lbvh_refit_options());
  run_coherent_api(state, bp, BoxScene::kUniform, /*with_pairs=*/false);
}

void coherent_grid(benchmark::State& state, BoxScene scene) {
  impact::BroadPhase bp(impact::BroadPhaseKind::kGrid);
  run_coherent_api(state, bp, scene, /*with_pairs=*/true);
}
void coherent_lbvh(benchmark::State& state, BoxScene scene) {
  impact::BroadPhase bp(lbvh_refit_options());
  run_coherent_api(state, bp, scene, /*with_pairs=*/true);
}
void coherent_lbvh_cache(benchmark::State& state, BoxScene scene) {
  impact::BroadPhaseOptions o;
  o.kind = impact::BroadPhaseKind::kLbvh;
  o.lbvh_update = impact::LbvhUpdate::kPairCache;
  impact::BroadPhase bp(o);
  run_coherent_api(state, bp, scene, /*with_pairs=*/true);
}
void BM_LbvhCacheCoherent(benchmark::State& state) { coherent_lbvh_cache(state, BoxScene::kUniform); }
void BM_LbvhCacheCoherentClustered(benchmark::State& state) { coherent_lbvh_cache(state, BoxScene::kClustered); }
void BM_LbvhCacheCoherentMixedSizes(benchmark::State& state) { coherent_lbvh_cache(state, BoxScene::kMixed); }

// BM_LbvhCacheMargin/<fat margin>/<bodies>/<threads>: the kPairCache knob's cost on
// the uniform coherent walk, through the host class so the counters can say why:
// movers_per_frame (boxes re-queried, over all frames), cached_per_pair (fat pairs held per exact
// pair), rebuild_share (updates that rebuilt instead).
void run_cache_margin(benchmark::State& state, float margin) {
  const uint32_t n = static_cast<uint32_t>(state.range(0));
  const impact::host::Executor exec(impact::Backend::kDefault, static_cast<uint32_t>(state.range(1)));
  impact::host::LbvhOptions o;
  o.update = impact::LbvhUpdate::kPairCache;
  o.fat_margin = margin;
  o.max_refits = std::numeric_limits<uint32_t>::max();
  impact::host::LbvhBroadPhase lbvh(o);
  impact::host::Buffer<impact::kernels::Pair> pairs;
  auto soa = [](const impact::bench::UniformBoxes& b) {
    return impact::kernels::AabbSoA{b.min_x.data(), b.min_y.data(), b.min_z.data(),
                                    b.max_x.data(), b.max_y.data(), b.max_z.data()};
  };
  const impact::kernels::PairFilter none{nullptr, nullptr, nullptr};
  double movers = 0.0, cached = 0.0, exact = 0.0, rebuilds = 0.0, frames = 0.0;
  const bool ok = impact::bench::run_coherent(
      state, scene_boxes(BoxScene::kUniform, n),
      [&](const impact::bench::UniformBoxes& b) {
        return check(state, lbvh.find_pairs(exec, soa(b), none, n, &pairs));
      },
      [&](const impact::bench::UniformBoxes& b) -> int64_t {
        if (!check(state, lbvh.find_pairs(exec, soa(b), none, n, &pairs))) return -1;
        const impact::host::LbvhInfo& info = lbvh.info();
        movers += info.rebuilt || !info.cached ? 0.0 : info.movers;
        rebuilds += info.rebuilt ? 1.0 : 0.0;
        cached += static_cast<double>(info.cached_pairs);
        exact += static_cast<double>(pairs.size());
        frames += 1.0;
        return static_cast<int64_t>(pairs.size());
      });
  if (!ok || frames == 0.0) return;
  state.counters["movers_per_frame"] = movers / frames;
  state.counters["cached_per_pair"] = exact > 0.0 ? cached / exact : 0.0;
  state.counters["rebuild_share"] = rebuilds / frames;
}

void BM_GridCoherent(benchmark::State& state) { coherent_grid(state, BoxScene::kUniform); }
void BM_LbvhCoherent(benchmark::State& state) { coherent_lbvh(state, BoxScene::kUniform); }
void BM_GridCoherentClustered(benchmark::State& state) { coherent_grid(state, BoxScene::kClustered); }
void BM_LbvhCoherentClustered(benchmark::State& state) { coherent_lbvh(state, BoxScene::kClustered); }
void BM_GridCoherentMixedSizes(benchmark::State& state) { coherent_grid(state, BoxScene::kMixed); }
void BM_LbvhCoherentMixedSizes(benchmark::State& state) { coherent_lbvh(state, BoxScene::kMixed); }

// --- tree quality ---------------------------------------------------------------------------

// The binned-SAH reference cost of one scene and size (the build takes ~1-2 s at 1M, so
// it is done once per run and kept).
double binned_sah_of(BoxScene scene, uint32_t n) {
  static std::map<std::pair<int, uint32_t>, double> cache;
  const std::pair<int, uint32_t> key{static_cast<int>(scene), n};
  if (auto it = cache.find(key); it != cache.end()) return it->second;
  const impact::bench::UniformBoxes& b = scene_boxes(scene, n);
  const impact::test::BinnedBvh bvh =
      impact::test::build_binned_sah<32>({b.min_x, b.min_y, b.min_z, b.max_x, b.max_y, b.max_z});
  return cache.emplace(key, impact::test::sah_cost(bvh)).first->second;
}

void run_sah_vs_binned(benchmark::State& state, BoxScene scene) {
  const uint32_t n = static_cast<uint32_t>(state.range(0));
  const impact::bench::UniformBoxes& b = scene_boxes(scene, n);
  const impact::host::Executor exec(impact::Backend::kDefault, static_cast<uint32_t>(state.range(1)));
  impact::host::LbvhBroadPhase lbvh;
  impact::host::Buffer<impact::kernels::Pair> pairs;
  const impact::kernels::AabbSoA soa{b.min_x.data(), b.min_y.data(), b.min_z.data(),
                                     b.max_x.data(), b.max_y.data(), b.max_z.data()};
  if (!check(state, lbvh.find_pairs(exec, soa, {nullptr, nullptr, nullptr}, n, &pairs))) return;
  const double binned = binned_sah_of(scene, n);
  double sah = 0.0;
  for (auto _ : state) {
    sah = lbvh.sah_cost(exec);
    benchmark::DoNotOptimize(sah);
  }
  state.counters["lbvh_sah"] = sah;
  state.counters["binned_sah"] = binned;
  state.counters["sah_ratio"] = binned > 0.0 ? sah / binned : 0.0;
  state.counters["morton_bits"] = lbvh.info().morton_bits;
}
void BM_LbvhSahVsBinned(benchmark::State& state) { run_sah_vs_binned(state, BoxScene::kUniform); }
void BM_LbvhSahVsBinnedClustered(benchmark::State& state) { run_sah_vs_binned(state, BoxScene::kClustered); }
void BM_LbvhSahVsBinnedMixedSizes(benchmark::State& state) { run_sah_vs_binned(state, BoxScene::kMixed); }

// --- whole step -----------------------------------------------------------------------------

// Steps before timing starts: by 2 s of simulated time the top of the grid has
// landed, so timed steps see the full contact load rather than free fall.
constexpr uint32_t kWorldWarmupSteps = 120;
// Steps timed after the warm-up (steps 121..150: the pile is landing).
constexpr int kWorldTimedSteps = 30;

void BM_WorldStepBox(benchmark::State& state) {
  const uint32_t n = static_cast<uint32_t>(state.range(0));
  impact::bench::Scene scene;
  if (!check(state, impact::bench::make_scene("box", n, impact::bench::kDefaultSeed, &scene))) return;
  impact::WorldDesc desc;
  desc.threads = static_cast<uint32_t>(state.range(1));
  std::unique_ptr<impact::World> world;
  if (!check(state, impact::bench::load_scene(scene, desc, &world))) return;
  for (uint32_t i = 0; i < kWorldWarmupSteps; ++i)
    if (!check(state, world->step())) return;
  double pairs = 0.0, contacts = 0.0;
  const Clock::time_point t0 = Clock::now();
  for (auto _ : state) {
    if (!check(state, world->step())) break;
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

// --- registration ---------------------------------------------------------------------------

constexpr int64_t k10k = 10000, k100k = 100000, k1M = 1000000, k10M = 10000000;

BENCHMARK(BM_GridBroadPhase)->ArgsProduct({{k10k, k100k, k1M}, impact::bench::bench_thread_counts()})->UseRealTime()->Unit(benchmark::kMillisecond);
BENCHMARK(BM_LbvhBroadPhase)->ArgsProduct({{k10k, k100k, k1M}, impact::bench::bench_thread_counts()})->UseRealTime()->Unit(benchmark::kMillisecond);
// 1M would take ~10 s per call: a one-axis sweep meets ~n^(2/3) boxes per box in 3D.
BENCHMARK(BM_SweepAndPruneBroadPhase)
    ->ArgsProduct({{k10k, k100k}, impact::bench::bench_thread_counts()})
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_GridClustered)->ArgsProduct({{k10k, k100k, k1M}, impact::bench::bench_thread_counts()})->UseRealTime()->Unit(benchmark::kMillisecond);
BENCHMARK(BM_LbvhClustered)->ArgsProduct({{k10k, k100k, k1M}, impact::bench::bench_thread_counts()})->UseRealTime()->Unit(benchmark::kMillisecond);
BENCHMARK(BM_GridMixedSizes)->ArgsProduct({{k100k, k1M}, impact::bench::bench_thread_counts()})->UseRealTime()->Unit(benchmark::kMillisecond);
BENCHMARK(BM_LbvhMixedSizes)->ArgsProduct({{k100k, k1M}, impact::bench::bench_thread_counts()})->UseRealTime()->Unit(benchmark::kMillisecond);
BENCHMARK(BM_BruteForceBroadPhase)->ArgsProduct({{k10k}, impact::bench::bench_thread_counts()})->UseRealTime()->Unit(benchmark::kMillisecond);
BENCHMARK(BM_GridColdStart)->ArgsProduct({{k10k, k100k, k1M}, impact::bench::bench_thread_counts()})->UseManualTime()->Unit(benchmark::kMillisecond);
BENCHMARK(BM_LbvhColdStart)->ArgsProduct({{k10k, k100k, k1M}, impact::bench::bench_thread_counts()})->UseManualTime()->Unit(benchmark::kMillisecond);

BENCHMARK(BM_LbvhBuild)->ArgsProduct({{k10k, k100k, k1M}, impact::bench::bench_thread_counts()})->UseRealTime()->Unit(benchmark::kMillisecond);
BENCHMARK(BM_LbvhRefit)->ArgsProduct({{k10k, k100k, k1M}, impact::bench::bench_thread_counts()})->UseManualTime()->Unit(benchmark::kMillisecond);
BENCHMARK(BM_LbvhTraverse)->ArgsProduct({{k10k, k100k, k1M}, impact::bench::bench_thread_counts()})->UseRealTime()->Unit(benchmark::kMillisecond);
BENCHMARK(BM_RadixSortMorton30)->ArgsProduct({{k10k, k100k, k1M}, impact::bench::bench_thread_counts()})->UseManualTime()->Unit(benchmark::kMillisecond);

BENCHMARK(BM_GridCoherent)->ArgsProduct({{k10k, k100k, k1M}, impact::bench::bench_thread_counts()})->UseManualTime()->Unit(benchmark::kMillisecond);
BENCHMARK(BM_LbvhCoherent)->ArgsProduct({{k10k, k100k, k1M}, impact::bench::bench_thread_counts()})->UseManualTime()->Unit(benchmark::kMillisecond);
// The pair cache's cost grows over an episode (boxes drift out of their fat boxes, and
// the movers add up to a rebuild), so these time whole episodes: every timed frame of
// one episode, whatever --benchmark_min_time says.
constexpr int64_t kEpisodeFrames = static_cast<int64_t>(impact::bench::kCoherentFrames - impact::bench::kCoherentWarmupFrames);
BENCHMARK(BM_LbvhCacheCoherent)
    ->ArgsProduct({{k10k, k100k, k1M}, impact::bench::bench_thread_counts()})
    ->Iterations(kEpisodeFrames)
    ->UseManualTime()
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_LbvhCacheCoherentClustered)
    ->ArgsProduct({{k10k, k100k, k1M}, impact::bench::bench_thread_counts()})
    ->Iterations(kEpisodeFrames)
    ->UseManualTime()
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_LbvhCacheCoherentMixedSizes)
    ->ArgsProduct({{k100k, k1M}, impact::bench::bench_thread_counts()})
    ->Iterations(kEpisodeFrames)
    ->UseManualTime()
    ->Unit(benchmark::kMillisecond);
const int kCacheMarginRegistered = [] {
  for (const char* m : {"0.02", "0.05", "0.1", "0.2", "0.4"}) {
    const float margin = std::strtof(m, nullptr);
    benchmark::RegisterBenchmark((std::string("BM_LbvhCacheMargin/") + m).c_str(),
                                 [margin](benchmark::State& state) { run_cache_margin(state, margin); })
        ->ArgsProduct({{k10k, k100k, k1M}, {1}})
        ->Iterations(kEpisodeFrames)
        ->UseManualTime()
        ->Unit(benchmark::kMillisecond);
  }
  return 0;
}();
BENCHMARK(BM_GridCoherentClustered)
    ->ArgsProduct({{k10k, k100k, k1M}, impact::bench::bench_thread_counts()})
    ->UseManualTime()
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_LbvhCoherentClustered)
    ->ArgsProduct({{k10k, k100k, k1M}, impact::bench::bench_thread_counts()})
    ->UseManualTime()
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_GridCoherentMixedSizes)
    ->ArgsProduct({{k100k, k1M}, impact::bench::bench_thread_counts()})
    ->UseManualTime()
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_LbvhCoherentMixedSizes)
    ->ArgsProduct({{k100k, k1M}, impact::bench::bench_thread_counts()})
    ->UseManualTime()
    ->Unit(benchmark::kMillisecond);

// Tree quality: one thread (the cost does not depend on it); the reference build runs
// once per scene and size, outside the timing.
BENCHMARK(BM_LbvhSahVsBinned)->ArgsProduct({{k100k, k1M}, {1}})->Iterations(3)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_LbvhSahVsBinnedClustered)->ArgsProduct({{k100k, k1M}, {1}})->Iterations(3)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_LbvhSahVsBinnedMixedSizes)->ArgsProduct({{k100k, k1M}, {1}})->Iterations(3)->Unit(benchmark::kMillisecond);

// A fixed step count, so every thread count times the same stretch of the same simulation.
BENCHMARK(BM_WorldStepBox)
    ->ArgsProduct({{100000}, impact::bench::bench_thread_counts()})
    ->Iterations(kWorldTimedSteps)
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);

// 10M bodies, grid and LBVH, only with IMPACT_BENCH_LARGE=1 (see the top of this file).
// A handful of iterations: each takes seconds.
void register_large() {
  const char* v = std::getenv("IMPACT_BENCH_LARGE");
  if (v == nullptr || std::strcmp(v, "1") != 0) return;
  struct Family {
    const char* name;
    void (*fn)(benchmark::State&);
    bool manual_time;
  };
  const Family families[] = {
      {"BM_GridBroadPhase", BM_GridBroadPhase, false}, {"BM_LbvhBroadPhase", BM_LbvhBroadPhase, false},
      {"BM_GridClustered", BM_GridClustered, false},   {"BM_LbvhClustered", BM_LbvhClustered, false},
      {"BM_GridMixedSizes", BM_GridMixedSizes, false}, {"BM_LbvhMixedSizes", BM_LbvhMixedSizes, false},
      {"BM_LbvhBuild", BM_LbvhBuild, false},           {"BM_LbvhRefit", BM_LbvhRefit, true},
      {"BM_LbvhTraverse", BM_LbvhTraverse, false},     {"BM_GridCoherent", BM_GridCoherent, true},
      {"BM_LbvhCoherent", BM_LbvhCoherent, true},     {"BM_LbvhCacheCoherent", BM_LbvhCacheCoherent, true},
  };
  for (const Family& f : families) {
    benchmark::internal::Benchmark* b = benchmark::RegisterBenchmark(f.name, f.fn);
    b->ArgsProduct({{k10M}, impact::bench::bench_thread_counts()})->Iterations(3)->Unit(benchmark::kMillisecond);
    if (f.manual_time)
      b->UseManualTime();
    else
      b->UseRealTime();
  }
}

}  // namespace

int main(int argc, char** argv) {
  register_large();
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
