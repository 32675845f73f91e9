// impact::World: validation at the API boundary, SoA storage, handles, time.
// Every mutating call validates its whole input first and only then writes, so a
// rejected call leaves the world exactly as it was.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "host/body_inertia.h"
#include "host/broadphase/query.h"
#include "host/shapes/pose.h"
#include "host/world_checks.h"
#include "host/world_impl.h"
#include "impact/broadphase.h"
#include "impact/world.h"

namespace impact {
using host::fmt_float;
using host::invalid;
using host::finite3;
using host::vec_str;
using host::kMaxCoordinate;
using host::check_position;
using host::check_velocity;
using host::handle_str;
using host::resolve_bodies;

namespace {

// Kernels use index n as a sentinel, and the solver's contact keys hold a body slot
// plus a plane bit and a 2-bit manifold point index in 32 bits.
constexpr uint64_t kMaxBodies = (1ull << 29) - 16;

Status check_body(const std::string& who, const Eigen::Vector3f& pos, const Eigen::Vector3f& vel,
                  float inv_mass, float radius, float restitution) {
  if (Status s = check_position(who, pos); !s.ok()) return s;
  if (Status s = check_velocity(who, vel); !s.ok()) return s;
  if (!(std::isfinite(inv_mass) && inv_mass >= 0.0f))
    return invalid(who, "inv_mass must be finite and >= 0 (0 = static), got " + fmt_float(inv_mass));
  if (!(std::isfinite(radius) && radius > 0.0f && radius <= kMaxCoordinate))
    return invalid(who, "radius must be finite and > 0, got " + fmt_float(radius));
  if (!(restitution >= 0.0f && restitution <= 1.0f))
    return invalid(who, "restitution must be in [0, 1], got " + fmt_float(restitution));
  return Status();
}

// The motion and material fields of a body: its orientation a unit quaternion (a plain
// sphere's too), finite angular velocity, friction, rolling resistance and damping
// finite and >= 0, a finite gravity scale.
Status check_motion(const std::string& who, const BodyDesc& d) {
  Pose pose;
  pose.orientation = d.orientation;
  if (!host::pose_ok(pose)) return host::check_pose(pose, who.c_str());
  if (!finite3(d.angular_velocity))
    return invalid(who, "angular_velocity must be finite, got " + vec_str(d.angular_velocity));
  auto non_negative = [&](const char* field, float v) {
    return std::isfinite(v) && v >= 0.0f
               ? Status()
               : invalid(who, std::string(field) + " must be finite and >= 0, got " + fmt_float(v));
  };
  if (Status st = non_negative("friction", d.friction); !st.ok()) return st;
  if (Status st = non_negative("rolling_resistance", d.rolling_resistance); !st.ok()) return st;
  if (Status st = non_negative("linear_damping", d.linear_damping); !st.ok()) return st;
  if (Status st = non_negative("angular_damping", d.angular_damping); !st.ok()) return st;
  if (!std::isfinite(d.gravity_scale))
    return invalid(who, "gravity_scale must be finite, got " + fmt_float(d.gravity_scale));
  return Status();
}

// A body's shape: a shape of the world's set that can be a body. *bounding_radius: the
// shape's local bounds' farthest corner (the radius stored for shaped bodies), or
// `radius` for spheres.
Status check_shape(const std::string& who, const WorldImpl& w, const BodyDesc& d, float* bounding_radius) {
  *bounding_radius = d.radius;
  if (!d.shape.valid()) return Status();
  const ShapeStore& st = w.shapes.store();
  if (d.shape.index >= st.shapes.size())
    return invalid(who, "shape " + std::to_string(d.shape.index) + " is not in World::shapes() (" +
                            std::to_string(st.shapes.size()) + " shapes)");
  const ShapeRecord& r = st.shapes[d.shape.index];
  if (r.type == ShapeType::kHalfSpace)
    return invalid(who, "a half-space shape cannot be a body (use create_planes)");
  if (r.type == ShapeType::kMesh && d.inv_mass != 0.0f)
    return invalid(who, "a mesh body must be static (inv_mass 0), got inv_mass " + fmt_float(d.inv_mass));
  // The farthest corner of the local box: per axis the larger magnitude (hulls and
  // compounds need not be centred on the body's origin).
  const float rr = r.local_min.cwiseAbs().cwiseMax(r.local_max.cwiseAbs()).norm();
  *bounding_radius = rr;
  if (!(rr > 0.0f && rr <= kMaxCoordinate)) return invalid(who, "shape bounds out of range");
  return Status();
}

Status check_desc(const WorldDesc& d) {
  const std::string w = "WorldDesc";
  if (!finite3(d.gravity)) return invalid(w, "gravity must be finite, got " + vec_str(d.gravity));
  if (!(std::isfinite(d.fixed_dt) && d.fixed_dt > 0.0f))
    return invalid(w, "fixed_dt must be finite and > 0, got " + fmt_float(d.fixed_dt));
  if (d.max_steps_per_frame == 0) return invalid(w, "max_steps_per_frame must be >= 1");
  const SolverDesc& s = d.solver;
  if (s.kind != SolverKind::kSoftStep && s.kind != SolverKind::kJacobi)
    return invalid(w, "solver.kind is not a known SolverKind");
  if (s.substeps == 0 || s.substeps > 64) return invalid(w, "solver.substeps must be in [1, 64], got " + std::to_string(s.substeps));
  if (!(std::isfinite(s.contact_hertz) && s.contact_hertz >= 0.0f))
    return invalid(w, "solver.contact_hertz must be finite and >= 0, got " + fmt_float(s.contact_hertz));
  if (!(std::isfinite(s.contact_damping_ratio) && s.contact_damping_ratio >= 0.0f))
    return invalid(w, "solver.contact_damping_ratio must be finite and >= 0, got " + fmt_float(s.contact_damping_ratio));
  if (!(std::isfinite(s.max_push_speed) && s.max_push_speed > 0.0f))
    return invalid(w, "solver.max_push_speed must be finite and > 0, got " + fmt_float(s.max_push_speed));
  if (!(s.position_correction >= 0.0f && s.position_correction <= 1.0f))
    return invalid(w, "solver.position_correction must be in [0, 1], got " + fmt_float(s.position_correction));
  if (!(std::isfinite(s.penetration_slop) && s.penetration_slop >= 0.0f))
    return invalid(w, "solver.penetration_slop must be finite and >= 0, got " + fmt_float(s.penetration_slop));
  if (!(std::isfinite(s.restitution_threshold) && s.restitution_threshold >= 0.0f))
    return invalid(w, "solver.restitution_threshold must be finite and >= 0, got " +
                          fmt_float(s.restitution_threshold));
  if (!(s.warm_start >= 0.0f && s.warm_start <= 1.0f))
    return invalid(w, "solver.warm_start must be in [0, 1], got " + fmt_float(s.warm_start));
  if (!(std::isfinite(s.sleep_speed) && s.sleep_speed > 0.0f))
    return invalid(w, "solver.sleep_speed must be finite and > 0, got " + fmt_float(s.sleep_speed));
  if (!(std::isfinite(s.sleep_time) && s.sleep_time > 0.0f))
    return invalid(w, "solver.sleep_time must be finite and > 0, got " + fmt_float(s.sleep_time));
  if (d.broad_phase != BroadPhaseKind::kGrid && d.broad_phase != BroadPhaseKind::kBruteForce &&
      d.broad_phase != BroadPhaseKind::kLbvh && d.broad_phase != BroadPhaseKind::kSweepAndPrune &&
      d.broad_phase != BroadPhaseKind::kAuto)
    return invalid(w, "broad_phase is not a known BroadPhaseKind");
  if (d.lbvh_update != LbvhUpdate::kRebuild && d.lbvh_update != LbvhUpdate::kRefit &&
      d.lbvh_update != LbvhUpdate::kAuto && d.lbvh_update != LbvhUpdate::kPairCache)
    return invalid(w, "lbvh_update is not a known LbvhUpdate");
  if (!(std::isfinite(d.lbvh_fat_margin) && d.lbvh_fat_margin >= 0.0f))
    return invalid(w, "lbvh_fat_margin must be finite and >= 0, got " + fmt_float(d.lbvh_fat_margin));
  if (!(std::isfinite(d.lbvh_refit_sah_limit) && d.lbvh_refit_sah_limit >= 1.0))
    return invalid(w, "lbvh_refit_sah_limit must be finite and >= 1, got " +
                          std::to_string(d.lbvh_refit_sah_limit));
  const ContinuousDesc& c = d.ccd;
  if (c.mode != ContinuousMode::kOff && c.mode != ContinuousMode::kSpeculative)
    return invalid(w, "ccd.mode is not a known ContinuousMode");
  if (!(std::isfinite(c.speculative_margin) && c.speculative_margin >= 0.0f))
    return invalid(w, "ccd.speculative_margin must be finite and >= 0, got " + fmt_float(c.speculative_margin));
  NarrowPhaseOptions narrow = d.narrow_phase;
  narrow.exec = {};  // ignored: the world's backend runs the passes
  if (Status st = host::validate_options(narrow); !st.ok()) return invalid(w, "narrow_phase." + st.message());
  Backend b;
  if (!host::resolve_backend(d.backend, &b))
    return Status(StatusCode::kUnsupported,
                  std::string("WorldDesc: backend '") + to_string(d.backend) + "' is not built into this library");
  return Status();
}

}  // namespace

WorldImpl::WorldImpl(const WorldDesc& d) : desc(d), exec(d.backend, d.threads) {
  if (desc.interpolation) bodies.enable(host::FieldSet::kInterpolation);
  configure_broad_phase();
}

void WorldImpl::configure_broad_phase() {
  positions_changed();
  broad_phase.set_kind(desc.broad_phase);
  host::LbvhOptions o = broad_phase.lbvh.options();
  o.update = desc.lbvh_update;
  o.refit_sah_limit = desc.lbvh_refit_sah_limit;
  o.fat_margin = desc.lbvh_fat_margin;
  broad_phase.set_lbvh_options(o);
}

void WorldImpl::slots_changed(bool bodies_moved) {
  if (bodies_moved) {
    broad_phase.invalidate();
    positions_changed();
    pairs.clear();
  }
  contacts.clear();
  solver.forget();
  solver.clear_impulses();
  soft_solver.forget();
  soft_solver.clear_impulses();
}

void WorldImpl::enable_rigid() {
  host::BodyStore& s = bodies;
  if (s.on(host::FieldSet::kRigid)) return;
  s.enable(host::FieldSet::kRigid);
  // The bodies that exist get their inertia now (until here nothing could turn them).
  for (uint32_t i = 0; i < s.size(); ++i) {
    if (!(s.inv_mass[i] > 0.0f) || s.fixed_rotation[i]) continue;
    const bool shaped = s.on(host::FieldSet::kShaped) && s.shape[i] != host::kNoShape;
    host::BodyRow row;
    host::body_inertia(shapes, shaped ? ShapeId{s.shape[i]} : ShapeId{}, s.radius[i], s.inv_mass[i], &row);
    host::set_rigid_fields(s, i, row);
  }
}

void WorldImpl::wake(std::span<const uint32_t> slots) {
  host::BodyStore& s = bodies;
  frozen = false;
  // Neighbours can be asleep only if the last step left bodies asleep.
  if (last.asleep_bodies > 0 && contacts.manifolds > 0) {
    std::vector<uint8_t> moved(s.size(), 0);
    for (const uint32_t k : slots) moved[k] = 1;
    const kernels::ContactManifoldArrays c = contacts.view();
    for (size_t m = 0; m < contacts.manifolds; ++m) {
      if (c.b_is_plane[m] || c.a[m] >= s.size() || c.b[m] >= s.size()) continue;
      if (moved[c.a[m]] || moved[c.b[m]]) {
        for (const uint32_t k : {c.a[m], c.b[m]}) {
          s.asleep[k] = 0;
          s.sleep_time[k] = 0.0f;
        }
      }
    }
  }
  for (const uint32_t k : slots) {
    s.asleep[k] = 0;
    s.sleep_time[k] = 0.0f;
  }
}

void WorldImpl::wake_all() {
  frozen = false;
  std::fill(bodies.asleep.begin(), bodies.asleep.end(), uint8_t{0});
  std::fill(bodies.sleep_time.begin(), bodies.sleep_time.end(), 0.0f);
}

void WorldImpl::swap_remove_body(uint32_t slot) {
  host::BodyStore& s = bodies;
  const auto last_slot = static_cast<uint32_t>(s.size() - 1);
  if (s.on(host::FieldSet::kShaped) && s.shape[slot] != host::kNoShape) --shaped_count;
  const BodyHandle gone = s.handle[slot];
  s.swap_remove(slot);
  if (slot != last_slot) body_handles.rebind(s.handle[slot].index, slot);
  body_handles.release(gone.index);
}

// --- World ------------------------------------------------------------------------------

World::World(std::unique_ptr<WorldImpl> impl) : impl_(std::move(impl)) {}
World::~World() = default;

Status World::create(const WorldDesc& desc, std::unique_ptr<World>* out) {
  if (out == nullptr) return invalid("World::create", "out must not be null");
  out->reset();
  if (Status s = check_desc(desc); !s.ok()) return s;
  out->reset(new World(std::make_unique<WorldImpl>(desc)));
  return Status();
}

namespace {

// Appends one validated body; returns its handle. The first body that can rotate
// switches the rigid field set on, the first with damping or a gravity scale the
// damping set (host/body_store.h).
BodyHandle append_body(WorldImpl& w, const BodyDesc& d, float radius) {
  host::BodyStore& s = w.bodies;
  const auto slot = static_cast<uint32_t>(s.size());
  const bool shaped = d.shape.valid();
  const bool spins = d.angular_velocity != Eigen::Vector3f::Zero();
  const bool rubs = d.friction > 0.0f || d.rolling_resistance > 0.0f;
  const bool rotates = spins || (d.inv_mass > 0.0f && !d.fixed_rotation && (shaped || rubs));
  if (shaped) s.enable(host::FieldSet::kShaped);  // the first shaped body: every body gets the fields
  if (d.orientation.coeffs() != Eigen::Quaternionf::Identity().coeffs())
    s.enable(host::FieldSet::kOriented);  // kept even where nothing turns the body
  const bool damped = d.linear_damping != 0.0f || d.angular_damping != 0.0f || d.gravity_scale != 1.0f;
  if (rotates || damped) w.enable_rigid();
  if (damped) s.enable(host::FieldSet::kDamping);
  host::BodyRow row;
  row.pos_x = d.position.x();
  row.pos_y = d.position.y();
  row.pos_z = d.position.z();
  row.vel_x = d.velocity.x();
  row.vel_y = d.velocity.y();
  row.vel_z = d.velocity.z();
  row.inv_mass = d.inv_mass;
  row.radius = radius;
  row.restitution = d.restitution;
  row.layer = d.layer;
  row.mask = d.mask;
  row.is_static = static_cast<uint8_t>(d.inv_mass == 0.0f);
  row.fixed_rotation = d.fixed_rotation ? 1 : 0;
  row.prev_x = d.position.x();
  row.prev_y = d.position.y();
  row.prev_z = d.position.z();
  row.shape = shaped ? d.shape.index : host::kNoShape;
  const Eigen::Quaternionf n = d.orientation.normalized();
  row.qx = n.x();
  row.qy = n.y();
  row.qz = n.z();
  row.qw = n.w();
  row.friction = d.friction;
  row.rolling = d.rolling_resistance;
  row.wx = d.angular_velocity.x();
  row.wy = d.angular_velocity.y();
  row.wz = d.angular_velocity.z();
  row.linear_damping = d.linear_damping;
  row.angular_damping = d.angular_damping;
  row.gravity_scale = d.gravity_scale;
  if (d.inv_mass > 0.0f && !d.fixed_rotation) host::body_inertia(w.shapes, d.shape, radius, d.inv_mass, &row);
  w.body_handles.acquire(slot, &row.handle.index, &row.handle.generation);
  s.append(row);
  if (shaped) ++w.shaped_count;
  w.broad_phase.invalidate();
  w.positions_changed();
  w.frozen = false;  // a new body is awake
  return row.handle;
}

void reserve_bodies(WorldImpl& w, size_t extra) { w.bodies.reserve(w.bodies.size() + extra); }

Status check_capacity(const WorldImpl& w, size_t extra, const char* where) {
  if (w.bodies.size() + extra > kMaxBodies)
    return Status(StatusCode::kCapacityExceeded,
                  std::string(where) + ": body count would exceed " + std::to_string(kMaxBodies));
  return Status();
}

}  // namespace

Status World::create_bodies(std::span<const BodyDesc> descs, std::span<BodyHandle> out) {
  if (out.size() != descs.size())
    return Status(StatusCode::kSizeMismatch, "create_bodies: out has " + std::to_string(out.size()) +
                                                 " handles for " + std::to_string(descs.size()) + " bodies");
  if (Status s = check_capacity(*impl_, descs.size(), "create_bodies"); !s.ok()) return s;
  std::vector<float> radius(descs.size());
  for (size_t i = 0; i < descs.size(); ++i) {
    const BodyDesc& d = descs[i];
    const std::string who = "create_bodies: body " + std::to_string(i);
    if (Status s = check_shape(who, *impl_, d, &radius[i]); !s.ok()) return s;
    if (Status s = check_body(who, d.position, d.velocity, d.inv_mass, radius[i], d.restitution); !s.ok())
      return s;
    if (Status s = check_motion(who, d); !s.ok()) return s;
  }
  reserve_bodies(*impl_, descs.size());
  for (size_t i = 0; i < descs.size(); ++i) out[i] = append_body(*impl_, descs[i], radius[i]);
  return Status();
}

Status World::create_bodies(const Eigen::Ref<const Eigen::Matrix3Xf>& positions,
                            const Eigen::Ref<const Eigen::Matrix3Xf>& velocities,
                            const Eigen::Ref<const Eigen::VectorXf>& radii,
                            const Eigen::Ref<const Eigen::VectorXf>& inv_masses, const BodyDesc& common,
                            std::span<BodyHandle> out) {
  const size_t n = static_cast<size_t>(positions.cols());
  auto mismatch = [&](const char* what, size_t got) {
    return Status(StatusCode::kSizeMismatch, std::string("create_bodies: ") + what + " has " +
                                                 std::to_string(got) + " entries for " +
                                                 std::to_string(n) + " positions");
  };
  if (velocities.cols() != 0 && static_cast<size_t>(velocities.cols()) != n)
    return mismatch("velocities", static_cast<size_t>(velocities.cols()));
  if (static_cast<size_t>(radii.size()) != n) return mismatch("radii", static_cast<size_t>(radii.size()));
  if (static_cast<size_t>(inv_masses.size()) != n)
    return mismatch("inv_masses", static_cast<size_t>(inv_masses.size()));
  if (out.size() != n) return mismatch("out", out.size());
  if (Status s = check_capacity(*impl_, n, "create_bodies"); !s.ok()) return s;
  if (common.shape.valid())
    return invalid("create_bodies", "the Eigen bulk import creates spheres; give shaped bodies as BodyDesc");
  if (Status s = check_motion("create_bodies: common", common); !s.ok()) return s;
  const bool has_vel = velocities.cols() != 0;
  auto vel = [&](size_t i) -> Eigen::Vector3f {
    return has_vel ? Eigen::Vector3f(velocities.col(static_cast<Eigen::Index>(i))) : Eigen::Vector3f::Zero();
  };
  for (size_t i = 0; i < n; ++i) {
    const auto c = static_cast<Eigen::Index>(i);
    if (Status s = check_body("create_bodies: body " + std::to_string(i), positions.col(c), vel(i),
                              inv_masses[c], radii[c], common.restitution);
        !s.ok())
      return s;
  }
  reserve_bodies(*impl_, n);
  for (size_t i = 0; i < n; ++i) {
    const auto c = static_cast<Eigen::Index>(i);
    BodyDesc d = common;
    d.position = positions.col(c);
    d.velocity = vel(i);
    d.inv_mass = inv_masses[c];
    d.radius = radii[c];
    out[i] = append_body(*impl_, d, radii[c]);
  }
  return Status();
}


Status World::destroy_bodies(std::span<const BodyHandle> handles) {
  std::vector<uint32_t> slots;
  if (Status s = resolve_bodies(*impl_, handles, "destroy_bodies", &slots); !s.ok()) return s;
  std::vector<uint32_t> sorted(slots);
  std::sort(sorted.begin(), sorted.end());  // validation only; does not shape results
  if (std::adjacent_find(sorted.begin(), sorted.end()) != sorted.end())
    return invalid("destroy_bodies", "the same body is listed twice");
  impl_->wake(slots);           // what rested on them falls
  impl_->slots_changed(true);  // slots move: last step's results and contact keys no longer apply
  for (const BodyHandle& h : handles) {
    // Look up again: earlier removals may have moved this body to another slot.
    impl_->swap_remove_body(impl_->body_handles.lookup(h.index, h.generation));
  }
  return Status();
}

Status World::set_positions(std::span<const BodyHandle> handles, std::span<const Eigen::Vector3f> values) {
  if (handles.size() != values.size())
    return Status(StatusCode::kSizeMismatch, "set_positions: handles and values differ in length");
  std::vector<uint32_t> slots;
  if (Status s = resolve_bodies(*impl_, handles, "set_positions", &slots); !s.ok()) return s;
  for (size_t i = 0; i < values.size(); ++i)
    if (Status s = check_position("set_positions: body " + std::to_string(i), values[i]); !s.ok()) return s;
  host::BodyStore& b = impl_->bodies;
  impl_->positions_changed();
  impl_->wake(slots);
  for (size_t i = 0; i < values.size(); ++i) {
    const uint32_t k = slots[i];
    b.pos_x[k] = values[i].x();
    b.pos_y[k] = values[i].y();
    b.pos_z[k] = values[i].z();
    if (b.on(host::FieldSet::kInterpolation)) {  // a teleport does not interpolate
      b.prev_x[k] = values[i].x();
      b.prev_y[k] = values[i].y();
      b.prev_z[k] = values[i].z();
    }
  }
  return Status();
}

Status World::set_velocities(std::span<const BodyHandle> handles, std::span<const Eigen::Vector3f> values) {
  if (handles.size() != values.size())
    return Status(StatusCode::kSizeMismatch, "set_velocities: handles and values differ in length");
  std::vector<uint32_t> slots;
  if (Status s = resolve_bodies(*impl_, handles, "set_velocities", &slots); !s.ok()) return s;
  for (size_t i = 0; i < values.size(); ++i)
    if (Status s = check_velocity("set_velocities: body " + std::to_string(i), values[i]); !s.ok()) return s;
  host::BodyStore& b = impl_->bodies;
  impl_->wake(slots);
  for (size_t i = 0; i < values.size(); ++i) {
    b.vel_x[slots[i]] = values[i].x();
    b.vel_y[slots[i]] = values[i].y();
    b.vel_z[slots[i]] = values[i].z();
  }
  return Status();
}

Status World::get_positions(std::span<const BodyHandle> handles, std::span<Eigen::Vector3f> out) const {
  if (handles.size() != out.size())
    return Status(StatusCode::kSizeMismatch, "get_positions: handles and out differ in length");
  std::vector<uint32_t> slots;
  if (Status s = resolve_bodies(*impl_, handles, "get_positions", &slots); !s.ok()) return s;
  const host::BodyStore& b = impl_->bodies;
  for (size_t i = 0; i < out.size(); ++i) out[i] = {b.pos_x[slots[i]], b.pos_y[slots[i]], b.pos_z[slots[i]]};
  return Status();
}

Status World::get_velocities(std::span<const BodyHandle> handles, std::span<Eigen::Vector3f> out) const {
  if (handles.size() != out.size())
    return Status(StatusCode::kSizeMismatch, "get_velocities: handles and out differ in length");
  std::vector<uint32_t> slots;
  if (Status s = resolve_bodies(*impl_, handles, "get_velocities", &slots); !s.ok()) return s;
  const host::BodyStore& b = impl_->bodies;
  for (size_t i = 0; i < out.size(); ++i) out[i] = {b.vel_x[slots[i]], b.vel_y[slots[i]], b.vel_z[slots[i]]};
  return Status();
}

Status World::slot_of(BodyHandle handle, uint32_t* out_slot) const {
  std::vector<uint32_t> slots;
  if (Status s = resolve_bodies(*impl_, std::span<const BodyHandle>(&handle, 1), "slot_of", &slots); !s.ok()) return s;
  *out_slot = slots[0];
  return Status();
}

size_t World::body_count() const { return impl_->bodies.size(); }

BodyArrays World::bodies() const { return host::body_arrays(impl_->bodies); }

// --- planes -----------------------------------------------------------------------------

Status World::create_planes(std::span<const PlaneDesc> descs, std::span<PlaneHandle> out) {
  if (out.size() != descs.size())
    return Status(StatusCode::kSizeMismatch, "create_planes: out and descs differ in length");
  for (size_t i = 0; i < descs.size(); ++i) {
    const PlaneDesc& d = descs[i];
    const std::string who = "create_planes: plane " + std::to_string(i);
    if (!finite3(d.normal)) return invalid(who, "normal must be finite, got " + vec_str(d.normal));
    // Length in double: float would overflow for 1e20 and underflow for 1e-30.
    const double len = d.normal.cast<double>().norm();
    if (!(len > 0.0)) return invalid(who, "normal must be non-zero, got " + vec_str(d.normal));
    if (!std::isfinite(d.offset)) return invalid(who, "offset must be finite, got " + fmt_float(d.offset));
    if (std::fabs(d.offset / len) > kMaxCoordinate)
      return invalid(who, "offset / |normal| must be <= 1e18 m, got " + std::to_string(d.offset / len));
    if (!(d.restitution >= 0.0f && d.restitution <= 1.0f))
      return invalid(who, "restitution must be in [0, 1], got " + fmt_float(d.restitution));
    if (!(std::isfinite(d.friction) && d.friction >= 0.0f))
      return invalid(who, "friction must be finite and >= 0, got " + fmt_float(d.friction));
  }
  host::PlaneStore& p = impl_->planes;
  for (size_t i = 0; i < descs.size(); ++i) {
    const PlaneDesc& d = descs[i];
    const Eigen::Vector3d nd = d.normal.cast<double>();
    const double len = nd.norm();
    const Eigen::Vector3f n = (nd / len).cast<float>();
    p.normal_x.push_back(n.x());
    p.normal_y.push_back(n.y());
    p.normal_z.push_back(n.z());
    p.offset.push_back(static_cast<float>(d.offset / len));  // n.x <= offset scales with the normal
    p.restitution.push_back(d.restitution);
    p.friction.push_back(d.friction);
    p.layer.push_back(d.layer);
    p.mask.push_back(d.mask);
    PlaneHandle h;
    impl_->plane_handles.acquire(static_cast<uint32_t>(p.handle.size()), &h.index, &h.generation);
    p.handle.push_back(h);
    out[i] = h;
  }
  if (!descs.empty()) impl_->wake_all();  // a new plane may cut through a sleeping pile
  return Status();
}

Status World::destroy_planes(std::span<const PlaneHandle> handles) {
  host::PlaneStore& p = impl_->planes;
  std::vector<uint32_t> slots(handles.size());
  for (size_t i = 0; i < handles.size(); ++i) {
    const uint32_t slot = impl_->plane_handles.lookup(handles[i].index, handles[i].generation);
    if (slot == host::HandleTable::kNoSlot)
      return Status(StatusCode::kStaleHandle,
                    "destroy_planes: plane " + std::to_string(i) + " handle {index " +
                        std::to_string(handles[i].index) + ", generation " +
                        std::to_string(handles[i].generation) + "} is stale or invalid");
    slots[i] = slot;
  }
  std::vector<uint32_t> sorted(slots);
  std::sort(sorted.begin(), sorted.end());
  if (std::adjacent_find(sorted.begin(), sorted.end()) != sorted.end())
    return invalid("destroy_planes", "the same plane is listed twice");
  impl_->slots_changed(false);  // plane slots move: last step's results and contact keys no longer apply
  if (!handles.empty()) impl_->wake_all();  // what rested on them falls
  for (const PlaneHandle& h : handles) {
    const uint32_t slot = impl_->plane_handles.lookup(h.index, h.generation);
    const uint32_t last = static_cast<uint32_t>(p.size() - 1);
    auto move = [&](auto& v) {
      v[slot] = v[last];
      v.pop_back();
    };
    for (auto* v : {&p.normal_x, &p.normal_y, &p.normal_z, &p.offset, &p.restitution, &p.friction}) move(*v);
    move(p.layer);
    move(p.mask);
    if (slot != last) impl_->plane_handles.rebind(p.handle[last].index, slot);
    move(p.handle);
    impl_->plane_handles.release(h.index);
  }
  return Status();
}

size_t World::plane_count() const { return impl_->planes.size(); }

PlaneArrays World::planes() const {
  const host::PlaneStore& p = impl_->planes;
  return PlaneArrays{p.normal_x, p.normal_y, p.normal_z, p.offset, p.restitution, p.friction, p.layer, p.mask, p.handle};
}

// --- time -------------------------------------------------------------------------------

Status World::step() { return impl_->step(); }

Status World::advance(float frame_seconds, FrameResult* out) {
  if (!(std::isfinite(frame_seconds) && frame_seconds >= 0.0f))
    return invalid("advance", "frame_seconds must be finite and >= 0, got " + fmt_float(frame_seconds));
  WorldImpl& w = *impl_;
  const double dt = w.desc.fixed_dt;
  w.accumulator += frame_seconds;
  FrameResult r;
  Status status;
  while (w.accumulator >= dt && r.steps < w.desc.max_steps_per_frame) {
    w.accumulator -= dt;
    ++r.steps;
    status = w.step();
    if (!status.ok()) break;
  }
  if (w.accumulator >= dt) {  // over budget: keep only the sub-step remainder
    const double drop = std::floor(w.accumulator / dt) * dt;
    w.accumulator -= drop;
    r.dropped = static_cast<float>(drop);
  }
  // Clamp after rounding to float: a remainder just below dt must not round to 1.
  w.alpha = std::clamp(static_cast<float>(w.accumulator / dt), 0.0f, std::nextafter(1.0f, 0.0f));
  r.alpha = w.alpha;
  if (out) *out = r;
  return status;
}

float World::interpolation_alpha() const { return impl_->alpha; }

Status World::interpolated_positions(std::span<Eigen::Vector3f> out) const {
  const WorldImpl& w = *impl_;
  if (!w.desc.interpolation)
    return Status(StatusCode::kUnsupported, "interpolated_positions: create the world with WorldDesc::interpolation");
  if (out.size() != w.bodies.size())
    return Status(StatusCode::kSizeMismatch, "interpolated_positions: out has " + std::to_string(out.size()) +
                                                 " entries for " + std::to_string(w.bodies.size()) + " bodies");
  const float a = w.alpha, b = 1.0f - w.alpha;
  const host::BodyStore& s = w.bodies;
  for (size_t i = 0; i < out.size(); ++i)
    out[i] = {b * s.prev_x[i] + a * s.pos_x[i], b * s.prev_y[i] + a * s.pos_y[i],
              b * s.prev_z[i] + a * s.pos_z[i]};
  return Status();
}

// --- results ----------------------------------------------------------------------------

const StepStats& World::last_step() const { return impl_->last; }

ContactArrays World::contacts() const {
  const host::ContactManifolds& c = impl_->contacts;
  const size_t m = c.manifolds, p = c.points;
  const std::span<const float> impulse = impl_->desc.solver.kind == SolverKind::kSoftStep
                                             ? impl_->soft_solver.impulses()
                                             : impl_->solver.impulses();
  ContactArrays out;
  out.a = {c.a.data(), m};
  out.b = {c.b.data(), m};
  out.b_is_plane = {c.b_is_plane.data(), m};
  out.normal_x = {c.normal[0].data(), m};
  out.normal_y = {c.normal[1].data(), m};
  out.normal_z = {c.normal[2].data(), m};
  out.depth = {c.depth.data(), m};
  out.point_count = {c.count.data(), m};
  out.first_points = {c.first_point.data(), c.first_point.empty() ? 0 : m};
  out.point_x = {c.point[0].data(), p};
  out.point_y = {c.point[1].data(), p};
  out.point_z = {c.point[2].data(), p};
  out.point_depth = {c.point_depth.data(), p};
  out.point_feature = {c.feature.data(), c.feature.empty() ? 0 : p};
  out.impulse = {impulse.data(), impulse.size() == p ? p : 0};
  return out;
}

static_assert(sizeof(BodyPair) == sizeof(kernels::Pair) && alignof(BodyPair) == alignof(kernels::Pair));

std::span<const BodyPair> World::pairs() const {
  const auto& p = impl_->pairs;
  return {reinterpret_cast<const BodyPair*>(p.data()), p.size()};
}

// --- queries -----------------------------------------------------------------------------

namespace {

template <class Queries>
Status world_query(WorldImpl& w, const Queries& q, const char* what, QueryHits* out) {
  if (out == nullptr) return Status(StatusCode::kInvalidArgument, std::string(what) + ": out must not be null");
  host::QueryBatch batch{};
  if (Status s = host::make_batch(q, what, &batch); !s.ok()) return s;
  if (Status s = w.prepare_queries(); !s.ok()) return Status(s.code(), std::string(what) + ": " + s.message());
  if (Status s = w.broad_phase.query(w.exec, batch, &out->offsets, &out->hits); !s.ok())
    return Status(s.code(), std::string(what) + ": " + s.message());
  return Status();
}

}  // namespace

Status World::query_aabbs(const AabbQueries& queries, QueryHits* out) {
  return world_query(*impl_, queries, "query_aabbs", out);
}
Status World::query_spheres(const SphereQueries& queries, QueryHits* out) {
  return world_query(*impl_, queries, "query_spheres", out);
}
Status World::query_points(const PointQueries& queries, QueryHits* out) {
  return world_query(*impl_, queries, "query_points", out);
}

uint64_t World::state_hash() const {
  // FNV-1a over the body count and the bytes of every array of the body field table
  // (host/body_store.h) that is on, in table order, each in slot order.
  uint64_t h = 1469598103934665603ull;
  auto mix = [&](const void* data, size_t bytes) {
    const auto* p = static_cast<const unsigned char*>(data);
    for (size_t i = 0; i < bytes; ++i) {
      h ^= p[i];
      h *= 1099511628211ull;
    }
  };
  const host::BodyStore& s = impl_->bodies;
  const size_t n = s.size();
  mix(&n, sizeof n);
  host::for_each_body_array(s, [&](const auto& v) { mix(v.data(), v.size() * sizeof(v[0])); });
  return h;
}

// --- settings ---------------------------------------------------------------------------

const WorldDesc& World::desc() const { return impl_->desc; }

Backend World::backend() const { return impl_->exec.backend(); }
uint32_t World::threads() const { return impl_->exec.threads(); }

Status World::set_backend(Backend backend, uint32_t threads) {
  Backend resolved;
  if (!host::resolve_backend(backend, &resolved))
    return Status(StatusCode::kUnsupported,
                  std::string("set_backend: backend '") + to_string(backend) + "' is not built into this library");
  impl_->exec = host::Executor(backend, threads);
  impl_->desc.backend = backend;
  impl_->desc.threads = threads;
  return Status();
}

Status World::set_broad_phase(BroadPhaseKind kind) {
  WorldDesc d = impl_->desc;
  d.broad_phase = kind;
  if (Status s = check_desc(d); !s.ok()) return s;
  impl_->desc = d;
  impl_->configure_broad_phase();
  return Status();
}

Status World::set_solver(const SolverDesc& solver) {
  WorldDesc d = impl_->desc;
  d.solver = solver;
  if (Status s = check_desc(d); !s.ok()) return s;
  impl_->desc = d;
  impl_->wake_all();
  return Status();
}

Status World::set_gravity(const Eigen::Vector3f& gravity) {
  if (!finite3(gravity)) return invalid("set_gravity", "gravity must be finite, got " + vec_str(gravity));
  impl_->desc.gravity = gravity;
  impl_->wake_all();
  return Status();
}

ShapeSet& World::shapes() { return impl_->shapes; }
const ShapeSet& World::shapes() const { return impl_->shapes; }

}  // namespace impact
