// The passes of host::ContactSolver, each a for_each_chunk over a kernel of
// kernels/solver/contact_solver.h: per-body passes by chunks of bodies, per-contact
// passes by chunks of manifolds. Every output element is written by one index and the
// adjacency is sorted, so the bytes do not depend on the thread count.
#include "host/solver/contact_solver.h"

#include <cstring>

#include "kernels/common/permute.h"
#include "kernels/sort/segments.h"

namespace impact::host {
namespace {

constexpr uint32_t kBodyGrain = 1u << 14;      // bodies per chunk
constexpr uint32_t kManifoldGrain = 1u << 13;  // manifolds per chunk
constexpr uint32_t kEntryGrain = 1u << 13;     // CSR entries, keys or points per chunk

kernels::SolverParams params_of(const SolverDesc& d, float dt = 0.0f) {
  return {d.restitution_threshold, d.position_correction, d.penetration_slop, dt};
}

}  // namespace

void ContactSolver::iterate(const Executor& exec, const kernels::ContactManifoldArrays& c, uint32_t manifolds,
                            uint32_t n, uint32_t iterations) {
  const kernels::BodyContacts adj{body_start_.data(), entry_pos_.data(), entry_delta_.data()};
  const kernels::SolverRows r = rows();
  kernels::BodyState* state = state_.data();
  for (uint32_t it = 0; it < iterations; ++it) {
    exec.for_each_chunk(manifolds, kManifoldGrain, [&](uint32_t b, uint32_t e, uint32_t) {
      kernels::contact_solve(c, r, adj, state, n, {b, e});
    });
    exec.for_each_chunk(n, kBodyGrain, [&](uint32_t b, uint32_t e, uint32_t) {
      kernels::body_apply(adj, state, {b, e});
    });
  }
}

void ContactSolver::solve_velocities(const Executor& exec, const SolverDesc& desc, const ContactManifolds& contacts,
                                     BodyStore& s, const float* plane_restitution, float dt) {
  const auto n = static_cast<uint32_t>(s.size());
  const auto nm = static_cast<uint32_t>(contacts.manifolds);
  const auto np = static_cast<uint32_t>(contacts.points);
  if (np == 0) {
    prev_contacts_ = 0;
    impulse_out_.clear();
    return;
  }
  const kernels::ContactManifoldArrays c = contacts.view();
  scratch(mass_, np);
  scratch(target_, np);
  scratch(impulse_, np);
  const kernels::SolverRows r = rows();
  // Hot per-body state; entry n is the immovable zero body that planes use.
  kernels::BodyState* state = scratch(state_, static_cast<size_t>(n) + 1);
  state[n] = kernels::BodyState{0.0f, 0.0f, 0.0f, 0.0f};
  exec.for_each_chunk(n, kBodyGrain, [&](uint32_t b, uint32_t e, uint32_t) {
    kernels::pack_velocity_state(s.vel_x.data(), s.vel_y.data(), s.vel_z.data(), s.inv_mass.data(), state, {b, e});
  });
  // Body -> contact adjacency (CSR) by sorting (body, 2*point+side) keys.
  const uint32_t nk = 2 * np;
  uint64_t* keys = scratch(csr_keys_, nk);
  exec.for_each_chunk(nm, kManifoldGrain, [&](uint32_t b, uint32_t e, uint32_t) {
    kernels::contact_body_keys(c, s.inv_mass.data(), n, keys, {b, e});
  });
  sorter_.sort(exec, keys, nk, 32, 32 + bits_for(n));
  uint32_t* start = scratch(body_start_, static_cast<size_t>(n) + 1);
  exec.for_each_chunk(nk, kEntryGrain, [&](uint32_t b, uint32_t e, uint32_t) {
    kernels::segment_starts(keys, nk, 32, n, start, {b, e});
  });
  uint32_t* pos = scratch(entry_pos_, nk);
  exec.for_each_chunk(nk, kEntryGrain, [&](uint32_t b, uint32_t e, uint32_t) {
    kernels::contact_entry_positions(keys, pos, {b, e});
  });
  scratch(entry_delta_, 4ull * nk);
  const kernels::BodyContacts adj{start, pos, entry_delta_.data()};
  const kernels::SolverParams sp = params_of(desc, dt);
  exec.for_each_chunk(nm, kManifoldGrain, [&](uint32_t b, uint32_t e, uint32_t) {
    kernels::contact_prepare(sp, c, r, state, n, s.restitution.data(), plane_restitution, adj, {b, e});
  });

  // Warm start from last step's impulses of the same (a, b, feature) contacts.
  uint64_t* pkeys = scratch(pair_keys_, np);
  exec.for_each_chunk(nm, kManifoldGrain, [&](uint32_t b, uint32_t e, uint32_t) {
    kernels::contact_pair_keys(c, pkeys, {b, e});
  });
  if (desc.warm_start > 0.0f && prev_contacts_ > 0) {
    const kernels::WarmStart ws{prev_keys_.data(), prev_impulse_.data(), prev_start_.data(), prev_body_count_,
                                desc.warm_start};
    exec.for_each_chunk(nm, kManifoldGrain, [&](uint32_t b, uint32_t e, uint32_t) {
      kernels::contact_warm_start(c, r, adj, pkeys, ws, {b, e});
    });
    exec.for_each_chunk(n, kBodyGrain, [&](uint32_t b, uint32_t e, uint32_t) {
      kernels::body_apply(adj, state, {b, e});
    });
  }
  iterate(exec, c, nm, n, desc.velocity_iterations);
  exec.for_each_chunk(n, kBodyGrain, [&](uint32_t b, uint32_t e, uint32_t) {
    kernels::unpack_velocity_state(state, s.vel_x.data(), s.vel_y.data(), s.vel_z.data(), {b, e});
  });

  // Remember (key, impulse) sorted by key, and per-body ranges, for the next warm start.
  uint64_t* pk = scratch(prev_keys_, np);
  float* pi = scratch(prev_impulse_, np);
  std::memcpy(pk, pkeys, sizeof(uint64_t) * np);
  std::memcpy(pi, impulse_.data(), sizeof(float) * np);
  sorter_.sort_kv(exec, pk, reinterpret_cast<uint32_t*>(pi), np, 0, 32 + bits_for(n));
  uint32_t* ps = scratch(prev_start_, static_cast<size_t>(n) + 1);
  exec.for_each_chunk(np, kEntryGrain, [&](uint32_t b, uint32_t e, uint32_t) {
    kernels::segment_starts(pk, np, 32, n, ps, {b, e});
  });
  prev_contacts_ = np;
  prev_body_count_ = n;
  impulse_out_.assign(impulse_.begin(), impulse_.begin() + np);
}

void ContactSolver::correct_positions(const Executor& exec, const SolverDesc& desc, const ContactManifolds& contacts,
                                      BodyStore& s, float dt) {
  const auto n = static_cast<uint32_t>(s.size());
  const auto nm = static_cast<uint32_t>(contacts.manifolds);
  if (contacts.points == 0 || desc.position_iterations == 0 || !(desc.position_correction > 0.0f)) return;
  const kernels::ContactManifoldArrays c = contacts.view();
  const kernels::SolverParams sp = params_of(desc);
  kernels::BodyState* state = state_.data();
  // Targets from the depth the solved velocities (still in state) leave after this step.
  exec.for_each_chunk(nm, kManifoldGrain, [&](uint32_t b, uint32_t e, uint32_t) {
    kernels::contact_position_target(sp, c, rows(), state, n, dt, {b, e});
  });
  // The same iteration on displacements (the rows' impulse and target reused).
  exec.for_each_chunk(n, kBodyGrain, [&](uint32_t b, uint32_t e, uint32_t) {
    kernels::pack_displacement_state(s.inv_mass.data(), state, {b, e});
  });
  iterate(exec, c, nm, n, desc.position_iterations);
  exec.for_each_chunk(n, kBodyGrain, [&](uint32_t b, uint32_t e, uint32_t) {
    kernels::commit_displacement_state(state, s.pos_x.data(), s.pos_y.data(), s.pos_z.data(), {b, e});
  });
}

void ContactSolver::remap_bodies(const Executor& exec, const uint32_t* inv_perm, uint32_t n) {
  impulse_out_.clear();
  if (prev_contacts_ == 0) return;
  exec.for_each_chunk(prev_contacts_, kEntryGrain, [&](uint32_t b, uint32_t e, uint32_t) {
    kernels::remap_pair_keys(inv_perm, prev_keys_.data(), {b, e});
  });
  sorter_.sort_kv(exec, prev_keys_.data(), reinterpret_cast<uint32_t*>(prev_impulse_.data()), prev_contacts_, 0,
                  32 + bits_for(n));
  uint32_t* ps = scratch(prev_start_, static_cast<size_t>(n) + 1);
  exec.for_each_chunk(prev_contacts_, kEntryGrain, [&](uint32_t b, uint32_t e, uint32_t) {
    kernels::segment_starts(prev_keys_.data(), prev_contacts_, 32, n, ps, {b, e});
  });
}

}  // namespace impact::host
