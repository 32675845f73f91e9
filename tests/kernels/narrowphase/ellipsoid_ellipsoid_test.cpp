// collide_ellipsoid_ellipsoid (kernels/narrowphase/pairs/ellipsoid/ellipsoid_ellipsoid.cpp) on both paths
// against an independent double-precision reference.
//
// Reference (double, world frame): f(n) = sqrt(n^T M_A n) + sqrt(n^T M_B n) - n.d, M =
// R diag(e^2) R^T, d = c_B - c_A; depth = min over unit n of f. Dense Fibonacci sampling
// of the whole sphere (kSamples directions, no candidate directions from the kernel),
// then the kRefine least samples at least 0.03 rad apart are refined by Newton on the
// sphere with an exact eigenvalue shift and an Armijo backtracking line search until the
// step stalls; the least wins. Separated lanes need only a certificate f <= 0. Where
// the kernel's normal gives a lower f in double than the reference's minimum (the
// sampling missed a 1e-4-wide basin: a pancake's cone point), that value is the better
// minimum and the kernel's depth must match it; a kernel normal that scores worse than
// the reference fails.
//
// Per lane, L = the pair's largest radius, tol = kRel * L:
//  (a) count > 0 iff the reference depth > 0 (either where |depth_ref| <= tol);
//  (b) |depth - depth_ref| <= tol;
//  (c) n finite and unit; the reference's f at the kernel's n is within tol of depth_ref
//      (n is a minimiser), and angle(n, n_ref) <= kAngleTol where the minimiser is well
//      conditioned (no other local minimum within 10 tol, smallest Hessian eigenvalue
//      above 1e-2 L);
//  (d) point[0] midway: A's and B's support planes along n lie depth/2 either side of
//      it (within tol plus an ulp of the largest world coordinate); where both bodies'
//      smallest radius is at least 1e-2 L, point[0] +- n depth/2 also lie on the two
//      surfaces (1e-4 L); pdepth[0] == depth;
//  (e) the scalar and SIMD paths agree within tol (depth) and as minimisers (c).
// Scenarios: random poses and radii (ratios to 10, about half overlapping) at sizes 1,
// 1e-4, 1e4 and 1e5 from the origin; needles (1 x 1e-4 x 1e-4) and pancakes (1 x 1 x
// 1e-4) against each other and against round and random ellipsoids at random angles and
// at exactly parallel / perpendicular axes; coincident centres; deep; near touching
// (the reference's depth +-1e-3 L); spheres as ellipsoids (analytic sphere-sphere);
// swapped order (depth kept, normal flipped).
// Registration, range partitions, shuffled buckets and the agreement with GJK / EPA:
// contract_test.cpp (every bucket of the table).
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <numeric>
#include <random>
#include <vector>

#include "kernels/narrowphase/pair_kernels.h"
#include "support/leaf_lanes.h"
#include "support/random_input.h"
#include "support/test_support.h"

namespace impact::kernels {
namespace {

using Vec3d = Eigen::Vector3d;
using Mat3d = Eigen::Matrix3d;

constexpr double kRel = 1e-5;
constexpr double kAngleTol = 1e-3;
constexpr int kSamples = 6000;
constexpr int kRefine = 32;

double angle(const Vec3d& a, const Vec3d& b) { return std::atan2(a.cross(b).norm(), a.dot(b)); }

struct Ell {
  Vec3d p;
  Mat3d R;  // columns: the axes of e
  Vec3d e;
  Mat3d M() const { return R * e.cwiseProduct(e).asDiagonal() * R.transpose(); }
};

struct Query {
  Ell a, b;
};

Query rounded(Query q) {
  for (Ell* s : {&q.a, &q.b}) {
    s->p = test::round_to_float(s->p);
    s->R = test::round_to_float(s->R);
    s->e = test::round_to_float(s->e);
  }
  return q;
}

double largest(const Query& q) { return std::max(q.a.e.maxCoeff(), q.b.e.maxCoeff()); }

struct Hit {
  uint32_t count = 0;
  Vec3d n = Vec3d::Zero(), pt = Vec3d::Zero();
  double depth = 0, pd = 0;
};

/// The raw output bytes of one lane (for byte-equality checks).
struct Bytes {
  uint8_t count;
  float v[8];
  bool operator==(const Bytes& o) const { return count == o.count && std::memcmp(v, o.v, sizeof v) == 0; }
};

struct Output {
  std::vector<Hit> hits;
  std::vector<Bytes> bytes;
};

Output run(const std::vector<Query>& qs, KernelPath path, PairKernel kern, uint32_t begin = 0,
           uint32_t end = ~0u) {
  const size_t n = qs.size();
  end = std::min<uint32_t>(end, static_cast<uint32_t>(n));
  std::vector<float> p[2][3], r[2][9], e[2][3];
  for (const Query& q : qs) {
    const Ell* s[2] = {&q.a, &q.b};
    for (int k = 0; k < 2; ++k) {
      for (int i = 0; i < 3; ++i) {
        p[k][i].push_back(float(s[k]->p[i]));
        e[k][i].push_back(float(s[k]->e[i]));
      }
      for (int i = 0; i < 9; ++i) r[k][i].push_back(float(s[k]->R(i / 3, i % 3)));
    }
  }
  LeafSoA soa[2]{};
  for (int k = 0; k < 2; ++k) {
    for (int i = 0; i < 3; ++i) soa[k].p[i] = p[k][i].data(), soa[k].e[i] = e[k][i].data();
    for (int i = 0; i < 9; ++i) soa[k].r[i] = r[k][i].data();
  }
  test::ManifoldLanes o(static_cast<uint32_t>(n));
  NarrowConfig cfg;
  cfg.path = path;
  kern(soa[0], soa[1], o.view(), Range{begin, end}, cfg);
  Output out;
  out.hits.resize(n);
  out.bytes.resize(n);
  for (uint32_t k = begin; k < end; ++k) {
    const test::PairResult res = o.result(k);
    Hit& h = out.hits[k];
    h.count = res.count;
    Bytes& b = out.bytes[k];
    std::memset(&b, 0, sizeof b);
    b.count = o.count[k];
    if (h.count == 0) continue;
    h.n = res.n;
    h.pt = res.pt[0];
    h.depth = res.depth;
    h.pd = res.pd[0];
    const float v[8] = {o.n[0][k], o.n[1][k], o.n[2][k], o.depth[k], o.pt[0][0][k], o.pt[0][1][k], o.pt[0][2][k],
                        o.pd[0][k]};
    std::memcpy(b.v, v, sizeof v);
  }
  return out;
}

Output run(const std::vector<Query>& qs, KernelPath path) { return run(qs, path, &collide_ellipsoid_ellipsoid); }

// ---------------------------------------------------------------------------------------
// Reference
// ---------------------------------------------------------------------------------------

struct Problem {
  Mat3d ma, mb;
  Vec3d d;
  double f(const Vec3d& n) const {
    return std::sqrt(std::max(n.dot(ma * n), 0.0)) + std::sqrt(std::max(n.dot(mb * n), 0.0)) - n.dot(d);
  }
};

Problem problem(const Query& q) { return {q.a.M(), q.b.M(), q.b.p - q.a.p}; }

struct Ref {
  double depth;
  Vec3d n;
  double second;  // the least other local minimum (> 0.03 rad away), or +inf
  double hmin;    // smallest eigenvalue of the Riemannian Hessian at n
};

/// Tangent basis, gradient and Hessian of f on the sphere at unit n.
void derivatives(const Problem& p, const Vec3d& n, Vec3d* t1, Vec3d* t2, Eigen::Vector2d* g,
                 Eigen::Matrix2d* h) {
  const Vec3d w = std::abs(n.x()) < 0.6 ? Vec3d::UnitX() : (std::abs(n.y()) < 0.6 ? Vec3d::UnitY() : Vec3d::UnitZ());
  *t1 = n.cross(w).normalized();
  *t2 = n.cross(*t1);
  const Vec3d wa = p.ma * n, wb = p.mb * n;
  const double qa = std::sqrt(n.dot(wa)), qb = std::sqrt(n.dot(wb));
  const Vec3d grad = wa / qa + wb / qb - p.d;
  const Mat3d hess = (p.ma - wa * wa.transpose() / (qa * qa)) / qa + (p.mb - wb * wb.transpose() / (qb * qb)) / qb;
  const double f = p.f(n);
  const Vec3d t[2] = {*t1, *t2};
  for (int i = 0; i < 2; ++i) {
    (*g)[i] = t[i].dot(grad);
    for (int j = 0; j < 2; ++j) (*h)(i, j) = t[i].dot(hess * t[j]) - (i == j ? f : 0.0);
  }
}

/// The smaller eigenvalue of a symmetric 2x2.
double min_eigenvalue(const Eigen::Matrix2d& h) {
  const double m = 0.5 * (h(0, 0) + h(1, 1)), r = std::hypot(0.5 * (h(0, 0) - h(1, 1)), h(0, 1));
  return m - r;
}

Vec3d refine(const Problem& p, Vec3d n) {
  for (int it = 0; it < 300; ++it) {
    Vec3d t1, t2;
    Eigen::Vector2d g;
    Eigen::Matrix2d h;
    derivatives(p, n, &t1, &t2, &g, &h);
    const double lmin = min_eigenvalue(h), lmax = std::max(std::abs(h(0, 0)) + std::abs(h(1, 1)), 1e-300);
    const double shift = std::max(0.0, -lmin + 1e-9 * lmax);
    const double k00 = h(0, 0) + shift, k11 = h(1, 1) + shift, k01 = h(0, 1);
    const double det = k00 * k11 - k01 * k01;
    Eigen::Vector2d s(-(k11 * g[0] - k01 * g[1]) / det, -(k00 * g[1] - k01 * g[0]) / det);
    if (!(s.norm() < 1.0)) s *= 1.0 / s.norm();
    const double f0 = p.f(n);
    double alpha = 1.0;
    bool moved = false;
    for (int ls = 0; ls < 60; ++ls) {
      const Vec3d m = (n + alpha * (s[0] * t1 + s[1] * t2)).normalized();
      if (p.f(m) <= f0 + 1e-4 * alpha * g.dot(s)) {
        moved = (m - n).norm() > 0;
        n = m;
        break;
      }
      alpha *= 0.5;
    }
    if (!moved || alpha * s.norm() < 1e-15) break;
  }
  return n;
}

Ref reference(const Query& q) {
  const Problem p = problem(q);
  struct S {
    double f;
    Vec3d n;
  };
  std::vector<S> s(kSamples);
  const double golden = M_PI * (3.0 - std::sqrt(5.0));
  for (int i = 0; i < kSamples; ++i) {
    const double z = 1.0 - (2.0 * i + 1.0) / kSamples, r = std::sqrt(1.0 - z * z), phi = golden * i;
    s[i].n = Vec3d(r * std::cos(phi), r * std::sin(phi), z);
    s[i].f = p.f(s[i].n);
  }
  std::sort(s.begin(), s.end(), [](const S& a, const S& b) { return a.f < b.f; });
  std::vector<Vec3d> starts;
  for (const S& x : s) {
    bool far = true;
    for (const Vec3d& y : starts) far = far && angle(x.n, y) > 0.03;
    if (far) starts.push_back(x.n);
    if (static_cast<int>(starts.size()) == kRefine) break;
  }
  std::vector<S> mins;
  for (const Vec3d& st : starts) {
    const Vec3d n = refine(p, st);
    mins.push_back({p.f(n), n});
  }
  std::sort(mins.begin(), mins.end(), [](const S& a, const S& b) { return a.f < b.f; });
  Ref r;
  r.depth = mins[0].f;
  r.n = mins[0].n;
  r.second = INFINITY;
  for (size_t i = 1; i < mins.size(); ++i)
    if (angle(mins[i].n, r.n) > 0.03) r.second = std::min(r.second, mins[i].f);
  Vec3d t1, t2;
  Eigen::Vector2d g;
  Eigen::Matrix2d h;
  derivatives(p, r.n, &t1, &t2, &g, &h);
  r.hmin = min_eigenvalue(h);
  return r;
}

/// Signed distance estimate of world w to the ellipsoid's surface: (|y / e| - 1) /
/// |grad| for the level function |y / e| (first order; exact on the surface).
double surface_gap(const Ell& s, const Vec3d& w) {
  const Vec3d y = s.R.transpose() * (w - s.p);
  const Vec3d u = y.cwiseQuotient(s.e);
  const double r = u.norm();
  if (r == 0) return -s.e.minCoeff();
  const Vec3d grad = u.cwiseQuotient(s.e) / r;
  return (r - 1.0) / grad.norm();
}

// ---------------------------------------------------------------------------------------
// Scenarios
// ---------------------------------------------------------------------------------------

Ell random_ell(std::mt19937& g, double size, double min_ratio) {
  std::uniform_real_distribution<double> u(min_ratio, 1.0);
  Ell s;
  s.p = Vec3d::Zero();
  s.R = test::random_rotation(g);
  s.e = Vec3d(u(g), u(g), u(g)) * size;
  return s;
}

Vec3d random_unit(std::mt19937& g) {
  std::normal_distribution<double> n;
  for (;;) {
    const Vec3d v(n(g), n(g), n(g));
    if (v.norm() > 1e-3) return v.normalized();
  }
}

/// B placed at a random direction and distance in [0, spread] x (the bounding radii sum).
Query place(std::mt19937& g, Ell a, Ell b, double spread, const Vec3d& origin) {
  std::uniform_real_distribution<double> u(0.0, spread);
  a.p = origin;
  b.p = origin + random_unit(g) * u(g) * (a.e.maxCoeff() + b.e.maxCoeff());
  return rounded(Query{a, b});
}

Ell shaped(std::mt19937& g, int kind, double size) {
  Ell s;
  s.p = Vec3d::Zero();
  s.R = test::random_rotation(g);
  switch (kind) {
    case 0: s.e = Vec3d(1, 1e-4, 1e-4); break;         // needle
    case 1: s.e = Vec3d(1, 1, 1e-4); break;            // pancake
    case 2: s.e = Vec3d(1, 1e-2, 3e-1); break;         // slab
    case 3: s.e = Vec3d(0.5, 0.5, 0.5); break;         // round
    default: return random_ell(g, size, 0.05);
  }
  s.e *= size;
  return s;
}

std::vector<Query> random_queries(uint32_t n, uint32_t seed, double size, const Vec3d& origin) {
  std::mt19937 g(seed);
  std::vector<Query> qs;
  for (uint32_t i = 0; i < n; ++i) qs.push_back(place(g, random_ell(g, size, 0.1), random_ell(g, size, 0.1), 1.0, origin));
  return qs;
}

std::vector<Query> thin_queries(uint32_t n, uint32_t seed) {
  std::mt19937 g(seed);
  std::vector<Query> qs;
  std::uniform_int_distribution<int> kind(0, 4);
  for (uint32_t i = 0; i < n; ++i) {
    Ell a = shaped(g, kind(g), 1.0), b = shaped(g, kind(g), 1.0);
    if (i % 4 == 1) b.R = a.R;  // parallel axes
    if (i % 4 == 2) {            // perpendicular: B's axes a permutation of A's
      b.R.col(0) = a.R.col(1);
      b.R.col(1) = a.R.col(2);
      b.R.col(2) = a.R.col(0);
    }
    qs.push_back(place(g, a, b, i % 3 == 0 ? 0.05 : 0.8, Vec3d::Zero()));
  }
  return qs;
}

struct Checked {
  int overlaps = 0, lanes = 0;
};

/// (a)-(e) on every lane.
void check(const std::vector<Query>& qs, const char* what, Checked* out = nullptr, double rel = kRel) {
  const Output simd = run(qs, KernelPath::kSimd), scalar = run(qs, KernelPath::kScalar);
  Checked dummy;
  Checked& c = out ? *out : dummy;
  for (size_t k = 0; k < qs.size(); ++k) {
    const Query& q = qs[k];
    const double L = largest(q), tol = rel * L;
    const Ref ref = reference(q);
    const Problem p = problem(q);
    ++c.lanes;
    c.overlaps += ref.depth > 0;
    for (const Output* o : {&simd, &scalar}) {
      const Hit& h = o->hits[k];
      const char* path = o == &simd ? "simd" : "scalar";
      if (std::abs(ref.depth) > tol) {
        ASSERT_EQ(h.count > 0, ref.depth > 0) << what << " lane " << k << " " << path << " ref " << ref.depth / L;
      }
      if (h.count == 0) continue;
      ASSERT_EQ(h.count, 1u);
      // The reference is a sampled search: where the kernel's own normal gives a lower f
      // (evaluated in double), that is the better minimum (the kernel's depth must then
      // match it); a kernel normal worse than the reference's fails below.
      const double fk = p.f(h.n.normalized());
      const double best = std::min(ref.depth, fk);
      EXPECT_NEAR(h.depth, best, tol) << what << " lane " << k << " " << path << " L " << L << " excess "
                                      << (h.depth - ref.depth) / L << "\n ea " << q.a.e.transpose() << " eb "
                                      << q.b.e.transpose() << "\n nref(A) " << (q.a.R.transpose() * ref.n).transpose()
                                      << " nref(B) " << (q.b.R.transpose() * ref.n).transpose() << "\n n(A) "
                                      << (q.a.R.transpose() * h.n).transpose() << " second " << ref.second;
      ASSERT_TRUE(h.n.allFinite());
      EXPECT_NEAR(h.n.norm(), 1.0, 1e-5);
      EXPECT_LE(fk, ref.depth + tol) << what << " lane " << k << " " << path;
      // The reference's `second` (its least other minimum, > 0.03 rad away) comes from
      // sampling; f at the kernel's normal, in double, bounds the values there too where
      // that normal is as far (at IMPACT_TEST_INTENSITY=30 a thin pair's kernel normal
      // 1.27 rad from the reference's had f within tol of the minimum: not unique).
      const double second = angle(h.n, ref.n) > 0.03 ? std::min(ref.second, fk) : ref.second;
      if (fk >= ref.depth - tol && second > ref.depth + 10 * tol && ref.hmin > 1e-2 * L) {
        EXPECT_LT(angle(h.n, ref.n), kAngleTol) << what << " lane " << k << " " << path;
      }
      EXPECT_EQ(h.pd, h.depth);
      const double ulp = 2.0 * std::ldexp(1.0, std::ilogb(std::max(1e-30, q.a.p.cwiseAbs().maxCoeff())) - 23);
      const double ptol = 1e-4 * L + ulp;
      // Midway along n: the support planes of A and B along the kernel's n are depth / 2
      // either side of the point.
      const Vec3d nn = h.n.normalized();
      const double ha = std::sqrt(nn.dot(p.ma * nn)), hb = std::sqrt(nn.dot(p.mb * nn));
      EXPECT_NEAR(nn.dot(h.pt - q.a.p) - ha, -h.depth / 2, tol + ulp) << what << " lane " << k << " " << path;
      EXPECT_NEAR(nn.dot(h.pt - q.b.p) + hb, h.depth / 2, tol + ulp) << what << " lane " << k << " " << path;
      // On the surfaces (where the support points are well conditioned: the tangential
      // offset of a support point grows like L / (smallest radius) per radian of n).
      if (std::min(q.a.e.minCoeff(), q.b.e.minCoeff()) >= 1e-2 * L) {
        EXPECT_NEAR(surface_gap(q.a, h.pt + h.n * (h.depth / 2)), 0.0, ptol) << what << " lane " << k << " " << path;
        EXPECT_NEAR(surface_gap(q.b, h.pt - h.n * (h.depth / 2)), 0.0, ptol) << what << " lane " << k << " " << path;
      }
    }
    if (simd.hits[k].count > 0 && scalar.hits[k].count > 0) {
      EXPECT_NEAR(simd.hits[k].depth, scalar.hits[k].depth, tol) << what << " lane " << k;
    }
  }
}

uint32_t lanes(uint32_t base) { return test::scaled(base, 8); }

TEST(EllipsoidEllipsoid, RandomPosesAgainstReference) {
  Checked c;
  check(random_queries(lanes(600), 11, 1.0, Vec3d::Zero()), "random", &c);
  EXPECT_GT(c.overlaps, c.lanes / 4);
  EXPECT_LT(c.overlaps, 3 * c.lanes / 4);
}

TEST(EllipsoidEllipsoid, SizesAndFarPoses) {
  check(random_queries(lanes(120), 12, 1e-4, Vec3d::Zero()), "tiny");
  check(random_queries(lanes(120), 13, 1e4, Vec3d::Zero()), "huge");
  check(random_queries(lanes(120), 14, 1.0, Vec3d(1e5, -1e5, 1e5)), "far");
}

TEST(EllipsoidEllipsoid, NeedlesPancakesAtAllAngles) {
  Checked c;
  check(thin_queries(lanes(800), 21), "thin", &c);
  EXPECT_GT(c.overlaps, c.lanes / 4);
}

TEST(EllipsoidEllipsoid, CoincidentCentresAndDeep) {
  std::mt19937 g(31);
  std::vector<Query> qs;
  std::uniform_int_distribution<int> kind(0, 4);
  for (uint32_t i = 0; i < lanes(200); ++i) {
    Query q{shaped(g, kind(g), 1.0), shaped(g, kind(g), 1.0)};
    q.a.p = q.b.p = Vec3d(1, 2, 3);
    if (i % 2) q.b.p += random_unit(g) * 1e-3;
    qs.push_back(rounded(q));
  }
  check(qs, "coincident");
  // Coincident centres: depth = min over n of h_A(n) + h_B(n); axis-aligned boxes of
  // radii: the least combined axis.
  Ell a{Vec3d::Zero(), Mat3d::Identity(), Vec3d(3, 2, 0.5)}, b{Vec3d::Zero(), Mat3d::Identity(), Vec3d(1, 0.25, 4)};
  const Output o = run({Query{a, b}}, KernelPath::kSimd);
  ASSERT_EQ(o.hits[0].count, 1u);
  EXPECT_NEAR(o.hits[0].depth, 2.25, 1e-5 * 4);
  EXPECT_NEAR(std::abs(o.hits[0].n.y()), 1.0, 1e-6);
}

TEST(EllipsoidEllipsoid, SpheresMatchSphereSphere) {
  std::mt19937 g(41);
  std::uniform_real_distribution<double> u(0.1, 2.0);
  std::vector<Query> qs;
  for (uint32_t i = 0; i < lanes(200); ++i) {
    const double ra = u(g), rb = u(g);
    Query q{Ell{Vec3d::Zero(), test::random_rotation(g), Vec3d::Constant(ra)},
            Ell{random_unit(g) * (ra + rb) * u(g) / 2.0, test::random_rotation(g), Vec3d::Constant(rb)}};
    qs.push_back(rounded(q));
  }
  const Output o = run(qs, KernelPath::kSimd);
  for (size_t k = 0; k < qs.size(); ++k) {
    const Vec3d d = qs[k].b.p - qs[k].a.p;
    const double depth = qs[k].a.e[0] + qs[k].b.e[0] - d.norm(), L = largest(qs[k]);
    if (std::abs(depth) < kRel * L) continue;
    ASSERT_EQ(o.hits[k].count > 0, depth > 0) << k;
    if (depth <= 0) continue;
    EXPECT_NEAR(o.hits[k].depth, depth, kRel * L) << k;
    if (d.norm() > 1e-3 * L) {
      EXPECT_LT(angle(o.hits[k].n, d), 1e-4) << k;
    }
  }
}

TEST(EllipsoidEllipsoid, NearTouching) {
  // B moved along the reference normal so that the reference depth is +-1e-3 L.
  std::mt19937 g(51);
  std::vector<Query> qs;
  std::uniform_int_distribution<int> kind(0, 4);
  for (uint32_t i = 0; i < lanes(60); ++i) {
    Query q = place(g, shaped(g, kind(g), 1.0), shaped(g, kind(g), 1.0), 0.6, Vec3d::Zero());
    for (int it = 0; it < 3; ++it) {
      const Ref r = reference(q);
      if (r.depth <= 0) break;
      q.b.p += r.n * (r.depth - (i % 2 ? 1e-3 : -1e-3) * largest(q));
      q = rounded(q);
    }
    qs.push_back(q);
  }
  check(qs, "touching");
}

TEST(EllipsoidEllipsoid, SwappedOrderFlipsNormal) {
  std::vector<Query> qs = random_queries(lanes(200), 61, 1.0, Vec3d::Zero());
  std::vector<Query> sw;
  for (const Query& q : qs) sw.push_back(Query{q.b, q.a});
  const Output o = run(qs, KernelPath::kSimd), s = run(sw, KernelPath::kSimd);
  for (size_t k = 0; k < qs.size(); ++k) {
    const double tol = kRel * largest(qs[k]);
    const Ref ref = reference(qs[k]);
    if (std::abs(ref.depth) <= tol) continue;
    ASSERT_EQ(o.hits[k].count, s.hits[k].count) << k;
    if (o.hits[k].count == 0) continue;
    EXPECT_NEAR(o.hits[k].depth, s.hits[k].depth, 2 * tol) << k;
    if (ref.second > ref.depth + 10 * tol && ref.hmin > 1e-2 * largest(qs[k])) {
      EXPECT_LT(angle(o.hits[k].n, -s.hits[k].n), kAngleTol) << k;
    }
  }
}

}  // namespace
}  // namespace impact::kernels
