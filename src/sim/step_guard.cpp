// The step guard (docs/math/step_guard.md): after the step's physics advance, test (i) how far
// each joint moved and (ii) whether the kinetic + gravity energy grew by more than the joint
// forces' work; on a failure redo the advance as n = 2, 4, ... sub-steps of dt / n from the
// step's start. Everything here runs on scratch sized by size_guard: a guarded step allocates
// nothing.
#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

#include "featherdrive/algorithm/energy.hpp"
#include "featherdrive/algorithm/kinematics.hpp"
#include "featherdrive/core/format.hpp"
#include "workspace.hpp"

namespace featherdrive {
namespace {

// Rounding of the energies themselves (sums over the links, a potential of any offset).
constexpr double kEnergyRounding = 1e-12;
// Test (iii), eq. (G-7)-(G-9): the account's memory per step (a time constant of 1000 steps) and
// the share of the remembered scale that may be created without dissipation paying for it.
constexpr double kAccountLeak = 0.999;
constexpr double kAccountSlack = 0.1;
// Eq. (G-11): a TGS drive's force changes between its sub-steps; F dq measured over the step
// then differs from the work by at most about 2 kp dq^2 (motion monotone within the step).
constexpr double kTgsSpringCredit = 2.0;

// The rotation angle from unit quaternion a to b, eq. (G-2): 4 atan2(|a - b|, |a + b|) with b's
// sign chosen nearer a (accurate at small and large angles alike; layout-free).
double rotation_angle(const double* a, const double* b) {
  const Eigen::Map<const Eigen::Vector4d> qa(a), qb(b);
  const double s = qa.dot(qb) < 0.0 ? -1.0 : 1.0;
  return 4.0 * std::atan2((qa - s * qb).norm(), (qa + s * qb).norm());
}

}  // namespace

void Workspace::size_guard(const Model& model) {
  guard_data.emplace(model);
  const Eigen::Index nq = model.nq, nv = model.nv;
  guard_q0 = VecX::Zero(nq);
  guard_qd0 = guard_force = guard_actuator = guard_qd1 = VecX::Zero(nv);
  guard_q1 = VecX::Zero(nq);
  for (VecX& v : guard_impulse) v = VecX::Zero(nv);
  guard_row_impulse = VecX::Zero(RowKinds::size * nv);
  guard_rows.assign(static_cast<size_t>(nv), GuardRow{});
  guard_anchors.assign(model.shapes.size(), FrictionAnchors{});
  guard_link_contact_force.assign(static_cast<size_t>(model.num_links()), Vec3::Zero());
  guard_link_velocity.assign(static_cast<size_t>(model.num_links()), Vec6::Zero());
  guard_e1_valid = false;
}

void Simulation::reset_guard_counters() {
  ws_->guard_substeps = 1;
  ws_->guard_triggers = 0;
  ws_->guard_exhausted = 0;
}

void Stepper::guard_energy(const VecX& q, const VecX& qd, double e[2]) {
  forward_kinematics(*model_, *ws_.guard_data, q, qd);
  e[0] = kinetic_energy(*model_, *ws_.guard_data, qd);
  e[1] = potential_energy(*model_, *ws_.guard_data);
}

bool Stepper::guard_passes(const VecX& tau, const double e0[2], double e1[2]) {
  const Model& model = *model_;
  const double h = ws_.dt;
  const double bound = settings_.options.guard.max_joint_step;
  bool moved_too_far = false;
  double work = 0.0;  // eq. (G-3): sum over dofs of the joint force's impulse times the motion
  double work_rounding = 0.0;  // sum |F| (|q| + |dq|): the positions' rounding carried into it
  double bracket = 0.0;  // eq. (G-10), the drives' work beyond their springs' and dampers'
  // Explicit actuators' efforts are evaluated at the start of the (sub-)step: their work is the
  // trapezoid of the efforts at its start and end (eq. G-3), which for a spring is the change of
  // its energy, so that an explicit law's overshoot shows as energy gained.
  const bool actuated = ws_.actuators.any();
  if (actuated) ws_.actuators.evaluate(*model_, ws_.q, ws_.qd, ws_.guard_force);
  auto impulse = [&](int d) {
    const GuardRow& r = ws_.guard_rows[static_cast<size_t>(d)];
    const double explicit_force =
        actuated ? tau[d] + 0.5 * (ws_.guard_force[d] - (tau[d] - ws_.applied_force[d])) : tau[d];
    double kinds = 0.0;
    for (const double k : r.kind_impulse) kinds += k;
    return explicit_force * h + r.drive_impulse + r.low_impulse + r.high_impulse +
           r.friction_impulse + r.transmission_friction_applied + r.velocity_limit_impulse +
           kinds;
  };
  for (const Link& link : model.links) {
    if (link.joint_type == JointType::revolute || link.joint_type == JointType::prismatic) {
      // A wrapped revolute joint's position jumps by 2 pi at the wrap: the move is modulo 2 pi.
      double dq = ws_.q[link.q_index] - ws_.guard_q0[link.q_index];
      if (settings_.revolute_wrap[static_cast<size_t>(link.v_index)] == RevoluteWrap::wrapped)
        dq = std::remainder(dq, 2.0 * std::numbers::pi);
      moved_too_far = moved_too_far || !(std::abs(dq) <= bound);
      const double force = impulse(link.v_index) / h;
      work += force * dq;
      bracket += drive_bracket(link.v_index, ws_.guard_q0[link.q_index], dq, h) +
                 row_kind_bracket(link.v_index, ws_.guard_q0[link.q_index], dq, h);
      work_rounding += std::abs(force) * (std::abs(ws_.q[link.q_index]) + std::abs(dq));
    } else if (link.joint_type == JointType::spherical || link.joint_type == JointType::floating) {
      // The rotation's angle (a floating base's translation is not bounded); the work over the
      // velocity coordinates, the motion h qd.
      const int iq = link.q_index + (link.joint_type == JointType::floating ? 3 : 0);
      moved_too_far =
          moved_too_far || !(rotation_angle(ws_.guard_q0.data() + iq, ws_.q.data() + iq) <= bound);
      for (int k = 0; k < link.nv; ++k)
        work += impulse(link.v_index + k) * ws_.qd[link.v_index + k];
    }
  }
  guard_energy(ws_.q, ws_.qd, e1);
  if (ws_.contacts_active) work += guard_contact_work();
  // eq. (G-4), (G-5); a NaN anywhere fails.
  const double excess = (e1[0] + e1[1]) - (e0[0] + e0[1]) - work;
  const double scale = e0[0] + e1[0] + std::abs(work) + std::abs(e1[1] - e0[1]);
  const double rounding =
      kEnergyRounding * (e0[0] + e1[0] + std::abs(e0[1]) + std::abs(e1[1]) + work_rounding);
  const double allowed = settings_.options.guard.energy_tolerance * scale + rounding;
  // Test (iii), eq. (G-7)-(G-9): the account over the run, a sub-step's memory fading by its
  // share of the step.
  const double leak = h == settings_.options.dt ? kAccountLeak : std::pow(kAccountLeak, h / settings_.options.dt);
  GuardAccount& next = ws_.guard_account_next;
  const double created = excess + bracket;
  next.created = leak * next.created + created;
  next.dissipated = leak * next.dissipated + h * damper_power();
  next.scale = leak * next.scale + scale;
  const double budget = settings_.options.guard.dissipation_share * next.dissipated +
                        kAccountSlack * (1.0 - kAccountLeak) * next.scale + allowed;
  // Over budget, a (sub-)step still passes if it pays back: it creates at most what the leak
  // forgives it (eq. G-9), so that the debt shrinks and old debts do not fail every sub-step.
  const bool account_ok = next.created <= budget || created <= (1.0 - leak) * budget;
  return !moved_too_far && excess <= allowed && account_ok;
}

// Eq. (G-3a): the ground rows' impulses times their points' end velocities, J . V with V each
// link's end velocity (guard_energy's kinematics) in frame 0 about the rows' origin, as a floating
// base's impulses are taken times its end velocity in (G-3).
double Stepper::guard_contact_work() {
  const Data& end = *ws_.guard_data;
  const Vec3& origin = ws_.data.frame_origin;  // the rows' (set up from the step's start)
  for (int i = 0; i < model_->num_links(); ++i) {
    const Mat3& R = end.world_rotation[i];
    const Vec3 w = R * end.velocity[i].head<3>();
    ws_.guard_link_velocity[static_cast<size_t>(i)] << w,
        R * end.velocity[i].tail<3>() + w.cross(origin - end.world_position[i]);
  }
  return ws_.contact_rows.work(ws_.guard_link_velocity);
}

// Eq. (G-10): a force or acceleration drive's work beyond what its spring released and its damper
// took, F dq + dU + kd (dq / h - v_T) dq; -kp dq^2 / 2 for a converged PGS row, positive where
// an unconverged row pushed harder than its spring. Not for rows another bound shaped (max force,
// an envelope) nor actuators' rows. TGS applies its force in sub-steps: credit (G-11).
double Stepper::drive_bracket(int d, double q0, double dq, double h) const {
  const GuardRow& r = ws_.guard_rows[static_cast<size_t>(d)];
  if (!r.has_drive || ws_.actuators.active(d) || r.has_envelope ||
      std::abs(r.drive_impulse) >= r.max_impulse)
    return 0.0;
  const Drive& drive = ws_.drive_delays.delayed(d) ? ws_.drive_delays.drive_seen(d)
                                                   : settings_.drives[static_cast<size_t>(d)];
  const double inv_m = drive.type == DriveType::acceleration ? 1.0 / r.response : 1.0;
  const double kp = drive.stiffness * inv_m, kd = drive.damping * inv_m;
  const double x = drive.target_position - drive.target_velocity * ws_.target_lead;
  const double q1 = q0 + dq;  // before a wrap: the branch the row's error was taken on
  const double credit = settings_.options.solver == SolverType::tgs ? kTgsSpringCredit * kp * dq * dq : 0.0;
  return r.drive_impulse / h * dq + 0.5 * kp * ((q1 - x) * (q1 - x) - (q0 - x) * (q0 - x)) +
         kd * (dq / h - drive.target_velocity) * dq - credit;
}

// Eq. (G-10) for the row kinds a dof has: each kind's own bracket (row_kind.hpp), at the
// settings the step read.
double Stepper::row_kind_bracket(int d, double q0, double dq, double h) const {
  const GuardRow& r = ws_.guard_rows[static_cast<size_t>(d)];
  const double credit = settings_.options.solver == SolverType::tgs ? kTgsSpringCredit : 0.0;
  double bracket = 0.0;
  RowKinds::for_each([&]<class E>(E, int field, int) {
    using K = typename E::Kind;
    const auto values = row_values<K>(settings_, d, field);
    if (K::active(values))
      bracket += K::guard_bracket(values, r.kind_impulse[E::index], q0, dq, h, credit);
  });
  return bracket;
}

// Eq. (G-7): the power the dampers take out at the end velocity, sum c_d v_d^2: a force drive's
// (or an actuator's) damping, an acceleration drive's times the dof's effective mass 1 / r,
// viscous friction. A drive at its force bound is not counted (its damper is not acting).
double Stepper::damper_power() const {
  double power = 0.0;
  for (int d = 0; d < model_->nv; ++d) {
    const GuardRow& r = ws_.guard_rows[static_cast<size_t>(d)];
    double c = settings_.friction[static_cast<size_t>(d)].viscous;
    if (ws_.actuators.active(d)) c += ws_.actuators.actuator(d).damping;
    if (r.has_drive && !ws_.actuators.implicit(d) &&
        !(std::abs(r.drive_impulse) >= r.max_impulse)) {
      const Drive& drive = settings_.drives[static_cast<size_t>(d)];
      c += drive.type == DriveType::acceleration ? drive.damping / r.response : drive.damping;
    }
    RowKinds::for_each([&]<class E>(E, int field, int) {
      using K = typename E::Kind;
      const auto values = row_values<K>(settings_, d, field);
      if (K::active(values)) c += K::damping_of(values);
    });
    power += c * ws_.qd[d] * ws_.qd[d];
  }
  return power;
}

// The step's start is in the storage (state_) until end_step commits; tau_step is begin_step's.
void Stepper::guarded_advance(const VecX& tau_step) {
  guard_start();
  advance(tau_step);
  guard_rows_from_step();
  if (guard_first_passes(tau_step)) {  // the unguarded step, bit for bit
    row_forces();
    return;
  }
  guard_redo();
}

// What the tests read of the advance's rows: copies, so the same bits as the rows themselves.
void Stepper::guard_rows_from_step() {
  for (int d = 0; d < model_->nv; ++d) {
    const DofRows& r = ws_.rows[static_cast<size_t>(d)];
    GuardRow& g = ws_.guard_rows[static_cast<size_t>(d)];
    g.drive_impulse = r.drive_impulse;
    g.low_impulse = r.low_impulse;
    g.high_impulse = r.high_impulse;
    g.friction_impulse = r.friction_impulse;
    g.transmission_friction_applied = r.transmission_friction_applied;
    g.velocity_limit_impulse = r.velocity_limit_impulse;
    g.response = r.response;
    g.max_impulse = r.drive.max_impulse;
    g.has_drive = r.has_drive;
    g.has_envelope = r.has_envelope;
    RowKinds::for_each([&]<class E>(E, int, int slot) {
      g.kind_impulse[E::index] = (r.kinds >> E::index & 1u) != 0
                                     ? r.kind_slots[slot + E::Kind::kImpulse]
                                     : 0.0;
    });
  }
}

// The loaded state is the step's start: kept for the tests, its energies taken.
void Stepper::guard_start() {
  ws_.guard_q0 = ws_.q;
  ws_.guard_qd0 = ws_.qd;
  // The start's energies are the last step's end's where nothing moved the state since (a
  // comparison instead of a forward kinematics pass).
  if (ws_.guard_e1_valid && ws_.q == ws_.guard_q1 && ws_.qd == ws_.guard_qd1) {
    ws_.guard_e0[0] = ws_.guard_e1[0];
    ws_.guard_e0[1] = ws_.guard_e1[1];
  } else {
    guard_energy(ws_.guard_q0, ws_.guard_qd0, ws_.guard_e0);
  }
  ws_.guard_e1_valid = false;  // valid again once this step has ended
  ws_.dt = settings_.options.dt;
  ws_.target_lead = 0.0;
}

// The whole step's advance, its end in q, qd and its rows in guard_rows, tested; kept on a pass.
bool Stepper::guard_first_passes(const VecX& tau) {
  ws_.guard_substeps = 1;
  ws_.guard_account_next = ws_.guard_account;
  double e1[2];
  if (!guard_passes(tau, ws_.guard_e0, e1)) return false;
  keep_guard_end(e1);
  return true;
}

// The step again from its start (loaded) as n = 2, 4, ... sub-steps (docs/math/step_guard.md,
// "The sub-step law").
void Stepper::guard_redo() {
  const double dt = settings_.options.dt;
  const int most = settings_.options.guard.max_substeps;
  double e0[2], e1[2];
  const double* e_start = ws_.guard_e0;
  ++ws_.guard_triggers;
  const bool contacts = ws_.contacts_active || ws_.self_contacts_active;
  if (ws_.contacts_active) ws_.guard_anchors = ws_.contact_rows.anchors();  // not yet concluded
  for (int n = 2;; n = std::min(2 * n, most)) {
    load_state();  // the step's start again
    for (VecX& v : ws_.guard_impulse) v.setZero();
    ws_.guard_row_impulse.setZero();
    ws_.guard_actuator.setZero();
    ws_.dt = dt / n;
    e0[0] = e_start[0];
    e0[1] = e_start[1];
    ws_.guard_account_next = ws_.guard_account;
    if (ws_.contacts_active) ws_.contact_rows.set_anchors(ws_.guard_anchors);
    std::fill(ws_.guard_link_contact_force.begin(), ws_.guard_link_contact_force.end(),
              Vec3::Zero());
    bool passed = true;
    // A failing sub-step ends this n, unless n is the last one there is: that one is kept.
    for (int i = 1; i <= n && (passed || n == most); ++i) {
      // Sub-step i's targets: x_T - v_T (n - i) dt / n, eq. (G-6).
      ws_.target_lead = (n - i) * ws_.dt;
      ws_.guard_q0 = ws_.q;
      ws_.guard_qd0 = ws_.qd;
      const VecX& tau = guard_substep_force();
      advance(tau);
      guard_rows_from_step();
      for (int d = 0; d < model_->nv; ++d) {
        const DofRows& r = ws_.rows[static_cast<size_t>(d)];
        ws_.guard_impulse[0][d] += r.drive_impulse;
        ws_.guard_impulse[1][d] += r.low_impulse + r.high_impulse;
        ws_.guard_impulse[2][d] += r.friction_impulse + r.transmission_friction_applied;
        ws_.guard_impulse[3][d] += r.velocity_limit_impulse;
      }
      row_kind_forces(ws_.row_force, 1.0);  // the sub-step's impulses
      ws_.guard_row_impulse += ws_.row_force;
      // A sub-step of dt / n as a step of its own: its impulses summed, its anchors the next's.
      if (contacts) {
        report_contacts();
        for (size_t l = 0; l < ws_.guard_link_contact_force.size(); ++l)
          ws_.guard_link_contact_force[l] += ws_.link_contact_force[l];
        if (ws_.contacts_active) ws_.contact_rows.conclude();
      }
      const bool ok = guard_passes(tau, e0, e1);
      passed = passed && ok;
      e0[0] = e1[0];
      e0[1] = e1[1];
    }
    if (passed || n == most) {
      ws_.guard_substeps = n;
      if (!passed) ++ws_.guard_exhausted;
      const double inv_dt = 1.0 / dt;  // the step's forces: its summed impulses / dt
      ws_.drive_force = ws_.guard_impulse[0] * inv_dt;
      ws_.limit_force = ws_.guard_impulse[1] * inv_dt;
      ws_.friction_force = ws_.guard_impulse[2] * inv_dt;
      ws_.velocity_limit_force = ws_.guard_impulse[3] * inv_dt;
      ws_.row_force = ws_.guard_row_impulse * inv_dt;
      if (ws_.actuators.any()) {
        ws_.actuator_force = ws_.guard_actuator / n;  // the explicit ones' mean effort
        for (int d = 0; d < model_->nv; ++d)
          if (ws_.actuators.implicit(d)) {  // the row was the actuator's
            ws_.actuator_force[d] = ws_.drive_force[d];
            ws_.drive_force[d] = 0.0;
          }
      }
      ws_.dt = dt;
      ws_.target_lead = 0.0;
      if (contacts) guard_contact_forces(n);
      keep_guard_end(e1);
      return;
    }
  }
}

// The last sub-step's points, their impulses times n (the step's rate: exact at rest); each link's
// force the step's summed impulses / dt. A redo that diverged keeps the step-start's anchors.
void Stepper::guard_contact_forces(int n) {
  for (int k = 0; k < ws_.num_contacts; ++k) {
    ContactReport& c = ws_.contacts[static_cast<size_t>(k)];
    c.normal_impulse *= n;
    c.friction_impulse *= n;
  }
  ws_.link_contact_force = ws_.guard_link_contact_force;
  try {
    check_finite_or_throw();
  } catch (const DivergenceError&) {
    if (ws_.contacts_active) ws_.contact_rows.set_anchors(ws_.guard_anchors);
    throw;
  }
}

// Test (iii)'s account after a committed step (eq. G-8). One that overflowed (gains near the
// largest double make inf - inf) starts again empty rather than failing every later step.
void Stepper::commit_guard_account() {
  const GuardAccount& a = ws_.guard_account_next;
  const bool finite = std::isfinite(a.created) && std::isfinite(a.dissipated) &&
                      std::isfinite(a.scale);
  ws_.guard_account = finite ? a : GuardAccount{};
}

// The end of a step that may be committed: end_step's finite check may still refuse it, and then
// the state is the start again, which the comparison tells apart.
void Stepper::keep_guard_end(const double e1[2]) {
  ws_.guard_q1 = ws_.q;
  ws_.guard_qd1 = ws_.qd;
  ws_.guard_e1[0] = e1[0];
  ws_.guard_e1[1] = e1[1];
  ws_.guard_e1_valid = true;
}

// Explicit actuators at a sub-step's start: the step's (delayed) commands, this state.
const VecX& Stepper::guard_substep_force() {
  if (!ws_.actuators.any()) return ws_.applied_force;
  ws_.actuators.evaluate(*model_, ws_.q, ws_.qd, ws_.guard_force);
  ws_.guard_actuator += ws_.guard_force;
  ws_.joint_force = ws_.applied_force + ws_.guard_force;
  return ws_.joint_force;
}

// A sub-step ending target_lead before the step's end drives towards x_T - v_T target_lead
// (eq. G-6): the row's constant term x (b + h kp (x_T - x0)) moves by -(x h kp) v_T lead, its
// bias_coefficient times -v_T lead (eq. 20, 23 of docs/math/implicit_drives.md).
void Stepper::lead_drive_targets() {
  for (int d = 0; d < model_->nv; ++d) {
    DofRows& rows = ws_.rows[static_cast<size_t>(d)];
    if (!rows.has_drive) continue;
    // An implicit actuator's row drives towards the command its delay line gives.
    const double target_velocity =
        ws_.actuators.implicit(d)     ? ws_.actuators.command_seen(d).velocity
        : ws_.drive_delays.delayed(d) ? ws_.drive_delays.drive_seen(d).target_velocity
                                      : settings_.drives[static_cast<size_t>(d)].target_velocity;
    rows.drive.target_vel_plus_initial_bias -=
        rows.drive.bias_coefficient * target_velocity * ws_.target_lead;
  }
}

}  // namespace featherdrive
