// impact::NarrowPhase and impact::ShapeSet through the public API: validation,
// posed bounds, expansion of compounds and meshes (against per-child / per-triangle
// brute force), output order, determinism across backends and thread counts, pair
// order and swap symmetry. The kernels' accuracy against an independent reference is
// tests/kernels/narrowphase/matrix_test.cpp.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>
#include <vector>

#include "host/shapes/shape_store.h"
#include "impact/impact.h"
#include "tests/support/shape_zoo.h"
#include "tests/support/test_support.h"

namespace impact {
namespace {

using test::IsError;
using test::IsOk;
using test::random_pose;
using test::random_scene;
using test::Scene;
using test::Zoo;

TEST(ShapeSet, RejectsBadShapesNamingTheField) {
  ShapeSet s;
  ShapeId id;
  EXPECT_TRUE(IsError(s.add_sphere(-1.0f, &id), StatusCode::kInvalidArgument, {"sphere", "radius"}));
  EXPECT_TRUE(IsError(s.add_sphere(NAN, &id), StatusCode::kInvalidArgument, {"radius"}));
  EXPECT_TRUE(IsError(s.add_capsule(0.5f, -1.0f, &id), StatusCode::kInvalidArgument, {"half_length"}));
  EXPECT_TRUE(IsError(s.add_box(Eigen::Vector3f(1, 0, 1), &id), StatusCode::kInvalidArgument,
                      {"box", "half_extents[1]"}));
  EXPECT_TRUE(IsError(s.add_ellipsoid(Eigen::Vector3f(1, 1, INFINITY), &id), StatusCode::kInvalidArgument,
                      {"radii[2]"}));
  EXPECT_TRUE(IsError(s.add_half_space(Eigen::Vector3f::Zero(), 0.0f, &id), StatusCode::kInvalidArgument,
                      {"non-zero"}));
  const Eigen::Vector3f tri[3] = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}};
  const uint32_t idx[3] = {0, 1, 2};
  EXPECT_TRUE(IsError(s.add_mesh(tri, idx, &id), StatusCode::kInvalidArgument, {"triangle 0", "degenerate"}));
  const uint32_t bad[3] = {0, 1, 3};
  EXPECT_TRUE(IsError(s.add_mesh(tri, bad, &id), StatusCode::kInvalidArgument, {"out of range"}));
  const Eigen::Vector3f flat[4] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}};
  EXPECT_FALSE(s.add_convex_hull(flat, &id).ok());
  EXPECT_EQ(s.size(), 0u);
  ShapeId half;
  ASSERT_TRUE(IsOk(s.add_half_space(Eigen::Vector3f(0, 0, 1), 0.0f, &half)));
  const CompoundChild kids[1] = {{half, Pose{}}};
  EXPECT_TRUE(IsError(s.add_compound(kids, &id), StatusCode::kInvalidArgument, {"child 0", "half-space"}));
  EXPECT_TRUE(IsError(s.add_compound({}, &id), StatusCode::kInvalidArgument, {"at least one"}));
  EXPECT_EQ(s.size(), 1u);
}

// Posed bounds against the shapes' exact extents along the world axes, computed in
// double from the definitions (support points), for random poses.
TEST(ShapeSet, PosedBoundsAreTheExactExtents) {
  Zoo z;
  std::mt19937 rng(3);
  for (int it = 0; it < 200; ++it) {
    const Pose pose = random_pose(rng, 10.0f);
    const Eigen::Matrix3d R = pose.orientation.cast<double>().normalized().toRotationMatrix();
    const Eigen::Vector3d p = pose.position.cast<double>();
    for (int axis = 0; axis < 3; ++axis) {
      const Eigen::Vector3d d = R.transpose().col(axis);  // world axis in local frame
      // Local support value h(d) of each analytic shape.
      const double sphere = 0.5;
      const double capsule = 0.6 * std::fabs(d[2]) + 0.3;
      const double box = 0.4 * std::fabs(d[0]) + 0.3 * std::fabs(d[1]) + 0.7 * std::fabs(d[2]);
      const double cyl = 0.5 * std::fabs(d[2]) + 0.4 * std::hypot(d[0], d[1]);
      const double ell = Eigen::Vector3d(0.6 * d[0], 0.3 * d[1], 0.4 * d[2]).norm();
      const std::pair<ShapeId, double> cases[] = {
          {z.sphere, sphere}, {z.capsule, capsule}, {z.box, box}, {z.cylinder, cyl}, {z.ellipsoid, ell}};
      for (const auto& [id, h] : cases) {
        Eigen::Vector3f lo, hi;
        ASSERT_TRUE(IsOk(z.set.bounds(id, pose, &lo, &hi)));
        const double tol = 1e-5 * (1.0 + std::fabs(p[axis]));
        EXPECT_NEAR(hi[axis], p[axis] + h, tol) << "shape " << id.index << " axis " << axis;
        EXPECT_NEAR(lo[axis], p[axis] - h, tol) << "shape " << id.index << " axis " << axis;
      }
      Eigen::Vector3f lo, hi;
      ASSERT_TRUE(IsOk(z.set.bounds(z.aabb, pose, &lo, &hi)));
      const double aabb_half[3] = {0.5, 0.2, 0.3};
      EXPECT_NEAR(hi[axis], p[axis] + aabb_half[axis], 1e-5 * (1.0 + std::fabs(p[axis])));
    }
  }
  Eigen::Vector3f lo, hi;
  EXPECT_TRUE(IsError(z.set.bounds(z.half_space, Pose{}, &lo, &hi), StatusCode::kInvalidArgument, {"unbounded"}));
}

TEST(ShapeSet, MassPropertiesOfASphere) {
  ShapeSet s;
  ShapeId id;
  ASSERT_TRUE(IsOk(s.add_sphere(2.0f, &id)));
  MassProperties m;
  ASSERT_TRUE(IsOk(s.mass_properties(id, 3.0f, &m)));
  const double v = 4.0 / 3.0 * M_PI * 8.0;
  EXPECT_NEAR(m.volume, v, 1e-9 * v);
  EXPECT_NEAR(m.mass, 3.0 * v, 1e-9 * v);
  EXPECT_NEAR(m.inertia(0, 0), 0.4 * 3.0 * v * 4.0, 1e-6 * v);
  EXPECT_TRUE(IsError(s.mass_properties(id, -1.0f, &m), StatusCode::kInvalidArgument, {"density"}));
}

TEST(NarrowPhase, RejectsBadInputNamingTheObject) {
  Zoo z;
  NarrowPhase np;
  std::vector<Manifold> out;
  std::vector<ShapeId> shapes = {z.sphere, z.box, z.half_space, z.half_space};
  std::vector<Pose> poses(4);
  std::vector<ShapePair> pairs = {{0, 1}};
  EXPECT_TRUE(IsOk(np.collide(z.set, shapes, poses, pairs, &out)));
  EXPECT_TRUE(IsError(np.collide(z.set, shapes, std::span(poses).first(3), pairs, &out),
                      StatusCode::kSizeMismatch));
  poses[1].position.x() = NAN;
  EXPECT_TRUE(IsError(np.collide(z.set, shapes, poses, pairs, &out), StatusCode::kInvalidArgument,
                      {"object 1", "position"}));
  poses[1] = Pose{};
  poses[0].orientation = Eigen::Quaternionf(1.1f, 0, 0, 0);
  EXPECT_TRUE(IsError(np.collide(z.set, shapes, poses, pairs, &out), StatusCode::kInvalidArgument,
                      {"object 0", "unit quaternion"}));
  poses[0] = Pose{};
  shapes[1] = ShapeId{999};
  EXPECT_TRUE(IsError(np.collide(z.set, shapes, poses, pairs, &out), StatusCode::kInvalidArgument,
                      {"object 1", "unknown shape"}));
  shapes[1] = z.box;
  pairs = {{0, 4}};
  EXPECT_TRUE(IsError(np.collide(z.set, shapes, poses, pairs, &out), StatusCode::kInvalidArgument,
                      {"pair 0", "out of range"}));
  pairs = {{0, 1}, {1, 1}};
  EXPECT_TRUE(IsError(np.collide(z.set, shapes, poses, pairs, &out), StatusCode::kInvalidArgument,
                      {"pair 1", "itself"}));
  pairs = {{2, 3}};
  EXPECT_TRUE(IsError(np.collide(z.set, shapes, poses, pairs, &out), StatusCode::kInvalidArgument,
                      {"pair 0", "half-spaces"}));
  NarrowPhaseOptions bad;
  bad.gjk_tolerance = 0.0f;
  EXPECT_TRUE(IsError(np.set_options(bad), StatusCode::kInvalidArgument, {"gjk_tolerance"}));
  NarrowPhase np_bad(bad);
  pairs = {{0, 1}};
  EXPECT_TRUE(IsError(np_bad.collide(z.set, shapes, poses, pairs, &out), StatusCode::kInvalidArgument,
                      {"gjk_tolerance"}));
}

/// A random scene of every shape type, close enough that about half the pairs touch.
bool same_bytes(const std::vector<Manifold>& x, const std::vector<Manifold>& y) {
  if (x.size() != y.size()) return false;
  return std::memcmp(x.data(), y.data(), x.size() * sizeof(Manifold)) == 0;
}

void expect_well_formed(const std::vector<Manifold>& out, size_t pair_count) {
  for (size_t i = 0; i < out.size(); ++i) {
    const Manifold& m = out[i];
    ASSERT_LT(m.pair, pair_count);
    EXPECT_TRUE(m.normal.allFinite());
    EXPECT_NEAR(m.normal.norm(), 1.0f, 1e-4f);
    EXPECT_GT(m.depth, 0.0f);
    EXPECT_GE(m.point_count, 1u);
    EXPECT_LE(m.point_count, 4u);
    if (i > 0) {  // sorted by (pair, child_a, child_b), no duplicates
      const Manifold& p = out[i - 1];
      EXPECT_TRUE(std::tie(p.pair, p.child_a, p.child_b) < std::tie(m.pair, m.child_a, m.child_b));
    }
  }
}

TEST(NarrowPhase, SameBytesForEveryBackendAndThreadCount) {
  Zoo z;
  const Scene s = random_scene(z, 600, test::scaled(6000), 11);
  std::vector<Manifold> ref;
  NarrowPhase serial(NarrowPhaseOptions{.exec = {Backend::kSerial, 1}});
  ASSERT_TRUE(IsOk(serial.collide(z.set, s.shapes, s.poses, s.pairs, &ref)));
  expect_well_formed(ref, s.pairs.size());
  EXPECT_GT(ref.size(), s.pairs.size() / 10);
  for (const test::ExecCase& c : test::exec_cases()) {
    NarrowPhaseOptions o;
    o.exec = {c.backend, c.threads};
    NarrowPhase np(o);
    std::vector<Manifold> out;
    ASSERT_TRUE(IsOk(np.collide(z.set, s.shapes, s.poses, s.pairs, &out)));
    EXPECT_TRUE(same_bytes(ref, out)) << test::to_string(c);
    // Twice with the same object: scratch reuse changes nothing.
    ASSERT_TRUE(IsOk(np.collide(z.set, s.shapes, s.poses, s.pairs, &out)));
    EXPECT_TRUE(same_bytes(ref, out)) << test::to_string(c) << " second call";
  }
}

// A pair's manifolds do not depend on where the pair sits in the list; swapping a
// and b flips the normal and keeps depth and points.
TEST(NarrowPhase, PairOrderAndSwapSymmetry) {
  Zoo z;
  const Scene s = random_scene(z, 300, test::scaled(3000), 12);
  NarrowPhase np;
  std::vector<Manifold> ref;
  ASSERT_TRUE(IsOk(np.collide(z.set, s.shapes, s.poses, s.pairs, &ref)));
  std::vector<uint32_t> perm(s.pairs.size());
  for (uint32_t i = 0; i < perm.size(); ++i) perm[i] = i;
  std::mt19937 rng(5);
  std::shuffle(perm.begin(), perm.end(), rng);
  std::vector<ShapePair> shuffled(s.pairs.size()), swapped(s.pairs.size());
  for (uint32_t i = 0; i < perm.size(); ++i) {
    shuffled[i] = s.pairs[perm[i]];
    swapped[i] = {s.pairs[i].b, s.pairs[i].a};
  }
  std::vector<Manifold> sh, sw;
  ASSERT_TRUE(IsOk(np.collide(z.set, s.shapes, s.poses, shuffled, &sh)));
  ASSERT_TRUE(IsOk(np.collide(z.set, s.shapes, s.poses, swapped, &sw)));
  ASSERT_EQ(sh.size(), ref.size());
  // Map back: manifolds of shuffled pair i belong to original pair perm[i].
  std::vector<std::vector<const Manifold*>> by_pair(s.pairs.size());
  for (const Manifold& m : ref) by_pair[m.pair].push_back(&m);
  std::vector<size_t> seen(s.pairs.size(), 0);
  for (const Manifold& m : sh) {
    const uint32_t orig = perm[m.pair];
    ASSERT_LT(seen[orig], by_pair[orig].size());
    const Manifold& r = *by_pair[orig][seen[orig]++];
    EXPECT_EQ(r.child_a, m.child_a);
    EXPECT_EQ(r.child_b, m.child_b);
    EXPECT_EQ(r.depth, m.depth);
    EXPECT_EQ(r.normal, m.normal);
  }
  // Swapped: same set of (pair, child) with children exchanged; normal flipped.
  std::vector<std::vector<const Manifold*>> sw_by_pair(s.pairs.size());
  for (const Manifold& m : sw) sw_by_pair[m.pair].push_back(&m);
  size_t compared = 0, mismatched = 0;
  for (size_t k = 0; k < s.pairs.size(); ++k) {
    for (const Manifold* r : by_pair[k]) {
      const Manifold* f = nullptr;
      for (const Manifold* m : sw_by_pair[k])
        if (m->child_a == r->child_b && m->child_b == r->child_a) f = m;
      if (f == nullptr) {
        // A contact this shallow may flip to "touching" under the other rounding.
        if (r->depth > 1e-4f) ++mismatched;
        continue;
      }
      ++compared;
      const float tol = 2e-3f * (1.0f + r->depth);
      if ((f->normal + r->normal).norm() > 1e-2f || std::fabs(f->depth - r->depth) > tol) ++mismatched;
    }
  }
  EXPECT_GT(compared, ref.size() / 2);
  // Deep overlaps between non-strictly-convex shapes can have two equally good
  // directions; allow a small share of ties to resolve differently.
  EXPECT_LE(mismatched, ref.size() / 50 + 1) << "of " << ref.size();
}

// Compounds: the manifolds of (compound, x) are exactly those of (child_i at its
// composed pose, x), child by child. Meshes: those of (one-triangle mesh, x) per
// triangle — a brute force over all triangles, so the mesh BVH may cull nothing real.
TEST(NarrowPhase, CompoundsAndMeshesMatchTheirPiecesOneByOne) {
  Zoo z;
  // The compound's children and the mesh's triangles as separate shapes.
  const ShapeStore& st = z.set.store();
  std::vector<ShapeId> tri_shapes;
  const MeshData mesh = st.meshes[st.shapes[z.mesh.index].ref];  // a copy: add_mesh below grows the store
  for (uint32_t t = 0; t < mesh.triangle_count(); ++t) {
    const Eigen::Vector3f v[3] = {mesh.vertices[mesh.indices[3 * t]], mesh.vertices[mesh.indices[3 * t + 1]],
                                  mesh.vertices[mesh.indices[3 * t + 2]]};
    const uint32_t idx[3] = {0, 1, 2};
    ShapeId id;
    ASSERT_TRUE(IsOk(z.set.add_mesh(v, idx, &id)));
    tri_shapes.push_back(id);
  }
  const uint32_t cb = st.child_begin[st.shapes[z.compound.index].ref];
  const uint32_t ce = st.child_begin[st.shapes[z.compound.index].ref + 1];
  std::mt19937 rng(21);
  const std::vector<ShapeId> others = {z.sphere, z.capsule, z.box, z.convex, z.cylinder, z.ellipsoid,
                                       z.half_space, z.compound};
  NarrowPhase np;
  size_t total = 0, count_differs = 0;
  for (int it = 0; it < 300; ++it) {
    const ShapeId other = others[rng() % others.size()];
    const bool use_mesh = it % 2 == 0;
    Pose pc = random_pose(rng, 1.0f);
    Pose po = random_pose(rng, 1.0f);
    if (use_mesh) pc = Pose{};
    const ShapeId container = use_mesh ? z.mesh : z.compound;
    std::vector<ShapeId> shapes = {container, other};
    std::vector<Pose> poses = {pc, po};
    std::vector<ShapePair> pairs = {{0, 1}};
    std::vector<Manifold> whole;
    ASSERT_TRUE(IsOk(np.collide(z.set, shapes, poses, pairs, &whole)));
    // Pieces.
    std::vector<ShapeId> ps = {other};
    std::vector<Pose> pp = {po};
    std::vector<uint32_t> piece_child;
    if (use_mesh) {
      for (uint32_t t = 0; t < tri_shapes.size(); ++t) {
        ps.push_back(tri_shapes[t]);
        pp.push_back(pc);
        piece_child.push_back(t);
      }
    } else {
      for (uint32_t c = cb; c < ce; ++c) {
        ps.push_back(st.children[c].shape);
        Pose w;
        w.orientation = pc.orientation * st.children[c].local.orientation;
        w.position = pc.orientation * st.children[c].local.position + pc.position;
        pp.push_back(w);
        piece_child.push_back(c - cb);
      }
    }
    std::vector<ShapePair> pieces;
    for (uint32_t i = 1; i < ps.size(); ++i) pieces.push_back({i, 0});
    std::vector<Manifold> parts;
    ASSERT_TRUE(IsOk(np.collide(z.set, ps, pp, pieces, &parts)));
    if (other == z.compound) {
      // Pieces against a compound come back per (piece, other child); compare counts
      // by (child_a, child_b).
      ASSERT_EQ(parts.size(), whole.size()) << "iteration " << it;
    } else {
      ASSERT_EQ(parts.size(), whole.size()) << "iteration " << it << " other " << other.index;
    }
    for (size_t i = 0; i < parts.size(); ++i) {
      const Manifold& p = parts[i];
      const Manifold& w = whole[i];
      EXPECT_EQ(w.child_a, piece_child[p.pair]) << "iteration " << it;
      EXPECT_EQ(w.child_b, p.child_b);
      // Composed poses round differently from the compound's own composition.
      EXPECT_NEAR(w.depth, p.depth, 1e-4f * (1.0f + p.depth)) << "iteration " << it;
      EXPECT_LT((w.normal - p.normal).norm(), 1e-3f) << "iteration " << it;
      // The clipped manifold's vertex count can change where a polygon corner sits
      // within rounding of a clipping plane; counted below.
      if (w.point_count != p.point_count) ++count_differs;
    }
    total += whole.size();
  }
  EXPECT_GT(total, 100u);
  EXPECT_LE(count_differs, total / 20) << "of " << total;
}

// The scalar reference path of every kernel finds the same contacts as the SIMD path.
TEST(NarrowPhase, ScalarPathAgreesWithSimdPath) {
  Zoo z;
  const Scene s = random_scene(z, 400, test::scaled(4000), 13);
  NarrowPhaseOptions o;
  NarrowPhase simd(o);
  o.simd = false;
  NarrowPhase scalar(o);
  std::vector<Manifold> a, b;
  ASSERT_TRUE(IsOk(simd.collide(z.set, s.shapes, s.poses, s.pairs, &a)));
  ASSERT_TRUE(IsOk(scalar.collide(z.set, s.shapes, s.poses, s.pairs, &b)));
  ASSERT_EQ(a.size(), b.size());
  size_t differ = 0;
  for (size_t i = 0; i < a.size(); ++i) {
    ASSERT_EQ(a[i].pair, b[i].pair);
    ASSERT_EQ(a[i].child_a, b[i].child_a);
    ASSERT_EQ(a[i].child_b, b[i].child_b);
    if (std::fabs(a[i].depth - b[i].depth) > 1e-4f * (1.0f + a[i].depth) ||
        (a[i].normal - b[i].normal).norm() > 1e-3f)
      ++differ;
  }
  // FMA contraction differs between the paths; near-ties may pick another axis.
  EXPECT_LE(differ, a.size() / 200 + 1) << "of " << a.size();
}

TEST(NarrowPhase, HullFacesOfManyVerticesKeepTheirManifold) {
  // A 64-gon prism (caps of 64 vertices: a cylinder as a hull) lying on its cap, 0.01
  // into a box, a box-shaped hull and another such prism: face contacts whose manifold
  // comes from clipping the cap (a cap over the clip buffers' size would give one point).
  ShapeSet set;
  ShapeId box, box_hull, prism, big_prism;
  ASSERT_TRUE(IsOk(set.add_box(Eigen::Vector3f(1.0f, 0.5f, 1.0f), &box)));
  std::vector<Eigen::Vector3f> corners;
  for (int i = 0; i < 8; ++i)
    corners.emplace_back((i & 1) ? 1.0f : -1.0f, (i & 2) ? 0.5f : -0.5f, (i & 4) ? 1.0f : -1.0f);
  ASSERT_TRUE(IsOk(set.add_convex_hull(corners, &box_hull)));
  auto ngon = [&](int n, float r, ShapeId* id) {
    std::vector<Eigen::Vector3f> pts;
    for (int i = 0; i < n; ++i) {
      const double t = 2 * M_PI * i / n;
      for (const float y : {-0.2f, 0.2f})
        pts.emplace_back(static_cast<float>(r * std::cos(t)), y, static_cast<float>(r * std::sin(t)));
    }
    ASSERT_TRUE(IsOk(set.add_convex_hull(pts, id)));
  };
  ngon(64, 0.5f, &prism);
  ngon(200, 0.8f, &big_prism);
  const std::vector<ShapeId> shapes = {box, box_hull, big_prism, prism};
  std::vector<Pose> poses(4);
  poses[2].position = Eigen::Vector3f(0.0f, -0.4f + 0.19f, 0.0f);  // its top 0.01 into the next
  poses[3].position = Eigen::Vector3f(0.1f, 0.5f + 0.2f - 0.01f, -0.05f);
  for (uint32_t a : {0u, 1u, 2u}) {
    SCOPED_TRACE(a);
    if (a == 2) poses[3].position.y() = -0.01f + 0.19f;  // on the big prism's top cap (y = 0)
    NarrowPhase np;
    std::vector<Manifold> out;
    const std::vector<ShapePair> pairs = {{a, 3}};
    ASSERT_TRUE(IsOk(np.collide(set, shapes, poses, pairs, &out)));
    ASSERT_EQ(out.size(), 1u);
    const Manifold& m = out[0];
    EXPECT_NEAR(m.normal.y(), 1.0f, 1e-5f);
    EXPECT_NEAR(m.depth, 0.01f, 1e-5f);
    EXPECT_EQ(m.point_count, 4u);
    for (uint32_t i = 0; i < m.point_count; ++i) {
      EXPECT_NEAR(m.point_depth[i], 0.01f, 1e-5f) << i;
      // on the prism's bottom rim, seen along the normal
      const Eigen::Vector3f q = m.points[i] - poses[3].position;
      EXPECT_NEAR(std::hypot(q.x(), q.z()), 0.5f, 1e-3f) << i;
    }
  }
}

TEST(NarrowPhase, EmptyInputsGiveNoManifolds) {
  Zoo z;
  NarrowPhase np;
  std::vector<Manifold> out(3);
  ASSERT_TRUE(IsOk(np.collide(z.set, {}, {}, {}, &out)));
  EXPECT_TRUE(out.empty());
  // Far apart: nothing.
  std::vector<ShapeId> shapes = {z.box, z.mesh};
  std::vector<Pose> poses(2);
  poses[0].position = Eigen::Vector3f(100, 100, 100);
  std::vector<ShapePair> pairs = {{0, 1}};
  ASSERT_TRUE(IsOk(np.collide(z.set, shapes, poses, pairs, &out)));
  EXPECT_TRUE(out.empty());
}

}  // namespace
}  // namespace impact
