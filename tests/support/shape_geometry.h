// Small double-precision geometry shared by the narrow-phase kernel tests (Eigen, the
// inputs already rounded to float as the kernel sees them): angles, rotations and
// frames, the closed-form signed distances of a point to a box and to a cylinder, the
// cylinder's closest point, the float rounding of a pair's coordinates, and conversions
// to the sampled reference's vectors (tests/support/narrow_reference.h).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <initializer_list>

#include "support/narrow_reference.h"

namespace impact::test {

/// The angle between two nonzero vectors, radians (accurate for small angles).
inline double angle(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::atan2(a.cross(b).norm(), a.dot(b));
}

/// The matrix with columns a, b, c.
inline Eigen::Matrix3d columns(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  Eigen::Matrix3d m;
  m.col(0) = a, m.col(1) = b, m.col(2) = c;
  return m;
}

/// The rotation by angle a (rad) about axis (any length).
inline Eigen::Matrix3d rot(double a, const Eigen::Vector3d& axis) {
  return Eigen::AngleAxisd(a, axis.normalized()).toRotationMatrix();
}

/// A rotation with column 2 = u (unit), turned by `spin` about it.
inline Eigen::Matrix3d frame_of(const Eigen::Vector3d& u, double spin) {
  const Eigen::Vector3d x = rot(spin, u) * u.unitOrthogonal();
  return columns(x, u.cross(x), u);
}

/// The rotation about from x to (not opposite) that turns `from` onto `to`.
inline Eigen::Matrix3d turn_to(const Eigen::Vector3d& from, const Eigen::Vector3d& to) {
  const Eigen::Vector3d a = from.normalized(), b = to.normalized();
  return rot(angle(a, b), a.cross(b));
}

/// The unit vector at angle a in the xy plane, and the one a quarter turn on.
inline Eigen::Vector3d radial(double a) {
  return {std::cos(a), std::sin(a), 0.0};
}
inline Eigen::Vector3d tangential(double a) {
  return {-std::sin(a), std::cos(a), 0.0};
}

/// Signed distance of x to the solid box at c with rotation Q (columns: its axes) and
/// half extents e (< 0 inside).
inline double box_sd(const Eigen::Vector3d& c, const Eigen::Matrix3d& Q, const Eigen::Vector3d& e,
                     const Eigen::Vector3d& x) {
  const Eigen::Vector3d l = (Q.transpose() * (x - c)).cwiseAbs() - e;
  const double inside = l.maxCoeff();
  return inside > 0 ? l.cwiseMax(0.0).norm() : inside;
}

/// Signed distance of l (in the cylinder's frame) to the solid cylinder of radius rc and
/// half length h about the z axis (< 0 inside: minus the distance to the nearest face).
inline double cylinder_sd_local(const Eigen::Vector3d& l, double rc, double h) {
  const double dr = std::hypot(l.x(), l.y()) - rc, dz = std::fabs(l.z()) - h;
  if (dr <= 0 && dz <= 0) return std::max(dr, dz);
  return std::hypot(std::max(dr, 0.0), std::max(dz, 0.0));
}

/// The same for the cylinder at p with rotation R (column 2 = axis), x in the world.
inline double cylinder_sd(const Eigen::Vector3d& p, const Eigen::Matrix3d& R, double rc, double h,
                          const Eigen::Vector3d& x) {
  return cylinder_sd_local(R.transpose() * (x - p), rc, h);
}

/// The closest point of that solid cylinder to an outside point x.
inline Eigen::Vector3d cylinder_closest(const Eigen::Vector3d& p, const Eigen::Matrix3d& R, double rc,
                                        double h, const Eigen::Vector3d& x) {
  const Eigen::Vector3d l = R.transpose() * (x - p);
  const double rho = std::hypot(l.x(), l.y());
  const double s = rho > rc ? rc / rho : 1.0;
  return p + R * Eigen::Vector3d(l.x() * s, l.y() * s, std::clamp(l.z(), -h, h));
}

/// One float ulp (2^-23 relative) of the largest coordinate a pair's inputs reach: the
/// largest |coefficient| of the given points (centres, vertices) plus the pair's size.
inline double coordinate_ulp(double size, std::initializer_list<Eigen::Vector3d> points) {
  double m = 0;
  for (const Eigen::Vector3d& p : points) m = std::max(m, p.cwiseAbs().maxCoeff());
  return (m + size) * std::ldexp(1.0, -23);
}

/// Eigen and reference vectors.
inline nref::V3 v3(const Eigen::Vector3d& v) {
  return {v.x(), v.y(), v.z()};
}
inline Eigen::Vector3d ev(const nref::V3& v) {
  return {v.x, v.y, v.z};
}

/// A posed leaf of type t for the reference: centre p, rotation R, sizes e (leaf.h).
inline nref::Shape posed_shape(kernels::LeafType t, const Eigen::Vector3d& p, const Eigen::Matrix3d& R,
                               const Eigen::Vector3d& e) {
  nref::Shape s;
  s.type = t;
  s.p = v3(p);
  for (int i = 0; i < 9; ++i) s.r[i] = R(i / 3, i % 3);
  for (int i = 0; i < 3; ++i) s.e[i] = e[i];
  return s;
}

}  // namespace impact::test
