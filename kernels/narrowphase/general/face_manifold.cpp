// The face manifold of the general convex routes: the contact points of a touching pair
// given its normal and witnesses (contact_manifold), for GJK / EPA (gjk_epa.cpp), the
// separating axis test (sat.cpp) and the hull-cylinder kernel (convex_cylinder.cpp).
// Method: when both sides offer a flat feature along n (box, convex and triangle faces;
// a cylinder's cap as an inscribed octagon or its side line; a capsule's side line),
// the reference face (the better aligned one with >= 3 vertices, within ~26 degrees of
// n) clips the incident face (Sutherland-Hodgman against side planes through the
// reference edges along n); points below the reference plane are kept, with their
// penetration along n (where the ray along n leaves the reference shape: Chord), reduced
// to 4 (reduce_manifold: deepest, farthest, then largest area); where no clipped point
// carries the depth (within kWitnessJoin: the incident face need not hold the support
// point, the octagon misses the rim between its vertices), the witnesses' midpoint joins
// them with the whole depth, if each witness moved by the depth along n lies in the
// other shape. Otherwise (edge-edge, rims, ellipsoids, spheres), one point midway
// between the witnesses. Either way point +- n pdepth/2 lie on B and A.
// Inputs: leaves loaded by load_leaf (relative to one origin), n unit from A to B,
// depth > 0. Faces of up to kMaxFaceVerts vertices are clipped (more: the witness
// point alone). Stack only, no allocation; no division without a guard.
// Cost: O(face vertices) per side for the face search and the clip, O(faces) per chord.
// Citation: Sutherland and Hodgman, "Reentrant polygon clipping", CACM 17(1), 1974; the
// reference / incident face manifold of Box2D (b2ClipPolygons) and Bullet.
#include "kernels/narrowphase/general/face_manifold.h"

#include <algorithm>
#include <cmath>

#include "kernels/simd/lanes.h"

namespace impact::kernels::cvx {

namespace {

using simd::fmax_nn;
using simd::fmin_nn;


constexpr uint32_t kMaxClip = 2 * kMaxFaceVerts + 8;

/// Types whose supporting feature can be a flat face (or a straight line).
IMPACT_INLINE bool has_faces(LeafType t) {
  return t == kLeafBox || t == kLeafConvex || t == kLeafTriangle || t == kLeafCylinder || t == kLeafCapsule;
}

struct Face {
  V3 v[kMaxFaceVerts];
  uint32_t n = 0;
  V3 normal{0, 0, 1};  // unit, outward
  float d = 0.0f;      // plane normal . x = d
  float align = -2.0f; // normal . dir
};

/// The face of a polytope leaf whose outward normal is most aligned with dir.
bool supporting_face(const Leaf& l, V3 dir, Face* out) {
  if (l.type == kLeafBox) {
    int bi = 0;
    float bs = -1.0f, sgn = 1.0f;
    for (int i = 0; i < 3; ++i) {
      const float s = dot(dir, l.ax[i]);
      if (std::fabs(s) > bs) {
        bs = std::fabs(s);
        bi = i;
        sgn = s >= 0.0f ? 1.0f : -1.0f;
      }
    }
    const int j = (bi + 1) % 3, k = (bi + 2) % 3;
    const V3 c = l.p + l.ax[bi] * (sgn * l.e[bi]);
    const V3 u = l.ax[j] * l.e[j], w = l.ax[k] * l.e[k];
    out->n = 4;
    out->v[0] = c + u + w;
    out->v[1] = c - u + w;
    out->v[2] = c - u - w;
    out->v[3] = c + u - w;
    out->normal = l.ax[bi] * sgn;
    out->d = dot(out->normal, c);
    out->align = bs;
    return true;
  }
  if (l.type == kLeafTriangle) {
    V3 n = cross(l.v1 - l.p, l.v2 - l.p);
    const float nl = len(n);
    if (!(nl > 0.0f)) return false;
    n = n * (1.0f / nl);
    if (dot(n, dir) < 0.0f) n = -n;
    out->n = 3;
    out->v[0] = l.p;
    out->v[1] = l.v1;
    out->v[2] = l.v2;
    out->normal = n;
    out->d = dot(n, l.p);
    out->align = dot(n, dir);
    return true;
  }
  if (l.type == kLeafCapsule) {
    // Lying within ~17 degrees of across dir: the line of its surface facing dir (a
    // 2-vertex face, only ever clipped).
    const float dl = len(dir);
    const float dz = dot(dir, l.ax[2]);
    if (!(dl > 0.0f) || std::fabs(dz) > 0.3f * dl) return false;
    const V3 off = dir * (l.e[0] / dl);
    out->n = 2;
    out->v[0] = l.p - l.ax[2] * l.e[1] + off;
    out->v[1] = l.p + l.ax[2] * l.e[1] + off;
    out->normal = dir * (1.0f / dl);
    out->d = dot(out->normal, out->v[0]);
    out->align = 1.0f;
    return true;
  }
  if (l.type == kLeafCylinder) {
    // Cap within ~45 degrees of dir: the cap as an inscribed octagon (its vertices are
    // on the rim). Side within ~17 degrees: the generator line, a 2-vertex "face" that
    // is only ever clipped (never a reference). In between: no face (one point).
    const float dx = dot(dir, l.ax[0]), dy = dot(dir, l.ax[1]), dz = dot(dir, l.ax[2]);
    const float dl = std::sqrt(dx * dx + dy * dy + dz * dz);
    if (!(dl > 0.0f)) return false;
    if (std::fabs(dz) >= 0.7f * dl) {
      const float sgn = dz >= 0.0f ? 1.0f : -1.0f;
      const V3 c = l.p + l.ax[2] * (sgn * l.e[1]);
      constexpr float kC = 0.70710678f;
      const float cs[8][2] = {{1, 0}, {kC, kC}, {0, 1}, {-kC, kC}, {-1, 0}, {-kC, -kC}, {0, -1}, {kC, -kC}};
      out->n = 8;
      for (uint32_t i = 0; i < 8; ++i) {
        const uint32_t j = sgn > 0.0f ? i : 7 - i;  // counter-clockwise about the outward normal
        out->v[i] = c + l.ax[0] * (cs[j][0] * l.e[0]) + l.ax[1] * (cs[j][1] * l.e[0]);
      }
      out->normal = l.ax[2] * sgn;
      out->d = dot(out->normal, c);
      out->align = std::fabs(dz) / dl;
      return true;
    }
    const float rl = std::sqrt(dx * dx + dy * dy);
    if (rl >= 0.95f * dl) {
      const V3 rad = (l.ax[0] * dx + l.ax[1] * dy) * (1.0f / rl);
      const V3 c = l.p + rad * l.e[0];
      out->n = 2;
      out->v[0] = c - l.ax[2] * l.e[1];
      out->v[1] = c + l.ax[2] * l.e[1];
      out->normal = rad;
      out->d = dot(rad, c);
      out->align = rl / dl;
      return true;
    }
    return false;
  }
  if (l.type == kLeafConvex) {
    const HullView& h = *l.hulls;
    const float dx = dot(dir, l.ax[0]), dy = dot(dir, l.ax[1]), dz = dot(dir, l.ax[2]);
    // The face of largest n.dir, the first among ties, kSimdWidth faces per step.
    const uint32_t bf = argmax_dot(h.fnx, h.fny, h.fnz, h.face_begin[l.hull], h.face_begin[l.hull + 1], dx, dy, dz);
    const float bs = dx * h.fnx[bf] + dy * h.fny[bf] + dz * h.fnz[bf];
    const uint32_t vb = h.face_vert_begin[bf], ve = h.face_vert_begin[bf + 1];
    if (ve - vb > kMaxFaceVerts || ve - vb < 3) return false;
    out->n = ve - vb;
    for (uint32_t i = vb; i < ve; ++i) out->v[i - vb] = hull_vertex(l, h.face_verts[i]);
    out->normal = l.ax[0] * h.fnx[bf] + l.ax[1] * h.fny[bf] + l.ax[2] * h.fnz[bf];
    out->d = dot(out->normal, l.p) + h.fd[bf];
    out->align = bs;
    return true;
  }
  return false;
}

/// The chord of the ray x + t dir (unit dir) through the leaf's planes: t_in is the
/// largest (d_f - n_f.x) / (n_f.dir) over faces facing against dir, t_out the smallest
/// over faces facing dir (box, convex hull); other types: (-inf, +inf) (their
/// reference plane bounds it). t_in > t_out: the ray misses the leaf.
struct Chord {
  float t_in = -INFINITY, t_out = INFINITY;
};

/// |n_f.dir| at or below this counts as parallel: a unit face normal and a unit
/// direction that are perpendicular up to rounding give ~1e-8, not 0, and slack / c
/// of a point on the plane (slack ~ rounding, of either sign) is then an arbitrary t.
/// Over a travel of the shape's size L a ray this close to parallel drifts <= 1e-5 L
/// off the plane, within the slack tolerance's order.
inline constexpr float kChordParallel = 1e-5f;

IMPACT_INLINE void chord_plane(float c, float slack, float tol, Chord* ch) {
  // slack = d_f - n_f.x; the ray crosses the plane at t = slack / c. A ray parallel
  // to the plane misses only when outside by more than tol (the rounding of slack):
  // clipped points lie on the reference face's side planes, and an exact face normal
  // (SAT) runs their rays along those planes.
  if (c > kChordParallel) ch->t_out = fmin_nn(ch->t_out, slack / c);
  else if (c < -kChordParallel) ch->t_in = fmax_nn(ch->t_in, slack / c);
  else if (slack < -tol) ch->t_in = INFINITY;  // parallel and outside
}

Chord chord(const Leaf& l, V3 x, V3 dir) {
  Chord ch;
  if (l.type == kLeafBox) {
    const V3 q = x - l.p;
    for (int i = 0; i < 3; ++i) {
      const float c = dot(l.ax[i], dir), s = dot(l.ax[i], q);
      const float tol = 4e-6f * (l.e[i] + std::fabs(s));
      chord_plane(c, l.e[i] - s, tol, &ch);
      chord_plane(-c, l.e[i] + s, tol, &ch);
    }
  } else if (l.type == kLeafConvex) {
    // kSimdWidth faces per step (min / max are exact, so the lanes' order does not
    // change the result), then the scalar tail.
    using F = simd::FloatN<simd::kSimdWidth>;
    constexpr uint32_t kW = simd::kSimdWidth;
    const HullView& h = *l.hulls;
    const V3 q = x - l.p;
    const float qx = dot(q, l.ax[0]), qy = dot(q, l.ax[1]), qz = dot(q, l.ax[2]);
    const float dx = dot(dir, l.ax[0]), dy = dot(dir, l.ax[1]), dz = dot(dir, l.ax[2]);
    const uint32_t fb = h.face_begin[l.hull], fe = h.face_begin[l.hull + 1];
    uint32_t f = fb;
    if (fe - fb >= kW) {
      const F DX(dx), DY(dy), DZ(dz), QX(qx), QY(qy), QZ(qz), one(1.0f);
      F t_in(-INFINITY), t_out(INFINITY), miss(0.0f);
      for (; f + kW <= fe; f += kW) {
        const F nx = F::load(h.fnx + f), ny = F::load(h.fny + f), nz = F::load(h.fnz + f);
        const F c = nx * DX + ny * DY + nz * DZ;
        const F d = F::load(h.fd + f), nq = nx * QX + ny * QY + nz * QZ;
        const F slack = d - nq;
        const auto pos = c > F(kChordParallel), neg = c < F(-kChordParallel);
        const F t = slack / select(pos | neg, c, one);
        t_out = select(pos, simd::min(t_out, t), t_out);
        t_in = select(neg, simd::max(t_in, t), t_in);
        const F tol = F(4e-6f) * (simd::abs(d) + simd::abs(nq));  // as chord_plane
        miss = select(andnot(slack < -tol, pos | neg), one, miss);
      }
      for (uint32_t k = 0; k < kW; ++k) {
        ch.t_out = fmin_nn(ch.t_out, t_out.lane(k));
        ch.t_in = fmax_nn(ch.t_in, miss.lane(k) > 0.0f ? INFINITY : t_in.lane(k));
      }
    }
    for (; f < fe; ++f) {
      const float c = h.fnx[f] * dx + h.fny[f] * dy + h.fnz[f] * dz;
      const float nq = h.fnx[f] * qx + h.fny[f] * qy + h.fnz[f] * qz;
      chord_plane(c, h.fd[f] - nq, 4e-6f * (std::fabs(h.fd[f]) + std::fabs(nq)), &ch);
    }
  }
  return ch;
}

/// Clips the incident face against the reference face's side planes; writes the
/// points that lie below the reference plane (penetration along n > 0). A point's
/// penetration is how far it travels along n (or -n) until it leaves the reference
/// shape, so that the point +- n pd/2 lies on both surfaces.
uint32_t clip_faces(const Face& ref, const Face& inc, const Leaf& ref_leaf, V3 n, bool ref_is_a, float depth,
                    V3* pts, float* pd) {
  V3 buf0[kMaxClip], buf1[kMaxClip];
  uint32_t cnt = inc.n;
  for (uint32_t i = 0; i < cnt; ++i) buf0[i] = inc.v[i];
  V3* in = buf0;
  V3* out = buf1;
  V3 centroid{0, 0, 0};
  for (uint32_t i = 0; i < ref.n; ++i) centroid = centroid + ref.v[i];
  centroid = centroid * (1.0f / static_cast<float>(ref.n));
  const bool segment = cnt == 2;  // a cylinder's side line: clipped parametrically
  float t0 = 0.0f, t1 = 1.0f;
  for (uint32_t e = 0; e < ref.n && cnt > 0; ++e) {
    const V3 a = ref.v[e], b = ref.v[(e + 1) % ref.n];
    // Side planes contain n (not the face normal): a point kept, moved along n by its
    // penetration, lands inside the reference polygon.
    V3 sn = cross(b - a, n);
    if (dot(sn, centroid - a) > 0.0f) sn = -sn;  // outward whatever the winding
    const float snl = len(sn);
    if (!(snl > 0.0f)) continue;                 // degenerate edge
    sn = sn * (1.0f / snl);
    const float sd = dot(sn, a);
    if (segment) {
      const float dp = dot(sn, in[0]) - sd, dq = dot(sn, in[1]) - sd;
      if (dp > 0.0f && dq > 0.0f) cnt = 0;
      else if (dp > 0.0f) t0 = fmax_nn(t0, dp / (dp - dq));
      else if (dq > 0.0f) t1 = fmin_nn(t1, dp / (dp - dq));
      if (t0 > t1) cnt = 0;
      continue;
    }
    uint32_t m = 0;
    for (uint32_t i = 0; i < cnt; ++i) {
      const V3 p = in[i], q = in[(i + 1) % cnt];
      const float dp = dot(sn, p) - sd, dq = dot(sn, q) - sd;
      if (dp <= 0.0f) out[m++] = p;
      if ((dp < 0.0f && dq > 0.0f) || (dp > 0.0f && dq < 0.0f)) {
        const float t = dp / (dp - dq);
        out[m++] = p + (q - p) * t;
      }
      if (m >= kMaxClip - 2) break;
    }
    cnt = m;
    V3* tmp = in;
    in = out;
    out = tmp;
  }
  if (segment && cnt == 2) {
    const V3 p = in[0], q = in[1];
    in[0] = p + (q - p) * t0;
    in[1] = p + (q - p) * t1;
    if (!(t1 - t0 > 1e-6f)) cnt = 1;
  }
  const float cosn = ref_is_a ? dot(ref.normal, n) : -dot(ref.normal, n);
  uint32_t k = 0;
  for (uint32_t i = 0; i < cnt; ++i) {
    const float s = ref.d - dot(ref.normal, in[i]);  // below the reference plane
    if (!(s > 0.0f)) continue;
    float pdepth = s / cosn;
    const Chord ch = chord(ref_leaf, in[i], ref_is_a ? n : -n);
    // The ray along n from the point must cross the reference shape (a point beside
    // it, outside a side face, is no contact).
    if (ch.t_in > ch.t_out + 1e-6f * std::fabs(ch.t_out)) continue;
    pdepth = fmin_nn(pdepth, ch.t_out);
    if (!(pdepth > 0.0f)) continue;
    pdepth = fmin_nn(pdepth, depth);
    const V3 mid = in[i] + n * (ref_is_a ? 0.5f * pdepth : -0.5f * pdepth);
    pts[k] = mid;
    pd[k] = pdepth;
    ++k;
  }
  return k;
}

/// Whether y = x + depth dir lies in leaf l within tol: outside none of its face planes
/// by more than tol (box, convex hull; other leaves count as holding it). A distance to
/// the planes, not the ray's chord through l: beside a sharp vertex the chord's end
/// moves by a witness's rounding times the cotangent of the vertex's half angle, so a
/// real vertex contact failed the chord form by 2e-7 of 9e-6 (a hull vertex just inside
/// a cylinder's rim, found at IMPACT_TEST_INTENSITY=30), while the planes' distance
/// moves by the rounding alone.
bool reaches_at(const Leaf& l, V3 x, V3 dir, float depth, float tol) {
  const V3 q = x + dir * depth - l.p;
  if (l.type == kLeafBox) {
    for (int i = 0; i < 3; ++i)
      if (std::fabs(dot(l.ax[i], q)) > l.e[i] + tol) return false;
  } else if (l.type == kLeafConvex) {
    const HullView& h = *l.hulls;
    const float qx = dot(q, l.ax[0]), qy = dot(q, l.ax[1]), qz = dot(q, l.ax[2]);
    for (uint32_t f = h.face_begin[l.hull], fe = h.face_begin[l.hull + 1]; f < fe; ++f)
      if (h.fnx[f] * qx + h.fny[f] * qy + h.fnz[f] * qz > h.fd[f] + tol) return false;
  }
  return true;
}

}  // namespace

uint32_t reduce_manifold(V3* pts, float* depth, uint32_t n, V3 normal) {
  if (n <= kMaxManifoldPoints) return n;
  uint32_t i0 = 0;
  for (uint32_t i = 1; i < n; ++i)
    if (depth[i] > depth[i0]) i0 = i;
  uint32_t i1 = i0;
  float best = -1.0f;
  for (uint32_t i = 0; i < n; ++i) {
    const float d2 = len2(pts[i] - pts[i0]);
    if (d2 > best) {
      best = d2;
      i1 = i;
    }
  }
  auto area = [&](uint32_t a, uint32_t b, uint32_t c) {
    return dot(cross(pts[b] - pts[a], pts[c] - pts[a]), normal);
  };
  uint32_t i2 = i0;
  best = -1.0f;
  for (uint32_t i = 0; i < n; ++i) {
    const float a = std::fabs(area(i0, i1, i));
    if (a > best) {
      best = a;
      i2 = i;
    }
  }
  const float sgn = area(i0, i1, i2) >= 0.0f ? 1.0f : -1.0f;
  uint32_t i3 = n;
  best = 0.0f;
  for (uint32_t i = 0; i < n; ++i) {
    const float out = fmax_nn(-sgn * area(i0, i1, i), fmax_nn(-sgn * area(i1, i2, i), -sgn * area(i2, i0, i)));
    if (out > best) {
      best = out;
      i3 = i;
    }
  }
  uint32_t keep[4] = {i0, i1, i2, i3};
  uint32_t m = (i3 == n) ? 3u : 4u;
  // Drop duplicates (tiny manifolds: i1/i2 may repeat i0).
  uint32_t u = 0;
  for (uint32_t i = 0; i < m; ++i) {
    bool dup = false;
    for (uint32_t j = 0; j < u; ++j) dup = dup || keep[j] == keep[i];
    if (!dup) keep[u++] = keep[i];
  }
  V3 tp[4];
  float td[4];
  for (uint32_t i = 0; i < u; ++i) {
    tp[i] = pts[keep[i]];
    td[i] = depth[keep[i]];
  }
  for (uint32_t i = 0; i < u; ++i) {
    pts[i] = tp[i];
    depth[i] = td[i];
  }
  return u;
}

void contact_manifold(const Leaf& A, const Leaf& B, V3 n, float depth, V3 pa, V3 pb, LaneContact* out) {
  const float ra = core_radius(A), rb = core_radius(B);
  out->n = n;
  out->depth = depth;
  // Pairs of faceted sides (polytopes, cylinder caps / side lines): clipped face
  // manifold. The reference face is the better aligned of the two faces with >= 3
  // vertices, and must be within ~26 degrees of n (else edge-edge: one point).
  if (has_faces(A.type) && has_faces(B.type)) {
    Face fa, fb;
    // B's first: where one side offers no face the other's is not needed, and B is the
    // cheaper one in the hull-cylinder bucket (a cap or side line against a face search)
    if (supporting_face(B, -n, &fb) && supporting_face(A, n, &fa)) {
      constexpr float kMinAlign = 0.9f;
      const bool ca = fa.n >= 3 && fa.align >= kMinAlign, cb = fb.n >= 3 && fb.align >= kMinAlign;
      if (ca || cb) {
        const bool ref_is_a = ca && (!cb || fa.align >= fb.align);
        const Face& ref = ref_is_a ? fa : fb;
        const Face& inc = ref_is_a ? fb : fa;
        V3 pts[kMaxClip + 1];
        float pd[kMaxClip + 1];
        uint32_t m = clip_faces(ref, inc, ref_is_a ? A : B, n, ref_is_a, depth, pts, pd);
        if (m > 0) {
          // The witnesses' midpoint joins where no clipped point carries the depth
          // (kWitnessJoin): where each witness moved by the depth along n lands in the
          // other shape (GJK / EPA's always do; SAT's face witness, one vertex and its
          // shadow on the face, may land beside the face on near-parallel features).
          float deepest = 0.0f;
          for (uint32_t i = 0; i < m; ++i) deepest = fmax_nn(deepest, pd[i]);
          const V3 sa = pa + n * ra, sb = pb - n * rb;  // on the surfaces
          const float tol = kWitnessReach * depth + 1e-6f * (leaf_size(A) + leaf_size(B));
          const float miss = kWitnessJoin * (depth + leaf_size(A) + leaf_size(B));
          if (deepest < depth - miss && reaches_at(A, sb, n, depth, tol) &&
              reaches_at(B, sa, -n, depth, tol)) {
            pts[m] = (sa + sb) * 0.5f;
            pd[m] = depth;
            ++m;
          }
          m = reduce_manifold(pts, pd, m, n);
          out->count = m;
          for (uint32_t i = 0; i < m; ++i) {
            out->point[i] = pts[i];
            out->pdepth[i] = pd[i];
          }
          return;
        }
      }
    }
  }
  // One point, midway between the surfaces (the witnesses moved out by the radii).
  const V3 sa = pa + n * ra, sb = pb - n * rb;
  out->count = 1;
  out->point[0] = (sa + sb) * 0.5f;
  out->pdepth[0] = depth;
}

}  // namespace impact::kernels::cvx
