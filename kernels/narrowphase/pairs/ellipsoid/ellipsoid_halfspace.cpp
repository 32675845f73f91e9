// Ellipsoid (A) against half-space (B): a closed-form lane kernel of one point,
// vectorised across pairs (one lane = one pair).
// Method: the support along -nh in closed form. With m = R^T nh and w = e o m (radii
// times m, per axis), the deepest point is -R (e o w) / |w| and its depth off + |w| (off
// = nh.(pB - pA)). One point.
//
// Inputs: LeafSoA lanes per leaf.h (A an ellipsoid: p, R, radii e0..e2; B a half-space {
// x : nh.(x - pB) <= 0 }, unit nh), Range r of the bucket.
// Outputs: ManifoldSoA lanes r.begin .. r.end: count, n = -nh (B moves down, away from A,
// to separate), depth = the deepest point's (exact), points midway between A's point and
// the plane, pdepth = each point's own depth. depth <= 0: count 0.
// All arithmetic relative to A's centre (poses far from the origin keep precision).
// Preconditions: finite inputs, positive sizes, orthonormal R, unit nh (host-validated).
// Cost: between triangle-half-space's ~40 and cylinder-half-space's ~150 flops per pair,
// no branches on lane data; both paths (kScalar: one lane, kSimd: kPairWidth lanes) run
// the same template.
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
IMPACT_INLINE void ellipsoid_halfspace_block(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out,
                                             uint32_t k) {
  const F zero(0.0f), half(0.5f);
  const V3<F> pa = load_p<F>(a, k);
  const V3<F> nh = load_e<F>(b, k);
  const F off = dot(nh, load_p<F>(b, k) - pa);
  const M3<F> ra = load_r<F>(a, k);
  const V3<F> e = load_e<F>(a, k);
  const V3<F> w{e.x * dot(nh, ra.c[0]), e.y * dot(nh, ra.c[1]), e.z * dot(nh, ra.c[2])};
  const F len = simd::sqrt(dot(w, w));
  const F d0 = off + len;
  if (simd::none(d0 > zero)) {
    store_no_contact<F>(out, k);
    return;
  }
  // len >= the smallest radius > 0 for a unit nh
  const F inv = F(-1.0f) / len;
  const V3<F> x = (ra.c[0] * (e.x * w.x) + ra.c[1] * (e.y * w.y) + ra.c[2] * (e.z * w.z)) * inv;
  Lanes<F, 1> m;
  m.count = simd::to_int(d0 > zero);
  m.n = -nh;
  m.depth = d0;
  m.point[0] = madd(x, half * d0, nh);
  m.pdepth[0] = d0;
  store(out, k, m, pa);
}

}  // namespace

void collide_ellipsoid_halfspace(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, Range r,
                                 const NarrowConfig& cfg) {
  IMPACT_LANE_KERNEL_BODY(ellipsoid_halfspace_block, 1);
}

}  // namespace impact::kernels
