#include "featherdrive/algorithm/inverse_mass_diagonal.hpp"

#include "featherdrive/algorithm/aba.hpp"
#include "featherdrive/algorithm/kinematics.hpp"

namespace featherdrive {

// Lambda_i = S D^-1 S^T + P T P^T with T = X Lambda_p X^T and P = I - S D^-1 U^T;
// (M^-1)_ii = D^-1 + D^-1 U^T T U D^-1 (docs/math/unit_response.md).
const VecX& articulated_response(const Model& model, Data& data) {
  for (int i = 0; i < model.num_links(); ++i) {
    const Link& link = model.links[i];
    Mat6 T = Mat6::Zero();
    if (link.parent >= 0) {
      const Mat6 X = data.parent_transform[i].matrix();
      T.noalias() = X * data.response[link.parent] * X.transpose();
    }
    if (link.nv == 0) {
      data.response[i] = T;
      continue;
    }
    const Mat6N& S = link.motion_subspace;
    const Mat6N& U = data.U[i];
    const MatNN& Dinv = data.D_inv[i];
    const Mat6N W = T * U;
    const MatNN UtW = U.transpose() * W;
    const Mat6N SDinv = S * Dinv;
    Mat6 L = T;
    L.noalias() -= SDinv * W.transpose();
    L.noalias() -= W * SDinv.transpose();
    L.noalias() += SDinv * UtW * SDinv.transpose();
    L.noalias() += SDinv * S.transpose();
    data.response[i] = L;
    data.parent_coupling[i] = W;
    data.inverse_mass_block[i] = Dinv + Dinv * UtW * Dinv;
    data.inverse_mass_diagonal.segment(link.v_index, link.nv) = data.inverse_mass_block[i].diagonal();
  }
  return data.inverse_mass_diagonal;
}

const VecX& inverse_mass_diagonal(const Model& model, Data& data, const VecX& q) {
  forward_kinematics(model, data, q);
  articulated_inertias(model, data);
  return articulated_response(model, data);
}

}  // namespace featherdrive
