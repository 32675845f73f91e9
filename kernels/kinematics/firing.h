// The firing solution: launch velocities of fixed speed s under constant gravity g
// that carry a projectile from o to a target p (no drag).
//
// What: the projectile's position is x(t) = o + u t + g t^2 / 2 with |u| = s. It
//   reaches p at time t iff u = d / t - g t / 2 (d = p - o); |u| = s then reads, with
//   T = t^2,
//       (|g|^2 / 4) T^2 - (d.g + s^2) T + |d|^2 = 0.
//   Discriminant D = (d.g + s^2)^2 - |g|^2 |d|^2, evaluated in the factored form
//   (d.g + s^2 - |g||d|)(d.g + s^2 + |g||d|) so that it keeps its sign near the edge
//   of range; roots by the cancellation-free pair T1 = q / a, T2 = c / q with
//   q = ((d.g + s^2) + sqrt(D)) / 2. D < 0: out of range, no solution. D == 0 (to
//   the relative band kFiringEdgeTolerance): the maximum-range shot, one solution. Otherwise two: the low arc (smaller t) first, then the high arc.
//   Both roots are positive whenever D >= 0 (their product |d|^2 / a and sum are).
// Special cases: g = 0 gives the straight shot t = |d| / s (one solution); d = 0 (the
//   target at the origin) gives one solution with t = 0 and direction -g/|g| (or +y
//   when g = 0), documented rather than meaningful. A target straight above or below
//   gives shots straight up/down (two when the target is within reach).
// Precision: all arithmetic in double from float inputs; the returned direction is
//   unit to float rounding, and the analytic trajectory passes the target within
//   1e-5 * max(1 m, |d|, s t), the bound tests/kernels/kinematics/firing_test.cpp checks.
// Method: the quadratic in t^2 of the kinematic equation d = u t + g t^2 / 2, as in
//   Millington, "Game Physics Engine Development" (firing solution), rewritten in the
//   stable forms above.
#pragma once

#include <cstdint>

#include "kernels/common/kernel.h"

namespace impact::kernels {

/// One launch: unit direction and time of flight to the target, s.
struct FiringShot {
  float dir[3];
  float time;
};

/// Input of one firing problem (m, m/s, m/s^2).
struct FiringProblem {
  float origin[3];
  float target[3];
  float gravity[3];
  float speed;  ///< > 0
};

/// Result: count in {0, 1, 2}; shots[0] is the low (fast) arc.
struct FiringResult {
  uint32_t count;
  FiringShot shots[2];
};

/// Relative width of the "exactly at maximum range" band: |D| <= tol * (d.g + s^2)^2
/// gives the single maximum-range solution. D / (d.g + s^2)^2 is about twice the
/// relative shortfall of the range, so targets within ~5e-7 of the maximum range (in
/// or out: float inputs carry 6e-8 of rounding) get the maximum-range shot, which then
/// misses by at most ~1e-6 relative, inside the stated tolerance.
inline constexpr double kFiringEdgeTolerance = 1e-6;

/// Solves one problem.
FiringResult firing_solution(const FiringProblem& p);

/// Solves problems[r] into out[r].
void firing_solutions(const FiringProblem* problems, FiringResult* out, Range r);

/// Point of the trajectory o + s dir t + g t^2 / 2 at time t (double precision).
void firing_arc_point(const FiringProblem& p, const FiringShot& shot, double t, double out[3]);

}  // namespace impact::kernels
