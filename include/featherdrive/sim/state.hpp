// What a step changes, as one value (docs/architecture.md, "Model, Settings, State, Workspace"),
// and the checks of a state's parts, shared by Simulation's setters and by whatever checks a
// state without a Simulation (Batch, the Python kinematics, checkpoints).
#pragma once

#include <vector>

#include "featherdrive/constraint/actuator_law.hpp"
#include "featherdrive/constraint/contact_rows.hpp"
#include "featherdrive/model/model.hpp"
#include "featherdrive/sim/drive_delay.hpp"

namespace featherdrive {

/// A delay line's contents: the pushes since its delay was set (or the history emptied) and its
/// ring of delay + 1 samples (delay_line.hpp).
template <class Sample>
struct DelayHistory {
  long pushes = 0;
  std::vector<Sample> ring;
};

/// Test (iii)'s account (docs/math/step_guard.md, eq. G-7, G-8): leaky sums over the run of the
/// energy created beyond the work (X), of what the dampers dissipated (D) and of the steps'
/// energy scales (S). Part of the state (State::guard_account).
struct GuardAccount {
  double created = 0.0;
  double dissipated = 0.0;
  double scale = 0.0;
};

/// A simulation's state (Simulation::state, set_state): what the next step starts from and the
/// outputs of the last one. Sizes in brackets.
struct State {
  VecX q;              ///< configuration (nq)
  VecX qd;             ///< joint velocities (nv)
  VecX applied_force;  ///< the joint force held through each step (nv)
  double time = 0.0;   ///< [s]
  long step_count = 0;
  /// The outputs of the last step (nv each), as Simulation::drive_force() etc. report them.
  VecX drive_force, limit_force, friction_force, velocity_limit_force;
  /// The row kinds' forces (constraint/row_kinds.hpp), nv each, kind after kind (nv x kinds).
  VecX row_force;
  VecX actuator_force;  ///< the actuators' efforts in the last step (nv)
  /// Per dof (nv): the actuator's last commands (empty on a dof without one) and the implicit
  /// drive's last targets (empty on a dof without a delay).
  std::vector<DelayHistory<ActuatorCommand>> actuator_history;
  std::vector<DelayHistory<DriveTarget>> drive_delay_history;
  /// Per shape (Model::shapes): the friction anchors kept from the last step (C9 of
  /// docs/math/contact.md); empty: none kept.
  std::vector<FrictionAnchors> friction_anchors;
  /// The step guard's test (iii) account, carried from step to step (zero with the guard off).
  GuardAccount guard_account;
};

/// Throws std::invalid_argument "what: expected n values, got m" or "what[i] = x is not finite".
void check_state_vector(const VecX& x, Eigen::Index expected, const char* what);

/// q checked (nq finite values; the quaternions of spherical and floating joints of a norm that
/// is neither zero nor overflows, or of norm 1 within 1e-9 with `unit`) and, unless `unit`,
/// normalised: what Simulation::set_q stores. Throws std::invalid_argument naming the joint.
VecX checked_configuration(const Model& model, const VecX& q, bool unit = false);

/// Throws std::invalid_argument "guard account: dissipated = -1 must be finite and >= 0" for a
/// negative or non-finite scale or dissipation, or a non-finite created energy.
void check_guard_account(const GuardAccount& account);

/// A clock a run can reach: throws std::invalid_argument for a step count outside
/// [0, kMaxStepCount], a time that is not finite or < 0, or a time above 2 * step_count * kMaxDt
/// (step_count steps of at most kMaxDt, with room for the rounding of the sum; so none > 0 at
/// step 0).
void check_clock(double time, long step_count);

}  // namespace featherdrive
