// Semi-implicit Euler for rotating bodies (the kRigid field set of host/body_store.h):
// the linear half of semi_implicit_euler.h plus angular velocity, orientation, body
// forces, damping and the gyroscopic term.
//
// integrate_rigid_velocities, per dynamic body (inv_mass > 0; others keep v and w):
//   v = v / (1 + h c_lin) + h (gravity_scale g + inv_mass F)
//   w = w / (1 + h c_ang) + h I_w^-1 T,     I_w^-1 = R diag(ii) R^T, R = rot(q pq)
//   gyroscopic: then one Newton step of the implicit Euler equation of the
//   torque-free body in its principal frame, I (w' - w) + h w' x I w' = 0
//   (Catto, "Numerical Methods", GDC 2015): stable at any spin, so a spinning long
//   body neither gains energy nor blows up, while the Dzhanibekov flip survives.
//   Bodies with a zero principal inverse inertia (fixed rotation) skip it.
// integrate_rigid_positions, per body: the centre of mass c_w = p + rot(q) c moves by
//   h v, q turns by w (first order, renormalised), p = c_w' - rot(q') c.
// Forces / damping views may be null (none of those field sets is on).
// Cost: ~60 flops per body (velocities, ~140 with the gyroscopic step), ~50 (positions);
// streaming over SoA arrays. Preconditions: finite inputs, unit quaternions.
#pragma once

#include "kernels/common/kernel.h"
#include "kernels/common/math3.h"

namespace impact::kernels {

struct RigidBodies {
  float* vx;
  float* vy;
  float* vz;
  float* wx;
  float* wy;
  float* wz;
  float* px;
  float* py;
  float* pz;
  float* qx;
  float* qy;
  float* qz;
  float* qw;
  const float* inv_mass;
  const float* iix;  ///< inverse principal inertia
  const float* iiy;
  const float* iiz;
  const float* pqx;  ///< principal axes in the shape frame
  const float* pqy;
  const float* pqz;
  const float* pqw;
  const float* cx;   ///< centre of mass in the shape frame
  const float* cy;
  const float* cz;
};

/// Accumulated force (N, at the centre of mass) and torque (N m) per body.
struct BodyForces {
  const float* fx;
  const float* fy;
  const float* fz;
  const float* tx;
  const float* ty;
  const float* tz;
};

/// Per-body damping (1/s) and gravity scale.
struct BodyDamping {
  const float* linear;
  const float* angular;
  const float* gravity_scale;
};

/// Orientation of body i's principal frame: rot(q) rot(pq).
IMPACT_INLINE Quat principal_orientation(const RigidBodies& b, uint32_t i) {
  return Quat{b.qx[i], b.qy[i], b.qz[i], b.qw[i]} * Quat{b.pqx[i], b.pqy[i], b.pqz[i], b.pqw[i]};
}

/// w' from the implicit gyroscopic step, in the principal frame (moments I = 1 / ii).
Vec3 gyroscopic_step(Vec3 w, Vec3 moments, float h);

void integrate_rigid_velocities(float h, Vec3 gravity, bool gyroscopic, const RigidBodies& b,
                                const BodyForces* forces, const BodyDamping* damping, Range r);

void integrate_rigid_positions(float h, const RigidBodies& b, Range r);

}  // namespace impact::kernels
