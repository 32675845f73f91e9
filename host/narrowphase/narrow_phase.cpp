// impact::NarrowPhase: validation, expansion of meshes and compounds into leaf pairs,
// bucketing by leaf-type pair, gather into SoA, the per-bucket kernels, and the
// ordered output.
//
// Passes (each a for_each_chunk over a fixed grain, so the bytes never depend on
// the thread count):
//   poses      per object: the check of its shape id and pose, then quaternion ->
//              rotation matrix, with the record's e or hull index on the same 64-byte
//              line and its type in a byte array (one pass, in NarrowPhase::Impl::collide;
//              the World's step builds the same arrays)
//   expand     per pair: its leaf pairs (a shape, a compound child, a mesh triangle
//              found through the mesh's BVH), in (child_a, child_b) order, into
//              per-chunk lists concatenated in chunk order
//   bucket     key = (type_a * 8 + type_b) << 32 | record, LSD radix sort on the
//              type bits: buckets are contiguous and keep record order inside
//   gather + kernels  per block of up to 512 sorted positions of one bucket: both
//              sides into a thread's LeafSoA scratch (lane_arrays.h), then
//              pair_kernel(ta, tb) on it (a plain shape from its posed line alone, the
//              others through their records)
//   output     manifolds of touching records in record order = (pair, child_a,
//              child_b) order
#include <algorithm>
#include <cmath>
#include <string>

#include "host/narrowphase/lane_arrays.h"
#include "host/narrowphase/narrow_arrays.h"
#include "host/narrowphase/narrow_phase.h"
#include "host/parallel.h"
#include "host/radix_sort.h"
#include "host/scan.h"
#include "host/shapes/pose.h"
#include "host/shapes/shape_store.h"
#include "impact/narrowphase.h"
#include "kernels/narrowphase/leaf/leaf.h"
#include "kernels/narrowphase/plain/sphere_plane.h"
#include "kernels/narrowphase/plain/sphere_sphere.h"

namespace impact {

namespace {

using kernels::LeafType;

constexpr uint32_t kExpandGrain = 2048;
constexpr uint32_t kLaneGrain = 1024;
/// Lanes gathered and run together (both sides' scratch: ~90 KB, in L2).
constexpr uint32_t kLaneBlock = 512;
/// Pairs per chunk of the sphere buckets' count and write passes.
constexpr uint32_t kContactGrain = 1u << 13;

/// Sorted positions [begin, end) of one bucket.
struct Block {
  uint32_t begin, end;
};

/// One leaf pair: pair index, children (kNoChild for plain shapes), the leaf types
/// as stored (side 0 = the pair's a), and whether the kernel sees b as its A.
struct LeafPair {
  uint32_t pair;
  uint32_t child_a;
  uint32_t child_b;
  uint8_t type_a;
  uint8_t type_b;
  uint8_t swapped;
  uint8_t pad = 0;
};

struct Box3 {
  Eigen::Vector3f lo, hi;
  bool overlaps(const Box3& o) const {
    return (lo.array() <= o.hi.array()).all() && (o.lo.array() <= hi.array()).all();
  }
};

using Posed = host::PosedObject;

// Feature ids of manifold m's points (rows p0 ..): the quadrant of each point about the
// points' centroid, in body a's frame (ra: its rotation), within the plane of a's two
// axes least along the normal. A resting manifold's points then keep their ids (and
// their warm-start impulses) whatever order the kernel reports them in, which changes
// with rounding (a box on a box: the first corner turns with 1e-9 rad normal jitter).
// Ids 0..3 are quadrants; a one-point manifold, or one whose points share a quadrant,
// keeps slot ids 4 + k. Cost: a 3x3 product per point. (Box2D and Box3D key points by
// the clipping features instead; our kernels report none.)
void assign_features(const kernels::ContactManifoldArrays& c, uint32_t m, uint32_t p0, const Eigen::Matrix3f& ra) {
  const uint32_t count = c.count[m];
  uint32_t ids[kernels::kMaxManifoldPoints] = {};
  bool quadrants = count > 1;
  if (quadrants) {
    const Eigen::Vector3f n = ra.transpose() * Eigen::Vector3f(c.normal[0][m], c.normal[1][m], c.normal[2][m]);
    const int drop = std::abs(n.x()) >= std::abs(n.y()) ? (std::abs(n.x()) >= std::abs(n.z()) ? 0 : 2)
                                                        : (std::abs(n.y()) >= std::abs(n.z()) ? 1 : 2);
    const int u = drop == 0 ? 1 : 0, v = drop == 2 ? 1 : 2;
    Eigen::Vector3f centroid = Eigen::Vector3f::Zero();
    for (uint32_t k = 0; k < count; ++k)
      centroid += Eigen::Vector3f(c.point[0][p0 + k], c.point[1][p0 + k], c.point[2][p0 + k]);
    centroid /= static_cast<float>(count);
    uint32_t used = 0;
    for (uint32_t k = 0; k < count && quadrants; ++k) {
      const Eigen::Vector3f l =
          ra.transpose() * (Eigen::Vector3f(c.point[0][p0 + k], c.point[1][p0 + k], c.point[2][p0 + k]) - centroid);
      ids[k] = (l[u] > 0.0f ? 1u : 0u) | (l[v] > 0.0f ? 2u : 0u);
      quadrants = (used & (1u << ids[k])) == 0;
      used |= 1u << ids[k];
    }
  }
  for (uint32_t k = 0; k < count; ++k) c.feature[p0 + k] = quadrants ? ids[k] : 4 + k;
}

using host::LeafArrays;

}  // namespace

struct host::NarrowRunner::State {
  host::RadixSorter sorter;

  std::vector<std::vector<LeafPair>> chunk_records;
  std::vector<LeafPair> records;
  std::vector<size_t> chunk_offsets;
  std::vector<uint64_t> keys;
  std::vector<uint32_t> order;     // sorted position -> record (unless sorted)
  std::vector<uint32_t> position;  // record -> sorted position (unless sorted)
  bool sorted = false;             // the records were in bucket order: both maps are the identity
  uint32_t record_at(uint32_t s) const { return sorted ? s : order[s]; }
  uint32_t position_of(uint32_t record) const { return sorted ? record : position[record]; }
  std::vector<Block> blocks;
  host::ManifoldArrays manifold;
  std::vector<uint32_t> chunk_hits, chunk_points;
  host::Buffer<uint64_t> body_offsets, plane_offsets;  // run_spheres' count -> scan
  std::vector<uint32_t> chunk_bad;  // per expansion chunk: its first bad pair (checked runs)

  // Inputs of the current call.
  const ShapeStore* store = nullptr;
  const ShapeRecord* const* rec = nullptr;
  const ShapeType* types = nullptr;
  const Posed* posed = nullptr;
  host::PairList pairs;
  uint32_t first_plane = host::kNoPlanes;

  const ShapeRecord& shape(uint32_t obj) const { return *rec[obj]; }

  Status run(const host::Executor& exec, const host::NarrowObjects& objects, const host::PairList& pairs_in,
             const kernels::NarrowConfig& cfg_in, host::ContactManifolds* out, size_t* bad_pair,
             const host::ManifoldHook* hook);
  Status run_spheres(const host::Executor& exec, const host::SphereObjects& objects,
                     const host::PairList& pairs_in, host::ContactManifolds* out);

  // --- expansion ---------------------------------------------------------------------
  Box3 leaf_bounds(uint32_t obj, uint32_t child) const;
  void mesh_query(const MeshData& m, const Posed& pose, const Box3& world_box,
                  std::vector<uint32_t>* tris) const;
  void mesh_below_plane(const MeshData& m, const Posed& pose, const Eigen::Vector3f& n, double d,
                        std::vector<uint32_t>* tris) const;
  /// The one leaf pair of a pair of two plain shapes.
  LeafPair plain_record(uint32_t pair_index) const {
    const ShapeType ta = types[pairs[pair_index].a], tb = types[pairs[pair_index].b];
    LeafPair lp;
    lp.pair = pair_index;
    lp.child_a = kNoChild;
    lp.child_b = kNoChild;
    lp.type_a = host::leaf_type_of(ta);
    lp.type_b = host::leaf_type_of(tb);
    lp.swapped = lp.type_a > lp.type_b ? 1 : 0;
    return lp;
  }
  void expand(uint32_t pair_index, std::vector<LeafPair>* out, std::vector<uint32_t>* scratch_a,
              std::vector<uint32_t>* scratch_b) const;
  void child_list(uint32_t obj, const Box3& other, std::vector<uint32_t>* out) const;

  // --- gather ------------------------------------------------------------------------
  /// Lane k of s: object obj's leaf, a plain convex shape (not a half-space), from its
  /// PosedObject line alone. Lanes with a derived leaf take fill_relative.
  void fill(LeafArrays& s, size_t k, uint32_t obj) const;
  /// Whether a leaf pair of these objects is posed relative to an anchor (below): one
  /// side a half-space, a mesh or a compound, whose leaves the gather derives.
  bool anchored(uint32_t obj_a, uint32_t obj_b) const {
    auto derived = [&](uint32_t o) {
      const ShapeType t = types[o];
      return t == ShapeType::kHalfSpace || t == ShapeType::kMesh || t == ShapeType::kCompound;
    };
    return derived(obj_a) || derived(obj_b);
  }
  /// The anchor of a leaf pair whose kernel side A is object obj (child): its pose's
  /// position (an input, exact), or for a mesh its triangle's first corner (the mesh's
  /// pose may lie far from its triangles), rounded once.
  Eigen::Vector3f anchor_of(uint32_t obj, uint32_t child) const;
  /// Lane k of s: the leaf as fill() writes it, but every world position taken relative
  /// to the anchor o and rounded once from double: positions p - o, compound children
  /// (R c + p) - o, triangle corners (R v + p) - o, and for a half-space the point of its
  /// plane nearest o (the plane's height over o along the normal, in double).
  void fill_relative(LeafArrays& s, size_t k, uint32_t obj, uint32_t child, const Eigen::Vector3f& o) const;
};

namespace {
/// The box widened by 2^-21 of each coordinate's magnitude: the float posing of a
/// bound (R c + p, then +- the rotated extents) rounds each coordinate by at most ~2
/// ulps of its magnitude, which far from the origin exceeds a shallow contact's depth
/// (half an ulp is 3.9 mm at 1e5 m); the widened boxes cull no touching leaf pair.
Box3 widened(Box3 b) {
  for (int i = 0; i < 3; ++i) {
    const float slack = 0x1p-21f * (std::fabs(b.lo[i]) + std::fabs(b.hi[i]));
    b.lo[i] -= slack;
    b.hi[i] += slack;
  }
  return b;
}
}  // namespace

Box3 host::NarrowRunner::State::leaf_bounds(uint32_t obj, uint32_t child) const {
  const ShapeRecord& r = shape(obj);
  const Posed& P = posed[obj];
  Box3 b;
  if (r.type == ShapeType::kCompound && child != kNoChild) {
    const CompoundChild& c = store->children[store->child_begin[r.ref] + child];
    const ShapeRecord& cr = store->shapes[c.shape.index];
    host::posed_bounds(cr, P.R * c.local.orientation.toRotationMatrix(), P.R * c.local.position + P.p,
                       store->hulls, &b.lo, &b.hi);
    return widened(b);
  }
  if (r.type == ShapeType::kMesh && child != kNoChild) {
    const MeshData& m = store->meshes[r.ref];
    b.lo = Eigen::Vector3f::Constant(INFINITY);
    b.hi = -b.lo;
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3f v = P.R * m.vertices[m.indices[3 * child + k]] + P.p;
      b.lo = b.lo.cwiseMin(v);
      b.hi = b.hi.cwiseMax(v);
    }
    return widened(b);
  }
  host::posed_bounds(r, P.R, P.p, store->hulls, &b.lo, &b.hi);
  return widened(b);
}

void host::NarrowRunner::State::mesh_query(const MeshData& m, const Posed& pose, const Box3& world_box,
                                   std::vector<uint32_t>* tris) const {
  tris->clear();
  // The query box in the mesh's frame (conservative: the box of the rotated box).
  const Eigen::Vector3f c = (world_box.lo + world_box.hi) * 0.5f;
  const Eigen::Vector3f e = (world_box.hi - world_box.lo) * 0.5f;
  const Eigen::Vector3f lc = pose.R.transpose() * (c - pose.p);
  const Eigen::Vector3f le = pose.R.transpose().cwiseAbs() * e;
  // Float slack: the two transforms round; a triangle just touching the box must not
  // be lost (the kernel decides).
  const float slack = 1e-5f * (le.maxCoeff() + lc.cwiseAbs().maxCoeff());
  const Eigen::Vector3f qlo = lc - le - Eigen::Vector3f::Constant(slack);
  const Eigen::Vector3f qhi = lc + le + Eigen::Vector3f::Constant(slack);
  uint32_t stack[64];
  uint32_t top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const MeshData::Node& n = m.nodes[stack[--top]];
    if (n.lo[0] > qhi[0] || n.hi[0] < qlo[0] || n.lo[1] > qhi[1] || n.hi[1] < qlo[1] ||
        n.lo[2] > qhi[2] || n.hi[2] < qlo[2]) {
      continue;
    }
    if (n.count > 0) {
      for (uint32_t i = n.left_or_first; i < n.left_or_first + n.count; ++i) {
        tris->push_back(m.tri_order[i]);
      }
    } else {
      stack[top++] = n.right;
      stack[top++] = n.left_or_first;
    }
  }
  std::sort(tris->begin(), tris->end());
}

void host::NarrowRunner::State::mesh_below_plane(const MeshData& m, const Posed& pose, const Eigen::Vector3f& n,
                                         double d, std::vector<uint32_t>* tris) const {
  tris->clear();
  // Plane in the mesh frame: n_l . x <= d_l (d_l in double: far from the origin d and
  // n.p cancel, and in float each rounds by more than the slack below).
  const Eigen::Vector3f nl = pose.R.transpose() * n;
  const auto dl = static_cast<float>(d - n.cast<double>().dot(pose.p.cast<double>()));
  uint32_t stack[64];
  uint32_t top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const MeshData::Node& node = m.nodes[stack[--top]];
    float lowest = 0.0f, scale = std::fabs(dl);
    for (int k = 0; k < 3; ++k) {
      lowest += nl[k] * (nl[k] >= 0.0f ? node.lo[k] : node.hi[k]);
      scale += std::fabs(nl[k]) * std::max(std::fabs(node.lo[k]), std::fabs(node.hi[k]));
    }
    if (lowest > dl + 1e-6f * scale) continue;
    if (node.count > 0) {
      for (uint32_t i = node.left_or_first; i < node.left_or_first + node.count; ++i) {
        tris->push_back(m.tri_order[i]);
      }
    } else {
      stack[top++] = node.right;
      stack[top++] = node.left_or_first;
    }
  }
  std::sort(tris->begin(), tris->end());
}

void host::NarrowRunner::State::child_list(uint32_t obj, const Box3& other, std::vector<uint32_t>* out) const {
  out->clear();
  const ShapeRecord& r = shape(obj);
  if (r.type == ShapeType::kCompound) {
    const uint32_t n = store->child_begin[r.ref + 1] - store->child_begin[r.ref];
    for (uint32_t c = 0; c < n; ++c) {
      if (leaf_bounds(obj, c).overlaps(other)) out->push_back(c);
    }
  } else if (r.type == ShapeType::kMesh) {
    mesh_query(store->meshes[r.ref], posed[obj], other, out);
  } else {
    out->push_back(kNoChild);
  }
}

void host::NarrowRunner::State::expand(uint32_t pair_index, std::vector<LeafPair>* out,
                               std::vector<uint32_t>* ca, std::vector<uint32_t>* cb) const {
  const uint32_t a = pairs[pair_index].a, b = pairs[pair_index].b;
  // Two plain shapes (the common case): one leaf pair, from the objects' lines alone.
  const ShapeType ta = types[a], tb = types[b];
  const bool a_plain = ta != ShapeType::kCompound && ta != ShapeType::kMesh;
  const bool b_plain = tb != ShapeType::kCompound && tb != ShapeType::kMesh;
  if (a_plain && b_plain) {
    out->push_back(plain_record(pair_index));
    return;
  }
  const ShapeRecord& ra = shape(a);
  const ShapeRecord& rb = shape(b);
  auto leaf_type = [&](const ShapeRecord& r, uint32_t child) -> uint8_t {
    if (r.type == ShapeType::kCompound) {
      const CompoundChild& c = store->children[store->child_begin[r.ref] + child];
      return host::leaf_type_of(store->shapes[c.shape.index].type);
    }
    return host::leaf_type_of(r.type);
  };
  auto emit = [&](uint32_t child_a, uint32_t child_b) {
    LeafPair lp;
    lp.pair = pair_index;
    lp.child_a = child_a;
    lp.child_b = child_b;
    lp.type_a = leaf_type(ra, child_a);
    lp.type_b = leaf_type(rb, child_b);
    lp.swapped = lp.type_a > lp.type_b ? 1 : 0;
    out->push_back(lp);
  };
  // One side a half-space: the other side's children that reach below the plane.
  auto plane_of = [&](uint32_t obj, Eigen::Vector3f* n, double* d) {
    const ShapeRecord& r = shape(obj);
    *n = posed[obj].R * Eigen::Vector3f(r.e[0], r.e[1], r.e[2]);
    *d = static_cast<double>(r.offset) + n->cast<double>().dot(posed[obj].p.cast<double>());
  };
  auto children_below = [&](uint32_t obj, const Eigen::Vector3f& n, double dd, std::vector<uint32_t>* list) {
    const ShapeRecord& r = shape(obj);
    list->clear();
    if (r.type == ShapeType::kMesh) {
      mesh_below_plane(store->meshes[r.ref], posed[obj], n, dd, list);
      return;
    }
    const auto d = static_cast<float>(dd);
    const uint32_t count = store->child_begin[r.ref + 1] - store->child_begin[r.ref];
    for (uint32_t c = 0; c < count; ++c) {
      const Box3 bx = leaf_bounds(obj, c);
      float lowest = 0.0f, scale = std::fabs(d);
      for (int k = 0; k < 3; ++k) {
        lowest += n[k] * (n[k] >= 0.0f ? bx.lo[k] : bx.hi[k]);
        scale += std::fabs(n[k]) * std::max(std::fabs(bx.lo[k]), std::fabs(bx.hi[k]));
      }
      if (lowest <= d + 1e-6f * scale) list->push_back(c);
    }
  };
  if (ra.type == ShapeType::kHalfSpace || rb.type == ShapeType::kHalfSpace) {
    const bool plane_is_a = ra.type == ShapeType::kHalfSpace;
    Eigen::Vector3f n;
    double d;
    plane_of(plane_is_a ? a : b, &n, &d);
    children_below(plane_is_a ? b : a, n, d, ca);
    for (uint32_t c : *ca) plane_is_a ? emit(kNoChild, c) : emit(c, kNoChild);
    return;
  }
  // Children of a that touch b's bounds, then for each, children of b touching it.
  const Box3 box_b = leaf_bounds(b, kNoChild);
  child_list(a, box_b, ca);
  for (uint32_t c : *ca) {
    const Box3 box_c = a_plain ? leaf_bounds(a, kNoChild) : leaf_bounds(a, c);
    child_list(b, box_c, cb);
    for (uint32_t d : *cb) emit(c, d);
  }
}


IMPACT_INLINE void host::NarrowRunner::State::fill(LeafArrays& s, size_t k, uint32_t obj) const {
  // Lanes of two plain convex leaves (anchored() is false: no half-space, mesh or
  // compound, whose lanes take fill_relative): the pose as it is, and the record's fields
  // from the same line.
  const Posed& P = posed[obj];
  switch (types[obj]) {
    case ShapeType::kSphere:
      put_p(s, k, P.p);
      s.f[12][k] = P.leaf.e[0];
      return;
    case ShapeType::kAabb:
      put_p(s, k, P.p);
      put_r(s, k, Eigen::Matrix3f::Identity());
      put_e(s, k, P.leaf.e);
      return;
    case ShapeType::kConvex:
      put_p(s, k, P.p);
      put_r(s, k, P.R);
      s.ref[k] = P.leaf.ref;
      return;
    default:  // capsule, box, cylinder, ellipsoid
      put_p(s, k, P.p);
      put_r(s, k, P.R);
      put_e(s, k, P.leaf.e);
      return;
  }
}

Eigen::Vector3f host::NarrowRunner::State::anchor_of(uint32_t obj, uint32_t child) const {
  const ShapeRecord& r = shape(obj);
  const Posed& P = posed[obj];
  if (r.type != ShapeType::kMesh || child == kNoChild) return P.p;
  const MeshData& m = store->meshes[r.ref];
  const Eigen::Vector3d v = P.R.cast<double>() * m.vertices[m.indices[3 * child]].cast<double>() + P.p.cast<double>();
  return v.cast<float>();
}

void host::NarrowRunner::State::fill_relative(LeafArrays& s, size_t k, uint32_t obj, uint32_t child,
                                              const Eigen::Vector3f& o) const {
  const ShapeRecord* r = &shape(obj);
  const Posed& P = posed[obj];
  // The object's pose relative to o, in double: differences of floats are exact there.
  const Eigen::Vector3d od = o.cast<double>();
  Eigen::Matrix3f R = P.R;
  Eigen::Vector3d pd = P.p.cast<double>() - od;
  if (r->type == ShapeType::kCompound) {
    const CompoundChild& c = store->children[store->child_begin[r->ref] + child];
    pd += P.R.cast<double>() * c.local.position.cast<double>();
    R = P.R * c.local.orientation.toRotationMatrix();
    r = &store->shapes[c.shape.index];
  }
  const Eigen::Vector3f p = pd.cast<float>();
  const float* e = r->type == ShapeType::kCompound ? nullptr : r->e;
  switch (r->type) {
    case ShapeType::kSphere:
      put_p(s, k, p);
      s.f[12][k] = e[0];
      return;
    case ShapeType::kAabb:
      put_p(s, k, p);
      put_r(s, k, Eigen::Matrix3f::Identity());
      put_e(s, k, e);
      return;
    case ShapeType::kConvex:
      put_p(s, k, p);
      put_r(s, k, R);
      s.ref[k] = r->ref;
      return;
    case ShapeType::kHalfSpace:
      put_plane_relative(s, k, R, pd, e, r->offset);
      return;
    case ShapeType::kMesh: {
      const MeshData& m = store->meshes[r->ref];
      const Eigen::Matrix3d Rd = R.cast<double>();
      Eigen::Vector3f v[3];
      for (int j = 0; j < 3; ++j) v[j] = (Rd * m.vertices[m.indices[3 * child + j]].cast<double>() + pd).cast<float>();
      put_p(s, k, v[0]);
      for (int i = 0; i < 3; ++i) {
        s.f[15 + i][k] = v[1][i];
        s.f[18 + i][k] = v[2][i];
      }
      return;
    }
    default:  // capsule, box, cylinder, ellipsoid (plain or compound children)
      put_p(s, k, p);
      put_r(s, k, R);
      put_e(s, k, e);
      return;
  }
}

Status host::NarrowRunner::State::run(const host::Executor& exec, const host::NarrowObjects& objects,
                                      const host::PairList& pairs_in, const kernels::NarrowConfig& cfg_in,
                                      host::ContactManifolds* out, size_t* bad_pair,
                                      const host::ManifoldHook* hook) {
  store = objects.store;
  rec = objects.rec.data();
  types = objects.types.data();
  posed = objects.poses.data();
  pairs = pairs_in;
  first_plane = objects.first_plane;
  if (bad_pair != nullptr) *bad_pair = pairs_in.size();
  if (pairs_in.size() >= 0xffffffffu) {
    out->clear();
    return Status(StatusCode::kCapacityExceeded, "narrow phase: more than 2^32 - 2 pairs");
  }

  // Expansion into leaf-pair records. With meshes or compounds among the objects, per
  // chunk, concatenated in chunk order; without, every pair is one record, written in
  // place. A checked run checks each pair first and stops its chunk at the first bad one.
  const auto np = static_cast<uint32_t>(pairs_in.size());
  const auto object_count = static_cast<uint32_t>(objects.rec.size());
  const uint32_t chunks = host::chunk_count(np, kExpandGrain);
  chunk_bad.assign(chunks, 0xffffffffu);
  const uint32_t object_chunks = host::chunk_count(object_count, kLaneGrain * 16);
  chunk_hits.assign(object_chunks, 0);
  exec.for_each_chunk(object_count, kLaneGrain * 16, [&](uint32_t b, uint32_t e, uint32_t chunk) {
    uint32_t complex = 0;
    for (uint32_t i = b; i < e; ++i) complex |= (types[i] == ShapeType::kMesh) | (types[i] == ShapeType::kCompound);
    chunk_hits[chunk] = complex;
  });
  bool plain = true;
  for (uint32_t c = 0; c < object_chunks; ++c) plain = plain && chunk_hits[c] == 0;
  auto bad = [&](uint32_t k) {
    const kernels::Pair& pr = pairs[k];
    return pr.a >= object_count || pr.b >= object_count || pr.a == pr.b ||
           (types[pr.a] == ShapeType::kHalfSpace && types[pr.b] == ShapeType::kHalfSpace);
  };
  if (plain) {
    records.resize(np);
    exec.for_each_chunk(np, kExpandGrain, [&](uint32_t b, uint32_t e, uint32_t chunk) {
      for (uint32_t k = b; k < e; ++k) {
        if (bad_pair != nullptr && bad(k)) {
          chunk_bad[chunk] = k;
          return;
        }
        records[k] = plain_record(k);
      }
    });
  } else {
    chunk_records.resize(chunks);
    exec.for_each_chunk(np, kExpandGrain, [&](uint32_t b, uint32_t e, uint32_t chunk) {
      std::vector<LeafPair>& list = chunk_records[chunk];
      list.clear();
      std::vector<uint32_t> ca, cb;
      for (uint32_t k = b; k < e; ++k) {
        if (bad_pair != nullptr && bad(k)) {
          chunk_bad[chunk] = k;
          return;
        }
        expand(k, &list, &ca, &cb);
      }
    });
  }
  if (bad_pair != nullptr) {
    for (uint32_t c = 0; c < chunks; ++c) {
      if (chunk_bad[c] != 0xffffffffu) {
        *bad_pair = chunk_bad[c];  // *out untouched, as after the object checks
        return Status(StatusCode::kInvalidArgument, "narrow phase: bad pair");
      }
    }
  }
  size_t total = np;
  if (!plain) {
    total = 0;
    for (uint32_t c = 0; c < chunks; ++c) total += chunk_records[c].size();
    if (total >= 0xffffffffu) {
      out->clear();
      return Status(StatusCode::kCapacityExceeded,
                    "narrow phase: more than 2^32 - 2 leaf pairs after expanding meshes and compounds");
    }
    records.resize(total);
    chunk_offsets.resize(static_cast<size_t>(chunks) + 1);
    chunk_offsets[0] = 0;
    for (uint32_t c = 0; c < chunks; ++c) chunk_offsets[c + 1] = chunk_offsets[c] + chunk_records[c].size();
    exec.for_each_chunk(np, kExpandGrain, [&](uint32_t, uint32_t, uint32_t chunk) {
      std::copy(chunk_records[chunk].begin(), chunk_records[chunk].end(),
                records.begin() + static_cast<ptrdiff_t>(chunk_offsets[chunk]));
    });
  }
  const auto nr = static_cast<uint32_t>(total);

  // Buckets: stable sort of (type pair, record). Keys already in bucket order (one
  // bucket, or pairs listed by type) skip the sort, and the order is the identity.
  keys.resize(nr);
  const uint32_t key_chunks = host::chunk_count(nr, kLaneGrain * 16);
  chunk_points.assign(key_chunks, 0);  // per chunk: 1 when its keys descend somewhere
  exec.for_each_chunk(nr, kLaneGrain * 16, [&](uint32_t b, uint32_t e, uint32_t chunk) {
    uint32_t descends = 0;
    for (uint32_t i = b; i < e; ++i) {
      const LeafPair& lp = records[i];
      const uint32_t lo = std::min(lp.type_a, lp.type_b), hi = std::max(lp.type_a, lp.type_b);
      keys[i] = (static_cast<uint64_t>(lo * kernels::kLeafTypeCount + hi) << 32) | i;
      descends |= i > b && keys[i] < keys[i - 1] ? 1u : 0u;
    }
    chunk_points[chunk] = descends;
  });
  sorted = true;
  for (uint32_t c = 0; c < key_chunks && sorted; ++c) {
    const uint32_t first = c * kLaneGrain * 16;
    sorted = chunk_points[c] == 0 && (c == 0 || keys[first] > keys[first - 1]);
  }
  if (!sorted) {
    sorter.sort(exec, keys.data(), nr, 32, 32 + 6);
    order.resize(nr);
    position.resize(nr);
    exec.for_each_chunk(nr, kLaneGrain * 16, [&](uint32_t b, uint32_t e, uint32_t) {
      for (uint32_t s = b; s < e; ++s) {
        const auto record = static_cast<uint32_t>(keys[s]);
        order[s] = record;
        position[record] = s;
      }
    });
  }

  // Gather and kernels, fused per block: a block is up to kLaneBlock consecutive
  // sorted positions of one bucket (blocks depend on the buckets alone, so the bytes
  // do not depend on the thread count; a kernel's lane gives the same bytes for any
  // range partition, leaf.h). Both sides of a block are gathered into this thread's
  // scratch (side 0 is the kernel's A, the lower leaf type) and the kernel runs on it
  // at once, while the inputs are in cache: the gathered inputs never go to memory.
  manifold.resize(nr);
  blocks.clear();
  for (uint32_t begin = 0; begin < nr;) {
    const uint64_t bucket = keys[begin] >> 32;
    uint32_t end = begin + 1;
    while (end < nr && (keys[end] >> 32) == bucket) ++end;
    for (uint32_t b = begin; b < end; b += kLaneBlock) blocks.push_back({b, std::min(end, b + kLaneBlock)});
    begin = end;
  }
  kernels::NarrowConfig cfg = cfg_in;
  cfg.hulls = store->hulls.view();
  exec.for_each_chunk(blocks.size(), 1, [&](uint32_t bi, uint32_t, uint32_t) {
    const Block blk = blocks[bi];
    const uint64_t bucket = keys[blk.begin] >> 32;
    const kernels::PairKernel kernel = kernels::pair_kernel(static_cast<LeafType>(bucket / kernels::kLeafTypeCount),
                                                            static_cast<LeafType>(bucket % kernels::kLeafTypeCount));
    IMPACT_ASSERT(kernel != nullptr);
    thread_local LeafArrays scratch[2];
    if (scratch[0].size < kLaneBlock) {
      scratch[0].resize(kLaneBlock, host::LeafArrays::kPhaseA);
      scratch[1].resize(kLaneBlock, host::LeafArrays::kPhaseB);
    }
    // Lanes with a derived leaf (half-space, mesh triangle, compound child) are posed
    // relative to an anchor, a point of the pair (anchor_of), and their points moved
    // back after the kernel: posed in world floats, such a leaf would round by half an
    // ulp of its coordinates (3.9 mm at 1e5 m), while the kernels compute relative to a
    // point of the pair and lose nothing on exact inputs (tests/host/narrowphase/
    // far_from_origin_test.cpp).
    thread_local uint32_t anchored_lanes[kLaneBlock];
    thread_local float anchors[kLaneBlock][3];
    uint32_t n_anchored = 0;
    for (uint32_t s = blk.begin; s < blk.end; ++s) {
      const LeafPair& lp = records[record_at(s)];
      const kernels::Pair& pr = pairs[lp.pair];
      const uint32_t k = s - blk.begin;
      const uint32_t obj0 = lp.swapped ? pr.b : pr.a, obj1 = lp.swapped ? pr.a : pr.b;
      const uint32_t child0 = lp.swapped ? lp.child_b : lp.child_a, child1 = lp.swapped ? lp.child_a : lp.child_b;
      if (anchored(obj0, obj1)) {
        const Eigen::Vector3f o = anchor_of(obj0, child0);
        fill_relative(scratch[0], k, obj0, child0, o);
        fill_relative(scratch[1], k, obj1, child1, o);
        anchored_lanes[n_anchored] = k;
        for (int d = 0; d < 3; ++d) anchors[n_anchored][d] = o[d];
        ++n_anchored;
      } else {
        fill(scratch[0], k, obj0);
        fill(scratch[1], k, obj1);
      }
    }
    kernel(scratch[0].view(0), scratch[1].view(0), manifold.view(blk.begin), kernels::Range{0, blk.end - blk.begin},
           cfg);
    for (uint32_t i = 0; i < n_anchored; ++i) {
      const uint32_t s = blk.begin + anchored_lanes[i];
      const uint32_t count = std::min<uint32_t>(manifold.count[s], kernels::kMaxManifoldPoints);
      for (uint32_t j = 0; j < count; ++j)
        for (uint32_t d = 0; d < 3; ++d) manifold.f[4 + 3 * j + d][s] += anchors[i][d];
    }
  });

  // Output in record order: touching records and their points counted per chunk,
  // scanned, then written at the chunk's offsets.
  const uint32_t out_grain = kLaneGrain * 4;
  const uint32_t out_chunks = host::chunk_count(nr, out_grain);
  chunk_hits.assign(out_chunks + 1, 0);
  chunk_points.assign(out_chunks + 1, 0);
  exec.for_each_chunk(nr, out_grain, [&](uint32_t b, uint32_t e, uint32_t chunk) {
    uint32_t hits = 0, points = 0;
    for (uint32_t i = b; i < e; ++i) {
      const uint32_t count = std::min<uint32_t>(manifold.count[position_of(i)], kernels::kMaxManifoldPoints);
      hits += count > 0 ? 1u : 0u;
      points += count;
    }
    chunk_hits[chunk + 1] = hits;
    chunk_points[chunk + 1] = points;
  });
  for (uint32_t c = 0; c < out_chunks; ++c) {
    chunk_hits[c + 1] += chunk_hits[c];
    chunk_points[c + 1] += chunk_points[c];
  }
  const uint32_t total_hits = chunk_hits[out_chunks], total_points = chunk_points[out_chunks];
  out->resize(total_hits, total_points, total_points == total_hits, false);
  if (hook != nullptr) hook->sized(total_hits);
  const kernels::ContactManifoldArrays c = out->view();
  exec.for_each_chunk(nr, out_grain, [&](uint32_t b, uint32_t e, uint32_t chunk) {
    uint32_t m = chunk_hits[chunk], p = chunk_points[chunk];
    for (uint32_t i = b; i < e; ++i) {
      const uint32_t s = position_of(i);
      const uint32_t count = std::min<uint32_t>(manifold.count[s], kernels::kMaxManifoldPoints);
      if (count == 0) continue;
      const LeafPair& lp = records[i];
      const kernels::Pair& pr = pairs[lp.pair];
      c.pair[m] = lp.pair;
      c.a[m] = pr.a;
      const bool plane = pr.b >= first_plane;
      c.b[m] = plane ? pr.b - first_plane : pr.b;
      c.b_is_plane[m] = plane ? 1 : 0;
      c.child_a[m] = lp.child_a;
      c.child_b[m] = lp.child_b;
      const float sign = lp.swapped ? -1.0f : 1.0f;
      for (int k = 0; k < 3; ++k) c.normal[k][m] = manifold.f[1 + k][s] * sign;
      c.depth[m] = manifold.f[0][s];
      c.count[m] = static_cast<uint8_t>(count);
      if (c.first_point != nullptr) c.first_point[m] = p;
      for (uint32_t k = 0; k < count; ++k) {
        for (uint32_t d = 0; d < 3; ++d) c.point[d][p + k] = manifold.f[4 + 3 * k + d][s];
        c.point_depth[p + k] = manifold.f[16 + k][s];
      }
      assign_features(c, m, p, posed[pr.a].R);
      p += count;
      ++m;
    }
    if (hook != nullptr) hook->written(chunk_hits[chunk], m);
  });
  return {};
}

Status host::NarrowRunner::State::run_spheres(const host::Executor& exec, const host::SphereObjects& objects,
                                              const host::PairList& pairs_in, host::ContactManifolds* out) {
  const kernels::SphereView sv = objects.spheres;
  const kernels::PlaneView pv = objects.planes;
  const auto nb = static_cast<uint32_t>(pairs_in.first.size());
  const auto np = static_cast<uint32_t>(pairs_in.second.size());
  const kernels::Pair* body_pairs = pairs_in.first.data();
  const kernels::Pair* plane_pairs = pairs_in.second.data();
  const uint64_t n_body = host::count_and_scan(exec, nb, kContactGrain, body_offsets, [&](uint32_t b, uint32_t e) {
    return kernels::sphere_sphere_count(body_pairs, sv, {b, e});
  });
  const uint64_t n_plane =
      np == 0 ? 0 : host::count_and_scan(exec, np, kContactGrain, plane_offsets, [&](uint32_t b, uint32_t e) {
        return kernels::sphere_plane_count(plane_pairs, sv, pv, objects.first_plane, {b, e});
      });
  if (n_body + n_plane >= 0xffffffffull) {
    out->clear();
    return Status(StatusCode::kCapacityExceeded, "narrow phase: more than 2^32 - 2 contacts");
  }
  out->resize(n_body + n_plane, n_body + n_plane, true, true);
  const kernels::ContactManifoldArrays c = out->view();
  exec.for_each_chunk(nb, kContactGrain, [&](uint32_t b, uint32_t e, uint32_t k) {
    kernels::sphere_sphere_write(body_pairs, sv, 0, c, body_offsets[k], {b, e});
  });
  if (n_plane > 0) {
    exec.for_each_chunk(np, kContactGrain, [&](uint32_t b, uint32_t e, uint32_t k) {
      kernels::sphere_plane_write(plane_pairs, sv, pv, objects.first_plane, nb, c, n_body + plane_offsets[k], {b, e});
    });
  }
  return {};
}

void host::to_manifolds(const ContactManifolds& cm, uint32_t begin, uint32_t end, Manifold* out) {
  const kernels::ContactManifoldArrays c = cm.view();
  for (uint32_t i = begin; i < end; ++i) {
    Manifold& m = out[i];
    m.pair = c.pair[i];
    m.child_a = kernels::child_a_of(c, i);
    m.child_b = kernels::child_b_of(c, i);
    m.normal = Eigen::Vector3f(c.normal[0][i], c.normal[1][i], c.normal[2][i]);
    m.depth = c.depth[i];
    m.point_count = c.count[i];
    const uint32_t p = kernels::first_point_of(c, i);
    for (uint32_t k = 0; k < 4; ++k) {
      if (k < m.point_count) {
        m.points[k] = Eigen::Vector3f(c.point[0][p + k], c.point[1][p + k], c.point[2][p + k]);
        m.point_depth[k] = c.point_depth[p + k];
      } else {
        m.points[k].setZero();
        m.point_depth[k] = 0.0f;
      }
    }
  }
}

host::NarrowRunner::NarrowRunner() : s_(std::make_unique<State>()) {}
host::NarrowRunner::~NarrowRunner() = default;

Status host::NarrowRunner::run(const Executor& exec, const NarrowObjects& objects, const PairList& pairs,
                               const kernels::NarrowConfig& cfg, ContactManifolds* out, size_t* bad_pair,
                               const ManifoldHook* hook) {
  return s_->run(exec, objects, pairs, cfg, out, bad_pair, hook);
}

Status host::NarrowRunner::run_spheres(const Executor& exec, const SphereObjects& objects, const PairList& pairs,
                                       ContactManifolds* out) {
  return s_->run_spheres(exec, objects, pairs, out);
}

// --- public ------------------------------------------------------------------------------

struct NarrowPhase::Impl {
  NarrowPhaseOptions options;
  Status options_status;  // a constructor given invalid options keeps the defaults and fails calls
  host::Executor exec;
  host::NarrowRunner runner;
  std::vector<Posed> posed;
  std::vector<const ShapeRecord*> rec;
  std::vector<ShapeType> types;
  std::vector<uint32_t> first_bad;  // per chunk of objects: its first bad object
  host::ContactManifolds contacts;
  host::ArrayRunner arrays;  // collide_arrays

  Status collide(const ShapeSet& shapes, std::span<const ShapeId> shape_of_in,
                 std::span<const Pose> poses, std::span<const ShapePair> pairs_in,
                 std::vector<Manifold>* result);
};

Status NarrowPhase::Impl::collide(const ShapeSet& shapes, std::span<const ShapeId> shape_of_in,
                                  std::span<const Pose> poses, std::span<const ShapePair> pairs_in,
                                  std::vector<Manifold>* result) {
  if (result == nullptr) return Status(StatusCode::kInvalidArgument, "out must not be null");
  if (shape_of_in.size() != poses.size()) {
    return Status(StatusCode::kSizeMismatch, "shape_of has " + std::to_string(shape_of_in.size()) +
                                                 " entries but poses has " + std::to_string(poses.size()));
  }
  if (shape_of_in.size() >= 0xffffffffu || pairs_in.size() >= 0xffffffffu) {
    return Status(StatusCode::kCapacityExceeded, "more than 2^32 - 2 objects or pairs");
  }
  const ShapeStore* store = &shapes.store();
  const auto n = static_cast<uint32_t>(shape_of_in.size());
  // One parallel pass checks and poses the objects and finds the first bad one (lowest
  // index: the same error for every thread count); its message comes from the serial
  // check below, run from there. After a bad object the rest of its chunk is left
  // unposed, and the call fails. The pairs are checked as the runner expands them.
  const uint32_t obj_chunks = host::chunk_count(n, kExpandGrain);
  first_bad.assign(obj_chunks, 0xffffffffu);
  const size_t shape_count = store->shapes.size();
  rec.resize(n);
  types.resize(n);
  posed.resize(n);
  exec.for_each_chunk(n, kExpandGrain, [&](uint32_t b, uint32_t e, uint32_t chunk) {
    for (uint32_t i = b; i < e; ++i) {
      const Pose& pose = poses[i];
      if (shape_of_in[i].index >= shape_count || !host::pose_ok(pose)) {
        first_bad[chunk] = i;
        return;
      }
      const ShapeRecord* r = &store->shapes[shape_of_in[i].index];
      rec[i] = r;
      types[i] = r->type;
      Posed& P = posed[i];
      // A sphere's rotation is never read (leaf.h: p and e0 only): the identity, no
      // quaternion.
      if (r->type == ShapeType::kSphere) {
        P.R.setIdentity();
      } else {
        P.R = host::rotation_of(pose.orientation);
      }
      P.p = pose.position;
      P.set_shape(*r);
    }
  });
  uint32_t bad_obj = n;
  for (uint32_t c = 0; c < obj_chunks && bad_obj == n; ++c)
    if (first_bad[c] != 0xffffffffu) bad_obj = first_bad[c];
  for (uint32_t i = bad_obj; i < n; ++i) {
    if (shape_of_in[i].index >= store->shapes.size()) {
      return Status(StatusCode::kInvalidArgument,
                    "object " + std::to_string(i) + ": unknown shape id " + std::to_string(shape_of_in[i].index));
    }
    if (!host::pose_ok(poses[i])) {
      const std::string who = "object " + std::to_string(i);
      return host::check_pose(poses[i], who.c_str());
    }
  }
  size_t bad_pair = pairs_in.size();
  static_assert(sizeof(ShapePair) == sizeof(kernels::Pair) && alignof(ShapePair) == alignof(kernels::Pair));
  const host::PairList list{{reinterpret_cast<const kernels::Pair*>(pairs_in.data()), pairs_in.size()}, {}};
  host::NarrowObjects objects;
  objects.store = store;
  objects.rec = rec;
  objects.types = types;
  objects.poses = posed;
  // The public Manifold structs are filled chunk by chunk as the runner writes the
  // manifolds, while they are in cache. Every field of every manifold is written: a
  // result vector kept from an earlier call is only resized.
  auto sized = [&](size_t m) { result->resize(m); };
  auto written = [&](uint32_t b, uint32_t e) { host::to_manifolds(contacts, b, e, result->data()); };
  const host::ManifoldHook hook{sized, written};
  const Status st = runner.run(exec, objects, list, host::config_of(options), &contacts, &bad_pair, &hook);
  if (bad_pair < pairs_in.size()) {
    const size_t k = bad_pair;
    const ShapePair& pr = pairs_in[k];
    if (pr.a >= n || pr.b >= n) {
      return Status(StatusCode::kInvalidArgument, "pair " + std::to_string(k) + ": index out of range (" +
                                                      std::to_string(n) + " objects)");
    }
    if (pr.a == pr.b) {
      return Status(StatusCode::kInvalidArgument,
                    "pair " + std::to_string(k) + ": an object cannot collide with itself");
    }
    return Status(StatusCode::kInvalidArgument,
                  "pair " + std::to_string(k) + ": two half-spaces have no finite collision data");
  }
  if (!st.ok()) result->clear();
  return st;
}

kernels::NarrowConfig host::config_of(const NarrowPhaseOptions& o) {
  kernels::NarrowConfig cfg;
  cfg.path = o.simd ? kernels::KernelPath::kSimd : kernels::KernelPath::kScalar;
  cfg.gjk_max_iterations = o.gjk_max_iterations;
  cfg.gjk_tolerance = o.gjk_tolerance;
  cfg.epa_max_iterations = o.epa_max_iterations;
  cfg.epa_tolerance = o.epa_tolerance;
  cfg.sat_max_vertices = o.sat_max_vertices;
  return cfg;
}


Status host::validate_options(const NarrowPhaseOptions& o) {
  auto bad = [](const std::string& m) { return Status(StatusCode::kInvalidArgument, m); };
  if (o.gjk_max_iterations == 0) return bad("gjk_max_iterations must be >= 1");
  if (o.epa_max_iterations == 0) return bad("epa_max_iterations must be >= 1");
  if (!std::isfinite(o.gjk_tolerance) || !(o.gjk_tolerance > 0.0f) || o.gjk_tolerance >= 1.0f) {
    return bad("gjk_tolerance must be in (0, 1)");
  }
  if (!std::isfinite(o.epa_tolerance) || !(o.epa_tolerance > 0.0f) || o.epa_tolerance >= 1.0f) {
    return bad("epa_tolerance must be in (0, 1)");
  }
  Backend resolved;
  if (!host::resolve_backend(o.exec.backend, &resolved)) {
    return Status(StatusCode::kUnsupported, std::string("backend ") + to_string(o.exec.backend) +
                                                " is not built into this library");
  }
  return {};
}

NarrowPhase::NarrowPhase(const NarrowPhaseOptions& options) : impl_(std::make_unique<Impl>()) {
  impl_->options_status = host::validate_options(options);
  if (impl_->options_status.ok()) {
    impl_->options = options;
    impl_->exec = host::Executor(options.exec.backend, options.exec.threads);
  }
}
NarrowPhase::~NarrowPhase() = default;
NarrowPhase::NarrowPhase(NarrowPhase&&) noexcept = default;
NarrowPhase& NarrowPhase::operator=(NarrowPhase&&) noexcept = default;

Status NarrowPhase::set_options(const NarrowPhaseOptions& options) {
  if (Status st = host::validate_options(options); !st.ok()) return st;
  const bool exec_changed = options.exec.backend != impl_->options.exec.backend ||
                            options.exec.threads != impl_->options.exec.threads;
  impl_->options = options;
  impl_->options_status = {};
  if (exec_changed) impl_->exec = host::Executor(options.exec.backend, options.exec.threads);
  return {};
}

const NarrowPhaseOptions& NarrowPhase::options() const { return impl_->options; }

Status NarrowPhase::collide(const ShapeSet& shapes, std::span<const ShapeId> shape_of,
                            std::span<const Pose> poses, std::span<const ShapePair> pairs,
                            std::vector<Manifold>* out) {
  if (!impl_->options_status.ok()) return impl_->options_status;
  return impl_->collide(shapes, shape_of, poses, pairs, out);
}

Status NarrowPhase::collide_arrays(const ShapeSet& shapes, std::span<const ShapeId> shape_of, const PoseArrays& poses,
                                   std::span<const ShapePair> pairs, const PairContactArrays& out) {
  if (!impl_->options_status.ok()) return impl_->options_status;
  return impl_->arrays.run(impl_->exec, shapes.store(), shape_of, poses, pairs, host::config_of(impl_->options), out);
}

}  // namespace impact
