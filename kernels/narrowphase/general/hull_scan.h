// Per-lane passes over one convex hull's faces and vertices (HullView), shared by the
// exact hull kernels (sphere_convex.cpp, capsule_convex.cpp, convex_triangle.cpp,
// convex_ellipsoid.cpp, convex_cylinder.cpp);
// internal to kernels/narrowphase.
//   next_block          block starts of a kSimdWidth-wide pass (last block overlaps)
//   block               items i .. i + W of an array of n, the last repeated past n
//   kKeep               hulls up to this many faces / edges keep pass values on the stack
//   lanes_min/max       horizontal min / max of the lanes
//   vertex, face_normal one hull vertex / face normal as a V3
//   projects_into_face  whether a point projects into a face's polygon
//   store_from_frame    one lane's collision data, from a hull's frame to the world
#pragma once

#include <cstdint>

#include "kernels/narrowphase/general/gjk_epa.h"
#include "kernels/simd/lanes.h"

namespace impact::kernels::hull_scan {

using cvx::V3;
using simd::FloatW;
using simd::kSimdWidth;

/// The first block start of a kSimdWidth-wide pass over [b, e) (e - b >= kSimdWidth) is
/// b; the next is i + kSimdWidth, or e - kSimdWidth for the last (overlapping) block,
/// which revisits some items: harmless for a max / min with the lowest index among ties.
IMPACT_INLINE uint32_t next_block(uint32_t i, uint32_t e) {
  return i + 2 * kSimdWidth <= e ? i + kSimdWidth : e - kSimdWidth;
}

/// Items i .. i + F::kWidth of p[0 .. n) (i < n), the last item repeated past n: a
/// pass over a hull's faces, vertices or queued slots in whole blocks (a repeated item
/// changes no minimum or maximum; lanes past n are masked where a count matters).
template <class F>
IMPACT_INLINE F block(const float* p, uint32_t i, uint32_t n) {
  return simd::load_clamped<F>(p, i, n);
}

/// Hulls of up to this many faces (edges) keep their pass values on the stack for the
/// second look at near ties (2 KiB per buffer); larger hulls compute them again.
inline constexpr uint32_t kKeep = 512;

/// Horizontal min / max of the lanes.
IMPACT_INLINE float lanes_min(FloatW v) {
  float m = v.lane(0);
  for (uint32_t l = 1; l < kSimdWidth; ++l) m = simd::fmin_nn(m, v.lane(l));
  return m;
}
IMPACT_INLINE float lanes_max(FloatW v) {
  float m = v.lane(0);
  for (uint32_t l = 1; l < kSimdWidth; ++l) m = simd::fmax_nn(m, v.lane(l));
  return m;
}

IMPACT_INLINE V3 vertex(const HullView& h, uint32_t i) {
  return V3{h.vx[i], h.vy[i], h.vz[i]};
}
IMPACT_INLINE V3 face_normal(const HullView& h, uint32_t f) {
  return V3{h.fnx[f], h.fny[f], h.fnz[f]};
}

/// Whether p projects into face f's polygon (on its boundary counts as inside): p is
/// behind every side plane through a polygon edge, perpendicular to the face.
IMPACT_INLINE bool projects_into_face(const HullView& h, uint32_t f, V3 p) {
  const uint32_t b = h.face_vert_begin[f], e = h.face_vert_begin[f + 1];
  if (e - b < 3) return false;
  const V3 n = face_normal(h, f);
  V3 a = vertex(h, h.face_verts[e - 1]);
  for (uint32_t j = b; j < e; ++j) {
    const V3 q = vertex(h, h.face_verts[j]);
    // Counter-clockwise seen from outside: (q - a) x n points out of the polygon.
    if (cvx::dot(cvx::cross(q - a, n), p - a) > 0.0f) return false;
    a = q;
  }
  return true;
}

/// Writes lane k of out: the normal nl, depth, and count points p[i] with depths d[i],
/// given in a frame with axes ax (R's columns) and origin o, turned into the world frame.
IMPACT_INLINE void store_from_frame(const ManifoldSoA& out, uint32_t k, const V3 ax[3], V3 o, V3 nl,
                                    float depth, uint32_t count, const V3* p, const float* d) {
  const V3 n = ax[0] * nl.x + ax[1] * nl.y + ax[2] * nl.z;
  out.count[k] = static_cast<uint8_t>(count);
  out.n[0][k] = n.x;
  out.n[1][k] = n.y;
  out.n[2][k] = n.z;
  out.depth[k] = depth;
  for (uint32_t i = 0; i < count; ++i) {
    const V3 q = p[i];
    out.point[i][0][k] = o.x + (ax[0].x * q.x + ax[1].x * q.y + ax[2].x * q.z);
    out.point[i][1][k] = o.y + (ax[0].y * q.x + ax[1].y * q.y + ax[2].y * q.z);
    out.point[i][2][k] = o.z + (ax[0].z * q.x + ax[1].z * q.y + ax[2].z * q.z);
    out.pdepth[i][k] = d[i];
  }
}

}  // namespace impact::kernels::hull_scan
