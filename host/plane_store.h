// host::PlaneStore: a World's static planes (half-spaces { x : n.x <= offset }, unit
// normals) in dense slots, one array per field; slot i is the plane index contacts and
// PlaneArrays use.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "impact/types.h"
#include "kernels/common/body_views.h"

namespace impact::host {

struct PlaneStore {
  std::vector<float> normal_x, normal_y, normal_z, offset, restitution, friction;
  std::vector<uint32_t> layer, mask;
  std::vector<PlaneHandle> handle;
  size_t size() const { return handle.size(); }
  kernels::PlaneView view() const {
    return {normal_x.data(), normal_y.data(), normal_z.data(), offset.data(),
            layer.data(),    mask.data(),     static_cast<uint32_t>(size())};
  }
};

}  // namespace impact::host
