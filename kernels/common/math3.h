// Scalar 3D vocabulary of the dynamics kernels: Vec3, Quat (unit quaternions as
// rotations), Mat3 (rotation matrices) and Sym3 (symmetric 3x3, e.g. a world inverse
// inertia). Plain structs of floats with inline operations, so loops over bodies or
// constraints that use them stay vectorisable by the compiler (`omp simd`). Kernels
// include only kernels/ headers: this is their Eigen.
// Conventions: Quat (x, y, z, w) with w the scalar part; rotate(q, v) = q v q*;
// integrate(q, w, h) is the first-order update q + h/2 (w, 0) q, renormalised
// (Baraff, "Physically Based Modeling: Rigid Body Simulation", SIGGRAPH 2001 notes).
#pragma once

#include <cmath>

#include "kernels/common/kernel.h"

namespace impact::kernels {

struct Vec3 {
  float x, y, z;
};

IMPACT_INLINE Vec3 operator+(Vec3 a, Vec3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
IMPACT_INLINE Vec3 operator-(Vec3 a, Vec3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
IMPACT_INLINE Vec3 operator-(Vec3 a) { return {-a.x, -a.y, -a.z}; }
IMPACT_INLINE Vec3 operator*(float s, Vec3 a) { return {s * a.x, s * a.y, s * a.z}; }
IMPACT_INLINE Vec3 operator*(Vec3 a, float s) { return {s * a.x, s * a.y, s * a.z}; }
IMPACT_INLINE float dot(Vec3 a, Vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
IMPACT_INLINE Vec3 cross(Vec3 a, Vec3 b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
/// Component-wise product.
IMPACT_INLINE Vec3 mul(Vec3 a, Vec3 b) { return {a.x * b.x, a.y * b.y, a.z * b.z}; }
IMPACT_INLINE float length(Vec3 a) { return std::sqrt(dot(a, a)); }

struct Quat {
  float x, y, z, w;
};

IMPACT_INLINE Quat operator*(Quat a, Quat b) {
  return {a.w * b.x + a.x * b.w + a.y * b.z - a.z * b.y, a.w * b.y - a.x * b.z + a.y * b.w + a.z * b.x,
          a.w * b.z + a.x * b.y - a.y * b.x + a.z * b.w, a.w * b.w - a.x * b.x - a.y * b.y - a.z * b.z};
}
IMPACT_INLINE Quat conjugate(Quat q) { return {-q.x, -q.y, -q.z, q.w}; }
IMPACT_INLINE Quat normalize(Quat q) {
  const float inv = 1.0f / std::sqrt(q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w);
  return {q.x * inv, q.y * inv, q.z * inv, q.w * inv};
}
/// q v q* for unit q: v + 2 w (u x v) + 2 u x (u x v), u = (x, y, z).
IMPACT_INLINE Vec3 rotate(Quat q, Vec3 v) {
  const Vec3 u{q.x, q.y, q.z};
  const Vec3 t = 2.0f * cross(u, v);
  return v + q.w * t + cross(u, t);
}
/// q* v q: the inverse rotation.
IMPACT_INLINE Vec3 rotate_inv(Quat q, Vec3 v) { return rotate(conjugate(q), v); }
/// The orientation after angular velocity w (world frame) for time h.
IMPACT_INLINE Quat integrate(Quat q, Vec3 w, float h) {
  const Quat dq = Quat{w.x, w.y, w.z, 0.0f} * q;
  const float s = 0.5f * h;
  return normalize({q.x + s * dq.x, q.y + s * dq.y, q.z + s * dq.z, q.w + s * dq.w});
}

/// Rotation matrix by columns.
struct Mat3 {
  Vec3 c0, c1, c2;
};
IMPACT_INLINE Mat3 to_matrix(Quat q) {
  return {rotate(q, {1, 0, 0}), rotate(q, {0, 1, 0}), rotate(q, {0, 0, 1})};
}
IMPACT_INLINE Vec3 operator*(const Mat3& m, Vec3 v) { return v.x * m.c0 + v.y * m.c1 + v.z * m.c2; }
/// m^T v.
IMPACT_INLINE Vec3 mul_t(const Mat3& m, Vec3 v) { return {dot(m.c0, v), dot(m.c1, v), dot(m.c2, v)}; }

/// Symmetric 3x3.
struct Sym3 {
  float xx, yy, zz, xy, xz, yz;
};
IMPACT_INLINE Vec3 operator*(const Sym3& s, Vec3 v) {
  return {s.xx * v.x + s.xy * v.y + s.xz * v.z, s.xy * v.x + s.yy * v.y + s.yz * v.z,
          s.xz * v.x + s.yz * v.y + s.zz * v.z};
}
/// R diag(d) R^T.
IMPACT_INLINE Sym3 rotate_diagonal(const Mat3& r, Vec3 d) {
  const Vec3 a = d.x * r.c0, b = d.y * r.c1, c = d.z * r.c2;
  return {a.x * r.c0.x + b.x * r.c1.x + c.x * r.c2.x, a.y * r.c0.y + b.y * r.c1.y + c.y * r.c2.y,
          a.z * r.c0.z + b.z * r.c1.z + c.z * r.c2.z, a.x * r.c0.y + b.x * r.c1.y + c.x * r.c2.y,
          a.x * r.c0.z + b.x * r.c1.z + c.x * r.c2.z, a.y * r.c0.z + b.y * r.c1.z + c.y * r.c2.z};
}
IMPACT_INLINE Sym3 operator+(const Sym3& a, const Sym3& b) {
  return {a.xx + b.xx, a.yy + b.yy, a.zz + b.zz, a.xy + b.xy, a.xz + b.xz, a.yz + b.yz};
}

/// A unit vector perpendicular to unit n, chosen continuously away from the poles
/// (Frisvad's branch on the smallest component, as Box3D's b3Perp).
IMPACT_INLINE Vec3 perpendicular(Vec3 n) {
  if (std::fabs(n.x) < 0.57735f) {
    const float inv = 1.0f / std::sqrt(n.y * n.y + n.z * n.z);
    return {0.0f, n.z * inv, -n.y * inv};
  }
  const float inv = 1.0f / std::sqrt(n.x * n.x + n.y * n.y);
  return {n.y * inv, -n.x * inv, 0.0f};
}

/// Inverse of a symmetric 3x3 (zero when singular).
IMPACT_INLINE Sym3 inverse(const Sym3& m) {
  const float c00 = m.yy * m.zz - m.yz * m.yz, c01 = m.xz * m.yz - m.xy * m.zz, c02 = m.xy * m.yz - m.xz * m.yy;
  const float det = m.xx * c00 + m.xy * c01 + m.xz * c02;
  if (!(std::fabs(det) > 1e-30f)) return {0, 0, 0, 0, 0, 0};
  const float inv = 1.0f / det;
  return {c00 * inv,
          (m.xx * m.zz - m.xz * m.xz) * inv,
          (m.xx * m.yy - m.xy * m.xy) * inv,
          c01 * inv,
          c02 * inv,
          (m.xz * m.xy - m.xx * m.yz) * inv};
}

}  // namespace impact::kernels
