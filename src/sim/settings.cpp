#include "featherdrive/sim/settings.hpp"

#include <bit>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <stdexcept>

#include "featherdrive/core/format.hpp"

namespace featherdrive {
namespace {

std::string fmt(double v) { return format_double(v); }

const Link& link_of(const Model& model, int dof) { return model.links[model.dof_link[dof]]; }

// The checks of limits, friction, velocity limits, the friction coefficient and envelopes.
void check_row_dof(const Model& model, int dof) {
  check_dof_index(model, dof);
  const Link& link = link_of(model, dof);
  if (!dof_has_rows(model, dof))
    throw std::invalid_argument("joint '" + link.joint_name + "' is " + to_string(link.joint_type) +
                                ": limits, friction and velocity limits act on revolute, "
                                "prismatic and spherical joints only");
}

// Bit for bit: a setting equal to its default is the default, NaN included.
bool same(double a, double b) {
  return std::bit_cast<std::uint64_t>(a) == std::bit_cast<std::uint64_t>(b);
}
bool same(const JointFriction& a, const JointFriction& b) {
  return same(a.static_effort, b.static_effort) && same(a.dynamic_effort, b.dynamic_effort) &&
         same(a.viscous, b.viscous);
}
bool same(const ActuatorEnvelope& a, const ActuatorEnvelope& b) {
  return same(a.max_effort, b.max_effort) &&
         same(a.max_actuator_velocity, b.max_actuator_velocity) &&
         same(a.speed_effort_gradient, b.speed_effort_gradient) &&
         same(a.velocity_dependent_resistance, b.velocity_dependent_resistance);
}

void check_size(size_t size, long expected, const char* field, const char* of) {
  if (static_cast<long>(size) != expected)
    throw std::invalid_argument("settings: " + std::string(field) + " has " +
                                std::to_string(size) + " entries, the model has " + of + " = " +
                                std::to_string(expected));
}

}  // namespace

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

Settings Settings::defaults(const Model& model, const SimulationOptions& options) {
  const int nv = model.nv;
  const auto n = static_cast<size_t>(nv);
  Settings s;
  s.options = options;
  s.drives.assign(n, Drive{});
  s.lower_limit = model.lower_limit;
  s.upper_limit = model.upper_limit;
  s.max_joint_velocity = model.velocity_limit;
  s.friction.assign(n, JointFriction{});
  s.envelopes.assign(n, ActuatorEnvelope{});
  s.friction_coefficient = VecX::Zero(nv);
  s.revolute_wrap.assign(n, RevoluteWrap::unwrapped);
  s.drive_delay.assign(n, 0);
  s.actuators.assign(n, ExplicitActuator{});
  s.actuator_feedforward = VecX::Zero(nv);
  s.row_parameters.resize(nv, RowKinds::fields);
  for (const RowKindInfo& kind : row_kinds())
    for (size_t j = 0; j < kind.fields.size(); ++j)
      s.row_parameters.col(kind.offset + static_cast<Eigen::Index>(j))
          .setConstant(kind.fields[j].default_value);
  s.link_parameters.assign(static_cast<size_t>(model.num_links()), LinkParameters{});
  const bool physx = options.compat == Compat::physx;
  // PhysX 5.6.1's defaults for everything nobody set; a model's velocity limit counts as set.
  if (physx) s.link_parameters.assign(s.link_parameters.size(), physx_default::link());
  for (int d = 0; d < nv; ++d) {
    if (!dof_has_rows(model, d)) continue;
    s.friction[static_cast<size_t>(d)] = {model.friction[d], model.friction[d], model.damping[d]};
    if (!physx) continue;
    if (link_of(model, d).joint_type == JointType::revolute)  // PhysX's eREVOLUTE
      s.revolute_wrap[static_cast<size_t>(d)] = RevoluteWrap::wrapped;
    s.friction_coefficient[d] = physx_default::friction_coefficient;
    if (!std::isfinite(s.max_joint_velocity[d]))
      s.max_joint_velocity[d] = physx_default::max_joint_velocity;
  }
  return s;
}

void Settings::validate(const Model& model) const {
  validate_options(options);
  const long nv = model.nv;
  check_size(drives.size(), nv, "drives", "nv");
  check_size(static_cast<size_t>(lower_limit.size()), nv, "lower_limit", "nv");
  check_size(static_cast<size_t>(upper_limit.size()), nv, "upper_limit", "nv");
  check_size(static_cast<size_t>(max_joint_velocity.size()), nv, "max_joint_velocity", "nv");
  check_size(friction.size(), nv, "friction", "nv");
  check_size(envelopes.size(), nv, "envelopes", "nv");
  check_size(static_cast<size_t>(friction_coefficient.size()), nv, "friction_coefficient", "nv");
  check_size(revolute_wrap.size(), nv, "revolute_wrap", "nv");
  check_size(drive_delay.size(), nv, "drive_delay", "nv");
  check_size(actuators.size(), nv, "actuators", "nv");
  check_size(static_cast<size_t>(actuator_feedforward.size()), nv, "actuator_feedforward", "nv");
  check_size(link_parameters.size(), model.num_links(), "link_parameters", "num_links");
  check_size(static_cast<size_t>(row_parameters.rows()), nv, "row_parameters", "nv");
  check_size(static_cast<size_t>(row_parameters.cols()), RowKinds::fields, "row_parameters' columns",
             "the row kinds' fields");
  // What equals the default passes (a model may hold values no setter takes, e.g. a velocity
  // limit of 0); anything else must pass its setter's check.
  const Settings base = defaults(model, options);
  for (int d = 0; d < model.nv; ++d) {
    const auto k = static_cast<size_t>(d);
    const Drive& drive = drives[k];
    const ExplicitActuator& actuator = actuators[k];
    check_drive(model, d, drive, actuator.kind);
    if (!same(lower_limit[d], base.lower_limit[d]) || !same(upper_limit[d], base.upper_limit[d]))
      check_joint_limits(model, d, lower_limit[d], upper_limit[d]);
    if (!same(max_joint_velocity[d], base.max_joint_velocity[d]))
      check_max_joint_velocity(model, d, max_joint_velocity[d]);
    if (!same(friction[k], base.friction[k])) check_joint_friction(model, d, friction[k]);
    if (!same(envelopes[k], base.envelopes[k])) check_actuator_envelope(model, d, envelopes[k]);
    if (!same(friction_coefficient[d], base.friction_coefficient[d]))
      check_friction_coefficient(model, d, friction_coefficient[d]);
    if (revolute_wrap[k] != base.revolute_wrap[k]) check_revolute_wrap(model, d, revolute_wrap[k]);
    check_actuator(model, d, actuator, drive);
    // Without an actuator the feed-forward is 0: set_actuator_feedforward refuses any there.
    if (actuator.kind != ActuatorKind::none || actuator_feedforward[d] != 0.0)
      check_actuator_feedforward(model, d, actuator_feedforward[d], actuator.kind);
    check_drive_delay(model, d, drive_delay[k], drive, actuator.kind);
    for (const RowKindInfo& kind : row_kinds()) {
      std::array<double, RowKinds::fields> values{};
      bool changed = false;
      for (size_t j = 0; j < kind.fields.size(); ++j) {
        values[j] = row_parameters(d, kind.offset + static_cast<Eigen::Index>(j));
        changed = changed || !same(values[j], kind.fields[j].default_value);
      }
      if (changed) check_row_parameters(model, d, kind, {values.data(), kind.fields.size()});
    }
  }
  for (int i = 0; i < model.num_links(); ++i)
    check_link_parameters_of(model, i, link_parameters[static_cast<size_t>(i)]);
  validate_mimic_joints(model, mimic_joints);
  check_ground(ground);
  check_ground_supported(model, ground);
  check_contact_options(contact);
}

int check_dof_index(const Model& model, int dof) {
  if (dof < 0 || dof >= model.nv)
    throw std::invalid_argument("dof index " + std::to_string(dof) + " is out of range [0, " +
                                std::to_string(model.nv) + ")");
  return dof;
}

// The joints whose dofs carry rows (drives, limits, friction, velocity limits): revolute,
// prismatic, and spherical per axis (twist, swing1, swing2; docs/math/spherical_joints.md).
bool dof_has_rows(const Model& model, int dof) {
  const JointType type = link_of(model, dof).joint_type;
  return type == JointType::revolute || type == JointType::prismatic ||
         type == JointType::spherical;
}

int setting_dof(const Model& model, const std::string& joint) {
  // A spherical joint's axes go by their dof names ("ball:twist", "ball:swing1", "ball:swing2").
  for (int d = 0; d < model.nv; ++d)
    if (model.dof_names[d] == joint && link_of(model, d).joint_type == JointType::spherical)
      return d;
  const Link& link = model.links[model.joint_link_index(joint)];
  if (link.joint_type == JointType::spherical)
    throw std::invalid_argument("joint '" + joint + "' is spherical: name one of its axes, '" +
                                joint + ":twist', '" + joint + ":swing1' or '" + joint +
                                ":swing2'");
  if (link.nv == 0 || !dof_has_rows(model, link.v_index))
    throw std::invalid_argument("joint '" + joint + "' is " + to_string(link.joint_type) +
                                ": this setting acts on revolute, prismatic and spherical "
                                "joints only");
  return link.v_index;
}

std::string no_drive_message(const Model& model, int dof) {
  const Link& link = link_of(model, dof);
  const std::string joint = "joint '" + model.dof_names[dof] + "' (dof " + std::to_string(dof);
  if (!dof_has_rows(model, dof))
    return joint + ") is " + to_string(link.joint_type) + ": it takes no drive, so no target";
  return joint + ") has no drive (type none), so a target would do nothing: give it one first "
                 "(set_drive, set_drive_gains for every joint, or set_actuator)";
}

void check_drive(const Model& model, int dof, const Drive& drive, ActuatorKind actuator_kind) {
  check_dof_index(model, dof);
  const Link& link = link_of(model, dof);
  if (drive.type != DriveType::none && !dof_has_rows(model, dof))
    throw std::invalid_argument("joint '" + link.joint_name + "' is " +
                                to_string(link.joint_type) +
                                ": drives act on revolute, prismatic and spherical joints only");
  validate_drive(drive, link.joint_name);
  if (drive.type != DriveType::none && actuator_kind != ActuatorKind::none)
    throw std::invalid_argument("joint '" + link.joint_name + "' has an explicit actuator (" +
                                to_string(actuator_kind) + "): a " + to_string(drive.type) +
                                " drive cannot act beside it (clear the actuator first; a drive "
                                "of type none sets its targets)");
}

void check_joint_limits(const Model& model, int dof, double lower, double upper) {
  check_row_dof(model, dof);
  // +-inf stand for "no limit" on their own side only; validate_limits does not know that.
  const Link& link = link_of(model, dof);
  const std::string& joint = link.joint_name;
  if (lower == std::numeric_limits<double>::infinity())
    throw std::invalid_argument("limits on joint '" + joint + "': lower = inf leaves no position");
  if (upper == -std::numeric_limits<double>::infinity())
    throw std::invalid_argument("limits on joint '" + joint + "': upper = -inf leaves no position");
  validate_limits(lower, upper, joint);
  // PhysX's spherical positions lie in [-pi, pi] (setLimitParams refuses wider limits).
  if (link.joint_type == JointType::spherical)
    for (const double limit : {lower, upper})
      if (std::isfinite(limit) && std::abs(limit) > std::numbers::pi)
        throw std::invalid_argument("limits on joint '" + model.dof_names[dof] + "': " +
                                    (limit == lower ? "lower = " : "upper = ") + fmt(limit) +
                                    " is outside [-pi, pi], where a spherical axis's position "
                                    "lies");
}

void check_joint_friction(const Model& model, int dof, const JointFriction& friction) {
  check_row_dof(model, dof);
  validate_friction(friction, link_of(model, dof).joint_name);
}

void check_max_joint_velocity(const Model& model, int dof, double max_velocity) {
  check_row_dof(model, dof);
  validate_max_velocity(max_velocity, link_of(model, dof).joint_name);
}

void check_friction_coefficient(const Model& model, int dof, double coefficient) {
  check_row_dof(model, dof);
  validate_friction_coefficient(coefficient, link_of(model, dof).joint_name);
}

void check_actuator_envelope(const Model& model, int dof, const ActuatorEnvelope& envelope) {
  check_row_dof(model, dof);
  validate_envelope(envelope, link_of(model, dof).joint_name);
}

void check_revolute_wrap(const Model& model, int dof, RevoluteWrap wrap) {
  check_dof_index(model, dof);
  const Link& link = link_of(model, dof);
  if (link.joint_type != JointType::revolute)
    throw std::invalid_argument("joint '" + link.joint_name + "' is " +
                                to_string(link.joint_type) + ": revolute = " + to_string(wrap) +
                                " acts on revolute joints only");
}

void check_actuator(const Model& model, int dof, const ExplicitActuator& actuator,
                    const Drive& drive) {
  check_dof_index(model, dof);
  if (actuator.kind == ActuatorKind::none) return;
  const Link& link = link_of(model, dof);
  if (link.joint_type != JointType::revolute && link.joint_type != JointType::prismatic)
    throw std::invalid_argument("joint '" + link.joint_name + "' is " +
                                to_string(link.joint_type) +
                                ": explicit actuators act on revolute and prismatic joints only");
  validate_actuator(actuator, link.joint_name);
  if (drive.type != DriveType::none)
    throw std::invalid_argument("joint '" + link.joint_name + "' has a " + to_string(drive.type) +
                                " drive: an explicit " + to_string(actuator.kind) +
                                " actuator cannot act beside it (set the drive's type to none)");
}

void check_drive_delay(const Model& model, int dof, int delay, const Drive& drive,
                       ActuatorKind actuator_kind) {
  check_dof_index(model, dof);
  const std::string& joint = model.dof_names[dof];
  if (delay < 0 || delay > kMaxDelay)
    throw std::invalid_argument("drive of joint '" + joint + "': delay = " +
                                std::to_string(delay) + " must be in [0, " +
                                std::to_string(kMaxDelay) + "] steps");
  if (delay == 0) return;
  if (actuator_kind != ActuatorKind::none)
    throw std::invalid_argument("joint '" + joint + "' has an explicit actuator: a drive delay "
                                "of " + std::to_string(delay) + " steps would do nothing (give "
                                "the actuator its own delay)");
  if (drive.type == DriveType::none)
    throw std::invalid_argument(no_drive_message(model, dof) + "; a drive delay of " +
                                std::to_string(delay) + " steps would do nothing too");
}

void check_row_parameters(const Model& model, int dof, const RowKindInfo& kind,
                          std::span<const double> values) {
  check_dof_index(model, dof);
  if (values.size() != kind.fields.size())
    throw std::invalid_argument(std::string(kind.name) + ": expected " +
                                std::to_string(kind.fields.size()) + " values, got " +
                                std::to_string(values.size()));
  const Link& link = link_of(model, dof);
  if (!dof_has_rows(model, dof))
    throw std::invalid_argument("joint '" + link.joint_name + "' is " + to_string(link.joint_type) +
                                ": " + std::string(kind.name) +
                                " acts on revolute, prismatic and spherical joints only");
  kind.check(model.dof_names[dof], values);
}

void check_actuator_feedforward(const Model& model, int dof, double effort,
                                ActuatorKind actuator_kind) {
  check_dof_index(model, dof);
  const std::string& joint = link_of(model, dof).joint_name;
  if (actuator_kind == ActuatorKind::none)
    throw std::invalid_argument("joint '" + joint + "' has no explicit actuator to take a "
                                "feed-forward effort (use set_applied_force)");
  if (!std::isfinite(effort))
    throw std::invalid_argument("actuator on joint '" + joint + "': feedforward = " + fmt(effort) +
                                " must be finite");
}

void check_ground(const Ground& ground) {
  auto bad = [](const std::string& what) { throw std::invalid_argument("ground." + what); };
  if (!std::isfinite(ground.height)) bad("height = " + fmt(ground.height) + " is not finite");
  const double length = ground.normal.norm();
  if (!ground.normal.allFinite() || !(length > 1e-12) || !std::isfinite(length))
    bad("normal = " + format_vec3(ground.normal) + " must be finite and of non-zero length");
  const Material& m = ground.material;
  auto friction = [&](const char* field, double v) {
    if (!(std::isfinite(v) && v >= 0.0)) bad(std::string(field) + " = " + fmt(v) +
                                            " must be finite and >= 0");
  };
  friction("static_friction", m.static_friction);
  friction("dynamic_friction", m.dynamic_friction);
  if (!(m.restitution >= 0.0 && m.restitution <= 1.0))
    bad("restitution = " + fmt(m.restitution) + " must be in [0, 1]");
}

void check_ground_supported(const Model& model, const Ground& ground) {
  if (!ground.enabled || model.unsupported_shapes.empty()) return;
  const size_t n = model.unsupported_shapes.size();
  throw std::invalid_argument(
      "ground: " + model.unsupported_shapes.front() +
      ": contacts do not support this shape yet (sphere, capsule, box, ellipsoid, cylinder, "
      "convex mesh)" +
      (n > 1 ? " (" + std::to_string(n) + " such shapes in all)" : std::string()) +
      "; leave the ground off or replace the geometry");
}

void check_contact_options(const ContactOptions& options) {
  auto bad = [](const std::string& what) { throw std::invalid_argument("contact." + what); };
  if (!(std::isfinite(options.rest_offset) && std::isfinite(options.contact_offset)))
    bad("contact_offset = " + fmt(options.contact_offset) + ", rest_offset = " +
        fmt(options.rest_offset) + ": must be finite");
  if (!(options.rest_offset >= 0.0 && options.contact_offset > options.rest_offset))
    bad("contact_offset = " + fmt(options.contact_offset) + ", rest_offset = " +
        fmt(options.rest_offset) + ": need 0 <= rest_offset < contact_offset");
  if (!(std::isfinite(options.bounce_threshold) && options.bounce_threshold >= 0.0))
    bad("bounce_threshold = " + fmt(options.bounce_threshold) + " must be finite and >= 0");
}

void check_link_parameters_of(const Model& model, int link, const LinkParameters& parameters) {
  if (link < 0 || link >= model.num_links())
    throw std::invalid_argument("link index " + std::to_string(link) + " is out of range [0, " +
                                std::to_string(model.num_links()) + ")");
  validate_link_parameters(parameters, model.links[static_cast<size_t>(link)].name);
}

}  // namespace featherdrive
