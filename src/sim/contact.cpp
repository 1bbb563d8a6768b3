// The step's contact stages (docs/math/contact.md): rows set up from the step-start poses after
// the free velocity, solved link by link inside each sweep (C15), tracked through TGS's
// sub-steps (C16) and reported.
#include "featherdrive/sim/simulation.hpp"

#include <algorithm>

namespace featherdrive {

void Simulation::update_contacts_active() {
  contacts_active_ = settings_.ground.enabled && contact_rows_.any_shapes();
  self_contacts_active_ = settings_.contact.self_collision && self_contacts_.any_pairs();
  if (contacts_active_) {
    sweep_.set_contact_links(contact_rows_.links_with_shapes());
  } else if (sweep_.any_contacts) {
    sweep_.set_contact_links(std::vector<char>(static_cast<size_t>(model_->num_links()), 0));
  }
  if (!contacts_active_ && !self_contacts_active_) {
    num_contacts_ = 0;
    std::fill(link_contact_force_.begin(), link_contact_force_.end(), Vec3::Zero());
  }
}

// The links' velocities the contact rows read: with compat physx, PhysX's link velocities, which
// carry the bias B of the free update (departure 1; docs/math/contact.md, C23a).
void Simulation::contact_link_velocities() {
  link_velocities0(*model_, data_, qd_, contact_link_velocity_);
  if (!physx()) return;
  for (size_t i = 0; i < contact_link_velocity_.size(); ++i)
    contact_link_velocity_[i] += contact_link_bias_[i];
}

void Simulation::setup_contacts(const RowPhase& phase) {
  if (physx()) {
    // B is at the centre of mass, world axes; frame 0's origin is o.
    for (int i = 0; i < model_->num_links(); ++i) {
      const auto k = static_cast<size_t>(i);
      const Vec3 com = data_.world_position[i] + data_.world_rotation[i] * model_->links[k].com;
      const Vec3& bw = departures_.bias_w[k];
      contact_link_bias_[k] << bw, departures_.bias_v[k] - bw.cross(com - data_.frame_origin);
    }
  }
  contact_link_velocities();
  std::fill(contact_link_motion_.begin(), contact_link_motion_.end(), Vec6::Zero());
  ContactPhase contact_phase;
  contact_phase.dt = phase.dt;
  contact_phase.h = phase.h;
  contact_phase.tgs = phase.tgs;
  const int iterations = settings_.options.position_iterations;
  num_ground_contacts_ =
      contacts_active_ ? contact_rows_.setup(*model_, data_, settings_.ground, settings_.contact,
                                             contact_link_velocity_, link_cfm_, iterations,
                                             contact_phase, contacts_)
                       : 0;
  num_contacts_ = num_ground_contacts_;
  if (self_contacts_active_)  // docs/math/contact.md, section 14
    num_contacts_ += self_contacts_.setup(*model_, data_, settings_.contact, contact_link_velocity_,
                                          link_cfm_, iterations, contact_phase, contacts_,
                                          num_ground_contacts_);
}

// TGS: the points move with the sub-step's velocities (C7's displacement).
void Simulation::track_contacts(double h) {
  contact_link_velocities();
  if (physx()) {
    // PhysX (recordDeltaMotion): a child link's linear motion is its centre of mass's move to the
    // posed sub-step, its angular motion the sum of h (omega + B_w); the root's is the sum of h V
    // (C25a). The poses and turns are the prismatic rows' (track_prismatic_position_change).
    const WorldPose &start = departures_.start, &now = departures_.now;
    for (int i = 0; i < model_->num_links(); ++i) {
      const auto k = static_cast<size_t>(i);
      Vec6& M = contact_link_motion_[k];
      Vec6 next;
      if (model_->links[k].parent < 0) {
        next = M + h * contact_link_velocity_[k];
      } else {
        const Vec3& theta = departures_.turn[k];
        next << theta, (now.com[k] - start.com[k]) - theta.cross(start.com[k] - data_.frame_origin);
      }
      contact_link_motion_step_[k] = next - M;
      M = next;
    }
    if (contacts_active_) contact_rows_.track(contact_link_motion_step_, 1.0);
    if (self_contacts_active_) self_contacts_.track(contact_link_motion_step_, 1.0);
    return;
  }
  if (contacts_active_) contact_rows_.track(contact_link_velocity_, h);
  if (self_contacts_active_) self_contacts_.track(contact_link_velocity_, h);
}

void Simulation::contact_forces() {
  if (!contacts_active_ && !self_contacts_active_) return;
  if (contacts_active_)
    contact_rows_.report(settings_.options.dt, contacts_, link_contact_force_);
  else
    std::fill(link_contact_force_.begin(), link_contact_force_.end(), Vec3::Zero());
  if (self_contacts_active_)
    self_contacts_.report(settings_.options.dt, contacts_, num_ground_contacts_,
                          link_contact_force_);
  // The anchors are kept only from a step that ends: one that diverges throws here and leaves
  // them as they were, as it leaves the state (found by fuzz_step: NaN anchors then made the
  // simulation's checkpoint unreadable).
  check_finite_or_throw();
  if (contacts_active_) contact_rows_.conclude();
}

}  // namespace featherdrive
