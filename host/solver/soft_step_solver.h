// host::SoftStepSolver: SolverKind::kSoftStep, the default contact solver of a World
// (kernels/solver/soft_contact.h has the method). It owns the solver's scratch (body
// states, constraints in colour order, the colouring) and last step's impulses for
// warm starting, and it integrates the bodies itself, substep by substep: in a soft
// step the integrate and correct stages of the Jacobi solver do nothing.
//
// Per step: prepare bodies -> colour the manifolds (kernels/solver/graph_colouring.h)
// -> order constraints by colour -> match last step's impulses by contact key ->
// prepare constraints -> substeps -> restitution -> store -> write the bodies back.
// Cost: O(bodies) per substep for integration, O(points) per pass, 3 passes a
// substep (warm start, solve, relax), one parallel loop per colour and pass; the
// colouring and the overflow colour are serial.
#pragma once

#include <cstdint>
#include <span>

#include "host/body_store.h"
#include "host/buffer.h"
#include "host/contact_manifolds.h"
#include "host/parallel.h"
#include "host/plane_store.h"
#include "host/radix_sort.h"
#include "impact/world.h"
#include "kernels/solver/graph_colouring.h"
#include "kernels/solver/soft_contact.h"

namespace impact::host {

class SoftStepSolver {
 public:
  /// Solves and integrates one step of dt: velocities, positions and orientations of
  /// `bodies` move; the force accumulators are left for the caller to clear.
  void step(const Executor& exec, const WorldDesc& desc, const ContactManifolds& c, BodyStore& bodies,
            const PlaneStore& planes, float dt);
  /// Body slots were permuted (inv_perm[old slot] = new slot, n bodies).
  void remap_bodies(const Executor& exec, const uint32_t* inv_perm, uint32_t n);
  /// Slots were removed or reused: last step's impulses no longer apply.
  void forget() { prev_count_ = 0; }
  /// This step has no contact results.
  void clear_impulses() { impulse_out_.clear(); }
  /// Accumulated normal impulse per contact point of the last step, N s.
  std::span<const float> impulses() const { return {impulse_out_.data(), impulse_out_.size()}; }

 private:
  template <class Fn>
  void for_each_colour(const Executor& exec, Fn&& fn) const;

  RadixSorter sorter_;
  Buffer<kernels::SolverBody> bodies_;  // entry n: the zero body of planes
  Buffer<kernels::BodyDrive> drive_;
  Buffer<kernels::Sym3> inv_inertia_;
  Buffer<kernels::Vec3> com_;
  Buffer<uint32_t> body_masks_;
  Buffer<uint8_t> colour_;
  Buffer<uint32_t> order_, first_;             // constraint -> manifold, first point
  Buffer<kernels::ContactConstraint> cons_;
  Buffer<kernels::ContactPoint> points_;
  Buffer<uint64_t> keys_;                      // this step's point keys
  Buffer<kernels::WarmPoint> warm_;            // matched last-step values per point row
  Buffer<kernels::WarmPoint> stored_;          // this step's values per point row
  Buffer<uint64_t> prev_keys_;                 // last step's, sorted
  Buffer<uint32_t> prev_index_;                // their rows in prev_values_
  Buffer<uint32_t> prev_start_;                // per body a: range in prev_keys_
  Buffer<kernels::WarmPoint> prev_values_;
  Buffer<float> impulse_out_;
  uint32_t prev_count_ = 0, prev_body_count_ = 0;
  uint32_t colour_start_[kernels::kColourCount + 2] = {};
};

}  // namespace impact::host
