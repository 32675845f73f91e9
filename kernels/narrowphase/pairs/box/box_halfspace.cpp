// Box (A) against half-space (B): a manifold of up to 4 points, vectorised across pairs
// (one lane = one pair).
//
// Inputs: LeafSoA lanes per leaf.h (A a box: p, R, half extents e0..e2; B a half-space: p
// on the plane, e0..e2 = unit outward normal nh). Outputs: ManifoldSoA lanes of the
// Range, point slots 0..3: n = -nh, depth = the deepest vertex's.
// Method: the deepest vertex and the other corners of the lower face most parallel to the
// plane (largest |cos|), sorted by depth, those below the plane (1, 2 or 4 points: a
// vertex, an edge or the face; a box sunk deeper keeps the 4 corners of that face, the
// deepest first). No candidate reduction. Each point lies midway between its vertex and
// the plane; pdepth is its own depth. All arithmetic relative to A's centre.
// Preconditions: finite inputs, positive half extents, orthonormal R, unit nh.
// Cost: closed form (no loop, no reduction); no branches on lane data except a block
// without contact (count 0 stored, nothing else); both paths (kScalar, kSimd) run the
// same template.
#include <cstdint>

#include "kernels/narrowphase/pair_kernels.h"
#include "kernels/narrowphase/lanes/block_driver.h"
#include "kernels/narrowphase/lanes/lane_io.h"

namespace impact::kernels {
namespace {

using namespace prim;  // NOLINT: lane helpers of this kernel family
using simd::dot;

template <class F>
IMPACT_INLINE void box_halfspace_block(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, uint32_t k) {
  using Mask = typename F::Mask;
  using Int = typename F::Int;
  const F zero(0.0f), half(0.5f), two(2.0f);
  const V3<F> pa = load_p<F>(a, k);
  const V3<F> q = load_p<F>(b, k) - pa;
  const M3<F> ra = load_r<F>(a, k);
  const V3<F> ea = load_e<F>(a, k);
  const V3<F> nh = load_e<F>(b, k);
  // cosines of the box axes with the plane normal, and nh . (half-extent vectors)
  const F c[3] = {dot(nh, ra.c[0]), dot(nh, ra.c[1]), dot(nh, ra.c[2])};
  const F g[3] = {c[0] * ea.x, c[1] * ea.y, c[2] * ea.z};
  const F eh[3] = {ea.x, ea.y, ea.z};
  // the deepest vertex: s_i = -sign(g_i) on every axis; its depth below the plane
  const F dn = dot(nh, q);  // the plane's height above the box centre
  const F ag[3] = {abs(g[0]), abs(g[1]), abs(g[2])};
  const F d0 = ag[0] + ag[1] + ag[2] + dn;
  V3<F> v0{zero, zero, zero}, flip[3];
  for (int i = 0; i < 3; ++i) {
    const V3<F> h = ra.c[i] * (-simd::sign_nonneg(g[i]) * eh[i]);
    v0 = v0 + h;
    flip[i] = h * F(-2.0f);  // to the vertex across axis i, 2|g_i| shallower
  }
  // the lower face most parallel to the plane (largest |cos|) holds the deepest vertex;
  // its other 3 corners, sorted by depth, follow: flip the axis of smaller |g|, the
  // larger, both. Depths fall monotonically, so the corners below the plane are a prefix.
  const F ac0 = abs(c[0]), ac1 = abs(c[1]), ac2 = abs(c[2]);
  const Mask j0 = (ac0 >= ac1) & (ac0 >= ac2);
  const Mask j1 = andnot(ac1 >= ac2, j0);
  const V3<F> fk = select(j0, flip[1], select(j1, flip[2], flip[0]));
  const V3<F> fl = select(j0, flip[2], select(j1, flip[0], flip[1]));
  const F gk = select(j0, ag[1], select(j1, ag[2], ag[0]));
  const F gl = select(j0, ag[2], select(j1, ag[0], ag[1]));
  const Mask swap = gl < gk;
  const V3<F> fs = select(swap, fl, fk), fb = select(swap, fk, fl);
  const F d1 = d0 - two * min(gk, gl), d2 = d0 - two * max(gk, gl);
  const F d3 = d1 - two * max(gk, gl);
  const V3<F> vtx[4] = {v0, v0 + fs, v0 + fb, v0 + fs + fb};
  const F dep[4] = {d0, d1, d2, d3};
  Lanes<F, 4> m;
  m.count = simd::to_int(d0 > zero) + simd::to_int(d1 > zero) + simd::to_int(d2 > zero) + simd::to_int(d3 > zero);
  if (simd::none(m.count > Int(0))) {
    store_no_contact<F>(out, k);
    return;
  }
  m.n = -nh;
  m.depth = d0;
  for (int i = 0; i < 4; ++i) {
    // the vertex lies dep below the plane; the point half of that up along nh
    m.point[i] = madd(vtx[i], half * dep[i], nh);
    m.pdepth[i] = dep[i];
  }
  store(out, k, m, pa);
}

}  // namespace

void collide_box_halfspace(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, Range r,
                           const NarrowConfig& cfg) {
  IMPACT_LANE_KERNEL_BODY(box_halfspace_block, 4);
}

}  // namespace impact::kernels
