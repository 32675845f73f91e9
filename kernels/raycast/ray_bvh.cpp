#include "kernels/raycast/ray_bvh.h"

namespace impact::kernels {
namespace {

IMPACT_INLINE float max2(float a, float b) { return a > b ? a : b; }  // NaN in a -> b
IMPACT_INLINE float min2(float a, float b) { return a < b ? a : b; }  // NaN in a -> b

// 1 + 2 gamma_3, gamma_n = n eps / (1 - n eps), eps = 2^-24 (Ize 2013).
constexpr float kFarScale = 1.0f + 2.0f * (3.0f * 5.9604645e-8f) / (1.0f - 3.0f * 5.9604645e-8f);

struct SlabRay {
  float o[3];
  float inv[3];
  uint32_t neg[3];  // direction component < 0: the near plane is the max plane
};

IMPACT_INLINE SlabRay slab_ray(const RayQuery& q) {
  SlabRay s;
  for (int k = 0; k < 3; ++k) {
    const float d = q.d[k] == 0.0f ? 0.0f : q.d[k];  // -0 -> +0: inv = +inf
    s.o[k] = q.o[k];
    s.inv[k] = 1.0f / d;
    s.neg[k] = d < 0.0f ? 1u : 0u;
  }
  return s;
}

// Box with min_x..max_z at the LbvhNode / SortedBox offsets. Entry distance in *tn.
template <class B>
IMPACT_INLINE bool slab(const B& b, const SlabRay& s, float tfar_limit, float* tn) {
  const float nx = s.neg[0] ? b.max_x : b.min_x, fx = s.neg[0] ? b.min_x : b.max_x;
  const float ny = s.neg[1] ? b.max_y : b.min_y, fy = s.neg[1] ? b.min_y : b.max_y;
  const float nz = s.neg[2] ? b.max_z : b.min_z, fz = s.neg[2] ? b.min_z : b.max_z;
  const float t0x = (nx - s.o[0]) * s.inv[0], t1x = (fx - s.o[0]) * s.inv[0];
  const float t0y = (ny - s.o[1]) * s.inv[1], t1y = (fy - s.o[1]) * s.inv[1];
  const float t0z = (nz - s.o[2]) * s.inv[2], t1z = (fz - s.o[2]) * s.inv[2];
  const float t0 = max2(t0x, max2(t0y, max2(t0z, 0.0f)));
  const float t1 = min2(t1x, min2(t1y, min2(t1z, 3.4e38f))) * kFarScale;
  *tn = t0;
  return t0 <= min2(t1, tfar_limit);
}

// Front-to-back traversal. leaf(s) tests sorted leaf s and returns true to stop;
// limit() is the current best distance (boxes entered beyond it are skipped).
template <class Leaf, class Limit>
IMPACT_INLINE void traverse(const RayTree& t, const RayQuery& q, Leaf&& leaf, Limit&& limit) {
  if (t.n == 0) return;
  if (t.n == 1) {
    leaf(0u);
    return;
  }
  const SlabRay s = slab_ray(q);
  float tn;
  if (!slab(t.nodes[0], s, limit(), &tn)) return;
  struct Entry {
    uint32_t node;
    float tnear;
  };
  Entry stack[kLbvhMaxDepth + 1];
  uint32_t top = 0;
  uint32_t node = 0;
  for (;;) {
    const LbvhNode& nd = t.nodes[node];
    const uint32_t g = nd.split & kLbvhSplitMask;
    const bool left_leaf = (nd.split & kLbvhLeftLeaf) != 0;
    const bool right_leaf = (nd.split & kLbvhRightLeaf) != 0;
    float tl = 0.0f, tr = 0.0f;
    bool hl = left_leaf ? slab(t.leaves[g], s, limit(), &tl) : slab(t.nodes[g], s, limit(), &tl);
    bool hr = right_leaf ? slab(t.leaves[g + 1], s, limit(), &tr)
                         : slab(t.nodes[g + 1], s, limit(), &tr);
    if (left_leaf && hl) {
      if (leaf(g)) return;
      hl = false;
    }
    if (right_leaf && hr) {
      if (leaf(g + 1)) return;
      hr = false;
    }
    // A leaf hit above may have shortened the ray.
    hl = hl && tl <= limit();
    hr = hr && tr <= limit();
    if (hl && hr) {
      if (tl <= tr) {
        stack[top++] = {g + 1, tr};
        node = g;
      } else {
        stack[top++] = {g, tl};
        node = g + 1;
      }
      continue;
    }
    if (hl) {
      node = g;
      continue;
    }
    if (hr) {
      node = g + 1;
      continue;
    }
    bool found = false;
    while (top > 0) {
      const Entry e = stack[--top];
      if (e.tnear <= limit()) {
        node = e.node;
        found = true;
        break;
      }
    }
    if (!found) return;
  }
}

IMPACT_INLINE float test_triangle(const RayQuery& q, const RayShear& sh, const TriangleRecord& rec) {
  if ((rec.layer & q.mask) == 0) return -1.0f;
  return ray_triangle(q, sh, rec.v0, rec.v1, rec.v2);
}

IMPACT_INLINE float test_shape(const RayQuery& q, const ShapeRecord& rec, bool sphere) {
  if ((rec.layer & q.mask) == 0) return -1.0f;
  return sphere ? ray_sphere(q, rec.a[0], rec.a[1], rec.a[2], rec.radius)
                : ray_capsule(q, rec.a, rec.b, rec.radius);
}

}  // namespace

void triangle_bounds(const TriangleSoup& soup, AabbSoAOut out, Range r) {
  for (uint32_t i = r.begin; i < r.end; ++i) {
    const float* a = soup.vertices + 3 * static_cast<size_t>(soup.indices[3 * static_cast<size_t>(i)]);
    const float* b = soup.vertices + 3 * static_cast<size_t>(soup.indices[3 * static_cast<size_t>(i) + 1]);
    const float* c = soup.vertices + 3 * static_cast<size_t>(soup.indices[3 * static_cast<size_t>(i) + 2]);
    out.min_x[i] = min2(a[0], min2(b[0], c[0]));
    out.min_y[i] = min2(a[1], min2(b[1], c[1]));
    out.min_z[i] = min2(a[2], min2(b[2], c[2]));
    out.max_x[i] = max2(a[0], max2(b[0], c[0]));
    out.max_y[i] = max2(a[1], max2(b[1], c[1]));
    out.max_z[i] = max2(a[2], max2(b[2], c[2]));
  }
}

void capsule_bounds(const float* ax, const float* ay, const float* az, const float* bx, const float* by,
                    const float* bz, const float* radius, AabbSoAOut out, Range r) {
#pragma omp simd
  for (uint32_t i = r.begin; i < r.end; ++i) {
    out.min_x[i] = min2(ax[i], bx[i]) - radius[i];
    out.min_y[i] = min2(ay[i], by[i]) - radius[i];
    out.min_z[i] = min2(az[i], bz[i]) - radius[i];
    out.max_x[i] = max2(ax[i], bx[i]) + radius[i];
    out.max_y[i] = max2(ay[i], by[i]) + radius[i];
    out.max_z[i] = max2(az[i], bz[i]) + radius[i];
  }
}

void triangle_records(const TriangleSoup& soup, const SortedBox* leaves, TriangleRecord* out, Range r) {
  for (uint32_t s = r.begin; s < r.end; ++s) {
    const size_t i = leaves[s].index;
    TriangleRecord& o = out[s];
    for (int k = 0; k < 3; ++k) {
      const float* v = soup.vertices + 3 * static_cast<size_t>(soup.indices[3 * i + k]);
      float* dst = k == 0 ? o.v0 : (k == 1 ? o.v1 : o.v2);
      dst[0] = v[0];
      dst[1] = v[1];
      dst[2] = v[2];
    }
    o.layer = soup.layer[i];
  }
}

void shape_records(const ShapeSoA& sh, const SortedBox* leaves, ShapeRecord* out, Range r) {
  for (uint32_t s = r.begin; s < r.end; ++s) {
    const uint32_t i = leaves[s].index;
    ShapeRecord& o = out[s];
    if (i < sh.first_capsule) {
      o.a[0] = o.b[0] = sh.sx[i];
      o.a[1] = o.b[1] = sh.sy[i];
      o.a[2] = o.b[2] = sh.sz[i];
      o.radius = sh.sr[i];
      o.layer = sh.s_layer[i];
    } else {
      const uint32_t c = i - sh.first_capsule;
      o.a[0] = sh.ax[c];
      o.a[1] = sh.ay[c];
      o.a[2] = sh.az[c];
      o.b[0] = sh.bx[c];
      o.b[1] = sh.by[c];
      o.b[2] = sh.bz[c];
      o.radius = sh.cr[c];
      o.layer = sh.c_layer[c];
    }
  }
}

void ray_closest_triangles(const RayTree& t, const TriangleRecord* rec, const RayQuery* rays,
                           RayBest* io_best, Range r) {
  for (uint32_t i = r.begin; i < r.end; ++i) {
    RayQuery q = rays[i];
    RayBest best = io_best[i];
    q.tmax = best.t;
    const RayShear sh = ray_shear(q);
    traverse(
        t, q,
        [&](uint32_t s) {
          const float th = test_triangle(q, sh, rec[s]);
          if (th >= 0.0f && ray_best_better(th, kRayHitTriangle, t.leaves[s].index, best)) {
            best = {th, kRayHitTriangle, t.leaves[s].index};
            q.tmax = th;
          }
          return false;
        },
        [&] { return q.tmax; });
    io_best[i] = best;
  }
}

void ray_any_triangles(const RayTree& t, const TriangleRecord* rec, const RayQuery* rays,
                       uint8_t* io_hit, Range r) {
  for (uint32_t i = r.begin; i < r.end; ++i) {
    if (io_hit[i]) continue;
    const RayQuery q = rays[i];
    const RayShear sh = ray_shear(q);
    bool hit = false;
    traverse(
        t, q,
        [&](uint32_t s) {
          hit = test_triangle(q, sh, rec[s]) >= 0.0f;
          return hit;
        },
        [&] { return q.tmax; });
    io_hit[i] = hit ? 1 : 0;
  }
}

void ray_closest_shapes(const RayTree& t, const ShapeRecord* rec, uint32_t first_capsule,
                        const RayQuery* rays, RayBest* io_best, Range r) {
  for (uint32_t i = r.begin; i < r.end; ++i) {
    RayQuery q = rays[i];
    RayBest best = io_best[i];
    q.tmax = best.t;
    traverse(
        t, q,
        [&](uint32_t s) {
          const uint32_t idx = t.leaves[s].index;
          const bool sphere = idx < first_capsule;
          const float th = test_shape(q, rec[s], sphere);
          if (th < 0.0f) return false;
          const uint32_t kind = sphere ? kRayHitSphere : kRayHitCapsule;
          const uint32_t prim = sphere ? idx : idx - first_capsule;
          if (ray_best_better(th, kind, prim, best)) {
            best = {th, kind, prim};
            q.tmax = th;
          }
          return false;
        },
        [&] { return q.tmax; });
    io_best[i] = best;
  }
}

void ray_any_shapes(const RayTree& t, const ShapeRecord* rec, uint32_t first_capsule,
                    const RayQuery* rays, uint8_t* io_hit, Range r) {
  for (uint32_t i = r.begin; i < r.end; ++i) {
    if (io_hit[i]) continue;
    const RayQuery q = rays[i];
    bool hit = false;
    traverse(
        t, q,
        [&](uint32_t s) {
          hit = test_shape(q, rec[s], t.leaves[s].index < first_capsule) >= 0.0f;
          return hit;
        },
        [&] { return q.tmax; });
    io_hit[i] = hit ? 1 : 0;
  }
}

void ray_closest_user(const RayTree& t, RayUserTest test, const void* ctx, uint32_t kind,
                      const RayQuery* rays, RayBest* io_best, Range r) {
  for (uint32_t i = r.begin; i < r.end; ++i) {
    RayQuery q = rays[i];
    RayBest best = io_best[i];
    q.tmax = best.t;
    traverse(
        t, q,
        [&](uint32_t s) {
          const uint32_t idx = t.leaves[s].index;
          const float th = test(ctx, idx, q);
          if (th >= 0.0f && ray_best_better(th, kind, idx, best)) {
            best = {th, kind, idx};
            q.tmax = th;
          }
          return false;
        },
        [&] { return q.tmax; });
    io_best[i] = best;
  }
}

void ray_any_user(const RayTree& t, RayUserTest test, const void* ctx, const RayQuery* rays,
                  uint8_t* io_hit, Range r) {
  for (uint32_t i = r.begin; i < r.end; ++i) {
    if (io_hit[i]) continue;
    const RayQuery q = rays[i];
    bool hit = false;
    traverse(
        t, q,
        [&](uint32_t s) {
          hit = test(ctx, t.leaves[s].index, q) >= 0.0f;
          return hit;
        },
        [&] { return q.tmax; });
    io_hit[i] = hit ? 1 : 0;
  }
}

bool ray_meets_box(const RayQuery& q, const float lo[3], const float hi[3]) {
  struct Box {
    float min_x, min_y, min_z, max_x, max_y, max_z;
  };
  const Box b{lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]};
  float tn;
  return slab(b, slab_ray(q), q.tmax, &tn);
}

void ray_closest_planes(const PlaneRecord* planes, uint32_t count, const RayQuery* rays,
                        RayBest* io_best, Range r) {
  for (uint32_t i = r.begin; i < r.end; ++i) {
    RayQuery q = rays[i];
    RayBest best = io_best[i];
    q.tmax = best.t;
    for (uint32_t p = 0; p < count; ++p) {
      if ((planes[p].layer & q.mask) == 0) continue;
      const float th = ray_plane(q, planes[p].n, planes[p].offset);
      if (th >= 0.0f && ray_best_better(th, kRayHitPlane, p, best)) {
        best = {th, kRayHitPlane, p};
        q.tmax = th;
      }
    }
    io_best[i] = best;
  }
}

void ray_any_planes(const PlaneRecord* planes, uint32_t count, const RayQuery* rays, uint8_t* io_hit,
                    Range r) {
  for (uint32_t i = r.begin; i < r.end; ++i) {
    if (io_hit[i]) continue;
    for (uint32_t p = 0; p < count; ++p) {
      if ((planes[p].layer & rays[i].mask) == 0) continue;
      if (ray_plane(rays[i], planes[p].n, planes[p].offset) >= 0.0f) {
        io_hit[i] = 1;
        break;
      }
    }
  }
}

}  // namespace impact::kernels
