// General convex pairs: GJK + EPA on support functions, then the face manifold
// (face_manifold.cpp). Small polytope pairs (box / hull) take the separating axis test
// instead: pair_kernels.cpp routes them (collide_sat_or_gjk_epa).
//
// What: collide_gjk_epa computes, per lane k of a bucket (A's type <= B's type, neither
// a half-space), the collision data of leaf.h: count, unit normal A->B, depth, up to 4
// contact points midway between the surfaces with their penetration along n.
// Method, per lane:
//  1. Both leaves are loaded relative to A's position (float precision far from the
//     world origin: every coordinate is then a difference of nearby values).
//  2. GJK (Gilbert, Johnson, Keerthi 1988; van den Bergen 1999 termination) on the
//     cores (sphere = point, capsule = segment, other types = themselves, support.h):
//     distance d and closest points. A margin lower bound v.w/|v| > ra + rb stops a
//     separated lane early. Cores apart (d > 1e-5 of the scale): depth = ra + rb - d,
//     exact for spheres / capsules; d >= ra + rb (or no radius) -> count 0.
//  3. Cores overlapping: EPA (Van den Bergen 2001) on the cores, from GJK's simplex
//     blown up to a tetrahedron; depth = EPA depth + ra + rb, the exact penetration of
//     the inflated shapes. The EPA depth reported is the support of A - B along the
//     final normal (>= the polytope's face distance, equal within the tolerance when
//     converged), so moving B by n * depth always separates the pair. EPA stopped by
//     its cap (curved, deep, near-concentric pairs: the polytope is refined evenly)
//     restarts from the face normal of least support value and minimises that support
//     function over the unit sphere (up to 40 descent steps with a quadratic-model step
//     and a two-subgradient bundle across kinks such as a cylinder's side), then runs a
//     GJK on the pair moved just clear for the witnesses. Converged lanes skip this.
//     Pairs with a hull side are not stopped by the cap: they expand until converged
//     or the polytope is full (512 vertices). A hull gives the support function a
//     strict local minimum at every face of A - B that holds the origin's projection
//     (hundreds around a deep core in a round many-vertex hull), and a descent stays on
//     the face it starts from: a sphere deep in a 400-vertex hull, stopped at the cap,
//     reported a face 104 degrees from the least one, its depth 3.4e-3 too large; 81
//     expansions converge it.
//     Smooth pairs (sphere and ellipsoid cores: unique supports, a differentiable
//     support function h) leave EPA once its gap is below 3e-3 of the scale: Newton's
//     method on h over unit directions (forward-difference Hessian, two supports per
//     step) converges quadratically where EPA gains a decade per ~5 expansions; it
//     stops when its predicted decrease is below 0.1 cfg.epa_tolerance, and its answer
//     stands only if every polytope face closer than it lies within ~25 degrees of its
//     normal (no second minimum elsewhere); else EPA goes on unchanged.
//     A flat core difference (crossing segments, coincident centres, coplanar
//     triangles) has core depth 0 along a deterministic normal (towards B's centre,
//     else +y).
//  4. Contact points: contact_manifold (face_manifold.cpp) from n, the depth and the
//     witnesses: clipped faces where both sides offer a flat feature along n, else one
//     point midway between the witnesses.
// Triangles are two-sided and zero-thickness: the normal is whichever side separates
// with less motion; two coplanar triangles have depth 0 (count 0).
// Precision: supports are float; the simplex and polytope arithmetic is double (no
// cost on a CPU, and it keeps the sub-algorithm's sign tests away from cancellation).
// Tolerances: cfg.gjk_tolerance and cfg.epa_tolerance times the scale (the sum of the
// two shapes' sizes, support.h leaf_size); iteration caps cfg.gjk_max_iterations and
// cfg.epa_max_iterations (the latter for pairs without a hull side; EPA also stops at
// its fixed polytope capacity, kEpaMaxVerts).
// Paths: GJK/EPA do not vectorise across lanes; cfg.path kSimd and kScalar run this same
// per-lane code (bit-identical results). Within a lane, hull supports and the ray chord
// through a hull's face planes run kSimdWidth vertices / faces per step; the EPA
// polytope keeps only live faces, in SoA (a removed face's slot takes the last live
// face), and the closest face is found by a branch-free minimum over them.
// Robustness: degenerate simplices fall back to their best sub-simplex, EPA aborts to
// its last valid face on any topological inconsistency, no division without a guard:
// no NaN for finite input. No allocation (the EPA polytope lives on the stack).
// Cost: GJK ~3-15 iterations of 2 supports; EPA ~5-40 iterations (curved shapes take
// the most: cylinder pairs average ~14 at the default tolerance, ellipsoid pairs ~12
// with the Newton finish (~23 without), hull pairs ~5-6); hull supports are
// O(vertices); the worst case of the uncapped hull pairs, deep nearly concentric lanes
// in a round 400-vertex hull, takes ~75 expansions (hull-hull ~130, at most ~180).
// Measured per pair, with the EPA-cap and worst-case lanes, in docs/results.md
// ("Narrow phase") and docs/history.md.
// cfg.epa_tolerance trades depth error for time on curved pairs (polytope pairs converge
// exactly and do not change): measured against the matrix test's double reference, the
// worst |depth error| over its curved-pair scenarios is ~2e-5 L at 1e-5 (the default),
// ~1.7e-4 L at 1e-4 (ellipsoid pairs ~20% faster, cylinder pairs ~15%), ~6e-4 L at 3e-4
// (~30% / 25% faster); L = the larger bounding radius.
#include "kernels/narrowphase/general/gjk_epa.h"

#include <algorithm>
#include <cmath>

#include "kernels/narrowphase/general/face_manifold.h"
#include "kernels/narrowphase/pair_kernels.h"
#include "kernels/simd/lanes.h"

namespace impact::kernels::cvx {

namespace {

using simd::fmax_nn;
using simd::fmin_nn;

IMPACT_INLINE D3 operator+(D3 a, D3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
IMPACT_INLINE D3 operator-(D3 a, D3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
IMPACT_INLINE D3 operator*(D3 a, double s) { return {a.x * s, a.y * s, a.z * s}; }
IMPACT_INLINE double dot(D3 a, D3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
IMPACT_INLINE D3 cross(D3 a, D3 b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
IMPACT_INLINE D3 to_d(V3 a) { return {a.x, a.y, a.z}; }
IMPACT_INLINE V3 to_f(D3 a) {
  return {static_cast<float>(a.x), static_cast<float>(a.y), static_cast<float>(a.z)};
}
IMPACT_INLINE double len2(D3 a) { return dot(a, a); }

/// Support of the core difference A - B along d.
IMPACT_INLINE SupportPoint support_diff(const Leaf& A, const Leaf& B, V3 d) {
  SupportPoint s;
  s.a = support_core(A, d);
  s.b = support_core(B, -d);
  s.w = to_d(s.a) - to_d(s.b);
  return s;
}

// --- GJK sub-algorithm: closest point of a simplex to the origin ---------------------------

/// Segment [v0, v1]: reduces s to the sub-simplex holding the closest point.
void closest_segment(Simplex& s) {
  const D3 a = s.v[0].w, b = s.v[1].w;
  const D3 ab = b - a;
  const double l2 = len2(ab);
  const double t = l2 > 0.0 ? -dot(a, ab) / l2 : 1.0;
  if (t >= 1.0) {
    s.v[0] = s.v[1];
    s.n = 1;
    s.lambda[0] = 1.0;
  } else if (t <= 0.0) {
    s.n = 1;
    s.lambda[0] = 1.0;
  } else {
    s.lambda[0] = 1.0 - t;
    s.lambda[1] = t;
  }
}

/// Triangle: Ericson, Real-Time Collision Detection, 5.1.5, with the origin as query.
void closest_triangle(Simplex& s) {
  const D3 a = s.v[0].w, b = s.v[1].w, c = s.v[2].w;
  const D3 ab = b - a, ac = c - a;
  const double d1 = -dot(ab, a), d2 = -dot(ac, a);
  if (d1 <= 0.0 && d2 <= 0.0) {
    s.n = 1;
    s.lambda[0] = 1.0;
    return;
  }
  const double d3 = -dot(ab, b), d4 = -dot(ac, b);
  if (d3 >= 0.0 && d4 <= d3) {
    s.v[0] = s.v[1];
    s.n = 1;
    s.lambda[0] = 1.0;
    return;
  }
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) {
    const double t = d1 / (d1 - d3);
    s.n = 2;
    s.lambda[0] = 1.0 - t;
    s.lambda[1] = t;
    return;
  }
  const double d5 = -dot(ab, c), d6 = -dot(ac, c);
  if (d6 >= 0.0 && d5 <= d6) {
    s.v[0] = s.v[2];
    s.n = 1;
    s.lambda[0] = 1.0;
    return;
  }
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) {
    const double t = d2 / (d2 - d6);
    s.v[1] = s.v[2];
    s.n = 2;
    s.lambda[0] = 1.0 - t;
    s.lambda[1] = t;
    return;
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0) {
    const double t = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    s.v[0] = s.v[1];
    s.v[1] = s.v[2];
    s.n = 2;
    s.lambda[0] = 1.0 - t;
    s.lambda[1] = t;
    return;
  }
  const double sum = va + vb + vc;
  const double area2 = len2(cross(ab, ac));
  if (!(sum > 1e-14 * (len2(ab) * len2(ac))) || !(area2 > 0.0)) {
    // Degenerate (collinear) triangle: the best of its three edges.
    Simplex best;
    double best_d = INFINITY;
    const int e[3][2] = {{0, 1}, {1, 2}, {2, 0}};
    for (const auto& ed : e) {
      Simplex t;
      t.n = 2;
      t.v[0] = s.v[ed[0]];
      t.v[1] = s.v[ed[1]];
      closest_segment(t);
      D3 p{0, 0, 0};
      for (uint32_t i = 0; i < t.n; ++i) p = p + t.v[i].w * t.lambda[i];
      const double dd = len2(p);
      if (dd < best_d) {
        best_d = dd;
        best = t;
      }
    }
    s = best;
    return;
  }
  const double inv = 1.0 / sum;
  s.lambda[1] = vb * inv;
  s.lambda[2] = vc * inv;
  s.lambda[0] = 1.0 - s.lambda[1] - s.lambda[2];
}

/// Tetrahedron: returns true when the origin is inside (s unchanged, lambdas set);
/// else s becomes the closest face's sub-simplex.
bool closest_tetrahedron(Simplex& s) {
  const D3 p[4] = {s.v[0].w, s.v[1].w, s.v[2].w, s.v[3].w};
  static constexpr int kFace[4][4] = {{0, 1, 2, 3}, {0, 1, 3, 2}, {0, 2, 3, 1}, {1, 2, 3, 0}};
  const double vol = dot(p[1] - p[0], cross(p[2] - p[0], p[3] - p[0]));
  const double scale3 = std::sqrt(len2(p[1] - p[0]) * len2(p[2] - p[0]) * len2(p[3] - p[0]));
  const bool degenerate = !(std::fabs(vol) > 1e-12 * scale3);
  bool outside[4];
  bool any = false;
  for (int f = 0; f < 4; ++f) {
    const D3 a = p[kFace[f][0]], b = p[kFace[f][1]], c = p[kFace[f][2]], o = p[kFace[f][3]];
    const D3 n = cross(b - a, c - a);
    const double so = dot(n, o - a), s0 = -dot(n, a);
    outside[f] = degenerate || (so * s0 < 0.0);
    any = any || outside[f];
  }
  if (!any) {
    // Barycentric weights of the origin.
    const double inv = 1.0 / vol;
    s.lambda[1] = dot(p[0] * -1.0, cross(p[2] - p[0], p[3] - p[0])) * inv;
    s.lambda[2] = dot(p[1] - p[0], cross(p[0] * -1.0, p[3] - p[0])) * inv;
    s.lambda[3] = dot(p[1] - p[0], cross(p[2] - p[0], p[0] * -1.0)) * inv;
    s.lambda[0] = 1.0 - s.lambda[1] - s.lambda[2] - s.lambda[3];
    return true;
  }
  Simplex best;
  double best_d = INFINITY;
  for (int f = 0; f < 4; ++f) {
    if (!outside[f]) continue;
    Simplex t;
    t.n = 3;
    for (int i = 0; i < 3; ++i) t.v[i] = s.v[kFace[f][i]];
    closest_triangle(t);
    D3 q{0, 0, 0};
    for (uint32_t i = 0; i < t.n; ++i) q = q + t.v[i].w * t.lambda[i];
    const double dd = len2(q);
    if (dd < best_d) {
      best_d = dd;
      best = t;
    }
  }
  s = best;
  return false;
}

/// Reduces s to the sub-simplex closest to the origin; returns the closest point and
/// whether the origin is enclosed by a tetrahedron.
bool solve_simplex(Simplex& s, D3* v) {
  bool inside = false;
  switch (s.n) {
    case 1: s.lambda[0] = 1.0; break;
    case 2: closest_segment(s); break;
    case 3: closest_triangle(s); break;
    default: inside = closest_tetrahedron(s); break;
  }
  D3 q{0, 0, 0};
  for (uint32_t i = 0; i < s.n; ++i) q = q + s.v[i].w * s.lambda[i];
  *v = inside ? D3{0, 0, 0} : q;
  return inside;
}

void witnesses(const Simplex& s, V3* pa, V3* pb) {
  D3 a{0, 0, 0}, b{0, 0, 0};
  for (uint32_t i = 0; i < s.n; ++i) {
    a = a + to_d(s.v[i].a) * s.lambda[i];
    b = b + to_d(s.v[i].b) * s.lambda[i];
  }
  *pa = to_f(a);
  *pb = to_f(b);
}

// --- EPA polytope ----------------------------------------------------------------------

// Capacities of the EPA polytope (on the stack, ~160 bytes per vertex, in its SoA
// arrays and the expansion's scratch). Every lane starts in the small one (~21 KB, the
// frame of the common path); the few that fill it go on in the large one (~80 KB, in a
// frame of its own), the same expansions from the same state. Those are pairs with a
// hull side, which run EPA to convergence (epa_cores): deep, nearly concentric, round
// many-vertex hulls take up to ~350 expansions at 1000 vertices per hull (~230 for a
// sphere in a 2000-vertex hull; beyond the capacity the lane ends as a capped one);
// and lanes with a cfg.epa_max_iterations above ~128. A closed triangulated polytope of
// V vertices has 2V - 4 faces.
constexpr uint32_t kEpaSmallVerts = 132;
constexpr uint32_t kEpaMaxVerts = 512;

struct EpaFace {
  uint16_t i[3];
  D3 n;
  double d;  // n . w[i0]: signed distance of the plane from the origin
};

/// The polytope: vertices, and its live faces in SoA (compacted in order after every
/// expansion), so that the visibility test runs over contiguous doubles. Capacity:
/// kMaxV vertices.
template <uint32_t kMaxV>
struct Polytope {
  static constexpr uint32_t kMaxVerts = kMaxV;
  static constexpr uint32_t kMaxFaces = 2 * kMaxV;
  static constexpr uint32_t kMaxHorizon = 3 * kMaxV;
  SupportPoint v[kMaxVerts];
  uint32_t nv = 0;
  double fnx[kMaxFaces], fny[kMaxFaces], fnz[kMaxFaces];
  double fd[kMaxFaces];  // n . w[i0]: signed distance of the plane from the origin
  uint16_t fi[kMaxFaces][3];
  uint32_t nf = 0;

  /// This polytope becomes a copy of o (o.nv <= kMaxVerts).
  template <uint32_t kOther>
  void copy_from(const Polytope<kOther>& o) {
    nv = o.nv;
    nf = o.nf;
    std::copy(o.v, o.v + o.nv, v);
    std::copy(o.fnx, o.fnx + o.nf, fnx);
    std::copy(o.fny, o.fny + o.nf, fny);
    std::copy(o.fnz, o.fnz + o.nf, fnz);
    std::copy(o.fd, o.fd + o.nf, fd);
    for (uint32_t k = 0; k < o.nf; ++k)
      for (int j = 0; j < 3; ++j) fi[k][j] = o.fi[k][j];
  }

  EpaFace face(uint32_t k) const {
    EpaFace F;
    for (int j = 0; j < 3; ++j) F.i[j] = fi[k][j];
    F.n = D3{fnx[k], fny[k], fnz[k]};
    F.d = fd[k];
    return F;
  }
  void move_face(uint32_t to, uint32_t from) {
    fnx[to] = fnx[from];
    fny[to] = fny[from];
    fnz[to] = fnz[from];
    fd[to] = fd[from];
    for (int j = 0; j < 3; ++j) fi[to][j] = fi[from][j];
  }
};

/// The live face of least distance, the lowest index among ties (P.nf > 0). A plain
/// compare-and-branch scan: the branch is rarely taken, so it predicts well, where a
/// branch-free running minimum is one long chain of dependent min operations.
template <class Poly>
uint32_t closest_face(const Poly& P) {
  double bd = P.fd[0];
  uint32_t best = 0;
  for (uint32_t k = 1; k < P.nf; ++k)
    if (P.fd[k] < bd) {
      bd = P.fd[k];
      best = k;
    }
  return best;
}

/// Adds face (a, b, c), counter-clockwise seen from outside; false if degenerate/full.
template <class Poly>
bool add_face(Poly& P, uint32_t a, uint32_t b, uint32_t c) {
  if (P.nf >= Poly::kMaxFaces) return false;  // P holds live faces only
  const D3 n = cross(P.v[b].w - P.v[a].w, P.v[c].w - P.v[a].w);
  const double l2 = len2(n);
  if (!(l2 > 0.0)) return false;
  const uint32_t k = P.nf++;
  P.fi[k][0] = static_cast<uint16_t>(a);
  P.fi[k][1] = static_cast<uint16_t>(b);
  P.fi[k][2] = static_cast<uint16_t>(c);
  const D3 u = n * (1.0 / std::sqrt(l2));
  P.fnx[k] = u.x;
  P.fny[k] = u.y;
  P.fnz[k] = u.z;
  P.fd[k] = dot(u, P.v[a].w);
  return true;
}

D3 unit_perp(D3 e) {
  // The axis least aligned with e, crossed with e.
  const double ax = std::fabs(e.x), ay = std::fabs(e.y), az = std::fabs(e.z);
  const D3 axis = (ax <= ay && ax <= az) ? D3{1, 0, 0} : (ay <= az ? D3{0, 1, 0} : D3{0, 0, 1});
  const D3 p = cross(e, axis);
  return p * (1.0 / std::sqrt(len2(p)));
}

/// Deterministic normal of a flat (dimension < 3) core difference: the unit direction
/// `normal_space` allows that is closest to centre(B) - centre(A); else a fixed axis.
V3 flat_normal(const Leaf& A, const Leaf& B, const Simplex& s, uint32_t dim) {
  const D3 c = to_d(leaf_center(B) - leaf_center(A));
  D3 n{0, 1, 0};
  if (dim == 2) {
    // Plane of the difference: its normal, signed towards B.
    n = cross(s.v[1].w - s.v[0].w, s.v[2].w - s.v[0].w);
    n = n * (1.0 / std::sqrt(len2(n)));
    if (dot(n, c) < 0.0) n = n * -1.0;
  } else if (dim == 1) {
    const D3 e0 = s.v[1].w - s.v[0].w;
    const D3 e = e0 * (1.0 / std::sqrt(len2(e0)));
    const D3 q = c - e * dot(c, e);
    const double cl = std::sqrt(len2(c));
    if (len2(q) > 1e-12 * (cl * cl) && len2(q) > 0.0) {
      n = q * (1.0 / std::sqrt(len2(q)));
    } else {
      n = unit_perp(e);
    }
  } else {
    if (len2(c) > 0.0) n = c * (1.0 / std::sqrt(len2(c)));
  }
  return to_f(n);
}

/// Normal, depth and witnesses from the polytope face F (its vertices are still stored).
/// The depth reported is the support of A - B along the normal, n.w >= F.d: moving B by
/// n * depth always separates (within float rounding), converged or not; converged,
/// the two differ by at most the tolerance.
/// Not converged (cap or inconsistency): the best face normal by h, then descent steps
/// on the support function h(n) = max_w n.w over the unit sphere (its gradient is the
/// support point w; the minimum of h is the penetration depth), each accepted only if
/// it lowers h, so the answer only improves.
// The support value h = m . w of A - B in unit direction m: where it is below *h, m
// becomes the direction (*n, its support point *w, *h) and the result is true.
bool lower_support(const Leaf& A, const Leaf& B, const V3& m, V3* n, SupportPoint* w, double* h) {
  const SupportPoint wm = support_diff(A, B, m);
  const double hm = dot(to_d(m), wm.w);
  if (!(hm < *h)) return false;
  *n = m;
  *w = wm;
  *h = hm;
  return true;
}

template <class Poly>
void epa_finish(const Leaf& A, const Leaf& B, const Poly& P, const EpaFace& F, bool converged,
                double tol, float scale, EpaResult* r) {
  V3 n = to_f(F.n);
  n = n * (1.0f / len(n));  // unit to float rounding
  SupportPoint w = support_diff(A, B, n);
  double h = dot(to_d(n), w.w);
  if (converged) {
    // Barycentric witnesses of the origin's projection. A flat face of A - B is split
    // into coplanar triangles with (nearly) tied distances; the projection lies in one
    // of them, not necessarily in F: prefer a tied, parallel face that contains it.
    const D3 q = F.n * F.d;
    Simplex best;
    bool found = false;
    for (uint32_t k = 0; k <= P.nf && !found; ++k) {
      const EpaFace G = k == 0 ? F : P.face(k - 1);
      if (k > 0 && (!(std::fabs(G.d - F.d) <= tol) || !(dot(G.n, F.n) > 1.0 - 1e-9))) continue;
      Simplex t;
      t.n = 3;
      for (int i = 0; i < 3; ++i) {
        t.v[i] = P.v[G.i[i]];
        t.v[i].w = t.v[i].w - q;  // the projection of the origin becomes the query point
      }
      closest_triangle(t);
      if (k == 0) best = t;
      if (t.n == 3) {
        best = t;
        found = true;
      }
    }
    witnesses(best, &r->pa, &r->pb);
  } else {
    // Start from the face normal with the lowest support value h (an upper bound),
    // not the lowest face distance (a lower bound): on a nearly round difference
    // (near-concentric curved shapes) the polytope at the cap is refined evenly and
    // its closest face may lie in the wrong basin of h. Lowest index wins ties.
    for (uint32_t k = 0; k < P.nf; ++k) {
      const EpaFace G = P.face(k);
      const V3 m = to_f(G.n);
      lower_support(A, B, m * (1.0f / len(m)), &n, &w, &h);
    }
    // Descent on the sphere of directions. The (sub)gradient of h at n is the support
    // point w; its tangential part g is the descent direction where h is smooth. At a
    // kink (a support set that is a segment or a face: a cylinder's side, a capsule)
    // the step overshoots and fails; the failed trial's support gives a second
    // subgradient, and the next step follows the least-norm point of the segment
    // between them (a two-element bundle), which is the descent direction along the
    // kink. Each step is accepted only if it lowers h, so the answer only improves.
    // Step control: a step is an angle along the great circle; each trial fits the
    // quadratic h0 - |g| s + c s^2 / 2 through its result and the next step is that
    // model's minimum (clamped to [s / 8, 4 s]); nearly concentric shapes make h very
    // flat (c ~ the centres' offset), so a fixed or slowly growing step would stall
    // in float rounding noise far from the minimum.
    constexpr int kRefineSteps = 40;
    constexpr double kMaxStep = 0.5;  // radians
    double step = 0.25;
    D3 dir{0, 0, 0};
    bool fresh = true;  // dir is the plain gradient at n
    for (int k = 0; k < kRefineSteps; ++k) {
      const D3 nd = to_d(n);
      if (fresh) dir = w.w - nd * dot(w.w, nd);
      const double dl = std::sqrt(len2(dir));
      if (!(dl > 1e-3 * tol) || !(step > 1e-7)) break;
      D3 m = nd - dir * (std::tan(step) / dl);
      m = m * (1.0 / std::sqrt(len2(m)));
      V3 mf = to_f(m);
      mf = mf * (1.0f / len(mf));
      const SupportPoint wm = support_diff(A, B, mf);
      const double hm = dot(to_d(mf), wm.w);
      const double curv = 2.0 * (hm - h + dl * step) / (step * step);
      const bool model = curv > 0.0;
      const double newton = model ? std::min(4.0 * step, std::max(0.125 * step, dl / curv)) : 0.0;
      if (hm < h) {
        n = mf;
        w = wm;
        h = hm;
        step = std::min(kMaxStep, model ? newton : 2.0 * step);
        fresh = true;
      } else {
        // Second subgradient: the trial's support, tangential at n.
        const D3 g2 = wm.w - nd * dot(wm.w, nd);
        const D3 e = g2 - dir;
        const double e2 = len2(e);
        double t = e2 > 0.0 ? -dot(dir, e) / e2 : 0.0;
        t = std::min(1.0, std::max(0.0, t));
        const D3 bundle = dir + e * t;
        if (len2(bundle) < 0.25 * len2(dir)) dir = bundle;  // a kink: follow it
        step = model ? std::min(0.5 * step, newton) : 0.25 * step;
        fresh = false;
      }
    }
    // Witnesses: at a kink of h (a support set that is an edge or a face, as a
    // capsule's side) the support points need not face each other. GJK on the pair
    // with B moved just clear along n (by depth + 1e-3 of the scale) finds the closest,
    // facing points; moved back, they are the contact's witnesses.
    r->pa = w.a;
    r->pb = w.b;
    const float clear = static_cast<float>(h + 1e-3 * scale);
    const V3 off = n * clear;
    Leaf moved = B;
    moved.p = moved.p + off;
    moved.v1 = moved.v1 + off;
    moved.v2 = moved.v2 + off;
    const GjkResult g = gjk_cores(A, moved, scale, scale, 64, 1e-6f);  // margin: no early out
    if (!g.overlap && !g.separated_early) {
      r->pa = g.pa;
      r->pb = g.pb - off;
    }
  }
  r->n = n;
  r->depth = static_cast<float>(h);
}

/// Leaf types whose core has a unique support point in every direction, so that the
/// support function of a pair of them is differentiable: sphere (a point), ellipsoid.
IMPACT_INLINE bool is_smooth(LeafType t) { return t == kLeafSphere || t == kLeafEllipsoid; }

/// EPA hands a smooth pair to polish_smooth once its closest face's gap (upper minus
/// lower bound of the depth) is below this fraction of the scale: the face normal is
/// then within a few degrees of the minimum's. Reported depths stay upper bounds, and
/// a Newton minimum that is not the global one (two local minima of h within this gap
/// of each other) is off by less than the gap.
constexpr double kPolishStart = 3e-3;
constexpr int kPolishSteps = 8;

/// Newton's method for the minimum of the support function h(n) = max_w n.w of the
/// core difference over unit directions n, from n0 (van den Bergen's EPA computes the
/// same minimum; for smooth h, Newton converges quadratically where EPA refines its
/// polytope linearly, ~5 expansions per decade of the tolerance).
/// In tangent coordinates t1, t2 at n: the gradient is g_j = w.t_j (w = support point),
/// the Hessian H = J - h I with J_ij = d(w.t_j)/d(theta_i) by forward differences
/// (two supports at 1e-3 rad), and the step solves H delta = -g. A step is taken only
/// if H is positive definite, the step is local (< 0.3 rad) and it lowers h (else one
/// halving); the method stops, converged, once the predicted decrease g.H^-1.g / 2 is
/// below 0.1 tol. Returns false (r untouched) when it does not converge in kPolishSteps:
/// the caller continues EPA. On success: r's normal, depth h (an upper bound: moving B
/// by n * h separates) and witnesses (the supports, unique for these shapes).
// Out of line: inlined, its frame and registers would burden every EPA lane, most of
// which (polytopes, cylinders) never call it.
__attribute__((noinline)) bool polish_smooth(const Leaf& A, const Leaf& B, D3 n0, double tol, EpaResult* r) {
  auto unit_f = [](D3 d) {
    V3 f = to_f(d);
    return f * (1.0f / len(f));
  };
  V3 n = unit_f(n0);
  SupportPoint w = support_diff(A, B, n);
  double h = dot(to_d(n), w.w);
  constexpr double kEps = 1e-3;
  for (int step = 0; step < kPolishSteps; ++step) {
    const D3 nd = to_d(n);
    const D3 t1 = unit_perp(nd);
    const D3 t2 = cross(nd, t1);
    const double g1 = dot(w.w, t1), g2 = dot(w.w, t2);
    const SupportPoint w1 = support_diff(A, B, to_f(nd + t1 * kEps));
    const SupportPoint w2 = support_diff(A, B, to_f(nd + t2 * kEps));
    const double j11 = (dot(w1.w, t1) - g1) / kEps, j12 = (dot(w1.w, t2) - g2) / kEps;
    const double j21 = (dot(w2.w, t1) - g1) / kEps, j22 = (dot(w2.w, t2) - g2) / kEps;
    const double h11 = j11 - h, h22 = j22 - h, h12 = 0.5 * (j12 + j21);
    const double det = h11 * h22 - h12 * h12;
    if (!(h11 > 0.0) || !(h22 > 0.0) || !(det > 0.0)) return false;
    double d1 = -(h22 * g1 - h12 * g2) / det;
    double d2 = -(h11 * g2 - h12 * g1) / det;
    const double predicted = -0.5 * (g1 * d1 + g2 * d2);
    if (!(predicted <= 0.1 * tol)) {
      if (!(d1 * d1 + d2 * d2 < 0.09)) return false;
    } else {
      r->n = n;
      r->depth = static_cast<float>(h);
      r->pa = w.a;
      r->pb = w.b;
      r->status = 0;
      return true;
    }
    bool accepted = false;
    for (int half = 0; half < 2 && !accepted; ++half) {
      accepted = lower_support(A, B, unit_f(nd + t1 * d1 + t2 * d2), &n, &w, &h);
      d1 *= 0.5;
      d2 *= 0.5;
    }
    if (!accepted) return false;
  }
  return false;
}

/// Guards polish_smooth's answer (n, h) against a second local minimum of h elsewhere
/// (nearly concentric pairs have two, in opposite directions): every polytope face
/// whose distance (a lower bound of h over the directions it covers) is below h - tol
/// must lie within ~25 degrees of n. False: EPA goes on.
template <class Poly>
__attribute__((noinline)) bool single_basin(const Poly& P, const EpaResult& pr, double tol) {
  const D3 n = to_d(pr.n);
  const double lim = static_cast<double>(pr.depth) - tol;
  for (uint32_t k = 0; k < P.nf; ++k) {
    if (!(P.fd[k] < lim)) continue;
    if (!(P.fnx[k] * n.x + P.fny[k] * n.y + P.fnz[k] * n.z > 0.9)) return false;
  }
  return true;
}

}  // namespace

// --- GJK ---------------------------------------------------------------------------------

GjkResult gjk_cores(const Leaf& A, const Leaf& B, float margin, float scale, uint32_t max_iterations,
                    float tolerance) {
  GjkResult r;
  Simplex& s = r.simplex;
  const double tol = static_cast<double>(simd::fmax_nn(tolerance, 1e-7f)) * scale;
  const double touch = 1e-5 * scale;
  // Start from the centres' difference (A - B).
  V3 d0 = leaf_center(B) - leaf_center(A);
  if (!(len2(d0) > 0.0f)) d0 = V3{0, 1, 0};
  s.v[0] = support_diff(A, B, d0);
  s.n = 1;
  s.lambda[0] = 1.0;
  D3 v = s.v[0].w;
  double v2 = len2(v);
  uint32_t it = 0;
  bool inside = false;
  while (it < max_iterations) {
    if (v2 <= touch * touch) break;
    ++it;
    const V3 dir = to_f(v * -1.0);
    const SupportPoint w = support_diff(A, B, dir);
    const double vw = dot(v, w.w);
    const double vl = std::sqrt(v2);
    if (vw > static_cast<double>(margin) * vl + tol) {
      // Lower bound on the distance exceeds the margin: separated.
      r.separated_early = true;
      break;
    }
    if (v2 - vw <= tol * vl) break;  // converged
    bool dup = false;
    for (uint32_t i = 0; i < s.n; ++i)
      if (s.v[i].w.x == w.w.x && s.v[i].w.y == w.w.y && s.v[i].w.z == w.w.z) dup = true;
    if (dup) break;
    const Simplex prev = s;
    s.v[s.n++] = w;
    D3 nv;
    inside = solve_simplex(s, &nv);
    if (inside) {
      v = nv;
      v2 = 0.0;
      break;
    }
    const double nv2 = len2(nv);
    if (!(nv2 < v2)) {
      // No progress (rounding): keep the previous simplex.
      s = prev;
      break;
    }
    v = nv;
    v2 = nv2;
  }
  r.iterations = it;
  witnesses(s, &r.pa, &r.pb);
  if (inside || v2 <= touch * touch) {
    r.overlap = true;
    r.distance = 0.0f;
  } else {
    const double vl = std::sqrt(v2);
    r.distance = static_cast<float>(vl);
    r.n = to_f(v * (-1.0 / vl));
  }
  return r;
}

// --- EPA ---------------------------------------------------------------------------------

namespace {

/// EPA's parameters and the state it carries from the small polytope to the large one.
struct EpaRun {
  const Leaf* A = nullptr;
  const Leaf* B = nullptr;
  double tol = 0.0, polish_start = 0.0;
  float scale = 0.0f;
  uint32_t max_iterations = 0;
  bool to_convergence = false;  // a hull side: no iteration cap (epa_cores)
  bool smooth = false;          // the Newton finish is still to be tried
  uint32_t it = 0;              // expansions so far
};

/// Expands P (a closed polytope about the origin) until EPA converges, reaches the
/// cap or an inconsistent polytope, or fills P; then sets *r (epa_finish) and returns
/// true. Except when P is full and can_grow (a larger capacity to go on in): then P is
/// as after its last expansion, *r untouched, and the result false.
template <uint32_t kMaxV>
IMPACT_INLINE bool epa_expand(EpaRun& run, Polytope<kMaxV>& P, bool can_grow, EpaResult* r) {
  const Leaf& A = *run.A;
  const Leaf& B = *run.B;
  const double tol = run.tol;
  using Poly = Polytope<kMaxV>;
  bool converged = false;
  uint16_t horizon[Poly::kMaxHorizon][2];
  // Closest face (lowest index wins ties): found here, then again after every expansion.
  uint32_t best = closest_face(P);
  // Per-vertex horizon counters, zero between iterations; cleared as vertices are
  // added (not up front: most lanes use a few dozen of the capacity).
  uint16_t starts[kMaxV], ends[kMaxV];
  for (uint32_t i = 0; i < P.nv; ++i) starts[i] = ends[i] = 0;
  double sees[Poly::kMaxFaces];
  uint16_t visible[Poly::kMaxFaces];
  for (;;) {
    const EpaFace F = P.face(best);
    const SupportPoint w = support_diff(A, B, to_f(F.n));
    const double gap = dot(F.n, w.w) - F.d;
    if (gap <= tol) {
      converged = true;
      break;
    }
    if (run.smooth && gap <= run.polish_start) {
      // Near the minimum of a smooth support function: Newton finishes it (see
      // polish_smooth); on failure EPA goes on as if it had not been tried.
      run.smooth = false;
      if (polish_smooth(A, B, F.n, tol, r) && single_basin(P, *r, tol)) {
        r->iterations = run.it;
        return true;
      }
    }
    if (P.nv >= kMaxV && can_grow) return false;
    if ((run.it >= run.max_iterations && !run.to_convergence) || P.nv >= kMaxV) break;
    ++run.it;
    // Faces that see w (a contiguous pass over the SoA normals), then their horizon
    // (edges not shared by two visible faces), walked in index order. The visible
    // faces are removed by moving the last live face into each hole (highest hole
    // first), so the SoA holds only live faces and no pass moves the faces that stay.
    const uint32_t nf = P.nf;
    for (uint32_t k = 0; k < nf; ++k) sees[k] = P.fnx[k] * w.w.x + P.fny[k] * w.w.y + P.fnz[k] * w.w.z - P.fd[k];
    sees[best] = 1.0;  // the closest face always goes (w is beyond it: gap > tol)
    uint32_t nvis = 0;
    for (uint32_t k = 0; k < nf; ++k) {
      visible[nvis] = static_cast<uint16_t>(k);
      nvis += sees[k] > 0.0 ? 1u : 0u;
    }
    uint32_t nh = 0;
    bool ok = true;
    for (uint32_t j = 0; j < nvis && ok; ++j) {
      const uint32_t k = visible[j];
      const uint16_t gi[3] = {P.fi[k][0], P.fi[k][1], P.fi[k][2]};
      for (int e = 0; e < 3; ++e) {
        const uint16_t a = gi[e], b = gi[(e + 1) % 3];
        bool cancelled = false;
        for (uint32_t h = 0; h < nh; ++h) {
          if (horizon[h][0] == b && horizon[h][1] == a) {
            horizon[h][0] = horizon[nh - 1][0];
            horizon[h][1] = horizon[nh - 1][1];
            --nh;
            cancelled = true;
            break;
          }
        }
        if (!cancelled) {
          if (nh >= Poly::kMaxHorizon) {
            ok = false;
            break;
          }
          horizon[nh][0] = a;
          horizon[nh][1] = b;
          ++nh;
        }
      }
    }
    // The horizon must be one simple loop: every vertex starts and ends one edge.
    // Counted per vertex (the counters are zero between iterations).
    if (ok) {
      for (uint32_t h = 0; h < nh; ++h) {
        ++starts[horizon[h][0]];
        ++ends[horizon[h][1]];
      }
      for (uint32_t h = 0; h < nh; ++h) ok = ok && starts[horizon[h][0]] == 1 && ends[horizon[h][0]] == 1;
      for (uint32_t h = 0; h < nh; ++h) {
        starts[horizon[h][0]] = 0;
        ends[horizon[h][1]] = 0;
      }
      ok = ok && nh >= 3;
    }
    if (ok) {
      uint32_t live = nf;
      for (uint32_t j = nvis; j-- > 0;) {
        const uint32_t k = visible[j];
        --live;
        if (k != live) P.move_face(k, live);
      }
      P.nf = live;
      const uint32_t wi = P.nv++;
      P.v[wi] = w;
      starts[wi] = ends[wi] = 0;
      for (uint32_t h = 0; h < nh && ok; ++h) ok = add_face(P, horizon[h][0], horizon[h][1], wi);
      if (ok) best = closest_face(P);
    }
    if (!ok) {
      // Inconsistent topology (rounding) or capacity: stop at the last good face. The
      // removal of the visible faces may be partly applied, so report F itself.
      epa_finish(A, B, P, F, false, tol, run.scale, r);
      r->status = 2;
      r->iterations = run.it;
      return true;
    }
  }
  epa_finish(A, B, P, P.face(best), converged, tol, run.scale, r);
  r->iterations = run.it;
  return true;
}

/// The expansions of a lane that filled the small polytope go on in the large one, from
/// the same state (out of line: only these lanes pay for its ~80 KB frame). run is a
/// copy, so that the caller's stays in registers.
__attribute__((noinline)) EpaResult epa_expand_large(EpaRun run, const Polytope<kEpaSmallVerts>& small) {
  Polytope<kEpaMaxVerts> P;
  P.copy_from(small);
  EpaResult r;
  epa_expand(run, P, false, &r);
  return r;
}

}  // namespace

EpaResult epa_cores(const Leaf& A, const Leaf& B, const Simplex& start, float scale,
                    uint32_t max_iterations, float tolerance) {
  EpaResult r;
  const double eps_len = 1e-5 * scale;
  const double tol = static_cast<double>(simd::fmax_nn(tolerance, 1e-7f)) * scale;
  Simplex s = start;
  // A tetrahedron from GJK's simplex; a degenerate one drops its last vertex first.
  if (s.n == 4) {
    const D3 p0 = s.v[0].w;
    const double vol = dot(s.v[1].w - p0, cross(s.v[2].w - p0, s.v[3].w - p0));
    const double l = std::sqrt(std::max({len2(s.v[1].w - p0), len2(s.v[2].w - p0), len2(s.v[3].w - p0)}));
    if (!(std::fabs(vol) > eps_len * l * l)) s.n = 3;
  }
  if (s.n == 3) {
    const D3 n = cross(s.v[1].w - s.v[0].w, s.v[2].w - s.v[0].w);
    const double nl = std::sqrt(len2(n));
    const double l = std::sqrt(std::max(len2(s.v[1].w - s.v[0].w), len2(s.v[2].w - s.v[0].w)));
    if (!(nl > eps_len * l)) s.n = 2;  // collinear
    // Drop the middle vertex of a collinear triple: keep the two farthest apart.
    if (s.n == 2) {
      const double d01 = len2(s.v[1].w - s.v[0].w), d02 = len2(s.v[2].w - s.v[0].w),
                   d12 = len2(s.v[2].w - s.v[1].w);
      if (d02 >= d01 && d02 >= d12) s.v[1] = s.v[2];
      else if (d12 > d01 && d12 > d02) s.v[0] = s.v[2];
    }
  }
  if (s.n == 2 && !(len2(s.v[1].w - s.v[0].w) > eps_len * eps_len)) s.n = 1;
  // Blow up to 3 dimensions by supports along directions the simplex lacks.
  uint32_t dim = s.n - 1;
  if (s.n == 1) {
    const V3 dirs[6] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
    for (const V3& d : dirs) {
      const SupportPoint w = support_diff(A, B, d);
      if (len2(w.w - s.v[0].w) > eps_len * eps_len) {
        s.v[s.n++] = w;
        break;
      }
    }
    dim = s.n - 1;
  }
  if (s.n == 2) {
    const D3 e = s.v[1].w - s.v[0].w;
    const D3 eu = e * (1.0 / std::sqrt(len2(e)));
    const D3 p1 = unit_perp(e);
    const D3 p2 = cross(eu, p1);
    const D3 dirs[4] = {p1, p1 * -1.0, p2, p2 * -1.0};
    for (const D3& d : dirs) {
      const SupportPoint w = support_diff(A, B, to_f(d));
      const D3 q = w.w - s.v[0].w;
      const D3 off = q - eu * dot(q, eu);
      if (len2(off) > eps_len * eps_len) {
        s.v[s.n++] = w;
        break;
      }
    }
    dim = s.n - 1;
  }
  if (s.n == 3) {
    D3 n = cross(s.v[1].w - s.v[0].w, s.v[2].w - s.v[0].w);
    n = n * (1.0 / std::sqrt(len2(n)));
    for (double sign : {1.0, -1.0}) {
      const SupportPoint w = support_diff(A, B, to_f(n * sign));
      if (std::fabs(dot(n, w.w - s.v[0].w)) > eps_len) {
        s.v[s.n++] = w;
        break;
      }
    }
    dim = s.n - 1;
  }
  if (s.n < 4) {
    // Flat difference: zero core depth along the normal of its affine hull.
    r.status = 1;
    r.n = flat_normal(A, B, s, dim);
    r.depth = 0.0f;
    // Witnesses: GJK's closest points (the origin lies on the difference).
    witnesses(start, &r.pa, &r.pb);
    return r;
  }

  Polytope<kEpaSmallVerts> P;
  for (uint32_t i = 0; i < 4; ++i) P.v[i] = s.v[i];
  P.nv = 4;
  {
    const D3 p0 = P.v[0].w;
    const double vol = dot(P.v[1].w - p0, cross(P.v[2].w - p0, P.v[3].w - p0));
    // Orient faces outward: with vol > 0, (0,1,2) has v3 on its negative side... check.
    if (vol < 0.0) {
      add_face(P, 0, 1, 2);
      add_face(P, 0, 3, 1);
      add_face(P, 0, 2, 3);
      add_face(P, 1, 3, 2);
    } else {
      add_face(P, 0, 2, 1);
      add_face(P, 0, 1, 3);
      add_face(P, 0, 3, 2);
      add_face(P, 1, 2, 3);
    }
  }
  EpaRun run;
  run.A = &A;
  run.B = &B;
  run.tol = tol;
  run.scale = scale;
  run.max_iterations = max_iterations;
  // Both supports unique in every direction (points and ellipsoids): h is smooth and
  // its minimum, once EPA has bracketed it to kPolishStart of the scale, goes to Newton.
  run.polish_start = kPolishStart * scale;
  run.smooth = is_smooth(A.type) && is_smooth(B.type) && run.polish_start > tol;
  // The iteration cap is for curved pairs, where EPA converges linearly and the
  // descent after the cap (epa_finish) completes a minimum that h has in few places.
  // Points, segments, boxes and triangles have at most 64 support points between
  // them, so their EPA converges within the default cap. A hull side gives h a strict
  // local minimum at every face of the difference that holds the origin's projection
  // (hundreds on a round many-vertex hull around a deep core): a descent stays on the
  // face it starts from, which can be 100 degrees from the least one. Such pairs
  // expand until converged or the polytope is full: exact and finite on a polytope
  // pair, to cfg.epa_tolerance with a curved side.
  run.to_convergence = A.type == kLeafConvex || B.type == kLeafConvex;
  if (epa_expand(run, P, true, &r)) return r;
  return epa_expand_large(run, P);
}

// --- GJK + EPA, one lane -----------------------------------------------------------------

void collide_convex_lane(const Leaf& A, const Leaf& B, const NarrowConfig& cfg, LaneContact* out) {
  out->count = 0;
  out->used_epa = false;
  const float ra = core_radius(A), rb = core_radius(B);
  const float margin = ra + rb;
  const float scale = fmax_nn(leaf_size(A) + leaf_size(B), 1e-30f);
  const GjkResult g = gjk_cores(A, B, margin, scale, cfg.gjk_max_iterations, cfg.gjk_tolerance);
  out->gjk_iterations = g.iterations;
  out->epa_iterations = 0;
  if (g.separated_early) return;
  V3 n, pa, pb;
  float depth;
  if (!g.overlap) {
    if (!(g.distance < margin)) return;
    n = g.n;
    depth = margin - g.distance;
    pa = g.pa;
    pb = g.pb;
  } else {
    const EpaResult e = epa_cores(A, B, g.simplex, scale, cfg.epa_max_iterations, cfg.epa_tolerance);
    out->used_epa = true;
    out->epa_iterations = e.iterations;
    out->epa_status = e.status;
    n = e.n;
    depth = e.depth + margin;
    pa = e.pa;
    pb = e.pb;
  }
  if (!(depth > 0.0f)) return;
  contact_manifold(A, B, n, depth, pa, pb, out);
}

}  // namespace impact::kernels::cvx

namespace impact::kernels {

void collide_gjk_epa(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, Range r,
                     const NarrowConfig& cfg, LeafType ta, LeafType tb) {
  // kSimd and kScalar run the same per-lane code (see the header block).
  for (uint32_t k = r.begin; k < r.end; ++k) {
    const cvx::V3 origin{a.p[0][k], a.p[1][k], a.p[2][k]};
    const cvx::Leaf A = cvx::load_leaf(a, k, ta, &cfg.hulls, origin);
    const cvx::Leaf B = cvx::load_leaf(b, k, tb, &cfg.hulls, origin);
    cvx::LaneContact c;
    cvx::collide_convex_lane(A, B, cfg, &c);
    cvx::write_lane(out, k, c, origin);
  }
}

}  // namespace impact::kernels
