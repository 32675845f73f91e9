// Sphere (A) against sphere, capsule, box, cylinder, triangle and half-space (B): one point of
// collision data per pair, vectorised across pairs (one lane = one pair). Sphere against
// ellipsoid has its own file (sphere_ellipsoid.cpp: an iterative root solve).
//
// Inputs: LeafSoA lanes per leaf.h (A a sphere; B per kernel), Range r of the bucket.
// Outputs: ManifoldSoA lanes r.begin .. r.end: count (0 or 1), n (A to B), depth,
// point[0] midway between the surfaces, pdepth[0] = depth. Slots 1..3 untouched.
// Method: closest point on B's core (centre, segment, box, solid cylinder, triangle) to
// the sphere centre; n from the centre to it; depth = radii - distance. Deep cases are
// the minimum translation: centre inside the box -> the face of least penetration
// (depth = r + distance to that face); inside the cylinder -> out through its side or
// the nearer cap, the shallower (ties: the side; on the axis the side direction is R's
// column 0); centre on B's core (coincident centres, on a
// capsule axis, in a triangle's plane) -> a deterministic fallback (+y for spheres,
// a perpendicular of the capsule axis, the triangle's normal). All arithmetic is
// relative to A's centre (poses far from the origin keep their precision).
// Preconditions: finite inputs, positive sizes, orthonormal R (host-validated).
// Cost: about 20 (sphere) to 120 (triangle) flops per pair; no branches on lane data
// (the SIMD path selects), both paths run the same template.
// The cylinder's closest point is exact: in its frame the radial part clamps to the
// radius and the height to the caps independently.
// Method citations: Ericson, Real-Time Collision Detection (2005) 5.1.3 (box), 5.1.5
// (triangle); minimum-translation rule for a centre inside a box as in Box2D
// (b2CollidePolygonAndCircle) and Bullet (btSphereBoxCollisionAlgorithm).
#include <cstdint>

#include "kernels/narrowphase/pair_kernels.h"
#include "kernels/narrowphase/lanes/primitives.h"

namespace impact::kernels {
namespace {

using namespace prim;  // NOLINT: lane helpers of this kernel family
using simd::cross;
using simd::dot;
using simd::length_sq;

/// Fills a one-point result from the normal, depth and the two surface points.
template <class F>
IMPACT_INLINE Lanes<F, 1> one_point(const V3<F>& n, F depth, const V3<F>& on_a, const V3<F>& on_b) {
  Lanes<F, 1> m;
  m.count = simd::to_int(depth > F(0.0f));
  m.n = n;
  m.depth = depth;
  m.point[0] = (on_a + on_b) * F(0.5f);
  m.pdepth[0] = depth;
  return m;
}

template <class F>
IMPACT_INLINE void sphere_sphere_block(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, uint32_t k) {
  const V3<F> pa = load_p<F>(a, k);
  const V3<F> d = load_p<F>(b, k) - pa;
  const F ra = ld<F>(a.e[0], k), rb = ld<F>(b.e[0], k);
  F dist;
  const V3<F> n = normalize_or(d, V3<F>{F(0.0f), F(1.0f), F(0.0f)}, dist);
  store(out, k, one_point(n, ra + rb - dist, n * ra, d - n * rb), pa);
}

template <class F>
IMPACT_INLINE void sphere_capsule_block(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, uint32_t k) {
  const V3<F> pa = load_p<F>(a, k);
  const V3<F> cb = load_p<F>(b, k) - pa;
  const V3<F> u = load_axis_z<F>(b, k);
  const F ra = ld<F>(a.e[0], k), rb = ld<F>(b.e[0], k), hb = ld<F>(b.e[1], k);
  const V3<F> origin{F(0.0f), F(0.0f), F(0.0f)};
  const F t = closest_on_segment(cb, u, hb, origin);
  const V3<F> q = madd(cb, t, u);  // closest axis point, relative to the sphere centre
  F dist;
  const V3<F> n = normalize_or(q, any_perpendicular(u), dist);
  store(out, k, one_point(n, ra + rb - dist, n * ra, q - n * rb), pa);
}

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

template <class F>
IMPACT_INLINE void sphere_triangle_block(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, uint32_t k) {
  const V3<F> pa = load_p<F>(a, k);
  const V3<F> v0 = load_p<F>(b, k) - pa;
  const V3<F> v1 = load_w<F>(b, k, 0) - pa;
  const V3<F> v2 = load_w<F>(b, k, 3) - pa;
  const F ra = ld<F>(a.e[0], k);
  const V3<F> nf = triangle_normal(v0, v1, v2);
  const V3<F> origin{F(0.0f), F(0.0f), F(0.0f)};
  typename F::Mask face;
  const V3<F> q = closest_on_triangle(v0, v1, v2, origin, nf, face);
  // Centre in the triangle: the separating direction is the face normal, pointing
  // away from the centre's side (+nf when exactly in the plane).
  F dist;
  const F side = dot(nf, v0);  // > 0: the triangle's plane lies along +nf from the centre
  const V3<F> fallback = select(side >= F(0.0f), nf, -nf);
  const V3<F> n = normalize_or(q, fallback, dist);
  store(out, k, one_point(n, ra - dist, n * ra, q), pa);
}

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

IMPACT_LANE_KERNEL(collide_sphere_sphere, sphere_sphere_block, 1)
IMPACT_LANE_KERNEL(collide_sphere_capsule, sphere_capsule_block, 1)
IMPACT_LANE_KERNEL(collide_sphere_box, sphere_box_block, 1)
IMPACT_LANE_KERNEL(collide_sphere_cylinder, sphere_cylinder_block, 1)
IMPACT_LANE_KERNEL(collide_sphere_triangle, sphere_triangle_block, 1)
IMPACT_LANE_KERNEL(collide_sphere_halfspace, sphere_halfspace_block, 1)

}  // namespace impact::kernels
