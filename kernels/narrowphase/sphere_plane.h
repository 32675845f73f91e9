// Sphere-plane narrow phase: every dynamic body against every plane.
//
// Plane { x : n.x <= offset }, n unit, pointing out of the solid. With the signed
// distance h = n.p - offset, the sphere collides when h < r; then (a = body,
// b = plane) normal = -n (from the sphere into the plane), depth = r - h, point =
// midpoint of the sphere's deepest point p - n*r and its projection p - n*h.
// Static bodies (inv_mass == 0) never collide with planes (static never pairs
// with static); layers/masks filter as for body pairs.
// count: contacts of bodies in r. write: those contacts at out[offset ...],
// ordered by body then plane. Cost: O(bodies * planes); planes are few.
#pragma once

#include "kernels/narrowphase/contact.h"

namespace impact::kernels {

struct BodyFilter {
  const float* inv_mass;
  const uint32_t* layer;
  const uint32_t* mask;
};

uint64_t sphere_plane_count(SphereView s, BodyFilter f, PlaneView planes, Range r);

void sphere_plane_write(SphereView s, BodyFilter f, PlaneView planes, ContactSoA out,
                        uint64_t offset, Range r);

}  // namespace impact::kernels
