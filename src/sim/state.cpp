#include "featherdrive/sim/state.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

#include "featherdrive/algorithm/joint_motion.hpp"
#include "featherdrive/core/format.hpp"
#include "featherdrive/sim/settings.hpp"

namespace featherdrive {

void check_state_vector(const VecX& x, Eigen::Index expected, const char* what) {
  if (x.size() != expected)
    throw std::invalid_argument(std::string(what) + ": expected " + std::to_string(expected) +
                                " values, got " + std::to_string(x.size()));
  for (Eigen::Index i = 0; i < x.size(); ++i)
    if (!std::isfinite(x[i]))
      throw std::invalid_argument(std::string(what) + "[" + std::to_string(i) + "] = " +
                                  format_double(x[i]) + " is not finite");
}

// A quaternion's norm of 0 (or one that under- or overflows) has no rotation.
VecX checked_configuration(const Model& model, const VecX& q, bool unit) {
  check_state_vector(q, model.nq, "q");
  for (const Link& link : model.links) {
    if (link.joint_type != JointType::spherical && link.joint_type != JointType::floating) continue;
    const int iq = link.q_index + (link.joint_type == JointType::floating ? 3 : 0);
    const double norm = q.segment<4>(iq).norm();
    const bool ok = unit ? std::abs(norm - 1.0) <= 1e-9 : (norm > 1e-150 && std::isfinite(norm));
    if (!ok)
      throw std::invalid_argument("q: the quaternion of joint '" + link.joint_name + "' (q[" +
                                  std::to_string(iq) + "..." + std::to_string(iq + 3) +
                                  "]) has norm " + format_double(norm) +
                                  (unit ? ", expected 1" : ": it must not be zero"));
  }
  VecX checked = q;
  if (!unit) normalize_configuration(model, checked);
  return checked;
}

void check_guard_account(const GuardAccount& account) {
  auto check = [](double v, const char* name, bool signed_ok) {
    if (!(std::isfinite(v) && (signed_ok || v >= 0.0)))
      throw std::invalid_argument(std::string("guard account: ") + name + " = " +
                                  format_double(v) +
                                  (signed_ok ? " must be finite" : " must be finite and >= 0"));
  };
  check(account.created, "created", true);
  check(account.dissipated, "dissipated", false);
  check(account.scale, "scale", false);
}

void check_clock(double time, long step_count) {
  if (step_count < 0 || step_count > kMaxStepCount)
    throw std::invalid_argument("clock: step_count = " + std::to_string(step_count) +
                                " must be in [0, " + std::to_string(kMaxStepCount) + "]");
  if (!std::isfinite(time) || time < 0.0)
    throw std::invalid_argument("clock: time = " + format_double(time) +
                                " must be finite and >= 0");
  // Each step adds one dt <= kMaxDt; the factor 2 covers the rounding of the sum (< n eps).
  const double most = 2.0 * static_cast<double>(step_count) * kMaxDt;
  if (time > most)
    throw std::invalid_argument("clock: time = " + format_double(time) + " s after " +
                                std::to_string(step_count) + " steps: no run reaches it (at most " +
                                format_double(most) + " s, 2 * steps * " + format_double(kMaxDt) +
                                " s)");
}

}  // namespace featherdrive
