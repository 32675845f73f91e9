// host::SoftStepSolver: SolverKind::kSoftStep, the default contact solver of a World
// (kernels/solver/soft_contact.h has the method). It owns the solver's scratch (body
// states, constraints in colour order, the colouring) and last step's impulses for
// warm starting, and it integrates the bodies itself, substep by substep: in a soft
// step the integrate and correct stages of the Jacobi solver do nothing.
//
// Per step: colour the manifolds (kernels/solver/graph_colouring.h) -> recovery
// velocity solve of the deep ones -> prepare bodies -> order constraints by colour ->
// match last step's impulses by contact key -> prepare constraints -> substeps ->
// restitution -> store -> write the bodies back -> recovery position correction.
//
// Deep overlaps: a manifold deeper than max_push_speed * dt cannot be pushed out by
// the soft bias within the step, and a body in hundreds of them (bodies created at
// one point, a fast body found far inside another) would sum hundreds of capped
// pushes into a large velocity. Those manifolds stay in the soft step without bias
// (a rigid stop: the bodies close no further, with friction), and the Jacobi solver
// (host/solver/contact_solver.h) separates them: its velocity solve stops their
// approach (with restitution) before the substeps, and its position correction moves
// them apart after, on displacements, so the recovery adds no kinetic energy. (Taking
// them out of the soft step instead left a pile with nothing holding its deep
// contacts during the substeps: they sank deeper, docs/solver.md.) A scene without
// deep manifolds pays one comparison per manifold for it.
//
// Constraints sit in slots in colour order, each colour padded to whole blocks of
// kernels::kContactLanes (kernels/solver/soft_contact.h): a colour's passes run its
// blocks in parallel chunks of whole blocks (one constraint a SIMD lane), so block and
// chunk boundaries depend only on the colour counts; the overflow colour runs slot by
// slot, in order, on the calling thread.
//
// Cost: O(bodies) per substep for integration, O(points) per pass, 3 passes a
// substep (warm start, solve, relax), one parallel loop per colour and pass; the
// colouring, the overflow colour and the copy of the deep manifolds are serial.
#pragma once

#include <cstdint>
#include <span>

#include "host/body_store.h"
#include "host/buffer.h"
#include "host/contact_manifolds.h"
#include "host/parallel.h"
#include "host/plane_store.h"
#include "host/radix_sort.h"
#include "host/solver/contact_solver.h"
#include "impact/world.h"
#include "kernels/solver/graph_colouring.h"
#include "kernels/solver/soft_contact.h"

namespace impact::host {

class SoftStepSolver {
 public:
  /// Solves and integrates one step of dt: velocities, positions and orientations of
  /// `bodies` move; the force accumulators are left for the caller to clear. inv_mass:
  /// the inverse masses the solver sees, bodies.inv_mass or a copy with the asleep
  /// bodies' zeroed (host/pipeline/sleep_stage.cpp): those stay where they are, and a
  /// manifold that moves no body is not solved (it keeps last step's impulses).
  void step(const Executor& exec, const WorldDesc& desc, const ContactManifolds& c, BodyStore& bodies,
            const PlaneStore& planes, float dt, const float* inv_mass);
  /// Body slots were permuted (inv_perm[old slot] = new slot, n bodies).
  void remap_bodies(const Executor& exec, const uint32_t* inv_perm, uint32_t n);
  /// Slots were removed or reused: last step's impulses no longer apply.
  void forget() {
    prev_count_ = 0;
    recovery_.forget();
  }
  /// This step has no contact results.
  void clear_impulses() {
    impulse_out_.clear();
    recovery_.clear_impulses();
  }
  /// Accumulated normal impulse per contact point of the last step, N s.
  std::span<const float> impulses() const { return {impulse_out_.data(), impulse_out_.size()}; }

 private:
  // wide(blocks) over each colour's blocks in chunks (whole blocks, in parallel), colour
  // after colour, then serial(slots) over the overflow colour on this thread.
  template <class Wide, class Serial>
  void for_each_colour(const Executor& exec, Wide&& wide, Serial&& serial) const;
  // Copies the solved manifolds (colour not left out) deeper than deep_depth into deep_
  // (rows into deep_rows_).
  void gather_deep(const kernels::ContactManifoldArrays& c, uint32_t manifolds, float deep_depth,
                   const uint8_t* colour);

  RadixSorter sorter_;
  Buffer<kernels::SolverBody> bodies_;  // entry n: the zero body of planes
  Buffer<kernels::BodyDrive> drive_;
  Buffer<kernels::Sym3> inv_inertia_;
  Buffer<kernels::Vec3> com_;
  Buffer<kernels::GyroBody> gyro_;             // when rotating bodies take the gyroscopic term
  Buffer<uint32_t> body_masks_;
  Buffer<uint8_t> colour_;
  Buffer<uint32_t> order_;                     // constraint slot -> manifold (kNoConstraint: padding)
  Buffer<kernels::ContactBlock> blocks_;       // the constraints, kContactLanes a block
  Buffer<uint64_t> keys_;                      // this step's point keys
  Buffer<kernels::WarmPoint> warm_;            // matched last-step values per point row
  Buffer<kernels::WarmPoint> stored_;          // this step's values per point row
  Buffer<uint64_t> prev_keys_;                 // last step's, sorted
  Buffer<uint32_t> prev_index_;                // their rows in prev_values_
  Buffer<uint32_t> prev_start_;                // per body a: range in prev_keys_
  Buffer<kernels::WarmPoint> prev_values_;
  Buffer<float> impulse_out_;
  ContactManifolds deep_;                      // this step's deep manifolds
  Buffer<uint32_t> deep_rows_;                 // their points' rows in the step's manifolds
  ContactSolver recovery_;                     // the Jacobi solver, on deep_ only
  uint32_t prev_count_ = 0, prev_body_count_ = 0;
  uint32_t colour_start_[kernels::kOverflowColour + 2] = {};  // first slot per colour (block aligned)
  uint32_t colour_count_[kernels::kOverflowColour + 1] = {};  // constraints per colour
};

}  // namespace impact::host
