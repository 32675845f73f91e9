// Sphere (A) against capsule (B): one point of collision data per pair, vectorised across
// pairs (one lane = one pair).
// Method: the closest point of B's core segment to the centre (Ericson, Real-Time
// Collision Detection (2005) 5.1.2); n from the centre to it, depth = the radii's sum -
// the distance. On or near the core (the closest point's offset as small as rounding) the
// offset keeps only its part in the cone of valid normals (into_segment_cone: across the
// axis inside, outwards at an end), so the normal never turns along the axis; a centre
// exactly on the core takes a deterministic perpendicular of the axis.
//
// Inputs: LeafSoA lanes per leaf.h (A a sphere: p = centre, e0 = radius; B a capsule: p,
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
IMPACT_INLINE void sphere_capsule_block(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, uint32_t k) {
  const V3<F> pa = load_p<F>(a, k);
  const V3<F> cb = load_p<F>(b, k) - pa;
  const V3<F> u = load_axis_z<F>(b, k);
  const F ra = ld<F>(a.e[0], k), rb = ld<F>(b.e[0], k), hb = ld<F>(b.e[1], k);
  const V3<F> origin{F(0.0f), F(0.0f), F(0.0f)};
  const F t = closest_on_segment(cb, u, hb, origin);
  // closest axis point, relative to the sphere centre; -q runs from it to the centre
  V3<F> q = madd(cb, t, u);
  const F reach = F(kConeReach) * (hb + abs(cb.x) + abs(cb.y) + abs(cb.z));
  const auto near = length_sq(q) < reach * reach;
  if (any(near)) q = select(near, -into_segment_cone(-q, u, t, hb), q);
  F dist;
  const V3<F> n = normalize_or(q, any_perpendicular(u), dist);
  store(out, k, one_point(n, ra + rb - dist, n * ra, q - n * rb), pa);
}

}  // namespace

void collide_sphere_capsule(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, Range r,
                            const NarrowConfig& cfg) {
  IMPACT_LANE_KERNEL_BODY(sphere_capsule_block, 1);
}

}  // namespace impact::kernels
