// Leaf distance: closed forms, then GJK on the cores plus radii (leaf_distance.h).
#include "kernels/distance/leaf_distance.h"

#include <cmath>

#include "kernels/narrowphase/general/gjk_epa.h"

namespace impact::kernels::dist {

using cvx::V3;

namespace {

// B against the half-space H = {x : n.(x - p) <= 0}: the deepest point of B along -n.
LeafDistance halfspace_vs(const cvx::Leaf& h, const cvx::Leaf& b) {
  LeafDistance r;
  const V3 n{h.e[0], h.e[1], h.e[2]};
  const V3 q = cvx::support(b, -n);
  const float s = cvx::dot(q - h.p, n);
  r.pb = q;
  r.pa = q - n * s;
  r.n = n;
  if (s > 0.0f) {
    r.distance = s;
  } else {
    r.overlap = true;
    r.pa = r.pb;
  }
  return r;
}

LeafDistance sphere_sphere(const cvx::Leaf& a, const cvx::Leaf& b) {
  LeafDistance r;
  const V3 d = b.p - a.p;
  const float l = cvx::len(d);
  const float s = l - a.e[0] - b.e[0];
  r.n = l > 0.0f ? d * (1.0f / l) : V3{0, 1, 0};
  r.pa = a.p + r.n * a.e[0];
  r.pb = b.p - r.n * b.e[0];
  if (s > 0.0f) {
    r.distance = s;
  } else {
    r.overlap = true;
  }
  return r;
}

LeafDistance flip(LeafDistance r) {
  const V3 t = r.pa;
  r.pa = r.pb;
  r.pb = t;
  r.n = -r.n;
  return r;
}

}  // namespace

LeafDistance leaf_distance(const cvx::Leaf& a, const cvx::Leaf& b, const NarrowConfig& cfg) {
  if (a.type == kLeafHalfSpace) return halfspace_vs(a, b);
  if (b.type == kLeafHalfSpace) return flip(halfspace_vs(b, a));
  if (a.type == kLeafSphere && b.type == kLeafSphere) return sphere_sphere(a, b);
  const float ra = cvx::core_radius(a), rb = cvx::core_radius(b);
  const float scale = cvx::leaf_size(a) + cvx::leaf_size(b);
  // margin = +inf: never stop early, so the core distance is exact.
  const cvx::GjkResult g = cvx::gjk_cores(a, b, INFINITY, scale, cfg.gjk_max_iterations, cfg.gjk_tolerance);
  LeafDistance r;
  r.iterations = g.iterations;
  r.n = g.n;
  r.pa = g.pa + g.n * ra;
  r.pb = g.pb - g.n * rb;
  const float s = g.overlap ? 0.0f : g.distance - ra - rb;
  if (!g.overlap && s > 0.0f) {
    r.distance = s;
  } else {
    r.overlap = true;
  }
  return r;
}

}  // namespace impact::kernels::dist
