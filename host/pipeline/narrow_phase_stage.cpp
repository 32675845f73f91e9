// The narrow-phase stage: contact manifolds for the step's candidate pairs.
//
// 1. The plane filter (kernels/broadphase/plane_pairs.h) lists the (body, plane)
//    pairs: dynamic bodies whose bounding sphere reaches a plane, layers and masks both
//    ways; by body slot then plane (a bit mask per body, then the set bits).
// 2. One narrow phase (host::NarrowRunner) runs on the broad-phase pairs followed by
//    those: a world of plain spheres takes its sphere buckets straight from the body
//    store (run_spheres); once a body has a shape every object is posed (a sphere
//    record for a plain body, a half-space record for a plane: object body_count + j)
//    and the general route runs with the knobs of WorldDesc::narrow_phase.
// Either way the manifolds land in ctx.contacts, in pair order: body pairs in
// broad-phase order, then body-plane pairs by body slot then plane (the order
// World::contacts() documents). Cost: the filter is one pass per plane over the
// bodies; the rest is the runner's (docs/narrowphase.md).
#include <algorithm>
#include <cmath>
#include <string>

#include "host/pipeline/step_context.h"
#include "host/scan.h"
#include "kernels/broadphase/plane_pairs.h"

namespace impact::host {
namespace {

constexpr uint32_t kBodyGrain = 1u << 14;
constexpr uint32_t kPoseGrain = 4096;

/// Poses every object for the general route: bodies (plain ones as sphere records of
/// their radius), then the planes as half-space records.
void pose_objects(StepContext& ctx) {
  const BodyStore& s = ctx.bodies;
  const PlaneStore& planes = ctx.planes;
  const ShapeStore& st = ctx.shapes.store();
  NarrowStage& ns = ctx.narrow;
  const auto n = static_cast<uint32_t>(s.size());
  const auto np = static_cast<uint32_t>(planes.size());
  const uint32_t objects = n + np;
  ns.records.resize(objects);
  ns.rec.resize(objects);
  ns.types.resize(objects);
  ns.poses.resize(objects);
  ctx.exec.for_each_chunk(n, kPoseGrain, [&](uint32_t b, uint32_t e, uint32_t) {
    for (uint32_t i = b; i < e; ++i) {
      PosedObject& P = ns.poses[i];
      P.p = Eigen::Vector3f(s.pos_x[i], s.pos_y[i], s.pos_z[i]);
      if (s.shape[i] == kNoShape) {
        ShapeRecord& r = ns.records[i];
        r.type = ShapeType::kSphere;
        r.e[0] = s.radius[i];
        ns.rec[i] = &r;
        P.R.setIdentity();
      } else {
        ns.rec[i] = &st.shapes[s.shape[i]];
        P.R = Eigen::Quaternionf(s.qw[i], s.qx[i], s.qy[i], s.qz[i]).toRotationMatrix();
      }
      P.set_shape(*ns.rec[i]);
      ns.types[i] = ns.rec[i]->type;
    }
  });
  for (uint32_t j = 0; j < np; ++j) {
    ShapeRecord& r = ns.records[n + j];
    r.type = ShapeType::kHalfSpace;
    r.e[0] = planes.normal_x[j];
    r.e[1] = planes.normal_y[j];
    r.e[2] = planes.normal_z[j];
    r.offset = planes.offset[j];
    ns.rec[n + j] = &r;
    ns.poses[n + j].R.setIdentity();
    ns.poses[n + j].p.setZero();
    ns.poses[n + j].set_shape(r);
    ns.types[n + j] = r.type;
  }
}

}  // namespace

Status narrow_phase_stage(StepContext& ctx) {
  const BodyStore& s = ctx.bodies;
  NarrowStage& ns = ctx.narrow;
  const auto n = static_cast<uint32_t>(s.size());
  const kernels::SphereView spheres{s.pos_x.data(), s.pos_y.data(), s.pos_z.data(), s.radius.data()};
  const kernels::PlaneView pv = ctx.planes.view();
  // Continuous collision: a body meets a plane its travel this step could reach.
  kernels::SphereView reach = spheres;
  if (ctx.desc.ccd.mode != ContinuousMode::kOff && pv.count > 0) {
    float* r = scratch(ns.speculative.reach_radius, n);
    const float dt = ctx.dt, margin = ctx.desc.ccd.speculative_margin;
    const bool spins = s.on(FieldSet::kRigid);
    ctx.exec.for_each_chunk(n, kBodyGrain, [&](uint32_t b, uint32_t e, uint32_t) {
      for (uint32_t i = b; i < e; ++i) {
        const float v = std::sqrt(s.vel_x[i] * s.vel_x[i] + s.vel_y[i] * s.vel_y[i] + s.vel_z[i] * s.vel_z[i]);
        const float w = spins ? std::sqrt(s.wx[i] * s.wx[i] + s.wy[i] * s.wy[i] + s.wz[i] * s.wz[i]) : 0.0f;
        r[i] = s.radius[i] + (v + w * s.radius[i]) * dt + margin;
      }
    });
    reach.radius = r;
  }
  const kernels::BodyFilter bf{s.inv_mass.data(), s.layer.data(), s.mask.data()};

  // The plane filter: per-body masks and their counts, scan, write.
  uint64_t n_plane_pairs = 0;
  if (pv.count > 0) {
    const uint32_t words = kernels::plane_mask_words(pv.count);
    uint32_t* masks = scratch(ns.plane_masks, static_cast<size_t>(words) * n);
    n_plane_pairs = count_and_scan(ctx.exec, n, kBodyGrain, ns.plane_offsets, [&](uint32_t b, uint32_t e) {
      return kernels::plane_pair_masks(reach, bf, pv, masks, n, {b, e});
    });
    kernels::Pair* out = scratch(ns.plane_pairs, n_plane_pairs);
    ctx.exec.for_each_chunk(n, kBodyGrain, [&](uint32_t b, uint32_t e, uint32_t k) {
      kernels::plane_pair_write(masks, words, n, n, out, ns.plane_offsets[k], {b, e});
    });
  }
  const PairList pairs{{ctx.pairs.data(), ctx.pairs.size()}, {ns.plane_pairs.data(), n_plane_pairs}};

  Status st;
  if (ctx.shaped_count == 0) {
    st = ns.runner.run_spheres(ctx.exec, SphereObjects{spheres, pv, n}, pairs, &ctx.contacts);
  } else {
    pose_objects(ctx);
    NarrowObjects objects;
    objects.store = &ctx.shapes.store();
    objects.rec = ns.rec;
    objects.types = ns.types;
    objects.poses = ns.poses;
    objects.first_plane = n;
    st = ns.runner.run(ctx.exec, objects, pairs, config_of(ctx.desc.narrow_phase), &ctx.contacts);
  }
  ns.body_plane_pairs = n_plane_pairs;
  if (!st.ok()) return st;
  return count_contacts(ctx);
}

Status count_contacts(StepContext& ctx) {
  // Two CSR keys per contact point index the solver's adjacency with 32 bits.
  const ContactManifolds& c = ctx.contacts;
  if (c.points > 0x7fffffffull) {
    return Status(StatusCode::kCapacityExceeded,
                  "step: " + std::to_string(c.points) + " contacts exceed the limit of 2^31 - 1");
  }
  // Body-plane points: the manifolds are in pair order and the plane pairs come last,
  // so they are the manifolds from the first whose pair index reaches nb on.
  const auto nm = static_cast<uint32_t>(c.manifolds);
  const uint32_t nb = static_cast<uint32_t>(ctx.pairs.size());
  const uint32_t* first_plane = std::lower_bound(c.pair.data(), c.pair.data() + nm, nb);
  const auto m = static_cast<uint32_t>(first_plane - c.pair.data());
  const uint64_t plane_points = m < nm ? c.points - kernels::first_point_of(c.view(), m) : 0;
  ctx.stats.manifolds = c.manifolds;
  ctx.stats.contacts = c.points;
  ctx.stats.plane_contacts = plane_points;
  return Status();
}

}  // namespace impact::host
