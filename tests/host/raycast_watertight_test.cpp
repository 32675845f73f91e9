// Watertightness of every path that intersects triangles: kernels::ray_triangle by brute
// force over a mesh, RayScene on the LBVH and on Embree (robust), any-hit segments, and
// mesh shapes through raycast_shapes. Rays are aimed exactly at shared edges (float
// midpoints, random points, and points 1e-6 barycentric to either side) and shared
// vertices of random meshes with random winding: a closed icosphere (rays from inside),
// a closed fan around one vertex and a heightfield strip (rays from both sides), at
// scales 1e-2 .. 1e3 m and up to 1e5 m from the origin. The rule (include/impact/raycast.h):
// an edge or vertex belongs to every triangle sharing it, so no such ray may miss; from
// inside the closed icosphere every hit lies on one crossing (all triangles hit at one
// t), and the reported hit is checked against the double reference of
// tests/kernels/raycast/ray_reference.h and against Embree on the same rays.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "impact/impact.h"
#include "impact/shape_queries.h"
#include "kernels/raycast/ray_primitives.h"
#include "kernels/raycast/ray_reference.h"
#include "support/mesh_input.h"
#include "support/test_support.h"

namespace impact::test {
namespace {

struct Case {
  std::string name;
  TriMesh mesh;
  bool closed;
  Eigen::Vector3d centre;
  Eigen::Vector3d up;  ///< open meshes: roughly the surface normal (rays come along +-up)
  double size;
};

std::vector<Case> cases(uint32_t seed) {
  std::mt19937 rng(seed);
  std::vector<Case> out;
  const std::pair<double, double> scales[] = {{1.0, 0.0}, {1e-2, 0.0}, {1e3, 0.0}, {1.0, 1e4}, {50.0, 1e5}};
  for (const auto& [size, off] : scales) {
    const Eigen::Vector3d c = Eigen::Vector3d(off, -0.7 * off, 0.3 * off) + Eigen::Vector3d(0.31, -0.17, 0.05) * size;
    const std::string at = " size " + std::to_string(size) + " at " + std::to_string(off);
    out.push_back({"icosphere" + at, make_icosphere(2, size, c, rng), true, c, Eigen::Vector3d::UnitZ(), size});
    out.push_back({"fan" + at, make_fan(11, size, c, rng), false, c, Eigen::Vector3d::UnitZ(), size});
    std::uniform_real_distribution<float> h(-0.3f, 0.3f);
    const float cell = static_cast<float>(size / 3.0);
    Grid g = make_grid(6, 6, cell, (c - Eigen::Vector3d(size, 0, size)).cast<float>(), [&](float, float) { return h(rng) * cell; });
    std::bernoulli_distribution flip(0.5);
    for (Eigen::Index i = 0; i < g.t.cols(); ++i)
      if (flip(rng)) std::swap(g.t(1, i), g.t(2, i));
    out.push_back({"strip" + at, TriMesh{g.v, g.t}, false, c, Eigen::Vector3d::UnitY(), size});
  }
  return out;
}

// Rays at every shared target of the case: from inside (closed) or from either side.
std::vector<Ray> rays_of(const Case& c, std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0), h(0.5, 2.0);
  std::vector<Ray> rays;
  for (const MeshTarget& t : shared_targets(c.mesh, 1e-6, rng)) {
    for (int side = 0; side < (c.closed ? 1 : 2); ++side) {
      Eigen::Vector3d o;
      if (c.closed) {
        o = c.centre + 0.3 * c.size * Eigen::Vector3d(u(rng), u(rng), u(rng));
      } else {
        const Eigen::Vector3d lateral = 0.5 * c.size * Eigen::Vector3d(u(rng), u(rng), u(rng));
        o = t.p + (lateral - lateral.dot(c.up) * c.up) + (side == 0 ? 1.0 : -1.0) * h(rng) * c.size * c.up;
      }
      Ray r;
      r.origin = o.cast<float>();
      r.direction = (t.p - r.origin.cast<double>()).cast<float>();
      rays.push_back(r);
    }
  }
  return rays;
}

kernels::RayQuery query_of(const Ray& r) {
  kernels::RayQuery q;
  const Eigen::Vector3f d = r.direction.cast<double>().normalized().cast<float>();
  for (int k = 0; k < 3; ++k) {
    q.o[k] = r.origin[k];
    q.d[k] = d[k];
  }
  q.tmax = r.tmax;
  q.mask = ~0u;
  return q;
}

// Distance tolerance: float rounding of inputs at the scene's scale.
double tol_of(const Case& c) { return 1e-5 * std::max({1.0, c.size, c.centre.cwiseAbs().maxCoeff()}); }

// The kernel itself, by brute force over the mesh: every ray hits at least one
// triangle; from inside the closed mesh all hits lie on one crossing.
TEST(RaycastWatertight, KernelBruteForceNeverLeaks) {
  for (const Case& c : cases(7)) {
    std::mt19937 rng(11);
    const std::vector<Ray> rays = rays_of(c, rng);
    uint32_t leaks = 0;
    for (size_t i = 0; i < rays.size(); ++i) {
      const kernels::RayQuery q = query_of(rays[i]);
      const kernels::RayShear sh = kernels::ray_shear(q);
      float tmin = INFINITY, tmax = -INFINITY;
      for (Eigen::Index k = 0; k < c.mesh.t.cols(); ++k) {
        const float t = kernels::ray_triangle(q, sh, c.mesh.v.col(c.mesh.t(0, k)).data(), c.mesh.v.col(c.mesh.t(1, k)).data(),
                                              c.mesh.v.col(c.mesh.t(2, k)).data());
        if (t < 0.0f) continue;
        tmin = std::min(tmin, t);
        tmax = std::max(tmax, t);
      }
      if (tmin == INFINITY) {
        if (leaks++ < 5) {
          ADD_FAILURE() << c.name << ": ray " << i << " leaked, from " << rays[i].origin.transpose() << " along "
                        << rays[i].direction.transpose();
        }
        continue;
      }
      if (c.closed) {
        EXPECT_LE(tmax - tmin, tol_of(c)) << c.name << " ray " << i << ": hits on more than one crossing";
      }
    }
    EXPECT_EQ(leaks, 0u) << c.name << " of " << rays.size() << " rays";
  }
}

// RayScene on both backends, segments, and the mesh as a posed shape.
TEST(RaycastWatertight, ScenesAndShapesNeverLeakAndAgreeWithEmbree) {
  for (const Case& c : cases(8)) {
    std::mt19937 rng(12);
    const std::vector<Ray> rays = rays_of(c, rng);
    RefScene ref;
    add_mesh_ref(ref, c.mesh.v, c.mesh.t, 0, 1u);
    std::vector<std::vector<RayHit>> hits;
    for (const RayBackend b : {RayBackend::kLbvh, RayBackend::kEmbree}) {
      RaySceneDesc d;
      d.backend = b;
      std::unique_ptr<RayScene> s;
      IMPACT_ASSERT_OK(RayScene::create(d, &s));
      MeshHandle h;
      IMPACT_ASSERT_OK(s->add_mesh(c.mesh.v, c.mesh.t, 1u, &h));
      IMPACT_ASSERT_OK(s->commit());
      hits.emplace_back(rays.size());
      IMPACT_ASSERT_OK(s->closest_hit(rays, hits.back()));
      // Segments through the target and on past it.
      std::vector<Segment> segs(rays.size());
      for (size_t i = 0; i < rays.size(); ++i) {
        segs[i].from = rays[i].origin;
        segs[i].to = rays[i].origin + 2.0f * rays[i].direction;
      }
      std::vector<uint8_t> occ(rays.size());
      IMPACT_ASSERT_OK(s->any_hit(segs, occ));
      const char* bn = b == RayBackend::kLbvh ? "lbvh" : "embree";
      uint32_t leaks = 0;
      for (size_t i = 0; i < rays.size(); ++i) {
        const RayHit& hit = hits.back()[i];
        if (!hit.hit() || !occ[i]) {
          if (leaks++ < 5) {
            ADD_FAILURE() << c.name << " " << bn << ": ray " << i << " leaked (closest " << hit.hit() << ", any "
                          << int(occ[i]) << ")";
          }
          continue;
        }
        EXPECT_EQ(check_closest(ref, rays[i], hit, 1e-5), "") << c.name << " " << bn << " ray " << i;
      }
      EXPECT_EQ(leaks, 0u) << c.name << " " << bn << " of " << rays.size() << " rays";
    }
    for (size_t i = 0; i < rays.size(); ++i) {
      if (hits[0][i].hit() && hits[1][i].hit()) {
        EXPECT_NEAR(hits[0][i].t, hits[1][i].t, tol_of(c)) << c.name << " lbvh vs embree, ray " << i;
      }
    }

    // The same mesh as a shape at the identity pose: the same rays.
    ShapeSet set;
    std::vector<Eigen::Vector3f> verts(static_cast<size_t>(c.mesh.v.cols()));
    for (size_t k = 0; k < verts.size(); ++k) verts[k] = c.mesh.v.col(static_cast<Eigen::Index>(k));
    std::vector<uint32_t> idx(c.mesh.t.data(), c.mesh.t.data() + c.mesh.t.size());
    ShapeId id;
    IMPACT_ASSERT_OK(set.add_mesh(verts, idx, &id));
    const std::vector<ShapeId> shape_of = {id};
    const std::vector<Pose> poses = {Pose{}};
    std::vector<ObjectRay> orays(rays.size());
    for (size_t i = 0; i < rays.size(); ++i) orays[i].ray = rays[i];
    std::vector<ShapeRayHit> sh(rays.size());
    IMPACT_ASSERT_OK(raycast_shapes(set, shape_of, poses, orays, sh));
    uint32_t leaks = 0;
    for (size_t i = 0; i < rays.size(); ++i) {
      if (!sh[i].hit) {
        if (leaks++ < 5) {
          ADD_FAILURE() << c.name << " shape: ray " << i << " leaked";
        }
        continue;
      }
      EXPECT_NEAR(sh[i].t, hits[1][i].t, tol_of(c)) << c.name << " shape vs embree, ray " << i;
    }
    EXPECT_EQ(leaks, 0u) << c.name << " shape of " << rays.size() << " rays";
  }
}

}  // namespace
}  // namespace impact::test
