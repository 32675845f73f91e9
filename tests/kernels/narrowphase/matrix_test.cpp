// Every narrow-phase kernel of the (leaf type, leaf type) matrix against the
// independent double-precision reference of tests/support/narrow_reference.h
// (support-function overlap minimised over directions: no GJK, EPA or SAT), on both
// paths (cfg.path = kScalar and kSimd).
//
// Per lane, with s / n_ref the reference's signed overlap / normal and tol the pair's
// tolerance (below):
//  (a) hit agreement: count > 0 iff s > 0, except when |s| <= tol (either accepted);
//  (b) depth: |depth - s| <= tol;
//  (c) normal: finite and unit; it must be as good a separating direction as the
//      reference's: o(n) <= s + tol, where o is the reference's overlap along n; where
//      the minimum is unique (everything outside a cone of kAngleTol around n_ref
//      overlaps by more than s + 2 tol) also angle(n, n_ref) <= kAngleTol. Against a
//      half-space the normal is exactly minus the plane normal (angle <= 1e-4 rad);
//  (d) every contact point (count <= 4, finite) lies within depth/2 + 2 tol of both
//      surfaces (exact signed distances for sphere, capsule, box, triangle, plane; the
//      support-based signed distance for hulls, cylinders, ellipsoids), with
//      -tol <= pdepth <= depth + tol, and the deepest point carries the depth
//      (max pdepth >= depth - tol);
//  (e) safe displacement: moving B by n*(depth + tol) separates along n
//      (o(n) <= depth + tol), and moving it by n*(depth - 2 tol) leaves it overlapping
//      by the reference (a fresh reference solve for the moved B).
// tol = rel * L, L = the larger bounding radius, rel = 1e-4 for the specialised kernels
// (sphere/capsule/box/triangle/half-space pairs of pair_kernels.h, triangle-triangle,
// sphere-hull, capsule-hull, hull-triangle, sphere-ellipsoid, capsule-ellipsoid,
// ellipsoid-triangle, ellipsoid-ellipsoid, capsule-cylinder, box-cylinder, cylinder-cylinder,
// cylinder-ellipsoid, cylinder-triangle, hull-half-space and box-hull, whose SAT box-hull route is exact: sat.cpp),
// 1e-3 for the general GJK/EPA and support kernels (100x cfg.epa_tolerance); the inputs
// are exact floats, so poses far from the origin get no extra depth tolerance; contact
// points, being world floats, get one ulp of the largest coordinate on top (0.008 at 1e5).
//
// Scenarios per pair: random poses and sizes (about half overlapping), tiny (1e-4) and
// huge (1e4) shapes, poses 1e5 from the origin, deep penetration, coincident centres,
// touching (B moved by the reference's s*n); near-parallel capsules, box-box with
// near-parallel edges, needle (1 x 1e-4 x 1e-4) and pancake (1 x 1 x 1e-4) boxes in
// every box pair. Also: range-partition independence and no writes past the range;
// symmetry (same-type pairs: swapping A and B keeps the depth and flips the normal);
// boxes through SAT, through collide_gjk_epa and as 8-vertex hulls agree; exact
// touching gives count 0.
//
// A failure prints the lane as C++ literals (LeafSoA fields of A and B, the hull's
// local vertices for convex leaves), the reference and the kernel's answer.
#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cfloat>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "host/narrowphase/shape_store.h"
#include "kernels/narrowphase/pair_kernels.h"
#include "support/narrow_reference.h"
#include "support/random_input.h"
#include "support/test_support.h"

namespace impact::test {
namespace {

using kernels::LeafType;
using nref::V3;
namespace k = kernels;

constexpr double kAngleTol = 0.02;  // rad, where the minimum is unique
constexpr double kHalfSpaceAngleTol = 1e-4;

// ---------------------------------------------------------------------------------------
// Float leaves and buckets
// ---------------------------------------------------------------------------------------

struct LeafF {
  LeafType t = k::kLeafSphere;
  float p[3] = {0, 0, 0};
  float r[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  float e[3] = {0, 0, 0};
  float w[6] = {0, 0, 0, 0, 0, 0};
  uint32_t ref = 0;
};

float f32(double v) { return static_cast<float>(v); }

struct Bucket {
  uint32_t n = 0, cap = 0;
  std::vector<float> p[3], r[9], e[3], w[6];
  std::vector<uint32_t> ref;

  explicit Bucket(const std::vector<LeafF>& leaves) {
    n = static_cast<uint32_t>(leaves.size());
    cap = (n + 15) / 16 * 16 + 16;
    for (auto& v : p) v.resize(cap);
    for (auto& v : r) v.resize(cap);
    for (auto& v : e) v.resize(cap);
    for (auto& v : w) v.resize(cap);
    ref.resize(cap);
    for (uint32_t i = 0; i < cap; ++i) {
      const LeafF& l = leaves[i < n ? i : 0];  // padding: valid copies of lane 0
      for (int j = 0; j < 3; ++j) p[j][i] = l.p[j];
      for (int j = 0; j < 9; ++j) r[j][i] = l.r[j];
      for (int j = 0; j < 3; ++j) e[j][i] = l.e[j];
      for (int j = 0; j < 6; ++j) w[j][i] = l.w[j];
      ref[i] = l.ref;
    }
  }
  k::LeafSoA view() const {
    k::LeafSoA s{};
    for (int j = 0; j < 3; ++j) s.p[j] = p[j].data();
    for (int j = 0; j < 9; ++j) s.r[j] = r[j].data();
    for (int j = 0; j < 3; ++j) s.e[j] = e[j].data();
    for (int j = 0; j < 6; ++j) s.w[j] = w[j].data();
    s.ref = ref.data();
    return s;
  }
};

constexpr uint32_t kPoisonBits = 0x7fc0dead;
constexpr uint8_t kPoisonCount = 0xee;

struct Out {
  uint32_t cap = 0;
  std::vector<uint8_t> count;
  std::vector<float> n[3], depth, pt[4][3], pd[4];
  explicit Out(uint32_t c) : cap(c) {
    count.assign(cap, kPoisonCount);
    const float poison = std::bit_cast<float>(kPoisonBits);
    for (auto& v : n) v.assign(cap, poison);
    depth.assign(cap, poison);
    for (auto& a : pt)
      for (auto& v : a) v.assign(cap, poison);
    for (auto& v : pd) v.assign(cap, poison);
  }
  k::ManifoldSoA view() {
    k::ManifoldSoA m{};
    m.count = count.data();
    for (int j = 0; j < 3; ++j) m.n[j] = n[j].data();
    m.depth = depth.data();
    for (int i = 0; i < 4; ++i) {
      for (int j = 0; j < 3; ++j) m.point[i][j] = pt[i][j].data();
      m.pdepth[i] = pd[i].data();
    }
    return m;
  }
  /// Bytes of lane i (count; the rest only when count > 0).
  std::vector<uint32_t> lane_bits(uint32_t i) const {
    std::vector<uint32_t> b{count[i]};
    if (count[i] == 0 || count[i] == kPoisonCount) return b;
    auto push = [&](float f) { b.push_back(std::bit_cast<uint32_t>(f)); };
    for (auto& v : n) push(v[i]);
    push(depth[i]);
    for (uint32_t q = 0; q < std::min<uint32_t>(count[i], 4); ++q) {
      for (auto& v : pt[q]) push(v[i]);
      push(pd[q][i]);
    }
    return b;
  }
  bool untouched(uint32_t i) const {
    if (count[i] != kPoisonCount) return false;
    for (auto& v : n)
      if (std::bit_cast<uint32_t>(v[i]) != kPoisonBits) return false;
    return std::bit_cast<uint32_t>(depth[i]) == kPoisonBits;
  }
};

// ---------------------------------------------------------------------------------------
// Random geometry
// ---------------------------------------------------------------------------------------

using Rng = std::mt19937;

double uni(Rng& g, double a, double b) { return std::uniform_real_distribution<double>(a, b)(g); }

V3 random_unit(Rng& g) {
  std::normal_distribution<double> d(0.0, 1.0);
  for (;;) {
    const V3 v{d(g), d(g), d(g)};
    if (nref::norm(v) > 1e-3) return nref::normalized(v);
  }
}

/// Rotation (row-major) of angle `a` about unit axis u.
void axis_angle(V3 u, double a, double m[9]) {
  const double c = std::cos(a), s = std::sin(a), t = 1 - c;
  const double r9[9] = {t * u.x * u.x + c,       t * u.x * u.y - s * u.z, t * u.x * u.z + s * u.y,
                        t * u.x * u.y + s * u.z, t * u.y * u.y + c,       t * u.y * u.z - s * u.x,
                        t * u.x * u.z - s * u.y, t * u.y * u.z + s * u.x, t * u.z * u.z + c};
  std::copy(r9, r9 + 9, m);
}

void mat_mul(const double a[9], const double b[9], double out[9]) {
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) out[3 * i + j] = a[3 * i] * b[j] + a[3 * i + 1] * b[3 + j] + a[3 * i + 2] * b[6 + j];
}

void set_r(LeafF& l, const double m[9]) {
  for (int i = 0; i < 9; ++i) l.r[i] = f32(m[i]);
}

/// A brute-force convex hull in double of points in general position or with exactly
/// coplanar faces (every triple's plane that keeps all points on one side is a face;
/// coplanar triples are merged; polygons ordered counter-clockwise from outside).
HullData brute_force_hull(const std::vector<Eigen::Vector3f>& pf) {
  std::vector<V3> P;
  for (const auto& v : pf) P.push_back({v.x(), v.y(), v.z()});
  double scale = 0;
  for (const V3& q : P) scale = std::max(scale, nref::norm(q));
  const double eps = 1e-9 * scale;
  struct Plane {
    V3 n;
    double d;
  };
  std::vector<Plane> planes;
  const size_t m = P.size();
  for (size_t i = 0; i < m; ++i)
    for (size_t j = i + 1; j < m; ++j)
      for (size_t l = j + 1; l < m; ++l) {
        V3 nn = nref::cross(P[j] - P[i], P[l] - P[i]);
        if (nref::norm(nn) < 1e-12 * scale * scale) continue;
        nn = nref::normalized(nn);
        double d = nref::dot(nn, P[i]);
        double hi = -1e300, lo = 1e300;
        for (const V3& q : P) {
          hi = std::max(hi, nref::dot(nn, q) - d);
          lo = std::min(lo, nref::dot(nn, q) - d);
        }
        if (hi > eps && lo < -eps) continue;
        if (hi > eps) {
          nn = -nn;
          d = -d;
        }
        bool dup = false;
        for (const Plane& pl : planes) dup = dup || (nref::dot(pl.n, nn) > 1 - 1e-9 && std::fabs(pl.d - d) < 1e-6 * scale);
        if (!dup) planes.push_back({nn, d});
      }
  HullData h;
  std::vector<int> remap(m, -1);
  for (const Plane& pl : planes) {
    std::vector<size_t> on;
    V3 c;
    for (size_t i = 0; i < m; ++i)
      if (std::fabs(nref::dot(pl.n, P[i]) - pl.d) <= 1e-7 * scale) {
        on.push_back(i);
        c = c + P[i];
      }
    c = (1.0 / static_cast<double>(on.size())) * c;
    V3 t1, t2;
    nref::detail::tangent_basis(pl.n, t1, t2);  // t1 x t2 = n: angles increase counter-clockwise
    std::sort(on.begin(), on.end(), [&](size_t a, size_t b) {
      return std::atan2(nref::dot(P[a] - c, t2), nref::dot(P[a] - c, t1)) <
             std::atan2(nref::dot(P[b] - c, t2), nref::dot(P[b] - c, t1));
    });
    std::vector<uint32_t> face;
    for (size_t i : on) {
      if (remap[i] < 0) {
        remap[i] = static_cast<int>(h.vertices.size());
        h.vertices.push_back(pf[i]);
      }
      face.push_back(static_cast<uint32_t>(remap[i]));
    }
    h.faces.push_back(face);
    h.face_normals.push_back(Eigen::Vector3f(f32(pl.n.x), f32(pl.n.y), f32(pl.n.z)));
    h.face_offsets.push_back(f32(pl.d));
    for (size_t i = 0; i < on.size(); ++i) {
      const V3 ed = nref::normalized(P[on[(i + 1) % on.size()]] - P[on[i]]);
      bool dup = false;
      for (const auto& x : h.edge_dirs)
        dup = dup || std::fabs(nref::dot(ed, V3{x.x(), x.y(), x.z()})) > 1 - 1e-9;
      if (!dup) h.edge_dirs.push_back(Eigen::Vector3f(f32(ed.x), f32(ed.y), f32(ed.z)));
    }
  }
  return h;
}

std::vector<Eigen::Vector3f> box_corners(double hx, double hy, double hz) {
  std::vector<Eigen::Vector3f> c;
  for (int i = 0; i < 8; ++i)
    c.emplace_back(f32((i & 1) ? hx : -hx), f32((i & 2) ? hy : -hy), f32((i & 4) ? hz : -hz));
  return c;
}

/// The hulls of one test (kept alive until the kernels ran), with their local points.
struct HullBank {
  HullStore hulls;
  std::vector<std::vector<Eigen::Vector3f>> hull_points;  // local, per hull, for literals
  uint32_t add_hull(const std::vector<Eigen::Vector3f>& pts) {
    hull_points.push_back(pts);
    return hulls.add(brute_force_hull(pts));
  }
};

/// A leaf of type t centred at c (size ~scale), random orientation and sizes.
LeafF make_leaf(LeafType t, V3 c, double scale, Rng& g, HullBank& w) {
  LeafF l;
  l.t = t;
  double m[9];
  test::random_rotation_rows(g, m);
  auto put_p = [&](V3 q) {
    l.p[0] = f32(q.x);
    l.p[1] = f32(q.y);
    l.p[2] = f32(q.z);
  };
  put_p(c);
  switch (t) {
    case k::kLeafSphere: l.e[0] = f32(scale * uni(g, 0.2, 1.0)); break;
    case k::kLeafCapsule:
    case k::kLeafCylinder:
      set_r(l, m);
      l.e[0] = f32(scale * uni(g, 0.1, t == k::kLeafCapsule ? 0.6 : 1.0));
      l.e[1] = f32(scale * uni(g, 0.1, 1.0));
      break;
    case k::kLeafBox:
    case k::kLeafEllipsoid:
      set_r(l, m);
      for (float& x : l.e) x = f32(scale * uni(g, 0.1, 1.0));
      break;
    case k::kLeafConvex: {
      set_r(l, m);
      std::vector<Eigen::Vector3f> pts;
      if (g() % 3 == 0) {
        pts = box_corners(scale * uni(g, 0.1, 1.0), scale * uni(g, 0.1, 1.0), scale * uni(g, 0.1, 1.0));
      } else {
        const double ax[3] = {uni(g, 0.3, 1.0), uni(g, 0.3, 1.0), uni(g, 0.3, 1.0)};
        const int np = 8 + static_cast<int>(g() % 7);
        for (int i = 0; i < np; ++i) {
          const V3 u = random_unit(g);
          pts.emplace_back(f32(scale * ax[0] * u.x), f32(scale * ax[1] * u.y), f32(scale * ax[2] * u.z));
        }
      }
      l.ref = w.add_hull(pts);
      break;
    }
    case k::kLeafTriangle: {
      V3 q[3];
      for (;;) {
        for (V3& v : q) v = uni(g, 0.2, 1.0) * random_unit(g);
        const V3 mid = (1.0 / 3.0) * (q[0] + q[1] + q[2]);
        for (V3& v : q) v = v - mid;
        if (nref::norm(nref::cross(q[1] - q[0], q[2] - q[0])) > 0.2) break;
      }
      put_p(c + scale * q[0]);
      for (int j = 0; j < 3; ++j) {
        l.w[j] = f32((c + scale * q[1])[j]);
        l.w[3 + j] = f32((c + scale * q[2])[j]);
      }
      break;
    }
    case k::kLeafHalfSpace: {
      const V3 n = random_unit(g);
      l.e[0] = f32(n.x);
      l.e[1] = f32(n.y);
      l.e[2] = f32(n.z);
      break;
    }
    default: break;
  }
  return l;
}

void translate(LeafF& l, V3 t) {
  for (int j = 0; j < 3; ++j) l.p[j] = f32(static_cast<double>(l.p[j]) + t[j]);
  if (l.t == k::kLeafTriangle)
    for (int j = 0; j < 6; ++j) l.w[j] = f32(static_cast<double>(l.w[j]) + t[j % 3]);
}

nref::Shape ref_shape(const LeafF& l, const HullBank& w) {
  const Bucket b({l});
  const k::HullView hv = w.hulls.view();
  return nref::shape_from_leaf(b.view(), 0, l.t, &hv);
}

// ---------------------------------------------------------------------------------------
// Literals for failure reports
// ---------------------------------------------------------------------------------------

std::string flit(float v) {
  char buf[48];
  std::snprintf(buf, sizeof buf, "%.9gf", static_cast<double>(v));
  return buf;
}

std::string literal(const char* name, const LeafF& l, const HullBank& w) {
  std::ostringstream o;
  auto arr = [&](const char* f, const float* v, int n) {
    o << " " << f << "={";
    for (int i = 0; i < n; ++i) o << (i ? ", " : "") << flit(v[i]);
    o << "};";
  };
  o << "    // " << name << ": " << k::leaf_type_name(l.t) << "\n    ";
  arr("p", l.p, 3);
  if (l.t != k::kLeafSphere && l.t != k::kLeafTriangle && l.t != k::kLeafHalfSpace) arr("r", l.r, 9);
  if (l.t != k::kLeafConvex && l.t != k::kLeafTriangle) arr("e", l.e, 3);
  if (l.t == k::kLeafTriangle) arr("w", l.w, 6);
  if (l.t == k::kLeafConvex) {
    o << "\n     hull local vertices={";
    const auto& pts = w.hull_points[l.ref];
    for (size_t i = 0; i < pts.size(); ++i)
      o << (i ? ", " : "") << "{" << flit(pts[i].x()) << ", " << flit(pts[i].y()) << ", " << flit(pts[i].z()) << "}";
    o << "};";
  }
  o << "\n";
  return o.str();
}

// ---------------------------------------------------------------------------------------
// The per-lane check
// ---------------------------------------------------------------------------------------

bool specialised(LeafType a, LeafType b) {
  const auto kp = k::pair_kernel(a, b);
  // Box-hull: the generic entry, whose SAT takes the exact box-hull route (sat.cpp).
  if (a == k::kLeafBox && b == k::kLeafConvex) return true;
  return kp != nullptr &&
         (kp == &k::collide_sphere_sphere || kp == &k::collide_sphere_capsule || kp == &k::collide_sphere_box ||
          kp == &k::collide_capsule_capsule || kp == &k::collide_capsule_box || kp == &k::collide_box_box ||
          kp == &k::collide_sphere_triangle || kp == &k::collide_capsule_triangle ||
          kp == &k::collide_sphere_halfspace || kp == &k::collide_capsule_halfspace ||
          kp == &k::collide_box_halfspace || kp == &k::collide_box_triangle ||
          kp == &k::collide_triangle_triangle || kp == &k::collide_sphere_convex ||
          kp == &k::collide_capsule_convex || kp == &k::collide_convex_triangle ||
          kp == &k::collide_sphere_ellipsoid || kp == &k::collide_capsule_ellipsoid ||
          kp == &k::collide_ellipsoid_triangle || kp == &k::collide_capsule_cylinder ||
          kp == &k::collide_box_cylinder || kp == &k::collide_cylinder_cylinder ||
          kp == &k::collide_box_ellipsoid || kp == &k::collide_convex_ellipsoid ||
          kp == &k::collide_ellipsoid_ellipsoid || kp == &k::collide_cylinder_ellipsoid ||
          kp == &k::collide_cylinder_triangle || kp == &k::collide_convex_halfspace);
}

struct Lane {
  LeafF a, b;
  nref::Shape sa, sb;
  nref::PairResult ref;
};

double coord_magnitude(const nref::Shape& s) {
  double c = std::max({std::fabs(s.p.x), std::fabs(s.p.y), std::fabs(s.p.z)});
  for (const V3& q : s.pts) c = std::max({c, std::fabs(q.x), std::fabs(q.y), std::fabs(q.z)});
  return c;
}

/// Depth / normal tolerance: relative to the shapes' size only (the inputs are exact
/// floats and the kernels work relative to A's position, so poses 1e5 from the origin
/// must not cost accuracy).
double lane_tol(const Lane& l, double rel) { return rel * std::max(l.sa.bound_radius(), l.sb.bound_radius()); }

/// Contact points are world floats: one ulp of the largest coordinate on top.
double point_slack(const Lane& l) {
  return std::max(coord_magnitude(l.sa), coord_magnitude(l.sb)) * std::ldexp(1.0, -23);
}

Lane make_lane(const LeafF& a, const LeafF& b, const HullBank& w) {
  Lane l{a, b, ref_shape(a, w), ref_shape(b, w), {}};
  l.ref = nref::solve_pair(l.sa, l.sb);
  return l;
}

/// Statistics of one (pair, scenario, path).
struct Stats {
  uint32_t lanes = 0, hits = 0, band = 0, failures = 0;
  double worst_depth = 0;  // max |depth - s| / tol
  double worst_rel = 0;    // max |depth - s| / L
  double worst_angle = 0;  // max angle to n_ref where unique
};

struct KernelLane {
  uint32_t count;
  V3 n;
  double depth;
  V3 pt[4];
  double pd[4];
};

KernelLane read_lane(const Out& o, uint32_t i) {
  KernelLane r{};
  r.count = o.count[i];
  r.n = {o.n[0][i], o.n[1][i], o.n[2][i]};
  r.depth = o.depth[i];
  for (uint32_t q = 0; q < 4; ++q) {
    r.pt[q] = {o.pt[q][0][i], o.pt[q][1][i], o.pt[q][2][i]};
    r.pd[q] = o.pd[q][i];
  }
  return r;
}

std::string describe(const KernelLane& kl) {
  std::ostringstream o;
  o.precision(9);
  o << "count=" << kl.count;
  if (kl.count > 0 && kl.count <= 4) {
    o << " n={" << kl.n.x << ", " << kl.n.y << ", " << kl.n.z << "} depth=" << kl.depth;
    for (uint32_t q = 0; q < kl.count; ++q)
      o << "\n      point[" << q << "]={" << kl.pt[q].x << ", " << kl.pt[q].y << ", " << kl.pt[q].z
        << "} pdepth=" << kl.pd[q];
  }
  return o.str();
}

/// Checks one kernel lane against the reference; returns "" or the reasons.
std::string check_lane(const Lane& l, const KernelLane& kl, double tol, Stats& st, bool deep_checks = true) {
  std::ostringstream why;
  why.precision(9);
  const double s = l.ref.s;
  const bool hs = l.sb.type == k::kLeafHalfSpace;
  ++st.lanes;
  const bool in_band = std::fabs(s) <= tol;
  if (in_band) ++st.band;
  if (kl.count > 4) {
    why << " count " << kl.count << " > 4;";
    return why.str();
  }
  const bool hit = kl.count > 0;
  if (hit) ++st.hits;
  if (!in_band && hit != (s > 0)) why << " hit mismatch: reference s=" << s << " (tol " << tol << ");";
  if (!hit) return why.str();
  // (b) depth, normal sanity.
  const double nl = nref::norm(kl.n);
  if (!std::isfinite(kl.depth) || !std::isfinite(nl) || std::fabs(nl - 1) > 1e-5) {
    why << " normal/depth not finite or not unit (|n|=" << nl << ");";
    return why.str();
  }
  const double dd = std::fabs(kl.depth - s);
  st.worst_depth = std::max(st.worst_depth, dd / tol);
  st.worst_rel = std::max(st.worst_rel, dd / std::max(l.sa.bound_radius(), l.sb.bound_radius()));
  if (dd > tol) why << " depth " << kl.depth << " vs reference " << s << " (|diff| " << dd << " > tol " << tol << ");";
  // (c) normal.
  const V3 n = nref::normalized(kl.n);
  const double ang = nref::angle(n, l.ref.n);
  if (hs) {
    if (ang > kHalfSpaceAngleTol) why << " normal off minus the plane normal by " << ang << " rad;";
  } else {
    const double on = nref::overlap(l.sa, l.sb, n);
    // o(n) >= s for every n; a kernel normal below the reference's minimum means the
    // reference missed the global minimum (a failure of the reference, not the kernel).
    if (on < s - 1e-9 * std::max(1.0, std::fabs(s))) why << " REFERENCE missed a minimum: o(n_kernel)=" << on << " < s;";
    if (on > s + tol) why << " normal is not a minimum direction: o(n)=" << on << " > s+tol=" << s + tol << ";";
    if (l.ref.unique(2 * tol)) {
      st.worst_angle = std::max(st.worst_angle, ang);
      if (ang > kAngleTol) why << " normal " << ang << " rad from the unique reference normal;";
    }
    // (e) safe displacement along n.
    if (on > kl.depth + tol) why << " moving B by n*(depth+tol) does not separate: o(n)=" << on << ";";
  }
  if (deep_checks && kl.depth > 3 * tol && s > 3 * tol) {
    const double still = nref::solve_pair(l.sa, l.sb, (kl.depth - 2 * tol) * n).s;
    if (!(still > 0)) why << " moving B by n*(depth-2tol) already separates (reference s'=" << still << ");";
  }
  // (d) contact points.
  nref::Options light;
  light.samples = 1000;
  light.starts = 3;
  for (uint32_t q = 0; q < kl.count; ++q) {
    const V3 x = kl.pt[q];
    if (!std::isfinite(x.x) || !std::isfinite(x.y) || !std::isfinite(x.z) || !std::isfinite(kl.pd[q])) {
      why << " point " << q << " not finite;";
      continue;
    }
    if (kl.pd[q] < -tol || kl.pd[q] > kl.depth + tol) why << " pdepth[" << q << "]=" << kl.pd[q] << " outside [-tol, depth+tol];";
    if (!deep_checks) continue;
    const double da = nref::signed_distance(l.sa, x, light), db = nref::signed_distance(l.sb, x, light);
    const double lim = 0.5 * std::max(kl.depth, 0.0) + 2 * tol + point_slack(l);
    if (std::fabs(da) > lim || std::fabs(db) > lim)
      why << " point " << q << " off the surfaces: sd_A=" << da << " sd_B=" << db << " (limit " << lim << ");";
  }
  if (kl.count > 0) {
    double deepest = -1e300;
    for (uint32_t q = 0; q < kl.count; ++q) deepest = std::max(deepest, static_cast<double>(kl.pd[q]));
    if (deepest < kl.depth - tol) why << " DEEPEST point carries " << deepest << " of depth " << kl.depth << ";";
  }
  return why.str();
}

// ---------------------------------------------------------------------------------------
// Running a kernel on a lane set
// ---------------------------------------------------------------------------------------

Out run(k::PairKernel kern, const std::vector<Lane>& lanes, const HullBank& w, k::KernelPath path,
        bool swap = false) {
  std::vector<LeafF> la, lb;
  for (const Lane& l : lanes) {
    la.push_back(swap ? l.b : l.a);
    lb.push_back(swap ? l.a : l.b);
  }
  const Bucket a(la), b(lb);
  Out out(a.cap);
  k::NarrowConfig cfg;
  cfg.path = path;
  cfg.hulls = w.hulls.view();
  kern(a.view(), b.view(), out.view(), k::Range{0, a.n}, cfg);
  return out;
}

const char* path_name(k::KernelPath p) { return p == k::KernelPath::kSimd ? "simd" : "scalar"; }

/// Runs both paths over the lanes and checks every lane; failures go to the test log.
void check_all(k::PairKernel kern, const std::vector<Lane>& lanes, const HullBank& w, double rel,
               const std::string& what, bool deep_checks = true) {
  for (k::KernelPath path : {k::KernelPath::kScalar, k::KernelPath::kSimd}) {
    const Out out = run(kern, lanes, w, path);
    Stats st;
    int printed = 0;
    for (uint32_t i = 0; i < lanes.size(); ++i) {
      const KernelLane kl = read_lane(out, i);
      const double tol = lane_tol(lanes[i], rel);
      const std::string why = check_lane(lanes[i], kl, tol, st, deep_checks);
      if (why.empty()) continue;
      ++st.failures;
      if (printed++ < 3) {
        ADD_FAILURE() << what << " [" << path_name(path) << "] lane " << i << ":" << why << "\n"
                      << literal("A", lanes[i].a, w) << literal("B", lanes[i].b, w) << "    reference: s="
                      << lanes[i].ref.s << " n={" << lanes[i].ref.n.x << ", " << lanes[i].ref.n.y << ", "
                      << lanes[i].ref.n.z << "}" << (lanes[i].ref.unique(2 * tol) ? " (unique)" : " (not unique)")
                      << "\n    kernel:    " << describe(kl);
      }
    }
    for (uint32_t i = static_cast<uint32_t>(lanes.size()); i < out.cap; ++i)
      if (!out.untouched(i)) {
        ADD_FAILURE() << what << " [" << path_name(path) << "] wrote lane " << i << " past the range end "
                      << lanes.size();
        break;
      }
    std::printf("  %-32s %-6s lanes %3u hits %3u band %2u fail %2u | worst |depth-s|: %.2g tol, %.2g L; angle %.2g\n",
                what.c_str(), path_name(path), st.lanes, st.hits, st.band, st.failures, st.worst_depth,
                st.worst_rel, st.worst_angle);
  }
}

// ---------------------------------------------------------------------------------------
// Scenarios
// ---------------------------------------------------------------------------------------

struct PairCase {
  LeafType a, b;
};

std::string case_name(const PairCase& c) {
  std::string s = std::string(k::leaf_type_name(c.a)) + "_" + k::leaf_type_name(c.b);
  std::replace(s.begin(), s.end(), '-', '_');
  return s;
}

void PrintTo(const PairCase& c, std::ostream* os) { *os << case_name(c); }

/// Pairs whose general-path kernel (GJK/EPA) does not yet meet this test's tolerances
/// (issue 4, open; the closing note has the measured errors). They run as
/// DISABLED_KnownFailing/PairMatrix.* (--gtest_also_run_disabled_tests shows them).
bool known_failing(const PairCase& c);

/// Every (ta, tb) pair with ta <= tb except half-space/half-space; `failing` selects
/// the known-failing ones or the rest.
std::vector<PairCase> all_pairs(bool failing) {
  std::vector<PairCase> v;
  for (uint8_t a = 0; a < k::kLeafTypeCount; ++a)
    for (uint8_t b = a; b < k::kLeafTypeCount; ++b)
      if (!(a == k::kLeafHalfSpace && b == k::kLeafHalfSpace)) {
        const PairCase c{static_cast<LeafType>(a), static_cast<LeafType>(b)};
        if (known_failing(c) == failing) v.push_back(c);
      }
  return v;
}

bool known_failing(const PairCase& c) {
  static const char* const kNames[] = {""};  // none today
  const std::string name = case_name(c);
  for (const char* n : kNames)
    if (name == n) return true;
  return false;
}

/// A at c (size scale); B placed at lambda * (bound radii) from A along a random direction
/// (B a half-space: its plane lambda * A's radius from A's centre).
std::pair<LeafF, LeafF> place_pair(LeafType ta, LeafType tb, V3 c, double scale, double lambda, Rng& g, HullBank& w) {
  LeafF a = make_leaf(ta, c, scale, g, w);
  LeafF b = make_leaf(tb, {0, 0, 0}, scale, g, w);
  const double ra = ref_shape(a, w).bound_radius();
  const V3 ca = ref_shape(a, w).centre();
  if (tb == k::kLeafHalfSpace) {
    const V3 n{b.e[0], b.e[1], b.e[2]};
    translate(b, ca + lambda * ra * n);
  } else {
    const double rb = ref_shape(b, w).bound_radius();
    const V3 cb0 = ref_shape(b, w).centre();
    translate(b, ca + lambda * (ra + rb) * random_unit(g) - cb0);
  }
  return {a, b};
}

/// Random lanes, about half overlapping (by the reference), at the given scale/offset.
std::vector<Lane> random_lanes(const PairCase& pc, uint32_t n, double scale, double offset, double lam_lo,
                               double lam_hi, Rng& g, HullBank& w,
                               LeafF (*mutate)(const LeafF&, Rng&, HullBank&) = nullptr) {
  std::vector<Lane> lanes;
  uint32_t over = 0, sep = 0;
  for (uint32_t attempt = 0; attempt < 40 * n && lanes.size() < n; ++attempt) {
    V3 c = scale * V3{uni(g, -1, 1), uni(g, -1, 1), uni(g, -1, 1)};
    if (offset != 0)
      c = c + V3{(g() & 1) ? offset : -offset, (g() & 1) ? offset : -offset, (g() & 1) ? offset : -offset};
    const double lo = pc.b == k::kLeafHalfSpace ? -1.2 : lam_lo;
    auto [a, b] = place_pair(pc.a, pc.b, c, scale, uni(g, lo, lam_hi), g, w);
    if (mutate != nullptr) {
      if (a.t == k::kLeafBox) a = mutate(a, g, w);
      if (b.t == k::kLeafBox && (a.t != k::kLeafBox || (g() & 1))) b = mutate(b, g, w);
    }
    Lane l = make_lane(a, b, w);
    const bool is_over = l.ref.s > 0;
    const bool last_tries = attempt >= 30 * n;
    if (is_over && over >= (n + 1) / 2 && !last_tries) continue;
    if (!is_over && sep >= n / 2 && !last_tries) continue;
    (is_over ? over : sep)++;
    lanes.push_back(std::move(l));
  }
  return lanes;
}

LeafF thin_box(const LeafF& box, Rng& g, HullBank&) {
  LeafF b = box;
  const double big = std::max({b.e[0], b.e[1], b.e[2]}) * 1.5;
  const bool needle = g() & 1;
  b.e[0] = f32(big);
  b.e[1] = f32(needle ? big * 1e-4 : big);
  b.e[2] = f32(big * 1e-4);
  return b;
}

class PairMatrix : public ::testing::TestWithParam<PairCase> {};

TEST_P(PairMatrix, AgainstReference) {
  const PairCase pc = GetParam();
  const k::PairKernel kern = k::pair_kernel(pc.a, pc.b);
  ASSERT_NE(kern, nullptr);
  const double rel = specialised(pc.a, pc.b) ? 1e-4 : 1e-3;
  const std::string name = case_name(pc);
  Rng g(1000u + 16u * pc.a + pc.b);
  HullBank w;
  // All lane sets are made first: HullStore may reallocate while hulls are added.
  struct Set {
    std::string what;
    std::vector<Lane> lanes;
  };
  std::vector<Set> sets;
  sets.push_back({name + " random", random_lanes(pc, scaled(96), 1.0, 0.0, 0.0, 1.1, g, w)});
  sets.push_back({name + " tiny 1e-4", random_lanes(pc, scaled(12), 1e-4, 0.0, 0.0, 1.1, g, w)});
  sets.push_back({name + " huge 1e4", random_lanes(pc, scaled(12), 1e4, 0.0, 0.0, 1.1, g, w)});
  sets.push_back({name + " far 1e5", random_lanes(pc, scaled(12), 1.0, 1e5, 0.0, 1.1, g, w)});
  sets.push_back({name + " deep", random_lanes(pc, scaled(16), 1.0, 0.0, 0.0, 0.05, g, w)});
  {
    std::vector<Lane> co;
    for (uint32_t i = 0; i < scaled(6); ++i) {
      const V3 c{uni(g, -1, 1), uni(g, -1, 1), uni(g, -1, 1)};
      auto [a, b] = place_pair(pc.a, pc.b, c, 1.0, 0.0, g, w);
      co.push_back(make_lane(a, b, w));
    }
    sets.push_back({name + " coincident", std::move(co)});
  }
  {
    // Touching: overlapping random lanes with B moved by the reference's s * n.
    std::vector<Lane> touch;
    for (const Lane& l : sets[0].lanes) {
      if (l.ref.s <= 0) continue;
      LeafF b = l.b;
      translate(b, l.ref.s * l.ref.n);
      touch.push_back(make_lane(l.a, b, w));
      if (touch.size() >= scaled(8)) break;
    }
    sets.push_back({name + " touching", std::move(touch)});
  }
  if (pc.a == k::kLeafBox || pc.b == k::kLeafBox)
    sets.push_back({name + " needle/pancake", random_lanes(pc, scaled(16), 1.0, 0.0, 0.0, 1.1, g, w, &thin_box)});
  if (pc.a == k::kLeafCapsule && pc.b == k::kLeafCapsule) {
    std::vector<Lane> par;
    const double angles[] = {0.0, 1e-7, 1e-6, 1e-5, 1e-4, 1e-3};
    for (uint32_t i = 0; i < scaled(18); ++i) {
      LeafF a = make_leaf(k::kLeafCapsule, {uni(g, -1, 1), uni(g, -1, 1), uni(g, -1, 1)}, 1.0, g, w);
      LeafF b = make_leaf(k::kLeafCapsule, {0, 0, 0}, 1.0, g, w);
      const nref::Shape sa = ref_shape(a, w);
      const V3 u = sa.col(2);
      const V3 perp = nref::normalized(nref::cross(u, random_unit(g)));
      double rot[9], ra9[9], rb9[9];
      axis_angle(perp, angles[i % 6], rot);
      for (int j = 0; j < 9; ++j) ra9[j] = a.r[j];
      mat_mul(rot, ra9, rb9);
      set_r(b, rb9);
      const V3 q = nref::normalized(nref::cross(u, perp));
      const double d = uni(g, 0.3, 1.1) * (a.e[0] + b.e[0]);
      translate(b, sa.p + d * q + uni(g, -1, 1) * (a.e[1] + b.e[1]) * u);
      par.push_back(make_lane(a, b, w));
    }
    sets.push_back({name + " near-parallel", std::move(par)});
  }
  if (pc.a == k::kLeafBox && pc.b == k::kLeafBox) {
    std::vector<Lane> ee;
    const double angles[] = {0.0, 1e-7, 1e-5, 1e-3};
    for (uint32_t i = 0; i < scaled(16); ++i) {
      LeafF a = make_leaf(k::kLeafBox, {uni(g, -1, 1), uni(g, -1, 1), uni(g, -1, 1)}, 1.0, g, w);
      LeafF b = make_leaf(k::kLeafBox, {0, 0, 0}, 1.0, g, w);
      const nref::Shape sa = ref_shape(a, w);
      double rot[9], ra9[9], rb9[9];
      axis_angle(random_unit(g), angles[i % 4], rot);
      for (int j = 0; j < 9; ++j) ra9[j] = a.r[j];
      mat_mul(ra9, rot, rb9);
      set_r(b, rb9);
      // Edge along A's z against B's nearly parallel edge: diagonal offset in A's xy.
      const double f = uni(g, 0.97, 1.02);
      const double sx = (g() & 1) ? 1 : -1, sy = (g() & 1) ? 1 : -1;
      const V3 off = f * sx * (a.e[0] + b.e[0]) * sa.col(0) + f * sy * (a.e[1] + b.e[1]) * sa.col(1) +
                     uni(g, -0.5, 0.5) * sa.col(2);
      translate(b, sa.p + off);
      ee.push_back(make_lane(a, b, w));
    }
    sets.push_back({name + " edge-edge near-parallel", std::move(ee)});
  }
  std::printf("%s (tolerance rel %.0e)\n", name.c_str(), rel);
  for (const Set& s : sets) check_all(kern, s.lanes, w, rel, s.what);

  // Range partition: the SIMD path over [0, 3) + [3, 11) + [11, n) gives the same bytes.
  {
    const auto& lanes = sets[0].lanes;
    const Out whole = run(kern, lanes, w, k::KernelPath::kSimd);
    std::vector<LeafF> la, lb;
    for (const Lane& l : lanes) {
      la.push_back(l.a);
      lb.push_back(l.b);
    }
    const Bucket a(la), b(lb);
    Out part(a.cap);
    k::NarrowConfig cfg;
    cfg.hulls = w.hulls.view();
    const uint32_t cuts[] = {0, std::min(3u, a.n), std::min(11u, a.n), a.n};
    for (int c = 0; c < 3; ++c) kern(a.view(), b.view(), part.view(), k::Range{cuts[c], cuts[c + 1]}, cfg);
    for (uint32_t i = 0; i < a.n; ++i)
      EXPECT_EQ(whole.lane_bits(i), part.lane_bits(i)) << name << " lane " << i << " depends on the range partition";
  }
  // Symmetry: same-type pairs swapped flip the normal and keep the depth.
  if (pc.a == pc.b) {
    const auto& lanes = sets[0].lanes;
    for (k::KernelPath path : {k::KernelPath::kScalar, k::KernelPath::kSimd}) {
      const Out ab = run(kern, lanes, w, path);
      const Out ba = run(kern, lanes, w, path, /*swap=*/true);
      int printed = 0;
      for (uint32_t i = 0; i < lanes.size(); ++i) {
        const double tol = lane_tol(lanes[i], rel);
        if (std::fabs(lanes[i].ref.s) <= tol) continue;
        const KernelLane x = read_lane(ab, i), y = read_lane(ba, i);
        std::string why;
        if ((x.count > 0) != (y.count > 0)) why = " hit differs when swapped";
        else if (x.count > 0) {
          if (std::fabs(x.depth - y.depth) > tol) why = " depth differs when swapped";
          const double ang = nref::angle(x.n, -y.n);
          const double o_swapped = nref::overlap(lanes[i].sa, lanes[i].sb, nref::normalized(-y.n));
          if (ang > kAngleTol && o_swapped > lanes[i].ref.s + tol) why += " swapped normal is not -n";
        }
        if (!why.empty() && printed++ < 3)
          ADD_FAILURE() << name << " [" << path_name(path) << "] symmetry lane " << i << ":" << why << "\n"
                        << literal("A", lanes[i].a, w) << literal("B", lanes[i].b, w) << "    A,B: " << describe(x)
                        << "\n    B,A: " << describe(y);
      }
    }
  }
}

INSTANTIATE_TEST_SUITE_P(All, PairMatrix, ::testing::ValuesIn(all_pairs(false)),
                         [](const ::testing::TestParamInfo<PairCase>& i) { return case_name(i.param); });
INSTANTIATE_TEST_SUITE_P(DISABLED_KnownFailing, PairMatrix, ::testing::ValuesIn(all_pairs(true)),
                         [](const ::testing::TestParamInfo<PairCase>& i) { return case_name(i.param); });
GTEST_ALLOW_UNINSTANTIATED_PARAMETERIZED_TEST(PairMatrix);

// ---------------------------------------------------------------------------------------
// Boxes three ways: the box-box kernel (pair_kernel), the general polytope route
// (collide_sat_or_gjk_epa: cvx SAT at the default sat_max_vertices), and 8-vertex hulls
// (pair_kernel: the same route).
// ---------------------------------------------------------------------------------------

TEST(NarrowMatrix, BoxesThroughSatGjkAndHullAgree) {
  Rng g(77);
  HullBank w;
  const PairCase pc{k::kLeafBox, k::kLeafBox};
  std::vector<Lane> lanes = random_lanes(pc, scaled(48), 1.0, 0.0, 0.0, 1.1, g, w);
  // The same boxes as convex hulls (local corners, same pose).
  std::vector<Lane> hl;
  for (const Lane& l : lanes) {
    LeafF a = l.a, b = l.b;
    for (LeafF* x : {&a, &b}) {
      x->t = k::kLeafConvex;
      x->ref = w.add_hull(box_corners(x->e[0], x->e[1], x->e[2]));
    }
    hl.push_back(make_lane(a, b, w));
  }
  auto gjk_boxes = [](const k::LeafSoA& a, const k::LeafSoA& b, const k::ManifoldSoA& o, k::Range r,
                      const k::NarrowConfig& cfg) {
    k::collide_sat_or_gjk_epa(a, b, o, r, cfg, k::kLeafBox, k::kLeafBox);
  };
  std::printf("boxes three ways\n");
  check_all(k::pair_kernel(k::kLeafBox, k::kLeafBox), lanes, w, 1e-4, "box-box SAT");
  check_all(gjk_boxes, lanes, w, 1e-3, "box-box general route");
  check_all(k::pair_kernel(k::kLeafConvex, k::kLeafConvex), hl, w, 1e-3, "box hulls general route");
  const Out sat = run(k::pair_kernel(k::kLeafBox, k::kLeafBox), lanes, w, k::KernelPath::kScalar);
  const Out gjk = run(gjk_boxes, lanes, w, k::KernelPath::kScalar);
  const Out hul = run(k::pair_kernel(k::kLeafConvex, k::kLeafConvex), hl, w, k::KernelPath::kScalar);
  for (uint32_t i = 0; i < lanes.size(); ++i) {
    const double tol = lane_tol(lanes[i], 1e-3);
    if (std::fabs(lanes[i].ref.s) <= tol) continue;
    for (const Out* o : {&gjk, &hul}) {
      const KernelLane x = read_lane(sat, i), y = read_lane(*o, i);
      EXPECT_EQ(x.count > 0, y.count > 0) << "lane " << i << (o == &gjk ? " gjk" : " hull");
      if (x.count > 0 && y.count > 0) {
        EXPECT_NEAR(x.depth, y.depth, tol) << "lane " << i << (o == &gjk ? " gjk" : " hull");
      }
    }
  }
}

// ---------------------------------------------------------------------------------------
// Exact touching (representable configurations): count 0 per the contract.
// ---------------------------------------------------------------------------------------

TEST(NarrowMatrix, ExactTouchingIsNoContact) {
  HullBank w;
  auto leaf = [](LeafType t, std::initializer_list<float> p, std::initializer_list<float> e) {
    LeafF l;
    l.t = t;
    std::copy(p.begin(), p.end(), l.p);
    std::copy(e.begin(), e.end(), l.e);
    return l;
  };
  auto along_x = [](LeafF l) {  // axis z -> x: R columns (0,0,-1)? use x = R col 2
    const float r[9] = {0, 0, 1, 0, 1, 0, -1, 0, 0};
    std::copy(r, r + 9, l.r);
    return l;
  };
  auto tri = [](std::initializer_list<float> v) {
    LeafF l;
    l.t = k::kLeafTriangle;
    std::vector<float> x(v);
    for (int j = 0; j < 3; ++j) l.p[j] = x[static_cast<size_t>(j)];
    for (int j = 0; j < 6; ++j) l.w[j] = x[static_cast<size_t>(3 + j)];
    return l;
  };
  struct Case {
    LeafF a, b;
  };
  const std::vector<Case> cases = {
      {leaf(k::kLeafSphere, {0, 0, 0}, {1}), leaf(k::kLeafSphere, {2, 0, 0}, {1})},
      {leaf(k::kLeafSphere, {0.5f, 0.25f, 1}, {0.75f}), leaf(k::kLeafSphere, {0.5f, 1.5f, 1}, {0.5f})},
      {leaf(k::kLeafSphere, {1.5f, 0, 0}, {0.5f}), leaf(k::kLeafBox, {0, 0, 0}, {1, 2, 3})},
      {leaf(k::kLeafSphere, {1, 0, 0.25f}, {0.5f}), leaf(k::kLeafCapsule, {0, 0, 0}, {0.5f, 1})},
      {leaf(k::kLeafCapsule, {0, 0, 0}, {0.5f, 1}), leaf(k::kLeafCapsule, {1, 0, 0}, {0.5f, 1})},
      {along_x(leaf(k::kLeafCapsule, {0, 0, 1.5f}, {0.5f, 0.5f})), leaf(k::kLeafBox, {0, 0, 0}, {1, 1, 1})},
      {leaf(k::kLeafBox, {0, 0, 0}, {1, 1, 1}), leaf(k::kLeafBox, {2, 0.5f, 0}, {1, 1, 1})},
      {leaf(k::kLeafSphere, {0.25f, 0.25f, 0.5f}, {0.5f}), tri({0, 0, 0, 1, 0, 0, 0, 1, 0})},
      {along_x(leaf(k::kLeafCapsule, {0.25f, 0.25f, 0.5f}, {0.5f, 0.125f})), tri({0, 0, 0, 1, 0, 0, 0, 1, 0})},
      {tri({0, 0, 0, 2, 0, 0, 0, 2, 0}), tri({0.5f, 0.5f, 0, 1, 0.5f, 1, 0.5f, 1, 1})},    // vertex on a face
      {tri({0, 0, 0, 0, 2, 0, 1, 1, 0}), tri({0, 0, 0, 0, 2, 0, 0, 1, 1})},                // hinged on an edge
      {tri({0, 0, 0, 2, 0, 0, 0, 2, 0}), tri({0.5f, 0.5f, 0, 3, 0.5f, 0, 0.5f, 3, 0})},  // coplanar overlap
      {leaf(k::kLeafSphere, {0, 0, 1}, {1}), leaf(k::kLeafHalfSpace, {0, 0, 0}, {0, 0, 1})},
      {along_x(leaf(k::kLeafCapsule, {0, 0, 0.5f}, {0.5f, 2})), leaf(k::kLeafHalfSpace, {0, 0, 0}, {0, 0, 1})},
      {leaf(k::kLeafBox, {0, 0, 1}, {1, 2, 1}), leaf(k::kLeafHalfSpace, {0, 0, 0}, {0, 0, 1})},
      // General kernels.
      {leaf(k::kLeafCylinder, {0, 0, 1}, {0.5f, 1}), leaf(k::kLeafHalfSpace, {0, 0, 0}, {0, 0, 1})},
      {leaf(k::kLeafEllipsoid, {0, 0, 0.5f}, {1, 2, 0.5f}), leaf(k::kLeafHalfSpace, {0, 0, 0}, {0, 0, 1})},
      {leaf(k::kLeafBox, {0, 0, 0}, {1, 1, 1}), leaf(k::kLeafCylinder, {0, 0, 3}, {0.5f, 2})},
      {leaf(k::kLeafBox, {0, 0, 0}, {1, 1, 1}), leaf(k::kLeafEllipsoid, {2, 0, 0}, {1, 0.5f, 0.5f})},
  };
  for (size_t i = 0; i < cases.size(); ++i) {
    const Case& c = cases[i];
    const bool spec = specialised(c.a.t, c.b.t);
    const Lane l = make_lane(c.a, c.b, w);
    ASSERT_NEAR(l.ref.s, 0.0, 1e-12) << "case " << i << " is not touching by the reference";
    for (k::KernelPath path : {k::KernelPath::kScalar, k::KernelPath::kSimd}) {
      const Out o = run(k::pair_kernel(c.a.t, c.b.t), {l}, w, path);
      const KernelLane kl = read_lane(o, 0);
      const std::string label = std::string(k::leaf_type_name(c.a.t)) + "-" + k::leaf_type_name(c.b.t) + " case " +
                                std::to_string(i) + " [" + path_name(path) + "]";
      if (spec) {
        EXPECT_EQ(kl.count, 0u) << label << ": exact touching must be no contact\n"
                                << literal("A", c.a, w) << literal("B", c.b, w) << "    kernel: " << describe(kl);
      } else if (kl.count > 0) {
        EXPECT_LE(kl.depth, lane_tol(l, 1e-3)) << label << "\n" << describe(kl);
      }
    }
  }
}

}  // namespace
}  // namespace impact::test
