// Peer broad phases on the same boxes as bench/broadphase_bench.cpp, in the same
// executable and run, so a user sees the ratios to the structures they would otherwise
// pick. Each peer is compiled in only when its Debian package is found (bench/CMakeLists.txt;
// scripts/install_deps.sh --peers installs them):
//   Bullet 3 btDbvtBroadphase with a btHashedOverlappingPairCache (libbullet-dev;
//     single precision, Debian's default build)
//   FCL 0.7 DynamicAABBTreeCollisionManager<double> over CollisionObject<double> boxes
//     (libfcl-dev)
//
// Scene: the "uniform" scene of BM_GridBroadPhase, byte for byte (unit-radius spheres'
// boxes, ~1 overlapping pair per body; bench/scenes/micro_common.h), at 10k, 100k, 1M
// bodies. The peers are single-threaded: one thread only. Names follow the
// BM_<what>/<bodies>/<threads> pattern of the other benchmarks:
//   BM_PeerBulletDbvtScratch   new broadphase + pair cache, createProxy for every box,
//                              calculateOverlappingPairs
//   BM_PeerBulletDbvtUpdate    every box moved (run_coherent's walk), setAabb for every
//                              proxy, calculateOverlappingPairs
//   BM_PeerFclDynTreeScratch   new manager, registerObjects + setup + collide
//   BM_PeerFclDynTreeUpdate    every object moved (setTranslation + computeAABB),
//                              update() + collide
// Only the broad phase is timed: the callback of FCL's collide counts the candidate
// pairs it is handed (the pairs whose AABBs overlap) and runs no narrow phase; Bullet
// is asked for its overlapping pairs with no dispatcher work. Creating the user's
// objects (FCL CollisionObjects) and destroying a structure are not timed (manual
// time); pushing new boxes into the structure is.
//
// Pair counts, as counters:
//   pairs      what the peer reports: FCL's callback count; Bullet's pair-cache size,
//              which is a superset (its tree stores boxes enlarged by a margin and
//              removes stale pairs lazily, a slice per frame)
//   exact      Bullet only: the cached pairs whose boxes really overlap
//   ref_pairs  our grid on the same boxes (the last frame's, for updates)
//   missing    ref_pairs minus the peer's exact pairs (should be 0; touching boxes
//              count as overlapping for all three)
// FCL's double boxes are built to equal the float boxes exactly (centre and size in
// double are exact), so its from-scratch count matches ref_pairs exactly. A moved
// object keeps its size and gets a new centre, and centre -+ size / 2 can then differ
// from the moved float box in the last bit: its update count may differ from ref_pairs
// by a pair or so whose boxes just touch (1 of 990k at 1M).
#include <benchmark/benchmark.h>

#include <chrono>
#include <cstdint>
#include <memory>
#include <vector>

#include "bench/scenes/micro_common.h"
#include "bench/scenes/scenes.h"

#ifndef IMPACT_BENCH_HAVE_BULLET
#define IMPACT_BENCH_HAVE_BULLET 0
#endif
#ifndef IMPACT_BENCH_HAVE_FCL
#define IMPACT_BENCH_HAVE_FCL 0
#endif

#if IMPACT_BENCH_HAVE_BULLET
#include <BulletCollision/BroadphaseCollision/btBroadphaseProxy.h>
#include <BulletCollision/BroadphaseCollision/btDbvtBroadphase.h>
#include <BulletCollision/BroadphaseCollision/btOverlappingPairCache.h>
#include <BulletCollision/CollisionDispatch/btCollisionDispatcher.h>
#include <BulletCollision/CollisionDispatch/btDefaultCollisionConfiguration.h>
#endif
#if IMPACT_BENCH_HAVE_FCL
#include <fcl/broadphase/broadphase_dynamic_AABB_tree.h>
#include <fcl/geometry/shape/box.h>
#include <fcl/narrowphase/collision_object.h>
#endif

namespace {

using impact::bench::BoxScene;
using impact::bench::FrameTimer;
using impact::bench::UniformBoxes;

void report_check(benchmark::State& state, uint64_t exact, uint64_t ref) {
  state.counters["ref_pairs"] = static_cast<double>(ref);
  state.counters["missing"] = static_cast<double>(ref) - static_cast<double>(exact);
}

// --- Bullet ---------------------------------------------------------------------------------
#if IMPACT_BENCH_HAVE_BULLET

// Boxes i and j overlap or touch (the contract of impact::AabbInput).
bool boxes_overlap(const UniformBoxes& b, uint32_t i, uint32_t j) {
  return b.min_x[i] <= b.max_x[j] && b.min_x[j] <= b.max_x[i] && b.min_y[i] <= b.max_y[j] &&
         b.min_y[j] <= b.max_y[i] && b.min_z[i] <= b.max_z[j] && b.min_z[j] <= b.max_z[i];
}

// The dispatcher Bullet's calls take. The broad phase only hands it to the pair cache,
// which needs it to free narrow-phase algorithms (none exist here).
btDispatcher* bullet_dispatcher() {
  static btDefaultCollisionConfiguration config;
  static btCollisionDispatcher dispatcher(&config);
  return &dispatcher;
}

// One btDbvtBroadphase over boxes [0, n), proxy i's user pointer holding i.
class BulletDbvt {
 public:
  BulletDbvt() : cache_(new btHashedOverlappingPairCache()), broadphase_(new btDbvtBroadphase(cache_.get())) {}
  BulletDbvt(const BulletDbvt&) = delete;
  BulletDbvt& operator=(const BulletDbvt&) = delete;
  ~BulletDbvt() {
    // destroyProxy asks the pair cache to drop the proxy's pairs, a scan of the whole
    // cache per proxy; hand it an empty cache while the proxies go.
    btNullPairCache none;
    broadphase_->m_paircache = &none;
    for (btBroadphaseProxy* p : proxies_) broadphase_->destroyProxy(p, bullet_dispatcher());
    broadphase_->m_paircache = cache_.get();
    broadphase_.reset();
  }

  void insert(const UniformBoxes& b) {
    const size_t n = b.min_x.size();
    proxies_.resize(n);
    for (size_t i = 0; i < n; ++i)
      proxies_[i] = broadphase_->createProxy(btVector3(b.min_x[i], b.min_y[i], b.min_z[i]),
                                             btVector3(b.max_x[i], b.max_y[i], b.max_z[i]), SPHERE_SHAPE_PROXYTYPE,
                                             reinterpret_cast<void*>(static_cast<uintptr_t>(i)),
                                             btBroadphaseProxy::DefaultFilter, btBroadphaseProxy::AllFilter,
                                             bullet_dispatcher());
  }
  void move(const UniformBoxes& b) {
    for (size_t i = 0; i < proxies_.size(); ++i)
      broadphase_->setAabb(proxies_[i], btVector3(b.min_x[i], b.min_y[i], b.min_z[i]),
                           btVector3(b.max_x[i], b.max_y[i], b.max_z[i]), bullet_dispatcher());
  }
  uint64_t find_pairs() {
    broadphase_->calculateOverlappingPairs(bullet_dispatcher());
    return static_cast<uint64_t>(cache_->getNumOverlappingPairs());
  }
  // Cached pairs whose boxes in b overlap.
  uint64_t exact_pairs(const UniformBoxes& b) const {
    const btBroadphasePairArray& pairs = cache_->getOverlappingPairArray();
    uint64_t count = 0;
    for (int k = 0; k < pairs.size(); ++k) {
      const auto i = static_cast<uint32_t>(reinterpret_cast<uintptr_t>(pairs[k].m_pProxy0->m_clientObject));
      const auto j = static_cast<uint32_t>(reinterpret_cast<uintptr_t>(pairs[k].m_pProxy1->m_clientObject));
      count += boxes_overlap(b, i, j) ? 1 : 0;
    }
    return count;
  }

 private:
  std::unique_ptr<btHashedOverlappingPairCache> cache_;
  std::unique_ptr<btDbvtBroadphase> broadphase_;
  std::vector<btBroadphaseProxy*> proxies_;
};

void BM_PeerBulletDbvtScratch(benchmark::State& state) {
  const uint32_t n = static_cast<uint32_t>(state.range(0));
  const UniformBoxes& boxes = impact::bench::scene_boxes(BoxScene::kUniform, n);
  FrameTimer timer;
  uint64_t pairs = 0, exact = 0;
  for (auto _ : state) {
    auto bp = std::make_unique<BulletDbvt>();
    timer.start();
    bp->insert(boxes);
    pairs = bp->find_pairs();
    state.SetIterationTime(timer.stop());
    exact = bp->exact_pairs(boxes);
  }
  impact::bench::report_frames(state, n, timer, pairs);
  state.counters["exact"] = static_cast<double>(exact);
  report_check(state, exact, impact::bench::reference_pair_count(boxes));
}

void BM_PeerBulletDbvtUpdate(benchmark::State& state) {
  const uint32_t n = static_cast<uint32_t>(state.range(0));
  const UniformBoxes& start = impact::bench::scene_boxes(BoxScene::kUniform, n);
  std::unique_ptr<BulletDbvt> bp;
  const bool ok = impact::bench::run_coherent(
      state, start,
      [&](const UniformBoxes& b) {
        bp.reset();
        bp = std::make_unique<BulletDbvt>();
        bp->insert(b);
        bp->find_pairs();
        return true;
      },
      [&](const UniformBoxes& b) -> int64_t {
        bp->move(b);
        return static_cast<int64_t>(bp->find_pairs());
      });
  if (!ok || !bp) return;
  const UniformBoxes last = impact::bench::coherent_frame(start, state.iterations());
  const uint64_t exact = bp->exact_pairs(last);
  state.counters["exact"] = static_cast<double>(exact);
  report_check(state, exact, impact::bench::reference_pair_count(last));
}

BENCHMARK(BM_PeerBulletDbvtScratch)->Args({10000, 1})->Args({100000, 1})->UseManualTime()->Unit(benchmark::kMillisecond);
BENCHMARK(BM_PeerBulletDbvtScratch)->Args({1000000, 1})->Iterations(1)->UseManualTime()->Unit(benchmark::kMillisecond);
BENCHMARK(BM_PeerBulletDbvtUpdate)->Args({10000, 1})->Args({100000, 1})->UseManualTime()->Unit(benchmark::kMillisecond);
BENCHMARK(BM_PeerBulletDbvtUpdate)->Args({1000000, 1})->Iterations(2)->UseManualTime()->Unit(benchmark::kMillisecond);

#endif  // IMPACT_BENCH_HAVE_BULLET

// --- FCL ------------------------------------------------------------------------------------
#if IMPACT_BENCH_HAVE_FCL

using FclManager = fcl::DynamicAABBTreeCollisionManager<double>;

// One CollisionObject per box: a box geometry of the box's size, translated to its
// centre. In double, (min + max) / 2 and max - min of float bounds are exact, so the
// object's AABB (centre -+ size / 2) is the float box exactly (at creation; see the
// top of the file for moved objects).
class FclObjects {
 public:
  explicit FclObjects(const UniformBoxes& b) {
    const size_t n = b.min_x.size();
    objects_.reserve(n);
    pointers_.reserve(n);
    for (size_t i = 0; i < n; ++i) {
      auto shape = std::make_shared<fcl::Boxd>(double{b.max_x[i]} - b.min_x[i], double{b.max_y[i]} - b.min_y[i],
                                               double{b.max_z[i]} - b.min_z[i]);
      fcl::Transform3d pose = fcl::Transform3d::Identity();
      pose.translation() = centre(b, i);
      objects_.push_back(std::make_unique<fcl::CollisionObjectd>(shape, pose));
      objects_.back()->setUserData(reinterpret_cast<void*>(static_cast<uintptr_t>(i)));
      pointers_.push_back(objects_.back().get());
    }
  }
  // New positions (sizes unchanged), AABBs recomputed.
  void move(const UniformBoxes& b) {
    for (size_t i = 0; i < objects_.size(); ++i) {
      objects_[i]->setTranslation(centre(b, i));
      objects_[i]->computeAABB();
    }
  }
  const std::vector<fcl::CollisionObjectd*>& pointers() const { return pointers_; }

 private:
  static fcl::Vector3d centre(const UniformBoxes& b, size_t i) {
    return {0.5 * (double{b.min_x[i]} + b.max_x[i]), 0.5 * (double{b.min_y[i]} + b.max_y[i]),
            0.5 * (double{b.min_z[i]} + b.max_z[i])};
  }
  std::vector<std::unique_ptr<fcl::CollisionObjectd>> objects_;
  std::vector<fcl::CollisionObjectd*> pointers_;
};

// Broad-phase candidate callback: counts the pair, asks for the next one.
bool count_candidate(fcl::CollisionObjectd*, fcl::CollisionObjectd*, void* data) {
  ++*static_cast<uint64_t*>(data);
  return false;
}

uint64_t fcl_pairs(const FclManager& manager) {
  uint64_t count = 0;
  manager.collide(&count, count_candidate);
  return count;
}

void BM_PeerFclDynTreeScratch(benchmark::State& state) {
  const uint32_t n = static_cast<uint32_t>(state.range(0));
  const UniformBoxes& boxes = impact::bench::scene_boxes(BoxScene::kUniform, n);
  FclObjects objects(boxes);
  FrameTimer timer;
  uint64_t pairs = 0;
  for (auto _ : state) {
    auto manager = std::make_unique<FclManager>();
    timer.start();
    manager->registerObjects(objects.pointers());
    manager->setup();
    pairs = fcl_pairs(*manager);
    state.SetIterationTime(timer.stop());
  }
  impact::bench::report_frames(state, n, timer, pairs);
  report_check(state, pairs, impact::bench::reference_pair_count(boxes));
}

void BM_PeerFclDynTreeUpdate(benchmark::State& state) {
  const uint32_t n = static_cast<uint32_t>(state.range(0));
  const UniformBoxes& start = impact::bench::scene_boxes(BoxScene::kUniform, n);
  FclObjects objects(start);
  std::unique_ptr<FclManager> manager;
  uint64_t pairs = 0;
  const bool ok = impact::bench::run_coherent(
      state, start,
      [&](const UniformBoxes& b) {
        objects.move(b);
        manager.reset();
        manager = std::make_unique<FclManager>();
        manager->registerObjects(objects.pointers());
        manager->setup();
        fcl_pairs(*manager);
        return true;
      },
      [&](const UniformBoxes& b) -> int64_t {
        objects.move(b);
        manager->update();
        pairs = fcl_pairs(*manager);
        return static_cast<int64_t>(pairs);
      });
  if (!ok) return;
  report_check(state, pairs, impact::bench::reference_pair_count(impact::bench::coherent_frame(start, state.iterations())));
}

BENCHMARK(BM_PeerFclDynTreeScratch)->Args({10000, 1})->Args({100000, 1})->UseManualTime()->Unit(benchmark::kMillisecond);
BENCHMARK(BM_PeerFclDynTreeScratch)->Args({1000000, 1})->Iterations(1)->UseManualTime()->Unit(benchmark::kMillisecond);
BENCHMARK(BM_PeerFclDynTreeUpdate)->Args({10000, 1})->Args({100000, 1})->UseManualTime()->Unit(benchmark::kMillisecond);
BENCHMARK(BM_PeerFclDynTreeUpdate)->Args({1000000, 1})->Iterations(2)->UseManualTime()->Unit(benchmark::kMillisecond);

#endif  // IMPACT_BENCH_HAVE_FCL

}  // namespace
