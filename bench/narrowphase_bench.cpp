// Narrow-phase micro-benchmarks: every pair kind of bench/scenes/narrow_scenes.h
// through its kernel (kernels::pair_kernel, scalar and SIMD paths) and through the
// public impact::NarrowPhase::collide, plus a streaming copy that gives the memory
// bandwidth the simple kernels are bounded by. The peers (FCL, libccd) run on the
// same scenes in bench/narrowphase_peers.cpp, in the same executable.
//
// What is timed:
//   BM_StreamCopy/<bytes>        memcpy of a float array (bytes counts read + write,
//                                STREAM's convention); 1 MiB stays in L2, 4 and 16 MiB
//                                are the working sets of the 64k-lane kernels (65 to
//                                200 bytes per lane), 256 MiB streams from memory
//   BM_Kernel/<pair>/<path>/<n>  one call of the bucket's kernel over all n lanes,
//                                1 thread, path scalar or simd (NarrowConfig::path).
//                                Inputs are the LeafSoA arrays of the scene, gathered
//                                once; the output ManifoldSoA is reused. n = 512: the
//                                block the public call gathers and hands a kernel
//                                (kLaneBlock, narrow_phase.cpp), inputs and outputs in
//                                L1 / L2, so the simple pairs' compute shows (but the
//                                same 512 lanes over and over: a branchy scalar path's
//                                branches can be learnt by the predictor); 4096: the
//                                README's size (~0.3 MB for the simple pairs: L2
//                                bandwidth bounds them); 65536: streams from L3 / memory
//   BM_Collide/<pair>/<n>/<threads>  NarrowPhase::collide on a ShapeSet with one shape
//                                per object (2n objects, pairs (2k, 2k+1)); triangles
//                                are one-triangle meshes at the identity pose;
//                                half-spaces are half-space shapes at the identity
//                                pose. Includes validation, leaf gathering, bucketing
//                                and manifold output: the whole batch call.
// Kernel and peer benchmarks report CPU time (the machine is shared; the benchmarks
// are single-threaded); BM_Collide reports real time (it runs worker threads).
//
// Counters:
//   ns_per_pair     time per lane (per pair)
//   hits            lanes with contact (count > 0 / a manifold) in the last call
//   expected        lanes the generator placed inside the touching distance
//   near_touch      lanes within 1e-4 (relative) of touching: either answer is fair
//   disagree        lanes whose answer contradicts the placement, near-touch lanes
//                   excluded (should be 0)
//   hit_frac        hits / n
//   bytes_per_pair  narrow::bytes_per_pair (minimum kernel traffic, an estimate)
//   bytes_per_second  bytes_per_pair / ns_per_pair: compare with BM_StreamCopy
//
// Run everything, short repetitions (about 8 minutes on 2 shared cores):
//   impact_narrowbench --benchmark_min_time=0.2 --benchmark_repetitions=3
//       --benchmark_report_aggregates_only=true
// one pair kind, all implementations: --benchmark_filter='/box-box/'
#include <benchmark/benchmark.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <map>
#include <memory>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "bench/bench_threads.h"
#include "bench/scenes/narrow_scenes.h"
#include "host/narrowphase/lane_arrays.h"
#include "host/shapes/convex_hull.h"
#include "host/shapes/shape_store.h"
#include "impact/narrowphase.h"
#include "impact/shapes.h"
#include "kernels/narrowphase/leaf/leaf.h"

namespace impact::bench::narrow {

// --- scene generation (defined here only: see narrow_scenes.h) ------------------------------

namespace {

// splitmix64: the same stream on every standard library.
struct Rng {
  uint64_t s;
  uint64_t next() {
    uint64_t z = (s += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
  }
  double uniform() { return static_cast<double>(next() >> 11) * 0x1.0p-53; }
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
};

using V3 = std::array<double, 3>;
constexpr double kPi = 3.14159265358979323846;

V3 sub(const V3& a, const V3& b) {
  return {a[0] - b[0], a[1] - b[1], a[2] - b[2]};
}
V3 add(const V3& a, const V3& b) {
  return {a[0] + b[0], a[1] + b[1], a[2] + b[2]};
}
V3 scale(const V3& a, double s) {
  return {a[0] * s, a[1] * s, a[2] * s};
}
V3 neg(const V3& a) {
  return {-a[0], -a[1], -a[2]};
}
double dot(const V3& a, const V3& b) {
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}
V3 cross(const V3& a, const V3& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
double norm(const V3& a) {
  return std::sqrt(dot(a, a));
}

V3 random_unit(Rng& rng) {
  // Marsaglia: uniform on the sphere.
  for (;;) {
    const double x = rng.uniform(-1, 1), y = rng.uniform(-1, 1), z = rng.uniform(-1, 1);
    const double l2 = x * x + y * y + z * z;
    if (l2 > 1e-6 && l2 <= 1.0) {
      const double l = std::sqrt(l2);
      return {x / l, y / l, z / l};
    }
  }
}

// Uniform random rotation (Shoemake), rounded to float; r is computed from the
// rounded quaternion (normalised in double).
void random_orientation(Rng& rng, Body* b) {
  const double u1 = rng.uniform(), u2 = rng.uniform() * 2 * kPi, u3 = rng.uniform() * 2 * kPi;
  const double a = std::sqrt(1 - u1), c = std::sqrt(u1);
  const double q[4] = {c * std::cos(u3), a * std::sin(u2), a * std::cos(u2), c * std::sin(u3)};
  for (int i = 0; i < 4; ++i) b->q[i] = static_cast<float>(q[i]);
  double w = b->q[0], x = b->q[1], y = b->q[2], z = b->q[3];
  const double l = std::sqrt(w * w + x * x + y * y + z * z);
  w /= l, x /= l, y /= l, z /= l;
  const double m[9] = {1 - 2 * (y * y + z * z), 2 * (x * y - w * z),     2 * (x * z + w * y),
                       2 * (x * y + w * z),     1 - 2 * (x * x + z * z), 2 * (y * z - w * x),
                       2 * (x * z - w * y),     2 * (y * z + w * x),     1 - 2 * (x * x + y * y)};
  for (int i = 0; i < 9; ++i) b->r[i] = static_cast<float>(m[i]);
}

V3 to_local(const Body& b, const V3& d) {  // R^T d
  return {b.r[0] * d[0] + b.r[3] * d[1] + b.r[6] * d[2], b.r[1] * d[0] + b.r[4] * d[1] + b.r[7] * d[2],
          b.r[2] * d[0] + b.r[5] * d[1] + b.r[8] * d[2]};
}
V3 to_world(const Body& b, const V3& l) {  // R l + p
  return {b.r[0] * l[0] + b.r[1] * l[1] + b.r[2] * l[2] + b.p[0],
          b.r[3] * l[0] + b.r[4] * l[1] + b.r[5] * l[2] + b.p[1],
          b.r[6] * l[0] + b.r[7] * l[1] + b.r[8] * l[2] + b.p[2]};
}

V3 support_v(const PairScene& s, const Body& b, const V3& dir) {
  const V3 d = to_local(b, dir);
  V3 l{0, 0, 0};
  switch (b.kind) {
    case kSphere: {
      const double n = norm(d);
      l = scale(d, b.e[0] / n);
      break;
    }
    case kCapsule: {
      const double n = norm(d);
      l = scale(d, b.e[0] / n);
      l[2] += d[2] >= 0 ? b.e[1] : -b.e[1];
      break;
    }
    case kBox:
      for (int i = 0; i < 3; ++i) l[i] = d[i] >= 0 ? b.e[i] : -b.e[i];
      break;
    case kConvex: {
      double best = -1e300;
      for (const auto& pt : s.hulls[b.hull].points) {
        const V3 v{pt[0], pt[1], pt[2]};
        const double h = dot(v, d);
        if (h > best) best = h, l = v;
      }
      break;
    }
    case kCylinder: {
      const double rxy = std::sqrt(d[0] * d[0] + d[1] * d[1]);
      if (rxy > 0) l[0] = d[0] * b.e[0] / rxy, l[1] = d[1] * b.e[0] / rxy;
      l[2] = d[2] >= 0 ? b.e[1] : -b.e[1];
      break;
    }
    case kEllipsoid: {
      const V3 ed{b.e[0] * d[0], b.e[1] * d[1], b.e[2] * d[2]};
      const double n = norm(ed);
      l = {b.e[0] * ed[0] / n, b.e[1] * ed[1] / n, b.e[2] * ed[2] / n};
      break;
    }
    case kTriangle: {
      double best = -1e300;
      V3 w{0, 0, 0};
      for (int i = 0; i < 3; ++i) {
        const V3 v{b.v[3 * i], b.v[3 * i + 1], b.v[3 * i + 2]};
        const double h = dot(v, dir);
        if (h > best) best = h, w = v;
      }
      return w;  // triangle vertices are stored in world coordinates
    }
    default:
      break;
  }
  return to_world(b, l);
}

V3 interior(const Body& b) {
  if (b.kind == kTriangle) {
    return {(double(b.v[0]) + b.v[3] + b.v[6]) / 3, (double(b.v[1]) + b.v[4] + b.v[7]) / 3,
            (double(b.v[2]) + b.v[5] + b.v[8]) / 3};
  }
  return {b.p[0], b.p[1], b.p[2]};
}

// Boolean GJK (the simplex-walk formulation, as in Muratori's "Implementing GJK"):
// does A intersect B translated by t? Works on the Minkowski difference A - (B + t).
// Touching counts as intersecting. Its "no" is a certificate (a separating support
// plane) and so is its "yes" when a tetrahedron encloses the origin; on degenerate
// polytope configurations it can cycle, and then GjkDistance decides.
class GjkBool {
 public:
  GjkBool(const PairScene& s, const Body& a, const Body& b, const V3& t) : s_(s), a_(a), b_(b), t_(t) {}

  enum Answer { kNo, kYes, kUnsure };
  Answer intersect() {
    V3 d = sub(add(interior(b_), t_), interior(a_));
    if (dot(d, d) < 1e-24) d = {1, 0, 0};
    simplex_[0] = sup(d);
    size_ = 1;
    d = neg(simplex_[0]);
    for (int it = 0; it < 128; ++it) {
      if (dot(d, d) < 1e-30) return kYes;  // the origin lies on the simplex
      const V3 p = sup(d);
      if (dot(p, d) < 0) return kNo;
      for (int i = size_; i > 0; --i) simplex_[i] = simplex_[i - 1];  // newest first
      simplex_[0] = p;
      ++size_;
      if (step(&d)) return kYes;
    }
    return kUnsure;  // cycling
  }

 private:
  V3 sup(const V3& d) const { return sub(support_v(s_, a_, d), add(support_v(s_, b_, neg(d)), t_)); }
  bool line(V3* d) {
    const V3 a = simplex_[0], b = simplex_[1];
    const V3 ab = sub(b, a), ao = neg(a);
    if (dot(ab, ao) > 0) {
      *d = cross(cross(ab, ao), ab);
    } else {
      size_ = 1;
      *d = ao;
    }
    return false;
  }
  bool triangle(V3* d) {
    const V3 a = simplex_[0], b = simplex_[1], c = simplex_[2];
    const V3 ab = sub(b, a), ac = sub(c, a), ao = neg(a);
    const V3 abc = cross(ab, ac);
    if (dot(cross(abc, ac), ao) > 0) {
      if (dot(ac, ao) > 0) {
        simplex_[1] = c;
        size_ = 2;
        *d = cross(cross(ac, ao), ac);
        return false;
      }
      return edge_ab(a, b, ab, ao, d);
    }
    if (dot(cross(ab, abc), ao) > 0) return edge_ab(a, b, ab, ao, d);
    const double side = dot(abc, ao);
    if (side > 0) {
      *d = abc;
    } else {
      simplex_[1] = c;
      simplex_[2] = b;
      *d = neg(abc);
    }
    size_ = 3;
    return side == 0;  // the origin lies in the triangle
  }
  bool edge_ab(const V3& a, const V3& b, const V3& ab, const V3& ao, V3* d) {
    if (dot(ab, ao) > 0) {
      simplex_[0] = a, simplex_[1] = b, size_ = 2;
      *d = cross(cross(ab, ao), ab);
    } else {
      simplex_[0] = a, size_ = 1;
      *d = ao;
    }
    return false;
  }
  bool tetra(V3* d) {
    const V3 a = simplex_[0], b = simplex_[1], c = simplex_[2], e = simplex_[3];
    const V3 ao = neg(a);
    if (dot(cross(sub(b, a), sub(c, a)), ao) > 0) {
      simplex_[0] = a, simplex_[1] = b, simplex_[2] = c, size_ = 3;
      return triangle(d);
    }
    if (dot(cross(sub(c, a), sub(e, a)), ao) > 0) {
      simplex_[0] = a, simplex_[1] = c, simplex_[2] = e, size_ = 3;
      return triangle(d);
    }
    if (dot(cross(sub(e, a), sub(b, a)), ao) > 0) {
      simplex_[0] = a, simplex_[1] = e, simplex_[2] = b, size_ = 3;
      return triangle(d);
    }
    return true;
  }
  bool step(V3* d) {
    switch (size_) {
      case 2:
        return line(d);
      case 3:
        return triangle(d);
      default:
        return tetra(d);
    }
  }

  const PairScene& s_;
  const Body& a_;
  const Body& b_;
  V3 t_;
  V3 simplex_[4];
  int size_ = 0;
};

// Distance between A and B translated by t: GJK (Gilbert, Johnson, Keerthi 1988) with
// van den Bergen's termination test, in double. The closest point of the simplex is
// found by brute force over its sub-simplices (at most 15 affine projections): slow
// but free of the case analysis in which fast formulations cycle on degenerate
// polytope configurations. Only used to bracket the touching distance.
class GjkDistance {
 public:
  GjkDistance(const PairScene& s, const Body& a, const Body& b, const V3& t) : s_(s), a_(a), b_(b), t_(t) {}

  /// Distance (0 when overlapping or touching within ~1e-12 relative).
  double distance() {
    V3 v = sub(add(interior(b_), t_), interior(a_));
    if (dot(v, v) < 1e-24) v = {1, 0, 0};
    v = sup(v);
    size_ = 0;
    for (int it = 0; it < 256; ++it) {
      const double vv = dot(v, v);
      if (vv < 1e-24) return 0.0;
      const V3 w = sup(neg(v));
      if (vv - dot(v, w) <= 1e-12 * vv) return std::sqrt(vv);  // no progress left
      for (int i = 0; i < size_; ++i)
        if (w == simplex_[i]) return std::sqrt(vv);
      simplex_[size_++] = w;
      v = closest();
    }
    return std::sqrt(dot(v, v));
  }

 private:
  V3 sup(const V3& d) const { return sub(support_v(s_, a_, d), add(support_v(s_, b_, neg(d)), t_)); }

  // Point of aff(points in mask) closest to the origin, if it lies in their relative
  // interior (all barycentric weights > 0) and the points are affinely independent.
  bool project(uint32_t mask, V3* out) const {
    V3 p[4];
    int m = 0;
    for (int i = 0; i < size_; ++i)
      if (mask & (1u << i)) p[m++] = simplex_[i];
    if (m == 1) {
      *out = p[0];
      return true;
    }
    // x = p0 + sum mu_i (p_i - p0); normal equations G mu = -E^T p0.
    const int k = m - 1;
    double g[3][4];
    V3 e[3];
    for (int i = 0; i < k; ++i) e[i] = sub(p[i + 1], p[0]);
    double scale = 0;
    for (int i = 0; i < k; ++i) {
      for (int j = 0; j < k; ++j) g[i][j] = dot(e[i], e[j]);
      g[i][k] = -dot(e[i], p[0]);
      scale = std::max(scale, g[i][i]);
    }
    for (int c = 0; c < k; ++c) {  // Gaussian elimination, partial pivoting
      int piv = c;
      for (int r = c + 1; r < k; ++r)
        if (std::fabs(g[r][c]) > std::fabs(g[piv][c])) piv = r;
      if (std::fabs(g[piv][c]) <= 1e-13 * scale) return false;  // degenerate
      for (int j = 0; j <= k; ++j) std::swap(g[c][j], g[piv][j]);
      for (int r = 0; r < k; ++r) {
        if (r == c) continue;
        const double f = g[r][c] / g[c][c];
        for (int j = c; j <= k; ++j) g[r][j] -= f * g[c][j];
      }
    }
    double mu_sum = 0;
    V3 x = p[0];
    for (int i = 0; i < k; ++i) {
      const double mu = g[i][k] / g[i][i];
      if (!(mu > 0)) return false;
      mu_sum += mu;
      x = add(x, scale3(e[i], mu));
    }
    if (!(mu_sum < 1)) return false;
    *out = x;
    return true;
  }
  static V3 scale3(const V3& a, double s) { return {a[0] * s, a[1] * s, a[2] * s}; }

  // Closest point of the simplex's hull to the origin; keeps only the points of the
  // sub-simplex it lies on.
  V3 closest() {
    double best = 1e300;
    uint32_t best_mask = 1;
    V3 best_x = simplex_[0];
    for (uint32_t mask = 1; mask < (1u << size_); ++mask) {
      V3 x;
      if (!project(mask, &x)) continue;
      const double d = dot(x, x);
      if (d < best) best = d, best_mask = mask, best_x = x;
    }
    int m = 0;
    for (int i = 0; i < size_; ++i)
      if (best_mask & (1u << i)) simplex_[m++] = simplex_[i];
    size_ = m;
    return best_x;
  }

  const PairScene& s_;
  const Body& a_;
  const Body& b_;
  V3 t_;
  V3 simplex_[4];
  int size_ = 0;
};

double bounding_radius(const PairScene& s, const Body& b) {
  switch (b.kind) {
    case kSphere:
      return b.e[0];
    case kCapsule:
      return double(b.e[0]) + b.e[1];
    case kBox:
    case kEllipsoid:
      return norm({b.e[0], b.e[1], b.e[2]});
    case kCylinder:
      return std::hypot(double(b.e[0]), double(b.e[1]));
    case kConvex: {
      double r = 0;
      for (const auto& p : s.hulls[b.hull].points) r = std::max(r, norm({p[0], p[1], p[2]}));
      return r;
    }
    case kTriangle: {
      const V3 c = interior(b);
      double r = 0;
      for (int i = 0; i < 3; ++i) r = std::max(r, norm(sub({b.v[3 * i], b.v[3 * i + 1], b.v[3 * i + 2]}, c)));
      return r;
    }
    default:
      return 0;
  }
}

constexpr uint32_t kHullCount = 16;
constexpr uint32_t kHullPoints = 24;

// Faces and vertices of a hull, by the library's builder (host/shapes/convex_hull.h).
void build_hull_faces(Hull* h) {
  std::vector<Eigen::Vector3f> pts;
  for (const auto& p : h->points) pts.emplace_back(p[0], p[1], p[2]);
  HullData data;
  if (!impact::build_convex_hull(pts, &data).ok()) return;
  for (const auto& v : data.vertices) h->verts.push_back({v.x(), v.y(), v.z()});
  for (const auto& f : data.faces) {
    h->faces.push_back(static_cast<uint32_t>(f.size()));
    h->faces.insert(h->faces.end(), f.begin(), f.end());
  }
  h->face_count = static_cast<uint32_t>(data.faces.size());
}

// Random sizes (and the triangle's vertices around the local origin) of a body.
void random_shape(Rng& rng, PairScene* s, Body* b) {
  switch (b->kind) {
    case kSphere:
      b->e[0] = static_cast<float>(rng.uniform(0.25, 1.0));
      break;
    case kCapsule:
      b->e[0] = static_cast<float>(rng.uniform(0.2, 0.6));
      b->e[1] = static_cast<float>(rng.uniform(0.2, 1.0));
      break;
    case kBox:
      for (float& e : b->e) e = static_cast<float>(rng.uniform(0.2, 1.0));
      break;
    case kConvex:
      b->hull = static_cast<uint32_t>(rng.next() % s->hulls.size());
      break;
    case kCylinder:
      b->e[0] = static_cast<float>(rng.uniform(0.2, 0.8));
      b->e[1] = static_cast<float>(rng.uniform(0.2, 1.0));
      break;
    case kEllipsoid:
      for (float& e : b->e) e = static_cast<float>(rng.uniform(0.25, 1.0));
      break;
    default:
      break;
  }
}

// Triangle: three vertices 0.5..1.5 from the centroid c in a random plane (no sliver:
// the angles are spread), rounded to float; p = v0.
void place_triangle(Rng& rng, const V3& c, Body* b) {
  const V3 n = random_unit(rng);
  V3 t = cross(n, std::fabs(n[0]) < 0.6 ? V3{1, 0, 0} : V3{0, 1, 0});
  t = scale(t, 1 / norm(t));
  const V3 bt = cross(n, t);
  const double a0 = rng.uniform(0, 2 * kPi);
  V3 v[3];
  for (int i = 0; i < 3; ++i) {
    const double ang = a0 + i * (2 * kPi / 3) + rng.uniform(-0.5, 0.5);
    const double rad = rng.uniform(0.5, 1.5);
    v[i] = add(scale(t, rad * std::cos(ang)), scale(bt, rad * std::sin(ang)));
  }
  const V3 mean = scale(add(add(v[0], v[1]), v[2]), 1.0 / 3);
  for (int i = 0; i < 3; ++i)
    for (int k = 0; k < 3; ++k) b->v[3 * i + k] = static_cast<float>(c[k] + v[i][k] - mean[k]);
  for (int k = 0; k < 3; ++k) b->p[k] = b->v[k];
}

void set_centre(Body* b, const V3& c) {
  for (int k = 0; k < 3; ++k) b->p[k] = static_cast<float>(c[k]);
}

std::unique_ptr<PairScene> generate(uint8_t ka, uint8_t kb, uint32_t n) {
  auto s = std::make_unique<PairScene>();
  s->ka = ka, s->kb = kb, s->n = n;
  Rng rng{0x5eed0000ull + 977ull * ka + 31ull * kb + n};
  if (ka == kConvex || kb == kConvex) {
    Rng hr{0x4a11ull};  // the same hulls in every scene
    s->hulls.resize(kHullCount);
    for (Hull& h : s->hulls) {
      const double sx = hr.uniform(0.4, 1.0), sy = hr.uniform(0.4, 1.0), sz = hr.uniform(0.4, 1.0);
      for (uint32_t i = 0; i < kHullPoints; ++i) {
        const V3 u = random_unit(hr);
        h.points.push_back(
            {static_cast<float>(sx * u[0]), static_cast<float>(sy * u[1]), static_cast<float>(sz * u[2])});
      }
      build_hull_faces(&h);
    }
  }
  s->a.resize(n);
  s->b.resize(n);
  for (uint32_t k = 0; k < n; ++k) {
    Body& a = s->a[k];
    Body& b = s->b[k];
    a.kind = ka, b.kind = kb;
    random_shape(rng, s.get(), &a);
    random_orientation(rng, &a);
    const V3 ca{rng.uniform(-50, 50), rng.uniform(-50, 50), rng.uniform(-50, 50)};
    if (ka == kTriangle) {
      place_triangle(rng, ca, &a);  // its vertices around ca (as for a triangle B)
    } else {
      set_centre(&a, ca);
    }
    const V3 u = random_unit(rng);
    const double f = rng.uniform(0.6, 1.4);
    s->f.push_back(static_cast<float>(f));
    s->expected_hits += f < 1 ? 1 : 0;
    s->near_touch += std::fabs(f - 1) < kNearTouch ? 1 : 0;
    if (kb == kHalfSpace) {
      // Plane normal u; A's lowest point along u is at depth h below its centre.
      const double h = dot(sub(interior(a), support_v(*s, a, neg(u))), u);
      const V3 q = sub(ca, scale(u, h * f));
      set_centre(&b, q);
      for (int i = 0; i < 3; ++i) b.e[i] = static_cast<float>(u[i]);
      continue;
    }
    random_shape(rng, s.get(), &b);
    // B first at A's centre; the bisection moves it along u.
    if (kb == kTriangle) {
      place_triangle(rng, ca, &b);
    } else {
      random_orientation(rng, &b);
      set_centre(&b, ca);
    }
    const V3 c0 = interior(b);
    const double reach = bounding_radius(*s, a) + bounding_radius(*s, b);
    double lo = 0, hi = 1.001 * reach;
    for (int it = 0; it < 26; ++it) {
      const double mid = 0.5 * (lo + hi);
      const V3 t = scale(u, mid);
      GjkBool::Answer ans = GjkBool(*s, a, b, t).intersect();
      if (ans == GjkBool::kUnsure)
        ans = GjkDistance(*s, a, b, t).distance() <= 1e-9 * reach ? GjkBool::kYes : GjkBool::kNo;
      if (ans == GjkBool::kYes)
        lo = mid;
      else
        hi = mid;
    }
    const V3 t = scale(u, f * 0.5 * (lo + hi));
    if (kb == kTriangle) {
      for (int i = 0; i < 3; ++i)
        for (int k2 = 0; k2 < 3; ++k2) b.v[3 * i + k2] = static_cast<float>(b.v[3 * i + k2] + t[k2]);
      for (int k2 = 0; k2 < 3; ++k2) b.p[k2] = b.v[k2];
    } else {
      set_centre(&b, add(c0, t));
    }
  }
  return s;
}

}  // namespace

double body_size(const PairScene& s, const Body& b) {
  return bounding_radius(s, b);
}

const char* kind_name(uint8_t k) {
  static const char* const names[] = {"sphere",   "capsule",   "box",      "convex",
                                      "cylinder", "ellipsoid", "triangle", "halfspace"};
  return k < 8 ? names[k] : "unknown";
}

std::string pair_name(uint8_t ka, uint8_t kb) {
  return std::string(kind_name(ka)) + "-" + kind_name(kb);
}

const PairScene& pair_scene(uint8_t ka, uint8_t kb, uint32_t n) {
  static std::map<std::tuple<uint8_t, uint8_t, uint32_t>, std::unique_ptr<PairScene>> cache;
  auto& slot = cache[{ka, kb, n}];
  if (!slot) slot = generate(ka, kb, n);
  return *slot;
}

void support(const PairScene& s, const Body& body, const double dir[3], double out[3]) {
  const V3 w = support_v(s, body, {dir[0], dir[1], dir[2]});
  out[0] = w[0], out[1] = w[1], out[2] = w[2];
}

void interior_point(const Body& body, double out[3]) {
  const V3 c = interior(body);
  out[0] = c[0], out[1] = c[1], out[2] = c[2];
}

namespace {
// LeafSoA floats a kernel of this kind needs (leaf.h's field table).
uint32_t leaf_floats(uint8_t k) {
  switch (k) {
    case kSphere:
      return 4;  // p, r
    case kCapsule:
      return 8;  // p, axis, r, h
    case kBox:
      return 15;  // p, R, e
    case kConvex:
      return 13;  // p, R, ref (the hulls are shared and stay in cache)
    case kCylinder:
      return 8;  // p, axis, r, h
    case kEllipsoid:
      return 15;  // p, R, e
    case kTriangle:
      return 9;  // v0, v1, v2
    case kHalfSpace:
      return 6;  // p, n
    default:
      return 0;
  }
}
uint32_t manifold_points(uint8_t ka, uint8_t kb) {
  auto round = [](uint8_t k) { return k == kSphere || k == kEllipsoid; };
  if (round(ka) || round(kb)) return 1;
  if (ka == kCapsule && (kb == kCapsule || kb == kBox || kb == kTriangle || kb == kHalfSpace)) return 2;
  return 4;
}
}  // namespace

uint32_t bytes_per_pair(uint8_t ka, uint8_t kb) {
  return 4 * (leaf_floats(ka) + leaf_floats(kb)) + 1 + 16 + 16 * manifold_points(ka, kb);
}

}  // namespace impact::bench::narrow

namespace {

namespace nb = impact::bench::narrow;
namespace kn = impact::kernels;
using Clock = std::chrono::steady_clock;

constexpr uint32_t k512 = 512, k4k = 4096, k64k = 65536;

void set_pair_counters(benchmark::State& state, const nb::PairScene& s, double ns, uint64_t hits,
                       uint32_t disagree) {
  const uint32_t n = s.n;
  const double pairs = static_cast<double>(state.iterations()) * n;
  state.counters["ns_per_pair"] = pairs > 0 ? ns / pairs : 0.0;
  state.counters["hits"] = static_cast<double>(hits);
  state.counters["expected"] = static_cast<double>(s.expected_hits);
  state.counters["near_touch"] = static_cast<double>(s.near_touch);
  state.counters["disagree"] = static_cast<double>(disagree);
  state.counters["hit_frac"] = n ? static_cast<double>(hits) / n : 0.0;
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations()) * n);
}

// --- memory bandwidth -----------------------------------------------------------------------

void BM_StreamCopy(benchmark::State& state) {
  const size_t bytes = static_cast<size_t>(state.range(0));
  std::vector<float> src(bytes / sizeof(float), 1.0f), dst(bytes / sizeof(float), 0.0f);
  for (auto _ : state) {
    std::memcpy(dst.data(), src.data(), bytes);
    benchmark::DoNotOptimize(dst.data());
    benchmark::ClobberMemory();
  }
  // Read + write, as STREAM counts a copy (write-allocate traffic not counted).
  state.SetBytesProcessed(static_cast<int64_t>(state.iterations()) * static_cast<int64_t>(2 * bytes));
}
BENCHMARK(BM_StreamCopy)->Arg(1 << 20)->Arg(4 << 20)->Arg(16 << 20)->Arg(256 << 20);

// --- kernels --------------------------------------------------------------------------------

uint32_t padded(uint32_t n) {
  return (n + 15u) & ~15u;
}

// LeafSoA arrays of one side of a scene (padded to a multiple of 16 lanes with copies
// of lane 0, so wide loads past n stay in bounds), in the public call's block layout
// (host/narrowphase/lane_arrays.h).
void gather(const std::vector<nb::Body>& bodies, uint32_t phase, impact::host::LeafArrays* out) {
  const uint32_t n = static_cast<uint32_t>(bodies.size()), m = padded(n);
  out->resize(m, phase);
  for (uint32_t k = 0; k < m; ++k) {
    const nb::Body& b = bodies[k < n ? k : 0];
    for (int i = 0; i < 3; ++i) out->f[i][k] = b.p[i], out->f[12 + i][k] = b.e[i];
    for (int i = 0; i < 9; ++i) out->f[3 + i][k] = b.r[i];
    for (int i = 0; i < 6; ++i) out->f[15 + i][k] = b.v[3 + i];
    out->ref[k] = b.hull;
  }
}

// The library's hulls for the scene's point clouds (the same builder ShapeSet uses).
struct Hulls {
  impact::HullStore store;
  explicit Hulls(const nb::PairScene& s) {
    for (const nb::Hull& h : s.hulls) {
      std::vector<Eigen::Vector3f> pts;
      for (const auto& p : h.points) pts.emplace_back(p[0], p[1], p[2]);
      impact::HullData data;
      if (!impact::build_convex_hull(pts, &data).ok()) std::abort();
      store.add(data);
    }
  }
};

// A scene's lanes in the kernels' layouts: both sides' LeafSoA arrays, the zeroed
// output and the hulls, ready for the pair kind's kernel.
struct KernelBucket {
  impact::host::LeafArrays a, b;
  impact::host::ManifoldArrays out;
  Hulls hulls;
  kn::NarrowConfig cfg;
  kn::PairKernel kernel;
  KernelBucket(const nb::PairScene& s, kn::KernelPath path)
      : hulls(s), kernel(kn::pair_kernel(static_cast<kn::LeafType>(s.ka), static_cast<kn::LeafType>(s.kb))) {
    gather(s.a, impact::host::LeafArrays::kPhaseA, &a);
    gather(s.b, impact::host::LeafArrays::kPhaseB, &b);
    out.resize(padded(s.n));
    std::fill(out.count, out.count + padded(s.n), uint8_t{0});
    for (float* f : out.f) std::fill(f, f + padded(s.n), 0.0f);
    cfg.path = path;
    cfg.hulls = hulls.store.view();
  }
};

void BM_Kernel(benchmark::State& state, uint8_t ka, uint8_t kb, kn::KernelPath path) {
  const uint32_t n = static_cast<uint32_t>(state.range(0));
  const nb::PairScene& s = nb::pair_scene(ka, kb, n);
  KernelBucket bucket(s, path);
  if (!bucket.kernel) {
    state.SkipWithError("no kernel for this pair");
    return;
  }
  const kn::LeafSoA av = bucket.a.view(), bv = bucket.b.view();
  const kn::ManifoldSoA ov = bucket.out.view();
  const double t0 = nb::thread_cpu_ns();
  for (auto _ : state) {
    bucket.kernel(av, bv, ov, kn::Range{0, n}, bucket.cfg);
    benchmark::ClobberMemory();
  }
  const double ns = nb::thread_cpu_ns() - t0;
  uint64_t hits = 0;
  for (uint32_t k = 0; k < n; ++k) hits += ov.count[k] > 0 ? 1 : 0;
  set_pair_counters(state, s, ns, hits, nb::disagreements(s, [&](uint32_t k) { return ov.count[k] > 0; }));
  const uint32_t bytes = nb::bytes_per_pair(ka, kb);
  state.counters["bytes_per_pair"] = bytes;
  state.SetBytesProcessed(static_cast<int64_t>(state.iterations()) * n * bytes);
}

}  // namespace

std::vector<nb::LaneResult> nb::kernel_results(const PairScene& s) {
  KernelBucket bucket(s, kn::KernelPath::kSimd);
  std::vector<LaneResult> r(s.n);
  if (!bucket.kernel) return r;
  const kn::ManifoldSoA ov = bucket.out.view();
  bucket.kernel(bucket.a.view(), bucket.b.view(), ov, kn::Range{0, s.n}, bucket.cfg);
  for (uint32_t k = 0; k < s.n; ++k) {
    r[k].count = ov.count[k];
    for (int i = 0; i < 3; ++i) r[k].n[i] = ov.n[i][k];
    r[k].depth = ov.depth[k];
  }
  return r;
}

namespace {

// --- public API -----------------------------------------------------------------------------

// Shapes, poses and pairs of a scene for NarrowPhase::collide.
struct ApiScene {
  impact::ShapeSet shapes;
  std::vector<impact::ShapeId> shape_of;
  std::vector<impact::Pose> poses;
  std::vector<impact::ShapePair> pairs;
  std::map<uint32_t, impact::ShapeId> hull_shape;  // one shape per hull of the scene
  std::string error;
};

bool add_body(const nb::PairScene& s, const nb::Body& b, ApiScene* out) {
  impact::ShapeId id;
  impact::Status st;
  impact::Pose pose;
  pose.position = Eigen::Vector3f(b.p[0], b.p[1], b.p[2]);
  pose.orientation = Eigen::Quaternionf(b.q[0], b.q[1], b.q[2], b.q[3]);
  switch (b.kind) {
    case nb::kSphere:
      st = out->shapes.add_sphere(b.e[0], &id);
      break;
    case nb::kCapsule:
      st = out->shapes.add_capsule(b.e[0], b.e[1], &id);
      break;
    case nb::kBox:
      st = out->shapes.add_box(Eigen::Vector3f(b.e[0], b.e[1], b.e[2]), &id);
      break;
    case nb::kConvex: {
      // One shape per hull, shared by the objects that use it.
      if (auto it = out->hull_shape.find(b.hull); it != out->hull_shape.end()) {
        id = it->second;
        break;
      }
      std::vector<Eigen::Vector3f> pts;
      for (const auto& p : s.hulls[b.hull].points) pts.emplace_back(p[0], p[1], p[2]);
      st = out->shapes.add_convex_hull(pts, &id);
      if (st.ok()) out->hull_shape[b.hull] = id;
      break;
    }
    case nb::kCylinder:
      st = out->shapes.add_cylinder(b.e[0], b.e[1], &id);
      break;
    case nb::kEllipsoid:
      st = out->shapes.add_ellipsoid(Eigen::Vector3f(b.e[0], b.e[1], b.e[2]), &id);
      break;
    case nb::kTriangle: {
      const Eigen::Vector3f v[3] = {
          {b.v[0], b.v[1], b.v[2]}, {b.v[3], b.v[4], b.v[5]}, {b.v[6], b.v[7], b.v[8]}};
      const uint32_t idx[3] = {0, 1, 2};
      st = out->shapes.add_mesh(v, idx, &id);
      pose = impact::Pose{};
      break;
    }
    case nb::kHalfSpace: {
      const Eigen::Vector3f nrm(b.e[0], b.e[1], b.e[2]);
      st = out->shapes.add_half_space(nrm, nrm.dot(Eigen::Vector3f(b.p[0], b.p[1], b.p[2])), &id);
      pose = impact::Pose{};
      break;
    }
    default:
      break;
  }
  if (!st.ok()) {
    out->error = st.message();
    return false;
  }
  out->shape_of.push_back(id);
  out->poses.push_back(pose);
  return true;
}

// Pair k of the scene as objects 2k and 2k + 1; false (api->error set) on a bad body.
bool api_scene(const nb::PairScene& s, uint32_t n, ApiScene* api) {
  for (uint32_t k = 0; k < n; ++k) {
    if (!add_body(s, s.a[k], api) || !add_body(s, s.b[k], api)) return false;
    api->pairs.push_back({2 * k, 2 * k + 1});
  }
  return true;
}

void BM_Collide(benchmark::State& state, uint8_t ka, uint8_t kb) {
  const uint32_t n = static_cast<uint32_t>(state.range(0));
  const nb::PairScene& s = nb::pair_scene(ka, kb, n);
  ApiScene api;
  if (!api_scene(s, n, &api)) {
    state.SkipWithError(api.error.c_str());
    return;
  }
  impact::NarrowPhaseOptions options;
  options.exec.threads = static_cast<uint32_t>(state.range(1));
  impact::NarrowPhase phase(options);
  std::vector<impact::Manifold> manifolds;
  const Clock::time_point t0 = Clock::now();  // worker threads: wall time
  for (auto _ : state) {
    const impact::Status st = phase.collide(api.shapes, api.shape_of, api.poses, api.pairs, &manifolds);
    if (!st.ok()) {
      state.SkipWithError(st.message().c_str());
      return;
    }
    benchmark::DoNotOptimize(manifolds.data());
  }
  const double ns = std::chrono::duration<double, std::nano>(Clock::now() - t0).count();
  std::vector<uint8_t> hit(n, 0);
  for (const impact::Manifold& m : manifolds) hit[m.pair] = 1;
  set_pair_counters(state, s, ns, manifolds.size(),
                    nb::disagreements(s, [&](uint32_t k) { return hit[k] != 0; }));
}

// The batch form over caller-owned arrays (NarrowPhase::collide_arrays), on the scene
// of BM_Collide: the public call's cost beyond BM_Kernel.
void BM_CollideArrays(benchmark::State& state, uint8_t ka, uint8_t kb) {
  const uint32_t n = static_cast<uint32_t>(state.range(0));
  const nb::PairScene& s = nb::pair_scene(ka, kb, n);
  ApiScene api;
  if (!api_scene(s, n, &api)) {
    state.SkipWithError(api.error.c_str());
    return;
  }
  std::vector<float> pose[7];
  for (const impact::Pose& p : api.poses) {
    const float v[7] = {p.position.x(),    p.position.y(),    p.position.z(),   p.orientation.x(),
                        p.orientation.y(), p.orientation.z(), p.orientation.w()};
    for (int i = 0; i < 7; ++i) pose[i].push_back(v[i]);
  }
  const impact::PoseArrays poses{pose[0], pose[1], pose[2], pose[3], pose[4], pose[5], pose[6]};
  std::vector<uint8_t> count(n);
  std::vector<float> f[4 + 16];
  for (auto& v : f) v.assign(n, 0.0f);
  impact::PairContactArrays out;
  out.count = count;
  out.normal_x = f[0];
  out.normal_y = f[1];
  out.normal_z = f[2];
  out.depth = f[3];
  for (int k = 0; k < 4; ++k) {
    out.point_x[k] = f[4 + 4 * k];
    out.point_y[k] = f[5 + 4 * k];
    out.point_z[k] = f[6 + 4 * k];
    out.point_depth[k] = f[7 + 4 * k];
  }
  impact::NarrowPhaseOptions options;
  options.exec.threads = static_cast<uint32_t>(state.range(1));
  impact::NarrowPhase phase(options);
  const Clock::time_point t0 = Clock::now();  // worker threads: wall time
  for (auto _ : state) {
    const impact::Status st = phase.collide_arrays(api.shapes, api.shape_of, poses, api.pairs, out);
    if (!st.ok()) {
      state.SkipWithError(st.message().c_str());
      return;
    }
    benchmark::DoNotOptimize(count.data());
    benchmark::ClobberMemory();
  }
  const double ns = std::chrono::duration<double, std::nano>(Clock::now() - t0).count();
  uint64_t hits = 0;
  for (uint32_t k = 0; k < n; ++k) hits += count[k] > 0 ? 1 : 0;
  set_pair_counters(state, s, ns, hits, nb::disagreements(s, [&](uint32_t k) { return count[k] > 0; }));
}

// --- registration ---------------------------------------------------------------------------

void register_all() {
  for (const nb::PairKind& pk : nb::kPairKinds) {
    const std::string name = nb::pair_name(pk.a, pk.b);
    for (const auto& [path, path_name] :
         {std::pair{kn::KernelPath::kScalar, "scalar"}, std::pair{kn::KernelPath::kSimd, "simd"}}) {
      benchmark::RegisterBenchmark(("BM_Kernel/" + name + "/" + path_name).c_str(), BM_Kernel, pk.a, pk.b,
                                   path)
          ->Arg(k512)
          ->Arg(k4k)
          ->Arg(k64k)
          ->Unit(benchmark::kMicrosecond);
    }
    benchmark::RegisterBenchmark(("BM_Collide/" + name).c_str(), BM_Collide, pk.a, pk.b)
        ->ArgsProduct({{k4k, k64k}, impact::bench::bench_thread_counts()})
        ->UseRealTime()
        ->Unit(benchmark::kMicrosecond);
    benchmark::RegisterBenchmark(("BM_CollideArrays/" + name).c_str(), BM_CollideArrays, pk.a, pk.b)
        ->ArgsProduct({{k4k, k64k}, impact::bench::bench_thread_counts()})
        ->UseRealTime()
        ->Unit(benchmark::kMicrosecond);
    nb::register_peer_benchmarks(pk.a, pk.b);
  }
}

}  // namespace

int main(int argc, char** argv) {
  register_all();
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
