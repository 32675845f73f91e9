// The speculative-contact stage (WorldDesc::ccd, any mode but kOff): after the narrow
// phase, every candidate pair without a manifold whose gap could close within the step
// gets a one-point manifold across the gap, depth = -gap (Catto, "Continuous
// collision", GDC 2013; Box2D v3 makes its contacts a speculative distance ahead the
// same way). The solvers let such a point close, never cross: the soft step treats
// s > -slop as speculative (kernels/solver/soft_contact.h) and applies restitution only
// where the relax pass pushed; kJacobi targets the approach speed gap / dt
// (kernels/solver/contact_solver.h).
//
// Candidates: the broad phase's pairs (on swept bounds, host/pipeline/bounds_stage.cpp)
// and the plane filter's (bodies whose travel reaches the plane,
// narrow_phase_stage.cpp). A pair is kept when
//   gap <= |v_b - v_a| dt + (|w_a| r_a + |w_b| r_b) dt + speculative_margin,
// v and w the velocities after gravity, r the bounding radii: no point of either body
// moves farther than that in the step. Gap, closest points and normal: closed forms for
// plain spheres and planes, host::distance_posed (host/shapes/shape_distance.h) for
// shaped bodies. Both manifold lists are in pair order, so one merge keeps the order
// World::contacts() documents.
// Cost: one pass over the pairs (one distance query per pair without a manifold), a
// count -> scan -> write compaction, and an O(manifolds) serial merge.
#include <algorithm>
#include <cmath>
#include <cstring>

#include "host/pipeline/step_context.h"
#include "host/scan.h"
#include "host/shapes/shape_distance.h"

namespace impact::host {
namespace {

constexpr uint32_t kPairGrain = 4096;

using Gap = SpeculativeGap;

float speed(const BodyStore& s, uint32_t i) {
  return std::sqrt(s.vel_x[i] * s.vel_x[i] + s.vel_y[i] * s.vel_y[i] + s.vel_z[i] * s.vel_z[i]);
}

float spin_reach(const BodyStore& s, uint32_t i) {
  if (!s.on(FieldSet::kRigid)) return 0.0f;
  return std::sqrt(s.wx[i] * s.wx[i] + s.wy[i] * s.wy[i] + s.wz[i] * s.wz[i]) * s.radius[i];
}

bool plain(const BodyStore& s, uint32_t i) { return !s.on(FieldSet::kShaped) || s.shape[i] == kNoShape; }

/// Pair k's speculative contact: a body pair (k < nb) or a body-plane pair.
Gap gap_of(const StepContext& ctx, uint32_t a, uint32_t b, bool plane) {
  const BodyStore& s = ctx.bodies;
  Gap g{};
  g.child_a = g.child_b = kNoChild;
  float reach;
  if (plane) {
    reach = (speed(s, a) + spin_reach(s, a)) * ctx.dt;
  } else {
    const float dv[3] = {s.vel_x[b] - s.vel_x[a], s.vel_y[b] - s.vel_y[a], s.vel_z[b] - s.vel_z[a]};
    reach = (std::sqrt(dv[0] * dv[0] + dv[1] * dv[1] + dv[2] * dv[2]) + spin_reach(s, a) + spin_reach(s, b)) * ctx.dt;
  }
  reach += ctx.desc.ccd.speculative_margin;
  const float pa[3] = {s.pos_x[a], s.pos_y[a], s.pos_z[a]};
  if (plain(s, a) && (plane || plain(s, b))) {
    if (plane) {  // half-space n.x <= offset: the normal from the body into it is -n
      const PlaneStore& P = ctx.planes;
      const float n[3] = {P.normal_x[b], P.normal_y[b], P.normal_z[b]};
      const float gap = n[0] * pa[0] + n[1] * pa[1] + n[2] * pa[2] - P.offset[b] - s.radius[a];
      if (!(gap > 0.0f && gap <= reach)) return g;
      g.gap = gap;
      for (int c = 0; c < 3; ++c) {
        g.n[c] = -n[c];
        g.p[c] = pa[c] - n[c] * (s.radius[a] + 0.5f * gap);
      }
    } else {
      const float d[3] = {s.pos_x[b] - pa[0], s.pos_y[b] - pa[1], s.pos_z[b] - pa[2]};
      const float len = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
      const float gap = len - s.radius[a] - s.radius[b];
      if (!(gap > 0.0f && gap <= reach)) return g;
      g.gap = gap;
      for (int c = 0; c < 3; ++c) {
        g.n[c] = d[c] / len;
        g.p[c] = pa[c] + g.n[c] * (s.radius[a] + 0.5f * gap);
      }
    }
    g.keep = true;
    return g;
  }
  const NarrowStage& ns = ctx.narrow;
  const uint32_t ob = plane ? static_cast<uint32_t>(s.size()) + b : b;
  const PosedObject& A = ns.poses[a];
  const PosedObject& B = ns.poses[ob];
  const PosedDistance pd = distance_posed(ctx.shapes.store(), *ns.rec[a], A.R, A.p, *ns.rec[ob], B.R, B.p,
                                          config_of(ctx.desc.narrow_phase), reach);
  if (pd.overlap || !(pd.distance > 0.0f && pd.distance <= reach)) return g;
  g.gap = pd.distance;
  for (int c = 0; c < 3; ++c) {
    g.n[c] = pd.normal[c];
    g.p[c] = 0.5f * (pd.pa[c] + pd.pb[c]);
  }
  g.child_a = pd.child_a;
  g.child_b = pd.child_b;
  g.keep = true;
  return g;
}

/// out = the manifolds of x and y (both sorted by pair, no pair in both) in pair order.
void merge(const ContactManifolds& x, const ContactManifolds& y, ContactManifolds* out) {
  const size_t m = x.manifolds + y.manifolds, p = x.points + y.points;
  const bool one_point = x.first_point.empty() && y.first_point.empty();
  const bool no_ids = x.child_a.empty() && x.feature.empty() && y.child_a.empty();
  out->resize(m, p, one_point, no_ids);
  size_t i = 0, j = 0, k = 0, q = 0;
  auto first = [](const ContactManifolds& c, size_t mi) { return c.first_point.empty() ? mi : c.first_point[mi]; };
  while (k < m) {
    const bool from_x = j >= y.manifolds || (i < x.manifolds && x.pair[i] < y.pair[j]);
    const ContactManifolds& c = from_x ? x : y;
    const size_t mi = from_x ? i++ : j++;
    out->pair[k] = c.pair[mi];
    out->a[k] = c.a[mi];
    out->b[k] = c.b[mi];
    out->b_is_plane[k] = c.b_is_plane[mi];
    out->count[k] = c.count[mi];
    for (int d = 0; d < 3; ++d) out->normal[d][k] = c.normal[d][mi];
    out->depth[k] = c.depth[mi];
    if (!no_ids) {
      out->child_a[k] = c.child_a.empty() ? kNoChild : c.child_a[mi];
      out->child_b[k] = c.child_b.empty() ? kNoChild : c.child_b[mi];
    }
    if (!one_point) out->first_point[k] = static_cast<uint32_t>(q);
    const size_t f = first(c, mi);
    for (uint32_t t = 0; t < c.count[mi]; ++t, ++q) {
      for (int d = 0; d < 3; ++d) out->point[d][q] = c.point[d][f + t];
      out->point_depth[q] = c.point_depth[f + t];
      if (!no_ids) out->feature[q] = c.feature.empty() ? t : c.feature[f + t];
    }
    ++k;
  }
}

}  // namespace

Status speculative_contacts_stage(StepContext& ctx) {
  if (ctx.desc.ccd.mode == ContinuousMode::kOff) return Status();
  NarrowStage& ns = ctx.narrow;
  SpeculativeStage& sp = ns.speculative;
  const auto nb = static_cast<uint32_t>(ctx.pairs.size());
  const auto npl = static_cast<uint32_t>(ns.body_plane_pairs);
  const uint32_t np = nb + npl;
  const auto n = static_cast<uint32_t>(ctx.bodies.size());
  ctx.stats.speculative = 0;
  if (np == 0) return Status();
  // Pairs that already have a manifold (serial: a pair's manifolds are adjacent).
  uint8_t* touched = scratch(sp.touched, np);
  std::memset(touched, 0, np);
  const ContactManifolds& c = ctx.contacts;
  for (size_t m = 0; m < c.manifolds; ++m) touched[c.pair[m]] = 1;
  // One pass: each untouched pair's gap, then count -> scan -> write.
  if (sp.rows.size() < np) sp.rows.resize(np);
  Gap* rows = sp.rows.data();
  const uint64_t total = count_and_scan(ctx.exec, np, kPairGrain, sp.offsets, [&](uint32_t b, uint32_t e) {
    uint64_t k = 0;
    for (uint32_t i = b; i < e; ++i) {
      rows[i].keep = false;
      if (touched[i]) continue;
      const bool plane = i >= nb;
      const kernels::Pair pr = plane ? ns.plane_pairs[i - nb] : ctx.pairs[i];
      rows[i] = gap_of(ctx, pr.a, plane ? pr.b - n : pr.b, plane);
      k += rows[i].keep;
    }
    return k;
  });
  ctx.stats.speculative = total;
  if (total == 0) return Status();
  const bool no_ids = c.child_a.empty() && c.feature.empty() && ctx.shaped_count == 0;
  ContactManifolds& g = sp.gaps;
  g.resize(total, total, true, no_ids);
  ctx.exec.for_each_chunk(np, kPairGrain, [&](uint32_t b, uint32_t e, uint32_t chunk) {
    uint64_t k = sp.offsets[chunk];
    for (uint32_t i = b; i < e; ++i) {
      if (!rows[i].keep) continue;
      const bool plane = i >= nb;
      const kernels::Pair pr = plane ? ns.plane_pairs[i - nb] : ctx.pairs[i];
      const Gap& r = rows[i];
      g.pair[k] = i;
      g.a[k] = pr.a;
      g.b[k] = plane ? pr.b - n : pr.b;
      g.b_is_plane[k] = plane ? 1 : 0;
      g.count[k] = 1;
      for (int d = 0; d < 3; ++d) {
        g.normal[d][k] = r.n[d];
        g.point[d][k] = r.p[d];
      }
      g.depth[k] = -r.gap;
      g.point_depth[k] = -r.gap;
      if (!no_ids) {
        g.child_a[k] = r.child_a;
        g.child_b[k] = r.child_b;
        g.feature[k] = 0;
      }
      ++k;
    }
  });
  merge(c, g, &sp.merged);
  std::swap(ctx.contacts, sp.merged);
  return count_contacts(ctx);
}

}  // namespace impact::host
