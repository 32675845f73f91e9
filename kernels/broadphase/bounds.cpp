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
// on the loads, -fopt-info-vec-missed), which left both scalar. The same accumulator runs
// on full blocks (FloatW) and on the tail (Float1).
template <class F, bool kCheck>
struct BoundsAcc {
  static constexpr float kInf = std::numeric_limits<float>::infinity();
  F lo[3] = {F(kInf), F(kInf), F(kInf)}, hi[3] = {F(-kInf), F(-kInf), F(-kInf)};
  F edge = F(0.0f), small = F(kInf);
  typename F::Mask good = typename F::Mask(true);

  IMPACT_INLINE void add(const AabbSoA& b, uint32_t i) {
    const F x0 = F::load(b.min_x + i), y0 = F::load(b.min_y + i), z0 = F::load(b.min_z + i);
    const F x1 = F::load(b.max_x + i), y1 = F::load(b.max_y + i), z1 = F::load(b.max_z + i);
    if constexpr (kCheck) {
      // NaN fails every comparison: -1e18 <= min <= max <= 1e18 holds only for valid boxes.
      const F lo_max(-1e18f), hi_max(1e18f);
      good = good & (x0 >= lo_max) & (x0 <= x1) & (x1 <= hi_max) & (y0 >= lo_max) & (y0 <= y1) &
             (y1 <= hi_max) & (z0 >= lo_max) & (z0 <= z1) & (z1 <= hi_max);
    }
    lo[0] = min(lo[0], x0), lo[1] = min(lo[1], y0), lo[2] = min(lo[2], z0);
    hi[0] = max(hi[0], x1), hi[1] = max(hi[1], y1), hi[2] = max(hi[2], z1);
    const F e = max(x1 - x0, max(y1 - y0, z1 - z0));
    edge = max(edge, e);
    small = min(small, e);
  }
  /// Folds every lane into s.
  void fold(BoundsSummary& s) const {
    for (uint32_t l = 0; l < F::kWidth; ++l) {
      for (int k = 0; k < 3; ++k) {
        s.lo[k] = std::min(s.lo[k], lo[k].lane(l));
        s.hi[k] = std::max(s.hi[k], hi[k].lane(l));
      }
      s.max_edge = std::max(s.max_edge, edge.lane(l));
      s.min_edge = std::min(s.min_edge, small.lane(l));
    }
  }
};

template <bool kCheck>
BoundsSummary reduce_lanes(AabbSoA b, Range r, bool* valid) {
  constexpr uint32_t W = simd::kSimdWidth;
  BoundsAcc<simd::FloatW, kCheck> full;
  BoundsAcc<simd::Float1, kCheck> tail;
  uint32_t i = r.begin;
  for (; i + W <= r.end; i += W) full.add(b, i);
  for (; i < r.end; ++i) tail.add(b, i);
  BoundsSummary out = empty_bounds_summary();
  full.fold(out);
  tail.fold(out);
  if (valid != nullptr) *valid = simd::all(full.good) && simd::all(tail.good);
  return out;
}

}  // namespace

BoundsSummary reduce_bounds(AabbSoA b, Range r) { return reduce_lanes<false>(b, r, nullptr); }

BoundsSummary reduce_valid_bounds(AabbSoA b, Range r, bool* valid) { return reduce_lanes<true>(b, r, valid); }

}  // namespace impact::kernels
