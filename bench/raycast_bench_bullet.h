// Bullet peer of impact_raybench (bench/raycast_bench.cpp): the same spheres in a
// btCollisionWorld (btDbvtBroadphase), closest-hit rayTest per ray, and the per-frame
// re-insertion (move every object, updateAabbs). Compiled only with libbullet-dev;
// without it bullet_available() is false and the rest are stubs.
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "impact/raycast.h"

namespace impact::bench {

struct BulletWorld;
struct BulletWorldDeleter {
  void operator()(BulletWorld* w) const;
};

bool bullet_available();
std::unique_ptr<BulletWorld, BulletWorldDeleter> make_bullet_spheres(std::span<const float> x, std::span<const float> y,
                                                                     std::span<const float> z, std::span<const float> r);
/// Closest-hit rayTest per ray over `length` m; returns the number of hits.
uint64_t bullet_ray_test(BulletWorld& w, std::span<const Ray> rays, float length);
/// Moves every object by dx along x (alternating sign per call) and updates the broad phase.
void bullet_move_all(BulletWorld& w, float dx);
/// Re-insertion: removes every object from the world and adds it back at its moved place.
void bullet_reinsert_all(BulletWorld& w, float dx);

}  // namespace impact::bench
