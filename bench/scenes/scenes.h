// Benchmark scenes: deterministic body and plane sets shared by the throughput tool
// (bench/scenes/throughput.cpp), the rigid-body peers tool (bench/rigid_peers.cpp) and
// the Google Benchmark micro-benchmarks (bench/broadphase_bench.cpp).
//
// Every scene is a pure function of (name, body count, seed): positions come from a
// counter-based generator (SplitMix64), not <random> distributions, whose output is
// implementation-defined. So the same arguments give the same bodies, and hence the
// same final state_hash, on every standard library — a hash printed by one machine
// can be checked on another (with the same ISA and FP-contraction setting).
//
// Units: m, m/s, kg.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "impact/impact.h"

namespace impact::bench {

/// Small deterministic PRNG (SplitMix64, Steele et al. 2014). Not for cryptography.
class Rng {
 public:
  explicit Rng(uint64_t seed) : state_(seed) {}
  uint64_t next_u64() {
    uint64_t z = (state_ += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
  }
  /// Uniform in [0, 1), 24 random bits.
  float uniform() { return static_cast<float>(next_u64() >> 40) * 0x1.0p-24f; }
  /// Uniform in [lo, hi).
  float uniform(float lo, float hi) { return lo + (hi - lo) * uniform(); }

 private:
  uint64_t state_;
};

/// Default seed of every scene.
inline constexpr uint64_t kDefaultSeed = 0x1badb002u;

/// Sphere radii of the mixed-size scenes, m.
inline constexpr float kMinRadius = 0.25f;
inline constexpr float kMaxRadius = 0.5f;

/// The geometry of one shape of a scene (the ShapeSet::add_* arguments). Only the
/// fields of its type are read.
struct SceneShape {
  ShapeType type = ShapeType::kBox;  ///< kSphere, kCapsule, kBox, kConvex, kCylinder or kMesh
  Eigen::Vector3f half_extents{0.5f, 0.5f, 0.5f};  ///< kBox, m
  float radius = 0.5f;       ///< kSphere, kCapsule, kCylinder, m
  float half_length = 0.5f;  ///< kCapsule, kCylinder (along local z), m
  std::vector<Eigen::Vector3f> points;  ///< kConvex: the point cloud; kMesh: the vertices, m
  std::vector<uint32_t> indices;        ///< kMesh: three vertex indices per triangle
};

/// A scene ready to be loaded into a World.
struct Scene {
  std::string name;
  /// Shapes the bodies refer to: a body's BodyDesc::shape.index is a position in this
  /// list (load_scene adds them, in order, to the new world's empty ShapeSet, where
  /// they get those same ids). Empty for the sphere scenes.
  std::vector<SceneShape> shapes;
  std::vector<BodyDesc> bodies;
  std::vector<PlaneDesc> planes;
  Eigen::Vector3f gravity{0.0f, -9.81f, 0.0f};  ///< m/s^2
  /// Bodies that rotate and rub (boxes, hulls, ...): the scene means to be run with
  /// the soft-step solver (SolverKind::kSoftStep), which impact_bench picks for it
  /// unless told otherwise. The sphere scenes are frictionless and leave it false.
  bool rigid = false;
};

/// Names accepted by make_scene(), in the order --help lists them.
std::span<const std::string_view> scene_names();
/// One line describing a scene, for --help.
std::string_view scene_summary(std::string_view name);
/// The body count a scene is documented at (100000 for the sphere scenes; 1240 for
/// "pyramid", ...; see make_scene); 0 for an unknown name.
uint32_t scene_default_bodies(std::string_view name);

/// Builds a scene. Sphere scenes (`bodies` spheres):
///  - "box":     frictionless spheres (r in [0.25, 0.5] m, restitution in [0, 0.5]) on a jittered grid
///               above the floor of an open box (5 static planes), falling under gravity.
///  - "rain":    the same box; spheres start higher and sparser, already moving down
///               at 4..12 m/s with some sideways drift.
///  - "uniform": spheres uniformly at random in a cube sized for about one overlapping
///               pair per body; no gravity, no planes.
/// Stacks of 1 m cubes (1 kg, friction 0.6, restitution 0) standing at rest on a floor
/// plane y = 0 (friction 0.6): neighbours in a layer kStackGap apart, each box
/// kStackOverlap into the one below (or the floor), so every resting contact exists
/// from the first step and nothing falls. Each is the largest complete structure of at
/// most `bodies` boxes (at least one layer / pyramid):
///  - "pyramid":  square pyramid, layer k (from the top, k >= 1) k x k boxes centred on
///                the y axis; 15 layers = 1240 boxes (the default).
///  - "wall":     a pyramid in the x-y plane (z = 0), row k from the top k boxes;
///                100 rows = 5050 boxes (the default).
///  - "pyramids": floor(bodies / 55) square pyramids of 5 layers (55 boxes) on a
///                square grid 8 m apart, row by row; 196 = 14 x 14 = 10780 boxes (the default).
///  - "column":   `bodies` boxes in one vertical column (default 20).
/// Piles dropped into the open box of "box" (same grid layout, 1.1 m pitch, random
/// orientations), density 1 kg/m^3, friction 0.6, restitution 0:
///  - "hulls":    `bodies` convex hulls of kHullPoints random points each (within a
///                0.48 m ball, squashed per axis, moved to put the centre of mass at
///                the origin; at most 0.5 m from it), each its own shape (default 5000).
///  - "mixed":    `bodies` bodies cycling box, capsule, hull, cylinder, sphere with
///                random sizes (bounding radius <= 0.5 m), dropped on a static
///                triangle-mesh floor of random heights in [-0.15, 0.15] m (one extra
///                static body, the last), walls as in "box" and a backstop floor plane
///                at y = -1 m under the mesh (default 10000 dynamic bodies).
/// Fails with kInvalidArgument for an unknown name or bodies == 0.
Status make_scene(std::string_view name, uint32_t bodies, uint64_t seed, Scene* out);

/// Horizontal gap between neighbouring boxes of the stacking scenes, m.
inline constexpr float kStackGap = 0.005f;
/// How far each box of the stacking scenes starts inside its support, m.
inline constexpr float kStackOverlap = 0.001f;
/// Points of each hull of the "hulls" and "mixed" scenes.
inline constexpr uint32_t kHullPoints = 32;

/// Adds the scene's shapes to `shapes` in order; fails unless they get the ids
/// 0, 1, 2, ... (shapes must then start empty) or when the set rejects one.
Status add_scene_shapes(const Scene& scene, ShapeSet* shapes);

/// Creates a world from desc (gravity taken from the scene) and loads the scene into it.
Status load_scene(const Scene& scene, WorldDesc desc, std::unique_ptr<World>* out);

/// Edge length (m) of a cube holding n spheres with radii uniform in [r_min, r_max]
/// placed uniformly at random, such that the expected number of overlapping pairs
/// is pairs_per_body * n. Two spheres overlap when their centres are closer than
/// ra + rb, so E[pairs] = n^2/2 * (4/3 pi E[(ra+rb)^3]) / side^3.
float sphere_cube_side(uint32_t n, float r_min, float r_max, double pairs_per_body);

/// Edge length (m) of a cube holding n axis-aligned cubes of edge 2*half_extent at
/// uniformly random centres, such that the expected number of overlapping box pairs
/// is pairs_per_body * n (two boxes overlap when |dx|, |dy|, |dz| < 2*half_extent, a
/// volume of (4*half_extent)^3).
float box_cube_side(uint32_t n, float half_extent, double pairs_per_body);

/// SoA bounding boxes of n spheres of one radius at uniformly random centres in a
/// cube; owns its arrays, view() borrows them.
struct UniformBoxes {
  std::vector<float> min_x, min_y, min_z, max_x, max_y, max_z;
  float side = 0.0f;  ///< cube edge, m
  AabbInput view() const;
};

/// n unit-radius (by default) spheres' boxes, about pairs_per_body overlapping
/// pairs per body.
UniformBoxes make_uniform_boxes(uint32_t n, float radius, double pairs_per_body, uint64_t seed);

/// Mixed sizes: n - n/10000 small boxes (half extent 0.05 m, ~1 overlapping pair
/// each) plus n/10000 (at least 1) big ones with half extents log-uniform in
/// [0.5, 5] m: a 100x spread where one grid cell sized for the big boxes would
/// hold thousands of small ones.
UniformBoxes make_mixed_boxes(uint32_t n, uint64_t seed);

/// Size spread: cubes with half extents log-uniform over [1 / ratio, 1] m (ratio 1:
/// all 1 m), centres uniform in a cube sized for about one overlapping pair per body,
/// times `sparsity` per axis (10: 1000x the volume, ~1/1000 of the pairs). The scenes
/// of the automatic grid / LBVH choice (docs/broadphase.md).
UniformBoxes make_size_spread_boxes(uint32_t n, double ratio, double sparsity, uint64_t seed);

/// Clustered: n boxes of unit-radius spheres (like make_uniform_boxes) in
/// kClusterBlobs gaussian-like blobs (each coordinate a sum of 12 uniforms, so no
/// transcendental function shapes the bodies), blob centres uniform in a cube 16
/// blob widths (sigma) across. sigma grows as n^(1/3) so that the bodies average
/// about pairs_per_body overlapping pairs at every n (about 2.8x that at a blob's
/// core, ~0.3x at 1.5 sigma). Most of the world's volume is empty: the boxes' bounds
/// hold 40-50 cells of 2 m (one box width) per body at 10k..1M.
UniformBoxes make_clustered_boxes(uint32_t n, double pairs_per_body, uint64_t seed);

/// Number of blobs of make_clustered_boxes.
inline constexpr uint32_t kClusterBlobs = 8;

/// Coherent motion for frame-to-frame benchmarks: a deterministic random walk of
/// every box's centre (extents kept), each step uniform in [-step, step] m per axis
/// and reflected at the bounds of the starting centres, so the scene neither drifts
/// nor spreads. Frame 0 is the starting set, byte for byte; every later frame is a
/// pure function of (start, step, seed, frame number).
class BoxWalk {
 public:
  BoxWalk(const UniformBoxes& start, float step, uint64_t seed);
  /// Moves every box by one step (O(n), ~10 ns per box).
  void advance();
  /// The current frame's boxes.
  const UniformBoxes& boxes() const { return boxes_; }
  uint64_t frame() const { return frame_; }

 private:
  UniformBoxes boxes_;
  std::vector<float> cx_, cy_, cz_, hx_, hy_, hz_;
  float lo_[3], hi_[3];
  float step_;
  Rng rng_;
  uint64_t frame_ = 0;
};

}  // namespace impact::bench
