// Any convex leaf (A) against a half-space (B), by A's support function.
//
// What: per lane k, the half-space B = { x : nh.(x - pB) <= 0 } (leaf.h: p = pB, e =
// unit nh). A's deepest point is its support along -nh; depth = -nh.(x - pB). Normal
// A->B: n = -nh (B must move down, away from A, to separate). depth <= 0: count 0.
// Manifold: every candidate point of A below the plane, reduced to at most 4: the
// deepest, the farthest from it, then the two adding most area:
//   box, convex hull: their vertices;
//   capsule: the lowest points of the two end spheres (up to 2);
//   sphere, ellipsoid, cylinder, triangle: the deepest point (pair_kernel() gives
//     these closed-form lane kernels, primitives_*.cpp, with the cylinder's cap / side
//     manifold and the triangle's vertices below; hulls have collide_convex_halfspace,
//     convex_halfspace.cpp, which sends hulls of more than 64 vertices here).
// Each point lies midway between A's point x and its projection onto the plane; its
// pdepth is x's depth. Points are computed relative to A's position (precision far from
// the origin) and shifted back on output.
// Inputs: posed leaves per leaf.h (finite, unit nh). Deterministic (fixed loop order,
// first index wins ties). Hulls: kSimd passes over the vertices kSimdWidth at a time,
// kScalar one at a time, with the same formulas and tie rule; other types run the same
// per-lane code on both paths.
// Cost: O(1) per lane, O(vertex count) for convex hulls: the plane is moved into the
// hull's frame once, then one SIMD pass finds the deepest vertex (all a separated pair
// costs), a second lists the vertices below, and the other three picks walk that list
// (more than 32 below: three masked passes over every vertex instead; first_max,
// hull_below); only the chosen points are transformed to the world frame. No
// allocation. Cost: measured per pair in docs/results.md ("Narrow phase").
#include <bit>
#include <cmath>

#include "kernels/narrowphase/pair_kernels.h"
#include "kernels/narrowphase/general/support.h"

namespace impact::kernels {

namespace {

using cvx::V3;

/// Picks up to 4 of the candidates get(i, &x) (i < n) whose depth d(x) > 0.
template <class Get>
uint32_t pick_below(uint32_t n, Get get, V3 nh, float off, V3* pts, float* pd) {
  auto depth_of = [&](uint32_t i, V3* x) {
    *x = get(i);
    return off - cvx::dot(nh, *x);
  };
  V3 x;
  uint32_t i0 = n;
  float d0 = 0.0f;
  for (uint32_t i = 0; i < n; ++i) {
    const float d = depth_of(i, &x);
    if (d > d0) {
      d0 = d;
      i0 = i;
    }
  }
  if (i0 == n) return 0;
  uint32_t idx[4] = {i0, n, n, n};
  V3 p0;
  depth_of(i0, &p0);
  // Farthest from p0.
  float best = 0.0f;
  V3 p1 = p0;
  for (uint32_t i = 0; i < n; ++i) {
    if (!(depth_of(i, &x) > 0.0f)) continue;
    const float d2 = cvx::len2(x - p0);
    if (d2 > best) {
      best = d2;
      idx[1] = i;
      p1 = x;
    }
  }
  uint32_t m = 1;
  if (idx[1] != n) {
    m = 2;
    // Largest |area| with p0, p1 (areas measured about nh).
    best = 0.0f;
    V3 p2 = p0;
    float sgn = 1.0f;
    for (uint32_t i = 0; i < n; ++i) {
      if (!(depth_of(i, &x) > 0.0f)) continue;
      const float a = cvx::dot(cvx::cross(p1 - p0, x - p0), nh);
      if (std::fabs(a) > best) {
        best = std::fabs(a);
        idx[2] = i;
        p2 = x;
        sgn = a >= 0.0f ? 1.0f : -1.0f;
      }
    }
    // Area threshold: a relative 1e-6 of the squared span, so rounding never adds a
    // collinear point.
    const float tiny = 1e-6f * cvx::len2(p1 - p0);
    if (idx[2] != n && best > tiny) {
      m = 3;
      best = tiny;
      for (uint32_t i = 0; i < n; ++i) {
        if (!(depth_of(i, &x) > 0.0f)) continue;
        const float o0 = -sgn * cvx::dot(cvx::cross(p1 - p0, x - p0), nh);
        const float o1 = -sgn * cvx::dot(cvx::cross(p2 - p1, x - p1), nh);
        const float o2 = -sgn * cvx::dot(cvx::cross(p0 - p2, x - p2), nh);
        const float o = simd::fmax_nn(o0, simd::fmax_nn(o1, o2));
        if (o > best) {
          best = o;
          idx[3] = i;
        }
      }
      if (idx[3] != n) m = 4;
    }
  }
  uint32_t k = 0;
  for (uint32_t j = 0; j < m; ++j) {
    if (idx[j] == n) continue;
    const float d = depth_of(idx[j], &x);
    pts[k] = x + nh * (0.5f * d);
    pd[k] = d;
    ++k;
  }
  return k;
}

/// First maximum of score(x, y, z) over the hull vertices [vb, ve) (local
/// coordinates), lanes of type F at a time: each lane keeps its first strict maximum,
/// then the lanes merge by (score, lowest index) (simd::all_lanes butterflies); the
/// last block overlaps the one before it instead of a scalar tail (a vertex seen
/// twice keeps its index, so the first maximum is unchanged). Float1 or fewer
/// vertices than lanes: one vertex at a time, strict >. score is a generic callable
/// (lane type in, same type out). Returns the maximum; *at is its index, set only
/// when the maximum exceeds `above` (the lanes' index merge is skipped otherwise).
template <class F, class Score>
IMPACT_INLINE float first_max(const HullView& h, uint32_t vb, uint32_t ve, Score score, float above,
                              uint32_t* at) {
  constexpr uint32_t kW = F::kWidth;
  auto one_by_one = [&] {
    float best = -INFINITY;
    uint32_t bi = vb;
    for (uint32_t i = vb; i < ve; ++i) {
      const float s = score(simd::Float1(h.vx[i]), simd::Float1(h.vy[i]), simd::Float1(h.vz[i])).lane(0);
      if (s > best) {
        best = s;
        bi = i;
      }
    }
    *at = bi;
    return best;
  };
  if constexpr (kW == 1) {
    return one_by_one();
  } else {
    if (ve - vb < kW) return one_by_one();
    const F lane = simd::lane_index<F>();
    F m(-INFINITY), idx(0.0f);
    auto step = [&](uint32_t i) {
      const F s = score(F::load(h.vx + i), F::load(h.vy + i), F::load(h.vz + i));
      const auto gt = s > m;
      m = select(gt, s, m);
      idx = select(gt, lane + F(static_cast<float>(i - vb)), idx);
    };
    uint32_t i = vb;
    for (; i + kW <= ve; i += kW) step(i);
    if (i < ve) step(ve - kW);
    const F bs = simd::all_lanes(m, [](F x, F y) { return max(x, y); });
    const float best = bs.lane(0);
    if (best > above) {
      const F bi = simd::all_lanes(select(m == bs, idx, F(INFINITY)), [](F x, F y) { return min(x, y); });
      *at = vb + static_cast<uint32_t>(bi.lane(0));
    }
    return best;
  }
}

/// Up to 4 vertices of hull [vb, ve) below the plane nl.x = offl (the hull's frame),
/// the same rule as pick_below: the deepest (pd > 0), the farthest from it, the one
/// adding the largest area, the one farthest outside that triangle (each the first
/// maximum in vertex order). One first_max pass finds the deepest vertex (a separated
/// pair stops there); a second SIMD pass lists the vertices below in vertex order, and
/// the other three picks walk only that list (a resting hull has a face's few vertices
/// below). More than kBelowList vertices below: those picks are masked first_max passes
/// over all vertices instead. Same picks either way. The area terms are triple
/// products with nl precomputed as one dot per vertex: nl.((p1 - p0) x (x - p0)) =
/// (x - p0).(nl x (p1 - p0)). Outputs local vertices v[] and their depths pd[];
/// returns the count.
inline constexpr uint32_t kBelowList = 32;

template <class F>
uint32_t hull_below(const HullView& h, uint32_t vb, uint32_t ve, V3 nl, float offl, V3* v, float* pd) {
  const float nx = nl.x, ny = nl.y, nz = nl.z;
  auto depth = [=](auto x, auto y, auto z) {
    using G = decltype(x);
    return G(offl) - (G(nx) * x + G(ny) * y + G(nz) * z);
  };
  auto local = [&](uint32_t i) { return V3{h.vx[i], h.vy[i], h.vz[i]}; };
  auto depth1 = [&](V3 p) { return depth(simd::Float1(p.x), simd::Float1(p.y), simd::Float1(p.z)).lane(0); };
  // Pass 1: the deepest vertex (a separated pair stops here).
  uint32_t i0 = vb;
  const float d0 = first_max<F>(h, vb, ve, depth, 0.0f, &i0);
  if (!(d0 > 0.0f)) return 0;
  const V3 p0 = local(i0);
  v[0] = p0;
  pd[0] = d0;
  // Pass 2: the vertices below, in vertex order (up to kBelowList; more: not listed).
  uint32_t list[kBelowList];
  uint32_t nlist = 0;
  bool listed = true;
  {
    constexpr uint32_t kW = F::kWidth;
    uint32_t i = vb;
    for (; i + kW <= ve && listed; i += kW) {
      uint32_t bits = simd::bits(depth(F::load(h.vx + i), F::load(h.vy + i), F::load(h.vz + i)) > F(0.0f));
      for (; bits != 0; bits &= bits - 1) {
        if (nlist == kBelowList) {
          listed = false;
          break;
        }
        list[nlist++] = i + static_cast<uint32_t>(std::countr_zero(bits));
      }
    }
    for (; i < ve && listed; ++i) {
      if (depth1(local(i)) > 0.0f) {
        if (nlist == kBelowList) {
          listed = false;
          break;
        }
        list[nlist++] = i;
      }
    }
  }
  // First strict maximum of score over the vertices below (list order = vertex order).
  auto list_max = [&](auto score, float above, uint32_t* at) {
    float best = -INFINITY;
    for (uint32_t q = 0; q < nlist; ++q) {
      const V3 x = local(list[q]);
      const float s = score(simd::Float1(x.x), simd::Float1(x.y), simd::Float1(x.z)).lane(0);
      if (s > best) {
        best = s;
        *at = list[q];
      }
    }
    (void)above;  // *at is read only when best > above, as first_max's
    return best;
  };
  auto pick = [&](auto score, float above, uint32_t* at) {
    if (listed) return list_max(score, above, at);
    return first_max<F>(
        h, vb, ve,
        [=](auto x, auto y, auto z) {
          using G = decltype(x);
          return select(depth(x, y, z) > G(0.0f), score(x, y, z), G(-INFINITY));
        },
        above, at);
  };
  // Farthest from p0 among the vertices below.
  uint32_t i1 = vb;
  const float far = pick(
      [=](auto x, auto y, auto z) {
        using G = decltype(x);
        const G dx = x - G(p0.x), dy = y - G(p0.y), dz = z - G(p0.z);
        return dx * dx + dy * dy + dz * dz;
      },
      0.0f, &i1);
  if (!(far > 0.0f)) return 1;
  const V3 p1 = local(i1);
  v[1] = p1;
  pd[1] = depth1(p1);
  // Largest |area| with p0, p1 (about nl): a = (x - p0).c with c = nl x (p1 - p0).
  const V3 c = cvx::cross(nl, p1 - p0);
  auto area = [=](auto x, auto y, auto z) {
    using G = decltype(x);
    return (x - G(p0.x)) * G(c.x) + (y - G(p0.y)) * G(c.y) + (z - G(p0.z)) * G(c.z);
  };
  // Area threshold: a relative 1e-6 of the squared span, so rounding never adds a
  // collinear point.
  const float tiny = 1e-6f * cvx::len2(p1 - p0);
  uint32_t i2 = vb;
  const float amax = pick([=](auto x, auto y, auto z) { return abs(area(x, y, z)); }, tiny, &i2);
  if (!(amax > tiny)) return 2;
  const V3 p2 = local(i2);
  v[2] = p2;
  pd[2] = depth1(p2);
  // Farthest outside the triangle p0 p1 p2: the largest of its three edge distances
  // (times the edge lengths), each (x - pj).gj with gj = -sgn nl x (pj+1 - pj).
  const float sgn = area(simd::Float1(p2.x), simd::Float1(p2.y), simd::Float1(p2.z)).lane(0) >= 0.0f ? -1.0f : 1.0f;
  const V3 g0 = cvx::cross(nl, p1 - p0) * sgn, g1 = cvx::cross(nl, p2 - p1) * sgn, g2 = cvx::cross(nl, p0 - p2) * sgn;
  uint32_t i3 = vb;
  const float omax = pick(
      [=](auto x, auto y, auto z) {
        using G = decltype(x);
        auto edge = [&](V3 p, V3 g) { return (x - G(p.x)) * G(g.x) + (y - G(p.y)) * G(g.y) + (z - G(p.z)) * G(g.z); };
        return max(edge(p0, g0), max(edge(p1, g1), edge(p2, g2)));
      },
      tiny, &i3);
  if (!(omax > tiny)) return 3;
  const V3 p3 = local(i3);
  v[3] = p3;
  pd[3] = depth1(p3);
  return 4;
}

}  // namespace

void collide_support_halfspace(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, Range r,
                               const NarrowConfig& cfg, LeafType ta) {
  for (uint32_t k = r.begin; k < r.end; ++k) {
    const V3 origin{a.p[0][k], a.p[1][k], a.p[2][k]};
    const cvx::Leaf A = cvx::load_leaf(a, k, ta, &cfg.hulls, origin);
    const V3 nh{b.e[0][k], b.e[1][k], b.e[2][k]};
    const V3 pb = V3{b.p[0][k], b.p[1][k], b.p[2][k]} - origin;
    const float off = cvx::dot(nh, pb);  // x is below when nh.x < off
    V3 pts[4];
    float pd[4];
    uint32_t m = 0;
    V3 deepest{0, 0, 0};
    float depth = 0.0f;
    if (ta == kLeafConvex) {
      // One pass lists the vertices that may lie below; the deepest of them (in the
      // world frame) is the support along -nh, so no separate support scan.
      // The plane in the hull's frame: nl = R^T nh, offl = off - nh.p.
      const uint32_t vb = cfg.hulls.vert_begin[A.hull];
      const uint32_t ve = cfg.hulls.vert_begin[A.hull + 1];
      const V3 nl{cvx::dot(nh, A.ax[0]), cvx::dot(nh, A.ax[1]), cvx::dot(nh, A.ax[2])};
      const float offl = off - cvx::dot(nh, A.p);
      V3 vl[4];
      m = cfg.path == KernelPath::kScalar ? hull_below<simd::Float1>(cfg.hulls, vb, ve, nl, offl, vl, pd)
                                          : hull_below<simd::FloatW>(cfg.hulls, vb, ve, nl, offl, vl, pd);
      if (m == 0) {
        out.count[k] = 0;
        continue;
      }
      for (uint32_t i = 0; i < m; ++i) {
        const V3 x = A.p + A.ax[0] * vl[i].x + A.ax[1] * vl[i].y + A.ax[2] * vl[i].z;
        pts[i] = x + nh * (0.5f * pd[i]);
      }
      depth = pd[0];  // hull_below's first point is the deepest vertex
    } else {
      deepest = cvx::support(A, -nh);
      depth = off - cvx::dot(nh, deepest);
      if (!(depth > 0.0f)) {
        out.count[k] = 0;
        continue;
      }
    }
    switch (ta) {
      case kLeafBox:
        m = pick_below(
            8,
            [&](uint32_t i) {
              return A.p + A.ax[0] * ((i & 1) ? A.e[0] : -A.e[0]) + A.ax[1] * ((i & 2) ? A.e[1] : -A.e[1]) +
                     A.ax[2] * ((i & 4) ? A.e[2] : -A.e[2]);
            },
            nh, off, pts, pd);
        break;
      case kLeafCapsule:
        m = pick_below(
            2, [&](uint32_t i) { return A.p + A.ax[2] * (i == 0 ? -A.e[1] : A.e[1]) - nh * A.e[0]; }, nh, off,
            pts, pd);
        break;
      default:
        break;
    }
    if (m == 0) {
      // Smooth shapes (and any rounding miss): the deepest point.
      pts[0] = deepest + nh * (0.5f * depth);
      pd[0] = depth;
      m = 1;
    }
    out.count[k] = static_cast<uint8_t>(m);
    out.n[0][k] = -nh.x;
    out.n[1][k] = -nh.y;
    out.n[2][k] = -nh.z;
    // The reported depth is the support's (the exact deepest point, also for curved sides).
    float dmax = depth;
    for (uint32_t i = 0; i < m; ++i) dmax = simd::fmax_nn(dmax, pd[i]);
    out.depth[k] = dmax;
    for (uint32_t i = 0; i < m; ++i) {
      out.point[i][0][k] = pts[i].x + origin.x;
      out.point[i][1][k] = pts[i].y + origin.y;
      out.point[i][2][k] = pts[i].z + origin.z;
      out.pdepth[i][k] = pd[i];
    }
  }
}

}  // namespace impact::kernels
