#include "kernels/integrate/rigid_euler.h"

namespace impact::kernels {

Vec3 gyroscopic_step(Vec3 w, Vec3 I, float h) {
  // f(w) = h w x (I w) at w0; J = diag(I) + h (skew(w) diag(I) - skew(I w)); w1 = w0 - J^-1 f.
  const Vec3 L = mul(I, w);
  const Vec3 f = h * cross(w, L);
  // Rows of J.
  const float j00 = I.x, j01 = h * (-w.z * I.y + L.z), j02 = h * (w.y * I.z - L.y);
  const float j10 = h * (w.z * I.x - L.z), j11 = I.y, j12 = h * (-w.x * I.z + L.x);
  const float j20 = h * (-w.y * I.x + L.y), j21 = h * (w.x * I.y - L.x), j22 = I.z;
  // Cramer's rule.
  const float c00 = j11 * j22 - j12 * j21, c01 = j12 * j20 - j10 * j22, c02 = j10 * j21 - j11 * j20;
  const float det = j00 * c00 + j01 * c01 + j02 * c02;
  if (!(det > 0.0f)) return w;  // J is I plus a small skew part: det > 0 unless degenerate
  const float inv = 1.0f / det;
  const float x = (c00 * f.x + (j02 * j21 - j01 * j22) * f.y + (j01 * j12 - j02 * j11) * f.z) * inv;
  const float y = (c01 * f.x + (j00 * j22 - j02 * j20) * f.y + (j02 * j10 - j00 * j12) * f.z) * inv;
  const float z = (c02 * f.x + (j01 * j20 - j00 * j21) * f.y + (j00 * j11 - j01 * j10) * f.z) * inv;
  return {w.x - x, w.y - y, w.z - z};
}

void integrate_rigid_velocities(float h, Vec3 g, bool gyroscopic, const RigidBodies& b,
                                const BodyForces* forces, const BodyDamping* damping, Range r) {
  for (uint32_t i = r.begin; i < r.end; ++i) {
    const float m = b.inv_mass[i];
    if (!(m > 0.0f)) continue;  // static or kinematic: moved by its own velocities
    Vec3 v{b.vx[i], b.vy[i], b.vz[i]};
    Vec3 w{b.wx[i], b.wy[i], b.wz[i]};
    Vec3 dv = g;
    float lin = 1.0f, ang = 1.0f;
    if (damping != nullptr) {
      dv = damping->gravity_scale[i] * g;
      lin = 1.0f / (1.0f + h * damping->linear[i]);
      ang = 1.0f / (1.0f + h * damping->angular[i]);
    }
    const Vec3 ii{b.iix[i], b.iiy[i], b.iiz[i]};
    const Quat rp = principal_orientation(b, i);
    // Angular velocity in the principal frame.
    Vec3 wp = rotate_inv(rp, w);
    if (forces != nullptr) {
      dv = dv + m * Vec3{forces->fx[i], forces->fy[i], forces->fz[i]};
      wp = wp + h * mul(ii, rotate_inv(rp, {forces->tx[i], forces->ty[i], forces->tz[i]}));
    }
    v = lin * v + h * dv;
    wp = ang * wp;
    if (gyroscopic && ii.x > 0.0f && ii.y > 0.0f && ii.z > 0.0f)
      wp = gyroscopic_step(wp, {1.0f / ii.x, 1.0f / ii.y, 1.0f / ii.z}, h);
    w = rotate(rp, wp);
    b.vx[i] = v.x;
    b.vy[i] = v.y;
    b.vz[i] = v.z;
    b.wx[i] = w.x;
    b.wy[i] = w.y;
    b.wz[i] = w.z;
  }
}

void integrate_rigid_positions(float h, const RigidBodies& b, Range r) {
  for (uint32_t i = r.begin; i < r.end; ++i) {
    const Quat q{b.qx[i], b.qy[i], b.qz[i], b.qw[i]};
    const Vec3 c{b.cx[i], b.cy[i], b.cz[i]};
    const Vec3 com = Vec3{b.px[i], b.py[i], b.pz[i]} + rotate(q, c);
    const Vec3 w{b.wx[i], b.wy[i], b.wz[i]};
    // A body that does not turn keeps its orientation's bits (no renormalisation drift).
    const bool turns = w.x != 0.0f || w.y != 0.0f || w.z != 0.0f;
    const Quat q1 = turns ? integrate(q, w, h) : q;
    const Vec3 p1 = com + h * Vec3{b.vx[i], b.vy[i], b.vz[i]} - rotate(q1, c);
    b.px[i] = p1.x;
    b.py[i] = p1.y;
    b.pz[i] = p1.z;
    b.qx[i] = q1.x;
    b.qy[i] = q1.y;
    b.qz[i] = q1.z;
    b.qw[i] = q1.w;
  }
}

}  // namespace impact::kernels
