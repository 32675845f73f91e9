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
// r.end (count-0 lanes: count only; touching lanes: all 4 point slots, those past
// count finite don't-care values).
// Method: the range goes kChunk lanes at a time, in two passes.
// 1. Listing, W = simd::kPairWidth lanes per block (16 under AVX-512, else
//    kSimdWidth): the plane moves into each lane's hull frame (nl = R^T nh,
//    offl = nh.(pB - pA), SIMD across the block); then each lane in turn
//    tests its own hull's vertices W consecutive ones per step (contiguous loads, the
//    last step's start clamped to the hull's last W vertices; a hull of fewer than W
//    from a zero-padded copy, masked) and keeps a bit mask of those strictly below
//    (nl.x < offl, i.e. depth offl - nl.x > 0). A lane with none gets count 0 and is done
//    (about half the lanes on the bench); the others are listed (compacted).
// 2. Picks, W listed lanes per group (the last group padded with repeats): the lanes'
//    plane and pose by prim::GroupRows (windows of the rows, not gathers); slot j of
//    lane l is lane l's j-th vertex below, in vertex order (past its count, its first
//    again: a vertex seen again changes no first strict maximum), the slots' vertices
//    by simd::gather_xyz (HullView::vxyz, a 16-byte record per vertex: one load a lane
//    and a transpose). So every slot of every lane lies below and the passes run over
//    full vectors of touching lanes only: the deepest, then the farthest, the widest
//    and the outmost, each a running strict maximum carrying its vertex (two
//    interleaved chains per pick, merged by (score, lowest slot): the first vertex wins
//    ties, as in collide_support_halfspace); depths recomputed from the chosen vertices
//    (the same expression, the same bits). Only the chosen vertices go back to the
//    world frame, relative to A's position (precision far from the origin); the driver
//    expands the chunk's results into the output blocks (prim::LiveOut).
// Big hulls: a lane whose hull has more than kLaneVerts vertices is not listed and gets
// collide_support_halfspace (one pair at a time, SIMD across its vertices) instead,
// decided by its own hull; the listing pass notes whether the range has any, so a range
// without them is not walked again for them.
// Preconditions: finite inputs, orthonormal R, unit nh (host-validated); a hull has at
// least one vertex. Degenerate input: a hull lying in the plane (all depths 0) counts
// 0, like exact touching; flat and needle hulls just give fewer points.
// Deterministic: fixed loop order; every verb lane-wise, and a lane's result depends only
// on its own hull and pose (never on which lanes share its block or group), so range
// partitions and shuffled buckets give the same bytes; the one-lane path (kScalar)
// runs the same template and gives the SIMD path's bytes except where two vertices'
// pick scores tie within rounding (GCC contracts the one-lane and vector code's
// multiply-adds differently; 8 lanes in 12,000 random ones, box and needle hulls):
// then either choice meets the pick rule (no contraction in this file would make them
// identical, at a cost: docs/history.md).
// Cost: per lane, one pass over its hull's vertices (W per step); per touching group,
// 18 pose and plane rows read (GroupRows) and a gather_xyz per slot. Measured per pair
// in docs/results.md ("Narrow phase"); the variants measured and dropped, with their
// figures, in docs/history.md.
#include <bit>
#include <cmath>
#include <cstdint>

#include "kernels/narrowphase/pair_kernels.h"
#include "kernels/narrowphase/lanes/lane_io.h"
#include "kernels/narrowphase/lanes/live_lanes.h"

namespace impact::kernels {
namespace {

using namespace prim;  // NOLINT: lane helpers of this kernel family
using simd::cross;
using simd::dot;

/// Largest vertex count walked by the lane kernel (the buffer's size); bigger hulls go
/// to collide_support_halfspace.
inline constexpr uint32_t kLaneVerts = 64;

/// Per lane, the first strict maximum of scores offered in slot order and the vertex
/// (local coordinates) it came with; offers alternate between two running maxima (two
/// short dependency chains instead of one long one), merged by (score, lowest slot).
/// (The vertex's depth is not carried: vertex_depth gives it again, the same bits.)
template <class F>
struct FirstMax {
  using I = typename F::Int;
  F v[2], x[2], y[2], z[2];
  I at[2];
  IMPACT_INLINE FirstMax(F init, const V3<F>& p) {
    for (int r = 0; r < 2; ++r) {
      v[r] = init;
      x[r] = p.x;
      y[r] = p.y;
      z[r] = p.z;
      at[r] = I(0);
    }
  }
  template <int r>
  IMPACT_INLINE void offer(F s, typename F::Mask ok, uint32_t slot, F px, F py, F pz) {
    const auto gt = (s > v[r]) & ok;
    v[r] = select(gt, s, v[r]);
    x[r] = select(gt, px, x[r]);
    y[r] = select(gt, py, y[r]);
    z[r] = select(gt, pz, z[r]);
    at[r] = select(gt, I(static_cast<int32_t>(slot)), at[r]);
  }
  /// The maximum; *p: its vertex (the initial one if never above init).
  IMPACT_INLINE F result(V3<F>* p) const {
    const auto take = (v[1] > v[0]) | ((v[1] == v[0]) & (at[0] > at[1]));
    *p = V3<F>{select(take, x[1], x[0]), select(take, y[1], y[0]), select(take, z[1], z[0])};
    return select(take, v[1], v[0]);
  }
};

/// nl.x for local vertex x: a vertex lies below the plane where nl.x < offl, and
/// its depth is offl - nl.x; one expression for every use (the listing pass and the
/// picks must agree bit for bit). offl - t > 0 exactly where t < offl (an IEEE
/// subtraction keeps the sign of the exact difference), so the listing pass compares.
template <class F>
IMPACT_INLINE F plane_dot(const V3<F>& nl, F x, F y, F z) {
  return nl.x * x + nl.y * y + nl.z * z;
}
template <class F>
IMPACT_INLINE F vertex_depth(const V3<F>& nl, F offl, F x, F y, F z) {
  return offl - plane_dot(nl, x, y, z);
}

/// The plane in the hull frames of lanes k .. k + width: nl = R^T nh, offl = nh.(pB - pA).
template <class F>
IMPACT_INLINE void local_plane(const V3<F>& pa, const M3<F>& ra, const V3<F>& nh, const V3<F>& pb, V3<F>* nl,
                               F* offl) {
  *offl = dot(nh, pb - pa);
  *nl = V3<F>{dot(nh, ra.c[0]), dot(nh, ra.c[1]), dot(nh, ra.c[2])};
}

/// Bit v set where vertex v of the c (1 <= c <= kLaneVerts) vertices at h.vx[vb].. lies
/// strictly below the plane (depth > 0): F::kWidth consecutive vertices per step, the
/// last step's start clamped to c - width (a vertex seen twice sets the same bit);
/// fewer vertices than lanes through a zero-padded copy, the padding masked off.
template <class F>
IMPACT_INLINE uint64_t below_bits(const HullView& h, uint32_t vb, uint32_t c, const V3<F>& nl, F offl) {
  constexpr uint32_t kW = F::kWidth;
  if (c < kW) {
    float px[kW], py[kW], pz[kW];
    for (uint32_t j = 0; j < kW; ++j) {
      const bool in = j < c;
      px[j] = in ? h.vx[vb + j] : 0.0f;
      py[j] = in ? h.vy[vb + j] : 0.0f;
      pz[j] = in ? h.vz[vb + j] : 0.0f;
    }
    const F t = plane_dot(nl, F::load(px), F::load(py), F::load(pz));
    return simd::bits_lt(t, offl) & ((uint64_t{1} << c) - 1u);
  }
  uint64_t bits = 0;
  for (uint32_t s = 0; s < c; s += kW) {
    const uint32_t at = s + kW <= c ? s : c - kW;
    const F t = plane_dot(nl, F::load(h.vx + vb + at), F::load(h.vy + vb + at), F::load(h.vz + vb + at));
    bits |= static_cast<uint64_t>(simd::bits_lt(t, offl)) << at;
  }
  return bits;
}

/// A touching lane's hull vertices below the plane: bit j for vertex vb + j.
struct Below {
  uint64_t bits;
  uint32_t vb;
};

/// Slot lists of I::kWidth (> 1) lanes, across the lanes: vi[j][l] = vb + the index of
/// lane l's j-th set bit (past its count, its first), j < ns. A set bit's index is the
/// exponent of its power of two converted to float (exact; bit 31, as a signed int
/// -2^31, has exponent field 31 too); the two 32-bit halves of the mask in turn, in
/// unsigned lanes (x & -x and x - 1 wrap there).
template <class I>
IMPACT_INLINE void slot_lists(const Below* below, uint32_t ns, int32_t (*vi)[I::kWidth]) {
  using R = typename I::Raw;
  using FR = typename simd::RawVec<I::kWidth>::F;
  using U = typename simd::RawVec<I::kWidth>::U;
  constexpr uint32_t kW = I::kWidth;
  alignas(64) uint32_t lo_a[kW], hi_a[kW];
  alignas(64) int32_t vb_a[kW];
  for (uint32_t l = 0; l < kW; ++l) {
    lo_a[l] = static_cast<uint32_t>(below[l].bits);
    hi_a[l] = static_cast<uint32_t>(below[l].bits >> 32);
    vb_a[l] = static_cast<int32_t>(below[l].vb);
  }
  U lo, hi;
  std::memcpy(&lo, lo_a, sizeof(U));
  std::memcpy(&hi, hi_a, sizeof(U));
  const R vb = I::load(vb_a).v;
  const U zero = U{} + 0u;
  auto lowest = [&](U x) -> R {  // index of x's lowest set bit (x != 0)
    const FR f = __builtin_convertvector(reinterpret_cast<R>(x & (zero - x)), FR);
    R e;
    std::memcpy(&e, &f, sizeof(R));
    return ((e >> 23) & 255) - 127;
  };
  auto next = [&]() -> R { return lo != zero ? lowest(lo) : lowest(hi) + 32; };
  const R first = vb + next();
  for (uint32_t j = 0; j < ns; ++j) {
    const auto use_lo = lo != zero, any = (lo | hi) != zero;
    const R v = any ? vb + next() : first;
    std::memcpy(vi[j], &v, sizeof(R));
    lo = use_lo ? lo & (lo - 1u) : lo;
    hi = use_lo ? hi : hi & (hi - 1u);
  }
}

/// The picks for F::kWidth touching lanes: lane l is pair live[l] (global index; the
/// group padded with repeats), below[l] its hull's vertices below the plane (non-zero).
/// Slot j of lane l holds its j-th vertex below (in vertex order; past its count, its
/// first again: a vertex seen again changes no first strict maximum), so every slot of
/// every lane is below and the picks run over full vectors. Hands the group's result to o.
template <class F>
IMPACT_INLINE void touching_group(const LeafSoA& a, const LeafSoA& b, const HullView& h, LiveOut<F, 4>& o,
                                  const int32_t* live, const Below* below, Range r) {
  using I = typename F::Int;
  constexpr uint32_t kW = F::kWidth;
  const GroupRows<F> rows(live, r);
  const V3<F> pa = rows.v3(a.p), nh = rows.v3(b.e), pb = rows.v3(b.p);
  const M3<F> ra = rows.rot(a);
  V3<F> nl;
  F offl;
  local_plane(pa, ra, nh, pb, &nl, &offl);

  // Slot lists: vertex indices (absolute) per slot and lane.
  uint32_t ns = 0;
  for (uint32_t l = 0; l < kW; ++l) {
    const auto c = static_cast<uint32_t>(std::popcount(below[l].bits));
    ns = c > ns ? c : ns;
  }
  int32_t vi[kLaneVerts][kW];
  if constexpr (kW > 1) {
    slot_lists<I>(below, ns, vi);
  } else {
    uint64_t m = below[0].bits;
    const uint32_t vb = below[0].vb;
    const auto first = static_cast<int32_t>(vb + static_cast<uint32_t>(std::countr_zero(m)));
    for (uint32_t j = 0; j < ns; ++j) {
      vi[j][0] = m != 0 ? static_cast<int32_t>(vb + static_cast<uint32_t>(std::countr_zero(m))) : first;
      m &= m - 1u;
    }
  }
  struct Buf {
    F x[kLaneVerts], y[kLaneVerts], z[kLaneVerts];
  } buf;
  const F zero(0.0f), half(0.5f);
  FirstMax<F> deepest(zero, V3<F>{zero, zero, zero});
  for (uint32_t j = 0; j < ns; ++j) {
    F x, y, z;
    simd::gather_xyz(h.vxyz, vi[j], &x, &y, &z);
    const F d = vertex_depth(nl, offl, x, y, z);
    buf.x[j] = x, buf.y[j] = y, buf.z[j] = z;
    if (j % 2 == 0) {
      deepest.template offer<0>(d, typename F::Mask(true), j, x, y, z);
    } else {
      deepest.template offer<1>(d, typename F::Mask(true), j, x, y, z);
    }
  }
  V3<F> p0;
  deepest.result(&p0);
  const F d0 = vertex_depth(nl, offl, p0.x, p0.y, p0.z);
  const auto hit = d0 > zero;
  auto offer = [&](FirstMax<F>& m, uint32_t j, F s) {
    if (j % 2 == 0) {
      m.template offer<0>(s, typename F::Mask(true), j, buf.x[j], buf.y[j], buf.z[j]);
    } else {
      m.template offer<1>(s, typename F::Mask(true), j, buf.x[j], buf.y[j], buf.z[j]);
    }
  };
  // Farthest from p0 among the vertices below (first strict maximum, as every pick).
  FirstMax<F> farthest(zero, p0);
  for (uint32_t j = 0; j < ns; ++j) {
    const F dx = buf.x[j] - p0.x, dy = buf.y[j] - p0.y, dz = buf.z[j] - p0.z;
    offer(farthest, j, dx * dx + dy * dy + dz * dz);
  }
  V3<F> p1;
  const F far = farthest.result(&p1);
  const auto has1 = hit & (far > zero);
  // Largest |area| with p0, p1 about nl: a = (x - p0).c, c = nl x (p1 - p0).
  const V3<F> c = cross(nl, p1 - p0);
  const F tiny = F(1e-6f) * length_sq(p1 - p0);
  auto area = [&](const F& x, const F& y, const F& z) {
    return (x - p0.x) * c.x + (y - p0.y) * c.y + (z - p0.z) * c.z;
  };
  F amax = tiny;
  V3<F> p2 = p0;
  if (simd::any(has1)) {
    FirstMax<F> widest(tiny, p0);
    for (uint32_t j = 0; j < ns; ++j) offer(widest, j, abs(area(buf.x[j], buf.y[j], buf.z[j])));
    amax = widest.result(&p2);
  }
  const auto has2 = has1 & (amax > tiny);
  // Farthest outside the triangle p0 p1 p2: the largest of its three edge distances
  // (times the edge lengths), each (x - pj).gj with gj = -sgn nl x (pj+1 - pj).
  F omax = tiny;
  V3<F> p3 = p0;
  if (simd::any(has2)) {
    const F sgn = select(area(p2.x, p2.y, p2.z) >= zero, F(-1.0f), F(1.0f));
    const V3<F> g0 = c * sgn, g1 = cross(nl, p2 - p1) * sgn, g2 = cross(nl, p0 - p2) * sgn;
    FirstMax<F> outmost(tiny, p0);
    for (uint32_t j = 0; j < ns; ++j) {
      const F x = buf.x[j], y = buf.y[j], z = buf.z[j];
      auto edge = [&](const V3<F>& p, const V3<F>& g) {
        return (x - p.x) * g.x + (y - p.y) * g.y + (z - p.z) * g.z;
      };
      offer(outmost, j, max(edge(p0, g0), max(edge(p1, g1), edge(p2, g2))));
    }
    omax = outmost.result(&p3);
  }
  const auto has3 = has2 & (omax > tiny);
  Lanes<F, 4> m;
  m.count = simd::to_int(hit) + simd::to_int(has1) + simd::to_int(has2) + simd::to_int(has3);
  m.n = -nh;
  m.depth = d0;
  const V3<F> pl[4] = {p0, p1, p2, p3};
  const F dep[4] = {d0, vertex_depth(nl, offl, p1.x, p1.y, p1.z), vertex_depth(nl, offl, p2.x, p2.y, p2.z),
                    vertex_depth(nl, offl, p3.x, p3.y, p3.z)};
  for (int j = 0; j < 4; ++j) {
    const V3<F> x = ra.c[0] * pl[j].x + ra.c[1] * pl[j].y + ra.c[2] * pl[j].z;
    m.point[j] = madd(x, half * dep[j], nh);
    m.pdepth[j] = dep[j];
  }
  o.put(m, pa);
}

/// The range through prim::for_each_live_group: the screen moves each block's planes
/// into their hulls' frames and lists, per lane, the hull's vertices below it (W
/// consecutive vertices of that lane's hull per step); a lane with none gets count 0,
/// the others are gathered W at a time into full groups for the picks
/// (touching_group). Then the big-hull lanes, one at a time, by
/// collide_support_halfspace. Every computation is lane-wise, so a pair's bytes do not
/// depend on which lanes share its block or group.
template <class F>
void convex_halfspace_range(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, Range r,
                            const NarrowConfig& cfg) {
  const HullView& h = cfg.hulls;
  constexpr uint32_t W = F::kWidth;
  bool big = false;  // a lane's hull has more than kLaneVerts vertices
  for_each_live_group<F, 4, Below>(
      a, b, out, r,
      [&](const LeafSoA& va, const LeafSoA& vb, uint32_t at, uint32_t k, uint32_t nb, Below* below) {
        V3<F> nl;
        F offl;
        local_plane(load_p<F>(va, at), load_r<F>(va, at), load_e<F>(vb, at), load_p<F>(vb, at), &nl, &offl);
        float lx[W], ly[W], lz[W], lo[W];
        nl.x.store(lx), nl.y.store(ly), nl.z.store(lz), offl.store(lo);
        uint32_t go = 0;
        for (uint32_t l = 0; l < nb; ++l) {
          const uint32_t hb = h.vert_begin[a.ref[k + l]], c = h.vert_begin[a.ref[k + l] + 1] - hb;
          if (c > kLaneVerts) {  // collide_support_halfspace, below
            big = true;
            continue;
          }
          below[l] = Below{below_bits<F>(h, hb, c, V3<F>{F(lx[l]), F(ly[l]), F(lz[l])}, F(lo[l])), hb};
          go |= (below[l].bits != 0 ? 1u : 0u) << l;
        }
        return go;
      },
      [&](const int32_t* index, const Below* below, uint32_t, LiveOut<F, 4>& o) {
        touching_group<F>(a, b, h, o, index, below, r);
      });
  for (uint32_t l = r.begin; big && l < r.end; ++l) {
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
    convex_halfspace_range<simd::FloatP>(a, b, out, r, cfg);
  }
}

}  // namespace impact::kernels
