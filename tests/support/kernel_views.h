// Kernel-level views of the tests' box sets (tests/support/aabb_reference.h) and
// query batches (tests/support/query_reference.h), and a serial executor, for the
// tests that drive host/ and kernels/ directly.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>

#include "host/broadphase/query.h"
#include "host/parallel.h"
#include "kernels/broadphase/bounds.h"
#include "kernels/bvh/lbvh_traverse.h"
#include "kernels/common/pair.h"
#include "kernels/common/sorted_box.h"
#include "support/aabb_reference.h"
#include "support/query_reference.h"

namespace impact::test {

inline kernels::AabbSoA soa(const Boxes& b) {
  return {b.min_x.data(), b.min_y.data(), b.min_z.data(), b.max_x.data(), b.max_y.data(), b.max_z.data()};
}

/// The box set's filter, or all null when it has none.
inline kernels::PairFilter filter_of(const Boxes& b) {
  if (!b.filtered()) return {nullptr, nullptr, nullptr};
  return {b.layer.data(), b.mask.data(), b.is_static.data()};
}

inline uint32_t count(const Boxes& b) { return static_cast<uint32_t>(b.size()); }

/// The queries as the host's batch (views into q).
inline host::QueryBatch query_batch(const Queries& q) {
  auto ptr = [](const std::vector<float>& v) { return v.empty() ? nullptr : v.data(); };
  const kernels::QueryShape shape = q.shape == QShape::kAabb     ? kernels::QueryShape::kAabb
                                    : q.shape == QShape::kSphere ? kernels::QueryShape::kSphere
                                                                 : kernels::QueryShape::kPoint;
  return host::QueryBatch{kernels::QueryView{shape, ptr(q.x0), ptr(q.y0), ptr(q.z0), ptr(q.x1), ptr(q.y1),
                                             ptr(q.z1), ptr(q.radius), q.mask.empty() ? nullptr : q.mask.data()},
                          static_cast<uint32_t>(q.size())};
}

/// A one-thread serial executor shared by a test binary.
inline const host::Executor& serial() {
  static const host::Executor e(Backend::kSerial, 1);
  return e;
}

/// The view's lane arrays hold exactly its leaves' bounds, and the padding past n
/// (+inf mins, -inf maxes) overlaps nothing (kernels::LbvhLanes); its id array holds
/// the leaves' body indices.
inline void expect_lanes_mirror_leaves(const kernels::LbvhView& v) {
  if (v.n == 0) return;
  ASSERT_NE(v.ids, nullptr);
  for (uint32_t s = 0; s < v.n; ++s) ASSERT_EQ(v.ids[s], v.leaves[s].index) << "leaf " << s;
  ASSERT_NE(v.lanes, nullptr);
  ASSERT_EQ(v.lane_stride, kernels::lbvh_lane_stride(v.n));
  ASSERT_GE(v.lane_stride, static_cast<size_t>(v.n) + kernels::kLbvhCluster);
  for (size_t s = 0; s < v.lane_stride; ++s) {
    float want[6] = {__builtin_inff(), __builtin_inff(), __builtin_inff(),
                     -__builtin_inff(), -__builtin_inff(), -__builtin_inff()};
    if (s < v.n) {
      const kernels::SortedBox& l = v.leaves[s];
      const float w[6] = {l.min_x, l.min_y, l.min_z, l.max_x, l.max_y, l.max_z};
      std::copy(w, w + 6, want);
    }
    for (size_t k = 0; k < 6; ++k)
      ASSERT_EQ(v.lanes[k * v.lane_stride + s], want[k]) << "leaf " << s << " lane array " << k;
  }
}

}  // namespace impact::test
