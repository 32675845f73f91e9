// Ray queries over an LBVH (kernels/bvh/lbvh_build.h + lbvh_refit.h): closest hit
// and any hit, one ray per index, for triangle trees, for sphere/capsule trees and for
// trees of user primitives tested by a callback (RayScene's posed shapes);
// plus the brute-force pass over the (few, unbounded) half-spaces.
//
// What: per ray i in r, rays[i] (unit direction, tmax, mask) is traced through the
//   tree and the result reduced into io_best[i] (closest: keep the smaller t, ties to
//   the smaller (kind, prim), see ray_best_better) or io_hit[i] (any: set to 1 on the
//   first hit; rays already marked are skipped). Primitive tests are the scalar ones of
//   kernels/raycast/ray_primitives.h, so every path shares one definition of a hit.
// Traversal: front to back with a short stack. At an internal node both children's
//   boxes are tested (slab test; leaves are tested at once, inner children hit are
//   visited nearer first and the farther one pushed with its entry distance); a popped
//   node whose entry distance exceeds the best t so far is skipped. The stack holds at
//   most one entry per tree level, so kLbvhMaxDepth + 1 entries never overflow.
// Slab test: per axis the near and far planes are chosen by the sign of the direction
//   (zero components are made +0); an axis with d = 0 whose origin lies exactly on a
//   plane gives 0 * inf = NaN, which the max/min below ignore, so the closed slab is
//   kept (a ray in a box face is inside it). The far distance is scaled by
//   1 + 2 gamma_3 (Ize, "Robust BVH Ray Traversal", JCGT 2013) so rounding never culls
//   a box the ray touches.
// Records: primitives are copied into sorted-leaf order (triangle_records /
//   shape_records) so a leaf test reads one record next to its neighbours'; the tree's
//   SortedBox::index gives the original primitive index reported in hits.
// Shape trees hold spheres (original index < first_capsule) and capsules (the rest,
//   reported as index - first_capsule). A sphere record has a == b.
// Preconditions: the tree is built and refitted over exactly these primitives' boxes;
//   rays validated (finite, unit direction, 0 <= tmax <= FLT_MAX).
// Cost: O(log n) node tests per ray for well-separated primitives; O(n) worst case.
// Method: binary BVH traversal with ordered children and a stack (e.g. Wald et al.,
//   "Ray Tracing Deformable Scenes using Dynamic BVHs", TOG 2007), over the LBVH of
//   Karras 2012.
#pragma once

#include "kernels/broadphase/bounds.h"
#include "kernels/bvh/lbvh_build.h"
#include "kernels/common/kernel.h"
#include "kernels/common/sorted_box.h"
#include "kernels/raycast/ray_primitives.h"

namespace impact::kernels {

/// A triangle in sorted-leaf order: 40 bytes.
struct TriangleRecord {
  float v0[3], v1[3], v2[3];
  uint32_t layer;
};
static_assert(sizeof(TriangleRecord) == 40);

/// A sphere (a == b) or capsule (segment a-b) in sorted-leaf order: 32 bytes.
struct ShapeRecord {
  float a[3];
  float radius;
  float b[3];
  uint32_t layer;
};
static_assert(sizeof(ShapeRecord) == 32);

/// A half-space {x : dot(n, x) <= offset}, n unit.
struct PlaneRecord {
  float n[3];
  float offset;
  uint32_t layer;
};

/// The parts of a built LBVH that ray traversal reads. n == 0: empty; n == 1: one leaf.
struct RayTree {
  const LbvhNode* nodes;     ///< n - 1 internal nodes, root 0
  const SortedBox* leaves;   ///< n, sorted order, .index = original primitive
  uint32_t n;
};

/// Triangle soup in original order (for triangle_records).
struct TriangleSoup {
  const float* vertices;     ///< xyz per vertex
  const uint32_t* indices;   ///< 3 per triangle
  const uint32_t* layer;     ///< per triangle
};

/// Primitive boxes of triangles [r) (exact min/max of the three vertices).
void triangle_bounds(const TriangleSoup& soup, AabbSoAOut out, Range r);
/// Primitive boxes of capsules [r) (segment box grown by the radius).
void capsule_bounds(const float* ax, const float* ay, const float* az, const float* bx, const float* by,
                    const float* bz, const float* radius, AabbSoAOut out, Range r);

/// out[s] = triangle leaves[s].index of the soup, for sorted leaves s in r.
void triangle_records(const TriangleSoup& soup, const SortedBox* leaves, TriangleRecord* out, Range r);

/// Spheres and capsules by original index (i < first_capsule: sphere i, else capsule
/// i - first_capsule), gathered in sorted-leaf order.
struct ShapeSoA {
  const float *sx, *sy, *sz, *sr;   ///< sphere centres and radii
  const uint32_t* s_layer;
  const float *ax, *ay, *az, *bx, *by, *bz, *cr;  ///< capsule segments and radii
  const uint32_t* c_layer;
  uint32_t first_capsule;           ///< sphere count
};
void shape_records(const ShapeSoA& shapes, const SortedBox* leaves, ShapeRecord* out, Range r);

void ray_closest_triangles(const RayTree& t, const TriangleRecord* rec, const RayQuery* rays,
                           RayBest* io_best, Range r);
void ray_any_triangles(const RayTree& t, const TriangleRecord* rec, const RayQuery* rays,
                       uint8_t* io_hit, Range r);
void ray_closest_shapes(const RayTree& t, const ShapeRecord* rec, uint32_t first_capsule,
                        const RayQuery* rays, RayBest* io_best, Range r);
void ray_any_shapes(const RayTree& t, const ShapeRecord* rec, uint32_t first_capsule,
                    const RayQuery* rays, uint8_t* io_hit, Range r);
/// User primitives (RayScene's posed shapes): test(ctx, index, q) is the hit distance
/// in [0, q.tmax] of original primitive `index` (its layer checked against q.mask), or
/// < 0 for a miss. Hits are reduced as (t, kind, index).
using RayUserTest = float (*)(const void* ctx, uint32_t index, const RayQuery& q);
void ray_closest_user(const RayTree& t, RayUserTest test, const void* ctx, uint32_t kind,
                      const RayQuery* rays, RayBest* io_best, Range r);
void ray_any_user(const RayTree& t, RayUserTest test, const void* ctx, const RayQuery* rays,
                  uint8_t* io_hit, Range r);
/// The conservative slab test the traversal uses on its boxes (far distance widened by
/// 1 + 2 gamma_3): false only when the ray misses the closed box [lo, hi] within
/// [0, q.tmax]. For engines that hand several primitives to one callback (Embree leaves).
bool ray_meets_box(const RayQuery& q, const float lo[3], const float hi[3]);
void ray_closest_planes(const PlaneRecord* planes, uint32_t count, const RayQuery* rays,
                        RayBest* io_best, Range r);
void ray_any_planes(const PlaneRecord* planes, uint32_t count, const RayQuery* rays, uint8_t* io_hit,
                    Range r);

}  // namespace impact::kernels
