// RayScene::set_shapes: posed shapes of every type (sphere, capsule, box, AABB, convex
// hull, cylinder, ellipsoid, mesh, compound) traced by both backends, against a brute
// force over impact::raycast_shapes for every object (itself checked against a double
// reference in tests/host/shapes/shape_queries_test.cpp). Shapes share the scene
// with spheres, capsules, a mesh and planes: the expected closest hit is the better of
// the shapes' brute force and a scene holding only that other geometry (checked against
// its own double reference in tests/host/raycast_test.cpp). Also: layers, any hit,
// thread counts, updates (refit and rebuild), bad input.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "impact/impact.h"
#include "impact/shape_queries.h"
#include "support/random_input.h"
#include "support/test_support.h"

namespace impact::test {
namespace {

using Eigen::Vector3f;
constexpr float kInf = std::numeric_limits<float>::infinity();

struct Rng : TestRng {
  Rng() : TestRng(12345u) {}
};

// One shape of every type (and a half-space for the error test).
struct Library {
  ShapeSet set;
  std::vector<ShapeId> kinds;  // every type but the half-space
  ShapeId half_space;

  explicit Library(Rng& r) {
    ShapeId id;
    auto add = [&](const Status& s) {
      EXPECT_TRUE(IsOk(s));
      kinds.push_back(id);
    };
    add(set.add_sphere(0.7f, &id));
    const ShapeId sphere = id;
    add(set.add_capsule(0.4f, 0.8f, &id));
    const ShapeId capsule = id;
    add(set.add_box(Vector3f(0.9f, 0.4f, 0.6f), &id));
    const ShapeId box = id;
    add(set.add_aabb(Vector3f(0.5f, 0.8f, 0.3f), &id));
    std::vector<Vector3f> cloud;
    for (int i = 0; i < 24; ++i) cloud.push_back(r.unit().cwiseProduct(Vector3f(1.0f, 0.7f, 0.5f)));
    add(set.add_convex_hull(cloud, &id));
    const ShapeId hull = id;
    add(set.add_cylinder(0.5f, 0.7f, &id));
    const ShapeId cylinder = id;
    add(set.add_ellipsoid(Vector3f(0.9f, 0.5f, 0.3f), &id));
    // A bumpy 6 x 6 cell mesh (two-sided triangles).
    std::vector<Vector3f> v;
    std::vector<uint32_t> idx;
    bumpy_grid(r, 6, 0.3f, 0.2f, &v, &idx);
    add(set.add_mesh(v, idx, &id));
    std::vector<CompoundChild> kids = {
        {box, Pose{Vector3f(0.8f, 0, 0), r.quat()}},
        {sphere, Pose{Vector3f(-0.7f, 0.2f, 0), Eigen::Quaternionf::Identity()}},
        {capsule, Pose{Vector3f(0, 0.6f, 0.3f), r.quat()}},
        {hull, Pose{Vector3f(0, -0.7f, 0), r.quat()}},
        {cylinder, Pose{Vector3f(0, 0, -0.8f), r.quat()}},
    };
    add(set.add_compound(kids, &id));
    EXPECT_TRUE(IsOk(set.add_half_space(Vector3f(0, 1, 0), 0.0f, &half_space)));
  }
};

struct Objects {
  std::vector<ShapeId> shape_of;
  std::vector<Pose> poses;
  std::vector<uint32_t> layer;
};

Objects random_objects(Rng& r, const Library& lib, uint32_t n, const Vector3f& centre, float extent) {
  Objects o;
  for (uint32_t i = 0; i < n; ++i) {
    o.shape_of.push_back(lib.kinds[i % lib.kinds.size()]);
    o.poses.push_back(Pose{centre + r.vec(-extent, extent), r.quat()});
    o.layer.push_back(1u << r.pick(3));
  }
  return o;
}

// The other geometry: spheres, capsules, a mesh and a plane, in layers 1..4.
void add_other_geometry(Rng& r, RayScene& s, const Vector3f& centre, float extent) {
  const uint32_t ns = 40, nc = 30;
  std::vector<float> x, y, z, rad;
  std::vector<uint32_t> sl, cl;
  for (uint32_t i = 0; i < ns; ++i) {
    const Vector3f p = centre + r.vec(-extent, extent);
    x.push_back(p.x());
    y.push_back(p.y());
    z.push_back(p.z());
    rad.push_back(r.uni(0.2f, 0.6f));
    sl.push_back(1u << r.pick(3));
  }
  EXPECT_TRUE(IsOk(s.set_spheres(x, y, z, rad, sl)));
  Eigen::Matrix3Xf a(3, nc), b(3, nc);
  std::vector<float> cr;
  for (uint32_t i = 0; i < nc; ++i) {
    a.col(i) = centre + r.vec(-extent, extent);
    b.col(i) = a.col(i) + r.vec(-1, 1);
    cr.push_back(r.uni(0.1f, 0.4f));
    cl.push_back(1u << r.pick(3));
  }
  EXPECT_TRUE(IsOk(s.set_capsules(a, b, cr, cl)));
  Eigen::Matrix3Xf v(3, 4);
  v.col(0) = centre + Vector3f(-extent, -extent * 0.5f, -extent);
  v.col(1) = centre + Vector3f(extent, -extent * 0.5f, -extent);
  v.col(2) = centre + Vector3f(extent, -extent * 0.3f, extent);
  v.col(3) = centre + Vector3f(-extent, -extent * 0.6f, extent);
  Eigen::Matrix<uint32_t, 3, Eigen::Dynamic> t(3, 2);
  t << 0, 0, 1, 2, 2, 3;
  MeshHandle h;
  EXPECT_TRUE(IsOk(s.add_mesh(v, t, 2u, &h)));
  Eigen::Matrix3Xf n(3, 1);
  n.col(0) = Vector3f(0, 1, 0);
  const float off[1] = {centre.y() - 1.2f * extent};
  const uint32_t pl[1] = {4u};
  EXPECT_TRUE(IsOk(s.set_planes(n, off, pl)));
}

std::vector<Ray> random_rays(Rng& r, const Objects& o, uint32_t n, const Vector3f& centre, float extent) {
  std::vector<Ray> rays;
  const uint32_t masks[] = {0xffffffffu, 1u, 2u, 4u, 3u, 6u};
  for (uint32_t i = 0; i < n; ++i) {
    Ray ray;
    const uint32_t kind = i % 4;
    if (kind == 0) {
      // From an object's centre (inside most solids).
      ray.origin = o.poses[r.pick(static_cast<uint32_t>(o.poses.size()))].position + r.vec(-0.1f, 0.1f);
    } else {
      ray.origin = centre + r.vec(-1.5f * extent, 1.5f * extent);
    }
    if (kind == 3) {
      // Aimed at an object.
      const Vector3f target = o.poses[r.pick(static_cast<uint32_t>(o.poses.size()))].position + r.vec(-0.8f, 0.8f);
      ray.direction = (target - ray.origin) * r.uni(0.5f, 3.0f);
      if (ray.direction.squaredNorm() == 0.0f) ray.direction = Vector3f::UnitX();
    } else {
      ray.direction = r.unit() * r.uni(0.5f, 2.0f);
    }
    ray.tmax = r.pick(3) == 0 ? r.uni(0.0f, extent) : kInf;
    ray.mask = masks[r.pick(6)];
    rays.push_back(ray);
  }
  return rays;
}

struct Expected {
  bool hit = false;
  float t = kInf;
  HitKind kind = HitKind::kNone;
  uint32_t id = 0, prim = 0;
  float second = kInf;  // the next-best t of any other primitive (for tie detection)
};

// Brute force over every object with raycast_shapes, then the other geometry's hit.
std::vector<Expected> brute_force(const ShapeSet& set, const Objects& o, std::span<const Ray> rays,
                                  std::span<const RayHit> other) {
  const uint32_t n = static_cast<uint32_t>(o.poses.size());
  std::vector<ObjectRay> q;
  q.reserve(rays.size() * n);
  for (const Ray& r : rays)
    for (uint32_t k = 0; k < n; ++k) q.push_back({r, k});
  std::vector<ShapeRayHit> h(q.size());
  EXPECT_TRUE(IsOk(raycast_shapes(set, o.shape_of, o.poses, q, h)));
  std::vector<Expected> out(rays.size());
  for (size_t i = 0; i < rays.size(); ++i) {
    Expected& e = out[i];
    auto consider = [&](float t, HitKind kind, uint32_t id, uint32_t prim) {
      if (t < e.t) {
        e.second = e.t;
        e = Expected{true, t, kind, id, prim, e.second};
      } else {
        e.second = std::min(e.second, t);
      }
    };
    for (uint32_t k = 0; k < n; ++k) {
      const ShapeRayHit& s = h[i * n + k];
      if (!s.hit || (o.layer[k] & rays[i].mask) == 0) continue;
      consider(s.t, HitKind::kShape, k, s.child == kNoChild ? 0u : s.child);
    }
    if (!other.empty() && other[i].hit()) consider(other[i].t, other[i].kind, other[i].id, other[i].prim);
  }
  return out;
}

bool close(float a, float b) { return std::fabs(a - b) <= 1e-5f * std::max(1.0f, std::fabs(b)); }

// Checks got against expected; returns the number of rays compared with a hit.
int check_hits(const char* what, std::span<const Ray> rays, std::span<const Expected> exp,
               std::span<const RayHit> got) {
  int hits = 0, failures = 0;
  for (size_t i = 0; i < rays.size() && failures < 10; ++i) {
    const Expected& e = exp[i];
    const RayHit& g = got[i];
    const float tmax = rays[i].tmax;
    if (e.hit != g.hit()) {
      // Only a hit at the very end of the ray may go either way (rounding of tmax).
      const float t = e.hit ? e.t : g.t;
      if (close(t, tmax)) continue;
      ADD_FAILURE() << what << " ray " << i << ": expected hit " << e.hit << " (t " << e.t << "), got "
                    << g.hit() << " (t " << g.t << ")";
      ++failures;
      continue;
    }
    if (!e.hit) continue;
    ++hits;
    if (!close(g.t, e.t)) {
      ADD_FAILURE() << what << " ray " << i << ": t " << g.t << " vs brute force " << e.t;
      ++failures;
      continue;
    }
    const Vector3f d = rays[i].direction.normalized();
    if (std::fabs(g.normal.norm() - 1.0f) > 1e-4f || g.normal.dot(d) > 1e-5f) {
      ADD_FAILURE() << what << " ray " << i << ": normal (" << g.normal.transpose() << ") not unit / facing the ray";
      ++failures;
    }
    if ((g.point - (rays[i].origin + g.t * d)).norm() > 1e-4f * std::max(1.0f, rays[i].origin.norm() + g.t)) {
      ADD_FAILURE() << what << " ray " << i << ": point off the ray";
      ++failures;
    }
    if (e.second - e.t > 1e-4f * std::max(1.0f, e.t) && (g.kind != e.kind || g.id != e.id || g.prim != e.prim)) {
      ADD_FAILURE() << what << " ray " << i << ": hit kind " << static_cast<int>(g.kind) << " id " << g.id
                    << " prim " << g.prim << ", brute force kind " << static_cast<int>(e.kind) << " id " << e.id
                    << " prim " << e.prim << " (t " << e.t << ")";
      ++failures;
    }
  }
  return hits;
}

struct Config {
  const char* name;
  RaySceneDesc desc;
};

std::vector<Config> configs() {
  std::vector<Config> c;
  RaySceneDesc d;
  d.backend = RayBackend::kLbvh;
  c.push_back({"lbvh", d});
  d.dynamic_update = DynamicUpdate::kRebuildLow;
  c.push_back({"lbvh_rebuild", d});
  d.backend = RayBackend::kEmbree;
  d.dynamic_update = DynamicUpdate::kRefit;
  c.push_back({"embree", d});
  d.packet_width = 8;
  c.push_back({"embree_packet8", d});
  d.packet_width = 1;
  d.dynamic_update = DynamicUpdate::kRebuildMedium;
  c.push_back({"embree_rebuild", d});
  d.embree_streams = EmbreeStreams::kAlways;  // user geometry through streams
  c.push_back({"embree_stream", d});
  return c;
}

std::unique_ptr<RayScene> make_scene(const RaySceneDesc& d) {
  std::unique_ptr<RayScene> s;
  EXPECT_TRUE(IsOk(RayScene::create(d, &s)));
  return s;
}

// Any hit of segments, against the brute force (shapes) or the other scene.
void check_any(const char* what, RayScene& scene, RayScene* other, const ShapeSet& set, const Objects& o,
               std::span<const Ray> rays) {
  std::vector<Segment> seg;
  std::vector<Ray> as_rays;
  for (const Ray& r : rays) {
    Segment s;
    s.from = r.origin;
    s.to = r.origin + r.direction;
    s.mask = r.mask;
    seg.push_back(s);
    // The brute force sees the segment as the scene does: direction to - from (which
    // differs from r.direction by rounding far from the origin).
    Ray q = r;
    q.direction = s.to - s.from;
    if (q.direction.squaredNorm() == 0.0f) q.direction = Vector3f::UnitX();
    q.tmax = kInf;
    as_rays.push_back(q);
  }
  std::vector<uint8_t> got(seg.size()), other_any(seg.size(), 0);
  IMPACT_ASSERT_OK(scene.any_hit(seg, got));
  if (other) {
    IMPACT_ASSERT_OK(other->any_hit(seg, other_any));
  }
  const std::vector<Expected> exp = brute_force(set, o, as_rays, {});
  int failures = 0, blocked = 0;
  for (size_t i = 0; i < seg.size() && failures < 10; ++i) {
    const float len = (seg[i].to - seg[i].from).norm();
    const bool shape_hit = exp[i].hit && exp[i].t <= len;
    const bool want = shape_hit || other_any[i] != 0;
    blocked += want;
    if (want == (got[i] != 0)) continue;
    if (exp[i].hit && close(exp[i].t, len)) continue;  // touches the end point: rounding
    ADD_FAILURE() << what << " segment " << i << ": expected " << want << " (shape t " << exp[i].t << ", length "
                  << len << "), got " << int(got[i]);
    ++failures;
  }
  EXPECT_GT(blocked, static_cast<int>(seg.size() / 10)) << what;
}

void run_scene_case(const Vector3f& centre, uint32_t seed) {
  Rng r;
  r.g.seed(seed);
  Library lib(r);
  const float extent = 6.0f;
  Objects o = random_objects(r, lib, 180, centre, extent);
  const std::vector<Ray> rays = random_rays(r, o, static_cast<uint32_t>(scaled(1500, 200)), centre, extent);
  const uint64_t other_seed = r.g();
  for (const Config& c : configs()) {
    SCOPED_TRACE(c.name);
    auto scene = make_scene(c.desc);
    auto other = make_scene(c.desc);
    Rng ra, rb;
    ra.g.seed(static_cast<uint32_t>(other_seed));
    rb.g.seed(static_cast<uint32_t>(other_seed));
    add_other_geometry(ra, *scene, centre, extent);
    add_other_geometry(rb, *other, centre, extent);
    IMPACT_ASSERT_OK(other->commit());
    Objects frame = o;
    for (int step = 0; step < 3; ++step) {
      SCOPED_TRACE("step " + std::to_string(step));
      if (step == 1) {
        // Same count: moved and turned (an update).
        for (Pose& p : frame.poses) {
          p.position += r.vec(-0.5f, 0.5f);
          p.orientation = (p.orientation * r.quat()).normalized();
        }
      } else if (step == 2) {
        // Fewer objects: a rebuild.
        frame.shape_of.resize(120);
        frame.poses.resize(120);
        frame.layer.resize(120);
      }
      IMPACT_ASSERT_OK(scene->set_shapes(lib.set, frame.shape_of, frame.poses, frame.layer));
      IMPACT_ASSERT_OK(scene->commit());
      EXPECT_EQ(scene->info().shapes, frame.poses.size());
      if (step == 1) {
        EXPECT_EQ(scene->info().dynamic_rebuilt, c.desc.dynamic_update != DynamicUpdate::kRefit);
      }
      if (step == 2) {
        EXPECT_TRUE(scene->info().dynamic_rebuilt);
      }
      std::vector<RayHit> other_hits(rays.size());
      IMPACT_ASSERT_OK(other->closest_hit(rays, other_hits));
      const std::vector<Expected> exp = brute_force(lib.set, frame, rays, other_hits);
      std::vector<RayHit> first;
      for (uint32_t threads : {1u, 2u, 3u}) {
        IMPACT_ASSERT_OK(scene->set_threads(Backend::kDefault, threads));
        std::vector<RayHit> got(rays.size());
        IMPACT_ASSERT_OK(scene->closest_hit(rays, got));
        const int hits = check_hits(c.name, rays, exp, got);
        EXPECT_GT(hits, static_cast<int>(rays.size() / 4));
        int shape_hits = 0;
        for (const RayHit& h : got) shape_hits += h.kind == HitKind::kShape;
        EXPECT_GT(shape_hits, static_cast<int>(rays.size() / 8));
        if (first.empty()) {
          first = got;
        } else if (c.desc.backend == RayBackend::kLbvh) {
          for (size_t i = 0; i < got.size(); ++i) {
            ASSERT_EQ(got[i].kind, first[i].kind) << i;
            ASSERT_EQ(got[i].t, first[i].t) << i;
            ASSERT_EQ(got[i].id, first[i].id) << i;
          }
        }
      }
      check_any(c.name, *scene, other.get(), lib.set, frame, rays);
    }
  }
}

TEST(RaycastShapes, EveryTypeMixedSceneBothBackends) { run_scene_case(Vector3f(0, 0, 0), 1u); }

TEST(RaycastShapes, FarFromOrigin) { run_scene_case(Vector3f(1e4f, -3e3f, 2e4f), 7u); }

// Only shapes, every ray type from a camera (pick) and each shape kind hit at least once.
TEST(RaycastShapes, PickSeesEveryShapeType) {
  Rng r;
  Library lib(r);
  Objects o;
  for (size_t k = 0; k < lib.kinds.size(); ++k) {
    o.shape_of.push_back(lib.kinds[k]);
    o.poses.push_back(Pose{Vector3f(3.0f * static_cast<float>(k) - 12.0f, 0, -10), r.quat()});
  }
  for (const Config& c : configs()) {
    SCOPED_TRACE(c.name);
    auto scene = make_scene(c.desc);
    IMPACT_ASSERT_OK(scene->set_shapes(lib.set, o.shape_of, o.poses));
    IMPACT_ASSERT_OK(scene->commit());
    Camera cam;
    cam.aspect = 2.0f;
    std::vector<Eigen::Vector2f> screen;
    for (int j = 0; j < 40; ++j)
      for (int i = 0; i < 160; ++i) screen.emplace_back((static_cast<float>(i) + 0.5f) / 160.0f, (static_cast<float>(j) + 0.5f) / 40.0f);
    std::vector<RayHit> hits(screen.size());
    IMPACT_ASSERT_OK(scene->pick(cam, screen, 0xffffffffu, hits));
    std::vector<Ray> rays(screen.size());
    IMPACT_ASSERT_OK(camera_rays(cam, screen, 0xffffffffu, rays));
    std::vector<int> seen(o.poses.size(), 0);
    for (const RayHit& h : hits)
      if (h.kind == HitKind::kShape) ++seen[h.id];
    for (size_t k = 0; k < seen.size(); ++k) EXPECT_GT(seen[k], 0) << "object " << k;
    o.layer.assign(o.poses.size(), 1u);
    check_hits(c.name, rays, brute_force(lib.set, o, rays, {}), hits);
    // A mask that excludes layer 1 sees nothing.
    IMPACT_ASSERT_OK(scene->pick(cam, screen, 2u, hits));
    for (const RayHit& h : hits) ASSERT_FALSE(h.hit());
  }
}

TEST(RaycastShapes, BadInput) {
  Rng r;
  Library lib(r);
  for (const Config& c : configs()) {
    SCOPED_TRACE(c.name);
    auto scene = make_scene(c.desc);
    const std::vector<ShapeId> ids = {lib.kinds[0], lib.kinds[2], lib.kinds[8]};
    std::vector<Pose> poses(3);
    EXPECT_TRUE(IsError(scene->set_shapes(lib.set, ids, std::span<const Pose>(poses).first(2)),
                        StatusCode::kSizeMismatch, {"set_shapes"}));
    const std::vector<uint32_t> layers = {1, 2};
    EXPECT_TRUE(IsError(scene->set_shapes(lib.set, ids, poses, layers), StatusCode::kSizeMismatch));
    std::vector<ShapeId> bad = ids;
    bad[1] = ShapeId{999};
    EXPECT_TRUE(IsError(scene->set_shapes(lib.set, bad, poses), StatusCode::kInvalidArgument,
                        {"object 1", "unknown shape id 999"}));
    bad[1] = lib.half_space;
    EXPECT_TRUE(IsError(scene->set_shapes(lib.set, bad, poses), StatusCode::kInvalidArgument, {"object 1", "half-space"}));
    std::vector<Pose> p2 = poses;
    p2[2].position.y() = std::numeric_limits<float>::quiet_NaN();
    EXPECT_TRUE(IsError(scene->set_shapes(lib.set, ids, p2), StatusCode::kInvalidArgument, {"object 2", "position"}));
    p2 = poses;
    p2[0].orientation.coeffs() << 0, 0, 0, 2;
    EXPECT_TRUE(IsError(scene->set_shapes(lib.set, ids, p2), StatusCode::kInvalidArgument, {"object 0", "unit"}));
    p2 = poses;
    p2[0].orientation.coeffs() << 0, kInf, 0, 1;
    EXPECT_TRUE(IsError(scene->set_shapes(lib.set, ids, p2), StatusCode::kInvalidArgument, {"object 0", "orientation"}));
    // Nothing was set by the failed calls: the scene is still empty and committed.
    std::vector<RayHit> h(1);
    const Ray ray{Vector3f(0, 0, 5), Vector3f(0, 0, -1)};
    IMPACT_ASSERT_OK(scene->closest_hit(std::span<const Ray>(&ray, 1), h));
    EXPECT_FALSE(h[0].hit());
    // Pending changes block queries until commit().
    IMPACT_ASSERT_OK(scene->set_shapes(lib.set, ids, poses));
    EXPECT_TRUE(IsError(scene->closest_hit(std::span<const Ray>(&ray, 1), h), StatusCode::kInvalidArgument, {"commit"}));
    IMPACT_ASSERT_OK(scene->commit());
    IMPACT_ASSERT_OK(scene->closest_hit(std::span<const Ray>(&ray, 1), h));
    ASSERT_TRUE(h[0].hit());
    EXPECT_EQ(h[0].kind, HitKind::kShape);
    // All three objects sit at the origin; the ray meets the first entered surface.
    EXPECT_EQ(scene->info().shapes, 3u);
    // An empty set removes them.
    IMPACT_ASSERT_OK(scene->set_shapes(lib.set, {}, {}));
    IMPACT_ASSERT_OK(scene->commit());
    IMPACT_ASSERT_OK(scene->closest_hit(std::span<const Ray>(&ray, 1), h));
    EXPECT_FALSE(h[0].hit());
    EXPECT_EQ(scene->info().shapes, 0u);
  }
}

}  // namespace
}  // namespace impact::test
