// RayScene (include/impact/raycast.h): validation at the API, host-owned SoA copies
// of the geometry (host/raycast/scene_data.h), and the batched query driver shared by
// both backends: per chunk of kRayGrain rays, validate and normalise -> backend trace
// -> half-spaces (kernels/raycast/ray_bvh.h) -> hit record (point and normal in double:
// a triangle's normal from the backend's Ng when it gives one, else from the stored
// primitive). Chunks depend only on the ray count, and each ray is traced by exactly
// one call, so the output does not depend on the thread count.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>

#include <Eigen/Geometry>

#include "host/raycast/embree_plain.h"
#include "host/raycast/scene_data.h"
#include "host/shapes/pose.h"
#include "host/shapes/shape_ray.h"
#include "impact/world.h"

namespace impact {

namespace {

constexpr uint32_t kRayGrain = 128;
constexpr float kFloatMax = std::numeric_limits<float>::max();

std::string fmt(float v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", static_cast<double>(v));
  return buf;
}
std::string fmt3(const Eigen::Vector3f& v) { return "(" + fmt(v.x()) + ", " + fmt(v.y()) + ", " + fmt(v.z()) + ")"; }

bool finite3(const Eigen::Vector3f& v) { return std::isfinite(v.x()) && std::isfinite(v.y()) && std::isfinite(v.z()); }

// Unit direction, in double: squares of finite floats neither overflow nor underflow
// to zero in double, so any finite non-zero float vector normalises. False for zero or
// non-finite input.
bool unit_direction(const Eigen::Vector3f& d, float out[3], double* length) {
  const double x = d.x(), y = d.y(), z = d.z();
  const double l2 = x * x + y * y + z * z;
  if (!(l2 > 0.0) || !(l2 < std::numeric_limits<double>::infinity())) return false;
  const double l = std::sqrt(l2);
  const double inv = 1.0 / l;
  out[0] = static_cast<float>(x * inv);
  out[1] = static_cast<float>(y * inv);
  out[2] = static_cast<float>(z * inv);
  *length = l;
  return true;
}

// Validates one ray and converts it; empty string on success, else the message tail.
std::string to_query(const Ray& r, kernels::RayQuery* q) {
  if (!finite3(r.origin)) return "origin must be finite, got " + fmt3(r.origin);
  double len = 0.0;
  if (!unit_direction(r.direction, q->d, &len))
    return "direction must be finite and non-zero, got " + fmt3(r.direction);
  if (std::isnan(r.tmax) || r.tmax < 0.0f) return "tmax must be >= 0 (or +inf), got " + fmt(r.tmax);
  q->o[0] = r.origin.x();
  q->o[1] = r.origin.y();
  q->o[2] = r.origin.z();
  q->tmax = std::min(r.tmax, kFloatMax);
  q->mask = r.mask;
  return {};
}

std::string to_query(const Segment& s, kernels::RayQuery* q) {
  if (!finite3(s.from)) return "from must be finite, got " + fmt3(s.from);
  if (!finite3(s.to)) return "to must be finite, got " + fmt3(s.to);
  q->o[0] = s.from.x();
  q->o[1] = s.from.y();
  q->o[2] = s.from.z();
  q->mask = s.mask;
  const Eigen::Vector3f d = s.to - s.from;
  double len = 0.0;
  if (!finite3(d)) return "to - from overflows, got " + fmt3(s.to) + " - " + fmt3(s.from);
  if (!unit_direction(d, q->d, &len)) {
    q->d[0] = 0.0f;
    q->d[1] = 0.0f;
    q->d[2] = 1.0f;
    q->tmax = 0.0f;  // from == to: never occluded
    return {};
  }
  q->tmax = static_cast<float>(std::min(len, static_cast<double>(kFloatMax)));
  return {};
}

// The hot-path forms: true when valid (the message comes from to_query, once).
bool convert(const Ray& r, kernels::RayQuery* q) {
  if (!finite3(r.origin) || std::isnan(r.tmax) || r.tmax < 0.0f) return false;
  double len = 0.0;
  if (!unit_direction(r.direction, q->d, &len)) return false;
  q->o[0] = r.origin.x();
  q->o[1] = r.origin.y();
  q->o[2] = r.origin.z();
  q->tmax = std::min(r.tmax, kFloatMax);
  q->mask = r.mask;
  return true;
}

bool convert(const Segment& s, kernels::RayQuery* q) {
  if (!finite3(s.from) || !finite3(s.to) || !finite3(s.to - s.from)) return false;
  return to_query(s, q).empty();  // never fails from here on; no allocation (empty string)
}

// Camera basis; empty string on success.
struct CameraBasis {
  Eigen::Vector3f pos;
  Eigen::Vector3d f, r, u;
  double h, aspect;
};

std::string camera_basis(const Camera& c, CameraBasis* b) {
  if (!finite3(c.position)) return "camera position must be finite, got " + fmt3(c.position);
  if (!finite3(c.forward) || c.forward.squaredNorm() == 0.0f)
    return "camera forward must be finite and non-zero, got " + fmt3(c.forward);
  if (!finite3(c.up)) return "camera up must be finite, got " + fmt3(c.up);
  if (!(c.vertical_fov > 0.0f && c.vertical_fov < 3.14159265f))
    return "camera vertical_fov must be in (0, pi) radians, got " + fmt(c.vertical_fov);
  if (!(c.aspect > 0.0f) || !std::isfinite(c.aspect)) return "camera aspect must be finite and > 0, got " + fmt(c.aspect);
  b->pos = c.position;
  b->f = c.forward.cast<double>().normalized();
  const Eigen::Vector3d right = b->f.cross(c.up.cast<double>());
  if (!(right.norm() > 1e-9 * c.up.cast<double>().norm()) || c.up.squaredNorm() == 0.0f)
    return "camera up must be non-zero and not parallel to forward, got " + fmt3(c.up);
  b->r = right.normalized();
  b->u = b->r.cross(b->f);
  b->h = std::tan(0.5 * static_cast<double>(c.vertical_fov));
  b->aspect = c.aspect;
  return {};
}

// Unit directions of the camera rays through the finite screen points s[0, m), 3 floats
// per point, in one plain loop over the points (vectorised: the double square roots
// and divisions of a chunk overlap). camera_rays and pick both call it, so pick's rays
// are camera_rays' bit for bit. The direction is forward + x right + y up with
// forward, right, up orthonormal, so its length is >= 1: never zero, and finite in
// double for any finite float screen point.
void camera_directions(const CameraBasis& b, const Eigen::Vector2f* s, uint32_t m, float* IMPACT_RESTRICT dir) {
  IMPACT_ASSERT(m <= kRayGrain);
  const double hx = b.h * b.aspect, hy = b.h;
  const double f0 = b.f.x(), f1 = b.f.y(), f2 = b.f.z();
  const double r0 = b.r.x(), r1 = b.r.y(), r2 = b.r.z();
  const double u0 = b.u.x(), u1 = b.u.y(), u2 = b.u.z();
  double sx[kRayGrain], sy[kRayGrain];  // widened first: GCC 12 vectorises no loop mixing the two
  for (uint32_t k = 0; k < m; ++k) {
    sx[k] = static_cast<double>(s[k].x());
    sy[k] = static_cast<double>(s[k].y());
  }
  for (uint32_t k = 0; k < m; ++k) {
    const double x = (2.0 * sx[k] - 1.0) * hx;
    const double y = (1.0 - 2.0 * sy[k]) * hy;
    const double dx = f0 + x * r0 + y * u0;
    const double dy = f1 + x * r1 + y * u1;
    const double dz = f2 + x * r2 + y * u2;
    const double inv = 1.0 / std::sqrt(dx * dx + dy * dy + dz * dz);
    dir[3 * k] = static_cast<float>(dx * inv);
    dir[3 * k + 1] = static_cast<float>(dy * inv);
    dir[3 * k + 2] = static_cast<float>(dz * inv);
  }
}

bool finite2(const Eigen::Vector2f& s) { return std::isfinite(s.x()) && std::isfinite(s.y()); }

Status api_error(StatusCode code, const std::string& msg) { return Status(code, msg); }

}  // namespace

// ------------------------------------------------------------------------------------
class RaySceneImpl {
 public:
  RaySceneDesc desc;
  host::Executor exec;
  host::SceneData data;
  host::SceneChanges changes;
  std::unique_ptr<host::TraceBackend> backend;
  RaySceneInfo info;

  explicit RaySceneImpl(const RaySceneDesc& d) : desc(d), exec(d.backend_threads, d.threads) {}

  bool pending() const { return changes.any(); }
  static const RaySceneImpl* of(const RayScene& s) { return s.impl_.get(); }

  // Finalises best into a RayHit (point, normal from the stored primitives, or for a
  // triangle from ng when finite and non-zero). ng: the backend's unnormalised
  // geometric normal of a triangle hit, or null.
  void finish(const kernels::RayQuery& q, const kernels::RayBest& b, const float* ng, RayHit* out) const {
    RayHit h;
    if (b.kind == kernels::kRayHitNone || q.tmax == 0.0f) {
      *out = h;
      return;
    }
    const Eigen::Vector3d o(q.o[0], q.o[1], q.o[2]);
    const Eigen::Vector3d d(q.d[0], q.d[1], q.d[2]);
    const Eigen::Vector3d p = o + static_cast<double>(b.t) * d;
    Eigen::Vector3d n = Eigen::Vector3d::Zero();
    const host::SceneData& s = data;
    switch (b.kind) {
      case kernels::kRayHitTriangle: {
        h.kind = HitKind::kTriangle;
        const auto it = std::upper_bound(s.mesh_first_tri.begin(), s.mesh_first_tri.end(), b.prim);
        const uint32_t mesh = static_cast<uint32_t>(it - s.mesh_first_tri.begin()) - 1;
        h.id = mesh;
        h.prim = b.prim - s.mesh_first_tri[mesh];
        if (ng != nullptr) {
          // Embree's Ng: the same cross product in float, from vertices it already read.
          n = Eigen::Vector3d(ng[0], ng[1], ng[2]);
          const double l2 = n.squaredNorm();
          if (l2 > 0.0 && l2 < std::numeric_limits<double>::infinity()) break;
        }
        auto vert = [&](int k) {
          const float* v = s.vertices.data() + 3 * size_t{s.indices[3 * size_t{b.prim} + k]};
          return Eigen::Vector3d(v[0], v[1], v[2]);
        };
        const Eigen::Vector3d v0 = vert(0);
        n = (vert(1) - v0).cross(vert(2) - v0);
        break;
      }
      case kernels::kRayHitSphere: {
        h.kind = HitKind::kSphere;
        h.id = b.prim;
        if (b.prim < s.s_body.size()) h.body = s.s_body[b.prim];
        if (b.t > 0.0f) n = p - Eigen::Vector3d(s.sx[b.prim], s.sy[b.prim], s.sz[b.prim]);
        break;
      }
      case kernels::kRayHitCapsule: {
        h.kind = HitKind::kCapsule;
        h.id = b.prim;
        if (b.t > 0.0f) {
          const uint32_t i = b.prim;
          const Eigen::Vector3d a(s.ax[i], s.ay[i], s.az[i]), e(s.bx[i], s.by[i], s.bz[i]);
          const Eigen::Vector3d ab = e - a;
          const double l2 = ab.squaredNorm();
          const double u = l2 > 0.0 ? std::clamp((p - a).dot(ab) / l2, 0.0, 1.0) : 0.0;
          n = p - (a + u * ab);
        }
        break;
      }
      case kernels::kRayHitShape: {
        h.kind = HitKind::kShape;
        h.id = b.prim;
        // Re-trace the one object for its normal and child (the same deterministic
        // test that found t, so the same hit).
        const host::SceneData::ShapeObject& ob = s.objects[b.prim];
        const ShapeRayHit sh = host::ray_posed_shape(
            *s.shape_store, s.shape_store->shapes[ob.shape], ob.R, ob.p, Eigen::Vector3f(q.o[0], q.o[1], q.o[2]),
            Eigen::Vector3f(q.d[0], q.d[1], q.d[2]), q.tmax);
        if (b.prim < s.o_body.size()) h.body = s.o_body[b.prim];
        if (sh.hit) {
          h.prim = sh.child == kNoChild ? 0u : sh.child;
          n = sh.normal.cast<double>();  // -d inside a solid; the triangle's for mesh shapes
        }
        break;
      }
      case kernels::kRayHitPlane: {
        h.kind = HitKind::kPlane;
        h.id = b.prim;
        if (b.prim < s.p_handle.size()) h.plane = s.p_handle[b.prim];
        const kernels::PlaneRecord& pl = s.planes[b.prim];
        if (b.t > 0.0f) n = Eigen::Vector3d(pl.n[0], pl.n[1], pl.n[2]);
        break;
      }
      default: break;
    }
    const double nl = n.norm();
    if (nl > 0.0) {
      n /= nl;
      if (n.dot(d) > 0.0) n = -n;
    } else {
      n = -d;
    }
    h.t = b.t;
    h.point = p.cast<float>();
    h.normal = n.cast<float>();
    *out = h;
  }

  // Chunked closest-hit over rays produced by fill(b, m, q), which writes queries
  // b .. b + m - 1 into q[0, m) and returns m, or the position k < m of the first
  // invalid one; describe(i) then gives the message of the first invalid one (off the
  // hot path).
  template <class Fill, class Describe>
  Status closest(size_t n, const char* what, bool coherent, Fill&& fill, Describe&& describe, RayHit* out) const {
    if (pending()) return api_error(StatusCode::kInvalidArgument, "RayScene: geometry changed since the last commit(); call commit() before querying");
    if (n > 0xffffffffu) return api_error(StatusCode::kInvalidArgument, std::string("too many ") + what + "s in one call (at most 2^32 - 1)");
    const uint32_t chunks = host::chunk_count(n, kRayGrain);
    std::vector<uint32_t> bad(chunks, 0xffffffffu);
    exec.for_each_chunk(n, kRayGrain, [&](uint32_t b, uint32_t e, uint32_t c) {
      kernels::RayQuery q[kRayGrain] = {};
      kernels::RayBest best[kRayGrain];
      float ng[3 * kRayGrain];  // triangle normals from the backend, when it has them
      const uint32_t m = e - b;
      if (const uint32_t k = fill(b, m, q); k != m) {
        bad[c] = b + k;
        return;
      }
      for (uint32_t k = 0; k < m; ++k) best[k] = {q[k].tmax, kernels::kRayHitNone, 0};
      const bool have_ng = backend && backend->closest(q, best, ng, m, coherent);
      kernels::ray_closest_planes(data.planes.data(), static_cast<uint32_t>(data.planes.size()), q, best, {0, m});
      for (uint32_t k = 0; k < m; ++k) finish(q[k], best[k], have_ng ? ng + 3 * k : nullptr, &out[b + k]);
    });
    for (uint32_t c = 0; c < chunks; ++c)
      if (bad[c] != 0xffffffffu)
        return api_error(StatusCode::kInvalidArgument, std::string(what) + " " + std::to_string(bad[c]) + ": " + describe(bad[c]));
    return Status();
  }
};

// ------------------------------------------------------------------------------------
RayScene::RayScene(std::unique_ptr<RaySceneImpl> impl) : impl_(std::move(impl)) {}
RayScene::~RayScene() = default;

Status RayScene::create(const RaySceneDesc& desc, std::unique_ptr<RayScene>* out) {
  if (out == nullptr) return Status(StatusCode::kInvalidArgument, "RayScene::create: out is null");
  out->reset();
  if (desc.packet_width != 1 && desc.packet_width != 4 && desc.packet_width != 8 && desc.packet_width != 16)
    return Status(StatusCode::kInvalidArgument,
                  "RaySceneDesc: packet_width must be 1, 4, 8 or 16, got " + std::to_string(desc.packet_width));
  if (desc.embree_streams != EmbreeStreams::kAuto && desc.embree_streams != EmbreeStreams::kNever &&
      desc.embree_streams != EmbreeStreams::kAlways)
    return Status(StatusCode::kInvalidArgument, "RaySceneDesc: embree_streams must be kAuto, kNever or kAlways, got " +
                                                    std::to_string(static_cast<int>(desc.embree_streams)));
  if (desc.embree_streams == EmbreeStreams::kAlways && desc.packet_width != 1)
    return Status(StatusCode::kInvalidArgument, "RaySceneDesc: embree_streams kAlways needs packet_width 1, got " +
                                                    std::to_string(desc.packet_width));
  if (!backend_available(desc.backend_threads))
    return Status(StatusCode::kUnsupported, std::string("RaySceneDesc: thread backend ") +
                                                to_string(desc.backend_threads) + " is not built in");
  auto impl = std::make_unique<RaySceneImpl>(desc);
  if (desc.backend == RayBackend::kEmbree) {
    Status s;
    impl->backend = host::make_embree_backend(desc, impl->data, impl->exec.threads(), &s);
    if (!s.ok()) return s;
  } else if (desc.backend == RayBackend::kLbvh) {
    impl->backend = host::make_lbvh_backend(desc);
  } else {
    return Status(StatusCode::kInvalidArgument, "RaySceneDesc: unknown backend");
  }
  out->reset(new RayScene(std::move(impl)));
  return Status();
}

Status RayScene::add_mesh(const Eigen::Ref<const Eigen::Matrix3Xf>& vertices,
                          const Eigen::Ref<const Eigen::Matrix<uint32_t, 3, Eigen::Dynamic>>& triangles,
                          uint32_t layer, MeshHandle* out) {
  host::SceneData& d = impl_->data;
  const uint64_t nv = static_cast<uint64_t>(vertices.cols()), nt = static_cast<uint64_t>(triangles.cols());
  if (d.vertices.size() / 3 + nv >= (1ull << 32) || d.triangle_count() + nt >= (1ull << 30))
    return Status(StatusCode::kCapacityExceeded, "add_mesh: the scene holds at most 2^30 - 1 triangles and 2^32 - 1 vertices");
  for (uint64_t i = 0; i < nv; ++i)
    if (!vertices.col(static_cast<Eigen::Index>(i)).allFinite())
      return Status(StatusCode::kInvalidArgument, "add_mesh: vertex " + std::to_string(i) + " must be finite, got " +
                                                      fmt3(vertices.col(static_cast<Eigen::Index>(i))));
  for (uint64_t t = 0; t < nt; ++t)
    for (int k = 0; k < 3; ++k) {
      const uint32_t v = triangles(k, static_cast<Eigen::Index>(t));
      if (v >= nv)
        return Status(StatusCode::kInvalidArgument, "add_mesh: triangle " + std::to_string(t) + " vertex " +
                                                        std::to_string(k) + " index " + std::to_string(v) +
                                                        " out of range (" + std::to_string(nv) + " vertices)");
    }
  const uint32_t v0 = static_cast<uint32_t>(d.vertices.size() / 3);
  if (d.mesh_first_tri.empty()) {
    d.mesh_first_tri.push_back(0);
    d.mesh_first_vertex.push_back(0);
  }
  d.vertices.reserve(d.vertices.size() + 3 * nv);
  for (uint64_t i = 0; i < nv; ++i)
    for (int k = 0; k < 3; ++k) d.vertices.push_back(vertices(k, static_cast<Eigen::Index>(i)));
  for (uint64_t t = 0; t < nt; ++t) {
    for (int k = 0; k < 3; ++k) d.indices.push_back(v0 + triangles(k, static_cast<Eigen::Index>(t)));
    d.tri_layer.push_back(layer);
  }
  d.mesh_first_tri.push_back(d.triangle_count());
  d.mesh_first_vertex.push_back(static_cast<uint32_t>(d.vertices.size() / 3));
  d.mesh_layer.push_back(layer);
  ++impl_->changes.meshes_added;
  if (out) out->id = d.mesh_count() - 1;
  return Status();
}

namespace {

template <class T>
void assign(host::Buffer<T>& dst, std::span<const T> src) {
  dst.assign(src.begin(), src.end());
}

}  // namespace

Status RayScene::set_spheres(std::span<const float> x, std::span<const float> y, std::span<const float> z,
                             std::span<const float> radius, std::span<const uint32_t> layer) {
  const size_t n = x.size();
  if (y.size() != n || z.size() != n || radius.size() != n || (!layer.empty() && layer.size() != n))
    return Status(StatusCode::kSizeMismatch, "set_spheres: x, y, z, radius (and layer, when given) must have equal sizes, got " +
                                                 std::to_string(n) + ", " + std::to_string(y.size()) + ", " +
                                                 std::to_string(z.size()) + ", " + std::to_string(radius.size()) +
                                                 ", " + std::to_string(layer.size()));
  if (n + impl_->data.capsule_count() >= (1u << 30))
    return Status(StatusCode::kCapacityExceeded, "set_spheres: spheres + capsules must be < 2^30");
  for (size_t i = 0; i < n; ++i) {
    if (!std::isfinite(x[i]) || !std::isfinite(y[i]) || !std::isfinite(z[i]))
      return Status(StatusCode::kInvalidArgument, "sphere " + std::to_string(i) + ": centre must be finite, got (" +
                                                      fmt(x[i]) + ", " + fmt(y[i]) + ", " + fmt(z[i]) + ")");
    if (!(radius[i] > 0.0f) || !std::isfinite(radius[i]))
      return Status(StatusCode::kInvalidArgument,
                    "sphere " + std::to_string(i) + ": radius must be finite and > 0, got " + fmt(radius[i]));
  }
  host::SceneData& d = impl_->data;
  impl_->changes.spheres = true;
  impl_->changes.spheres_resized |= d.sphere_count() != n;
  assign(d.sx, x);
  assign(d.sy, y);
  assign(d.sz, z);
  assign(d.sr, radius);
  if (layer.empty())
    d.s_layer.assign(n, 1u);
  else
    assign(d.s_layer, layer);
  d.s_body.clear();
  return Status();
}

Status RayScene::sync_spheres(const World& world) {
  const BodyArrays b = world.bodies();
  Status s = set_spheres(b.pos_x, b.pos_y, b.pos_z, b.radius, b.layer);
  if (!s.ok()) return s;
  impl_->data.s_body.assign(b.handles.begin(), b.handles.end());
  return Status();
}

Status RayScene::set_capsules(const Eigen::Ref<const Eigen::Matrix3Xf>& a, const Eigen::Ref<const Eigen::Matrix3Xf>& b,
                              std::span<const float> radius, std::span<const uint32_t> layer) {
  const size_t n = static_cast<size_t>(a.cols());
  if (static_cast<size_t>(b.cols()) != n || radius.size() != n || (!layer.empty() && layer.size() != n))
    return Status(StatusCode::kSizeMismatch, "set_capsules: a, b, radius (and layer, when given) must have equal sizes, got " +
                                                 std::to_string(n) + ", " + std::to_string(b.cols()) + ", " +
                                                 std::to_string(radius.size()) + ", " + std::to_string(layer.size()));
  if (n + impl_->data.sphere_count() >= (1u << 30))
    return Status(StatusCode::kCapacityExceeded, "set_capsules: spheres + capsules must be < 2^30");
  for (size_t i = 0; i < n; ++i) {
    const auto col = static_cast<Eigen::Index>(i);
    if (!a.col(col).allFinite()) return Status(StatusCode::kInvalidArgument, "capsule " + std::to_string(i) + ": a must be finite, got " + fmt3(a.col(col)));
    if (!b.col(col).allFinite()) return Status(StatusCode::kInvalidArgument, "capsule " + std::to_string(i) + ": b must be finite, got " + fmt3(b.col(col)));
    if (!(radius[i] > 0.0f) || !std::isfinite(radius[i]))
      return Status(StatusCode::kInvalidArgument,
                    "capsule " + std::to_string(i) + ": radius must be finite and > 0, got " + fmt(radius[i]));
  }
  host::SceneData& d = impl_->data;
  impl_->changes.capsules = true;
  impl_->changes.capsules_resized |= d.capsule_count() != n;
  for (host::Buffer<float>* v : {&d.ax, &d.ay, &d.az, &d.bx, &d.by, &d.bz}) v->resize(n);
  for (size_t i = 0; i < n; ++i) {
    const auto col = static_cast<Eigen::Index>(i);
    d.ax[i] = a(0, col);
    d.ay[i] = a(1, col);
    d.az[i] = a(2, col);
    d.bx[i] = b(0, col);
    d.by[i] = b(1, col);
    d.bz[i] = b(2, col);
  }
  assign(d.cr, radius);
  if (layer.empty())
    d.c_layer.assign(n, 1u);
  else
    assign(d.c_layer, layer);
  return Status();
}

Status RayScene::set_planes(const Eigen::Ref<const Eigen::Matrix3Xf>& normals, std::span<const float> offsets,
                            std::span<const uint32_t> layer) {
  const size_t n = static_cast<size_t>(normals.cols());
  if (offsets.size() != n || (!layer.empty() && layer.size() != n))
    return Status(StatusCode::kSizeMismatch, "set_planes: normals, offsets (and layer, when given) must have equal sizes, got " +
                                                 std::to_string(n) + ", " + std::to_string(offsets.size()) + ", " +
                                                 std::to_string(layer.size()));
  host::Buffer<kernels::PlaneRecord> planes(n);
  for (size_t i = 0; i < n; ++i) {
    const auto col = static_cast<Eigen::Index>(i);
    float u[3];
    double len = 0.0;
    if (!unit_direction(normals.col(col), u, &len))
      return Status(StatusCode::kInvalidArgument, "plane " + std::to_string(i) + ": normal must be finite and non-zero, got " +
                                                      fmt3(normals.col(col)));
    if (!std::isfinite(offsets[i]))
      return Status(StatusCode::kInvalidArgument, "plane " + std::to_string(i) + ": offset must be finite, got " + fmt(offsets[i]));
    // dot(n, x) <= offset with n scaled to unit: the offset scales by 1 / |n|.
    planes[i] = {{u[0], u[1], u[2]}, static_cast<float>(offsets[i] / len), layer.empty() ? 1u : layer[i]};
  }
  impl_->data.planes = std::move(planes);
  impl_->data.p_handle.clear();
  return Status();
}

Status RayScene::set_shapes(const ShapeSet& shapes, std::span<const ShapeId> shape_of, std::span<const Pose> poses,
                            std::span<const uint32_t> layer) {
  const size_t n = shape_of.size();
  if (poses.size() != n || (!layer.empty() && layer.size() != n))
    return Status(StatusCode::kSizeMismatch, "set_shapes: shape_of, poses (and layer, when given) must have equal sizes, got " +
                                                 std::to_string(n) + ", " + std::to_string(poses.size()) + ", " +
                                                 std::to_string(layer.size()));
  if (n >= (1u << 30)) return Status(StatusCode::kCapacityExceeded, "set_shapes: at most 2^30 - 1 objects");
  const ShapeStore& store = shapes.store();
  for (size_t i = 0; i < n; ++i) {
    if (shape_of[i].index >= store.shapes.size())
      return Status(StatusCode::kInvalidArgument, "set_shapes: object " + std::to_string(i) + ": unknown shape id " +
                                                      std::to_string(shape_of[i].index) + " (" +
                                                      std::to_string(store.shapes.size()) + " shapes)");
    if (store.shapes[shape_of[i].index].type == ShapeType::kHalfSpace)
      return Status(StatusCode::kInvalidArgument, "set_shapes: object " + std::to_string(i) +
                                                      ": half-spaces are unbounded; add them with set_planes");
    if (!host::pose_ok(poses[i])) {
      const std::string who = "set_shapes: object " + std::to_string(i);
      return host::check_pose(poses[i], who.c_str());
    }
  }
  host::SceneData& d = impl_->data;
  impl_->changes.shapes = true;
  impl_->changes.shapes_resized |= d.shape_count() != n;
  d.shape_store = &store;
  d.objects.resize(n);
  d.o_body.clear();
  for (host::Buffer<float>* v :
       {&d.ob_min_x, &d.ob_min_y, &d.ob_min_z, &d.ob_max_x, &d.ob_max_y, &d.ob_max_z})
    v->resize(n);
  impl_->exec.for_each_chunk(n, 1024, [&](uint32_t first, uint32_t end, uint32_t) {
    for (uint32_t i = first; i < end; ++i) {
      const ShapeRecord& rec = store.shapes[shape_of[i].index];
      const Pose pose = host::normalized(poses[i]);
      host::SceneData::ShapeObject& ob = d.objects[i];
      ob.R = host::shape_rotation(rec, pose);
      ob.p = pose.position;
      ob.shape = shape_of[i].index;
      ob.layer = layer.empty() ? 1u : layer[i];
      Eigen::Vector3f lo, hi;
      host::posed_bounds(rec, pose, store.hulls, &lo, &hi);
      // Pad by a few ulps of the box's magnitude: the bounds and the ray test round
      // differently, and a ray grazing the shape must not be culled by its box.
      const float pad = 8.0f * std::numeric_limits<float>::epsilon() *
                        std::max(lo.cwiseAbs().maxCoeff(), hi.cwiseAbs().maxCoeff());
      d.ob_min_x[i] = lo.x() - pad;
      d.ob_min_y[i] = lo.y() - pad;
      d.ob_min_z[i] = lo.z() - pad;
      d.ob_max_x[i] = hi.x() + pad;
      d.ob_max_y[i] = hi.y() + pad;
      d.ob_max_z[i] = hi.z() + pad;
    }
  });
  return Status();
}

Status RayScene::sync_world(const World& world) {
  const BodyArrays b = world.bodies();
  const size_t n = b.size();
  // Split the bodies: plain spheres keep their slot order, shaped bodies theirs.
  std::vector<float> x, y, z, r;
  std::vector<uint32_t> s_layer, o_layer;
  std::vector<BodyHandle> s_body, o_body;
  std::vector<ShapeId> shape_of;
  std::vector<Pose> poses;
  const size_t shaped =
      b.shape.empty() ? 0 : static_cast<size_t>(std::count_if(b.shape.begin(), b.shape.end(), [](uint32_t v) {
        return v != BodyArrays::kSphereBody;
      }));
  for (auto* v : {&x, &y, &z, &r}) v->reserve(n - shaped);
  s_layer.reserve(n - shaped);
  s_body.reserve(n - shaped);
  shape_of.reserve(shaped);
  poses.reserve(shaped);
  o_layer.reserve(shaped);
  o_body.reserve(shaped);
  for (size_t i = 0; i < n; ++i) {
    if (shaped != 0 && b.shape[i] != BodyArrays::kSphereBody) {
      shape_of.push_back(ShapeId{b.shape[i]});
      Pose p;
      p.position = Eigen::Vector3f(b.pos_x[i], b.pos_y[i], b.pos_z[i]);
      p.orientation = Eigen::Quaternionf(b.qw[i], b.qx[i], b.qy[i], b.qz[i]);
      poses.push_back(p);
      o_layer.push_back(b.layer[i]);
      o_body.push_back(b.handles[i]);
    } else {
      x.push_back(b.pos_x[i]);
      y.push_back(b.pos_y[i]);
      z.push_back(b.pos_z[i]);
      r.push_back(b.radius[i]);
      s_layer.push_back(b.layer[i]);
      s_body.push_back(b.handles[i]);
    }
  }
  const PlaneArrays pl = world.planes();
  Eigen::Matrix3Xf normals(3, static_cast<Eigen::Index>(pl.size()));
  for (size_t i = 0; i < pl.size(); ++i)
    normals.col(static_cast<Eigen::Index>(i)) =
        Eigen::Vector3f(pl.normal_x[i], pl.normal_y[i], pl.normal_z[i]);
  // The world validated all of this; the setters check again (cheap) and say what is wrong.
  Status s = set_spheres(x, y, z, r, s_layer);
  if (s.ok()) s = set_shapes(world.shapes(), shape_of, poses, o_layer);
  if (s.ok()) s = set_planes(normals, pl.offset, pl.layer);
  if (!s.ok()) return Status(s.code(), "sync_world: " + s.message());
  impl_->data.s_body = std::move(s_body);
  impl_->data.o_body = std::move(o_body);
  impl_->data.p_handle.assign(pl.handles.begin(), pl.handles.end());
  return Status();
}

Status RayScene::commit() {
  const auto t0 = std::chrono::steady_clock::now();
  bool rebuilt = false;
  if (impl_->backend && impl_->changes.any()) {
    Status s = impl_->backend->commit(impl_->exec, impl_->data, impl_->changes, &rebuilt);
    if (!s.ok()) return s;
  }
  impl_->changes = {};
  RaySceneInfo& in = impl_->info;
  const host::SceneData& d = impl_->data;
  in.meshes = d.mesh_count();
  in.triangles = d.triangle_count();
  in.spheres = d.sphere_count();
  in.capsules = d.capsule_count();
  in.planes = static_cast<uint32_t>(d.planes.size());
  in.shapes = d.shape_count();
  in.dynamic_rebuilt = rebuilt;
  in.commit_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return Status();
}

Status RayScene::closest_hit(std::span<const Ray> rays, std::span<RayHit> out) const {
  if (out.size() != rays.size())
    return Status(StatusCode::kSizeMismatch, "closest_hit: out has " + std::to_string(out.size()) + " entries for " +
                                                 std::to_string(rays.size()) + " rays");
  return impl_->closest(
      rays.size(), "ray", false,
      [&](uint32_t b, uint32_t m, kernels::RayQuery* q) {
        for (uint32_t k = 0; k < m; ++k)
          if (!convert(rays[b + k], &q[k])) return k;
        return m;
      },
      [&](uint32_t i) {
        kernels::RayQuery q;
        return to_query(rays[i], &q);
      },
      out.data());
}

Status RayScene::any_hit(std::span<const Segment> segments, std::span<uint8_t> out) const {
  if (out.size() != segments.size())
    return Status(StatusCode::kSizeMismatch, "any_hit: out has " + std::to_string(out.size()) + " entries for " +
                                                 std::to_string(segments.size()) + " segments");
  if (impl_->pending())
    return Status(StatusCode::kInvalidArgument, "RayScene: geometry changed since the last commit(); call commit() before querying");
  const size_t n = segments.size();
  if (n > 0xffffffffu) return Status(StatusCode::kInvalidArgument, "too many segments in one call (at most 2^32 - 1)");
  const uint32_t chunks = host::chunk_count(n, kRayGrain);
  std::vector<uint32_t> bad(chunks, 0xffffffffu);
  const RaySceneImpl& im = *impl_;
  im.exec.for_each_chunk(n, kRayGrain, [&](uint32_t b, uint32_t e, uint32_t c) {
    kernels::RayQuery q[kRayGrain] = {};
    uint8_t hit[kRayGrain];
    const uint32_t m = e - b;
    for (uint32_t k = 0; k < m; ++k) {
      if (!convert(segments[b + k], &q[k])) {
        bad[c] = b + k;
        return;
      }
      hit[k] = q[k].tmax == 0.0f ? 2 : 0;  // 2: zero length, skipped by every pass
    }
    kernels::ray_any_planes(im.data.planes.data(), static_cast<uint32_t>(im.data.planes.size()), q, hit, {0, m});
    if (im.backend) im.backend->any(q, hit, m);
    for (uint32_t k = 0; k < m; ++k) out[b + k] = hit[k] == 1 ? 1 : 0;
  });
  for (uint32_t c = 0; c < chunks; ++c)
    if (bad[c] != 0xffffffffu)
      return Status(StatusCode::kInvalidArgument, "segment " + std::to_string(bad[c]) + ": " + [&] {
        kernels::RayQuery q;
        return to_query(segments[bad[c]], &q);
      }());
  return Status();
}

Status RayScene::pick(const Camera& camera, std::span<const Eigen::Vector2f> screen, uint32_t mask,
                      std::span<RayHit> out) const {
  if (out.size() != screen.size())
    return Status(StatusCode::kSizeMismatch, "pick: out has " + std::to_string(out.size()) + " entries for " +
                                                 std::to_string(screen.size()) + " screen points");
  CameraBasis basis;
  if (std::string e = camera_basis(camera, &basis); !e.empty()) return Status(StatusCode::kInvalidArgument, "pick: " + e);
  return impl_->closest(
      screen.size(), "screen point", true,
      [&](uint32_t b, uint32_t m, kernels::RayQuery* q) {
        for (uint32_t k = 0; k < m; ++k)
          if (!finite2(screen[b + k])) return k;
        float dir[3 * kRayGrain];
        camera_directions(basis, screen.data() + b, m, dir);
        // What closest_hit does with camera_rays' rays (convert), without the checks
        // that cannot fail here: a finite origin, tmax = +inf, a finite unit direction.
        for (uint32_t k = 0; k < m; ++k) {
          double len = 0.0;
          (void)unit_direction(Eigen::Vector3f(dir[3 * k], dir[3 * k + 1], dir[3 * k + 2]), q[k].d, &len);
          q[k].o[0] = basis.pos.x();
          q[k].o[1] = basis.pos.y();
          q[k].o[2] = basis.pos.z();
          q[k].tmax = kFloatMax;
          q[k].mask = mask;
        }
        return m;
      },
      [&](uint32_t i) -> std::string {
        const Eigen::Vector2f& s = screen[i];
        return "must be finite, got (" + fmt(s.x()) + ", " + fmt(s.y()) + ")";
      },
      out.data());
}

Status RayScene::set_threads(Backend backend, uint32_t threads) {
  if (!backend_available(backend))
    return Status(StatusCode::kUnsupported, std::string("set_threads: backend ") + to_string(backend) + " is not built in");
  impl_->exec = host::Executor(backend, threads);
  impl_->desc.backend_threads = backend;
  impl_->desc.threads = threads;
  if (impl_->backend) impl_->backend->set_threads(impl_->exec.threads());
  return Status();
}

const RaySceneDesc& RayScene::desc() const { return impl_->desc; }
const RaySceneInfo& RayScene::info() const { return impl_->info; }

Status camera_rays(const Camera& camera, std::span<const Eigen::Vector2f> screen, uint32_t mask, std::span<Ray> out) {
  if (out.size() != screen.size())
    return Status(StatusCode::kSizeMismatch, "camera_rays: out has " + std::to_string(out.size()) + " entries for " +
                                                 std::to_string(screen.size()) + " screen points");
  CameraBasis basis;
  if (std::string e = camera_basis(camera, &basis); !e.empty()) return Status(StatusCode::kInvalidArgument, "camera_rays: " + e);
  for (size_t i = 0; i < screen.size(); ++i)
    if (!finite2(screen[i]))
      return Status(StatusCode::kInvalidArgument, "camera_rays: screen point " + std::to_string(i) + " must be finite");
  float dir[3 * kRayGrain];
  for (size_t b = 0; b < screen.size(); b += kRayGrain) {
    const uint32_t m = static_cast<uint32_t>(std::min<size_t>(kRayGrain, screen.size() - b));
    camera_directions(basis, screen.data() + b, m, dir);
    for (uint32_t k = 0; k < m; ++k) {
      Ray& r = out[b + k];
      r.origin = basis.pos;
      r.direction = Eigen::Vector3f(dir[3 * k], dir[3 * k + 1], dir[3 * k + 2]);
      r.tmax = std::numeric_limits<float>::infinity();
      r.mask = mask;
    }
  }
  return Status();
}

// ------------------------------------------------------------------------------------
namespace host {

float shape_ray_t(const SceneData& d, uint32_t i, const kernels::RayQuery& q) {
  const SceneData::ShapeObject& ob = d.objects[i];
  if ((ob.layer & q.mask) == 0) return -1.0f;
  const ShapeRayHit h = ray_posed_shape(*d.shape_store, d.shape_store->shapes[ob.shape], ob.R, ob.p,
                                        Eigen::Vector3f(q.o[0], q.o[1], q.o[2]),
                                        Eigen::Vector3f(q.d[0], q.d[1], q.d[2]), q.tmax);
  return h.hit ? h.t : -1.0f;
}

float shape_user_test(const void* ctx, uint32_t i, const kernels::RayQuery& q) {
  return shape_ray_t(*static_cast<const SceneData*>(ctx), i, q);
}

uint64_t embree_plain_closest(const RayScene& scene, std::span<const Ray> rays) {
  const RaySceneImpl* impl = RaySceneImpl::of(scene);
  void* top = embree_top_scene(impl->backend.get());
  if (top == nullptr || impl->pending()) return UINT64_MAX;
  return embree_plain_closest_raw(top, rays);
}

uint64_t embree_plain_closest_store(const RayScene& scene, std::span<const Ray> rays, std::span<PlainHit> out) {
  const RaySceneImpl* impl = RaySceneImpl::of(scene);
  void* top = embree_top_scene(impl->backend.get());
  if (top == nullptr || impl->pending() || out.size() != rays.size()) return UINT64_MAX;
  return embree_plain_closest_store_raw(top, rays, out);
}

uint64_t embree_plain_any(const RayScene& scene, std::span<const Segment> segments) {
  const RaySceneImpl* impl = RaySceneImpl::of(scene);
  void* top = embree_top_scene(impl->backend.get());
  if (top == nullptr || impl->pending()) return UINT64_MAX;
  return embree_plain_any_raw(top, segments);
}

}  // namespace host

}  // namespace impact
