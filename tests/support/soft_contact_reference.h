// The soft step's contact kernels as they were before SIMD across constraints: one
// constraint at a time over AoS ContactConstraint / ContactPoint records, the same
// math as kernels/solver/soft_contact.cpp's lane kernels. The reference of
// tests/kernels/solver/soft_contact_lanes_test.cpp (the lane kernels must match it to
// rounding; in the same operation order, to the bit).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "kernels/solver/soft_contact.h"

namespace impact::test::soft_ref {

using namespace impact::kernels;

/// One manifold point of a constraint.
struct ContactPoint {
  Vec3 ra, rb;       ///< anchors: point - centre of mass, world, at the step's start
  float base;        ///< s0 - dot(rb - ra, n)
  float normal_mass;
  float impulse;     ///< accumulated normal impulse of a substep, N s (warm starts the next)
  float total;       ///< impulse the step applied: the sum over substeps, plus restitution's
  float max_impulse; ///< largest accumulated impulse of the step (restitution's "touched")
  float approach;    ///< relative normal velocity at the step's start (restitution)
  float lever;       ///< |ra - centre_a| (twist friction's arm)
};

/// One manifold's constraint.
struct ContactConstraint {
  uint32_t a, b;            ///< SolverBody indices; b == body_count for a plane
  uint32_t first, count;    ///< its points in the point array
  uint32_t deep;            ///< 1: deeper than max_push_speed * dt, no soft bias (held rigid)
  float ma, mb;             ///< inverse masses
  Sym3 ia, ib;              ///< world inverse inertias
  Vec3 n, t1, t2;           ///< normal (a -> b) and tangents
  Vec3 ca, cb;              ///< friction anchor relative to each centre of mass
  float friction, restitution, rolling;
  float k11, k12, k22;      ///< inverse 2x2 tangent mass
  float twist_mass;
  Sym3 rolling_mass;        ///< (I_a^-1 + I_b^-1)^-1
  float f1, f2, twist;      ///< accumulated friction impulses
  Vec3 roll;                ///< accumulated rolling impulse
};

namespace detail {


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

}  // namespace detail

using namespace detail;

inline void prepare_contacts(const SoftParams& p, const ContactManifoldArrays& c, const uint32_t* order,
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
    const float kt = dot(k.n, (k.ia + k.ib) * k.n);
    k.twist_mass = kt > 0.0f ? 1.0f / kt : 0.0f;
    k.rolling_mass = k.rolling > 0.0f ? inverse((k.ia + k.ib)) : zero;
    out[i] = k;
  }
}

inline void warm_start_contacts(const ContactConstraint* cons, const ContactPoint* points, SolverBody* bodies, Range r) {
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

inline void solve_contacts(const SoftParams& p, bool use_bias, ContactConstraint* cons, ContactPoint* points,
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

inline void restitute_contacts(const SoftParams& p, const ContactConstraint* cons, ContactPoint* points,
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

inline void store_contacts(const ContactManifoldArrays& c, const uint32_t* order, const ContactConstraint* cons,
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

}  // namespace impact::test::soft_ref
