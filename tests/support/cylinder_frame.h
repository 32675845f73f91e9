// A solid cylinder posed in double as the cylinder pair tests describe it, its boundary
// pieces, and pairs built in its frame (centre 0, axis z) then posed in the world:
//   PosedCylinder         centre, rotation (column 2 = the unit axis), radius, half length
//   rounded               every input rounded to float, as the kernel sees it
//   FlatCylinder          the cylinder fields (p, R, rc, h) of a flat pair struct (a base)
//   round_cylinder        the same rounding for those fields
//   move_cylinder         those fields' cylinder moved (rounded to float)
//   random_posed_cylinder  at the origin, a random rotation, radius and half length in
//                         [0.1, 1] size
//   CylinderPiece         cap, rim, side
//   cylinder_piece_point  a random point of a piece with an outward normal there
//   posed_in_cylinder_frame  a pair given in A's frame, turned and moved at random
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <random>

#include "support/random_input.h"
#include "support/shape_geometry.h"
#include "support/test_support.h"

namespace impact::test {

/// One solid cylinder.
struct PosedCylinder {
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();  ///< column 2: the unit axis
  double r = 1, h = 1;                              ///< radius, half length
};

inline PosedCylinder rounded(PosedCylinder c) {
  c.p = round_to_float(c.p);
  c.R = round_to_float(c.R);
  c.r = round_to_float(c.r);
  c.h = round_to_float(c.h);
  return c;
}

/// The cylinder of a pair struct that holds it flat (a base of the box-, capsule- and
/// triangle-cylinder tests' pairs): centre p, rotation R (column 2 = the unit axis),
/// radius rc, half length h, as random_cylinder draws them.
struct FlatCylinder {
  Eigen::Vector3d p;
  Eigen::Matrix3d R;
  double rc, h;
};

/// The cylinder fields of a pair struct that holds them flat (p, R, rc, h: as
/// random_cylinder draws them) rounded to float.
template <class Q>
void round_cylinder(Q* q) {
  q->p = round_to_float(q->p);
  q->R = round_to_float(q->R);
  q->rc = round_to_float(q->rc);
  q->h = round_to_float(q->h);
}

/// The flat pair q's cylinder moved by shift (its centre rounded to float).
template <class Q>
void move_cylinder(Q& q, const Eigen::Vector3d& shift) {
  q.p = round_to_float(Eigen::Vector3d(q.p + shift));
}

/// A cylinder centred at the origin with a random rotation, radius and half length
/// uniform in [0.1, 1] size.
inline PosedCylinder random_posed_cylinder(std::mt19937& g, double size) {
  std::uniform_real_distribution<double> uni(0, 1);
  PosedCylinder c;
  c.R = random_rotation(g);
  c.r = size * (0.1 + 0.9 * uni(g));
  c.h = size * (0.1 + 0.9 * uni(g));
  return c;
}

/// The boundary pieces of a cylinder.
enum class CylinderPiece { kCap, kRim, kSide };

/// A point x on a cylinder's boundary and an outward normal n there (unit).
struct PiecePoint {
  Eigen::Vector3d x, n;
};

/// A point of piece p of the cylinder of radius r and half length h in its frame, at
/// azimuth a, on the cap or rim of sign s (+-1): on the cap 0.7 r |u| from the axis, n
/// along the axis; on the rim, n 0.3 .. 1.27 rad from the radial direction towards the
/// cap; on the side 0.7 h u along the axis, n radial (u: uniform in [-1, 1], drawn from g).
inline PiecePoint cylinder_piece_point(CylinderPiece p, double r, double h, double a, double s,
                                       std::mt19937& g) {
  std::uniform_real_distribution<double> uni(-1, 1);
  const Eigen::Vector3d z = Eigen::Vector3d::UnitZ();
  switch (p) {
    case CylinderPiece::kCap:
      return {0.7 * r * std::fabs(uni(g)) * radial(a) + s * h * z, s * z};
    case CylinderPiece::kRim: {
      const double phi = 0.3 + (1.27 - 0.3) * std::fabs(uni(g));
      return {r * radial(a) + s * h * z, std::cos(phi) * radial(a) + std::sin(phi) * s * z};
    }
    case CylinderPiece::kSide:
      break;
  }
  return {r * radial(a) + 0.7 * h * uni(g) * z, radial(a)};
}

/// The pair of A (a PosedCylinder of radius ra, half length ha at the origin of its
/// frame) and B given in A's frame (b_local: its centre and rotation there), turned by a
/// random rotation and moved near `offset` from the origin; rounded(Q) gives the float
/// inputs.
template <class Q, class B>
Q posed_in_cylinder_frame(std::mt19937& g, double ra, double ha, const B& b_local, double offset) {
  Q q;
  q.a.R = random_rotation(g);
  q.a.p = Eigen::Vector3d(offset, 0.3 * offset, -0.7 * offset) + Eigen::Vector3d(0.25, -0.5, 0.75);
  q.a.r = ra, q.a.h = ha;
  q.b = b_local;
  q.b.p = q.a.p + q.a.R * b_local.p;
  q.b.R = q.a.R * b_local.R;
  return rounded(q);
}

}  // namespace impact::test
