// What a Simulation keeps beside its model, settings, state storage and clock (simulation.hpp),
// and the step's stages over them: internal, so that the public header shows none of it.
// docs/architecture.md lists the stages.
#pragma once

#include <optional>
#include <vector>

#include "featherdrive/algorithm/data.hpp"
#include "featherdrive/constraint/contact_rows.hpp"
#include "featherdrive/constraint/dof_rows.hpp"
#include "featherdrive/sim/drive_delay.hpp"
#include "featherdrive/sim/explicit_actuator.hpp"
#include "featherdrive/sim/physx_departures.hpp"
#include "featherdrive/sim/settings.hpp"
#include "featherdrive/sim/simulation.hpp"
#include "featherdrive/solver/gauss_seidel.hpp"
#include "featherdrive/solver/mimic_solve.hpp"
#include "featherdrive/solver/self_contacts.hpp"

namespace featherdrive {

/// What the step guard reads of a dof's rows after an advance (step_guard.cpp, eq. G-3, G-7,
/// G-10): filled from the rows by the scalar step, from the lanes' rows by Batch's lanes.
struct GuardRow {
  double drive_impulse = 0.0, low_impulse = 0.0, high_impulse = 0.0, friction_impulse = 0.0;
  double transmission_friction_applied = 0.0, velocity_limit_impulse = 0.0;
  double response = 0.0;     ///< r = (M^-1)_jj
  double max_impulse = 0.0;  ///< the drive row's bound
  bool has_drive = false, has_envelope = false;
  /// Each row kind's accumulated impulse (RowKinds' order; 0 without the row).
  std::array<double, RowKinds::size> kind_impulse{};
};

/// The workspace of one simulation: the step's working copies of the state and its scratch, the
/// setters' copies of settings that carry delay histories or buffers (actuators, drive delays,
/// mimic rows), the contact rows with their anchors, the outputs a State does not hold and the
/// step guard's scratch and counters. Sized at construction, so that a step allocates nothing.
struct Workspace {
  Workspace(const Model& model, const Settings& settings);

  /// Whether Stepper::control_stages changes anything (actuators, delays, or efforts to clear).
  bool has_control_stages() const { return actuators.any() || drive_delays.any() || actuated; }
  /// Which of PhysX's link stages run (link damping, link cfm), from the settings.
  void update_link_damping_active(const Settings& settings);
  /// Which contact rows run (contact.cpp), from the settings and the model's shapes.
  void update_contacts_active(const Model& model, const Settings& settings);
  /// The guard's scratch (step_guard.cpp).
  void size_guard(const Model& model);
  /// The contact rows of the model's shapes and room for their points.
  void set_shapes(const Model& model);

  Data data;  ///< poses of the step's start, velocities in frame 0
  SweepWorkspace sweep;

  // The step works on copies of the stored state (Stepper::load_state, commit_state), so a
  // diverging step leaves the storage as it was.
  VecX q, qd;
  VecX applied_force;
  VecX drive_force, limit_force, friction_force, velocity_limit_force;
  VecX row_force;  ///< the row kinds' forces, nv each, kind after kind
  /// Some dof has a row kind (setup_rows' last full set-up); the stored row_force may be nonzero
  /// (a state was set, kinds changed, the lanes stepped): a step writes row_force while either
  /// holds, and leaves the stored zeros alone otherwise.
  bool any_row_kinds = false, row_force_live = true;
  bool track_convergence = false;
  VecX last_drive_change;  ///< see Simulation::last_drive_impulse_change (nv)

  // Per-step scratch.
  std::vector<DofRows> rows;  ///< every dof's rows for this step
  bool any_rows = false;
  /// A row other than a lone drive (acts in TGS velocity iterations).
  bool any_undriven_rows = false;
  /// PGS, compat none, no mimic rows, and every row a lone drive's (step.cpp, sweep).
  bool only_lone_drives_pgs = false;
  /// Every dof once: first the num_lone_drives whose only row is an undelayed drive on a revolute
  /// or prismatic joint, then the others from the back. setup_rows sets up only the drive row of
  /// the first, and sorts the dofs again after a setter changed what the sorting reads
  /// (row_kinds_changed). Sized nv at construction: a copy of the simulation keeps the size.
  std::vector<int> dof_order;
  int num_lone_drives = 0;
  bool row_kinds_changed = true;
  VecX delta_x;               ///< TGS: position change accumulated over the sub-steps per dof
  Mat3 root_rotation0 = Mat3::Identity();  ///< a floating root's axes at the step's start
  PhysxDepartures departures; ///< compat physx: the link bias and momentum corrections
  // PhysX's parameters (physx_stages.hpp), per link.
  std::vector<Vec6> link_force;     ///< link damping / velocity-limit forces, frame 0
  bool any_link_force = false;
  bool link_damping_active = false;  ///< some link has damping or a velocity limit
  bool link_cfm_active = false;      ///< some link has a cfm_scale (else link_cfm stays 0)
  VecX transmitted_force;           ///< |F| through each link's inbound joint
  VecX link_cfm;
  // Explicit actuators: their efforts, the applied force plus them, and the copy for a restore.
  ExplicitActuators actuators;
  VecX actuator_force, joint_force, actuator_force_start;
  bool actuated = false;  ///< the last step had actuators (actuator_force may be nonzero)
  bool actuated_start = false;
  DriveDelays drive_delays;  ///< pushed after the actuators, read by setup_rows
  MimicSolver mimic;

  // Contacts (contact.cpp): the rows, the last step's points (the first num_contacts of
  // contacts, sized for the shapes' most points at construction) and per-link forces.
  ContactRows contact_rows;
  bool contacts_active = false;  ///< the ground is on and the model has shapes
  SelfContacts self_contacts;    ///< contacts between the robot's own shapes, after the ground's
  bool self_contacts_active = false;  ///< self_collision is on and some pair can touch
  std::vector<Vec6> contact_link_velocity;  ///< frame 0, at a sweep's start
  /// compat physx: each link's bias B (departure 1) in frame 0, which PhysX's contact rows see on
  /// the link's velocity (docs/math/contact.md, C23a).
  std::vector<Vec6> contact_link_bias;
  /// compat physx, TGS: each link's motion since the step's start as PhysX tracks it for its
  /// contact rows (C25a), frame 0, and its increment over a sub-step.
  std::vector<Vec6> contact_link_motion, contact_link_motion_step;
  std::vector<ContactReport> contacts;
  int num_contacts = 0;
  int num_ground_contacts = 0;  ///< the first of contacts; the self contacts follow
  std::vector<Vec3> link_contact_force;

  // The step guard: the time the advance covers (options().dt, or dt / n in a guard sub-step),
  // how long before the step's end the sub-step ends (its drive targets lead by it), the
  // scratch (sized by size_guard, so that a guarded step allocates nothing) and the counters.
  double dt = 0.0;
  double target_lead = 0.0;
  std::optional<Data> guard_data;  ///< for the energies (a second Data: data keeps the step's)
  VecX guard_q0, guard_qd0, guard_force, guard_actuator, guard_impulse[4];
  VecX guard_row_impulse;  ///< the row kinds' impulses summed over sub-steps, as row_force
  std::vector<GuardRow> guard_rows;  ///< the advance's rows, as the tests read them
  double guard_e0[2] = {0.0, 0.0};  ///< the step's start energies (kinetic, potential)
  /// The last step's end state and energies: the next step's start, unless a setter moved it.
  VecX guard_q1, guard_qd1;
  double guard_e1[2] = {0.0, 0.0};
  bool guard_e1_valid = false;
  /// A redone step's contacts: the anchors at its start (each n starts from them), the links'
  /// contact impulses / dt summed over its sub-steps, the links' end velocities (frame 0) the
  /// contacts' work reads (eq. G-3a).
  std::vector<FrictionAnchors> guard_anchors;
  std::vector<Vec3> guard_link_contact_force;
  std::vector<Vec6> guard_link_velocity;
  GuardAccount guard_account;  ///< test (iii): committed with the step
  GuardAccount guard_account_next;  ///< the account after the (sub-)step being tested
  int guard_substeps = 1;
  long guard_triggers = 0;
  long guard_exhausted = 0;
};

/// The step's stages over one simulation's parts, for the length of a call: begin (actuators,
/// delays; once per step), the physics advance over the workspace's dt, the end (outputs, finite
/// check, commit, clock). Simulation::step and Batch's lanes run them.
class Stepper {
 public:
  Stepper(const Model& model, const Settings& settings, StateStorage& state, double& time,
          long& step_count, Workspace& ws)
      : model_(&model), settings_(settings), state_(state), time_(time),
        step_count_(step_count), ws_(ws) {}

  /// Advances by one step of options.dt; throws DivergenceError (state unchanged) if it would
  /// produce a non-finite value.
  void step();
  /// The step's working copies of the stored state (the step writes every force).
  void load_state();
  /// begin_step's control stages on the loaded q, qd, applied force: the actuators' efforts and
  /// the delays' push; the joint force the physics uses. Batch runs them for its lanes.
  const VecX& control_stages();
  /// What control_stages changed, taken back when the step diverges.
  void undo_actuators();
  /// The end: outputs' finite check (throws DivergenceError, state unchanged), commit, clock.
  void end_step();

  // The step guard in parts, for Batch's lanes, which advance the step themselves
  // (step_guard.cpp, docs/simd_batch.md): guard_start on the loaded step-start state; after the
  // advance (its end loaded as q, qd, its rows in ws.guard_rows) guard_first_passes (true: the
  // step is kept, as a Simulation keeps it); else, from the start loaded again, guard_redo.
  // guarded_advance: the whole guarded advance from the loaded start, the step's forces.
  void guarded_advance(const VecX& tau);
  void guard_start();
  bool guard_first_passes(const VecX& tau);
  void guard_redo();
  void commit_guard_account();

 private:
  bool physx() const { return settings_.options.compat == Compat::physx; }
  // The step's stages (step.cpp).
  const VecX& begin_step();
  /// The actuators' efforts of this step on the step-start state; the joint force the step uses.
  const VecX& apply_actuators();
  void advance(const VecX& tau);
  void row_forces();
  void row_kind_forces(VecX& out, double inv_dt) const;
  void check_finite_or_throw();
  void commit_state();
  void scale_to_velocity_limits();
  void setup_rows(double h, bool tgs);
  void setup_dof_rows(int dof, double h, bool tgs);
  void setup_row_kinds(DofRows& rows, int dof, const RowInputs<double>& in);
  void setup_lone_drives(double h, bool tgs);
  void sweep(RowPhase& phase);
  void solve_pgs();
  void solve_tgs();
  void integrate_positions(double h);
  void begin_classical_root(const Vec6& root_qd0, double dt);
  void end_classical_root();
  // Contacts (contact.cpp, docs/math/contact.md).
  void setup_contacts(const RowPhase& phase);
  void track_contacts(double h);
  void contact_link_velocities();
  void contact_forces();
  void report_contacts();
  void conclude_contacts();
  // The guard (step_guard.cpp).
  void guard_rows_from_step();
  double row_kind_bracket(int dof, double q0, double dq, double h) const;
  /// Tests (i) and (ii) of the advance just made from guard_q0, guard_qd0 (energies e0);
  /// leaves the end's energies in e1.
  bool guard_passes(const VecX& tau, const double e0[2], double e1[2]);
  /// The contact rows' work over the (sub-)step at the end velocities in guard_data (eq. G-3a).
  double guard_contact_work();
  /// A redone step's contacts: the last sub-step's points at the step's rate, the summed forces.
  void guard_contact_forces(int n);
  void guard_energy(const VecX& q, const VecX& qd, double e[2]);  ///< kinetic, potential
  const VecX& guard_substep_force();
  void keep_guard_end(const double e1[2]);
  double damper_power() const;
  double drive_bracket(int d, double q0, double dq, double h) const;
  void lead_drive_targets();

  const Model* model_;
  const Settings& settings_;
  StateStorage& state_;  ///< q, qd, applied force and outputs, written after each whole step
  double& time_;
  long& step_count_;
  Workspace& ws_;
};

}  // namespace featherdrive
