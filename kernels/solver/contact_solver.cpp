#include "kernels/solver/contact_solver.h"

#include <algorithm>

namespace impact::kernels {
namespace {

// Solver slot of body b: planes map to the immovable zero entry at body_count.
IMPACT_INLINE uint32_t solver_b(SolverContacts c, uint32_t k, uint32_t body_count) {
  return c.b_is_plane[k] ? body_count : c.b[k];
}

// Relative normal velocity (b minus a) along n.
IMPACT_INLINE float normal_velocity(SolverContacts c, const BodyState* s, uint32_t body_count, uint32_t k) {
  const BodyState& A = s[c.a[k]];
  const BodyState& B = s[solver_b(c, k, body_count)];
  return (B.x - A.x) * c.normal_x[k] + (B.y - A.y) * c.normal_y[k] + (B.z - A.z) * c.normal_z[k];
}

IMPACT_INLINE void set_delta(SolverContacts c, BodyContacts adj, uint32_t k, float d) {
  const float x = d * c.normal_x[k], y = d * c.normal_y[k], z = d * c.normal_z[k];
  float* va = adj.delta + 4ull * adj.pos[2ull * k];
  float* vb = adj.delta + 4ull * adj.pos[2ull * k + 1];
  va[0] = -x;
  va[1] = -y;
  va[2] = -z;
  va[3] = 0.0f;
  vb[0] = x;
  vb[1] = y;
  vb[2] = z;
  vb[3] = 0.0f;
}

}  // namespace

void pack_velocity_state(const float* IMPACT_RESTRICT vx, const float* IMPACT_RESTRICT vy,
                         const float* IMPACT_RESTRICT vz, const float* IMPACT_RESTRICT inv_mass,
                         BodyState* IMPACT_RESTRICT out, Range r) {
  for (uint32_t i = r.begin; i < r.end; ++i) out[i] = BodyState{vx[i], vy[i], vz[i], inv_mass[i]};
}

void pack_displacement_state(const float* IMPACT_RESTRICT inv_mass, BodyState* IMPACT_RESTRICT out, Range r) {
  for (uint32_t i = r.begin; i < r.end; ++i) out[i] = BodyState{0.0f, 0.0f, 0.0f, inv_mass[i]};
}

void unpack_velocity_state(const BodyState* IMPACT_RESTRICT s, float* IMPACT_RESTRICT vx,
                           float* IMPACT_RESTRICT vy, float* IMPACT_RESTRICT vz, Range r) {
  for (uint32_t i = r.begin; i < r.end; ++i) {
    vx[i] = s[i].x;
    vy[i] = s[i].y;
    vz[i] = s[i].z;
  }
}

void commit_displacement_state(const BodyState* IMPACT_RESTRICT s, float* IMPACT_RESTRICT px,
                               float* IMPACT_RESTRICT py, float* IMPACT_RESTRICT pz, Range r) {
  for (uint32_t i = r.begin; i < r.end; ++i) {
    px[i] += s[i].x;
    py[i] += s[i].y;
    pz[i] += s[i].z;
  }
}

void contact_body_keys(SolverContacts c, const float* inv_mass, uint32_t body_count,
                       uint64_t* IMPACT_RESTRICT out_keys, Range r) {
  for (uint32_t k = r.begin; k < r.end; ++k) {
    const uint32_t ia = c.a[k];
    const uint64_t ka = inv_mass[ia] > 0.0f ? ia : body_count;
    const uint64_t kb = (!c.b_is_plane[k] && inv_mass[c.b[k]] > 0.0f) ? c.b[k] : body_count;
    out_keys[2ull * k] = (ka << 32) | (2ull * k);
    out_keys[2ull * k + 1] = (kb << 32) | (2ull * k + 1);
  }
}

void contact_entry_positions(const uint64_t* IMPACT_RESTRICT sorted_keys, uint32_t* IMPACT_RESTRICT out_pos,
                             Range r) {
  for (uint32_t e = r.begin; e < r.end; ++e) out_pos[static_cast<uint32_t>(sorted_keys[e])] = e;
}

void contact_prepare(const SolverParams& p, SolverContacts c, const BodyState* s, uint32_t body_count,
                     const float* restitution, const float* plane_restitution, BodyContacts adj, Range r) {
  for (uint32_t k = r.begin; k < r.end; ++k) {
    const uint32_t ia = c.a[k];
    float w = s[ia].inv_mass * static_cast<float>(adj.start[ia + 1] - adj.start[ia]);
    float e = restitution[ia];
    if (c.b_is_plane[k]) {
      e = std::max(e, plane_restitution[c.b[k]]);
    } else {
      const uint32_t ib = c.b[k];
      w += s[ib].inv_mass * static_cast<float>(adj.start[ib + 1] - adj.start[ib]);
      e = std::max(e, restitution[ib]);
    }
    c.mass[k] = w > 0.0f ? 1.0f / w : 0.0f;
    const float vn = normal_velocity(c, s, body_count, k);
    c.target[k] = vn < -p.restitution_threshold ? -e * vn : 0.0f;
    c.impulse[k] = 0.0f;
  }
}

void contact_pair_keys(SolverContacts c, uint64_t* IMPACT_RESTRICT out_keys, Range r) {
  for (uint32_t k = r.begin; k < r.end; ++k)
    out_keys[k] = (static_cast<uint64_t>(c.a[k]) << 32) | c.b[k] | (c.b_is_plane[k] ? 0x80000000ull : 0ull) |
                  (c.point != nullptr ? static_cast<uint64_t>(c.point[k] & 3u) << 29 : 0ull);
}

void contact_warm_start(SolverContacts c, BodyContacts adj, const uint64_t* IMPACT_RESTRICT keys,
                        WarmStart prev, Range r) {
  for (uint32_t k = r.begin; k < r.end; ++k) {
    const uint64_t key = keys[k];
    const uint32_t a = c.a[k];
    float imp = 0.0f;
    if (a < prev.body_count) {
      // Last step's contacts of body a: a handful, scanned linearly.
      for (uint32_t j = prev.start[a]; j < prev.start[a + 1]; ++j) {
        if (prev.keys[j] == key) {
          imp = prev.factor * prev.impulse[j];
          break;
        }
      }
    }
    c.impulse[k] = imp;
    set_delta(c, adj, k, imp);
  }
}

void contact_solve(SolverContacts c, BodyContacts adj, const BodyState* s, uint32_t body_count, Range r) {
  for (uint32_t k = r.begin; k < r.end; ++k) {
    const float vn = normal_velocity(c, s, body_count, k);
    const float old = c.impulse[k];
    const float next = std::max(old + c.mass[k] * (c.target[k] - vn), 0.0f);
    c.impulse[k] = next;
    set_delta(c, adj, k, next - old);
  }
}

void body_apply(BodyContacts adj, BodyState* io, Range r) {
  for (uint32_t i = r.begin; i < r.end; ++i) {
    const uint32_t e0 = adj.start[i], e1 = adj.start[i + 1];
    if (e0 == e1) continue;
    float x = 0.0f, y = 0.0f, z = 0.0f;
    for (uint32_t e = e0; e < e1; ++e) {
      const float* d = adj.delta + 4ull * e;
      x += d[0];
      y += d[1];
      z += d[2];
    }
    const float w = io[i].inv_mass;
    io[i].x += w * x;
    io[i].y += w * y;
    io[i].z += w * z;
  }
}

void contact_position_target(const SolverParams& p, SolverContacts c, const BodyState* s, uint32_t body_count,
                             float dt, Range r) {
  for (uint32_t k = r.begin; k < r.end; ++k) {
    const float depth = c.depth[k] - dt * normal_velocity(c, s, body_count, k);
    c.target[k] = p.position_correction * std::max(depth - p.penetration_slop, 0.0f);
    c.impulse[k] = 0.0f;
  }
}

}  // namespace impact::kernels
