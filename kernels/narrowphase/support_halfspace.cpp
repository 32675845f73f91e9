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
//     manifold and the triangle's vertices below; this routine serves hulls).
// Each point lies midway between A's point x and its projection onto the plane; its
// pdepth is x's depth. Points are computed relative to A's position (precision far from
// the origin) and shifted back on output.
// Inputs: posed leaves per leaf.h (finite, unit nh). Deterministic (fixed loop order,
// first index wins ties). cfg.path kSimd and kScalar run the same per-lane code.
// Cost: O(1) per lane, O(vertex count) for convex hulls: one kSimdWidth-wide pass in
// the hull's frame lists the vertices below the plane (at most 64; more fall back to
// scanning all vertices), their world positions are computed once, and the deepest
// vertex and the selection passes come from that list (no separate support scan). No
// allocation. impact_narrowbench (24-point hulls, half the pairs touching): ~70 ns per
// pair (was 130 with the support scan and per-pass vertex transforms; FCL ~190).
#include <cmath>

#include "kernels/narrowphase/pair_kernels.h"
#include "kernels/narrowphase/support.h"

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

/// Most hull vertices below the plane that the candidate list holds; a hull sunk
/// deeper falls back to scanning all its vertices.
constexpr uint32_t kMaxCandidates = 64;

/// Hull vertices [vb, ve) that may lie below the plane nh.x = off, in index order:
/// one pass in the hull's frame (the plane moved into it: nl = R^T nh, offl = off -
/// nh.p), kSimdWidth vertices per step. The slack admits the vertices whose local and
/// world depths differ in sign by rounding; pick_below re-tests every candidate in the
/// world frame, so the result equals a scan of all vertices. Returns the count, or
/// kMaxCandidates + 1 when more would be needed.
uint32_t hull_candidates(const HullView& h, uint32_t vb, uint32_t ve, const cvx::Leaf& A, V3 nh, float off,
                         uint32_t* cand) {
  using F = simd::FloatN<simd::kSimdWidth>;
  constexpr uint32_t kW = simd::kSimdWidth;
  const float nx = cvx::dot(nh, A.ax[0]), ny = cvx::dot(nh, A.ax[1]), nz = cvx::dot(nh, A.ax[2]);
  const float offl = off - cvx::dot(nh, A.p);
  // Rounding of the two frames' dot products: relative to the terms' magnitudes.
  const float reach = std::fabs(off) + cvx::len(A.p);
  const float slack = 1e-5f * reach + 1e-30f;
  const float lim = offl + slack;  // below: nl.v < lim
  uint32_t nc = 0;
  uint32_t i = vb;
  const F X(nx), Y(ny), Z(nz), L(lim);
  for (; i + kW <= ve; i += kW) {
    const F s = X * F::load(h.vx + i) + Y * F::load(h.vy + i) + Z * F::load(h.vz + i);
    // the set lanes only, lowest first
    for (uint32_t below = simd::bits(s < L); below != 0; below &= below - 1) {
      if (nc == kMaxCandidates) return kMaxCandidates + 1;
      cand[nc++] = i + static_cast<uint32_t>(__builtin_ctz(below));
    }
  }
  for (; i < ve; ++i) {
    if (!(nx * h.vx[i] + ny * h.vy[i] + nz * h.vz[i] < lim)) continue;
    if (nc == kMaxCandidates) return kMaxCandidates + 1;
    cand[nc++] = i;
  }
  return nc;
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
      const uint32_t vb = cfg.hulls.vert_begin[A.hull];
      const uint32_t ve = cfg.hulls.vert_begin[A.hull + 1];
      uint32_t cand[kMaxCandidates];
      const uint32_t nc = hull_candidates(cfg.hulls, vb, ve, A, nh, off, cand);
      if (nc <= kMaxCandidates) {
        V3 xs[kMaxCandidates];
        for (uint32_t i = 0; i < nc; ++i) xs[i] = cvx::hull_vertex(A, cand[i]);
        m = pick_below(nc, [&](uint32_t i) { return xs[i]; }, nh, off, pts, pd);
      } else {
        m = pick_below(ve - vb, [&](uint32_t i) { return cvx::hull_vertex(A, vb + i); }, nh, off, pts, pd);
      }
      if (m == 0) {
        out.count[k] = 0;
        continue;
      }
      depth = pd[0];  // pick_below's first point is the deepest vertex
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
