// The separating axis test for pairs of polytopes (box, convex hull), one lane at a
// time, behind collide_sat_or_gjk_epa (kernels/narrowphase/pair_kernels.cpp). See sat.cpp.
#pragma once

#include <cstdint>

#include "kernels/narrowphase/general/lane_contact.h"
#include "kernels/narrowphase/general/support.h"

namespace impact::kernels::cvx {

/// Size of (A, B) for the dispatch between SAT and GJK/EPA: the two vertex counts
/// summed (a box has 8), or 0 when SAT does not apply (a side is not a box / hull, or
/// a hull has no edge adjacency or exceeds SAT's stack capacity: 512 vertices, 1024
/// faces, 1536 edges).
uint32_t sat_vertex_count(const Leaf& A, const Leaf& B);

/// Statistics of one SAT lane, for tests and benchmarks.
struct SatStats {
  uint32_t edges_a = 0, edges_b = 0;  // edges left after the cone bound (candidates)
  uint32_t gauss_hits = 0;            // edge pairs that form a Minkowski face
  int feature = -1;                   // 0: face of A, 1: face of B, 2: edge pair; -1: separated
};

/// Collision data of two polytopes (sat_vertex_count(A, B) > 0) by the separating axis
/// test, with the manifold of contact_manifold: the same contract as
/// collide_convex_lane. stats may be null.
void collide_sat_lane(const Leaf& A, const Leaf& B, LaneContact* out, SatStats* stats = nullptr);

/// The general route of collide_sat_lane (both sides as vertex / face / edge lists),
/// which collide_sat_lane leaves only for box A against hull B: kept callable for the
/// tests and benchmarks that compare the two.
void collide_sat_general_lane(const Leaf& A, const Leaf& B, LaneContact* out, SatStats* stats = nullptr);

}  // namespace impact::kernels::cvx
