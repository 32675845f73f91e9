// Checks shared by the per-kernel narrow-phase tests (one pair type per file, against
// their own double references): pairs built with known collision data, and the scales
// every random-pose suite runs at.
//   Built<Q>       a test's pair struct with its built depth and normal
//   expect_built   a kernel's answers against the built ones (hit, depth, normal)
//   expect_touching_after_push  overlapping pairs moved apart by the reference: touching
//   run_table_kernel  the pair-kernel table's entry for a bucket over a test's pairs
//   kernel_scales  (size, offset from the origin): 1, 1e-4, 1e4, and 1 at 1e5
//   scale_seed / random_pose_suite  one random-pose suite at one of those scales, and
//                  the coverage it asks of its lanes (SuiteCoverage)
//   expect_built_on_both_paths  expect_built on the SIMD and the scalar path
//   expect_feature_pairs  a built-feature case: the feature's normal on most meeting
//                  lanes, a contact on exactly those
//   check_lanes    every lane of a bucket on both paths against the test's reference
//                  (PairModel: its reference, surfaces, support overlap and distance)
//   check_lanes_on_both_paths  check_lanes of a test's run(queries, path)
//   check_built_features  pairs built to meet (or just miss) at a feature pair: the
//                  test's check and its reference against the construction
//   expect_line_contact  a two-point contact along a coordinate axis (a side line lying
//                  on a face, an edge along a side) against its closed form
//   expect_thin_pairs_meet  needle and pancake pairs: checked, and a fifth of them meet
//   expect_all_meet  pairs that all meet: checked, every one a contact
#pragma once

#include <gtest/gtest.h>

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <functional>
#include <limits>
#include <random>
#include <string>
#include <tuple>
#include <type_traits>
#include <vector>

#include "kernels/narrowphase/pair_kernels.h"
#include "support/leaf_lanes.h"
#include "support/shape_geometry.h"

namespace impact::test {

/// A pair built in closed form: depth (> 0 overlapping, else minus the distance) and the
/// normal from A to B.
template <class Q>
struct Built {
  Q q;
  double depth = 0;
  Eigen::Vector3d n = Eigen::Vector3d::UnitZ();
};

template <class Q>
std::vector<Q> queries_of(const std::vector<Built<Q>>& ts) {
  std::vector<Q> qs;
  for (const Built<Q>& t : ts) qs.push_back(t.q);
  return qs;
}

/// The kernel's answers hs[k] for the built pairs ts[k], tol = rel * size_of(q): where
/// |depth| <= tol (touching) a contact no deeper than depth + tol; else a contact iff
/// depth > 0, its depth within tol and its normal within angle_tol(k, L) rad of the
/// built one. Prints a line of the worst errors; returns the contacts checked.
template <class Q, class Size, class AngleTol>
int expect_built(const std::vector<Built<Q>>& ts, const std::vector<PairResult>& hs, double rel, Size size_of,
                 AngleTol angle_tol, const char* what) {
  int hits = 0;
  double worst = 0, worst_angle = 0;
  for (size_t k = 0; k < ts.size(); ++k) {
    const double L = size_of(ts[k].q), tol = rel * L;
    const PairResult& h = hs[k];
    if (std::fabs(ts[k].depth) <= tol) {
      if (h.count) {
        EXPECT_LE(h.depth, ts[k].depth + tol) << what << " " << k;
      }
      continue;
    }
    EXPECT_EQ(h.count > 0, ts[k].depth > 0) << what << " " << k << " depth " << ts[k].depth;
    if (h.count == 0 || ts[k].depth <= 0) continue;
    ++hits;
    const double ang = angle(h.n, ts[k].n);
    worst = std::max(worst, std::fabs(h.depth - ts[k].depth) / L);
    worst_angle = std::max(worst_angle, ang);
    EXPECT_NEAR(h.depth, ts[k].depth, tol) << what << " " << k << " kind " << k % 3;
    EXPECT_LE(ang, angle_tol(k, L)) << what << " " << k << " kind " << k % 3 << " n " << h.n.transpose()
                                    << " want " << ts[k].n.transpose() << " depth " << h.depth << " want "
                                    << ts[k].depth << " (L " << L << ")";
  }
  std::printf("  %s: hits %d, worst depth %.2g L, angle %.2g\n", what, hits, worst, worst_angle);
  return hits;
}

/// Up to `want` pairs drawn by draw(g) (in at most `attempts` draws) that overlap by more
/// than 1e-3 by reference(q) (a struct with depth and n), B moved apart by that depth
/// along n by move_b(q, shift) (rounding to float): touching up to rounding, so a contact
/// that run(qs) still reports must be no deeper than 4 rel size_of(q).
template <class Draw, class Reference, class Move, class Run, class Size>
void expect_touching_after_push(std::mt19937& g, int want, int attempts, Draw draw, Reference reference,
                                Move move_b, Run run, Size size_of, double rel) {
  using Q = decltype(draw(g));
  std::vector<Q> qs;
  for (int i = 0; i < attempts && static_cast<int>(qs.size()) < want; ++i) {
    Q q = draw(g);
    const auto f = reference(q);
    if (f.depth <= 1e-3) continue;
    move_b(q, Eigen::Vector3d(f.depth * f.n));
    qs.push_back(q);
  }
  const std::vector<PairResult> res = run(qs);
  for (size_t k = 0; k < qs.size(); ++k) {
    if (res[k].count > 0) {
      EXPECT_LE(res[k].depth, 4 * rel * size_of(qs[k])) << "pushed-apart lane " << k;
    }
  }
}

/// The table's kernel for the bucket (ta, tb), which must be `want`, over all of qs
/// (run_queries: leaves(q) gives a pair's two Leafs).
template <class Q, class Leaves>
std::vector<PairResult> run_table_kernel(kernels::LeafType ta, kernels::LeafType tb, kernels::PairKernel want,
                                         const std::vector<Q>& qs, kernels::KernelPath path, Leaves leaves) {
  const kernels::PairKernel k = kernels::pair_kernel(ta, tb);
  EXPECT_EQ(k, want);
  return run_queries(k, qs, path, leaves);
}

/// (size, offset from the origin) of the random-pose suites: sizes 1, 1e-4 and 1e4 at the
/// origin, and size 1 at 1e5 from it.
inline std::vector<std::tuple<double, double>> kernel_scales() {
  return {std::make_tuple(1.0, 0.0), std::make_tuple(1e-4, 0.0), std::make_tuple(1e4, 0.0),
          std::make_tuple(1.0, 1e5)};
}

/// The seed of a random-pose suite at (size, offset): base, shifted by the size's decade
/// and by 10 away from the origin, so each scale draws its own lanes.
inline uint32_t scale_seed(uint32_t base, double size, double offset) {
  return static_cast<uint32_t>(base + std::lround(std::log10(size)) + (offset > 0 ? 10 : 0));
}

/// An angle tolerance for expect_built that is the same for every pair: angle rad.
inline auto every_pair_angle_tol(double angle) {
  return [angle](size_t, double) { return angle; };
}

/// Built pairs ts on both kernel paths: run(queries, path) against them by expect_built;
/// each path must check more than a quarter of them as contacts.
template <class Q, class Run, class Size, class AngleTol>
void expect_built_on_both_paths(const std::vector<Built<Q>>& ts, Run run, double rel, Size size_of,
                                AngleTol angle_tol, const char* what) {
  for (kernels::KernelPath path : {kernels::KernelPath::kSimd, kernels::KernelPath::kScalar}) {
    const int hits = expect_built(ts, run(queries_of(ts), path), rel, size_of, angle_tol, what);
    EXPECT_GT(hits, static_cast<int>(ts.size()) / 4) << what;
  }
}

/// A lane's reference, the test's own: depth (> 0 overlapping, else minus the distance),
/// the normal from A to B, whether it is the unique minimum (normals are held to it
/// there, within angle_tol), a test-defined class of the lane (counted, printed), and
/// whether the pair is apart (the distance in closed form, not refined by `improve`).
struct LaneRef {
  double depth = 0;
  Eigen::Vector3d n = Eigen::Vector3d::UnitZ();
  bool unique = false;
  double angle_tol = 0;
  bool flag = false;
  bool apart = false;
};

/// What check_lanes saw: lanes, contacts (SIMD path), lanes by point count, flagged
/// contacts, normals held to the reference, references refined, the worst errors.
struct LaneStats {
  int lanes = 0, hits = 0, flagged = 0, normals_checked = 0, improved = 0;
  int counts[5] = {0, 0, 0, 0, 0};
  double worst_depth = 0, worst_angle = 0;  // of L; rad
  size_t worst_depth_lane = 0, worst_angle_lane = 0;
};

/// What a random-pose suite asks of its lanes besides hits > n / 4 (0: not asked):
/// hits < n * max_hit_tenths / 10, flagged > n / flagged_div, and normals_checked >
/// hits / normals_div.
struct SuiteCoverage {
  int max_hit_tenths = 0;
  int flagged_div = 0;
  int normals_div = 0;
};

/// One random-pose suite: n pairs drawn by draw(g, n, size, offset) from g(seed), checked
/// by check(pairs, "random", &stats) (the test's check_all), then the coverage c.
template <class Draw, class Check>
void random_pose_suite(uint32_t seed, int n, double size, double offset, Draw draw, Check check,
                       SuiteCoverage c) {
  std::mt19937 g(seed);
  LaneStats st;
  check(draw(g, n, size, offset), "random", &st);
  EXPECT_GT(st.hits, n / 4);
  if (c.max_hit_tenths > 0) {
    EXPECT_LT(st.hits, n * c.max_hit_tenths / 10);
  }
  if (c.flagged_div > 0) {
    EXPECT_GT(st.flagged, n / c.flagged_div);
  }
  if (c.normals_div > 0) {
    EXPECT_GT(st.normals_checked, st.hits / c.normals_div);
  }
}

/// The same at scale = (size, offset), one of kernel_scales() (a TEST_P's GetParam()).
template <class Draw, class Check>
void random_pose_suite(const std::tuple<double, double>& scale, uint32_t seed, int n, Draw draw, Check check,
                       SuiteCoverage c) {
  random_pose_suite(seed, n, std::get<0>(scale), std::get<1>(scale), draw, check, c);
}

/// Needle and pancake pairs qs (one shape or both thinned to about 1e-4 of their size)
/// run by the test's check_all(qs, what, stats): more than a fifth of them meet.
template <class Q, class CheckAll>
void expect_thin_pairs_meet(const std::vector<Q>& qs, CheckAll check_all) {
  LaneStats st;
  check_all(qs, "needle / pancake", &st);
  EXPECT_GT(st.hits, static_cast<int>(qs.size()) / 5);
}

/// Pairs that all meet (coincident centres, a centre on the other shape) run by the
/// test's check_all(qs, what, stats): every one a contact. Returns the statistics.
template <class Q, class CheckAll>
LaneStats expect_all_meet(const std::vector<Q>& qs, CheckAll check_all, const char* what) {
  LaneStats st;
  check_all(qs, what, &st);
  EXPECT_EQ(st.hits, static_cast<int>(qs.size())) << what;
  return st;
}

/// A built-feature case: check_built(&stats, &meeting) runs pairs built to meet (or just
/// miss) at one feature pair and returns how many meeting lanes got that pair's normal;
/// at least 3/4 of them must, and exactly the meeting lanes must report a contact.
/// Returns the case's stats.
template <class CheckBuilt>
LaneStats expect_feature_pairs(CheckBuilt check_built) {
  LaneStats st;
  int meeting = 0;
  const int on = check_built(&st, &meeting);
  EXPECT_GE(on, meeting * 3 / 4);
  EXPECT_EQ(st.hits, meeting);
  return st;
}

/// The two surface points of a single-point contact h: pt[0] + n depth/2 (on A's
/// surface) and pt[0] - n depth/2 (on B's).
struct ContactSides {
  Eigen::Vector3d on_a, on_b;
};
inline ContactSides contact_sides(const PairResult& h) {
  return {h.pt[0] + h.n * (0.5 * h.depth), h.pt[0] - h.n * (0.5 * h.depth)};
}

/// How a contact's points must carry the depth: a single point exactly, the deepest
/// within tol of it, or no rule (a degenerate triangle's point may lie shallower).
enum class Carries { kSinglePointExact, kDeepestWithinTol, kNoRule };

/// What a per-kernel test knows of its pairs Q (rounded to float already), for
/// check_lanes. The functions taking a point or a shift are in the world frame.
template <class Q>
struct PairModel {
  double rel = 1e-5;                ///< depth tolerance, of L
  uint32_t max_points = 4;          ///< the kernel's most contact points
  const char* flag_name = nullptr;  ///< printed name of LaneRef::flag ("core inside")
  Carries carries = Carries::kSinglePointExact;
  std::function<LaneRef(const Q&)> reference = {};
  std::function<double(const Q&)> size = {};       ///< L: the larger bounding radius
  std::function<double(const Q&)> coord_ulp = {};  ///< one ulp of the largest coordinate
  /// The support overlap h_A(n) + h_B(-n) along n (any length).
  std::function<double(const Q&, const Eigen::Vector3d&)> overlap = {};
  /// Signed distances to A's and B's surfaces (< 0 inside).
  std::function<double(const Q&, const Eigen::Vector3d&)> sd_a = {}, sd_b = {};
  /// > 0: the distance between A and B moved by shift; <= 0: they meet (the translation check).
  std::function<double(const Q&, const Eigen::Vector3d&)> apart = {};
  /// Optional: the default point check's allowance beyond ptol for the point on A's
  /// (b_side false) or B's surface, e.g. the slide of a curved side's support point
  /// under the normal's error; < 0 leaves that side unchecked (where only the other side
  /// is known exactly).
  std::function<double(const Q&, const LaneRef&, const PairResult&, bool b_side)> side_slack = {};
  /// Optional: a check of a contact's points replacing the default (points_on_surfaces).
  std::function<void(const Q&, const LaneRef&, const PairResult&, double tol, double ptol,
                     const std::string& where)>
      points = {};
  /// Optional: whether a normal ang rad from a unique reference's is acceptable, replacing
  /// ang <= angle_tol.
  std::function<bool(const Q&, const LaneRef&, const PairResult&, double ang)> normal_ok = {};
  /// Optional: refines the reference from a kernel answer (a basin its sampling missed).
  std::function<void(const Q&, LaneRef&, const PairResult&, LaneStats&)> improve = {};
  /// Optional: the lane as C++ literals, for failure messages.
  std::function<std::string(const Q&)> literal = {};
  bool apart_at_most_d = false;  ///< the translation check also bounds the distance above
  /// The two paths give the same bytes; else (kernels whose two widths contract
  /// differently) depths within tol and, where unique, normals within angle_tol.
  bool same_bytes_paths = true;
  double point_ulps = 4;  ///< ptol = tol + this many ulps of the coordinates
};

/// The default point check: each point finite, 0 < pdepth <= depth (+ tol for
/// kDeepestWithinTol), point +- n pdepth/2 on A's / B's surface within ptol (+ the
/// model's side_slack; a side with a negative one unchecked); the depth carried as
/// `carries` says.
template <class Q>
void points_on_surfaces(const PairModel<Q>& m, const Q& q, const LaneRef& f, const PairResult& h, double tol,
                        double ptol, const std::string& where) {
  const double slack = m.carries == Carries::kDeepestWithinTol ? tol : 0.0;
  const double slack_a = m.side_slack ? m.side_slack(q, f, h, false) : 0.0,
               slack_b = m.side_slack ? m.side_slack(q, f, h, true) : 0.0;
  double deepest = -std::numeric_limits<double>::infinity();
  for (uint32_t i = 0; i < h.count; ++i) {
    ASSERT_TRUE(h.pt[i].allFinite()) << where;
    EXPECT_GT(h.pd[i], 0.0) << where << " point " << i;
    EXPECT_LE(h.pd[i], h.depth + slack) << where << " point " << i;
    deepest = std::max(deepest, h.pd[i]);
    const Eigen::Vector3d on_a = h.pt[i] + 0.5 * h.pd[i] * h.n, on_b = h.pt[i] - 0.5 * h.pd[i] * h.n;
    if (slack_a >= 0) {
      EXPECT_LE(std::fabs(m.sd_a(q, on_a)), ptol + slack_a) << where << " point " << i << " off A";
    }
    if (slack_b >= 0) {
      EXPECT_LE(std::fabs(m.sd_b(q, on_b)), ptol + slack_b) << where << " point " << i << " off B";
    }
  }
  if (m.carries == Carries::kDeepestWithinTol) {
    EXPECT_GE(deepest, h.depth - tol) << where << ": no point carries the depth";
  } else if (m.carries == Carries::kSinglePointExact && h.count == 1) {
    EXPECT_EQ(h.pd[0], h.depth) << where;
  }
}

/// Every lane of qs on both paths (simd, scal: the kernel's answers), L = m.size(q),
/// tol = m.rel L, ptol = tol + 4 ulps of the coordinates:
///  (a) count <= m.max_points; away from touching (|depth_ref| > tol) a contact iff
///      depth_ref > 0;
///  (b) |depth - depth_ref| <= tol;
///  (c) n finite and unit, as good a direction as the reference's (overlap along n <=
///      depth_ref + tol), within angle_tol of n_ref where the reference is unique;
///  (d) the points (m.points, or points_on_surfaces);
///  (e) the two paths give the same bytes (or agree within tol and angle_tol);
///  and, given m.apart, the translation check by it alone: B moved by n (depth + d), d = depth / 20,
///  is apart by at least d - 2 tol (and at most d + 2 tol with m.apart_at_most_d), moved
///  by n (depth - d) still meets A (contacts deeper than 20 tol).
/// Prints one line of statistics under `what`.
template <class Q>
LaneStats check_lanes(const PairModel<Q>& m, const std::vector<Q>& qs, const std::vector<PairResult>& simd,
                      const std::vector<PairResult>& scal, const char* what) {
  SCOPED_TRACE(what);
  LaneStats st;
  for (size_t k = 0; k < qs.size(); ++k) {
    const Q& q = qs[k];
    const std::string lane = std::string(what) + " lane " + std::to_string(k);
    SCOPED_TRACE(m.literal ? "lane " + std::to_string(k) + " as C++: " + m.literal(q) : std::string());
    LaneRef f = m.reference(q);
    const double L = m.size(q), tol = m.rel * L, ptol = tol + m.point_ulps * m.coord_ulp(q);
    ++st.lanes;
    if (m.improve)
      for (const PairResult* h : {&simd[k], &scal[k]}) m.improve(q, f, *h, st);
    // (a)-(d) on one path; an ASSERT ends that path's checks of the lane
    auto check_path = [&](const PairResult& h, bool is_simd) {
      const std::string where = lane + (is_simd ? " simd" : " scalar");
      ASSERT_LE(h.count, m.max_points) << where;
      if (std::fabs(f.depth) <= tol) return;
      ASSERT_EQ(h.count > 0, f.depth > 0)
          << where << " depth_ref " << f.depth << " got " << (h.count > 0 ? h.depth : 0.0);
      if (f.depth <= 0) return;
      if (is_simd) {
        ++st.hits;
        st.flagged += f.flag;
        ++st.counts[h.count];
      }
      const double dd = std::fabs(h.depth - f.depth);
      if (dd / L > st.worst_depth) st.worst_depth = dd / L, st.worst_depth_lane = k;
      EXPECT_LE(dd, tol) << where << " depth " << h.depth << " ref " << f.depth << " ("
                         << (h.depth - f.depth) / L << " L)";
      ASSERT_TRUE(h.n.allFinite()) << where;
      EXPECT_NEAR(h.n.norm(), 1.0, 1e-6) << where;
      EXPECT_LE(m.overlap(q, h.n), f.depth + tol) << where << ": n is not a minimum direction";
      if (f.unique) {
        const double ang = angle(h.n, f.n);
        if (is_simd) ++st.normals_checked;
        if (ang > st.worst_angle) st.worst_angle = ang, st.worst_angle_lane = k;
        EXPECT_TRUE(m.normal_ok ? m.normal_ok(q, f, h, ang) : ang <= f.angle_tol)
            << where << " angle " << ang << " n " << h.n.transpose() << " ref " << f.n.transpose()
            << " overlap - ref " << m.overlap(q, h.n) - f.depth;
      }
      if (m.points)
        m.points(q, f, h, tol, ptol, where);
      else
        points_on_surfaces(m, q, f, h, tol, ptol, where);
    };
    check_path(simd[k], true);
    check_path(scal[k], false);
    if (m.same_bytes_paths) {
      EXPECT_TRUE(same_bytes(simd[k], scal[k])) << lane << ": the SIMD and scalar paths differ";
    } else if (std::fabs(f.depth) > tol && simd[k].count && scal[k].count) {
      EXPECT_LE(std::fabs(simd[k].depth - scal[k].depth), tol)
          << lane << ": the SIMD and scalar depths differ";
      if (f.unique) {
        EXPECT_LE(angle(simd[k].n, scal[k].n), f.angle_tol) << lane << ": the SIMD and scalar normals differ";
      }
    }
    const PairResult& h = simd[k];
    if (m.apart && h.count > 0 && h.count <= m.max_points && h.depth > 20 * tol && h.n.allFinite()) {
      const double d = 0.05 * h.depth;
      const Eigen::Vector3d n = h.n.normalized();
      const double apart = m.apart(q, (h.depth + d) * n);
      EXPECT_GE(apart, d - 2 * tol) << lane << ": moved by n (depth + d) not apart by d";
      if (m.apart_at_most_d) {
        EXPECT_LE(apart, d + 2 * tol) << lane << ": moved by n (depth + d) apart by more than d";
      }
      EXPECT_LT(m.apart(q, (h.depth - d) * n), 0.0) << lane << ": moved by n (depth - d) already apart";
    }
  }
  std::printf("  %-28s lanes %4d hits %4d", what, st.lanes, st.hits);
  if (m.flag_name != nullptr) std::printf(" %s %4d", m.flag_name, st.flagged);
  std::printf(" points 1/2/3/4 %d/%d/%d/%d normals %4d", st.counts[1], st.counts[2], st.counts[3],
              st.counts[4], st.normals_checked);
  if (m.improve) std::printf(" ref improved %d", st.improved);
  std::printf(" | worst |depth-ref| %.2g L (lane %zu), angle %.2g rad (lane %zu)\n", st.worst_depth,
              st.worst_depth_lane, st.worst_angle, st.worst_angle_lane);
  return st;
}

/// check_lanes of run(qs, KernelPath::kSimd) and run(qs, KernelPath::kScalar) (a test's
/// kernel call); the stats go to *out_stats when given.
template <class Q, class Run>
void check_lanes_on_both_paths(const PairModel<Q>& m, const std::vector<Q>& qs, Run run, const char* what,
                               LaneStats* out_stats) {
  const LaneStats st =
      check_lanes(m, qs, run(qs, kernels::KernelPath::kSimd), run(qs, kernels::KernelPath::kScalar), what);
  if (out_stats != nullptr) *out_stats = st;
}

/// Feature pairs built in closed form: n lanes b = build(i) (each with b.q, the pair;
/// b.delta, > 0 the overlap along b.n, < 0 minus the distance; b.n from A to B) run by
/// check_all(queries, what, st), then reference(b.q) (a struct with apart, depth, n)
/// against the construction: apart lanes (delta < 0) apart, at depth delta within 1e-6
/// and n within apart_angle rad (the built points are each other's closest points);
/// meeting ones no deeper than delta + 1e-6 (the overlap along n); more than a quarter
/// apart. literal(b.q), if given, names a lane in failures. Sets *meeting_lanes and
/// returns how many meeting lanes have their minimum at the built pair (depth delta
/// within 1e-6, n within 1e-4 rad).
template <class Build, class CheckAll, class Reference, class Literal = std::nullptr_t>
int check_built_features(int n, Build build, CheckAll check_all, Reference reference, const char* what,
                         LaneStats* st, int* meeting_lanes, double apart_angle = 1e-4,
                         Literal literal = nullptr) {
  using B = decltype(build(0));
  std::vector<B> bs;
  std::vector<decltype(B::q)> qs;
  for (int i = 0; i < n; ++i) {
    bs.push_back(build(i));
    qs.push_back(bs.back().q);
  }
  check_all(qs, what, st);
  int on_feature = 0, apart = 0;
  *meeting_lanes = 0;
  for (size_t k = 0; k < bs.size(); ++k) {
    std::string trace;
    if constexpr (!std::is_same_v<Literal, std::nullptr_t>) {
      trace = "lane " + std::to_string(k) + " as C++: " + literal(bs[k].q);
    }
    SCOPED_TRACE(trace);
    const auto r = reference(bs[k].q);
    if (bs[k].delta < 0) {
      ++apart;
      EXPECT_TRUE(r.apart) << what << " lane " << k;
      EXPECT_NEAR(r.depth, bs[k].delta, 1e-6) << what << " lane " << k;
      EXPECT_LT(angle(r.n, bs[k].n), apart_angle) << what << " lane " << k;
    } else {
      ++*meeting_lanes;
      EXPECT_LE(r.depth, bs[k].delta + 1e-6) << what << " lane " << k;
      on_feature += std::fabs(r.depth - bs[k].delta) <= 1e-6 && angle(r.n, bs[k].n) <= 1e-4;
    }
  }
  EXPECT_GT(apart, static_cast<int>(bs.size()) / 4);
  std::printf("  %-28s meeting %d, of which at the built pair %d\n", what, *meeting_lanes, on_feature);
  return on_feature;
}

/// The closed form of a two-point line contact, coordinates relative to `origin`: the
/// normal n, the depth d; the points' coordinate `axis` spanning [lo, hi]; each point's
/// other coordinates at `at`'s (those that are not NaN) and, with `points_carry_depth`,
/// its depth d.
struct LineContact {
  Eigen::Vector3d n;
  double d = 0;
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  int axis = 0;
  double lo = 0, hi = 0;
  Eigen::Vector3d at = Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
  bool points_carry_depth = true;
};

/// r against the line contact c: two points, the normal within 1e-6 rad, the depth, the
/// span and the points' coordinates and depths within 1e-6.
inline void expect_line_contact(const PairResult& r, const LineContact& c) {
  ASSERT_EQ(r.count, 2u);
  EXPECT_LT(angle(r.n, c.n), 1e-6) << r.n.transpose();
  EXPECT_NEAR(r.depth, c.d, 1e-6);
  const double x0 = std::min(r.pt[0][c.axis], r.pt[1][c.axis]) - c.origin[c.axis],
               x1 = std::max(r.pt[0][c.axis], r.pt[1][c.axis]) - c.origin[c.axis];
  EXPECT_NEAR(x0, c.lo, 1e-6);
  EXPECT_NEAR(x1, c.hi, 1e-6);
  for (int i = 0; i < 2; ++i) {
    for (int j = 0; j < 3; ++j)
      if (j != c.axis && !std::isnan(c.at[j])) {
        EXPECT_NEAR(r.pt[i][j] - c.origin[j], c.at[j], 1e-6) << "point " << i << " coordinate " << j;
      }
    if (c.points_carry_depth) {
      EXPECT_NEAR(r.pd[i], c.d, 1e-6) << "point " << i;
    }
  }
}

}  // namespace impact::test
