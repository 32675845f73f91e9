#include "kernels/solver/contact_solver.h"

#include <algorithm>

namespace impact::kernels {
namespace {

IMPACT_INLINE uint32_t body_b(SolverContacts c, uint32_t k) {
  return c.b_is_plane[k] ? kInvalidBody : c.b[k];
}

// Relative normal velocity (b minus a) along n; planes do not move.
IMPACT_INLINE float normal_velocity(SolverContacts c, const SolverBodies& b, uint32_t k) {
  const uint32_t ia = c.a[k];
  float rx = -b.vel_x[ia], ry = -b.vel_y[ia], rz = -b.vel_z[ia];
  if (!c.b_is_plane[k]) {
    const uint32_t ib = c.b[k];
    rx += b.vel_x[ib];
    ry += b.vel_y[ib];
    rz += b.vel_z[ib];
  }
  return rx * c.normal_x[k] + ry * c.normal_y[k] + rz * c.normal_z[k];
}

// Sum over a body's contacts of side * delta * n, in CSR order.
IMPACT_INLINE void gather(SolverContacts c, BodyContacts adj, uint32_t body, float* sx, float* sy,
                          float* sz) {
  float x = 0.0f, y = 0.0f, z = 0.0f;
  for (uint32_t e = adj.start[body]; e < adj.start[body + 1]; ++e) {
    const uint32_t entry = static_cast<uint32_t>(adj.sorted_keys[e]);
    const uint32_t k = entry >> 1;
    const float d = (entry & 1u) ? c.delta[k] : -c.delta[k];
    x += d * c.normal_x[k];
    y += d * c.normal_y[k];
    z += d * c.normal_z[k];
  }
  *sx = x;
  *sy = y;
  *sz = z;
}

}  // namespace

void contact_body_keys(SolverContacts c, const float* inv_mass, uint32_t body_count,
                       uint64_t* IMPACT_RESTRICT out_keys, Range r) {
  for (uint32_t k = r.begin; k < r.end; ++k) {
    const uint32_t ia = c.a[k];
    const uint32_t ib = body_b(c, k);
    const uint64_t ka = inv_mass[ia] > 0.0f ? ia : body_count;
    const uint64_t kb = (ib != kInvalidBody && inv_mass[ib] > 0.0f) ? ib : body_count;
    out_keys[2ull * k] = (ka << 32) | (2ull * k);
    out_keys[2ull * k + 1] = (kb << 32) | (2ull * k + 1);
  }
}

void contact_prepare(const SolverParams& p, SolverContacts c, const SolverBodies& b,
                     const float* plane_restitution, BodyContacts adj, Range r) {
  for (uint32_t k = r.begin; k < r.end; ++k) {
    const uint32_t ia = c.a[k];
    const float ka = static_cast<float>(adj.start[ia + 1] - adj.start[ia]);
    float w = b.inv_mass[ia] * ka;
    float e = b.restitution[ia];
    if (c.b_is_plane[k]) {
      e = std::max(e, plane_restitution[c.b[k]]);
    } else {
      const uint32_t ib = c.b[k];
      const float kb = static_cast<float>(adj.start[ib + 1] - adj.start[ib]);
      w += b.inv_mass[ib] * kb;
      e = std::max(e, b.restitution[ib]);
    }
    c.mass[k] = w > 0.0f ? 1.0f / w : 0.0f;
    const float vn = normal_velocity(c, b, k);
    c.target[k] = vn < -p.restitution_threshold ? -e * vn : 0.0f;
    c.impulse[k] = 0.0f;
    c.delta[k] = 0.0f;
  }
}

void contact_solve(SolverContacts c, const SolverBodies& b, Range r) {
  for (uint32_t k = r.begin; k < r.end; ++k) {
    const float vn = normal_velocity(c, b, k);
    const float old = c.impulse[k];
    const float next = std::max(old + c.mass[k] * (c.target[k] - vn), 0.0f);
    c.impulse[k] = next;
    c.delta[k] = next - old;
  }
}

void body_apply_velocity(SolverContacts c, const SolverBodies& b, BodyContacts adj, Range r) {
  for (uint32_t i = r.begin; i < r.end; ++i) {
    if (adj.start[i] == adj.start[i + 1]) continue;
    float sx, sy, sz;
    gather(c, adj, i, &sx, &sy, &sz);
    const float w = b.inv_mass[i];
    b.vel_x[i] += w * sx;
    b.vel_y[i] += w * sy;
    b.vel_z[i] += w * sz;
  }
}

void contact_pair_keys(SolverContacts c, uint64_t* IMPACT_RESTRICT out_keys, Range r) {
  for (uint32_t k = r.begin; k < r.end; ++k)
    out_keys[k] = (static_cast<uint64_t>(c.a[k]) << 32) | c.b[k] |
                  (c.b_is_plane[k] ? 0x80000000ull : 0ull);
}

void contact_warm_start(SolverContacts c, const uint64_t* IMPACT_RESTRICT keys,
                        const uint64_t* IMPACT_RESTRICT prev_keys, const float* IMPACT_RESTRICT prev_impulse,
                        uint32_t prev_count, float factor, Range r) {
  for (uint32_t k = r.begin; k < r.end; ++k) {
    const uint64_t key = keys[k];
    const uint64_t* it = std::lower_bound(prev_keys, prev_keys + prev_count, key);
    const float imp = (it != prev_keys + prev_count && *it == key) ? factor * prev_impulse[it - prev_keys] : 0.0f;
    c.impulse[k] = imp;
    c.delta[k] = imp;
  }
}

void contact_position_target(const SolverParams& p, SolverContacts c, Range r) {
#pragma omp simd
  for (uint32_t k = r.begin; k < r.end; ++k) {
    c.target[k] = p.position_correction * std::max(c.depth[k] - p.penetration_slop, 0.0f);
    c.impulse[k] = 0.0f;
    c.delta[k] = 0.0f;
  }
}

void body_commit_displacement(const float* IMPACT_RESTRICT dx, const float* IMPACT_RESTRICT dy,
                              const float* IMPACT_RESTRICT dz, float* IMPACT_RESTRICT io_px,
                              float* IMPACT_RESTRICT io_py, float* IMPACT_RESTRICT io_pz, Range r) {
#pragma omp simd
  for (uint32_t i = r.begin; i < r.end; ++i) {
    io_px[i] += dx[i];
    io_py[i] += dy[i];
    io_pz[i] += dz[i];
  }
}

}  // namespace impact::kernels
