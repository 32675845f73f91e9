#include "host/narrowphase/narrow_arrays.h"

#include <algorithm>
#include <string>

#include "host/narrowphase/lane_arrays.h"
#include "host/narrowphase/narrow_phase.h"
#include "host/shapes/pose.h"
#include "kernels/narrowphase/pair_kernels.h"

namespace impact::host {
namespace {

constexpr uint32_t kObjectGrain = 4096;
constexpr uint32_t kPairGrain = 8192;
constexpr uint32_t kLaneBlock = 512;  // as the runner's: both sides' lanes in L2
constexpr uint32_t kNone = 0xffffffffu;

Status size_error(const char* what, size_t got, size_t want, const char* of) {
  return Status(StatusCode::kSizeMismatch, std::string(what) + " has " + std::to_string(got) + " entries for " +
                                               std::to_string(want) + " " + of);
}

Pose pose_at(const PoseArrays& p, uint32_t i) {
  Pose out;
  out.position = Eigen::Vector3f(p.px[i], p.py[i], p.pz[i]);
  out.orientation = Eigen::Quaternionf(p.qw[i], p.qx[i], p.qy[i], p.qz[i]);
  return out;
}

// The pose arrays as plain pointers (hoisted out of the loops: spans behind a
// reference would be reloaded after every store).
struct Raw {
  const float *px, *py, *pz, *qx, *qy, *qz, *qw;
};
Raw raw_of(const PoseArrays& p) {
  return {p.px.data(), p.py.data(), p.pz.data(), p.qx.data(), p.qy.data(), p.qz.data(), p.qw.data()};
}

// Lane k of side s: object i, a convex shape other than a half-space, as the kernels'
// leaf (the fields NarrowRunner's fill writes for the same record and pose, so both
// calls give the same bytes); pos: the position written (object i's own, or relative to
// an anchor). Half-space buckets take fill_relative.
IMPACT_INLINE void fill(LeafArrays& s, size_t k, const ShapeRecord& r, const Eigen::Vector3f& pos, const Raw& p,
                        uint32_t i) {
  switch (r.type) {
    case ShapeType::kSphere:
      put_p(s, k, pos);
      s.f[12][k] = r.e[0];
      return;
    case ShapeType::kAabb:
      put_p(s, k, pos);
      put_r(s, k, Eigen::Matrix3f::Identity());
      put_e(s, k, r.e);
      return;
    case ShapeType::kConvex:
      put_p(s, k, pos);
      put_r(s, k, rotation_of(Eigen::Quaternionf(p.qw[i], p.qx[i], p.qy[i], p.qz[i])));
      s.ref[k] = r.ref;
      return;
    default:  // capsule, box, cylinder, ellipsoid
      put_p(s, k, pos);
      put_r(s, k, rotation_of(Eigen::Quaternionf(p.qw[i], p.qx[i], p.qy[i], p.qz[i])));
      put_e(s, k, r.e);
      return;
  }
}

// fill() for a pair with a half-space side, every position relative to the anchor o (a
// point of the pair: the kernel A side's position), from double and rounded once, and a
// half-space as the point of its plane nearest o: NarrowRunner's fill_relative for the
// same leaf, so the far-from-origin accuracy and the bytes are those of collide().
void fill_relative(LeafArrays& s, size_t k, const ShapeRecord& r, const Raw& p, uint32_t i,
                   const Eigen::Vector3f& o) {
  const Eigen::Vector3d pd = Eigen::Vector3d(p.px[i], p.py[i], p.pz[i]) - o.cast<double>();
  const Eigen::Vector3f pos = pd.cast<float>();
  if (r.type != ShapeType::kHalfSpace) {
    fill(s, k, r, pos, p, i);
    return;
  }
  put_plane_relative(s, k, rotation_of(Eigen::Quaternionf(p.qw[i], p.qx[i], p.qy[i], p.qz[i])), pd, r.e, r.offset);
}

kernels::ManifoldSoA out_view(const PairContactArrays& o, size_t offset) {
  kernels::ManifoldSoA m{};
  m.count = o.count.data() + offset;
  m.depth = o.depth.data() + offset;
  m.n[0] = o.normal_x.data() + offset;
  m.n[1] = o.normal_y.data() + offset;
  m.n[2] = o.normal_z.data() + offset;
  for (uint32_t k = 0; k < kernels::kMaxManifoldPoints; ++k) {
    m.point[k][0] = o.point_x[k].data() + offset;
    m.point[k][1] = o.point_y[k].data() + offset;
    m.point[k][2] = o.point_z[k].data() + offset;
    m.pdepth[k] = o.point_depth[k].data() + offset;
  }
  return m;
}

}  // namespace

Status ArrayRunner::run(const Executor& exec, const ShapeStore& store, std::span<const ShapeId> shape_of,
                        const PoseArrays& poses, std::span<const ShapePair> pairs, const kernels::NarrowConfig& cfg_in,
                        const PairContactArrays& out) {
  if (shape_of.size() >= kNone || pairs.size() >= kNone)
    return Status(StatusCode::kCapacityExceeded, "collide_arrays: more than 2^32 - 2 objects or pairs");
  const auto n = static_cast<uint32_t>(shape_of.size());
  const auto np = static_cast<uint32_t>(pairs.size());
  {
    const std::span<const float>* in[7] = {&poses.px, &poses.py, &poses.pz, &poses.qx, &poses.qy, &poses.qz, &poses.qw};
    const char* names[7] = {"poses.px", "poses.py", "poses.pz", "poses.qx", "poses.qy", "poses.qz", "poses.qw"};
    for (int i = 0; i < 7; ++i)
      if (in[i]->size() != n) return size_error(names[i], in[i]->size(), n, "objects (shape_of)");
    if (out.count.size() != np) return size_error("out.count", out.count.size(), np, "pairs");
    const std::span<float>* f[5] = {&out.normal_x, &out.normal_y, &out.normal_z, &out.depth, nullptr};
    const char* fnames[4] = {"out.normal_x", "out.normal_y", "out.normal_z", "out.depth"};
    for (int i = 0; i < 4; ++i)
      if (f[i]->size() != np) return size_error(fnames[i], f[i]->size(), np, "pairs");
    for (uint32_t k = 0; k < kernels::kMaxManifoldPoints; ++k) {
      const std::span<float>* pk[4] = {&out.point_x[k], &out.point_y[k], &out.point_z[k], &out.point_depth[k]};
      const char* pn[4] = {"out.point_x[", "out.point_y[", "out.point_z[", "out.point_depth["};
      for (int i = 0; i < 4; ++i)
        if (pk[i]->size() != np) {
          const std::string what = std::string(pn[i]) + std::to_string(k) + "]";
          return size_error(what.c_str(), pk[i]->size(), np, "pairs");
        }
    }
  }

  // Objects: shape ids, poses, leaf types; the lowest bad index wins (any thread count).
  const size_t shape_count = store.shapes.size();
  leaf_.resize(n);
  const uint32_t obj_chunks = chunk_count(n, kObjectGrain);
  first_bad_.assign(obj_chunks, kNone);
  const Raw raw = raw_of(poses);
  const ShapeRecord* records = store.shapes.data();
  exec.for_each_chunk(n, kObjectGrain, [&](uint32_t b, uint32_t e, uint32_t chunk) {
    // Branch-free first (vectorised): finite poses, unit quaternions, known shape ids;
    // the chunk's first bad object is searched for (by pose_ok, exactly; the float
    // pre-check is a little stricter) only when one may be there.
    uint32_t bad = 0;
    for (uint32_t i = b; i < e; ++i) {
      const float q2 = raw.qx[i] * raw.qx[i] + raw.qy[i] * raw.qy[i] + raw.qz[i] * raw.qz[i] + raw.qw[i] * raw.qw[i];
      const float fin = (raw.px[i] - raw.px[i]) + (raw.py[i] - raw.py[i]) + (raw.pz[i] - raw.pz[i]) + (q2 - q2);
      bad |= static_cast<uint32_t>(!(fin == 0.0f)) | static_cast<uint32_t>(!(std::fabs(q2 - 1.0f) <= 1.9e-3f)) |
             static_cast<uint32_t>(shape_of[i].index >= shape_count);
    }
    for (uint32_t i = b; i < e; ++i) {
      if (bad != 0 && (shape_of[i].index >= shape_count || !pose_ok(pose_at(poses, i)))) {
        first_bad_[chunk] = i;
        return;
      }
      const ShapeType t = records[shape_of[i].index].type;
      if (t == ShapeType::kMesh || t == ShapeType::kCompound) {
        first_bad_[chunk] = i;
        return;
      }
      leaf_[i] = static_cast<uint8_t>(leaf_type_of(t));
    }
  });
  for (uint32_t c = 0; c < obj_chunks; ++c) {
    const uint32_t i = first_bad_[c];
    if (i == kNone) continue;
    const std::string who = "collide_arrays: object " + std::to_string(i);
    if (shape_of[i].index >= shape_count)
      return Status(StatusCode::kInvalidArgument, who + ": unknown shape id " + std::to_string(shape_of[i].index));
    if (Status s = check_pose(pose_at(poses, i), who.c_str()); !s.ok()) return s;
    return Status(StatusCode::kInvalidArgument,
                  who + ": a mesh or compound has more than one result per pair; NarrowPhase::collide takes it");
  }

  // Pairs: checks and bucket keys; whether they are already in bucket order.
  uint64_t* keys = scratch(keys_, np);
  const uint32_t pair_chunks = chunk_count(np, kPairGrain);
  first_bad_.assign(pair_chunks, kNone);
  chunk_descends_.assign(pair_chunks, 0);
  exec.for_each_chunk(np, kPairGrain, [&](uint32_t b, uint32_t e, uint32_t chunk) {
    uint8_t descends = 0;
    for (uint32_t k = b; k < e; ++k) {
      const ShapePair pr = pairs[k];
      if (pr.a >= n || pr.b >= n || pr.a == pr.b ||
          (leaf_[pr.a] == kernels::kLeafHalfSpace && leaf_[pr.b] == kernels::kLeafHalfSpace)) {
        first_bad_[chunk] = k;
        return;
      }
      const uint32_t lo = std::min(leaf_[pr.a], leaf_[pr.b]), hi = std::max(leaf_[pr.a], leaf_[pr.b]);
      keys[k] = (static_cast<uint64_t>(lo * kernels::kLeafTypeCount + hi) << 32) | k;
      descends |= k > b && keys[k] < keys[k - 1] ? 1 : 0;
    }
    chunk_descends_[chunk] = descends;
  });
  bool sorted = true;
  for (uint32_t c = 0; c < pair_chunks; ++c) {
    if (const uint32_t k = first_bad_[c]; k != kNone) {
      const ShapePair& pr = pairs[k];
      const std::string who = "collide_arrays: pair " + std::to_string(k);
      if (pr.a >= n || pr.b >= n)
        return Status(StatusCode::kInvalidArgument,
                      who + ": index out of range (" + std::to_string(n) + " objects)");
      if (pr.a == pr.b) return Status(StatusCode::kInvalidArgument, who + ": an object cannot collide with itself");
      return Status(StatusCode::kInvalidArgument, who + ": two half-spaces have no finite collision data");
    }
    const uint32_t first = c * kPairGrain;
    sorted = sorted && chunk_descends_[c] == 0 && (c == 0 || keys[first] > keys[first - 1]);
  }
  if (!sorted) sorter_.sort(exec, keys, np, 32, 32 + 7);

  // Blocks of one bucket, kLaneBlock pairs at most.
  blocks_.clear();
  for (uint32_t begin = 0; begin < np;) {
    const uint64_t bucket = keys[begin] >> 32;
    uint32_t end = begin + 1;
    while (end < np && (keys[end] >> 32) == bucket) ++end;
    for (uint32_t b = begin; b < end; b += kLaneBlock) blocks_.push_back(b);
    begin = end;
  }
  const auto nblocks = static_cast<uint32_t>(blocks_.size());
  blocks_.push_back(np);
  kernels::NarrowConfig cfg = cfg_in;
  cfg.hulls = store.hulls.view();
  exec.for_each_chunk(nblocks, 1, [&](uint32_t bi, uint32_t, uint32_t) {
    const uint32_t begin = blocks_[bi];
    const uint32_t end = std::min(blocks_[bi + 1], begin + kLaneBlock);
    const uint64_t bucket = keys[begin] >> 32;
    const auto ta = static_cast<kernels::LeafType>(bucket / kernels::kLeafTypeCount);
    const auto tb = static_cast<kernels::LeafType>(bucket % kernels::kLeafTypeCount);
    const kernels::PairKernel kernel = kernels::pair_kernel(ta, tb);
    IMPACT_ASSERT(kernel != nullptr);
    thread_local LeafArrays side[2];
    thread_local ManifoldArrays lanes;
    if (side[0].size < kLaneBlock) {
      side[0].resize(kLaneBlock, LeafArrays::kPhaseA);
      side[1].resize(kLaneBlock, LeafArrays::kPhaseB);
      lanes.resize(kLaneBlock);
    }
    // A bucket with a half-space side is posed relative to a point of each pair, and
    // its points moved back after the kernel (docs/narrowphase.md, "Far from the origin").
    const bool anchored = ta == kernels::kLeafHalfSpace || tb == kernels::kLeafHalfSpace;
    thread_local float anchor[kLaneBlock][3];
    for (uint32_t s = begin; s < end; ++s) {
      const auto k = static_cast<uint32_t>(keys[s]);
      const ShapePair pr = pairs[k];
      const bool swap = leaf_[pr.a] != ta;  // the kernel's A is the lower leaf type
      const uint32_t a = swap ? pr.b : pr.a, b = swap ? pr.a : pr.b;
      if (anchored) {
        const Eigen::Vector3f o(raw.px[a], raw.py[a], raw.pz[a]);
        fill_relative(side[0], s - begin, records[shape_of[a].index], raw, a, o);
        fill_relative(side[1], s - begin, records[shape_of[b].index], raw, b, o);
        for (int d = 0; d < 3; ++d) anchor[s - begin][d] = o[d];
      } else {
        fill(side[0], s - begin, records[shape_of[a].index], Eigen::Vector3f(raw.px[a], raw.py[a], raw.pz[a]), raw, a);
        fill(side[1], s - begin, records[shape_of[b].index], Eigen::Vector3f(raw.px[b], raw.py[b], raw.pz[b]), raw, b);
      }
    }
    const uint32_t m = end - begin;
    // In pair order the kernel writes the caller's slots begin .. end itself.
    const kernels::ManifoldSoA o = sorted ? out_view(out, begin) : lanes.view(0);
    kernel(side[0].view(0), side[1].view(0), o, kernels::Range{0, m}, cfg);
    if (anchored)
      for (uint32_t l = 0; l < m; ++l) {
        const uint32_t count = std::min<uint32_t>(o.count[l], kernels::kMaxManifoldPoints);
        for (uint32_t j = 0; j < count; ++j)
          for (int d = 0; d < 3; ++d) o.point[j][d][l] += anchor[l][d];
      }
    if (sorted && ta == tb) return;  // in place, and no lane is swapped
    for (uint32_t l = 0; l < m; ++l) {
      const auto k = static_cast<uint32_t>(keys[begin + l]);
      const bool swap = leaf_[pairs[k].a] != ta;
      if (!sorted) {
        const uint32_t count = std::min<uint32_t>(o.count[l], kernels::kMaxManifoldPoints);
        out.count[k] = static_cast<uint8_t>(count);
        if (count == 0) continue;
        out.depth[k] = o.depth[l];
        out.normal_x[k] = o.n[0][l];
        out.normal_y[k] = o.n[1][l];
        out.normal_z[k] = o.n[2][l];
        for (uint32_t j = 0; j < count; ++j) {
          out.point_x[j][k] = o.point[j][0][l];
          out.point_y[j][k] = o.point[j][1][l];
          out.point_z[j][k] = o.point[j][2][l];
          out.point_depth[j][k] = o.pdepth[j][l];
        }
      }
      if (swap && out.count[k] > 0) {  // the kernel's normal runs from b to a
        out.normal_x[k] = -out.normal_x[k];
        out.normal_y[k] = -out.normal_y[k];
        out.normal_z[k] = -out.normal_z[k];
      }
    }
  });
  return Status();
}

}  // namespace impact::host
