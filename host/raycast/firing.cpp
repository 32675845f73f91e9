// Public firing-solution API (include/impact/firing.h): validation, the kernel
// (kernels/kinematics/firing.h), and arc visibility as chords through RayScene::any_hit.
#include "impact/firing.h"

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "kernels/kinematics/firing.h"

namespace impact {
namespace {

bool finite3(const Eigen::Vector3f& v) { return v.allFinite(); }

std::string fmt(float v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", static_cast<double>(v));
  return buf;
}

std::string check(const FiringQuery& q, size_t i) {
  const std::string p = "firing query " + std::to_string(i) + ": ";
  if (!finite3(q.origin)) return p + "origin must be finite";
  if (!finite3(q.target)) return p + "target must be finite";
  if (!finite3(q.gravity)) return p + "gravity must be finite";
  if (!(q.speed > 0.0f) || !std::isfinite(q.speed)) return p + "speed must be finite and > 0, got " + fmt(q.speed);
  return {};
}

kernels::FiringProblem problem_of(const FiringQuery& q) {
  kernels::FiringProblem p;
  for (int k = 0; k < 3; ++k) {
    p.origin[k] = q.origin[k];
    p.target[k] = q.target[k];
    p.gravity[k] = q.gravity[k];
  }
  p.speed = q.speed;
  return p;
}

}  // namespace

Status firing_solutions(std::span<const FiringQuery> queries, std::span<FiringSolution> out) {
  if (out.size() != queries.size())
    return Status(StatusCode::kSizeMismatch, "firing_solutions: out has " + std::to_string(out.size()) +
                                                 " entries for " + std::to_string(queries.size()) + " queries");
  for (size_t i = 0; i < queries.size(); ++i)
    if (std::string e = check(queries[i], i); !e.empty()) return Status(StatusCode::kInvalidArgument, e);
  for (size_t i = 0; i < queries.size(); ++i) {
    const kernels::FiringResult r = kernels::firing_solution(problem_of(queries[i]));
    FiringSolution s;
    s.count = r.count;
    for (uint32_t k = 0; k < r.count; ++k) {
      s.shots[k].direction = Eigen::Vector3f(r.shots[k].dir[0], r.shots[k].dir[1], r.shots[k].dir[2]);
      s.shots[k].time = r.shots[k].time;
    }
    out[i] = s;
  }
  return Status();
}

Eigen::Vector3f trajectory_point(const FiringQuery& q, const FiringShot& shot, float t) {
  const kernels::FiringProblem p = problem_of(q);
  const kernels::FiringShot s{{shot.direction.x(), shot.direction.y(), shot.direction.z()}, shot.time};
  double x[3];
  kernels::firing_arc_point(p, s, t, x);
  return Eigen::Vector3f(static_cast<float>(x[0]), static_cast<float>(x[1]), static_cast<float>(x[2]));
}

Status arc_clear(const RayScene& scene, std::span<const FiringQuery> queries, std::span<const FiringShot> shots,
                 const ArcCheckDesc& desc, std::span<uint8_t> out_clear) {
  if (shots.size() != queries.size() || out_clear.size() != queries.size())
    return Status(StatusCode::kSizeMismatch, "arc_clear: queries, shots and out_clear must have equal sizes, got " +
                                                 std::to_string(queries.size()) + ", " + std::to_string(shots.size()) +
                                                 ", " + std::to_string(out_clear.size()));
  if (desc.segments == 0 || desc.segments > 4096)
    return Status(StatusCode::kInvalidArgument, "arc_clear: segments must be in [1, 4096], got " + std::to_string(desc.segments));
  if (!(desc.skip_start >= 0.0f && desc.skip_end >= 0.0f && desc.skip_start + desc.skip_end < 1.0f))
    return Status(StatusCode::kInvalidArgument, "arc_clear: skip_start, skip_end must be >= 0 with a sum < 1, got " +
                                                    fmt(desc.skip_start) + ", " + fmt(desc.skip_end));
  for (size_t i = 0; i < queries.size(); ++i) {
    if (std::string e = check(queries[i], i); !e.empty()) return Status(StatusCode::kInvalidArgument, "arc_clear: " + e);
    if (!shots[i].direction.allFinite() || !std::isfinite(shots[i].time) || shots[i].time < 0.0f)
      return Status(StatusCode::kInvalidArgument, "arc_clear: shot " + std::to_string(i) + ": direction and time must be finite, time >= 0");
  }
  const uint32_t n = desc.segments;
  std::vector<Segment> segs(queries.size() * n);
  for (size_t i = 0; i < queries.size(); ++i) {
    const float t0 = desc.skip_start * shots[i].time;
    const float span = (1.0f - desc.skip_start - desc.skip_end) * shots[i].time;
    Eigen::Vector3f prev = trajectory_point(queries[i], shots[i], t0);
    for (uint32_t k = 0; k < n; ++k) {
      const float t = t0 + span * static_cast<float>(k + 1) / static_cast<float>(n);
      const Eigen::Vector3f next = trajectory_point(queries[i], shots[i], t);
      segs[i * n + k] = Segment{prev, next, desc.mask};
      prev = next;
    }
  }
  std::vector<uint8_t> hit(segs.size());
  if (Status s = scene.any_hit(segs, hit); !s.ok()) return s;
  for (size_t i = 0; i < queries.size(); ++i) {
    uint8_t clear = 1;
    for (uint32_t k = 0; k < n; ++k)
      if (hit[i * n + k]) clear = 0;
    out_clear[i] = clear;
  }
  return Status();
}

}  // namespace impact
