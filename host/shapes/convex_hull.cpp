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
// Cost: each step walks its cone (triangle adjacency, no global pass), and only the
// visible faces' conflict lists are handed on; the edge classes take O(1) expected per
// edge (a hash grid): O(n log n) in practice, also when every point is a vertex.
// Deterministic: faces are processed in creation order, ties go to the lowest index;
// the hash grid only answers lookups (its order never shapes the result).
#include "host/shapes/convex_hull.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Geometry>

namespace impact {

namespace {

using Vec3d = Eigen::Vector3d;

constexpr uint32_t kNone = UINT32_MAX;

/// A triangle of the hull under construction. nb[e] is the face across the edge
/// v[e] -> v[(e + 1) % 3] (kNone: none); head/tail: its conflict list (points outside
/// it, linked through Quickhull::next_, in the order they were handed to it).
struct Tri {
  uint32_t v[3];
  uint32_t nb[3] = {kNone, kNone, kNone};
  Vec3d n;
  double d;
  uint32_t head = kNone, tail = kNone;
  bool alive = true;
};

/// The hull's triangles with their adjacency, so that adding a point costs its cone:
/// the visible faces and their rim are found by a walk over nb, the new faces are
/// linked to the rim and to each other through per-vertex slots, and only the points
/// of the visible faces' conflict lists are handed on, to the new faces (Barber,
/// Dobkin, Huhdanpaa 1996, section 3; O(n log n) expected for points in general
/// position, as their analysis of conflict lists).
class Quickhull {
 public:
  Quickhull(const std::vector<Vec3d>& p, double eps)
      : p_(p), eps_(eps), next_(p.size(), kNone), cone_from_(p.size(), kNone), cone_to_(p.size(), kNone) {}

  uint32_t add_tri(uint32_t a, uint32_t b, uint32_t c, const Vec3d& fallback_n) {
    Tri t;
    t.v[0] = a;
    t.v[1] = b;
    t.v[2] = c;
    Vec3d n = (p_[b] - p_[a]).cross(p_[c] - p_[a]);
    const double l = n.norm();
    t.n = l > 0 ? Vec3d(n / l) : fallback_n;
    t.d = t.n.dot(p_[a]);
    tris_.push_back(t);
    return static_cast<uint32_t>(tris_.size() - 1);
  }

  double dist(const Tri& t, uint32_t i) const { return t.n.dot(p_[i]) - t.d; }

  /// Hands point i to the new face it is farthest outside of (if any).
  void assign(uint32_t i, uint32_t first_face) {
    double best = eps_;
    uint32_t bf = kNone;
    for (uint32_t f = first_face; f < tris_.size(); ++f) {
      if (!tris_[f].alive) continue;
      const double d = dist(tris_[f], i);
      if (d > best) {
        best = d;
        bf = f;
      }
    }
    if (bf == kNone) return;
    Tri& t = tris_[bf];
    next_[i] = kNone;
    if (t.tail == kNone) {
      t.head = i;
    } else {
      next_[t.tail] = i;
    }
    t.tail = i;
  }

  void run(uint32_t i0, uint32_t i1, uint32_t i2, uint32_t i3) {
    const double vol = (p_[i1] - p_[i0]).dot((p_[i2] - p_[i0]).cross(p_[i3] - p_[i0]));
    if (vol > 0) std::swap(i1, i2);  // i3 below face (i0, i1, i2)
    add_tri(i0, i1, i2, Vec3d::UnitZ());
    add_tri(i0, i3, i1, Vec3d::UnitZ());
    add_tri(i1, i3, i2, Vec3d::UnitZ());
    add_tri(i2, i3, i0, Vec3d::UnitZ());
    for (uint32_t t = 0; t < 4; ++t)
      for (int e = 0; e < 3; ++e) tris_[t].nb[e] = find_across(t, e, 0, 4);
    for (uint32_t i = 0; i < p_.size(); ++i) {
      if (i == i0 || i == i1 || i == i2 || i == i3) continue;
      assign(i, 0);
    }
    uint32_t cursor = 0;
    std::vector<uint32_t> visible, stack, orphans, touched;
    struct RimEdge {
      uint32_t a, b, across;
    };
    std::vector<RimEdge> horizon;
    std::vector<uint8_t> mark;
    while (true) {
      while (cursor < tris_.size() && (!tris_[cursor].alive || tris_[cursor].head == kNone)) ++cursor;
      if (cursor == tris_.size()) break;
      const Tri& f = tris_[cursor];
      uint32_t eye = f.head;
      double bd = dist(f, eye);
      for (uint32_t i = f.head; i != kNone; i = next_[i])
        if (dist(f, i) > bd) {
          bd = dist(f, i);
          eye = i;
        }
      // Visible faces: connected walk from f. `mark` is all 0 between iterations: the
      // faces marked here are reset from `touched` below, so an iteration costs the
      // size of the cone and its rim, not the number of faces ever made.
      mark.resize(tris_.size(), 0);  // 0 unknown, 1 visible, 2 not visible
      visible.clear();
      touched.assign(1, cursor);
      stack.assign(1, cursor);
      mark[cursor] = 1;
      while (!stack.empty()) {
        const uint32_t t = stack.back();
        stack.pop_back();
        visible.push_back(t);
        for (int e = 0; e < 3; ++e) {
          const uint32_t u = tris_[t].nb[e];
          if (u == kNone || mark[u] != 0) continue;
          touched.push_back(u);
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
      for (uint32_t t : visible)
        for (int e = 0; e < 3; ++e) {
          const uint32_t u = tris_[t].nb[e];
          if (u == kNone || mark[u] != 1) horizon.push_back({tris_[t].v[e], tris_[t].v[(e + 1) % 3], u});
        }
      for (uint32_t t : touched) mark[t] = 0;
      orphans.clear();
      const Vec3d fallback = tris_[cursor].n;
      for (uint32_t t : visible) {
        Tri& g = tris_[t];
        g.alive = false;
        for (uint32_t i = g.head; i != kNone; i = next_[i])
          if (i != eye) orphans.push_back(i);
        g.head = g.tail = kNone;
      }
      // The cone: face k = (a_k, b_k, eye) across its rim edge from the face that stays,
      // and across (b_k, eye) and (eye, a_k) from the cone faces starting at b_k and
      // ending at a_k.
      const uint32_t first_new = static_cast<uint32_t>(tris_.size());
      for (const RimEdge& r : horizon) {
        const uint32_t c = add_tri(r.a, r.b, eye, fallback);
        tris_[c].nb[0] = r.across;
        if (r.across != kNone) {
          Tri& u = tris_[r.across];
          for (int e = 0; e < 3; ++e)
            if (u.v[e] == r.b && u.v[(e + 1) % 3] == r.a) u.nb[e] = c;
        }
        cone_from_[r.a] = c;
        cone_to_[r.b] = c;
      }
      for (uint32_t c = first_new; c < tris_.size(); ++c) {
        tris_[c].nb[1] = cone_from_[tris_[c].v[1]];
        tris_[c].nb[2] = cone_to_[tris_[c].v[0]];
      }
      for (const RimEdge& r : horizon) cone_from_[r.a] = cone_to_[r.b] = kNone;
      std::sort(orphans.begin(), orphans.end());
      for (uint32_t i : orphans) assign(i, first_new);
    }
  }

  const std::vector<Tri>& tris() const { return tris_; }

 private:
  /// The face in [begin, end) holding the reverse of tris_[t]'s edge e (setup only).
  uint32_t find_across(uint32_t t, int e, uint32_t begin, uint32_t end) const {
    const uint32_t a = tris_[t].v[e], b = tris_[t].v[(e + 1) % 3];
    for (uint32_t u = begin; u < end; ++u)
      for (int k = 0; k < 3; ++k)
        if (tris_[u].v[k] == b && tris_[u].v[(k + 1) % 3] == a) return u;
    return kNone;
  }

  const std::vector<Vec3d>& p_;
  double eps_;
  std::vector<Tri> tris_;
  std::vector<uint32_t> next_;                 // conflict-list link per point
  std::vector<uint32_t> cone_from_, cone_to_;  // per vertex, while a cone is linked
};

/// Unit directions reduced to one per parallel class, greedily in the order offered: a
/// direction is kept unless a kept one satisfies |e.d| > 1 - 1e-7 (about 4.5e-4 rad,
/// either sign). Such an e lies within 4.48e-4 of d or -d per axis, so a kept e is
/// filed under every grid cell (edge 1/256) that the boxes of half side 4.5e-4 about e
/// and -e touch (about 4 cells in all), and a query reads d's own cell only. Cost: O(1)
/// expected per direction, about two cache misses (open addressing with the cell's key
/// and chain head in one slot, the direction in the chain node; the table only answers
/// lookups, its order never shapes the result).
class ParallelClasses {
 public:
  /// Offers unit d; returns true (and keeps it) when no kept direction is parallel.
  bool add(const Vec3d& d) {
    for (uint32_t node = find(cell_key(d)); node != kNone; node = nodes_[node].next)
      if (std::fabs(nodes_[node].d.dot(d)) > 1.0 - 1e-7) return false;
    kept_.push_back(d);
    file(d);
    file(-d);
    return true;
  }
  const std::vector<Vec3d>& kept() const { return kept_; }

 private:
  static constexpr double kCellsPerUnit = 256.0;
  static constexpr double kReach = 4.5e-4;  // > sqrt(2e-7) + rounding
  static constexpr uint64_t kEmpty = UINT64_MAX;
  struct Slot {
    uint64_t key = kEmpty;
    uint32_t head = kNone;
  };
  struct Node {
    Vec3d d;
    uint32_t next;
  };

  /// Cell coordinate of x in [-1 - kReach, 1 + kReach]: 0 .. 512.
  static uint64_t coord(double x) {
    return static_cast<uint64_t>(std::clamp(std::floor((x + 1.0) * kCellsPerUnit), 0.0, 2 * kCellsPerUnit));
  }
  static uint64_t key(uint64_t cx, uint64_t cy, uint64_t cz) { return (cx << 20) | (cy << 10) | cz; }
  static uint64_t cell_key(const Vec3d& d) { return key(coord(d.x()), coord(d.y()), coord(d.z())); }
  size_t slot_of(uint64_t k) const { return static_cast<size_t>((k * 0x9E3779B97F4A7C15ull) >> shift_); }
  uint32_t find(uint64_t k) const {
    if (slots_.empty()) return kNone;
    for (size_t s = slot_of(k);; s = (s + 1) & (slots_.size() - 1)) {
      if (slots_[s].key == k) return slots_[s].head;
      if (slots_[s].key == kEmpty) return kNone;
    }
  }
  void file(const Vec3d& e) {
    uint64_t lo[3], hi[3];
    for (int a = 0; a < 3; ++a) {
      lo[a] = coord(e[a] - kReach);
      hi[a] = coord(e[a] + kReach);
    }
    for (uint64_t x = lo[0]; x <= hi[0]; ++x)
      for (uint64_t y = lo[1]; y <= hi[1]; ++y)
        for (uint64_t z = lo[2]; z <= hi[2]; ++z) file_in(key(x, y, z), e);
  }
  void file_in(uint64_t k, const Vec3d& e) {
    if (2 * (used_ + 1) > slots_.size()) grow();
    size_t s = slot_of(k);
    while (slots_[s].key != k && slots_[s].key != kEmpty) s = (s + 1) & (slots_.size() - 1);
    if (slots_[s].key == kEmpty) {
      slots_[s].key = k;
      ++used_;
    }
    nodes_.push_back({e, slots_[s].head});
    slots_[s].head = static_cast<uint32_t>(nodes_.size() - 1);
  }
  void grow() {
    const std::vector<Slot> old = std::move(slots_);
    const size_t size = old.empty() ? 256 : 2 * old.size();
    slots_.assign(size, Slot{});
    shift_ = 64 - std::countr_zero(size);
    for (const Slot& o : old) {
      if (o.key == kEmpty) continue;
      size_t s = slot_of(o.key);
      while (slots_[s].key != kEmpty) s = (s + 1) & (size - 1);
      slots_[s] = o;
    }
  }

  std::vector<Vec3d> kept_;
  std::vector<Slot> slots_;
  std::vector<Node> nodes_;  // a cell's chain: head, then next
  size_t used_ = 0;
  int shift_ = 64;
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
  std::vector<uint32_t> next_of(n, kNone);
  std::vector<std::pair<uint32_t, uint32_t>> bedges;
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
        const uint32_t w = tris[u].nb[e];
        if (w == kNone || group[w] >= 0 || !tris[w].alive) continue;
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
    // Boundary edges, chained into one loop from the first member's first boundary edge
    // (next_of: per vertex, the boundary edge leaving it; reset after each group).
    bedges.clear();
    bool ok = true;
    for (uint32_t u : members)
      for (int e = 0; e < 3; ++e) {
        const uint32_t a = tris[u].v[e], b = tris[u].v[(e + 1) % 3];
        const uint32_t w = tris[u].nb[e];
        if (w != kNone && group[w] == g) continue;
        bedges.emplace_back(a, b);
        if (next_of[a] != kNone) ok = false;  // pinched boundary
        next_of[a] = b;
      }
    std::vector<uint32_t> loop;
    if (ok && !bedges.empty()) {
      uint32_t v = bedges[0].first;
      for (size_t k = 0; k < bedges.size(); ++k) {
        loop.push_back(v);
        if (next_of[v] == kNone) {
          ok = false;
          break;
        }
        v = next_of[v];
      }
      ok = ok && v == bedges[0].first && loop.size() == bedges.size();
    }
    for (const auto& [a, b] : bedges) next_of[a] = kNone;
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
  // One edge direction per parallel class, the first met in face order.
  ParallelClasses classes;
  for (const auto& f : h.faces)
    for (size_t k = 0; k < f.size(); ++k)
      classes.add((h.vertices[f[(k + 1) % f.size()]] - h.vertices[f[k]]).cast<double>().normalized());
  for (const Vec3d& d : classes.kept()) h.edge_dirs.push_back(d.cast<float>());
  *out = std::move(h);
  return Status();
}

}  // namespace impact
