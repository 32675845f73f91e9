// host::BodyStore: a World's bodies in dense slots, one array per field, and the body
// field table (kBodyFields) that lists every array once. Adding, removing, re-sorting,
// reserving, reading back (World::bodies()) and the state hash all walk the table, so a
// new field is one line of it and one member.
//
// Field sets: an array is either as long as the store (its set is on) or empty. kCore
// fields are always on; kInterpolation ones with WorldDesc::interpolation; kShaped
// (the shape index) from the first body with a shape; kRigid (angular velocity,
// inertia, centre of mass) from the first body that can rotate; kOriented (the
// orientation) with either of those two; kDamping from the first body with damping or
// a gravity scale; kForces (the accumulators of World::apply_forces) from its first
// call. A world of frictionless plain spheres never touches the optional sets.
// Cost: every table walk is one pass per array; nothing else is per field.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <tuple>

#include "host/buffer.h"
#include "impact/types.h"
#include "impact/world.h"

namespace impact::host {

/// Shape index of a plain sphere body (BodyArrays::kSphereBody).
inline constexpr uint32_t kNoShape = 0xffffffffu;

enum class FieldSet : uint8_t { kCore, kInterpolation, kShaped, kOriented, kRigid, kDamping, kForces, kCount };

/// One body's value of every field: what append() stores, and the defaults a field set
/// fills in for the bodies that exist when it is switched on.
struct BodyRow {
  float pos_x = 0, pos_y = 0, pos_z = 0;
  float vel_x = 0, vel_y = 0, vel_z = 0;
  float inv_mass = 0, radius = 0, restitution = 0;
  uint32_t layer = 0, mask = 0;
  uint8_t is_static = 0;
  uint8_t fixed_rotation = 0;
  float prev_x = 0, prev_y = 0, prev_z = 0;
  uint32_t shape = kNoShape;
  float qx = 0, qy = 0, qz = 0, qw = 1;
  float friction = 0, rolling = 0;
  float wx = 0, wy = 0, wz = 0;
  float iix = 0, iiy = 0, iiz = 0;
  float pqx = 0, pqy = 0, pqz = 0, pqw = 1;
  float cx = 0, cy = 0, cz = 0;
  float linear_damping = 0, angular_damping = 0, gravity_scale = 1;
  float fx = 0, fy = 0, fz = 0, tx = 0, ty = 0, tz = 0;
  float sleep_time = 0;
  uint8_t asleep = 0;
  BodyHandle handle;
};

struct BodyStore {
  Buffer<float> pos_x, pos_y, pos_z;
  Buffer<float> vel_x, vel_y, vel_z;
  Buffer<float> inv_mass, radius, restitution;
  Buffer<uint32_t> layer, mask;
  Buffer<uint8_t> is_static;
  Buffer<uint8_t> fixed_rotation;        ///< 1: never rotated by contacts or torques
  Buffer<float> prev_x, prev_y, prev_z;  ///< positions at the last step's start (kInterpolation)
  Buffer<uint32_t> shape;                ///< World::shapes() index, or kNoShape (kShaped)
  Buffer<float> qx, qy, qz, qw;          ///< unit orientation of the shape frame (kOriented)
  Buffer<float> friction;                ///< Coulomb coefficient
  Buffer<float> rolling;                 ///< rolling resistance
  Buffer<float> wx, wy, wz;              ///< angular velocity, rad/s, world (kRigid)
  Buffer<float> iix, iiy, iiz;           ///< inverse principal inertia, 1/(kg m^2) (kRigid)
  Buffer<float> pqx, pqy, pqz, pqw;      ///< principal axes in the shape frame (kRigid)
  Buffer<float> cx, cy, cz;              ///< centre of mass in the shape frame, m (kRigid)
  Buffer<float> linear_damping, angular_damping, gravity_scale;  ///< (kDamping)
  Buffer<float> fx, fy, fz, tx, ty, tz;  ///< force (N) and torque (N m) for the next step (kForces)
  Buffer<float> sleep_time;              ///< s the body has been slower than SolverDesc::sleep_speed
  Buffer<uint8_t> asleep;                ///< 1: asleep (host/pipeline/sleep_stage.cpp)
  Buffer<BodyHandle> handle;             ///< slot -> handle

  size_t size() const { return handle.size(); }
  bool on(FieldSet set) const { return on_[static_cast<int>(set)]; }
  /// Switches a field set on, giving the bodies that exist BodyRow's defaults.
  void enable(FieldSet set);
  /// Appends one body (the fields of the sets that are on).
  void append(const BodyRow& row);
  /// Moves the last slot's body into `slot` and shrinks by one.
  void swap_remove(uint32_t slot);
  void reserve(size_t n);

 private:
  bool on_[static_cast<int>(FieldSet::kCount)] = {true, false, false, false, false, false, false};
};

/// One row of the body field table: its name, array, value in BodyRow, span in the
/// public BodyArrays (null: not read back) and field set.
template <class T>
struct BodyField {
  const char* name;
  Buffer<T> BodyStore::*array;
  T BodyRow::*value;
  std::span<const T> BodyArrays::*view;
  FieldSet set;
};

/// The body field table: every array of BodyStore, once.
inline constexpr auto kBodyFields = std::tuple{
    BodyField<float>{"pos_x", &BodyStore::pos_x, &BodyRow::pos_x, &BodyArrays::pos_x, FieldSet::kCore},
    BodyField<float>{"pos_y", &BodyStore::pos_y, &BodyRow::pos_y, &BodyArrays::pos_y, FieldSet::kCore},
    BodyField<float>{"pos_z", &BodyStore::pos_z, &BodyRow::pos_z, &BodyArrays::pos_z, FieldSet::kCore},
    BodyField<float>{"vel_x", &BodyStore::vel_x, &BodyRow::vel_x, &BodyArrays::vel_x, FieldSet::kCore},
    BodyField<float>{"vel_y", &BodyStore::vel_y, &BodyRow::vel_y, &BodyArrays::vel_y, FieldSet::kCore},
    BodyField<float>{"vel_z", &BodyStore::vel_z, &BodyRow::vel_z, &BodyArrays::vel_z, FieldSet::kCore},
    BodyField<float>{"inv_mass", &BodyStore::inv_mass, &BodyRow::inv_mass, &BodyArrays::inv_mass, FieldSet::kCore},
    BodyField<float>{"radius", &BodyStore::radius, &BodyRow::radius, &BodyArrays::radius, FieldSet::kCore},
    BodyField<float>{"restitution", &BodyStore::restitution, &BodyRow::restitution, &BodyArrays::restitution,
                     FieldSet::kCore},
    BodyField<uint32_t>{"layer", &BodyStore::layer, &BodyRow::layer, &BodyArrays::layer, FieldSet::kCore},
    BodyField<uint32_t>{"mask", &BodyStore::mask, &BodyRow::mask, &BodyArrays::mask, FieldSet::kCore},
    BodyField<uint8_t>{"is_static", &BodyStore::is_static, &BodyRow::is_static, nullptr, FieldSet::kCore},
    BodyField<uint8_t>{"fixed_rotation", &BodyStore::fixed_rotation, &BodyRow::fixed_rotation, nullptr,
                       FieldSet::kCore},
    BodyField<float>{"prev_x", &BodyStore::prev_x, &BodyRow::prev_x, nullptr, FieldSet::kInterpolation},
    BodyField<float>{"prev_y", &BodyStore::prev_y, &BodyRow::prev_y, nullptr, FieldSet::kInterpolation},
    BodyField<float>{"prev_z", &BodyStore::prev_z, &BodyRow::prev_z, nullptr, FieldSet::kInterpolation},
    BodyField<uint32_t>{"shape", &BodyStore::shape, &BodyRow::shape, &BodyArrays::shape, FieldSet::kShaped},
    BodyField<float>{"qx", &BodyStore::qx, &BodyRow::qx, &BodyArrays::qx, FieldSet::kOriented},
    BodyField<float>{"qy", &BodyStore::qy, &BodyRow::qy, &BodyArrays::qy, FieldSet::kOriented},
    BodyField<float>{"qz", &BodyStore::qz, &BodyRow::qz, &BodyArrays::qz, FieldSet::kOriented},
    BodyField<float>{"qw", &BodyStore::qw, &BodyRow::qw, &BodyArrays::qw, FieldSet::kOriented},
    BodyField<float>{"friction", &BodyStore::friction, &BodyRow::friction, &BodyArrays::friction, FieldSet::kCore},
    BodyField<float>{"rolling", &BodyStore::rolling, &BodyRow::rolling, &BodyArrays::rolling_resistance,
                     FieldSet::kCore},
    BodyField<float>{"wx", &BodyStore::wx, &BodyRow::wx, &BodyArrays::wx, FieldSet::kRigid},
    BodyField<float>{"wy", &BodyStore::wy, &BodyRow::wy, &BodyArrays::wy, FieldSet::kRigid},
    BodyField<float>{"wz", &BodyStore::wz, &BodyRow::wz, &BodyArrays::wz, FieldSet::kRigid},
    BodyField<float>{"iix", &BodyStore::iix, &BodyRow::iix, nullptr, FieldSet::kRigid},
    BodyField<float>{"iiy", &BodyStore::iiy, &BodyRow::iiy, nullptr, FieldSet::kRigid},
    BodyField<float>{"iiz", &BodyStore::iiz, &BodyRow::iiz, nullptr, FieldSet::kRigid},
    BodyField<float>{"pqx", &BodyStore::pqx, &BodyRow::pqx, nullptr, FieldSet::kRigid},
    BodyField<float>{"pqy", &BodyStore::pqy, &BodyRow::pqy, nullptr, FieldSet::kRigid},
    BodyField<float>{"pqz", &BodyStore::pqz, &BodyRow::pqz, nullptr, FieldSet::kRigid},
    BodyField<float>{"pqw", &BodyStore::pqw, &BodyRow::pqw, nullptr, FieldSet::kRigid},
    BodyField<float>{"cx", &BodyStore::cx, &BodyRow::cx, nullptr, FieldSet::kRigid},
    BodyField<float>{"cy", &BodyStore::cy, &BodyRow::cy, nullptr, FieldSet::kRigid},
    BodyField<float>{"cz", &BodyStore::cz, &BodyRow::cz, nullptr, FieldSet::kRigid},
    BodyField<float>{"linear_damping", &BodyStore::linear_damping, &BodyRow::linear_damping, nullptr,
                     FieldSet::kDamping},
    BodyField<float>{"angular_damping", &BodyStore::angular_damping, &BodyRow::angular_damping, nullptr,
                     FieldSet::kDamping},
    BodyField<float>{"gravity_scale", &BodyStore::gravity_scale, &BodyRow::gravity_scale, nullptr,
                     FieldSet::kDamping},
    BodyField<float>{"fx", &BodyStore::fx, &BodyRow::fx, nullptr, FieldSet::kForces},
    BodyField<float>{"fy", &BodyStore::fy, &BodyRow::fy, nullptr, FieldSet::kForces},
    BodyField<float>{"fz", &BodyStore::fz, &BodyRow::fz, nullptr, FieldSet::kForces},
    BodyField<float>{"tx", &BodyStore::tx, &BodyRow::tx, nullptr, FieldSet::kForces},
    BodyField<float>{"ty", &BodyStore::ty, &BodyRow::ty, nullptr, FieldSet::kForces},
    BodyField<float>{"tz", &BodyStore::tz, &BodyRow::tz, nullptr, FieldSet::kForces},
    BodyField<float>{"sleep_time", &BodyStore::sleep_time, &BodyRow::sleep_time, nullptr, FieldSet::kCore},
    BodyField<uint8_t>{"asleep", &BodyStore::asleep, &BodyRow::asleep, &BodyArrays::asleep, FieldSet::kCore},
    BodyField<BodyHandle>{"handle", &BodyStore::handle, &BodyRow::handle, &BodyArrays::handles, FieldSet::kCore},
};

/// fn(field) for every row of kBodyFields, in table order.
template <class Fn>
void for_each_body_field(Fn&& fn) {
  std::apply([&](const auto&... field) { (fn(field), ...); }, kBodyFields);
}

/// fn(array) for every array of s that is on (non-empty or its set enabled), in table order.
template <class Store, class Fn>
void for_each_body_array(Store& s, Fn&& fn) {
  for_each_body_field([&](const auto& f) {
    if (s.on(f.set)) fn(s.*f.array);
  });
}

inline void BodyStore::enable(FieldSet set) {
  if (on(set)) return;
  if (set == FieldSet::kShaped || set == FieldSet::kRigid) enable(FieldSet::kOriented);
  const BodyRow defaults;
  const size_t n = size();
  for_each_body_field([&](const auto& f) {
    if (f.set == set) (this->*f.array).assign(n, defaults.*f.value);
  });
  on_[static_cast<int>(set)] = true;
}

inline void BodyStore::append(const BodyRow& row) {
  for_each_body_field([&](const auto& f) {
    if (on(f.set)) (this->*f.array).push_back(row.*f.value);
  });
}

inline void BodyStore::swap_remove(uint32_t slot) {
  const size_t last = size() - 1;
  for_each_body_array(*this, [&](auto& v) {
    v[slot] = v[last];
    v.pop_back();
  });
}

inline void BodyStore::reserve(size_t n) {
  for_each_body_array(*this, [&](auto& v) { v.reserve(n); });
}

/// The public read-back view of s (World::bodies()).
inline BodyArrays body_arrays(const BodyStore& s) {
  BodyArrays out;
  for_each_body_field([&](const auto& f) {
    if (f.view != nullptr) {
      const auto& v = s.*f.array;
      out.*f.view = {v.data(), v.size()};
    }
  });
  return out;
}

}  // namespace impact::host
