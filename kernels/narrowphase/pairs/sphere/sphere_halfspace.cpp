// Sphere (A) against half-space (B): one point of collision data per pair, vectorised
// across pairs (one lane = one pair).
// Method: the centre's height h above the plane; n = -(the plane's normal), depth = r -
// h, the point midway between the sphere's deepest point and the plane.
//
// Inputs: LeafSoA lanes per leaf.h (A a sphere: p = centre, e0 = radius; B a half-space:
// p on the plane, e0..e2 = unit outward normal), Range r of the bucket.
// Outputs: ManifoldSoA lanes r.begin .. r.end: count (0 or 1), n (A to B), depth,
// point[0] midway between the surfaces, pdepth[0] = depth. Slots 1..3 untouched.
// All arithmetic is relative to A's centre (poses 1e5 from the origin keep their
// precision).
// Preconditions: finite inputs, positive sizes, orthonormal R (host-validated).
// Cost: below sphere-sphere's ~20 flops per pair; no branches on lane data (the SIMD path
// selects), both paths (kScalar: one lane, kSimd: kPairWidth lanes) run the same
// template.
#include <cstdint>

#include "kernels/narrowphase/pair_kernels.h"
#include "kernels/narrowphase/lanes/block_driver.h"
#include "kernels/narrowphase/lanes/lane_io.h"

namespace impact::kernels {
namespace {

using namespace prim;  // NOLINT: lane helpers of this kernel family
using simd::cross;
using simd::dot;
using simd::length_sq;

template <class F>
IMPACT_INLINE void sphere_halfspace_block(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, uint32_t k) {
  const V3<F> pa = load_p<F>(a, k);
  const V3<F> q = load_p<F>(b, k) - pa;
  const V3<F> nh = load_e<F>(b, k);
  const F ra = ld<F>(a.e[0], k);
  const F h = -dot(nh, q);  // height of the centre above the plane
  const V3<F> n = -nh;
  store(out, k, one_point(n, ra - h, n * ra, n * h), pa);
}

}  // namespace

void collide_sphere_halfspace(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, Range r,
                              const NarrowConfig& cfg) {
  IMPACT_LANE_KERNEL_BODY(sphere_halfspace_block, 1);
}

}  // namespace impact::kernels
