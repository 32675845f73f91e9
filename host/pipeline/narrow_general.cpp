// The step's general narrow phase: bodies that carry shapes (BodyDesc::shape).
//
// A world whose bodies are all plain spheres never comes here (step.cpp runs the
// sphere kernels). Once one body has a shape, every candidate pair and every
// body-plane pair goes through host::NarrowRunner (the code of NarrowPhase::collide):
// plain spheres become sphere records, planes half-space records, and each manifold
// point becomes one solver contact (a, b, normal, its own depth, point, point index),
// in manifold order: body pairs in broad-phase order, then body-plane pairs by body
// slot then plane - the order contacts() documents.
// Bodies do not rotate yet: a shape keeps the orientation it was created with.
#include <algorithm>
#include <cmath>
#include <string>

#include "host/broadphase/broadphase.h"
#include "host/narrowphase/pose.h"
#include "host/world_impl.h"

namespace impact {

namespace {
constexpr uint32_t kGrain = 4096;
}  // namespace

void WorldImpl::shaped_bounds(const kernels::AabbSoAOut& out, float swept_dt) {
  const BodyStore& s = bodies;
  const ShapeStore& st = shapes.store();
  const auto n = static_cast<uint32_t>(s.size());
  exec.for_each_chunk(n, kGrain, [&](uint32_t b, uint32_t e, uint32_t) {
    for (uint32_t i = b; i < e; ++i) {
      if (s.shape[i] == kNoShape) continue;
      Pose pose;
      pose.position = Eigen::Vector3f(s.pos_x[i], s.pos_y[i], s.pos_z[i]);
      pose.orientation = Eigen::Quaternionf(s.qw[i], s.qx[i], s.qy[i], s.qz[i]);
      Eigen::Vector3f lo, hi;
      host::posed_bounds(st.shapes[s.shape[i]], pose, st.hulls, &lo, &hi);
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

Status WorldImpl::general_narrow_phase() {
  BodyStore& s = bodies;
  const ShapeStore& st = shapes.store();
  const auto n = static_cast<uint32_t>(s.size());
  const auto np = static_cast<uint32_t>(planes.size());
  const uint32_t objects = n + np;
  narrow_spheres.resize(objects);
  narrow_rec.resize(objects);
  narrow_types.resize(objects);
  narrow_pose.resize(objects);
  exec.for_each_chunk(n, kGrain, [&](uint32_t b, uint32_t e, uint32_t) {
    for (uint32_t i = b; i < e; ++i) {
      host::PosedObject& P = narrow_pose[i];
      P.p = Eigen::Vector3f(s.pos_x[i], s.pos_y[i], s.pos_z[i]);
      if (s.shape[i] == kNoShape) {
        ShapeRecord& r = narrow_spheres[i];
        r.type = ShapeType::kSphere;
        r.e[0] = s.radius[i];
        narrow_rec[i] = &r;
        P.R.setIdentity();
      } else {
        narrow_rec[i] = &st.shapes[s.shape[i]];
        P.R = Eigen::Quaternionf(s.qw[i], s.qx[i], s.qy[i], s.qz[i]).toRotationMatrix();
      }
      P.set_shape(*narrow_rec[i]);
      narrow_types[i] = narrow_rec[i]->type;
    }
  });
  for (uint32_t j = 0; j < np; ++j) {
    ShapeRecord& r = narrow_spheres[n + j];
    r.type = ShapeType::kHalfSpace;
    r.e[0] = planes.normal_x[j];
    r.e[1] = planes.normal_y[j];
    r.e[2] = planes.normal_z[j];
    r.offset = planes.offset[j];
    narrow_rec[n + j] = &r;
    narrow_pose[n + j].R.setIdentity();
    narrow_pose[n + j].p.setZero();
    narrow_pose[n + j].set_shape(r);
    narrow_types[n + j] = r.type;
  }
  // Body pairs as the broad phase found them, then (body, plane) pairs that pass the
  // filter of the sphere path (dynamic bodies only, layers and masks both ways) and
  // whose bounding sphere reaches the plane: the stored radius bounds the whole shape,
  // so no contact is lost (a relative 1e-4 slack covers rounding). Counted per chunk,
  // scanned, then written in (body slot, plane) order, so the order is the serial one.
  const size_t nb = pairs.size();
  auto plane_candidate = [&](uint32_t i, uint32_t j) {
    if ((s.layer[i] & planes.mask[j]) == 0 || (planes.layer[j] & s.mask[i]) == 0) return false;
    const double c = static_cast<double>(planes.normal_x[j]) * s.pos_x[i] +
                     static_cast<double>(planes.normal_y[j]) * s.pos_y[i] +
                     static_cast<double>(planes.normal_z[j]) * s.pos_z[i];
    const double off = planes.offset[j], r = s.radius[i];
    return c - off <= r + 1e-4 * (std::fabs(c) + std::fabs(off) + r);
  };
  const uint64_t n_plane_pairs =
      np == 0 ? 0 : host::count_and_scan(exec, n, kGrain, plane_offsets, [&](uint32_t b, uint32_t e) {
        uint64_t k = 0;
        for (uint32_t i = b; i < e; ++i)
          if (s.inv_mass[i] > 0.0f)
            for (uint32_t j = 0; j < np; ++j) k += plane_candidate(i, j) ? 1 : 0;
        return k;
      });
  narrow_pairs.resize(nb + n_plane_pairs);
  static_assert(sizeof(ShapePair) == sizeof(kernels::Pair));
  exec.for_each_chunk(nb, 16 * kGrain, [&](uint32_t b, uint32_t e, uint32_t) {
    for (uint32_t k = b; k < e; ++k) narrow_pairs[k] = ShapePair{pairs[k].a, pairs[k].b};
  });
  if (n_plane_pairs > 0) {
    exec.for_each_chunk(n, kGrain, [&](uint32_t b, uint32_t e, uint32_t c) {
      uint64_t at = nb + plane_offsets[c];
      for (uint32_t i = b; i < e; ++i)
        if (s.inv_mass[i] > 0.0f)
          for (uint32_t j = 0; j < np; ++j)
            if (plane_candidate(i, j)) narrow_pairs[at++] = ShapePair{i, n + j};
    });
  }
  const kernels::NarrowConfig cfg = host::config_of(desc.narrow_phase);
  if (Status r = narrow.run(exec, st, narrow_rec, narrow_types, narrow_pose, narrow_pairs, cfg, &manifolds);
      !r.ok()) {
    return r;
  }

  // Manifold points -> contacts, in manifold order: points counted per chunk, scanned,
  // written in parallel.
  const auto nm = static_cast<uint32_t>(manifolds.size());
  const uint64_t points = host::count_and_scan(exec, nm, kGrain, pair_offsets, [&](uint32_t b, uint32_t e) {
    uint64_t k = 0;
    for (uint32_t m = b; m < e; ++m) k += manifolds[m].point_count;
    return k;
  });
  if (points > 0x7fffffffull) {
    return Status(StatusCode::kCapacityExceeded,
                  "step: " + std::to_string(points) + " contacts exceed the limit of 2^31 - 1");
  }
  ContactStore& c = contacts;
  c.resize(points);
  std::vector<uint64_t> plane_points(host::chunk_count(nm, kGrain), 0);
  exec.for_each_chunk(nm, kGrain, [&](uint32_t b, uint32_t e, uint32_t ch) {
    uint64_t at = pair_offsets[ch];
    for (uint32_t mi = b; mi < e; ++mi) {
      const Manifold& m = manifolds[mi];
      const ShapePair& pr = narrow_pairs[m.pair];
      const bool plane = pr.b >= n;
      for (uint32_t k = 0; k < m.point_count; ++k, ++at) {
        c.a[at] = pr.a;
        c.b[at] = plane ? pr.b - n : pr.b;
        c.b_is_plane[at] = plane ? 1 : 0;
        c.normal_x[at] = m.normal.x();
        c.normal_y[at] = m.normal.y();
        c.normal_z[at] = m.normal.z();
        c.depth[at] = m.point_depth[k];
        c.point_x[at] = m.points[k].x();
        c.point_y[at] = m.points[k].y();
        c.point_z[at] = m.points[k].z();
        c.point[at] = static_cast<uint8_t>(k);
      }
      if (plane) plane_points[ch] += m.point_count;
    }
  });
  uint64_t plane_contacts = 0;
  for (uint64_t v : plane_points) plane_contacts += v;
  last.contacts = c.count;
  last.plane_contacts = plane_contacts;
  return Status();
}

}  // namespace impact
