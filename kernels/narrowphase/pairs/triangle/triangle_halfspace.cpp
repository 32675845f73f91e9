// Triangle (A) against half-space (B): a closed-form lane kernel of up to 3 points,
// vectorised across pairs (one lane = one pair).
// Method: its vertices below the plane, deepest first (a 3-element sorting network; equal
// depths keep vertex order), up to 3 points.
//
// Inputs: LeafSoA lanes per leaf.h (A a triangle: p = v0, w0..w2 = v1, w3..w5 = v2; B a
// half-space { x : nh.(x - pB) <= 0 }, unit nh), Range r of the bucket.
// Outputs: ManifoldSoA lanes r.begin .. r.end: count, n = -nh (B moves down, away from A,
// to separate), depth = the deepest point's (exact), points midway between A's point and
// the plane, pdepth = each point's own depth. depth <= 0: count 0.
// All arithmetic relative to A's first vertex (poses far from the origin keep precision).
// Preconditions: finite inputs, positive sizes, orthonormal R, unit nh (host-validated).
// Cost: ~40 flops per pair, no branches on lane data; both paths (kScalar: one lane,
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
IMPACT_INLINE void triangle_halfspace_block(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out,
                                            uint32_t k) {
  const F zero(0.0f), half(0.5f);
  const V3<F> pa = load_p<F>(a, k);  // v0, the origin of the arithmetic
  const V3<F> nh = load_e<F>(b, k);
  const F off = dot(nh, load_p<F>(b, k) - pa);
  V3<F> v[3] = {V3<F>{zero, zero, zero}, load_w<F>(a, k, 0) - pa, load_w<F>(a, k, 3) - pa};
  F d[3] = {off, off - dot(nh, v[1]), off - dot(nh, v[2])};
  if (simd::none((d[0] > zero) | (d[1] > zero) | (d[2] > zero))) {
    store_no_contact<F>(out, k);
    return;
  }
  // deepest first: swap a later vertex forward only when strictly deeper
  auto order = [&](int i, int j) {
    const auto sw = d[j] > d[i];
    const F di = d[i];
    const V3<F> vi = v[i];
    d[i] = select(sw, d[j], di);
    d[j] = select(sw, di, d[j]);
    v[i] = select(sw, v[j], vi);
    v[j] = select(sw, vi, v[j]);
  };
  order(0, 1);
  order(1, 2);
  order(0, 1);
  Lanes<F, 3> m;
  m.count = simd::to_int(d[0] > zero) + simd::to_int(d[1] > zero) + simd::to_int(d[2] > zero);
  m.n = -nh;
  m.depth = d[0];
  for (int i = 0; i < 3; ++i) {
    m.point[i] = madd(v[i], half * d[i], nh);
    m.pdepth[i] = d[i];
  }
  store(out, k, m, pa);
}

}  // namespace

void collide_triangle_halfspace(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, Range r,
                                const NarrowConfig& cfg) {
  IMPACT_LANE_KERNEL_BODY(triangle_halfspace_block, 3);
}

}  // namespace impact::kernels
