// Capsule (A) against half-space (B): collision data of 1 or 2 points per pair,
// vectorised across pairs (one lane = one pair).
// Method: the capsule's surface below each core endpoint (along the normal), where below
// the plane; one point when the capsule stands steep (both lines leave through the lower
// end's cap).
//
// Inputs: LeafSoA lanes per leaf.h (A a capsule: p, R column 2 = axis, e0 = radius, e1 =
// half length). Outputs: ManifoldSoA lanes of the Range, point slots 0 and 1
// (capsule_lanes.h finish). All arithmetic is relative to A's centre.
// Preconditions: finite inputs, positive radius, half lengths >= 0, unit axes.
// Cost: ~60 flops per pair, no branches on lane data except skipping work no lane of a
// block needs; both paths (kScalar, kSimd) run the same template.
#include <cstdint>

#include "kernels/narrowphase/pair_kernels.h"
#include "kernels/narrowphase/lanes/block_driver.h"
#include "kernels/narrowphase/lanes/lane_geometry.h"
#include "kernels/narrowphase/lanes/lane_io.h"
#include "kernels/narrowphase/pairs/capsule/capsule_lanes.h"

namespace impact::kernels {
namespace {

using namespace prim;           // NOLINT: lane helpers of this kernel family
using namespace capsule_lanes;  // NOLINT: tolerances and the two-point result
using simd::cross;
using simd::dot;
using simd::length_sq;

template <class F>
IMPACT_INLINE void capsule_halfspace_block(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out,
                                           uint32_t k) {
  const V3<F> pa = load_p<F>(a, k);
  const V3<F> q = load_p<F>(b, k) - pa;
  const V3<F> nh = load_e<F>(b, k);
  const V3<F> u = load_axis_z<F>(a, k);
  const F ra = ld<F>(a.e[0], k), ha = ld<F>(a.e[1], k);
  const F zero(0.0f), half(0.5f);
  const F hc = -dot(nh, q);       // centre height above the plane
  const F hu = dot(nh, u) * ha;   // endpoint offset
  const V3<F> n = -nh;
  // the capsule's surface along n from each endpoint (its cap, or the cylinder when n
  // leans back along the axis), and its penetration below the plane
  const F snu = dot(n, u);
  const F l0 = capsule_exit(-ha, snu, ra, ha), l1 = capsule_exit(ha, snu, ra, ha);
  const F d0 = l0 - (hc - hu), d1 = l1 - (hc + hu);  // endpoints -ha, +ha
  const V3<F> x0 = u * (-ha), x1 = u * ha;
  const V3<F> p0 = madd(x0, l0 - half * d0, n), p1 = madd(x1, l1 - half * d1, n);
  // A steep capsule (the line down from the upper endpoint leaves through the lower
  // end's cap: r |s| > 2 h sin) touches with that cap alone; its second line would give
  // the same point for an upright capsule (or a zero-length core), so it keeps one.
  const auto steep = ra * abs(snu) > F(2.0f) * ha * sqrt(max(F(1.0f) - snu * snu, F(1e-12f)));
  const auto two = andnot((d0 > zero) & (d1 > zero), steep);
  const auto first = d0 >= d1;
  L2<F> m;
  finish(m, n, max(d0, d1), two, p0, d0, p1, d1, select(first, p0, p1), max(d0, d1));
  store(out, k, m, pa);
}

}  // namespace

void collide_capsule_halfspace(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, Range r,
                               const NarrowConfig& cfg) {
  IMPACT_LANE_KERNEL_BODY(capsule_halfspace_block, 2);
}

}  // namespace impact::kernels
