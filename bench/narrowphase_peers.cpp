// Peer narrow phases on the scenes of bench/narrowphase_bench.cpp (bench/scenes/
// narrow_scenes.h: same shapes, same poses, about half the pairs overlapping), in the
// same executable and run. Each peer is compiled in only when its Debian package is
// found (bench/CMakeLists.txt; scripts/install_deps.sh --peers installs them):
//   FCL 0.7 (libfcl-dev), double precision: fcl::collide(geometry, transform, ...)
//     with request.enable_contact = true, num_max_contacts = 4 and the default GJK
//     solver (GST_LIBCCD; FCL's analytic routines where it has them). Shapes: Sphere,
//     Capsule (radius, length = 2 * half length, axis z), Box (side = 2 * half
//     extent), Convex (the library's hull of the scene's points: vertices and
//     polygon faces), Cylinder, Ellipsoid, Halfspace (n, n.p) and, for triangles, a
//     BVHModel<OBBRSS> of the one triangle in world coordinates.
//   libccd 2 (libccd-dev), double precision, with support callbacks over the scene's
//     bodies (narrow::support: the same functions the generator uses), for every
//     bounded pair (not half-spaces):
//       BM_CcdGjk     ccdGJKIntersect     boolean only
//       BM_CcdMpr     ccdMPRPenetration   depth, direction, one point
//       BM_CcdGjkEpa  ccdGJKPenetration   depth, direction, one point (GJK + EPA)
//     max_iterations 100, default tolerances (1e-4 for MPR and EPA).
// Only the query is timed; building the peers' objects is not. Single-threaded, CPU
// time, n = 4096 lanes. Counters as in narrowphase_bench.cpp: ns_per_pair, hits (lanes
// the peer reports in contact), expected (lanes the generator placed overlapping),
// near_touch, disagree (lanes whose answer contradicts the placement outside the
// near-touch band; from one untimed pass after the timed loop), and from the same pass,
// for the peers that return a contact, how it compares with ours (class Agreement:
// depth_dev_*, normal_dev_deg_*, excess_*, self_gap_max; scripts/peer_accuracy_table.py).
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "bench/scenes/narrow_scenes.h"

#ifndef IMPACT_BENCH_HAVE_FCL
#define IMPACT_BENCH_HAVE_FCL 0
#endif
#ifndef IMPACT_BENCH_HAVE_CCD
#define IMPACT_BENCH_HAVE_CCD 0
#endif

#if IMPACT_BENCH_HAVE_FCL
#include <fcl/geometry/bvh/BVH_model.h>
#include <fcl/geometry/shape/box.h>
#include <fcl/geometry/shape/capsule.h>
#include <fcl/geometry/shape/convex.h>
#include <fcl/geometry/shape/cylinder.h>
#include <fcl/geometry/shape/ellipsoid.h>
#include <fcl/geometry/shape/halfspace.h>
#include <fcl/geometry/shape/sphere.h>
#include <fcl/math/bv/OBBRSS.h>
#include <fcl/narrowphase/collision.h>
#endif
#if IMPACT_BENCH_HAVE_CCD
#include <ccd/ccd.h>
#endif

namespace {

namespace nb = impact::bench::narrow;

#if IMPACT_BENCH_HAVE_FCL || IMPACT_BENCH_HAVE_CCD
constexpr uint32_t kPeerLanes = 4096;

// hit[k]: the peer's answer for lane k (from one untimed pass after the timed loop).
void set_peer_counters(benchmark::State& state, const nb::PairScene& s, double ns,
                       const std::vector<uint8_t>& hit) {
  const uint32_t n = s.n;
  uint64_t hits = 0;
  for (uint8_t h : hit) hits += h;
  const double pairs = static_cast<double>(state.iterations()) * n;
  state.counters["ns_per_pair"] = pairs > 0 ? ns / pairs : 0.0;
  state.counters["hits"] = static_cast<double>(hits);
  state.counters["expected"] = static_cast<double>(s.expected_hits);
  state.counters["near_touch"] = static_cast<double>(s.near_touch);
  state.counters["disagree"] =
      static_cast<double>(nb::disagreements(s, [&](uint32_t k) { return hit[k] != 0; }));
  state.counters["hit_frac"] = n ? static_cast<double>(hits) / n : 0.0;
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations()) * n);
}

// How a peer's contacts compare with ours, on the lanes both report touching (from the
// untimed pass). With size = the two bodies' bounding radii (A's alone against a
// half-space) and overlap(n) = max over A of n.x - min over B of n.y along a unit n
// (A to B), in double from the generator's support functions (every n gives at least
// the penetration depth, the least overlap over n, so of two normals the one of smaller
// overlap is the better answer):
//   depth_dev   |the peer's depth - ours| / size
//   normal_dev  the angle between the two normals, degrees
//   excess      (overlap(peer's normal) - overlap(our normal)) / size: > 0 where our
//               normal is the better one, < 0 where the peer's is (bounded pairs only)
//   self_gap    |overlap(our normal) - our depth| / size: our own answer's consistency
// Counters: both_hit, the p50 / p99 / max of depth_dev and normal_dev (deg), the p50 /
// p99 / min of excess and the max of self_gap.
class Agreement {
 public:
  explicit Agreement(const nb::PairScene& s) : s_(s), ours_(nb::kernel_results(s)) {}

  /// Lane k: the peer touches with this depth and normal (any length, A to B).
  void add(uint32_t k, double depth, const double n[3]) {
    const nb::LaneResult& o = ours_[k];
    if (o.count == 0) return;
    const double nl = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    if (!(nl > 0)) {  // no direction (a peer may return a zero normal): worst case
      depth_dev_.push_back(std::fabs(depth - o.depth) / size(k));
      normal_dev_.push_back(180.0);
      return;
    }
    const double pn[3] = {n[0] / nl, n[1] / nl, n[2] / nl}, on[3] = {o.n[0], o.n[1], o.n[2]};
    const double c[3] = {pn[1] * on[2] - pn[2] * on[1], pn[2] * on[0] - pn[0] * on[2],
                         pn[0] * on[1] - pn[1] * on[0]};
    depth_dev_.push_back(std::fabs(depth - o.depth) / size(k));
    normal_dev_.push_back(std::atan2(std::sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]),
                                     pn[0] * on[0] + pn[1] * on[1] + pn[2] * on[2]) *
                          (180.0 / 3.14159265358979323846));
    if (s_.b[k].kind == nb::kHalfSpace) return;
    const double ol = std::sqrt(on[0] * on[0] + on[1] * on[1] + on[2] * on[2]);
    const double oun[3] = {on[0] / ol, on[1] / ol, on[2] / ol};
    const double o_ours = overlap(k, oun);
    excess_.push_back((overlap(k, pn) - o_ours) / size(k));
    self_gap_.push_back(std::fabs(o_ours - o.depth) / size(k));
  }

  void set_counters(benchmark::State& state) {
    state.counters["both_hit"] = static_cast<double>(depth_dev_.size());
    state.counters["depth_dev_p50"] = quantile(&depth_dev_, 0.5);
    state.counters["depth_dev_p99"] = quantile(&depth_dev_, 0.99);
    state.counters["depth_dev_max"] = quantile(&depth_dev_, 1.0);
    state.counters["normal_dev_deg_p50"] = quantile(&normal_dev_, 0.5);
    state.counters["normal_dev_deg_p99"] = quantile(&normal_dev_, 0.99);
    state.counters["normal_dev_deg_max"] = quantile(&normal_dev_, 1.0);
    if (excess_.empty()) return;
    state.counters["excess_p50"] = quantile(&excess_, 0.5);
    state.counters["excess_p99"] = quantile(&excess_, 0.99);
    state.counters["excess_min"] = quantile(&excess_, 0.0);
    state.counters["self_gap_max"] = quantile(&self_gap_, 1.0);
  }

 private:
  double size(uint32_t k) const { return nb::body_size(s_, s_.a[k]) + nb::body_size(s_, s_.b[k]); }
  double overlap(uint32_t k, const double n[3]) const {
    const double m[3] = {-n[0], -n[1], -n[2]};
    double sa[3], sb[3];
    nb::support(s_, s_.a[k], n, sa);
    nb::support(s_, s_.b[k], m, sb);
    return n[0] * (sa[0] - sb[0]) + n[1] * (sa[1] - sb[1]) + n[2] * (sa[2] - sb[2]);
  }
  static double quantile(std::vector<double>* v, double q) {
    if (v->empty()) return 0.0;
    const auto at = static_cast<size_t>(q * static_cast<double>(v->size() - 1));
    std::nth_element(v->begin(), v->begin() + static_cast<std::ptrdiff_t>(at), v->end());
    return (*v)[at];
  }

  const nb::PairScene& s_;
  std::vector<nb::LaneResult> ours_;
  std::vector<double> depth_dev_, normal_dev_, excess_, self_gap_;
};
#endif  // IMPACT_BENCH_HAVE_FCL || IMPACT_BENCH_HAVE_CCD

// --- FCL ------------------------------------------------------------------------------------
#if IMPACT_BENCH_HAVE_FCL

using Geometry = std::shared_ptr<fcl::CollisionGeometryd>;

// FCL's Convex of each hull of the scene (shared by the lanes that use it).
std::vector<Geometry> fcl_hulls(const nb::PairScene& s) {
  std::vector<Geometry> out;
  for (const nb::Hull& h : s.hulls) {
    auto verts = std::make_shared<std::vector<fcl::Vector3d>>();
    for (const auto& v : h.verts) verts->emplace_back(v[0], v[1], v[2]);
    auto faces = std::make_shared<std::vector<int>>(h.faces.begin(), h.faces.end());
    out.push_back(std::make_shared<fcl::Convexd>(verts, static_cast<int>(h.face_count), faces));
  }
  return out;
}

// The body as an FCL geometry and its transform.
Geometry fcl_geometry(const nb::Body& b, const std::vector<Geometry>& hulls, fcl::Transform3d* tf) {
  tf->setIdentity();
  fcl::Matrix3d r;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) r(i, j) = b.r[3 * i + j];
  const fcl::Vector3d p(b.p[0], b.p[1], b.p[2]);
  switch (b.kind) {
    case nb::kSphere:
      tf->linear() = r, tf->translation() = p;
      return std::make_shared<fcl::Sphered>(b.e[0]);
    case nb::kCapsule:
      tf->linear() = r, tf->translation() = p;
      return std::make_shared<fcl::Capsuled>(b.e[0], 2.0 * b.e[1]);
    case nb::kBox:
      tf->linear() = r, tf->translation() = p;
      return std::make_shared<fcl::Boxd>(2.0 * b.e[0], 2.0 * b.e[1], 2.0 * b.e[2]);
    case nb::kConvex:
      tf->linear() = r, tf->translation() = p;
      return hulls[b.hull];
    case nb::kCylinder:
      tf->linear() = r, tf->translation() = p;
      return std::make_shared<fcl::Cylinderd>(b.e[0], 2.0 * b.e[1]);
    case nb::kEllipsoid:
      tf->linear() = r, tf->translation() = p;
      return std::make_shared<fcl::Ellipsoidd>(b.e[0], b.e[1], b.e[2]);
    case nb::kTriangle: {
      auto m = std::make_shared<fcl::BVHModel<fcl::OBBRSSd>>();
      m->beginModel(1, 3);
      m->addTriangle(fcl::Vector3d(b.v[0], b.v[1], b.v[2]), fcl::Vector3d(b.v[3], b.v[4], b.v[5]),
                     fcl::Vector3d(b.v[6], b.v[7], b.v[8]));
      m->endModel();
      return m;
    }
    case nb::kHalfSpace: {
      const fcl::Vector3d n(b.e[0], b.e[1], b.e[2]);
      return std::make_shared<fcl::Halfspaced>(n, n.dot(p));
    }
    default:
      return nullptr;
  }
}

void BM_Fcl(benchmark::State& state, uint8_t ka, uint8_t kb) {
  const uint32_t n = static_cast<uint32_t>(state.range(0));
  const nb::PairScene& s = nb::pair_scene(ka, kb, n);
  for (const nb::Hull& h : s.hulls) {
    if (h.face_count == 0) {
      state.SkipWithError("hull faces not built");
      return;
    }
  }
  const std::vector<Geometry> hulls = fcl_hulls(s);
  std::vector<Geometry> ga(n), gb(n);
  std::vector<fcl::Transform3d> ta(n), tb(n);
  for (uint32_t k = 0; k < n; ++k) {
    ga[k] = fcl_geometry(s.a[k], hulls, &ta[k]);
    gb[k] = fcl_geometry(s.b[k], hulls, &tb[k]);
    if (!ga[k] || !gb[k]) {
      state.SkipWithError("FCL geometry not built");
      return;
    }
    ga[k]->computeLocalAABB();
    gb[k]->computeLocalAABB();
  }
  fcl::CollisionRequestd request(4, true);
  fcl::CollisionResultd result;
  uint64_t hits = 0;
  const double t0 = nb::thread_cpu_ns();
  for (auto _ : state) {
    hits = 0;
    for (uint32_t k = 0; k < n; ++k) {
      result.clear();
      hits += fcl::collide(ga[k].get(), ta[k], gb[k].get(), tb[k], request, result) > 0 ? 1 : 0;
    }
    benchmark::DoNotOptimize(hits);
  }
  const double ns = nb::thread_cpu_ns() - t0;
  std::vector<uint8_t> hit(n);
  Agreement agree(s);
  // FCL's shape-mesh contacts (a shape against our triangle, a one-triangle BVHModel)
  // give the normal from the mesh to the shape, against its documented convention (o1
  // to o2): measured ~180 degrees off on those pairs; compared here flipped. (Mesh-mesh
  // and mesh-half-space follow the convention.)
  const double sign = kb == nb::kTriangle && ka != nb::kTriangle ? -1.0 : 1.0;
  for (uint32_t k = 0; k < n; ++k) {
    result.clear();
    hit[k] = fcl::collide(ga[k].get(), ta[k], gb[k].get(), tb[k], request, result) > 0 ? 1 : 0;
    if (hit[k] == 0) continue;
    // The deepest of FCL's contacts (their normal is one: the first's).
    double depth = 0;
    for (size_t c = 0; c < result.numContacts(); ++c)
      depth = std::max(depth, result.getContact(c).penetration_depth);
    const fcl::Vector3d& fn = result.getContact(0).normal;
    const double dir[3] = {sign * fn.x(), sign * fn.y(), sign * fn.z()};
    agree.add(k, depth, dir);
  }
  set_peer_counters(state, s, ns, hit);
  agree.set_counters(state);
}

#endif  // IMPACT_BENCH_HAVE_FCL

// --- libccd ---------------------------------------------------------------------------------
#if IMPACT_BENCH_HAVE_CCD

struct CcdObject {
  const nb::PairScene* scene;
  const nb::Body* body;
};

void ccd_support(const void* obj, const ccd_vec3_t* dir, ccd_vec3_t* out) {
  const auto* o = static_cast<const CcdObject*>(obj);
  nb::support(*o->scene, *o->body, dir->v, out->v);
}

void ccd_centre(const void* obj, ccd_vec3_t* out) {
  nb::interior_point(*static_cast<const CcdObject*>(obj)->body, out->v);
}

enum class CcdQuery { kGjkIntersect, kMprPenetration, kGjkPenetration };

void BM_Ccd(benchmark::State& state, uint8_t ka, uint8_t kb, CcdQuery query) {
  const uint32_t n = static_cast<uint32_t>(state.range(0));
  const nb::PairScene& s = nb::pair_scene(ka, kb, n);
  std::vector<CcdObject> oa(n), ob(n);
  for (uint32_t k = 0; k < n; ++k) oa[k] = {&s, &s.a[k]}, ob[k] = {&s, &s.b[k]};
  ccd_t ccd;
  CCD_INIT(&ccd);
  ccd.support1 = ccd_support;
  ccd.support2 = ccd_support;
  ccd.center1 = ccd_centre;
  ccd.center2 = ccd_centre;
  ccd.max_iterations = 100;
  ccd_real_t depth = 0;  // the last lane's penetration (the queries that give one)
  ccd_vec3_t dir{}, pos{};
  auto lane = [&](uint32_t k) -> uint8_t {
    switch (query) {
      case CcdQuery::kGjkIntersect:
        return ccdGJKIntersect(&oa[k], &ob[k], &ccd) ? 1 : 0;
      case CcdQuery::kMprPenetration:
        return ccdMPRPenetration(&oa[k], &ob[k], &ccd, &depth, &dir, &pos) == 0 ? 1 : 0;
      case CcdQuery::kGjkPenetration:
        return ccdGJKPenetration(&oa[k], &ob[k], &ccd, &depth, &dir, &pos) == 0 ? 1 : 0;
    }
    return 0;
  };
  const double t0 = nb::thread_cpu_ns();
  for (auto _ : state) {
    uint64_t hits = 0;
    for (uint32_t k = 0; k < n; ++k) hits += lane(k);
    benchmark::DoNotOptimize(hits);
  }
  const double ns = nb::thread_cpu_ns() - t0;
  std::vector<uint8_t> hit(n);
  Agreement agree(s);
  for (uint32_t k = 0; k < n; ++k) {
    hit[k] = lane(k);
    if (hit[k] != 0 && query != CcdQuery::kGjkIntersect) agree.add(k, depth, dir.v);
  }
  set_peer_counters(state, s, ns, hit);
  if (query != CcdQuery::kGjkIntersect) agree.set_counters(state);
}

#endif  // IMPACT_BENCH_HAVE_CCD

}  // namespace

namespace impact::bench::narrow {

void register_peer_benchmarks(uint8_t ka, uint8_t kb) {
  const std::string name = pair_name(ka, kb);
#if IMPACT_BENCH_HAVE_FCL
  benchmark::RegisterBenchmark(("BM_Fcl/" + name).c_str(), BM_Fcl, ka, kb)
      ->Arg(kPeerLanes)
      ->Unit(benchmark::kMicrosecond);
#endif
#if IMPACT_BENCH_HAVE_CCD
  if (kb == kHalfSpace) return;  // unbounded: no support function
  for (const auto& [query, qname] :
       {std::pair{CcdQuery::kGjkIntersect, "BM_CcdGjk/"}, std::pair{CcdQuery::kMprPenetration, "BM_CcdMpr/"},
        std::pair{CcdQuery::kGjkPenetration, "BM_CcdGjkEpa/"}}) {
    benchmark::RegisterBenchmark((qname + name).c_str(), BM_Ccd, ka, kb, query)
        ->Arg(kPeerLanes)
        ->Unit(benchmark::kMicrosecond);
  }
#endif
  (void)name;
}

}  // namespace impact::bench::narrow
