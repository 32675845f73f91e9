// Narrow-phase benchmark scenes, shared by bench/narrowphase_bench.cpp (our kernels,
// the public NarrowPhase) and bench/narrowphase_peers.cpp (FCL, libccd), so that every
// implementation sees the same shapes and poses.
//
// A scene is a bucket of n pairs of one (leaf type, leaf type) kind, A's type <= B's
// type in kernels::LeafType order. Lane k:
//   sizes     random per lane (sphere r 0.25..1; capsule r 0.2..0.6, half length
//             0.2..1; box half extents 0.2..1; cylinder r 0.2..0.8, half length 0.2..1;
//             ellipsoid radii 0.25..1; convex: one of 16 hulls of 24 points on a
//             squashed unit sphere; triangle: 3 vertices 0.5..1.5 from the centroid)
//   poses     uniformly random orientations; A's centre uniform in a 100 m cube
//   placement B's centre (a triangle's centroid) is A's centre + d*u for a random
//             unit u, with d = f*t: t is the distance along u at which the two just
//             touch (bisection on an independent double-precision GJK test,
//             relative precision ~1e-7), f uniform in [0.6, 1.4]. So a lane overlaps
//             iff f < 1: about half of them ("expected_hits"), with depths up to 40%
//             of the touching distance. A half-space's plane is placed the same way
//             against A's support point along the plane normal.
// Everything is generated in double and rounded to float; the peers read the float
// values (converted exactly to double). The generator and the support functions are
// defined in one translation unit (narrowphase_bench.cpp, built for the project's ISA)
// so that both files see bit-identical scenes.
#pragma once

#include <time.h>

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace impact::bench::narrow {

/// Leaf kinds, numbered as kernels::LeafType.
enum Kind : uint8_t {
  kSphere = 0,
  kCapsule = 1,
  kBox = 2,
  kConvex = 3,
  kCylinder = 4,
  kEllipsoid = 5,
  kTriangle = 6,
  kHalfSpace = 7,
};

/// One posed leaf, in the kernels' LeafSoA convention (kernels/narrowphase/leaf/leaf.h).
struct Body {
  uint8_t kind = kSphere;
  float p[3] = {0, 0, 0};                    ///< centre; triangle: v0; half-space: a point on the plane
  float q[4] = {1, 0, 0, 0};                 ///< orientation w, x, y, z (identity for triangle / half-space)
  float r[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};  ///< row-major rotation of q
  float e[3] = {0, 0, 0};                    ///< sizes as LeafSoA::e; half-space: unit outward normal
  float v[9] = {};                           ///< triangle: world vertices v0, v1, v2
  uint32_t hull = 0;                         ///< convex: index into PairScene::hulls
};

/// A convex hull: its points (local frame) and, for the peers that need a polytope,
/// its faces as built by host/shapes/convex_hull.h.
struct Hull {
  std::vector<std::array<float, 3>> points;  ///< the input cloud (support = over these)
  std::vector<std::array<float, 3>> verts;   ///< hull vertices (empty if not built)
  std::vector<uint32_t> faces;               ///< per face: vertex count, then indices into verts
  uint32_t face_count = 0;
};

struct PairScene {
  uint8_t ka = kSphere, kb = kSphere;
  uint32_t n = 0;
  std::vector<Body> a, b;
  std::vector<Hull> hulls;
  std::vector<float> f;        ///< per lane: placement distance / touching distance
  uint32_t expected_hits = 0;  ///< lanes placed inside the touching distance (f < 1)
  uint32_t near_touch = 0;     ///< lanes with |f - 1| < kNearTouch (either answer is fair)
};

/// Lanes this close to touching (relative to the touching distance) may fairly be
/// reported either way by a float kernel or a peer's tolerance.
inline constexpr double kNearTouch = 1e-4;

/// Lanes whose reported contact (hit[k] != 0) contradicts the placement, ignoring the
/// near-touch lanes: should be 0 for every implementation.
template <typename HitFn>
uint32_t disagreements(const PairScene& s, HitFn&& hit) {
  uint32_t bad = 0;
  for (uint32_t k = 0; k < s.n; ++k) {
    const double f = s.f[k];
    if (f - 1 > -kNearTouch && f - 1 < kNearTouch) continue;
    bad += (hit(k) != (f < 1)) ? 1 : 0;
  }
  return bad;
}

/// The pair kinds the benchmarks cover: every pair of the matrix (A's kind <= B's),
/// the original 19 first (their rows keep their place in reports), then the other 16.
struct PairKind {
  uint8_t a, b;
};
inline constexpr PairKind kPairKinds[] = {
    {kSphere, kSphere},      {kSphere, kCapsule},      {kSphere, kBox},          {kCapsule, kCapsule},
    {kCapsule, kBox},        {kBox, kBox},             {kSphere, kConvex},       {kBox, kConvex},
    {kConvex, kConvex},      {kCylinder, kCylinder},   {kEllipsoid, kEllipsoid}, {kSphere, kTriangle},
    {kCapsule, kTriangle},   {kBox, kTriangle},        {kSphere, kHalfSpace},    {kCapsule, kHalfSpace},
    {kBox, kHalfSpace},      {kConvex, kHalfSpace},    {kCylinder, kHalfSpace},  {kSphere, kCylinder},
    {kSphere, kEllipsoid},   {kCapsule, kConvex},      {kCapsule, kCylinder},    {kCapsule, kEllipsoid},
    {kBox, kCylinder},       {kBox, kEllipsoid},       {kConvex, kCylinder},     {kConvex, kEllipsoid},
    {kConvex, kTriangle},    {kCylinder, kEllipsoid},  {kCylinder, kTriangle},   {kEllipsoid, kTriangle},
    {kTriangle, kTriangle},  {kEllipsoid, kHalfSpace}, {kTriangle, kHalfSpace},
};


const char* kind_name(uint8_t k);
/// "sphere-box" etc.
std::string pair_name(uint8_t ka, uint8_t kb);

/// The scene of kind (ka, kb) with n lanes; built on first use and cached (not
/// thread-safe: call from benchmark setup, which runs on one thread).
const PairScene& pair_scene(uint8_t ka, uint8_t kb, uint32_t n);

/// Support point of a bounded body in world direction dir (any length, non-zero).
void support(const PairScene& s, const Body& body, const double dir[3], double out[3]);
/// A point inside the body (its centre; a triangle's centroid).
void interior_point(const Body& body, double out[3]);

/// Minimum read + write traffic of one lane of the kernel, bytes: the LeafSoA fields
/// the two leaf types need (4 bytes each) plus the count byte, normal, depth and the
/// kind's manifold points with their depths (kernels write them for every lane in
/// the worst case). An estimate for comparing with the stream bandwidth.
uint32_t bytes_per_pair(uint8_t ka, uint8_t kb);

/// CPU time of the calling thread, ns (the benchmarks' per-pair counters use it: the
/// machine is shared, and the kernel and peer benchmarks are single-threaded).
inline double thread_cpu_ns() {
  timespec ts;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) * 1e9 + static_cast<double>(ts.tv_nsec);
}

/// A body's bounding radius about its centre (0 for a half-space): the scale of a pair's
/// depth deviations.
double body_size(const PairScene& s, const Body& b);

/// Our collision data of one lane (the fields a peer's contact can be compared with).
struct LaneResult {
  uint8_t count = 0;
  float n[3] = {0, 0, 0};  ///< unit normal, A to B
  float depth = 0;
};

/// Every lane of the scene through the library's SIMD kernel for its kind (as
/// BM_Kernel runs it), for comparing a peer's answers with ours.
std::vector<LaneResult> kernel_results(const PairScene& s);

/// Registers the peers' benchmarks of one pair kind (bench/narrowphase_peers.cpp;
/// none when no peer was found at configure time).
void register_peer_benchmarks(uint8_t ka, uint8_t kb);

}  // namespace impact::bench::narrow
