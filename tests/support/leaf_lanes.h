// One side of a narrow-phase kernel bucket as owning SoA lanes (kernels::LeafSoA), the
// output lanes (kernels::ManifoldSoA), and one pair's collision data read back in
// double: shared by the kernel-level tests that drive kernels pair by pair.
#pragma once

#include <cmath>
#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "kernels/narrowphase/leaf/leaf.h"

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

/// Owning output lanes for n pairs (kernels::ManifoldSoA), every value poisoned (count
/// 0xff, NaN floats) so a kernel that leaves a lane or a slot unwritten shows; result(k)
/// reads lane k back as a PairResult (the points and depths of its count slots).
struct ManifoldLanes {
  std::vector<uint8_t> count;
  std::vector<float> n[3], depth, pt[4][3], pd[4];

  explicit ManifoldLanes(uint32_t lanes = 1) : count(lanes, 0xff), depth(lanes, NAN) {
    for (int i = 0; i < 3; ++i) n[i].assign(lanes, NAN);
    for (int j = 0; j < 4; ++j) {
      for (int i = 0; i < 3; ++i) pt[j][i].assign(lanes, NAN);
      pd[j].assign(lanes, NAN);
    }
  }

  kernels::ManifoldSoA view() {
    kernels::ManifoldSoA o{};
    o.count = count.data();
    for (int i = 0; i < 3; ++i) o.n[i] = n[i].data();
    o.depth = depth.data();
    for (int j = 0; j < 4; ++j) {
      for (int i = 0; i < 3; ++i) o.point[j][i] = pt[j][i].data();
      o.pdepth[j] = pd[j].data();
    }
    return o;
  }

  PairResult result(uint32_t k = 0) const {
    PairResult r;
    r.count = count[k];
    if (r.count == 0) return r;
    r.n = Eigen::Vector3d(n[0][k], n[1][k], n[2][k]);
    r.depth = depth[k];
    for (uint32_t j = 0; j < r.count && j < 4; ++j) {
      r.pt[j] = Eigen::Vector3d(pt[j][0][k], pt[j][1][k], pt[j][2][k]);
      r.pd[j] = pd[j][k];
    }
    return r;
  }
};

}  // namespace impact::test
