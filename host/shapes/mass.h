// Uniform-density mass properties of the shapes of a ShapeStore (ShapeSet::mass_properties).
#pragma once

#include <cstdint>

#include "host/shapes/shape_store.h"
#include "impact/shapes.h"
#include "impact/status.h"

namespace impact {

/// Volume, mass, centre of mass and inertia tensor about the centre of mass, in the
/// shape's local frame, for density in kg/m^3 (finite, > 0). Closed forms for sphere,
/// capsule, box / AABB, cylinder and ellipsoid; the divergence theorem over fan
/// triangles for convex hulls; compounds combine their children (rotated R I R^T and
/// moved to the compound's centre of mass by the parallel-axis theorem; overlapping
/// children count twice). Errors (kInvalidArgument): an unknown shape index, a
/// non-positive or non-finite density, half-spaces and meshes (no finite closed volume).
Status shape_mass_properties(const ShapeStore& store, uint32_t shape, double density, MassProperties* out);

}  // namespace impact
