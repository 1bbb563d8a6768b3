#include "featherdrive/algorithm/rnea.hpp"

#include "featherdrive/algorithm/kinematics.hpp"

namespace featherdrive {

const VecX& rnea(const Model& model, Data& data, const VecX& q, const VecX& v, const VecX& a) {
  forward_kinematics(model, data, q, v);
  Vec6 a_world = Vec6::Zero();
  a_world.tail<3>() = -model.gravity;  // gravity as an upward acceleration of the world
  for (int i = 0; i < model.num_links(); ++i) {
    const Link& link = model.links[i];
    const Vec6& a_parent = link.parent >= 0 ? data.acceleration[link.parent] : a_world;
    const Vec6 ai = data.parent_transform[i].apply_motion(a_parent) +
                    link.motion_subspace * a.segment(link.v_index, link.nv) +
                    data.bias_acceleration[i];
    data.acceleration[i] = ai;
    const Vec6& vi = data.velocity[i];
    data.force[i] = link.inertia * ai + cross_force(vi, link.inertia * vi);
  }
  for (int i = model.num_links() - 1; i >= 0; --i) {
    const Link& link = model.links[i];
    data.tau.segment(link.v_index, link.nv) =
        link.motion_subspace.transpose() * data.force[i] +
        model.armature.segment(link.v_index, link.nv).cwiseProduct(a.segment(link.v_index, link.nv));
    if (link.parent >= 0)
      data.force[link.parent] += data.parent_transform[i].transpose_apply_force(data.force[i]);
  }
  return data.tau;
}

}  // namespace featherdrive
