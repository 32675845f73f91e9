// Box (A) against box (B): a manifold of up to 4 points, vectorised across pairs (one
// lane = one pair).
//
// Inputs: LeafSoA lanes per leaf.h (boxes: p, R, half extents e0..e2; the AABB proxy
// is a box with R = I). Outputs: ManifoldSoA lanes of the Range, point slots 0..3.
// box-box (separating-axis test, then clipping; Gottschalk's OBB test, Ericson 4.4.1,
// and the reference/incident-face manifold of Box2D / Bullet / ODE dBoxBox):
//   1. SAT over 15 axes in A's frame: 3 + 3 face normals and the 9 edge cross
//      products a_i x b_j. A cross product is skipped where |a_i x b_j| < 1e-6 (the
//      axes are unit, so the threshold is relative): it is then within 1e-6 rad of
//      parallel and the face axes decide. Its components come straight from the
//      rotation B->A (no 1 - c^2 cancellation), so near-parallel edges, needles and
//      pancakes keep their precision. Overlap per axis is computed on the normalised
//      axis; separated (or exactly touching) on any axis -> count 0.
//   2. The axis of least overlap, with a tie tolerance so resting contacts do not
//      flip: a B face beats an A face, and an edge beats the best face, only when
//      shallower by more than tie = 1e-5 * overlap + 1e-6 * (sum of all extents);
//      an edge axis also by its own rounding error, ~2e-7 * (extents + |t|) / |a_i x
//      b_j| (its components lose relative precision as the edges become parallel).
//      So the depth is the true minimum to ~1e-5 relative. Lanes where that band
//      decided (an edge under the face limit lost only to it), or where a winning edge
//      axis's band exceeds the tie tolerance, are redone in double (box_box_sat_double:
//      near-parallel edges of long boxes, where float cannot rank the axes or place the
//      edges' crossing); rare, and a lane's result still depends only on its inputs.
//   3. Face axis: the reference face (on the box owning the axis) and the incident
//      face (the other box's face most anti-parallel to it). Their intersection in
//      the reference face's frame is found without a variable-length polygon: its
//      vertices are among 24 fixed candidates - the 4 incident corners inside the
//      reference rectangle, the 4 rectangle corners inside the incident
//      parallelogram, and the 16 crossings of incident edges with rectangle edges -
//      each computed with a validity mask (the Sutherland-Hodgman result, branch-free).
//      Candidates below the reference face are reduced to at most 4: the deepest,
//      then the farthest from it, then the two of largest area on either side of that
//      diagonal. Each point lies midway between the incident surface and the
//      reference face; pdepth is its own depth.
//   4. Edge axis: one point midway between the closest points of the two edges.
//   n points from A to B. All arithmetic relative to A's centre.
// Preconditions: finite inputs, positive half extents, orthonormal R.
// Cost: SAT ~250 flops; the face manifold ~700 flops. The SIMD path runs the SAT block
// by block, queues the lanes whose face axis won (FaceQueue, chunks of 32 blocks: the
// partly filled last face block of a chunk pads about W / 2 lanes, a few % of ~15 W) and
// clips only those, W to a block (inputs gathered by pair index, points scattered
// back), so separated and edge lanes cost no clipping; a lane's arithmetic is the
// same wherever it lands, so the output bytes do not depend on its neighbours.
// reduce4 picks by max/min trees over index-tagged keys (no select chain).
#include <algorithm>
#include <cmath>
#include <cstdint>

#include "kernels/narrowphase/pair_kernels.h"
#include "kernels/narrowphase/lanes/block_driver.h"
#include "kernels/narrowphase/lanes/lane_geometry.h"
#include "kernels/narrowphase/lanes/lane_io.h"
#include "kernels/narrowphase/lanes/live_lanes.h"
#include "kernels/narrowphase/lanes/manifold_reduce.h"

namespace impact::kernels {
namespace {

using namespace prim;  // NOLINT: lane helpers of this kernel family
using simd::cross;
using simd::dot;
using simd::length_sq;

inline constexpr float kTieRel = 1e-5f;       // tie tolerance, relative to the overlap
inline constexpr float kTieSize = 1e-6f;      // tie tolerance floor, relative to the boxes' size
inline constexpr float kEdgeRound = 2e-7f;    // edge axis rounding, relative to size / |a_i x b_j|
inline constexpr float kEdgeSkipSq = 1e-12f;  // |a_i x b_j|^2 below this: skip the axis
inline constexpr float kPointRel = 1e-5f;     // edge contact point accuracy, relative to size

template <class F>
using L4 = Lanes<F, 4>;

/// Lanes of up to kChunk consecutive pairs whose face manifold is still to be computed
/// (the SIMD path computes the SAT for every lane, then the costly face clipping only
/// for these, W at a time: separated and edge lanes no longer ride along).
struct FaceQueue {
  static constexpr uint32_t kChunk = 32 * simd::kPairWidth;
  static constexpr uint32_t kCap = kChunk + simd::kPairWidth;  // room to pad the last block
  int32_t idx[kCap];
  float axis[kCap], best[kCap], nx[kCap], ny[kCap], nz[kCap];
  uint32_t n = 0;
  void push(uint32_t i, float ax, float b, float x, float y, float z) {
    idx[n] = static_cast<int32_t>(i), axis[n] = ax, best[n] = b, nx[n] = x, ny[n] = y, nz[n] = z;
    ++n;
  }
  void copy(uint32_t from, uint32_t to) {
    idx[to] = idx[from], axis[to] = axis[from], best[to] = best[from];
    nx[to] = nx[from], ny[to] = ny[from], nz[to] = nz[from];
  }
};

// ---------------------------------------------------------------------------------------
// box - box
// ---------------------------------------------------------------------------------------

/// Step 1's result for one lane.
struct BoxSat {
  float best, min_all, axis;
  float edge_l[3];  // the winning edge axis in A's frame, unit
  float point[3];   // edge axis: step 4's contact point, relative to A's centre
};

/// closest_segment_segment (lanes/lane_geometry.h) in double, for directions ua, ub that are unit
/// only to float precision (a box's float columns): the terms in |ua|^2 and |ub|^2 are
/// kept, because for near-parallel edges the crossing moves by (|t| * 1e-7) / |ua x ub|^2
/// when they are dropped (100 m needles 1.7e-4 rad apart, t ~ 58 m: the crossing moved
/// ~160 m and the contact point landed off both boxes; found at IMPACT_TEST_INTENSITY 30).
void closest_segments_double(const double pa[3], const double ua[3], double ha, const double pb[3],
                             const double ub[3], double hb, double* s_out, double* t_out) {
  const double r[3] = {pa[0] - pb[0], pa[1] - pb[1], pa[2] - pb[2]};
  const double aa = ua[0] * ua[0] + ua[1] * ua[1] + ua[2] * ua[2];
  const double bb = ub[0] * ub[0] + ub[1] * ub[1] + ub[2] * ub[2];
  const double b = ua[0] * ub[0] + ua[1] * ub[1] + ua[2] * ub[2];
  const double c = ua[0] * r[0] + ua[1] * r[1] + ua[2] * r[2];
  const double f = ub[0] * r[0] + ub[1] * r[1] + ub[2] * r[2];
  const double x[3] = {ua[1] * ub[2] - ua[2] * ub[1], ua[2] * ub[0] - ua[0] * ub[2], ua[0] * ub[1] - ua[1] * ub[0]};
  const double denom = x[0] * x[0] + x[1] * x[1] + x[2] * x[2];  // aa bb - b^2, no cancellation
  double s;
  if (denom < 1e-20) {
    // Parallel: the middle of [-ha, ha] and B's projection onto A's line.
    const double ext = std::fabs(b) * hb;
    const double lo = std::max(-ha, (-c - ext) / aa), hi = std::min(ha, (-c + ext) / aa);
    s = std::clamp(0.5 * (lo + hi), -ha, ha);
  } else {
    s = std::clamp((b * f - c * bb) / denom, -ha, ha);
  }
  const double t_raw = (b * s + f) / bb;
  const double t = std::clamp(t_raw, -hb, hb);
  if (t != t_raw) s = std::clamp((b * t - c) / aa, -ha, ha);
  *s_out = s;
  *t_out = t;
}

/// Steps 1 and 4 for one pair in double, from its float inputs (world frame: columns
/// a_i, b_j of the rotations, t = B's centre - A's). Run on the lanes where the float SAT
/// could not decide (see box_box_block): near-parallel edges of long boxes, where the
/// float overlap of the edge axis is off by up to ~(longest extent) * 1e-7 / |a_i x b_j|
/// and the true minimum can be that edge. In double the axes a_i x b_j carry ~1e-16
/// relative error; the same tie rules apply, with a band for the inputs' own precision.
/// Products of floats are exact in double, so the result depends only on the inputs.
__attribute__((noinline)) BoxSat box_box_sat_double(const double t[3], const double A[3][3], const double B[3][3],
                                            const double eA[3], const double eB[3]) {
  auto dot3 = [](const double* u, const double* v) { return u[0] * v[0] + u[1] * v[1] + u[2] * v[2]; };
  double AB[3][3];
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) AB[i][j] = std::fabs(dot3(A[i], B[j]));
  double best = 3.0e38, min_all = 3.0e38;
  int axis = 0;
  for (int i = 0; i < 3; ++i) {
    const double o = eA[i] + eB[0] * AB[i][0] + eB[1] * AB[i][1] + eB[2] * AB[i][2] - std::fabs(dot3(t, A[i]));
    if (o < best) best = o, axis = i;
  }
  min_all = best;
  const double size = eA[0] + eA[1] + eA[2] + eB[0] + eB[1] + eB[2];
  const double tie_floor = double(kTieSize) * size;
  const double lim_a = best - (double(kTieRel) * std::fabs(best) + tie_floor);
  for (int j = 0; j < 3; ++j) {
    const double o = eB[j] + eA[0] * AB[0][j] + eA[1] * AB[1][j] + eA[2] * AB[2][j] - std::fabs(dot3(t, B[j]));
    min_all = std::min(min_all, o);
    if (o < lim_a && o < best) best = o, axis = 3 + j;
  }
  const double lim_face = best - (double(kTieRel) * std::fabs(best) + tie_floor);
  // The axes are exact to ~1e-16 here, but the boxes themselves are only known to the
  // inputs' float precision (unit columns rounded to ~6e-8: corners move by that times
  // the extents), so an edge must still beat the faces by more than that to win.
  const double edge_round = double(kEdgeRound) * (size + std::fabs(t[0]) + std::fabs(t[1]) + std::fabs(t[2]));
  double el[3] = {0.0, 0.0, 0.0}, lw[3] = {0.0, 0.0, 0.0};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      const double l[3] = {A[i][1] * B[j][2] - A[i][2] * B[j][1], A[i][2] * B[j][0] - A[i][0] * B[j][2],
                           A[i][0] * B[j][1] - A[i][1] * B[j][0]};
      const double l2 = dot3(l, l);
      if (!(l2 > double(kEdgeSkipSq))) continue;
      const double len = std::sqrt(l2);
      double r = 0.0;
      for (int m = 0; m < 3; ++m) r += eA[m] * std::fabs(dot3(A[m], l)) + eB[m] * std::fabs(dot3(B[m], l));
      const double o = (r - std::fabs(dot3(t, l))) / len;
      min_all = std::min(min_all, o);
      if (o < lim_face - edge_round && o < best) {
        best = o, axis = 6 + 3 * i + j;
        for (int m = 0; m < 3; ++m) el[m] = dot3(A[m], l) / len, lw[m] = l[m] / len;
      }
    }
  double x[3] = {0.0, 0.0, 0.0};
  if (axis >= 6) {
    // Step 4 in double: the edges' closest points are as ill-conditioned as the axis
    // (the crossing of near-parallel edges moves by |t| * 1e-7 / |a_i x b_j| in float).
    const int ei = (axis - 6) / 3, ej = (axis - 6) % 3;
    const double sg = dot3(lw, t) >= 0.0 ? 1.0 : -1.0;
    const double n[3] = {sg * lw[0], sg * lw[1], sg * lw[2]};
    double va[3] = {0.0, 0.0, 0.0}, vb[3] = {t[0], t[1], t[2]};
    for (int m = 0; m < 3; ++m) {
      const double sa = m == ei ? 0.0 : (dot3(n, A[m]) >= 0.0 ? eA[m] : -eA[m]);
      const double sb = m == ej ? 0.0 : (dot3(n, B[m]) >= 0.0 ? -eB[m] : eB[m]);
      for (int c = 0; c < 3; ++c) va[c] += A[m][c] * sa, vb[c] += B[m][c] * sb;
    }
    double s, u;
    closest_segments_double(va, A[ei], eA[ei], vb, B[ej], eB[ej], &s, &u);
    for (int c = 0; c < 3; ++c) x[c] = 0.5 * (va[c] + s * A[ei][c] + vb[c] + u * B[ej][c]);
  }
  return BoxSat{static_cast<float>(best),
                static_cast<float>(min_all),
                static_cast<float>(axis),
                {static_cast<float>(el[0]), static_cast<float>(el[1]), static_cast<float>(el[2])},
                {static_cast<float>(x[0]), static_cast<float>(x[1]), static_cast<float>(x[2])}};
}

/// Step 1's state of a block.
template <class F>
struct BoxSatLanes {
  F best, min_all, axis;
  V3<F> edge_l;
  V3<F> point;  // redone lanes with an edge axis: the contact point
};

/// box_box_sat_double on the lanes in `redo`, the others kept. Inputs by value and the
/// state through a copy (*io): references to the caller's lanes would make them escape
/// and live in memory on the hot path.
template <class F>
__attribute__((noinline)) void box_box_redo_lanes(typename F::Mask redo, V3<F> t, M3<F> ra, M3<F> rb, V3<F> ea,
                                                  V3<F> eb, BoxSatLanes<F>* io) {
  BoxSatLanes<F>& s = *io;
  constexpr uint32_t W = F::kWidth;
  float b[W], mn[W], ax[W], lx[W], ly[W], lz[W], px[W] = {}, py[W] = {}, pz[W] = {};
  s.best.store(b), s.min_all.store(mn), s.axis.store(ax);
  s.edge_l.x.store(lx), s.edge_l.y.store(ly), s.edge_l.z.store(lz);
  for (uint32_t i = 0; i < W; ++i) {
    if (!redo.lane(i)) continue;
    const double tt[3] = {t.x.lane(i), t.y.lane(i), t.z.lane(i)};
    const double e1[3] = {ea.x.lane(i), ea.y.lane(i), ea.z.lane(i)};
    const double e2[3] = {eb.x.lane(i), eb.y.lane(i), eb.z.lane(i)};
    double A[3][3], B[3][3];
    for (int c = 0; c < 3; ++c) {
      A[c][0] = ra.c[c].x.lane(i), A[c][1] = ra.c[c].y.lane(i), A[c][2] = ra.c[c].z.lane(i);
      B[c][0] = rb.c[c].x.lane(i), B[c][1] = rb.c[c].y.lane(i), B[c][2] = rb.c[c].z.lane(i);
    }
    const BoxSat r = box_box_sat_double(tt, A, B, e1, e2);
    b[i] = r.best, mn[i] = r.min_all, ax[i] = r.axis;
    lx[i] = r.edge_l[0], ly[i] = r.edge_l[1], lz[i] = r.edge_l[2];
    px[i] = r.point[0], py[i] = r.point[1], pz[i] = r.point[2];
  }
  s = BoxSatLanes<F>{F::load(b), F::load(mn), F::load(ax), V3<F>{F::load(lx), F::load(ly), F::load(lz)},
                     V3<F>{F::load(px), F::load(py), F::load(pz)}};
}

/// Step 3 of box-box for the lanes in `face` (a face axis won): the clipped manifold
/// into m's points (relative to A's centre), pdepth and count. t = B's centre - A's.
template <class F>
IMPACT_INLINE void box_box_face(const V3<F>& t, const M3<F>& ra, const M3<F>& rb, const F (&eA)[3], const F (&eB)[3],
                                F axis, const V3<F>& n, F best, typename F::Mask face, L4<F>& m) {
  using Mask = typename F::Mask;
  using Int = typename F::Int;
  const F zero(0.0f), one(1.0f);
  const Mask face_a = axis < F(3.0f);
    // reference box: A for A's face axes, B for B's
  const F fk = select(face_a, axis, axis - F(3.0f));  // face axis index 0..2
  const V3<F> cr = select(face_a, V3<F>{zero, zero, zero}, t);
  const V3<F> rc0 = select(face_a, ra.c[0], rb.c[0]), rc1 = select(face_a, ra.c[1], rb.c[1]),
              rc2 = select(face_a, ra.c[2], rb.c[2]);
  const F rh0 = select(face_a, eA[0], eB[0]), rh1 = select(face_a, eA[1], eB[1]), rh2 = select(face_a, eA[2], eB[2]);
  const V3<F> ic = select(face_a, t, V3<F>{zero, zero, zero});
  const V3<F> ic0 = select(face_a, rb.c[0], ra.c[0]), ic1 = select(face_a, rb.c[1], ra.c[1]),
              ic2 = select(face_a, rb.c[2], ra.c[2]);
  const F ih0 = select(face_a, eB[0], eA[0]), ih1 = select(face_a, eB[1], eA[1]), ih2 = select(face_a, eB[2], eA[2]);
  // outward normal of the reference face, towards the incident box
  const V3<F> mref = select(face_a, n, -n);
  const V3<F> u1 = pick3(fk, rc1, rc2, rc0), u2 = pick3(fk, rc2, rc0, rc1);
  const F w1 = pick3(fk, rh1, rh2, rh0), w2 = pick3(fk, rh2, rh0, rh1), wk = pick3(fk, rh0, rh1, rh2);
  const V3<F> cf = madd(cr, wk, mref);  // reference face centre
  // incident face: most anti-parallel to mref
  const F d0 = dot(ic0, mref), d1 = dot(ic1, mref), d2 = dot(ic2, mref);
  const F a0 = abs(d0), a1 = abs(d1), a2 = abs(d2);
  const Mask j0 = (a0 >= a1) & (a0 >= a2);
  const Mask j1 = andnot(a1 >= a2, j0);
  const F fj = select(j0, zero, select(j1, one, F(2.0f)));
  const V3<F> inrm = pick3(fj, ic0, ic1, ic2);
  const F sgn = -simd::sign_nonneg(pick3(fj, d0, d1, d2));
  const V3<F> icen = madd(ic, sgn * pick3(fj, ih0, ih1, ih2), inrm);
  const V3<F> T1 = pick3(fj, ic1, ic2, ic0) * pick3(fj, ih1, ih2, ih0);
  const V3<F> T2 = pick3(fj, ic2, ic0, ic1) * pick3(fj, ih2, ih0, ih1);
  // incident face in the reference face's frame (x, y in the face, z along mref)
  const V3<F> dc = icen - cf;
  const F xc = dot(dc, u1), yc = dot(dc, u2), zc = dot(dc, mref);
  const F ax1 = dot(T1, u1), ay1 = dot(T1, u2), az1 = dot(T1, mref);
  const F ax2 = dot(T2, u1), ay2 = dot(T2, u2), az2 = dot(T2, mref);
  const F scale = w1 + w2;
  const F tol_in = F(1e-6f) * scale;
  const F one_in(1.0f + 1e-6f);

  constexpr int M = 24;
  F cx[M], cy[M], cz[M];
  Mask cv[M];
  int q = 0;
  // (1) incident corners inside the rectangle
  for (int s1 = -1; s1 <= 1; s1 += 2)
    for (int s2 = -1; s2 <= 1; s2 += 2) {
      const F f1(static_cast<float>(s1)), f2(static_cast<float>(s2));
      cx[q] = xc + f1 * ax1 + f2 * ax2;
      cy[q] = yc + f1 * ay1 + f2 * ay2;
      cz[q] = zc + f1 * az1 + f2 * az2;
      cv[q] = (abs(cx[q]) <= w1 + tol_in) & (abs(cy[q]) <= w2 + tol_in);
      ++q;
    }
  // (2) rectangle corners inside the incident parallelogram (alpha, beta in [-1, 1])
  const F det = ax1 * ay2 - ax2 * ay1;
  const Mask det_ok = abs(det) > F(1e-12f) * scale * scale;
  const F inv_det = one / select(det_ok, det, one);
  for (int s1 = -1; s1 <= 1; s1 += 2)
    for (int s2 = -1; s2 <= 1; s2 += 2) {
      const F X = F(static_cast<float>(s1)) * w1, Y = F(static_cast<float>(s2)) * w2;
      const F rx = X - xc, ry = Y - yc;
      const F al = (rx * ay2 - ax2 * ry) * inv_det;
      const F be = (ax1 * ry - ay1 * rx) * inv_det;
      cx[q] = X;
      cy[q] = Y;
      cz[q] = zc + al * az1 + be * az2;
      cv[q] = det_ok & (abs(al) <= one_in) & (abs(be) <= one_in);
      ++q;
    }
  // (3) incident edges crossing rectangle edges. Edge (s, param p): point =
  // centre + s*E_fixed + p*E_run, p in [-1, 1]; lines x = +-w1 and y = +-w2.
  auto crossings = [&](F fx, F fy, F fz, F rx, F ry, F rz) {
    const Mask okx = abs(rx) > F(1e-20f), oky = abs(ry) > F(1e-20f);
    const F irx = one / select(okx, rx, one), iry = one / select(oky, ry, one);
    for (int s = -1; s <= 1; s += 2) {
      const F fs(static_cast<float>(s));
      const F bx = xc + fs * fx, by = yc + fs * fy, bz = zc + fs * fz;
      for (int side = -1; side <= 1; side += 2) {
        const F sd(static_cast<float>(side));
        {  // x = side * w1
          const F p = (sd * w1 - bx) * irx;
          cx[q] = sd * w1;
          cy[q] = by + p * ry;
          cz[q] = bz + p * rz;
          cv[q] = okx & (abs(p) <= one_in) & (abs(cy[q]) <= w2 + tol_in);
          ++q;
        }
        {  // y = side * w2
          const F p = (sd * w2 - by) * iry;
          cx[q] = bx + p * rx;
          cy[q] = sd * w2;
          cz[q] = bz + p * rz;
          cv[q] = oky & (abs(p) <= one_in) & (abs(cx[q]) <= w1 + tol_in);
          ++q;
        }
      }
    }
  };
  crossings(ax1, ay1, az1, ax2, ay2, az2);  // edges at +-T1, running along T2
  crossings(ax2, ay2, az2, ax1, ay1, az1);  // edges at +-T2, running along T1
  // keep those below the reference face
  F cd[M];
  for (int i = 0; i < M; ++i) {
    cd[i] = -cz[i];
    cv[i] = cv[i] & (cd[i] > zero);
  }
  F ox[4], oy[4], od[4];
  Int cnt;
  reduce4<F, M>(cx, cy, cd, cv, F(1e-5f) * scale, ox, oy, od, cnt);
  for (int i = 0; i < 4; ++i) {
    // midway between the incident point (height -od) and the reference face (0)
    const V3<F> p = madd(madd(madd(cf, ox[i], u1), oy[i], u2), F(-0.5f) * od[i], mref);
    m.point[i] = select(face, p, m.point[i]);
    m.pdepth[i] = select(face, min(od[i], best), m.pdepth[i]);
  }
  m.count = select(face, cnt, m.count);
}

template <class F, bool Compact = false>
IMPACT_INLINE void box_box_block(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, uint32_t k,
                                  FaceQueue* queue = nullptr, uint32_t base = 0, uint32_t lim = 0) {
  using Mask = typename F::Mask;
  using Int = typename F::Int;
  const F zero(0.0f), one(1.0f), half(0.5f);
  const V3<F> pa = load_p<F>(a, k);
  const V3<F> t = load_p<F>(b, k) - pa;
  const M3<F> ra = load_r<F>(a, k), rb = load_r<F>(b, k);
  const V3<F> ea = load_e<F>(a, k), eb = load_e<F>(b, k);
  const F eA[3] = {ea.x, ea.y, ea.z}, eB[3] = {eb.x, eb.y, eb.z};

  // --- 1. SAT in A's frame ---
  F R[3][3], AR[3][3];
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      R[i][j] = dot(ra.c[i], rb.c[j]);
      AR[i][j] = abs(R[i][j]);
    }
  const V3<F> ta = ra.apply_t(t);
  const F tA[3] = {ta.x, ta.y, ta.z};
  const V3<F> tb = rb.apply_t(t);
  const F tB[3] = {tb.x, tb.y, tb.z};

  F best(3.0e38f), min_all(3.0e38f);
  F axis(0.0f);  // 0..2 A face, 3..5 B face, 6 + 3i + j edge
  for (int i = 0; i < 3; ++i) {
    const F o = eA[i] + eB[0] * AR[i][0] + eB[1] * AR[i][1] + eB[2] * AR[i][2] - abs(tA[i]);
    const Mask take = o < best;
    best = select(take, o, best);
    axis = select(take, F(static_cast<float>(i)), axis);
  }
  min_all = best;
  const F size = eA[0] + eA[1] + eA[2] + eB[0] + eB[1] + eB[2];
  const F tie_floor = F(kTieSize) * size;
  {
    const F best_a = best;
    const F lim_a = best_a - mul_add(F(kTieRel), abs(best_a), tie_floor);
    for (int j = 0; j < 3; ++j) {
      const F o = eB[j] + eA[0] * AR[0][j] + eA[1] * AR[1][j] + eA[2] * AR[2][j] - abs(tB[j]);
      min_all = min(min_all, o);
      const Mask take = (o < lim_a) & (o < best);
      best = select(take, o, best);
      axis = select(take, F(static_cast<float>(3 + j)), axis);
    }
  }
  const F best_face = best;
  const F lim_face = best_face - mul_add(F(kTieRel), abs(best_face), tie_floor);
  const F edge_round = F(kEdgeRound) * (size + abs(ta.x) + abs(ta.y) + abs(ta.z));
  V3<F> edge_l{zero, zero, zero};  // the winning edge axis in A's frame (normalised)
  F min_edge(3.0e38f);              // the smallest edge overlap, rounding band ignored
  F edge_len(1.0f);                 // |a_i x b_j| of the winning edge axis
  // Unrolled: l's components and the axis constants then stay in registers.
#pragma GCC unroll 3
  for (int i = 0; i < 3; ++i) {
    const int i1 = (i + 1) % 3, i2 = (i + 2) % 3;
#pragma GCC unroll 3
    for (int j = 0; j < 3; ++j) {
      // L = e_i x R[:, j] in A's frame: L_i = 0, L_i1 = -R[i2][j], L_i2 = R[i1][j]
      F l[3];
      l[i] = zero;
      l[i1] = -R[i2][j];
      l[i2] = R[i1][j];
      const F l2 = l[i1] * l[i1] + l[i2] * l[i2];
      const Mask ok = l2 > F(kEdgeSkipSq);
      const F len = sqrt(select(ok, l2, one));
      const F ra_ = eA[i1] * abs(l[i1]) + eA[i2] * abs(l[i2]);
      F rb_ = zero;
      for (int m = 0; m < 3; ++m) rb_ += eB[m] * abs(l[0] * R[0][m] + l[1] * R[1][m] + l[2] * R[2][m]);
      const F tl = l[0] * tA[0] + l[1] * tA[1] + l[2] * tA[2];
      const F o = (ra_ + rb_ - abs(tl)) / len;
      min_all = select(ok, min(min_all, o), min_all);
      min_edge = select(ok, min(min_edge, o), min_edge);
      const F inv = one / len;
      const Mask take = ok & (o < lim_face - edge_round * inv) & (o < best);
      best = select(take, o, best);
      axis = select(take, F(static_cast<float>(6 + 3 * i + j)), axis);
      edge_l = select(take, V3<F>{l[0] * inv, l[1] * inv, l[2] * inv}, edge_l);
      edge_len = select(take, len, edge_len);
    }
  }
  // Lanes float cannot settle, redone in double: a face won, but an edge axis came under
  // the face limit and lost only to its rounding band; or an edge axis won (beating the
  // faces by more than its band, so that choice stands) whose band exceeds 1e-5 of
  // the boxes' size: its contact point, the crossing of nearly parallel edges of long
  // boxes, slides by about a third of the band.
  const Mask redo = ((min_edge < lim_face) & (axis < F(6.0f))) |
                    ((axis >= F(6.0f)) & (edge_round > edge_len * (F(kPointRel) * size)));
  V3<F> redo_point{zero, zero, zero};
  if (simd::any(redo)) {
    BoxSatLanes<F> r{best, min_all, axis, edge_l, redo_point};
    box_box_redo_lanes(redo, t, ra, rb, ea, eb, &r);
    best = r.best, min_all = r.min_all, axis = r.axis, edge_l = r.edge_l, redo_point = r.point;
  }
  const Mask hit = min_all > zero;
  const Mask face_a = axis < F(3.0f);
  const Mask face_b = andnot(axis < F(6.0f), face_a);
  const Mask is_edge = axis >= F(6.0f);

  // Normal (world, A to B).
  V3<F> n;
  {
    const F ia = axis, ib = axis - F(3.0f);
    const V3<F> na = pick3(ia, ra.c[0], ra.c[1], ra.c[2]) * simd::sign_nonneg(pick3(ia, tA[0], tA[1], tA[2]));
    const V3<F> nb = pick3(ib, rb.c[0], rb.c[1], rb.c[2]) * simd::sign_nonneg(pick3(ib, tB[0], tB[1], tB[2]));
    const V3<F> ne = ra.apply(edge_l) * simd::sign_nonneg(dot(edge_l, ta));
    n = select(face_a, na, select(face_b, nb, ne));
  }
  L4<F> m;
  m.n = n;
  m.depth = best;
  for (int q = 0; q < 4; ++q) {
    m.point[q] = V3<F>{zero, zero, zero};
    m.pdepth[q] = zero;
  }
  m.count = Int(0);
  if (simd::none(hit)) {
    store_no_contact<F>(out, k);
    return;
  }

  // --- 4. edge-edge: one point between the two edges' closest points ---
  if (simd::any(hit & is_edge)) {
    const F e_idx = axis - F(6.0f);
    const F ei = select(e_idx < F(3.0f), zero, select(e_idx < F(6.0f), one, F(2.0f)));
    const F ej = e_idx - F(3.0f) * ei;
    // support points: A's vertex furthest along n, B's furthest along -n
    const F sa[3] = {simd::sign_nonneg(dot(n, ra.c[0])), simd::sign_nonneg(dot(n, ra.c[1])),
                     simd::sign_nonneg(dot(n, ra.c[2]))};
    const F sb[3] = {-simd::sign_nonneg(dot(n, rb.c[0])), -simd::sign_nonneg(dot(n, rb.c[1])),
                     -simd::sign_nonneg(dot(n, rb.c[2]))};
    V3<F> va = ra.c[0] * (sa[0] * eA[0]) + ra.c[1] * (sa[1] * eA[1]) + ra.c[2] * (sa[2] * eA[2]);
    V3<F> vb = t + rb.c[0] * (sb[0] * eB[0]) + rb.c[1] * (sb[1] * eB[1]) + rb.c[2] * (sb[2] * eB[2]);
    const V3<F> da = pick3(ei, ra.c[0], ra.c[1], ra.c[2]);
    const V3<F> db = pick3(ej, rb.c[0], rb.c[1], rb.c[2]);
    const F ha = pick3(ei, eA[0], eA[1], eA[2]), hb = pick3(ej, eB[0], eB[1], eB[2]);
    // edge centres: drop the edge's own axis from the support vertex
    va = va - da * (pick3(ei, sa[0], sa[1], sa[2]) * ha);
    vb = vb - db * (pick3(ej, sb[0], sb[1], sb[2]) * hb);
    F s, u;
    closest_segment_segment(va, da, ha, vb, db, hb, s, u);
    const V3<F> xa = madd(va, s, da), xb = madd(vb, u, db);
    const Mask e = hit & is_edge;
    m.point[0] = select(e, select(redo, redo_point, (xa + xb) * half), m.point[0]);
    m.pdepth[0] = select(e, best, m.pdepth[0]);
    m.count = select(e, Int(1), m.count);
  }

  // --- 3. face contact: reference and incident faces, 24 clip candidates ---
  const Mask face = hit & ~is_edge;
  if constexpr (Compact) {
    // the face lanes go to the queue; their manifold comes later (box_box_face_queued)
    const typename F::Int cnt0 = select(face, Int(0), m.count);
    m.count = cnt0;
    for (uint32_t i = 0; i < F::kWidth; ++i)
      if (face.lane(i) && base + i < lim)
        queue->push(base + i, axis.lane(i), best.lane(i), n.x.lane(i), n.y.lane(i), n.z.lane(i));
  } else {
    if (simd::any(face)) box_box_face(t, ra, rb, eA, eB, axis, n, best, face, m);
  }
  m.count = select(hit, m.count, Int(0));
  if constexpr (Compact) {
    store<F, 4, 1>(out, k, m, pa);  // slots 1..3: count <= 1 here, face lanes come later
  } else {
    store(out, k, m, pa);
  }
}

/// The face manifold of queue entries j .. j + W (entries past `valid` are padding and
/// are not written): inputs read by pair index (ascending, inside the chunk [c0, c1):
/// GroupRows' windows), outputs scattered back.
template <class F>
IMPACT_INLINE void box_box_face_queued(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out,
                                       const FaceQueue& q, uint32_t j, uint32_t valid, uint32_t c0,
                                       uint32_t c1) {
  using Int = typename F::Int;
  const F zero(0.0f);
  const GroupRows<F> g(q.idx + j, Range{c0, c1});
  const V3<F> pa = g.v3(a.p);
  const V3<F> t = g.v3(b.p) - pa;
  const M3<F> ra = g.rot(a), rb = g.rot(b);
  const F eA[3] = {g(a.e[0]), g(a.e[1]), g(a.e[2])}, eB[3] = {g(b.e[0]), g(b.e[1]), g(b.e[2])};
  const F axis = F::load(q.axis + j), best = F::load(q.best + j);
  const V3<F> n{F::load(q.nx + j), F::load(q.ny + j), F::load(q.nz + j)};
  L4<F> m;
  for (int s = 0; s < 4; ++s) {
    m.point[s] = V3<F>{zero, zero, zero};
    m.pdepth[s] = zero;
  }
  m.count = Int(0);
  box_box_face(t, ra, rb, eA, eB, axis, n, best, typename F::Mask(true), m);
  V3<F> pw[4];
  for (int s = 0; s < 4; ++s) pw[s] = pa + m.point[s];  // as store() makes them absolute
  for (uint32_t i = 0; i < valid; ++i) {
    const uint32_t k = static_cast<uint32_t>(q.idx[j + i]);
    out.count[k] = static_cast<uint8_t>(m.count.lane(i));
    for (int s = 0; s < 4; ++s) {
      out.point[s][0][k] = pw[s].x.lane(i);
      out.point[s][1][k] = pw[s].y.lane(i);
      out.point[s][2][k] = pw[s].z.lane(i);
      out.pdepth[s][k] = m.pdepth[s].lane(i);
    }
  }
}

/// The SIMD path of box-box: chunks of FaceQueue::kChunk pairs; the SAT (and edge
/// contacts) block by block, then the face manifolds of the chunk's face lanes,
/// packed W to a block. Each lane's arithmetic is the same as box_box_block's alone.
template <class F>
void box_box_compact(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, Range r) {
  constexpr uint32_t W = F::kWidth;
  FaceQueue q;
  for (uint32_t c0 = r.begin; c0 < r.end; c0 += FaceQueue::kChunk) {
    const uint32_t c1 = c0 + FaceQueue::kChunk < r.end ? c0 + FaceQueue::kChunk : r.end;
    q.n = 0;
    uint32_t k = c0;
    for (; k + W <= c1; k += W) box_box_block<F, true>(a, b, out, k, &q, k, c1);
    if (k < c1) {
      const uint32_t n = c1 - k;
      TailSide<W> ta, tb;
      ta.fill(a, k, n);
      tb.fill(b, k, n);
      TailOut<W, 4> to{};
      box_box_block<F, true>(ta.view, tb.view, to.view(), 0u, &q, k, c1);
      to.copy_to(out, k, n);
    }
    for (uint32_t j = 0; j < q.n; j += W) {
      const uint32_t valid = q.n - j < W ? q.n - j : W;
      for (uint32_t i = valid; i < W; ++i) q.copy(j + valid - 1, j + i);
      box_box_face_queued<F>(a, b, out, q, j, valid, c0, c1);
    }
  }
}

}  // namespace

void collide_box_box(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, Range r, const NarrowConfig& cfg) {
  if (cfg.path == KernelPath::kScalar || simd::kPairWidth == 1) {
    for_each_block<simd::Float1, 4>(a, b, out, r, [](const LeafSoA& aa, const LeafSoA& bb, const ManifoldSoA& o,
                                                     uint32_t k) { box_box_block<simd::Float1>(aa, bb, o, k); });
  } else {
    box_box_compact<simd::FloatP>(a, b, out, r);
  }
}

}  // namespace impact::kernels
