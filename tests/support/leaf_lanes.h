// One side of a narrow-phase kernel bucket as owning SoA lanes (kernels::LeafSoA), and
// one pair's collision data read back in double: shared by the kernel-level tests
// that drive the general convex kernels pair by pair.
#pragma once

#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "kernels/narrowphase/leaf.h"

namespace impact::test {

/// Lanes filled from a test shape with fields p, R (3x3, row-major into LeafSoA::r),
/// e and hull, and the triangle corners v1, v2 (LeafSoA::w) when its type has them.
struct LeafLanes {
  std::vector<float> p[3], r[9], e[3], w[6];
  std::vector<uint32_t> ref;

  template <class S>
  void push(const S& s) {
    for (int i = 0; i < 3; ++i) p[i].push_back(static_cast<float>(s.p[i]));
    for (int i = 0; i < 9; ++i) r[i].push_back(static_cast<float>(s.R(i / 3, i % 3)));
    for (int i = 0; i < 3; ++i) e[i].push_back(static_cast<float>(s.e[i]));
    for (int i = 0; i < 3; ++i) {
      if constexpr (requires { s.v1; s.v2; }) {
        w[i].push_back(static_cast<float>(s.v1[i]));
        w[3 + i].push_back(static_cast<float>(s.v2[i]));
      } else {
        w[i].push_back(0.0f);
        w[3 + i].push_back(0.0f);
      }
    }
    ref.push_back(s.hull);
  }

  kernels::LeafSoA soa() const {
    kernels::LeafSoA s{};
    for (int i = 0; i < 3; ++i) s.p[i] = p[i].data();
    for (int i = 0; i < 9; ++i) s.r[i] = r[i].data();
    for (int i = 0; i < 3; ++i) s.e[i] = e[i].data();
    for (int i = 0; i < 6; ++i) s.w[i] = w[i].data();
    s.ref = ref.data();
    return s;
  }
};

/// One pair's collision data in double: count, normal (A to B), depth, points and
/// their depths.
struct PairResult {
  uint32_t count = 0;
  Eigen::Vector3d n = Eigen::Vector3d::Zero();
  double depth = 0;
  Eigen::Vector3d pt[4];
  double pd[4] = {0, 0, 0, 0};
};

}  // namespace impact::test
