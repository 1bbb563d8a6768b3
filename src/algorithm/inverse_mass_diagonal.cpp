#include "featherdrive/algorithm/inverse_mass_diagonal.hpp"

#include "featherdrive/algorithm/aba.hpp"
#include "featherdrive/algorithm/kinematics.hpp"
#include "featherdrive/algorithm/response_law.hpp"
#include "joint_acceleration.hpp"
#include "mat6_storage.hpp"

namespace featherdrive {
namespace {

const Mat6 kZero = Mat6::Zero();  // the world's response: it does not move

// At a joint of N dofs (spherical, floating) by response_law (docs/math/unit_response.md,
// eq. R6-R10). Out of line: inlined, it costs the 1-dof path registers.
template <int N>
[[gnu::noinline]] void multi_dof_response(Data& data, int i, const Mat6& T, Mat6& L) {
  const Data::LinkInfo& link = data.info[i];
  // A spherical joint's dense S, a floating root's diag(R, R) read from R (RotationPair), as the
  // lanes' ball_response and root_response read them.
  const auto S = [&] {
    if constexpr (N == 6) return detail::Subspace<6>::of(data, i);
    else return response_law::Columns<double>{data.motion_subspace[i].data()};
  }();
  const detail::ColumnMajor<N> D_inv{data.D_inv[i].data()};
  detail::Mat6Assigned Lambda(L);
  MatNN& block = data.inverse_mass_block[i];
  if (link.parent < 0) {  // T = 0: W = 0, (M^-1)_ii = D^-1
    response_law::world_response<N, double>(S, D_inv, Lambda);
    data.parent_coupling[i].setZero();
    block = data.D_inv[i];
  } else {
    double Minv[N * N];
    response_law::response_n<N>(detail::Mat6Entries(T), S, data.U[i].data(), D_inv,
                                data.parent_coupling[i].data(), Minv, Lambda);
    for (int a = 0; a < N; ++a)
      for (int b = 0; b < N; ++b) block(a, b) = Minv[N * a + b];
  }
  data.inverse_mass_diagonal.segment(link.v_index, N) = block.diagonal();
}

// Link i's Lambda_i, W_i and (M^-1)_ii, its parent's being done. In frame 0, where a link's and
// its parent's spatial vectors share coordinates: Lambda_i = S D^-1 S^T + P T P^T with
// T = Lambda_p and P = I - S D^-1 U^T; (M^-1)_ii = D^-1 + D^-1 U^T T U D^-1
// (docs/math/unit_response.md). Forced inline: both loops below take it.
[[gnu::always_inline]] inline void link_response(Data& data, int i) {
  const Data::LinkInfo& link = data.info[i];
  const Mat6& T = link.parent >= 0 ? data.response[link.parent] : kZero;
  Mat6& L = data.response[i];
  if (link.nv == 1) {  // by response_law (docs/math/unit_response.md, eq. R1-R5)
    Data::OneDof& J = data.one_dof[i];
    const double D_inv = J.D_inv;
    detail::Mat6Assigned Lambda(L);
    const double r = response_law::response(
        detail::Mat6Entries(T), detail::aligned16(J.S.data()), detail::aligned16(J.U.data()), D_inv,
        detail::aligned16(J.W.data()), detail::aligned16(J.G.data()), Lambda);
    J.inverse_mass = r;
    if (link.parent >= 0 && data.info[link.parent].nv == 1) {
      const Data::OneDof& P = data.one_dof[link.parent];
      const response_law::Chain<double> c =
          response_law::chain(detail::aligned16(J.U.data()), D_inv, detail::aligned16(P.S.data()),
                              detail::aligned16(P.W.data()), P.D_inv, P.inverse_mass);
      J.parent_W = c.parent_W;
      J.parent_S = c.parent_S;
      J.base_per_parent_base = c.base_per_parent_base;
      J.base_per_parent_impulse = c.base_per_parent_impulse;
    }
    data.inverse_mass_block[i](0, 0) = r;
    data.inverse_mass_diagonal[link.v_index] = r;
    return;
  }
  if (link.nv == 0) {
    L = T;
    return;
  }
  if (link.nv == 3) return multi_dof_response<3>(data, i, T, L);
  multi_dof_response<6>(data, i, T, L);
}

}  // namespace

const VecX& articulated_response(const Model& model, Data& data) {
  for (int i = 0; i < model.num_links(); ++i) link_response(data, i);
  return data.inverse_mass_diagonal;
}

const VecX& accelerations_and_response(const Model& model, Data& data) {
  const Vec6 a_world = detail::world_acceleration(model);
  for (int i = 0; i < model.num_links(); ++i) {
    detail::link_acceleration(data, i, a_world);
    link_response(data, i);
  }
  return data.qdd;
}

const VecX& inverse_mass_diagonal(const Model& model, Data& data, const VecX& q) {
  forward_kinematics(model, data, q);
  articulated_inertias(model, data);
  return articulated_response(model, data);
}

}  // namespace featherdrive
