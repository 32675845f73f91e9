// One fixed step of a sphere world as a sequence of flat passes:
//   integrate velocities (gravity) -> bounds -> broad phase
//   -> narrow phase (sphere-sphere on pairs, sphere-plane on bodies), on the
//      poses the step starts from
//   -> contact solve (warm start + velocity iterations)
//   -> integrate positions with the solved velocities (semi-implicit Euler)
//   -> position correction (iterations on displacements).
// Solving velocities before positions move keeps resting contacts from sinking
// by g dt^2 every step. Every pass is for_each_chunk over a kernel;
// variable-size outputs use count -> scan -> write or chunk-local buffers, so
// results are identical for any thread count.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <string>

#include "host/world_impl.h"
#include "kernels/broadphase/bounds.h"
#include "kernels/common/permute.h"
#include "kernels/integrate/semi_implicit_euler.h"
#include "kernels/narrowphase/sphere_plane.h"
#include "kernels/narrowphase/sphere_sphere.h"
#include "kernels/solver/contact_solver.h"
#include "kernels/sort/segments.h"

namespace impact {
namespace {

using Clock = std::chrono::steady_clock;

double ms_since(Clock::time_point& t) {
  const auto now = Clock::now();
  const double ms = std::chrono::duration<double, std::milli>(now - t).count();
  t = now;
  return ms;
}

constexpr uint32_t kBodyGrain = 1u << 14;     // bodies per chunk, streaming passes
constexpr float kMaxCoordinate = 1e18f;       // m; the API's limit on positions

bool in_range(const kernels::BoundsSummary& s) {
  for (int k = 0; k < 3; ++k)
    if (!(std::fabs(s.lo[k]) <= kMaxCoordinate && std::fabs(s.hi[k]) <= kMaxCoordinate)) return false;
  return std::isfinite(s.max_edge);
}
constexpr uint32_t kContactGrain = 1u << 13;  // contacts or pairs per chunk

}  // namespace

void ContactStore::resize(size_t n) {
  for (auto* v : {&a, &b}) v->resize(n);
  b_is_plane.resize(n);
  point.resize(n);
  for (auto* v : {&normal_x, &normal_y, &normal_z, &depth, &point_x, &point_y, &point_z, &mass,
                  &target, &impulse})
    v->resize(n);
  count = n;
}

void WorldImpl::reorder_bodies() {
  const uint32_t n = static_cast<uint32_t>(bodies.size());
  if (broad_phase.size() != n || n < 2) return;
  uint32_t* p = host::scratch(perm, n);
  if (!broad_phase.spatial_order(exec, p)) return;
  uint32_t* inv = host::scratch(inv_perm, n);
  exec.for_each_chunk(n, kBodyGrain, [&](uint32_t b, uint32_t e, uint32_t) {
    kernels::invert_permutation(p, inv, {b, e});
  });
  auto permute = [&](auto& v, auto& tmp) {
    if (v.size() != n) return;  // optional arrays that are off
    auto* dst = host::scratch(tmp, n);
    exec.for_each_chunk(n, kBodyGrain, [&](uint32_t b, uint32_t e, uint32_t) {
      kernels::gather(v.data(), p, dst, {b, e});
    });
    exec.for_each_chunk(n, kBodyGrain, [&](uint32_t b, uint32_t e, uint32_t) {
      std::memcpy(v.data() + b, dst + b, sizeof(v[0]) * (e - b));
    });
  };
  BodyStore& s = bodies;
  for (auto* v : {&s.pos_x, &s.pos_y, &s.pos_z, &s.vel_x, &s.vel_y, &s.vel_z, &s.inv_mass, &s.radius,
                  &s.restitution, &s.prev_x, &s.prev_y, &s.prev_z})
    permute(*v, tmp_f32);
  permute(s.layer, tmp_u32);
  permute(s.mask, tmp_u32);
  permute(s.is_static, tmp_u8);
  permute(s.shape, tmp_u32);
  for (auto* v : {&s.qx, &s.qy, &s.qz, &s.qw}) permute(*v, tmp_f32);
  std::vector<BodyHandle> handles(n);
  for (uint32_t i = 0; i < n; ++i) {
    handles[i] = s.handle[p[i]];
    body_handles.rebind(handles[i].index, i);
  }
  s.handle.swap(handles);
  // Last step's contact keys name slots: renumber them and restore their order.
  if (prev_contacts > 0) {
    exec.for_each_chunk(prev_contacts, kContactGrain, [&](uint32_t b, uint32_t e, uint32_t) {
      kernels::remap_pair_keys(inv, prev_keys.data(), {b, e});
    });
    sorter.sort_kv(exec, prev_keys.data(), reinterpret_cast<uint32_t*>(prev_impulse.data()), prev_contacts,
                   0, 32 + host::bits_for(n));
    uint32_t* ps = host::scratch(prev_start, static_cast<size_t>(n) + 1);
    exec.for_each_chunk(prev_contacts, kContactGrain, [&](uint32_t b, uint32_t e, uint32_t) {
      kernels::segment_starts(prev_keys.data(), prev_contacts, 32, n, ps, {b, e});
    });
  }
  // Results of the last step name old slots; so does a coherent structure's state.
  broad_phase.invalidate();
  positions_changed();
  pairs.clear();
  contacts.resize(0);
  impulse_out.clear();
}

Status WorldImpl::prepare_queries() {
  if (queries_fresh && broad_phase.built()) return Status();
  const uint32_t n = static_cast<uint32_t>(bodies.size());
  const BodyStore& s = bodies;
  const kernels::AabbSoAOut out{host::scratch(box[0], n), host::scratch(box[1], n), host::scratch(box[2], n),
                                host::scratch(box[3], n), host::scratch(box[4], n), host::scratch(box[5], n)};
  exec.for_each_chunk(n, kBodyGrain, [&](uint32_t b, uint32_t e, uint32_t) {
    kernels::sphere_bounds(s.pos_x.data(), s.pos_y.data(), s.pos_z.data(), s.radius.data(), out, {b, e});
  });
  const kernels::AabbSoA boxes{out.min_x, out.min_y, out.min_z, out.max_x, out.max_y, out.max_z};
  const kernels::PairFilter filter{s.layer.data(), s.mask.data(), s.is_static.data()};
  // Positions are validated at the API and by every step's range check, so the
  // boxes are finite.
  if (Status st = broad_phase.update(exec, boxes, filter, n); !st.ok()) return st;
  queries_fresh = true;
  return Status();
}

Status WorldImpl::step() {
  StepStats& st = last;
  st = StepStats{};
  const auto t_start = Clock::now();
  auto t = t_start;
  if (desc.reorder_interval > 0 && ++steps_since_reorder >= desc.reorder_interval) {
    steps_since_reorder = 0;
    reorder_bodies();
  }
  const uint32_t n = static_cast<uint32_t>(bodies.size());
  const float dt = desc.fixed_dt;
  BodyStore& s = bodies;
  positions_changed();  // the step moves bodies (and its structure sees start poses)

  // --- integrate (semi-implicit Euler) -------------------------------------------------
  if (desc.interpolation) {
    exec.for_each_chunk(n, kBodyGrain, [&](uint32_t b, uint32_t e, uint32_t) {
      const size_t bytes = sizeof(float) * (e - b);
      std::memcpy(s.prev_x.data() + b, s.pos_x.data() + b, bytes);
      std::memcpy(s.prev_y.data() + b, s.pos_y.data() + b, bytes);
      std::memcpy(s.prev_z.data() + b, s.pos_z.data() + b, bytes);
    });
  }
  const kernels::Vec3f g{desc.gravity.x(), desc.gravity.y(), desc.gravity.z()};
  exec.for_each_chunk(n, kBodyGrain, [&](uint32_t b, uint32_t e, uint32_t) {
    kernels::integrate_velocities(dt, g, s.inv_mass.data(), s.vel_x.data(), s.vel_y.data(),
                                  s.vel_z.data(), {b, e});
  });
  st.ms.integrate = ms_since(t);

  // --- bounds ----------------------------------------------------------------------------
  kernels::AabbSoAOut boxes_out{host::scratch(box[0], n), host::scratch(box[1], n),
                                host::scratch(box[2], n), host::scratch(box[3], n),
                                host::scratch(box[4], n), host::scratch(box[5], n)};
  if (desc.swept_bounds) {
    exec.for_each_chunk(n, kBodyGrain, [&](uint32_t b, uint32_t e, uint32_t) {
      kernels::swept_sphere_bounds(s.pos_x.data(), s.pos_y.data(), s.pos_z.data(), s.vel_x.data(),
                                   s.vel_y.data(), s.vel_z.data(), s.radius.data(), dt, boxes_out, {b, e});
    });
  } else {
    exec.for_each_chunk(n, kBodyGrain, [&](uint32_t b, uint32_t e, uint32_t) {
      kernels::sphere_bounds(s.pos_x.data(), s.pos_y.data(), s.pos_z.data(), s.radius.data(),
                             boxes_out, {b, e});
    });
  }
  if (shaped_count > 0) shaped_bounds(boxes_out, desc.swept_bounds ? dt : 0.0f);
  const kernels::AabbSoA boxes{boxes_out.min_x, boxes_out.min_y, boxes_out.min_z,
                               boxes_out.max_x, boxes_out.max_y, boxes_out.max_z};
  // Finite inputs can still integrate out of range (a huge speed for long enough):
  // stop before Inf or NaN reaches the grid's cell arithmetic or the sort keys.
  const kernels::BoundsSummary summary = host::summarize_bounds(exec, boxes, n, bounds_partials);
  if (n > 0 && !in_range(summary)) {
    for (uint32_t i = 0; i < n; ++i) {
      const float v[6] = {boxes.min_x[i], boxes.min_y[i], boxes.min_z[i], boxes.max_x[i], boxes.max_y[i], boxes.max_z[i]};
      for (float x : v) {
        if (!(std::fabs(x) <= kMaxCoordinate)) {
          pairs.clear();
          contacts.resize(0);
          impulse_out.clear();
          const BodyHandle h = s.handle[i];
          return Status(StatusCode::kInvalidArgument,
                        "step: body {index " + std::to_string(h.index) + ", generation " +
                            std::to_string(h.generation) + "} position (" + std::to_string(s.pos_x[i]) + ", " +
                            std::to_string(s.pos_y[i]) + ", " + std::to_string(s.pos_z[i]) +
                            ") left the supported range |x| <= 1e18 m (velocity (" + std::to_string(s.vel_x[i]) +
                            ", " + std::to_string(s.vel_y[i]) + ", " + std::to_string(s.vel_z[i]) +
                            ")); fix it with set_positions/set_velocities or destroy it");
        }
      }
    }
  }
  st.ms.bounds = ms_since(t);

  // --- broad phase -------------------------------------------------------------------------
  const kernels::PairFilter filter{s.layer.data(), s.mask.data(), s.is_static.data()};
  const Status bp = broad_phase.find_pairs(exec, boxes, filter, n, &pairs, &summary);
  if (!bp.ok()) {  // more pairs than 32-bit indices can hold: never drop them silently
    contacts.resize(0);
    return bp;
  }
  st.pairs = pairs.size();
  st.ms.broad_phase = ms_since(t);

  // --- narrow phase ----------------------------------------------------------------------
  ContactStore& c = contacts;
  if (shaped_count > 0) {
    if (Status gs = general_narrow_phase(); !gs.ok()) {
      contacts.resize(0);
      return gs;
    }
  } else {
  const kernels::SphereView sv{s.pos_x.data(), s.pos_y.data(), s.pos_z.data(), s.radius.data()};
  const kernels::PlaneView pv{planes.normal_x.data(), planes.normal_y.data(),
                              planes.normal_z.data(), planes.offset.data(),
                              planes.layer.data(),    planes.mask.data(),
                              static_cast<uint32_t>(planes.size())};
  const kernels::BodyFilter bf{s.inv_mass.data(), s.layer.data(), s.mask.data()};
  const uint32_t np = static_cast<uint32_t>(pairs.size());
  const uint64_t n_pair_contacts = host::count_and_scan(
      exec, np, kContactGrain, pair_offsets,
      [&](uint32_t b, uint32_t e) { return kernels::sphere_sphere_count(pairs.data(), sv, {b, e}); });
  const uint64_t n_plane_contacts =
      pv.count == 0 ? 0
                    : host::count_and_scan(exec, n, kBodyGrain, plane_offsets, [&](uint32_t b, uint32_t e) {
                        return kernels::sphere_plane_count(sv, bf, pv, {b, e});
                      });
  // Two keys per contact index the solver's CSR with 32 bits.
  if (n_pair_contacts + n_plane_contacts > 0x7fffffffull) {
    contacts.resize(0);
    return Status(StatusCode::kCapacityExceeded,
                  "step: " + std::to_string(n_pair_contacts + n_plane_contacts) +
                      " contacts exceed the limit of 2^31 - 1");
  }
  c.resize(n_pair_contacts + n_plane_contacts);
  const kernels::ContactSoA cs{c.a.data(),        c.b.data(),        c.b_is_plane.data(),
                               c.normal_x.data(), c.normal_y.data(), c.normal_z.data(),
                               c.depth.data(),    c.point_x.data(),  c.point_y.data(),
                               c.point_z.data()};
  exec.for_each_chunk(np, kContactGrain, [&](uint32_t b, uint32_t e, uint32_t k) {
    kernels::sphere_sphere_write(pairs.data(), sv, cs, pair_offsets[k], {b, e});
  });
  if (n_plane_contacts > 0) {
    exec.for_each_chunk(n, kBodyGrain, [&](uint32_t b, uint32_t e, uint32_t k) {
      kernels::sphere_plane_write(sv, bf, pv, cs, n_pair_contacts + plane_offsets[k], {b, e});
    });
  }
  st.contacts = c.count;
  st.plane_contacts = n_plane_contacts;
  }
  st.ms.narrow_phase = ms_since(t);

  // Positions move with the solved velocities (semi-implicit Euler's second half).
  double positions_ms = 0.0;
  auto integrate_positions = [&] {
    const auto t0 = Clock::now();
    exec.for_each_chunk(n, kBodyGrain, [&](uint32_t b, uint32_t e, uint32_t) {
      kernels::integrate_positions(dt, s.vel_x.data(), s.vel_y.data(), s.vel_z.data(), s.pos_x.data(),
                                   s.pos_y.data(), s.pos_z.data(), {b, e});
    });
    positions_ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
  };

  // --- contact solver ----------------------------------------------------------------------
  const uint32_t nc = static_cast<uint32_t>(c.count);
  const SolverDesc& sd = desc.solver;
  if (nc > 0) {
    const kernels::SolverContacts sc{c.a.data(),        c.b.data(),         c.b_is_plane.data(),
                                     c.normal_x.data(), c.normal_y.data(),  c.normal_z.data(),
                                     c.depth.data(),    c.mass.data(),      c.target.data(),
                                     c.impulse.data(),  shaped_count > 0 ? c.point.data() : nullptr};
    const kernels::SolverParams sp{sd.restitution_threshold, sd.position_correction,
                                   sd.penetration_slop};
    // Hot per-body state; entry n is the immovable zero body that planes use.
    kernels::BodyState* state = host::scratch(solver_state, static_cast<size_t>(n) + 1);
    state[n] = kernels::BodyState{0.0f, 0.0f, 0.0f, 0.0f};
    exec.for_each_chunk(n, kBodyGrain, [&](uint32_t b, uint32_t e, uint32_t) {
      kernels::pack_velocity_state(s.vel_x.data(), s.vel_y.data(), s.vel_z.data(), s.inv_mass.data(),
                                   state, {b, e});
    });
    // Body -> contact adjacency (CSR) by sorting (body, 2*contact+side) keys.
    const uint32_t nk = 2 * nc;
    uint64_t* keys = host::scratch(csr_keys, nk);
    exec.for_each_chunk(nc, kContactGrain, [&](uint32_t b, uint32_t e, uint32_t) {
      kernels::contact_body_keys(sc, s.inv_mass.data(), n, keys, {b, e});
    });
    sorter.sort(exec, keys, nk, 32, 32 + host::bits_for(n));
    uint32_t* start = host::scratch(body_start, static_cast<size_t>(n) + 1);
    exec.for_each_chunk(nk, kContactGrain, [&](uint32_t b, uint32_t e, uint32_t) {
      kernels::segment_starts(keys, nk, 32, n, start, {b, e});
    });
    uint32_t* pos = host::scratch(entry_pos, nk);
    exec.for_each_chunk(nk, kContactGrain, [&](uint32_t b, uint32_t e, uint32_t) {
      kernels::contact_entry_positions(keys, pos, {b, e});
    });
    const kernels::BodyContacts adj{start, pos, host::scratch(entry_delta, 4ull * nk)};
    auto iterate = [&](uint32_t iterations) {
      for (uint32_t it = 0; it < iterations; ++it) {
        exec.for_each_chunk(nc, kContactGrain, [&](uint32_t b, uint32_t e, uint32_t) {
          kernels::contact_solve(sc, adj, state, n, {b, e});
        });
        exec.for_each_chunk(n, kBodyGrain, [&](uint32_t b, uint32_t e, uint32_t) {
          kernels::body_apply(adj, state, {b, e});
        });
      }
    };
    exec.for_each_chunk(nc, kContactGrain, [&](uint32_t b, uint32_t e, uint32_t) {
      kernels::contact_prepare(sp, sc, state, n, s.restitution.data(), planes.restitution.data(), adj,
                               {b, e});
    });

    // Warm start from last step's impulses of the same (a, b) contacts.
    uint64_t* pkeys = host::scratch(pair_keys, nc);
    exec.for_each_chunk(nc, kContactGrain, [&](uint32_t b, uint32_t e, uint32_t) {
      kernels::contact_pair_keys(sc, pkeys, {b, e});
    });
    if (sd.warm_start > 0.0f && prev_contacts > 0) {
      const kernels::WarmStart ws{prev_keys.data(), prev_impulse.data(), prev_start.data(),
                                  prev_body_count, sd.warm_start};
      exec.for_each_chunk(nc, kContactGrain, [&](uint32_t b, uint32_t e, uint32_t) {
        kernels::contact_warm_start(sc, adj, pkeys, ws, {b, e});
      });
      exec.for_each_chunk(n, kBodyGrain, [&](uint32_t b, uint32_t e, uint32_t) {
        kernels::body_apply(adj, state, {b, e});
      });
    }
    iterate(sd.velocity_iterations);
    exec.for_each_chunk(n, kBodyGrain, [&](uint32_t b, uint32_t e, uint32_t) {
      kernels::unpack_velocity_state(state, s.vel_x.data(), s.vel_y.data(), s.vel_z.data(), {b, e});
    });

    // Remember (key, impulse) sorted by key, and per-body ranges, for the next warm start.
    uint64_t* pk = host::scratch(prev_keys, nc);
    float* pi = host::scratch(prev_impulse, nc);
    std::memcpy(pk, pkeys, sizeof(uint64_t) * nc);
    std::memcpy(pi, c.impulse.data(), sizeof(float) * nc);
    sorter.sort_kv(exec, pk, reinterpret_cast<uint32_t*>(pi), nc, 0, 32 + host::bits_for(n));
    uint32_t* ps = host::scratch(prev_start, static_cast<size_t>(n) + 1);
    exec.for_each_chunk(nc, kContactGrain, [&](uint32_t b, uint32_t e, uint32_t) {
      kernels::segment_starts(pk, nc, 32, n, ps, {b, e});
    });
    prev_contacts = nc;
    prev_body_count = n;
    impulse_out.assign(c.impulse.begin(), c.impulse.begin() + nc);

    const bool correct = sd.position_iterations > 0 && sd.position_correction > 0.0f;
    if (correct) {  // targets from the depth the solved velocities leave after this step
      exec.for_each_chunk(nc, kContactGrain, [&](uint32_t b, uint32_t e, uint32_t) {
        kernels::contact_position_target(sp, sc, state, n, dt, {b, e});
      });
    }
    integrate_positions();
    if (correct) {
      // The same iteration on displacements (impulse/target reused as scratch).
      exec.for_each_chunk(n, kBodyGrain, [&](uint32_t b, uint32_t e, uint32_t) {
        kernels::pack_displacement_state(s.inv_mass.data(), state, {b, e});
      });
      iterate(sd.position_iterations);
      exec.for_each_chunk(n, kBodyGrain, [&](uint32_t b, uint32_t e, uint32_t) {
        kernels::commit_displacement_state(state, s.pos_x.data(), s.pos_y.data(), s.pos_z.data(), {b, e});
      });
    }
  } else {
    prev_contacts = 0;
    impulse_out.clear();
    integrate_positions();
  }
  st.ms.solve = ms_since(t) - positions_ms;
  st.ms.integrate += positions_ms;
  st.ms.total = std::chrono::duration<double, std::milli>(Clock::now() - t_start).count();
  return Status();
}

}  // namespace impact
