// ODE 0.16 (libode-dev, double precision) as an engine of impact_rigidbench; see
// bench/rigid_peers.h. dWorldQuickStep (projected Gauss-Seidel) with the given
// iterations, a multi-resolution hash space (cells 0.5 .. 16 m), up to 4 contact points
// per touching pair (ODE's box-box and box-plane tests return at most 4 once culled).
// Each contact: friction pyramid scaled by the normal force (dContactApprox1),
// mu = sqrt(f_a f_b) as in impact, no bounce (every scene has restitution 0). World
// ERP 0.2 and CFM 1e-5 (ODE's defaults in a single-precision build; this double build
// would start from CFM 1e-10), a 1 mm contact surface layer (impact's penetration
// slop), corrections capped at 3 m/s (impact's max_push_speed).
// Auto-disable off, as impact runs with sleeping off. One thread.
#include <ode/ode.h>

#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "bench/rigid_peers.h"

namespace impact::bench::rigid {
namespace {

constexpr int kMaxContacts = 4;

// ODE's global state: initialised once for the process (dInitODE2 / dCloseODE).
struct OdeLibrary {
  OdeLibrary() { dInitODE2(0); }
  ~OdeLibrary() { dCloseODE(); }
};

class OdeEngine final : public Engine {
 public:
  OdeEngine(const PeerScene& scene, uint32_t iterations) : dt_(scene.dt), iterations_(iterations) {
    static OdeLibrary library;
    world_ = dWorldCreate();
    dWorldSetGravity(world_, scene.gravity[0], scene.gravity[1], scene.gravity[2]);
    dWorldSetQuickStepNumIterations(world_, static_cast<int>(iterations));
    dWorldSetERP(world_, 0.2);
    dWorldSetCFM(world_, 1e-5);
    dWorldSetContactSurfaceLayer(world_, 0.001);
    dWorldSetContactMaxCorrectingVel(world_, 3.0);
    dWorldSetAutoDisableFlag(world_, 0);
    space_ = dHashSpaceCreate(nullptr);
    dHashSpaceSetLevels(space_, -1, 4);
    contacts_ = dJointGroupCreate(0);
    // Geom data: an index into friction_ (planes first, then boxes).
    friction_.reserve(scene.planes.size() + scene.boxes.size());
    for (const Plane& p : scene.planes) {
      // dCreatePlane: {x : dot(n, x) = d}, solid on the side against n, as our planes.
      dGeomID g = dCreatePlane(space_, p.normal[0], p.normal[1], p.normal[2], p.offset);
      tag(g, p.friction);
    }
    bodies_.reserve(scene.boxes.size());
    for (const BoxBody& b : scene.boxes) {
      dBodyID body = dBodyCreate(world_);
      dMass m;
      dMassSetBoxTotal(&m, b.mass, 2.0 * b.half_extents[0], 2.0 * b.half_extents[1], 2.0 * b.half_extents[2]);
      dBodySetMass(body, &m);
      dBodySetPosition(body, b.position[0], b.position[1], b.position[2]);
      const dQuaternion q = {b.orientation[3], b.orientation[0], b.orientation[1], b.orientation[2]};  // w, x, y, z
      dBodySetQuaternion(body, q);
      dGeomID g = dCreateBox(space_, 2.0 * b.half_extents[0], 2.0 * b.half_extents[1], 2.0 * b.half_extents[2]);
      dGeomSetBody(g, body);
      tag(g, b.friction);
      bodies_.push_back(body);
    }
  }
  ~OdeEngine() override {
    dJointGroupDestroy(contacts_);
    dSpaceDestroy(space_);  // destroys its geoms (cleanup mode on by default)
    dWorldDestroy(world_);  // and its bodies
  }
  OdeEngine(const OdeEngine&) = delete;
  OdeEngine& operator=(const OdeEngine&) = delete;

  const char* name() const override { return "ode"; }
  std::string settings() const override {
    return "ODE dWorldQuickStep, " + std::to_string(iterations_) +
           " iterations, ERP 0.2, CFM 1e-5, hash space, 4 contacts per pair, 1 thread";
  }
  bool step() override {
    dSpaceCollide(space_, this, &OdeEngine::near_callback);
    const int ok = dWorldQuickStep(world_, dt_);
    dJointGroupEmpty(contacts_);
    if (ok == 0) std::fprintf(stderr, "impact_rigidbench: dWorldQuickStep failed (out of memory)\n");
    return ok != 0;
  }
  void read(std::vector<BoxState>* out) const override {
    out->resize(bodies_.size());
    for (size_t i = 0; i < bodies_.size(); ++i) {
      const dReal* p = dBodyGetPosition(bodies_[i]);
      const dReal* v = dBodyGetLinearVel(bodies_[i]);
      const dReal* w = dBodyGetAngularVel(bodies_[i]);
      auto f = [](dReal x) { return static_cast<float>(x); };
      (*out)[i] = BoxState{{f(p[0]), f(p[1]), f(p[2])}, {f(v[0]), f(v[1]), f(v[2])}, {f(w[0]), f(w[1]), f(w[2])}};
    }
  }

 private:
  void tag(dGeomID g, float friction) {
    friction_.push_back(friction);
    dGeomSetData(g, reinterpret_cast<void*>(static_cast<uintptr_t>(friction_.size() - 1)));
  }
  float friction_of(dGeomID g) const {
    return friction_[static_cast<size_t>(reinterpret_cast<uintptr_t>(dGeomGetData(g)))];
  }

  static void near_callback(void* data, dGeomID a, dGeomID b) {
    auto* self = static_cast<OdeEngine*>(data);
    dBodyID ba = dGeomGetBody(a), bb = dGeomGetBody(b);
    if (ba == nullptr && bb == nullptr) return;  // static against static
    dContact c[kMaxContacts];
    const int n = dCollide(a, b, kMaxContacts, &c[0].geom, sizeof(dContact));
    if (n <= 0) return;
    const dReal mu = std::sqrt(static_cast<dReal>(self->friction_of(a)) * self->friction_of(b));
    for (int k = 0; k < n; ++k) {
      c[k].surface.mode = dContactApprox1;
      c[k].surface.mu = mu;
      dJointID j = dJointCreateContact(self->world_, self->contacts_, &c[k]);
      dJointAttach(j, ba, bb);
    }
  }

  dReal dt_;
  uint32_t iterations_;
  dWorldID world_ = nullptr;
  dSpaceID space_ = nullptr;
  dJointGroupID contacts_ = nullptr;
  std::vector<dBodyID> bodies_;
  std::vector<float> friction_;
};

}  // namespace

std::unique_ptr<Engine> make_ode_engine(const PeerScene& scene, uint32_t iterations) {
  return std::make_unique<OdeEngine>(scene, iterations);
}

}  // namespace impact::bench::rigid
