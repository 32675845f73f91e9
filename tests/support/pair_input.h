// Input of the table-wide narrow-phase tests (matrix_test, contract_test): a random posed
// leaf of every type (float, as the kernel reads it), hulls by a brute-force double hull
// (independent of the library's quickhull), a pair placed at a given fraction of its
// bounding radii, and the lane sets every pair is tried on:
//   random      random poses and sizes, about half overlapping by the reference
//   tiny, huge  the same at sizes 1e-4 and 1e4
//   far         poses 1e5 from the origin
//   deep        B's centre within 5% of the radii sum of A's
//   coincident  the centres on each other
//   touching    overlapping random lanes with B moved by the reference's s*n
//   degenerate  one or both leaves flattened or thinned to 1e-4 of their size (needle and
//               pancake boxes, cylinders and ellipsoids, coins, zero-length and hair-thin
//               capsules, flat hulls, sliver triangles; tiny spheres)
//   many-vertex hulls  72-point hulls (the kernels' big-hull routes)
//   needle/pancake  boxes only (matrix_test's set)
// Every lane carries its double reference (tests/support/narrow_reference.h).
// The specialised kernels of kernels/narrowphase/pair_kernels.h are listed once here
// (specialised_kernels()): the table the contract test holds pair_kernel() to, and the
// tolerance class of every pair (1e-4 of the size for exact kernels, 1e-3 for the general
// GJK / EPA route).
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <random>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "host/shapes/shape_store.h"
#include "kernels/narrowphase/pair_kernels.h"
#include "support/leaf_lanes.h"
#include "support/narrow_reference.h"
#include "support/random_input.h"
#include "support/test_support.h"

namespace impact::test {

using kernels::LeafType;

// ---------------------------------------------------------------------------------------
// The pair-kernel table
// ---------------------------------------------------------------------------------------

/// One specialised entry of pair_kernel(): the bucket (a <= b) and its kernel.
struct SpecialisedKernel {
  LeafType a, b;
  kernels::PairKernel kernel;
  const char* name;
};

/// Every specialised kernel of kernels/narrowphase/pair_kernels.h by bucket; the other
/// buckets (box-hull, hull-hull) take the general route (collide_gjk_epa).
inline const std::vector<SpecialisedKernel>& specialised_kernels() {
  namespace k = kernels;
  static const std::vector<SpecialisedKernel> v = {
      {k::kLeafSphere, k::kLeafSphere, &k::collide_sphere_sphere, "collide_sphere_sphere"},
      {k::kLeafSphere, k::kLeafCapsule, &k::collide_sphere_capsule, "collide_sphere_capsule"},
      {k::kLeafSphere, k::kLeafBox, &k::collide_sphere_box, "collide_sphere_box"},
      {k::kLeafSphere, k::kLeafConvex, &k::collide_sphere_convex, "collide_sphere_convex"},
      {k::kLeafSphere, k::kLeafCylinder, &k::collide_sphere_cylinder, "collide_sphere_cylinder"},
      {k::kLeafSphere, k::kLeafEllipsoid, &k::collide_sphere_ellipsoid, "collide_sphere_ellipsoid"},
      {k::kLeafSphere, k::kLeafTriangle, &k::collide_sphere_triangle, "collide_sphere_triangle"},
      {k::kLeafSphere, k::kLeafHalfSpace, &k::collide_sphere_halfspace, "collide_sphere_halfspace"},
      {k::kLeafCapsule, k::kLeafCapsule, &k::collide_capsule_capsule, "collide_capsule_capsule"},
      {k::kLeafCapsule, k::kLeafBox, &k::collide_capsule_box, "collide_capsule_box"},
      {k::kLeafCapsule, k::kLeafConvex, &k::collide_capsule_convex, "collide_capsule_convex"},
      {k::kLeafCapsule, k::kLeafCylinder, &k::collide_capsule_cylinder, "collide_capsule_cylinder"},
      {k::kLeafCapsule, k::kLeafEllipsoid, &k::collide_capsule_ellipsoid, "collide_capsule_ellipsoid"},
      {k::kLeafCapsule, k::kLeafTriangle, &k::collide_capsule_triangle, "collide_capsule_triangle"},
      {k::kLeafCapsule, k::kLeafHalfSpace, &k::collide_capsule_halfspace, "collide_capsule_halfspace"},
      {k::kLeafBox, k::kLeafBox, &k::collide_box_box, "collide_box_box"},
      {k::kLeafBox, k::kLeafCylinder, &k::collide_box_cylinder, "collide_box_cylinder"},
      {k::kLeafBox, k::kLeafEllipsoid, &k::collide_box_ellipsoid, "collide_box_ellipsoid"},
      {k::kLeafBox, k::kLeafTriangle, &k::collide_box_triangle, "collide_box_triangle"},
      {k::kLeafBox, k::kLeafHalfSpace, &k::collide_box_halfspace, "collide_box_halfspace"},
      {k::kLeafConvex, k::kLeafCylinder, &k::collide_convex_cylinder, "collide_convex_cylinder"},
      {k::kLeafConvex, k::kLeafEllipsoid, &k::collide_convex_ellipsoid, "collide_convex_ellipsoid"},
      {k::kLeafConvex, k::kLeafTriangle, &k::collide_convex_triangle, "collide_convex_triangle"},
      {k::kLeafConvex, k::kLeafHalfSpace, &k::collide_convex_halfspace, "collide_convex_halfspace"},
      {k::kLeafCylinder, k::kLeafCylinder, &k::collide_cylinder_cylinder, "collide_cylinder_cylinder"},
      {k::kLeafCylinder, k::kLeafEllipsoid, &k::collide_cylinder_ellipsoid, "collide_cylinder_ellipsoid"},
      {k::kLeafCylinder, k::kLeafTriangle, &k::collide_cylinder_triangle, "collide_cylinder_triangle"},
      {k::kLeafCylinder, k::kLeafHalfSpace, &k::collide_cylinder_halfspace, "collide_cylinder_halfspace"},
      {k::kLeafEllipsoid, k::kLeafEllipsoid, &k::collide_ellipsoid_ellipsoid, "collide_ellipsoid_ellipsoid"},
      {k::kLeafEllipsoid, k::kLeafTriangle, &k::collide_ellipsoid_triangle, "collide_ellipsoid_triangle"},
      {k::kLeafEllipsoid, k::kLeafHalfSpace, &k::collide_ellipsoid_halfspace, "collide_ellipsoid_halfspace"},
      {k::kLeafTriangle, k::kLeafTriangle, &k::collide_triangle_triangle, "collide_triangle_triangle"},
      {k::kLeafTriangle, k::kLeafHalfSpace, &k::collide_triangle_halfspace, "collide_triangle_halfspace"},
  };
  return v;
}

/// The specialised entry of bucket (a, b), or null (the general route).
inline const SpecialisedKernel* specialised_kernel(LeafType a, LeafType b) {
  for (const SpecialisedKernel& s : specialised_kernels())
    if (s.a == a && s.b == b) return &s;
  return nullptr;
}

/// The depth tolerance of a pair's kernel, of its size: 1e-4 for the exact kernels
/// (every specialised one, and box-hull, whose SAT route is exact: sat.cpp), 1e-3 for
/// the general GJK / EPA route (100x cfg.epa_tolerance).
inline double kernel_rel_tolerance(LeafType a, LeafType b) {
  if (a == kernels::kLeafBox && b == kernels::kLeafConvex) return 1e-4;
  return specialised_kernel(a, b) != nullptr ? 1e-4 : 1e-3;
}

/// The general route of a bucket, as pair_kernels.cpp takes it where no specialised
/// kernel exists: SAT or GJK + EPA by vertex count (collide_sat_or_gjk_epa, the route
/// the table names), or the support-function kernel against a half-space
/// (collide_support_halfspace). cfg passes through (sat_max_vertices = 0 keeps box /
/// hull pairs on GJK + EPA).
inline void collide_general(LeafType a, LeafType b, const kernels::LeafSoA& la, const kernels::LeafSoA& lb,
                            const kernels::ManifoldSoA& out, kernels::Range r,
                            const kernels::NarrowConfig& cfg) {
  if (b == kernels::kLeafHalfSpace)
    kernels::collide_support_halfspace(la, lb, out, r, cfg, a);
  else
    kernels::collide_sat_or_gjk_epa(la, lb, out, r, cfg, a, b);
}

/// "sphere_box": the bucket's name as a test name.
inline std::string pair_name(LeafType a, LeafType b) {
  std::string s = std::string(kernels::leaf_type_name(a)) + "_" + kernels::leaf_type_name(b);
  std::replace(s.begin(), s.end(), '-', '_');
  return s;
}

/// Every bucket of the table: (a, b) with a <= b, except half-space/half-space.
inline std::vector<std::pair<LeafType, LeafType>> all_buckets() {
  std::vector<std::pair<LeafType, LeafType>> v;
  for (uint8_t a = 0; a < kernels::kLeafTypeCount; ++a)
    for (uint8_t b = a; b < kernels::kLeafTypeCount; ++b)
      if (!(a == kernels::kLeafHalfSpace && b == kernels::kLeafHalfSpace))
        v.emplace_back(static_cast<LeafType>(a), static_cast<LeafType>(b));
  return v;
}

// ---------------------------------------------------------------------------------------
// Random leaves
// ---------------------------------------------------------------------------------------

using nref::V3;
using Rng = std::mt19937;

inline float f32(double v) {
  return static_cast<float>(v);
}
inline double uni(Rng& g, double a, double b) {
  return std::uniform_real_distribution<double>(a, b)(g);
}
/// test::random_normal_draws, normalised as a V3.
inline V3 random_unit_v3(Rng& g) {
  const Eigen::Vector3d v = random_normal_draws(g);
  return nref::normalized(V3{v.x(), v.y(), v.z()});
}

/// A brute-force convex hull in double of points in general position or with exactly
/// coplanar faces (every triple's plane that keeps all points on one side is a face;
/// coplanar triples are merged; polygons ordered counter-clockwise from outside).
inline HullData brute_force_hull(const std::vector<Eigen::Vector3f>& pf) {
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
        for (const Plane& pl : planes)
          dup = dup || (nref::dot(pl.n, nn) > 1 - 1e-9 && std::fabs(pl.d - d) < 1e-6 * scale);
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

/// The 8 corners of the box of half extents hx, hy, hz about the origin.
inline std::vector<Eigen::Vector3f> corners(double hx, double hy, double hz) {
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

inline void set_rotation(Leaf& l, const double m[9]) {
  for (int i = 0; i < 9; ++i) l.r[i] = f32(m[i]);
}

/// A leaf of type t centred at c (size ~scale), random orientation and sizes.
inline Leaf make_leaf(LeafType t, V3 c, double scale, Rng& g, HullBank& w) {
  namespace k = kernels;
  Leaf l;
  l.t = t;
  double m[9];
  random_rotation_rows(g, m);
  auto put_p = [&](V3 q) {
    l.p[0] = f32(q.x);
    l.p[1] = f32(q.y);
    l.p[2] = f32(q.z);
  };
  put_p(c);
  switch (t) {
    case k::kLeafSphere:
      l.e[0] = f32(scale * uni(g, 0.2, 1.0));
      break;
    case k::kLeafCapsule:
    case k::kLeafCylinder:
      set_rotation(l, m);
      l.e[0] = f32(scale * uni(g, 0.1, t == k::kLeafCapsule ? 0.6 : 1.0));
      l.e[1] = f32(scale * uni(g, 0.1, 1.0));
      break;
    case k::kLeafBox:
    case k::kLeafEllipsoid:
      set_rotation(l, m);
      for (float& x : l.e) x = f32(scale * uni(g, 0.1, 1.0));
      break;
    case k::kLeafConvex: {
      set_rotation(l, m);
      std::vector<Eigen::Vector3f> pts;
      if (g() % 3 == 0) {
        pts = corners(scale * uni(g, 0.1, 1.0), scale * uni(g, 0.1, 1.0), scale * uni(g, 0.1, 1.0));
      } else {
        const double ax[3] = {uni(g, 0.3, 1.0), uni(g, 0.3, 1.0), uni(g, 0.3, 1.0)};
        const int np = 8 + static_cast<int>(g() % 7);
        for (int i = 0; i < np; ++i) {
          const V3 u = random_unit_v3(g);
          pts.emplace_back(f32(scale * ax[0] * u.x), f32(scale * ax[1] * u.y), f32(scale * ax[2] * u.z));
        }
      }
      l.ref = w.add_hull(pts);
      break;
    }
    case k::kLeafTriangle: {
      V3 q[3];
      for (;;) {
        for (V3& v : q) v = uni(g, 0.2, 1.0) * random_unit_v3(g);
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
      const V3 n = random_unit_v3(g);
      l.e[0] = f32(n.x);
      l.e[1] = f32(n.y);
      l.e[2] = f32(n.z);
      break;
    }
    default:
      break;
  }
  return l;
}

/// The leaf moved by t (rounded to float).
inline void translate(Leaf& l, V3 t) {
  for (int j = 0; j < 3; ++j) l.p[j] = f32(static_cast<double>(l.p[j]) + t[j]);
  if (l.t == kernels::kLeafTriangle)
    for (int j = 0; j < 6; ++j) l.w[j] = f32(static_cast<double>(l.w[j]) + t[j % 3]);
}

/// The leaf in double for the reference, exactly as a kernel sees it.
inline nref::Shape ref_shape(const Leaf& l, const HullBank& w) {
  const LeafLanes b({l});
  const kernels::HullView hv = w.hulls.view();
  return nref::shape_from_leaf(b.soa(), 0, l.t, &hv);
}

/// The leaf flattened or thinned to 1e-4 of its size (1e-3 for ellipsoids, a tenth of
/// its size for spheres), a different degeneracy on alternate draws: needle and pancake
/// boxes, cylinders and ellipsoids, coins, zero-length and hair-thin capsules, flat
/// hulls, sliver triangles. Half-spaces stay as they are.
inline Leaf degenerate_leaf(const Leaf& in, Rng& g, HullBank& w) {
  namespace k = kernels;
  Leaf l = in;
  const bool first = g() & 1;
  switch (l.t) {
    case k::kLeafSphere:
      l.e[0] = f32(0.1 * l.e[0]);
      break;
    case k::kLeafCapsule:
      if (first)
        l.e[1] = 0.0f;  // a sphere
      else
        l.e[0] = f32(1e-4 * l.e[1]);  // a hair
      break;
    case k::kLeafCylinder:
      if (first)
        l.e[1] = f32(1e-4 * l.e[0]);  // a coin
      else
        l.e[0] = f32(1e-4 * l.e[1]);  // a needle
      break;
    case k::kLeafBox:
    case k::kLeafEllipsoid: {
      const double big = std::max({l.e[0], l.e[1], l.e[2]}) * 1.5;
      const double thin = big * (l.t == k::kLeafBox ? 1e-4 : 1e-3);
      l.e[0] = f32(big);
      l.e[1] = f32(first ? thin : big);
      l.e[2] = f32(thin);
      break;
    }
    case k::kLeafConvex: {
      // A flat hull: the same outline squashed to 1e-4 of its thickness.
      std::vector<Eigen::Vector3f> pts = w.hull_points[l.ref];
      for (auto& p : pts) p.z() *= 1e-4f;
      l.ref = w.add_hull(pts);
      break;
    }
    case k::kLeafTriangle: {
      // A sliver: v2 1e-4 of the edge's length off the middle of v0-v1.
      const V3 v0{l.p[0], l.p[1], l.p[2]}, v1{l.w[0], l.w[1], l.w[2]}, v2{l.w[3], l.w[4], l.w[5]};
      const V3 e = v1 - v0, mid = 0.5 * (v0 + v1);
      const V3 off = nref::normalized(nref::cross(nref::cross(e, v2 - v0), e));
      const V3 apex = mid + (1e-4 * nref::norm(e)) * off;
      for (int j = 0; j < 3; ++j) l.w[3 + j] = f32(apex[j]);
      break;
    }
    default:
      break;
  }
  return l;
}

/// A hull leaf given a hull of 72 points on an ellipsoid of its size: more vertices than
/// hull-half-space's lane kernel takes (64: convex_halfspace.cpp), and two of them more
/// than NarrowConfig::sat_max_vertices (the big-hull routes); other leaves unchanged.
inline Leaf many_vertex_hull(const Leaf& in, Rng& g, HullBank& w) {
  if (in.t != kernels::kLeafConvex) return in;
  Leaf l = in;
  double r = 0;
  for (const auto& p : w.hull_points[l.ref]) r = std::max(r, static_cast<double>(p.norm()));
  const double ax[3] = {uni(g, 0.5, 1.0), uni(g, 0.5, 1.0), uni(g, 0.5, 1.0)};
  std::vector<Eigen::Vector3f> pts;
  for (int i = 0; i < 72; ++i) {
    const V3 u = random_unit_v3(g);
    pts.emplace_back(f32(r * ax[0] * u.x), f32(r * ax[1] * u.y), f32(r * ax[2] * u.z));
  }
  l.ref = w.add_hull(pts);
  return l;
}

/// Box leaves made needles or pancakes (1 x 1e-4 x 1e-4 or 1 x 1 x 1e-4, 1.5x the
/// largest extent); other leaves unchanged.
inline Leaf thin_box(const Leaf& box, Rng& g, HullBank&) {
  Leaf b = box;
  const double big = std::max({b.e[0], b.e[1], b.e[2]}) * 1.5;
  const bool needle = g() & 1;
  b.e[0] = f32(big);
  b.e[1] = f32(needle ? big * 1e-4 : big);
  b.e[2] = f32(big * 1e-4);
  return b;
}

// ---------------------------------------------------------------------------------------
// Lanes: a pair and its reference
// ---------------------------------------------------------------------------------------

struct Lane {
  Leaf a, b;
  nref::Shape sa, sb;
  nref::PairResult ref;
};

inline Lane make_lane(const Leaf& a, const Leaf& b, const HullBank& w) {
  Lane l{a, b, ref_shape(a, w), ref_shape(b, w), {}};
  l.ref = nref::solve_pair(l.sa, l.sb);
  return l;
}

/// The pair's size: the larger bounding radius.
inline double lane_size(const Lane& l) {
  return std::max(l.sa.bound_radius(), l.sb.bound_radius());
}

/// Whether the lane's reference normal is well conditioned at tol: unique (every
/// direction 0.02 rad or more from it overlaps by more than s + tol) and the overlap
/// rising by at least 1e-6 L 3e-3 rad from it in every direction (the per-kernel tests'
/// rule, e.g. box_ellipsoid_test.cpp).
inline bool well_conditioned(const Lane& l, double tol) {
  return nref::well_conditioned(l.sa, l.sb, l.ref, tol, lane_size(l));
}

/// The largest coordinate of a shape (its centre, its vertices).
inline double coord_magnitude(const nref::Shape& s) {
  double c = std::max({std::fabs(s.p.x), std::fabs(s.p.y), std::fabs(s.p.z)});
  for (const V3& q : s.pts) c = std::max({c, std::fabs(q.x), std::fabs(q.y), std::fabs(q.z)});
  return c;
}

/// A at c (size scale); B placed at lambda * (bound radii) from A along a random direction
/// (B a half-space: its plane lambda * A's radius from A's centre).
inline std::pair<Leaf, Leaf> place_pair(LeafType ta, LeafType tb, V3 c, double scale, double lambda, Rng& g,
                                        HullBank& w) {
  Leaf a = make_leaf(ta, c, scale, g, w);
  Leaf b = make_leaf(tb, {0, 0, 0}, scale, g, w);
  const double ra = ref_shape(a, w).bound_radius();
  const V3 ca = ref_shape(a, w).centre();
  if (tb == kernels::kLeafHalfSpace) {
    const V3 n{b.e[0], b.e[1], b.e[2]};
    translate(b, ca + lambda * ra * n);
  } else {
    const double rb = ref_shape(b, w).bound_radius();
    const V3 cb0 = ref_shape(b, w).centre();
    translate(b, ca + lambda * (ra + rb) * random_unit_v3(g) - cb0);
  }
  return {a, b};
}

/// Changes a leaf of a placed pair (degenerate_leaf, thin_box).
using LeafMutation = Leaf (*)(const Leaf&, Rng&, HullBank&);

/// n random lanes of bucket (ta, tb), about half overlapping (by the reference), at the
/// given scale / offset, B at lam_lo..lam_hi of the radii sum. `mutate`, if given,
/// changes the boxes (box_only) or every leaf of A and, on alternate draws (always when
/// A is not changed), of B.
inline std::vector<Lane> random_lanes(LeafType ta, LeafType tb, uint32_t n, double scale, double offset,
                                      double lam_lo, double lam_hi, Rng& g, HullBank& w,
                                      LeafMutation mutate = nullptr, bool box_only = true) {
  std::vector<Lane> lanes;
  uint32_t over = 0, sep = 0;
  for (uint32_t attempt = 0; attempt < 40 * n && lanes.size() < n; ++attempt) {
    V3 c = scale * V3{uni(g, -1, 1), uni(g, -1, 1), uni(g, -1, 1)};
    if (offset != 0)
      c = c + V3{(g() & 1) ? offset : -offset, (g() & 1) ? offset : -offset, (g() & 1) ? offset : -offset};
    const double lo = tb == kernels::kLeafHalfSpace ? -1.2 : lam_lo;
    auto [a, b] = place_pair(ta, tb, c, scale, uni(g, lo, lam_hi), g, w);
    if (mutate != nullptr) {
      const bool ma = !box_only || a.t == kernels::kLeafBox;
      const bool mb = box_only ? b.t == kernels::kLeafBox : b.t != kernels::kLeafHalfSpace;
      if (ma) a = mutate(a, g, w);
      if (mb && (!ma || (g() & 1))) b = mutate(b, g, w);
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

/// A named set of lanes.
struct LaneSet {
  std::string what;
  std::vector<Lane> lanes;
};

/// The standard sets of bucket (ta, tb), each `count` lanes times `per` (random: 8 per,
/// the others 1-1.3 per): random, tiny 1e-4, huge 1e4, far 1e5, deep, coincident,
/// touching, and for box pairs needle/pancake boxes; with `extended`, a set of
/// degenerate leaves of every type and, for hull pairs, one of many-vertex hulls. The sets are made first and
/// in this order: HullStore may reallocate while hulls are added (views are taken after).
inline std::vector<LaneSet> standard_lane_sets(LeafType ta, LeafType tb, double per, Rng& g, HullBank& w,
                                               bool extended = false) {
  const std::string name = pair_name(ta, tb);
  auto count = [&](double base) { return scaled(static_cast<uint32_t>(std::lround(base * per)), 1); };
  std::vector<LaneSet> sets;
  sets.push_back({name + " random", random_lanes(ta, tb, count(96), 1.0, 0.0, 0.0, 1.1, g, w)});
  sets.push_back({name + " tiny 1e-4", random_lanes(ta, tb, count(12), 1e-4, 0.0, 0.0, 1.1, g, w)});
  sets.push_back({name + " huge 1e4", random_lanes(ta, tb, count(12), 1e4, 0.0, 0.0, 1.1, g, w)});
  sets.push_back({name + " far 1e5", random_lanes(ta, tb, count(12), 1.0, 1e5, 0.0, 1.1, g, w)});
  sets.push_back({name + " deep", random_lanes(ta, tb, count(16), 1.0, 0.0, 0.0, 0.05, g, w)});
  {
    std::vector<Lane> co;
    for (uint32_t i = 0; i < count(6); ++i) {
      const V3 c{uni(g, -1, 1), uni(g, -1, 1), uni(g, -1, 1)};
      auto [a, b] = place_pair(ta, tb, c, 1.0, 0.0, g, w);
      co.push_back(make_lane(a, b, w));
    }
    sets.push_back({name + " coincident", std::move(co)});
  }
  {
    std::vector<Lane> touch;
    for (const Lane& l : sets[0].lanes) {
      if (l.ref.s <= 0) continue;
      Leaf b = l.b;
      translate(b, l.ref.s * l.ref.n);
      touch.push_back(make_lane(l.a, b, w));
      if (touch.size() >= count(8)) break;
    }
    sets.push_back({name + " touching", std::move(touch)});
  }
  if (ta == kernels::kLeafBox || tb == kernels::kLeafBox)
    sets.push_back(
        {name + " needle/pancake", random_lanes(ta, tb, count(16), 1.0, 0.0, 0.0, 1.1, g, w, &thin_box)});
  if (extended) {
    sets.push_back({name + " degenerate",
                    random_lanes(ta, tb, count(24), 1.0, 0.0, 0.0, 1.1, g, w, &degenerate_leaf, false)});
    if (ta == kernels::kLeafConvex || tb == kernels::kLeafConvex)
      sets.push_back({name + " many-vertex hulls",
                      random_lanes(ta, tb, count(12), 1.0, 0.0, 0.0, 1.1, g, w, &many_vertex_hull, false)});
  }
  return sets;
}

/// The A and B leaves of lanes (swapped: B and A).
inline std::pair<std::vector<Leaf>, std::vector<Leaf>> leaves_of(const std::vector<Lane>& lanes,
                                                                 bool swap = false) {
  std::pair<std::vector<Leaf>, std::vector<Leaf>> v;
  for (const Lane& l : lanes) {
    v.first.push_back(swap ? l.b : l.a);
    v.second.push_back(swap ? l.a : l.b);
  }
  return v;
}

/// kern over lanes [begin, end) of the bucket (test::run_bucket), with cfg's hulls set
/// to the bank's.
inline ManifoldLanes run_lanes(kernels::PairKernel kern, const std::vector<Lane>& lanes, const HullBank& w,
                               kernels::NarrowConfig cfg, uint32_t begin, uint32_t end, bool swap = false) {
  const auto [a, b] = leaves_of(lanes, swap);
  cfg.hulls = w.hulls.view();
  return run_bucket(kern, a, b, cfg, begin, end);
}

inline ManifoldLanes run_lanes(kernels::PairKernel kern, const std::vector<Lane>& lanes, const HullBank& w,
                               kernels::KernelPath path, bool swap = false) {
  kernels::NarrowConfig cfg;
  cfg.path = path;
  return run_lanes(kern, lanes, w, cfg, 0, static_cast<uint32_t>(lanes.size()), swap);
}

// ---------------------------------------------------------------------------------------
// Failure reports
// ---------------------------------------------------------------------------------------

inline std::string flit(float v) {
  char buf[48];
  std::snprintf(buf, sizeof buf, "%.9gf", static_cast<double>(v));
  return buf;
}

/// The leaf as C++ literals (LeafSoA fields; a hull's local vertices).
inline std::string literal(const char* name, const Leaf& l, const HullBank& w) {
  namespace k = kernels;
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
      o << (i ? ", " : "") << "{" << flit(pts[i].x()) << ", " << flit(pts[i].y()) << ", " << flit(pts[i].z())
        << "}";
    o << "};";
  }
  o << "\n";
  return o.str();
}

/// Both leaves of a lane and its reference, for a failure message.
inline std::string literal(const Lane& l, const HullBank& w) {
  std::ostringstream o;
  o.precision(9);
  o << literal("A", l.a, w) << literal("B", l.b, w) << "    reference: s=" << l.ref.s << " n={" << l.ref.n.x
    << ", " << l.ref.n.y << ", " << l.ref.n.z << "}";
  return o.str();
}

}  // namespace impact::test
