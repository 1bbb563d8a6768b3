#include "featherdrive/sim/simulation.hpp"

#include "featherdrive/core/format.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <sstream>

#include "featherdrive/algorithm/joint_motion.hpp"
#include "featherdrive/model/model_variant.hpp"
#include "featherdrive/sim/state.hpp"

namespace featherdrive {
namespace {

std::string fmt(double v) { return format_double(v); }

// The ground's normal made unit length, leaving one that already is (within rounding) as it is:
// normalising is not idempotent in floating point (a normalised vector normalised again can move
// by an ulp), and a checkpoint's normal, normalised when it was set, must restore bit for bit.
Vec3 unit_normal(const Vec3& n) {
  constexpr double kTolerance = 8 * std::numeric_limits<double>::epsilon();
  return std::abs(n.squaredNorm() - 1.0) <= kTolerance ? n : Vec3(n.normalized());
}

}  // namespace

StateStorage::StateStorage(Eigen::Index nq, Eigen::Index nv) : own_(VecX::Zero(nq + 6 * nv)) {
  Eigen::Index offset = 0;  // no arithmetic on the null data() of an empty block
  for (int f = 0; f < kFields; ++f) {
    size_[f] = f == q ? nq : nv;
    data_[f] = size_[f] > 0 ? own_.data() + offset : nullptr;
    offset += size_[f];
  }
}

StateStorage::StateStorage(const StateStorage& other)
    : StateStorage(other.size_[q], other.size_[qd]) {
  for (int f = 0; f < kFields; ++f) (*this)[Field(f)] = other[Field(f)];
}

StateStorage& StateStorage::operator=(const StateStorage& other) {
  if (this == &other) return *this;
  if (size_ != other.size_) {
    if (lent_)
      throw std::invalid_argument("Simulation: cannot assign a simulation of nq = " +
                                  std::to_string(other.size_[q]) + ", nv = " +
                                  std::to_string(other.size_[qd]) +
                                  " to a batch environment of nq = " +
                                  std::to_string(size_[q]) + ", nv = " + std::to_string(size_[qd]));
    StateStorage copy(other);  // its block moves here with the addresses copy.data_ holds
    own_ = std::move(copy.own_);
    data_ = copy.data_;
    size_ = copy.size_;
    return *this;
  }
  for (int f = 0; f < kFields; ++f) (*this)[Field(f)] = other[Field(f)];
  return *this;
}

void StateStorage::lend(const std::array<double*, kFields>& rows) {
  for (int f = 0; f < kFields; ++f) {
    Eigen::Map<VecX>(rows[f], size_[f]) = (*this)[Field(f)];
    data_[f] = rows[f];
  }
  own_.resize(0);
  lent_ = true;
}

Simulation::Simulation(std::shared_ptr<const Model> model, const SimulationOptions& options)
    : model_(model ? std::move(model) : throw std::invalid_argument("Simulation: model is null")),
      data_(*model_),
      sweep_(*model_),
      departures_(*model_) {
  validate_options(options);
  settings_ = Settings::defaults(*model_, options);
  const int nv = model_->nv;
  state_ = StateStorage(model_->nq, nv);
  state_[StateStorage::q] = model_->neutral_configuration();
  actuators_ = ExplicitActuators(nv);
  drive_delays_ = DriveDelays(nv);
  actuator_force_ = actuator_force_start_ = joint_force_ = VecX::Zero(nv);
  load_state();  // sizes the working copies, so that a step allocates nothing
  drive_force_ = limit_force_ = friction_force_ = velocity_limit_force_ = VecX::Zero(nv);
  rows_.assign(static_cast<size_t>(nv), DofRows{});
  dof_order_.assign(static_cast<size_t>(nv), 0);
  delta_x_ = VecX::Zero(nv);
  last_drive_change_ = VecX::Zero(nv);
  const size_t n = static_cast<size_t>(model_->num_links());
  link_force_.assign(n, Vec6::Zero());
  subtree_force_.assign(n, Vec6::Zero());
  transmitted_force_ = VecX::Zero(model_->num_links());
  link_cfm_ = VecX::Zero(model_->num_links());
  link_contact_force_.assign(n, Vec3::Zero());
  contact_rows_ = ContactRows(*model_);
  self_contacts_ = SelfContacts(*model_);
  contacts_.assign(static_cast<size_t>(contact_rows_.max_points() + self_contacts_.max_points()),
                   ContactReport{});
  contact_link_velocity_.assign(n, Vec6::Zero());
  contact_link_bias_.assign(n, Vec6::Zero());
  contact_link_motion_.assign(n, Vec6::Zero());
  contact_link_motion_step_.assign(n, Vec6::Zero());
  update_link_damping_active();
  dt_ = settings_.options.dt;
  if (settings_.options.guard.enabled) size_guard();
}

void Simulation::set_track_convergence(bool on) {
  track_convergence_ = on;
  last_drive_change_.setZero();
}

void Simulation::set_options(const SimulationOptions& options) {
  validate_options(options);
  if (options.compat != settings_.options.compat)
    throw std::invalid_argument(std::string("simulation options: compat = ") +
                                to_string(options.compat) + " differs from the simulation's " +
                                to_string(settings_.options.compat) +
                                ": compat is chosen at construction");
  settings_.options = options;
  if (settings_.options.guard.enabled && !guard_data_) size_guard();
}

void Simulation::set_settings(const Settings& settings) {
  settings.validate(*model_);
  set_options(settings.options);  // the compat check; options are values, nothing else changes
  // Everything that may throw or allocate is made before anything changes.
  MimicSolver mimic(*model_, settings.mimic_joints);
  Settings next = settings;
  next.ground.normal = unit_normal(next.ground.normal);
  for (int d = 0; d < model_->nv; ++d) {
    const auto k = static_cast<size_t>(d);
    if (!(settings.actuators[k] == settings_.actuators[k]))
      set_actuator_unchecked(d, settings.actuators[k]);
    if (settings.actuators[k].kind != ActuatorKind::none)
      actuators_.set_feedforward(d, settings.actuator_feedforward[d]);
    if (settings.drive_delay[k] != settings_.drive_delay[k]) set_delay(d, settings.drive_delay[k]);
  }
  // A moved ground invalidates the anchors kept on it.
  const bool ground_moved = !(settings_.ground.normal == next.ground.normal) ||
                            settings_.ground.height != next.ground.height;
  settings_ = std::move(next);
  mimic_ = std::move(mimic);
  row_kinds_changed_ = true;
  update_link_damping_active();
  if (ground_moved) contact_rows_.clear_anchors();
  update_contacts_active();
}

void Simulation::set_model(std::shared_ptr<const Model> model) {
  if (!model) throw std::invalid_argument("set_model: model is null");
  const std::string difference = topology_difference(*model_, *model);
  if (!difference.empty())
    throw std::invalid_argument("set_model: the model has another topology: " + difference);
  // The workspaces hold copies of inertial parameters (Data::constants, the total mass).
  data_ = Data(*model);
  row_kinds_changed_ = true;
  sweep_ = SweepWorkspace(*model);
  departures_ = PhysxDepartures(*model);
  model_ = std::move(model);
  contact_rows_ = ContactRows(*model_);  // the shapes may differ
  self_contacts_ = SelfContacts(*model_);
  contacts_.assign(static_cast<size_t>(contact_rows_.max_points() + self_contacts_.max_points()),
                   ContactReport{});
  update_contacts_active();
  if (guard_data_) size_guard();  // the guard's energies read the masses too
}

void Simulation::set_q(const VecX& q) {
  state_[StateStorage::q] = checked_configuration(*model_, q);
  contact_rows_.clear_anchors();  // moved by hand: the kept anchors no longer hold
}

void Simulation::set_clock(double time, long step_count) {
  check_clock(time, step_count);
  time_ = time;
  step_count_ = step_count;
}

State Simulation::state() const {
  State s;
  s.q = q();
  s.qd = qd();
  s.applied_force = applied_force();
  s.time = time_;
  s.step_count = step_count_;
  s.drive_force = drive_force();
  s.limit_force = limit_force();
  s.friction_force = friction_force();
  s.velocity_limit_force = velocity_limit_force();
  s.actuator_force = actuator_force_;
  const auto nv = static_cast<size_t>(model_->nv);
  s.actuator_history.resize(nv);
  s.drive_delay_history.resize(nv);
  for (int d = 0; d < model_->nv; ++d) {
    const auto k = static_cast<size_t>(d);
    if (actuators_.active(d)) s.actuator_history[k] = {actuators_.pushes(d), actuators_.ring(d)};
    if (drive_delays_.delayed(d))
      s.drive_delay_history[k] = {drive_delays_.pushes(d), drive_delays_.ring(d)};
  }
  s.friction_anchors = contact_rows_.anchors();
  return s;
}

void Simulation::set_state(const State& s) {
  const int nv = model_->nv;
  check_clock(s.time, s.step_count);
  check_state_vector(s.qd, nv, "qd");
  check_state_vector(s.applied_force, nv, "applied_force");
  check_state_vector(s.actuator_force, nv, "actuator_force");
  for (const size_t n : {s.actuator_history.size(), s.drive_delay_history.size()})
    if (n != static_cast<size_t>(nv))
      throw std::invalid_argument("state: " + std::to_string(n) + " delay histories, expected " +
                                  "one per dof (nv = " + std::to_string(nv) + ")");
  // The histories are restored into copies: nothing changes if one is refused.
  ExplicitActuators actuators = actuators_;
  DriveDelays delays = drive_delays_;
  for (int d = 0; d < nv; ++d) {
    const auto k = static_cast<size_t>(d);
    const DelayHistory<ActuatorCommand>& a = s.actuator_history[k];
    if (actuators.active(d)) actuators.restore_history(d, a.pushes, a.ring);
    else if (a.pushes != 0 || !a.ring.empty())
      throw std::invalid_argument("actuator history of dof " + std::to_string(d) +
                                  ": the dof has no actuator");
    const DelayHistory<DriveTarget>& t = s.drive_delay_history[k];
    if (delays.delayed(d)) delays.restore_history(d, t.pushes, t.ring);
    else if (t.pushes != 0 || !t.ring.empty())
      throw std::invalid_argument("drive delay history of dof " + std::to_string(d) +
                                  ": the dof has no drive delay");
  }
  if (!s.friction_anchors.empty()) contact_rows_.check_anchors(s.friction_anchors);
  // q exactly as given (no normalisation, unlike set_q): a checkpoint's, bit for bit.
  VecX exact = checked_configuration(*model_, s.q, /*unit=*/true);
  check_state_vector(s.drive_force, nv, "drive_force");
  check_state_vector(s.limit_force, nv, "limit_force");
  check_state_vector(s.friction_force, nv, "friction_force");
  check_state_vector(s.velocity_limit_force, nv, "velocity_limit_force");
  // Nothing below throws.
  state_[StateStorage::q] = exact;
  state_[StateStorage::drive_force] = s.drive_force;
  state_[StateStorage::limit_force] = s.limit_force;
  state_[StateStorage::friction_force] = s.friction_force;
  state_[StateStorage::velocity_limit_force] = s.velocity_limit_force;
  if (s.friction_anchors.empty()) contact_rows_.clear_anchors();
  else contact_rows_.set_anchors(s.friction_anchors);
  state_[StateStorage::qd] = s.qd;
  state_[StateStorage::applied_force] = s.applied_force;
  time_ = s.time;
  step_count_ = s.step_count;
  actuator_force_ = s.actuator_force;
  actuated_ = true;  // actuator_force_ may be nonzero
  actuators_ = std::move(actuators);
  drive_delays_ = std::move(delays);
}

void Simulation::set_qd(const VecX& qd) {
  check_state_vector(qd, model_->nv, "qd");
  state_[StateStorage::qd] = qd;
}

void Simulation::set_applied_force(const VecX& tau) {
  check_state_vector(tau, model_->nv, "applied_force");
  state_[StateStorage::applied_force] = tau;
}

void Simulation::set_drive(int dof, const Drive& drive) {
  check_dof(dof);
  check_drive(*model_, dof, drive, settings_.actuators[static_cast<size_t>(dof)].kind);
  // New targets or gains leave a lone drive one.
  Drive& kept = settings_.drives[static_cast<size_t>(dof)];
  if (drive.type != kept.type) row_kinds_changed_ = true;
  kept = drive;
  // No drive, no delay: what set_drive_delay refuses is not kept either (checkpoints restore it).
  if (drive.type == DriveType::none && drive_delays_.delayed(dof)) set_delay(dof, 0);
}

void Simulation::set_drive(const std::string& joint, const Drive& drive) {
  set_drive(driven_dof(joint), drive);
}

// Driven by the implicit drive or by an explicit actuator, which reads the drive's targets.
bool Simulation::accepts_targets(int dof) const {
  return settings_.drives[static_cast<size_t>(dof)].type != DriveType::none || has_actuator(dof);
}

void Simulation::check_targets_have_drives(const VecX& positions, const VecX& velocities) const {
  for (int d = 0; d < std::min(positions.size(), velocities.size()); ++d)
    if ((positions[d] != 0.0 || velocities[d] != 0.0) && !accepts_targets(d))
      throw std::invalid_argument(no_drive_message(*model_, d) +
                                  "; this vector sets its target to " + fmt(positions[d]) +
                                  ", velocity " + fmt(velocities[d]));
}

void Simulation::set_drive_target(int dof, double position, double velocity) {
  check_dof(dof);
  if (!accepts_targets(dof)) throw std::invalid_argument(no_drive_message(*model_, dof));
  Drive d = drive(dof);
  d.target_position = position;
  d.target_velocity = velocity;
  set_drive(dof, d);
}

void Simulation::set_drive_target(const std::string& joint, double position, double velocity) {
  set_drive_target(driven_dof(joint), position, velocity);
}

void Simulation::set_joint_limits(int dof, double lower, double upper) {
  check_joint_limits(*model_, dof, lower, upper);
  settings_.lower_limit[dof] = lower;
  settings_.upper_limit[dof] = upper;
  row_kinds_changed_ = true;
}
void Simulation::set_joint_limits(const std::string& joint, double lower, double upper) {
  set_joint_limits(driven_dof(joint), lower, upper);
}

void Simulation::set_joint_friction(int dof, const JointFriction& friction) {
  check_joint_friction(*model_, dof, friction);
  settings_.friction[static_cast<size_t>(dof)] = friction;
  row_kinds_changed_ = true;
}
void Simulation::set_joint_friction(const std::string& joint, const JointFriction& friction) {
  set_joint_friction(driven_dof(joint), friction);
}

void Simulation::set_max_joint_velocity(int dof, double max_velocity) {
  check_max_joint_velocity(*model_, dof, max_velocity);
  settings_.max_joint_velocity[dof] = max_velocity;
  row_kinds_changed_ = true;
}
void Simulation::set_max_joint_velocity(const std::string& joint, double max_velocity) {
  set_max_joint_velocity(driven_dof(joint), max_velocity);
}

void Simulation::set_friction_coefficient(int dof, double coefficient) {
  check_friction_coefficient(*model_, dof, coefficient);
  settings_.friction_coefficient[dof] = coefficient;
  row_kinds_changed_ = true;
}
void Simulation::set_friction_coefficient(const std::string& joint, double coefficient) {
  set_friction_coefficient(driven_dof(joint), coefficient);
}

void Simulation::set_revolute_wrap(int dof, RevoluteWrap wrap) {
  check_revolute_wrap(*model_, dof, wrap);
  settings_.revolute_wrap[static_cast<size_t>(dof)] = wrap;
}
void Simulation::set_revolute_wrap(const std::string& joint, RevoluteWrap wrap) {
  set_revolute_wrap(model_->links[model_->joint_link_index(joint)].v_index, wrap);
}
RevoluteWrap Simulation::revolute_wrap(int dof) const {
  return settings_.revolute_wrap[static_cast<size_t>(check_dof(dof))];
}

void Simulation::set_mimic_joints(const std::vector<MimicJoint>& mimic) {
  MimicSolver solver(*model_, mimic);  // validates
  settings_.mimic_joints = mimic;
  mimic_ = std::move(solver);
}

void Simulation::set_ground(const Ground& ground) {
  check_ground(ground);
  check_ground_supported(*model_, ground);
  settings_.ground = ground;
  settings_.ground.normal = unit_normal(settings_.ground.normal);
  contact_rows_.clear_anchors();
  update_contacts_active();
}

void Simulation::set_contact_options(const ContactOptions& options) {
  check_contact_options(options);
  settings_.contact = options;
  update_contacts_active();
}

void Simulation::update_link_damping_active() {
  link_damping_active_ = false;
  link_cfm_active_ = false;
  for (const LinkParameters& p : settings_.link_parameters) {
    link_damping_active_ = link_damping_active_ || p.linear_damping > 0.0 ||
                           p.angular_damping > 0.0 || std::isfinite(p.max_linear_velocity) ||
                           std::isfinite(p.max_angular_velocity);
    link_cfm_active_ = link_cfm_active_ || p.cfm_scale != 0.0;
  }
  if (!link_cfm_active_) link_cfm_.setZero();  // what link_cfm would write every step
}

void Simulation::set_link_parameters(int link, const LinkParameters& parameters) {
  check_link_parameters_of(*model_, link, parameters);
  settings_.link_parameters[static_cast<size_t>(link)] = parameters;
  update_link_damping_active();
}
void Simulation::set_link_parameters(const std::string& link, const LinkParameters& parameters) {
  set_link_parameters(model_->link_index(link), parameters);
}
const LinkParameters& Simulation::link_parameters(int link) const {
  if (link < 0 || link >= model_->num_links())
    throw std::invalid_argument("link index " + std::to_string(link) + " is out of range [0, " +
                                std::to_string(model_->num_links()) + ")");
  return settings_.link_parameters[static_cast<size_t>(link)];
}
const LinkParameters& Simulation::link_parameters(const std::string& link) const {
  return link_parameters(model_->link_index(link));
}

void Simulation::set_actuator_envelope(int dof, const ActuatorEnvelope& envelope) {
  check_actuator_envelope(*model_, dof, envelope);
  settings_.envelopes[static_cast<size_t>(dof)] = envelope;
  row_kinds_changed_ = true;
}
void Simulation::set_actuator_envelope(const std::string& joint, const ActuatorEnvelope& envelope) {
  set_actuator_envelope(driven_dof(joint), envelope);
}

void Simulation::set_actuator(int dof, const ExplicitActuator& actuator) {
  check_dof(dof);
  check_actuator(*model_, dof, actuator, settings_.drives[static_cast<size_t>(dof)]);
  set_actuator_unchecked(dof, actuator);
}

// actuators_ and the settings' copy, kept equal; the feed-forward of a cleared one is 0.
void Simulation::set_actuator_unchecked(int dof, const ExplicitActuator& actuator) {
  // An implicit actuator's dof is never a lone drive (setup_rows): its rows are set up again.
  if (actuators_.implicit(dof) ||
      (actuator.kind != ActuatorKind::none &&
       actuator.integration == ActuatorIntegration::implicit_law))
    row_kinds_changed_ = true;
  actuators_.set(dof, actuator);
  settings_.actuators[static_cast<size_t>(dof)] = actuator;
  settings_.actuator_feedforward[dof] = actuators_.feedforward(dof);
}

void Simulation::set_actuator(const std::string& joint, const ExplicitActuator& actuator) {
  set_actuator(driven_dof(joint), actuator);
}

void Simulation::set_actuator_feedforward(int dof, double effort) {
  check_dof(dof);
  check_actuator_feedforward(*model_, dof, effort,
                             settings_.actuators[static_cast<size_t>(dof)].kind);
  actuators_.set_feedforward(dof, effort);
  settings_.actuator_feedforward[dof] = effort;
}
void Simulation::set_actuator_feedforward(const std::string& joint, double effort) {
  set_actuator_feedforward(driven_dof(joint), effort);
}

void Simulation::check_drive_delay(int dof, int delay) const {
  check_dof(dof);
  featherdrive::check_drive_delay(*model_, dof, delay, settings_.drives[static_cast<size_t>(dof)],
                                  settings_.actuators[static_cast<size_t>(dof)].kind);
}

void Simulation::set_drive_delay(int dof, int delay) {
  check_drive_delay(dof, delay);
  set_delay(dof, delay);
}

// drive_delays_ and the settings' copy, kept equal.
void Simulation::set_delay(int dof, int delay) {
  drive_delays_.set(dof, delay);
  settings_.drive_delay[static_cast<size_t>(dof)] = delay;
  row_kinds_changed_ = true;
}
void Simulation::set_drive_delay(const std::string& joint, int delay) {
  set_drive_delay(driven_dof(joint), delay);
}

// Called by step() first: the efforts on the state the step starts from, added to the applied
// force for the whole step (eq. 10 of docs/math/explicit_actuators.md).
const VecX& Simulation::apply_actuators() {
  actuator_force_start_ = actuator_force_;
  actuated_start_ = actuated_;
  if (!actuators_.any()) {
    if (actuated_) actuator_force_.setZero();
    actuated_ = false;
    return applied_force_;
  }
  actuators_.compute(*model_, q_, qd_, settings_.drives, actuator_force_);
  joint_force_ = applied_force_ + actuator_force_;
  actuated_ = true;
  return joint_force_;
}

void Simulation::step(int count) {
  if (count < 0) throw std::invalid_argument("step count = " + std::to_string(count) + " must be >= 0");
  for (int i = 0; i < count; ++i) step();
}

// What apply_actuators() and the drive delays' push changed, taken back when the step diverges
// (the state itself is only committed by a whole step).
void Simulation::undo_actuators() {
  if (actuators_.any()) actuators_.undo_push();
  if (drive_delays_.any()) drive_delays_.undo_push();
  actuator_force_ = actuator_force_start_;
  actuated_ = actuated_start_;
}

// The step's working copies of the state it starts from (the step writes every force); the
// storage keeps it until the step is committed, so a step that diverges leaves it as it was.
void Simulation::load_state() {
  q_ = state_[StateStorage::q];
  qd_ = state_[StateStorage::qd];
  applied_force_ = state_[StateStorage::applied_force];
}

void Simulation::commit_state() {
  state_[StateStorage::q] = q_;
  state_[StateStorage::qd] = qd_;
  state_[StateStorage::drive_force] = drive_force_;
  state_[StateStorage::limit_force] = limit_force_;
  state_[StateStorage::friction_force] = friction_force_;
  state_[StateStorage::velocity_limit_force] = velocity_limit_force_;
}

void Simulation::check_finite_or_throw() {
  const Model& model = *model_;
  // A diverged step reports no contacts (its forces may be the culprit).
  auto diverged = [&](const std::string& what, double value) {
    const long step = step_count_ + 1;
    const double t = time_;
    undo_actuators();
    num_contacts_ = 0;
    std::fill(link_contact_force_.begin(), link_contact_force_.end(), Vec3::Zero());
    std::ostringstream s;
    s.precision(6);
    s << "simulation diverged at step " << step << " (t = " << t << " s): " << what << " = "
      << value << "; the state is left as it was before this step (lower dt or the gains)";
    throw DivergenceError(s.str());
  };
  auto fail = [&](const char* quantity, int dof, double value) {
    diverged("joint '" + model.links[model.dof_link[dof]].joint_name + "' " + quantity, value);
  };
  // x * 0 is 0 for a finite x and NaN otherwise, so one sum tells whether all are finite; the
  // search for the culprit runs only when one is not. The contact forces too: impulse / dt can
  // overflow where the state stays finite (found by fuzzing: dt = 1e-100).
  double zero = (qd_.array() * 0.0).sum() + (drive_force_.array() * 0.0).sum() +
                (limit_force_.array() * 0.0).sum() + (friction_force_.array() * 0.0).sum() +
                (velocity_limit_force_.array() * 0.0).sum() + (q_.array() * 0.0).sum();
  if (contacts_active_)
    for (const Vec3& f : link_contact_force_) zero += (f.array() * 0.0).sum();
  if (zero == 0.0 && std::isfinite(time_ + settings_.options.dt)) return;
  // Velocities and forces first: a non-finite velocity also makes the position non-finite, and
  // the velocity is the nearer cause.
  for (int d = 0; d < model.nv; ++d) {
    if (!std::isfinite(qd_[d])) fail("velocity qd", d, qd_[d]);
    if (!std::isfinite(drive_force_[d])) fail("drive force", d, drive_force_[d]);
    if (!std::isfinite(limit_force_[d])) fail("limit force", d, limit_force_[d]);
    if (!std::isfinite(friction_force_[d])) fail("friction force", d, friction_force_[d]);
    if (!std::isfinite(velocity_limit_force_[d]))
      fail("velocity limit force", d, velocity_limit_force_[d]);
  }
  for (const Link& link : model.links)
    for (int k = 0; k < link.nq; ++k)
      if (!std::isfinite(q_[link.q_index + k])) {
        if (link.nv > 0) fail("position q", link.v_index + std::min(k, link.nv - 1), q_[link.q_index + k]);
      }
  for (size_t l = 0; l < link_contact_force_.size(); ++l)
    for (int k = 0; k < 3; ++k)
      if (!std::isfinite(link_contact_force_[l][k]))
        diverged("link '" + model.links[l].name + "' contact force f" + "xyz"[k],
                 link_contact_force_[l][k]);
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
