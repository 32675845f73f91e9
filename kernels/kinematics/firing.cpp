#include "kernels/kinematics/firing.h"

#include <cmath>

namespace impact::kernels {
namespace {

FiringShot make_shot(const double d[3], const double g[3], double speed, double t) {
  // u = d / t - g t / 2, then normalised (|u| = speed up to rounding).
  double u[3];
  for (int k = 0; k < 3; ++k) u[k] = d[k] / t - 0.5 * g[k] * t;
  const double len = std::sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
  FiringShot s;
  for (int k = 0; k < 3; ++k) s.dir[k] = static_cast<float>(len > 0.0 ? u[k] / len : 0.0);
  s.time = static_cast<float>(t);
  (void)speed;
  return s;
}

}  // namespace

FiringResult firing_solution(const FiringProblem& p) {
  FiringResult r{};
  double d[3], g[3];
  for (int k = 0; k < 3; ++k) {
    d[k] = static_cast<double>(p.target[k]) - static_cast<double>(p.origin[k]);
    g[k] = static_cast<double>(p.gravity[k]);
  }
  const double s = p.speed;
  const double dd = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
  const double gg = g[0] * g[0] + g[1] * g[1] + g[2] * g[2];
  const double dg = d[0] * g[0] + d[1] * g[1] + d[2] * g[2];
  if (dd == 0.0) {
    // Target at the origin: hit at t = 0; the direction is a convention (up).
    r.count = 1;
    const double gl = std::sqrt(gg);
    r.shots[0].dir[0] = gl > 0.0 ? static_cast<float>(-g[0] / gl) : 0.0f;
    r.shots[0].dir[1] = gl > 0.0 ? static_cast<float>(-g[1] / gl) : 1.0f;
    r.shots[0].dir[2] = gl > 0.0 ? static_cast<float>(-g[2] / gl) : 0.0f;
    r.shots[0].time = 0.0f;
    return r;
  }
  if (gg == 0.0) {
    r.count = 1;
    r.shots[0] = make_shot(d, g, s, std::sqrt(dd) / s);
    return r;
  }
  const double a = 0.25 * gg;
  const double bneg = dg + s * s;  // -b
  const double gd = std::sqrt(gg) * std::sqrt(dd);
  double disc = (bneg - gd) * (bneg + gd);
  if (disc < -kFiringEdgeTolerance * bneg * bneg || bneg <= 0.0) return r;  // out of range
  if (disc <= kFiringEdgeTolerance * bneg * bneg) {
    // Maximum range: the double root T = -b / 2a.
    r.count = 1;
    r.shots[0] = make_shot(d, g, s, std::sqrt(bneg / (2.0 * a)));
    return r;
  }
  const double q = 0.5 * (bneg + std::sqrt(disc));  // > 0
  const double t_hi2 = q / a;     // larger root of T
  const double t_lo2 = dd / q;    // smaller root (product of the roots is dd / a)
  r.count = 2;
  r.shots[0] = make_shot(d, g, s, std::sqrt(t_lo2));
  r.shots[1] = make_shot(d, g, s, std::sqrt(t_hi2));
  return r;
}

void firing_solutions(const FiringProblem* problems, FiringResult* out, Range r) {
  for (uint32_t i = r.begin; i < r.end; ++i) out[i] = firing_solution(problems[i]);
}

void firing_arc_point(const FiringProblem& p, const FiringShot& shot, double t, double out[3]) {
  for (int k = 0; k < 3; ++k)
    out[k] = static_cast<double>(p.origin[k]) + static_cast<double>(p.speed) * shot.dir[k] * t +
             0.5 * static_cast<double>(p.gravity[k]) * t * t;
}

}  // namespace impact::kernels
