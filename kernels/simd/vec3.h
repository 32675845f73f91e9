// 3-vectors and 3x3 rotations of lanes (kernels/simd/lanes.h): V3<F> holds one
// vector per lane as three FloatN, so every operation is lane-wise and a kernel
// written against V3<F> runs unchanged on FloatW (SIMD) and Float1 (scalar).
#pragma once

#include "kernels/simd/lanes.h"

namespace impact::kernels::simd {

template <class F>
struct V3 {
  F x, y, z;

  V3() = default;
  IMPACT_INLINE V3(F x_, F y_, F z_) : x(x_), y(y_), z(z_) {}

  friend IMPACT_INLINE V3 operator+(const V3& a, const V3& b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
  friend IMPACT_INLINE V3 operator-(const V3& a, const V3& b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
  friend IMPACT_INLINE V3 operator-(const V3& a) { return {-a.x, -a.y, -a.z}; }
  friend IMPACT_INLINE V3 operator*(const V3& a, F s) { return {a.x * s, a.y * s, a.z * s}; }
  friend IMPACT_INLINE V3 operator*(F s, const V3& a) { return {a.x * s, a.y * s, a.z * s}; }
};

template <class F>
IMPACT_INLINE F dot(const V3<F>& a, const V3<F>& b) {
  return a.x * b.x + a.y * b.y + a.z * b.z;
}
template <class F>
IMPACT_INLINE V3<F> cross(const V3<F>& a, const V3<F>& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
template <class F>
IMPACT_INLINE F length_sq(const V3<F>& a) {
  return dot(a, a);
}
/// a + s * b
template <class F>
IMPACT_INLINE V3<F> madd(const V3<F>& a, F s, const V3<F>& b) {
  return {mul_add(s, b.x, a.x), mul_add(s, b.y, a.y), mul_add(s, b.z, a.z)};
}
template <class F>
IMPACT_INLINE V3<F> select(typename F::Mask m, const V3<F>& a, const V3<F>& b) {
  return {select(m, a.x, b.x), select(m, a.y, b.y), select(m, a.z, b.z)};
}

/// Rotation, stored by columns: world = c[0]*x + c[1]*y + c[2]*z.
template <class F>
struct M3 {
  V3<F> c[3];
  /// R * v (local -> world directions)
  IMPACT_INLINE V3<F> apply(const V3<F>& v) const { return c[0] * v.x + c[1] * v.y + c[2] * v.z; }
  /// R^T * v (world -> local directions)
  IMPACT_INLINE V3<F> apply_t(const V3<F>& v) const { return {dot(c[0], v), dot(c[1], v), dot(c[2], v)}; }
};

}  // namespace impact::kernels::simd
