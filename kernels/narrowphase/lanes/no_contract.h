// No FMA contraction in the rest of the including file: include this last, after the
// other headers, in a kernel source whose directions are built from rounding noise.
//
// Why: in the cylinder kernels (capsule_cylinder.cpp, box_cylinder.cpp,
// cylinder_triangle.cpp) several quantities are rounding noise by nature (a segment's
// or an edge's horizontal part when it runs along the axis, the offset of an end point
// on the axis, the 2-D closest point of a segment crossing the axis in projection). Any
// unit direction built from them is as good as another, but it must be unit, or the
// support overlap o(n) is no upper bound. GCC 12 at -O3 (SLP vectorisation of the
// one-lane path) was seen to evaluate such a quantity twice, contracted differently, and
// normalise one copy by the other's length (|n| = 0.93, a depth 6% short). Without
// contraction every copy rounds alike; the cost was not measurable (these kernels are
// bound by their divisions and square roots).
//
// Deliberately no include guard: the pragma must take effect in every file that
// includes it.
#if defined(__clang__)
#pragma STDC FP_CONTRACT OFF
#elif defined(__GNUC__)
#pragma GCC optimize("fp-contract=off")
#endif
