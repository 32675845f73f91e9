// Convex hull (A) against a half-space (B): a lane kernel, one pair per SIMD lane.
//
// What: per lane, the half-space B = { x : nh.(x - pB) <= 0 } (leaf.h: p = pB, e = unit
// nh). Normal A->B: n = -nh; depth = the deepest hull vertex's -nh.(x - pB) (the support
// along -nh, exact up to float rounding); depth <= 0: count 0. Manifold: up to 4 of the
// hull's vertices below the plane, the same rule as collide_support_halfspace
// (support_halfspace.cpp): the deepest, the one below farthest from it, the one below
// adding the largest |area| about nh, the one below farthest outside that triangle (each
// the first maximum in vertex order; the area and outside picks only above a relative
// 1e-6 of the squared span, so rounding never adds a collinear point). Each point lies
// midway between the vertex x and its projection onto the plane; pdepth = x's depth.
// Inputs: LeafSoA lanes per leaf.h (A a hull: p, R, ref into NarrowConfig::hulls; B a
// half-space, unit nh), Range r of the bucket. Outputs: ManifoldSoA lanes r.begin ..
// r.end (all 4 point slots written; those past count hold finite don't-care values).
// Method: the plane moves into each lane's hull frame (nl = R^T nh, offl = nh.(pB - pA)).
// Walk: kSimdWidth vertices of every lane per step: lane l reads that many consecutive
// vertices of its own hull (simd::load_transposed: one row per lane, no gathers; the
// row start clamped to the hull's last full row, a vertex seen again changing no first
// strict maximum; hulls of fewer vertices than lanes from a padded copy, the padding
// masked out). Each vertex's local coordinates and depth go to a stack buffer of lanes,
// and the slots below the plane in some lane are listed. The deepest vertex, then the
// three other picks over the listed slots, are running strict maxima that carry their
// vertex along (two interleaved chains per pick, merged by (score, lowest slot): the
// first vertex wins ties, as in collide_support_halfspace); no horizontal reductions,
// no gathers. Only the chosen vertices go back to the world frame, relative to A's
// position (precision far from the origin).
// Big hulls: a lane whose hull has more than kLaneVerts vertices takes no part in the
// walk and gets collide_support_halfspace (one pair at a time, SIMD across its
// vertices) instead, decided by its own hull, so a lane's bytes never depend on the
// other lanes of its block.
// Preconditions: finite inputs, orthonormal R, unit nh (host-validated); a hull has at
// least one vertex. Degenerate input: a hull lying in the plane (all depths 0) counts
// 0, like exact touching; flat and needle hulls just give fewer points.
// Deterministic: fixed loop order; every verb lane-wise. Both paths (kScalar: one lane,
// kSimd: kSimdWidth lanes) run the same template.
// Cost: per vertex and lane ~4 shuffles (the transposes), 3 FMAs and the running
// maximum; per pick and listed slot ~15 operations. impact_narrowbench (24-point hulls,
// half the pairs touching; loaded 2-core machine, alternated runs, best of 6): SIMD
// ~27-29 ns per pair against ~44-47 for collide_support_halfspace (one pair at a time,
// SIMD across its vertices); see docs/narrowphase.md for the same-run FCL figures.
// Variants measured and dropped: AVX2 gathers per vertex (3 per vertex and block:
// ~50-65 ns), picks tracked by slot index and fetched by gather_lanes (~37), one
// chain per pick (~30-33), max-then-backward-scan picks (~36).
#include <cmath>
#include <cstdint>

#include "kernels/narrowphase/pair_kernels.h"
#include "kernels/narrowphase/primitives.h"

namespace impact::kernels {
namespace {

using namespace prim;  // NOLINT: lane helpers of this kernel family
using simd::cross;
using simd::dot;

/// Largest vertex count walked by the lane kernel (the buffer's size); bigger hulls go
/// to collide_support_halfspace.
inline constexpr uint32_t kLaneVerts = 64;

/// Per lane, the first strict maximum of scores offered in slot order and the vertex
/// (local coordinates and depth) it came with; offers alternate between two running
/// maxima (two short dependency chains instead of one long one), merged by (score,
/// lowest slot).
template <class F>
struct FirstMax {
  using I = typename F::Int;
  F v[2], x[2], y[2], z[2], d[2];
  I at[2];
  IMPACT_INLINE FirstMax(F init, const V3<F>& p, F dp) {
    for (int r = 0; r < 2; ++r) {
      v[r] = init;
      x[r] = p.x;
      y[r] = p.y;
      z[r] = p.z;
      d[r] = dp;
      at[r] = I(0);
    }
  }
  template <int r>
  IMPACT_INLINE void offer(F s, typename F::Mask ok, uint32_t slot, F px, F py, F pz, F pd) {
    const auto gt = (s > v[r]) & ok;
    v[r] = select(gt, s, v[r]);
    x[r] = select(gt, px, x[r]);
    y[r] = select(gt, py, y[r]);
    z[r] = select(gt, pz, z[r]);
    d[r] = select(gt, pd, d[r]);
    at[r] = select(gt, I(static_cast<int32_t>(slot)), at[r]);
  }
  /// The maximum; *p, *dp: its vertex (the initial one if never above init).
  IMPACT_INLINE F result(V3<F>* p, F* dp) const {
    const auto take = (v[1] > v[0]) | ((v[1] == v[0]) & (at[0] > at[1]));
    *p = V3<F>{select(take, x[1], x[0]), select(take, y[1], y[0]), select(take, z[1], z[0])};
    *dp = select(take, d[1], d[0]);
    return select(take, v[1], v[0]);
  }
};

/// Runs one block of F::kWidth lanes. A lane whose hull is too big for the walk gets
/// don't-care output (its caller runs it again through collide_support_halfspace).
template <class F>
IMPACT_INLINE void convex_halfspace_block(const LeafSoA& a, const LeafSoA& b, const HullView& h,
                                          const ManifoldSoA& out, uint32_t k) {
  using I = typename F::Int;
  const uint32_t* ref = a.ref + k;
  constexpr uint32_t kW = F::kWidth;
  // Per lane: where its hull's vertices start and how many (0 for a big hull).
  int32_t cnt_l[kW];
  uint32_t vb_l[kW];
  uint32_t nmax = 0;
  for (uint32_t l = 0; l < kW; ++l) {
    const uint32_t hb = h.vert_begin[ref[l]], he = h.vert_begin[ref[l] + 1];
    uint32_t c = he - hb;
    if (c > kLaneVerts) c = 0;
    vb_l[l] = hb;
    cnt_l[l] = static_cast<int32_t>(c);
    nmax = c > nmax ? c : nmax;
  }
  const I cnt = I::load(cnt_l);

  const F zero(0.0f), half(0.5f);
  const V3<F> pa = load_p<F>(a, k);
  const V3<F> nh = load_e<F>(b, k);
  const F offl = dot(nh, load_p<F>(b, k) - pa);  // x (local) is below when nl.x < offl
  const M3<F> ra = load_r<F>(a, k);
  const V3<F> nl{dot(nh, ra.c[0]), dot(nh, ra.c[1]), dot(nh, ra.c[2])};

  // Walk: kW vertices of every lane per step (lane l reads kW consecutive vertices of its
  // own hull from its start, clamped to its last kW: a vertex seen again changes no
  // first strict maximum; hulls of fewer than kW vertices from a padded copy, the
  // padding masked out). Each vertex's local coordinates and depth go to the buffer
  // (-inf where masked), the deepest so far is kept, and `below` lists the buffer
  // slots below the plane in some lane (the only ones the other picks visit).
  struct Buf {
    F x[kLaneVerts], y[kLaneVerts], z[kLaneVerts], d[kLaneVerts];
  } buf;
  float pad[3][kW][kW];
  const float* rows[3][kW];
  for (uint32_t l = 0; l < kW; ++l) {
    if (static_cast<uint32_t>(cnt_l[l]) < kW) {
      for (uint32_t j = 0; j < kW; ++j) {
        const bool in = j < static_cast<uint32_t>(cnt_l[l]);
        pad[0][l][j] = in ? h.vx[vb_l[l] + j] : 0.0f;
        pad[1][l][j] = in ? h.vy[vb_l[l] + j] : 0.0f;
        pad[2][l][j] = in ? h.vz[vb_l[l] + j] : 0.0f;
      }
    }
  }
  uint32_t below[kLaneVerts];
  uint32_t nbelow = 0;
  FirstMax<F> deepest(zero, V3<F>{zero, zero, zero}, zero);
  const uint32_t nblk = (nmax + kW - 1) / kW;
  for (uint32_t blk = 0; blk < nblk; ++blk) {
    for (uint32_t l = 0; l < kW; ++l) {
      const auto c = static_cast<uint32_t>(cnt_l[l]);
      if (c < kW) {
        for (uint32_t q = 0; q < 3; ++q) rows[q][l] = pad[q][l];
      } else {
        const uint32_t at = vb_l[l] + (blk * kW + kW <= c ? blk * kW : c - kW);
        rows[0][l] = h.vx + at;
        rows[1][l] = h.vy + at;
        rows[2][l] = h.vz + at;
      }
    }
    F* const x = buf.x + blk * kW;
    F* const y = buf.y + blk * kW;
    F* const z = buf.z + blk * kW;
    simd::load_transposed(rows[0], x);
    simd::load_transposed(rows[1], y);
    simd::load_transposed(rows[2], z);
    for (uint32_t j = 0; j < kW; ++j) {
      const uint32_t i = blk * kW + j;
      const F d = select(cnt > I(static_cast<int32_t>(j)), offl - (nl.x * x[j] + nl.y * y[j] + nl.z * z[j]),
                         F(-INFINITY));
      buf.d[i] = d;
      if (j % 2 == 0) {
        deepest.template offer<0>(d, typename F::Mask(true), i, x[j], y[j], z[j], d);
      } else {
        deepest.template offer<1>(d, typename F::Mask(true), i, x[j], y[j], z[j], d);
      }
      below[nbelow] = i;
      nbelow += simd::any(d > zero) ? 1u : 0u;
    }
  }
  V3<F> p0;
  F d0;
  deepest.result(&p0, &d0);
  const auto hit = d0 > zero;
  if (simd::none(hit)) {
    store_no_contact<F>(out, k);
    return;
  }
  // Offers slot below[q] to m (alternating between its two chains).
  auto offer_below = [&](FirstMax<F>& m, uint32_t q, F s) {
    const uint32_t i = below[q];
    if (q % 2 == 0) {
      m.template offer<0>(s, buf.d[i] > zero, i, buf.x[i], buf.y[i], buf.z[i], buf.d[i]);
    } else {
      m.template offer<1>(s, buf.d[i] > zero, i, buf.x[i], buf.y[i], buf.z[i], buf.d[i]);
    }
  };
  // Farthest from p0 among the vertices below (first strict maximum, as every pick).
  FirstMax<F> farthest(zero, p0, d0);
  for (uint32_t q = 0; q < nbelow; ++q) {
    const uint32_t i = below[q];
    const F dx = buf.x[i] - p0.x, dy = buf.y[i] - p0.y, dz = buf.z[i] - p0.z;
    offer_below(farthest, q, dx * dx + dy * dy + dz * dz);
  }
  V3<F> p1;
  F d1;
  const F far = farthest.result(&p1, &d1);
  const auto has1 = hit & (far > zero);
  // Largest |area| with p0, p1 about nl: a = (x - p0).c, c = nl x (p1 - p0).
  const V3<F> c = cross(nl, p1 - p0);
  const F tiny = F(1e-6f) * length_sq(p1 - p0);
  auto area = [&](const F& x, const F& y, const F& z) {
    return (x - p0.x) * c.x + (y - p0.y) * c.y + (z - p0.z) * c.z;
  };
  F amax = tiny, d2 = d0;
  V3<F> p2 = p0;
  if (simd::any(has1)) {
    FirstMax<F> widest(tiny, p0, d0);
    for (uint32_t q = 0; q < nbelow; ++q) {
      const uint32_t i = below[q];
      offer_below(widest, q, abs(area(buf.x[i], buf.y[i], buf.z[i])));
    }
    amax = widest.result(&p2, &d2);
  }
  const auto has2 = has1 & (amax > tiny);
  // Farthest outside the triangle p0 p1 p2: the largest of its three edge distances
  // (times the edge lengths), each (x - pj).gj with gj = -sgn nl x (pj+1 - pj).
  F omax = tiny, d3 = d0;
  V3<F> p3 = p0;
  if (simd::any(has2)) {
    const F sgn = select(area(p2.x, p2.y, p2.z) >= zero, F(-1.0f), F(1.0f));
    const V3<F> g0 = c * sgn, g1 = cross(nl, p2 - p1) * sgn, g2 = cross(nl, p0 - p2) * sgn;
    FirstMax<F> outmost(tiny, p0, d0);
    for (uint32_t q = 0; q < nbelow; ++q) {
      const uint32_t i = below[q];
      const F x = buf.x[i], y = buf.y[i], z = buf.z[i];
      auto edge = [&](const V3<F>& p, const V3<F>& g) {
        return (x - p.x) * g.x + (y - p.y) * g.y + (z - p.z) * g.z;
      };
      offer_below(outmost, q, max(edge(p0, g0), max(edge(p1, g1), edge(p2, g2))));
    }
    omax = outmost.result(&p3, &d3);
  }
  const auto has3 = has2 & (omax > tiny);
  Lanes<F, 4> m;
  m.count = simd::to_int(hit) + simd::to_int(has1) + simd::to_int(has2) + simd::to_int(has3);
  m.n = -nh;
  m.depth = d0;
  const V3<F> pl[4] = {p0, p1, p2, p3};
  const F dep[4] = {d0, d1, d2, d3};
  for (int j = 0; j < 4; ++j) {
    const V3<F> x = ra.c[0] * pl[j].x + ra.c[1] * pl[j].y + ra.c[2] * pl[j].z;
    m.point[j] = madd(x, half * dep[j], nh);
    m.pdepth[j] = dep[j];
  }
  store(out, k, m, pa);
}

/// The lane walk over every block of r (prim::for_each_block: the tail through padded
/// local copies); then the big-hull lanes, one at a time, by collide_support_halfspace.
template <class F>
void convex_halfspace_range(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, Range r,
                            const NarrowConfig& cfg) {
  const HullView& h = cfg.hulls;
  for_each_block<F, 4>(a, b, out, r,
                       [&](const LeafSoA& la, const LeafSoA& lb, const ManifoldSoA& lo, uint32_t k) {
                         convex_halfspace_block<F>(la, lb, h, lo, k);
                       });
  for (uint32_t l = r.begin; l < r.end; ++l) {
    if (h.vert_begin[a.ref[l] + 1] - h.vert_begin[a.ref[l]] > kLaneVerts) {
      collide_support_halfspace(a, b, out, Range{l, l + 1}, cfg, kLeafConvex);
    }
  }
}

}  // namespace

void collide_convex_halfspace(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, Range r,
                              const NarrowConfig& cfg) {
  if (cfg.path == KernelPath::kScalar) {
    convex_halfspace_range<simd::Float1>(a, b, out, r, cfg);
  } else {
    convex_halfspace_range<simd::FloatW>(a, b, out, r, cfg);
  }
}

}  // namespace impact::kernels
