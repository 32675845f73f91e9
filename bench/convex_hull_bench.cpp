// Micro-benchmarks of ShapeSet::add_convex_hull (host/shapes/convex_hull.cpp, quickhull
// in double) through the public API: the whole call (hull, coplanar merge, edge
// classes, the HullStore's adjacency) on two point clouds:
//   BM_ConvexHullSphere/<n>   n points uniform on the unit sphere: every point is a
//       hull vertex (the worst case of quickhull's conflict lists: no point is dropped
//       early, and the hull has ~2n triangles and ~3n edge classes)
//   BM_ConvexHullCube/<n>     n points uniform in the unit cube: O(log^2 n) expected
//       hull vertices, most points dropped as inside the first tetrahedra
// A new ShapeSet per iteration (created untimed, as the cloud). Counters: vertices,
// faces (read from the set's HullStore, host/shapes/shape_store.h), ns_per_point. Run with e.g.
//   impact_microbench --benchmark_filter='^BM_ConvexHull' --benchmark_repetitions=3
//       --benchmark_report_aggregates_only=true
#include <benchmark/benchmark.h>

#include <cstdint>
#include <random>
#include <vector>

#include <Eigen/Core>

#include "host/shapes/shape_store.h"
#include "impact/impact.h"

namespace {

using V = Eigen::Vector3f;

std::vector<V> sphere_cloud(int64_t n) {
  std::mt19937 rng(11);
  std::normal_distribution<float> g;
  std::vector<V> pts;
  pts.reserve(static_cast<size_t>(n));
  while (static_cast<int64_t>(pts.size()) < n) {
    const V p(g(rng), g(rng), g(rng));
    if (p.norm() > 1e-3f) pts.push_back(p.normalized());
  }
  return pts;
}

std::vector<V> cube_cloud(int64_t n) {
  std::mt19937 rng(12);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  std::vector<V> pts(static_cast<size_t>(n));
  for (V& p : pts) p = V(u(rng), u(rng), u(rng));
  return pts;
}

void run_hull(benchmark::State& state, const std::vector<V>& pts) {
  uint64_t vertices = 0, faces = 0;
  for (auto _ : state) {
    state.PauseTiming();
    impact::ShapeSet set;
    state.ResumeTiming();
    impact::ShapeId id;
    const impact::Status st = set.add_convex_hull(pts, &id);
    if (!st.ok()) {
      state.SkipWithError(st.message().c_str());
      return;
    }
    state.PauseTiming();
    const impact::HullStore& hulls = set.store().hulls;
    vertices = hulls.vert_begin[1] - hulls.vert_begin[0];
    faces = hulls.face_begin[1] - hulls.face_begin[0];
    state.ResumeTiming();
  }
  state.counters["vertices"] = static_cast<double>(vertices);
  state.counters["faces"] = static_cast<double>(faces);
  state.counters["ns_per_point"] =
      benchmark::Counter(static_cast<double>(pts.size()) * 1e-9, benchmark::Counter::kIsIterationInvariantRate |
                                                                     benchmark::Counter::kInvert);
}

void BM_ConvexHullSphere(benchmark::State& state) { run_hull(state, sphere_cloud(state.range(0))); }
void BM_ConvexHullCube(benchmark::State& state) { run_hull(state, cube_cloud(state.range(0))); }

BENCHMARK(BM_ConvexHullSphere)->Arg(1000)->Arg(8000)->Arg(32000)->Arg(100000)->UseRealTime()->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ConvexHullCube)->Arg(1000)->Arg(8000)->Arg(32000)->Arg(100000)->UseRealTime()->Unit(benchmark::kMillisecond);

}  // namespace
