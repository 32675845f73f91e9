// Quickhull in double (Barber, Dobkin, Huhdanpaa, "The Quickhull Algorithm for Convex
// Hulls", ACM TOMS 1996): an initial tetrahedron of extreme points, then repeatedly the
// farthest outside point of a face is added: the faces it sees (a connected set, found
// by a walk over face adjacency) are replaced by a cone from the point to their horizon,
// and their outside points are handed to the new faces. Afterwards, adjacent triangles
// coplanar within a relative 1e-6 are merged into polygons.
// Tolerances are relative to the bounding-box diagonal D: a point counts as outside a
// face when it is more than 1e-9 D above it (duplicates and points on faces are
// dropped); triangles merge when their vertices lie within 1e-6 D of the seed plane and
// their normals agree within ~1.4e-5 rad; a vertex within 1e-6 D of the straight line
// through its neighbours in every polygon holding it (a point on a hull edge) is dropped.
// Deterministic: faces are processed in creation order, ties go to the lowest index;
// the hash map only answers lookups (its iteration order never shapes the result).
#include "host/shapes/convex_hull.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <unordered_map>
#include <vector>

#include <Eigen/Geometry>

namespace impact {

namespace {

using Vec3d = Eigen::Vector3d;

struct Tri {
  uint32_t v[3];
  Vec3d n;
  double d;
  bool alive = true;
  std::vector<uint32_t> outside;
};

uint64_t edge_key(uint32_t a, uint32_t b) { return (static_cast<uint64_t>(a) << 32) | b; }

class Quickhull {
 public:
  Quickhull(const std::vector<Vec3d>& p, double eps) : p_(p), eps_(eps) {}

  void add_tri(uint32_t a, uint32_t b, uint32_t c, const Vec3d& fallback_n) {
    Tri t;
    t.v[0] = a;
    t.v[1] = b;
    t.v[2] = c;
    Vec3d n = (p_[b] - p_[a]).cross(p_[c] - p_[a]);
    const double l = n.norm();
    t.n = l > 0 ? Vec3d(n / l) : fallback_n;
    t.d = t.n.dot(p_[a]);
    const uint32_t id = static_cast<uint32_t>(tris_.size());
    edges_[edge_key(a, b)] = id;
    edges_[edge_key(b, c)] = id;
    edges_[edge_key(c, a)] = id;
    tris_.push_back(std::move(t));
  }

  double dist(const Tri& t, uint32_t i) const { return t.n.dot(p_[i]) - t.d; }

  /// Hands point i to the new face it is farthest outside of (if any).
  void assign(uint32_t i, uint32_t first_face) {
    double best = eps_;
    uint32_t bf = UINT32_MAX;
    for (uint32_t f = first_face; f < tris_.size(); ++f) {
      if (!tris_[f].alive) continue;
      const double d = dist(tris_[f], i);
      if (d > best) {
        best = d;
        bf = f;
      }
    }
    if (bf != UINT32_MAX) tris_[bf].outside.push_back(i);
  }

  void run(uint32_t i0, uint32_t i1, uint32_t i2, uint32_t i3) {
    const double vol = (p_[i1] - p_[i0]).dot((p_[i2] - p_[i0]).cross(p_[i3] - p_[i0]));
    if (vol > 0) std::swap(i1, i2);  // i3 below face (i0, i1, i2)
    add_tri(i0, i1, i2, Vec3d::UnitZ());
    add_tri(i0, i3, i1, Vec3d::UnitZ());
    add_tri(i1, i3, i2, Vec3d::UnitZ());
    add_tri(i2, i3, i0, Vec3d::UnitZ());
    for (uint32_t i = 0; i < p_.size(); ++i) {
      if (i == i0 || i == i1 || i == i2 || i == i3) continue;
      assign(i, 0);
    }
    uint32_t cursor = 0;
    std::vector<uint32_t> visible, stack, orphans;
    std::vector<std::pair<uint32_t, uint32_t>> horizon;
    std::vector<uint8_t> mark;
    while (true) {
      while (cursor < tris_.size() && (!tris_[cursor].alive || tris_[cursor].outside.empty())) ++cursor;
      if (cursor == tris_.size()) break;
      Tri& f = tris_[cursor];
      uint32_t eye = f.outside[0];
      double bd = dist(f, eye);
      for (uint32_t i : f.outside)
        if (dist(f, i) > bd) {
          bd = dist(f, i);
          eye = i;
        }
      // Visible faces: connected walk from f.
      mark.assign(tris_.size(), 0);  // 0 unknown, 1 visible, 2 not visible
      visible.clear();
      stack.assign(1, cursor);
      mark[cursor] = 1;
      while (!stack.empty()) {
        const uint32_t t = stack.back();
        stack.pop_back();
        visible.push_back(t);
        for (int e = 0; e < 3; ++e) {
          const uint32_t a = tris_[t].v[e], b = tris_[t].v[(e + 1) % 3];
          const auto it = edges_.find(edge_key(b, a));
          if (it == edges_.end()) continue;
          const uint32_t u = it->second;
          if (mark[u] != 0) continue;
          if (dist(tris_[u], eye) > eps_) {
            mark[u] = 1;
            stack.push_back(u);
          } else {
            mark[u] = 2;
          }
        }
      }
      std::sort(visible.begin(), visible.end());
      horizon.clear();
      for (uint32_t t : visible) {
        for (int e = 0; e < 3; ++e) {
          const uint32_t a = tris_[t].v[e], b = tris_[t].v[(e + 1) % 3];
          const auto it = edges_.find(edge_key(b, a));
          if (it == edges_.end() || mark[it->second] != 1) horizon.emplace_back(a, b);
        }
      }
      orphans.clear();
      Vec3d fallback = tris_[cursor].n;
      for (uint32_t t : visible) {
        Tri& g = tris_[t];
        g.alive = false;
        for (uint32_t i : g.outside)
          if (i != eye) orphans.push_back(i);
        g.outside.clear();
        g.outside.shrink_to_fit();
        for (int e = 0; e < 3; ++e) {
          const auto it = edges_.find(edge_key(g.v[e], g.v[(e + 1) % 3]));
          if (it != edges_.end() && it->second == t) edges_.erase(it);
        }
      }
      const uint32_t first_new = static_cast<uint32_t>(tris_.size());
      for (const auto& [a, b] : horizon) add_tri(a, b, eye, fallback);
      std::sort(orphans.begin(), orphans.end());
      for (uint32_t i : orphans) assign(i, first_new);
    }
  }

  const std::vector<Tri>& tris() const { return tris_; }
  uint32_t face_across(uint32_t a, uint32_t b) const {
    const auto it = edges_.find(edge_key(b, a));
    return it == edges_.end() ? UINT32_MAX : it->second;
  }

 private:
  const std::vector<Vec3d>& p_;
  double eps_;
  std::vector<Tri> tris_;
  std::unordered_map<uint64_t, uint32_t> edges_;
};

Status invalid(std::string msg) { return Status(StatusCode::kInvalidArgument, std::move(msg)); }

}  // namespace

Status build_convex_hull(std::span<const Eigen::Vector3f> points, HullData* out) {
  const size_t n = points.size();
  if (n < 4) return invalid("convex hull: needs at least 4 points, got " + std::to_string(n));
  if (n >= UINT32_MAX) return invalid("convex hull: too many points");
  for (size_t i = 0; i < n; ++i)
    if (!points[i].allFinite()) return invalid("convex hull: point " + std::to_string(i) + " is not finite");
  std::vector<Vec3d> p(n);
  Vec3d lo = Vec3d::Constant(INFINITY), hi = Vec3d::Constant(-INFINITY);
  for (size_t i = 0; i < n; ++i) {
    p[i] = points[i].cast<double>();
    lo = lo.cwiseMin(p[i]);
    hi = hi.cwiseMax(p[i]);
  }
  const double diag = (hi - lo).norm();
  const double reject = 1e-6 * diag;
  if (!(diag > 0)) return invalid("convex hull: all points coincide");

  // Initial tetrahedron: the farthest pair among the axis extremes, the point farthest
  // from their line, the point farthest from their plane.
  uint32_t ext[6] = {0, 0, 0, 0, 0, 0};
  for (uint32_t i = 0; i < n; ++i)
    for (int a = 0; a < 3; ++a) {
      if (p[i][a] < p[ext[2 * a]][a]) ext[2 * a] = i;
      if (p[i][a] > p[ext[2 * a + 1]][a]) ext[2 * a + 1] = i;
    }
  uint32_t i0 = ext[0], i1 = ext[1];
  double best = -1;
  for (int a = 0; a < 6; ++a)
    for (int b = a + 1; b < 6; ++b) {
      const double d = (p[ext[a]] - p[ext[b]]).squaredNorm();
      if (d > best) {
        best = d;
        i0 = ext[a];
        i1 = ext[b];
      }
    }
  const Vec3d dir = (p[i1] - p[i0]).normalized();
  uint32_t i2 = i0;
  best = -1;
  for (uint32_t i = 0; i < n; ++i) {
    const double d = (p[i] - p[i0]).cross(dir).norm();
    if (d > best) {
      best = d;
      i2 = i;
    }
  }
  if (!(best > reject))
    return invalid("convex hull: all points are collinear (within a relative 1e-6 of their extent)");
  const Vec3d pn = (p[i1] - p[i0]).cross(p[i2] - p[i0]).normalized();
  uint32_t i3 = i0;
  best = -1;
  for (uint32_t i = 0; i < n; ++i) {
    const double d = std::fabs(pn.dot(p[i] - p[i0]));
    if (d > best) {
      best = d;
      i3 = i;
    }
  }
  if (!(best > reject))
    return invalid("convex hull: all points are coplanar (within a relative 1e-6 of their extent)");

  Quickhull qh(p, 1e-9 * diag);
  qh.run(i0, i1, i2, i3);
  const std::vector<Tri>& tris = qh.tris();

  // Merge coplanar neighbours: region growing from each unassigned triangle in order,
  // against the seed's plane (no drift along a chain of nearly coplanar triangles).
  const double merge_tol = 1e-6 * diag;
  std::vector<int64_t> group(tris.size(), -1);
  std::vector<std::vector<uint32_t>> polys;
  std::vector<uint32_t> members, stack;
  for (uint32_t t = 0; t < tris.size(); ++t) {
    if (!tris[t].alive || group[t] >= 0) continue;
    const int64_t g = static_cast<int64_t>(polys.size());
    const Vec3d sn = tris[t].n;
    const double sd = tris[t].d;
    members.clear();
    stack.assign(1, t);
    group[t] = g;
    while (!stack.empty()) {
      const uint32_t u = stack.back();
      stack.pop_back();
      members.push_back(u);
      for (int e = 0; e < 3; ++e) {
        const uint32_t w = qh.face_across(tris[u].v[e], tris[u].v[(e + 1) % 3]);
        if (w == UINT32_MAX || group[w] >= 0 || !tris[w].alive) continue;
        // Normals within ~1.4e-5 rad as well: a region grown by distance alone could
        // turn non-convex on a gently curved surface.
        bool coplanar = sn.dot(tris[w].n) > 1.0 - 1e-10;
        for (int k = 0; k < 3 && coplanar; ++k) coplanar = std::fabs(sn.dot(p[tris[w].v[k]]) - sd) <= merge_tol;
        if (coplanar) {
          group[w] = g;
          stack.push_back(w);
        }
      }
    }
    std::sort(members.begin(), members.end());
    // Boundary edges, chained into one loop from the first member's first boundary edge.
    std::unordered_map<uint32_t, uint32_t> next;
    std::vector<std::pair<uint32_t, uint32_t>> bedges;
    bool ok = true;
    for (uint32_t u : members)
      for (int e = 0; e < 3; ++e) {
        const uint32_t a = tris[u].v[e], b = tris[u].v[(e + 1) % 3];
        const uint32_t w = qh.face_across(a, b);
        if (w != UINT32_MAX && group[w] == g) continue;
        bedges.emplace_back(a, b);
        if (!next.emplace(a, b).second) ok = false;  // pinched boundary
      }
    std::vector<uint32_t> loop;
    if (ok && !bedges.empty()) {
      uint32_t v = bedges[0].first;
      for (size_t k = 0; k < bedges.size(); ++k) {
        loop.push_back(v);
        const auto it = next.find(v);
        if (it == next.end()) {
          ok = false;
          break;
        }
        v = it->second;
      }
      ok = ok && v == bedges[0].first && loop.size() == bedges.size();
    }
    // The merged polygon must be convex (two nearly coplanar slivers can meet at an
    // in-plane reflex corner); otherwise its triangles stay separate faces.
    if (ok && members.size() > 1) {
      const size_t m = loop.size();
      for (size_t k = 0; k < m && ok; ++k) {
        const Vec3d e0 = p[loop[(k + 1) % m]] - p[loop[k]], e1 = p[loop[(k + 2) % m]] - p[loop[(k + 1) % m]];
        ok = e0.cross(e1).dot(sn) >= -1e-6 * e0.norm() * e1.norm();
      }
    }
    if (ok) {
      polys.push_back(loop);
    } else {
      // Not a simple disc (cannot happen on a convex surface; kept as triangles).
      for (uint32_t u : members) {
        group[u] = static_cast<int64_t>(polys.size());
        polys.push_back({tris[u].v[0], tris[u].v[1], tris[u].v[2]});
      }
    }
  }

  // Drop vertices that lie on a straight hull edge: collinear with their neighbours in
  // every polygon that holds them (on a convex surface: the two faces of that edge).
  {
    std::vector<uint8_t> keep(n, 0);  // bit 0: seen, bit 1: a true corner somewhere
    for (const auto& poly : polys) {
      const size_t m = poly.size();
      for (size_t k = 0; k < m; ++k) {
        const Vec3d& a = p[poly[(k + m - 1) % m]];
        const Vec3d& b = p[poly[k]];
        const Vec3d& c = p[poly[(k + 1) % m]];
        const Vec3d ac = c - a;
        const double l2 = ac.squaredNorm();
        const double t = l2 > 0 ? (b - a).dot(ac) / l2 : 0.0;
        const bool on_segment = t > 0 && t < 1 && (a + ac * t - b).norm() <= merge_tol;
        keep[poly[k]] |= on_segment ? 1 : 3;
      }
    }
    for (auto& poly : polys) {
      std::vector<uint32_t> kept;
      for (uint32_t v : poly)
        if (keep[v] & 2) kept.push_back(v);
      if (kept.size() >= 3) poly = std::move(kept);
    }
  }

  // Output: vertices numbered by first use.
  HullData h;
  std::vector<uint32_t> remap(n, UINT32_MAX);
  for (const auto& poly : polys) {
    std::vector<uint32_t> f;
    f.reserve(poly.size());
    Vec3d nn = Vec3d::Zero();
    const Vec3d& o = p[poly[0]];
    for (size_t k = 0; k < poly.size(); ++k) {
      const uint32_t a = poly[k], b = poly[(k + 1) % poly.size()];
      nn += (p[a] - o).cross(p[b] - o);
      if (remap[a] == UINT32_MAX) {
        remap[a] = static_cast<uint32_t>(h.vertices.size());
        h.vertices.push_back(points[a]);
      }
      f.push_back(remap[a]);
    }
    nn.normalize();
    double off = -INFINITY;
    for (uint32_t a : poly) off = std::max(off, nn.dot(p[a]));
    h.faces.push_back(std::move(f));
    h.face_normals.push_back(nn.cast<float>());
    h.face_offsets.push_back(static_cast<float>(off));
  }
  // One edge direction per parallel class.
  std::vector<Vec3d> dirs;
  for (const auto& f : h.faces)
    for (size_t k = 0; k < f.size(); ++k) {
      const Vec3d d = (h.vertices[f[(k + 1) % f.size()]] - h.vertices[f[k]]).cast<double>().normalized();
      bool seen = false;
      for (const Vec3d& e : dirs) seen = seen || std::fabs(e.dot(d)) > 1.0 - 1e-7;  // 4.5e-4 rad
      if (!seen) dirs.push_back(d);
    }
  for (const Vec3d& d : dirs) h.edge_dirs.push_back(d.cast<float>());
  *out = std::move(h);
  return Status();
}

}  // namespace impact
