#include "featherdrive/algorithm/data.hpp"

#include <cmath>

namespace featherdrive {

Data::Data(const Model& model) {
  const size_t n = model.links.size();
  for (const Link& link : model.links) {
    LinkInfo li{link.parent, link.nv, link.v_index, link.q_index, link.joint_type};
    li.tree_rotation_identity = link.tree_transform.E == Mat3::Identity();
    const Mat3& I = link.inertia_com;
    li.inertia_diagonal = I(0, 1) == 0.0 && I(0, 2) == 0.0 && I(1, 2) == 0.0 && I(1, 0) == 0.0 &&
                          I(2, 0) == 0.0 && I(2, 1) == 0.0;
    if (link.joint_type == JointType::revolute || link.joint_type == JointType::prismatic)
      for (int k = 0; k < 3; ++k)
        if (std::abs(link.axis[k]) == 1.0 && link.axis[(k + 1) % 3] == 0.0 &&
            link.axis[(k + 2) % 3] == 0.0) {
          li.unit_axis = k;
          li.axis_sign = link.axis[k];
        }
    li.coordinate_revolute = link.joint_type == JointType::revolute && li.unit_axis >= 0 &&
                             li.tree_rotation_identity && link.parent >= 0;
    if (link.parent >= 0) {
      li.last_child = model.links[link.parent].children.back() == static_cast<int>(info.size());
      li.later = !li.last_child || info[link.parent].later;
    }
    info.push_back(li);
    constants.push_back({link.tree_transform, link.axis, link.com, link.inertia_com, link.mass});
  }
  parent_transform.resize(n);
  world_rotation.assign(n, Mat3::Identity());
  world_position.assign(n, Vec3::Zero());
  frame_position.assign(n, Vec3::Zero());
  velocity.assign(n, Vec6::Zero());
  bias_acceleration.assign(n, Vec6::Zero());
  velocity0.assign(n, Vec6::Zero());
  bias_acceleration0.assign(n, Vec6::Zero());
  articulated_inertia.assign(n, Mat6::Zero());
  articulated_bias.assign(n, Vec6::Zero());
  acceleration0.assign(n, Vec6::Zero());
  response.assign(n, Mat6::Zero());
  one_dof.assign(n, OneDof{});
  acceleration.assign(n, Vec6::Zero());
  force.assign(n, Vec6::Zero());
  composite_inertia.assign(n, Mat6::Zero());
  for (const Link& link : model.links) {
    const int k = link.nv == 1 ? 0 : link.nv;  // 1-dof joints use one_dof
    // A floating root's S is read from its rotation (multi_dof_law::RotationPair).
    motion_subspace.push_back(Mat6N::Zero(6, link.joint_type == JointType::floating ? 0 : k));
    U.push_back(Mat6N::Zero(6, k));
    D_inv.push_back(MatNN::Zero(k, k));
    parent_coupling.push_back(Mat6N::Zero(6, k));
    inverse_mass_block.push_back(MatNN::Zero(link.nv, link.nv));
  }
  u = VecX::Zero(model.nv);
  qdd = VecX::Zero(model.nv);
  inverse_mass_diagonal = VecX::Zero(model.nv);
  tau = VecX::Zero(model.nv);
  M = MatX::Zero(model.nv, model.nv);
  subtree_mass.assign(n, 0.0);
  subtree_moment.assign(n, Vec3::Zero());
}

}  // namespace featherdrive
