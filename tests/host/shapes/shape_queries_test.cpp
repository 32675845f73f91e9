// raycast_shapes / query_shape_points against an independent double-precision
// reference written here from the shapes' definitions:
//  - membership: |x| <= r (sphere), distance to the core segment <= r (capsule),
//    |x_i| <= e_i (box), every face plane (hulls: planes found here by brute force over
//    the point cloud's triples, not from the library's hull), rho <= r and |z| <= h
//    (cylinder), sum (x_i / e_i)^2 <= 1 (ellipsoid), n.x <= offset (half-space); unions
//    of children for compounds;
//  - ray entry: fine stepping along the ray in double, then bisection, refined near the
//    library's answer when the coarse steps could have stepped over a thin chord;
//  - signed distance: closed forms (sphere, capsule, box, cylinder, half-space), plane
//    distances inside / point-triangle distances outside (hulls), dense sampling of the
//    surface plus local pattern search (ellipsoids);
//  - meshes: the BVH answer equals a brute force over every triangle (same kernel,
//    bit for bit) and a double-precision ray-triangle / point-triangle reference.
// Acceptance is geometric: a hit point within tol of the surface and t within tol of
// the reference entry, or (grazing / glancing rays) the ray between the two entries
// hugging the surface within tol. tol scales with the shape's size and the query's
// distance from it (float rounding of the local transform), so tiny (1e-4), huge
// (1e4) and far (1e5 from the origin) cases run through the same checks.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "host/shapes/shape_store.h"
#include "impact/shape_queries.h"
#include "impact/shapes.h"
#include "kernels/narrowphase/leaf/leaf_queries.h"
#include "kernels/raycast/ray_primitives.h"
#include "tests/support/test_support.h"

namespace impact {
namespace {

using Eigen::Matrix3d;
using Eigen::Vector3d;
using Eigen::Vector3f;

constexpr double kPi = 3.14159265358979323846;

// --- the reference ----------------------------------------------------------------------

// One convex piece in its own frame, placed by (R, p) in the shape's frame.
struct RefLeaf {
  ShapeType type = ShapeType::kSphere;
  double e[3] = {0, 0, 0};
  Vector3d n = Vector3d::UnitZ();  // half-space
  double off = 0.0;
  std::vector<Vector3d> pn;        // hull planes pn.x <= pd
  std::vector<double> pd;
  std::vector<std::array<Vector3d, 3>> tris;  // hull faces as triangles (any 3 coplanar vertices)
  Matrix3d R = Matrix3d::Identity();
  Vector3d p = Vector3d::Zero();
};

struct RefShape {
  ShapeType type = ShapeType::kSphere;
  std::vector<RefLeaf> leaves;
  double size = 1.0;   // radius of a ball about the origin that holds the shape
  double thin = 1.0;   // smallest feature size (for the ray steps and normal tolerances)
};

double seg_dist(const Vector3d& x, const Vector3d& a, const Vector3d& b) {
  const Vector3d ab = b - a;
  const double l2 = ab.squaredNorm();
  const double s = l2 > 0 ? std::clamp((x - a).dot(ab) / l2, 0.0, 1.0) : 0.0;
  return (x - (a + s * ab)).norm();
}

// Point-triangle distance: projection + barycentric test, else the three edges
// (a different route from the kernel's Voronoi-region walk).
double tri_dist(const Vector3d& x, const Vector3d& a, const Vector3d& b, const Vector3d& c) {
  const Vector3d n = (b - a).cross(c - a);
  const double n2 = n.squaredNorm();
  if (n2 > 0) {
    const Vector3d q = x - n * ((x - a).dot(n) / n2);
    const double u = (c - b).cross(q - b).dot(n), v = (a - c).cross(q - c).dot(n), w = (b - a).cross(q - a).dot(n);
    if (u >= 0 && v >= 0 && w >= 0) return std::fabs((x - a).dot(n)) / std::sqrt(n2);
  }
  return std::min({seg_dist(x, a, b), seg_dist(x, b, c), seg_dist(x, c, a)});
}

const std::vector<Vector3d>& fib_sphere() {
  static const std::vector<Vector3d> pts = [] {
    std::vector<Vector3d> v;
    const int n = 4096;
    const double ga = kPi * (3.0 - std::sqrt(5.0));
    for (int i = 0; i < n; ++i) {
      const double z = 1.0 - (2.0 * i + 1.0) / n;
      const double r = std::sqrt(1.0 - z * z);
      v.emplace_back(r * std::cos(ga * i), r * std::sin(ga * i), z);
    }
    return v;
  }();
  return pts;
}

// Unsigned distance from x to the ellipsoid surface: the surface as the radial image
// of the unit sphere, dense samples, then a pattern search on the sphere from the
// best few samples.
double ellipsoid_surface_dist(const double e[3], const Vector3d& x) {
  auto surf = [&](const Vector3d& u) {
    const double k = std::sqrt(std::pow(u[0] / e[0], 2) + std::pow(u[1] / e[1], 2) + std::pow(u[2] / e[2], 2));
    return Vector3d(u / k);
  };
  auto f = [&](const Vector3d& u) { return (surf(u) - x).squaredNorm(); };
  const auto& pts = fib_sphere();
  std::vector<std::pair<double, int>> s;
  s.reserve(pts.size());
  for (int i = 0; i < static_cast<int>(pts.size()); ++i) s.push_back({f(pts[i]), i});
  std::partial_sort(s.begin(), s.begin() + 6, s.end());
  double best = s[0].first;
  for (int k = 0; k < 6; ++k) {
    Vector3d u = pts[s[k].second];
    double fu = s[k].first, h = 0.05;
    while (h > 1e-13) {
      const Vector3d t1 = u.unitOrthogonal(), t2 = u.cross(t1);
      bool moved = false;
      for (const Vector3d& dir : {t1, Vector3d(-t1), t2, Vector3d(-t2), Vector3d((t1 + t2) * 0.7071), Vector3d((-t1 - t2) * 0.7071),
                                  Vector3d((t1 - t2) * 0.7071), Vector3d((t2 - t1) * 0.7071)}) {
        const Vector3d v = (u + h * dir).normalized();
        const double fv = f(v);
        if (fv < fu) {
          u = v;
          fu = fv;
          moved = true;
          break;
        }
      }
      if (!moved) h *= 0.5;
    }
    best = std::min(best, fu);
  }
  return std::sqrt(best);
}

bool leaf_inside(const RefLeaf& l, const Vector3d& x) {
  switch (l.type) {
    case ShapeType::kSphere: return x.norm() <= l.e[0];
    case ShapeType::kCapsule: return seg_dist(x, Vector3d(0, 0, -l.e[1]), Vector3d(0, 0, l.e[1])) <= l.e[0];
    case ShapeType::kBox:
    case ShapeType::kAabb:
      return std::fabs(x[0]) <= l.e[0] && std::fabs(x[1]) <= l.e[1] && std::fabs(x[2]) <= l.e[2];
    case ShapeType::kCylinder: return std::hypot(x[0], x[1]) <= l.e[0] && std::fabs(x[2]) <= l.e[1];
    case ShapeType::kEllipsoid: {
      double s = 0;
      for (int i = 0; i < 3; ++i) s += (x[i] / l.e[i]) * (x[i] / l.e[i]);
      return s <= 1.0;
    }
    case ShapeType::kHalfSpace: return l.n.dot(x) <= l.off;
    case ShapeType::kConvex:
      for (size_t f = 0; f < l.pn.size(); ++f)
        if (l.pn[f].dot(x) > l.pd[f]) return false;
      return true;
    default: return false;
  }
}

double leaf_sd(const RefLeaf& l, const Vector3d& x) {
  switch (l.type) {
    case ShapeType::kSphere: return x.norm() - l.e[0];
    case ShapeType::kCapsule: return seg_dist(x, Vector3d(0, 0, -l.e[1]), Vector3d(0, 0, l.e[1])) - l.e[0];
    case ShapeType::kBox:
    case ShapeType::kAabb: {
      const Vector3d q(std::fabs(x[0]) - l.e[0], std::fabs(x[1]) - l.e[1], std::fabs(x[2]) - l.e[2]);
      return q.cwiseMax(0.0).norm() + std::min(q.maxCoeff(), 0.0);
    }
    case ShapeType::kCylinder: {
      const double a = std::hypot(x[0], x[1]) - l.e[0], b = std::fabs(x[2]) - l.e[1];
      return std::min(std::max(a, b), 0.0) + std::hypot(std::max(a, 0.0), std::max(b, 0.0));
    }
    case ShapeType::kEllipsoid: {
      const double d = ellipsoid_surface_dist(l.e, x);
      return leaf_inside(l, x) ? -d : d;
    }
    case ShapeType::kHalfSpace: return l.n.dot(x) - l.off;
    case ShapeType::kConvex: {
      double m = -1e300;
      for (size_t f = 0; f < l.pn.size(); ++f) m = std::max(m, l.pn[f].dot(x) - l.pd[f]);
      if (m <= 0) return m;
      double d = 1e300;
      for (const auto& t : l.tris) d = std::min(d, tri_dist(x, t[0], t[1], t[2]));
      return d;
    }
    default: return 0;
  }
}

// Valid outward normals at a surface point x (every face within tol of x).
void leaf_normals(const RefLeaf& l, const Vector3d& x, double tol, std::vector<Vector3d>* out) {
  switch (l.type) {
    case ShapeType::kSphere: out->push_back(x.normalized()); return;
    case ShapeType::kCapsule: {
      const double zc = std::clamp(x[2], -l.e[1], l.e[1]);
      out->push_back((x - Vector3d(0, 0, zc)).normalized());
      return;
    }
    case ShapeType::kBox:
    case ShapeType::kAabb:
      for (int i = 0; i < 3; ++i)
        if (std::fabs(std::fabs(x[i]) - l.e[i]) <= tol) out->push_back(Vector3d::Unit(i) * (x[i] < 0 ? -1.0 : 1.0));
      return;
    case ShapeType::kCylinder:
      if (std::fabs(std::hypot(x[0], x[1]) - l.e[0]) <= tol) out->push_back(Vector3d(x[0], x[1], 0).normalized());
      if (std::fabs(std::fabs(x[2]) - l.e[1]) <= tol) out->push_back(Vector3d(0, 0, x[2] < 0 ? -1 : 1));
      return;
    case ShapeType::kEllipsoid:
      out->push_back(Vector3d(x[0] / (l.e[0] * l.e[0]), x[1] / (l.e[1] * l.e[1]), x[2] / (l.e[2] * l.e[2])).normalized());
      return;
    case ShapeType::kHalfSpace: out->push_back(l.n); return;
    case ShapeType::kConvex:
      for (size_t f = 0; f < l.pn.size(); ++f)
        if (std::fabs(l.pn[f].dot(x) - l.pd[f]) <= tol) out->push_back(l.pn[f]);
      return;
    default: return;
  }
}

Vector3d to_leaf(const RefLeaf& l, const Vector3d& x) { return l.R.transpose() * (x - l.p); }

bool ref_inside(const RefShape& s, const Vector3d& x) {
  for (const RefLeaf& l : s.leaves)
    if (leaf_inside(l, to_leaf(l, x))) return true;
  return false;
}

double ref_sd(const RefShape& s, const Vector3d& x, int* which = nullptr) {
  double best = 1e300;
  for (size_t i = 0; i < s.leaves.size(); ++i) {
    const double d = leaf_sd(s.leaves[i], to_leaf(s.leaves[i], x));
    if (d < best) {
      best = d;
      if (which) *which = static_cast<int>(i);
    }
  }
  return best;
}

std::vector<Vector3d> ref_normals(const RefShape& s, const Vector3d& x, double tol) {
  std::vector<Vector3d> out;
  for (const RefLeaf& l : s.leaves) {
    const Vector3d xl = to_leaf(l, x);
    if (std::fabs(leaf_sd(l, xl)) > tol) continue;
    std::vector<Vector3d> ln;
    leaf_normals(l, xl, tol, &ln);
    for (const Vector3d& n : ln) out.push_back(l.R * n);
  }
  return out;
}

// Entry of the ray o + t d (d unit, shape frame) into the shape over t in [ta, tb]:
// steps of (tb - ta) / steps, then bisection. Also the exit after the entry.
struct RefRay {
  bool hit = false;
  double t = 0, t_exit = 0;
};

RefRay step_ray(const RefShape& s, const Vector3d& o, const Vector3d& d, double ta, double tb, int steps) {
  RefRay r;
  auto in = [&](double t) { return ref_inside(s, o + t * d); };
  if (in(ta)) {
    r.hit = true;
    r.t = ta;
  } else {
    const double dt = (tb - ta) / steps;
    double prev = ta;
    for (int k = 1; k <= steps; ++k) {
      const double t = ta + k * dt;
      if (in(t)) {
        double lo = prev, hi = t;
        for (int it = 0; it < 100; ++it) {
          const double m = 0.5 * (lo + hi);
          if (m <= lo || m >= hi) break;
          (in(m) ? hi : lo) = m;
        }
        r.hit = true;
        r.t = hi;
        break;
      }
      prev = t;
    }
    if (!r.hit) return r;
  }
  const double dt = (tb - r.t) / steps;
  double prev = r.t;
  r.t_exit = tb;
  for (int k = 1; k <= steps; ++k) {
    const double t = r.t + k * dt;
    if (!in(t)) {
      double lo = prev, hi = t;
      for (int it = 0; it < 100; ++it) {
        const double m = 0.5 * (lo + hi);
        if (m <= lo || m >= hi) break;
        (in(m) ? lo : hi) = m;
      }
      r.t_exit = lo;
      break;
    }
    prev = t;
  }
  return r;
}

// Where the ray is inside the shape's bounding ball (half-spaces: analytic).
bool ray_window(const RefShape& s, const Vector3d& o, const Vector3d& d, double* ta, double* tb) {
  const double R = s.size * 1.01;
  const double b = o.dot(d), c = o.squaredNorm() - R * R;
  const double disc = b * b - c;
  if (disc < 0) return false;
  const double sq = std::sqrt(disc);
  *ta = std::max(0.0, -b - sq);
  *tb = -b + sq;
  return *tb >= 0;
}

// --- test shapes ------------------------------------------------------------------------

struct TestShape {
  ShapeId id;
  RefShape ref;
};

RefLeaf hull_leaf(const std::vector<Vector3d>& pts) {
  RefLeaf l;
  l.type = ShapeType::kConvex;
  double scale = 0;
  for (const Vector3d& p : pts) scale = std::max(scale, p.norm());
  const double eps = 1e-9 * scale;
  const size_t n = pts.size();
  for (size_t i = 0; i < n; ++i)
    for (size_t j = i + 1; j < n; ++j)
      for (size_t k = j + 1; k < n; ++k) {
        Vector3d nn = (pts[j] - pts[i]).cross(pts[k] - pts[i]);
        if (nn.norm() <= 1e-12 * scale * scale) continue;
        nn.normalize();
        for (double sg : {1.0, -1.0}) {
          const Vector3d m = sg * nn;
          const double dd = m.dot(pts[i]);
          bool ok = true;
          for (size_t q = 0; q < n && ok; ++q) ok = m.dot(pts[q]) <= dd + eps;
          if (!ok) continue;
          bool dup = false;
          for (size_t f = 0; f < l.pn.size(); ++f) dup |= (l.pn[f] - m).norm() < 1e-9 && std::fabs(l.pd[f] - dd) <= eps;
          if (dup) continue;
          l.pn.push_back(m);
          l.pd.push_back(dd);
          std::vector<Vector3d> on;
          for (const Vector3d& p : pts)
            if (std::fabs(m.dot(p) - dd) <= eps) on.push_back(p);
          for (size_t a = 0; a < on.size(); ++a)
            for (size_t b = a + 1; b < on.size(); ++b)
              for (size_t c = b + 1; c < on.size(); ++c) l.tris.push_back({on[a], on[b], on[c]});
        }
      }
  return l;
}

class Builder {
 public:
  ShapeSet set;
  std::mt19937 rng{12345};

  double uni(double a, double b) { return std::uniform_real_distribution<double>(a, b)(rng); }

  TestShape sphere(double r) {
    TestShape t;
    IMPACT_EXPECT_OK(set.add_sphere(static_cast<float>(r), &t.id));
    t.ref = single(leaf(ShapeType::kSphere, r, 0, 0));
    return t;
  }
  TestShape capsule(double r, double h) {
    TestShape t;
    IMPACT_EXPECT_OK(set.add_capsule(static_cast<float>(r), static_cast<float>(h), &t.id));
    t.ref = single(leaf(ShapeType::kCapsule, r, h, 0));
    return t;
  }
  TestShape box(Vector3d e, bool aabb = false) {
    TestShape t;
    IMPACT_EXPECT_OK(aabb ? set.add_aabb(e.cast<float>(), &t.id) : set.add_box(e.cast<float>(), &t.id));
    t.ref = single(leaf(aabb ? ShapeType::kAabb : ShapeType::kBox, e[0], e[1], e[2]));
    return t;
  }
  TestShape cylinder(double r, double h) {
    TestShape t;
    IMPACT_EXPECT_OK(set.add_cylinder(static_cast<float>(r), static_cast<float>(h), &t.id));
    t.ref = single(leaf(ShapeType::kCylinder, r, h, 0));
    return t;
  }
  TestShape ellipsoid(Vector3d e) {
    TestShape t;
    IMPACT_EXPECT_OK(set.add_ellipsoid(e.cast<float>(), &t.id));
    t.ref = single(leaf(ShapeType::kEllipsoid, e[0], e[1], e[2]));
    return t;
  }
  TestShape half_space(Vector3d n, double off) {
    TestShape t;
    IMPACT_EXPECT_OK(set.add_half_space(n.cast<float>(), static_cast<float>(off), &t.id));
    RefLeaf l;
    l.type = ShapeType::kHalfSpace;
    l.n = test::round_to_float(n).normalized();
    l.off = static_cast<float>(off);
    t.ref = single(l);
    return t;
  }
  // Float points of the cloud; the reference sees exactly those floats.
  TestShape hull(const std::vector<Vector3d>& pts_in) {
    std::vector<Vector3f> pf;
    std::vector<Vector3d> pd;
    for (const Vector3d& p : pts_in) {
      pf.push_back(p.cast<float>());
      pd.push_back(pf.back().cast<double>());
    }
    TestShape t;
    IMPACT_EXPECT_OK(set.add_convex_hull(pf, &t.id));
    t.ref = single(hull_leaf(pd));
    return t;
  }
  TestShape compound(const std::vector<std::pair<TestShape, Pose>>& kids) {
    std::vector<CompoundChild> cc;
    TestShape t;
    t.ref.type = ShapeType::kCompound;
    t.ref.size = 0;
    t.ref.thin = 1e300;
    for (const auto& [ts, pose] : kids) {
      cc.push_back({ts.id, pose});
      RefLeaf l = ts.ref.leaves[0];
      const Eigen::Quaterniond q = pose.orientation.cast<double>().normalized();
      l.R = q.toRotationMatrix();
      l.p = pose.position.cast<double>();
      t.ref.leaves.push_back(l);
      t.ref.size = std::max(t.ref.size, l.p.norm() + ts.ref.size);
      t.ref.thin = std::min(t.ref.thin, ts.ref.thin);
    }
    IMPACT_EXPECT_OK(set.add_compound(cc, &t.id));
    return t;
  }

  static RefLeaf leaf(ShapeType type, double a, double b, double c) {
    RefLeaf l;
    l.type = type;
    l.e[0] = static_cast<float>(a);
    l.e[1] = static_cast<float>(b);
    l.e[2] = static_cast<float>(c);
    return l;
  }
  static RefShape single(const RefLeaf& l) {
    RefShape s;
    s.type = l.type;
    s.leaves.push_back(l);
    const double* e = l.e;
    switch (l.type) {
      case ShapeType::kSphere: s.size = e[0]; s.thin = e[0]; break;
      case ShapeType::kCapsule: s.size = e[0] + e[1]; s.thin = e[0]; break;
      case ShapeType::kBox:
      case ShapeType::kAabb:
        s.size = std::sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]);
        s.thin = std::min({e[0], e[1], e[2]});
        break;
      case ShapeType::kCylinder: s.size = std::hypot(e[0], e[1]); s.thin = std::min(e[0], e[1]); break;
      case ShapeType::kEllipsoid: s.size = std::max({e[0], e[1], e[2]}); s.thin = std::min({e[0], e[1], e[2]}); break;
      case ShapeType::kConvex: {
        s.size = 0;
        for (const auto& t : l.tris)
          for (const Vector3d& v : t) s.size = std::max(s.size, v.norm());
        double inr = 1e300;  // inradius-ish: plane distances from the centroid-free origin
        for (double d : l.pd) inr = std::min(inr, std::fabs(d));
        s.thin = std::max(inr, 1e-3 * s.size);
        break;
      }
      default: s.size = 1e300; s.thin = 1; break;
    }
    return s;
  }

  Pose random_pose(double spread, double far) {
    Pose p;
    Eigen::Vector4f q(static_cast<float>(uni(-1, 1)), static_cast<float>(uni(-1, 1)), static_cast<float>(uni(-1, 1)),
                      static_cast<float>(uni(-1, 1)));
    q.normalize();
    p.orientation = Eigen::Quaternionf(q[3], q[0], q[1], q[2]);
    p.position = Vector3d(far + uni(-spread, spread), uni(-spread, spread), -far + uni(-spread, spread)).cast<float>();
    return p;
  }
  Vector3d unit() {
    Vector3d v;
    do v = Vector3d(uni(-1, 1), uni(-1, 1), uni(-1, 1));
    while (v.norm() > 1 || v.norm() < 1e-3);
    return v.normalized();
  }
};

// A set of shapes of every convex type at scale s (plus a half-space), with random
// aspect ratios.
std::vector<TestShape> convex_zoo(Builder& b, double s) {
  std::vector<TestShape> z;
  z.push_back(b.sphere(s * b.uni(0.3, 1.5)));
  z.push_back(b.capsule(s * b.uni(0.2, 0.8), s * b.uni(0.1, 1.5)));
  z.push_back(b.capsule(s * 0.5, 0.0));
  z.push_back(b.box(s * Vector3d(b.uni(0.1, 1.5), b.uni(0.1, 1.5), b.uni(0.1, 1.5))));
  z.push_back(b.box(s * Vector3d(b.uni(0.2, 1.0), b.uni(0.2, 1.0), b.uni(0.2, 1.0)), /*aabb=*/true));
  z.push_back(b.cylinder(s * b.uni(0.2, 1.2), s * b.uni(0.1, 1.2)));
  z.push_back(b.ellipsoid(s * Vector3d(b.uni(0.2, 1.5), b.uni(0.2, 1.5), b.uni(0.2, 1.5))));
  z.push_back(b.ellipsoid(s * Vector3d(1.0, 1.0, 0.4)));  // equal radii (spheroid)
  // Hulls: a cube (quad faces), an octahedron, a random tetrahedron, a random polytope.
  std::vector<Vector3d> cube, octa, tet, blob;
  for (int i = 0; i < 8; ++i) cube.push_back(s * 0.7 * Vector3d(i & 1 ? 1 : -1, i & 2 ? 1 : -1, i & 4 ? 1 : -1));
  for (int i = 0; i < 3; ++i) {
    octa.push_back(s * Vector3d::Unit(i));
    octa.push_back(-s * Vector3d::Unit(i));
  }
  for (;;) {
    tet.clear();
    for (int i = 0; i < 4; ++i) tet.push_back(s * b.unit() * b.uni(0.5, 1.0));
    Vector3d c = (tet[0] + tet[1] + tet[2] + tet[3]) / 4;
    for (Vector3d& v : tet) v -= c;
    if (std::fabs((tet[1] - tet[0]).cross(tet[2] - tet[0]).dot(tet[3] - tet[0])) > 0.2 * s * s * s) break;
  }
  for (int i = 0; i < 14; ++i) blob.push_back(s * Vector3d(b.uni(0.5, 1.2) * b.unit()));
  z.push_back(b.hull(cube));
  z.push_back(b.hull(octa));
  z.push_back(b.hull(tet));
  z.push_back(b.hull(blob));
  return z;
}

// --- checks -----------------------------------------------------------------------------

struct Posed {
  Matrix3d R;
  Vector3d p;
};

Posed posed(const RefShape& s, const Pose& pose) {
  Posed q;
  q.R = s.type == ShapeType::kAabb ? Matrix3d::Identity()
                                   : Matrix3d(pose.orientation.cast<double>().normalized().toRotationMatrix());
  q.p = pose.position.cast<double>();
  return q;
}

Vector3d unit_dir(const Vector3f& d) { return test::round_to_float(d.cast<double>().normalized()); }

struct Stats {
  int hits = 0, misses = 0, inside = 0, grazing = 0, total = 0;
};

// Checks one ray result against the reference; returns a failure description or "".
std::string check_ray(const RefShape& s, const Pose& pose, const Ray& ray, const ShapeRayHit& h, Stats* st) {
  ++st->total;
  const Posed P = posed(s, pose);
  const Vector3d dw = unit_dir(ray.direction);
  const Vector3d o = P.R.transpose() * (ray.origin.cast<double>() - P.p);
  const Vector3d d = P.R.transpose() * dw;
  const double tmax = ray.tmax;
  const double tol = 2e-6 * (s.size + o.norm()) + 1e-30;
  const bool half = s.type == ShapeType::kHalfSpace;

  // Reference entry.
  RefRay r;
  double ta = 0, tb = 0;
  int steps = 4000;
  if (half) {
    const RefLeaf& l = s.leaves[0];
    const double sd = l.n.dot(o) - l.off, dn = l.n.dot(d);
    if (sd <= 0) r = {true, 0.0, 0.0};
    else if (dn < 0) r = {true, sd / -dn, sd / -dn};
  } else if (ray_window(s, o, d, &ta, &tb)) {
    r = step_ray(s, o, d, ta, tb, steps);
    if (h.hit && (!r.hit || h.t < r.t - tol)) {
      // A chord thinner than the coarse step may hide before the reported entry.
      const double w = 2.0 * (tb - ta) / steps;
      const RefRay fine = step_ray(s, o, d, std::max(ta, h.t - w), std::min(tb, h.t + w), steps);
      if (fine.hit && (!r.hit || fine.t < r.t)) r = fine;
    }
  }
  auto hugs = [&](double t0, double t1) {  // the ray between t0 and t1 stays within tol of the surface
    for (int k = 0; k <= 8; ++k) {
      const double t = t0 + (t1 - t0) * k / 8.0;
      if (std::fabs(ref_sd(s, o + t * d)) > 4 * tol) return false;
    }
    return true;
  };
  // A hit point carries the rounding of its own magnitude (|o + t d| <= |o| + t): far
  // along a grazing ray the float t of a half-space hit moves the point 3.6e-5 off the
  // plane at t = 749 (IMPACT_TEST_INTENSITY=30), a few float ulps of the point.
  auto on_surface = [&](double t) { return std::fabs(ref_sd(s, o + t * d)) <= 4 * tol + 4e-7 * t; };
  char buf[512];
  std::snprintf(buf, sizeof buf, "[%s] o=(%.9g %.9g %.9g) d=(%.9g %.9g %.9g) tmax=%g size=%g: kernel hit=%d t=%.9g, ref hit=%d t=%.9g exit=%.9g",
                to_string(s.type), o[0], o[1], o[2], d[0], d[1], d[2], tmax, s.size, h.hit, h.t, r.hit, r.t, r.t_exit);
  std::string what = buf;
  if (s.type == ShapeType::kCompound) what += " child " + std::to_string(h.child);
  // Walk the reference's entries: a chord that only grazes the surface (within tol all
  // along) may be missed by the float kernel; then the next entry must match. An entry
  // the kernel reports before the reference's must lie on the surface (a graze the
  // reference's steps missed).
  bool grazed = false;
  for (int guard = 0;; ++guard) {
    const bool ref_hit = r.hit && r.t <= tmax;
    if (h.hit && (!ref_hit || h.t < r.t - 4 * tol)) {
      if (!on_surface(h.t)) return (ref_hit ? "early hit " : "spurious hit ") + what;
      grazed = true;
      break;
    }
    if (!ref_hit) break;  // both miss
    if (h.hit && (std::fabs(h.t - r.t) <= 4 * tol || hugs(std::min<double>(h.t, r.t), std::max<double>(h.t, r.t)))) break;
    // The kernel misses this chord (or enters later): allowed for a graze or an entry at tmax.
    if (tmax - r.t <= 4 * tol) {
      grazed = true;
      if (!h.hit) break;
    }
    if (half || guard > 4 || !hugs(r.t, std::min(r.t_exit, tmax))) return (h.hit ? "late hit " : "missed hit ") + what;
    grazed = true;
    // Skip the whole stretch that stays within tol of the surface (a ray sliding along
    // a face crosses it back and forth by rounding), then look for the next entry.
    const double dt = (tb - ta) / steps;
    double t_next = r.t_exit;
    while (t_next < tb && std::fabs(ref_sd(s, o + t_next * d)) <= 4 * tol) t_next += dt;
    r = t_next < tb ? step_ray(s, o, d, t_next, tb, steps) : RefRay{};
  }
  if (grazed) {
    ++st->grazing;
    return "";
  }
  if (!h.hit) {
    ++st->misses;
    if (h.t != 0.0f || h.child != kNoChild || h.point != Vector3f::Zero() || h.normal != Vector3f::Zero())
      return "a miss must be ShapeRayHit{} " + what;
    return "";
  }
  ++st->hits;
  if (!(h.t >= 0.0f && h.t <= ray.tmax)) return "t out of [0, tmax] " + what;
  if (r.t == 0.0) {
    ++st->inside;
    if (h.t != 0.0f && !hugs(0.0, h.t)) return "origin inside: t must be 0 " + what;
    if (s.type == ShapeType::kCompound && h.t == 0.0f) {
      // Inside several children: the lowest index wins (unless one is ambiguous).
      for (uint32_t i = 0; i < s.leaves.size(); ++i) {
        const double sdi = leaf_sd(s.leaves[i], to_leaf(s.leaves[i], o));
        if (std::fabs(sdi) <= 4 * tol) break;
        if (sdi < 0) {
          if (h.child != i) return "origin inside: the lowest child containing it must win " + what;
          break;
        }
      }
    }
  }
  // Point: origin + t d in world float.
  const Vector3d pw = ray.origin.cast<double>() + static_cast<double>(h.t) * dw;
  const double pscale = ray.origin.cast<double>().norm() + static_cast<double>(h.t);  // o + t d rounds at this scale
  if ((h.point.cast<double>() - pw).norm() > 4e-7 * pscale + 1e-30) return "point " + what;
  // Normal.
  const Vector3d nw = h.normal.cast<double>();
  if (std::fabs(nw.norm() - 1.0) > 1e-5) return "normal not unit " + what;
  if (h.t == 0.0f) {
    if (h.normal != Vector3f(-dw.cast<float>())) return "t = 0: normal must be -direction " + what;
    return "";
  }
  const Vector3d nl = (P.R.transpose() * nw).normalized();  // acos needs exactly unit vectors
  const Vector3d x = o + static_cast<double>(h.t) * d;
  const std::vector<Vector3d> cand = ref_normals(s, x, 20 * tol);
  const double ang_tol = 1e-4 + 50 * tol / s.thin;
  bool ok = false;
  for (const Vector3d& c : cand) ok |= std::acos(std::clamp(c.dot(nl), -1.0, 1.0)) <= ang_tol;
  if (!ok) {
    std::snprintf(buf, sizeof buf, " normal (%.6g %.6g %.6g), %zu candidates, first (%.6g %.6g %.6g)", nl[0], nl[1], nl[2],
                  cand.size(), cand.empty() ? 0.0 : cand[0][0], cand.empty() ? 0.0 : cand[0][1],
                  cand.empty() ? 0.0 : cand[0][2]);
    return "normal " + what + buf;
  }
  if (s.type == ShapeType::kCompound) {
    if (h.child >= s.leaves.size()) return "compound child out of range " + what;
    const RefLeaf& l = s.leaves[h.child];
    if (!(std::fabs(leaf_sd(l, to_leaf(l, x))) <= 4 * tol)) return "compound child does not hold the hit " + what;
  } else if (h.child != kNoChild) {
    return "child must be kNoChild " + what;
  }
  return "";
}

std::string check_point(const RefShape& s, const Pose& pose, const Vector3f& pw, const ShapePointResult& r) {
  const Posed P = posed(s, pose);
  const Vector3d p = P.R.transpose() * (pw.cast<double>() - P.p);
  const double tol = 2e-6 * (s.size + p.norm()) + 1e-30;
  int which = -1;
  const double sd = ref_sd(s, p, &which);
  const Vector3d c = P.R.transpose() * (r.closest.cast<double>() - P.p);
  const Vector3d n = P.R.transpose() * r.normal.cast<double>();
  // World closest carries the rounding of its own magnitude.
  const double ctol = tol + 4e-7 * r.closest.cast<double>().norm();
  char buf[512];
  std::snprintf(buf, sizeof buf, "[%s] p=(%.9g %.9g %.9g) size=%g: kernel d=%.9g inside=%d c=(%.9g %.9g %.9g) n=(%.6g %.6g %.6g) child=%u, ref d=%.9g",
                to_string(s.type), p[0], p[1], p[2], s.size, r.distance, r.inside, c[0], c[1], c[2], n[0], n[1], n[2],
                r.child, sd);
  const std::string what = buf;
  if (!(std::fabs(r.distance - sd) <= tol)) return "distance " + what;
  if (std::fabs(sd) > tol && r.inside != (sd < 0)) return "inside flag " + what;
  if (r.inside != (r.distance <= 0.0f)) return "inside != (distance <= 0) " + what;
  // Compounds: the closest point and normal belong to the reported child (inside, the
  // smallest signed distance is a child's, whose surface may lie inside another child).
  RefShape child_shape;
  const RefShape* surf = &s;
  if (s.type == ShapeType::kCompound) {
    if (r.child >= s.leaves.size()) return "compound child out of range " + what;
    const RefLeaf& l = s.leaves[r.child];
    if (!(std::fabs(leaf_sd(l, to_leaf(l, p)) - sd) <= tol)) return "compound child is not the nearest " + what;
    child_shape.type = l.type;
    child_shape.leaves.push_back(l);
    child_shape.size = s.size;
    child_shape.thin = s.thin;
    surf = &child_shape;
  } else if (r.child != kNoChild) {
    return "child must be kNoChild " + what;
  }
  if (!(std::fabs(ref_sd(*surf, c)) <= ctol)) return "closest not on the surface " + what;
  if (!(std::fabs((p - c).norm() - std::fabs(sd)) <= tol + ctol)) return "|p - closest| != |distance| " + what;
  if (std::fabs(n.norm() - 1.0) > 1e-5) return "normal not unit " + what;
  if (std::fabs(sd) > 100 * ctol) {
    // Off the surface: n points from closest to p (outside) or from p to closest (inside).
    const Vector3d dir = (sd > 0 ? (p - c) : (c - p)).normalized();
    if ((dir - n).norm() > 1e-4 + 10 * ctol / std::fabs(sd)) return "normal direction " + what;
  } else {
    const std::vector<Vector3d> cand = ref_normals(*surf, c, 20 * ctol);
    const double ang = 1e-4 + 50 * ctol / s.thin;
    bool ok = false;
    for (const Vector3d& m : cand) ok |= (m - n).norm() <= ang;
    if (!ok && surf->type == ShapeType::kConvex) {
      // p just off the surface beside an edge or a vertex: n = (p - c) / |p - c| lies
      // in that feature's normal cone, between the faces' normals, and c maximises n.x
      // over the hull (up to the angle's tolerance over the hull's size). Seen at
      // IMPACT_TEST_INTENSITY=30: a point 6.7e-9 off a 1e-4 hull's edge (and at 1e4).
      const RefLeaf& l = surf->leaves[0];
      const Vector3d nl = l.R.transpose() * n, cl = to_leaf(l, c);
      double top = -1e300;
      for (const auto& tri : l.tris)
        for (const Vector3d& v : tri) top = std::max(top, nl.dot(v - cl));
      ok = top <= ang * s.size + 20 * ctol;
    }
    if (!ok) return "normal on the surface " + what;
  }
  return "";
}

// Rays of every kind against shape `obj` posed by `pose`.
void add_rays(Builder& b, const TestShape& ts, uint32_t obj, const Pose& pose, int n, std::vector<ObjectRay>* rays) {
  const RefShape& s = ts.ref;
  const bool half = s.type == ShapeType::kHalfSpace;
  const double size = s.size;
  const Posed P = posed(s, pose);
  auto world = [&](const Vector3d& xl) { return Vector3d(P.R * xl + P.p); };
  auto wdir = [&](const Vector3d& dl) { return Vector3d(P.R * dl); };
  auto push = [&](const Vector3d& ow, const Vector3d& dw, double tmax) {
    ObjectRay r;
    r.ray.origin = ow.cast<float>();
    r.ray.direction = dw.cast<float>();
    r.ray.tmax = static_cast<float>(tmax);
    r.object = obj;
    rays->push_back(r);
  };
  const double inf = std::numeric_limits<double>::infinity();
  for (int i = 0; i < n; ++i) {
    const int kind = i % 8;
    const Vector3d o = b.unit() * size * b.uni(1.2, 4.0);
    switch (kind) {
      case 0:
      case 1: {  // aimed at a random point of the bounding ball: hits and misses
        const Vector3d target = b.unit() * size * b.uni(0.0, 1.1);
        push(world(o), wdir(target - o), inf);
        break;
      }
      case 2: {  // from inside (rejection-sampled) in a random direction, sometimes tmax = 0
        Vector3d x;
        int tries = 0;
        do x = b.unit() * size * b.uni(0.0, 1.0);
        while (!ref_inside(s, x) && ++tries < 100);
        push(world(x), wdir(b.unit()), i % 16 == 2 ? 0.0 : inf);
        break;
      }
      case 3: {  // along a local axis (parallel to faces / the axis), offset randomly
        Vector3d d = Vector3d::Zero();
        d[b.rng() % 3] = (b.rng() & 1) ? 1.0 : -1.0;
        const Vector3d off = Vector3d(b.uni(-1, 1), b.uni(-1, 1), b.uni(-1, 1)) * size * 0.9;
        push(world(off - 3.0 * size * d), wdir(d), inf);
        break;
      }
      case 4: {  // a segment that stops short of (or just past) the reference entry
        const Vector3d target = b.unit() * size * b.uni(0.0, 0.5);
        const Vector3d dir = (target - o).normalized();
        RefRay r;
        double ta, tb;
        if (half) {
          const RefLeaf& l = s.leaves[0];
          const double sd = l.n.dot(o) - l.off, dn = l.n.dot(dir);
          if (sd > 0 && dn < 0) r = {true, sd / -dn, 0};
        } else if (ray_window(s, o, dir, &ta, &tb)) {
          r = step_ray(s, o, dir, ta, tb, 2000);
        }
        const double len = r.hit ? r.t * ((b.rng() & 1) ? 0.9 : 1.01) : (target - o).norm();
        push(world(o), wdir(target - o), len);
        break;
      }
      case 5: {  // grazing: tangent to the surface at a random surface point
        const Vector3d target = b.unit() * size * b.uni(0.0, 0.9);
        if (half) {
          push(world(o), wdir(target - o), inf);
          break;
        }
        // Walk from the centre-ish target outward until the boundary, then shoot tangentially.
        const Vector3d u = b.unit();
        double lo = 0, hi = 2 * size;
        const Vector3d base = ref_inside(s, Vector3d::Zero()) ? Vector3d::Zero() : target;
        for (int it = 0; it < 60; ++it) {
          const double m = 0.5 * (lo + hi);
          (ref_inside(s, base + m * u) ? lo : hi) = m;
        }
        const Vector3d xs = base + lo * u;
        const std::vector<Vector3d> nn = ref_normals(s, xs, 1e-6 * size);
        const Vector3d nrm = nn.empty() ? u : nn[0];
        const Vector3d t = nrm.unitOrthogonal();
        push(world(xs - 2.0 * size * t), wdir(t), inf);
        break;
      }
      case 6: {  // random direction from far away (mostly misses)
        push(world(o * 3.0), wdir(b.unit()), inf);
        break;
      }
      default: {  // aimed exactly at the centre
        push(world(o), wdir(-o), inf);
        break;
      }
    }
  }
}

void add_points(Builder& b, const TestShape& ts, uint32_t obj, const Pose& pose, int n,
                std::vector<ObjectPoint>* pts) {
  const RefShape& s = ts.ref;
  const double size = s.size;
  const Posed P = posed(s, pose);
  for (int i = 0; i < n; ++i) {
    Vector3d x;
    switch (i % 6) {
      case 0: x = b.unit() * size * b.uni(0.0, 1.0); break;   // mostly inside
      case 1: x = b.unit() * size * b.uni(0.5, 2.0); break;   // around the surface
      case 2: x = b.unit() * size * b.uni(2.0, 50.0); break;  // far
      case 3: {  // on a local axis or plane (symmetry)
        x = Vector3d::Zero();
        x[b.rng() % 3] = size * b.uni(-1.5, 1.5);
        if (b.rng() & 1) x[b.rng() % 3] = size * b.uni(-1.5, 1.5);
        break;
      }
      case 4: x = Vector3d::Zero(); break;  // the centre
      default: {  // near the surface: the boundary along a ray from the centre
        const Vector3d u = b.unit();
        double lo = 0, hi = 2 * size;
        for (int it = 0; it < 60; ++it) {
          const double m = 0.5 * (lo + hi);
          (ref_inside(s, m * u) ? lo : hi) = m;
        }
        x = u * (lo + size * b.uni(-1e-4, 1e-4));
        break;
      }
    }
    ObjectPoint p;
    p.point = (P.R * x + P.p).cast<float>();
    p.object = obj;
    pts->push_back(p);
  }
}

struct Scene {
  Builder b;
  std::vector<TestShape> shapes;
  std::vector<ShapeId> shape_of;
  std::vector<Pose> poses;
  std::vector<uint32_t> ref_of;  // object -> shapes index
  void add_object(uint32_t shape, const Pose& pose) {
    shape_of.push_back(shapes[shape].id);
    poses.push_back(pose);
    ref_of.push_back(shape);
  }
};

// Every convex type at one scale, several random poses each (near and far from the
// origin), plus compounds and a half-space.
void build_scene(Scene* sc, double scale, double far) {
  Builder& b = sc->b;
  sc->shapes = convex_zoo(b, scale);
  const size_t nz = sc->shapes.size();
  // Compounds of the zoo's children (no AABB / half-space children).
  std::vector<std::pair<TestShape, Pose>> kids;
  for (size_t i = 0; i < nz; ++i) {
    const ShapeType t = sc->shapes[i].ref.type;
    if (t == ShapeType::kAabb || (i % 3) != 0) continue;
    kids.push_back({sc->shapes[i], b.random_pose(scale * 1.0, 0.0)});
  }
  sc->shapes.push_back(b.compound(kids));
  kids.clear();
  kids.push_back({sc->shapes[0], Pose{}});
  kids.push_back({sc->shapes[3], b.random_pose(scale * 0.3, 0.0)});  // overlapping children
  sc->shapes.push_back(b.compound(kids));
  sc->shapes.push_back(b.half_space(b.unit(), scale * b.uni(-1, 1)));
  sc->shapes.back().ref.size = scale;  // unbounded: the scale of its queries
  sc->shapes.back().ref.thin = scale;
  for (uint32_t s = 0; s < sc->shapes.size(); ++s) {
    sc->add_object(s, Pose{});
    sc->add_object(s, b.random_pose(3 * scale, 0.0));
    sc->add_object(s, b.random_pose(3 * scale, far));
  }
}

void run_rays(Scene& sc, int per_object, const char* label) {
  std::vector<ObjectRay> rays;
  for (uint32_t obj = 0; obj < sc.shape_of.size(); ++obj)
    add_rays(sc.b, sc.shapes[sc.ref_of[obj]], obj, sc.poses[obj], per_object, &rays);
  std::vector<ShapeRayHit> out(rays.size());
  IMPACT_ASSERT_OK(raycast_shapes(sc.b.set, sc.shape_of, sc.poses, rays, out));
  Stats st;
  int failures = 0;
  for (size_t k = 0; k < rays.size(); ++k) {
    const uint32_t obj = rays[k].object;
    const std::string f = check_ray(sc.shapes[sc.ref_of[obj]].ref, sc.poses[obj], rays[k].ray, out[k], &st);
    if (!f.empty() && ++failures <= 10) ADD_FAILURE() << label << " ray " << k << " object " << obj << ": " << f;
  }
  EXPECT_EQ(failures, 0) << label;
  std::printf("%s: %d rays, %d hits (%d inside), %d misses, %d grazing\n", label, st.total, st.hits, st.inside, st.misses,
              st.grazing);
  // The set must exercise hits, misses, inside origins, with few grazing disagreements.
  EXPECT_GT(st.hits, st.total / 5) << label;
  EXPECT_GT(st.misses, st.total / 10) << label;
  EXPECT_GT(st.inside, st.total / 20) << label;
  EXPECT_LT(st.grazing, st.total / 8) << label;  // mostly the tangent rays (1 in 8)
}

void run_points(Scene& sc, int per_object, const char* label) {
  std::vector<ObjectPoint> pts;
  for (uint32_t obj = 0; obj < sc.shape_of.size(); ++obj)
    add_points(sc.b, sc.shapes[sc.ref_of[obj]], obj, sc.poses[obj], per_object, &pts);
  std::vector<ShapePointResult> out(pts.size());
  IMPACT_ASSERT_OK(query_shape_points(sc.b.set, sc.shape_of, sc.poses, pts, out));
  int failures = 0, inside = 0;
  for (size_t k = 0; k < pts.size(); ++k) {
    const uint32_t obj = pts[k].object;
    inside += out[k].inside;
    const std::string f = check_point(sc.shapes[sc.ref_of[obj]].ref, sc.poses[obj], pts[k].point, out[k]);
    if (!f.empty() && ++failures <= 10) ADD_FAILURE() << label << " point " << k << " object " << obj << ": " << f;
  }
  EXPECT_EQ(failures, 0) << label;
  EXPECT_GT(inside, static_cast<int>(pts.size()) / 10) << label;
}

TEST(ShapeQueries, RaysMatchTheReferenceUnitScale) {
  Scene sc;
  build_scene(&sc, 1.0, 0.0);
  run_rays(sc, static_cast<int>(test::scaled(96)), "scale 1");
}

TEST(ShapeQueries, RaysMatchTheReferenceTinyHugeAndFar) {
  for (double scale : {1e-4, 1e4}) {
    Scene sc;
    build_scene(&sc, scale, 0.0);
    run_rays(sc, static_cast<int>(test::scaled(48)), scale < 1 ? "scale 1e-4" : "scale 1e4");
  }
  Scene sc;
  build_scene(&sc, 1.0, 1e5);
  run_rays(sc, static_cast<int>(test::scaled(48)), "poses 1e5 from the origin");
}

TEST(ShapeQueries, PointsMatchTheReferenceUnitScale) {
  Scene sc;
  build_scene(&sc, 1.0, 0.0);
  run_points(sc, static_cast<int>(test::scaled(60)), "scale 1");
}

TEST(ShapeQueries, PointsMatchTheReferenceTinyHugeAndFar) {
  for (double scale : {1e-4, 1e4}) {
    Scene sc;
    build_scene(&sc, scale, 0.0);
    run_points(sc, static_cast<int>(test::scaled(30)), scale < 1 ? "scale 1e-4" : "scale 1e4");
  }
  Scene sc;
  build_scene(&sc, 1.0, 1e5);
  run_points(sc, static_cast<int>(test::scaled(30)), "poses 1e5 from the origin");
}

// Exact cases in the local frame (identity pose, exactly representable inputs).
TEST(ShapeQueries, ExactAxisAlignedCases) {
  Builder b;
  const TestShape box = b.box(Vector3d(1, 2, 3));
  const TestShape cyl = b.cylinder(1, 2);
  const TestShape sph = b.sphere(2);
  const std::vector<ShapeId> shape_of{box.id, cyl.id, sph.id};
  const std::vector<Pose> poses(3);
  auto ray = [](Vector3f o, Vector3f d, uint32_t obj, float tmax = INFINITY) {
    ObjectRay r;
    r.ray.origin = o;
    r.ray.direction = d;
    r.ray.tmax = tmax;
    r.object = obj;
    return r;
  };
  const std::vector<ObjectRay> rays{
      ray({-5, 0, 0}, {1, 0, 0}, 0),        // 0: face x = -1 at t = 4
      ray({-5, 2, 0}, {1, 0, 0}, 0),        // 1: in the plane y = 2 (the closed box's face): enters at x = -1
      ray({-5, 2.5f, 0}, {1, 0, 0}, 0),     // 2: parallel, outside: miss
      ray({0, 0, 0}, {0, 0, 2}, 0),         // 3: inside: t = 0, normal -d
      ray({1, 2, 3}, {1, 1, 1}, 0),         // 4: on a corner, leaving: t = 0 (closed)
      ray({-5, 0, 0}, {1, 0, 0}, 0, 3.9f),  // 5: segment short of the face
      ray({-5, 0, 0}, {1, 0, 0}, 0, 4.0f),  // 6: segment ending on the face
      ray({0, 0, 10}, {0, 0, -1}, 1),       // 7: cylinder cap at t = 8
      ray({5, 0, 0}, {-1, 0, 0}, 1),        // 8: cylinder side at t = 4
      ray({1, 0, 10}, {0, 0, -1}, 1),       // 9: along the side line x = 1: the closed side at t = 8
      ray({1.5f, 0, 10}, {0, 0, -1}, 1),    // 10: parallel to the axis, outside: miss
      ray({0, 0, 5}, {0, 0, -3}, 2),        // 11: sphere pole at t = 3
      ray({2, 0, 5}, {0, 0, -1}, 2),        // 12: tangent to the sphere at (2, 0, 0), t = 5
  };
  std::vector<ShapeRayHit> out(rays.size());
  IMPACT_ASSERT_OK(raycast_shapes(b.set, shape_of, poses, rays, out));
  auto expect_hit = [&](int k, float t, Vector3f n) {
    EXPECT_TRUE(out[k].hit) << k;
    EXPECT_EQ(out[k].t, t) << k;
    EXPECT_LT((out[k].normal - n).norm(), 1e-6f) << k << ": " << out[k].normal.transpose();
  };
  expect_hit(0, 4, {-1, 0, 0});
  expect_hit(1, 4, {-1, 0, 0});
  EXPECT_FALSE(out[2].hit);
  expect_hit(3, 0, {0, 0, -1});
  expect_hit(4, 0, Vector3f(-1, -1, -1).normalized());
  EXPECT_FALSE(out[5].hit);
  expect_hit(6, 4, {-1, 0, 0});
  expect_hit(7, 8, {0, 0, 1});
  expect_hit(8, 4, {1, 0, 0});
  expect_hit(9, 8, {0, 0, 1});
  EXPECT_FALSE(out[10].hit);
  expect_hit(11, 3, {0, 0, 1});
  EXPECT_TRUE(out[12].hit);
  EXPECT_NEAR(out[12].t, 5.0f, 2e-3f);  // tangent: t is ill-conditioned, the point is not
  EXPECT_LT((out[12].point - Vector3f(2, 0, 0)).norm(), 2e-3f);

  const std::vector<ObjectPoint> pts{
      {{0, 0, 0}, 0},    // box centre: nearest face x (first axis on ties? no: x gap 1 is smallest)
      {{0, 0, 0}, 1},    // cylinder centre: side (gap 1) nearer than caps (gap 2)
      {{0, 0, 1.5f}, 1}, // on the axis near a cap: cap (gap 0.5)
      {{0, 0, 0}, 2},    // sphere centre: fallback +x
      {{3, 0, 5}, 1},    // rim region
      {{1, 2, 3}, 0},    // box corner: on the surface
  };
  std::vector<ShapePointResult> pr(pts.size());
  IMPACT_ASSERT_OK(query_shape_points(b.set, shape_of, poses, pts, pr));
  EXPECT_EQ(pr[0].distance, -1.0f);
  EXPECT_EQ(pr[0].normal, Vector3f(1, 0, 0));
  EXPECT_EQ(pr[0].closest, Vector3f(1, 0, 0));
  EXPECT_EQ(pr[1].distance, -1.0f);
  EXPECT_EQ(pr[1].normal, Vector3f(1, 0, 0));
  EXPECT_EQ(pr[2].distance, -0.5f);
  EXPECT_EQ(pr[2].normal, Vector3f(0, 0, 1));
  EXPECT_EQ(pr[3].distance, -2.0f);
  EXPECT_EQ(pr[3].normal, Vector3f(1, 0, 0));
  EXPECT_TRUE(pr[3].inside);
  EXPECT_NEAR(pr[4].distance, std::sqrt(4.0f + 9.0f), 1e-6f);
  EXPECT_LT((pr[4].closest - Vector3f(1, 0, 2)).norm(), 1e-6f);
  EXPECT_LT((pr[4].normal - Vector3f(2, 0, 3).normalized()).norm(), 1e-6f);
  EXPECT_EQ(pr[5].distance, 0.0f);
  EXPECT_TRUE(pr[5].inside);
}

// Ellipsoid points where the Lagrange root is ill-conditioned: on and near the axes
// and coordinate planes, inside and outside, against the sampling reference.
TEST(ShapeQueries, EllipsoidPointsNearTheAxes) {
  const float radii[3] = {3.0f, 2.0f, 1.0f};
  RefLeaf l = Builder::leaf(ShapeType::kEllipsoid, 3, 2, 1);
  const float vals[] = {0.0f, 1e-30f, 1e-7f, 0.3f, 0.9f, 1.5f, 2.5f, 4.0f};
  int n = 0;
  for (float x : vals)
    for (float y : vals)
      for (float z : vals) {
        for (int sg = 0; sg < 2; ++sg) {
          const float p[3] = {sg ? -x : x, y, sg ? z : -z};
          const kernels::LeafPointResult r = kernels::point_leaf_ellipsoid(p, radii);
          const Vector3d pd(p[0], p[1], p[2]);
          const double ref = leaf_sd(l, pd);
          const Vector3d c(r.closest[0], r.closest[1], r.closest[2]);
          ASSERT_NEAR(r.distance, ref, 2e-6) << pd.transpose();
          ASSERT_NEAR(leaf_sd(l, c), 0.0, 2e-6) << pd.transpose();
          ASSERT_NEAR((pd - c).norm(), std::fabs(ref), 4e-6) << pd.transpose();
          ++n;
        }
      }
  EXPECT_EQ(n, 1024);
}

// A random terrain: the BVH answers equal a brute force over every triangle with the
// same kernel (bit for bit, same triangle), and a double reference within tolerance.
// amplitude 0: a flat grid, where straight-down rays and points tie between many
// triangles and BVH nodes (the lowest triangle index must win).
void mesh_bvh_equals_brute_force(double amplitude) {
  Builder b;
  const int g = 40;  // 40 x 40 cells, 3200 triangles
  std::vector<Vector3f> verts;
  std::vector<uint32_t> idx;
  for (int j = 0; j <= g; ++j)
    for (int i = 0; i <= g; ++i)
      verts.emplace_back(static_cast<float>(i - g / 2), static_cast<float>(b.uni(-amplitude, amplitude)),
                         static_cast<float>(j - g / 2));
  for (int j = 0; j < g; ++j)
    for (int i = 0; i < g; ++i) {
      const uint32_t a = j * (g + 1) + i, c = a + 1, d = a + (g + 1), e = d + 1;
      idx.insert(idx.end(), {a, d, c, c, d, e});
    }
  ShapeId mesh;
  IMPACT_ASSERT_OK(b.set.add_mesh(verts, idx, &mesh));
  const Pose far_pose = b.random_pose(1.0, 1e3);
  const std::vector<ShapeId> shape_of{mesh, mesh};
  const std::vector<Pose> poses{Pose{}, far_pose};
  std::vector<ObjectRay> rays;
  const int nr = static_cast<int>(test::scaled(3000));
  for (int k = 0; k < nr; ++k) {
    ObjectRay r;
    const Vector3d o(b.uni(-25, 25), b.uni(-8, 8), b.uni(-25, 25));
    Vector3d d = b.unit();
    if (k % 5 == 0) d = Vector3d(d[0], 0, d[2]).normalized();         // horizontal
    if (k % 7 == 0) d = Vector3d(0, -1, 0);                             // straight down
    if (k % 11 == 0) d = Vector3d(1, 0, 0);                             // along grid lines
    r.ray.origin = o.cast<float>();
    if (k % 11 == 0) r.ray.origin = Vector3f(-30.0f, 0.5f, static_cast<float>(k % 40 - 20));
    if (k % 13 == 0) {  // straight down onto a vertex (shared by up to 6 triangles) or an edge
      d = Vector3d(0, -1, 0);
      r.ray.origin = Vector3f(static_cast<float>(k % 37 - 18) + ((k & 1) ? 0.5f : 0.0f), 5.0f,
                              static_cast<float>(k % 29 - 14));
    }
    r.ray.direction = d.cast<float>();
    r.ray.tmax = (k % 3 == 0) ? static_cast<float>(b.uni(0, 30)) : INFINITY;
    r.object = 0;
    rays.push_back(r);
    r.object = 1;
    r.ray.origin = (far_pose.orientation * r.ray.origin + far_pose.position);
    r.ray.direction = far_pose.orientation * r.ray.direction;
    rays.push_back(r);
  }
  std::vector<ShapeRayHit> out(rays.size());
  IMPACT_ASSERT_OK(raycast_shapes(b.set, shape_of, poses, rays, out));
  int hits = 0;
  const uint32_t nt = static_cast<uint32_t>(idx.size() / 3);
  for (size_t k = 0; k < rays.size(); k += 2) {
    // Brute force in the mesh frame (identity pose: the query is the ray itself).
    kernels::RayQuery q;
    const Vector3f d = rays[k].ray.direction.cast<double>().normalized().cast<float>();
    for (int i = 0; i < 3; ++i) {
      q.o[i] = rays[k].ray.origin[i];
      q.d[i] = d[i];
    }
    q.tmax = rays[k].ray.tmax;
    q.mask = ~0u;
    const kernels::RayShear sh = kernels::ray_shear(q);
    float bt = INFINITY;
    uint32_t btri = kNoChild;
    for (uint32_t t = 0; t < nt; ++t) {
      const float tt = kernels::ray_triangle(q, sh, verts[idx[3 * t]].data(), verts[idx[3 * t + 1]].data(),
                                             verts[idx[3 * t + 2]].data());
      if (tt >= 0 && tt < bt) {
        bt = tt;
        btri = t;
      }
    }
    ASSERT_EQ(out[k].hit, btri != kNoChild) << k;
    if (!out[k].hit) continue;
    ++hits;
    ASSERT_EQ(out[k].t, bt) << k;
    ASSERT_EQ(out[k].child, btri) << k;
    EXPECT_LE(out[k].normal.dot(d), 0.0f);
    // Double reference for the posed copy: Moller-Trumbore in double on the posed triangle.
    const ShapeRayHit& h = out[k + 1];
    const Eigen::Matrix3d R = far_pose.orientation.cast<double>().normalized().toRotationMatrix();
    auto wv = [&](uint32_t v) { return Vector3d(R * verts[v].cast<double>() + far_pose.position.cast<double>()); };
    const Vector3d ow = rays[k + 1].ray.origin.cast<double>(), dw = rays[k + 1].ray.direction.cast<double>().normalized();
    double rt = 1e300;
    for (uint32_t t = 0; t < nt; ++t) {
      const Vector3d a = wv(idx[3 * t]), e1 = wv(idx[3 * t + 1]) - a, e2 = wv(idx[3 * t + 2]) - a;
      const Vector3d pv = dw.cross(e2);
      const double det = e1.dot(pv);
      if (std::fabs(det) < 1e-14) continue;
      const Vector3d tv = ow - a;
      const double u = tv.dot(pv) / det;
      const Vector3d qv = tv.cross(e1);
      const double v = dw.dot(qv) / det;
      const double tt = e2.dot(qv) / det;
      if (u >= -1e-9 && v >= -1e-9 && u + v <= 1 + 1e-9 && tt >= 0 && tt <= rays[k + 1].ray.tmax) rt = std::min(rt, tt);
    }
    if (h.hit && rt < 1e300) {
      EXPECT_NEAR(h.t, rt, 2e-3 + 1e-5 * rt) << k;
    }
  }
  EXPECT_GT(hits, nr / 6);
  // Points: BVH == brute force with the same kernel; the posed copy against double.
  std::vector<ObjectPoint> pts;
  for (int k = 0; k < nr; ++k) {
    const Vector3f p = Vector3d(b.uni(-25, 25), b.uni(-6, 6), b.uni(-25, 25)).cast<float>();
    pts.push_back({p, 0});
    pts.push_back({far_pose.orientation * p + far_pose.position, 1});
  }
  pts.push_back({verts[17], 0});  // a vertex: distance 0
  pts.push_back({verts[17], 0});
  std::vector<ShapePointResult> pr(pts.size());
  IMPACT_ASSERT_OK(query_shape_points(b.set, shape_of, poses, pts, pr));
  for (size_t k = 0; k < pts.size(); k += 2) {
    const float p[3] = {pts[k].point[0], pts[k].point[1], pts[k].point[2]};
    float bd = INFINITY;
    uint32_t btri = kNoChild;
    for (uint32_t t = 0; t < nt; ++t) {
      const kernels::LeafPointResult r = kernels::point_leaf_triangle(p, verts[idx[3 * t]].data(),
                                                                      verts[idx[3 * t + 1]].data(), verts[idx[3 * t + 2]].data());
      if (r.distance < bd) {
        bd = r.distance;
        btri = t;
      }
    }
    ASSERT_EQ(pr[k].distance, bd) << k;
    ASSERT_EQ(pr[k].child, btri) << k;
    ASSERT_FALSE(pr[k].inside);
    double rd = 1e300;
    const Vector3d pd = pts[k].point.cast<double>();
    for (uint32_t t = 0; t < nt; ++t)
      rd = std::min(rd, tri_dist(pd, verts[idx[3 * t]].cast<double>(), verts[idx[3 * t + 1]].cast<double>(),
                                 verts[idx[3 * t + 2]].cast<double>()));
    EXPECT_NEAR(pr[k].distance, rd, 1e-5 * (1 + rd)) << k;
    EXPECT_NEAR(pr[k + 1].distance, rd, 2e-4 * (1 + rd)) << k;  // posed 1e3 away
    EXPECT_NEAR((pr[k].closest.cast<double>() - pd).norm(), rd, 1e-5 * (1 + rd)) << k;
    if (rd > 0.1) {
      EXPECT_LT((pr[k].normal.cast<double>() - (pd - pr[k].closest.cast<double>()).normalized()).norm(), 1e-4);
    }
  }
}

TEST(ShapeQueries, MeshBvhEqualsBruteForce) {
  mesh_bvh_equals_brute_force(1.5);
  mesh_bvh_equals_brute_force(0.0);
}

TEST(ShapeQueries, SameBytesForEveryBackendAndThreadCount) {
  Scene sc;
  build_scene(&sc, 1.0, 1e5);
  std::vector<ObjectRay> rays;
  std::vector<ObjectPoint> pts;
  for (uint32_t obj = 0; obj < sc.shape_of.size(); ++obj) {
    add_rays(sc.b, sc.shapes[sc.ref_of[obj]], obj, sc.poses[obj], 200, &rays);
    add_points(sc.b, sc.shapes[sc.ref_of[obj]], obj, sc.poses[obj], 200, &pts);
  }
  auto bytes_r = [](const std::vector<ShapeRayHit>& v) {
    std::vector<uint32_t> w;
    for (const ShapeRayHit& h : v) {
      w.push_back(h.hit);
      w.push_back(std::bit_cast<uint32_t>(h.t));
      for (int i = 0; i < 3; ++i) w.push_back(std::bit_cast<uint32_t>(h.point[i]));
      for (int i = 0; i < 3; ++i) w.push_back(std::bit_cast<uint32_t>(h.normal[i]));
      w.push_back(h.child);
    }
    return w;
  };
  auto bytes_p = [](const std::vector<ShapePointResult>& v) {
    std::vector<uint32_t> w;
    for (const ShapePointResult& h : v) {
      w.push_back(h.inside);
      w.push_back(std::bit_cast<uint32_t>(h.distance));
      for (int i = 0; i < 3; ++i) w.push_back(std::bit_cast<uint32_t>(h.closest[i]));
      for (int i = 0; i < 3; ++i) w.push_back(std::bit_cast<uint32_t>(h.normal[i]));
      w.push_back(h.child);
    }
    return w;
  };
  std::vector<uint32_t> ref_r, ref_p;
  for (const test::ExecCase& c : test::exec_cases()) {
    const ExecConfig ex{c.backend, c.threads};
    std::vector<ShapeRayHit> out(rays.size());
    std::vector<ShapePointResult> pout(pts.size());
    IMPACT_ASSERT_OK(raycast_shapes(sc.b.set, sc.shape_of, sc.poses, rays, out, ex));
    IMPACT_ASSERT_OK(query_shape_points(sc.b.set, sc.shape_of, sc.poses, pts, pout, ex));
    if (ref_r.empty()) {
      ref_r = bytes_r(out);
      ref_p = bytes_p(pout);
    } else {
      EXPECT_EQ(bytes_r(out), ref_r) << test::to_string(c);
      EXPECT_EQ(bytes_p(pout), ref_p) << test::to_string(c);
    }
  }
}

TEST(ShapeQueries, RejectsBadInputNamingTheIndex) {
  Builder b;
  const TestShape s = b.sphere(1);
  std::vector<ShapeId> shape_of{s.id, s.id};
  std::vector<Pose> poses(2);
  std::vector<ObjectRay> rays(3);
  for (ObjectRay& r : rays) r.ray.direction = Vector3f(1, 0, 0);
  std::vector<ShapeRayHit> out(3);
  std::vector<ObjectPoint> pts(3);
  std::vector<ShapePointResult> pout(3);
  IMPACT_EXPECT_OK(raycast_shapes(b.set, shape_of, poses, rays, out));
  IMPACT_EXPECT_OK(query_shape_points(b.set, shape_of, poses, pts, pout));
  using test::IsError;
  // Sizes.
  EXPECT_TRUE(IsError(raycast_shapes(b.set, shape_of, std::span<const Pose>(poses).first(1), rays, out),
                      StatusCode::kSizeMismatch));
  EXPECT_TRUE(IsError(raycast_shapes(b.set, shape_of, poses, rays, std::span<ShapeRayHit>(out).first(2)),
                      StatusCode::kSizeMismatch));
  EXPECT_TRUE(IsError(query_shape_points(b.set, shape_of, poses, pts, std::span<ShapePointResult>(pout).first(1)),
                      StatusCode::kSizeMismatch));
  // Objects.
  shape_of[1].index = 99;
  EXPECT_TRUE(IsError(raycast_shapes(b.set, shape_of, poses, rays, out), StatusCode::kInvalidArgument,
                      {"object 1", "unknown shape id"}));
  shape_of[1] = s.id;
  poses[1].position.y() = NAN;
  EXPECT_TRUE(IsError(query_shape_points(b.set, shape_of, poses, pts, pout), StatusCode::kInvalidArgument,
                      {"object 1", "position"}));
  poses[1] = Pose{};
  poses[0].orientation = Eigen::Quaternionf(1.1f, 0, 0, 0);
  EXPECT_TRUE(IsError(raycast_shapes(b.set, shape_of, poses, rays, out), StatusCode::kInvalidArgument,
                      {"object 0", "unit quaternion"}));
  poses[0] = Pose{};
  // Rays.
  rays[2].object = 2;
  EXPECT_TRUE(IsError(raycast_shapes(b.set, shape_of, poses, rays, out), StatusCode::kInvalidArgument,
                      {"ray 2", "out of range"}));
  rays[2].object = 0;
  rays[1].ray.origin.x() = INFINITY;
  EXPECT_TRUE(IsError(raycast_shapes(b.set, shape_of, poses, rays, out), StatusCode::kInvalidArgument,
                      {"ray 1", "origin"}));
  rays[1].ray.origin.x() = 0;
  rays[1].ray.direction = Vector3f::Zero();
  EXPECT_TRUE(IsError(raycast_shapes(b.set, shape_of, poses, rays, out), StatusCode::kInvalidArgument,
                      {"ray 1", "direction"}));
  rays[1].ray.direction = Vector3f(0, NAN, 1);
  EXPECT_TRUE(IsError(raycast_shapes(b.set, shape_of, poses, rays, out), StatusCode::kInvalidArgument,
                      {"ray 1", "direction"}));
  rays[1].ray.direction = Vector3f(1, 0, 0);
  rays[0].ray.tmax = NAN;
  EXPECT_TRUE(IsError(raycast_shapes(b.set, shape_of, poses, rays, out), StatusCode::kInvalidArgument,
                      {"ray 0", "tmax"}));
  rays[0].ray.tmax = -1;
  EXPECT_TRUE(IsError(raycast_shapes(b.set, shape_of, poses, rays, out), StatusCode::kInvalidArgument,
                      {"ray 0", "tmax"}));
  rays[0].ray.tmax = INFINITY;
  IMPACT_EXPECT_OK(raycast_shapes(b.set, shape_of, poses, rays, out));
  // Points.
  pts[2].object = 7;
  EXPECT_TRUE(IsError(query_shape_points(b.set, shape_of, poses, pts, pout), StatusCode::kInvalidArgument,
                      {"point 2", "out of range"}));
  pts[2].object = 1;
  pts[0].point.z() = NAN;
  EXPECT_TRUE(IsError(query_shape_points(b.set, shape_of, poses, pts, pout), StatusCode::kInvalidArgument,
                      {"point 0", "not finite"}));
  // Empty batches are fine.
  IMPACT_EXPECT_OK(raycast_shapes(b.set, shape_of, poses, {}, {}));
  IMPACT_EXPECT_OK(query_shape_points(b.set, {}, {}, {}, {}));
}

}  // namespace
}  // namespace impact
