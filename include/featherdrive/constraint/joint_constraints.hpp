// Per-dof rows solved beside the drive, in PhysX's order (../shared/physx/NOTES.md, "Several rows
// on one dof"): drive -> friction -> position limit -> velocity limit, each seeing the velocity
// the previous one left. docs/math/joint_constraints.md.
#pragma once

#include <limits>
#include <string>

namespace featherdrive {

/// Joint friction: a joint whose stopping effort stays within static_effort does not move; beyond
/// it, dynamic_effort + viscous * |qd| opposes the motion. Efforts in N or Nm, viscous in Ns/m or
/// Nms/rad.
struct JointFriction {
  double static_effort = 0.0;
  double dynamic_effort = 0.0;
  double viscous = 0.0;
  bool active() const { return static_effort > 0.0 || dynamic_effort > 0.0 || viscous > 0.0; }
};

/// A DC-motor-like actuator envelope for a drive (none while max_effort = 0): the drive's effort is
/// limited to max_effort - speed_effort_gradient * |qd| (in the direction of motion), to zero past
/// max_actuator_velocity, and reduced by velocity_dependent_resistance * qd.
struct ActuatorEnvelope {
  double max_effort = 0.0;  ///< N or Nm; 0 = no envelope
  double max_actuator_velocity = std::numeric_limits<double>::infinity();  ///< m/s or rad/s
  double speed_effort_gradient = 0.0;         ///< effort lost per unit speed [N s/m or Nm s/rad]
  double velocity_dependent_resistance = 0.0; ///< opposing effort per unit speed
  bool active() const { return max_effort > 0.0; }
};

/// Throw std::invalid_argument naming the joint, field and value.
void validate_friction(const JointFriction& friction, const std::string& joint);
void validate_envelope(const ActuatorEnvelope& envelope, const std::string& joint);
void validate_limits(double lower, double upper, const std::string& joint);
void validate_max_velocity(double max_velocity, const std::string& joint);

}  // namespace featherdrive
