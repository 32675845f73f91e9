// Independent double-precision reference for the broad phase: boxes as SoA,
// an O(n^2) all-pairs oracle and a sort-and-sweep oracle for large inputs, both
// written from the documented contract (include/impact/broadphase.h):
//   boxes i < j pair  <=>  min <= max on all axes (touching counts),
//                          (layer_i & mask_j) && (layer_j & mask_i),
//                          not (static_i && static_j).
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <iterator>
#include <numeric>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "impact/impact.h"

namespace impact::test {

using PairVec = std::vector<std::pair<uint32_t, uint32_t>>;

struct Boxes {
  std::vector<float> min_x, min_y, min_z, max_x, max_y, max_z;
  std::vector<uint32_t> layer, mask;
  std::vector<uint8_t> is_static;

  size_t size() const { return min_x.size(); }
  void add(float cx, float cy, float cz, float hx, float hy, float hz) {
    min_x.push_back(cx - hx);
    min_y.push_back(cy - hy);
    min_z.push_back(cz - hz);
    max_x.push_back(cx + hx);
    max_y.push_back(cy + hy);
    max_z.push_back(cz + hz);
  }
  void add_box(float x0, float y0, float z0, float x1, float y1, float z1) {
    min_x.push_back(x0);
    min_y.push_back(y0);
    min_z.push_back(z0);
    max_x.push_back(x1);
    max_y.push_back(y1);
    max_z.push_back(z1);
  }
  bool filtered() const { return !layer.empty(); }
  AabbInput input() const {
    return AabbInput{min_x, min_y, min_z, max_x, max_y, max_z, layer, mask, is_static};
  }
};

inline bool ref_overlap(const Boxes& b, size_t i, size_t j) {
  auto le = [](float x, float y) { return static_cast<double>(x) <= static_cast<double>(y); };
  return le(b.min_x[i], b.max_x[j]) && le(b.min_x[j], b.max_x[i]) && le(b.min_y[i], b.max_y[j]) &&
         le(b.min_y[j], b.max_y[i]) && le(b.min_z[i], b.max_z[j]) && le(b.min_z[j], b.max_z[i]);
}

inline bool ref_filter(const Boxes& b, size_t i, size_t j) {
  if (!b.filtered()) return true;
  if ((b.layer[i] & b.mask[j]) == 0 || (b.layer[j] & b.mask[i]) == 0) return false;
  return !(b.is_static[i] && b.is_static[j]);
}

// O(n^2), double precision, sorted (a, b) with a < b.
inline PairVec reference_pairs_n2(const Boxes& b) {
  PairVec out;
  for (size_t i = 0; i < b.size(); ++i)
    for (size_t j = i + 1; j < b.size(); ++j)
      if (ref_overlap(b, i, j) && ref_filter(b, i, j))
        out.emplace_back(static_cast<uint32_t>(i), static_cast<uint32_t>(j));
  return out;
}

// Sort-and-sweep on min_x (double), for inputs too large for O(n^2). Sorted output.
inline PairVec reference_pairs_sweep(const Boxes& b) {
  std::vector<uint32_t> order(b.size());
  std::iota(order.begin(), order.end(), 0u);
  std::sort(order.begin(), order.end(), [&](uint32_t p, uint32_t q) {
    return b.min_x[p] != b.min_x[q] ? b.min_x[p] < b.min_x[q] : p < q;
  });
  PairVec out;
  for (size_t s = 0; s < order.size(); ++s) {
    const uint32_t i = order[s];
    for (size_t t = s + 1; t < order.size(); ++t) {
      const uint32_t j = order[t];
      if (static_cast<double>(b.min_x[j]) > static_cast<double>(b.max_x[i])) break;
      if (ref_overlap(b, i, j) && ref_filter(b, i, j)) out.emplace_back(std::min(i, j), std::max(i, j));
    }
  }
  std::sort(out.begin(), out.end());
  return out;
}

inline PairVec reference_pairs(const Boxes& b) {
  return b.size() <= 6000 ? reference_pairs_n2(b) : reference_pairs_sweep(b);
}

/// Any range of structs with .a and .b (BodyPair, kernels::Pair) as (a, b) pairs.
template <class Range>
PairVec to_vec(const Range& p) {
  PairVec v;
  v.reserve(p.size());
  for (const auto& q : p) v.emplace_back(q.a, q.b);
  return v;
}

// a < b, in range, no duplicates; then equal to ref as sets.
template <class Range>
void expect_same_set(const Range& got, const PairVec& ref, size_t n, const std::string& what) {
  PairVec g = to_vec(got);
  for (const auto& [a, b] : g) {
    ASSERT_LT(a, b) << what;
    ASSERT_LT(b, n) << what;
  }
  std::sort(g.begin(), g.end());
  const auto dup = std::adjacent_find(g.begin(), g.end());
  ASSERT_TRUE(dup == g.end()) << what << ": duplicate pair (" << dup->first << ", " << dup->second << ")";
  if (g == ref) return;
  PairVec missing, extra;
  std::set_difference(ref.begin(), ref.end(), g.begin(), g.end(), std::back_inserter(missing));
  std::set_difference(g.begin(), g.end(), ref.begin(), ref.end(), std::back_inserter(extra));
  ADD_FAILURE() << what << ": " << g.size() << " pairs, reference " << ref.size() << "; missing "
                << missing.size()
                << (missing.empty() ? ""
                                    : " e.g. (" + std::to_string(missing[0].first) + ", " +
                                          std::to_string(missing[0].second) + ")")
                << ", extra " << extra.size()
                << (extra.empty() ? ""
                                  : " e.g. (" + std::to_string(extra[0].first) + ", " +
                                        std::to_string(extra[0].second) + ")");
}

/// Random layers (one of 4 bits), masks (all, or all but one bit) and static flags.
inline void add_random_filter(Boxes& b, uint32_t seed, double static_fraction) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<uint32_t> bits(0, 3);
  std::bernoulli_distribution is_static(static_fraction);
  std::bernoulli_distribution full_mask(0.5);
  for (size_t i = 0; i < b.size(); ++i) {
    b.layer.push_back(1u << bits(rng));
    b.mask.push_back(full_mask(rng) ? 0xffffffffu : (0xfu & ~(1u << bits(rng))));
    b.is_static.push_back(is_static(rng) ? 1 : 0);
  }
}

/// n boxes, centres uniform in a cube sized for a handful of overlaps per box,
/// half extents uniform in [half_lo, half_hi]; everything scaled by `scale`
/// about the origin, then translated by `offset` on every axis.
inline Boxes uniform_boxes(uint32_t n, uint32_t seed, float half_lo, float half_hi, float offset = 0.0f,
                           float scale = 1.0f) {
  std::mt19937 rng(seed);
  const float side = 2.2f * half_hi * std::cbrt(static_cast<float>(n));
  std::uniform_real_distribution<float> pos(-0.5f * side, 0.5f * side);
  std::uniform_real_distribution<float> half(half_lo, half_hi);
  Boxes b;
  for (uint32_t i = 0; i < n; ++i)
    b.add(offset + scale * pos(rng), offset + scale * pos(rng), offset + scale * pos(rng),
          scale * half(rng), scale * half(rng), scale * half(rng));
  return b;
}

/// A crowd of n uniform boxes (uniform_boxes(n, seed, 0.2, 1)) plus far outliers:
/// clumps of four mutually overlapping boxes of the crowd's sizes at +-d on each axis
/// for each d in `distances` (in range on the other axes: inside the crowd's span
/// there; far out, float rounds them to coincident points, which still touch); a
/// chain of 20 overlapping unit boxes from 1.5 crowd widths past it along +x (just
/// outside the grid's core range when the far outliers make it use one); a clump of
/// zero-size boxes at one far point; and, when `long_box`, one box from inside the
/// crowd to the first distance along +y (it overlaps crowd boxes and the +y clump
/// region; a size outlier too, so the grid goes hierarchical). Appended after the
/// crowd, so outliers have the highest indices.
inline Boxes outlier_boxes(uint32_t n, uint32_t seed, const std::vector<float>& distances, bool long_box) {
  Boxes b = uniform_boxes(n, seed, 0.2f, 1.0f);
  const float side = 2.2f * std::cbrt(static_cast<float>(n));
  std::mt19937 rng(seed + 1);
  std::uniform_real_distribution<float> in(-0.4f * side, 0.4f * side);
  for (float d : distances) {
    for (int axis = 0; axis < 3; ++axis)
      for (float sign : {1.0f, -1.0f}) {
        float c[3] = {in(rng), in(rng), in(rng)};
        c[axis] = sign * d;
        b.add(c[0], c[1], c[2], 0.5f, 0.5f, 0.5f);
        b.add(c[0], c[1], c[2], 0.3f, 0.7f, 0.3f);
        b.add(c[0], c[1], c[2], 0.7f, 0.3f, 0.7f);
        b.add(c[0] + 0.9f, c[1], c[2], 0.5f, 0.5f, 0.5f);
      }
  }
  for (int j = 0; j < 20; ++j) b.add(2.0f * side + 1.5f * static_cast<float>(j), 0.0f, 0.0f, 1.0f, 1.0f, 1.0f);
  if (!distances.empty()) {
    for (int j = 0; j < 4; ++j) b.add(-distances[0], distances[0], 0.0f, 0.0f, 0.0f, 0.0f);
    if (long_box) b.add_box(-0.5f, -0.5f, -0.5f, 0.5f, distances[0], 0.5f);
  }
  return b;
}

/// n points on a 13^3 lattice of step 0.5 (touching = same point), many repeated, with
/// every 50th a unit box instead.
inline Boxes point_lattice_boxes(uint32_t n, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> cell(0, 12);
  Boxes b;
  for (uint32_t i = 0; i < n; ++i) {
    const float x = 0.5f * static_cast<float>(cell(rng)), y = 0.5f * static_cast<float>(cell(rng)),
                z = 0.5f * static_cast<float>(cell(rng));
    if (i % 50 == 0) b.add(x, y, z, 0.5f, 0.5f, 0.5f);
    else b.add(x, y, z, 0, 0, 0);
  }
  return b;
}

/// n boxes (half extents 0.05 .. 0.4) in 6 gaussian blobs (sigma 1.5) in [-50, 50]^3.
inline Boxes clustered_boxes(uint32_t n, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> centre(-50.0f, 50.0f);
  std::vector<std::array<float, 3>> blobs(6);
  for (auto& c : blobs) c = {centre(rng), centre(rng), centre(rng)};
  std::normal_distribution<float> g(0.0f, 1.5f);
  std::uniform_real_distribution<float> half(0.05f, 0.4f);
  std::uniform_int_distribution<size_t> pick(0, blobs.size() - 1);
  Boxes b;
  for (uint32_t i = 0; i < n; ++i) {
    const auto& c = blobs[pick(rng)];
    b.add(c[0] + g(rng), c[1] + g(rng), c[2] + g(rng), half(rng), half(rng), half(rng));
  }
  return b;
}

}  // namespace impact::test
