// The step, as a table of contents. PGS and TGS follow the spec and ../shared/physx/NOTES.md
// ("One step, PGS" / "One step, TGS"); docs/math/implicit_drives.md has the math.
#include <algorithm>
#include <cmath>

#include "featherdrive/algorithm/aba.hpp"
#include "featherdrive/algorithm/inverse_mass_diagonal.hpp"
#include "featherdrive/algorithm/joint_motion.hpp"
#include "featherdrive/algorithm/kinematics.hpp"
#include "featherdrive/sim/simulation.hpp"
#include "physx_stages.hpp"

namespace featherdrive {
namespace {

// Share of a limit violation corrected per solve in position iterations: PhysX's articulation
// bias coefficients (0.8 for PGS; 2 sqrt(1 / n) for TGS with n sub-steps).
double limit_erp(SolverType solver, int position_iterations) {
  return solver == SolverType::pgs ? 0.8 : 2.0 * std::sqrt(1.0 / position_iterations);
}

}  // namespace

// The step's stages: its start (once per step), the physics advance over dt, its end. With the
// guard on, the advance may be redone as sub-steps (step_guard.cpp, docs/math/step_guard.md).
void Simulation::step() {
  const VecX& tau = begin_step();
  if (settings_.options.guard.enabled) {
    guarded_advance(tau);
  } else {
    dt_ = settings_.options.dt;
    target_lead_ = 0.0;
    advance(tau);
    row_forces();
  }
  end_step();
}

// Explicit actuators on the step-start state (tau = applied force + their efforts), and the
// delayed drives' targets for this step (drive_delay.cpp): pushed once per step.
const VecX& Simulation::begin_step() {
  load_state();  // the storage keeps the step's start until commit_state
  return control_stages();
}

const VecX& Simulation::control_stages() {
  const VecX& tau = apply_actuators();
  if (drive_delays_.any()) drive_delays_.push(settings_.drives);
  return tau;
}

// The physics over dt_ from q_, qd_ with joint force tau: the rows' impulses are left in rows_.
void Simulation::advance(const VecX& tau) {
  const Model& model = *model_;
  const double dt = dt_;
  // Joint velocities above their limits are scaled down together (PhysX 5.6.1).
  scale_to_velocity_limits();
  // Poses at the start of the step. ABA computes the velocities it needs, in frame 0; the link
  // bias of compat physx and link damping read the link-frame ones.
  if (physx() || link_damping_active_) forward_kinematics(model, data_, q_, qd_);
  else world_poses(model, data_, q_);
  // PhysX's link damping and link velocity limits: forces on the free velocity (link_damping.cpp).
  any_link_force_ = link_damping_active_ &&
                    link_damping_forces(model, data_, settings_.link_parameters, dt, link_force_);
  const std::vector<Vec6>* link_force = any_link_force_ ? &link_force_ : nullptr;
  // Free velocity v* = v + dt M^-1 (tau_applied + gravity - c(q, v)), once per step (NOTES 1);
  // with the accelerations, in the same pass, the unit responses r = (M^-1)_jj and the
  // whole-articulation response, frozen for the step.
  articulated_bodies(model, data_, qd_, tau, link_force);
  accelerations_and_response(model, data_);
  // The force each joint transmits, for the friction coefficient (transmitted_force.cpp).
  if ((settings_.friction_coefficient.array() > 0.0).any())
    transmitted_force_magnitudes(model, data_, link_force, subtree_force_, transmitted_force_);
  const bool classical_root = !physx() && model.floating_base();
  Vec6 root_qd0 = Vec6::Zero();
  if (classical_root) root_qd0 = qd_.head<6>();
  qd_ += dt * data_.qdd;
  if (classical_root) begin_classical_root(root_qd0, dt);
  // compat physx: the rows' link bias; a floating base's momentum kept (NOTES, departures 1, 2).
  if (physx()) {
    compute_link_bias(model, data_, qd_, dt, departures_);
    if (model.floating_base())
      correct_free_velocity_momentum(model, data_, tau, link_force, dt, departures_, qd_);
  }
  if (link_cfm_active_)
    link_cfm(model, data_, settings_.link_parameters, link_cfm_);  // link_cfm.cpp
  // Rows, position iterations, position update, velocity iterations.
  if (settings_.options.solver == SolverType::pgs) solve_pgs();
  else solve_tgs();
  if (physx() && model.floating_base()) correct_end_of_step_momentum(model, dt, departures_, q_, qd_);
  if (classical_root) end_classical_root();
  // PhysX's eREVOLUTE joints wrap once, at the end of the step (revolute_wrap.cpp).
  wrap_revolute_positions(model, settings_.revolute_wrap, q_);
}

// Outputs: each force is its accumulated impulse of the step / dt (ERRATA 7).
void Simulation::row_forces() {
  const double inv_dt = 1.0 / settings_.options.dt;
  for (int d = 0; d < model_->nv; ++d) {
    const DofRows& r = rows_[static_cast<size_t>(d)];
    drive_force_[d] = r.drive_impulse * inv_dt;
    if (actuated_ && actuators_.implicit(d)) {  // the row was the actuator's
      actuator_force_[d] = drive_force_[d];
      drive_force_[d] = 0.0;
    }
    limit_force_[d] = (r.low_impulse + r.high_impulse) * inv_dt;
    friction_force_[d] = (r.friction_impulse + r.transmission_friction_applied) * inv_dt;
    velocity_limit_force_[d] = r.velocity_limit_impulse * inv_dt;
  }
  contact_forces();  // contact.cpp
}

void Simulation::end_step() {
  check_finite_or_throw();
  commit_state();
  if (settings_.options.guard.enabled) commit_guard_account();
  time_ += settings_.options.dt;
  ++step_count_;
}

// Rows later in a sweep can push a dof already clamped by its velocity limit past it again. Like
// PhysX (computeLinkStates), the step starts by scaling every joint velocity by the one ratio that
// brings the worst offender back to its limit, which keeps the direction of motion.
void Simulation::scale_to_velocity_limits() {
  double ratio = 1.0;
  for (int d = 0; d < model_->nv; ++d)
    if (std::abs(qd_[d]) > settings_.max_joint_velocity[d])
      ratio = std::min(ratio, settings_.max_joint_velocity[d] / std::abs(qd_[d]));
  if (ratio < 1.0) qd_ *= ratio;
}

// Every dof's rows, set up once per step from the start-of-step configuration (eq. 20-24, 35-39).
// A dof whose only row is an undelayed drive needs its drive row alone: the other fields stay as
// the last full setup left them (the drive row writes no other accumulator).
void Simulation::setup_rows(double h, bool tgs) {
  const Model& model = *model_;
  const int nv = model.nv;
  int* const order = dof_order_.data();
  if (row_kinds_changed_) {
    int front = 0, back = nv;
    for (int d = 0; d < nv; ++d) {
      setup_dof_rows(d, h, tgs);
      // An implicit actuator's row is set up from the actuator, not from settings_.drives.
      const bool lone = rows_[static_cast<size_t>(d)].drive_only && !drive_delays_.delayed(d) &&
                        !actuators_.implicit(d) &&
                        model.links[model.dof_link[d]].joint_type != JointType::spherical;
      order[lone ? front++ : --back] = d;
    }
    num_lone_drives_ = front;
    row_kinds_changed_ = false;
  } else {
    setup_lone_drives(h, tgs);
    for (int k = nv - 1; k >= num_lone_drives_; --k) setup_dof_rows(order[k], h, tgs);
  }
  bool other_rows = false;  // rows on a dof that is not a lone drive
  any_undriven_rows_ = false;
  for (int k = num_lone_drives_; k < nv; ++k) {
    const DofRows& rows = rows_[static_cast<size_t>(order[k])];
    other_rows = other_rows || rows.active();
    any_undriven_rows_ = any_undriven_rows_ || (rows.active() && !rows.drive_only);
  }
  any_rows_ = num_lone_drives_ > 0 || other_rows;
  only_lone_drives_pgs_ = !other_rows && !tgs && !physx() && mimic_.empty();
  delta_x_.setZero();
  if (!mimic_.empty())  // mimic_solve.cpp: the rows' responses, with the limits' bias coefficient
    mimic_.setup(model, data_, h,
                 limit_erp(settings_.options.solver, settings_.options.position_iterations));
  if (target_lead_ != 0.0) lead_drive_targets();  // a guard sub-step (step_guard.cpp)
}

// The lone drives' rows (setup_dof_rows's fields that change from step to step), in one loop
// over raw pointers: Eigen's stores may alias anything, so the compiler would reload every
// vector's data pointer after each of them.
void Simulation::setup_lone_drives(double h, bool tgs) {
  const int* const dof_link = model_->dof_link.data();
  const Data::LinkInfo* const info = data_.info.data();
  const double* const r_of = data_.inverse_mass_diagonal.data();
  const double* const q = q_.data();
  const double* const cfm = link_cfm_.data();
  const double* const applied = applied_force_.data();
  const Drive* const drives = settings_.drives.data();
  DofRows* const rows = rows_.data();
  const int* const order = dof_order_.data();
  const double dt = dt_;
  for (int k = 0; k < num_lone_drives_; ++k) {
    const int d = order[k];
    const int i = dof_link[d];
    const Data::LinkInfo& link = info[i];
    const Drive& drive = drives[d];
    double r = r_of[d];
    DofRows& row = rows[d];
    row.drive_impulse = 0.0;
    row.response = r;
    row.external_impulse = applied[d] * dt;
    if (drive.type == DriveType::acceleration)
      r += std::max(cfm[i], link.parent >= 0 ? cfm[link.parent] : 0.0);
    row.drive = setup_drive_row(drive, r, q[link.q_index], h, dt, tgs);
  }
}

// Dof d's rows, every field.
void Simulation::setup_dof_rows(int d, double h, bool tgs) {
  const Model& model = *model_;
  const double dt = dt_;
  auto drive_seen = [this](int dof) -> const Drive& {
    return drive_delays_.delayed(dof) ? drive_delays_.drive_seen(dof)
                                      : settings_.drives[static_cast<size_t>(dof)];
  };
  // A spherical joint's three drives, twist first: their targets make one rotation.
  auto axis_drives = [&](int dof) {
    const int first = model.links[model.dof_link[dof]].v_index;
    return std::array<const Drive*, 3>{&drive_seen(first), &drive_seen(first + 1),
                                       &drive_seen(first + 2)};
  };
  DofRows& rows = rows_[static_cast<size_t>(d)];
  // Data's compact copy of the link: a Link spreads over a kilobyte.
  const Data::LinkInfo& link = data_.info[model.dof_link[d]];
  const bool spherical = link.type == JointType::spherical;
  if (link.type != JointType::revolute && link.type != JointType::prismatic && !spherical) {
    rows = DofRows{};
    sweep_.has_rows[d] = 0;
    return;
  }
  // Every field is set below; the accumulators start from zero.
  rows.drive_impulse = 0.0;
  rows.transmission_friction_impulse = 0.0;
  rows.transmission_friction_applied = 0.0;
  rows.friction_impulse = 0.0;
  rows.low_impulse = 0.0;
  rows.high_impulse = 0.0;
  rows.velocity_limit_impulse = 0.0;
  const double r = data_.inverse_mass_diagonal[d];
  // A spherical axis's position is PhysX's, from the quaternion (spherical_rows.cpp).
  const double x0 = spherical ? spherical_axis_position(model, q_, d) : q_[link.q_index];
  // PhysX's cfm: the larger of the child's and the parent's (link_cfm.cpp).
  const double cfm = std::max(link_cfm_[model.dof_link[d]],
                              link.parent >= 0 ? link_cfm_[link.parent] : 0.0);
  rows.response = r;
  const Drive& drive = drive_seen(d);
  const bool driven = drive.type != DriveType::none;
  rows.has_drive = driven;
  // An acceleration drive's coefficients carry 1 / (r + cfm), a force drive's r (eq. 32-39).
  // A spherical drive's error is formed from the quaternion: x0 stands for target - error.
  const double x0_drive =
      spherical && rows.has_drive
          ? drive.target_position - spherical_axis_drive_error(model, q_, d, axis_drives(d))
          : x0;
  rows.drive = rows.has_drive ? setup_drive_row(drive, drive.type == DriveType::acceleration
                                                           ? r + cfm : r, x0_drive, h, dt, tgs)
                              : DriveRow{};
  // An implicit actuator's law is the row of its (driveless) dof (implicit_actuators.md, I4-I7).
  rows.actuator = nullptr;
  if (actuators_.implicit(d)) {
    const ExplicitActuator& actuator = actuators_.actuator(d);
    rows.has_drive = true;
    rows.drive = setup_actuator_row(actuator, actuators_.command_seen(d), r, x0, h, dt, tgs);
    if (actuator_clip_depends_on_state(actuator)) rows.actuator = &actuator;
    rows.actuator_x0 = x0;
  }
  const ActuatorEnvelope& envelope = settings_.envelopes[static_cast<size_t>(d)];
  rows.has_envelope = driven && envelope.active();
  rows.envelope = envelope;
  rows.external_impulse = applied_force_[d] * dt;
  const JointFriction& friction = settings_.friction[static_cast<size_t>(d)];
  rows.has_transmission_friction = settings_.friction_coefficient[d] > 0.0 &&
                                   friction.static_effort == 0.0 && friction.viscous == 0.0;
  rows.transmission_friction_bound =
      settings_.friction_coefficient[d] * h * transmitted_force_[model.dof_link[d]];
  rows.has_friction = friction.active();
  rows.static_friction_impulse = friction.static_effort * dt;
  rows.dynamic_friction_impulse = friction.dynamic_effort * dt;
  rows.viscous_friction = friction.viscous * dt;
  rows.has_limit =
      std::isfinite(settings_.lower_limit[d]) || std::isfinite(settings_.upper_limit[d]);
  rows.error_low = x0 - settings_.lower_limit[d];  // +inf where unbounded
  rows.error_high = settings_.upper_limit[d] - x0;
  rows.max_velocity = settings_.max_joint_velocity[d];
  rows.drive_only = rows.has_drive && !rows.has_envelope && !rows.actuator &&
                    !rows.has_transmission_friction &&
                    !rows.has_friction && !rows.has_limit &&
                    !(rows.max_velocity < DofRows::kNoVelocityLimit);
  // 1 / (r + cfm) is read by every row but a lone drive.
  rows.recip_response = rows.drive_only ? 0.0 : 1.0 / (r + cfm);
  sweep_.has_rows[d] = rows.active() ? 1 : 0;
}

// Where a contact solve stands: TGS's elapsed time is the sub-step's start; the velocity
// iterations run at dt (docs/math/contact.md, C7).
static ContactPhase contact_phase(const RowPhase& phase) {
  ContactPhase c;
  c.dt = phase.dt;
  c.h = phase.h;
  c.tgs = phase.tgs;
  c.velocity_iteration = phase.velocity_iteration;
  c.elapsed = phase.velocity_iteration ? phase.dt : phase.dt - phase.time_to_step_end - phase.h;
  return c;
}

// The phase is updated in place with each dof's delta_x (a copy per row solve was a fifth of the
// row solves' cost).
void Simulation::sweep(RowPhase& phase) {
  // PhysX solves the mimic rows first in every iteration (solveInternalConstraints).
  if (!mimic_.empty())
    mimic_.solve(*model_, data_, q_, departures_.row_bias.data(), phase.velocity_iteration, qd_);
  // Self-collision rows too, as PhysX's constraints outside the sweep (contact.md, C31).
  if (self_contacts_active_) self_contacts_.solve(*model_, data_, contact_phase(phase), qd_);
  if (!any_rows_ && !contacts_active_) return;
  // Raw pointers and a copy of the phase: the compiler need not reload them after each store.
  DofRows* const rows = rows_.data();
  const double* const row_bias = departures_.row_bias.data();
  const double* const delta_x = delta_x_.data();
  auto solve_row = [rows, row_bias, delta_x, phase](int dof, double v) mutable {
    phase.delta_x = delta_x[dof];
    return solve_dof_rows(rows[dof], v + row_bias[dof], phase);
  };
  if (contacts_active_) {
    // Each link's contact rows right after its joint's rows (docs/math/contact.md, C15), at
    // the link's velocity of the sweep's start plus the sweep's change.
    contact_link_velocities();
    const ContactPhase contacts = contact_phase(phase);
    gauss_seidel_sweep(*model_, data_, sweep_, qd_, solve_row, [&](int link, Vec6& dv) {
      return contact_rows_.solve_link(link, contact_link_velocity_[static_cast<size_t>(link)], dv,
                                      contacts);
    });
    return;
  }
  if (only_lone_drives_pgs_) {  // the common case of drives alone, without the general row law
    gauss_seidel_sweep(*model_, data_, sweep_, qd_,
                       [rows](int dof, double v) { return solve_lone_drive_pgs(rows[dof], v); });
    return;
  }
  gauss_seidel_sweep(*model_, data_, sweep_, qd_, solve_row);
}

// PGS: the rows converge on the coupled implicit step; positions move with the velocity after the
// position iterations; velocity iterations continue the same update without new position error
// (spec "PGS Velocity Iteration").
void Simulation::solve_pgs() {
  const double dt = dt_;
  setup_rows(dt, /*tgs=*/false);
  RowPhase phase;
  phase.dt = dt;
  phase.h = dt;
  phase.limit_erp = limit_erp(SolverType::pgs, settings_.options.position_iterations);
  if (contacts_active_ || self_contacts_active_) setup_contacts(phase);
  const int last = settings_.options.position_iterations - 1;
  for (int it = 0; it < last; ++it) sweep(phase);
  if (track_convergence_)  // the impulses before the last iteration, then its change
    for (int d = 0; d < model_->nv; ++d)
      last_drive_change_[d] = rows_[static_cast<size_t>(d)].drive_impulse;
  sweep(phase);
  if (track_convergence_)
    for (int d = 0; d < model_->nv; ++d)
      last_drive_change_[d] = rows_[static_cast<size_t>(d)].drive_impulse - last_drive_change_[d];
  departures_.qd_position = qd_;
  integrate_positions(dt);
  phase.velocity_iteration = true;
  // A guard sub-step runs none: at every sub-step they fed energy into long chains
  // (docs/math/step_guard.md, "The sub-step law").
  const int velocity_iterations =
      dt_ == settings_.options.dt ? settings_.options.velocity_iterations : 0;
  for (int it = 0; it < velocity_iterations; ++it) sweep(phase);
  if (physx())  // prismatic_limits.cpp
    clamp_prismatic_positions(*model_, settings_.lower_limit, settings_.upper_limit, q_);
}

// TGS: each position iteration is a sub-step of rho = dt / n with a fresh drive impulse, the
// target interpolated (eq. 41) and the position change tracked (eq. 42-45); the inertia stays that
// of the step's start. Drive impulses are frozen in the velocity iterations (spec "TGS Velocity
// Iteration"); friction, limits and velocity limits keep acting there.
void Simulation::solve_tgs() {
  const double dt = dt_;
  const int n = settings_.options.position_iterations;
  const double rho = dt / n;
  setup_rows(rho, /*tgs=*/true);
  if (track_convergence_) last_drive_change_.setZero();  // no iteration to converge
  RowPhase phase;
  phase.dt = dt;
  phase.h = rho;
  phase.tgs = true;
  phase.limit_erp = limit_erp(SolverType::tgs, n);
  if (contacts_active_ || self_contacts_active_) setup_contacts(phase);
  departures_.qd_position.setZero();
  for (int i = 1; i <= n; ++i) {
    phase.time_to_step_end = dt - i * rho;
    sweep(phase);
    integrate_positions(rho);
    // PhysX clamps a limited prismatic joint's position in every sub-step (propagateTransform,
    // from recordDeltaMotion), so the next sub-step's rows and the velocity iterations measure
    // the position change from the clamped pose (prismatic_limits.cpp).
    if (physx())
      clamp_prismatic_positions(*model_, settings_.lower_limit, settings_.upper_limit, q_);
    delta_x_ += rho * qd_;
    if (physx()) {
      // A spherical row's position change carries its link bias (spherical_joints.md, eq. S-8);
      // a prismatic row's is measured again below.
      delta_x_ += rho * departures_.row_bias;
      // PhysX measures a prismatic row's position change geometrically (NOTES, departure 1);
      // the sub-step's poses and turns it leaves are the contacts' too (contact.md, C25a).
      track_prismatic_position_change(*model_, q_, qd_, rho, departures_, delta_x_);
      departures_.qd_position += (1.0 / n) * qd_;
    }
    if (contacts_active_ || self_contacts_active_) track_contacts(rho);
  }
  phase.velocity_iteration = true;
  // Drives alone apply nothing there: the sweep would leave every velocity as it is.
  if (!any_undriven_rows_ && mimic_.empty() && !contacts_active_ && !self_contacts_active_) return;
  for (int it = 0; it < settings_.options.velocity_iterations; ++it) sweep(phase);
}

// compat none: a floating root's body-frame velocity (omega_b, v_b) gains dt (omega_b x v_b)
// over the free update, which makes R0 v_b the classical velocity of its origin at the step's end
// (v_O + dt a_O) instead of the spatial one; the rows and the position update use that, and the
// step's end expresses it in the root's new axes (docs/math/contact.md, C26-C28).
void Simulation::begin_classical_root(const Vec6& root_qd0, double dt) {
  const Vec3 w = root_qd0.head<3>(), v = root_qd0.tail<3>();
  qd_.segment<3>(3) += dt * w.cross(v);
  root_rotation0_ = Quat(q_[3], q_[4], q_[5], q_[6]).normalized().toRotationMatrix();
}

void Simulation::end_classical_root() {
  const Mat3 R1 = Quat(q_[3], q_[4], q_[5], q_[6]).normalized().toRotationMatrix();
  qd_.segment<3>(3) = R1.transpose() * (root_rotation0_ * qd_.segment<3>(3));
}

// q advanced over h. compat physx moves a floating root about its COM with the world velocity of
// the step's start frame, as PhysX keeps it (updateRootBody, recordDeltaMotion).
void Simulation::integrate_positions(double h) {
  // compat physx turns a spherical joint's link in the world as PhysX does (spherical_rows.cpp):
  // the rotations before the sub-step.
  const bool spherical = physx() && has_spherical_joints(*model_);
  if (spherical) world_pose(*model_, q_, departures_.now);
  if (!model_->floating_base()) {
    integrate_configuration(*model_, q_, qd_, h, q_);
  } else if (!physx()) {
    // The root's origin moves with its world velocity in the step's start axes (R0 v_b), the
    // velocity the rows solved for (docs/math/contact.md, C27).
    const Vec3 p = q_.head<3>();
    integrate_configuration(*model_, q_, qd_, h, q_);
    q_.head<3>() = p + h * (root_rotation0_ * qd_.segment<3>(3));
  } else {
    const int iq = model_->links[0].q_index;
    const Eigen::Matrix<double, 7, 1> root = q_.segment<7>(iq);
    integrate_configuration(*model_, q_, qd_, h, q_);
    q_.segment<7>(iq) = root;
    integrate_root_about_com(*model_, qd_, h, departures_, q_);
  }
  if (spherical)
    integrate_spherical_joints(*model_, data_.world_rotation, qd_,
                               &departures_.bias_w, h, departures_, q_);
}

}  // namespace featherdrive
