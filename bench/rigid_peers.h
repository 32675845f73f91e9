// The engines of impact_rigidbench (bench/rigid_peers.cpp): one box scene stepped by
// impact and by the peer physics engines, each behind the same small interface.
//
// The scene crosses this header as plain float arrays (no Eigen, no impact type), so
// each peer's file can be compiled for the ISA its Debian library was built for
// (bench/CMakeLists.txt) and sees nothing of impact's. Bodies are boxes; planes are
// static half-spaces {x : dot(normal, x) <= offset} (free space on the normal's side).
// Units: m, s, kg.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace impact::bench::rigid {

/// A dynamic box.
struct BoxBody {
  float position[3];     ///< centre of mass, m
  float orientation[4];  ///< unit quaternion (x, y, z, w)
  float half_extents[3]; ///< m
  float mass;            ///< kg, > 0
  float friction;        ///< Coulomb coefficient; a pair uses sqrt(f_a f_b) (impact's rule)
  float restitution;     ///< in [0, 1]; a pair uses the larger
};

/// A static plane.
struct Plane {
  float normal[3];  ///< unit
  float offset;     ///< m
  float friction;
  float restitution;
};

/// What every engine builds.
struct PeerScene {
  std::vector<BoxBody> boxes;
  std::vector<Plane> planes;
  float gravity[3] = {0.0f, -9.81f, 0.0f};  ///< m/s^2
  float dt = 1.0f / 60.0f;                  ///< s, one step
};

/// One box's state after a step, in scene order.
struct BoxState {
  float position[3];          ///< m
  float velocity[3];          ///< m/s
  float angular_velocity[3];  ///< rad/s, world frame
};

/// A physics engine holding one copy of the scene.
class Engine {
 public:
  virtual ~Engine() = default;
  /// Short name: "impact", "bullet", "ode".
  virtual const char* name() const = 0;
  /// One line of the settings it runs with.
  virtual std::string settings() const = 0;
  /// Advances one step of PeerScene::dt; false (with a message on stderr) on failure.
  virtual bool step() = 0;
  /// The boxes' states, out->size() == boxes.
  virtual void read(std::vector<BoxState>* out) const = 0;
};

/// Bullet 3: btDiscreteDynamicsWorld, btDbvtBroadphase, btSequentialImpulseConstraintSolver
/// with `iterations` iterations, no sleeping (bench/rigid_peers_bullet.cpp; only when
/// IMPACT_RIGIDBENCH_HAVE_BULLET).
std::unique_ptr<Engine> make_bullet_engine(const PeerScene& scene, uint32_t iterations);
/// ODE: dWorldQuickStep with `iterations` iterations, a hash space, up to 4 contacts per
/// pair, no auto-disable (bench/rigid_peers_ode.cpp; only when IMPACT_RIGIDBENCH_HAVE_ODE).
std::unique_ptr<Engine> make_ode_engine(const PeerScene& scene, uint32_t iterations);

}  // namespace impact::bench::rigid
