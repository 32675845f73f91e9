// LBVH tracing backend: one tree over all static triangles (built when meshes are
// added), one over the dynamic spheres and capsules (refit or rebuilt per commit), each
// with its primitives copied into sorted-leaf order, and one over the posed shapes
// (refit or rebuilt the same way; leaves call host::shape_user_test). Deterministic: every pass chunks
// by size only, and each ray is traced by one call.
#include <string>

#include "host/raycast/ray_lbvh.h"
#include "host/raycast/scene_data.h"
#include "kernels/broadphase/bounds.h"

namespace impact::host {
namespace {

struct Boxes {
  Buffer<float> min_x, min_y, min_z, max_x, max_y, max_z;
  kernels::AabbSoAOut out(size_t n) {
    return {scratch(min_x, n), scratch(min_y, n), scratch(min_z, n),
            scratch(max_x, n), scratch(max_y, n), scratch(max_z, n)};
  }
  kernels::AabbSoA in() const {
    return {min_x.data(), min_y.data(), min_z.data(), max_x.data(), max_y.data(), max_z.data()};
  }
  kernels::AabbSoAOut shifted(size_t off) {
    return {min_x.data() + off, min_y.data() + off, min_z.data() + off,
            max_x.data() + off, max_y.data() + off, max_z.data() + off};
  }
};

class LbvhBackend final : public TraceBackend {
 public:
  explicit LbvhBackend(const RaySceneDesc& desc) : desc_(desc) {}

  Status commit(const Executor& exec, const SceneData& d, const SceneChanges& ch,
                bool* dynamic_rebuilt) override {
    constexpr uint32_t kGrain = RayLbvh::kGrain;
    *dynamic_rebuilt = false;
    if (ch.meshes_added != 0) {
      const uint32_t n = d.triangle_count();
      const kernels::TriangleSoup soup{d.vertices.data(), d.indices.data(), d.tri_layer.data()};
      const kernels::AabbSoAOut out = boxes_.out(n);
      exec.for_each_chunk(n, kGrain, [&](uint32_t b, uint32_t e, uint32_t) {
        kernels::triangle_bounds(soup, out, {b, e});
      });
      tri_tree_.build(exec, boxes_.in(), n);
      kernels::TriangleRecord* rec = scratch(tri_rec_, n);
      const kernels::SortedBox* leaves = tri_tree_.tree().leaves;
      exec.for_each_chunk(n, kGrain, [&](uint32_t b, uint32_t e, uint32_t) {
        kernels::triangle_records(soup, leaves, rec, {b, e});
      });
    }
    if (ch.spheres || ch.capsules) {
      const uint32_t ns = d.sphere_count(), nc = d.capsule_count(), n = ns + nc;
      boxes_.out(n);
      exec.for_each_chunk(ns, kGrain, [&](uint32_t b, uint32_t e, uint32_t) {
        kernels::sphere_bounds(d.sx.data(), d.sy.data(), d.sz.data(), d.sr.data(), boxes_.shifted(0),
                               {b, e});
      });
      const kernels::AabbSoAOut cap = boxes_.shifted(ns);
      exec.for_each_chunk(nc, kGrain, [&](uint32_t b, uint32_t e, uint32_t) {
        kernels::capsule_bounds(d.ax.data(), d.ay.data(), d.az.data(), d.bx.data(), d.by.data(),
                                d.bz.data(), d.cr.data(), cap, {b, e});
      });
      const bool resized = ch.spheres_resized || ch.capsules_resized || dyn_tree_.size() != n;
      if (resized || desc_.dynamic_update != DynamicUpdate::kRefit) {
        dyn_tree_.build(exec, boxes_.in(), n);
        *dynamic_rebuilt = true;
      } else {
        dyn_tree_.refit(exec, boxes_.in());
      }
      first_capsule_ = ns;
      const kernels::ShapeSoA shapes{d.sx.data(), d.sy.data(), d.sz.data(), d.sr.data(), d.s_layer.data(),
                                     d.ax.data(), d.ay.data(), d.az.data(), d.bx.data(), d.by.data(),
                                     d.bz.data(), d.cr.data(), d.c_layer.data(), ns};
      kernels::ShapeRecord* rec = scratch(dyn_rec_, n);
      const kernels::SortedBox* leaves = dyn_tree_.tree().leaves;
      exec.for_each_chunk(n, kGrain, [&](uint32_t b, uint32_t e, uint32_t) {
        kernels::shape_records(shapes, leaves, rec, {b, e});
      });
    }
    if (ch.shapes) {
      const uint32_t n = d.shape_count();
      const kernels::AabbSoA boxes{d.ob_min_x.data(), d.ob_min_y.data(), d.ob_min_z.data(),
                                   d.ob_max_x.data(), d.ob_max_y.data(), d.ob_max_z.data()};
      const bool resized = ch.shapes_resized || shape_tree_.size() != n;
      if (resized || desc_.dynamic_update != DynamicUpdate::kRefit) {
        shape_tree_.build(exec, boxes, n);
        *dynamic_rebuilt = true;
      } else {
        shape_tree_.refit(exec, boxes);
      }
      data_ = &d;
    }
    return Status();
  }

  bool closest(const kernels::RayQuery* rays, kernels::RayBest* best, float*, uint32_t n, bool) const override {
    if (tri_tree_.size() != 0) kernels::ray_closest_triangles(tri_tree_.tree(), tri_rec_.data(), rays, best, {0, n});
    if (dyn_tree_.size() != 0)
      kernels::ray_closest_shapes(dyn_tree_.tree(), dyn_rec_.data(), first_capsule_, rays, best, {0, n});
    if (shape_tree_.size() != 0)
      kernels::ray_closest_user(shape_tree_.tree(), shape_user_test, data_, kernels::kRayHitShape, rays, best,
                                {0, n});
    return false;
  }

  void any(const kernels::RayQuery* rays, uint8_t* hit, uint32_t n) const override {
    if (tri_tree_.size() != 0) kernels::ray_any_triangles(tri_tree_.tree(), tri_rec_.data(), rays, hit, {0, n});
    if (dyn_tree_.size() != 0)
      kernels::ray_any_shapes(dyn_tree_.tree(), dyn_rec_.data(), first_capsule_, rays, hit, {0, n});
    if (shape_tree_.size() != 0) kernels::ray_any_user(shape_tree_.tree(), shape_user_test, data_, rays, hit, {0, n});
  }

 private:
  RaySceneDesc desc_;
  Boxes boxes_;
  RayLbvh tri_tree_, dyn_tree_, shape_tree_;
  const SceneData* data_ = nullptr;
  Buffer<kernels::TriangleRecord> tri_rec_;
  Buffer<kernels::ShapeRecord> dyn_rec_;
  uint32_t first_capsule_ = 0;
};

}  // namespace

std::unique_ptr<TraceBackend> make_lbvh_backend(const RaySceneDesc& desc) {
  return std::make_unique<LbvhBackend>(desc);
}

}  // namespace impact::host
