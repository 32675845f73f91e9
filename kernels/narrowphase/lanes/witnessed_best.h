// The running best candidate of the kernels on candidate normals (box-cylinder,
// cylinder-cylinder, kernels/narrowphase/pairs/): WitnessedBest (the least support
// overlap whose witness checks out, and the least of all), and its per-chunk state of
// one array per field: saved and loaded by contiguous lanes, gathered and scattered by
// listed lanes, merged from packed solves.
#pragma once

#include <cstdint>

#include "kernels/simd/lanes.h"
#include "kernels/simd/vec3.h"

namespace impact::kernels::prim {

using simd::M3;
using simd::V3;

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

}  // namespace impact::kernels::prim
