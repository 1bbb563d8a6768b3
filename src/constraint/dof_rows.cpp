#include "featherdrive/constraint/dof_rows.hpp"

#include <algorithm>
#include <cmath>

#include "featherdrive/constraint/row_laws.hpp"

namespace featherdrive {

double clamp_to_envelope(const ActuatorEnvelope& e, double unclamped, double accumulated, double v,
                         double r, double external, double dt) {
  return row_law::envelope<double>({e.max_effort, e.max_actuator_velocity, e.speed_effort_gradient,
                                    e.velocity_dependent_resistance},
                                   unclamped, accumulated, v, r, external, dt);
}

double solve_all_dof_rows(DofRows& rows, double v, const RowPhase& phase) {
  double total = 0.0;
  auto apply = [&](double delta) {
    total += delta;
    v += rows.response * delta;
  };
  if (rows.has_transmission_friction) {
    // PhysX re-applies it whole in every TGS solve (solveInternalJointConstraintRecursive).
    const double applied = phase.tgs ? 0.0 : rows.transmission_friction_impulse;
    const double next = row_law::transmission_friction(applied, v, rows.recip_response,
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
  if (rows.has_friction)
    apply(row_law::friction(rows.friction_impulse, v, rows.recip_response,
                            rows.static_friction_impulse, rows.dynamic_friction_impulse,
                            rows.viscous_friction));
  if (rows.has_limit)
    apply(row_law::limit(rows.low_impulse, rows.high_impulse, v, rows.recip_response,
                         rows.error_low, rows.error_high, phase.delta_x,
                         {phase.h, phase.recip_h, phase.limit_erp, phase.velocity_iteration}));
  if (row_law::beyond(v, rows.max_velocity))
    apply(row_law::velocity_limit(rows.velocity_limit_impulse, v, rows.recip_response,
                                  rows.max_velocity));
  return total;
}

}  // namespace featherdrive
