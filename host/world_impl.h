// WorldImpl: the SoA storage behind impact::World, and the scratch of its step.
#pragma once

#include <cstdint>
#include <vector>

#include "host/broadphase/broadphase.h"
#include "host/broadphase/stage.h"
#include "host/buffer.h"
#include "host/handle_table.h"
#include "host/narrowphase/narrow_phase.h"
#include "host/narrowphase/shape_store.h"
#include "host/parallel.h"
#include "impact/world.h"
#include "kernels/broadphase/bounds.h"
#include "kernels/broadphase/grid.h"
#include "kernels/solver/contact_solver.h"

namespace impact {

/// Body state in dense slots. Hot (per-iteration) and cold fields are separate arrays.
struct BodyStore {
  host::Buffer<float> pos_x, pos_y, pos_z;
  host::Buffer<float> vel_x, vel_y, vel_z;
  host::Buffer<float> inv_mass, radius, restitution;
  host::Buffer<uint32_t> layer, mask;
  host::Buffer<uint8_t> is_static;
  host::Buffer<float> prev_x, prev_y, prev_z;  // only with WorldDesc::interpolation
  // Only once a body with a shape exists (empty otherwise, and a sphere-only world
  // never touches them): shape index (kNoShape = sphere of `radius`) and orientation.
  host::Buffer<uint32_t> shape;
  host::Buffer<float> qx, qy, qz, qw;
  std::vector<BodyHandle> handle;              // slot -> handle
  size_t size() const { return handle.size(); }
};

struct PlaneStore {
  std::vector<float> normal_x, normal_y, normal_z, offset, restitution;
  std::vector<uint32_t> layer, mask;
  std::vector<PlaneHandle> handle;
  size_t size() const { return handle.size(); }
};

/// Per-contact arrays: collision data plus solver rows.
struct ContactStore {
  host::Buffer<uint32_t> a, b;
  host::Buffer<uint8_t> b_is_plane;
  host::Buffer<float> normal_x, normal_y, normal_z, depth, point_x, point_y, point_z;
  host::Buffer<float> mass, target, impulse;
  host::Buffer<uint8_t> point;  // manifold point index (general narrow phase only; warm-start key)
  size_t count = 0;
  void resize(size_t n);
};

inline constexpr uint32_t kNoShape = 0xffffffffu;

class WorldImpl {
 public:
  explicit WorldImpl(const WorldDesc& desc);

  Status step();
  /// Permutes body storage into the broad phase's spatial order of the last step.
  void reorder_bodies();
  /// Applies desc's broad-phase settings to the stage (next step builds afresh).
  void configure_broad_phase();
  /// Brings the broad-phase structure up to the bodies' current boxes for queries.
  Status prepare_queries();
  /// Body positions or slots changed: the next query refreshes the structure.
  void positions_changed() { queries_fresh = false; }
  bool queries_fresh = false;
  void swap_remove_body(uint32_t slot);

  WorldDesc desc;
  host::Executor exec;
  ShapeSet shapes;
  uint32_t shaped_count = 0;  // bodies with a shape: the step runs the general narrow phase
  host::NarrowRunner narrow;
  std::vector<const ShapeRecord*> narrow_rec;
  std::vector<ShapeType> narrow_types;  // narrow_rec[i]->type
  std::vector<host::PosedObject> narrow_pose;
  std::vector<ShapeRecord> narrow_spheres;  // sphere records of plain bodies, then plane records
  std::vector<ShapePair> narrow_pairs;
  std::vector<Manifold> manifolds;
  /// The general path of the step's narrow phase (bodies with shapes): writes contacts.
  Status general_narrow_phase();
  /// Overwrites the boxes of bodies with shapes by their posed bounds (swept over
  /// swept_dt of motion when > 0).
  void shaped_bounds(const kernels::AabbSoAOut& out, float swept_dt);
  BodyStore bodies;
  PlaneStore planes;
  host::HandleTable body_handles;
  host::HandleTable plane_handles;

  double accumulator = 0.0;  // s, in double so long runs keep sub-step precision
  float alpha = 0.0f;
  StepStats last;

  // Step scratch, reused across steps.
  host::Buffer<float> box[6];
  host::Buffer<kernels::Pair> pairs;
  host::Buffer<kernels::BoundsSummary> bounds_partials;
  ContactStore contacts;
  host::Buffer<uint64_t> csr_keys;
  host::Buffer<uint32_t> entry_pos;          // CSR position of each (contact, side)
  host::Buffer<float> entry_delta;           // 4 floats per CSR entry
  host::Buffer<uint64_t> pair_keys;          // this step's contact keys (a << 32 | b | plane bit)
  host::Buffer<uint64_t> prev_keys;          // last step's, sorted, for warm starting
  host::Buffer<float> prev_impulse;          // their impulses
  host::Buffer<uint32_t> prev_start;         // per body a: range in prev_keys
  uint32_t prev_contacts = 0;
  uint32_t prev_body_count = 0;
  host::Buffer<float> impulse_out;           // velocity impulses of the last step, for contacts()
  host::Buffer<kernels::BodyState> solver_state;
  uint64_t steps_since_reorder = 0;
  host::Buffer<uint32_t> perm, inv_perm;
  host::Buffer<uint32_t> tmp_u32;
  host::Buffer<uint8_t> tmp_u8;
  host::Buffer<float> tmp_f32;
  host::Buffer<uint64_t> tmp_u64;
  host::Buffer<uint32_t> body_start;
  host::Buffer<uint64_t> pair_offsets, plane_offsets;
  host::RadixSorter sorter;
  host::BroadPhaseStage broad_phase;
};

}  // namespace impact
