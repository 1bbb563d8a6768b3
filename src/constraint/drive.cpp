#include "featherdrive/constraint/drive.hpp"

#include "featherdrive/constraint/drive_range.hpp"
#include "featherdrive/core/format.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace featherdrive {
namespace {

void reject(const std::string& joint, const char* field, double value, const char* expected) {
  throw std::invalid_argument("drive on joint '" + joint + "': " + field + " = " +
                              format_double(value) + " " + expected);
}

}  // namespace

const char* to_string(DriveType type) {
  switch (type) {
    case DriveType::none: return "none";
    case DriveType::force: return "force";
    case DriveType::acceleration: return "acceleration";
  }
  return "unknown";
}

void validate_drive(const Drive& d, const std::string& joint) {
  if (!std::isfinite(d.stiffness) || d.stiffness < 0.0)
    reject(joint, "stiffness", d.stiffness, "must be finite and >= 0");
  if (!std::isfinite(d.damping) || d.damping < 0.0)
    reject(joint, "damping", d.damping, "must be finite and >= 0");
  if (std::isnan(d.max_force) || d.max_force <= 0.0)
    reject(joint, "max_force", d.max_force, "must be > 0");
  if (std::isnan(d.max_impulse) || d.max_impulse <= 0.0)
    reject(joint, "max_impulse", d.max_impulse, "must be > 0");
  if (std::isfinite(d.max_force) && std::isfinite(d.max_impulse))
    throw std::invalid_argument("drive on joint '" + joint +
                                "': set max_force (a force) or max_impulse (an impulse per step), "
                                "not both");
  if (!std::isfinite(d.target_position))
    reject(joint, "target_position", d.target_position, "must be finite");
  if (!std::isfinite(d.target_velocity))
    reject(joint, "target_velocity", d.target_velocity, "must be finite");
  // Beyond these the drive impulse's rounding swamps the step's other impulses (eq. T1-T3).
  // A target whose gain is 0 adds nothing to the impulse (eq. T1): only driven targets count.
  const bool driven = d.type != DriveType::none;
  if (driven && d.stiffness > 0.0 && std::abs(d.target_position) > kMaxDriveTargetPosition)
    reject(joint, "target_position", d.target_position,
           "is beyond +-1e6 (m or rad): its drive impulse cannot be represented beside the "
           "step's other impulses");
  if (driven && d.damping > 0.0 && std::abs(d.target_velocity) > kMaxDriveTargetVelocity)
    reject(joint, "target_velocity", d.target_velocity,
           "is beyond +-1e6 (m/s or rad/s): its drive impulse cannot be represented beside the "
           "step's other impulses");
}

}  // namespace featherdrive
