// Checks shared by the per-kernel narrow-phase tests (one pair type per file, against
// their own double references): pairs built with known collision data, and the scales
// every random-pose suite runs at.
//   Built<Q>       a test's pair struct with its built depth and normal
//   expect_built   a kernel's answers against the built ones (hit, depth, normal)
//   kernel_scales  (size, offset from the origin): 1, 1e-4, 1e4, and 1 at 1e5
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <tuple>
#include <vector>

#include <Eigen/Core>

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

/// (size, offset from the origin) of the random-pose suites: sizes 1, 1e-4 and 1e4 at the
/// origin, and size 1 at 1e5 from it.
inline std::vector<std::tuple<double, double>> kernel_scales() {
  return {std::make_tuple(1.0, 0.0), std::make_tuple(1e-4, 0.0), std::make_tuple(1e4, 0.0),
          std::make_tuple(1.0, 1e5)};
}

}  // namespace impact::test
