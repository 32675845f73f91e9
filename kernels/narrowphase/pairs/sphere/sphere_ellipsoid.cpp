// Sphere (A) against ellipsoid (B): the closest point of the ellipsoid's surface to the
// sphere's centre, vectorised across pairs (one lane = one pair), no GJK / EPA.
//
// Inputs: LeafSoA lanes per leaf.h (A a sphere: p, e0 = radius; B an ellipsoid: p, R,
// radii e0, e1, e2 along R's columns), Range r of the bucket.
// Outputs: ManifoldSoA lanes r.begin .. r.end: count (0 or 1), n (unit, A to B), depth,
// point[0] midway between the sphere's deepest point (centre + n r) and the ellipsoid's
// surface point, pdepth[0] = depth. Slots 1..3 untouched; count 0 lanes leave the
// other fields unspecified.
// Depth is the minimum translation distance: outside, r - dist(centre, ellipsoid);
// centre inside, r + the distance from the centre to the nearest surface point, with n
// minus the outward surface normal there (B moves along n, as for sphere-box and
// sphere-cylinder). Centre at the ellipsoid's centre: the nearest point is on the
// smallest axis (lowest axis index among equal smallest radii), on its + side.
// Method, in the ellipsoid's frame relative to the sphere centre (poses far from the
// origin keep their precision), scaled by the largest radius (a_i = e_i / e_max in
// (0, 1], z_i = |local centre_i| / e_max; signs restored at the end): the closest
// point is x_i = a_i^2 z_i / (s + d_i), d_i = a_i^2 - a_m^2 >= 0 (m: the smallest axis),
// where s > 0 is the root of the secular equation sum_i q_i^2 = 1, q_i = a_i z_i /
// (s + d_i) (the Lagrange condition; Eberly, "Distance from a Point to an Ellipse, an
// Ellipsoid, or a Hyperellipsoid", Geometric Tools, 2013, who writes t = s - a_m^2: t > 0
// outside, t in (-a_m^2, 0) inside). psi(s) = 1/|q(s)| - 1 is increasing and concave for
// s > 0 (Cauchy-Schwarz on its derivatives; Newton on 1/|q| is the usual choice for this
// secular function in trust-region steps: More and Sorensen, "Computing a trust region
// step", SIAM J. Sci. Stat. Comput. 4(3), 1983), so a Newton step from any point lands at
// or below the root. The solve (ellip::closest_on_ellipsoid in ellipsoid_solve.h, shared
// with the capsule- and triangle-ellipsoid kernels) is a fixed number (kIterations) of
// safeguarded steps, the same for every lane:
//  - a certified lower bound lo (start: max_i (a_i z_i - d_i) and |a z| - max d_i, the
//    roots of one-term and all-terms minorants), raised by the Newton step on psi and
//    by the Newton step on the same function without the smallest axis's term (whose
//    root is below the full root; it is the fast one when that term is negligible);
//  - an upper bound hi (|a z|, then any evaluated point with |q| <= 1);
//  - the next point is lo, except where one term dominates psi's derivative (its pole
//    -d_p is near): there Newton on that term's q_p = v instead (s + d_p = a_p z_p / v),
//    which is exact when the other terms are constant, taken only inside (lo, hi).
//    Newton on psi alone crawls there (about x1.5 per step between a pole at 0 and a
//    root far from it: centres near a principal plane, near a rim or a tip).
// Degenerate cases: the components of an inside centre below kSnap (1e-6 e_max) are
// solved as 0 (the distance to a set is 1-Lipschitz, so the depth moves by at most
// 1e-6 e_max; it is measured from the exact centre; the normal keeps the centre's
// side). A centre on the smallest axis's principal plane whose root is at s = 0
// (Eberly's special case: an inside point whose nearest point is off that plane; also
// the ellipsoid's centre) has x_i = a_i^2 z_i / d_i on the other axes and x_m = a_m
// sqrt(1 - sum_{i != m} (x_i / a_i)^2) from the surface equation. The normal is the
// surface gradient x_i / a_i^2 (= z_i / (s + d_i)), accurate even where x - centre is
// tiny or cancels; the depth uses |centre - x|. Inside is sum (local_i / e_i)^2 < 1.
// Iterations, measured in a float model of this solve against a converged double one on
// 600k adversarial points (radius ratios to 1e4, components down to 1e-30, centres at
// the evolute of a principal section): the distance reaches the float rounding floor
// with 8 (7: up to 3e-5 e_max, 6: 1e-4); a normal can need one more (a centre just
// outside a pancake's rim: 1.2e-3 rad off with 8); 10 for margin.
// Precision (tests/kernels/narrowphase/sphere_ellipsoid_test.cpp, 400k lanes): depth
// within 8e-7 of max(e_max, r), normals within 3e-6 rad on random poses and 6e-4 rad at
// worst (needles' interior points whose thin component was solved as 0), where the
// nearest point is well conditioned.
// Preconditions: finite inputs, positive sizes, orthonormal R (host-validated); no
// division without a guard, so finite inputs give finite outputs.
// Cost: per lane at most 11 evaluations of the secular function (3 divisions) and 10 x
// (2 square roots, 3 divisions) for the steps; the solve stops once every lane of the
// block sits at a fixed point of its step (each lane frozen at its own; measured: the
// same bytes as running all 10); no branch on lane data (selects), no libm call; a block whose
// lanes are all farther than r + e_max from the ellipsoid stops early.
// Measured per pair in docs/results.md ("Narrow phase").
// Both paths run the same template (F = FloatW, or Float1 for the scalar reference).
#include <cfloat>
#include <cstdint>

#include "kernels/narrowphase/solvers/ellipsoid_solve.h"
#include "kernels/narrowphase/pair_kernels.h"
#include "kernels/narrowphase/lanes/block_driver.h"
#include "kernels/narrowphase/lanes/lane_geometry.h"
#include "kernels/narrowphase/lanes/lane_io.h"

namespace impact::kernels {
namespace {

using namespace prim;  // NOLINT: lane helpers of this kernel family
using simd::dot;
using simd::length_sq;

template <class F>
IMPACT_INLINE void sphere_ellipsoid_block(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out,
                                          uint32_t k) {
  const F zero(0.0f), one(1.0f);
  const V3<F> pa = load_p<F>(a, k);
  const V3<F> cb = load_p<F>(b, k) - pa;
  const F ra = ld<F>(a.e[0], k);
  const V3<F> e = load_e<F>(b, k);
  const F emax = max(max(e.x, e.y), e.z);
  // Every lane farther than r + e_max from the ellipsoid's centre: no contact.
  const F reach = ra + emax;
  if (simd::none(length_sq(cb) < reach * reach)) {
    store_no_contact<F>(out, k);
    return;
  }
  const M3<F> rot = load_r<F>(b, k);
  // Sphere centre in the ellipsoid frame, scaled by the largest radius.
  const V3<F> dl = rot.apply_t(-cb);
  const F inv = one / emax;
  const F dls[3] = {dl.x, dl.y, dl.z};
  const F es[3] = {e.x, e.y, e.z};
  F av[3], zv[3], x[3], g[3];
  F level = zero;  // sum (local_i / e_i)^2: < 1 inside
  for (int i = 0; i < 3; ++i) {
    av[i] = es[i] * inv;
    zv[i] = abs(dls[i]) * inv;
    const F u = dls[i] / es[i];
    level += u * u;
  }
  const auto inside = level < one;
  ellip::closest_on_ellipsoid(av, zv, inside, x, g);
  // Signs back; the distance from the exact (unsnapped) centre.
  F dist2 = zero, xs[3], gs[3];
  for (int i = 0; i < 3; ++i) {
    const F sg = simd::sign_nonneg(dls[i]);
    const F diff = zv[i] - x[i];
    dist2 += diff * diff;
    xs[i] = sg * x[i] * emax;
    gs[i] = sg * g[i];
  }
  const F dist = sqrt(dist2) * emax;
  const F depth = select(inside, ra + dist, ra - dist);
  // n = minus the outward normal at x, inside and outside. g never vanishes for x on
  // the surface; the fallback (minus the smallest axis) only guards the normalisation.
  const auto m0 = (e.x <= e.y) & (e.x <= e.z);
  const auto m1 = andnot(e.y <= e.z, m0);
  const V3<F> fallback{select(m0, -one, zero), select(m1, -one, zero), select(m0 | m1, zero, -one)};
  F glen;
  const V3<F> n = rot.apply(normalize_or(V3<F>{-gs[0], -gs[1], -gs[2]}, fallback, glen));
  const V3<F> xl{xs[0], xs[1], xs[2]};
  const V3<F> on_b = cb + rot.apply(xl);
  Lanes<F, 1> m;
  m.count = simd::to_int(depth > zero);
  m.n = n;
  m.depth = depth;
  m.point[0] = (n * ra + on_b) * F(0.5f);
  m.pdepth[0] = depth;
  store(out, k, m, pa);
}

}  // namespace

void collide_sphere_ellipsoid(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, Range r,
                              const NarrowConfig& cfg) {
  IMPACT_LANE_KERNEL_BODY(sphere_ellipsoid_block, 1);
}

}  // namespace impact::kernels
