// Spherical joints as PhysX 5.6.1 has them: the positions and drive errors of their three axes
// (constraint/spherical_axes.hpp) read from the state's quaternion, and PhysX's turn of the link
// in the world. docs/math/spherical_joints.md.
#include "featherdrive/algorithm/joint_motion.hpp"
#include "featherdrive/algorithm/multi_dof_law.hpp"
#include "featherdrive/constraint/spherical_axes.hpp"
#include "featherdrive/spatial/quaternion_law.hpp"
#include "physx_stages.hpp"

namespace featherdrive {
namespace {

Quat joint_quat(const Model& model, const VecX& q, int dof) {
  const Link& link = model.links[model.dof_link[dof]];
  const int iq = link.q_index;
  return Quat(q[iq], q[iq + 1], q[iq + 2], q[iq + 3]).normalized();
}

}  // namespace

double spherical_axis_position(const Model& model, const VecX& q, int dof) {
  const int axis = dof - model.links[model.dof_link[dof]].v_index;
  return spherical_joint_positions(joint_quat(model, q, dof))[axis];
}

double spherical_axis_drive_error(const Model& model, const VecX& q, int dof,
                                  const std::array<const Drive*, 3>& axes) {
  const int axis = dof - model.links[model.dof_link[dof]].v_index;
  Vec3 target;
  std::array<bool, 3> driven{};
  for (size_t k = 0; k < 3; ++k) {
    target[static_cast<int>(k)] = axes[k]->target_position;
    driven[k] = axes[k]->type != DriveType::none;
  }
  return spherical_drive_error(joint_quat(model, q, dof), target, driven)[axis];
}

bool has_spherical_joints(const Model& model) {
  for (const Link& link : model.links)
    if (link.joint_type == JointType::spherical) return true;
  return false;
}

void integrate_spherical_joints(const Model& model, const Data& data, const VecX& qd,
                                const std::vector<Vec3>* link_bias, double h,
                                PhysxDepartures& dep, VecX& q) {
  std::vector<Mat3>& R = dep.now.R;     // before the sub-step on entry, after it on return
  std::vector<Vec3>& w = dep.scratch.w;  // world angular velocities, the step's start frames
  for (int i = 0; i < model.num_links(); ++i) {
    const Link& link = model.links[i];
    const int p = link.parent;
    w[i] = p >= 0 ? w[p] : Vec3::Zero();
    // The joint's turn from its frame-0 S of the step's start (AP14's angular rows), as the lanes'
    // integrate_balls_physx.
    const double* x = qd.data() + link.v_index;
    if (link.joint_type == JointType::revolute) {
      w[i] += data.one_dof[i].S.head<3>() * x[0];
    } else if (link.nv == 3 || link.nv == 6) {
      Vec3 t;
      if (link.nv == 3)
        multi_dof_law::joint_turn(
            multi_dof_law::DenseSubspace<double, 3>{data.motion_subspace[i].data()}, x, t.data());
      else
        multi_dof_law::joint_turn(
            multi_dof_law::RotationPair<double, true>{data.world_rotation[i].data()}, x, t.data());
      w[i] += t;
    }
    const Mat3 parent = p >= 0 ? R[p] : Mat3::Identity();
    if (link.joint_type != JointType::spherical) {
      R[i] = parent * (joint_transform(link, &q[link.q_index]) * link.tree_transform).E.transpose();
      continue;
    }
    Vec3 turn = w[i];
    if (link_bias) turn += (*link_bias)[i];
    // exp(h turn) R (eq. Q-7), the lanes' integrate_balls_physx's law.
    double before[9], after[9];
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) before[3 * a + b] = R[i](a, b);
    quaternion_law::turn_rotation(turn.data(), h, before, after);
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) R[i](a, b) = after[3 * a + b];
    // The link's orientation in its joint frame, whose world rotation is parent * X_T's.
    Quat Q(Mat3(link.tree_transform.E * parent.transpose() * R[i]));
    Q.normalize();
    const int iq = link.q_index;
    if (Q.coeffs().dot(Eigen::Vector4d(q[iq + 1], q[iq + 2], q[iq + 3], q[iq])) < 0.0)
      Q.coeffs() = -Q.coeffs();
    q[iq] = Q.w();
    q[iq + 1] = Q.x();
    q[iq + 2] = Q.y();
    q[iq + 3] = Q.z();
  }
}

}  // namespace featherdrive
