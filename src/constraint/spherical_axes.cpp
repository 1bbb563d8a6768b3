#include "featherdrive/constraint/spherical_axes.hpp"

#include <cmath>

namespace featherdrive {

Vec3 spherical_joint_positions(const Quat& Q) {
  // q and -q are one rotation: PhysX takes w >= 0, so that the angle is at most pi (eq. S-1).
  const double sign = Q.w() < 0.0 ? -1.0 : 1.0;
  const Vec3 v = sign * Q.vec();
  const double s = v.norm();
  if (s == 0.0) return Vec3::Zero();
  return (2.0 * std::atan2(s, sign * Q.w()) / s) * v;  // eq. S-2
}

Vec3 spherical_drive_error(const Quat& Q, const Vec3& target, const std::array<bool, 3>& driven) {
  Vec3 axis = Vec3::Zero();
  bool any = false;
  for (int k = 0; k < 3; ++k) {
    if (!driven[static_cast<size_t>(k)]) continue;
    axis[k] = target[k];
    any = true;
  }
  if (!any) return Vec3::Zero();
  const double angle = axis.norm();
  Quat T = Quat::Identity();
  if (angle > 0.0) T = Quat(Eigen::AngleAxisd(angle, axis / angle));  // eq. S-4
  if (T.coeffs().dot(Q.coeffs()) < 0.0) T.coeffs() = -T.coeffs();
  return -2.0 * (T.conjugate() * Q).vec();  // eq. S-5
}

}  // namespace featherdrive
