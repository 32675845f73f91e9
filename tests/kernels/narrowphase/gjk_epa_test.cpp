// The general convex path (kernels/narrowphase/general/gjk_epa.cpp) against independent answers:
// closed forms (sphere-sphere, axis-aligned boxes, sphere-capsule, coaxial cylinders),
// a separating-axis brute force in double over face normals and edge-pair crosses for
// box-box and hull-hull, and the "safe displacement" property for every type pair
// (moving B by n * depth separates the pair, moving it by less does not). Also: caps
// on GJK/EPA iterations, the tolerance knob, degenerate and extreme inputs, no NaN,
// determinism across range partitions, and deep pairs with a round 400-vertex hull (EPA
// past its iteration cap) against brute-force SAT in double, the SAT kernel and the
// support-function reference of narrow_reference.h.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <random>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "host/shapes/convex_hull.h"
#include "host/shapes/shape_store.h"
#include "kernels/narrowphase/general/gjk_epa.h"
#include "kernels/narrowphase/general/sat.h"
#include "kernels/narrowphase/pair_kernels.h"
#include "support/leaf_lanes.h"
#include "support/narrow_reference.h"
#include "support/random_input.h"
#include "support/test_support.h"

namespace impact::kernels {
namespace {

using Vec3d = Eigen::Vector3d;
using Mat3d = Eigen::Matrix3d;

/// One posed leaf in double (the reference's view) that can be written into lanes.
struct Shape {
  LeafType type = kLeafSphere;
  Vec3d p = Vec3d::Zero();
  Mat3d R = Mat3d::Identity();
  Vec3d e = Vec3d::Zero();
  Vec3d v1 = Vec3d::Zero(), v2 = Vec3d::Zero();  // triangle
  uint32_t hull = 0;
};

using Lanes = test::LeafLanes;

using Out = test::ManifoldLanes;

/// Hulls shared by the tests of this file.
struct Hulls {
  HullStore store;
  std::vector<HullData> data;
  uint32_t add(const std::vector<Eigen::Vector3f>& pts) {
    HullData h;
    const Status s = build_convex_hull(pts, &h);
    EXPECT_TRUE(test::IsOk(s));
    data.push_back(h);
    return store.add(h);
  }
};

Hulls& hulls() {
  static Hulls h;
  return h;
}

NarrowConfig config() {
  NarrowConfig c;
  c.hulls = hulls().store.view();
  return c;
}

using Result = test::PairResult;

/// The general route of bucket (ta, tb): collide_sat_or_gjk_epa for two polytopes (box,
/// hull: SAT up to cfg.sat_max_vertices, as pair_kernel() routes box-hull and hull-hull),
/// else collide_gjk_epa.
void general_route(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, Range r, const NarrowConfig& cfg,
                   LeafType ta, LeafType tb) {
  const auto polytope = [](LeafType t) { return t == kLeafBox || t == kLeafConvex; };
  if (polytope(ta) && polytope(tb))
    collide_sat_or_gjk_epa(a, b, out, r, cfg, ta, tb);
  else
    collide_gjk_epa(a, b, out, r, cfg, ta, tb);
}

/// Runs the general route on one pair, A's type <= B's.
Result run_pair(const Shape& a, const Shape& b, const NarrowConfig& cfg = config()) {
  Lanes la, lb;
  la.push(a);
  lb.push(b);
  Out o(1);
  general_route(la.soa(), lb.soa(), o.view(), Range{0, 1}, cfg, a.type, b.type);
  return o.result();
}

Shape sphere(Vec3d p, double r) {
  Shape s;
  s.type = kLeafSphere;
  s.p = p;
  s.e = {r, 0, 0};
  return s;
}
Shape box(Vec3d p, Mat3d R, Vec3d h) {
  Shape s;
  s.type = kLeafBox;
  s.p = p;
  s.R = R;
  s.e = h;
  return s;
}
Shape capsule(Vec3d p, Mat3d R, double r, double hl) {
  Shape s;
  s.type = kLeafCapsule;
  s.p = p;
  s.R = R;
  s.e = {r, hl, 0};
  return s;
}
Shape cylinder(Vec3d p, Mat3d R, double r, double hl) {
  Shape s = capsule(p, R, r, hl);
  s.type = kLeafCylinder;
  return s;
}
Shape ellipsoid(Vec3d p, Mat3d R, Vec3d radii) {
  Shape s = box(p, R, radii);
  s.type = kLeafEllipsoid;
  return s;
}
Shape convex(Vec3d p, Mat3d R, uint32_t hull) {
  Shape s;
  s.type = kLeafConvex;
  s.p = p;
  s.R = R;
  s.hull = hull;
  return s;
}
Shape triangle(Vec3d v0, Vec3d v1, Vec3d v2) {
  Shape s;
  s.type = kLeafTriangle;
  s.p = v0;
  s.v1 = v1;
  s.v2 = v2;
  return s;
}

/// The shape as the float lanes see it (pose rounded to float), for references.
Shape rounded(const Shape& s) {
  Shape t = s;
  t.p = test::round_to_float(s.p);
  t.R = test::round_to_float(s.R);
  t.e = test::round_to_float(s.e);
  t.v1 = test::round_to_float(s.v1);
  t.v2 = test::round_to_float(s.v2);
  return t;
}

// --- a double-precision polytope reference (SAT) ---------------------------------------

struct Polytope {
  std::vector<Vec3d> verts, normals, edges;
};

Polytope polytope_of(const Shape& s0) {
  const Shape s = rounded(s0);
  Polytope P;
  if (s.type == kLeafBox) {
    for (int i = 0; i < 8; ++i) {
      const Vec3d l((i & 1) ? s.e[0] : -s.e[0], (i & 2) ? s.e[1] : -s.e[1], (i & 4) ? s.e[2] : -s.e[2]);
      P.verts.push_back(s.R * l + s.p);
    }
    for (int i = 0; i < 3; ++i) {
      P.normals.push_back(s.R.col(i));
      P.edges.push_back(s.R.col(i));
    }
  } else if (s.type == kLeafTriangle) {
    P.verts = {s.p, s.v1, s.v2};
    P.normals.push_back((s.v1 - s.p).cross(s.v2 - s.p).normalized());
    P.edges = {(s.v1 - s.p).normalized(), (s.v2 - s.v1).normalized(), (s.p - s.v2).normalized()};
  } else if (s.type == kLeafConvex) {
    const HullData& h = hulls().data[s.hull];
    for (const auto& v : h.vertices) P.verts.push_back(s.R * v.cast<double>() + s.p);
    // Exact face normals from the vertices (double), and every polygon edge.
    for (const auto& f : h.faces) {
      const Vec3d a = P.verts[f[0]];
      Vec3d n = Vec3d::Zero();
      for (size_t i = 0; i < f.size(); ++i) {
        const Vec3d p = P.verts[f[i]], q = P.verts[f[(i + 1) % f.size()]];
        n += (p - a).cross(q - a);
        P.edges.push_back((q - p).normalized());
      }
      P.normals.push_back(n.normalized());
    }
  }
  return P;
}

struct Sat {
  bool overlap = false;
  double depth = 0;  // > 0 when overlapping
  Vec3d n = Vec3d::Zero();
};

/// Penetration of A and B along unit axis L: the displacement of B along +L that separates.
double overlap_along(const Polytope& A, const Polytope& B, const Vec3d& L) {
  double amax = -INFINITY, bmin = INFINITY;
  for (const auto& v : A.verts) amax = std::max(amax, L.dot(v));
  for (const auto& v : B.verts) bmin = std::min(bmin, L.dot(v));
  return amax - bmin;
}

Sat sat(const Polytope& A, const Polytope& B) {
  std::vector<Vec3d> axes = A.normals;
  axes.insert(axes.end(), B.normals.begin(), B.normals.end());
  for (const auto& ea : A.edges)
    for (const auto& eb : B.edges) {
      const Vec3d c = ea.cross(eb);
      if (c.norm() > 1e-9) axes.push_back(c.normalized());
    }
  Sat s;
  s.depth = INFINITY;
  for (const auto& L0 : axes) {
    for (double sg : {1.0, -1.0}) {
      const Vec3d L = L0 * sg;
      const double d = overlap_along(A, B, L);
      if (d < s.depth) {
        s.depth = d;
        s.n = L;
      }
    }
  }
  s.overlap = s.depth > 0;
  return s;
}

/// Is x in the polytope leaf s (box, convex, triangle), within tol?
bool inside_polytope(const Shape& s0, const Vec3d& x, double tol) {
  const Shape s = rounded(s0);
  if (s.type == kLeafBox) return ((s.R.transpose() * (x - s.p)).cwiseAbs() - s.e).maxCoeff() <= tol;
  if (s.type == kLeafConvex) {
    const HullData& h = hulls().data[s.hull];
    const Vec3d q = s.R.transpose() * (x - s.p);
    for (size_t f = 0; f < h.faces.size(); ++f)
      if (h.face_normals[f].cast<double>().dot(q) > h.face_offsets[f] + tol) return false;
    return true;
  }
  if (s.type == kLeafTriangle) {
    const Vec3d n = (s.v1 - s.p).cross(s.v2 - s.p).normalized();
    if (std::fabs(n.dot(x - s.p)) > tol) return false;
    const Vec3d v[3] = {s.p, s.v1, s.v2};
    for (int i = 0; i < 3; ++i)
      if ((v[(i + 1) % 3] - v[i]).normalized().cross(x - v[i]).dot(n) < -tol) return false;
    return true;
  }
  return false;
}

/// Is x in the leaf s (any type), within tol?
bool inside_leaf(const Shape& s0, const Vec3d& x, double tol) {
  const Shape s = rounded(s0);
  const Vec3d q = s.R.transpose() * (x - s.p);
  switch (s.type) {
    case kLeafSphere: return (x - s.p).norm() <= s.e[0] + tol;
    case kLeafCapsule: {
      const double z = std::clamp(q.z(), -s.e[1], s.e[1]);
      return (q - Vec3d(0, 0, z)).norm() <= s.e[0] + tol;
    }
    case kLeafCylinder: return std::hypot(q.x(), q.y()) <= s.e[0] + tol && std::fabs(q.z()) <= s.e[1] + tol;
    case kLeafEllipsoid: {
      // Scale the tolerance by the smallest radius (a conservative bound).
      return q.cwiseQuotient(s.e).norm() <= 1 + tol / s.e.minCoeff();
    }
    default: return inside_polytope(s0, x, tol);
  }
}

/// Each contact point lies midway between a point of A (p + n pd/2) and one of B.
void expect_points_on_both(const Shape& a, const Shape& b, const Result& r, double tol, int t) {
  for (uint32_t j = 0; j < r.count; ++j) {
    EXPECT_TRUE(inside_polytope(a, r.pt[j] + r.n * (0.5 * r.pd[j]), tol)) << t << " point " << j;
    EXPECT_TRUE(inside_polytope(b, r.pt[j] - r.n * (0.5 * r.pd[j]), tol)) << t << " point " << j;
  }
}

// --- tests ---------------------------------------------------------------------------------

TEST(GjkEpa, SphereSphereClosedForm) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1, 1);
  for (double size : {1e-4, 1.0, 1e4}) {
    for (double offset : {0.0, 1e5}) {
      if (size < 1e-2 && offset > 0) continue;  // float spacing at 1e5 is 8e-3
      for (int t = 0; t < 200; ++t) {
        const Vec3d ca = Vec3d(u(rng), u(rng), u(rng)) * size + Vec3d::Constant(offset);
        const Vec3d cb = ca + Vec3d(u(rng), u(rng), u(rng)) * size * 1.5;
        const double ra = (0.2 + std::fabs(u(rng))) * size, rb = (0.2 + std::fabs(u(rng))) * size;
        const Shape a = rounded(sphere(ca, ra)), b = rounded(sphere(cb, rb));
        const Result r = run_pair(a, b);
        const double d = (b.p - a.p).norm();
        const double depth = ra + rb - d;
        const double tol = 1e-5 * size + offset * 2e-7;
        if (depth > tol) {
          ASSERT_EQ(r.count, 1u) << t;
          EXPECT_NEAR(r.depth, depth, tol);
          EXPECT_NEAR(r.n.norm(), 1.0, 1e-6);
          EXPECT_GT(r.n.dot((b.p - a.p).normalized()), 1 - 1e-4);
          const Vec3d mid = 0.5 * ((a.p + r.n * ra) + (b.p - r.n * rb));
          EXPECT_LT((r.pt[0] - mid).norm(), tol * 4);
          EXPECT_NEAR(r.pd[0], depth, tol);
        } else if (depth < -tol) {
          EXPECT_EQ(r.count, 0u);
        }
      }
    }
  }
  // Coincident centres: a finite unit normal and the full depth.
  const Result r = run_pair(sphere({1, 2, 3}, 0.5), sphere({1, 2, 3}, 0.25));
  ASSERT_EQ(r.count, 1u);
  EXPECT_NEAR(r.n.norm(), 1.0, 1e-6);
  EXPECT_NEAR(r.depth, 0.75, 1e-6);
}

TEST(GjkEpa, AxisAlignedBoxesClosedForm) {
  std::mt19937 rng(12);
  std::uniform_real_distribution<double> u(-1, 1);
  int overlapping = 0;
  for (int t = 0; t < 1000; ++t) {
    const Shape a = rounded(box(Vec3d(u(rng), u(rng), u(rng)), Mat3d::Identity(),
                                Vec3d(0.1 + std::fabs(u(rng)), 0.1 + std::fabs(u(rng)), 0.1 + std::fabs(u(rng)))));
    const Shape b = rounded(box(Vec3d(u(rng), u(rng), u(rng)) * 2, Mat3d::Identity(),
                                Vec3d(0.1 + std::fabs(u(rng)), 0.1 + std::fabs(u(rng)), 0.1 + std::fabs(u(rng)))));
    // Per axis: overlap of the intervals, and the side B must move to.
    double best = INFINITY;
    Vec3d bn = Vec3d::Zero();
    for (int i = 0; i < 3; ++i) {
      const double up = (a.p[i] + a.e[i]) - (b.p[i] - b.e[i]);   // move B +axis
      const double down = (b.p[i] + b.e[i]) - (a.p[i] - a.e[i]); // move B -axis
      if (up < best) {
        best = up;
        bn = Vec3d::Unit(i);
      }
      if (down < best) {
        best = down;
        bn = -Vec3d::Unit(i);
      }
    }
    const Result r = run_pair(a, b);
    const double tol = 2e-5;
    if (best < -tol) {
      EXPECT_EQ(r.count, 0u) << t;
      continue;
    }
    if (best < tol) continue;
    ++overlapping;
    ASSERT_GE(r.count, 1u) << t;
    EXPECT_NEAR(r.depth, best, tol) << t;
    // The minimal axis is unique unless two overlaps tie.
    EXPECT_GT(r.n.dot(bn), 1 - 1e-4) << t << " n " << r.n.transpose() << " ref " << bn.transpose();
    // Points: across n, inside the overlap of the two boxes; along n, midway between
    // A's face and B's face (pdepth apart); pdepth in (0, depth].
    int axis = 0;
    bn.cwiseAbs().maxCoeff(&axis);
    for (uint32_t j = 0; j < r.count; ++j) {
      for (int i = 0; i < 3; ++i) {
        if (i == axis) continue;
        const double lo = std::max(a.p[i] - a.e[i], b.p[i] - b.e[i]);
        const double hi = std::min(a.p[i] + a.e[i], b.p[i] + b.e[i]);
        EXPECT_GE(r.pt[j][i], lo - 1e-4) << t;
        EXPECT_LE(r.pt[j][i], hi + 1e-4) << t;
      }
      const double s = bn[axis];  // +-1
      const double a_face = s * a.p[axis] + a.e[axis], b_face = s * b.p[axis] - b.e[axis];
      EXPECT_NEAR(s * r.pt[j][axis] + 0.5 * r.pd[j], a_face, 1e-4) << t;
      EXPECT_NEAR(s * r.pt[j][axis] - 0.5 * r.pd[j], b_face, 1e-4) << t;
      EXPECT_GT(r.pd[j], 0.0);
      EXPECT_LE(r.pd[j], r.depth + 1e-5);
    }
  }
  EXPECT_GT(overlapping, 100);
}

/// Face contact of two stacked boxes: 4 corner points at the right depth.
TEST(GjkEpa, StackedBoxesGiveFourPoints) {
  const Shape a = box({0, 0, 0}, Mat3d::Identity(), {1, 1, 1});
  const Mat3d Rz = Eigen::AngleAxisd(0.3, Vec3d::UnitZ()).toRotationMatrix();
  const Shape b = box({0.1, -0.05, 1.45}, Rz, {0.5, 0.5, 0.5});
  const Result r = run_pair(a, b);
  ASSERT_EQ(r.count, 4u);
  EXPECT_NEAR(r.depth, 0.05, 1e-5);
  EXPECT_GT(r.n.z(), 1 - 1e-5);
  for (uint32_t j = 0; j < 4; ++j) {
    EXPECT_NEAR(r.pd[j], 0.05, 1e-5);
    EXPECT_NEAR(r.pt[j].z(), 1.0 - 0.025, 1e-5);
  }
}

/// Cylinders against faces: a cap gives rim points, a side its line, a rim one point.
TEST(GjkEpa, CylinderManifolds) {
  const Mat3d I = Mat3d::Identity();
  const Shape ground = box({0, 0, -1}, I, {5, 5, 1});
  // Standing on its cap, 0.02 deep.
  Result r = run_pair(ground, cylinder({0.3, -0.2, 0.98}, Eigen::AngleAxisd(0.5, Vec3d::UnitZ()).toRotationMatrix(), 0.5, 1.0));
  ASSERT_EQ(r.count, 4u);
  EXPECT_NEAR(r.depth, 0.02, 1e-5);
  for (uint32_t j = 0; j < 4; ++j) {
    EXPECT_NEAR(r.pd[j], 0.02, 1e-5);
    EXPECT_NEAR(r.pt[j].z(), -0.01, 1e-5);
    EXPECT_NEAR((r.pt[j] - Vec3d(0.3, -0.2, r.pt[j].z())).norm(), 0.5, 1e-5);  // on the rim
  }
  // Lying on its side: the two ends of the line.
  const Mat3d side = Eigen::AngleAxisd(M_PI / 2, Vec3d::UnitX()).toRotationMatrix();
  r = run_pair(ground, cylinder({0, 0, 0.49}, side, 0.5, 1.0));
  ASSERT_EQ(r.count, 2u);
  EXPECT_NEAR(std::fabs(r.pt[0].y() - r.pt[1].y()), 2.0, 1e-4);
  for (uint32_t j = 0; j < 2; ++j) EXPECT_NEAR(r.pd[j], 0.01, 1e-4);
  // Tilted 40 degrees onto its rim: the rim points that penetrate, at most the depth.
  const double tilt = 40 * M_PI / 180;
  r = run_pair(ground, cylinder({0, 0, std::cos(tilt) * 1.0 + std::sin(tilt) * 0.5 - 0.01},
                                Eigen::AngleAxisd(tilt, Vec3d::UnitY()).toRotationMatrix(), 0.5, 1.0));
  ASSERT_GE(r.count, 1u);
  EXPECT_NEAR(r.depth, 0.01, 1e-4);
  for (uint32_t j = 0; j < r.count; ++j) EXPECT_LE(r.pd[j], r.depth + 1e-6);
  // A capsule lying on a hull (a cube's corners): the two ends of its lowest line.
  std::vector<Eigen::Vector3f> cube;
  for (int i = 0; i < 8; ++i) cube.emplace_back((i & 1) ? 2.f : -2.f, (i & 2) ? 2.f : -2.f, (i & 4) ? 0.f : -4.f);
  const uint32_t cube_hull = hulls().add(cube);
  r = run_pair(capsule({0.5, 0, 0.29}, side, 0.3, 1.0), convex({0, 0, 0}, I, cube_hull));
  ASSERT_EQ(r.count, 2u);
  EXPECT_LT(r.n.z(), -1 + 1e-5);
  EXPECT_NEAR(std::fabs(r.pt[0].y() - r.pt[1].y()), 2.0, 1e-4);
  for (uint32_t j = 0; j < 2; ++j) {
    EXPECT_NEAR(r.pd[j], 0.01, 1e-5);
    EXPECT_NEAR(r.pt[j].z(), -0.005, 1e-5);
  }
  // A triangle under a cap (cylinder is A, its cap the reference): points in the disc.
  r = run_pair(cylinder({0, 0, 1}, I, 0.5, 1.0), triangle({-2, -2, 0.03}, {2, -2, 0.03}, {0, 3, 0.03}));
  ASSERT_EQ(r.count, 4u);
  EXPECT_NEAR(r.depth, 0.03, 1e-5);
  EXPECT_LT(r.n.z(), -1 + 1e-5);
  for (uint32_t j = 0; j < 4; ++j) {
    EXPECT_LE(std::hypot(r.pt[j].x(), r.pt[j].y()), 0.5 + 1e-5);
    EXPECT_NEAR(r.pd[j], 0.03, 1e-5);
  }
}

/// A cylinder tilted onto its rim, its lowest rim point halfway between two vertices of
/// the octagon that stands for its cap in the face clip: the clipped octagon alone
/// carries ~2/3 of the depth; the witnesses' midpoint joins with all of it.
TEST(GjkEpa, TiltedCylinderRimCarriesTheDepth) {
  const Shape ground = box({0, 0, -1}, Mat3d::Identity(), {5, 5, 1});
  const double rc = 0.5, h = 1.0, depth = 0.02;
  for (const double tilt_deg : {5.0, 10.0, 20.0}) {
    const double tilt = tilt_deg * M_PI / 180;
    // spun 22.5 degrees about its own axis, then tilted about x: the lowest rim point
    // lies at -112.5 degrees in the cylinder's frame
    const Mat3d R = (Eigen::AngleAxisd(tilt, Vec3d::UnitX()) * Eigen::AngleAxisd(M_PI / 8, Vec3d::UnitZ())).toRotationMatrix();
    const Vec3d a = R.col(2);
    const Vec3d w = (-Vec3d::UnitZ() + a.z() * a).normalized();  // down, across the cap
    const Vec3d low_rel = -h * a + rc * w;                       // the lowest point, from the centre
    const Vec3d c(0.2, -0.1, -low_rel.z() - depth);
    const Shape cyl = cylinder(c, R, rc, h);
    const Result r = run_pair(ground, cyl);
    ASSERT_GE(r.count, 1u) << tilt_deg;
    EXPECT_NEAR(r.depth, depth, 1e-4) << tilt_deg;
    EXPECT_GT(r.n.z(), 1 - 1e-4) << tilt_deg;  // A (the ground) to B
    uint32_t deepest = 0;
    for (uint32_t j = 1; j < r.count; ++j)
      if (r.pd[j] > r.pd[deepest]) deepest = j;
    EXPECT_NEAR(r.pd[deepest], r.depth, 1e-4) << tilt_deg;
    // near the lowest rim point (EPA's witness slides along the rim, where the height
    // changes with the square of the angle)
    const Vec3d low = c + low_rel;
    EXPECT_LT((r.pt[deepest] - (low + Vec3d(0, 0, 0.5 * depth))).norm(), 2e-2) << tilt_deg;
    for (uint32_t j = 0; j < r.count; ++j) {
      EXPECT_TRUE(inside_leaf(ground, r.pt[j] + r.n * (0.5 * r.pd[j]), 1e-4)) << tilt_deg << " point " << j;
      EXPECT_TRUE(inside_leaf(cyl, r.pt[j] - r.n * (0.5 * r.pd[j]), 1e-4)) << tilt_deg << " point " << j;
    }
  }
}

TEST(GjkEpa, OrientedBoxesAgreeWithSat) {
  std::mt19937 rng(13);
  std::uniform_real_distribution<double> u(-1, 1);
  int overlapping = 0;
  for (int t = 0; t < 2000; ++t) {
    const Shape a = rounded(box(Vec3d(u(rng), u(rng), u(rng)) * 0.2, test::random_rotation(rng),
                                Vec3d(0.05 + std::fabs(u(rng)), 0.05 + std::fabs(u(rng)), 0.05 + std::fabs(u(rng)))));
    const Shape b = rounded(box(Vec3d(u(rng), u(rng), u(rng)) * 2, test::random_rotation(rng),
                                Vec3d(0.05 + std::fabs(u(rng)), 0.05 + std::fabs(u(rng)), 0.05 + std::fabs(u(rng)))));
    const Sat s = sat(polytope_of(a), polytope_of(b));
    const Result r = run_pair(a, b);
    const double tol = 1e-4;
    if (std::fabs(s.depth) < tol) continue;  // touching within float rounding
    ASSERT_EQ(r.count > 0, s.overlap) << t << " sat depth " << s.depth;
    if (!s.overlap) continue;
    ++overlapping;
    EXPECT_NEAR(r.depth, s.depth, tol) << t;
    // The reported normal is a minimal direction: B moved along it by depth separates.
    EXPECT_NEAR(overlap_along(polytope_of(a), polytope_of(b), r.n), r.depth, tol) << t;
    for (uint32_t j = 0; j < r.count; ++j) EXPECT_LE(r.pd[j], r.depth + 1e-5);
    expect_points_on_both(a, b, r, 1e-4, t);
  }
  EXPECT_GT(overlapping, 200);
}

/// Hulls of random clouds (and hull vs box, hull vs triangle) against SAT in double over
/// all face normals and edge-pair crosses: overlap status, depth, minimal normal.
TEST(GjkEpa, RandomHullsAgreeWithSat) {
  std::mt19937 rng(23);
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<uint32_t> ids;
  for (int h = 0; h < 6; ++h) {
    std::vector<Eigen::Vector3f> pts;
    const int n = 4 + 10 * h;
    const Eigen::Vector3f stretch(1.0f, 0.3f + 0.15f * static_cast<float>(h), 0.7f);
    for (int i = 0; i < n; ++i)
      pts.push_back(Eigen::Vector3f(static_cast<float>(u(rng)), static_cast<float>(u(rng)), static_cast<float>(u(rng)))
                        .cwiseProduct(stretch));
    ids.push_back(hulls().add(pts));
  }
  const NarrowConfig cfg = config();  // after the hulls are added
  int overlapping = 0;
  for (int t = 0; t < 1500; ++t) {
    const uint32_t ha = ids[t % ids.size()], hb = ids[(t / 6) % ids.size()];
    const Shape a = rounded(convex(Vec3d(u(rng), u(rng), u(rng)) * 0.2, test::random_rotation(rng), ha));
    Shape b;
    const Vec3d pb = Vec3d(u(rng), u(rng), u(rng)) * 1.5;
    switch (t % 3) {
      case 0: b = convex(pb, test::random_rotation(rng), hb); break;
      case 1: b = box(pb, test::random_rotation(rng), Vec3d(0.1 + std::fabs(u(rng)), 0.1 + std::fabs(u(rng)), 0.1)); break;
      default:
        b = triangle(pb + Vec3d(u(rng), u(rng), u(rng)), pb + Vec3d(u(rng), u(rng), u(rng)), pb + Vec3d(u(rng), u(rng), u(rng)));
        break;
    }
    b = rounded(b);
    // Types in bucket order (box < convex < triangle): swap so that A's type <= B's.
    const bool swap = b.type < a.type;
    const Shape& A = swap ? b : a;
    const Shape& B = swap ? a : b;
    const Sat s = sat(polytope_of(A), polytope_of(B));
    const Result r = run_pair(A, B, cfg);
    const double tol = 1e-4;
    if (std::fabs(s.depth) < tol) continue;
    ASSERT_EQ(r.count > 0, s.overlap) << t << " sat depth " << s.depth;
    if (!s.overlap) continue;
    ++overlapping;
    EXPECT_NEAR(r.depth, s.depth, tol) << t;
    EXPECT_NEAR(overlap_along(polytope_of(A), polytope_of(B), r.n), r.depth, tol) << t;
    for (uint32_t j = 0; j < r.count; ++j) {
      EXPECT_GT(r.pd[j], 0.0);
      EXPECT_LE(r.pd[j], r.depth + 1e-5);
    }
    expect_points_on_both(A, B, r, 1e-4, t);
  }
  EXPECT_GT(overlapping, 300);
}

/// Sphere against capsule: closed form (distance from the centre to the segment).
TEST(GjkEpa, SphereCapsuleClosedForm) {
  std::mt19937 rng(14);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int t = 0; t < 500; ++t) {
    const Shape a = rounded(sphere(Vec3d(u(rng), u(rng), u(rng)), 0.1 + 0.5 * std::fabs(u(rng))));
    const Shape b = rounded(capsule(Vec3d(u(rng), u(rng), u(rng)), test::random_rotation(rng), 0.1 + 0.5 * std::fabs(u(rng)),
                                    std::fabs(u(rng))));
    const Vec3d ax = b.R.col(2);
    const double tt = std::clamp((a.p - b.p).dot(ax), -b.e[1], b.e[1]);
    const Vec3d q = b.p + ax * tt;
    const double d = (q - a.p).norm();
    const double depth = a.e[0] + b.e[0] - d;
    const Result r = run_pair(a, b);
    if (std::fabs(depth) < 1e-5) continue;
    ASSERT_EQ(r.count > 0, depth > 0) << t;
    if (depth <= 0) continue;
    EXPECT_NEAR(r.depth, depth, 1e-5);
    if (d > 1e-3) {
      EXPECT_GT(r.n.dot((q - a.p) / d), 1 - 1e-5);
    }
  }
}

/// Coaxial cylinders stacked along their axis: depth = axial overlap, normal = axis.
TEST(GjkEpa, CoaxialCylinders) {
  std::mt19937 rng(15);
  for (int t = 0; t < 100; ++t) {
    const Mat3d R = test::random_rotation(rng);
    const Shape a = rounded(cylinder({0, 0, 0}, R, 1.0, 0.5));
    const Shape b = rounded(cylinder(R.col(2) * 0.9, R, 0.7, 0.5));
    const Result r = run_pair(a, b);
    ASSERT_GE(r.count, 1u);
    EXPECT_NEAR(r.depth, 0.1, 2e-4) << t;
    EXPECT_GT(r.n.dot(R.col(2)), 1 - 1e-3) << t;
  }
}

/// An ellipsoid with equal radii is a sphere.
TEST(GjkEpa, RoundEllipsoidIsASphere) {
  std::mt19937 rng(16);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int t = 0; t < 200; ++t) {
    const Shape a = rounded(sphere(Vec3d(u(rng), u(rng), u(rng)) * 0.3, 0.6));
    const Shape b = rounded(ellipsoid(Vec3d(u(rng), u(rng), u(rng)), test::random_rotation(rng), {0.5, 0.5, 0.5}));
    const double d = (b.p - a.p).norm();
    const double depth = 1.1 - d;
    const Result r = run_pair(a, b);
    if (std::fabs(depth) < 1e-4) continue;
    ASSERT_EQ(r.count > 0, depth > 0) << t;
    if (depth > 0) {
      EXPECT_NEAR(r.depth, depth, 1e-4) << t;
      if (d > 1e-2) {
        EXPECT_GT(r.n.dot((b.p - a.p) / d), 1 - 1e-3) << t;
      }
    }
  }
}

/// Near-concentric round ellipsoids: the core difference is a ball of radius R1 + R2
/// about a point close to the origin, so every face of EPA's polytope is about as close
/// and EPA stops at its cap far from the answer (before the refinement on the sphere of
/// directions, its closest face could lie in the wrong basin: errors of ~|offset|).
TEST(GjkEpa, NearConcentricRoundEllipsoids) {
  std::mt19937 rng(21);
  std::uniform_real_distribution<double> u(-1, 1), mag(1e-3, 0.05);
  for (int t = 0; t < 200; ++t) {
    Vec3d dir(u(rng), u(rng), u(rng));
    if (!(dir.norm() > 1e-3)) continue;
    const Vec3d c = dir.normalized() * mag(rng);
    const Shape a = rounded(ellipsoid(Vec3d(u(rng), u(rng), u(rng)) * 0.5, test::random_rotation(rng), {0.45, 0.45, 0.45}));
    const Shape b = rounded(ellipsoid(a.p + c, test::random_rotation(rng), {0.9, 0.9, 0.9}));
    const double depth = 1.35 - (b.p - a.p).norm();
    const Result r = run_pair(a, b);
    ASSERT_GE(r.count, 1u) << t;
    EXPECT_NEAR(r.depth, depth, 5e-5) << t;
  }
}

// --- smooth pairs: EPA bracketing + Newton (gjk_epa.cpp polish_smooth) -----------------

/// Support of an ellipsoid (a sphere: equal radii) in double: n.p + |diag(e) R^T n|.
double ellipsoid_support(const Shape& s, const Vec3d& n) {
  const Vec3d radii = s.type == kLeafSphere ? Vec3d::Constant(s.e.x()) : s.e;
  const Vec3d q = (s.R.transpose() * n).cwiseProduct(radii);
  return n.dot(s.p) + q.norm();
}

/// Penetration depth of two ellipsoids / spheres, brute force in double: the minimum
/// over unit n of h_A(n) + h_B(-n) - (no GJK, EPA or Newton): 20000 Fibonacci
/// directions, then a compass search in tangent coordinates from the best 8 (steps
/// halved down to 1e-12 rad). Also returns the minimiser.
double smooth_reference(const Shape& a, const Shape& b, Vec3d* n_out) {
  auto h = [&](const Vec3d& n) { return ellipsoid_support(a, n) + ellipsoid_support(b, -n); };
  constexpr int kN = 20000;
  std::vector<std::pair<double, Vec3d>> best;
  const double golden = 3.14159265358979323846 * (3.0 - std::sqrt(5.0));
  for (int i = 0; i < kN; ++i) {
    const double z = 1.0 - 2.0 * (i + 0.5) / kN, rr = std::sqrt(1.0 - z * z), ph = golden * i;
    const Vec3d n(rr * std::cos(ph), rr * std::sin(ph), z);
    best.emplace_back(h(n), n);
  }
  std::partial_sort(best.begin(), best.begin() + 8, best.end(),
                    [](const auto& x, const auto& y) { return x.first < y.first; });
  double vbest = INFINITY;
  Vec3d nbest = best[0].second;
  for (int s0 = 0; s0 < 8; ++s0) {
    Vec3d n = best[s0].second;
    double v = best[s0].first;
    for (double step = 0.02; step > 1e-12;) {
      const Vec3d t1 = n.unitOrthogonal(), t2 = n.cross(t1);
      bool moved = false;
      for (const Vec3d& d : {t1, Vec3d(-t1), t2, Vec3d(-t2)}) {
        const Vec3d m = (n + d * step).normalized();
        const double hv = h(m);
        if (hv < v) {
          v = hv;
          n = m;
          moved = true;
          break;
        }
      }
      if (!moved) step *= 0.5;
    }
    if (v < vbest) {
      vbest = v;
      nbest = n;
    }
  }
  *n_out = nbest;
  return vbest;
}

/// Ellipsoid-ellipsoid and sphere-ellipsoid pairs (smooth support functions: EPA hands
/// its bracket to Newton): depth and normal against the brute-force reference, at
/// scales 1e-4, 1 and 1e4, 1e5 from the origin, for shallow to deep overlaps and
/// eccentric (20:1) shapes; depth never below the true one by more than rounding (a
/// safe displacement). Also the point of Newton: far fewer EPA expansions than the
/// ~28 that EPA alone needs here at the default tolerance (~16 with it).
TEST(GjkEpa, SmoothPairsNewtonMatchesReference) {
  for (const auto& [scale, offset] : {std::pair{1.0, 0.0}, {1e-4, 0.0}, {1e4, 0.0}, {1.0, 1e5}}) {
    std::mt19937 rng(31);
    std::uniform_real_distribution<double> u(-1, 1), rad(0.25, 1.0), f(0.2, 1.0);
    double iters = 0;
    int hits = 0;
    for (int t = 0; t < 150; ++t) {
      const bool sphere_a = t % 5 == 0, thin = t % 4 == 1;
      Vec3d ea(rad(rng), rad(rng), rad(rng)), eb(rad(rng), rad(rng), rad(rng));
      if (thin) eb = Vec3d(1.0, 0.05, 0.3);
      const Vec3d pa = Vec3d::Constant(offset) + Vec3d(u(rng), u(rng), u(rng)) * scale;
      Shape a = sphere_a ? sphere(pa, ea.x() * scale) : ellipsoid(pa, test::random_rotation(rng), ea * scale);
      Vec3d dir(u(rng), u(rng), u(rng));
      if (!(dir.norm() > 1e-2)) continue;
      dir.normalize();
      // B along dir at f times roughly the touching distance (sizes along dir).
      const double reach = (sphere_a ? ea.x() : ea.maxCoeff()) + eb.maxCoeff();
      const Shape b = rounded(ellipsoid(pa + dir * (f(rng) * reach * scale), test::random_rotation(rng), eb * scale));
      a = rounded(a);
      Vec3d n_ref;
      const double depth = smooth_reference(a, b, &n_ref);
      const double L = reach * scale;
      if (!(depth > 1e-3 * L)) continue;
      Lanes la, lb;
      la.push(a);
      lb.push(b);
      const NarrowConfig cfg = config();
      const cvx::V3 origin{static_cast<float>(a.p.x()), static_cast<float>(a.p.y()), static_cast<float>(a.p.z())};
      const cvx::Leaf A = cvx::load_leaf(la.soa(), 0, a.type, &cfg.hulls, origin);
      const cvx::Leaf B = cvx::load_leaf(lb.soa(), 0, b.type, &cfg.hulls, origin);
      cvx::LaneContact c;
      cvx::collide_convex_lane(A, B, cfg, &c);
      ASSERT_EQ(c.count, 1u) << scale << " " << t;
      // A sphere's centre outside the ellipsoid: GJK's distance of the cores, no EPA.
      if (c.used_epa) {
        ++hits;
        iters += c.epa_iterations;
      }
      EXPECT_NEAR(c.depth, depth, 5e-5 * L) << scale << " " << t;
      EXPECT_GE(c.depth, depth - 2e-6 * L) << scale << " " << t;
      const Vec3d n(c.n.x, c.n.y, c.n.z);
      EXPECT_LT(std::acos(std::clamp(n.dot(n_ref), -1.0, 1.0)), 2e-2) << scale << " " << t;
      // The witness point lies within tolerance of both surfaces' contact region:
      // moving B by n * depth leaves the pair touching (support overlap ~ 0).
      const Vec3d pt = Vec3d(c.point[0].x, c.point[0].y, c.point[0].z) + a.p;
      EXPECT_NEAR((pt - a.p).dot(n), ellipsoid_support(a, n) - a.p.dot(n) - 0.5 * c.depth, 1e-3 * L)
          << scale << " " << t;
    }
    ASSERT_GT(hits, 60);
    EXPECT_LT(iters / hits, 20.0) << scale;  // EPA alone: ~28 here
  }
}

/// A sphere deep inside a cylinder, near its centre, where the side and the caps are
/// about equally close: depth = r + min(radius - radial offset, half-length - |axial
/// offset|). The support function of the cylinder has a kink across the side (a
/// segment support set), which plain gradient steps cannot follow.
TEST(GjkEpa, SphereDeepInCylinder) {
  std::mt19937 rng(22);
  std::uniform_real_distribution<double> u(-1, 1), size(0.25, 0.3), rs(0.1, 0.3);
  for (int t = 0; t < 300; ++t) {
    const Mat3d R = test::random_rotation(rng);
    const double rad = size(rng), hl = size(rng), r0 = rs(rng);
    const Shape b = rounded(cylinder(Vec3d(u(rng), u(rng), u(rng)), R, rad, hl));
    const Shape a = rounded(sphere(b.p + Vec3d(u(rng), u(rng), u(rng)) * 0.01, r0));
    const Vec3d q = b.R.transpose() * (a.p - b.p);
    const double depth = r0 + std::min(rad - std::hypot(q.x(), q.y()), hl - std::fabs(q.z()));
    const Result r = run_pair(a, b);
    ASSERT_GE(r.count, 1u) << t;
    EXPECT_NEAR(r.depth, depth, 2e-5) << t;
  }
}

/// Type names without pair_kernels.cpp (which also references the specialised kernels).
const char* tname(LeafType t) {
  static const char* const names[] = {"sphere", "capsule", "box", "convex", "cylinder", "ellipsoid", "triangle", "half-space"};
  return t < kLeafTypeCount ? names[t] : "unknown";
}

// --- every type pair: random fuzz, the safe-displacement property, no NaN -----------------

Shape random_shape(LeafType t, std::mt19937& rng, Vec3d centre, double size) {
  std::uniform_real_distribution<double> u(0.2, 1.0);
  const Mat3d R = test::random_rotation(rng);
  switch (t) {
    case kLeafSphere: return sphere(centre, size * u(rng));
    case kLeafCapsule: return capsule(centre, R, size * u(rng) * 0.5, size * u(rng));
    case kLeafBox: return box(centre, R, Vec3d(u(rng), u(rng), u(rng)) * size);
    case kLeafConvex: {
      static uint32_t hull_id = [] {
        std::mt19937 g(99);
        std::normal_distribution<float> n;
        std::vector<Eigen::Vector3f> pts;
        for (int i = 0; i < 40; ++i) pts.emplace_back(n(g), 0.6f * n(g), 0.8f * n(g));
        return hulls().add(pts);
      }();
      Shape s = convex(centre, R, hull_id);
      // The hull is ~2 units across: scale is fixed, so only use it at size ~1.
      return s;
    }
    case kLeafCylinder: return cylinder(centre, R, size * u(rng), size * u(rng));
    case kLeafEllipsoid: return ellipsoid(centre, R, Vec3d(u(rng), u(rng), u(rng)) * size);
    case kLeafTriangle: {
      std::uniform_real_distribution<double> v(-1, 1);
      return triangle(centre + Vec3d(v(rng), v(rng), v(rng)) * size, centre + Vec3d(v(rng), v(rng), v(rng)) * size,
                      centre + Vec3d(v(rng), v(rng), v(rng)) * size);
    }
    default: return sphere(centre, size);
  }
}

Shape moved(Shape s, const Vec3d& d) {
  s.p += d;
  if (s.type == kLeafTriangle) {
    s.v1 += d;
    s.v2 += d;
  }
  return s;
}

/// Every type pair at one size and offset: count <= 4, finite, unit normal, pdepth in
/// (0, depth], and the safe displacement: B moved by n * (depth + slack) is free, B
/// moved by n * (depth - slack) still touches (depth is not overestimated).
void safe_displacement(double size, double offset, double slack, bool with_convex) {
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> u(-1, 1);
  const LeafType types[] = {kLeafSphere, kLeafCapsule, kLeafBox, kLeafConvex, kLeafCylinder, kLeafEllipsoid, kLeafTriangle};
  const int trials = static_cast<int>(test::scaled(150));
  const Vec3d base = Vec3d(1.0, -0.5, 0.25) * offset;
  for (LeafType ta : types) {
    for (LeafType tb : types) {
      if (tb < ta || (!with_convex && (ta == kLeafConvex || tb == kLeafConvex))) continue;
      int hits = 0;
      for (int t = 0; t < trials; ++t) {
        const Shape a = rounded(random_shape(ta, rng, base, size));
        const Shape b = rounded(random_shape(tb, rng, base + Vec3d(u(rng), u(rng), u(rng)) * 1.2 * size, size));
        const Result r = run_pair(a, b);
        ASSERT_LE(r.count, 4u);
        if (r.count == 0) continue;
        ++hits;
        ASSERT_TRUE(std::isfinite(r.depth)) << tname(ta) << "/" << tname(tb);
        ASSERT_NEAR(r.n.norm(), 1.0, 1e-5);
        EXPECT_GT(r.depth, 0.0);
        for (uint32_t j = 0; j < r.count; ++j) {
          ASSERT_TRUE(r.pt[j].allFinite());
          EXPECT_GT(r.pd[j], 0.0);
          EXPECT_LE(r.pd[j], r.depth * (1 + 1e-5) + 1e-6 * size);
          // Midway between a point of A and a point of B, pd apart along n.
          EXPECT_TRUE(inside_leaf(a, r.pt[j] + r.n * (0.5 * r.pd[j]), slack))
              << tname(ta) << "/" << tname(tb) << " t " << t << " point " << j;
          EXPECT_TRUE(inside_leaf(b, r.pt[j] - r.n * (0.5 * r.pd[j]), slack))
              << tname(ta) << "/" << tname(tb) << " t " << t << " point " << j;
        }
        const Result beyond = run_pair(a, rounded(moved(b, r.n * (r.depth + slack))));
        EXPECT_EQ(beyond.count, 0u) << tname(ta) << "/" << tname(tb) << " t " << t << " depth " << r.depth
                                    << " remaining " << beyond.depth;
        if (r.depth > 4 * slack) {
          const Result shy = run_pair(a, rounded(moved(b, r.n * (r.depth - slack))));
          EXPECT_GT(shy.count, 0u) << tname(ta) << "/" << tname(tb) << " t " << t;
        }
      }
      // Two random zero-thickness triangles rarely cross.
      EXPECT_GT(hits, (ta == kLeafTriangle && tb == kLeafTriangle) ? trials / 30 : trials / 10)
          << tname(ta) << "/" << tname(tb);
    }
  }
}

TEST(GjkEpa, EveryPairSafeDisplacement) { safe_displacement(1.0, 0.0, 2e-3, true); }
TEST(GjkEpa, EveryPairSafeDisplacementTiny) { safe_displacement(1e-4, 0.0, 2e-7, false); }
/// Regression (found by the test above at IMPACT_TEST_INTENSITY=30): two tiny boxes
/// (1e-4 scale) overlapping deeper than A is thick, face axis A's x. The clipped
/// points lie on the side planes of A's face and their rays run along them; the ray's
/// direction cosine with those planes is rounding (~1e-8, not 0), so slack / c was an
/// arbitrary t and the chord rejected every point, leaving the one-point fallback
/// outside A. Planes within kChordParallel of parallel are now treated as parallel.
TEST(GjkEpa, DeepTinyBoxesKeepTheirClippedPoints) {
  Mat3d ra, rb;
  ra << -0.51715076, 0.509102225, 0.688018918, 0.386209488, 0.856173396, -0.343233645, -0.763804495, 0.0882158875,
      -0.639390826;
  rb << -0.290857047, 0.680982769, -0.672060013, -0.928076863, -0.030086318, 0.371171355, 0.232541472, 0.731681168,
      0.640755117;
  const Shape a = rounded(box(Vec3d(0, 0, 0), ra, Vec3d(2.26050179e-05, 6.92345129e-05, 3.87736181e-05)));
  const Shape b = rounded(box(Vec3d(-2.11805e-05, 2.61831701e-05, 1.7516355e-05), rb,
                              Vec3d(4.31563749e-05, 4.56742346e-05, 7.49517058e-05)));
  for (uint32_t sat : {96u, 0u}) {  // through SAT and through GJK/EPA
    NarrowConfig cfg = config();
    cfg.sat_max_vertices = sat;
    const Result r = run_pair(a, b, cfg);
    ASSERT_GT(r.count, 1u) << "sat " << sat << ": the face clip kept no point";
    for (uint32_t j = 0; j < r.count; ++j) {
      EXPECT_TRUE(inside_leaf(a, r.pt[j] + r.n * (0.5 * r.pd[j]), 2e-7)) << "sat " << sat << " point " << j;
      EXPECT_TRUE(inside_leaf(b, r.pt[j] - r.n * (0.5 * r.pd[j]), 2e-7)) << "sat " << sat << " point " << j;
    }
  }
}
TEST(GjkEpa, EveryPairSafeDisplacementHuge) { safe_displacement(1e4, 0.0, 20.0, false); }
/// 1e5 from the origin the float spacing is 7.8e-3: the slack covers the pose rounding.
TEST(GjkEpa, EveryPairSafeDisplacementFarAway) { safe_displacement(1.0, 1e5, 3e-2, true); }

/// Coincident centres, identical shapes, and extreme aspect ratios: finite output.
TEST(GjkEpa, DegenerateInputsStayFinite) {
  std::mt19937 rng(18);
  const LeafType types[] = {kLeafSphere, kLeafCapsule, kLeafBox, kLeafConvex, kLeafCylinder, kLeafEllipsoid, kLeafTriangle};
  for (double size : {1e-4, 1.0, 1e4}) {
    for (LeafType ta : types) {
      for (LeafType tb : types) {
        if (tb < ta || (size != 1.0 && (ta == kLeafConvex || tb == kLeafConvex))) continue;
        const Vec3d c = Vec3d(1e5, -1e5, 3e4) * (size >= 1.0 ? 1.0 : 0.0);
        Shape a = random_shape(ta, rng, c, size);
        Shape b = random_shape(tb, rng, c, size);
        // Triangles through the common centre (their centroid), so every pair overlaps.
        auto centre_triangle = [&](Shape& s) {
          if (s.type != kLeafTriangle) return;
          const Vec3d d0 = s.p - c, d1 = s.v1 - c;
          s.v2 = c - d0 - d1;
        };
        centre_triangle(a);
        centre_triangle(b);
        if (tb == kLeafTriangle && ta == kLeafTriangle) b = a;  // coplanar, identical
        const Result r = run_pair(rounded(a), rounded(b));
        if (r.count == 0) {
          // Only two zero-thickness triangles may miss (depth 0 when coplanar).
          EXPECT_TRUE(ta == kLeafTriangle && tb == kLeafTriangle) << tname(ta) << "/" << tname(tb);
          continue;
        }
        EXPECT_NEAR(r.n.norm(), 1.0, 1e-5) << tname(ta) << "/" << tname(tb);
        EXPECT_TRUE(std::isfinite(r.depth) && r.depth > 0);
        for (uint32_t j = 0; j < r.count; ++j) EXPECT_TRUE(r.pt[j].allFinite());
      }
    }
  }
  // Needles and pancakes.
  const Mat3d I = Mat3d::Identity();
  const Result n1 = run_pair(box({0, 0, 0}, I, {1e-3, 1e-3, 10}), box({0, 0, 9.95}, I, {1e-3, 10, 1e-3}) );
  ASSERT_GE(n1.count, 1u);
  EXPECT_TRUE(std::isfinite(n1.depth));
  const Result p1 = run_pair(cylinder({0, 0, 0}, I, 10, 1e-3), cylinder({0, 0, 1.5e-3}, I, 10, 1e-3));
  ASSERT_GE(p1.count, 1u);
  EXPECT_NEAR(p1.depth, 0.5e-3, 1e-5);
  EXPECT_GT(std::fabs(p1.n.z()), 1 - 1e-4);
}

TEST(GjkEpa, IterationCapsRespected) {
  std::mt19937 rng(19);
  for (uint32_t cap : {1u, 2u, 5u}) {
    NarrowConfig cfg = config();
    cfg.gjk_max_iterations = cap;
    cfg.epa_max_iterations = cap;
    for (int t = 0; t < 100; ++t) {
      const Shape a = rounded(random_shape(kLeafEllipsoid, rng, Vec3d::Zero(), 1.0));
      const Shape b = rounded(random_shape(kLeafCylinder, rng, Vec3d(0.3, 0.2, 0.1), 1.0));
      Lanes la, lb;
      la.push(a);
      lb.push(b);
      const cvx::V3 origin{static_cast<float>(a.p.x()), static_cast<float>(a.p.y()), static_cast<float>(a.p.z())};
      const cvx::Leaf A = cvx::load_leaf(la.soa(), 0, a.type, &cfg.hulls, origin);
      const cvx::Leaf B = cvx::load_leaf(lb.soa(), 0, b.type, &cfg.hulls, origin);
      cvx::LaneContact c;
      cvx::collide_convex_lane(A, B, cfg, &c);
      EXPECT_LE(c.gjk_iterations, cap);
      EXPECT_LE(c.epa_iterations, cap);
      if (c.count > 0) {
        EXPECT_NEAR(len(c.n), 1.0f, 1e-5f);
        EXPECT_TRUE(std::isfinite(c.depth));
      }
    }
  }
}

/// EPA on a curved shape: the depth error shrinks with the tolerance knob.
TEST(GjkEpa, ToleranceKnobChangesError) {
  std::mt19937 rng(20);
  auto mean_error = [&](float tol) {
    NarrowConfig cfg = config();
    cfg.epa_tolerance = tol;
    cfg.epa_max_iterations = 200;
    std::mt19937 g(21);
    double err = 0;
    for (int t = 0; t < 100; ++t) {
      // A round ellipsoid (radius 1, curved for EPA) resting 0.2 deep on a big box.
      const Mat3d R = test::random_rotation(g);
      const Shape a = rounded(box(Vec3d(0, 0, -5), test::random_rotation(g) * 0 + Mat3d::Identity(), {5, 5, 5}));
      const Shape b = rounded(ellipsoid(Vec3d(0, 0, 0.8), R, {1, 1, 1}));
      const Result r = run_pair(a, b, cfg);
      EXPECT_EQ(r.count, 1u);
      err += std::fabs(r.depth - 0.2);
    }
    return err / 100;
  };
  (void)rng;
  const double loose = mean_error(1e-1f), tight = mean_error(1e-6f);
  EXPECT_LT(tight, 1e-4);
  EXPECT_GT(loose, 3 * tight);
}

TEST(GjkEpa, DeterministicAcrossPartitions) {
  std::mt19937 rng(22);
  std::uniform_real_distribution<double> u(-1, 1);
  const LeafType types[] = {kLeafBox, kLeafConvex, kLeafCylinder, kLeafEllipsoid};
  for (LeafType ta : types)
    for (LeafType tb : types) {
      if (tb < ta) continue;
      Lanes la, lb;
      const uint32_t m = 64;
      for (uint32_t k = 0; k < m; ++k) {
        la.push(rounded(random_shape(ta, rng, Vec3d::Zero(), 1.0)));
        lb.push(rounded(random_shape(tb, rng, Vec3d(u(rng), u(rng), u(rng)), 1.0)));
      }
      Out o1(m), o2(m);
      const NarrowConfig cfg = config();
      general_route(la.soa(), lb.soa(), o1.view(), Range{0, m}, cfg, ta, tb);
      for (uint32_t b0 = 0; b0 < m; b0 += 7)
        general_route(la.soa(), lb.soa(), o2.view(), Range{b0, std::min(m, b0 + 7)}, cfg, ta, tb);
      for (uint32_t k = 0; k < m; ++k) {
        ASSERT_EQ(o1.count[k], o2.count[k]);
        if (o1.count[k] == 0) continue;
        EXPECT_EQ(std::memcmp(&o1.depth[k], &o2.depth[k], 4), 0);
        for (int i = 0; i < 3; ++i) EXPECT_EQ(std::memcmp(&o1.n[i][k], &o2.n[i][k], 4), 0);
      }
    }
}

// --- deep pairs with a many-vertex hull: EPA past its iteration cap ------------------------
// Around a deep core, a round hull's support function has a strict local minimum at
// nearly every face, and EPA must uncover most of the faces within the depth band
// before it converges: up to ~100-350 expansions where the cap is 64. EPA stopped at
// the cap ended on a wrong face (depth 3e-3 too large, normal up to 104 degrees off).

/// Points on an ellipsoid with semi-axes uniform in [lo, 1] (float), like
/// sphere_convex_test.cpp's ellipsoid_points (same draws for the same generator state).
std::vector<Eigen::Vector3f> ellipsoid_cloud(std::mt19937& g, int np, double lo) {
  double ax[3];
  for (double& a : ax) a = std::uniform_real_distribution<double>(lo, 1.0)(g);
  std::vector<Eigen::Vector3f> pts;
  for (int i = 0; i < np; ++i) {
    Vec3d u;
    do {
      std::normal_distribution<double> d(0.0, 1.0);
      const double x = d(g), y = d(g), z = d(g);
      u = Vec3d(x, y, z);
    } while (!(u.norm() > 1e-3));
    u.normalize();
    pts.emplace_back(static_cast<float>(ax[0] * u.x()), static_cast<float>(ax[1] * u.y()),
                     static_cast<float>(ax[2] * u.z()));
  }
  return pts;
}

/// The posed hull of a convex shape (as the lanes see it) with its faces' outward unit
/// normals in double from the polygons (Newell), one per face.
Polytope posed_hull(const Shape& s) {
  const Shape r = rounded(s);
  const HullData& h = hulls().data[r.hull];
  Polytope P;
  for (const auto& v : h.vertices) P.verts.push_back(r.R * v.cast<double>() + r.p);
  for (const auto& f : h.faces) {
    Vec3d n = Vec3d::Zero();
    for (size_t i = 0; i < f.size(); ++i) n += P.verts[f[i]].cross(P.verts[f[(i + 1) % f.size()]]);
    P.normals.push_back(n.normalized());
    for (size_t i = 0; i < f.size(); ++i) {
      const uint32_t a = f[i], b = f[(i + 1) % f.size()];
      if (a < b) P.edges.push_back((P.verts[b] - P.verts[a]).normalized());  // each edge once
    }
  }
  return P;
}

/// The lane's EPA expansions through collide_convex_lane (0: no EPA), and whether
/// the SAT kernel accepts the pair (sat_vertex_count > 0).
struct LaneInfo {
  uint32_t epa_expansions = 0;
  bool sat_applies = false;
};
LaneInfo lane_info(const Shape& a, const Shape& b, const NarrowConfig& cfg) {
  Lanes la, lb;
  la.push(a);
  lb.push(b);
  const cvx::V3 origin{static_cast<float>(a.p.x()), static_cast<float>(a.p.y()), static_cast<float>(a.p.z())};
  const cvx::Leaf A = cvx::load_leaf(la.soa(), 0, a.type, &cfg.hulls, origin);
  const cvx::Leaf B = cvx::load_leaf(lb.soa(), 0, b.type, &cfg.hulls, origin);
  cvx::LaneContact c;
  cvx::collide_convex_lane(A, B, cfg, &c);
  LaneInfo info;
  info.epa_expansions = c.used_epa ? c.epa_iterations : 0u;
  info.sat_applies = (a.type == kLeafBox || a.type == kLeafConvex) &&
                     (b.type == kLeafBox || b.type == kLeafConvex) && cvx::sat_vertex_count(A, B) > 0;
  return info;
}

/// The lane of sphere_convex_test.cpp (ManyFaceHull, IMPACT_TEST_INTENSITY=30) where
/// GJK/EPA disagreed with the sphere-hull kernel: a sphere deep in a 400-vertex hull
/// (796 faces). Reference: the nearest face plane of the posed hull in double
/// (depth = r + its distance, normal = minus its outward normal).
TEST(GjkEpa, SphereDeepInManyFaceHull) {
  std::mt19937 g(99);
  const uint32_t h = hulls().add(ellipsoid_cloud(g, 400, 0.3));
  ASSERT_EQ(hulls().data[h].vertices.size(), 400u);
  ASSERT_EQ(hulls().data[h].faces.size(), 796u);
  const float r9[9] = {-0.346952617f, 0.932676554f,  0.0986829549f, 0.00505506434f, 0.107076995f,
                       -0.9942379f,   -0.937869012f, -0.344454587f, -0.0418653823f};
  Mat3d R;
  for (int i = 0; i < 9; ++i) R(i / 3, i % 3) = r9[i];
  const Shape a = rounded(sphere(Vec3d(-0.77271837f, 3.45435047f, -0.32568711f), 0.672836065f));
  const Shape b = rounded(convex(Vec3d(-0.794422328f, 3.45396376f, -0.31916979f), R, h));
  const Polytope P = posed_hull(b);
  double best = INFINITY, second = INFINITY;
  Vec3d n_ref = Vec3d::Zero();
  for (const Vec3d& m : P.normals) {
    double hi = -INFINITY;
    for (const Vec3d& v : P.verts) hi = std::max(hi, m.dot(v));
    const double s = hi - m.dot(a.p);  // > 0: the centre is inside this face's plane
    ASSERT_GT(s, 0.0);
    if (s < best) {
      second = best;
      best = s;
      n_ref = -m;
    } else {
      second = std::min(second, s);
    }
  }
  const double depth_ref = a.e[0] + best;  // 1.4532464
  ASSERT_GT(second - best, 1e-3);          // one nearest face: the normal is defined
  // The regression's premise: EPA needs more expansions than the default cap.
  EXPECT_GT(lane_info(a, b, config()).epa_expansions, config().epa_max_iterations);
  const Result r = run_pair(a, b);
  ASSERT_EQ(r.count, 1u);
  EXPECT_NEAR(r.depth, depth_ref, 2e-5);
  EXPECT_GT(r.n.dot(n_ref), std::cos(1e-3)) << r.n.transpose() << " vs " << n_ref.transpose();
}

/// Deep, nearly concentric pairs of a round 400-vertex hull with every other type,
/// against exact references: the brute-force separating axis minimum in double over
/// the pair's face normals and edge crosses (sphere, capsule, box, triangle), the SAT
/// kernel (hull-hull, forced past sat_max_vertices; sat_test checks it against the
/// same brute force), the double-precision support-function minimiser of
/// narrow_reference.h (cylinder, ellipsoid). Checked: depth, and that the normal is a
/// minimiser (the overlap along it is the depth). Many lanes go past the default cap.
TEST(GjkEpa, DeepInManyVertexHullsMatchReferences) {
  std::mt19937 g(31);
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<uint32_t> round;
  for (int i = 0; i < 4; ++i) round.push_back(hulls().add(ellipsoid_cloud(g, 400, 0.9)));
  const LeafType types[] = {kLeafSphere,   kLeafCapsule,   kLeafBox,     kLeafConvex,
                            kLeafCylinder, kLeafEllipsoid, kLeafTriangle};
  const int trials = static_cast<int>(test::scaled(12));
  NarrowConfig gjk = config();
  gjk.sat_max_vertices = 0;  // hull-hull through GJK/EPA even where SAT would take it
  NarrowConfig exact = config();
  exact.sat_max_vertices = 1024;
  for (LeafType t : types) {
    int past_cap = 0;
    for (int k = 0; k < trials; ++k) {
      const Shape hs =
          rounded(convex(Vec3d(u(g), u(g), u(g)) * 0.02, test::random_rotation(g), round[k % 4]));
      const Shape o =
          rounded(t == kLeafConvex ? convex(Vec3d::Zero(), test::random_rotation(g), round[(k + 1) % 4])
                                   : random_shape(t, g, Vec3d::Zero(), 0.8));
      const Shape& a = t <= kLeafConvex ? o : hs;
      const Shape& b = t <= kLeafConvex ? hs : o;
      const LaneInfo info = lane_info(a, b, gjk);
      past_cap += info.epa_expansions > gjk.epa_max_iterations ? 1 : 0;
      const Result r = run_pair(a, b, gjk);
      ASSERT_GE(r.count, 1u) << tname(t) << " " << k;
      // Exact depth and the overlap along a unit direction, from the reference.
      double depth_ref = 0, along = 0;
      if (t == kLeafConvex) {
        ASSERT_TRUE(info.sat_applies);  // else `exact` would run GJK/EPA too
        const Result s = run_pair(a, b, exact);
        ASSERT_GE(s.count, 1u);
        depth_ref = s.depth;
        const Polytope A = posed_hull(a), B = posed_hull(b);
        along = overlap_along(A, B, r.n);
      } else if (t == kLeafCylinder || t == kLeafEllipsoid) {
        Lanes la, lb;
        la.push(a);
        lb.push(b);
        const test::nref::Shape ra = test::nref::shape_from_leaf(la.soa(), 0, a.type, &gjk.hulls);
        const test::nref::Shape rb = test::nref::shape_from_leaf(lb.soa(), 0, b.type, &gjk.hulls);
        depth_ref = test::nref::solve_pair(ra, rb).s;
        along = test::nref::overlap(ra, rb, {r.n.x(), r.n.y(), r.n.z()});
      } else {
        // Polytope cores: the point, the segment, the box, the triangle; radius added.
        Polytope A;
        double radius = 0;
        if (t == kLeafSphere) {
          A.verts = {a.p};
          radius = a.e[0];
        } else if (t == kLeafCapsule) {
          const Vec3d axis = a.R.col(2);
          A.verts = {a.p - axis * a.e[1], a.p + axis * a.e[1]};
          A.edges = {axis};
          radius = a.e[0];
        } else {
          A = polytope_of(t == kLeafTriangle ? b : a);
        }
        const Polytope H = posed_hull(hs);
        const bool hull_is_b = t != kLeafTriangle;
        const Sat s = hull_is_b ? sat(A, H) : sat(H, A);
        depth_ref = s.depth + radius;
        along = (hull_is_b ? overlap_along(A, H, r.n) : overlap_along(H, A, r.n)) + radius;
      }
      const double tol = 1e-4;  // of L ~ 1; EPA converges to 1e-5 of the pair's size
      EXPECT_NEAR(r.depth, depth_ref, tol) << tname(t) << " " << k;
      EXPECT_NEAR(along, depth_ref, tol) << tname(t) << " " << k << ": the normal is not a minimiser";
    }
    if (t == kLeafSphere || t == kLeafConvex || t == kLeafEllipsoid) {
      EXPECT_GT(past_cap, 0) << tname(t);
    }
  }
}

}  // namespace
}  // namespace impact::kernels
