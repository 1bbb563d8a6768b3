#include "featherdrive/algorithm/kinematics.hpp"

#include "featherdrive/algorithm/joint_motion.hpp"

namespace featherdrive {

void forward_kinematics(const Model& model, Data& data, const VecX& q) {
  for (int i = 0; i < model.num_links(); ++i) {
    const Link& link = model.links[i];
    const Transform X = joint_transform(link, q.data() + link.q_index) * link.tree_transform;
    data.parent_transform[i] = X;
    const Mat3 R = X.E.transpose();  // link orientation in its parent
    if (link.parent < 0) {
      data.world_rotation[i] = R;
      data.world_position[i] = X.r;
    } else {
      const Mat3& Rp = data.world_rotation[link.parent];
      data.world_rotation[i] = Rp * R;
      data.world_position[i] = data.world_position[link.parent] + Rp * X.r;
    }
  }
}

void forward_kinematics(const Model& model, Data& data, const VecX& q, const VecX& v) {
  forward_kinematics(model, data, q);
  for (int i = 0; i < model.num_links(); ++i) {
    const Link& link = model.links[i];
    const Vec6 vJ = link.motion_subspace * v.segment(link.v_index, link.nv);
    Vec6 vi = vJ;
    if (link.parent >= 0) vi += data.parent_transform[i].apply_motion(data.velocity[link.parent]);
    data.velocity[i] = vi;
    data.bias_acceleration[i] = cross_motion(vi, vJ);
  }
}

}  // namespace featherdrive
