// The narrow phase far from the origin: every pair type at 1e5, 1e6 and 1e7 m against
// the same pair at the origin, through the kernels (every bucket of pair_kernel(), both
// paths), the public NarrowPhase::collide (every shape type, meshes, compounds and
// half-spaces included) and the World's step (plain spheres, shaped bodies, planes).
//
// Reference: the origin answer. The far pair is the origin pair translated by T, whose
// components are +-1e5, +-1e6 or +-1e7 (floats, multiples of their own spacing g). The
// origin pair's world coordinates (kernel leaves: positions, triangle corners, plane
// points; public calls: pose positions) are multiples of g and small beside T, so T + x
// is exact and the far pair is the origin pair moved exactly: its collision data is the
// origin's with T added to the points. Shape-local data (radii, hull and mesh vertices,
// compound children's poses, plane offsets) and orientations stay as they are, so what
// a far pair tests is the posing and arithmetic of the pair, not a rounded input. Pairs
// are sized max(1, 128 g) (1 m at 1e5, 8 m at 1e6, 128 m at 1e7) so that positions on
// the grid g still vary.
//
// Tolerances, from the float spacing u = 2^(e - 24) of the pair's own coordinates
// (|x| < 2^e at the origin: the largest position, corner or vertex relative to the
// origin pair's frame): a kernel that computes relative to a point of the pair sees the
// same relative inputs at T as at the origin up to one rounding of each input at u, so
// depth and points (T removed) agree within kTolUlps u, plus, for points, the rounding of
// a world coordinate at T (half its spacing g_T per component) and at the origin; normals
// within kTolUlps u / L rad (L the pair's size). Hit / miss agree except where the
// touching side's depth is within the depth tolerance of zero (touching within rounding).
// Points are compared as sets (each within tolerance of one of the other side's), counts
// equal except for points whose own depth is within the tolerance of zero.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <memory>
#include <random>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

#include "impact/impact.h"
#include "kernels/narrowphase/pair_kernels.h"
#include "tests/support/pair_input.h"
#include "tests/support/test_support.h"

namespace impact {
namespace {

using kernels::LeafType;
using test::IsOk;

constexpr double kOffsets[3] = {1e5, 1e6, 1e7};
/// Spacings of the pair's own coordinates allowed between the far and the origin answer.
constexpr double kTolUlps = 16.0;

/// The spacing of floats in the binade holding m (m > 0): 2^(e - 24) for 2^(e-1) <= m < 2^e.
double spacing(double m) {
  int e = 0;
  std::frexp(m, &e);
  return std::ldexp(1.0, e - 24);
}

/// x rounded to a multiple of g (g a power of two; the result is a float).
float snap(double x, double g) { return static_cast<float>(std::nearbyint(x / g) * g); }

/// Pair size at offset: large enough that positions on the offset's grid still vary.
double pair_scale(double offset) { return std::max(1.0, 128.0 * spacing(offset)); }

/// The translation of draw i: +-offset per component (every sign pattern in turn).
Eigen::Vector3d translation(double offset, uint32_t i) {
  return Eigen::Vector3d((i & 1) ? -offset : offset, (i & 2) ? -offset : offset, (i & 4) ? -offset : offset);
}

/// One contact as compared: depth, normal, points and their depths, in double.
struct Contact {
  double depth = 0;
  Eigen::Vector3d n = Eigen::Vector3d::Zero();
  std::vector<Eigen::Vector3d> pts;
  std::vector<double> pd;
};

/// Tolerances of one pair (see the file header).
struct Tolerance {
  double depth, point, angle;
  static Tolerance of(double coord_mag, double size, double offset) {
    const double u = spacing(std::max(coord_mag, size));
    Tolerance t;
    t.depth = kTolUlps * u;
    // A world coordinate rounds at T (half its spacing) and at the origin (half of u);
    // per component, so sqrt(3) over the three.
    t.point = kTolUlps * u + std::sqrt(3.0) * 0.5 * (spacing(offset + coord_mag) + u);
    t.angle = kTolUlps * u / size;
    return t;
  }
};

/// Why `far` (T removed) is not the origin answer `near`, or empty.
std::string compare(const Contact& near, const Contact& far, const Eigen::Vector3d& T, const Tolerance& tol) {
  std::ostringstream why;
  why.precision(9);
  if (std::fabs(far.depth - near.depth) > tol.depth)
    why << " depth " << far.depth << " vs " << near.depth << " (tol " << tol.depth << ")";
  const double cosang = std::clamp(far.n.dot(near.n) / (far.n.norm() * near.n.norm()), -1.0, 1.0);
  const double ang = std::acos(cosang);
  if (!(ang <= tol.angle)) why << " normal " << ang << " rad off (tol " << tol.angle << ")";
  auto unmatched = [&](const Contact& x, const Contact& y, const Eigen::Vector3d& shift, const char* who) {
    for (size_t i = 0; i < x.pts.size(); ++i) {
      double best = INFINITY;
      for (const Eigen::Vector3d& q : y.pts) best = std::min(best, (x.pts[i] + shift - q).norm());
      if (best > tol.point && x.pd[i] > tol.depth)
        why << " " << who << " point " << i << " " << best << " from the other's (tol " << tol.point << ")";
    }
  };
  unmatched(far, near, -T, "far");
  unmatched(near, far, T, "origin");
  return why.str();
}

/// Hit / miss and, for two hits, compare(); empty when they agree.
std::string compare_hits(bool near_hit, const Contact& near, bool far_hit, const Contact& far,
                         const Eigen::Vector3d& T, const Tolerance& tol) {
  if (near_hit && far_hit) return compare(near, far, T, tol);
  if (near_hit != far_hit) {
    const double d = near_hit ? near.depth : far.depth;
    if (d > tol.depth) {
      std::ostringstream why;
      why << (near_hit ? " origin hits" : " far hits") << " alone, depth " << d << " (tol " << tol.depth << ")";
      return why.str();
    }
  }
  return {};
}

Contact contact_of(const test::PairResult& r) {
  Contact c;
  c.depth = r.depth;
  c.n = r.n;
  for (uint32_t j = 0; j < r.count && j < 4; ++j) {
    c.pts.push_back(r.pt[j]);
    c.pd.push_back(r.pd[j]);
  }
  return c;
}

// ---------------------------------------------------------------------------------------
// The kernels
// ---------------------------------------------------------------------------------------

/// The leaf's world coordinates (position, triangle corners) snapped to multiples of g.
void snap_leaf(test::Leaf& l, double g) {
  for (float& x : l.p) x = snap(x, g);
  if (l.t == kernels::kLeafTriangle)
    for (float& x : l.w) x = snap(x, g);
}

/// The leaf moved by T (exact: its coordinates are multiples of T's spacing).
test::Leaf moved(test::Leaf l, const Eigen::Vector3d& T) {
  for (int i = 0; i < 3; ++i) l.p[i] = static_cast<float>(l.p[i] + T[i]);
  if (l.t == kernels::kLeafTriangle)
    for (int i = 0; i < 6; ++i) l.w[i] = static_cast<float>(l.w[i] + T[i % 3]);
  return l;
}

/// The largest world coordinate of a leaf (hull vertices posed about p included).
double leaf_magnitude(const test::Leaf& l, const test::HullBank& w) {
  return test::coord_magnitude(test::ref_shape(l, w));
}

class FarKernels : public ::testing::TestWithParam<std::pair<LeafType, LeafType>> {};

TEST_P(FarKernels, MatchTheSamePairAtTheOrigin) {
  const auto [ta, tb] = GetParam();
  const kernels::PairKernel kern = kernels::pair_kernel(ta, tb);
  ASSERT_NE(kern, nullptr);
  for (double offset : kOffsets) {
    const double g = spacing(offset), scale = pair_scale(offset);
    test::Rng rng(static_cast<uint32_t>(1000 * ta + 10 * tb) + static_cast<uint32_t>(std::log10(offset)));
    test::HullBank bank;
    std::vector<test::Leaf> a0, b0, a1, b1;
    std::vector<Eigen::Vector3d> shift;
    const uint32_t n = test::scaled(64);
    for (uint32_t i = 0; i < n; ++i) {
      // Most pairs at 0..1.1 of the radii sum (about half touching), every fourth deep.
      const double lam = (i % 4 == 3) ? test::uni(rng, 0.0, 0.05) : test::uni(rng, 0.0, 1.1);
      const test::V3 c{scale * test::uni(rng, -1, 1), scale * test::uni(rng, -1, 1), scale * test::uni(rng, -1, 1)};
      auto [a, b] = test::place_pair(ta, tb, c, scale, tb == kernels::kLeafHalfSpace ? lam * 2.4 - 1.2 : lam, rng,
                                     bank);
      snap_leaf(a, g);
      snap_leaf(b, g);
      const Eigen::Vector3d T = translation(offset, i);
      a0.push_back(a);
      b0.push_back(b);
      a1.push_back(moved(a, T));
      b1.push_back(moved(b, T));
      shift.push_back(T);
    }
    for (kernels::KernelPath path : {kernels::KernelPath::kSimd, kernels::KernelPath::kScalar}) {
      kernels::NarrowConfig cfg;
      cfg.path = path;
      cfg.hulls = bank.hulls.view();
      const test::ManifoldLanes near = test::run_bucket(kern, a0, b0, cfg, 0, n);
      const test::ManifoldLanes far = test::run_bucket(kern, a1, b1, cfg, 0, n);
      int failures = 0;
      for (uint32_t k = 0; k < n && failures < 5; ++k) {
        const test::PairResult rn = near.result(k), rf = far.result(k);
        const double mag = std::max(leaf_magnitude(a0[k], bank), leaf_magnitude(b0[k], bank));
        const double size = std::max(test::ref_shape(a0[k], bank).bound_radius(),
                                     test::ref_shape(b0[k], bank).bound_radius());
        const Tolerance tol = Tolerance::of(mag, size, offset);
        const std::string why = compare_hits(rn.count > 0, contact_of(rn), rf.count > 0, contact_of(rf), shift[k], tol);
        if (!why.empty()) {
          ++failures;
          ADD_FAILURE() << test::pair_name(ta, tb) << " at " << offset << " m, "
                        << (path == kernels::KernelPath::kSimd ? "SIMD" : "scalar") << " lane " << k << ":" << why
                        << "\n"
                        << test::literal("A (origin)", a0[k], bank) << test::literal("B (origin)", b0[k], bank);
        }
      }
    }
  }
}

INSTANTIATE_TEST_SUITE_P(EveryBucket, FarKernels, ::testing::ValuesIn(test::all_buckets()),
                         [](const auto& p) { return test::pair_name(p.param.first, p.param.second); });

// ---------------------------------------------------------------------------------------
// NarrowPhase::collide
// ---------------------------------------------------------------------------------------

/// Every shape type of ShapeSet at size `s`: the plain shapes, two half-spaces (a tilted
/// normal and an axis one, offsets not on any grid), a small bumpy mesh whose vertices
/// lie off its pose, and a compound of six convex children at odd local poses.
struct FarZoo {
  ShapeSet set;
  std::vector<ShapeId> ids;
  std::vector<const char*> names;
  std::vector<double> radius;  // a bounding radius of each, for placing pairs
  uint32_t first_half_space = 0, half_spaces = 2;

  explicit FarZoo(double s) {
    const auto f = [&](double x) { return static_cast<float>(x * s); };
    auto add = [&](const char* name, double r, const Status& st, ShapeId id) {
      EXPECT_TRUE(IsOk(st)) << name;
      ids.push_back(id);
      names.push_back(name);
      radius.push_back(r * s);
    };
    ShapeId id;
    Status st = set.add_sphere(f(0.5), &id);
    add("sphere", 0.5, st, id);
    st = set.add_capsule(f(0.3), f(0.6), &id);
    add("capsule", 0.9, st, id);
    st = set.add_box(Eigen::Vector3f(f(0.4), f(0.3), f(0.7)), &id);
    add("box", 0.87, st, id);
    st = set.add_aabb(Eigen::Vector3f(f(0.5), f(0.2), f(0.3)), &id);
    add("aabb", 0.62, st, id);
    std::mt19937 rng(7);
    std::normal_distribution<float> gn(0.0f, 1.0f);
    std::vector<Eigen::Vector3f> pts;
    for (int i = 0; i < 24; ++i) pts.push_back(Eigen::Vector3f(gn(rng), gn(rng), gn(rng)).normalized() * f(0.6));
    ShapeId hull;
    st = set.add_convex_hull(pts, &hull);
    add("convex", 0.6, st, hull);
    st = set.add_cylinder(f(0.4), f(0.5), &id);
    add("cylinder", 0.65, st, id);
    st = set.add_ellipsoid(Eigen::Vector3f(f(0.6), f(0.3), f(0.4)), &id);
    add("ellipsoid", 0.6, st, id);
    first_half_space = static_cast<uint32_t>(ids.size());
    st = set.add_half_space(Eigen::Vector3f(0.48f, -0.6f, 0.64f), f(0.37), &id);
    add("half-space tilted", 0.0, st, id);
    st = set.add_half_space(Eigen::Vector3f(0, 0, 1), f(-0.21), &id);
    add("half-space axis", 0.0, st, id);
    // A 4 x 4 patch of 32 triangles about (0.31, -0.17, 0.23) s from its pose, bumpy.
    std::vector<Eigen::Vector3f> v;
    std::vector<uint32_t> idx;
    const int m = 4;
    for (int i = 0; i <= m; ++i)
      for (int j = 0; j <= m; ++j)
        v.emplace_back(f(0.31 - 0.9 + 0.45 * i), f(-0.17 + 0.2 * std::sin(1.3 * i + 2.1 * j)),
                       f(0.23 - 0.9 + 0.45 * j));
    for (int i = 0; i < m; ++i)
      for (int j = 0; j < m; ++j) {
        const auto a = static_cast<uint32_t>(i * (m + 1) + j), b = a + 1,
                   c = static_cast<uint32_t>((i + 1) * (m + 1) + j), d = c + 1;
        idx.insert(idx.end(), {a, b, c, b, d, c});
      }
    st = set.add_mesh(v, idx, &id);
    add("mesh", 1.4, st, id);
    // Children of every convex type at local poses off any grid.
    std::vector<CompoundChild> kids;
    const double at[6][3] = {{-0.53, 0.11, 0.07}, {0.49, -0.13, 0.21}, {0.03, 0.47, -0.29},
                             {0.17, -0.41, -0.37}, {-0.23, -0.07, 0.51}, {0.31, 0.29, 0.33}};
    for (int k = 0; k < 6; ++k) {
      Pose lp;
      lp.position = Eigen::Vector3f(f(at[k][0]), f(at[k][1]), f(at[k][2]));
      lp.orientation = Eigen::Quaternionf(Eigen::AngleAxisf(0.37f + 0.71f * static_cast<float>(k),
                                                            Eigen::Vector3f(0.3f, -0.5f, 0.81f).normalized()));
      kids.push_back({ids[k == 5 ? 4 : k == 4 ? 6 : k], lp});  // sphere, capsule, box, aabb, ellipsoid, hull
    }
    kids[3].shape = ids[5];  // a cylinder in place of the AABB
    st = set.add_compound(kids, &id);
    add("compound", 1.3, st, id);
  }
  bool is_half_space(size_t k) const { return k >= first_half_space && k < first_half_space + half_spaces; }
};

/// A random unit quaternion.
Eigen::Quaternionf random_orientation(std::mt19937& rng) {
  std::normal_distribution<float> g(0.0f, 1.0f);
  Eigen::Vector4f q(g(rng), g(rng), g(rng), g(rng));
  q.normalize();
  return Eigen::Quaternionf(q[3], q[0], q[1], q[2]);
}

/// Objects (shape and pose at the origin) and pairs of every kind pair of the zoo.
struct FarScene {
  std::vector<ShapeId> shape_of;
  std::vector<Pose> poses;
  std::vector<ShapePair> pairs;
  std::vector<std::string> what;  // per pair
};

FarScene far_scene(const FarZoo& z, double g, uint32_t per_kind, std::mt19937& rng) {
  FarScene sc;
  std::uniform_real_distribution<double> u(-1.0, 1.0), lam(0.0, 1.1);
  const size_t kinds = z.ids.size();
  for (size_t i = 0; i < kinds; ++i) {
    for (size_t j = i; j < kinds; ++j) {
      if (z.is_half_space(i) && z.is_half_space(j)) continue;
      // The half-space, if any, second: normals point from the other shape into it.
      const size_t x = z.is_half_space(i) ? j : i, y = z.is_half_space(i) ? i : j;
      for (uint32_t k = 0; k < per_kind; ++k) {
        const double s = std::max(z.radius[x], z.radius[y]);
        const Eigen::Vector3d c(s * u(rng), s * u(rng), s * u(rng));
        Eigen::Vector3d d(u(rng), u(rng), u(rng));
        d.normalize();
        // B at 0..1.1 of the radii sum from A (a half-space's pose within A's radius).
        const double reach = z.is_half_space(y) ? z.radius[x] * u(rng) : lam(rng) * (z.radius[x] + z.radius[y]);
        const Eigen::Vector3d cb = c + reach * d;
        Pose pa, pb;
        pa.position = Eigen::Vector3f(snap(c.x(), g), snap(c.y(), g), snap(c.z(), g));
        pb.position = Eigen::Vector3f(snap(cb.x(), g), snap(cb.y(), g), snap(cb.z(), g));
        pa.orientation = random_orientation(rng);
        pb.orientation = random_orientation(rng);
        const auto ia = static_cast<uint32_t>(sc.poses.size());
        sc.shape_of.push_back(z.ids[x]);
        sc.shape_of.push_back(z.ids[y]);
        sc.poses.push_back(pa);
        sc.poses.push_back(pb);
        // Alternate the pair's order so both kernel sides see every kind.
        if (k % 2 == 1 && !z.is_half_space(y))
          sc.pairs.push_back({ia + 1, ia});
        else
          sc.pairs.push_back({ia, ia + 1});
        sc.what.push_back(std::string(z.names[x]) + "-" + z.names[y]);
      }
    }
  }
  return sc;
}

Contact contact_of(const Manifold& m) {
  Contact c;
  c.depth = m.depth;
  c.n = m.normal.cast<double>();
  for (uint32_t j = 0; j < m.point_count; ++j) {
    c.pts.push_back(m.points[j].cast<double>());
    c.pd.push_back(m.point_depth[j]);
  }
  return c;
}

using ManifoldKey = std::tuple<uint32_t, uint32_t, uint32_t>;

std::map<ManifoldKey, Contact> by_key(const std::vector<Manifold>& ms) {
  std::map<ManifoldKey, Contact> m;
  for (const Manifold& x : ms) m[{x.pair, x.child_a, x.child_b}] = contact_of(x);
  return m;
}

/// Compares two runs' manifolds by (pair, child_a, child_b); returns the failures' count
/// (reported, at most 8 of them).
int compare_runs(const std::map<ManifoldKey, Contact>& near, const std::map<ManifoldKey, Contact>& far,
                 const std::vector<Eigen::Vector3d>& T_of_pair, const std::vector<std::string>& what, double size,
                 double mag, double offset, const char* where) {
  const Tolerance tol = Tolerance::of(mag, size, offset);
  int failures = 0;
  std::map<ManifoldKey, std::pair<const Contact*, const Contact*>> all;
  for (const auto& [k, c] : near) all[k].first = &c;
  for (const auto& [k, c] : far) all[k].second = &c;
  const Contact none;
  std::map<std::string, int> per_kind;
  for (const auto& [k, pr] : all) {
    const uint32_t pair = std::get<0>(k);
    const std::string why = compare_hits(pr.first != nullptr, pr.first ? *pr.first : none, pr.second != nullptr,
                                         pr.second ? *pr.second : none, T_of_pair[pair], tol);
    if (why.empty()) continue;
    ++per_kind[what[pair]];
    if (++failures <= 8) {
      ADD_FAILURE() << where << " at " << offset << " m, pair " << pair << " (" << what[pair] << "), children "
                    << static_cast<int64_t>(static_cast<int32_t>(std::get<1>(k))) << ", "
                    << static_cast<int64_t>(static_cast<int32_t>(std::get<2>(k))) << ":" << why;
    }
  }
  if (failures > 0) {
    std::ostringstream o;
    for (const auto& [kind, count] : per_kind) o << " " << kind << ": " << count << ";";
    ADD_FAILURE() << where << " at " << offset << " m, failures by kind:" << o.str();
  }
  return failures;
}

TEST(FarFromOrigin, NarrowPhaseMatchesTheOriginForEveryShapePair) {
  for (double offset : kOffsets) {
    const double g = spacing(offset), s = pair_scale(offset);
    const FarZoo z(s);
    std::mt19937 rng(11 + static_cast<uint32_t>(std::log10(offset)));
    const FarScene sc = far_scene(z, g, test::scaled(12), rng);
    std::vector<Pose> far_poses = sc.poses;
    std::vector<Eigen::Vector3d> T_of_pair(sc.pairs.size());
    for (size_t p = 0; p < sc.pairs.size(); ++p) {
      const Eigen::Vector3d T = translation(offset, static_cast<uint32_t>(p));
      T_of_pair[p] = T;
      for (uint32_t obj : {sc.pairs[p].a, sc.pairs[p].b})
        for (int i = 0; i < 3; ++i)
          far_poses[obj].position[i] = static_cast<float>(sc.poses[obj].position[i] + T[i]);
    }
    for (bool simd : {true, false}) {
      NarrowPhaseOptions opt;
      opt.simd = simd;
      NarrowPhase np(opt);
      std::vector<Manifold> near, far;
      ASSERT_TRUE(IsOk(np.collide(z.set, sc.shape_of, sc.poses, sc.pairs, &near)));
      ASSERT_TRUE(IsOk(np.collide(z.set, sc.shape_of, far_poses, sc.pairs, &far)));
      ASSERT_GT(near.size(), sc.pairs.size() / 4);  // many pairs touch
      // Coordinates at the origin: positions up to ~2.2 s and shapes ~1.4 s about them.
      const int failures = compare_runs(by_key(near), by_key(far), T_of_pair, sc.what, s, 4.0 * s, offset,
                                        simd ? "collide (SIMD)" : "collide (scalar)");
      EXPECT_EQ(failures, 0) << "of " << near.size() << " manifolds";
    }
  }
}

// ---------------------------------------------------------------------------------------
// The World's step
// ---------------------------------------------------------------------------------------

/// One step of a world without gravity from rest: its contacts are those of the bodies
/// as created (the step collides before it moves anything), keyed by (a, b, plane, slot).
std::map<ManifoldKey, Contact> world_contacts(bool shaped, const Eigen::Vector3d& T, double s, double g,
                                              uint32_t bodies, std::mt19937 rng) {
  WorldDesc d;
  d.gravity = Eigen::Vector3f::Zero();
  d.reorder_interval = 0;  // slots stay the creation order in both worlds
  std::unique_ptr<World> w;
  EXPECT_TRUE(IsOk(World::create(d, &w)));
  // Axis planes through T + (offset along the axis), offsets on the grid: exact moves.
  std::vector<PlaneDesc> planes(3);
  const double offs[3] = {-0.75, 1.25, -2.5};
  for (int k = 0; k < 3; ++k) {
    planes[k].normal = Eigen::Vector3f::Zero();
    planes[k].normal[k] = (k == 1) ? -1.0f : 1.0f;
    planes[k].offset = static_cast<float>(planes[k].normal[k] * (T[k] + snap(offs[k] * s, g)));
  }
  std::vector<PlaneHandle> ph(planes.size());
  EXPECT_TRUE(IsOk(w->create_planes(planes, ph)));
  ShapeId box{}, hull{};
  if (shaped) {
    EXPECT_TRUE(IsOk(w->shapes().add_box(Eigen::Vector3f(0.4f, 0.3f, 0.7f) * static_cast<float>(s), &box)));
    std::vector<Eigen::Vector3f> pts;
    std::normal_distribution<float> gn(0.0f, 1.0f);
    std::mt19937 hr(5);
    for (int i = 0; i < 16; ++i)
      pts.push_back(Eigen::Vector3f(gn(hr), gn(hr), gn(hr)).normalized() * static_cast<float>(0.6 * s));
    EXPECT_TRUE(IsOk(w->shapes().add_convex_hull(pts, &hull)));
  }
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<BodyDesc> descs(bodies);
  for (uint32_t i = 0; i < bodies; ++i) {
    BodyDesc& b = descs[i];
    for (int k = 0; k < 3; ++k) b.position[k] = static_cast<float>(T[k] + snap(2.5 * s * u(rng), g));
    b.radius = static_cast<float>(s * (0.3 + 0.4 * (u(rng) + 1.0) / 2.0));
    b.orientation = random_orientation(rng);
    if (shaped && i % 3 != 0) b.shape = (i % 3 == 1) ? box : hull;
  }
  std::vector<BodyHandle> bh(bodies);
  EXPECT_TRUE(IsOk(w->create_bodies(descs, bh)));
  EXPECT_TRUE(IsOk(w->step()));
  const ContactArrays c = w->contacts();
  std::map<ManifoldKey, Contact> out;
  std::map<std::pair<uint32_t, uint32_t>, uint32_t> seen;
  for (size_t m = 0; m < c.size(); ++m) {
    Contact x;
    x.depth = c.depth[m];
    x.n = Eigen::Vector3d(c.normal_x[m], c.normal_y[m], c.normal_z[m]);
    for (size_t p = c.first_point(m); p < c.first_point(m) + c.point_count[m]; ++p) {
      x.pts.emplace_back(c.point_x[p], c.point_y[p], c.point_z[p]);
      x.pd.push_back(c.point_depth[p]);
    }
    const uint32_t b = c.b[m] + (c.b_is_plane[m] ? 0x80000000u : 0u);
    out[{c.a[m], b, seen[{c.a[m], b}]++}] = x;
  }
  return out;
}

TEST(FarFromOrigin, WorldStepMatchesTheOrigin) {
  for (bool shaped : {false, true}) {
    for (double offset : kOffsets) {
      const double g = spacing(offset), s = pair_scale(offset);
      const Eigen::Vector3d T = translation(offset, shaped ? 5 : 2);
      std::mt19937 rng(21 + static_cast<uint32_t>(std::log10(offset)));
      const uint32_t n = test::scaled(64);
      const auto near = world_contacts(shaped, Eigen::Vector3d::Zero(), s, g, n, rng);
      const auto far = world_contacts(shaped, T, s, g, n, rng);
      ASSERT_GT(near.size(), n / 8);
      const std::vector<Eigen::Vector3d> shifts(1, T);
      std::vector<std::string> what(1, shaped ? "world, shaped bodies" : "world, plain spheres");
      std::map<ManifoldKey, Contact> n0, f0;
      for (const auto& [k, c] : near) n0[{0, std::get<0>(k) * 4096 + std::get<2>(k), std::get<1>(k)}] = c;
      for (const auto& [k, c] : far) f0[{0, std::get<0>(k) * 4096 + std::get<2>(k), std::get<1>(k)}] = c;
      EXPECT_EQ(compare_runs(n0, f0, shifts, what, s, 4.0 * s, offset, what[0].c_str()), 0);
    }
  }
}

}  // namespace
}  // namespace impact
