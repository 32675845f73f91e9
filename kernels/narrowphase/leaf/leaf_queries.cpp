// Ray and point queries against one leaf in its local frame (see leaf_queries.h for the
// contract, methods and citations).
#include "kernels/narrowphase/leaf/leaf_queries.h"

#include <cmath>
#include <cstdint>
#include <limits>

namespace impact::kernels {

namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();

IMPACT_INLINE void set3(float out[3], float x, float y, float z) {
  out[0] = x;
  out[1] = y;
  out[2] = z;
}

// A hit at t; t == 0 on a solid reports -d, else the caller's normal.
IMPACT_INLINE LeafRayHit solid_hit(const RayQuery& q, float t, float nx, float ny, float nz) {
  LeafRayHit h;
  h.t = t;
  if (t == 0.0f) {
    set3(h.n, -q.d[0], -q.d[1], -q.d[2]);
  } else {
    set3(h.n, nx, ny, nz);
  }
  return h;
}

// Normalises (x, y, z) into out; a zero vector gives the fallback.
IMPACT_INLINE void unit_or(float out[3], float x, float y, float z, float fx, float fy, float fz) {
  const float l2 = x * x + y * y + z * z;
  if (l2 > 0.0f && std::isfinite(l2)) {
    const float inv = 1.0f / std::sqrt(l2);
    set3(out, x * inv, y * inv, z * inv);
  } else {
    // Tiny or huge vector: normalise in double (no underflow / overflow), else fallback.
    const double l = std::sqrt(static_cast<double>(x) * x + static_cast<double>(y) * y +
                               static_cast<double>(z) * z);
    if (l > 0.0) {
      set3(out, static_cast<float>(x / l), static_cast<float>(y / l), static_cast<float>(z / l));
    } else {
      set3(out, fx, fy, fz);
    }
  }
}

}  // namespace

// --- rays --------------------------------------------------------------------------------

LeafRayHit ray_leaf_sphere(const RayQuery& q, float radius) {
  const float t = ray_sphere(q, 0.0f, 0.0f, 0.0f, radius);
  if (t < 0.0f) return {};
  LeafRayHit h = solid_hit(q, t, 0, 0, 0);
  if (t > 0.0f) {
    unit_or(h.n, q.o[0] + t * q.d[0], q.o[1] + t * q.d[1], q.o[2] + t * q.d[2], -q.d[0], -q.d[1], -q.d[2]);
  }
  return h;
}

LeafRayHit ray_leaf_capsule(const RayQuery& q, float radius, float half_length) {
  const float a[3] = {0.0f, 0.0f, -half_length};
  const float b[3] = {0.0f, 0.0f, half_length};
  const float t = ray_capsule(q, a, b, radius);
  if (t < 0.0f) return {};
  LeafRayHit h = solid_hit(q, t, 0, 0, 0);
  if (t > 0.0f) {
    const float x[3] = {q.o[0] + t * q.d[0], q.o[1] + t * q.d[1], q.o[2] + t * q.d[2]};
    const float zc = std::fmin(std::fmax(x[2], -half_length), half_length);
    unit_or(h.n, x[0], x[1], x[2] - zc, -q.d[0], -q.d[1], -q.d[2]);
  }
  return h;
}

LeafRayHit ray_leaf_box(const RayQuery& q, const float half[3]) {
  if (std::fabs(q.o[0]) <= half[0] && std::fabs(q.o[1]) <= half[1] && std::fabs(q.o[2]) <= half[2]) {
    return solid_hit(q, 0.0f, 0, 0, 0);
  }
  float tn = -kInf, tf = q.tmax;
  int axis = -1;
  for (int i = 0; i < 3; ++i) {
    if (q.d[i] == 0.0f) {
      if (std::fabs(q.o[i]) > half[i]) return {};
      continue;
    }
    float t0 = (-half[i] - q.o[i]) / q.d[i];
    float t1 = (half[i] - q.o[i]) / q.d[i];
    if (t0 > t1) {
      const float tmp = t0;
      t0 = t1;
      t1 = tmp;
    }
    if (t0 > tn) {
      tn = t0;
      axis = i;
    }
    if (t1 < tf) tf = t1;
  }
  // The origin is outside, so the slab it is outside of sets tn > 0 when the ray heads
  // in (else tf < 0).
  if (axis < 0 || tn > tf || tf < 0.0f) return {};
  const float t = tn < 0.0f ? 0.0f : tn;
  float n[3] = {0.0f, 0.0f, 0.0f};
  n[axis] = q.d[axis] < 0.0f ? 1.0f : -1.0f;
  return solid_hit(q, t, n[0], n[1], n[2]);
}

LeafRayHit ray_leaf_hull(const RayQuery& q, const HullView& h, uint32_t hull) {
  const uint32_t fb = h.face_begin[hull], fe = h.face_begin[hull + 1];
  float tn = -kInf, tf = q.tmax;
  uint32_t entry = 0xffffffffu;
  bool outside = false;
  for (uint32_t f = fb; f < fe; ++f) {
    const float fn[3] = {h.fnx[f], h.fny[f], h.fnz[f]};
    const float dist = dot3(fn, q.o) - h.fd[f];  // > 0: in front of the face
    const float den = dot3(fn, q.d);
    if (dist > 0.0f) outside = true;
    if (den == 0.0f) {
      if (dist > 0.0f) return {};
      continue;
    }
    const float t = -dist / den;
    if (den < 0.0f) {  // entering this face's half-space
      if (t > tn) {
        tn = t;
        entry = f;
      }
    } else if (t < tf) {
      tf = t;
    }
  }
  if (!outside) return solid_hit(q, 0.0f, 0, 0, 0);
  if (entry == 0xffffffffu || tn > tf || tf < 0.0f) return {};
  const float t = tn < 0.0f ? 0.0f : tn;
  return solid_hit(q, t, h.fnx[entry], h.fny[entry], h.fnz[entry]);
}

LeafRayHit ray_leaf_cylinder(const RayQuery& q, float radius, float half_length) {
  const float r = radius, hl = half_length;
  // Interval of the ray inside the infinite cylinder x^2 + y^2 <= r^2 ...
  float t0 = -kInf, t1 = kInf;
  const float rho2 = q.o[0] * q.o[0] + q.o[1] * q.o[1];
  const float A = q.d[0] * q.d[0] + q.d[1] * q.d[1];
  const bool in_r = rho2 <= r * r;
  if (A > 1e-30f) {
    // Closest approach to the axis in the xy plane (the form of ray_sphere, in 2-D).
    const float tca = -(q.o[0] * q.d[0] + q.o[1] * q.d[1]) / A;
    const float mx = q.o[0] + tca * q.d[0], my = q.o[1] + tca * q.d[1];
    const float m2 = mx * mx + my * my;
    if (m2 > r * r) {
      if (!in_r) return {};
      t1 = tca;  // rounding: the origin is on the surface; it leaves at once
    } else {
      const float m = std::sqrt(m2);
      const float thc = std::sqrt((r - m) * (r + m) / A);
      t1 = tca + thc;
      if (!in_r) t0 = tca - thc;
    }
  } else if (!in_r) {
    return {};  // parallel to the axis, outside it
  }
  // ... and inside the slab |z| <= h.
  float s0 = -kInf, s1 = kInf;
  const bool in_z = std::fabs(q.o[2]) <= hl;
  if (q.d[2] == 0.0f) {
    if (!in_z) return {};
  } else {
    const float a = (-hl - q.o[2]) / q.d[2], b = (hl - q.o[2]) / q.d[2];
    s1 = a > b ? a : b;
    if (!in_z) s0 = a > b ? b : a;
  }
  if (in_r && in_z) return solid_hit(q, 0.0f, 0, 0, 0);
  const bool side = t0 >= s0;
  const float tn = side ? t0 : s0;
  const float tf = t1 < s1 ? t1 : s1;
  if (tn > tf || tf < 0.0f || tn > q.tmax) return {};
  const float t = tn < 0.0f ? 0.0f : tn;
  if (side) {
    LeafRayHit hit = solid_hit(q, t, 0, 0, 0);
    if (t > 0.0f) unit_or(hit.n, q.o[0] + t * q.d[0], q.o[1] + t * q.d[1], 0.0f, -q.d[0], -q.d[1], 0.0f);
    return hit;
  }
  return solid_hit(q, t, 0.0f, 0.0f, q.o[2] > 0.0f ? 1.0f : -1.0f);
}

LeafRayHit ray_leaf_ellipsoid(const RayQuery& q, const float radii[3]) {
  // Scale space so that the ellipsoid is the unit ball; the direction's length L
  // converts distances: t = t' / L.
  RayQuery s = q;
  float dd[3];
  for (int i = 0; i < 3; ++i) {
    s.o[i] = q.o[i] / radii[i];
    dd[i] = q.d[i] / radii[i];
  }
  const float L = std::sqrt(dot3(dd, dd));
  for (int i = 0; i < 3; ++i) s.d[i] = dd[i] / L;
  s.tmax = q.tmax * L;
  const float ts = ray_sphere(s, 0.0f, 0.0f, 0.0f, 1.0f);
  if (ts < 0.0f) return {};
  float t = ts / L;
  if (t > q.tmax) t = q.tmax;
  LeafRayHit h = solid_hit(q, t, 0, 0, 0);
  if (t > 0.0f) {
    float x[3];
    for (int i = 0; i < 3; ++i) x[i] = (q.o[i] + t * q.d[i]) / (radii[i] * radii[i]);
    unit_or(h.n, x[0], x[1], x[2], -q.d[0], -q.d[1], -q.d[2]);
  }
  return h;
}

LeafRayHit ray_leaf_half_space(const RayQuery& q, const float n[3], float offset) {
  const float t = ray_plane(q, n, offset);
  if (t < 0.0f) return {};
  return solid_hit(q, t, n[0], n[1], n[2]);
}

// --- points ------------------------------------------------------------------------------

LeafPointResult point_leaf_sphere(const float p[3], float radius) {
  LeafPointResult r;
  unit_or(r.n, p[0], p[1], p[2], 1.0f, 0.0f, 0.0f);
  r.distance = std::sqrt(dot3(p, p)) - radius;
  for (int i = 0; i < 3; ++i) r.closest[i] = r.n[i] * radius;
  return r;
}

LeafPointResult point_leaf_capsule(const float p[3], float radius, float half_length) {
  const float zc = std::fmin(std::fmax(p[2], -half_length), half_length);
  const float v[3] = {p[0], p[1], p[2] - zc};
  LeafPointResult r = point_leaf_sphere(v, radius);
  r.closest[2] += zc;
  return r;
}

LeafPointResult point_leaf_box(const float p[3], const float half[3]) {
  LeafPointResult r;
  const bool outside = std::fabs(p[0]) > half[0] || std::fabs(p[1]) > half[1] || std::fabs(p[2]) > half[2];
  if (outside) {
    float dv[3];
    for (int i = 0; i < 3; ++i) {
      r.closest[i] = std::fmin(std::fmax(p[i], -half[i]), half[i]);
      dv[i] = p[i] - r.closest[i];
    }
    const float l = std::sqrt(dot3(dv, dv));
    r.distance = l;
    unit_or(r.n, dv[0], dv[1], dv[2], 1.0f, 0.0f, 0.0f);
    return r;
  }
  // Inside or on: the nearest face (first axis on ties).
  int k = 0;
  float gap = half[0] - std::fabs(p[0]);
  for (int i = 1; i < 3; ++i) {
    const float g = half[i] - std::fabs(p[i]);
    if (g < gap) {
      gap = g;
      k = i;
    }
  }
  const float sgn = p[k] < 0.0f ? -1.0f : 1.0f;
  r.distance = -gap;
  for (int i = 0; i < 3; ++i) r.closest[i] = p[i];
  r.closest[k] = sgn * half[k];
  r.n[k] = sgn;
  return r;
}

LeafPointResult point_leaf_hull(const float p[3], const HullView& h, uint32_t hull) {
  LeafPointResult r;
  const uint32_t fb = h.face_begin[hull], fe = h.face_begin[hull + 1];
  float dmax = -kInf;
  uint32_t fmax = fb;
  for (uint32_t f = fb; f < fe; ++f) {
    const float d = h.fnx[f] * p[0] + h.fny[f] * p[1] + h.fnz[f] * p[2] - h.fd[f];
    if (d > dmax) {
      dmax = d;
      fmax = f;
    }
  }
  if (dmax <= 0.0f) {
    // Inside or on: the nearest face plane; its projection lies on the hull.
    const float fn[3] = {h.fnx[fmax], h.fny[fmax], h.fnz[fmax]};
    r.distance = dmax;
    for (int i = 0; i < 3; ++i) {
      r.closest[i] = p[i] - dmax * fn[i];
      r.n[i] = fn[i];
    }
    return r;
  }
  // Outside: the closest point lies on a face the point is in front of (its normal
  // cone holds p - closest). Per such face, the projection when it is inside the
  // polygon, else the nearest point of the polygon's edges.
  float best2 = kInf;
  float best[3] = {0, 0, 0};
  bool best_is_face = false;
  uint32_t best_face = fmax;
  for (uint32_t f = fb; f < fe; ++f) {
    const float fn[3] = {h.fnx[f], h.fny[f], h.fnz[f]};
    const float d = dot3(fn, p) - h.fd[f];
    if (!(d > 0.0f)) continue;
    if (d * d >= best2) continue;  // nothing on this face is nearer than its plane
    const float proj[3] = {p[0] - d * fn[0], p[1] - d * fn[1], p[2] - d * fn[2]};
    const uint32_t vb = h.face_vert_begin[f], ve = h.face_vert_begin[f + 1];
    bool inside = true;
    for (uint32_t k = vb; k < ve; ++k) {
      const uint32_t ia = h.face_verts[k], ib = h.face_verts[k + 1 < ve ? k + 1 : vb];
      const float a[3] = {h.vx[ia], h.vy[ia], h.vz[ia]};
      const float e[3] = {h.vx[ib] - a[0], h.vy[ib] - a[1], h.vz[ib] - a[2]};
      const float w[3] = {proj[0] - a[0], proj[1] - a[1], proj[2] - a[2]};
      // (e x w) . fn >= 0 for a point left of the edge (counter-clockwise from outside).
      const float c = (e[1] * w[2] - e[2] * w[1]) * fn[0] + (e[2] * w[0] - e[0] * w[2]) * fn[1] +
                      (e[0] * w[1] - e[1] * w[0]) * fn[2];
      if (c < 0.0f) {
        inside = false;
        break;
      }
    }
    if (inside) {
      best2 = d * d;
      set3(best, proj[0], proj[1], proj[2]);
      best_is_face = true;
      best_face = f;
      continue;
    }
    for (uint32_t k = vb; k < ve; ++k) {
      const uint32_t ia = h.face_verts[k], ib = h.face_verts[k + 1 < ve ? k + 1 : vb];
      const float a[3] = {h.vx[ia], h.vy[ia], h.vz[ia]};
      const float e[3] = {h.vx[ib] - a[0], h.vy[ib] - a[1], h.vz[ib] - a[2]};
      const float w[3] = {p[0] - a[0], p[1] - a[1], p[2] - a[2]};
      const float ee = dot3(e, e);
      float s = ee > 0.0f ? dot3(w, e) / ee : 0.0f;
      s = s < 0.0f ? 0.0f : (s > 1.0f ? 1.0f : s);
      const float c[3] = {a[0] + s * e[0], a[1] + s * e[1], a[2] + s * e[2]};
      const float dv[3] = {p[0] - c[0], p[1] - c[1], p[2] - c[2]};
      const float l2 = dot3(dv, dv);
      if (l2 < best2) {
        best2 = l2;
        set3(best, c[0], c[1], c[2]);
        best_is_face = false;
        best_face = f;
      }
    }
  }
  set3(r.closest, best[0], best[1], best[2]);
  if (best_is_face) {
    r.distance = std::sqrt(best2);
    set3(r.n, h.fnx[best_face], h.fny[best_face], h.fnz[best_face]);
  } else {
    const float dv[3] = {p[0] - best[0], p[1] - best[1], p[2] - best[2]};
    r.distance = std::sqrt(dot3(dv, dv));
    unit_or(r.n, dv[0], dv[1], dv[2], h.fnx[best_face], h.fny[best_face], h.fnz[best_face]);
  }
  return r;
}

LeafPointResult point_leaf_cylinder(const float p[3], float radius, float half_length) {
  LeafPointResult r;
  const float rho = std::sqrt(p[0] * p[0] + p[1] * p[1]);
  // Radial unit direction (fallback +x on the axis).
  float ux = 1.0f, uy = 0.0f;
  if (rho > 0.0f) {
    ux = p[0] / rho;
    uy = p[1] / rho;
  } else if (p[0] != 0.0f || p[1] != 0.0f) {
    float u[3];
    unit_or(u, p[0], p[1], 0.0f, 1.0f, 0.0f, 0.0f);
    ux = u[0];
    uy = u[1];
  }
  const float az = std::fabs(p[2]);
  const float zs = p[2] < 0.0f ? -1.0f : 1.0f;
  const float dr = rho - radius, dz = az - half_length;
  if (dr <= 0.0f && dz <= 0.0f) {
    // Inside or on: the nearer of side and cap (side on ties).
    if (-dr <= -dz) {
      r.distance = dr;
      set3(r.closest, ux * radius, uy * radius, p[2]);
      set3(r.n, ux, uy, 0.0f);
    } else {
      r.distance = dz;
      set3(r.closest, p[0], p[1], zs * half_length);
      set3(r.n, 0.0f, 0.0f, zs);
    }
    return r;
  }
  if (dz <= 0.0f) {  // beside the side
    r.distance = dr;
    set3(r.closest, ux * radius, uy * radius, p[2]);
    set3(r.n, ux, uy, 0.0f);
  } else if (dr <= 0.0f) {  // above / below a cap
    r.distance = dz;
    set3(r.closest, p[0], p[1], zs * half_length);
    set3(r.n, 0.0f, 0.0f, zs);
  } else {  // nearest the rim
    r.distance = std::sqrt(dr * dr + dz * dz);
    set3(r.closest, ux * radius, uy * radius, zs * half_length);
    unit_or(r.n, dr * ux, dr * uy, dz * zs, ux, uy, 0.0f);
  }
  return r;
}

namespace {

// Root sigma > 0 of G(sigma) = sum_i (w_i / (sigma + d_i))^2 - 1 (w_i > 0, d_i >= 0, the
// last d = 0): G decreases, and the root lies in [lo, hi]. Bisection, geometric while
// the bracket spans more than a factor 4 (a point near the plane of the shortest axis
// puts the root near 0, many binades below 1), arithmetic after.
double ellipse_root(int n, const double* w, const double* d, double lo, double hi) {
  double s = lo;
  for (int it = 0; it < 400; ++it) {
    s = (lo > 0.0 && hi > 4.0 * lo) ? std::sqrt(lo) * std::sqrt(hi) : 0.5 * (lo + hi);
    if (!(s > lo && s < hi)) break;
    double g = -1.0;
    for (int i = 0; i < n; ++i) {
      const double q = w[i] / (s + d[i]);
      g += q * q;
    }
    if (g > 0.0) {
      lo = s;
    } else if (g < 0.0) {
      hi = s;
    } else {
      break;
    }
  }
  return s;
}

// Closest point x on the ellipsoid / ellipse with semi-axes a[0] >= ... >= a[n-1] > 0 to
// y (all y_i >= 0), n = 1..3. x_i >= 0.
void closest_on_ellipsoid_octant(int n, const double* a, const double* y, double* x) {
  if (n == 1) {
    x[0] = a[0];
    return;
  }
  const int last = n - 1;
  if (y[last] > 0.0) {
    // Coordinates with y_i = 0 (i < last) have x_i = 0: drop them.
    int idx[3], m = 0;
    for (int i = 0; i < n; ++i) {
      if (i == last || y[i] > 0.0) idx[m++] = i;
      else x[i] = 0.0;
    }
    if (m < n) {
      double as[3] = {}, ys[3] = {}, xs[3] = {};
      for (int k = 0; k < m; ++k) {
        as[k] = a[idx[k]];
        ys[k] = y[idx[k]];
      }
      closest_on_ellipsoid_octant(m, as, ys, xs);
      for (int k = 0; k < m; ++k) x[idx[k]] = xs[k];
      return;
    }
    // All y_i > 0: x_i = r_i y_i / (sigma + d_i) with r_i = (a_i / a_last)^2,
    // d_i = r_i - 1 and sigma = 1 + lambda / a_last^2 the root of the secular equation
    // (sigma, not lambda, keeps its relative precision when it tends to 0).
    double z[3] = {}, rr[3] = {}, dd[3] = {}, w[3] = {};
    double g = -1.0;
    for (int i = 0; i < n; ++i) {
      z[i] = y[i] / a[i];
      g += z[i] * z[i];
      const double ra = a[i] / a[last];
      rr[i] = ra * ra;
      dd[i] = (a[i] - a[last]) * (a[i] + a[last]) / (a[last] * a[last]);
      w[i] = rr[i] * z[i];
    }
    if (g == 0.0) {
      for (int i = 0; i < n; ++i) x[i] = y[i];
      return;
    }
    double lo = z[last], hi = 1.0;
    if (g > 0.0) {
      double wn = 0.0;
      for (int i = 0; i < n; ++i) wn += w[i] * w[i];
      lo = 1.0;
      hi = std::fmax(1.0, std::sqrt(wn));
    }
    const double s = ellipse_root(n, w, dd, lo, hi);
    for (int i = 0; i < n; ++i) x[i] = rr[i] * y[i] / (s + dd[i]);
    return;
  }
  // y_last = 0. An inside point close enough to the plane x_last = 0 has its nearest
  // point off that plane: x_i = a_i^2 y_i / (a_i^2 - a_last^2), x_last from the surface
  // equation, when that is real.
  bool off_plane = true;
  double sum = 0.0, xo[3];
  const double al2 = a[last] * a[last];
  for (int i = 0; i < last; ++i) {
    const double den = a[i] * a[i] - al2;
    const double num = a[i] * y[i];
    if (!(num < den)) {
      off_plane = false;
      break;
    }
    const double xde = num / den;
    xo[i] = a[i] * xde;
    sum += xde * xde;
  }
  if (off_plane && sum < 1.0) {
    for (int i = 0; i < last; ++i) x[i] = xo[i];
    x[last] = a[last] * std::sqrt(1.0 - sum);
    return;
  }
  x[last] = 0.0;
  closest_on_ellipsoid_octant(last, a, y, x);
}

}  // namespace

LeafPointResult point_leaf_ellipsoid(const float p[3], const float radii[3]) {
  // Sort the axes by decreasing radius (stable: index order on ties).
  int perm[3] = {0, 1, 2};
  for (int i = 1; i < 3; ++i) {
    for (int j = i; j > 0 && radii[perm[j]] > radii[perm[j - 1]]; --j) {
      const int tmp = perm[j];
      perm[j] = perm[j - 1];
      perm[j - 1] = tmp;
    }
  }
  double a[3] = {}, y[3] = {}, xs[3] = {};
  for (int k = 0; k < 3; ++k) {
    a[k] = radii[perm[k]];
    y[k] = std::fabs(static_cast<double>(p[perm[k]]));
  }
  closest_on_ellipsoid_octant(3, a, y, xs);
  double x[3], dv[3], g[3];
  double level = 0.0;
  for (int k = 0; k < 3; ++k) {
    const int i = perm[k];
    const double sgn = p[i] < 0.0f ? -1.0 : 1.0;
    x[i] = sgn * xs[k];
    dv[i] = static_cast<double>(p[i]) - x[i];
    const double e = radii[i];
    g[i] = x[i] / (e * e);
    const double u = static_cast<double>(p[i]) / e;
    level += u * u;
  }
  const double dist = std::sqrt(dv[0] * dv[0] + dv[1] * dv[1] + dv[2] * dv[2]);
  const double gl = std::sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]);
  LeafPointResult r;
  r.distance = static_cast<float>(level < 1.0 ? -dist : dist);
  for (int i = 0; i < 3; ++i) {
    r.closest[i] = static_cast<float>(x[i]);
    r.n[i] = static_cast<float>(g[i] / gl);
  }
  return r;
}

LeafPointResult point_leaf_half_space(const float p[3], const float n[3], float offset) {
  LeafPointResult r;
  const float s = dot3(n, p) - offset;
  r.distance = s;
  for (int i = 0; i < 3; ++i) {
    r.closest[i] = p[i] - s * n[i];
    r.n[i] = n[i];
  }
  return r;
}

}  // namespace impact::kernels
