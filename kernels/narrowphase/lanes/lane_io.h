// Lane loads and stores of the specialised narrow-phase kernels (kernels/narrowphase/pairs/):
// a LeafSoA field, position, rotation or axis for lanes k .. k + F::kWidth, a block's
// collision data (Lanes), its store into a ManifoldSoA (points made absolute by adding
// the driver's origin, A's position), a block without contact, and the one-point result
// of the sphere kernels.
// Every helper is a template over the lane type F (simd::FloatW or simd::Float1), so the
// SIMD path and the scalar reference path run the same code. Positions are taken relative
// to A's position before any arithmetic, so poses 1e5 from the origin lose no more than
// the inputs' own rounding.
#pragma once

#include <cstdint>
#include <cstring>

#include "kernels/narrowphase/leaf/leaf.h"
#include "kernels/simd/lanes.h"
#include "kernels/simd/vec3.h"

namespace impact::kernels::prim {

using simd::M3;
using simd::V3;

template <class F>
IMPACT_INLINE F ld(const float* p, uint32_t k) {
  return F::load(p + k);
}
template <class F>
IMPACT_INLINE V3<F> load_p(const LeafSoA& s, uint32_t k) {
  return {ld<F>(s.p[0], k), ld<F>(s.p[1], k), ld<F>(s.p[2], k)};
}
template <class F>
IMPACT_INLINE V3<F> load_w(const LeafSoA& s, uint32_t k, uint32_t first) {
  return {ld<F>(s.w[first], k), ld<F>(s.w[first + 1], k), ld<F>(s.w[first + 2], k)};
}
template <class F>
IMPACT_INLINE V3<F> load_e(const LeafSoA& s, uint32_t k) {
  return {ld<F>(s.e[0], k), ld<F>(s.e[1], k), ld<F>(s.e[2], k)};
}
/// Rotation by columns (LeafSoA stores R row-major: r[3*row + col]).
template <class F>
IMPACT_INLINE M3<F> load_r(const LeafSoA& s, uint32_t k) {
  M3<F> m;
  for (uint32_t c = 0; c < 3; ++c) m.c[c] = {ld<F>(s.r[c], k), ld<F>(s.r[3 + c], k), ld<F>(s.r[6 + c], k)};
  return m;
}
/// Column 2 of R: a capsule's axis.
template <class F>
IMPACT_INLINE V3<F> load_axis_z(const LeafSoA& s, uint32_t k) {
  return {ld<F>(s.r[2], k), ld<F>(s.r[5], k), ld<F>(s.r[8], k)};
}

/// One block's collision data, points relative to the driver's origin (A's position).
template <class F, uint32_t P>
struct Lanes {
  typename F::Int count;
  V3<F> n;
  F depth;
  V3<F> point[P];
  F pdepth[P];
};

/// Writes lanes k .. k + width of out: count, n, depth and point slots 0 .. S-1
/// (S <= P; points made absolute by adding origin).
template <class F, uint32_t P, uint32_t S = P>
IMPACT_INLINE void store(const ManifoldSoA& out, uint32_t k, const Lanes<F, P>& m, const V3<F>& origin) {
  static_assert(S <= P);
  // The counts narrowed in a local array, then one copy: a byte store through
  // out.count may alias `out` itself, so storing lane by lane made GCC reload the
  // pointer after every byte (8 loads and 8 byte stores per block, measured on
  // sphere-halfspace).
  uint8_t counts[F::kWidth];
  for (uint32_t i = 0; i < F::kWidth; ++i) counts[i] = static_cast<uint8_t>(m.count.lane(i));
  std::memcpy(out.count + k, counts, sizeof(counts));
  m.n.x.store(out.n[0] + k);
  m.n.y.store(out.n[1] + k);
  m.n.z.store(out.n[2] + k);
  m.depth.store(out.depth + k);
  for (uint32_t j = 0; j < S; ++j) {
    (origin.x + m.point[j].x).store(out.point[j][0] + k);
    (origin.y + m.point[j].y).store(out.point[j][1] + k);
    (origin.z + m.point[j].z).store(out.point[j][2] + k);
    m.pdepth[j].store(out.pdepth[j] + k);
  }
}

/// Writes count 0 to lanes k .. k + width (a block with no contact: the contract lets
/// every other field of a count-0 lane stay unwritten).
template <class F>
IMPACT_INLINE void store_no_contact(const ManifoldSoA& out, uint32_t k) {
  std::memset(out.count + k, 0, F::kWidth);
}

/// A one-point result from the normal, the depth and the two surface points (the point
/// midway between them, count 1 where depth > 0; the sphere (A) kernels).
template <class F>
IMPACT_INLINE Lanes<F, 1> one_point(const V3<F>& n, F depth, const V3<F>& on_a, const V3<F>& on_b) {
  Lanes<F, 1> m;
  m.count = simd::to_int(depth > F(0.0f));
  m.n = n;
  m.depth = depth;
  m.point[0] = (on_a + on_b) * F(0.5f);
  m.pdepth[0] = depth;
  return m;
}

}  // namespace impact::kernels::prim
