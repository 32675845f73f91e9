// HullStore (host/narrowphase/shape_store.h): every convex hull of a ShapeSet in one set
// of flat arrays, the layout kernels read through kernels::HullView.
#include "host/narrowphase/shape_store.h"

namespace impact {

uint32_t HullStore::add(const HullData& h) {
  const uint32_t id = size();
  const uint32_t vbase = static_cast<uint32_t>(vx.size());
  for (const Eigen::Vector3f& v : h.vertices) {
    vx.push_back(v.x());
    vy.push_back(v.y());
    vz.push_back(v.z());
  }
  vert_begin.push_back(static_cast<uint32_t>(vx.size()));
  for (size_t f = 0; f < h.faces.size(); ++f) {
    fnx.push_back(h.face_normals[f].x());
    fny.push_back(h.face_normals[f].y());
    fnz.push_back(h.face_normals[f].z());
    fd.push_back(h.face_offsets[f]);
    // Face vertex indices become absolute (into vx/vy/vz).
    for (uint32_t i : h.faces[f]) face_verts.push_back(vbase + i);
    face_vert_begin.push_back(static_cast<uint32_t>(face_verts.size()));
  }
  face_begin.push_back(static_cast<uint32_t>(fnx.size()));
  for (const Eigen::Vector3f& e : h.edge_dirs) {
    ex.push_back(e.x());
    ey.push_back(e.y());
    ez.push_back(e.z());
  }
  edge_begin.push_back(static_cast<uint32_t>(ex.size()));
  return id;
}

kernels::HullView HullStore::view() const {
  kernels::HullView v;
  v.vert_begin = vert_begin.data();
  v.vx = vx.data();
  v.vy = vy.data();
  v.vz = vz.data();
  v.face_begin = face_begin.data();
  v.fnx = fnx.data();
  v.fny = fny.data();
  v.fnz = fnz.data();
  v.fd = fd.data();
  v.face_vert_begin = face_vert_begin.data();
  v.face_verts = face_verts.data();
  v.edge_begin = edge_begin.data();
  v.ex = ex.data();
  v.ey = ey.data();
  v.ez = ez.data();
  return v;
}

}  // namespace impact
