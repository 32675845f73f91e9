// Support functions of the convex leaf types (kernels/narrowphase/leaf/leaf.h), one lane at a
// time, for the general convex path (GJK / EPA in gjk_epa.cpp, SAT in sat.cpp, the face
// manifold in face_manifold.cpp, half-spaces in support_halfspace.cpp).
//
// What: support(d) = argmax_{x in shape} d.x for sphere, capsule, box, convex hull
// (HullView), cylinder, ellipsoid and triangle, in the world frame shifted by an
// `origin` (the caller passes A's position, so that pairs far from the world origin
// keep their float precision: every coordinate is a small difference).
// Core + radius: a sphere is a point inflated by r, a capsule a segment inflated by r;
// every other type is its own core with radius 0. support = support_core + r * d/|d|.
// GJK runs on the cores, so the distance of two spheres / capsules is exact and their
// margin never needs an iterative search (van den Bergen, "Collision Detection in
// Interactive 3D Environments", 2003, sec. 4.3.6 on margins).
// Inputs: a LeafSoA lane as the host gathered it (finite, positive sizes, R orthonormal,
// half-space lanes never reach these functions). Ties (d orthogonal to an edge or a
// face) resolve to a fixed vertex (the + side, the lowest index), so the result is a
// deterministic function of the lane's bytes. d = 0 returns a valid point of the shape.
// Cost: O(1) per call except convex hulls, O(vertex count): brute force, kSimdWidth
// vertices per step over the SoA vertex arrays (the hulls of games have tens of
// vertices; hill climbing would need adjacency in HullView).
#pragma once

#include <cmath>
#include <cstdint>

#include "kernels/narrowphase/leaf/leaf.h"
#include "kernels/simd/lanes.h"

namespace impact::kernels::cvx {

/// A small float 3-vector for the one-lane code of the convex path.
struct V3 {
  float x, y, z;
};

IMPACT_INLINE V3 operator+(V3 a, V3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
IMPACT_INLINE V3 operator-(V3 a, V3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
IMPACT_INLINE V3 operator-(V3 a) { return {-a.x, -a.y, -a.z}; }
IMPACT_INLINE V3 operator*(V3 a, float s) { return {a.x * s, a.y * s, a.z * s}; }
IMPACT_INLINE V3 operator*(float s, V3 a) { return {a.x * s, a.y * s, a.z * s}; }
IMPACT_INLINE float dot(V3 a, V3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
IMPACT_INLINE V3 cross(V3 a, V3 b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
IMPACT_INLINE float len2(V3 a) { return dot(a, a); }
IMPACT_INLINE float len(V3 a) { return std::sqrt(dot(a, a)); }

/// One posed leaf, relative to an origin. Axes are R's columns.
struct Leaf {
  LeafType type = kLeafSphere;
  V3 p{0, 0, 0};           // centre (triangle: v0), minus origin
  V3 ax[3]{};              // R columns (local x, y, z in the world)
  float e[3]{0, 0, 0};     // sizes, per leaf.h
  V3 v1{0, 0, 0}, v2{0, 0, 0};  // triangle: v1, v2 minus origin
  const HullView* hulls = nullptr;
  uint32_t hull = 0;
};

/// Reads lane k of s as a leaf of type t, shifted by -origin.
inline Leaf load_leaf(const LeafSoA& s, uint32_t k, LeafType t, const HullView* hulls, V3 origin) {
  Leaf l;
  l.type = t;
  l.p = V3{s.p[0][k], s.p[1][k], s.p[2][k]} - origin;
  if (t == kLeafTriangle) {
    l.v1 = V3{s.w[0][k], s.w[1][k], s.w[2][k]} - origin;
    l.v2 = V3{s.w[3][k], s.w[4][k], s.w[5][k]} - origin;
    return l;
  }
  if (t != kLeafSphere) {
    for (int c = 0; c < 3; ++c) l.ax[c] = V3{s.r[c][k], s.r[3 + c][k], s.r[6 + c][k]};
  }
  if (t == kLeafConvex) {
    l.hulls = hulls;
    l.hull = s.ref[k];
  } else {
    for (int i = 0; i < 3; ++i) l.e[i] = s.e[i] != nullptr ? s.e[i][k] : 0.0f;
  }
  return l;
}

/// Radius of the margin around the core: sphere and capsule radius, else 0.
IMPACT_INLINE float core_radius(const Leaf& l) {
  return (l.type == kLeafSphere || l.type == kLeafCapsule) ? l.e[0] : 0.0f;
}

/// A point inside the shape (centre; triangle: centroid), minus origin.
IMPACT_INLINE V3 leaf_center(const Leaf& l) {
  if (l.type == kLeafTriangle) return (l.p + l.v1 + l.v2) * (1.0f / 3.0f);
  return l.p;
}

/// Convex hull vertex i (absolute index into the HullView arrays), posed.
IMPACT_INLINE V3 hull_vertex(const Leaf& l, uint32_t i) {
  const HullView& h = *l.hulls;
  return l.p + l.ax[0] * h.vx[i] + l.ax[1] * h.vy[i] + l.ax[2] * h.vz[i];
}

/// Index in [b, e) (b < e) of the point (vx, vy, vz)[i] of largest projection on
/// (dx, dy, dz) (hull vertices, face normals), the lowest index among ties:
/// kSimdWidth points per step, each lane keeping its first maximum (strict >), then
/// the lanes merged by (score, lowest index); the tail is scalar with strict > (its
/// indices are larger). Deterministic for given bytes.
IMPACT_INLINE uint32_t argmax_dot(const float* vx, const float* vy, const float* vz, uint32_t b, uint32_t e, float dx,
                                  float dy, float dz) {
  using F = simd::FloatN<simd::kSimdWidth>;
  constexpr uint32_t kW = simd::kSimdWidth;
  uint32_t best = b;
  float best_s = -INFINITY;
  uint32_t i = b;
  if (e - b >= kW) {
    const F lane = simd::lane_index<F>(), X(dx), Y(dy), Z(dz);
    F m(-INFINITY), idx(0.0f);
    for (; i + kW <= e; i += kW) {
      const F s = X * F::load(vx + i) + Y * F::load(vy + i) + Z * F::load(vz + i);
      const auto gt = s > m;
      m = select(gt, s, m);
      idx = select(gt, lane + F(static_cast<float>(i - b)), idx);
    }
    // Merge without data-dependent branches (they mispredict about half the time):
    // the largest score, then the lowest index among the lanes that hold it.
    float bi;
    best_s = simd::max_lowest_index(m, idx, static_cast<float>(e - b), &bi);
    best = b + static_cast<uint32_t>(bi);
  }
  for (; i < e; ++i) {
    const float s = dx * vx[i] + dy * vy[i] + dz * vz[i];
    if (s > best_s) {
      best_s = s;
      best = i;
    }
  }
  return best;
}

/// Index in [b, e) of the hull vertex of largest projection on (dx, dy, dz) (argmax_dot).
IMPACT_INLINE uint32_t hull_support_index(const HullView& h, uint32_t b, uint32_t e, float dx, float dy, float dz) {
  return argmax_dot(h.vx, h.vy, h.vz, b, e, dx, dy, dz);
}

/// Support point of the core (no margin) along d.
inline V3 support_core(const Leaf& l, V3 d) {
  switch (l.type) {
    case kLeafSphere:
      return l.p;
    case kLeafCapsule:
      return dot(d, l.ax[2]) >= 0.0f ? l.p + l.ax[2] * l.e[1] : l.p - l.ax[2] * l.e[1];
    case kLeafBox: {
      V3 q = l.p;
      for (int i = 0; i < 3; ++i) q = q + l.ax[i] * (dot(d, l.ax[i]) >= 0.0f ? l.e[i] : -l.e[i]);
      return q;
    }
    case kLeafConvex: {
      // Local direction, then the vertex of largest projection (first wins ties).
      const HullView& h = *l.hulls;
      const float dx = dot(d, l.ax[0]), dy = dot(d, l.ax[1]), dz = dot(d, l.ax[2]);
      return hull_vertex(l, hull_support_index(h, h.vert_begin[l.hull], h.vert_begin[l.hull + 1], dx, dy, dz));
    }
    case kLeafCylinder: {
      // Radial direction from the local x, y components: d - u (u.d) would keep an
      // axial rounding residue that normalising blows up for near-axial d.
      const float dx = dot(d, l.ax[0]), dy = dot(d, l.ax[1]), dz = dot(d, l.ax[2]);
      V3 q = l.p + l.ax[2] * (dz >= 0.0f ? l.e[1] : -l.e[1]);
      const float rl2 = dx * dx + dy * dy;
      // A direction along the axis: the cap's centre is a support point.
      if (rl2 > 0.0f) {
        const float s = l.e[0] / std::sqrt(rl2);
        q = q + l.ax[0] * (dx * s) + l.ax[1] * (dy * s);
      }
      return q;
    }
    case kLeafEllipsoid: {
      // x = M d / sqrt(d^T M d) with M = R diag(e^2) R^T.
      const float a0 = dot(d, l.ax[0]) * l.e[0], a1 = dot(d, l.ax[1]) * l.e[1], a2 = dot(d, l.ax[2]) * l.e[2];
      const float n2 = a0 * a0 + a1 * a1 + a2 * a2;
      if (!(n2 > 0.0f)) return l.p + l.ax[0] * l.e[0];
      const float inv = 1.0f / std::sqrt(n2);
      return l.p + l.ax[0] * (a0 * l.e[0] * inv) + l.ax[1] * (a1 * l.e[1] * inv) + l.ax[2] * (a2 * l.e[2] * inv);
    }
    case kLeafTriangle: {
      const float s0 = dot(d, l.p), s1 = dot(d, l.v1), s2 = dot(d, l.v2);
      if (s0 >= s1 && s0 >= s2) return l.p;
      return s1 >= s2 ? l.v1 : l.v2;
    }
    default:
      return l.p;
  }
}

/// Support point of the whole shape (core + margin) along d (d = 0: a core point).
inline V3 support(const Leaf& l, V3 d) {
  const V3 c = support_core(l, d);
  const float r = core_radius(l);
  const float dl2 = len2(d);
  if (r == 0.0f || !(dl2 > 0.0f)) return c;
  return c + d * (r / std::sqrt(dl2));
}

/// A size of the shape (m): the radius of a ball about leaf_center that holds it,
/// up to a factor <= 2. Scales the relative tolerances.
inline float leaf_size(const Leaf& l) {
  switch (l.type) {
    case kLeafSphere: return l.e[0];
    case kLeafCapsule: return l.e[0] + l.e[1];
    case kLeafBox: return l.e[0] + l.e[1] + l.e[2];
    case kLeafCylinder: return l.e[0] + l.e[1];
    case kLeafEllipsoid: return simd::fmax_nn(l.e[0], simd::fmax_nn(l.e[1], l.e[2]));
    case kLeafTriangle: {
      const V3 c = leaf_center(l);
      return std::sqrt(simd::fmax_nn(len2(l.p - c), simd::fmax_nn(len2(l.v1 - c), len2(l.v2 - c))));
    }
    case kLeafConvex: {
      // kSimdWidth vertices per step (max is exact: the order does not matter).
      using F = simd::FloatN<simd::kSimdWidth>;
      constexpr uint32_t kW = simd::kSimdWidth;
      const HullView& h = *l.hulls;
      const uint32_t e = h.vert_begin[l.hull + 1];
      uint32_t i = h.vert_begin[l.hull];
      float m = 0.0f;
      if (e - i >= kW) {
        F mw(0.0f);
        for (; i + kW <= e; i += kW)
          mw = simd::max(mw, simd::abs(F::load(h.vx + i)) + simd::abs(F::load(h.vy + i)) + simd::abs(F::load(h.vz + i)));
        for (uint32_t k = 0; k < kW; ++k) m = mw.lane(k) > m ? mw.lane(k) : m;
      }
      for (; i < e; ++i) {
        const float s = std::fabs(h.vx[i]) + std::fabs(h.vy[i]) + std::fabs(h.vz[i]);
        m = s > m ? s : m;  // not std::fmax: that is a libm call here
      }
      return m;
    }
    default: return 0.0f;
  }
}

}  // namespace impact::kernels::cvx
