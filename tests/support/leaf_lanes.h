// One side of a narrow-phase kernel bucket as owning SoA lanes (kernels::LeafSoA), the
// output lanes (kernels::ManifoldSoA, poisoned), one pair's collision data read back in
// double, and a kernel run over a whole bucket: the lane packer of every kernel-level
// narrow-phase test.
//   Leaf          one leaf as the kernel reads it (float fields of LeafSoA, and its type)
//   LeafLanes     owning SoA lanes, filled from Leafs or from a test's own shape struct
//   ManifoldLanes owning, poisoned output lanes; result(k), lane_bits(k), untouched(k)
//   run_bucket    a kernel over lanes [begin, end) of two Leaf lists, padded past n
//   run_queries   the same over a test's own pair structs, read back as PairResults
//   BucketLanes   a test's pairs as both sides of one bucket, and a kernel run over it
//   *_leaf        Leafs from double shapes (rounded to float as the host stores them)
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <utility>
#include <vector>

#include "kernels/narrowphase/leaf/leaf.h"

namespace impact::test {

/// One leaf as a kernel reads it: the float fields of LeafSoA's lane (leaf.h gives their
/// meaning per type; unused fields stay zero, R the identity) and the leaf's type.
struct Leaf {
  kernels::LeafType t = kernels::kLeafSphere;
  float p[3] = {0, 0, 0};
  float r[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};  ///< row-major
  float e[3] = {0, 0, 0};
  float w[6] = {0, 0, 0, 0, 0, 0};  ///< triangle: v1 then v2
  uint32_t ref = 0;                 ///< convex: hull index
};

/// A posed leaf (box, ellipsoid, capsule or cylinder: e = radius, half length, 0; a hull:
/// ref) at p with rotation R (columns: its axes).
inline Leaf posed_leaf(kernels::LeafType t, const Eigen::Vector3d& p, const Eigen::Matrix3d& R,
                       const Eigen::Vector3d& e, uint32_t ref = 0) {
  Leaf l;
  l.t = t;
  for (int i = 0; i < 3; ++i) l.p[i] = static_cast<float>(p[i]), l.e[i] = static_cast<float>(e[i]);
  for (int i = 0; i < 9; ++i) l.r[i] = static_cast<float>(R(i / 3, i % 3));
  l.ref = ref;
  return l;
}

/// A sphere of radius r at c.
inline Leaf sphere_leaf(const Eigen::Vector3d& c, double r) {
  return posed_leaf(kernels::kLeafSphere, c, Eigen::Matrix3d::Identity(), Eigen::Vector3d(r, 0, 0));
}

/// A capsule (or cylinder) along the axis u, stored as R's column 2 exactly as given (the
/// float-rounded axis the references use); the other columns complete a frame.
inline Leaf axial_leaf(kernels::LeafType t, const Eigen::Vector3d& p, const Eigen::Vector3d& u, double r,
                       double h) {
  const Eigen::Vector3d w = u.normalized();
  const Eigen::Vector3d a = std::fabs(w.x()) < 0.6 ? Eigen::Vector3d(1, 0, 0) : Eigen::Vector3d(0, 1, 0);
  const Eigen::Vector3d x = a.cross(w).normalized();
  Eigen::Matrix3d R;
  R.col(0) = x, R.col(1) = w.cross(x), R.col(2) = u;
  return posed_leaf(t, p, R, Eigen::Vector3d(r, h, 0));
}

/// A triangle v0, v1, v2.
inline Leaf triangle_leaf(const Eigen::Vector3d& v0, const Eigen::Vector3d& v1, const Eigen::Vector3d& v2) {
  Leaf l;
  l.t = kernels::kLeafTriangle;
  for (int i = 0; i < 3; ++i) {
    l.p[i] = static_cast<float>(v0[i]);
    l.w[i] = static_cast<float>(v1[i]);
    l.w[3 + i] = static_cast<float>(v2[i]);
  }
  return l;
}

/// Lanes filled from a test shape with fields p, R (3x3, row-major into LeafSoA::r),
/// e and hull, and the triangle corners v1, v2 (LeafSoA::w) when its type has them.
struct LeafLanes {
  std::vector<float> p[3], r[9], e[3], w[6];
  std::vector<uint32_t> ref;

  LeafLanes() = default;
  /// The leaves, then copies of leaves[0] up to `cap` lanes (valid padding that a
  /// kernel may read but must not answer for).
  explicit LeafLanes(const std::vector<Leaf>& leaves, size_t cap = 0) {
    for (const Leaf& l : leaves) push(l);
    while (!leaves.empty() && ref.size() < cap) push(leaves[0]);
  }

  uint32_t size() const { return static_cast<uint32_t>(ref.size()); }

  void push(const Leaf& l) {
    for (int i = 0; i < 3; ++i) p[i].push_back(l.p[i]);
    for (int i = 0; i < 9; ++i) r[i].push_back(l.r[i]);
    for (int i = 0; i < 3; ++i) e[i].push_back(l.e[i]);
    for (int i = 0; i < 6; ++i) w[i].push_back(l.w[i]);
    ref.push_back(l.ref);
  }

  /// A test shape with fields p, R and e (Eigen, any scalar), and optionally hull and
  /// the triangle corners v1, v2.
  template <class S>
  void push(const S& s) {
    for (int i = 0; i < 3; ++i) p[i].push_back(static_cast<float>(s.p[i]));
    for (int i = 0; i < 9; ++i) r[i].push_back(static_cast<float>(s.R(i / 3, i % 3)));
    for (int i = 0; i < 3; ++i) e[i].push_back(static_cast<float>(s.e[i]));
    for (int i = 0; i < 3; ++i) {
      if constexpr (requires { s.v1; s.v2; }) {
        w[i].push_back(static_cast<float>(s.v1[i]));
        w[3 + i].push_back(static_cast<float>(s.v2[i]));
      } else {
        w[i].push_back(0.0f);
        w[3 + i].push_back(0.0f);
      }
    }
    if constexpr (requires { s.hull; })
      ref.push_back(s.hull);
    else
      ref.push_back(0);
  }

  kernels::LeafSoA soa() const {
    kernels::LeafSoA s{};
    for (int i = 0; i < 3; ++i) s.p[i] = p[i].data();
    for (int i = 0; i < 9; ++i) s.r[i] = r[i].data();
    for (int i = 0; i < 3; ++i) s.e[i] = e[i].data();
    for (int i = 0; i < 6; ++i) s.w[i] = w[i].data();
    s.ref = ref.data();
    return s;
  }
};

/// One pair's collision data in double: count, normal (A to B), depth, points and
/// their depths.
struct PairResult {
  uint32_t count = 0;
  Eigen::Vector3d n = Eigen::Vector3d::Zero();
  double depth = 0;
  Eigen::Vector3d pt[4];
  double pd[4] = {0, 0, 0, 0};
};

/// Whether two lanes read back hold the same bytes: count, and for a contact the depth,
/// normal and the points and point depths of its count slots (at most 4).
inline bool same_bytes(const PairResult& x, const PairResult& y) {
  auto eq = [](double a, double b) { return std::bit_cast<uint64_t>(a) == std::bit_cast<uint64_t>(b); };
  bool same = x.count == y.count;
  if (same && x.count > 0) {
    same = eq(x.depth, y.depth);
    for (int i = 0; i < 3; ++i) same = same && eq(x.n[i], y.n[i]);
    for (uint32_t j = 0; j < x.count && j < 4; ++j) {
      same = same && eq(x.pd[j], y.pd[j]);
      for (int i = 0; i < 3; ++i) same = same && eq(x.pt[j][i], y.pt[j][i]);
    }
  }
  return same;
}

/// Owning output lanes for n pairs (kernels::ManifoldSoA), every value poisoned (count
/// kPoisonCount, floats the NaN kPoisonBits) so a kernel that leaves a lane or a slot
/// unwritten shows; result(k) reads lane k back as a PairResult (the points and depths
/// of its count slots), lane_bits(k) as the bytes the kernel wrote, untouched(k) says
/// whether the kernel left lane k alone.
struct ManifoldLanes {
  static constexpr uint8_t kPoisonCount = 0xff;
  static constexpr uint32_t kPoisonBits = 0x7fc0dead;  ///< a quiet NaN no kernel computes

  std::vector<uint8_t> count;
  std::vector<float> n[3], depth, pt[4][3], pd[4];

  explicit ManifoldLanes(uint32_t lanes = 1) : count(lanes, kPoisonCount) {
    const float poison = std::bit_cast<float>(kPoisonBits);
    depth.assign(lanes, poison);
    for (int i = 0; i < 3; ++i) n[i].assign(lanes, poison);
    for (int j = 0; j < 4; ++j) {
      for (int i = 0; i < 3; ++i) pt[j][i].assign(lanes, poison);
      pd[j].assign(lanes, poison);
    }
  }

  uint32_t size() const { return static_cast<uint32_t>(count.size()); }

  /// Lane k's bytes: the count, and for 1..4 points the normal, depth, points and point
  /// depths (slots past the count and lanes without contact are unspecified).
  std::vector<uint32_t> lane_bits(uint32_t k) const {
    std::vector<uint32_t> b{count[k]};
    if (count[k] == 0 || count[k] > 4) return b;
    auto put = [&](float f) { b.push_back(std::bit_cast<uint32_t>(f)); };
    for (const auto& v : n) put(v[k]);
    put(depth[k]);
    for (uint32_t j = 0; j < count[k]; ++j) {
      for (const auto& v : pt[j]) put(v[k]);
      put(pd[j][k]);
    }
    return b;
  }

  /// Every field of lane k still holds its poison.
  bool untouched(uint32_t k) const {
    auto poisoned = [](float f) { return std::bit_cast<uint32_t>(f) == kPoisonBits; };
    if (count[k] != kPoisonCount || !poisoned(depth[k])) return false;
    for (int i = 0; i < 3; ++i)
      if (!poisoned(n[i][k])) return false;
    for (int j = 0; j < 4; ++j) {
      if (!poisoned(pd[j][k])) return false;
      for (int i = 0; i < 3; ++i)
        if (!poisoned(pt[j][i][k])) return false;
    }
    return true;
  }

  kernels::ManifoldSoA view() {
    kernels::ManifoldSoA o{};
    o.count = count.data();
    for (int i = 0; i < 3; ++i) o.n[i] = n[i].data();
    o.depth = depth.data();
    for (int j = 0; j < 4; ++j) {
      for (int i = 0; i < 3; ++i) o.point[j][i] = pt[j][i].data();
      o.pdepth[j] = pd[j].data();
    }
    return o;
  }

  PairResult result(uint32_t k = 0) const {
    PairResult r;
    r.count = count[k];
    if (r.count == 0) return r;
    r.n = Eigen::Vector3d(n[0][k], n[1][k], n[2][k]);
    r.depth = depth[k];
    for (uint32_t j = 0; j < r.count && j < 4; ++j) {
      r.pt[j] = Eigen::Vector3d(pt[j][0][k], pt[j][1][k], pt[j][2][k]);
      r.pd[j] = pd[j][k];
    }
    return r;
  }
};

/// Lanes rounded up to whole blocks of 16 plus one more block: room for every SIMD
/// width and for a kernel that wrongly writes past its range.
inline uint32_t padded_lanes(uint32_t n) {
  return (n + 15) / 16 * 16 + 16;
}

/// kern over lanes [begin, end) of the bucket a[k], b[k] (a and b of equal size), with
/// cfg (its path and hulls as given); the inputs are padded to padded_lanes(n) with
/// copies of lane 0, the output poisoned there and outside [begin, end).
inline ManifoldLanes run_bucket(kernels::PairKernel kern, const std::vector<Leaf>& a,
                                const std::vector<Leaf>& b, const kernels::NarrowConfig& cfg, uint32_t begin,
                                uint32_t end) {
  const uint32_t n = static_cast<uint32_t>(a.size()), cap = padded_lanes(n);
  const LeafLanes la(a, cap), lb(b, cap);
  ManifoldLanes out(cap);
  kern(la.soa(), lb.soa(), out.view(), kernels::Range{begin, std::min(end, n)}, cfg);
  return out;
}

/// kern (path, hulls) over lanes [begin, end) of a test's own pair structs, each made
/// into its two Leafs by leaves(q) (a std::pair); lane k read back as a PairResult (lanes
/// outside the range left empty); `keep`, if given, receives the output lanes.
template <class Q, class Leaves>
std::vector<PairResult> run_queries(kernels::PairKernel kern, const std::vector<Q>& qs,
                                    kernels::KernelPath path, Leaves leaves, uint32_t begin = 0,
                                    uint32_t end = ~0u, ManifoldLanes* keep = nullptr,
                                    const kernels::HullView* hulls = nullptr) {
  std::vector<Leaf> a, b;
  for (const Q& q : qs) {
    const auto [la, lb] = leaves(q);
    a.push_back(la);
    b.push_back(lb);
  }
  kernels::NarrowConfig cfg;
  cfg.path = path;
  if (hulls != nullptr) cfg.hulls = *hulls;
  const uint32_t n = static_cast<uint32_t>(qs.size());
  end = std::min(end, n);
  ManifoldLanes o = run_bucket(kern, a, b, cfg, begin, end);
  std::vector<PairResult> out(n);
  for (uint32_t k = begin; k < end; ++k) out[k] = o.result(k);
  if (keep != nullptr) *keep = std::move(o);
  return out;
}

/// A test's pairs as the two sides of one bucket (leaves(p): its A and B Leafs).
struct BucketLanes {
  uint32_t n = 0;
  LeafLanes la, lb;

  template <class P, class Leaves>
  BucketLanes(const std::vector<P>& pairs, Leaves leaves) : n(static_cast<uint32_t>(pairs.size())) {
    for (const P& p : pairs) {
      const auto [a, b] = leaves(p);
      la.push(a);
      lb.push(b);
    }
  }
  kernels::LeafSoA a() const { return la.soa(); }
  kernels::LeafSoA b() const { return lb.soa(); }

  /// kern over the whole bucket on `path` with the hulls hv.
  ManifoldLanes run(kernels::PairKernel kern, const kernels::HullView& hv, kernels::KernelPath path) const {
    ManifoldLanes o(n);
    kernels::NarrowConfig cfg;
    cfg.path = path;
    cfg.hulls = hv;
    kern(a(), b(), o.view(), kernels::Range{0, n}, cfg);
    return o;
  }
};

/// The same over the whole bucket.
inline ManifoldLanes run_bucket(kernels::PairKernel kern, const std::vector<Leaf>& a,
                                const std::vector<Leaf>& b, const kernels::NarrowConfig& cfg) {
  return run_bucket(kern, a, b, cfg, 0, static_cast<uint32_t>(a.size()));
}

}  // namespace impact::test
