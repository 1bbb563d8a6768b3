#include "featherdrive/algorithm/data.hpp"

namespace featherdrive {

Data::Data(const Model& model) {
  const size_t n = model.links.size();
  parent_transform.resize(n);
  world_rotation.assign(n, Mat3::Identity());
  world_position.assign(n, Vec3::Zero());
  velocity.assign(n, Vec6::Zero());
  bias_acceleration.assign(n, Vec6::Zero());
  articulated_inertia.assign(n, Mat6::Zero());
  articulated_bias.assign(n, Vec6::Zero());
  acceleration.assign(n, Vec6::Zero());
  response.assign(n, Mat6::Zero());
  force.assign(n, Vec6::Zero());
  composite_inertia.assign(n, Mat6::Zero());
  for (const Link& link : model.links) {
    U.push_back(Mat6N::Zero(6, link.nv));
    D_inv.push_back(MatNN::Zero(link.nv, link.nv));
    parent_coupling.push_back(Mat6N::Zero(6, link.nv));
    inverse_mass_block.push_back(MatNN::Zero(link.nv, link.nv));
  }
  u = VecX::Zero(model.nv);
  qdd = VecX::Zero(model.nv);
  inverse_mass_diagonal = VecX::Zero(model.nv);
  tau = VecX::Zero(model.nv);
  M = MatX::Zero(model.nv, model.nv);
}

}  // namespace featherdrive
