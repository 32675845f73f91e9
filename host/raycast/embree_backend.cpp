// Embree 3 tracing backend. The only file (with embree_plain.cpp) that includes Embree.
//
// Scene layout (two levels):
//   static scene: one triangle geometry per mesh (geomID = mesh id, mask = mesh layer),
//                 build quality MEDIUM, RTC_SCENE_FLAG_ROBUST when desc.robust;
//                 committed only when meshes are added.
//   top scene:    geomID 0 = instance of the static scene (identity),
//                 geomID 1 = spheres, geomID 2 = capsules, geomID 3 = posed shapes.
// Spheres and capsules are user geometry calling kernels/raycast/ray_primitives.h, and
// posed shapes (boxes, hulls, compounds, ...) user geometry calling
// host/shapes/shape_ray.h (bounds: the padded posed AABBs of SceneData), so
// hits follow the same rules as the LBVH path (solid shapes, per-primitive layers
// tested in the callback). EmbreeSpheres::kBuiltin uses Embree's sphere points instead,
// with an intersection filter for per-primitive layers when the layers differ.
// Capsules are not Embree round linear curves: those miss rays running along the
// curve's axis (measured with Embree 3.13.5; docs/raycast.md).
// Dynamic updates: the dynamic geometries carry the build quality of
// RaySceneDesc::dynamic_update (REFIT / LOW / MEDIUM); a changed count makes a new
// geometry. Commits run inside a TBB arena of the scene's thread count, so Embree's
// internal builders use that many threads.
#include <embree3/rtcore.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <string>

#include "host/raycast/embree_plain.h"
#include "host/raycast/scene_data.h"
#include "kernels/raycast/ray_primitives.h"

#if IMPACT_HAVE_TBB
#include <tbb/task_arena.h>
#endif

namespace impact::host {
namespace {

constexpr unsigned kInstanceId = 0, kSpheresId = 1, kCapsulesId = 2, kShapesId = 3;
// User geometry kinds (template argument K below).
constexpr int kUserSphere = 0, kUserCapsule = 1, kUserShape = 2;

kernels::RayQuery query_of(RTCRayN* ray, unsigned N, unsigned i) {
  kernels::RayQuery q;
  q.o[0] = RTCRayN_org_x(ray, N, i);
  q.o[1] = RTCRayN_org_y(ray, N, i);
  q.o[2] = RTCRayN_org_z(ray, N, i);
  q.d[0] = RTCRayN_dir_x(ray, N, i);
  q.d[1] = RTCRayN_dir_y(ray, N, i);
  q.d[2] = RTCRayN_dir_z(ray, N, i);
  q.tmax = RTCRayN_tfar(ray, N, i);
  q.mask = RTCRayN_mask(ray, N, i);
  return q;
}

// Primitive test of user geometry K (sphere, capsule, shape) for one ray; -1 on a miss.
template <int K>
float user_hit(const SceneData& d, unsigned prim, const kernels::RayQuery& q) {
  if constexpr (K == kUserShape) {
    // Embree hands every primitive of a leaf to the callback without testing its own
    // box; the full shape test is costly, so cull by the object's box first.
    const float lo[3] = {d.ob_min_x[prim], d.ob_min_y[prim], d.ob_min_z[prim]};
    const float hi[3] = {d.ob_max_x[prim], d.ob_max_y[prim], d.ob_max_z[prim]};
    if (!kernels::ray_meets_box(q, lo, hi)) return -1.0f;
    return shape_ray_t(d, prim, q);
  } else if constexpr (K == kUserCapsule) {
    if ((d.c_layer[prim] & q.mask) == 0) return -1.0f;
    const float a[3] = {d.ax[prim], d.ay[prim], d.az[prim]};
    const float b[3] = {d.bx[prim], d.by[prim], d.bz[prim]};
    return kernels::ray_capsule(q, a, b, d.cr[prim]);
  } else {
    if ((d.s_layer[prim] & q.mask) == 0) return -1.0f;
    return kernels::ray_sphere(q, d.sx[prim], d.sy[prim], d.sz[prim], d.sr[prim]);
  }
}

template <int K>
void user_bounds(const RTCBoundsFunctionArguments* args) {
  const SceneData& d = *static_cast<const SceneData*>(args->geometryUserPtr);
  const unsigned i = args->primID;
  RTCBounds* b = args->bounds_o;
  if constexpr (K == kUserShape) {
    b->lower_x = d.ob_min_x[i];
    b->lower_y = d.ob_min_y[i];
    b->lower_z = d.ob_min_z[i];
    b->upper_x = d.ob_max_x[i];
    b->upper_y = d.ob_max_y[i];
    b->upper_z = d.ob_max_z[i];
  } else if constexpr (K == kUserCapsule) {
    const float r = d.cr[i];
    b->lower_x = std::fmin(d.ax[i], d.bx[i]) - r;
    b->lower_y = std::fmin(d.ay[i], d.by[i]) - r;
    b->lower_z = std::fmin(d.az[i], d.bz[i]) - r;
    b->upper_x = std::fmax(d.ax[i], d.bx[i]) + r;
    b->upper_y = std::fmax(d.ay[i], d.by[i]) + r;
    b->upper_z = std::fmax(d.az[i], d.bz[i]) + r;
  } else {
    const float r = d.sr[i];
    b->lower_x = d.sx[i] - r;
    b->lower_y = d.sy[i] - r;
    b->lower_z = d.sz[i] - r;
    b->upper_x = d.sx[i] + r;
    b->upper_y = d.sy[i] + r;
    b->upper_z = d.sz[i] + r;
  }
}

template <int K>
void user_intersect(const RTCIntersectFunctionNArguments* args) {
  const SceneData& d = *static_cast<const SceneData*>(args->geometryUserPtr);
  RTCRayN* ray = RTCRayHitN_RayN(args->rayhit, args->N);
  RTCHitN* hit = RTCRayHitN_HitN(args->rayhit, args->N);
  for (unsigned i = 0; i < args->N; ++i) {
    if (args->valid[i] == 0) continue;
    const kernels::RayQuery q = query_of(ray, args->N, i);
    const float t = user_hit<K>(d, args->primID, q);
    if (t < 0.0f) continue;
    RTCRayN_tfar(ray, args->N, i) = t;
    RTCHitN_Ng_x(hit, args->N, i) = 0.0f;
    RTCHitN_Ng_y(hit, args->N, i) = 0.0f;
    RTCHitN_Ng_z(hit, args->N, i) = 0.0f;
    RTCHitN_u(hit, args->N, i) = 0.0f;
    RTCHitN_v(hit, args->N, i) = 0.0f;
    RTCHitN_primID(hit, args->N, i) = args->primID;
    RTCHitN_geomID(hit, args->N, i) = args->geomID;
    RTCHitN_instID(hit, args->N, i, 0) = args->context->instID[0];
  }
}

template <int K>
void user_occluded(const RTCOccludedFunctionNArguments* args) {
  const SceneData& d = *static_cast<const SceneData*>(args->geometryUserPtr);
  for (unsigned i = 0; i < args->N; ++i) {
    if (args->valid[i] == 0) continue;
    const kernels::RayQuery q = query_of(args->ray, args->N, i);
    if (user_hit<K>(d, args->primID, q) >= 0.0f)
      RTCRayN_tfar(args->ray, args->N, i) = -std::numeric_limits<float>::infinity();
  }
}

// Built-in spheres with mixed layers: reject candidates whose layer the ray does not see.
void sphere_layer_filter(const RTCFilterFunctionNArguments* args) {
  const SceneData& d = *static_cast<const SceneData*>(args->geometryUserPtr);
  for (unsigned i = 0; i < args->N; ++i) {
    if (args->valid[i] == 0) continue;
    const unsigned prim = RTCHitN_primID(args->hit, args->N, i);
    if ((d.s_layer[prim] & RTCRayN_mask(args->ray, args->N, i)) == 0) args->valid[i] = 0;
  }
}

uint32_t layer_union(const Buffer<uint32_t>& layers, bool* uniform) {
  uint32_t u = 0;
  *uniform = true;
  for (size_t i = 0; i < layers.size(); ++i) {
    u |= layers[i];
    if (layers[i] != layers[0]) *uniform = false;
  }
  return u;
}

RTCBuildQuality quality_of(DynamicUpdate u) {
  switch (u) {
    case DynamicUpdate::kRefit: return RTC_BUILD_QUALITY_REFIT;
    case DynamicUpdate::kRebuildLow: return RTC_BUILD_QUALITY_LOW;
    case DynamicUpdate::kRebuildMedium: return RTC_BUILD_QUALITY_MEDIUM;
  }
  return RTC_BUILD_QUALITY_LOW;
}

void error_callback(void* user, RTCError code, const char* str) {
  std::string* last = static_cast<std::string*>(user);
  *last = "Embree error " + std::to_string(static_cast<int>(code)) + ": " + (str ? str : "");
}

template <int W>
struct Packet;
template <>
struct Packet<4> {
  using RayHit = RTCRayHit4;
  using Ray = RTCRay4;
  static void intersect(const int* v, RTCScene s, RTCIntersectContext* c, RayHit* r) { rtcIntersect4(v, s, c, r); }
  static void occluded(const int* v, RTCScene s, RTCIntersectContext* c, Ray* r) { rtcOccluded4(v, s, c, r); }
};
template <>
struct Packet<8> {
  using RayHit = RTCRayHit8;
  using Ray = RTCRay8;
  static void intersect(const int* v, RTCScene s, RTCIntersectContext* c, RayHit* r) { rtcIntersect8(v, s, c, r); }
  static void occluded(const int* v, RTCScene s, RTCIntersectContext* c, Ray* r) { rtcOccluded8(v, s, c, r); }
};
template <>
struct Packet<16> {
  using RayHit = RTCRayHit16;
  using Ray = RTCRay16;
  static void intersect(const int* v, RTCScene s, RTCIntersectContext* c, RayHit* r) { rtcIntersect16(v, s, c, r); }
  static void occluded(const int* v, RTCScene s, RTCIntersectContext* c, Ray* r) { rtcOccluded16(v, s, c, r); }
};

template <class R>
void fill_packet_ray(R& r, int k, const kernels::RayQuery& q, float tfar) {
  r.org_x[k] = q.o[0];
  r.org_y[k] = q.o[1];
  r.org_z[k] = q.o[2];
  r.dir_x[k] = q.d[0];
  r.dir_y[k] = q.d[1];
  r.dir_z[k] = q.d[2];
  r.tnear[k] = 0.0f;
  r.tfar[k] = tfar;
  r.time[k] = 0.0f;
  r.mask[k] = q.mask;
  r.id[k] = 0;
  r.flags[k] = 0;
}

void fill_ray(RTCRay& r, const kernels::RayQuery& q, float tfar) {
  r.org_x = q.o[0];
  r.org_y = q.o[1];
  r.org_z = q.o[2];
  r.dir_x = q.d[0];
  r.dir_y = q.d[1];
  r.dir_z = q.d[2];
  r.tnear = 0.0f;
  r.tfar = tfar;
  r.time = 0.0f;
  r.mask = q.mask;
  r.id = 0;
  r.flags = 0;
}

// Rays per rtcIntersect1M / rtcOccluded1M stream (RTCRayHit blocks on the stack).
constexpr uint32_t kStream = 64;

class EmbreeBackend final : public TraceBackend {
 public:
  EmbreeBackend(const RaySceneDesc& desc, const SceneData& data, uint32_t threads)
      : desc_(desc), data_(data), threads_(threads) {}

  Status init() {
    device_ = rtcNewDevice(nullptr);
    if (!device_) return Status(StatusCode::kUnsupported, "Embree: rtcNewDevice failed");
    rtcSetDeviceErrorFunction(device_, error_callback, &error_);
    if (rtcGetDeviceProperty(device_, RTC_DEVICE_PROPERTY_RAY_MASK_SUPPORTED) == 0)
      return Status(StatusCode::kUnsupported,
                    "Embree: this build has no ray masks (EMBREE_RAY_MASK=OFF); layers need them");
    static_ = rtcNewScene(device_);
    rtcSetSceneBuildQuality(static_, RTC_BUILD_QUALITY_MEDIUM);
    rtcSetSceneFlags(static_, desc_.robust ? RTC_SCENE_FLAG_ROBUST : RTC_SCENE_FLAG_NONE);
    top_ = rtcNewScene(device_);
    rtcSetSceneFlags(top_, desc_.robust ? RTC_SCENE_FLAG_ROBUST : RTC_SCENE_FLAG_NONE);
    rtcSetSceneBuildQuality(top_, desc_.dynamic_update == DynamicUpdate::kRebuildMedium
                                      ? RTC_BUILD_QUALITY_MEDIUM
                                      : RTC_BUILD_QUALITY_LOW);
    return check();
  }

  ~EmbreeBackend() override {
    if (top_) rtcReleaseScene(top_);
    if (static_) rtcReleaseScene(static_);
    if (device_) rtcReleaseDevice(device_);
  }

  Status commit(const Executor&, const SceneData& d, const SceneChanges& ch, bool* dynamic_rebuilt) override {
    *dynamic_rebuilt = false;
    error_.clear();
    if (ch.meshes_added != 0) {
      for (uint32_t m = d.mesh_count() - ch.meshes_added; m < d.mesh_count(); ++m) add_mesh(d, m);
      run([&] { rtcCommitScene(static_); });
      if (!instance_) {
        instance_ = rtcNewGeometry(device_, RTC_GEOMETRY_TYPE_INSTANCE);
        rtcSetGeometryInstancedScene(instance_, static_);
        const float identity[12] = {1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0};
        rtcSetGeometryTransform(instance_, 0, RTC_FORMAT_FLOAT3X4_COLUMN_MAJOR, identity);
        rtcCommitGeometry(instance_);
        rtcAttachGeometryByID(top_, instance_, kInstanceId);
        rtcReleaseGeometry(instance_);
      } else {
        rtcCommitGeometry(instance_);
      }
    }
    if (ch.spheres) *dynamic_rebuilt |= update_spheres(d, ch.spheres_resized);
    if (ch.capsules) *dynamic_rebuilt |= update_user<kUserCapsule>(d, ch.capsules_resized, d.capsule_count(),
                                                                   d.c_layer, kCapsulesId, &capsules_);
    if (ch.shapes) {
      shape_layers_.resize(d.shape_count());
      for (uint32_t i = 0; i < d.shape_count(); ++i) shape_layers_[i] = d.objects[i].layer;
      *dynamic_rebuilt |= update_user<kUserShape>(d, ch.shapes_resized, d.shape_count(), shape_layers_,
                                                  kShapesId, &shapes_);
    }
    run([&] { rtcCommitScene(top_); });
    return check();
  }

  bool closest(const kernels::RayQuery* rays, kernels::RayBest* best, float* tri_normal, uint32_t n,
               bool coherent) const override {
    switch (desc_.packet_width) {
      case 4: closest_packets<4>(rays, best, tri_normal, n); return tri_normal != nullptr;
      case 8: closest_packets<8>(rays, best, tri_normal, n); return tri_normal != nullptr;
      case 16: closest_packets<16>(rays, best, tri_normal, n); return tri_normal != nullptr;
      default: break;
    }
    const bool stream = desc_.embree_streams == EmbreeStreams::kAlways ||
                        (desc_.embree_streams == EmbreeStreams::kAuto && coherent && data_.sphere_count() == 0 &&
                         data_.capsule_count() == 0 && data_.shape_count() == 0);
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    if (stream) ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
    // Blocks of kStream rays: one rtcIntersect1M per block, or one rtcIntersect1 per ray.
    RTCRayHit rh[kStream];
    for (uint32_t base = 0; base < n; base += kStream) {
      const uint32_t m = std::min(kStream, n - base);
      for (uint32_t k = 0; k < m; ++k) {
        fill_ray(rh[k].ray, rays[base + k], best[base + k].t);
        rh[k].hit.geomID = RTC_INVALID_GEOMETRY_ID;
        rh[k].hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
        if (!stream) rtcIntersect1(top_, &ctx, &rh[k]);
      }
      if (stream) rtcIntersect1M(top_, &ctx, rh, m, sizeof(RTCRayHit));
      for (uint32_t k = 0; k < m; ++k) {
        const uint32_t i = base + k;
        if (rh[k].hit.geomID != RTC_INVALID_GEOMETRY_ID &&
            reduce(rh[k].ray.tfar, rh[k].hit.geomID, rh[k].hit.primID, rh[k].hit.instID[0], best[i]) &&
            tri_normal) {
          tri_normal[3 * i] = rh[k].hit.Ng_x;
          tri_normal[3 * i + 1] = rh[k].hit.Ng_y;
          tri_normal[3 * i + 2] = rh[k].hit.Ng_z;
        }
      }
    }
    return tri_normal != nullptr;
  }

  void any(const kernels::RayQuery* rays, uint8_t* hit, uint32_t n) const override {
    switch (desc_.packet_width) {
      case 4: any_packets<4>(rays, hit, n); return;
      case 8: any_packets<8>(rays, hit, n); return;
      case 16: any_packets<16>(rays, hit, n); return;
      default: break;
    }
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    if (desc_.embree_streams == EmbreeStreams::kAlways) {
      // One rtcOccluded1M per block over the rays not yet occluded. No coherent flag
      // here (see any_packets).
      RTCRay r[kStream];
      uint32_t idx[kStream];
      for (uint32_t base = 0; base < n; base += kStream) {
        const uint32_t e = std::min(base + kStream, n);
        uint32_t m = 0;
        for (uint32_t i = base; i < e; ++i)
          if (!hit[i]) fill_ray(r[m], rays[i], rays[i].tmax), idx[m++] = i;
        if (m == 0) continue;
        rtcOccluded1M(top_, &ctx, r, m, sizeof(RTCRay));
        for (uint32_t k = 0; k < m; ++k)
          if (r[k].tfar < 0.0f) hit[idx[k]] = 1;
      }
      return;
    }
    for (uint32_t i = 0; i < n; ++i) {
      if (hit[i]) continue;
      RTCRay r;
      fill_ray(r, rays[i], rays[i].tmax);
      rtcOccluded1(top_, &ctx, &r);
      if (r.tfar < 0.0f) hit[i] = 1;
    }
  }

  RTCScene top() const { return top_; }

  void set_threads(uint32_t threads) override {
    threads_ = threads;
#if IMPACT_HAVE_TBB
    arena_.reset();
#endif
  }

 private:
  // Hit (t, geomID, primID, instID) into the chunk's best record; true when it became
  // the best and is a triangle (the caller then keeps Embree's Ng).
  bool reduce(float t, unsigned geom, unsigned prim, unsigned inst, kernels::RayBest& best) const {
    uint32_t kind, index;
    if (inst != RTC_INVALID_GEOMETRY_ID) {
      kind = kernels::kRayHitTriangle;
      index = data_.mesh_first_tri[geom] + prim;
    } else if (geom == kSpheresId) {
      kind = kernels::kRayHitSphere;
      index = prim;
    } else if (geom == kShapesId) {
      kind = kernels::kRayHitShape;
      index = prim;
    } else {
      kind = kernels::kRayHitCapsule;
      index = prim;
    }
    if (!kernels::ray_best_better(t, kind, index, best)) return false;
    best = {t, kind, index};
    return kind == kernels::kRayHitTriangle;
  }

  template <int W>
  void closest_packets(const kernels::RayQuery* rays, kernels::RayBest* best, float* tri_normal,
                       uint32_t n) const {
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
    for (uint32_t base = 0; base < n; base += W) {
      typename Packet<W>::RayHit rh;
      alignas(64) int valid[W];  // Embree reads the mask with aligned W-wide loads
      for (int k = 0; k < W; ++k) {
        const uint32_t i = base + static_cast<uint32_t>(k);
        valid[k] = i < n ? -1 : 0;
        fill_packet_ray(rh.ray, k, rays[i < n ? i : base], i < n ? best[i].t : 0.0f);
        rh.hit.geomID[k] = RTC_INVALID_GEOMETRY_ID;
        rh.hit.instID[0][k] = RTC_INVALID_GEOMETRY_ID;
      }
      Packet<W>::intersect(valid, top_, &ctx, &rh);
      for (int k = 0; k < W && base + static_cast<uint32_t>(k) < n; ++k)
        if (rh.hit.geomID[k] != RTC_INVALID_GEOMETRY_ID &&
            reduce(rh.ray.tfar[k], rh.hit.geomID[k], rh.hit.primID[k], rh.hit.instID[0][k], best[base + k]) &&
            tri_normal) {
          float* ng = tri_normal + 3 * (base + static_cast<uint32_t>(k));
          ng[0] = rh.hit.Ng_x[k];
          ng[1] = rh.hit.Ng_y[k];
          ng[2] = rh.hit.Ng_z[k];
        }
    }
  }

  template <int W>
  void any_packets(const kernels::RayQuery* rays, uint8_t* hit, uint32_t n) const {
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    // No RTC_INTERSECT_CONTEXT_FLAG_COHERENT here: with it, rtcOccluded16 never returned on
    // this scene layout (Embree 3.13.5, AVX-512 machine; tests/host/raycast_test.cpp).
    for (uint32_t base = 0; base < n; base += W) {
      typename Packet<W>::Ray r;
      alignas(64) int valid[W];  // Embree reads the mask with aligned W-wide loads
      for (int k = 0; k < W; ++k) {
        const uint32_t i = base + static_cast<uint32_t>(k);
        valid[k] = i < n && !hit[i] ? -1 : 0;
        fill_packet_ray(r, k, rays[i < n ? i : base], rays[i < n ? i : base].tmax);
      }
      Packet<W>::occluded(valid, top_, &ctx, &r);
      for (int k = 0; k < W && base + static_cast<uint32_t>(k) < n; ++k)
        if (valid[k] && r.tfar[k] < 0.0f) hit[base + k] = 1;
    }
  }

  template <class F>
  void run(F&& f) {
#if IMPACT_HAVE_TBB
    if (threads_ > 0) {
      if (!arena_) arena_ = std::make_unique<tbb::task_arena>(static_cast<int>(threads_));
      arena_->execute(f);
      return;
    }
#endif
    f();
  }

  Status check() const {
    if (!error_.empty()) return Status(StatusCode::kUnsupported, error_);
    return Status();
  }

  void add_mesh(const SceneData& d, uint32_t m) {
    const uint32_t v0 = d.mesh_first_vertex[m], v1 = d.mesh_first_vertex[m + 1];
    const uint32_t t0 = d.mesh_first_tri[m], t1 = d.mesh_first_tri[m + 1];
    RTCGeometry g = rtcNewGeometry(device_, RTC_GEOMETRY_TYPE_TRIANGLE);
    // Embree reads vertex buffers with 16-byte loads: one float of padding at the end.
    float* v = static_cast<float*>(
        rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), v1 - v0));
    if (v1 > v0) std::memcpy(v, d.vertices.data() + 3 * size_t{v0}, 3 * sizeof(float) * (v1 - v0));
    uint32_t* idx = static_cast<uint32_t*>(
        rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(uint32_t), t1 - t0));
    for (size_t k = 3 * size_t{t0}; k < 3 * size_t{t1}; ++k) idx[k - 3 * size_t{t0}] = d.indices[k] - v0;
    rtcSetGeometryMask(g, d.mesh_layer[m]);
    rtcSetGeometryBuildQuality(g, RTC_BUILD_QUALITY_MEDIUM);
    rtcCommitGeometry(g);
    rtcAttachGeometryByID(static_, g, m);
    rtcReleaseGeometry(g);
  }

  // Returns true when the geometry was made anew (a rebuild).
  template <int K>
  bool update_user(const SceneData& d, bool resized, uint32_t n, const Buffer<uint32_t>& layers,
                   unsigned id, RTCGeometry* geom) {
    bool rebuilt = resized || *geom == nullptr || desc_.dynamic_update != DynamicUpdate::kRefit;
    if (resized || *geom == nullptr) {
      if (*geom) rtcDetachGeometry(top_, id);
      *geom = nullptr;
      if (n == 0) return true;
      RTCGeometry g = rtcNewGeometry(device_, RTC_GEOMETRY_TYPE_USER);
      rtcSetGeometryUserPrimitiveCount(g, n);
      rtcSetGeometryUserData(g, const_cast<SceneData*>(&d));
      rtcSetGeometryBoundsFunction(g, user_bounds<K>, const_cast<SceneData*>(&d));
      rtcSetGeometryIntersectFunction(g, user_intersect<K>);
      rtcSetGeometryOccludedFunction(g, user_occluded<K>);
      rtcSetGeometryBuildQuality(g, quality_of(desc_.dynamic_update));
      rtcAttachGeometryByID(top_, g, id);
      rtcReleaseGeometry(g);
      *geom = g;
    }
    bool uniform = true;
    rtcSetGeometryMask(*geom, layer_union(layers, &uniform));
    rtcCommitGeometry(*geom);
    return rebuilt;
  }

  bool update_spheres(const SceneData& d, bool resized) {
    if (desc_.embree_spheres == EmbreeSpheres::kUserGeometry)
      return update_user<kUserSphere>(d, resized, d.sphere_count(), d.s_layer, kSpheresId, &spheres_);
    const uint32_t n = d.sphere_count();
    const bool rebuilt = resized || spheres_ == nullptr || desc_.dynamic_update != DynamicUpdate::kRefit;
    if (resized || spheres_ == nullptr) {
      if (spheres_) rtcDetachGeometry(top_, kSpheresId);
      spheres_ = nullptr;
      if (n == 0) return true;
      RTCGeometry g = rtcNewGeometry(device_, RTC_GEOMETRY_TYPE_SPHERE_POINT);
      rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT4, 4 * sizeof(float), n);
      rtcSetGeometryUserData(g, const_cast<SceneData*>(&d));
      rtcSetGeometryBuildQuality(g, quality_of(desc_.dynamic_update));
      rtcAttachGeometryByID(top_, g, kSpheresId);
      rtcReleaseGeometry(g);
      spheres_ = g;
    }
    float* v = static_cast<float*>(rtcGetGeometryBufferData(spheres_, RTC_BUFFER_TYPE_VERTEX, 0));
    for (uint32_t i = 0; i < n; ++i) {
      v[4 * i + 0] = d.sx[i];
      v[4 * i + 1] = d.sy[i];
      v[4 * i + 2] = d.sz[i];
      v[4 * i + 3] = d.sr[i];
    }
    rtcUpdateGeometryBuffer(spheres_, RTC_BUFFER_TYPE_VERTEX, 0);
    bool uniform = true;
    rtcSetGeometryMask(spheres_, layer_union(d.s_layer, &uniform));
    rtcSetGeometryIntersectFilterFunction(spheres_, uniform ? nullptr : sphere_layer_filter);
    rtcSetGeometryOccludedFilterFunction(spheres_, uniform ? nullptr : sphere_layer_filter);
    rtcCommitGeometry(spheres_);
    return rebuilt;
  }

  RaySceneDesc desc_;
  const SceneData& data_;
  uint32_t threads_;
  std::string error_;
  RTCDevice device_ = nullptr;
  RTCScene static_ = nullptr;
  RTCScene top_ = nullptr;
  RTCGeometry instance_ = nullptr;
  RTCGeometry spheres_ = nullptr;
  RTCGeometry capsules_ = nullptr;
  RTCGeometry shapes_ = nullptr;
  Buffer<uint32_t> shape_layers_;  // per object, for the geometry's mask
#if IMPACT_HAVE_TBB
  std::unique_ptr<tbb::task_arena> arena_;
#endif
};

}  // namespace

std::unique_ptr<TraceBackend> make_embree_backend(const RaySceneDesc& desc, const SceneData& data,
                                                  uint32_t threads, Status* status) {
  auto b = std::make_unique<EmbreeBackend>(desc, data, threads);
  *status = b->init();
  if (!status->ok()) return nullptr;
  return b;
}

namespace {

// The plain rtcIntersect1 loop; kStore: keep each ray's hit in out[i].
template <bool kStore>
uint64_t plain_closest_loop(void* rtc_scene, std::span<const Ray> rays, PlainHit* out) {
  RTCScene scene = static_cast<RTCScene>(rtc_scene);
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  uint64_t hits = 0;
  for (size_t i = 0; i < rays.size(); ++i) {
    const Ray& r = rays[i];
    RTCRayHit rh;
    rh.ray.org_x = r.origin.x();
    rh.ray.org_y = r.origin.y();
    rh.ray.org_z = r.origin.z();
    rh.ray.dir_x = r.direction.x();
    rh.ray.dir_y = r.direction.y();
    rh.ray.dir_z = r.direction.z();
    rh.ray.tnear = 0.0f;
    rh.ray.tfar = r.tmax;
    rh.ray.time = 0.0f;
    rh.ray.mask = r.mask;
    rh.ray.id = 0;
    rh.ray.flags = 0;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(scene, &ctx, &rh);
    if constexpr (kStore)
      out[i] = PlainHit{rh.ray.tfar, rh.hit.geomID, rh.hit.primID, rh.hit.instID[0], {rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z}};
    hits += rh.hit.geomID != RTC_INVALID_GEOMETRY_ID;
  }
  return hits;
}

}  // namespace

uint64_t embree_plain_closest_raw(void* rtc_scene, std::span<const Ray> rays) {
  return plain_closest_loop<false>(rtc_scene, rays, nullptr);
}

uint64_t embree_plain_closest_store_raw(void* rtc_scene, std::span<const Ray> rays, std::span<PlainHit> out) {
  return plain_closest_loop<true>(rtc_scene, rays, out.data());
}

uint64_t embree_plain_any_raw(void* rtc_scene, std::span<const Segment> segments) {
  RTCScene scene = static_cast<RTCScene>(rtc_scene);
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  uint64_t hits = 0;
  for (const Segment& s : segments) {
    // Unit direction, tfar = length (the user-geometry kernels expect unit directions).
    const Eigen::Vector3f v = s.to - s.from;
    const float len = v.norm();
    const Eigen::Vector3f d = len > 0.0f ? Eigen::Vector3f(v / len) : Eigen::Vector3f::UnitZ();
    RTCRay r;
    r.org_x = s.from.x();
    r.org_y = s.from.y();
    r.org_z = s.from.z();
    r.dir_x = d.x();
    r.dir_y = d.y();
    r.dir_z = d.z();
    r.tnear = 0.0f;
    r.tfar = len;
    r.time = 0.0f;
    r.mask = s.mask;
    r.id = 0;
    r.flags = 0;
    rtcOccluded1(scene, &ctx, &r);
    hits += r.tfar < 0.0f;
  }
  return hits;
}

void* embree_top_scene(const TraceBackend* backend) {
  const auto* e = dynamic_cast<const EmbreeBackend*>(backend);
  return e ? static_cast<void*>(e->top()) : nullptr;
}

}  // namespace impact::host
