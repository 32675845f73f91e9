// Validation vocabulary of the World API (host/world.cpp, host/world_motion.cpp):
// error messages that name the call, the body and the field, and the handle lookup
// every batched call starts with. A call checks its whole input with these before it
// writes anything.
#pragma once

#include <cmath>
#include <cstdio>
#include <span>
#include <string>
#include <vector>

#include "host/world_impl.h"

namespace impact::host {

/// Position magnitudes beyond this overflow box arithmetic (p +- r, extents) in float.
inline constexpr float kMaxCoordinate = 1e18f;

inline std::string fmt_float(float v) {
  char buf[48];
  std::snprintf(buf, sizeof buf, "%.9g", static_cast<double>(v));
  return buf;
}

inline Status invalid(const std::string& where, const std::string& what) {
  return Status(StatusCode::kInvalidArgument, where + ": " + what);
}

inline bool finite3(const Eigen::Vector3f& v) {
  return std::isfinite(v.x()) && std::isfinite(v.y()) && std::isfinite(v.z());
}

inline std::string vec_str(const Eigen::Vector3f& v) {
  return "(" + fmt_float(v.x()) + ", " + fmt_float(v.y()) + ", " + fmt_float(v.z()) + ")";
}

inline std::string handle_str(BodyHandle h) {
  return "{index " + std::to_string(h.index) + ", generation " + std::to_string(h.generation) + "}";
}

inline Status check_position(const std::string& who, const Eigen::Vector3f& p) {
  if (!finite3(p)) return invalid(who, "position must be finite, got " + vec_str(p));
  if (p.cwiseAbs().maxCoeff() > kMaxCoordinate)
    return invalid(who, "position magnitude must be <= 1e18 m, got " + vec_str(p));
  return Status();
}

inline Status check_velocity(const std::string& who, const Eigen::Vector3f& v) {
  if (!finite3(v)) return invalid(who, "velocity must be finite, got " + vec_str(v));
  return Status();
}

/// Resolves every handle to a slot, or reports the first bad one (kStaleHandle).
inline Status resolve_bodies(const WorldImpl& w, std::span<const BodyHandle> handles, const char* where,
                             std::vector<uint32_t>* slots) {
  slots->resize(handles.size());
  for (size_t i = 0; i < handles.size(); ++i) {
    const uint32_t slot = w.body_handles.lookup(handles[i].index, handles[i].generation);
    if (slot == HandleTable::kNoSlot)
      return Status(StatusCode::kStaleHandle, std::string(where) + ": body " + std::to_string(i) + " handle " +
                                                  handle_str(handles[i]) +
                                                  (handles[i].is_null() ? " is null" : " is stale or invalid"));
    (*slots)[i] = slot;
  }
  return Status();
}

}  // namespace impact::host
