// The rotational mass of a World body from its shape (BodyDesc, ShapeSet): the
// shape's uniform-density inertia about its centre of mass (ShapeSet::mass_properties)
// scaled to the body's mass, diagonalised into principal moments and axes. A plain
// sphere is a solid ball of its radius: I = 2/5 m r^2 about every axis.
// Cost: one mass-properties evaluation and a 3x3 symmetric eigen-solve per body, at
// creation only.
#pragma once

#include "host/body_store.h"
#include "impact/shapes.h"

namespace impact::host {

/// Sets row's inverse principal inertia (iix, iiy, iiz), principal axes in the shape
/// frame (pq*) and centre of mass in the shape frame (c*) for a dynamic body of inverse
/// mass inv_mass > 0 and shape `shape` (invalid id: a sphere of `radius`).
void body_inertia(const ShapeSet& shapes, ShapeId shape, float radius, float inv_mass, BodyRow* row);

/// Copies row's inertia and centre of mass (the fields body_inertia sets) into slot i of
/// s (kRigid on).
inline void set_rigid_fields(BodyStore& s, uint32_t i, const BodyRow& row) {
  s.iix[i] = row.iix;
  s.iiy[i] = row.iiy;
  s.iiz[i] = row.iiz;
  s.pqx[i] = row.pqx;
  s.pqy[i] = row.pqy;
  s.pqz[i] = row.pqz;
  s.pqw[i] = row.pqw;
  s.cx[i] = row.cx;
  s.cy[i] = row.cy;
  s.cz[i] = row.cz;
}

}  // namespace impact::host
