// The narrow phase's passes without the public API's validation: what
// impact::NarrowPhase::collide and the World's step share.
#pragma once

#include <memory>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "host/contact_manifolds.h"
#include "host/parallel.h"
#include "host/shapes/shape_store.h"
#include "impact/narrowphase.h"
#include "impact/status.h"
#include "kernels/common/body_views.h"
#include "kernels/common/pair.h"
#include "kernels/narrowphase/leaf/leaf.h"

namespace impact::host {

/// kInvalidArgument naming the field when a knob is out of range (iteration caps 0,
/// tolerances outside (0, 1)); kUnsupported for a thread backend not built in.
Status validate_options(const NarrowPhaseOptions& options);
/// The kernels' configuration for the options' knobs (the hull view is set by the run).
kernels::NarrowConfig config_of(const NarrowPhaseOptions& options);

/// The kernels' leaf type of a shape type (kLeafTypeCount: a compound, which has none).
inline kernels::LeafType leaf_type_of(ShapeType t) {
  switch (t) {
    case ShapeType::kSphere: return kernels::kLeafSphere;
    case ShapeType::kCapsule: return kernels::kLeafCapsule;
    case ShapeType::kBox:
    case ShapeType::kAabb: return kernels::kLeafBox;
    case ShapeType::kConvex: return kernels::kLeafConvex;
    case ShapeType::kCylinder: return kernels::kLeafCylinder;
    case ShapeType::kEllipsoid: return kernels::kLeafEllipsoid;
    case ShapeType::kHalfSpace: return kernels::kLeafHalfSpace;
    case ShapeType::kMesh: return kernels::kLeafTriangle;
    case ShapeType::kCompound: break;
  }
  return kernels::kLeafTypeCount;
}

/// An object's placement (world = R * local + p, R a rotation) and, on the same 64-byte
/// line, what the gather copies from a plain shape's record: its e (sphere, capsule, box,
/// cylinder, ellipsoid, half-space) or hull index (convex), and a half-space's offset. So
/// a plain pair's gather reads one line per object instead of chasing its record too.
/// R of a sphere is never read.
struct alignas(64) PosedObject {
  Eigen::Matrix3f R;
  Eigen::Vector3f p;
  union {
    float e[3];    // the record's e (types other than convex)
    uint32_t ref;  // convex: the record's hull index
  } leaf;
  float offset;  // the record's offset (a half-space's plane)

  /// leaf and offset from the object's record.
  void set_shape(const ShapeRecord& r) {
    if (r.type == ShapeType::kConvex) {
      leaf.ref = r.ref;
    } else {
      for (int i = 0; i < 3; ++i) leaf.e[i] = r.e[i];
    }
    offset = r.offset;
  }
};
static_assert(sizeof(PosedObject) == 64);

/// The pair list of a run: pair k is first[k] for k < first.size(), else
/// second[k - first.size()] (a World passes its broad-phase pairs and its body-plane
/// pairs without joining them).
struct PairList {
  std::span<const kernels::Pair> first;
  std::span<const kernels::Pair> second;
  size_t size() const { return first.size() + second.size(); }
  const kernels::Pair& operator[](size_t k) const {
    return k < first.size() ? first[k] : second[k - first.size()];
  }
};

/// Objects at or past NarrowObjects::first_plane are a World's static planes.
inline constexpr uint32_t kNoPlanes = 0xffffffffu;

/// The objects of a run: object i is shape *rec[i] (it may point outside store, e.g.
/// a sphere or half-space record of the caller's own; convex/mesh/compound records
/// index into store), types[i] = rec[i]->type (a compact copy: the pair pass reads
/// only it), poses[i] its rotation and position with set_shape(*rec[i]) applied.
/// Manifolds name an object b >= first_plane by its plane index b - first_plane, with
/// b_is_plane set.
struct NarrowObjects {
  const ShapeStore* store = nullptr;
  std::span<const ShapeRecord* const> rec;
  std::span<const ShapeType> types;
  std::span<const PosedObject> poses;
  uint32_t first_plane = kNoPlanes;
};

/// A World of plain spheres: bodies read straight from the body store, planes from
/// the plane store; plane j is object first_plane + j of the pair list.
struct SphereObjects {
  kernels::SphereView spheres;
  kernels::PlaneView planes;
  uint32_t first_plane = 0;
};

/// Lets a caller consume a run's manifolds while they are in cache: sized(m) once the
/// run knows it writes m manifolds (before it writes any), then written(begin, end) for
/// each output chunk's manifolds [begin, end), right after the chunk wrote them, on
/// that chunk's thread (so written() must only touch its own range).
struct ManifoldHook {
  FunctionRef<void(size_t manifolds)> sized;
  FunctionRef<void(uint32_t begin, uint32_t end)> written;
};

/// The narrow phase of host/narrowphase/narrow_phase.cpp: expansion, bucketing by
/// leaf-type pair, gather, the pair kernels, and the ordered output into the one
/// contact layout (host::ContactManifolds). Keeps its scratch between calls.
class NarrowRunner {
 public:
  NarrowRunner();
  ~NarrowRunner();
  NarrowRunner(NarrowRunner&&) noexcept = default;
  NarrowRunner& operator=(NarrowRunner&&) noexcept = default;

  /// Collision data of every pair (inputs valid: the caller checked them; pairs index
  /// objects, a != b, not two half-spaces) into *out, in (pair, child_a, child_b) order.
  /// cfg.hulls is set here. bad_pair: null, or the pairs are checked as they are
  /// expanded (indices in range, a != b, not two half-spaces): when one fails,
  /// *bad_pair is the lowest failing index, *out is left as it was and the call returns
  /// kInvalidArgument (the caller words the message); else *bad_pair = pairs.size().
  /// The check rides on the expansion, which reads the same records, instead of
  /// costing a pass of its own.
  Status run(const Executor& exec, const NarrowObjects& objects, const PairList& pairs,
             const kernels::NarrowConfig& cfg, ContactManifolds* out, size_t* bad_pair = nullptr,
             const ManifoldHook* hook = nullptr);

  /// The sphere buckets of a World without shapes: pairs.first are sphere-sphere
  /// pairs (the sphere_sphere kernels), pairs.second (body, first_plane + j) pairs from
  /// the plane filter (sphere_plane kernels); one-point manifolds in pair order.
  Status run_spheres(const Executor& exec, const SphereObjects& objects, const PairList& pairs,
                     ContactManifolds* out);

 private:
  struct State;
  std::unique_ptr<State> s_;
};

/// The public Manifold of manifolds [begin, end) of c (pair, children, normal, depth
/// and points) into out[begin, end).
void to_manifolds(const ContactManifolds& c, uint32_t begin, uint32_t end, Manifold* out);

}  // namespace impact::host
