// The step, as a table of contents. PGS and TGS follow the spec and ../shared/physx/NOTES.md
// ("One step, PGS" / "One step, TGS"); docs/math/implicit_drives.md has the math.
#include "featherdrive/algorithm/aba.hpp"
#include "featherdrive/algorithm/inverse_mass_diagonal.hpp"
#include "featherdrive/algorithm/joint_motion.hpp"
#include "featherdrive/algorithm/kinematics.hpp"
#include "featherdrive/sim/simulation.hpp"

namespace featherdrive {

void Simulation::step() {
  const Model& model = *model_;
  const double dt = options_.dt;
  q_start_ = q_;  // kept to restore the state if the step diverges
  qd_start_ = qd_;
  drive_force_start_ = drive_force_;

  // Poses and velocities at the start of the step.
  forward_kinematics(model, data_, q_, qd_);
  // Free velocity v* = v + dt M^-1 (tau_applied + gravity - c(q, v)), once per step (NOTES 1).
  aba_from_kinematics(model, data_, qd_, applied_force_);
  qd_ += dt * data_.qdd;
  // Unit responses r = (M^-1)_jj and the whole-articulation response, frozen for the step.
  articulated_response(model, data_);
  // Drive rows, position iterations, position update, velocity iterations.
  if (options_.solver == SolverType::pgs) solve_pgs();
  else solve_tgs();
  // Outputs: the drive force is the step's accumulated impulse / dt (ERRATA 7).
  drive_force_ = drive_impulse_ / dt;
  check_finite_or_restore();
  time_ += dt;
  ++step_count_;
}

void Simulation::setup_drive_rows(double h, bool tgs) {
  const Model& model = *model_;
  for (int d = 0; d < model.nv; ++d) {
    const Drive& drive = drives_[static_cast<size_t>(d)];
    sweep_.has_rows[d] = drive.type != DriveType::none;
    if (!sweep_.has_rows[d]) continue;
    const double x0 = q_[model.links[model.dof_link[d]].q_index];
    drive_rows_[static_cast<size_t>(d)] = setup_drive_row(
        drive, data_.inverse_mass_diagonal[d], x0, h, options_.dt, tgs);
  }
  drive_impulse_.setZero();
  delta_x_.setZero();
}

// PGS: the rows converge on the coupled implicit step; positions move with the velocity after the
// position iterations; velocity iterations continue the same update (spec "PGS Velocity
// Iteration").
void Simulation::solve_pgs() {
  const Model& model = *model_;
  const double dt = options_.dt;
  setup_drive_rows(dt, /*tgs=*/false);
  auto drive_row = [this](int dof, double v) {
    const double before = drive_impulse_[dof];
    const double after = drive_impulse(drive_rows_[static_cast<size_t>(dof)], v, before, 0.0, 0.0);
    drive_impulse_[dof] = after;
    return after - before;
  };
  for (int it = 0; it < options_.position_iterations; ++it)
    gauss_seidel_sweep(model, data_, sweep_, qd_, drive_row);
  integrate_configuration(model, q_, qd_, dt, q_);
  for (int it = 0; it < options_.velocity_iterations; ++it)
    gauss_seidel_sweep(model, data_, sweep_, qd_, drive_row);
}

// TGS: each position iteration is a sub-step of rho = dt / n with a fresh impulse, the target
// interpolated (eq. 41) and the position change tracked (eq. 42-45); the inertia stays that of the
// step's start. Drive impulses are frozen in the velocity iterations (spec "TGS Velocity
// Iteration"), so with drives as the only rows they change nothing.
void Simulation::solve_tgs() {
  const Model& model = *model_;
  const double dt = options_.dt;
  const int n = options_.position_iterations;
  const double rho = dt / n;
  setup_drive_rows(rho, /*tgs=*/true);
  for (int i = 1; i <= n; ++i) {
    const double time_to_step_end = dt - i * rho;
    auto drive_row = [this, time_to_step_end](int dof, double v) {
      const double before = drive_impulse_[dof];
      const double after = drive_impulse(drive_rows_[static_cast<size_t>(dof)], v, before,
                                         delta_x_[dof], time_to_step_end);
      drive_impulse_[dof] = after;
      return after - before;
    };
    gauss_seidel_sweep(model, data_, sweep_, qd_, drive_row);
    integrate_configuration(model, q_, qd_, rho, q_);
    delta_x_ += rho * qd_;
  }
}

}  // namespace featherdrive
