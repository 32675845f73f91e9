// Probe for GCC 12's SLP folding of (double)(float)x into a copy (docs/narrowphase.md
// "Float roundings in double code"): runs the tests' float roundings
// (test::round_to_float, shared_targets' edge midpoints) and ray_triangle's sheared
// coordinates on fixed random inputs and prints a 64-bit FNV-1a hash of every output's
// bytes, plus one line per rounding that disagrees with a volatile one. A naive
// cast<float>().cast<double>() runs as a control, counted, not hashed. Built twice by
// scripts/slp_probe.sh (project flags, then with -fno-tree-slp-vectorize); the two
// hashes must match. Not part of the CMake build.
#include <Eigen/Core>

#include <cstdint>
#include <cstdio>
#include <cstring>
#include <random>
#include <vector>

#include "kernels/raycast/ray_primitives.h"
#include "support/mesh_input.h"
#include "support/test_support.h"

namespace {

uint64_t g_hash = 1469598103934665603ull;
void mix(const void* p, size_t n) {
  const auto* b = static_cast<const unsigned char*>(p);
  for (size_t i = 0; i < n; ++i) g_hash = (g_hash ^ b[i]) * 1099511628211ull;
}
double vround(double x) {
  volatile float f = static_cast<float>(x);
  return f;
}
int g_bad = 0;
int g_control = 0;  // naive round trips left unrounded: the compiler's folding, not ours
void expect_rounded(const char* what, const Eigen::Vector3d& got, const Eigen::Vector3d& in) {
  for (int i = 0; i < 3; ++i)
    if (got[i] != vround(in[i])) {
      if (g_bad++ < 20) std::printf("UNROUNDED %s[%d]: %.17g (float rounding %.17g)\n", what, i, got[i], vround(in[i]));
    }
}

// The naive Eigen round trip the tests used before test::round_to_float (control).
__attribute__((noinline)) Eigen::Vector3d naive_round(const Eigen::Vector3d& v) {
  return v.cast<float>().cast<double>();
}
// tests/support/test_support.h.
__attribute__((noinline)) Eigen::Vector3d guarded_round(const Eigen::Vector3d& v) {
  return impact::test::round_to_float(v);
}
__attribute__((noinline)) float ray_tri(const impact::kernels::RayQuery& q, const float* v0, const float* v1,
                                        const float* v2) {
  return impact::kernels::ray_triangle(q, impact::kernels::ray_shear(q), v0, v1, v2);
}

}  // namespace

int main() {
  std::mt19937_64 g(12345);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  // Values whose float rounding matters: 1e5 offsets, products of floats, thirds.
  for (int n = 0; n < 20000; ++n) {
    const double s = (n % 3 == 0) ? 1e5 : (n % 3 == 1 ? 1.0 : 1e-3);
    const Eigen::Vector3d v(s * u(g) + 1.0 / 3.0, s * u(g), s * u(g));
    const Eigen::Vector3d w(static_cast<double>(static_cast<float>(u(g))) * static_cast<float>(u(g)), s * u(g),
                            s * u(g));
    for (const Eigen::Vector3d& x : {v, w}) {
      const Eigen::Vector3d a = naive_round(x), b = guarded_round(x);
      mix(b.data(), sizeof(double) * 3);
      for (int i = 0; i < 3; ++i) g_control += a[i] != vround(x[i]);
      expect_rounded("test::round_to_float", b, x);
    }
  }
  // tests/support/mesh_input.h shared_targets: per interior edge the float-rounded
  // midpoint first, then three unrounded points.
  for (const double c : {0.0, 1e5}) {
    std::mt19937 rng(5);
    const impact::test::TriMesh m = impact::test::make_icosphere(3, 1.0, Eigen::Vector3d(c, -c, 0.5 * c), rng);
    const auto edges = impact::test::interior_edges(m);
    const auto t = impact::test::shared_targets(m, 1e-6, rng);
    for (size_t e = 0; e < edges.size(); ++e) {
      const Eigen::Vector3d a = m.v.col(edges[e][0]).cast<double>(), b = m.v.col(edges[e][1]).cast<double>();
      expect_rounded("shared_targets midpoint", t[4 * e].p, ((a + b) * 0.5).eval());
    }
    for (const auto& x : t) mix(x.p.data(), sizeof(double) * 3);
  }
  // ray_triangle: rays at 1e5 and near the unit cube, through shared edges of a fan.
  int hits = 0;
  for (int n = 0; n < 200000; ++n) {
    const float s = (n & 1) ? 1e5f : 1.0f;
    impact::kernels::RayQuery q{};
    Eigen::Vector3f d(static_cast<float>(u(g)), static_cast<float>(u(g)), static_cast<float>(u(g)));
    d.normalize();
    for (int i = 0; i < 3; ++i) q.o[i] = s + static_cast<float>(u(g) * 2.0), q.d[i] = d[i];
    q.tmax = 10.0f;
    float v[3][3];
    for (int k = 0; k < 3; ++k)
      for (int i = 0; i < 3; ++i) v[k][i] = q.o[i] + d[i] * 2.0f + static_cast<float>(u(g) * 0.7);
    const float t = ray_tri(q, v[0], v[1], v[2]);
    hits += t >= 0.0f;
    mix(&t, sizeof t);
  }
  std::printf("ray_triangle hits %d\n", hits);
  std::printf("control: naive round trips left unrounded %d\n", g_control);
  std::printf("unrounded %d\nhash %016llx\n", g_bad, static_cast<unsigned long long>(g_hash));
  return 0;
}
