// The pair-kernel table: the kernel, and so the route, of every (leaf type, leaf type)
// bucket (A's type <= B's), and the routes that are not a single kernel.
// Routes: a bucket with a specialised kernel (pairs/<a>/<a>_<b>.cpp) takes it; the
// polytope pairs without one (box-hull, hull-hull) take collide_sat_or_gjk_epa, which
// chooses per lane between the separating axis test and GJK + EPA
// (NarrowConfig::sat_max_vertices); half-space against half-space has none (the host
// rejects such pairs). The specialised kernels fall back to collide_gjk_epa or
// collide_support_halfspace (general/) for the lanes they leave (hulls without edge
// adjacency, hulls over their vertex limit).
#include "kernels/narrowphase/pair_kernels.h"

#include "kernels/narrowphase/general/gjk_epa.h"
#include "kernels/narrowphase/general/sat.h"

namespace impact::kernels {

void collide_sat_or_gjk_epa(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, Range r,
                            const NarrowConfig& cfg, LeafType ta, LeafType tb) {
  // kSimd and kScalar run the same per-lane code (gjk_epa.cpp, sat.cpp). A lane takes the
  // separating axis test when it applies (sat_vertex_count > 0: both hulls with edge
  // adjacency, within SAT's capacity) and is the cheaper (NarrowConfig::sat_max_vertices).
  const bool sat = cfg.sat_max_vertices > 0;
  for (uint32_t k = r.begin; k < r.end; ++k) {
    const cvx::V3 origin{a.p[0][k], a.p[1][k], a.p[2][k]};
    const cvx::Leaf A = cvx::load_leaf(a, k, ta, &cfg.hulls, origin);
    const cvx::Leaf B = cvx::load_leaf(b, k, tb, &cfg.hulls, origin);
    cvx::LaneContact c;
    const uint32_t sat_size = sat ? cvx::sat_vertex_count(A, B) : 0u;
    if (sat_size > 0 && sat_size <= cfg.sat_max_vertices)
      cvx::collide_sat_lane(A, B, &c);
    else
      cvx::collide_convex_lane(A, B, cfg, &c);
    cvx::write_lane(out, k, c, origin);
  }
}

namespace {

/// collide_sat_or_gjk_epa as the PairKernel of bucket (A, B).
template <LeafType A, LeafType B>
void sat_or_gjk_epa_pair(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, Range r,
                         const NarrowConfig& cfg) {
  collide_sat_or_gjk_epa(a, b, out, r, cfg, A, B);
}

struct Table {
  PairKernel k[kLeafTypeCount][kLeafTypeCount] = {};

  Table() {
    // pairs/sphere/
    k[kLeafSphere][kLeafSphere] = &collide_sphere_sphere;
    k[kLeafSphere][kLeafCapsule] = &collide_sphere_capsule;
    k[kLeafSphere][kLeafBox] = &collide_sphere_box;
    k[kLeafSphere][kLeafConvex] = &collide_sphere_convex;
    k[kLeafSphere][kLeafCylinder] = &collide_sphere_cylinder;
    k[kLeafSphere][kLeafEllipsoid] = &collide_sphere_ellipsoid;
    k[kLeafSphere][kLeafTriangle] = &collide_sphere_triangle;
    k[kLeafSphere][kLeafHalfSpace] = &collide_sphere_halfspace;
    // pairs/capsule/
    k[kLeafCapsule][kLeafCapsule] = &collide_capsule_capsule;
    k[kLeafCapsule][kLeafBox] = &collide_capsule_box;
    k[kLeafCapsule][kLeafConvex] = &collide_capsule_convex;
    k[kLeafCapsule][kLeafCylinder] = &collide_capsule_cylinder;
    k[kLeafCapsule][kLeafEllipsoid] = &collide_capsule_ellipsoid;
    k[kLeafCapsule][kLeafTriangle] = &collide_capsule_triangle;
    k[kLeafCapsule][kLeafHalfSpace] = &collide_capsule_halfspace;
    // pairs/box/
    k[kLeafBox][kLeafBox] = &collide_box_box;
    k[kLeafBox][kLeafConvex] = &sat_or_gjk_epa_pair<kLeafBox, kLeafConvex>;  // general route
    k[kLeafBox][kLeafCylinder] = &collide_box_cylinder;
    k[kLeafBox][kLeafEllipsoid] = &collide_box_ellipsoid;
    k[kLeafBox][kLeafTriangle] = &collide_box_triangle;
    k[kLeafBox][kLeafHalfSpace] = &collide_box_halfspace;
    // pairs/convex/
    k[kLeafConvex][kLeafConvex] = &sat_or_gjk_epa_pair<kLeafConvex, kLeafConvex>;  // general route
    k[kLeafConvex][kLeafCylinder] = &collide_convex_cylinder;
    k[kLeafConvex][kLeafEllipsoid] = &collide_convex_ellipsoid;
    k[kLeafConvex][kLeafTriangle] = &collide_convex_triangle;
    k[kLeafConvex][kLeafHalfSpace] = &collide_convex_halfspace;
    // pairs/cylinder/
    k[kLeafCylinder][kLeafCylinder] = &collide_cylinder_cylinder;
    k[kLeafCylinder][kLeafEllipsoid] = &collide_cylinder_ellipsoid;
    k[kLeafCylinder][kLeafTriangle] = &collide_cylinder_triangle;
    k[kLeafCylinder][kLeafHalfSpace] = &collide_cylinder_halfspace;
    // pairs/ellipsoid/
    k[kLeafEllipsoid][kLeafEllipsoid] = &collide_ellipsoid_ellipsoid;
    k[kLeafEllipsoid][kLeafTriangle] = &collide_ellipsoid_triangle;
    k[kLeafEllipsoid][kLeafHalfSpace] = &collide_ellipsoid_halfspace;
    // pairs/triangle/
    k[kLeafTriangle][kLeafTriangle] = &collide_triangle_triangle;
    k[kLeafTriangle][kLeafHalfSpace] = &collide_triangle_halfspace;
    // k[kLeafHalfSpace][kLeafHalfSpace] stays null.
  }
};

const Table& table() {
  static const Table t;
  return t;
}

}  // namespace

PairKernel pair_kernel(LeafType ta, LeafType tb) {
  if (ta >= kLeafTypeCount || tb >= kLeafTypeCount || ta > tb) return nullptr;
  return table().k[ta][tb];
}

}  // namespace impact::kernels
