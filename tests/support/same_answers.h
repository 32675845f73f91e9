// Two answers for the same pairs, lane by lane: a kernel against a special-case kernel on
// the pairs where the two coincide (a round ellipsoid is a sphere, a zero-length core is
// a sphere), or against itself on the same solids described differently (box axes
// relabelled, triangle vertices reordered, a core's axis reversed, the pair turned).
//   SameAnswerTolerances  what one comparison allows, in units of a lane's scale
//   LaneRule              per lane: skipped, its scale, whether the normal and the first
//                         point are held, and how the normal maps from one answer to the other
//   expect_same_answers   mine[k] against theirs[k]; returns the lanes compared
//   SymmetricCopy / expect_symmetric  a kernel's answers against its answers for copies
//                         of the pairs moved by a symmetry, away from touching
#pragma once

#include <gtest/gtest.h>

#include <Eigen/Core>
#include <cmath>
#include <cstddef>
#include <functional>
#include <string>
#include <vector>

#include "support/leaf_lanes.h"
#include "support/shape_geometry.h"

namespace impact::test {

/// The tolerances of expect_same_answers, each times the lane's scale (LaneRule::scale)
/// but the angle.
struct SameAnswerTolerances {
  double miss = 1e-5;       ///< a contact on one side only: its |depth| below this (0: none allowed)
  double depth = 2e-6;      ///< |depth difference| where both report a contact
  double angle = 1e-5;      ///< rad between the normals, where LaneRule::normal
  double point = 1e-5;      ///< distance of the first points, where LaneRule::point
  bool same_count = false;  ///< both contacts have the same point count
};

/// How one lane is compared.
struct LaneRule {
  bool skip = false;  ///< not compared (touching, by the test's reference)
  double scale = 1;   ///< the tolerances' unit: 1, or a length of the pair
  bool normal = false;
  bool point = false;
  /// theirs' normal is map * mine's: -I where the roles of A and B are swapped, a
  /// symmetry's rotation where the pair is moved by one.
  Eigen::Matrix3d map = Eigen::Matrix3d::Identity();
};

/// mine[k] against theirs[k] by rule(k) (a LaneRule) and t: a contact on one side only
/// no deeper than t.miss; where both report one, depths within t.depth (and the same
/// point count if t.same_count), normals within t.angle rad (mapped) where rule.normal,
/// first points within t.point where rule.point. Returns the lanes where both report a
/// contact.
template <class Rule>
int expect_same_answers(const std::vector<PairResult>& mine, const std::vector<PairResult>& theirs,
                        const SameAnswerTolerances& t, Rule rule) {
  int compared = 0;
  for (size_t k = 0; k < mine.size(); ++k) {
    const LaneRule r = rule(k);
    if (r.skip) continue;
    const PairResult &x = mine[k], &y = theirs[k];
    if ((x.count == 0) != (y.count == 0)) {
      EXPECT_LT(std::fabs(x.count ? x.depth : y.depth), t.miss * r.scale)
          << "lane " << k << ": a contact on one side only";
      continue;
    }
    if (x.count == 0) continue;
    ++compared;
    if (t.same_count) {
      EXPECT_EQ(x.count, y.count) << "lane " << k;
    }
    EXPECT_NEAR(x.depth, y.depth, t.depth * r.scale) << "lane " << k;
    if (r.normal) {
      EXPECT_LT(angle(r.map * x.n, y.n), t.angle)
          << "lane " << k << " n " << x.n.transpose() << " other " << y.n.transpose();
    }
    if (r.point) {
      EXPECT_LT((x.pt[0] - y.pt[0]).norm(), t.point * r.scale) << "lane " << k;
    }
  }
  return compared;
}

/// A copy of a test's pairs moved by a symmetry of the pair or described differently,
/// for expect_symmetric: the kernel's answers h for it, its depth tolerance in lane
/// tolerances, and the map of the normal from the base answer's (map(k); the identity
/// when not given).
struct SymmetricCopy {
  std::vector<PairResult> h;
  double depth_tols = 1;
  std::function<Eigen::Matrix3d(size_t)> map = {};
};

/// What expect_symmetric knows of a lane from the test's reference: the depth tolerance,
/// the reference depth, whether its normal is unique, and a trace for failures.
struct SymmetryLane {
  double tol = 0;
  double depth_ref = 0;
  bool unique = false;
  std::string trace = {};
};

/// The base answers a against each copy, lane by lane (lane(k): a SymmetryLane): lanes
/// with |depth_ref| <= 4 tol skipped; elsewhere the same hit in every copy, depths within
/// depth_tols tol, and where the reference is unique the normal mapped by the copy's map
/// within angle_tol rad of the copy's. More than a quarter of the lanes compared.
template <class Lane>
void expect_symmetric(const std::vector<PairResult>& a, const std::vector<SymmetricCopy>& copies,
                      double angle_tol, Lane lane) {
  int compared = 0;
  for (size_t k = 0; k < a.size(); ++k) {
    const SymmetryLane l = lane(k);
    SCOPED_TRACE(l.trace);
    if (std::fabs(l.depth_ref) <= 4 * l.tol) continue;
    for (const SymmetricCopy& c : copies) ASSERT_EQ(a[k].count > 0, c.h[k].count > 0) << "lane " << k;
    if (a[k].count == 0) continue;
    ++compared;
    for (const SymmetricCopy& c : copies) {
      EXPECT_NEAR(a[k].depth, c.h[k].depth, c.depth_tols * l.tol) << "lane " << k;
      if (l.unique) {
        const Eigen::Vector3d n = c.map ? Eigen::Vector3d(c.map(k) * a[k].n) : a[k].n;
        EXPECT_LT(angle(n, c.h[k].n), angle_tol) << "lane " << k;
      }
    }
  }
  EXPECT_GT(compared, static_cast<int>(a.size()) / 4);
}

}  // namespace impact::test
