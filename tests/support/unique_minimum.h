// Whether a reference normal is the only minimiser of a pair's support overlap, as the
// cylinder pair tests decide it: sampled on a cone around it and on the great circles
// where whole circles of minima occur (a cylinder's horizontal circle, the circles
// perpendicular to a box's axes or a triangle's edges), then its rise in every
// direction close by (a flat valley's minimum is not unique either).
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "support/shape_geometry.h"

namespace impact::test {

/// The great circles unique_minimum samples: those perpendicular to each pole (unit),
/// `samples` directions `step` rad apart on each.
struct GreatCircles {
  std::vector<Eigen::Vector3d> poles;
  int samples = 6284;
  double step = 1e-3;
};

/// The least overlap o(n) (n of any length) over `count` directions on the cone of
/// half-angle `cone` rad around n_ref.
template <class Overlap>
double least_on_cone(Overlap o, const Eigen::Vector3d& n_ref, double cone, int count) {
  const Eigen::Vector3d t1 = n_ref.unitOrthogonal(), t2 = n_ref.cross(t1);
  double r = std::numeric_limits<double>::infinity();
  for (int i = 0; i < count; ++i) {
    const double a = 2 * M_PI * i / count;
    r = std::min(r, o(n_ref + std::tan(cone) * (std::cos(a) * t1 + std::sin(a) * t2)));
  }
  return r;
}

/// Whether n_ref (unit) is the only minimiser of the support overlap o within 0.02 rad:
/// every direction outside that cone overlaps by more than depth + 2 tol (second: the
/// reference's own second best; 720 directions on the 0.02 rad cone; the great circles
/// c, outside the cone), and the overlap rises by at least min_rise on 96 directions
/// 3e-3 rad from n_ref (*rise, if given: that least rise, once the first test passes).
template <class Overlap>
bool unique_minimum(Overlap o, const Eigen::Vector3d& n_ref, double depth, double second, double tol,
                    const GreatCircles& c, double min_rise, double* rise = nullptr) {
  double best = std::min(second, least_on_cone(o, n_ref, 0.02, 720));
  for (const Eigen::Vector3d& ax : c.poles) {
    const Eigen::Vector3d e1 = ax.unitOrthogonal(), e2 = ax.cross(e1);
    for (int i = 0; i < c.samples; ++i) {
      const double a = c.step * i;
      const Eigen::Vector3d n = std::cos(a) * e1 + std::sin(a) * e2;
      if (angle(n, n_ref) > 0.02) best = std::min(best, o(n));
    }
  }
  if (!(best > depth + 2 * tol)) return false;
  const double r = least_on_cone(o, n_ref, 3e-3, 96) - depth;
  if (rise != nullptr) *rise = r;
  return r >= min_rise;
}

}  // namespace impact::test
