// The workspace's construction (workspace.hpp); the stages that use it live in step.cpp,
// contact.cpp and step_guard.cpp.
#include "workspace.hpp"

#include <cmath>

namespace featherdrive {

Workspace::Workspace(const Model& model, const Settings& settings)
    : data(model), sweep(model), departures(model) {
  const int nv = model.nv;
  actuators = ExplicitActuators(nv);
  drive_delays = DriveDelays(nv);
  actuator_force = actuator_force_start = joint_force = VecX::Zero(nv);
  drive_force = limit_force = friction_force = velocity_limit_force = VecX::Zero(nv);
  row_force = VecX::Zero(RowKinds::size * nv);
  rows.assign(static_cast<size_t>(nv), DofRows{});
  dof_order.assign(static_cast<size_t>(nv), 0);
  delta_x = VecX::Zero(nv);
  last_drive_change = VecX::Zero(nv);
  const size_t n = static_cast<size_t>(model.num_links());
  link_force.assign(n, Vec6::Zero());
  transmitted_force = VecX::Zero(model.num_links());
  link_cfm = VecX::Zero(model.num_links());
  link_contact_force.assign(n, Vec3::Zero());
  set_shapes(model);
  contact_link_velocity.assign(n, Vec6::Zero());
  contact_link_bias.assign(n, Vec6::Zero());
  contact_link_motion.assign(n, Vec6::Zero());
  contact_link_motion_step.assign(n, Vec6::Zero());
  update_link_damping_active(settings);
  dt = settings.options.dt;
  if (settings.options.guard.enabled) size_guard(model);
}

void Workspace::set_shapes(const Model& model) {
  contact_rows = ContactRows(model);
  self_contacts = SelfContacts(model);
  contacts.assign(static_cast<size_t>(contact_rows.max_points() + self_contacts.max_points()),
                  ContactReport{});
}

void Workspace::update_link_damping_active(const Settings& settings) {
  link_damping_active = false;
  link_cfm_active = false;
  for (const LinkParameters& p : settings.link_parameters) {
    link_damping_active = link_damping_active || p.linear_damping > 0.0 ||
                          p.angular_damping > 0.0 || std::isfinite(p.max_linear_velocity) ||
                          std::isfinite(p.max_angular_velocity);
    link_cfm_active = link_cfm_active || p.cfm_scale != 0.0;
  }
  if (!link_cfm_active) link_cfm.setZero();  // what link_cfm would write every step
}

}  // namespace featherdrive
