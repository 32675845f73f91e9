// The SoA blocks the narrow phase hands its pair kernels (kernels/narrowphase/leaf/leaf.h):
// one side's LeafSoA and the ManifoldSoA results, each in one host::SoaArrays, so every
// array sits at its own 64-byte slot modulo 4096 (docs/narrowphase.md, "Array layout").
// NarrowRunner's per-thread scratch and results and the kernel benchmark share them, so
// BM_Kernel measures the layout the library uses.
#pragma once

#include <cstddef>
#include <cstdint>

#include <Eigen/Core>

#include "host/buffer.h"
#include "kernels/narrowphase/leaf/leaf.h"

namespace impact::host {

/// One side of a block of lanes: f = p[3], r[9], e[3], w[6] (leaf.h's fields), then ref.
/// The kernel's A at slot phase kPhaseA, its B at kPhaseB; the results at
/// ManifoldArrays::kPhase.
struct LeafArrays {
  static constexpr uint32_t kPhaseA = 0, kPhaseB = 22;
  SoaArrays store;
  float* f[21] = {};
  uint32_t* ref = nullptr;
  std::size_t size = 0;

  void resize(std::size_t n, uint32_t phase) {
    store.resize(22, n, phase);
    for (uint32_t i = 0; i < 21; ++i) f[i] = store.get<float>(i);
    ref = store.get<uint32_t>(21);
    size = n;
  }
  kernels::LeafSoA view(std::size_t offset = 0) const {
    kernels::LeafSoA s{};
    for (int i = 0; i < 3; ++i) s.p[i] = f[i] + offset;
    for (int i = 0; i < 9; ++i) s.r[i] = f[3 + i] + offset;
    for (int i = 0; i < 3; ++i) s.e[i] = f[12 + i] + offset;
    for (int i = 0; i < 6; ++i) s.w[i] = f[15 + i] + offset;
    s.ref = ref + offset;
    return s;
  }
};

// Writers of one lane k of a LeafArrays side. Only the fields the leaf type uses
// (leaf.h's table): a sphere lane writes 4 of the 22 arrays. Unused fields keep stale
// values that no kernel reads.
inline void put_p(LeafArrays& s, size_t k, const Eigen::Vector3f& p) {
  for (int i = 0; i < 3; ++i) s.f[i][k] = p[i];
}
inline void put_r(LeafArrays& s, size_t k, const Eigen::Matrix3f& R) {
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) s.f[3 + 3 * i + j][k] = R(i, j);
  }
}
inline void put_e(LeafArrays& s, size_t k, const float* e) {
  for (int i = 0; i < 3; ++i) s.f[12 + i][k] = e[i];
}

/// A half-space (local unit normal e, plane offset) with rotation R at position p_rel
/// relative to an anchor o (p - o, in double), posed relative to o: the point of its plane
/// nearest o and the world normal, renormalised. The plane is { x : nn.(x - q) <= 0 },
/// q = p + R (e offset), nn = R e / |R e|; its height over o is
/// h = nn.(o - p) - offset nn.(R e), and -nn h the point. Rounded once, the plane moves by
/// ~1e-7 of |h| (the distance to o), not by the rounding of a world coordinate.
inline void put_plane_relative(LeafArrays& s, size_t k, const Eigen::Matrix3f& R, const Eigen::Vector3d& p_rel,
                               const float* e, float offset) {
  const Eigen::Vector3f el(e[0], e[1], e[2]);
  const Eigen::Vector3f n = R * el;
  const Eigen::Vector3f nn = n / n.norm();
  const Eigen::Vector3d nd = nn.cast<double>();
  const double h = -nd.dot(p_rel) - static_cast<double>(offset) * nd.dot(R.cast<double>() * el.cast<double>());
  put_p(s, k, (-h * nd).cast<float>());
  const float ne[3] = {nn[0], nn[1], nn[2]};
  put_e(s, k, ne);
}

/// The kernels' results: count, then f = depth, n[3], point[4][3], pdepth[4].
struct ManifoldArrays {
  static constexpr uint32_t kPhase = 44;
  SoaArrays store;
  uint8_t* count = nullptr;
  float* f[1 + 3 + 4 * 3 + 4] = {};

  void resize(std::size_t n) {
    store.resize(21, n, kPhase);
    count = store.get<uint8_t>(0);
    for (uint32_t i = 0; i < 20; ++i) f[i] = store.get<float>(1 + i);
  }
  kernels::ManifoldSoA view(std::size_t offset = 0) const {
    kernels::ManifoldSoA m{};
    m.count = count + offset;
    m.depth = f[0] + offset;
    for (int i = 0; i < 3; ++i) m.n[i] = f[1 + i] + offset;
    for (uint32_t k = 0; k < 4; ++k) {
      for (int i = 0; i < 3; ++i) m.point[k][i] = f[4 + 3 * k + i] + offset;
      m.pdepth[k] = f[16 + k] + offset;
    }
    return m;
  }
};

}  // namespace impact::host
