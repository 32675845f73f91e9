#include "kernels/narrowphase/pair_kernels.h"

#include <utility>

namespace impact::kernels {

namespace {

template <LeafType A, LeafType B>
void generic_pair(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, Range r,
                  const NarrowConfig& cfg) {
  if constexpr (B == kLeafHalfSpace) {
    collide_support_halfspace(a, b, out, r, cfg, A);
  } else {
    collide_gjk_epa(a, b, out, r, cfg, A, B);
  }
}

struct Table {
  PairKernel k[kLeafTypeCount][kLeafTypeCount] = {};

  template <uint8_t A, uint8_t B>
  constexpr void fill_one() {
    if constexpr (A <= B && !(A == kLeafHalfSpace && B == kLeafHalfSpace)) {
      k[A][B] = &generic_pair<static_cast<LeafType>(A), static_cast<LeafType>(B)>;
    }
  }
  template <uint8_t A, uint8_t... Bs>
  constexpr void fill_row(std::integer_sequence<uint8_t, Bs...>) {
    (fill_one<A, Bs>(), ...);
  }
  template <uint8_t... As>
  constexpr void fill(std::integer_sequence<uint8_t, As...> seq) {
    (fill_row<As>(seq), ...);
  }

  Table() {
    fill(std::make_integer_sequence<uint8_t, kLeafTypeCount>{});
    // Specialised kernels replace the general path where they exist.
    k[kLeafSphere][kLeafSphere] = &collide_sphere_sphere;
    k[kLeafSphere][kLeafCapsule] = &collide_sphere_capsule;
    k[kLeafSphere][kLeafBox] = &collide_sphere_box;
    k[kLeafSphere][kLeafCylinder] = &collide_sphere_cylinder;
    k[kLeafCapsule][kLeafCapsule] = &collide_capsule_capsule;
    k[kLeafCapsule][kLeafBox] = &collide_capsule_box;
    k[kLeafBox][kLeafBox] = &collide_box_box;
    k[kLeafSphere][kLeafTriangle] = &collide_sphere_triangle;
    k[kLeafCapsule][kLeafTriangle] = &collide_capsule_triangle;
    k[kLeafBox][kLeafTriangle] = &collide_box_triangle;
    k[kLeafTriangle][kLeafTriangle] = &collide_triangle_triangle;
    k[kLeafSphere][kLeafHalfSpace] = &collide_sphere_halfspace;
    k[kLeafCapsule][kLeafHalfSpace] = &collide_capsule_halfspace;
    k[kLeafBox][kLeafHalfSpace] = &collide_box_halfspace;
    k[kLeafCylinder][kLeafHalfSpace] = &collide_cylinder_halfspace;
    k[kLeafEllipsoid][kLeafHalfSpace] = &collide_ellipsoid_halfspace;
    k[kLeafTriangle][kLeafHalfSpace] = &collide_triangle_halfspace;
    k[kLeafSphere][kLeafConvex] = &collide_sphere_convex;
    k[kLeafCapsule][kLeafConvex] = &collide_capsule_convex;
    k[kLeafConvex][kLeafTriangle] = &collide_convex_triangle;
    k[kLeafSphere][kLeafEllipsoid] = &collide_sphere_ellipsoid;
    k[kLeafCapsule][kLeafEllipsoid] = &collide_capsule_ellipsoid;
    k[kLeafEllipsoid][kLeafTriangle] = &collide_ellipsoid_triangle;
    k[kLeafCapsule][kLeafCylinder] = &collide_capsule_cylinder;
    k[kLeafBox][kLeafEllipsoid] = &collide_box_ellipsoid;
    k[kLeafBox][kLeafCylinder] = &collide_box_cylinder;
    k[kLeafCylinder][kLeafCylinder] = &collide_cylinder_cylinder;
    k[kLeafConvex][kLeafEllipsoid] = &collide_convex_ellipsoid;
    k[kLeafConvex][kLeafCylinder] = &collide_convex_cylinder;
    k[kLeafCylinder][kLeafTriangle] = &collide_cylinder_triangle;
    k[kLeafCylinder][kLeafEllipsoid] = &collide_cylinder_ellipsoid;
    k[kLeafConvex][kLeafHalfSpace] = &collide_convex_halfspace;
    k[kLeafEllipsoid][kLeafEllipsoid] = &collide_ellipsoid_ellipsoid;
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
