// The block drivers of the specialised narrow-phase kernels (kernels/narrowphase/pairs/):
// for_each_block walks a Range kSimdWidth pairs at a time, IMPACT_LANE_KERNEL_BODY is a
// lane kernel's PairKernel body over both lane types, for_each_chunk runs a kernel in
// three phases per chunk of blocks.
// Tail: a Range that is not a multiple of the width ends with a partial block. Its
// inputs are copied into a local full-width block (the last valid lane repeated in the
// padding, so padding lanes compute finite values), the same block code runs, and only
// the valid lanes are copied out. So a pair's output bytes do not depend on where a
// range boundary falls, and no array is read or written past the Range.
#pragma once

#include <cstdint>

#include "kernels/narrowphase/leaf/leaf.h"
#include "kernels/simd/lanes.h"
#include "kernels/simd/vec3.h"

namespace impact::kernels::prim {

using simd::M3;
using simd::V3;

/// Local full-width copy of one side's lanes (tail blocks).
template <uint32_t W>
struct TailSide {
  float p[3][W], r[9][W], e[3][W], w[6][W];
  uint32_t ref[W];
  LeafSoA view{};

  void fill(const LeafSoA& s, uint32_t k, uint32_t n) {
    auto copy = [&](const float* src, float* dst) -> const float* {
      if (src == nullptr) return nullptr;
      for (uint32_t i = 0; i < W; ++i) dst[i] = src[k + (i < n ? i : n - 1)];
      return dst;
    };
    for (uint32_t j = 0; j < 3; ++j) view.p[j] = copy(s.p[j], p[j]);
    for (uint32_t j = 0; j < 9; ++j) view.r[j] = copy(s.r[j], r[j]);
    for (uint32_t j = 0; j < 3; ++j) view.e[j] = copy(s.e[j], e[j]);
    for (uint32_t j = 0; j < 6; ++j) view.w[j] = copy(s.w[j], w[j]);
    view.ref = nullptr;
    if (s.ref != nullptr) {
      for (uint32_t i = 0; i < W; ++i) ref[i] = s.ref[k + (i < n ? i : n - 1)];
      view.ref = ref;
    }
  }
};

template <uint32_t W, uint32_t P>
struct TailOut {
  uint8_t count[W];
  float n[3][W], depth[W], point[P][3][W], pdepth[P][W];
  ManifoldSoA view() {
    ManifoldSoA m{};
    m.count = count;
    for (uint32_t j = 0; j < 3; ++j) m.n[j] = n[j];
    m.depth = depth;
    for (uint32_t i = 0; i < P; ++i) {
      for (uint32_t j = 0; j < 3; ++j) m.point[i][j] = point[i][j];
      m.pdepth[i] = pdepth[i];
    }
    return m;
  }
  void copy_to(const ManifoldSoA& out, uint32_t k, uint32_t n_lanes) const {
    for (uint32_t i = 0; i < n_lanes; ++i) {
      out.count[k + i] = count[i];
      for (uint32_t j = 0; j < 3; ++j) out.n[j][k + i] = n[j][i];
      out.depth[k + i] = depth[i];
      for (uint32_t q = 0; q < P; ++q) {
        for (uint32_t j = 0; j < 3; ++j) out.point[q][j][k + i] = point[q][j][i];
        out.pdepth[q][k + i] = pdepth[q][i];
      }
    }
  }
};

/// Runs block(a, b, out, k) for every full block of F::kWidth lanes of r, then the
/// tail through local copies. P = the point slots the kernel writes.
template <class F, uint32_t P, class Block>
IMPACT_INLINE void for_each_block(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, Range r,
                                  Block&& block) {
  constexpr uint32_t W = F::kWidth;
  uint32_t k = r.begin;
  for (; k + W <= r.end; k += W) block(a, b, out, k);
  if constexpr (W > 1) {
    if (k < r.end) {
      const uint32_t n = r.end - k;
      TailSide<W> ta, tb;
      ta.fill(a, k, n);
      tb.fill(b, k, n);
      TailOut<W, P> to{};  // zeroed: count-0 lanes may leave fields unwritten
      const ManifoldSoA lo = to.view();
      block(ta.view, tb.view, lo, 0u);
      to.copy_to(out, k, n);
    }
  }
}

/// The body of a lane kernel's PairKernel over its block template `block<F>(a, b, out, k)`
/// writing P point slots: for_each_block at simd::Float1 (one lane, the reference path)
/// for KernelPath::kScalar, else at simd::FloatP (kPairWidth lanes). Every pair function
/// is defined by its own name and forwards here, e.g.
///   void collide_sphere_sphere(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out,
///                              Range r, const NarrowConfig& cfg) {
///     IMPACT_LANE_KERNEL_BODY(sphere_sphere_block, 1);
///   }
/// A macro, not a function template, because `block` is a function template (and the
/// lambdas must stay in the pair function for its inlining); it reads the PairKernel
/// parameters a, b, out, r and cfg.
#define IMPACT_LANE_KERNEL_BODY(block, P)                                                                  \
  {                                                                                                       \
    if (cfg.path == KernelPath::kScalar) {                                                                \
      for_each_block<simd::Float1, P>(                                                                    \
          a, b, out, r, [](const LeafSoA& aa, const LeafSoA& bb, const ManifoldSoA& o, uint32_t k) {      \
            block<simd::Float1>(aa, bb, o, k);                                                            \
          });                                                                                             \
    } else {                                                                                              \
      for_each_block<simd::FloatP, P>(                                                                    \
          a, b, out, r, [](const LeafSoA& aa, const LeafSoA& bb, const ManifoldSoA& o, uint32_t k) {      \
            block<simd::FloatP>(aa, bb, o, k);                                                            \
          });                                                                                             \
    }                                                                                                     \
  }

/// Runs a lane kernel in three phases over r, C::kLanes pairs (a chunk) at a time:
/// phase_a(a, b, k, j, nb, ch) for each block (k: its first pair, j: its first lane in
/// the chunk, nb: its real lanes), then phase_b(ch) (work the blocks listed in the chunk
/// state, packed across them; it leaves the chunk's lists empty), then
/// phase_c(a, b, out, k, j, ch) for each block. A block past the range's end runs on local
/// full-width copies (TailSide, TailOut), as for_each_block's tail does.
template <class F, uint32_t P, class C, class PhaseA, class PhaseB, class PhaseC>
IMPACT_INLINE void for_each_chunk(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, Range r, C& ch,
                                  PhaseA&& phase_a, PhaseB&& phase_b, PhaseC&& phase_c) {
  constexpr uint32_t W = F::kWidth;
  for (uint32_t k0 = r.begin; k0 < r.end; k0 += C::kLanes) {
    const uint32_t n = r.end - k0 < C::kLanes ? r.end - k0 : C::kLanes;
    for (uint32_t j = 0; j < n; j += W) {
      const uint32_t k = k0 + j, nb = n - j < W ? n - j : W;
      if (nb == W) {
        phase_a(a, b, k, j, nb, ch);
      } else {
        TailSide<W> ta, tb;
        ta.fill(a, k, nb);
        tb.fill(b, k, nb);
        phase_a(ta.view, tb.view, 0u, j, nb, ch);
      }
    }
    phase_b(ch);
    for (uint32_t j = 0; j < n; j += W) {
      const uint32_t k = k0 + j, nb = n - j < W ? n - j : W;
      if (nb == W) {
        phase_c(a, b, out, k, j, ch);
      } else {
        TailSide<W> ta, tb;
        ta.fill(a, k, nb);
        tb.fill(b, k, nb);
        TailOut<W, P> to{};
        phase_c(ta.view, tb.view, to.view(), 0u, j, ch);
        to.copy_to(out, k, nb);
      }
    }
  }
}

}  // namespace impact::kernels::prim
