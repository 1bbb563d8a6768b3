// A dof's rows set up for one step, written once over the number type: the scalar step's
// setup_dof_rows and setup_lone_drives (sim/step.cpp, T = double, writing a DofRows) and the SIMD
// lanes' setup_dof_row and setup_row_constants (sim/simd_lane_step.hpp, T a pack of
// environments, writing the packed row) all run these. Every choice on T is a select
// (core/select.hpp); which rows a dof has is the caller's. docs/math/implicit_drives.md (eq.
// 20-24, 35-39), implicit_actuators.md (I4-I7), joint_constraints.md; docs/architecture.md,
// "Where each row kind lives".
#pragma once

#include "featherdrive/constraint/actuator_row.hpp"
#include "featherdrive/constraint/drive.hpp"
#include "featherdrive/core/select.hpp"

namespace featherdrive::row_setup {

/// Where in the step the rows are set up (one value for all lanes).
struct Step {
  double h = 0.0;   ///< the step of one solve: tau (PGS) or rho = tau / n (TGS)
  double dt = 0.0;  ///< the whole step tau
  bool tgs = false;
};

// Dof is the dof as a set-up reads and writes it (a DofRows and the settings, or a packed row
// and the lanes' parameters), over T and its mask M:
//   inputs:  bool any_of(M)              some lane's mask is set;
//            bool any_driven()           some lane has a drive row (else the empty row);
//            M acceleration_drive()      the lanes whose drive is an acceleration drive;
//            DriveTermsOf<T> drive_terms();
//            bool any_actuated()         some lane's row is an implicit actuator's;
//            M actuated(); ActuatorTermsOf<T> actuator_terms();
//            bool any_cfm()              some lane's link or parent has a cfm (else r + cfm
//                                        is r: skipped);
//            T cfm_child(), cfm_parent() the link's and its parent's cfm (link_cfm.cpp);
//            T applied_force(), lower_limit(), upper_limit();
//            T static_effort(), dynamic_effort(), viscous()   its friction;
//   outputs: set_drive(DriveRowOf<T>), and as T&: response(), recip(), external(),
//            actuator_x0(), error_low(), error_high(), friction_static(), friction_dynamic(),
//            friction_viscous(), and the accumulators drive_impulse(), tf_impulse(),
//            tf_applied(), friction_impulse(), low(), high(), velocity_limit().
// The set-ups are forced inline into the callers' loops, where what the adapter fixes (no
// actuator on a lone drive) folds away: out of line, a lone drive's set-up ran 55 % more
// instructions.

/// r + cfm, the response every row but a force drive's reads: cfm the larger of the link's and
/// its parent's (joint_constraints.md); r itself where no lane has one (r + 0 = r).
template <class T, class Dof>
T response_with_cfm(const Dof& dof, const T& r) {
  if (!dof.any_cfm()) return r;
  const T child = dof.cfm_child(), parent = dof.cfm_parent();
  return r + select(child < parent, parent, child);  // std::max(child, parent)
}

/// The drive row of a dof with unit response r, r_cfm = r + cfm, start-of-step position x0 and
/// x0_drive, the position its drive's error is taken from (target - error for a spherical axis):
/// a force drive with response r, an acceleration drive with r + cfm (eq. 32-39), and where an
/// implicit actuator is, its row in the drive's place with r at x0 (implicit_actuators.md, I4).
template <class T, class Dof>
[[gnu::always_inline]] inline DriveRowOf<T> drive_row(const Dof& dof, const T& r, const T& r_cfm,
                                                     const T& x0, const T& x0_drive,
                                                     const Step& s) {
  DriveRowOf<T> row;
  if (dof.any_driven()) {
    const auto acceleration = dof.acceleration_drive();
    row = drive_law::setup(dof.drive_terms(), acceleration, select(acceleration, r_cfm, r),
                           x0_drive, s.h, s.dt, s.tgs, dof.any_of(acceleration));
  }
  if (dof.any_actuated()) {
    const auto actuated = dof.actuated();
    const DriveRowOf<T> a = actuator_row::setup(dof.actuator_terms(), r, x0, s.h, s.dt, s.tgs);
    row.target_vel_plus_initial_bias =
        select(actuated, a.target_vel_plus_initial_bias, row.target_vel_plus_initial_bias);
    row.vel_multiplier = select(actuated, a.vel_multiplier, row.vel_multiplier);
    row.impulse_multiplier = select(actuated, a.impulse_multiplier, row.impulse_multiplier);
    row.bias_coefficient = select(actuated, a.bias_coefficient, row.bias_coefficient);
    row.target_pos_bias = select(actuated, a.target_pos_bias, row.target_pos_bias);
    row.max_impulse = select(actuated, a.max_impulse, row.max_impulse);
  }
  return row;
}

/// What of a dof's rows depends only on its settings and the step's dt: friction's efforts as
/// impulses (J1). The lanes set it once a call, the scalar step with every full set-up.
template <class T, class Dof>
void constants(Dof& dof, double dt) {
  const T step(dt);
  dof.friction_static() = dof.static_effort() * step;
  dof.friction_dynamic() = dof.dynamic_effort() * step;
  dof.friction_viscous() = dof.viscous() * step;
}

/// The bound of transmitted-force friction (J6): coefficient * h * |F|, F the force the joint
/// transmits at the step's start.
template <class T>
T transmission_friction_bound(const T& coefficient, double h, const T& force) {
  return coefficient * T(h) * force;
}

/// The fields of a dof's rows that change from step to step when its only row is its drive: the
/// drive row, its accumulator, r and the external impulse (the rest stays as set up before).
template <class T, class Dof>
[[gnu::always_inline]] inline void lone_drive(Dof& dof, const T& r, const T& x0, const Step& s) {
  dof.drive_impulse() = T(0.0);
  dof.response() = r;
  dof.external() = dof.applied_force() * T(s.dt);
  // Only an acceleration drive reads r + cfm (elsewhere the select takes r): formed where one is.
  const T r_cfm = dof.any_of(dof.acceleration_drive()) ? response_with_cfm(dof, r) : r;
  dof.set_drive(drive_row(dof, r, r_cfm, x0, x0, s));
}

/// Every per-step field of a dof's rows: the accumulators zeroed, the drive (or implicit
/// actuator) row, r and 1 / (r + cfm), the external impulse, the limit errors x0 - lower and
/// upper - x0 (+inf where unbounded). r, x0 and x0_drive as for drive_row.
template <class T, class Dof>
[[gnu::always_inline]] inline void setup(Dof& dof, const T& r, const T& x0, const T& x0_drive,
                                         const Step& s) {
  const T zero(0.0);
  dof.drive_impulse() = zero;
  dof.tf_impulse() = zero;
  dof.tf_applied() = zero;
  dof.friction_impulse() = zero;
  dof.low() = zero;
  dof.high() = zero;
  dof.velocity_limit() = zero;
  const T r_cfm = response_with_cfm(dof, r);
  dof.response() = r;
  dof.set_drive(drive_row(dof, r, r_cfm, x0, x0_drive, s));
  if (dof.any_actuated()) dof.actuator_x0() = x0;  // a remotized_pd clip reads it
  dof.external() = dof.applied_force() * T(s.dt);
  dof.error_low() = x0 - dof.lower_limit();
  dof.error_high() = dof.upper_limit() - x0;
  dof.recip() = T(1.0) / r_cfm;
}

}  // namespace featherdrive::row_setup
