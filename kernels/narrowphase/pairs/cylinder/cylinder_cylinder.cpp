// Cylinder (A) against cylinder (B): exact collision data of 1 to 4 points per pair,
// vectorised across pairs (one lane = one pair), no GJK / EPA.
//
// Inputs: LeafSoA lanes per leaf.h (both cylinders: p centre, R column 2 = unit axis, e0 =
// radius, e1 = half length; flat caps with sharp rims), Range r of the bucket. Outputs:
// ManifoldSoA lanes r.begin .. r.end: count (0..4), n (unit, A to B), depth, point slots
// midway between the surfaces with their depths along n; count-0 lanes leave the other
// fields unspecified.
//
// Method, in B's frame relative to its centre (c = A's centre, u its axis, ax / ay its
// other axes; A: radius ra, half length ha; B: rb, hb along z):
//     o(n) = h_A(n) + h_B(-n) = n.c + ha |n.u| + ra |n x u| + hb |n_z| + rb |n_xy|
// is the support function of the Minkowski difference A - B: its minimum over unit n is
// minus the distance when apart and the depth when they meet (no case split), and every
// unit n gives an upper bound, so the answer is the least o over a candidate set sure to
// hold the minimiser (as capsule_cylinder.cpp and box_cylinder.cpp). A cylinder's normal
// sets are its cap normals (points), its side's great circle and its rims' open quarter
// arcs (2-D); one candidate set per piece of A - B (a feature of A summed with one of B
// whose normal sets meet in a 2-D piece):
//  - a cap x anything: n = +-u, +-z (o in closed form);
//  - side x side (two segments): n = +-(u x z) / |u x z|, counted where the axes' closest
//    points lie on both segments;
//  - A's side x B's rims: n on the great circle n.u = 0, where o is the 2-D signed
//    distance from A's axis's shadow to B's shadow along u, whose rims are half ellipses:
//    one local minimum per rim by the fixed-step solve of Eberly's secular equation
//    (rim_solve.h, as capsule-cylinder's core against the rims); B's side x A's rims the
//    same in A's frame; the four solves run as one loop;
//  - rim x rim (a circle of A summed with one of B, 4 pairs): the critical points are the
//    critical points of the distance between the two circles (Eberly, "Distance between
//    two circles in 3D": roots of a degree-8 polynomial). Instead of the polynomial, the
//    distance D from a point of one rim to the other circle (closed form) is minimised
//    over the rim's angle. Its local minima are bracketed from D2 and its derivative at
//    kArcSamples = 16 angles: (1) a step where the derivative turns from falling to
//    rising, started at the root of the step's cubic Hermite interpolant's derivative;
//    (2) a step whose ends have one sign where that interpolant turns inside it (two
//    critical points within a step: seen where D is nearly flat); (3) a sample whose slope
//    is below 1/kStill of its neighbours' (a narrow dip where the rims pass close, or a
//    minimum at the end of a flat stretch next to another one in the same step), the two
//    steps around it. Each bracket (at most kArcSlots) is refined by safeguarded Newton
//    steps (bisection where Newton leaves it). The smaller rim is the one sampled (along
//    the larger, a small rim passing near it makes two minima closer than a step). The
//    refined pair's offset x = pA - pB is perpendicular to both rims' tangents: n = +-x /
//    |x| or +-(tA x tB) / |tA x tB|, whichever the solve's angle error turns less (the
//    cross product where the circles touch and x is rounding noise), with the sign that
//    puts n in A's rim's normal cone and -n in B's.
// A candidate counts as the minimiser only where its witnesses are points of its piece
// (the side pieces' axis points within the heights; a rim pair's normal within both
// rims' cones, kConeSlack); the least o of every candidate, valid or not, is kept too (an
// exact upper bound) and is the answer where it is below the least valid one by more
// than rounding. Ties keep the first in the order caps, sides, side-rims, rim pairs.
// Global minimum: the pieces cover A - B's boundary, so the least o over their critical
// points is exact, up to the rim x rim search, which rests on sampling: a local minimum of
// D that none of the three bracket rules shows is missed (the answer is then another
// candidate's o, an upper bound: a depth too large, a valid separating direction).
// Measured (matrix_test at IMPACT_TEST_INTENSITY=100, cylinder_cylinder_test at 50:
// ~10^4 random lanes at four scales and ~2400 rim pairs built to touch, against dense
// sampling refined in double and a signed-distance gap by nested golden-section search):
// no miss. Without rule (3): 3 built rim pairs of ~2400 missed by up to 2.4e-3 L; with 12
// samples instead of 16: 6; sampling the larger rim, or with rule (1) alone: a random
// lane in ~3000 (up to 4e-3 L).
// Cost: the side-rim solves run only where the caps and sides have not certified a lane
// apart (some o <= 0), listed per chunk of kChunkBlocks blocks and solved W lanes at a
// time (~60% of the bench's lanes); the rim pairs run only where a lane is still not
// certified apart after them and, where it is certified to meet (a centre in the other, a
// point of the axes' closest pair, or either support point along the least o's normal,
// inside the other shape), only where a lower bound of the two circles' distance (from
// either rim's frame) is below the least o; they are listed per chunk and sampled W
// pairs at a time, and their brackets refined W at a time, 4 groups side by side
// (independent Newton chains), each lane frozen once a Newton step moves it by at most
// kArcFreeze (so its bytes do not depend on its neighbours). A bracket none of whose
// points can meet the rims' cone rules (rim_brackets: the signs of the offset's radial
// and axial parts from B's circle and of its part along A's axis, bounded over each step
// from the samples) is not refined (the prune's counts and its mutation check:
// docs/history.md). The `far` guard matters only where rounding makes the offset's
// direction noise.
// Cost: measured per pair in docs/results.md ("Narrow phase").
// Contact points: one, midway between the witnesses. Where n is within kParallelSin of
// both axes (cap on cap): each rim's 8 samples seen along n on the other's cap plane and
// inside its disk, with their gaps, reduced to 4 (reduce4). Where n is within kParallelSin
// of B's axis and of A's side (A lying on B's cap): A's side line along n clipped to B's
// disk (2 ends); likewise B lying on A's cap; where n is within kParallelSin of both sides
// and the axes within it of each other (side by side): A's side line clipped to B's height
// (each end's gap where the line from it along -n leaves B's side). Points with no
// positive gap are dropped; the witness stays only where no other point is as deep.
// Preconditions: finite inputs, positive sizes, unit axes, orthonormal R. Degenerate
// input: parallel axes have no side x side candidate (the side-rim pieces hold the
// minimum); coincident centres give a finite unit normal (the ties above decide it).
// Both paths run the same template (F = FloatW, or Float1 for the scalar reference); a
// lane's arithmetic is the same wherever it is packed, so its bytes do not depend on its
// neighbours.
// References: Minkowski-difference support functions for penetration depth (van den
// Bergen, Collision Detection in Interactive 3D Environments, 2003, ch. 4); the secular
// equation of the point-ellipse distance (Eberly, "Distance from a Point to an Ellipse,
// an Ellipsoid, or a Hyperellipsoid", Geometric Tools, 2013); safeguarded Newton (Press
// et al., Numerical Recipes, rtsafe).
#include <cstdint>
#include <iterator>

#include "kernels/narrowphase/pair_kernels.h"
#include "kernels/narrowphase/lanes/block_driver.h"
#include "kernels/narrowphase/lanes/lane_geometry.h"
#include "kernels/narrowphase/lanes/lane_io.h"
#include "kernels/narrowphase/lanes/live_lanes.h"
#include "kernels/narrowphase/lanes/manifold_reduce.h"
#include "kernels/narrowphase/lanes/witnessed_best.h"
#include "kernels/narrowphase/solvers/rim_solve.h"

// No FMA contraction in this file (see no_contract.h).
#include "kernels/narrowphase/lanes/no_contract.h"  // last: its pragma covers what follows

namespace impact::kernels {
namespace {

using namespace prim;  // NOLINT: lane helpers of this kernel family
using simd::cross;
using simd::dot;
using simd::length_sq;

/// Witness tests accept a critical point within this times the pair's size.
constexpr float kSlackRel = 4e-6f;
/// |n.axis| at or below this: the support feature extends along the axis (a side line),
/// |n x axis| at or below it: across the cap (a disk).
constexpr float kFree = 1e-6f;
/// |sin| between n and an axis (a cap plane) below which the contact is a cap (side)
/// contact with a clipped manifold.
constexpr float kParallelSin = 0.05f;
constexpr float kNever = 3.0e38f;
/// Rim x rim: samples of A's rim angle per rim pair, local minima refined per lane
/// (at most kArcSlots of them), at most kArcSteps safeguarded Newton steps each.
constexpr int kArcSamples = 16;
constexpr float kArcCos[kArcSamples] = {
    1.0f,  0.92387953f,  0.70710678f,  0.38268343f,  0.0f, -0.38268343f, -0.70710678f, -0.92387953f,
    -1.0f, -0.92387953f, -0.70710678f, -0.38268343f, 0.0f, 0.38268343f,  0.70710678f,  0.92387953f};
struct ArcSin {
  float v[kArcSamples];
  constexpr ArcSin() : v() {
    for (int k = 0; k < kArcSamples; ++k) v[k] = kArcCos[(k + 12) % kArcSamples];
  }
};
constexpr ArcSin kArcSin{};
constexpr float kArcStep = 0.39269908f;  // 2 pi / kArcSamples
constexpr int kArcSlots = 6;
/// A sample whose slope is below 1 / kStill of its two neighbours' together brackets
/// the two steps around it.
constexpr float kStill = 8.0f;
constexpr int kArcSteps = 12;
/// A Newton step this short (rad) freezes a lane: the next would move it by ~its square.
constexpr float kArcFreeze = 1e-7f;
/// Blocks per chunk: phase B packs the rim pairs of this many blocks.
constexpr uint32_t kChunkBlocks = 16;
/// Rim pair p: A's rim tau, B's rim s.
constexpr float kPairTau[4] = {1.0f, -1.0f, 1.0f, -1.0f};
constexpr float kPairS[4] = {1.0f, 1.0f, -1.0f, -1.0f};
/// A rim x rim point counts where its normal lies in both rims' normal cones within
/// this (rad, about).
constexpr float kConeSlack = 1e-4f;

/// One lane's pair in B's frame, relative to B's centre.
template <class F>
struct Geo {
  V3<F> c;           // A's centre
  V3<F> ax, ay, u;   // A's axes (u: its cylinder axis)
  F ra, ha, rb, hb;  // radii and half lengths
};

/// o(n) = h_A(n) + h_B(-n): the support function of A - B along unit n.
template <class F>
IMPACT_INLINE F score(const Geo<F>& g, const V3<F>& n) {
  const F na = dot(n, g.ax), nb = dot(n, g.ay);
  return dot(n, g.c) + g.ha * abs(dot(n, g.u)) + g.ra * sqrt(na * na + nb * nb) + g.hb * abs(n.z) +
         g.rb * sqrt(n.x * n.x + n.y * n.y);
}

template <class F>
IMPACT_INLINE F pair_slack(const Geo<F>& g) {
  return F(kSlackRel) * (g.ra + g.ha + g.rb + g.hb);
}

/// A's support point along n; a tie (a side line, a cap disk) takes its point nearest B's
/// centre line (the z axis) or centre.
template <class F>
IMPACT_INLINE V3<F> support_a(const Geo<F>& g, const V3<F>& n) {
  const F zero(0.0f), one(1.0f), free(kFree);
  const F nu = dot(n, g.u), na = dot(n, g.ax), nb = dot(n, g.ay);
  const F t = select(abs(nu) > free, g.ha * simd::sign_nonneg(nu), clamp(-dot(g.c, g.u), -g.ha, g.ha));
  const F r2 = na * na + nb * nb;
  const auto radial = r2 > free * free;
  // tie: B's centre seen in A's cap plane, clamped to the disk
  const F qa = -dot(g.c, g.ax), qb = -dot(g.c, g.ay);
  const F q2 = qa * qa + qb * qb;
  const F qs = select(q2 > g.ra * g.ra, g.ra / sqrt(select(q2 > zero, q2, one)), one);
  const F inv = g.ra / sqrt(select(radial, r2, one));
  const F ca = select(radial, na * inv, qa * qs), cb = select(radial, nb * inv, qb * qs);
  return madd(madd(madd(g.c, t, g.u), ca, g.ax), cb, g.ay);
}

/// B's support point along -n; a tie takes its point nearest A's centre.
template <class F>
IMPACT_INLINE V3<F> support_b(const Geo<F>& g, const V3<F>& n) {
  const F zero(0.0f), one(1.0f), free(kFree);
  const F z = select(abs(n.z) > free, -g.hb * simd::sign_nonneg(n.z), clamp(g.c.z, -g.hb, g.hb));
  const F r2 = n.x * n.x + n.y * n.y;
  const auto radial = r2 > free * free;
  const F q2 = g.c.x * g.c.x + g.c.y * g.c.y;
  const F qs = select(q2 > g.rb * g.rb, g.rb / sqrt(select(q2 > zero, q2, one)), one);
  const F inv = -g.rb / sqrt(select(radial, r2, one));
  return {select(radial, n.x * inv, g.c.x * qs), select(radial, n.y * inv, g.c.y * qs), z};
}

/// p inside B / inside A (closed).
template <class F>
IMPACT_INLINE typename F::Mask in_b(const Geo<F>& g, const V3<F>& p) {
  return (abs(p.z) <= g.hb) & (p.x * p.x + p.y * p.y <= g.rb * g.rb);
}
template <class F>
IMPACT_INLINE typename F::Mask in_a(const Geo<F>& g, const V3<F>& p) {
  const V3<F> q = p - g.c;
  const F qa = dot(q, g.ax), qb = dot(q, g.ay);
  return (abs(dot(q, g.u)) <= g.ha) & (qa * qa + qb * qb <= g.ra * g.ra);
}

/// o, normal, A's witness point x (B's is x - o n) of the least (valid) candidate.
template <class F>
using Best = WitnessedBest<F>;

/// cos and sin of |d| <= 2 kArcStep (Taylor to degree 9 / 10: error below 1e-9).
template <class F>
IMPACT_INLINE void cos_sin_small(F d, F& cd, F& sd) {
  const F d2 = d * d;
  cd =
      F(1.0f) + d2 * (F(-0.5f) + d2 * (F(1.0f / 24.0f) + d2 * (F(-1.0f / 720.0f) + d2 * F(1.0f / 40320.0f))));
  sd = d * (F(1.0f) + d2 * (F(-1.0f / 6.0f) +
                            d2 * (F(1.0f / 120.0f) + d2 * (F(-1.0f / 5040.0f) + d2 * F(1.0f / 362880.0f)))));
}

/// The pair seen from B (swap = false) or from A (swap = true, roles exchanged): the rim x
/// rim solves sample the smaller rim, whose distance to the other circle varies slowly
/// along it (sampling the larger one, two minima can lie closer than a sample step
/// where a small rim passes near it).
template <class F>
IMPACT_INLINE Geo<F> swapped(const Geo<F>& g) {
  Geo<F> s;
  s.c = V3<F>{-dot(g.c, g.ax), -dot(g.c, g.ay), -dot(g.c, g.u)};
  s.ax = V3<F>{g.ax.x, g.ay.x, g.u.x};
  s.ay = V3<F>{g.ax.y, g.ay.y, g.u.y};
  s.u = V3<F>{g.ax.z, g.ay.z, g.u.z};
  s.ra = g.rb, s.ha = g.hb, s.rb = g.ra, s.hb = g.ha;
  return s;
}
template <class F>
IMPACT_INLINE Geo<F> select_geo(typename F::Mask m, const Geo<F>& a, const Geo<F>& b) {
  Geo<F> r;
  r.c = select(m, a.c, b.c), r.ax = select(m, a.ax, b.ax), r.ay = select(m, a.ay, b.ay),
  r.u = select(m, a.u, b.u);
  r.ra = select(m, a.ra, b.ra), r.ha = select(m, a.ha, b.ha), r.rb = select(m, a.rb, b.rb),
  r.hb = select(m, a.hb, b.hb);
  return r;
}

/// A lower bound of the distance of A's rim at tau and B's rim at s, the larger of two,
/// one from each rim's frame: a rim spans r |sin| of the axes' angle across the other's
/// plane and moves its points by at most r from the other's axis.
template <class F>
IMPACT_INLINE F rim_pair_bound(const Geo<F>& g, F tau, F s) {
  const F zero(0.0f);
  const V3<F> ca = madd(g.c, tau * g.ha, g.u);
  const V3<F> d{-ca.x, -ca.y, s * g.hb - ca.z};  // A's rim centre to B's
  const F uxy = sqrt(g.u.x * g.u.x + g.u.y * g.u.y);
  const F dz = max(abs(d.z) - g.ra * uxy, zero);
  const F rho = sqrt(d.x * d.x + d.y * d.y);
  const F dr = max(max(rho - g.ra - g.rb, g.rb - rho - g.ra), zero);
  const F du = dot(d, g.u);
  const F dz2 = max(abs(du) - g.rb * uxy, zero);
  const F rho2 = sqrt(max(length_sq(d) - du * du, zero));
  const F dr2 = max(max(rho2 - g.ra - g.rb, g.ra - rho2 - g.rb), zero);
  return sqrt(max(dz * dz + dr * dr, dz2 * dz2 + dr2 * dr2));
}

/// A Geo from its 16 fields by index (the chunk's geo rows): c, ax, ay, u, ra, ha, rb, hb.
template <class F, class Get>
IMPACT_INLINE Geo<F> read_geo(const Get& get) {
  Geo<F> g;
  g.c = V3<F>{get(0), get(1), get(2)};
  g.ax = V3<F>{get(3), get(4), get(5)};
  g.ay = V3<F>{get(6), get(7), get(8)};
  g.u = V3<F>{get(9), get(10), get(11)};
  g.ra = get(12), g.ha = get(13), g.rb = get(14), g.hb = get(15);
  return g;
}

/// One rim pair of a lane, in the frame of gs (the pair g itself, or swapped where
/// swap: the solves sample the smaller rim): gs's A rim at tau (centre ca = c + tau ha
/// u) against its B rim at s (centre s hb z); q0 = ca relative to B's rim centre.
template <class F>
struct RimPair {
  Geo<F> g, gs;
  typename F::Mask swap;
  F tau, s;
  V3<F> ca, q0;
};

/// The chunk's geometry rows of lanes idx.
template <class F, class Chunk>
IMPACT_INLINE Geo<F> gather_geo(const Chunk& ch, typename F::Int idx) {
  // Ascending chunk lanes (listed in order): read by windows (simd::SortedGather).
  const simd::SortedGather<F::kWidth> rows(idx, 0, static_cast<int32_t>(std::size(ch.geo[0])));
  return read_geo<F>([&](int f) IMPACT_LAMBDA_INLINE { return rows(ch.geo[f]); });
}

/// The rim pairs (lane idx, pair pr) of the chunk's geometry.
template <class F, class Chunk>
IMPACT_INLINE RimPair<F> gather_rim_pair(const Chunk& ch, typename F::Int idx, typename F::Int pr) {
  RimPair<F> r;
  r.g = gather_geo<F>(ch, idx);
  const F tau = simd::gather(kPairTau, pr), s = simd::gather(kPairS, pr);
  r.swap = r.g.ra > r.g.rb;
  r.gs = select_geo(r.swap, swapped(r.g), r.g);
  r.tau = select(r.swap, s, tau), r.s = select(r.swap, tau, s);
  r.ca = madd(r.gs.c, r.tau * r.gs.ha, r.gs.u);
  r.q0 = V3<F>{r.ca.x, r.ca.y, r.ca.z - r.s * r.gs.hb};
  return r;
}

/// Rim x rim, step 1: the local minima over gs's A rim angle of the distance D from its
/// rim point to gs's B rim circle (g = D2 / 2, D2 = q_z^2 + (|q_xy| - rb)^2, q = the point
/// relative to B's rim centre), bracketed from g and g' at kArcSamples angles: a sample
/// step where g' turns from falling to rising holds one; so may a step whose ends have
/// g' of one sign where the cubic Hermite interpolant of g turns inside it (two critical
/// points close together: seen where D is nearly flat along the rim); and a sample whose
/// slope is far below its neighbours' (the two steps around it). The first kArcSlots
/// brackets in angle order go to slots: the bracket's first sample, its span (one step or
/// two) and a start in it, as angles past that sample. D is ra-Lipschitz in the angle, so
/// where cut (the least o of a lane certified to meet, else kNever) is below sqrt(D2) -
/// ra step / 2 at both ends of a step, no angle in it can win: not listed.
template <class F>
IMPACT_INLINE typename F::Int rim_brackets(const RimPair<F>& r, F cut, typename F::Int (&slot_k)[kArcSlots],
                                           F (&b_st)[kArcSlots], F (&b_span)[kArcSlots]) {
  using Mask = typename F::Mask;
  using Int = typename F::Int;
  const F zero(0.0f), one(1.0f), half(0.5f), h(kArcStep), tiny(kTinySq);
  const Geo<F>& gs = r.gs;
  F d2[kArcSamples], m[kArcSamples], er[kArcSamples], ez[kArcSamples], eu[kArcSamples];
  for (int k = 0; k < kArcSamples; ++k) {
    const F ck(kArcCos[k]), sk(kArcSin.v[k]);
    const V3<F> p = madd(madd(r.q0, gs.ra * ck, gs.ax), gs.ra * sk, gs.ay);
    const V3<F> t = madd(gs.ay * ck, -sk, gs.ax);  // d p / d angle, over ra
    const F rho = sqrt(max(p.x * p.x + p.y * p.y, tiny));
    const F irho = one / rho;
    const F e = rho - gs.rb;
    d2[k] = p.z * p.z + e * e;
    m[k] = gs.ra * (p.z * t.z + e * (p.x * t.x + p.y * t.y) * irho);  // g'
    er[k] = e, ez[k] = r.s * p.z;
    eu[k] = r.tau * (dot(p, gs.u) - gs.rb * (p.x * gs.u.x + p.y * gs.u.y) * irho);
  }
  // Steps outside the rims' cones. At a critical point of D (not on B's circle) the
  // normal is +-x, x = p - rb (p_xy / rho, 0) = (e radial, p_z): valid only where tau x.u
  // (A's cap side), e and s p_z (B's) have the signs of one of the two rules (plus: x.u
  // >= 0, e <= 0, s p_z <= 0; minus: all reversed; within kConeSlack |x|). Over a step
  // e and p_z lie within M h^2 / 8 of their chords (|p_z''| <= ra |(ax_z, ay_z)|, |e''| =
  // |rho''| <= ra (1 + ra / rho)), and x.u = p0.u - rb (p_xy / rho).u_xy within L h / 2 of
  // its ends' mean (L = rb ra |u_xy| / rho: B's angle turns at most ra / rho per unit of
  // A's); rho is at least its ends' least less ra h / 2 (ra-Lipschitz). Where neither
  // rule can hold anywhere in a step by a margin, and the step lies farther than far from
  // B's circle (x, not the tangents' cross product, gives the normal there), no critical
  // point of D in it is a valid rim point: a bracket made of such steps is not listed (a
  // point it would end on is an upper bound no lower than the critical point that holds
  // the minimum).
  Mask outside[kArcSamples];
  {
    const F hh(0.125f * kArcStep * kArcStep), lip_h = gs.ra * F(0.5f * kArcStep);
    const F bz = hh * gs.ra * sqrt(gs.ax.z * gs.ax.z + gs.ay.z * gs.ay.z);
    const F lu = lip_h * gs.rb * sqrt(gs.u.x * gs.u.x + gs.u.y * gs.u.y);
    const F far = gs.ra * F(0.5f * kArcStep + 1e-2f);
    const F far2 = far * far;
    for (int k = 0; k < kArcSamples; ++k) {
      const int kn = (k + 1) % kArcSamples;
      const F irlo = one / max(min(er[k], er[kn]) + gs.rb - lip_h, F(1e-3f) * gs.ra);
      const F be = hh * gs.ra * (one + gs.ra * irlo), bu = lu * irlo;
      const F elo = min(er[k], er[kn]) - be, ehi = max(er[k], er[kn]) + be;
      const F zlo = min(ez[k], ez[kn]) - bz, zhi = max(ez[k], ez[kn]) + bz;
      const F um = half * (eu[k] + eu[kn]);
      const F ulo = um - bu, uhi = um + bu;
      const F mg = F(4.0f * kConeSlack) * (max(abs(elo), abs(ehi)) + max(abs(zlo), abs(zhi)));
      const Mask plus = (uhi >= -mg) & (elo <= mg) & (zlo <= mg);
      const Mask minus = (ulo <= mg) & (ehi >= -mg) & (zhi >= -mg);
      outside[k] = ~(plus | minus) & (min(d2[k], d2[kn]) > far2);
    }
  }
  const F lip = gs.ra * F(0.5f * kArcStep);
  const F reach = (cut + lip) * (cut + lip);  // (inf where cut is kNever)
  for (int j = 0; j < kArcSlots; ++j) slot_k[j] = Int(0), b_st[j] = half * h, b_span[j] = h;
  Int cnt(0);
  int cmax = 0;
  const F ih = one / h;
  Mask held[kArcSamples];  // a bracket in step k
  F st[kArcSamples];
  for (int k = 0; k < kArcSamples; ++k) {
    const int kn = (k + 1) % kArcSamples;
    const Mask turn = (m[k] < zero) & (m[kn] >= zero);
    // the Hermite interpolant's g' = a s^2 + b s + c over s in [0, 1]
    const F dg = F(3.0f) * (d2[kn] - d2[k]) * ih;  // 6 (g1 - g0) / h
    const F qa = F(3.0f) * (m[k] + m[kn]) - dg, qb = dg - F(4.0f) * m[k] - F(2.0f) * m[kn], qc = m[k];
    const Mask curved = abs(qa) > tiny;
    const F vs = -qb / (F(2.0f) * select(curved, qa, one));  // its turning point
    const Mask dips = curved & (vs > zero) & (vs < one) & (qb * qb > F(4.0f) * qa * qc);
    const Mask up = dips & (m[k] >= zero) & (m[kn] >= zero) & (qa > zero);  // + - +: min after vs
    const Mask down = dips & (m[k] < zero) & (m[kn] < zero) & (qa < zero);  // - + -: min before vs
    held[k] = andnot((min(d2[k], d2[kn]) < reach) & (turn | up | down), outside[k]);
    // Starts: for a turn, the interpolant's root of g' (one in the step: - to +; written
    // without cancellation), not the chord's: a flat stretch at one end can hold a
    // second pair of critical points, and Newton from the chord's root near it finds
    // that one. For a dip, the whole step is the bracket, from the interpolant's turning
    // point: the model places the pair only roughly, and Newton from there finds the
    // minimum's side of the maximum (g' < 0 (> 0) at a point fixes the bracket's end).
    const F sq = sqrt(max(qb * qb - F(4.0f) * qa * qc, zero));
    const Mask pos_b = qb > zero;
    const F num = select(pos_b, F(2.0f) * qc, sq - qb);
    const F den = select(pos_b, -qb - sq, F(2.0f) * qa);
    const F root = clamp(num / select(turn & (abs(den) > tiny), den, one), zero, one);
    st[k] = select(turn, root, vs) * h;
  }
  for (int k = 0; k < kArcSamples; ++k) {
    // a sample whose slope is far below its neighbours' lies by a critical point the
    // steps may not show or may hold beside another (a narrow dip where the rims pass
    // close, D small against the step's arc; a flat stretch, D nearly constant, with a
    // minimum at either end): the two steps around it are one more bracket, from the
    // sample
    const int kp = (k + kArcSamples - 1) % kArcSamples, kn = (k + 1) % kArcSamples;
    const Mask wide =
        andnot((F(kStill) * abs(m[k]) < abs(m[kp]) + abs(m[kn])) & (d2[k] < reach), outside[kp] & outside[k]);
    // (slots past cmax + 1 cannot be written here: cmax bounds every lane's cnt)
    const int last = cmax + 1 < kArcSlots ? cmax + 1 : kArcSlots - 1;
    for (int j = 0; j <= last; ++j) {
      const Mask put_w = wide & (cnt == Int(j));
      const Mask put_h = held[k] & (cnt + simd::to_int(wide) == Int(j));
      slot_k[j] = select(put_w, Int(kp), select(put_h, Int(k), slot_k[j]));
      b_st[j] = select(put_w, h, select(put_h, st[k], b_st[j]));
      b_span[j] = select(put_w, F(2.0f) * h, select(put_h, h, b_span[j]));
    }
    cnt = cnt + simd::to_int(wide) + simd::to_int(held[k]);
    cmax += (simd::any(wide) ? 1 : 0) + (simd::any(held[k]) ? 1 : 0);
  }
  return select(cnt > Int(kArcSlots), Int(kArcSlots), cnt);
}

/// Rim x rim, step 2, for M groups side by side (independent chains: their divisions and
/// square roots overlap): each bracket [0, span] past its sample refined by safeguarded
/// Newton steps on D2 / 2 (bisection where Newton leaves the bracket), from the start
/// rim_brackets gave it; a lane freezes once a Newton
/// step moves it by at most kArcFreeze (its later steps would move it by ~that squared),
/// so its bytes do not depend on the lanes beside it. The refined point pair x = pA - pB
/// is perpendicular to both rims' tangents: n = +-x / |x| or +-(tA x tB) / |tA x tB|,
/// whichever the solve's angle error turns less (the cross product where the circles
/// touch and x is rounding noise), with the sign that puts n in A's rim's normal cone
/// and -n in B's,
/// within kConeSlack; none: not a point of the piece (the candidate still bounds o).
/// Outputs: the candidate in g's terms (n from A to B, A's witness point), scored there.
template <class F, int M>
IMPACT_INLINE void rim_refine(const RimPair<F> (&r)[M], const typename F::Int (&k0)[M], const F (&bst)[M],
                              const F (&bspan)[M], F (&o)[M], V3<F> (&n)[M], V3<F> (&xw)[M],
                              typename F::Mask (&valid)[M]) {
  using Mask = typename F::Mask;
  const F zero(0.0f), one(1.0f), tiny(kTinySq);
  F ck[M], sk[M], lo[M], hi[M], d[M];
  Mask frozen[M];
  for (int m = 0; m < M; ++m) {
    ck[m] = simd::gather(kArcCos, k0[m]), sk[m] = simd::gather(kArcSin.v, k0[m]);
    lo[m] = zero, hi[m] = bspan[m], d[m] = bst[m];
    frozen[m] = Mask(false);
  }
  for (int it = 0; it < kArcSteps; ++it) {
    Mask all_frozen(true);
    for (int m = 0; m < M; ++m) {
      const Geo<F>& gs = r[m].gs;
      F cd, sd;
      cos_sin_small(d[m], cd, sd);
      const F cs = ck[m] * cd - sk[m] * sd, sn = sk[m] * cd + ck[m] * sd;
      const V3<F> rad = madd(gs.ax * cs, sn, gs.ay);
      const V3<F> q = madd(r[m].q0, gs.ra, rad);
      const V3<F> q1 = madd(gs.ay * cs, -sn, gs.ax) * gs.ra;  // dq / d angle; d2q = -ra rad
      const F rho = sqrt(max(q.x * q.x + q.y * q.y, tiny));
      const F irho = one / rho;
      const F rho_1 = (q.x * q1.x + q.y * q1.y) * irho;
      const F e = rho - gs.rb;
      const F g1 = q.z * q1.z + e * rho_1;
      const F t2 = q1.x * q1.x + q1.y * q1.y;
      const F qq2 = -gs.ra * (q.x * rad.x + q.y * rad.y);
      const F rho_2 = (t2 + qq2 - rho_1 * rho_1) * irho;
      const F g2 = q1.z * q1.z - gs.ra * q.z * rad.z + rho_1 * rho_1 + e * rho_2;
      const Mask up = g1 > zero;
      const F lo1 = select(up, lo[m], d[m]), hi1 = select(up, d[m], hi[m]);
      const Mask curved = g2 > zero;
      const F newton = d[m] - g1 / select(curved, g2, one);
      // (a Newton step within kArcFreeze is taken even onto the bracket's end: at the
      // root, rounding can put it exactly there)
      const Mask tiny_step = curved & (abs(newton - d[m]) <= F(kArcFreeze));
      const Mask use = curved & (newton >= lo1) & (newton <= hi1);
      const F dn =
          select(g1 == zero, d[m], select(use | tiny_step, clamp(newton, lo1, hi1), F(0.5f) * (lo1 + hi1)));
      const Mask done = tiny_step | (hi1 - lo1 <= F(kArcFreeze)) | (g1 == zero);
      lo[m] = select(frozen[m], lo[m], lo1), hi[m] = select(frozen[m], hi[m], hi1);
      d[m] = select(frozen[m], d[m], dn);
      frozen[m] = frozen[m] | done;
      all_frozen = all_frozen & frozen[m];
    }
    if (simd::all(all_frozen)) break;
  }
  for (int m = 0; m < M; ++m) {
    const Geo<F>& gs = r[m].gs;
    F cd, sd;
    cos_sin_small(d[m], cd, sd);
    const F cs = ck[m] * cd - sk[m] * sd, sn = sk[m] * cd + ck[m] * sd;
    const V3<F> rad = madd(gs.ax * cs, sn, gs.ay);
    const V3<F> q = madd(r[m].q0, gs.ra, rad);
    const F rho2 = q.x * q.x + q.y * q.y;
    const Mask off_axis = rho2 > tiny;
    const F irho = one / sqrt(select(off_axis, rho2, one));
    const V3<F> radb{q.x * irho, q.y * irho, zero};
    const V3<F> pa = madd(r[m].ca, gs.ra, rad);
    const V3<F> pb{gs.rb * radb.x, gs.rb * radb.y, r[m].s * gs.hb};
    const V3<F> cr = cross(madd(gs.ay * cs, -sn, gs.ax), V3<F>{-radb.y, radb.x, zero});
    const V3<F> x = pa - pb;
    // the better conditioned of the two: an angle error e of the solve turns x by about
    // ra e / |x| and the cross product by e / |cr|
    const V3<F> v = select(length_sq(x) > gs.ra * gs.ra * length_sq(cr), x, cr);
    const F lv2 = length_sq(v);
    const Mask dir = lv2 > tiny;
    const F lv = sqrt(select(dir, lv2, one));
    const F e = F(kConeSlack) * lv;
    const F xa = dot(v, rad), xu = r[m].tau * dot(v, gs.u), xb = dot(v, radb), xz = r[m].s * v.z;
    const Mask plus = (xa >= -e) & (xu >= -e) & (xb <= e) & (xz <= e);
    const Mask minus = (xa <= e) & (xu <= e) & (xb >= -e) & (xz >= -e);
    const V3<F> ns = v * (select(plus, one, F(-1.0f)) / lv);
    // back to g: n from A to B, A's witness point
    const Geo<F>& g = r[m].g;
    n[m] = select(r[m].swap, -(madd(madd(g.ax * ns.x, ns.y, g.ay), ns.z, g.u)), ns);
    // the witness x whose x - o n / 2 is the pair's midpoint (x - o n = pB where x - pB
    // = o n exactly; rounding of the solve is shared by the two surfaces)
    const V3<F> mid = (pa + pb) * F(0.5f);
    const V3<F> mw = select(r[m].swap, madd(madd(madd(g.c, mid.x, g.ax), mid.y, g.ay), mid.z, g.u), mid);
    valid[m] = off_axis & dir & (plus | minus);
    o[m] = select(dir, score(g, n[m]), F(kNever));
    xw[m] = madd(mw, F(0.5f) * o[m], n[m]);
  }
}

// ---------------------------------------------------------------------------------------
// Chunk state: phase A (closed-form candidates) writes it, phase B (packed rim x rim
// solves) updates it, phase C (manifold) reads it.
// ---------------------------------------------------------------------------------------

template <uint32_t W>
struct Chunk {
  static constexpr uint32_t kLanes = kChunkBlocks * W;
  // Rows kLanes + 16 floats apart (as box_cylinder.cpp's chunk): a lane's rows in
  // different L1 sets (docs/narrowphase.md, "Array layout").
  static constexpr uint32_t kRow = kLanes + 16;
  // geometry: c 0..2, ax 3..5, ay 6..8, u 9..11, ra 12, ha 13, rb 14, hb 15
  float geo[16][kRow];
  // best: o 0, n 1..3, x 4..6, any_o 7, any_n 8..10, any_x 11..13
  float st[14][kRow];
  float cut[kLanes];
  // lanes the side-rim solves run on (phase A lists them)
  int32_t srl[kLanes + W];
  uint32_t nsr = 0;
  int32_t lane[4 * kLanes + W];
  int32_t pair[4 * kLanes + W];
  uint32_t nitems = 0;
  // phase B's refinement units (a bracket of a rim pair), flushed 4 W at a time
  static constexpr uint32_t kUnits = 4 * W + kArcSlots * W + W;
  int32_t ulane[kUnits], upair[kUnits], uk[kUnits];
  float ust[kUnits], uspan[kUnits];
  uint32_t nunits = 0;
};

template <class F, uint32_t W>
IMPACT_INLINE void save_geo(Chunk<W>& ch, uint32_t j, const Geo<F>& g) {
  const V3<F>* v[4] = {&g.c, &g.ax, &g.ay, &g.u};
  for (int i = 0; i < 4; ++i)
    v[i]->x.store(ch.geo[3 * i] + j), v[i]->y.store(ch.geo[3 * i + 1] + j),
        v[i]->z.store(ch.geo[3 * i + 2] + j);
  g.ra.store(ch.geo[12] + j), g.ha.store(ch.geo[13] + j), g.rb.store(ch.geo[14] + j),
      g.hb.store(ch.geo[15] + j);
}

/// The pair in B's frame (relative to B's centre), B's rotation and centre relative to A's.
template <class F>
IMPACT_INLINE Geo<F> load_geo(const LeafSoA& a, const LeafSoA& b, uint32_t k, V3<F>& cb, M3<F>& rot) {
  Geo<F> g;
  cb = load_p<F>(b, k) - load_p<F>(a, k);
  rot = load_r<F>(b, k);
  const M3<F> ra = load_r<F>(a, k);
  g.c = rot.apply_t(-cb);
  g.ax = rot.apply_t(ra.c[0]);
  g.ay = rot.apply_t(ra.c[1]);
  g.u = rot.apply_t(ra.c[2]);
  g.ra = ld<F>(a.e[0], k), g.ha = ld<F>(a.e[1], k);
  g.rb = ld<F>(b.e[0], k), g.hb = ld<F>(b.e[1], k);
  return g;
}

/// Phase A for one block (chunk lanes j .. j + nb): the closed-form candidates, the
/// certificate of meeting, the rim pairs listed for phase B.
template <class F, uint32_t W>
IMPACT_INLINE void phase_a(const LeafSoA& a, const LeafSoA& b, uint32_t k, uint32_t j, uint32_t nb,
                           Chunk<W>& ch) {
  using Mask = typename F::Mask;
  const F zero(0.0f), one(1.0f), never(kNever);
  V3<F> cb;
  M3<F> rot;
  const Geo<F> g = load_geo<F>(a, b, k, cb, rot);
  save_geo<F, W>(ch, j, g);
  const V3<F> ez{zero, zero, one};
  Best<F> best;
  best.o = never, best.any_o = never;
  best.n = ez, best.x = g.c, best.any_n = ez, best.any_x = g.c;
  // Lanes whose bounding spheres are apart: no contact.
  const F reach = sqrt(g.ra * g.ra + g.ha * g.ha) + sqrt(g.rb * g.rb + g.hb * g.hb);
  const Mask near = length_sq(cb) < reach * reach;
  if (simd::none(near)) {
    best.o = F(-1.0f), best.any_o = F(-1.0f);
    save_best<F>(ch.st, j, best);
    return;
  }
  const F slack = pair_slack(g);
  // --- caps: n = +-z (B's caps; A's witness its support), n = +-u (A's caps; B's witness
  // its support, A's = that + o n), o in closed form; one witness, for the least ---
  {
    const F kz = g.ha * abs(g.u.z) + g.ra * sqrt(g.ax.z * g.ax.z + g.ay.z * g.ay.z) + g.hb;
    const F ku = g.ha + g.hb * abs(g.u.z) + g.rb * sqrt(g.u.x * g.u.x + g.u.y * g.u.y);
    const F cu = dot(g.c, g.u);
    F o = g.c.z + kz;
    V3<F> n = ez;
    Mask on_a(false);
    auto take_cap = [&](F o2, const V3<F>& n2, bool a_cap) {
      const Mask m = o2 < o;
      o = select(m, o2, o), n = select(m, n2, n);
      if (a_cap) on_a = on_a | m;
    };
    take_cap(kz - g.c.z, -ez, false);
    take_cap(cu + ku, g.u, true);
    take_cap(ku - cu, -g.u, true);
    const V3<F> x = select(on_a, madd(support_b(g, n), o, n), support_a(g, n));
    best.o = o, best.n = n, best.x = x;
    best.any_o = o, best.any_n = n, best.any_x = x;
  }
  // --- side x side: n = +-(u x z) / |u x z| (o = +-c.w + ra + rb), where the axes'
  // closest points lie on both ---
  {
    const F uxy2 = g.u.x * g.u.x + g.u.y * g.u.y;
    const Mask crossing = uxy2 > F(1e-10f);
    const F iw = one / sqrt(select(crossing, uxy2, one));
    const V3<F> w{g.u.y * iw, -g.u.x * iw, zero};
    const F bz = g.u.z, d1 = dot(g.c, g.u), d2 = g.c.z;
    const F sa = (bz * d2 - d1) / select(crossing, uxy2, one);
    const F tb = mul_add(sa, bz, d2);
    const Mask ok = crossing & (abs(sa) <= g.ha + slack) & (abs(tb) <= g.hb + slack);
    const V3<F> axis_pt = madd(g.c, sa, g.u);
    const F cw = dot(g.c, w), rr = g.ra + g.rb;
    for (int sg = 0; sg < 2; ++sg) {
      const V3<F> n = sg == 0 ? w : -w;
      best.take(select(crossing, (sg == 0 ? cw : -cw) + rr, never), n, madd(axis_pt, g.ra, n), ok);
    }
  }
  // --- the lanes not yet certified apart (some o <= 0) go on to the side-rim solves and
  // the rim pairs, packed (phase B) ---
  list_lanes<F>(ch.srl, ch.nsr, near & (best.any_o > zero), j, nb);
  never.store(ch.cut + j);
  save_best_near<F>(ch.st, j, best, near);
}

/// Phase B, side x rims, for W listed lanes (idx; the first `real` are the list's, the
/// rest repeat the last): A's side against B's rims (n.u = 0) and B's side against A's
/// rims (n.z = 0), the four half-ellipse solves in one loop (independent chains side by
/// side), merged into the lanes' best after the caps and sides; then the rim pairs to
/// solve of the lanes still not certified apart.
template <class F, uint32_t W>
IMPACT_INLINE void side_rims(Chunk<W>& ch, typename F::Int idx, uint32_t real, uint32_t& cnt) {
  using Mask = typename F::Mask;
  using Int = typename F::Int;
  const F zero(0.0f), one(1.0f), never(kNever);
  const V3<F> ez{zero, zero, one};
  const Geo<F> g = gather_geo<F>(ch, idx);
  Best<F> best = gather_best<F>(ch.st, idx);
  const F slack = pair_slack(g);
  {
    const Geo<F> gs = swapped(g);  // B's centre and axis in A's frame
    rim::CoreRims<F> sa, sb;
    F rb[4], rx[4], ry[4], ex[4], ey[4];
    sa.setup(g.c, g.u, g.rb, g.hb, rb, rx, ry);
    sb.setup(gs.c, gs.u, g.ra, g.ha, rb + 2, rx + 2, ry + 2);
    rim::half_ellipse_normals(rb, rx, ry, ex, ey);
    V3<F> n[2], y[2];
    F t[2];
    Mask on[2];
    sa.finish(g.c, g.u, g.ha, g.rb, g.hb, slack, ex, ey, n, y, t, on);
    for (int i = 0; i < 2; ++i) {
      const F o = score(g, n[i]);
      best.take(o, n[i], madd(y[i], o, n[i]), on[i]);
    }
    sb.finish(gs.c, gs.u, g.hb, g.ra, g.ha, slack, ex + 2, ey + 2, n, y, t, on);
    for (int i = 0; i < 2; ++i) {
      // back from A's frame: n from A to B, A's rim point
      const V3<F> nw = -(madd(madd(g.ax * n[i].x, n[i].y, g.ay), n[i].z, g.u));
      const V3<F> x = madd(madd(madd(g.c, y[i].x, g.ax), y[i].y, g.ay), y[i].z, g.u);
      best.take(score(g, nw), nw, x, on[i]);
    }
  }
  // --- rim x rim pairs to solve, where a lane is not certified apart (some o <= 0) ---
  const Mask live = best.any_o > zero;
  F cut = never;
  uint32_t keep = simd::bits(live);
  if (real < W) keep &= (1u << real) - 1u;
  if (keep != 0) {
    // certified to meet: a centre in the other, the axes' closest points, or either
    // shape's support point along the least o's normal inside the other (points of the
    // shapes: a cap candidate's witness x = y + o n need not be); then a rim pair
    // farther apart than the least o cannot win
    Mask cert = in_b(g, g.c) | in_a(g, V3<F>{zero, zero, zero});
    {
      F sa, tb;
      closest_segment_segment(g.c, g.u, g.ha, V3<F>{zero, zero, zero}, ez, g.hb, sa, tb);
      cert = cert | in_b(g, madd(g.c, sa, g.u)) | in_a(g, V3<F>{zero, zero, tb});
    }
    cert = cert | in_b(g, support_a(g, best.any_n)) | in_a(g, support_b(g, best.any_n));
    cut = select(cert, best.any_o, never);
    for (int pr = 0; pr < 4; ++pr) {
      const F tau((pr & 1) != 0 ? -1.0f : 1.0f), s((pr & 2) != 0 ? -1.0f : 1.0f);
      const uint32_t bits = simd::bits(rim_pair_bound(g, tau, s) < cut) & keep;
      Int(pr).store(ch.pair + cnt);
      cnt += simd::compact_store(ch.lane + cnt, idx, bits);
    }
  }
  // back to the chunk's rows, the listed lanes only
  scatter_best<F>(ch.st, idx, real, best);
  float cuts[W];
  int32_t ln[W];
  cut.store(cuts), idx.store(ln);
  for (uint32_t l = 0; l < real; ++l) ch.cut[ln[l]] = cuts[l];
}

/// Phase B, refinement: M groups of W units from unit `at` (the last group padded by
/// repeating the last unit), their candidates merged into their lanes' best in unit
/// order (a lane's units are listed in its pairs' and brackets' order: the merge order
/// does not depend on the grouping).
template <class F, uint32_t W, int M>
IMPACT_INLINE void refine_units(Chunk<W>& ch, uint32_t at, uint32_t total) {
  using Int = typename F::Int;
  RimPair<F> r[M];
  Int k0[M];
  F bst[M], bspan[M], o[M];
  V3<F> n[M], xw[M];
  typename F::Mask valid[M];
  for (int m = 0; m < M; ++m) {
    const uint32_t u = at + static_cast<uint32_t>(m) * W;
    r[m] = gather_rim_pair<F>(ch, Int::load(ch.ulane + u), Int::load(ch.upair + u));
    k0[m] = Int::load(ch.uk + u);
    bst[m] = F::load(ch.ust + u), bspan[m] = F::load(ch.uspan + u);
  }
  rim_refine<F, M>(r, k0, bst, bspan, o, n, xw, valid);
  for (int m = 0; m < M; ++m) {
    const uint32_t u = at + static_cast<uint32_t>(m) * W;
    const uint32_t cnt = u >= total ? 0u : (total - u < W ? total - u : W);
    merge_best(ch.st, ch.ulane + u, cnt, o[m], n[m], xw[m], valid[m]);
  }
}

/// Refines the first `count` units (4, 2 or 1 groups at a time) and drops them.
template <class F, uint32_t W>
IMPACT_INLINE void flush_units(Chunk<W>& ch, uint32_t count) {
  const uint32_t groups = (count + W - 1) / W;
  for (uint32_t l = count; l < groups * W; ++l) {
    ch.ulane[l] = ch.ulane[count - 1], ch.upair[l] = ch.upair[count - 1], ch.uk[l] = ch.uk[count - 1];
    ch.ust[l] = ch.ust[count - 1], ch.uspan[l] = ch.uspan[count - 1];
  }
  uint32_t gi = 0;
  for (; gi + 4 <= groups; gi += 4) refine_units<F, W, 4>(ch, gi * W, count);
  if (gi + 2 <= groups) refine_units<F, W, 2>(ch, gi * W, count), gi += 2;
  if (gi < groups) refine_units<F, W, 1>(ch, gi * W, count);
  // keep what was past count (not refined yet)
  const uint32_t rest = ch.nunits - count;
  for (uint32_t l = 0; l < rest; ++l) {
    ch.ulane[l] = ch.ulane[count + l], ch.upair[l] = ch.upair[count + l], ch.uk[l] = ch.uk[count + l];
    ch.ust[l] = ch.ust[count + l], ch.uspan[l] = ch.uspan[count + l];
  }
  ch.nunits = rest;
}

/// Phase B: the listed rim pairs, W at a time (the last group repeating the last item):
/// their brackets become units, refined 4 W at a time.
template <class F, uint32_t W>
IMPACT_INLINE void phase_b(Chunk<W>& ch) {
  using Int = typename F::Int;
  if (ch.nsr == 0) return;
  {
    uint32_t cnt = 0;
    for_each_listed<F>(ch.srl, ch.nsr, [&](Int idx, uint32_t real) { side_rims<F, W>(ch, idx, real, cnt); });
    ch.nsr = 0;
    ch.nitems = cnt;
  }
  const uint32_t total = ch.nitems;
  if (total == 0) return;
  const uint32_t groups = (total + W - 1) / W;
  for (uint32_t l = total; l < groups * W; ++l)
    ch.lane[l] = ch.lane[total - 1], ch.pair[l] = ch.pair[total - 1];
  ch.nunits = 0;
  for (uint32_t gi = 0; gi < groups; ++gi) {
    const uint32_t at = gi * W;
    const Int idx = Int::load(ch.lane + at), pr = Int::load(ch.pair + at);
    const RimPair<F> r = gather_rim_pair<F>(ch, idx, pr);
    Int slot_k[kArcSlots];
    F b_st[kArcSlots], b_span[kArcSlots];
    const Int cnt = rim_brackets(r, simd::gather(ch.cut, idx), slot_k, b_st, b_span);
    int32_t c[W], sk[kArcSlots][W];
    float st[kArcSlots][W], sp[kArcSlots][W];
    for (uint32_t l = 0; l < W; ++l) c[l] = cnt.lane(l);
    for (int j = 0; j < kArcSlots; ++j) {
      for (uint32_t l = 0; l < W; ++l) sk[j][l] = slot_k[j].lane(l);
      b_st[j].store(st[j]), b_span[j].store(sp[j]);
    }
    const uint32_t real = total - at < W ? total - at : W;
    uint32_t nu = ch.nunits;
    for (uint32_t l = 0; l < real; ++l) {
      for (int j = 0; j < c[l]; ++j) {
        ch.ulane[nu] = ch.lane[at + l], ch.upair[nu] = ch.pair[at + l], ch.uk[nu] = sk[j][l];
        ch.ust[nu] = st[j][l], ch.uspan[nu] = sp[j][l];
        ++nu;
      }
    }
    ch.nunits = nu;
    // A group adds up to kArcSlots W units: flush until fewer than 4 W are left, so the
    // next group always fits (at most 4 W - 1 + kArcSlots W units, below kUnits).
    while (ch.nunits >= 4 * W) flush_units<F, W>(ch, 4 * W);
  }
  if (ch.nunits > 0) flush_units<F, W>(ch, ch.nunits);
  ch.nitems = 0;
}

/// Phase C for one block: the answer, the manifold, the store.
template <class F, uint32_t W>
IMPACT_INLINE void phase_c(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, uint32_t k, uint32_t j,
                           const Chunk<W>& ch) {
  using Mask = typename F::Mask;
  using Int = typename F::Int;
  const F zero(0.0f), one(1.0f), half(0.5f), tiny(kTinySq), never(kNever);
  const Best<F> best = load_best<F>(ch.st, j);
  if (simd::none(best.any_o > zero)) {
    store_no_contact<F>(out, k);
    return;
  }
  const Geo<F> g = read_geo<F>([&](int f) { return F::load(ch.geo[f] + j); });
  const V3<F> pa = load_p<F>(a, k);
  const V3<F> cb = load_p<F>(b, k) - pa;
  const M3<F> rot = load_r<F>(b, k);
  const F slack = pair_slack(g);
  const F uxy2 = g.u.x * g.u.x + g.u.y * g.u.y;
  // The least valid candidate, unless an invalid one is below it by more than rounding.
  const Mask use_any = (best.o >= never) | (best.any_o < best.o - F(4.0f) * slack);
  const F o = select(use_any, best.any_o, best.o);
  const V3<F> n = select(use_any, best.any_n, best.n);
  const V3<F> x = select(use_any, best.any_x, best.x);
  const Mask hit = o > zero;
  if (simd::none(hit)) {
    store_no_contact<F>(out, k);
    return;
  }
  const F size = g.ra + g.ha + g.rb + g.hb;
  // (the witness joins a clipped manifold once the others miss its depth by this: within
  // 1e-5 of the larger bounding radius, size <= 2.9 times that)
  const F tol = F(2e-6f) * size;
  const F par2(kParallelSin * kParallelSin);
  const F nu = dot(n, g.u);
  const F nxy2 = n.x * n.x + n.y * n.y;
  const F na = dot(n, g.ax), nb = dot(n, g.ay);
  const F nperp2 = na * na + nb * nb;  // |n x u|^2

  Lanes<F, 4> m;
  {
    const V3<F> p1 = madd(x, F(-0.5f) * o, n);
    m.count = select(hit, Int(1), Int(0));
    for (int i = 0; i < 4; ++i) m.point[i] = p1, m.pdepth[i] = o;
  }
  const Mask cap_b = hit & (nxy2 < par2);
  const Mask cap_a = hit & (nperp2 < par2);
  const Mask side_b = hit & (n.z * n.z < par2);
  const Mask side_a = hit & (nu * nu < par2);
  const F zc = -g.hb * simd::sign_nonneg(n.z);  // B's cap plane facing A
  const F tau = simd::sign_nonneg(nu);          // A's cap facing B: outward tau u
  const V3<F> cap_ac = madd(g.c, tau * g.ha, g.u);
  const F nz = select(abs(n.z) > half, n.z, one);
  const F tn = tau * nu;
  const F itn = one / select(tn > half, tn, one);

  // Cap on cap: A's rim samples seen along n on B's cap plane inside B's disk, B's rim
  // samples seen along n on A's cap plane inside A's disk, each with its gap; reduced to 4
  // in B's cap plane.
  const Mask capcap = cap_a & cap_b;
  if (simd::any(capcap)) {
    constexpr int M = 1 + 2 * kRimSamples;
    F cx[M], cy[M], cd[M];
    Mask cv[M];
    {
      const V3<F> y = madd(x, -o, n);
      cx[0] = y.x, cy[0] = y.y, cd[0] = o;
      cv[0] = Mask(true);
    }
    const F rb2 = g.rb * g.rb, ra2 = g.ra * g.ra;
    for (int i = 0; i < kRimSamples; ++i) {
      const F cs(kRimCos[i]), sn(kRimCos[(i + 6) % 8]);
      // A's rim point, along -n onto B's cap plane
      const V3<F> p = madd(madd(cap_ac, g.ra * cs, g.ax), g.ra * sn, g.ay);
      const F mu = (p.z - zc) / nz;
      const F px = p.x - mu * n.x, py = p.y - mu * n.y;
      cx[1 + i] = px, cy[1 + i] = py, cd[1 + i] = mu;
      cv[1 + i] = px * px + py * py <= rb2;
      // B's rim point, along n onto A's cap plane
      const F qx = g.rb * cs, qy = g.rb * sn;
      const V3<F> q{qx, qy, zc};
      const F lam = (g.ha - tau * dot(q - g.c, g.u)) * itn;
      const V3<F> qa = madd(q, lam, n) - cap_ac;
      const F sa = dot(qa, g.ax), sb = dot(qa, g.ay);
      cx[1 + kRimSamples + i] = qx, cy[1 + kRimSamples + i] = qy, cd[1 + kRimSamples + i] = lam;
      cv[1 + kRimSamples + i] = sa * sa + sb * sb <= ra2;
    }
    cap_manifold_tail<F, M>(cx, cy, cd, cv, o, tol, zc, n, capcap, m);
  }
  // A lying on B's cap: A's side line along n seen on B's cap plane, clipped to B's
  // disk and A's length (a quadratic in the line's parameter).
  const Mask line_a = andnot(cap_b & side_a, capcap);
  if (simd::any(line_a)) {
    constexpr int M = 3;
    F cx[M], cy[M], cd[M];
    Mask cv[M];
    {
      const V3<F> y = madd(x, -o, n);
      cx[0] = y.x, cy[0] = y.y, cd[0] = o;
      cv[0] = Mask(true);
    }
    const Mask radial = nperp2 > tiny;
    const F ir = g.ra / sqrt(select(radial, nperp2, one));
    const V3<F> l0 = madd(madd(g.c, na * ir, g.ax), nb * ir, g.ay);  // the line's centre
    // points l0 + t u - mu(t) n on the plane: mu = m0 + m1 t
    const F m0 = (l0.z - zc) / nz, m1 = g.u.z / nz;
    const F a0x = l0.x - m0 * n.x, a0y = l0.y - m0 * n.y;
    const F a1x = g.u.x - m1 * n.x, a1y = g.u.y - m1 * n.y;
    F t0, t1;
    const Mask ok = clip_segment_disk(a0x, a0y, a1x, a1y, g.rb, g.ha, t0, t1);
    for (int c = 0; c < 2; ++c) {
      const F t = c == 0 ? t0 : t1;
      cx[1 + c] = mul_add(t, a1x, a0x), cy[1 + c] = mul_add(t, a1y, a0y), cd[1 + c] = mul_add(t, m1, m0);
      cv[1 + c] = ok;
    }
    cap_manifold_tail<F, M>(cx, cy, cd, cv, o, tol, zc, n, line_a, m);
  }
  // B lying on A's cap: B's side line along -n seen on A's cap plane, clipped to A's disk
  // and B's length; A side by side with B (axes within kParallelSin): A's side line
  // clipped to B's height. Both reduced in B's side coordinates.
  const Mask line_b = andnot(cap_a & side_b, capcap | line_a);
  const Mask sides = andnot(side_a & side_b & (uxy2 < par2), capcap | line_a | line_b);
  if (simd::any(line_b | sides)) {
    constexpr int M = 3;
    V3<F> ca[M];
    F cd[M];
    Mask cv[M];
    ca[0] = x, cd[0] = o, cv[0] = Mask(true);
    const Mask okxy = nxy2 > tiny;
    const F ixy = one / sqrt(select(okxy, nxy2, one));
    const F mx = select(okxy, n.x * ixy, one), my = select(okxy, n.y * ixy, zero);
    // B's line: (-rb m, t), |t| <= hb; on A's cap plane at lam(t) = l0 + l1 t along n
    const F l0 = (g.ha - tau * (-g.rb * (mx * g.u.x + my * g.u.y) - dot(g.c, g.u))) * itn;
    const F l1 = -tau * g.u.z * itn;
    // the plane point minus A's cap centre: a0 + a1 t, in A's cap coordinates
    const V3<F> b0 = V3<F>{-g.rb * mx, -g.rb * my, zero} - cap_ac;
    const F a0x = dot(b0, g.ax) + l0 * na, a0y = dot(b0, g.ay) + l0 * nb;
    const F a1x = g.ax.z + l1 * na, a1y = g.ay.z + l1 * nb;
    F bt0, bt1;
    const Mask bok = clip_segment_disk(a0x, a0y, a1x, a1y, g.ra, g.hb, bt0, bt1);
    // A's line: l(t) = la + t u; its point seen along -n on B's side at height
    // z(t) - d n_z ~ z(t) - o n_z within [-hb, hb]
    const Mask radial = nperp2 > tiny;
    const F ir = g.ra / sqrt(select(radial, nperp2, one));
    const V3<F> la = madd(madd(g.c, na * ir, g.ax), nb * ir, g.ay);
    const F cz = la.z - o * n.z;
    const Mask level = abs(g.u.z) < tiny;
    const F iz = one / select(level, one, g.u.z);
    const F ta = (-g.hb - cz) * iz, tb = (g.hb - cz) * iz;
    const F at0 = select(level, -g.ha, max(min(ta, tb), -g.ha));
    const F at1 = select(level, g.ha, min(max(ta, tb), g.ha));
    const Mask aok = select(level, abs(cz) <= g.hb, Mask(true)) & (at0 <= at1);
    for (int c = 0; c < 2; ++c) {
      // B's line point on A's cap (A's surface point), gap lam
      const F bt = c == 0 ? bt0 : bt1;
      const F lam = mul_add(bt, l1, l0);
      const V3<F> pb = madd(V3<F>{-g.rb * mx, -g.rb * my, bt}, lam, n);
      // A's line point (A's surface), gap: where the line from it along -n leaves B's side;
      // an end whose exit lies past B's height (the clip took the gap as o; a tilted pair's
      // differs along the line) moves along the line until it does not (the exit's height
      // changes by u_z per unit t, to first order): one correction
      auto exit_gap = [&](F t, V3<F>& p) {
        p = madd(la, t, g.u);
        const F bb = p.x * n.x + p.y * n.y, cc = p.x * p.x + p.y * p.y - g.rb * g.rb;
        return (bb + sqrt(max(bb * bb - nxy2 * cc, zero))) / select(okxy, nxy2, one);
      };
      F at = c == 0 ? at0 : at1;
      V3<F> pa2;
      F dside = exit_gap(at, pa2);
      {
        const F ez = pa2.z - dside * n.z;
        const F excess = ez - clamp(ez, -g.hb, g.hb);
        at = clamp(at - excess * iz, at0, at1);
        dside = exit_gap(at, pa2);
      }
      const F cc = pa2.x * pa2.x + pa2.y * pa2.y - g.rb * g.rb;
      ca[1 + c] = select(line_b, pb, pa2);
      cd[1 + c] = select(line_b, lam, dside);
      cv[1 + c] = select(line_b, bok, aok & (cc <= zero));
    }
    side_manifold_tail<F, M, true>(ca, cd, cv, o, tol, mx, my, n, line_b | sides, m);
  }

  m.count = select(hit, m.count, Int(0));
  // a single point carries the depth (a clip can leave one point a rounding short of it)
  m.pdepth[0] = select(m.count == Int(1), o, m.pdepth[0]);
  m.n = rot.apply(n);
  m.depth = o;
  for (int i = 0; i < 4; ++i) m.point[i] = cb + rot.apply(m.point[i]);
  store(out, k, m, pa);
}

template <class F>
void cylinder_cylinder_range(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, Range r) {
  constexpr uint32_t W = F::kWidth;
  Chunk<W> ch;
  for_each_chunk<F, 4>(a, b, out, r, ch, phase_a<F, W>, phase_b<F, W>, phase_c<F, W>);
}

}  // namespace

void collide_cylinder_cylinder(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, Range r,
                               const NarrowConfig& cfg) {
  if (cfg.path == KernelPath::kScalar)
    cylinder_cylinder_range<simd::Float1>(a, b, out, r);
  else
    cylinder_cylinder_range<simd::FloatP>(a, b, out, r);
}

}  // namespace impact::kernels
