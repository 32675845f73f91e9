// Sphere-sphere collision data (kernels/narrowphase/sphere_sphere.*) read through
// World::contacts() after one step, against a double-precision reference:
//   contact iff |pb - pa| < ra + rb (touching is not a contact),
//   n = (pb - pa) / |pb - pa| (unit, from a to b), depth = ra + rb - |pb - pa|,
//   point = midpoint of the surfaces' deepest points pa + n ra and pb - n rb.
// Bodies rest without gravity, so the step's integration leaves positions
// bit-identical and the narrow phase sees the creation-time positions.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <random>
#include <utility>
#include <vector>

#include "impact/impact.h"
#include "support/test_support.h"

namespace impact {
namespace {

struct RefContact {
  double n[3];
  double depth;
  double point[3];
  double dist;
};

RefContact reference(const BodyDesc& a, const BodyDesc& b) {
  const double pa[3] = {a.position.x(), a.position.y(), a.position.z()};
  const double pb[3] = {b.position.x(), b.position.y(), b.position.z()};
  const double d[3] = {pb[0] - pa[0], pb[1] - pa[1], pb[2] - pa[2]};
  const double dist = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
  RefContact c;
  c.dist = dist;
  c.depth = static_cast<double>(a.radius) + b.radius - dist;
  for (int k = 0; k < 3; ++k) {
    c.n[k] = dist > 0 ? d[k] / dist : (k == 1 ? 1.0 : 0.0);
    c.point[k] = 0.5 * ((pa[k] + c.n[k] * a.radius) + (pb[k] - c.n[k] * b.radius));
  }
  return c;
}

std::vector<BodyDesc> random_spheres(uint32_t n, uint32_t seed, float offset) {
  std::mt19937 rng(seed);
  const float side = 1.1f * std::cbrt(static_cast<float>(n));
  std::uniform_real_distribution<float> pos(-0.5f * side, 0.5f * side);
  std::uniform_real_distribution<float> rad(0.1f, 0.6f);
  std::vector<BodyDesc> out(n);
  for (auto& d : out) {
    d.position = {offset + pos(rng), pos(rng), pos(rng)};
    d.radius = rad(rng);
    d.inv_mass = 1.0f;
  }
  return out;
}

void check_contacts(const std::vector<BodyDesc>& descs, const char* what, size_t min_contacts) {
  SCOPED_TRACE(what);
  auto world = test::make_world(test::zero_gravity_desc());
  ASSERT_TRUE(world);
  std::vector<BodyHandle> h(descs.size());
  IMPACT_ASSERT_OK(world->create_bodies(descs, h));
  for (uint32_t i = 0; i < h.size(); ++i) {
    uint32_t slot = 0;
    IMPACT_ASSERT_OK(world->slot_of(h[i], &slot));
    ASSERT_EQ(slot, i);  // no removals: slots follow creation order
  }
  IMPACT_ASSERT_OK(world->step());
  const ContactArrays c = world->contacts();
  const auto pairs = world->pairs();
  // A world of plain spheres: one point per manifold, point k belongs to manifold k.
  ASSERT_EQ(c.points(), c.size());
  ASSERT_TRUE(c.first_points.empty());

  double scale = 1.0;
  for (const BodyDesc& d : descs) scale = std::max<double>(scale, d.position.cwiseAbs().maxCoeff());
  // Float positions carry ~6e-8 relative error into differences of coordinates.
  const double tol = 4e-7 * scale;

  // Reference: every colliding pair, excluding pairs within rounding of touching.
  std::map<std::pair<uint32_t, uint32_t>, RefContact> ref;
  std::map<std::pair<uint32_t, uint32_t>, bool> borderline;
  for (uint32_t i = 0; i < descs.size(); ++i)
    for (uint32_t j = i + 1; j < descs.size(); ++j) {
      const RefContact r = reference(descs[i], descs[j]);
      if (std::abs(r.depth) <= 4 * tol)
        borderline[{i, j}] = true;
      else if (r.depth > 0)
        ref[{i, j}] = r;
    }
  ASSERT_GE(ref.size(), min_contacts);

  size_t seen = 0, body_body = 0;
  size_t pair_cursor = 0;  // contacts come in broad-phase pair order
  for (size_t k = 0; k < c.size(); ++k) {
    if (c.b_is_plane[k]) continue;
    ++body_body;
    const uint32_t a = c.a[k], b = c.b[k];
    ASSERT_LT(a, b);
    while (pair_cursor < pairs.size() && !(pairs[pair_cursor].a == a && pairs[pair_cursor].b == b))
      ++pair_cursor;
    ASSERT_LT(pair_cursor, pairs.size())
        << "contact " << k << " (" << a << ", " << b << ") out of broad-phase pair order";
    ++pair_cursor;
    const float nx = c.normal_x[k], ny = c.normal_y[k], nz = c.normal_z[k];
    ASSERT_TRUE(std::isfinite(nx) && std::isfinite(ny) && std::isfinite(nz));
    EXPECT_NEAR(std::sqrt(double(nx) * nx + double(ny) * ny + double(nz) * nz), 1.0, 1e-6);
    const auto it = ref.find({a, b});
    if (it == ref.end()) {
      EXPECT_TRUE(borderline.count({a, b})) << "contact (" << a << ", " << b << ") not in the reference";
      continue;
    }
    ++seen;
    const RefContact& r = it->second;
    const double ntol = tol / std::max(r.dist, 1e-3) + 1e-6;
    EXPECT_NEAR(nx, r.n[0], ntol) << a << "," << b;
    EXPECT_NEAR(ny, r.n[1], ntol) << a << "," << b;
    EXPECT_NEAR(nz, r.n[2], ntol) << a << "," << b;
    EXPECT_NEAR(c.depth[k], r.depth, 2 * tol) << a << "," << b;
    EXPECT_GT(c.depth[k], 0.0f);
    EXPECT_NEAR(c.point_x[k], r.point[0], 2 * tol) << a << "," << b;
    EXPECT_NEAR(c.point_y[k], r.point[1], 2 * tol) << a << "," << b;
    EXPECT_NEAR(c.point_z[k], r.point[2], 2 * tol) << a << "," << b;
  }
  EXPECT_EQ(seen, ref.size()) << "reference contacts missing from the world";
  EXPECT_EQ(world->last_step().contacts, c.size());
  EXPECT_EQ(world->last_step().contacts - world->last_step().plane_contacts, body_body);
}

TEST(SphereSphereContacts, RandomSpheresMatchReference) {
  check_contacts(random_spheres(test::scaled(1500), 1, 0.0f), "random", 500);
}

TEST(SphereSphereContacts, RandomSpheresFarFromOrigin) {
  check_contacts(random_spheres(test::scaled(800), 2, 1000.0f), "offset 1000 m", 250);
}

TEST(SphereSphereContacts, AxisAlignedAndDiagonalPairs) {
  std::vector<BodyDesc> d(6);
  d[0].position = {0, 0, 0};
  d[0].radius = 0.5f;
  d[1].position = {0.9f, 0, 0};  // depth 0.1 along +x
  d[1].radius = 0.5f;
  d[2].position = {10, 10, 10};
  d[2].radius = 1.0f;
  d[3].position = {10.5f, 10.5f, 10.5f};  // diagonal, unequal radii
  d[3].radius = 0.25f;
  d[4].position = {-10, 0, 0};
  d[4].radius = 2.0f;
  d[5].position = {-10, -2.5f, 0};  // depth 0.5 along -y
  d[5].radius = 1.0f;
  check_contacts(d, "hand-made", 3);

  // Exact values where float arithmetic is exact.
  auto world = test::make_world(test::zero_gravity_desc());
  std::vector<BodyHandle> h(2);
  IMPACT_ASSERT_OK(world->create_bodies(std::span(d).subspan(4, 2), h));
  IMPACT_ASSERT_OK(world->step());
  const ContactArrays c = world->contacts();
  ASSERT_EQ(c.size(), 1u);
  EXPECT_EQ(c.normal_x[0], 0.0f);
  EXPECT_EQ(c.normal_y[0], -1.0f);
  EXPECT_EQ(c.normal_z[0], 0.0f);
  EXPECT_EQ(c.depth[0], 0.5f);
  // Deepest points: (-10, -2, 0) and (-10, -1.5, 0); midway -1.75.
  EXPECT_EQ(c.point_x[0], -10.0f);
  EXPECT_EQ(c.point_y[0], -1.75f);
  EXPECT_EQ(c.point_z[0], 0.0f);
}

TEST(SphereSphereContacts, CoincidentCentresGiveFiniteUnitNormal) {
  std::vector<BodyDesc> d(3);
  for (auto& b : d) b.position = {1.5f, -2.0f, 3.0f};
  d[0].radius = 0.5f;
  d[1].radius = 0.25f;
  d[2].radius = 1.0f;
  auto world = test::make_world(test::zero_gravity_desc());
  std::vector<BodyHandle> h(3);
  IMPACT_ASSERT_OK(world->create_bodies(d, h));
  IMPACT_ASSERT_OK(world->step());
  const ContactArrays c = world->contacts();
  ASSERT_EQ(c.size(), 3u);
  for (size_t k = 0; k < c.size(); ++k) {
    const double nx = c.normal_x[k], ny = c.normal_y[k], nz = c.normal_z[k];
    ASSERT_TRUE(std::isfinite(nx) && std::isfinite(ny) && std::isfinite(nz));
    EXPECT_NEAR(std::sqrt(nx * nx + ny * ny + nz * nz), 1.0, 1e-6);
    const float ra = d[c.a[k]].radius, rb = d[c.b[k]].radius;
    EXPECT_EQ(c.depth[k], ra + rb);  // full overlap: ra + rb - 0
    // Midpoint of pa + n ra and pa - n rb.
    EXPECT_NEAR(c.point_x[k], 1.5 + nx * 0.5 * (ra - rb), 1e-6);
    EXPECT_NEAR(c.point_y[k], -2.0 + ny * 0.5 * (ra - rb), 1e-6);
    EXPECT_NEAR(c.point_z[k], 3.0 + nz * 0.5 * (ra - rb), 1e-6);
    EXPECT_TRUE(std::isfinite(c.impulse[k]));
  }
  // The bodies separate without NaN.
  for (int s = 0; s < 5; ++s) IMPACT_ASSERT_OK(world->step());
  const BodyArrays b = world->bodies();
  for (size_t i = 0; i < b.size(); ++i)
    EXPECT_TRUE(std::isfinite(b.pos_x[i]) && std::isfinite(b.pos_y[i]) && std::isfinite(b.pos_z[i]));
}

TEST(SphereSphereContacts, TouchingIsAPairButNotAContact) {
  std::vector<BodyDesc> d(2);
  d[0].position = {0, 0, 0};
  d[1].position = {1, 0, 0};  // radii 0.5 + 0.5 == distance
  auto world = test::make_world(test::zero_gravity_desc());
  std::vector<BodyHandle> h(2);
  IMPACT_ASSERT_OK(world->create_bodies(d, h));
  IMPACT_ASSERT_OK(world->step());
  EXPECT_EQ(world->pairs().size(), 1u);
  EXPECT_EQ(world->contacts().size(), 0u);
}

}  // namespace
}  // namespace impact
