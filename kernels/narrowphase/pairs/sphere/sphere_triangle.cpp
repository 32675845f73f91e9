// Sphere (A) against triangle (B, two-sided, zero thickness): one point of collision data
// per pair, vectorised across pairs (one lane = one pair).
// Method: the closest point of the triangle to the centre (Ericson, Real-Time Collision
// Detection (2005) 5.1.5, regions by selects); n from the centre to it, depth = r -
// distance. The direction to the closest point is kept in the normal cone of its region
// (project_to_cone: along +-normal over the face, across an edge, outwards at a vertex),
// so a centre on the triangle within rounding gets a normal the overlap is least along.
// A centre in the triangle takes the face normal, pointing away from the centre's side
// (+normal when exactly in the plane).
//
// Inputs: LeafSoA lanes per leaf.h (A a sphere: p = centre, e0 = radius; B a triangle: p
// = v0, w0..w2 = v1, w3..w5 = v2), Range r of the bucket.
// Outputs: ManifoldSoA lanes r.begin .. r.end: count (0 or 1), n (A to B), depth,
// point[0] midway between the surfaces, pdepth[0] = depth. Slots 1..3 untouched.
// All arithmetic is relative to A's centre (poses 1e5 from the origin keep their
// precision).
// Preconditions: finite inputs, positive sizes, orthonormal R (host-validated).
// Cost: ~120 flops per pair (~100 more in blocks with a centre within kConeReach); no branches on lane data (the SIMD path selects), both paths
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
IMPACT_INLINE void sphere_triangle_block(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, uint32_t k) {
  const V3<F> pa = load_p<F>(a, k);
  const V3<F> v0 = load_p<F>(b, k) - pa;
  const V3<F> v1 = load_w<F>(b, k, 0) - pa;
  const V3<F> v2 = load_w<F>(b, k, 3) - pa;
  const F ra = ld<F>(a.e[0], k);
  const V3<F> nf = triangle_normal(v0, v1, v2);
  const V3<F> origin{F(0.0f), F(0.0f), F(0.0f)};
  TriangleRegion<F> reg;
  const V3<F> q = closest_on_triangle(v0, v1, v2, origin, nf, reg);
  // Centre in the triangle: the separating direction is the face normal, pointing
  // away from the centre's side (+nf when exactly in the plane).
  F dist;
  const F side = dot(nf, v0);  // > 0: the triangle's plane lies along +nf from the centre
  const V3<F> fallback = select(side >= F(0.0f), nf, -nf);
  V3<F> n = normalize_or(q, fallback, dist);
  // Within kConeReach of the coordinates' size, q is moved back into its region's normal
  // cone (rounding of a centre on the triangle, on an edge or at a vertex leaves it
  // pointing anywhere, in the plane included).
  const F size = max(max(abs(v0.x) + abs(v0.y) + abs(v0.z), abs(v1.x) + abs(v1.y) + abs(v1.z)),
                     abs(v2.x) + abs(v2.y) + abs(v2.z));
  const auto near = dist < F(kConeReach) * size;
  if (any(near)) {
    HalfCone<F> ca, cb;
    triangle_half_cones(v0, v1, v2, nf, reg, ca, cb);
    const V3<F> qc = -project_to_cone(-q, ca, cb, nf, F(kNormalConeSlack) * dist);
    F ql;
    n = select(near, normalize_or(qc, fallback, ql), n);
  }
  store(out, k, one_point(n, ra - dist, n * ra, q), pa);
}

}  // namespace

void collide_sphere_triangle(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, Range r,
                             const NarrowConfig& cfg) {
  IMPACT_LANE_KERNEL_BODY(sphere_triangle_block, 1);
}

}  // namespace impact::kernels
