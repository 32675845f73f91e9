// Bullet 3 (libbullet-dev, single precision) as an engine of impact_rigidbench; see
// bench/rigid_peers.h. A btDiscreteDynamicsWorld with its default collision
// configuration, a btDbvtBroadphase and a btSequentialImpulseConstraintSolver (Debian's
// Bullet is built without BT_THREADSAFE, so btDiscreteDynamicsWorldMt has no task
// scheduler: one thread). Bullet multiplies the two friction coefficients of a pair;
// each object gets sqrt(friction) so that the pair's product is impact's
// sqrt(f_a f_b). Restitution is likewise combined by product (0 in every scene).
// Sleeping is off (DISABLE_DEACTIVATION), as in impact's run.
#include <BulletCollision/BroadphaseCollision/btDbvtBroadphase.h>
#include <BulletCollision/CollisionDispatch/btCollisionDispatcher.h>
#include <BulletCollision/CollisionDispatch/btDefaultCollisionConfiguration.h>
#include <BulletCollision/CollisionShapes/btBoxShape.h>
#include <BulletCollision/CollisionShapes/btStaticPlaneShape.h>
#include <BulletDynamics/ConstraintSolver/btSequentialImpulseConstraintSolver.h>
#include <BulletDynamics/Dynamics/btDiscreteDynamicsWorld.h>
#include <BulletDynamics/Dynamics/btRigidBody.h>
#include <LinearMath/btScalar.h>

#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "bench/rigid_peers.h"

namespace impact::bench::rigid {
namespace {

class BulletEngine final : public Engine {
 public:
  BulletEngine(const PeerScene& scene, uint32_t iterations) : dt_(scene.dt), iterations_(iterations) {
    dispatcher_ = std::make_unique<btCollisionDispatcher>(&config_);
    world_ = std::make_unique<btDiscreteDynamicsWorld>(dispatcher_.get(), &broadphase_, &solver_, &config_);
    world_->setGravity(btVector3(scene.gravity[0], scene.gravity[1], scene.gravity[2]));
    world_->getSolverInfo().m_numIterations = static_cast<int>(iterations);
    for (const Plane& p : scene.planes) {
      // btStaticPlaneShape: {x : dot(n, x) = constant}, solid below, as our planes.
      auto shape = std::make_unique<btStaticPlaneShape>(btVector3(p.normal[0], p.normal[1], p.normal[2]), p.offset);
      btRigidBody::btRigidBodyConstructionInfo info(0.0f, nullptr, shape.get());
      info.m_friction = std::sqrt(p.friction);
      info.m_restitution = p.restitution;
      add(info, std::move(shape), /*dynamic=*/false);
    }
    for (const BoxBody& b : scene.boxes) {
      btBoxShape* shape = box_shape(btVector3(b.half_extents[0], b.half_extents[1], b.half_extents[2]));
      btVector3 inertia(0, 0, 0);
      shape->calculateLocalInertia(b.mass, inertia);
      btRigidBody::btRigidBodyConstructionInfo info(b.mass, nullptr, shape, inertia);
      info.m_startWorldTransform.setOrigin(btVector3(b.position[0], b.position[1], b.position[2]));
      info.m_startWorldTransform.setRotation(
          btQuaternion(b.orientation[0], b.orientation[1], b.orientation[2], b.orientation[3]));
      info.m_friction = std::sqrt(b.friction);
      info.m_restitution = b.restitution;
      boxes_.push_back(add(info, nullptr, /*dynamic=*/true));
    }
  }
  ~BulletEngine() override {
    for (auto it = bodies_.rbegin(); it != bodies_.rend(); ++it) world_->removeRigidBody(it->get());
  }

  const char* name() const override { return "bullet"; }
  std::string settings() const override {
    return "Bullet " + std::to_string(BT_BULLET_VERSION) +
           " btDiscreteDynamicsWorld, btDbvtBroadphase, btSequentialImpulseConstraintSolver, " +
           std::to_string(iterations_) + " iterations, 1 thread";
  }
  bool step() override {
    // maxSubSteps 0: exactly one internal step of dt (no fixed-step accumulator).
    world_->stepSimulation(dt_, 0);
    return true;
  }
  void read(std::vector<BoxState>* out) const override {
    out->resize(boxes_.size());
    for (size_t i = 0; i < boxes_.size(); ++i) {
      const btRigidBody* b = boxes_[i];
      const btVector3& p = b->getWorldTransform().getOrigin();
      const btVector3& v = b->getLinearVelocity();
      const btVector3& w = b->getAngularVelocity();
      (*out)[i] = BoxState{{p.x(), p.y(), p.z()}, {v.x(), v.y(), v.z()}, {w.x(), w.y(), w.z()}};
    }
  }

 private:
  // One shape per distinct size (the scenes use one or a few).
  btBoxShape* box_shape(const btVector3& half) {
    for (size_t k = 0; k < box_halves_.size(); ++k)
      if (box_halves_[k] == half) return box_shapes_[k];
    auto shape = std::make_unique<btBoxShape>(half);
    box_halves_.push_back(half);
    box_shapes_.push_back(shape.get());
    shapes_.push_back(std::move(shape));
    return box_shapes_.back();
  }

  // Adds a body (its shape, when given, is kept alive with it).
  btRigidBody* add(const btRigidBody::btRigidBodyConstructionInfo& info, std::unique_ptr<btCollisionShape> shape,
                   bool dynamic) {
    auto body = std::make_unique<btRigidBody>(info);
    if (dynamic) body->setActivationState(DISABLE_DEACTIVATION);
    world_->addRigidBody(body.get());
    if (shape) shapes_.push_back(std::move(shape));
    bodies_.push_back(std::move(body));
    return bodies_.back().get();
  }

  float dt_;
  uint32_t iterations_;
  btDefaultCollisionConfiguration config_;
  btDbvtBroadphase broadphase_;
  btSequentialImpulseConstraintSolver solver_;
  std::unique_ptr<btCollisionDispatcher> dispatcher_;
  std::unique_ptr<btDiscreteDynamicsWorld> world_;
  std::vector<std::unique_ptr<btCollisionShape>> shapes_;
  std::vector<std::unique_ptr<btRigidBody>> bodies_;
  std::vector<btRigidBody*> boxes_;
  std::vector<btVector3> box_halves_;
  std::vector<btBoxShape*> box_shapes_;
};

}  // namespace

std::unique_ptr<Engine> make_bullet_engine(const PeerScene& scene, uint32_t iterations) {
  return std::make_unique<BulletEngine>(scene, iterations);
}

}  // namespace impact::bench::rigid
