// An implicit actuator's row: the law of an explicit actuator (docs/math/explicit_actuators.md,
// eq. 1-9) linearised at the end of the (sub-)step and solved as the dof's force drive row, with
// the law's own clip on the row's impulse. docs/math/implicit_actuators.md, eq. I1-I16.
#pragma once

#include <algorithm>

#include "featherdrive/constraint/drive.hpp"
#include "featherdrive/constraint/actuator_law.hpp"

namespace featherdrive {

/// The drive row of `actuator` seeing `command` on a dof with unit response r at start-of-step
/// position x0; h, step_dt and tgs as for setup_drive_row. A force drive with the actuator's gains
/// and the command's targets (eq. I4), the feed-forward effort a constant term (eq. I5), the
/// symmetric clip +-effort_limit * step_dt (eq. I7).
inline DriveRow setup_actuator_row(const ExplicitActuator& actuator, const ActuatorCommand& command,
                                   double r, double x0, double h, double step_dt, bool tgs) {
  Drive drive;
  drive.type = DriveType::force;
  drive.stiffness = actuator.stiffness;
  drive.damping = actuator.damping;
  drive.target_position = command.position;
  drive.target_velocity = command.velocity;
  DriveRow row = setup_drive_row(drive, r, x0, h, step_dt, tgs);
  // x of implicit_drives.md eq. (15): the impulse a constant effort ff adds per solve is x h ff.
  const double x = 1.0 / (h * (h * actuator.stiffness + actuator.damping) * r + 1.0);
  row.target_vel_plus_initial_bias += x * h * command.effort;
  row.max_impulse = actuator.effort_limit * step_dt;
  return row;
}

/// The clip beyond +-effort_limit * dt depends on the velocity (dc_motor) or position
/// (remotized_pd) the impulse leads to, so the row solve applies it (clip_actuator_impulse).
inline bool actuator_clip_depends_on_state(const ExplicitActuator& actuator) {
  return actuator.kind == ActuatorKind::dc_motor || actuator.kind == ActuatorKind::remotized_pd;
}

/// The row's new accumulated impulse `lambda` within the law's range at the iterate: v the dof's
/// velocity with `accumulated` applied, r its response, x0 + delta_x its position at the start of
/// the (sub-)step of length h, dt the whole step.
inline double clip_actuator_impulse(const ExplicitActuator& a, double lambda, double accumulated,
                                    double v, double r, double x0, double delta_x, double h,
                                    double dt) {
  const double bound = a.effort_limit * dt;
  if (a.kind == ActuatorKind::dc_motor) {
    // The end velocity v(lambda) = v_free + r lambda (eq. I8); the line's bounds solved for
    // lambda (eq. I10-I11), each cut at +-E dt.
    const double v_free = v - r * accumulated;
    const double S = a.saturation_effort, v_max = a.velocity_limit;
    const double slope = 1.0 / dt + S * r / v_max;
    const double high = std::clamp(S * (1.0 - v_free / v_max) / slope, -bound, bound);
    const double low = std::clamp(S * (-1.0 - v_free / v_max) / slope, -bound, bound);
    return std::clamp(lambda, low, high);
  }
  if (a.kind == ActuatorKind::remotized_pd) {
    // The table read at the iterate's end-of-(sub-)step position (eq. I13): a fixed point.
    const double limit = std::min(bound, lookup_effort_limit(a.lookup, x0 + delta_x + h * v) * dt);
    return std::clamp(lambda, -limit, limit);
  }
  return lambda;
}

}  // namespace featherdrive
