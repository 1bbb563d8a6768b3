#include "featherdrive/algorithm/crba.hpp"

#include "featherdrive/algorithm/kinematics.hpp"

namespace featherdrive {

const MatX& crba(const Model& model, Data& data, const VecX& q) {
  forward_kinematics(model, data, q);
  for (int i = 0; i < model.num_links(); ++i) data.composite_inertia[i] = model.links[i].inertia;
  for (int i = model.num_links() - 1; i >= 0; --i) {
    const Link& link = model.links[i];
    if (link.parent >= 0)
      data.composite_inertia[link.parent] +=
          data.parent_transform[i].transpose_inertia(data.composite_inertia[i]);
  }
  data.M.setZero();
  for (int i = 0; i < model.num_links(); ++i) {
    const Link& link = model.links[i];
    if (link.nv == 0) continue;
    Mat6N F = data.composite_inertia[i] * link.motion_subspace;
    data.M.block(link.v_index, link.v_index, link.nv, link.nv) = link.motion_subspace.transpose() * F;
    int j = i;
    while (model.links[j].parent >= 0) {
      for (int c = 0; c < link.nv; ++c)
        F.col(c) = data.parent_transform[j].transpose_apply_force(F.col(c));
      j = model.links[j].parent;
      const Link& lj = model.links[j];
      if (lj.nv == 0) continue;
      data.M.block(lj.v_index, link.v_index, lj.nv, link.nv) = lj.motion_subspace.transpose() * F;
      data.M.block(link.v_index, lj.v_index, link.nv, lj.nv) =
          data.M.block(lj.v_index, link.v_index, lj.nv, link.nv).transpose();
    }
  }
  data.M.diagonal() += model.armature;
  return data.M;
}

}  // namespace featherdrive
