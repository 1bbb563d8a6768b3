#include "featherdrive/constraint/dof_rows.hpp"

#include <algorithm>
#include <cmath>

#include "featherdrive/constraint/row_laws.hpp"
#include "featherdrive/constraint/row_sequence.hpp"

namespace featherdrive {

double clamp_to_envelope(const ActuatorEnvelope& e, double unclamped, double accumulated, double v,
                         double r, double external, double dt) {
  return row_law::envelope<double>({e.max_effort, e.max_actuator_velocity, e.speed_effort_gradient,
                                    e.velocity_dependent_resistance},
                                   unclamped, accumulated, v, r, external, dt);
}

namespace {

// A DofRows as row_sequence::solve reads it: one dof, so any row it has is on every "lane".
struct ScalarRows {
  using Row = row_sequence::Row;
  DofRows& rows;
  const RowPhase& phase;
  bool any(Row k) const {
    switch (k) {
      case Row::transmission_friction: return rows.has_transmission_friction;
      case Row::drive: return rows.has_drive;
      case Row::friction: return rows.has_friction;
      case Row::limit: return rows.has_limit;
      case Row::velocity_limit: return rows.max_velocity < DofRows::kNoVelocityLimit;
    }
    return false;
  }
  static bool all(Row) { return true; }
  static bool has(Row) { return true; }
  static bool any_of(bool mask) { return mask; }
  double response() const { return rows.response; }
  double recip() const { return rows.recip_response; }
  double& tf_impulse() const { return rows.transmission_friction_impulse; }
  double& tf_applied() const { return rows.transmission_friction_applied; }
  double tf_bound() const { return rows.transmission_friction_bound; }
  const DriveRow& drive() const { return rows.drive; }
  double& drive_impulse() const { return rows.drive_impulse; }
  double clip_drive(double next, double accumulated, double v, double dx) const {
    if (rows.has_envelope)
      next = clamp_to_envelope(rows.envelope, next, accumulated, v, rows.response,
                               rows.external_impulse, phase.dt);
    if (rows.actuator)
      next = clip_actuator_impulse(*rows.actuator, next, accumulated, v, rows.response,
                                   rows.actuator_x0, dx, phase.h, phase.dt);
    return next;
  }
  double& friction_impulse() const { return rows.friction_impulse; }
  double friction_static() const { return rows.static_friction_impulse; }
  double friction_dynamic() const { return rows.dynamic_friction_impulse; }
  double friction_viscous() const { return rows.viscous_friction; }
  double& low() const { return rows.low_impulse; }
  double& high() const { return rows.high_impulse; }
  double error_low() const { return rows.error_low; }
  double error_high() const { return rows.error_high; }
  double max_velocity() const { return rows.max_velocity; }
  double& velocity_limit() const { return rows.velocity_limit_impulse; }
  bool any_kinds() const { return rows.kinds != 0; }
  bool any_kind(int i) const { return (rows.kinds >> i & 1u) != 0; }
  static bool has_kind(int) { return true; }
  double* kind_slots(int offset) const { return rows.kind_slots.data() + offset; }
};

}  // namespace

double solve_all_dof_rows(DofRows& rows, double v, const RowPhase& phase) {
  ScalarRows scalar{rows, phase};
  return row_sequence::solve(scalar, v, phase.delta_x,
                             {phase.tgs, phase.velocity_iteration, phase.time_to_step_end,
                              {phase.h, phase.recip_h, phase.limit_erp, phase.velocity_iteration}});
}

}  // namespace featherdrive
