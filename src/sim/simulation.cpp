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
#include "workspace.hpp"

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

// Driven by the implicit drive or by an explicit actuator, which reads the drive's targets.
bool accepts_targets(const Settings& settings, const Workspace& ws, int dof) {
  return settings.drives[static_cast<size_t>(dof)].type != DriveType::none ||
         ws.actuators.active(dof);
}

// The workspace's actuators and the settings' copy, kept equal; the feed-forward of a cleared
// one is 0.
void set_actuator_unchecked(Settings& settings, Workspace& ws, int dof,
                            const ExplicitActuator& actuator) {
  // An implicit actuator's dof is never a lone drive (setup_rows): its rows are set up again.
  if (ws.actuators.implicit(dof) ||
      (actuator.kind != ActuatorKind::none &&
       actuator.integration == ActuatorIntegration::implicit_law))
    ws.row_kinds_changed = true;
  ws.actuators.set(dof, actuator);
  settings.actuators[static_cast<size_t>(dof)] = actuator;
  settings.actuator_feedforward[dof] = ws.actuators.feedforward(dof);
}

// The workspace's drive delays and the settings' copy, kept equal.
void set_delay(Settings& settings, Workspace& ws, int dof, int delay) {
  ws.drive_delays.set(dof, delay);
  settings.drive_delay[static_cast<size_t>(dof)] = delay;
  ws.row_kinds_changed = true;
}

}  // namespace

StateStorage::StateStorage(Eigen::Index nq, Eigen::Index nv)
    : own_(VecX::Zero(nq + (6 + RowKinds::size) * nv)) {
  Eigen::Index offset = 0;  // no arithmetic on the null data() of an empty block
  for (int f = 0; f < kFields; ++f) {
    size_[f] = f == q ? nq : f == row_force ? RowKinds::size * nv : nv;
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
    : model_(model ? std::move(model) : throw std::invalid_argument("Simulation: model is null")) {
  validate_options(options);
  settings_ = Settings::defaults(*model_, options);
  state_ = StateStorage(model_->nq, model_->nv);
  state_[StateStorage::q] = model_->neutral_configuration();
  ws_ = DeepCopyPtr<Workspace>(std::make_unique<Workspace>(*model_, settings_));
  stepper().load_state();  // sizes the working copies, so that a step allocates nothing
}

Simulation::Simulation(std::shared_ptr<const Model> model, const Settings& settings)
    : Simulation(std::move(model), settings.options) {
  set_settings(settings);
}

Simulation::Simulation(const Simulation& other) = default;
Simulation::Simulation(Simulation&& other) noexcept = default;
Simulation& Simulation::operator=(const Simulation& other) = default;
Simulation& Simulation::operator=(Simulation&& other) = default;
Simulation::~Simulation() = default;

Stepper Simulation::stepper() {
  return Stepper(*model_, settings_, state_, time_, step_count_, *ws_);
}

void Simulation::step() { stepper().step(); }

void Simulation::set_track_convergence(bool on) {
  ws_->track_convergence = on;
  ws_->last_drive_change.setZero();
}

void Simulation::set_options(const SimulationOptions& options) {
  validate_options(options);
  if (options.compat != settings_.options.compat)
    throw std::invalid_argument(std::string("simulation options: compat = ") +
                                to_string(options.compat) + " differs from the simulation's " +
                                to_string(settings_.options.compat) +
                                ": compat is chosen at construction");
  settings_.options = options;
  if (settings_.options.guard.enabled && !ws_->guard_data) ws_->size_guard(*model_);
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
      set_actuator_unchecked(settings_, *ws_, d, settings.actuators[k]);
    if (settings.actuators[k].kind != ActuatorKind::none)
      ws_->actuators.set_feedforward(d, settings.actuator_feedforward[d]);
    if (settings.drive_delay[k] != settings_.drive_delay[k])
      set_delay(settings_, *ws_, d, settings.drive_delay[k]);
  }
  // A moved ground invalidates the anchors kept on it.
  const bool ground_moved = !(settings_.ground.normal == next.ground.normal) ||
                            settings_.ground.height != next.ground.height;
  settings_ = std::move(next);
  ws_->mimic = std::move(mimic);
  ws_->row_kinds_changed = true;
  ws_->update_link_damping_active(settings_);
  if (ground_moved) ws_->contact_rows.clear_anchors();
  ws_->update_contacts_active(*model_, settings_);
}

void Simulation::set_model(std::shared_ptr<const Model> model) {
  if (!model) throw std::invalid_argument("set_model: model is null");
  const std::string difference = topology_difference(*model_, *model);
  if (!difference.empty())
    throw std::invalid_argument("set_model: the model has another topology: " + difference);
  // The workspaces hold copies of inertial parameters (Data::constants, the total mass).
  ws_->data = Data(*model);
  ws_->row_kinds_changed = true;
  ws_->sweep = SweepWorkspace(*model);
  ws_->departures = PhysxDepartures(*model);
  model_ = std::move(model);
  ws_->set_shapes(*model_);  // the shapes may differ
  ws_->update_contacts_active(*model_, settings_);
  if (ws_->guard_data) ws_->size_guard(*model_);  // the guard's energies read the masses too
}

void Simulation::set_q(const VecX& q) {
  state_[StateStorage::q] = checked_configuration(*model_, q);
  ws_->contact_rows.clear_anchors();  // moved by hand: the kept anchors no longer hold
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
  s.row_force = state_[StateStorage::row_force];
  s.actuator_force = ws_->actuator_force;
  const auto nv = static_cast<size_t>(model_->nv);
  s.actuator_history.resize(nv);
  s.drive_delay_history.resize(nv);
  for (int d = 0; d < model_->nv; ++d) {
    const auto k = static_cast<size_t>(d);
    if (ws_->actuators.active(d))
      s.actuator_history[k] = {ws_->actuators.pushes(d), ws_->actuators.ring(d)};
    if (ws_->drive_delays.delayed(d))
      s.drive_delay_history[k] = {ws_->drive_delays.pushes(d), ws_->drive_delays.ring(d)};
  }
  s.friction_anchors = ws_->contact_rows.anchors();
  s.guard_account = ws_->guard_account;
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
  ExplicitActuators actuators = ws_->actuators;
  DriveDelays delays = ws_->drive_delays;
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
  if (!s.friction_anchors.empty()) ws_->contact_rows.check_anchors(s.friction_anchors);
  // q exactly as given (no normalisation, unlike set_q): a checkpoint's, bit for bit.
  VecX exact = checked_configuration(*model_, s.q, /*unit=*/true);
  check_state_vector(s.drive_force, nv, "drive_force");
  check_state_vector(s.limit_force, nv, "limit_force");
  check_state_vector(s.friction_force, nv, "friction_force");
  check_state_vector(s.velocity_limit_force, nv, "velocity_limit_force");
  check_state_vector(s.row_force, RowKinds::size * nv, "row_force");
  check_guard_account(s.guard_account);
  // Nothing below throws.
  state_[StateStorage::q] = exact;
  state_[StateStorage::drive_force] = s.drive_force;
  state_[StateStorage::limit_force] = s.limit_force;
  state_[StateStorage::friction_force] = s.friction_force;
  state_[StateStorage::velocity_limit_force] = s.velocity_limit_force;
  state_[StateStorage::row_force] = s.row_force;
  ws_->row_force_live = true;
  if (s.friction_anchors.empty()) ws_->contact_rows.clear_anchors();
  else ws_->contact_rows.set_anchors(s.friction_anchors);
  state_[StateStorage::qd] = s.qd;
  state_[StateStorage::applied_force] = s.applied_force;
  time_ = s.time;
  step_count_ = s.step_count;
  ws_->actuator_force = s.actuator_force;
  ws_->actuated = true;  // the actuator force may be nonzero
  ws_->actuators = std::move(actuators);
  ws_->drive_delays = std::move(delays);
  ws_->guard_account = s.guard_account;
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
  check_dof_index(*model_, dof);
  check_drive(*model_, dof, drive, settings_.actuators[static_cast<size_t>(dof)].kind);
  // New targets or gains leave a lone drive one.
  Drive& kept = settings_.drives[static_cast<size_t>(dof)];
  if (drive.type != kept.type) ws_->row_kinds_changed = true;
  kept = drive;
  // No drive, no delay: what set_drive_delay refuses is not kept either (checkpoints restore it).
  if (drive.type == DriveType::none && ws_->drive_delays.delayed(dof))
    set_delay(settings_, *ws_, dof, 0);
}

void Simulation::set_drive(const std::string& joint, const Drive& drive) {
  set_drive(setting_dof(*model_, joint), drive);
}

void Simulation::check_targets_have_drives(const VecX& positions, const VecX& velocities) const {
  for (int d = 0; d < std::min(positions.size(), velocities.size()); ++d)
    if ((positions[d] != 0.0 || velocities[d] != 0.0) && !accepts_targets(settings_, *ws_, d))
      throw std::invalid_argument(no_drive_message(*model_, d) +
                                  "; this vector sets its target to " + fmt(positions[d]) +
                                  ", velocity " + fmt(velocities[d]));
}

void Simulation::set_drive_target(int dof, double position, double velocity) {
  check_dof_index(*model_, dof);
  if (!accepts_targets(settings_, *ws_, dof))
    throw std::invalid_argument(no_drive_message(*model_, dof));
  Drive d = drive(dof);
  d.target_position = position;
  d.target_velocity = velocity;
  set_drive(dof, d);
}

void Simulation::set_drive_target(const std::string& joint, double position, double velocity) {
  set_drive_target(setting_dof(*model_, joint), position, velocity);
}

void Simulation::set_joint_limits(int dof, double lower, double upper) {
  check_joint_limits(*model_, dof, lower, upper);
  settings_.lower_limit[dof] = lower;
  settings_.upper_limit[dof] = upper;
  ws_->row_kinds_changed = true;
}
void Simulation::set_joint_limits(const std::string& joint, double lower, double upper) {
  set_joint_limits(setting_dof(*model_, joint), lower, upper);
}

void Simulation::set_joint_friction(int dof, const JointFriction& friction) {
  check_joint_friction(*model_, dof, friction);
  settings_.friction[static_cast<size_t>(dof)] = friction;
  ws_->row_kinds_changed = true;
}
void Simulation::set_joint_friction(const std::string& joint, const JointFriction& friction) {
  set_joint_friction(setting_dof(*model_, joint), friction);
}

void Simulation::set_max_joint_velocity(int dof, double max_velocity) {
  check_max_joint_velocity(*model_, dof, max_velocity);
  settings_.max_joint_velocity[dof] = max_velocity;
  ws_->row_kinds_changed = true;
}
void Simulation::set_max_joint_velocity(const std::string& joint, double max_velocity) {
  set_max_joint_velocity(setting_dof(*model_, joint), max_velocity);
}

void Simulation::set_row_parameters(std::string_view kind, int dof,
                                    std::span<const double> values) {
  const RowKindInfo& k = row_kind(kind);
  check_row_parameters(*model_, dof, k, values);
  for (size_t j = 0; j < values.size(); ++j)
    settings_.row_parameters(dof, k.offset + static_cast<Eigen::Index>(j)) = values[j];
  ws_->row_kinds_changed = true;
}
void Simulation::set_row_parameters(std::string_view kind, const std::string& joint,
                                    std::span<const double> values) {
  set_row_parameters(kind, setting_dof(*model_, joint), values);
}
std::vector<double> Simulation::row_parameters(std::string_view kind, int dof) const {
  const RowKindInfo& k = row_kind(kind);
  check_dof_index(*model_, dof);
  std::vector<double> values(k.fields.size());
  for (size_t j = 0; j < values.size(); ++j)
    values[j] = settings_.row_parameters(dof, k.offset + static_cast<Eigen::Index>(j));
  return values;
}
VecView Simulation::row_force(std::string_view kind) const {
  const int nv = model_->nv;
  return {state_[StateStorage::row_force].data() + row_kind(kind).index * nv, nv};
}

void Simulation::set_friction_coefficient(int dof, double coefficient) {
  check_friction_coefficient(*model_, dof, coefficient);
  settings_.friction_coefficient[dof] = coefficient;
  ws_->row_kinds_changed = true;
}
void Simulation::set_friction_coefficient(const std::string& joint, double coefficient) {
  set_friction_coefficient(setting_dof(*model_, joint), coefficient);
}

void Simulation::set_revolute_wrap(int dof, RevoluteWrap wrap) {
  check_revolute_wrap(*model_, dof, wrap);
  settings_.revolute_wrap[static_cast<size_t>(dof)] = wrap;
}
void Simulation::set_revolute_wrap(const std::string& joint, RevoluteWrap wrap) {
  set_revolute_wrap(model_->links[model_->joint_link_index(joint)].v_index, wrap);
}
RevoluteWrap Simulation::revolute_wrap(int dof) const {
  return settings_.revolute_wrap[static_cast<size_t>(check_dof_index(*model_, dof))];
}

void Simulation::set_mimic_joints(const std::vector<MimicJoint>& mimic) {
  MimicSolver solver(*model_, mimic);  // validates
  settings_.mimic_joints = mimic;
  ws_->mimic = std::move(solver);
}

void Simulation::set_ground(const Ground& ground) {
  check_ground(ground);
  check_ground_supported(*model_, ground);
  settings_.ground = ground;
  settings_.ground.normal = unit_normal(settings_.ground.normal);
  ws_->contact_rows.clear_anchors();
  ws_->update_contacts_active(*model_, settings_);
}

void Simulation::set_contact_options(const ContactOptions& options) {
  check_contact_options(options);
  settings_.contact = options;
  ws_->update_contacts_active(*model_, settings_);
}

void Simulation::set_link_parameters(int link, const LinkParameters& parameters) {
  check_link_parameters_of(*model_, link, parameters);
  settings_.link_parameters[static_cast<size_t>(link)] = parameters;
  ws_->update_link_damping_active(settings_);
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
  ws_->row_kinds_changed = true;
}
void Simulation::set_actuator_envelope(const std::string& joint, const ActuatorEnvelope& envelope) {
  set_actuator_envelope(setting_dof(*model_, joint), envelope);
}

void Simulation::set_actuator(int dof, const ExplicitActuator& actuator) {
  check_dof_index(*model_, dof);
  check_actuator(*model_, dof, actuator, settings_.drives[static_cast<size_t>(dof)]);
  set_actuator_unchecked(settings_, *ws_, dof, actuator);
}

void Simulation::set_actuator(const std::string& joint, const ExplicitActuator& actuator) {
  set_actuator(setting_dof(*model_, joint), actuator);
}

void Simulation::set_actuator_feedforward(int dof, double effort) {
  check_dof_index(*model_, dof);
  check_actuator_feedforward(*model_, dof, effort,
                             settings_.actuators[static_cast<size_t>(dof)].kind);
  ws_->actuators.set_feedforward(dof, effort);
  settings_.actuator_feedforward[dof] = effort;
}
void Simulation::set_actuator_feedforward(const std::string& joint, double effort) {
  set_actuator_feedforward(setting_dof(*model_, joint), effort);
}

void Simulation::check_drive_delay(int dof, int delay) const {
  check_dof_index(*model_, dof);
  featherdrive::check_drive_delay(*model_, dof, delay, settings_.drives[static_cast<size_t>(dof)],
                                  settings_.actuators[static_cast<size_t>(dof)].kind);
}

void Simulation::set_drive_delay(int dof, int delay) {
  check_drive_delay(dof, delay);
  set_delay(settings_, *ws_, dof, delay);
}

void Simulation::set_drive_delay(const std::string& joint, int delay) {
  set_drive_delay(setting_dof(*model_, joint), delay);
}

// The workspace's parts the accessors show.
const ExplicitActuator& Simulation::actuator(int dof) const {
  return ws_->actuators.actuator(check_dof_index(*model_, dof));
}
bool Simulation::has_actuator(int dof) const {
  return ws_->actuators.active(check_dof_index(*model_, dof));
}
void Simulation::reset_actuator_history() { ws_->actuators.reset_history(); }
const ExplicitActuators& Simulation::actuators() const { return ws_->actuators; }
const VecX& Simulation::actuator_force() const { return ws_->actuator_force; }
int Simulation::drive_delay(int dof) const {
  return ws_->drive_delays.delay(check_dof_index(*model_, dof));
}
void Simulation::reset_drive_delay_history() { ws_->drive_delays.reset_history(); }
const DriveDelays& Simulation::drive_delays() const { return ws_->drive_delays; }
std::span<const ContactReport> Simulation::contacts() const {
  return {ws_->contacts.data(), static_cast<size_t>(ws_->num_contacts)};
}
const std::vector<Vec3>& Simulation::link_contact_force() const {
  return ws_->link_contact_force;
}
bool Simulation::track_convergence() const { return ws_->track_convergence; }
const VecX& Simulation::last_drive_impulse_change() const { return ws_->last_drive_change; }
const Data& Simulation::data() const { return ws_->data; }
int Simulation::guard_substeps() const { return ws_->guard_substeps; }
long Simulation::guard_triggers() const { return ws_->guard_triggers; }
long Simulation::guard_exhausted() const { return ws_->guard_exhausted; }
const GuardAccount& Simulation::guard_account() const { return ws_->guard_account; }

void Simulation::step(int count) {
  if (count < 0) throw std::invalid_argument("step count = " + std::to_string(count) + " must be >= 0");
  for (int i = 0; i < count; ++i) step();
}

}  // namespace featherdrive
