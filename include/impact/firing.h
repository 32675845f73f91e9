// The firing solution: launch directions of a projectile with fixed speed under
// constant gravity (no drag) that hit a target, and a line-of-sight check of the
// resulting arc against a RayScene. Method and precision: kernels/kinematics/firing.h
// and docs/raycast.md.
#pragma once

#include <cstdint>
#include <span>

#include <Eigen/Core>

#include "impact/raycast.h"
#include "impact/status.h"

namespace impact {

/// One aiming problem. Units: m, m/s, m/s^2.
struct FiringQuery {
  /// Launch point, m (finite).
  Eigen::Vector3f origin = Eigen::Vector3f::Zero();
  /// Point to hit, m (finite).
  Eigen::Vector3f target = Eigen::Vector3f::Zero();
  /// Constant acceleration, m/s^2 (finite; zero allowed: a straight shot).
  Eigen::Vector3f gravity{0.0f, -9.81f, 0.0f};
  float speed = 10.0f;  ///< launch speed, finite and > 0
};

/// One launch that reaches the target.
struct FiringShot {
  Eigen::Vector3f direction = Eigen::Vector3f::Zero();  ///< unit
  float time = 0.0f;                                    ///< s of flight to the target
  /// Launch velocity, m/s (speed * direction).
  Eigen::Vector3f velocity(float speed) const { return speed * direction; }
};

/// 0 (out of range), 1 (exactly at maximum range, g = 0, or target at the origin) or
/// 2 solutions; shots[0] is the low (shorter-time) arc, shots[1] the high arc.
/// The analytic trajectory of each shot passes within 1e-5 * max(1 m, |target - origin|,
/// speed * time) of the target (tests/kernels/kinematics/firing_test.cpp).
struct FiringSolution {
  /// Valid entries of shots: 0, 1 or 2.
  uint32_t count = 0;
  /// The shots, low arc first.
  FiringShot shots[2];
};

/// Solves each query. Rejects non-finite vectors and speed <= 0 naming the query and
/// field. A target at the origin gives one shot with time 0 pointing against gravity
/// (+y when gravity is zero).
Status firing_solutions(std::span<const FiringQuery> queries, std::span<FiringSolution> out);

/// Position of the projectile of `shot` at time t (s): origin + speed dir t + g t^2 / 2.
Eigen::Vector3f trajectory_point(const FiringQuery& query, const FiringShot& shot, float t);

/// How an arc is checked against a scene.
struct ArcCheckDesc {
  /// Chords per arc, in [1, 4096]. A chord deviates from the parabola by at most
  /// |g| (time / segments)^2 / 8 m: the check's geometric tolerance.
  uint32_t segments = 16;
  uint32_t mask = 0xffffffffu;  ///< layers the projectile sees
  /// Fractions of the flight time skipped at the start and the end (e.g. to leave out
  /// the shooter and the target, if they are in the scene and in the mask): each >= 0,
  /// their sum < 1.
  float skip_start = 0.0f;
  /// Fraction of the flight time skipped at the end (see skip_start).
  float skip_end = 0.0f;
};

/// out_clear[i] = 1 when nothing in `scene` blocks the chords of shots[i] (the arc of
/// queries[i]), else 0. Uses RayScene::any_hit (both backends).
Status arc_clear(const RayScene& scene, std::span<const FiringQuery> queries, std::span<const FiringShot> shots,
                 const ArcCheckDesc& desc, std::span<uint8_t> out_clear);

}  // namespace impact
