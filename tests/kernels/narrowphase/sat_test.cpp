// The separating axis test for polytope pairs (kernels/narrowphase/general/sat.cpp) against
// (1) a brute-force SAT in double over every face normal and every edge-pair cross
// product (no Gauss map pruning, no bounds), (2) GJK/EPA (the same kernel with
// NarrowConfig::sat_max_vertices = 0), (3) the specialised box-box kernel; on random
// poses and on the extremes: touching, deep, coincident centres, near-parallel edges,
// aspect 1e4, 1e-4 / 1e4 sizes, 1e5 offsets; swap symmetry; the hull store's edge
// adjacency; the dispatch knob. SatBoxHull: the box-hull route of collide_sat_lane
// against the brute force (depth within 1e-5 L, the normal a minimum direction, each
// manifold point midway between the two surfaces), GJK/EPA and the general route, on
// random poses, coincident centres, deep, touching, needle / pancake boxes and hulls,
// 1e-4 / 1e4 boxes, 1e5 offsets, hull edges parallel and near parallel to a box axis,
// parallel faces; SIMD and scalar paths. Range partitions and shuffled buckets of every
// bucket: contract_test.cpp.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
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
#include "support/random_input.h"
#include "support/test_support.h"

namespace impact::kernels {
namespace {

using Vec3d = Eigen::Vector3d;
using Mat3d = Eigen::Matrix3d;

struct Shape {
  LeafType type = kLeafBox;
  Vec3d p = Vec3d::Zero();
  Mat3d R = Mat3d::Identity();
  Vec3d e = Vec3d::Zero();  // box half extents
  uint32_t hull = 0;
};

using Lanes = test::LeafLanes;

using Result = test::PairResult;

/// Hulls of this file: random ellipsoid clouds, a needle, a pancake, a 400-point hull.
struct Hulls {
  HullStore store;
  std::vector<std::vector<Vec3d>> verts;  // local, double (as stored, from float)
  std::vector<std::vector<Vec3d>> normals;
  uint32_t add(const std::vector<Eigen::Vector3f>& pts) {
    HullData h;
    EXPECT_TRUE(test::IsOk(build_convex_hull(pts, &h)));
    std::vector<Vec3d> v, n;
    for (const auto& x : h.vertices) v.push_back(x.cast<double>());
    for (const auto& x : h.face_normals) n.push_back(x.cast<double>());
    verts.push_back(v);
    normals.push_back(n);
    return store.add(h);
  }
};

std::vector<Eigen::Vector3f> ellipsoid_cloud(std::mt19937& g, int n, Vec3d s) {
  std::normal_distribution<double> nd;
  std::vector<Eigen::Vector3f> pts;
  for (int i = 0; i < n; ++i) {
    Vec3d u(nd(g), nd(g), nd(g));
    u.normalize();
    pts.emplace_back(static_cast<float>(s.x() * u.x()), static_cast<float>(s.y() * u.y()),
                     static_cast<float>(s.z() * u.z()));
  }
  return pts;
}

Hulls& hulls() {
  static Hulls* h = [] {
    auto* hs = new Hulls;
    std::mt19937 g(7);
    std::uniform_real_distribution<double> u(0.4, 1.0);
    for (int i = 0; i < 8; ++i) hs->add(ellipsoid_cloud(g, 8 + 4 * i, Vec3d(u(g), u(g), u(g))));
    hs->add(ellipsoid_cloud(g, 24, Vec3d(1e-2, 1e-2, 1e2)));  // 8: needle (aspect 1e4)
    hs->add(ellipsoid_cloud(g, 24, Vec3d(1e2, 1e2, 1e-2)));   // 9: pancake
    hs->add(ellipsoid_cloud(g, 400, Vec3d(1.0, 0.8, 0.6)));   // 10: 400 points
    return hs;
  }();
  return *h;
}
constexpr uint32_t kRandomHulls = 8, kNeedle = 8, kPancake = 9, kBig = 10;

NarrowConfig config(bool sat) {
  NarrowConfig c;
  c.hulls = hulls().store.view();
  c.sat_max_vertices = sat ? 1u << 20 : 0u;
  return c;
}

/// Runs the kernel of (a.type, b.type) on one pair (a.type <= b.type).
Result run(const Shape& a, const Shape& b, const NarrowConfig& cfg) {
  Lanes la, lb;
  la.push(a);
  lb.push(b);
  test::ManifoldLanes out;
  if (a.type == kLeafBox && b.type == kLeafBox && cfg.sat_max_vertices == 0xffffffffu)
    collide_box_box(la.soa(), lb.soa(), out.view(), Range{0, 1}, cfg);  // the specialised kernel
  else
    collide_sat_or_gjk_epa(la.soa(), lb.soa(), out.view(), Range{0, 1}, cfg, a.type, b.type);
  return out.result();
}

/// World vertices, face normals and edges of a shape, in double (float pose as the
/// kernel reads it).
struct Poly {
  std::vector<Vec3d> v, n;
  std::vector<std::pair<Vec3d, Vec3d>> e;  // (a, b) of each edge (hulls: each face's)
};

Poly world_poly(const Shape& s) {
  // The pose as the kernel reads it: through the float lanes.
  Lanes l;
  l.push(s);
  Poly P;
  Mat3d R;
  Vec3d p, e;
  for (int i = 0; i < 9; ++i) R(i / 3, i % 3) = l.r[i][0];
  for (int i = 0; i < 3; ++i) p[i] = l.p[i][0], e[i] = l.e[i][0];
  if (s.type == kLeafBox) {
    for (int i = 0; i < 8; ++i)
      P.v.push_back(p + R * Vec3d((i & 1) ? e[0] : -e[0], (i & 2) ? e[1] : -e[1], (i & 4) ? e[2] : -e[2]));
    for (int a = 0; a < 3; ++a) {
      P.n.push_back(R.col(a));
      P.n.push_back(-R.col(a));
    }
    for (int i = 0; i < 8; ++i)
      for (int b = 0; b < 3; ++b)
        if (!(i & (1 << b))) P.e.emplace_back(P.v[i], P.v[i | (1 << b)]);
    return P;
  }
  const Hulls& H = hulls();
  for (const Vec3d& x : H.verts[s.hull]) P.v.push_back(p + R * x);
  for (const Vec3d& x : H.normals[s.hull]) P.n.push_back(R * x);
  const HullView hv = H.store.view();
  const uint32_t vb = hv.vert_begin[s.hull];
  for (uint32_t k = hv.adj_begin[s.hull]; k < hv.adj_begin[s.hull + 1]; ++k)
    P.e.emplace_back(P.v[hv.ev0[k]], P.v[hv.ev1[k]]);
  (void)vb;
  return P;
}

/// Separation of A and B along unit n: min_B n.x - max_A n.x.
double separation(const Poly& A, const Poly& B, const Vec3d& n) {
  double ha = -INFINITY, lb = INFINITY;
  for (const Vec3d& x : A.v) ha = std::max(ha, n.dot(x));
  for (const Vec3d& x : B.v) lb = std::min(lb, n.dot(x));
  return lb - ha;
}

/// Brute-force SAT in double: the largest separation over all face normals and all
/// edge-pair crosses (both signs), and its axis. For polytopes this is -depth.
double brute_sat(const Poly& A, const Poly& B, Vec3d* axis) {
  double best = -INFINITY;
  auto test = [&](const Vec3d& n) {
    const double s = separation(A, B, n);
    if (s > best) best = s, *axis = n;
  };
  for (const Vec3d& n : A.n) test(n);
  for (const Vec3d& n : B.n) test(-n);
  for (const auto& ea : A.e)
    for (const auto& eb : B.e) {
      const Vec3d da = ea.second - ea.first, db = eb.second - eb.first;
      Vec3d c = da.cross(db);
      if (!(c.norm() > 1e-9 * da.norm() * db.norm())) continue;
      c.normalize();
      test(c);
      test(-c);
    }
  return best;
}

double bound_radius(const Shape& s) {
  if (s.type == kLeafBox) return s.e.norm();
  double r = 0;
  for (const Vec3d& v : hulls().verts[s.hull]) r = std::max(r, v.norm());
  return r;
}

/// Checks one pair through SAT against the brute force and GJK/EPA: hit agreement
/// outside the touching band, depth, the normal's separation (a minimum direction),
/// points between the surfaces. tol relative to the larger bounding radius.
void check_pair(const Shape& a, const Shape& b, double rel, const char* what) {
  const double L = std::max(bound_radius(a), bound_radius(b));
  const double tol = rel * L;
  const Poly A = world_poly(a), B = world_poly(b);
  Vec3d axis;
  const double s = -brute_sat(A, B, &axis);  // > 0: penetration depth
  const Result sat = run(a, b, config(true));
  const Result gjk = run(a, b, config(false));
  SCOPED_TRACE(what);
  if (std::fabs(s) > tol) {
    EXPECT_EQ(sat.count > 0, s > 0) << "depth " << s << " tol " << tol;
    EXPECT_EQ(gjk.count > 0, s > 0);
  }
  if (sat.count == 0) return;
  EXPECT_LE(sat.count, 4u);
  EXPECT_NEAR(sat.n.norm(), 1.0, 1e-5);
  EXPECT_NEAR(sat.depth, s, tol) << "gjk depth " << gjk.depth;
  // Moving B by n * depth separates along n: the separation along n is about -depth.
  EXPECT_NEAR(separation(A, B, sat.n), -sat.depth, tol);
  for (uint32_t j = 0; j < sat.count; ++j) {
    EXPECT_GE(sat.pd[j], -tol);
    EXPECT_LE(sat.pd[j], sat.depth + tol);
    EXPECT_TRUE(std::isfinite(sat.pt[j].x()) && std::isfinite(sat.pt[j].y()) && std::isfinite(sat.pt[j].z()));
  }
  if (gjk.count > 0) {
    EXPECT_NEAR(sat.depth, gjk.depth, 2 * tol);
  }
}

Shape random_hull(std::mt19937& g, uint32_t hull, Vec3d p) {
  Shape s;
  s.type = kLeafConvex;
  s.hull = hull;
  s.R = test::random_rotation(g);
  s.p = p;
  return s;
}

Shape random_box(std::mt19937& g, Vec3d p, double scale = 1.0) {
  std::uniform_real_distribution<double> u(0.2, 1.0);
  Shape s;
  s.type = kLeafBox;
  s.e = Vec3d(u(g), u(g), u(g)) * scale;
  s.R = test::random_rotation(g);
  s.p = p;
  return s;
}

Vec3d random_unit(std::mt19937& g) {
  std::normal_distribution<double> nd;
  Vec3d v(nd(g), nd(g), nd(g));
  return v.normalized();
}

/// True when both runs found a contact; where only one did, that pair is touching:
/// its depth is within tol.
bool both_touch(const Result& x, const Result& y, double tol) {
  if (x.count > 0 && y.count > 0) return true;
  if (x.count != y.count) {
    EXPECT_LT(std::max(x.depth, y.depth), tol);
  }
  return false;
}

// --- hull store adjacency ----------------------------------------------------------------

TEST(Sat, HullEdgeAdjacency) {
  const Hulls& H = hulls();
  const HullView v = H.store.view();
  for (uint32_t h = 0; h < H.store.size(); ++h) {
    const uint32_t nv = v.vert_begin[h + 1] - v.vert_begin[h], nf = v.face_begin[h + 1] - v.face_begin[h];
    const uint32_t eb = v.adj_begin[h], ee = v.adj_begin[h + 1];
    ASSERT_GT(ee, eb);
    EXPECT_EQ((ee - eb) % 8, 0u);
    // Unique (undirected) edges: Euler V - E + F = 2; every edge lies on both faces.
    std::vector<std::pair<uint32_t, uint32_t>> uniq;
    for (uint32_t k = eb; k < ee; ++k) {
      const auto e = std::minmax(v.ev0[k], v.ev1[k]);
      if (std::find(uniq.begin(), uniq.end(), std::pair<uint32_t, uint32_t>(e.first, e.second)) == uniq.end())
        uniq.emplace_back(e.first, e.second);
      for (uint32_t f : {v.ef0[k], v.ef1[k]}) {
        ASSERT_LT(f, nf);
        const uint32_t fb = v.face_begin[h] + f;
        const uint32_t* b0 = v.face_verts + v.face_vert_begin[fb];
        const uint32_t* b1 = v.face_verts + v.face_vert_begin[fb + 1];
        EXPECT_NE(std::find(b0, b1, v.vert_begin[h] + v.ev0[k]), b1);
        EXPECT_NE(std::find(b0, b1, v.vert_begin[h] + v.ev1[k]), b1);
      }
      EXPECT_NE(v.ef0[k], v.ef1[k]);
      // The cone (em, theta) holds both face normals.
      const uint32_t f0 = v.face_begin[h] + v.ef0[k], f1 = v.face_begin[h] + v.ef1[k];
      const Vec3d m(v.emx[k], v.emy[k], v.emz[k]);
      EXPECT_NEAR(m.norm(), 1.0, 1e-6);
      for (uint32_t f : {f0, f1}) EXPECT_GE(m.dot(Vec3d(v.fnx[f], v.fny[f], v.fnz[f])), v.ecos[k] - 1e-6);
      EXPECT_NEAR(v.ecos[k] * v.ecos[k] + v.esin[k] * v.esin[k], 1.0, 1e-5);
      EXPECT_EQ(v.epx[k], v.vx[v.vert_begin[h] + v.ev0[k]]);
      // ed: the far end less the start, the float difference the kernels would compute.
      const uint32_t i0 = v.vert_begin[h] + v.ev0[k], i1 = v.vert_begin[h] + v.ev1[k];
      EXPECT_EQ(v.edx[k], v.vx[i1] - v.vx[i0]);
      EXPECT_EQ(v.edy[k], v.vy[i1] - v.vy[i0]);
      EXPECT_EQ(v.edz[k], v.vz[i1] - v.vz[i0]);
    }
    EXPECT_EQ(static_cast<int>(nv) - static_cast<int>(uniq.size()) + static_cast<int>(nf), 2) << "hull " << h;
  }
}

TEST(Sat, NonManifoldFacesGetNoAdjacency) {
  HullData h;  // two triangles sharing an edge: open surface
  h.vertices = {Eigen::Vector3f(0, 0, 0), Eigen::Vector3f(1, 0, 0), Eigen::Vector3f(0, 1, 0), Eigen::Vector3f(0, 0, 1)};
  h.faces = {{0, 2, 1}, {0, 1, 3}};
  h.face_normals = {Eigen::Vector3f(0, 0, -1), Eigen::Vector3f(0, -1, 0)};
  h.face_offsets = {0, 0};
  HullStore s;
  s.add(h);
  EXPECT_EQ(s.view().adj_begin[1], 0u);
  NarrowConfig c;
  c.hulls = s.view();
  cvx::Leaf a;
  a.type = kLeafConvex;
  a.hulls = &c.hulls;
  a.ax[0] = {1, 0, 0}, a.ax[1] = {0, 1, 0}, a.ax[2] = {0, 0, 1};
  EXPECT_EQ(cvx::sat_vertex_count(a, a), 0u);  // GJK/EPA takes such hulls
}

// --- accuracy ------------------------------------------------------------------------------

TEST(Sat, RandomPosesAgainstBruteForceAndGjk) {
  std::mt19937 g(11);
  std::uniform_real_distribution<double> f(0.0, 1.3);
  const uint32_t n = test::scaled(300);
  uint32_t edge = 0, face = 0;
  for (uint32_t i = 0; i < n; ++i) {
    const bool box_a = i % 3 == 0;
    Shape a = box_a ? random_box(g, Vec3d::Zero()) : random_hull(g, i % kRandomHulls, Vec3d::Zero());
    Shape b = random_hull(g, (i * 5 + 1) % kRandomHulls, Vec3d::Zero());
    b.p = random_unit(g) * f(g) * (bound_radius(a) + bound_radius(b)) * 0.8;
    check_pair(a, b, 1e-4, box_a ? "box-hull" : "hull-hull");
    // Which feature SAT picked (both kinds must be exercised).
    const NarrowConfig cfg = config(true);
    Lanes la, lb;
    la.push(a), lb.push(b);
    const cvx::V3 o{la.p[0][0], la.p[1][0], la.p[2][0]};
    const cvx::Leaf A = cvx::load_leaf(la.soa(), 0, a.type, &cfg.hulls, o);
    const cvx::Leaf B = cvx::load_leaf(lb.soa(), 0, b.type, &cfg.hulls, o);
    cvx::LaneContact c;
    cvx::SatStats st;
    cvx::collide_sat_lane(A, B, &c, &st);
    edge += st.feature == 2;
    face += st.feature == 0 || st.feature == 1;
    EXPECT_GT(cvx::sat_vertex_count(A, B), 0u);
  }
  EXPECT_GT(edge, n / 20);
  EXPECT_GT(face, n / 20);
}

TEST(Sat, Extremes) {
  std::mt19937 g(12);
  for (int rep = 0; rep < static_cast<int>(test::scaled(20)); ++rep) {
    // Deep and coincident centres.
    {
      Shape a = random_hull(g, rep % kRandomHulls, Vec3d::Zero());
      Shape b = random_hull(g, (rep + 3) % kRandomHulls, Vec3d::Zero());
      check_pair(a, b, 1e-4, "coincident centres");
      b.p = random_unit(g) * 0.2;
      check_pair(a, b, 1e-4, "deep");
    }
    // Touching: B moved along a direction to the brute-force touching distance.
    {
      Shape a = random_box(g, Vec3d::Zero());
      Shape b = random_hull(g, rep % kRandomHulls, Vec3d::Zero());
      const Vec3d u = random_unit(g);
      double lo = 0, hi = 10;
      for (int it = 0; it < 60; ++it) {
        b.p = u * (0.5 * (lo + hi));
        Vec3d ax;
        (brute_sat(world_poly(a), world_poly(b), &ax) < 0 ? lo : hi) = 0.5 * (lo + hi);
      }
      b.p = u * hi;
      check_pair(a, b, 1e-4, "touching");
    }
    // Sizes 1e-4 and 1e4, poses 1e5 from the origin.
    for (double sc : {1e-4, 1e4}) {
      Shape a = random_box(g, Vec3d::Zero(), sc);
      Shape b = random_box(g, random_unit(g) * 0.8 * sc, sc);
      check_pair(a, b, 1e-4, sc < 1 ? "boxes 1e-4" : "boxes 1e4");
    }
    {
      const Vec3d far(1e5, -1e5, 1e5);
      Shape a = random_hull(g, rep % kRandomHulls, far);
      Shape b = random_hull(g, (rep + 1) % kRandomHulls, far + random_unit(g) * 0.9);
      check_pair(a, b, 1e-3, "far 1e5");  // the float pose at 1e5 is exact to ~4e-3
    }
    // Aspect 1e4: needle against pancake and against a box.
    {
      Shape a = random_hull(g, kNeedle, Vec3d::Zero());
      Shape b = random_hull(g, kPancake, random_unit(g) * 0.005);
      check_pair(a, b, 1e-4, "needle-pancake");
      Shape c = random_box(g, random_unit(g) * 0.5);
      check_pair(c, a, 1e-4, "box-needle");
    }
  }
}

TEST(Sat, NearParallelEdges) {
  // Two boxes crossing edge to edge, the second turned by tiny angles about the
  // first's edge direction and about the contact normal.
  for (double ang : {0.0, 1e-7, 1e-5, 1e-4, 1e-3, 1e-2}) {
    for (int k = 0; k < 4; ++k) {
      Shape a;
      a.type = kLeafBox;
      a.e = Vec3d(1, 1, 1);
      a.R = Eigen::AngleAxisd(M_PI / 4, Vec3d::UnitX()).toRotationMatrix();  // edge along x, up
      Shape b;
      b.type = kLeafBox;
      b.e = Vec3d(1, 0.5, 0.7);
      b.R = Eigen::AngleAxisd(M_PI / 4 + ang, Vec3d::UnitX()).toRotationMatrix() *
            Eigen::AngleAxisd(k * ang, Vec3d::UnitZ()).toRotationMatrix();
      b.R = Eigen::AngleAxisd(M_PI, Vec3d::UnitY()).toRotationMatrix() * b.R;  // edge down
      b.p = Vec3d(0.1 * k, 0, std::sqrt(2.0) + 0.7 * std::sqrt(2.0) - 0.01);
      check_pair(a, b, 1e-4, "near-parallel edges");
    }
  }
}

TEST(Sat, SwapSymmetry) {
  std::mt19937 g(14);
  for (uint32_t i = 0; i < test::scaled(100); ++i) {
    Shape a = random_hull(g, i % kRandomHulls, Vec3d::Zero());
    Shape b = random_hull(g, (i + 2) % kRandomHulls, random_unit(g) * 0.8);
    const Result x = run(a, b, config(true)), y = run(b, a, config(true));
    const double tol = 1e-4 * std::max(bound_radius(a), bound_radius(b));
    if (!both_touch(x, y, tol)) continue;
    EXPECT_NEAR(x.depth, y.depth, tol);
    // Unique minimum directions: opposite normals (ties may pick either).
    const Poly A = world_poly(a), B = world_poly(b);
    EXPECT_NEAR(separation(B, A, -x.n), -x.depth, tol);
    EXPECT_NEAR(separation(A, B, -y.n), -y.depth, tol);
  }
}

TEST(Sat, BoxesThroughSatMatchTheBoxBoxKernel) {
  std::mt19937 g(15);
  NarrowConfig box_kernel = config(true);
  box_kernel.sat_max_vertices = 0xffffffffu;  // run() then calls collide_box_box
  for (uint32_t i = 0; i < test::scaled(200); ++i) {
    Shape a = random_box(g, Vec3d::Zero()), b = random_box(g, random_unit(g) * 1.2);
    const Result x = run(a, b, config(true)), y = run(a, b, box_kernel);
    const double tol = 1e-4 * std::max(a.e.norm(), b.e.norm());
    if (!both_touch(x, y, tol)) continue;
    EXPECT_NEAR(x.depth, y.depth, tol);
    const Poly A = world_poly(a), B = world_poly(b);
    EXPECT_NEAR(separation(A, B, x.n), separation(A, B, y.n), tol);
    // (Point counts may differ: the box-box kernel clips and reduces its own way.)
    check_pair(a, b, 1e-4, "box-box");
  }
}

TEST(Sat, BigHullAndTheKnob) {
  std::mt19937 g(16);
  NarrowConfig off = config(false);
  for (uint32_t i = 0; i < test::scaled(20); ++i) {
    Shape a = random_hull(g, kBig, Vec3d::Zero());
    Shape b = random_box(g, random_unit(g) * 1.3);
    Shape c = random_hull(g, i % kRandomHulls, random_unit(g) * 1.0);
    check_pair(b, a, 1e-4, "box - 400-point hull");
    check_pair(a, c, 1e-4, "400-point hull - hull");
    // Knob 0: GJK/EPA, same answer.
    const Result x = run(a, c, off), y = run(a, c, config(true));
    EXPECT_EQ(x.count > 0, y.count > 0);
    if (x.count > 0 && y.count > 0) {
      EXPECT_NEAR(x.depth, y.depth, 2e-4);
    }
  }
}

// --- box-hull route -------------------------------------------------------------------------

/// collide_sat_lane on one (box, hull) pair through its box-hull route and through the
/// general route (the box as an 8-vertex polytope), with the routes' statistics.
struct TwoRoutes {
  cvx::LaneContact fast, general;
  cvx::SatStats sf, sg;
};

TwoRoutes two_routes(const Shape& a, const Shape& b) {
  const NarrowConfig cfg = config(true);
  Lanes la, lb;
  la.push(a), lb.push(b);
  const cvx::V3 o{la.p[0][0], la.p[1][0], la.p[2][0]};
  const cvx::Leaf A = cvx::load_leaf(la.soa(), 0, a.type, &cfg.hulls, o);
  const cvx::Leaf B = cvx::load_leaf(lb.soa(), 0, b.type, &cfg.hulls, o);
  TwoRoutes r;
  cvx::collide_sat_lane(A, B, &r.fast, &r.sf);
  cvx::collide_sat_general_lane(A, B, &r.general, &r.sg);
  return r;
}

/// The box-hull route against the brute force, GJK/EPA (check_pair) and the general
/// route: the same hit outside the touching band, the depth within rel_route * L plus
/// the feature rule's bias of the brute force's (the general route's within 1e-4 L: near
/// a face's arc end its edge axes carry errors up to ~4e-5 L), the normal a minimum
/// direction (its separation -depth within the same), the manifold's depths within
/// [0, depth]. The bias: an edge axis beats the best face only by more than 1e-5 of the
/// sum of the two largest face offsets (sat.cpp), at most 1e-5 of the two bounding
/// radii; an edge axis ahead by less keeps the face and its depth (found at
/// IMPACT_TEST_INTENSITY=10: an edge 1.66e-5 ahead of a box face, L = 1.43).
void check_box_hull(const Shape& box, const Shape& hull, double rel, double rel_route, const char* what) {
  check_pair(box, hull, rel, what);
  SCOPED_TRACE(what);
  const TwoRoutes r = two_routes(box, hull);
  const double L = std::max(bound_radius(box), bound_radius(hull));
  const double tol = rel_route * L + 1e-5 * (bound_radius(box) + bound_radius(hull));  // depths
  const double tol_surface = rel_route * L;                                              // points
  const Poly A = world_poly(box), B = world_poly(hull);
  Vec3d axis;
  const double s = -brute_sat(A, B, &axis);
  if (std::fabs(s) > tol) {
    EXPECT_EQ(r.fast.count > 0, s > 0) << "brute depth " << s;
  }
  if (std::fabs(s) > 1e-4 * L) {
    EXPECT_EQ(r.fast.count > 0, r.general.count > 0);
  }
  if (r.fast.count == 0) return;
  EXPECT_NEAR(r.fast.depth, s, tol) << "feature " << r.sf.feature << ", general " << r.sg.feature;
  if (r.general.count > 0) {
    EXPECT_NEAR(r.fast.depth, r.general.depth, 1e-4 * L);
  }
  const Vec3d nf(r.fast.n.x, r.fast.n.y, r.fast.n.z);
  EXPECT_NEAR(nf.norm(), 1.0, 1e-6);
  EXPECT_NEAR(separation(A, B, nf), -r.fast.depth, tol);
  EXPECT_GE(r.fast.count, 1u);
  EXPECT_LE(r.fast.count, 4u);
  // Each point lies midway between the surfaces: p + n pd / 2 on A's, p - n pd / 2 on
  // B's (signed plane distances in double; the points are relative to A's centre).
  const Vec3d o(static_cast<float>(box.p.x()), static_cast<float>(box.p.y()), static_cast<float>(box.p.z()));
  const auto dist = [](const Poly& P, const Vec3d& q) {
    double sd = -INFINITY;
    for (const Vec3d& nn : P.n) {
      double d = -INFINITY;
      for (const Vec3d& v : P.v) d = std::max(d, nn.dot(v));
      sd = std::max(sd, nn.dot(q) - d);
    }
    return sd;
  };
  const double tol_pt = tol_surface + 4e-7 * o.cwiseAbs().maxCoeff();
  for (uint32_t j = 0; j < r.fast.count; ++j) {
    EXPECT_GE(r.fast.pdepth[j], 0.0f);
    EXPECT_LE(r.fast.pdepth[j], r.fast.depth + tol);
    if (r.sf.feature == 2) continue;  // the edge points: the closest points of the edges
    const Vec3d p = o + Vec3d(r.fast.point[j].x, r.fast.point[j].y, r.fast.point[j].z);
    const double h = 0.5 * r.fast.pdepth[j];
    EXPECT_NEAR(dist(A, p + nf * h), 0.0, tol_pt) << "point " << j;
    EXPECT_NEAR(dist(B, p - nf * h), 0.0, tol_pt) << "point " << j;
  }
}

/// A rotation taking unit u to unit x (rows: u and two unit vectors normal to it).
Mat3d turn_onto(const Vec3d& u, const Vec3d& x) {
  auto frame = [](const Vec3d& a) {
    const Vec3d b = (std::fabs(a.x()) < 0.6 ? Vec3d::UnitX() : Vec3d::UnitY()).cross(a).normalized();
    Mat3d F;
    F.row(0) = a, F.row(1) = b, F.row(2) = a.cross(b);
    return F;
  };
  return frame(x).transpose() * frame(u);  // both frames right-handed: a rotation
}

/// Rotation taking unit u to the x axis, then turned by ang about z and y.
Mat3d align_to_x(const Vec3d& u, double ang) {
  return Mat3d(Eigen::AngleAxisd(ang, Vec3d::UnitZ()).toRotationMatrix() *
               Eigen::AngleAxisd(0.7 * ang, Vec3d::UnitY()).toRotationMatrix() * turn_onto(u, Vec3d::UnitX()));
}

TEST(SatBoxHull, RandomPoses) {
  std::mt19937 g(21);
  std::uniform_real_distribution<double> f(0.0, 1.3);
  const uint32_t n = test::scaled(400);
  uint32_t edge = 0, face_a = 0, face_b = 0, hits = 0;
  for (uint32_t i = 0; i < n; ++i) {
    const Shape a = random_box(g, Vec3d::Zero());
    Shape b = random_hull(g, i % kRandomHulls, Vec3d::Zero());
    b.p = random_unit(g) * f(g) * (bound_radius(a) + bound_radius(b)) * 0.8;
    check_box_hull(a, b, 1e-4, 1e-5, "random");
    const TwoRoutes r = two_routes(a, b);
    edge += r.sf.feature == 2, face_a += r.sf.feature == 0, face_b += r.sf.feature == 1;
    hits += r.fast.count > 0;
  }
  // Every feature kind is exercised, and about half the pairs overlap.
  EXPECT_GT(edge, n / 20);
  EXPECT_GT(face_a, n / 20);
  EXPECT_GT(face_b, n / 40);
  EXPECT_GT(hits, n / 4);
  EXPECT_LT(hits, 3 * n / 4);
}

TEST(SatBoxHull, Extremes) {
  std::mt19937 g(22);
  for (int rep = 0; rep < static_cast<int>(test::scaled(20)); ++rep) {
    const uint32_t h = rep % kRandomHulls;
    // Coincident centres and deep.
    {
      Shape a = random_box(g, Vec3d::Zero());
      Shape b = random_hull(g, h, Vec3d::Zero());
      check_box_hull(a, b, 1e-4, 1e-5, "coincident centres");
      b.p = random_unit(g) * 0.1;
      check_box_hull(a, b, 1e-4, 1e-5, "deep");
    }
    // Touching: the brute-force touching distance along a random direction.
    {
      Shape a = random_box(g, Vec3d::Zero());
      Shape b = random_hull(g, h, Vec3d::Zero());
      const Vec3d u = random_unit(g);
      double lo = 0, hi = 10;
      for (int it = 0; it < 60; ++it) {
        b.p = u * (0.5 * (lo + hi));
        Vec3d ax;
        (brute_sat(world_poly(a), world_poly(b), &ax) < 0 ? lo : hi) = 0.5 * (lo + hi);
      }
      b.p = test::round_to_float(Vec3d(u * hi));
      check_box_hull(a, b, 1e-4, 1e-5, "touching");
    }
    // Needle and pancake boxes (1e-4), needle and pancake hulls (aspect 1e4).
    {
      Shape a = random_box(g, Vec3d::Zero());
      a.e = Vec3d(1, 1e-4, 1e-4);
      Shape b = random_hull(g, h, random_unit(g) * 0.5);
      check_box_hull(a, b, 1e-4, 1e-5, "needle box");
      a.e = Vec3d(1, 1, 1e-4);
      check_box_hull(a, b, 1e-4, 1e-5, "pancake box");
      const Shape c = random_box(g, Vec3d::Zero());
      check_box_hull(c, random_hull(g, kNeedle, random_unit(g) * 0.5), 1e-4, 1e-5, "needle hull");
      check_box_hull(c, random_hull(g, kPancake, random_unit(g) * 0.005), 1e-4, 1e-5, "pancake hull");
    }
    // Tiny and huge boxes against a unit hull; a 400-point hull.
    for (double sc : {1e-4, 1e4}) {
      const Shape a = random_box(g, Vec3d::Zero(), sc);
      const Shape b = random_hull(g, h, random_unit(g) * (sc < 1 ? 0.5 : 0.5 * sc));
      check_box_hull(a, b, 1e-4, 1e-5, sc < 1 ? "box 1e-4" : "box 1e4");
    }
    check_box_hull(random_box(g, Vec3d::Zero()), random_hull(g, kBig, random_unit(g) * 1.2), 1e-4, 1e-5, "400 points");
    // 1e5 from the origin (the float pose is exact to ~4e-3: as Sat.Extremes).
    {
      const Vec3d far(1e5, -1e5, 1e5);
      const Shape a = random_box(g, far);
      const Shape b = random_hull(g, h, far + random_unit(g) * 0.9);
      check_box_hull(a, b, 1e-3, 1e-5, "far 1e5");
    }
  }
}

TEST(SatBoxHull, ParallelAndNearParallelFeatures) {
  // A hull edge turned onto the box's x axis (skipped as parallel by both routes), and
  // by small angles off it; a hull face turned onto the box's +z face (parallel faces).
  std::mt19937 g(23);
  const HullView hv = hulls().store.view();
  for (uint32_t h = 0; h < kRandomHulls; ++h) {
    const uint32_t k = hv.adj_begin[h];
    const Vec3d d(hv.edx[k], hv.edy[k], hv.edz[k]);
    const Vec3d n0 = hulls().normals[h][hv.ef0[k]];
    for (double ang : {0.0, 1e-7, 1e-5, 1e-3, 1e-2}) {
      Shape a = random_box(g, Vec3d::Zero());
      a.R = Mat3d::Identity();
      Shape b = random_hull(g, h, Vec3d::Zero());
      b.R = align_to_x(d.normalized(), ang);
      // Move B along -(its first face normal) so the edge meets the box near an edge.
      const Vec3d dir = -(b.R * n0).normalized();
      for (double f : {0.6, 0.9, 1.0}) {
        b.p = test::round_to_float(Vec3d(dir * f * (bound_radius(a) + bound_radius(b)) * 0.7));
        check_box_hull(a, b, 1e-4, 1e-5, "near-parallel edge");
      }
    }
    for (double ang : {0.0, 1e-6, 1e-3}) {
      Shape a = random_box(g, Vec3d::Zero());
      a.R = Mat3d::Identity();
      Shape b = random_hull(g, h, Vec3d::Zero());
      const Vec3d nf = hulls().normals[h][0];
      b.R = Eigen::AngleAxisd(ang, Vec3d::UnitX()).toRotationMatrix() * turn_onto(nf.normalized(), -Vec3d::UnitZ());
      // Face 0 sunk 0.02 into the box's top: a face contact (never an edge axis, whose
      // separation ties the faces' here), the hull face clipped to >= 3 points.
      const double d0 = hv.fd[hv.face_begin[h]];
      b.p = test::round_to_float(Vec3d(0.05, -0.05, a.e.z() + d0 - 0.02));
      check_box_hull(a, b, 1e-4, 1e-5, "parallel faces");
      if (ang == 0.0) {
        const TwoRoutes r = two_routes(a, b);
        EXPECT_NE(r.sf.feature, 2);
        EXPECT_GE(r.fast.count, 3u);
        EXPECT_NEAR(r.fast.depth, 0.02, 1e-5);
      }
    }
  }
}

}  // namespace
}  // namespace impact::kernels
