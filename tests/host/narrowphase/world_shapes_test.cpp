// Bodies with shapes (BodyDesc::shape) in the World's step: validation, resting
// contacts against closed-form heights, slot re-sorts that keep each body's shape and
// orientation, determinism across backends and threads with every proxy type in one
// scene, sphere bodies giving the same contacts through the general path as through
// the sphere path, and resting contact points that keep their ids (the solver's
// warm-start keys) from step to step.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <random>
#include <vector>

#include "impact/impact.h"
#include "tests/support/test_support.h"

namespace impact {
namespace {

using test::IsError;
using test::IsOk;

std::unique_ptr<World> make_world(WorldDesc d = {}) {
  std::unique_ptr<World> w;
  EXPECT_TRUE(IsOk(World::create(d, &w)));
  return w;
}

PlaneHandle add_floor(World& w, float y = 0.0f) {
  PlaneDesc p;
  p.normal = Eigen::Vector3f::UnitY();
  p.offset = y;
  PlaneHandle h;
  EXPECT_TRUE(IsOk(w.create_planes({&p, 1}, {&h, 1})));
  return h;
}

TEST(WorldShapes, RejectsBadShapeBodies) {
  auto w = make_world();
  ShapeId box, half, mesh;
  ASSERT_TRUE(IsOk(w->shapes().add_box(Eigen::Vector3f(0.5f, 0.5f, 0.5f), &box)));
  ASSERT_TRUE(IsOk(w->shapes().add_half_space(Eigen::Vector3f::UnitY(), 0.0f, &half)));
  const Eigen::Vector3f v[3] = {{0, 0, 0}, {1, 0, 0}, {0, 0, 1}};
  const uint32_t idx[3] = {0, 1, 2};
  ASSERT_TRUE(IsOk(w->shapes().add_mesh(v, idx, &mesh)));
  BodyDesc d;
  BodyHandle h;
  d.shape = ShapeId{99};
  EXPECT_TRUE(IsError(w->create_bodies({&d, 1}, {&h, 1}), StatusCode::kInvalidArgument, {"body 0", "shape 99"}));
  d.shape = half;
  EXPECT_TRUE(IsError(w->create_bodies({&d, 1}, {&h, 1}), StatusCode::kInvalidArgument, {"half-space"}));
  d.shape = mesh;
  EXPECT_TRUE(IsError(w->create_bodies({&d, 1}, {&h, 1}), StatusCode::kInvalidArgument, {"mesh", "static"}));
  d.shape = box;
  d.orientation = Eigen::Quaternionf(2.0f, 0, 0, 0);
  EXPECT_TRUE(IsError(w->create_bodies({&d, 1}, {&h, 1}), StatusCode::kInvalidArgument, {"body 0", "unit quaternion"}));
  d.orientation.coeffs()[0] = NAN;
  EXPECT_TRUE(IsError(w->create_bodies({&d, 1}, {&h, 1}), StatusCode::kInvalidArgument, {"orientation"}));
  EXPECT_EQ(w->body_count(), 0u);
  d.orientation = Eigen::Quaternionf::Identity();
  d.radius = -1.0f;  // ignored with a shape
  EXPECT_TRUE(IsOk(w->create_bodies({&d, 1}, {&h, 1})));
  EXPECT_NEAR(w->bodies().radius[0], std::sqrt(0.75f), 1e-6f);  // bounding radius
  d.shape = mesh;
  d.inv_mass = 0.0f;
  EXPECT_TRUE(IsOk(w->create_bodies({&d, 1}, {&h, 1})));
  BodyDesc common;
  common.shape = box;
  Eigen::Matrix3Xf pos = Eigen::Matrix3Xf::Zero(3, 1);
  Eigen::VectorXf r = Eigen::VectorXf::Ones(1), m = Eigen::VectorXf::Ones(1);
  EXPECT_TRUE(IsError(w->create_bodies(pos, Eigen::Matrix3Xf(3, 0), r, m, common, {&h, 1}),
                      StatusCode::kInvalidArgument, {"BodyDesc"}));
}

// Boxes of distinct half extents lying in different orientations settle on a floor
// at the height of the half extent that ends up vertical; the world re-sorts slots
// every 4 steps, so each body's shape and orientation must travel with its handle.
TEST(WorldShapes, BoxesRestAtTheirClosedFormHeights) {
  WorldDesc desc;
  desc.reorder_interval = 4;
  auto w = make_world(desc);
  add_floor(*w);
  ShapeId box;
  const Eigen::Vector3f half(0.2f, 0.5f, 0.35f);
  ASSERT_TRUE(IsOk(w->shapes().add_box(half, &box)));
  std::vector<BodyDesc> descs;
  std::vector<float> expect;
  for (int i = 0; i < 30; ++i) {
    BodyDesc d;
    d.shape = box;
    d.position = Eigen::Vector3f(static_cast<float>(i % 6) * 2.0f, 1.5f, static_cast<float>(i / 6) * 2.0f);
    const int axis = i % 3;  // which local axis points up
    if (axis == 0) d.orientation = Eigen::Quaternionf(Eigen::AngleAxisf(static_cast<float>(M_PI / 2), Eigen::Vector3f::UnitZ()));
    if (axis == 2) d.orientation = Eigen::Quaternionf(Eigen::AngleAxisf(static_cast<float>(M_PI / 2), Eigen::Vector3f::UnitX()));
    descs.push_back(d);
    expect.push_back(half[axis]);
  }
  std::vector<BodyHandle> h(descs.size());
  ASSERT_TRUE(IsOk(w->create_bodies(descs, h)));
  for (int s = 0; s < 240; ++s) ASSERT_TRUE(IsOk(w->step()));
  std::vector<Eigen::Vector3f> p(h.size()), v(h.size());
  ASSERT_TRUE(IsOk(w->get_positions(h, p)));
  ASSERT_TRUE(IsOk(w->get_velocities(h, v)));
  for (size_t i = 0; i < h.size(); ++i) {
    // Penetration slop and position correction leave a few mm.
    EXPECT_NEAR(p[i].y(), expect[i], 0.02f) << "body " << i;
    EXPECT_LT(v[i].norm(), 0.05f) << "body " << i;
  }
  // Face contacts on the floor: one manifold of 4 points per resting box, normals into
  // the plane, the points consecutive and each within the manifold's depth.
  const ContactArrays c = w->contacts();
  EXPECT_EQ(c.size(), h.size());
  EXPECT_EQ(c.points(), 4 * h.size());
  for (size_t k = 0; k < c.size(); ++k) {
    EXPECT_TRUE(c.b_is_plane[k]);
    EXPECT_NEAR(c.normal_y[k], -1.0f, 1e-5f);
    EXPECT_EQ(c.point_count[k], 4u);
    EXPECT_EQ(c.first_point(k), 4 * k);
    for (size_t q = c.first_point(k); q < c.first_point(k) + c.point_count[k]; ++q)
      EXPECT_LE(c.point_depth[q], c.depth[k] + 1e-6f) << "manifold " << k << " point " << q;
  }
}

TEST(WorldShapes, StackOfBoxesAndCapsuleOnConvexStaysUp) {
  auto w = make_world();
  add_floor(*w);
  ShapeId box, capsule, hull;
  ASSERT_TRUE(IsOk(w->shapes().add_box(Eigen::Vector3f(0.5f, 0.25f, 0.5f), &box)));
  ASSERT_TRUE(IsOk(w->shapes().add_capsule(0.2f, 0.4f, &capsule)));
  const Eigen::Vector3f cube[8] = {{-1, -0.5f, -1}, {1, -0.5f, -1}, {-1, 0.5f, -1}, {1, 0.5f, -1},
                                   {-1, -0.5f, 1},  {1, -0.5f, 1},  {-1, 0.5f, 1},  {1, 0.5f, 1}};
  ASSERT_TRUE(IsOk(w->shapes().add_convex_hull(cube, &hull)));
  std::vector<BodyDesc> d(5);
  for (int i = 0; i < 3; ++i) {
    d[i].shape = box;
    d[i].position = Eigen::Vector3f(0, 0.25f + 0.5f * static_cast<float>(i) + 0.01f * static_cast<float>(i), 0);
  }
  d[3].shape = hull;  // a 2 x 1 x 2 slab, static, beside the stack
  d[3].inv_mass = 0.0f;
  d[3].position = Eigen::Vector3f(5, 0.5f, 0);
  d[4].shape = capsule;  // lying along x on the slab
  d[4].orientation = Eigen::Quaternionf(Eigen::AngleAxisf(static_cast<float>(M_PI / 2), Eigen::Vector3f::UnitY()));
  d[4].position = Eigen::Vector3f(5, 1.5f, 0);
  std::vector<BodyHandle> h(d.size());
  ASSERT_TRUE(IsOk(w->create_bodies(d, h)));
  for (int s = 0; s < 300; ++s) ASSERT_TRUE(IsOk(w->step()));
  std::vector<Eigen::Vector3f> p(h.size());
  ASSERT_TRUE(IsOk(w->get_positions(h, p)));
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(p[static_cast<size_t>(i)].y(), 0.25f + 0.5f * static_cast<float>(i), 0.05f) << i;
  EXPECT_NEAR(p[4].y(), 1.0f + 0.2f, 0.02f);
  EXPECT_NEAR(p[4].x(), 5.0f, 1e-3f);
}

/// Every proxy type in one pile, on a static mesh terrain inside a box of planes.
struct Pile {
  std::unique_ptr<World> world;
  std::vector<BodyHandle> handles;
};

Pile make_pile(Backend backend, uint32_t threads) {
  WorldDesc desc;
  desc.backend = backend;
  desc.threads = threads;
  desc.reorder_interval = 8;
  Pile pile;
  pile.world = make_world(desc);
  World& w = *pile.world;
  ShapeSet& s = w.shapes();
  ShapeId ids[8];
  EXPECT_TRUE(IsOk(s.add_box(Eigen::Vector3f(0.3f, 0.2f, 0.25f), &ids[0])));
  EXPECT_TRUE(IsOk(s.add_capsule(0.15f, 0.3f, &ids[1])));
  EXPECT_TRUE(IsOk(s.add_cylinder(0.25f, 0.2f, &ids[2])));
  EXPECT_TRUE(IsOk(s.add_ellipsoid(Eigen::Vector3f(0.3f, 0.2f, 0.25f), &ids[3])));
  std::mt19937 rng(4);
  std::normal_distribution<float> g(0.0f, 1.0f);
  std::vector<Eigen::Vector3f> pts;
  for (int i = 0; i < 20; ++i) pts.push_back(Eigen::Vector3f(g(rng), g(rng), g(rng)).normalized() * 0.3f);
  EXPECT_TRUE(IsOk(s.add_convex_hull(pts, &ids[4])));
  Pose l0, l1;
  l0.position = Eigen::Vector3f(-0.25f, 0, 0);
  l1.position = Eigen::Vector3f(0.25f, 0, 0);
  const CompoundChild kids[2] = {{ids[0], l0}, {ids[1], l1}};
  EXPECT_TRUE(IsOk(s.add_compound(kids, &ids[5])));
  EXPECT_TRUE(IsOk(s.add_aabb(Eigen::Vector3f(0.2f, 0.2f, 0.2f), &ids[6])));
  ids[7] = ShapeId{};  // plain sphere
  // Terrain: a bumpy 12 x 12 grid, static mesh body.
  std::vector<Eigen::Vector3f> v;
  std::vector<uint32_t> idx;
  const int n = 12;
  for (int i = 0; i <= n; ++i)
    for (int j = 0; j <= n; ++j)
      v.emplace_back(-3.0f + 0.5f * static_cast<float>(i), 0.15f * std::sin(static_cast<float>(i) * 0.9f + static_cast<float>(j) * 0.7f),
                     -3.0f + 0.5f * static_cast<float>(j));
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      const auto a = static_cast<uint32_t>(i * (n + 1) + j), b = a + 1, c = static_cast<uint32_t>((i + 1) * (n + 1) + j), d = c + 1;
      idx.insert(idx.end(), {a, b, c, b, d, c});
    }
  ShapeId terrain;
  EXPECT_TRUE(IsOk(s.add_mesh(v, idx, &terrain)));
  std::vector<BodyDesc> descs;
  BodyDesc ground;
  ground.shape = terrain;
  ground.inv_mass = 0.0f;
  descs.push_back(ground);
  std::uniform_real_distribution<float> u(-2.5f, 2.5f);
  for (int i = 0; i < 120; ++i) {
    BodyDesc d;
    d.shape = ids[i % 8];
    d.radius = 0.2f;
    d.position = Eigen::Vector3f(u(rng), 0.6f + 0.25f * static_cast<float>(i / 10), u(rng));
    Eigen::Vector4f q(g(rng), g(rng), g(rng), g(rng));
    q.normalize();
    d.orientation = Eigen::Quaternionf(q[3], q[0], q[1], q[2]);
    descs.push_back(d);
  }
  pile.handles.resize(descs.size());
  EXPECT_TRUE(IsOk(w.create_bodies(descs, pile.handles)));
  for (const auto& [nrm, off] : {std::pair{Eigen::Vector3f(0, 1, 0), -1.0f}, {Eigen::Vector3f(1, 0, 0), -3.0f},
                                 {Eigen::Vector3f(-1, 0, 0), -3.0f}, {Eigen::Vector3f(0, 0, 1), -3.0f},
                                 {Eigen::Vector3f(0, 0, -1), -3.0f}}) {
    PlaneDesc p;
    p.normal = nrm;
    p.offset = off;
    PlaneHandle ph;
    EXPECT_TRUE(IsOk(w.create_planes({&p, 1}, {&ph, 1})));
  }
  return pile;
}

TEST(WorldShapes, EveryProxyInOnePileIsDeterministicAndStaysAboveTheTerrain) {
  const int steps = 90;
  Pile ref = make_pile(Backend::kSerial, 1);
  for (int s = 0; s < steps; ++s) ASSERT_TRUE(IsOk(ref.world->step()));
  const uint64_t hash = ref.world->state_hash();
  EXPECT_GT(ref.world->contacts().size(), 100u);
  std::vector<Eigen::Vector3f> p(ref.handles.size());
  ASSERT_TRUE(IsOk(ref.world->get_positions(ref.handles, p)));
  for (size_t i = 1; i < p.size(); ++i) {
    EXPECT_GT(p[i].y(), -0.5f) << "body " << i << " fell through the terrain";
    EXPECT_TRUE(p[i].allFinite());
  }
  for (const test::ExecCase& c : test::exec_cases()) {
    Pile other = make_pile(c.backend, c.threads);
    for (int s = 0; s < steps; ++s) ASSERT_TRUE(IsOk(other.world->step()));
    EXPECT_EQ(other.world->state_hash(), hash) << test::to_string(c);
  }
}

// One shaped body far away switches the world to the general narrow phase: its
// sphere-sphere and sphere-plane contacts are those of the sphere path.
TEST(WorldShapes, SpheresGiveTheSameContactsThroughTheGeneralPath) {
  auto build = [](bool with_shape) {
    auto w = make_world();
    add_floor(*w);
    std::mt19937 rng(9);
    std::uniform_real_distribution<float> u(-2.0f, 2.0f);
    std::vector<BodyDesc> d(400);
    for (auto& b : d) {
      b.position = Eigen::Vector3f(u(rng), 0.3f + 0.5f * (u(rng) + 2.0f), u(rng));
      b.radius = 0.3f;
    }
    if (with_shape) {
      ShapeId box;
      EXPECT_TRUE(IsOk(w->shapes().add_box(Eigen::Vector3f(0.5f, 0.5f, 0.5f), &box)));
      BodyDesc far;
      far.shape = box;
      far.position = Eigen::Vector3f(1000, 1000, 1000);
      d.push_back(far);
    }
    std::vector<BodyHandle> h(d.size());
    EXPECT_TRUE(IsOk(w->create_bodies(d, h)));
    EXPECT_TRUE(IsOk(w->step()));
    return w;
  };
  auto a = build(false), b = build(true);
  auto key_of = [](const ContactArrays& c, size_t k) {
    return std::tuple(c.a[k], c.b[k], c.b_is_plane[k]);
  };
  const ContactArrays ca = a->contacts(), cb = b->contacts();
  ASSERT_EQ(ca.size(), cb.size());
  ASSERT_GT(ca.size(), 100u);
  std::map<std::tuple<uint32_t, uint32_t, uint8_t>, size_t> index;
  for (size_t k = 0; k < cb.size(); ++k) index[key_of(cb, k)] = k;
  for (size_t k = 0; k < ca.size(); ++k) {
    auto it = index.find(key_of(ca, k));
    ASSERT_NE(it, index.end()) << "contact " << k;
    const size_t j = it->second;
    EXPECT_NEAR(ca.depth[k], cb.depth[j], 1e-5f);
    EXPECT_NEAR(ca.normal_x[k], cb.normal_x[j], 1e-5f);
    EXPECT_NEAR(ca.normal_y[k], cb.normal_y[j], 1e-5f);
    EXPECT_NEAR(ca.normal_z[k], cb.normal_z[j], 1e-5f);
  }
}

// The stored bounding radius covers shapes that are not centred on the body's origin
// (its farthest local corner mixes min and max coordinates), and the body-plane cull
// that uses it keeps the contact of such a shape's far corner.
TEST(WorldShapes, OffCentreShapeKeepsItsFarCornerContact) {
  auto w = make_world();
  add_floor(*w, 0.0f);
  ShapeId slab, compound;
  ASSERT_TRUE(IsOk(w->shapes().add_box(Eigen::Vector3f(1.5f, 1.5f, 0.1f), &slab)));
  const CompoundChild child{slab, Pose{Eigen::Vector3f(-1.5f, 1.5f, 0.0f), Eigen::Quaternionf::Identity()}};
  ASSERT_TRUE(IsOk(w->shapes().add_compound({&child, 1}, &compound)));
  // Local box [-3, 0] x [0, 3] x [-0.1, 0.1]: the far corner (-3, 3, +-0.1) is 4.244 m
  // out. Turned by 135 degrees about z it points straight down.
  BodyDesc d;
  d.shape = compound;
  d.orientation = Eigen::Quaternionf(Eigen::AngleAxisf(0.75f * 3.14159265f, Eigen::Vector3f::UnitZ()));
  d.position = Eigen::Vector3f(0.0f, 4.2f, 0.0f);  // the corner 0.044 m below the floor
  BodyHandle h;
  ASSERT_TRUE(IsOk(w->create_bodies({&d, 1}, {&h, 1})));
  EXPECT_GE(w->bodies().radius[0], 4.2438f);
  ASSERT_TRUE(IsOk(w->step()));
  EXPECT_GT(w->last_step().plane_contacts, 0u);
  float depth = 0.0f;
  for (float v : w->contacts().depth) depth = std::max(depth, v);
  EXPECT_NEAR(depth, 0.044f, 0.01f);  // gravity moved it a little within the step
}

// WorldDesc::narrow_phase reaches the step: bad knobs are refused at creation, the
// scalar kernels agree with the SIMD ones to rounding, and a one-iteration EPA changes
// the contacts of curved pairs (so the caps are wired, not ignored).
TEST(WorldShapes, NarrowPhaseKnobsReachTheStep) {
  {
    WorldDesc d;
    d.narrow_phase.epa_tolerance = 0.0f;
    std::unique_ptr<World> w;
    EXPECT_TRUE(IsError(World::create(d, &w), StatusCode::kInvalidArgument, {"narrow_phase", "epa_tolerance"}));
    d.narrow_phase.epa_tolerance = 1e-5f;
    d.narrow_phase.gjk_max_iterations = 0;
    EXPECT_TRUE(IsError(World::create(d, &w), StatusCode::kInvalidArgument, {"narrow_phase", "gjk_max_iterations"}));
  }
  // An ellipsoid-like hull on a cylinder (the hull-cylinder kernel), a box on a box (SIMD
  // kernel), a capsule on the floor and a 120-point hull on a box (more vertices than
  // sat_max_vertices: the general path, GJK / EPA), all slightly overlapping.
  auto run = [](const NarrowPhaseOptions& o) {
    WorldDesc d;
    d.narrow_phase = o;
    d.gravity = Eigen::Vector3f::Zero();
    auto w = make_world(d);
    add_floor(*w, 0.0f);
    ShapeId ell, cyl, box, cap;
    // The axes' ends and the octants' directions on the ellipsoid of radii 0.6, 0.4, 0.5.
    std::vector<Eigen::Vector3f> pts;
    const Eigen::Vector3f radii(0.6f, 0.4f, 0.5f);
    for (int k = 0; k < 3; ++k)
      for (const float sgn : {-1.0f, 1.0f}) pts.push_back(sgn * radii[k] * Eigen::Vector3f::Unit(k));
    for (int i = 0; i < 8; ++i) {
      const Eigen::Vector3f dir((i & 1) ? 1.0f : -1.0f, (i & 2) ? 1.0f : -1.0f, (i & 4) ? 1.0f : -1.0f);
      pts.push_back(radii.cwiseProduct(dir) / std::sqrt(3.0f));
    }
    EXPECT_TRUE(IsOk(w->shapes().add_convex_hull(pts, &ell)));
    EXPECT_TRUE(IsOk(w->shapes().add_cylinder(0.5f, 0.5f, &cyl)));
    EXPECT_TRUE(IsOk(w->shapes().add_box(Eigen::Vector3f(0.5f, 0.5f, 0.5f), &box)));
    EXPECT_TRUE(IsOk(w->shapes().add_capsule(0.3f, 0.4f, &cap)));
    std::vector<BodyDesc> b(5);
    b[0].shape = cyl;  // axis z: turned upright about x
    b[0].orientation = Eigen::Quaternionf(Eigen::AngleAxisf(1.5707963f, Eigen::Vector3f::UnitX()));
    b[0].position = Eigen::Vector3f(0, 0.5f, 0);
    b[0].inv_mass = 0.0f;
    b[1].shape = ell;
    b[1].orientation = Eigen::Quaternionf(Eigen::AngleAxisf(0.3f, Eigen::Vector3f(1, 1, 0).normalized()));
    b[1].position = Eigen::Vector3f(0.05f, 1.35f, 0.02f);
    b[2].shape = box;
    b[2].position = Eigen::Vector3f(3, 0.5f, 0);
    b[2].inv_mass = 0.0f;
    b[3].shape = box;
    b[3].orientation = Eigen::Quaternionf(Eigen::AngleAxisf(0.2f, Eigen::Vector3f::UnitY()));
    b[3].position = Eigen::Vector3f(3.1f, 1.45f, 0);
    b[4].shape = cap;
    b[4].position = Eigen::Vector3f(-3, 0.2f, 0);
    // 120 points of the sphere of radius 0.5 (a golden-angle spiral) on a static box
    std::vector<Eigen::Vector3f> ball;
    for (int i = 0; i < 120; ++i) {
      const float z = 1.0f - (2.0f * static_cast<float>(i) + 1.0f) / 120.0f;
      const float r = std::sqrt(1.0f - z * z), t = 2.39996323f * static_cast<float>(i);
      ball.push_back(0.5f * Eigen::Vector3f(r * std::cos(t), r * std::sin(t), z));
    }
    ShapeId big;
    EXPECT_TRUE(IsOk(w->shapes().add_convex_hull(ball, &big)));
    b.resize(7);
    b[5].shape = box;
    b[5].position = Eigen::Vector3f(6, 0.5f, 0);
    b[5].inv_mass = 0.0f;
    b[6].shape = big;
    b[6].orientation = Eigen::Quaternionf(Eigen::AngleAxisf(0.4f, Eigen::Vector3f(0, 1, 1).normalized()));
    b[6].position = Eigen::Vector3f(6.02f, 1.48f, 0.01f);
    std::vector<BodyHandle> h(b.size());
    EXPECT_TRUE(IsOk(w->create_bodies(b, h)));
    EXPECT_TRUE(IsOk(w->step()));
    std::vector<float> depth(w->contacts().depth.begin(), w->contacts().depth.end());
    return depth;
  };
  const NarrowPhaseOptions simd;
  NarrowPhaseOptions scalar;
  scalar.simd = false;
  // (epa_max_iterations no longer reaches the step: every pair without a hull side has a
  // lane kernel, and EPA runs hull pairs to its tolerance: include/impact/narrowphase.h)
  NarrowPhaseOptions coarse;
  coarse.epa_tolerance = 0.2f;
  const std::vector<float> a = run(simd), s = run(scalar), c = run(coarse);
  ASSERT_GE(a.size(), 3u);
  ASSERT_EQ(a.size(), s.size());
  for (size_t i = 0; i < a.size(); ++i) EXPECT_NEAR(a[i], s[i], 1e-5f) << i;
  bool differs = a.size() != c.size();
  for (size_t i = 0; !differs && i < a.size(); ++i) differs = a[i] != c[i];
  EXPECT_TRUE(differs) << "a coarse EPA tolerance left every contact unchanged";
}

TEST(WorldShapes, DestroyingTheShapedBodiesReturnsToTheSpherePath) {
  auto w = make_world();
  add_floor(*w);
  ShapeId box;
  ASSERT_TRUE(IsOk(w->shapes().add_box(Eigen::Vector3f(0.5f, 0.5f, 0.5f), &box)));
  std::vector<BodyDesc> d(3);
  d[0].position = Eigen::Vector3f(0, 0.4f, 0);
  d[1].shape = box;
  d[1].position = Eigen::Vector3f(3, 0.4f, 0);
  d[2].position = Eigen::Vector3f(6, 0.4f, 0);
  std::vector<BodyHandle> h(3);
  ASSERT_TRUE(IsOk(w->create_bodies(d, h)));
  ASSERT_TRUE(IsOk(w->step()));
  EXPECT_EQ(w->contacts().size(), 3u);
  EXPECT_EQ(w->contacts().points(), 1u + 4u + 1u);
  EXPECT_EQ(w->last_step().contacts, 1u + 4u + 1u);
  EXPECT_EQ(w->last_step().manifolds, 3u);
  ASSERT_TRUE(IsOk(w->destroy_bodies({&h[1], 1})));
  EXPECT_EQ(w->contacts().size(), 0u);  // the last step's results named the old slots
  ASSERT_TRUE(IsOk(w->step()));
  EXPECT_EQ(w->contacts().size(), 2u);
  EXPECT_EQ(w->contacts().points(), 2u);
  EXPECT_TRUE(w->contacts().first_points.empty());  // the sphere path: one point each
}

// Two boxes stacked on a floor and a box resting on a tilted static slab: once at rest
// every corner keeps its point id from step to step (matched by position), and a
// manifold's ids are distinct. The box-box kernel reports the corners in an order that
// turns with rounding (1e-9 rad of normal jitter), so slot ids would not hold.
TEST(WorldShapes, RestingCornersKeepTheirPointIds) {
  auto w = make_world();
  PlaneDesc floor;
  PlaneHandle ph;
  IMPACT_ASSERT_OK(w->create_planes(std::span(&floor, 1), std::span(&ph, 1)));
  ShapeId cube, slab;
  IMPACT_ASSERT_OK(w->shapes().add_box(Eigen::Vector3f(0.5f, 0.5f, 0.5f), &cube));
  IMPACT_ASSERT_OK(w->shapes().add_box(Eigen::Vector3f(3.0f, 0.5f, 3.0f), &slab));
  const Eigen::Quaternionf tilt(Eigen::AngleAxisf(0.35f, Eigen::Vector3f::UnitZ()));
  const Eigen::Vector3f up = tilt * Eigen::Vector3f::UnitY(), slab_top(10.0f, 3.0f, 0.0f);
  std::vector<BodyDesc> d(4);
  d[0].shape = d[1].shape = d[3].shape = cube;
  d[0].position = {0.0f, 0.499f, 0.0f};
  d[1].position = {0.0f, 1.498f, 0.0f};
  d[2].shape = slab;
  d[2].inv_mass = 0.0f;
  d[2].orientation = tilt;
  d[2].position = slab_top - 0.5f * up;
  d[3].orientation = tilt;
  d[3].friction = 0.8f;
  d[3].position = slab_top + 0.499f * up;
  std::vector<BodyHandle> h(d.size());
  IMPACT_ASSERT_OK(w->create_bodies(d, h));
  struct Corner {
    Eigen::Vector3f p;
    uint32_t id;
  };
  std::vector<Corner> last;
  uint32_t checked = 0;
  for (int step = 0; step < 120; ++step) {
    IMPACT_ASSERT_OK(w->step());
    const ContactArrays c = w->contacts();
    ASSERT_EQ(c.point_feature.size(), c.points());
    std::vector<Corner> now;
    for (size_t m = 0; m < c.size(); ++m) {
      uint32_t seen = 0;
      for (size_t k = c.first_point(m); k < c.first_point(m) + c.point_count[m]; ++k) {
        const uint32_t id = c.point_feature[k];
        ASSERT_LT(id, 32u);
        EXPECT_EQ(seen & (1u << id), 0u) << "ids within a manifold are distinct";
        seen |= 1u << id;
        now.push_back({Eigen::Vector3f(c.point_x[k], c.point_y[k], c.point_z[k]), id});
      }
    }
    if (step >= 60) {
      ASSERT_EQ(now.size(), last.size()) << "the same contacts at rest";
      for (const Corner& x : now) {
        const auto near = std::min_element(last.begin(), last.end(), [&](const Corner& a, const Corner& b) {
          return (a.p - x.p).squaredNorm() < (b.p - x.p).squaredNorm();
        });
        ASSERT_LT((near->p - x.p).norm(), 1e-3f);
        EXPECT_EQ(near->id, x.id) << "step " << step << ": the corner at " << x.p.transpose() << " changed its id";
        ++checked;
      }
    }
    last = std::move(now);
  }
  EXPECT_EQ(checked, 60u * 12u) << "three four-point manifolds were checked every step";
}

}  // namespace
}  // namespace impact
