// The narrow phase's kernel contract (kernels/narrowphase/leaf/leaf.h), checked for every
// bucket of the pair-kernel table (kernels/narrowphase/pair_kernels.h), one
// parameterised test per bucket and clause so that a failure names the pair:
//  Registered         pair_kernel(a, b) is the bucket's specialised kernel
//                     (test::specialised_kernels()), or for the general buckets the
//                     general route (the same bytes as collide_gjk_epa /
//                     collide_support_halfspace); the other order (b, a) with a < b is
//                     null (the host orders every pair so that type(A) <= type(B)), as are
//                     half-space/half-space and types out of range.
//  BothOrders         same-type buckets (SameTypeContract): A and B swapped give the same hit and depth
//                     (within the pair's tolerance) and the normal reversed, where the
//                     reference's minimum is unique (else a reversed normal as good as
//                     the reference's).
//  SimdMatchesScalar  the two KernelPaths: the same bytes where the kernel promises
//                     them (same_bytes_buckets() below), else away from touching the same
//                     hit and point count, depths within 1e-6 L, normals within 1e-5 rad of
//                     each other where the minimum is unique (each as good a direction as
//                     the reference's everywhere), the same points in any order within
//                     1e-5 L (plus their slide with the normal and the coordinates'
//                     rounding).
//  PartitionAndShuffle  both paths: every split of the lane range, random partitions into
//                     chunks of 1..13 lanes and lane-by-lane runs give each lane the same
//                     bytes, nothing is written outside the range (or in the padding past
//                     the bucket), and a shuffled bucket gives every lane its own bytes.
//  AgreesWithGjkEpa   the general route on the same lanes (GJK + EPA with SAT off, or the
//                     support-function kernel against a half-space): away from touching
//                     (|s| >= 1e-3 L) the same hit, depth within 1e-3 L, the kernel's depth
//                     no deeper than the general route's (whose support value along its
//                     normal bounds the depth from above) by more than the kernel's
//                     tolerance, its normal separating no worse than the general route's
//                     (support overlap within 1e-3 L), and normals within 0.02 rad where
//                     the reference's minimum is well conditioned (test::well_conditioned
//                     at the kernel's tolerance, the per-kernel tests' rule).
// Tolerances: L = the larger bounding radius; the pair's tolerance rel * L, rel = 1e-4
// for the exact kernels, 1e-3 for the general route (test::kernel_rel_tolerance, the
// matrix test's); kAngleTol = 0.02 rad. Inputs: test::standard_lane_sets (random at
// sizes 1, 1e-4, 1e4 and 1e5 from the origin, deep, coincident, touching, needle and
// pancake boxes, degenerate leaves of every type, many-vertex hulls), a seed per bucket.
// The per-kernel files keep what is special to their pair; the reference itself is
// matrix_test's (every lane against the double reference, both paths).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <initializer_list>
#include <set>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "kernels/narrowphase/pair_kernels.h"
#include "support/lane_checks.h"
#include "support/leaf_lanes.h"
#include "support/narrow_reference.h"
#include "support/pair_input.h"
#include "support/test_support.h"

namespace impact::test {
namespace {

namespace k = kernels;
using kernels::KernelPath;

constexpr double kAngleTol = 0.02;  // rad, where the reference's minimum is unique
// The two paths of a kernel without the same-bytes promise: the same formulas, fused
// multiply-adds contracted differently (measured: depth 2.2e-7 L, normals 4.9e-7 rad).
constexpr double kPathDepthRel = 1e-6;  // of L
constexpr double kPathAngleTol = 1e-5;  // rad, where the reference's minimum is unique
constexpr double kPointRel = 1e-5;      // of L: points and point depths
constexpr double kGeneralRel = 1e-3;    // the general route's depth tolerance, of L

/// Buckets whose kernels promise the same bytes on both paths: those running the same
/// per-lane code for kSimd and kScalar (GJK / EPA and SAT: gjk_epa.cpp, sat.cpp; sphere-
/// and capsule-hull: sphere_convex.cpp, capsule_convex.cpp) and the cylinder kernels
/// compiled without FMA contraction (no_contract.h). The others agree within tolerance.
const std::set<std::pair<LeafType, LeafType>>& same_bytes_buckets() {
  static const std::set<std::pair<LeafType, LeafType>> s = {
      {k::kLeafBox, k::kLeafConvex},        {k::kLeafConvex, k::kLeafConvex},
      {k::kLeafSphere, k::kLeafConvex},     {k::kLeafCapsule, k::kLeafConvex},
      {k::kLeafCapsule, k::kLeafCylinder},  {k::kLeafBox, k::kLeafCylinder},
      {k::kLeafCylinder, k::kLeafCylinder}, {k::kLeafCylinder, k::kLeafEllipsoid},
      {k::kLeafCylinder, k::kLeafTriangle},
  };
  return s;
}

struct Bucket {
  LeafType a, b;
};

void PrintTo(const Bucket& c, std::ostream* os) {
  *os << pair_name(c.a, c.b);
}

std::vector<Bucket> buckets(bool same_type_only = false) {
  std::vector<Bucket> v;
  for (const auto& [a, b] : all_buckets())
    if (!same_type_only || a == b) v.push_back({a, b});
  return v;
}

std::string bucket_name(const ::testing::TestParamInfo<Bucket>& i) {
  return pair_name(i.param.a, i.param.b);
}

const char* path_name(KernelPath p) {
  return p == KernelPath::kSimd ? "simd" : "scalar";
}

class PairContract : public ::testing::TestWithParam<Bucket> {
 protected:
  void SetUp() override {
    const Bucket c = GetParam();
    kern_ = k::pair_kernel(c.a, c.b);
    ASSERT_NE(kern_, nullptr) << pair_name(c.a, c.b) << " has no kernel";
    rel_ = kernel_rel_tolerance(c.a, c.b);
  }

  /// The standard sets of the bucket (one seed per bucket and test).
  std::vector<LaneSet> sets(uint32_t salt, double per = 1.0) {
    const Bucket c = GetParam();
    Rng g(7000u + 97u * salt + 16u * c.a + c.b);
    return standard_lane_sets(c.a, c.b, per, g, bank_, /*extended=*/true);
  }

  double tol(const Lane& l) const { return rel_ * lane_size(l); }

  k::PairKernel kern_ = nullptr;
  double rel_ = 1e-4;
  HullBank bank_;
};

std::string describe(const PairResult& r) {
  std::ostringstream o;
  o.precision(9);
  o << "count " << r.count;
  if (r.count > 0 && r.count <= 4)
    o << " depth " << r.depth << " n {" << r.n.x() << ", " << r.n.y() << ", " << r.n.z() << "}";
  return o.str();
}

V3 v3_of(const Eigen::Vector3d& v) {
  return {v.x(), v.y(), v.z()};
}

/// Every point of r lies within depth/2 + 2 tol (+ 2 ulps) of both surfaces, with
/// -tol <= pdepth <= depth + tol (matrix_test's (d)).
bool points_on_surfaces(const Lane& l, const PairResult& r, double tol) {
  nref::Options light;
  light.samples = 1000;
  light.starts = 3;
  const double lim = 0.5 * std::max(r.depth, 0.0) + 2 * tol +
                     2 * std::max(coord_magnitude(l.sa), coord_magnitude(l.sb)) * std::ldexp(1.0, -23);
  for (uint32_t q = 0; q < r.count && q < 4; ++q) {
    const V3 x{r.pt[q].x(), r.pt[q].y(), r.pt[q].z()};
    if (r.pd[q] < -tol || r.pd[q] > r.depth + tol) return false;
    if (std::fabs(nref::signed_distance(l.sa, x, light)) > lim ||
        std::fabs(nref::signed_distance(l.sb, x, light)) > lim)
      return false;
  }
  return true;
}

/// One float ulp of the lane's largest world coordinate.
double point_ulp(const Lane& l) {
  return std::max(coord_magnitude(l.sa), coord_magnitude(l.sb)) * std::ldexp(1.0, -23);
}

// ---------------------------------------------------------------------------------------

TEST(PairTable, OrderAndRange) {
  // Only a <= b is registered; half-space/half-space and types out of range are null.
  for (uint8_t a = 0; a < k::kLeafTypeCount; ++a)
    for (uint8_t b = 0; b < k::kLeafTypeCount; ++b) {
      const LeafType ta = static_cast<LeafType>(a), tb = static_cast<LeafType>(b);
      const bool registered = a <= b && !(ta == k::kLeafHalfSpace && tb == k::kLeafHalfSpace);
      EXPECT_EQ(k::pair_kernel(ta, tb) != nullptr, registered) << pair_name(ta, tb);
    }
  EXPECT_EQ(k::pair_kernel(k::kLeafTypeCount, k::kLeafSphere), nullptr);
  EXPECT_EQ(k::pair_kernel(k::kLeafSphere, k::kLeafTypeCount), nullptr);
  // The list of specialised kernels names each bucket once, a <= b.
  std::set<std::pair<LeafType, LeafType>> seen;
  for (const SpecialisedKernel& s : specialised_kernels()) {
    EXPECT_LE(s.a, s.b) << s.name;
    EXPECT_TRUE(seen.insert({s.a, s.b}).second) << s.name << " listed twice";
  }
  EXPECT_EQ(seen.size() + 2, all_buckets().size())
      << "every bucket but box-hull and hull-hull is specialised";
}

TEST_P(PairContract, Registered) {
  const Bucket c = GetParam();
  if (c.a < c.b) {
    EXPECT_EQ(k::pair_kernel(c.b, c.a), nullptr) << "only type(A) <= type(B) is registered";
  }
  if (const SpecialisedKernel* s = specialised_kernel(c.a, c.b)) {
    EXPECT_EQ(kern_, s->kernel) << pair_name(c.a, c.b) << " is not routed to " << s->name;
    return;
  }
  for (const SpecialisedKernel& s : specialised_kernels())
    EXPECT_NE(kern_, s.kernel) << pair_name(c.a, c.b) << " is routed to " << s.name;
  // The general route: the table's entry gives collide_gjk_epa's bytes.
  const std::vector<LaneSet> ss = sets(1, 0.5);
  for (const LaneSet& s : ss)
    for (KernelPath path : {KernelPath::kSimd, KernelPath::kScalar}) {
      k::NarrowConfig cfg;
      cfg.path = path;
      cfg.hulls = bank_.hulls.view();
      const auto [la, lb] = leaves_of(s.lanes);
      const uint32_t n = static_cast<uint32_t>(s.lanes.size()), cap = padded_lanes(n);
      const LeafLanes a(la, cap), b(lb, cap);
      ManifoldLanes x(cap), y(cap);
      kern_(a.soa(), b.soa(), x.view(), k::Range{0, n}, cfg);
      collide_general(c.a, c.b, a.soa(), b.soa(), y.view(), k::Range{0, n}, cfg);
      for (uint32_t i = 0; i < n; ++i)
        EXPECT_EQ(x.lane_bits(i), y.lane_bits(i)) << s.what << " [" << path_name(path) << "] lane " << i;
    }
}

/// The same-type buckets, the only ones whose kernel sees both orders of a pair.
class SameTypeContract : public PairContract {};

TEST_P(SameTypeContract, BothOrders) {
  const std::vector<LaneSet> ss = sets(2);
  int compared = 0;
  for (const LaneSet& s : ss)
    for (KernelPath path : {KernelPath::kSimd, KernelPath::kScalar}) {
      const ManifoldLanes ab = run_lanes(kern_, s.lanes, bank_, path),
                          ba = run_lanes(kern_, s.lanes, bank_, path, true);
      int printed = 0;
      for (uint32_t i = 0; i < s.lanes.size(); ++i) {
        const Lane& l = s.lanes[i];
        const double t = tol(l);
        if (std::fabs(l.ref.s) <= t) continue;
        const PairResult x = ab.result(i), y = ba.result(i);
        std::string why;
        if ((x.count > 0) != (y.count > 0)) {
          why = " hit differs when swapped";
        } else if (x.count > 0) {
          ++compared;
          if (std::fabs(x.depth - y.depth) > t) why = " depth differs when swapped";
          const double ang = nref::angle(v3_of(x.n), v3_of(-y.n));
          const double o_swapped = nref::overlap(l.sa, l.sb, nref::normalized(v3_of(-y.n)));
          if (l.ref.unique(2 * t) ? ang > kAngleTol : o_swapped > l.ref.s + t)
            why += " swapped normal is not -n";
        }
        if (!why.empty() && printed++ < 3)
          ADD_FAILURE() << s.what << " [" << path_name(path) << "] lane " << i << ":" << why << "\n"
                        << literal(l, bank_) << "\n    A,B: " << describe(x) << "\n    B,A: " << describe(y);
      }
    }
  EXPECT_GT(compared, 20);
}

TEST_P(PairContract, SimdMatchesScalar) {
  const Bucket c = GetParam();
  const bool bytes = same_bytes_buckets().count({c.a, c.b}) > 0;
  int compared = 0, same = 0, lanes = 0, alternative = 0;
  double worst_depth = 0, worst_angle = 0;
  for (const LaneSet& s : sets(3)) {
    const ManifoldLanes simd = run_lanes(kern_, s.lanes, bank_, KernelPath::kSimd);
    const ManifoldLanes scal = run_lanes(kern_, s.lanes, bank_, KernelPath::kScalar);
    int printed = 0;
    for (uint32_t i = 0; i < s.lanes.size(); ++i) {
      const Lane& l = s.lanes[i];
      const double t = tol(l);
      ++lanes;
      const bool identical = simd.lane_bits(i) == scal.lane_bits(i);
      same += identical;
      std::string why;
      const PairResult x = simd.result(i), y = scal.result(i);
      if (bytes) {
        if (!identical) why = " the paths' bytes differ";
      } else if (x.count > 4 || y.count > 4) {
        why = " count past 4";
      } else if ((x.count > 0) != (y.count > 0)) {
        if (std::fabs(l.ref.s) > t) why = " hit differs";
      } else if (x.count > 0) {
        ++compared;
        const double L = lane_size(l), dd = std::fabs(x.depth - y.depth),
                     ang = nref::angle(v3_of(x.n), v3_of(y.n));
        worst_depth = std::max(worst_depth, dd / L);
        if (dd > kPathDepthRel * L) why += " depths differ by more than 1e-6 L";
        if (l.ref.unique(2 * t)) {
          worst_angle = std::max(worst_angle, ang);
          if (ang > kPathAngleTol) why += " normals differ by more than 1e-5 rad where the minimum is unique";
        }
        for (const PairResult* r : {&x, &y})
          if (nref::overlap(l.sa, l.sb, nref::normalized(v3_of(r->n))) > l.ref.s + t)
            why +=
                std::string(" the ") + (r == &x ? "simd" : "scalar") + " normal is not a minimum direction";
        if (x.count != y.count && std::fabs(l.ref.s) > t) {
          why += " point counts differ";
        } else if (x.count == y.count) {
          // Points are built along the normal: they move with it by up to the size times
          // the normals' difference, plus the world coordinates' rounding. The same set
          // of points, in any order (a tie in the reduction's order may fall either way).
          const double slack = kPointRel * L + L * ang + 2 * point_ulp(l);
          bool used[4] = {false, false, false, false}, found_all = true;
          for (uint32_t q = 0; q < x.count; ++q) {
            bool found = false;
            for (uint32_t r = 0; r < y.count && !found; ++r)
              if (!used[r] && (x.pt[q] - y.pt[r]).norm() <= slack &&
                  std::fabs(x.pd[q] - y.pd[r]) <= kPointRel * L)
                found = used[r] = true;
            found_all = found_all && found;
          }
          // Else another choice among near ties (box vertices scoring alike): both
          // manifolds valid, on a few lanes (primitives_test's bound: 1 in 50).
          if (!found_all) {
            ++alternative;
            if (!points_on_surfaces(l, x, t) || !points_on_surfaces(l, y, t))
              why += " the paths chose different points, not both on the surfaces";
          }
        }
      }
      if (!why.empty() && printed++ < 3)
        ADD_FAILURE() << s.what << " lane " << i << ":" << why << "\n"
                      << literal(l, bank_) << "\n    simd:   " << describe(x)
                      << "\n    scalar: " << describe(y);
    }
  }
  EXPECT_LE(alternative, std::max(1, lanes / 50)) << "lanes whose paths chose different points";
  std::printf(
      "  %-22s lanes %4d same bytes %4d%s | compared %4d worst |depth diff| %.2g L, angle %.2g; other points "
      "%d\n",
      pair_name(c.a, c.b).c_str(), lanes, same, bytes ? " (promised)" : "", compared, worst_depth,
      worst_angle, alternative);
}

TEST_P(PairContract, PartitionAndShuffle) {
  std::vector<Lane> all;
  for (LaneSet& s : sets(4, 0.5)) all.insert(all.end(), s.lanes.begin(), s.lanes.end());
  const uint32_t n = static_cast<uint32_t>(all.size());
  ASSERT_GT(n, 40u);
  Rng g(4242u + n);
  for (KernelPath path : {KernelPath::kSimd, KernelPath::kScalar}) {
    SCOPED_TRACE(path_name(path));
    k::NarrowConfig cfg;
    cfg.path = path;
    const auto run = [&](const std::vector<Lane>& qs, uint32_t begin, uint32_t end) {
      const ManifoldLanes o = run_lanes(kern_, qs, bank_, cfg, begin, end);
      std::vector<std::vector<uint32_t>> bits(qs.size());
      for (uint32_t i = 0; i < o.size(); ++i) {
        if (i >= begin && i < end) {
          bits[i] = o.lane_bits(i);
          EXPECT_LE(o.count[i], 4u) << "lane " << i << " not written or count past 4";
        } else {
          EXPECT_TRUE(o.untouched(i)) << "lane " << i << " written outside the range [" << begin << ", "
                                      << end << ") of " << qs.size();
        }
      }
      return bits;
    };
    const auto same = [](const std::vector<uint32_t>& x, const std::vector<uint32_t>& y) { return x == y; };
    expect_partition_invariant(all, {1u, 3u, 5u, 8u, 11u, 13u, 16u, 36u, 61u, n / 2, n - 1}, run, same, g);
    expect_chunk_invariant(all, run, same, g);
  }
}

TEST_P(PairContract, AgreesWithGjkEpa) {
  const Bucket c = GetParam();
  int compared = 0, lanes = 0, normals = 0;
  double worst_depth = 0, worst_angle = 0;
  for (const LaneSet& s : sets(5)) {
    k::NarrowConfig gcfg;
    gcfg.sat_max_vertices = 0;  // GJK + EPA even for small box / hull pairs
    gcfg.hulls = bank_.hulls.view();
    const auto [la, lb] = leaves_of(s.lanes);
    const uint32_t n = static_cast<uint32_t>(s.lanes.size()), cap = padded_lanes(n);
    const LeafLanes a(la, cap), b(lb, cap);
    ManifoldLanes gj(cap);
    collide_general(c.a, c.b, a.soa(), b.soa(), gj.view(), k::Range{0, n}, gcfg);
    for (KernelPath path : {KernelPath::kSimd, KernelPath::kScalar}) {
      const ManifoldLanes mine = run_lanes(kern_, s.lanes, bank_, path);
      int printed = 0;
      for (uint32_t i = 0; i < n; ++i) {
        const Lane& l = s.lanes[i];
        const double L = lane_size(l), gt = kGeneralRel * L;
        ++lanes;
        if (std::fabs(l.ref.s) < gt) continue;
        const PairResult x = mine.result(i), y = gj.result(i);
        std::string why;
        if ((x.count > 0) != (y.count > 0)) {
          why = " hit differs";
        } else if (x.count > 0) {
          ++compared;
          const double dd = std::fabs(x.depth - y.depth);
          worst_depth = std::max(worst_depth, dd / L);
          if (dd > gt) why += " depth differs by more than 1e-3 L";
          if (x.depth > y.depth + tol(l)) why += " deeper than the general route's upper bound";
          const V3 nx = nref::normalized(v3_of(x.n)), ny = nref::normalized(v3_of(y.n));
          if (nref::overlap(l.sa, l.sb, nx) > nref::overlap(l.sa, l.sb, ny) + gt)
            why += " the kernel's normal separates worse than the general route's";
          if (well_conditioned(l, tol(l))) {
            const double ang = nref::angle(nx, ny);
            worst_angle = std::max(worst_angle, ang);
            ++normals;
            if (ang > kAngleTol) why += " normals differ where the minimum is well conditioned";
          }
        }
        if (!why.empty() && printed++ < 3)
          ADD_FAILURE() << s.what << " [" << path_name(path) << "] lane " << i << ":" << why << "\n"
                        << literal(l, bank_) << "\n    kernel:  " << describe(x)
                        << "\n    general: " << describe(y);
      }
    }
  }
  std::printf("  %-22s lanes %4d compared %4d normals %4d | worst |depth diff| %.2g L, angle %.2g\n",
              pair_name(c.a, c.b).c_str(), lanes, compared, normals, worst_depth, worst_angle);
  EXPECT_GT(compared, lanes / 8);
  EXPECT_GT(normals, compared / 4) << "too few well-conditioned normals compared";
}

/// Found by SimdMatchesScalar's reference clause (cylinder_ellipsoid, random set, lane 13,
/// before the bucket was marked same-bytes): a cylinder through a flat ellipsoid where
/// collide_cylinder_ellipsoid's multi-start solve misses the global minimum of the support
/// overlap: depth 0.536486 along (-0.440, -0.653, -0.616) against the least overlap
/// 0.519370 along (0.177, 0.566, 0.805) (confirmed by 2e5 random directions in double).
/// Disabled until the kernel is fixed (kernels/narrowphase/pairs/cylinder/cylinder_ellipsoid.cpp;
/// --gtest_also_run_disabled_tests runs it).
TEST(KnownMisses, DISABLED_CylinderEllipsoidTakesTheGlobalMinimum) {
  Leaf a, b;
  a.t = k::kLeafCylinder;
  b.t = k::kLeafEllipsoid;
  const float ap[3] = {-0.304256618f, 0.561342537f, 0.626860738f};
  const float ar[9] = {-0.0957207084f, -0.961459756f, -0.257745475f,  -0.0016461882f, 0.259086996f,
                       -0.965852559f,  0.995406866f,  -0.0920277983f, -0.026382735f};
  const float ae[3] = {0.1232327f, 0.297027081f, 0.0f};
  const float bp[3] = {-0.478819937f, 0.47155115f, 0.7963202f};
  const float br[9] = {0.944330752f, -0.0341334678f, 0.327222198f,  -0.202874303f, 0.722578883f,
                       0.660849273f, -0.259000927f,  -0.690445304f, 0.675428629f};
  const float be[3] = {0.693425834f, 0.840815246f, 0.247810468f};
  std::copy(ap, ap + 3, a.p), std::copy(ar, ar + 9, a.r), std::copy(ae, ae + 3, a.e);
  std::copy(bp, bp + 3, b.p), std::copy(br, br + 9, b.r), std::copy(be, be + 3, b.e);
  HullBank w;
  const Lane l = make_lane(a, b, w);
  ASSERT_NEAR(l.ref.s, 0.519369643, 1e-6);
  for (KernelPath path : {KernelPath::kSimd, KernelPath::kScalar}) {
    const PairResult r = run_lanes(k::pair_kernel(a.t, b.t), {l}, w, path).result(0);
    ASSERT_EQ(r.count, 1u) << path_name(path);
    EXPECT_NEAR(r.depth, l.ref.s, 1e-4 * lane_size(l)) << path_name(path);
  }
}

INSTANTIATE_TEST_SUITE_P(Table, PairContract, ::testing::ValuesIn(buckets()), bucket_name);
INSTANTIATE_TEST_SUITE_P(Table, SameTypeContract, ::testing::ValuesIn(buckets(true)), bucket_name);

}  // namespace
}  // namespace impact::test
