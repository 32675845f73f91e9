// collide_triangle_triangle (kernels/narrowphase/pairs/triangle/triangle_triangle.cpp) on both
// paths against independent double-precision references.
//
// References (double, on the kernel's float inputs):
//   - depth and normal: tests/support/narrow_reference.h (the minimum over unit
//     directions of the support overlap h_A(n) + h_B(-n), by dense sampling and
//     Nelder-Mead; no SAT, no GJK / EPA);
//   - a brute-force SAT over the 11 axes (both normals, 9 edge crosses), itself checked
//     against the sampled reference where they overlap (the SAT's axes hold the
//     minimum, so both give the same depth);
//   - hit or miss: a segment-triangle crossing test (an edge of one triangle through
//     the other), which shares nothing with either.
// Per lane, L = the larger bounding radius, tol = kRel * L:
//  (a) count > 0 iff the reference s > 0 (either where |s| <= tol);
//  (b) |depth - s| <= tol;
//  (c) n finite and unit, o(n) <= s + tol (as good a separating direction as the
//      reference's), and within kAngleTol of the reference normal where the minimum is
//      unique;
//  (d) every point (count <= 4) finite, 0 <= pdepth <= depth + tol, and point + n pd/2
//      lies on A, point - n pd/2 on B (within tol plus an ulp of the largest world
//      coordinate): midway between the two triangles;
//  (e) moving B by n (depth + tol) separates it (SAT in double), by n (depth - 2 tol)
//      does not.
// Scenarios: random poses (about half overlapping) at sizes 1, 1e-4 and 1e4 and 1e5 from
// the origin; deep crossings (common centre); touching (B moved by the reference's s n)
// and exactly touching representable configurations (count 0); coplanar overlapping
// triangles (count 0 by the reference; within rounding a hit must have ~0 depth, the
// plane's normal and the overlap polygon as its points) and near-coplanar crossings
// (tilts 1e-6 .. 1e-2 rad); edges within 0 .. 1e-3 rad of parallel crossing each other;
// slivers (height 1e-3 .. 1e-7 of the base) and degenerate triangles (collinear, two or
// three coincident vertices: finite output); the face tie rule (A's normal on a mirror-
// symmetric crossing); swap symmetry. The two paths (depth within 1e-6 L, normals within
// 1e-5 rad, the same points), range partitions and the agreement with GJK / EPA:
// contract_test.cpp.
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "kernels/narrowphase/pair_kernels.h"
#include "support/leaf_lanes.h"
#include "support/narrow_reference.h"
#include "support/random_input.h"
#include "support/test_support.h"

namespace impact::kernels {
namespace {

namespace nref = test::nref;
using Vec3d = Eigen::Vector3d;
using test::ManifoldLanes, test::PairResult;

constexpr double kRel = 1e-5;       // depth / point tolerance, of L
constexpr double kAngleTol = 1e-3;  // rad, where the reference's minimum is unique
constexpr double kGjkRel = 1e-3;    // GJK / EPA agreement (its own tolerance, matrix_test.cpp)

/// One triangle as test::LeafLanes pushes it (p = v0, v1, v2; R, e, hull unused).
struct Tri {
  Vec3d p = Vec3d::Zero(), v1 = Vec3d::Zero(), v2 = Vec3d::Zero();
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  Vec3d e = Vec3d::Zero();
  uint32_t hull = 0;
  Vec3d v(int i) const { return i == 0 ? p : (i == 1 ? v1 : v2); }
};

Vec3d to_float(const Vec3d& v) { return test::round_to_float(v); }
/// The triangle as the kernel sees it: every coordinate rounded to float.
Tri tri(const Vec3d& a, const Vec3d& b, const Vec3d& c) {
  Tri t;
  t.p = to_float(a), t.v1 = to_float(b), t.v2 = to_float(c);
  return t;
}
/// t moved by d, rounded to float (a kernel input) or exact (for a reference check).
Tri moved(const Tri& t, const Vec3d& d) { return tri(t.p + d, t.v1 + d, t.v2 + d); }
Tri shifted(const Tri& t, const Vec3d& d) {
  Tri s = t;
  s.p += d, s.v1 += d, s.v2 += d;
  return s;
}

nref::V3 nv(const Vec3d& v) { return {v.x(), v.y(), v.z()}; }
Vec3d ev(const nref::V3& v) { return {v.x, v.y, v.z}; }
nref::Shape shape(const Tri& t) { return nref::make_triangle(nv(t.p), nv(t.v1), nv(t.v2)); }

double bound(const Tri& t) { return shape(t).bound_radius(); }
double coord_mag(const Tri& t) {
  return std::max({t.p.cwiseAbs().maxCoeff(), t.v1.cwiseAbs().maxCoeff(), t.v2.cwiseAbs().maxCoeff()});
}
double angle(const Vec3d& a, const Vec3d& b) { return std::atan2(a.cross(b).norm(), a.dot(b)); }

struct Case {
  Tri a, b;
};

// ---------------------------------------------------------------------------------------
// Running the kernels
// ---------------------------------------------------------------------------------------

using Kernel = void (*)(const LeafSoA&, const LeafSoA&, const ManifoldSoA&, Range, const NarrowConfig&);

ManifoldLanes run(const std::vector<Case>& cases, KernelPath path, bool swap = false,
                  Kernel kern = &collide_triangle_triangle) {
  test::LeafLanes la, lb;
  for (const Case& c : cases) {
    la.push(swap ? c.b : c.a);
    lb.push(swap ? c.a : c.b);
  }
  const uint32_t n = static_cast<uint32_t>(cases.size());
  ManifoldLanes out(n);
  NarrowConfig cfg;
  cfg.path = path;
  kern(la.soa(), lb.soa(), out.view(), Range{0, n}, cfg);
  return out;
}

const char* path_name(KernelPath p) { return p == KernelPath::kSimd ? "simd" : "scalar"; }

// ---------------------------------------------------------------------------------------
// References
// ---------------------------------------------------------------------------------------

/// Brute-force SAT in double over the 11 axes: the least overlap (> 0: overlapping) and
/// its axis, oriented from A to B. Separated pairs: the largest gap (negative), which
/// is a lower bound on minus the distance, not the distance.
struct Sat {
  double o = 0;
  Vec3d n = Vec3d::UnitZ();
};
Sat sat_double(const Tri& a, const Tri& b) {
  std::vector<Vec3d> axes;
  const Vec3d A[3] = {a.p, a.v1, a.v2}, B[3] = {b.p, b.v1, b.v2};
  axes.push_back((A[1] - A[0]).cross(A[2] - A[0]));
  axes.push_back((B[1] - B[0]).cross(B[2] - B[0]));
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      const Vec3d ea = A[(i + 1) % 3] - A[i], eb = B[(j + 1) % 3] - B[j];
      const Vec3d l = ea.cross(eb);
      if (l.norm() > 1e-9 * ea.norm() * eb.norm()) axes.push_back(l);
    }
  Sat best{1e300, Vec3d::UnitZ()};
  for (Vec3d l : axes) {
    if (!(l.norm() > 0)) continue;
    l.normalize();
    double amin = 1e300, amax = -1e300, bmin = 1e300, bmax = -1e300;
    for (int k = 0; k < 3; ++k) {
      amin = std::min(amin, l.dot(A[k] - A[0])), amax = std::max(amax, l.dot(A[k] - A[0]));
      bmin = std::min(bmin, l.dot(B[k] - A[0])), bmax = std::max(bmax, l.dot(B[k] - A[0]));
    }
    const double op = amax - bmin, on = bmax - amin;
    const double o = std::min(op, on);
    if (o < best.o) best = {o, op <= on ? l : Vec3d(-l)};
  }
  return best;
}

/// Whether segment p..q crosses triangle t (double; coplanar segments do not count).
bool segment_crosses(const Vec3d& p, const Vec3d& q, const Tri& t) {
  const Vec3d n = (t.v1 - t.p).cross(t.v2 - t.p);
  const double dp = n.dot(p - t.p), dq = n.dot(q - t.p);
  if (dp * dq > 0 || (dp == 0 && dq == 0)) return false;
  const Vec3d x = p + (dp / (dp - dq)) * (q - p);
  const double u = n.dot((t.v1 - x).cross(t.v2 - x)), v = n.dot((t.v2 - x).cross(t.p - x)),
               w = n.dot((t.p - x).cross(t.v1 - x));
  return (u >= 0 && v >= 0 && w >= 0) || (u <= 0 && v <= 0 && w <= 0);
}
bool triangles_cross(const Tri& a, const Tri& b) {
  for (int i = 0; i < 3; ++i) {
    if (segment_crosses(a.v(i), a.v((i + 1) % 3), b)) return true;
    if (segment_crosses(b.v(i), b.v((i + 1) % 3), a)) return true;
  }
  return false;
}

struct Ref {
  nref::PairResult r;
  double L = 1, tol = 0;
};
Ref reference(const Case& c) {
  Ref f;
  nref::Options opt;
  opt.unique_cone = kAngleTol;  // unique: every direction > kAngleTol away overlaps by > s + 2 tol
  f.r = nref::solve_pair(shape(c.a), shape(c.b), {}, opt);
  f.L = std::max(bound(c.a), bound(c.b));
  f.tol = kRel * f.L;
  return f;
}

// ---------------------------------------------------------------------------------------
// The per-lane check
// ---------------------------------------------------------------------------------------

std::string literal(const Case& c) {
  std::ostringstream o;
  o.precision(9);
  for (const Tri* t : {&c.a, &c.b}) {
    o << (t == &c.a ? "    A: " : "    B: ");
    for (int i = 0; i < 3; ++i) o << "{" << t->v(i).x() << ", " << t->v(i).y() << ", " << t->v(i).z() << "} ";
    o << "\n";
  }
  return o.str();
}
std::string describe(const PairResult& r) {
  std::ostringstream o;
  o.precision(9);
  o << "count=" << r.count;
  if (r.count > 0 && r.count <= 4) {
    o << " n={" << r.n.x() << ", " << r.n.y() << ", " << r.n.z() << "} depth=" << r.depth;
    for (uint32_t q = 0; q < r.count; ++q)
      o << "\n      point[" << q << "]={" << r.pt[q].x() << ", " << r.pt[q].y() << ", " << r.pt[q].z()
        << "} pdepth=" << r.pd[q];
  }
  return o.str();
}

struct Worst {
  double depth = 0, angle = 0, point = 0;  // |depth - s| / L, rad, point off a surface / L
  uint32_t lanes = 0, hits = 0, band = 0;
};

/// Checks one lane against the reference; "" or the reasons.
std::string check_lane(const Case& c, const Ref& f, const PairResult& r, Worst& w, double point_rel) {
  std::ostringstream why;
  why.precision(9);
  const double s = f.r.s, tol = f.tol;
  const bool in_band = std::fabs(s) <= tol;
  ++w.lanes;
  w.band += in_band ? 1 : 0;
  if (r.count > 4) return " count > 4;";
  const bool hit = r.count > 0;
  w.hits += hit ? 1 : 0;
  if (!in_band && hit != (s > 0)) why << " hit mismatch: reference s=" << s << ";";
  if (!hit) return why.str();
  if (!std::isfinite(r.depth) || !r.n.allFinite() || std::fabs(r.n.norm() - 1) > 1e-5)
    return " normal / depth not finite or not unit;";
  const double dd = std::fabs(r.depth - s);
  w.depth = std::max(w.depth, dd / f.L);
  if (dd > tol) why << " depth " << r.depth << " vs reference " << s << ";";
  const Vec3d n = r.n.normalized();
  const nref::Shape sa = shape(c.a), sb = shape(c.b);
  const double on = nref::overlap(sa, sb, nv(n));
  if (on > s + tol) why << " normal not a minimum direction: o(n)=" << on << " > s + tol;";
  if (f.r.unique(2 * tol)) {
    const double ang = angle(n, ev(f.r.n));
    w.angle = std::max(w.angle, ang);
    if (ang > kAngleTol) why << " normal " << ang << " rad from the unique reference normal;";
  }
  // (e) safe displacement, by the double SAT (exact for two triangles)
  if (sat_double(c.a, shifted(c.b, (r.depth + tol) * n)).o > 1e-12 * f.L)
    why << " moving B by n (depth + tol) does not separate;";
  if (r.depth > 3 * tol && s > 3 * tol && !(sat_double(c.a, shifted(c.b, (r.depth - 2 * tol) * n)).o > 0))
    why << " moving B by n (depth - 2 tol) already separates;";
  // (d) points midway between the triangles
  const double slack = point_rel * f.L + std::max(coord_mag(c.a), coord_mag(c.b)) * std::ldexp(1.0, -23);
  for (uint32_t q = 0; q < r.count; ++q) {
    const Vec3d& x = r.pt[q];
    if (!x.allFinite() || !std::isfinite(r.pd[q])) {
      why << " point " << q << " not finite;";
      continue;
    }
    if (r.pd[q] < 0 || r.pd[q] > r.depth + tol) why << " pdepth[" << q << "]=" << r.pd[q] << " outside [0, depth];";
    const Vec3d on_a = x + 0.5 * r.pd[q] * n, on_b = x - 0.5 * r.pd[q] * n;
    const double da = nref::triangle_distance(nv(on_a), nv(c.a.p), nv(c.a.v1), nv(c.a.v2));
    const double db = nref::triangle_distance(nv(on_b), nv(c.b.p), nv(c.b.v1), nv(c.b.v2));
    w.point = std::max(w.point, std::max(da, db) / f.L);
    if (da > slack || db > slack)
      why << " point " << q << " not midway: x + n pd/2 is " << da << " off A, x - n pd/2 " << db << " off B;";
  }
  return why.str();
}

/// Both paths over the cases, every lane checked; returns the failure count.
int check_all(const std::vector<Case>& cases, const std::vector<Ref>& refs, const std::string& what,
              double point_rel = kRel) {
  int failures = 0;
  for (KernelPath path : {KernelPath::kScalar, KernelPath::kSimd}) {
    const ManifoldLanes out = run(cases, path);
    Worst w;
    int printed = 0;
    for (uint32_t i = 0; i < cases.size(); ++i) {
      const PairResult r = out.result(i);
      const std::string why = check_lane(cases[i], refs[i], r, w, point_rel);
      if (why.empty()) continue;
      ++failures;
      if (printed++ < 3)
        ADD_FAILURE() << what << " [" << path_name(path) << "] lane " << i << ":" << why << "\n"
                      << literal(cases[i]) << "    reference: s=" << refs[i].r.s << " n={" << refs[i].r.n.x
                      << ", " << refs[i].r.n.y << ", " << refs[i].r.n.z << "}"
                      << (refs[i].r.unique(2 * refs[i].tol) ? " (unique)" : " (not unique)")
                      << "\n    kernel:    " << describe(r);
    }
    std::printf("  %-28s %-6s lanes %4u hits %4u band %3u | worst |depth-s| %.2g L, angle %.2g, point %.2g L\n",
                what.c_str(), path_name(path), w.lanes, w.hits, w.band, w.depth, w.angle, w.point);
  }
  return failures;
}

std::vector<Ref> references(const std::vector<Case>& cases) {
  std::vector<Ref> refs;
  refs.reserve(cases.size());
  for (const Case& c : cases) refs.push_back(reference(c));
  return refs;
}

/// Face contacts (n along A's or B's normal): the manifold must be the part of the
/// triangles' overlap polygon where they interpenetrate. Independently in double: both
/// triangles projected along n, A's polygon clipped by B's edges (Sutherland-Hodgman),
/// each vertex's penetration = A's height minus B's along n there. Every kernel point
/// must be such a vertex (2-D within 1e-6 L, pdepth within 1e-6 L of its penetration,
/// which is > -1e-6 L), the deepest vertex must be among them, and count >=
/// min(2, distinct penetrating vertices). Returns "" (also for non-face lanes) or why.
std::string check_face_manifold(const Case& c, const PairResult& r, double L, bool* checked) {
  *checked = false;
  if (r.count == 0) return "";
  const Vec3d n = r.n.normalized();
  const Vec3d na = (c.a.v1 - c.a.p).cross(c.a.v2 - c.a.p).normalized();
  const Vec3d nb = (c.b.v1 - c.b.p).cross(c.b.v2 - c.b.p).normalized();
  // (an edge axis within a few 1e-5 rad of a face normal may win on its own, with one point)
  const bool face = std::min(angle(n, na), angle(n, -na)) < 1e-6 || std::min(angle(n, nb), angle(n, -nb)) < 1e-6;
  // both faces well inside the projection (the kernel skips candidates of a triangle
  // within ~0.6 deg of edge-on, which has no interior to speak of)
  if (!face || std::fabs(n.dot(na)) < 0.05 || std::fabs(n.dot(nb)) < 0.05) return "";
  *checked = true;
  const Vec3d t1 = n.unitOrthogonal(), t2 = n.cross(t1);
  const Vec3d o = c.a.p;
  auto proj = [&](const Vec3d& x) { return Eigen::Vector2d(t1.dot(x - o), t2.dot(x - o)); };
  auto height = [&](const Tri& t, const Eigen::Vector2d& q) {  // along n, of t's plane over q
    const Vec3d tn = (t.v1 - t.p).cross(t.v2 - t.p);
    const Vec3d x0 = o + q.x() * t1 + q.y() * t2;
    return tn.dot(t.p - x0) / tn.dot(n);
  };
  // Each vertex carries its conditioning: 1 for a corner, 1 / sin(crossing angle) for a
  // crossing of two edges (float moves it along the shallower edge by that much more).
  struct PV {
    Eigen::Vector2d q;
    double cond;
  };
  std::vector<PV> poly;
  for (int i = 0; i < 3; ++i) poly.push_back({proj(c.a.v(i)), 1.0});
  Eigen::Vector2d b2[3];
  for (int i = 0; i < 3; ++i) b2[i] = proj(c.b.v(i));
  const double orient = (b2[1] - b2[0]).x() * (b2[2] - b2[0]).y() - (b2[1] - b2[0]).y() * (b2[2] - b2[0]).x();
  for (int e = 0; e < 3 && !poly.empty(); ++e) {
    const Eigen::Vector2d p0 = b2[e], d = b2[(e + 1) % 3] - b2[e];
    auto side = [&](const Eigen::Vector2d& q) { return (d.x() * (q - p0).y() - d.y() * (q - p0).x()) * orient; };
    std::vector<PV> next;
    for (size_t k = 0; k < poly.size(); ++k) {
      const Eigen::Vector2d& p = poly[k].q;
      const Eigen::Vector2d& q = poly[(k + 1) % poly.size()].q;
      const double sp = side(p), sq = side(q);
      if (sp >= 0) next.push_back(poly[k]);
      if ((sp >= 0) != (sq >= 0)) {
        const Eigen::Vector2d pq = q - p;
        const double sine = std::fabs(d.x() * pq.y() - d.y() * pq.x()) / (d.norm() * pq.norm());
        next.push_back({p + (sp / (sp - sq)) * pq, 1.0 / std::max(sine, 1e-3)});
      }
    }
    poly = next;
  }
  struct V {
    Eigen::Vector2d q;
    double depth, cond;
  };
  std::vector<V> verts;
  double deepest = -1e300;
  for (const PV& p : poly) {
    verts.push_back({p.q, height(c.a, p.q) - height(c.b, p.q), p.cond});
    deepest = std::max(deepest, verts.back().depth);
  }
  std::ostringstream why;
  const double tol = 1e-6 * L + std::max(coord_mag(c.a), coord_mag(c.b)) * std::ldexp(1.0, -23);
  std::vector<Eigen::Vector2d> distinct;
  for (const V& v : verts)
    if (v.depth > tol) {
      bool dup = false;
      for (const auto& q : distinct) dup = dup || (q - v.q).norm() < 1e-4 * L;
      if (!dup) distinct.push_back(v.q);
    }
  bool has_deepest = false;
  for (uint32_t k = 0; k < r.count; ++k) {
    const Eigen::Vector2d q = proj(r.pt[k]);
    bool found = false;
    for (const V& v : verts) {
      if ((v.q - q).norm() > tol * v.cond || v.depth < -tol) continue;
      found = found || std::fabs(v.depth - r.pd[k]) <= tol * v.cond;
      has_deepest = has_deepest || v.depth >= deepest - tol;
    }
    if (!found) why << " point " << k << " is no penetrating vertex of the overlap polygon;";
  }
  if (!verts.empty() && deepest > tol && !has_deepest) why << " the deepest vertex (" << deepest << ") is missing;";
  if (r.count < std::min<size_t>(2, distinct.size())) why << " " << distinct.size() << " penetrating vertices, count " << r.count << ";";
  return why.str();
}

// ---------------------------------------------------------------------------------------
// Generators
// ---------------------------------------------------------------------------------------

/// A random triangle about c, vertices within `scale` of it, no sliver (every angle
/// above ~10 degrees).
Tri random_tri(std::mt19937& g, const Vec3d& c, double scale) {
  std::uniform_real_distribution<double> u(-1, 1);
  for (;;) {
    Vec3d v[3];
    for (Vec3d& x : v) x = c + scale * Vec3d(u(g), u(g), u(g));
    const Vec3d e0 = v[1] - v[0], e1 = v[2] - v[1], e2 = v[0] - v[2];
    const double area2 = e0.cross(-e2).norm();
    const double lmax = std::max({e0.squaredNorm(), e1.squaredNorm(), e2.squaredNorm()});
    if (area2 > 0.35 * lmax && lmax > 0.25 * scale * scale) return tri(v[0], v[1], v[2]);
  }
}

Vec3d random_unit(std::mt19937& g) {
  std::normal_distribution<double> d;
  for (;;) {
    const Vec3d v(d(g), d(g), d(g));
    if (v.norm() > 1e-3) return v.normalized();
  }
}

Vec3d centroid(const Tri& t) { return (t.p + t.v1 + t.v2) / 3.0; }

/// Random pairs at `scale` about centres `offset` from the origin: B's centroid at
/// lambda (rA + rB) from A's, lambda uniform in [lam_lo, lam_hi]; about half overlapping
/// (by the reference) unless lam_hi is small.
void random_cases(std::mt19937& g, uint32_t n, double scale, double offset, double lam_lo, double lam_hi,
                  std::vector<Case>& cases, std::vector<Ref>& refs) {
  std::uniform_real_distribution<double> u(-1, 1), lam(lam_lo, lam_hi);
  uint32_t over = 0, sep = 0;
  for (uint32_t attempt = 0; attempt < 40 * n && cases.size() < n; ++attempt) {
    Vec3d c = scale * Vec3d(u(g), u(g), u(g));
    for (int k = 0; k < 3; ++k) c[k] += offset * (u(g) < 0 ? -1 : 1);
    const Tri a = random_tri(g, c, scale);
    Tri b = random_tri(g, Vec3d::Zero(), scale);
    const double reach = bound(a) + bound(b);
    b = moved(b, centroid(a) - centroid(b) + lam(g) * reach * random_unit(g));
    const Case cs{a, b};
    const Ref f = reference(cs);
    const bool is_over = f.r.s > 0, last = attempt >= 30 * n;
    if (lam_hi > 0.2) {
      if (is_over && over >= (n + 1) / 2 && !last) continue;
      if (!is_over && sep >= n / 2 && !last) continue;
    }
    (is_over ? over : sep)++;
    cases.push_back(cs);
    refs.push_back(f);
  }
}

/// Rotates and moves a case (rigidly, about the origin then by t).
Case posed(const Case& c, const Eigen::Matrix3d& R, const Vec3d& t) {
  auto f = [&](const Tri& x) { return tri(R * x.p + t, R * x.v1 + t, R * x.v2 + t); };
  return {f(c.a), f(c.b)};
}

// ---------------------------------------------------------------------------------------
// Tests
// ---------------------------------------------------------------------------------------

TEST(TriangleTriangleReference, SatAndSampledMinimumAgree) {
  // The brute-force SAT and the sampled minimum are independent; where the pair
  // overlaps they must give the same depth, and both agree with the crossing test.
  std::mt19937 g(11);
  std::vector<Case> cases;
  std::vector<Ref> refs;
  random_cases(g, test::scaled(200), 1.0, 0.0, 0.0, 1.1, cases, refs);
  int crossing_checked = 0;
  for (size_t i = 0; i < cases.size(); ++i) {
    const Sat s = sat_double(cases[i].a, cases[i].b);
    const double s_ref = refs[i].r.s;
    if (s_ref > 0 || s.o > 0) {
      EXPECT_NEAR(s.o, s_ref, 1e-9 * refs[i].L) << "lane " << i << "\n" << literal(cases[i]);
      if (refs[i].r.unique(1e-6)) {
        EXPECT_LT(angle(s.n, ev(refs[i].r.n)), 1e-5) << "lane " << i;
      }
    }
    if (std::fabs(s_ref) > 1e-9 * refs[i].L) {
      EXPECT_EQ(triangles_cross(cases[i].a, cases[i].b), s_ref > 0) << "lane " << i << "\n" << literal(cases[i]);
      ++crossing_checked;
    }
  }
  EXPECT_GT(crossing_checked, static_cast<int>(cases.size()) * 9 / 10);
}

class TriangleTriangleScales : public ::testing::TestWithParam<std::pair<double, double>> {};

TEST_P(TriangleTriangleScales, RandomPosesAgainstReference) {
  const auto [scale, offset] = GetParam();
  std::mt19937 g(static_cast<uint32_t>(1000 + std::log10(scale) * 7 + (offset > 0 ? 50 : 0)));
  std::vector<Case> cases;
  std::vector<Ref> refs;
  random_cases(g, test::scaled(scale == 1.0 && offset == 0 ? 400 : 120), scale, offset, 0.0, 1.1, cases, refs);
  char what[64];
  std::snprintf(what, sizeof what, "random scale %g offset %g", scale, offset);
  EXPECT_EQ(check_all(cases, refs, what), 0);
}

INSTANTIATE_TEST_SUITE_P(Scales, TriangleTriangleScales,
                         ::testing::Values(std::pair{1.0, 0.0}, std::pair{1e-4, 0.0}, std::pair{1e4, 0.0},
                                           std::pair{1.0, 1e5}));

TEST(TriangleTriangle, DeepCrossingAndTouching) {
  std::mt19937 g(21);
  std::vector<Case> cases, touch;
  std::vector<Ref> refs, trefs;
  random_cases(g, test::scaled(120), 1.0, 0.0, 0.0, 0.05, cases, refs);
  EXPECT_EQ(check_all(cases, refs, "deep"), 0);
  // Touching: overlapping lanes with B moved by the reference's s n (in the band: either
  // answer; a hit must be ~0 deep).
  for (size_t i = 0; i < cases.size() && touch.size() < test::scaled(40); ++i) {
    if (refs[i].r.s <= 0) continue;
    touch.push_back({cases[i].a, moved(cases[i].b, refs[i].r.s * ev(refs[i].r.n))});
    trefs.push_back(reference(touch.back()));
  }
  EXPECT_EQ(check_all(touch, trefs, "touching"), 0);
}

TEST(TriangleTriangle, ExactTouchingIsNoContact) {
  // Representable configurations whose arithmetic is exact: depth 0 -> count 0.
  const std::vector<Case> cases = {
      // B's vertex on A's face, B above
      {tri({0, 0, 0}, {2, 0, 0}, {0, 2, 0}), tri({0.5, 0.5, 0}, {1, 0.5, 1}, {0.5, 1, 1})},
      // coplanar, overlapping (z = 0 and x = 0.25)
      {tri({0, 0, 0}, {2, 0, 0}, {0, 2, 0}), tri({0.5, 0.5, 0}, {3, 0.5, 0}, {0.5, 3, 0})},
      {tri({0.25, 0, 0}, {0.25, 2, 0}, {0.25, 0, 2}), tri({0.25, 1, 1}, {0.25, -1, 0.5}, {0.25, 0.5, -1})},
      // identical
      {tri({0, 0, 0}, {2, 0, 0}, {0, 2, 0}), tri({0, 0, 0}, {2, 0, 0}, {0, 2, 0})},
      // sharing an edge, hinged (z = 0 and x = 0 planes)
      {tri({0, 0, 0}, {0, 2, 0}, {1, 1, 0}), tri({0, 0, 0}, {0, 2, 0}, {0, 1, 1})},
      // edges crossing at a point, A below, B above
      {tri({-1, 0, 0}, {1, 0, 0}, {0, 0, -1}), tri({0, -1, 0}, {0, 1, 0}, {0, 0, 1})},
      // A's edge on B's face
      {tri({-1, 0, 0}, {1, 0, 0}, {0, -1, -1}), tri({-2, -2, 0}, {2, -2, 0}, {0, 2, 0})},
  };
  for (KernelPath path : {KernelPath::kScalar, KernelPath::kSimd})
    for (bool swap : {false, true}) {
      const ManifoldLanes out = run(cases, path, swap);
      for (uint32_t i = 0; i < cases.size(); ++i) {
        ASSERT_NEAR(reference(cases[i]).r.s, 0.0, 1e-12) << "case " << i << " is not touching";
        EXPECT_EQ(out.result(i).count, 0u) << "case " << i << " [" << path_name(path) << (swap ? ", swapped" : "")
                                           << "]\n" << literal(cases[i]) << "    " << describe(out.result(i));
      }
    }
}

TEST(TriangleTriangle, CoplanarOverlapIsTouching) {
  // Two overlapping triangles in one plane: A - B is flat, the least overlap is 0
  // (the reference's s is 0 up to the float rounding of the vertices): count 0 in both
  // orders, on both paths, at sizes 1e-2 .. 1e2 in rotated planes (the vertices' rounding
  // tilts them by ~1e-7 rad) and in axis planes 1e5 from the origin (exactly coplanar).
  std::mt19937 g(31);
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<Case> cases;
  for (uint32_t i = 0; i < test::scaled(200); ++i) {
    const double scale = std::pow(10.0, std::round(u(g) * 2));
    const int ax = static_cast<int>(i % 3);
    auto in_plane = [&](double x, double y) {
      Vec3d v = Vec3d::Zero();
      v[(ax + 1) % 3] = scale * x, v[(ax + 2) % 3] = scale * y;
      return v;
    };
    const Case flat{tri(in_plane(-1, -1), in_plane(1.5, -1), in_plane(-1, 1.5)),
                    tri(in_plane(u(g) * 0.3 + 1, u(g) * 0.3 + 1), in_plane(-1.2 + 0.2 * u(g), 0.2 * u(g)),
                        in_plane(0.2 * u(g), -1.2 + 0.2 * u(g)))};
    if (i % 2 == 0) {
      cases.push_back(posed(flat, test::random_rotation(g), Vec3d(u(g), u(g), u(g)) * scale));
    } else {
      const double far = 1e5 * (u(g) < 0 ? -1 : 1);
      cases.push_back(posed(flat, Eigen::Matrix3d::Identity(), Vec3d(far, far, far)));
    }
  }
  for (KernelPath path : {KernelPath::kScalar, KernelPath::kSimd})
    for (bool swap : {false, true}) {
      const ManifoldLanes out = run(cases, path, swap);
      for (uint32_t i = 0; i < cases.size(); ++i) {
        const Ref f = reference(cases[i]);
        ASSERT_LE(std::fabs(f.r.s), 1e-6 * f.L) << "lane " << i << " is not coplanar\n" << literal(cases[i]);
        EXPECT_EQ(out.result(i).count, 0u) << "lane " << i << " [" << path_name(path) << (swap ? ", swapped" : "")
                                           << "]\n" << literal(cases[i]) << "    " << describe(out.result(i));
      }
    }
}

TEST(TriangleTriangle, NearCoplanarCrossings) {
  // B in A's plane, then tilted by 1e-6 .. 1e-2 rad about an in-plane axis through the
  // common centroid: the two cross along a line, depth ~ tilt * reach.
  std::mt19937 g(41);
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<Case> cases;
  std::vector<Ref> refs;
  const double tilts[] = {1e-6, 1e-5, 1e-4, 1e-3, 1e-2};
  for (uint32_t i = 0; i < test::scaled(100); ++i) {
    const Vec3d c(u(g), u(g), u(g));
    const Eigen::Matrix3d R = test::random_rotation(g);
    Vec3d a[3], b[3];
    for (int k = 0; k < 3; ++k) {
      const double ang = 2.0944 * k + 0.3 * u(g);
      a[k] = Vec3d(std::cos(ang), std::sin(ang), 0) * (0.8 + 0.4 * u(g));
      const double bng = 2.0944 * k + 1.0 + 0.3 * u(g);
      b[k] = Vec3d(std::cos(bng), std::sin(bng), 0) * (0.8 + 0.4 * u(g));
    }
    const double t = tilts[i % 5] * (u(g) < 0 ? -1 : 1);
    const Eigen::Matrix3d tilt(Eigen::AngleAxisd(t, Vec3d(u(g), u(g), 0).normalized()));
    const Case cs{tri(R * a[0] + c, R * a[1] + c, R * a[2] + c),
                  tri(R * tilt * b[0] + c, R * tilt * b[1] + c, R * tilt * b[2] + c)};
    cases.push_back(cs);
    refs.push_back(reference(cs));
  }
  EXPECT_EQ(check_all(cases, refs, "near-coplanar"), 0);
}

TEST(TriangleTriangle, FaceManifoldIsThePenetratingOverlap) {
  // Random, deep and near-coplanar (tilts 1e-4 .. 1e-1) lanes whose normal is a face
  // normal: check_face_manifold.
  std::mt19937 g(45);
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<Case> cases;
  std::vector<Ref> refs;
  random_cases(g, test::scaled(300), 1.0, 0.0, 0.0, 1.1, cases, refs);
  random_cases(g, test::scaled(200), 1.0, 0.0, 0.0, 0.05, cases, refs);
  const double tilts[] = {1e-4, 1e-3, 1e-2, 1e-1};
  for (uint32_t i = 0; i < test::scaled(200); ++i) {
    const Vec3d c(u(g), u(g), u(g));
    const Eigen::Matrix3d R = test::random_rotation(g);
    Vec3d a[3], b[3];
    for (int k = 0; k < 3; ++k) {
      const double ang = 2.0944 * k + 0.3 * u(g), bng = 2.0944 * k + 1.0 + 0.3 * u(g);
      a[k] = Vec3d(std::cos(ang), std::sin(ang), 0) * (0.8 + 0.4 * u(g));
      b[k] = Vec3d(std::cos(bng), std::sin(bng), 0) * (0.8 + 0.4 * u(g)) + Vec3d(0.3 * u(g), 0.3 * u(g), 0);
    }
    const Eigen::Matrix3d tilt(Eigen::AngleAxisd(tilts[i % 4], Vec3d(u(g), u(g), 0).normalized()));
    cases.push_back({tri(R * a[0] + c, R * a[1] + c, R * a[2] + c),
                     tri(R * tilt * b[0] + c, R * tilt * b[1] + c, R * tilt * b[2] + c)});
    refs.push_back(reference(cases.back()));
  }
  for (KernelPath path : {KernelPath::kScalar, KernelPath::kSimd}) {
    const ManifoldLanes out = run(cases, path);
    uint32_t checked = 0, failures = 0;
    for (uint32_t i = 0; i < cases.size(); ++i) {
      bool chk = false;
      const PairResult r = out.result(i);
      const std::string why = check_face_manifold(cases[i], r, refs[i].L, &chk);
      checked += chk ? 1 : 0;
      if (why.empty()) continue;
      if (failures++ < 3) ADD_FAILURE() << "lane " << i << " [" << path_name(path) << "]:" << why << "\n" << literal(cases[i]) << "    " << describe(r);
    }
    std::printf("  face manifolds checked: %u of %zu lanes [%s]\n", checked, cases.size(), path_name(path));
    EXPECT_GT(checked, cases.size() / 10);
    EXPECT_EQ(failures, 0u);
  }
}

TEST(TriangleTriangle, NearParallelEdgesCrossing) {
  // A's edge along x, B's edge within 0 .. 1e-3 rad of it and 0 .. 0.04 away across it;
  // each third vertex at a random angle about its edge: the two cross-sections are rays
  // from nearby tips, so the edges pass through each other in about a fifth of the lanes and
  // the least translation is along the common perpendicular of the (near-parallel) edges,
  // a face normal, or another edge pair.
  std::mt19937 g(51);
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<Case> cases;
  std::vector<Ref> refs;
  const double angles[] = {0.0, 1e-7, 1e-5, 1e-3};
  for (uint32_t i = 0; i < test::scaled(200); ++i) {
    const Eigen::Matrix3d rot(Eigen::AngleAxisd(angles[i % 4], Vec3d(0, u(g), u(g)).normalized()));
    const double pa = M_PI * u(g), pb = M_PI * u(g), oa = M_PI * u(g);
    const Vec3d off = 0.04 * std::fabs(u(g)) * Vec3d(0, std::cos(oa), std::sin(oa)) + Vec3d(0.5 * u(g), 0, 0);
    const Case local{tri({-1, 0, 0}, {1, 0, 0}, {0.3 * u(g), std::cos(pa), std::sin(pa)}),
                     tri(rot * Vec3d(-1.2, 0, 0) + off, rot * Vec3d(0.9, 0, 0) + off,
                         rot * Vec3d(0.3 * u(g), std::cos(pb), std::sin(pb)) + off)};
    const Case cs = posed(local, test::random_rotation(g), Vec3d(u(g), u(g), u(g)));
    cases.push_back(cs);
    refs.push_back(reference(cs));
  }
  EXPECT_EQ(check_all(cases, refs, "edge-edge near-parallel"), 0);
  uint32_t hits = 0;
  for (const Ref& f : refs) hits += f.r.s > f.tol ? 1 : 0;
  EXPECT_GT(hits, cases.size() / 8);
}

TEST(TriangleTriangle, NearParallelKnifeEdges) {
  // Two steep triangles, A hanging below its edge along x, B standing above its edge,
  // which is turned by theta = 1e-5 .. 3e-2 rad about z and lowered by delta below A's:
  // the edges cross like two knife edges and, for delta below ~theta, the least
  // translation is along their common perpendicular (z): the near-parallel edge axis
  // itself wins (its float cross product points ~eps / theta off; theta < 0.05 takes
  // the double path).
  std::mt19937 g(53);
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<Case> cases;
  std::vector<Ref> refs;
  const double thetas[] = {1e-5, 1e-4, 1e-3, 1e-2, 3e-2};
  uint32_t edge_wins = 0;
  for (uint32_t i = 0; i < test::scaled(200); ++i) {
    const double th = thetas[i % 5];
    const double delta = (0.3 * u(g) + 0.1) * th;  // mostly overlapping
    const Eigen::Matrix3d rz(Eigen::AngleAxisd(th, Vec3d::UnitZ()));
    const Vec3d c(0.3 * u(g), 0, -delta);
    const Case local{tri({-1, 0, 0}, {1, 0, 0}, {0.3 * u(g), 0.2 * u(g), -1}),
                     tri(rz * Vec3d(-1.1, 0, 0) + c, rz * Vec3d(0.9, 0, 0) + c, rz * Vec3d(0.3 * u(g), 0.2 * u(g), 1) + c)};
    const Eigen::Matrix3d R = test::random_rotation(g);
    const Case cs = posed(local, R, Vec3d(u(g), u(g), u(g)));
    cases.push_back(cs);
    refs.push_back(reference(cs));
    edge_wins += (refs.back().r.s > 0 && angle(ev(refs.back().r.n), R * Vec3d::UnitZ()) < 1e-3) ? 1 : 0;
  }
  EXPECT_EQ(check_all(cases, refs, "knife edges near-parallel"), 0);
  EXPECT_GT(edge_wins, cases.size() / 3);
}

TEST(TriangleTriangle, SliversAgainstReference) {
  // B a sliver: base p..q, apex off the base's middle by h |pq|, h = 1e-3 .. 1e-7.
  std::mt19937 g(61);
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<Case> cases;
  std::vector<Ref> refs;
  const double hs[] = {1e-3, 1e-5, 1e-7};
  uint32_t over = 0;
  for (uint32_t i = 0; i < test::scaled(150); ++i) {
    const Tri a = random_tri(g, Vec3d::Zero(), 1.0);
    const double len = 1.0 + 0.5 * u(g), h = hs[i % 3];
    const Vec3d d = random_unit(g), e = d.cross(random_unit(g)).normalized();
    const Vec3d p = centroid(a) + Vec3d(u(g), u(g), u(g)) * 0.5 - 0.5 * len * d;
    const Vec3d q = p + len * d, apex = p + (0.3 + 0.4 * (u(g) + 1) / 2) * len * d + h * len * e;
    const Case cs = (i % 2) ? Case{a, tri(p, q, apex)} : Case{tri(p, apex, q), a};
    cases.push_back(cs);
    refs.push_back(reference(cs));
    over += refs.back().r.s > 0 ? 1 : 0;
  }
  EXPECT_GT(over, cases.size() / 5);
  // Points get 1e-3 L: a sliver's three edges give edge axes equal within rounding, and
  // the one taken may name the wrong half of the sliver as the support feature (measured:
  // 1 lane in ~800 hits, 1.2e-4 L off B; depth and normal are not affected).
  EXPECT_EQ(check_all(cases, refs, "slivers", 1e-3), 0);
}

TEST(TriangleTriangle, DegenerateTrianglesGiveFiniteOutput) {
  // Zero-area triangles: collinear, two or three coincident vertices, against proper
  // triangles and each other. A degenerate triangle against a proper one is still
  // checked against the reference (its SAT axes stay complete: the segment's crosses);
  // two degenerate ones only for finite output and depth within rounding of 0 (their
  // difference is flat: s <= 0).
  std::mt19937 g(71);
  std::uniform_real_distribution<double> u(-1, 1);
  auto degenerate = [&](int kind) {
    const Vec3d p = Vec3d(u(g), u(g), u(g)) * 0.7, d = random_unit(g);
    switch (kind) {
      case 0: return tri(p, p + d, p + 0.4 * d);  // collinear
      case 1: return tri(p, p + d, p + d);        // two coincident
      case 2: return tri(p, p, p + d);
      default: return tri(p, p, p);  // a point
    }
  };
  std::vector<Case> proper, both;
  for (uint32_t i = 0; i < test::scaled(120); ++i) {
    const Tri t = random_tri(g, Vec3d::Zero(), 1.0);
    const Tri d = degenerate(static_cast<int>(i % 4));
    proper.push_back((i / 4) % 2 ? Case{t, d} : Case{d, t});
    both.push_back({d, degenerate(static_cast<int>((i / 4) % 4))});
  }
  EXPECT_EQ(check_all(proper, references(proper), "degenerate vs proper"), 0);
  for (KernelPath path : {KernelPath::kScalar, KernelPath::kSimd}) {
    const ManifoldLanes out = run(both, path);
    for (uint32_t i = 0; i < both.size(); ++i) {
      const PairResult r = out.result(i);
      ASSERT_LE(r.count, 4u);
      if (r.count == 0) continue;
      EXPECT_TRUE(std::isfinite(r.depth) && r.n.allFinite()) << "lane " << i;
      EXPECT_LE(r.depth, 1e-5) << "lane " << i << "\n" << literal(both[i]) << "    " << describe(r);
      for (uint32_t q = 0; q < r.count; ++q) EXPECT_TRUE(r.pt[q].allFinite() && std::isfinite(r.pd[q]));
    }
  }
}

TEST(TriangleTriangle, FaceTieTakesANormal) {
  // A and B mirror images through the plane x = 0 (exact in float), crossing: their
  // normals' overlaps tie exactly in reals; the tie rule takes A's normal (B's only
  // when shallower by more than the tie tolerance), and the swapped pair takes B's.
  std::mt19937 g(81);
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<Case> cases;
  for (uint32_t i = 0; i < test::scaled(60); ++i) {
    const Vec3d a0(0.6 + 0.2 * u(g), 0.1 * u(g), 0.1 * u(g)), a1(-0.5 + 0.1 * u(g), -0.6 + 0.1 * u(g), 0.3 * u(g)),
        a2(-0.5 + 0.1 * u(g), 0.6 + 0.1 * u(g), 0.3 * u(g));
    // tilt A about y so that it crosses its mirror image
    const Eigen::Matrix3d t(Eigen::AngleAxisd(0.4 + 0.3 * u(g), Vec3d::UnitY()));
    const Tri a = tri(t * a0, t * a1, t * a2);
    auto mirror = [](const Vec3d& v) { return Vec3d(-v.x(), v.y(), v.z()); };
    cases.push_back({a, tri(mirror(a.p), mirror(a.v1), mirror(a.v2))});
  }
  for (KernelPath path : {KernelPath::kScalar, KernelPath::kSimd}) {
    uint32_t face_wins = 0;
    const ManifoldLanes ab = run(cases, path), ba = run(cases, path, true);
    for (uint32_t i = 0; i < cases.size(); ++i) {
      const Case& c = cases[i];
      const Vec3d na = (c.a.v1 - c.a.p).cross(c.a.v2 - c.a.p).normalized();
      const Vec3d nb = (c.b.v1 - c.b.p).cross(c.b.v2 - c.b.p).normalized();
      const Sat s = sat_double(c.a, c.b);
      // only lanes where the faces are the least overlap (not an edge axis)
      if (std::min(angle(s.n, na), angle(s.n, -na)) > 1e-9 && std::min(angle(s.n, nb), angle(s.n, -nb)) > 1e-9)
        continue;
      const PairResult x = ab.result(i), y = ba.result(i);
      ASSERT_GT(x.count, 0u);
      ASSERT_GT(y.count, 0u);
      ++face_wins;
      EXPECT_LT(std::min(angle(x.n, na), angle(x.n, -na)), 1e-6) << "lane " << i << "\n" << literal(c) << describe(x);
      EXPECT_LT(std::min(angle(y.n, nb), angle(y.n, -nb)), 1e-6) << "lane " << i << " swapped\n" << describe(y);
    }
    EXPECT_GT(face_wins, cases.size() / 5);
  }
}

TEST(TriangleTriangle, SwapSymmetry) {
  std::mt19937 g(91);
  std::vector<Case> cases;
  std::vector<Ref> refs;
  random_cases(g, test::scaled(300), 1.0, 0.0, 0.0, 1.1, cases, refs);
  for (KernelPath path : {KernelPath::kScalar, KernelPath::kSimd}) {
    const ManifoldLanes ab = run(cases, path), ba = run(cases, path, true);
    for (uint32_t i = 0; i < cases.size(); ++i) {
      const double tol = refs[i].tol;
      if (std::fabs(refs[i].r.s) <= tol) continue;
      const PairResult x = ab.result(i), y = ba.result(i);
      ASSERT_EQ(x.count > 0, y.count > 0) << "lane " << i;
      if (x.count == 0) continue;
      EXPECT_NEAR(x.depth, y.depth, tol) << "lane " << i;
      // -y.n must be a minimum direction for (A, B) as well (ties may pick another axis)
      const double o = nref::overlap(shape(cases[i].a), shape(cases[i].b), nv(Vec3d(-y.n)));
      if (angle(x.n, -y.n) > kAngleTol) {
        EXPECT_LE(o, refs[i].r.s + tol) << "lane " << i;
      }
    }
  }
}

}  // namespace
}  // namespace impact::kernels
