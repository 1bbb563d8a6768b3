// The implicit PD joint drive of one dof, as PhysX solves it: coefficients computed once per step
// (spec eq. 20-24 for force drives, 35-39 for acceleration drives, ERRATA 1-5) and a pure impulse
// update shared by PGS (eq. 18/34) and TGS (eq. 44/45). docs/math/implicit_drives.md.
#pragma once

#include <algorithm>
#include <limits>
#include <string>

#include "featherdrive/core/select.hpp"

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

/// One step's drive row over a number type T (double, or a SIMD pack of environments: the lanes
/// of sim/simd_lane_step.hpp): the members of PhysX's ArticulationInternalConstraint, named after
/// the spec. lambda_new = target_vel_plus_initial_bias + vel_multiplier * v
///                        + impulse_multiplier * lambda - bias_coefficient * delta_x
///                        - target_pos_bias * time_to_step_end, clamped to +-max_impulse.
template <class T>
struct DriveRowOf {
  T target_vel_plus_initial_bias = T(0.0);  ///< eq. (20)/(35) [Ns]
  T vel_multiplier = T(0.0);                ///< eq. (21)/(36) [kg]
  T impulse_multiplier = T(1.0);            ///< eq. (22)/(37); 1 in TGS
  T bias_coefficient = T(0.0);              ///< eq. (23)/(38) [Ns/m]
  T target_pos_bias = T(0.0);               ///< eq. (24)/(39) [N], TGS only
  T max_impulse = T(std::numeric_limits<double>::infinity());  ///< ERRATA 8
};
using DriveRow = DriveRowOf<double>;

/// A drive's gains, targets and bounds over a number type T (Drive's fields but its type).
template <class T>
struct DriveTermsOf {
  T stiffness, damping, target_position, target_velocity, max_force, max_impulse;
};

namespace drive_law {

/// Row coefficients of a drive whose type is acceleration where `acceleration` holds, force
/// elsewhere, on a dof with unit response r = (M^-1)_jj at start-of-step position x0. h is the
/// time step of one solve: tau for PGS, rho = tau / n for TGS (ERRATA 4); tgs selects
/// driveImpulseMultiplier = 1 and the target interpolation. step_dt is the whole step tau (the
/// impulse limit is max_force * tau for the whole step). any_acceleration false says that no
/// lane's drive is an acceleration drive: the force drive's coefficients alone are formed (the
/// selects would take them).
template <class T, class Mask>
DriveRowOf<T> setup(const DriveTermsOf<T>& drive, const Mask& acceleration, const T& r, const T& x0,
                    double h_solve, double step_dt, bool tgs, bool any_acceleration = true) {
  const T h(h_solve), one(1.0);
  const T kp = drive.stiffness, kd = drive.damping;
  const T a = h * (h * kp + kd);               // eq. (13) / (30)
  const T b = h * kd * drive.target_velocity;  // eq. (14) / (31)
  // Force drive: x = 1 / (a r + 1), eq. (15); acceleration drive: x = 1 / (a + 1) and every
  // coefficient carries r^-1, eq. (32)-(39) with ERRATA 1-2.
  T x, scale;
  if (any_acceleration) {
    x = select(acceleration, one / (a + one), one / (a * r + one));
    scale = select(acceleration, x / r, x);
  } else {
    x = one / (a * r + one);
    scale = x;
  }
  DriveRowOf<T> row;
  row.target_vel_plus_initial_bias = scale * (b + h * kp * (drive.target_position - x0));
  row.vel_multiplier = -scale * a;
  row.impulse_multiplier = tgs ? one : one - x;
  row.bias_coefficient = scale * h * kp;
  row.target_pos_bias = tgs ? scale * h * kp * drive.target_velocity : T(0.0);
  const T by_force = drive.max_force * T(step_dt);
  row.max_impulse = select(drive.max_impulse < by_force, drive.max_impulse, by_force);  // std::min
  return row;
}

/// lambda clamped to +-row.max_impulse.
template <class T>
T clamp_to_max(const DriveRowOf<T>& row, T lambda) {
  lambda = select(row.max_impulse < lambda, row.max_impulse, lambda);
  return select(lambda < -row.max_impulse, -row.max_impulse, lambda);
}

/// The new accumulated impulse after one update at joint velocity v (eq. 18/34, TGS eq. 44/45).
template <class T>
T impulse(const DriveRowOf<T>& row, const T& v, const T& accumulated, const T& delta_x,
          const T& time_to_step_end) {
  // The velocity term last: in a sweep, v is the one input that waits on the previous row.
  const T rest = row.target_vel_plus_initial_bias + row.impulse_multiplier * accumulated -
                 row.bias_coefficient * delta_x - row.target_pos_bias * time_to_step_end;
  return clamp_to_max(row, rest + row.vel_multiplier * v);
}

/// impulse() in PGS without a row bias: delta_x, target_pos_bias and the time to the step's end
/// are 0 there (and bias_coefficient >= 0), so the terms in them subtract +0: the same value.
template <class T>
T impulse_pgs(const DriveRowOf<T>& row, const T& v, const T& accumulated) {
  return clamp_to_max(row, row.target_vel_plus_initial_bias + row.impulse_multiplier * accumulated +
                               row.vel_multiplier * v);
}

}  // namespace drive_law

/// A drive's terms (all its fields but the type).
inline DriveTermsOf<double> drive_terms(const Drive& drive) {
  return {drive.stiffness,       drive.damping,   drive.target_position,
          drive.target_velocity, drive.max_force, drive.max_impulse};
}

/// drive_law::setup for one drive (a drive of type none gives the empty row).
inline DriveRow setup_drive_row(const Drive& drive, double r, double x0, double h,
                                double step_dt, bool tgs) {
  if (drive.type == DriveType::none) return DriveRow{};
  return drive_law::setup(drive_terms(drive), drive.type == DriveType::acceleration, r, x0, h,
                          step_dt, tgs);
}

/// The new accumulated impulse of the step after one update at joint velocity v.
inline double drive_impulse(const DriveRow& row, double v, double accumulated, double delta_x,
                            double time_to_step_end) {
  return drive_law::impulse(row, v, accumulated, delta_x, time_to_step_end);
}

}  // namespace featherdrive
