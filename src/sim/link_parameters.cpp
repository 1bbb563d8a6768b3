#include "featherdrive/sim/link_parameters.hpp"

#include <cmath>
#include <stdexcept>

#include "featherdrive/core/format.hpp"

namespace featherdrive {
namespace {

[[noreturn]] void reject(const char* what, const std::string& name, const char* field, double value,
                         const char* expected) {
  std::string message = what;
  message += " '";
  message += name;
  message += "': ";
  message += field;
  message += " = ";
  message += format_double(value);
  message += " ";
  message += expected;
  throw std::invalid_argument(message);
}

}  // namespace

void validate_link_parameters(const LinkParameters& p, const std::string& link) {
  if (!(p.cfm_scale >= 0.0 && p.cfm_scale <= 1.0))
    reject("link", link, "cfm_scale", p.cfm_scale, "must be in [0, 1]");
  if (!std::isfinite(p.linear_damping) || p.linear_damping < 0.0)
    reject("link", link, "linear_damping", p.linear_damping, "must be finite and >= 0");
  if (!std::isfinite(p.angular_damping) || p.angular_damping < 0.0)
    reject("link", link, "angular_damping", p.angular_damping, "must be finite and >= 0");
  if (!(p.max_linear_velocity >= 0.0))
    reject("link", link, "max_linear_velocity", p.max_linear_velocity, "must be >= 0");
  if (!(p.max_angular_velocity >= 0.0))
    reject("link", link, "max_angular_velocity", p.max_angular_velocity, "must be >= 0");
}

void validate_friction_coefficient(double c, const std::string& joint) {
  if (!std::isfinite(c) || c < 0.0)
    reject("joint", joint, "friction_coefficient", c, "must be finite and >= 0");
}

}  // namespace featherdrive
