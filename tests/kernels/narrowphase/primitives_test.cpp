// The specialised narrow-phase kernels (kernels/narrowphase/pairs/), called
// directly on hand-built LeafSoA buckets:
//   SimdMatchesScalar  SIMD vs scalar path on thousands of random lanes per pair type
//                      (about half overlapping): same counts, same data within a
//                      size-scaled tolerance; odd bucket sizes and ranges split at odd
//                      places give bytes identical to one whole range.
//   Analytic*          cases with exact answers (resting boxes, crossed edges, parallel
//                      capsules, sphere inside a box, coincident centres, touching; a
//                      box resting on a triangle, a box corner into a triangle's face,
//                      a triangle vertex into a box face, box edge x triangle edge).
//   MinimumAxis        deep lanes where an edge axis is slightly shallower than every
//                      face axis (once lost to a 1% face bias), against the exact
//                      double-precision reference of tests/support/narrow_reference.h;
//                      tilted resting boxes still give a 4-point face manifold.
//   Random / Extremes  for every contact, independent double-precision checks:
//                      (a) the surfaces: x + n*pdepth/2 lies on A's surface and
//                          x - n*pdepth/2 on B's (signed distances in double);
//                      (b) minimum translation: B moved by n*(depth + eps) is separated
//                          and by n*(depth - eps) still overlaps (double overlap tests:
//                          distance by convex 1-D minimisation for round shapes,
//                          15-axis SAT for box-box, 13-axis for box-triangle);
//                      (c) every lane the double test calls overlapping (by more than
//                          a tolerance) has a contact, and every clearly separated
//                          lane none.
//                      Extremes: aspect-1e4 needles and pancakes, sizes 1e-4 and 1e4,
//                      poses 1e5 from the origin, near-parallel edges and axes.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <ostream>
#include <random>
#include <string>
#include <vector>

#include "kernels/narrowphase/pair_kernels.h"
#include "support/narrow_reference.h"
#include "support/test_support.h"

namespace impact::kernels {
namespace {

// ---------------------------------------------------------------------------------------
// Double-precision shapes and the reference geometry
// ---------------------------------------------------------------------------------------

enum class Kind { kSphere, kCapsule, kBox, kTriangle, kHalfSpace };

using D3 = std::array<double, 3>;

D3 add(const D3& a, const D3& b) { return {a[0] + b[0], a[1] + b[1], a[2] + b[2]}; }
D3 sub(const D3& a, const D3& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
D3 mul(const D3& a, double s) { return {a[0] * s, a[1] * s, a[2] * s}; }
double dot(const D3& a, const D3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
D3 cross(const D3& a, const D3& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
double norm(const D3& a) { return std::sqrt(dot(a, a)); }

/// A posed shape, every value already rounded to float (what the kernel sees).
struct Shape {
  Kind kind = Kind::kSphere;
  D3 p{};                   // centre / triangle v0 / plane point
  double R[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};  // row-major, world = R*local + p
  D3 e{};                   // sizes (see leaf.h), half-space: unit normal
  D3 v1{}, v2{};            // triangle

  D3 col(int c) const { return {R[0][c], R[1][c], R[2][c]}; }
  D3 to_local(const D3& x) const {
    const D3 d = sub(x, p);
    return {dot(col(0), d), dot(col(1), d), dot(col(2), d)};
  }
  /// Bounding radius about p (not for half-spaces).
  double bound() const {
    switch (kind) {
      case Kind::kSphere: return e[0];
      case Kind::kCapsule: return e[0] + e[1];
      case Kind::kBox: return norm(e);
      case Kind::kTriangle: return std::max(norm(sub(v1, p)), norm(sub(v2, p)));
      default: return 0;
    }
  }
  /// A characteristic size.
  double size() const {
    switch (kind) {
      case Kind::kSphere: return e[0];
      case Kind::kCapsule: return e[0] + e[1];
      case Kind::kBox: return std::max({e[0], e[1], e[2]});
      case Kind::kTriangle: return bound();
      default: return 0;
    }
  }
  Shape moved(const D3& t) const {
    Shape s = *this;
    s.p = add(p, t);
    s.v1 = add(v1, t);
    s.v2 = add(v2, t);
    return s;
  }
};

double rf(double x) { return test::round_to_float(x); }

Shape rounded(Shape s) {
  for (auto* v : {&s.p, &s.e, &s.v1, &s.v2})
    for (double& x : *v) x = rf(x);
  for (auto& row : s.R)
    for (double& x : row) x = rf(x);
  return s;
}

/// Rotation from a (not necessarily unit) quaternion (w, x, y, z).
void set_rotation(Shape& s, double w, double x, double y, double z) {
  const double l = std::sqrt(w * w + x * x + y * y + z * z);
  w /= l, x /= l, y /= l, z /= l;
  const double m[3][3] = {{1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)},
                          {2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)},
                          {2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)}};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) s.R[i][j] = m[i][j];
}

/// s's rotation = from's turned by the small angle ang (rad) about unit axis w (each
/// column moved by ang * w x column, renormalised).
void turn_rotation(Shape& s, const Shape& from, const D3& w, double ang) {
  for (int c = 0; c < 3; ++c) {
    const D3 col = from.col(c);
    const D3 r = add(col, mul(cross(w, col), ang));
    const D3 rn = mul(r, 1.0 / norm(r));
    for (int i = 0; i < 3; ++i) s.R[i][c] = rn[i];
  }
}

/// Rotation taking local z to unit direction u (for capsules), deterministic.
void set_axis(Shape& s, const D3& u) {
  const D3 h = std::fabs(u[0]) < 0.9 ? D3{1, 0, 0} : D3{0, 1, 0};
  D3 x = cross(h, u);
  x = mul(x, 1.0 / norm(x));
  const D3 y = cross(u, x);
  for (int i = 0; i < 3; ++i) {
    s.R[i][0] = x[i];
    s.R[i][1] = y[i];
    s.R[i][2] = u[i];
  }
}

double clampd(double x, double lo, double hi) { return std::min(std::max(x, lo), hi); }

D3 closest_on_segment(const D3& a, const D3& b, const D3& x) {
  const D3 ab = sub(b, a);
  const double l2 = dot(ab, ab);
  const double t = l2 > 0 ? clampd(dot(sub(x, a), ab) / l2, 0, 1) : 0;
  return add(a, mul(ab, t));
}

/// Unsigned distance from x to triangle (a, b, c): the plane projection when it falls
/// inside (barycentric test), else the nearest edge.
double triangle_distance(const D3& a, const D3& b, const D3& c, const D3& x) {
  const D3 n = cross(sub(b, a), sub(c, a));
  const double n2 = dot(n, n);
  if (n2 > 0) {
    const D3 q = sub(x, mul(n, dot(sub(x, a), n) / n2));
    const double u = dot(cross(sub(b, q), sub(c, q)), n), v = dot(cross(sub(c, q), sub(a, q)), n),
                 w = dot(cross(sub(a, q), sub(b, q)), n);
    if (u >= 0 && v >= 0 && w >= 0) return norm(sub(x, q));
  }
  double d = norm(sub(x, closest_on_segment(a, b, x)));
  d = std::min(d, norm(sub(x, closest_on_segment(b, c, x))));
  return std::min(d, norm(sub(x, closest_on_segment(c, a, x))));
}

/// Signed distance from x to the shape's surface (triangles: unsigned, zero thickness).
double signed_distance(const Shape& s, const D3& x) {
  switch (s.kind) {
    case Kind::kSphere: return norm(sub(x, s.p)) - s.e[0];
    case Kind::kCapsule: {
      const D3 u = s.col(2);
      const D3 q = closest_on_segment(sub(s.p, mul(u, s.e[1])), add(s.p, mul(u, s.e[1])), x);
      return norm(sub(x, q)) - s.e[0];
    }
    case Kind::kBox: {
      const D3 l = s.to_local(x);
      D3 q;
      for (int i = 0; i < 3; ++i) q[i] = std::fabs(l[i]) - s.e[i];
      const D3 qo = {std::max(q[0], 0.0), std::max(q[1], 0.0), std::max(q[2], 0.0)};
      return norm(qo) + std::min(std::max({q[0], q[1], q[2]}), 0.0);
    }
    case Kind::kTriangle: return triangle_distance(s.p, s.v1, s.v2, x);
    case Kind::kHalfSpace: return dot(s.e, sub(x, s.p));
  }
  return 0;
}

/// Minimum of a convex function on [lo, hi] (golden-section search).
template <class Fn>
double convex_min(Fn f, double lo, double hi) {
  const double g = 0.5 * (std::sqrt(5.0) - 1.0);
  double a = lo, b = hi;
  double c = b - g * (b - a), d = a + g * (b - a);
  double fc = f(c), fd = f(d);
  for (int i = 0; i < 120 && b - a > 1e-15 * (std::fabs(a) + std::fabs(b) + 1e-300); ++i) {
    if (fc < fd) {
      b = d, d = c, fd = fc;
      c = b - g * (b - a), fc = f(c);
    } else {
      a = c, c = d, fc = fd;
      d = a + g * (b - a), fd = f(d);
    }
  }
  return std::min({f(lo), f(hi), fc, fd});
}

/// Box-box overlap depth by SAT over all 15 axes in double (> 0 overlap).
double box_box_sat(const Shape& a, const Shape& b) {
  std::vector<D3> axes;
  for (int i = 0; i < 3; ++i) axes.push_back(a.col(i)), axes.push_back(b.col(i));
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      const D3 c = cross(a.col(i), b.col(j));
      if (norm(c) > 1e-12) axes.push_back(mul(c, 1.0 / norm(c)));
    }
  double best = 1e300;
  const D3 t = sub(b.p, a.p);
  for (const D3& l : axes) {
    double ra = 0, rb = 0;
    for (int k = 0; k < 3; ++k) ra += a.e[k] * std::fabs(dot(a.col(k), l)), rb += b.e[k] * std::fabs(dot(b.col(k), l));
    best = std::min(best, ra + rb - std::fabs(dot(t, l)));
  }
  return best;
}

/// Box-triangle overlap depth by SAT over all 13 axes in double (> 0 overlap): box
/// faces, the triangle normal, box axes x triangle edges.
double box_triangle_sat(const Shape& a, const Shape& b) {
  const D3 v[3] = {b.p, b.v1, b.v2};
  std::vector<D3> axes;
  for (int i = 0; i < 3; ++i) axes.push_back(a.col(i));
  const D3 nt = cross(sub(v[1], v[0]), sub(v[2], v[0]));
  if (norm(nt) > 0) axes.push_back(mul(nt, 1.0 / norm(nt)));
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      const D3 f = sub(v[(j + 1) % 3], v[j]);
      const D3 c = cross(a.col(i), f);
      if (norm(c) > 1e-12 * norm(f)) axes.push_back(mul(c, 1.0 / norm(c)));
    }
  double best = 1e300;
  for (const D3& l : axes) {
    double ra = 0;
    for (int k = 0; k < 3; ++k) ra += a.e[k] * std::fabs(dot(a.col(k), l));
    const double c = dot(a.p, l);
    double lo = 1e300, hi = -1e300;
    for (const D3& x : v) lo = std::min(lo, dot(x, l) - c), hi = std::max(hi, dot(x, l) - c);
    best = std::min(best, std::min(ra - lo, hi + ra));
  }
  return best;
}

/// "Core" of a round shape: segment (a, b) and radius; spheres have a == b.
struct Core {
  D3 a, b;
  double r;
};
Core core(const Shape& s) {
  if (s.kind == Kind::kSphere) return {s.p, s.p, s.e[0]};
  const D3 u = s.col(2);
  return {sub(s.p, mul(u, s.e[1])), add(s.p, mul(u, s.e[1])), s.e[0]};
}

/// Overlap measure in double: > 0 when the solids overlap (the value is a distance-like
/// margin, exact at 0). A is never a triangle / half-space (kernel order).
double overlap(const Shape& a, const Shape& b) {
  if (a.kind == Kind::kBox && b.kind == Kind::kBox) return box_box_sat(a, b);
  if (a.kind == Kind::kBox && b.kind == Kind::kTriangle) return box_triangle_sat(a, b);
  if (a.kind == Kind::kBox && b.kind == Kind::kHalfSpace) {
    double m = 1e300;
    for (int i = 0; i < 8; ++i) {
      D3 x = a.p;
      for (int k = 0; k < 3; ++k) x = add(x, mul(a.col(k), ((i >> k) & 1 ? 1 : -1) * a.e[k]));
      m = std::min(m, dot(b.e, sub(x, b.p)));
    }
    return -m;
  }
  const Core c = core(a);
  auto at = [&](double s) { return add(c.a, mul(sub(c.b, c.a), s)); };
  if (b.kind == Kind::kSphere || b.kind == Kind::kCapsule) {
    const Core d = core(b);
    // distance between two segments: convex in s, inner closed form
    const double m = convex_min([&](double s) { return norm(sub(at(s), closest_on_segment(d.a, d.b, at(s)))); }, 0, 1);
    return c.r + d.r - m;
  }
  if (b.kind == Kind::kTriangle) {
    // segment-triangle distance: 0 when the segment crosses the triangle
    double m = convex_min([&](double s) { return triangle_distance(b.p, b.v1, b.v2, at(s)); }, 0, 1);
    const D3 n = cross(sub(b.v1, b.p), sub(b.v2, b.p));
    const double ha = dot(n, sub(c.a, b.p)), hb = dot(n, sub(c.b, b.p));
    if ((ha <= 0 && hb >= 0) || (ha >= 0 && hb <= 0)) {
      const double s = ha == hb ? 0 : ha / (ha - hb);
      m = std::min(m, triangle_distance(b.p, b.v1, b.v2, at(s)));
    }
    return c.r - m;
  }
  // box or half-space B: signed distance is convex along the segment
  const double m = convex_min([&](double s) { return signed_distance(b, at(s)); }, 0, 1);
  return c.r - m;
}

// ---------------------------------------------------------------------------------------
// Buckets
// ---------------------------------------------------------------------------------------

struct Side {
  std::vector<float> p[3], r[9], e[3], w[6];
  explicit Side(uint32_t n) {
    for (auto& v : p) v.assign(n, 0.0f);
    for (auto& v : r) v.assign(n, 0.0f);
    for (auto& v : e) v.assign(n, 0.0f);
    for (auto& v : w) v.assign(n, 0.0f);
  }
  void set(uint32_t k, const Shape& s) {
    for (int i = 0; i < 3; ++i) p[i][k] = static_cast<float>(s.p[i]), e[i][k] = static_cast<float>(s.e[i]);
    for (int i = 0; i < 9; ++i) r[i][k] = static_cast<float>(s.R[i / 3][i % 3]);
    for (int i = 0; i < 3; ++i) w[i][k] = static_cast<float>(s.v1[i]), w[3 + i][k] = static_cast<float>(s.v2[i]);
  }
  LeafSoA view() const {
    LeafSoA v{};
    for (int i = 0; i < 3; ++i) v.p[i] = p[i].data(), v.e[i] = e[i].data();
    for (int i = 0; i < 9; ++i) v.r[i] = r[i].data();
    for (int i = 0; i < 6; ++i) v.w[i] = w[i].data();
    return v;
  }
};

struct Out {
  std::vector<uint8_t> count;
  std::vector<float> n[3], depth, point[4][3], pdepth[4];
  explicit Out(uint32_t m) {
    count.assign(m, 0xee);
    for (auto& v : n) v.assign(m, -7.0f);
    depth.assign(m, -7.0f);
    for (auto& pt : point)
      for (auto& v : pt) v.assign(m, -7.0f);
    for (auto& v : pdepth) v.assign(m, -7.0f);
  }
  ManifoldSoA view() {
    ManifoldSoA v{};
    v.count = count.data();
    for (int i = 0; i < 3; ++i) v.n[i] = n[i].data();
    v.depth = depth.data();
    for (int j = 0; j < 4; ++j) {
      for (int i = 0; i < 3; ++i) v.point[j][i] = point[j][i].data();
      v.pdepth[j] = pdepth[j].data();
    }
    return v;
  }
  D3 normal(uint32_t k) const { return {n[0][k], n[1][k], n[2][k]}; }
  D3 pt(uint32_t j, uint32_t k) const { return {point[j][0][k], point[j][1][k], point[j][2][k]}; }
};

struct PairType {
  const char* name;
  Kind ka, kb;
  PairKernel fn;
  uint32_t max_points;
};

Out run(const PairType& t, const std::vector<Shape>& a, const std::vector<Shape>& b, KernelPath path,
        std::vector<uint32_t> cuts = {}) {
  const uint32_t n = static_cast<uint32_t>(a.size());
  Side sa(n), sb(n);
  for (uint32_t k = 0; k < n; ++k) sa.set(k, a[k]), sb.set(k, b[k]);
  Out out(n);
  NarrowConfig cfg;
  cfg.path = path;
  cuts.insert(cuts.begin(), 0u);
  cuts.push_back(n);
  const ManifoldSoA mv = out.view();
  for (size_t i = 0; i + 1 < cuts.size(); ++i) t.fn(sa.view(), sb.view(), mv, Range{cuts[i], cuts[i + 1]}, cfg);
  return out;
}

// ---------------------------------------------------------------------------------------
// Random shapes
// ---------------------------------------------------------------------------------------

struct Gen {
  std::mt19937_64 rng;
  explicit Gen(uint64_t seed) : rng(seed) {}
  double uni(double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(rng); }
  D3 unit() {
    std::normal_distribution<double> g;
    D3 v{g(rng), g(rng), g(rng)};
    return mul(v, 1.0 / norm(v));
  }
  /// size in [lo, hi] log-uniform
  double size(double lo, double hi) { return std::exp(uni(std::log(lo), std::log(hi))); }

  Shape shape(Kind k, double scale, const D3& at) {
    Shape s;
    s.kind = k;
    s.p = at;
    std::normal_distribution<double> g;
    switch (k) {
      case Kind::kSphere: s.e = {scale * size(0.3, 1.5), 0, 0}; break;
      case Kind::kCapsule:
        set_axis(s, unit());
        s.e = {scale * size(0.2, 1.0), scale * size(0.2, 1.5), 0};
        break;
      case Kind::kBox:
        set_rotation(s, g(rng), g(rng), g(rng), g(rng));
        s.e = {scale * size(0.2, 1.5), scale * size(0.2, 1.5), scale * size(0.2, 1.5)};
        break;
      case Kind::kTriangle: {
        const D3 c = at;
        s.p = add(c, mul(unit(), scale * size(0.5, 2.0)));
        s.v1 = add(c, mul(unit(), scale * size(0.5, 2.0)));
        s.v2 = add(c, mul(unit(), scale * size(0.5, 2.0)));
        break;
      }
      case Kind::kHalfSpace: s.e = unit(); break;
    }
    return s;
  }
};

/// Random pair: B placed around A so that about half the pairs overlap.
std::pair<Shape, Shape> random_pair(Gen& g, Kind ka, Kind kb, double scale, const D3& origin) {
  Shape a = g.shape(ka, scale, origin);
  if (kb == Kind::kHalfSpace) {
    Shape b = g.shape(kb, scale, origin);
    // plane through a point at a signed offset from A's centre along its normal
    const double off = g.uni(-2.0, 1.0) * a.bound();
    b.p = add(origin, mul(b.e, off));
    return {rounded(a), rounded(b)};
  }
  Shape b0 = g.shape(kb, scale, D3{0, 0, 0});
  const double reach = a.bound() + b0.bound();
  const D3 at = add(origin, mul(g.unit(), g.uni(0.1, 1.1) * reach));
  return {rounded(a), rounded(b0.moved(at))};
}

// ---------------------------------------------------------------------------------------
// Checks
// ---------------------------------------------------------------------------------------

struct Tol {
  double len;  // absolute length tolerance
};

Tol tolerance(const Shape& a, const Shape& b) {
  // float rounding of sizes and positions (relative to A), and of the absolute outputs
  double s = std::max(a.size(), b.size());
  if (b.kind == Kind::kHalfSpace) s = a.bound();
  const double mag = std::max({std::fabs(a.p[0]), std::fabs(a.p[1]), std::fabs(a.p[2])});
  return {2e-5 * s + 4e-7 * mag};
}

/// The contact of lane k satisfies (a) surfaces, unit n, pdepth <= depth, and (b) the
/// minimum translation. Returns a message on failure, empty on success.
std::string check_contact(const PairType& t, const Shape& a, const Shape& b, const Out& o, uint32_t k,
                          bool check_min_translation = true) {
  char buf[512];
  const Tol tol = tolerance(a, b);
  const uint32_t c = o.count[k];
  if (c < 1 || c > t.max_points) return "bad count " + std::to_string(c);
  const D3 n = o.normal(k);
  const double depth = o.depth[k];
  if (std::fabs(norm(n) - 1.0) > 1e-5) return "normal not unit";
  if (!(depth > 0)) return "depth not positive";
  for (uint32_t j = 0; j < c; ++j) {
    const double pd = o.pdepth[j][k];
    const D3 x = o.pt(j, k);
    if (!(pd > 0) || pd > depth * (1 + 1e-5) + tol.len) {
      std::snprintf(buf, sizeof buf, "point %u: pdepth %g vs depth %g", j, pd, depth);
      return buf;
    }
    const double sa = signed_distance(a, add(x, mul(n, 0.5 * pd)));
    const double sb = signed_distance(b, sub(x, mul(n, 0.5 * pd)));
    if (std::fabs(sa) > 4 * tol.len || std::fabs(sb) > 4 * tol.len) {
      std::snprintf(buf, sizeof buf, "point %u off the surfaces: sdA %g sdB %g (tol %g, pd %g)", j, sa, sb,
                    tol.len, pd);
      return buf;
    }
  }
  if (check_min_translation) {
    const double eps_plus = 2e-4 * depth + 8 * tol.len;
    const double eps_minus = 0.012 * depth + 8 * tol.len;
    const double o_plus = overlap(a, b.moved(mul(n, depth + eps_plus)));
    if (o_plus > 0) {
      std::snprintf(buf, sizeof buf, "B moved by n*(depth + eps) still overlaps by %g (depth %g)", o_plus, depth);
      return buf;
    }
    if (depth > eps_minus) {
      const double o_minus = overlap(a, b.moved(mul(n, depth - eps_minus)));
      if (!(o_minus > 0)) {
        std::snprintf(buf, sizeof buf, "B moved by n*(depth - eps) separates (%g; depth %g): not minimal", o_minus,
                      depth);
        return buf;
      }
    }
  }
  return {};
}

std::string describe(const Shape& s) {
  char buf[400];
  std::snprintf(buf, sizeof buf, "p(%.9g %.9g %.9g) e(%.9g %.9g %.9g) R[%.9g %.9g %.9g; %.9g %.9g %.9g; %.9g %.9g %.9g]",
                s.p[0], s.p[1], s.p[2], s.e[0], s.e[1], s.e[2], s.R[0][0], s.R[0][1], s.R[0][2], s.R[1][0],
                s.R[1][1], s.R[1][2], s.R[2][0], s.R[2][1], s.R[2][2]);
  return buf;
}

/// Runs the per-lane checks over a whole bucket; returns the number of contacts.
uint32_t check_bucket(const PairType& t, const std::vector<Shape>& a, const std::vector<Shape>& b, const Out& o,
                      bool check_min_translation = true) {
  uint32_t contacts = 0, failures = 0;
  for (uint32_t k = 0; k < a.size(); ++k) {
    const Tol tol = tolerance(a[k], b[k]);
    const double ov = overlap(a[k], b[k]);
    if (o.count[k] == 0) {
      if (ov > 8 * tol.len && failures++ < 5)
        ADD_FAILURE() << t.name << " lane " << k << ": overlap " << ov << " but no contact\n A " << describe(a[k])
                      << "\n B " << describe(b[k]);
      continue;
    }
    ++contacts;
    if (ov < -8 * tol.len && failures++ < 5)
      ADD_FAILURE() << t.name << " lane " << k << ": separated by " << -ov << " but contact, depth " << o.depth[k];
    const std::string msg = check_contact(t, a[k], b[k], o, k, check_min_translation);
    if (!msg.empty() && failures++ < 5)
      ADD_FAILURE() << t.name << " lane " << k << ": " << msg << "\n A " << describe(a[k]) << "\n B "
                    << describe(b[k]) << "\n n (" << o.n[0][k] << " " << o.n[1][k] << " " << o.n[2][k]
                    << ") depth " << o.depth[k] << " count " << int(o.count[k]);
  }
  return contacts;
}

void PrintTo(const PairType& t, std::ostream* os) { *os << t.name; }

const std::vector<PairType>& pair_types() {
  static const std::vector<PairType> types = {
      {"sphere-sphere", Kind::kSphere, Kind::kSphere, &collide_sphere_sphere, 1},
      {"sphere-capsule", Kind::kSphere, Kind::kCapsule, &collide_sphere_capsule, 1},
      {"sphere-box", Kind::kSphere, Kind::kBox, &collide_sphere_box, 1},
      {"sphere-triangle", Kind::kSphere, Kind::kTriangle, &collide_sphere_triangle, 1},
      {"sphere-halfspace", Kind::kSphere, Kind::kHalfSpace, &collide_sphere_halfspace, 1},
      {"capsule-capsule", Kind::kCapsule, Kind::kCapsule, &collide_capsule_capsule, 2},
      {"capsule-box", Kind::kCapsule, Kind::kBox, &collide_capsule_box, 2},
      {"capsule-triangle", Kind::kCapsule, Kind::kTriangle, &collide_capsule_triangle, 2},
      {"capsule-halfspace", Kind::kCapsule, Kind::kHalfSpace, &collide_capsule_halfspace, 2},
      {"box-box", Kind::kBox, Kind::kBox, &collide_box_box, 4},
      {"box-triangle", Kind::kBox, Kind::kTriangle, &collide_box_triangle, 4},
      {"box-halfspace", Kind::kBox, Kind::kHalfSpace, &collide_box_halfspace, 4},
  };
  return types;
}

const PairType& pair_type(const char* name) {
  for (const PairType& t : pair_types())
    if (std::string(t.name) == name) return t;
  static PairType none{"?", Kind::kSphere, Kind::kSphere, nullptr, 0};
  ADD_FAILURE() << "no pair type " << name;
  return none;
}

// ---------------------------------------------------------------------------------------
// Tests
// ---------------------------------------------------------------------------------------

class Primitives : public ::testing::TestWithParam<PairType> {};

std::string param_name(const ::testing::TestParamInfo<PairType>& info) {
  std::string s = info.param.name;
  std::replace(s.begin(), s.end(), '-', '_');
  return s;
}

TEST_P(Primitives, SimdMatchesScalar) {
  const PairType& t = GetParam();
  Gen g(0x5eed0001u + static_cast<uint64_t>(t.ka) * 31 + static_cast<uint64_t>(t.kb));
  const uint32_t n = test::scaled(4001);  // not a multiple of 8
  std::vector<Shape> a, b;
  for (uint32_t k = 0; k < n; ++k) {
    auto [sa, sb] = random_pair(g, t.ka, t.kb, 1.0, D3{g.uni(-10, 10), g.uni(-10, 10), g.uni(-10, 10)});
    a.push_back(sa), b.push_back(sb);
  }
  const Out simd = run(t, a, b, KernelPath::kSimd);
  const Out scalar = run(t, a, b, KernelPath::kScalar);
  const Out split = run(t, a, b, KernelPath::kSimd, {1, 2, 3, 13, 21, 22, 1001, n - 9, n - 1});
  uint32_t contacts = 0, mismatches = 0, loose_normals = 0, alternative = 0;
  for (uint32_t k = 0; k < n; ++k) {
    // identical bytes whatever the partition (slots the kernel writes)
    ASSERT_EQ(simd.count[k], split.count[k]) << k;
    if (simd.count[k] > 0) {
      for (int i = 0; i < 3; ++i) ASSERT_EQ(simd.n[i][k], split.n[i][k]) << k;
      ASSERT_EQ(simd.depth[k], split.depth[k]) << k;
      for (uint32_t j = 0; j < simd.count[k]; ++j) {
        for (int i = 0; i < 3; ++i) ASSERT_EQ(simd.point[j][i][k], split.point[j][i][k]) << k;
        ASSERT_EQ(simd.pdepth[j][k], split.pdepth[j][k]) << k;
      }
    }
    if (simd.count[k] != scalar.count[k]) {
      if (mismatches++ < 5) ADD_FAILURE() << t.name << " lane " << k << ": count simd " << int(simd.count[k])
                                          << " scalar " << int(scalar.count[k]);
      continue;
    }
    if (simd.count[k] == 0) continue;
    ++contacts;
    const double tol = 1e-5 * std::max(a[k].size(), b[k].size()) + 1e-6;
    bool ok = std::fabs(simd.depth[k] - scalar.depth[k]) <= tol;
    // The paths may fuse multiply-adds differently; a normal from nearly touching cores
    // (closest points ~1e-3 apart) is ill-conditioned, so normals get 1e-5 on most lanes
    // and 1e-3 on a few (counted below); points built along the normal move with it
    // (by up to the shapes' size times the normal's difference).
    double ndiff = 0;
    for (int i = 0; i < 3; ++i) ndiff = std::max(ndiff, std::fabs(double(simd.n[i][k]) - scalar.n[i][k]));
    if (ndiff > 1e-5) ++loose_normals;
    ok = ok && ndiff <= 1e-3;
    for (uint32_t j = 0; j < simd.count[k]; ++j) {
      ok = ok && std::fabs(simd.pdepth[j][k] - scalar.pdepth[j][k]) <= tol;
      for (int i = 0; i < 3; ++i)
        ok = ok && std::fabs(simd.point[j][i][k] - scalar.point[j][i][k]) <=
                       tol + 1e-6 * std::fabs(a[k].p[i]) + std::max(a[k].size(), b[k].size()) * ndiff;
    }
    if (!ok && simd.count[k] > 1 && check_contact(t, a[k], b[k], simd, k, false).empty() &&
        check_contact(t, a[k], b[k], scalar, k, false).empty() &&
        std::fabs(simd.depth[k] - scalar.depth[k]) <= tol) {
      // Manifold reduction: candidates of (nearly) equal area or depth may be chosen
      // differently under different rounding; both choices must be valid manifolds.
      ++alternative;
      continue;
    }
    if (!ok && mismatches++ < 5) {
      ADD_FAILURE() << t.name << " lane " << k << ": simd and scalar data differ: depth " << simd.depth[k] << " / "
                    << scalar.depth[k] << ", n (" << simd.n[0][k] << " " << simd.n[1][k] << " " << simd.n[2][k]
                    << ") / (" << scalar.n[0][k] << " " << scalar.n[1][k] << " " << scalar.n[2][k] << "), count "
                    << int(simd.count[k]) << "\n A " << describe(a[k]) << "\n B " << describe(b[k]);
      for (uint32_t j = 0; j < simd.count[k]; ++j)
        ADD_FAILURE() << " point " << j << " (" << simd.point[j][0][k] << " " << simd.point[j][1][k] << " "
                      << simd.point[j][2][k] << ") / (" << scalar.point[j][0][k] << " " << scalar.point[j][1][k]
                      << " " << scalar.point[j][2][k] << ") pd " << simd.pdepth[j][k] << " / " << scalar.pdepth[j][k];
    }
  }
  EXPECT_GT(contacts, n / 10);
  EXPECT_LT(contacts, n - n / 10);
  EXPECT_LE(loose_normals, n / 200) << "normals differing by more than 1e-5";
  EXPECT_LE(alternative, n / 50) << "manifolds reduced to different (valid) points";
}

TEST_P(Primitives, RandomPosesAgainstDoubleReference) {
  const PairType& t = GetParam();
  Gen g(0x5eed0002u + static_cast<uint64_t>(t.ka) * 31 + static_cast<uint64_t>(t.kb));
  const uint32_t n = test::scaled(2003);
  for (KernelPath path : {KernelPath::kSimd, KernelPath::kScalar}) {
    std::vector<Shape> a, b;
    for (uint32_t k = 0; k < n; ++k) {
      auto [sa, sb] = random_pair(g, t.ka, t.kb, 1.0, D3{g.uni(-10, 10), g.uni(-10, 10), g.uni(-10, 10)});
      a.push_back(sa), b.push_back(sb);
    }
    const Out o = run(t, a, b, path);
    const uint32_t contacts = check_bucket(t, a, b, o);
    EXPECT_GT(contacts, n / 5);
  }
}

TEST_P(Primitives, ExtremeScalesAndPoses) {
  const PairType& t = GetParam();
  Gen g(0x5eed0003u + static_cast<uint64_t>(t.ka) * 31 + static_cast<uint64_t>(t.kb));
  const uint32_t n = test::scaled(301);
  struct Case {
    double scale;
    double far;
  };
  for (const Case c : {Case{1e-4, 0}, Case{1e4, 0}, Case{1.0, 1e5}, Case{1e-2, 1e3}, Case{1e4, 1e5}}) {
    std::vector<Shape> a, b;
    for (uint32_t k = 0; k < n; ++k) {
      const D3 at = add(mul(g.unit(), c.far), D3{g.uni(-10, 10) * c.scale, 0, 0});
      auto [sa, sb] = random_pair(g, t.ka, t.kb, c.scale, at);
      a.push_back(sa), b.push_back(sb);
    }
    SCOPED_TRACE("scale " + std::to_string(c.scale) + " far " + std::to_string(c.far));
    for (KernelPath path : {KernelPath::kSimd, KernelPath::kScalar}) check_bucket(t, a, b, run(t, a, b, path));
  }
}

INSTANTIATE_TEST_SUITE_P(Kernels, Primitives, ::testing::ValuesIn(pair_types()), param_name);

// ---------------------------------------------------------------------------------------
// Analytic cases
// ---------------------------------------------------------------------------------------

Shape sphere(D3 p, double r) {
  Shape s;
  s.kind = Kind::kSphere;
  s.p = p;
  s.e = {r, 0, 0};
  return rounded(s);
}
Shape capsule(D3 p, D3 u, double r, double h) {
  Shape s;
  s.kind = Kind::kCapsule;
  s.p = p;
  set_axis(s, mul(u, 1.0 / norm(u)));
  s.e = {r, h, 0};
  return rounded(s);
}
Shape box(D3 p, D3 e) {
  Shape s;
  s.kind = Kind::kBox;
  s.p = p;
  s.e = e;
  return rounded(s);
}
Shape triangle(D3 a, D3 b, D3 c) {
  Shape s;
  s.kind = Kind::kTriangle;
  s.p = a, s.v1 = b, s.v2 = c;
  return rounded(s);
}
Shape halfspace(D3 p, D3 n) {
  Shape s;
  s.kind = Kind::kHalfSpace;
  s.p = p;
  s.e = mul(n, 1.0 / norm(n));
  return rounded(s);
}

/// Runs one pair through both paths; expects them to agree exactly on count.
Out run_one(const char* type, const Shape& a, const Shape& b, KernelPath path = KernelPath::kSimd) {
  return run(pair_type(type), {a}, {b}, path);
}

void expect_near3(const D3& got, const D3& want, double tol, const char* what) {
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(got[i], want[i], tol) << what << " [" << i << "]";
}

TEST(PrimitivesAnalytic, SphereSphere) {
  for (KernelPath path : {KernelPath::kSimd, KernelPath::kScalar}) {
    Out o = run_one("sphere-sphere", sphere({1, 2, 3}, 1.0), sphere({2.5, 2, 3}, 1.0), path);
    ASSERT_EQ(o.count[0], 1);
    expect_near3(o.normal(0), {1, 0, 0}, 1e-7, "n");
    EXPECT_NEAR(o.depth[0], 0.5, 1e-6);
    expect_near3(o.pt(0, 0), {1.75, 2, 3}, 1e-6, "point");
    // touching exactly: no contact
    o = run_one("sphere-sphere", sphere({0, 0, 0}, 1.0), sphere({2, 0, 0}, 1.0), path);
    EXPECT_EQ(o.count[0], 0);
    // coincident centres: finite unit normal, depth = sum of radii
    o = run_one("sphere-sphere", sphere({5, 5, 5}, 1.0), sphere({5, 5, 5}, 0.5), path);
    ASSERT_EQ(o.count[0], 1);
    EXPECT_NEAR(norm(o.normal(0)), 1.0, 1e-6);
    EXPECT_NEAR(o.depth[0], 1.5, 1e-6);
  }
}

TEST(PrimitivesAnalytic, SphereCapsule) {
  for (KernelPath path : {KernelPath::kSimd, KernelPath::kScalar}) {
    // sphere beside the capsule's middle
    Out o = run_one("sphere-capsule", sphere({0, 0, 0}, 1.0), capsule({1.5, 0, 0}, {0, 0, 1}, 1.0, 2.0), path);
    ASSERT_EQ(o.count[0], 1);
    expect_near3(o.normal(0), {1, 0, 0}, 1e-6, "n");
    EXPECT_NEAR(o.depth[0], 0.5, 1e-6);
    // sphere centre on the axis: n perpendicular to the axis, depth = sum of radii
    o = run_one("sphere-capsule", sphere({0, 0, 1}, 0.5), capsule({0, 0, 0}, {0, 0, 1}, 1.0, 2.0), path);
    ASSERT_EQ(o.count[0], 1);
    EXPECT_NEAR(norm(o.normal(0)), 1.0, 1e-6);
    EXPECT_NEAR(o.normal(0)[2], 0.0, 1e-6);
    EXPECT_NEAR(o.depth[0], 1.5, 1e-6);
    // beyond the cap, touching exactly
    o = run_one("sphere-capsule", sphere({0, 0, 4}, 1.0), capsule({0, 0, 0}, {0, 0, 1}, 1.0, 2.0), path);
    EXPECT_EQ(o.count[0], 0);
  }
}

TEST(PrimitivesAnalytic, SphereBox) {
  for (KernelPath path : {KernelPath::kSimd, KernelPath::kScalar}) {
    // sphere above the top face
    Out o = run_one("sphere-box", sphere({0.2, 0.1, 1.5}, 0.75), box({0, 0, 0}, {1, 2, 1}), path);
    ASSERT_EQ(o.count[0], 1);
    expect_near3(o.normal(0), {0, 0, -1}, 1e-6, "n");
    EXPECT_NEAR(o.depth[0], 0.25, 1e-6);
    expect_near3(o.pt(0, 0), {0.2, 0.1, 0.875}, 1e-6, "point");
    // sphere centre inside the box, nearest face +y (0.3 away): n = -y, depth = r + 0.3
    o = run_one("sphere-box", sphere({0.1, 1.7, -0.2}, 0.5), box({0, 0, 0}, {1, 2, 1}), path);
    ASSERT_EQ(o.count[0], 1);
    expect_near3(o.normal(0), {0, -1, 0}, 1e-6, "n");
    EXPECT_NEAR(o.depth[0], 0.8, 1e-6);
    // coincident centres, cube: a finite unit face normal, depth = r + half extent
    o = run_one("sphere-box", sphere({3, 3, 3}, 0.5), box({3, 3, 3}, {1, 1, 1}), path);
    ASSERT_EQ(o.count[0], 1);
    EXPECT_NEAR(norm(o.normal(0)), 1.0, 1e-6);
    EXPECT_NEAR(o.depth[0], 1.5, 1e-6);
    // corner region, touching exactly: no contact
    o = run_one("sphere-box", sphere({2, 0, 0}, 1.0), box({0, 0, 0}, {1, 1, 1}), path);
    EXPECT_EQ(o.count[0], 0);
  }
}

TEST(PrimitivesAnalytic, SphereTriangleAndHalfSpace) {
  for (KernelPath path : {KernelPath::kSimd, KernelPath::kScalar}) {
    const Shape tri = triangle({-1, -1, 0}, {2, -1, 0}, {-1, 2, 0});
    // above the face: n = -z (from the sphere down to the triangle)
    Out o = run_one("sphere-triangle", sphere({0, 0, 0.5}, 1.0), tri, path);
    ASSERT_EQ(o.count[0], 1);
    expect_near3(o.normal(0), {0, 0, -1}, 1e-6, "n");
    EXPECT_NEAR(o.depth[0], 0.5, 1e-6);
    // below the face (two-sided): n = +z
    o = run_one("sphere-triangle", sphere({0, 0, -0.5}, 1.0), tri, path);
    ASSERT_EQ(o.count[0], 1);
    expect_near3(o.normal(0), {0, 0, 1}, 1e-6, "n");
    // centre in the triangle: depth = r, n = +-z
    o = run_one("sphere-triangle", sphere({0, 0, 0}, 1.0), tri, path);
    ASSERT_EQ(o.count[0], 1);
    EXPECT_NEAR(std::fabs(o.normal(0)[2]), 1.0, 1e-6);
    EXPECT_NEAR(o.depth[0], 1.0, 1e-6);
    // beside vertex (-1,-1,0)
    o = run_one("sphere-triangle", sphere({-1.6, -1.8, 0}, 1.5), tri, path);
    ASSERT_EQ(o.count[0], 1);
    expect_near3(o.normal(0), {0.6, 0.8, 0}, 1e-6, "n");
    EXPECT_NEAR(o.depth[0], 0.5, 1e-6);

    o = run_one("sphere-halfspace", sphere({0, 0, 0.25}, 1.0), halfspace({7, -3, 0}, {0, 0, 1}), path);
    ASSERT_EQ(o.count[0], 1);
    expect_near3(o.normal(0), {0, 0, -1}, 1e-7, "n");
    EXPECT_NEAR(o.depth[0], 0.75, 1e-6);
    expect_near3(o.pt(0, 0), {0, 0, -0.375}, 1e-6, "point");
    o = run_one("sphere-halfspace", sphere({0, 0, 1}, 1.0), halfspace({7, -3, 0}, {0, 0, 1}), path);
    EXPECT_EQ(o.count[0], 0);
  }
}

TEST(PrimitivesAnalytic, CapsuleCapsule) {
  for (KernelPath path : {KernelPath::kSimd, KernelPath::kScalar}) {
    // parallel, one lying on the other: 2 points at the overlap ends
    Out o = run_one("capsule-capsule", capsule({0, 0, 0}, {1, 0, 0}, 0.5, 2.0),
                    capsule({1, 0.9, 0}, {1, 0, 0}, 0.5, 2.0), path);
    ASSERT_EQ(o.count[0], 2);
    expect_near3(o.normal(0), {0, 1, 0}, 1e-6, "n");
    EXPECT_NEAR(o.depth[0], 0.1, 1e-6);
    expect_near3(o.pt(0, 0), {-1, 0.45, 0}, 1e-6, "p0");
    expect_near3(o.pt(1, 0), {2, 0.45, 0}, 1e-6, "p1");
    EXPECT_NEAR(o.pdepth[0][0], 0.1, 1e-6);
    EXPECT_NEAR(o.pdepth[1][0], 0.1, 1e-6);
    // near-parallel (1e-7 rad): still 2 points
    o = run_one("capsule-capsule", capsule({0, 0, 0}, {1, 0, 0}, 0.5, 2.0),
                capsule({1, 0.9, 0}, {1, 1e-7, 0}, 0.5, 2.0), path);
    ASSERT_EQ(o.count[0], 2);
    EXPECT_NEAR(o.depth[0], 0.1, 1e-5);
    // crossed at 90 degrees: one point
    o = run_one("capsule-capsule", capsule({0, 0, 0}, {1, 0, 0}, 0.5, 2.0),
                capsule({0, 0, 0.8}, {0, 1, 0}, 0.5, 2.0), path);
    ASSERT_EQ(o.count[0], 1);
    expect_near3(o.normal(0), {0, 0, 1}, 1e-6, "n");
    EXPECT_NEAR(o.depth[0], 0.2, 1e-6);
    expect_near3(o.pt(0, 0), {0, 0, 0.4}, 1e-6, "point");
    // axes meeting: n = +-(ua x ub), depth = sum of radii
    o = run_one("capsule-capsule", capsule({0, 0, 0}, {1, 0, 0}, 0.5, 2.0),
                capsule({0.5, 0, 0}, {0, 1, 0}, 0.25, 2.0), path);
    ASSERT_EQ(o.count[0], 1);
    EXPECT_NEAR(std::fabs(o.normal(0)[2]), 1.0, 1e-6);
    EXPECT_NEAR(o.depth[0], 0.75, 1e-6);
    // coaxial, coincident: finite unit normal perpendicular to the axis
    o = run_one("capsule-capsule", capsule({0, 0, 0}, {0, 0, 1}, 0.5, 2.0),
                capsule({0, 0, 0}, {0, 0, 1}, 0.5, 1.0), path);
    ASSERT_GE(o.count[0], 1);
    EXPECT_NEAR(norm(o.normal(0)), 1.0, 1e-6);
    EXPECT_NEAR(o.normal(0)[2], 0.0, 1e-6);
    EXPECT_NEAR(o.depth[0], 1.0, 1e-6);
    // touching exactly, end to end
    o = run_one("capsule-capsule", capsule({0, 0, 0}, {0, 0, 1}, 0.5, 2.0),
                capsule({0, 0, 5}, {0, 0, 1}, 0.5, 2.0), path);
    EXPECT_EQ(o.count[0], 0);
  }
}

TEST(PrimitivesAnalytic, CapsuleBox) {
  for (KernelPath path : {KernelPath::kSimd, KernelPath::kScalar}) {
    const Shape bx = box({0, 0, 0}, {2, 2, 1});
    // lying on the top face: 2 points
    Out o = run_one("capsule-box", capsule({0.5, 0, 1.4}, {1, 0, 0}, 0.5, 1.0), bx, path);
    ASSERT_EQ(o.count[0], 2);
    expect_near3(o.normal(0), {0, 0, -1}, 1e-6, "n");
    EXPECT_NEAR(o.depth[0], 0.1, 1e-6);
    expect_near3(o.pt(0, 0), {-0.5, 0, 0.95}, 1e-6, "p0");
    expect_near3(o.pt(1, 0), {1.5, 0, 0.95}, 1e-6, "p1");
    // hanging over the edge: clipped to the face, x in [1, 2]
    o = run_one("capsule-box", capsule({2, 0, 1.4}, {1, 0, 0}, 0.5, 1.0), bx, path);
    ASSERT_EQ(o.count[0], 2);
    expect_near3(o.pt(0, 0), {1, 0, 0.95}, 1e-6, "p0");
    expect_near3(o.pt(1, 0), {2, 0, 0.95}, 1e-6, "p1");
    // tilted: one point at the low end
    o = run_one("capsule-box", capsule({0, 0, 1.8}, {1, 0, 1}, 0.5, 1.0), bx, path);
    ASSERT_EQ(o.count[0], 1);
    expect_near3(o.normal(0), {0, 0, -1}, 1e-6, "n");
    EXPECT_NEAR(o.depth[0], 0.5 - (1.8 - std::sqrt(0.5) - 1.0), 1e-6);
    // core through the box centre along z: least penetration through a side (x first)
    o = run_one("capsule-box", capsule({0, 0, 0}, {0, 0, 1}, 0.5, 0.5), box({0, 0, 0}, {1, 1, 1}), path);
    ASSERT_GE(o.count[0], 1);
    EXPECT_NEAR(o.depth[0], 1.5, 1e-6);
    EXPECT_NEAR(std::fabs(o.normal(0)[0]) + std::fabs(o.normal(0)[1]), 1.0, 1e-6);
    // touching exactly
    o = run_one("capsule-box", capsule({0, 0, 1.5}, {1, 0, 0}, 0.5, 1.0), bx, path);
    EXPECT_EQ(o.count[0], 0);
  }
}

TEST(PrimitivesAnalytic, CapsuleTriangleAndHalfSpace) {
  for (KernelPath path : {KernelPath::kSimd, KernelPath::kScalar}) {
    const Shape tri = triangle({-5, -5, 0}, {5, -5, 0}, {-5, 5, 0});
    // lying flat on the face: 2 points
    Out o = run_one("capsule-triangle", capsule({-1, -1, 0.4}, {1, 0, 0}, 0.5, 1.0), tri, path);
    ASSERT_EQ(o.count[0], 2);
    expect_near3(o.normal(0), {0, 0, -1}, 1e-6, "n");
    EXPECT_NEAR(o.depth[0], 0.1, 1e-6);
    expect_near3(o.pt(0, 0), {-2, -1, -0.05}, 1e-6, "p0");
    expect_near3(o.pt(1, 0), {0, -1, -0.05}, 1e-6, "p1");
    // under the face (two-sided)
    o = run_one("capsule-triangle", capsule({-1, -1, -0.4}, {1, 0, 0}, 0.5, 1.0), tri, path);
    ASSERT_EQ(o.count[0], 2);
    expect_near3(o.normal(0), {0, 0, 1}, 1e-6, "n");
    // standing through the face: separated along the face normal by the shorter side
    o = run_one("capsule-triangle", capsule({-1, -1, 0.3}, {0, 0, 1}, 0.25, 1.0), tri, path);
    ASSERT_GE(o.count[0], 1);
    expect_near3(o.normal(0), {0, 0, -1}, 1e-6, "n");
    EXPECT_NEAR(o.depth[0], 0.7 + 0.25, 1e-6);

    const Shape ground = halfspace({3, 1, -1}, {0, 0, 1});
    o = run_one("capsule-halfspace", capsule({0, 0, -0.75}, {1, 0, 0}, 0.5, 1.0), ground, path);
    ASSERT_EQ(o.count[0], 2);
    expect_near3(o.normal(0), {0, 0, -1}, 1e-6, "n");
    EXPECT_NEAR(o.depth[0], 0.25, 1e-6);
    expect_near3(o.pt(0, 0), {-1, 0, -1.125}, 1e-6, "p0");
    expect_near3(o.pt(1, 0), {1, 0, -1.125}, 1e-6, "p1");
    o = run_one("capsule-halfspace", capsule({0, 0, 0}, {1, 0, 1}, 0.5, 1.0), ground, path);
    ASSERT_EQ(o.count[0], 1);
    EXPECT_NEAR(o.depth[0], 0.5 - (1.0 - std::sqrt(0.5)), 1e-6);
    o = run_one("capsule-halfspace", capsule({0, 0, -0.5}, {1, 0, 0}, 0.5, 1.0), ground, path);
    EXPECT_EQ(o.count[0], 0);
  }
}

Shape rotated(Shape s, D3 axis, double angle) {
  const D3 u = mul(axis, 1.0 / norm(axis));
  set_rotation(s, std::cos(angle / 2), u[0] * std::sin(angle / 2), u[1] * std::sin(angle / 2),
               u[2] * std::sin(angle / 2));
  return rounded(s);
}

/// Sorted copy of a manifold's points (for order-free comparisons).
std::vector<D3> points_of(const Out& o, uint32_t k = 0) {
  std::vector<D3> v;
  for (uint32_t j = 0; j < o.count[k]; ++j) v.push_back(o.pt(j, k));
  std::sort(v.begin(), v.end());
  return v;
}

TEST(PrimitivesAnalytic, BoxBoxFaceToFace) {
  for (KernelPath path : {KernelPath::kSimd, KernelPath::kScalar}) {
    // equal cubes stacked: the 4 shared corners
    Out o = run_one("box-box", box({0, 0, 0}, {1, 1, 1}), box({0, 0, 1.9}, {1, 1, 1}), path);
    ASSERT_EQ(o.count[0], 4);
    expect_near3(o.normal(0), {0, 0, 1}, 1e-6, "n");
    EXPECT_NEAR(o.depth[0], 0.1, 1e-6);
    std::vector<D3> pts = points_of(o);
    const std::vector<D3> want = {{-1, -1, 0.95}, {-1, 1, 0.95}, {1, -1, 0.95}, {1, 1, 0.95}};
    for (int i = 0; i < 4; ++i) expect_near3(pts[i], want[i], 1e-6, "corner");
    for (int j = 0; j < 4; ++j) EXPECT_NEAR(o.pdepth[j][0], 0.1, 1e-6);
    // smaller box on top, off centre: its 4 bottom corners
    o = run_one("box-box", box({0, 0, 0}, {1, 1, 1}), box({0.2, 0.1, 1.4}, {0.5, 0.5, 0.5}), path);
    ASSERT_EQ(o.count[0], 4);
    expect_near3(o.normal(0), {0, 0, 1}, 1e-6, "n");
    EXPECT_NEAR(o.depth[0], 0.1, 1e-6);
    pts = points_of(o);
    const std::vector<D3> want2 = {{-0.3, -0.4, 0.95}, {-0.3, 0.6, 0.95}, {0.7, -0.4, 0.95}, {0.7, 0.6, 0.95}};
    for (int i = 0; i < 4; ++i) expect_near3(pts[i], want2[i], 1e-6, "corner");
    // B below A: n = -z; larger box below (reference face on B)
    o = run_one("box-box", box({0, 0, 0}, {0.5, 0.5, 0.5}), box({0, 0, -2.45}, {3, 3, 2}), path);
    ASSERT_EQ(o.count[0], 4);
    expect_near3(o.normal(0), {0, 0, -1}, 1e-6, "n");
    EXPECT_NEAR(o.depth[0], 0.05, 1e-6);
    for (const D3& p : points_of(o)) EXPECT_NEAR(p[2], -0.475, 1e-6);
    // rotated 45 degrees about z: an octagon, reduced to 4 points at the right depth
    o = run_one("box-box", box({0, 0, 0}, {1, 1, 1}), rotated(box({0, 0, 1.9}, {1, 1, 1}), {0, 0, 1}, M_PI / 4), path);
    ASSERT_EQ(o.count[0], 4);
    expect_near3(o.normal(0), {0, 0, 1}, 1e-6, "n");
    EXPECT_NEAR(o.depth[0], 0.1, 1e-6);
    for (const D3& p : points_of(o)) EXPECT_NEAR(p[2], 0.95, 1e-6);
    // near-parallel (1e-7 rad): the face contact survives
    o = run_one("box-box", box({0, 0, 0}, {1, 1, 1}), rotated(box({0, 0, 1.9}, {1, 1, 1}), {0, 0, 1}, 1e-7), path);
    ASSERT_EQ(o.count[0], 4);
    expect_near3(o.normal(0), {0, 0, 1}, 1e-6, "n");
    EXPECT_NEAR(o.depth[0], 0.1, 1e-6);
    // touching exactly
    o = run_one("box-box", box({0, 0, 0}, {1, 1, 1}), box({0.5, 0, 2}, {1, 1, 1}), path);
    EXPECT_EQ(o.count[0], 0);
  }
}

TEST(PrimitivesAnalytic, BoxBoxEdgeEdge) {
  for (KernelPath path : {KernelPath::kSimd, KernelPath::kScalar}) {
    // A's top edge along x (rotated 45 deg about x), B's bottom edge along y (45 deg
    // about y), crossing at 90 degrees with 0.1 overlap along z
    const double r2 = std::sqrt(2.0);
    const Shape a = rotated(box({0, 0, 0}, {1, 1, 1}), {1, 0, 0}, M_PI / 4);
    const Shape b = rotated(box({0, 0, 2 * r2 - 0.1}, {1, 1, 1}), {0, 1, 0}, M_PI / 4);
    Out o = run_one("box-box", a, b, path);
    ASSERT_EQ(o.count[0], 1);
    expect_near3(o.normal(0), {0, 0, 1}, 1e-6, "n");
    EXPECT_NEAR(o.depth[0], 0.1, 1e-5);
    expect_near3(o.pt(0, 0), {0, 0, r2 - 0.05}, 1e-5, "point");
    // both edges along x, 1e-7 rad apart (cross product ~1e-7, skipped): a 2-D
    // vertex-on-vertex contact of two diamonds, separated fastest along a face normal
    // at 45 degrees by 0.1 / sqrt(2)
    const Shape b2 = rotated(box({0, 0, 2 * r2 - 0.1}, {1, 1, 1}), {1, 1e-7, 0}, M_PI / 4);
    o = run_one("box-box", a, b2, path);
    ASSERT_GE(o.count[0], 1);
    EXPECT_NEAR(o.depth[0], 0.1 / r2, 1e-5);
    EXPECT_NEAR(o.normal(0)[2], 1.0 / r2, 1e-5);
    EXPECT_NEAR(std::fabs(o.normal(0)[1]), 1.0 / r2, 1e-5);
    EXPECT_EQ(check_contact(pair_type("box-box"), a, b2, o, 0), "");
  }
}

TEST(PrimitivesAnalytic, BoxHalfSpace) {
  for (KernelPath path : {KernelPath::kSimd, KernelPath::kScalar}) {
    const Shape ground = halfspace({5, 5, 0}, {0, 0, 1});
    Out o = run_one("box-halfspace", box({0, 0, 0.9}, {2, 1, 1}), ground, path);
    ASSERT_EQ(o.count[0], 4);
    expect_near3(o.normal(0), {0, 0, -1}, 1e-6, "n");
    EXPECT_NEAR(o.depth[0], 0.1, 1e-6);
    std::vector<D3> pts = points_of(o);
    const std::vector<D3> want = {{-2, -1, -0.05}, {-2, 1, -0.05}, {2, -1, -0.05}, {2, 1, -0.05}};
    for (int i = 0; i < 4; ++i) expect_near3(pts[i], want[i], 1e-6, "corner");
    // resting on an edge: 2 points
    o = run_one("box-halfspace", rotated(box({0, 0, std::sqrt(2.0) - 0.1}, {1, 1, 1}), {1, 0, 0}, M_PI / 4), ground,
                path);
    ASSERT_EQ(o.count[0], 2);
    EXPECT_NEAR(o.depth[0], 0.1, 1e-6);
    // deep (all 8 below): 4 points, the deepest first
    o = run_one("box-halfspace", rotated(box({0, 0, -5}, {1, 1, 1}), {1, 1, 0}, 0.3), ground, path);
    ASSERT_EQ(o.count[0], 4);
    EXPECT_NEAR(o.pdepth[0][0], o.depth[0], 0);
    // touching
    o = run_one("box-halfspace", box({0, 0, 1}, {2, 1, 1}), ground, path);
    EXPECT_EQ(o.count[0], 0);
  }
}

TEST(PrimitivesAnalytic, BoxTriangle) {
  const PairType& t = pair_type("box-triangle");
  for (KernelPath path : {KernelPath::kSimd, KernelPath::kScalar}) {
    // a box resting on a big triangle (below it): the 4 bottom corners, n = -z
    const Shape big = triangle({-10, -10, 0}, {10, -10, 0}, {0, 10, 0});
    Out o = run_one("box-triangle", box({0.5, -1, 0.9}, {2, 1, 1}), big, path);
    ASSERT_EQ(o.count[0], 4);
    expect_near3(o.normal(0), {0, 0, -1}, 1e-6, "n");
    EXPECT_NEAR(o.depth[0], 0.1, 1e-6);
    std::vector<D3> pts = points_of(o);
    const std::vector<D3> want = {{-1.5, -2, -0.05}, {-1.5, 0, -0.05}, {2.5, -2, -0.05}, {2.5, 0, -0.05}};
    for (int i = 0; i < 4; ++i) expect_near3(pts[i], want[i], 1e-6, "corner");
    for (int j = 0; j < 4; ++j) EXPECT_NEAR(o.pdepth[j][0], 0.1, 1e-6);
    // the same triangle above the box (two-sided): n = +z
    o = run_one("box-triangle", box({0.5, -1, -0.9}, {2, 1, 1}), big, path);
    ASSERT_EQ(o.count[0], 4);
    expect_near3(o.normal(0), {0, 0, 1}, 1e-6, "n");
    EXPECT_NEAR(o.depth[0], 0.1, 1e-6);
    for (const D3& p : points_of(o)) EXPECT_NEAR(p[2], 0.05, 1e-6);
    // tilted triangle under a tilted box, still resting flat: 4 points of equal depth
    {
      const Shape tr = rotated(box({0, 0, 0}, {1, 1, 1}), {0.3, 1, 0.2}, 0.4);
      const D3 c0 = tr.col(0), c1 = tr.col(1);
      const Shape bx = rotated(box(mul(tr.col(2), 0.9), {1, 0.5, 1}), {0.3, 1, 0.2}, 0.4);
      const Shape tri = triangle(add(mul(c0, -10), mul(c1, -10)), add(mul(c0, 10), mul(c1, -10)), mul(c1, 10));
      o = run_one("box-triangle", bx, tri, path);
      ASSERT_EQ(o.count[0], 4);
      EXPECT_EQ(check_contact(t, bx, tri, o, 0), "");
      EXPECT_NEAR(o.depth[0], 0.1, 1e-5);
      for (int j = 0; j < 4; ++j) EXPECT_NEAR(o.pdepth[j][0], 0.1, 1e-5);
    }
    // a box corner into the triangle's face: the box rotated so its corner points down
    // (-z); the corner at depth 0.1 below the plane z = 0, one point, n = -z
    {
      const double h = std::sqrt(3.0);  // half diagonal of the unit-half-extent cube
      Shape bx = box({0.2, 0.1, h - 0.1}, {1, 1, 1});
      // rotate the diagonal (1,1,1)/sqrt3 onto +z: axis (1,-1,0), angle acos(1/sqrt3)
      bx = rotated(bx, {1, -1, 0}, std::acos(1.0 / h));
      o = run_one("box-triangle", bx, big, path);
      ASSERT_EQ(o.count[0], 1);
      expect_near3(o.normal(0), {0, 0, -1}, 1e-6, "n");
      EXPECT_NEAR(o.depth[0], 0.1, 1e-5);
      expect_near3(o.pt(0, 0), {0.2, 0.1, -0.05}, 1e-5, "corner point");
      EXPECT_EQ(check_contact(t, bx, big, o, 0), "");
    }
    // a triangle vertex poking into a box face: vertex (0, 0, 0.9) under the face
    // z = 1 of a box at the origin; the triangle leans away, n = +z, one point
    {
      const Shape tri = triangle({0, 0, 0.9}, {-3, -2, 5}, {3, -2, 5});
      o = run_one("box-triangle", box({0, 0, 0}, {1, 1, 1}), tri, path);
      ASSERT_EQ(o.count[0], 1);
      expect_near3(o.normal(0), {0, 0, 1}, 1e-6, "n");
      EXPECT_NEAR(o.depth[0], 0.1, 1e-6);
      expect_near3(o.pt(0, 0), {0, 0, 0.95}, 1e-6, "vertex point");
    }
    // edge-edge: the box's top edge along x (rotated 45 deg about x, at z = sqrt2)
    // against the triangle's edge (0, 3, z) -> (-1, -3, z) at z = sqrt2 - 0.1, the
    // triangle rising from it: the crossing edges separate fastest, along +z by 0.1
    {
      const double r2 = std::sqrt(2.0);
      const Shape bx = rotated(box({0, 0, 0}, {1, 1, 1}), {1, 0, 0}, M_PI / 4);
      const double z = r2 - 0.1;
      const Shape tri = triangle({-1, -3, z}, {1, -3, z + 2}, {0, 3, z});
      o = run_one("box-triangle", bx, tri, path);
      ASSERT_EQ(o.count[0], 1);
      expect_near3(o.normal(0), {0, 0, 1}, 1e-6, "n");
      EXPECT_NEAR(o.depth[0], 0.1, 1e-6);
      EXPECT_NEAR(o.depth[0], box_triangle_sat(bx, tri), 1e-6);
      expect_near3(o.pt(0, 0), {-0.5, 0, r2 - 0.05}, 1e-6, "crossing point");
      EXPECT_EQ(check_contact(t, bx, tri, o, 0), "");
    }
    // touching exactly (the box's top face on the triangle's plane): no contact
    o = run_one("box-triangle", box({0, 0, -1}, {1, 1, 1}), big, path);
    EXPECT_EQ(o.count[0], 0);
    // separated along an edge axis only
    o = run_one("box-triangle", box({0, 0, 0}, {1, 1, 1}), triangle({2.1, 0, 5}, {2.1, 0, -5}, {7, 0, 0}), path);
    EXPECT_EQ(o.count[0], 0);
  }
}

TEST(PrimitivesExtremes, NeedleAndPancakeBoxes) {
  // aspect 1e4 boxes in random poses against each other and against unit boxes
  const PairType& t = pair_type("box-box");
  Gen g(0x5eed0004u);
  const uint32_t n = test::scaled(1001);
  std::vector<Shape> a, b;
  for (uint32_t k = 0; k < n; ++k) {
    std::normal_distribution<double> nd;
    auto make = [&](int kind) {
      Shape s;
      s.kind = Kind::kBox;
      set_rotation(s, nd(g.rng), nd(g.rng), nd(g.rng), nd(g.rng));
      if (kind == 0) s.e = {100.0, 0.01, 0.01};       // needle
      else if (kind == 1) s.e = {100.0, 100.0, 0.01};  // pancake
      else s.e = {1.0, 1.0, 1.0};
      return s;
    };
    Shape sa = make(static_cast<int>(k % 3)), sb = make(static_cast<int>((k / 3) % 3));
    sa.p = {g.uni(-1, 1), g.uni(-1, 1), g.uni(-1, 1)};
    sb.p = add(sa.p, mul(g.unit(), g.uni(0, 1.5)));
    // near-parallel variants: B = A's rotation turned by 1e-7 .. 1e-3 rad
    if (k % 4 == 0) {
      const double ang = std::pow(10.0, -g.uni(3, 7));
      turn_rotation(sb, sa, g.unit(), ang);
    }
    a.push_back(rounded(sa)), b.push_back(rounded(sb));
  }
  for (KernelPath path : {KernelPath::kSimd, KernelPath::kScalar}) {
    const Out o = run(t, a, b, path);
    // min-translation checked; surfaces with the size-scaled tolerance
    const uint32_t contacts = check_bucket(t, a, b, o);
    EXPECT_GT(contacts, n / 10);
  }
}

TEST(PrimitivesExtremes, CrossingCapsuleCoresTakeTheCrossProductNormal) {
  // Cores that cross (or pass within 1e-7 .. 1e-5 of each other) away from the origin:
  // the minimum translation is along ua x ub, which the closest-points difference only
  // gives up to rounding / distance (found at IMPACT_TEST_INTENSITY 100).
  const PairType& t = pair_type("capsule-capsule");
  Gen g(0x5eed0015u);
  const uint32_t n = test::scaled(2000);
  std::normal_distribution<double> nd;
  std::vector<Shape> a, b;
  for (uint32_t k = 0; k < n; ++k) {
    Shape sa, sb;
    sa.kind = sb.kind = Kind::kCapsule;
    set_rotation(sa, nd(g.rng), nd(g.rng), nd(g.rng), nd(g.rng));
    set_rotation(sb, nd(g.rng), nd(g.rng), nd(g.rng), nd(g.rng));
    sa.e = {g.uni(0.1, 0.6), g.uni(0.2, 1.5), 0.0};
    sb.e = {g.uni(0.1, 0.6), g.uni(0.2, 1.5), 0.0};
    sa.p = {g.uni(-10, 10), g.uni(-10, 10), g.uni(-10, 10)};
    const D3 ua = sa.col(2), ub = sb.col(2);
    const D3 c = cross(ua, ub);
    const double gap = k % 4 == 0 ? 0.0 : std::pow(10.0, -g.uni(5, 7));
    // cores meet at A's parameter s and B's parameter u (inside both), then B is lifted
    // by gap along ua x ub
    const D3 x = add(sa.p, mul(ua, g.uni(-0.9, 0.9) * sa.e[1]));
    sb.p = add(sub(x, mul(ub, g.uni(-0.9, 0.9) * sb.e[1])), mul(c, gap / norm(c)));
    a.push_back(rounded(sa)), b.push_back(rounded(sb));
  }
  const Out simd = run(t, a, b, KernelPath::kSimd);
  const Out scalar = run(t, a, b, KernelPath::kScalar);
  EXPECT_EQ(check_bucket(t, a, b, simd), n);
  EXPECT_EQ(check_bucket(t, a, b, scalar), n);
  uint32_t bad = 0;
  for (uint32_t k = 0; k < n; ++k) {
    const D3 c = cross(a[k].col(2), b[k].col(2));
    const double align = std::fabs(dot(simd.normal(k), c)) / norm(c);
    const double agree = dot(simd.normal(k), scalar.normal(k));
    if ((align < 1.0 - 1e-6 || agree < 1.0 - 1e-6) && bad++ < 5)
      ADD_FAILURE() << "lane " << k << ": |n . ua x ub| " << align << ", simd . scalar normals " << agree;
  }
}

TEST(PrimitivesExtremes, CapsuleCoreJustOffATriangleTakesTheFeatureNormal) {
  // A capsule core within 1e-7 .. 1e-4 of a triangle, away from the origin: (a) crossing
  // over an edge's interior (the minimum translation is along u x edge), (b) an end
  // point over the face's interior (along the face normal). The difference of the two
  // closest points gives those directions only up to rounding / gap (a 1.7e-4 rad
  // error failed the matrix test at IMPACT_TEST_INTENSITY 10).
  const PairType& t = pair_type("capsule-triangle");
  Gen g(0x5eed0021u);
  const uint32_t n = test::scaled(2000);
  std::vector<Shape> a, b;
  std::vector<D3> want;  // expected normal: from the capsule to the triangle
  for (uint32_t k = 0; k < n; ++k) {
    // Local frame: the triangle in z = 0, edge v0 v1 on the x axis, the face at y < 0.
    const double r = g.uni(0.1, 0.5), h = g.uni(0.3, 1.5);
    // (the face case needs room for its foot: an in-radius well over 2 r)
    const double l = k % 2 == 0 ? g.uni(0.5, 2.0) : g.uni(8.0, 12.0) * r;
    const double gap = std::pow(10.0, -g.uni(4, 7));
    const D3 v0{-l, 0, 0}, v1{l, 0, 0}, v2{g.uni(-0.5, 0.5) * l, -l, 0};
    D3 c, u, axis;
    if (k % 2 == 0) {
      // over the edge: uy, uz > 0 keep the part of the core above the face farther
      // than gap from it; the common perpendicular is u x ex
      u = D3{g.uni(-1, 1), g.uni(0.2, 1.0), g.uni(0.2, 1.0)};
      u = mul(u, 1.0 / norm(u));
      axis = cross(u, D3{1, 0, 0});
      axis = mul(axis, 1.0 / norm(axis));
      const D3 x{g.uni(-0.6, 0.6) * l, 0, 0};
      c = add(add(x, mul(axis, gap)), mul(u, g.uni(-0.6, 0.6) * h));
    } else {
      // an end point over the face, at least 2 r inside every edge (else sliding off
      // an edge can be the shorter way out), the core leaning up and away
      u = D3{g.uni(-0.5, 0.5), g.uni(-0.5, 0.5), 1.0};
      u = mul(u, 1.0 / norm(u));
      axis = D3{0, 0, 1};
      D3 foot;
      for (bool inside = false; !inside;) {
        double w[3] = {g.uni(0.1, 1), g.uni(0.1, 1), g.uni(0.1, 1)};
        const double sum = w[0] + w[1] + w[2];
        foot = add(add(mul(v0, w[0] / sum), mul(v1, w[1] / sum)), mul(v2, w[2] / sum));
        inside = true;
        const D3 vs[3] = {v0, v1, v2};
        for (int i = 0; i < 3; ++i) {
          const D3 e = sub(vs[(i + 1) % 3], vs[i]), f = sub(foot, vs[i]);
          inside = inside && std::fabs(e[0] * f[1] - e[1] * f[0]) / norm(e) > 2.0 * r;
        }
      }
      foot[2] = gap;
      c = add(foot, mul(u, h));
    }
    // A random frame, 10 m from the origin.
    const D3 e0 = g.unit();
    D3 e1 = cross(e0, g.unit());
    e1 = mul(e1, 1.0 / norm(e1));
    const D3 e2 = cross(e0, e1);
    const D3 o{g.uni(-10, 10), g.uni(-10, 10), g.uni(-10, 10)};
    auto world = [&](const D3& q) { return add(o, add(add(mul(e0, q[0]), mul(e1, q[1])), mul(e2, q[2]))); };
    auto dir = [&](const D3& q) { return add(add(mul(e0, q[0]), mul(e1, q[1])), mul(e2, q[2])); };
    a.push_back(capsule(world(c), dir(u), r, h));
    b.push_back(triangle(world(v0), world(v1), world(v2)));
    want.push_back(mul(dir(axis), -1.0));  // the core sits on the +axis side
  }
  const Out simd = run(t, a, b, KernelPath::kSimd);
  const Out scalar = run(t, a, b, KernelPath::kScalar);
  EXPECT_EQ(check_bucket(t, a, b, simd), n);
  EXPECT_EQ(check_bucket(t, a, b, scalar), n);
  uint32_t bad = 0;
  for (uint32_t k = 0; k < n; ++k) {
    if (simd.count[k] == 0 || scalar.count[k] == 0) {
      if (bad++ < 5) ADD_FAILURE() << "lane " << k << ": no contact";
      continue;
    }
    const double align = dot(simd.normal(k), want[k]) / norm(want[k]);
    const double agree = dot(simd.normal(k), scalar.normal(k));
    if ((align < 1.0 - 1e-6 || agree < 1.0 - 1e-6) && bad++ < 5)
      ADD_FAILURE() << "lane " << k << (k % 2 == 0 ? " (edge)" : " (face)") << ": n . expected " << align
                    << ", simd . scalar normals " << agree;
  }
}

TEST(PrimitivesExtremes, NearParallelNeedlesTakeTheEdgeAxis) {
  // Needles (aspect 1e4) crossing at 1e-4 .. 1e-3 rad: the cross product of the long
  // edges is so short that float rounding of that edge axis's overlap (~100 * 1e-7 /
  // |a x b|) swamps the gap to the face axes, and yet it is often the true minimum.
  // The kernel settles such lanes in double; without that the depth along the face
  // normal is up to ~1.5x the minimum translation (found at IMPACT_TEST_INTENSITY 25).
  const PairType& t = pair_type("box-box");
  Gen g(0x5eed0014u);
  const uint32_t n = test::scaled(2000);
  std::normal_distribution<double> nd;
  std::vector<Shape> a, b;
  for (uint32_t k = 0; k < n; ++k) {
    Shape sa;
    sa.kind = Kind::kBox;
    set_rotation(sa, nd(g.rng), nd(g.rng), nd(g.rng), nd(g.rng));
    sa.e = {100.0, 0.01, 0.01};
    sa.p = {g.uni(-1, 1), g.uni(-1, 1), g.uni(-1, 1)};
    Shape sb = sa;
    const double ang = std::pow(10.0, -g.uni(3, 4));
    turn_rotation(sb, sa, g.unit(), ang);
    // across the needle by up to its width, along it anywhere
    sb.p = add(sa.p, add(mul(sa.col(0), g.uni(-60, 60)),
                         add(mul(sa.col(1), g.uni(-0.03, 0.03)), mul(sa.col(2), g.uni(-0.03, 0.03)))));
    a.push_back(rounded(sa)), b.push_back(rounded(sb));
  }
  for (KernelPath path : {KernelPath::kSimd, KernelPath::kScalar}) {
    const Out o = run(t, a, b, path);
    EXPECT_GT(check_bucket(t, a, b, o), n / 4);
  }
}

// ---------------------------------------------------------------------------------------
// Minimum axis: an edge axis a little shallower than the faces must win
// ---------------------------------------------------------------------------------------

/// The reference's view of a primitives_test shape.
test::nref::Shape to_ref(const Shape& s) {
  using test::nref::V3;
  const V3 p{s.p[0], s.p[1], s.p[2]};
  const double r9[9] = {s.R[0][0], s.R[0][1], s.R[0][2], s.R[1][0], s.R[1][1],
                        s.R[1][2], s.R[2][0], s.R[2][1], s.R[2][2]};
  switch (s.kind) {
    case Kind::kCapsule: {
      test::nref::Shape t =
          test::nref::make_axial(kLeafCapsule, p, {s.R[0][2], s.R[1][2], s.R[2][2]}, s.e[0], s.e[1]);
      test::nref::set_rotation(t, r9);
      return t;
    }
    case Kind::kBox:
      return test::nref::make_box(p, r9, s.e[0], s.e[1], s.e[2]);
    case Kind::kTriangle:
      return test::nref::make_triangle(p, {s.v1[0], s.v1[1], s.v1[2]}, {s.v2[0], s.v2[1], s.v2[2]});
    default:
      return test::nref::make_sphere(p, s.e[0]);
  }
}

/// A shape from float literals (R row-major).
Shape literal(Kind kind, const std::array<float, 3>& p, const std::array<float, 9>& r,
              const std::array<float, 3>& e, const std::array<float, 6>& w = {}) {
  Shape s;
  s.kind = kind;
  for (int i = 0; i < 3; ++i) s.p[i] = p[i], s.e[i] = e[i], s.v1[i] = w[i], s.v2[i] = w[3 + i];
  for (int i = 0; i < 9; ++i) s.R[i / 3][i % 3] = r[i];
  return s;
}

void expect_minimum(const char* type, const Shape& a, const Shape& b) {
  const test::nref::PairResult ref = test::nref::solve_pair(to_ref(a), to_ref(b));
  ASSERT_GT(ref.s, 0.0);
  const double tol = 1e-4 * std::max(a.bound(), b.bound());
  for (KernelPath path : {KernelPath::kSimd, KernelPath::kScalar}) {
    const Out o = run_one(type, a, b, path);
    ASSERT_GT(o.count[0], 0) << type;
    EXPECT_NEAR(o.depth[0], ref.s, tol) << type;
    const D3 n = o.normal(0);
    const double ang = test::nref::angle({n[0], n[1], n[2]}, ref.n);
    EXPECT_LT(ang, 1e-3) << type << " normal " << n[0] << " " << n[1] << " " << n[2];
  }
}

TEST(PrimitivesMinimumAxis, DeepEdgeAxesAgainstReference) {
  // box-box: an edge axis 0.9% shallower than the best face
  expect_minimum("box-box",
                 literal(Kind::kBox, {-0.0958060026f, -0.433721513f, -0.349768162f},
                         {-0.687881529f, -0.602422893f, 0.404852659f, 0.448655039f, 0.0855477005f,
                          0.889601171f, -0.570550323f, 0.7935794f, 0.211433396f},
                         {0.680252671f, 0.22365512f, 0.877120435f}),
                 literal(Kind::kBox, {-0.238325879f, -0.301449776f, -0.182889134f},
                         {-0.506703436f, -0.831654012f, 0.227163449f, -0.861302793f, 0.476860315f,
                          -0.175390288f, 0.0375388041f, -0.284527361f, -0.957932651f},
                         {0.557256877f, 0.90927273f, 0.757196665f}));
  // capsule-box: core inside the box, axis x box edge 0.67% shallower than a face
  expect_minimum("capsule-box",
                 literal(Kind::kCapsule, {0.651563466f, 0.035944283f, -0.648745835f},
                         {-0.0432255976f, 0.976309776f, -0.212015823f, 0.49665907f, 0.205132961f, 0.84335655f,
                          0.866868675f, -0.0688449964f, -0.493760139f},
                         {0.140245631f, 0.534180522f, 0.0f}),
                 literal(Kind::kBox, {0.716778338f, 0.23175633f, -0.653880894f},
                         {-0.750863433f, 0.211657524f, 0.625623822f, -0.590800345f, 0.208176941f, -0.7794981f,
                          -0.295227081f, -0.954915404f, -0.0312651098f},
                         {0.248116925f, 0.284482121f, 0.973235309f}));
  // capsule-triangle: core crossing the triangle, an axis x edge direction wins
  expect_minimum(
      "capsule-triangle",
      literal(Kind::kCapsule, {-0.937919021f, -0.951433539f, -0.434715748f},
              {-0.0989829749f, -0.665195584f, -0.740079224f, -0.924715042f, 0.336207688f, -0.178511739f,
               0.367565542f, 0.666692734f, -0.648395181f},
              {0.421726763f, 0.520743072f, 0.0f}),
      literal(Kind::kTriangle, {-1.47319317f, -0.833539069f, -0.622549891f}, {1, 0, 0, 0, 1, 0, 0, 0, 1},
              {0, 0, 0},
              {-0.243811056f, -1.00577545f, -0.438361138f, -1.18273866f, -1.01132023f, -0.282669425f}));
}

TEST(PrimitivesExtremes, NearParallelNeedlesCrossInsideBothEdges) {
  // 100 m needles 1.7e-4 rad apart, 58 m along each other (IMPACT_TEST_INTENSITY 30's
  // lane of NearParallelNeedlesTakeTheEdgeAxis): the edge axis wins, settled in double,
  // and the long edges' crossing moves by |t| * 1e-7 / |a x b|^2 (~160 m) unless the
  // closest-point step keeps the float columns' own lengths; the point then lay 0.0097
  // off both boxes (tolerance 0.002).
  const Shape a = literal(Kind::kBox, {0.20999366f, -0.358985394f, -0.34091121f},
                          {-0.133778051f, 0.241670951f, -0.961092412f, -0.661389291f, 0.700454414f,
                           0.268193632f, 0.738016009f, 0.671534657f, 0.066133149f},
                          {100.0f, 0.00999999978f, 0.00999999978f});
  const Shape b = literal(Kind::kBox, {7.96573591f, 38.0897179f, -43.2073898f},
                          {-0.133939311f, 0.24157232f, -0.961094737f, -0.661348403f, 0.700478196f,
                           0.268232346f, 0.73802346f, 0.671545327f, 0.0659418851f},
                          {100.0f, 0.00999999978f, 0.00999999978f});
  const PairType& t = pair_type("box-box");
  for (KernelPath path : {KernelPath::kSimd, KernelPath::kScalar}) {
    const Out o = run(t, {a}, {b}, path);
    EXPECT_EQ(check_bucket(t, {a}, {b}, o), 1u);
  }
}

TEST(PrimitivesMinimumAxis, TiltedRestingBoxesKeepFaceManifold) {
  // B resting on A, tilted by small angles about a diagonal axis: the face axis (or an
  // edge axis equal to it) must win and give 4 points.
  for (KernelPath path : {KernelPath::kSimd, KernelPath::kScalar}) {
    for (double tilt : {1e-6, 1e-4, 1e-3, 1e-2}) {
      const Shape a = box({0, 0, 0}, {1, 1, 1});
      const Shape b = rotated(box({0.1, -0.2, 1.9}, {1, 1, 1}), {1, 1, 0}, tilt);
      const Out o = run_one("box-box", a, b, path);
      ASSERT_EQ(o.count[0], 4) << "tilt " << tilt;
      EXPECT_LT(test::nref::angle({o.n[0][0], o.n[1][0], o.n[2][0]}, {0, 0, 1}), 1.5 * tilt + 1e-6) << tilt;
      const test::nref::PairResult ref = test::nref::solve_pair(to_ref(a), to_ref(b));
      EXPECT_NEAR(o.depth[0], ref.s, 1e-4 * b.bound()) << tilt;
    }
  }
}

}  // namespace
}  // namespace impact::kernels
