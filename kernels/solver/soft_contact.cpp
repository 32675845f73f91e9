#include "kernels/solver/soft_contact.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "kernels/simd/vec3.h"
// No FMA contraction in this file: GCC contracts the block (FloatW) and slot (Float1)
// instantiations of one template differently, and they must give the same bytes.
#include "kernels/narrowphase/lanes/no_contract.h"  // last: its pragma covers what follows

namespace impact::kernels {
namespace {

IMPACT_INLINE Vec3 load3(const float* x, const float* y, const float* z, uint32_t i) { return {x[i], y[i], z[i]}; }


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

// ---------------------------------------------------------------------------------------
// Lane kernels: one template over the lane type F (FloatW: a block, lane 0; Float1: one
// slot, its lane). Lane fields are read at &field[lane], so both paths read the same
// storage; the expressions are those of the per-constraint math, in its order.
// ---------------------------------------------------------------------------------------

using simd::V3;
constexpr uint32_t W = kContactLanes;

template <class F>
IMPACT_INLINE F ld(const float* f, uint32_t lane) {
  return F::load(f + lane);
}
template <class F>
IMPACT_INLINE V3<F> ld3(const float (*f)[W], uint32_t lane) {
  return {F::load(f[0] + lane), F::load(f[1] + lane), F::load(f[2] + lane)};
}
template <class F>
IMPACT_INLINE void st3(float (*f)[W], uint32_t lane, const V3<F>& v) {
  v.x.store(f[0] + lane);
  v.y.store(f[1] + lane);
  v.z.store(f[2] + lane);
}

template <class F>
struct S3 {
  F xx, yy, zz, xy, xz, yz;
};
template <class F>
IMPACT_INLINE S3<F> ld_sym(const float (*f)[W], uint32_t lane) {
  return {F::load(f[0] + lane), F::load(f[1] + lane), F::load(f[2] + lane),
          F::load(f[3] + lane), F::load(f[4] + lane), F::load(f[5] + lane)};
}
// As Sym3 * Vec3.
template <class F>
IMPACT_INLINE V3<F> operator*(const S3<F>& s, const V3<F>& v) {
  return {s.xx * v.x + s.xy * v.y + s.xz * v.z, s.xy * v.x + s.yy * v.y + s.yz * v.z,
          s.xz * v.x + s.yz * v.y + s.zz * v.z};
}
// As rotate(Quat, Vec3): v + w t + u x t, t = 2 (u x v).
template <class F>
IMPACT_INLINE V3<F> rotate_lanes(const F* q, const V3<F>& v) {
  const V3<F> u{q[0], q[1], q[2]};
  const V3<F> c = simd::cross(u, v);
  const V3<F> t{F(2.0f) * c.x, F(2.0f) * c.y, F(2.0f) * c.z};
  const V3<F> e = simd::cross(u, t);
  return {v.x + q[3] * t.x + e.x, v.y + q[3] * t.y + e.y, v.z + q[3] * t.z + e.z};
}
// s * v as the scalar code's float * Vec3 (s first).
template <class F>
IMPACT_INLINE V3<F> scale(F s, const V3<F>& v) {
  return {s * v.x, s * v.y, s * v.z};
}
template <class F>
IMPACT_INLINE V3<F> keep(typename F::Mask m, const V3<F>& changed, const V3<F>& old) {
  return simd::select(m, changed, old);
}

// Each lane's body: 8 floats of its SolverBody row from float `offset` (0: v, inv_mass,
// w, pad; 8: dp, pad, dq), transposed into lanes.
template <class F>
IMPACT_INLINE void gather_body(const SolverBody* bodies, const int32_t* idx, uint32_t offset, F* out) {
  constexpr uint32_t N = F::kWidth;
  static_assert(N <= 8 && 8 % N == 0, "gather_body: widths 1, 2, 4, 8");
  for (uint32_t o = 0; o < 8; o += N) {
    const float* rows[N];
    for (uint32_t l = 0; l < N; ++l) rows[l] = reinterpret_cast<const float*>(bodies + idx[l]) + offset + o;
    simd::load_transposed(rows, out + o);
  }
}
// The inverse for the lanes of `bits`: v, inv_mass (as gathered), w, pad.
template <class F>
IMPACT_INLINE void scatter_body(SolverBody* bodies, const int32_t* idx, uint32_t bits, const F* in) {
  constexpr uint32_t N = F::kWidth;
  for (uint32_t o = 0; o < 8; o += N) {
    float* rows[N];
    for (uint32_t l = 0; l < N; ++l) rows[l] = reinterpret_cast<float*>(bodies + idx[l]) + o;
    simd::store_transposed(rows, in + o, bits);
  }
}

// The velocities of a lane's two bodies while a pass runs on them.
template <class F>
struct LaneBodies {
  F ra[8], rb[8];  // gathered rows: v, inv_mass, w, pad
  V3<F> va, wa, vb, wb;
};
template <class F>
IMPACT_INLINE void load_velocities(const ContactBlock& k, uint32_t lane, const SolverBody* bodies, LaneBodies<F>& s) {
  gather_body(bodies, k.a + lane, 0, s.ra);
  gather_body(bodies, k.b + lane, 0, s.rb);
  s.va = {s.ra[0], s.ra[1], s.ra[2]};
  s.wa = {s.ra[4], s.ra[5], s.ra[6]};
  s.vb = {s.rb[0], s.rb[1], s.rb[2]};
  s.wb = {s.rb[4], s.rb[5], s.rb[6]};
}
// Back to the lanes whose body is dynamic (ma, mb > 0): never the zero body or a static.
template <class F>
IMPACT_INLINE void store_velocities(const ContactBlock& k, uint32_t lane, F ma, F mb, LaneBodies<F>& s,
                                    SolverBody* bodies) {
  s.ra[0] = s.va.x, s.ra[1] = s.va.y, s.ra[2] = s.va.z;
  s.ra[4] = s.wa.x, s.ra[5] = s.wa.y, s.ra[6] = s.wa.z;
  s.rb[0] = s.vb.x, s.rb[1] = s.vb.y, s.rb[2] = s.vb.z;
  s.rb[4] = s.wb.x, s.rb[5] = s.wb.y, s.rb[6] = s.wb.z;
  scatter_body(bodies, k.a + lane, simd::bits(ma > F(0.0f)), s.ra);
  scatter_body(bodies, k.b + lane, simd::bits(mb > F(0.0f)), s.rb);
}

// The constraint's masses.
template <class F>
struct LaneMass {
  F ma, mb;
  S3<F> ia, ib;
};
template <class F>
IMPACT_INLINE LaneMass<F> load_mass(const ContactBlock& k, uint32_t lane) {
  return {ld<F>(k.ma, lane), ld<F>(k.mb, lane), ld_sym<F>(k.ia, lane), ld_sym<F>(k.ib, lane)};
}

// Linear impulse P at anchors ra, rb: a gets -P, b gets +P (where m, else unchanged).
template <class F>
IMPACT_INLINE void push(const LaneMass<F>& m, const V3<F>& P, const V3<F>& ra, const V3<F>& rb, LaneBodies<F>& s) {
  s.va = s.va - scale(m.ma, P);
  s.wa = s.wa - m.ia * simd::cross(ra, P);
  s.vb = s.vb + scale(m.mb, P);
  s.wb = s.wb + m.ib * simd::cross(rb, P);
}
template <class F>
IMPACT_INLINE void push_masked(typename F::Mask live, const LaneMass<F>& m, const V3<F>& P, const V3<F>& ra,
                               const V3<F>& rb, LaneBodies<F>& s) {
  s.va = keep<F>(live, s.va - scale(m.ma, P), s.va);
  s.wa = keep<F>(live, s.wa - m.ia * simd::cross(ra, P), s.wa);
  s.vb = keep<F>(live, s.vb + scale(m.mb, P), s.vb);
  s.wb = keep<F>(live, s.wb + m.ib * simd::cross(rb, P), s.wb);
}
// Angular impulse: a gets -ang, b gets +ang.
template <class F>
IMPACT_INLINE void turn(const LaneMass<F>& m, const V3<F>& ang, LaneBodies<F>& s) {
  s.wa = s.wa - m.ia * ang;
  s.wb = s.wb + m.ib * ang;
}

template <class F>
IMPACT_INLINE typename F::Mask lanes_with_point(const ContactBlock& k, uint32_t lane, uint32_t j) {
  using I = typename F::Int;
  return I::load(k.count + lane) > I(static_cast<int32_t>(j));
}

template <class F>
IMPACT_INLINE void warm_start_lanes(const ContactBlock& k, uint32_t lane, SolverBody* bodies) {
  LaneBodies<F> s;
  load_velocities(k, lane, bodies, s);
  const LaneMass<F> m = load_mass<F>(k, lane);
  const V3<F> n = ld3<F>(k.n, lane);
  for (uint32_t j = 0; j < kMaxContactPoints; ++j) {
    const auto live = lanes_with_point<F>(k, lane, j);
    if (simd::none(live)) break;
    const ContactBlockPoint& cp = k.p[j];
    push_masked(live, m, scale(ld<F>(cp.impulse, lane), n), ld3<F>(cp.ra, lane), ld3<F>(cp.rb, lane), s);
  }
  const V3<F> t1 = ld3<F>(k.t1, lane), t2 = ld3<F>(k.t2, lane);
  push(m, scale(ld<F>(k.f1, lane), t1) + scale(ld<F>(k.f2, lane), t2), ld3<F>(k.ca, lane), ld3<F>(k.cb, lane), s);
  turn(m, scale(ld<F>(k.twist, lane), n) + ld3<F>(k.roll, lane), s);
  store_velocities(k, lane, m.ma, m.mb, s, bodies);
}

template <class F>
IMPACT_INLINE void solve_lanes(const SoftParams& p, bool use_bias, ContactBlock& k, uint32_t lane,
                               SolverBody* bodies) {
  using M = typename F::Mask;
  const F inv_h(1.0f / p.h);
  LaneBodies<F> s;
  load_velocities(k, lane, bodies, s);
  F da[8], db[8];  // dp, pad, dq
  gather_body(bodies, k.a + lane, 8, da);
  gather_body(bodies, k.b + lane, 8, db);
  const V3<F> dp = V3<F>{db[0], db[1], db[2]} - V3<F>{da[0], da[1], da[2]};
  const LaneMass<F> m = load_mass<F>(k, lane);
  const V3<F> n = ld3<F>(k.n, lane);
  using I = typename F::Int;
  const M soft_ok = use_bias ? I::load(k.deep + lane) == I(0) : M(false);
  const F bias_coef(p.bias_rate * p.mass_scale);
  F total(0.0f), twist_limit(0.0f);
  for (uint32_t j = 0; j < kMaxContactPoints; ++j) {
    const M live = lanes_with_point<F>(k, lane, j);
    if (simd::none(live)) break;
    ContactBlockPoint& cp = k.p[j];
    const V3<F> ra = ld3<F>(cp.ra, lane), rb = ld3<F>(cp.rb, lane);
    const V3<F> ds = dp + rotate_lanes(db + 4, rb) - rotate_lanes(da + 4, ra);
    const F sep = simd::dot(ds, n) + ld<F>(cp.base, lane) + F(p.slop);
    // s > 0 is speculative (the gap may close, no more); else the soft bias where
    // biased and not deep; else rigid.
    const M spec = sep > F(0.0f);
    const M soft = simd::andnot(soft_ok, spec);
    const F bias = simd::select(spec, sep * inv_h,
                                simd::select(soft, simd::max(F(-p.max_push_speed), bias_coef * sep), F(0.0f)));
    const F mass_scale = simd::select(soft, F(p.mass_scale), F(1.0f));
    const F impulse_scale = simd::select(soft, F(p.impulse_scale), F(0.0f));
    const F vn = simd::dot((s.vb + simd::cross(s.wb, rb)) - (s.va + simd::cross(s.wa, ra)), n);
    const F impulse = ld<F>(cp.impulse, lane);
    const F d = -ld<F>(cp.normal_mass, lane) * (mass_scale * vn + bias) - impulse_scale * impulse;
    const F next = simd::max(F(0.0f), impulse + d);  // std::max(impulse + d, 0)
    const F applied = next - impulse;
    simd::select(live, next, impulse).store(cp.impulse + lane);
    const F max_impulse = ld<F>(cp.max_impulse, lane);
    simd::select(live, simd::max(next, max_impulse), max_impulse).store(cp.max_impulse + lane);
    if (!use_bias) {  // the relax pass ends a substep: its impulse is final
      const F tot = ld<F>(cp.total, lane);
      simd::select(live, tot + next, tot).store(cp.total + lane);
    }
    total = simd::select(live, total + next, total);
    twist_limit = simd::select(live, twist_limit + ld<F>(cp.lever, lane) * next, twist_limit);
    push_masked(live, m, scale(applied, n), ra, rb, s);
  }
  if (!use_bias) {
    const F friction = ld<F>(k.friction, lane);
    // Twist about the normal.
    {
      const F speed = simd::dot(n, s.wb - s.wa);
      const F lim = friction * twist_limit;
      const F old = ld<F>(k.twist, lane);
      // std::clamp(x, -lim, lim) for lim >= 0.
      const F twist = simd::min(lim, simd::max(-lim, old - ld<F>(k.twist_mass, lane) * speed));
      twist.store(k.twist + lane);
      turn(m, scale(twist - old, n), s);
    }
    // Rolling resistance: a 3D angular impulse opposing relative spin.
    const F rolling = ld<F>(k.rolling, lane);
    const M rolls = rolling > F(0.0f);
    if (simd::any(rolls)) {
      const V3<F> old = ld3<F>(k.roll, lane);
      V3<F> next = old - ld_sym<F>(k.rolling_mass, lane) * (s.wb - s.wa);
      const F lim = rolling * total;
      const F mag2 = simd::dot(next, next);
      next = keep<F>(mag2 > lim * lim, scale(lim / simd::sqrt(mag2), next), next);
      next = keep<F>(rolls, next, old);
      st3(k.roll, lane, next);
      const V3<F> ang = next - old;
      const V3<F> wa = s.wa, wb = s.wb;
      turn(m, ang, s);
      s.wa = keep<F>(rolls, s.wa, wa);
      s.wb = keep<F>(rolls, s.wb, wb);
    }
    // Coulomb friction at the anchor, clamped to the disc of radius mu * sum(lambda).
    {
      const V3<F> ca = ld3<F>(k.ca, lane), cb = ld3<F>(k.cb, lane);
      const V3<F> t1 = ld3<F>(k.t1, lane), t2 = ld3<F>(k.t2, lane);
      const V3<F> vr = (s.vb + simd::cross(s.wb, cb)) - (s.va + simd::cross(s.wa, ca));
      const F v1 = simd::dot(vr, t1), v2 = simd::dot(vr, t2);
      const F k11 = ld<F>(k.k11, lane), k12 = ld<F>(k.k12, lane), k22 = ld<F>(k.k22, lane);
      const F f1_old = ld<F>(k.f1, lane), f2_old = ld<F>(k.f2, lane);
      F f1 = f1_old - (k11 * v1 + k12 * v2);
      F f2 = f2_old - (k12 * v1 + k22 * v2);
      const F lim = friction * total;
      const F mag2 = f1 * f1 + f2 * f2;
      const M over = mag2 > lim * lim;
      const F sc = lim / simd::sqrt(mag2);
      f1 = simd::select(over, f1 * sc, f1);
      f2 = simd::select(over, f2 * sc, f2);
      const V3<F> P = scale(f1 - f1_old, t1) + scale(f2 - f2_old, t2);
      f1.store(k.f1 + lane);
      f2.store(k.f2 + lane);
      push(m, P, ca, cb, s);
    }
  }
  store_velocities(k, lane, m.ma, m.mb, s, bodies);
}

template <class F>
IMPACT_INLINE void restitute_lanes(const SoftParams& p, ContactBlock& k, uint32_t lane, SolverBody* bodies) {
  using M = typename F::Mask;
  const F restitution = ld<F>(k.restitution, lane);
  const M bounces = restitution != F(0.0f);
  if (simd::none(bounces)) return;
  LaneBodies<F> s;
  load_velocities(k, lane, bodies, s);
  const LaneMass<F> m = load_mass<F>(k, lane);
  const V3<F> n = ld3<F>(k.n, lane);
  for (uint32_t j = 0; j < kMaxContactPoints; ++j) {
    const M live = lanes_with_point<F>(k, lane, j);
    if (simd::none(live)) break;
    ContactBlockPoint& cp = k.p[j];
    // Only points that approached fast enough and took an impulse bounce.
    const F approach = ld<F>(cp.approach, lane);
    const M quiet = (approach > F(-p.restitution_threshold)) | (ld<F>(cp.max_impulse, lane) == F(0.0f));
    const M act = simd::andnot(live & bounces, quiet);
    if (simd::none(act)) continue;
    const V3<F> ra = ld3<F>(cp.ra, lane), rb = ld3<F>(cp.rb, lane);
    const F vn = simd::dot((s.vb + simd::cross(s.wb, rb)) - (s.va + simd::cross(s.wa, ra)), n);
    const F impulse = ld<F>(cp.impulse, lane);
    const F d = -ld<F>(cp.normal_mass, lane) * (vn + restitution * approach);
    const F next = simd::max(F(0.0f), impulse + d);
    const F applied = next - impulse;
    simd::select(act, next, impulse).store(cp.impulse + lane);
    const F tot = ld<F>(cp.total, lane);
    simd::select(act, tot + applied, tot).store(cp.total + lane);
    push_masked(act, m, scale(applied, n), ra, rb, s);
  }
  // Lanes without restitution keep their velocities: storing them writes the same bytes.
  store_velocities(k, lane, m.ma, m.mb, s, bodies);
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
                      const SolverBody* bodies, const Sym3* inv_inertia, const Vec3* com, uint32_t body_count,
                      const ContactMaterials& mat, const WarmPoint* warm, ContactBlock* IMPACT_RESTRICT out, Range r) {
  const Sym3 zero{0, 0, 0, 0, 0, 0};
  auto put3 = [](float (*f)[W], uint32_t l, Vec3 v) { f[0][l] = v.x, f[1][l] = v.y, f[2][l] = v.z; };
  auto put_sym = [](float (*f)[W], uint32_t l, const Sym3& m) {
    f[0][l] = m.xx, f[1][l] = m.yy, f[2][l] = m.zz, f[3][l] = m.xy, f[4][l] = m.xz, f[5][l] = m.yz;
  };
  for (uint32_t i = r.begin; i < r.end; ++i) {
    ContactBlock& k = out[i / W];
    const uint32_t l = i % W;
    for (ContactBlockPoint& cp : k.p) {
      for (int d = 0; d < 3; ++d) cp.ra[d][l] = cp.rb[d][l] = 0.0f;
      cp.base[l] = cp.normal_mass[l] = cp.impulse[l] = cp.total[l] = 0.0f;
      cp.max_impulse[l] = cp.approach[l] = cp.lever[l] = 0.0f;
    }
    const uint32_t m = order[i];
    if (m == kNoConstraint) {  // padding: both bodies the zero body, no points, zero masses
      k.a[l] = k.b[l] = static_cast<int32_t>(body_count);
      k.count[l] = 0;
      k.deep[l] = 0;
      k.ma[l] = k.mb[l] = 0.0f;
      put_sym(k.ia, l, zero);
      put_sym(k.ib, l, zero);
      put3(k.n, l, {0, 0, 0});
      put3(k.t1, l, {0, 0, 0});
      put3(k.t2, l, {0, 0, 0});
      put3(k.ca, l, {0, 0, 0});
      put3(k.cb, l, {0, 0, 0});
      k.friction[l] = k.restitution[l] = k.rolling[l] = 0.0f;
      k.k11[l] = k.k12[l] = k.k22[l] = k.twist_mass[l] = 0.0f;
      put_sym(k.rolling_mass, l, zero);
      k.f1[l] = k.f2[l] = k.twist[l] = 0.0f;
      put3(k.roll, l, {0, 0, 0});
      continue;
    }
    const bool plane = c.b_is_plane[m] != 0;
    const uint32_t a = c.a[m];
    const uint32_t b = plane ? body_count : c.b[m];
    const uint32_t count = c.count[m];
    k.a[l] = static_cast<int32_t>(a);
    k.b[l] = static_cast<int32_t>(b);
    k.count[l] = static_cast<int32_t>(count);
    k.deep[l] = c.depth[m] > p.max_push_speed * p.dt ? 1 : 0;
    const float ma = bodies[a].inv_mass;
    const float mb = plane ? 0.0f : bodies[b].inv_mass;
    const Sym3 ia = inv_inertia[a];
    const Sym3 ib = plane ? zero : inv_inertia[b];
    const Vec3 n{c.normal[0][m], c.normal[1][m], c.normal[2][m]};
    const Vec3 t1 = perpendicular(n);
    const Vec3 t2 = cross(n, t1);
    const float fb = plane ? mat.plane_friction[c.b[m]] : mat.friction[b];
    const float friction = std::sqrt(mat.friction[a] * fb);
    const float rolling = plane ? mat.rolling[a] : std::max(mat.rolling[a], mat.rolling[b]);
    k.ma[l] = ma;
    k.mb[l] = mb;
    put_sym(k.ia, l, ia);
    put_sym(k.ib, l, ib);
    put3(k.n, l, n);
    put3(k.t1, l, t1);
    put3(k.t2, l, t2);
    k.friction[l] = friction;
    k.restitution[l] = std::max(mat.restitution[a], plane ? mat.plane_restitution[c.b[m]] : mat.restitution[b]);
    k.rolling[l] = rolling;
    float f1 = 0.0f, f2 = 0.0f, twist = 0.0f;
    Vec3 roll{0, 0, 0};
    const Vec3 com_a = com[a];
    const Vec3 com_b = plane ? com_a : com[b];
    const SolverBody& A = bodies[a];
    const SolverBody& B = bodies[b];  // the zero body for a plane
    const uint32_t row0 = first_point_of(c, m);
    Vec3 centre_a{0, 0, 0}, centre_b{0, 0, 0};
    bool warmed = false;
    for (uint32_t j = 0; j < count; ++j) {
      const uint32_t row = row0 + j;
      ContactBlockPoint& cp = k.p[j];
      const Vec3 x{c.point[0][row], c.point[1][row], c.point[2][row]};
      const Vec3 ra = x - com_a;
      // A plane never moves (dp_b = 0, dq_b = 1): any anchor gives the same
      // separation change, and r_b = r_a keeps it free of world-coordinate rounding.
      const Vec3 rb = plane ? ra : x - com_b;
      put3(cp.ra, l, ra);
      put3(cp.rb, l, rb);
      const float s0 = -c.point_depth[row];
      cp.base[l] = s0 - dot(rb - ra, n);
      const Vec3 rna = cross(ra, n), rnb = cross(rb, n);
      const float kn = ma + mb + dot(rna, ia * rna) + dot(rnb, ib * rnb);
      cp.normal_mass[l] = kn > 0.0f ? 1.0f / kn : 0.0f;
      const Vec3 vra = A.v + cross(A.w, ra), vrb = B.v + cross(B.w, rb);
      cp.approach[l] = dot(vrb - vra, n);
      if (warm != nullptr && warm[row].normal >= 0.0f) {
        cp.impulse[l] = p.warm_start * warm[row].normal;
        if (!warmed) {
          const WarmPoint& w = warm[row];
          const Vec3 f{w.fx, w.fy, w.fz};
          f1 = p.warm_start * dot(f, t1);
          f2 = p.warm_start * dot(f, t2);
          twist = p.warm_start * w.twist;
          roll = p.warm_start * Vec3{w.rx, w.ry, w.rz};
          warmed = true;
        }
      }
      centre_a = centre_a + ra;
      centre_b = centre_b + rb;
    }
    k.f1[l] = f1;
    k.f2[l] = f2;
    k.twist[l] = twist;
    put3(k.roll, l, roll);
    const float inv_count = 1.0f / static_cast<float>(count);
    const Vec3 ca = inv_count * centre_a;
    const Vec3 cb = inv_count * centre_b;
    put3(k.ca, l, ca);
    put3(k.cb, l, cb);
    for (uint32_t j = 0; j < count; ++j) {
      ContactBlockPoint& cp = k.p[j];
      k.p[j].lever[l] = length(Vec3{cp.ra[0][l], cp.ra[1][l], cp.ra[2][l]} - ca);
    }
    const Vec3 ra1 = cross(ca, t1), ra2 = cross(ca, t2), rb1 = cross(cb, t1), rb2 = cross(cb, t2);
    const float m11 = ma + mb + dot(ra1, ia * ra1) + dot(rb1, ib * rb1);
    const float m22 = ma + mb + dot(ra2, ia * ra2) + dot(rb2, ib * rb2);
    const float m12 = dot(ra1, ia * ra2) + dot(rb1, ib * rb2);
    const float det = m11 * m22 - m12 * m12;
    float k11 = 0.0f, k12 = 0.0f, k22 = 0.0f;
    if (det > 0.0f) {
      const float inv = 1.0f / det;
      k11 = m22 * inv;
      k22 = m11 * inv;
      k12 = -m12 * inv;
    }
    k.k11[l] = k11;
    k.k12[l] = k12;
    k.k22[l] = k22;
    const float kt = dot(n, (ia + ib) * n);
    k.twist_mass[l] = kt > 0.0f ? 1.0f / kt : 0.0f;
    put_sym(k.rolling_mass, l, rolling > 0.0f ? inverse((ia + ib)) : zero);
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

void warm_start_contacts(const ContactBlock* blocks, SolverBody* bodies, Range r) {
  for (uint32_t i = r.begin; i < r.end; ++i) warm_start_lanes<simd::FloatW>(blocks[i], 0, bodies);
}
void solve_contacts(const SoftParams& p, bool use_bias, ContactBlock* blocks, SolverBody* bodies, Range r) {
  for (uint32_t i = r.begin; i < r.end; ++i) solve_lanes<simd::FloatW>(p, use_bias, blocks[i], 0, bodies);
}
void restitute_contacts(const SoftParams& p, ContactBlock* blocks, SolverBody* bodies, Range r) {
  for (uint32_t i = r.begin; i < r.end; ++i) restitute_lanes<simd::FloatW>(p, blocks[i], 0, bodies);
}

void warm_start_contacts_serial(const ContactBlock* blocks, SolverBody* bodies, Range r) {
  for (uint32_t i = r.begin; i < r.end; ++i) warm_start_lanes<simd::Float1>(blocks[i / W], i % W, bodies);
}
void solve_contacts_serial(const SoftParams& p, bool use_bias, ContactBlock* blocks, SolverBody* bodies, Range r) {
  for (uint32_t i = r.begin; i < r.end; ++i) solve_lanes<simd::Float1>(p, use_bias, blocks[i / W], i % W, bodies);
}
void restitute_contacts_serial(const SoftParams& p, ContactBlock* blocks, SolverBody* bodies, Range r) {
  for (uint32_t i = r.begin; i < r.end; ++i) restitute_lanes<simd::Float1>(p, blocks[i / W], i % W, bodies);
}

void store_contacts(const ContactManifoldArrays& c, const uint32_t* order, const ContactBlock* blocks,
                    WarmPoint* IMPACT_RESTRICT out, float* IMPACT_RESTRICT impulse_out, Range r) {
  for (uint32_t i = r.begin; i < r.end; ++i) {
    if (order[i] == kNoConstraint) continue;
    const ContactBlock& k = blocks[i / W];
    const uint32_t l = i % W;
    const uint32_t row0 = first_point_of(c, order[i]);
    const Vec3 t1{k.t1[0][l], k.t1[1][l], k.t1[2][l]}, t2{k.t2[0][l], k.t2[1][l], k.t2[2][l]};
    const Vec3 f = k.f1[l] * t1 + k.f2[l] * t2;
    for (uint32_t j = 0; j < static_cast<uint32_t>(k.count[l]); ++j) {
      const ContactBlockPoint& cp = k.p[j];
      out[row0 + j] = WarmPoint{cp.impulse[l], f.x, f.y, f.z, k.twist[l], k.roll[0][l], k.roll[1][l], k.roll[2][l]};
      impulse_out[row0 + j] = cp.total[l];
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
