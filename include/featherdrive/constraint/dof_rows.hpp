// All rows of one dof, solved together in PhysX's order: transmitted-force friction -> drive ->
// friction -> position limit -> velocity limit (docs/math/joint_constraints.md). Each sees the
// joint velocity the previous one left (v += r * impulse), and their impulse changes are applied
// as one.
#pragma once

#include "featherdrive/constraint/actuator_row.hpp"
#include "featherdrive/constraint/drive.hpp"
#include "featherdrive/constraint/joint_constraints.hpp"
#include "featherdrive/constraint/row_kinds.hpp"

namespace featherdrive {

/// One dof's rows for one step: set up once, updated every iteration.
struct DofRows {
  // The drive, read in every solve, first: with drive_only they are all a solve reads.
  DriveRow drive;
  double drive_impulse = 0.0;   ///< accumulated over the step
  bool has_drive = false;
  /// The drive is the dof's only row (no envelope, friction, limit or velocity limit): the
  /// sweep's inline fast path.
  bool drive_only = false;

  double response = 0.0;        ///< r = (M^-1)_jj (ERRATA 6)
  /// 1 / (r + cfm): every row but a force drive's (cfm from the link's cfm_scale, else 0); a
  /// lone drive's is the last full set-up's (setup_lone_drives leaves it)
  double recip_response = 0.0;

  /// PhysX's older friction (frictionCoefficient): |impulse| <= coefficient * h * |F|, F the
  /// spatial force the joint transmits at the step's start. Accumulated in PGS, fresh per solve
  /// in TGS. Used only where no static or viscous friction is set (like PhysX).
  bool has_transmission_friction = false;
  double transmission_friction_bound = 0.0;  ///< coefficient * h * |F| [N s]
  double transmission_friction_impulse = 0.0;  ///< PGS: the accumulated impulse
  double transmission_friction_applied = 0.0;  ///< all its impulse changes of the step

  bool has_envelope = false;
  ActuatorEnvelope envelope;
  double external_impulse = 0.0;  ///< applied joint force * dt, part of the actuator's effort

  bool has_friction = false;
  double static_friction_impulse = 0.0;   ///< static effort * dt
  double dynamic_friction_impulse = 0.0;  ///< dynamic effort * dt
  double viscous_friction = 0.0;          ///< viscous coefficient * dt

  bool has_limit = false;
  double error_low = 0.0;   ///< q0 - lower (negative: violated)
  double error_high = 0.0;  ///< upper - q0

  double max_velocity = 0.0;  ///< +inf for none

  /// An implicit actuator whose clip depends on the state (actuator_row.hpp): the drive row is
  /// its row and clip_actuator_impulse bounds it. Points into the simulation's actuators, set
  /// again by every step's setup; null otherwise.
  const ExplicitActuator* actuator = nullptr;
  double actuator_x0 = 0.0;  ///< the dof's position at the step's start

  // Accumulated over the step.
  double friction_impulse = 0.0;
  double low_impulse = 0.0;   ///< >= 0
  double high_impulse = 0.0;  ///< <= 0
  double velocity_limit_impulse = 0.0;

  /// The row kinds (constraint/row_kinds.hpp) the dof has: bit i for RowKinds' kind i, whose row
  /// is kind_slots from its slot offset on.
  unsigned kinds = 0;
  std::array<double, RowKinds::slots> kind_slots{};

  bool active() const {
    return has_transmission_friction || has_drive || has_friction || has_limit ||
           max_velocity < kNoVelocityLimit || kinds != 0;
  }
  static constexpr double kNoVelocityLimit = std::numeric_limits<double>::infinity();
};

/// Where in the step an update happens.
struct RowPhase {
  double dt = 0.0;              ///< the whole step tau
  double h = 0.0;               ///< the step of one solve: tau (PGS) or rho = tau / n (TGS)
  double recip_h = 0.0;         ///< 1 / h
  bool tgs = false;
  bool velocity_iteration = false;
  double delta_x = 0.0;         ///< TGS: position change accumulated over the sub-steps
  double time_to_step_end = 0.0;  ///< TGS: tau - i rho (eq. 41)
  double limit_erp = 0.8;       ///< share of a limit violation corrected per (sub-)step
};

/// Updates every row of the dof at joint velocity v; returns the impulse change to apply
/// (row_sequence::solve, constraint/row_sequence.hpp, the lanes' sequence too).
double solve_all_dof_rows(DofRows& rows, double v, const RowPhase& phase);

/// solve_all_dof_rows, with a dof whose only row is its drive solved inline (the common case in
/// the sweep's innermost loop).
inline double solve_dof_rows(DofRows& rows, double v, const RowPhase& phase) {
  if (!rows.drive_only) return solve_all_dof_rows(rows, v, phase);
  if (phase.tgs && phase.velocity_iteration) return 0.0;  // TGS freezes the drive
  const double next =
      drive_impulse(rows.drive, v, rows.drive_impulse, phase.delta_x, phase.time_to_step_end);
  const double delta = next - rows.drive_impulse;
  rows.drive_impulse = next;
  return delta;
}

/// solve_dof_rows for a lone drive (drive_only) in PGS without a row bias: delta_x and the time
/// to the step's end are 0 there, so drive_impulse's terms in them vanish (the same value).
inline double solve_lone_drive_pgs(DofRows& rows, double v) {
  const double lambda = drive_law::impulse_pgs(rows.drive, v, rows.drive_impulse);
  const double delta = lambda - rows.drive_impulse;
  rows.drive_impulse = lambda;
  return delta;
}

/// The accumulated drive impulse clamped to what the actuator envelope allows (the effort of the
/// step, drive plus external, within |E| <= max_effort - resistance |v| and
/// |v| <= max_actuator_velocity - gradient |E|, at the velocity v(lambda) the impulse leads to).
/// The envelope only ever scales the effort down, never reverses it.
double clamp_to_envelope(const ActuatorEnvelope& envelope, double unclamped, double accumulated,
                         double v, double response, double external_impulse, double dt);

}  // namespace featherdrive
