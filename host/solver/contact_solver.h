// host::ContactSolver: the contact solver of a World's step (kernels/solver/contact_solver.h
// has the method: Jacobi iteration with mass splitting, warm starting, position
// correction on displacements). It reads the step's manifolds (host::ContactManifolds),
// owns every array the solve needs (the body -> contact adjacency, one row per contact
// point, the hot body state) and last step's impulses for warm starting, and writes
// velocities and positions back into the body store.
//
// Per step: solve_velocities (after the narrow phase), then the positions move, then
// correct_positions. Between steps, remap_bodies / forget keep the warm-start cache
// meaningful when slots move.
// Cost per step: two radix sorts of 2 keys per contact point, then per iteration one
// pass over the points and one over the bodies (docs/solver.md).
#pragma once

#include <cstdint>
#include <span>

#include "host/body_store.h"
#include "host/buffer.h"
#include "host/contact_manifolds.h"
#include "host/parallel.h"
#include "host/radix_sort.h"
#include "impact/world.h"
#include "kernels/solver/contact_solver.h"

namespace impact::host {

class ContactSolver {
 public:
  /// Builds the rows of c's points, warm starts them from last step's impulses, runs
  /// desc.velocity_iterations and writes the velocities of `bodies` back; keeps the
  /// impulses for the next step's warm start and for impulses(). plane_restitution:
  /// per plane of c's b_is_plane manifolds. dt: the step, for speculative points
  /// (depth < 0: kernels::SolverParams::dt) when WorldDesc::ccd asks for them; 0 keeps
  /// the points of a manifold that lie apart (clipped box faces) on the plain target.
  void solve_velocities(const Executor& exec, const SolverDesc& desc, const ContactManifolds& c,
                        BodyStore& bodies, const float* plane_restitution, float dt);
  /// After the positions moved with the solved velocities: desc.position_iterations on
  /// displacements toward position_correction * (depth left - slop), added to the
  /// positions. A no-op when position correction is off or there were no contacts.
  void correct_positions(const Executor& exec, const SolverDesc& desc, const ContactManifolds& c,
                         BodyStore& bodies, float dt);
  /// Body slots were permuted (inv_perm[old slot] = new slot, n bodies): last step's
  /// impulses follow their bodies.
  void remap_bodies(const Executor& exec, const uint32_t* inv_perm, uint32_t n);
  /// Slots were removed or reused: last step's impulses no longer apply.
  void forget() { prev_contacts_ = 0; }
  /// This step has no contact results (a failed step, or slots renumbered).
  void clear_impulses() { impulse_out_.clear(); }
  /// Accumulated normal impulse of each contact point of the last solve, N s.
  std::span<const float> impulses() const { return {impulse_out_.data(), impulse_out_.size()}; }

 private:
  kernels::SolverRows rows() { return {mass_.data(), target_.data(), impulse_.data()}; }
  void iterate(const Executor& exec, const kernels::ContactManifoldArrays& c, uint32_t manifolds, uint32_t n,
               uint32_t iterations);

  RadixSorter sorter_;
  Buffer<float> mass_, target_, impulse_;  // one row per contact point
  Buffer<uint64_t> csr_keys_;              // (body << 32) | (2 * point + side), sorted
  Buffer<uint32_t> body_start_;            // per body: its first CSR entry
  Buffer<uint32_t> entry_pos_;             // CSR position of each (point, side)
  Buffer<float> entry_delta_;              // 4 floats per CSR entry
  Buffer<kernels::BodyState> state_;       // hot per-body state; entry n is the zero body
  Buffer<uint64_t> pair_keys_;             // this step's contact keys
  Buffer<uint64_t> prev_keys_;             // last step's, sorted, for warm starting
  Buffer<float> prev_impulse_;             // their impulses
  Buffer<uint32_t> prev_start_;            // per body a: range in prev_keys
  uint32_t prev_contacts_ = 0;
  uint32_t prev_body_count_ = 0;
  Buffer<float> impulse_out_;              // the last solve's impulses, for impulses()
};

}  // namespace impact::host
