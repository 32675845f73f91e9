#include "kernels/solver/islands.h"

#include <cmath>

namespace impact::kernels {
namespace {

// Root of i with path halving.
uint32_t root_of(uint32_t* parent, uint32_t i) {
  while (parent[i] != i) {
    parent[i] = parent[parent[i]];
    i = parent[i];
  }
  return i;
}

bool moving(const IslandArrays& b, uint32_t i) {
  const bool linear = b.vx[i] != 0.0f || b.vy[i] != 0.0f || b.vz[i] != 0.0f;
  return linear || (b.wx != nullptr && (b.wx[i] != 0.0f || b.wy[i] != 0.0f || b.wz[i] != 0.0f));
}

}  // namespace

void update_sleep_timers(float dt, float speed, const float* inv_mass, const float* radius, const float* vx,
                         const float* vy, const float* vz, const float* wx, const float* wy, const float* wz,
                         const uint8_t* asleep, float* IMPACT_RESTRICT sleep_time, Range r) {
  for (uint32_t i = r.begin; i < r.end; ++i) {
    if (!(inv_mass[i] > 0.0f) || asleep[i]) continue;
    float s = std::sqrt(vx[i] * vx[i] + vy[i] * vy[i] + vz[i] * vz[i]);
    if (wx != nullptr) s += radius[i] * std::sqrt(wx[i] * wx[i] + wy[i] * wy[i] + wz[i] * wz[i]);
    sleep_time[i] = s < speed ? sleep_time[i] + dt : 0.0f;
  }
}

void find_islands(const ContactManifoldArrays& c, uint32_t manifolds, uint32_t body_count, const IslandArrays& b) {
  uint32_t* parent = b.parent;
  for (uint32_t i = 0; i < body_count; ++i) {
    parent[i] = i;
    b.kept_awake[i] = 0;
  }
  for (uint32_t m = 0; m < manifolds; ++m) {
    if (c.b_is_plane[m]) continue;
    const uint32_t x = c.a[m], y = c.b[m];
    const bool dx = b.inv_mass[x] > 0.0f, dy = b.inv_mass[y] > 0.0f;
    if (dx && dy) {
      const uint32_t rx = root_of(parent, x), ry = root_of(parent, y);
      if (rx < ry) parent[ry] = rx;
      if (ry < rx) parent[rx] = ry;
    } else if (dx && moving(b, y)) {
      b.kept_awake[x] = 1;
    } else if (dy && moving(b, x)) {
      b.kept_awake[y] = 1;
    }
  }
  // Roots are the smallest slots, so one ascending pass flattens every path and
  // gathers the flags at the roots.
  for (uint32_t i = 0; i < body_count; ++i) {
    parent[i] = parent[parent[i]];
    if (b.kept_awake[i]) b.kept_awake[parent[i]] = 1;
  }
}

uint32_t decide_sleep(float sleep_time_needed, uint32_t body_count, const IslandArrays& b, float* vx, float* vy,
                      float* vz, float* wx, float* wy, float* wz, float* IMPACT_RESTRICT sleep_time,
                      float* IMPACT_RESTRICT island_min, uint8_t* IMPACT_RESTRICT asleep) {
  const uint32_t* parent = b.parent;
  for (uint32_t i = 0; i < body_count; ++i) island_min[i] = INFINITY;
  for (uint32_t i = 0; i < body_count; ++i)
    if (b.inv_mass[i] > 0.0f) island_min[parent[i]] = std::fmin(island_min[parent[i]], sleep_time[i]);
  uint32_t sleeping = 0;
  for (uint32_t i = 0; i < body_count; ++i) {
    if (!(b.inv_mass[i] > 0.0f)) {
      asleep[i] = 0;
      continue;
    }
    const uint32_t r = parent[i];
    const bool sleeps = island_min[r] >= sleep_time_needed && !b.kept_awake[r];
    if (sleeps) {
      vx[i] = vy[i] = vz[i] = 0.0f;
      if (wx != nullptr) wx[i] = wy[i] = wz[i] = 0.0f;
      ++sleeping;
    } else if (asleep[i]) {
      sleep_time[i] = 0.0f;  // woken: a full sleep_time before it sleeps again
    }
    asleep[i] = sleeps ? 1 : 0;
  }
  return sleeping;
}

}  // namespace impact::kernels
