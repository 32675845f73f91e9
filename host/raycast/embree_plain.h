// Reference loops over a RayScene's Embree scene for the benchmarks: what a user who
// calls Embree directly would write (one rtcIntersect1 / rtcOccluded1 per ray, on the
// calling thread), so bench/raycast_bench.cpp can measure the overhead of the batched
// API against it. Embree stays inside host/raycast/.
#pragma once

#include <cstdint>
#include <span>

#include "impact/raycast.h"

namespace impact::host {

class TraceBackend;

/// The top-level RTCScene of an Embree backend (as void*), or null for other backends.
void* embree_top_scene(const TraceBackend* backend);

/// What a plain loop that keeps its results stores per ray: Embree's hit as returned.
struct PlainHit {
  float t;
  uint32_t geom, prim, inst;
  float ng[3];
};

/// The loops on a raw RTCScene (passed as void*).
uint64_t embree_plain_closest_raw(void* rtc_scene, std::span<const Ray> rays);
/// The same loop, storing each ray's hit in out[i] (out.size() == rays.size()).
uint64_t embree_plain_closest_store_raw(void* rtc_scene, std::span<const Ray> rays, std::span<PlainHit> out);
uint64_t embree_plain_any_raw(void* rtc_scene, std::span<const Segment> segments);

/// rtcIntersect1 over rays (unit directions expected) on scene's Embree top-level scene;
/// returns the number of rays that hit something (planes are not in Embree). Returns
/// UINT64_MAX when the scene does not use Embree or is not committed.
uint64_t embree_plain_closest(const RayScene& scene, std::span<const Ray> rays);
/// The same, storing Embree's hit per ray (a loop that keeps its results).
uint64_t embree_plain_closest_store(const RayScene& scene, std::span<const Ray> rays, std::span<PlainHit> out);
/// rtcOccluded1 over segments; returns the number occluded.
uint64_t embree_plain_any(const RayScene& scene, std::span<const Segment> segments);

}  // namespace impact::host
