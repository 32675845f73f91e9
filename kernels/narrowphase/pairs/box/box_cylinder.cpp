// Box (A) against cylinder (B): exact collision data of 1 to 4 points per pair,
// vectorised across pairs (one lane = one pair), no GJK / EPA.
//
// Inputs: LeafSoA lanes per leaf.h (A a box: p centre, R, e0..e2 half extents; B a
// cylinder C: p centre, R column 2 = unit axis, e0 = radius rc, e1 = half length h, flat
// caps with sharp rims), Range r of the bucket. Outputs: ManifoldSoA lanes r.begin ..
// r.end: count (0..4), n (unit, A to B), depth, point slots midway between the surfaces
// with their depths along n; count-0 lanes leave the other fields unspecified.
//
// Method, in the cylinder's frame relative to its centre (c the box centre, a_i its unit
// axes, e_i its half extents): o(n) = h_box(n) + h_C(-n) = n.c + sum_i e_i |n.a_i| +
// h |n_z| + rc |n_xy| is the support function of the Minkowski difference box - C. Its
// minimum over unit n is minus the distance when apart and the depth when they meet (no
// case split), and every unit n gives an upper bound, so the answer is the least o over
// a candidate set sure to hold the minimiser (as capsule_cylinder.cpp and
// cylinder_triangle.cpp). One candidate per boundary piece of box - C (a box feature
// summed with a cylinder feature whose normal sets meet):
//  - face x anything: n = +-a_i (6); anything x cap: n = +-z (2);
//  - edge x side (two lines): n = +-(a_i x z) / |a_i x z| (6);
//  - vertex x side: n horizontal, from the vertex towards the axis (8);
//  - vertex x rim: n from the rim circle's point nearest the vertex, with the sign the
//    rim's normal cone allows (16; each only where the vertex is the box's support
//    along its n, within 1e-3 of |n|_1 per axis: elsewhere it is no point of its piece);
//  - edge interior x rim: n on the great circle n.a_i = 0, where o is the 2D signed
//    distance from the edge's shadow point to the rim's shadow along a_i (an ellipse:
//    the upper / lower half for the one rim / the other), by the fixed-step solve of
//    Eberly's secular equation shared with capsule-cylinder (rim_solve.h): 24 slots
//    (12 edges x 2 rims), the only costly pieces. They are pruned per lane, and the
//    survivors of a chunk of 16 blocks are solved packed, kSimdWidth slots at a time.
//    A slot is kept where (1) the edge's normal cone reaches the rim's half sphere;
//    (2) a lower bound of o on that cone (the box's part is least at an end of the
//    quarter arc unless both ends are negative; the cylinder's is at least min(h, rc))
//    is at most the least o so far; (3) the edge segment's distance to the rim circle
//    (at least sqrt(radial gap^2 + height gap^2), both bounded along the edge), a lower
//    bound of the piece's |o|, is at most the least o so far where the pair is certified
//    to meet (a box vertex in the cylinder, either centre in the other shape, or the
//    best candidate's witnesses in both), and elsewhere at most the larger of that and
//    the distance of a point pair of the two shapes (which bounds the distance if they
//    are apart): the pair from three alternating nearest-point steps starting at the
//    box centre, whose direction is also offered as a candidate (it usually separates
//    a lane that is apart, which then needs no slot at all).
// Those are all the pieces: the cylinder's normal sets are the cap normals, the
// horizontal circle (side lines) and the half spheres' open quarter arcs (rim points);
// the box's the face normals, the quarter arcs of the edges and the vertices' regions.
// A candidate counts as the minimiser only where its witnesses x on the box and y on the
// cylinder (points of the two support features) satisfy x - y = o n within kSlackRel of
// the pair's size (the Minkowski point along n: a critical point of the distance from
// the origin to the piece; x and y are then supports along +-n). Near the minimum o is
// flat, and a candidate off its piece could tie the true one within rounding with a
// direction 1e-4 rad off. The least o of every candidate, valid or not, is kept as well
// (an exact upper bound): where it is below the least valid o by more than rounding, it
// is the answer, with its own witness. Ties keep the first in the order caps, faces,
// edge-sides, vertex-sides, the point pair's direction, vertex-rims, edge-rims. The
// point pair runs only on lanes not certified to meet, the vertex-rims only on those of
// them that it did not separate. Supports with ties (a face or line
// parallel to n) take the feature's point nearest the other shape's centre line
// (kFree: |n.a| at or below it counts as parallel).
// Contact points: one, midway between the witnesses. Where n is within kParallelSin of
// the axis (a cap): the box face most aligned with n, seen along n on the cap plane,
// clipped to the disk (its corners inside, its edges' rim crossings, 8 rim samples
// inside it) with each point's gap along n, reduced to 4 (reduce4). Where n is within
// kParallelSin of the horizontal (the side): the side's line along n clipped to that
// face, and the face's edges clipped to the side's height (depth = where the line from
// the point along -n leaves the cylinder), reduced to 4. Points with no positive gap
// are dropped; the witness stays only where no other point is as deep.
// Preconditions: finite inputs, positive sizes, unit axes, orthonormal R. Degenerate
// input: an edge along the axis takes x as its horizontal normal; a vertex on the axis
// takes x as its radial direction; coincident centres give a finite unit normal (the
// ties above decide it).
// Cost: 22 candidate directions in closed form per lane: the caps and faces (10) on
// every lane, the edges and vertices against the side (12) only on the lanes those do
// not certify apart, listed per chunk and run W at a time (gathered geometry and best,
// written back per lane) (+ the point
// pair where the lane is not certified to meet, + the vertex-rims where the point pair
// did not separate it:
// ~5% of the bench's lanes, in ~54% of its blocks; the support test above drops most
// vertex-rims of such a block), the pruned rim solves packed
// (at most kArcIterations steps of 3 divisions and 2 square roots each; in the bench ~1.1
// slots per lane, 2.3 before the cone bound and the point pair), the two manifold clips
// only where a lane of the block needs them; a block whose lanes are all farther
// apart than their bounding spheres stops at that screen.
// Both paths run the same template (F = FloatW, or Float1 for the scalar reference); a
// lane's arithmetic is the same wherever it is packed, so its bytes do not depend on its
// neighbours.
// References: Minkowski-difference support functions for penetration depth (van den
// Bergen, Collision Detection in Interactive 3D Environments, 2003, ch. 4); the
// secular equation of the point-ellipse distance (Eberly, "Distance from a Point to an
// Ellipse, an Ellipsoid, or a Hyperellipsoid", Geometric Tools, 2013).
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

/// Witness tests accept x - y = o n within this times the pair's size.
constexpr float kSlackRel = 4e-6f;
/// |n.a| at or below this: the box's support feature extends along a (and likewise
/// the cylinder's along z / across the cap).
constexpr float kFree = 1e-6f;
/// |sin| between n and the axis (the cap plane) below which the contact is a cap (side)
/// contact with a clipped manifold.
constexpr float kParallelSin = 0.05f;
constexpr float kNever = 3.0e38f;
/// Edge-rim slots per lane: 3 directions x 4 edges x 2 rims.
constexpr int kSlots = 24;

/// Per-slot constants: the edge's direction i, the signs of the other two axes
/// (j = i + 1, k = i + 2 mod 3), the rim slot (0: the rim's shadow's upper half).
struct SlotTable {
  float dir[kSlots], sj[kSlots], sk[kSlots], slot[kSlots];
  constexpr SlotTable() : dir(), sj(), sk(), slot() {
    for (int s = 0; s < kSlots; ++s) {
      dir[s] = static_cast<float>(s >> 3);
      sj[s] = (s & 2) != 0 ? -1.0f : 1.0f;
      sk[s] = (s & 4) != 0 ? -1.0f : 1.0f;
      slot[s] = static_cast<float>(s & 1);
    }
  }
};
constexpr SlotTable kSlotTable{};

/// One lane's pair in the cylinder frame.
template <class F>
struct Geo {
  V3<F> c;     // box centre
  V3<F> a[3];  // box axes
  F e[3];      // half extents
  F rc, h;
};

template <class F>
IMPACT_INLINE Geo<F> load_geo(const LeafSoA& a, const LeafSoA& b, uint32_t k, V3<F>& cb, M3<F>& rot) {
  Geo<F> g;
  cb = load_p<F>(b, k) - load_p<F>(a, k);
  rot = load_r<F>(b, k);
  const M3<F> ra = load_r<F>(a, k);
  g.c = rot.apply_t(-cb);
  for (int i = 0; i < 3; ++i) g.a[i] = rot.apply_t(ra.c[i]);
  g.e[0] = ld<F>(a.e[0], k), g.e[1] = ld<F>(a.e[1], k), g.e[2] = ld<F>(a.e[2], k);
  g.rc = ld<F>(b.e[0], k), g.h = ld<F>(b.e[1], k);
  return g;
}

/// o(n) for unit n.
template <class F>
IMPACT_INLINE F score(const Geo<F>& g, const V3<F>& n) {
  F s = dot(n, g.c);
  for (int i = 0; i < 3; ++i) s = s + g.e[i] * abs(dot(n, g.a[i]));
  return s + g.h * abs(n.z) + g.rc * sqrt(n.x * n.x + n.y * n.y);
}

/// o(n) and o(-n) for unit n: the even part plus / minus n.c.
template <class F>
IMPACT_INLINE void score_pm(const Geo<F>& g, const V3<F>& n, F& plus, F& minus) {
  F s = g.h * abs(n.z) + g.rc * sqrt(n.x * n.x + n.y * n.y);
  for (int i = 0; i < 3; ++i) s = s + g.e[i] * abs(dot(n, g.a[i]));
  const F nc = dot(n, g.c);
  plus = s + nc, minus = s - nc;
}

/// score_pm for a horizontal unit n = (nx, ny, 0): the cap term drops and |n_xy| = 1
/// (to rounding: the overlap along the unrounded unit direction).
template <class F>
IMPACT_INLINE void score_h_pm(const Geo<F>& g, F nx, F ny, F& plus, F& minus) {
  F s = g.rc;
  for (int i = 0; i < 3; ++i) s = s + g.e[i] * abs(nx * g.a[i].x + ny * g.a[i].y);
  const F nc = nx * g.c.x + ny * g.c.y;
  plus = s + nc, minus = s - nc;
}

template <class F>
IMPACT_INLINE F pair_slack(const Geo<F>& g) {
  const F cm = max(max(abs(g.c.x), abs(g.c.y)), abs(g.c.z));
  return F(kSlackRel) * (g.rc + g.h + g.e[0] + g.e[1] + g.e[2] + cm);
}

/// x - y = o n within slack, x in the box, y in the cylinder (each within slack).
template <class F>
IMPACT_INLINE typename F::Mask witnessed(const Geo<F>& g, F slack, F o, const V3<F>& n, const V3<F>& x,
                                         const V3<F>& y) {
  const V3<F> r = x - y - o * n;
  auto m = length_sq(r) <= slack * slack;
  const V3<F> q = x - g.c;
  for (int i = 0; i < 3; ++i) m = m & (abs(dot(q, g.a[i])) <= g.e[i] + slack);
  const F rr = g.rc + slack;
  m = m & (y.x * y.x + y.y * y.y <= rr * rr) & (abs(y.z) <= g.h + slack);
  return m;
}

/// The least valid candidate (o, n, box witness x) and the least of all (any_*).
template <class F>
using Best = WitnessedBest<F>;

/// The cylinder's support point along -n nearest (in its support feature) to the point f.
template <class F>
IMPACT_INLINE V3<F> cyl_support_near(const Geo<F>& g, const V3<F>& n, const V3<F>& f) {
  const F one(1.0f), zero(0.0f);
  const F nxy2 = n.x * n.x + n.y * n.y;
  const auto disk = nxy2 <= F(kFree * kFree);
  const F inv = one / sqrt(select(disk, one, nxy2));
  // across the cap: f's shadow clamped to the disk
  const F f2 = f.x * f.x + f.y * f.y;
  const F fs = select(f2 > g.rc * g.rc, g.rc / sqrt(select(f2 > zero, f2, one)), one);
  V3<F> y;
  y.x = select(disk, f.x * fs, -g.rc * n.x * inv);
  y.y = select(disk, f.y * fs, -g.rc * n.y * inv);
  y.z = select(abs(n.z) <= F(kFree), clamp(f.z, -g.h, g.h), -g.h * simd::sign_nonneg(n.z));
  return y;
}

/// The box's support point along n nearest (in its support feature) to the axis.
template <class F>
IMPACT_INLINE V3<F> box_support_near_axis(const Geo<F>& g, const V3<F>& n) {
  typename F::Mask freei[3];
  V3<F> p = g.c;
  for (int i = 0; i < 3; ++i) {
    const F d = dot(n, g.a[i]);
    freei[i] = abs(d) <= F(kFree);
    p = select(freei[i], p, madd(p, simd::sign_nonneg(d) * g.e[i], g.a[i]));
  }
  for (int i = 0; i < 3; ++i) {
    const F t = clamp(-(p.x * g.a[i].x + p.y * g.a[i].y), -g.e[i], g.e[i]);
    p = select(freei[i], madd(p, t, g.a[i]), p);
  }
  return p;
}

template <class F>
IMPACT_INLINE V3<F> box_support(const Geo<F>& g, const V3<F>& n) {
  V3<F> p = g.c;
  for (int i = 0; i < 3; ++i) p = madd(p, simd::sign_nonneg(dot(n, g.a[i])) * g.e[i], g.a[i]);
  return p;
}

// ---------------------------------------------------------------------------------------
// Chunk state: phase A (closed-form candidates) writes it, phase B (packed rim solves)
// updates it, phase C (manifold) reads it.
// ---------------------------------------------------------------------------------------

template <uint32_t W>
struct Chunk {
  static constexpr uint32_t kLanes = 16 * W;
  // Rows kLanes + 16 floats apart: 1088 bytes at W = 16, so a lane's rows sit in
  // different L1 sets (1024 apart, every fourth row shared one; docs/narrowphase.md,
  // "Array layout").
  static constexpr uint32_t kRow = kLanes + 16;
  // geometry: c 0..2, a 3..11, e 12..14, rc 15, h 16
  float geo[17][kRow];
  // best: o 0, n 1..3, x 4..6, any_o 7, any_n 8..10, any_x 11..13
  float st[14][kRow];
  // lanes phase B's first step runs on (phase A lists them)
  int32_t live[kLanes + W];
  uint32_t nlive = 0;
  int32_t lane[kSlots * kLanes + 4 * W];
  int32_t kind[kSlots * kLanes + 4 * W];
  uint32_t nitems = 0;
};

template <class F, uint32_t W>
IMPACT_INLINE void save_geo(Chunk<W>& ch, uint32_t j, const Geo<F>& g) {
  g.c.x.store(ch.geo[0] + j), g.c.y.store(ch.geo[1] + j), g.c.z.store(ch.geo[2] + j);
  for (int i = 0; i < 3; ++i) {
    g.a[i].x.store(ch.geo[3 + 3 * i] + j);
    g.a[i].y.store(ch.geo[4 + 3 * i] + j);
    g.a[i].z.store(ch.geo[5 + 3 * i] + j);
  }
  for (int i = 0; i < 3; ++i) g.e[i].store(ch.geo[12 + i] + j);
  g.rc.store(ch.geo[15] + j), g.h.store(ch.geo[16] + j);
}

/// A Geo from the chunk's 17 geometry rows (save_geo's layout), row f read by get(f).
template <class F, class Get>
IMPACT_INLINE Geo<F> read_geo(const Get& get) {
  Geo<F> g;
  g.c = V3<F>{get(0), get(1), get(2)};
  for (int i = 0; i < 3; ++i) g.a[i] = V3<F>{get(3 + 3 * i), get(4 + 3 * i), get(5 + 3 * i)};
  for (int i = 0; i < 3; ++i) g.e[i] = get(12 + i);
  g.rc = get(15), g.h = get(16);
  return g;
}

template <class F, uint32_t W>
IMPACT_INLINE Geo<F> gather_geo(const Chunk<W>& ch, typename F::Int idx) {
  // Ascending chunk lanes (listed in order): read by windows (simd::SortedGather).
  const simd::SortedGather<F::kWidth> rows(idx, 0, static_cast<int32_t>(std::size(ch.geo[0])));
  return read_geo<F>([&](int f) IMPACT_LAMBDA_INLINE { return rows(ch.geo[f]); });
}

/// Phase A for one block (lanes k.. of a / b, chunk lanes j..): the caps' and faces'
/// candidates; the lanes they do not certify apart listed for rest_a.
template <class F, uint32_t W>
IMPACT_INLINE void phase_a(const LeafSoA& a, const LeafSoA& b, uint32_t k, uint32_t j, uint32_t nb,
                           Chunk<W>& ch) {
  using Mask = typename F::Mask;
  const F zero(0.0f);
  V3<F> cb;
  M3<F> rot;
  const Geo<F> g = load_geo<F>(a, b, k, cb, rot);
  save_geo<F, W>(ch, j, g);
  Best<F> best;
  best.init();
  // Every lane's bounding spheres apart: no contact (o = -1 marks it).
  const F reach = sqrt(g.e[0] * g.e[0] + g.e[1] * g.e[1] + g.e[2] * g.e[2]) + sqrt(g.rc * g.rc + g.h * g.h);
  const Mask near = length_sq(cb) < reach * reach;
  if (simd::none(near)) {
    best.o = best.any_o = F(-1.0f);
    save_best<F>(ch.st, j, best);
    return;
  }
  const F slack = pair_slack(g);
  const V3<F> A[3] = {g.a[0] * g.e[0], g.a[1] * g.e[1], g.a[2] * g.e[2]};
  const F ext_z = g.e[0] * abs(g.a[0].z) + g.e[1] * abs(g.a[1].z) + g.e[2] * abs(g.a[2].z);

  // --- caps: n = +-z; x: the box's support feature's point nearest the axis ---
  for (int s = 0; s < 2; ++s) {
    const F sg(s == 0 ? 1.0f : -1.0f);
    const V3<F> n{zero, zero, sg};
    const F o = sg * g.c.z + ext_z + g.h;
    const V3<F> x = box_support_near_axis(g, n);  // y = x - o n: on the cap plane
    const F rr = g.rc + slack;
    best.take(o, n, x, x.x * x.x + x.y * x.y <= rr * rr);
  }
  // --- faces: n = +-a_i; y: the cylinder's support feature's point nearest the face
  // centre, x above it on the face plane ---
  for (int i = 0; i < 3; ++i) {
    F op, om;
    score_pm(g, g.a[i], op, om);
    for (int s = 0; s < 2; ++s) {
      const V3<F> n = s == 0 ? g.a[i] : -g.a[i];
      const F o = s == 0 ? op : om;
      const V3<F> f = s == 0 ? g.c + A[i] : g.c - A[i];
      const V3<F> y = cyl_support_near(g, n, f);
      const V3<F> x = madd(y, o, n);  // on the face's plane: in the box where in the face
      const V3<F> q = x - f;
      const int j1 = (i + 1) % 3, j2 = (i + 2) % 3;
      best.take(o, n, x,
                (abs(dot(q, g.a[j1])) <= g.e[j1] + slack) & (abs(dot(q, g.a[j2])) <= g.e[j2] + slack));
    }
  }
  // --- the lanes not yet certified apart (some o <= 0) go on to the rest, packed
  // (phase B) ---
  list_lanes<F>(ch.live, ch.nlive, near & (best.any_o > zero), j, nb);
  save_best_near<F>(ch.st, j, best, near);
}

/// Phase B, first step, for W listed lanes (idx; the first `real` are the list's, the
/// rest repeat the last): the candidates after the caps and faces (edges and vertices
/// against the side, the point pair and the vertex-rims where the lane may be apart),
/// then the edge-rim slots each lane still needs, appended to the chunk; the lanes' best
/// goes back to the chunk's rows.
template <class F, uint32_t W>
IMPACT_INLINE void rest_a(Chunk<W>& ch, typename F::Int idx, uint32_t real, uint32_t& cnt) {
  using Mask = typename F::Mask;
  using Int = typename F::Int;
  const F zero(0.0f), one(1.0f), tiny(kTinySq), never(kNever);
  const Geo<F> g = gather_geo<F, W>(ch, idx);
  Best<F> best = gather_best<F>(ch.st, idx);
  const uint32_t keep = real < W ? (1u << real) - 1u : ~0u;
  const F slack = pair_slack(g);
  const V3<F> ez{zero, zero, one};
  // x and y built inside their shapes: only x - y = o n is left to test
  auto along = [&](F o, const V3<F>& n, const V3<F>& x, const V3<F>& y) IMPACT_LAMBDA_INLINE {
    return length_sq(x - y - o * n) <= slack * slack;
  };
  auto consider = [&](F o, const V3<F>& n, const V3<F>& x, const V3<F>& y) IMPACT_LAMBDA_INLINE {
    best.take(o, n, x, along(o, n, x, y));
  };
  const V3<F> A[3] = {g.a[0] * g.e[0], g.a[1] * g.e[1], g.a[2] * g.e[2]};
  // --- edge x side: n = +-(a_i x z) / |.|, the edge against the side line ---
  for (int i = 0; i < 3; ++i) {
    const V3<F>& u = g.a[i];
    const F uxy2 = u.x * u.x + u.y * u.y;
    const Mask tilted = uxy2 > tiny;
    const F inv = one / sqrt(select(tilted, uxy2, one));
    const F wx = select(tilted, u.y * inv, one), wy = select(tilted, -u.x * inv, zero);
    F op, om;
    score_h_pm(g, wx, wy, op, om);
    for (int s = 0; s < 2; ++s) {
      const F sg(s == 0 ? 1.0f : -1.0f);
      const V3<F> n{sg * wx, sg * wy, zero};
      const F o = s == 0 ? op : om;
      V3<F> pe = g.c;
      for (int q = 1; q < 3; ++q) {
        const int jj = (i + q) % 3;
        pe = madd(pe, simd::sign_nonneg(dot(n, g.a[jj])), A[jj]);
      }
      const V3<F> g0{-g.rc * n.x, -g.rc * n.y, zero};
      const V3<F> r = pe - g0;
      const F bz = u.z, d1 = dot(u, r);
      const F den = one - bz * bz;
      const F sv = clamp((bz * r.z - d1) / select(tilted, den, one), -g.e[i], g.e[i]);
      const V3<F> x = madd(pe, sv, u);
      const V3<F> y{g0.x, g0.y, clamp(x.z, -g.h, g.h)};
      consider(o, n, x, y);
    }
  }
  // --- vertices against the side: n horizontal, from the vertex towards the axis ---
  V3<F> vtx[8];
  F vrho[8], vmx[8], vmy[8];
  for (int q = 0; q < 8; ++q) {
    V3<F> v = g.c;
    for (int i = 0; i < 3; ++i) v = (q >> i) & 1 ? v - A[i] : v + A[i];
    const F rho2 = v.x * v.x + v.y * v.y;
    const Mask off = rho2 > tiny;
    const F rho = sqrt(rho2);
    const F ri = one / select(off, rho, one);
    const F mx = select(off, v.x * ri, one), my = select(off, v.y * ri, zero);
    vtx[q] = v, vrho[q] = rho, vmx[q] = mx, vmy[q] = my;
    const V3<F> n{-mx, -my, zero};
    const V3<F> y{g.rc * mx, g.rc * my, clamp(v.z, -g.h, g.h)};
    F o, o_flip;
    score_h_pm(g, -mx, -my, o, o_flip);
    consider(o, n, v, y);
  }
  // Certified to meet: a vertex in the cylinder, either centre in the other shape, or
  // the best valid candidate's witnesses in both shapes.
  Mask meets(false);
  for (int q = 0; q < 8; ++q) meets = meets | ((vrho[q] <= g.rc) & (abs(vtx[q].z) <= g.h));
  {
    Mask inb(true);
    for (int i = 0; i < 3; ++i) inb = inb & (abs(dot(g.c, g.a[i])) <= g.e[i]);
    const Mask cin = (g.c.x * g.c.x + g.c.y * g.c.y <= g.rc * g.rc) & (abs(g.c.z) <= g.h);
    meets = meets | inb | cin;
    const Mask has = best.o < never;
    const V3<F>& x = best.x;
    const V3<F> y = x - best.o * best.n;
    const Mask x_in = (x.x * x.x + x.y * x.y <= g.rc * g.rc) & (abs(x.z) <= g.h);
    Mask y_in(true);
    const V3<F> q = y - g.c;
    for (int i = 0; i < 3; ++i) y_in = y_in & (abs(dot(q, g.a[i])) <= g.e[i]);
    meets = meets | (has & (x_in | y_in));
  }
  const Mask live = best.any_o > zero;
  // Lanes not certified to meet; the two passes below run where a block has one, and
  // count only on those lanes (a lane's bytes must not depend on its neighbours).
  const Mask uncertified = live & ~meets;
  // --- lanes that may be apart: a point pair (x in the box, y in the cylinder) by
  // alternating nearest points from the box centre. |x - y| bounds the distance, and
  // the direction y - x usually separates (o <= 0: the lane is done) ---
  Mask live2 = live;
  F apart_bound = best.o;
  if (simd::any(uncertified)) {
    auto to_cyl = [&](const V3<F>& p) IMPACT_LAMBDA_INLINE {
      const F r2 = p.x * p.x + p.y * p.y;
      const F sc = select(r2 > g.rc * g.rc, g.rc / sqrt(select(r2 > zero, r2, one)), one);
      return V3<F>{p.x * sc, p.y * sc, clamp(p.z, -g.h, g.h)};
    };
    auto to_box = [&](const V3<F>& p) IMPACT_LAMBDA_INLINE {
      const V3<F> q = p - g.c;
      V3<F> x = g.c;
      for (int i = 0; i < 3; ++i) x = madd(x, clamp(dot(q, g.a[i]), -g.e[i], g.e[i]), g.a[i]);
      return x;
    };
    V3<F> y = to_cyl(g.c);
    V3<F> x = to_box(y);
    y = to_cyl(x);
    x = to_box(y);
    y = to_cyl(x);
    F len;
    const V3<F> n = normalize_or(y - x, ez, len);
    best.take(select(uncertified, score(g, n), never), n, x, Mask(false));
    live2 = best.any_o > zero;
    apart_bound = select(uncertified, min(apart_bound, len), apart_bound);
  }

  // --- vertices against the rims (n from the rim point nearest the vertex): an edge of
  // box - C, a minimiser only when the pair is apart, so only where it is not certified
  // to meet, and only on lanes the point pair did not separate ---
  const Mask unseparated = uncertified & live2;
  if (simd::any(unseparated)) {
    for (int q = 0; q < 8; ++q) {
      const V3<F>& v = vtx[q];
      const F mx = vmx[q], my = vmy[q];
      for (int s = 0; s < 2; ++s) {
        const F zs(s == 0 ? 1.0f : -1.0f);
        const V3<F> y{g.rc * mx, g.rc * my, zs * g.h};
        const F radial = abs(vrho[q] - g.rc), vert = abs(v.z - zs * g.h);
        const V3<F> nu{-radial * mx, -radial * my, -zs * vert};
        const V3<F> fb{-mx * F(0.70710678f), -my * F(0.70710678f), -zs * F(0.70710678f)};
        // The piece holds the minimiser only where v is the box's support along n
        // (sigma_i n.a_i >= 0, loosely: rounding); elsewhere the candidate is skipped,
        // and where no lane of the block keeps it, so is its arithmetic.
        const V3<F> nc = select(length_sq(nu) < tiny, fb, nu);
        const F tol = F(-1e-3f) * (abs(nc.x) + abs(nc.y) + abs(nc.z));
        Mask cone = unseparated;
        for (int i = 0; i < 3; ++i) {
          const F d = dot(nc, g.a[i]);
          cone = cone & (((q >> i) & 1 ? -d : d) >= tol);
        }
        if (simd::none(cone)) continue;
        F len;
        const V3<F> n = normalize_or(nu, fb, len);
        consider(select(cone, score(g, n), never), n, v, y);
      }
    }
    live2 = best.any_o > zero;
    apart_bound = min(apart_bound, best.o);
  }

  // --- which edge-rim slots each lane still needs ---
  // A slot's candidate has o = |x - y| for x on the edge, y on the rim: at least lb, a
  // lower bound of the edge-to-rim distance. Where the pair meets, it only matters below
  // every candidate's o (any_o >= the least o); where it may be apart, it also matters as
  // the closest features, no farther apart than a point pair of the two shapes.
  const F bound = select(meets, best.any_o, max(best.any_o, apart_bound)) + slack;
  for (int i = 0; i < 3; ++i) {
    const V3<F>& u = g.a[i];
    const int ja = (i + 1) % 3, ka = (i + 2) % 3;
    const F uxy2 = u.x * u.x + u.y * u.y;
    const Mask tilted = uxy2 > tiny;
    const F iu = one / select(tilted, uxy2, one);
    for (int q = 0; q < 4; ++q) {
      const F sj((q & 1) != 0 ? -1.0f : 1.0f), sk((q & 2) != 0 ? -1.0f : 1.0f);
      const V3<F> pe = madd(madd(g.c, sj, A[ja]), sk, A[ka]);
      // the edge's end points (vertices)
      const int qv = (((q & 1) != 0 ? 1 : 0) << ja) | (((q & 2) != 0 ? 1 : 0) << ka);
      const F rho_p = vrho[qv], rho_m = vrho[qv | (1 << i)];
      const F z_p = vtx[qv].z, z_m = vtx[qv | (1 << i)].z;
      const F ts = clamp(select(tilted, -(pe.x * u.x + pe.y * u.y) * iu, zero), -g.e[i], g.e[i]);
      const F mx = mul_add(ts, u.x, pe.x), my = mul_add(ts, u.y, pe.y);
      const F rho_min = sqrt(mx * mx + my * my);
      const F lb_r = max(max(rho_min - g.rc, g.rc - max(rho_p, rho_m)), zero);
      const F za = sj * g.a[ja].z, zk = sk * g.a[ka].z;
      // o on the edge's normal cone (n = cos t sj a_ja + sin t sk a_ka, t in [0, pi/2]):
      // the box's part A cos t + B sin t is least at an end unless both ends are
      // negative; the cylinder's h |n_z| + rc |n_xy| is at least min(h, rc).
      const F ea = g.e[ja] + sj * dot(g.a[ja], g.c), eb = g.e[ka] + sk * dot(g.a[ka], g.c);
      // (box_min <= lim, box_min = -sqrt(ea^2 + eb^2) where both are negative: lim >= 0,
      // or lim^2 <= ea^2 + eb^2, without the root)
      const F lim = best.any_o + slack - min(g.h, g.rc);
      const Mask both_neg = (ea <= zero) & (eb <= zero);
      const Mask arc_ok = (both_neg & ((lim >= zero) | (lim * lim <= ea * ea + eb * eb))) |
                          andnot(min(ea, eb) <= lim, both_neg);
      for (int s = 0; s < 2; ++s) {
        // slot 0: n_z >= 0 (the rim at -h); slot 1: n_z <= 0 (the rim at +h)
        const F z0(s == 0 ? -1.0f : 1.0f);
        const F rz = z0 * g.h;
        const F dp = z_p - rz, dm = z_m - rz;
        const F lb_z = select(dp * dm <= zero, zero, min(abs(dp), abs(dm)));
        // |x - y|^2 >= (rho(x) - rc)^2 + (x.z - rz)^2, each term bounded along the edge
        // (compared squared: bound > 0 on the live lanes, where any_o > 0)
        const F lb2 = lb_r * lb_r + lb_z * lb_z;
        const F cone_eps(-1e-6f);
        const Mask cone =
            s == 0 ? ((za >= cone_eps) | (zk >= cone_eps)) : ((za <= -cone_eps) | (zk <= -cone_eps));
        const Mask need = live2 & arc_ok & cone & (lb2 <= bound * bound);
        const uint32_t bits = simd::bits(need) & keep;
        // (branch-free: which slots a lane keeps is close to random)
        Int(static_cast<int32_t>(8 * i + 2 * q + s)).store(ch.kind + cnt);
        cnt += simd::compact_store(ch.lane + cnt, idx, bits);
      }
    }
  }
  scatter_best<F>(ch.st, idx, real, best);  // back to the chunk's rows, the listed lanes only
}

/// Phase B, one batch: M groups of W listed edge-rim slots from item g0 (their solves
/// interleaved: independent chains, so the divisions and square roots overlap); each
/// result offered to its lane, in list order.
template <class F, uint32_t W, int M>
IMPACT_INLINE void solve_batch(Chunk<W>& ch, uint32_t g0, uint32_t total) {
  using Int = typename F::Int;
  using Mask = typename F::Mask;
  const F zero(0.0f), one(1.0f), tiny(kTinySq);
  Geo<F> g[M];
  V3<F> u[M], pe[M], w[M], v[M];
  F eu[M], rb[M], rx[M], ry[M], ex[M], ey[M], sg[M];
  for (int m = 0; m < M; ++m) {
    const uint32_t at = g0 + static_cast<uint32_t>(m) * W;
    const Int idx = Int::load(ch.lane + at), kind = Int::load(ch.kind + at);
    g[m] = gather_geo<F, W>(ch, idx);
    const F dir = simd::gather(kSlotTable.dir, kind), sj = simd::gather(kSlotTable.sj, kind);
    const F sk = simd::gather(kSlotTable.sk, kind), slot = simd::gather(kSlotTable.slot, kind);
    const Mask d0 = dir == zero, d1 = dir == one;
    u[m] = select(d0, g[m].a[0], select(d1, g[m].a[1], g[m].a[2]));
    const V3<F> aj = select(d0, g[m].a[1], select(d1, g[m].a[2], g[m].a[0]));
    const V3<F> ak = select(d0, g[m].a[2], select(d1, g[m].a[0], g[m].a[1]));
    eu[m] = select(d0, g[m].e[0], select(d1, g[m].e[1], g[m].e[2]));
    const F ej = select(d0, g[m].e[1], select(d1, g[m].e[2], g[m].e[0]));
    const F ek = select(d0, g[m].e[2], select(d1, g[m].e[0], g[m].e[1]));
    pe[m] = madd(madd(g[m].c, sj * ej, aj), sk * ek, ak);
    // the shadow along u: w = z x u / |z x u| (x for an edge along the axis), v = u x w
    const F uxy2 = u[m].x * u[m].x + u[m].y * u[m].y;
    const Mask tl = uxy2 > tiny;
    const F ie = one / sqrt(select(tl, uxy2, one));
    w[m] = V3<F>{select(tl, -u[m].y * ie, one), select(tl, u[m].x * ie, zero), zero};
    v[m] = cross(u[m], w[m]);
    v[m] = select(v[m].z < zero, -v[m], v[m]);
    const F inv_rc = one / g[m].rc;
    const F lr = g[m].h * v[m].z * inv_rc;
    const F by = -dot(pe[m], v[m]) * inv_rc;
    const Mask top = slot == zero;
    rb[m] = abs(u[m].z);
    rx[m] = -dot(pe[m], w[m]) * inv_rc;
    ry[m] = select(top, by - lr, -(by + lr));
    sg[m] = select(top, one, F(-1.0f));
  }
  rim::half_ellipse_normals(rb, rx, ry, ex, ey);
  for (int m = 0; m < M; ++m) {
    const uint32_t at = g0 + static_cast<uint32_t>(m) * W;
    F len;
    const V3<F> n = normalize_or(madd(w[m] * ex[m], sg[m] * ey[m], v[m]), w[m], len);
    const F o = score(g[m], n);
    // witnesses: the rim point along -n, the edge point level with it
    const F nxy2 = n.x * n.x + n.y * n.y;
    const F sr = g[m].rc / sqrt(select(nxy2 > tiny, nxy2, one));
    const V3<F> y{-sr * n.x, -sr * n.y, -g[m].h * simd::sign_nonneg(n.z)};
    const F tw = clamp(dot(y - pe[m], u[m]), -eu[m], eu[m]);
    const V3<F> x = madd(pe[m], tw, u[m]);
    const Mask valid = witnessed(g[m], pair_slack(g[m]), o, n, x, y);
    const uint32_t cnt = at >= total ? 0u : (total - at < W ? total - at : W);
    merge_best(ch.st, ch.lane + at, cnt, o, n, x, valid);
  }
}

/// Phase B: the listed edge-rim slots, padded to whole groups (repeating the last),
/// solved 4 groups at a time, then 2, then 1.
template <class F, uint32_t W>
IMPACT_INLINE void phase_b(Chunk<W>& ch) {
  if (ch.nlive == 0) return;
  uint32_t cnt = 0;
  for_each_listed<F>(ch.live, ch.nlive,
                     [&](typename F::Int idx, uint32_t real) { rest_a<F, W>(ch, idx, real, cnt); });
  ch.nlive = 0;
  ch.nitems = cnt;
  const uint32_t total = ch.nitems;
  if (total == 0) return;
  const uint32_t groups = (total + W - 1) / W;
  for (uint32_t l = total; l < groups * W; ++l)
    ch.lane[l] = ch.lane[total - 1], ch.kind[l] = ch.kind[total - 1];
  uint32_t gi = 0;
  for (; gi + 4 <= groups; gi += 4) solve_batch<F, W, 4>(ch, gi * W, total);
  if (gi + 2 <= groups) solve_batch<F, W, 2>(ch, gi * W, total), gi += 2;
  if (gi < groups) solve_batch<F, W, 1>(ch, gi * W, total);
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
  // phase A's geometry, kept in the chunk (the same floats, not recomputed)
  const V3<F> cb = load_p<F>(b, k) - load_p<F>(a, k);
  const M3<F> rot = load_r<F>(b, k);
  const Geo<F> g = read_geo<F>([&](int f) IMPACT_LAMBDA_INLINE { return F::load(ch.geo[f] + j); });
  const F slack = pair_slack(g);
  // The least valid candidate, unless an invalid one is below it by more than rounding.
  const Mask use_any = (best.o >= never) | (best.any_o < best.o - F(4.0f) * slack);
  const F o = select(use_any, best.any_o, best.o);
  const V3<F> n = select(use_any, best.any_n, best.n);
  const V3<F> x = select(use_any, best.any_x, best.x);
  const Mask hit = o > zero;
  const F size = g.rc + g.h + g.e[0] + g.e[1] + g.e[2];
  const F tol = F(1e-5f) * size;
  const F nxy2 = n.x * n.x + n.y * n.y;
  const F par2(kParallelSin * kParallelSin);

  Lanes<F, 4> m;
  {
    const V3<F> p1 = madd(x, F(-0.5f) * o, n);
    m.count = select(hit, Int(1), Int(0));
    for (int i = 0; i < 4; ++i) m.point[i] = p1, m.pdepth[i] = o;
  }
  // The box face most aligned with n (outward normal f = s a_i), its centre and corners.
  F al[3];
  for (int i = 0; i < 3; ++i) al[i] = dot(n, g.a[i]);
  const Mask f0 = (abs(al[0]) >= abs(al[1])) & (abs(al[0]) >= abs(al[2]));
  const Mask f1 = andnot(abs(al[1]) >= abs(al[2]), f0);
  const V3<F> fa = select(f0, g.a[0], select(f1, g.a[1], g.a[2]));
  const V3<F> ua = select(f0, g.a[1], select(f1, g.a[2], g.a[0]));
  const V3<F> va = select(f0, g.a[2], select(f1, g.a[0], g.a[1]));
  const F fe = select(f0, g.e[0], select(f1, g.e[1], g.e[2]));
  const F ue = select(f0, g.e[1], select(f1, g.e[2], g.e[0]));
  const F ve = select(f0, g.e[2], select(f1, g.e[0], g.e[1]));
  const F fs = simd::sign_nonneg(dot(n, fa));
  const V3<F> fn = fa * fs;  // outward, along n
  const V3<F> fc = madd(g.c, fs * fe, fa);
  V3<F> corner[4];
  {
    const V3<F> U = ua * ue, Vv = va * ve;
    corner[0] = fc + U + Vv, corner[1] = fc - U + Vv, corner[2] = fc - U - Vv, corner[3] = fc + U - Vv;
  }
  const F fdn = dot(fn, n);

  // Cap contact: the face seen along n on the cap plane z = zc facing the box, clipped
  // to the disk, each point with its gap along n.
  // (only where a face or an edge of the box lies within kParallelSin of the cap plane:
  // else the box touches the cap at a vertex, one point)
  const F amin = min(min(abs(al[0]), abs(al[1])), abs(al[2]));
  const Mask cap_like = hit & (nxy2 < par2) & (amin < F(kParallelSin));
  if (simd::any(cap_like)) {
    constexpr int M = 1 + 4 + 8 + kRimSamples;
    F cx[M], cy[M], cd[M];
    Mask cv[M];
    const F zc = -g.h * simd::sign_nonneg(n.z);
    const F nz = select(abs(n.z) > half, n.z, one);
    const F rr = g.rc * g.rc;
    const F rin = g.rc + slack;
    F px[4], py[4], pd[4];
    for (int q = 0; q < 4; ++q) {
      const F mu = (corner[q].z - zc) / nz;
      px[q] = corner[q].x - mu * n.x, py[q] = corner[q].y - mu * n.y, pd[q] = mu;
    }
    {
      const V3<F> y = x - o * n;
      cx[0] = y.x, cy[0] = y.y, cd[0] = o;
      cv[0] = y.x * y.x + y.y * y.y <= rin * rin;
    }
    for (int q = 0; q < 4; ++q) {
      cx[1 + q] = px[q], cy[1 + q] = py[q], cd[1 + q] = pd[q];
      cv[1 + q] = px[q] * px[q] + py[q] * py[q] <= rr;
    }
    for (int q = 0; q < 4; ++q) {
      const int q1 = (q + 1) % 4;
      const F dx = px[q1] - px[q], dy = py[q1] - py[q], dd = pd[q1] - pd[q];
      const F qa = dx * dx + dy * dy, qb = px[q] * dx + py[q] * dy, qc = px[q] * px[q] + py[q] * py[q] - rr;
      const F disc = qb * qb - qa * qc;
      const Mask ok = (qa > tiny) & (disc >= zero);
      const F root = sqrt(max(disc, zero)), ia = one / select(ok, qa, one);
      for (int c = 0; c < 2; ++c) {
        const F t = (c == 0 ? -qb - root : root - qb) * ia;
        const int i = 5 + 2 * q + c;
        cx[i] = mul_add(t, dx, px[q]), cy[i] = mul_add(t, dy, py[q]), cd[i] = mul_add(t, dd, pd[q]);
        cv[i] = ok & (t >= zero) & (t <= one);
      }
    }
    {
      // rim samples inside the face's shadow (a parallelogram, either orientation), with
      // the gap to the face plane along n (only for a face within 60 degrees of n)
      const Mask ok = fdn >= half;
      const F ifd = one / select(ok, fdn, one);
      const F fcd = dot(fn, fc);
      F cz[4];
      for (int i = 0; i < kRimSamples; ++i) {
        const F sx = g.rc * F(kRimCos[i]), sy = g.rc * F(kRimCos[(i + 6) % 8]);
        Mask pos(true), neg(true);
        for (int q = 0; q < 4; ++q) {
          const int q1 = (q + 1) % 4;
          cz[q] = (px[q1] - px[q]) * (sy - py[q]) - (py[q1] - py[q]) * (sx - px[q]);
          pos = pos & (cz[q] >= zero), neg = neg & (cz[q] <= zero);
        }
        const int c = 13 + i;
        cx[c] = sx, cy[c] = sy;
        cd[c] = (fcd - (fn.x * sx + fn.y * sy + fn.z * zc)) * ifd;
        cv[c] = ok & (pos | neg);
      }
    }
    cap_manifold_tail<F, M>(cx, cy, cd, cv, o, tol, zc, n, cap_like, m);
  }
  // Side contact: the side's line along -n clipped to the face seen along n, the face's
  // edges clipped to the side's height (each point's gap: where the line from it along
  // -n leaves the cylinder), the witness; reduced to 4.
  // (only where a face of the box lies within kParallelSin of the side, or an edge within
  // kParallelSin of the axis: else one point)
  const F azmax = max(max(abs(g.a[0].z), abs(g.a[1].z)), abs(g.a[2].z));
  const Mask side_like =
      andnot(hit & (n.z * n.z < par2) & ((fdn * fdn > one - par2) | (azmax * azmax > one - par2)), cap_like);
  if (simd::any(side_like)) {
    constexpr int M = 1 + 2 + 8;
    V3<F> ca[M];
    F cd[M];
    Mask cv[M];
    const Mask okxy = nxy2 > tiny;
    const F ixy = one / sqrt(select(okxy, nxy2, one));
    const F mx = select(okxy, n.x * ixy, one), my = select(okxy, n.y * ixy, zero);
    ca[0] = madd(x, F(-0.5f) * o, n), cd[0] = o, cv[0] = Mask(true);
    {
      // G(t) = (-rc m, t) + lam(t) n on the face plane: lam = lam0 + lam1 t
      const Mask flat = fdn > F(0.01f);
      const F inn = one / select(flat, fdn, one);
      const V3<F> s0{-g.rc * mx, -g.rc * my, zero};
      const F lam0 = dot(fn, fc - s0) * inn, lam1 = -fn.z * inn;
      F tlo = -g.h, thi = g.h;
      Mask ok = flat;
      for (int c = 0; c < 2; ++c) {
        const V3<F>& ax = c == 0 ? ua : va;
        const F ext = c == 0 ? ue : ve;
        // (G(t) + lam(t) n - fc).ax = g0 + g1 t in [-ext, ext]
        const F g0 = dot(s0 - fc, ax) + lam0 * dot(n, ax), g1 = ax.z + lam1 * dot(n, ax);
        const Mask moves = abs(g1) > tiny;
        const F ig = one / select(moves, g1, one);
        const F ta = (-ext - g0) * ig, tb = (ext - g0) * ig;
        tlo = select(moves, max(tlo, min(ta, tb)), tlo);
        thi = select(moves, min(thi, max(ta, tb)), thi);
        ok = ok & (moves | (abs(g0) <= ext));
      }
      ok = ok & (tlo <= thi);
      for (int c = 0; c < 2; ++c) {
        const F t = c == 0 ? tlo : thi;
        const F lam = mul_add(lam1, t, lam0);
        ca[1 + c] = madd(V3<F>{s0.x, s0.y, t}, half * lam, n);
        cd[1 + c] = lam;
        cv[1 + c] = ok;
      }
    }
    for (int q = 0; q < 4; ++q) {
      const V3<F>& p0 = corner[q];
      const V3<F> e = corner[(q + 1) % 4] - p0;
      const Mask rises = abs(e.z) > tiny;
      const F iz = one / select(rises, e.z, one);
      const F za = (-g.h - p0.z) * iz, zb = (g.h - p0.z) * iz;
      const F s0 = select(rises, max(min(za, zb), zero), zero);
      const F s1 = select(rises, min(max(za, zb), one), select(abs(p0.z) <= g.h, one, F(-1.0f)));
      for (int c = 0; c < 2; ++c) {
        V3<F> bq = madd(p0, c == 0 ? s0 : s1, e);
        const Mask within = abs(bq.z) <= g.h + slack;
        bq.z = clamp(bq.z, -g.h, g.h);
        const F bb = bq.x * n.x + bq.y * n.y, cc = bq.x * bq.x + bq.y * bq.y - g.rc * g.rc;
        const F d_side = (bb + sqrt(max(bb * bb - nxy2 * cc, zero))) / select(okxy, nxy2, one);
        const Mask up = abs(n.z) > tiny;
        const F d_cap = select(up, (bq.z + simd::sign_nonneg(n.z) * g.h) / select(up, n.z, one), F(3.0e38f));
        const F d = select(abs(n.z) * (d_side - d_cap) > slack, min(d_side, d_cap), d_side);
        const int i = 3 + 2 * q + c;
        ca[i] = madd(bq, F(-0.5f) * d, n), cd[i] = d;
        cv[i] = (s0 <= s1) & (cc <= zero) & within;
      }
    }
    side_manifold_tail<F, M, false>(ca, cd, cv, o, tol, mx, my, n, side_like, m);
  }

  m.count = select(hit, m.count, Int(0));
  // a single point carries the depth (a clip can leave one point a rounding short of it)
  m.pdepth[0] = select(m.count == Int(1), o, m.pdepth[0]);
  m.n = rot.apply(n);
  m.depth = o;
  for (int i = 0; i < 4; ++i) m.point[i] = cb + rot.apply(m.point[i]);
  store(out, k, m, load_p<F>(a, k));
}

template <class F>
void box_cylinder_range(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, Range r) {
  constexpr uint32_t W = F::kWidth;
  Chunk<W> ch;
  for_each_chunk<F, 4>(a, b, out, r, ch, phase_a<F, W>, phase_b<F, W>, phase_c<F, W>);
}

}  // namespace

void collide_box_cylinder(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, Range r,
                          const NarrowConfig& cfg) {
  if (cfg.path == KernelPath::kScalar)
    box_cylinder_range<simd::Float1>(a, b, out, r);
  else
    box_cylinder_range<simd::FloatP>(a, b, out, r);
}

}  // namespace impact::kernels
