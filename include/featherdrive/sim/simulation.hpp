// One simulation of a Model: its state, its inputs (applied forces, drives), its outputs (drive
// forces) and the workspace a step writes. Many simulations may share one Model across threads.
#pragma once

#include <array>
#include <limits>
#include <memory>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "featherdrive/algorithm/data.hpp"
#include "featherdrive/core/deep_copy_ptr.hpp"
#include "featherdrive/sim/drive_delay.hpp"
#include "featherdrive/sim/explicit_actuator.hpp"
#include "featherdrive/sim/link_parameters.hpp"
#include "featherdrive/sim/revolute_wrap.hpp"
#include "featherdrive/sim/settings.hpp"
#include "featherdrive/sim/state.hpp"

namespace featherdrive {

struct Workspace;  // src/sim/workspace.hpp
class Stepper;

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
  /// row_force: the row kinds' forces (row_kinds.hpp), nv each, kind after kind.
  enum Field : int { q, qd, applied_force, drive_force, limit_force, friction_force,
                     velocity_limit_force, row_force };
  static constexpr int kFields = 8;
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
  /// A simulation with these settings (an importer's robot_settings, scene_settings, another's
  /// settings()): throws std::invalid_argument as set_settings does.
  Simulation(std::shared_ptr<const Model> model, const Settings& settings);
  Simulation(const Simulation& other);
  Simulation(Simulation&& other) noexcept;
  Simulation& operator=(const Simulation& other);
  Simulation& operator=(Simulation&& other);
  ~Simulation();

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
    return settings_.drives[static_cast<size_t>(check_dof_index(*model_, dof))];
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
  double lower_limit(int dof) const { return settings_.lower_limit[check_dof_index(*model_, dof)]; }
  double upper_limit(int dof) const { return settings_.upper_limit[check_dof_index(*model_, dof)]; }
  void set_joint_friction(int dof, const JointFriction& friction);
  void set_joint_friction(const std::string& joint, const JointFriction& friction);
  const JointFriction& joint_friction(int dof) const {
    return settings_.friction[static_cast<size_t>(check_dof_index(*model_, dof))];
  }
  /// Largest |qd| (m/s or rad/s); +inf for none.
  void set_max_joint_velocity(int dof, double max_velocity);
  void set_max_joint_velocity(const std::string& joint, double max_velocity);
  double max_joint_velocity(int dof) const {
    return settings_.max_joint_velocity[check_dof_index(*model_, dof)];
  }
  /// PhysX's older joint friction: |impulse| <= coefficient * h * |F| per solve, F the spatial
  /// force the joint transmits (docs/math/joint_constraints.md). 0 (none) by default;
  /// PhysX's 0.05 with Compat::physx. Not applied where static or viscous friction is set.
  void set_friction_coefficient(int dof, double coefficient);
  void set_friction_coefficient(const std::string& joint, double coefficient);
  double friction_coefficient(int dof) const {
    return settings_.friction_coefficient[check_dof_index(*model_, dof)];
  }
  void set_actuator_envelope(int dof, const ActuatorEnvelope& envelope);
  void set_actuator_envelope(const std::string& joint, const ActuatorEnvelope& envelope);
  const ActuatorEnvelope& actuator_envelope(int dof) const {
    return settings_.envelopes[static_cast<size_t>(check_dof_index(*model_, dof))];
  }
  /// A row kind's fields on a dof (constraint/row_kinds.hpp; e.g. "joint_spring": stiffness,
  /// damping, reference), in the kind's field order. Throws std::invalid_argument for an unknown
  /// kind, a count other than its fields', or what check_row_parameters refuses.
  void set_row_parameters(std::string_view kind, int dof, std::span<const double> values);
  void set_row_parameters(std::string_view kind, const std::string& joint,
                          std::span<const double> values);
  std::vector<double> row_parameters(std::string_view kind, int dof) const;

  // Explicit actuators (explicit_actuator.hpp), on revolute and prismatic dofs without an implicit
  // drive: the dof's drive targets are their targets. Setting one (kind none clears) empties its
  // delay history; a dof with a drive of type != none is refused, as set_drive is on a dof with an
  // actuator. Throw std::invalid_argument naming the joint, the field and the value.
  void set_actuator(int dof, const ExplicitActuator& actuator);
  void set_actuator(const std::string& joint, const ExplicitActuator& actuator);
  const ExplicitActuator& actuator(int dof) const;
  bool has_actuator(int dof) const;
  void clear_actuator(int dof) { set_actuator(dof, ExplicitActuator{}); }
  /// The feed-forward effort of the dof's actuator (eq. 1), delayed with its targets.
  void set_actuator_feedforward(int dof, double effort);
  void set_actuator_feedforward(const std::string& joint, double effort);
  /// Empties every actuator's delay history (eq. 9), e.g. when an episode starts over.
  void reset_actuator_history();
  const ExplicitActuators& actuators() const;
  /// The effort each actuator applied in the last step (nv; 0 on dofs without one), clipped.
  const VecX& actuator_force() const;

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
  int drive_delay(int dof) const;
  /// The check of set_drive_delay, changing nothing.
  void check_drive_delay(int dof, int delay) const;
  /// Empties every drive's delay history (eq. 9), e.g. when an episode starts over.
  void reset_drive_delay_history();
  const DriveDelays& drive_delays() const;

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
  std::span<const ContactReport> contacts() const;
  /// The contact force on each link in the last step (num_links; world frame, N): the sum of its
  /// points' impulses / dt.
  const std::vector<Vec3>& link_contact_force() const;
  /// The drive force of each dof: the step's accumulated drive impulse / dt (ERRATA 7).
  VecView drive_force() const { return state_[StateStorage::drive_force]; }
  /// The position-limit force of each dof (impulse / dt; positive pushes towards +q).
  VecView limit_force() const { return state_[StateStorage::limit_force]; }
  /// The joint-friction force of each dof (impulse / dt), both friction models.
  VecView friction_force() const { return state_[StateStorage::friction_force]; }
  /// The force the joint velocity limit applied on each dof (impulse / dt).
  VecView velocity_limit_force() const { return state_[StateStorage::velocity_limit_force]; }
  /// The force a row kind's rows applied on each dof (nv; impulse / dt), e.g. "joint_spring".
  VecView row_force(std::string_view kind) const;

  /// Diagnostics of the PGS solver's convergence, off by default (a step then stores nothing for
  /// them): with it on, each PGS step keeps how much the last position iteration changed each
  /// dof's drive impulse. Not kept in checkpoints.
  void set_track_convergence(bool on);
  bool track_convergence() const;
  /// The change of each dof's drive impulse (N s or N m s) in the last position iteration of the
  /// last PGS step (nv). Zeros when tracking is off, before a step, and for TGS, whose sub-steps
  /// each solve a fresh drive impulse once.
  const VecX& last_drive_impulse_change() const;

  /// Advances by one step of options().dt; throws DivergenceError (state unchanged) if it would
  /// produce a non-finite value.
  void step();
  void step(int count);

  /// The algorithms' workspace after the last step: poses of the step's start, velocities in
  /// frame 0 (velocity0); the link-frame velocities (Data::velocity) are not computed by a step.
  const Data& data() const;

  // The step guard (options().guard; docs/math/step_guard.md). Not kept in checkpoints.
  /// The sub-steps the last step took: 1 when the guard did not redo it (or is off).
  int guard_substeps() const;
  /// Steps the guard redid since construction (or reset_guard_counters).
  long guard_triggers() const;
  /// Steps whose max_substeps sub-steps still failed a test (kept as they were).
  long guard_exhausted() const;
  void reset_guard_counters();
  /// Test (iii)'s account (eq. G-7, G-8), carried from step to step: part of state().
  const GuardAccount& guard_account() const;

 private:
  friend class Batch;  // lends the storage of state_; runs the control stages for its lanes
  /// The step's stages over this simulation's parts (workspace.hpp).
  Stepper stepper();

  std::shared_ptr<const Model> model_;
  /// Every setting. The actuators, drive delays and mimic rows are also held, with their delay
  /// histories and buffers, by the workspace, which the setters keep equal.
  Settings settings_;
  StateStorage state_;  ///< q, qd, applied force and outputs, written after each whole step
  double time_ = 0.0;
  long step_count_ = 0;
  /// Behind a deep-copying pointer so that how the step works stays out of this header.
  DeepCopyPtr<Workspace> ws_;
};

}  // namespace featherdrive
