#include "featherdrive/sim/explicit_actuator.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "featherdrive/core/format.hpp"

namespace featherdrive {
namespace {

[[noreturn]] void reject(const std::string& joint, const std::string& field, double value,
                         const char* expected) {
  throw std::invalid_argument("actuator on joint '" + joint + "': " + field + " = " +
                              format_double(value) + " " + expected);
}

}  // namespace

void validate_actuator(const ExplicitActuator& a, const std::string& joint) {
  if (a.kind == ActuatorKind::none) return;
  const char* kind = to_string(a.kind);
  if (a.integration != ActuatorIntegration::explicit_law &&
      a.integration != ActuatorIntegration::implicit_law)
    throw std::invalid_argument("actuator on joint '" + joint + "': integration = " +
                                std::to_string(static_cast<int>(a.integration)) +
                                " must be explicit or implicit");
  if (!std::isfinite(a.stiffness) || a.stiffness < 0.0)
    reject(joint, "stiffness", a.stiffness, "must be finite and >= 0");
  if (!std::isfinite(a.damping) || a.damping < 0.0)
    reject(joint, "damping", a.damping, "must be finite and >= 0");
  if (std::isnan(a.effort_limit) || a.effort_limit <= 0.0)
    reject(joint, "effort_limit", a.effort_limit, "must be > 0");
  if (a.kind == ActuatorKind::dc_motor) {
    if (!std::isfinite(a.saturation_effort) || a.saturation_effort <= 0.0)
      reject(joint, "saturation_effort", a.saturation_effort,
             "must be finite and > 0 for a dc_motor");
    if (!std::isfinite(a.velocity_limit) || a.velocity_limit <= 0.0)
      reject(joint, "velocity_limit", a.velocity_limit, "must be finite and > 0 for a dc_motor");
  } else {
    if (a.saturation_effort != 0.0)
      reject(joint, "saturation_effort", a.saturation_effort,
             (std::string("is for a dc_motor only, not ") + kind).c_str());
    if (a.velocity_limit != 0.0)
      reject(joint, "velocity_limit", a.velocity_limit,
             (std::string("is for a dc_motor only, not ") + kind).c_str());
  }
  if (a.kind == ActuatorKind::remotized_pd) {
    if (a.lookup.empty())
      throw std::invalid_argument("actuator on joint '" + joint +
                                  "': a remotized_pd needs a lookup table of (position, effort)");
    for (size_t i = 0; i < a.lookup.size(); ++i) {
      const std::string at = "lookup[" + std::to_string(i) + "]";
      const auto [position, effort] = a.lookup[i];
      if (!std::isfinite(position)) reject(joint, at + ".position", position, "must be finite");
      if (i > 0 && !(position > a.lookup[i - 1].first))
        reject(joint, at + ".position", position,
               ("must be above the previous position " + format_double(a.lookup[i - 1].first))
                   .c_str());
      if (!std::isfinite(effort) || effort < 0.0)
        reject(joint, at + ".effort", effort, "must be finite and >= 0");
    }
  } else if (!a.lookup.empty()) {
    throw std::invalid_argument("actuator on joint '" + joint + "': a lookup table (" +
                                std::to_string(a.lookup.size()) +
                                " points) is for a remotized_pd only, not " + kind);
  }
  if (a.delay < 0 || a.delay > kMaxActuatorDelay)
    throw std::invalid_argument("actuator on joint '" + joint + "': delay = " +
                                std::to_string(a.delay) + " must be in [0, " +
                                std::to_string(kMaxActuatorDelay) + "] steps");
}

ExplicitActuators::ExplicitActuators(int nv) : slots_(static_cast<size_t>(nv)) {}

void ExplicitActuators::set(int dof, const ExplicitActuator& actuator) {
  Slot& s = slots_[static_cast<size_t>(dof)];
  s.actuator = actuator;
  if (actuator.kind == ActuatorKind::none) {
    s.feedforward = 0.0;
    s.history.clear();
  } else {
    s.history.set_delay(actuator.delay);
  }
  active_.erase(std::remove(active_.begin(), active_.end(), dof), active_.end());
  if (actuator.kind != ActuatorKind::none)
    active_.insert(std::upper_bound(active_.begin(), active_.end(), dof), dof);
}

void ExplicitActuators::reset_history() {
  for (Slot& s : slots_) s.history.reset();
}

// eq. (8)-(9): the command of `delay` pushes ago, or the oldest one there is.
void ExplicitActuators::compute(const Model& model, const VecX& q, const VecX& qd,
                                const std::vector<Drive>& drives, VecX& effort) {
  effort.setZero();
  for (const int d : active_) {
    Slot& s = slots_[static_cast<size_t>(d)];
    const Drive& drive = drives[static_cast<size_t>(d)];
    const ActuatorCommand& seen =
        s.history.push({drive.target_position, drive.target_velocity, s.feedforward});
    if (s.actuator.integration == ActuatorIntegration::implicit_law) {
      s.seen = seen;  // the rows solve the law (setup_dof_rows)
      continue;
    }
    effort[d] = actuator_effort(s.actuator, q[model.links[model.dof_link[d]].q_index], qd[d], seen);
  }
}

void ExplicitActuators::evaluate(const Model& model, const VecX& q, const VecX& qd,
                                 VecX& effort) const {
  effort.setZero();
  for (const int d : active_) {
    const Slot& s = slot(d);
    if (s.actuator.integration == ActuatorIntegration::implicit_law) continue;  // in the rows
    effort[d] = actuator_effort(s.actuator, q[model.links[model.dof_link[d]].q_index], qd[d],
                                s.history.last_seen());
  }
}

void ExplicitActuators::undo_push() {
  for (const int d : active_) slots_[static_cast<size_t>(d)].history.undo_push();
}

void ExplicitActuators::restore_history(int dof, long pushes,
                                        const std::vector<ActuatorCommand>& ring) {
  for (const ActuatorCommand& c : ring)
    if (!std::isfinite(c.position) || !std::isfinite(c.velocity) || !std::isfinite(c.effort))
      throw std::invalid_argument("actuator history of dof " + std::to_string(dof) +
                                  ": a command is not finite");
  slots_[static_cast<size_t>(dof)].history.restore(
      pushes, ring, "actuator history of dof " + std::to_string(dof));
}

}  // namespace featherdrive
