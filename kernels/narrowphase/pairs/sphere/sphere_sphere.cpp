// Sphere (A) against sphere (B): one point of collision data per pair, vectorised across
// pairs (one lane = one pair).
// Method: n from A's centre to B's, depth = the radii's sum - the centres' distance;
// coincident centres (distance below FLT_MIN) take n = +y.
//
// Inputs: LeafSoA lanes per leaf.h (A a sphere: p = centre, e0 = radius; B a sphere),
// Range r of the bucket.
// Outputs: ManifoldSoA lanes r.begin .. r.end: count (0 or 1), n (A to B), depth,
// point[0] midway between the surfaces, pdepth[0] = depth. Slots 1..3 untouched.
// All arithmetic is relative to A's centre (poses 1e5 from the origin keep their
// precision).
// Preconditions: finite inputs, positive sizes, orthonormal R (host-validated).
// Cost: ~20 flops per pair; no branches on lane data (the SIMD path selects), both paths
// (kScalar: one lane, kSimd: kPairWidth lanes) run the same template.
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
IMPACT_INLINE void sphere_sphere_block(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, uint32_t k) {
  const V3<F> pa = load_p<F>(a, k);
  const V3<F> d = load_p<F>(b, k) - pa;
  const F ra = ld<F>(a.e[0], k), rb = ld<F>(b.e[0], k);
  F dist;
  const V3<F> n = normalize_or(d, V3<F>{F(0.0f), F(1.0f), F(0.0f)}, dist);
  store(out, k, one_point(n, ra + rb - dist, n * ra, d - n * rb), pa);
}

}  // namespace

void collide_sphere_sphere(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, Range r,
                           const NarrowConfig& cfg) {
  IMPACT_LANE_KERNEL_BODY(sphere_sphere_block, 1);
}

}  // namespace impact::kernels
