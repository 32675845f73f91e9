#include "kernels/broadphase/bounds.h"

#include <algorithm>
#include <limits>

#include "kernels/simd/lanes.h"

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

namespace {

// reduce_bounds / reduce_valid_bounds over lanes of the SIMD vocabulary: GCC 12 does not
// vectorise the omp simd min / max reductions of the plain loop ("no vectype for stmt"
// on the loads, -fopt-info-vec-missed), which left both scalar.
template <bool kCheck>
BoundsSummary reduce_lanes(AabbSoA b, Range r, bool* valid) {
  using F = simd::FloatW;
  constexpr uint32_t W = simd::kSimdWidth;
  constexpr float inf = std::numeric_limits<float>::infinity();
  constexpr float kMax = 1e18f;
  F lx(inf), ly(inf), lz(inf), hx(-inf), hy(-inf), hz(-inf), edge(0.0f), small(inf);
  typename F::Mask good(true);
  uint32_t i = r.begin;
  for (; i + W <= r.end; i += W) {
    const F x0 = F::load(b.min_x + i), y0 = F::load(b.min_y + i), z0 = F::load(b.min_z + i);
    const F x1 = F::load(b.max_x + i), y1 = F::load(b.max_y + i), z1 = F::load(b.max_z + i);
    if constexpr (kCheck) {
      // NaN fails every comparison: -1e18 <= min <= max <= 1e18 holds only for valid boxes.
      const F lo_max(-kMax), hi_max(kMax);
      good = good & (x0 >= lo_max) & (x0 <= x1) & (x1 <= hi_max) & (y0 >= lo_max) & (y0 <= y1) &
             (y1 <= hi_max) & (z0 >= lo_max) & (z0 <= z1) & (z1 <= hi_max);
    }
    lx = min(lx, x0), ly = min(ly, y0), lz = min(lz, z0);
    hx = max(hx, x1), hy = max(hy, y1), hz = max(hz, z1);
    const F e = max(x1 - x0, max(y1 - y0, z1 - z0));
    edge = max(edge, e);
    small = min(small, e);
  }
  bool ok = simd::all(good);
  BoundsSummary out{{inf, inf, inf}, {-inf, -inf, -inf}, 0.0f, inf};
  for (uint32_t l = 0; l < W; ++l) {  // lanes, then the tail, as scalars
    out.lo[0] = std::min(out.lo[0], lx.lane(l));
    out.lo[1] = std::min(out.lo[1], ly.lane(l));
    out.lo[2] = std::min(out.lo[2], lz.lane(l));
    out.hi[0] = std::max(out.hi[0], hx.lane(l));
    out.hi[1] = std::max(out.hi[1], hy.lane(l));
    out.hi[2] = std::max(out.hi[2], hz.lane(l));
    out.max_edge = std::max(out.max_edge, edge.lane(l));
    out.min_edge = std::min(out.min_edge, small.lane(l));
  }
  for (; i < r.end; ++i) {
    const float x0 = b.min_x[i], y0 = b.min_y[i], z0 = b.min_z[i];
    const float x1 = b.max_x[i], y1 = b.max_y[i], z1 = b.max_z[i];
    if constexpr (kCheck) {
      ok = ok && x0 >= -kMax && x0 <= x1 && x1 <= kMax && y0 >= -kMax && y0 <= y1 && y1 <= kMax &&
           z0 >= -kMax && z0 <= z1 && z1 <= kMax;
    }
    out.lo[0] = std::min(out.lo[0], x0);
    out.lo[1] = std::min(out.lo[1], y0);
    out.lo[2] = std::min(out.lo[2], z0);
    out.hi[0] = std::max(out.hi[0], x1);
    out.hi[1] = std::max(out.hi[1], y1);
    out.hi[2] = std::max(out.hi[2], z1);
    const float e = std::max(x1 - x0, std::max(y1 - y0, z1 - z0));
    out.max_edge = std::max(out.max_edge, e);
    out.min_edge = std::min(out.min_edge, e);
  }
  if (valid != nullptr) *valid = ok;
  return out;
}

}  // namespace

BoundsSummary reduce_bounds(AabbSoA b, Range r) { return reduce_lanes<false>(b, r, nullptr); }

BoundsSummary reduce_valid_bounds(AabbSoA b, Range r, bool* valid) { return reduce_lanes<true>(b, r, valid); }

}  // namespace impact::kernels
