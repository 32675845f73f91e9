#include "kernels/broadphase/bounds.h"

#include <algorithm>
#include <limits>

namespace impact::kernels {

BoundsSummary empty_bounds_summary() {
  constexpr float inf = std::numeric_limits<float>::infinity();
  return BoundsSummary{{inf, inf, inf}, {-inf, -inf, -inf}, 0.0f, inf};
}

BoundsSummary combine(const BoundsSummary& a, const BoundsSummary& b) {
  BoundsSummary s;
  for (int k = 0; k < 3; ++k) {
    s.lo[k] = std::min(a.lo[k], b.lo[k]);
    s.hi[k] = std::max(a.hi[k], b.hi[k]);
  }
  s.max_edge = std::max(a.max_edge, b.max_edge);
  s.min_edge = std::min(a.min_edge, b.min_edge);
  return s;
}

void sphere_bounds(const float* IMPACT_RESTRICT px, const float* IMPACT_RESTRICT py,
                   const float* IMPACT_RESTRICT pz, const float* IMPACT_RESTRICT radius,
                   AabbSoAOut out, Range r) {
  float* IMPACT_RESTRICT min_x = out.min_x;
  float* IMPACT_RESTRICT min_y = out.min_y;
  float* IMPACT_RESTRICT min_z = out.min_z;
  float* IMPACT_RESTRICT max_x = out.max_x;
  float* IMPACT_RESTRICT max_y = out.max_y;
  float* IMPACT_RESTRICT max_z = out.max_z;
#pragma omp simd
  for (uint32_t i = r.begin; i < r.end; ++i) {
    const float rad = radius[i];
    min_x[i] = px[i] - rad;
    min_y[i] = py[i] - rad;
    min_z[i] = pz[i] - rad;
    max_x[i] = px[i] + rad;
    max_y[i] = py[i] + rad;
    max_z[i] = pz[i] + rad;
  }
}

void swept_sphere_bounds(const float* IMPACT_RESTRICT px, const float* IMPACT_RESTRICT py,
                         const float* IMPACT_RESTRICT pz, const float* IMPACT_RESTRICT vx,
                         const float* IMPACT_RESTRICT vy, const float* IMPACT_RESTRICT vz,
                         const float* IMPACT_RESTRICT radius, float dt, AabbSoAOut out, Range r) {
  float* IMPACT_RESTRICT min_x = out.min_x;
  float* IMPACT_RESTRICT min_y = out.min_y;
  float* IMPACT_RESTRICT min_z = out.min_z;
  float* IMPACT_RESTRICT max_x = out.max_x;
  float* IMPACT_RESTRICT max_y = out.max_y;
  float* IMPACT_RESTRICT max_z = out.max_z;
#pragma omp simd
  for (uint32_t i = r.begin; i < r.end; ++i) {
    const float rad = radius[i];
    // The end pose as integrate_positions computes it (p + v dt).
    const float ex = px[i] + vx[i] * dt;
    const float ey = py[i] + vy[i] * dt;
    const float ez = pz[i] + vz[i] * dt;
    min_x[i] = std::min(px[i] - rad, ex - rad);
    min_y[i] = std::min(py[i] - rad, ey - rad);
    min_z[i] = std::min(pz[i] - rad, ez - rad);
    max_x[i] = std::max(px[i] + rad, ex + rad);
    max_y[i] = std::max(py[i] + rad, ey + rad);
    max_z[i] = std::max(pz[i] + rad, ez + rad);
  }
}

void sweep_boxes(AabbSoA boxes, const float* IMPACT_RESTRICT dx, const float* IMPACT_RESTRICT dy,
                 const float* IMPACT_RESTRICT dz, AabbSoAOut out, Range r) {
  float* IMPACT_RESTRICT min_x = out.min_x;
  float* IMPACT_RESTRICT min_y = out.min_y;
  float* IMPACT_RESTRICT min_z = out.min_z;
  float* IMPACT_RESTRICT max_x = out.max_x;
  float* IMPACT_RESTRICT max_y = out.max_y;
  float* IMPACT_RESTRICT max_z = out.max_z;
  const float* IMPACT_RESTRICT in_min_x = boxes.min_x;
  const float* IMPACT_RESTRICT in_min_y = boxes.min_y;
  const float* IMPACT_RESTRICT in_min_z = boxes.min_z;
  const float* IMPACT_RESTRICT in_max_x = boxes.max_x;
  const float* IMPACT_RESTRICT in_max_y = boxes.max_y;
  const float* IMPACT_RESTRICT in_max_z = boxes.max_z;
#pragma omp simd
  for (uint32_t i = r.begin; i < r.end; ++i) {
    const float x0 = in_min_x[i], y0 = in_min_y[i], z0 = in_min_z[i];
    const float x1 = in_max_x[i], y1 = in_max_y[i], z1 = in_max_z[i];
    min_x[i] = std::min(x0, x0 + dx[i]);
    min_y[i] = std::min(y0, y0 + dy[i]);
    min_z[i] = std::min(z0, z0 + dz[i]);
    max_x[i] = std::max(x1, x1 + dx[i]);
    max_y[i] = std::max(y1, y1 + dy[i]);
    max_z[i] = std::max(z1, z1 + dz[i]);
  }
}

BoundsSummary reduce_bounds(AabbSoA b, Range r) {
  constexpr float inf = std::numeric_limits<float>::infinity();
  float lx = inf, ly = inf, lz = inf, hx = -inf, hy = -inf, hz = -inf, edge = 0.0f, small = inf;
#pragma omp simd reduction(min : lx, ly, lz, small) reduction(max : hx, hy, hz, edge)
  for (uint32_t i = r.begin; i < r.end; ++i) {
    lx = std::min(lx, b.min_x[i]);
    ly = std::min(ly, b.min_y[i]);
    lz = std::min(lz, b.min_z[i]);
    hx = std::max(hx, b.max_x[i]);
    hy = std::max(hy, b.max_y[i]);
    hz = std::max(hz, b.max_z[i]);
    const float ex = b.max_x[i] - b.min_x[i];
    const float ey = b.max_y[i] - b.min_y[i];
    const float ez = b.max_z[i] - b.min_z[i];
    const float e = std::max(ex, std::max(ey, ez));
    edge = std::max(edge, e);
    small = std::min(small, e);
  }
  return BoundsSummary{{lx, ly, lz}, {hx, hy, hz}, edge, small};
}

}  // namespace impact::kernels
