// Sphere-plane collision data (kernels/narrowphase/sphere_plane.*) through
// World::contacts(), against a double-precision reference built from the
// PlaneDesc as given (normal not unit, offset along that normal):
//   n_hat = normal / |normal|, h = n_hat . p - offset / |normal|,
//   contact iff h < r, for dynamic bodies whose layer/mask pass the plane's;
//   normal = -n_hat (from the sphere into the plane), depth = r - h,
//   point = midpoint of p - n_hat r and p - n_hat h.
// Body-plane contacts follow the body-body ones, ordered by body slot then plane.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <tuple>
#include <vector>

#include "impact/impact.h"
#include "support/test_support.h"

namespace impact {
namespace {

struct RefPlaneContact {
  uint32_t body, plane;
  double n[3], depth, point[3];
};

std::vector<RefPlaneContact> reference(const std::vector<BodyDesc>& bodies,
                                       const std::vector<PlaneDesc>& planes, double tol,
                                       std::vector<std::pair<uint32_t, uint32_t>>* borderline) {
  std::vector<RefPlaneContact> out;
  for (uint32_t i = 0; i < bodies.size(); ++i) {
    const BodyDesc& b = bodies[i];
    if (b.inv_mass == 0.0f) continue;
    for (uint32_t k = 0; k < planes.size(); ++k) {
      const PlaneDesc& p = planes[k];
      if ((b.layer & p.mask) == 0 || (p.layer & b.mask) == 0) continue;
      const double len = std::sqrt(double(p.normal.x()) * p.normal.x() + double(p.normal.y()) * p.normal.y() +
                                   double(p.normal.z()) * p.normal.z());
      const double nh[3] = {p.normal.x() / len, p.normal.y() / len, p.normal.z() / len};
      const double h =
          nh[0] * b.position.x() + nh[1] * b.position.y() + nh[2] * b.position.z() - p.offset / len;
      const double depth = b.radius - h;
      if (std::abs(depth) <= tol) {
        borderline->emplace_back(i, k);
        continue;
      }
      if (depth <= 0) continue;
      RefPlaneContact c{i, k, {-nh[0], -nh[1], -nh[2]}, depth, {}};
      const double pos[3] = {b.position.x(), b.position.y(), b.position.z()};
      for (int a = 0; a < 3; ++a) c.point[a] = pos[a] - nh[a] * 0.5 * (b.radius + h);
      out.push_back(c);
    }
  }
  return out;
}

void check(const std::vector<BodyDesc>& bodies, const std::vector<PlaneDesc>& planes, const char* what) {
  SCOPED_TRACE(what);
  auto world = test::make_world(test::zero_gravity_desc());
  ASSERT_TRUE(world);
  std::vector<PlaneHandle> ph(planes.size());
  IMPACT_ASSERT_OK(world->create_planes(planes, ph));
  std::vector<BodyHandle> bh(bodies.size());
  IMPACT_ASSERT_OK(world->create_bodies(bodies, bh));
  IMPACT_ASSERT_OK(world->step());

  double scale = 1.0;
  for (const BodyDesc& d : bodies) scale = std::max<double>(scale, d.position.cwiseAbs().maxCoeff());
  for (const PlaneDesc& p : planes) scale = std::max<double>(scale, std::abs(p.offset) / p.normal.norm());
  const double tol = 5e-7 * scale;
  std::vector<std::pair<uint32_t, uint32_t>> borderline;
  const auto ref = reference(bodies, planes, 4 * tol, &borderline);

  const ContactArrays c = world->contacts();
  std::vector<size_t> plane_rows;
  // A world of plain spheres: one point per manifold, point k belongs to manifold k.
  ASSERT_EQ(c.points(), c.size());
  ASSERT_TRUE(c.first_points.empty());
  bool plane_seen = false;
  for (size_t k = 0; k < c.size(); ++k) {
    if (c.b_is_plane[k]) {
      plane_seen = true;
      plane_rows.push_back(k);
    } else {
      EXPECT_FALSE(plane_seen) << "body-body contact " << k << " after a body-plane contact";
    }
  }
  EXPECT_EQ(world->last_step().plane_contacts, plane_rows.size());
  // Walk both lists in (body, plane) order; borderline entries may or may not appear.
  size_t r = 0;
  for (size_t row : plane_rows) {
    const uint32_t body = c.a[row], plane = c.b[row];
    while (r < ref.size() && std::tie(ref[r].body, ref[r].plane) < std::tie(body, plane)) {
      ADD_FAILURE() << "missing contact body " << ref[r].body << " plane " << ref[r].plane;
      ++r;
    }
    if (r == ref.size() || ref[r].body != body || ref[r].plane != plane) {
      const bool ok =
          std::find(borderline.begin(), borderline.end(), std::pair{body, plane}) != borderline.end();
      EXPECT_TRUE(ok) << "unexpected or out-of-order contact body " << body << " plane " << plane;
      continue;
    }
    const RefPlaneContact& e = ref[r++];
    EXPECT_NEAR(c.normal_x[row], e.n[0], 1e-6);
    EXPECT_NEAR(c.normal_y[row], e.n[1], 1e-6);
    EXPECT_NEAR(c.normal_z[row], e.n[2], 1e-6);
    EXPECT_NEAR(c.depth[row], e.depth, 2 * tol) << "body " << body << " plane " << plane;
    EXPECT_NEAR(c.point_x[row], e.point[0], 2 * tol);
    EXPECT_NEAR(c.point_y[row], e.point[1], 2 * tol);
    EXPECT_NEAR(c.point_z[row], e.point[2], 2 * tol);
  }
  for (; r < ref.size(); ++r)
    ADD_FAILURE() << "missing contact body " << ref[r].body << " plane " << ref[r].plane;
}

TEST(SpherePlaneContacts, FloorExact) {
  std::vector<BodyDesc> b(1);
  b[0].position = {2.0f, 0.25f, -1.0f};
  b[0].radius = 0.5f;
  std::vector<PlaneDesc> p(1);  // y <= 0 solid, +y free
  auto world = test::make_world(test::zero_gravity_desc());
  std::vector<PlaneHandle> ph(1);
  IMPACT_ASSERT_OK(world->create_planes(p, ph));
  std::vector<BodyHandle> bh(1);
  IMPACT_ASSERT_OK(world->create_bodies(b, bh));
  IMPACT_ASSERT_OK(world->step());
  const ContactArrays c = world->contacts();
  ASSERT_EQ(c.size(), 1u);
  EXPECT_EQ(c.b_is_plane[0], 1);
  EXPECT_EQ(c.a[0], 0u);
  EXPECT_EQ(c.b[0], 0u);
  EXPECT_EQ(c.normal_x[0], 0.0f);
  EXPECT_EQ(c.normal_y[0], -1.0f);  // -plane normal
  EXPECT_EQ(c.normal_z[0], 0.0f);
  EXPECT_EQ(c.depth[0], 0.25f);  // r - h
  EXPECT_EQ(c.point_x[0], 2.0f);
  EXPECT_EQ(c.point_y[0], -0.125f);  // midway between -0.25 and 0
  EXPECT_EQ(c.point_z[0], -1.0f);
}

TEST(SpherePlaneContacts, TiltedNonUnitPlanesRandomSpheres) {
  std::mt19937 rng(1);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  std::vector<PlaneDesc> planes;
  for (int k = 0; k < 5; ++k) {
    PlaneDesc p;
    p.normal = Eigen::Vector3f(u(rng), u(rng), u(rng)) * (static_cast<float>(k) + 0.5f);  // not unit
    p.offset = u(rng) * 3.0f;
    planes.push_back(p);
  }
  std::uniform_real_distribution<float> pos(-6.0f, 6.0f);
  std::uniform_real_distribution<float> rad(0.1f, 1.5f);
  std::vector<BodyDesc> bodies(test::scaled(2000));
  for (auto& b : bodies) {
    b.position = {pos(rng), pos(rng), pos(rng)};
    b.radius = rad(rng);
  }
  check(bodies, planes, "tilted planes");
}

TEST(SpherePlaneContacts, StaticBodiesAndFilters) {
  std::mt19937 rng(2);
  std::uniform_real_distribution<float> pos(-3.0f, 3.0f);
  std::vector<PlaneDesc> planes(3);
  planes[0].normal = {0, 1, 0};
  planes[0].offset = 0.0f;
  planes[0].layer = 1u;
  planes[0].mask = 0x3u;
  planes[1].normal = {1, 0, 0};
  planes[1].offset = -1.0f;
  planes[1].layer = 2u;
  planes[1].mask = 0x2u;
  planes[2].normal = {0, 0, -2};
  planes[2].offset = 2.0f;  // z >= -1 free
  std::vector<BodyDesc> bodies(test::scaled(1500));
  for (size_t i = 0; i < bodies.size(); ++i) {
    BodyDesc& b = bodies[i];
    b.position = {pos(rng), pos(rng), pos(rng)};
    b.radius = 0.8f;
    b.inv_mass = i % 5 == 0 ? 0.0f : 1.0f;  // static bodies never touch planes
    b.layer = 1u << (i % 3);
    b.mask = i % 2 ? 0xffffffffu : 0x1u;
  }
  check(bodies, planes, "static bodies and layer filters");
}

TEST(SpherePlaneContacts, OffsetFarFromOrigin) {
  std::vector<PlaneDesc> planes(1);
  planes[0].normal = {0.0f, 3.0f, 4.0f};
  planes[0].offset = 5.0e4f;  // 1e4 m along the unit normal
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> along(-1.0f, 1.0f);
  std::vector<BodyDesc> bodies(200);
  for (auto& b : bodies) {
    // Points near the surface: 1e4 * (0, .6, .8) plus a small offset.
    b.position = Eigen::Vector3f(3.0f * along(rng), 6000.0f + along(rng), 8000.0f + along(rng));
    b.radius = 1.0f;
  }
  check(bodies, planes, "plane 1e4 m from the origin");
}

}  // namespace
}  // namespace impact
