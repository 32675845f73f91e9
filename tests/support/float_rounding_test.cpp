// Roundings to float that a double computation relies on, checked on the bits of the
// result. GCC 12 (-O2 and -O3, any -march) folds (double)(float)x into a plain copy
// when SLP vectorisation turns two or more adjacent round trips into a vector
// narrowing and widening (scripts/slp_probe.sh reproduces it, docs/narrowphase.md
// "Precision"). These tests fail if that folding reaches
//   test::round_to_float (tests/support/test_support.h, a volatile float),
//   shared_targets' float-rounded edge midpoints (tests/support/mesh_input.h; the
//     naive cast<float>().cast<double>() there happened to survive, checked anyway),
//   ray_triangle's sheared vertex coordinates (kernels/raycast/ray_primitives.h).
#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include "kernels/raycast/ray_primitives.h"
#include "support/mesh_input.h"
#include "support/test_support.h"

namespace impact::test {
namespace {

/// True iff the double x (finite, in float's normal range) holds a float value: the 29
/// mantissa bits a float lacks are zero. Read from the bits, so no compiler folding of
/// a conversion can make it true.
bool holds_float(double x) {
  return (std::bit_cast<uint64_t>(x) & ((uint64_t{1} << 29) - 1)) == 0;
}

/// Values whose float rounding is visible: offsets of 1e5, thirds, small magnitudes.
std::vector<Eigen::Vector3d> needs_rounding(uint32_t n) {
  std::mt19937 g(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<Eigen::Vector3d> v;
  for (uint32_t i = 0; i < n; ++i) {
    const double s = i % 3 == 0 ? 1e5 : (i % 3 == 1 ? 1.0 : 1e-3);
    v.emplace_back(s * u(g) + 1.0 / 3.0, s * u(g) + 1.0 / 7.0, s * u(g) - 1.0 / 9.0);
  }
  return v;
}

TEST(FloatRounding, RoundToFloatRoundsEveryCoefficient) {
  int unrounded = 0, far = 0, unlike_scalar = 0;
  for (const Eigen::Vector3d& x : needs_rounding(3000)) {
    const Eigen::Vector3d r = round_to_float(x);
    for (int i = 0; i < 3; ++i) {
      unrounded += !holds_float(r[i]);
      // Round to nearest: within half a float ulp (2^-24 relative) of the input.
      far += !(std::fabs(r[i] - x[i]) <= 0x1p-24 * std::fabs(x[i]));
      unlike_scalar += round_to_float(x[i]) != r[i];
    }
    const Eigen::Matrix3d m = round_to_float(Eigen::Matrix3d(x * x.transpose()));
    for (int i = 0; i < 9; ++i) unrounded += !holds_float(m.data()[i]);
  }
  EXPECT_EQ(unrounded, 0);
  EXPECT_EQ(far, 0);
  EXPECT_EQ(unlike_scalar, 0);
}

TEST(FloatRounding, SharedTargetMidpointsAreFloats) {
  std::mt19937 rng(3);
  for (const double c : {0.0, 1e5}) {
    const TriMesh m = make_icosphere(2, 1.0, Eigen::Vector3d(c, -c, 0.5 * c), rng);
    const size_t edges = interior_edges(m).size();
    const std::vector<MeshTarget> t = shared_targets(m, 1e-6, rng);
    ASSERT_GE(t.size(), 4 * edges);
    int unrounded = 0;
    for (size_t e = 0; e < edges; ++e)  // per edge: the rounded midpoint first
      for (int i = 0; i < 3; ++i) unrounded += !holds_float(t[4 * e].p[i]);
    for (size_t k = 4 * edges; k < t.size(); ++k)  // then the (float) vertices
      for (int i = 0; i < 3; ++i) unrounded += !holds_float(t[k].p[i]);
    EXPECT_EQ(unrounded, 0) << "centre " << c;
  }
}

/// ray_triangle with each sheared coordinate rounded through round_to_float: the
/// function's documented arithmetic, written out with roundings no compiler can drop.
float ray_triangle_rounded(const kernels::RayQuery& q, const kernels::RayShear& s, const float* v0,
                           const float* v1, const float* v2) {
  const float A[3] = {v0[0] - q.o[0], v0[1] - q.o[1], v0[2] - q.o[2]};
  const float B[3] = {v1[0] - q.o[0], v1[1] - q.o[1], v1[2] - q.o[2]};
  const float C[3] = {v2[0] - q.o[0], v2[1] - q.o[1], v2[2] - q.o[2]};
  auto shear = [&](const float* P, uint32_t k, float sk) {
    return round_to_float(static_cast<double>(P[k]) - static_cast<double>(sk) * static_cast<double>(P[s.kz]));
  };
  const double ax = shear(A, s.kx, s.sx), ay = shear(A, s.ky, s.sy);
  const double bx = shear(B, s.kx, s.sx), by = shear(B, s.ky, s.sy);
  const double cx = shear(C, s.kx, s.sx), cy = shear(C, s.ky, s.sy);
  const double U = cx * by - cy * bx, V = ax * cy - ay * cx, W = bx * ay - by * ax;
  if ((U < 0.0 || V < 0.0 || W < 0.0) && (U > 0.0 || V > 0.0 || W > 0.0)) return -1.0f;
  const double det = U + V + W;
  if (det == 0.0) return -1.0f;
  const double sz = s.sz;
  const double t = (U * (sz * A[s.kz]) + V * (sz * B[s.kz]) + W * (sz * C[s.kz])) / det;
  if (!(t >= 0.0) || t > static_cast<double>(q.tmax)) return -1.0f;
  const float tf = static_cast<float>(t);
  return tf > q.tmax ? q.tmax : tf;
}

TEST(FloatRounding, RayTriangleShearIsRoundedToFloat) {
  std::mt19937 g(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  int hits = 0, differ = 0;
  for (int n = 0; n < 100000; ++n) {
    const double at = n % 2 ? 1e5 : 1.0;
    kernels::RayQuery q{};
    const Eigen::Vector3d d = Eigen::Vector3d(u(g), u(g), u(g)).normalized();
    for (int i = 0; i < 3; ++i) {
      q.o[i] = static_cast<float>(at + 2.0 * u(g));
      q.d[i] = static_cast<float>(d[i]);
    }
    q.tmax = 10.0f;
    q.mask = ~0u;
    float v[3][3];
    for (int k = 0; k < 3; ++k)
      for (int i = 0; i < 3; ++i) v[k][i] = static_cast<float>(q.o[i] + 2.0 * d[i] + 0.7 * u(g));
    const kernels::RayShear s = kernels::ray_shear(q);
    const float got = kernels::ray_triangle(q, s, v[0], v[1], v[2]);
    const float want = ray_triangle_rounded(q, s, v[0], v[1], v[2]);
    hits += want >= 0.0f;
    differ += std::bit_cast<uint32_t>(got) != std::bit_cast<uint32_t>(want);
  }
  EXPECT_GT(hits, 10000);  // the rays exercise the hit path
  EXPECT_EQ(differ, 0);
}

}  // namespace
}  // namespace impact::test
