// Capsule (A) against cylinder (B): exact collision data of 1 or 2 points per pair,
// vectorised across pairs (one lane = one pair), no GJK / EPA.
//
// Inputs: LeafSoA lanes per leaf.h (A a capsule: p, R column 2 = unit axis, e0 = radius
// r, e1 = half length hs of the core segment S; B a cylinder C: p, R column 2 = unit
// axis, e0 = radius rc, e1 = half length h, flat caps with sharp rims), Range r of the
// bucket. Outputs: ManifoldSoA lanes r.begin .. r.end: count (0, 1 or 2), n (unit, A
// to B), depth, point slots 0 and 1 midway between the surfaces with their depths along
// n; count-0 lanes leave the other fields unspecified (slots 2, 3 are never written).
//
// Method, in the cylinder's frame relative to its centre (c = core centre, u = core axis):
// with o(n) = h_S(n) + h_C(-n) = n.c + hs |n.u| + h |n_z| + rc |n_xy| (the support
// function of the Minkowski difference M = S - C), min over unit n of o is minus the
// distance of S and C when they are apart and the depth of S in C when they meet; the
// capsule's depth is r + min o and the minimiser is the normal (Minkowski's theorem;
// the same quantity tests/support/narrow_reference.h minimises by sampling). Every
// candidate direction gives an upper bound o(n) >= min o, so the answer is the least
// o over a candidate set that is sure to hold the minimiser. Where n* = argmin lies on
// M's boundary fixes the set:
//  - n* = +-z (a cap disk swept by an end): the two cap normals;
//  - n* horizontal (an end or the core against the side): then n* also minimises o over
//    the horizontal circle, where o = h_{S_xy}(n) + rc: the direction from the core's
//    point nearest the axis in the xy plane (2D segment vs point) towards the axis,
//    and, where that point is the foot of the perpendicular, +-w, w = z x u / |z x u|
//    (the core crossing the axis in projection, where the first is undefined);
//  - n* perpendicular to u (the core's interior against a rim): then n* minimises o over
//    the great circle n.u = 0, where o is the support function of C's shadow along u
//    (an ellipse of semi-axes rc along w and rc|u_z| along v = u x w, swept by 2 h |u_xy|
//    along v) seen from the core's shadow point: a 2D signed distance to that stadium.
//    Its minimiser is +-w (the flat sides) or the one local minimum of the distance on
//    each half ellipse (one per rim). Of a half ellipse seen from a point on its own
//    side that is the nearest point; from the far side (a core lying across the cap,
//    inside the cylinder) it is the second local minimum, which exists inside the
//    ellipse's evolute. Both are roots of Eberly's secular equation for the point
//    (t > -b^2: nearest; t in (-a^2, -b^2), the root next to -b^2: the far-side minimum),
//    written with tau = |t + b^2| as 1/|q(tau)| = 1, q = (a X / (a^2 - b^2 +- tau),
//    b |Y| / tau), whose left side is concave in tau on either range (Cauchy-Schwarz, as
//    in sphere_ellipsoid.cpp): kArcIterations Newton steps from a certified lower bound
//    (Newton on a concave function lands at or below the root), a certified upper
//    bound from any evaluated point, and a pole step on the b|Y|/tau term where it
//    dominates (Newton crawls there: points near the evolute's cusps): the shared
//    solve of rim_solve.h, both rims in one loop;
//  - otherwise n* meets a rim at a core end (M's edge: an end point plus a rim circle):
//    the nearest point of that circle, n along it with the sign its normal cone allows
//    (4 candidates: 2 ends x 2 rims).
// Those are all of M's boundary pieces (a core end's normal cone is a half sphere, the
// interior's the great circle n.u = 0; the cylinder's are the cap normals, the
// horizontal circle and the quarter arcs between them at the rims), so the least o is
// exact up to float rounding whatever the configuration, apart or meeting: no case split
// on overlap. A rim or end candidate whose witness lies off its piece (the core point
// beyond the core's ends; the end's normal cone, or the end - rim point offset, not
// along n) is dropped: it is no minimiser, and near the minimum, where o is flat, it
// could tie the true one within rounding with a direction 1e-4 rad off.
// Ties keep the first candidate in the order caps, sides, rims, ends.
// Contact points: the core point t of the winning candidate, moved along n by (r - o)/2
// (midway between the capsule's surface and the cylinder's, which lies at -o along n
// from the core point). Two points where n is within kParallelSin of a cap normal and
// the core within kParallelSin of the cap's plane (or the core meets the cylinder): the
// core clipped to the cap disk; or where n is within kParallelSin of the horizontal
// plane and the core of the axis: the core clipped to the side's height. Each end has
// its own depth along n (the capsule's surface, capsule_exit, against where the line
// enters the cylinder), and both are kept when both are positive.
// Preconditions: finite inputs, positive radii and half lengths (hs >= 0), unit axes,
// orthonormal R. Degenerate input: a zero-length core is a sphere (its candidates
// reduce to point-cylinder); a core along the axis takes w = R's x axis; an end on the
// axis takes its rim direction along the core's own horizontal direction. Coincident
// centres give a finite unit normal (the ties above decide it).
// Cost: 11 candidate directions, each o(n) in closed form, and two 2D root solves of
// kArcIterations steps (3 divisions, 2 square roots each); no branch on lane data
// (selects) except a block whose lanes are all farther apart than their bounding
// spheres. Measured per pair in docs/results.md ("Narrow phase").
// Both paths run the same template (F = FloatW, or Float1 for the scalar reference).
// References: Minkowski-difference support functions for penetration depth (van den
// Bergen, Collision Detection in Interactive 3D Environments, 2003, ch. 4); the
// secular equation of the point-ellipse distance (Eberly, "Distance from a Point to an
// Ellipse, an Ellipsoid, or a Hyperellipsoid", Geometric Tools, 2013).
#include <cstdint>

#include "kernels/narrowphase/pair_kernels.h"
#include "kernels/narrowphase/lanes/block_driver.h"
#include "kernels/narrowphase/lanes/lane_geometry.h"
#include "kernels/narrowphase/lanes/lane_io.h"
#include "kernels/narrowphase/solvers/rim_solve.h"

// No FMA contraction in this file (see no_contract.h).
#include "kernels/narrowphase/lanes/no_contract.h"  // last: its pragma covers what follows

namespace impact::kernels {
namespace {

using namespace prim;  // NOLINT: lane helpers of this kernel family
using simd::cross;
using simd::dot;
using simd::length_sq;

/// |sin| between the core and the cap plane / the axis below which a cap / side
/// contact is a 2-point manifold (as for capsule-capsule, -box and -triangle).
constexpr float kParallelSin = 0.05f;
/// Candidate classes (for the manifold).
constexpr float kClassCap = 0.0f, kClassSide = 1.0f, kClassOther = 2.0f;

/// o(n) = h_S(n) + h_C(-n) for unit n, in the cylinder frame.
template <class F>
IMPACT_INLINE F overlap(const V3<F>& n, const V3<F>& c, const V3<F>& u, F hs, F rc, F h) {
  return dot(n, c) + hs * abs(dot(n, u)) + h * abs(n.z) + rc * sqrt(n.x * n.x + n.y * n.y);
}

/// The least-so-far candidate: o, its normal, the core parameter of its witness, class.
template <class F>
struct Best {
  F o;
  V3<F> n;
  F t;
  F cls;
  IMPACT_INLINE void take(F o2, const V3<F>& n2, F t2, float cls2) {
    const auto m = o2 < o;
    o = select(m, o2, o);
    n = select(m, n2, n);
    t = select(m, t2, t);
    cls = select(m, F(cls2), cls);
  }
};

template <class F>
IMPACT_INLINE void capsule_cylinder_block(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out,
                                          uint32_t k) {
  using Mask = typename F::Mask;
  using Int = typename F::Int;
  const F zero(0.0f), one(1.0f), half(0.5f), tiny(kTinySq);
  const V3<F> pa = load_p<F>(a, k);
  const V3<F> cb = load_p<F>(b, k) - pa;
  const F r = ld<F>(a.e[0], k), hs = ld<F>(a.e[1], k);
  const F rc = ld<F>(b.e[0], k), h = ld<F>(b.e[1], k);
  // Every lane's bounding spheres apart: no contact.
  const F reach = r + hs + sqrt(rc * rc + h * h);
  if (simd::none(length_sq(cb) < reach * reach)) {
    store_no_contact<F>(out, k);
    return;
  }
  const M3<F> rot = load_r<F>(b, k);
  const V3<F> c = rot.apply_t(-cb);                   // core centre, cylinder frame
  const V3<F> u = rot.apply_t(load_axis_z<F>(a, k));  // core axis, cylinder frame

  // Horizontal directions: w = z x u / |z x u| (x for a core along the axis) and the
  // core's own horizontal direction m = w turned by -90 degrees.
  const F uxy2 = u.x * u.x + u.y * u.y;
  const Mask tilted = uxy2 > tiny;
  const F inv_uxy = one / sqrt(select(tilted, uxy2, one));
  const F wx = select(tilted, -u.y * inv_uxy, one), wy = select(tilted, u.x * inv_uxy, zero);
  const F mx = wy, my = -wx;
  const F never(3.0e38f);                    // o of a dropped candidate
  const F slack = F(1e-6f) * (hs + rc + h);  // rounding allowance of a witness test

  Best<F> best;
  // --- caps: n = +-z; the witness is the core end that reaches furthest along n ---
  {
    const F ext = mul_add(hs, abs(u.z), h);
    const F t_up = hs * simd::sign_nonneg(u.z);
    best.o = c.z + ext;
    best.n = V3<F>{zero, zero, one};
    best.t = t_up;
    best.cls = F(kClassCap);
    best.take(ext - c.z, V3<F>{zero, zero, F(-1.0f)}, -t_up, kClassCap);
  }
  // --- side: the direction from the core's point nearest the axis (xy) towards it, and
  // +-w where that point is the foot of the perpendicular (only there can +-w be the
  // minimiser: elsewhere the 2D closest point is an end, not along w; and w, from u's
  // horizontal part, loses its precision for a core nearly along the axis) ---
  const F cu = c.x * u.x + c.y * u.y;
  const F t_free = select(tilted, -cu / select(tilted, uxy2, one), zero);
  const F t_axis = clamp(t_free, -hs, hs);
  {
    auto side_o = [&](F nx, F ny) { return mul_add(hs, abs(nx * u.x + ny * u.y), nx * c.x + ny * c.y) + rc; };
    const F qx = mul_add(t_axis, u.x, c.x), qy = mul_add(t_axis, u.y, c.y);
    const F q2 = qx * qx + qy * qy;
    const Mask off = q2 > tiny;
    const F qi = one / sqrt(select(off, q2, one));
    const F nx = select(off, -qx * qi, wx), ny = select(off, -qy * qi, wy);
    best.take(side_o(nx, ny), V3<F>{nx, ny, zero}, t_axis, kClassSide);
    const Mask foot = abs(t_free) <= hs;
    best.take(select(foot, side_o(wx, wy), never), V3<F>{wx, wy, zero}, t_axis, kClassSide);
    best.take(select(foot, side_o(-wx, -wy), never), V3<F>{-wx, -wy, zero}, t_axis, kClassSide);
  }
  // --- rims against the core's interior: n perpendicular to u (half ellipses) ---
  {
    rim::CoreRims<F> cr;
    F rb[2], rx[2], ry[2], ex[2], ey[2], tw[2];
    cr.setup(c, u, rc, h, rb, rx, ry);
    rim::half_ellipse_normals(rb, rx, ry, ex, ey);
    V3<F> nr[2], pc[2];
    Mask on_core[2];
    cr.finish(c, u, hs, rc, h, slack, ex, ey, nr, pc, tw, on_core);
    // a witness beyond the core's ends (by more than rounding) is no point of this piece,
    // and such a candidate is dropped: near the minimum o is flat, and an invalid
    // direction whose o ties the minimum within rounding would win half the time
    for (int i = 0; i < 2; ++i)
      best.take(select(on_core[i], overlap(nr[i], c, u, hs, rc, h), never), nr[i], clamp(tw[i], -hs, hs),
                kClassOther);
  }
  // --- a core end against a rim circle: its nearest point, n with the allowed sign ---
  for (int e = 0; e < 2; ++e) {
    const F se(e == 0 ? 1.0f : -1.0f);
    const V3<F> x = madd(c, se * hs, u);
    const F rho2 = x.x * x.x + x.y * x.y;
    const Mask off = rho2 > tiny;
    const F rho = sqrt(rho2);
    const F ri = one / select(off, rho, one);
    // towards the axis; an end on it: along the core's horizontal direction, outwards
    const F dx = select(off, -x.x * ri, se * mx), dy = select(off, -x.y * ri, se * my);
    const F radial = abs(rc - rho);
    for (int s = 0; s < 2; ++s) {
      const F sg(s == 0 ? 1.0f : -1.0f);
      const F vert = sg * abs(mul_add(sg, x.z, h));
      F len;
      const V3<F> n = normalize_or(V3<F>{radial * dx, radial * dy, vert},
                                   V3<F>{dx * F(0.70710678f), dy * F(0.70710678f), sg * F(0.70710678f)}, len);
      // a critical point only where n is in the end's normal cone and along +-(end - rim
      // point): rc - rho and h + sg x_z of one sign (else dropped, as above)
      const Mask valid = (se * dot(n, u) >= F(-1e-6f)) & ((rc - rho) * mul_add(sg, x.z, h) >= -slack * slack);
      best.take(select(valid, overlap(n, c, u, hs, rc, h), never), n, se * hs, kClassOther);
    }
  }

  const F o = best.o;
  const V3<F> n = best.n;
  const F depth = r + o;
  const Mask is_cap = best.cls == F(kClassCap), is_side = best.cls == F(kClassSide);
  // Two points where n is within kParallelSin of a cap normal with the core level or
  // inside, or of the horizontal with the core along the axis: the core clipped where
  // its points, moved along n, meet the face (capsule-box's rule): the cap plane z = -s h
  // (s = sign n_z) inside the disk, a line in t; or the side within |z| <= h, the line's
  // height there taken as the witness's (x_z - o n_z). For n = +-z (horizontal n), the
  // cap (side) witnesses', that is the core clipped to the disk (the side's height).
  const F nxy2 = n.x * n.x + n.y * n.y;
  const F par2 = F(kParallelSin * kParallelSin);
  const Mask cap_like = (nxy2 < par2) & ((abs(u.z) < F(kParallelSin)) | (o > zero));
  const Mask side_like = andnot((n.z * n.z < par2) & (uxy2 < par2), cap_like);
  const F s_cap = simd::sign_nonneg(n.z);
  const F nz = select(abs(n.z) > half, n.z, one);
  F cl_lo, cl_hi, sd_lo, sd_hi;
  Mask cl_ok, sd_ok;
  {
    const F l0 = (-s_cap * h - c.z) / nz, l1 = -u.z / nz;  // x(t) + (l0 + l1 t) n on the plane
    const F csx = mul_add(l0, n.x, c.x), csy = mul_add(l0, n.y, c.y);
    const F usx = mul_add(l1, n.x, u.x), usy = mul_add(l1, n.y, u.y);
    const F qa = usx * usx + usy * usy, qb = csx * usx + csy * usy;
    const F qc = csx * csx + csy * csy - rc * rc;
    const F disc = qb * qb - qa * qc;
    const F root = sqrt(max(disc, zero));
    const Mask moving = qa > tiny;
    const F ia = one / select(moving, qa, one);
    cl_lo = max(select(moving, (-qb - root) * ia, -hs), -hs);
    cl_hi = min(select(moving, (root - qb) * ia, hs), hs);
    cl_ok = select(moving, disc >= zero, qc <= zero) & (cl_lo <= cl_hi);
    const F cz = c.z - o * n.z;
    const Mask level = abs(u.z) < tiny;
    const F iz = one / select(level, one, u.z);
    const F ta = (-h - cz) * iz, tb = (h - cz) * iz;
    sd_lo = select(level, -hs, max(min(ta, tb), -hs));
    sd_hi = select(level, hs, min(max(ta, tb), hs));
    sd_ok = select(level, abs(cz) <= h, Mask(true)) & (sd_lo <= sd_hi);
  }
  // One point: the witness (a cap / side witness moved into the clipped core, for a
  // core level with the cap or along the axis whose ends tie).
  F t = best.t;
  t = select(is_cap & cl_ok, clamp(t, cl_lo, cl_hi), t);
  t = select(is_side & sd_ok, clamp(t, sd_lo, sd_hi), t);
  const V3<F> pf = madd(madd(c, t, u), half * (r - o), n);
  // The clipped ends, each with its own depth along n: the capsule's surface
  // (capsule_exit) against the cap plane / where the line enters the side (a line that
  // misses the side beyond rounding: no second point).
  const F snu = dot(n, u);
  const F ia = one / select(side_like, nxy2, one);
  // A side end whose line enters the infinite cylinder beyond the cap's height (a tilted
  // n: the entry is not where the witness's is) moves along the core until it does not
  // (the height changes by u_z per unit t, to first order).
  auto side_end = [&](F te) {
    const V3<F> x = madd(c, te, u);
    const F bh = x.x * n.x + x.y * n.y, ch = x.x * x.x + x.y * x.y - rc * rc;
    const F lam = (-bh - sqrt(max(bh * bh - nxy2 * ch, zero))) * ia;
    const F ze = mul_add(lam, n.z, x.z);
    const F excess = select(ze > h, ze - h, select(ze < -h, ze + h, zero));
    return clamp(te - excess / select(abs(u.z) > half, u.z, one), sd_lo, sd_hi);
  };
  const F t0 = select(cap_like, cl_lo, side_end(sd_lo)), t1 = select(cap_like, cl_hi, side_end(sd_hi));
  auto end_point = [&](F te, V3<F>& p, F& d) {
    const V3<F> x = madd(c, te, u);
    const F l = capsule_exit(te, snu, r, hs);
    const F lam_cap = (-s_cap * h - x.z) / nz;
    const F bh = x.x * n.x + x.y * n.y, ch = x.x * x.x + x.y * x.y - rc * rc;
    const F disc = bh * bh - nxy2 * ch;
    // side: where the line enters the infinite cylinder, if that is within the side's
    // height (up to rounding); else where it then enters the slab through the cap it is
    // heading for; a line that misses (beyond rounding): no point
    const F root = sqrt(max(disc, zero));
    const F side_in = (-bh - root) * ia, side_out = (root - bh) * ia;
    const F ze = mul_add(side_in, n.z, x.z);
    const F zlim = h + F(1e-6f) * (h + abs(x.z));
    const Mask above = ze > zlim, below = ze < -zlim;
    const F lz = (select(above, h, -h) - x.z) / select(abs(n.z) > tiny, n.z, one);
    const Mask via_cap = ((above & (n.z < zero)) | (below & (n.z > zero))) & (lz <= side_out);
    const Mask met = disc >= F(-1e-5f) * nxy2 * rc * rc;
    const F big(3.0e38f);
    const F lam_side = select(met, select(above | below, select(via_cap, lz, big), side_in), big);
    const F lam = select(cap_like, lam_cap, lam_side);
    d = l - lam;
    p = madd(x, half * (l + lam), n);
  };
  V3<F> p0, p1;
  F d0, d1;
  end_point(t0, p0, d0);
  end_point(t1, p1, d1);
  const Mask cap_two = cap_like & cl_ok & (cl_hi - cl_lo > F(1e-4f) * (hs + rc));
  const Mask side_two = side_like & sd_ok & (sd_hi - sd_lo > F(1e-4f) * (hs + h));
  const Mask hit = depth > zero;
  const Mask two = (cap_two | side_two) & (d0 > zero) & (d1 > zero) & hit;

  Lanes<F, 2> m;
  m.count = select(hit, select(two, Int(2), Int(1)), Int(0));
  m.n = rot.apply(n);
  m.depth = depth;
  // The deepest point carries the depth: where both clipped ends miss it by more than
  // 1e-5 of (depth + the pair's size) (the core's ends cut short of where the minimum
  // is reached, as with coincident centres), the witness takes the shallower end's slot.
  const F miss = F(1e-5f) * (depth + r + hs + rc + h);
  const Mask short0 = two & (max(d0, d1) < depth - miss) & (d0 <= d1);
  const Mask short1 = andnot(two & (max(d0, d1) < depth - miss), short0);
  m.point[0] = cb + rot.apply(select(two & ~short0, p0, pf));
  m.pdepth[0] = select(two & ~short0, min(d0, depth), depth);
  m.point[1] = cb + rot.apply(select(two & ~short1, p1, pf));  // (slot 1 of a 1-point lane: finite filler)
  m.pdepth[1] = select(two & ~short1, min(d1, depth), depth);
  store(out, k, m, pa);
}

}  // namespace

void collide_capsule_cylinder(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, Range r,
                              const NarrowConfig& cfg) {
  IMPACT_LANE_KERNEL_BODY(capsule_cylinder_block, 2);
}

}  // namespace impact::kernels
