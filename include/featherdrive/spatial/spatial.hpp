// Spatial (6D) algebra after Featherstone, "Rigid Body Dynamics Algorithms" (2008), ch. 2.
// Vectors are [angular; linear]. A Transform X_BA maps motion vectors from frame A to frame B.
#pragma once

#include "featherdrive/spatial/types.hpp"

namespace featherdrive {

/// Skew-symmetric matrix: skew(a) * b = a x b.
inline Mat3 skew(const Vec3& a) {
  Mat3 s;
  s << 0, -a.z(), a.y(), a.z(), 0, -a.x(), -a.y(), a.x(), 0;
  return s;
}

/// Plücker transform from frame A to frame B: E rotates A coordinates into B coordinates
/// (E = R_AB^T where R_AB is B's orientation in A), r is B's origin in A coordinates.
struct Transform {
  Mat3 E = Mat3::Identity();
  Vec3 r = Vec3::Zero();

  static Transform identity() { return {}; }
  /// The transform into a frame B whose pose in A is (R, p): E = R^T, r = p.
  static Transform from_pose(const Mat3& R, const Vec3& p) { return {R.transpose(), p}; }

  /// X v for a motion vector.
  Vec6 apply_motion(const Vec6& v) const {
    Vec6 out;
    out.head<3>() = E * v.head<3>();
    out.tail<3>() = E * (v.tail<3>() - r.cross(v.head<3>()));
    return out;
  }
  /// X^-1 v for a motion vector (from B back to A).
  Vec6 inverse_apply_motion(const Vec6& v) const {
    Vec6 out;
    out.head<3>() = E.transpose() * v.head<3>();
    out.tail<3>() = E.transpose() * v.tail<3>() + r.cross(out.head<3>());
    return out;
  }
  /// X^* f for a force vector (from A to B).
  Vec6 apply_force(const Vec6& f) const {
    Vec6 out;
    out.head<3>() = E * (f.head<3>() - r.cross(f.tail<3>()));
    out.tail<3>() = E * f.tail<3>();
    return out;
  }
  /// X^T f: a force in B expressed in A (the transpose of the motion transform).
  Vec6 transpose_apply_force(const Vec6& f) const {
    Vec6 out;
    out.tail<3>() = E.transpose() * f.tail<3>();
    out.head<3>() = E.transpose() * f.head<3>() + r.cross(out.tail<3>());
    return out;
  }
  /// Composition: (this * other) maps from other's source frame to this's target frame.
  Transform operator*(const Transform& other) const {
    return {E * other.E, other.r + other.E.transpose() * r};
  }
  Transform inverse() const { return {E.transpose(), -E * r}; }
  /// The 6x6 motion transform matrix.
  Mat6 matrix() const {
    Mat6 X;
    X.topLeftCorner<3, 3>() = E;
    X.topRightCorner<3, 3>().setZero();
    X.bottomLeftCorner<3, 3>() = -E * skew(r);
    X.bottomRightCorner<3, 3>() = E;
    return X;
  }
  /// X^T I X: an inertia (or articulated inertia) given in B, expressed in A.
  Mat6 transpose_inertia(const Mat6& I) const {
    const Mat6 X = matrix();
    return X.transpose() * I * X;
  }
};

/// Motion cross product v x m.
inline Vec6 cross_motion(const Vec6& v, const Vec6& m) {
  Vec6 out;
  out.head<3>() = v.head<3>().cross(m.head<3>());
  out.tail<3>() = v.head<3>().cross(m.tail<3>()) + v.tail<3>().cross(m.head<3>());
  return out;
}

/// Force cross product v x* f.
inline Vec6 cross_force(const Vec6& v, const Vec6& f) {
  Vec6 out;
  out.head<3>() = v.head<3>().cross(f.head<3>()) + v.tail<3>().cross(f.tail<3>());
  out.tail<3>() = v.head<3>().cross(f.tail<3>());
  return out;
}

/// Spatial inertia about a frame's origin of a body with mass m, centre of mass c and rotational
/// inertia Ic about the centre of mass (all in that frame).
inline Mat6 spatial_inertia(double m, const Vec3& c, const Mat3& Ic) {
  const Mat3 C = skew(c);
  Mat6 I;
  I.topLeftCorner<3, 3>() = Ic + m * C * C.transpose();
  I.topRightCorner<3, 3>() = m * C;
  I.bottomLeftCorner<3, 3>() = m * C.transpose();
  I.bottomRightCorner<3, 3>() = m * Mat3::Identity();
  return I;
}

/// Rotation from URDF roll-pitch-yaw: R = Rz(yaw) Ry(pitch) Rx(roll).
inline Mat3 rotation_from_rpy(const Vec3& rpy) {
  return (Eigen::AngleAxisd(rpy.z(), Vec3::UnitZ()) * Eigen::AngleAxisd(rpy.y(), Vec3::UnitY()) *
          Eigen::AngleAxisd(rpy.x(), Vec3::UnitX()))
      .toRotationMatrix();
}

/// Rotation by angle about a unit axis.
inline Mat3 rotation_about(const Vec3& unit_axis, double angle) {
  return Eigen::AngleAxisd(angle, unit_axis).toRotationMatrix();
}

}  // namespace featherdrive
