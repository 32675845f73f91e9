#include "bench/raycast_bench_bullet.h"

#if IMPACT_RAYBENCH_HAVE_BULLET
#include <btBulletCollisionCommon.h>
#endif

namespace impact::bench {

#if IMPACT_RAYBENCH_HAVE_BULLET
struct BulletWorld {
  btDefaultCollisionConfiguration config;
  btCollisionDispatcher dispatcher{&config};
  btDbvtBroadphase broadphase;
  btCollisionWorld world{&dispatcher, &broadphase, &config};
  std::vector<std::unique_ptr<btSphereShape>> shapes;
  std::vector<std::unique_ptr<btCollisionObject>> objects;
  float sign = 1.0f;
  ~BulletWorld() {
    for (auto& o : objects) world.removeCollisionObject(o.get());
  }
};

bool bullet_available() { return true; }

std::unique_ptr<BulletWorld, BulletWorldDeleter> make_bullet_spheres(std::span<const float> x, std::span<const float> y,
                                                                     std::span<const float> z, std::span<const float> r) {
  std::unique_ptr<BulletWorld, BulletWorldDeleter> w(new BulletWorld);
  w->shapes.reserve(x.size());
  w->objects.reserve(x.size());
  for (size_t i = 0; i < x.size(); ++i) {
    w->shapes.push_back(std::make_unique<btSphereShape>(r[i]));
    auto o = std::make_unique<btCollisionObject>();
    o->setCollisionShape(w->shapes.back().get());
    btTransform t;
    t.setIdentity();
    t.setOrigin(btVector3(x[i], y[i], z[i]));
    o->setWorldTransform(t);
    w->world.addCollisionObject(o.get());
    w->objects.push_back(std::move(o));
  }
  w->world.updateAabbs();
  return w;
}

uint64_t bullet_ray_test(BulletWorld& w, std::span<const Ray> rays, float length) {
  uint64_t hits = 0;
  for (const Ray& r : rays) {
    const btVector3 from(r.origin.x(), r.origin.y(), r.origin.z());
    const Eigen::Vector3f e = r.origin + length * r.direction.normalized();
    const btVector3 to(e.x(), e.y(), e.z());
    btCollisionWorld::ClosestRayResultCallback cb(from, to);
    w.world.rayTest(from, to, cb);
    hits += cb.hasHit();
  }
  return hits;
}

void bullet_move_all(BulletWorld& w, float dx) {
  const btVector3 d(w.sign * dx, 0, 0);
  w.sign = -w.sign;
  for (auto& o : w.objects) o->getWorldTransform().setOrigin(o->getWorldTransform().getOrigin() + d);
  w.world.updateAabbs();
}
void bullet_reinsert_all(BulletWorld& w, float dx) {
  const btVector3 d(w.sign * dx, 0, 0);
  w.sign = -w.sign;
  for (auto& o : w.objects) w.world.removeCollisionObject(o.get());
  for (auto& o : w.objects) {
    o->getWorldTransform().setOrigin(o->getWorldTransform().getOrigin() + d);
    w.world.addCollisionObject(o.get());
  }
  w.world.updateAabbs();
}
#else
struct BulletWorld {};
void bullet_reinsert_all(BulletWorld&, float) {}
bool bullet_available() { return false; }
std::unique_ptr<BulletWorld, BulletWorldDeleter> make_bullet_spheres(std::span<const float>, std::span<const float>,
                                                                     std::span<const float>, std::span<const float>) {
  return nullptr;
}
uint64_t bullet_ray_test(BulletWorld&, std::span<const Ray>, float) { return 0; }
void bullet_move_all(BulletWorld&, float) {}
#endif

void BulletWorldDeleter::operator()(BulletWorld* w) const { delete w; }

}  // namespace impact::bench
