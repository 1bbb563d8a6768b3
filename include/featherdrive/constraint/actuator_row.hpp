// An implicit actuator's row: the law of an explicit actuator (docs/math/explicit_actuators.md,
// eq. 1-9) linearised at the end of the (sub-)step and solved as the dof's force drive row, with
// the law's own clip on the row's impulse. docs/math/implicit_actuators.md, eq. I1-I16. The laws
// are written once over a number type T: double in the step (step.cpp, dof_rows.cpp) and a pack
// of environments in the SIMD lanes (sim/simd_lane_step.hpp), every choice a select.
#pragma once

#include <algorithm>
#include <limits>

#include "featherdrive/constraint/actuator_law.hpp"
#include "featherdrive/constraint/drive.hpp"

namespace featherdrive {

/// An implicit actuator's gains, outer clip and the command it sees, over a number type T.
template <class T>
struct ActuatorTermsOf {
  T stiffness, damping, effort_limit;
  T position, velocity, effort;  ///< the command seen this step (eq. I16)
};

namespace actuator_row {

/// The drive row of an actuator on a dof with unit response r at start-of-step position x0; h,
/// step_dt and tgs as for drive_law::setup. A force drive with the actuator's gains and the
/// command's targets (eq. I4), the feed-forward effort a constant term (eq. I5), the symmetric
/// clip +-effort_limit * step_dt (eq. I7).
template <class T>
DriveRowOf<T> setup(const ActuatorTermsOf<T>& a, const T& r, const T& x0, double h_solve,
                    double step_dt, bool tgs) {
  const T inf(std::numeric_limits<double>::infinity()), h(h_solve), one(1.0);
  const DriveTermsOf<T> drive{a.stiffness, a.damping, a.position, a.velocity, inf, inf};
  DriveRowOf<T> row =
      drive_law::setup(drive, /*acceleration=*/T(0.0) != T(0.0), r, x0, h_solve, step_dt, tgs,
                       /*any_acceleration=*/false);
  // x of implicit_drives.md eq. (15): the impulse a constant effort ff adds per solve is x h ff.
  const T x = one / (h * (h * a.stiffness + a.damping) * r + one);
  row.target_vel_plus_initial_bias = row.target_vel_plus_initial_bias + x * h * a.effort;
  row.max_impulse = a.effort_limit * T(step_dt);
  return row;
}

/// dc_motor's clip (eq. I8-I11): the row's new accumulated impulse lambda within the bounds of
/// the torque-speed line at the end velocity v(lambda) = v_free + r lambda, each cut at
/// +-bound = +-E dt; v the dof's velocity with `accumulated` applied, S the saturation effort.
template <class T>
T clip_dc_motor(const T& lambda, const T& accumulated, const T& v, const T& r, const T& bound,
                const T& S, const T& v_max, double dt) {
  const T one(1.0);
  const T v_free = v - r * accumulated;
  const T slope = T(1.0 / dt) + S * r / v_max;
  const T high = clamp_select(S * (one - v_free / v_max) / slope, -bound, bound);
  const T low = clamp_select(S * (-one - v_free / v_max) / slope, -bound, bound);
  return clamp_select(lambda, low, high);
}

/// remotized_pd's clip (eq. I13): lambda within +-dt min(E, L), L the table's effort limit read
/// at the iterate's end-of-(sub-)step position; bound = E dt.
template <class T>
T clip_to_table(const T& lambda, const T& bound, const T& table_limit, double dt) {
  const T by_table = table_limit * T(dt);
  const T limit = select(by_table < bound, by_table, bound);  // std::min(bound, by_table)
  return clamp_select(lambda, -limit, limit);
}

}  // namespace actuator_row

/// The terms of `actuator` seeing `command`, for actuator_row::setup.
inline ActuatorTermsOf<double> actuator_terms(const ExplicitActuator& actuator,
                                              const ActuatorCommand& command) {
  return {actuator.stiffness, actuator.damping, actuator.effort_limit,
          command.position,   command.velocity, command.effort};
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
  if (a.kind == ActuatorKind::dc_motor)
    return actuator_row::clip_dc_motor(lambda, accumulated, v, r, bound, a.saturation_effort,
                                       a.velocity_limit, dt);
  if (a.kind == ActuatorKind::remotized_pd)  // the table read at the iterate's end position
    return actuator_row::clip_to_table(lambda, bound,
                                       lookup_effort_limit(a.lookup, x0 + delta_x + h * v), dt);
  return lambda;
}

}  // namespace featherdrive
