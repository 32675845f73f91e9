// Cylinder (A) against half-space (B): a closed-form lane kernel of up to 4 points,
// vectorised across pairs (one lane = one pair).
// Method: s = nh.u, and the unit radial direction rad = the part of -nh across the axis,
// from its coordinates on R's columns 0 and 1 (dx, dy; |.| = rl; rad = column 0 when rl
// <= 1e-6: an upright cylinder, whose cap rim is all equally deep). The lower cap's
// centre c = -sign(s) h u lies off + h|s| below the plane; its rim point along rad is the
// deepest point, r rl deeper. The manifold is the deepest point and the other points of
// the feature most parallel to the plane (the box rule, box_halfspace.cpp):
//   the cap when |s| >= rl (its normal within 45 degrees of nh): the rim points at 90, 270
//   and 180 degrees from rad, depths off + h|s|, the same, and r rl less;
//   the side otherwise: the other cap's rim point along rad, 2 h|s| less deep.
// Depths fall along that order, so the points below the plane are a prefix: an upright
// cylinder sunk into the plane gives 4 rim points, one lying on its side 2, one tilted
// onto its rim 1. Depths are the closed forms (the geometric ones up to rounding: nh.rad
// = -rl, nh.(u x rad) = 0).
//
// Inputs: LeafSoA lanes per leaf.h (A a cylinder: p, R column 2 = axis u, e0 = radius r,
// e1 = half length h; B a half-space { x : nh.(x - pB) <= 0 }, unit nh), Range r of the
// bucket.
// Outputs: ManifoldSoA lanes r.begin .. r.end: count, n = -nh (B moves down, away from A,
// to separate), depth = the deepest point's (exact), points midway between A's point and
// the plane, pdepth = each point's own depth. depth <= 0: count 0.
// All arithmetic relative to A's centre (poses far from the origin keep precision).
// Preconditions: finite inputs, positive sizes, orthonormal R, unit nh (host-validated).
// Cost: ~150 flops per pair, no branches on lane data; both paths (kScalar: one lane,
// kSimd: kPairWidth lanes) run the same template.
#include <cstdint>

#include "kernels/narrowphase/pair_kernels.h"
#include "kernels/narrowphase/lanes/block_driver.h"
#include "kernels/narrowphase/lanes/lane_io.h"

namespace impact::kernels {
namespace {

using namespace prim;  // NOLINT: lane helpers of this kernel family
using simd::cross;
using simd::dot;

template <class F>
IMPACT_INLINE void cylinder_halfspace_block(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out,
                                            uint32_t k) {
  const F zero(0.0f), half(0.5f), two(2.0f);
  const V3<F> pa = load_p<F>(a, k);
  const V3<F> nh = load_e<F>(b, k);
  const F off = dot(nh, load_p<F>(b, k) - pa);  // x lies below the plane when nh.x < off
  const M3<F> ra = load_r<F>(a, k);
  const F r = ld<F>(a.e[0], k), h = ld<F>(a.e[1], k);
  const V3<F>& u = ra.c[2];
  const F s = dot(nh, u);
  const F dx = -dot(nh, ra.c[0]), dy = -dot(nh, ra.c[1]);
  const F rl = simd::sqrt(dx * dx + dy * dy);
  const auto radial = rl > F(1e-6f);
  const F inv = F(1.0f) / select(radial, rl, F(1.0f));
  const V3<F> rad = select(radial, (ra.c[0] * dx + ra.c[1] * dy) * inv, ra.c[0]);
  const V3<F> side = cross(u, rad);
  const F hs = abs(s) * h;
  const V3<F> c = u * (-simd::sign_nonneg(s) * h);  // the lower cap's centre
  const F base = off + hs;                          // its depth below the plane
  const F d0 = base + r * rl;
  const V3<F> p0 = madd(c, r, rad);
  Lanes<F, 4> m;
  if (simd::none(d0 > zero)) {
    store_no_contact<F>(out, k);
    return;
  }
  const auto cap = abs(s) >= rl;
  const F d3 = base - r * rl;
  const F dh = d0 - two * hs;
  // cap: p0, c + r side, c - r side, c - r rad; side: p0, the upper cap's rim point.
  const V3<F> p1 = select(cap, madd(c, r, side), p0 - c * two);
  const V3<F> p2 = madd(c, -r, side);
  const V3<F> p3 = madd(c, -r, rad);
  const F d1 = select(cap, base, dh);
  const F d2 = select(cap, base, F(-1.0f));
  const F dd3 = select(cap, d3, F(-1.0f));
  // d0 >= every other depth, so a lane with d0 <= 0 counts 0
  m.count =
      simd::to_int(d0 > zero) + simd::to_int(d1 > zero) + simd::to_int(d2 > zero) + simd::to_int(dd3 > zero);
  m.n = -nh;
  m.depth = d0;
  const V3<F> pts[4] = {p0, p1, p2, p3};
  const F dep[4] = {d0, d1, d2, dd3};
  for (int i = 0; i < 4; ++i) {
    m.point[i] = madd(pts[i], half * dep[i], nh);
    m.pdepth[i] = dep[i];
  }
  store(out, k, m, pa);
}

}  // namespace

void collide_cylinder_halfspace(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, Range r,
                                const NarrowConfig& cfg) {
  IMPACT_LANE_KERNEL_BODY(cylinder_halfspace_block, 4);
}

}  // namespace impact::kernels
