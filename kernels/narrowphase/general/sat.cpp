// Polytope pairs (box, convex hull) by the separating axis test.
//
// What: collide_sat_lane computes one lane's collision data (leaf.h: count, unit normal
// A->B, depth = the smallest separating translation, up to 4 points midway between the
// surfaces with their own depth) for two polytopes, as collide_convex_lane does with
// GJK + EPA, and through the same manifold routine (contact_manifold, face_manifold.cpp).
// Method (D. Gregorius, "The Separating Axis Test between Convex Polyhedra", GDC 2013):
// the penetration of two polytopes is the largest separation over the face normals of
// the Minkowski difference A - B: (1) the faces of A, (2) the faces of B, (3) the cross
// products of an edge of A and an edge of B whose arcs on the Gauss map cross (only
// those pairs form a face of A - B; the others are skipped). Separation along a unit
// axis n: min over B of n.x - max over A of n.x; > 0 anywhere: separated, stop.
//  0. Everything runs in A's local frame: B's vertices, face planes and edges are
//     transformed once per lane (B relative to A: far-from-origin poses keep their
//     precision, as in gjk_epa.cpp). The line of the two origins is tried first (one
//     support per side, SIMD): most separated pairs stop there.
//  1. Face queries: for kSimdWidth faces of one side at a time, the minimum over the
//     other side's vertices of n.v (the vertices broadcast one by one, two running
//     minima): O(F_A V_B + F_B V_A) / kSimdWidth steps, no horizontal reduction per face.
//     A face's separation is at most n.c - r - d (c, r: the other side's origin and the
//     radius of a ball about it inside it); the face of largest bound is evaluated
//     first, and only faces whose bound beats its separation (less the bias) follow.
//  2. Edge query: an edge's normal cone (the arc between its two face normals) lies
//     within angle theta of the bisector m (stored per hull edge, HullView). For any
//     axis n in A's edge cone, the separation is n.(p_B - p_A) with p_A on the edge and
//     p_B on B, <= n.(c_B - p_A) - r_B (c_B, r_B: B's local origin and the radius of a
//     ball about it inside B, the least face offset), and <= n.(v - p_A) for any vertex
//     v of B (the one deepest below A's best face is used: near the contact, where the
//     ball is loosest); n.w <= max(m.w, cos(theta) m.w) + sin(theta)|w|. An edge whose
//     bound is below the best face separation cannot win and is dropped (likewise for
//     B's edges with A's ball and vertex); on the bench's hulls this leaves 15 of each
//     side's 66 edges (21 with the ball alone). The remaining pairs get Gregorius's
//     Gauss map test (arc a-b of A's edge against arc (-c)-(-d) of B's: three sign tests
//     of triple products), kSimdWidth B edges per step, the pairs that pass (~4%, about
//     E_A + E_B of all pairs) compacted into a hit list; then the hits, kSimdWidth at a
//     time, get the axis e_A x e_B oriented along A's bisector and its separation (so
//     the root and the division are paid per hit, not per tested pair). Nearly
//     parallel edges (|e_A x e_B| < 1e-3 |e_A||e_B|) are skipped: their Minkowski face is
//     a sliver whose normal is within that angle of a face query's axis.
//  3. Feature choice with a bias for faces (Gregorius, Box2D): an edge axis wins only
//     if it separates more than the best face by 1e-5 of the pair's size, and B's face
//     only if it beats A's by as much (a stable choice near ties; the depth changes
//     by less than the bias). Face contact: the reference face's normal, the deepest
//     vertex of the other side as witness; edge contact: the axis, the closest points
//     of the two edge segments as witnesses. contact_manifold then clips the faces
//     (or gives the one midway point), exactly as for GJK / EPA.
// Box A against hull B (box-hull buckets) takes a route with the box in closed form
// (box_hull_lane), in A's frame: (1) the box faces' separations from the hull's
// coordinate ranges (one pass over its vertices, which also gives the origin line's
// support); (2) a hull face's separation -sum |n_i| e_i - d' (no vertex loop, kSimdWidth
// faces per step); (3) the edge pairs are hull edge x box axis i: a face of the
// Minkowski difference iff the edge's two face normals differ in sign along i (from
// the stored bisector and half-angle: m_i^2 cos^2 |d|^2 < ((d x m)_i)^2 sin^2, no
// gather), its separation n.p - sum |n_j| e_j (the box's support in closed form),
// ranked by s |s| (no root per axis); (4) the same feature rule (bias) and witnesses;
// (5) contact_manifold's reference-face choice, clipping, chords, witness join and
// reduction, done in A's frame on the hull data already there (box_hull_manifold).
// Against brute-force SAT in double it is the more exact route (sat_test.cpp
// SatBoxHull: 1e-5 L; the general route's edge axes near a face's arc end can be off
// by ~4e-5 L). The manifold is about a third of its time (measured per pair:
// docs/results.md, "Narrow phase").
// Inputs: lanes loaded by load_leaf (finite, R orthonormal, positive sizes); hulls
// with edge adjacency (HullView adj_*; sat_vertex_count() says when SAT applies).
// Outputs: as collide_convex_lane; touching (separation >= 0) gives count 0.
// Precision: float, in A's frame; separations carry an error of ~1e-7 of the
// coordinates, below the contract's tolerance. No division without a guard: no NaN for
// finite input; no allocation (stack buffers sized by the capacity limits of sat.h).
// Cost: O(F_A V_B + F_B V_A + E_A + E_B) vector steps plus the surviving edge pairs
// E'_A E'_B / kSimdWidth Gauss tests; see docs/narrowphase.md for the measured times
// and the crossover with GJK / EPA (NarrowConfig::sat_max_vertices: V_A + V_B <= 96).
// Paths: cfg.path kSimd and kScalar run this same code (as GJK / EPA do); the one-lane
// build (IMPACT_SIMD_SCALAR) runs it with kSimdWidth = 1.
#include "kernels/narrowphase/general/sat.h"

#include <cmath>
#include <initializer_list>

#include "kernels/narrowphase/general/face_manifold.h"
#include "kernels/simd/lanes.h"

namespace impact::kernels::cvx {

namespace {

using F = simd::FloatN<simd::kSimdWidth>;
constexpr uint32_t kW = simd::kSimdWidth;

constexpr uint32_t kSatMaxVerts = 512;
constexpr uint32_t kSatMaxFaces = 1024;
constexpr uint32_t kSatMaxEdges = 1536;

constexpr uint32_t kHitFlush = 256;  // the edge query's hit list is evaluated past this
constexpr uint32_t kHitShift = 11;   // a hit's key: (A candidate << 11) | B candidate
constexpr int32_t kHitMask = (1 << kHitShift) - 1;
static_assert(kSatMaxEdges + kW <= (1u << kHitShift) && (kSatMaxEdges << kHitShift) < (1u << 24),
              "hit keys: both indices fit, and the key is exact in a float");

constexpr uint32_t padded(uint32_t n) { return (n + kW - 1) / kW * kW; }
constexpr uint32_t kARec = 12, kBRec = 8;  // floats per A / B candidate-edge record

using simd::fmax_nn;
using simd::fmin_nn;

/// A polytope's data in its local frame (a hull's slice of HullView, or a box built on
/// the stack); edge indices are local.
struct Poly {
  const float *vx, *vy, *vz;
  uint32_t nv;
  const float *fnx, *fny, *fnz, *fd;
  uint32_t nf;
  const uint32_t *ev0, *ev1, *ef0, *ef1;
  const float *emx, *emy, *emz, *ecos, *esin, *epx, *epy, *epz;
  uint32_t ne;
  const float *edx = nullptr, *edy = nullptr, *edz = nullptr;  // hulls only
};

// Box topology: vertex i = (+-e0, +-e1, +-e2) with bit 0, 1, 2 of i selecting +; faces
// +x, -x, +y, -y, +z, -z; 4 edges along each axis.
constexpr uint32_t kBoxEv0[12] = {0, 2, 4, 6, 0, 1, 4, 5, 0, 1, 2, 3};
constexpr uint32_t kBoxEv1[12] = {1, 3, 5, 7, 2, 3, 6, 7, 4, 5, 6, 7};
constexpr uint32_t kBoxEf0[12] = {3, 2, 3, 2, 1, 0, 1, 0, 1, 0, 1, 0};
constexpr uint32_t kBoxEf1[12] = {5, 5, 4, 4, 5, 5, 4, 4, 3, 3, 2, 2};
constexpr float kH = 0.70710678f;
constexpr float kBoxEmx[12] = {0, 0, 0, 0, -kH, kH, -kH, kH, -kH, kH, -kH, kH};
constexpr float kBoxEmy[12] = {-kH, kH, -kH, kH, 0, 0, 0, 0, -kH, -kH, kH, kH};
constexpr float kBoxEmz[12] = {-kH, -kH, kH, kH, -kH, -kH, kH, kH, 0, 0, 0, 0};
// cos / sin of 45 degrees rounded outward (the cone still holds both face normals).
constexpr float kBoxCos[12] = {0.7071067f, 0.7071067f, 0.7071067f, 0.7071067f, 0.7071067f, 0.7071067f,
                               0.7071067f, 0.7071067f, 0.7071067f, 0.7071067f, 0.7071067f, 0.7071067f};
constexpr float kBoxSin[12] = {0.7071068f, 0.7071068f, 0.7071068f, 0.7071068f, 0.7071068f, 0.7071068f,
                               0.7071068f, 0.7071068f, 0.7071068f, 0.7071068f, 0.7071068f, 0.7071068f};
constexpr float kBoxFnx[6] = {1, -1, 0, 0, 0, 0};
constexpr float kBoxFny[6] = {0, 0, 1, -1, 0, 0};
constexpr float kBoxFnz[6] = {0, 0, 0, 0, 1, -1};

struct BoxPoly {
  float vx[8], vy[8], vz[8], fd[6], epx[12], epy[12], epz[12];
};

/// The Poly of a box or hull leaf; false when SAT does not apply to it.
bool make_poly(const Leaf& l, BoxPoly* box, Poly* p) {
  if (l.type == kLeafBox) {
    for (uint32_t i = 0; i < 8; ++i) {
      box->vx[i] = (i & 1) ? l.e[0] : -l.e[0];
      box->vy[i] = (i & 2) ? l.e[1] : -l.e[1];
      box->vz[i] = (i & 4) ? l.e[2] : -l.e[2];
    }
    for (uint32_t f = 0; f < 6; ++f) box->fd[f] = l.e[f / 2];
    for (uint32_t e = 0; e < 12; ++e) {
      box->epx[e] = box->vx[kBoxEv0[e]];
      box->epy[e] = box->vy[kBoxEv0[e]];
      box->epz[e] = box->vz[kBoxEv0[e]];
    }
    *p = Poly{box->vx,  box->vy,  box->vz,  8,        kBoxFnx,  kBoxFny,  kBoxFnz,  box->fd,  6,
              kBoxEv0,  kBoxEv1,  kBoxEf0,  kBoxEf1,  kBoxEmx,  kBoxEmy,  kBoxEmz,  kBoxCos,  kBoxSin,
              box->epx, box->epy, box->epz, 12,       nullptr,  nullptr,  nullptr};
    return true;
  }
  if (l.type != kLeafConvex || l.hulls == nullptr || l.hulls->adj_begin == nullptr) return false;
  const HullView& h = *l.hulls;
  const uint32_t vb = h.vert_begin[l.hull], fb = h.face_begin[l.hull], eb = h.adj_begin[l.hull];
  p->nv = h.vert_begin[l.hull + 1] - vb;
  p->nf = h.face_begin[l.hull + 1] - fb;
  p->ne = h.adj_begin[l.hull + 1] - eb;
  if (p->ne == 0 || p->nv > kSatMaxVerts || p->nf > kSatMaxFaces || p->ne > kSatMaxEdges) return false;
  p->vx = h.vx + vb, p->vy = h.vy + vb, p->vz = h.vz + vb;
  p->fnx = h.fnx + fb, p->fny = h.fny + fb, p->fnz = h.fnz + fb, p->fd = h.fd + fb;
  p->ev0 = h.ev0 + eb, p->ev1 = h.ev1 + eb, p->ef0 = h.ef0 + eb, p->ef1 = h.ef1 + eb;
  p->emx = h.emx + eb, p->emy = h.emy + eb, p->emz = h.emz + eb, p->ecos = h.ecos + eb, p->esin = h.esin + eb;
  p->epx = h.epx + eb, p->epy = h.epy + eb, p->epz = h.epz + eb;
  p->edx = h.edx + eb, p->edy = h.edy + eb, p->edz = h.edz + eb;
  return true;
}

/// kW floats from p[i ..] where n - i > 0 remain (the rest repeat the last one).
IMPACT_INLINE F load_tail(const float* p, uint32_t i, uint32_t n) {
  return simd::load_clamped<F>(p, i, n);
}

/// Faces in padded SoA (the face query's candidates) and their original indices.
struct FaceList {
  float nx[kSatMaxFaces + kW], ny[kSatMaxFaces + kW], nz[kSatMaxFaces + kW], d[kSatMaxFaces + kW];
  uint32_t id[kSatMaxFaces + kW];
  uint32_t n = 0;
  void pad() {
    for (uint32_t k = n; k < padded(n); ++k) nx[k] = nx[0], ny[k] = ny[0], nz[k] = nz[0], d[k] = d[0], id[k] = id[0];
  }
};

/// max over the list's faces f of (min_j n_f.v_j - d_f), and that face (original
/// index, the lowest among ties); kW faces per step, the vertices broadcast one at a
/// time (two running minima hide the min latency). L.n > 0.
float face_query(const FaceList& L, const float* vx, const float* vy, const float* vz, uint32_t nv,
                 uint32_t* out_face) {
  F best(-INFINITY), bidx(0.0f);
  for (uint32_t f = 0; f < L.n; f += kW) {
    const F NX = F::load(L.nx + f), NY = F::load(L.ny + f), NZ = F::load(L.nz + f);
    F m0(INFINITY), m1(INFINITY);
    uint32_t j = 0;
    for (; j + 2 <= nv; j += 2) {
      m0 = simd::min(m0, NX * F(vx[j]) + NY * F(vy[j]) + NZ * F(vz[j]));
      m1 = simd::min(m1, NX * F(vx[j + 1]) + NY * F(vy[j + 1]) + NZ * F(vz[j + 1]));
    }
    if (j < nv) m0 = simd::min(m0, NX * F(vx[j]) + NY * F(vy[j]) + NZ * F(vz[j]));
    const F s = simd::min(m0, m1) - F::load(L.d + f);
    float ids[kW];
    for (uint32_t k = 0; k < kW; ++k) ids[k] = static_cast<float>(L.id[f + k]);
    const auto gt = s > best;
    best = simd::select(gt, s, best);
    bidx = simd::select(gt, F::load(ids), bidx);
  }
  float bi;
  const float bs = simd::max_lowest_index(best, bidx, INFINITY, &bi);
  *out_face = static_cast<uint32_t>(bi);
  return bs;
}

/// min_j n.v_j over padded vertex arrays (nv > 0; the padding repeats a vertex).
IMPACT_INLINE float min_dot(const float* vx, const float* vy, const float* vz, uint32_t nv, float nx, float ny,
                            float nz) {
  const F NX(nx), NY(ny), NZ(nz);
  F m(INFINITY);
  for (uint32_t j = 0; j < nv; j += kW) m = simd::min(m, NX * F::load(vx + j) + NY * F::load(vy + j) + NZ * F::load(vz + j));
  float r = m.lane(0);
  for (uint32_t k = 1; k < kW; ++k) r = fmin_nn(r, m.lane(k));
  return r;
}

/// Upper bound of n.v over unit n within the cone (m, theta): max(m.v, cos m.v) + sin |v|.
IMPACT_INLINE F cone_bound(F mx, F my, F mz, F c, F s, F vx, F vy, F vz) {
  const F mv = mx * vx + my * vy + mz * vz;
  return simd::max(mv, c * mv) + s * simd::sqrt(vx * vx + vy * vy + vz * vz);
}

/// Closest points of segments p1 + s d1 and p2 + t d2, s, t in [0, 1] (Ericson 5.1.9).
void closest_segments(V3 p1, V3 d1, V3 p2, V3 d2, V3* c1, V3* c2) {
  const V3 r = p1 - p2;
  const float a = dot(d1, d1), e = dot(d2, d2), f = dot(d2, r);
  float s = 0.0f, t = 0.0f;
  const float c = dot(d1, r), b = dot(d1, d2);
  const float denom = a * e - b * b;
  if (denom > 1e-12f * a * e) s = fmin_nn(fmax_nn((b * f - c * e) / denom, 0.0f), 1.0f);
  t = e > 0.0f ? (b * s + f) / e : 0.0f;
  if (t < 0.0f) {
    t = 0.0f;
    s = a > 0.0f ? fmin_nn(fmax_nn(-c / a, 0.0f), 1.0f) : 0.0f;
  } else if (t > 1.0f) {
    t = 1.0f;
    s = a > 0.0f ? fmin_nn(fmax_nn((b - c) / a, 0.0f), 1.0f) : 0.0f;
  }
  *c1 = p1 + d1 * s;
  *c2 = p2 + d2 * t;
}

// Stack buffers of one lane (B's data in A's frame, A's vertices padded, the candidate
// faces and edges).
struct Scratch {
  float avx[kSatMaxVerts + kW], avy[kSatMaxVerts + kW], avz[kSatMaxVerts + kW];
  float bvx[kSatMaxVerts + kW], bvy[kSatMaxVerts + kW], bvz[kSatMaxVerts + kW];
  float bfx[kSatMaxFaces + kW], bfy[kSatMaxFaces + kW], bfz[kSatMaxFaces + kW], bfd[kSatMaxFaces + kW];
  float u[kSatMaxEdges + kW];  // face / edge bounds
  float tpx[kSatMaxEdges + kW], tpy[kSatMaxEdges + kW], tpz[kSatMaxEdges + kW];  // B's edge starts
  FaceList fl;
  // B's candidate edges, padded to kW: -n0 (c), -n1 (d), d x c, edge vector, first vertex.
  float cx[kSatMaxEdges + kW], cy[kSatMaxEdges + kW], cz[kSatMaxEdges + kW];
  float dx[kSatMaxEdges + kW], dy[kSatMaxEdges + kW], dz[kSatMaxEdges + kW];
  float qx[kSatMaxEdges + kW], qy[kSatMaxEdges + kW], qz[kSatMaxEdges + kW];
  // B's candidate edges again as records for the hits (simd::gather4: 16-byte loads,
  // where gathers cost ~17 cycles a 16-lane one on AMD Zen 4): edge vector, |e|^2,
  // first vertex, 0.
  alignas(16) float brec[kSatMaxEdges + kW][kBRec];
  uint32_t aedge[kSatMaxEdges + kW];
  // A's candidate edges by candidate index, records: direction, kParallel2 |e|^2; start,
  // 0; bisector, 0.
  alignas(16) float arec[kSatMaxEdges + kW][kARec];
  // The edge query's hits, keys (A candidate index << kHitShift) | B candidate index,
  // flushed past kHitFlush (one A edge appends at most kSatMaxEdges + kW).
  int32_t hit[kHitFlush + kSatMaxEdges + 2 * kW];
  uint32_t bedge[kSatMaxEdges + kW];
};

/// Copies n values into dst and pads it to kW with the last one.
IMPACT_INLINE void copy_padded(const float* src, uint32_t n, float* dst) {
  for (uint32_t i = 0; i < n; ++i) dst[i] = src[i];
  for (uint32_t i = n; i < padded(n); ++i) dst[i] = src[n - 1];
}

}  // namespace

uint32_t sat_vertex_count(const Leaf& A, const Leaf& B) {
  BoxPoly ba, bb;
  Poly pa, pb;
  if (!make_poly(A, &ba, &pa) || !make_poly(B, &bb, &pb)) return 0;
  return pa.nv + pb.nv;
}

namespace {

// Stack buffers of the box-hull route (the hull's vertices and face normals in the
// box's frame).
struct BoxHullScratch {
  float vx[kSatMaxVerts + kW], vy[kSatMaxVerts + kW], vz[kSatMaxVerts + kW];
  float fx[kSatMaxFaces + kW], fy[kSatMaxFaces + kW], fz[kSatMaxFaces + kW], fd[kSatMaxFaces + kW];
  float fo[kSatMaxFaces + kW];  // the offsets in B's frame; all padded to kW (copies of the last face)
};

// --- the box-hull route's manifold, in A's frame -------------------------------------------

/// Clip buffers for faces of up to kMaxFaceVerts (face_manifold.h). Stack only: ~27 KB per call.
constexpr uint32_t kMaxClip = 2 * kMaxFaceVerts + 8;
constexpr float kChordParallel = 1e-5f;  // as face_manifold.cpp's chord

struct LocalFace {
  V3 v[kMaxFaceVerts];
  uint32_t n = 0;
  V3 normal{0, 0, 1};
  float d = 0.0f;
  float align = -2.0f;
};

IMPACT_INLINE void chord_plane(float c, float slack, float tol, float* t_in, float* t_out) {
  if (c > kChordParallel) *t_out = fmin_nn(*t_out, slack / c);
  else if (c < -kChordParallel) *t_in = fmax_nn(*t_in, slack / c);
  else if (slack < -tol) *t_in = INFINITY;  // parallel and outside
}

/// contact_manifold (face_manifold.cpp) for box A and hull B, in A's frame (A's centre at 0,
/// B's vertices, face normals and offsets already there in S; t: B's centre): the same
/// reference face choice, clipping, chords through the reference shape and reduction,
/// without moving the hull's face or the chords' planes to the world.
void box_hull_manifold(const Leaf& A, const Leaf& B, const Poly& PB, const BoxHullScratch& S, const float t[3], V3 n,
                       float depth, V3 pa, V3 pb, LaneContact* out) {
  const auto to_world = [&](V3 x) { return A.p + A.ax[0] * x.x + A.ax[1] * x.y + A.ax[2] * x.z; };
  out->n = A.ax[0] * n.x + A.ax[1] * n.y + A.ax[2] * n.z;
  out->depth = depth;
  LocalFace fa, fb;
  {  // A's face most aligned with n (the first axis among ties)
    const float s[3] = {n.x, n.y, n.z};
    int bi = 0;
    float bs = -1.0f, sgn = 1.0f;
    for (int i = 0; i < 3; ++i) {
      if (std::fabs(s[i]) > bs) {
        bs = std::fabs(s[i]);
        bi = i;
        sgn = s[i] >= 0.0f ? 1.0f : -1.0f;
      }
    }
    const int j = (bi + 1) % 3, k = (bi + 2) % 3;
    V3 c{0, 0, 0}, u{0, 0, 0}, w{0, 0, 0}, nn{0, 0, 0};
    (bi == 0 ? c.x : bi == 1 ? c.y : c.z) = sgn * A.e[bi];
    (bi == 0 ? nn.x : bi == 1 ? nn.y : nn.z) = sgn;
    (j == 0 ? u.x : j == 1 ? u.y : u.z) = A.e[j];
    (k == 0 ? w.x : k == 1 ? w.y : w.z) = A.e[k];
    fa.n = 4;
    fa.v[0] = c + u + w, fa.v[1] = c - u + w, fa.v[2] = c - u - w, fa.v[3] = c + u - w;
    fa.normal = nn;
    fa.d = A.e[bi];
    fa.align = bs;
  }
  bool have_b = false;
  {  // B's face most aligned with -n (the first among ties)
    const HullView& h = *B.hulls;
    const uint32_t f = argmax_dot(S.fx, S.fy, S.fz, 0, PB.nf, -n.x, -n.y, -n.z);
    const uint32_t gf = h.face_begin[B.hull] + f, vbase = h.vert_begin[B.hull];
    const uint32_t vb = h.face_vert_begin[gf], ve = h.face_vert_begin[gf + 1];
    if (ve - vb <= kMaxFaceVerts && ve - vb >= 3) {
      have_b = true;
      fb.n = ve - vb;
      for (uint32_t i = vb; i < ve; ++i) {
        const uint32_t v = h.face_verts[i] - vbase;
        fb.v[i - vb] = V3{S.vx[v], S.vy[v], S.vz[v]};
      }
      fb.normal = V3{S.fx[f], S.fy[f], S.fz[f]};
      fb.d = S.fd[f];
      fb.align = -(n.x * S.fx[f] + n.y * S.fy[f] + n.z * S.fz[f]);
    }
  }
  constexpr float kMinAlign = 0.9f;
  const bool ca = fa.align >= kMinAlign, cb = have_b && fb.align >= kMinAlign;
  if (have_b && (ca || cb)) {
    const bool ref_is_a = ca && (!cb || fa.align >= fb.align);
    const LocalFace& ref = ref_is_a ? fa : fb;
    const LocalFace& inc = ref_is_a ? fb : fa;
    V3 buf0[kMaxClip], buf1[kMaxClip];
    uint32_t cnt = inc.n;
    for (uint32_t i = 0; i < cnt; ++i) buf0[i] = inc.v[i];
    V3* in = buf0;
    V3* outp = buf1;
    V3 centroid{0, 0, 0};
    for (uint32_t i = 0; i < ref.n; ++i) centroid = centroid + ref.v[i];
    centroid = centroid * (1.0f / static_cast<float>(ref.n));
    for (uint32_t e = 0; e < ref.n && cnt > 0; ++e) {
      const V3 a = ref.v[e], b = ref.v[(e + 1) % ref.n];
      V3 sn = cross(b - a, n);
      if (dot(sn, centroid - a) > 0.0f) sn = -sn;
      const float snl = len(sn);
      if (!(snl > 0.0f)) continue;
      sn = sn * (1.0f / snl);
      const float sd = dot(sn, a);
      uint32_t m = 0;
      for (uint32_t i = 0; i < cnt; ++i) {
        const V3 p = in[i], q = in[(i + 1) % cnt];
        const float dp = dot(sn, p) - sd, dq = dot(sn, q) - sd;
        if (dp <= 0.0f) outp[m++] = p;
        if ((dp < 0.0f && dq > 0.0f) || (dp > 0.0f && dq < 0.0f)) {
          const float tt = dp / (dp - dq);
          outp[m++] = p + (q - p) * tt;
        }
        if (m >= kMaxClip - 2) break;
      }
      cnt = m;
      V3* tmp = in;
      in = outp;
      outp = tmp;
    }
    const float cosn = ref_is_a ? dot(ref.normal, n) : -dot(ref.normal, n);
    V3 pts[kMaxClip + 1];
    float pd[kMaxClip + 1];
    uint32_t k = 0;
    const V3 dir = ref_is_a ? n : -n;
    for (uint32_t i = 0; i < cnt; ++i) {
      const V3 x = in[i];
      const float s = ref.d - dot(ref.normal, x);  // below the reference plane
      if (!(s > 0.0f)) continue;
      float pdepth = s / cosn;
      // The chord of the ray x + t dir through the reference shape.
      float t_in = -INFINITY, t_out = INFINITY;
      if (ref_is_a) {
        const float xs[3] = {x.x, x.y, x.z}, ds[3] = {dir.x, dir.y, dir.z};
        for (int a = 0; a < 3; ++a) {
          const float tol = 4e-6f * (A.e[a] + std::fabs(xs[a]));
          chord_plane(ds[a], A.e[a] - xs[a], tol, &t_in, &t_out);
          chord_plane(-ds[a], A.e[a] + xs[a], tol, &t_in, &t_out);
        }
      } else {
        const V3 q{x.x - t[0], x.y - t[1], x.z - t[2]};  // from B's centre
        const F DX(dir.x), DY(dir.y), DZ(dir.z), QX(q.x), QY(q.y), QZ(q.z), one(1.0f);
        F ti(-INFINITY), to(INFINITY), miss(0.0f);
        for (uint32_t f = 0; f < PB.nf; f += kW) {
          const F nx = F::load(S.fx + f), ny = F::load(S.fy + f), nz = F::load(S.fz + f);
          const F c = nx * DX + ny * DY + nz * DZ;
          const F d = F::load(S.fo + f), nq = nx * QX + ny * QY + nz * QZ;
          const F slack = d - nq;
          const auto pos = c > F(kChordParallel), neg = c < F(-kChordParallel);
          const F tc = slack / simd::select(pos | neg, c, one);
          to = simd::select(pos, simd::min(to, tc), to);
          ti = simd::select(neg, simd::max(ti, tc), ti);
          const F tol = F(4e-6f) * (simd::abs(d) + simd::abs(nq));
          miss = simd::select(simd::andnot(slack < -tol, pos | neg), one, miss);
        }
        for (uint32_t l = 0; l < kW; ++l) {
          t_out = fmin_nn(t_out, to.lane(l));
          t_in = fmax_nn(t_in, miss.lane(l) > 0.0f ? INFINITY : ti.lane(l));
        }
      }
      if (t_in > t_out + 1e-6f * std::fabs(t_out)) continue;
      pdepth = fmin_nn(pdepth, t_out);
      if (!(pdepth > 0.0f)) continue;
      pdepth = fmin_nn(pdepth, depth);
      pts[k] = x + n * (ref_is_a ? 0.5f * pdepth : -0.5f * pdepth);
      pd[k] = pdepth;
      ++k;
    }
    if (k > 0) {
      // The witnesses' midpoint joins where no clipped point carries the depth, as in
      // contact_manifold (kWitnessJoin): where pa lies in the box and pb in the hull.
      float deepest = 0.0f;
      for (uint32_t i = 0; i < k; ++i) deepest = fmax_nn(deepest, pd[i]);
      bool held = deepest < depth - kWitnessJoin * (depth + A.e[0] + A.e[1] + A.e[2]);
      const float tol = kWitnessReach * depth + 1e-6f * (A.e[0] + A.e[1] + A.e[2]);
      held = held && std::fabs(pa.x) <= A.e[0] + tol && std::fabs(pa.y) <= A.e[1] + tol &&
             std::fabs(pa.z) <= A.e[2] + tol;
      for (uint32_t f = 0; f < PB.nf && held; ++f)
        held = S.fx[f] * (pb.x - t[0]) + S.fy[f] * (pb.y - t[1]) + S.fz[f] * (pb.z - t[2]) <= S.fo[f] + tol;
      if (held) {
        pts[k] = (pa + pb) * 0.5f;
        pd[k] = depth;
        ++k;
      }
      k = reduce_manifold(pts, pd, k, n);
      out->count = k;
      for (uint32_t i = 0; i < k; ++i) {
        out->point[i] = to_world(pts[i]);
        out->pdepth[i] = pd[i];
      }
      return;
    }
  }
  // One point, midway between the witnesses (no radii).
  out->count = 1;
  out->point[0] = (to_world(pa) + to_world(pb)) * 0.5f;
  out->pdepth[0] = depth;
}

/// Box A against hull B (PB), the same test as the general route with the box's
/// structure in closed form: its faces' separations are the hull's coordinate ranges
/// in A's frame, a hull face's is -sum |n_i| e_i - d (no vertex loop), and its edge
/// directions are A's axes, so an edge pair is hull edge e x axis i: it forms a face of
/// the Minkowski difference iff e's two face normals differ in sign along axis i (the
/// crossing point on the Gauss map picks which of the four parallel box edges), and its
/// separation is n.p_e - sum |n_j| e_j (p_e: a point of e; the box's support in closed
/// form). The feature rule (bias), witnesses and manifold are the general route's.
void box_hull_lane(const Leaf& A, const Leaf& B, const Poly& PB, LaneContact* out, SatStats* stats) {
  BoxHullScratch S;
  const float e0 = A.e[0], e1 = A.e[1], e2 = A.e[2];
  float R[3][3], t[3];
  {
    const V3 d = B.p - A.p;
    for (int r = 0; r < 3; ++r) {
      t[r] = dot(d, A.ax[r]);
      for (int c = 0; c < 3; ++c) R[r][c] = dot(A.ax[r], B.ax[c]);
    }
  }
  const F r00(R[0][0]), r01(R[0][1]), r02(R[0][2]), r10(R[1][0]), r11(R[1][1]), r12(R[1][2]), r20(R[2][0]),
      r21(R[2][1]), r22(R[2][2]), tx(t[0]), ty(t[1]), tz(t[2]);
  const F E0(e0), E1(e1), E2(e2);

  // B's vertices in A's frame and their coordinate ranges: the box faces' separations.
  F lox(INFINITY), loy(INFINITY), loz(INFINITY), hix(-INFINITY), hiy(-INFINITY), hiz(-INFINITY);
  for (uint32_t j = 0; j < PB.nv; j += kW) {  // the padding repeats the last vertex
    const F x = load_tail(PB.vx, j, PB.nv), y = load_tail(PB.vy, j, PB.nv), z = load_tail(PB.vz, j, PB.nv);
    const F X = tx + r00 * x + r01 * y + r02 * z, Y = ty + r10 * x + r11 * y + r12 * z,
            Z = tz + r20 * x + r21 * y + r22 * z;
    X.store(S.vx + j), Y.store(S.vy + j), Z.store(S.vz + j);
    lox = simd::min(lox, X), loy = simd::min(loy, Y), loz = simd::min(loz, Z);
    hix = simd::max(hix, X), hiy = simd::max(hiy, Y), hiz = simd::max(hiz, Z);
  }
  float lo[3] = {lox.lane(0), loy.lane(0), loz.lane(0)}, hi[3] = {hix.lane(0), hiy.lane(0), hiz.lane(0)};
  for (uint32_t k = 1; k < kW; ++k) {
    lo[0] = fmin_nn(lo[0], lox.lane(k)), lo[1] = fmin_nn(lo[1], loy.lane(k)), lo[2] = fmin_nn(lo[2], loz.lane(k));
    hi[0] = fmax_nn(hi[0], hix.lane(k)), hi[1] = fmax_nn(hi[1], hiy.lane(k)), hi[2] = fmax_nn(hi[2], hiz.lane(k));
  }
  // Faces +x, -x, +y, -y, +z, -z (the general route's box order), the lowest index
  // among ties.
  float sa = -INFINITY;
  uint32_t fa = 0;
  for (uint32_t f = 0; f < 6; ++f) {
    const uint32_t k = f / 2;
    const float s = ((f & 1) ? -hi[k] : lo[k]) - A.e[k];
    if (s > sa) sa = s, fa = f;
  }
  if (!(sa < 0.0f)) return;
  // The line of the origins (one support of B, the box's in closed form).
  {
    const float tl2 = t[0] * t[0] + t[1] * t[1] + t[2] * t[2];
    if (tl2 > 0.0f) {
      const float il = 1.0f / std::sqrt(tl2);
      const float ux = t[0] * il, uy = t[1] * il, uz = t[2] * il;
      const float s = min_dot(S.vx, S.vy, S.vz, PB.nv, ux, uy, uz) -
                      (std::fabs(ux) * e0 + std::fabs(uy) * e1 + std::fabs(uz) * e2);
      if (s > 0.0f) return;
    }
  }
  // B's faces in A's frame: separation -sum |n_i| e_i - d' (d' = d + n.t), kW per step.
  float sb, mb;
  uint32_t fb;
  {
    F best(-INFINITY), bidx(0.0f), dmax(0.0f);
    const F lane_f = simd::lane_index<F>();
    for (uint32_t f = 0; f < PB.nf; f += kW) {
      const F x = load_tail(PB.fnx, f, PB.nf), y = load_tail(PB.fny, f, PB.nf), z = load_tail(PB.fnz, f, PB.nf);
      const F ox = r00 * x + r01 * y + r02 * z, oy = r10 * x + r11 * y + r12 * z, oz = r20 * x + r21 * y + r22 * z;
      const F d = load_tail(PB.fd, f, PB.nf);
      const F od = d + ox * tx + oy * ty + oz * tz;
      ox.store(S.fx + f), oy.store(S.fy + f), oz.store(S.fz + f), od.store(S.fd + f), d.store(S.fo + f);
      const F s = -(simd::abs(ox) * E0 + simd::abs(oy) * E1 + simd::abs(oz) * E2) - od;
      dmax = simd::max(dmax, d);
      const auto gt = s > best;
      best = simd::select(gt, s, best);
      bidx = simd::select(gt, lane_f + F(static_cast<float>(f)), bidx);
    }
    float bi;
    sb = simd::max_lowest_index(best, bidx, INFINITY, &bi);
    fb = static_cast<uint32_t>(bi);
    mb = dmax.lane(0);
    for (uint32_t k = 1; k < kW; ++k) mb = fmax_nn(mb, dmax.lane(k));
  }
  if (!(sb < 0.0f)) return;
  const float ma = fmax_nn(fmax_nn(fmax_nn(e0, e1), e2), 0.0f);
  const float bias = 1e-5f * fmax_nn(ma + mb, 1e-30f);
  const float s_face = fmax_nn(sa, sb);

  // Edge pairs: hull edge e (kW per step) x axis i. Minkowski face iff e's face normals
  // differ in sign along i; n = x_i x d_e oriented against e's bisector (outward of A);
  // ranked by s |s| (one division, no root per axis), the winner's s by one root.
  constexpr float kParallel2 = 1e-6f;  // |x_i x d|^2 < 1e-6 |d|^2: skipped (as the general route)
  F best(-INFINITY), bkey(0.0f);
  uint32_t hits = 0;
  const F zero(0.0f), par(kParallel2), lane = simd::lane_index<F>();
  const uint32_t ne = PB.ne;  // a multiple of kW (the hull store pads edge lists to 8)
  for (uint32_t e = 0; e < ne; e += kW) {
    const F lx = F::load(PB.edx + e), ly = F::load(PB.edy + e), lz = F::load(PB.edz + e);
    const F Dx = r00 * lx + r01 * ly + r02 * lz, Dy = r10 * lx + r11 * ly + r12 * lz, Dz = r20 * lx + r21 * ly + r22 * lz;
    const F qx = F::load(PB.epx + e), qy = F::load(PB.epy + e), qz = F::load(PB.epz + e);
    const F Px = tx + r00 * qx + r01 * qy + r02 * qz, Py = ty + r10 * qx + r11 * qy + r12 * qz,
            Pz = tz + r20 * qx + r21 * qy + r22 * qz;
    // The arc's end points are m cos + w sin and m cos - w sin (m: the unit bisector,
    // w = d x m / |d|, both normal to d): they differ in sign along axis i iff
    // m_i^2 cos^2 |d|^2 < (d x m)_i^2 sin^2 (cos / sin rounded outward by the store).
    const F ux = F::load(PB.emx + e), uy = F::load(PB.emy + e), uz = F::load(PB.emz + e);
    const F mx = r00 * ux + r01 * uy + r02 * uz, my = r10 * ux + r11 * uy + r12 * uz, mz = r20 * ux + r21 * uy + r22 * uz;
    const F wx = Dy * mz - Dz * my, wy = Dz * mx - Dx * mz, wz = Dx * my - Dy * mx;
    const F dl2 = Dx * Dx + Dy * Dy + Dz * Dz;
    const F co = F::load(PB.ecos + e), si = F::load(PB.esin + e);
    const F c2 = co * co * dl2, s2 = si * si;
    const F cx = mx * mx * c2, cy = my * my * c2, cz = mz * mz * c2;  // against w_i^2 s2
    const F dx = wx * wx * s2, dy = wy * wy * s2, dz = wz * wz * s2;
    const F pl = par * dl2;
    const F key0 = lane + F(static_cast<float>(e));
    // Axis x: n = (0, -Dz, Dy); y: (Dz, 0, -Dx); z: (-Dy, Dx, 0).
    const auto axis = [&](F a, F b, F ea, F eb, F pa, F pb, F ma_, F mb_, F ci, F di, uint32_t i) {
      const F l2 = a * a + b * b;
      const auto ok = (ci < di) & (l2 > pl);
      // The separation times |x_i x d| (no root), ranked by s |s| = r |r| / l2.
      const F pr = a * pa + b * pb;
      const F r = simd::select((a * ma_ + b * mb_) > zero, -pr, pr) - (simd::abs(a) * ea + simd::abs(b) * eb);
      const F s = r * simd::abs(r) / simd::select(ok, l2, F(1.0f));
      const auto gt = ok & (s > best);
      best = simd::select(gt, s, best);
      bkey = simd::select(gt, key0 + F(static_cast<float>(i * ne)), bkey);
      if (stats != nullptr)
        for (uint32_t k = 0; k < kW; ++k) hits += ok.lane(k) ? 1u : 0u;
    };
    axis(-Dz, Dy, E1, E2, Py, Pz, my, mz, cx, dx, 0);
    axis(Dz, -Dx, E0, E2, Px, Pz, mx, mz, cy, dy, 1);
    axis(-Dy, Dx, E0, E1, Px, Py, mx, my, cz, dz, 2);
  }
  float key;
  const float s_sq = simd::max_lowest_index(best, bkey, INFINITY, &key);
  const float s_edge = s_sq >= 0.0f ? std::sqrt(s_sq) : (s_sq > -INFINITY ? -std::sqrt(-s_sq) : s_sq);
  if (stats != nullptr) {
    stats->edges_a = 3;
    stats->edges_b = ne;
    stats->gauss_hits = hits;
  }
  if (!(s_edge < 0.0f)) return;

  // Feature, normal (A's frame), witnesses: the general route's rule.
  V3 n, pa_l, pb_l;
  float depth;
  int feature;
  if (s_edge > s_face + bias) {
    feature = 2;
    const uint32_t k = static_cast<uint32_t>(key);
    const uint32_t i = k / ne, e = k % ne;
    const V3 q0{PB.epx[e], PB.epy[e], PB.epz[e]}, q1{PB.vx[PB.ev1[e]], PB.vy[PB.ev1[e]], PB.vz[PB.ev1[e]]};
    const auto xf = [&](V3 q) {
      return V3{t[0] + R[0][0] * q.x + R[0][1] * q.y + R[0][2] * q.z, t[1] + R[1][0] * q.x + R[1][1] * q.y + R[1][2] * q.z,
                t[2] + R[2][0] * q.x + R[2][1] * q.y + R[2][2] * q.z};
    };
    const V3 p2 = xf(q0), d2 = xf(q1) - p2;
    V3 ax{0, 0, 0};
    (i == 0 ? ax.x : i == 1 ? ax.y : ax.z) = 1.0f;
    n = cross(ax, d2);
    n = n * (1.0f / len(n));
    const uint32_t g0 = PB.ef0[e], g1 = PB.ef1[e];
    const V3 m{S.fx[g0] + S.fx[g1], S.fy[g0] + S.fy[g1], S.fz[g0] + S.fz[g1]};
    if (dot(n, m) > 0.0f) n = -n;
    depth = -s_edge;
    // The box edge along axis i on the side of n: from -e_i to +e_i.
    V3 p1{n.x >= 0.0f ? e0 : -e0, n.y >= 0.0f ? e1 : -e1, n.z >= 0.0f ? e2 : -e2};
    (i == 0 ? p1.x : i == 1 ? p1.y : p1.z) = -A.e[i];
    const V3 d1 = ax * (2.0f * A.e[i]);
    closest_segments(p1, d1, p2, d2, &pa_l, &pb_l);
  } else if (!(sb > sa + bias)) {
    feature = 0;
    const uint32_t k = fa / 2;
    n = V3{0, 0, 0};
    (k == 0 ? n.x : k == 1 ? n.y : n.z) = (fa & 1) ? -1.0f : 1.0f;
    depth = -sa;
    const uint32_t j = argmax_dot(S.vx, S.vy, S.vz, 0, PB.nv, -n.x, -n.y, -n.z);
    pb_l = V3{S.vx[j], S.vy[j], S.vz[j]};
    pa_l = pb_l + n * depth;
  } else {
    feature = 1;
    n = V3{-S.fx[fb], -S.fy[fb], -S.fz[fb]};
    depth = -sb;
    pa_l = V3{n.x > 0.0f ? e0 : -e0, n.y > 0.0f ? e1 : -e1, n.z > 0.0f ? e2 : -e2};  // first among ties
    pb_l = pa_l - n * depth;
  }
  if (stats != nullptr) stats->feature = feature;
  box_hull_manifold(A, B, PB, S, t, n, depth, pa_l, pb_l, out);
}

}  // namespace

void collide_sat_lane(const Leaf& A, const Leaf& B, LaneContact* out, SatStats* stats) {
  out->count = 0;
  out->used_epa = false;
  out->gjk_iterations = 0;
  out->epa_iterations = 0;
  if (stats != nullptr) *stats = SatStats{};
  if (A.type == kLeafBox && B.type == kLeafConvex) {
    BoxPoly unused;
    Poly PB;
    if (!make_poly(B, &unused, &PB)) return;
    if (PB.ne % kW == 0) {
      box_hull_lane(A, B, PB, out, stats);
      return;
    }
  }
  collide_sat_general_lane(A, B, out, stats);
}

void collide_sat_general_lane(const Leaf& A, const Leaf& B, LaneContact* out, SatStats* stats) {
  out->count = 0;
  out->used_epa = false;
  out->gjk_iterations = 0;
  out->epa_iterations = 0;
  if (stats != nullptr) *stats = SatStats{};
  BoxPoly boxa, boxb;
  Poly PA, PB;
  if (!make_poly(A, &boxa, &PA) || !make_poly(B, &boxb, &PB)) return;
  Scratch S;

  // 0. B relative to A: x_A = R x_B + t.
  float R[3][3], t[3];
  {
    const V3 d = B.p - A.p;
    for (int r = 0; r < 3; ++r) {
      t[r] = dot(d, A.ax[r]);
      for (int c = 0; c < 3; ++c) R[r][c] = dot(A.ax[r], B.ax[c]);
    }
  }
  const F r00(R[0][0]), r01(R[0][1]), r02(R[0][2]), r10(R[1][0]), r11(R[1][1]), r12(R[1][2]), r20(R[2][0]),
      r21(R[2][1]), r22(R[2][2]), tx(t[0]), ty(t[1]), tz(t[2]);
  copy_padded(PA.vx, PA.nv, S.avx);
  copy_padded(PA.vy, PA.nv, S.avy);
  copy_padded(PA.vz, PA.nv, S.avz);
  for (uint32_t j = 0; j < PB.nv; j += kW) {  // the padding repeats the last vertex
    const F x = load_tail(PB.vx, j, PB.nv), y = load_tail(PB.vy, j, PB.nv), z = load_tail(PB.vz, j, PB.nv);
    (tx + r00 * x + r01 * y + r02 * z).store(S.bvx + j);
    (ty + r10 * x + r11 * y + r12 * z).store(S.bvy + j);
    (tz + r20 * x + r21 * y + r22 * z).store(S.bvz + j);
  }
  // A separated pair often separates along the line of the origins: one support per
  // side (SIMD over the vertices) proves it before any face or edge query.
  {
    const float tl2 = t[0] * t[0] + t[1] * t[1] + t[2] * t[2];
    if (tl2 > 0.0f) {
      const float il = 1.0f / std::sqrt(tl2);
      const float ux = t[0] * il, uy = t[1] * il, uz = t[2] * il;
      const float s = min_dot(S.bvx, S.bvy, S.bvz, PB.nv, ux, uy, uz) + min_dot(S.avx, S.avy, S.avz, PA.nv, -ux, -uy, -uz);
      if (s > 0.0f) return;
    }
  }
  // Balls about the local origins inside A and B (radius: the least face offset; <= 0
  // when the origin is not inside: the bounds are then off for that side); the largest
  // offsets give the pair's size for the bias.
  F fmin_a(INFINITY), fmin_b(INFINITY), fmax_a(0.0f), fmax_b(0.0f);
  for (uint32_t f = 0; f < PA.nf; f += kW) {
    const F d = load_tail(PA.fd, f, PA.nf);
    fmin_a = simd::min(fmin_a, d), fmax_a = simd::max(fmax_a, d);
  }
  for (uint32_t f = 0; f < PB.nf; f += kW) {
    const F d = load_tail(PB.fd, f, PB.nf);
    fmin_b = simd::min(fmin_b, d), fmax_b = simd::max(fmax_b, d);
  }
  float ra = fmin_a.lane(0), rb = fmin_b.lane(0), ma = fmax_a.lane(0), mb = fmax_b.lane(0);
  for (uint32_t k = 1; k < kW; ++k) {
    ra = fmin_nn(ra, fmin_a.lane(k)), rb = fmin_nn(rb, fmin_b.lane(k));
    ma = fmax_nn(ma, fmax_a.lane(k)), mb = fmax_nn(mb, fmax_b.lane(k));
  }
  const float ball_a = ra > 0.0f ? ra : -INFINITY, ball_b = rb > 0.0f ? rb : -INFINITY;
  const float scale = fmax_nn(ma + mb, 1e-30f);
  const float bias = 1e-5f * scale;

  // 1. Face queries. Bound: sep_f = min_B n_f.x - d_f <= n_f.c_B - r_B - d_f. The face of
  // largest bound on each side is evaluated first; its separation is a lower bound of
  // the answer, and only faces whose bound beats it (less the bias) are evaluated.
  uint32_t fa_seed = 0, fb_seed = 0;
  {
    F best(-INFINITY), bidx(0.0f);
    const F lane_f = simd::lane_index<F>();
    for (uint32_t f = 0; f < PA.nf; f += kW) {
      const F u = load_tail(PA.fnx, f, PA.nf) * tx + load_tail(PA.fny, f, PA.nf) * ty +
                  load_tail(PA.fnz, f, PA.nf) * tz - F(ball_b) - load_tail(PA.fd, f, PA.nf);
      u.store(S.u + f);
      const auto gt = u > best;
      best = simd::select(gt, u, best);
      bidx = simd::select(gt, lane_f + F(static_cast<float>(f)), bidx);
    }
    float bi;
    simd::max_lowest_index(best, bidx, INFINITY, &bi);
    fa_seed = static_cast<uint32_t>(bi);
  }
  float sa = min_dot(S.bvx, S.bvy, S.bvz, PB.nv, PA.fnx[fa_seed], PA.fny[fa_seed], PA.fnz[fa_seed]) - PA.fd[fa_seed];
  uint32_t fa = fa_seed;
  if (!(sa < 0.0f)) return;
  // B's faces in A's frame, their bounds (c_A = 0): -r_A - d'_g.
  {
    F best(-INFINITY), bidx(0.0f);
    const F lane_f = simd::lane_index<F>();
    for (uint32_t f = 0; f < PB.nf; f += kW) {
      const F x = load_tail(PB.fnx, f, PB.nf), y = load_tail(PB.fny, f, PB.nf), z = load_tail(PB.fnz, f, PB.nf);
      const F ox = r00 * x + r01 * y + r02 * z, oy = r10 * x + r11 * y + r12 * z, oz = r20 * x + r21 * y + r22 * z;
      const F od = load_tail(PB.fd, f, PB.nf) + ox * tx + oy * ty + oz * tz;
      ox.store(S.bfx + f), oy.store(S.bfy + f), oz.store(S.bfz + f), od.store(S.bfd + f);
      const F u = -F(ball_a) - od;
      const auto gt = u > best;
      best = simd::select(gt, u, best);
      bidx = simd::select(gt, lane_f + F(static_cast<float>(f)), bidx);
    }
    float bi;
    simd::max_lowest_index(best, bidx, INFINITY, &bi);
    fb_seed = static_cast<uint32_t>(bi);
  }
  float sb = min_dot(S.avx, S.avy, S.avz, PA.nv, S.bfx[fb_seed], S.bfy[fb_seed], S.bfz[fb_seed]) - S.bfd[fb_seed];
  uint32_t fb = fb_seed;
  if (!(sb < 0.0f)) return;
  {
    const float thr = fmax_nn(sa, sb) - bias;
    FaceList& L = S.fl;
    // Candidate indices without branches, then their planes.
    L.n = 0;
    for (uint32_t f = 0; f < PA.nf; ++f) {
      L.id[L.n] = f;
      L.n += (S.u[f] > thr && f != fa_seed) ? 1u : 0u;
    }
    for (uint32_t k = 0; k < L.n; ++k) {
      const uint32_t f = L.id[k];
      L.nx[k] = PA.fnx[f], L.ny[k] = PA.fny[f], L.nz[k] = PA.fnz[f], L.d[k] = PA.fd[f];
    }
    if (L.n > 0) {
      L.pad();
      uint32_t f;
      const float s = face_query(L, S.bvx, S.bvy, S.bvz, PB.nv, &f);
      if (s > sa || (s == sa && f < fa)) sa = s, fa = f;
      if (!(sa < 0.0f)) return;
    }
    L.n = 0;
    for (uint32_t f = 0; f < PB.nf; ++f) {
      L.id[L.n] = f;
      L.n += (-ball_a - S.bfd[f] > thr && f != fb_seed) ? 1u : 0u;
    }
    for (uint32_t k = 0; k < L.n; ++k) {
      const uint32_t f = L.id[k];
      L.nx[k] = S.bfx[f], L.ny[k] = S.bfy[f], L.nz[k] = S.bfz[f], L.d[k] = S.bfd[f];
    }
    if (L.n > 0) {
      L.pad();
      uint32_t f;
      const float s = face_query(L, S.avx, S.avy, S.avz, PA.nv, &f);
      if (s > sb || (s == sb && f < fb)) sb = s, fb = f;
      if (!(sb < 0.0f)) return;
    }
  }
  const float s_face = fmax_nn(sa, sb);

  // 2. Edge query: edges whose cone bound cannot beat the best face by the bias are
  // dropped; the rest pass the Gauss map test pairwise.
  // A second bound from one vertex of the other side (s <= n.(v_B - p_A) for any v_B in
  // B): the vertex deepest below the best face of the other side, near the contact, where
  // the ball's bound is loosest.
  const float thr = s_face + bias;
  const uint32_t wb = argmax_dot(S.bvx, S.bvy, S.bvz, 0, PB.nv, -PA.fnx[fa], -PA.fny[fa], -PA.fnz[fa]);
  const uint32_t wa = argmax_dot(S.avx, S.avy, S.avz, 0, PA.nv, -S.bfx[fb], -S.bfy[fb], -S.bfz[fb]);
  uint32_t na = 0;
  {
    const F vx(S.bvx[wb]), vy(S.bvy[wb]), vz(S.bvz[wb]);
    for (uint32_t e = 0; e < PA.ne; e += kW) {
      const F mx = load_tail(PA.emx, e, PA.ne), my = load_tail(PA.emy, e, PA.ne),
              mz = load_tail(PA.emz, e, PA.ne);
      const F c = load_tail(PA.ecos, e, PA.ne), sn = load_tail(PA.esin, e, PA.ne);
      const F px = load_tail(PA.epx, e, PA.ne), py = load_tail(PA.epy, e, PA.ne),
              pz = load_tail(PA.epz, e, PA.ne);
      const F u = simd::min(cone_bound(mx, my, mz, c, sn, tx - px, ty - py, tz - pz) - F(ball_b),
                            cone_bound(mx, my, mz, c, sn, vx - px, vy - py, vz - pz));
      u.store(S.u + e);
    }
  }
  for (uint32_t e = 0; e < PA.ne; ++e) {
    S.aedge[na] = e;
    na += S.u[e] > thr ? 1u : 0u;
  }
  {
    const F vx(S.avx[wa]), vy(S.avy[wa]), vz(S.avz[wa]);
    for (uint32_t e = 0; e < PB.ne; e += kW) {
      const F mx = load_tail(PB.emx, e, PB.ne), my = load_tail(PB.emy, e, PB.ne),
              mz = load_tail(PB.emz, e, PB.ne);
      const F x = load_tail(PB.epx, e, PB.ne), y = load_tail(PB.epy, e, PB.ne),
              z = load_tail(PB.epz, e, PB.ne);
      const F px = tx + r00 * x + r01 * y + r02 * z, py = ty + r10 * x + r11 * y + r12 * z,
              pz = tz + r20 * x + r21 * y + r22 * z;
      const F ox = r00 * mx + r01 * my + r02 * mz, oy = r10 * mx + r11 * my + r12 * mz,
              oz = r20 * mx + r21 * my + r22 * mz;
      const F c = load_tail(PB.ecos, e, PB.ne), sn = load_tail(PB.esin, e, PB.ne);
      const F u = simd::min(cone_bound(ox, oy, oz, c, sn, -px, -py, -pz) - F(ball_a),
                            cone_bound(ox, oy, oz, c, sn, vx - px, vy - py, vz - pz));
      u.store(S.u + e);
      px.store(S.tpx + e), py.store(S.tpy + e), pz.store(S.tpz + e);
    }
  }
  uint32_t nbc = 0;  // candidate indices first, without branches
  for (uint32_t e = 0; e < PB.ne; ++e) {
    S.bedge[nbc] = e;
    nbc += S.u[e] > thr ? 1u : 0u;
  }
  uint32_t nb = 0;
  for (uint32_t k = 0; k < nbc; ++k) {
    const uint32_t e = S.bedge[k];
    const uint32_t g0 = PB.ef0[e], g1 = PB.ef1[e], v1 = PB.ev1[e];
    const V3 c{-S.bfx[g0], -S.bfy[g0], -S.bfz[g0]}, d{-S.bfx[g1], -S.bfy[g1], -S.bfz[g1]};
    const V3 dxc = cross(d, c);
    const V3 p{S.tpx[e], S.tpy[e], S.tpz[e]};
    const V3 ed{S.bvx[v1] - p.x, S.bvy[v1] - p.y, S.bvz[v1] - p.z};
    S.cx[nb] = c.x, S.cy[nb] = c.y, S.cz[nb] = c.z;
    S.dx[nb] = d.x, S.dy[nb] = d.y, S.dz[nb] = d.z;
    S.qx[nb] = dxc.x, S.qy[nb] = dxc.y, S.qz[nb] = dxc.z;
    float* br = S.brec[nb];
    br[0] = ed.x, br[1] = ed.y, br[2] = ed.z, br[3] = dot(ed, ed);
    br[4] = p.x, br[5] = p.y, br[6] = p.z, br[7] = 0.0f;
    ++nb;
  }
  // Padding lanes: c = d fails the first sign test (CBA * DBA = CBA^2 >= 0). One vector
  // store per array (the arrays hold kW past any count; GCC turned the per-lane loop
  // into a memset call per array).
  {
    const F one(1.0f), zero(0.0f);
    one.store(S.cx + nb), one.store(S.dx + nb);
    for (float* row : {S.cy, S.cz, S.dy, S.dz, S.qx, S.qy, S.qz}) zero.store(row + nb);
  }
  float s_edge = -INFINITY;
  uint32_t best_a = 0, best_b = 0;
  uint32_t hits = 0;
  if (nb > 0) {
    // Two passes: (a) the Gauss map tests of every (A, B) candidate pair, kSimdWidth B
    // edges per step, the pairs that pass appended (compacted) to a hit list in key
    // order (key = (i << kHitShift) | j: exact in a float); (b) the separations of
    // the listed pairs, kSimdWidth hits per step (their edge records read by
    // simd::gather4, not 17 gathers). Only ~4% of
    // the pairs pass on the bench's hulls, so (b) replaces a root, a division and a
    // cross product per tested pair by one per hit; the list is flushed through (b)
    // when full, so the running maximum sees the keys in order: the first maximum.
    constexpr float kParallel2 = 1e-6f;  // |e_A x e_B|^2 < 1e-6 |e_A|^2 |e_B|^2: skipped
    const simd::IntN<kW> lane_i = simd::lane_ids<simd::IntN<kW>>(0);
    const F zero(0.0f);
    F best(-INFINITY), bkey(0.0f);
    for (uint32_t i = 0; i < na; ++i) {  // A's candidate edges: direction, start, bisector
      const uint32_t e = S.aedge[i], v1 = PA.ev1[e];
      const V3 pa{PA.epx[e], PA.epy[e], PA.epz[e]};
      const V3 ea = V3{PA.vx[v1], PA.vy[v1], PA.vz[v1]} - pa;
      float* ar = S.arec[i];
      ar[0] = ea.x, ar[1] = ea.y, ar[2] = ea.z, ar[3] = kParallel2 * dot(ea, ea);
      ar[4] = pa.x, ar[5] = pa.y, ar[6] = pa.z, ar[7] = 0.0f;
      ar[8] = PA.emx[e], ar[9] = PA.emy[e], ar[10] = PA.emz[e], ar[11] = 0.0f;
    }
    uint32_t nh = 0;
    auto separations = [&]() {  // (b) over hits 0 .. nh
      // The last block's padding: valid indices (a vector store: GCC made a loop a memset).
      simd::IntN<kW>(0).store(S.hit + nh);
      for (uint32_t k = 0; k < nh; k += kW) {
        const auto in = simd::IntN<kW>(static_cast<int32_t>(nh - k)) > lane_i;
        const simd::IntN<kW> hk = simd::IntN<kW>::load(S.hit + k);
        int32_t ia[kW], ib[kW];
        (hk >> kHitShift).store(ia);
        (hk & simd::IntN<kW>(kHitMask)).store(ib);
        F rea[4], rpa[4], rma[4], reb[4], rpb[4];  // the records' rows (rea[3] = apar, reb[3] = el2)
        simd::gather4(S.arec[0], kARec, ia, rea);
        simd::gather4(S.arec[0] + 4, kARec, ia, rpa);
        simd::gather4(S.arec[0] + 8, kARec, ia, rma);
        simd::gather4(S.brec[0], kBRec, ib, reb);
        simd::gather4(S.brec[0] + 4, kBRec, ib, rpb);
        const F nx = rea[1] * reb[2] - rea[2] * reb[1], ny = rea[2] * reb[0] - rea[0] * reb[2],
                nz = rea[0] * reb[1] - rea[1] * reb[0];
        const F l2 = nx * nx + ny * ny + nz * nz;
        const auto ok = in & (l2 > rea[3] * reb[3]);
        const F inv = F(1.0f) / simd::sqrt(simd::select(ok, l2, F(1.0f)));
        const F sgn = simd::select((nx * rma[0] + ny * rma[1] + nz * rma[2]) < zero, -inv, inv);
        const F s = (nx * (rpb[0] - rpa[0]) + ny * (rpb[1] - rpa[1]) + nz * (rpb[2] - rpa[2])) * sgn;
        const auto gt = ok & (s > best);
        best = simd::select(gt, s, best);
        bkey = simd::select(gt, simd::to_float(hk), bkey);
        if (stats != nullptr) hits += static_cast<uint32_t>(__builtin_popcount(simd::bits(ok)));
      }
      nh = 0;
    };
    for (uint32_t i = 0; i < na; ++i) {  // (a)
      const uint32_t e = S.aedge[i];
      const uint32_t f0 = PA.ef0[e], f1 = PA.ef1[e];
      const V3 a{PA.fnx[f0], PA.fny[f0], PA.fnz[f0]}, b{PA.fnx[f1], PA.fny[f1], PA.fnz[f1]};
      const V3 bxa = cross(b, a);
      const F BXAx(bxa.x), BXAy(bxa.y), BXAz(bxa.z), Ax(a.x), Ay(a.y), Az(a.z), Bx(b.x), By(b.y), Bz(b.z);
      const simd::IntN<kW> key_i(static_cast<int32_t>(i << kHitShift));
      for (uint32_t j = 0; j < nb; j += kW) {
        const F cx = F::load(S.cx + j), cy = F::load(S.cy + j), cz = F::load(S.cz + j);
        const F dx = F::load(S.dx + j), dy = F::load(S.dy + j), dz = F::load(S.dz + j);
        const F qx = F::load(S.qx + j), qy = F::load(S.qy + j), qz = F::load(S.qz + j);
        const F cba = cx * BXAx + cy * BXAy + cz * BXAz, dba = dx * BXAx + dy * BXAy + dz * BXAz;
        const F adc = qx * Ax + qy * Ay + qz * Az, bdc = qx * Bx + qy * By + qz * Bz;
        const uint32_t face =
            simd::bits_lt(cba * dba, zero) & simd::bits_lt(adc * bdc, zero) & simd::bits_lt(zero, cba * bdc);
        nh += simd::compact_store(S.hit + nh, key_i + lane_i + simd::IntN<kW>(static_cast<int32_t>(j)), face);
      }
      if (nh > kHitFlush) separations();
    }
    separations();
    float key;
    s_edge = simd::max_lowest_index(best, bkey, INFINITY, &key);
    if (s_edge > -INFINITY) {
      const uint32_t k = static_cast<uint32_t>(key);
      best_a = S.aedge[k >> kHitShift];
      best_b = k & kHitMask;
    }
  }
  if (stats != nullptr) {
    stats->edges_a = na;
    stats->edges_b = nb;
    stats->gauss_hits = hits;
  }
  if (!(s_edge < 0.0f)) return;

  // 3. Feature, normal (A's frame), witnesses.
  V3 n, pa_l, pb_l;
  float depth;
  int feature;
  if (s_edge > s_face + bias) {
    feature = 2;
    const uint32_t v1 = PA.ev1[best_a];
    const V3 p1{PA.epx[best_a], PA.epy[best_a], PA.epz[best_a]};
    const V3 d1 = V3{PA.vx[v1], PA.vy[v1], PA.vz[v1]} - p1;
    const uint32_t j = best_b;
    const V3 p2{S.brec[j][4], S.brec[j][5], S.brec[j][6]}, d2{S.brec[j][0], S.brec[j][1], S.brec[j][2]};
    n = cross(d1, d2);
    n = n * (1.0f / len(n));
    if (dot(n, V3{PA.emx[best_a], PA.emy[best_a], PA.emz[best_a]}) < 0.0f) n = -n;
    depth = -s_edge;
    closest_segments(p1, d1, p2, d2, &pa_l, &pb_l);
  } else if (!(sb > sa + bias)) {
    feature = 0;
    n = V3{PA.fnx[fa], PA.fny[fa], PA.fnz[fa]};
    depth = -sa;
    const uint32_t j = argmax_dot(S.bvx, S.bvy, S.bvz, 0, PB.nv, -n.x, -n.y, -n.z);
    pb_l = V3{S.bvx[j], S.bvy[j], S.bvz[j]};
    pa_l = pb_l + n * depth;
  } else {
    feature = 1;
    n = V3{-S.bfx[fb], -S.bfy[fb], -S.bfz[fb]};
    depth = -sb;
    const uint32_t i = argmax_dot(PA.vx, PA.vy, PA.vz, 0, PA.nv, n.x, n.y, n.z);
    pa_l = V3{PA.vx[i], PA.vy[i], PA.vz[i]};
    pb_l = pa_l - n * depth;
  }
  if (stats != nullptr) stats->feature = feature;
  const auto to_world = [&](V3 x) { return A.p + A.ax[0] * x.x + A.ax[1] * x.y + A.ax[2] * x.z; };
  const V3 nw = A.ax[0] * n.x + A.ax[1] * n.y + A.ax[2] * n.z;
  contact_manifold(A, B, nw, depth, to_world(pa_l), to_world(pb_l), out);
}

}  // namespace impact::kernels::cvx
