#include "kernels/narrowphase/plain/sphere_sphere.h"

#include <cmath>
#include <limits>

namespace impact::kernels {

uint64_t sphere_sphere_count(const Pair* IMPACT_RESTRICT pairs, SphereView s, Range r) {
  uint64_t count = 0;
#pragma omp simd reduction(+ : count)
  for (uint32_t k = r.begin; k < r.end; ++k) {
    const uint32_t a = pairs[k].a, b = pairs[k].b;
    const float dx = s.pos_x[b] - s.pos_x[a];
    const float dy = s.pos_y[b] - s.pos_y[a];
    const float dz = s.pos_z[b] - s.pos_z[a];
    const float rs = s.radius[a] + s.radius[b];
    count += (dx * dx + dy * dy + dz * dz < rs * rs) ? 1u : 0u;
  }
  return count;
}

void sphere_sphere_write(const Pair* IMPACT_RESTRICT pairs, SphereView s, uint32_t pair_base,
                         const ContactManifoldArrays& out, uint64_t offset, Range r) {
  uint64_t c = offset;
  for (uint32_t k = r.begin; k < r.end; ++k) {
    const uint32_t a = pairs[k].a, b = pairs[k].b;
    const float dx = s.pos_x[b] - s.pos_x[a];
    const float dy = s.pos_y[b] - s.pos_y[a];
    const float dz = s.pos_z[b] - s.pos_z[a];
    const float ra = s.radius[a], rb = s.radius[b];
    const float rs = ra + rb;
    const float d2 = dx * dx + dy * dy + dz * dz;
    if (!(d2 < rs * rs)) continue;
    float nx = 0.0f, ny = 1.0f, nz = 0.0f, dist = 0.0f;
    // Below FLT_MIN, d2 is subnormal and sqrt / division lose their precision:
    // treat the centres as coincident rather than return a non-unit normal.
    if (d2 >= std::numeric_limits<float>::min()) {
      dist = std::sqrt(d2);
      const float inv = 1.0f / dist;
      nx = dx * inv;
      ny = dy * inv;
      nz = dz * inv;
    }
    const float depth = rs - dist;
    const float h = 0.5f * (ra - rb);
    out.pair[c] = pair_base + k;
    out.a[c] = a;
    out.b[c] = b;
    out.b_is_plane[c] = 0;
    out.normal[0][c] = nx;
    out.normal[1][c] = ny;
    out.normal[2][c] = nz;
    out.depth[c] = depth;
    out.count[c] = 1;
    // The midpoint from a's centre (a + d / 2, not (a + b) / 2: the world sum rounds at
    // twice the coordinates' magnitude, a whole ulp more far from the origin).
    out.point[0][c] = s.pos_x[a] + (0.5f * dx + nx * h);
    out.point[1][c] = s.pos_y[a] + (0.5f * dy + ny * h);
    out.point[2][c] = s.pos_z[a] + (0.5f * dz + nz * h);
    out.point_depth[c] = depth;
    ++c;
  }
}

}  // namespace impact::kernels
