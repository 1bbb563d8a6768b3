#include "featherdrive/sim/simulation.hpp"

#include "featherdrive/core/format.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>

#include "featherdrive/algorithm/joint_motion.hpp"
#include "featherdrive/model/model_variant.hpp"

namespace featherdrive {
namespace {

std::string fmt(double v) { return format_double(v); }

// The joints whose dofs carry rows (drives, limits, friction, velocity limits): revolute,
// prismatic, and spherical per axis (twist, swing1, swing2; docs/math/spherical_joints.md).
bool has_axis_rows(JointType type) {
  return type == JointType::revolute || type == JointType::prismatic ||
         type == JointType::spherical;
}

void check_vector(const VecX& x, Eigen::Index expected, const char* what) {
  if (x.size() != expected)
    throw std::invalid_argument(std::string(what) + ": expected " + std::to_string(expected) +
                                " values, got " + std::to_string(x.size()));
  for (Eigen::Index i = 0; i < x.size(); ++i)
    if (!std::isfinite(x[i]))
      throw std::invalid_argument(std::string(what) + "[" + std::to_string(i) + "] = " +
                                  fmt(x[i]) + " is not finite");
}

// Quaternions of spherical and floating joints: a norm of 0 (or one that under- or overflows)
// has no rotation; with `unit`, the norm must be 1 within 1e-9.
void check_quaternions(const Model& model, const VecX& q, bool unit) {
  for (const Link& link : model.links) {
    if (link.joint_type != JointType::spherical && link.joint_type != JointType::floating) continue;
    const int iq = link.q_index + (link.joint_type == JointType::floating ? 3 : 0);
    const double norm = q.segment<4>(iq).norm();
    const bool ok = unit ? std::abs(norm - 1.0) <= 1e-9 : (norm > 1e-150 && std::isfinite(norm));
    if (!ok)
      throw std::invalid_argument("q: the quaternion of joint '" + link.joint_name + "' (q[" +
                                  std::to_string(iq) + "..." + std::to_string(iq + 3) +
                                  "]) has norm " + fmt(norm) +
                                  (unit ? ", expected 1" : ": it must not be zero"));
  }
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

const char* to_string(SolverType type) { return type == SolverType::pgs ? "pgs" : "tgs"; }
const char* to_string(Compat compat) { return compat == Compat::physx ? "physx" : "none"; }

void validate_options(const SimulationOptions& o) {
  if (!std::isfinite(o.dt) || o.dt <= 0.0)
    throw std::invalid_argument("simulation options: dt = " + fmt(o.dt) + " must be finite and > 0");
  if (!(o.dt >= kMinDt && o.dt <= kMaxDt))
    throw std::invalid_argument("simulation options: dt = " + fmt(o.dt) +
                                " must be a normal number in [" + fmt(kMinDt) + ", " + fmt(kMaxDt) +
                                "] s");
  const std::string most = std::to_string(kMaxIterations);
  if (o.position_iterations < 1)
    throw std::invalid_argument("simulation options: position_iterations = " +
                                std::to_string(o.position_iterations) + " must be >= 1");
  if (o.position_iterations > kMaxIterations)
    throw std::invalid_argument("simulation options: position_iterations = " +
                                std::to_string(o.position_iterations) + " must be <= " + most);
  if (o.velocity_iterations < 0)
    throw std::invalid_argument("simulation options: velocity_iterations = " +
                                std::to_string(o.velocity_iterations) + " must be >= 0");
  if (o.velocity_iterations > kMaxIterations)
    throw std::invalid_argument("simulation options: velocity_iterations = " +
                                std::to_string(o.velocity_iterations) + " must be <= " + most);
  if (!std::isfinite(o.guard.max_joint_step) || o.guard.max_joint_step <= 0.0)
    throw std::invalid_argument("simulation options: guard.max_joint_step = " +
                                fmt(o.guard.max_joint_step) + " must be finite and > 0");
  if (o.guard.max_substeps < 2 || o.guard.max_substeps > kMaxGuardSubsteps)
    throw std::invalid_argument("simulation options: guard.max_substeps = " +
                                std::to_string(o.guard.max_substeps) + " must be in [2, " +
                                std::to_string(kMaxGuardSubsteps) + "]");
  if (!(o.guard.energy_tolerance > 0.0 && o.guard.energy_tolerance <= 1.0))
    throw std::invalid_argument("simulation options: guard.energy_tolerance = " +
                                fmt(o.guard.energy_tolerance) + " must be in (0, 1]");
  if (!(o.guard.dissipation_share > 0.0 && o.guard.dissipation_share <= 100.0))
    throw std::invalid_argument("simulation options: guard.dissipation_share = " +
                                fmt(o.guard.dissipation_share) + " must be in (0, 100]");
}

Simulation::Simulation(std::shared_ptr<const Model> model, const SimulationOptions& options)
    : model_(model ? std::move(model) : throw std::invalid_argument("Simulation: model is null")),
      options_(options),
      data_(*model_),
      sweep_(*model_),
      departures_(*model_) {
  validate_options(options_);
  const int nv = model_->nv;
  state_ = StateStorage(model_->nq, nv);
  state_[StateStorage::q] = model_->neutral_configuration();
  drives_.assign(static_cast<size_t>(nv), Drive{});
  lower_limit_ = model_->lower_limit;
  upper_limit_ = model_->upper_limit;
  max_velocity_ = model_->velocity_limit;
  friction_.assign(static_cast<size_t>(nv), JointFriction{});
  envelopes_.assign(static_cast<size_t>(nv), ActuatorEnvelope{});
  for (int d = 0; d < nv; ++d) {
    const JointType type = model_->links[model_->dof_link[d]].joint_type;
    if (!has_axis_rows(type)) continue;
    friction_[static_cast<size_t>(d)] = {model_->friction[d], model_->friction[d], model_->damping[d]};
  }
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
  friction_coefficient_ = VecX::Zero(nv);
  link_parameters_.assign(n, LinkParameters{});
  link_force_.assign(n, Vec6::Zero());
  subtree_force_.assign(n, Vec6::Zero());
  transmitted_force_ = VecX::Zero(model_->num_links());
  link_cfm_ = VecX::Zero(model_->num_links());
  wrapped_.assign(static_cast<size_t>(nv), 0);
  if (options_.compat == Compat::physx) {
    // PhysX 5.6.1's defaults for everything nobody set; a model's velocity limit counts as set.
    link_parameters_.assign(n, physx_default::link());
    for (int d = 0; d < nv; ++d) {
      const JointType type = model_->links[model_->dof_link[d]].joint_type;
      if (!has_axis_rows(type)) continue;
      wrapped_[static_cast<size_t>(d)] = type == JointType::revolute;  // PhysX's eREVOLUTE
      friction_coefficient_[d] = physx_default::friction_coefficient;
      if (!std::isfinite(max_velocity_[d])) max_velocity_[d] = physx_default::max_joint_velocity;
    }
  }
  update_link_damping_active();
  dt_ = options_.dt;
  if (options_.guard.enabled) size_guard();
}

void Simulation::set_track_convergence(bool on) {
  track_convergence_ = on;
  last_drive_change_.setZero();
}

void Simulation::set_options(const SimulationOptions& options) {
  validate_options(options);
  if (options.compat != options_.compat)
    throw std::invalid_argument(std::string("simulation options: compat = ") +
                                to_string(options.compat) + " differs from the simulation's " +
                                to_string(options_.compat) + ": compat is chosen at construction");
  options_ = options;
  if (options_.guard.enabled && !guard_data_) size_guard();
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
  if (guard_data_) size_guard();  // the guard's energies read the masses too
}

void Simulation::set_q(const VecX& q) {
  check_vector(q, model_->nq, "q");
  check_quaternions(*model_, q, /*unit=*/false);
  VecX normalized = q;
  normalize_configuration(*model_, normalized);
  state_[StateStorage::q] = normalized;
}

void Simulation::set_clock(double time, long step_count) {
  if (step_count < 0 || step_count > kMaxStepCount)
    throw std::invalid_argument("clock: step_count = " + std::to_string(step_count) +
                                " must be in [0, " + std::to_string(kMaxStepCount) + "]");
  if (!std::isfinite(time) || time < 0.0)
    throw std::invalid_argument("clock: time = " + fmt(time) + " must be finite and >= 0");
  // Each step adds one dt <= kMaxDt; the factor 2 covers the rounding of the sum (< n eps).
  const double most = 2.0 * static_cast<double>(step_count) * kMaxDt;
  if (time > most)
    throw std::invalid_argument("clock: time = " + fmt(time) + " s after " +
                                std::to_string(step_count) + " steps: no run reaches it (at most " +
                                fmt(most) + " s, 2 * steps * " + fmt(kMaxDt) + " s)");
  time_ = time;
  step_count_ = step_count;
}

void Simulation::restore_state(const VecX& q, const VecX& drive_force, const VecX& limit_force,
                               const VecX& friction_force, const VecX& velocity_limit_force) {
  check_vector(q, model_->nq, "q");
  check_quaternions(*model_, q, /*unit=*/true);
  check_vector(drive_force, model_->nv, "drive_force");
  check_vector(limit_force, model_->nv, "limit_force");
  check_vector(friction_force, model_->nv, "friction_force");
  check_vector(velocity_limit_force, model_->nv, "velocity_limit_force");
  state_[StateStorage::q] = q;
  state_[StateStorage::drive_force] = drive_force;
  state_[StateStorage::limit_force] = limit_force;
  state_[StateStorage::friction_force] = friction_force;
  state_[StateStorage::velocity_limit_force] = velocity_limit_force;
}

void Simulation::set_qd(const VecX& qd) {
  check_vector(qd, model_->nv, "qd");
  state_[StateStorage::qd] = qd;
}

void Simulation::set_applied_force(const VecX& tau) {
  check_vector(tau, model_->nv, "applied_force");
  state_[StateStorage::applied_force] = tau;
}

int Simulation::check_dof(int dof) const {
  if (dof < 0 || dof >= model_->nv)
    throw std::invalid_argument("dof index " + std::to_string(dof) + " is out of range [0, " +
                                std::to_string(model_->nv) + ")");
  return dof;
}

int Simulation::driven_dof(const std::string& joint) const {
  // A spherical joint's axes go by their dof names ("ball:twist", "ball:swing1", "ball:swing2").
  for (int d = 0; d < model_->nv; ++d)
    if (model_->dof_names[d] == joint &&
        model_->links[model_->dof_link[d]].joint_type == JointType::spherical)
      return d;
  const Link& link = model_->links[model_->joint_link_index(joint)];
  if (link.joint_type == JointType::spherical)
    throw std::invalid_argument("joint '" + joint + "' is spherical: name one of its axes, '" +
                                joint + ":twist', '" + joint + ":swing1' or '" + joint +
                                ":swing2'");
  if (!has_axis_rows(link.joint_type))
    throw std::invalid_argument("joint '" + joint + "' is " + to_string(link.joint_type) +
                                ": this setting acts on revolute, prismatic and spherical "
                                "joints only");
  return link.v_index;
}

void Simulation::set_drive(int dof, const Drive& drive) {
  check_dof(dof);
  const Link& link = model_->links[model_->dof_link[dof]];
  if (drive.type != DriveType::none && !has_axis_rows(link.joint_type))
    throw std::invalid_argument("joint '" + link.joint_name + "' is " +
                                to_string(link.joint_type) +
                                ": drives act on revolute, prismatic and spherical joints only");
  validate_drive(drive, link.joint_name);
  if (drive.type != DriveType::none && actuators_.active(dof))
    throw std::invalid_argument("joint '" + link.joint_name + "' has an explicit actuator (" +
                                to_string(actuators_.actuator(dof).kind) + "): a " +
                                to_string(drive.type) + " drive cannot act beside it (clear the "
                                "actuator first; a drive of type none sets its targets)");
  // New targets or gains leave a lone drive one.
  if (drive.type != drives_[static_cast<size_t>(dof)].type) row_kinds_changed_ = true;
  drives_[static_cast<size_t>(dof)] = drive;
  // No drive, no delay: what set_drive_delay refuses is not kept either (checkpoints restore it).
  if (drive.type == DriveType::none && drive_delays_.delayed(dof)) drive_delays_.set(dof, 0);
}

void Simulation::set_drive(const std::string& joint, const Drive& drive) {
  set_drive(driven_dof(joint), drive);
}

// Driven by the implicit drive or by an explicit actuator, which reads the drive's targets.
bool Simulation::accepts_targets(int dof) const {
  return drives_[static_cast<size_t>(dof)].type != DriveType::none || has_actuator(dof);
}

std::string Simulation::no_drive_message(int dof) const {
  const Link& link = model_->links[model_->dof_link[dof]];
  const std::string joint = "joint '" + model_->dof_names[dof] + "' (dof " + std::to_string(dof);
  if (!has_axis_rows(link.joint_type))
    return joint + ") is " + to_string(link.joint_type) + ": it takes no drive, so no target";
  return joint + ") has no drive (type none), so a target would do nothing: give it one first "
                 "(set_drive, set_drive_gains for every joint, or set_actuator)";
}

void Simulation::check_targets_have_drives(const VecX& positions, const VecX& velocities) const {
  for (int d = 0; d < std::min(positions.size(), velocities.size()); ++d)
    if ((positions[d] != 0.0 || velocities[d] != 0.0) && !accepts_targets(d))
      throw std::invalid_argument(no_drive_message(d) + "; this vector sets its target to " +
                                  fmt(positions[d]) + ", velocity " + fmt(velocities[d]));
}

void Simulation::set_drive_target(int dof, double position, double velocity) {
  check_dof(dof);
  if (!accepts_targets(dof)) throw std::invalid_argument(no_drive_message(dof));
  Drive d = drive(dof);
  d.target_position = position;
  d.target_velocity = velocity;
  set_drive(dof, d);
}

void Simulation::set_drive_target(const std::string& joint, double position, double velocity) {
  set_drive_target(driven_dof(joint), position, velocity);
}

int Simulation::one_dof_joint(int dof) const {
  check_dof(dof);
  const Link& link = model_->links[model_->dof_link[dof]];
  if (!has_axis_rows(link.joint_type))
    throw std::invalid_argument("joint '" + link.joint_name + "' is " + to_string(link.joint_type) +
                                ": limits, friction and velocity limits act on revolute, "
                                "prismatic and spherical joints only");
  return dof;
}

void Simulation::set_joint_limits(int dof, double lower, double upper) {
  one_dof_joint(dof);
  // +-inf stand for "no limit" on their own side only; validate_limits does not know that.
  const std::string& joint = model_->links[model_->dof_link[dof]].joint_name;
  if (lower == std::numeric_limits<double>::infinity())
    throw std::invalid_argument("limits on joint '" + joint + "': lower = inf leaves no position");
  if (upper == -std::numeric_limits<double>::infinity())
    throw std::invalid_argument("limits on joint '" + joint + "': upper = -inf leaves no position");
  validate_limits(lower, upper, model_->links[model_->dof_link[dof]].joint_name);
  // PhysX's spherical positions lie in [-pi, pi] (setLimitParams refuses wider limits).
  if (model_->links[model_->dof_link[dof]].joint_type == JointType::spherical)
    for (const double limit : {lower, upper})
      if (std::isfinite(limit) && std::abs(limit) > std::numbers::pi)
        throw std::invalid_argument("limits on joint '" + model_->dof_names[dof] + "': " +
                                    (limit == lower ? "lower = " : "upper = ") + fmt(limit) +
                                    " is outside [-pi, pi], where a spherical axis's position "
                                    "lies");
  lower_limit_[dof] = lower;
  upper_limit_[dof] = upper;
  row_kinds_changed_ = true;
}
void Simulation::set_joint_limits(const std::string& joint, double lower, double upper) {
  set_joint_limits(driven_dof(joint), lower, upper);
}

void Simulation::set_joint_friction(int dof, const JointFriction& friction) {
  one_dof_joint(dof);
  validate_friction(friction, model_->links[model_->dof_link[dof]].joint_name);
  friction_[static_cast<size_t>(dof)] = friction;
  row_kinds_changed_ = true;
}
void Simulation::set_joint_friction(const std::string& joint, const JointFriction& friction) {
  set_joint_friction(driven_dof(joint), friction);
}

void Simulation::set_max_joint_velocity(int dof, double max_velocity) {
  one_dof_joint(dof);
  validate_max_velocity(max_velocity, model_->links[model_->dof_link[dof]].joint_name);
  max_velocity_[dof] = max_velocity;
  row_kinds_changed_ = true;
}
void Simulation::set_max_joint_velocity(const std::string& joint, double max_velocity) {
  set_max_joint_velocity(driven_dof(joint), max_velocity);
}

void Simulation::set_friction_coefficient(int dof, double coefficient) {
  one_dof_joint(dof);
  validate_friction_coefficient(coefficient, model_->links[model_->dof_link[dof]].joint_name);
  friction_coefficient_[dof] = coefficient;
  row_kinds_changed_ = true;
}
void Simulation::set_friction_coefficient(const std::string& joint, double coefficient) {
  set_friction_coefficient(driven_dof(joint), coefficient);
}

void Simulation::set_revolute_wrap(int dof, RevoluteWrap wrap) {
  check_dof(dof);
  const Link& link = model_->links[model_->dof_link[dof]];
  if (link.joint_type != JointType::revolute)
    throw std::invalid_argument("joint '" + link.joint_name + "' is " +
                                to_string(link.joint_type) + ": revolute = " + to_string(wrap) +
                                " acts on revolute joints only");
  wrapped_[static_cast<size_t>(dof)] = wrap == RevoluteWrap::wrapped;
}
void Simulation::set_revolute_wrap(const std::string& joint, RevoluteWrap wrap) {
  set_revolute_wrap(model_->links[model_->joint_link_index(joint)].v_index, wrap);
}
RevoluteWrap Simulation::revolute_wrap(int dof) const {
  return wrapped_[static_cast<size_t>(check_dof(dof))] ? RevoluteWrap::wrapped
                                                        : RevoluteWrap::unwrapped;
}

void Simulation::set_mimic_joints(const std::vector<MimicJoint>& mimic) {
  mimic_ = MimicSolver(*model_, mimic);
}

void Simulation::update_link_damping_active() {
  link_damping_active_ = false;
  link_cfm_active_ = false;
  for (const LinkParameters& p : link_parameters_) {
    link_damping_active_ = link_damping_active_ || p.linear_damping > 0.0 ||
                           p.angular_damping > 0.0 || std::isfinite(p.max_linear_velocity) ||
                           std::isfinite(p.max_angular_velocity);
    link_cfm_active_ = link_cfm_active_ || p.cfm_scale != 0.0;
  }
  if (!link_cfm_active_) link_cfm_.setZero();  // what link_cfm would write every step
}

void Simulation::set_link_parameters(int link, const LinkParameters& parameters) {
  if (link < 0 || link >= model_->num_links())
    throw std::invalid_argument("link index " + std::to_string(link) + " is out of range [0, " +
                                std::to_string(model_->num_links()) + ")");
  validate_link_parameters(parameters, model_->links[link].name);
  link_parameters_[static_cast<size_t>(link)] = parameters;
  update_link_damping_active();
}
void Simulation::set_link_parameters(const std::string& link, const LinkParameters& parameters) {
  set_link_parameters(model_->link_index(link), parameters);
}
const LinkParameters& Simulation::link_parameters(int link) const {
  if (link < 0 || link >= model_->num_links())
    throw std::invalid_argument("link index " + std::to_string(link) + " is out of range [0, " +
                                std::to_string(model_->num_links()) + ")");
  return link_parameters_[static_cast<size_t>(link)];
}
const LinkParameters& Simulation::link_parameters(const std::string& link) const {
  return link_parameters(model_->link_index(link));
}

void Simulation::set_actuator_envelope(int dof, const ActuatorEnvelope& envelope) {
  one_dof_joint(dof);
  validate_envelope(envelope, model_->links[model_->dof_link[dof]].joint_name);
  envelopes_[static_cast<size_t>(dof)] = envelope;
  row_kinds_changed_ = true;
}
void Simulation::set_actuator_envelope(const std::string& joint, const ActuatorEnvelope& envelope) {
  set_actuator_envelope(driven_dof(joint), envelope);
}

void Simulation::set_actuator(int dof, const ExplicitActuator& actuator) {
  check_dof(dof);
  const Link& link = model_->links[model_->dof_link[dof]];
  // An implicit actuator's dof is never a lone drive (setup_rows): its rows are set up again.
  if (actuators_.implicit(dof) ||
      (actuator.kind != ActuatorKind::none &&
       actuator.integration == ActuatorIntegration::implicit_law))
    row_kinds_changed_ = true;
  if (actuator.kind == ActuatorKind::none) {
    actuators_.set(dof, actuator);
    return;
  }
  if (link.joint_type != JointType::revolute && link.joint_type != JointType::prismatic)
    throw std::invalid_argument("joint '" + link.joint_name + "' is " +
                                to_string(link.joint_type) +
                                ": explicit actuators act on revolute and prismatic joints only");
  validate_actuator(actuator, link.joint_name);
  if (drives_[static_cast<size_t>(dof)].type != DriveType::none)
    throw std::invalid_argument("joint '" + link.joint_name + "' has a " +
                                to_string(drives_[static_cast<size_t>(dof)].type) +
                                " drive: an explicit " + to_string(actuator.kind) +
                                " actuator cannot act beside it (set the drive's type to none)");
  actuators_.set(dof, actuator);
}
void Simulation::set_actuator(const std::string& joint, const ExplicitActuator& actuator) {
  set_actuator(driven_dof(joint), actuator);
}

void Simulation::set_actuator_feedforward(int dof, double effort) {
  check_dof(dof);
  const std::string& joint = model_->links[model_->dof_link[dof]].joint_name;
  if (!actuators_.active(dof))
    throw std::invalid_argument("joint '" + joint + "' has no explicit actuator to take a "
                                "feed-forward effort (use set_applied_force)");
  if (!std::isfinite(effort))
    throw std::invalid_argument("actuator on joint '" + joint + "': feedforward = " + fmt(effort) +
                                " must be finite");
  actuators_.set_feedforward(dof, effort);
}
void Simulation::set_actuator_feedforward(const std::string& joint, double effort) {
  set_actuator_feedforward(driven_dof(joint), effort);
}

void Simulation::restore_actuator_history(int dof, long pushes,
                                          const std::vector<ActuatorCommand>& ring) {
  actuators_.restore_history(check_dof(dof), pushes, ring);
}

void Simulation::check_drive_delay(int dof, int delay) const {
  check_dof(dof);
  const std::string& joint = model_->dof_names[dof];
  if (delay < 0 || delay > kMaxDelay)
    throw std::invalid_argument("drive of joint '" + joint + "': delay = " +
                                std::to_string(delay) + " must be in [0, " +
                                std::to_string(kMaxDelay) + "] steps");
  if (delay == 0) return;
  if (actuators_.active(dof))
    throw std::invalid_argument("joint '" + joint + "' has an explicit actuator: a drive delay "
                                "of " + std::to_string(delay) + " steps would do nothing (give "
                                "the actuator its own delay)");
  if (drives_[static_cast<size_t>(dof)].type == DriveType::none)
    throw std::invalid_argument(no_drive_message(dof) + "; a drive delay of " +
                                std::to_string(delay) + " steps would do nothing too");
}

void Simulation::set_drive_delay(int dof, int delay) {
  check_drive_delay(dof, delay);
  drive_delays_.set(dof, delay);
  row_kinds_changed_ = true;
}
void Simulation::set_drive_delay(const std::string& joint, int delay) {
  set_drive_delay(driven_dof(joint), delay);
}

void Simulation::restore_drive_delay_history(int dof, long pushes,
                                             const std::vector<DriveTarget>& ring) {
  drive_delays_.restore_history(check_dof(dof), pushes, ring);
}

void Simulation::restore_actuator_force(const VecX& force) {
  check_vector(force, model_->nv, "actuator_force");
  actuator_force_ = force;
  actuated_ = true;
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
  actuators_.compute(*model_, q_, qd_, drives_, actuator_force_);
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
  auto fail = [&](const char* quantity, int dof, double value) {
    const std::string joint = model.links[model.dof_link[dof]].joint_name;
    const long step = step_count_ + 1;
    const double t = time_;
    undo_actuators();
    std::ostringstream s;
    s.precision(6);
    s << "simulation diverged at step " << step << " (t = " << t << " s): joint '" << joint
      << "' " << quantity << " = " << value
      << "; the state is left as it was before this step (lower dt or the gains)";
    throw DivergenceError(s.str());
  };
  // x * 0 is 0 for a finite x and NaN otherwise, so one sum tells whether all are finite; the
  // search for the culprit runs only when one is not.
  const double zero = (qd_.array() * 0.0).sum() + (drive_force_.array() * 0.0).sum() +
                      (limit_force_.array() * 0.0).sum() + (friction_force_.array() * 0.0).sum() +
                      (velocity_limit_force_.array() * 0.0).sum() + (q_.array() * 0.0).sum();
  if (zero == 0.0 && std::isfinite(time_ + options_.dt)) return;
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
  // The clock itself (found by fuzzing: dt = 1e308 twice made the time +inf without an error).
  if (!std::isfinite(time_ + options_.dt)) {
    undo_actuators();
    std::ostringstream s;
    s.precision(6);
    s << "simulation diverged at step " << step_count_ + 1 << " (t = " << time_
      << " s): time t + dt = " << time_ + options_.dt
      << " is not finite; the state is left as it was before this step (lower dt)";
    throw DivergenceError(s.str());
  }
}

}  // namespace featherdrive
