// An actuator's law (Isaac Lab's IdealPDActuator, DCMotor, RemotizedPDActuator): what one dof's
// actuator is, what it is told and the effort it gives, docs/math/explicit_actuators.md eq. (1)-(7).
// The simulation evaluates it explicitly (sim/explicit_actuator.hpp) or solves it as a row
// (actuator_row.hpp, docs/math/implicit_actuators.md).
#pragma once

#include <limits>
#include <utility>
#include <vector>

namespace featherdrive {

enum class ActuatorKind {
  none,          ///< no explicit actuator on this dof
  ideal_pd,      ///< PD + feed-forward clipped to +-effort_limit, eq. (1)-(2)
  dc_motor,      ///< ideal PD within the torque-speed line of a DC motor, eq. (3)-(5)
  remotized_pd,  ///< ideal PD within a position-dependent limit from a table, eq. (6)-(7)
};
const char* to_string(ActuatorKind kind);

/// Where an actuator's law is evaluated.
enum class ActuatorIntegration {
  explicit_law,  ///< on the step-start state, applied as a constant force (Isaac Lab's way)
  implicit_law,  ///< linearised at the step's end and solved as a row (implicit_actuators.md)
};
/// "explicit" or "implicit" (the scene's and Python's spelling).
const char* to_string(ActuatorIntegration integration);

/// One dof's explicit actuator. Fields a kind does not use must keep their defaults.
struct ExplicitActuator {
  ActuatorKind kind = ActuatorKind::none;
  double stiffness = 0.0;  ///< N/m or Nm/rad
  double damping = 0.0;    ///< Ns/m or Nms/rad
  /// The actuator's clip |effort| <= effort_limit (N or Nm; Isaac Lab's effort_limit), apart from
  /// the implicit drive's max_force (Isaac Lab's effort_limit_sim).
  double effort_limit = std::numeric_limits<double>::infinity();
  double saturation_effort = 0.0;  ///< dc_motor: the stall effort at zero speed (N or Nm)
  double velocity_limit = 0.0;     ///< dc_motor: the no-load speed (m/s or rad/s)
  /// remotized_pd: (joint position, largest |effort|) pairs, positions strictly increasing;
  /// linear between them, the end values beyond them.
  std::vector<std::pair<double, double>> lookup;
  int delay = 0;  ///< physics steps between a command and the effort it gives, eq. (8)
  /// explicit: eq. (1)-(10) here; implicit: solved at the step's end (implicit_actuators.md).
  ActuatorIntegration integration = ActuatorIntegration::explicit_law;

  bool operator==(const ExplicitActuator&) const = default;
};

/// What an actuator is told: target position and velocity, feed-forward effort.
struct ActuatorCommand {
  double position = 0.0;
  double velocity = 0.0;
  double effort = 0.0;
};

/// The effort the actuator applies at joint position q and velocity qd for `command`, eq. (1)-(7).
double actuator_effort(const ExplicitActuator& actuator, double q, double qd,
                       const ActuatorCommand& command);

/// The remotized table's limit at q, eq. (6).
double lookup_effort_limit(const std::vector<std::pair<double, double>>& lookup, double q);

}  // namespace featherdrive
