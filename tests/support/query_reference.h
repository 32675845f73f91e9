// Independent double-precision reference for the batched proximity queries (AABB,
// sphere, point) over stored boxes, written from the documented contract
// (kernels/broadphase/query.h, docs/broadphase.md "Queries"):
//   AABB [lo, hi] hits box j   <=>  lo <= max_j and min_j <= hi on every axis
//   point p hits box j         <=>  min_j <= p <= max_j on every axis
//   sphere (c, r) hits box j   <=>  d2 <= r * r in double, where per axis
//                                   d = max(min_j - c, c - max_j, 0) and
//                                   d2 = fma(d_z, d_z, fma(d_y, d_y, d_x * d_x))
//   and, when the boxes carry a filter, (layer_j & mask_i) != 0 (no mask: all ones).
// The sphere formula is the documented one, evaluated here by brute force in double
// (the contract fixes the rounding so that every structure agrees on borderline
// boxes; a different formula would be a different contract). Output: CSR, each
// query's hits ascending. O(boxes * queries).
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include "support/aabb_reference.h"

namespace impact::test {

enum class QShape { kAabb, kSphere, kPoint };

inline const char* to_string(QShape s) {
  return s == QShape::kAabb ? "aabb" : s == QShape::kSphere ? "sphere" : "point";
}

/// A batch of queries of one shape, SoA. AABB: (x0..z0) min, (x1..z1) max; sphere:
/// (x0, y0, z0) centre and radius; point: (x0, y0, z0). mask empty = all ones.
struct Queries {
  QShape shape = QShape::kAabb;
  std::vector<float> x0, y0, z0, x1, y1, z1, radius;
  std::vector<uint32_t> mask;

  size_t size() const { return x0.size(); }
  void add_box(float ax, float ay, float az, float bx, float by, float bz) {
    x0.push_back(ax), y0.push_back(ay), z0.push_back(az);
    x1.push_back(bx), y1.push_back(by), z1.push_back(bz);
  }
  void add_sphere(float cx, float cy, float cz, float r) {
    x0.push_back(cx), y0.push_back(cy), z0.push_back(cz);
    radius.push_back(r);
  }
  void add_point(float px, float py, float pz) { x0.push_back(px), y0.push_back(py), z0.push_back(pz); }
};

inline Queries empty_queries(QShape shape) {
  Queries q;
  q.shape = shape;
  return q;
}

struct Csr {
  std::vector<uint32_t> offsets, hits;
  friend bool operator==(const Csr&, const Csr&) = default;
};

inline bool ref_query_hit(const Boxes& b, size_t j, const Queries& q, size_t i) {
  const double bmin[3] = {b.min_x[j], b.min_y[j], b.min_z[j]};
  const double bmax[3] = {b.max_x[j], b.max_y[j], b.max_z[j]};
  if (b.filtered()) {
    const uint32_t mask = q.mask.empty() ? 0xffffffffu : q.mask[i];
    if ((b.layer[j] & mask) == 0) return false;
  }
  const double p[3] = {q.x0[i], q.y0[i], q.z0[i]};
  switch (q.shape) {
    case QShape::kAabb: {
      const double hi[3] = {q.x1[i], q.y1[i], q.z1[i]};
      for (int k = 0; k < 3; ++k)
        if (!(p[k] <= bmax[k] && bmin[k] <= hi[k])) return false;
      return true;
    }
    case QShape::kPoint:
      for (int k = 0; k < 3; ++k)
        if (!(bmin[k] <= p[k] && p[k] <= bmax[k])) return false;
      return true;
    case QShape::kSphere: {
      double d[3];
      for (int k = 0; k < 3; ++k) d[k] = std::max(std::max(bmin[k] - p[k], p[k] - bmax[k]), 0.0);
      const double d2 = std::fma(d[2], d[2], std::fma(d[1], d[1], d[0] * d[0]));
      const double r = q.radius[i];
      return d2 <= r * r;
    }
  }
  return false;
}

inline Csr reference_query(const Boxes& b, const Queries& q) {
  Csr out;
  out.offsets.push_back(0);
  for (size_t i = 0; i < q.size(); ++i) {
    for (size_t j = 0; j < b.size(); ++j)
      if (ref_query_hit(b, j, q, i)) out.hits.push_back(static_cast<uint32_t>(j));
    out.offsets.push_back(static_cast<uint32_t>(out.hits.size()));
  }
  return out;
}

/// Byte equality of two CSR answers, with the first differing query in the message.
inline ::testing::AssertionResult SameCsr(const Csr& got, const Csr& ref) {
  if (got == ref) return ::testing::AssertionSuccess();
  if (got.offsets.size() != ref.offsets.size())
    return ::testing::AssertionFailure() << got.offsets.size() << " offsets, reference " << ref.offsets.size();
  for (size_t i = 0; i + 1 < ref.offsets.size(); ++i) {
    const std::vector<uint32_t> g(got.hits.begin() + got.offsets[i], got.hits.begin() + got.offsets[i + 1]);
    const std::vector<uint32_t> r(ref.hits.begin() + ref.offsets[i], ref.hits.begin() + ref.offsets[i + 1]);
    if (g != r) {
      std::string s;
      for (size_t k = 0; k < std::min<size_t>(g.size(), 8); ++k) s += std::to_string(g[k]) + " ";
      std::string t;
      for (size_t k = 0; k < std::min<size_t>(r.size(), 8); ++k) t += std::to_string(r[k]) + " ";
      return ::testing::AssertionFailure() << "query " << i << ": " << g.size() << " hits [" << s
                                           << "...], reference " << r.size() << " [" << t << "...]";
    }
  }
  return ::testing::AssertionFailure() << "offsets or hits differ (total " << got.hits.size() << " vs "
                                       << ref.hits.size() << ")";
}

/// Bounds of a box set: lo[3], hi[3] (zeros when empty).
inline void box_bounds(const Boxes& b, float lo[3], float hi[3]) {
  for (int k = 0; k < 3; ++k) lo[k] = hi[k] = 0.0f;
  if (b.size() == 0) return;
  lo[0] = *std::min_element(b.min_x.begin(), b.min_x.end());
  lo[1] = *std::min_element(b.min_y.begin(), b.min_y.end());
  lo[2] = *std::min_element(b.min_z.begin(), b.min_z.end());
  hi[0] = *std::max_element(b.max_x.begin(), b.max_x.end());
  hi[1] = *std::max_element(b.max_y.begin(), b.max_y.end());
  hi[2] = *std::max_element(b.max_z.begin(), b.max_z.end());
}

/// n random queries of `shape` in the scene's bounds grown by 20% on each side (so
/// some fall outside): AABB half sizes and sphere radii uniform in [0, size]. Half of
/// the queries are centred on a random box's min or max corner coordinates, so
/// exactly-touching cases occur. mask_kind: 0 none, 1 random (all ones, one bit, all
/// but one bit, or 0).
inline Queries random_queries(const Boxes& b, QShape shape, uint32_t n, uint32_t seed, float size,
                              int mask_kind = 0) {
  std::mt19937 rng(seed);
  float lo[3], hi[3];
  box_bounds(b, lo, hi);
  float c_lo[3], c_hi[3];
  for (int k = 0; k < 3; ++k) {
    const float m = 0.2f * (hi[k] - lo[k]) + size;
    c_lo[k] = lo[k] - m;
    c_hi[k] = hi[k] + m;
  }
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  std::uniform_int_distribution<size_t> pick(0, b.size() == 0 ? 0 : b.size() - 1);
  std::uniform_int_distribution<uint32_t> bit(0, 3);
  Queries q;
  q.shape = shape;
  for (uint32_t i = 0; i < n; ++i) {
    float c[3];
    if (b.size() > 0 && (i & 1)) {
      const size_t j = pick(rng);
      const float corner[2][3] = {{b.min_x[j], b.min_y[j], b.min_z[j]}, {b.max_x[j], b.max_y[j], b.max_z[j]}};
      for (int k = 0; k < 3; ++k) c[k] = corner[rng() & 1][k];
    } else {
      for (int k = 0; k < 3; ++k) c[k] = c_lo[k] + unit(rng) * (c_hi[k] - c_lo[k]);
    }
    switch (shape) {
      case QShape::kAabb: {
        float h[3];
        for (int k = 0; k < 3; ++k) h[k] = unit(rng) * size;
        if (i % 5 == 2) {  // touching: the query's max (or min) is exactly a coordinate
          q.add_box(c[0] - 2 * h[0], c[1] - 2 * h[1], c[2] - 2 * h[2], c[0], c[1], c[2]);
        } else if (i % 5 == 4) {
          q.add_box(c[0], c[1], c[2], c[0] + 2 * h[0], c[1] + 2 * h[1], c[2] + 2 * h[2]);
        } else {
          q.add_box(c[0] - h[0], c[1] - h[1], c[2] - h[2], c[0] + h[0], c[1] + h[1], c[2] + h[2]);
        }
        break;
      }
      case QShape::kSphere: q.add_sphere(c[0], c[1], c[2], i % 7 == 3 ? 0.0f : unit(rng) * size); break;
      case QShape::kPoint: q.add_point(c[0], c[1], c[2]); break;
    }
    if (mask_kind == 1) {
      const uint32_t kind = rng() % 4;
      q.mask.push_back(kind == 0 ? 0xffffffffu : kind == 1 ? (1u << bit(rng)) : kind == 2 ? ~(1u << bit(rng)) : 0u);
    }
  }
  return q;
}

}  // namespace impact::test
