// impact_raybench: ray throughput of RayScene (Embree and LBVH paths) on
//   - a 1M-triangle procedural terrain (static): coherent picking rays from a camera
//     grid (pick, and closest_hit on the same rays) and incoherent visibility
//     segments (any hit), and incoherent closest-hit rays (closest_incoherent);
//   - 100k dynamic spheres and 100k dynamic capsules: incoherent closest-hit rays,
//     camera picking, and the per-frame update (set + commit: refit vs rebuild);
//   - 100k dynamic posed shapes (boxes, convex hulls, cylinders; set_shapes): the same
//     queries and update;
//   - a World of 100k bodies (half spheres, half boxes): sync_world + commit per frame;
//   - peers on the same rays and scenes: a plain rtcIntersect1 / rtcOccluded1 loop on
//     the scene's own Embree scene (the batching overhead), and, when libbullet-dev is
//     present, Bullet's btCollisionWorld::rayTest and its per-frame AABB update
//     (bench/raycast_bench_bullet.cpp).
// Counter "Mrays/s" is millions of rays per second of wall time for the whole batch
// (all threads). Names: <scene>/<query>/<backend>/threads:<T>.
// Usage: impact_raybench [--quick] [google benchmark flags]   (--quick: small scenes, for CI)
#include <benchmark/benchmark.h>

#include <cmath>
#include <cstring>
#include <functional>
#include <limits>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "bench/bench_threads.h"
#include "bench/raycast_bench_bullet.h"
#include "host/raycast/embree_plain.h"
#include "impact/impact.h"

namespace {

using namespace impact;

bool g_quick = false;

uint32_t terrain_side() { return g_quick ? 64 : 708; }    // 2 * 708^2 = 1.0M triangles
uint32_t dynamic_count() { return g_quick ? 2000 : 100000; }
uint32_t ray_count() { return g_quick ? 4096 : 65536; }

float terrain_height(float x, float z) {
  return 6.0f * std::sin(0.021f * x) * std::cos(0.017f * z) + 2.0f * std::sin(0.11f * x + 0.07f * z) +
         0.5f * std::sin(0.9f * x) * std::sin(0.8f * z);
}

struct Terrain {
  Eigen::Matrix3Xf v;
  Eigen::Matrix<uint32_t, 3, Eigen::Dynamic> t;
  float size = 0;
};

const Terrain& terrain() {
  static Terrain tr = [] {
    Terrain g;
    const uint32_t n = terrain_side();
    g.size = static_cast<float>(n);
    g.v.resize(3, (n + 1) * (n + 1));
    g.t.resize(3, 2 * n * n);
    for (uint32_t j = 0; j <= n; ++j)
      for (uint32_t i = 0; i <= n; ++i) {
        const float x = static_cast<float>(i), z = static_cast<float>(j);
        g.v.col(j * (n + 1) + i) = Eigen::Vector3f(x, terrain_height(x, z), z);
      }
    uint32_t k = 0;
    for (uint32_t j = 0; j < n; ++j)
      for (uint32_t i = 0; i < n; ++i) {
        const uint32_t a = j * (n + 1) + i, b = a + 1, c = a + n + 1, d = c + 1;
        g.t.col(k++) = Eigen::Matrix<uint32_t, 3, 1>(a, c, b);
        g.t.col(k++) = Eigen::Matrix<uint32_t, 3, 1>(b, c, d);
      }
    return g;
  }();
  return tr;
}

// Dynamic bodies: centres uniform in a box of side L with ~1% volume fraction.
struct Bodies {
  std::vector<float> x, y, z, r;
  Eigen::Matrix3Xf a, b;  // capsules
  std::vector<float> cr;
  float side = 0;
};

const Bodies& bodies() {
  static Bodies bd = [] {
    Bodies g;
    const uint32_t n = dynamic_count();
    g.side = 4.0f * std::cbrt(static_cast<float>(n));  // 100k: 186 m
    std::mt19937 rng(42);
    std::uniform_real_distribution<float> pos(0.0f, g.side), rad(0.2f, 0.6f), u(-1.0f, 1.0f);
    for (uint32_t i = 0; i < n; ++i) {
      g.x.push_back(pos(rng));
      g.y.push_back(pos(rng));
      g.z.push_back(pos(rng));
      g.r.push_back(rad(rng));
    }
    g.a.resize(3, n);
    g.b.resize(3, n);
    for (uint32_t i = 0; i < n; ++i) {
      const Eigen::Vector3f c(pos(rng), pos(rng), pos(rng));
      const Eigen::Vector3f h = Eigen::Vector3f(u(rng), u(rng), u(rng)).normalized() * 0.5f;
      g.a.col(i) = c - h;
      g.b.col(i) = c + h;
      g.cr.push_back(0.5f * rad(rng));
    }
    return g;
  }();
  return bd;
}

// Posed shapes (the Shapes100k scene): the centres and sizes of bodies(), as boxes
// (half), 16-vertex convex hulls and cylinders (a quarter each), randomly oriented.
struct Shapes {
  ShapeSet set;
  std::vector<ShapeId> shape_of;
  std::vector<Pose> poses;
};

const Shapes& shapes() {
  static Shapes sh = [] {
    Shapes g;
    const Bodies& b = bodies();
    std::mt19937 rng(43);
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    auto unit = [&] {
      for (;;) {
        const Eigen::Vector3f v(u(rng), u(rng), u(rng));
        if (v.norm() > 0.1f && v.norm() <= 1.0f) return Eigen::Vector3f(v.normalized());
      }
    };
    // A few sizes of each kind, scaled like the spheres (radius 0.2 to 0.6).
    std::vector<ShapeId> kinds;
    for (float r : {0.25f, 0.4f, 0.55f}) {
      ShapeId id;
      (void)g.set.add_box(Eigen::Vector3f(r, 0.7f * r, 0.5f * r), &id);
      kinds.push_back(id);
      kinds.push_back(id);
      std::vector<Eigen::Vector3f> cloud;
      for (int k = 0; k < 16; ++k) cloud.push_back(r * unit());
      (void)g.set.add_convex_hull(cloud, &id);
      kinds.push_back(id);
      (void)g.set.add_cylinder(0.7f * r, 0.6f * r, &id);
      kinds.push_back(id);
    }
    for (size_t i = 0; i < b.x.size(); ++i) {
      g.shape_of.push_back(kinds[i % kinds.size()]);
      const Eigen::Vector4f c(u(rng), u(rng), u(rng), u(rng));
      Pose p;
      p.position = Eigen::Vector3f(b.x[i], b.y[i], b.z[i]);
      p.orientation = Eigen::Quaternionf(c[0], c[1], c[2], c[3]).normalized();
      g.poses.push_back(p);
    }
    return g;
  }();
  return sh;
}

// Incoherent rays: from random points on the box's faces towards random interior points.
std::vector<Ray> incoherent_rays(float side, float y_lo, float y_hi, uint32_t n, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  std::vector<Ray> rays(n);
  for (auto& r : rays) {
    const Eigen::Vector3f from(side * u(rng), y_lo + (y_hi - y_lo) * u(rng), -1.0f);
    const Eigen::Vector3f to(side * u(rng), y_lo + (y_hi - y_lo) * u(rng), side * u(rng));
    r.origin = from;
    r.direction = (to - from).normalized();
  }
  return rays;
}

std::vector<Segment> terrain_segments(uint32_t n, uint32_t seed) {
  // Line of sight between two random points 1.8 m above the terrain (eye height),
  // up to 200 m apart: the AI visibility query.
  std::mt19937 rng(seed);
  const float s = terrain().size;
  std::uniform_real_distribution<float> u(0.0f, s), off(-100.0f, 100.0f);
  std::vector<Segment> segs(n);
  for (auto& sg : segs) {
    const float x0 = u(rng), z0 = u(rng);
    const float x1 = std::clamp(x0 + off(rng), 0.0f, s), z1 = std::clamp(z0 + off(rng), 0.0f, s);
    sg.from = Eigen::Vector3f(x0, terrain_height(x0, z0) + 1.8f, z0);
    sg.to = Eigen::Vector3f(x1, terrain_height(x1, z1) + 1.8f, z1);
  }
  return segs;
}

std::vector<Eigen::Vector2f> screen_grid(uint32_t w, uint32_t h) {
  std::vector<Eigen::Vector2f> s;
  s.reserve(size_t{w} * h);
  for (uint32_t j = 0; j < h; ++j)
    for (uint32_t i = 0; i < w; ++i)
      s.emplace_back((static_cast<float>(i) + 0.5f) / static_cast<float>(w), (static_cast<float>(j) + 0.5f) / static_cast<float>(h));
  return s;
}

uint32_t grid_w() { return g_quick ? 64 : 320; }
uint32_t grid_h() { return g_quick ? 64 : 200; }  // 64k camera rays

struct Variant {
  const char* name;
  RaySceneDesc desc;
};

std::vector<Variant> variants(bool with_builtin) {
  std::vector<Variant> v;
  RaySceneDesc d;
  d.backend = RayBackend::kEmbree;
  v.push_back({"embree", d});
  d.packet_width = 8;
  v.push_back({"embree_packet8", d});
  d.packet_width = 16;
  v.push_back({"embree_packet16", d});
  d.packet_width = 1;
  d.embree_streams = EmbreeStreams::kAlways;  // "embree" is kAuto: streams for pick on meshes only
  v.push_back({"embree_stream", d});
  d.embree_streams = EmbreeStreams::kAuto;
  if (with_builtin) {
    d.embree_spheres = EmbreeSpheres::kBuiltin;
    v.push_back({"embree_builtin", d});
  }
  RaySceneDesc l;
  l.backend = RayBackend::kLbvh;
  v.push_back({"lbvh", l});
  return v;
}

void check(const Status& s, benchmark::State& state) {
  if (!s.ok()) state.SkipWithError(s.message().c_str());
}

// Scenes are built once per (scene kind, variant) and kept for the process.
enum class SceneKind { kTerrain, kSpheres, kCapsules, kShapes };

RayScene* get_scene(SceneKind kind, const Variant& v) {
  static std::vector<std::pair<std::string, std::unique_ptr<RayScene>>> cache;
  const std::string key = std::to_string(static_cast<int>(kind)) + v.name;
  for (auto& [k, s] : cache)
    if (k == key) return s.get();
  std::unique_ptr<RayScene> s;
  if (!RayScene::create(v.desc, &s).ok()) return nullptr;
  Status st;
  if (kind == SceneKind::kTerrain) {
    MeshHandle h;
    st = s->add_mesh(terrain().v, terrain().t, 1u, &h);
  } else if (kind == SceneKind::kSpheres) {
    const Bodies& b = bodies();
    st = s->set_spheres(b.x, b.y, b.z, b.r);
  } else if (kind == SceneKind::kShapes) {
    st = s->set_shapes(shapes().set, shapes().shape_of, shapes().poses);
  } else {
    const Bodies& b = bodies();
    st = s->set_capsules(b.a, b.b, b.cr);
  }
  if (!st.ok() || !s->commit().ok()) return nullptr;
  cache.emplace_back(key, std::move(s));
  return cache.back().second.get();
}

void set_rate(benchmark::State& state, size_t rays) {
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations() * rays));
  state.counters["Mrays/s"] =
      benchmark::Counter(static_cast<double>(rays) * 1e-6, benchmark::Counter::kIsIterationInvariantRate);
}

void closest_bench(benchmark::State& state, SceneKind kind, const Variant& v, uint32_t threads,
                   const std::vector<Ray>& rays) {
  RayScene* s = get_scene(kind, v);
  if (!s) return state.SkipWithError("scene creation failed");
  check(s->set_threads(Backend::kTbb, threads), state);
  std::vector<RayHit> hits(rays.size());
  for (auto _ : state) {
    check(s->closest_hit(rays, hits), state);
    benchmark::DoNotOptimize(hits.data());
  }
  size_t n_hit = 0;
  for (const auto& h : hits) n_hit += h.hit();
  state.counters["hit%"] = 100.0 * static_cast<double>(n_hit) / static_cast<double>(rays.size());
  set_rate(state, rays.size());
}

void pick_bench(benchmark::State& state, SceneKind kind, const Variant& v, uint32_t threads, const Camera& cam) {
  RayScene* s = get_scene(kind, v);
  if (!s) return state.SkipWithError("scene creation failed");
  check(s->set_threads(Backend::kTbb, threads), state);
  const auto screen = screen_grid(grid_w(), grid_h());
  std::vector<RayHit> hits(screen.size());
  for (auto _ : state) {
    check(s->pick(cam, screen, 0xffffffffu, hits), state);
    benchmark::DoNotOptimize(hits.data());
  }
  size_t n_hit = 0;
  for (const auto& h : hits) n_hit += h.hit();
  state.counters["hit%"] = 100.0 * static_cast<double>(n_hit) / static_cast<double>(screen.size());
  set_rate(state, screen.size());
}

void any_bench(benchmark::State& state, SceneKind kind, const Variant& v, uint32_t threads,
               const std::vector<Segment>& segs) {
  RayScene* s = get_scene(kind, v);
  if (!s) return state.SkipWithError("scene creation failed");
  check(s->set_threads(Backend::kTbb, threads), state);
  std::vector<uint8_t> occ(segs.size());
  for (auto _ : state) {
    check(s->any_hit(segs, occ), state);
    benchmark::DoNotOptimize(occ.data());
  }
  size_t n = 0;
  for (uint8_t o : occ) n += o;
  state.counters["occluded%"] = 100.0 * static_cast<double>(n) / static_cast<double>(segs.size());
  set_rate(state, segs.size());
}

// The per-frame update of the dynamic bodies: every centre moves a little, then
// set + commit (refit or rebuild per the variant's DynamicUpdate).
void update_bench(benchmark::State& state, SceneKind kind, RaySceneDesc desc, uint32_t threads) {
  desc.threads = threads;
  desc.backend_threads = Backend::kTbb;
  std::unique_ptr<RayScene> s;
  check(RayScene::create(desc, &s), state);
  if (!s) return;
  Bodies b = bodies();
  std::vector<Pose> poses = kind == SceneKind::kShapes ? shapes().poses : std::vector<Pose>{};
  auto set = [&] {
    if (kind == SceneKind::kShapes) return s->set_shapes(shapes().set, shapes().shape_of, poses);
    return kind == SceneKind::kSpheres ? s->set_spheres(b.x, b.y, b.z, b.r) : s->set_capsules(b.a, b.b, b.cr);
  };
  check(set(), state);
  check(s->commit(), state);
  // Every body moves 0.05 m per frame along x (sign alternating), as in the Bullet case.
  float dx = 0.05f;
  const float dy = 0.0f;
  double commit_ms = 0.0;
  for (auto _ : state) {
    dx = -dx;
    for (size_t i = 0; i < b.x.size(); ++i) {
      b.x[i] += dx;
      b.y[i] += dy;
    }
    b.a.row(0).array() += dx;
    b.b.row(0).array() += dx;
    for (Pose& p : poses) p.position.x() += dx;
    check(set(), state);
    check(s->commit(), state);
    commit_ms += s->info().commit_ms;
  }
  state.counters["commit_ms"] = commit_ms / static_cast<double>(state.iterations());
  state.counters["rebuilt"] = s->info().dynamic_rebuilt ? 1 : 0;
}

// A World of bodies() (even slots spheres, odd slots boxes of the same size, randomly
// oriented): the per-frame cost of bringing a RayScene up to the world, sync_world +
// commit, with the bodies moved by the world's own set_positions between frames
// (not timed). Then closest-hit rays on the synced scene.
struct WorldScene {
  std::unique_ptr<World> world;
  std::vector<BodyHandle> handles;
};

WorldScene make_world_scene() {
  WorldScene ws;
  if (!World::create(WorldDesc{}, &ws.world).ok()) return ws;
  const Bodies& b = bodies();
  std::vector<ShapeId> boxes;
  for (float r : {0.25f, 0.4f, 0.55f}) {
    ShapeId id;
    (void)ws.world->shapes().add_box(Eigen::Vector3f(r, 0.7f * r, 0.5f * r), &id);
    boxes.push_back(id);
  }
  std::mt19937 rng(44);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  std::vector<BodyDesc> descs(b.x.size());
  for (size_t i = 0; i < descs.size(); ++i) {
    descs[i].position = Eigen::Vector3f(b.x[i], b.y[i], b.z[i]);
    descs[i].radius = b.r[i];
    if (i % 2 == 1) {
      descs[i].shape = boxes[i % 3];
      descs[i].orientation = Eigen::Quaternionf(Eigen::Vector4f(u(rng), u(rng), u(rng), u(rng)).normalized());
    }
  }
  ws.handles.resize(descs.size());
  if (!ws.world->create_bodies(descs, ws.handles).ok()) ws.world.reset();
  return ws;
}

void world_sync_bench(benchmark::State& state, RaySceneDesc desc, uint32_t threads) {
  desc.threads = threads;
  desc.backend_threads = Backend::kTbb;
  WorldScene ws = make_world_scene();
  if (!ws.world) return state.SkipWithError("world creation failed");
  std::unique_ptr<RayScene> s;
  check(RayScene::create(desc, &s), state);
  if (!s) return;
  check(s->sync_world(*ws.world), state);
  check(s->commit(), state);
  std::vector<Eigen::Vector3f> pos(ws.handles.size());
  check(ws.world->get_positions(ws.handles, pos), state);
  float dx = 0.05f;
  for (auto _ : state) {
    state.PauseTiming();
    dx = -dx;
    for (auto& p : pos) p.x() += dx;
    check(ws.world->set_positions(ws.handles, pos), state);
    state.ResumeTiming();
    check(s->sync_world(*ws.world), state);
    check(s->commit(), state);
  }
  state.counters["rebuilt"] = s->info().dynamic_rebuilt ? 1 : 0;
}

void plain_closest_bench(benchmark::State& state, SceneKind kind, const Variant& v, const std::vector<Ray>& rays) {
  RayScene* s = get_scene(kind, v);
  if (!s) return state.SkipWithError("scene creation failed");
  uint64_t hits = 0;
  for (auto _ : state) {
    hits = host::embree_plain_closest(*s, rays);
    benchmark::DoNotOptimize(hits);
  }
  state.counters["hit%"] = 100.0 * static_cast<double>(hits) / static_cast<double>(rays.size());
  set_rate(state, rays.size());
}

// The plain loop keeping each ray's Embree hit (t, ids, Ng: 28 bytes) in an array, as
// a caller that uses its results would: the like-for-like reference for closest_hit.
void plain_closest_store_bench(benchmark::State& state, SceneKind kind, const Variant& v, const std::vector<Ray>& rays) {
  RayScene* s = get_scene(kind, v);
  if (!s) return state.SkipWithError("scene creation failed");
  std::vector<host::PlainHit> out(rays.size());
  uint64_t hits = 0;
  for (auto _ : state) {
    hits = host::embree_plain_closest_store(*s, rays, out);
    benchmark::DoNotOptimize(out.data());
  }
  state.counters["hit%"] = 100.0 * static_cast<double>(hits) / static_cast<double>(rays.size());
  set_rate(state, rays.size());
}

void plain_any_bench(benchmark::State& state, SceneKind kind, const Variant& v, const std::vector<Segment>& segs) {
  RayScene* s = get_scene(kind, v);
  if (!s) return state.SkipWithError("scene creation failed");
  uint64_t occ = 0;
  for (auto _ : state) {
    occ = host::embree_plain_any(*s, segs);
    benchmark::DoNotOptimize(occ);
  }
  state.counters["occluded%"] = 100.0 * static_cast<double>(occ) / static_cast<double>(segs.size());
  set_rate(state, segs.size());
}

Camera terrain_camera() {
  Camera c;
  const float s = terrain().size;
  c.position = Eigen::Vector3f(0.1f * s, 40.0f, 0.1f * s);
  c.forward = Eigen::Vector3f(1.0f, -0.35f, 1.0f);
  c.aspect = static_cast<float>(grid_w()) / static_cast<float>(grid_h());
  return c;
}

Camera bodies_camera() {
  Camera c;
  const float s = bodies().side;
  c.position = Eigen::Vector3f(0.5f * s, 0.5f * s, -0.3f * s);
  c.forward = Eigen::Vector3f(0, 0, 1);
  c.aspect = static_cast<float>(grid_w()) / static_cast<float>(grid_h());
  return c;
}

void register_all() {
  static std::vector<Ray> body_rays, terrain_rays, terrain_down_rays;
  static std::vector<Segment> terrain_segs, body_segs;
  const float side = bodies().side;
  body_rays = incoherent_rays(side, 0.0f, side, ray_count(), 7);
  terrain_segs = terrain_segments(ray_count(), 9);
  // Incoherent closest-hit rays on the terrain: from the segments' starts, towards
  // their ends tilted down, so most meet the ground.
  terrain_down_rays.resize(terrain_segs.size());
  for (size_t i = 0; i < terrain_segs.size(); ++i) {
    const Eigen::Vector3f d = terrain_segs[i].to - terrain_segs[i].from + Eigen::Vector3f(0.0f, -20.0f, 0.0f);
    terrain_down_rays[i] = Ray{terrain_segs[i].from, d.normalized(), std::numeric_limits<float>::infinity(), ~0u};
  }
  body_segs.resize(body_rays.size());
  for (size_t i = 0; i < body_rays.size(); ++i)
    body_segs[i] = {body_rays[i].origin, body_rays[i].origin + 50.0f * body_rays[i].direction, ~0u};
  {
    std::vector<Ray> r(grid_w() * grid_h());
    (void)camera_rays(terrain_camera(), screen_grid(grid_w(), grid_h()), ~0u, r);
    terrain_rays = r;
  }
  std::vector<uint32_t> thread_counts;
  for (int64_t t : impact::bench::bench_thread_counts()) thread_counts.push_back(static_cast<uint32_t>(t));
  auto name = [](const std::string& scene, const std::string& q, const std::string& v, uint32_t t) {
    return scene + "/" + q + "/" + v + "/threads:" + std::to_string(t);
  };
  auto reg = [](const std::string& n, std::function<void(benchmark::State&)> f) {
    benchmark::RegisterBenchmark(n.c_str(), [f](benchmark::State& st) { f(st); })->Unit(benchmark::kMillisecond)->UseRealTime();
  };

  // Terrain: coherent picking and incoherent visibility.
  for (const Variant& v : variants(false))
    for (uint32_t t : thread_counts) {
      reg(name("Terrain1M", "pick", v.name, t), [v, t](benchmark::State& s) { pick_bench(s, SceneKind::kTerrain, v, t, terrain_camera()); });
      // The same camera rays through closest_hit: the batching overhead against the
      // plain loop below on identical input (pick adds making the rays).
      reg(name("Terrain1M", "closest", v.name, t),
          [v, t](benchmark::State& s) { closest_bench(s, SceneKind::kTerrain, v, t, terrain_rays); });
      reg(name("Terrain1M", "closest_incoherent", v.name, t),
          [v, t](benchmark::State& s) { closest_bench(s, SceneKind::kTerrain, v, t, terrain_down_rays); });
      reg(name("Terrain1M", "visibility", v.name, t),
          [v, t](benchmark::State& s) { any_bench(s, SceneKind::kTerrain, v, t, terrain_segs); });
    }
  const Variant embree1 = variants(false)[0];
  reg("Terrain1M/pick/plain_rtcIntersect1/threads:1",
      [embree1](benchmark::State& s) { plain_closest_bench(s, SceneKind::kTerrain, embree1, terrain_rays); });
  reg("Terrain1M/closest_incoherent/plain_rtcIntersect1/threads:1",
      [embree1](benchmark::State& s) { plain_closest_bench(s, SceneKind::kTerrain, embree1, terrain_down_rays); });
  reg("Terrain1M/pick/plain_rtcIntersect1_store/threads:1",
      [embree1](benchmark::State& s) { plain_closest_store_bench(s, SceneKind::kTerrain, embree1, terrain_rays); });
  reg("Terrain1M/visibility/plain_rtcOccluded1/threads:1",
      [embree1](benchmark::State& s) { plain_any_bench(s, SceneKind::kTerrain, embree1, terrain_segs); });

  // Dynamic spheres and capsules.
  for (SceneKind kind : {SceneKind::kSpheres, SceneKind::kCapsules}) {
    const std::string sc = kind == SceneKind::kSpheres ? "Spheres100k" : "Capsules100k";
    for (const Variant& v : variants(kind == SceneKind::kSpheres))
      for (uint32_t t : thread_counts) {
        reg(name(sc, "closest", v.name, t), [kind, v, t](benchmark::State& s) { closest_bench(s, kind, v, t, body_rays); });
        reg(name(sc, "pick", v.name, t), [kind, v, t](benchmark::State& s) { pick_bench(s, kind, v, t, bodies_camera()); });
        reg(name(sc, "visibility", v.name, t), [kind, v, t](benchmark::State& s) { any_bench(s, kind, v, t, body_segs); });
      }
    for (const Variant& v : variants(kind == SceneKind::kSpheres)) {
      if (v.desc.packet_width != 1 || v.desc.backend != RayBackend::kEmbree ||
          v.desc.embree_streams == EmbreeStreams::kAlways)
        continue;
      reg(name(sc, "closest", std::string("plain_rtcIntersect1_") + v.name, 1),
          [kind, v](benchmark::State& s) { plain_closest_bench(s, kind, v, body_rays); });
    }
    // Per-frame update: refit vs rebuild, both backends.
    for (RayBackend b : {RayBackend::kEmbree, RayBackend::kLbvh})
      for (DynamicUpdate u : {DynamicUpdate::kRefit, DynamicUpdate::kRebuildLow, DynamicUpdate::kRebuildMedium})
        for (EmbreeSpheres es : {EmbreeSpheres::kUserGeometry, EmbreeSpheres::kBuiltin}) {
          if ((b == RayBackend::kLbvh || kind == SceneKind::kCapsules) && es == EmbreeSpheres::kBuiltin) continue;
          if (b == RayBackend::kLbvh && u == DynamicUpdate::kRebuildMedium) continue;  // same as low
          for (uint32_t t : thread_counts) {
            RaySceneDesc d;
            d.backend = b;
            d.dynamic_update = u;
            d.embree_spheres = es;
            const char* un = u == DynamicUpdate::kRefit ? "refit" : (u == DynamicUpdate::kRebuildLow ? "rebuild_low" : "rebuild_medium");
            const std::string bn = std::string(b == RayBackend::kEmbree ? (es == EmbreeSpheres::kBuiltin ? "embree_builtin" : "embree") : "lbvh") + "_" + un;
            reg(name(sc, "update", bn, t), [kind, d, t](benchmark::State& s) { update_bench(s, kind, d, t); });
          }
        }
  }

  // Posed shapes: queries on Embree (user geometry, packets) and the LBVH, and the update.
  for (const Variant& v : variants(false)) {
    if (v.desc.packet_width == 16) continue;
    for (uint32_t t : thread_counts) {
      reg(name("Shapes100k", "closest", v.name, t), [v, t](benchmark::State& s) { closest_bench(s, SceneKind::kShapes, v, t, body_rays); });
      reg(name("Shapes100k", "pick", v.name, t), [v, t](benchmark::State& s) { pick_bench(s, SceneKind::kShapes, v, t, bodies_camera()); });
      reg(name("Shapes100k", "visibility", v.name, t), [v, t](benchmark::State& s) { any_bench(s, SceneKind::kShapes, v, t, body_segs); });
    }
  }
  for (RayBackend b : {RayBackend::kEmbree, RayBackend::kLbvh})
    for (DynamicUpdate u : {DynamicUpdate::kRefit, DynamicUpdate::kRebuildLow})
      for (uint32_t t : thread_counts) {
        RaySceneDesc d;
        d.backend = b;
        d.dynamic_update = u;
        const std::string bn = std::string(b == RayBackend::kEmbree ? "embree" : "lbvh") + (u == DynamicUpdate::kRefit ? "_refit" : "_rebuild_low");
        reg(name("Shapes100k", "update", bn, t), [d, t](benchmark::State& s) { update_bench(s, SceneKind::kShapes, d, t); });
        reg(name("World100k", "sync_world", bn, t), [d, t](benchmark::State& s) { world_sync_bench(s, d, t); });
      }

  // Bullet on the same spheres and rays.
  if (bench::bullet_available()) {
    const uint32_t nb = g_quick ? 512 : 8192;  // Bullet is slow: fewer rays, same distribution
    static std::vector<Ray> bullet_rays(body_rays.begin(), body_rays.begin() + std::min<size_t>(nb, body_rays.size()));
    reg("Spheres100k/closest/bullet_rayTest/threads:1", [](benchmark::State& s) {
      const Bodies& b = bodies();
      auto world = bench::make_bullet_spheres(b.x, b.y, b.z, b.r);
      uint64_t hits = 0;
      for (auto _ : s) hits = bench::bullet_ray_test(*world, bullet_rays, 1e4f);
      s.counters["hit%"] = 100.0 * static_cast<double>(hits) / static_cast<double>(bullet_rays.size());
      set_rate(s, bullet_rays.size());
    });
    // Small motion (0.05 m: inside Bullet's fattened AABBs, few tree updates), large
    // motion (1 m: every leaf moves), and explicit removal + re-insertion.
    for (float dx : {0.05f, 1.0f})
      reg("Spheres100k/update/bullet_updateAabbs_dx" + std::string(dx < 0.5f ? "0.05" : "1") + "/threads:1",
          [dx](benchmark::State& s) {
            const Bodies& b = bodies();
            auto world = bench::make_bullet_spheres(b.x, b.y, b.z, b.r);
            for (auto _ : s) bench::bullet_move_all(*world, dx);
          });
    reg("Spheres100k/update/bullet_reinsert/threads:1", [](benchmark::State& s) {
      const Bodies& b = bodies();
      auto world = bench::make_bullet_spheres(b.x, b.y, b.z, b.r);
      for (auto _ : s) bench::bullet_reinsert_all(*world, 0.05f);
    });
  }
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<char*> args;
  for (int i = 0; i < argc; ++i) {
    if (std::strcmp(argv[i], "--quick") == 0) {
      g_quick = true;
      continue;
    }
    args.push_back(argv[i]);
  }
  int n = static_cast<int>(args.size());
  benchmark::Initialize(&n, args.data());
  if (benchmark::ReportUnrecognizedArguments(n, args.data())) return 2;
  register_all();
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
