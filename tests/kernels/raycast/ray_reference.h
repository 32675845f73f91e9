// Independent double-precision reference for the ray queries, written from the rules
// in include/impact/raycast.h (not from the kernels): every primitive is tested in
// double with textbook formulas (sphere and capsule by the plain quadratic, triangles
// by Moller-Trumbore, half-spaces directly), and each test also says whether its
// answer is *robust*: a hit or miss that a float implementation must reproduce, or an
// ambiguous case (within a relative band of the boundary: grazing a sphere, on a
// triangle edge, at tmax, origin on a surface) where either answer is acceptable.
//
// Tolerances are relative to the scene scale S = max(1, |origin|, |primitive|, t):
// float inputs carry ~6e-8 S of rounding, so a float kernel's t can differ from the
// exact one by a few ulps of S, not of t. That is why scenes offset 1e5 m from the
// origin need S-relative (not t-relative) tolerances.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "impact/raycast.h"

namespace impact::test {

using V3 = Eigen::Vector3d;

/// Width of the ambiguous band, relative to the scale S.
inline constexpr double kBand = 2e-5;

enum class Ref : int { kMiss = 0, kHit = 1, kAmbiguous = 2 };

struct RefHit {
  Ref state = Ref::kMiss;
  double t = std::numeric_limits<double>::infinity();
};

inline double scale_of(const V3& o, double extra) { return std::max({1.0, o.cwiseAbs().maxCoeff(), extra}); }

// Classifies a candidate hit at t against [0, tmax] with band eps.
inline RefHit classify(bool hit, bool near_boundary, double t, double tmax, double eps) {
  if (!hit && !near_boundary) return {};
  const double tt = std::max(t, 0.0);
  if (tt > tmax + eps) return {};
  const bool at_end = std::fabs(tt - tmax) <= eps;
  return {(near_boundary || at_end) ? Ref::kAmbiguous : Ref::kHit, tt};
}

/// |cos| of the angle between a ray and a surface below which t is ill-conditioned
/// (a float t may then differ from the exact one by more than the tolerance).
inline constexpr double kGrazingCos = 1e-2;

/// Ball (c, r); solid.
inline RefHit ref_sphere(const V3& o, const V3& d, double tmax, const V3& c, double r) {
  const double S = scale_of(o, std::max(c.cwiseAbs().maxCoeff() + r, 1.0));
  const double eps = kBand * S;
  const V3 oc = o - c;
  const double dist = oc.norm();
  if (dist <= r - eps) return {Ref::kHit, 0.0};
  if (dist <= r + eps) return {Ref::kAmbiguous, 0.0};
  // |oc + t d|^2 = r^2: t^2 + 2 b t + c = 0.
  const double b = oc.dot(d);
  const double cc = oc.squaredNorm() - r * r;
  const double disc = b * b - cc;
  // Distance of the line from the centre vs r decides grazing.
  const double m = (oc - b * d).norm();
  if (m > r + eps || b > 0.0) return {};
  const double t = -b - std::sqrt(std::max(disc, 0.0));
  return classify(m <= r - eps, m > r - eps, t, tmax, eps);
}

inline double seg_dist(const V3& p, const V3& a, const V3& b) {
  const V3 ab = b - a;
  const double l2 = ab.squaredNorm();
  const double u = l2 > 0.0 ? std::clamp((p - a).dot(ab) / l2, 0.0, 1.0) : 0.0;
  return (p - (a + u * ab)).norm();
}

/// Capsule (segment a-b, radius r); solid. Union of two balls and the finite cylinder.
inline RefHit ref_capsule(const V3& o, const V3& d, double tmax, const V3& a, const V3& b, double r) {
  const double S = scale_of(o, std::max({a.cwiseAbs().maxCoeff(), b.cwiseAbs().maxCoeff(), 1.0}) + r);
  const double eps = kBand * S;
  const double dist = seg_dist(o, a, b);
  if (dist <= r - eps) return {Ref::kHit, 0.0};
  if (dist <= r + eps) return {Ref::kAmbiguous, 0.0};
  RefHit best;
  auto take = [&](const RefHit& h) {
    if (h.state == Ref::kMiss) return;
    if (best.state == Ref::kMiss || h.t < best.t - eps) {
      best = h;
    } else if (std::fabs(h.t - best.t) <= eps) {
      // Same entry within the band: robust if either is.
      if (h.state == Ref::kHit) best.state = Ref::kHit;
      best.t = std::min(best.t, h.t);
    }
  };
  take(ref_sphere(o, d, tmax, a, r));
  take(ref_sphere(o, d, tmax, b, r));
  const V3 ab = b - a;
  const double L = ab.norm();
  if (L > 0.0) {
    const V3 u = ab / L;
    // Infinite cylinder: |(o + t d - a) x u| = r  ->  A t^2 + 2 B t + C = 0.
    const V3 w = o - a;
    const V3 dp = d - d.dot(u) * u, wp = w - w.dot(u) * u;
    const double A = dp.squaredNorm(), B = wp.dot(dp), C = wp.squaredNorm() - r * r;
    // C > 0: the origin is outside the infinite cylinder; B <= 0: approaching its axis.
    if (A > 1e-18 && C > 0.0 && B <= 0.0) {
      const double m = (wp - (B / A) * dp).norm();  // closest approach of the line to the axis
      if (m <= r + eps) {
        const double disc = std::max(B * B - A * C, 0.0);
        const double t = (-B - std::sqrt(disc)) / A;
        const double y = (w + t * d).dot(u);
        const bool inside_len = y > eps && y < L - eps;
        const bool near_len = std::fabs(y) <= eps || std::fabs(y - L) <= eps;
        // Ill-conditioned when the ray runs nearly along the axis (A small).
        const bool grazing = m > r - eps || A < kGrazingCos * kGrazingCos;
        if (inside_len || near_len) take(classify(inside_len && !grazing, grazing || near_len, t, tmax, eps));
      }
    }
  }
  if (best.state != Ref::kMiss && best.t > tmax + eps) return {};
  return best;
}

/// Triangle, two-sided, edges inclusive; a ray in its plane misses.
inline RefHit ref_triangle(const V3& o, const V3& d, double tmax, const V3& v0, const V3& v1, const V3& v2) {
  const double S = scale_of(o, std::max({v0.cwiseAbs().maxCoeff(), v1.cwiseAbs().maxCoeff(), v2.cwiseAbs().maxCoeff()}));
  const double eps = kBand * S;
  const V3 e1 = v1 - v0, e2 = v2 - v0;
  const V3 n = e1.cross(e2);
  const double area2 = n.norm();
  if (area2 == 0.0) return {};
  const double dn = d.dot(n) / area2;  // cos of the angle to the normal
  const V3 p = d.cross(e2);
  const double det = e1.dot(p);
  const bool near_parallel = std::fabs(dn) < kGrazingCos;
  if (det == 0.0) return {};
  const V3 s = o - v0;
  const double bu = s.dot(p) / det;
  const V3 q = s.cross(e1);
  const double bv = d.dot(q) / det;
  const double t = e2.dot(q) / det;
  const double bw = 1.0 - bu - bv;
  // Barycentric band: eps relative to the triangle's size, in barycentric units.
  const double size = std::max({e1.norm(), e2.norm(), (v2 - v1).norm()});
  const double beps = std::max(kBand * S / std::max(size, 1e-30), 1e-9);
  const double mn = std::min({bu, bv, bw});
  if (mn < -beps) return {};
  if (t < -eps) return {};
  const bool near_edge = mn <= beps;
  // Grazing incidence: tiny rounding in the plane moves t a lot; treat as ambiguous.
  return classify(!near_edge && !near_parallel, near_edge || near_parallel || t < eps, t, tmax, eps);
}

/// Half-space {x : n.x <= off} with n unit; solid.
inline RefHit ref_plane(const V3& o, const V3& d, double tmax, const V3& n, double off) {
  const double S = scale_of(o, std::fabs(off));
  const double eps = kBand * S;
  const double s = n.dot(o) - off;
  if (s <= -eps) return {Ref::kHit, 0.0};
  if (s <= eps) return {Ref::kAmbiguous, 0.0};
  const double dn = n.dot(d);
  if (dn >= 0.0) return {};
  return classify(dn < -kGrazingCos, dn >= -kGrazingCos, s / -dn, tmax, eps);
}

/// A reference scene: the same geometry a test gives the RayScene, in double.
struct RefScene {
  std::vector<V3> verts;                  // all meshes, global vertex index
  std::vector<Eigen::Vector3i> tris;      // global vertex indices
  std::vector<uint32_t> tri_mesh, tri_local, tri_layer;
  std::vector<V3> sc;
  std::vector<double> sr;
  std::vector<uint32_t> s_layer;
  std::vector<V3> ca, cb;
  std::vector<double> cr;
  std::vector<uint32_t> c_layer;
  std::vector<V3> pn;
  std::vector<double> poff;
  std::vector<uint32_t> p_layer;
};

/// One primitive's answer for a ray.
struct RefCandidate {
  HitKind kind;
  uint32_t id, prim;
  RefHit h;
};

/// Every non-miss primitive for the ray (unit direction d).
inline std::vector<RefCandidate> ref_candidates(const RefScene& s, const V3& o, const V3& d, double tmax, uint32_t mask) {
  std::vector<RefCandidate> out;
  auto add = [&](HitKind k, uint32_t id, uint32_t prim, const RefHit& h) {
    if (h.state != Ref::kMiss) out.push_back({k, id, prim, h});
  };
  for (size_t i = 0; i < s.tris.size(); ++i) {
    if ((s.tri_layer[i] & mask) == 0) continue;
    const auto& t = s.tris[i];
    add(HitKind::kTriangle, s.tri_mesh[i], s.tri_local[i], ref_triangle(o, d, tmax, s.verts[t[0]], s.verts[t[1]], s.verts[t[2]]));
  }
  for (size_t i = 0; i < s.sc.size(); ++i)
    if (s.s_layer[i] & mask) add(HitKind::kSphere, static_cast<uint32_t>(i), 0, ref_sphere(o, d, tmax, s.sc[i], s.sr[i]));
  for (size_t i = 0; i < s.ca.size(); ++i)
    if (s.c_layer[i] & mask)
      add(HitKind::kCapsule, static_cast<uint32_t>(i), 0, ref_capsule(o, d, tmax, s.ca[i], s.cb[i], s.cr[i]));
  for (size_t i = 0; i < s.pn.size(); ++i)
    if (s.p_layer[i] & mask) add(HitKind::kPlane, static_cast<uint32_t>(i), 0, ref_plane(o, d, tmax, s.pn[i], s.poff[i]));
  return out;
}

inline V3 unit(const Eigen::Vector3f& v) { return v.cast<double>().normalized(); }

/// Checks a closest hit against the reference; returns "" when acceptable.
/// Acceptable: no robust hit and no hit reported; or the reported primitive is a
/// candidate with t within tol of its reference t, and no robust candidate is nearer
/// than t - tol.
inline std::string check_closest(const RefScene& s, const Ray& ray, const RayHit& got, double rel_tol = 1e-4) {
  const V3 o = ray.origin.cast<double>(), d = unit(ray.direction);
  const double tmax = ray.tmax;
  if (tmax == 0.0) return got.hit() ? "hit with tmax = 0" : "";
  const auto cands = ref_candidates(s, o, d, tmax, ray.mask);
  double best_robust = std::numeric_limits<double>::infinity();
  for (const auto& c : cands)
    if (c.h.state == Ref::kHit) best_robust = std::min(best_robust, c.h.t);
  const double S = scale_of(o, std::isfinite(best_robust) ? best_robust : 1.0);
  const double tol = rel_tol * S;
  if (!got.hit()) {
    return std::isfinite(best_robust) ? "missed a robust hit at t = " + std::to_string(best_robust) : "";
  }
  if (!(got.t >= 0.0f) || got.t > ray.tmax) return "t out of [0, tmax]: " + std::to_string(got.t);
  const RefCandidate* match = nullptr;
  for (const auto& c : cands)
    if (c.kind == got.kind && c.id == got.id && c.prim == got.prim) match = &c;
  if (!match)
    return "hit kind " + std::to_string(int(got.kind)) + " id " + std::to_string(got.id) + " prim " +
           std::to_string(got.prim) + " at t = " + std::to_string(got.t) + " is not a reference candidate (robust best " +
           std::to_string(best_robust) + ")";
  if (std::fabs(match->h.t - got.t) > tol && match->h.state == Ref::kHit)
    return "t = " + std::to_string(got.t) + ", reference " + std::to_string(match->h.t);
  if (got.t > best_robust + tol) return "t = " + std::to_string(got.t) + " beyond the nearest robust hit " + std::to_string(best_robust);
  // Point and normal.
  const V3 p = o + static_cast<double>(got.t) * d;
  if ((got.point.cast<double>() - p).norm() > tol + 1e-6 * S) return "point off the ray";
  const V3 n = got.normal.cast<double>();
  if (std::fabs(n.norm() - 1.0) > 1e-5) return "normal not unit";
  if (n.dot(d) > 1e-6) return "normal does not face the ray";
  return "";
}

/// Checks an any-hit answer (segment from -> to, closed) against the reference.
inline std::string check_any(const RefScene& s, const Segment& seg, bool got) {
  const V3 o = seg.from.cast<double>();
  const V3 v = (seg.to - seg.from).cast<double>();
  const double len = v.norm();
  if (len == 0.0) return got ? "zero-length segment occluded" : "";
  const auto cands = ref_candidates(s, o, v / len, len, seg.mask);
  bool robust = false, any = false;
  for (const auto& c : cands) {
    any = true;
    robust |= c.h.state == Ref::kHit;
  }
  if (robust && !got) return "robustly occluded, reported clear";
  if (!any && got) return "reported occluded, nothing near the segment";
  return "";
}

// --- scene builders -----------------------------------------------------------------

/// Grid heightfield mesh: (nx+1) x (nz+1) vertices spaced `cell` from `origin`, height
/// h(x, z); two triangles per cell (shared edges and vertices).
struct Grid {
  Eigen::Matrix3Xf v;
  Eigen::Matrix<uint32_t, 3, Eigen::Dynamic> t;
};

template <class H>
Grid make_grid(uint32_t nx, uint32_t nz, float cell, const Eigen::Vector3f& origin, H&& height) {
  Grid g;
  g.v.resize(3, (nx + 1) * (nz + 1));
  g.t.resize(3, 2 * nx * nz);
  for (uint32_t j = 0; j <= nz; ++j)
    for (uint32_t i = 0; i <= nx; ++i) {
      const float x = static_cast<float>(i) * cell, z = static_cast<float>(j) * cell;
      g.v.col(j * (nx + 1) + i) = origin + Eigen::Vector3f(x, height(x, z), z);
    }
  uint32_t k = 0;
  for (uint32_t j = 0; j < nz; ++j)
    for (uint32_t i = 0; i < nx; ++i) {
      const uint32_t a = j * (nx + 1) + i, b = a + 1, c = a + nx + 1, d = c + 1;
      g.t.col(k++) = Eigen::Matrix<uint32_t, 3, 1>(a, c, b);
      g.t.col(k++) = Eigen::Matrix<uint32_t, 3, 1>(b, c, d);
    }
  return g;
}

inline void add_mesh_ref(RefScene& s, const Eigen::Matrix3Xf& v, const Eigen::Matrix<uint32_t, 3, Eigen::Dynamic>& t,
                         uint32_t mesh, uint32_t layer) {
  const int base = static_cast<int>(s.verts.size());
  for (Eigen::Index i = 0; i < v.cols(); ++i) s.verts.push_back(v.col(i).cast<double>());
  for (Eigen::Index i = 0; i < t.cols(); ++i) {
    s.tris.emplace_back(base + static_cast<int>(t(0, i)), base + static_cast<int>(t(1, i)), base + static_cast<int>(t(2, i)));
    s.tri_mesh.push_back(mesh);
    s.tri_local.push_back(static_cast<uint32_t>(i));
    s.tri_layer.push_back(layer);
  }
}

}  // namespace impact::test
