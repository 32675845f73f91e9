// distance_posed (host/shapes/shape_distance.h).
#include "host/shapes/shape_distance.h"

#include <cmath>
#include <limits>

#include "host/shapes/pose.h"
#include "host/shapes/posed_leaf.h"
#include "kernels/distance/leaf_distance.h"

namespace impact::host {

namespace {

using kernels::cvx::Leaf;
using kernels::cvx::V3;

constexpr uint32_t kNone = 0xffffffffu;

V3 v3(const Eigen::Vector3f& v) { return V3{v.x(), v.y(), v.z()}; }
Eigen::Vector3f ev(V3 v) { return Eigen::Vector3f(v.x, v.y, v.z); }

// The rotation a record is posed with: an AABB ignores the pose's orientation.
Eigen::Matrix3f effective_rotation(const ShapeRecord& r, const Eigen::Matrix3f& R) {
  return r.type == ShapeType::kAabb ? Eigen::Matrix3f::Identity() : R;
}

PosedDistance from_leaf(const kernels::dist::LeafDistance& d, const Eigen::Vector3f& o) {
  PosedDistance r;
  r.overlap = d.overlap;
  r.distance = d.overlap ? 0.0f : d.distance;
  r.pa = ev(d.pa) + o;
  r.pb = ev(d.pb) + o;
  r.normal = ev(d.n);
  return r;
}

PosedDistance flip(PosedDistance r) {
  std::swap(r.pa, r.pb);
  std::swap(r.child_a, r.child_b);
  r.normal = -r.normal;
  return r;
}

PosedDistance unsupported() {
  PosedDistance r;
  r.distance = std::numeric_limits<float>::quiet_NaN();
  return r;
}

PosedDistance far_result() {
  PosedDistance r;
  r.distance = std::numeric_limits<float>::infinity();
  return r;
}

// Better: overlap first, then smaller distance; ties keep the earlier (lower index).
bool better(const PosedDistance& c, const PosedDistance& best) {
  if (best.overlap) return false;
  if (c.overlap) return true;
  return c.distance < best.distance;
}

// Distance of an axis-aligned box [lo, hi] (world) to B's world bounds [blo, bhi].
float box_gap(const float lo[3], const float hi[3], const Eigen::Vector3f& blo, const Eigen::Vector3f& bhi) {
  float g2 = 0.0f;
  for (int i = 0; i < 3; ++i) {
    const float g = std::fmax(std::fmax(lo[i] - bhi[i], blo[i] - hi[i]), 0.0f);
    g2 += g * g;
  }
  return std::sqrt(g2);
}

// Mesh A (posed) vs bounded convex B: BVH branch and bound in the mesh frame.
PosedDistance mesh_vs(const ShapeStore& s, const ShapeRecord& ra, const Eigen::Matrix3f& Ra, const Eigen::Vector3f& pa,
                      const ShapeRecord& rb, const Eigen::Matrix3f& Rb, const Eigen::Vector3f& pb,
                      const kernels::NarrowConfig& cfg, float max_distance) {
  const MeshData& m = s.meshes[ra.ref];
  PosedDistance best = far_result();
  if (m.nodes.empty()) return best;
  // B's bounds in the mesh frame: pose B relative to A.
  const Eigen::Matrix3f Rrel = Ra.transpose() * effective_rotation(rb, Rb);
  const Eigen::Vector3f prel = Ra.transpose() * (pb - pa);
  // In the mesh frame an AABB is a rotated box.
  ShapeRecord rbb = rb;
  if (rbb.type == ShapeType::kAabb) rbb.type = ShapeType::kBox;
  Eigen::Vector3f blo, bhi;
  posed_bounds(rbb, Rrel, prel, s.hulls, &blo, &bhi);
  const kernels::HullView hv = s.hulls.view();
  // The origin: B's centre (in the mesh frame), so triangle coordinates stay small.
  const Eigen::Vector3f o = prel;
  const Leaf lb = posed_leaf(rb, Rrel, prel - o, &hv);
  float bound = max_distance;
  uint32_t stack[64];
  uint32_t top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const MeshData::Node& nd = m.nodes[stack[--top]];
    if (box_gap(nd.lo, nd.hi, blo, bhi) > bound) continue;
    if (nd.count == 0) {
      const MeshData::Node& l = m.nodes[nd.left_or_first];
      const MeshData::Node& r = m.nodes[nd.right];
      const float gl = box_gap(l.lo, l.hi, blo, bhi), gr = box_gap(r.lo, r.hi, blo, bhi);
      if (top + 2 > 64) continue;  // depth cap: the builder keeps trees far shallower
      if (gl <= gr) {
        stack[top++] = nd.right;
        stack[top++] = nd.left_or_first;
      } else {
        stack[top++] = nd.left_or_first;
        stack[top++] = nd.right;
      }
      continue;
    }
    for (uint32_t k = nd.left_or_first; k < nd.left_or_first + nd.count; ++k) {
      const uint32_t t = m.tri_order[k];
      Leaf lt;
      lt.type = kernels::kLeafTriangle;
      lt.p = v3(m.vertices[m.indices[3 * t]] - o);
      lt.v1 = v3(m.vertices[m.indices[3 * t + 1]] - o);
      lt.v2 = v3(m.vertices[m.indices[3 * t + 2]] - o);
      PosedDistance c = from_leaf(kernels::dist::leaf_distance(lt, lb, cfg), o);
      c.child_a = t;
      if (c.overlap || c.distance <= bound) {
        if (better(c, best) || (!best.overlap && c.distance == best.distance && t < best.child_a)) {
          best = c;
          bound = c.overlap ? 0.0f : c.distance;
        }
      }
    }
    if (best.overlap) break;
  }
  if (best.child_a == kNone) return far_result();
  // Back to the world frame.
  best.pa = Ra * best.pa + pa;
  best.pb = Ra * best.pb + pa;
  best.normal = Ra * best.normal;
  return best;
}

}  // namespace

PosedDistance distance_posed(const ShapeStore& s, const ShapeRecord& ra, const Eigen::Matrix3f& Ra,
                             const Eigen::Vector3f& pa, const ShapeRecord& rb, const Eigen::Matrix3f& Rb,
                             const Eigen::Vector3f& pb, const kernels::NarrowConfig& cfg, float max_distance) {
  const bool ha = ra.type == ShapeType::kHalfSpace, hb = rb.type == ShapeType::kHalfSpace;
  if (ha && hb) return unsupported();
  // Compounds: minimum over children, lowest child index among ties.
  if (ra.type == ShapeType::kCompound || rb.type == ShapeType::kCompound) {
    const bool on_a = ra.type == ShapeType::kCompound;
    const ShapeRecord& rc = on_a ? ra : rb;
    const Eigen::Matrix3f& Rc = on_a ? Ra : Rb;
    const Eigen::Vector3f& pc = on_a ? pa : pb;
    PosedDistance best = far_result();
    bool found = false;
    float bound = max_distance;
    const uint32_t cb = s.child_begin[rc.ref], ce = s.child_begin[rc.ref + 1];
    for (uint32_t c = cb; c < ce; ++c) {
      const CompoundChild& ch = s.children[c];
      const ShapeRecord& cr = s.shapes[ch.shape.index];
      const Eigen::Matrix3f Rch = Rc * ch.local.orientation.toRotationMatrix();
      const Eigen::Vector3f pch = Rc * ch.local.position + pc;
      PosedDistance d = on_a ? distance_posed(s, cr, Rch, pch, rb, Rb, pb, cfg, bound)
                             : distance_posed(s, ra, Ra, pa, cr, Rch, pch, cfg, bound);
      if (std::isnan(d.distance)) return d;
      if (!d.overlap && !(d.distance <= bound)) continue;
      if (on_a) d.child_a = c - cb; else d.child_b = c - cb;
      if (!found || better(d, best)) {
        found = true;
        best = d;
        bound = d.overlap ? 0.0f : d.distance;
      }
      if (best.overlap) break;
    }
    return best;
  }
  const bool ma = ra.type == ShapeType::kMesh, mb = rb.type == ShapeType::kMesh;
  if (ma || mb) {
    if ((ma && mb) || ha || hb) return unsupported();
    return ma ? mesh_vs(s, ra, Ra, pa, rb, Rb, pb, cfg, max_distance)
              : flip(mesh_vs(s, rb, Rb, pb, ra, Ra, pa, cfg, max_distance));
  }
  const kernels::HullView hv = s.hulls.view();
  // The origin: A's position (B's when A is a half-space, whose point may be far).
  const Eigen::Vector3f o = ha ? pb : pa;
  const Leaf la = posed_leaf(ra, effective_rotation(ra, Ra), pa - o, &hv);
  const Leaf lb = posed_leaf(rb, effective_rotation(rb, Rb), pb - o, &hv);
  PosedDistance r = from_leaf(kernels::dist::leaf_distance(la, lb, cfg), o);
  if (!r.overlap && r.distance > max_distance) return far_result();
  return r;
}

}  // namespace impact::host
