// Shared pieces of the Google Benchmark micro-benchmarks (bench/broadphase_bench.cpp,
// bench/peers_bench.cpp): one cached box set per (scene, size), the counters every
// broad-phase benchmark reports, and the frame-to-frame (coherent) driver, so our
// structures and the peer libraries are timed on the same boxes the same way.
//
// Counters (per benchmark run):
//   ms_per_frame      wall ms per timed call (one frame)
//   cpu_ms_per_frame  process CPU ms per timed call, all threads together: on a shared
//                     machine, a one-thread figure that other processes inflate less
//   ns_per_body       wall ns per body per call
//   pairs             pairs found by the last call
//   pairs_per_second  pairs * calls / wall seconds (left out where a benchmark times a
//                     phase that produces no pairs: LBVH build, LBVH refit)
//   items_per_second  bodies per second
//
// Coherent motion: run_coherent() drives a BoxWalk (bench/scenes/scenes.h): every
// box's centre takes a random step of up to kCoherentStep m per axis per frame,
// reflected at the scene's bounds. A structure is built once (untimed) at frame 0,
// updated once more untimed (frame 1: the first move after creation, where e.g.
// Bullet's tree replaces every exact creation box by an enlarged one, a one-off cost a
// game pays once per object), then updated frame after frame (timed, one iteration
// per frame). After kCoherentFrames frames the walk restarts from frame 0 with an
// untimed rebuild, so a long run measures the same episode again instead of an ever
// older tree. Only the update is timed (manual time): the walk itself is not.
#pragma once

#include <benchmark/benchmark.h>

#include <chrono>
#include <cstdint>
#include <ctime>
#include <map>
#include <optional>
#include <utility>
#include <vector>

#include "bench/scenes/scenes.h"
#include "impact/impact.h"

namespace impact::bench {

using MicroClock = std::chrono::steady_clock;

/// Box sets of the micro-benchmarks, all built around unit-size bodies at about one
/// overlapping pair per body.
enum class BoxScene : int {
  kUniform = 0,    ///< make_uniform_boxes(n, 1 m, 1 pair per body): the README's scene
  kClustered = 1,  ///< make_clustered_boxes(n, 2 pairs per body)
  kMixed = 2,      ///< make_mixed_boxes(n): 100x size spread
};

/// Pairs per body of the clustered scene (averaged over bodies; ~2.8x at a blob's core).
inline constexpr double kClusteredPairsPerBody = 2.0;

/// The boxes of one scene and size, built on first use and kept for the whole run
/// (so every benchmark of that scene and size, ours or a peer's, sees the same bytes).
inline const UniformBoxes& scene_boxes(BoxScene scene, uint32_t n) {
  static std::map<std::pair<int, uint32_t>, UniformBoxes> cache;
  const std::pair<int, uint32_t> key{static_cast<int>(scene), n};
  auto it = cache.find(key);
  if (it != cache.end()) return it->second;
  UniformBoxes b;
  switch (scene) {
    case BoxScene::kUniform: b = make_uniform_boxes(n, /*radius=*/1.0f, /*pairs_per_body=*/1.0, kDefaultSeed); break;
    case BoxScene::kClustered: b = make_clustered_boxes(n, kClusteredPairsPerBody, kDefaultSeed); break;
    case BoxScene::kMixed: b = make_mixed_boxes(n, kDefaultSeed); break;
  }
  return cache.emplace(key, std::move(b)).first->second;
}

/// Pairs our grid finds on `boxes` (all threads): the count the peers are checked
/// against. The grid is itself checked against a double-precision oracle in tests/.
inline uint64_t reference_pair_count(const UniformBoxes& boxes) {
  BroadPhase bp(BroadPhaseKind::kGrid);
  std::vector<BodyPair> pairs;
  if (!bp.find_pairs(boxes.view(), &pairs).ok()) return 0;
  return pairs.size();
}

/// CPU seconds used by this process so far, all threads.
inline double process_cpu_seconds() {
#if defined(CLOCK_PROCESS_CPUTIME_ID)
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
#else
  return static_cast<double>(std::clock()) / CLOCKS_PER_SEC;
#endif
}

/// Sums the wall and process-CPU time of the timed regions of a benchmark.
class FrameTimer {
 public:
  void start() {
    wall0_ = MicroClock::now();
    cpu0_ = process_cpu_seconds();
  }
  /// Ends a region; returns its wall seconds (for State::SetIterationTime).
  double stop() {
    const double w = std::chrono::duration<double>(MicroClock::now() - wall0_).count();
    wall_ += w;
    cpu_ += process_cpu_seconds() - cpu0_;
    return w;
  }
  double wall() const { return wall_; }
  double cpu() const { return cpu_; }

 private:
  MicroClock::time_point wall0_{};
  double cpu0_ = 0.0, wall_ = 0.0, cpu_ = 0.0;
};

/// Sets the counters listed at the top of this file from the timed regions of
/// state.iterations() frames.
inline void report_frames(benchmark::State& state, uint32_t n, const FrameTimer& t, uint64_t pairs,
                          bool pair_rate = true) {
  const double frames = static_cast<double>(state.iterations());
  const double seconds = t.wall();
  state.SetItemsProcessed(static_cast<int64_t>(frames * n));
  state.counters["ms_per_frame"] = frames > 0 ? seconds * 1e3 / frames : 0.0;
  state.counters["cpu_ms_per_frame"] = frames > 0 ? t.cpu() * 1e3 / frames : 0.0;
  state.counters["ns_per_body"] = frames > 0 && n > 0 ? seconds * 1e9 / (frames * n) : 0.0;
  state.counters["pairs"] = static_cast<double>(pairs);
  if (pair_rate) state.counters["pairs_per_second"] = seconds > 0 ? static_cast<double>(pairs) * frames / seconds : 0.0;
}

/// Frames per coherent episode (about one second of a 60 Hz game).
inline constexpr uint64_t kCoherentFrames = 64;
/// Largest step per axis per frame, m: 5% of the unit radius (3 m/s at 60 Hz).
inline constexpr float kCoherentStep = 0.05f;
/// Seed of the walk (the scene itself uses kDefaultSeed).
inline constexpr uint64_t kCoherentSeed = 0x0c0ffee5u;
/// Untimed updates after each build (frames 1 .. kCoherentWarmupFrames).
inline constexpr uint64_t kCoherentWarmupFrames = 1;

/// Frame-to-frame driver (see the top of this file). `build(const UniformBoxes&)`
/// sets the structure up at frame 0 and returns false on failure (after calling
/// state.SkipWithError); `step(const UniformBoxes&)` is the timed per-frame work and
/// returns the pair count, or a negative value on failure (after SkipWithError).
/// Needs ->UseManualTime(). Returns false when a callback failed.
template <class Build, class Step>
bool run_coherent(benchmark::State& state, const UniformBoxes& start, Build&& build, Step&& step,
                  bool pair_rate = true) {
  const uint32_t n = static_cast<uint32_t>(start.min_x.size());
  std::optional<BoxWalk> walk;
  FrameTimer timer;
  int64_t pairs = 0;
  for (auto _ : state) {
    if (!walk || walk->frame() == kCoherentFrames) {
      walk.emplace(start, kCoherentStep, kCoherentSeed);
      if (!build(walk->boxes())) return false;
      while (walk->frame() < kCoherentWarmupFrames) {
        walk->advance();
        if (step(walk->boxes()) < 0) return false;
      }
    }
    walk->advance();
    timer.start();
    const int64_t p = step(walk->boxes());
    state.SetIterationTime(timer.stop());
    if (p < 0) return false;
    pairs = p;
  }
  report_frames(state, n, timer, static_cast<uint64_t>(pairs), pair_rate);
  return true;
}

/// The boxes of run_coherent's last timed frame after `iterations` timed frames, for
/// checking a peer's pair count afterwards.
inline UniformBoxes coherent_frame(const UniformBoxes& start, uint64_t iterations) {
  static_assert(kCoherentWarmupFrames < kCoherentFrames);
  BoxWalk walk(start, kCoherentStep, kCoherentSeed);
  const uint64_t timed = kCoherentFrames - kCoherentWarmupFrames;
  const uint64_t frame = iterations == 0 ? 0 : kCoherentWarmupFrames + (iterations - 1) % timed + 1;
  while (walk.frame() < frame) walk.advance();
  return walk.boxes();
}

}  // namespace impact::bench
