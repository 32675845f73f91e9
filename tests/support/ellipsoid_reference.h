// A double-precision reference for points against an ellipsoid, shared by the ellipsoid
// kernels' tests (sphere_ellipsoid_test.cpp, capsule_ellipsoid_test.cpp,
// ellipsoid_triangle_test.cpp): the nearest surface point by plain bisection of the
// secular equation to the last bit, with the cases of a point on a principal plane
// written out (a zero component has a zero closest coordinate, except an inside point
// on the smallest axis's plane whose nearest point lies off it; Eberly, "Distance from
// a Point to an Ellipse, an Ellipsoid, or a Hyperellipsoid", 2013). Checked against a
// dense parametric sampling of the surface and the Lagrange conditions in
// sphere_ellipsoid_test.cpp (SphereEllipsoidReference). No fixed iteration count and no
// float: unrelated to the kernels' solver beyond the equation itself.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cmath>

namespace impact::test::eref {

using Vec3d = Eigen::Vector3d;

/// Root s in [lo, hi] of sum_i (w_i / (s + dd_i))^2 = 1 (decreasing in s) by bisection
/// until the interval stops shrinking.
inline double bisect_secular(int n, const double* w, const double* dd, double lo, double hi) {
  for (int it = 0; it < 4000; ++it) {
    const double mid = 0.5 * (lo + hi);
    if (!(mid > lo && mid < hi)) break;
    double f = -1.0;
    for (int i = 0; i < n; ++i) {
      const double q = w[i] / (mid + dd[i]);
      f += q * q;
    }
    if (f > 0) {
      lo = mid;
    } else if (f < 0) {
      hi = mid;
    } else {
      return mid;
    }
  }
  return 0.5 * (lo + hi);
}

/// Closest point x (x_i >= 0) to y (y_i >= 0) on sum (x_i / a_i)^2 = 1 in n = 1..3
/// dimensions, a[0] >= ... >= a[n-1] > 0.
inline void octant_closest(int n, const double* a, const double* y, double* x) {
  if (n == 1) {
    x[0] = a[0];
    return;
  }
  const int l = n - 1;
  if (y[l] > 0) {
    // Components with y_i = 0 have x_i = 0 (every denominator is positive): drop them.
    int idx[3], m = 0;
    for (int i = 0; i < n; ++i) {
      if (i == l || y[i] > 0)
        idx[m++] = i;
      else
        x[i] = 0;
    }
    if (m < n) {
      double as[3] = {}, ys[3] = {}, xs[3] = {};
      for (int k = 0; k < m; ++k) as[k] = a[idx[k]], ys[k] = y[idx[k]];
      octant_closest(m, as, ys, xs);
      for (int k = 0; k < m; ++k) x[idx[k]] = xs[k];
      return;
    }
    double w[3], dd[3], wn = 0;
    for (int i = 0; i < n; ++i) {
      w[i] = a[i] * y[i];
      dd[i] = (a[i] - a[l]) * (a[i] + a[l]);
      wn += w[i] * w[i];
    }
    const double s = bisect_secular(n, w, dd, w[l], std::max(std::sqrt(wn), w[l]));
    for (int i = 0; i < n; ++i) x[i] = a[i] * a[i] * y[i] / (s + dd[i]);
    return;
  }
  // y_l = 0: an inside point near that plane can have its nearest point off it.
  bool off = true;
  double sum = 0, u[3];
  for (int i = 0; i < l; ++i) {
    const double den = (a[i] - a[l]) * (a[i] + a[l]);
    const double num = a[i] * y[i];
    if (!(num < den)) {
      off = false;
      break;
    }
    u[i] = num / den;  // x_i / a_i
    sum += u[i] * u[i];
  }
  if (off && sum < 1) {
    for (int i = 0; i < l; ++i) x[i] = a[i] * u[i];
    x[l] = a[l] * std::sqrt(1 - sum);
    return;
  }
  x[l] = 0;
  octant_closest(l, a, y, x);
}

/// Nearest point of the ellipsoid with radii e (local frame) to the local point y.
inline Vec3d closest_local(const Vec3d& e, const Vec3d& y) {
  int perm[3] = {0, 1, 2};
  std::stable_sort(perm, perm + 3, [&](int i, int j) { return e[i] > e[j]; });
  double a[3], yy[3], xs[3];
  for (int k = 0; k < 3; ++k) a[k] = e[perm[k]], yy[k] = std::fabs(y[perm[k]]);
  octant_closest(3, a, yy, xs);
  Vec3d x;
  for (int k = 0; k < 3; ++k) x[perm[k]] = std::copysign(xs[k], y[perm[k]] < 0 ? -1.0 : 1.0);
  return x;
}

/// (y_i / e_i)^2 summed: < 1 inside.
inline double level(const Vec3d& e, const Vec3d& y) {
  return y.cwiseQuotient(e).squaredNorm();
}

/// Signed distance of the local point y to the surface of the ellipsoid with radii e
/// (< 0 inside).
inline double signed_distance_local(const Vec3d& e, const Vec3d& y) {
  const double d = (y - closest_local(e, y)).norm();
  return level(e, y) < 1 ? -d : d;
}

/// Signed distance of the world point x to the ellipsoid b (any struct with centre p,
/// rotation R and radii e; < 0 inside).
template <class Posed>
double signed_distance_posed(const Posed& b, const Vec3d& x) {
  return signed_distance_local(b.e, b.R.transpose() * (x - b.p));
}

/// The surface point of the ellipsoid b (p, R, e) along the local direction dir (non-zero)
/// from its centre, in the world frame, and the outward unit normal there.
struct SurfacePoint {
  Vec3d x, m;
};
template <class Posed>
SurfacePoint surface_point(const Posed& b, const Vec3d& dir) {
  const Vec3d xs = dir / std::sqrt(level(b.e, dir));
  const Vec3d m = b.R * xs.cwiseQuotient(b.e.cwiseProduct(b.e)).normalized();
  const Vec3d x = b.p + b.R * xs;
  return {x, m};
}

/// The largest radius of curvature of the ellipsoid with radii e: e_max^2 / e_min (its
/// support point slides by this much per radian the direction turns).
inline double largest_curvature_radius(const Vec3d& e) {
  return e.maxCoeff() * e.maxCoeff() / e.minCoeff();
}

}  // namespace impact::test::eref
