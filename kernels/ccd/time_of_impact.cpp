// Time of impact of two moving convex leaves: closed forms and conservative advancement
// (contract, cost and citations: time_of_impact.h).
#include "kernels/ccd/time_of_impact.h"

#include <cmath>

#include "kernels/narrowphase/general/gjk_epa.h"

namespace impact::kernels::ccd {
namespace {

using cvx::Leaf;
using cvx::V3;

// x rotated by the rotation vector th (Rodrigues' formula; first order below 1e-9 rad).
V3 rotate(V3 x, V3 th) {
  const double ang = std::sqrt(double(th.x) * th.x + double(th.y) * th.y + double(th.z) * th.z);
  if (ang < 1e-9) return x + cvx::cross(th, x);
  const double kx = th.x / ang, ky = th.y / ang, kz = th.z / ang;
  const double c = std::cos(ang), s = std::sin(ang);
  const double kd = kx * x.x + ky * x.y + kz * x.z;
  const double cx = ky * x.z - kz * x.y, cy = kz * x.x - kx * x.z, cz = kx * x.y - ky * x.x;
  return V3{float(x.x * c + cx * s + kx * kd * (1.0 - c)), float(x.y * c + cy * s + ky * kd * (1.0 - c)),
            float(x.z * c + cz * s + kz * kd * (1.0 - c))};
}

V3 half_space_normal(const Leaf& l) { return V3{l.e[0], l.e[1], l.e[2]}; }

V3 unit_or(V3 v, V3 fallback) {
  const float l2 = cvx::len2(v);
  return l2 > 0.0f ? v * (1.0f / std::sqrt(l2)) : fallback;
}

// Closed form: sphere a against sphere b (both translating; a sphere's rotation about
// its centre does not move its surface). Relative motion u of b as seen from a.
ToiResult sphere_sphere(const Leaf& a, const Motion& ma, const Leaf& b, const Motion& mb, float target,
                        float tolerance) {
  ToiResult r;
  const double dx = double(b.p.x) - a.p.x, dy = double(b.p.y) - a.p.y, dz = double(b.p.z) - a.p.z;
  const double ux = double(mb.v.x) - ma.v.x, uy = double(mb.v.y) - ma.v.y, uz = double(mb.v.z) - ma.v.z;
  const double rr = double(a.e[0]) + b.e[0];
  const double reach = rr + target;
  const double dist0 = std::sqrt(dx * dx + dy * dy + dz * dz);
  auto finish = [&](double t) {
    const double px = dx + ux * t, py = dy + uy * t, pz = dz + uz * t;
    const double l = std::sqrt(px * px + py * py + pz * pz);
    r.normal = l > 0.0 ? V3{float(px / l), float(py / l), float(pz / l)} : V3{0, 1, 0};
    // Midway between the surfaces, on the centre line.
    const double s = (double(a.e[0]) + (l - rr) * 0.5);
    r.point = V3{float(a.p.x + ma.v.x * t + r.normal.x * s), float(a.p.y + ma.v.y * t + r.normal.y * s),
                 float(a.p.z + ma.v.z * t + r.normal.z * s)};
    r.t = float(t);
  };
  const double sep0 = dist0 - rr;
  if (sep0 <= 0.0 || sep0 < double(target) - tolerance) {
    r.state = ToiResult::kOverlapAtStart;
    finish(0.0);
    r.t = 0.0f;
    return r;
  }
  if (sep0 <= double(target) + tolerance) {
    r.state = ToiResult::kHit;
    finish(0.0);
    return r;
  }
  const double qa = ux * ux + uy * uy + uz * uz;
  const double qb = dx * ux + dy * uy + dz * uz;  // b' = d.u
  const double qc = (dist0 - reach) * (dist0 + reach);  // |d|^2 - r^2 without cancellation
  const double disc = qb * qb - qa * qc;
  if (qb >= 0.0 || disc < 0.0) return r;  // receding or passing by
  const double t = qc / (-qb + std::sqrt(disc));
  if (!(t <= 1.0)) return r;
  r.state = ToiResult::kHit;
  finish(t);
  return r;
}

// Closed form: translating sphere s against a translating half-space h (no rotation).
ToiResult sphere_half_space(const Leaf& s, const Motion& ms, const Leaf& h, const Motion& mh, bool sphere_is_a,
                            float target, float tolerance) {
  ToiResult r;
  const V3 n = half_space_normal(h);
  const double s0 = double(cvx::dot(n, s.p - h.p)) - s.e[0];
  const double un = double(cvx::dot(n, ms.v - mh.v));
  double t = 0.0;
  if (s0 <= 0.0 || s0 < double(target) - tolerance) {
    r.state = ToiResult::kOverlapAtStart;
  } else if (s0 <= double(target) + tolerance) {
    r.state = ToiResult::kHit;
  } else {
    if (!(un < 0.0)) return r;
    t = (s0 - target) / -un;
    if (!(t <= 1.0)) return r;
    r.state = ToiResult::kHit;
  }
  r.t = float(t);
  r.normal = sphere_is_a ? -n : n;
  const double sep = s0 + un * t;
  const V3 c = s.p + ms.v * float(t);
  r.point = c - n * float(double(s.e[0]) + sep * 0.5);
  return r;
}

}  // namespace

Leaf leaf_at(const Leaf& l, const Motion& m, float t) {
  Leaf o = l;
  const V3 th = m.w * t;
  const V3 dv = m.v * t;
  if (l.type == kLeafTriangle) {
    const V3 c = cvx::leaf_center(l);
    o.p = c + dv + rotate(l.p - c, th);
    o.v1 = c + dv + rotate(l.v1 - c, th);
    o.v2 = c + dv + rotate(l.v2 - c, th);
    return o;
  }
  o.p = l.p + dv;
  if (l.type == kLeafHalfSpace) {
    const V3 n = rotate(half_space_normal(l), th);
    o.e[0] = n.x;
    o.e[1] = n.y;
    o.e[2] = n.z;
    return o;
  }
  if (l.type != kLeafSphere)
    for (int c = 0; c < 3; ++c) o.ax[c] = rotate(l.ax[c], th);
  return o;
}

float leaf_reach(const Leaf& l) {
  switch (l.type) {
    case kLeafSphere: return l.e[0];
    case kLeafCapsule: return l.e[0] + l.e[1];
    case kLeafBox: return std::sqrt(l.e[0] * l.e[0] + l.e[1] * l.e[1] + l.e[2] * l.e[2]);
    case kLeafCylinder: return std::sqrt(l.e[0] * l.e[0] + l.e[1] * l.e[1]);
    case kLeafHalfSpace: return 0.0f;
    default: return cvx::leaf_size(l);  // ellipsoid: max radius; triangle: exact; hull: L1 bound
  }
}

float leaf_separation(const Leaf& a, const Leaf& b, const NarrowConfig& cfg, V3* normal, V3* point) {
  if (a.type == kLeafHalfSpace || b.type == kLeafHalfSpace) {
    const bool a_plane = a.type == kLeafHalfSpace;
    const Leaf& h = a_plane ? a : b;
    const Leaf& o = a_plane ? b : a;
    const V3 n = half_space_normal(h);
    const V3 q = cvx::support(o, -n);
    const float d = cvx::dot(n, q - h.p);
    *normal = a_plane ? n : -n;
    *point = q - n * (0.5f * d);
    return d;
  }
  const float ra = cvx::core_radius(a), rb = cvx::core_radius(b);
  const float scale = cvx::leaf_size(a) + cvx::leaf_size(b);
  const cvx::GjkResult g = cvx::gjk_cores(a, b, INFINITY, scale, cfg.gjk_max_iterations, cfg.gjk_tolerance);
  if (!g.overlap) {
    *normal = g.n;
    const V3 sa = g.pa + g.n * ra, sb = g.pb - g.n * rb;
    *point = (sa + sb) * 0.5f;
    return g.distance - ra - rb;
  }
  // Cores overlap: the penetration direction from EPA (only reached at t = 0).
  const cvx::EpaResult e = cvx::epa_cores(a, b, g.simplex, scale, cfg.epa_max_iterations, cfg.epa_tolerance);
  *normal = unit_or(e.n, V3{0, 1, 0});
  *point = (e.pa + e.pb) * 0.5f;
  return -(e.depth > 0.0f ? e.depth : 0.0f) - ra - rb;
}

ToiResult time_of_impact(const Leaf& a, const Motion& ma, const Leaf& b, const Motion& mb, float target,
                         float tolerance, uint32_t max_iterations, const NarrowConfig& cfg) {
  ToiResult r;
  if (a.type == kLeafHalfSpace && b.type == kLeafHalfSpace) {
    r.state = ToiResult::kFailed;
    r.t = 0.0f;
    return r;
  }
  const bool still_a = ma.w.x == 0.0f && ma.w.y == 0.0f && ma.w.z == 0.0f;
  const bool still_b = mb.w.x == 0.0f && mb.w.y == 0.0f && mb.w.z == 0.0f;
  if (a.type == kLeafSphere && b.type == kLeafSphere) return sphere_sphere(a, ma, b, mb, target, tolerance);
  if (a.type == kLeafSphere && b.type == kLeafHalfSpace && still_b)
    return sphere_half_space(a, ma, b, mb, true, target, tolerance);
  if (b.type == kLeafSphere && a.type == kLeafHalfSpace && still_a)
    return sphere_half_space(b, mb, a, ma, false, target, tolerance);

  // Conservative advancement: every step moves t by a fraction that cannot close the
  // gap below target under the bound mu on the approach speed.
  const float wa = cvx::len(ma.w) * leaf_reach(a);
  const float wb = cvx::len(mb.w) * leaf_reach(b);
  const V3 vrel = mb.v - ma.v;
  float t = 0.0f;
  bool exhausted = true;
  for (uint32_t it = 0; it < max_iterations; ++it) {
    const Leaf la = leaf_at(a, ma, t), lb = leaf_at(b, mb, t);
    V3 n, p;
    const float d = leaf_separation(la, lb, cfg, &n, &p);
    r.iterations = it + 1;
    r.normal = n;
    r.point = p;
    r.t = t;
    if (it == 0 && (d <= 0.0f || d < target - tolerance)) {
      r.state = ToiResult::kOverlapAtStart;
      return r;
    }
    if (d <= target + tolerance) {
      r.state = ToiResult::kHit;
      return r;
    }
    const float mu = std::fabs(cvx::dot(vrel, n)) + wa + wb;
    const float dt = (d - target) / mu;
    if (!(mu > 0.0f) || !(t + dt <= 1.0f)) {
      exhausted = false;
      break;
    }
    t += dt;
  }
  if (exhausted) {
    r.state = ToiResult::kFailed;
    return r;
  }
  r.state = ToiResult::kSeparated;
  r.t = 1.0f;
  return r;
}

}  // namespace impact::kernels::ccd
