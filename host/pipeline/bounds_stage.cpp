// The bounds stage: one axis-aligned box per body for the broad phase, and their
// union and largest edge. A plain sphere's box is [p - r, p + r]; a shaped body's is
// its shape's posed bounds (host/shapes/pose.h). With WorldDesc::swept_bounds (or any
// continuous-collision mode) each box covers the body's motion over the step (p to p + v dt, v after gravity).
// Finite inputs can still integrate out of range (a huge speed for long enough): the
// stage fails, naming the body, before Inf or NaN reaches the grid's cell arithmetic
// or the sort keys. Cost: one streaming pass (spheres), one posed-bounds evaluation
// per shaped body, one reduction.
#include <cmath>
#include <string>

#include "host/broadphase/broadphase.h"
#include "host/pipeline/step_context.h"
#include "host/shapes/pose.h"
#include "kernels/broadphase/bounds.h"

namespace impact::host {
namespace {

constexpr uint32_t kBodyGrain = 1u << 14;
constexpr uint32_t kShapedGrain = 4096;
constexpr float kMaxCoordinate = 1e18f;  // m; the API's limit on positions

bool in_range(const kernels::BoundsSummary& s) {
  for (int k = 0; k < 3; ++k)
    if (!(std::fabs(s.lo[k]) <= kMaxCoordinate && std::fabs(s.hi[k]) <= kMaxCoordinate)) return false;
  return std::isfinite(s.max_edge);
}

/// Overwrites the boxes of bodies with shapes by their posed bounds (swept over
/// swept_dt of motion when > 0).
void shaped_bounds(const StepContext& ctx, const kernels::AabbSoAOut& out, float swept_dt) {
  const BodyStore& s = ctx.bodies;
  const ShapeStore& st = ctx.shapes.store();
  const auto n = static_cast<uint32_t>(s.size());
  ctx.exec.for_each_chunk(n, kShapedGrain, [&](uint32_t b, uint32_t e, uint32_t) {
    for (uint32_t i = b; i < e; ++i) {
      if (s.shape[i] == kNoShape) continue;
      Pose pose;
      pose.position = Eigen::Vector3f(s.pos_x[i], s.pos_y[i], s.pos_z[i]);
      pose.orientation = Eigen::Quaternionf(s.qw[i], s.qx[i], s.qy[i], s.qz[i]);
      Eigen::Vector3f lo, hi;
      posed_bounds(st.shapes[s.shape[i]], pose, st.hulls, &lo, &hi);
      if (swept_dt > 0.0f) {  // the union with the box moved by this step's motion
        const Eigen::Vector3f d = Eigen::Vector3f(s.vel_x[i], s.vel_y[i], s.vel_z[i]) * swept_dt;
        lo = lo.cwiseMin(lo + d);
        hi = hi.cwiseMax(hi + d);
      }
      out.min_x[i] = lo.x();
      out.min_y[i] = lo.y();
      out.min_z[i] = lo.z();
      out.max_x[i] = hi.x();
      out.max_y[i] = hi.y();
      out.max_z[i] = hi.z();
    }
  });
}

Status out_of_range(const BodyStore& s, uint32_t i) {
  const BodyHandle h = s.handle[i];
  return Status(StatusCode::kInvalidArgument,
                "step: body {index " + std::to_string(h.index) + ", generation " + std::to_string(h.generation) +
                    "} position (" + std::to_string(s.pos_x[i]) + ", " + std::to_string(s.pos_y[i]) + ", " +
                    std::to_string(s.pos_z[i]) + ") left the supported range |x| <= 1e18 m (velocity (" +
                    std::to_string(s.vel_x[i]) + ", " + std::to_string(s.vel_y[i]) + ", " +
                    std::to_string(s.vel_z[i]) + ")); fix it with set_positions/set_velocities or destroy it");
}

}  // namespace

Status bounds_stage(StepContext& ctx) {
  const BodyStore& s = ctx.bodies;
  const auto n = static_cast<uint32_t>(s.size());
  Buffer<float>* box = ctx.scratch.box;
  const kernels::AabbSoAOut out{scratch(box[0], n), scratch(box[1], n), scratch(box[2], n),
                                scratch(box[3], n), scratch(box[4], n), scratch(box[5], n)};
  const bool swept = swept_step(ctx.desc);
  if (swept) {
    ctx.exec.for_each_chunk(n, kBodyGrain, [&](uint32_t b, uint32_t e, uint32_t) {
      kernels::swept_sphere_bounds(s.pos_x.data(), s.pos_y.data(), s.pos_z.data(), s.vel_x.data(), s.vel_y.data(),
                                   s.vel_z.data(), s.radius.data(), ctx.dt, out, {b, e});
    });
  } else {
    ctx.exec.for_each_chunk(n, kBodyGrain, [&](uint32_t b, uint32_t e, uint32_t) {
      kernels::sphere_bounds(s.pos_x.data(), s.pos_y.data(), s.pos_z.data(), s.radius.data(), out, {b, e});
    });
  }
  if (ctx.shaped_count > 0) shaped_bounds(ctx, out, swept ? ctx.dt : 0.0f);
  ctx.boxes = kernels::AabbSoA{out.min_x, out.min_y, out.min_z, out.max_x, out.max_y, out.max_z};
  ctx.summary = summarize_bounds(ctx.exec, ctx.boxes, n, ctx.scratch.bounds_partials);
  if (n > 0 && !in_range(ctx.summary)) {
    for (uint32_t i = 0; i < n; ++i) {
      const float v[6] = {out.min_x[i], out.min_y[i], out.min_z[i], out.max_x[i], out.max_y[i], out.max_z[i]};
      for (float x : v) {
        if (!(std::fabs(x) <= kMaxCoordinate)) {
          ctx.pairs.clear();
          return out_of_range(s, i);
        }
      }
    }
  }
  return Status();
}

}  // namespace impact::host
