// Sphere (A) against box (B): one point of collision data per pair, vectorised across
// pairs (one lane = one pair).
// Method: in the box frame, the closest box point to the centre (Ericson, Real-Time
// Collision Detection (2005) 5.1.3); n from the centre to it, depth = r - distance. A
// centre inside the box takes the minimum translation: the face of least penetration
// (ties: x, then y, then z), depth = r + the distance to that face, as in Box2D
// (b2CollidePolygonAndCircle) and Bullet (btSphereBoxCollisionAlgorithm).
//
// Inputs: LeafSoA lanes per leaf.h (A a sphere: p = centre, e0 = radius; B a box: p, R,
// half extents e0..e2), Range r of the bucket.
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
IMPACT_INLINE void sphere_box_block(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, uint32_t k) {
  const V3<F> pa = load_p<F>(a, k);
  const V3<F> cb = load_p<F>(b, k) - pa;
  const M3<F> rot = load_r<F>(b, k);
  const V3<F> e = load_e<F>(b, k);
  const F ra = ld<F>(a.e[0], k);
  const F zero(0.0f), one(1.0f);
  // Sphere centre in the box frame, and its closest box point.
  const V3<F> d = rot.apply_t(-cb);
  const V3<F> c{clamp(d.x, -e.x, e.x), clamp(d.y, -e.y, e.y), clamp(d.z, -e.z, e.z)};
  const V3<F> v = d - c;  // box -> centre
  const F v2 = length_sq(v);
  const auto outside = v2 >= F(kTinySq);
  // Outside: n from the centre towards the box.
  const F vl = sqrt(v2);
  const F inv = one / select(outside, vl, one);
  const V3<F> n_out = v * (-inv);
  // Inside: the face of least penetration (ties: x, then y, then z).
  const F px = e.x - abs(d.x), py = e.y - abs(d.y), pz = e.z - abs(d.z);
  const auto use_x = (px <= py) & (px <= pz);
  const auto use_y = andnot(py <= pz, use_x);
  const F sx = simd::sign_nonneg(d.x), sy = simd::sign_nonneg(d.y), sz = simd::sign_nonneg(d.z);
  V3<F> n_in{zero, zero, -sz};
  n_in = select(use_y, V3<F>{zero, -sy, zero}, n_in);
  n_in = select(use_x, V3<F>{-sx, zero, zero}, n_in);
  F pen = select(use_x, px, select(use_y, py, pz));
  V3<F> face{d.x, d.y, sz * e.z};
  face = select(use_y, V3<F>{d.x, sy * e.y, d.z}, face);
  face = select(use_x, V3<F>{sx * e.x, d.y, d.z}, face);
  const V3<F> nl = select(outside, n_out, n_in);
  const F depth = select(outside, ra - vl, ra + pen);
  const V3<F> on_b_local = select(outside, c, face);
  // Back to the world frame (relative to the sphere centre).
  const V3<F> n = rot.apply(nl);
  const V3<F> on_b = cb + rot.apply(on_b_local);
  store(out, k, one_point(n, depth, n * ra, on_b), pa);
}

}  // namespace

void collide_sphere_box(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, Range r,
                        const NarrowConfig& cfg) {
  IMPACT_LANE_KERNEL_BODY(sphere_box_block, 1);
}

}  // namespace impact::kernels
