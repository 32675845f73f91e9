// RayScene against the double-precision brute force of tests/kernels/raycast/ray_reference.h,
// for every backend configuration: random rays (some inside shapes, axis-aligned, with
// finite tmax, masks), segments, a scene 1e5 m from the origin, edges and vertices of a
// closed grid, rays parallel to faces, tmax = 0, very long rays, dynamic updates (refit
// and rebuild), thread-count independence, picking, World sync and bad input.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include "impact/impact.h"
#include "kernels/raycast/ray_reference.h"
#include "support/test_support.h"

namespace impact::test {
namespace {

struct Config {
  const char* name;
  RaySceneDesc desc;
};

std::vector<Config> configs() {
  std::vector<Config> c;
  RaySceneDesc d;
  d.backend = RayBackend::kLbvh;
  c.push_back({"lbvh", d});
  d.backend = RayBackend::kEmbree;
  c.push_back({"embree", d});
  d.packet_width = 8;
  c.push_back({"embree_packet8", d});
  d.packet_width = 16;
  c.push_back({"embree_packet16", d});
  d.packet_width = 8;
  d.robust = false;
  c.push_back({"embree_packet8_fast", d});
  d.packet_width = 1;
  c.push_back({"embree_fast", d});
  d.robust = true;
  d.embree_streams = EmbreeStreams::kAlways;  // streams of 64 rays for every query
  c.push_back({"embree_stream", d});
  return c;
}

std::unique_ptr<RayScene> make_scene(const RaySceneDesc& d) {
  std::unique_ptr<RayScene> s;
  EXPECT_TRUE(IsOk(RayScene::create(d, &s)));
  return s;
}

// Geometry kept as float arrays (what the scene gets) and as the reference.
struct TestGeometry {
  std::vector<Grid> meshes;
  std::vector<uint32_t> mesh_layers;
  std::vector<float> sx, sy, sz, sr;
  std::vector<uint32_t> sl;
  Eigen::Matrix3Xf ca, cb;
  std::vector<float> cr;
  std::vector<uint32_t> cl;
  Eigen::Matrix3Xf pn;
  std::vector<float> poff;
  std::vector<uint32_t> pl;
  RefScene ref;

  void load(RayScene& s) {
    for (size_t m = 0; m < meshes.size(); ++m) {
      MeshHandle h;
      IMPACT_ASSERT_OK(s.add_mesh(meshes[m].v, meshes[m].t, mesh_layers[m], &h));
      ASSERT_EQ(h.id, m);
    }
    IMPACT_ASSERT_OK(s.set_spheres(sx, sy, sz, sr, sl));
    IMPACT_ASSERT_OK(s.set_capsules(ca, cb, cr, cl));
    IMPACT_ASSERT_OK(s.set_planes(pn, poff, pl));
    IMPACT_ASSERT_OK(s.commit());
  }

  void build_ref() {
    ref = RefScene{};
    for (size_t m = 0; m < meshes.size(); ++m)
      add_mesh_ref(ref, meshes[m].v, meshes[m].t, static_cast<uint32_t>(m), mesh_layers[m]);
    for (size_t i = 0; i < sx.size(); ++i) {
      ref.sc.emplace_back(sx[i], sy[i], sz[i]);
      ref.sr.push_back(sr[i]);
      ref.s_layer.push_back(sl[i]);
    }
    for (Eigen::Index i = 0; i < ca.cols(); ++i) {
      ref.ca.push_back(ca.col(i).cast<double>());
      ref.cb.push_back(cb.col(i).cast<double>());
      ref.cr.push_back(cr[i]);
      ref.c_layer.push_back(cl[i]);
    }
    for (Eigen::Index i = 0; i < pn.cols(); ++i) {
      const double len = pn.col(i).cast<double>().norm();
      ref.pn.push_back(pn.col(i).cast<double>() / len);
      ref.poff.push_back(poff[i] / len);
      ref.p_layer.push_back(pl[i]);
    }
  }
};

TestGeometry random_geometry(uint32_t seed, float off, uint32_t spheres = 200, uint32_t capsules = 100) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> pos(-10.0f, 10.0f), unit(-1.0f, 1.0f), u01(0.0f, 1.0f);
  std::uniform_int_distribution<int> bit(0, 2);
  TestGeometry g;
  const Eigen::Vector3f o(off, off, off);
  // Mesh 0: a wavy closed grid; mesh 1: a random triangle soup.
  g.meshes.push_back(make_grid(24, 24, 1.0f, o + Eigen::Vector3f(-12, -4, -12),
                               [](float x, float z) { return 0.7f * std::sin(0.5f * x) * std::cos(0.3f * z); }));
  g.mesh_layers.push_back(1u);
  Grid soup;
  const int tris = 300;
  soup.v.resize(3, 3 * tris);
  soup.t.resize(3, tris);
  for (int i = 0; i < tris; ++i) {
    const Eigen::Vector3f c(pos(rng), pos(rng), pos(rng));
    for (int k = 0; k < 3; ++k) soup.v.col(3 * i + k) = o + c + 1.5f * Eigen::Vector3f(unit(rng), unit(rng), unit(rng));
    soup.t.col(i) = Eigen::Matrix<uint32_t, 3, 1>(3 * i, 3 * i + 1, 3 * i + 2);
  }
  g.meshes.push_back(soup);
  g.mesh_layers.push_back(2u);
  for (uint32_t i = 0; i < spheres; ++i) {
    g.sx.push_back(off + pos(rng));
    g.sy.push_back(off + pos(rng));
    g.sz.push_back(off + pos(rng));
    g.sr.push_back(0.2f + 0.8f * u01(rng));
    g.sl.push_back(1u << bit(rng));
  }
  g.ca.resize(3, capsules);
  g.cb.resize(3, capsules);
  for (uint32_t i = 0; i < capsules; ++i) {
    const Eigen::Vector3f a(pos(rng), pos(rng), pos(rng));
    g.ca.col(i) = o + a;
    // Some capsules axis-aligned (rays along their axis), some zero length.
    Eigen::Vector3f ax = 3.0f * Eigen::Vector3f(unit(rng), unit(rng), unit(rng));
    if (i % 7 == 0) ax = Eigen::Vector3f(0, 2.5f, 0);
    if (i % 13 == 0) ax.setZero();
    g.cb.col(i) = o + a + ax;
    g.cr.push_back(0.1f + 0.5f * u01(rng));
    g.cl.push_back(1u << bit(rng));
  }
  g.pn.resize(3, 1);
  g.pn.col(0) = Eigen::Vector3f(0, 2, 0);  // not unit on purpose
  g.poff.push_back(2.0f * (off - 12.0f));  // y <= off - 12
  g.pl.push_back(1u);
  g.build_ref();
  return g;
}

std::vector<Ray> random_rays(uint32_t n, uint32_t seed, float off) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> pos(-14.0f, 14.0f), unit(-1.0f, 1.0f), u01(0.0f, 1.0f);
  std::uniform_int_distribution<int> axis(0, 5);
  std::vector<Ray> rays(n);
  for (uint32_t i = 0; i < n; ++i) {
    Ray& r = rays[i];
    r.origin = Eigen::Vector3f(off + pos(rng), off + pos(rng), off + pos(rng));
    Eigen::Vector3f d(unit(rng), unit(rng), unit(rng));
    if (i % 10 == 3) {  // axis-aligned
      const int a = axis(rng);
      d.setZero();
      d[a % 3] = a < 3 ? 1.0f : -1.0f;
    }
    if (d.squaredNorm() < 1e-6f) d = Eigen::Vector3f(0, -1, 0);
    d *= std::pow(10.0f, 6.0f * u01(rng) - 3.0f);  // unnormalised: 1e-3 .. 1e3
    r.direction = d;
    const float k = u01(rng);
    r.tmax = k < 0.7f ? std::numeric_limits<float>::infinity() : (k < 0.95f ? 20.0f * u01(rng) : 0.0f);
    r.mask = i % 3 == 0 ? (1u << (i % 4)) | 8u : 0xffffffffu;
  }
  return rays;
}

void expect_matches_reference(const TestGeometry& g, const std::vector<Ray>& rays, const std::vector<RayHit>& hits,
                              const std::string& what, size_t max_report = 5) {
  size_t bad = 0;
  for (size_t i = 0; i < rays.size(); ++i) {
    const std::string e = check_closest(g.ref, rays[i], hits[i]);
    if (!e.empty() && ++bad <= max_report) ADD_FAILURE() << what << " ray " << i << ": " << e;
  }
  EXPECT_EQ(bad, 0u) << what;
}

bool same_bits(const RayHit& a, const RayHit& b) {
  return a.kind == b.kind && a.id == b.id && a.prim == b.prim && a.body == b.body &&
         std::memcmp(&a.t, &b.t, sizeof(float)) == 0 && std::memcmp(a.point.data(), b.point.data(), 12) == 0 &&
         std::memcmp(a.normal.data(), b.normal.data(), 12) == 0;
}

// --- closest hit against the reference ------------------------------------------------

class RaycastReference : public ::testing::TestWithParam<int> {};

TEST_P(RaycastReference, RandomRaysMatchBruteForce) {
  const Config c = configs()[static_cast<size_t>(GetParam())];
  for (float off : {0.0f, 1e5f}) {
    const TestGeometry g = random_geometry(7, off);
    auto scene = make_scene(c.desc);
    ASSERT_TRUE(scene);
    TestGeometry gl = g;
    gl.load(*scene);
    const auto rays = random_rays(scaled(3000), 11, off);
    std::vector<RayHit> hits(rays.size());
    IMPACT_ASSERT_OK(scene->closest_hit(rays, hits));
    expect_matches_reference(g, rays, hits, std::string(c.name) + " offset " + std::to_string(off));
    size_t n_hit = 0, n_zero = 0;
    for (const auto& h : hits) {
      n_hit += h.hit();
      n_zero += h.hit() && h.t == 0.0f;
    }
    // The scene is dense enough that most rays hit, and some start inside a solid.
    EXPECT_GT(n_hit, rays.size() / 3);
    EXPECT_GT(n_zero, 10u);
  }
}

TEST_P(RaycastReference, SegmentsMatchBruteForce) {
  const Config c = configs()[static_cast<size_t>(GetParam())];
  for (float off : {0.0f, 1e5f}) {
    TestGeometry g = random_geometry(8, off);
    auto scene = make_scene(c.desc);
    g.load(*scene);
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> pos(-14.0f, 14.0f);
    std::vector<Segment> segs(scaled(3000));
    for (size_t i = 0; i < segs.size(); ++i) {
      segs[i].from = Eigen::Vector3f(off + pos(rng), off + pos(rng), off + pos(rng));
      segs[i].to = i % 50 == 0 ? segs[i].from : Eigen::Vector3f(off + pos(rng), off + pos(rng), off + pos(rng));
      segs[i].mask = i % 4 == 0 ? 2u : 0xffffffffu;
    }
    std::vector<uint8_t> occ(segs.size());
    IMPACT_ASSERT_OK(scene->any_hit(segs, occ));
    size_t bad = 0, n_occ = 0;
    for (size_t i = 0; i < segs.size(); ++i) {
      n_occ += occ[i];
      const std::string e = check_any(g.ref, segs[i], occ[i] != 0);
      if (!e.empty() && ++bad <= 5) ADD_FAILURE() << c.name << " segment " << i << ": " << e;
      if (i % 50 == 0) {
        EXPECT_EQ(occ[i], 0) << "zero-length segment " << i;
      }
    }
    EXPECT_EQ(bad, 0u);
    EXPECT_GT(n_occ, segs.size() / 4);
    EXPECT_LT(n_occ, segs.size());
  }
}

TEST_P(RaycastReference, DynamicUpdatesRefitAndRebuild) {
  const Config c = configs()[static_cast<size_t>(GetParam())];
  for (DynamicUpdate u : {DynamicUpdate::kRefit, DynamicUpdate::kRebuildLow, DynamicUpdate::kRebuildMedium}) {
    RaySceneDesc d = c.desc;
    d.dynamic_update = u;
    auto scene = make_scene(d);
    TestGeometry g = random_geometry(9, 0.0f);
    g.load(*scene);
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> step(-2.0f, 2.0f);
    for (int frame = 0; frame < 3; ++frame) {
      // Move every sphere and capsule (same counts: an update, refit when asked).
      for (size_t i = 0; i < g.sx.size(); ++i) {
        g.sx[i] += step(rng);
        g.sy[i] += step(rng);
      }
      for (Eigen::Index i = 0; i < g.ca.cols(); ++i) {
        const Eigen::Vector3f dv(step(rng), step(rng), step(rng));
        g.ca.col(i) += dv;
        g.cb.col(i) += dv;
      }
      IMPACT_ASSERT_OK(scene->set_spheres(g.sx, g.sy, g.sz, g.sr, g.sl));
      IMPACT_ASSERT_OK(scene->set_capsules(g.ca, g.cb, g.cr, g.cl));
      IMPACT_ASSERT_OK(scene->commit());
      EXPECT_EQ(scene->info().dynamic_rebuilt, u != DynamicUpdate::kRefit);
      g.build_ref();
      const auto rays = random_rays(1000, 20 + static_cast<uint32_t>(frame), 0.0f);
      std::vector<RayHit> hits(rays.size());
      IMPACT_ASSERT_OK(scene->closest_hit(rays, hits));
      expect_matches_reference(g, rays, hits, std::string(c.name) + " frame " + std::to_string(frame));
    }
    // A count change rebuilds whatever the knob says.
    g.sx.pop_back();
    g.sy.pop_back();
    g.sz.pop_back();
    g.sr.pop_back();
    g.sl.pop_back();
    IMPACT_ASSERT_OK(scene->set_spheres(g.sx, g.sy, g.sz, g.sr, g.sl));
    IMPACT_ASSERT_OK(scene->commit());
    EXPECT_TRUE(scene->info().dynamic_rebuilt);
    g.build_ref();
    const auto rays = random_rays(1000, 40, 0.0f);
    std::vector<RayHit> hits(rays.size());
    IMPACT_ASSERT_OK(scene->closest_hit(rays, hits));
    expect_matches_reference(g, rays, hits, std::string(c.name) + " after resize");
  }
}

TEST_P(RaycastReference, ThreadCountsGiveIdenticalResults) {
  const Config c = configs()[static_cast<size_t>(GetParam())];
  TestGeometry g = random_geometry(10, 0.0f);
  auto scene = make_scene(c.desc);
  g.load(*scene);
  const auto rays = random_rays(scaled(2000), 12, 0.0f);
  std::vector<Segment> segs(rays.size());
  for (size_t i = 0; i < rays.size(); ++i) segs[i] = {rays[i].origin, rays[i].origin + 30.0f * rays[i].direction.normalized(), rays[i].mask};
  std::vector<RayHit> first;
  std::vector<uint8_t> first_occ;
  for (const ExecCase& e : exec_cases()) {
    IMPACT_ASSERT_OK(scene->set_threads(e.backend, e.threads));
    std::vector<RayHit> hits(rays.size());
    std::vector<uint8_t> occ(rays.size());
    IMPACT_ASSERT_OK(scene->closest_hit(rays, hits));
    IMPACT_ASSERT_OK(scene->any_hit(segs, occ));
    if (first.empty()) {
      first = hits;
      first_occ = occ;
      continue;
    }
    for (size_t i = 0; i < rays.size(); ++i) ASSERT_TRUE(same_bits(first[i], hits[i])) << c.name << " " << to_string(e) << " ray " << i;
    ASSERT_EQ(first_occ, occ) << c.name << " " << to_string(e);
  }
}

INSTANTIATE_TEST_SUITE_P(Backends, RaycastReference, ::testing::Range(0, static_cast<int>(configs().size())),
                         [](const ::testing::TestParamInfo<int>& i) { return std::string(configs()[static_cast<size_t>(i.param)].name); });

// --- backends agree with each other -----------------------------------------------------

TEST(Raycast, EmbreeAndLbvhAgree) {
  TestGeometry g = random_geometry(21, 0.0f);
  RaySceneDesc d;
  d.backend = RayBackend::kLbvh;
  auto a = make_scene(d);
  d.backend = RayBackend::kEmbree;
  auto b = make_scene(d);
  g.load(*a);
  g.load(*b);
  const auto rays = random_rays(scaled(4000), 22, 0.0f);
  std::vector<RayHit> ha(rays.size()), hb(rays.size());
  IMPACT_ASSERT_OK(a->closest_hit(rays, ha));
  IMPACT_ASSERT_OK(b->closest_hit(rays, hb));
  size_t differ = 0;
  for (size_t i = 0; i < rays.size(); ++i) {
    ASSERT_EQ(ha[i].hit(), hb[i].hit()) << "ray " << i;
    if (!ha[i].hit()) continue;
    EXPECT_NEAR(ha[i].t, hb[i].t, 1e-4 * (1.0 + ha[i].t)) << "ray " << i;
    if (ha[i].kind != hb[i].kind || ha[i].id != hb[i].id || ha[i].prim != hb[i].prim) {
      // Different primitives only on ties: both must be acceptable to the reference.
      ++differ;
      EXPECT_EQ(check_closest(g.ref, rays[i], ha[i]), "") << "lbvh ray " << i;
      EXPECT_EQ(check_closest(g.ref, rays[i], hb[i]), "") << "embree ray " << i;
      std::printf("ray %zu: lbvh kind %d id %u prim %u t %.9g; embree kind %d id %u prim %u t %.9g\n", i,
                  static_cast<int>(ha[i].kind), ha[i].id, ha[i].prim, static_cast<double>(ha[i].t),
                  static_cast<int>(hb[i].kind), hb[i].id, hb[i].prim, static_cast<double>(hb[i].t));
    }
  }
  EXPECT_LE(differ, rays.size() / 1000);
}

// --- edges, vertices, parallel rays, tmax, long rays --------------------------------------

// A flat grid at y = 0 on integer coordinates: vertical rays through vertices and edge
// midpoints are exact in float, so they hit exactly on shared edges.
TEST(Raycast, EdgesAndVerticesOfAClosedGridNeverLeak) {
  for (const Config& c : configs()) {
    auto scene = make_scene(c.desc);
    const Grid grid = make_grid(8, 8, 1.0f, Eigen::Vector3f(-4, 0, -4), [](float, float) { return 0.0f; });
    MeshHandle h;
    IMPACT_ASSERT_OK(scene->add_mesh(grid.v, grid.t, 1u, &h));
    IMPACT_ASSERT_OK(scene->commit());
    RefScene ref;
    add_mesh_ref(ref, grid.v, grid.t, 0, 1u);
    std::vector<Ray> rays;
    for (int i = 0; i <= 16; ++i)
      for (int j = 0; j <= 16; ++j) {
        Ray r;
        r.origin = Eigen::Vector3f(-4.0f + 0.5f * static_cast<float>(i), 5.0f, -4.0f + 0.5f * static_cast<float>(j));
        r.direction = Eigen::Vector3f(0, -1, 0);
        rays.push_back(r);
        r.origin.y() = -5.0f;  // from below: two-sided
        r.direction = Eigen::Vector3f(0, 1, 0);
        rays.push_back(r);
      }
    // Oblique rays through the grid vertices.
    for (int i = 1; i < 8; ++i) {
      Ray r;
      r.origin = Eigen::Vector3f(-4.0f + static_cast<float>(i) - 3.0f, 3.0f, -4.0f + static_cast<float>(i) - 3.0f);
      r.direction = Eigen::Vector3f(1, -1, 1);
      rays.push_back(r);
    }
    std::vector<RayHit> hits(rays.size());
    IMPACT_ASSERT_OK(scene->closest_hit(rays, hits));
    for (size_t i = 0; i < rays.size(); ++i) {
      // Embree may leave out points on the outer boundary of an open mesh (its edge
      // rule is not "closed triangles"); interior edges and vertices must never leak.
      const bool boundary = std::fabs(rays[i].origin.x()) == 4.0f || std::fabs(rays[i].origin.z()) == 4.0f;
      if (c.desc.backend == RayBackend::kEmbree && boundary && !hits[i].hit()) continue;
      ASSERT_TRUE(hits[i].hit()) << c.name << " ray " << i << " leaked through the grid at "
                                 << rays[i].origin.transpose();
      EXPECT_NEAR(hits[i].point.y(), 0.0f, 1e-6f) << c.name << " ray " << i;
      // The triangle reported must contain the point (closed triangle).
      const auto& t = ref.tris[hits[i].prim];
      const V3 p = hits[i].point.cast<double>();
      const RefHit rh = ref_triangle(p + V3(0, 1, 0), V3(0, -1, 0), 2.0, ref.verts[t[0]], ref.verts[t[1]], ref.verts[t[2]]);
      EXPECT_NE(rh.state, Ref::kMiss) << c.name << " ray " << i << " reported triangle " << hits[i].prim << " not containing the point";
      EXPECT_FLOAT_EQ(std::fabs(hits[i].normal.y()), 1.0f);
      EXPECT_LE(hits[i].normal.dot(rays[i].direction), 0.0f);
    }
    // LBVH: a tie between triangles goes to the lower index. Vertex (0, 0, 0) is shared
    // by 6 triangles; the lowest index among them is reported.
    if (c.desc.backend == RayBackend::kLbvh) {
      Ray r;
      r.origin = Eigen::Vector3f(0, 1, 0);
      r.direction = Eigen::Vector3f(0, -1, 0);
      RayHit hit;
      IMPACT_ASSERT_OK(scene->closest_hit({&r, 1}, {&hit, 1}));
      uint32_t lowest = 0xffffffffu;
      for (uint32_t t = 0; t < ref.tris.size(); ++t)
        for (int k = 0; k < 3; ++k)
          if (ref.verts[ref.tris[t][k]].norm() == 0.0) lowest = std::min(lowest, t);
      EXPECT_EQ(hit.prim, lowest);
    }
  }
}

TEST(Raycast, RaysParallelToFacesAndTmax) {
  for (const Config& c : configs()) {
    auto scene = make_scene(c.desc);
    const Grid grid = make_grid(8, 8, 1.0f, Eigen::Vector3f(-4, 0, -4), [](float, float) { return 0.0f; });
    MeshHandle h;
    IMPACT_ASSERT_OK(scene->add_mesh(grid.v, grid.t, 1u, &h));
    const std::vector<float> sx{0.0f}, sy{3.0f}, sz{0.0f}, sr{1.0f};
    IMPACT_ASSERT_OK(scene->set_spheres(sx, sy, sz, sr));
    IMPACT_ASSERT_OK(scene->commit());
    std::vector<Ray> rays(6);
    rays[0].origin = Eigen::Vector3f(-10, 0, 0.3f);  // in the grid's plane: misses it
    rays[0].direction = Eigen::Vector3f(1, 0, 0);
    rays[1].origin = Eigen::Vector3f(-10, 1e-3f, 0.3f);  // just above, parallel
    rays[1].direction = Eigen::Vector3f(1, 0, 0);
    rays[2].origin = Eigen::Vector3f(0, 3, 0);  // inside the sphere, tmax 0: no hit
    rays[2].direction = Eigen::Vector3f(1, 0, 0);
    rays[2].tmax = 0.0f;
    rays[3].origin = Eigen::Vector3f(0, 3, 0);  // inside: t = 0, normal = -dir
    rays[3].direction = Eigen::Vector3f(0, 0, 2);
    rays[4].origin = Eigen::Vector3f(0, 10, 0);  // stops 1 mm short of the sphere
    rays[4].direction = Eigen::Vector3f(0, -1, 0);
    rays[4].tmax = 5.999f;
    rays[5].origin = Eigen::Vector3f(1e6f, 3.0f, 0);  // very long ray, grazing the sphere top
    rays[5].direction = Eigen::Vector3f(-1, 0, 0);
    std::vector<RayHit> hits(rays.size());
    IMPACT_ASSERT_OK(scene->closest_hit(rays, hits));
    EXPECT_FALSE(hits[0].hit()) << c.name;
    EXPECT_FALSE(hits[1].hit()) << c.name;
    EXPECT_FALSE(hits[2].hit()) << c.name;
    ASSERT_TRUE(hits[3].hit()) << c.name;
    EXPECT_EQ(hits[3].t, 0.0f);
    EXPECT_EQ(hits[3].kind, HitKind::kSphere);
    EXPECT_TRUE(hits[3].normal.isApprox(Eigen::Vector3f(0, 0, -1))) << hits[3].normal.transpose();
    EXPECT_FALSE(hits[4].hit()) << c.name;
    ASSERT_TRUE(hits[5].hit()) << c.name;
    EXPECT_NEAR(hits[5].t, 1e6f - 1.0f, 1.0f) << c.name;  // relative 1e-6 of a 1e6 m ray
  }
}

// --- layers, picking, World sync -----------------------------------------------------------

TEST(Raycast, LayerMasksSelectPrimitives) {
  for (const Config& c : configs()) {
    for (EmbreeSpheres es : {EmbreeSpheres::kUserGeometry, EmbreeSpheres::kBuiltin}) {
      RaySceneDesc d = c.desc;
      d.embree_spheres = es;
      auto scene = make_scene(d);
      // Three spheres in a row along +x with layers 1, 2, 4.
      const std::vector<float> sx{2, 4, 6}, sy{0, 0, 0}, sz{0, 0, 0}, sr{0.5f, 0.5f, 0.5f};
      const std::vector<uint32_t> sl{1, 2, 4};
      IMPACT_ASSERT_OK(scene->set_spheres(sx, sy, sz, sr, sl));
      IMPACT_ASSERT_OK(scene->commit());
      for (uint32_t mask : {7u, 6u, 4u, 8u, 5u}) {
        Ray r;
        r.direction = Eigen::Vector3f(1, 0, 0);
        r.mask = mask;
        RayHit h;
        IMPACT_ASSERT_OK(scene->closest_hit({&r, 1}, {&h, 1}));
        const int expect = (mask & 1) ? 0 : (mask & 2) ? 1 : (mask & 4) ? 2 : -1;
        if (expect < 0) {
          EXPECT_FALSE(h.hit()) << c.name << " mask " << mask;
        } else {
          ASSERT_TRUE(h.hit()) << c.name << " mask " << mask;
          EXPECT_EQ(h.id, static_cast<uint32_t>(expect)) << c.name << " mask " << mask;
          EXPECT_NEAR(h.t, 1.5f + 2.0f * static_cast<float>(expect), 1e-5f);
        }
        Segment s{Eigen::Vector3f::Zero(), Eigen::Vector3f(10, 0, 0), mask};
        uint8_t occ = 0;
        IMPACT_ASSERT_OK(scene->any_hit({&s, 1}, {&occ, 1}));
        EXPECT_EQ(occ, expect >= 0 ? 1 : 0) << c.name << " mask " << mask;
      }
    }
  }
}

TEST(Raycast, BuiltinEmbreeSpheresMatchFromOutside) {
  // Embree's own sphere points agree with the rules for rays that start outside every
  // sphere (inside, they report the far side: documented).
  TestGeometry g = random_geometry(31, 0.0f);
  RaySceneDesc d;
  d.embree_spheres = EmbreeSpheres::kBuiltin;
  auto scene = make_scene(d);
  g.load(*scene);
  auto rays = random_rays(scaled(3000), 32, 0.0f);
  std::vector<Ray> outside;
  for (const Ray& r : rays) {
    bool in = false;
    for (size_t i = 0; i < g.sx.size(); ++i)
      in |= (r.origin - Eigen::Vector3f(g.sx[i], g.sy[i], g.sz[i])).norm() <= g.sr[i] * 1.001f;
    if (!in) outside.push_back(r);
  }
  std::vector<RayHit> hits(outside.size());
  IMPACT_ASSERT_OK(scene->closest_hit(outside, hits));
  expect_matches_reference(g, outside, hits, "embree builtin spheres");
}

TEST(Raycast, PickMatchesCameraRays) {
  for (const Config& c : configs()) {
    TestGeometry g = random_geometry(41, 0.0f);
    auto scene = make_scene(c.desc);
    g.load(*scene);
    Camera cam;
    cam.position = Eigen::Vector3f(0, 2, 25);
    cam.forward = Eigen::Vector3f(0, -0.1f, -1);
    cam.aspect = 1.5f;
    std::vector<Eigen::Vector2f> screen;
    for (int j = 0; j < 30; ++j)
      for (int i = 0; i < 40; ++i) screen.emplace_back((static_cast<float>(i) + 0.5f) / 40.0f, (static_cast<float>(j) + 0.5f) / 30.0f);
    std::vector<RayHit> picked(screen.size()), direct(screen.size());
    IMPACT_ASSERT_OK(scene->pick(cam, screen, 0xffffffffu, picked));
    std::vector<Ray> rays(screen.size());
    IMPACT_ASSERT_OK(camera_rays(cam, screen, 0xffffffffu, rays));
    IMPACT_ASSERT_OK(scene->closest_hit(rays, direct));
    for (size_t i = 0; i < rays.size(); ++i) ASSERT_TRUE(same_bits(picked[i], direct[i])) << c.name << " " << i;
    expect_matches_reference(g, rays, picked, std::string(c.name) + " pick");
    // The centre ray runs along forward; the top-left corner ray leans left and up.
    Ray centre;
    IMPACT_ASSERT_OK(camera_rays(cam, std::vector<Eigen::Vector2f>{{0.5f, 0.5f}}, ~0u, {&centre, 1}));
    EXPECT_TRUE(centre.direction.isApprox(cam.forward.normalized(), 1e-6f));
    Ray corner;
    IMPACT_ASSERT_OK(camera_rays(cam, std::vector<Eigen::Vector2f>{{0.0f, 0.0f}}, ~0u, {&corner, 1}));
    EXPECT_LT(corner.direction.x(), 0.0f);
    EXPECT_GT(corner.direction.y(), centre.direction.y());
  }
}

TEST(Raycast, PickStreamsOnMeshOnlyScenes) {
  // kAuto traces pick() as streams when the Embree geometry is meshes only: the hits
  // still follow the reference and name the same triangles as one call per ray.
  TestGeometry g = random_geometry(43, 0.0f, 0, 0);
  RaySceneDesc d;
  auto streamed = make_scene(d);
  d.embree_streams = EmbreeStreams::kNever;
  auto single = make_scene(d);
  g.load(*streamed);
  g.load(*single);
  Camera cam;
  cam.position = Eigen::Vector3f(-3, 6, 20);
  cam.forward = Eigen::Vector3f(0.1f, -0.3f, -1);
  std::vector<Eigen::Vector2f> screen;
  for (int j = 0; j < 48; ++j)
    for (int i = 0; i < 64; ++i) screen.emplace_back((static_cast<float>(i) + 0.5f) / 64.0f, (static_cast<float>(j) + 0.5f) / 48.0f);
  std::vector<RayHit> a(screen.size()), b(screen.size());
  IMPACT_ASSERT_OK(streamed->pick(cam, screen, ~0u, a));
  IMPACT_ASSERT_OK(single->pick(cam, screen, ~0u, b));
  std::vector<Ray> rays(screen.size());
  IMPACT_ASSERT_OK(camera_rays(cam, screen, ~0u, rays));
  expect_matches_reference(g, rays, a, "streamed pick");
  size_t hits = 0;
  for (size_t i = 0; i < a.size(); ++i) {
    hits += a[i].hit();
    ASSERT_EQ(a[i].kind, b[i].kind) << i;
    if (!a[i].hit()) continue;
    EXPECT_EQ(a[i].id, b[i].id) << i;
    EXPECT_NEAR(a[i].t, b[i].t, 1e-5f * b[i].t) << i;
  }
  EXPECT_GT(hits, screen.size() / 2);
}

TEST(Raycast, SyncSpheresFromWorldReportsBodies) {
  for (const Config& c : configs()) {
    auto world = make_world(zero_gravity_desc());
    std::vector<BodyDesc> bodies(3);
    for (int i = 0; i < 3; ++i) {
      bodies[i].position = Eigen::Vector3f(5.0f * static_cast<float>(i + 1), 0, 0);
      bodies[i].radius = 1.0f;
      bodies[i].layer = 1u << i;
    }
    std::vector<BodyHandle> handles(3);
    IMPACT_ASSERT_OK(world->create_bodies(bodies, handles));
    auto scene = make_scene(c.desc);
    IMPACT_ASSERT_OK(scene->sync_spheres(*world));
    IMPACT_ASSERT_OK(scene->commit());
    Ray r;
    r.direction = Eigen::Vector3f(1, 0, 0);
    r.mask = 2u;  // sees only the second body
    RayHit h;
    IMPACT_ASSERT_OK(scene->closest_hit({&r, 1}, {&h, 1}));
    ASSERT_TRUE(h.hit());
    EXPECT_EQ(h.body, handles[1]);
    EXPECT_NEAR(h.t, 9.0f, 1e-5f);
    EXPECT_TRUE(h.normal.isApprox(Eigen::Vector3f(-1, 0, 0)));
  }
}

// --- bad input ----------------------------------------------------------------------------

TEST(Raycast, BadInputIsRejectedNamingIndexAndField) {
  for (const Config& c : configs()) {
    auto scene = make_scene(c.desc);
    const std::vector<float> one{1.0f}, zero{0.0f}, nan{std::nanf("")};
    IMPACT_ASSERT_OK(scene->set_spheres(zero, zero, zero, one));
    // Queries before commit are refused.
    {
      Ray r;
      RayHit h;
      EXPECT_TRUE(IsError(scene->closest_hit({&r, 1}, {&h, 1}), StatusCode::kInvalidArgument, {"commit"}));
    }
    IMPACT_ASSERT_OK(scene->commit());
    const float inf = std::numeric_limits<float>::infinity();
    std::vector<Ray> rays(8);
    for (auto& r : rays) r.origin = Eigen::Vector3f(0, 0, -5);
    std::vector<RayHit> hits(rays.size());
    auto expect_ray_error = [&](size_t i, const char* field) {
      EXPECT_TRUE(IsError(scene->closest_hit(rays, hits), StatusCode::kInvalidArgument, {("ray " + std::to_string(i)).c_str(), field}))
          << c.name;
    };
    IMPACT_EXPECT_OK(scene->closest_hit(rays, hits));
    rays[5].direction = Eigen::Vector3f::Zero();
    expect_ray_error(5, "direction");
    rays[5].direction = Eigen::Vector3f(nan[0], 0, 1);
    expect_ray_error(5, "direction");
    rays[5].direction = Eigen::Vector3f(inf, 0, 1);
    expect_ray_error(5, "direction");
    rays[5].direction = Eigen::Vector3f(0, 0, 1);
    rays[3].origin = Eigen::Vector3f(0, nan[0], 0);
    expect_ray_error(3, "origin");  // the lowest bad index is reported
    rays[3].origin = Eigen::Vector3f::Zero();
    rays[7].tmax = -1.0f;
    expect_ray_error(7, "tmax");
    rays[7].tmax = nan[0];
    expect_ray_error(7, "tmax");
    rays[7].tmax = inf;
    IMPACT_EXPECT_OK(scene->closest_hit(rays, hits));
    hits.pop_back();
    EXPECT_TRUE(IsError(scene->closest_hit(rays, hits), StatusCode::kSizeMismatch));
    // Segments.
    std::vector<Segment> segs(4);
    segs[2].to = Eigen::Vector3f(inf, 0, 0);
    std::vector<uint8_t> occ(segs.size());
    EXPECT_TRUE(IsError(scene->any_hit(segs, occ), StatusCode::kInvalidArgument, {"segment 2", "to"}));
    // Geometry.
    EXPECT_TRUE(IsError(scene->set_spheres(zero, zero, zero, zero), StatusCode::kInvalidArgument, {"sphere 0", "radius"}));
    EXPECT_TRUE(IsError(scene->set_spheres(nan, zero, zero, one), StatusCode::kInvalidArgument, {"sphere 0", "centre"}));
    EXPECT_TRUE(IsError(scene->set_spheres(zero, zero, zero, std::vector<float>{1, 1}), StatusCode::kSizeMismatch));
    Eigen::Matrix3Xf a = Eigen::Matrix3Xf::Zero(3, 2), b = Eigen::Matrix3Xf::Ones(3, 2);
    b(1, 1) = inf;
    EXPECT_TRUE(IsError(scene->set_capsules(a, b, std::vector<float>{1, 1}), StatusCode::kInvalidArgument, {"capsule 1", "b"}));
    Eigen::Matrix3Xf n = Eigen::Matrix3Xf::Zero(3, 1);
    EXPECT_TRUE(IsError(scene->set_planes(n, zero), StatusCode::kInvalidArgument, {"plane 0", "normal"}));
    Eigen::Matrix3Xf v = Eigen::Matrix3Xf::Zero(3, 3);
    Eigen::Matrix<uint32_t, 3, Eigen::Dynamic> t(3, 1);
    t << 0, 1, 3;
    MeshHandle mh;
    EXPECT_TRUE(IsError(scene->add_mesh(v, t, 1u, &mh), StatusCode::kInvalidArgument, {"triangle 0", "index 3"}));
    v(0, 1) = nan[0];
    t(2, 0) = 2;
    EXPECT_TRUE(IsError(scene->add_mesh(v, t, 1u, &mh), StatusCode::kInvalidArgument, {"vertex 1"}));
    // Camera.
    Camera cam;
    cam.up = cam.forward;
    std::vector<Eigen::Vector2f> screen{{0.5f, 0.5f}};
    std::vector<RayHit> ph(1);
    EXPECT_TRUE(IsError(scene->pick(cam, screen, ~0u, ph), StatusCode::kInvalidArgument, {"up"}));
    cam = Camera{};
    cam.vertical_fov = 0.0f;
    EXPECT_TRUE(IsError(scene->pick(cam, screen, ~0u, ph), StatusCode::kInvalidArgument, {"vertical_fov"}));
    cam = Camera{};
    screen[0].x() = nan[0];
    EXPECT_TRUE(IsError(scene->pick(cam, screen, ~0u, ph), StatusCode::kInvalidArgument, {"screen point 0"}));
  }
  RaySceneDesc d;
  d.packet_width = 3;
  std::unique_ptr<RayScene> s;
  EXPECT_TRUE(IsError(RayScene::create(d, &s), StatusCode::kInvalidArgument, {"packet_width"}));
  d.packet_width = 8;
  d.embree_streams = EmbreeStreams::kAlways;
  EXPECT_TRUE(IsError(RayScene::create(d, &s), StatusCode::kInvalidArgument, {"embree_streams", "packet_width 1"}));
  d.packet_width = 1;
  d.embree_streams = static_cast<EmbreeStreams>(7);
  EXPECT_TRUE(IsError(RayScene::create(d, &s), StatusCode::kInvalidArgument, {"embree_streams"}));
}

}  // namespace
}  // namespace impact::test
