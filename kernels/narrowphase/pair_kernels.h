// Every narrow-phase pair kernel, declared by name: one per (leaf type, leaf type) bucket
// of the matrix, with the PairKernel signature of kernels/narrowphase/leaf/leaf.h (A's
// type <= B's type, LeafType order). collide_<a>_<b> is defined in
// kernels/narrowphase/pairs/<a>/<a>_<b>.cpp; the general routes (GJK / EPA, SAT, the
// support-function half-space kernel) in kernels/narrowphase/general/. pair_kernel()
// (pair_kernels.cpp) is the table that maps each bucket to its kernel; a bucket without
// a specialised kernel takes a general route there. docs/narrowphase.md "Kernels" has
// the method and cost of each.
#pragma once

#include "kernels/narrowphase/leaf/leaf.h"

namespace impact::kernels {

// --- pairs/sphere/ --------------------------------------------------------------------
/// Sphere against sphere: the centres' line, one point (sphere_sphere.cpp), SIMD across pairs.
void collide_sphere_sphere(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, Range r,
                           const NarrowConfig& cfg);
/// Sphere against capsule: the closest point of the core segment, one point, SIMD across pairs.
void collide_sphere_capsule(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, Range r,
                            const NarrowConfig& cfg);
/// Sphere against box: the closest box point, the face of least penetration inside, one point,
/// SIMD across pairs.
void collide_sphere_box(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, Range r,
                        const NarrowConfig& cfg);
/// Sphere against convex hull: exact, by the hull's face planes and, near an edge, its
/// edge segments (sphere_convex.cpp); one lane at a time, not GJK / EPA.
void collide_sphere_convex(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, Range r,
                           const NarrowConfig& cfg);
/// Sphere against cylinder: the exact closest point (radius and height clamped apart), one
/// point, SIMD across pairs.
void collide_sphere_cylinder(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, Range r,
                             const NarrowConfig& cfg);
/// Sphere against ellipsoid: closest surface point by a fixed-count root solve, SIMD across pairs.
void collide_sphere_ellipsoid(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, Range r,
                              const NarrowConfig& cfg);
/// Sphere against triangle: the closest point (Ericson 5.1.5), one point, SIMD across pairs.
void collide_sphere_triangle(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, Range r,
                             const NarrowConfig& cfg);
/// Sphere against half-space: the centre's height, one point, SIMD across pairs.
void collide_sphere_halfspace(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, Range r,
                              const NarrowConfig& cfg);

// --- pairs/capsule/ -------------------------------------------------------------------
/// Capsule against capsule: closest points of the cores, 2 points for overlapping
/// near-parallel axes, SIMD across pairs.
void collide_capsule_capsule(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, Range r,
                             const NarrowConfig& cfg);
/// Capsule against box: the core's exact closest point outside, SAT on 6 axes inside, 1-2
/// points, SIMD across pairs.
void collide_capsule_box(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, Range r,
                         const NarrowConfig& cfg);
/// Capsule against convex hull: exact, by the hull's face planes and edges (distance of the
/// core outside, separating axes when the core meets the hull; capsule_convex.cpp); one
/// lane at a time, not GJK / EPA.
void collide_capsule_convex(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, Range r,
                            const NarrowConfig& cfg);
/// Capsule against cylinder: the least support overlap of the core and the cylinder over
/// the candidate normals of their Minkowski difference's boundary pieces (caps, side,
/// rims by a fixed-count 2D root solve, end-rim edges), 1-2 points, SIMD across pairs.
void collide_capsule_cylinder(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, Range r,
                              const NarrowConfig& cfg);
/// Capsule against ellipsoid: exact, the least of five candidate normals (each end point's
/// nearest and far local minimum on the ellipsoid, the shadow's nearest point to the
/// core; capsule_ellipsoid.cpp), SIMD across pairs.
void collide_capsule_ellipsoid(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, Range r,
                               const NarrowConfig& cfg);
/// Capsule against triangle: closest points outside, SAT on 4 axes when the core crosses,
/// 1-2 points, SIMD across pairs.
void collide_capsule_triangle(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, Range r,
                              const NarrowConfig& cfg);
/// Capsule against half-space: the surface below each core end, 1-2 points, SIMD across pairs.
void collide_capsule_halfspace(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, Range r,
                               const NarrowConfig& cfg);

// --- pairs/box/ -----------------------------------------------------------------------
/// Box against box: SAT on 15 axes, the reference face clipped to 4 points (face lanes
/// queued and clipped together), SIMD across pairs.
void collide_box_box(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, Range r,
                     const NarrowConfig& cfg);
/// Box (A) against cylinder (B): exact, the least support overlap over the candidate normals
/// of their Minkowski difference's pieces (faces, caps, edges and vertices against the
/// side, vertices against the rims in closed form, edges against the rims by the 2D root
/// solve of rim_solve.h, packed across lanes after a distance bound), the cap or side
/// clipped to the box (1-4 points; box_cylinder.cpp), SIMD across pairs.
void collide_box_cylinder(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, Range r,
                          const NarrowConfig& cfg);
/// Box against ellipsoid: exact, the least support overlap over the box's face normals and
/// the candidate normals of the vertex and edge pieces that can hold one (pruned along
/// each candidate's solution curve, the rest solved packed; box_ellipsoid.cpp), SIMD
/// across pairs.
void collide_box_ellipsoid(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, Range r,
                           const NarrowConfig& cfg);
/// Box against triangle: SAT on 13 axes in the box frame, the triangle clipped by the box
/// face, up to 4 points, SIMD across pairs.
void collide_box_triangle(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, Range r,
                          const NarrowConfig& cfg);
/// Box against half-space: the deepest vertex and the rest of the lowest face below the
/// plane, up to 4 points, SIMD across pairs.
void collide_box_halfspace(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, Range r,
                           const NarrowConfig& cfg);

// --- pairs/convex/ --------------------------------------------------------------------
/// Convex hull vs cylinder: the least support overlap over the candidate directions of
/// the Minkowski difference's pieces (faces, caps, edge-side, vertex-side and vertex-rim
/// in closed form, edge-rim by rim_solve.h's root solve after lower bounds), then the
/// general route's manifold (cvx::contact_manifold); one pair at a time, kSimdWidth
/// hull features per step (convex_cylinder.cpp), not GJK / EPA.
void collide_convex_cylinder(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, Range r,
                             const NarrowConfig& cfg);
/// Convex hull (A) against ellipsoid (B): exact, the least support overlap over the hull's
/// face normals and the candidate normals of the vertex and edge pieces that can still
/// win (distance and level bounds, the curve test along each edge candidate's solution;
/// survivors solved packed; convex_ellipsoid.cpp); one pair at a time, kSimdWidth
/// features per step, not GJK / EPA.
void collide_convex_ellipsoid(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, Range r,
                              const NarrowConfig& cfg);
/// Convex hull (A) against triangle (B): exact, by the separating axis test in the hull's
/// frame (hull faces, the triangle's normal, hull edge x triangle edge axes pruned by the
/// Gauss map), a clipped face manifold or one edge point (convex_triangle.cpp); one lane
/// at a time, not GJK / EPA.
void collide_convex_triangle(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, Range r,
                             const NarrowConfig& cfg);
/// Convex hull (A) against half-space (B): the deepest vertex and up to 3 more vertices
/// below the plane, one pair per SIMD lane: each lane lists its own hull's vertices
/// below, then the touching lanes, compacted into full groups, pick over those
/// (convex_halfspace.cpp); hulls of more than 64 vertices take collide_support_halfspace.
void collide_convex_halfspace(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, Range r,
                              const NarrowConfig& cfg);

// --- pairs/cylinder/ ------------------------------------------------------------------
/// Cylinder against cylinder: exact, the least support overlap over the candidate normals
/// of their Minkowski difference's pieces (caps, side x side, a side against the other's
/// rims by the 2D root solve of rim_solve.h, rim x rim by the local minima of the
/// circle-circle distance), the caps or sides clipped against each other (1-4 points;
/// cylinder_cylinder.cpp), SIMD across pairs.
void collide_cylinder_cylinder(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, Range r,
                               const NarrowConfig& cfg);
/// Cylinder (A) against ellipsoid (B): the least support overlap over the unit sphere:
/// the caps' normals and the side's circle in closed form (the circle by the nearest
/// point of the ellipsoid's shadow), each rim's piece by a multi-start trust-region
/// Newton solve on the sphere (ellipsoid-ellipsoid's, with the rim as a flat ellipsoid);
/// lanes certified apart first, the rest gathered into full blocks
/// (cylinder_ellipsoid.cpp); one point midway, SIMD across pairs.
void collide_cylinder_ellipsoid(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, Range r,
                                const NarrowConfig& cfg);
/// Cylinder against triangle: the least support overlap over the candidate normals of
/// their Minkowski difference's pieces (caps, faces, side against edges and vertices,
/// vertices against rims, edges against rims by the 2D root solve of rim_solve.h), the
/// cap or side clipped to the triangle (1-4 points), SIMD across pairs.
void collide_cylinder_triangle(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, Range r,
                               const NarrowConfig& cfg);
/// Cylinder against half-space: the deepest rim point and the cap's or the side's other
/// points below the plane, up to 4, closed form, SIMD across pairs.
void collide_cylinder_halfspace(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, Range r,
                                const NarrowConfig& cfg);

// --- pairs/ellipsoid/ -----------------------------------------------------------------
/// Ellipsoid against ellipsoid: the least support overlap f(n) = h_A(n) + h_B(n) - n.d over
/// the unit sphere by a trust-region Newton solve on the sphere from the eight least of 25
/// candidate directions (d, the six axes, their nine cross products, d perpendicular to
/// each axis, the least eigenvectors of M_A + w M_B), two kept after three steps; lanes
/// certified apart first, the rest gathered into full blocks (ellipsoid_ellipsoid.cpp);
/// one point midway, SIMD across pairs. Global minimum by multi-start (no proof; tested).
void collide_ellipsoid_ellipsoid(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, Range r,
                                 const NarrowConfig& cfg);
/// Ellipsoid against triangle: exact, the least of fourteen candidate normals (the face
/// normals, each vertex's nearest and far local minimum on the ellipsoid, each edge's on
/// the ellipsoid's shadow across it; ellipsoid_triangle.cpp), SIMD across pairs.
void collide_ellipsoid_triangle(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, Range r,
                                const NarrowConfig& cfg);
/// Ellipsoid against half-space: the support point in closed form, one point, SIMD across pairs.
void collide_ellipsoid_halfspace(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, Range r,
                                 const NarrowConfig& cfg);

// --- pairs/triangle/ ------------------------------------------------------------------
/// Triangle against triangle: SAT on 11 axes, face manifold by clipping candidates
/// (triangle_triangle.cpp), SIMD across pairs.
void collide_triangle_triangle(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, Range r,
                               const NarrowConfig& cfg);
/// Triangle against half-space: its vertices below the plane, deepest first, up to 3 points,
/// SIMD across pairs.
void collide_triangle_halfspace(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, Range r,
                                const NarrowConfig& cfg);

// --- general/ and the routes of pair_kernels.cpp -----------------------------------------
/// GJK + EPA for any two convex leaf types ta <= tb (neither a half-space), one pair
/// per lane, then the face manifold (general/gjk_epa.cpp, general/face_manifold.cpp):
/// polytope pairs (box, convex, triangle) get a clipped face manifold.
void collide_gjk_epa(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, Range r,
                     const NarrowConfig& cfg, LeafType ta, LeafType tb);
/// Two polytopes (box, convex hull; ta <= tb), lane by lane: the separating axis test
/// (cvx::collide_sat_lane, general/sat.cpp; box-hull by an exact route with the box in
/// closed form) where it applies and the two vertex counts sum to at most
/// cfg.sat_max_vertices (cvx::sat_vertex_count), else GJK + EPA (cvx::collide_convex_lane);
/// the face manifold either way. The route of the box-hull and hull-hull buckets
/// (pair_kernels.cpp).
void collide_sat_or_gjk_epa(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, Range r,
                            const NarrowConfig& cfg, LeafType ta, LeafType tb);
/// Any convex leaf type ta against a half-space (B): the deepest point by the support
/// function, and for polytopes up to 4 manifold points below the plane, one pair at a
/// time (every type has a lane kernel in pair_kernel(); collide_convex_halfspace sends
/// its hulls of more than 64 vertices here).
void collide_support_halfspace(const LeafSoA& a, const LeafSoA& b, const ManifoldSoA& out, Range r,
                               const NarrowConfig& cfg, LeafType ta);

}  // namespace impact::kernels
