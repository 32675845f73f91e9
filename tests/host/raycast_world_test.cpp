// RayScene::sync_world: a World's sphere bodies, shaped bodies (boxes, hulls,
// cylinders, ellipsoids, capsules, compounds, a static mesh) and planes traced by both
// backends, against a brute force over the world's own arrays (double-precision
// ray-sphere and ray-half-space, impact::raycast_shapes per shaped body). Checks the
// handles in the hits, layers, slot re-sorts and destroyed bodies between syncs, what
// a sync replaces and what it keeps, and the same bytes for every thread count.
// Also the World views it reads: BodyArrays' shape and orientation, PlaneArrays.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <vector>

#include <Eigen/Geometry>

#include "impact/impact.h"
#include "impact/shape_queries.h"
#include "support/random_input.h"
#include "support/test_support.h"

namespace impact::test {
namespace {

using Eigen::Vector3d;
using Eigen::Vector3f;
constexpr float kInf = std::numeric_limits<float>::infinity();

struct Rng : TestRng {
  Rng() : TestRng(20261121u) {}
};

struct TestWorld {
  std::unique_ptr<World> world;
  std::vector<BodyHandle> bodies;
  std::vector<PlaneHandle> planes;
};

// About 120 bodies over a mesh floor: a third plain spheres, the rest shapes of every
// kind with random orientations, in layers 1, 2, 4; two planes (one with a non-unit
// normal). reorder_interval 1 re-sorts slots every step.
TestWorld make_world(Rng& r, const Vector3f& origin) {
  TestWorld tw;
  WorldDesc desc;
  desc.reorder_interval = 1;
  EXPECT_TRUE(IsOk(World::create(desc, &tw.world)));
  ShapeSet& set = tw.world->shapes();
  std::vector<ShapeId> kinds;
  ShapeId id, box, sphere, hull;
  EXPECT_TRUE(IsOk(set.add_box(Vector3f(0.6f, 0.3f, 0.4f), &box)));
  kinds.push_back(box);
  EXPECT_TRUE(IsOk(set.add_sphere(0.5f, &sphere)));
  std::vector<Vector3f> cloud;
  for (int i = 0; i < 20; ++i) cloud.push_back(r.unit().cwiseProduct(Vector3f(0.7f, 0.5f, 0.4f)));
  EXPECT_TRUE(IsOk(set.add_convex_hull(cloud, &hull)));
  kinds.push_back(hull);
  EXPECT_TRUE(IsOk(set.add_cylinder(0.4f, 0.5f, &id)));
  kinds.push_back(id);
  EXPECT_TRUE(IsOk(set.add_ellipsoid(Vector3f(0.7f, 0.4f, 0.3f), &id)));
  kinds.push_back(id);
  EXPECT_TRUE(IsOk(set.add_capsule(0.3f, 0.5f, &id)));
  kinds.push_back(id);
  const std::vector<CompoundChild> kids = {{box, Pose{Vector3f(0.6f, 0, 0), r.quat()}},
                                           {sphere, Pose{Vector3f(-0.5f, 0.1f, 0), Eigen::Quaternionf::Identity()}},
                                           {hull, Pose{Vector3f(0, 0, 0.6f), r.quat()}}};
  EXPECT_TRUE(IsOk(set.add_compound(kids, &id)));
  kinds.push_back(id);
  // A static bumpy mesh floor, 12 x 12 m.
  std::vector<Vector3f> v;
  std::vector<uint32_t> idx;
  bumpy_grid(r, 8, 1.5f, 0.2f, &v, &idx);
  ShapeId mesh;
  EXPECT_TRUE(IsOk(set.add_mesh(v, idx, &mesh)));

  std::vector<BodyDesc> descs;
  BodyDesc floor;
  floor.position = origin;
  floor.inv_mass = 0.0f;
  floor.shape = mesh;
  floor.layer = 2u;
  descs.push_back(floor);
  for (uint32_t i = 0; i < 120; ++i) {
    BodyDesc b;
    b.position = origin + Vector3f(r.uni(-5, 5), r.uni(1, 9), r.uni(-5, 5));
    b.velocity = r.vec(-1, 1);
    b.layer = 1u << r.pick(3);
    if (i % 3 == 0) {
      b.radius = r.uni(0.2f, 0.6f);
    } else {
      b.shape = kinds[i % kinds.size()];
      b.orientation = r.quat();
    }
    descs.push_back(b);
  }
  tw.bodies.resize(descs.size());
  EXPECT_TRUE(IsOk(tw.world->create_bodies(descs, tw.bodies)));
  std::vector<PlaneDesc> pd(2);
  pd[0].normal = Vector3f(0, 1, 0);
  pd[0].offset = origin.y() - 0.5f;
  pd[0].layer = 4u;
  pd[1].normal = Vector3f(-2, 0, 0);  // solid: x >= 7 (offset scales with the normal)
  pd[1].offset = -2.0f * (origin.x() + 7.0f);
  pd[1].layer = 1u;
  tw.planes.resize(2);
  EXPECT_TRUE(IsOk(tw.world->create_planes(pd, tw.planes)));
  return tw;
}

// Random rays around the scene, some from inside bodies, some aimed at them.
std::vector<Ray> make_rays(Rng& r, const World& w, const Vector3f& origin, uint32_t n) {
  const BodyArrays b = w.bodies();
  const uint32_t masks[] = {0xffffffffu, 1u, 2u, 4u, 3u, 5u};
  std::vector<Ray> rays;
  for (uint32_t i = 0; i < n; ++i) {
    Ray ray;
    const uint32_t s = r.pick(static_cast<uint32_t>(b.size()));
    const Vector3f body(b.pos_x[s], b.pos_y[s], b.pos_z[s]);
    switch (i % 3) {
      case 0: ray.origin = body + r.vec(-0.1f, 0.1f); break;
      default: ray.origin = origin + Vector3f(r.uni(-9, 9), r.uni(-2, 12), r.uni(-9, 9)); break;
    }
    ray.direction = i % 3 == 2 ? Vector3f(body + r.vec(-0.5f, 0.5f) - ray.origin) : Vector3f(r.unit() * r.uni(0.5f, 2.0f));
    if (ray.direction.squaredNorm() == 0.0f) ray.direction = Vector3f::UnitX();
    ray.tmax = r.pick(4) == 0 ? r.uni(0.0f, 8.0f) : kInf;
    ray.mask = masks[r.pick(6)];
    rays.push_back(ray);
  }
  return rays;
}

struct Expected {
  float t = kInf;
  HitKind kind = HitKind::kNone;
  BodyHandle body;
  PlaneHandle plane;
  float second = kInf;  // next-best t of anything else (ties are not compared)
};

void offer(Expected& e, float t, HitKind kind, BodyHandle body, PlaneHandle plane) {
  if (t < e.t) {
    e.second = e.t;
    e.t = t;
    e.kind = kind;
    e.body = body;
    e.plane = plane;
  } else if (t < e.second) {
    e.second = t;
  }
}

// Double precision: t of the solid sphere (0 from inside), or -1.
double ray_sphere(const Vector3d& o, const Vector3d& d, const Vector3d& c, double rad) {
  const Vector3d m = o - c;
  const double cc = m.squaredNorm() - rad * rad;
  if (cc <= 0.0) return 0.0;
  const double b = m.dot(d);
  const double disc = b * b - cc;
  if (b > 0.0 || disc < 0.0) return -1.0;
  return -b - std::sqrt(disc);
}

// Double precision: t of the half-space dot(n, x) <= off (0 from inside), or -1.
double ray_half_space(const Vector3d& o, const Vector3d& d, const Vector3d& n, double off) {
  const double s = n.dot(o) - off;
  if (s <= 0.0) return 0.0;
  const double dn = n.dot(d);
  if (dn >= 0.0) return -1.0;
  return -s / dn;
}

std::vector<Expected> brute_force(const World& w, std::span<const Ray> rays) {
  const BodyArrays b = w.bodies();
  const PlaneArrays p = w.planes();
  std::vector<uint32_t> shaped;
  std::vector<ShapeId> shape_of;
  std::vector<Pose> poses;
  for (uint32_t i = 0; i < b.size(); ++i)
    if (!b.shape.empty() && b.shape[i] != BodyArrays::kSphereBody) {
      shaped.push_back(i);
      shape_of.push_back(ShapeId{b.shape[i]});
      poses.push_back(Pose{Vector3f(b.pos_x[i], b.pos_y[i], b.pos_z[i]),
                           Eigen::Quaternionf(b.qw[i], b.qx[i], b.qy[i], b.qz[i])});
    }
  std::vector<ObjectRay> q;
  for (const Ray& r : rays)
    for (uint32_t k = 0; k < shaped.size(); ++k) q.push_back({r, k});
  std::vector<ShapeRayHit> sh(q.size());
  EXPECT_TRUE(IsOk(raycast_shapes(w.shapes(), shape_of, poses, q, sh)));
  std::vector<Expected> out(rays.size());
  for (size_t k = 0; k < rays.size(); ++k) {
    const Ray& r = rays[k];
    Expected& e = out[k];
    const Vector3d o = r.origin.cast<double>(), d = r.direction.cast<double>().normalized();
    const double tmax = r.tmax;
    for (uint32_t i = 0; i < b.size(); ++i) {
      if ((b.layer[i] & r.mask) == 0) continue;
      if (!b.shape.empty() && b.shape[i] != BodyArrays::kSphereBody) continue;
      const double t = ray_sphere(o, d, Vector3d(b.pos_x[i], b.pos_y[i], b.pos_z[i]), b.radius[i]);
      if (t >= 0.0 && t <= tmax && tmax > 0.0) offer(e, static_cast<float>(t), HitKind::kSphere, b.handles[i], {});
    }
    for (uint32_t j = 0; j < shaped.size(); ++j) {
      const uint32_t i = shaped[j];
      const ShapeRayHit& h = sh[k * shaped.size() + j];
      if ((b.layer[i] & r.mask) == 0 || !h.hit || tmax == 0.0) continue;
      offer(e, h.t, HitKind::kShape, b.handles[i], {});
    }
    for (uint32_t i = 0; i < p.size(); ++i) {
      if ((p.layer[i] & r.mask) == 0) continue;
      const double t = ray_half_space(o, d, Vector3d(p.normal_x[i], p.normal_y[i], p.normal_z[i]), p.offset[i]);
      if (t >= 0.0 && t <= tmax && tmax > 0.0) offer(e, static_cast<float>(t), HitKind::kPlane, {}, p.handles[i]);
    }
  }
  return out;
}

struct Config {
  RayBackend backend;
  const char* name;
};

std::vector<Config> backends() {
  std::vector<Config> c{{RayBackend::kLbvh, "lbvh"}};
  std::unique_ptr<RayScene> probe;
  RaySceneDesc d;
  if (RayScene::create(d, &probe).ok()) c.push_back({RayBackend::kEmbree, "embree"});
  return c;
}

std::unique_ptr<RayScene> make_scene(RayBackend backend, uint32_t threads) {
  RaySceneDesc d;
  d.backend = backend;
  d.threads = threads;
  std::unique_ptr<RayScene> s;
  EXPECT_TRUE(IsOk(RayScene::create(d, &s)));
  return s;
}

// Compares hits with the brute force; returns the number of rays that hit.
uint32_t compare(const std::vector<Expected>& want, std::span<const Ray> rays, std::span<const RayHit> got,
                 const char* what) {
  uint32_t hits = 0;
  for (size_t k = 0; k < rays.size(); ++k) {
    const Expected& e = want[k];
    const RayHit& h = got[k];
    SCOPED_TRACE(std::string(what) + " ray " + std::to_string(k));
    const float tol = 2e-4f * (1.0f + std::fabs(e.t == kInf ? 0.0f : e.t));
    const bool near_tmax = e.t != kInf && std::fabs(e.t - rays[k].tmax) < tol;
    if (near_tmax) continue;
    EXPECT_EQ(h.hit(), e.t != kInf);
    if (!h.hit() || e.t == kInf) continue;
    ++hits;
    EXPECT_NEAR(h.t, e.t, tol);
    if (e.second - e.t < 10.0f * tol) continue;  // a tie: either owner is right
    EXPECT_EQ(h.kind, e.kind);
    EXPECT_EQ(h.body, e.body);
    EXPECT_EQ(h.plane, e.plane);
  }
  return hits;
}

void same_bytes(std::span<const RayHit> a, std::span<const RayHit> b, const char* what) {
  ASSERT_EQ(a.size(), b.size());
  for (size_t k = 0; k < a.size(); ++k) {
    const bool same = a[k].kind == b[k].kind && a[k].id == b[k].id && a[k].prim == b[k].prim &&
                      a[k].body == b[k].body && a[k].plane == b[k].plane &&
                      std::memcmp(&a[k].t, &b[k].t, sizeof(float)) == 0 &&
                      std::memcmp(a[k].point.data(), b[k].point.data(), 3 * sizeof(float)) == 0 &&
                      std::memcmp(a[k].normal.data(), b[k].normal.data(), 3 * sizeof(float)) == 0;
    ASSERT_TRUE(same) << what << " ray " << k;
  }
}

TEST(RaycastWorld, SyncedWorldMatchesBruteForceAcrossStepsAndDestroys) {
  for (const Vector3f& origin : {Vector3f(0, 0, 0), Vector3f(1e4f, -3e3f, 2e4f)}) {
    Rng r;
    TestWorld tw = make_world(r, origin);
    World& w = *tw.world;
    const uint32_t nrays = scaled(1500);
    for (int round = 0; round < 3; ++round) {
      SCOPED_TRACE("round " + std::to_string(round));
      // Between rounds: steps (slots re-sort every step) and destroyed bodies.
      for (int s = 0; s < 8; ++s) {
        IMPACT_ASSERT_OK(w.step());
      }
      if (round == 1) {
        std::vector<BodyHandle> gone;
        for (size_t i = 5; i < tw.bodies.size(); i += 9) gone.push_back(tw.bodies[i]);
        IMPACT_ASSERT_OK(w.destroy_bodies(gone));
      }
      if (round == 2) {
        IMPACT_ASSERT_OK(w.destroy_planes({&tw.planes[0], 1}));
      }
      const std::vector<Ray> rays = make_rays(r, w, origin, nrays);
      const std::vector<Expected> want = brute_force(w, rays);
      for (const Config& c : backends()) {
        std::vector<RayHit> first;
        for (uint32_t threads : {1u, 2u, 3u}) {
          auto scene = make_scene(c.backend, threads);
          IMPACT_ASSERT_OK(scene->sync_world(w));
          IMPACT_ASSERT_OK(scene->commit());
          std::vector<RayHit> got(rays.size());
          IMPACT_ASSERT_OK(scene->closest_hit(rays, got));
          if (threads == 1) {
            const uint32_t hits = compare(want, rays, got, c.name);
            EXPECT_GT(hits, nrays / 4) << c.name;  // the scene is actually in the rays' way
            first = got;
          } else {
            same_bytes(first, got, c.name);
          }
          // Any hit agrees with the closest hit of the same segment as a ray (the same
          // unit direction and length), on segments reaching just past each hit.
          std::vector<Segment> segs(rays.size());
          std::vector<Ray> as_rays(rays.size());
          for (size_t k = 0; k < rays.size(); ++k) {
            const Vector3f d = rays[k].direction.normalized();
            const float len = got[k].hit() ? got[k].t + 0.05f : 5.0f;
            segs[k] = {rays[k].origin, rays[k].origin + len * d, rays[k].mask};
            as_rays[k].origin = segs[k].from;
            as_rays[k].direction = segs[k].to - segs[k].from;
            as_rays[k].tmax = static_cast<float>(as_rays[k].direction.cast<double>().norm());
            as_rays[k].mask = segs[k].mask;
          }
          std::vector<uint8_t> occ(segs.size());
          IMPACT_ASSERT_OK(scene->any_hit(segs, occ));
          std::vector<RayHit> seg_hits(rays.size());
          IMPACT_ASSERT_OK(scene->closest_hit(as_rays, seg_hits));
          uint32_t occluded = 0;
          for (size_t k = 0; k < rays.size(); ++k) {
            EXPECT_EQ(occ[k], seg_hits[k].hit() ? 1 : 0) << c.name << " segment " << k;
            occluded += occ[k];
          }
          EXPECT_GT(occluded, nrays / 4) << c.name;
        }
      }
    }
  }
}

TEST(RaycastWorld, ResyncUpdatesInPlaceAndKeepsMeshesAndCapsules) {
  for (const Config& c : backends()) {
    for (DynamicUpdate u : {DynamicUpdate::kRefit, DynamicUpdate::kRebuildLow}) {
      SCOPED_TRACE(c.name);
      Rng r;
      TestWorld tw = make_world(r, Vector3f::Zero());
      RaySceneDesc d;
      d.backend = c.backend;
      d.dynamic_update = u;
      std::unique_ptr<RayScene> scene;
      IMPACT_ASSERT_OK(RayScene::create(d, &scene));
      // A capsule far away on z and a mesh far away on -z stay through the syncs.
      Eigen::Matrix3Xf a(3, 1), b(3, 1);
      a.col(0) = Vector3f(0, 2, 40);
      b.col(0) = Vector3f(0, 4, 40);
      const float cr[1] = {1.0f};
      IMPACT_ASSERT_OK(scene->set_capsules(a, b, cr));
      Eigen::Matrix3Xf v(3, 3);
      v << -5, 5, 0, -2, -2, 8, -40, -40, -40;
      Eigen::Matrix<uint32_t, 3, Eigen::Dynamic> t(3, 1);
      t << 0, 1, 2;
      MeshHandle mh;
      IMPACT_ASSERT_OK(scene->add_mesh(v, t, 1u, &mh));
      // Spheres and shapes given by hand are replaced by the sync.
      const std::vector<float> x{0}, y{100}, z{0}, rad{1};
      IMPACT_ASSERT_OK(scene->set_spheres(x, y, z, rad));
      std::vector<Ray> rays(3);
      rays[0].origin = Vector3f(0, 3, 30);
      rays[0].direction = Vector3f(0, 0, 1);
      rays[1].origin = Vector3f(0, 3, -30);
      rays[1].direction = Vector3f(0, 0, -1);
      rays[2].origin = Vector3f(0, 90, 0);
      rays[2].direction = Vector3f(0, 1, 0);
      for (int frame = 0; frame < 4; ++frame) {
        IMPACT_ASSERT_OK(scene->sync_world(*tw.world));
        IMPACT_ASSERT_OK(scene->commit());
        std::vector<RayHit> got(rays.size());
        IMPACT_ASSERT_OK(scene->closest_hit(rays, got));
        EXPECT_EQ(got[0].kind, HitKind::kCapsule);
        EXPECT_NEAR(got[0].t, 9.0f, 1e-4f);
        EXPECT_EQ(got[1].kind, HitKind::kTriangle);
        EXPECT_NEAR(got[1].t, 10.0f, 1e-4f);
        EXPECT_FALSE(got[2].hit());  // the hand-made sphere at y = 100 is gone
        // Same counts frame to frame: the update path (refit or rebuild) stays correct.
        std::vector<Ray> probe = make_rays(r, *tw.world, Vector3f::Zero(), 400);
        for (Ray& pr : probe) pr.tmax = std::min(pr.tmax, 25.0f);  // short of the capsule and mesh
        const std::vector<Expected> want = brute_force(*tw.world, probe);
        std::vector<RayHit> ph(probe.size());
        IMPACT_ASSERT_OK(scene->closest_hit(probe, ph));
        compare(want, probe, ph, c.name);
        for (int s = 0; s < 3; ++s) {
          IMPACT_ASSERT_OK(tw.world->step());
        }
      }
      // set_planes / set_shapes by hand drop the synced handles.
      const std::vector<ShapeId> none;
      const std::vector<Pose> no_pose;
      IMPACT_ASSERT_OK(scene->set_shapes(tw.world->shapes(), none, no_pose));
      Eigen::Matrix3Xf n(3, 1);
      n.col(0) = Vector3f(0, 1, 0);
      const float off[1] = {-50.0f};
      IMPACT_ASSERT_OK(scene->set_planes(n, off));
      IMPACT_ASSERT_OK(scene->commit());
      Ray down;
      down.origin = Vector3f(0, -40, 20);
      down.direction = Vector3f(0, -1, 0);
      RayHit h;
      IMPACT_ASSERT_OK(scene->closest_hit({&down, 1}, {&h, 1}));
      ASSERT_EQ(h.kind, HitKind::kPlane);
      EXPECT_TRUE(h.plane.is_null());
    }
  }
}

TEST(RaycastWorld, SphereOnlyWorldAndEmptyWorld) {
  for (const Config& c : backends()) {
    std::unique_ptr<World> w;
    IMPACT_ASSERT_OK(World::create(WorldDesc{}, &w));
    auto scene = make_scene(c.backend, 2);
    IMPACT_ASSERT_OK(scene->sync_world(*w));  // nothing at all
    IMPACT_ASSERT_OK(scene->commit());
    Ray r;
    RayHit h;
    IMPACT_ASSERT_OK(scene->closest_hit({&r, 1}, {&h, 1}));
    EXPECT_FALSE(h.hit());
    BodyDesc b;
    b.position = Vector3f(0, 0, 5);
    b.radius = 1.0f;
    BodyHandle bh;
    IMPACT_ASSERT_OK(w->create_bodies({&b, 1}, {&bh, 1}));
    EXPECT_TRUE(w->bodies().shape.empty());
    IMPACT_ASSERT_OK(scene->sync_world(*w));
    IMPACT_ASSERT_OK(scene->commit());
    IMPACT_ASSERT_OK(scene->closest_hit({&r, 1}, {&h, 1}));
    ASSERT_EQ(h.kind, HitKind::kSphere);
    EXPECT_EQ(h.body, bh);
    EXPECT_NEAR(h.t, 4.0f, 1e-5f);
    EXPECT_EQ(scene->info().shapes, 0u);
  }
}

TEST(WorldViews, BodyShapesOrientationsAndPlanes) {
  std::unique_ptr<World> w;
  IMPACT_ASSERT_OK(World::create(WorldDesc{}, &w));
  BodyDesc s;
  s.position = Vector3f(1, 2, 3);
  s.friction = 0.0f;  // a frictionless sphere never rotates: no orientation fields yet
  BodyHandle hs;
  IMPACT_ASSERT_OK(w->create_bodies({&s, 1}, {&hs, 1}));
  EXPECT_TRUE(w->bodies().shape.empty());
  EXPECT_TRUE(w->bodies().qw.empty());
  ShapeId box;
  IMPACT_ASSERT_OK(w->shapes().add_box(Vector3f(1, 2, 3), &box));
  BodyDesc b;
  b.shape = box;
  b.orientation = Eigen::Quaternionf(Eigen::AngleAxisf(0.7f, Vector3f(1, 2, 3).normalized()));
  BodyHandle hb;
  IMPACT_ASSERT_OK(w->create_bodies({&b, 1}, {&hb, 1}));
  const BodyArrays a = w->bodies();
  ASSERT_EQ(a.shape.size(), 2u);
  ASSERT_EQ(a.qx.size(), 2u);
  uint32_t ss = 0, sb = 0;
  IMPACT_ASSERT_OK(w->slot_of(hs, &ss));
  IMPACT_ASSERT_OK(w->slot_of(hb, &sb));
  EXPECT_EQ(a.shape[ss], BodyArrays::kSphereBody);
  EXPECT_EQ(a.shape[sb], box.index);
  EXPECT_EQ(a.qw[ss], 1.0f);
  EXPECT_EQ(a.qx[ss], 0.0f);
  const Eigen::Quaternionf q(a.qw[sb], a.qx[sb], a.qy[sb], a.qz[sb]);
  EXPECT_NEAR(q.angularDistance(b.orientation), 0.0f, 1e-5f);

  std::vector<PlaneDesc> pd(2);
  pd[0].normal = Vector3f(0, 3, 4);
  pd[0].offset = 10.0f;
  pd[0].layer = 8u;
  pd[1].normal = Vector3f(1, 0, 0);
  pd[1].offset = -2.0f;
  pd[1].restitution = 0.5f;
  std::vector<PlaneHandle> ph(2);
  IMPACT_ASSERT_OK(w->create_planes(pd, ph));
  PlaneArrays p = w->planes();
  ASSERT_EQ(p.size(), 2u);
  EXPECT_EQ(p.handles[0], ph[0]);
  EXPECT_NEAR(p.normal_y[0], 0.6f, 1e-7f);
  EXPECT_NEAR(p.normal_z[0], 0.8f, 1e-7f);
  EXPECT_NEAR(p.offset[0], 2.0f, 1e-6f);  // 10 / |(0, 3, 4)|
  EXPECT_EQ(p.layer[0], 8u);
  EXPECT_EQ(p.restitution[1], 0.5f);
  IMPACT_ASSERT_OK(w->destroy_planes({&ph[0], 1}));
  p = w->planes();
  ASSERT_EQ(p.size(), 1u);
  EXPECT_EQ(p.handles[0], ph[1]);
  EXPECT_EQ(p.offset[0], -2.0f);
}

}  // namespace
}  // namespace impact::test
