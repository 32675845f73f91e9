// Sphere (A) against cylinder (B): one point of collision data per pair, vectorised
// across pairs (one lane = one pair).
// Method: the closest point of the solid cylinder, exact: in its frame the radial part
// clamps to the radius and the height to the caps independently; n from the centre to it,
// depth = r - distance. A centre inside goes out through the side or the nearer cap, the
// shallower (ties: the side; on the axis the side direction is R's column 0).
//
// Inputs: LeafSoA lanes per leaf.h (A a sphere: p = centre, e0 = radius; B a cylinder: p,
// R column 2 = axis, e0 = radius, e1 = half length), Range r of the bucket.
// Outputs: ManifoldSoA lanes r.begin .. r.end: count (0 or 1), n (A to B), depth,
// point[0] midway between the surfaces, pdepth[0] = depth. Slots 1..3 untouched.
// All arithmetic is relative to A's centre (poses 1e5 from the origin keep their
// precision).
// Preconditions: finite inputs, positive sizes, orthonormal R (host-validated).
// Cost: between sphere-sphere's ~20 and sphere-triangle's ~120 flops per pair; no
// branches on lane data (the SIMD path selects), both paths (kScalar: one lane, kSimd:
// kPairWidth lanes) run the same template.
#include <cstdint>

#include "kernels/narrowphase/pair_kernels.h"
#include "kernels/narrowphase/lanes/block_driver.h"
#include "kernels/narrowphase/lanes/lane_geometry.h"
#include "kernels/narrowphase/lanes/lane_io.h"

namespace impact::kernels {
namespace {

using namespace prim;  // NOLINT: lane helpers of this kernel family
using simd::cross;
using simd::dot;
using simd::length_sq;

template <class F>
IMPACT_INLINE void sphere_cylinder_block(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, uint32_t k) {
  const V3<F> pa = load_p<F>(a, k);
  const V3<F> cb = load_p<F>(b, k) - pa;
  const M3<F> rot = load_r<F>(b, k);
  const F ra = ld<F>(a.e[0], k), rc = ld<F>(b.e[0], k), hc = ld<F>(b.e[1], k);
  const F zero(0.0f), one(1.0f);
  // Sphere centre in the cylinder frame (axis z): radial part (x, y), height z.
  const V3<F> d = rot.apply_t(-cb);
  const F rq = sqrt(d.x * d.x + d.y * d.y);
  const auto off_axis = rq > F(1e-30f);
  const F inv_rq = one / select(off_axis, rq, one);
  const F ex = select(off_axis, d.x * inv_rq, one), ey = select(off_axis, d.y * inv_rq, zero);
  // Closest cylinder point: the radial part clamped to the radius, z to the caps.
  const auto beyond = rq > rc;
  const V3<F> c{select(beyond, ex * rc, d.x), select(beyond, ey * rc, d.y), clamp(d.z, -hc, hc)};
  const V3<F> v = d - c;  // cylinder -> centre
  const F v2 = length_sq(v);
  const auto outside = v2 >= F(kTinySq);
  const F vl = sqrt(v2);
  const F inv = one / select(outside, vl, one);
  const V3<F> n_out = v * (-inv);
  // Inside: out through the side or the nearer cap, whichever is shallower (ties: side).
  const F ps = rc - rq, pc = hc - abs(d.z);
  const auto use_side = ps <= pc;
  const F sz = simd::sign_nonneg(d.z);
  const V3<F> n_in = select(use_side, V3<F>{-ex, -ey, zero}, V3<F>{zero, zero, -sz});
  const V3<F> face = select(use_side, V3<F>{ex * rc, ey * rc, d.z}, V3<F>{d.x, d.y, sz * hc});
  const V3<F> nl = select(outside, n_out, n_in);
  const F depth = select(outside, ra - vl, ra + select(use_side, ps, pc));
  const V3<F> on_b_local = select(outside, c, face);
  const V3<F> n = rot.apply(nl);
  const V3<F> on_b = cb + rot.apply(on_b_local);
  store(out, k, one_point(n, depth, n * ra, on_b), pa);
}

}  // namespace

void collide_sphere_cylinder(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, Range r,
                             const NarrowConfig& cfg) {
  IMPACT_LANE_KERNEL_BODY(sphere_cylinder_block, 1);
}

}  // namespace impact::kernels
