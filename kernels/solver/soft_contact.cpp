#include "kernels/solver/soft_contact.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace impact::kernels {
namespace {

IMPACT_INLINE Vec3 load3(const float* x, const float* y, const float* z, uint32_t i) { return {x[i], y[i], z[i]}; }

// A unit vector perpendicular to unit n, chosen continuously away from the poles
// (Frisvad's branch on the smallest component, as Box3D's b3Perp).
IMPACT_INLINE Vec3 perpendicular(Vec3 n) {
  if (std::fabs(n.x) < 0.57735f) {
    const float inv = 1.0f / std::sqrt(n.y * n.y + n.z * n.z);
    return {0.0f, n.z * inv, -n.y * inv};
  }
  const float inv = 1.0f / std::sqrt(n.x * n.x + n.y * n.y);
  return {n.y * inv, -n.x * inv, 0.0f};
}

// Inverse of a symmetric 3x3 (zero when singular).
IMPACT_INLINE Sym3 inverse(const Sym3& m) {
  const float c00 = m.yy * m.zz - m.yz * m.yz, c01 = m.xz * m.yz - m.xy * m.zz, c02 = m.xy * m.yz - m.xz * m.yy;
  const float det = m.xx * c00 + m.xy * c01 + m.xz * c02;
  if (!(std::fabs(det) > 1e-30f)) return {0, 0, 0, 0, 0, 0};
  const float inv = 1.0f / det;
  return {c00 * inv,
          (m.xx * m.zz - m.xz * m.xz) * inv,
          (m.xx * m.yy - m.xy * m.xy) * inv,
          c01 * inv,
          c02 * inv,
          (m.xz * m.xy - m.xx * m.yz) * inv};
}

IMPACT_INLINE Sym3 add(const Sym3& a, const Sym3& b) { return a + b; }

// Double-precision rotation helpers of the gyroscopic update.
struct DVec {
  double x, y, z;
};
struct DQuat {
  double x, y, z, w;
};
IMPACT_INLINE DQuat unit(Quat q) {
  const double x = q.x, y = q.y, z = q.z, w = q.w;
  const double inv = 1.0 / std::sqrt(x * x + y * y + z * z + w * w);
  return {x * inv, y * inv, z * inv, w * inv};
}
IMPACT_INLINE DVec cross_d(DVec a, DVec b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
IMPACT_INLINE DVec rotate_d(DQuat q, DVec v) {
  const DVec u{q.x, q.y, q.z};
  const DVec c = cross_d(u, v);
  const DVec t{2.0 * c.x, 2.0 * c.y, 2.0 * c.z};
  const DVec e = cross_d(u, t);
  return {v.x + q.w * t.x + e.x, v.y + q.w * t.y + e.y, v.z + q.w * t.z + e.z};
}
IMPACT_INLINE DVec rotate_inv_d(DQuat q, DVec v) { return rotate_d({-q.x, -q.y, -q.z, q.w}, v); }
IMPACT_INLINE DVec rotate_inv_d(DQuat q, Vec3 v) { return rotate_inv_d(q, DVec{v.x, v.y, v.z}); }
IMPACT_INLINE DVec mul_d(Vec3 a, DVec b) { return {a.x * b.x, a.y * b.y, a.z * b.z}; }

// Applies linear impulse P at anchors ra, rb: a gets -P, b gets +P.
IMPACT_INLINE void push(const ContactConstraint& k, Vec3 P, Vec3 ra, Vec3 rb, Vec3& va, Vec3& wa, Vec3& vb,
                        Vec3& wb) {
  va = va - k.ma * P;
  wa = wa - k.ia * cross(ra, P);
  vb = vb + k.mb * P;
  wb = wb + k.ib * cross(rb, P);
}

IMPACT_INLINE void write_back(const ContactConstraint& k, SolverBody* bodies, Vec3 va, Vec3 wa, Vec3 vb, Vec3 wb) {
  if (k.ma > 0.0f) {
    bodies[k.a].v = va;
    bodies[k.a].w = wa;
  }
  if (k.mb > 0.0f) {
    bodies[k.b].v = vb;
    bodies[k.b].w = wb;
  }
}

}  // namespace

SoftParams soft_params(float dt, uint32_t substeps, float hertz, float zeta) {
  SoftParams p{};
  p.dt = dt;
  p.h = dt / static_cast<float>(substeps);
  const float cap = kMaxHertzPerSubstepRate / p.h;
  const float f = hertz > 0.0f ? std::min(hertz, cap) : cap;
  const float omega = 2.0f * std::numbers::pi_v<float> * f;
  const float a1 = 2.0f * zeta + p.h * omega;
  const float a2 = p.h * omega * a1;
  const float a3 = 1.0f / (1.0f + a2);
  p.bias_rate = omega / a1;
  p.mass_scale = a2 * a3;
  p.impulse_scale = a3;
  return p;
}

void prepare_bodies(const SoftParams& p, Vec3 g, const SoftBodyInput& in, SolverBody* IMPACT_RESTRICT out,
                    BodyDrive* IMPACT_RESTRICT drive, Sym3* IMPACT_RESTRICT inv_inertia, Vec3* IMPACT_RESTRICT com,
                    GyroBody* IMPACT_RESTRICT gyro, Range r) {
  const RigidBodies& b = in.rigid;
  for (uint32_t i = r.begin; i < r.end; ++i) {
    const float m = b.inv_mass[i];
    SolverBody s{};
    s.v = load3(b.vx, b.vy, b.vz, i);
    s.inv_mass = m;
    s.dq = {0.0f, 0.0f, 0.0f, 1.0f};
    BodyDrive d{};
    Sym3 ii{0, 0, 0, 0, 0, 0};
    Vec3 c = load3(b.px, b.py, b.pz, i);
    if (in.rotating) {
      const Quat q{b.qx[i], b.qy[i], b.qz[i], b.qw[i]};
      c = c + rotate(q, load3(b.cx, b.cy, b.cz, i));
      s.w = load3(b.wx, b.wy, b.wz, i);
      const Quat rp = principal_orientation(b, i);
      const Vec3 d_inv{b.iix[i], b.iiy[i], b.iiz[i]};
      if (m > 0.0f) ii = rotate_diagonal(to_matrix(rp), d_inv);
      if (gyro != nullptr) {
        GyroBody gb{rp, {0, 0, 0}, d_inv};
        if (m > 0.0f && d_inv.x > 0.0f && d_inv.y > 0.0f && d_inv.z > 0.0f)
          gb.moments = {1.0f / d_inv.x, 1.0f / d_inv.y, 1.0f / d_inv.z};
        gyro[i] = gb;
      }
    }
    if (m > 0.0f) {
      Vec3 accel = g;
      if (in.damping != nullptr) {
        accel = in.damping->gravity_scale[i] * g;
        s.v = (1.0f / (1.0f + p.dt * in.damping->linear[i])) * s.v;
        s.w = (1.0f / (1.0f + p.dt * in.damping->angular[i])) * s.w;
      }
      if (in.forces != nullptr) {
        accel = accel + m * load3(in.forces->fx, in.forces->fy, in.forces->fz, i);
        d.dw = p.h * (ii * load3(in.forces->tx, in.forces->ty, in.forces->tz, i));
      }
      d.dv = p.h * accel;
    }
    out[i] = s;
    drive[i] = d;
    inv_inertia[i] = ii;
    com[i] = c;
  }
}

void prepare_contacts(const SoftParams& p, const ContactManifoldArrays& c, const uint32_t* order,
                      const uint32_t* first_point, const SolverBody* bodies, const Sym3* inv_inertia,
                      const Vec3* com, uint32_t body_count, const ContactMaterials& mat, const WarmPoint* warm,
                      ContactConstraint* IMPACT_RESTRICT out, ContactPoint* IMPACT_RESTRICT points, Range r) {
  const Sym3 zero{0, 0, 0, 0, 0, 0};
  for (uint32_t i = r.begin; i < r.end; ++i) {
    const uint32_t m = order[i];
    ContactConstraint k{};
    const bool plane = c.b_is_plane[m] != 0;
    k.a = c.a[m];
    k.b = plane ? body_count : c.b[m];
    k.first = first_point[i];
    k.count = c.count[m];
    k.deep = c.depth[m] > p.max_push_speed * p.dt ? 1u : 0u;
    k.ma = bodies[k.a].inv_mass;
    k.mb = plane ? 0.0f : bodies[k.b].inv_mass;
    k.ia = inv_inertia[k.a];
    k.ib = plane ? zero : inv_inertia[k.b];
    k.n = {c.normal[0][m], c.normal[1][m], c.normal[2][m]};
    k.t1 = perpendicular(k.n);
    k.t2 = cross(k.n, k.t1);
    const float fb = plane ? mat.plane_friction[c.b[m]] : mat.friction[k.b];
    k.friction = std::sqrt(mat.friction[k.a] * fb);
    k.restitution = std::max(mat.restitution[k.a], plane ? mat.plane_restitution[c.b[m]] : mat.restitution[k.b]);
    k.rolling = plane ? mat.rolling[k.a] : std::max(mat.rolling[k.a], mat.rolling[k.b]);
    const Vec3 com_a = com[k.a];
    const Vec3 com_b = plane ? com_a : com[k.b];
    const SolverBody& A = bodies[k.a];
    const SolverBody& B = bodies[k.b];  // the zero body for a plane
    const uint32_t row0 = first_point_of(c, m);
    Vec3 centre_a{0, 0, 0}, centre_b{0, 0, 0};
    bool warmed = false;
    for (uint32_t j = 0; j < k.count; ++j) {
      const uint32_t row = row0 + j;
      ContactPoint& cp = points[k.first + j];
      const Vec3 x{c.point[0][row], c.point[1][row], c.point[2][row]};
      cp.ra = x - com_a;
      // A plane never moves (dp_b = 0, dq_b = 1): any anchor gives the same
      // separation change, and r_b = r_a keeps it free of world-coordinate rounding.
      cp.rb = plane ? cp.ra : x - com_b;
      const float s0 = -c.point_depth[row];
      cp.base = s0 - dot(cp.rb - cp.ra, k.n);
      const Vec3 rna = cross(cp.ra, k.n), rnb = cross(cp.rb, k.n);
      const float kn = k.ma + k.mb + dot(rna, k.ia * rna) + dot(rnb, k.ib * rnb);
      cp.normal_mass = kn > 0.0f ? 1.0f / kn : 0.0f;
      const Vec3 vra = A.v + cross(A.w, cp.ra), vrb = B.v + cross(B.w, cp.rb);
      cp.approach = dot(vrb - vra, k.n);
      cp.impulse = 0.0f;
      cp.total = 0.0f;
      cp.max_impulse = 0.0f;
      if (warm != nullptr && warm[row].normal >= 0.0f) {
        cp.impulse = p.warm_start * warm[row].normal;
        if (!warmed) {
          const WarmPoint& w = warm[row];
          const Vec3 f{w.fx, w.fy, w.fz};
          k.f1 = p.warm_start * dot(f, k.t1);
          k.f2 = p.warm_start * dot(f, k.t2);
          k.twist = p.warm_start * w.twist;
          k.roll = p.warm_start * Vec3{w.rx, w.ry, w.rz};
          warmed = true;
        }
      }
      centre_a = centre_a + cp.ra;
      centre_b = centre_b + cp.rb;
    }
    const float inv_count = 1.0f / static_cast<float>(k.count);
    k.ca = inv_count * centre_a;
    k.cb = inv_count * centre_b;
    for (uint32_t j = 0; j < k.count; ++j) points[k.first + j].lever = length(points[k.first + j].ra - k.ca);
    const Vec3 ra1 = cross(k.ca, k.t1), ra2 = cross(k.ca, k.t2), rb1 = cross(k.cb, k.t1), rb2 = cross(k.cb, k.t2);
    const float m11 = k.ma + k.mb + dot(ra1, k.ia * ra1) + dot(rb1, k.ib * rb1);
    const float m22 = k.ma + k.mb + dot(ra2, k.ia * ra2) + dot(rb2, k.ib * rb2);
    const float m12 = dot(ra1, k.ia * ra2) + dot(rb1, k.ib * rb2);
    const float det = m11 * m22 - m12 * m12;
    if (det > 0.0f) {
      const float inv = 1.0f / det;
      k.k11 = m22 * inv;
      k.k22 = m11 * inv;
      k.k12 = -m12 * inv;
    }
    const float kt = dot(k.n, add(k.ia, k.ib) * k.n);
    k.twist_mass = kt > 0.0f ? 1.0f / kt : 0.0f;
    k.rolling_mass = k.rolling > 0.0f ? inverse(add(k.ia, k.ib)) : zero;
    out[i] = k;
  }
}

void integrate_substep_velocities(const BodyDrive* IMPACT_RESTRICT drive, SolverBody* IMPACT_RESTRICT b, Range r) {
  for (uint32_t i = r.begin; i < r.end; ++i) {
    b[i].v = b[i].v + drive[i].dv;
    b[i].w = b[i].w + drive[i].dw;
  }
}

void integrate_substep_positions(float h, const GyroBody* IMPACT_RESTRICT gyro, SolverBody* IMPACT_RESTRICT b,
                                 Range r) {
  for (uint32_t i = r.begin; i < r.end; ++i) {
    SolverBody& s = b[i];
    s.dp = s.dp + h * s.v;
    if (s.w.x == 0.0f && s.w.y == 0.0f && s.w.z == 0.0f) continue;
    Quat dq = integrate(s.dq, s.w, h);
    if (gyro != nullptr && gyro[i].moments.x > 0.0f) {
      // L = R I R^T w at the old frame R = dq frame; w' = R' I^-1 R'^T L at the new
      // frame R', first turned by w, then again by the mean of w and that w'.
      const GyroBody& g = gyro[i];
      // In double: float rotations of near-unit quaternions scale the part of v
      // across the axis by 1 + O(eps) with a bias that |L| would accumulate.
      const DQuat r0 = unit(s.dq * g.frame);
      const DVec l = rotate_d(r0, mul_d(g.moments, rotate_inv_d(r0, s.w)));
      auto spin_at = [&](Quat turned) {
        const DQuat r1 = unit(turned * g.frame);
        const DVec w = rotate_d(r1, mul_d(g.inv_moments, rotate_inv_d(r1, l)));
        return Vec3{static_cast<float>(w.x), static_cast<float>(w.y), static_cast<float>(w.z)};
      };
      const Vec3 w1 = spin_at(dq);
      dq = integrate(s.dq, 0.5f * (s.w + w1), h);
      s.w = spin_at(dq);
    }
    s.dq = dq;
  }
}

void warm_start_contacts(const ContactConstraint* cons, const ContactPoint* points, SolverBody* bodies, Range r) {
  for (uint32_t i = r.begin; i < r.end; ++i) {
    const ContactConstraint& k = cons[i];
    Vec3 va = bodies[k.a].v, wa = bodies[k.a].w, vb = bodies[k.b].v, wb = bodies[k.b].w;
    for (uint32_t j = 0; j < k.count; ++j) {
      const ContactPoint& cp = points[k.first + j];
      push(k, cp.impulse * k.n, cp.ra, cp.rb, va, wa, vb, wb);
    }
    push(k, k.f1 * k.t1 + k.f2 * k.t2, k.ca, k.cb, va, wa, vb, wb);
    const Vec3 ang = k.twist * k.n + k.roll;
    wa = wa - k.ia * ang;
    wb = wb + k.ib * ang;
    write_back(k, bodies, va, wa, vb, wb);
  }
}

void solve_contacts(const SoftParams& p, bool use_bias, ContactConstraint* cons, ContactPoint* points,
                    SolverBody* bodies, Range r) {
  const float inv_h = 1.0f / p.h;
  for (uint32_t i = r.begin; i < r.end; ++i) {
    ContactConstraint& k = cons[i];
    const SolverBody& A = bodies[k.a];
    const SolverBody& B = bodies[k.b];
    Vec3 va = A.v, wa = A.w, vb = B.v, wb = B.w;
    const Vec3 dp = B.dp - A.dp;
    const Quat dqa = A.dq, dqb = B.dq;
    float total = 0.0f, twist_limit = 0.0f;
    for (uint32_t j = 0; j < k.count; ++j) {
      ContactPoint& cp = points[k.first + j];
      const Vec3 ds = dp + rotate(dqb, cp.rb) - rotate(dqa, cp.ra);
      const float s = dot(ds, k.n) + cp.base + p.slop;
      float bias = 0.0f, mass_scale = 1.0f, impulse_scale = 0.0f;
      if (s > 0.0f) {
        bias = s * inv_h;  // speculative: may close the gap, no more
      } else if (use_bias && k.deep == 0) {
        bias = std::max(p.bias_rate * p.mass_scale * s, -p.max_push_speed);
        mass_scale = p.mass_scale;
        impulse_scale = p.impulse_scale;
      }
      const float vn = dot((vb + cross(wb, cp.rb)) - (va + cross(wa, cp.ra)), k.n);
      const float d = -cp.normal_mass * (mass_scale * vn + bias) - impulse_scale * cp.impulse;
      const float next = std::max(cp.impulse + d, 0.0f);
      const float applied = next - cp.impulse;
      cp.impulse = next;
      cp.max_impulse = std::max(cp.max_impulse, next);
      if (!use_bias) cp.total += next;  // the relax pass ends a substep: its impulse is final
      total += next;
      twist_limit += cp.lever * next;
      push(k, applied * k.n, cp.ra, cp.rb, va, wa, vb, wb);
    }
    if (!use_bias) {
      // Twist about the normal.
      {
        const float speed = dot(k.n, wb - wa);
        const float lim = k.friction * twist_limit;
        const float old = k.twist;
        k.twist = std::clamp(old - k.twist_mass * speed, -lim, lim);
        const Vec3 ang = (k.twist - old) * k.n;
        wa = wa - k.ia * ang;
        wb = wb + k.ib * ang;
      }
      // Rolling resistance: a 3D angular impulse opposing relative spin.
      if (k.rolling > 0.0f) {
        const Vec3 old = k.roll;
        Vec3 next = old - k.rolling_mass * (wb - wa);
        const float lim = k.rolling * total;
        const float mag2 = dot(next, next);
        if (mag2 > lim * lim) next = (lim / std::sqrt(mag2)) * next;
        k.roll = next;
        const Vec3 ang = next - old;
        wa = wa - k.ia * ang;
        wb = wb + k.ib * ang;
      }
      // Coulomb friction at the anchor, clamped to the disc of radius mu * sum(lambda).
      {
        const Vec3 vr = (vb + cross(wb, k.cb)) - (va + cross(wa, k.ca));
        const float v1 = dot(vr, k.t1), v2 = dot(vr, k.t2);
        float f1 = k.f1 - (k.k11 * v1 + k.k12 * v2);
        float f2 = k.f2 - (k.k12 * v1 + k.k22 * v2);
        const float lim = k.friction * total;
        const float mag2 = f1 * f1 + f2 * f2;
        if (mag2 > lim * lim) {
          const float sc = lim / std::sqrt(mag2);
          f1 *= sc;
          f2 *= sc;
        }
        const Vec3 P = (f1 - k.f1) * k.t1 + (f2 - k.f2) * k.t2;
        k.f1 = f1;
        k.f2 = f2;
        push(k, P, k.ca, k.cb, va, wa, vb, wb);
      }
    }
    write_back(k, bodies, va, wa, vb, wb);
  }
}

void restitute_contacts(const SoftParams& p, const ContactConstraint* cons, ContactPoint* points,
                        SolverBody* bodies, Range r) {
  for (uint32_t i = r.begin; i < r.end; ++i) {
    const ContactConstraint& k = cons[i];
    if (k.restitution == 0.0f) continue;
    Vec3 va = bodies[k.a].v, wa = bodies[k.a].w, vb = bodies[k.b].v, wb = bodies[k.b].w;
    for (uint32_t j = 0; j < k.count; ++j) {
      ContactPoint& cp = points[k.first + j];
      // Only points that approached fast enough and took an impulse bounce.
      if (cp.approach > -p.restitution_threshold || cp.max_impulse == 0.0f) continue;
      const float vn = dot((vb + cross(wb, cp.rb)) - (va + cross(wa, cp.ra)), k.n);
      const float d = -cp.normal_mass * (vn + k.restitution * cp.approach);
      const float next = std::max(cp.impulse + d, 0.0f);
      const float applied = next - cp.impulse;
      cp.impulse = next;
      cp.total += applied;
      push(k, applied * k.n, cp.ra, cp.rb, va, wa, vb, wb);
    }
    write_back(k, bodies, va, wa, vb, wb);
  }
}

void store_contacts(const ContactManifoldArrays& c, const uint32_t* order, const ContactConstraint* cons,
                    const ContactPoint* points, WarmPoint* IMPACT_RESTRICT out, float* IMPACT_RESTRICT impulse_out,
                    Range r) {
  for (uint32_t i = r.begin; i < r.end; ++i) {
    const ContactConstraint& k = cons[i];
    const uint32_t row0 = first_point_of(c, order[i]);
    const Vec3 f = k.f1 * k.t1 + k.f2 * k.t2;
    for (uint32_t j = 0; j < k.count; ++j) {
      const ContactPoint& cp = points[k.first + j];
      out[row0 + j] = WarmPoint{cp.impulse, f.x, f.y, f.z, k.twist, k.roll.x, k.roll.y, k.roll.z};
      impulse_out[row0 + j] = cp.total;
    }
  }
}

void match_warm_points(const uint64_t* IMPACT_RESTRICT keys, const WarmTable& prev, WarmPoint* IMPACT_RESTRICT out,
                       Range r) {
  for (uint32_t k = r.begin; k < r.end; ++k) {
    WarmPoint w{-1.0f, 0, 0, 0, 0, 0, 0, 0};
    const auto a = static_cast<uint32_t>(keys[k] >> 32);
    if (a < prev.body_count) {
      // Last step's points of body a: a handful, scanned linearly.
      for (uint32_t j = prev.start[a]; j < prev.start[a + 1]; ++j) {
        if (prev.keys[j] == keys[k]) {
          w = prev.values[prev.index[j]];
          break;
        }
      }
    }
    out[k] = w;
  }
}

void finish_bodies(const SoftBodyInput& in, const SolverBody* IMPACT_RESTRICT b, const Vec3* IMPACT_RESTRICT com,
                   Range r) {
  const RigidBodies& s = in.rigid;
  for (uint32_t i = r.begin; i < r.end; ++i) {
    const SolverBody& x = b[i];
    s.vx[i] = x.v.x;
    s.vy[i] = x.v.y;
    s.vz[i] = x.v.z;
    if (!in.rotating) {
      s.px[i] += x.dp.x;
      s.py[i] += x.dp.y;
      s.pz[i] += x.dp.z;
      continue;
    }
    s.wx[i] = x.w.x;
    s.wy[i] = x.w.y;
    s.wz[i] = x.w.z;
    const Quat q0{s.qx[i], s.qy[i], s.qz[i], s.qw[i]};
    const bool turned = x.dq.x != 0.0f || x.dq.y != 0.0f || x.dq.z != 0.0f || x.dq.w != 1.0f;
    const Quat q1 = turned ? normalize(x.dq * q0) : q0;
    const Vec3 c{s.cx[i], s.cy[i], s.cz[i]};
    const Vec3 p1 = turned ? com[i] + x.dp - rotate(q1, c) : Vec3{s.px[i] + x.dp.x, s.py[i] + x.dp.y, s.pz[i] + x.dp.z};
    s.px[i] = p1.x;
    s.py[i] = p1.y;
    s.pz[i] = p1.z;
    s.qx[i] = q1.x;
    s.qy[i] = q1.y;
    s.qz[i] = q1.z;
    s.qw[i] = q1.w;
  }
}

}  // namespace impact::kernels
