#include "featherdrive/constraint/joint_constraints.hpp"

#include "featherdrive/core/format.hpp"

#include <charconv>
#include <cmath>
#include <stdexcept>

namespace featherdrive {
namespace {

std::string fmt(double v) { return format_double(v); }

void reject(const char* what, const std::string& joint, const char* field, double value,
            const char* expected) {
  throw std::invalid_argument(std::string(what) + " on joint '" + joint + "': " + field + " = " +
                              fmt(value) + " " + expected);
}

void non_negative(const char* what, const std::string& joint, const char* field, double v) {
  if (!std::isfinite(v) || v < 0.0) reject(what, joint, field, v, "must be finite and >= 0");
}

}  // namespace

void validate_friction(const JointFriction& f, const std::string& joint) {
  non_negative("friction", joint, "static_effort", f.static_effort);
  non_negative("friction", joint, "dynamic_effort", f.dynamic_effort);
  non_negative("friction", joint, "viscous", f.viscous);
}

void validate_envelope(const ActuatorEnvelope& e, const std::string& joint) {
  non_negative("actuator envelope", joint, "max_effort", e.max_effort);
  if (std::isnan(e.max_actuator_velocity) || e.max_actuator_velocity <= 0.0)
    reject("actuator envelope", joint, "max_actuator_velocity", e.max_actuator_velocity,
           "must be > 0");
  non_negative("actuator envelope", joint, "speed_effort_gradient", e.speed_effort_gradient);
  non_negative("actuator envelope", joint, "velocity_dependent_resistance",
               e.velocity_dependent_resistance);
}

void validate_limits(double lower, double upper, const std::string& joint) {
  if (std::isnan(lower)) reject("limits", joint, "lower", lower, "is not a number");
  if (std::isnan(upper)) reject("limits", joint, "upper", upper, "is not a number");
  if (lower > upper)
    throw std::invalid_argument("limits on joint '" + joint + "': lower = " + fmt(lower) +
                                " is above upper = " + fmt(upper));
}

void validate_max_velocity(double v, const std::string& joint) {
  if (std::isnan(v) || v <= 0.0) reject("velocity limit", joint, "max_velocity", v, "must be > 0");
}

}  // namespace featherdrive
