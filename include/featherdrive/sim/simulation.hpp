// One simulation of a Model: its state, its inputs (applied forces, drives), its outputs (drive
// forces) and the workspace a step writes. Many simulations may share one Model across threads.
#pragma once

#include <array>
#include <limits>
#include <memory>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "featherdrive/algorithm/data.hpp"
#include "featherdrive/constraint/contact_rows.hpp"
#include "featherdrive/solver/self_contacts.hpp"
#include "featherdrive/constraint/dof_rows.hpp"
#include "featherdrive/sim/drive_delay.hpp"
#include "featherdrive/sim/explicit_actuator.hpp"
#include "featherdrive/sim/link_parameters.hpp"
#include "featherdrive/sim/physx_departures.hpp"
#include "featherdrive/sim/revolute_wrap.hpp"
#include "featherdrive/sim/settings.hpp"
#include "featherdrive/sim/state.hpp"
#include "featherdrive/solver/gauss_seidel.hpp"
#include "featherdrive/solver/mimic_solve.hpp"

namespace featherdrive {

/// A step that would leave a non-finite position, velocity or force. The simulation keeps the
/// state it had before that step.
class DivergenceError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// A read-only view of one of a simulation's vectors (q, qd, forces): valid as long as the
/// simulation is, and it shows the current values. `auto x = sim.q()` is such a view, not a
/// copy: keep one with `VecX x = sim.q()`.
using VecView = Eigen::Map<const VecX>;

/// Where a simulation keeps q, qd, the applied force and the four output forces: a block of its
/// own, or rows a Batch lends it (batch.hpp), so that a batch's states lie in (N, n) arrays. A
/// copy gets a block of its own with the same values; an assignment copies the values into the
/// storage in place (the addresses stay; a lent storage refuses other sizes).
class StateStorage {
 public:
  enum Field : int { q, qd, applied_force, drive_force, limit_force, friction_force,
                     velocity_limit_force };
  static constexpr int kFields = 7;
  StateStorage() = default;
  StateStorage(Eigen::Index nq, Eigen::Index nv);  ///< an own block of zeros
  StateStorage(const StateStorage& other);
  StateStorage(StateStorage&& other) noexcept = default;
  StateStorage& operator=(const StateStorage& other);
  StateStorage& operator=(StateStorage&& other) { return *this = other; }
  Eigen::Map<VecX> operator[](Field f) { return {data_[f], size_[f]}; }
  VecView operator[](Field f) const { return {data_[f], size_[f]}; }
  Eigen::Index size(Field f) const { return size_[f]; }
  /// Copies the values to rows[f] (size(f) doubles each, kept alive by the lender) and uses them
  /// from now on.
  void lend(const std::array<double*, kFields>& rows);

 private:
  VecX own_;
  std::array<double*, kFields> data_{};
  std::array<Eigen::Index, kFields> size_{};
  bool lent_ = false;
};

class Simulation {
 public:
  explicit Simulation(std::shared_ptr<const Model> model, const SimulationOptions& options = {});

  const Model& model() const { return *model_; }
  const std::shared_ptr<const Model>& model_ptr() const { return model_; }
  const SimulationOptions& options() const { return settings_.options; }
  /// Throws std::invalid_argument for invalid options or a different compat.
  void set_options(const SimulationOptions& options);
  /// Every setting as one value (settings.hpp): what the setters below change one field at a time.
  const Settings& settings() const { return settings_; }
  /// Replaces every setting. Throws std::invalid_argument (Settings::validate; a compat other
  /// than the simulation's) and changes nothing then. The delay histories of the actuators and
  /// drive delays that change are emptied, as their setters do.
  void set_settings(const Settings& settings);
  /// Replaces the model by one of the same topology (link and joint names, parents, joint types
  /// and axes, tree transforms, nq, nv), e.g. other masses, centres of mass or armature
  /// (model_builder.hpp: with_link_inertial, with_armature); state and settings stay. Throws
  /// std::invalid_argument naming the first difference; nothing changes then.
  void set_model(std::shared_ptr<const Model> model);

  // State.
  VecView q() const { return state_[StateStorage::q]; }    ///< configuration (nq)
  VecView qd() const { return state_[StateStorage::qd]; }  ///< joint velocities (nv)
  void set_q(const VecX& q);              ///< quaternions are normalised
  void set_qd(const VecX& qd);
  double time() const { return time_; }
  long step_count() const { return step_count_; }
  /// Sets the clock to one a run could have reached; throws std::invalid_argument otherwise
  /// (check_clock, state.hpp).
  void set_clock(double time, long step_count);
  /// The whole state as one value (state.hpp): q, qd, applied force, clock, the last step's
  /// outputs and the delay histories.
  State state() const;
  /// Restores a state() of a simulation with the same settings, bit for bit (q as given: its
  /// quaternions must have unit norm within 1e-9). Throws std::invalid_argument naming the part
  /// for a size, a non-finite value, a clock no run reaches, or a history that is not the
  /// settings' (ring of delay + 1 on exactly the dofs with an actuator or a drive delay); nothing
  /// changes then.
  void set_state(const State& state);

  // Inputs.
  /// Joint forces applied through the whole step (nv), e.g. feed-forward torques.
  void set_applied_force(const VecX& tau);
  VecView applied_force() const { return state_[StateStorage::applied_force]; }
  void set_drive(int dof, const Drive& drive);
  void set_drive(const std::string& joint, const Drive& drive);
  const Drive& drive(int dof) const {
    return settings_.drives[static_cast<size_t>(check_dof(dof))];
  }
  /// Throws std::invalid_argument naming the joint if the dof has no drive (a target would do
  /// nothing): give it one first (set_drive, set_drive_gains).
  void set_drive_target(int dof, double position, double velocity);
  void set_drive_target(const std::string& joint, double position, double velocity);
  /// For whole-vector setters (nv each): throws std::invalid_argument naming the first dof that
  /// has no drive and a nonzero target position or velocity; zeros there are accepted.
  void check_targets_have_drives(const VecX& positions, const VecX& velocities) const;

  // Joint constraints per dof of revolute and prismatic joints. Initialised from the model: limits
  // from lower_limit/upper_limit (enforced where finite), friction static = dynamic =
  // model.friction with viscous = model.damping, max velocity = model.velocity_limit.
  void set_joint_limits(int dof, double lower, double upper);
  void set_joint_limits(const std::string& joint, double lower, double upper);
  double lower_limit(int dof) const { return settings_.lower_limit[check_dof(dof)]; }
  double upper_limit(int dof) const { return settings_.upper_limit[check_dof(dof)]; }
  void set_joint_friction(int dof, const JointFriction& friction);
  void set_joint_friction(const std::string& joint, const JointFriction& friction);
  const JointFriction& joint_friction(int dof) const {
    return settings_.friction[static_cast<size_t>(check_dof(dof))];
  }
  /// Largest |qd| (m/s or rad/s); +inf for none.
  void set_max_joint_velocity(int dof, double max_velocity);
  void set_max_joint_velocity(const std::string& joint, double max_velocity);
  double max_joint_velocity(int dof) const { return settings_.max_joint_velocity[check_dof(dof)]; }
  /// PhysX's older joint friction: |impulse| <= coefficient * h * |F| per solve, F the spatial
  /// force the joint transmits (docs/math/joint_constraints.md). 0 (none) by default;
  /// PhysX's 0.05 with Compat::physx. Not applied where static or viscous friction is set.
  void set_friction_coefficient(int dof, double coefficient);
  void set_friction_coefficient(const std::string& joint, double coefficient);
  double friction_coefficient(int dof) const {
    return settings_.friction_coefficient[check_dof(dof)];
  }
  void set_actuator_envelope(int dof, const ActuatorEnvelope& envelope);
  void set_actuator_envelope(const std::string& joint, const ActuatorEnvelope& envelope);
  const ActuatorEnvelope& actuator_envelope(int dof) const {
    return settings_.envelopes[static_cast<size_t>(check_dof(dof))];
  }

  // Explicit actuators (explicit_actuator.hpp), on revolute and prismatic dofs without an implicit
  // drive: the dof's drive targets are their targets. Setting one (kind none clears) empties its
  // delay history; a dof with a drive of type != none is refused, as set_drive is on a dof with an
  // actuator. Throw std::invalid_argument naming the joint, the field and the value.
  void set_actuator(int dof, const ExplicitActuator& actuator);
  void set_actuator(const std::string& joint, const ExplicitActuator& actuator);
  const ExplicitActuator& actuator(int dof) const { return actuators_.actuator(check_dof(dof)); }
  bool has_actuator(int dof) const { return actuators_.active(check_dof(dof)); }
  void clear_actuator(int dof) { set_actuator(dof, ExplicitActuator{}); }
  /// The feed-forward effort of the dof's actuator (eq. 1), delayed with its targets.
  void set_actuator_feedforward(int dof, double effort);
  void set_actuator_feedforward(const std::string& joint, double effort);
  /// Empties every actuator's delay history (eq. 9), e.g. when an episode starts over.
  void reset_actuator_history() { actuators_.reset_history(); }
  const ExplicitActuators& actuators() const { return actuators_; }
  /// The effort each actuator applied in the last step (nv; 0 on dofs without one), clipped.
  const VecX& actuator_force() const { return actuator_force_; }

  // Actuator delay of the implicit drive (drive_delay.hpp): the dof's drive row uses the targets
  // set `delay` steps before the step (eq. 8-9 of docs/math/explicit_actuators.md), as Isaac Lab's
  // DelayedPDActuator. drive(dof) reports the targets as commanded, not as delayed. Setting a
  // delay empties the dof's history; set_drive keeps it, but a drive of type none removes it.
  // 0 (the default) is no delay.
  /// Throws std::invalid_argument naming the joint and the value for a delay outside
  /// [0, kMaxDelay], or > 0 on a dof without an implicit drive (type none: it would do nothing;
  /// an explicit actuator has its own delay).
  void set_drive_delay(int dof, int delay);
  void set_drive_delay(const std::string& joint, int delay);
  int drive_delay(int dof) const { return drive_delays_.delay(check_dof(dof)); }
  /// The check of set_drive_delay, changing nothing.
  void check_drive_delay(int dof, int delay) const;
  /// Empties every drive's delay history (eq. 9), e.g. when an episode starts over.
  void reset_drive_delay_history() { drive_delays_.reset_history(); }
  const DriveDelays& drive_delays() const { return drive_delays_; }

  // Link parameters (link_parameters.hpp): inert by default; PhysX 5.6.1's defaults with
  // Compat::physx. Throw std::invalid_argument naming the link, field and value.
  void set_link_parameters(int link, const LinkParameters& parameters);
  void set_link_parameters(const std::string& link, const LinkParameters& parameters);
  const LinkParameters& link_parameters(int link) const;
  const LinkParameters& link_parameters(const std::string& link) const;

  // Revolute wrap and mimic joints (docs/math/revolute_wrap.md, docs/math/mimic_joints.md).
  /// PhysX's eREVOLUTE (wrapped: the position returns into [-2 pi, 2 pi] after each step) or
  /// eREVOLUTE_UNWRAPPED. Unwrapped by default, wrapped with Compat::physx (PhysX's revolute
  /// joint). Throws std::invalid_argument naming the joint for a dof that is not revolute.
  void set_revolute_wrap(int dof, RevoluteWrap wrap);
  void set_revolute_wrap(const std::string& joint, RevoluteWrap wrap);
  RevoluteWrap revolute_wrap(int dof) const;
  /// Replaces the mimic joints (rows q_a + gear_ratio q_b + offset = 0); {} removes them. Throws
  /// std::invalid_argument (validate_mimic_joints); nothing changes then.
  void set_mimic_joints(const std::vector<MimicJoint>& mimic);
  const std::vector<MimicJoint>& mimic_joints() const { return settings_.mimic_joints; }

  // Ground contact (docs/math/contact.md): the model's shapes against the ground.
  /// Throws std::invalid_argument (check_ground); the normal is stored normalised.
  void set_ground(const Ground& ground);
  const Ground& ground() const { return settings_.ground; }
  /// Throws std::invalid_argument (check_contact_options).
  void set_contact_options(const ContactOptions& options);
  const ContactOptions& contact_options() const { return settings_.contact; }

  // Outputs of the last step.
  /// The contact points of the last step and their impulses (empty without a ground).
  std::span<const ContactReport> contacts() const {
    return {contacts_.data(), static_cast<size_t>(num_contacts_)};
  }
  /// The contact force on each link in the last step (num_links; world frame, N): the sum of its
  /// points' impulses / dt.
  const std::vector<Vec3>& link_contact_force() const { return link_contact_force_; }
  /// The drive force of each dof: the step's accumulated drive impulse / dt (ERRATA 7).
  VecView drive_force() const { return state_[StateStorage::drive_force]; }
  /// The position-limit force of each dof (impulse / dt; positive pushes towards +q).
  VecView limit_force() const { return state_[StateStorage::limit_force]; }
  /// The joint-friction force of each dof (impulse / dt), both friction models.
  VecView friction_force() const { return state_[StateStorage::friction_force]; }
  /// The force the joint velocity limit applied on each dof (impulse / dt).
  VecView velocity_limit_force() const { return state_[StateStorage::velocity_limit_force]; }

  /// Diagnostics of the PGS solver's convergence, off by default (a step then stores nothing for
  /// them): with it on, each PGS step keeps how much the last position iteration changed each
  /// dof's drive impulse. Not kept in checkpoints.
  void set_track_convergence(bool on);
  bool track_convergence() const { return track_convergence_; }
  /// The change of each dof's drive impulse (N s or N m s) in the last position iteration of the
  /// last PGS step (nv). Zeros when tracking is off, before a step, and for TGS, whose sub-steps
  /// each solve a fresh drive impulse once.
  const VecX& last_drive_impulse_change() const { return last_drive_change_; }

  /// Advances by one step of options().dt; throws DivergenceError (state unchanged) if it would
  /// produce a non-finite value.
  void step();
  void step(int count);

  /// The algorithms' workspace after the last step: poses of the step's start, velocities in
  /// frame 0 (velocity0); the link-frame velocities (Data::velocity) are not computed by a step.
  const Data& data() const { return data_; }

  // The step guard (options().guard; docs/math/step_guard.md). Not kept in checkpoints.
  /// The sub-steps the last step took: 1 when the guard did not redo it (or is off).
  int guard_substeps() const { return guard_substeps_; }
  /// Steps the guard redid since construction (or reset_guard_counters).
  long guard_triggers() const { return guard_triggers_; }
  /// Steps whose max_substeps sub-steps still failed a test (kept as they were).
  long guard_exhausted() const { return guard_exhausted_; }
  void reset_guard_counters();
  /// Test (iii)'s account (eq. G-7, G-8), carried from step to step; checkpoints keep it.
  const GuardAccount& guard_account() const { return guard_account_; }
  /// Throws std::invalid_argument for a negative or non-finite scale or dissipation, or a
  /// non-finite created energy.
  void set_guard_account(const GuardAccount& account);

 private:
  friend class Batch;  // lends the storage of state_
  int check_dof(int dof) const { return check_dof_index(*model_, dof); }
  int driven_dof(const std::string& joint) const { return setting_dof(*model_, joint); }
  /// Whether a drive target on this dof acts: the one test of every target setter.
  bool accepts_targets(int dof) const;
  void set_actuator_unchecked(int dof, const ExplicitActuator& actuator);
  void set_delay(int dof, int delay);
  void scale_to_velocity_limits();
  void setup_rows(double h, bool tgs);
  void setup_dof_rows(int dof, double h, bool tgs);
  void setup_lone_drives(double h, bool tgs);
  void sweep(RowPhase& phase);
  // Contacts (contact.cpp, docs/math/contact.md).
  void update_contacts_active();
  void setup_contacts(const RowPhase& phase);
  void track_contacts(double h);
  void contact_link_velocities();
  void contact_forces();
  void solve_pgs();
  void solve_tgs();
  void check_finite_or_throw();
  void load_state();
  void commit_state();
  void update_link_damping_active();
  bool physx() const { return settings_.options.compat == Compat::physx; }
  void integrate_positions(double h);
  void begin_classical_root(const Vec6& root_qd0, double dt);
  void end_classical_root();
  /// The actuators' efforts of this step on the step-start state; the joint force the step uses.
  const VecX& apply_actuators();
  void undo_actuators();
  // The step's stages (step.cpp): begin (actuators, delays; once per step), the physics advance
  // over dt_, the end (outputs, finite check, commit, clock).
  const VecX& begin_step();
  /// begin_step's control stages on the loaded q_, qd_, applied_force_: the actuators' efforts
  /// and the delays' push; the joint force the physics uses. Batch runs them for its lanes.
  const VecX& control_stages();
  /// Whether control_stages() changes anything (actuators, delays, or efforts left to clear).
  bool has_control_stages() const { return actuators_.any() || drive_delays_.any() || actuated_; }
  void advance(const VecX& tau);
  void row_forces();
  void end_step();
  // The guard (step_guard.cpp).
  void size_guard();
  void guarded_advance(const VecX& tau);
  /// Tests (i) and (ii) of the advance just made from guard_q0_, guard_qd0_ (energies e0);
  /// leaves the end's energies in e1.
  bool guard_passes(const VecX& tau, const double e0[2], double e1[2]);
  void guard_energy(const VecX& q, const VecX& qd, double e[2]);  ///< kinetic, potential
  const VecX& guard_substep_force();
  void keep_guard_end(const double e1[2]);
  double damper_power() const;
  void commit_guard_account();
  double drive_bracket(int d, double q0, double dq, double h) const;
  void lead_drive_targets();

  std::shared_ptr<const Model> model_;
  /// Every setting. The actuators, drive delays and mimic rows are also held, with their delay
  /// histories and buffers, by actuators_, drive_delays_ and mimic_, which the setters keep equal.
  Settings settings_;
  Data data_;
  SweepWorkspace sweep_;

  StateStorage state_;  ///< q, qd, applied force and outputs, written after each whole step
  // The step works on copies of them (load_state, commit_state), so a diverging step leaves the
  // storage as it was.
  VecX q_, qd_;
  double time_ = 0.0;
  long step_count_ = 0;
  VecX applied_force_;
  VecX drive_force_, limit_force_, friction_force_, velocity_limit_force_;
  bool track_convergence_ = false;
  VecX last_drive_change_;  ///< see last_drive_impulse_change (nv)

  // Per-step scratch.
  std::vector<DofRows> rows_;  ///< every dof's rows for this step
  bool any_rows_ = false;
  bool any_undriven_rows_ = false;  ///< a row other than a lone drive (acts in TGS velocity iterations)
  /// PGS, compat none, no mimic rows, and every row a lone drive's (step.cpp, sweep).
  bool only_lone_drives_pgs_ = false;
  /// Every dof once: first the num_lone_drives_ whose only row is an undelayed drive on a revolute
  /// or prismatic joint, then the others from the back. setup_rows sets up only the drive row of
  /// the first, and sorts the dofs again after a setter changed what the sorting reads
  /// (row_kinds_changed_). Sized nv at construction: a copy of the simulation keeps the size.
  std::vector<int> dof_order_;
  int num_lone_drives_ = 0;
  bool row_kinds_changed_ = true;
  VecX delta_x_;               ///< TGS: position change accumulated over the sub-steps per dof
  Mat3 root_rotation0_ = Mat3::Identity();  ///< a floating root's axes at the step's start
  PhysxDepartures departures_; ///< compat physx: the link bias and momentum corrections
  // PhysX's parameters (physx_stages.hpp), per link.
  std::vector<Vec6> link_force_;     ///< link damping / velocity-limit forces, frame 0
  bool any_link_force_ = false;
  bool link_damping_active_ = false;  ///< some link has damping or a velocity limit
  bool link_cfm_active_ = false;      ///< some link has a cfm_scale (else link_cfm_ stays 0)
  std::vector<Vec6> subtree_force_;  ///< scratch of transmitted_force_magnitudes
  VecX transmitted_force_;           ///< |F| through each link's inbound joint
  VecX link_cfm_;
  // Explicit actuators: their efforts, the applied force plus them, and the copy for a restore.
  ExplicitActuators actuators_;
  VecX actuator_force_, joint_force_, actuator_force_start_;
  bool actuated_ = false;  ///< the last step had actuators (actuator_force_ may be nonzero)
  bool actuated_start_ = false;
  DriveDelays drive_delays_;  ///< pushed after the actuators, read by setup_rows
  MimicSolver mimic_;

  // Contacts (contact.cpp): the rows, the last step's points (the first num_contacts_ of
  // contacts_, sized for the shapes' most points at construction) and per-link forces.
  ContactRows contact_rows_;
  bool contacts_active_ = false;  ///< the ground is on and the model has shapes
  SelfContacts self_contacts_;    ///< contacts between the robot's own shapes, after the ground's
  bool self_contacts_active_ = false;  ///< self_collision is on and some pair can touch
  std::vector<Vec6> contact_link_velocity_;  ///< frame 0, at a sweep's start
  /// compat physx: each link's bias B (departure 1) in frame 0, which PhysX's contact rows see on
  /// the link's velocity (docs/math/contact.md, C23a).
  std::vector<Vec6> contact_link_bias_;
  /// compat physx, TGS: each link's motion since the step's start as PhysX tracks it for its
  /// contact rows (C25a), frame 0, and its increment over a sub-step.
  std::vector<Vec6> contact_link_motion_, contact_link_motion_step_;
  std::vector<ContactReport> contacts_;
  int num_contacts_ = 0;
  int num_ground_contacts_ = 0;  ///< the first of contacts_; the self contacts follow
  std::vector<Vec3> link_contact_force_;

  // The step guard: the time the advance covers (options().dt, or dt / n in a guard sub-step),
  // how long before the step's end the sub-step ends (its drive targets lead by it), the
  // scratch (sized by size_guard, so that a guarded step allocates nothing) and the counters.
  double dt_ = 0.0;
  double target_lead_ = 0.0;
  std::optional<Data> guard_data_;  ///< for the energies (a second Data: data_ keeps the step's)
  VecX guard_q0_, guard_qd0_, guard_force_, guard_actuator_, guard_impulse_[4];
  /// The last step's end state and energies: the next step's start, unless a setter moved it.
  VecX guard_q1_, guard_qd1_;
  double guard_e1_[2] = {0.0, 0.0};
  bool guard_e1_valid_ = false;
  GuardAccount guard_account_;  ///< test (iii): committed with the step
  GuardAccount guard_account_next_;  ///< the account after the (sub-)step being tested
  int guard_substeps_ = 1;
  long guard_triggers_ = 0;
  long guard_exhausted_ = 0;
};

}  // namespace featherdrive
