// The narrow phase's passes without the public API's validation: what
// impact::NarrowPhase::collide and the World's step share.
#pragma once

#include <memory>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "host/narrowphase/shape_store.h"
#include "host/parallel.h"
#include "impact/narrowphase.h"
#include "impact/status.h"
#include "kernels/narrowphase/leaf.h"

namespace impact::host {

/// kInvalidArgument naming the field when a knob is out of range (iteration caps 0,
/// tolerances outside (0, 1)); kUnsupported for a thread backend not built in.
Status validate_options(const NarrowPhaseOptions& options);
/// The kernels' configuration for the options' knobs (the hull view is set by the run).
kernels::NarrowConfig config_of(const NarrowPhaseOptions& options);

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

/// Expansion, bucketing, gather, kernels and output of host/narrowphase/narrow_phase.cpp.
/// Keeps its scratch between calls.
class NarrowRunner {
 public:
  NarrowRunner();
  ~NarrowRunner();
  NarrowRunner(NarrowRunner&&) noexcept = default;
  NarrowRunner& operator=(NarrowRunner&&) noexcept = default;

  /// Inputs are valid (the caller checked them): rec[i] is object i's shape (it may
  /// point outside store, e.g. a sphere or half-space record of the caller's own;
  /// convex/mesh/compound records index into store), types[i] = rec[i]->type (a compact
  /// copy: the pair pass reads only it), poses[i] its rotation and position with
  /// set_shape(*rec[i]) applied, pairs index objects (a != b, not two half-spaces). cfg.hulls is set here.
  /// bad_pair: null, or the pairs are checked as they are expanded (indices in range,
  /// a != b, not two half-spaces): when one fails, *bad_pair is the lowest failing
  /// index, *out is left empty and the call returns kInvalidArgument (the caller words
  /// the message); else *bad_pair = pairs.size(). The check rides on the expansion,
  /// which reads the same records, instead of costing a pass of its own.
  Status run(const Executor& exec, const ShapeStore& store, std::span<const ShapeRecord* const> rec,
             std::span<const ShapeType> types, std::span<const PosedObject> poses,
             std::span<const ShapePair> pairs, const kernels::NarrowConfig& cfg, std::vector<Manifold>* out,
             size_t* bad_pair = nullptr);

 private:
  struct State;
  std::unique_ptr<State> s_;
};

}  // namespace impact::host
