// Isaac Lab's explicit actuators (isaaclab.actuators: IdealPDActuator, DCMotor,
// RemotizedPDActuator, with DelayedPDActuator's delay): a joint effort computed from the state at
// the start of a step and applied through the whole step, beside (never on the same dof as) the
// implicit drive. docs/math/explicit_actuators.md has the equations. With integration implicit_law
// the same law is linearised at the step's end and solved in the sweep as the dof's drive row
// (constraint/actuator_row.hpp, docs/math/implicit_actuators.md).
#pragma once

#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "featherdrive/constraint/actuator_law.hpp"
#include "featherdrive/constraint/drive.hpp"
#include "featherdrive/model/model.hpp"
#include "featherdrive/sim/delay_line.hpp"

namespace featherdrive {

/// The most steps an actuator may delay its commands (a ring of delay + 1 commands per dof).
inline constexpr int kMaxActuatorDelay = kMaxDelay;

/// Throws std::invalid_argument naming the joint, the field and the value: gains not finite or
/// < 0, effort_limit not > 0, a dc_motor without a finite saturation_effort > 0 and velocity_limit
/// > 0, a remotized_pd without a table or with positions not strictly increasing or efforts not
/// finite and >= 0, a field the kind does not use, delay outside [0, kMaxActuatorDelay].
void validate_actuator(const ExplicitActuator& actuator, const std::string& joint);

/// The explicit actuators of one simulation: per dof the actuator, its feed-forward effort and a
/// ring of its last delay + 1 commands, sized when the actuator is set, so a step allocates
/// nothing.
class ExplicitActuators {
 public:
  explicit ExplicitActuators(int nv = 0);

  /// Sets (or, for kind none, clears) dof's actuator and empties its history. Not validated here.
  void set(int dof, const ExplicitActuator& actuator);
  const ExplicitActuator& actuator(int dof) const { return slot(dof).actuator; }
  bool active(int dof) const { return actuator(dof).kind != ActuatorKind::none; }
  bool any() const { return !active_.empty(); }
  /// dof's actuator is solved in the step's rows (integration implicit_law).
  bool implicit(int dof) const {
    return active(dof) && actuator(dof).integration == ActuatorIntegration::implicit_law;
  }
  /// Some dof's actuator is implicit.
  bool any_implicit() const {
    for (const int d : active_)
      if (implicit(d)) return true;
    return false;
  }
  /// The command an implicit actuator sees this step, eq. (8)-(9): set by the step's compute().
  const ActuatorCommand& command_seen(int dof) const { return slot(dof).seen; }
  void set_feedforward(int dof, double effort) {
    slots_[static_cast<size_t>(dof)].feedforward = effort;
  }
  double feedforward(int dof) const { return slot(dof).feedforward; }
  /// Empties every history: the next step starts over with eq. (9).
  void reset_history();

  /// Once per step: pushes every active dof's command (the targets of `drives`, the feed-forward)
  /// and writes the effort each explicit one applies at the step-start q, qd into `effort` (nv;
  /// 0 elsewhere); an implicit one keeps the command it sees for the rows (command_seen).
  void compute(const Model& model, const VecX& q, const VecX& qd, const std::vector<Drive>& drives,
               VecX& effort);
  /// The explicit efforts at q, qd for the commands the last compute() used, pushing nothing (a
  /// guard sub-step's start: docs/math/step_guard.md); 0 for implicit ones, which the rows solve.
  void evaluate(const Model& model, const VecX& q, const VecX& qd, VecX& effort) const;
  /// Takes back the last compute()'s pushes (a step that diverged).
  void undo_push();

  /// A dof's history, for checkpoints: pushes since set (or reset) and the ring (delay + 1).
  long pushes(int dof) const { return slot(dof).history.pushes(); }
  const std::vector<ActuatorCommand>& ring(int dof) const { return slot(dof).history.ring(); }
  /// Throws std::invalid_argument for pushes < 0 or a ring of another size than delay + 1.
  void restore_history(int dof, long pushes, const std::vector<ActuatorCommand>& ring);

 private:
  struct Slot {
    ExplicitActuator actuator;
    double feedforward = 0.0;
    DelayLine<ActuatorCommand> history;
    ActuatorCommand seen;  ///< implicit: this step's command
  };
  const Slot& slot(int dof) const { return slots_[static_cast<size_t>(dof)]; }
  std::vector<Slot> slots_;
  std::vector<int> active_;  ///< dofs with an actuator, ascending
};

}  // namespace featherdrive
