// The soft-step contact solver's kernels: rigid contacts with angular terms, Coulomb
// friction at one central anchor per manifold, twist friction, rolling resistance and
// restitution, solved by Gauss-Seidel over the colours of a contact graph colouring
// (kernels/solver/graph_colouring.h), with soft constraints and substeps.
//
// One step (host/solver/soft_step_solver.cpp drives it):
//   prepare_bodies        per body: the solver state (v, w, dp = 0, dq = 1), the world
//                         inverse inertia I_w^-1 = R diag(ii) R^T, the centre of mass,
//                         the per-substep velocity increments (gravity, forces),
//                         damping, and the principal frames for the gyroscopic term
//   prepare_contacts      per manifold: anchors relative to the centres of mass, the
//                         normal mass of each point, the friction anchor, the 2x2
//                         tangent mass, twist and rolling masses, warm-start impulses
//   per substep h = dt / substeps:
//     integrate_substep_velocities  v += dv, w += dw
//     warm_start_contacts           apply the accumulated impulses
//     solve_contacts(bias)          normal impulses toward separation -slop, soft
//     integrate_substep_positions   dp += h v, dq = integrate(dq, w, h); with the
//                                   gyroscopic term w' = I_w(dq')^-1 I_w(dq) w (a
//                                   torque-free substep keeps L = I_w w exactly)
//     solve_contacts(no bias)       relax: normal impulses rigid, then friction
//   restitute_contacts    normal impulses toward -e * (approach speed) where the
//                         approach was faster than the threshold
//   finish_bodies         v, w back; p = com0 + dp - R(dq q0) c, q = dq q0
//
// The separation of a point during the step follows the bodies without a new narrow
// phase: s = s0 + dot(dp_b - dp_a + rot(dq_b) r_b - rot(dq_a) r_a - (r_b - r_a), n),
// with r the anchors (point - centre of mass) at the step's start and n fixed.
// Solve, per point: s > -slop is speculative (the impulse only stops the bodies
// closing more than s + slop this substep); points of a deep manifold (depth >
// max_push_speed * dt: a push could not separate it this step) get no bias, only the
// rigid stop (the host separates them by position correction); deeper points get the soft bias
//   bias = max(bias_rate * mass_scale * (s + slop), -max_push_speed)
//   dλ = -m_n (mass_scale * v_n + bias) - impulse_scale * λ,   λ = max(λ + dλ, 0)
// with (Catto, "Solver2D: soft step", 2024; Box2D v3 b2MakeSoft)
//   ω = 2π hertz, a1 = 2ζ + h ω, a2 = h ω a1, a3 = 1 / (1 + a2),
//   bias_rate = ω / a1, mass_scale = a2 a3, impulse_scale = a3;
// the relax pass is rigid (bias 0, mass_scale 1, impulse_scale 0). Friction runs in
// the relax pass only, at the manifold's anchor: tangent impulse clamped to a disc of
// radius μ Σλ, twist to μ Σ λ_i |r_i - r_centre|, rolling (3D angular) to ρ Σλ.
//
// Each constraint reads and writes only its two bodies; the host runs one colour's
// constraints in parallel (no two share a dynamic body) and colours in order, so the
// result is the same bytes for any thread count. Bodies with inv_mass 0 (static,
// kinematic, planes: index body_count, a zero body) are read, never written.
// SIMD across the constraints of a colour (Box2D v3 / Box3D contact_solver.c,
// b3SolveContact_Convex): constraints are stored in blocks of kContactLanes (SoA, one
// constraint a lane, each colour padded to whole blocks); a pass gathers each lane's
// two bodies (SolverBody rows, transposed), runs the points to the block's largest
// count with the shorter lanes masked, and scatters the lanes whose body is dynamic.
// The kernels are one template over the lane type: FloatW for blocks, Float1 for the
// overflow colour slot by slot; every verb is lane-wise and IEEE and the operation
// order is the same, so both give the same bytes.
// Cost per constraint and pass: ~40 flops per point plus ~120 for the friction anchor,
// and the gather / scatter of two 64-byte bodies (two 8 x 8 transposes each way); a
// block does kContactLanes constraints in about the instructions of one.
#pragma once

#include "kernels/common/contact_manifolds.h"
#include "kernels/common/kernel.h"
#include "kernels/common/math3.h"
#include "kernels/integrate/rigid_euler.h"
#include "kernels/simd/lanes.h"

namespace impact::kernels {

/// Per-body solver state, one cache line: velocity, angular velocity, displacement
/// of the centre of mass and rotation since the step's start.
struct alignas(64) SolverBody {
  Vec3 v;
  float inv_mass;
  Vec3 w;
  float pad0;
  Vec3 dp;
  float pad1;
  Quat dq;
};
static_assert(sizeof(SolverBody) == 64);

/// Per-body increments of one substep (gravity, forces, torques).
struct BodyDrive {
  Vec3 dv;
  Vec3 dw;
};

/// Per-body data of the gyroscopic update (SoftBodyInput::gyroscopic): the principal
/// frame at the step's start and the principal moments; moments.x == 0 for a body
/// that takes none (static, kinematic, or with a zero moment).
struct GyroBody {
  Quat frame;
  Vec3 moments, inv_moments;
};

/// What prepare_bodies reads: the body store's arrays. Angular arrays (and the
/// orientation) may be null when no body can rotate; forces / damping null when off.
struct SoftBodyInput {
  RigidBodies rigid;  ///< vx..vz, px..pz, inv_mass always; the rest null when !rotating
  bool rotating;
  bool gyroscopic;
  const BodyForces* forces;
  const BodyDamping* damping;
};

struct SoftParams {
  float dt;              ///< s, the step
  float h;               ///< s, a substep
  float bias_rate, mass_scale, impulse_scale;
  float slop;            ///< m
  float max_push_speed;  ///< m/s
  float restitution_threshold;
  float warm_start;      ///< factor on last step's impulses
};

/// The stiffest contact the soft step takes, as a fraction of the substep rate 1/h
/// (Box3D's cap; h * omega <= pi/4): stiffer contacts at a given substep make piles
/// jitter and slide (docs/solver.md, "Stiffness and substeps").
inline constexpr float kMaxHertzPerSubstepRate = 0.125f;

/// Soft constraint coefficients for stiffness hertz (<= 0: the cap, substep rate / 8;
/// larger values are capped there), damping ratio zeta, substep h = dt / substeps.
SoftParams soft_params(float dt, uint32_t substeps, float hertz, float zeta);

/// Lanes of a constraint block: kSimdWidth (kernels/simd/lanes.h).
inline constexpr uint32_t kContactLanes = simd::kSimdWidth;

/// Constraint slots: colour k's constraints take slots colour_start .. + count, with
/// colour_start a multiple of kContactLanes (each colour padded to whole blocks).
/// Slot i is lane i % kContactLanes of block i / kContactLanes.
IMPACT_INLINE uint32_t contact_blocks(uint32_t constraints) {
  return (constraints + kContactLanes - 1) / kContactLanes;
}

/// Point j of every lane of a block (SoA over the lanes).
struct ContactBlockPoint {
  static constexpr uint32_t W = kContactLanes;
  float ra[3][W], rb[3][W];  ///< anchors: point - centre of mass, world, at the step's start
  float base[W];             ///< s0 - dot(rb - ra, n)
  float normal_mass[W];
  float impulse[W];          ///< accumulated normal impulse of a substep, N s (warm starts the next)
  float total[W];            ///< impulse the step applied: the sum over substeps, plus restitution's
  float max_impulse[W];      ///< largest accumulated impulse of the step (restitution's "touched")
  float approach[W];         ///< relative normal velocity at the step's start (restitution)
  float lever[W];            ///< |ra - centre_a| (twist friction's arm)
};

/// kContactLanes constraints, one a lane, SoA (Box2D v3 / Box3D b3ContactConstraintWide).
/// A padding lane (past its colour's end) has count 0, both bodies the zero body and
/// zero masses: the kernels act on nothing there and write no body. Points j >= count
/// of a lane are zero.
struct alignas(64) ContactBlock {
  static constexpr uint32_t W = kContactLanes;
  int32_t a[W], b[W];         ///< SolverBody indices; b == body_count for a plane
  int32_t count[W];           ///< points, 0 (padding) .. 4
  int32_t deep[W];            ///< 1: deeper than max_push_speed * dt, no soft bias (held rigid)
  float ma[W], mb[W];         ///< inverse masses
  float ia[6][W], ib[6][W];   ///< world inverse inertias (Sym3 order: xx yy zz xy xz yz)
  float n[3][W], t1[3][W], t2[3][W];  ///< normal (a -> b) and tangents
  float ca[3][W], cb[3][W];   ///< friction anchor relative to each centre of mass
  float friction[W], restitution[W], rolling[W];
  float k11[W], k12[W], k22[W];  ///< inverse 2x2 tangent mass
  float twist_mass[W];
  float rolling_mass[6][W];   ///< (I_a^-1 + I_b^-1)^-1
  float f1[W], f2[W], twist[W];  ///< accumulated friction impulses
  float roll[3][W];           ///< accumulated rolling impulse
  ContactBlockPoint p[kMaxContactPoints];
};

/// order[i] of a padding slot.
inline constexpr uint32_t kNoConstraint = 0xffffffffu;

/// Warm-start values of one point of last step: its normal impulse, and its
/// manifold's friction impulse (world), twist and rolling impulses.
struct WarmPoint {
  float normal;
  float fx, fy, fz;
  float twist;
  float rx, ry, rz;
};

/// Per-body material tables the constraints combine: friction sqrt(f_a f_b),
/// restitution max(e_a, e_b), rolling max(ρ_a, ρ_b). Plane entries by plane index.
struct ContactMaterials {
  const float* friction;
  const float* restitution;
  const float* rolling;
  const float* plane_friction;
  const float* plane_restitution;
};

/// gyro may be null when !in.gyroscopic or !in.rotating.
void prepare_bodies(const SoftParams& p, Vec3 gravity, const SoftBodyInput& in, SolverBody* IMPACT_RESTRICT out,
                    BodyDrive* IMPACT_RESTRICT drive, Sym3* IMPACT_RESTRICT inv_inertia, Vec3* IMPACT_RESTRICT com,
                    GyroBody* IMPACT_RESTRICT gyro, Range r);

/// Constraint slots i in r: manifold order[i] of c becomes the constraint in slot i
/// (order[i] == kNoConstraint: a padding lane); warm[k] (null: cold) is point row k's
/// value from last step (normal < 0: no match). Per slot, scalar; any partition of the
/// slots gives the same bytes.
void prepare_contacts(const SoftParams& p, const ContactManifoldArrays& c, const uint32_t* order,
                      const SolverBody* bodies, const Sym3* inv_inertia, const Vec3* com, uint32_t body_count,
                      const ContactMaterials& mat, const WarmPoint* warm, ContactBlock* IMPACT_RESTRICT out, Range r);

void integrate_substep_velocities(const BodyDrive* IMPACT_RESTRICT drive, SolverBody* IMPACT_RESTRICT b, Range r);
/// gyro: null, or prepare_bodies' per-body gyroscopic data.
///
/// The gyroscopic update conserves angular momentum instead of integrating the torque
/// -w x I w: w is re-derived from the unchanged world momentum L at the orientation
/// reached by turning with the mean of the old w and the w so derived at the turn by
/// the old w (one fixed-point step of the implicit midpoint rule, second order). For a torque-free body L is kept
/// to rounding, and the energy stays below |L|^2 / (2 I_min) (stable at any spin;
/// the implicit Euler step of kernels/integrate/rigid_euler.h, which the Jacobi path
/// uses, is stable too but dissipates; docs/solver.md).
void integrate_substep_positions(float h, const GyroBody* IMPACT_RESTRICT gyro, SolverBody* IMPACT_RESTRICT b,
                                 Range r);

/// The constraint passes over blocks r of one colour (no two lanes of a range share
/// a dynamic body): kContactLanes constraints at a time, one a lane (FloatW), bodies
/// gathered per lane and scattered back to the lanes whose body is dynamic.
void warm_start_contacts(const ContactBlock* blocks, SolverBody* bodies, Range r);
void solve_contacts(const SoftParams& p, bool use_bias, ContactBlock* blocks, SolverBody* bodies, Range r);
void restitute_contacts(const SoftParams& p, ContactBlock* blocks, SolverBody* bodies, Range r);

/// The same passes over slots r one after another (Float1, the same template), for
/// constraints that may share bodies: the overflow colour. For a range of one colour
/// they give the bytes of the block passes.
void warm_start_contacts_serial(const ContactBlock* blocks, SolverBody* bodies, Range r);
void solve_contacts_serial(const SoftParams& p, bool use_bias, ContactBlock* blocks, SolverBody* bodies, Range r);
void restitute_contacts_serial(const SoftParams& p, ContactBlock* blocks, SolverBody* bodies, Range r);

/// Warm-start values of constraint slots r (padding slots skipped), written at their
/// manifolds' point rows (c's first_point for the rows), and each point's total
/// impulse of the step (ContactArrays::impulse).
void store_contacts(const ContactManifoldArrays& c, const uint32_t* order, const ContactBlock* blocks,
                    WarmPoint* IMPACT_RESTRICT out, float* IMPACT_RESTRICT impulse_out, Range r);

/// Last step's stored values, keys sorted ascending with the rows of their values
/// and start[a] over body a = key >> 32 (a < body_count).
struct WarmTable {
  const uint64_t* keys;
  const uint32_t* index;
  const uint32_t* start;
  const WarmPoint* values;
  uint32_t body_count;
};

/// Per point k in r: out[k] = the value stored under keys[k] last step, or normal = -1.
void match_warm_points(const uint64_t* IMPACT_RESTRICT keys, const WarmTable& prev, WarmPoint* IMPACT_RESTRICT out,
                       Range r);

/// Velocities, positions and orientations back into the store.
void finish_bodies(const SoftBodyInput& in, const SolverBody* IMPACT_RESTRICT b, const Vec3* IMPACT_RESTRICT com,
                   Range r);

}  // namespace impact::kernels
