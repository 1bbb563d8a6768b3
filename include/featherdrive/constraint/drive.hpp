// The implicit PD joint drive of one dof, as PhysX solves it: coefficients computed once per step
// (spec eq. 20-24 for force drives, 35-39 for acceleration drives, ERRATA 1-5) and a pure impulse
// update shared by PGS (eq. 18/34) and TGS (eq. 44/45). docs/math/implicit_drives.md.
#pragma once

#include <algorithm>
#include <limits>
#include <string>

namespace featherdrive {

enum class DriveType {
  none,          ///< no drive on this dof
  force,         ///< stiffness in N/m or Nm/rad, damping in Ns/m or Nms/rad
  acceleration,  ///< stiffness in 1/s^2, damping in 1/s: the drive's response is mass-free
};

const char* to_string(DriveType type);

/// A drive's settings; all of them may change between steps.
struct Drive {
  DriveType type = DriveType::none;
  double stiffness = 0.0;
  double damping = 0.0;
  /// Largest drive force (N or Nm): the step's impulse is limited to max_force * dt (PhysX with
  /// eDRIVE_LIMITS_ARE_FORCES).
  double max_force = std::numeric_limits<double>::infinity();
  double target_position = 0.0;
  double target_velocity = 0.0;
  /// Largest drive impulse of a step (N s or Nm s; PhysX's maxForce without
  /// eDRIVE_LIMITS_ARE_FORCES). Set at most one of max_force and max_impulse. In TGS it bounds the
  /// impulse summed over the sub-steps.
  double max_impulse = std::numeric_limits<double>::infinity();
};

/// Throws std::invalid_argument naming the joint, the field and the value for negative or
/// non-finite gains, max_force or max_impulse <= 0, both of them set, or non-finite targets.
void validate_drive(const Drive& drive, const std::string& joint);

/// One step's drive row: the members of PhysX's ArticulationInternalConstraint, named after the
/// spec. lambda_new = target_vel_plus_initial_bias + vel_multiplier * v
///                    + impulse_multiplier * lambda - bias_coefficient * delta_x
///                    - target_pos_bias * time_to_step_end, clamped to +-max_impulse.
struct DriveRow {
  double target_vel_plus_initial_bias = 0.0;  ///< eq. (20)/(35) [Ns]
  double vel_multiplier = 0.0;                ///< eq. (21)/(36) [kg]
  double impulse_multiplier = 1.0;            ///< eq. (22)/(37); 1 in TGS
  double bias_coefficient = 0.0;              ///< eq. (23)/(38) [Ns/m]
  double target_pos_bias = 0.0;               ///< eq. (24)/(39) [N], TGS only
  double max_impulse = std::numeric_limits<double>::infinity();  ///< ERRATA 8
};

/// Row coefficients for a drive on a dof with unit response r = (M^-1)_jj at start-of-step
/// position x0. h is the time step of one solve: tau for PGS, rho = tau / n for TGS
/// (ERRATA 4); tgs selects driveImpulseMultiplier = 1 and the target interpolation.
/// step_dt is the whole step tau (the impulse limit is max_force * tau for the whole step).
inline DriveRow setup_drive_row(const Drive& drive, double r, double x0, double h,
                                double step_dt, bool tgs) {
  DriveRow row;
  row.impulse_multiplier = 1.0;
  if (drive.type == DriveType::none) return row;
  const double kp = drive.stiffness;
  const double kd = drive.damping;
  const double a = h * (h * kp + kd);                   // eq. (13) / (30)
  const double b = h * kd * drive.target_velocity;      // eq. (14) / (31)
  // Force drive: x = 1 / (a r + 1), eq. (15); acceleration drive: x = 1 / (a + 1) and every
  // coefficient carries r^-1, eq. (32)-(39) with ERRATA 1-2.
  const bool accel = drive.type == DriveType::acceleration;
  const double x = accel ? 1.0 / (a + 1.0) : 1.0 / (a * r + 1.0);
  const double scale = accel ? x / r : x;
  row.target_vel_plus_initial_bias = scale * (b + h * kp * (drive.target_position - x0));
  row.vel_multiplier = -scale * a;
  row.impulse_multiplier = tgs ? 1.0 : 1.0 - x;
  row.bias_coefficient = scale * h * kp;
  row.target_pos_bias = tgs ? scale * h * kp * drive.target_velocity : 0.0;
  row.max_impulse = std::min(drive.max_force * step_dt, drive.max_impulse);
  return row;
}

/// The new accumulated impulse of the step after one update at joint velocity v.
inline double drive_impulse(const DriveRow& row, double v, double accumulated, double delta_x,
                            double time_to_step_end) {
  // The velocity term last: in a sweep, v is the one input that waits on the previous row.
  const double rest = row.target_vel_plus_initial_bias + row.impulse_multiplier * accumulated -
                      row.bias_coefficient * delta_x - row.target_pos_bias * time_to_step_end;
  double lambda = rest + row.vel_multiplier * v;
  if (lambda > row.max_impulse) lambda = row.max_impulse;
  if (lambda < -row.max_impulse) lambda = -row.max_impulse;
  return lambda;
}

}  // namespace featherdrive
