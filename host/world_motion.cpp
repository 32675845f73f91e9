// impact::World, the calls that turn bodies: angular velocity and orientation read and
// write, forces and torques for the next step, impulses now. Each batched call checks
// its whole input first (host/world_checks.h), then writes; the first call that can
// make a body rotate switches the rigid field set on (WorldImpl::enable_rigid).
// Cost: O(batch) plus, once per world, O(bodies) to give the existing bodies inertia.
#include <string>
#include <vector>

#include "host/shapes/pose.h"
#include "host/world_checks.h"
#include "impact/world.h"

namespace impact {
namespace {

using host::BodyStore;
using host::FieldSet;

std::string body_who(const char* call, size_t i) { return std::string(call) + ": body " + std::to_string(i); }

Status check_sizes(const char* call, size_t handles, size_t values) {
  if (handles == values) return Status();
  return Status(StatusCode::kSizeMismatch, std::string(call) + ": handles and values differ in length (" +
                                               std::to_string(handles) + " vs " + std::to_string(values) + ")");
}

Status check_finite(const char* call, const char* field, std::span<const Eigen::Vector3f> values) {
  for (size_t i = 0; i < values.size(); ++i)
    if (!host::finite3(values[i]))
      return host::invalid(body_who(call, i), std::string(field) + " must be finite, got " + host::vec_str(values[i]));
  return Status();
}

Eigen::Quaternionf orientation(const BodyStore& s, uint32_t k) {
  if (!s.on(FieldSet::kOriented)) return Eigen::Quaternionf::Identity();
  return Eigen::Quaternionf(s.qw[k], s.qx[k], s.qy[k], s.qz[k]);
}

// Centre of mass of slot k, world frame (kRigid on).
Eigen::Vector3f centre_of_mass(const BodyStore& s, uint32_t k) {
  return Eigen::Vector3f(s.pos_x[k], s.pos_y[k], s.pos_z[k]) +
         orientation(s, k) * Eigen::Vector3f(s.cx[k], s.cy[k], s.cz[k]);
}

// World inverse inertia R diag(ii) R^T, R the principal frame's rotation (kRigid on).
Eigen::Matrix3f inverse_inertia(const BodyStore& s, uint32_t k) {
  const Eigen::Matrix3f r =
      (orientation(s, k) * Eigen::Quaternionf(s.pqw[k], s.pqx[k], s.pqy[k], s.pqz[k])).toRotationMatrix();
  return r * Eigen::Vector3f(s.iix[k], s.iiy[k], s.iiz[k]).asDiagonal() * r.transpose();
}

// Adds force f (at point p when given, else at the centre of mass) and torque t to the
// accumulators of slot k; bodies that do not move dynamically ignore them.
void accumulate(BodyStore& s, uint32_t k, const Eigen::Vector3f& f, const Eigen::Vector3f* p, Eigen::Vector3f t) {
  if (!(s.inv_mass[k] > 0.0f)) return;
  if (p != nullptr) t += (*p - centre_of_mass(s, k)).cross(f);
  s.fx[k] += f.x();
  s.fy[k] += f.y();
  s.fz[k] += f.z();
  s.tx[k] += t.x();
  s.ty[k] += t.y();
  s.tz[k] += t.z();
}

}  // namespace

Status World::set_angular_velocities(std::span<const BodyHandle> handles, std::span<const Eigen::Vector3f> values) {
  const char* call = "set_angular_velocities";
  if (Status s = check_sizes(call, handles.size(), values.size()); !s.ok()) return s;
  std::vector<uint32_t> slots;
  if (Status s = host::resolve_bodies(*impl_, handles, call, &slots); !s.ok()) return s;
  if (Status s = check_finite(call, "angular velocity", values); !s.ok()) return s;
  BodyStore& b = impl_->bodies;
  for (size_t i = 0; i < values.size(); ++i)
    if (b.fixed_rotation[slots[i]] && values[i] != Eigen::Vector3f::Zero())
      return host::invalid(body_who(call, i), "has fixed_rotation; its angular velocity must stay zero, got " +
                                                  host::vec_str(values[i]));
  impl_->wake(slots);
  bool any = false;
  for (const Eigen::Vector3f& w : values) any = any || w != Eigen::Vector3f::Zero();
  if (!any && !b.on(FieldSet::kRigid)) return Status();  // zero is what every body has
  impl_->enable_rigid();
  for (size_t i = 0; i < values.size(); ++i) {
    b.wx[slots[i]] = values[i].x();
    b.wy[slots[i]] = values[i].y();
    b.wz[slots[i]] = values[i].z();
  }
  return Status();
}

Status World::get_angular_velocities(std::span<const BodyHandle> handles, std::span<Eigen::Vector3f> out) const {
  const char* call = "get_angular_velocities";
  if (Status s = check_sizes(call, handles.size(), out.size()); !s.ok()) return s;
  std::vector<uint32_t> slots;
  if (Status s = host::resolve_bodies(*impl_, handles, call, &slots); !s.ok()) return s;
  const BodyStore& b = impl_->bodies;
  const bool on = b.on(FieldSet::kRigid);
  for (size_t i = 0; i < out.size(); ++i)
    out[i] = on ? Eigen::Vector3f(b.wx[slots[i]], b.wy[slots[i]], b.wz[slots[i]]) : Eigen::Vector3f::Zero();
  return Status();
}

Status World::set_orientations(std::span<const BodyHandle> handles, std::span<const Eigen::Quaternionf> values) {
  const char* call = "set_orientations";
  if (Status s = check_sizes(call, handles.size(), values.size()); !s.ok()) return s;
  std::vector<uint32_t> slots;
  if (Status s = host::resolve_bodies(*impl_, handles, call, &slots); !s.ok()) return s;
  for (size_t i = 0; i < values.size(); ++i) {
    Pose pose;
    pose.orientation = values[i];
    if (!host::pose_ok(pose)) return host::check_pose(pose, body_who(call, i).c_str());
  }
  BodyStore& b = impl_->bodies;
  b.enable(FieldSet::kOriented);
  impl_->positions_changed();
  impl_->wake(slots);
  for (size_t i = 0; i < values.size(); ++i) {
    const Eigen::Quaternionf q = values[i].normalized();
    b.qx[slots[i]] = q.x();
    b.qy[slots[i]] = q.y();
    b.qz[slots[i]] = q.z();
    b.qw[slots[i]] = q.w();
  }
  return Status();
}

Status World::get_orientations(std::span<const BodyHandle> handles, std::span<Eigen::Quaternionf> out) const {
  const char* call = "get_orientations";
  if (Status s = check_sizes(call, handles.size(), out.size()); !s.ok()) return s;
  std::vector<uint32_t> slots;
  if (Status s = host::resolve_bodies(*impl_, handles, call, &slots); !s.ok()) return s;
  for (size_t i = 0; i < out.size(); ++i) out[i] = orientation(impl_->bodies, slots[i]);
  return Status();
}

Status World::apply_forces(std::span<const BodyHandle> handles, std::span<const Eigen::Vector3f> forces) {
  const char* call = "apply_forces";
  if (Status s = check_sizes(call, handles.size(), forces.size()); !s.ok()) return s;
  std::vector<uint32_t> slots;
  if (Status s = host::resolve_bodies(*impl_, handles, call, &slots); !s.ok()) return s;
  if (Status s = check_finite(call, "force", forces); !s.ok()) return s;
  impl_->enable_rigid();
  impl_->bodies.enable(FieldSet::kForces);
  impl_->wake(slots);
  for (size_t i = 0; i < forces.size(); ++i)
    accumulate(impl_->bodies, slots[i], forces[i], nullptr, Eigen::Vector3f::Zero());
  return Status();
}

Status World::apply_forces_at(std::span<const BodyHandle> handles, std::span<const Eigen::Vector3f> forces,
                              std::span<const Eigen::Vector3f> points) {
  const char* call = "apply_forces_at";
  if (Status s = check_sizes(call, handles.size(), forces.size()); !s.ok()) return s;
  if (Status s = check_sizes(call, handles.size(), points.size()); !s.ok()) return s;
  std::vector<uint32_t> slots;
  if (Status s = host::resolve_bodies(*impl_, handles, call, &slots); !s.ok()) return s;
  if (Status s = check_finite(call, "force", forces); !s.ok()) return s;
  for (size_t i = 0; i < points.size(); ++i)
    if (Status s = host::check_position(body_who(call, i) + " point", points[i]); !s.ok()) return s;
  impl_->enable_rigid();
  impl_->bodies.enable(FieldSet::kForces);
  impl_->wake(slots);
  for (size_t i = 0; i < forces.size(); ++i)
    accumulate(impl_->bodies, slots[i], forces[i], &points[i], Eigen::Vector3f::Zero());
  return Status();
}

Status World::apply_torques(std::span<const BodyHandle> handles, std::span<const Eigen::Vector3f> torques) {
  const char* call = "apply_torques";
  if (Status s = check_sizes(call, handles.size(), torques.size()); !s.ok()) return s;
  std::vector<uint32_t> slots;
  if (Status s = host::resolve_bodies(*impl_, handles, call, &slots); !s.ok()) return s;
  if (Status s = check_finite(call, "torque", torques); !s.ok()) return s;
  impl_->enable_rigid();
  impl_->bodies.enable(FieldSet::kForces);
  impl_->wake(slots);
  for (size_t i = 0; i < torques.size(); ++i)
    accumulate(impl_->bodies, slots[i], Eigen::Vector3f::Zero(), nullptr, torques[i]);
  return Status();
}

Status World::apply_impulses(std::span<const BodyHandle> handles, std::span<const Eigen::Vector3f> impulses,
                             std::span<const Eigen::Vector3f> points) {
  const char* call = "apply_impulses";
  if (Status s = check_sizes(call, handles.size(), impulses.size()); !s.ok()) return s;
  if (Status s = check_sizes(call, handles.size(), points.size()); !s.ok()) return s;
  std::vector<uint32_t> slots;
  if (Status s = host::resolve_bodies(*impl_, handles, call, &slots); !s.ok()) return s;
  if (Status s = check_finite(call, "impulse", impulses); !s.ok()) return s;
  for (size_t i = 0; i < points.size(); ++i)
    if (Status s = host::check_position(body_who(call, i) + " point", points[i]); !s.ok()) return s;
  impl_->enable_rigid();
  impl_->wake(slots);
  BodyStore& b = impl_->bodies;
  for (size_t i = 0; i < impulses.size(); ++i) {
    const uint32_t k = slots[i];
    const float m = b.inv_mass[k];
    if (!(m > 0.0f)) continue;  // static and kinematic bodies are not pushed
    const Eigen::Vector3f& j = impulses[i];
    const Eigen::Vector3f dw = inverse_inertia(b, k) * (points[i] - centre_of_mass(b, k)).cross(j);
    b.vel_x[k] += m * j.x();
    b.vel_y[k] += m * j.y();
    b.vel_z[k] += m * j.z();
    b.wx[k] += dw.x();
    b.wy[k] += dw.y();
    b.wz[k] += dw.z();
  }
  return Status();
}

Status World::wake_bodies(std::span<const BodyHandle> handles) {
  std::vector<uint32_t> slots;
  if (Status s = host::resolve_bodies(*impl_, handles, "wake_bodies", &slots); !s.ok()) return s;
  impl_->wake(slots);
  return Status();
}

}  // namespace impact
