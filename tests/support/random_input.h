// Random input shared by the shape, raycast and narrow-phase tests: a seeded generator of
// uniform floats, indices, vectors, unit vectors and rotations, the double draws of the
// narrow-phase kernel tests (a unit vector, a rotation, a frame about a given axis, a
// cylinder's random pose), a generator's case loop (draw_cases), and a bumpy grid mesh.
#pragma once

#include <cmath>
#include <cstddef>
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

/// Three normal draws in double, x first (from a fresh distribution, so they depend on g
/// alone), drawn again while their length is at most 1e-3: a uniformly random direction
/// before normalisation (callers normalise as their arithmetic needs). The draws are
/// sequenced (a braced list): constructor arguments are evaluated in an unspecified order.
inline Eigen::Vector3d random_normal_draws(std::mt19937& g) {
  std::normal_distribution<double> d;
  for (;;) {
    const double c[3] = {d(g), d(g), d(g)};
    const Eigen::Vector3d v(c[0], c[1], c[2]);
    if (std::sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]) > 1e-3) return v;
  }
}

/// A uniformly random unit vector in double (random_normal_draws, normalised).
inline Eigen::Vector3d random_unit_vector(std::mt19937& g) {
  return random_normal_draws(g).normalized();
}

/// A rotation taking +z to the unit vector m, turned about m by a uniform random angle.
inline Eigen::Matrix3d frame_with_z(std::mt19937& g, const Eigen::Vector3d& m) {
  const Eigen::Vector3d t = m.unitOrthogonal();
  const double a = std::uniform_real_distribution<double>(0, 2 * M_PI)(g);
  const Eigen::Vector3d x = std::cos(a) * t + std::sin(a) * m.cross(t);
  Eigen::Matrix3d R;
  R.col(0) = x;
  R.col(1) = m.cross(x);
  R.col(2) = m;
  return R;
}

/// A uniformly random rotation as a row-major 3x3 in double: a quaternion of 4 normal
/// draws (drawn again while its length is below 1e-3), normalised (the matrix and
/// sphere-hull tests' draws).
inline void random_rotation_rows(std::mt19937& g, double m[9]) {
  std::normal_distribution<double> d(0.0, 1.0);
  double q[4], l = 0;
  do {
    for (double& c : q) c = d(g);
    l = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
  } while (l < 1e-3);
  const double w = q[0] / l, x = q[1] / l, y = q[2] / l, z = q[3] / l;
  const double r9[9] = {1 - 2 * (y * y + z * z), 2 * (x * y - w * z),     2 * (x * z + w * y),
                        2 * (x * y + w * z),     1 - 2 * (x * x + z * z), 2 * (y * z - w * x),
                        2 * (x * z - w * y),     2 * (y * z + w * x),     1 - 2 * (x * x + y * y)};
  for (int i = 0; i < 9; ++i) m[i] = r9[i];
}

/// A uniformly random rotation (a normalised quaternion of 4 normal draws), in double.
inline Eigen::Matrix3d random_rotation(std::mt19937& rng) {
  std::normal_distribution<double> g;
  Eigen::Quaterniond q(g(rng), g(rng), g(rng), g(rng));
  q.normalize();
  return q.toRotationMatrix();
}

/// make(0), make(1) .. make(n - 1), in that order: a generator's cases, each drawn from
/// the generator's random stream in turn.
template <class Make>
auto draw_cases(int n, Make make) {
  std::vector<decltype(make(0))> v;
  v.reserve(n > 0 ? static_cast<size_t>(n) : 0);
  for (int k = 0; k < n; ++k) v.push_back(make(k));
  return v;
}

/// A cylinder's random pose and size for the cylinder kernels' random-pose suites (Q has
/// p, R, rc, h): its centre within size / 2 of (offset, -offset, offset / 2) per axis, a
/// random rotation, radius and half height uniform in [0.1, 1] size.
template <class Q>
void random_cylinder(std::mt19937& g, double size, double offset, Q* q) {
  std::uniform_real_distribution<double> uni(0, 1);
  q->p = Eigen::Vector3d(offset, -offset, 0.5 * offset) +
         size * Eigen::Vector3d(uni(g) - 0.5, uni(g) - 0.5, uni(g) - 0.5);
  q->R = random_rotation(g);
  q->rc = size * (0.1 + 0.9 * uni(g));
  q->h = size * (0.1 + 0.9 * uni(g));
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
