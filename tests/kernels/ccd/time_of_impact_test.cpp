// time_of_impact (kernels/ccd/time_of_impact.cpp) against a double-precision reference.
//
// Reference: the signed separation of the posed shapes in closed form, in double (point
// to box / segment / triangle / plane for a sphere; the least vertex height for a box or
// a capsule over a plane; a slab for a thin wall), the poses moved by Eigen's AngleAxisd
// about each centre; the first time the separation falls to target by dense sampling
// (4096 steps) then bisection. Checks: a kernel hit lies where the reference separation
// is within target +- (tolerance + slack), and no earlier sampled time is below
// target - tolerance (nothing tunnels); a reference miss is a kernel miss.
#include "kernels/ccd/time_of_impact.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <functional>
#include <random>

#include "tests/support/test_support.h"

namespace impact::kernels::ccd {
namespace {

using cvx::Leaf;
using cvx::V3;
using Vd = Eigen::Vector3d;
using Md = Eigen::Matrix3d;

Vd d3(V3 v) { return Vd(v.x, v.y, v.z); }
V3 f3(const Vd& v) { return V3{float(v.x()), float(v.y()), float(v.z())}; }

Md rot(const V3& w, double t) {
  const Vd th = d3(w) * t;
  const double a = th.norm();
  if (a == 0.0) return Md::Identity();
  return Eigen::AngleAxisd(a, th / a).toRotationMatrix();
}

// Posed shape in double: centre c, axes R (columns), for a leaf moved to t.
struct PosedD {
  LeafType type;
  Vd c;
  Md R;
  Vd e;
  Vd v[3];  // triangle vertices
  Vd n;     // half-space normal
};

PosedD pose_d(const Leaf& l, const Motion& m, double t) {
  PosedD p;
  p.type = l.type;
  const Md Rt = rot(m.w, t);
  p.e = Vd(l.e[0], l.e[1], l.e[2]);
  if (l.type == kLeafTriangle) {
    const Vd c = (d3(l.p) + d3(l.v1) + d3(l.v2)) / 3.0;
    p.c = c + d3(m.v) * t;
    p.v[0] = p.c + Rt * (d3(l.p) - c);
    p.v[1] = p.c + Rt * (d3(l.v1) - c);
    p.v[2] = p.c + Rt * (d3(l.v2) - c);
    return p;
  }
  p.c = d3(l.p) + d3(m.v) * t;
  for (int k = 0; k < 3; ++k) p.R.col(k) = Rt * d3(l.ax[k]);
  p.n = Rt * Vd(l.e[0], l.e[1], l.e[2]);
  return p;
}

double seg_dist(const Vd& x, const Vd& a, const Vd& b) {
  const Vd ab = b - a;
  const double s = std::clamp((x - a).dot(ab) / std::max(ab.squaredNorm(), 1e-300), 0.0, 1.0);
  return (x - (a + ab * s)).norm();
}

// Signed distance of point x to the solid shape (sphere radius excluded for capsules).
double point_dist(const PosedD& s, const Vd& x) {
  switch (s.type) {
    case kLeafSphere: return (x - s.c).norm() - s.e[0];
    case kLeafCapsule: {
      const Vd u = s.R.col(2) * s.e[1];
      return seg_dist(x, s.c - u, s.c + u) - s.e[0];
    }
    case kLeafBox: {
      const Vd q = s.R.transpose() * (x - s.c);
      const Vd ex = q.cwiseAbs() - s.e;
      const double out = ex.cwiseMax(0.0).norm();
      return out > 0.0 ? out : ex.maxCoeff();
    }
    case kLeafTriangle: {
      const Vd n = (s.v[1] - s.v[0]).cross(s.v[2] - s.v[0]).normalized();
      const Vd pr = x - n * n.dot(x - s.v[0]);
      bool inside = true;
      for (int k = 0; k < 3; ++k) {
        const Vd& a = s.v[k];
        const Vd& b = s.v[(k + 1) % 3];
        if ((b - a).cross(pr - a).dot(n) < 0.0) inside = false;
      }
      if (inside) return std::fabs(n.dot(x - s.v[0]));
      return std::min({seg_dist(x, s.v[0], s.v[1]), seg_dist(x, s.v[1], s.v[2]), seg_dist(x, s.v[2], s.v[0])});
    }
    case kLeafHalfSpace: return s.n.dot(x - s.c);
    default: ADD_FAILURE() << "no reference"; return 0.0;
  }
}

// Separation of a pair the reference covers: one side a sphere, or a plane against a box / capsule.
double separation(const PosedD& a, const PosedD& b) {
  if (a.type == kLeafSphere) return point_dist(b, a.c) - a.e[0];
  if (b.type == kLeafSphere) return point_dist(a, b.c) - b.e[0];
  const PosedD& h = a.type == kLeafHalfSpace ? a : b;
  const PosedD& o = a.type == kLeafHalfSpace ? b : a;
  double m = INFINITY;
  if (o.type == kLeafBox) {
    for (int k = 0; k < 8; ++k) {
      const Vd q = o.c + o.R * Vd((k & 1 ? 1 : -1) * o.e[0], (k & 2 ? 1 : -1) * o.e[1], (k & 4 ? 1 : -1) * o.e[2]);
      m = std::min(m, h.n.dot(q - h.c));
    }
  } else {  // capsule
    for (int k = -1; k <= 1; k += 2) m = std::min(m, h.n.dot(o.c + o.R.col(2) * (k * o.e[1]) - h.c) - o.e[0]);
  }
  return m;
}

struct RefToi {
  bool hit;
  double t_band;  // first time separation <= target
  double t_deep;  // first time separation <= target - tolerance (1 if never)
};

RefToi reference(const std::function<double(double)>& sep, double target, double tol) {
  constexpr int kSteps = 4096;
  auto first_below = [&](double level) {
    double prev = 0.0;
    if (sep(0.0) <= level) return 0.0;
    for (int i = 1; i <= kSteps; ++i) {
      const double t = double(i) / kSteps;
      if (sep(t) <= level) {
        double lo = prev, hi = t;
        for (int k = 0; k < 60; ++k) {
          const double mid = 0.5 * (lo + hi);
          (sep(mid) <= level ? hi : lo) = mid;
        }
        return hi;
      }
      prev = t;
    }
    return 2.0;
  };
  RefToi r;
  r.t_band = first_below(target);
  r.t_deep = first_below(target - tol);
  r.hit = r.t_band <= 1.0;
  return r;
}

Leaf sphere(Vd c, double r) {
  Leaf l;
  l.type = kLeafSphere;
  l.p = f3(c);
  l.e[0] = float(r);
  return l;
}
Leaf oriented(LeafType t, Vd c, const Md& R, Vd e) {
  Leaf l;
  l.type = t;
  l.p = f3(c);
  for (int k = 0; k < 3; ++k) l.ax[k] = f3(R.col(k));
  for (int k = 0; k < 3; ++k) l.e[k] = float(e[k]);
  return l;
}
Leaf triangle(Vd a, Vd b, Vd c) {
  Leaf l;
  l.type = kLeafTriangle;
  l.p = f3(a);
  l.v1 = f3(b);
  l.v2 = f3(c);
  return l;
}
Leaf half_space(Vd p, Vd n) {
  Leaf l;
  l.type = kLeafHalfSpace;
  l.p = f3(p);
  n.normalize();
  l.e[0] = float(n.x());
  l.e[1] = float(n.y());
  l.e[2] = float(n.z());
  return l;
}

// Checks the kernel against the reference for one pair; returns true on a hit.
bool check_pair(const Leaf& a, const Motion& ma, const Leaf& b, const Motion& mb, float target, float tol,
                const char* what) {
  const NarrowConfig cfg{};
  const ToiResult r = time_of_impact(a, ma, b, mb, target, tol, 64, cfg);
  auto sep = [&](double t) { return separation(pose_d(a, ma, t), pose_d(b, mb, t)); };
  const RefToi ref = reference(sep, target, tol);
  const double slack = 2e-5 * (1.0 + d3(ma.v).norm() + d3(mb.v).norm());
  EXPECT_NE(r.state, ToiResult::kFailed) << what;
  if (ref.t_deep == 0.0 || sep(0.0) <= 0.0) {
    EXPECT_EQ(r.state, ToiResult::kOverlapAtStart) << what << " sep0 " << sep(0.0);
    return true;
  }
  if (r.state == ToiResult::kOverlapAtStart) {
    ADD_FAILURE() << what << ": overlap at start, reference separation " << sep(0.0);
    return true;
  }
  if (r.state != ToiResult::kHit) {
    // A reference miss, or a graze that only dips into the band (never below
    // target - tol), may be reported as separated.
    EXPECT_GT(ref.t_deep, 1.0) << what << ": missed, t_ref " << ref.t_band;
    return false;
  }
  // A hit (also one the reference's band misses by a graze) lies in the band.
  const double s = sep(r.t);
  EXPECT_LE(s, target + tol + slack) << what << " t " << r.t << " t_ref " << ref.t_band;
  EXPECT_GE(s, target - tol - slack) << what << " t " << r.t << " t_ref " << ref.t_band;
  EXPECT_LE(r.t, ref.t_deep + 1e-6) << what;  // no tunnelling past target - tol
  EXPECT_NEAR(cvx::len(r.normal), 1.0f, 1e-4f) << what;
  return ref.hit;
}

Md random_rotation(std::mt19937& g) {
  std::normal_distribution<double> n(0.0, 1.0);
  Eigen::Quaterniond q(n(g), n(g), n(g), n(g));
  return q.normalized().toRotationMatrix();
}
Vd random_vec(std::mt19937& g, double s) {
  std::uniform_real_distribution<double> u(-s, s);
  return Vd(u(g), u(g), u(g));
}

TEST(TimeOfImpact, RandomSweptPairsMatchReference) {
  std::mt19937 g(41);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const int n = int(test::scaled(300, 50));
  int hits = 0;
  for (int i = 0; i < n; ++i) {
    for (int kind = 0; kind < 7; ++kind) {
      const Vd c = random_vec(g, 0.2);
      Leaf a = sphere(c, 0.05 + 0.3 * u(g));
      Motion ma, mb;
      Leaf b;
      switch (kind) {
        case 0: b = sphere(Vd(2, 0, 0) + random_vec(g, 0.5), 0.05 + 0.5 * u(g)); break;
        case 1: b = oriented(kLeafBox, Vd(2, 0, 0) + random_vec(g, 0.5), random_rotation(g), Vd(0.05 + u(g), 0.05 + u(g), 0.05 + u(g))); break;
        case 2: b = oriented(kLeafCapsule, Vd(2, 0, 0) + random_vec(g, 0.5), random_rotation(g), Vd(0.05 + 0.3 * u(g), 0.5 * u(g), 0)); break;
        case 3: b = triangle(Vd(2, -1, -1) + random_vec(g, 0.3), Vd(2, 1, -1) + random_vec(g, 0.3), Vd(2, 0, 1) + random_vec(g, 0.3)); break;
        case 4: b = half_space(Vd(2, 0, 0) + random_vec(g, 0.3), Vd(-1, 0, 0) + random_vec(g, 0.5)); break;
        case 5: a = oriented(kLeafBox, c, random_rotation(g), Vd(0.05 + 0.5 * u(g), 0.05 + 0.5 * u(g), 0.05 + 0.5 * u(g)));
                b = half_space(Vd(2, 0, 0) + random_vec(g, 0.3), Vd(-1, 0, 0) + random_vec(g, 0.5)); break;
        default: a = oriented(kLeafCapsule, c, random_rotation(g), Vd(0.05 + 0.3 * u(g), 0.6 * u(g), 0));
                 b = half_space(Vd(2, 0, 0) + random_vec(g, 0.3), Vd(-1, 0, 0) + random_vec(g, 0.5)); break;
      }
      ma.v = f3(Vd(3.0 * u(g), 0, 0) + random_vec(g, 1.0));
      if (kind >= 5 || u(g) < 0.5) ma.w = f3(random_vec(g, 3.0));
      if (kind < 4) {
        mb.v = f3(random_vec(g, 1.0));
        if (kind != 3 || u(g) < 0.5) mb.w = f3(random_vec(g, 3.0));
      }
      const bool swap = u(g) < 0.5;
      const std::string what = "case " + std::to_string(i) + " kind " + std::to_string(kind) + (swap ? " swapped" : "");
      hits += swap ? check_pair(b, mb, a, ma, 0.01f, 0.0025f, what.c_str())
                   : check_pair(a, ma, b, mb, 0.01f, 0.0025f, what.c_str());
    }
  }
  EXPECT_GT(hits, n);  // the set is not all misses
}

TEST(TimeOfImpact, AdversarialCases) {
  const Md I = Md::Identity();
  const Leaf box = oriented(kLeafBox, Vd(0, 0, 0), I, Vd(0.5, 0.5, 0.5));
  Motion still, toward, parallel;
  toward.v = V3{-2, 0, 0};
  parallel.v = V3{0, 2, 0};
  // Touching at t = 0 and overlapping: kOverlapAtStart.
  EXPECT_TRUE(check_pair(sphere(Vd(0.7, 0, 0), 0.2), toward, box, still, 0.01f, 0.0025f, "touching"));
  EXPECT_TRUE(check_pair(sphere(Vd(0.6, 0, 0), 0.2), toward, box, still, 0.01f, 0.0025f, "overlap"));
  EXPECT_TRUE(check_pair(sphere(Vd(0.7, 0, 0), 0.2), still, sphere(Vd(0.3, 0, 0), 0.2), still, 0.01f, 0.0025f, "spheres touching"));
  // Parallel motion at a constant gap: never hits.
  EXPECT_FALSE(check_pair(sphere(Vd(0.8, -3, 0), 0.2), parallel, box, still, 0.01f, 0.0025f, "parallel"));
  // Grazing: the sphere passes the box's edge at exactly target.
  EXPECT_TRUE(check_pair(sphere(Vd(3, 0.5 + 0.2 + 0.01, 0.0), 0.2), Motion{V3{-6, 0, 0}, V3{0, 0, 0}}, box, still,
                         0.01f, 0.0025f, "graze"));
  // Receding and short of reach: no hit.
  EXPECT_FALSE(check_pair(sphere(Vd(2, 0, 0), 0.2), Motion{V3{1, 0, 0}, V3{0, 0, 0}}, box, still, 0.01f, 0.0025f, "receding"));
  EXPECT_FALSE(check_pair(sphere(Vd(2, 0, 0), 0.2), Motion{V3{-1, 0, 0}, V3{0, 0, 0}}, box, still, 0.01f, 0.0025f, "short"));
  // Half-space against half-space: kFailed.
  const Leaf h = half_space(Vd(0, 0, 0), Vd(0, 1, 0));
  EXPECT_EQ(time_of_impact(h, still, h, still, 0.01f, 0.0025f, 64, NarrowConfig{}).state, ToiResult::kFailed);
}

// The bullet: a 0.1 m sphere at 1e4 m/s over dt = 1/60 s (167 m) into a 1 cm wall.
TEST(TimeOfImpact, BulletNeverTunnels) {
  std::mt19937 g(7);
  std::uniform_real_distribution<double> u(-4.0, 4.0);
  const Leaf wall = oriented(kLeafBox, Vd(0, 0, 0), Md::Identity(), Vd(0.005, 5, 5));
  const Leaf plane = half_space(Vd(0.005, 0, 0), Vd(-1, 0, 0));  // solid x >= -0.005... as seen from -x
  const Leaf tri = triangle(Vd(-0.005, -20, -20), Vd(-0.005, 20, -20), Vd(-0.005, 0, 40));
  const int n = int(test::scaled(10000, 10000));
  const float target = 0.01f, tol = 0.0025f;
  int misses = 0;
  for (int i = 0; i < n; ++i) {
    const Vd start(-100, u(g) * 20, u(g) * 20);
    const Vd aim(0, u(g), u(g));
    const Vd d = (aim - start).normalized() * (1e4 / 60.0);
    const Leaf s = sphere(start, 0.1);
    const Motion ms{f3(d), V3{0, 0, 0}};
    const Leaf* others[3] = {&wall, &plane, &tri};
    for (const Leaf* o : others) {
      Leaf other = *o;
      if (o == &plane) other = half_space(Vd(-0.005, 0, 0), Vd(-1, 0, 0));
      const ToiResult r = time_of_impact(s, ms, other, Motion{}, target, tol, 64, NarrowConfig{});
      const double x = start.x() + d.x() * r.t;  // centre at t
      const bool ok = r.state == ToiResult::kHit && x <= -0.005 - 0.1 - target + tol + 2e-3 &&
                      x >= -0.005 - 0.1 - target - tol - 2e-3;
      if (!ok && ++misses < 5)
        ADD_FAILURE() << "aim " << i << " type " << int(other.type) << " state " << int(r.state) << " x " << x;
    }
  }
  EXPECT_EQ(misses, 0);
}

// A 2 m x 0.02 m plank spinning at 100 rad/s (dt 1/60: 1.67 rad) next to a thin wall.
TEST(TimeOfImpact, SpinningPlankFindsWallBeforePassing) {
  const Md I = Md::Identity();
  Md R;
  R.col(0) = Vd(0, 1, 0);
  R.col(1) = Vd(-1, 0, 0);
  R.col(2) = Vd(0, 0, 1);
  const Leaf plank = oriented(kLeafBox, Vd(0, 0, 0), R, Vd(1.0, 0.01, 0.01));
  const Leaf wall = oriented(kLeafBox, Vd(0.8, 0, 0), I, Vd(0.005, 5, 5));
  const Motion spin{V3{0, 0, 0}, V3{0, 0, -100.0f / 60.0f}};
  const ToiResult r = time_of_impact(plank, spin, wall, Motion{}, 0.01f, 0.0025f, 64, NarrowConfig{});
  ASSERT_EQ(r.state, ToiResult::kHit);
  // Reference: the plank's corner x (double) against the wall's near face x = 0.795.
  auto sep = [&](double t) {
    const PosedD p = pose_d(plank, spin, t);
    double m = -INFINITY;
    for (int k = 0; k < 8; ++k)
      m = std::max(m, (p.c + p.R * Vd((k & 1 ? 1 : -1) * 1.0, (k & 2 ? 1 : -1) * 0.01, (k & 4 ? 1 : -1) * 0.01)).x());
    return 0.795 - m;
  };
  const RefToi ref = reference(sep, 0.01, 0.0025);
  ASSERT_TRUE(ref.hit);
  EXPECT_NEAR(sep(r.t), 0.01, 0.0025 + 1e-4) << r.t << " " << ref.t_band;
  EXPECT_LE(r.t, ref.t_deep);
  EXPECT_GT(r.iterations, 1u);
}

}  // namespace
}  // namespace impact::kernels::ccd
