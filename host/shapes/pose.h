// Pose validation and posed bounds of shapes: shared by the World (bodies' poses and
// bounds), the narrow phase, the shape queries and the ray scene.
#pragma once

#include <cmath>
#include <cstdio>
#include <string>

#include <Eigen/Geometry>

#include "host/shapes/shape_store.h"
#include "impact/shapes.h"
#include "impact/status.h"
#include "impact/types.h"

namespace impact::host {

/// The check of check_pose without building a message (the per-object fast path).
inline bool pose_ok(const Pose& p) {
  if (!p.position.allFinite() || !p.orientation.coeffs().allFinite()) return false;
  const double n2 = p.orientation.coeffs().cast<double>().squaredNorm();
  return std::fabs(n2 - 1.0) <= kUnitQuaternionTolerance;
}

/// Finite position, finite quaternion of unit length within kUnitQuaternionTolerance
/// (include/impact/types.h).
inline Status check_pose(const Pose& p, const char* who) {
  if (!p.position.allFinite()) {
    return Status(StatusCode::kInvalidArgument, std::string(who) + ": position is not finite");
  }
  if (!p.orientation.coeffs().allFinite()) {
    return Status(StatusCode::kInvalidArgument, std::string(who) + ": orientation is not finite");
  }
  const double n2 = p.orientation.coeffs().cast<double>().squaredNorm();
  if (!(std::fabs(n2 - 1.0) <= kUnitQuaternionTolerance)) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%g", std::sqrt(n2));
    return Status(StatusCode::kInvalidArgument,
                  std::string(who) + ": orientation must be a unit quaternion (|q| = " + buf + ")");
  }
  return {};
}

/// The rotation of q / |q| (q finite, not zero), without the square root of
/// normalising first: with s = 2 / |q|^2, R = I + s (w [v]x + [v]x^2) term by term.
inline Eigen::Matrix3f rotation_of(const Eigen::Quaternionf& q) {
  const float x = q.x(), y = q.y(), z = q.z(), w = q.w();
  const float s = 2.0f / (x * x + y * y + z * z + w * w);
  const float xs = x * s, ys = y * s, zs = z * s;
  const float wx = w * xs, wy = w * ys, wz = w * zs;
  const float xx = x * xs, xy = x * ys, xz = x * zs;
  const float yy = y * ys, yz = y * zs, zz = z * zs;
  Eigen::Matrix3f R;
  R << 1.0f - (yy + zz), xy - wz, xz + wy,  //
      xy + wz, 1.0f - (xx + zz), yz - wx,   //
      xz - wy, yz + wx, 1.0f - (xx + yy);
  return R;
}

inline Pose normalized(const Pose& p) {
  Pose out;
  out.position = p.position;
  out.orientation = Eigen::Quaternionf(p.orientation.coeffs().cast<double>().normalized().cast<float>());
  return out;
}

/// World AABB of a (non-half-space) shape at a normalised pose.
/// The same with the pose as a rotation matrix R and a position p.
inline void posed_bounds(const ShapeRecord& r, const Eigen::Matrix3f& R, const Eigen::Vector3f& p,
                         const HullStore& hulls, Eigen::Vector3f* lo, Eigen::Vector3f* hi) {
  Eigen::Vector3f half = Eigen::Vector3f::Zero();
  switch (r.type) {
    case ShapeType::kSphere:
      half = Eigen::Vector3f::Constant(r.e[0]);
      break;
    case ShapeType::kCapsule:
      half = R.col(2).cwiseAbs() * r.e[1] + Eigen::Vector3f::Constant(r.e[0]);
      break;
    case ShapeType::kAabb:
      half = Eigen::Vector3f(r.e[0], r.e[1], r.e[2]);
      break;
    case ShapeType::kBox:
      half = R.cwiseAbs() * Eigen::Vector3f(r.e[0], r.e[1], r.e[2]);
      break;
    case ShapeType::kCylinder: {
      const Eigen::Vector3f u = R.col(2);
      for (int i = 0; i < 3; ++i) {
        half[i] = std::fabs(u[i]) * r.e[1] + r.e[0] * std::sqrt(std::max(0.0f, 1.0f - u[i] * u[i]));
      }
      break;
    }
    case ShapeType::kEllipsoid:
      for (int i = 0; i < 3; ++i) {
        half[i] = Eigen::Vector3f(R(i, 0) * r.e[0], R(i, 1) * r.e[1], R(i, 2) * r.e[2]).norm();
      }
      break;
    case ShapeType::kConvex: {
      Eigen::Vector3f l = Eigen::Vector3f::Constant(INFINITY), h = -l;
      for (uint32_t v = hulls.vert_begin[r.ref]; v < hulls.vert_begin[r.ref + 1]; ++v) {
        const Eigen::Vector3f w = R * Eigen::Vector3f(hulls.vx[v], hulls.vy[v], hulls.vz[v]);
        l = l.cwiseMin(w);
        h = h.cwiseMax(w);
      }
      *lo = l + p;
      *hi = h + p;
      return;
    }
    case ShapeType::kMesh:
    case ShapeType::kCompound: {
      const Eigen::Vector3f c = (r.local_min + r.local_max) * 0.5f;
      const Eigen::Vector3f e = (r.local_max - r.local_min) * 0.5f;
      const Eigen::Vector3f wc = R * c + p;
      const Eigen::Vector3f we = R.cwiseAbs() * e;
      *lo = wc - we;
      *hi = wc + we;
      return;
    }
    case ShapeType::kHalfSpace:
      *lo = Eigen::Vector3f::Constant(-INFINITY);
      *hi = Eigen::Vector3f::Constant(INFINITY);
      return;
  }
  *lo = p - half;
  *hi = p + half;
}

inline void posed_bounds(const ShapeRecord& r, const Pose& pose, const HullStore& hulls,
                         Eigen::Vector3f* lo, Eigen::Vector3f* hi) {
  posed_bounds(r, pose.orientation.toRotationMatrix(), pose.position, hulls, lo, hi);
}

}  // namespace impact::host
