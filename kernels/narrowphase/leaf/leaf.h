// The narrow phase's kernel contract: posed convex leaves in SoA, a manifold per
// lane, and one kernel per (leaf type, leaf type) bucket.
//
// The host (host/narrowphase/) expands meshes into triangles and compounds into
// their children, buckets the resulting leaf pairs by type pair with the radix sort,
// orders every pair so that type(A) <= type(B) in LeafType order, and gathers both
// sides into LeafSoA arrays: lane k of A, of B and of the output belong to pair k of
// the bucket. A kernel reads only the fields its two types use (table below), writes
// only out lane k for k in its Range, and is correct for any partition of the bucket.
// Layout for speed (not correctness): the simplest kernels run up to 3x slower (box-box
// ~12%) when their arrays start at one offset modulo 4096 or 16 bytes apart (L1 set
// conflicts, 4K aliasing); the host lays each SoA out with host::SoaArrays
// (host/buffer.h), every array at its own 64-byte slot modulo 4096.
//
// Field meaning per leaf type (all in the world frame; R is row-major, world = R*local + p):
//   sphere      p = centre; e0 = radius
//   capsule     p = centre; R column 2 = unit axis u; e0 = radius; e1 = half length
//               (the core segment is p - e1*u .. p + e1*u)
//   box         p = centre; R = orientation (identity for the AABB proxy);
//               e0, e1, e2 = half extents along R's columns
//   convex      p, R = pose of the hull's local frame; ref = hull index in HullView
//   cylinder    p = centre; R column 2 = unit axis; e0 = radius; e1 = half length
//   ellipsoid   p = centre; R = orientation; e0, e1, e2 = radii along R's columns
//   triangle    p = v0; w0..w2 = v1; w3..w5 = v2 (zero thickness, both sides solid
//               for the purpose of contact: the normal is the separating direction)
//   half-space  p = a point on the boundary plane; e0, e1, e2 = unit outward normal n;
//               the solid is { x : n.(x - p) <= 0 }
//
// Collision data of lane k (ManifoldSoA), per the seeds' definition:
//   count      0 = no contact (separated or exactly touching), else 1..4 points
//   n          unit normal from A to B (the direction B must move to separate)
//   depth      > 0: the smallest translation that separates them is n*depth on B
//              (or -n*depth on A): the safe displacement
//   point[i]   contact points, world, midway between the two surfaces
//   pdepth[i]  > 0: penetration along n at point i (<= depth up to tolerance)
// Lanes with count 0 leave every other field unspecified.
#pragma once

#include <cstdint>

#include "kernels/common/kernel.h"

namespace impact::kernels {

enum LeafType : uint8_t {
  kLeafSphere = 0,
  kLeafCapsule = 1,
  kLeafBox = 2,
  kLeafConvex = 3,
  kLeafCylinder = 4,
  kLeafEllipsoid = 5,
  kLeafTriangle = 6,
  kLeafHalfSpace = 7,
  kLeafTypeCount = 8,
};

const char* leaf_type_name(LeafType t);

/// One side of a bucket; lane k at index k of every array. Unused fields may be null.
struct LeafSoA {
  const float* p[3];
  const float* r[9];   // row-major: r[3*row + col]
  const float* e[3];
  const float* w[6];   // triangle only: v1 then v2
  const uint32_t* ref; // convex only
};

inline constexpr uint32_t kMaxManifoldPoints = 4;

struct ManifoldSoA {
  uint8_t* count;
  float* n[3];
  float* depth;
  float* point[kMaxManifoldPoints][3];
  float* pdepth[kMaxManifoldPoints];
};

/// Convex hulls, all concatenated; hull h is LeafSoA::ref. Vertices and planes are in
/// the hull's local frame. Face f's polygon is face_verts[face_vert_begin[f] ..
/// face_vert_begin[f + 1]) (absolute vertex indices), counter-clockwise seen from
/// outside; its plane is { x : fn.x <= fd } with fn unit and outward. Edge
/// directions (unit, one per parallel class; e*) are hints for the tests' reference;
/// SAT (sat.cpp) reads the per-edge adjacency (adj_*, below).
/// A hull's edge adjacency list (HullView adj_*) is padded to a multiple of this with
/// copies of its last edge, so the kernels that walk the edges a vector at a time need
/// no tail. It is a contract between the host's HullStore and those kernels: each one
/// static_asserts that its vector width divides it (a wider walk would read past the
/// hull's list into the next hull's, or past the arrays).
inline constexpr uint32_t kHullEdgePad = 8;

struct HullView {
  const uint32_t* vert_begin;       // [h], [h + 1]
  const float* vx;
  const float* vy;
  const float* vz;
  const float* vxyz;                // vertex v again as one record: vxyz[4 v ..] = x, y, z, 0
  const uint32_t* face_begin;       // [h], [h + 1]
  const float* fnx;
  const float* fny;
  const float* fnz;
  const float* fd;
  const uint32_t* face_vert_begin;  // [f], [f + 1]
  const uint32_t* face_verts;
  const uint32_t* edge_begin;       // [h], [h + 1]
  const float* ex;
  const float* ey;
  const float* ez;
  // Edge adjacency for SAT (kernels/narrowphase/general/sat.cpp): every hull edge once, hull h's
  // edges adj_begin[h] .. adj_begin[h + 1] (none when the faces do not close into a
  // 2-manifold: SAT then leaves the hull to GJK/EPA). Hull-local indices: ev0 / ev1 are
  // the end vertices minus vert_begin[h], ef0 / ef1 the two faces minus face_begin[h].
  // em = unit bisector of the two face normals (local), ecos / esin = cos / sin of half
  // the angle between them: the edge's normal cone lies within that angle of em.
  // ep = vertex ev0 (local), ed = vertex ev1 - vertex ev0 (the float difference), next
  // to the rest for contiguous SIMD loads (no gather of the far end). A hull's edge list
  // is padded to a multiple of kHullEdgePad with copies of its last edge.
  const uint32_t* adj_begin;        // [h], [h + 1]
  const uint32_t* ev0;
  const uint32_t* ev1;
  const uint32_t* ef0;
  const uint32_t* ef1;
  const float* emx;
  const float* emy;
  const float* emz;
  const float* ecos;
  const float* esin;
  const float* epx;
  const float* epy;
  const float* epz;
  const float* edx;
  const float* edy;
  const float* edz;
};

/// Which implementation a kernel runs. Both give the same collision data up to
/// float rounding; kScalar is the reference path the SIMD path is tested against.
enum class KernelPath : uint8_t { kSimd = 0, kScalar = 1 };

/// Accuracy knobs of the iterative kernels (GJK, EPA) and the data they share.
struct NarrowConfig {
  KernelPath path = KernelPath::kSimd;
  uint32_t gjk_max_iterations = 64;
  float gjk_tolerance = 1e-6f;   // relative to the shapes' size
  uint32_t epa_max_iterations = 64;  // not for pairs with a hull side (gjk_epa.cpp)
  float epa_tolerance = 1e-5f;   // relative to the shapes' size
  /// Polytope pairs (box, hull) go through SAT (sat.cpp) instead of GJK/EPA when their
  /// vertex counts sum to at most this (a box has 8); 0: always GJK/EPA. SAT's cost
  /// grows with F_A V_B + F_B V_A, GJK/EPA's with V_A + V_B: measured crossover ~100.
  uint32_t sat_max_vertices = 96;
  HullView hulls{};
};

using PairKernel = void (*)(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, Range r,
                            const NarrowConfig& cfg);

/// The kernel of a (ta, tb) bucket, ta <= tb; null for half-space/half-space (two
/// unbounded solids have no finite collision data; the host rejects such pairs).
PairKernel pair_kernel(LeafType ta, LeafType tb);

}  // namespace impact::kernels
