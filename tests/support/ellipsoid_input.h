// Ellipsoids as the ellipsoid pair tests pose them (double, rounded to float as the
// kernel sees them) and the ones their random cases draw:
//   PosedSolid        centre, rotation, extents along its axes (radii; a box's half extents)
//   rounded           every field rounded to float
//   random_ellipsoid  centre in [-1, 1]^3, a random rotation, radii in [0.2, 1]
//   random_round_ellipsoid  the same with one radius in [0.2, 0.8]
//   thin_radii        needle and pancake radii (ratios 1e-3, 1e-4), axes permuted
//   thinnest_axis     the index of the smallest radius
//   random_surface_touch  a random ellipsoid, a point on its surface and its normal
//                     there, and the touching point just off (or on) it
#pragma once

#include <Eigen/Core>
#include <random>

#include "support/ellipsoid_reference.h"
#include "support/random_input.h"
#include "support/test_support.h"

namespace impact::test {

/// A posed ellipsoid (or box): centre p, rotation R (columns: the axes of e), e the
/// radii (half extents) along them.
struct PosedSolid {
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  Eigen::Vector3d e = Eigen::Vector3d::Ones();
};

inline PosedSolid rounded(PosedSolid s) {
  s.p = round_to_float(s.p);
  s.R = round_to_float(s.R);
  s.e = round_to_float(s.e);
  return s;
}

/// Centre uniform in [-1, 1]^3, a random rotation, radii uniform in [0.2, 1].
inline PosedSolid random_ellipsoid(std::mt19937& g) {
  std::uniform_real_distribution<double> u(-1, 1), s(0.2, 1.0);
  return PosedSolid{Eigen::Vector3d(u(g), u(g), u(g)), random_rotation(g), Eigen::Vector3d(s(g), s(g), s(g))};
}

/// The same with the radii e given (centre and rotation drawn as random_ellipsoid's).
inline PosedSolid random_ellipsoid(std::mt19937& g, const Eigen::Vector3d& e) {
  std::uniform_real_distribution<double> u(-1, 1);
  return PosedSolid{Eigen::Vector3d(u(g), u(g), u(g)), random_rotation(g), e};
}

/// A round ellipsoid (a sphere): centre and rotation as random_ellipsoid's, radius
/// uniform in [0.2, 0.8].
inline PosedSolid random_round_ellipsoid(std::mt19937& g) {
  std::uniform_real_distribution<double> u(-1, 1), u01(0, 1);
  return PosedSolid{Eigen::Vector3d(u(g), u(g), u(g)), random_rotation(g),
                    Eigen::Vector3d::Constant(0.2 + 0.6 * u01(g))};
}

/// Case k of the needle and pancake radii: ratio 1e-3 (k odd) or 1e-4; a needle (1,
/// ratio, ratio (0.5 .. 1.5)) where (k / 2) is odd, else a pancake (1, 0.5 .. 1, ratio);
/// the axes turned by k mod 3.
inline Eigen::Vector3d thin_radii(std::mt19937& g, int k) {
  std::uniform_real_distribution<double> u01(0, 1);
  const double ratio = (k % 2) ? 1e-3 : 1e-4;
  const bool needle = (k / 2) % 2;
  const Eigen::Vector3d e = needle ? Eigen::Vector3d(1, ratio, ratio * (0.5 + u01(g)))
                                   : Eigen::Vector3d(1, 0.5 + 0.5 * u01(g), ratio);
  const int sh = k % 3;
  return {e[sh], e[(sh + 1) % 3], e[(sh + 2) % 3]};
}

/// The index of the smallest of e (the first of equal ones).
inline int thinnest_axis(const Eigen::Vector3d& e) {
  return e[0] <= e[1] && e[0] <= e[2] ? 0 : (e[1] <= e[2] ? 1 : 2);
}

/// A random ellipsoid (random_ellipsoid) touched at a surface point: x along a random
/// direction, m the outward unit normal there, and the touching feature's point
/// c = x + f m, f = 0 for every fifth case k, else uniform in [-1e-3, 1e-3].
struct SurfaceTouch {
  PosedSolid ell;
  Eigen::Vector3d x, m, c;
  double f = 0;
};

inline SurfaceTouch random_surface_touch(std::mt19937& g, int k) {
  std::uniform_real_distribution<double> f(-1e-3, 1e-3);
  SurfaceTouch t;
  t.ell = random_ellipsoid(g);
  const eref::SurfacePoint sp = eref::surface_point(t.ell, random_unit_vector(g));
  t.x = sp.x, t.m = sp.m;
  t.f = (k % 5 == 0) ? 0.0 : f(g);
  t.c = t.x + t.f * t.m;
  return t;
}

}  // namespace impact::test
