// An independent double-precision reference for the narrow phase's collision data.
//
// Every leaf type of kernels/narrowphase/leaf/leaf.h is described by its support function
// h(d) = max over the shape of d.x (exact, closed form per type), and where it is
// cheap by an exact signed distance (sphere, capsule, box, half-space; the triangle's
// unsigned distance, zero thickness).
//
// Collision data come from the support functions alone, by a method unrelated to the
// kernels' GJK / EPA / SAT-with-clipping: with o(n) = h_A(n) + h_B(-n) (how far A
// reaches towards n plus how far B reaches back towards -n, i.e. the support function
// of the Minkowski difference A - B), the quantity
//     s = min over unit n of o(n)
// is the penetration depth when s > 0 (the origin lies inside A - B and its distance
// to the boundary is the smallest support value) and minus the distance between the
// shapes when s < 0 (the distance from the origin to a convex set is
// max_n -h(n)); the minimiser n is the contact normal from A to B: moving B by s*n
// makes them touch. The minimum is found by dense sampling (a Fibonacci sphere plus
// candidate directions: face normals, axes, edge-edge cross products, the centre
// difference) and local refinement of the best few samples from distinct basins by
// Nelder-Mead in the tangent plane, restarted until it stops improving. Translating
// B by t changes o(n) to o(n) - n.t, so the "safe displacement" property of a
// kernel's answer can be checked with the same function.
//
// Signed distance of a point x to a convex shape without a closed form uses the same
// minimiser: sd(x) = -min_n (h(n) - n.x) (inside: minus the distance to the boundary).
//
// Accuracy, verified by tests/kernels/narrowphase/reference_self_test.cpp against
// closed forms (sphere-sphere, axis-aligned box-box, rotated overlapping box-box vs
// the 15 SAT axes, sphere-box via the box's signed distance, sphere-triangle,
// sphere / box / capsule vs half-space, parallel and skew capsule-capsule, needle and
// pancake boxes of aspect 1e4, point distances to cylinders, hulls and ellipsoids)
// with shapes of size 0.1..1: the measured worst |s - exact| is 1e-15 on smooth
// minima and 5e-13 on polytope corners even WITHOUT the polytope hints (sampling +
// refinement alone); the tests assert 1e-9 (1e-7 without hints). The normal is within
// 2e-7 rad of the exact one wherever the minimum is unique.
// Cost: about 4000-8000 support evaluations per solve (~0.2-1 ms).
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <utility>
#include <vector>

#include "kernels/narrowphase/leaf/leaf.h"

namespace impact::test::nref {

struct V3 {
  double x = 0, y = 0, z = 0;
  double operator[](int i) const { return i == 0 ? x : (i == 1 ? y : z); }
};
inline V3 operator+(V3 a, V3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
inline V3 operator-(V3 a, V3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
inline V3 operator-(V3 a) { return {-a.x, -a.y, -a.z}; }
inline V3 operator*(double s, V3 a) { return {s * a.x, s * a.y, s * a.z}; }
inline double dot(V3 a, V3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline V3 cross(V3 a, V3 b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
inline double norm(V3 a) { return std::sqrt(dot(a, a)); }
inline V3 normalized(V3 a) {
  const double l = norm(a);
  return l > 0 ? (1.0 / l) * a : V3{0, 0, 1};
}
/// Angle between two nonzero vectors, radians (accurate for small angles).
inline double angle(V3 a, V3 b) { return std::atan2(norm(cross(a, b)), dot(a, b)); }

using kernels::LeafType;

/// One posed leaf, in double. Build with the make_* helpers or from a LeafSoA lane.
struct Shape {
  LeafType type = kernels::kLeafSphere;
  V3 p;                                   ///< centre / hull frame origin / triangle v0 / plane point
  double r[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};  ///< row-major; columns are the local axes
  double e[3] = {0, 0, 0};                ///< sizes per leaf.h; half-space: unit normal
  std::vector<V3> pts;                    ///< convex: world vertices; triangle: v0, v1, v2
  std::vector<V3> face_normals;           ///< convex: optional hints (world, unit)
  std::vector<V3> edge_dirs;              ///< convex: optional hints (world)

  V3 col(int c) const { return {r[c], r[3 + c], r[6 + c]}; }
  V3 plane_normal() const { return {e[0], e[1], e[2]}; }
  /// A point well inside (the centroid of a triangle / hull).
  V3 centre() const {
    if (type == kernels::kLeafConvex || type == kernels::kLeafTriangle) {
      V3 c;
      for (const V3& q : pts) c = c + q;
      return (1.0 / static_cast<double>(pts.size())) * c;
    }
    return p;
  }
  /// Radius of a ball about centre() holding the shape (0 for half-spaces).
  double bound_radius() const {
    switch (type) {
      case kernels::kLeafSphere: return e[0];
      case kernels::kLeafCapsule: return e[0] + e[1];
      case kernels::kLeafBox: return std::sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]);
      case kernels::kLeafCylinder: return std::sqrt(e[0] * e[0] + e[1] * e[1]);
      case kernels::kLeafEllipsoid: return std::max({e[0], e[1], e[2]});
      case kernels::kLeafConvex:
      case kernels::kLeafTriangle: {
        const V3 c = centre();
        double m = 0;
        for (const V3& q : pts) m = std::max(m, norm(q - c));
        return m;
      }
      default: return 0.0;
    }
  }
};

inline void set_rotation(Shape& s, const double* r9) { std::copy(r9, r9 + 9, s.r); }

inline Shape make_sphere(V3 c, double radius) {
  Shape s;
  s.type = kernels::kLeafSphere;
  s.p = c;
  s.e[0] = radius;
  return s;
}
/// Capsule / cylinder along `axis` (unit; stored as rotation column 2 of an orthonormal frame).
inline Shape make_axial(LeafType t, V3 c, V3 axis, double radius, double half_length) {
  Shape s;
  s.type = t;
  s.p = c;
  const V3 w = normalized(axis);
  const V3 a = std::fabs(w.x) < 0.6 ? V3{1, 0, 0} : V3{0, 1, 0};
  const V3 u = normalized(cross(a, w));
  const V3 v = cross(w, u);
  const double r9[9] = {u.x, v.x, w.x, u.y, v.y, w.y, u.z, v.z, w.z};
  set_rotation(s, r9);
  s.e[0] = radius;
  s.e[1] = half_length;
  return s;
}
inline Shape make_box(V3 c, const double* r9, double hx, double hy, double hz,
                      LeafType t = kernels::kLeafBox) {
  Shape s;
  s.type = t;
  s.p = c;
  set_rotation(s, r9);
  s.e[0] = hx;
  s.e[1] = hy;
  s.e[2] = hz;
  return s;
}
inline Shape make_triangle(V3 a, V3 b, V3 c) {
  Shape s;
  s.type = kernels::kLeafTriangle;
  s.p = a;
  s.pts = {a, b, c};
  return s;
}
inline Shape make_halfspace(V3 point, V3 unit_normal) {
  Shape s;
  s.type = kernels::kLeafHalfSpace;
  s.p = point;
  s.e[0] = unit_normal.x;
  s.e[1] = unit_normal.y;
  s.e[2] = unit_normal.z;
  return s;
}
/// A convex hull from world points (all of them; interior points do not change h).
inline Shape make_convex(std::vector<V3> world_points) {
  Shape s;
  s.type = kernels::kLeafConvex;
  s.p = V3{};
  s.pts = std::move(world_points);
  return s;
}

/// Lane k of a LeafSoA, exactly as a kernel sees it (floats widened to double).
/// Convex leaves read their hull from `hulls` (vertices and, as hints, face normals
/// and edge directions, posed by the lane's R and p).
inline Shape shape_from_leaf(const kernels::LeafSoA& s, uint32_t k, LeafType t,
                             const kernels::HullView* hulls = nullptr) {
  Shape out;
  out.type = t;
  out.p = {s.p[0][k], s.p[1][k], s.p[2][k]};
  const bool posed = t == kernels::kLeafCapsule || t == kernels::kLeafBox || t == kernels::kLeafConvex ||
                     t == kernels::kLeafCylinder || t == kernels::kLeafEllipsoid;
  if (posed)
    for (int i = 0; i < 9; ++i) out.r[i] = s.r[i][k];
  if (t != kernels::kLeafConvex && t != kernels::kLeafTriangle)
    for (int i = 0; i < 3; ++i)
      if (s.e[i] != nullptr) out.e[i] = s.e[i][k];
  auto rot = [&](double x, double y, double z) {
    return V3{out.r[0] * x + out.r[1] * y + out.r[2] * z, out.r[3] * x + out.r[4] * y + out.r[5] * z,
              out.r[6] * x + out.r[7] * y + out.r[8] * z};
  };
  if (t == kernels::kLeafTriangle) {
    out.pts = {out.p, V3{s.w[0][k], s.w[1][k], s.w[2][k]}, V3{s.w[3][k], s.w[4][k], s.w[5][k]}};
  } else if (t == kernels::kLeafConvex && hulls != nullptr) {
    const uint32_t h = s.ref[k];
    for (uint32_t v = hulls->vert_begin[h]; v < hulls->vert_begin[h + 1]; ++v)
      out.pts.push_back(out.p + rot(hulls->vx[v], hulls->vy[v], hulls->vz[v]));
    for (uint32_t f = hulls->face_begin[h]; f < hulls->face_begin[h + 1]; ++f)
      out.face_normals.push_back(normalized(rot(hulls->fnx[f], hulls->fny[f], hulls->fnz[f])));
    for (uint32_t e = hulls->edge_begin[h]; e < hulls->edge_begin[h + 1]; ++e)
      out.edge_dirs.push_back(normalized(rot(hulls->ex[e], hulls->ey[e], hulls->ez[e])));
  }
  return out;
}

// --- support function and signed distances ------------------------------------------------

/// h(d) = max over the shape of d.x, for any d (positively homogeneous). Half-spaces
/// are unbounded: finite only for d along the outward normal (within 1e-12 rad).
inline double support(const Shape& s, V3 d) {
  switch (s.type) {
    case kernels::kLeafSphere: return dot(s.p, d) + s.e[0] * norm(d);
    case kernels::kLeafCapsule: return dot(s.p, d) + s.e[1] * std::fabs(dot(s.col(2), d)) + s.e[0] * norm(d);
    case kernels::kLeafBox:
      return dot(s.p, d) + s.e[0] * std::fabs(dot(s.col(0), d)) + s.e[1] * std::fabs(dot(s.col(1), d)) +
             s.e[2] * std::fabs(dot(s.col(2), d));
    case kernels::kLeafConvex:
    case kernels::kLeafTriangle: {
      double m = -std::numeric_limits<double>::infinity();
      for (const V3& q : s.pts) m = std::max(m, dot(q, d));
      return m;
    }
    case kernels::kLeafCylinder: {
      const V3 u = s.col(2);
      const double ud = dot(u, d);
      return dot(s.p, d) + s.e[1] * std::fabs(ud) + s.e[0] * norm(d - ud * u);
    }
    case kernels::kLeafEllipsoid: {
      const double a = s.e[0] * dot(s.col(0), d), b = s.e[1] * dot(s.col(1), d), c = s.e[2] * dot(s.col(2), d);
      return dot(s.p, d) + std::sqrt(a * a + b * b + c * c);
    }
    case kernels::kLeafHalfSpace: {
      const V3 n = s.plane_normal();
      if (angle(n, d) <= 1e-12 || norm(d) == 0) return dot(s.p, d);
      return std::numeric_limits<double>::infinity();
    }
    default: return std::numeric_limits<double>::quiet_NaN();
  }
}

/// Distance from x to the segment a..b.
inline double segment_distance(V3 x, V3 a, V3 b) {
  const V3 ab = b - a;
  const double l2 = dot(ab, ab);
  const double t = l2 > 0 ? std::clamp(dot(x - a, ab) / l2, 0.0, 1.0) : 0.0;
  return norm(x - (a + t * ab));
}

/// Distance from x to the triangle (a, b, c) (a closed set in 3D).
inline double triangle_distance(V3 x, V3 a, V3 b, V3 c) {
  const V3 n = cross(b - a, c - a);
  const double nn = dot(n, n);
  if (nn > 0) {
    // Barycentric test of the projection.
    const V3 q = x - (dot(x - a, n) / nn) * n;
    const double u = dot(cross(b - q, c - q), n), v = dot(cross(c - q, a - q), n), w = dot(cross(a - q, b - q), n);
    if (u >= 0 && v >= 0 && w >= 0) return std::fabs(dot(x - a, n)) / std::sqrt(nn);
  }
  return std::min({segment_distance(x, a, b), segment_distance(x, b, c), segment_distance(x, c, a)});
}

// --- minimisation on the unit sphere -------------------------------------------------------

/// n points on the unit sphere, evenly spread (Fibonacci lattice).
inline const std::vector<V3>& fibonacci_sphere(int n) {
  static std::vector<V3> cache;
  if (static_cast<int>(cache.size()) != n) {
    cache.resize(static_cast<size_t>(n));
    const double golden = M_PI * (3.0 - std::sqrt(5.0));
    for (int i = 0; i < n; ++i) {
      const double z = 1.0 - (2.0 * i + 1.0) / n;
      const double rr = std::sqrt(std::max(0.0, 1.0 - z * z));
      const double phi = golden * i;
      cache[static_cast<size_t>(i)] = {rr * std::cos(phi), rr * std::sin(phi), z};
    }
  }
  return cache;
}

struct Options {
  int samples = 3000;          ///< Fibonacci directions
  int starts = 5;              ///< refined basins
  double start_separation = 0.15;  ///< rad between refinement starts
  double initial_step = 0.05;  ///< rad, about the sampling spacing
  bool use_hints = true;       ///< face normals, axes, edge crosses as extra samples
  double unique_cone = 0.02;   ///< rad: `second` is the best value outside this cone
};

struct SphereMin {
  double value = std::numeric_limits<double>::infinity();
  V3 n{0, 0, 1};
  /// Best value found at directions more than Options::unique_cone from n (sampled
  /// directions, the other basins' minima and a ring on the cone's boundary): an upper
  /// bound on the second-best; the minimiser is unique when it is clearly above value.
  double second = std::numeric_limits<double>::infinity();
};

namespace detail {

/// Nelder-Mead in 2D on g, from (0, 0) with a simplex of size `step` turned by `turn`.
template <class G>
std::pair<double, std::array<double, 2>> nelder_mead_2d(const G& g, double step, double turn, int max_evals) {
  std::array<std::array<double, 2>, 3> x{};
  std::array<double, 3> f{};
  x[0] = {0, 0};
  x[1] = {step * std::cos(turn), step * std::sin(turn)};
  x[2] = {step * std::cos(turn + 2.0943951), step * std::sin(turn + 2.0943951)};
  for (int i = 0; i < 3; ++i) f[static_cast<size_t>(i)] = g(x[static_cast<size_t>(i)][0], x[static_cast<size_t>(i)][1]);
  int evals = 3;
  auto order = [&] {
    for (int i = 0; i < 2; ++i)
      for (int j = 0; j < 2 - i; ++j)
        if (f[static_cast<size_t>(j + 1)] < f[static_cast<size_t>(j)]) {
          std::swap(f[static_cast<size_t>(j)], f[static_cast<size_t>(j + 1)]);
          std::swap(x[static_cast<size_t>(j)], x[static_cast<size_t>(j + 1)]);
        }
  };
  while (evals < max_evals) {
    order();
    const double size = std::max(std::hypot(x[1][0] - x[0][0], x[1][1] - x[0][1]),
                                 std::hypot(x[2][0] - x[0][0], x[2][1] - x[0][1]));
    if (size < 1e-12) break;
    const std::array<double, 2> c = {0.5 * (x[0][0] + x[1][0]), 0.5 * (x[0][1] + x[1][1])};
    auto at = [&](double t) {
      return std::array<double, 2>{c[0] + t * (x[2][0] - c[0]), c[1] + t * (x[2][1] - c[1])};
    };
    const auto xr = at(-1.0);
    const double fr = g(xr[0], xr[1]);
    ++evals;
    if (fr < f[0]) {
      const auto xe = at(-2.0);
      const double fe = g(xe[0], xe[1]);
      ++evals;
      if (fe < fr) {
        x[2] = xe;
        f[2] = fe;
      } else {
        x[2] = xr;
        f[2] = fr;
      }
    } else if (fr < f[1]) {
      x[2] = xr;
      f[2] = fr;
    } else {
      const bool outside = fr < f[2];
      const auto xc = at(outside ? -0.5 : 0.5);
      const double fc = g(xc[0], xc[1]);
      ++evals;
      if (fc < (outside ? fr : f[2])) {
        x[2] = xc;
        f[2] = fc;
      } else {
        for (size_t i = 1; i < 3; ++i) {
          x[i] = {0.5 * (x[0][0] + x[i][0]), 0.5 * (x[0][1] + x[i][1])};
          f[i] = g(x[i][0], x[i][1]);
        }
        evals += 2;
      }
    }
  }
  order();
  return {f[0], x[0]};
}

inline void tangent_basis(V3 n, V3& t1, V3& t2) {
  const V3 a = std::fabs(n.x) < 0.6 ? V3{1, 0, 0} : (std::fabs(n.y) < 0.6 ? V3{0, 1, 0} : V3{0, 0, 1});
  t1 = normalized(cross(a, n));
  t2 = cross(n, t1);
}

/// Local refinement from n0 by restarted Nelder-Mead in n0's tangent plane.
template <class F>
std::pair<double, V3> refine(const F& f, V3 n0, double f0, double step0) {
  V3 n = n0;
  double best = f0;
  const double steps[] = {1.0, 0.2, 1.0, 0.03, 0.3, 3e-3, 1.0, 3e-4, 0.1, 3e-5};
  int stale = 0;
  for (int k = 0; k < 10 && stale < 3; ++k) {
    V3 t1, t2;
    tangent_basis(n, t1, t2);
    auto g = [&](double a, double b) { return f(normalized(n + a * t1 + b * t2)); };
    const auto [v, ab] = nelder_mead_2d(g, std::max(step0 * steps[k], 1e-9), 0.61 * k, 600);
    if (v < best) {
      const double gain = best - v;
      best = v;
      n = normalized(n + ab[0] * t1 + ab[1] * t2);
      stale = gain > 1e-15 * std::max(1.0, std::fabs(best)) ? 0 : stale + 1;
    } else {
      ++stale;
    }
  }
  return {best, n};
}

}  // namespace detail

/// min over unit n of f(n): dense samples plus `candidates`, then local refinement of
/// the best samples from distinct basins. f must accept any unit vector.
template <class F>
SphereMin minimise_on_sphere(const F& f, const std::vector<V3>& candidates, const Options& opt = {}) {
  std::vector<std::pair<double, V3>> samples;
  const auto& fib = fibonacci_sphere(opt.samples);
  samples.reserve(fib.size() + candidates.size());
  for (const V3& d : fib) samples.push_back({f(d), d});
  for (const V3& c : candidates) {
    if (!(norm(c) > 0)) continue;
    const V3 d = normalized(c);
    samples.push_back({f(d), d});
  }
  std::vector<size_t> idx(samples.size());
  for (size_t i = 0; i < idx.size(); ++i) idx[i] = i;
  std::stable_sort(idx.begin(), idx.end(), [&](size_t a, size_t b) { return samples[a].first < samples[b].first; });
  std::vector<V3> starts;
  for (size_t i : idx) {
    if (static_cast<int>(starts.size()) >= opt.starts) break;
    if (!std::isfinite(samples[i].first)) break;
    bool far = true;
    for (const V3& s : starts) far = far && angle(s, samples[i].second) > opt.start_separation;
    if (far) starts.push_back(samples[i].second);
  }
  std::vector<std::pair<double, V3>> minima;
  SphereMin out;
  for (const V3& s : starts) {
    const auto m = detail::refine(f, s, f(s), opt.initial_step);
    minima.push_back(m);
    if (m.first < out.value) {
      out.value = m.first;
      out.n = m.second;
    }
  }
  if (starts.empty() && !samples.empty()) {
    out.value = samples[idx[0]].first;
    out.n = samples[idx[0]].second;
  }
  // Second best outside the cone: samples, other minima, and a ring on the cone.
  for (const auto& s : samples)
    if (angle(s.second, out.n) > opt.unique_cone) out.second = std::min(out.second, s.first);
  for (const auto& m : minima)
    if (angle(m.second, out.n) > opt.unique_cone) out.second = std::min(out.second, m.first);
  V3 t1, t2;
  detail::tangent_basis(out.n, t1, t2);
  const double tc = std::tan(opt.unique_cone * 1.0001);
  for (int i = 0; i < 64; ++i) {
    const double a = 2.0 * M_PI * i / 64.0;
    out.second = std::min(out.second, f(normalized(out.n + tc * std::cos(a) * t1 + tc * std::sin(a) * t2)));
  }
  return out;
}

/// Directions worth sampling exactly for a shape: face normals, axes, edges.
inline void shape_directions(const Shape& s, std::vector<V3>& faces, std::vector<V3>& edges) {
  switch (s.type) {
    case kernels::kLeafBox:
    case kernels::kLeafEllipsoid:
      for (int c = 0; c < 3; ++c) {
        faces.push_back(s.col(c));
        edges.push_back(s.col(c));
      }
      break;
    case kernels::kLeafCapsule:
    case kernels::kLeafCylinder:
      faces.push_back(s.col(2));
      edges.push_back(s.col(2));
      break;
    case kernels::kLeafTriangle: {
      const V3 a = s.pts[0], b = s.pts[1], c = s.pts[2];
      faces.push_back(cross(b - a, c - a));
      edges.push_back(b - a);
      edges.push_back(c - b);
      edges.push_back(a - c);
      break;
    }
    case kernels::kLeafConvex:
      faces.insert(faces.end(), s.face_normals.begin(), s.face_normals.end());
      edges.insert(edges.end(), s.edge_dirs.begin(), s.edge_dirs.end());
      break;
    case kernels::kLeafHalfSpace: faces.push_back(s.plane_normal()); break;
    default: break;
  }
}

/// o(n) = h_A(n) + h_B(-n) - n.t for B translated by t: > 0 means A and B overlap
/// along n (their projections on n overlap by o(n)).
inline double overlap(const Shape& a, const Shape& b, V3 n, V3 b_shift = {}) {
  return support(a, n) + support(b, -n) - dot(n, b_shift);
}

struct PairResult {
  double s = 0;     ///< > 0: penetration depth; < 0: minus the distance
  V3 n{0, 0, 1};    ///< unit, from A to B: moving B by s*n makes them touch
  double second = std::numeric_limits<double>::infinity();  ///< see SphereMin::second
  bool unique(double tol) const { return second > s + tol; }
};

/// How far a float kernel's normal may be off the reference's unique minimiser: `floor`,
/// or, in a flat valley, the angle at which the overlap rises by `noise` above its
/// minimum (the float overlap is only that exact), the valley taken as quadratic through
/// `rise`, the overlap's least rise `at` rad from the minimiser (rise > 0).
inline double valley_angle(double floor, double rise, double at, double noise) {
  return std::max(floor, at * std::sqrt(noise / rise));
}

/// More samples and starts than the default, for the kernel tests that hold a normal to
/// 1e-4 rad (needles, pancakes and flat valleys).
inline Options dense_options() {
  Options o;
  o.samples = 6000;
  o.starts = 8;
  return o;
}

/// The least rise of the overlap of A and B over its value at n along the ring `cone`
/// rad around n (3e-3 by default): 64 samples, the best 4 refined by golden-section
/// search on the ring's angle (a needle's flat valley is ~1e-4 of the ring wide and
/// slips between samples). How well conditioned the minimum at n is.
inline double ring_rise(const Shape& a, const Shape& b, V3 n, double cone = 3e-3) {
  V3 t1, t2;
  detail::tangent_basis(n, t1, t2);
  const double th = std::tan(cone), s = overlap(a, b, n);
  auto f = [&](double ang) {
    return overlap(a, b, normalized(n + th * std::cos(ang) * t1 + th * std::sin(ang) * t2)) - s;
  };
  std::vector<std::pair<double, double>> samples;
  for (int i = 0; i < 64; ++i) samples.push_back({f(2 * M_PI * i / 64), 2 * M_PI * i / 64});
  std::partial_sort(samples.begin(), samples.begin() + 4, samples.end());
  double best = samples[0].first;
  for (int k = 0; k < 4; ++k) {
    double lo = samples[k].second - 2 * M_PI / 64, hi = samples[k].second + 2 * M_PI / 64;
    for (int it = 0; it < 40; ++it) {
      const double m1 = lo + 0.381966 * (hi - lo), m2 = lo + 0.618034 * (hi - lo);
      (f(m1) < f(m2) ? hi : lo) = f(m1) < f(m2) ? m2 : m1;
    }
    best = std::min(best, f(0.5 * (lo + hi)));
  }
  return best;
}

/// Whether r (solve_pair's answer for a and b) is well conditioned at tol for a pair of
/// size L: its minimum unique at tol and the overlap rising by at least 1e-6 L 3e-3 rad
/// from it in every direction (the per-kernel tests' rule).
inline bool well_conditioned(const Shape& a, const Shape& b, const PairResult& r, double tol, double L) {
  return r.unique(tol) && ring_rise(a, b, r.n) >= 1e-6 * L;
}

/// The reference collision data of A and B (B translated by b_shift).
inline PairResult solve_pair(const Shape& a, const Shape& b, V3 b_shift = {}, const Options& opt = {}) {
  PairResult r;
  if (b.type == kernels::kLeafHalfSpace || a.type == kernels::kLeafHalfSpace) {
    const bool b_plane = b.type == kernels::kLeafHalfSpace;
    const V3 m = b_plane ? b.plane_normal() : a.plane_normal();
    r.n = b_plane ? -m : m;
    r.s = b_plane ? support(a, -m) + dot(m, b.p + b_shift) : dot(m, a.p) + support(b, -m) - dot(m, b_shift);
    return r;
  }
  std::vector<V3> cand;
  if (opt.use_hints) {
    std::vector<V3> fa, ea, fb, eb;
    shape_directions(a, fa, ea);
    shape_directions(b, fb, eb);
    for (const auto* v : {&fa, &fb})
      for (const V3& d : *v) {
        cand.push_back(d);
        cand.push_back(-d);
      }
    for (const V3& x : ea)
      for (const V3& y : eb) {
        const V3 c = cross(x, y);
        if (norm(c) > 1e-12 * norm(x) * norm(y)) {
          cand.push_back(c);
          cand.push_back(-c);
        }
      }
  }
  const V3 dc = b.centre() + b_shift - a.centre();
  if (norm(dc) > 0) cand.push_back(dc);
  const auto f = [&](V3 n) { return overlap(a, b, n, b_shift); };
  const SphereMin m = minimise_on_sphere(f, cand, opt);
  r.s = m.value;
  r.n = m.n;
  r.second = m.second;
  return r;
}

/// Signed distance from x to the shape's surface (< 0 inside; triangles: unsigned).
inline double signed_distance(const Shape& s, V3 x, const Options& opt = {}) {
  switch (s.type) {
    case kernels::kLeafSphere: return norm(x - s.p) - s.e[0];
    case kernels::kLeafCapsule: {
      const V3 u = s.col(2);
      return segment_distance(x, s.p - s.e[1] * u, s.p + s.e[1] * u) - s.e[0];
    }
    case kernels::kLeafBox: {
      double q[3], out2 = 0, inside = -std::numeric_limits<double>::infinity();
      for (int i = 0; i < 3; ++i) {
        q[i] = std::fabs(dot(s.col(i), x - s.p)) - s.e[i];
        out2 += q[i] > 0 ? q[i] * q[i] : 0.0;
        inside = std::max(inside, q[i]);
      }
      return inside > 0 ? std::sqrt(out2) : inside;
    }
    case kernels::kLeafHalfSpace: return dot(s.plane_normal(), x - s.p);
    case kernels::kLeafTriangle: return triangle_distance(x, s.pts[0], s.pts[1], s.pts[2]);
    default: {
      std::vector<V3> cand, edges;
      if (opt.use_hints) shape_directions(s, cand, edges);
      const size_t nf = cand.size();
      for (size_t i = 0; i < nf; ++i) cand.push_back(-cand[i]);
      if (norm(x - s.centre()) > 0) cand.push_back(x - s.centre());
      const auto f = [&](V3 n) { return support(s, n) - dot(n, x); };
      return -minimise_on_sphere(f, cand, opt).value;
    }
  }
}

}  // namespace impact::test::nref
