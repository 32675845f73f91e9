// No FMA contraction in the functions the including file defines after this header.
//
// Why: in the cylinder kernels (capsule_cylinder.cpp, box_cylinder.cpp,
// cylinder_cylinder.cpp, cylinder_triangle.cpp, cylinder_ellipsoid.cpp,
// convex_cylinder.cpp) several quantities are rounding noise by nature (a segment's
// or an edge's horizontal part when it runs along the axis, the offset of an end point
// on the axis, the 2-D closest point of a segment crossing the axis in projection). Any
// unit direction built from them is as good as another, but it must be unit, or the
// support overlap o(n) is no upper bound. GCC 12 at -O3 (SLP vectorisation of the
// one-lane path) was seen to evaluate such a quantity twice, contracted differently, and
// normalise one copy by the other's length (|n| = 0.93, a depth 6% short). Without
// contraction every copy rounds alike, and the one-lane and SIMD paths give the same
// bytes (tests/kernels/narrowphase/contract_test.cpp relies on it).
//
// The soft step's contact kernels (kernels/solver/soft_contact.cpp) include it for the
// same reason: GCC contracts a template's block (FloatW) and one-lane (Float1)
// instantiations differently, and both must give the same bytes.
//
// Where to include it (GCC 12, checked on its assembly): the pragma covers every
// function and template defined after it, and whatever is inlined into them, including
// IMPACT_INLINE helpers and templates from headers included before it. A function
// defined before it and called out of line keeps contraction. So after the other
// headers is enough when the headers' helpers are inlined (most of these kernels);
// cylinder_ellipsoid.cpp includes it first so that it also covers the shared solvers'
// templates (ellipsoid_solve.h, sphere_newton.h) wherever GCC leaves them out of line.
// Out-of-line copies emitted under it are weak (COMDAT) symbols like any inline
// function's: where another file instantiates the same helper with contraction, the
// linker keeps one of the two copies for both.
//
// Deliberately no include guard: the pragma must take effect in every file that
// includes it.
#if defined(__clang__)
#pragma STDC FP_CONTRACT OFF
#elif defined(__GNUC__)
#pragma GCC optimize("fp-contract=off")
#endif
