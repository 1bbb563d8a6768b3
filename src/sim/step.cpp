// The step, as a table of contents. PGS and TGS follow the spec and ../shared/physx/NOTES.md
// ("One step, PGS" / "One step, TGS"); docs/math/implicit_drives.md has the math.
#include <algorithm>
#include <cmath>

#include "featherdrive/algorithm/aba.hpp"
#include "featherdrive/algorithm/inverse_mass_diagonal.hpp"
#include "featherdrive/algorithm/joint_motion.hpp"
#include "featherdrive/algorithm/kinematics.hpp"
#include "featherdrive/algorithm/link_motion_law.hpp"
#include "featherdrive/constraint/row_laws.hpp"
#include "featherdrive/constraint/row_setup.hpp"
#include "physx_stages.hpp"
#include "workspace.hpp"

namespace featherdrive {
namespace {

// Share of a limit violation corrected per solve in position iterations: PhysX's articulation
// bias coefficients (0.8 for PGS; 2 sqrt(1 / n) for TGS with n sub-steps).
double limit_erp(SolverType solver, int position_iterations) {
  return solver == SolverType::pgs ? 0.8 : 2.0 * std::sqrt(1.0 / position_iterations);
}

// A dof as row_setup (constraint/row_setup.hpp) reads and writes it in the scalar step: its
// DofRows and settings, every row it has on its one "lane" (each mask a bool). What the lone
// drives' loop reads comes as raw pointers and values (setup_lone_drives); the rest from
// settings only where a full set-up asks.
struct ScalarDof {
  DofRows& rows;
  const Drive& drive;
  const double* link_cfm;
  int link, parent;
  double applied;
  const Settings& settings;
  int d;
  const ExplicitActuator* actuator = nullptr;  ///< an implicit actuator's (its row is the drive's)
  const ActuatorCommand* command = nullptr;    ///< the command it sees

  static bool any_of(bool mask) { return mask; }
  bool any_driven() const { return drive.type != DriveType::none; }
  bool acceleration_drive() const { return drive.type == DriveType::acceleration; }
  DriveTermsOf<double> drive_terms() const { return featherdrive::drive_terms(drive); }
  bool any_actuated() const { return actuator != nullptr; }
  static bool actuated() { return true; }
  ActuatorTermsOf<double> actuator_terms() const {
    return featherdrive::actuator_terms(*actuator, *command);
  }
  static bool any_cfm() { return true; }
  double cfm_child() const { return link_cfm[link]; }
  double cfm_parent() const { return parent >= 0 ? link_cfm[parent] : 0.0; }
  double applied_force() const { return applied; }
  double lower_limit() const { return settings.lower_limit[d]; }
  double upper_limit() const { return settings.upper_limit[d]; }
  const JointFriction& friction() const { return settings.friction[static_cast<size_t>(d)]; }
  double static_effort() const { return friction().static_effort; }
  double dynamic_effort() const { return friction().dynamic_effort; }
  double viscous() const { return friction().viscous; }

  void set_drive(const DriveRow& row) const { rows.drive = row; }
  double& response() const { return rows.response; }
  double& recip() const { return rows.recip_response; }
  double& external() const { return rows.external_impulse; }
  double& actuator_x0() const { return rows.actuator_x0; }
  double& error_low() const { return rows.error_low; }
  double& error_high() const { return rows.error_high; }
  double& friction_static() const { return rows.static_friction_impulse; }
  double& friction_dynamic() const { return rows.dynamic_friction_impulse; }
  double& friction_viscous() const { return rows.viscous_friction; }
  double& drive_impulse() const { return rows.drive_impulse; }
  double& tf_impulse() const { return rows.transmission_friction_impulse; }
  double& tf_applied() const { return rows.transmission_friction_applied; }
  double& friction_impulse() const { return rows.friction_impulse; }
  double& low() const { return rows.low_impulse; }
  double& high() const { return rows.high_impulse; }
  double& velocity_limit() const { return rows.velocity_limit_impulse; }
};

}  // namespace

// The step's stages: its start (once per step), the physics advance over dt, its end. With the
// guard on, the advance may be redone as sub-steps (step_guard.cpp, docs/math/step_guard.md).
void Stepper::step() {
  const VecX& tau = begin_step();
  if (settings_.options.guard.enabled) {
    guarded_advance(tau);
  } else {
    ws_.dt = settings_.options.dt;
    ws_.target_lead = 0.0;
    advance(tau);
    row_forces();
  }
  end_step();
}

// Explicit actuators on the step-start state (tau = applied force + their efforts), and the
// delayed drives' targets for this step (drive_delay.cpp): pushed once per step.
const VecX& Stepper::begin_step() {
  load_state();  // the storage keeps the step's start until commit_state
  return control_stages();
}

const VecX& Stepper::control_stages() {
  const VecX& tau = apply_actuators();
  if (ws_.drive_delays.any()) ws_.drive_delays.push(settings_.drives);
  return tau;
}

// The physics over the workspace's dt from its q, qd with joint force tau: the rows' impulses are
// left in its rows.
void Stepper::advance(const VecX& tau) {
  const Model& model = *model_;
  const double dt = ws_.dt;
  // Joint velocities above their limits are scaled down together (PhysX 5.6.1).
  scale_to_velocity_limits();
  // Poses at the start of the step; ABA's pass 1 forms the velocities (frame 0) that the link bias
  // of compat physx and link damping read too.
  world_poses(model, ws_.data, ws_.q);
  body_motions(model, ws_.data, ws_.qd);
  // PhysX's link damping and link velocity limits: forces on the free velocity (link_damping.cpp).
  ws_.any_link_force =
      ws_.link_damping_active &&
      link_damping_forces(model, ws_.data, settings_.link_parameters, dt, ws_.link_force);
  const std::vector<Vec6>* link_force = ws_.any_link_force ? &ws_.link_force : nullptr;
  // Free velocity v* = v + dt M^-1 (tau_applied + gravity - c(q, v)), once per step (NOTES 1);
  // with the accelerations, in the same pass, the unit responses r = (M^-1)_jj and the
  // whole-articulation response, frozen for the step.
  articulate(model, ws_.data, tau, link_force);
  accelerations_and_response(model, ws_.data);
  // The force each joint transmits, for the friction coefficient (transmitted_force.cpp).
  if ((settings_.friction_coefficient.array() > 0.0).any())
    transmitted_force_magnitudes(model, ws_.data, ws_.transmitted_force);
  const bool classical_root = !physx() && model.floating_base();
  Vec6 root_qd0 = Vec6::Zero();
  if (classical_root) root_qd0 = ws_.qd.head<6>();
  ws_.qd += dt * ws_.data.qdd;
  if (classical_root) begin_classical_root(root_qd0, dt);
  // compat physx: the rows' link bias; a floating base's momentum kept (NOTES, departures 1, 2).
  if (physx()) {
    compute_link_bias(model, ws_.data, dt, ws_.departures);
    if (model.floating_base())
      correct_free_velocity_momentum(model, ws_.data, tau, link_force, dt, ws_.departures, ws_.qd);
  }
  if (ws_.link_cfm_active)
    link_cfm(model, ws_.data, settings_.link_parameters, ws_.link_cfm);  // link_cfm.cpp
  // Rows, position iterations, position update, velocity iterations.
  if (settings_.options.solver == SolverType::pgs) solve_pgs();
  else solve_tgs();
  if (physx() && model.floating_base())
    correct_end_of_step_momentum(model, ws_.data, dt, ws_.departures, ws_.q, ws_.qd);
  if (classical_root) end_classical_root();
  // PhysX's eREVOLUTE joints wrap once, at the end of the step (revolute_wrap.cpp).
  wrap_revolute_positions(model, settings_.revolute_wrap, ws_.q);
}

// Outputs: each force is its accumulated impulse of the step / dt (ERRATA 7).
void Stepper::row_forces() {
  const double inv_dt = 1.0 / settings_.options.dt;
  for (int d = 0; d < model_->nv; ++d) {
    const DofRows& r = ws_.rows[static_cast<size_t>(d)];
    ws_.drive_force[d] = r.drive_impulse * inv_dt;
    if (ws_.actuated && ws_.actuators.implicit(d)) {  // the row was the actuator's
      ws_.actuator_force[d] = ws_.drive_force[d];
      ws_.drive_force[d] = 0.0;
    }
    ws_.limit_force[d] = (r.low_impulse + r.high_impulse) * inv_dt;
    ws_.friction_force[d] = (r.friction_impulse + r.transmission_friction_applied) * inv_dt;
    ws_.velocity_limit_force[d] = r.velocity_limit_impulse * inv_dt;
  }
  if (ws_.any_row_kinds || ws_.row_force_live) row_kind_forces(ws_.row_force, inv_dt);
  contact_forces();  // contact.cpp
}

// Each row kind's force, kind after kind (nv each): its accumulated impulse times inv_dt, 0 on a
// dof without the row.
void Stepper::row_kind_forces(VecX& out, double inv_dt) const {
  const int nv = model_->nv;
  RowKinds::for_each([&]<class E>(E, int, int slot) {
    for (int d = 0; d < nv; ++d) {
      const DofRows& r = ws_.rows[static_cast<size_t>(d)];
      out[E::index * nv + d] = (r.kinds >> E::index & 1u) != 0
                                   ? r.kind_slots[slot + E::Kind::kImpulse] * inv_dt
                                   : 0.0;
    }
  });
}

void Stepper::end_step() {
  check_finite_or_throw();
  commit_state();
  if (settings_.options.guard.enabled) commit_guard_account();
  time_ += settings_.options.dt;
  ++step_count_;
}

// Rows later in a sweep can push a dof already clamped by its velocity limit past it again. Like
// PhysX (computeLinkStates), the step starts by scaling every joint velocity by the one ratio that
// brings the worst offender back to its limit, which keeps the direction of motion.
void Stepper::scale_to_velocity_limits() {
  double ratio = 1.0;
  for (int d = 0; d < model_->nv; ++d)
    ratio = row_law::velocity_scale(ratio, ws_.qd[d], settings_.max_joint_velocity[d]);
  if (ratio < 1.0) ws_.qd *= ratio;
}

// Every dof's rows, set up once per step from the start-of-step configuration (eq. 20-24, 35-39).
// A dof whose only row is an undelayed drive needs its drive row alone: the other fields stay as
// the last full setup left them (the drive row writes no other accumulator).
void Stepper::setup_rows(double h, bool tgs) {
  const Model& model = *model_;
  const int nv = model.nv;
  int* const order = ws_.dof_order.data();
  if (ws_.row_kinds_changed) {
    int front = 0, back = nv;
    for (int d = 0; d < nv; ++d) {
      setup_dof_rows(d, h, tgs);
      // An implicit actuator's row is set up from the actuator, not from settings_.drives.
      const bool lone = ws_.rows[static_cast<size_t>(d)].drive_only &&
                        !ws_.drive_delays.delayed(d) && !ws_.actuators.implicit(d) &&
                        model.links[model.dof_link[d]].joint_type != JointType::spherical;
      order[lone ? front++ : --back] = d;
    }
    ws_.num_lone_drives = front;
    ws_.row_kinds_changed = false;
    ws_.any_row_kinds = false;
    for (const DofRows& rows : ws_.rows) ws_.any_row_kinds = ws_.any_row_kinds || rows.kinds != 0;
    ws_.row_force_live = true;
  } else {
    setup_lone_drives(h, tgs);
    for (int k = nv - 1; k >= ws_.num_lone_drives; --k) setup_dof_rows(order[k], h, tgs);
  }
  bool other_rows = false;  // rows on a dof that is not a lone drive
  ws_.any_undriven_rows = false;
  for (int k = ws_.num_lone_drives; k < nv; ++k) {
    const DofRows& rows = ws_.rows[static_cast<size_t>(order[k])];
    other_rows = other_rows || rows.active();
    ws_.any_undriven_rows = ws_.any_undriven_rows || (rows.active() && !rows.drive_only);
  }
  ws_.any_rows = ws_.num_lone_drives > 0 || other_rows;
  ws_.only_lone_drives_pgs = !other_rows && !tgs && !physx() && ws_.mimic.empty();
  ws_.delta_x.setZero();
  // mimic_solve.cpp: the rows' responses, with the limits' bias coefficient.
  if (!ws_.mimic.empty())
    ws_.mimic.setup(model, ws_.data, h,
                    limit_erp(settings_.options.solver, settings_.options.position_iterations));
  if (ws_.target_lead != 0.0) lead_drive_targets();  // a guard sub-step (step_guard.cpp)
}

// The lone drives' rows (row_setup::lone_drive: setup_dof_rows's fields that change from step to
// step), in one loop over raw pointers: Eigen's stores may alias anything, so the compiler would
// reload every vector's data pointer after each of them.
void Stepper::setup_lone_drives(double h, bool tgs) {
  const int* const dof_link = model_->dof_link.data();
  const Data::LinkInfo* const info = ws_.data.info.data();
  const double* const r_of = ws_.data.inverse_mass_diagonal.data();
  const double* const q = ws_.q.data();
  const double* const cfm = ws_.link_cfm.data();
  const double* const applied = ws_.applied_force.data();
  const Drive* const drives = settings_.drives.data();
  DofRows* const rows = ws_.rows.data();
  const int* const order = ws_.dof_order.data();
  const row_setup::Step step{h, ws_.dt, tgs};
  for (int k = 0; k < ws_.num_lone_drives; ++k) {
    const int d = order[k];
    const int i = dof_link[d];
    const Data::LinkInfo& link = info[i];
    const ScalarDof dof{rows[d], drives[d], cfm, i, link.parent, applied[d], settings_, d};
    row_setup::lone_drive(dof, r_of[d], q[link.q_index], step);
  }
}

// Dof d's rows, every field: which rows it has here, their fields by row_setup::constants and
// row_setup::setup.
void Stepper::setup_dof_rows(int d, double h, bool tgs) {
  const Model& model = *model_;
  const double dt = ws_.dt;
  auto drive_seen = [this](int dof) -> const Drive& {
    return ws_.drive_delays.delayed(dof) ? ws_.drive_delays.drive_seen(dof)
                                         : settings_.drives[static_cast<size_t>(dof)];
  };
  // A spherical joint's three drives, twist first: their targets make one rotation.
  auto axis_drives = [&](int dof) {
    const int first = model.links[model.dof_link[dof]].v_index;
    return std::array<const Drive*, 3>{&drive_seen(first), &drive_seen(first + 1),
                                       &drive_seen(first + 2)};
  };
  DofRows& rows = ws_.rows[static_cast<size_t>(d)];
  // Data's compact copy of the link: a Link spreads over a kilobyte.
  const int i = model.dof_link[d];
  const Data::LinkInfo& link = ws_.data.info[i];
  const bool spherical = link.type == JointType::spherical;
  if (link.type != JointType::revolute && link.type != JointType::prismatic && !spherical) {
    rows = DofRows{};
    ws_.sweep.has_rows[d] = 0;
    return;
  }
  const double r = ws_.data.inverse_mass_diagonal[d];
  // A spherical axis's position is PhysX's, from the quaternion (spherical_rows.cpp).
  const double x0 = spherical ? spherical_axis_position(model, ws_.q, d) : ws_.q[link.q_index];
  const Drive& drive = drive_seen(d);
  const bool driven = drive.type != DriveType::none;
  // A spherical drive's error is formed from the quaternion: x0 stands for target - error.
  const double x0_drive =
      spherical && driven
          ? drive.target_position - spherical_axis_drive_error(model, ws_.q, d, axis_drives(d))
          : x0;
  ScalarDof dof{rows, drive, ws_.link_cfm.data(), i, link.parent, ws_.applied_force[d],
                settings_, d};
  // An implicit actuator's law is the row of its (driveless) dof (implicit_actuators.md, I4-I7).
  rows.actuator = nullptr;
  if (ws_.actuators.implicit(d)) {
    const ExplicitActuator& actuator = ws_.actuators.actuator(d);
    dof.actuator = &actuator;
    dof.command = &ws_.actuators.command_seen(d);
    if (actuator_clip_depends_on_state(actuator)) rows.actuator = &actuator;
  }
  row_setup::constants<double>(dof, dt);
  row_setup::setup(dof, r, x0, x0_drive, {h, dt, tgs});
  rows.has_drive = driven || dof.actuator;
  setup_row_kinds(rows, d, {r, row_setup::response_with_cfm(dof, r), x0, h, dt, tgs});
  const ActuatorEnvelope& envelope = settings_.envelopes[static_cast<size_t>(d)];
  rows.has_envelope = driven && envelope.active();
  rows.envelope = envelope;
  const JointFriction& friction = settings_.friction[static_cast<size_t>(d)];
  rows.has_transmission_friction = settings_.friction_coefficient[d] > 0.0 &&
                                   friction.static_effort == 0.0 && friction.viscous == 0.0;
  rows.transmission_friction_bound = row_setup::transmission_friction_bound(
      settings_.friction_coefficient[d], h, ws_.transmitted_force[i]);
  rows.has_friction = friction.active();
  rows.has_limit =
      std::isfinite(settings_.lower_limit[d]) || std::isfinite(settings_.upper_limit[d]);
  rows.max_velocity = settings_.max_joint_velocity[d];
  rows.drive_only = rows.has_drive && !rows.has_envelope && !rows.actuator &&
                    !rows.has_transmission_friction &&
                    !rows.has_friction && !rows.has_limit && rows.kinds == 0 &&
                    !(rows.max_velocity < DofRows::kNoVelocityLimit);
  ws_.sweep.has_rows[d] = rows.active() ? 1 : 0;
}

// The row kinds dof d has (its settings leave the row on: K::active) and their rows (K::setup).
void Stepper::setup_row_kinds(DofRows& rows, int d, const RowInputs<double>& in) {
  rows.kinds = 0;
  RowKinds::for_each([&]<class E>(E, int field, int slot) {
    using K = typename E::Kind;
    const auto values = row_values<K>(settings_, d, field);
    if (!K::active(values)) return;
    rows.kinds |= 1u << E::index;
    double* row = rows.kind_slots.data() + slot;
    K::setup(row, values, in);
  });
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
void Stepper::sweep(RowPhase& phase) {
  // PhysX solves the mimic rows first in every iteration (solveInternalConstraints).
  if (!ws_.mimic.empty())
    ws_.mimic.solve(*model_, ws_.data, ws_.q, ws_.departures.row_bias.data(),
                    phase.velocity_iteration, ws_.qd);
  // Self-collision rows too, as PhysX's constraints outside the sweep (contact.md, C31).
  if (ws_.self_contacts_active)
    ws_.self_contacts.solve(*model_, ws_.data, contact_phase(phase), ws_.qd);
  if (!ws_.any_rows && !ws_.contacts_active) return;
  // Raw pointers and a copy of the phase: the compiler need not reload them after each store.
  DofRows* const rows = ws_.rows.data();
  const double* const row_bias = ws_.departures.row_bias.data();
  const double* const delta_x = ws_.delta_x.data();
  auto solve_row = [rows, row_bias, delta_x, phase](int dof, double v) mutable {
    phase.delta_x = delta_x[dof];
    return solve_dof_rows(rows[dof], v + row_bias[dof], phase);
  };
  if (ws_.contacts_active) {
    // Each link's contact rows right after its joint's rows (docs/math/contact.md, C15), at
    // the link's velocity of the sweep's start plus the sweep's change.
    contact_link_velocities();
    const ContactPhase contacts = contact_phase(phase);
    gauss_seidel_sweep(*model_, ws_.data, ws_.sweep, ws_.qd, solve_row, [&](int link, Vec6& dv) {
      return ws_.contact_rows.solve_link(link, ws_.contact_link_velocity[static_cast<size_t>(link)],
                                         dv, contacts);
    });
    return;
  }
  if (ws_.only_lone_drives_pgs) {  // the common case of drives alone, without the general row law
    gauss_seidel_sweep(*model_, ws_.data, ws_.sweep, ws_.qd,
                       [rows](int dof, double v) { return solve_lone_drive_pgs(rows[dof], v); });
    return;
  }
  gauss_seidel_sweep(*model_, ws_.data, ws_.sweep, ws_.qd, solve_row);
}

// PGS: the rows converge on the coupled implicit step; positions move with the velocity after the
// position iterations; velocity iterations continue the same update without new position error
// (spec "PGS Velocity Iteration").
void Stepper::solve_pgs() {
  const double dt = ws_.dt;
  setup_rows(dt, /*tgs=*/false);
  RowPhase phase;
  phase.dt = dt;
  phase.h = dt;
  phase.recip_h = 1.0 / dt;
  phase.limit_erp = limit_erp(SolverType::pgs, settings_.options.position_iterations);
  if (ws_.contacts_active || ws_.self_contacts_active) setup_contacts(phase);
  const int last = settings_.options.position_iterations - 1;
  for (int it = 0; it < last; ++it) sweep(phase);
  if (ws_.track_convergence)  // the impulses before the last iteration, then its change
    for (int d = 0; d < model_->nv; ++d)
      ws_.last_drive_change[d] = ws_.rows[static_cast<size_t>(d)].drive_impulse;
  sweep(phase);
  if (ws_.track_convergence)
    for (int d = 0; d < model_->nv; ++d)
      ws_.last_drive_change[d] =
          ws_.rows[static_cast<size_t>(d)].drive_impulse - ws_.last_drive_change[d];
  ws_.departures.qd_position = ws_.qd;
  integrate_positions(dt);
  phase.velocity_iteration = true;
  // A guard sub-step runs none: at every sub-step they fed energy into long chains; but with the
  // ground on, whose push-out they take back (docs/math/step_guard.md, "The sub-step law").
  const int velocity_iterations =
      ws_.dt == settings_.options.dt || ws_.contacts_active ? settings_.options.velocity_iterations
                                                            : 0;
  for (int it = 0; it < velocity_iterations; ++it) sweep(phase);
  if (physx())  // prismatic_limits.cpp
    clamp_prismatic_positions(*model_, settings_.lower_limit, settings_.upper_limit, ws_.q);
}

// TGS: each position iteration is a sub-step of rho = dt / n with a fresh drive impulse, the
// target interpolated (eq. 41) and the position change tracked (eq. 42-45); the inertia stays that
// of the step's start. Drive impulses are frozen in the velocity iterations (spec "TGS Velocity
// Iteration"); friction, limits and velocity limits keep acting there.
void Stepper::solve_tgs() {
  const double dt = ws_.dt;
  const int n = settings_.options.position_iterations;
  const double rho = dt / n;
  setup_rows(rho, /*tgs=*/true);
  if (ws_.track_convergence) ws_.last_drive_change.setZero();  // no iteration to converge
  RowPhase phase;
  phase.dt = dt;
  phase.h = rho;
  phase.recip_h = 1.0 / rho;
  phase.tgs = true;
  phase.limit_erp = limit_erp(SolverType::tgs, n);
  if (ws_.contacts_active || ws_.self_contacts_active) setup_contacts(phase);
  ws_.departures.qd_position.setZero();
  for (int i = 1; i <= n; ++i) {
    phase.time_to_step_end = dt - i * rho;
    sweep(phase);
    integrate_positions(rho);
    // PhysX clamps a limited prismatic joint's position in every sub-step (propagateTransform,
    // from recordDeltaMotion), so the next sub-step's rows and the velocity iterations measure
    // the position change from the clamped pose (prismatic_limits.cpp).
    if (physx())
      clamp_prismatic_positions(*model_, settings_.lower_limit, settings_.upper_limit, ws_.q);
    ws_.delta_x += rho * ws_.qd;
    if (physx()) {
      // A spherical row's position change carries its link bias (spherical_joints.md, eq. S-8);
      // a prismatic row's is measured again below.
      ws_.delta_x += rho * ws_.departures.row_bias;
      // PhysX measures a prismatic row's position change geometrically (NOTES, departure 1);
      // the sub-step's poses and turns it leaves are the contacts' too (contact.md, C25a).
      track_prismatic_position_change(*model_, ws_.data, ws_.q, ws_.qd, rho, ws_.departures,
                                      ws_.delta_x);
      ws_.departures.qd_position += (1.0 / n) * ws_.qd;
    }
    if (ws_.contacts_active || ws_.self_contacts_active) track_contacts(rho);
  }
  phase.velocity_iteration = true;
  // Drives alone apply nothing there: the sweep would leave every velocity as it is.
  if (!ws_.any_undriven_rows && ws_.mimic.empty() && !ws_.contacts_active &&
      !ws_.self_contacts_active)
    return;
  for (int it = 0; it < settings_.options.velocity_iterations; ++it) sweep(phase);
}

// compat none: a floating root's body-frame velocity (omega_b, v_b) gains dt (omega_b x v_b)
// over the free update, which makes R0 v_b the classical velocity of its origin at the step's end
// (v_O + dt a_O) instead of the spatial one; the rows and the position update use that, and the
// step's end expresses it in the root's new axes (docs/math/contact.md, C26-C28).
void Stepper::begin_classical_root(const Vec6& root_qd0, double dt) {
  const Vec3 w = root_qd0.head<3>(), v = root_qd0.tail<3>();
  ws_.qd.segment<3>(3) += dt * w.cross(v);
  ws_.root_rotation0 = quaternion_rotation(&ws_.q[3]);
}

void Stepper::end_classical_root() {
  const Mat3 R1 = quaternion_rotation(&ws_.q[3]);
  double v[3];  // R1^T (R_q v), as the lanes' end_classical_root
  link_motion_law::in_world_axes(ws_.root_rotation0, &ws_.qd[3], v);
  link_motion_law::in_link_axes(R1, v, &ws_.qd[3]);
}

// q advanced over h. compat physx moves a floating root about its COM with the world velocity of
// the step's start frame, as PhysX keeps it (updateRootBody, recordDeltaMotion).
void Stepper::integrate_positions(double h) {
  // compat physx turns a spherical joint's link in the world as PhysX does (spherical_rows.cpp):
  // the rotations before the sub-step.
  const bool spherical = physx() && has_spherical_joints(*model_);
  if (spherical) world_pose(*model_, ws_.data, ws_.q, ws_.departures.now);
  if (!model_->floating_base()) {
    integrate_configuration(*model_, ws_.q, ws_.qd, h, ws_.q);
  } else if (!physx()) {
    // The root's origin moves with its world velocity in the step's start axes (R0 v_b), the
    // velocity the rows solved for (docs/math/contact.md, C27).
    const Vec3 p = ws_.q.head<3>();
    integrate_configuration(*model_, ws_.q, ws_.qd, h, ws_.q);
    ws_.q.head<3>() = p + h * (ws_.root_rotation0 * ws_.qd.segment<3>(3));
  } else {
    const int iq = model_->links[0].q_index;
    const Eigen::Matrix<double, 7, 1> root = ws_.q.segment<7>(iq);
    integrate_configuration(*model_, ws_.q, ws_.qd, h, ws_.q);
    ws_.q.segment<7>(iq) = root;
    integrate_root_about_com(*model_, ws_.qd, h, ws_.departures, ws_.q);
  }
  if (spherical)
    integrate_spherical_joints(*model_, ws_.data, ws_.qd, &ws_.departures.bias_w, h,
                               ws_.departures, ws_.q);
}

// Called by step() first: the efforts on the state the step starts from, added to the applied
// force for the whole step (eq. 10 of docs/math/explicit_actuators.md).
const VecX& Stepper::apply_actuators() {
  ws_.actuator_force_start = ws_.actuator_force;
  ws_.actuated_start = ws_.actuated;
  if (!ws_.actuators.any()) {
    if (ws_.actuated) ws_.actuator_force.setZero();
    ws_.actuated = false;
    return ws_.applied_force;
  }
  ws_.actuators.compute(*model_, ws_.q, ws_.qd, settings_.drives, ws_.actuator_force);
  ws_.joint_force = ws_.applied_force + ws_.actuator_force;
  ws_.actuated = true;
  return ws_.joint_force;
}

// What apply_actuators() and the drive delays' push changed, taken back when the step diverges
// (the state itself is only committed by a whole step).
void Stepper::undo_actuators() {
  if (ws_.actuators.any()) ws_.actuators.undo_push();
  if (ws_.drive_delays.any()) ws_.drive_delays.undo_push();
  ws_.actuator_force = ws_.actuator_force_start;
  ws_.actuated = ws_.actuated_start;
}

// The step's working copies of the state it starts from (the step writes every force); the
// storage keeps it until the step is committed, so a step that diverges leaves it as it was.
void Stepper::load_state() {
  ws_.q = state_[StateStorage::q];
  ws_.qd = state_[StateStorage::qd];
  ws_.applied_force = state_[StateStorage::applied_force];
}

void Stepper::commit_state() {
  state_[StateStorage::q] = ws_.q;
  state_[StateStorage::qd] = ws_.qd;
  state_[StateStorage::drive_force] = ws_.drive_force;
  state_[StateStorage::limit_force] = ws_.limit_force;
  state_[StateStorage::friction_force] = ws_.friction_force;
  state_[StateStorage::velocity_limit_force] = ws_.velocity_limit_force;
  if (ws_.any_row_kinds || ws_.row_force_live) {
    state_[StateStorage::row_force] = ws_.row_force;
    ws_.row_force_live = ws_.any_row_kinds;
  }
}

void Stepper::check_finite_or_throw() {
  const Model& model = *model_;
  // A diverged step reports no contacts (its forces may be the culprit).
  auto diverged = [&](const std::string& what, double value) {
    const long step = step_count_ + 1;
    const double t = time_;
    undo_actuators();
    ws_.num_contacts = 0;
    std::fill(ws_.link_contact_force.begin(), ws_.link_contact_force.end(), Vec3::Zero());
    std::ostringstream s;
    s.precision(6);
    // A NaN's sign is the operation order's (the lanes' may differ): "nan" whatever it is.
    s << "simulation diverged at step " << step << " (t = " << t << " s): " << what << " = ";
    if (std::isnan(value)) s << "nan";
    else s << value;
    s << "; the state is left as it was before this step (lower dt or the gains)";
    throw DivergenceError(s.str());
  };
  auto fail = [&](const char* quantity, int dof, double value) {
    diverged("joint '" + model.links[model.dof_link[dof]].joint_name + "' " + quantity, value);
  };
  // x * 0 is 0 for a finite x and NaN otherwise, so one sum tells whether all are finite; the
  // search for the culprit runs only when one is not. The contact forces too: impulse / dt can
  // overflow where the state stays finite (found by fuzzing: dt = 1e-100).
  double zero = (ws_.qd.array() * 0.0).sum() + (ws_.drive_force.array() * 0.0).sum() +
                (ws_.limit_force.array() * 0.0).sum() + (ws_.friction_force.array() * 0.0).sum() +
                (ws_.velocity_limit_force.array() * 0.0).sum() + (ws_.q.array() * 0.0).sum();
  if (ws_.any_row_kinds) zero += (ws_.row_force.array() * 0.0).sum();
  if (ws_.contacts_active)
    for (const Vec3& f : ws_.link_contact_force) zero += (f.array() * 0.0).sum();
  if (zero == 0.0 && std::isfinite(time_ + settings_.options.dt)) return;
  // Velocities and forces first: a non-finite velocity also makes the position non-finite, and
  // the velocity is the nearer cause.
  for (int d = 0; d < model.nv; ++d) {
    if (!std::isfinite(ws_.qd[d])) fail("velocity qd", d, ws_.qd[d]);
    if (!std::isfinite(ws_.drive_force[d])) fail("drive force", d, ws_.drive_force[d]);
    if (!std::isfinite(ws_.limit_force[d])) fail("limit force", d, ws_.limit_force[d]);
    if (!std::isfinite(ws_.friction_force[d])) fail("friction force", d, ws_.friction_force[d]);
    if (!std::isfinite(ws_.velocity_limit_force[d]))
      fail("velocity limit force", d, ws_.velocity_limit_force[d]);
    for (const RowKindInfo& kind : row_kinds())
      if (const double f = ws_.row_force[kind.index * model.nv + d]; !std::isfinite(f))
        fail((std::string(kind.name) + " force").c_str(), d, f);
  }
  for (const Link& link : model.links)
    for (int k = 0; k < link.nq; ++k)
      if (!std::isfinite(ws_.q[link.q_index + k])) {
        if (link.nv > 0)
          fail("position q", link.v_index + std::min(k, link.nv - 1), ws_.q[link.q_index + k]);
      }
  for (size_t l = 0; l < ws_.link_contact_force.size(); ++l)
    for (int k = 0; k < 3; ++k)
      if (!std::isfinite(ws_.link_contact_force[l][k]))
        diverged("link '" + model.links[l].name + "' contact force f" + "xyz"[k],
                 ws_.link_contact_force[l][k]);
  // The clock itself (found by fuzzing: dt = 1e308 twice made the time +inf without an error).
  if (!std::isfinite(time_ + settings_.options.dt)) {
    undo_actuators();
    std::ostringstream s;
    s.precision(6);
    s << "simulation diverged at step " << step_count_ + 1 << " (t = " << time_
      << " s): time t + dt = " << time_ + settings_.options.dt
      << " is not finite; the state is left as it was before this step (lower dt)";
    throw DivergenceError(s.str());
  }
}

}  // namespace featherdrive
