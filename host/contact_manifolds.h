// host::ContactManifolds: the storage behind kernels::ContactManifoldArrays, the one
// contact layout of the library (kernels/common/contact_manifolds.h has the fields'
// meaning). The narrow phase resizes and fills it; the solver and World::contacts()
// read it. Buffers keep their capacity across steps, so a steady scene allocates
// nothing. Three arrays may be left empty (their view pointer null): first_point when
// every manifold has one point, child_a / child_b and feature for a plain run (no
// children, every feature its slot): the sphere buckets write neither.
#pragma once

#include <cstddef>
#include <cstdint>

#include "host/buffer.h"
#include "kernels/common/contact_manifolds.h"

namespace impact::host {

struct ContactManifolds {
  Buffer<uint32_t> pair, a, b, child_a, child_b, first_point, feature;
  Buffer<uint8_t> b_is_plane, count;
  Buffer<float> normal[3], depth, point[3], point_depth;
  size_t manifolds = 0;
  size_t points = 0;

  /// Room for m manifolds and p points (contents of earlier steps are not kept
  /// meaningful). one_point: every manifold has exactly one point (p == m) and
  /// first_point stays empty; plain: child_a, child_b and feature stay empty.
  void resize(size_t m, size_t p, bool one_point, bool plain) {
    for (auto* v : {&pair, &a, &b}) v->resize(m);
    child_a.resize(plain ? 0 : m);
    child_b.resize(plain ? 0 : m);
    b_is_plane.resize(m);
    count.resize(m);
    for (auto& v : normal) v.resize(m);
    depth.resize(m);
    first_point.resize(one_point ? 0 : m);
    for (auto& v : point) v.resize(p);
    point_depth.resize(p);
    feature.resize(plain ? 0 : p);
    manifolds = m;
    points = p;
  }
  void clear() { resize(0, 0, true, true); }

  kernels::ContactManifoldArrays view() {
    return {pair.data(),
            a.data(),
            b.data(),
            b_is_plane.data(),
            child_a.empty() ? nullptr : child_a.data(),
            child_b.empty() ? nullptr : child_b.data(),
            {normal[0].data(), normal[1].data(), normal[2].data()},
            depth.data(),
            count.data(),
            first_point.empty() ? nullptr : first_point.data(),
            {point[0].data(), point[1].data(), point[2].data()},
            point_depth.data(),
            feature.empty() ? nullptr : feature.data()};
  }
  kernels::ContactManifoldArrays view() const { return const_cast<ContactManifolds*>(this)->view(); }
};

}  // namespace impact::host
