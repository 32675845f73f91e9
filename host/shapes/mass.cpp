// Mass properties in double. Closed forms (uniform density rho):
//   sphere r:           V = 4/3 pi r^3,           I = 2/5 m r^2
//   box half a, b, c:   V = 8abc,                 Ixx = m (b^2 + c^2) / 3
//   cylinder r, h (half length, axis z): V = 2 pi r^2 h, Izz = m r^2 / 2,
//                       Ixx = m (3 r^2 + (2h)^2) / 12
//   ellipsoid a, b, c:  V = 4/3 pi abc,           Ixx = m (b^2 + c^2) / 5
//   capsule r, h:       the cylinder plus two hemispheres of total mass ms; about z
//                       2/5 ms r^2; about x each hemisphere (mass ms/2, centroid 3r/8
//                       from its flat face, I about its own centroid 2/5 (ms/2) r^2 -
//                       (ms/2)(3r/8)^2) moved by h + 3r/8: ms (2/5 r^2 + h^2 + 3hr/4).
//   convex hull:        the divergence theorem as a sum over tetrahedra (c, a, b, d)
//                       from a reference point c (the vertices' mean, for small
//                       cancellation) to each fan triangle of each face; each
//                       tetrahedron's covariance is det(A) A C0 A^T with C0 the
//                       canonical tetrahedron's (Blow & Binstock, "How to find the
//                       inertia tensor (or other mass properties) of a 3D solid body
//                       represented by a triangle mesh", 2004); I = tr(C) 1 - C.
#include "host/shapes/mass.h"

#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include <Eigen/Geometry>

namespace impact {

namespace {

using Vec3d = Eigen::Vector3d;
using Mat3d = Eigen::Matrix3d;

Status invalid(std::string msg) { return Status(StatusCode::kInvalidArgument, std::move(msg)); }

MassProperties diagonal(double volume, double density, const Vec3d& inertia_per_mass) {
  MassProperties m;
  m.volume = volume;
  m.mass = density * volume;
  m.center_of_mass = Vec3d::Zero();
  m.inertia = (inertia_per_mass * m.mass).asDiagonal();
  return m;
}

MassProperties hull_mass(const HullStore& hs, uint32_t h, double density) {
  const uint32_t vb = hs.vert_begin[h], ve = hs.vert_begin[h + 1];
  auto vert = [&](uint32_t i) { return Vec3d(hs.vx[i], hs.vy[i], hs.vz[i]); };
  Vec3d c = Vec3d::Zero();
  for (uint32_t i = vb; i < ve; ++i) c += vert(i);
  c /= static_cast<double>(ve - vb);
  Mat3d C0;
  C0 << 2, 1, 1, 1, 2, 1, 1, 1, 2;
  C0 /= 120.0;
  double vol = 0;
  Vec3d first = Vec3d::Zero();  // sum of volume * centroid (relative to c)
  Mat3d cov = Mat3d::Zero();    // second moment about c (per unit density)
  for (uint32_t f = hs.face_begin[h]; f < hs.face_begin[h + 1]; ++f) {
    const uint32_t b = hs.face_vert_begin[f], e = hs.face_vert_begin[f + 1];
    const Vec3d p0 = vert(hs.face_verts[b]) - c;
    for (uint32_t k = b + 1; k + 1 < e; ++k) {
      const Vec3d p1 = vert(hs.face_verts[k]) - c, p2 = vert(hs.face_verts[k + 1]) - c;
      Mat3d A;
      A.col(0) = p0;
      A.col(1) = p1;
      A.col(2) = p2;
      const double det = A.determinant();  // 6 x signed volume (faces wound outward)
      vol += det / 6.0;
      first += det / 6.0 * (p0 + p1 + p2) / 4.0;
      cov += det * A * C0 * A.transpose();
    }
  }
  MassProperties m;
  m.volume = vol;
  m.mass = density * vol;
  const Vec3d com = vol > 0 ? Vec3d(first / vol) : Vec3d::Zero();
  m.center_of_mass = c + com;
  // Covariance about the centre of mass, then the inertia tensor.
  const Mat3d cc = density * (cov - vol * com * com.transpose());
  m.inertia = cc.trace() * Mat3d::Identity() - cc;
  return m;
}

}  // namespace

Status shape_mass_properties(const ShapeStore& store, uint32_t shape, double density, MassProperties* out) {
  if (out == nullptr) return invalid("mass properties: out must not be null");
  if (shape >= store.shapes.size()) return invalid("mass properties: unknown shape " + std::to_string(shape));
  if (!(density > 0.0) || !std::isfinite(density))
    return invalid("mass properties: density must be finite and > 0, got " + std::to_string(density));
  const ShapeRecord& r = store.shapes[shape];
  const double pi = std::numbers::pi;
  const double e0 = r.e[0], e1 = r.e[1], e2 = r.e[2];
  switch (r.type) {
    case ShapeType::kSphere: {
      const double s = 0.4 * e0 * e0;
      *out = diagonal(4.0 / 3.0 * pi * e0 * e0 * e0, density, Vec3d(s, s, s));
      return {};
    }
    case ShapeType::kBox:
    case ShapeType::kAabb:
      *out = diagonal(8.0 * e0 * e1 * e2, density,
                      Vec3d(e1 * e1 + e2 * e2, e0 * e0 + e2 * e2, e0 * e0 + e1 * e1) / 3.0);
      return {};
    case ShapeType::kCylinder: {
      const double rr = e0 * e0, len = 2.0 * e1;
      const double t = (3.0 * rr + len * len) / 12.0;
      *out = diagonal(pi * rr * len, density, Vec3d(t, t, 0.5 * rr));
      return {};
    }
    case ShapeType::kEllipsoid:
      *out = diagonal(4.0 / 3.0 * pi * e0 * e1 * e2, density,
                      Vec3d(e1 * e1 + e2 * e2, e0 * e0 + e2 * e2, e0 * e0 + e1 * e1) / 5.0);
      return {};
    case ShapeType::kCapsule: {
      const double rad = e0, h = e1;
      const double vc = pi * rad * rad * 2.0 * h, vs = 4.0 / 3.0 * pi * rad * rad * rad;
      const double mc = density * vc, ms = density * vs;
      const double ixx = mc * (3.0 * rad * rad + 4.0 * h * h) / 12.0 + ms * (0.4 * rad * rad + h * h + 0.75 * h * rad);
      const double izz = mc * 0.5 * rad * rad + ms * 0.4 * rad * rad;
      MassProperties m;
      m.volume = vc + vs;
      m.mass = mc + ms;
      m.inertia = Vec3d(ixx, ixx, izz).asDiagonal();
      *out = m;
      return {};
    }
    case ShapeType::kConvex:
      if (r.ref >= store.hulls.size()) return invalid("mass properties: shape " + std::to_string(shape) + " has no hull");
      *out = hull_mass(store.hulls, r.ref, density);
      return {};
    case ShapeType::kCompound: {
      if (r.ref + 1 >= store.child_begin.size())
        return invalid("mass properties: shape " + std::to_string(shape) + " has no children");
      const uint32_t cb = store.child_begin[r.ref], ce = store.child_begin[r.ref + 1];
      MassProperties total;
      std::vector<MassProperties> parts;
      std::vector<Mat3d> rot;
      std::vector<Vec3d> pos;
      Vec3d weighted = Vec3d::Zero();
      for (uint32_t i = cb; i < ce; ++i) {
        const CompoundChild& ch = store.children[i];
        if (ch.shape.index == shape) return invalid("mass properties: compound contains itself");
        MassProperties cm;
        if (Status st = shape_mass_properties(store, ch.shape.index, density, &cm); !st.ok()) return st;
        const Mat3d R = ch.local.orientation.cast<double>().normalized().toRotationMatrix();
        const Vec3d c = R * cm.center_of_mass + ch.local.position.cast<double>();
        parts.push_back(cm);
        rot.push_back(R);
        pos.push_back(c);
        total.volume += cm.volume;
        total.mass += cm.mass;
        weighted += cm.mass * c;
      }
      total.center_of_mass = total.mass > 0 ? Vec3d(weighted / total.mass) : Vec3d::Zero();
      for (size_t k = 0; k < parts.size(); ++k) {
        const Vec3d d = pos[k] - total.center_of_mass;
        total.inertia += rot[k] * parts[k].inertia * rot[k].transpose() +
                         parts[k].mass * (d.squaredNorm() * Mat3d::Identity() - d * d.transpose());
      }
      *out = total;
      return {};
    }
    case ShapeType::kHalfSpace:
      return invalid("mass properties: shape " + std::to_string(shape) + " is a half-space (unbounded volume)");
    case ShapeType::kMesh:
      return invalid("mass properties: shape " + std::to_string(shape) +
                     " is a triangle mesh (static, no closed volume)");
  }
  return invalid("mass properties: unknown shape type");
}

}  // namespace impact
