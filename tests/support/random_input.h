// Random input shared by the shape and raycast tests: a seeded generator of uniform
// floats, indices, vectors, unit vectors and rotations, and a bumpy grid mesh.
#pragma once

#include <cstdint>
#include <random>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace impact::test {

struct TestRng {
  explicit TestRng(uint32_t seed) : g(seed) {}
  std::mt19937 g;
  float uni(float a, float b) { return std::uniform_real_distribution<float>(a, b)(g); }
  uint32_t pick(uint32_t n) { return std::uniform_int_distribution<uint32_t>(0, n - 1)(g); }
  Eigen::Vector3f vec(float a, float b) { return {uni(a, b), uni(a, b), uni(a, b)}; }
  Eigen::Vector3f unit() {
    for (;;) {
      const Eigen::Vector3f v = vec(-1, 1);
      const float n = v.norm();
      if (n > 0.1f && n <= 1.0f) return v / n;
    }
  }
  Eigen::Quaternionf quat() {
    Eigen::Vector4f c(uni(-1, 1), uni(-1, 1), uni(-1, 1), uni(-1, 1));
    c.normalize();
    return Eigen::Quaternionf(c[0], c[1], c[2], c[3]);
  }
};

/// A uniformly random rotation (a normalised quaternion of 4 normal draws), in double.
inline Eigen::Matrix3d random_rotation(std::mt19937& rng) {
  std::normal_distribution<double> g;
  Eigen::Quaterniond q(g(rng), g(rng), g(rng), g(rng));
  q.normalize();
  return q.toRotationMatrix();
}

/// A cells x cells grid of `spacing` m squares centred on the origin in the xz plane,
/// each vertex lifted by a uniform height in [-bump, bump]; two triangles per square.
inline void bumpy_grid(TestRng& r, int cells, float spacing, float bump, std::vector<Eigen::Vector3f>* v,
                       std::vector<uint32_t>* idx) {
  for (int j = 0; j <= cells; ++j)
    for (int i = 0; i <= cells; ++i)
      v->emplace_back(spacing * static_cast<float>(i - cells / 2), r.uni(-bump, bump),
                      spacing * static_cast<float>(j - cells / 2));
  for (int j = 0; j < cells; ++j)
    for (int i = 0; i < cells; ++i) {
      const uint32_t a = static_cast<uint32_t>(j * (cells + 1) + i), c = a + 1, d = a + (cells + 1), e = d + 1;
      idx->insert(idx->end(), {a, d, c, c, d, e});
    }
}

}  // namespace impact::test
