// Independent reference BVH for judging the LBVH's tree quality: a top-down binned
// surface-area-heuristic (SAH) build, in double precision, with one box per leaf
// (as the LBVH), and the same SAH metric the LBVH reports (LbvhBroadPhase::sah_cost,
// kernels/bvh/lbvh_traverse.h):
//
//   SAH = sum over all 2n - 1 nodes (internal and leaf) of area(node) / area(root),
//   area = 2 (dx dy + dy dz + dz dx)   (n when the root has zero area).
//
// Build: each node's boxes are binned by centroid into kBins equal slots along each
// axis of the node's centroid bounds; the split between slots that minimises
// area(left) * count(left) + area(right) * count(right) over the three axes wins
// (the greedy top-down SAH sweep over bins, Wald 2007, "On fast construction of
// SAH-based bounding volume hierarchies"; the cost model of Goldsmith & Salmon 1987
// and MacDonald & Booth 1990). Nodes whose centroids coincide on every axis split in
// the middle of the list. Iterative (explicit stack), O(n log n) for spread-out input,
// ~1-2 s for 1M boxes. The code depends on the C++ standard library only, so the
// benchmarks can include it too (it includes no GoogleTest).
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <span>
#include <string>
#include <vector>

namespace impact::test {

/// A binary BVH with one primitive per leaf. Node 0 is the root; 2n - 1 nodes for n >= 1.
struct BinnedBvh {
  static constexpr uint32_t kNone = std::numeric_limits<uint32_t>::max();
  struct Node {
    std::array<double, 3> lo, hi;  ///< bounds, m
    uint32_t left = kNone, right = kNone;  ///< children (internal nodes)
    uint32_t prim = kNone;                 ///< box index (leaves)
    bool leaf() const { return prim != kNone; }
  };
  std::vector<Node> nodes;
};

/// Axis-aligned boxes as SoA spans of equal length (m).
struct SahBoxes {
  std::span<const float> min_x, min_y, min_z, max_x, max_y, max_z;
  size_t size() const { return min_x.size(); }
};

/// Surface area of a box given by two corners, in double.
inline double sah_box_area(const std::array<double, 3>& lo, const std::array<double, 3>& hi) {
  const double dx = hi[0] - lo[0], dy = hi[1] - lo[1], dz = hi[2] - lo[2];
  return 2.0 * (dx * dy + dy * dz + dz * dx);
}

/// Builds the binned-SAH tree over all boxes (kBins slots per axis, >= 2).
template <uint32_t kBins = 32>
BinnedBvh build_binned_sah(const SahBoxes& boxes) {
  static_assert(kBins >= 2);
  constexpr double kInf = std::numeric_limits<double>::infinity();
  const uint32_t n = static_cast<uint32_t>(boxes.size());
  BinnedBvh bvh;
  if (n == 0) return bvh;
  const std::span<const float> mins[3] = {boxes.min_x, boxes.min_y, boxes.min_z};
  const std::span<const float> maxs[3] = {boxes.max_x, boxes.max_y, boxes.max_z};
  std::vector<double> centre[3];
  for (int k = 0; k < 3; ++k) {
    centre[k].resize(n);
    for (uint32_t i = 0; i < n; ++i)
      centre[k][i] = 0.5 * (static_cast<double>(mins[k][i]) + static_cast<double>(maxs[k][i]));
  }
  std::vector<uint32_t> prims(n);
  for (uint32_t i = 0; i < n; ++i) prims[i] = i;
  bvh.nodes.reserve(2 * static_cast<size_t>(n) - 1);
  bvh.nodes.emplace_back();

  struct Bin {
    std::array<double, 3> lo{kInf, kInf, kInf}, hi{-kInf, -kInf, -kInf};
    uint32_t count = 0;
    void grow(const std::array<double, 3>& l, const std::array<double, 3>& h) {
      for (int k = 0; k < 3; ++k) lo[k] = std::min(lo[k], l[k]), hi[k] = std::max(hi[k], h[k]);
    }
  };
  auto box_of = [&](uint32_t i, std::array<double, 3>& lo, std::array<double, 3>& hi) {
    for (int k = 0; k < 3; ++k) lo[k] = mins[k][i], hi[k] = maxs[k][i];
  };
  struct Task {
    uint32_t node, begin, end;
  };
  std::vector<Task> stack{{0, 0, n}};
  std::array<Bin, kBins> bins[3];
  std::array<double, kBins> right_area;
  std::array<uint32_t, kBins> right_count;
  while (!stack.empty()) {
    const Task t = stack.back();
    stack.pop_back();
    // Node bounds and centroid bounds.
    Bin node, cb;
    std::array<double, 3> lo, hi;
    for (uint32_t p = t.begin; p < t.end; ++p) {
      box_of(prims[p], lo, hi);
      node.grow(lo, hi);
      const std::array<double, 3> c{centre[0][prims[p]], centre[1][prims[p]], centre[2][prims[p]]};
      cb.grow(c, c);
    }
    bvh.nodes[t.node].lo = node.lo;
    bvh.nodes[t.node].hi = node.hi;
    if (t.end - t.begin == 1) {
      bvh.nodes[t.node].prim = prims[t.begin];
      continue;
    }
    // Bin along each axis with a non-zero centroid extent; sweep for the best split.
    double best_cost = kInf;
    int best_axis = -1;
    uint32_t best_bin = 0;  // left side = bins [0, best_bin]
    auto bin_of = [&](int axis, uint32_t prim) {
      const double extent = cb.hi[axis] - cb.lo[axis];
      const double f = (centre[axis][prim] - cb.lo[axis]) * (kBins / extent);
      // Written so that NaN (0 * inf for a subnormal extent) and inf stay in range.
      return f >= kBins - 1 ? kBins - 1 : f > 0.0 ? static_cast<uint32_t>(f) : 0u;
    };
    for (int axis = 0; axis < 3; ++axis) {
      if (!(cb.hi[axis] > cb.lo[axis])) continue;
      bins[axis].fill(Bin{});
      for (uint32_t p = t.begin; p < t.end; ++p) {
        Bin& b = bins[axis][bin_of(axis, prims[p])];
        box_of(prims[p], lo, hi);
        b.grow(lo, hi);
        ++b.count;
      }
      Bin acc;
      for (uint32_t b = kBins - 1; b > 0; --b) {
        acc.grow(bins[axis][b].lo, bins[axis][b].hi);
        acc.count += bins[axis][b].count;
        right_area[b] = acc.count > 0 ? sah_box_area(acc.lo, acc.hi) : 0.0;
        right_count[b] = acc.count;
      }
      acc = Bin{};
      for (uint32_t b = 0; b + 1 < kBins; ++b) {
        acc.grow(bins[axis][b].lo, bins[axis][b].hi);
        acc.count += bins[axis][b].count;
        if (acc.count == 0 || right_count[b + 1] == 0) continue;
        const double cost = sah_box_area(acc.lo, acc.hi) * acc.count + right_area[b + 1] * right_count[b + 1];
        if (cost < best_cost) best_cost = cost, best_axis = axis, best_bin = b;
      }
    }
    uint32_t mid;
    if (best_axis >= 0) {
      uint32_t* split = std::partition(prims.data() + t.begin, prims.data() + t.end,
                                       [&](uint32_t prim) { return bin_of(best_axis, prim) <= best_bin; });
      mid = static_cast<uint32_t>(split - prims.data());
    } else {
      mid = t.begin + (t.end - t.begin) / 2;  // all centroids equal: any split has the same cost
    }
    const uint32_t left = static_cast<uint32_t>(bvh.nodes.size());
    bvh.nodes.emplace_back();
    bvh.nodes.emplace_back();
    bvh.nodes[t.node].left = left;
    bvh.nodes[t.node].right = left + 1;
    stack.push_back({left + 1, mid, t.end});
    stack.push_back({left, t.begin, mid});
  }
  return bvh;
}

/// The SAH metric above (0 for an empty tree).
inline double sah_cost(const BinnedBvh& bvh) {
  if (bvh.nodes.empty()) return 0.0;
  double total = 0.0;
  for (const BinnedBvh::Node& node : bvh.nodes) total += sah_box_area(node.lo, node.hi);
  const double root = sah_box_area(bvh.nodes[0].lo, bvh.nodes[0].hi);
  return root > 0.0 ? total / root : static_cast<double>((bvh.nodes.size() + 1) / 2);
}

/// Structure check: 2n - 1 nodes, every node reached once from the root, every box in
/// exactly one leaf whose bounds are that box, every internal node's bounds contain
/// its children's. Returns an empty string when valid, else what is wrong.
inline std::string validate_binned_bvh(const BinnedBvh& bvh, const SahBoxes& boxes) {
  const size_t n = boxes.size();
  if (n == 0) return bvh.nodes.empty() ? std::string() : "nodes for no boxes";
  if (bvh.nodes.size() != 2 * n - 1)
    return std::to_string(bvh.nodes.size()) + " nodes for " + std::to_string(n) + " boxes";
  std::vector<uint8_t> node_seen(bvh.nodes.size(), 0), prim_seen(n, 0);
  std::vector<uint32_t> stack{0};
  const std::span<const float> mins[3] = {boxes.min_x, boxes.min_y, boxes.min_z};
  const std::span<const float> maxs[3] = {boxes.max_x, boxes.max_y, boxes.max_z};
  while (!stack.empty()) {
    const uint32_t id = stack.back();
    stack.pop_back();
    if (id >= bvh.nodes.size()) return "child index " + std::to_string(id) + " out of range";
    if (node_seen[id]++) return "node " + std::to_string(id) + " reached twice";
    const BinnedBvh::Node& node = bvh.nodes[id];
    if (node.leaf()) {
      if (node.prim >= n) return "leaf " + std::to_string(id) + " holds box " + std::to_string(node.prim);
      if (prim_seen[node.prim]++) return "box " + std::to_string(node.prim) + " in two leaves";
      for (int k = 0; k < 3; ++k)
        if (node.lo[k] != mins[k][node.prim] || node.hi[k] != maxs[k][node.prim])
          return "leaf " + std::to_string(id) + " bounds differ from box " + std::to_string(node.prim);
      continue;
    }
    if (node.left == BinnedBvh::kNone || node.right == BinnedBvh::kNone)
      return "internal node " + std::to_string(id) + " lacks a child";
    for (uint32_t c : {node.left, node.right}) {
      if (c >= bvh.nodes.size()) return "child index " + std::to_string(c) + " out of range";
      for (int k = 0; k < 3; ++k)
        if (bvh.nodes[c].lo[k] < node.lo[k] || bvh.nodes[c].hi[k] > node.hi[k])
          return "node " + std::to_string(id) + " does not contain child " + std::to_string(c);
      stack.push_back(c);
    }
  }
  for (size_t i = 0; i < n; ++i)
    if (!prim_seen[i]) return "box " + std::to_string(i) + " in no leaf";
  for (size_t i = 0; i < bvh.nodes.size(); ++i)
    if (!node_seen[i]) return "node " + std::to_string(i) + " unreachable";
  return {};
}

}  // namespace impact::test
