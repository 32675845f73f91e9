// collide_convex_cylinder (kernels/narrowphase/pairs/convex/convex_cylinder.cpp) on both paths against an
// independent double-precision reference.
//
// Reference (double, the inputs as the kernel sees them, no candidate enumeration): the
// support overlap h_A(n) + h_B(-n) minimised over densely sampled directions and refined by
// Nelder-Mead (tests/support/narrow_reference.h, more samples and starts than its default):
// depth (> 0) or minus the distance, and the normal. Points are checked against the solids
// in closed form: the cylinder's radial and axial excess (its axis as the reference reads
// it, R's column 2), the hull's face planes (Newell normals of the posed vertices, each
// plane through the face's outermost vertex). Built scenarios are checked against their
// construction first: the overlap along the built normal is the built depth, and apart
// pairs built from their closest features are apart by exactly the built distance.
// Per lane, L = the larger bounding radius, tol = kRel L plus the offset term of the
// ellipsoid test (1e-8 of the hull position's 1-norm); points within tol plus 4 float ulps
// of the largest coordinate:
//  (a) count > 0 iff the reference depth > 0 (either where |depth_ref| <= tol);
//  (b) |depth - depth_ref| <= tol;
//  (c) n finite and unit; the reference overlap along n <= depth_ref + tol (a safe
//      displacement); angle(n, n_ref) <= kAngleTol where the minimum is unique (every
//      direction 0.02 rad from n_ref overlaps by more than depth_ref + 10 kRel L: the
//      ellipsoid test's rule less the offset term, so far lanes are checked too), or up to
//      10 kAngleTol where n is as good as n_ref up to the overlap's float rounding;
//  (d) 1 <= count <= 4, every value finite; each pdepth in (0, depth + tol]; each point
//      - n pdepth/2 in the cylinder and point + n pdepth/2 in the hull; the deepest pdepth
//      within tol of depth, plus the margin by which contact_manifold lets clipped points
//      stand for it (cvx::kWitnessJoin of depth + both leaf sizes, face_manifold.h);
//  (e) the scalar and SIMD paths agree: the count away from touching, depth within tol,
//      the normal within kAngleTol (or both as good as the reference's) (not their
//      bytes: the shared helpers' multiply-adds fuse differently at the two widths);
// Scenarios: random poses (about half meeting) at sizes 1, 1e-4, 1e4 and 1e5 from the
// origin, with point-cloud hulls (8-40 points, and the bench's 24), boxes and flat hulls;
// built in the cylinder's frame and posed at random: a hull face resting on a cap
// (parallel, shallow: a multi-point manifold), a face against the side (the side line
// clipped: 2 points), an edge parallel to the axis against the side, a vertex pushed into
// the side, an edge across a rim (apart and meeting), a vertex just inside near a rim, a
// vertex off a rim (apart, count 0); deep pairs and coincident centres; needle (radius 1e-3
// of the length) and pancake (half length 1e-3 of the radius) cylinders; flat hulls (1e-3
// thick boxes); hulls the kernel leaves to GJK / EPA (open faces, so no edge adjacency;
// 400 vertices; a view without adjacency): the same bytes as GJK / EPA.
// Registration, range partitions, shuffled buckets and the agreement with GJK / EPA:
// contract_test.cpp (every bucket of the table).
// Sizes scale with IMPACT_TEST_INTENSITY (about 2.5 s at 1 in a Release build).
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

#include "kernels/narrowphase/general/face_manifold.h"
#include "kernels/narrowphase/general/gjk_epa.h"
#include "kernels/narrowphase/pair_kernels.h"
#include "support/hull_input.h"
#include "support/leaf_lanes.h"
#include "support/narrow_reference.h"
#include "support/test_support.h"

namespace impact::kernels {
namespace {

using Vec3d = Eigen::Vector3d;
using Mat3d = Eigen::Matrix3d;
namespace nref = test::nref;
namespace hi = test::hull_input;

constexpr double kRel = 1e-5;
constexpr double kAngleTol = 1e-4;
/// A few float ulps of the overlap at size L (4 x 2^-24): its evaluation's rounding.
constexpr double kRoundingSlack = 2.4e-7;

void gjk_kernel(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, Range r,
                const NarrowConfig& cfg) {
  collide_gjk_epa(a, b, out, r, cfg, kLeafConvex, kLeafCylinder);
}

/// The kernel under test.
PairKernel under_test() {
  return &collide_convex_cylinder;
}

struct Side {
  Vec3d p = Vec3d::Zero();
  Mat3d R = Mat3d::Identity();
  Vec3d e = Vec3d::Zero();
  uint32_t hull = 0;
};

/// One bucket: hulls (A), cylinders (B), and per lane what its construction promises:
/// the overlap d_built along the unit n_built (zero: nothing built); exact: apart and
/// built from its closest features (depth_ref = d_built).
struct Case {
  std::vector<Side> a, b;
  std::vector<Vec3d> n_built;
  std::vector<double> d_built;
  std::vector<char> exact;
  void add(const Side& ha, const Side& cb, const Vec3d& n = Vec3d::Zero(), double d = 0, bool ex = false) {
    a.push_back(ha);
    b.push_back(cb);
    n_built.push_back(n);
    d_built.push_back(d);
    exact.push_back(ex);
  }
  uint32_t size() const { return static_cast<uint32_t>(a.size()); }
};

Vec3d rounded(const Vec3d& v) {
  return test::round_to_float(v);
}

struct Lanes {
  test::LeafLanes la, lb;
  test::ManifoldLanes out;
  explicit Lanes(const Case& c) : out(c.size()) {
    for (const auto& s : c.a) la.push(s);
    for (const auto& s : c.b) lb.push(s);
  }
  void go(PairKernel k, const HullView& hv, KernelPath path, Range r) {
    NarrowConfig cfg;
    cfg.hulls = hv;
    cfg.path = path;
    k(la.soa(), lb.soa(), out.view(), r, cfg);
  }
  uint32_t n() const { return static_cast<uint32_t>(la.ref.size()); }
};

/// Lane k's bytes in x equal lane j's in y (count, and the written slots).
bool same_bytes(const test::ManifoldLanes& x, uint32_t k, const test::ManifoldLanes& y, uint32_t j) {
  if (x.count[k] != y.count[j]) return false;
  const uint32_t c = std::min<uint32_t>(x.count[k], 4u);
  if (c == 0) return true;
  auto eq = [](float u, float v) { return std::memcmp(&u, &v, sizeof u) == 0; };
  bool same = eq(x.depth[k], y.depth[j]);
  for (int i = 0; i < 3; ++i) same = same && eq(x.n[i][k], y.n[i][j]);
  for (uint32_t s = 0; s < c; ++s) {
    same = same && eq(x.pd[s][k], y.pd[s][j]);
    for (int i = 0; i < 3; ++i) same = same && eq(x.pt[s][i][k], y.pt[s][i][j]);
  }
  return same;
}

// --- the reference -------------------------------------------------------------------------

/// Lane k as the kernel sees it, in double, and its reference collision data.
struct Ref {
  nref::Shape sa, sb;
  nref::PairResult r;
  double L = 0, tol = 0, ptol = 0;
  double scale = 0;  // leaf_size(A) + leaf_size(B) of support.h: the hull's largest local
                     // 1-norm, the cylinder's radius + half length
  Vec3d pa, pb, u;
  double rc = 0, h = 0;
  uint32_t hull = 0;
  std::vector<Vec3d> fn;  // the hull's face planes, relative to pa
  std::vector<double> fd;

  /// The minimum is unique (kRel L without the offset term: far from the origin too).
  bool unique() const { return r.unique(10 * kRel * L) && r.s > tol; }
  double overlap(const Vec3d& n) const {
    return nref::overlap(sa, sb, nref::normalized(nref::V3{n.x(), n.y(), n.z()}));
  }
  /// > 0 outside the cylinder (the distance), < 0 inside (minus the distance to the boundary).
  double cyl_sd(const Vec3d& x) const {
    const Vec3d l = x - pb;
    const double ax = l.dot(u), rad = (l - ax * u).norm();
    const double dr = rad - rc, dz = std::fabs(ax) - h;
    if (dr <= 0 && dz <= 0) return std::max(dr, dz);
    return std::hypot(std::max(dr, 0.0), std::max(dz, 0.0));
  }
  /// The largest face plane excess: <= 0 inside the hull, at most the distance outside.
  double hull_sd(const Vec3d& x) const {
    const Vec3d y = x - pa;
    double m = -1e300;
    for (size_t f = 0; f < fn.size(); ++f) m = std::max(m, fn[f].dot(y) - fd[f]);
    return m;
  }
};

Ref reference(const Lanes& run, const hi::Hulls& hulls, uint32_t k) {
  const HullView hv = hulls.store.view();
  const LeafSoA a = run.la.soa(), b = run.lb.soa();
  Ref f;
  f.sa = nref::shape_from_leaf(a, k, kLeafConvex, &hv);
  f.sb = nref::shape_from_leaf(b, k, kLeafCylinder);
  nref::Options opt;
  opt.samples = 6000;
  opt.starts = 8;
  f.r = nref::solve_pair(f.sa, f.sb, {}, opt);
  f.L = std::max(f.sa.bound_radius(), f.sb.bound_radius());
  f.pa = Vec3d(a.p[0][k], a.p[1][k], a.p[2][k]);
  f.pb = Vec3d(b.p[0][k], b.p[1][k], b.p[2][k]);
  f.u = Vec3d(b.r[2][k], b.r[5][k], b.r[8][k]);
  f.rc = b.e[0][k];
  f.h = b.e[1][k];
  f.hull = a.ref[k];
  f.tol = kRel * f.L + 1e-8 * f.pa.lpNorm<1>();
  f.ptol = f.tol + 4 * std::ldexp(1.0, -23) *
                       (std::max(f.pa.lpNorm<Eigen::Infinity>(), f.pb.lpNorm<Eigen::Infinity>()) + 2 * f.L);
  Mat3d R;
  for (int i = 0; i < 9; ++i) R(i / 3, i % 3) = a.r[i][k];
  const HullData& hd = hulls.data[a.ref[k]];
  std::vector<Vec3d> w;
  double l1 = 0;
  for (const auto& v : hd.vertices) {
    w.push_back(R * v.cast<double>());
    l1 = std::max(l1, static_cast<double>(v.cwiseAbs().sum()));
  }
  f.scale = l1 + f.rc + f.h;
  for (const auto& face : hd.faces) {
    Vec3d nn = Vec3d::Zero();
    for (size_t i = 0; i < face.size(); ++i) nn += w[face[i]].cross(w[face[(i + 1) % face.size()]]);
    nn.normalize();
    double d = -1e300;
    for (uint32_t i : face) d = std::max(d, nn.dot(w[i]));
    f.fn.push_back(nn);
    f.fd.push_back(d);
  }
  return f;
}

// --- the per-lane checks -------------------------------------------------------------------

struct Stats {
  int lanes = 0, hits = 0, unique = 0;
  int counts[5] = {0, 0, 0, 0, 0};
  double worst_depth = 0, worst_angle = 0;
};

/// Whether n (unit) is within kAngleTol of the reference's normal, or within 10 kAngleTol
/// and as good a direction up to the overlap's float rounding (kRoundingSlack L).
bool normal_ok(const Ref& f, const Vec3d& n, double* ang) {
  *ang = nref::angle({n.x(), n.y(), n.z()}, f.r.n);
  const bool as_good = f.overlap(n) <= f.r.s + kRoundingSlack * f.L;
  return *ang <= kAngleTol || (as_good && *ang <= 10 * kAngleTol);
}

/// (a)-(d) for one path's answer on lane k.
void check_lane(const Ref& f, const test::PairResult& got, uint32_t k, const char* path, Stats* st) {
  SCOPED_TRACE(::testing::Message() << path << " lane " << k << " hull " << f.hull << " depth_ref " << f.r.s
                                    << " count " << got.count << " depth " << got.depth << " L " << f.L);
  ASSERT_LE(got.count, 4u);
  if (std::fabs(f.r.s) > f.tol) {
    EXPECT_EQ(got.count > 0, f.r.s > 0);
  }
  if (got.count == 0) return;
  ASSERT_TRUE(std::isfinite(got.depth) && got.n.allFinite());
  if (st != nullptr) ++st->hits, ++st->counts[got.count];
  const Vec3d n = got.n;
  EXPECT_NEAR(n.norm(), 1.0, 1e-5);
  const double dd = std::fabs(got.depth - f.r.s);
  if (st != nullptr) st->worst_depth = std::max(st->worst_depth, dd / f.L);
  EXPECT_LE(dd, f.tol);
  EXPECT_LE(f.overlap(n), f.r.s + f.tol);
  if (f.unique()) {
    double ang = 0;
    EXPECT_TRUE(normal_ok(f, n, &ang)) << "angle " << ang << " n " << n.transpose();
    if (st != nullptr) ++st->unique, st->worst_angle = std::max(st->worst_angle, ang);
  }
  // (d) the manifold
  double deepest = 0;
  for (uint32_t i = 0; i < got.count; ++i) {
    const Vec3d& p = got.pt[i];
    const double pd = got.pd[i];
    ASSERT_TRUE(p.allFinite() && std::isfinite(pd)) << "point " << i;
    EXPECT_GT(pd, 0.0) << "point " << i;
    EXPECT_LE(pd, got.depth + f.tol) << "point " << i;
    deepest = std::max(deepest, pd);
    EXPECT_LE(f.cyl_sd(p - 0.5 * pd * n), f.ptol) << "point " << i << " off the cylinder";
    EXPECT_LE(f.hull_sd(p + 0.5 * pd * n), f.ptol) << "point " << i << " off the hull";
  }
  const double join = cvx::kWitnessJoin * (got.depth + f.scale);
  EXPECT_GE(deepest, got.depth - f.tol - join) << "no point carries the depth";
}

/// (e): the scalar path's answer against the SIMD path's on lane k.
void check_paths(const Ref& f, const test::PairResult& x, const test::PairResult& y, uint32_t k) {
  SCOPED_TRACE(::testing::Message() << "lane " << k << " depth_ref " << f.r.s);
  if (x.count == 0 || y.count == 0) {
    if (std::fabs(f.r.s) > f.tol) {
      EXPECT_EQ(x.count, y.count) << "simd and scalar differ";
    } else {
      EXPECT_LE(std::max(x.count ? x.depth : 0.0, y.count ? y.depth : 0.0), 2 * f.tol);
    }
    return;
  }
  EXPECT_NEAR(x.depth, y.depth, f.tol) << "simd and scalar differ";
  if (f.unique()) {
    const double ang = nref::angle({x.n.x(), x.n.y(), x.n.z()}, {y.n.x(), y.n.y(), y.n.z()});
    double a1 = 0, a2 = 0;
    const bool both_good = normal_ok(f, x.n, &a1) && normal_ok(f, y.n, &a2);
    EXPECT_TRUE(ang <= kAngleTol || (both_good && ang <= 20 * kAngleTol))
        << "simd and scalar normals " << ang;
  }
}

/// The construction's promise on lane k (see Case).
void check_built(const Case& c, const Ref& f, uint32_t k) {
  if (c.n_built[k].isZero()) return;
  // the poses' float rounding moves features by ~1e-7 of their distance from the origin
  const double slack = 2e-6 * (f.L + f.pa.lpNorm<Eigen::Infinity>());
  const double along = f.overlap(c.n_built[k]);
  EXPECT_NEAR(along, c.d_built[k], slack) << "lane " << k << ": the construction's overlap";
  EXPECT_LE(f.r.s, along + 1e-9 * f.L) << "lane " << k << ": the reference misses the built normal";
  if (c.exact[k]) {
    EXPECT_NEAR(f.r.s, c.d_built[k], slack) << "lane " << k << ": the built distance";
    EXPECT_LE(nref::angle(f.r.n, {c.n_built[k].x(), c.n_built[k].y(), c.n_built[k].z()}), 1e-4)
        << "lane " << k;
  }
}

// --- inputs --------------------------------------------------------------------------------

Mat3d random_rotation(hi::Rng& g) {
  return test::random_rotation(g);
}

Vec3d radial(double a) {
  return {std::cos(a), std::sin(a), 0.0};
}
Vec3d tangential(double a) {
  return {-std::sin(a), std::cos(a), 0.0};
}

/// The rotation taking the orthonormal pair (a, b) onto (ta, tb).
Mat3d frame_map(const Vec3d& a, const Vec3d& b, const Vec3d& ta, const Vec3d& tb) {
  Mat3d F, T;
  F << a, b, a.cross(b);
  T << ta, tb, ta.cross(tb);
  return T * F.transpose();
}

Vec3d unit_orthogonal(hi::Rng& g, const Vec3d& a) {
  const Vec3d t1 = a.unitOrthogonal(), t2 = a.cross(t1);
  const double s = hi::uni(g, 0, 2 * M_PI);
  return std::cos(s) * t1 + std::sin(s) * t2;
}

/// A random rotation taking the unit `from` onto the unit `to`.
Mat3d spin_to(hi::Rng& g, const Vec3d& from, const Vec3d& to) {
  return frame_map(from, from.unitOrthogonal(), to, unit_orthogonal(g, to));
}

/// Per hull, local: the faces' centroids and, per vertex, the normalised sum of its faces'
/// normals (inside its normal cone).
struct Features {
  std::vector<std::vector<Vec3d>> face_centroid, vertex_cone;
  explicit Features(const hi::Hulls& hulls) {
    for (const HullData& h : hulls.data) {
      std::vector<Vec3d> fc, vc(h.vertices.size(), Vec3d::Zero());
      for (size_t f = 0; f < h.faces.size(); ++f) {
        Vec3d c = Vec3d::Zero();
        for (uint32_t i : h.faces[f]) {
          c += h.vertices[i].cast<double>();
          vc[i] += h.face_normals[f].cast<double>();
        }
        fc.push_back(c / static_cast<double>(h.faces[f].size()));
      }
      for (auto& v : vc) v.normalize();
      face_centroid.push_back(fc);
      vertex_cone.push_back(vc);
    }
  }
};

/// Adds hull `hull` at (Rl, pl) in the frame of a cylinder (centre 0, axis z, radius rc,
/// half length h), the pair turned and moved at random; n_local / d: what it was built as.
void add_posed(hi::Rng& g, Case& c, uint32_t hull, const Mat3d& Rl, const Vec3d& pl, double rc, double h,
               const Vec3d& n_local, double d, bool exact = false) {
  const Mat3d Rc = random_rotation(g);
  const Vec3d pc(hi::uni(g, -1, 1), hi::uni(g, -1, 1), hi::uni(g, -1, 1));
  Side a, b;
  a.hull = hull;
  a.R = test::round_to_float(Mat3d(Rc * Rl));
  a.p = rounded(pc + Rc * pl);
  b.R = test::round_to_float(Rc);
  b.p = rounded(pc);
  b.e = rounded(Vec3d(rc, h, 0));
  c.add(a, b, Rc * n_local, d, exact);
}

/// Cylinder radius and half length at `scale`: kind 0 random in [0.2, 1], 1 a needle
/// (radius 1e-3 of the length), 2 a pancake (half length 1e-3 of the radius).
Vec3d cylinder_size(hi::Rng& g, double scale, int kind) {
  double rc = hi::uni(g, 0.2, 1.0), h = hi::uni(g, 0.2, 1.0);
  if (kind == 1) rc = 1e-3 * 2 * h;
  if (kind == 2) h = 1e-3 * rc;
  return rounded(scale * Vec3d(rc, h, 0));
}

/// Random pairs: the hull near base + offset, the cylinder's centre within 0.9 of the sum
/// of the bounding radii from the hull's origin (about half meeting).
void random_pairs(hi::Rng& g, const hi::Hulls& hulls, const std::vector<uint32_t>& pool, double scale,
                  double offset, uint32_t count, int kind, Case& c) {
  for (uint32_t i = 0; i < count; ++i) {
    Side a, b;
    a.hull = pool[g() % pool.size()];
    a.R = test::round_to_float(random_rotation(g));
    const Vec3d base(offset, -0.5 * offset, 0.25 * offset);
    a.p = rounded(base + scale * Vec3d(hi::uni(g, -0.1, 0.1), hi::uni(g, -0.1, 0.1), hi::uni(g, -0.1, 0.1)));
    b.e = cylinder_size(g, scale, kind == 3 ? static_cast<int>(g() % 3) : kind);
    b.R = test::round_to_float(random_rotation(g));
    double rh = 0;
    for (const auto& v : hulls.data[a.hull].vertices) rh = std::max(rh, static_cast<double>(v.norm()));
    const hi::D3 u = hi::random_unit(g);
    const double dist = hi::uni(g, 0.0, 1.0) * (rh + std::hypot(b.e.x(), b.e.y())) * 0.9;
    b.p = rounded(a.p + dist * Vec3d(u.x, u.y, u.z));
    c.add(a, b);
  }
}

/// The feature pairs built in the cylinder's frame.
enum class Built { kFaceOnCap, kFaceOnSide, kEdgeAlongSide, kVertexIntoSide, kEdgeAcrossRim, kVertexAtRim };

/// One pair of kind `kind` with hull `hull`; `d` > 0: overlap along the built normal, < 0:
/// apart (rim kinds only; exact distance). Face and side kinds take d from the sizes.
void build(hi::Rng& g, const hi::Hulls& hulls, const Features& ft, uint32_t hull, Built kind, double d,
           Case& c) {
  const HullData& hd = hulls.data[hull];
  const HullView hv = hulls.store.view();
  const double rc = hi::uni(g, 0.3, 1.0), h = hi::uni(g, 0.3, 1.0);
  const double a = hi::uni(g, -M_PI, M_PI), s = g() % 2 ? 1.0 : -1.0, z0 = hi::uni(g, -0.5, 0.5) * h;
  const Vec3d ez = Vec3d::UnitZ();
  const double phi = hi::uni(g, 0.3, 1.27);
  const Vec3d rim = rc * radial(a) + s * h * ez, m = std::cos(phi) * radial(a) + s * std::sin(phi) * ez;
  const uint32_t f = static_cast<uint32_t>(g() % hd.faces.size());
  const Vec3d nf = hd.face_normals[f].cast<double>().normalized();
  double thick_lo = 1e300, thick_hi = -1e300;
  for (const auto& v : hd.vertices) {
    thick_lo = std::min(thick_lo, nf.dot(v.cast<double>()));
    thick_hi = std::max(thick_hi, nf.dot(v.cast<double>()));
  }
  const double shallow = hi::uni(g, 0.02, 0.2) * std::min({thick_hi - thick_lo, rc, h});
  const uint32_t e =
      hv.adj_begin[hull] + static_cast<uint32_t>(g() % (hv.adj_begin[hull + 1] - hv.adj_begin[hull]));
  const uint32_t vb = hv.vert_begin[hull];
  const Vec3d e0(hv.vx[vb + hv.ev0[e]], hv.vy[vb + hv.ev0[e]], hv.vz[vb + hv.ev0[e]]);
  const Vec3d e1(hv.vx[vb + hv.ev1[e]], hv.vy[vb + hv.ev1[e]], hv.vz[vb + hv.ev1[e]]);
  const Vec3d ed = (e1 - e0).normalized(), emid = 0.5 * (e0 + e1);
  Vec3d em(hv.emx[e], hv.emy[e], hv.emz[e]);
  em = (em - em.dot(ed) * ed).normalized();
  const uint32_t vi = static_cast<uint32_t>(g() % hd.vertices.size());
  const Vec3d vx = hd.vertices[vi].cast<double>(), vcone = ft.vertex_cone[hull][vi];
  Mat3d Rl;
  Vec3d n, x0, feat;  // the built normal, where the hull's feature goes, the feature (local)
  switch (kind) {
    case Built::kFaceOnCap:  // the face's centroid within 0.4 rc of the cap's centre
      n = -s * ez, d = shallow, feat = ft.face_centroid[hull][f];
      Rl = spin_to(g, nf, n);
      x0 = Vec3d(hi::uni(g, -0.28, 0.28) * rc, hi::uni(g, -0.28, 0.28) * rc, s * (h - d));
      break;
    case Built::kFaceOnSide:
      n = -radial(a), d = shallow, feat = ft.face_centroid[hull][f];
      Rl = spin_to(g, nf, n);
      x0 = (rc - d) * radial(a) + z0 * ez;
      break;
    case Built::kEdgeAlongSide:
      n = -radial(a), d = hi::uni(g, 0.01, 0.1) * std::min(rc, h), feat = emid;
      Rl = frame_map(ed, em, g() % 2 ? ez : Vec3d(-ez), n);
      x0 = (rc - d) * radial(a) + z0 * ez;
      break;
    case Built::kVertexIntoSide:
      n = -radial(a), d = hi::uni(g, 0.01, 0.1) * std::min(rc, h), feat = vx;
      Rl = spin_to(g, vcone, n);
      x0 = (rc - d) * radial(a) + z0 * ez;
      break;
    case Built::kEdgeAcrossRim: {
      n = -m, feat = emid;
      const double al = hi::uni(g, -1, 1);
      const Vec3d dir = std::cos(al) * m.cross(tangential(a)).normalized() + std::sin(al) * tangential(a);
      Rl = frame_map(ed, em, dir, n);
      x0 = rim + d * n;
      break;
    }
    case Built::kVertexAtRim:
      n = -m, feat = vx;
      Rl = spin_to(g, vcone, n);
      x0 = rim + d * n;
      break;
  }
  const bool exact = d < 0;  // apart rim kinds: the built features are the closest points
  add_posed(g, c, hull, Rl, x0 - Rl * feat, rc, h, n, d, exact);
}

// --- the fixture ---------------------------------------------------------------------------

uint32_t count_of(uint32_t n) {
  return static_cast<uint32_t>(n * test::intensity());
}

class ConvexCylinder : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    hulls_ = new hi::Hulls;
    hi::Rng g(7);
    hi::add_random_hulls(g, hulls_, 12, 1.0);  // 0..11: size 1 (boxes and point clouds)
    hi::add_random_hulls(g, hulls_, 4, 1e-4);  // 12..15
    hi::add_random_hulls(g, hulls_, 4, 1e4);   // 16..19
    for (int i = 0; i < 4; ++i) hulls_->add(hi::ellipsoid_points(g, 24, 1.0));  // 20..23: the bench's
    hulls_->add(hi::box_corners(1.0f, 0.5f, 5e-4f));                            // 24: flat (1e-3 thick)
    hulls_->add(hi::box_corners(0.6f, 0.6f, 5e-4f));                            // 25: flat
    hulls_->add(hi::box_corners(0.7f, 0.4f, 0.3f));                             // 26: box
    features_ = new Features(*hulls_);
    HullData open = hulls_->data[20];  // 27: hull 20 less a face: no edge adjacency
    open.faces.pop_back();
    open.face_normals.pop_back();
    open.face_offsets.pop_back();
    hulls_->data.push_back(open);
    hulls_->store.add(open);
    hulls_->add(hi::ellipsoid_points(g, 400, 1.0));  // 28: more vertices than the kernel takes
  }
  static void TearDownTestSuite() {
    delete features_;
    delete hulls_;
  }

  static std::vector<uint32_t> unit_pool() {
    return {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 20, 21, 22, 23, 26};
  }

  /// Runs both paths of the kernel under test and checks every lane; returns the SIMD
  /// answers and the references.
  struct Run {
    std::vector<Ref> refs;
    std::vector<test::PairResult> simd, scalar;
    Stats st;
  };
  Run run_all(const Case& c, const char* what) {
    SCOPED_TRACE(what);
    Lanes simd(c), scal(c);
    const HullView hv = hulls_->store.view();
    simd.go(under_test(), hv, KernelPath::kSimd, Range{0, simd.n()});
    scal.go(under_test(), hv, KernelPath::kScalar, Range{0, scal.n()});
    Run out;
    for (uint32_t k = 0; k < simd.n(); ++k) {
      out.refs.push_back(reference(simd, *hulls_, k));
      const Ref& f = out.refs.back();
      out.simd.push_back(simd.out.result(k));
      out.scalar.push_back(scal.out.result(k));
      ++out.st.lanes;
      check_built(c, f, k);
      check_lane(f, out.simd[k], k, "simd", &out.st);
      check_lane(f, out.scalar[k], k, "scalar", nullptr);
      check_paths(f, out.simd[k], out.scalar[k], k);
      if (::testing::Test::HasFailure() && hi::failure_parts() > 30) break;
    }
    const Stats& st = out.st;
    std::printf(
        "  %-26s lanes %4d hits %4d points 1/2/3/4 %3d/%3d/%3d/%3d unique %4d | worst |depth-ref| "
        "%.2g L, angle %.2g rad\n",
        what, st.lanes, st.hits, st.counts[1], st.counts[2], st.counts[3], st.counts[4], st.unique,
        st.worst_depth, st.worst_angle);
    return out;
  }

  static hi::Hulls* hulls_;
  static Features* features_;
};

hi::Hulls* ConvexCylinder::hulls_ = nullptr;
Features* ConvexCylinder::features_ = nullptr;

// --- tests ---------------------------------------------------------------------------------

TEST_F(ConvexCylinder, RandomPosesUnitSize) {
  hi::Rng g(11);
  Case c;
  random_pairs(g, *hulls_, unit_pool(), 1.0, 0.0, count_of(300), 0, c);
  const Run r = run_all(c, "random, size 1");
  EXPECT_GT(r.st.hits, r.st.lanes / 4);
  EXPECT_LT(r.st.hits, r.st.lanes * 9 / 10);
  EXPECT_GT(r.st.unique, r.st.hits / 2);
}

TEST_F(ConvexCylinder, RandomPosesScalesAndFarFromOrigin) {
  hi::Rng g(12);
  Case small, large, far;
  random_pairs(g, *hulls_, {12, 13, 14, 15}, 1e-4, 0.0, count_of(70), 0, small);
  random_pairs(g, *hulls_, {16, 17, 18, 19}, 1e4, 0.0, count_of(70), 0, large);
  random_pairs(g, *hulls_, unit_pool(), 1.0, 1e5, count_of(70), 0, far);
  for (const auto& [c, what] : {std::pair{&small, "random, size 1e-4"}, std::pair{&large, "random, size 1e4"},
                                std::pair{&far, "random, 1e5 from the origin"}}) {
    const Run r = run_all(*c, what);
    EXPECT_GT(r.st.hits, r.st.lanes / 5) << what;
    EXPECT_GT(r.st.unique, r.st.hits / 2) << what;
  }
}

TEST_F(ConvexCylinder, NeedlesPancakesAndFlatHulls) {
  hi::Rng g(13);
  Case needles, pancakes, flat;
  random_pairs(g, *hulls_, unit_pool(), 1.0, 0.0, count_of(60), 1, needles);
  random_pairs(g, *hulls_, unit_pool(), 1.0, 0.0, count_of(60), 2, pancakes);
  random_pairs(g, *hulls_, {24, 25}, 1.0, 0.0, count_of(60), 3, flat);
  for (const auto& [c, what] : {std::pair{&needles, "needle cylinders"},
                                std::pair{&pancakes, "pancake cylinders"}, std::pair{&flat, "flat hulls"}}) {
    const Run r = run_all(*c, what);
    EXPECT_GT(r.st.hits, r.st.lanes / 10) << what;
  }
}

/// A hull face resting on a cap, parallel and shallow (its centroid within the cap's
/// inscribed octagon): the built normal, and the clipped face: 2-4 points on at least 9 in
/// 10 lanes, 3-4 on at least 3 in 4. (contact_manifold keeps a clipped point only where
/// its chord along n crosses the hull; a face corner's chord only touches the hull where
/// the hull narrows above the face or has walls along n, so rounding keeps or drops it:
/// seen with GJK / EPA as with this kernel, ~3-5% single points at IMPACT_TEST_INTENSITY=8.
/// For the same reason a corner's pdepth may fall short of the depth by the chord's float
/// rounding over the cosine of a near-parallel wall: not checked beyond (d).)
TEST_F(ConvexCylinder, FaceRestingOnACap) {
  hi::Rng g(14);
  Case c;
  const std::vector<uint32_t> pool = {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 20, 21, 22, 23, 24, 25, 26};
  for (uint32_t i = 0; i < count_of(40); ++i)
    build(g, *hulls_, *features_, pool[i % pool.size()], Built::kFaceOnCap, 0, c);
  const Run r = run_all(c, "face on a cap");
  EXPECT_EQ(r.st.hits, r.st.lanes);  // every lane checked meets
  EXPECT_GE(r.st.hits - r.st.counts[1], r.st.hits * 9 / 10);
  EXPECT_GE(r.st.counts[3] + r.st.counts[4], r.st.hits * 3 / 4);
  for (uint32_t k = 0; k < r.simd.size(); ++k) {
    const Vec3d& n = r.simd[k].n;
    EXPECT_LT(nref::angle({n.x(), n.y(), n.z()}, {c.n_built[k].x(), c.n_built[k].y(), c.n_built[k].z()}),
              1e-4)
        << "lane " << k;
  }
}

/// A hull face against the side (its normal radial): the side line clipped to the face,
/// at least 2 points.
TEST_F(ConvexCylinder, FaceAgainstTheSide) {
  hi::Rng g(15);
  Case c;
  const std::vector<uint32_t> pool = {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 20, 21, 22, 23, 24, 25, 26};
  for (uint32_t i = 0; i < count_of(240); ++i)
    build(g, *hulls_, *features_, pool[i % pool.size()], Built::kFaceOnSide, 0, c);
  const Run r = run_all(c, "face against the side");
  EXPECT_EQ(r.st.hits, r.st.lanes);  // every lane checked meets
  EXPECT_GE(r.st.hits - r.st.counts[1], r.st.hits * 9 / 10);
}

/// Edges parallel to the axis and vertices pushed into the side.
TEST_F(ConvexCylinder, EdgesAndVerticesAgainstTheSide) {
  hi::Rng g(16);
  Case edges, vertices;
  const std::vector<uint32_t> pool = unit_pool();
  for (uint32_t i = 0; i < count_of(300); ++i) {
    build(g, *hulls_, *features_, pool[i % pool.size()], Built::kEdgeAlongSide, 0, edges);
    build(g, *hulls_, *features_, pool[(i + 5) % pool.size()], Built::kVertexIntoSide, 0, vertices);
  }
  {
    const Stats st = run_all(edges, "edge along the side").st;
    EXPECT_EQ(st.hits, st.lanes);
  }
  {
    const Stats st = run_all(vertices, "vertex into the side").st;
    EXPECT_EQ(st.hits, st.lanes);
  }
}

/// An edge across a rim (meeting, and apart: then the edge and the rim are the closest
/// features), a vertex just inside near a rim, a vertex off a rim (apart: count 0).
TEST_F(ConvexCylinder, EdgesAndVerticesAtARim) {
  hi::Rng g(17);
  Case across, apart, inside, off;
  const std::vector<uint32_t> pool = unit_pool();
  for (uint32_t i = 0; i < count_of(30); ++i) {
    const uint32_t h = pool[i % pool.size()];
    build(g, *hulls_, *features_, h, Built::kEdgeAcrossRim, hi::uni(g, 0.01, 0.1), across);
    build(g, *hulls_, *features_, h, Built::kEdgeAcrossRim, -hi::uni(g, 0.01, 0.1), apart);
    build(g, *hulls_, *features_, h, Built::kVertexAtRim, hi::uni(g, 1e-3, 1e-2), inside);
    build(g, *hulls_, *features_, h, Built::kVertexAtRim, -hi::uni(g, 0.003, 0.1), off);
  }
  {
    const Stats st = run_all(across, "edge across a rim").st;
    EXPECT_EQ(st.hits, st.lanes);
  }
  EXPECT_EQ(run_all(apart, "edge off a rim (apart)").st.hits, 0);
  {
    const Stats st = run_all(inside, "vertex just inside a rim").st;
    EXPECT_EQ(st.hits, st.lanes);
  }
  EXPECT_EQ(run_all(off, "vertex off a rim (apart)").st.hits, 0);
}

/// Deep pairs (the hull's centroid within 0.2 of the smaller size of the cylinder's
/// centre) and coincident centres: a finite unit normal and the reference depth.
TEST_F(ConvexCylinder, DeepAndCoincident) {
  hi::Rng g(18);
  Case c;
  const std::vector<uint32_t> pool = {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 20, 21, 22, 23, 24, 25, 26};
  for (uint32_t i = 0; i < count_of(40); ++i) {
    const uint32_t h = pool[i % pool.size()];
    Vec3d cen = Vec3d::Zero();
    for (const auto& v : hulls_->data[h].vertices) cen += v.cast<double>();
    cen /= static_cast<double>(hulls_->data[h].vertices.size());
    const Vec3d sz = cylinder_size(g, 1.0, static_cast<int>(i % 5 == 4 ? 1 + (i / 5) % 2 : 0));
    const Mat3d Rl = i % 3 == 0 ? Mat3d::Identity() : random_rotation(g);
    const double off = i % 2 == 0 ? 0.0 : 0.2 * std::min(sz.x(), sz.y());
    const Vec3d at = off * Vec3d(hi::uni(g, -1, 1), hi::uni(g, -1, 1), hi::uni(g, -1, 1));
    add_posed(g, c, h, Rl, at - Rl * cen, sz.x(), sz.y(), Vec3d::Zero(), 0);
  }
  const Run r = run_all(c, "deep and coincident");
  EXPECT_EQ(r.st.hits, r.st.lanes);  // every lane checked meets
}

/// A hull without edge adjacency (open faces) and one of 400 vertices go to GJK / EPA, in
/// a bucket with hulls the kernel takes: the same bytes as collide_gjk_epa on their lanes.
TEST_F(ConvexCylinder, OpenAndBigHullsTakeGjkEpa) {
  const HullView hv = hulls_->store.view();
  ASSERT_EQ(hv.adj_begin[27], hv.adj_begin[28]);
  ASSERT_GT(hulls_->data[28].vertices.size(), 256u);
  hi::Rng g(20);
  Case c;
  random_pairs(g, *hulls_, {20, 26, 27, 28}, 1.0, 0.0, count_of(80), 0, c);
  for (KernelPath path : {KernelPath::kSimd, KernelPath::kScalar}) {
    Lanes x(c), y(c);
    x.go(under_test(), hv, path, Range{0, x.n()});
    y.go(&gjk_kernel, hv, path, Range{0, y.n()});
    int general = 0, hits = 0;
    for (uint32_t k = 0; k < x.n(); ++k) {
      ASSERT_LE(x.out.count[k], 4u) << "lane " << k;
      if (c.a[k].hull < 27) continue;
      ++general;
      EXPECT_TRUE(same_bytes(x.out, k, y.out, k)) << "lane " << k << " hull " << c.a[k].hull;
      hits += x.out.count[k] > 0;
    }
    EXPECT_GT(general, static_cast<int>(x.n()) / 3);
    EXPECT_GT(hits, 5);
  }
}

/// A hull view without edge adjacency at all (adj_begin null, as sphere_convex_test,
/// capsule_convex_test and convex_triangle_test pass it; sat.cpp checks for it too): every
/// lane to GJK / EPA, the same bytes. Last in the file: a kernel that reads the null
/// pointer ends the run here.
TEST_F(ConvexCylinder, ViewWithoutAdjacencyTakesGjkEpa) {
  hi::Rng g(22);
  Case c;
  random_pairs(g, *hulls_, unit_pool(), 1.0, 0.0, count_of(60), 0, c);
  HullView hv = hulls_->store.view();
  hv.adj_begin = nullptr;
  for (KernelPath path : {KernelPath::kSimd, KernelPath::kScalar}) {
    Lanes x(c), y(c);
    x.go(under_test(), hv, path, Range{0, x.n()});
    y.go(&gjk_kernel, hv, path, Range{0, y.n()});
    int hits = 0;
    for (uint32_t k = 0; k < x.n(); ++k) {
      EXPECT_TRUE(same_bytes(x.out, k, y.out, k)) << "lane " << k;
      hits += x.out.count[k] > 0;
    }
    EXPECT_GT(hits, 10);
  }
}

}  // namespace
}  // namespace impact::kernels
