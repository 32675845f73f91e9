// Capsule (A) against capsule (B): collision data of 1 or 2 points per pair, vectorised
// across pairs (one lane = one pair).
// Method: lying on another rests on two points. Closest points inside both segments (|ua
// x ub| > 1e-3): n = +-ua x ub, exact where qb - qa is rounding noise (cores crossing);
// elsewhere qb - qa moved into the cone of normals the closest points' optimality allows
// (parallel or meeting cores: across the axes, never along them); axes that meet and are
// parallel: a perpendicular.
//
// Inputs: LeafSoA lanes per leaf.h (A a capsule: p, R column 2 = axis, e0 = radius, e1 =
// half length). Outputs: ManifoldSoA lanes of the Range, point slots 0 and 1
// (capsule_lanes.h finish). All arithmetic is relative to A's centre.
// Preconditions: finite inputs, positive radius, half lengths >= 0, unit axes.
// Cost: between capsule-half-space's ~60 and capsule-triangle's ~600 flops per pair, no
// branches on lane data except skipping work no lane of a block needs; both paths
// (kScalar, kSimd) run the same template.
#include <cstdint>

#include "kernels/narrowphase/pair_kernels.h"
#include "kernels/narrowphase/lanes/block_driver.h"
#include "kernels/narrowphase/lanes/lane_geometry.h"
#include "kernels/narrowphase/lanes/lane_io.h"
#include "kernels/narrowphase/pairs/capsule/capsule_lanes.h"

namespace impact::kernels {
namespace {

using namespace prim;           // NOLINT: lane helpers of this kernel family
using namespace capsule_lanes;  // NOLINT: tolerances and the two-point result
using simd::cross;
using simd::dot;
using simd::length_sq;

/// Where the line o + n * lambda (unit n, travelling along +n) enters the capsule with
/// core cb + ub * t (|t| <= hb, unit ub) and radius rb: the smallest lambda on its
/// surface (cylinder or cap); `met` is false in lanes where the line misses it.
template <class F>
IMPACT_INLINE F capsule_entry(const V3<F>& o, const V3<F>& n, const V3<F>& cb, const V3<F>& ub, F hb, F rb,
                              typename F::Mask& met) {
  const F zero(0.0f), one(1.0f), far(3.0e38f);
  const V3<F> w = o - cb;
  const F wu = dot(w, ub), nu = dot(n, ub);
  const V3<F> wp = madd(w, -wu, ub), np = madd(n, -nu, ub);  // across the axis
  const F a = length_sq(np), b = dot(wp, np), c = length_sq(wp) - rb * rb;
  const F disc = b * b - a * c;
  const auto across = (a > F(1e-12f)) & (disc >= zero);
  const F lc = (-b - sqrt(max(disc, zero))) / select(a > F(1e-12f), a, one);
  const auto cyl = across & (abs(mul_add(nu, lc, wu)) <= hb);
  F best = select(cyl, lc, far);
  met = cyl;
  for (int sgn = -1; sgn <= 1; sgn += 2) {
    const V3<F> m = madd(w, F(static_cast<float>(-sgn)) * hb, ub);  // from the cap's centre
    const F mn = dot(m, n);
    const F d2 = mn * mn - (length_sq(m) - rb * rb);
    const auto ok = d2 >= zero;
    const F ls = -mn - sqrt(max(d2, zero));
    best = select(ok & (ls < best), ls, best);
    met = met | ok;
  }
  return best;
}

template <class F>
IMPACT_INLINE void capsule_capsule_block(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, uint32_t k) {
  const V3<F> pa = load_p<F>(a, k);
  const V3<F> cb = load_p<F>(b, k) - pa;
  const V3<F> ua = load_axis_z<F>(a, k), ub = load_axis_z<F>(b, k);
  const F ra = ld<F>(a.e[0], k), ha = ld<F>(a.e[1], k);
  const F rb = ld<F>(b.e[0], k), hb = ld<F>(b.e[1], k);
  const F zero(0.0f), half(0.5f);
  const V3<F> ca{zero, zero, zero};
  F s, t;
  closest_segment_segment(ca, ua, ha, cb, ub, hb, s, t);
  const V3<F> qa = ua * s;
  const V3<F> qb = madd(cb, t, ub);
  // Fallback normal where the axes meet: ua x ub towards B (or any perpendicular).
  const V3<F> c = cross(ua, ub);
  const F c2 = length_sq(c);
  F cl;
  const V3<F> cu = normalize_or(c, any_perpendicular(ua), cl);
  const V3<F> fb = select(dot(cu, cb) < zero, -cu, cu);
  const V3<F> dq = qb - qa;
  F dist;
  V3<F> n = normalize_or(dq, fb, dist);
  // Within kConeReach of the coordinates' size, dq is moved into the cone of normals both
  // closest points' optimality allows (segment_half_cone: across an axis where its point
  // is inside, outwards at an end): where the cores meet or run parallel and touch, dq
  // is rounding noise in any direction, the axes' included, along which the overlap is
  // far larger. Slack: kNormalConeSlack, and for near-parallel cores |ua x ub| (the
  // parallel rule's s is the overlap's middle, off A's optimum by that). The line across
  // both axes: ua x ub, or across A's axis where ua x ub is rounding noise, made
  // perpendicular to both (Gram-Schmidt: the cross product's rounding, ~1e-7 / |ua x ub|
  // rad, would tilt it along an axis, each core adding its half length times the tilt).
  const auto near = dist < F(kConeReach) * (ha + hb + abs(cb.x) + abs(cb.y) + abs(cb.z));
  if (any(near)) {
    V3<F> base = select(c2 > F(kCrossSq), cu, any_perpendicular(ua));
    base = madd(base, -dot(base, ua), ua);
    base = madd(base, -dot(base, ub), ub);
    F bl;
    const V3<F> ln = normalize_or(base, any_perpendicular(ua), bl);
    const V3<F> fl = select(dot(ln, cb) < zero, -ln, ln);  // towards B
    const F slack = (F(kNormalConeSlack) + select(c2 < F(1e-6f), cl, zero)) * dist;
    const V3<F> mc = project_to_cone(dq, segment_half_cone(ua, s, ha, true), segment_half_cone(ub, t, hb, false),
                                     ln, slack);
    F ml;
    n = select(near, normalize_or(mc, fl, ml), n);
  }
  // Closest points inside both segments: qb - qa is along ua x ub exactly, so take that
  // direction (oriented by qb - qa, or towards B where qb - qa is rounding noise): from
  // qb - qa alone it turns by rounding / |qb - qa| as the cores come to cross.
  {
    const F dc = dot(cu, dq);
    const F noise = F(kEdgeRound) * (ha + hb + abs(cb.x) + abs(cb.y) + abs(cb.z));
    // |ua x ub| > 1e-3: its direction is good to ~1e-4 rad (float rounding / |ua x ub|)
    const auto inner = (abs(s) < ha) & (abs(t) < hb) & (c2 > F(1e-6f));
    const V3<F> nc = select(abs(dc) > noise, select(dc < zero, -cu, cu), fb);
    n = select(inner, nc, n);
    dist = select(inner, abs(dc), dist);
  }
  const F rs = ra + rb;
  const F depth = rs - dist;
  const V3<F> pf = (qa + qb + n * (ra - rb)) * half;

  // Near-parallel: the ends of the overlap of B's projection onto A's axis.
  const F sb = dot(cb, ua), eb = abs(dot(ub, ua)) * hb;
  const F lo = max(-ha, sb - eb), hi = min(ha, sb + eb);
  const auto par = (c2 < F(kParallelSin * kParallelSin)) & (hi - lo > F(1e-4f) * (ha + hb));
  const F sna = dot(n, ua), snb = -dot(n, ub);
  auto end_point = [&](F sa, V3<F>& p, F& d) IMPACT_LAMBDA_INLINE {
    const V3<F> xa = ua * sa;
    const F tb = closest_on_segment(cb, ub, hb, xa);
    const V3<F> xb = madd(cb, tb, ub);
    // the surfaces along n from the two core points
    // B's surface on the same line along n (where it enters B from A's side), so both
    // surface points lie on one line along n even when the axes are not exactly
    // parallel; from B's closest core point where that line misses B.
    const V3<F> on_a = madd(xa, capsule_exit(sa, sna, ra, ha), n);
    typename F::Mask met;
    const F lb = capsule_entry(xa, n, cb, ub, hb, rb, met);
    const V3<F> on_b = select(met, madd(xa, lb, n), madd(xb, -capsule_exit(tb, snb, rb, hb), n));
    d = dot(n, on_a - on_b);
    p = (on_a + on_b) * half;
  };
  V3<F> p0, p1;
  F d0, d1;
  end_point(lo, p0, d0);
  end_point(hi, p1, d1);
  const auto two = par & (d0 > zero) & (d1 > zero);
  L2<F> m;
  finish(m, n, depth, two, p0, d0, p1, d1, pf, depth);
  store(out, k, m, pa);
}

}  // namespace

void collide_capsule_capsule(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, Range r,
                             const NarrowConfig& cfg) {
  IMPACT_LANE_KERNEL_BODY(capsule_capsule_block, 2);
}

}  // namespace impact::kernels
