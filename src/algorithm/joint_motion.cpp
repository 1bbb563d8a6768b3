#include "featherdrive/algorithm/joint_motion.hpp"

#include "featherdrive/spatial/quaternion_law.hpp"

namespace featherdrive {
namespace {

Quat quat_at(const double* q) { return Quat(q[0], q[1], q[2], q[3]).normalized(); }

void store_quat(const Quat& Q, double* q) {
  q[0] = Q.w();
  q[1] = Q.x();
  q[2] = Q.y();
  q[3] = Q.z();
}

}  // namespace

Mat3 quaternion_rotation(const double* q) {
  double R[9];
  quaternion_law::rotation(q, R);
  return Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(R);
}

Transform joint_transform(const Link& link, const double* q) {
  switch (link.joint_type) {
    case JointType::fixed: return Transform::identity();
    case JointType::revolute: return {rotation_about(link.axis, q[0]).transpose(), Vec3::Zero()};
    case JointType::prismatic: return {Mat3::Identity(), link.axis * q[0]};
    case JointType::spherical: return Transform::from_pose(quaternion_rotation(q), Vec3::Zero());
    case JointType::floating:
      return Transform::from_pose(quaternion_rotation(q + 3), Vec3(q[0], q[1], q[2]));
  }
  return Transform::identity();
}

void integrate_configuration(const Model& model, const VecX& q, const VecX& v, double dt,
                             VecX& q_out) {
  for (const Link& link : model.links) {
    const int iq = link.q_index;
    const int iv = link.v_index;
    switch (link.joint_type) {
      case JointType::fixed: break;
      case JointType::revolute:
      case JointType::prismatic: q_out[iq] = q[iq] + dt * v[iv]; break;
      case JointType::spherical:
        quaternion_law::integrate_body(&q[iq], &v[iv], dt, &q_out[iq]);
        break;
      case JointType::floating: {
        // The origin moves by R v_body, R the rotation at the step's start (eq. Q-6).
        double Q0[4], Rv[3];
        quaternion_law::unit(&q[iq + 3], Q0);
        quaternion_law::rotate(Q0, &v[iv + 3], Rv);
        const double p[3] = {q[iq] + dt * Rv[0], q[iq + 1] + dt * Rv[1], q[iq + 2] + dt * Rv[2]};
        quaternion_law::integrate_unit_body(Q0, &v[iv], dt, &q_out[iq + 3]);
        for (int r = 0; r < 3; ++r) q_out[iq + r] = p[r];
        break;
      }
    }
  }
}

void normalize_configuration(const Model& model, VecX& q) {
  for (const Link& link : model.links) {
    if (link.joint_type == JointType::spherical) store_quat(quat_at(&q[link.q_index]), &q[link.q_index]);
    if (link.joint_type == JointType::floating)
      store_quat(quat_at(&q[link.q_index + 3]), &q[link.q_index + 3]);
  }
}

}  // namespace featherdrive
