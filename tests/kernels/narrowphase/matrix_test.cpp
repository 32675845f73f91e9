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
// (test::specialised_kernels(), tests/support/pair_input.h) and box-hull, whose SAT
// box-hull route is exact: sat.cpp; 1e-3 for the general GJK/EPA route (100x
// cfg.epa_tolerance; test::kernel_rel_tolerance); the inputs
// are exact floats, so poses far from the origin get no extra depth tolerance; contact
// points, being world floats, get one ulp of the largest coordinate on top (0.008 at 1e5).
//
// Scenarios per pair (test::standard_lane_sets): random poses and sizes (about half
// overlapping), tiny (1e-4) and huge (1e4) shapes, poses 1e5 from the origin, deep
// penetration, coincident centres, touching (B moved by the reference's s*n), needle
// (1 x 1e-4 x 1e-4) and pancake (1 x 1 x 1e-4) boxes in every box pair; here also
// near-parallel capsules and box-box with near-parallel edges; no writes past the range.
// Also: boxes through SAT, through collide_gjk_epa and as 8-vertex hulls agree; exact
// touching gives count 0. Registration, the two paths, range partitions and shuffles,
// the swapped order and the GJK / EPA agreement are contract_test.cpp's.
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

#include "kernels/narrowphase/pair_kernels.h"
#include "support/narrow_reference.h"
#include "support/pair_input.h"
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
// Rotations
// ---------------------------------------------------------------------------------------

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

// ---------------------------------------------------------------------------------------
// The per-lane check
// ---------------------------------------------------------------------------------------

/// Depth / normal tolerance: relative to the shapes' size only (the inputs are exact
/// floats and the kernels work relative to A's position, so poses 1e5 from the origin
/// must not cost accuracy).
double lane_tol(const Lane& l, double rel) { return rel * std::max(l.sa.bound_radius(), l.sb.bound_radius()); }

/// Contact points are world floats: one ulp of the largest coordinate on top.
double point_slack(const Lane& l) {
  return std::max(coord_magnitude(l.sa), coord_magnitude(l.sb)) * std::ldexp(1.0, -23);
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

KernelLane read_lane(const ManifoldLanes& o, uint32_t i) {
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

ManifoldLanes run(k::PairKernel kern, const std::vector<Lane>& lanes, const HullBank& w, k::KernelPath path) {
  return run_lanes(kern, lanes, w, path);
}

const char* path_name(k::KernelPath p) { return p == k::KernelPath::kSimd ? "simd" : "scalar"; }

/// Runs both paths over the lanes and checks every lane; failures go to the test log.
void check_all(k::PairKernel kern, const std::vector<Lane>& lanes, const HullBank& w, double rel,
               const std::string& what, bool deep_checks = true) {
  for (k::KernelPath path : {k::KernelPath::kScalar, k::KernelPath::kSimd}) {
    const ManifoldLanes out = run(kern, lanes, w, path);
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
    for (uint32_t i = static_cast<uint32_t>(lanes.size()); i < out.size(); ++i)
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
  return pair_name(c.a, c.b);
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
  for (const auto& [a, b] : all_buckets())
    if (known_failing(PairCase{a, b}) == failing) v.push_back(PairCase{a, b});
  return v;
}

bool known_failing(const PairCase& c) {
  static const char* const kNames[] = {""};  // none today
  const std::string name = case_name(c);
  for (const char* n : kNames)
    if (name == n) return true;
  return false;
}

class PairMatrix : public ::testing::TestWithParam<PairCase> {};

TEST_P(PairMatrix, AgainstReference) {
  const PairCase pc = GetParam();
  const k::PairKernel kern = k::pair_kernel(pc.a, pc.b);
  ASSERT_NE(kern, nullptr);
  const double rel = kernel_rel_tolerance(pc.a, pc.b);
  const std::string name = case_name(pc);
  Rng g(1000u + 16u * pc.a + pc.b);
  HullBank w;
  // All lane sets are made first: HullStore may reallocate while hulls are added.
  std::vector<LaneSet> sets = standard_lane_sets(pc.a, pc.b, 1.0, g, w);
  if (pc.a == k::kLeafCapsule && pc.b == k::kLeafCapsule) {
    std::vector<Lane> par;
    const double angles[] = {0.0, 1e-7, 1e-6, 1e-5, 1e-4, 1e-3};
    for (uint32_t i = 0; i < scaled(18); ++i) {
      Leaf a = make_leaf(k::kLeafCapsule, {uni(g, -1, 1), uni(g, -1, 1), uni(g, -1, 1)}, 1.0, g, w);
      Leaf b = make_leaf(k::kLeafCapsule, {0, 0, 0}, 1.0, g, w);
      const nref::Shape sa = ref_shape(a, w);
      const V3 u = sa.col(2);
      const V3 perp = nref::normalized(nref::cross(u, random_unit_v3(g)));
      double rot[9], ra9[9], rb9[9];
      axis_angle(perp, angles[i % 6], rot);
      for (int j = 0; j < 9; ++j) ra9[j] = a.r[j];
      mat_mul(rot, ra9, rb9);
      set_rotation(b, rb9);
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
      Leaf a = make_leaf(k::kLeafBox, {uni(g, -1, 1), uni(g, -1, 1), uni(g, -1, 1)}, 1.0, g, w);
      Leaf b = make_leaf(k::kLeafBox, {0, 0, 0}, 1.0, g, w);
      const nref::Shape sa = ref_shape(a, w);
      double rot[9], ra9[9], rb9[9];
      axis_angle(random_unit_v3(g), angles[i % 4], rot);
      for (int j = 0; j < 9; ++j) ra9[j] = a.r[j];
      mat_mul(ra9, rot, rb9);
      set_rotation(b, rb9);
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
  for (const LaneSet& s : sets) check_all(kern, s.lanes, w, rel, s.what);
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
  std::vector<Lane> lanes = random_lanes(pc.a, pc.b, scaled(48), 1.0, 0.0, 0.0, 1.1, g, w);
  // The same boxes as convex hulls (local corners, same pose).
  std::vector<Lane> hl;
  for (const Lane& l : lanes) {
    Leaf a = l.a, b = l.b;
    for (Leaf* x : {&a, &b}) {
      x->t = k::kLeafConvex;
      x->ref = w.add_hull(corners(x->e[0], x->e[1], x->e[2]));
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
  const ManifoldLanes sat = run(k::pair_kernel(k::kLeafBox, k::kLeafBox), lanes, w, k::KernelPath::kScalar);
  const ManifoldLanes gjk = run(gjk_boxes, lanes, w, k::KernelPath::kScalar);
  const ManifoldLanes hul =
      run(k::pair_kernel(k::kLeafConvex, k::kLeafConvex), hl, w, k::KernelPath::kScalar);
  for (uint32_t i = 0; i < lanes.size(); ++i) {
    const double tol = lane_tol(lanes[i], 1e-3);
    if (std::fabs(lanes[i].ref.s) <= tol) continue;
    for (const ManifoldLanes* o : {&gjk, &hul}) {
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
    Leaf l;
    l.t = t;
    std::copy(p.begin(), p.end(), l.p);
    std::copy(e.begin(), e.end(), l.e);
    return l;
  };
  auto along_x = [](Leaf l) {  // axis z -> x: R columns (0,0,-1)? use x = R col 2
    const float r[9] = {0, 0, 1, 0, 1, 0, -1, 0, 0};
    std::copy(r, r + 9, l.r);
    return l;
  };
  auto tri = [](std::initializer_list<float> v) {
    Leaf l;
    l.t = k::kLeafTriangle;
    std::vector<float> x(v);
    for (int j = 0; j < 3; ++j) l.p[j] = x[static_cast<size_t>(j)];
    for (int j = 0; j < 6; ++j) l.w[j] = x[static_cast<size_t>(3 + j)];
    return l;
  };
  struct Case {
    Leaf a, b;
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
    const bool spec = kernel_rel_tolerance(c.a.t, c.b.t) < 1e-3;  // an exact kernel
    const Lane l = make_lane(c.a, c.b, w);
    ASSERT_NEAR(l.ref.s, 0.0, 1e-12) << "case " << i << " is not touching by the reference";
    for (k::KernelPath path : {k::KernelPath::kScalar, k::KernelPath::kSimd}) {
      const ManifoldLanes o = run(k::pair_kernel(c.a.t, c.b.t), {l}, w, path);
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
