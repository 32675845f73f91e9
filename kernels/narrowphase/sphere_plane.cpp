#include "kernels/narrowphase/sphere_plane.h"

namespace impact::kernels {
namespace {

IMPACT_INLINE bool pairs_with(BodyFilter f, PlaneView p, uint32_t i, uint32_t k) {
  return f.inv_mass[i] > 0.0f && (f.layer[i] & p.mask[k]) != 0 && (p.layer[k] & f.mask[i]) != 0;
}

IMPACT_INLINE float signed_height(SphereView s, PlaneView p, uint32_t i, uint32_t k) {
  return p.normal_x[k] * s.pos_x[i] + p.normal_y[k] * s.pos_y[i] + p.normal_z[k] * s.pos_z[i] -
         p.offset[k];
}

}  // namespace

uint64_t sphere_plane_count(SphereView s, BodyFilter f, PlaneView planes, Range r) {
  uint64_t count = 0;
  for (uint32_t k = 0; k < planes.count; ++k) {
#pragma omp simd reduction(+ : count)
    for (uint32_t i = r.begin; i < r.end; ++i)
      count += (pairs_with(f, planes, i, k) && signed_height(s, planes, i, k) < s.radius[i]) ? 1u : 0u;
  }
  return count;
}

void sphere_plane_write(SphereView s, BodyFilter f, PlaneView planes, ContactSoA out,
                        uint64_t offset, Range r) {
  uint64_t c = offset;
  for (uint32_t i = r.begin; i < r.end; ++i) {
    for (uint32_t k = 0; k < planes.count; ++k) {
      if (!pairs_with(f, planes, i, k)) continue;
      const float h = signed_height(s, planes, i, k);
      const float rad = s.radius[i];
      if (!(h < rad)) continue;
      const float nx = planes.normal_x[k], ny = planes.normal_y[k], nz = planes.normal_z[k];
      out.a[c] = i;
      out.b[c] = k;
      out.b_is_plane[c] = 1;
      out.normal_x[c] = -nx;
      out.normal_y[c] = -ny;
      out.normal_z[c] = -nz;
      out.depth[c] = rad - h;
      const float m = 0.5f * (rad + h);
      out.point_x[c] = s.pos_x[i] - nx * m;
      out.point_y[c] = s.pos_y[i] - ny * m;
      out.point_z[c] = s.pos_z[i] - nz * m;
      ++c;
    }
  }
}

}  // namespace impact::kernels
