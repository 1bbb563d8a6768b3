// The step's contact stages (docs/math/contact.md): rows set up from the step-start poses after
// the free velocity, solved link by link inside each sweep (C15), tracked through TGS's
// sub-steps (C16) and reported.
#include <algorithm>

#include "workspace.hpp"

namespace featherdrive {

void Workspace::update_contacts_active(const Model& model, const Settings& settings) {
  contacts_active = settings.ground.enabled && contact_rows.any_shapes();
  self_contacts_active = settings.contact.self_collision && self_contacts.any_pairs();
  if (contacts_active) {
    sweep.set_contact_links(contact_rows.links_with_shapes());
  } else if (sweep.any_contacts) {
    sweep.set_contact_links(std::vector<char>(static_cast<size_t>(model.num_links()), 0));
  }
  if (!contacts_active && !self_contacts_active) {
    num_contacts = 0;
    std::fill(link_contact_force.begin(), link_contact_force.end(), Vec3::Zero());
  }
}

// The links' velocities the contact rows read: with compat physx, PhysX's link velocities, which
// carry the bias B of the free update (departure 1; docs/math/contact.md, C23a).
void Stepper::contact_link_velocities() {
  link_velocities0(*model_, ws_.data, ws_.qd, ws_.contact_link_velocity);
  if (!physx()) return;
  for (size_t i = 0; i < ws_.contact_link_velocity.size(); ++i)
    ws_.contact_link_velocity[i] += ws_.contact_link_bias[i];
}

void Stepper::setup_contacts(const RowPhase& phase) {
  if (physx()) {
    // B is at the centre of mass, world axes; frame 0's origin is o.
    for (int i = 0; i < model_->num_links(); ++i) {
      const auto k = static_cast<size_t>(i);
      const Vec3 com =
          ws_.data.world_position[i] + ws_.data.world_rotation[i] * model_->links[k].com;
      const Vec3& bw = ws_.departures.bias_w[k];
      ws_.contact_link_bias[k] << bw,
          ws_.departures.bias_v[k] - bw.cross(com - ws_.data.frame_origin);
    }
  }
  contact_link_velocities();
  std::fill(ws_.contact_link_motion.begin(), ws_.contact_link_motion.end(), Vec6::Zero());
  ContactPhase contact_phase;
  contact_phase.dt = phase.dt;
  contact_phase.h = phase.h;
  contact_phase.tgs = phase.tgs;
  contact_phase.push_dt = settings_.options.dt;
  const int iterations = settings_.options.position_iterations;
  ws_.num_ground_contacts =
      ws_.contacts_active
          ? ws_.contact_rows.setup(*model_, ws_.data, settings_.ground, settings_.contact,
                                   ws_.contact_link_velocity, ws_.link_cfm, iterations,
                                   contact_phase, ws_.contacts)
          : 0;
  ws_.num_contacts = ws_.num_ground_contacts;
  if (ws_.self_contacts_active)  // docs/math/contact.md, section 14
    ws_.num_contacts += ws_.self_contacts.setup(
        *model_, ws_.data, settings_.contact, ws_.contact_link_velocity, ws_.link_cfm, iterations,
        contact_phase, ws_.contacts, ws_.num_ground_contacts);
}

// TGS: the points move with the sub-step's velocities (C7's displacement).
void Stepper::track_contacts(double h) {
  contact_link_velocities();
  if (physx()) {
    // PhysX (recordDeltaMotion): a child link's linear motion is its centre of mass's move to the
    // posed sub-step, its angular motion the sum of h (omega + B_w); the root's is the sum of h V
    // (C25a). The poses and turns are the prismatic rows' (track_prismatic_position_change).
    const WorldPose &start = ws_.departures.start, &now = ws_.departures.now;
    for (int i = 0; i < model_->num_links(); ++i) {
      const auto k = static_cast<size_t>(i);
      Vec6& M = ws_.contact_link_motion[k];
      Vec6 next;
      if (model_->links[k].parent < 0) {
        next = M + h * ws_.contact_link_velocity[k];
      } else {
        const Vec3& theta = ws_.departures.turn[k];
        next << theta,
            (now.com[k] - start.com[k]) - theta.cross(start.com[k] - ws_.data.frame_origin);
      }
      ws_.contact_link_motion_step[k] = next - M;
      M = next;
    }
    if (ws_.contacts_active) ws_.contact_rows.track(ws_.contact_link_motion_step, 1.0);
    if (ws_.self_contacts_active) ws_.self_contacts.track(ws_.contact_link_motion_step, 1.0);
    return;
  }
  if (ws_.contacts_active) ws_.contact_rows.track(ws_.contact_link_velocity, h);
  if (ws_.self_contacts_active) ws_.self_contacts.track(ws_.contact_link_velocity, h);
}

void Stepper::contact_forces() {
  if (!ws_.contacts_active && !ws_.self_contacts_active) return;
  report_contacts();
  conclude_contacts();
}

// The (sub-)step's impulses into the reports, the links' forces their sum / options.dt.
void Stepper::report_contacts() {
  if (ws_.contacts_active)
    ws_.contact_rows.report(settings_.options.dt, ws_.contacts, ws_.link_contact_force);
  else
    std::fill(ws_.link_contact_force.begin(), ws_.link_contact_force.end(), Vec3::Zero());
  if (ws_.self_contacts_active)
    ws_.self_contacts.report(settings_.options.dt, ws_.contacts, ws_.num_ground_contacts,
                             ws_.link_contact_force);
}

void Stepper::conclude_contacts() {
  // The anchors are kept only from a step that ends: one that diverges throws here and leaves
  // them as they were, as it leaves the state (found by fuzz_step: NaN anchors then made the
  // simulation's checkpoint unreadable).
  check_finite_or_throw();
  if (ws_.contacts_active) ws_.contact_rows.conclude();
}

}  // namespace featherdrive
