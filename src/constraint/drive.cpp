#include "featherdrive/constraint/drive.hpp"

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
}

DriveRow setup_drive_row(const Drive& drive, double r, double x0, double h, double step_dt,
                         bool tgs) {
  DriveRow row;
  row.impulse_multiplier = 1.0;
  if (drive.type == DriveType::none) return row;
  const double kp = drive.stiffness;
  const double kd = drive.damping;
  const double a = h * (h * kp + kd);                   // eq. (13) / (30)
  const double b = h * kd * drive.target_velocity;      // eq. (14) / (31)
  // Force drive: x = 1 / (a r + 1), eq. (15); acceleration drive: x = 1 / (a + 1) and every
  // coefficient carries r^-1, eq. (32)-(39) with ERRATA 1-2.
  const bool accel = drive.type == DriveType::acceleration;
  const double x = accel ? 1.0 / (a + 1.0) : 1.0 / (a * r + 1.0);
  const double scale = accel ? x / r : x;
  row.target_vel_plus_initial_bias = scale * (b + h * kp * (drive.target_position - x0));
  row.vel_multiplier = -scale * a;
  row.impulse_multiplier = tgs ? 1.0 : 1.0 - x;
  row.bias_coefficient = scale * h * kp;
  row.target_pos_bias = tgs ? scale * h * kp * drive.target_velocity : 0.0;
  row.max_impulse = std::min(drive.max_force * step_dt, drive.max_impulse);
  return row;
}

}  // namespace featherdrive
