// Islands and sleeping. An island is a connected component of the graph whose nodes
// are the dynamic bodies (inv_mass > 0) and whose edges are the step's body-body
// contact manifolds; static, kinematic and plane bodies join nothing, so a floor does
// not merge every pile on it into one island. An island sleeps while every body of
// it has been slow (sleep_speed) for sleep_time, and no moving kinematic body
// touches it (Box2D v3 and Bullet keep the same per-body timer; Catto, "Box2D v3
// islands", box2d.org 2023, and Bullet's btSimulationIslandManager).
//
// The islands are found each step by union-find over the manifolds (Tarjan, "Efficiency
// of a Good But Not Linear Set Union Algorithm", JACM 1975), linking the larger root
// under the smaller: every island's root is then its smallest body slot whatever the
// manifold order, so the answer does not depend on how the manifolds were produced.
// Cost: O(manifolds α + bodies), serial, 4 bytes of parent per body.
#pragma once

#include "kernels/common/contact_manifolds.h"
#include "kernels/common/kernel.h"

namespace impact::kernels {

/// Sleep timers of bodies r: a dynamic awake body whose speed |v| + radius |w| is below
/// speed has timer += dt, otherwise 0; asleep and non-dynamic bodies keep theirs.
/// w* may be null (no body rotates).
void update_sleep_timers(float dt, float speed, const float* inv_mass, const float* radius, const float* vx,
                         const float* vy, const float* vz, const float* wx, const float* wy, const float* wz,
                         const uint8_t* asleep, float* IMPACT_RESTRICT sleep_time, Range r);

/// The per-body inputs and outputs of find_islands / decide_sleep.
struct IslandArrays {
  const float* inv_mass;
  const float* vx;  ///< velocities: a kinematic body (inv_mass 0) with any non-zero one keeps its contacts awake
  const float* vy;
  const float* vz;
  const float* wx;  ///< null: no body rotates
  const float* wy;
  const float* wz;
  uint32_t* parent;      ///< per body: island root after find_islands
  uint8_t* kept_awake;   ///< per body: 1 when touched by a moving kinematic body (roots: the island's)
};

/// Links the dynamic bodies of every body-body manifold m < manifolds and marks bodies
/// touched by a moving kinematic body; on return parent[i] is the root (smallest slot)
/// of i's island for every i < body_count, and kept_awake[root] the island's flag.
void find_islands(const ContactManifoldArrays& c, uint32_t manifolds, uint32_t body_count, const IslandArrays& b);

/// Per island, asleep iff every body's sleep_time >= sleep_time_needed and nothing keeps
/// it awake; sets asleep[i] for every dynamic body, zeroes the velocities of the bodies
/// that sleep, and gives a body that wakes a zero timer. island_min: body_count floats
/// of scratch. Returns the bodies asleep.
uint32_t decide_sleep(float sleep_time_needed, uint32_t body_count, const IslandArrays& b, float* vx, float* vy,
                      float* vz, float* wx, float* wy, float* wz, float* IMPACT_RESTRICT sleep_time,
                      float* IMPACT_RESTRICT island_min, uint8_t* IMPACT_RESTRICT asleep);

}  // namespace impact::kernels
