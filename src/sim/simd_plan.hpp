// What Batch's lane kernels (simd_lane_step.hpp, one translation unit per instruction
// set) read and write: plain structs and pointers, so that those units, compiled with -mavx2 or
// -mavx512f, share no inline function with the rest of the library. docs/simd_batch.md.
#pragma once

#include <cstddef>

#include "featherdrive/constraint/row_kind.hpp"
#include "featherdrive/constraint/row_kinds.hpp"

namespace featherdrive::simd {

/// Per-environment parameters are stored in groups of kGroup environments, interleaved: entry k of
/// environment e at ((e / kGroup) * entries + k) * kGroup + e % kGroup. A block of W | kGroup
/// lanes reads entry k of its environments as one vector, whatever W.
inline constexpr int kGroup = 8;
/// A block holds K vectors of W lanes (simd_lane_step.hpp's Pack): K independent chains of
/// dependencies per operation. K = 4 with AVX2 where the batch fills such blocks, else 2; AVX-512
/// always 2, which measured faster on one thread and on two; SSE2, the fallback of CPUs without
/// AVX2, always 2, for one instantiation fewer to compile (docs/simd_batch.md).
inline constexpr int kMaxInterleave = 4;
constexpr int interleave(int width, int count) {
  return width == 4 && count >= 4 * width ? 4 : 2;
}

enum DofParameter : int {
  has_drive,
  acceleration,
  stiffness,
  damping,
  max_force,
  max_impulse,
  target_position,
  target_velocity,
  lower,
  upper,
  armature,
  static_friction,
  dynamic_friction,
  viscous_friction,
  max_velocity,  ///< the joint's velocity limit, +inf for none
  wrapped,       ///< 1: a revolute joint whose position wraps at the step's end (revolute_wrap.hpp)
  // The actuator envelope (ActuatorEnvelope; max_effort 0: none).
  envelope_max_effort,
  envelope_max_velocity,
  envelope_gradient,
  envelope_resistance,
  friction_coefficient,  ///< PhysX's transmitted-force friction (joint_constraints.md J6)
  // An implicit actuator (ExplicitActuator with implicit_law; docs/math/implicit_actuators.md): its
  // row takes the drive's (a dof with one has no drive).
  implicit_actuator,  ///< 1: the dof's row is its implicit actuator's
  actuator_kind,      ///< its clip: 1 dc_motor, 2 remotized_pd, 0 the outer bound alone
  actuator_stiffness,
  actuator_damping,
  actuator_effort_limit,
  actuator_saturation,      ///< dc_motor: the stall effort
  actuator_velocity_limit,  ///< dc_motor: the no-load speed
  // The command the actuator sees this step (eq. I16), set before every step.
  command_position,
  command_velocity,
  command_effort,
  // The row kinds (constraint/row_kinds.hpp): whether the dof has each (1 or 0, RowKinds' order),
  // then their fields (Settings::row_parameters' row).
  row_kind_on,
  row_kind_fields = row_kind_on + RowKinds::size,
  kDofParameters = row_kind_fields + RowKinds::fields
};
enum LinkParameter : int {
  mass,
  com_x,
  com_y,
  com_z,
  inertia_xx,
  inertia_yy,
  inertia_zz,
  inertia_xy,
  inertia_xz,
  inertia_yz,
  // PhysX's per-link parameters (LinkParameters; docs/math/joint_constraints.md).
  link_cfm_scale,
  link_linear_damping,
  link_angular_damping,
  link_max_linear_velocity,
  link_max_angular_velocity,
  kLinkParameters
};

/// An environment's own parameters of the whole model, after its mimic rows': gravity, per lane
/// (environments of one lane group may differ in it; docs/simd_batch.md, "Lane groups").
enum EnvParameter : int { gravity_x, gravity_y, gravity_z, kEnvParameters };

/// A mimic row's parameters (MimicJoint), per environment.
enum MimicParameter : int {
  mimic_gear_ratio,
  mimic_offset,
  mimic_natural_frequency,
  mimic_damping_ratio,
  kMimicParameters
};

/// A mimic row's dofs, the same in every lane (docs/math/mimic_joints.md).
struct MimicConstants {
  int dof_a = 0, dof_b = 0;    ///< follower and leader
  int q_a = 0, q_b = 0;        ///< their positions in q
  int slot_a = 0, slot_b = 0;  ///< their indices in Plan::mimic_dofs
};

/// A link's topology and joint constants, the same in every lane.
struct LinkConstants {
  int parent = -1;
  int type = 0;  ///< 0 fixed, 1 revolute, 2 prismatic, 3 floating (the root only), 4 spherical
  int v_index = 0;
  int q_index = 0;
  int unit_axis = -1;  ///< k for an axis +-e_k, else -1
  double axis_sign = 1.0;
  bool tree_rotation_identity = false;
  /// The inertia about the centre of mass is diagonal in the link frame (in every lane: the
  /// setters scale it, never rotate it).
  bool diagonal_inertia = false;
  bool first_child = true;  ///< its parent's first child
  bool last_child = true;   ///< no sibling after it
  bool later = false;       ///< it or an ancestor has a sibling after it
  bool leaf = true;         ///< it has no children
  bool finish_on_leave = false;
  /// It carries collision shapes and Plan::contacts: its ground contact rows are solved right
  /// after its joint's (the sweep's C15), and its children add to the pA they start.
  bool contacts = false;
  /// One dof with a one-dof parent: the sweep's hand-over forms (implicit_drives.md, eq. GS1-GS3)
  /// apply; chain_in when the parent is link i - 1 and has no contacts too, so that the sweep
  /// enters this link right after it and its base comes from the parent's impulse.
  bool parent_one_dof = false;
  bool chain_in = false;
  /// Left in a run of only children (sweep_walk::chain_up, its parent of any kind).
  bool chain_up = false;
  /// A child's finish after the sweep reads the later-subtree change this link's finish stores
  /// (implicit_drives.md, eq. SW5): a fixed link's finish does nothing, a one-dof link's stores
  /// nothing, where none does.
  bool later_read = false;
  /// One dof, finished after the sweep, and its only child too (link i + 1): the child's E is
  /// this link's (eq. SW5), carried down in registers (LaneStep::finish_run).
  bool finish_down = false;
  double E[9] = {};     ///< tree transform rotation, row-major
  double r[3] = {};     ///< tree transform translation (parent frame)
  /// E^T as a unit quaternion (w x y z): a floating root's joint frame in the world, which
  /// compat physx turns the root about (momentum_correction.cpp's integrate_root_about_com).
  double frame_q[4] = {1.0, 0.0, 0.0, 0.0};
  double axis[3] = {};  ///< unit joint axis (joint frame)
};

/// Where a block's scratch keeps each quantity, counted in vectors (make_layout, lane_engine.cpp, fills it).
struct Layout {
  // Per dof, kRowFields vectors: the drive row, accumulators, limit errors, masks.
  enum RowField : int {
    tvb,
    velm,
    impm,
    biasc,
    tpb,
    maxi,
    dimp,
    low,
    high,
    err_low,
    err_high,
    recip,
    has_limit,
    driven,
    delta_x,
    response,
    has_friction,
    fstat,
    fdyn,
    fvisc,
    fimp,
    vmax,   ///< the velocity limit (+inf: none)
    vlimp,  ///< the velocity limit row's accumulated impulse
    has_envelope,  ///< an actuator envelope bounds the drive
    external,      ///< the applied joint force times dt (part of the actuator's effort)
    has_tf,        ///< transmitted-force friction (friction coefficient, no static or viscous)
    tf_bound,      ///< its bound coefficient h |F| [N s]
    tf_imp,        ///< PGS: its accumulated impulse
    tf_applied,    ///< all its impulse changes of the step
    x_start,       ///< the dof's position at the step's start (a remotized_pd clip reads it)
    kind_masks,    ///< per row kind: 1 where the lane's dof has it (RowKinds' order)
    kind_slots = kind_masks + RowKinds::size,  ///< the kinds' rows (their slot offsets)
    kRowFields = kind_slots + RowKinds::slots
  };
  // The mimic rows (MimicRowOf's three fields per row), each row's velocity change at the coupled
  // dofs per unit impulse (rows x coupled dofs), those dofs' current velocities, and the joint
  // impulses a sweep applies as given (the mimic rows').
  int mimic_row = 0, mimic_change = 0, mimic_velocity = 0, given = 0;
  // Per dof: the implicit actuators' forces, and for convergence tracking the drive impulses
  // before the last position iteration and their change in it.
  int af = 0, before = 0, change = 0;
  // compat physx's prismatic departure (Plan::physx_prismatic): each link's centre of mass and
  // its velocity at the step's start, link bias (angular, linear) and accumulated turn, its pose
  // at the current sub-step, and each dof's row bias.
  int start_com = 0, com_velocity = 0, bias_w = 0, bias_v = 0, turn = 0, now_R = 0, now_pos = 0,
      row_bias = 0;
  // A floating root (Plan::floating_base): its rotation in the world R0 and its joint's R_q (the
  // step's start axes of compat none's root velocity), U = IA S and D^-1 as full 6 x 6 matrices.
  int root_R = 0, root_Rq = 0, root_U = 0, root_D_inv = 0;
  // Spherical joints (Plan::any_spherical), per link: S, U and W as 6 x 3 (column by column),
  // D^-1 and the unit-response block as 3 x 3 (row-major).
  int ball_S = 0, ball_U = 0, ball_W = 0, ball_D_inv = 0, ball_response = 0;
  int ball_w = 0;  ///< compat physx: each link's angular velocity of a (sub)step, start frames
  // compat physx on a floating root (Plan::physx_floating): the step's start poses (world axes,
  // positions from the root's origin), link forces (link damping), the free velocity's momentum
  // targets P0, L0 with the start's centre of mass and total mass (10), the compound inertia's
  // inverse, link velocities of a momentum pass, the pose after the step and
  // the velocity the positions moved with.
  int start_R = 0, start_pos = 0, link_force = 0, targets = 0, compound_inverse = 0, vel_w = 0,
      vel_v = 0, now_com = 0, qd_position = 0;
  int contact_vel = 0;  ///< Plan::contacts: each link's velocity at a sweep's start (frame 0)
  /// Plan::physx_contacts: each link's bias B as a twist in frame 0 (contact.md, C23a) and its
  /// motion since the step's start as PhysX tracks it (C25a).
  int contact_bias = 0, contact_motion = 0;
  int R = 0, pos = 0, S = 0, IA = 0, pA = 0, c = 0, U = 0, D_inv = 0, acc = 0, Lambda = 0, W = 0,
      G = 0, inverse_mass = 0, vel = 0, dv = 0, subtree = 0, after = 0, later = 0, q = 0, qd = 0,
      tau = 0, u = 0, old_q = 0, old_qd = 0, old_df = 0, old_lf = 0, old_ff = 0, old_vf = 0, df = 0,
      lf = 0, ff = 0, vf = 0, rk = 0, old_rk = 0, cg = 0, cfm = 0, row = 0, jimp = 0, entry = 0, saved = 0, saved_tgs = 0, zero = 0, flags = 0, size = 0;
  /// Per link with a one-dof parent (LinkConstants::parent_one_dof), from the response pass:
  /// U_i^T S_p and the base's change per parent impulse; chain_base, the base a chained link is
  /// entered with (implicit_drives.md, eq. GS1-GS3).
  int chain_pS = 0, chain_pi = 0, chain_base = 0;
};

struct Plan {
  int num_links = 0, nq = 0, nv = 0;
  const LinkConstants* links = nullptr;
  const int* finish_after = nullptr;  ///< links finished after a sweep, in order
  int num_finish_after = 0;
  /// The mimic rows, in the order they are solved, and the dofs they couple.
  int num_mimic = 0, num_mimic_dofs = 0;
  const MimicConstants* mimic = nullptr;
  const int* mimic_dofs = nullptr;
  int entries = 0;  ///< parameters per environment
  double dt = 0.0;
  bool tgs = false;
  /// Link 0 is a floating root (six dofs: body-frame [w; v], q: position and quaternion w x y z).
  bool floating_base = false;
  /// Some link has a spherical joint (three dofs: twist, swing1, swing2; q: quaternion w x y z).
  bool any_spherical = false;
  /// Some environment has a finite joint velocity limit: steps start by scaling qd to them.
  bool any_velocity_limit = false;
  /// Some environment has a friction coefficient: steps form the joints' transmitted forces.
  bool any_transmission_friction = false;
  /// Some environment's dof has a row kind: steps report the kinds' forces (else a call writes
  /// zeros once, at its end).
  bool any_row_kinds = false;
  /// Some environment has link damping or a link velocity limit (forces on the free velocity),
  /// some a cfm_scale (the rows' 1 / (r + cfm)).
  bool any_link_damping = false, any_cfm = false;
  /// compat physx with a prismatic joint: its rows see the link bias, TGS measures its position
  /// change geometrically and its position is clamped to its limits (physx_departures.md, PD-1
  /// to PD-3).
  bool physx_prismatic = false;
  /// compat physx on a floating root: its momentum corrections and its pose integrated about its
  /// centre of mass (physx_departures.md, section 2); the links' bias (PD-1) feeds them.
  bool physx_floating = false;
  /// compat physx with a spherical joint: its rows' link bias (S-8), its link turned in the world.
  bool physx_spherical = false;
  /// Some environment's ground or self-collision is on and the model has shapes: each
  /// environment's own contact rows (ContactRows, SelfContacts) run in its lane, out of line
  /// (lane_contacts.cpp).
  bool contacts = false;
  /// compat physx; with contacts: their rows see the link bias and PhysX's tracked motion.
  bool physx = false, physx_contacts = false;
  /// Some environment has an implicit actuator: the drive force of its dofs is the actuator's.
  bool any_implicit_actuator = false;
  int position_iterations = 1, velocity_iterations = 0;
  double limit_erp = 0.8;
  Layout layout;
};

/// What the step guard reads of a dof's rows after a lane step (GuardRow, workspace.hpp):
/// kGuardFields values a dof in Block::guard_rows.
enum GuardField : int {
  guard_drive,
  guard_low,
  guard_high,
  guard_friction,
  guard_transmission,
  guard_velocity_limit,
  guard_response,
  guard_max_impulse,
  guard_has_drive,
  guard_has_envelope,
  guard_row_kinds,  ///< each row kind's impulse (RowKinds' order)
  kGuardFields = guard_row_kinds + RowKinds::size
};

/// Why a lane stopped: the first non-finite quantity in Simulation's order.
struct Stop {
  /// 0 none, 1 velocity qd, 2 drive force, 3 limit force, 4 friction force, 5 velocity limit
  /// force, 6 position q, 7 a link's contact force (dof: 3 link + component), 8 the step guard's
  /// scalar redo diverged (LaneEngine keeps its message), 10 + k row kind k's force
  int quantity = 0;
  int dof = -1;
  double value = 0.0;
};

/// Each environment's ground and self-contact rows (lane_engine.hpp), which the lane step calls
/// out of line, one lane at a time, on that lane's entries of its scratch (docs/simd_batch.md,
/// "Contacts"). s: the scratch as doubles; entry k of a lane at s[k * width + lane].
struct ContactLanes;
/// Where a contact solve stands (ContactPhase's fields).
struct LaneContactPhase {
  double dt = 0.0, h = 0.0, elapsed = 0.0;
  bool tgs = false, velocity_iteration = false;
};
/// Whether environment env's contact rows run: its ground's (the ground is on), its self
/// contacts' (self_collision is on and some pair can touch), either.
bool contacts_active(const ContactLanes& c, int env);
bool ground_active(const ContactLanes& c, int env);
bool self_contacts_active(const ContactLanes& c, int env);
/// The step's start: the shape links' poses (before the response takes their room), then the
/// rows from the response, the cfm and the link velocities (layout contact_vel).
void contact_poses(ContactLanes& c, const Plan& p, int env, const double* s, int width, int lane);
void contact_setup(ContactLanes& c, const Plan& p, int env, const double* s, int width, int lane);
/// The self-contact rows, each iteration before the sweep (Stepper::sweep; contact.md, C31), at
/// the joint velocities (layout qd), which they change.
void contact_self_solve(ContactLanes& c, const Plan& p, int env, const LaneContactPhase& phase,
                        double* s, int width, int lane);
/// Link's ground rows in a sweep at its start velocity plus its change dv (layout dv), which they
/// change; their impulse starts its subtree impulse (layout subtree).
void contact_solve(ContactLanes& c, const Plan& p, int env, int link, const LaneContactPhase& phase,
                   double* s, int width, int lane);
/// TGS: the points moved over a sub-step h at the link velocities (layout contact_vel).
void contact_track(ContactLanes& c, const Plan& p, int env, double h, const double* s, int width,
                   int lane);
/// The step's contact forces into the environment's reports; the first non-finite one as a Stop
/// (quantity 7), or quantity 0.
Stop contact_report(ContactLanes& c, const Plan& p, int env);
/// The step's end: the anchors kept (kept) or, for a lane that stopped, no contacts reported.
void contact_conclude(ContactLanes& c, int env, bool kept);
struct ActuatorTables;  // lane_engine.hpp: every lane's remotized_pd tables

/// One block of lanes: environments env0 ... env0 + W - 1, of which the first `valid` exist (the
/// others repeat environment env0 + valid - 1 and are never written). States are (N, n) row-major;
/// the parameters, stops and contacts are the engine's, by lane index e, the state arrays' row of
/// lane e is rows[e] (a lane group's members in the Batch), or e without rows.
struct Block {
  int env0 = 0, valid = 0;
  const int* rows = nullptr;
  int interleave = 2;  ///< K: vectors of the block (2 or 4; 1 for one lane)
  double* q = nullptr;
  double* qd = nullptr;
  const double* applied = nullptr;
  double* drive_force = nullptr;
  double* limit_force = nullptr;
  double* friction_force = nullptr;
  double* velocity_limit_force = nullptr;
  double* row_force = nullptr;  ///< (N, RowKinds::size nv): the row kinds' forces, kind after kind
  const double* parameters = nullptr;  ///< the whole packed array
  long* step_count = nullptr;
  double* time = nullptr;
  Stop* stop = nullptr;         ///< per environment; quantity != 0: stopped
  bool* stopped_now = nullptr;  ///< per environment: stopped in this call
  bool any_limit = true;        ///< some lane has a finite joint limit
  ContactLanes* contacts = nullptr;  ///< Plan::contacts: each environment's contact rows
  /// (N, nv), or null: the implicit actuators' forces, written at their dofs (0 elsewhere).
  double* actuator_force = nullptr;
  /// (N, nv), or null (no environment tracks convergence): each drive impulse's change in the
  /// last position iteration (Simulation::last_drive_impulse_change), kept for stopped lanes.
  double* drive_change = nullptr;
  const ActuatorTables* tables = nullptr;  ///< the remotized_pd tables (lane_engine.hpp)
  /// (N, nv kGuardFields), or null (no environment is guarded): each dof's rows of the last step
  /// (GuardField), for the step guard, which Batch runs one step a call.
  double* guard_rows = nullptr;
};

/// A spherical joint's PhysX positions (twist, swing1, swing2) and drive errors for the
/// orientation q (w x y z, normalised here as Simulation does) and its axes' targets (driven: 1 or 0): spherical_axes.hpp's,
/// out of line, so that the lane units call it on plain arrays.
void spherical_axes(const double* q, const double* target, const double* driven, double* position,
                    double* error);
/// The remotized_pd table's limit of environment env's dof at position x (lookup_effort_limit),
/// out of line, so that the lane units call it on plain values.
double table_effort_limit(const ActuatorTables& tables, int env, int dof, double x);
/// compat physx: the unit quaternion of the rotation m (row-major) in q's hemisphere, written over
/// q (w x y z): spherical_rows.cpp's, out of line.
void rotation_quaternion(const double* m, double* q);

/// The layout of p's scratch, and the doubles of scratch one block of any width needs (kGroup
/// kMaxInterleave doubles a vector).
Layout make_layout(const Plan& p);
std::size_t scratch_doubles(const Plan& p);

/// `steps` steps of one block of lanes (simd_lane_step_<isa>.cpp); scratch: scratch_doubles(p),
/// 64-byte aligned.
void run_block_sse2(const Plan& p, const Block& b, double* scratch, int steps);
void run_block_avx2(const Plan& p, const Block& b, double* scratch, int steps);
void run_block_avx512(const Plan& p, const Block& b, double* scratch, int steps);
/// One lane (Block: W = 1, interleave 1; simd_lane_step_one.cpp): the same bits as any width.
void run_block_one(const Plan& p, const Block& b, double* scratch, int steps);

}  // namespace featherdrive::simd
