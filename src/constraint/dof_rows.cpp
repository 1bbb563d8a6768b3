#include "featherdrive/constraint/dof_rows.hpp"

#include <algorithm>
#include <cmath>

namespace featherdrive {
namespace {

// The friction row: the impulse that would stop the joint is applied whole while it stays within
// the static threshold; beyond it the accumulated friction is clamped to dynamic + viscous |v|.
double friction_update(DofRows& rows, double v) {
  const double stopping = rows.friction_impulse - v * rows.recip_response;
  double total = stopping;
  if (std::abs(stopping) > rows.static_friction_impulse) {
    const double bound = rows.dynamic_friction_impulse + rows.viscous_friction * std::abs(v);
    total = std::clamp(stopping, -bound, bound);
  }
  const double delta = total - rows.friction_impulse;
  rows.friction_impulse = total;
  return delta;
}

// The position limit: speculative (acts when the limit would be crossed by the end of the
// (sub-)step), with Baumgarte correction of an existing violation in position iterations, and
// separately accumulated, one-signed lower and upper impulses.
double limit_update(DofRows& rows, double v, const RowPhase& phase) {
  const double future_delta = phase.delta_x + v * phase.h;
  const double err_low_now = rows.error_low + phase.delta_x;
  const double err_low_next = rows.error_low + future_delta;
  const double err_high_now = rows.error_high - phase.delta_x;
  const double err_high_next = rows.error_high - future_delta;
  if (err_low_now < 0.0 || err_low_next < 0.0) {
    double target_v = v;
    if (err_low_now < 0.0) {
      if (!phase.velocity_iteration) target_v = -err_low_now / phase.h * phase.limit_erp;
    } else {
      target_v = -err_low_now / phase.h;  // arrive exactly at the limit
    }
    const double delta =
        std::max(rows.low_impulse + (target_v - v) * rows.recip_response, 0.0) - rows.low_impulse;
    rows.low_impulse += delta;
    return delta;
  }
  if (err_high_now < 0.0 || err_high_next < 0.0) {
    double target_v = v;
    if (err_high_now < 0.0) {
      if (!phase.velocity_iteration) target_v = err_high_now / phase.h * phase.limit_erp;
    } else {
      target_v = err_high_now / phase.h;
    }
    const double delta =
        std::min(rows.high_impulse + (target_v - v) * rows.recip_response, 0.0) - rows.high_impulse;
    rows.high_impulse += delta;
    return delta;
  }
  // Inside both limits: a limit that pushed in an earlier iteration may give back what it
  // overshot, at most down to zero velocity and to zero accumulated impulse.
  const double to_rest = -v * rows.recip_response;
  if (v > 0.0) {
    const double delta = std::max(to_rest, -rows.low_impulse);
    rows.low_impulse += delta;
    return delta;
  }
  const double delta = std::min(to_rest, -rows.high_impulse);
  rows.high_impulse += delta;
  return delta;
}

}  // namespace

double clamp_to_envelope(const ActuatorEnvelope& e, double unclamped, double accumulated, double v,
                         double r, double external, double dt) {
  // Work in the effort E = (lambda + external) / dt and the final velocity
  // v(lambda) = v + r (lambda - accumulated); both are affine in lambda.
  const double sign = unclamped + external >= 0.0 ? 1.0 : -1.0;
  // In the direction of the unclamped effort, s E = s (lambda + external) / dt >= 0.
  // Each constraint reads alpha * lambda <= beta; intersect them into [lo, hi].
  double lo = std::min(-external, unclamped);  // E = 0 ... E_unclamped, in lambda
  double hi = std::max(-external, unclamped);
  auto add = [&](double alpha, double beta) {  // alpha lambda <= beta
    if (alpha > 0.0) hi = std::min(hi, beta / alpha);
    else if (alpha < 0.0) lo = std::max(lo, beta / alpha);
    else if (beta < 0.0) hi = lo - 1.0;  // infeasible
  };
  const double v_free = v - r * accumulated;  // v(lambda) = v_free + r lambda
  for (double vs : {1.0, -1.0}) {
    // s E + resistance * (vs v) <= max_effort
    add(sign / dt + e.velocity_dependent_resistance * vs * r,
        e.max_effort - sign * external / dt - e.velocity_dependent_resistance * vs * v_free);
    // vs v + gradient * s E <= max_actuator_velocity
    if (std::isfinite(e.max_actuator_velocity))
      add(vs * r + e.speed_effort_gradient * sign / dt,
          e.max_actuator_velocity - vs * v_free - e.speed_effort_gradient * sign * external / dt);
  }
  if (lo > hi) return -external;  // no effort is available at this speed
  return std::clamp(unclamped, lo, hi);
}

double solve_all_dof_rows(DofRows& rows, double v, const RowPhase& phase) {
  double total = 0.0;
  auto apply = [&](double delta) {
    total += delta;
    v += rows.response * delta;
  };
  if (rows.has_transmission_friction) {
    // The impulse that stops the joint, within +-bound; PhysX re-applies it whole in every TGS
    // solve (solveInternalJointConstraintRecursive).
    const double applied = phase.tgs ? 0.0 : rows.transmission_friction_impulse;
    const double next = std::clamp(applied - v * rows.recip_response,
                                   -rows.transmission_friction_bound,
                                   rows.transmission_friction_bound);
    rows.transmission_friction_impulse = next;
    rows.transmission_friction_applied += next - applied;
    apply(next - applied);
  }
  if (rows.has_drive && !(phase.tgs && phase.velocity_iteration)) {  // TGS freezes the drive
    double next = drive_impulse(rows.drive, v, rows.drive_impulse, phase.delta_x,
                                phase.time_to_step_end);
    if (rows.has_envelope)
      next = clamp_to_envelope(rows.envelope, next, rows.drive_impulse, v, rows.response,
                               rows.external_impulse, phase.dt);
    if (rows.actuator)
      next = clip_actuator_impulse(*rows.actuator, next, rows.drive_impulse, v, rows.response,
                                   rows.actuator_x0, phase.delta_x, phase.h, phase.dt);
    const double delta = next - rows.drive_impulse;
    rows.drive_impulse = next;
    apply(delta);
  }
  if (rows.has_friction) apply(friction_update(rows, v));
  if (rows.has_limit) apply(limit_update(rows, v, phase));
  if (std::abs(v) > rows.max_velocity) {
    const double delta = (std::clamp(v, -rows.max_velocity, rows.max_velocity) - v) * rows.recip_response;
    rows.velocity_limit_impulse += delta;
    apply(delta);
  }
  return total;
}

}  // namespace featherdrive
