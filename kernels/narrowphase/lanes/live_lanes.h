// Live-lane drivers of the specialised narrow-phase kernels (kernels/narrowphase/pairs/):
// kernels whose lanes mostly stop at a cheap screen (about half the pairs of a bucket are
// apart) screen every block first, then run the expensive solve on the survivors only,
// gathered W at a time into full blocks (for_each_live_group, GroupRows, LiveOut); lanes
// set aside to finish packed (LaneQueue); lane lists (list_lanes, for_each_listed).
// Every computation is lane-wise, so a pair's bytes do not depend on which lanes share
// its block or group.
#pragma once

#include <bit>
#include <cstdint>
#include <cstring>
#include <type_traits>

#include "kernels/narrowphase/lanes/block_driver.h"
#include "kernels/narrowphase/lanes/lane_io.h"
#include "kernels/narrowphase/leaf/leaf.h"
#include "kernels/simd/lanes.h"

namespace impact::kernels::prim {

using simd::M3;
using simd::V3;

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

}  // namespace impact::kernels::prim
