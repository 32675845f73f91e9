#include "kernels/narrowphase/plain/sphere_plane.h"

namespace impact::kernels {
namespace {

// The centre's height over the plane, n.p - offset, in double and rounded once: far from
// the origin n.p and the offset cancel (in float each term rounds by half an ulp of the
// coordinates, 3.9 mm at 1e5 m), while a product of two floats is exact in double and
// the sum's rounding is ~1e-16 of the coordinates.
IMPACT_INLINE float signed_height(SphereView s, PlaneView p, uint32_t i, uint32_t k) {
  const double h = static_cast<double>(p.normal_x[k]) * s.pos_x[i] + static_cast<double>(p.normal_y[k]) * s.pos_y[i] +
                   static_cast<double>(p.normal_z[k]) * s.pos_z[i] - static_cast<double>(p.offset[k]);
  return static_cast<float>(h);
}

}  // namespace

uint64_t sphere_plane_count(const Pair* IMPACT_RESTRICT pairs, SphereView s, PlaneView planes,
                            uint32_t plane_base, Range r) {
  uint64_t count = 0;
#pragma omp simd reduction(+ : count)
  for (uint32_t k = r.begin; k < r.end; ++k) {
    const uint32_t i = pairs[k].a, j = pairs[k].b - plane_base;
    count += signed_height(s, planes, i, j) < s.radius[i] ? 1u : 0u;
  }
  return count;
}

void sphere_plane_write(const Pair* IMPACT_RESTRICT pairs, SphereView s, PlaneView planes, uint32_t plane_base,
                        uint32_t pair_base, const ContactManifoldArrays& out, uint64_t offset, Range r) {
  uint64_t c = offset;
  for (uint32_t k = r.begin; k < r.end; ++k) {
    const uint32_t i = pairs[k].a, j = pairs[k].b - plane_base;
    const float h = signed_height(s, planes, i, j);
    const float rad = s.radius[i];
    if (!(h < rad)) continue;
    const float nx = planes.normal_x[j], ny = planes.normal_y[j], nz = planes.normal_z[j];
    const float m = 0.5f * (rad + h);
    out.pair[c] = pair_base + k;
    out.a[c] = i;
    out.b[c] = j;
    out.b_is_plane[c] = 1;
    out.normal[0][c] = -nx;
    out.normal[1][c] = -ny;
    out.normal[2][c] = -nz;
    out.depth[c] = rad - h;
    out.count[c] = 1;
    out.point[0][c] = s.pos_x[i] - nx * m;
    out.point[1][c] = s.pos_y[i] - ny * m;
    out.point[2][c] = s.pos_z[i] - nz * m;
    out.point_depth[c] = rad - h;
    ++c;
  }
}

}  // namespace impact::kernels
