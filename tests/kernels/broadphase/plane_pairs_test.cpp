// The plane filter (kernels/broadphase/plane_pairs.*) against a brute-force reference
// in double: every (body, plane) pair whose bounding sphere touches or overlaps the
// plane is listed (so no contact can be lost), no pair farther than the documented
// slack is, filters (dynamic only, layers and masks both ways) hold, the order is (body,
// plane), and count and write agree for every split of the body range.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "kernels/broadphase/plane_pairs.h"
#include "support/test_support.h"

namespace impact {
namespace {

struct Scene {
  std::vector<float> px, py, pz, r, w;
  std::vector<uint32_t> layer, mask;
  std::vector<float> nx, ny, nz, off;
  std::vector<uint32_t> plane_layer, plane_mask;
  kernels::SphereView spheres() const { return {px.data(), py.data(), pz.data(), r.data()}; }
  kernels::BodyFilter filter() const { return {w.data(), layer.data(), mask.data()}; }
  kernels::PlaneView planes() const {
    return {nx.data(), ny.data(), nz.data(), off.data(), plane_layer.data(), plane_mask.data(),
            static_cast<uint32_t>(nx.size())};
  }
};

Scene random_scene(std::mt19937& g, uint32_t n, uint32_t planes, float scale) {
  std::uniform_real_distribution<float> u(-1.0f, 1.0f), rad(0.01f, 0.5f);
  Scene s;
  for (uint32_t j = 0; j < planes; ++j) {
    Eigen::Vector3d nrm(u(g), u(g), u(g));
    if (j % 4 == 0) nrm = Eigen::Vector3d::Unit(j % 3);  // axis-aligned planes too
    nrm.normalize();
    s.nx.push_back(static_cast<float>(nrm.x()));
    s.ny.push_back(static_cast<float>(nrm.y()));
    s.nz.push_back(static_cast<float>(nrm.z()));
    s.off.push_back(u(g) * scale * 0.5f);
    s.plane_layer.push_back(j % 5 == 0 ? 2u : 1u);
    s.plane_mask.push_back(j % 7 == 0 ? 2u : 0xffffffffu);
  }
  for (uint32_t i = 0; i < n; ++i) {
    float x = u(g) * scale, y = u(g) * scale, z = u(g) * scale;
    const float radius = rad(g);
    if (i % 5 == 0 && planes > 0) {  // exactly touching a plane (up to float rounding)
      const uint32_t j = i % planes;
      const float h = s.nx[j] * x + s.ny[j] * y + s.nz[j] * z - s.off[j];
      x -= s.nx[j] * (h - radius);
      y -= s.ny[j] * (h - radius);
      z -= s.nz[j] * (h - radius);
    }
    s.px.push_back(x);
    s.py.push_back(y);
    s.pz.push_back(z);
    s.r.push_back(radius);
    s.w.push_back(i % 11 == 0 ? 0.0f : 1.0f);
    s.layer.push_back(i % 3 == 0 ? 2u : 1u);
    s.mask.push_back(i % 13 == 0 ? 1u : 0xffffffffu);
  }
  return s;
}

std::vector<kernels::Pair> run(const Scene& s, uint32_t plane_base, std::initializer_list<uint32_t> cuts) {
  const auto n = static_cast<uint32_t>(s.px.size());
  const uint32_t words = kernels::plane_mask_words(static_cast<uint32_t>(s.nx.size()));
  std::vector<uint32_t> masks(static_cast<size_t>(words) * n + 1, 0xdeadbeefu);
  std::vector<uint32_t> bounds{0};
  for (uint32_t c : cuts) bounds.push_back(std::min(c, n));
  bounds.push_back(n);
  std::vector<uint64_t> offsets(bounds.size(), 0);
  for (size_t k = 0; k + 1 < bounds.size(); ++k)
    offsets[k + 1] = offsets[k] + kernels::plane_pair_masks(s.spheres(), s.filter(), s.planes(), masks.data(), n,
                                                            {bounds[k], bounds[k + 1]});
  EXPECT_EQ(masks.back(), 0xdeadbeefu) << "written past the masks";
  std::vector<kernels::Pair> out(offsets.back(), kernels::Pair{~0u, ~0u});
  for (size_t k = 0; k + 1 < bounds.size(); ++k)
    kernels::plane_pair_write(masks.data(), words, n, plane_base, out.data(), offsets[k], {bounds[k], bounds[k + 1]});
  return out;
}

void check(const Scene& s, const char* what) {
  SCOPED_TRACE(what);
  const uint32_t base = 1000;
  const auto got = run(s, base, {});
  // Order (body, plane), no duplicates, every written entry filled.
  for (size_t k = 1; k < got.size(); ++k)
    ASSERT_TRUE(got[k - 1].a < got[k].a || (got[k - 1].a == got[k].a && got[k - 1].b < got[k].b)) << k;
  std::vector<std::vector<bool>> listed(s.px.size(), std::vector<bool>(s.nx.size(), false));
  for (const kernels::Pair& p : got) {
    ASSERT_LT(p.a, s.px.size());
    ASSERT_GE(p.b, base);
    ASSERT_LT(p.b - base, s.nx.size());
    listed[p.a][p.b - base] = true;
  }
  size_t touching = 0;
  for (size_t i = 0; i < s.px.size(); ++i) {
    for (size_t j = 0; j < s.nx.size(); ++j) {
      const bool passes = s.w[i] > 0.0f && (s.layer[i] & s.plane_mask[j]) != 0 && (s.plane_layer[j] & s.mask[i]) != 0;
      const double c = double(s.nx[j]) * s.px[i] + double(s.ny[j]) * s.py[i] + double(s.nz[j]) * s.pz[i];
      const double gap = c - s.off[j] - s.r[i];  // > 0: the sphere clears the plane
      const double slack = 1e-4 * (std::fabs(c) + std::fabs(s.off[j]) + s.r[i]);
      if (!passes) {
        EXPECT_FALSE(listed[i][j]) << "filtered pair listed: body " << i << " plane " << j;
      } else if (gap <= 0.0) {
        ++touching;
        EXPECT_TRUE(listed[i][j]) << "touching pair missed: body " << i << " plane " << j << " gap " << gap;
      } else if (gap > 2.0 * slack) {
        EXPECT_FALSE(listed[i][j]) << "far pair listed: body " << i << " plane " << j << " gap " << gap;
      }
    }
  }
  EXPECT_GT(touching, 0u);
  // The same pairs for other splits of the body range.
  const auto n = static_cast<uint32_t>(s.px.size());
  for (auto cuts : {std::initializer_list<uint32_t>{1}, {n / 3, n / 2}, {7, 8, 9, n - 1}}) {
    const auto split = run(s, base, cuts);
    ASSERT_EQ(split.size(), got.size());
    for (size_t k = 0; k < got.size(); ++k) EXPECT_TRUE(split[k].a == got[k].a && split[k].b == got[k].b) << k;
  }
}

TEST(PlanePairs, RandomSpheresAndPlanesMatchBruteForce) {
  std::mt19937 g(11);
  for (int round = 0; round < 4; ++round) check(random_scene(g, test::scaled(3000), 1 + round * 3, 5.0f), "near");
}

TEST(PlanePairs, FarFromTheOrigin) {
  std::mt19937 g(12);
  Scene s = random_scene(g, test::scaled(2000), 6, 5.0f);
  for (size_t i = 0; i < s.px.size(); ++i) s.px[i] += 1e5f;
  for (size_t j = 0; j < s.nx.size(); ++j) s.off[j] += s.nx[j] * 1e5f;
  check(s, "1e5 m");
}

TEST(PlanePairs, MoreThanOneMaskWordOfPlanes) {
  std::mt19937 g(14);
  check(random_scene(g, test::scaled(500), 70, 3.0f), "70 planes");
}

TEST(PlanePairs, NoPlanesOrNoBodies) {
  std::mt19937 g(13);
  const Scene no_planes = random_scene(g, 100, 0, 1.0f);
  EXPECT_TRUE(run(no_planes, 0, {50}).empty());
  const Scene s = random_scene(g, 10, 3, 1.0f);
  std::vector<uint32_t> masks(10, 0);
  EXPECT_EQ(kernels::plane_pair_masks(s.spheres(), s.filter(), s.planes(), masks.data(), 10, {4, 4}), 0u);
}

}  // namespace
}  // namespace impact
