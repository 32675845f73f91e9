// toi_posed: shapes -> moving leaves -> kernels::ccd::time_of_impact per leaf pair
// (contract: shape_cast.h).
#include "host/shapes/shape_cast.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include <Eigen/Geometry>

#include "host/shapes/posed_leaf.h"
#include "kernels/ccd/time_of_impact.h"

namespace impact::host {
namespace {

using kernels::ccd::Motion;
using kernels::ccd::ToiResult;
using kernels::cvx::Leaf;
using kernels::cvx::V3;

struct MovingLeaf {
  Leaf leaf;
  Motion m;
  uint32_t child = kNoChildIndex;
  static constexpr uint32_t kNoChildIndex = 0xffffffffu;
};

V3 v3(const Eigen::Vector3d& v) { return V3{float(v.x()), float(v.y()), float(v.z())}; }

Eigen::Matrix3d rotation_vector(const Eigen::Vector3d& w) {
  const double a = w.norm();
  if (a == 0.0) return Eigen::Matrix3d::Identity();
  return Eigen::AngleAxisd(a, w / a).toRotationMatrix();
}

// A convex record (or half-space) posed at (R, p), p relative to the origin; an AABB
// keeps the world axes whatever R.
Leaf make_leaf(const ShapeRecord& r, const Eigen::Matrix3d& R, const Eigen::Vector3d& p,
               const kernels::HullView* hv) {
  const Eigen::Matrix3f Rf = r.type == ShapeType::kAabb ? Eigen::Matrix3f(Eigen::Matrix3f::Identity())
                                                         : Eigen::Matrix3f(R.cast<float>());
  return posed_leaf(r, Rf, p.cast<float>(), hv);
}

struct Side {
  const ShapeRecord* r;
  Eigen::Matrix3d R;
  Eigen::Vector3d p;  // relative to the origin
  Eigen::Vector3d d, w;
};

// The leaves of a non-mesh side, in child order.
void expand(const ShapeStore& s, const Side& sd, const kernels::HullView* hv, std::vector<MovingLeaf>* out) {
  const bool rotates = sd.r->type != ShapeType::kAabb;
  if (sd.r->type == ShapeType::kCompound) {
    const Eigen::Matrix3d Rw = rotation_vector(sd.w);
    const uint32_t cb = s.child_begin[sd.r->ref], ce = s.child_begin[sd.r->ref + 1];
    for (uint32_t c = cb; c < ce; ++c) {
      const CompoundChild& ch = s.children[c];
      const ShapeRecord& cr = s.shapes[ch.shape.index];
      const Eigen::Vector3d o = sd.R * ch.local.position.cast<double>();
      const Eigen::Matrix3d Rc = sd.R * ch.local.orientation.cast<double>().normalized().toRotationMatrix();
      MovingLeaf ml;
      ml.leaf = make_leaf(cr, Rc, sd.p + o, hv);
      // The child's centre along the chord of its arc about the compound's origin.
      ml.m.v = v3(Eigen::Vector3d(sd.d + (Rw - Eigen::Matrix3d::Identity()) * o));
      ml.m.w = cr.type == ShapeType::kAabb ? V3{0, 0, 0} : v3(sd.w);
      ml.child = c - cb;
      out->push_back(ml);
    }
    return;
  }
  MovingLeaf ml;
  ml.leaf = make_leaf(*sd.r, sd.R, sd.p, hv);
  if (sd.r->type != ShapeType::kHalfSpace) {
    ml.m.v = v3(sd.d);
    if (rotates) ml.m.w = v3(sd.w);
  }
  out->push_back(ml);
}

// World AABB (relative to the origin) swept by the leaves, grown by `pad`.
void swept_bounds(const std::vector<MovingLeaf>& ls, double pad, Eigen::Vector3d* lo, Eigen::Vector3d* hi) {
  *lo = Eigen::Vector3d::Constant(INFINITY);
  *hi = Eigen::Vector3d::Constant(-INFINITY);
  for (const MovingLeaf& ml : ls) {
    const V3 c = kernels::cvx::leaf_center(ml.leaf);
    const Eigen::Vector3d c0(c.x, c.y, c.z), c1 = c0 + Eigen::Vector3d(ml.m.v.x, ml.m.v.y, ml.m.v.z);
    const double r = double(kernels::ccd::leaf_reach(ml.leaf)) + pad;
    *lo = lo->cwiseMin(c0.cwiseMin(c1) - Eigen::Vector3d::Constant(r));
    *hi = hi->cwiseMax(c0.cwiseMax(c1) + Eigen::Vector3d::Constant(r));
  }
}

// The triangles of a static mesh at (R, p) whose bounds meet the world box [lo, hi].
void mesh_leaves(const MeshData& m, const Eigen::Matrix3d& R, const Eigen::Vector3d& p, const Eigen::Vector3d& lo,
                 const Eigen::Vector3d& hi, std::vector<MovingLeaf>* out) {
  if (m.nodes.empty()) return;
  // The box in the mesh's frame: centre and half extents through |R^T|.
  const Eigen::Vector3d c = R.transpose() * (0.5 * (lo + hi) - p);
  const Eigen::Vector3d h = R.transpose().cwiseAbs() * (0.5 * (hi - lo));
  const Eigen::Vector3d llo = c - h, lhi = c + h;
  uint32_t stack[64];
  uint32_t top = 0;
  stack[top++] = 0;
  std::vector<uint32_t> tris;
  while (top > 0) {
    const MeshData::Node& nd = m.nodes[stack[--top]];
    bool meets = true;
    for (int i = 0; i < 3; ++i) meets = meets && nd.lo[i] <= lhi[i] && nd.hi[i] >= llo[i];
    if (!meets) continue;
    if (nd.count > 0) {
      for (uint32_t k = 0; k < nd.count; ++k) tris.push_back(m.tri_order[nd.left_or_first + k]);
    } else if (top + 2 <= 64) {
      stack[top++] = nd.right;
      stack[top++] = nd.left_or_first;
    }
  }
  std::sort(tris.begin(), tris.end());
  for (uint32_t t : tris) {
    MovingLeaf ml;
    ml.leaf.type = kernels::kLeafTriangle;
    Eigen::Vector3d v[3];
    for (int j = 0; j < 3; ++j) v[j] = R * m.vertices[m.indices[3 * t + j]].cast<double>() + p;
    ml.leaf.p = v3(v[0]);
    ml.leaf.v1 = v3(v[1]);
    ml.leaf.v2 = v3(v[2]);
    ml.child = t;
    out->push_back(ml);
  }
}

bool is_static_leaf(const MovingLeaf& l) {
  return l.leaf.type == kernels::kLeafHalfSpace || l.leaf.type == kernels::kLeafTriangle;
}

}  // namespace

PosedToi toi_posed(const ShapeStore& store, const ShapeRecord& ra, const Eigen::Matrix3f& Ra,
                   const Eigen::Vector3f& pa, const Eigen::Vector3f& da, const Eigen::Vector3f& wa,
                   const ShapeRecord& rb, const Eigen::Matrix3f& Rb, const Eigen::Vector3f& pb,
                   const Eigen::Vector3f& db, const Eigen::Vector3f& wb, const kernels::NarrowConfig& cfg,
                   float target, float tolerance) {
  PosedToi out;
  const bool mesh_a = ra.type == ShapeType::kMesh, mesh_b = rb.type == ShapeType::kMesh;
  if (mesh_a && mesh_b) return out;  // both static
  const Eigen::Vector3d origin = pa.cast<double>();
  const kernels::HullView hv = store.hulls.view();
  const Side sa{&ra, Ra.cast<double>(), pa.cast<double>() - origin, da.cast<double>(), wa.cast<double>()};
  const Side sb{&rb, Rb.cast<double>(), pb.cast<double>() - origin, db.cast<double>(), wb.cast<double>()};
  std::vector<MovingLeaf> la, lb;
  if (!mesh_a) expand(store, sa, &hv, &la);
  if (!mesh_b) expand(store, sb, &hv, &lb);
  const double pad = double(target) + tolerance;
  if (mesh_a || mesh_b) {
    Eigen::Vector3d lo, hi;
    swept_bounds(mesh_a ? lb : la, pad, &lo, &hi);
    const Side& ms = mesh_a ? sa : sb;
    mesh_leaves(store.meshes[ms.r->ref], ms.R, ms.p, lo, hi, mesh_a ? &la : &lb);
  }
  ToiResult best;
  bool found = false;
  for (const MovingLeaf& a : la) {
    for (const MovingLeaf& b : lb) {
      if (is_static_leaf(a) && is_static_leaf(b)) continue;
      const ToiResult r = kernels::ccd::time_of_impact(a.leaf, a.m, b.leaf, b.m, target, tolerance,
                                                       kToiMaxIterations, cfg);
      out.iterations += r.iterations;
      if (r.state == ToiResult::kSeparated) continue;
      // kFailed: the last safe fraction, reported as a hit (nothing passes through).
      const bool overlap = r.state == ToiResult::kOverlapAtStart;
      const bool better = !found || r.t < best.t ||
                          (r.t == best.t && overlap && best.state != ToiResult::kOverlapAtStart);
      if (!better) continue;
      found = true;
      best = r;
      out.child_a = a.child;
      out.child_b = b.child;
    }
  }
  if (!found) return out;
  out.hit = true;
  out.initially_overlapping = best.state == ToiResult::kOverlapAtStart;
  out.t = out.initially_overlapping ? 0.0f : best.t;
  out.normal = Eigen::Vector3f(best.normal.x, best.normal.y, best.normal.z);
  out.point = (origin + Eigen::Vector3d(best.point.x, best.point.y, best.point.z)).cast<float>();
  return out;
}

}  // namespace impact::host
