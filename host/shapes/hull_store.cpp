// HullStore (host/shapes/shape_store.h): every convex hull of a ShapeSet in one set
// of flat arrays, the layout kernels read through kernels::HullView.
#include "host/shapes/shape_store.h"

#include <cmath>
#include <map>

namespace impact {

namespace {

constexpr size_t kEdgePad = kernels::kHullEdgePad;  // kernels/narrowphase/leaf/leaf.h

/// Undirected edges of h's faces, each with its two faces (ev0 -> ev1 runs
/// counter-clockwise in ef0), in order of first appearance. Empty when some edge does
/// not have exactly two faces (not a closed 2-manifold).
struct Adjacency {
  std::vector<uint32_t> v0, v1, f0, f1;
};

Adjacency edge_adjacency(const HullData& h) {
  Adjacency a;
  std::map<uint64_t, uint32_t> open;  // directed edge (v0, v1) of f0 -> edge index
  bool ok = true;
  for (uint32_t f = 0; f < h.faces.size() && ok; ++f) {
    const auto& poly = h.faces[f];
    for (size_t k = 0; k < poly.size() && ok; ++k) {
      const uint32_t p = poly[k], q = poly[(k + 1) % poly.size()];
      const auto twin = open.find((static_cast<uint64_t>(q) << 32) | p);
      if (twin != open.end()) {
        a.f1[twin->second] = f;
        open.erase(twin);
        continue;
      }
      const auto [it, inserted] = open.emplace((static_cast<uint64_t>(p) << 32) | q, static_cast<uint32_t>(a.v0.size()));
      ok = inserted;  // the same directed edge twice: not a manifold
      a.v0.push_back(p);
      a.v1.push_back(q);
      a.f0.push_back(f);
      a.f1.push_back(UINT32_MAX);
    }
  }
  if (!ok || !open.empty()) return Adjacency{};
  return a;
}

void add_adjacency(const HullData& h, HullStore* st) {
  HullStore& s = *st;
  const Adjacency a = edge_adjacency(h);
  for (size_t e = 0; e < a.v0.size(); ++e) {
    s.ev0.push_back(a.v0[e]);
    s.ev1.push_back(a.v1[e]);
    s.ef0.push_back(a.f0[e]);
    s.ef1.push_back(a.f1[e]);
    s.epx.push_back(h.vertices[a.v0[e]].x());
    s.epy.push_back(h.vertices[a.v0[e]].y());
    s.epz.push_back(h.vertices[a.v0[e]].z());
    s.edx.push_back(h.vertices[a.v1[e]].x() - h.vertices[a.v0[e]].x());
    s.edy.push_back(h.vertices[a.v1[e]].y() - h.vertices[a.v0[e]].y());
    s.edz.push_back(h.vertices[a.v1[e]].z() - h.vertices[a.v0[e]].z());
    const Eigen::Vector3d n0 = h.face_normals[a.f0[e]].cast<double>().normalized();
    const Eigen::Vector3d n1 = h.face_normals[a.f1[e]].cast<double>().normalized();
    const Eigen::Vector3d sum = n0 + n1;
    const double sl = sum.norm();
    const Eigen::Vector3d m = sl > 0 ? Eigen::Vector3d(sum / sl) : n0;
    s.emx.push_back(static_cast<float>(m.x()));
    s.emy.push_back(static_cast<float>(m.y()));
    s.emz.push_back(static_cast<float>(m.z()));
    // Rounded outward (cos down, sin up) so the cone still holds both normals.
    s.ecos.push_back(std::nextafter(static_cast<float>(0.5 * sl), 0.0f));
    s.esin.push_back(std::nextafter(static_cast<float>(0.5 * (n0 - n1).norm()), 2.0f));
  }
  // Padded to a multiple of kEdgePad with copies of the last edge (SIMD loops over
  // the edges need no tail; a repeated edge changes no maximum).
  while (!a.v0.empty() && (s.ev0.size() - s.adj_begin.back()) % kEdgePad != 0) {
    for (auto* v : {&s.ev0, &s.ev1, &s.ef0, &s.ef1}) v->push_back(v->back());
    for (auto* v : {&s.emx, &s.emy, &s.emz, &s.ecos, &s.esin, &s.epx, &s.epy, &s.epz, &s.edx, &s.edy, &s.edz})
      v->push_back(v->back());
  }
  s.adj_begin.push_back(static_cast<uint32_t>(s.ev0.size()));
}

}  // namespace

uint32_t HullStore::add(const HullData& h) {
  const uint32_t id = size();
  const uint32_t vbase = static_cast<uint32_t>(vx.size());
  for (const Eigen::Vector3f& v : h.vertices) {
    vx.push_back(v.x());
    vy.push_back(v.y());
    vz.push_back(v.z());
    vxyz.insert(vxyz.end(), {v.x(), v.y(), v.z(), 0.0f});
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
  add_adjacency(h, this);
  return id;
}

kernels::HullView HullStore::view() const {
  kernels::HullView v;
  v.vert_begin = vert_begin.data();
  v.vx = vx.data();
  v.vy = vy.data();
  v.vz = vz.data();
  v.vxyz = vxyz.data();
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
  v.adj_begin = adj_begin.data();
  v.ev0 = ev0.data();
  v.ev1 = ev1.data();
  v.ef0 = ef0.data();
  v.ef1 = ef1.data();
  v.emx = emx.data();
  v.emy = emy.data();
  v.emz = emz.data();
  v.ecos = ecos.data();
  v.esin = esin.data();
  v.epx = epx.data();
  v.epy = epy.data();
  v.epz = epz.data();
  v.edx = edx.data();
  v.edy = edy.data();
  v.edz = edz.data();
  return v;
}

}  // namespace impact
