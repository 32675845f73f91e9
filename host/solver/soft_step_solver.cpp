// The passes of host::SoftStepSolver (see soft_step_solver.h): per-body passes by
// chunks of bodies, per-constraint passes by chunks of one colour's constraints, the
// colouring and the overflow colour on the calling thread. Every output element is
// written by one index, so the bytes do not depend on the thread count.
#include "host/solver/soft_step_solver.h"

#include <cstring>

#include "host/pipeline/step_context.h"
#include "kernels/common/permute.h"
#include "kernels/solver/contact_solver.h"
#include "kernels/sort/segments.h"

namespace impact::host {
namespace {

// Grains. The per-substep passes of a small scene are short (a 1240-box pyramid has
// ~150 constraints a colour and ~1.2k bodies), so they split into chunks down to the
// minimum grains, about four per thread; large scenes take bigger chunks and pay
// less scheduling. Chunks never change the bytes: bodies, and one colour's
// constraints, are independent of each other.
constexpr uint32_t kMinBodyGrain = 1u << 8;     // bodies per chunk, at least
constexpr uint32_t kConstraintGrain = 1u << 9;  // constraint slots per chunk of prepare and store
constexpr uint32_t kMinColourGrain = 1u << 5;   // constraint slots per chunk of a colour's pass, at least
static_assert(kMinColourGrain % kernels::kContactLanes == 0);
constexpr uint32_t kPointGrain = 1u << 13;      // points or keys per chunk
constexpr uint8_t kLeftOut = 0xff;              // colour of a manifold between asleep or static bodies
static_assert(kernels::kOverflowColour < kLeftOut);

// About four chunks per thread of `count` items, at least `min_grain` items each.
uint32_t grain_for(const Executor& exec, uint32_t count, uint32_t min_grain) {
  const uint32_t parts = 4 * std::max(exec.threads(), 1u);
  return std::max(min_grain, (count + parts - 1) / parts);
}
kernels::SoftBodyInput body_input(BodyStore& s, const WorldDesc& desc, kernels::BodyForces* forces,
                                  kernels::BodyDamping* damping) {
  kernels::SoftBodyInput in{};
  in.rotating = s.on(FieldSet::kRigid);
  if (in.rotating) {
    in.rigid = rigid_view(s);
  } else {  // the linear fields only
    in.rigid.vx = s.vel_x.data();
    in.rigid.vy = s.vel_y.data();
    in.rigid.vz = s.vel_z.data();
    in.rigid.px = s.pos_x.data();
    in.rigid.py = s.pos_y.data();
    in.rigid.pz = s.pos_z.data();
    in.rigid.inv_mass = s.inv_mass.data();
  }
  in.gyroscopic = desc.gyroscopic;
  if (s.on(FieldSet::kForces)) {
    *forces = {s.fx.data(), s.fy.data(), s.fz.data(), s.tx.data(), s.ty.data(), s.tz.data()};
    in.forces = forces;
  }
  if (s.on(FieldSet::kDamping)) {
    *damping = {s.linear_damping.data(), s.angular_damping.data(), s.gravity_scale.data()};
    in.damping = damping;
  }
  return in;
}

}  // namespace

template <class Wide, class Serial>
void SoftStepSolver::for_each_colour(const Executor& exec, Wide&& wide, Serial&& serial) const {
  constexpr uint32_t W = kernels::kContactLanes;
  for (uint32_t k = 0; k < kernels::kColourCount; ++k) {
    // Whole blocks: the colour's slots start at a multiple of W and are padded to one.
    const uint32_t b = colour_start_[k] / W, e = b + kernels::contact_blocks(colour_count_[k]);
    if (b == e) continue;
    const uint32_t grain = grain_for(exec, e - b, kMinColourGrain / W);  // in blocks
    exec.for_each_chunk(e - b, grain, [&](uint32_t cb, uint32_t ce, uint32_t) {
      wide(kernels::Range{b + cb, b + ce});
    });
  }
  const uint32_t ob = colour_start_[kernels::kOverflowColour];
  const uint32_t oe = ob + colour_count_[kernels::kOverflowColour];
  if (ob != oe) serial(kernels::Range{ob, oe});  // slot by slot in order, on this thread
}

void SoftStepSolver::gather_deep(const kernels::ContactManifoldArrays& c, uint32_t manifolds, float deep_depth,
                                 const uint8_t* colour) {
  auto deep = [&](uint32_t m) { return c.depth[m] > deep_depth && colour[m] != kLeftOut; };
  uint32_t md = 0, pd = 0;
  for (uint32_t m = 0; m < manifolds; ++m)
    if (deep(m)) {
      ++md;
      pd += c.count[m];
    }
  const bool plain = c.child_a == nullptr && c.feature == nullptr;
  deep_.resize(md, pd, c.first_point == nullptr, plain);
  uint32_t* rows = scratch(deep_rows_, pd);
  uint32_t i = 0, k = 0;
  for (uint32_t m = 0; m < manifolds; ++m) {
    if (!deep(m)) continue;
    deep_.pair[i] = c.pair[m];
    deep_.a[i] = c.a[m];
    deep_.b[i] = c.b[m];
    deep_.b_is_plane[i] = c.b_is_plane[m];
    if (!plain) {
      deep_.child_a[i] = kernels::child_a_of(c, m);
      deep_.child_b[i] = kernels::child_b_of(c, m);
    }
    for (int d = 0; d < 3; ++d) deep_.normal[d][i] = c.normal[d][m];
    deep_.depth[i] = c.depth[m];
    deep_.count[i] = c.count[m];
    if (c.first_point != nullptr) deep_.first_point[i] = k;
    const uint32_t row0 = kernels::first_point_of(c, m);
    for (uint32_t j = 0; j < c.count[m]; ++j, ++k) {
      const uint32_t row = row0 + j;
      rows[k] = row;
      for (int d = 0; d < 3; ++d) deep_.point[d][k] = c.point[d][row];
      deep_.point_depth[k] = c.point_depth[row];
      if (!plain) deep_.feature[k] = kernels::feature_of(c, m, row);
    }
    ++i;
  }
}

void SoftStepSolver::step(const Executor& exec, const WorldDesc& desc, const ContactManifolds& contacts, BodyStore& s,
                          const PlaneStore& planes, float dt, const float* inv_mass) {
  const uint32_t body_grain = grain_for(exec, static_cast<uint32_t>(s.size()), kMinBodyGrain);
  const SolverDesc& sd = desc.solver;
  const auto n = static_cast<uint32_t>(s.size());
  const auto nm = static_cast<uint32_t>(contacts.manifolds);
  const auto np = static_cast<uint32_t>(contacts.points);
  kernels::SoftParams p = kernels::soft_params(dt, sd.substeps, sd.contact_hertz, sd.contact_damping_ratio);
  p.slop = sd.penetration_slop;
  p.max_push_speed = sd.max_push_speed;
  p.restitution_threshold = sd.restitution_threshold;
  p.warm_start = sd.warm_start;
  const kernels::ContactManifoldArrays c = contacts.view();
  // Asleep bodies (inv_mass 0 here, kernels/solver/islands.h) are static to the solver;
  // a manifold with no body it moves is left out and keeps last step's values.
  const bool sleeping = inv_mass != s.inv_mass.data();
  auto moves_a_body = [&](uint32_t m) {
    return inv_mass[c.a[m]] > 0.0f || (c.b_is_plane[m] == 0 && inv_mass[c.b[m]] > 0.0f);
  };

  // Colour, then order the constraints by colour (stable: manifold order within one).
  // The deep manifolds also go to the recovery velocity solve now, before the bodies'
  // velocities are read.
  deep_.clear();
  uint32_t slots = 0;
  const float deep_depth = sd.max_push_speed * dt;
  if (nm > 0) {
    uint32_t* masks = scratch(body_masks_, n);
    std::memset(masks, 0, sizeof(uint32_t) * n);
    uint8_t* colour = scratch(colour_, nm);
    uint32_t counts[kernels::kOverflowColour + 1];
    kernels::colour_manifolds(c, inv_mass, nm, masks, colour, counts);
    if (sleeping)
      for (uint32_t m = 0; m < nm; ++m)
        if (!moves_a_body(m)) {
          --counts[colour[m]];
          colour[m] = kLeftOut;
        }
    // Slots: each colour padded to whole blocks (padding slots: kNoConstraint).
    uint32_t next[kernels::kOverflowColour + 1];
    colour_start_[0] = 0;
    for (uint32_t k = 0; k <= kernels::kOverflowColour; ++k) {
      next[k] = colour_start_[k];
      colour_count_[k] = counts[k];
      colour_start_[k + 1] = colour_start_[k] + kernels::contact_blocks(counts[k]) * kernels::kContactLanes;
    }
    slots = colour_start_[kernels::kOverflowColour + 1];
    uint32_t* order = scratch(order_, slots);
    for (uint32_t i = 0; i < slots; ++i) order[i] = kernels::kNoConstraint;
    for (uint32_t m = 0; m < nm; ++m)
      if (colour[m] != kLeftOut) order[next[colour[m]]++] = m;
    gather_deep(c, nm, deep_depth, colour);
    if (deep_.manifolds > 0)
      recovery_.solve_velocities(exec, sd, deep_, s, planes.restitution.data(), 0.0f);
    else
      recovery_.clear_impulses();
  }

  kernels::BodyForces forces{};
  kernels::BodyDamping damping{};
  kernels::SoftBodyInput in = body_input(s, desc, &forces, &damping);
  in.rigid.inv_mass = inv_mass;
  kernels::SolverBody* bodies = scratch(bodies_, static_cast<size_t>(n) + 1);
  kernels::BodyDrive* drive = scratch(drive_, n);
  kernels::Sym3* ii = scratch(inv_inertia_, n);
  kernels::Vec3* com = scratch(com_, n);
  kernels::GyroBody* gyro = in.rotating && in.gyroscopic ? scratch(gyro_, n) : nullptr;
  const kernels::Vec3 g{desc.gravity.x(), desc.gravity.y(), desc.gravity.z()};
  exec.for_each_chunk(n, body_grain, [&](uint32_t b, uint32_t e, uint32_t) {
    kernels::prepare_bodies(p, g, in, bodies, drive, ii, com, gyro, {b, e});
  });
  bodies[n] = kernels::SolverBody{};
  bodies[n].dq = {0.0f, 0.0f, 0.0f, 1.0f};

  kernels::ContactBlock* blocks = nullptr;
  if (nm > 0) {
    // Last step's impulses of the same contacts (a, b, plane, feature).
    uint64_t* keys = scratch(keys_, np);
    exec.for_each_chunk(nm, kPointGrain, [&](uint32_t b, uint32_t e, uint32_t) {
      kernels::contact_pair_keys(c, keys, {b, e});
    });
    const kernels::WarmPoint* warm = nullptr;
    if (sd.warm_start > 0.0f && prev_count_ > 0) {
      kernels::WarmPoint* w = scratch(warm_, np);
      const kernels::WarmTable table{prev_keys_.data(), prev_index_.data(), prev_start_.data(), prev_values_.data(),
                                     prev_body_count_};
      exec.for_each_chunk(np, kPointGrain, [&](uint32_t b, uint32_t e, uint32_t) {
        kernels::match_warm_points(keys, table, w, {b, e});
      });
      warm = w;
    }
    const kernels::ContactMaterials mat{s.friction.data(), s.restitution.data(), s.rolling.data(),
                                        planes.friction.data(), planes.restitution.data()};
    blocks = scratch(blocks_, slots / kernels::kContactLanes);
    const uint32_t* order = order_.data();
    exec.for_each_chunk(slots, kConstraintGrain, [&](uint32_t b, uint32_t e, uint32_t) {
      kernels::prepare_contacts(p, c, order, bodies, ii, com, n, mat, warm, blocks, {b, e});
    });
  }

  for (uint32_t sub = 0; sub < sd.substeps; ++sub) {
    exec.for_each_chunk(n, body_grain, [&](uint32_t b, uint32_t e, uint32_t) {
      kernels::integrate_substep_velocities(drive, bodies, {b, e});
    });
    if (nm > 0) {
      for_each_colour(
          exec, [&](kernels::Range r) { kernels::warm_start_contacts(blocks, bodies, r); },
          [&](kernels::Range r) { kernels::warm_start_contacts_serial(blocks, bodies, r); });
      for_each_colour(
          exec, [&](kernels::Range r) { kernels::solve_contacts(p, true, blocks, bodies, r); },
          [&](kernels::Range r) { kernels::solve_contacts_serial(p, true, blocks, bodies, r); });
    }
    exec.for_each_chunk(n, body_grain, [&](uint32_t b, uint32_t e, uint32_t) {
      kernels::integrate_substep_positions(p.h, gyro, bodies, {b, e});
    });
    if (nm > 0)
      for_each_colour(
          exec, [&](kernels::Range r) { kernels::solve_contacts(p, false, blocks, bodies, r); },
          [&](kernels::Range r) { kernels::solve_contacts_serial(p, false, blocks, bodies, r); });
  }

  if (nm > 0) {
    for_each_colour(
        exec, [&](kernels::Range r) { kernels::restitute_contacts(p, blocks, bodies, r); },
        [&](kernels::Range r) { kernels::restitute_contacts_serial(p, blocks, bodies, r); });
    // Keep (key, values) for the next step's warm start; the public impulses (a deep
    // point's adds the recovery solve's).
    kernels::WarmPoint* stored = scratch(stored_, np);
    float* out = scratch(impulse_out_, np);
    const uint32_t* order = order_.data();
    exec.for_each_chunk(slots, kConstraintGrain, [&](uint32_t b, uint32_t e, uint32_t) {
      kernels::store_contacts(c, order, blocks, stored, out, {b, e});
    });
    if (sleeping) {  // the left-out manifolds keep last step's values (a step's worth of impulse)
      const kernels::WarmPoint* warm = sd.warm_start > 0.0f && prev_count_ > 0 ? warm_.data() : nullptr;
      const uint8_t* colour = colour_.data();
      for (uint32_t m = 0; m < nm; ++m) {
        if (colour[m] != kLeftOut) continue;
        const uint32_t row0 = kernels::first_point_of(c, m);
        for (uint32_t j = 0; j < c.count[m]; ++j) {
          kernels::WarmPoint w{};
          if (warm != nullptr && warm[row0 + j].normal >= 0.0f) w = warm[row0 + j];
          stored[row0 + j] = w;
          out[row0 + j] = w.normal * static_cast<float>(sd.substeps);
        }
      }
    }
    if (deep_.manifolds > 0) {
      const std::span<const float> deep_impulse = recovery_.impulses();
      const uint32_t* rows = deep_rows_.data();
      for (uint32_t k = 0; k < deep_.points; ++k) out[rows[k]] += deep_impulse[k];
    }
    uint64_t* pk = scratch(prev_keys_, np);
    uint32_t* pi = scratch(prev_index_, np);
    std::memcpy(pk, keys_.data(), sizeof(uint64_t) * np);
    for (uint32_t k = 0; k < np; ++k) pi[k] = k;
    sorter_.sort_kv(exec, pk, pi, np, 0, 32 + bits_for(n));
    std::swap(prev_values_, stored_);
    uint32_t* ps = scratch(prev_start_, static_cast<size_t>(n) + 1);
    exec.for_each_chunk(np, kPointGrain, [&](uint32_t b, uint32_t e, uint32_t) {
      kernels::segment_starts(pk, np, 32, n, ps, {b, e});
    });
    prev_count_ = np;
    prev_body_count_ = n;
  } else {
    prev_count_ = 0;
    impulse_out_.clear();
    recovery_.clear_impulses();
  }

  exec.for_each_chunk(n, body_grain, [&](uint32_t b, uint32_t e, uint32_t) {
    kernels::finish_bodies(in, bodies, com, {b, e});
  });
  if (deep_.manifolds > 0) recovery_.correct_positions(exec, sd, deep_, s, dt);
}

void SoftStepSolver::remap_bodies(const Executor& exec, const uint32_t* inv_perm, uint32_t n) {
  impulse_out_.clear();
  recovery_.remap_bodies(exec, inv_perm, n);
  if (prev_count_ == 0) return;
  exec.for_each_chunk(prev_count_, kPointGrain, [&](uint32_t b, uint32_t e, uint32_t) {
    kernels::remap_pair_keys(inv_perm, prev_keys_.data(), {b, e});
  });
  sorter_.sort_kv(exec, prev_keys_.data(), prev_index_.data(), prev_count_, 0, 32 + bits_for(n));
  uint32_t* ps = scratch(prev_start_, static_cast<size_t>(n) + 1);
  exec.for_each_chunk(prev_count_, kPointGrain, [&](uint32_t b, uint32_t e, uint32_t) {
    kernels::segment_starts(prev_keys_.data(), prev_count_, 32, n, ps, {b, e});
  });
}

}  // namespace impact::host
