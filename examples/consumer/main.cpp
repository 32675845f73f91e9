// Smallest useful impact program: a few spheres dropped onto a floor. Checks that
// after 2 s every sphere rests on the floor (centre within 2 cm of its radius above
// it, nearly still) and prints OK; exits 1 otherwise.
#include <impact/impact.h>

#include <cmath>
#include <cstdio>
#include <memory>
#include <vector>

namespace {

int fail(const char* what, const impact::Status& s) {
  std::fprintf(stderr, "%s: %s: %s\n", what, impact::to_string(s.code()), s.message().c_str());
  return 1;
}

}  // namespace

int main() {
  impact::WorldDesc desc;  // gravity -9.81 m/s^2 along y, 60 Hz, all hardware threads
  std::unique_ptr<impact::World> world;
  if (impact::Status s = impact::World::create(desc, &world); !s.ok()) return fail("World::create", s);

  // Floor: the half-space y <= 0.
  const impact::PlaneDesc floor;  // normal +y, offset 0
  impact::PlaneHandle floor_handle;
  if (impact::Status s = world->create_planes({&floor, 1}, {&floor_handle, 1}); !s.ok())
    return fail("create_planes", s);

  // Five spheres of different sizes, side by side, dropped from 1..3 m.
  std::vector<impact::BodyDesc> descs;
  for (int i = 0; i < 5; ++i) {
    impact::BodyDesc d;
    d.radius = 0.2f + 0.1f * static_cast<float>(i);
    d.position = Eigen::Vector3f(2.0f * static_cast<float>(i), 1.0f + 0.5f * static_cast<float>(i), 0.0f);
    d.restitution = 0.3f;
    descs.push_back(d);
  }
  std::vector<impact::BodyHandle> bodies(descs.size());
  if (impact::Status s = world->create_bodies(descs, bodies); !s.ok()) return fail("create_bodies", s);

  for (int step = 0; step < 120; ++step)
    if (impact::Status s = world->step(); !s.ok()) return fail("World::step", s);

  std::vector<Eigen::Vector3f> pos(bodies.size()), vel(bodies.size());
  if (impact::Status s = world->get_positions(bodies, pos); !s.ok()) return fail("get_positions", s);
  if (impact::Status s = world->get_velocities(bodies, vel); !s.ok()) return fail("get_velocities", s);

  bool ok = true;
  for (size_t i = 0; i < bodies.size(); ++i) {
    const float height = pos[i].y() - descs[i].radius;  // gap between sphere bottom and floor, m
    const bool resting = std::isfinite(height) && height > -0.02f && height < 0.02f && vel[i].norm() < 0.1f;
    std::printf("sphere %zu: r %.2f m, bottom at %+.4f m, speed %.4f m/s%s\n", i,
                static_cast<double>(descs[i].radius), static_cast<double>(height),
                static_cast<double>(vel[i].norm()), resting ? "" : "  <-- not resting");
    ok = ok && resting;
  }
  std::printf("%s\n", ok ? "OK" : "FAILED");
  return ok ? 0 : 1;
}
