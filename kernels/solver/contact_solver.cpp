#include "kernels/solver/contact_solver.h"

#include <algorithm>

namespace impact::kernels {
namespace {

// Solver slot of manifold m's body b: planes map to the immovable zero entry at body_count.
IMPACT_INLINE uint32_t solver_b(const ContactManifoldArrays& c, uint32_t m, uint32_t body_count) {
  return c.b_is_plane[m] ? body_count : c.b[m];
}

// Relative normal velocity (b minus a) along manifold m's normal.
IMPACT_INLINE float normal_velocity(const ContactManifoldArrays& c, const BodyState* s, uint32_t body_count,
                                    uint32_t m) {
  const BodyState& A = s[c.a[m]];
  const BodyState& B = s[solver_b(c, m, body_count)];
  return (B.x - A.x) * c.normal[0][m] + (B.y - A.y) * c.normal[1][m] + (B.z - A.z) * c.normal[2][m];
}

// fn(m, p) for every point p of every manifold m in r, in order.
template <class Fn>
IMPACT_INLINE void for_each_point(const ContactManifoldArrays& c, Range r, Fn&& fn) {
  if (c.first_point == nullptr) {
    for (uint32_t m = r.begin; m < r.end; ++m) fn(m, m);
  } else {
    for (uint32_t m = r.begin; m < r.end; ++m) {
      const uint32_t p0 = c.first_point[m], p1 = p0 + c.count[m];
      for (uint32_t p = p0; p < p1; ++p) fn(m, p);
    }
  }
}

IMPACT_INLINE void set_delta(const ContactManifoldArrays& c, BodyContacts adj, uint32_t m, uint32_t p, float d) {
  const float x = d * c.normal[0][m], y = d * c.normal[1][m], z = d * c.normal[2][m];
  float* va = adj.delta + 4ull * adj.pos[2ull * p];
  float* vb = adj.delta + 4ull * adj.pos[2ull * p + 1];
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

void contact_body_keys(const ContactManifoldArrays& c, const float* inv_mass, uint32_t body_count,
                       uint64_t* IMPACT_RESTRICT out_keys, Range r) {
  for_each_point(c, r, [&](uint32_t m, uint32_t p) IMPACT_LAMBDA_INLINE {
    const uint32_t ia = c.a[m];
    const uint64_t ka = inv_mass[ia] > 0.0f ? ia : body_count;
    const uint64_t kb = (!c.b_is_plane[m] && inv_mass[c.b[m]] > 0.0f) ? c.b[m] : body_count;
    out_keys[2ull * p] = (ka << 32) | (2ull * p);
    out_keys[2ull * p + 1] = (kb << 32) | (2ull * p + 1);
  });
}

void contact_entry_positions(const uint64_t* IMPACT_RESTRICT sorted_keys, uint32_t* IMPACT_RESTRICT out_pos,
                             Range r) {
  for (uint32_t e = r.begin; e < r.end; ++e) out_pos[static_cast<uint32_t>(sorted_keys[e])] = e;
}

void contact_prepare(const SolverParams& p, const ContactManifoldArrays& c, SolverRows rows, const BodyState* s,
                     uint32_t body_count, const float* restitution, const float* plane_restitution,
                     BodyContacts adj, Range r) {
  for_each_point(c, r, [&](uint32_t m, uint32_t k) IMPACT_LAMBDA_INLINE {
    const uint32_t ia = c.a[m];
    float w = s[ia].inv_mass * static_cast<float>(adj.start[ia + 1] - adj.start[ia]);
    float e = restitution[ia];
    if (c.b_is_plane[m]) {
      e = std::max(e, plane_restitution[c.b[m]]);
    } else {
      const uint32_t ib = c.b[m];
      w += s[ib].inv_mass * static_cast<float>(adj.start[ib + 1] - adj.start[ib]);
      e = std::max(e, restitution[ib]);
    }
    rows.mass[k] = w > 0.0f ? 1.0f / w : 0.0f;
    const float vn = normal_velocity(c, s, body_count, m);
    const float gap = -c.point_depth[k];
    rows.target[k] = (gap > 0.0f && p.dt > 0.0f) ? -gap / p.dt : (vn < -p.restitution_threshold ? -e * vn : 0.0f);
    rows.impulse[k] = 0.0f;
  });
}

void contact_pair_keys(const ContactManifoldArrays& c, uint64_t* IMPACT_RESTRICT out_keys, Range r) {
  for_each_point(c, r, [&](uint32_t m, uint32_t p) IMPACT_LAMBDA_INLINE {
    out_keys[p] = (static_cast<uint64_t>(c.a[m]) << 32) | c.b[m] | (c.b_is_plane[m] ? 0x80000000ull : 0ull) |
                  (static_cast<uint64_t>(feature_of(c, m, p) & 3u) << 29);
  });
}

void contact_warm_start(const ContactManifoldArrays& c, SolverRows rows, BodyContacts adj,
                        const uint64_t* IMPACT_RESTRICT keys, WarmStart prev, Range r) {
  for_each_point(c, r, [&](uint32_t m, uint32_t k) IMPACT_LAMBDA_INLINE {
    const uint64_t key = keys[k];
    const uint32_t a = c.a[m];
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
    rows.impulse[k] = imp;
    set_delta(c, adj, m, k, imp);
  });
}

void contact_solve(const ContactManifoldArrays& c, SolverRows rows, BodyContacts adj, const BodyState* s,
                   uint32_t body_count, Range r) {
  for_each_point(c, r, [&](uint32_t m, uint32_t k) IMPACT_LAMBDA_INLINE {
    const float vn = normal_velocity(c, s, body_count, m);
    const float old = rows.impulse[k];
    const float next = std::max(old + rows.mass[k] * (rows.target[k] - vn), 0.0f);
    rows.impulse[k] = next;
    set_delta(c, adj, m, k, next - old);
  });
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

void contact_position_target(const SolverParams& p, const ContactManifoldArrays& c, SolverRows rows,
                             const BodyState* s, uint32_t body_count, float dt, Range r) {
  for_each_point(c, r, [&](uint32_t m, uint32_t k) IMPACT_LAMBDA_INLINE {
    const float depth = c.point_depth[k] - dt * normal_velocity(c, s, body_count, m);
    rows.target[k] = p.position_correction * std::max(depth - p.penetration_slop, 0.0f);
    rows.impulse[k] = 0.0f;
  });
}

}  // namespace impact::kernels
