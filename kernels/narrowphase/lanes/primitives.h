// Shared lane helpers of the specialised narrow-phase kernels
// (kernels/narrowphase/pairs/): the block driver that
// walks a Range kSimdWidth pairs at a time, LeafSoA loads, the manifold store, and the
// geometric queries the kernels share (closest point on a segment, closest points of
// two segments robust for parallel ones, closest point on a triangle, a deterministic
// perpendicular for degenerate normals, a capsule's surface along a direction from a
// core point), and the reduction of a candidate set of contact
// points to at most 4 (reduce4, reduce4_indices).
//
// Every helper is a template over the lane type F (simd::FloatW or simd::Float1), so
// the SIMD path and the scalar reference path run the same code. Positions are taken
// relative to A's position (the driver's `origin`) before any arithmetic, so poses
// 1e5 from the origin lose no more than the inputs' own rounding.
//
// Tail: a Range that is not a multiple of the width ends with a partial block. Its
// inputs are copied into a local full-width block (the last valid lane repeated in
// the padding, so padding lanes compute finite values), the same block code runs,
// and only the valid lanes are copied out. So a pair's output bytes do not depend on
// where a range boundary falls, and no array is read or written past the Range.
#pragma once

#include <bit>
#include <cfloat>
#include <cstdint>
#include <cstring>
#include <type_traits>

#include "kernels/narrowphase/leaf/leaf.h"
#include "kernels/simd/lanes.h"
#include "kernels/simd/vec3.h"

namespace impact::kernels::prim {

using simd::M3;
using simd::V3;

// ---------------------------------------------------------------------------------------
// Loads and stores
// ---------------------------------------------------------------------------------------

template <class F>
IMPACT_INLINE F ld(const float* p, uint32_t k) {
  return F::load(p + k);
}
template <class F>
IMPACT_INLINE V3<F> load_p(const LeafSoA& s, uint32_t k) {
  return {ld<F>(s.p[0], k), ld<F>(s.p[1], k), ld<F>(s.p[2], k)};
}
template <class F>
IMPACT_INLINE V3<F> load_w(const LeafSoA& s, uint32_t k, uint32_t first) {
  return {ld<F>(s.w[first], k), ld<F>(s.w[first + 1], k), ld<F>(s.w[first + 2], k)};
}
template <class F>
IMPACT_INLINE V3<F> load_e(const LeafSoA& s, uint32_t k) {
  return {ld<F>(s.e[0], k), ld<F>(s.e[1], k), ld<F>(s.e[2], k)};
}
/// Rotation by columns (LeafSoA stores R row-major: r[3*row + col]).
template <class F>
IMPACT_INLINE M3<F> load_r(const LeafSoA& s, uint32_t k) {
  M3<F> m;
  for (uint32_t c = 0; c < 3; ++c) m.c[c] = {ld<F>(s.r[c], k), ld<F>(s.r[3 + c], k), ld<F>(s.r[6 + c], k)};
  return m;
}
/// Column 2 of R: a capsule's axis.
template <class F>
IMPACT_INLINE V3<F> load_axis_z(const LeafSoA& s, uint32_t k) {
  return {ld<F>(s.r[2], k), ld<F>(s.r[5], k), ld<F>(s.r[8], k)};
}

/// One block's collision data, points relative to the driver's origin (A's position).
template <class F, uint32_t P>
struct Lanes {
  typename F::Int count;
  V3<F> n;
  F depth;
  V3<F> point[P];
  F pdepth[P];
};

/// Writes lanes k .. k + width of out: count, n, depth and point slots 0 .. S-1
/// (S <= P; points made absolute by adding origin).
template <class F, uint32_t P, uint32_t S = P>
IMPACT_INLINE void store(const ManifoldSoA& out, uint32_t k, const Lanes<F, P>& m, const V3<F>& origin) {
  static_assert(S <= P);
  // The counts narrowed in a local array, then one copy: a byte store through
  // out.count may alias `out` itself, so storing lane by lane made GCC reload the
  // pointer after every byte (8 loads and 8 byte stores per block, measured on
  // sphere-halfspace).
  uint8_t counts[F::kWidth];
  for (uint32_t i = 0; i < F::kWidth; ++i) counts[i] = static_cast<uint8_t>(m.count.lane(i));
  std::memcpy(out.count + k, counts, sizeof(counts));
  m.n.x.store(out.n[0] + k);
  m.n.y.store(out.n[1] + k);
  m.n.z.store(out.n[2] + k);
  m.depth.store(out.depth + k);
  for (uint32_t j = 0; j < S; ++j) {
    (origin.x + m.point[j].x).store(out.point[j][0] + k);
    (origin.y + m.point[j].y).store(out.point[j][1] + k);
    (origin.z + m.point[j].z).store(out.point[j][2] + k);
    m.pdepth[j].store(out.pdepth[j] + k);
  }
}

/// Writes count 0 to lanes k .. k + width (a block with no contact: the contract lets
/// every other field of a count-0 lane stay unwritten).
template <class F>
IMPACT_INLINE void store_no_contact(const ManifoldSoA& out, uint32_t k) {
  std::memset(out.count + k, 0, F::kWidth);
}

/// A one-point result from the normal, the depth and the two surface points (the point
/// midway between them, count 1 where depth > 0; the sphere (A) kernels).
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

// ---------------------------------------------------------------------------------------
// Block driver
// ---------------------------------------------------------------------------------------

/// Local full-width copy of one side's lanes (tail blocks).
template <uint32_t W>
struct TailSide {
  float p[3][W], r[9][W], e[3][W], w[6][W];
  uint32_t ref[W];
  LeafSoA view{};

  void fill(const LeafSoA& s, uint32_t k, uint32_t n) {
    auto copy = [&](const float* src, float* dst) -> const float* {
      if (src == nullptr) return nullptr;
      for (uint32_t i = 0; i < W; ++i) dst[i] = src[k + (i < n ? i : n - 1)];
      return dst;
    };
    for (uint32_t j = 0; j < 3; ++j) view.p[j] = copy(s.p[j], p[j]);
    for (uint32_t j = 0; j < 9; ++j) view.r[j] = copy(s.r[j], r[j]);
    for (uint32_t j = 0; j < 3; ++j) view.e[j] = copy(s.e[j], e[j]);
    for (uint32_t j = 0; j < 6; ++j) view.w[j] = copy(s.w[j], w[j]);
    view.ref = nullptr;
    if (s.ref != nullptr) {
      for (uint32_t i = 0; i < W; ++i) ref[i] = s.ref[k + (i < n ? i : n - 1)];
      view.ref = ref;
    }
  }
};

template <uint32_t W, uint32_t P>
struct TailOut {
  uint8_t count[W];
  float n[3][W], depth[W], point[P][3][W], pdepth[P][W];
  ManifoldSoA view() {
    ManifoldSoA m{};
    m.count = count;
    for (uint32_t j = 0; j < 3; ++j) m.n[j] = n[j];
    m.depth = depth;
    for (uint32_t i = 0; i < P; ++i) {
      for (uint32_t j = 0; j < 3; ++j) m.point[i][j] = point[i][j];
      m.pdepth[i] = pdepth[i];
    }
    return m;
  }
  void copy_to(const ManifoldSoA& out, uint32_t k, uint32_t n_lanes) const {
    for (uint32_t i = 0; i < n_lanes; ++i) {
      out.count[k + i] = count[i];
      for (uint32_t j = 0; j < 3; ++j) out.n[j][k + i] = n[j][i];
      out.depth[k + i] = depth[i];
      for (uint32_t q = 0; q < P; ++q) {
        for (uint32_t j = 0; j < 3; ++j) out.point[q][j][k + i] = point[q][j][i];
        out.pdepth[q][k + i] = pdepth[q][i];
      }
    }
  }
};

/// Runs block(a, b, out, k) for every full block of F::kWidth lanes of r, then the
/// tail through local copies. P = the point slots the kernel writes.
template <class F, uint32_t P, class Block>
IMPACT_INLINE void for_each_block(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, Range r,
                                  Block&& block) {
  constexpr uint32_t W = F::kWidth;
  uint32_t k = r.begin;
  for (; k + W <= r.end; k += W) block(a, b, out, k);
  if constexpr (W > 1) {
    if (k < r.end) {
      const uint32_t n = r.end - k;
      TailSide<W> ta, tb;
      ta.fill(a, k, n);
      tb.fill(b, k, n);
      TailOut<W, P> to{};  // zeroed: count-0 lanes may leave fields unwritten
      const ManifoldSoA lo = to.view();
      block(ta.view, tb.view, lo, 0u);
      to.copy_to(out, k, n);
    }
  }
}

// ---------------------------------------------------------------------------------------
// Live-lane driver: kernels whose lanes mostly stop at a cheap screen (about half the
// pairs of a bucket are apart) screen every block first, then run the expensive solve on
// the survivors only, gathered W at a time into full blocks.
// ---------------------------------------------------------------------------------------

/// A group's rows of the LeafSoA fields: its W listed lanes (ascending pair indices,
/// the padding repeating the last, all inside the range r) read through
/// simd::SortedGather (windows and permutes at 16 lanes, where 16-lane gathers cost
/// ~17 cycles each on AMD Zen 4; gathers elsewhere): one field, three (p, e or w rows)
/// or R by columns.
template <class F>
class GroupRows {
 public:
  IMPACT_INLINE GroupRows(const int32_t* live, Range r)
      : g_(F::Int::load(live), static_cast<int32_t>(r.begin), static_cast<int32_t>(r.end)) {}
  IMPACT_INLINE F operator()(const float* p) const { return g_(p); }
  IMPACT_INLINE V3<F> v3(const float* const* p) const { return {g_(p[0]), g_(p[1]), g_(p[2])}; }
  IMPACT_INLINE M3<F> rot(const LeafSoA& s) const {
    M3<F> m;
    for (uint32_t c = 0; c < 3; ++c) m.c[c] = {g_(s.r[c]), g_(s.r[3 + c]), g_(s.r[6 + c])};
    return m;
  }

 private:
  simd::SortedGather<F::kWidth> g_;
};

/// No per-lane payload.
struct NoExtra {};

/// A chunk's group results in live-list order (row i: the chunk's i-th listed lane), kept
/// until the chunk's groups are done, then expanded into the output blocks (contiguous,
/// masked stores per block instead of one scalar store per field and lane): count, n,
/// depth, and S point slots (absolute) with their depths.
template <class F, uint32_t S>
struct LiveOut {
  static constexpr uint32_t kW = F::kWidth;
  static constexpr uint32_t kRows = 17 * kW;  // kChunk + W: the last group's padding
  static constexpr uint32_t kFields = 4 + 4 * S;
  float f[kFields][kRows];
  int32_t count[kRows];
  uint32_t row = 0;  // the current group's first row

  /// The current group's lanes 0 .. W (padding lanes too: the next group's rows overwrite
  /// them, and the last group's lie past the list): points made absolute by adding origin.
  template <uint32_t P>
  IMPACT_INLINE void put(const Lanes<F, P>& m, const V3<F>& origin) {
    static_assert(S <= P);
    m.count.store(count + row);
    m.n.x.store(f[0] + row), m.n.y.store(f[1] + row), m.n.z.store(f[2] + row);
    m.depth.store(f[3] + row);
    for (uint32_t j = 0; j < S; ++j) {
      (origin.x + m.point[j].x).store(f[4 + 4 * j] + row);
      (origin.y + m.point[j].y).store(f[5 + 4 * j] + row);
      (origin.z + m.point[j].z).store(f[6 + 4 * j] + row);
      m.pdepth[j].store(f[7 + 4 * j] + row);
    }
  }
  /// Lanes l < cnt of m to rows rows[l] (any rows of the chunk's list; a kernel that
  /// finishes some lanes after their group, for_each_live_group's `finish`).
  template <uint32_t P>
  IMPACT_INLINE void put_rows(const Lanes<F, P>& m, const V3<F>& origin, const int32_t* rows, uint32_t cnt) {
    static_assert(S <= P);
    float t[kFields][kW];
    int32_t c[kW];
    m.count.store(c);
    m.n.x.store(t[0]), m.n.y.store(t[1]), m.n.z.store(t[2]);
    m.depth.store(t[3]);
    for (uint32_t j = 0; j < S; ++j) {
      (origin.x + m.point[j].x).store(t[4 + 4 * j]);
      (origin.y + m.point[j].y).store(t[5 + 4 * j]);
      (origin.z + m.point[j].z).store(t[6 + 4 * j]);
      m.pdepth[j].store(t[7 + 4 * j]);
    }
    for (uint32_t l = 0; l < cnt; ++l) {
      const auto r = static_cast<uint32_t>(rows[l]);
      count[r] = c[l];
      for (uint32_t q = 0; q < kFields; ++q) f[q][r] = t[q][l];
    }
  }
  /// Rows at .. at + popcount(bits) to the set lanes of block k .. k + W of out.
  IMPACT_INLINE void expand(const ManifoldSoA& out, uint32_t k, uint32_t bits, uint32_t at) const {
    simd::expand_store<kW>(out.count + k, count + at, bits);
    for (uint32_t q = 0; q < 3; ++q) simd::expand_store<kW>(out.n[q] + k, f[q] + at, bits);
    simd::expand_store<kW>(out.depth + k, f[3] + at, bits);
    for (uint32_t j = 0; j < S; ++j) {
      for (uint32_t q = 0; q < 3; ++q) simd::expand_store<kW>(out.point[j][q] + k, f[4 + 4 * j + q] + at, bits);
      simd::expand_store<kW>(out.pdepth[j] + k, f[7 + 4 * j] + at, bits);
    }
  }
};

/// The range kChunk = 16 W pairs at a time (16 blocks: a chunk's last, partly filled
/// group pads about W / 2 lanes; with 4 blocks that was ~20% of box-ellipsoid's live work):
///   bits = screen(va, vb, at, k, nb, extra): block k .. k + nb of the range (nb < W only
///     at the range's end), its lanes at `at` of the views va / vb (full-width copies in
///     a tail); bit l set: lane k + l goes on, with payload extra[l]. The driver writes
///     count 0 for every lane of the block first (the groups' lanes are overwritten).
///   group(index, extra, cnt, o): W listed lanes (cnt real ones, the rest repeating the
///     last); it hands its result, S point slots, to o.put (a LiveOut<F, S>), and the
///     driver writes them to lanes index[0 .. cnt) of the output once the chunk's groups
///     are done (LiveOut::expand, block by block).
///   finish(o) (optional): after the chunk's groups, before the expansion: a kernel that
///     set some lanes aside (their group's row o.row + l) completes them here, packed
///     into full groups, through o.put_rows.
/// The list and its length stay local here: appending through a struct member after the
/// byte stores of out.count made GCC reload and store the length around every lane (a
/// uint8_t store may alias anything; convex-halfspace measured ~30% slower that way).
/// Every computation is lane-wise, so a pair's bytes do not depend on which lanes share
/// its block or group.
template <class F, uint32_t S, class Extra = NoExtra, class Screen, class Group, class Finish>
IMPACT_INLINE void for_each_live_group(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, Range r,
                                       Screen&& screen, Group&& group, Finish&& finish) {
  constexpr uint32_t W = F::kWidth;
  constexpr uint32_t kChunk = 16 * W;
  LiveOut<F, S> lo;
  for (uint32_t k0 = r.begin; k0 < r.end; k0 += kChunk) {
    const uint32_t n = r.end - k0 < kChunk ? r.end - k0 : kChunk;
    int32_t index[kChunk + W];
    Extra extra[kChunk + W];
    uint32_t block_bits[16];
    uint32_t nlive = 0;
    for (uint32_t j = 0; j < n; j += W) {
      const uint32_t k = k0 + j, nb = n - j < W ? n - j : W;
      Extra ex[W]{};
      uint32_t bits;
      if (nb == W) {
        bits = screen(a, b, k, k, nb, ex);
      } else {
        TailSide<W> ta, tb;
        ta.fill(a, k, nb);
        tb.fill(b, k, nb);
        bits = screen(ta.view, tb.view, 0u, k, nb, ex);
      }
      bits &= nb == W ? ~0u : (1u << nb) - 1u;
      block_bits[j / W] = bits;
      std::memset(out.count + k, 0, nb);
      for (uint32_t l = 0; l < nb; ++l) {  // branch-free: written, then counted
        index[nlive] = static_cast<int32_t>(k + l);
        extra[nlive] = ex[l];
        nlive += (bits >> l) & 1u;
      }
    }
    for (uint32_t g = 0; g < nlive; g += W) {
      const uint32_t cnt = nlive - g < W ? nlive - g : W;
      for (uint32_t l = cnt; l < W; ++l) {  // padding repeats the last
        index[g + l] = index[g + cnt - 1];
        extra[g + l] = extra[g + cnt - 1];
      }
      lo.row = g;
      group(index + g, extra + g, cnt, lo);
    }
    finish(lo);
    for (uint32_t j = 0, at = 0; j < n; j += W) {
      const uint32_t bits = block_bits[j / W];
      lo.expand(out, k0 + j, bits, at);
      at += static_cast<uint32_t>(std::popcount(bits));
    }
  }
}
/// Without a finish step.
template <class F, uint32_t S, class Extra = NoExtra, class Screen, class Group>
IMPACT_INLINE void for_each_live_group(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, Range r,
                                       Screen&& screen, Group&& group) {
  for_each_live_group<F, S, Extra>(a, b, out, r, screen, group, [](LiveOut<F, S>&) {});
}

/// Lanes of a struct T of W-lane vectors (4-byte lanes, e.g. a solve's state) set aside
/// to be finished later packed into full blocks: a lane moves field by field (T seen as
/// rows of W int32), pushed by compaction, popped W at a time from the end.
template <class F, class T>
struct LaneQueue {
  static constexpr uint32_t kW = F::kWidth;
  static constexpr uint32_t kRows = sizeof(T) / (4 * kW);
  static_assert(sizeof(T) == kRows * 4 * kW && std::is_trivially_copyable_v<T>);
  int32_t q[kRows][2 * kW];  // fewer than kW held between pushes (pop after each), a push adds <= kW
  uint32_t n = 0;

  /// The lanes of v whose bit is set, appended.
  IMPACT_INLINE void push(const T& v, uint32_t bits) {
    alignas(64) int32_t raw[kRows][kW];
    std::memcpy(raw, &v, sizeof raw);
    uint32_t c = 0;
    for (uint32_t r = 0; r < kRows; ++r) c = simd::compact_store(q[r] + n, F::Int::load(raw[r]), bits);
    n += c;
  }
  /// The last min(n, kW) entries into v (fewer: the last one repeated); returns how many.
  IMPACT_INLINE uint32_t pop(T& v) {
    const uint32_t cnt = n < kW ? n : kW, at = n - cnt;
    alignas(64) int32_t raw[kRows][kW];
    if (cnt == kW) {
      for (uint32_t r = 0; r < kRows; ++r) std::memcpy(raw[r], q[r] + at, sizeof raw[r]);
    } else {
      for (uint32_t r = 0; r < kRows; ++r)
        for (uint32_t l = 0; l < kW; ++l) raw[r][l] = q[r][at + (l < cnt ? l : cnt - 1)];
    }
    std::memcpy(&v, raw, sizeof raw);
    n = at;
    return cnt;
  }
};

/// The body of a lane kernel's PairKernel over its block template `block<F>(a, b, out, k)`
/// writing P point slots: for_each_block at simd::Float1 (one lane, the reference path)
/// for KernelPath::kScalar, else at simd::FloatP (kPairWidth lanes). Every pair function
/// is defined by its own name and forwards here, e.g.
///   void collide_sphere_sphere(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out,
///                              Range r, const NarrowConfig& cfg) {
///     IMPACT_LANE_KERNEL_BODY(sphere_sphere_block, 1);
///   }
/// A macro, not a function template, because `block` is a function template (and the
/// lambdas must stay in the pair function for its inlining); it reads the PairKernel
/// parameters a, b, out, r and cfg.
#define IMPACT_LANE_KERNEL_BODY(block, P)                                                                  \
  {                                                                                                       \
    if (cfg.path == KernelPath::kScalar) {                                                                \
      for_each_block<simd::Float1, P>(                                                                    \
          a, b, out, r, [](const LeafSoA& aa, const LeafSoA& bb, const ManifoldSoA& o, uint32_t k) {      \
            block<simd::Float1>(aa, bb, o, k);                                                            \
          });                                                                                             \
    } else {                                                                                              \
      for_each_block<simd::FloatP, P>(                                                                    \
          a, b, out, r, [](const LeafSoA& aa, const LeafSoA& bb, const ManifoldSoA& o, uint32_t k) {      \
            block<simd::FloatP>(aa, bb, o, k);                                                            \
          });                                                                                             \
    }                                                                                                     \
  }

// ---------------------------------------------------------------------------------------
// Geometry
// ---------------------------------------------------------------------------------------

/// Squared lengths below this are treated as zero (normalising them would lose all
/// precision): the smallest normal float.
inline constexpr float kTinySq = FLT_MIN;

/// A unit vector perpendicular to unit u, chosen deterministically: u x (the world axis
/// least aligned with u).
template <class F>
IMPACT_INLINE V3<F> any_perpendicular(const V3<F>& u) {
  const F ax = abs(u.x), ay = abs(u.y), az = abs(u.z);
  const auto use_x = (ax <= ay) & (ax <= az);
  const auto use_y = andnot(ay <= az, use_x);
  // u x e_x = (0, uz, -uy); u x e_y = (-uz, 0, ux); u x e_z = (uy, -ux, 0)
  const F zero(0.0f);
  V3<F> c = {u.y, -u.x, zero};
  c = select(use_y, V3<F>{-u.z, zero, u.x}, c);
  c = select(use_x, V3<F>{zero, u.z, -u.y}, c);
  const F inv = F(1.0f) / sqrt(length_sq(c));
  return c * inv;
}

/// v / |v|, or fallback where |v|^2 < kTinySq. len receives |v| (0 where fallback).
template <class F>
IMPACT_INLINE V3<F> normalize_or(const V3<F>& v, const V3<F>& fallback, F& len) {
  const F l2 = length_sq(v);
  const auto ok = l2 >= F(kTinySq);
  const F l = sqrt(l2);
  const F inv = F(1.0f) / select(ok, l, F(1.0f));
  len = select(ok, l, F(0.0f));
  return select(ok, v * inv, fallback);
}

/// Parameter t in [-h, h] of the point of segment c + t*u (u unit) closest to q.
template <class F>
IMPACT_INLINE F closest_on_segment(const V3<F>& c, const V3<F>& u, F h, const V3<F>& q) {
  return clamp(dot(q - c, u), -h, h);
}

/// Distance lambda from the core point at axial parameter t (|t| <= h) along unit
/// direction n (s = n.axis) to the capsule's surface: through the cylinder, or through
/// an end cap where the cylinder exit would lie beyond the segment (capsule-capsule, -box,
/// -triangle, -half-space, -cylinder manifolds).
template <class F>
IMPACT_INLINE F capsule_exit(F t, F s, F r, F h) {
  const F c2 = max(F(1.0f) - s * s, F(1e-12f));  // sin^2 of the angle to the axis
  const F lc = r / sqrt(c2);
  const F ax = mul_add(lc, s, t);
  const auto over = ax > h, under = ax < -h;
  const F delta = select(over, t - h, t + h);  // from the cap's centre
  const F disc = max(r * r - delta * delta * c2, F(0.0f));
  const F lcap = sqrt(disc) - delta * s;
  return select(over | under, lcap, lc);
}

/// Closest points of segments A: pa + s*ua, s in [-ha, ha] and B: pb + t*ub, t in
/// [-hb, hb] (ua, ub unit). Robust for parallel and degenerate (h = 0) segments: with
/// near-parallel axes s is the middle of the overlap of B's projection onto A
/// (Ericson, Real-Time Collision Detection 5.1.9, with that parallel rule).
template <class F>
IMPACT_INLINE void closest_segment_segment(const V3<F>& pa, const V3<F>& ua, F ha, const V3<F>& pb,
                                           const V3<F>& ub, F hb, F& s, F& t) {
  const V3<F> r = pa - pb;
  const F b = dot(ua, ub);
  const F c = dot(ua, r);
  const F f = dot(ub, r);
  const F denom = length_sq(cross(ua, ub));  // 1 - b^2 without cancellation
  const auto parallel = denom < F(1e-10f);
  // Non-parallel: the unconstrained minimiser's s, clamped.
  const F s_gen = clamp((b * f - c) / select(parallel, F(1.0f), denom), -ha, ha);
  // Parallel: middle of [-ha, ha] intersected with B's projection [-c - |b|hb, -c + |b|hb].
  const F ext = abs(b) * hb;
  const F lo = max(-ha, -c - ext), hi = min(ha, -c + ext);
  const F s_par = clamp(F(0.5f) * (lo + hi), -ha, ha);
  s = select(parallel, s_par, s_gen);
  const F t_raw = mul_add(b, s, f);
  t = clamp(t_raw, -hb, hb);
  const F s_back = clamp(mul_add(b, t, -c), -ha, ha);
  s = select(t_raw != t, s_back, s);
}

/// Closest point of triangle (a, b, c) to q (Ericson 5.1.5, regions by selects; the
/// interior point is the projection onto the plane, which keeps its precision for
/// large triangles). Returns the point; region_face receives the interior lanes.
template <class F>
IMPACT_INLINE V3<F> closest_on_triangle(const V3<F>& a, const V3<F>& b, const V3<F>& c, const V3<F>& q,
                                        const V3<F>& unit_normal, typename F::Mask& region_face) {
  const V3<F> ab = b - a, ac = c - a, bc = c - b;
  const V3<F> ap = q - a, bp = q - b, cp = q - c;
  const F d1 = dot(ab, ap), d2 = dot(ac, ap);
  const F d3 = dot(ab, bp), d4 = dot(ac, bp);
  const F d5 = dot(ab, cp), d6 = dot(ac, cp);
  const F zero(0.0f), one(1.0f);
  const F vc = d1 * d4 - d3 * d2;
  const F vb = d5 * d2 - d1 * d6;
  const F va = d3 * d6 - d5 * d4;
  const auto in_a = (d1 <= zero) & (d2 <= zero);
  const auto in_b = (d3 >= zero) & (d4 <= d3);
  const auto in_ab = (vc <= zero) & (d1 >= zero) & (d3 <= zero);
  const auto in_c = (d6 >= zero) & (d5 <= d6);
  const auto in_ac = (vb <= zero) & (d2 >= zero) & (d6 <= zero);
  const auto in_bc = (va <= zero) & ((d4 - d3) >= zero) & ((d5 - d6) >= zero);
  // Edge points by projection onto the edge (accurate), clamped.
  const F lab = length_sq(ab), lac = length_sq(ac), lbc = length_sq(bc);
  const F tab = clamp(d1 / select(lab > zero, lab, one), zero, one);
  const F tac = clamp(d2 / select(lac > zero, lac, one), zero, one);
  const F tbc = clamp(dot(bc, bp) / select(lbc > zero, lbc, one), zero, one);
  V3<F> r = q - unit_normal * dot(unit_normal, ap);
  r = select(in_bc, madd(b, tbc, bc), r);
  r = select(in_ac, madd(a, tac, ac), r);
  r = select(in_c, c, r);
  r = select(in_ab, madd(a, tab, ab), r);
  r = select(in_b, b, r);
  r = select(in_a, a, r);
  region_face = ~(in_a | in_b | in_ab | in_c | in_ac | in_bc);
  return r;
}

/// Unit normal of triangle (a, b, c) (counter-clockwise); for a degenerate triangle a
/// unit vector perpendicular to its longest edge (or +z for a point).
template <class F>
IMPACT_INLINE V3<F> triangle_normal(const V3<F>& a, const V3<F>& b, const V3<F>& c) {
  const V3<F> ab = b - a, ac = c - a, bc = c - b;
  const V3<F> nrm = cross(ab, ac);
  F l;
  // Fallback: perpendicular to the longest edge.
  const F lab = length_sq(ab), lac = length_sq(ac), lbc = length_sq(bc);
  V3<F> e = select(lab >= lac, ab, ac);
  e = select(lbc > max(lab, lac), bc, e);
  F el;
  const V3<F> eu = normalize_or(e, V3<F>{F(0.0f), F(0.0f), F(1.0f)}, el);
  return normalize_or(nrm, any_perpendicular(eu), l);
}

// ---------------------------------------------------------------------------------------
// Manifold reduction
// ---------------------------------------------------------------------------------------

/// Picks lane-wise among three values by an index lane holding 0, 1 or 2.
template <class F, class T>
IMPACT_INLINE T pick3(F idx, const T& v0, const T& v1, const T& v2) {
  return select(idx == F(0.0f), v0, select(idx == F(1.0f), v1, v2));
}

/// One level of tree_extreme: folds the top half of t[0 .. N) onto the bottom, then the
/// rest. N is a template parameter so every level unrolls completely and t stays in
/// registers (a run-time level count left GCC a loop over a stack copy of t).
template <bool Max, int N, class F>
IMPACT_INLINE F tree_fold(F* t) {
  if constexpr (N == 1) {
    return t[0];
  } else {
    constexpr int h = N / 2;
#pragma GCC unroll 16
    for (int i = 0; i < h; ++i) t[i] = Max ? max(t[i], t[N - 1 - i]) : min(t[i], t[N - 1 - i]);
    return tree_fold<Max, N - h>(t);
  }
}

/// Lane-wise maximum (Max = true) or minimum of M values, as a tree (depth log2 M, no
/// serial dependency). min/max of non-NaN floats is exact, so the order is free.
template <bool Max, class F, int M>
IMPACT_INLINE F tree_extreme(const F (&v)[M]) {
  F t[M];
#pragma GCC unroll 32
  for (int i = 0; i < M; ++i) t[i] = v[i];
  return tree_fold<Max, M>(t);
}

/// Reduces M <= 32 candidate points (2-D coordinates x, y in a plane, depth d, valid)
/// to at most 4: the deepest, the farthest from it, then the largest-area point on
/// each side of that diagonal. tol: lengths below it count as coincident.
/// Each choice is one max/min tree over keys that carry their candidate's index in
/// their low bits (simd::tag), then a per-lane pick of the winner (gather_lanes): no
/// select chain through the candidates. Keys equal to ~4e-6 relative may resolve
/// either way (deterministically). idx receives the chosen candidates' indices (slots
/// count .. 3 repeat chosen ones), for kernels that carry more than (x, y, d) per point,
/// and ox, oy their coordinates.
template <class F, int M>
IMPACT_INLINE void reduce4_indices(const F (&x)[M], const F (&y)[M], const F (&d)[M],
                                   const typename F::Mask (&valid)[M], F tol, typename F::Int (&idx)[4],
                                   typename F::Int& count, F (&ox)[4], F (&oy)[4]) {
  static_assert(M <= 32, "tag() holds indices below 32");
  using Mask = typename F::Mask;
  using Int = typename F::Int;
  const F zero(0.0f);
  const F neg(-3.0e38f), pos(3.0e38f);
  F key[M], key2[M];
  // deepest
  Mask any = valid[0];
  for (int i = 1; i < M; ++i) any = any | valid[i];
  for (int i = 0; i < M; ++i) key[i] = simd::tag(select(valid[i], d[i], neg), i);
  const Int ib = simd::tag_index(tree_extreme<true>(key));
  const F bx = simd::gather_lanes(x, ib), by = simd::gather_lanes(y, ib);
  // farthest from it
  for (int i = 0; i < M; ++i) {
    const F dx = x[i] - bx, dy = y[i] - by;
    key[i] = simd::tag(select(valid[i], dx * dx + dy * dy, neg), i);
  }
  const Int jf = simd::tag_index(tree_extreme<true>(key));
  const F fx = simd::gather_lanes(x, jf), fy = simd::gather_lanes(y, jf);
  const F fd2 = (fx - bx) * (fx - bx) + (fy - by) * (fy - by);
  const Mask v1 = fd2 > tol * tol;
  // largest signed area on either side of the diagonal
  const F ex = fx - bx, ey = fy - by;
  for (int i = 0; i < M; ++i) {
    const F ar = ex * (y[i] - by) - ey * (x[i] - bx);
    key[i] = simd::tag(select(valid[i], ar, neg), i);
    key2[i] = simd::tag(select(valid[i], ar, pos), i);
  }
  const Int jp = simd::tag_index(tree_extreme<true>(key)), jq = simd::tag_index(tree_extreme<false>(key2));
  const F px = simd::gather_lanes(x, jp), py = simd::gather_lanes(y, jp);
  const F qx = simd::gather_lanes(x, jq), qy = simd::gather_lanes(y, jq);
  const F amax = ex * (py - by) - ey * (px - bx), amin = ex * (qy - by) - ey * (qx - bx);
  const F area_tol = tol * sqrt(max(fd2, zero));
  const Mask v2 = v1 & (amax > area_tol);
  const Mask v3 = v1 & (-amin > area_tol);
  idx[0] = ib;
  idx[1] = jf;
  idx[2] = select(v2, jp, jq);
  idx[3] = jq;
  ox[0] = bx, oy[0] = by;
  ox[1] = fx, oy[1] = fy;
  ox[2] = select(v2, px, qx), oy[2] = select(v2, py, qy);
  ox[3] = qx, oy[3] = qy;
  const Int c = Int(1) + simd::to_int(v1) + simd::to_int(v2 | v3) + simd::to_int(v2 & v3);
  count = select(any, c, Int(0));
}

/// reduce4_indices, returning the chosen candidates' values: the outputs are the
/// candidates' exact values.
template <class F, int M>
IMPACT_INLINE void reduce4(const F (&x)[M], const F (&y)[M], const F (&d)[M],
                           const typename F::Mask (&valid)[M], F tol, F (&ox)[4], F (&oy)[4], F (&od)[4],
                           typename F::Int& count) {
  typename F::Int idx[4];
  reduce4_indices<F, M>(x, y, d, valid, tol, idx, count, ox, oy);
  for (int i = 0; i < 4; ++i) od[i] = simd::gather_lanes(d, idx[i]);
}

/// Candidate 0 of a clipped manifold is the winning candidate's witness (as deep as the
/// contact, on both surfaces, so never none). It stays only where no other candidate is
/// that deep (within tol): else it lies among them (the middle of a segment contact) and
/// would keep reduce4 from picking the contact's ends.
template <class F, int M>
IMPACT_INLINE void drop_shadowed_witness(const F (&d)[M], typename F::Mask (&valid)[M], F o, F tol) {
  F deepest(-3.0e38f);
  for (int i = 1; i < M; ++i) deepest = max(deepest, select(valid[i], d[i], F(-3.0e38f)));
  valid[0] = valid[0] & (deepest < o - tol);
}

/// The tail of a side-contact manifold against a cylinder (box-cylinder,
/// cylinder-triangle): M candidate points ca (0: the witness) with their gaps d and
/// validity, in the cylinder's frame, where (mx, my) is the side's horizontal unit
/// normal along n: candidates without a positive gap and a shadowed witness dropped,
/// reduced to 4 in the side's own 2-D coordinates (across (mx, my), and z), and the
/// chosen ones written to m where `use` (count, points, pdepth = min(gap, o)). kHalfBack:
/// each chosen point is moved by -gap/2 along n (candidates on the far surface).
template <class F, int M, bool kHalfBack>
IMPACT_INLINE void side_manifold_tail(const V3<F> (&ca)[M], F (&d)[M], typename F::Mask (&valid)[M], F o,
                                      F tol, F mx, F my, const V3<F>& n, typename F::Mask use,
                                      Lanes<F, 4>& m) {
  using Int = typename F::Int;
  F c2x[M], c2y[M], ax[M], ay[M], az[M];
  for (int i = 0; i < M; ++i) {
    valid[i] = valid[i] & (d[i] > F(0.0f));
    c2x[i] = ca[i].y * mx - ca[i].x * my, c2y[i] = ca[i].z;
    ax[i] = ca[i].x, ay[i] = ca[i].y, az[i] = ca[i].z;
  }
  drop_shadowed_witness<F, M>(d, valid, o, tol);
  Int idx[4], cnt;
  F ox[4], oy[4];
  reduce4_indices<F, M>(c2x, c2y, d, valid, tol, idx, cnt, ox, oy);
  const typename F::Mask on = use & (cnt > Int(0));
  m.count = select(on, cnt, m.count);
  for (int i = 0; i < 4; ++i) {
    V3<F> q{simd::gather_lanes(ax, idx[i]), simd::gather_lanes(ay, idx[i]), simd::gather_lanes(az, idx[i])};
    const F dq = simd::gather_lanes(d, idx[i]);
    if constexpr (kHalfBack) q = madd(q, F(-0.5f) * dq, n);
    m.point[i] = select(on, q, m.point[i]);
    m.pdepth[i] = select(on, min(dq, o), m.pdepth[i]);
  }
}

/// The least candidate whose witness checks out, and the least of all (an upper bound
/// either way), of the kernels on candidate normals (box-cylinder, cylinder-cylinder):
/// o, the normal, A's witness point x. take() keeps the first of equal o's.
template <class F>
struct WitnessedBest {
  F o, any_o;
  V3<F> n, x, any_n, any_x;
  IMPACT_INLINE void init() {
    o = any_o = F(3.0e38f);
    n = any_n = V3<F>{F(0.0f), F(0.0f), F(1.0f)};
    x = any_x = n;
  }
  IMPACT_INLINE void take(F o2, const V3<F>& n2, const V3<F>& x2, typename F::Mask valid) {
    const auto ma = o2 < any_o;
    any_o = select(ma, o2, any_o);
    any_n = select(ma, n2, any_n);
    any_x = select(ma, x2, any_x);
    const auto m = valid & (o2 < o);
    o = select(m, o2, o);
    n = select(m, n2, n);
    x = select(m, x2, x);
  }
};

/// WitnessedBest lanes in a chunk's state, one array per field: st[0] o, st[1..3] n,
/// st[4..6] x, st[7] any_o, st[8..10] any_n, st[11..13] any_x. write_best hands field f's
/// lanes to put(f, lanes) and read_best builds one from row(f); the loads and stores
/// below (contiguous lanes j .., or gathered / scattered listed lanes) go through them.
template <class F, class Put>
IMPACT_INLINE void write_best(const WitnessedBest<F>& b, Put&& put) {
  auto p3 = [&](int f, const V3<F>& v) IMPACT_LAMBDA_INLINE { put(f, v.x), put(f + 1, v.y), put(f + 2, v.z); };
  put(0, b.o), p3(1, b.n), p3(4, b.x);
  put(7, b.any_o), p3(8, b.any_n), p3(11, b.any_x);
}
template <class F, class Row>
IMPACT_INLINE WitnessedBest<F> read_best(Row&& row) {
  auto l3 = [&](int f) IMPACT_LAMBDA_INLINE { return V3<F>{row(f), row(f + 1), row(f + 2)}; };
  WitnessedBest<F> b;
  b.o = row(0), b.n = l3(1), b.x = l3(4), b.any_o = row(7), b.any_n = l3(8), b.any_x = l3(11);
  return b;
}
/// Lanes j .. j + width.
template <class F, uint32_t L>
IMPACT_INLINE void save_best(float (&st)[14][L], uint32_t j, const WitnessedBest<F>& b) {
  write_best(b, [&](int f, const F& v) IMPACT_LAMBDA_INLINE { v.store(st[f] + j); });
}
template <class F, uint32_t L>
IMPACT_INLINE WitnessedBest<F> load_best(const float (&st)[14][L], uint32_t j) {
  return read_best<F>([&](int f) IMPACT_LAMBDA_INLINE { return F::load(st[f] + j); });
}
/// Appends chunk lanes j + l (l < nb) where m is set to list[count ..] and advances
/// count (list holds W entries past the end: compact_store writes them).
template <class F>
IMPACT_INLINE void list_lanes(int32_t* list, uint32_t& count, typename F::Mask m, uint32_t j,
                              uint32_t nb) {
  constexpr uint32_t W = F::kWidth;
  uint32_t bits = simd::bits(m);
  if (nb < W) bits &= (1u << nb) - 1u;
  count += simd::compact_store(list + count, simd::lane_ids<typename F::Int>(static_cast<int32_t>(j)), bits);
}

/// group(idx, real) over list[0 .. count) W entries at a time (count > 0; the last group
/// padded by repeating the last entry, real = the group's entries from the list).
template <class F, class Group>
IMPACT_INLINE void for_each_listed(int32_t* list, uint32_t count, Group&& group) {
  constexpr uint32_t W = F::kWidth;
  for (uint32_t l = count; l < (count + W - 1) / W * W; ++l) list[l] = list[count - 1];
  for (uint32_t at = 0; at < count; at += W)
    group(F::Int::load(list + at), count - at < W ? count - at : W);
}

/// save_best, the lanes not near marked apart (o = any_o = -1).
template <class F, uint32_t L>
IMPACT_INLINE void save_best_near(float (&st)[14][L], uint32_t j, WitnessedBest<F> b,
                                  typename F::Mask near) {
  b.o = select(near, b.o, F(-1.0f));
  b.any_o = select(near, b.any_o, F(-1.0f));
  save_best<F>(st, j, b);
}

/// load_best for lanes idx of the chunk (a packed group's lanes, ascending: read by
/// windows, simd::SortedGather).
template <class F, uint32_t L>
IMPACT_INLINE WitnessedBest<F> gather_best(const float (&st)[14][L], typename F::Int idx) {
  const simd::SortedGather<F::kWidth> rows(idx, 0, static_cast<int32_t>(L));
  return read_best<F>([&](int f) IMPACT_LAMBDA_INLINE { return rows(st[f]); });
}
/// save_best for the first `real` lanes of idx (a packed group's listed lanes; the
/// padding lanes, repeats of the last, are not written).
template <class F, uint32_t L>
IMPACT_INLINE void scatter_best(float (&st)[14][L], typename F::Int idx, uint32_t real,
                                const WitnessedBest<F>& b) {
  constexpr uint32_t W = F::kWidth;
  float rows[14][W];
  write_best(b, [&](int f, const F& v) IMPACT_LAMBDA_INLINE { v.store(rows[f]); });
  int32_t ln[W];
  idx.store(ln);
  for (uint32_t l = 0; l < real; ++l)
    for (int f = 0; f < 14; ++f) st[f][ln[l]] = rows[f][l];
}

/// Merges one packed candidate per lane (o, n, x, valid) of cnt listed lanes (chunk lanes
/// lane[0 .. cnt)) into the chunk's WitnessedBest state, lane by lane in list order.
template <class F, uint32_t L>
IMPACT_INLINE void merge_best(float (&st)[14][L], const int32_t* lane, uint32_t cnt, F o, const V3<F>& n,
                              const V3<F>& x, typename F::Mask valid) {
  constexpr uint32_t W = F::kWidth;
  float ro[W], rv[W], rn[3][W], rx[3][W];
  o.store(ro);
  select(valid, F(1.0f), F(0.0f)).store(rv);
  n.x.store(rn[0]), n.y.store(rn[1]), n.z.store(rn[2]);
  x.x.store(rx[0]), x.y.store(rx[1]), x.z.store(rx[2]);
  for (uint32_t l = 0; l < cnt; ++l) {
    const auto ln = static_cast<uint32_t>(lane[l]);
    if (ro[l] < st[7][ln]) {
      st[7][ln] = ro[l];
      for (int q = 0; q < 3; ++q) st[8 + q][ln] = rn[q][l], st[11 + q][ln] = rx[q][l];
    }
    if (rv[l] != 0.0f && ro[l] < st[0][ln]) {
      st[0][ln] = ro[l];
      for (int q = 0; q < 3; ++q) st[1 + q][ln] = rn[q][l], st[4 + q][ln] = rx[q][l];
    }
  }
}

/// The part t0 <= t1 of the 2-D segment a0 + a1 t, |t| <= h, inside the disk |p| <= r
/// (a quadratic in t); false where it is empty. A segment that does not move (|a1|^2 below
/// kTinySq) is inside or not as a whole.
template <class F>
IMPACT_INLINE typename F::Mask clip_segment_disk(F a0x, F a0y, F a1x, F a1y, F r, F h, F& t0, F& t1) {
  const F zero(0.0f), one(1.0f);
  const F qa = a1x * a1x + a1y * a1y, qb = a0x * a1x + a0y * a1y;
  const F qc = a0x * a0x + a0y * a0y - r * r;
  const F disc = qb * qb - qa * qc;
  const auto moving = qa > F(kTinySq);
  const F root = sqrt(max(disc, zero)), ia = one / select(moving, qa, one);
  t0 = max(select(moving, (-qb - root) * ia, -h), -h);
  t1 = min(select(moving, (root - qb) * ia, h), h);
  return select(moving, disc >= zero, qc <= zero) & (t0 <= t1);
}

/// Rim samples of the cap manifolds against a cylinder (box-cylinder, cylinder-cylinder):
/// cos of multiples of 45 degrees (the sin of sample i is kRimCos[(i + 6) % 8]).
inline constexpr int kRimSamples = 8;
inline constexpr float kRimCos[kRimSamples] = {1.0f,  0.70710678f,  0.0f, -0.70710678f,
                                               -1.0f, -0.70710678f, 0.0f, 0.70710678f};

/// The tail of a cap-contact manifold against a cylinder (box-cylinder, cylinder-cylinder):
/// M candidate points (x, y) on the cap plane z = zc (0: the witness) with their gaps d
/// along n and validity: candidates without a positive gap and a shadowed witness dropped,
/// reduced to 4 in the plane, and the chosen ones written to m where `use` (count, the
/// points moved by half their gap along n, pdepth = min(gap, o)).
template <class F, int M>
IMPACT_INLINE void cap_manifold_tail(const F (&x)[M], const F (&y)[M], F (&d)[M],
                                     typename F::Mask (&valid)[M], F o, F tol, F zc, const V3<F>& n,
                                     typename F::Mask use, Lanes<F, 4>& m) {
  using Int = typename F::Int;
  for (int i = 0; i < M; ++i) valid[i] = valid[i] & (d[i] > F(0.0f));
  drop_shadowed_witness<F, M>(d, valid, o, tol);
  F ox[4], oy[4], od[4];
  Int cnt;
  reduce4<F, M>(x, y, d, valid, tol, ox, oy, od, cnt);
  const typename F::Mask on = use & (cnt > Int(0));
  m.count = select(on, cnt, m.count);
  for (int i = 0; i < 4; ++i) {
    const V3<F> p = madd(V3<F>{ox[i], oy[i], zc}, F(0.5f) * od[i], n);
    m.point[i] = select(on, p, m.point[i]);
    m.pdepth[i] = select(on, min(od[i], o), m.pdepth[i]);
  }
}

/// Runs a lane kernel in three phases over r, C::kLanes pairs (a chunk) at a time:
/// phase_a(a, b, k, j, nb, ch) for each block (k: its first pair, j: its first lane in
/// the chunk, nb: its real lanes), then phase_b(ch) (work the blocks listed in the chunk
/// state, packed across them; it leaves the chunk's lists empty), then
/// phase_c(a, b, out, k, j, ch) for each block. A block past the range's end runs on local
/// full-width copies (TailSide, TailOut), as for_each_block's tail does.
template <class F, uint32_t P, class C, class PhaseA, class PhaseB, class PhaseC>
IMPACT_INLINE void for_each_chunk(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, Range r, C& ch,
                                  PhaseA&& phase_a, PhaseB&& phase_b, PhaseC&& phase_c) {
  constexpr uint32_t W = F::kWidth;
  for (uint32_t k0 = r.begin; k0 < r.end; k0 += C::kLanes) {
    const uint32_t n = r.end - k0 < C::kLanes ? r.end - k0 : C::kLanes;
    for (uint32_t j = 0; j < n; j += W) {
      const uint32_t k = k0 + j, nb = n - j < W ? n - j : W;
      if (nb == W) {
        phase_a(a, b, k, j, nb, ch);
      } else {
        TailSide<W> ta, tb;
        ta.fill(a, k, nb);
        tb.fill(b, k, nb);
        phase_a(ta.view, tb.view, 0u, j, nb, ch);
      }
    }
    phase_b(ch);
    for (uint32_t j = 0; j < n; j += W) {
      const uint32_t k = k0 + j, nb = n - j < W ? n - j : W;
      if (nb == W) {
        phase_c(a, b, out, k, j, ch);
      } else {
        TailSide<W> ta, tb;
        ta.fill(a, k, nb);
        tb.fill(b, k, nb);
        TailOut<W, P> to{};
        phase_c(ta.view, tb.view, to.view(), 0u, j, ch);
        to.copy_to(out, k, nb);
      }
    }
  }
}

}  // namespace impact::kernels::prim
