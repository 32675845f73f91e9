// Normal-impulse contact response with restitution and position correction, as
// flat passes that parallelise without locks or float atomics.
//
// The solver is Jacobi iteration with mass splitting (Tonge, Benevolenski &
// Voroshilov 2012, "Mass splitting for jitter-free parallel rigid body
// simulation"): a body in k contacts is seen by each contact as k times lighter
// (inverse mass w*k), each contact computes its impulse from the velocities at
// the start of the iteration, and each body then adds up the impulses of its
// contacts in a fixed (sorted) order. For an isolated pair (k = 1) one iteration
// is the exact two-body impulse of the seeds:
//   v_n' = -e v_n  with  e = max(e_a, e_b)  (1 elastic, 0 inelastic),
// and infinite mass (inv_mass 0) gives the one-way cases. Approach speeds below
// restitution_threshold get no bounce, so resting bodies settle.
// Impulses accumulate and are clamped to >= 0 (contacts push, never pull).
//
// Body -> contact adjacency is a CSR built by sorting keys
//   (body << 32) | (2 * contact + side),  side 0 = a (gets -n), 1 = b (gets +n);
// static bodies and planes use the sentinel body id n_bodies and are skipped.
//
// Warm starting: each contact has a key (a << 32 | b, with bit 31 set when b is a
// plane and the point's feature key in bits 29-30); last step's keys are kept sorted with their impulses, and a contact
// that persists starts from warm_start * last impulse (Catto, "Iterative Dynamics
// with Temporal Coherence", GDC 2005), so stacks converge over steps, not within one.
//
// Position correction runs the same Jacobi iteration on per-body displacements
// instead of velocities ("split impulses" / pseudo-velocities): the target of a
// contact is position_correction * max(depth - slop, 0), reached without adding
// kinetic energy; then positions move by the displacement.
//
// Contacts are the points of the step's manifolds (kernels/common/contact_manifolds.h):
// one solver row per point, along its manifold's normal. The contact passes take a
// range of manifolds and handle each one's points (rows first_point .. + count).
//
// Passes (each output element written by exactly one index):
//   pack_*_state             per body: hot 16-byte state (velocity or displacement, w)
//   contact_body_keys        per contact: two CSR keys
//   contact_prepare          per contact: effective mass, restitution target, impulse = 0
//   contact_pair_keys        per contact: persistence key
//   contact_warm_start       per contact: impulse = warm * last impulse (looked up among
//                            last step's contacts of the same body a)
//   contact_solve            per contact: impulse increment of one iteration
//   body_apply               per body: state += w * sum(side * increment * n)
//   contact_position_target  per contact: position target, impulse = 0
//   unpack / commit          per body: velocities back, or p += displacement
#pragma once

#include "kernels/common/contact_manifolds.h"
#include "kernels/common/kernel.h"

namespace impact::kernels {

struct SolverParams {
  float restitution_threshold;  ///< m/s
  float position_correction;    ///< fraction in [0, 1]
  float penetration_slop;       ///< m
  /// s, the step (contact_prepare): a speculative point (point_depth < 0, a gap g)
  /// targets the approach speed g / dt, so the gap may close within the step but not
  /// cross, and takes no restitution until it touches (0: no speculative points).
  float dt = 0.0f;
};

/// Hot per-body solver state, 16 bytes: the velocity (or, in the position phase,
/// the displacement) and the inverse mass, packed so that a contact reads one
/// cache line per body (Box2D's b2BodyState idea). Slot n (one past the last
/// body) is a zero, immovable entry that plane contacts use as body b.
struct alignas(16) BodyState {
  float x, y, z;
  float inv_mass;
};
static_assert(sizeof(BodyState) == 16);

/// The solver's rows, one per contact point (row p = point p of the manifolds).
struct SolverRows {
  float* mass;     ///< 1 / (w_a k_a + w_b k_b), 0 if both immovable
  float* target;   ///< desired relative normal velocity (or displacement) after the solve
  float* impulse;  ///< accumulated normal impulse, N s
};

/// CSR adjacency of bodies to contacts. Entry e in [start[i], start[i+1]) belongs
/// to body i. Each contact writes its signed impulse increment (-d n for a, +d n
/// for b) straight into its two entries (positions pos[2k], pos[2k+1]), so a body
/// sums a contiguous run instead of gathering from scattered contacts: scattered
/// writes, streaming reads.
struct BodyContacts {
  const uint32_t* start;  ///< body_count + 1 entries
  const uint32_t* pos;    ///< 2 per contact: entry index of side a, side b
  float* delta;           ///< 4 per entry: impulse increment times signed normal (xyz, 0)
};

/// Last step's contacts for warm starting: keys sorted ascending (unique), their
/// impulses, and start[a] over the a-half of the key for a in [0, body_count].
struct WarmStart {
  const uint64_t* keys;
  const float* impulse;
  const uint32_t* start;
  uint32_t body_count;
  float factor;
};

void pack_velocity_state(const float* IMPACT_RESTRICT vx, const float* IMPACT_RESTRICT vy,
                         const float* IMPACT_RESTRICT vz, const float* IMPACT_RESTRICT inv_mass,
                         BodyState* IMPACT_RESTRICT out, Range r);
void pack_displacement_state(const float* IMPACT_RESTRICT inv_mass, BodyState* IMPACT_RESTRICT out, Range r);
void unpack_velocity_state(const BodyState* IMPACT_RESTRICT s, float* IMPACT_RESTRICT vx,
                           float* IMPACT_RESTRICT vy, float* IMPACT_RESTRICT vz, Range r);
/// p += displacement.
void commit_displacement_state(const BodyState* IMPACT_RESTRICT s, float* IMPACT_RESTRICT px,
                               float* IMPACT_RESTRICT py, float* IMPACT_RESTRICT pz, Range r);

/// Per manifold in r, per point p: the CSR keys 2p (side a) and 2p + 1 (side b).
void contact_body_keys(const ContactManifoldArrays& c, const float* inv_mass, uint32_t body_count,
                       uint64_t* IMPACT_RESTRICT out_keys, Range r);

/// pos[entry] = e for each sorted CSR key e in r (entry = low 32 bits of the key).
void contact_entry_positions(const uint64_t* IMPACT_RESTRICT sorted_keys, uint32_t* IMPACT_RESTRICT out_pos,
                             Range r);

// The passes below take a Range of manifolds and handle every point of each.
void contact_prepare(const SolverParams& p, const ContactManifoldArrays& c, SolverRows rows, const BodyState* s,
                     uint32_t body_count, const float* restitution, const float* plane_restitution,
                     BodyContacts adj, Range r);

/// Per point: a << 32 | b | (b is a plane) << 31 | (feature & 3) << 29.
void contact_pair_keys(const ContactManifoldArrays& c, uint64_t* IMPACT_RESTRICT out_keys, Range r);

void contact_warm_start(const ContactManifoldArrays& c, SolverRows rows, BodyContacts adj,
                        const uint64_t* IMPACT_RESTRICT keys, WarmStart prev, Range r);

void contact_solve(const ContactManifoldArrays& c, SolverRows rows, BodyContacts adj, const BodyState* s,
                   uint32_t body_count, Range r);

/// Per body: state += inv_mass * sum of its entries' deltas.
void body_apply(BodyContacts adj, BodyState* io, Range r);

/// Writes position targets to rows.target and zeroes rows.impulse. The target is
/// position_correction * max(depth' - slop, 0), where depth' = point depth - dt * v_n
/// is the overlap left once positions move with the solved velocities s.
void contact_position_target(const SolverParams& p, const ContactManifoldArrays& c, SolverRows rows,
                             const BodyState* s, uint32_t body_count, float dt, Range r);

}  // namespace impact::kernels
